# The valgrind capture on a program nobody tagged by hand or instrumented
# (examples/smooth.c, EMM_TAG rules), as emm run's auto picks it for such a
# binary (no --capture given; --verbose says so, and the summary):
#   sh valgrind.sh SHIM WORKDIR EMM SANCOV_BUILD PROGRAM MESH
# stdout and exit status as in the native run; the report covers the whole
# run; its element accesses are its sancov build's, within 1%.
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM=$1 SANCOV=$2; shift 2
TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
env -u LD_PRELOAD "$@" > "$WORK/native.out"; native_rc=$?
"$EMM" run --verbose --tag "$TAG" --report "$WORK/valgrind.json" -- "$@" \
  > "$WORK/valgrind.out" 2> "$WORK/valgrind.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/valgrind.err" >&2; fail "exit status $rc under valgrind capture, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/valgrind.out" || { cat "$WORK/valgrind.err" >&2; fail "stdout differs under valgrind capture"; }
grep -q '^emm: answer: ' "$WORK/valgrind.err" || { cat "$WORK/valgrind.err" >&2; fail "no answer"; }
grep -q "simulated: the whole run from the frozen mesh on, .*(the valgrind capture, --capture auto's pick" "$WORK/valgrind.err" ||
  fail "the summary does not say the whole run was simulated, by auto's pick"
# auto says which backend it took and why (--verbose).
grep -q "^emm: run: --capture auto: valgrind for .*: emm's Valgrind tool captures the whole run" "$WORK/valgrind.err" ||
  { cat "$WORK/valgrind.err" >&2; fail "--verbose does not say why auto took valgrind"; }
# The reports are read by Python's own JSON parser, each check with its
# own message: here the valgrind run's, at the end both runs' counts.
python3 - "$WORK/valgrind.json" <<'PY' || exit 1
import json, sys
r = json.load(open(sys.argv[1]))
if r['coverage']['simulated'] != 'run':
    sys.exit("FAIL: coverage.simulated is not 'run'")
if r['capture'] != 'valgrind':
    sys.exit("FAIL: capture is not 'valgrind'")
PY
shift
"$EMM" run --capture sancov --tag "$TAG" --report "$WORK/sancov.json" -- "$SANCOV" "$@" \
  > "$WORK/sancov.out" 2> "$WORK/sancov.err" || { cat "$WORK/sancov.err" >&2; fail "the sancov build failed"; }
cmp -s "$WORK/native.out" "$WORK/sancov.out" || fail "the sancov build prints something else"
python3 - "$WORK/valgrind.json" "$WORK/sancov.json" <<'PY' || exit 1
import json, sys
v, s = (json.load(open(p))['coverage']['element_accesses'] for p in sys.argv[1:3])
print("element accesses: valgrind %s, sancov %s" % (v, s))
if not (s > 0 and abs(v - s) <= 0.01 * s):
    sys.exit("FAIL: element accesses differ by more than 1%%: valgrind %s, sancov %s" % (v, s))
PY
echo "valgrind: ok"
