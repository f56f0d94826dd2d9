#!/bin/sh
# The shim's overhead (issue 6's benchmark; not a test: it times things).
#
#   sh bench/shim_overhead.sh BUILD
#
# 1. Wall-time ratio of `curve_tracing.sancov --long` on a 1,000,000-face
#    mesh under libemmshim.so (EMM_COMPARE=baselines: the chosen strategy,
#    direct and cache simulated over the whole run) to the plain build's
#    native run, and the same of CPU times. Median of 3 runs each.
#    Target: at most 5x (Cachegrind runs 20-100x slower than native,
#    DynamoRIO's cache simulator 15-100x).
# 2. The cost of one access captured by EMM_CAPTURE=fault (a page fault and a
#    single step, then the session): the plain build under fault capture with
#    a window of 50,000 element accesses; its time beyond the native run's,
#    divided by the accesses its report counts. (The window comes after the
#    program's leading sweep over its vertices, which fault capture records
#    too, so two windows of different sizes differ by too little to measure.)
# The mesh is generated once and cached as BUILD/bench/mesh1m.off.
# Without a strategy table (data/table.txt) the session cannot decide, so the
# strategy is fixed (EMM_STRATEGY, default tiles+extrapolated@64) and the
# output says so.
set -u
[ $# -eq 1 ] || { echo "usage: sh bench/shim_overhead.sh BUILD" >&2; exit 2; }
B=$(cd "$1" && pwd) || exit 1
SRC=$(cd "$(dirname "$0")/.." && pwd)
EMM=$B/bin/emm SHIM=$B/lib/libemmshim.so
PLAIN=$B/bin/curve_tracing SANCOV=$B/bin/curve_tracing.sancov
for f in "$EMM" "$SHIM" "$PLAIN" "$SANCOV"; do
  [ -e "$f" ] || { echo "shim_overhead: $f is not built" >&2; exit 1; }
done
mkdir -p "$B/bench" || exit 1
MESH=$B/bench/mesh1m.off
if [ ! -s "$MESH" ]; then
  "$EMM" mesh gen --faces 1000000 -o "$MESH.tmp.off" >/dev/null && mv "$MESH.tmp.off" "$MESH" || exit 1
fi
TMP=$(mktemp -d) || exit 1
trap 'rm -rf "$TMP"' EXIT

unset EMM_TAG EMM_REPORT EMM_TRACE EMM_PROFILE_DUMP EMM_PROFILE EMM_CAPTURE EMM_LOG
if [ -n "${EMM_STRATEGY:-}" ]; then
  echo "strategy: $EMM_STRATEGY (EMM_STRATEGY)"
elif [ -f "$SRC/data/table.txt" ]; then
  echo "strategy: decided by the session from the strategy table"
else
  EMM_STRATEGY=tiles+extrapolated@64
  echo "strategy: $EMM_STRATEGY (fixed: no data/table.txt yet, so the session cannot decide)"
fi
[ -n "${EMM_STRATEGY:-}" ] && export EMM_STRATEGY

now() { date +%s%N; }
TIME=
[ -x /usr/bin/time ] && TIME=/usr/bin/time
# median3 CMD...: runs CMD three times (stdout to $TMP/out, stderr to
# $TMP/err) and prints the median wall time and the median CPU time (user +
# system, all threads; "-" without /usr/bin/time) in seconds. The CPU time
# moves less when other work shares the machine.
median3() {
  for i in 1 2 3; do
    t0=$(now)
    if [ -n "$TIME" ]; then
      "$TIME" -f '%U %S' -o "$TMP/cpu" "$@" > "$TMP/out" 2> "$TMP/err"
    else
      "$@" > "$TMP/out" 2> "$TMP/err"
    fi || { cat "$TMP/err" >&2; echo "shim_overhead: $* failed" >&2; exit 1; }
    wall=$(( $(now) - t0 ))
    cpu=-
    [ -n "$TIME" ] && cpu=$(tail -1 "$TMP/cpu" | awk '{ printf "%.3f", $1 + $2 }')
    echo "$wall $cpu"
  done > "$TMP/times"
  w=$(awk '{ print $1 }' "$TMP/times" | sort -n | sed -n 2p | awk '{ printf "%.3f", $1 / 1e9 }')
  c=$(awk '{ print $2 }' "$TMP/times" | sort -n | sed -n 2p)
  echo "$w $c"
}

# shellcheck disable=SC2046 # two words: the wall and the CPU time
set -- $(median3 env -u LD_PRELOAD "$PLAIN" --long "$MESH") || exit 1
native=$1 native_cpu=$2
cp "$TMP/out" "$TMP/native.out"
# shellcheck disable=SC2046
set -- $(median3 env -u LD_PRELOAD "$SANCOV" --long "$MESH") || exit 1
hooks=$1 hooks_cpu=$2
# shellcheck disable=SC2046
set -- $(median3 env LD_PRELOAD="$SHIM" EMM_COMPARE=baselines "$SANCOV" --long "$MESH") || exit 1
shim=$1 shim_cpu=$2
cmp -s "$TMP/out" "$TMP/native.out" || echo "WARNING: stdout under the shim differs from the native run"
echo "the last run's summary:"
sed 's/^/  /' "$TMP/err"
echo "curve_tracing --long, 1,000,000 faces (medians of 3):"
printf '  %-36s %8s s wall %8s s cpu\n' "plain build, native:" "$native" "$native_cpu"
printf '  %-36s %8s s wall %8s s cpu (no-op hooks)\n' "instrumented build, native:" "$hooks" "$hooks_cpu"
printf '  %-36s %8s s wall %8s s cpu\n' "instrumented build under the shim:" "$shim" "$shim_cpu"
awk -v s="$shim" -v n="$native" -v sc="$shim_cpu" -v nc="$native_cpu" 'BEGIN { r = s / n;
  printf "shim overhead: %.2fx the plain native run", r
  if (sc != "-" && nc > 0) printf " (cpu %.2fx)", sc / nc
  printf " (target <= 5x: %s)\n", r <= 5 ? "met" : "NOT met" }'

# fault capture: one window; the time beyond the native run per captured access.
fault_run() { # WINDOW -> wall seconds; the report in $TMP/f$WINDOW.json
  t0=$(now)
  env LD_PRELOAD="$SHIM" EMM_CAPTURE=fault EMM_COMPARE=baselines EMM_PROFILE=$1 \
      EMM_REPORT="$TMP/f$1.json" "$PLAIN" --long "$MESH" > /dev/null 2> "$TMP/ferr" ||
      { cat "$TMP/ferr" >&2; exit 1; }
  echo $(( $(now) - t0 ))
}
accesses() { sed -n 's/^  "accesses": \([0-9]*\),*$/\1/p' "$1"; }
window=50000
tf=$(fault_run $window) || exit 1
af=$(accesses "$TMP/f$window.json")
[ -n "$af" ] && [ "$af" -gt 0 ] ||
  { echo "shim_overhead: the fault run's report counts no accesses" >&2; exit 1; }
awk -v tf="$tf" -v af="$af" -v w=$window -v n="$native" 'BEGIN {
  printf "fault capture: window of %d element accesses: %d accesses captured in %.3f s (native %.3f s)\n",
         w, af, tf / 1e9, n
  printf "fault capture: %.2f us per captured access (fault, single step, session)\n",
         (tf / 1e9 - n) * 1e6 / af }'
