# emm run --list-sites on a program that keeps its vertices as a structure
# of arrays (examples/smooth_soa.c: x, y and z in three blocks), then the
# rules it suggests, used as they are:
#   sh list_sites_soa.sh SHIM WORKDIR EMM PROGRAM MESH.off
# The listing reads the x and y blocks as one f32 coordinate per entry and
# names their axes in the order the program allocated them (z, all zero on
# a planar mesh, reads as nothing: it is optional); the suggested axis and
# triangle rules tag the mesh and the run is decided.
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
EMM=$1; shift
list_sites "$EMM" "$@"
grep -q 'records: one f32 coordinate per 4 bytes (a structure of arrays' "$WORK/list.err" ||
  fail "no block read as one coordinate per entry"
xrule=$(sed -n 's/^emm:      rule: \(vertices:site=[^,]*,x=0:f32\)$/\1/p' "$WORK/list.err")
yrule=$(sed -n 's/^emm:      rule: \(vertices:site=[^,]*,y=0:f32\)$/\1/p' "$WORK/list.err")
trule=$(sed -n 's/^emm:      rule: \(triangles:site=[^,]*,stride=12,vidx=0:u32\)$/\1/p' "$WORK/list.err" | head -1)
[ "$(echo "$xrule" | grep -c .)" = 1 ] || fail "not one x rule suggested: '$xrule'"
[ "$(echo "$yrule" | grep -c .)" = 1 ] || fail "not one y rule suggested: '$yrule'"
[ -n "$trule" ] || fail "no triangles rule suggested"
run_suggested "$EMM" "$xrule;$yrule;$trule" "$@"
grep -q 'the vertices are 2 blocks (x, y[;)]' "$WORK/tagged.err" ||
  { cat "$WORK/tagged.err" >&2; fail "the suggested rules did not tag the x and y blocks as one mesh"; }
echo "suggested: $xrule;$yrule;$trule"
echo "list_sites_soa: ok"
