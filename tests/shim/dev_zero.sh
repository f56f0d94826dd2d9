# An input file that never ends (/dev/zero as EMM_TABLE or EMM_MACHINE)
# must not starve the program: the shim refuses it as too large after a
# bounded read, says so in one line naming the variable, and steps aside;
# the program's stdout and exit status are those of the native run, within
# a few seconds. (It used to grow to 4 GB while the program printed nothing.)
. "$(dirname "$0")/lib.sh"
for var in EMM_TABLE EMM_MACHINE; do
  export "$var=/dev/zero"
  start=$(date +%s)
  run_both "$var" "$@"
  secs=$(( $(date +%s) - start ))
  [ "$secs" -le 10 ] || fail "$var=/dev/zero: the two runs took ${secs}s"
  [ "$(wc -l < "$WORK/$var.shim.err")" = 1 ] || { cat "$WORK/$var.shim.err" >&2; fail "$var: expected one stderr line"; }
  expect_err "$var" "^emm: $var: /dev/zero: too large"
  unset "$var"
done
echo "dev_zero: ok"
