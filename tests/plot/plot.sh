#!/bin/sh
# emm plot as a user runs it: on the report of `emm replay --all --json` of
# a synthetic trace, every figure but the profile is written as a valid PNG
# and SVG (with the data and script beside it) and the profile is skipped
# with a note; --format; a malformed or missing report, a missing gnuplot
# and an unwritable --out are one error line, exit 1, nothing written; bad
# usage exits 2. Exits 77 (skipped) when gnuplot is not installed.
# usage: plot.sh EMM WORKDIR
set -u
EMM=$1
W=$2
command -v gnuplot >/dev/null 2>&1 || { echo "gnuplot not installed: skipped"; exit 77; }
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
one_line() {
    [ "$(wc -l <"$W/err")" = 1 ] || { no "stderr is not one line"; cat "$W/err"; }
    grep -q "^emm: $1" "$W/err" || { no "stderr lacks 'emm: $1'"; cat "$W/err"; }
}
is_png() { [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ]; }
is_svg() { grep -q '<svg' "$1"; }

expect 0 "$EMM" mesh gen --faces 2000 --seed 3 -o "$W/m.off"
expect 0 "$EMM" trace synth --mesh "$W/m.off" --pattern curve --visits 6000 --length 40 \
    --work 2 -o "$W/t.emmt"
expect 0 "$EMM" replay "$W/t.emmt" --all --quiet --json "$W/all.json"
grep -q '"rects"' "$W/all.json" || no "the report has no per-cell bytes"
# A sweep keeps the per-cell bytes of its fastest EMM strategy only.
[ "$(grep -c '"rects"' "$W/all.json")" = 1 ] || no "a sweep's report has per-cell bytes for more than the fastest EMM strategy"
expect 0 "$EMM" replay "$W/t.emmt" --strategy tiles+naive@8 --strategy grid+naive@16 --quiet \
    --json "$W/two.json"

# The default DIR: REPORT minus .json, plus -plots.
expect 0 "$EMM" plot "$W/all.json"
has 'no profile figure: the report has no profile'
for f in breakdown compare transfer cells; do
    for x in png svg; do
        p="$W/all-plots/$f.$x"
        [ -s "$p" ] || { no "$p missing or empty"; continue; }
        grep -q "^wrote $p\$" "$W/out" || no "'wrote $p' not printed"
    done
    is_png "$W/all-plots/$f.png" || no "$f.png is not a PNG"
    is_svg "$W/all-plots/$f.svg" || no "$f.svg is not an SVG"
    [ -s "$W/all-plots/$f.gp" ] && [ -s "$W/all-plots/$f.dat" ] || no "$f.gp or $f.dat missing"
