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
# under `emm run --capture sancov` (their instrumented builds).
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
work=$build/bench/predict
mkdir -p "$work"
cases=$work/cases.txt
: >"$cases.new"

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

echo "$meshes" | while IFS=: read -r mname surface faces seed density order; do
    mesh=$work/$mname.off
    if [ ! -s "$mesh" ]; then
        if [ "$density" = - ]; then
            "$bin/emm" mesh gen --surface "$surface" --faces "$faces" --seed "$seed" \
                --order "$order" -o "$mesh" >/dev/null
        else
            "$bin/emm" mesh gen --faces "$faces" --seed "$seed" --density "$density" \
                --order "$order" -o "$mesh" >/dev/null
        fi
    fi
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
            all=$work/$case_name.$mach.all
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
