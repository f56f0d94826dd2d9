#!/bin/sh
# Layouts in space as a user meets them: emm layout draws and describes
# octree, grid3d and tiles3d on a closed surface; emm replay --all adds them
# to the sweep of a mesh with depth (a sphere) and not of a planar one,
# whose sweep stays the standard 68, and the contest (emm profile
# --finalists) likewise; a bunny trace replays under each strategy in space.
# usage: space.sh EMM WORKDIR
set -u
EMM=$1
DIR=$2
PY=/usr/bin/python3
BUNNY=/usr/share/glmark2/models/bunny.obj
rm -rf "$DIR" && mkdir -p "$DIR" || exit 1
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
[ -x "$PY" ] || { echo "skipped: $PY missing"; exit 77; }

# A UV sphere of radius 1: 24 rings of 32 quads, 1,472 triangles.
"$PY" - "$DIR/sphere.off" <<'EOF' || { echo "FAIL: sphere"; exit 1; }
import math, sys
n, m = 24, 32
v = [(0.0, 0.0, 1.0)]
for i in range(1, n):
    th = math.pi * i / n
    for j in range(m):
        ph = 2 * math.pi * j / m
        v.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)))
v.append((0.0, 0.0, -1.0))
ring = lambda i, j: 1 + (i - 1) * m + j % m
f = [(0, ring(1, j), ring(1, j + 1)) for j in range(m)]
for i in range(1, n - 1):
    for j in range(m):
        f += [(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)), (ring(i, j), ring(i + 1, j + 1), ring(i, j + 1))]
f += [(len(v) - 1, ring(n - 1, j + 1), ring(n - 1, j)) for j in range(m)]
with open(sys.argv[1], "w") as o:
    o.write("OFF\n%d %d 0\n" % (len(v), len(f)))
    o.writelines("%.9f %.9f %.9f\n" % p for p in v)
    o.writelines("3 %d %d %d\n" % t for t in f)
EOF

# emm layout: an SVG (the projection, coloured by cell) and the statistics.
for s in octree+naive@64 grid3d+convolution@32 tiles3d+extrapolated@16; do
    f="$DIR/$(echo "$s" | tr '+@' '__').svg"
    "$EMM" layout "$DIR/sphere.off" --strategy "$s" --svg "$f" --stats > "$DIR/out" 2> "$DIR/err" ||
        fail "$s: emm layout exits non-zero: $(cat "$DIR/err")"
    tail -n 1 "$f" | grep -q '^</svg>$' || fail "$s: $f is not a whole SVG"
    [ "$(grep -c '<path fill=' "$f")" -ge 8 ] || fail "$s: $f draws fewer than 8 cells"
    grep -q "over x, y and z" "$DIR/out" || fail "$s: not laid out in space: $(sed -n 2p "$DIR/out")"
done
"$EMM" layout "$DIR/sphere.off" --strategy octree+naive@16 > "$DIR/stats" 2>&1 || fail "octree --stats"
grep -q '^octree depth    min [0-9]*, max [0-9]*$' "$DIR/stats" || fail "octree stats lack the depths: $(cat "$DIR/stats")"
grep -q '^octree nodes    [0-9,]* (0 leaves over CELL' "$DIR/stats" || fail "octree stats lack the nodes: $(cat "$DIR/stats")"
grep -q 'triangles/cell  min [0-9]*, median [0-9]*, max \(1[0-6]\|[0-9]\)$' "$DIR/stats" ||
    fail "an octree leaf holds more than CELL 16: $(grep triangles/cell "$DIR/stats")"
"$EMM" layout "$DIR/sphere.off" --strategy tiles3d+naive@16 > "$DIR/stats" 2>&1 || fail "tiles3d --stats"
grep -q '^layout          tiles3d, CELL 16 ([0-9]* layers of [0-9]* and [0-9]* rows of [0-9]* and [0-9]* boxes), over x, y and z$' "$DIR/stats" ||
    fail "tiles3d stats: $(sed -n 2p "$DIR/stats")"

# The sweep: a sphere has depth (134 strategies, the layouts in space among
# them), a planar mesh has none (the standard 68, none in space).
"$EMM" mesh gen --faces 1500 --seed 2 -o "$DIR/flat.off" > /dev/null || fail "mesh gen"
for m in sphere flat; do
    "$EMM" trace synth --mesh "$DIR/$m.off" --pattern region -o "$DIR/$m.trace" > /dev/null ||
        fail "$m: trace synth"
    "$EMM" replay "$DIR/$m.trace" --all --json "$DIR/$m.json" -q > /dev/null 2> "$DIR/err" ||
        fail "$m: replay --all: $(cat "$DIR/err")"
