# Real shapes of mesh data (issue 14 item 5), as a user runs them: a program
# that keeps its mesh column-major (examples/smooth_columns.c, libigl's V and
# F), as a structure of arrays (examples/smooth_soa.c: x, y, z in three
# blocks) or as a triangle soup (examples/stl_normals.c, binary STL facets),
# run natively and under `emm run --capture CAPTURE` with an EMM_TAG rule:
#   sh shapes.sh SHIM WORKDIR EMM CASE CAPTURE PROGRAM MESH.off
# CASE columns:  order=columns rules for V (f64) and F (i32)
# CASE soa:      x=, y=, z= rules for the three f32 blocks, records for F (u32)
# CASE soup:     soup:stride=50,corners=12:f32 on the mesh written as binary STL
# CASE wrong-n:  a column-major rule whose n= is not the block's: one line
#                names the rule and the block that does not fit, nothing is
#                tagged as vertices, nothing is simulated (the report says
#                so, and why)
# CASE soa-main: the soa rules with site=main, where the loader (inlined)
#                also has the C library allocate its FILE's 4 KiB buffer, a
#                whole number of 4-byte entries: no rule selects a block the
#                C library allocates for itself (under fault capture the
#                program's own reads into it failed with EFAULT)
# CASE soa-missing-y: the y rule selects no block (min=1G): one line names
#                the x block's rule and says no y block was tagged, nothing
#                is simulated (the report says so, and why)
# stdout and exit status as in the native run; the report has a pattern and
# a decision, and counts the vertices and triangles the program loaded; the
# geometry in the run's trace is the mesh file's, exactly (columns read
# column by column; a soup's corners, merged by position).
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM=$1 CASE=$2 CAPTURE=$3 PROG=$4 MESH=$5
# The window closes in the first pass, before the program moves a vertex:
# the geometry read at the decision is the file's.
EMM_PROFILE=2000; export EMM_PROFILE
COLUMNS='vertices:site=load_mesh,order=columns,xyz=0:f64;triangles:site=load_mesh,order=columns,vidx=0:i32'
SOA='vertices:site=mesh_alloc,x=0:f32;vertices:site=mesh_alloc,y=0:f32;vertices:site=mesh_alloc,z=0:f32;triangles:site=mesh_alloc,stride=12,vidx=0:u32'
case $CASE in
columns) TAG=$COLUMNS INPUT=$MESH ;;
soa)     TAG=$SOA INPUT=$MESH ;;
soa-main) TAG=$(echo "$SOA" | sed 's/site=mesh_alloc/site=main/g') INPUT=$MESH CASE=soa ;;
soa-missing-y) TAG=$(echo "$SOA" | sed 's/site=mesh_alloc,y=/site=mesh_alloc,min=1G,y=/') INPUT=$MESH ;;
wrong-n) TAG='vertices:site=load_mesh,order=columns,n=999,xyz=0:f64;triangles:site=load_mesh,order=columns,vidx=0:i32'
         INPUT=$MESH ;;
soup)    TAG='soup:site=load_stl,stride=50,corners=12:f32' INPUT=$WORK/mesh.stl
         # The OFF mesh as binary STL: an 80-byte header, a u32 count, then
         # 50-byte facets (normal, three corners, attribute).
         python3 - "$MESH" "$INPUT" <<'PY' || fail "cannot write the STL file"
import struct, sys
tok = open(sys.argv[1]).read().split()
nv, nf, p = int(tok[1]), int(tok[2]), 4
V = [tuple(float(t) for t in tok[p + 3 * i:p + 3 * i + 3]) for i in range(nv)]
p += 3 * nv
with open(sys.argv[2], 'wb') as out:
    out.write(b'emm tests/shim/shapes.sh'.ljust(80, b' ') + struct.pack('<I', nf))
    for _ in range(nf):
        k, a, b, c = (int(t) for t in tok[p:p + 4])
        assert k == 3
        p += 4
        out.write(struct.pack('<3f', 0, 0, 0) +
                  b''.join(struct.pack('<3f', *V[j]) for j in (a, b, c)) + b'\0\0')
PY
         ;;
*) fail "unknown case $CASE" ;;
esac
REPORT=$WORK/report.json TRACE=$WORK/run.emmt
env -u LD_PRELOAD "$PROG" "$INPUT" > "$WORK/native.out" 2> "$WORK/native.err"; native_rc=$?
[ $native_rc = 0 ] || { cat "$WORK/native.err" >&2; fail "the native run failed"; }
"$EMM" run --capture "$CAPTURE" --tag "$TAG" --report "$REPORT" --trace "$TRACE" \
  -- "$PROG" "$INPUT" > "$WORK/emm.out" 2> "$WORK/emm.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/emm.err" >&2; fail "exit status $rc under emm run, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/emm.out" || {
  diff "$WORK/native.out" "$WORK/emm.out" >&2; cat "$WORK/emm.err" >&2; fail "stdout differs under emm run"; }
cat "$WORK/emm.err"
# Fault capture simulates the window only: nothing is said of the run.
if [ "$CAPTURE" = fault ] && grep -q 'over the run' "$WORK/emm.err"; then
  fail "the summary speaks of the run, but only the window was simulated"
fi

