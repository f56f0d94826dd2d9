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

# list_sites EMM PROGRAM ARGS...: the program natively (native.out), then
# under `emm run --list-sites` (list.out, list.err): same exit status and
# stdout; the listing is shown.
list_sites() {
  _emm=$1; shift
  env -u LD_PRELOAD "$@" > "$WORK/native.out"; native_rc=$?
  "$_emm" run --list-sites -- "$@" > "$WORK/list.out" 2> "$WORK/list.err"; _rc=$?
  [ $_rc = $native_rc ] || { cat "$WORK/list.err" >&2; fail "exit status $_rc under --list-sites, $native_rc natively"; }
  cmp -s "$WORK/native.out" "$WORK/list.out" || fail "stdout differs under --list-sites"
  cat "$WORK/list.err"
}

# run_suggested EMM RULES PROGRAM ARGS...: the rules --list-sites suggested,
# used as they are under fault capture (tagged.out, tagged.err, r.json):
# stdout as natively and an answer.
run_suggested() {
  _emm=$1 _rules=$2; shift 2
  "$_emm" run --capture fault --tag "$_rules" --report "$WORK/r.json" -- "$@" \
    > "$WORK/tagged.out" 2> "$WORK/tagged.err" || { cat "$WORK/tagged.err" >&2; fail "the suggested rules: run failed"; }
  cmp -s "$WORK/native.out" "$WORK/tagged.out" || fail "stdout differs under the suggested rules"
  grep -q '^emm: answer: ' "$WORK/tagged.err" || { cat "$WORK/tagged.err" >&2; fail "the suggested rules: no answer"; }
}
