# Libraries lying in the directory emm is run from are not loaded: neither
# by emm, nor by the shim inside the program, nor by the session's process.
# Every library emm's own depend on gets a stand-in there that leaves a file
# when loaded (a build run path once held empty entries, which the loader
# reads as the current directory).
#   sh cwd_libs.sh SHIM WORKDIR EMM FAKE_LIBRARY VALGRIND(1|0) PROGRAM
. "$(dirname "$0")/lib.sh"
EMM=$1 FAKE=$2 VG=$3 PROG=$4
MARK=loaded-from-the-current-directory
for dep in $(ldd "$(dirname "$SHIM")/libemm.so.0" "$SHIM" | awk '/=>/ { print $1 }' | sort -u); do
  cp "$FAKE" "$WORK/$dep" || fail "cannot copy the stand-in for $dep"
done
[ -e "$WORK/libzstd.so.1" ] || fail "no stand-in was made (ldd found no dependency)"
cd "$WORK" || fail "cannot enter $WORK"
env -u LD_PRELOAD "$PROG" > native.out 2>&1; native_rc=$?
[ ! -e $MARK ] || fail "a stand-in was loaded natively: the test is wrong"

"$EMM" --version > version.out 2>&1 || { cat version.out >&2; fail "emm --version failed"; }
[ ! -e $MARK ] || fail "emm loaded a library from the current directory"

# check NAME CAPTURE: emm run of the program keeps its output and status, and
# loads nothing from here.
check() {
  "$EMM" run --capture "$2" -- "$PROG" > "$1.out" 2> "$1.err"; rc=$?
  [ "$rc" = "$native_rc" ] || { cat "$1.err" >&2; fail "$1: exit status $rc, $native_rc natively"; }
  cmp -s native.out "$1.out" || fail "$1: stdout differs from the native run's"
  [ ! -e $MARK ] || { cat "$1.err" >&2; fail "$1: a library was loaded from the current directory"; }
}
check fault fault
if [ "$VG" = 1 ] && command -v valgrind > /dev/null; then
  check valgrind valgrind
else
  echo "valgrind or emm's tool is not there: the valgrind capture is not tried"
fi
echo "cwd_libs test passed"
