# A report whenever --report is given, also when nothing was simulated, with
# the reason; and --verbose never loses a line the quiet run prints. Each
# case runs the program natively, then under emm run (or plain LD_PRELOAD)
# with --report, then again with --verbose; stdout and exit status are the
# native run's each time, the report is read back with python3
# (coverage.simulated "nothing", coverage.reason matching the case, no
# results), and every line of the default run's stderr is in the verbose
# run's (addresses and numbers aside).
# A wrapper that simulates nothing (a shell, which the shim enters too)
# leaves the report of the program it ran as it is.
#   sh nothing.sh SHIM WORKDIR EMM UNTAGGED REGION_GROWING REGION_GROWING_SANCOV
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY EMM_CAPTURE EMM_REPORT EMM_TAG EMM_LOG
EMM=$1 UNTAGGED=$2 REGION=$3 REGION_SANCOV=$4
"$EMM" mesh gen --faces 60 --seed 2 -o "$WORK/tiny.off" >/dev/null || fail "mesh gen"

# norm FILE: the lines with addresses and numbers made alike.
norm() { sed -E 's/0x[0-9a-f]+/ADDR/g; s/[0-9][0-9,.]*/N/g' "$1"; }

# check NAME REASON_REGEX SAYS_REGEX HOW -- COMMAND...: the report's reason
# matches REASON_REGEX and a line of the summary SAYS_REGEX; HOW is plain
# (COMMAND under plain LD_PRELOAD with EMM_REPORT) or emm run's options.
check() {
  name=$1 reason=$2 says=$3 how=$4; shift 5
  report=$WORK/$name.json
  env -u LD_PRELOAD "$@" > "$WORK/$name.native.out" 2>/dev/null; native_rc=$?
  for v in quiet verbose; do
    rm -f "$report"
    opt=; [ $v = verbose ] && opt=--verbose
    if [ "$how" = plain ]; then
      log=1; [ $v = verbose ] && log=2
      EMM_REPORT=$report EMM_LOG=$log LD_PRELOAD="$SHIM" "$@" \
        > "$WORK/$name.$v.out" 2> "$WORK/$name.$v.err"
    else
      "$EMM" run $opt $how --report "$report" -- "$@" > "$WORK/$name.$v.out" 2> "$WORK/$name.$v.err"
    fi
    rc=$?
    [ $rc = $native_rc ] || { cat "$WORK/$name.$v.err" >&2; fail "$name ($v): exit status $rc, natively $native_rc"; }
    cmp -s "$WORK/$name.native.out" "$WORK/$name.$v.out" || fail "$name ($v): stdout differs"
    [ -s "$report" ] || { cat "$WORK/$name.$v.err" >&2; fail "$name ($v): no report"; }
    python3 - "$report" "$reason" <<'PY' || { cat "$WORK/$name.$v.err" >&2; fail "$name ($v): the report"; }
import json, re, sys
r = json.load(open(sys.argv[1]))
c = r["coverage"]
assert c["simulated"] == "nothing", c
assert re.search(sys.argv[2], c["reason"]), (sys.argv[2], c["reason"])
assert r["results"] == [] and r["strategy"] is None and r["accesses"] == 0, r["results"]
print("%s: nothing simulated: %s" % (r["program"], c["reason"]))
PY
  done
  # The reason is on the summary too, and every quiet line is in the
  # verbose run's stderr.
  grep -Eq -- "$says" "$WORK/$name.quiet.err" || { cat "$WORK/$name.quiet.err" >&2; fail "$name: stderr does not say why"; }
  norm "$WORK/$name.quiet.err" > "$WORK/$name.quiet.norm"
  norm "$WORK/$name.verbose.err" > "$WORK/$name.verbose.norm"
  missing=$(grep -vxF -f "$WORK/$name.verbose.norm" "$WORK/$name.quiet.norm")
  [ -z "$missing" ] || { cat "$WORK/$name.verbose.err" >&2; fail "$name: --verbose lost: $missing"; }
}

# No array tagged: a program that makes no emm_tag_* call, without rules.
# (A rule's block refused as no mesh: silent.sh and shapes.sh.)
why='no vertex array was tagged'
check untagged "$why" "^emm: test_shim_untagged: no simulation: $why" --capture=fault -- "$UNTAGGED"
# The arrays tagged, none of their accesses seen: the fault capture sees an
# array tagged after its allocation only on the pages wholly inside it, and
# a 60-face mesh's arrays have none.
why='no access to the tagged arrays was seen'
check unseen "$why" "^emm: region_growing: no simulation: $why" --capture=fault -- "$REGION" "$WORK/tiny.off"
# List mode lists, and simulates nothing.
check listed 'list mode' '^emm: test_shim_untagged: 2 candidate array sites' --list-sites -- "$UNTAGGED"
# The shim steps aside before a session starts (plain LD_PRELOAD asking for
# the valgrind capture, which only emm run can start).
EMM_CAPTURE=valgrind; export EMM_CAPTURE
why="is not running under emm's Valgrind tool"
check stepped_aside "$why" "^emm: EMM_CAPTURE=valgrind: .*$why" plain -- "$UNTAGGED"
unset EMM_CAPTURE

# The wrapper's session ends last, with nothing tagged: the program's
# report, written since the wrapper started, stays.
rm -f "$WORK/wrapped.json"
# (the "; true" keeps the shell from exec'ing the program in its place)
"$EMM" run --capture sancov --report "$WORK/wrapped.json" -- sh -c '"$0" "$1"; true' \
  "$REGION_SANCOV" "$WORK/tiny.off" > "$WORK/wrapped.out" 2> "$WORK/wrapped.err" ||
  { cat "$WORK/wrapped.err" >&2; fail "wrapped: run failed"; }
grep -q '^emm: sh: no simulation: no vertex array was tagged' "$WORK/wrapped.err" ||
  { cat "$WORK/wrapped.err" >&2; fail "wrapped: the wrapper's session did not end with nothing simulated"; }
python3 - "$WORK/wrapped.json" <<'PY' || fail "wrapped: the wrapper's report replaced the program's"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["coverage"]["simulated"] == "run" and r["strategy"], (r["program"], r["coverage"])
print("wrapped: the report is %s's, %s" % (r["program"], r["strategy"]))
PY
# A run that simulates: --verbose keeps every line of the default summary.
"$EMM" run --capture sancov -- "$REGION_SANCOV" "$WORK/tiny.off" >/dev/null 2> "$WORK/ran.quiet.err" &&
  "$EMM" run --verbose --capture sancov -- "$REGION_SANCOV" "$WORK/tiny.off" >/dev/null \
    2> "$WORK/ran.verbose.err" || fail "ran: run failed"
grep -q '^emm: answer: ' "$WORK/ran.quiet.err" || fail "ran: no answer"
norm "$WORK/ran.quiet.err" > "$WORK/ran.quiet.norm"
norm "$WORK/ran.verbose.err" > "$WORK/ran.verbose.norm"
missing=$(grep -vxF -f "$WORK/ran.verbose.norm" "$WORK/ran.quiet.norm")
[ -z "$missing" ] || { cat "$WORK/ran.verbose.err" >&2; fail "ran: --verbose lost: $missing"; }
echo "nothing: ok"
