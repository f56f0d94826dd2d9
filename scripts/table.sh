#!/bin/sh
# Rebuilds the shipped strategy table, data/table.txt (docs/profile.md):
# the canonical patterns of `emm table build`, and the example workloads'
# own traces — region growing, long and short curves, random access, and
# the traversal programs of bench/predict_traversals.c (walks, flood fill,
# 8-seed growth, scans in three orders, smoothing) — recorded under
# `emm run` on three generated planar meshes (one randomly numbered) and
# three with depth (a 16k and a 32k sphere, a 24k torus) that neither the
# tests, the demo nor `make predict` use (seeds 5–10; the default mesh is
# seed 1), as the thesis' Table 5.1 holds profiles of its applications.
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
# faces:seed:density:order (density - : a sphere; torus: a torus)
for mesh in 12000:5:clustered:made 24000:6:uniform:random 16000:7:clustered:made \
            16000:8:-:made 24000:9:torus:made 32000:10:-:made; do
    faces=${mesh%%:*}
    rest=${mesh#*:}
    seed=${rest%%:*}
    rest=${rest#*:}
    density=${rest%%:*}
    order=${rest#*:}
    if [ "$density" = torus ]; then
        "$bin/emm" mesh gen --surface torus --faces "$faces" --seed "$seed" --order "$order" \
            -o "$work/mesh-$seed.off" >/dev/null
    elif [ "$density" = - ]; then
        "$bin/emm" mesh gen --surface sphere --faces "$faces" --seed "$seed" --order "$order" \
            -o "$work/mesh-$seed.off" >/dev/null
    else
        "$bin/emm" mesh gen --faces "$faces" --seed "$seed" --density "$density" \
            --order "$order" -o "$work/mesh-$seed.off" >/dev/null
    fi
    # program:arguments:class:recipe (the traversal programs of
    # bench/predict_traversals.c take their mode as the argument and are
    # named by it: prog-walk-5-w4096)
    for w in region_growing::region:- curve_tracing:--long:curve:- \
             curve_tracing:--short:curve:- random_access::random:- \
             predict_traversals:walk:curve:- predict_traversals:flood:region:- \
             predict_traversals:seeds:region:- predict_traversals:scan-index:scanline:- \
             predict_traversals:scan-rows:scanline:- predict_traversals:scan-hilbert:hilbert:- \
             predict_traversals:smooth:scanline:-; do
        prog=${w%%:*}; rest=${w#*:}
        arg=${rest%%:*}; rest=${rest#*:}
        class=${rest%%:*}; recipe=${rest#*:}
        case $prog in
            predict_traversals) name=$arg-$seed ;;
            *) name=$prog${arg:+$arg}-$seed ;;
        esac
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
# The programs' runs are measured on the default machine and on the second
# machine of the prediction benchmark (bench/predict_machines): each sample
# carries its machine's fingerprint and its run's costs.
"$bin/emm" table build -o "$out" "$@" \
    --program-machine "$(dirname "$0")/../bench/predict_machines/small_store.ini"
