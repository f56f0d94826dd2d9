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
run_both decide "$@"
[ -s "$EMM_REPORT" ] || fail "no report"
pattern=$(sed -n 's/^  "pattern": "\(.*\)",$/\1/p' "$EMM_REPORT")
strategy=$(sed -n 's/^  "strategy": "\(.*\)",$/\1/p' "$EMM_REPORT")
echo "pattern $pattern, strategy $strategy"
[ "$pattern" = "$want_pattern" ] || { cat "$WORK/decide.shim.err" >&2; fail "pattern '$pattern', not '$want_pattern'"; }
[ "$want_strategy" = - ] || [ "$strategy" = "$want_strategy" ] ||
  { cat "$WORK/decide.shim.err" >&2; fail "strategy '$strategy', not '$want_strategy'"; }
echo "decide: ok"
