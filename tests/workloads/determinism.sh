#!/bin/sh
# Each workload prints the same bytes twice on the default mesh (the shim's
# runs are compared with native ones byte for byte), and the output has the
# documented form.
. "$(dirname "$0")/lib.sh"
bin=$1
for args in "curve_tracing --short" "curve_tracing --long" region_growing random_access; do
  set -- $args
  prog=$1; shift
  a=$("$bin/$prog" "$@") || fail "$args: exit $?"
  b=$("$bin/$prog" "$@") || fail "$args: exit $?"
  expect_eq "$args twice" "$a" "$b"
  case $prog in
    curve_tracing) pat='^curves: [1-9][0-9]*
length: [0-9]+\.[0-9]{6}$' ;;
    region_growing) pat='^codes: [0-9]+
splits: [0-9]+
merges: 0
checksum: 0x[0-9a-f]{16}$' ;;
    random_access) pat='^vertices: [0-9]+
checksum: 0x[0-9a-f]{16}$' ;;
  esac
  printf '%s' "$a" | tr '\n' '|' | grep -Eq "^$(printf '%s' "$pat" | tr '\n' '|')\$" || fail "$args: output form: $a"
done
echo ok
