#!/bin/sh
# The workloads on the 3D surfaces of 'emm mesh gen --surface'.
#
# region_growing grows over edge neighbours only: from triangle 0 it conquers
# every vertex of the closed sphere and torus once (codes = vertices) and the
# terrain's too; --conquest finds the torus' handle (1 merge), none on the
# sphere (its invariants check the rest).
#
# curve_tracing walks each triangle's plane: on a sphere in the uniform
# field (1, 0, 0), projected, every --long curve runs along its meridian from
# its seed to the sink (1, 0, 0) and stops just past it, so the total length
# is the sum of the seeds' great-circle distances arccos(x / |p|) plus less
# than one step (half the mean edge) per curve; computed here with python.
# The tension field gives curves of positive length on all three surfaces.
. "$(dirname "$0")/lib.sh"
bin=$1
work=$4
emm=$bin/emm
py=/usr/bin/python3
rm -rf "$work" && mkdir -p "$work" || exit 1

"$emm" mesh gen --surface sphere --faces 6000 --seed 3 -o "$work/sphere.off" >/dev/null || fail "gen sphere"
"$emm" mesh gen --surface torus --faces 6000 --seed 3 -o "$work/torus.off" >/dev/null || fail "gen torus"
"$emm" mesh gen --surface terrain --faces 6001 --seed 3 -o "$work/terrain.off" >/dev/null || fail "gen terrain"

for s in sphere torus terrain; do
    verts=$("$emm" mesh info "$work/$s.off" | sed -n 's/^vertices: //p')
    out=$("$bin/region_growing" "$work/$s.off") || fail "region_growing $s exited $?"
    echo "$out" | grep -qx "codes: $verts" || fail "region_growing $s: $out, not $verts codes"
    out=$("$bin/region_growing" --conquest "$work/$s.off") || fail "--conquest $s exited $?"
    want=0
    [ $s = torus ] && want=1
    echo "$out" | grep -qx "merges: $want" || fail "--conquest $s: $out, not $want merges"
    for mode in --short --long; do
        out=$("$bin/curve_tracing" $mode "$work/$s.off") || fail "curve_tracing $mode $s exited $?"
        echo "$s $mode: $(echo $out)"
        echo "$out" | awk '/^curves:/ { c = $2 } /^length:/ { l = $2 }
            END { exit !(c >= 30 && l > 0) }' || fail "curve_tracing $mode $s: $out"
    done
done

out=$("$bin/curve_tracing" --long --field uniform --curves 200 "$work/sphere.off") ||
    fail "uniform field exited $?"
edge=$("$emm" mesh info "$work/sphere.off" | sed -n 's/^mean edge length: //p')
echo "$out" | "$py" -c '
import math, sys
path, curves, half_edge = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]) / 2
got = dict(line.split(": ") for line in sys.stdin.read().splitlines())
w = open(path).read().split()
nv = int(w[1])
xyz = [[float(v) for v in w[4 + 3 * i:7 + 3 * i]] for i in range(nv)]
want = 0.0
for i in range(curves):
    p = xyz[i * nv // curves]
    want += math.acos(max(-1.0, min(1.0, p[0] / math.sqrt(sum(c * c for c in p)))))
length = float(got["length"])
print(f"uniform field on the sphere: length {length:.4f}, geodesics {want:.4f}, "
      f"allowed excess {curves * half_edge:.4f}")
sys.exit(0 if got["curves"] == str(curves) and want - 1e-6 <= length <= want + curves * half_edge else 1)
' "$work/sphere.off" 200 "$edge" || fail "uniform field on the sphere: $out"
echo ok
