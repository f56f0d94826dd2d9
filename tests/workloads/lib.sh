# Shared by the workload tests: fail with a message, compare outputs.
fail() { echo "FAIL: $*" >&2; exit 1; }
# expect_eq WHAT EXPECTED ACTUAL
expect_eq() {
  [ "$2" = "$3" ] || fail "$1: expected
$2
got
$3"
}
