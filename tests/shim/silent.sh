# The three silent failures of issue 14, each now a clear line, nothing
# mis-tagged and the program's output unchanged (fault capture, quick):
#   sh silent.sh SHIM WORKDIR CASE PROGRAM [ARGS...]
# CASE inlined:  site=load_mesh on a build where load_mesh is inlined into
#                main: the rule says it matched nothing and names the sites
#                seen, and nothing is simulated (the report says so, and why).
# CASE stride:   a 48-byte stride for 40-byte records selects the triangle
#                block as vertices: refused in one line (rule, block, why),
#                and in the report, which has nothing simulated.
# CASE realloc:  a loader that grows its arrays with realloc: the window
#                does not close at the first realloc, the vertices counted
#                are the program's (not the capacity), a decision is made.
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
CASE=$1; shift
EMM_CAPTURE=fault EMM_REPORT="$WORK/report.json"
export EMM_CAPTURE EMM_REPORT
SMOOTH_TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
# report EXPR: a value of the JSON report (r), by Python's own parser.
report() { python3 -c "import json; r = json.load(open('$EMM_REPORT')); print($1)"; }
case $CASE in
inlined)
  EMM_TAG=$SMOOTH_TAG; export EMM_TAG
  run_both inlined "$@"
  expect_err inlined '^emm: EMM_TAG rule 1 \(vertices:site=load_mesh,stride=12,xyz=0:f32\) matched no allocation; sites seen, closest first: '
  expect_err inlined 'a function the compiler inlined is no frame of the stack'
  expect_err inlined 'no vertex array was tagged'
  [ "$(report "r['coverage']['simulated'], r['results']")" = "nothing []" ] ||
    fail "inlined: the report does not say nothing was simulated"
  report "r['coverage']['reason']" | grep -q 'no vertex array was tagged' || fail "inlined: the report's reason"
  grep '^emm: EMM_TAG rule 1' "$WORK/inlined.shim.err"
  ;;
stride)
  EMM_TAG='vertices:site=load_records,stride=48,xyz=0:f64'; export EMM_TAG
  run_both stride "$@"
  expect_err stride '^emm: .*EMM_TAG rule 1 \(vertices:site=load_records,stride=48,xyz=0:f64\): the block at 0x[0-9a-f]+ \(7500 records of 48 bytes\) is refused: vertex 0 has x = .*, not a coordinate'
  [ "$(grep -c 'refused' "$WORK/stride.shim.err")" -eq 1 ] || fail "stride: not one line"
  [ "$(report "r['coverage']['simulated'], r['results']")" = "nothing []" ] ||
    fail "stride: the report does not say nothing was simulated"
  report "r['coverage']['reason']" | grep -q 'is refused: vertex 0 has x = ' || fail "stride: the report's reason"
  grep 'refused' "$WORK/stride.shim.err"
  ;;
realloc)
  EMM_TAG=$SMOOTH_TAG; export EMM_TAG
  run_both realloc "$@"
  expect_err realloc '^emm: answer: '
  nv=$(sed -n 's/^vertices \([0-9]*\) .*/\1/p' "$WORK/realloc.native.out")
  set -- $(report "r['mesh']['vertices'], r['window']['element_accesses'], r['coverage']['loader_writes']")
  vr=$1 w=$2 lw=$3
  [ "$vr" = "$nv" ] || fail "realloc: the report counts $vr vertices, the program $nv"
  [ "$w" -ge 256 ] || fail "realloc: the window profiled $w element accesses"
  [ "$lw" -gt 0 ] || fail "realloc: no loader writes counted"
  grep -q 'closes early' "$WORK/realloc.shim.err" && fail "realloc: the window closed early"
  echo "realloc: $nv vertices, window $w element accesses, loader $lw writes"
  ;;
*) fail "unknown case $CASE" ;;
esac
echo "silent $CASE: ok"
