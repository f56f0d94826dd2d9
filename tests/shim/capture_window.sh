# The window's decision, whatever the capture (docs/profile.md "The
# window"): examples/smooth.c on a 100,000-face mesh, its plain build under
# --capture valgrind (whose batches are large: the window fills tens of
# thousands of records before the batch ends) and, when clang is there,
# its sancov build under --capture sancov, tagged by rules. The decision
# sees the window up to the read that filled it, so both runs predict what
# `emm profile` predicts on the trace the valgrind run wrote: the same
# strategy, from the same nearest sample. (The batch's further records
# once joined the decision's sweeps: the valgrind run predicted another
# strategy than the other two.)
#   sh capture_window.sh SHIM WORKDIR EMM SANCOV_BUILD|- PROGRAM
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY EMM_CAPTURE EMM_MACHINE EMM_TABLE # the session's own decision
EMM=$1 SANCOV=$2 PROG=$3
TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
MESH=$WORK/mesh.obj
"$EMM" mesh gen --faces 100000 --seed 5 -o "$MESH" > /dev/null || fail "emm mesh gen"
env -u LD_PRELOAD "$PROG" "$MESH" 1 > "$WORK/native.out" || fail "smooth natively"

# run NAME CAPTURE PROGRAM [emm run options...]: the decision alone matters
# here, so no contest, phases or baselines.
run() {
  name=$1 capture=$2 prog=$3; shift 3
  "$EMM" run --capture "$capture" --tag "$TAG" --finalists 0 --no-phases --compare none \
    --report "$WORK/$name.json" "$@" -- "$prog" "$MESH" 1 > "$WORK/$name.out" 2> "$WORK/$name.err" ||
    { cat "$WORK/$name.err" >&2; fail "$name: emm run failed"; }
  cmp -s "$WORK/native.out" "$WORK/$name.out" || fail "$name: stdout differs from the native run's"
}
run valgrind valgrind "$PROG" --trace "$WORK/valgrind.emmt"
"$EMM" profile "$WORK/valgrind.emmt" --finalists 0 --json "$WORK/profile.json" > "$WORK/profile.out" ||
  fail "emm profile of the valgrind run's trace"
names="valgrind profile"
if [ "$SANCOV" != - ]; then
  run sancov sancov "$SANCOV"
  names="$names sancov"
else
  echo "no sancov build (no clang): the valgrind run against its trace only"
fi
python3 - "$WORK" $names <<'PY' || exit 1
import json, os, sys
d = sys.argv[1]
got = {}
for n in sys.argv[2:]:
    x = json.load(open(os.path.join(d, n + '.json')))
    if n == 'profile':
        got[n] = (x['predicted'], x['nearest'])
    else:
        got[n] = (x['decision']['predicted'], x['decision']['nearest'])
    print('%-8s predicted %s (nearest %s)' % ((n,) + got[n]))
bad = [n for n in got if got[n] != got['profile']]
for n in bad:
    print('FAIL: %s predicted %s (nearest %s), emm profile on the trace %s (nearest %s)'
          % ((n,) + got[n] + got['profile']), file=sys.stderr)
sys.exit(1 if bad else 0)
PY
echo "capture window: ok"
