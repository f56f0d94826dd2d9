# A tie answered by the window alone (EMM_FINALISTS=0, EMM_COMPARE=none):
# stdout and exit status as natively, and the summary names both strategies
# of the tie — the second is the decision's runner-up, never simulated.
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY # the decision's own answer
run_both tie "$@"
expect_err tie '^emm: answer: a tie between [a-z][a-z0-9]*\+[a-z]+@[0-9]+ and [a-z][a-z0-9]*\+[a-z]+@[0-9]+ \(within 3%'
expect_err tie '^emm: .*[0-9] cycles'
echo "tie: ok"
