#!/bin/sh
# random_access: the sorted order computed independently with awk from the
# mesh file (the tension field's formula from examples/workload.c, the
# bounding box of grid4.off being the unit square) and sort(1), its checksum
# with the tests' own FNV-1a (fnv1a64.c). With the uniform field every
# magnitude is 1 and the order is the ids, 0 to 24.
. "$(dirname "$0")/lib.sh"
bin=$1 data=$2 fnv=$3
mesh=$data/grid4.off
expected=$(awk 'NR == 2 { nv = $1 } NR > 2 && NR <= 2 + nv {
    ux = $1; uy = $2; gx = 1.0; gy = 0.35
    split("0.30 0.65 0.70", cx, " "); split("0.35 0.70 0.25", cy, " ")
    split("0.15 0.12 0.10", s, " "); split("0.062 -0.050 0.041", a, " ")
    for (k = 1; k <= 3; k++) {
      dx = ux - cx[k]; dy = uy - cy[k]; s2 = s[k] * s[k]
      e = a[k] * exp(-(dx * dx + dy * dy) / (2.0 * s2)) / s2
      gx -= e * dx; gy -= e * dy
    }
    printf "%.17g %d\n", gx * gx + gy * gy, NR - 3 }' "$mesh" | sort -k1,1g -k2,2n | awk '{ print $2 }')
out=$("$bin/random_access" --print-order "$mesh") || fail "exited $?"
expect_eq "tension order" "$expected" "$(printf '%s\n' "$out" | head -n 25)"
expect_eq "tension summary" "vertices: 25
checksum: $(printf '%s\n' "$expected" | "$fnv")" "$(printf '%s\n' "$out" | tail -n 2)"
ids=$(seq 0 24)
out=$("$bin/random_access" --field uniform "$mesh") || fail "exited $?"
expect_eq "uniform summary" "vertices: 25
checksum: $(printf '%s\n' "$ids" | "$fnv")" "$out"
echo ok
