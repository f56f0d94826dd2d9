#!/bin/sh
# One OpenMesh app, natively and under emm run:
#   sh app.sh EMM CAPTURE RULES WORK APP ARGS...
# ARGS name the output file as @OUT@ (here out.native / out.emm). The
# output files must be byte-identical and the exit status the same; the
# report must exist with a pattern and a strategy, covering the whole run
# under valgrind and the window under fault. (stdout is not compared: the
# apps print their timings.)
set -u
EMM=$1 CAPTURE=$2 RULES=$3 WORK=$4
shift 4
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "$WORK" && mkdir -p "$WORK" || fail "cannot make $WORK"
APP=$1; shift
args() { for a in "$@"; do printf '%s\n' "$a" | sed "s|@OUT@|$WORK/$which|g"; done; }
which=out.native
set -f
IFS='
'
native_args=$(args "$@")
which=out.emm
emm_args=$(args "$@")
# shellcheck disable=SC2086
env -u LD_PRELOAD "$APP" $native_args > "$WORK/native.log" 2>&1; native_rc=$?
# shellcheck disable=SC2086
"$EMM" run --capture "$CAPTURE" --tag "$RULES" --report "$WORK/report.json" -- "$APP" $emm_args \
  > "$WORK/emm.log" 2> "$WORK/emm.err"; rc=$?
unset IFS
set +f
[ "$rc" = "$native_rc" ] || { cat "$WORK/emm.err" >&2; fail "exit status $rc under emm run, $native_rc natively"; }
n=0
for f in "$WORK"/out.native*; do
  [ -e "$f" ] || continue
  g=$WORK/out.emm${f#"$WORK"/out.native}
  cmp "$f" "$g" || fail "$(basename "$g") differs from the native run's $(basename "$f")"
  n=$((n + 1))
done
[ $n -gt 0 ] || fail "the native run wrote no output file"
report() { python3 -c "import json; r = json.load(open('$WORK/report.json')); print($1)"; }
[ -s "$WORK/report.json" ] || { cat "$WORK/emm.err" >&2; fail "no report"; }
want=window
[ "$CAPTURE" = valgrind ] && want=run
[ "$(report "r['coverage']['simulated']")" = "$want" ] || fail "coverage.simulated is not '$want'"
[ "$(report "r['pattern'] is not None")" = True ] || fail "no pattern"
[ "$(report "r['strategy'] is not None")" = True ] || fail "no strategy decided"
grep '^emm: ' "$WORK/emm.err" | head -3
echo "$(basename "$APP") under $CAPTURE: $n output file(s) identical, $(report "r['coverage']['accesses']") accesses simulated ($(report "r['coverage']['simulated']")), pattern $(report "r['pattern']"), $(report "r['strategy']")"
