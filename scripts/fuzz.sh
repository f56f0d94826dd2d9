#!/usr/bin/env bash
# scripts/fuzz.sh BUILD SECONDS [HARNESS...]: runs each libFuzzer harness of
# tests/fuzz (built in BUILD by `make fuzz`) for SECONDS, one after the
# other, starting from a copy of its seed corpus and regression files, with
# a per-input time limit (-timeout=10 s) and a memory limit (-rss_limit_mb=2048,
# -malloc_limit_mb=256). New inputs go to BUILD/fuzz-work/HARNESS/corpus; an
# input that fails is written there as crash-*, timeout-* or oom-*: keep it
# as a regression file in tests/fuzz/regress/HARNESS/ once it is fixed.
# Prints, per harness, libFuzzer's executions, coverage (cov), features (ft)
# and corpus size; exits non-zero when any harness found a failure.
set -uo pipefail
build=$1 seconds=$2; shift 2
src="$(cd "$(dirname "$0")/.." && pwd)"
harnesses=("$@")
if [ ${#harnesses[@]} -eq 0 ]; then
  for f in "$build"/fuzz/fuzz_*; do harnesses+=("$(basename "$f" | sed 's/^fuzz_//')"); done
fi
failed=0
for h in "${harnesses[@]}"; do
  exe="$build/fuzz/fuzz_$h"
  [ -x "$exe" ] || { echo "fuzz: $exe not built (make fuzz builds it)" >&2; exit 2; }
  work="$build/fuzz-work/$h"
  mkdir -p "$work/corpus"
  touch "$work/.start"
  for d in "$src/tests/fuzz/corpus/$h" "$src/tests/fuzz/regress/$h"; do
    [ -d "$d" ] && cp -n "$d"/* "$work/corpus/" 2>/dev/null
  done
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    "$exe" "$work/corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -malloc_limit_mb=256 -print_final_stats=1 -artifact_prefix="$work/" > "$work/log" 2>&1
  rc=$?
  done_line=$(grep -E '^#[0-9]+[[:space:]]+DONE' "$work/log" | tail -1)
  execs=$(grep -E '^stat::number_of_executed_units' "$work/log" | awk '{print $2}')
  artifacts=$(find "$work" -maxdepth 1 -newer "$work/.start" \( -name 'crash-*' -o -name 'timeout-*' \
    -o -name 'oom-*' -o -name 'leak-*' \) | head -3)
  if [ $rc -ne 0 ] || [ -n "$artifacts" ]; then
    failed=1
    echo "fuzz $h: FAILED (exit $rc): $(grep -E 'ERROR|SUMMARY|Test unit written' "$work/log" | head -3 | tr '\n' ' ')"
  else
    echo "fuzz $h: ${seconds}s, ${execs:-?} executions, 0 crashes, 0 timeouts, 0 oom: ${done_line#*DONE   }"
  fi
done
exit $failed
