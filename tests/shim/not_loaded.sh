# A program the shim cannot load into runs untouched, with its own output
# and exit status, and `emm run` says so in one line (issue 25: a static
# binary was silently not analysed): a statically linked program under the
# preloading captures, --list-sites and the valgrind capture, and a
# set-user-ID copy of a dynamic one when the system honours the bit. A
# program the shim did load gets no such line; --quiet says nothing.
#   sh not_loaded.sh SHIM WORKDIR EMM STATIC DYNAMIC NEEDS_LIB
. "$(dirname "$0")/lib.sh"
EMM=$1 STATIC=$2 DYNAMIC=$3 NEEDS_LIB=$4
# check NAME PATTERN EMM_RUN_ARGS...: status 3, stdout as natively, and
# exactly one line of emm run, matching PATTERN ("" for none).
check() {
  name=$1 pattern=$2; shift 2
  "$EMM" run "$@" > "$WORK/$name.out" 2> "$WORK/$name.err"; rc=$?
  [ $rc = 3 ] || { cat "$WORK/$name.err" >&2; fail "$name: exit status $rc, not 3"; }
  grep -q '^uid ' "$WORK/$name.out" || fail "$name: the program's output is missing"
  n=$(grep -c '^emm: run: ' "$WORK/$name.err")
  if [ -z "$pattern" ]; then
    [ "$n" = 0 ] || { cat "$WORK/$name.err" >&2; fail "$name: emm run said something"; }
  else
    [ "$n" = 1 ] || { cat "$WORK/$name.err" >&2; fail "$name: $n lines from emm run, not 1"; }
    grep -Eq -- "$pattern" "$WORK/$name.err" || { cat "$WORK/$name.err" >&2; fail "$name: not '$pattern'"; }
    [ "$(wc -l < "$WORK/$name.err")" = 1 ] || { cat "$WORK/$name.err" >&2; fail "$name: more than one line"; }
  fi
  cat "$WORK/$name.err"
}
STATIC_LINE="^emm: run: $STATIC ran without emm, nothing captured: it is statically linked"
for capture in api fault; do
  check static-$capture "$STATIC_LINE" --capture $capture -- "$STATIC"
done
check static-list "$STATIC_LINE" --list-sites -- "$STATIC"
check static-quiet "" --quiet --capture api -- "$STATIC"
if "$EMM" run --capture valgrind -- true 2>/dev/null; then
  check static-valgrind "$STATIC_LINE" --capture valgrind -- "$STATIC"
fi
# The dynamic build: the shim loads, and the session's own line (nothing
# tagged) is all that is said.
check dynamic "" --capture api -- "$DYNAMIC"
grep -q "^emm: $(basename "$DYNAMIC"): no simulation" "$WORK/dynamic.err" || fail "dynamic: no summary from the shim"

# Set-user-ID to another user: only root can make one, and a nosuid mount
# ignores the bit (the native run's ids tell).
if [ "$(id -u)" = 0 ] && id nobody >/dev/null 2>&1; then
  cp "$DYNAMIC" "$WORK/setuid" && chown nobody "$WORK/setuid" && chmod 4755 "$WORK/setuid" || exit 1
  "$WORK/setuid" > "$WORK/setuid.native" 2>&1
  if grep -q "euid $(id -u nobody)\$" "$WORK/setuid.native"; then
    check setuid "^emm: run: $WORK/setuid ran without emm, nothing captured: it is set-user-ID" \
      --capture api -- "$WORK/setuid"
  else
    echo "set-user-ID: not honoured here (nosuid?): skipped"
  fi
fi
# A program the loader cannot start (a library it needs is not found): the
# loader's own message, then emm run's line saying so, and status 127.
"$EMM" run --capture api -- "$NEEDS_LIB" > "$WORK/needs.out" 2> "$WORK/needs.err"; rc=$?
cat "$WORK/needs.err"
[ $rc = 127 ] || fail "needs-lib: exit status $rc, not 127"
grep -q 'error while loading shared libraries' "$WORK/needs.err" || fail "needs-lib: no message from the loader"
[ "$(grep -c '^emm: ' "$WORK/needs.err")" = 1 ] || fail "needs-lib: not one line from emm"
grep -q "^emm: run: $NEEDS_LIB ran without emm, nothing captured: the dynamic loader could not start it (exit status 127" \
  "$WORK/needs.err" || fail "needs-lib: emm run's line does not say the loader could not start it"
echo "not_loaded: ok"
