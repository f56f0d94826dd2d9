# The program's own SIGSEGV handler gets its own faults under fault capture.
. "$(dirname "$0")/lib.sh"
EMM_CAPTURE=fault EMM_TAG='vertices:site=load,stride=32,xyz=8:f64' EMM_LOG=2
export EMM_CAPTURE EMM_TAG EMM_LOG
run_both segv "$@"
grep -q 'caught: 2' "$WORK/segv.shim.out" || fail "the program's handler did not run twice"
grep -q 'handler kept: yes' "$WORK/segv.shim.out" || fail "sigaction did not give back the program's handler"
expect_err segv 'tagged vertices at 0x[0-9a-f]+: 4000 records'
echo "segv: ok"
