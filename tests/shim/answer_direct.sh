# A run whose fastest strategy over the run is direct reads (random access
# on the default 20,000-face mesh, the whole run captured): the contest
# keeps direct reads in its ranking to the end and names them, and the
# summary points at no DMA stalls, which direct reads do not have.
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY # the session's own answer
run_both direct "$@"
expect_err direct '^emm: answer: direct \(measured over the run: the fastest of (the [0-9]+ candidates that ran to the end; the other [0-9]+ of [0-9]+ were dropped at [0-9, and]+ windows|[0-9]+ candidates, every one run to the end)'
expect_err direct '^emm:   runner-up [a-z][a-z0-9]*\+[a-z]+@[0-9]+: [0-9,]+ cycles \([0-9.]+% slower over the run\)'
if grep -q 'DMA stalls' "$WORK/direct.shim.err"; then
  cat "$WORK/direct.shim.err" >&2
  fail "the summary speaks of DMA stalls for direct reads"
fi
echo "answer_direct: ok"
