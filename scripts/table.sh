#!/bin/sh
# Rebuilds the shipped strategy table, data/table.txt (docs/profile.md):
# the canonical patterns of `emm table build`, and the example workloads'
# own traces — region growing, long and short curves, random access,
# recorded under `emm run` on three generated meshes that neither the tests
# nor the demo use (seeds 5–7; the default mesh is seed 1) — as the thesis'
# Table 5.1 holds profiles of its applications.
#
# usage: scripts/table.sh [BUILD_DIR] [OUTPUT]   (defaults: build data/table.txt)
set -eu
build=${1:-build}
out=${2:-data/table.txt}
bin=$build/bin
[ -x "$bin/emm" ] || { echo "table.sh: $bin/emm not built (make build)" >&2; exit 1; }
work=$(mktemp -d "${TMPDIR:-/tmp}/emm-table-XXXXXX")
trap 'rm -rf "$work"' EXIT INT TERM

set --
for mesh in 12000:5:clustered 24000:6:uniform 16000:7:clustered; do
    faces=${mesh%%:*}
    rest=${mesh#*:}
    seed=${rest%%:*}
    density=${rest#*:}
    "$bin/emm" mesh gen --faces "$faces" --seed "$seed" --density "$density" \
        -o "$work/mesh-$seed.off" >/dev/null
    # program:arguments:class:recipe
    for w in region_growing::region:- curve_tracing:--long:curve:- \
             curve_tracing:--short:curve:- random_access::random:-; do
        prog=${w%%:*}; rest=${w#*:}
        arg=${rest%%:*}; rest=${rest#*:}
        class=${rest%%:*}; recipe=${rest#*:}
        name=$prog${arg:+$arg}-$seed
        if [ -x "$bin/$prog.sancov" ]; then
            exe=$bin/$prog.sancov capture=sancov
        else
            exe=$bin/$prog capture=fault
        fi
        # shellcheck disable=SC2086 # $arg is one word or none
        "$bin/emm" run --quiet --capture "$capture" --trace "$work/$name.emmt" -- \
            "$exe" $arg "$work/mesh-$seed.off" >/dev/null
        set -- "$@" --program "$work/$name.emmt:$class:$recipe"
    done
done
"$bin/emm" table build -o "$out" "$@"
