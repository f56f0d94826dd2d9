# The geometry is not a mesh when the window closes (tests/shim/deferred.c:
# 1-based indices, renumbered later): the decision waits for the program's
# end, reads the arrays as they were freed, and the summary and report say
# so; the program's stdout and exit status are its own.
#   sh deferred.sh SHIM WORKDIR PROGRAM             (preloaded: EMM_CAPTURE says how)
#   sh deferred.sh SHIM WORKDIR EMM PROGRAM         (emm run --capture valgrind)
. "$(dirname "$0")/lib.sh"
EMM_TAG='vertices:site=load_grid,stride=24,xyz=0:f64;triangles:site=load_grid,stride=12,vidx=0:i32'
EMM_PROFILE=4096 EMM_REPORT="$WORK/r.json"
export EMM_TAG EMM_PROFILE EMM_REPORT
if [ $# = 2 ]; then
  EMM=$1; shift
  "$@" > "$WORK/deferred.native.out"; native_rc=$?
  "$EMM" run --capture valgrind -- "$@" > "$WORK/deferred.shim.out" 2> "$WORK/deferred.shim.err"; rc=$?
  [ $rc = $native_rc ] || { cat "$WORK/deferred.shim.err" >&2; fail "exit status $rc, $native_rc natively"; }
  cmp -s "$WORK/deferred.native.out" "$WORK/deferred.shim.out" || fail "stdout differs"
else
  run_both deferred "$@"
fi
expect_err deferred 'simulated: the profiling window only, .*when it closed the arrays held no mesh yet \(.*triangle [0-9]+ has vertex index 4096, outside the 4096 records.*\); read again at the program.s end they did'
python3 - "$WORK/r.json" <<'PY' || { cat "$WORK/deferred.shim.err" >&2; fail "the report"; }
import json, sys
r = json.load(open(sys.argv[1]))
c = r['coverage']
ok = c['geometry_read'] == 'end' and c['simulated'] == 'window' and r['mesh']['triangles'] == 7938 \
     and r['mesh']['vertices'] == 4096
print('coverage', c, 'mesh', r['mesh']['vertices'], r['mesh']['triangles'])
sys.exit(0 if ok else 1)
PY
echo "deferred: ok"
