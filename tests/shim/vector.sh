# A std::vector grown by push_back in build_mesh: many buffers are
# allocated, tagged and freed on the way; exactly one tag is left at exit.
. "$(dirname "$0")/lib.sh"
EMM_TAG='vertices:site=build_mesh,stride=80,xyz=8:f64'; EMM_LOG=2; export EMM_TAG EMM_LOG
run_both vector "$@"
expect_err vector 'at exit: 1 arrays tagged'
expect_err vector 'at exit: vertices at 0x[0-9a-f]+, 2048 records of 80 bytes'
n=$(grep -c 'tagged vertices' "$WORK/vector.shim.err")
[ "$n" -gt 1 ] || fail "expected the growing vector to be tagged several times, got $n"
# The buffers read in the window are simulated, and counted in one line.
grep -Eq '^emm:   simulated arrays: [0-9]+ vertex arrays \(80-byte records, the largest 2,000\)$' "$WORK/vector.shim.err" ||
  fail "the summary does not count the vector's buffers in one line"
echo "vector: ok ($n buffers tagged on the way)"
