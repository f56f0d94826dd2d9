# A structure of arrays whose x, y and z blocks one malloc call in a loop
# allocates (tests/shim/soa_loop.c): --list-sites lists them as one site of
# three blocks and suggests one axis rule per block with nth=1 (a rule
# follows its first call path, so without nth= the x rule would take all
# three); the suggested rules, used as they are, tag one mesh of three
# blocks and the run is decided.
#   sh list_sites_loop.sh SHIM WORKDIR EMM PROGRAM 140   (a 140 x 140 grid)
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
EMM=$1; shift
list_sites "$EMM" "$@"
axes=$(sed -n 's/^emm:      rule: \(vertices:site=mesh_alloc,x=0:f32,nth=1;vertices:site=mesh_alloc,y=0:f32,nth=1;vertices:site=mesh_alloc,z=0:f32,nth=1\)$/\1/p' "$WORK/list.err")
trule=$(sed -n 's/^emm:      rule: \(triangles:site=mesh_alloc,stride=12,vidx=0:u32\)$/\1/p' "$WORK/list.err")
[ -n "$axes" ] || fail "no x, y, z rules with nth=1 suggested for the loop's three blocks"
[ -n "$trule" ] || fail "no triangles rule suggested"
run_suggested "$EMM" "$axes;$trule" "$@"
cat "$WORK/tagged.err"
grep -q 'the vertices are 3 blocks (x, y, z) of 19,600 f32 each' "$WORK/tagged.err" ||
  fail "the suggested rules did not tag the three blocks as one mesh"
echo "list_sites_loop: ok"
