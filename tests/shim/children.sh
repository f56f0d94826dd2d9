# Processes the program starts (issue 25): an exec'd tool that tags nothing
# (/bin/echo, /bin/true) prints no emm line — the program's own summary
# does, as before — and says what it is, in one line, only under --verbose; a helper, a
# symbolizer (here a copy of /bin/true named llvm-symbolizer-14), is not
# entered at all, not even under --verbose. Under a preloading capture
# (api) and, when it is built, the valgrind capture.
#   sh children.sh SHIM WORKDIR EMM FORKEXEC
. "$(dirname "$0")/lib.sh"
EMM=$1 FORKEXEC=$2
cp /bin/true "$WORK/llvm-symbolizer-14" || exit 1
captures=api
"$EMM" run --capture valgrind -- true 2>/dev/null && captures="api valgrind"
for capture in $captures; do
  # /bin/true too under api; under Valgrind, whose runs cost a second or
  # two each, /bin/echo stands for both.
  children="/bin/echo /bin/true"
  [ $capture = valgrind ] && children=/bin/echo
  for child in $children; do
    name=$capture-$(basename $child)
    "$EMM" run --capture $capture -- "$FORKEXEC" $child hi > "$WORK/$name.out" 2> "$WORK/$name.err" ||
      { cat "$WORK/$name.err" >&2; fail "$name: exit status $?"; }
    grep -q 'exec child: 0' "$WORK/$name.out" || fail "$name: the exec'd child failed"
    grep -q "^emm: $(basename $child)" "$WORK/$name.err" && { cat "$WORK/$name.err" >&2; fail "$name: the child printed an emm line"; }
    grep -q "^emm: $(basename "$FORKEXEC"): no simulation" "$WORK/$name.err" ||
      { cat "$WORK/$name.err" >&2; fail "$name: the program's own line is missing"; }
  done
  # --verbose: the child says in one line that the program started it, and
  # nothing more (the program's own verbose lines are all there).
  name=$capture-verbose
  "$EMM" run --verbose --capture $capture -- "$FORKEXEC" /bin/true > "$WORK/$name.out" 2> "$WORK/$name.err" ||
    fail "$name: exit status $?"
  grep -q "^emm: libemmshim.so in true (pid [0-9]*, started by the program), capture $capture: silent unless it tags an array\$" "$WORK/$name.err" ||
    { cat "$WORK/$name.err" >&2; fail "$name: no line from the child under --verbose"; }
  n=$(grep -c "true" "$WORK/$name.err")
  [ "$n" = 1 ] || { cat "$WORK/$name.err" >&2; fail "$name: $n lines name the child, not 1"; }
  n=$(grep -c "^emm:   EMM_STRICT=" "$WORK/$name.err")
  [ "$n" = 1 ] || { cat "$WORK/$name.err" >&2; fail "$name: $n settings dumps, not the program's one"; }
  n=$(grep -c "^emm: at exit: " "$WORK/$name.err")
  [ "$n" = 1 ] || { cat "$WORK/$name.err" >&2; fail "$name: $n 'at exit' lines, not the program's one"; }
  grep -q "^emm: libemmshim.so in $(basename "$FORKEXEC") (pid [0-9]*), capture" "$WORK/$name.err" ||
    { cat "$WORK/$name.err" >&2; fail "$name: the program's own verbose line is missing"; }
  # A symbolizer: not entered.
  name=$capture-helper
  "$EMM" run --verbose --capture $capture -- "$FORKEXEC" "$WORK/llvm-symbolizer-14" > "$WORK/$name.out" 2> "$WORK/$name.err" ||
    fail "$name: exit status $?"
  grep -q 'exec child: 0' "$WORK/$name.out" || fail "$name: the helper failed"
  grep -q 'llvm-symbolizer' "$WORK/$name.err" && { cat "$WORK/$name.err" >&2; fail "$name: the shim entered the helper"; }
  echo "$capture: ok"
done
echo "children: ok"
