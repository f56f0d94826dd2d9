# One program, one answer, whatever the capture (issue 25; docs/machine.md
# "Compute"): examples/flood_walk.c, a newcomer's program with nothing of
# emm in it, on a generated mesh, tagged by rules, run
#   plain    under --capture valgrind (and --verbose),
#   sancov   its sancov build under --capture sancov,
#   sancovvg that build under --capture valgrind,
#   charged  the sancov build with compute.per_work = 1.
# The first three give the same answer, the same prediction and total
# cycles within 2% (the two builds make the same loads; one binary the
# same records, phases and stall lines under both captures), stdout as
# natively, and reports whose compute says "per access" in the capture's
# unit of work, with every result's compute bucket one cycle per access.
# The fourth charges the capture's work: its report says so, its compute
# is accesses plus work, its summary warns.
#   sh compute.sh SHIM WORKDIR EMM PLAIN SANCOV_BUILD|- VALGRIND_TOOL(1|0)
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY EMM_CAPTURE EMM_MACHINE # the session's own answer, on the default machine
EMM=$1 PLAIN=$2 SANCOV=$3 VGTOOL=$4
if [ "$SANCOV" = - ]; then
  echo "skipped: no clang, so no sancov build of flood_walk to compare the captures on"; exit 77
fi
if [ "$VGTOOL" != 1 ]; then
  echo "skipped: emm was built without its Valgrind tool: no valgrind capture to compare"; exit 77
fi
TAG='vertices:site=read_obj,stride=12,xyz=0:f32;triangles:site=read_obj,stride=12,vidx=0:u32'
MESH=$WORK/mesh.obj
"$EMM" mesh gen --faces 20000 --seed 3 -o "$MESH" > /dev/null || fail "emm mesh gen"
env -u LD_PRELOAD "$PLAIN" "$MESH" > "$WORK/native.out"; native_rc=$?
[ $native_rc = 0 ] || fail "flood_walk natively: exit status $native_rc"

# run NAME CAPTURE PROGRAM [emm run options...]
run() {
  name=$1 capture=$2 prog=$3; shift 3
  "$EMM" run --capture "$capture" --tag "$TAG" --report "$WORK/$name.json" "$@" -- \
    "$prog" "$MESH" > "$WORK/$name.out" 2> "$WORK/$name.err"; rc=$?
  [ $rc = 0 ] || { cat "$WORK/$name.err" >&2; fail "$name: exit status $rc"; }
  cmp -s "$WORK/native.out" "$WORK/$name.out" || {
    cat "$WORK/$name.err" >&2; fail "$name: stdout differs from the native run's"; }
  grep -q '^emm: answer: ' "$WORK/$name.err" || { cat "$WORK/$name.err" >&2; fail "$name: no answer"; }
}
run plain valgrind "$PLAIN" --verbose
run sancov sancov "$SANCOV"
run sancovvg valgrind "$SANCOV"
printf 'compute.per_work = 1\n' > "$WORK/charged.ini"
run charged sancov "$SANCOV" --machine "$WORK/charged.ini"

grep -Eq "^emm: compute: 1 cycle per access, whatever the capture; the valgrind capture's work between accesses \([0-9,]+ superblocks\) is not charged" "$WORK/plain.err" ||
  { cat "$WORK/plain.err" >&2; fail "plain: --verbose does not say how compute was counted"; }
grep -q 'compute:' "$WORK/sancov.err" &&
  { cat "$WORK/sancov.err" >&2; fail "sancov: the summary speaks of compute, though only accesses are charged"; }
grep -Eq '^emm:   compute: [0-9,]+ cycles: 1 per access and 1 per unit of the sancov capture.s work \([0-9,]+ edges; compute.per_work = 1\): these figures depend on the capture' "$WORK/charged.err" ||
  { cat "$WORK/charged.err" >&2; fail "charged: the summary does not say the capture's work was charged"; }

python3 - "$WORK" <<'PY' || exit 1
import json, os, sys
d = sys.argv[1]
r = {n: json.load(open(os.path.join(d, n + '.json')))
     for n in ('plain', 'sancov', 'sancovvg', 'charged')}
