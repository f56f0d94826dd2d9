# The contest's margin (docs/profile.md "The contest"): on a smoothing run
# the prediction leads, and challengers more than 25% behind it that do not
# gain on it are stopped early. Each one the report lists as stopped by the
# margin is that far behind the leader, from the fourth window on; the
# summary counts them; and the answer is the one of the contest that drops
# none (--finalists all), every candidate run to the end.
#   sh margin.sh SHIM WORKDIR EMM SMOOTH_SANCOV MESH.obj
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM=$1 PROG=$2 MESH=$3
TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
env -u LD_PRELOAD "$PROG" "$MESH" 4 > "$WORK/native.out" || fail "the native run failed"
for f in 4 all; do
  "$EMM" run --capture sancov --no-phases --finalists $f --tag "$TAG" --report "$WORK/$f.json" \
    -- "$PROG" "$MESH" 4 > "$WORK/$f.out" 2> "$WORK/$f.err" ||
    { cat "$WORK/$f.err" >&2; fail "emm run --finalists $f failed"; }
  cmp -s "$WORK/native.out" "$WORK/$f.out" || fail "--finalists $f: stdout differs under emm run"
done
grep -E '^emm: answer: .*\([0-9]+ of them stopped as more than 25% behind the leader, so far and since the previous check\)' \
  "$WORK/4.err" || { cat "$WORK/4.err" >&2; fail "the summary does not count the stopped challengers"; }
python3 - "$WORK/4.json" "$WORK/all.json" <<'PY' || fail "the margin's report"
import json, sys
r, full = (json.load(open(p)) for p in sys.argv[1:3])
c = r["decision"]["contest"]
assert c["margin_percent"] == 25, c["margin_percent"]
stopped = [d for d in c["dropped"] if d["by"] == "margin"]
assert stopped, "no challenger was stopped by the margin"
for d in stopped:
    assert d["at"] >= c["lead"] + 4 * c["unit"], d
    assert 100 * (d["cycles"] - d["leader_cycles"]) > 25 * d["leader_cycles"], d
assert all(d["by"] == "halving" and "leader_cycles" not in d
           for d in c["dropped"] if d not in stopped)
assert full["decision"]["contest"]["dropped"] == [], "--finalists all dropped candidates"
answer = next(x["cycles"]["total"] for x in r["results"] if x["strategy"] == r["strategy"])
whole = {x["strategy"]: x["cycles"]["total"] for x in full["results"]}
for d in stopped:
    assert whole[d["strategy"]] >= answer, (d, whole[d["strategy"]], r["strategy"], answer)
print(f"margin: {len(stopped)} stopped, {len(c['dropped'])} dropped of {c['entrants']}; "
      f"each ended slower than the answer, {r['strategy']} ({answer:,} cycles)")
PY
