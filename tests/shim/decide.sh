# The decision on the example workloads (issue: region growing classified
# as region growth, long curves as curves, random access choosing the
# cache): run natively and under the shim with the shipped table on the
# default 20,000-face mesh (seed 1; the table's program samples come from
# meshes of seeds 5-7), then read the report back.
#   sh decide.sh SHIM WORKDIR PATTERN STRATEGY|- PROGRAM [ARGS...]
# With EMM_CLI (a sancov build: the whole run and program counters), also
# the answer's timeline and stall lines; EMM_TEST_OVERRULED=1 says the
# run's contest answers other than the window's prediction here, so that
# they are shown to be the answer's, not the prediction's. Without it (a
# plain build under plain LD_PRELOAD, where auto picks the fault capture),
# the window-only answer.
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
want_pattern=$1; want_strategy=$2; shift 2
unset EMM_STRATEGY EMM_TABLE EMM_TIMELINE
EMM_REPORT="$WORK/report.json"; export EMM_REPORT
if [ -n "${EMM_CLI:-}" ]; then
  EMM_TRACE="$WORK/run.emmt" EMM_TIMELINE="$WORK/timeline.json"; export EMM_TRACE EMM_TIMELINE
fi
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
  # The timeline and the stall lines are the answer's: its strategy, its
  # cycles and DMA transfers, and its DMA stalls by line as emm annotate
  # counts them over the run's trace.
  case $strategy in
    direct|cache*) ;; # no DMA: no stall lines
    *) "$EMM_CLI" annotate "$EMM_TRACE" --strategy "$strategy" --sort dma_stall --top 5 \
         > "$WORK/annotate.out" 2>&1 || { cat "$WORK/annotate.out" >&2; fail "emm annotate failed"; } ;;
  esac
  python3 - "$EMM_REPORT" "$EMM_TIMELINE" "$WORK/annotate.out" "${EMM_TEST_OVERRULED:-0}" <<'PY' ||
import json, re, sys
r = json.load(open(sys.argv[1]))
t = json.load(open(sys.argv[2]))["otherData"]
answer, first = r["strategy"], r["results"][0]
assert first["strategy"] == answer, (first["strategy"], answer)
if sys.argv[4] == "1":
    assert r["decision"]["predicted"] != answer, \
        "the contest answers the prediction here: this run no longer shows whose lines they are"
assert t["strategy"] == answer, ("timeline", t["strategy"], "answer", answer)
assert t["cycles"] == first["cycles"]["total"], (t["cycles"], first["cycles"]["total"])
assert t["transfers"] == first.get("dma", {}).get("transfers", 0), (t["transfers"], first.get("dma"))
if not answer.startswith(("direct", "cache")):
    assert r["stall_lines_strategy"] == answer, (r["stall_lines_strategy"], answer)
    assert r["stall_lines"], "no stall lines"
    ann = {}
    for row in open(sys.argv[3]):
        m = re.match(r"\s*(\d+)\s+(\d+)\s+[\d.]+%.*\s(\S+:\d+) \(", row)
        if m:
            ann[m.group(3)] = int(m.group(2))
    for l in r["stall_lines"]:
        key = "%s:%d" % (l["file"].rsplit("/", 1)[-1], l["line"])
        assert ann.get(key) == l["dma_stall"], (key, l["dma_stall"], ann.get(key))
print("timeline and stall lines of the answer %s (predicted %s)" % (answer, r["decision"]["predicted"]))
PY
    { cat "$WORK/decide.shim.err" >&2; fail "the timeline or the stall lines are not the answer's"; }
  case $strategy in
    direct|cache*) ;;
    *) grep -F "(every line: emm annotate $EMM_TRACE --strategy $strategy)" "$WORK/decide.shim.err" |
         grep -q "^emm:   the answer's DMA stalls come from " ||
         { cat "$WORK/decide.shim.err" >&2; fail "the summary does not name the answer's stall lines"; } ;;
  esac
else
  # A window-only capture answers over its window: every candidate set
  # against direct reads there, and never an EMM strategy slower than them.
  python3 - "$EMM_REPORT" <<'PY' || { cat "$WORK/decide.shim.err" >&2; fail "the window-only answer"; }
import json, sys
r = json.load(open(sys.argv[1]))
assert r["capture"] == "fault" and r["coverage"]["simulated"] == "window", (r["capture"], r["coverage"])
runs = {x["strategy"]: x["cycles"]["total"] for x in r["results"] if "cycles" in x}
check = r["decision"]["window_check"]
cands = {k: v for k, v in runs.items() if not k.startswith("cache")}
assert check and check["candidates"] == len(cands), (check, len(cands))
answer, direct = runs[r["strategy"]], runs["direct"]
assert answer <= direct, "answer %s: %d cycles, direct %d" % (r["strategy"], answer, direct)
pred = r["decision"]["predicted"]
assert check["predicted_cycles"] == runs[pred] and check["direct_cycles"] == direct
if check["kept"]:
    assert r["strategy"] == pred and runs[pred] <= direct
else:
    assert runs[pred] > direct and answer == min(cands.values()), (pred, runs[pred], direct)
print("window-only answer %s: %d cycles, direct %d; predicted %s: %d (%s)"
      % (r["strategy"], answer, direct, pred, runs[pred], "kept" if check["kept"] else "replaced"))
PY
  expect_err decide '^emm: answer: .*over the profiling window only'
  expect_err decide 'for an answer over the whole run, capture all of it: emm run --capture valgrind'
  expect_err decide 'its window took [0-9.]* s from the first access it captured to the decision, [0-9.]* us per access'
fi
echo "decide: ok"
