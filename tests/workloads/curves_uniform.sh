#!/bin/sh
# curve_tracing on grid4.off (4x4 squares over the unit square, each split by
# the diagonal from its lower-left corner; vertex id = 5*row + column, square
# (row j, column i) has triangles 8j+2i = (a, a+1, a+6) and 8j+2i+1 =
# (a, a+6, a+5) with a = 5j+i) in the uniform field (1, 0), with all 25
# vertices as seeds (--curves 25: seed i is vertex i*25/25 = i).
#
# --long, by hand: every curve is the horizontal segment from its seed to the
# right side x = 1, of length 1 - x. The five seeds on x = 1 have no triangle
# ahead (length 0, not counted). 20 curves; 5 rows * (1 + .75 + .5 + .25) = 12.5.
#
# --short, by hand: the curve from vertex 0 runs along y = 0 through the
# lower-right triangle of each square of row 0 and, where it passes a vertex,
# the upper-left one beside it: it marks all of row 0's triangles but 1
# (0,6,5); length 1. Vertices 1, 2, 3 start in lower-right triangles it
# marked: length 0. Vertex 4 is on x = 1: 0. Vertices 5, 10 and 15 start in
# the (unmarked) lower-right triangle above their row and repeat the pattern
# one row up: length 1 each, leaving triangles 9, 17 and 25 unmarked; the
# others of rows 1-3 start in marked triangles. Vertex 20 starts in triangle
# 25 = (15,21,20), runs along y = 1 and at vertex 21 enters triangle 24,
# marked by curve 15: length 0.25. Vertices 21-24: 0.
# 5 curves; 1 + 1 + 1 + 1 + 0.25 = 4.25.
. "$(dirname "$0")/lib.sh"
bin=$1 data=$2 fnv=$3
out=$("$bin/curve_tracing" --long --field uniform --curves 25 "$data/grid4.off") || fail "--long exited $?"
expect_eq "--long" "curves: 20
length: 12.500000" "$out"
out=$("$bin/curve_tracing" --short --field uniform --curves 25 "$data/grid4.off") || fail "--short exited $?"
expect_eq "--short" "curves: 5
length: 4.250000" "$out"
# --short is the default mode.
out2=$("$bin/curve_tracing" --field uniform --curves 25 "$data/grid4.off")
expect_eq "default mode" "$out" "$out2"
echo ok
