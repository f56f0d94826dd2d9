# Fault capture of a program that reads a mesh file into its own arrays
# (tagged by EMM_TAG rules, no emm calls), then traverses them: the window
# is the traversal's (reads, not the loader's writes), and the summary and
# the report say that only the window was simulated.
#   sh loader.sh SHIM WORKDIR PROGRAM MESH
EMM_TEST_DECIDE=1
. "$(dirname "$0")/lib.sh"
unset EMM_STRATEGY
EMM_TAG='vertices:site=read_mesh,stride=24,xyz=0:f64;triangles:site=read_mesh,stride=12,vidx=0:i32'
EMM_REPORT="$WORK/report.json"
export EMM_TAG EMM_REPORT
run_both loader timeout 300 "$@"
expect_err loader '^emm: answer: '
expect_err loader 'simulated: the profiling window only, [0-9,]+ accesses'
expect_err loader 'before it, [0-9,]+ writes while the mesh was being built \(the loader\): not simulated'
R=$EMM_REPORT
num() { sed -n "s/^ *\"$1\": \([0-9]*\),\{0,1\}$/\1/p" "$R" | head -1; }
grep -q '"simulated": "window"' "$R" || fail "report: coverage.simulated is not 'window'"
grep -q '"share": null' "$R" || fail "report: coverage.share is not null"
loader=$(num loader_writes) reads=$(num reads) writes=$(num writes)
[ "${loader:-0}" -gt 0 ] || fail "report: no loader writes counted"
[ "${reads:-0}" -gt 0 ] && [ "$reads" -gt "${writes:-0}" ] ||
  fail "report: the window has $reads reads and $writes writes"
strategy=$(sed -n 's/^  "strategy": "\(.*\)",$/\1/p' "$R")
case $strategy in ''|cache*) fail "report: strategy '$strategy' on a machine without a cache" ;; esac
echo "window: $reads reads, $writes writes; loader: $loader writes not simulated; $strategy"
# Every figure of the window-only report says so in its title.
if [ -n "${EMM_CLI:-}" ]; then
  "$EMM_CLI" plot "$R" --out "$WORK/plots" --format svg > "$WORK/plot.out" 2>&1 ||
    { cat "$WORK/plot.out" >&2; fail "emm plot failed on the report"; }
  n=0
  for gp in "$WORK"/plots/*.gp; do
    [ -e "$gp" ] || continue
    n=$((n + 1))
    grep -q 'window only' "$gp" || fail "$(basename "$gp"): its title does not say 'window only'"
  done
  [ "$n" -ge 2 ] || fail "emm plot drew $n figures"
  echo "plots: $n figures, each titled 'window only'"
fi
echo "loader: ok"
