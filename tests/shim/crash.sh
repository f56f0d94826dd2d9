# Reports outlive the program: a program that dies of SIGSEGV after walking
# its mesh (tests/shim/crash.c) keeps its native exit status under plain
# LD_PRELOAD and under emm run with the fault and valgrind captures, and
# its report is written, "ended": "signal 11 (SIGSEGV)", with a decision;
# the summary says how the run ended. A program that closes every
# descriptor (tests/shim/closefd.c all) under valgrind capture, which takes
# the socket to emm-session with them, still gets its report, "ended"
# saying the connection ended before the program's exit.
#   sh crash.sh SHIM WORK EMM VALGRIND(0|1) CRASH CLOSEFD
. "$(dirname "$0")/lib.sh"
EMM=$1 VG=$2 CRASH=$3 CLOSEFD=$4
unset EMM_STRATEGY
TAG='vertices:site=load_grid,stride=32,xyz=8:f64;triangles:site=load_grid,stride=16,vidx=4:i32'
env -u LD_PRELOAD "$CRASH" > "$WORK/native.out" 2>/dev/null; native_rc=$?
[ $native_rc = 139 ] || fail "the native run did not die of SIGSEGV (status $native_rc)"

# ended NAME REPORT WANT: the report's "ended" is WANT and it has a decision.
ended() {
  [ -s "$2" ] || { cat "$WORK/$1.err" >&2; fail "$1: no report"; }
  python3 - "$2" "$3" "$1" <<'PY' || fail "$1: the report is not as expected"
import json, sys
r = json.load(open(sys.argv[1]))
assert r.get("ended") == sys.argv[2], "%s: ended %r, expected %r" % (sys.argv[3], r.get("ended"), sys.argv[2])
assert r.get("strategy"), "%s: no strategy in the report" % sys.argv[3]
assert r.get("accesses", 0) > 0, "%s: no accesses" % sys.argv[3]
PY
}

EMM_TAG=$TAG EMM_REPORT="$WORK/preload.json" LD_PRELOAD="$SHIM" "$CRASH" > "$WORK/preload.out" 2> "$WORK/preload.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/preload.err" >&2; fail "LD_PRELOAD: exit status $rc, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/preload.out" || fail "LD_PRELOAD: stdout differs"
ended preload "$WORK/preload.json" "signal 11 (SIGSEGV)"
grep -q '^emm:   the run ended by signal 11 (SIGSEGV)' "$WORK/preload.err" || { cat "$WORK/preload.err" >&2; fail "LD_PRELOAD: the summary does not say how the run ended"; }

captures=fault
[ "$VG" = 1 ] && captures="fault valgrind"
for capture in $captures; do
  "$EMM" run --capture "$capture" --tag "$TAG" --report "$WORK/$capture.json" -- "$CRASH" \
    > "$WORK/$capture.out" 2> "$WORK/$capture.err"; rc=$?
  [ $rc = $native_rc ] || { cat "$WORK/$capture.err" >&2; fail "$capture: exit status $rc, $native_rc natively"; }
  cmp -s "$WORK/native.out" "$WORK/$capture.out" || fail "$capture: stdout differs"
  ended "$capture" "$WORK/$capture.json" "signal 11 (SIGSEGV)"
done

if [ "$VG" = 1 ]; then
  mkdir -p "$WORK/all.native" "$WORK/all.vg"
  env -u LD_PRELOAD "$CLOSEFD" "$WORK/all.native" all > /dev/null 2>&1; native_rc=$?
  "$EMM" run --capture valgrind --tag "$TAG" --report "$WORK/closed.json" -- "$CLOSEFD" "$WORK/all.vg" all \
    > "$WORK/closed.out" 2> "$WORK/closed.err"; rc=$?
  [ $rc = $native_rc ] || { cat "$WORK/closed.err" >&2; fail "closed descriptors: exit status $rc, $native_rc natively"; }
  for f in a b c; do cmp -s "$WORK/all.native/$f.dat" "$WORK/all.vg/$f.dat" || fail "closed descriptors: $f.dat differs"; done
  # emm-session writes the report once it sees the connection end; emm run
  # has waited for it: the report is there, and its summary said how the
  # run ended.
  grep -q "^emm:   the run ended by the end of the program's connection" "$WORK/closed.err" ||
    { cat "$WORK/closed.err" >&2; fail "closed descriptors: the summary does not say how the run ended"; }
  ended closed "$WORK/closed.json" "the end of the program's connection to emm-session, before its exit"
fi
echo "crash: ok ($captures, LD_PRELOAD)"
