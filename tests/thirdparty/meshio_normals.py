"""A mesh program on meshio and numpy, as a user writes one: read a mesh,
compute each vertex's area-weighted normal by gathering the corners of
every triangle (numpy's fancy indexing walks the vertices in triangle
order), and write the mesh as OFF (meshio's OFF writer puts no date in
the file) and the normals as text beside it, OUT.normals.

    python3 meshio_normals.py IN OUT
"""
import sys

import meshio
import numpy as np


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: meshio_normals.py IN OUT")
    mesh = meshio.read(sys.argv[1])
    points = np.ascontiguousarray(mesh.points, dtype=np.float64)
    tris = np.ascontiguousarray(mesh.get_cells_type("triangle"), dtype=np.int32)
    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    face = np.cross(b - a, c - a)
    normals = np.zeros_like(points)
    for k in range(3):
        np.add.at(normals, tris[:, k], face)
    length = np.linalg.norm(normals, axis=1)
    length[length == 0] = 1
    normals /= length[:, None]
    meshio.write(sys.argv[2], meshio.Mesh(points, [("triangle", tris)]), file_format="off")
    np.savetxt(sys.argv[2] + ".normals", normals, fmt="%.9f")
    print("vertices: %d\ntriangles: %d" % (len(points), len(tris)))


if __name__ == "__main__":
    main()
