# The outputs are whole or absent however the program ends (docs/design.md "The shim and
# the session", "Output"): SIGTERM and SIGINT mid-run (also while the program is
# inside malloc), _exit, a report directory that is read-only from the start
# or becomes so mid-run, and a full disk. Each time: the exit status is the
# one of the native run, and a report that exists is complete JSON with the
# session's keys, and no temporary file is left behind.
# Usage: sh report_whole.sh SHIM WORKDIR LONGRUN (tests/shim/longrun.c)
. "$(dirname "$0")/lib.sh"
PROG=$1
EMM_PROFILE=2000; EMM_COMPARE=baselines; EMM_LOG=1; export EMM_PROFILE EMM_COMPARE EMM_LOG
unset EMM_REPORT EMM_TRACE EMM_PROFILE_DUMP EMM_TAG
# The programs get default SIGINT/SIGTERM actions (an asynchronous command of
# a non-interactive shell starts with SIGINT ignored).
if env --default-signal=INT true 2>/dev/null; then START="env --default-signal=INT,TERM"
else START=env; fi
reports=0 absent=0

# check_outputs DIR: every file in DIR is whole; counts reports and absences.
# With Python, a report is queued: check_reports reads the queued reports
# in one Python process, not one each.
check_outputs() {
  ls -a "$1" | grep -q '\.tmp' && { ls -la "$1" >&2; fail "a temporary file is left in $1"; }
  if [ ! -e "$1/r.json" ]; then absent=$((absent + 1)); return 0; fi
  reports=$((reports + 1))
  if command -v python3 >/dev/null 2>&1; then
    echo "$1/r.json" >> "$WORK/reports.queued"
  else
    tail -c 2 "$1/r.json" | grep -q '}' || fail "$1/r.json is truncated"
    for k in emm_report results pattern strategy decision capture window; do
      grep -q "\"$k\":" "$1/r.json" || fail "$1/r.json has no \"$k\""; done
  fi
}

# check_reports: each queued report is complete JSON with the session's keys.
check_reports() {
  [ -s "$WORK/reports.queued" ] || return 0
  python3 - "$WORK/reports.queued" <<'PY' || fail "a report is not whole"
import json, sys
for path in open(sys.argv[1]).read().split("\n"):
    if not path:
        continue
    try:
        d = json.load(open(path))
        for k in ("emm_report", "accesses", "machine", "results", "program", "capture",
                  "pattern", "strategy", "decision", "window"):
            assert k in d, "no key " + k
        assert d["accesses"] > 0 and len(d["results"]) == 2, d["results"]
        for r in d["results"]:
            c = r["cycles"]
            assert r["accesses"] == d["accesses"] and c["total"] > 0, r
            assert c["total"] == sum(v for k, v in c.items() if k != "total"), r
    except Exception as e:
        sys.exit("FAIL: %s is not a whole report: %r" % (path, e))
PY
  : > "$WORK/reports.queued"
}

# start NAME DIR MODE: runs PROG MODE in the background under the shim with
# its report in DIR, and waits for its "ready" line.
start() {
  out=$WORK/$1.out
  : > "$out"
  EMM_REPORT=$2/r.json LD_PRELOAD="$SHIM" $START "$PROG" $3 > "$out" 2> "$WORK/$1.err" &
  pid=$!
  i=0
  until grep -q ready "$out"; do
    kill -0 $pid 2>/dev/null || { cat "$WORK/$1.err" >&2; fail "$1: the program ended early"; }
    i=$((i + 1)); [ $i -lt 1200 ] || { kill -KILL $pid; fail "$1: no 'ready' in 120 s"; }
    sleep 0.1
  done
}

# stop NAME SIG STATUS: sends SIG, waits (a hang fails) and checks the status.
# It looks every 20 ms: the program ends a fraction of a second after the
# signal, and the test stops a program 16 times.
stop() {
  kill -"$2" $pid
  i=0
  while kill -0 $pid 2>/dev/null; do
    i=$((i + 1))
    [ $i -lt 3000 ] || { kill -KILL $pid; fail "$1: still running 60 s after SIG$2 (a hang)"; }
    sleep 0.02
  done
  wait $pid; rc=$?
  [ "$rc" = "$3" ] || { cat "$WORK/$1.err" >&2; fail "$1: exit status $rc after SIG$2, expected $3"; }
}

