# Shared by the shim tests. Each script is called as
#   sh SCRIPT SHIM WORKDIR PROGRAM [ARGS...]
# and runs PROGRAM natively and under LD_PRELOAD=SHIM, with the EMM_*
# variables the script sets, comparing stdout and exit status.
fail() { echo "FAIL: $*" >&2; exit 1; }

SHIM=$1; WORK=$2; shift 2
rm -rf "$WORK" && mkdir -p "$WORK" || fail "cannot make $WORK"
# The tests must not depend on a strategy table being built: a fixed
# strategy (the decision is the session's, tested elsewhere) — except the
# decision tests (decide.sh), which set EMM_TEST_DECIDE.
if [ -z "${EMM_TEST_DECIDE:-}" ]; then
  EMM_STRATEGY=${EMM_STRATEGY:-cache}; export EMM_STRATEGY
fi

# run_both NAME PROGRAM [ARGS...]: native run into $WORK/NAME.native.*, shim
# run into $WORK/NAME.shim.*; fails unless stdout and exit status match.
run_both() {
  name=$1; shift
  env -u LD_PRELOAD "$@" > "$WORK/$name.native.out" 2> "$WORK/$name.native.err"
  native_rc=$?
  LD_PRELOAD="$SHIM" "$@" > "$WORK/$name.shim.out" 2> "$WORK/$name.shim.err"
  shim_rc=$?
  [ "$native_rc" = "$shim_rc" ] || { cat "$WORK/$name.shim.err" >&2; fail "$name: exit status $shim_rc under the shim, $native_rc natively"; }
  cmp -s "$WORK/$name.native.out" "$WORK/$name.shim.out" || {
    diff "$WORK/$name.native.out" "$WORK/$name.shim.out" >&2; cat "$WORK/$name.shim.err" >&2
    fail "$name: stdout differs under the shim"; }
}

# expect_err NAME REGEX: the shim run's stderr has a line matching REGEX.
expect_err() {
  grep -Eq -- "$2" "$WORK/$1.shim.err" || { cat "$WORK/$1.shim.err" >&2; fail "$1: no stderr line matches '$2'"; }
}
