#!/bin/sh
# Adopting a layout's numbering, as an author would: emm layout --write
# renumbers a mesh (and --perm says how); the example workloads give the
# same results on it up to the numbering (region growing's code count and
# multiset of valences, long curves from every vertex: their count and total
# length); and their run under an :indexed strategy keeps no per-element
# look-up table: the report's look-up bytes are the per-cell table, 16 bytes
# a cell, where the same strategy without :indexed keeps 4 bytes an element.
# With REGION_GROWING_SANCOV (a sancov build: the whole run, so a contest),
# the run's contest takes the indexed variants on a mesh whose per-element
# tables exceed emm.lookup_budget (here lowered to 4K) and not otherwise,
# and an indexed answer's summary says what adopting the numbering saves.
# A sanitizer build has no shim (NOSHIM given): the trace of the renumbered
# mesh is then emm trace synth's region growth, replayed under S:indexed.
# usage: indexed.sh EMM WORKDIR REGION_GROWING CURVE_TRACING [REGION_GROWING_SANCOV|-] [NOSHIM]
set -u
EMM=$1
DIR=$2
RG=$3
CT=$4
RG_SANCOV=${5:-}
[ "$RG_SANCOV" = - ] && RG_SANCOV=
NOSHIM=${6:-}
PY=/usr/bin/python3
rm -rf "$DIR" && mkdir -p "$DIR" || exit 1
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
[ -x "$PY" ] || { echo "skipped: $PY missing"; exit 77; }

"$EMM" mesh gen --faces 2000 -o "$DIR/plane.off" > /dev/null || exit 1
"$EMM" mesh gen --surface sphere --faces 2000 -o "$DIR/sphere.obj" > /dev/null || exit 1

# On the plane the total length of the long curves is the same to the last
# digit; on the sphere a curve's first triangle, where its direction runs
# along an edge of the seed's fan, depends on the fan's order, and the
# total moves by a few parts in 100,000.
for c in "plane.off tiles+naive@16:indexed plane_t.off 1e-9" \
         "sphere.obj octree+convolution@32:indexed sphere_t.obj 1e-4"; do
    set -- $c
    mesh=$DIR/$1 s=$2 out=$DIR/$3 tol=$4
    "$EMM" layout "$mesh" --strategy "$s" --write "$out" --perm "$out.perm" > "$DIR/out" 2>&1 ||
        fail "$s: emm layout --write: $(cat "$DIR/out")"
    grep -q "^wrote $out: [0-9]* vertices and [0-9]* triangles in the order of $s's [0-9]* cells$" \
        "$DIR/out" || fail "$s: emm layout says $(cat "$DIR/out")"
    # The permutation is one, and the written mesh is the original under it.
    "$PY" - "$mesh" "$out" "$out.perm" <<'PY' || fail "$s: $out is not $mesh renumbered by $out.perm"
import sys
def read(p):
    L = [l.split() for l in open(p) if l.strip() and not l.startswith("#")]
    if p.endswith(".obj"):
        v = [tuple(map(float, l[1:4])) for l in L if l[0] == "v"]
        t = [tuple(int(x.split("/")[0]) - 1 for x in l[1:4]) for l in L if l[0] == "f"]
    else:
        nv, nt = int(L[1][0]), int(L[1][1])
        v = [tuple(map(float, l[:3])) for l in L[2:2 + nv]]
        t = [tuple(map(int, l[1:4])) for l in L[2 + nv:2 + nv + nt]]
    return v, t
v0, t0 = read(sys.argv[1]); v1, t1 = read(sys.argv[2])
lines = [l.split() for l in open(sys.argv[3])]
assert lines[0] == ["vertices", str(len(v0))], lines[0]
pv = [tuple(map(int, l)) for l in lines[1:1 + len(v0)]]
assert lines[1 + len(v0)] == ["triangles", str(len(t0))]
pt = [tuple(map(int, l)) for l in lines[2 + len(v0):]]
assert len(pt) == len(t0) == len(t1) and len(v1) == len(v0)
assert [n for n, _ in pv] == list(range(len(v0))) and sorted(o for _, o in pv) == list(range(len(v0)))
assert [n for n, _ in pt] == list(range(len(t0))) and sorted(o for _, o in pt) == list(range(len(t0)))
old_v = [o for _, o in pv]
assert all(v1[n] == v0[o] for n, o in enumerate(old_v)), "vertex coordinates"
assert all(tuple(old_v[x] for x in t1[n]) == t0[o] for n, o in pt), "triangles"
PY
    # The workloads agree up to the numbering.
    for m in "$mesh" "$out"; do
        "$RG" --print-codes "$m" > "$m.rg" || fail "region_growing $m"
        nv=$(sed -n 's/^codes: //p' "$m.rg")
        "$CT" --long --curves 1000000 "$m" > "$m.ct" || fail "curve_tracing $m"
        grep -v : "$m.rg" | sort > "$m.codes"
        echo "codes: $nv $(grep "^curves" "$m.ct")" > "$m.cmp"
    done
    cmp -s "$mesh.codes" "$out.codes" || fail "$s: region growing's valences differ on $out"
    cmp -s "$mesh.cmp" "$out.cmp" || fail "$s: $(cat "$mesh.cmp") on $mesh, $(cat "$out.cmp") on $out"
    "$PY" -c "import sys; a, b = (float(open(f).read().split('length: ')[1]) for f in sys.argv[2:]); assert a > 0 and abs(a - b) <= float(sys.argv[1]) * a, (a, b)" \
        "$tol" "$mesh.ct" "$out.ct" || fail "$s: long curves' total length differs on $out"
    # Under the :indexed strategy the look-up table is the per-cell one.
    cells=$("$EMM" layout "$out" --strategy "$s" --stats | sed -n 's/^cells *\([0-9,]*\) .*/\1/p' | tr -d ,)
    if [ -n "$NOSHIM" ]; then
        "$EMM" trace synth --mesh "$out" --pattern region -o "$out.emmt" > /dev/null &&
            "$EMM" replay "$out.emmt" -s "$s" --json "$out.json" -q ||
            fail "$s: synth and replay of $out"
    else
        EMM_STRATEGY=$s EMM_REPORT="$out.json" EMM_TRACE="$out.emmt" "$EMM" run -- "$RG" "$out" \
            > "$DIR/run.out" 2> "$DIR/run.err" || fail "$s: emm run: $(cat "$DIR/run.err")"
        "$RG" "$out" | cmp -s - "$DIR/run.out" ||
            fail "$s: the program's output changes under the shim"
    fi
    plain=${s%:indexed}
    "$EMM" replay "$out.emmt" -s "$plain" --json "$out.plain.json" -q || fail "$s: replay $plain"
    "$PY" - "$out.json" "$out.plain.json" "$s" "$plain" "$cells" <<'PY' || fail "$s: look-up bytes"
