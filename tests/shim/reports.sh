# One report per process: a program that walks its own mesh and starts
# another that walks one too (tests/shim/parent.c running untagged.c),
# with one EMM_REPORT path and no %p. Under plain LD_PRELOAD and emm run
# with the fault and valgrind captures, both reports are there, each naming
# its program: the one that finishes first (here the child) writes the
# path; the other, finding it written by another process of the run since
# it started, writes PATH.PID beside it and its summary names it.
#   sh reports.sh SHIM WORK EMM VALGRIND(0|1) PARENT CHILD
. "$(dirname "$0")/lib.sh"
EMM=$1 VG=$2 PARENT=$3 CHILD=$4
TAG='vertices:site=load_grid,stride=32,xyz=8:f64;triangles:site=load_grid,stride=16,vidx=4:i32'
env -u LD_PRELOAD "$PARENT" "$CHILD" > "$WORK/native.out" 2>/dev/null; native_rc=$?
[ $native_rc = 0 ] || fail "the native run failed"

# both NAME DIR: DIR holds r.json and one r.json.PID, one naming each program.
both() {
  python3 - "$2" "$1" <<'PY' || { cat "$WORK/$1.err" >&2; fail "$1: not one report for each process"; }
import glob, json, os, sys
d, name = sys.argv[1], sys.argv[2]
plain = os.path.join(d, "r.json")
others = glob.glob(plain + ".*")
assert os.path.exists(plain) and len(others) == 1, "%s: %s and %s" % (name, os.path.exists(plain), others)
progs = sorted(json.load(open(p))["program"] for p in [plain] + others)
assert progs == ["test_shim_parent", "test_shim_untagged"], "%s: programs %s" % (name, progs)
PY
  grep -q "^emm:   report: $2/r.json.[0-9]* (r.json holds another process's of this run)" "$WORK/$1.err" ||
    grep -q "^emm:   report: $2/r.json.[0-9]* ($2/r.json holds" "$WORK/$1.err" ||
    { cat "$WORK/$1.err" >&2; fail "$1: no summary names the second report"; }
}

mkdir -p "$WORK/preload"
EMM_TAG=$TAG EMM_REPORT="$WORK/preload/r.json" LD_PRELOAD="$SHIM" "$PARENT" "$CHILD" \
  > "$WORK/preload.out" 2> "$WORK/preload.err"; rc=$?
[ $rc = $native_rc ] || fail "LD_PRELOAD: exit status $rc"
cmp -s "$WORK/native.out" "$WORK/preload.out" || fail "LD_PRELOAD: stdout differs"
both preload "$WORK/preload"

captures=fault
[ "$VG" = 1 ] && captures="fault valgrind"
for capture in $captures; do
  mkdir -p "$WORK/$capture"
  "$EMM" run --capture "$capture" --tag "$TAG" --report "$WORK/$capture/r.json" -- "$PARENT" "$CHILD" \
    > "$WORK/$capture.out" 2> "$WORK/$capture.err"; rc=$?
  [ $rc = $native_rc ] || { cat "$WORK/$capture.err" >&2; fail "$capture: exit status $rc"; }
  cmp -s "$WORK/native.out" "$WORK/$capture.out" || fail "$capture: stdout differs"
  both "$capture" "$WORK/$capture"
done
echo "reports: ok ($captures, LD_PRELOAD)"
