#!/bin/sh
# An outside CMake project builds an instrumented program against the moved
# install only (find_package(emm), emm_sancov_executable), and it runs under
# `emm run` with the sancov capture.
# Usage: sancov_cmake.sh WORK_DIR SOURCE_DIR
set -eu
work=$1 src=$2
prefix=$work/moved
out=$work/sancov-cmake
rm -rf "$out" && mkdir -p "$out"
cmake -S "$src/tests/install/sancov-cmake" -B "$out/build" -DCMAKE_PREFIX_PATH="$prefix" \
  -DEMM_EXAMPLES="$src/examples" >/dev/null
cmake --build "$out/build" >/dev/null
env -i "$prefix/bin/emm" mesh gen --faces 2000 --seed 3 -o "$out/mesh.off" >/dev/null
sh "$src/tests/install/run_moved.sh" "$prefix" "$out" curves \
  "$out/build/curves" --long "$out/mesh.off"
grep -q "capture.*sancov\|\"capture\": \"sancov\"" "$out/curves.json" || { echo "FAIL: not captured by sancov"; exit 1; }
echo "outside CMake project test passed"
