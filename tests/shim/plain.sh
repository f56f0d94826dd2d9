# Runs the program natively and under the shim with the EMM_* variables the
# test's environment sets; stdout and exit status must match, and the
# summary must show a simulation.
. "$(dirname "$0")/lib.sh"
run_both plain "$@"
expect_err plain '^emm: .*[0-9] cycles'
echo "plain: ok"
