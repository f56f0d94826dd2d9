# Every EMM_* variable with malformed values (empty, garbage, negative,
# overflowing, unknown strategy, unusable path): exactly one stderr line
# naming the variable and its value, and the program's stdout and exit status
# unchanged. Then EMM_STRICT=1 turns a bad value into exit status 125.
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
big=99999999999999999999999
mkdir -p "$WORK/adir"
n=0
check() { # VAR VALUE
  var=$1; val=$2; n=$((n + 1))
  env -u LD_PRELOAD "$var=$val" $PROG > "$WORK/native.out" 2> /dev/null; nrc=$?
  env LD_PRELOAD="$SHIM" "$var=$val" $PROG > "$WORK/shim.out" 2> "$WORK/shim.err"; src=$?
  [ "$nrc" = "$src" ] || fail "$var='$val': exit status $src under the shim, $nrc natively"
  cmp -s "$WORK/native.out" "$WORK/shim.out" || fail "$var='$val': stdout differs"
  lines=$(wc -l < "$WORK/shim.err")
  [ "$lines" = 1 ] || { cat "$WORK/shim.err" >&2; fail "$var='$val': expected one stderr line, got $lines"; }
  grep -q "^emm: $var='" "$WORK/shim.err" || { cat "$WORK/shim.err" >&2; fail "$var='$val': the line does not name the variable"; }
}
PROG="$*"
for v in '' garbage 'vertices:stride=-1,xyz=8:f64' "vertices:stride=$big,xyz=8:f64" \
         'edges:stride=8' 'vertices:site=f,stride=8,xyz=4:f64' 'vertices:stride=32' \
         'triangles:stride=16,vidx=4:f64' 'vertices:nth=0,stride=32,xyz=8:f64'; do
  check EMM_TAG "$v"; done
for v in '' bogus -1 SANCOV; do check EMM_CAPTURE "$v"; done
for v in '' abc -5 "$big" 0 5x it 0it 1.5; do check EMM_PROFILE "$v"; done
for v in '' fastest 'grid+naive@-1' 'tiles+magic' "grid+naive@$big"; do check EMM_STRATEGY "$v"; done
for v in '' some -1; do check EMM_COMPARE "$v"; done
for v in '' /nonexistent/machine.txt "$WORK/adir"; do check EMM_MACHINE "$v"; done
for v in '' /nonexistent/table.txt "$WORK/adir"; do check EMM_TABLE "$v"; done
for var in EMM_REPORT EMM_PROFILE_DUMP EMM_TRACE; do
  for v in '' /nonexistent/dir/out "$WORK/adir" "$WORK/adir/"; do check $var "$v"; done
done
for v in '' 3 loud -1; do check EMM_LOG "$v"; done
for v in '' 2 yes -1; do check EMM_STRICT "$v"; done
# An unwritable directory (root can write anywhere, so only as another user).
if [ "$(id -u)" != 0 ]; then
  mkdir -p "$WORK/ro" && chmod 500 "$WORK/ro"
  check EMM_REPORT "$WORK/ro/r.json"
fi

# EMM_STRICT=1: the program does not run, exit status 125, one line.
env LD_PRELOAD="$SHIM" EMM_STRICT=1 EMM_PROFILE=abc $PROG > "$WORK/strict.out" 2> "$WORK/strict.err"
rc=$?
[ "$rc" = 125 ] || fail "EMM_STRICT=1: exit status $rc, expected 125"
[ -s "$WORK/strict.out" ] && fail "EMM_STRICT=1: the program ran"
[ "$(wc -l < "$WORK/strict.err")" = 1 ] || fail "EMM_STRICT=1: expected one stderr line"
grep -q "^emm: EMM_PROFILE='abc': .*EMM_STRICT=1" "$WORK/strict.err" || fail "EMM_STRICT=1: unclear message"
echo "env_errors: ok ($n bad values)"
