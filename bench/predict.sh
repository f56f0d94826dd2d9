#!/bin/sh
# The prediction benchmark (make predict; docs/profile.md "The prediction
# benchmark"): a corpus of program traces — the example workloads (region
# growing, long and short curves, random access) and the traversal programs
# of bench/predict_traversals.c (walks, a flood fill, 8-seed growth, scans in
# index, row and Hilbert order, smoothing) over planar meshes of three sizes
# and two numberings and two 3D surfaces (sphere, torus) — each on the
# machines of bench/predict_machines/. For each case, the whole run's best
# strategy (`emm replay --all`, the cache left out) against the window's
# prediction, leave-one-program-out (build/bin/predict).
#
# The traces and the `replay --all` listings are kept in BUILD/bench/predict
# (delete it to start again): a rerun only decides the windows. Programs run
# under `emm run --capture sancov` (their instrumented builds). The cache is
# keyed so that nothing stale is reused: the traces on a hash of the
# programs, the capture libraries and the meshes (made again each run, a few
# seconds), the listings on that and on a hash of the model — each machine
# as `emm machine show` prints it, and `emm replay --all` of two small probe
# traces (a region growth over a planar mesh and over a sphere) on it, so a
# change in the simulator or the machine's defaults makes new listings. A
# key's folder replaces the others (they are deleted, with a message).
#
# usage: bench/predict.sh [BUILD_DIR] [extra arguments for build/bin/predict]
set -eu
build=${1:-build}
[ $# -gt 0 ] && shift
bin=$build/bin
src=$(cd "$(dirname "$0")" && pwd)
for x in emm predict predict_traversals.sancov region_growing.sancov; do
    [ -x "$bin/$x" ] || { echo "predict.sh: $bin/$x not built (make build)" >&2; exit 1; }
done
top=$build/bench/predict
mkdir -p "$top"
cases=$top/cases.txt
tmp=$top/tmp.$$
rm -rf "$tmp"
mkdir -p "$tmp"
trap 'rm -rf "$tmp"' EXIT INT TERM
# A hash of the files' contents (not their names: the temporary folder's
# changes each run).
key() { for f in "$@"; do sha256sum <"$f"; done | sha256sum | cut -c1-16; }

# name:surface:faces:seed:density:order — seeds no table mesh uses (11-14, 5-7).
meshes="p10c:plane:10000:41:clustered:made
p30u:plane:30000:42:uniform:made
p30r:plane:30000:42:uniform:random
p60h:plane:60000:43:clustered:hilbert
sph20:sphere:20000:44:-:made
tor30:torus:30000:45:-:made"

# program-name:executable:arguments (program-name is what the table's
# prog-NAME-... samples are called: curve_tracing's two runs are one program)
programs="region_growing:region_growing.sancov:
curve_tracing:curve_tracing.sancov:--long
curve_tracing:curve_tracing.sancov:--short
random_access:random_access.sancov:
walk:predict_traversals.sancov:walk
flood:predict_traversals.sancov:flood
seeds:predict_traversals.sancov:seeds
scan-index:predict_traversals.sancov:scan-index
scan-rows:predict_traversals.sancov:scan-rows
scan-hilbert:predict_traversals.sancov:scan-hilbert
smooth:predict_traversals.sancov:smooth"

# The meshes, made again (the generator may have changed), then the keys.
echo "$meshes" | while IFS=: read -r mname surface faces seed density order; do
    if [ "$density" = - ]; then
        "$bin/emm" mesh gen --surface "$surface" --faces "$faces" --seed "$seed" \
            --order "$order" -o "$tmp/$mname.off" >/dev/null
    else
        "$bin/emm" mesh gen --faces "$faces" --seed "$seed" --density "$density" \
            --order "$order" -o "$tmp/$mname.off" >/dev/null
    fi
done
capture=$(key "$bin/region_growing.sancov" "$bin/curve_tracing.sancov" \
    "$bin/random_access.sancov" "$bin/predict_traversals.sancov" \
    "$build/lib/libemmshim.so" "$build/lib/libemmhooks.so" "$tmp"/*.off)
"$bin/emm" mesh gen --faces 3000 --seed 9 -o "$tmp/probe-plane.off" >/dev/null
"$bin/emm" mesh gen --surface sphere --faces 3000 --seed 9 -o "$tmp/probe-sphere.off" >/dev/null
for p in plane sphere; do
    "$bin/emm" trace synth --mesh "$tmp/probe-$p.off" --pattern region --seed 9 \
        -o "$tmp/probe-$p.emmt" >/dev/null
done
for machine in "$src"/predict_machines/*.ini; do
    # The listing's first line names the file: only the settings key.
    "$bin/emm" machine show --machine "$machine" | tail -n +2 >"$tmp/model.$(basename "$machine")"
    for p in plane sphere; do
        "$bin/emm" replay "$tmp/probe-$p.emmt" --all --machine "$machine" |
            tail -n +2 >"$tmp/model.$p.$(basename "$machine")"
    done
done
model=$(key "$tmp"/model.*)
work=$top/$capture
lists=$work/model-$model
for old in "$top"/*/; do
    [ ! -d "$old" ] || [ "$old" = "$work/" ] || [ "$old" = "$tmp/" ] || {
        echo "predict.sh: removing ${old%/} (made by other programs or meshes)" >&2
        rm -rf "$old"
    }
done
for old in "$work"/model-*/; do
    [ -d "$old" ] && [ "$old" != "$lists/" ] && {
        echo "predict.sh: removing ${old%/} (made on another model)" >&2
        rm -rf "$old"
    }
done
if ls "$top"/*.emmt "$top"/*.all >/dev/null 2>&1; then
    echo "predict.sh: removing the unkeyed traces and listings of $top" >&2
    rm -f "$top"/*.emmt "$top"/*.all "$top"/*.off
fi
mkdir -p "$lists"
for m in "$tmp"/*.off; do
    case $m in */probe-*) continue ;; esac
    cmp -s "$m" "$work/${m##*/}" 2>/dev/null || mv "$m" "$work/${m##*/}"
done
: >"$cases.new"

echo "$meshes" | while IFS=: read -r mname surface faces seed density order; do
    mesh=$work/$mname.off
    echo "$programs" | while IFS=: read -r prog exe arg; do
        case $prog in
            curve_tracing) case_name=curve${arg#-}-$mname ;;
            *) case_name=$prog-$mname ;;
        esac
        trace=$work/$case_name.emmt
        if [ ! -s "$trace" ]; then
            # shellcheck disable=SC2086 # $arg is one word or none
            "$bin/emm" run --quiet --capture sancov --trace "$trace.tmp" -- \
                "$bin/$exe" $arg "$mesh" >/dev/null
            mv "$trace.tmp" "$trace"
        fi
        for machine in "$src"/predict_machines/*.ini; do
            mach=$(basename "$machine" .ini)
            all=$lists/$case_name.$mach.all
            if [ ! -s "$all" ]; then
                "$bin/emm" replay "$trace" --all --machine "$machine" >"$all.tmp"
                mv "$all.tmp" "$all"
            fi
            echo "$prog $case_name $trace $machine $all" >>"$cases.new"
        done
    done
done
mv "$cases.new" "$cases"
"$bin/predict" "$cases" "$@"
