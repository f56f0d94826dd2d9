# A FIFO nobody writes to, named as an input of emm's (EMM_TABLE,
# EMM_MACHINE, --table, --machine, a trace, a mesh), must not block the
# program or emm: open() on it would wait for a writer for ever, and under
# the shim that wait is in the host program's constructor. The shim says so
# in one line naming the input and steps aside, the program's stdout and
# exit status are the native run's, within 5 s; emm's commands, emm run
# included, refuse it with one line.
#   sh fifo.sh SHIM WORK EMM VALGRIND(0|1) PROGRAM...
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
EMM=$1 VG=$2; shift 2
fifo="$WORK/fifo.off"
mkfifo "$fifo" || fail "cannot make a FIFO" # .off: a mesh too

# within NAME SECONDS COMMAND...: runs COMMAND, fails when it took longer.
within() {
  _name=$1 _max=$2; shift 2
  _t0=$(date +%s)
  "$@"
  _rc=$?
  _secs=$(( $(date +%s) - _t0 ))
  [ "$_secs" -le "$_max" ] || fail "$_name: took ${_secs}s (at most ${_max}s)"
  return $_rc
}

# one_line NAME FILE REGEX: FILE holds exactly one line, matching REGEX.
one_line() {
  [ "$(wc -l < "$2")" = 1 ] && grep -Eq -- "$3" "$2" || { cat "$2" >&2; fail "$1: expected one line matching '$3'"; }
}

# The cases that wait for the bound run side by side (each with its own
# files and its own 5 s limit): the test takes one bound, not six.
pids=
# Plain LD_PRELOAD (the auto capture: fault for this program).
for var in EMM_TABLE EMM_MACHINE; do
  (
    export "$var=$fifo"
    within "LD_PRELOAD $var" 5 run_both "$var" "$@"
    one_line "LD_PRELOAD $var" "$WORK/$var.shim.err" "^emm: $var: $fifo: nothing to read for 2 s"
  ) &
  pids="$pids $!"
done

# emm run under each capture: the option is checked before the program
# starts, so emm refuses the run in one line (status 2), as for any bad option.
# (The check is the same under every capture: one option each.)
cases="fault:--table fault:--machine"
[ "$VG" = 1 ] && cases="fault:--table valgrind:--machine"
for c in $cases; do
  (
    capture=${c%%:*} opt=${c#*:}
    name="run-$capture$opt"
    within "$name" 5 "$EMM" run --capture "$capture" "$opt" "$fifo" -- "$@" \
      > "$WORK/$name.out" 2> "$WORK/$name.err"
    rc=$?
    [ "$rc" = 2 ] || { cat "$WORK/$name.err" >&2; fail "$name: exit status $rc, expected 2"; }
    one_line "$name" "$WORK/$name.err" "^emm run: $opt: $fifo: nothing to read for 2 s"
  ) &
  pids="$pids $!"
done
(
  within mesh 5 "$EMM" mesh info "$fifo" > /dev/null 2> "$WORK/mesh.err" && fail "mesh info of a FIFO succeeded"
  one_line mesh "$WORK/mesh.err" "$fifo: nothing to read for 2 s"
) &
pids="$pids $!"
failed=0
for p in $pids; do wait "$p" || failed=1; done
[ $failed = 0 ] || fail "a FIFO case failed (above)"

# emm's own commands: a trace needs a regular file (refused at once); a mesh
# may come from a pipe (refused after the bound, above).
within replay 5 "$EMM" replay "$fifo" > /dev/null 2> "$WORK/replay.err" && fail "replay of a FIFO succeeded"
one_line replay "$WORK/replay.err" "$fifo: is a pipe or FIFO, not a trace"
# A pipe with a writer is still read: a machine file from a pipe.
echo "dma.channels = 1" | within machine-pipe 5 "$EMM" machine show --machine /dev/stdin \
  > "$WORK/machine.out" 2> "$WORK/machine.err" || { cat "$WORK/machine.err" >&2; fail "a machine file from a pipe was refused"; }
echo "fifo: ok"