bad = []
def check(ok, what):
    if not ok:
        bad.append(what)
unit = {'plain': 'superblocks', 'sancov': 'edges', 'sancovvg': 'superblocks', 'charged': 'edges'}
for n, x in r.items():
    c = x.get('compute')
    check(c is not None, '%s: the report has no compute' % n)
    if c is None:
        continue
    charged = n == 'charged'
    check(c['counted'] == ('per access and work' if charged else 'per access'),
          '%s: compute.counted is %r' % (n, c['counted']))
    check(c['per_access'] == 1 and c['per_work'] == (1 if charged else 0),
          '%s: compute keys %r' % (n, c))
    check(c['work_unit'] == unit[n] and c['work'] > 0, '%s: work %r' % (n, c))
    check(x['coverage']['simulated'] == 'run', '%s: coverage %r' % (n, x['coverage']))
    for res in x['results']:
        if 'cycles' not in res:
            continue
        want = res['accesses'] + (c['work'] if charged else 0)
        check(res['cycles']['compute'] == want, '%s: %s charged %d compute cycles, not %d'
              % (n, res['strategy'], res['cycles']['compute'], want))
total = {n: x['results'][0]['cycles']['total'] for n, x in r.items()}
for n in ('plain', 'sancov', 'sancovvg'):
    print('%-8s %-20s %10d accesses %12d cycles' % (n, r[n]['strategy'], r[n]['accesses'], total[n]))
for n in ('plain', 'sancovvg'):
    check(r[n]['strategy'] == r['sancov']['strategy'],
          'the answers differ: %s %s, sancov %s' % (n, r[n]['strategy'], r['sancov']['strategy']))
    # The window's prediction too: the decision sees the window up to the
    # read that filled it, however large the capture's batches.
    check(r[n]['decision']['predicted'] == r['sancov']['decision']['predicted'],
          'the predictions differ: %s %s, sancov %s'
          % (n, r[n]['decision']['predicted'], r['sancov']['decision']['predicted']))
    check(abs(total[n] - total['sancov']) <= 0.02 * total['sancov'],
          'total cycles differ by more than 2%%: %s %d, sancov %d' % (n, total[n], total['sancov']))
# One binary, the same records: the sancov build makes the loads its
# coverage callbacks report (cmake/EmmSancov.cmake: no machine sinking).
check(r['sancovvg']['accesses'] == r['sancov']['accesses'],
      'the sancov build made %d records under valgrind, %d under sancov'
      % (r['sancovvg']['accesses'], r['sancov']['accesses']))
# ... and the same phases: a probe lands a fixed number of records after it
# filled, whatever the capture's batches (valgrind's are large).
def phases(x):
    return [(p['start'], p['pattern'], p.get('best')) for p in x.get('phases') or []]
check(phases(r['sancovvg']) == phases(r['sancov']) and r['sancovvg']['probes'] == r['sancov']['probes'],
      'the phases differ: under valgrind %s (probes %s), under sancov %s (probes %s)'
      % (phases(r['sancovvg']), r['sancovvg']['probes'], phases(r['sancov']), r['sancov']['probes']))
# ... and the answer's stalls fall in the same functions: a valgrind
# record's pc lies in its load's instruction as a sancov hook's return
# address lies past its call (the lines may differ where the compiler gave
# the load another line than its hook's; line 0 is none).
def stalls(x):
    return [(l['function'], l['dma_stall']) for l in x.get('stall_lines') or []]
check(stalls(r['sancovvg']) == stalls(r['sancov']),
      'the stall lines differ: under valgrind %s, under sancov %s'
      % (r['sancovvg'].get('stall_lines'), r['sancov'].get('stall_lines')))
for n in ('plain', 'sancov', 'sancovvg'):
    check(all(l['line'] > 0 for l in r[n].get('stall_lines') or []),
          '%s: a stall line without a line: %s' % (n, r[n].get('stall_lines')))
for b in bad:
    print('FAIL:', b, file=sys.stderr)
sys.exit(1 if bad else 0)
PY
echo "compute: ok"
