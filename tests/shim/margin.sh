# The contest's margin (docs/profile.md "The contest"): on the random
# access workload (examples/random_access.c, the thesis' sort of the
# vertices by tension) over a 40,000-face mesh, direct reads lead and the
# EMM finalists, which fetch a whole cell for each scattered vertex, fall
# more than 25% behind, so far and since the previous check: they are
# stopped instead of running to the end. Each one the report lists as stopped by
# the margin is that far behind the leader, after halving and from the
# fourth window on; the summary counts them; and replayed over the whole
# recorded run (emm replay: the same models over the same records, as the
# replayed answer's cycles show), none of them would have beaten the
# answer: it is the answer of the contest without the margin.
#   sh margin.sh SHIM WORKDIR EMM RANDOM_ACCESS_SANCOV
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM=$1 PROG=$2
MESH=$WORK/m.obj
"$EMM" mesh gen --faces 40000 --seed 5 -o "$MESH" > /dev/null || fail "cannot generate $MESH"
env -u LD_PRELOAD "$PROG" "$MESH" > "$WORK/native.out" || fail "the native run failed"
# Two finalists (the default is one): halving reaches four by 32 windows,
# and the margin's checks come before the run ends. The window is short
# (its 8,192 element reads read on to 12,288 to fill the local store, which
# the mesh outgrows), so the run is over 40 windows long; at the default
# window, read on to 24,576, it ends before 32.
"$EMM" run --capture sancov --no-phases --finalists 2 --profile 8192 --report "$WORK/r.json" \
  --trace "$WORK/run.emmt" -- "$PROG" "$MESH" > "$WORK/emm.out" 2> "$WORK/emm.err" ||
  { cat "$WORK/emm.err" >&2; fail "emm run failed"; }
cmp -s "$WORK/native.out" "$WORK/emm.out" || fail "stdout differs under emm run"
grep -E '^emm: answer: .*\([0-9]+ of them stopped as more than 25% behind the leader, so far and since the previous check\)' \
  "$WORK/emm.err" || { cat "$WORK/emm.err" >&2; fail "the summary does not count the stopped finalists"; }
# The answer and the stopped finalists, one -s each, for emm replay.
python3 - "$WORK/r.json" > "$WORK/strategies" <<'PY' || fail "the margin's report"
import json, sys
r = json.load(open(sys.argv[1]))
c = r["decision"]["contest"]
assert c["margin_percent"] == 25, c["margin_percent"]
stopped = [d for d in c["dropped"] if d["by"] == "margin"]
assert stopped, "no finalist was stopped by the margin"
for d in stopped:
    assert d["at"] >= c["lead"] + 4 * c["unit"], d
    assert 100 * (d["cycles"] - d["leader_cycles"]) > 25 * d["leader_cycles"], d
assert all(d["by"] == "halving" and "leader_cycles" not in d
           for d in c["dropped"] if d not in stopped)
print(r["strategy"])
for d in stopped:
    print(d["strategy"])
PY
set --
while read -r s; do set -- "$@" -s "$s"; done < "$WORK/strategies"
"$EMM" replay "$WORK/run.emmt" "$@" --json "$WORK/replay.json" --quiet > /dev/null ||
  fail "emm replay of the stopped finalists failed"
python3 - "$WORK/r.json" "$WORK/replay.json" <<'PY' || fail "a stopped finalist beat the answer"
import json, sys
r, rep = (json.load(open(p)) for p in sys.argv[1:3])
answer = next(x["cycles"]["total"] for x in r["results"] if x["strategy"] == r["strategy"])
whole = {x["strategy"]: x["cycles"]["total"] for x in rep["results"]}
assert whole[r["strategy"]] == answer, ("the replay is not the run", whole, answer)
stopped = [s for s in whole if s != r["strategy"]]
for s in stopped:
    assert whole[s] >= answer, (s, whole[s], r["strategy"], answer)
print(f"margin: {len(stopped)} finalists stopped, each slower than the answer over the run, "
      f"{r['strategy']} ({answer:,} cycles): " +
      ", ".join(f"{s} {whole[s]:,}" for s in stopped))
PY
