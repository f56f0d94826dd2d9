# emm run --list-sites on a program nobody tagged (examples/smooth.c), then
# the rules it suggests, used as they are:
#   sh list_sites.sh SHIM WORKDIR EMM PROGRAM MESH
# The listing names the sites of the vertex and triangle arrays with their
# stacks and a rule each; the program's output is unchanged; the suggested
# rules tag the arrays and the run is decided.
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
EMM=$1; shift
list_sites "$EMM" "$@"
grep -q 'candidate array sites (blocks of 65,536 bytes or more' "$WORK/list.err" || fail "no listing"
grep -q '^emm:      stack: .* < main' "$WORK/list.err" || fail "no stack down to main"
vrule=$(sed -n 's/^emm:      rule: \(vertices:site=[^,]*,stride=12,xyz=0:f32\)$/\1/p' "$WORK/list.err" | head -1)
trule=$(sed -n 's/^emm:      rule: \(triangles:site=[^,]*,stride=12,vidx=0:u32\)$/\1/p' "$WORK/list.err" | head -1)
[ -n "$vrule" ] || fail "no vertices rule with 3 x f32 in 12 bytes suggested"
[ -n "$trule" ] || fail "no triangles rule with 3 x u32 in 12 bytes suggested"
grep -q 'no simulation\|answer' "$WORK/list.err" && fail "--list-sites simulated something"
run_suggested "$EMM" "$vrule;$trule" "$@"
echo "suggested: $vrule;$trule"
echo "list_sites: ok"
