#!/bin/sh
# A moved install, run with nothing in the environment: `emm run` preloads
# its shim (which finds libemm.so by its run path), the shim finds the
# shipped table beside the install, and a workload is decided and simulated.
# Usage: relocated.sh WORK_DIR WORKLOAD
set -eu
work=$1 workload=$2
prefix=$work/moved
out=$work/relocated
rm -rf "$out" && mkdir -p "$out"
env -i "$prefix/bin/emm" mesh gen --faces 2000 --seed 3 -o "$out/mesh.off" >/dev/null
# The shipped table is the moved install's own.
env -i "$prefix/bin/emm" table list > "$out/table.txt"
head -n 2 "$out/table.txt"
grep -q " $prefix/share/emm/table.txt:" "$out/table.txt" || {
  echo "FAIL: the table is not the moved install's"; exit 1; }
sh "$(dirname "$0")/run_moved.sh" "$prefix" "$out" workload "$workload" "$out/mesh.off"
# The valgrind capture from the moved install, when its tool was built: the
# tool's directory finds the shim and libemm through its relative links.
vgtool=$(ls -d "$prefix"/lib*/emm/valgrind "$prefix"/lib/*/emm/valgrind 2>/dev/null | head -1)
if [ -n "$vgtool" ] && command -v valgrind >/dev/null; then
  sh "$(dirname "$0")/run_moved.sh" "$prefix" "$out" valgrind --capture valgrind -- \
    "$workload" "$out/mesh.off"
  grep -q '(the valgrind capture)' "$out/valgrind.err" || {
    echo "FAIL: the moved install's valgrind capture did not simulate the run"; exit 1; }
fi
echo "relocated install test passed"
