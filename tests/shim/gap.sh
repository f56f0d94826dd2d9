# The valgrind capture's inline test when the program's hottest data lies
# between its tagged arrays (tests/shim/gap.c): one interval covers both
# arrays and the scratch between them at first, so each scratch access is a
# helper call that finds nothing; past MISSES_FOR_TWO such misses, more
# than the records, the tool tests two intervals instead (its
# --emm-stats=yes line says how many). No record is lost on the way: the
# report counts exactly the element reads the program made.
#   sh gap.sh SHIM WORKDIR EMM PROGRAM
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM=$1; shift
TAG='vertices:site=make_mesh,stride=12,xyz=0:f32;triangles:site=make_mesh,stride=12,vidx=0:u32'
env -u LD_PRELOAD "$@" > "$WORK/native.out"; native_rc=$?
VALGRIND_OPTS=--emm-stats=yes "$EMM" run --capture valgrind --tag "$TAG" --report "$WORK/gap.json" \
  -- "$@" > "$WORK/gap.out" 2> "$WORK/gap.err"; rc=$?
[ $rc = $native_rc ] || { cat "$WORK/gap.err" >&2; fail "exit status $rc under valgrind capture, $native_rc natively"; }
cmp -s "$WORK/native.out" "$WORK/gap.out" || { cat "$WORK/gap.err" >&2; fail "stdout differs under valgrind capture"; }
grep -q 'emm tool: .* 2 intervals tested' "$WORK/gap.err" ||
  { cat "$WORK/gap.err" >&2; fail "the tool did not go to two intervals"; }
python3 - "$WORK/gap.json" "$WORK/native.out" <<'PY' || exit 1
import json, sys
r = json.load(open(sys.argv[1]))
reads = int(open(sys.argv[2]).read().split()[2])
got = r['coverage']['element_accesses']
print("element reads: the program's %d, the report's %d" % (reads, got))
if got != reads:
    sys.exit("FAIL: the report counts %d element accesses, the program made %d reads" % (got, reads))
PY
echo "gap: ok"
