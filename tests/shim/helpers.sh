# The session's helper threads allocate blocks that match a tag rule (a
# layout of this mesh mallocs a whole number of triangle records) while the
# main thread holds the shim's lock for the decision: they must be the
# shim's own, or the program hangs. The decision is a real one (no fixed
# strategy), so its sweep runs on the helpers. Run under `timeout`: a hang
# is a failure, not a stuck suite.
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM_TAG='triangles:min=4K,stride=28,vidx=4:i32;vertices:min=4K,stride=80,xyz=8:f64'
EMM_PROFILE=4000 EMM_LOG=2 EMM_REPORT="$WORK/report.json"
export EMM_TAG EMM_PROFILE EMM_LOG EMM_REPORT
run_both helpers timeout 120 "$@"
expect_err helpers 'tagged triangles at 0x[0-9a-f]+: 19602 records of 28 bytes \(EMM_TAG rule\)'
expect_err helpers 'tagged vertices at 0x[0-9a-f]+: 10000 records of 80 bytes \(EMM_TAG rule\)'
expect_err helpers '[0-9] cycles'
# Only the program's two arrays were tagged: nothing a helper allocated.
n=$(grep -c '^emm: tagged ' "$WORK/helpers.shim.err")
[ "$n" = 2 ] || { cat "$WORK/helpers.shim.err" >&2; fail "$n arrays tagged, expected the program's 2"; }
grep -q '"source": "\(checked\|simulated\)"' "$EMM_REPORT" ||
  { cat "$EMM_REPORT" >&2; fail "the decision did not simulate (no sweep on the helpers)"; }
echo "helpers: ok"
