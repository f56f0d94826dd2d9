#!/bin/sh
# The workloads' speed on a generated 1,000,000-face mesh (clustered, seed 1),
# natively: for each, the median of three runs of the whole program (wall
# clock), of loading the mesh file (read_mesh: parse, validate, fill the
# records) and of the traversal itself, both as the program reports them
# with --times. Target: every workload under 10 s on a 2-core machine.
# Usage: bench/workloads.sh BUILD_DIR [FACES]
set -eu
build=${1:?usage: bench/workloads.sh BUILD_DIR [FACES]}
faces=${2:-1000000}
bin=$build/bin
dir=$build/bench
mesh=$dir/workloads-$faces.off
mkdir -p "$dir"
if [ ! -s "$mesh" ]; then
  echo "generating $mesh ..."
  "$bin/emm" mesh gen --faces "$faces" --seed 1 -o "$mesh"
fi

now() { date +%s.%N; }
median3() { printf '%s\n' "$@" | sort -g | sed -n 2p; }

printf '%-22s %9s %9s %9s   %s\n' workload total_s load_s run_s result
for args in "curve_tracing --short" "curve_tracing --long" region_growing random_access; do
  totals= loads= runs=
  for i in 1 2 3; do
    t0=$(now)
    # shellcheck disable=SC2086
    result=$("$bin"/$args --times "$mesh" 2>"$dir/times")
    t1=$(now)
    totals="$totals $(echo "$t1 - $t0" | awk '{ printf "%.3f", $1 - $3 }')"
    loads="$loads $(awk '{ print $2 }' "$dir/times")"
    runs="$runs $(awk '{ print $5 }' "$dir/times")"
  done
  # shellcheck disable=SC2086
  printf '%-22s %9s %9s %9s   %s\n' "$args" "$(median3 $totals)" "$(median3 $loads)" \
    "$(median3 $runs)" "$(printf '%s' "$result" | tr '\n' ' ')"
done
