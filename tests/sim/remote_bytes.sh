#!/bin/sh
# remote.bytes (docs/machine.md): a mesh whose arrays take more than the
# machine's remote store is simulated as if it fitted, and emm says so in
# one line naming both sizes and the key, in `emm replay` and in `emm run`'s
# summary; a mesh that fits gets no such line, nor does --quiet.
# usage: remote_bytes.sh EMM WORKDIR PROGRAM
#   PROGRAM: region_growing (its sancov build when there is one)
set -u
EMM=$1 W=$2 PROG=$3
rm -rf "$W" && mkdir -p "$W" || exit 1
fail=0
no() { echo "FAIL: $*"; fail=1; }

"$EMM" mesh gen --faces 2000 --seed 3 -o "$W/m.off" >/dev/null || exit 1
"$EMM" trace synth --mesh "$W/m.off" --pattern region --visits 200 -o "$W/t.emmt" >/dev/null || exit 1
# The trace's arrays: count x record size, summed (vertices 80 B, triangles 28 B).
bytes=$("$EMM" trace info "$W/t.emmt" |
  awk '/record [0-9]+ B +count/ { for (i = 1; i <= NF; i++) { if ($i == "record") r = $(i + 1); if ($i == "count") c = $(i + 1) } s += r * c } END { print s }')
[ -n "$bytes" ] && [ "$bytes" -gt 65536 ] || { echo "FAIL: the mesh's arrays take '$bytes' bytes"; exit 1; }
grouped=$(echo "$bytes" | sed -e ':a' -e 's/\([0-9]\)\([0-9]\{3\}\)\($\|,\)/\1,\2\3/' -e 'ta')
line="the mesh's arrays take $grouped bytes, more than the machine's remote store of 65,536 (remote.bytes = 64K): simulated as if they fitted"

"$EMM" replay "$W/t.emmt" --strategy direct --set remote.bytes=64K >"$W/out" 2>"$W/err" || no "replay failed"
[ "$(cat "$W/err")" = "emm replay: $W/t.emmt: $line" ] || no "replay over remote.bytes: '$(cat "$W/err")'"
"$EMM" replay "$W/t.emmt" --strategy direct >"$W/out" 2>"$W/err" || no "replay failed"
[ -s "$W/err" ] && no "replay within the default 6M said: '$(cat "$W/err")'"
"$EMM" replay "$W/t.emmt" --strategy direct --set remote.bytes=64K --quiet >"$W/out" 2>"$W/err" || no "replay failed"
[ -s "$W/err" ] && no "replay --quiet said: '$(cat "$W/err")'"

# emm run: the summary's line, from a machine file.
printf 'remote.bytes = 64K\n' >"$W/small.ini"
"$EMM" run --machine "$W/small.ini" --compare none -- "$PROG" "$W/m.off" >/dev/null 2>"$W/run.err" ||
  { cat "$W/run.err"; no "emm run failed"; }
grep -q "^emm:   the mesh's arrays take [0-9,]* bytes, more than the machine's remote store of 65,536 (remote.bytes = 64K): simulated as if they fitted\$" "$W/run.err" ||
  { cat "$W/run.err"; no "emm run over remote.bytes: no line"; }
"$EMM" run --compare none -- "$PROG" "$W/m.off" >/dev/null 2>"$W/run.err" || no "emm run failed"
grep -q "remote store" "$W/run.err" && { cat "$W/run.err"; no "emm run within the default said something"; }
grep -q "^emm: answer: " "$W/run.err" || { cat "$W/run.err"; no "emm run: no answer"; }
[ $fail = 0 ] && echo "remote_bytes: ok"
exit $fail
