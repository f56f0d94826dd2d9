# Any program under emm run --capture valgrind, with the EMM_* variables the
# test sets: stdout and exit status as in the native run, and a summary.
#   sh valgrind_plain.sh SHIM WORKDIR EMM PROGRAM [ARGS...]
. "$(dirname "$0")/lib.sh"
EMM=$1; shift
env -u LD_PRELOAD "$@" > "$WORK/native.out"; native_rc=$?
"$EMM" run --capture valgrind -- "$@" > "$WORK/valgrind.out" 2> "$WORK/valgrind.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/valgrind.err" >&2; fail "exit status $rc under valgrind capture, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/valgrind.out" || { cat "$WORK/valgrind.err" >&2; fail "stdout differs"; }
grep -Eq '^emm: .*[0-9] cycles' "$WORK/valgrind.err" || { cat "$WORK/valgrind.err" >&2; fail "no summary"; }
echo "valgrind_plain: ok"
