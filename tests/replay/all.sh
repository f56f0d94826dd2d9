#!/bin/sh
# emm replay --all as a user runs it: the standard sweep's strategies in
# one command, the table sorted by total cycles, the JSON report (parseable,
# one entry per strategy, buckets adding up), the same numbers on 1 and 2
# threads, strategies that cannot run reported as skipped, bad usage.
# usage: all.sh EMM WORKDIR
set -u
EMM=$1
W=$2
rm -rf "$W" && mkdir -p "$W" || exit 1
fail=0
no() { echo "FAIL: $*"; fail=1; }
expect() {
    want=$1; shift
    "$@" >"$W/out" 2>"$W/err"
    got=$?
    [ "$got" = "$want" ] || { no "'$*' exited $got, wanted $want"; cat "$W/out" "$W/err"; }
}
has() { grep -q -- "$1" "$W/out" "$W/err" || { no "output lacks '$1'"; cat "$W/out" "$W/err"; }; }

# The sweep's size, as emm replay --help states it: N strategies over L
# layouts, of which N - 2 - L are EMM strategies (then direct, cache and
# cache@ each layout).
"$EMM" replay --help >"$W/help"
N=$(sed -n 's/.* \([0-9][0-9]*\) strategies.*/\1/p' "$W/help")
L=$(sed -n 's/^ *\([0-9][0-9]*\) layouts x .*/\1/p' "$W/help")
[ -n "$N" ] && [ -n "$L" ] || { no "emm replay --help does not state the sweep"; exit 1; }
E=$((N - 2 - L))

expect 0 "$EMM" mesh gen --faces 2000 --seed 3 -o "$W/m.off"
expect 0 "$EMM" trace synth --mesh "$W/m.off" --pattern curve --visits 6000 --length 40 \
    --work 2 -o "$W/t.emmt"
has 'wrote .*: 24000 records (pattern curve)'

expect 0 "$EMM" replay "$W/t.emmt" --all --jobs 1 --json "$W/j1.json"
cp "$W/out" "$W/table1"
has "$N strategies (0 skipped)"
expect 0 "$EMM" replay "$W/t.emmt" --all --jobs 2 --json "$W/j2.json"
cp "$W/out" "$W/table2"
# The table: N ranked lines, totals ascending; the same on 1 and 2 threads.
n=$(grep -c '^ *[0-9][0-9]*  ' "$W/table1")
[ "$n" = "$N" ] || no "table has $n ranked lines, wanted $N"
grep '^ *[0-9][0-9]*  ' "$W/table1" | awk '{ print $3 }' >"$W/totals"
sort -n "$W/totals" | cmp -s - "$W/totals" || no "table is not sorted by total cycles"
for s in direct cache cache@grid cache@tiles cache@quadtree grid+naive@4 grid+naive@16 \
         tiles+convolution@64 quadtree+extrapolated@256; do
    grep -q "^ *[0-9][0-9]*  $s  *[0-9]" "$W/table1" || no "table lacks $s"
done
cmp -s "$W/table1" "$W/table2" || no "tables differ between --jobs 1 and --jobs 2"
cmp -s "$W/j1.json" "$W/j2.json" || no "JSON reports differ between --jobs 1 and --jobs 2"
# The default number of threads gives the same numbers too.
expect 0 "$EMM" replay "$W/t.emmt" --all --quiet --json "$W/jd.json"
cmp -s "$W/j1.json" "$W/jd.json" || no "JSON report differs with the default --jobs"

# The report: parseable, N results, each bucket set adding up to its total,
# and the same numbers as single-strategy replays.
n=$(grep -c '"strategy":' "$W/j1.json")
[ "$n" = "$N" ] || no "report has $n results, wanted $N"
if command -v python3 >/dev/null 2>&1; then
    python3 - "$W/j1.json" "$N" <<'PY' || no "report check failed"
import json, sys
d = json.load(open(sys.argv[1]))
res = d["results"]
n = int(sys.argv[2])
assert len(res) == n, len(res)
assert len({r["strategy"] for r in res}) == n
for r in res:
    c = r["cycles"]
    assert "error" not in r, r
    assert r["accesses"] == d["accesses"] == 24000, r
    assert c["total"] == sum(v for k, v in c.items() if k != "total"), r["strategy"]
    if r["strategy"].startswith("cache"):
        assert "cache" in r and "dma" not in r
