# The api backend: a program that reads its mesh only through the mesh
# interface, under EMM_CAPTURE=api and under auto (which must pick api):
# stdout and exit status of the native run, and a report of the api capture
# with accesses.
. "$(dirname "$0")/lib.sh"
unset EMM_TAG
for capture in api auto; do
  EMM_CAPTURE=$capture EMM_REPORT=$WORK/$capture.json; export EMM_CAPTURE EMM_REPORT
  run_both $capture "$@"
  expect_err $capture '^emm: .*[0-9] cycles'
  [ -f "$WORK/$capture.json" ] || { cat "$WORK/$capture.shim.err" >&2; fail "$capture: no report"; }
  grep -q '"capture": "api"' "$WORK/$capture.json" || fail "$capture: the report's capture is not api"
  acc=$(sed -n 's/^  "accesses": \([0-9]*\),*$/\1/p' "$WORK/$capture.json")
  [ -n "$acc" ] && [ "$acc" -gt 0 ] || fail "$capture: the report has no accesses ($acc)"
  echo "$capture: ok ($acc accesses)"
done