import json, sys
rep, plain, s, p, cells = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3], sys.argv[4], int(sys.argv[5])
r = next(x for x in rep["results"] if x["strategy"] == s)
q = next(x for x in plain["results"] if x["strategy"] == p)
assert rep.get("strategy", s) == s, rep["strategy"]  # emm run's answer; replay has none
assert r["emm"]["lookup_bytes"] == 16 * cells, (r["emm"]["lookup_bytes"], cells)
assert r["emm"]["lookup_paged"] == 0 and r["emm"]["lookups"] > 0, r["emm"]
assert q["emm"]["lookup_bytes"] > 4 * 2000 + 16 * cells, q["emm"]["lookup_bytes"]
PY
done

# The run's contest: the indexed variants join where the tables are paged.
if [ -n "$RG_SANCOV" ]; then
    printf '[emm]\nlookup_budget = 4K\n' > "$DIR/small.ini"
    for budget in default small; do
        set -- --capture sancov
        [ "$budget" = small ] && set -- "$@" --machine "$DIR/small.ini"
        EMM_REPORT="$DIR/contest-$budget.json" "$EMM" run "$@" \
            --finalists 2 -- "$RG_SANCOV" "$DIR/plane.off" > "$DIR/contest.out" 2> "$DIR/contest-$budget.err" ||
            fail "contest ($budget): $(cat "$DIR/contest-$budget.err")"
        "$RG" "$DIR/plane.off" | cmp -s - "$DIR/contest.out" || fail "contest ($budget): output changes"
    done
    "$PY" - "$DIR/contest-default.json" "$DIR/contest-small.json" "$DIR/contest-small.err" <<'PY' ||
import json, sys
d, m = (json.load(open(p)) for p in sys.argv[1:3])
names = lambda r: [x["strategy"] for x in r["results"]]
assert not any(n.endswith(":indexed") for n in names(d)), names(d)
# The small budget's contest: the default's entrants and the indexed variant
# of each of its EMM strategies (63 in the plane).
assert m["decision"]["contest"]["entrants"] == d["decision"]["contest"]["entrants"] + 63, (
    m["decision"]["contest"]["entrants"], d["decision"]["contest"]["entrants"])
assert any(n.endswith(":indexed") for n in names(m)), names(m)
rep = json.load(open(sys.argv[2]))
summary = open(sys.argv[3]).read()
line = "adopt this numbering (emm layout --write) and the look-up cost disappears"
assert (line in summary) == rep["strategy"].endswith(":indexed"), (rep["strategy"], summary)
PY
        fail "the contest's indexed variants: $(grep answer "$DIR/contest-small.err")"
fi

# A bad output: one message naming the file.
"$EMM" layout "$DIR/plane.off" --strategy tiles+naive --write "$DIR/m.ply" > /dev/null 2> "$DIR/err" &&
    fail "--write .ply accepted"
grep -q "m.ply: the file must end in .off (OFF) or .obj (OBJ)" "$DIR/err" || fail "--write .ply: $(cat "$DIR/err")"
"$EMM" layout "$DIR/plane.off" --strategy tiles+naive --write "$DIR/no/m.off" > /dev/null 2> "$DIR/err" &&
    fail "--write into a missing directory accepted"
[ "$(wc -l < "$DIR/err")" = 1 ] && grep -q "$DIR/no/m.off: cannot write the mesh" "$DIR/err" ||
    fail "--write into a missing directory: $(cat "$DIR/err")"
"$EMM" layout "$DIR/plane.off" --strategy tiles+naive --write "$DIR/m.off" --perm "$DIR/no/p" \
    > /dev/null 2> "$DIR/err" && fail "--perm into a missing directory accepted"
grep -q "$DIR/no/p: cannot write the permutation" "$DIR/err" || fail "--perm: $(cat "$DIR/err")"

[ "$fails" -eq 0 ] && echo "ok" || exit 1
