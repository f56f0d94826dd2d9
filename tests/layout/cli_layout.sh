#!/bin/sh
# emm layout as a user runs it: SVG output, statistics (the triangle's slot
# with its vertex pointers, also in a run's report), and the errors.
# usage: cli_layout.sh EMM WORKDIR
set -u
EMM=$1
DIR=$2
rm -rf "$DIR" && mkdir -p "$DIR" || exit 1
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

"$EMM" layout --help > "$DIR/help" 2>&1 || fail "--help exits non-zero"
grep -q '^usage: emm layout MESH --strategy S' "$DIR/help" || fail "--help prints no usage"

"$EMM" mesh gen --faces 3000 --seed 3 -o "$DIR/m.off" > /dev/null || { echo "FAIL: mesh gen"; exit 1; }

for s in grid+naive@32 tiles+convolution@64 quadtree+extrapolated@16 cache@tiles; do
    f="$DIR/$(echo "$s" | tr '+@' '__').svg"
    "$EMM" layout "$DIR/m.off" --strategy "$s" --svg "$f" > "$DIR/out" 2> "$DIR/err" || fail "$s: --svg exits non-zero: $(cat "$DIR/err")"
    head -c 5 "$f" | grep -q '^<?xml\|^<svg' || fail "$s: $f does not start with <?xml or <svg"
    tail -n 1 "$f" | grep -q '^</svg>$' || fail "$s: $f does not end with </svg>"
    grep -q '<path fill=' "$f" || fail "$s: $f draws no cells"
    grep -q "layout, CELL" "$f" || fail "$s: $f has no title"
    [ "$(wc -l < "$DIR/out")" = 1 ] && grep -q "^wrote $f: $s's [0-9]* cells over 3000 triangles\$" "$DIR/out" ||
        fail "$s: --svg does not say what it wrote: $(cat "$DIR/out")"
    ls "$DIR" | grep -q '\.tmp\.' && fail "$s: a temporary file was left behind"
done

"$EMM" layout "$DIR/m.off" --strategy quadtree+naive@32 --stats > "$DIR/stats" 2>&1 || fail "--stats exits non-zero"
for key in '^cells ' '^triangles/cell  min [0-9,]*, median [0-9,]*, max ' '^bytes/cell ' 'duplicated' '^lookup bytes ' '^quadtree depth  min [0-9]*, max [0-9]*'; do
    grep -q "$key" "$DIR/stats" || fail "--stats lacks '$key'"
done
# A triangle's slot in its cell: its record, then 3 pointers to its
# vertices' copies (thesis 4.1.1), the machine's words: 28 + 3 x 4 = 40 bytes
# by default, 28 + 3 x 8 = 52 with 8-byte pointers, and every one of the
# 3,000 triangles' slots is in the image.
grep -q '^triangle slot   40 bytes (28 of record, 3 pointers of 4 ' "$DIR/stats" ||
    fail "--stats: triangle slot not 40 bytes: $(grep slot "$DIR/stats")"
"$EMM" layout "$DIR/m.off" --strategy quadtree+naive@32 --pointer-bytes 8 > "$DIR/stats8" 2>&1 ||
    fail "--pointer-bytes 8 exits non-zero"
grep -q '^triangle slot   52 bytes (28 of record, 3 pointers of 8 ' "$DIR/stats8" ||
    fail "--pointer-bytes 8: triangle slot not 52 bytes: $(grep slot "$DIR/stats8")"
i4=$(sed -n 's/^image bytes *//p' "$DIR/stats" | tr -d ,)
i8=$(sed -n 's/^image bytes *//p' "$DIR/stats8" | tr -d ,)
[ -n "$i4" ] && [ -n "$i8" ] && [ $((i8 - i4)) -eq 36000 ] ||
    fail "image bytes $i4 (4-byte pointers), $i8 (8-byte): not 3000 x 12 apart"
# The run's report: with word.bytes = 8 an EMM strategy moves the same cells
# with 12 bytes more a triangle (a scanline visits each triangle once; a 1M
# store keeps every cell, so each moves once).
"$EMM" trace synth --mesh "$DIR/m.off" --pattern scanline -o "$DIR/s.emmt" > /dev/null ||
    fail "trace synth"
for w in 4 8; do
    "$EMM" replay "$DIR/s.emmt" --strategy grid+naive@64 --set local.bytes=1M --set word.bytes=$w \
        --json "$DIR/w$w.json" > /dev/null 2>&1 || fail "replay with word.bytes=$w exits non-zero"
done
/usr/bin/python3 - "$DIR/w4.json" "$DIR/w8.json" <<'PY' || fail "report: cell bytes do not follow word.bytes"
import json, sys
r4, r8 = (json.load(open(f))["results"][0] for f in sys.argv[1:])
for r in (r4, r8):
    assert r["emm"]["refetches"] == 0 and r["emm"]["lookup_page_bytes"] == 0, r["emm"]
d = r8["dma"]["bytes"] - r4["dma"]["bytes"]
assert d == 3000 * 12, (r4["dma"]["bytes"], r8["dma"]["bytes"])
PY
# No --svg and no --stats: statistics.
"$EMM" layout "$DIR/m.off" --strategy grid+naive > "$DIR/stats2" 2>&1 || fail "default run exits non-zero"
grep -q '^layout          grid, CELL 64 ' "$DIR/stats2" || fail "default run prints no statistics"

# Bad usage: one message, exit 2.
"$EMM" layout "$DIR/m.off" --strategy tiles+sideways@8 > /dev/null 2> "$DIR/err"
[ $? -eq 2 ] || fail "bad strategy does not exit 2"
head -n 1 "$DIR/err" | grep -q '^emm layout: .*sideways' || fail "bad strategy message: $(cat "$DIR/err")"
"$EMM" layout "$DIR/m.off" --strategy direct > /dev/null 2> "$DIR/err"
[ $? -eq 2 ] || fail "direct (no layout) does not exit 2"
"$EMM" layout "$DIR/m.off" > /dev/null 2>&1
[ $? -eq 2 ] || fail "missing --strategy does not exit 2"
"$EMM" layout "$DIR/m.off" --strategy grid+naive --bogus > /dev/null 2>&1
[ $? -eq 2 ] || fail "unknown option does not exit 2"

# Bad data: one line, exit 1.
"$EMM" layout "$DIR/m.off" --strategy tiles+convolution@256 --local 48K > /dev/null 2> "$DIR/err"
[ $? -eq 1 ] || fail "too-large cell does not exit 1"
[ "$(wc -l < "$DIR/err")" -eq 1 ] || fail "too-large cell: not one line"
grep -q "more than the 49,152-byte local store: use a smaller CELL than 256 (e.g. tiles+convolution@" "$DIR/err" || fail "too-large cell message: $(cat "$DIR/err")"
# ... but cache@LAYOUT moves no cells, so no local-store limit applies.
"$EMM" layout "$DIR/m.off" --strategy cache@tiles --local 2K > /dev/null 2>&1 || fail "cache@tiles is checked against the local store"
"$EMM" layout "$DIR/missing.off" --strategy grid+naive > /dev/null 2> "$DIR/err"
[ $? -eq 1 ] || fail "missing mesh does not exit 1"
[ "$(wc -l < "$DIR/err")" -eq 1 ] || fail "missing mesh: not one line"
"$EMM" layout "$DIR/m.off" --strategy grid+naive --svg "$DIR/no/such/dir/x.svg" > /dev/null 2> "$DIR/err"
[ $? -eq 1 ] || fail "unwritable svg does not exit 1"

[ $fails -eq 0 ] && echo "all passed"
exit $fails
