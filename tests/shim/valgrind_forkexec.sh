# fork + exec under the valgrind capture, whose sessions run in processes
# of their own: the exec'd child (traced by Valgrind, the shim loaded again)
# gets its own session and report; the forked child that only exits lets go
# of its copy of the parent's connection, and the parent's session goes on.
#   sh valgrind_forkexec.sh SHIM WORKDIR EMM FORKEXEC CHILD
. "$(dirname "$0")/lib.sh"
EMM=$1; shift
EMM_TAG='vertices:site=load_grid,stride=32,xyz=8:f64;triangles:site=load_grid,stride=16,vidx=4:i32'
export EMM_TAG
env -u LD_PRELOAD "$@" > "$WORK/native.out"; native_rc=$?
"$EMM" run --capture valgrind --report "$WORK/r.%p.json" -- "$@" \
  > "$WORK/vg.out" 2> "$WORK/vg.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/vg.err" >&2; fail "exit status $rc, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/vg.out" || { cat "$WORK/vg.err" >&2; fail "stdout differs"; }
grep -q 'exec child: 0' "$WORK/vg.out" || fail "the exec'd child failed"
grep -q 'fork child: 7' "$WORK/vg.out" || fail "the forked child failed"
child=$(basename "$2")
grep -Eq "^emm: $child: " "$WORK/vg.err" || { cat "$WORK/vg.err" >&2; fail "no summary from the exec'd child"; }
python3 - "$WORK" "$child" <<'PY' || { cat "$WORK/vg.err" >&2; fail "the exec'd child's report"; }
import glob, json, sys
reports = [json.load(open(p)) for p in glob.glob(sys.argv[1] + '/r.*.json')]
mine = [r for r in reports if r['program'] == sys.argv[2]]
ok = len(mine) == 1 and mine[0]['capture'] == 'valgrind' and mine[0]['coverage']['simulated'] == 'run'
print('reports:', [(r['program'], r['coverage']['simulated']) for r in reports])
sys.exit(0 if ok else 1)
PY
echo "valgrind_forkexec: ok"