PY
fi
expect 0 "$EMM" replay "$W/t.emmt" --strategy cache@tiles --strategy tiles+naive@32 --json "$W/one.json"
for s in cache@tiles tiles+naive@32; do
    a=$(grep -A3 "\"strategy\": \"$s\"" "$W/one.json" | grep '"total"')
    b=$(grep -A3 "\"strategy\": \"$s\"" "$W/j1.json" | grep '"total"')
    [ -n "$a" ] && [ "$a" = "$b" ] || no "$s: total '$a' alone, '$b' in the sweep"
done
# The cache on the layout at another cell (cache@LAYOUT@CELL): the cell-by-cell
# image of grid+naive@4's cells, not of the default 64's, so other lines miss.
expect 0 "$EMM" replay "$W/t.emmt" --strategy cache@grid@4 --strategy cache@grid@64 \
    --json "$W/cell.json"
has 'cache@grid@4 '
a=$(grep -A3 '"strategy": "cache@grid@4"' "$W/cell.json" | grep '"total"')
b=$(grep -A3 '"strategy": "cache@grid"' "$W/cell.json" | grep '"total"')
c=$(grep -A3 '"strategy": "cache@grid"' "$W/j1.json" | grep '"total"')
[ -n "$a" ] && [ -n "$b" ] && [ "$a" != "$b" ] && [ "$b" = "$c" ] ||
  no "cache@grid@4 '$a', cache@grid@64 '$b', cache@grid in the sweep '$c'"
expect 2 "$EMM" replay "$W/t.emmt" --strategy cache@grid@0; has "cell size '0'"

# Strategies that cannot run are skipped, with the reason, and the sweep goes
# on: a local store of 8 KiB pages the look-up tables into 4 KiB and leaves
# 4 KiB, too small for the larger cells (small ones still run).
expect 0 "$EMM" replay "$W/t.emmt" --all --set local.bytes=8K --json "$W/sk.json"
k=$(sed -n "s/.*$N strategies (\([0-9][0-9]*\) skipped).*/\1/p" "$W/out")
[ -n "$k" ] && [ "$k" -gt 0 ] && [ "$k" -lt "$E" ] || no "8K local store: '$k' skipped of $E EMM strategies"
has '^skipped:'
has '^  grid+naive@256 (local store less 4,096 bytes of look-up tables): '
# grid+naive@8's largest cell (its triangles' slots with their vertex
# pointers) needs more than the 5 KiB three of the budget's frames would
# leave: the tables keep fewer frames (2 of 1 KiB) and it runs.
grep -q '"strategy": "grid+naive@8"' "$W/sk.json" && grep -q '"local_budget": 6144' "$W/sk.json" ||
  no "8K local store: grid+naive@8 does not run with the tables' frames shrunk to its cell"
grep -q '^ *[0-9][0-9]*  grid+naive@4  *[0-9]' "$W/out" || no "8K local store: grid+naive@4 did not run"
n=$(grep -c '"error":' "$W/sk.json")
[ "$n" = "$k" ] || no "report has $n skipped entries, wanted $k"
n=$(grep -c '"strategy":' "$W/sk.json")
[ "$n" = "$N" ] || no "report has $n entries, wanted $N"
if command -v python3 >/dev/null 2>&1; then
    python3 -m json.tool "$W/sk.json" >/dev/null || no "skipped report is not JSON"
fi
# An address-only trace: only direct and cache run.
printf '0 1000\n0 1004\n1 2000\n' >"$W/a.din"
expect 0 "$EMM" trace import --din "$W/a.din" -o "$W/a.emmt"
expect 0 "$EMM" replay "$W/a.emmt" --all
has "$N strategies ($((N - 2)) skipped)"
has 'cache@grid: the trace has no mesh geometry'
# Without --all a strategy that cannot run is still an error.
expect 1 "$EMM" replay "$W/a.emmt" --strategy cache@grid; has 'address-only'

# Bad usage.
expect 2 "$EMM" replay "$W/t.emmt" --all --strategy cache; has 'do not go together'
expect 2 "$EMM" replay "$W/t.emmt" --all --jobs 0; has 'jobs'
expect 2 "$EMM" replay "$W/t.emmt" --all --jobs x
expect 2 "$EMM" replay "$W/t.emmt" --all --jobs
expect 0 "$EMM" replay --help; has '--all'; has '--jobs'

[ $fail = 0 ] && echo "all ok"
exit $fail
