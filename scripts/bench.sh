#!/bin/sh
# make bench: every benchmark of bench/, one after the other. Each prints its
# own figures (times as medians, throughputs, ratios to a baseline run in the
# same command). Benchmarks are reports, not tests: nothing here fails on a
# slow machine. Usage: scripts/bench.sh BUILD_DIR [NAME...]
set -eu
build=${1:?usage: scripts/bench.sh BUILD_DIR [NAME...]}
shift
here=$(cd "$(dirname "$0")/.." && pwd)
selected() {
  [ -z "$names" ] && return 0
  for n in $names; do [ "$n" = "$1" ] && return 0; done
  return 1
}
names="$*"

run() {
  name=$1
  shift
  selected "$name" || return 0
  printf '\n==== bench: %s\n' "$name"
  "$@" || echo "bench $name failed (exit $?)"
}

for sh in "$here"/bench/*.sh; do
  [ -e "$sh" ] || continue
  run "$(basename "$sh" .sh)" sh "$sh" "$build"
done
for exe in replay_throughput profile_speed decision_quality; do
  [ -x "$build/bin/$exe" ] && run "$exe" "$build/bin/$exe"
done
exit 0
