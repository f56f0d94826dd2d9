# One run, two traversals of the same arrays: a scan line, then a region
# grown breadth-first. The session's probes after the window must find the
# second phase: the report lists two phases with different patterns and
# says whether switching strategy between them pays. With EMM_PHASES=0 in
# the environment, the run is not probed: one phase, the window's, and the
# report says it was not probed.
#   sh phases.sh SHIM WORKDIR PROGRAM MESH --phases
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM_TAG='vertices:site=read_mesh,stride=24,xyz=0:f64;triangles:site=read_mesh,stride=12,vidx=0:i32'
EMM_REPORT="$WORK/report.json"
export EMM_TAG EMM_REPORT
run_both phases "$@"
expect_err phases '^emm: answer: '
R=$EMM_REPORT
if [ "${EMM_PHASES:-1}" = 0 ]; then
  ! grep -q '^emm:   phases: ' "$WORK/phases.shim.err" || fail "EMM_PHASES=0: the summary lists phases"
  n=$(grep -c '"start":' "$R")
  [ "$n" = 1 ] || { cat "$R" >&2; fail "EMM_PHASES=0: report: $n phases, expected the window's only"; }
  grep -q '"phases_probed": false' "$R" || fail "EMM_PHASES=0: report: phases_probed is not false"
  echo "phases: not probed, one phase"
  exit 0
fi
grep -q '"phases_probed": true' "$R" || fail "report: phases_probed is not true"
expect_err phases '^emm:   phases: 2 '
expect_err phases 'switching (pays|does not pay)'
n=$(grep -c '"start":' "$R")
[ "$n" = 2 ] || { cat "$R" >&2; fail "report: $n phases, expected 2"; }
p1=$(sed -n '/"phases"/,$s/^ *"pattern": "\(.*\)",$/\1/p' "$R" | sed -n 1p)
p2=$(sed -n '/"phases"/,$s/^ *"pattern": "\(.*\)",$/\1/p' "$R" | sed -n 2p)
[ -n "$p1" ] && [ -n "$p2" ] && [ "$p1" != "$p2" ] || fail "report: phase patterns '$p1' and '$p2'"
grep -q '"pays": \(true\|false\)' "$R" || fail "report: no switch verdict"
echo "phases: $p1 then $p2"
