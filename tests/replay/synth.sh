#!/bin/sh
# emm trace synth as a user runs it: every pattern writes a valid trace of 4
# records per visit; the same seed gives the same file, another seed another
# file where the seed matters; bad usage and bad input.
# usage: synth.sh EMM WORKDIR
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

expect 0 "$EMM" mesh gen --faces 1000 --seed 5 -o "$W/m.off"
M="$W/m.off"

for p in region curve scanline zorder gray hilbert random spiral; do
    expect 0 "$EMM" trace synth --mesh "$M" --pattern $p --visits 300 -o "$W/$p.emmt"
    has "wrote $W/$p.emmt: 1200 records (pattern $p)"
    expect 0 "$EMM" trace info --verify "$W/$p.emmt"
    has 'verify: *ok'
    has 'accesses:    1200 '
    has 'geometry:    [0-9]* vertices, 1000 triangles'
    # Same options, same file.
    expect 0 "$EMM" trace synth --mesh "$M" --pattern $p --visits 300 -o "$W/$p.again.emmt"
    cmp -s "$W/$p.emmt" "$W/$p.again.emmt" || no "$p: the same seed gave different files"
    # Every triangle once by default.
    expect 0 "$EMM" trace synth --mesh "$M" --pattern $p -o "$W/$p.full.emmt"
    has "4000 records"
done

# The seed matters for region, curve and random.
for p in region curve random; do
    expect 0 "$EMM" trace synth --mesh "$M" --pattern $p --visits 300 --seed 2 -o "$W/$p.s2.emmt"
    cmp -s "$W/$p.emmt" "$W/$p.s2.emmt" && no "$p: seeds 1 and 2 gave the same file"
done

# Curves revisit triangles: more visits than triangles, walks of a set length.
expect 0 "$EMM" trace synth --mesh "$M" --pattern curve --visits 5000 --length 25 -o "$W/long.emmt"
has '20000 records'
expect 0 "$EMM" trace info --verify "$W/long.emmt"; has 'verify: *ok'
# Options that change the file: --corner, --ring, --work, --compress.
expect 0 "$EMM" trace synth --mesh "$M" --pattern region --corner --visits 300 -o "$W/corner.emmt"
cmp -s "$W/region.emmt" "$W/corner.emmt" && no "--corner changed nothing"
# Growth over vertices' one-rings: every triangle once a corner, 3 visits
# a triangle by default; the same seed, the same file.
expect 0 "$EMM" trace synth --mesh "$M" --pattern region --ring -o "$W/ring.emmt"
has "wrote $W/ring.emmt: 12000 records (pattern region)"
expect 0 "$EMM" trace info --verify "$W/ring.emmt"; has 'verify: *ok'
expect 0 "$EMM" trace synth --mesh "$M" --pattern region --ring -o "$W/ring.again.emmt"
cmp -s "$W/ring.emmt" "$W/ring.again.emmt" || no "--ring: the same seed gave different files"
expect 0 "$EMM" trace synth --mesh "$M" --pattern region --ring --visits 300 -o "$W/ring300.emmt"
has '1200 records'
cmp -s "$W/region.emmt" "$W/ring300.emmt" && no "--ring changed nothing"
expect 0 "$EMM" trace synth --mesh "$M" --pattern zorder --work 7 --compress -o "$W/z.emmt"
expect 0 "$EMM" trace info --verify "$W/z.emmt"; has 'compressed:  yes'; has 'verify: *ok'
# A synthetic trace replays under every strategy.
expect 0 "$EMM" replay "$W/z.emmt" --strategy cache@quadtree --strategy cache --quiet

# Bad usage, bad input.
expect 2 "$EMM" trace synth --mesh "$M" --pattern zigzag -o "$W/x.emmt"
has "--pattern expects region, curve, scanline, zorder, gray, hilbert, random or spiral, not 'zigzag'"
[ -e "$W/x.emmt" ] && no "a bad pattern left a file"
expect 2 "$EMM" trace synth --pattern region -o "$W/x.emmt"; has 'missing --mesh'
expect 2 "$EMM" trace synth --mesh "$M" -o "$W/x.emmt"; has 'missing --pattern'
expect 2 "$EMM" trace synth --mesh "$M" --pattern region; has 'missing -o'
expect 2 "$EMM" trace synth --mesh "$M" --pattern region --visits 0 -o "$W/x.emmt"
expect 2 "$EMM" trace synth --mesh "$M" --pattern region --seed -1 -o "$W/x.emmt"
expect 2 "$EMM" trace synth --mesh "$M" --pattern region --bogus -o "$W/x.emmt"
expect 1 "$EMM" trace synth --mesh "$W/none.off" --pattern region -o "$W/x.emmt"
has 'none.off'
expect 1 "$EMM" trace synth --mesh "$M" --pattern region -o "$W/no/such/dir/x.emmt"
has 'x.emmt'
expect 0 "$EMM" trace synth --help; has 'usage: emm trace synth'; has 'hilbert'
expect 0 "$EMM" trace --help; has 'emm trace synth'

[ $fail = 0 ] && echo "synth ok"
exit $fail
