# Threads that build one mesh together under the fault capture
# (tests/shim/shared_build.c): eight threads write every page of the tagged
# arrays at once and the first to finish reads while the others still
# write. A page the loader had open could be closed twice, or protected by
# one thread while another read it to close it: a SIGSEGV inside the
# capture's handler, and the program killed (exit 139) in most runs. Ten
# runs, each with the native stdout and exit status and a report that
# simulated the mesh: its 9,216 vertices and 18,050 triangles, or up to a
# page of records fewer (a write on the arrays' last page by a thread that
# slipped through while another had it open is not seen: with threads the
# capture is approximate).
#   sh shared_build.sh SHIM WORK PROGRAM
. "$(dirname "$0")/lib.sh"
PROG=$1
TAG='vertices:site=make_mesh,stride=32,xyz=8:f64;triangles:site=make_mesh,stride=16,vidx=4:i32'
env -u LD_PRELOAD "$PROG" > "$WORK/native.out" 2>/dev/null; native_rc=$?
[ $native_rc = 0 ] || fail "the native run failed"
i=1
while [ $i -le 10 ]; do
  EMM_TAG=$TAG EMM_CAPTURE=fault EMM_REPORT="$WORK/r$i.json" LD_PRELOAD="$SHIM" "$PROG" \
    > "$WORK/r$i.out" 2> "$WORK/r$i.err"; rc=$?
  [ $rc = $native_rc ] || { cat "$WORK/r$i.err" >&2; fail "run $i: exit status $rc"; }
  cmp -s "$WORK/native.out" "$WORK/r$i.out" || fail "run $i: stdout differs"
  python3 - "$WORK/r$i.json" <<'PY' || { cat "$WORK/r$i.err" >&2; fail "run $i: not the mesh"; }
import json, sys
r = json.load(open(sys.argv[1]))
m = r["mesh"]
assert 9216 - 128 <= m["vertices"] <= 9216 and 18050 - 256 <= m["triangles"] <= 18050, m
assert r.get("strategy") and r.get("accesses", 0) > 0, "nothing simulated"
PY
  i=$((i + 1))
done
echo "shared_build: ok (10 runs)"