# The native runs: what the signals do without the shim. The output is
# emptied before each start, as start() does: else the second run could
# find the first one's "ready" and be signalled before it runs the program
# (the shell's child ignores SIGINT until env resets it: a 60 s "hang").
: > "$WORK/native.out"
env -u LD_PRELOAD $START "$PROG" loop > "$WORK/native.out" 2>&1 &
pid=$!
until grep -q ready "$WORK/native.out"; do sleep 0.05; done
stop native TERM 143
: > "$WORK/native.out"
env -u LD_PRELOAD $START "$PROG" loop > "$WORK/native.out" 2>&1 &
pid=$!
until grep -q ready "$WORK/native.out"; do sleep 0.05; done
stop native INT 130

# Signals mid-run, several times each (where the signal lands varies).
for round in 1 2 3; do
  for sig in TERM:143 INT:130; do
    for mode in loop loop-alloc; do
      name=$mode-${sig%:*}-$round
      mkdir -p "$WORK/$name"
      start $name "$WORK/$name" $mode
      stop $name ${sig%:*} ${sig#*:}
      check_outputs "$WORK/$name"
    done
  done
done
check_reports
[ $reports -gt 0 ] || fail "no signal run wrote a report ($absent absent)"
echo "signals: $reports reports whole, $absent absent"

# _exit: the status and output of the native run, and a whole report.
mkdir -p "$WORK/exit"
export EMM_REPORT=$WORK/exit/r.json
run_both exit "$PROG" exit 300000
unset EMM_REPORT
[ -e "$WORK/exit/r.json" ] || { cat "$WORK/exit.shim.err" >&2; fail "_exit: no report"; }
check_outputs "$WORK/exit"
check_reports
echo "_exit: ok"

# A read-only directory. Root writes anywhere, so as root it is a read-only
# mount; elsewhere the directory's mode.
ro_dir=$WORK/ro
mkdir -p "$ro_dir"
make_ro() {
  if [ "$(id -u)" = 0 ]; then
    mountpoint -q "$ro_dir" || mount -t tmpfs -o size=1m tmpfs "$ro_dir" 2>/dev/null || return 1
    mount -o remount,ro "$ro_dir" 2>/dev/null
  else
    chmod 500 "$ro_dir"
  fi
}
make_rw() {
  if [ "$(id -u)" = 0 ]; then mount -o remount,rw "$ro_dir" 2>/dev/null; else chmod 700 "$ro_dir"; fi
}
cleanup() { mountpoint -q "$ro_dir" 2>/dev/null && umount "$ro_dir"
            mountpoint -q "$WORK/full" 2>/dev/null && umount "$WORK/full"; }
trap cleanup EXIT
if make_ro; then
  # From the start: one line, the program untouched.
  export EMM_REPORT=$ro_dir/r.json
  run_both ro-start "$PROG" exit 50000
  unset EMM_REPORT
  expect_err ro-start "^emm: EMM_REPORT=.*not writable"
  [ "$(wc -l < "$WORK/ro-start.shim.err")" = 1 ] || fail "ro-start: more than one stderr line"
  # Mid-run: the report is absent, and stderr says why.
  make_rw || fail "cannot make $ro_dir writable again"
  start ro-mid "$ro_dir" loop
  make_ro || fail "cannot make $ro_dir read-only"
  stop ro-mid TERM 143
  [ -e "$ro_dir/r.json" ] && fail "ro-mid: a report in a read-only directory"
  check_outputs "$ro_dir"
  grep -q "^emm: EMM_REPORT: $ro_dir/r.json: " "$WORK/ro-mid.err" ||
    { cat "$WORK/ro-mid.err" >&2; fail "ro-mid: no line says the report was not written"; }
  echo "read-only directory: ok"
else
  echo "note: cannot make a read-only directory here; that part is skipped"
fi

# A full disk (a small tmpfs, filled mid-run): the report, the trace and the
# profile CSV are absent, not truncated.
full=$WORK/full
mkdir -p "$full"
if [ "$(id -u)" = 0 ] && mount -t tmpfs -o size=256k tmpfs "$full" 2>/dev/null; then
  export EMM_TRACE=$full/t.emmt EMM_PROFILE_DUMP=$full/p.csv
  start full "$full" loop
  unset EMM_TRACE EMM_PROFILE_DUMP
  dd if=/dev/zero of="$full/filler" bs=4k 2>/dev/null
  stop full TERM 143
  rm -f "$full/filler"
  [ -e "$full/r.json" ] || [ -e "$full/t.emmt" ] || [ -e "$full/p.csv" ] &&
    { ls -la "$full" >&2; fail "full disk: an output was written"; }
  check_outputs "$full"
  grep -q "^emm: EMM_REPORT: $full/r.json: " "$WORK/full.err" ||
    { cat "$WORK/full.err" >&2; fail "full disk: no line says the report was not written"; }
  echo "full disk: ok"
else
  echo "note: cannot mount a small tmpfs here (needs root); the full-disk part is skipped"
fi
check_reports
echo "report_whole: ok"
