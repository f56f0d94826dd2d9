# An untouched program (no emm_tag_* calls) gets both arrays tagged by
# EMM_TAG rules that select them by the allocating function's name.
. "$(dirname "$0")/lib.sh"
EMM_TAG='vertices:site=load_grid,stride=32,xyz=8:f64;triangles:site=load_grid,stride=16,vidx=4:i32'
EMM_LOG=2; export EMM_TAG EMM_LOG
run_both untagged "$@"
expect_err untagged 'tagged vertices at 0x[0-9a-f]+: 4096 records of 32 bytes \(EMM_TAG rule\)'
expect_err untagged 'tagged triangles at 0x[0-9a-f]+: 7938 records of 16 bytes \(EMM_TAG rule\)'
expect_err untagged 'accesses simulated'
# Not selected by a rule whose site is on no stack.
EMM_TAG='vertices:site=no_such_function,stride=32,xyz=8:f64'
run_both nosite "$@"
grep -q 'tagged vertices' "$WORK/nosite.shim.err" && fail "a rule with an absent site tagged an array"
echo "rule_site: ok"
