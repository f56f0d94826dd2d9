# A package converter, OpenCTM's ctmconv (openctm-tools), under
# emm run --capture valgrind with rules tagging its arrays: its loader
# writes far more than the mesh's records (some 17 writes a face) before it
# reads the mesh once to write STL. The window is its reads, not its
# loader's writes: an answer, no --profile, output identical to the native
# run's. (It used to get 0 element reads and "no answer".)
#   sh ctmconv.sh SHIM WORKDIR EMM VG
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
EMM=$1 VG=$2
unset EMM_STRATEGY EMM_TAG EMM_REPORT EMM_CAPTURE EMM_PROFILE
CTM=$(command -v ctmconv) || { echo "skipped: ctmconv is not installed (openctm-tools, scripts/deps.sh)"; exit 77; }
[ "$VG" = 1 ] || { echo "skipped: emm was built without its Valgrind tool"; exit 77; }
PY=/usr/bin/python3
[ -x $PY ] || PY=python3
"$EMM" mesh gen --faces 20000 --seed 1 -o "$WORK/m.off" > /dev/null || fail "emm mesh gen failed"
mkdir -p "$WORK/native" || fail "cannot make $WORK/native"
( cd "$WORK/native" && env -u LD_PRELOAD "$CTM" ../m.off out.stl > ../native.out 2>&1 ) ||
  fail "ctmconv failed natively: $(cat "$WORK/native.out")"
# The triangles: 20,000 of 12 bytes; the vertices: 10,101 of 12 bytes, the
# first block of at least that size (nth=1: ctmconv allocates a larger one
# for its vertex grid later).
RULES='triangles:min=240000,stride=12,vidx=0:u32;vertices:min=121000,nth=1,stride=12,xyz=0:f32'
( cd "$WORK" && "$EMM" run --capture valgrind --tag "$RULES" --report r.json -- \
    "$CTM" m.off out.stl > shim.out 2> shim.err ) || { cat "$WORK/shim.err" >&2; fail "emm run failed"; }
cmp -s "$WORK/native/out.stl" "$WORK/out.stl" || fail "out.stl differs from the native run's"
grep -q '^emm: answer: ' "$WORK/shim.err" || { cat "$WORK/shim.err" >&2; fail "no answer"; }
grep -Eq '^emm:   simulated arrays: 10,101 vertices \(12-byte records\) and 20,000 triangles \(12-byte records\)$' "$WORK/shim.err" ||
  { cat "$WORK/shim.err" >&2; fail "the summary does not list the mesh's arrays"; }
$PY - "$WORK/r.json" <<'PY' || { cat "$WORK/shim.err" >&2; fail "report: see above"; }
import json, sys
r = json.load(open(sys.argv[1]))
w = r['window']
ok = (r['strategy'] and w['complete'] and w['ended_by'] == 'full' and
      w['element_accesses'] == w['size'] + w['read_on'] and w['reads'] > 0 and
      r['coverage']['loader_writes'] > 100000 and
      sorted((a['kind'], a['records']) for a in r['arrays']) ==
      [('triangles', 20000), ('vertices', 10101)])
print('window: %d element reads, %d reads, %d writes; loader writes %d; %s' %
      (w['element_accesses'], w['reads'], w['writes'], r['coverage']['loader_writes'],
       r['strategy']))
sys.exit(0 if ok else 1)
PY
grep '^emm: answer: ' "$WORK/shim.err"
echo "ctmconv: ok"
