#!/bin/sh
# The session's own cost on one run (not a test: it times things).
#
#   sh bench/session_overhead.sh BUILD [FACES] [PASSES]
#
# examples/smooth.c on a generated mesh of FACES faces (default 100,000),
# PASSES Laplacian passes (default 10), the sancov build under
#   emm run --capture sancov --compare baselines
# (the window decided, the run probed for phases, the contest of every
# candidate, the phases, direct reads and the reference cache simulated
# over the whole run), against the plain build's native run of the same
# input, in this one command: median of 3 wall times, and of 3 CPU times
# (user + system, all threads) where /usr/bin/time exists. The same run as
# bench/valgrind_overhead.sh's sancov row, without Valgrind.
set -u
[ $# -ge 1 ] || { echo "usage: sh bench/session_overhead.sh BUILD [FACES] [PASSES]" >&2; exit 2; }
B=$(cd "$1" && pwd) || exit 1
FACES=${2:-100000} PASSES=${3:-10}
EMM=$B/bin/emm PROG=$B/bin/smooth SANCOV=$B/bin/smooth.sancov
for f in "$EMM" "$PROG" "$SANCOV"; do
  [ -e "$f" ] || { echo "session_overhead: $f is not built" >&2; exit 1; }
done
NAME=session_overhead
. "$(dirname "$0")/smooth_setup.sh"
TIME=
[ -x /usr/bin/time ] && TIME=/usr/bin/time

# median3 CMD...: three runs; prints the median wall time and the median CPU
# time in seconds ("-" without /usr/bin/time).
median3() {
  for _ in 1 2 3; do
    t0=$(now)
    if [ -n "$TIME" ]; then
      "$TIME" -f '%U %S' -o "$TMP/cpu" "$@" > "$TMP/out" 2> "$TMP/err"
    else
      "$@" > "$TMP/out" 2> "$TMP/err"
    fi || { cat "$TMP/err" >&2; echo "session_overhead: $* failed" >&2; exit 1; }
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
set -- $(median3 "$PROG" "$MESH" "$PASSES") || exit 1
nwall=$1 ncpu=$2
cp "$TMP/out" "$TMP/native.out"
# shellcheck disable=SC2046
set -- $(median3 "$EMM" run --capture sancov --compare baselines --tag "$TAG" -- "$SANCOV" "$MESH" \
  "$PASSES") || exit 1
swall=$1 scpu=$2
cmp -s "$TMP/out" "$TMP/native.out" || echo "session_overhead: output differs under emm run!"
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "-" || b == "-" || b <= 0) print "-"; else printf "%.0fx", a / b }'; }
echo "smooth on $FACES faces, $PASSES passes; medians of 3"
printf '  %-58s %8s s wall %8s s cpu\n' "native (plain build)" "$nwall" "$ncpu"
printf '  %-58s %8s s wall %8s s cpu\n' "emm run --capture sancov --compare baselines (the session)" \
  "$swall" "$scpu"
echo "  the session over the native run: $(ratio "$swall" "$nwall") wall, $(ratio "$scpu" "$ncpu") cpu"
