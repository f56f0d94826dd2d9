#!/bin/sh
# Fails when a registered test has no label, naming it.
#   sh labels.sh CTEST BUILD_DIR WORK_DIR
# ctest lists the tests of BUILD_DIR from WORK_DIR (a CTestTestfile.cmake
# that points there): a ctest run writes its logs under the directory it
# starts in, and the suite's own log in BUILD_DIR/Testing is being written
# by the run this test is part of.
set -eu
ctest=$1 build=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
printf 'subdirs("%s")\n' "$build" > "$work/CTestTestfile.cmake"
cd "$work"
total=$("$ctest" -N | sed -n 's/^Total Tests: //p')
[ "${total:-0}" -gt 0 ] || { echo "FAIL: ctest lists no test in $build"; exit 1; }
# -LE . leaves out every test that matches some label: what remains has none.
unlabelled=$("$ctest" -N -LE . | sed -n 's/^ *Test *#[0-9]*: //p')
if [ -n "$unlabelled" ]; then
  echo "FAIL: tests without a label (tests/CMakeLists.txt gives every test of tests/AREA/ the label AREA; a test registered elsewhere needs LABELS of its own):"
  printf '%s\n' "$unlabelled" | sed 's/^/  /'
  exit 1
fi
echo "labels: all $total tests carry one"
