#!/bin/sh
# Bad input: a missing file and a malformed one make each workload exit 1
# with one line "<prog>: <file>: <problem>" on stderr and nothing on stdout;
# bad usage exits 2; --help exits 0 with the usage on stdout.
. "$(dirname "$0")/lib.sh"
bin=$1 work=$4
mkdir -p "$work"
printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n' > "$work/truncated.off"
for prog in curve_tracing region_growing random_access; do
  for mesh in "$work/missing.off" "$work/truncated.off"; do
    "$bin/$prog" "$mesh" >"$work/out" 2>"$work/err"; rc=$?
    expect_eq "$prog $mesh exit" 1 "$rc"
    [ -s "$work/out" ] && fail "$prog $mesh: wrote to stdout"
    expect_eq "$prog $mesh stderr lines" 1 "$(wc -l < "$work/err" | tr -d ' ')"
    grep -q "^$prog: $mesh: " "$work/err" || fail "$prog $mesh: stderr: $(cat "$work/err")"
  done
  "$bin/$prog" --no-such-option >/dev/null 2>&1; expect_eq "$prog bad option" 2 $?
  "$bin/$prog" a.off b.off >/dev/null 2>&1; expect_eq "$prog two meshes" 2 $?
  "$bin/$prog" --help >"$work/out" 2>&1; expect_eq "$prog --help" 0 $?
  grep -q "^usage: $prog" "$work/out" || fail "$prog --help: $(cat "$work/out")"
done
"$bin/curve_tracing" --curves 0 >/dev/null 2>&1; expect_eq "--curves 0" 2 $?
"$bin/curve_tracing" --field sideways >/dev/null 2>&1; expect_eq "--field sideways" 2 $?
echo ok
