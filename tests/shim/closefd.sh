# emm's words go only where emm means them to (tests/shim/closefd.c): a
# program that closes its stderr and opens data files keeps them byte for
# byte as natively under plain LD_PRELOAD and under emm run with the fault
# and valgrind captures, exit status as natively, and emm's summary still
# reaches the stderr the program was started with.
#   sh closefd.sh SHIM WORK EMM VALGRIND(0|1) PROGRAM
. "$(dirname "$0")/lib.sh"
EMM=$1 VG=$2 PROG=$3
TAG='vertices:site=load_grid,stride=32,xyz=8:f64;triangles:site=load_grid,stride=16,vidx=4:i32'
mkdir -p "$WORK/native"
env -u LD_PRELOAD "$PROG" "$WORK/native" > "$WORK/native.out" 2> "$WORK/native.err"; native_rc=$?
[ $native_rc = 0 ] || fail "the native run failed ($native_rc)"
[ -s "$WORK/native/c.dat" ] || fail "the native run wrote no third file"

# same NAME: NAME's data files are the native run's.
same() {
  for f in a b c; do
    cmp -s "$WORK/native/$f.dat" "$WORK/$1/$f.dat" || {
      diff "$WORK/native/$f.dat" "$WORK/$1/$f.dat" >&2; fail "$1: $f.dat differs from the native run's"; }
  done
}

mkdir -p "$WORK/preload"
EMM_TAG=$TAG LD_PRELOAD="$SHIM" "$PROG" "$WORK/preload" > "$WORK/preload.out" 2> "$WORK/preload.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/preload.err" >&2; fail "LD_PRELOAD: exit status $rc, $native_rc natively"; }
same preload
grep -q '^emm: .*[0-9] cycles' "$WORK/preload.err" || { cat "$WORK/preload.err" >&2; fail "LD_PRELOAD: no summary on the original stderr"; }

captures=fault
[ "$VG" = 1 ] && captures="fault valgrind"
for capture in $captures; do
  mkdir -p "$WORK/$capture"
  "$EMM" run --capture "$capture" --tag "$TAG" -- "$PROG" "$WORK/$capture" \
    > "$WORK/$capture.out" 2> "$WORK/$capture.err"; rc=$?
  [ $rc = $native_rc ] || { cat "$WORK/$capture.err" >&2; fail "$capture: exit status $rc, $native_rc natively"; }
  same "$capture"
  grep -q '^emm: .*[0-9] cycles' "$WORK/$capture.err" || { cat "$WORK/$capture.err" >&2; fail "$capture: no summary on the original stderr"; }
done
echo "closefd: ok ($captures, LD_PRELOAD)"
