# fork + exec: the exec'd child runs under the shim too; a forked child
# without exec goes quiet. Outputs and statuses match the native run.
. "$(dirname "$0")/lib.sh"
EMM_LOG=1; export EMM_LOG
run_both forkexec "$@"
grep -q 'exec child: 0' "$WORK/forkexec.shim.out" || fail "the exec'd child failed"
grep -q 'fork child: 7' "$WORK/forkexec.shim.out" || fail "the forked child failed"
echo "forkexec: ok"
