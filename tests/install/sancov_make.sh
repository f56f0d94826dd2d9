#!/bin/sh
# An outside Makefile project builds an instrumented program against a moved
# install only, through pkg-config (emm-sancov.pc, whose prefix is
# ${pcfiledir}-relative), and it runs under `emm run` with the sancov
# capture. Then the install is moved once more, after the build: the
# program's recorded run path now points nowhere (natively it cannot start),
# and under the moved install's `emm run` it still runs, with that emm's
# libraries (emm run puts its libdir first in LD_LIBRARY_PATH).
# Usage: sancov_make.sh WORK_DIR SOURCE_DIR
set -eu
work=$1 src=$2
out=$work/sancov-make
rm -rf "$out" && mkdir -p "$out"
# A copy of the fixture's moved install, to move again without disturbing
# the tests that share the fixture.
cp -a "$work/moved" "$out/first"
prefix=$out/first
pcdir=$(dirname "$(find "$prefix" -name 'emm-sancov.pc' | head -n 1)")
[ "$(PKG_CONFIG_PATH="$pcdir" pkg-config --variable=prefix emm-sancov)" = "$pcdir/../.." ] ||
  { echo "FAIL: emm-sancov.pc's prefix is not relative to the file"; exit 1; }
PKG_CONFIG_PATH="$pcdir" make -s -C "$out" -f "$src/tests/install/sancov-make/Makefile" \
  EXAMPLES="$src/examples" region
env -i "$prefix/bin/emm" mesh gen --faces 2000 --seed 3 -o "$out/mesh.off" >/dev/null
sh "$src/tests/install/run_moved.sh" "$prefix" "$out" region "$out/region" "$out/mesh.off"
grep -q "\"capture\": \"sancov\"" "$out/region.json" || { echo "FAIL: not captured by sancov"; exit 1; }

mv "$out/first" "$out/second"
rc=0
env -i "$out/region" "$out/mesh.off" >/dev/null 2>&1 || rc=$?
[ $rc = 127 ] || { echo "FAIL: natively, with its install moved away, the program exited $rc, not 127"; exit 1; }
# run_moved.sh's native run would fail now: the summary is checked alone.
env -i "$out/second/bin/emm" run --report "$out/region2.json" -- "$out/region" "$out/mesh.off" \
  >"$out/region2.out" 2>"$out/region2.err" || { cat "$out/region2.err"; echo "FAIL: emm run after the move"; exit 1; }
cmp -s "$out/region.out" "$out/region2.out" || { echo "FAIL: the output differs after the move"; exit 1; }
grep -q "^emm: answer: " "$out/region2.err" || { cat "$out/region2.err"; echo "FAIL: no answer after the move"; exit 1; }
grep -q "\"capture\": \"sancov\"" "$out/region2.json" || { echo "FAIL: not captured by sancov after the move"; exit 1; }
echo "outside Makefile project test passed (built, then the install moved)"
