# The valgrind capture's session runs natively in its own process
# (emm-session, beside the tool): the program's stdout and exit status are
# its own, and it answers as the session inside the program does, which is
# what runs when emm-session is not there (here: a VALGRIND_LIB without it).
# emm run starts it while Valgrind starts and the shim takes it over;
# under valgrind --tool=emm alone the shim starts it.
#   sh valgrind_session.sh SHIM WORKDIR EMM PROGRAM MESH
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM=$1; shift
TOOLDIR=$(dirname "$EMM")/../lib/emm/valgrind
[ -x "$TOOLDIR/emm-session" ] || fail "$TOOLDIR/emm-session is not built"
TAG='vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32'
EMM_TAG=$TAG; export EMM_TAG
env -u LD_PRELOAD "$@" > "$WORK/native.out"; native_rc=$?

# Its own process.
"$EMM" run --capture valgrind --verbose --report "$WORK/own.json" -- "$@" \
  > "$WORK/own.out" 2> "$WORK/own.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/own.err" >&2; fail "exit status $rc, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/own.out" || { cat "$WORK/own.err" >&2; fail "stdout differs"; }
grep -q 'the session runs natively in its own process, .*/emm-session (started by emm run)' "$WORK/own.err" ||
  { cat "$WORK/own.err" >&2; fail "the session emm run started was not taken over"; }
grep -q '^emm: answer: ' "$WORK/own.err" || { cat "$WORK/own.err" >&2; fail "no answer"; }

# Valgrind alone: the shim starts it, with the same answer.
EMM_LOG=2 EMM_CAPTURE=valgrind VALGRIND_LIB="$TOOLDIR" valgrind --tool=emm -q "$@"   > "$WORK/alone.out" 2> "$WORK/alone.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/alone.err" >&2; fail "exit status $rc under valgrind alone"; }
cmp -s "$WORK/native.out" "$WORK/alone.out" || fail "stdout differs under valgrind alone"
grep -q 'the session runs natively in its own process, .*/emm-session$' "$WORK/alone.err" ||
  { cat "$WORK/alone.err" >&2; fail "the shim did not start the session itself"; }
[ "$(grep '^emm: answer: ' "$WORK/alone.err")" = "$(grep '^emm: answer: ' "$WORK/own.err")" ] ||
  fail "another answer when the shim starts the session"

# In the program: the tool's directory without emm-session.
mkdir -p "$WORK/lib" || fail "mkdir"
for f in "$TOOLDIR"/*; do
  [ "$(basename "$f")" = emm-session ] || ln -s "$(readlink -f "$f")" "$WORK/lib/$(basename "$f")"
done
EMM_LOG=2 EMM_CAPTURE=valgrind EMM_REPORT="$WORK/inside.json" VALGRIND_LIB="$WORK/lib" \
  valgrind --tool=emm -q "$@" > "$WORK/inside.out" 2> "$WORK/inside.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/inside.err" >&2; fail "exit status $rc in the program, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/inside.out" || fail "stdout differs with the session in the program"
grep -q 'the session runs natively' "$WORK/inside.err" && fail "emm-session ran though it is not there"
grep -q '^emm: answer: ' "$WORK/inside.err" || { cat "$WORK/inside.err" >&2; fail "no answer in the program"; }

# The same answer, records and transfers, and the same work between records
# (the tool's count of superblocks, the report's compute.work, within 0.1%:
# the shim's own calls into the C library while it feeds the session are
# not the program's work, in either place; they were: in the program the
# total was 4.5 times the program's own on this run). Compute is charged
# per access (docs/machine.md "Compute"), so the work is compared, not the
# compute cycles.
python3 - "$WORK/own.json" "$WORK/inside.json" <<'PY' || fail "the two sessions answer differently"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
same = lambda r: (r['strategy'], r['accesses'], r.get('dma'), r.get('emm'))
checks = [
    ('strategy', a['strategy'], b['strategy']),
    ('pattern', a['pattern'], b['pattern']),
    ('coverage', a['coverage'], b['coverage']),
    ('mesh', a['mesh'], b['mesh']),
    ('decision.predicted', a['decision']['predicted'], b['decision']['predicted']),
    ('results', [same(r) for r in a['results']], [same(r) for r in b['results']]),
]
bad = [name for name, x, y in checks if x != y]
for r in a, b:
    c = r['compute']
    if c['counted'] != 'per access' or c['work_unit'] != 'superblocks' or c['work'] <= 0:
        bad.append('compute: %s' % c)
wa, wb = a['compute']['work'], b['compute']['work']
if abs(wa - wb) > 0.001 * max(wa, wb):
    bad.append('work between records: %d and %d superblocks' % (wa, wb))
for name in bad:
    print('differs:', name, file=sys.stderr)
sys.exit(1 if bad else 0)
PY

# Started by hand, it says what it is for.
"$TOOLDIR/emm-session" > "$WORK/hand.out" 2> "$WORK/hand.err"; rc=$?
[ $rc = 2 ] || fail "emm-session by hand: exit status $rc, not 2"
[ "$(wc -l < "$WORK/hand.err")" = 1 ] && grep -q 'libemmshim.so starts it' "$WORK/hand.err" ||
  fail "emm-session by hand: not one line saying what it is"
echo "valgrind_session: ok"
