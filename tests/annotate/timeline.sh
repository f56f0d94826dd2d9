#!/bin/sh
# Timelines as a user makes them: emm replay --timeline and emm run
# --timeline on the long-curve trace of annotate.sh (the fixture); each
# parses as JSON and has one track per DMA channel and one complete event
# per transfer, as many as the report's DMA transfers (timeline.py checks).
# usage: timeline.sh EMM WORKDIR PYTHON3 TIMELINE_PY
set -u
EMM=$1 W=$2 PY=$3 CHECK=$4
S=tiles+extrapolated@4
fail=0
no() { echo "FAIL: $*"; fail=1; }
"$EMM" replay "$W/curves.emmt" --strategy $S --strategy direct --timeline "$W/tl.json" \
    --json "$W/tl-replay.json" >"$W/tl.out" 2>"$W/tl.err" || { cat "$W/tl.err"; no "replay --timeline failed"; }
grep -q "wrote $S's timeline to $W/tl.json" "$W/tl.err" || no "replay says nothing of the timeline"
"$PY" "$CHECK" "$W/tl.json" --report "$W/tl-replay.json" --channels 2 || no "replay's timeline"
# emm run: the chosen strategy's, with the window and the run after it as phases.
"$EMM" mesh gen --faces 3000 --seed 4 -o "$W/small.off" >/dev/null
"$EMM" run --strategy grid+convolution@16 --timeline "$W/run-tl.json" --report "$W/run-tl-report.json" \
    --quiet -- "$(dirname "$EMM")/curve_tracing.sancov" --long "$W/small.off" >/dev/null ||
    no "emm run --timeline failed"
"$PY" "$CHECK" "$W/run-tl.json" --report "$W/run-tl-report.json" --channels 2 --phases 2 ||
    no "emm run's timeline"
# A direct strategy has no DMA: the file says so.
"$EMM" replay "$W/curves.emmt" --strategy direct --timeline "$W/direct.json" --quiet || no "direct"
grep -q "no DMA engine" "$W/direct.json" || no "direct's timeline does not say it has no DMA"
"$EMM" replay --help | grep -q "500,000 events" || no "--help does not state the cap"
"$EMM" run --help | grep -q "EMM_TIMELINE" || no "emm run --help lacks EMM_TIMELINE"
[ $fail -eq 0 ] && echo "timeline test passed"
exit $fail
