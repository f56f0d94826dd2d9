# The decision on the example workloads (issue: region growing classified
# as region growth, long curves as curves, random access choosing the
# cache): run natively and under the shim with the shipped table on the
# default 20,000-face mesh (seed 1; the table's program samples come from
# meshes of seeds 5-7), then read the report back.
#   sh decide.sh SHIM WORKDIR PATTERN STRATEGY|- PROGRAM [ARGS...]
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
want_pattern=$1; want_strategy=$2; shift 2
unset EMM_STRATEGY EMM_TABLE
EMM_REPORT="$WORK/report.json"; export EMM_REPORT
if [ -n "${EMM_CLI:-}" ]; then EMM_TRACE="$WORK/run.emmt"; export EMM_TRACE; fi
run_both decide "$@"
[ -s "$EMM_REPORT" ] || fail "no report"
pattern=$(sed -n 's/^  "pattern": "\(.*\)",$/\1/p' "$EMM_REPORT")
strategy=$(sed -n 's/^  "strategy": "\(.*\)",$/\1/p' "$EMM_REPORT")
echo "pattern $pattern, strategy $strategy"
[ "$pattern" = "$want_pattern" ] || { cat "$WORK/decide.shim.err" >&2; fail "pattern '$pattern', not '$want_pattern'"; }
[ "$want_strategy" = - ] || [ "$strategy" = "$want_strategy" ] ||
  { cat "$WORK/decide.shim.err" >&2; fail "strategy '$strategy', not '$want_strategy'"; }
# With the whole run captured, the answer is the run's contest's: the fastest
# over the run of every candidate the report shows (the cache is a reference
# on this machine), and emm profile on the trace the run wrote says the same.
if [ -n "${EMM_CLI:-}" ]; then
  python3 - "$EMM_REPORT" <<'PY' || fail "the answer is not the fastest candidate of the report"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["decision"]["contest"], "no contest in a whole-run report"
runs = {x["strategy"]: x["cycles"]["total"] for x in r["results"] if "cycles" in x}
cands = {k: v for k, v in runs.items() if not k.startswith("cache")}
best = min(cands.values())
assert runs[r["strategy"]] == best, (r["strategy"], runs[r["strategy"]], best)
print("answer %s: %d cycles, the fewest of %d whole-run candidates; predicted %s"
      % (r["strategy"], best, len(cands), r["decision"]["predicted"]))
PY
  "$EMM_CLI" profile "$EMM_TRACE" > "$WORK/profile.out" 2>&1 || { cat "$WORK/profile.out" >&2; fail "emm profile failed"; }
  grep -q "^strategy: *$strategy\$" "$WORK/profile.out" ||
    { cat "$WORK/profile.out" >&2; fail "emm profile on the run's trace does not answer $strategy"; }
fi
echo "decide: ok"
