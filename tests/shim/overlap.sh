# Two rules that overlap (issue: "rule 2 matched no allocation; no block of
# 4096 bytes or more was allocated" though rule 1 had taken its block): on
# tests/shim/untagged.c, rule 1 (16-byte records, no site) selects both the
# vertex block and the triangle block, so rule 2, the triangles' rule, tags
# nothing. The line at exit says where its block went, under plain
# LD_PRELOAD and under emm run with the fault and valgrind captures; the
# program's stdout and exit status are the native run's.
#   sh overlap.sh SHIM WORK EMM VALGRIND(0|1) PROGRAM
. "$(dirname "$0")/lib.sh"
EMM=$1 VG=$2 PROG=$3
TAG='vertices:stride=16,xyz=4:f32;triangles:stride=16,vidx=4:i32'
want="^emm: EMM_TAG rule 2 \(triangles:stride=16,vidx=4:i32\) tagged nothing: the 2 blocks it selects \(up to 131072 bytes\) went to rule 1 \(vertices:stride=16,xyz=4:f32\) first, which tagged them as vertices; narrow rule 1"
env -u LD_PRELOAD "$PROG" > "$WORK/native.out" 2>/dev/null; native_rc=$?

EMM_TAG=$TAG LD_PRELOAD="$SHIM" "$PROG" > "$WORK/preload.out" 2> "$WORK/preload.err"; rc=$?
[ $rc = $native_rc ] || fail "LD_PRELOAD: exit status $rc, $native_rc natively"
cmp -s "$WORK/native.out" "$WORK/preload.out" || fail "LD_PRELOAD: stdout differs"
grep -Eq "$want" "$WORK/preload.err" || { cat "$WORK/preload.err" >&2; fail "LD_PRELOAD: no line says where rule 2's block went"; }
grep -q 'rule 2.*matched no allocation' "$WORK/preload.err" && fail "LD_PRELOAD: rule 2 said to match no allocation"

captures=fault
[ "$VG" = 1 ] && captures="fault valgrind"
for capture in $captures; do
  "$EMM" run --capture "$capture" --tag "$TAG" -- "$PROG" > "$WORK/$capture.out" 2> "$WORK/$capture.err"; rc=$?
  [ $rc = $native_rc ] || { cat "$WORK/$capture.err" >&2; fail "$capture: exit status $rc"; }
  cmp -s "$WORK/native.out" "$WORK/$capture.out" || fail "$capture: stdout differs"
  grep -Eq "$want" "$WORK/$capture.err" || { cat "$WORK/$capture.err" >&2; fail "$capture: no line says where rule 2's block went"; }
done
echo "overlap: ok ($captures, LD_PRELOAD)"
