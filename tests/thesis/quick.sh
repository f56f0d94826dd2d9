#!/bin/sh
# bench/thesis --quick --calibrate on a 2,000-face mesh: it must finish, print
# the table of each of Figs. 6.1-6.9, exactly one REPRODUCED / NOT REPRODUCED
# verdict for each of the 6 statements of chapter 6 (and a summary that
# counts them), the
# profiler's choice for each workload, the contest's halving against every
# candidate, and the calibration's grid and outcome.
# The verdicts themselves are not checked: they are the model's findings.
# Usage: quick.sh BENCH_THESIS BUILD_DIR WORK_DIR
set -eu
script=$1 build=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
out=$work/out.txt
"$script" --quick --calibrate --out "$work" "$build" >"$out" 2>"$work/err.txt" || {
  echo "bench/thesis --quick failed:"; cat "$work/err.txt" "$out"; exit 1; }
fail=0
no() { echo "quick.sh: $*"; fail=1; }
for fig in 6.1 6.2 6.3 6.4 6.5 6.6 6.7 6.8 6.9; do
  grep -q "^Fig $fig  " "$out" || no "no table for Fig $fig"
done
for n in 1 2 3 4 5 6; do
  c=$(grep -Ec "^claim $n .*: (NOT )?REPRODUCED\$" "$out" || true)
  # once in the main verdicts, at most once more in the predictions
  [ "$c" -ge 1 ] && [ "$c" -le 2 ] || no "claim $n: $c verdict lines"
done
grep -Eq '^[0-6] of 6 statements reproduced$' "$out" || no "no summary line"
got=$(grep -Ec '^claim [1-6] .*: REPRODUCED$' "$out" || true)
sum=$(grep -E '^[0-6] of 6 statements reproduced$' "$out" | awk '{ s += $1 } END { print s + 0 }')
[ "$got" = "$sum" ] || no "summary counts $sum reproduced, verdict lines say $got"
for w in "short curves" "long curves" "region growing" "random access"; do
  grep -Eq "^  $w +[a-z-]+ +[a-z]" "$out" || no "no profiler choice for $w"
done
grep -Eq '^  halving missed the best in [0-4] of 4 workloads; mean regret ' "$out" ||
  no "no line on the contest's halving against every candidate"
grep -Eq '^  16 +125 ' "$out" || no "calibration grid incomplete"
grep -Eq '^  (fitted|NOT FITTED): ' "$out" || no "no calibration outcome"
for f in curves-short curves-long region random; do
  [ -s "$work/$f.json" ] && [ -s "$work/$f.emmt" ] || no "$f: no report or trace"
done
[ $fail = 0 ] || { cat "$out"; exit 1; }
echo "bench/thesis --quick: all sections present"
