#!/bin/sh
# emm annotate as a user runs it: curve_tracing.sancov --long on the thesis'
# default mesh under emm run with a trace (program counters included); the
# curve-tracing loop's function, trace_curve, is among the three functions
# with the most DMA stall under tiles+extrapolated@4 (the thesis' long-curve
# strategy); the costs add up to emm replay's total; --source prints the
# file with counts in the margin; a trace without program counters is
# refused; the session's summary and report name the stall lines.
# usage: annotate.sh EMM CURVES WORKDIR
set -u
EMM=$1 CURVES=$2 W=$3
S=tiles+extrapolated@4
rm -rf "$W" && mkdir -p "$W" || exit 1
fail=0
no() { echo "FAIL: $*"; fail=1; }

"$EMM" mesh gen --faces 20000 --seed 1 -o "$W/mesh.off" >/dev/null || exit 1
"$EMM" run --capture sancov --strategy $S --trace "$W/curves.emmt" --report "$W/run.json" \
    -- "$CURVES" --long "$W/mesh.off" >"$W/run.out" 2>"$W/run.err" || { cat "$W/run.err"; exit 1; }
cat "$W/run.err"
grep -q "^emm:   the answer's DMA stalls come from .*curve_tracing.c:[0-9]" "$W/run.err" ||
    no "the summary names no stall line"
grep -q '"stall_lines"' "$W/run.json" || no "the report has no stall_lines"
"$EMM" trace info "$W/curves.emmt" | grep -q "^pcs: *yes" || no "the trace has no pcs"

"$EMM" annotate "$W/curves.emmt" --strategy $S --sort dma_stall --top 3 >"$W/ann.out" 2>"$W/ann.err" ||
    { cat "$W/ann.err"; no "emm annotate failed"; }
cat "$W/ann.out"
[ -s "$W/ann.err" ] && { cat "$W/ann.err"; no "emm annotate complained"; }
# The three function rows.
sed -n '/^-- functions/,/^$/p' "$W/ann.out" | grep -q " trace_curve (curve_tracing.c)$" ||
    no "trace_curve is not among the top three functions for DMA stalls"
# The session's stall lines (the chosen model reporting its stalls as it
# runs) are emm annotate's DMA stalls of those lines (a costed replay).
python3 - "$W/run.json" "$W/ann.out" <<'PY' || no "the session's stall lines are not emm annotate's"
import json, re, sys
lines = json.load(open(sys.argv[1]))["stall_lines"]
ann = {}
for row in open(sys.argv[2]):
    m = re.match(r"\s*(\d+)\s+(\d+)\s+[\d.]+%.*\s(\S+:\d+) \(", row)
    if m:
        ann[m.group(3)] = int(m.group(2))
assert lines, "no stall lines"
for l in lines:
    key = "%s:%d" % (l["file"].rsplit("/", 1)[-1], l["line"])
    assert ann.get(key) == l["dma_stall"], (key, l["dma_stall"], ann.get(key))
PY
# The total is emm replay's.
"$EMM" replay "$W/curves.emmt" --strategy $S --json "$W/replay.json" --quiet || no "replay failed"
total=$(sed -n 's/.* accesses, \([0-9]*\) cycles .*/\1/p' "$W/ann.out")
grep -q "\"total\": $total," "$W/replay.json" || no "annotate's total $total is not replay's"
# --source: the loop's line has counts in the margin, a line without accesses dots.
"$EMM" annotate "$W/curves.emmt" --strategy $S --top 1 --source curve_tracing.c >"$W/src.out" ||
    no "--source failed"
grep -q "^ *[0-9][0-9]* *[0-9][0-9]* *[0-9][0-9]*  *int32_t x = T->vertexIndices\[i\]" "$W/src.out" ||
    no "--source: shared_edge's load has no counts"
grep -q "^ *\. *\. *\.  *static int shared_edge" "$W/src.out" || no "--source: no dots"
"$EMM" annotate "$W/curves.emmt" --strategy $S --source nosuch.c >/dev/null 2>"$W/err" &&
    no "--source nosuch.c succeeded"
grep -q "nosuch.c: no access of the trace lies in that file" "$W/err" || no "--source nosuch.c: message"
# A trace without program counters.
"$EMM" trace synth --mesh "$W/mesh.off" --pattern curve --visits 100 -o "$W/synth.emmt" >/dev/null
"$EMM" annotate "$W/synth.emmt" --strategy $S >/dev/null 2>"$W/err" && no "a trace without pcs was annotated"
grep -q "has no program counters" "$W/err" || no "no-pc message: $(cat "$W/err")"
"$EMM" annotate "$W/curves.emmt" >/dev/null 2>&1; [ $? -eq 2 ] || no "no --strategy: not a usage error"
[ $fail -eq 0 ] && echo "annotate test passed"
exit $fail
