# The valgrind capture on a program nobody tagged by hand or instrumented
# (examples/smooth.c, EMM_TAG rules), as emm run's auto picks it for such a
# binary (no --capture given):
#   sh valgrind.sh SHIM WORKDIR EMM SANCOV_BUILD PROGRAM MESH
# stdout and exit status as in the native run; the report covers the whole
# run; its element accesses are its sancov build's, within 1%.
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM=$1 SANCOV=$2; shift 2
TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
report() { python3 -c "import json; r = json.load(open('$1')); print($2)"; }
env -u LD_PRELOAD "$@" > "$WORK/native.out"; native_rc=$?
"$EMM" run --tag "$TAG" --report "$WORK/valgrind.json" -- "$@" \
  > "$WORK/valgrind.out" 2> "$WORK/valgrind.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/valgrind.err" >&2; fail "exit status $rc under valgrind capture, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/valgrind.out" || { cat "$WORK/valgrind.err" >&2; fail "stdout differs under valgrind capture"; }
grep -q '^emm: answer: ' "$WORK/valgrind.err" || { cat "$WORK/valgrind.err" >&2; fail "no answer"; }
grep -q 'simulated: the whole run from the frozen mesh on, .*(the valgrind capture)' "$WORK/valgrind.err" ||
  fail "the summary does not say the whole run was simulated"
[ "$(report "$WORK/valgrind.json" "r['coverage']['simulated']")" = run ] || fail "coverage.simulated is not 'run'"
[ "$(report "$WORK/valgrind.json" "r['capture']")" = valgrind ] || fail "capture is not 'valgrind'"
shift
"$EMM" run --capture sancov --tag "$TAG" --report "$WORK/sancov.json" -- "$SANCOV" "$@" \
  > "$WORK/sancov.out" 2> "$WORK/sancov.err" || { cat "$WORK/sancov.err" >&2; fail "the sancov build failed"; }
cmp -s "$WORK/native.out" "$WORK/sancov.out" || fail "the sancov build prints something else"
v=$(report "$WORK/valgrind.json" "r['coverage']['element_accesses']")
s=$(report "$WORK/sancov.json" "r['coverage']['element_accesses']")
echo "element accesses: valgrind $v, sancov $s"
python3 -c "import sys; v, s = $v, $s; sys.exit(0 if s > 0 and abs(v - s) <= 0.01 * s else 1)" ||
  fail "element accesses differ by more than 1%: valgrind $v, sancov $s"
echo "valgrind: ok"
