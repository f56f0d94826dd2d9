# One traversal repeated: ten smoothing passes over a 40,000-face mesh, a
# loop over the triangles then one over the vertices each pass. The probes
# land on different stretches of the same two loops, and their weak matches
# scatter over the patterns (three phases were found here before the rule
# below); none of them runs code the window's phase has not run, so the
# run is one phase: probed, and the window's pattern stands, and its old
# code is profiled only now and then.
#   sh phases_periodic.sh SHIM WORKDIR PROGRAM MESH PASSES
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM_TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
EMM_REPORT="$WORK/report.json"
export EMM_TAG EMM_REPORT
run_both periodic "$@"
expect_err periodic '^emm: answer: '
grep -q '"phases_probed": true' "$EMM_REPORT" || fail "report: phases_probed is not true"
! grep -q '^emm:   phases: ' "$WORK/periodic.shim.err" || {
  cat "$WORK/periodic.shim.err" >&2; fail "the summary lists phases of a periodic run"; }
n=$(grep -c '"start":' "$EMM_REPORT")
[ "$n" = 1 ] || { cat "$EMM_REPORT" >&2; fail "report: $n phases, expected the window's only"; }
# Its probes run the window's code and move as it does: most are not profiled
# (a probe whose moves are new, or one in 16 in a row, is).
probes=$(/usr/bin/python3 -c '
import json, sys
p = json.load(open(sys.argv[1]))["probes"]
if not (p["taken"] >= 4 and 0 < p["profiled"] <= (p["taken"] + 3) // 4):
    sys.exit("report: probes %s: expected at least 4, at most one in four of them profiled" % p)
print("%d probes, %d profiled" % (p["taken"], p["profiled"]))' "$EMM_REPORT") || fail "$probes"
echo "periodic: one phase, probed ($probes)"