done
[ -e "$W/all-plots/profile.png" ] && no "a profile figure without a profile"
ls -A "$W/all-plots" | grep -q '^\.emm-plot' && no "the work directory was left behind"
# The breakdown shows every layout x fetch scheme (as many as the sweep has,
# from emm replay --help); the cells are the best EMM's.
lf=$("$EMM" replay --help | sed -n 's/.* \([0-9][0-9]*\) layouts x \([0-9][0-9]*\) fetch schemes.*/\1 \2/p')
bars=$(( ${lf% *} * ${lf#* } ))
[ "$bars" -ge 9 ] || no "emm replay --help does not say the layouts and fetch schemes"
[ "$(grep -c '^"' "$W/all-plots/breakdown.dat")" = "$bars" ] || no "breakdown has not $bars bars"
grep -q '^"direct"' "$W/all-plots/compare.dat" || no "compare lacks direct"
grep -q '(best EMM)' "$W/all-plots/compare.dat" || no "compare lacks the best EMM strategy"
# One point per EMM strategy of the sweep: layouts x fetch schemes x cells.
ne=$(grep -c '"strategy": "[a-z][a-z0-9]*+' "$W/all.json")
[ "$(grep -c '^[0-9]' "$W/all-plots/transfer.dat")" = "$ne" ] || no "transfer has not $ne points"

# --format and --out; the figures' script can be rerun by hand.
expect 0 "$EMM" plot "$W/two.json" --out "$W/svg" --format svg --cells grid+naive@16
is_svg "$W/svg/cells.svg" || no "--format svg: no cells.svg"
[ -e "$W/svg/cells.png" ] && no "--format svg wrote a PNG"
grep -q 'grid+naive@16' "$W/svg/cells.dat" || no "--cells: not the strategy asked for"
(cd "$W/svg" && gnuplot -e "fmt='png'" cells.gp) && is_png "$W/svg/cells.png" ||
    no "cells.gp does not rerun"

# Malformed and missing reports: one line, exit 1, nothing written.
printf '{"emm_report": 1, "results": [}' >"$W/bad.json"
expect 1 "$EMM" plot "$W/bad.json"
one_line "$W/bad.json: line 1, column 31"
[ -e "$W/bad-plots" ] && no "a malformed report left a directory"
printf '{"emm_report": 1, "results": [{"strategy": "cache", "cycles": {"total": 5}}]}' \
    >"$W/short.json"
expect 1 "$EMM" plot "$W/short.json"
one_line "$W/short.json: results\[0\].cycles"
printf '[1, 2]' >"$W/notreport.json"
expect 1 "$EMM" plot "$W/notreport.json"
one_line "$W/notreport.json: not an emm report"
# A trace, a text file and a timeline say what they are.
"$EMM" trace synth --mesh "$W/m.off" --pattern curve --visits 50 -o "$W/x.emmt" >/dev/null 2>&1 ||
    no "trace synth"
expect 1 "$EMM" plot "$W/x.emmt"
one_line "$W/x.emmt: an emm trace, not a report: simulate it first"
printf 'hello\n' >"$W/text.txt"
expect 1 "$EMM" plot "$W/text.txt"
one_line "$W/text.txt: not a JSON report"
printf '{"traceEvents": []}' >"$W/tl.json"
expect 1 "$EMM" plot "$W/tl.json"
one_line "$W/tl.json: a timeline, not a report"
expect 1 "$EMM" plot "$W/none.json"
one_line "$W/none.json: cannot open"

# No gnuplot, an unwritable --out, a failing gnuplot: one line, exit 1, nothing written.
expect 1 "$EMM" plot "$W/all.json" --out "$W/x1" --gnuplot "$W/no-such-gnuplot"
one_line "$W/no-such-gnuplot: not found"
[ -e "$W/x1" ] && no "no gnuplot: a directory was made"
expect 1 env PATH=/nonexistent "$EMM" plot "$W/all.json" --out "$W/x2"
one_line "gnuplot: not found on PATH"
: >"$W/file"
expect 1 "$EMM" plot "$W/all.json" --out "$W/file/sub"
one_line "$W/file/sub: cannot create the directory"
printf '#!/bin/sh\necho "gnuplot broke" >&2\nexit 1\n' >"$W/fakegp" && chmod +x "$W/fakegp"
mkdir -p "$W/x3" && : >"$W/x3/keep"
expect 1 "$EMM" plot "$W/all.json" --out "$W/x3" --gnuplot "$W/fakegp"
one_line ".*gnuplot broke"
[ "$(ls -A "$W/x3")" = keep ] || { no "a failed gnuplot left files"; ls -A "$W/x3"; }
if [ "$(id -u)" != 0 ]; then
    mkdir -p "$W/ro" && chmod 555 "$W/ro"
    expect 1 "$EMM" plot "$W/all.json" --out "$W/ro"
    one_line "$W/ro: cannot write there"
    chmod 755 "$W/ro"
fi

# Usage.
expect 0 "$EMM" plot --help
has 'usage: emm plot REPORT'
expect 2 "$EMM" plot
expect 2 "$EMM" plot "$W/all.json" --format jpeg
expect 2 "$EMM" plot "$W/all.json" --bogus
expect 2 "$EMM" plot "$W/all.json" --cells grid+sideways

[ $fail = 0 ] && echo "plot: all checks passed"
exit $fail
