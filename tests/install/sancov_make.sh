#!/bin/sh
# An outside Makefile project builds an instrumented program against the
# moved install only, through pkg-config (emm-sancov.pc), and it runs under
# `emm run` with the sancov capture.
# Usage: sancov_make.sh WORK_DIR SOURCE_DIR
set -eu
work=$1 src=$2
prefix=$work/moved
out=$work/sancov-make
rm -rf "$out" && mkdir -p "$out"
libdir=$(dirname "$(find "$prefix" -name 'emm-sancov.pc' | head -n 1)")
PKG_CONFIG_PATH="$libdir" make -s -C "$out" -f "$src/tests/install/sancov-make/Makefile" \
  EXAMPLES="$src/examples" region
env -i "$prefix/bin/emm" mesh gen --faces 2000 --seed 3 -o "$out/mesh.off" >/dev/null
sh "$src/tests/install/run_moved.sh" "$prefix" "$out" region "$out/region" "$out/mesh.off"
grep -q "\"capture\": \"sancov\"" "$out/region.json" || { echo "FAIL: not captured by sancov"; exit 1; }
echo "outside Makefile project test passed"
