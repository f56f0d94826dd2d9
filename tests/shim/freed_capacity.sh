# Arrays grown with realloc (capacity past the records in use) and freed
# before the decision: a window longer than the run decides at exit, from
# the copies kept when the program freed its arrays. Both arrays are the
# mesh's there, the vertices too (the vertex array, left at its capacity,
# was more records than the mesh's vertices and fell out of the trace:
# only the triangles' index reads were simulated).
#   sh freed_capacity.sh SHIM WORKDIR EMM SMOOTH_SANCOV MESH.obj
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM=$1 PROG=$2 MESH=$3
TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
REPORT=$WORK/report.json
env -u LD_PRELOAD "$PROG" "$MESH" 1 > "$WORK/native.out" || fail "the native run failed"
"$EMM" run --capture sancov --profile 100M --tag "$TAG" --report "$REPORT" -- "$PROG" "$MESH" 1 \
  > "$WORK/emm.out" 2> "$WORK/emm.err" || { cat "$WORK/emm.err" >&2; fail "emm run failed"; }
cmp -s "$WORK/native.out" "$WORK/emm.out" || fail "stdout differs under emm run"
cat "$WORK/emm.err"
python3 - "$REPORT" <<'PY' || fail "the report does not simulate the vertices"
import json, sys
r = json.load(open(sys.argv[1]))
nt, acc = r["mesh"]["triangles"], r["coverage"]["accesses"]
# One pass reads each triangle's 3 indices and its corners' 3 coordinates:
# more than 3 accesses a triangle unless the vertices were left out.
assert r["coverage"]["geometry_read"] == "decision", r["coverage"]
assert acc > 6 * nt, f"{acc} accesses for {nt} triangles: the vertices' reads are missing"
PY
echo "freed_capacity: ok"
