#!/bin/sh
# region_growing on two tiny meshes, the code sequences worked out by hand
# from the rules in examples/region_growing.c; the checksums are the tests'
# own FNV-1a (fnv1a64.c) of those sequences.
#
# triangle.off, one triangle (0,1,2): closed by a dummy vertex d over its
# three boundary edges it is a tetrahedron, every valence 3. Seed: A3 A3 A3,
# list 0 1 2. Pivot 0: across gate (0,1) the dummy triangle (1,0,d), d free:
# D3, list 0 d 1 2. Across (0,d): dummy triangle (0,2,d), 2 precedes 0: 0 is
# full, list 2 d 1, pivot 2. Across (2,d): (2,1,d), 1 precedes 2: 2 is full,
# two vertices left. Codes: A3 A3 A3 D3.
#
# square.off, triangles (0,1,2) and (0,2,3), one boundary loop of 4: valences
# 0: 2 triangles + 2 dummy = 4, 1: 3, 2: 4, 3: 3, d: 4. Seed: A4 A3 A4, list
# 0 1 2. Pivot 0: across (0,1) dummy (1,0,d): D4, list 0 d 1 2. Across (0,d)
# dummy (0,3,d): 3 free, A3, list 0 3 d 1 2. Across (0,3): (0,2,3), 2 precedes
# 0: 0 full, list 2 3 d 1, pivot 2. Its predecessor 1 has one free triangle,
# (2,1,d) across gate (1,2), whose third vertex d precedes 1: closed first
# (ear), list 2 3 d. Across (2,3): dummy (3,2,d), d precedes 2: 2 full.
# Codes: A4 A3 A4 D4 A3.
. "$(dirname "$0")/lib.sh"
bin=$1 data=$2 fnv=$3
check() { # MESH "CODES" (space-separated)
  listing=$(printf '%s\n' $2)
  n=$(printf '%s\n' $2 | wc -l | tr -d ' ')
  sum=$(printf '%s\n' $2 | "$fnv")
  out=$("$bin/region_growing" --conquest --print-codes "$data/$1") || fail "$1: exited $?"
  expect_eq "$1 codes" "$listing" "$(printf '%s\n' "$out" | head -n "$n")"
  expect_eq "$1 summary" "codes: $n
splits: 0
merges: 0
checksum: $sum" "$(printf '%s\n' "$out" | tail -n 4)"
  out2=$("$bin/region_growing" --conquest "$data/$1")
  expect_eq "$1 without --print-codes" "$(printf '%s\n' "$out" | tail -n 4)" "$out2"
}
check triangle.off "A3 A3 A3 D3"
check square.off "A4 A3 A4 D4 A3"

# The default, Program 4.2 (breadth-first, FIFO), whose codes are each
# vertex's triangle count. triangle.off: the seed's three vertices, one
# triangle each; focus 0 meets 1 and 2 full: A1 A1 A1, no split.
# square.off: seed (0,1,2): A2 A1 A2, list 0 1 2. Focus 0's fan, in
# rotation from its first triangle (0,1,2) the other way round, is
# (0,2,3) then (0,1,2): conquering (0,2,3) meets 2 in the list with (0,1,2)
# still free around it — a split, pushed for later — and frees 3: A1. The
# split's list is full by the time it is popped and is dropped.
fifo() { # MESH "CODES" SPLITS
  listing=$(printf '%s\n' $2)
  n=$(printf '%s\n' $2 | wc -l | tr -d ' ')
  sum=$(printf '%s\n' $2 | "$fnv")
  out=$("$bin/region_growing" --print-codes "$data/$1") || fail "$1: exited $?"
  expect_eq "$1 codes (Program 4.2)" "$listing" "$(printf '%s\n' "$out" | head -n "$n")"
  expect_eq "$1 summary (Program 4.2)" "codes: $n
splits: $3
checksum: $sum" "$(printf '%s\n' "$out" | tail -n 3)"
}
fifo triangle.off "A1 A1 A1" 0
fifo square.off "A2 A1 A2 A1" 1
echo ok
