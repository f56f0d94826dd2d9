#!/bin/sh
# 'emm trace' as a user runs it: help, usage errors, din import/export round
# trips, malformed input, damaged traces. Usage: cli_trace.sh EMM WORKDIR
set -u
EMM=$1
DIR=$2/cli_trace_$$
mkdir -p "$DIR" || exit 1
trap 'rm -rf "$DIR"' EXIT
fails=0
fail() { echo "FAIL: $*" >&2; fails=$((fails + 1)); }
# expect STATUS CMD...: runs CMD, checks its exit status.
expect() {
    want=$1; shift
    "$@" >"$DIR/out" 2>"$DIR/err"
    got=$?
    [ "$got" -eq "$want" ] || fail "exit $got (wanted $want): $* : $(cat "$DIR/err")"
}

# Help everywhere, exit 0, on stdout.
for sub in "" info export import; do
    expect 0 "$EMM" trace $sub --help
    grep -q usage "$DIR/out" || fail "no usage for 'trace $sub --help'"
done
# Usage errors: exit 2 with one line and a hint.
expect 2 "$EMM" trace
expect 2 "$EMM" trace frobnicate
expect 2 "$EMM" trace info
expect 2 "$EMM" trace info a b
expect 2 "$EMM" trace info --bogus x
expect 2 "$EMM" trace export x.emt
expect 2 "$EMM" trace export --din
expect 2 "$EMM" trace export --din x.emt -o
expect 2 "$EMM" trace import --din x.din
expect 2 "$EMM" trace import x.din -o y.emt
expect 2 "$EMM" trace import --din x.din -o y.emt --bytes 0
expect 2 "$EMM" trace import --din x.din -o y.emt --bytes lots
grep -q "Try 'emm trace import --help'" "$DIR/err" || fail "usage error without a hint"

# A din file with comments, 0x prefixes, upper case, tabs, blank lines and
# instruction fetches.
cat >"$DIR/a.din" <<'DIN'
0 1000
1 0x1004 some comment
2 400000
0	7FFFFFFFFFF1

  1 3
0 0
1 ffffffffffffffff
DIN
expect 0 "$EMM" trace import --din "$DIR/a.din" -o "$DIR/a.emt"
grep -q "6 accesses (1 instruction fetches skipped)" "$DIR/out" || fail "import summary: $(cat "$DIR/out")"
expect 0 "$EMM" trace info --verify "$DIR/a.emt"
grep -q "accesses:    6 (3 reads, 3 writes)" "$DIR/out" || fail "info: $(cat "$DIR/out")"
grep -q "verify:      ok" "$DIR/out" || fail "verify not ok"
grep -q "geometry:    none" "$DIR/out" || fail "info geometry"
expect 0 "$EMM" trace export --din "$DIR/a.emt"
printf '0 1000\n1 1004\n0 7ffffffffff1\n1 3\n0 0\n1 ffffffffffffffff\n' >"$DIR/a.want"
cmp -s "$DIR/out" "$DIR/a.want" || fail "export differs: $(cat "$DIR/out")"

# export -> import -> export gives identical text, compressed or not, over
# several blocks (200,000 references with local and far moves).
awk 'BEGIN { a = 4096; for (i = 0; i < 200000; i++) {
        r = (i * 7919) % 1000; if (r < 5) a += 1048576 * r; else a += (r % 64) - 32;
        if (a < 0) a = -a; printf "%d %x\n", (i % 3 == 0), a } }' >"$DIR/b.din"
expect 0 "$EMM" trace import --din "$DIR/b.din" -o "$DIR/b.emt"
expect 0 "$EMM" trace export --din "$DIR/b.emt" -o "$DIR/b1.din"
cmp -s "$DIR/b.din" "$DIR/b1.din" || fail "canonical din changed on import/export"
expect 0 "$EMM" trace import --din "$DIR/b1.din" -o "$DIR/b2.emt" --compress
expect 0 "$EMM" trace info "$DIR/b2.emt"
grep -q "compressed:  yes" "$DIR/out" || fail "not compressed"
grep -q "blocks:      4" "$DIR/out" || fail "expected 4 blocks: $(cat "$DIR/out")"
expect 0 "$EMM" trace export --din "$DIR/b2.emt" -o "$DIR/b2.din"
cmp -s "$DIR/b1.din" "$DIR/b2.din" || fail "export -> import -> export differs"
# stdin input
expect 0 sh -c "\"$EMM\" trace import --din - -o \"$DIR/c.emt\" <\"$DIR/a.din\""
expect 0 "$EMM" trace export --din "$DIR/c.emt"
cmp -s "$DIR/out" "$DIR/a.want" || fail "stdin import differs"

# Malformed din: exit 1, 'FILE:LINE: problem', no output left behind.
i=0
for bad in '5 1000' '0' 'x 1000' '0 zz' '0 1000zz' '1 10000000000000000' '0x 10'; do
    i=$((i + 1))
    printf '0 10\n1 20\n%s\n' "$bad" >"$DIR/bad$i.din"
    expect 1 "$EMM" trace import --din "$DIR/bad$i.din" -o "$DIR/bad$i.emt"
    grep -q "^emm: $DIR/bad$i.din:3: " "$DIR/err" || fail "no FILE:LINE for '$bad': $(cat "$DIR/err")"
    [ "$(wc -l <"$DIR/err")" -eq 1 ] || fail "more than one line for '$bad'"
    ls "$DIR" | grep -q "bad$i.emt" && fail "output left behind for '$bad'"
done
expect 1 "$EMM" trace import --din "$DIR/missing.din" -o "$DIR/m.emt"
[ -e "$DIR/m.emt" ] && fail "output for a missing input"

# Damaged traces: exit 1, one line naming the byte offset.
expect 1 "$EMM" trace info "$DIR/a.din"
grep -q "byte 0: not an emm trace" "$DIR/err" || fail "bad magic: $(cat "$DIR/err")"
size=$(wc -c <"$DIR/b.emt")
head -c $((size - 100)) "$DIR/b.emt" >"$DIR/cut.emt"
expect 0 "$EMM" trace info "$DIR/cut.emt"
expect 1 "$EMM" trace info --verify "$DIR/cut.emt"
grep -q "byte [0-9]*: truncated in block 3 payload" "$DIR/err" || fail "truncated: $(cat "$DIR/err")"
expect 1 "$EMM" trace export --din "$DIR/cut.emt" -o "$DIR/cut.din"
[ -e "$DIR/cut.din" ] && fail "export of a damaged trace left its output"
cp "$DIR/b.emt" "$DIR/flip.emt"
printf '\377' | dd of="$DIR/flip.emt" bs=1 seek=5000 conv=notrunc 2>/dev/null
expect 1 "$EMM" trace info --verify "$DIR/flip.emt"
grep -q "payload checksum mismatch" "$DIR/err" || fail "flip: $(cat "$DIR/err")"

[ "$fails" -eq 0 ] && echo "cli_trace: all checks passed"
exit $([ "$fails" -eq 0 ] && echo 0 || echo 1)
