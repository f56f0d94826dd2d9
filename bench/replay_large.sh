#!/bin/sh
# emm replay --all on a mesh of real size: a generated 10,000,000-face mesh
# and a 10,000,000-access trace over it (breadth-first region growth, four
# records a triangle), the whole standard sweep — every EMM strategy pages
# its look-up tables (docs/fetch.md) and the sweep runs in passes that keep
# the models under --memory (default: half the physical memory, at most
# 4 GiB). Prints wall time and peak RSS. Target: under 10 minutes and under
# 8 GiB on a 2-core machine. Not a test; the mesh takes a few minutes to
# generate and is kept in WORK_DIR when one is given.
#
# --surface S: the mesh is a closed surface in space instead (emm mesh gen
# --surface S: sphere, torus or terrain), whose sweep adds the layouts in
# space (grid3d, tiles3d, octree). --indexed: the indexed variant of every
# EMM strategy joins the sweep (emm replay --all --indexed: the program
# renumbered by the layout, no per-element look-up table).
# usage: bench/replay_large.sh [--surface S] [--indexed] BUILD_DIR [WORK_DIR] [FACES]
set -eu
SURFACE=
INDEXED=
while [ $# -gt 0 ]; do
    case $1 in
    --surface) SURFACE=${2:?--surface needs sphere, torus or terrain}; shift 2 ;;
    --indexed) INDEXED=--indexed; shift ;;
    *) break ;;
    esac
done
BUILD=${1:?usage: replay_large.sh [--surface S] [--indexed] BUILD_DIR [WORK_DIR] [FACES]}
EMM=$BUILD/bin/emm
MEASURE=$BUILD/bin/measure
W=${2:-${TMPDIR:-/tmp}/emm-replay-large.$$}
FACES=${3:-10000000}
mkdir -p "$W"
[ -n "${2:-}" ] || trap 'rm -rf "$W"' EXIT
name=mesh${SURFACE:+-$SURFACE}-$FACES
mesh=$W/$name.off
trace=$W/region-$name.emmt
if [ ! -s "$mesh" ]; then
    echo "generating a $FACES-face ${SURFACE:-planar} mesh"
    "$MEASURE" "$EMM" mesh gen ${SURFACE:+--surface "$SURFACE"} --faces "$FACES" -o "$mesh"
fi
if [ ! -s "$trace" ]; then
    "$MEASURE" "$EMM" trace synth --mesh "$mesh" --pattern region --visits $((FACES / 4)) \
        --work 10 -o "$trace"
fi
echo "cpus online: $(getconf _NPROCESSORS_ONLN)"
"$EMM" trace info "$trace" | grep -E '^(geometry|accesses):'
"$MEASURE" "$EMM" replay "$trace" --all $INDEXED --quiet --json "$W/report.json"
skipped=$(grep -c '"error":' "$W/report.json" || true)
paged=$(grep -c '"lookup_paged": 1' "$W/report.json" || true)
echo "strategies skipped: $skipped; EMM strategies with paged look-up tables: $paged"
grep -o '"error": "[^"]*look-up tables take[^"]*"' "$W/report.json" | head -3 || true
# The fastest EMM strategy against direct reads, and how much of its DMA
# refetched cells evicted before (docs/layouts.md "The indexed variant":
# a breadth-first front larger than the local store is fetched again on
# every pass).
python3 - "$W/report.json" <<'PY'
import json, sys
res = [r for r in json.load(open(sys.argv[1]))["results"] if "cycles" in r]
direct = next(r["cycles"]["total"] for r in res if r["strategy"] == "direct")
emm = min((r for r in res if "emm" in r), key=lambda r: r["cycles"]["total"])
e = emm["emm"]
moved = e["demand_fetches"] + e["prefetches"]
print("fastest EMM strategy: %s, %.2fx direct reads; %d of its %d cell transfers (%.0f%%) "
      "refetch a cell, %.1f cells held on average"
      % (emm["strategy"], direct / emm["cycles"]["total"], e["refetches"], moved,
         100.0 * e["refetches"] / max(moved, 1), e["resident_cells"] / max(e["cell_changes"], 1)))
PY