done
"$PY" - "$DIR/sphere.json" "$DIR/flat.json" <<'EOF' || fail "the sweeps (above)"
import json, sys
space = ("grid3d", "tiles3d", "octree")
def sweep(path):
    r = json.load(open(path))["results"]
    return {x["strategy"]: x for x in r}
deep, flat = sweep(sys.argv[1]), sweep(sys.argv[2])
bad = []
if len(deep) != 134: bad.append("sphere: %d strategies, not 134" % len(deep))
if len(flat) != 68: bad.append("flat: %d strategies, not 68" % len(flat))
for l in space:
    for f in ("naive", "convolution", "extrapolated"):
        for c in (4, 8, 16, 32, 64, 128, 256):
            s = "%s+%s@%d" % (l, f, c)
            if s not in deep: bad.append("sphere: %s missing" % s)
            if s in flat: bad.append("flat: %s in the sweep" % s)
    if "cache@" + l not in deep: bad.append("sphere: cache@%s missing" % l)
if sorted(set(deep) - set(flat)) != sorted(s for s in deep if s.split("+")[0].split("@")[-1] in space):
    bad.append("sphere: the sweep differs from the flat one by more than the layouts in space")
# The layouts in space keep the sphere's front and back apart: grid3d's
# convolution moves fewer bytes than the planar grid's.
g3, g2 = deep.get("grid3d+convolution@16"), deep.get("grid+convolution@16")
if g3 and g2 and not g3["dma"]["bytes"] < g2["dma"]["bytes"]:
    bad.append("grid3d+convolution@16 moves %d bytes, grid+convolution@16 %d" % (g3["dma"]["bytes"], g2["dma"]["bytes"]))
for b in bad: print("FAIL:", b)
sys.exit(1 if bad else 0)
EOF
# The run's contest over the sphere's trace holds them: 127 candidates (126
# EMM strategies and direct: the default machine offers no cache), the
# planar mesh's 64 (63 and direct).
for m in sphere:127 flat:64; do
    "$EMM" profile "$DIR/${m%:*}.trace" --finalists 4 > "$DIR/contest" 2>&1 ||
        fail "${m%:*}: contest: $(cat "$DIR/contest")"
    grep -q "^contest: *${m#*:} candidates" "$DIR/contest" ||
        fail "${m%:*}: the contest does not hold ${m#*:} candidates: $(grep -A1 '^contest' "$DIR/contest")"
done
# A strategy in space named on a planar mesh still runs (one layer of boxes).
"$EMM" replay "$DIR/flat.trace" --strategy octree+naive@64 --strategy tiles3d+convolution@16 -q \
    > /dev/null 2> "$DIR/err" || fail "flat: strategies in space: $(cat "$DIR/err")"

# The bunny, a real scan: each strategy in space replays.
if [ ! -r "$BUNNY" ]; then
    echo "skipped: $BUNNY missing (install glmark2-data, scripts/deps.sh)"
    [ $fails -eq 0 ] && exit 77
    exit 1
fi
"$EMM" trace synth --mesh "$BUNNY" --pattern curve --visits 20000 -o "$DIR/bunny.trace" > /dev/null ||
    fail "bunny: trace synth"
"$EMM" replay "$DIR/bunny.trace" --strategy octree+naive@64 --strategy grid3d+convolution@32 \
    --strategy tiles3d+extrapolated@16 --strategy direct --json "$DIR/bunny.json" -q > /dev/null 2> "$DIR/err" ||
    fail "bunny: replay: $(cat "$DIR/err")"
"$PY" - "$DIR/bunny.json" <<'EOF' || fail "bunny replay (above)"
import json, sys
r = {x["strategy"]: x for x in json.load(open(sys.argv[1]))["results"]}
bad = []
for s in ("octree+naive@64", "grid3d+convolution@32", "tiles3d+extrapolated@16"):
    x = r.get(s)
    if not x: bad.append("%s did not run" % s); continue
    if x["accesses"] != 80000: bad.append("%s: %d accesses, not 80000" % (s, x["accesses"]))
    if not x["dma"]["transfers"] > 0: bad.append("%s: no DMA" % s)
    if len(x["cells"]["bbox"]) != 6: bad.append("%s: the cells' box is not 3D" % s)
    if not x["cycles"]["total"] < r["direct"]["cycles"]["total"]:
        bad.append("%s: %d cycles, direct %d" % (s, x["cycles"]["total"], r["direct"]["cycles"]["total"]))
for b in bad: print("FAIL:", b)
sys.exit(1 if bad else 0)
EOF

[ $fails -eq 0 ] || exit 1
echo "space: all passed"
