#!/bin/sh
# Layouts in space against layouts in the plane, and EMM against direct
# reads, on meshes with depth: the glmark2 bunny (when Debian's glmark2-data
# is installed), a torus and a sphere of FACES faces (emm mesh gen
# --surface). Two traversals each (emm trace synth): region growing, a
# breadth-first growth over the whole mesh (the thesis' Program 4.2 order),
# and long curves (walks to the boundary, as many visits as triangles).
# For each, the whole sweep with the indexed variants (emm replay --all
# --indexed) and one line: direct reads' cycles, the fastest EMM strategy
# laid out in the plane (grid, tiles, quadtree, indexed or not) and in space
# (grid3d, tiles3d, octree), each as a speed-up over direct reads, and space
# over plane. A report, not a test.
# usage: bench/space.sh BUILD_DIR [FACES] [WORK_DIR]   (FACES default 20000)
set -eu
BUILD=${1:?usage: space.sh BUILD_DIR [FACES] [WORK_DIR]}
FACES=${2:-20000}
EMM=$BUILD/bin/emm
W=${3:-${TMPDIR:-/tmp}/emm-space.$$}
mkdir -p "$W"
[ -n "${3:-}" ] || trap 'rm -rf "$W"' EXIT

meshes=
bunny=/usr/share/glmark2/models/bunny.obj
if [ -s "$bunny" ]; then
    cp "$bunny" "$W/bunny.obj"
    meshes="bunny.obj"
else
    echo "(no $bunny: install glmark2-data for the bunny's line)"
fi
for s in torus sphere; do
    [ -s "$W/$s-$FACES.off" ] ||
        "$EMM" mesh gen --surface $s --faces "$FACES" -o "$W/$s-$FACES.off" >/dev/null
    meshes="$meshes $s-$FACES.off"
done

printf '%-18s %-7s %13s  %-34s %7s  %-34s %7s %7s\n' mesh pattern direct \
    "fastest in the plane" "x dir" "fastest in space" "x dir" "space/plane"
for m in $meshes; do
    for p in region curve; do
        t=$W/${m%.*}-$p.emmt
        [ -s "$t" ] || "$EMM" trace synth --mesh "$W/$m" --pattern $p -o "$t" >/dev/null
        # The sweep's table: rank, strategy, total cycles, ...
        "$EMM" replay "$t" --all --indexed 2>/dev/null | awk -v m="$m" -v p="$p" '
            $1 ~ /^[0-9]+$/ && NF >= 3 {
                s = $2; c = $3
                if (s == "direct") d = c
                else if (s ~ /^(grid3d|tiles3d|octree)\+/) { if (!bs || c < bs) { bs = c; ns = s } }
                else if (s ~ /^(grid|tiles|quadtree)\+/) { if (!bp || c < bp) { bp = c; np = s } }
            }
            END {
                if (!d || !bp || !bs) { printf "%-18s %-7s: the sweep lacks a figure\n", m, p; exit 1 }
                printf "%-18s %-7s %13d  %-34s %6.2fx  %-34s %6.2fx %7.2fx\n", m, p, d, np, d / bp, ns,
                       d / bs, bp / bs
            }'
    done
done
