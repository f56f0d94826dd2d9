#!/bin/sh
# One OpenMesh app under emm run, against its native run:
#   sh app.sh EMM CAPTURE RULES WORK NATIVE APP ARGS...
# ARGS name the output file as @OUT@. CAPTURE native runs APP natively in
# NATIVE (outputs out.native*, exit status in native.rc): the fixture that
# the valgrind and fault tests of one app and input share, as the app's
# native run is the same for both. Any other CAPTURE runs APP under emm run
# in WORK (outputs out.emm*): the output files must be byte-identical to
# NATIVE's and the exit status the same; the report must exist with a
# pattern and a strategy, covering the whole run under valgrind and the
# window under fault. (stdout is not compared: the apps print their
# timings.)
set -u
EMM=$1 CAPTURE=$2 RULES=$3 WORK=$4 NATIVE=$5
shift 5
fail() { echo "FAIL: $*" >&2; exit 1; }
[ "$CAPTURE" = native ] && WORK=$NATIVE
rm -rf "$WORK" && mkdir -p "$WORK" || fail "cannot make $WORK"
APP=$1; shift
args() { for a in "$@"; do printf '%s\n' "$a" | sed "s|@OUT@|$WORK/$which|g"; done; }
set -f
IFS='
'
if [ "$CAPTURE" = native ]; then
  which=out.native
  native_args=$(args "$@")
  # shellcheck disable=SC2086
  env -u LD_PRELOAD "$APP" $native_args > "$WORK/native.log" 2>&1
  echo $? > "$WORK/native.rc"
  echo "$(basename "$APP") natively: exit status $(cat "$WORK/native.rc")"
  exit 0
fi
which=out.emm
emm_args=$(args "$@")
# shellcheck disable=SC2086
"$EMM" run --capture "$CAPTURE" --tag "$RULES" --report "$WORK/report.json" -- "$APP" $emm_args \
  > "$WORK/emm.log" 2> "$WORK/emm.err"; rc=$?
unset IFS
set +f
[ -s "$NATIVE/native.rc" ] || fail "no native run in $NATIVE"
native_rc=$(cat "$NATIVE/native.rc")
[ "$rc" = "$native_rc" ] || { cat "$WORK/emm.err" >&2; fail "exit status $rc under emm run, $native_rc natively"; }
n=0
for f in "$NATIVE"/out.native*; do
  [ -e "$f" ] || continue
  g=$WORK/out.emm${f#"$NATIVE"/out.native}
  cmp "$f" "$g" || fail "$(basename "$g") differs from the native run's $(basename "$f")"
  n=$((n + 1))
done
[ $n -gt 0 ] || fail "the native run wrote no output file"
[ -s "$WORK/report.json" ] || { cat "$WORK/emm.err" >&2; fail "no report"; }
want=window
[ "$CAPTURE" = valgrind ] && want=run
# The report read once, by Python's own JSON parser: the checks, then the
# summary line's numbers.
summary=$(python3 - "$WORK/report.json" "$want" "$RULES" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
if r['coverage']['simulated'] != sys.argv[2]:
    sys.exit("FAIL: coverage.simulated is not '%s'" % sys.argv[2])
if r['pattern'] is None:
    sys.exit("FAIL: no pattern")
if r['strategy'] is None:
    sys.exit("FAIL: no strategy decided")
# The preset tags the connectivity too: each of its arrays counted.
parts = {}
for a in r['arrays']:
    for p in a.get('parts', []):
        parts[p['kind']] = parts.get(p['kind'], 0) + p['accesses']
if sys.argv[3] == 'openmesh':
    for kind in ('halfedges', 'faces', 'vconn'):
        if parts.get(kind, 0) <= 0:
            sys.exit("FAIL: no accesses to %s counted (%s)" % (kind, parts))
print("%s accesses simulated (%s), pattern %s, %s%s" % (
    r['coverage']['accesses'], r['coverage']['simulated'], r['pattern'], r['strategy'],
    ''.join(', %s %d' % kv for kv in sorted(parts.items()))))
PY
) || exit 1
grep '^emm: ' "$WORK/emm.err" | head -3
echo "$(basename "$APP") under $CAPTURE: $n output file(s) identical, $summary"
