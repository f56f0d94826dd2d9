#!/bin/sh
# emm machine and emm replay as a user runs them: acceptance numbers,
# machine files and --set (good and bad), EMM_MACHINE, replay's table and
# JSON report against the reference model's counts (din_ref).
# usage: cli_test.sh EMM DIN_REF WORKDIR
set -u
EMM=$1
DINREF=$2
W=$3
rm -rf "$W" && mkdir -p "$W" || exit 1
fail=0
no() { echo "FAIL: $*"; fail=1; }

# expect RC CMD...: runs CMD, stdout+stderr to $W/out, checks the exit status
expect() {
    want=$1; shift
    "$@" >"$W/out" 2>&1
    got=$?
    [ "$got" = "$want" ] || { no "'$*' exited $got, wanted $want"; cat "$W/out"; }
}
has() { grep -q -- "$1" "$W/out" || { no "output lacks '$1'"; cat "$W/out"; }; }

expect 0 "$EMM" machine dma 64;   has '^282$'
expect 0 "$EMM" machine dma 1025; has '^732$'
expect 0 "$EMM" machine --help;   has 'usage: emm machine'
expect 0 "$EMM" replay --help;    has 'usage: emm replay'
expect 2 "$EMM" machine;          has 'missing subcommand'
expect 2 "$EMM" machine dma;      has 'missing BYTES'
expect 2 "$EMM" machine dma 12x;  has "12x"
expect 2 "$EMM" machine dma 64 --set dma.isue=300; has "unknown key 'dma.isue'"
expect 2 "$EMM" machine dma 64 --set dma.issue=abc; has "dma.issue = 'abc'"
expect 0 "$EMM" machine dma 64 --set dma.issue=300; has '^316$'

# A machine file, and EMM_MACHINE when --machine is absent.
printf '# test\n[dma]\nissue = 100\n' >"$W/m.ini"
expect 0 "$EMM" machine dma 64 --machine "$W/m.ini"; has '^116$'
expect 0 env EMM_MACHINE="$W/m.ini" "$EMM" machine dma 64; has '^116$'
expect 0 env EMM_MACHINE="$W/m.ini" "$EMM" machine dma 64 --set dma.issue=0; has '^16$'
printf '[dma]\nissue = 100\nchanels = 3\n' >"$W/bad.ini"
expect 1 "$EMM" machine show --machine "$W/bad.ini"; has "bad.ini:3: unknown key 'dma.chanels'"
expect 1 "$EMM" machine show --machine "$W/missing.ini"; has "missing.ini"
printf 'cache.bytes = 1000\n' >"$W/geo.ini"
expect 1 "$EMM" machine show --machine "$W/geo.ini"; has "cache.bytes = 1000"

# show prints a machine file that reads back to the same machine.
"$EMM" machine show --set cache.fetch=always --set dma.channels=3 >"$W/shown.ini" || no "show"
"$EMM" machine show --machine "$W/shown.ini" >"$W/again.ini" || no "show of shown"
grep -v '^# emm machine' "$W/shown.ini" >"$W/a"; grep -v '^# emm machine' "$W/again.ini" >"$W/b"
cmp -s "$W/a" "$W/b" || no "show does not read back"
grep -q '^fetch = always' "$W/again.ini" || no "show lost cache.fetch"

# Replay: counts equal the reference model's, for the three policies.
"$DINREF" --generate 20000 7 >"$W/t.din" || no "generate"
"$DINREF" "$W/t.din" --write-trace "$W/t.emmt" || no "write trace"
for f in demand miss always; do
    c=$(echo $f | cut -c1)
    "$DINREF" "$W/t.din" --fetch "$c" >"$W/ref.$f" || no "din_ref $f"
    expect 0 "$EMM" replay "$W/t.emmt" --strategy cache --set cache.fetch=$f --json "$W/r.$f.json"
    has 'cache_miss_stall'
    for k in demand_fetches demand_misses prefetch_fetches; do
        v=$(grep "^$k " "$W/ref.$f" | cut -d' ' -f2)
        grep -q "\"$k\": $v," "$W/r.$f.json" || no "$f: $k differs from the reference ($v)"
    done
done
grep -q '"emm_report": 1' "$W/r.miss.json" || no "report version"
grep -q '"strategy": "cache"' "$W/r.miss.json" || no "report strategy"
grep -q '"total":' "$W/r.miss.json" || no "report total"
grep -q '"dma.program": 125' "$W/r.miss.json" || no "report machine"
grep -q '"dma.latency": 141' "$W/r.miss.json" || no "report machine latency"
expect 0 "$EMM" replay "$W/t.emmt" --strategy direct --strategy cache --json "$W/both.json"
has 'remote_access'
[ "$(grep -c '"strategy"' "$W/both.json")" = 2 ] || no "two results"
expect 0 "$EMM" replay "$W/t.emmt"; has 'direct'; has 'cache'
expect 1 "$EMM" replay "$W/t.emmt" --strategy grid+naive@64; has 'address-only trace'
expect 2 "$EMM" replay "$W/t.emmt" --strategy bogus
expect 1 "$EMM" replay "$W/nope.emmt"; has 'nope.emmt'
expect 2 "$EMM" replay
expect 1 "$EMM" replay "$W/t.emmt" --json "$W/no/such/dir/r.json"; has 'r.json'
[ -e "$W/no/such/dir/r.json" ] && no "partial report left"

[ $fail = 0 ] && echo "cli ok"
exit $fail
