#!/bin/sh
# A program on a half-edge mesh under emm run, against its native run
# (issue 30):
#   sh halfedge.sh MODE EMM CAPTURE RULES WANT WORK PROG ARGS...
# Both runs in WORK; stdout and the exit status must be identical.
# MODE simulated: the report has an answer (a strategy) and counts
#   accesses to each kind of connectivity in WANT (comma-separated:
#   halfedges, faces, vconn), each non-zero, in the parts of its arrays;
#   "fans" in WANT: more triangles than faces (polygons cut into fans).
# MODE refused: the mesh is refused in exactly one line of emm's that names
#   the rule (WANT: its text's start, e.g. "EMM_TAG rule 2 (halfedges:") and
#   the cycle that does not close, and the program runs on untouched.
set -u
MODE=$1 EMM=$2 CAPTURE=$3 RULES=$4 WANT=$5 WORK=$6
shift 6
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "$WORK" && mkdir -p "$WORK" || fail "cannot make $WORK"
env -u LD_PRELOAD "$@" > "$WORK/native.out" 2>&1
native_rc=$?
"$EMM" run --capture "$CAPTURE" --tag "$RULES" --report "$WORK/report.json" -- "$@" \
  > "$WORK/emm.out" 2> "$WORK/emm.err"
rc=$?
[ "$rc" = "$native_rc" ] || { cat "$WORK/emm.err" >&2; fail "exit status $rc under emm run, $native_rc natively"; }
grep -v '^emm:' "$WORK/emm.out" | cmp -s - "$WORK/native.out" ||
  { diff "$WORK/native.out" "$WORK/emm.out" >&2; fail "the output differs from the native run's"; }
if [ "$MODE" = refused ]; then
  n=$(grep -c 'the half-edge mesh is refused' "$WORK/emm.err")
  [ "$n" = 1 ] || { cat "$WORK/emm.err" >&2; fail "$n lines refuse the mesh, not 1"; }
  line=$(grep 'the half-edge mesh is refused' "$WORK/emm.err")
  case $line in
    *"$WANT"*"cycle does not close"*) ;;
    *) fail "the refusal does not name '$WANT' and the cycle: $line" ;;
  esac
  echo "refused in one line: $line"
  exit 0
fi
[ -s "$WORK/report.json" ] || { cat "$WORK/emm.err" >&2; fail "no report"; }
/usr/bin/python3 - "$WORK/report.json" "$WANT" <<'PY' || { cat "$WORK/emm.err" >&2; exit 1; }
import json, sys
r = json.load(open(sys.argv[1]))
if r['strategy'] is None:
    sys.exit("FAIL: no strategy decided")
seen = {}
for a in r['arrays']:
    for p in a.get('parts', []):
        seen[p['kind']] = seen.get(p['kind'], 0) + p['accesses']
want = sys.argv[2].split(',')
if 'fans' in want:  # polygons: more triangles than faces
    want.remove('fans')
    tris = [a for a in r['arrays'] if a['kind'] == 'triangles']
    faces = [p for a in tris for p in a.get('parts', []) if p['kind'] == 'faces']
    if not tris or not faces or tris[0]['records'] <= faces[0]['records']:
        sys.exit("FAIL: the polygons are not fans of triangles (%s)" % r['arrays'])
for kind in want:
    if seen.get(kind, 0) <= 0:
        sys.exit("FAIL: no accesses to %s counted (parts: %s)" % (kind, seen))
print("strategy %s; accesses by array: %s" % (
    r['strategy'], ', '.join('%s %d' % kv for kv in sorted(seen.items()))))
PY
grep -E '^emm: answer|^emm:   connectivity|fans of triangles' "$WORK/emm.err" | cut -c1-200
