"""Checks a generated surface (an OFF file of 'emm mesh gen --surface'):
usage: surface_check.py FILE KIND FACES   (KIND: sphere | torus | terrain)

Exactly FACES triangles; every directed edge in at most one face (consistent
orientation) and, for the closed kinds, every edge in exactly two; no
triangle of zero area; the Euler characteristic of the kind (2 sphere, 0
torus, 1 terrain, a disc); normals outward (positive signed volume) for the
closed kinds, up (positive xy area) for the terrain. Prints one line of
facts, or FAIL lines and exits 1."""
import sys

path, kind, want = sys.argv[1], sys.argv[2], int(sys.argv[3])
with open(path) as f:
    words = f.read().split()
assert words[0] == "OFF"
nv, nf = int(words[1]), int(words[2])
pos = 4
xyz = [tuple(float(w) for w in words[pos + 3 * i:pos + 3 * i + 3]) for i in range(nv)]
pos += 3 * nv
tris = []
for _ in range(nf):
    assert words[pos] == "3"
    tris.append(tuple(int(w) for w in words[pos + 1:pos + 4]))
    pos += 4

fails = []
if nf != want:
    fails.append(f"{nf} faces, not {want}")
directed, undirected = set(), {}
volume = area_xy = 0.0
min_area = float("inf")
for a, b, c in tris:
    for e in ((a, b), (b, c), (c, a)):
        if e in directed:
            fails.append(f"directed edge {e} twice: orientation or manifold")
        directed.add(e)
        k = (min(e), max(e))
        undirected[k] = undirected.get(k, 0) + 1
    p, q, r = xyz[a], xyz[b], xyz[c]
    u = [q[i] - p[i] for i in range(3)]
    v = [r[i] - p[i] for i in range(3)]
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    min_area = min(min_area, 0.5 * sum(x * x for x in n) ** 0.5)
    volume += sum(p[i] * n[i] for i in range(3)) / 6
    area_xy += n[2] / 2
closed = kind != "terrain"
counts = set(undirected.values())
if closed and counts != {2}:
    fails.append(f"edges in {sorted(counts)} faces, not all in 2")
if not closed and not counts <= {1, 2}:
    fails.append(f"edges in {sorted(counts)} faces")
used = {v for t in tris for v in t}
if len(used) != nv:
    fails.append(f"{nv - len(used)} vertices unused")
euler = nv - len(undirected) + nf
if euler != {"sphere": 2, "torus": 0, "terrain": 1}[kind]:
    fails.append(f"Euler characteristic {euler}")
if not min_area > 0:
    fails.append(f"a degenerate triangle (area {min_area})")
if closed and not volume > 0:
    fails.append(f"signed volume {volume}: normals inward")
if not closed and not area_xy > 0:
    fails.append(f"xy area {area_xy}: normals down")
for f in fails:
    print(f"FAIL: {path}: {f}")
if not fails:
    print(f"ok: {path}: {nf} faces, {nv} vertices, Euler {euler}, "
          f"smallest area {min_area:.3g}, volume {volume:.4g}")
sys.exit(1 if fails else 0)
