#!/bin/sh
# region_growing checks its own invariants (every vertex conquered once,
# every triangle reached, valences adding up to 3 * triangles, and with
# --conquest merges equal to the genus) and exits 1 when one fails. Both the
# default (Program 4.2) and --conquest run on: the generated default mesh;
# holes.off (two holes, a second component, an unused vertex); a regular
# 20x20 grid, where the conquest must not split; and a closed torus (genus 1,
# built here with awk), which needs exactly one merge.
. "$(dirname "$0")/lib.sh"
bin=$1 data=$2 work=$4
mkdir -p "$work"
run() { # NAME ARGS...; prints the output
  name=$1; shift
  out=$("$bin/region_growing" "$@" 2>"$work/stderr") || fail "$name: exit $?: $(cat "$work/stderr")"
  [ -s "$work/stderr" ] && fail "$name: wrote to stderr: $(cat "$work/stderr")"
  printf '%s\n' "$out" | grep -Eq '^checksum: 0x[0-9a-f]{16}$' || fail "$name: bad output: $out"
  printf '%s\n' "$out"
}
field() { printf '%s\n' "$1" | awk -v k="$2:" '$1 == k { print $2 }'; }
run default >/dev/null
run default-conquest --conquest >/dev/null
out=$(run holes "$data/holes.off")
expect_eq "holes codes" 90 "$(field "$out" codes)"
out=$(run holes-conquest --conquest "$data/holes.off")
expect_eq "holes merges" 0 "$(field "$out" merges)"
awk 'BEGIN { n = 20; print "OFF"; print (n+1)*(n+1), 2*n*n, 0
  for (j = 0; j <= n; j++) for (i = 0; i <= n; i++) printf "%.17g %.17g 0\n", i/n, j/n
  for (j = 0; j < n; j++) for (i = 0; i < n; i++) { a = j*(n+1)+i
    print 3, a, a+1, a+n+2; print 3, a, a+n+2, a+n+1 } }' > "$work/grid20.off"
out=$(run grid20 "$work/grid20.off")
expect_eq "grid20 codes" 441 "$(field "$out" codes)"
out=$(run grid20-conquest --conquest "$work/grid20.off")
expect_eq "grid20 splits" 0 "$(field "$out" splits)"
# 12 x 8 torus: vertices on a ring of rings, faces wrapping in both directions.
awk 'BEGIN { n = 12; m = 8; R = 3; r = 1; print "OFF"; print n*m, 2*n*m, 0
  for (i = 0; i < n; i++) for (j = 0; j < m; j++) {
    u = 6.283185307179586 * i / n; v = 6.283185307179586 * j / m
    printf "%.17g %.17g %.17g\n", (R + r*cos(v))*cos(u), (R + r*cos(v))*sin(u), r*sin(v) }
  for (i = 0; i < n; i++) for (j = 0; j < m; j++) {
    a = i*m + j; b = ((i+1)%n)*m + j; c = ((i+1)%n)*m + (j+1)%m; d = i*m + (j+1)%m
    print 3, a, b, c; print 3, a, c, d } }' > "$work/torus.off"
out=$(run torus "$work/torus.off")
expect_eq "torus codes" 96 "$(field "$out" codes)"
out=$(run torus-conquest --conquest "$work/torus.off")
expect_eq "torus merges" 1 "$(field "$out" merges)"
# Codes: one per vertex (96, no dummies) plus the splits and the merge.
expect_eq "torus codes" $((96 + $(field "$out" splits) + 1)) "$(field "$out" codes)"
echo ok
