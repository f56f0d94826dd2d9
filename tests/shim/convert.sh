# A converter (examples/convert_once.c: load OFF into realloc-grown arrays,
# read the mesh once to write STL or OFF, exit) under EMM_TAG rules, no
# --profile: its window is its reads, it gets an answer, and its output is
# byte-identical to the native run's.
#   sh convert.sh SHIM WORKDIR EMM VG CAPTURE CASE CONVERT_ONCE MESH
# CAPTURE: valgrind (emm run --capture valgrind; skipped without emm's
# Valgrind tool, VG=0) or fault (LD_PRELOAD). CASE:
#   stl          face by face, each face's vertices: a full window
#   sweep        OFF out: vertices then faces in index order, every read a
#                leading sweep: the sweep is profiled as the traversal
#   faces_first  the faces' array filled before the vertices' exists: both
#                arrays simulated
#   late         the triangles tagged after the decision: the summary and
#                the report name them, with their record count
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
EMM=$1 VG=$2 CAPTURE=$3 CASE=$4 PROG=$5 MESH=$6
unset EMM_STRATEGY EMM_TAG EMM_REPORT EMM_CAPTURE EMM_PROFILE
PY=/usr/bin/python3
[ -x $PY ] || PY=python3
if [ "$CAPTURE" = valgrind ] && [ "$VG" != 1 ]; then
  echo "skipped: emm was built without its Valgrind tool"; exit 77
fi
site=load_faces opts= out=out.stl
case $CASE in
  stl) ;;
  sweep) out=out.off ;;
  faces_first) opts=--faces-first ;;
  late) opts=--late site=late_faces ;;
  *) fail "unknown case $CASE" ;;
esac
RULES="vertices:site=load_vertices,stride=12,xyz=0:f32;triangles:site=$site,stride=12,vidx=0:u32"
R=$WORK/r.json
mkdir -p "$WORK/native" || fail "cannot make $WORK/native"
( cd "$WORK/native" && env -u LD_PRELOAD "$PROG" $opts "$MESH" $out > ../native.out 2> ../native.err ) ||
  fail "the native run failed: $(cat "$WORK/native.err")"
if [ "$CAPTURE" = valgrind ]; then
  ( cd "$WORK" && "$EMM" run --capture valgrind --tag "$RULES" --report "$R" -- \
      "$PROG" $opts "$MESH" $out > shim.out 2> shim.err ) || { cat "$WORK/shim.err" >&2; fail "emm run failed"; }
else
  ( cd "$WORK" && EMM_CAPTURE=fault EMM_TAG="$RULES" EMM_REPORT="$R" LD_PRELOAD="$SHIM" \
      "$PROG" $opts "$MESH" $out > shim.out 2> shim.err ) || { cat "$WORK/shim.err" >&2; fail "the run under the shim failed"; }
fi
cmp -s "$WORK/native.out" "$WORK/shim.out" || fail "stdout differs under $CAPTURE capture"
cmp -s "$WORK/native/$out" "$WORK/$out" || fail "$out differs from the native run's"
err=$WORK/shim.err
grep -q '^emm: answer: ' "$err" || { cat "$err" >&2; fail "no answer"; }
grep -q '0 element reads profiled' "$err" && ! grep -q '0 element reads profiled:' "$err" &&
  { cat "$err" >&2; fail "'0 element reads profiled' without its reason"; }
# The report: a window of reads, the arrays simulated with their counts.
$PY - "$R" "$CASE" "$MESH" "$CAPTURE" <<'PY' || { cat "$err" >&2; fail "report: see above"; }
import json, sys
r = json.load(open(sys.argv[1]))
case, capture = sys.argv[2], sys.argv[4]
nv = nf = None
with open(sys.argv[3]) as f:
    assert f.readline().startswith('OFF')
    nv, nf = map(int, f.readline().split()[:2])
w = r['window']
arrays = {a['kind']: a['records'] for a in r['arrays']}
def need(cond, what):
    if not cond:
        print('FAIL:', what, '| window', w, '| arrays', r['arrays'], '| late', r['late_arrays'])
        sys.exit(1)
need(r['strategy'], 'no strategy')
need(w['reads'] > 0 and w['element_accesses'] > 0, 'no element read profiled')
need(w['writes'] <= w['reads'], 'the window is mostly writes')
need(r['coverage']['loader_writes'] > 0, 'no loader writes counted')
if case == 'late':
    need(arrays == {'vertices': nv}, 'the simulated arrays are not the vertices alone')
    need(w['waited'] > 0, 'the window did not wait for the triangle array')
    need([(a['kind'], a['records']) for a in r['late_arrays']] == [('triangles', nf)],
         'the late triangle array is not reported')
    need('late_faces' in r['late_arrays'][0]['origin'], 'the late array has no origin')
    need(r['missing_kinds'] == ['triangles'], 'the triangles are not said missing')
else:
    need(arrays == {'vertices': nv, 'triangles': nf}, 'the simulated arrays are not the mesh')
    need(r['late_arrays'] == [] and r['missing_kinds'] == [], 'late or missing arrays reported')
if case == 'sweep':
    need(w['sweep_profiled'] and w['leading_sweep'] == nv + nf and
         w['element_accesses'] == nv + nf, 'the sweep was not profiled as the traversal')
    need(not w['complete'], 'a window that never began is complete')
elif case != 'late':
    # A mesh larger than the local store: under a whole-run capture the
    # window reads on, up to half its length again, until its records fill
    # the store (the fault capture, which stops at the decision, does not).
    need(w['complete'] and w['ended_by'] == 'full' and
         w['element_accesses'] == w['size'] + w['read_on'] and
         (w['read_on'] == 0 if capture == 'fault' else
          w['store_filled'] or 2 * w['read_on'] == w['size']),
         'the window did not fill with reads')
print('window: %d element reads (%s), %d reads, %d writes; arrays %s; %s' %
      (w['element_accesses'], w['ended_by'], w['reads'], w['writes'], arrays, r['strategy']))
PY
case $CASE in
  sweep) grep -Eq '^emm:   every one of the [0-9,]+ element reads seen was a leading index-order sweep .*the sweep is the traversal, and it was profiled' "$err" ||
           { cat "$err" >&2; fail "the summary does not say the sweep was profiled"; } ;;
  late) grep -Eq '^emm:   EMM_TAG rule 2 \(triangles:site=late_faces[^)]*\) tagged [0-9,]+ triangles \(12-byte records\) after the decision: its accesses are not simulated' "$err" ||
          { cat "$err" >&2; fail "the summary does not name the late triangle array"; }
        grep -q '^emm:   no triangle array was tagged by the decision although a tag rule names one' "$err" ||
          { cat "$err" >&2; fail "the summary does not say the triangles were missing"; } ;;
  *) grep -Eq '^emm:   simulated arrays: [0-9,]+ (vertices|triangles) \(12-byte records\) and [0-9,]+ (vertices|triangles) \(12-byte records\)$' "$err" ||
       { cat "$err" >&2; fail "the summary does not list both arrays"; }
     # The mesh's 361 KB outgrow the local store: the window read on
     # (not under the fault capture, which stops at the decision).
     if [ "$CAPTURE" = fault ]; then
       ! grep -q 'the window read on' "$err" || { cat "$err" >&2; fail "the fault capture's window read on"; }
     else
       grep -Eq '^emm:   the window read on past its 16,384 element reads to [0-9,]+ .*local store \(262,144 bytes\)' "$err" ||
         { cat "$err" >&2; fail "the summary does not say the window read on"; }
     fi ;;
esac
grep '^emm: answer: ' "$err"
echo "convert $CAPTURE $CASE: ok"
