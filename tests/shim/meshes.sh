# Several meshes, one per thread (tests/shim/meshes.c): under plain
# LD_PRELOAD and emm run with the fault and valgrind captures, stdout and
# exit status as natively, and a report that simulates one complete mesh:
# its vertex and triangle counts are those of one thread's grid (side n:
# n^2 vertices, 2 (n-1)^2 triangles), never one thread's triangles with
# another's vertices.
#   sh meshes.sh SHIM WORK EMM VALGRIND(0|1) PROGRAM
. "$(dirname "$0")/lib.sh"
EMM=$1 VG=$2 PROG=$3
unset EMM_STRATEGY
TAG='vertices:site=load_grid,stride=32,xyz=8:f64;triangles:site=load_grid,stride=16,vidx=4:i32'
env -u LD_PRELOAD "$PROG" > "$WORK/native.out" 2>/dev/null; native_rc=$?
[ $native_rc = 0 ] || fail "the native run failed"

# one_mesh NAME: NAME's report simulated one thread's whole grid.
one_mesh() {
  [ -s "$WORK/$1.json" ] || { cat "$WORK/$1.err" >&2; fail "$1: no report"; }
  python3 - "$WORK/$1.json" "$1" <<'PY' || { cat "$WORK/$1.err" >&2; fail "$1: not one complete mesh"; }
import json, sys
r = json.load(open(sys.argv[1]))
m = r["mesh"]
grids = [(n * n, 2 * (n - 1) ** 2) for n in (24, 32, 40, 48)]
assert (m["vertices"], m["triangles"]) in grids, "%s: %d vertices, %d triangles: no thread's grid" % (sys.argv[2], m["vertices"], m["triangles"])
assert r.get("strategy") and r.get("accesses", 0) > 0, "%s: nothing simulated" % sys.argv[2]
PY
}

EMM_TAG=$TAG EMM_CAPTURE=fault EMM_REPORT="$WORK/preload.json" LD_PRELOAD="$SHIM" "$PROG" > "$WORK/preload.out" 2> "$WORK/preload.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/preload.err" >&2; fail "LD_PRELOAD: exit status $rc"; }
cmp -s "$WORK/native.out" "$WORK/preload.out" || fail "LD_PRELOAD: stdout differs"
one_mesh preload

captures=fault
[ "$VG" = 1 ] && captures="fault valgrind"
for capture in $captures; do
  "$EMM" run --capture "$capture" --tag "$TAG" --report "$WORK/$capture.json" -- "$PROG" \
    > "$WORK/$capture.out" 2> "$WORK/$capture.err"; rc=$?
  [ $rc = $native_rc ] || { cat "$WORK/$capture.err" >&2; fail "$capture: exit status $rc"; }
  cmp -s "$WORK/native.out" "$WORK/$capture.out" || fail "$capture: stdout differs"
  one_mesh "$capture"
done
grep -h 'several meshes' "$WORK"/*.err | head -1
echo "meshes: ok ($captures, LD_PRELOAD)"