# nothing REGEX: the report says nothing was simulated, for a reason
# matching REGEX.
nothing() {
  python3 - "$REPORT" "$1" <<'PY' || fail "the report does not say nothing was simulated, and why"
import json, re, sys
r = json.load(open(sys.argv[1]))
assert r["coverage"]["simulated"] == "nothing" and r["results"] == [], r["coverage"]
assert re.search(sys.argv[2], r["coverage"]["reason"]), r["coverage"]["reason"]
PY
}
if [ "$CASE" = wrong-n ]; then
  line='^emm: EMM_TAG rule 1 \(vertices:site=load_mesh,order=columns,n=999,stride=8,xyz=0:f64\) matched no allocation; sites seen, closest first: load_mesh \([0-9]+ blocks?, up to [0-9]+ bytes, not 3 columns of n=999 entries of 8 bytes \(23976 bytes\)\)'
  grep -Eq "$line" "$WORK/emm.err" || fail "no line says rule 1's n= does not fit the block"
  [ "$(grep -c 'EMM_TAG rule 1' "$WORK/emm.err")" -eq 1 ] || fail "not one line for rule 1"
  grep -q 'no vertex array was tagged' "$WORK/emm.err" || fail "a vertex array was tagged"
  nothing 'no vertex array was tagged'
  echo "shapes $CASE $CAPTURE: ok"
  exit 0
fi
if [ "$CASE" = soa-missing-y ]; then
  # The block the line names is the x or the z block, whichever the
  # session read most (under fault capture the loader's writes are seen a
  # page at a time).
  line='^emm: smooth_soa: no simulation: EMM_TAG rule (1 \(vertices:site=mesh_alloc,stride=4,x=0:f32\) tagged the x|3 \(vertices:site=mesh_alloc,stride=4,z=0:f32\) tagged the z) block at 0x[0-9a-f]+, [0-9,]+ entries, but no y block was tagged: the vertices need their x and y'
  grep -Eq "$line" "$WORK/emm.err" || fail "no line says the y block is missing"
  [ "$(grep -c 'no y block' "$WORK/emm.err")" -eq 1 ] || fail "not one line for the missing y"
  grep -q 'EMM_TAG rule 2 (vertices:site=mesh_alloc,min=1073741824,stride=4,y=0:f32) matched no allocation' \
    "$WORK/emm.err" || fail "no line says rule 2 matched nothing"
  nothing 'but no y block was tagged'
  echo "shapes $CASE $CAPTURE: ok"
  exit 0
fi

grep -q '^emm: answer: ' "$WORK/emm.err" || fail "no answer"
python3 - "$REPORT" "$TRACE" "$WORK/native.out" "$CASE" "$MESH" "$INPUT" <<'PY' || fail "the report or the geometry is wrong"
import json, struct, sys
report, trace, out, case, mesh, inp = sys.argv[1:]
r = json.load(open(report))
assert r["pattern"], "no pattern"
assert r["strategy"] and r["decision"]["source"], "no decision"
words = open(out).read().split()
said = dict(zip(words[::2], words[1::2]))
nv = int(said["vertices"])
nt = int(said["facets"] if case == "soup" else said["triangles"])
m = r["mesh"]
assert (m["vertices"], m["triangles"]) == (nv, nt), \
    "the report counts %d vertices and %d triangles, the program %d and %d" % (
        m["vertices"], m["triangles"], nv, nt)
# The trace's geometry (docs/trace-format.md): after the 72-byte header and
# the array table, nv x 3 f64, then nt x 3 i32.
b = open(trace, "rb").read()
narrays, gnv, gnt = struct.unpack_from("<I", b, 16)[0], *struct.unpack_from("<QQ", b, 48)
at = 72 + 24 * narrays + 8
xyz = struct.unpack_from("<%dd" % (3 * gnv), b, at)
tri = struct.unpack_from("<%di" % (3 * gnt), b, at + 24 * gnv)
assert (gnv, gnt) == (nv, nt), (gnv, gnt)
if case in ("columns", "soa"):
    tok = open(mesh).read().split()
    V = [float(t) for t in tok[4:4 + 3 * nv]]
    if case == "soa":  # read as f32 by the program
        V = [struct.unpack("<f", struct.pack("<f", x))[0] for x in V]
        assert "3 blocks (x, y, z) of %s f32 each (EMM_TAG rules 1, 2, 3)" % format(nv, ",") \
            in m["note"], m["note"]
    F = [int(t) for i in range(nt) for t in tok[4 + 3 * nv + 4 * i + 1:4 + 3 * nv + 4 * i + 4]]
    assert list(xyz) == V, "the vertices emm read are not the file's"
    assert list(tri) == F, "the triangles emm read are not the file's"
else:
    s = open(inp, "rb").read()
    for t in range(nt):
        for k in range(3):
            want = struct.unpack_from("<3f", s, 84 + 50 * t + 12 + 12 * k)
            got = xyz[3 * tri[3 * t + k]:3 * tri[3 * t + k] + 3]
            assert tuple(got) == tuple(x + 0.0 for x in want), (t, k, got, want)
print("report: pattern %s, strategy %s, %d vertices, %d triangles; geometry as loaded"
      % (r["pattern"], r["strategy"], nv, nt))
PY
echo "shapes $CASE $CAPTURE: ok"
