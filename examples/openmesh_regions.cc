// openmesh_regions — a traversal of our own over OpenMesh's half-edge
// mesh, with nothing of emm in it: emm finds its arrays with
// `--tag openmesh` (docs/tagging.md "Half-edge meshes").
//
//   openmesh_regions MESH [--seed F]
//
// Reads MESH with OpenMesh's readers (OFF, OBJ, PLY, STL), then
//  1. grows regions over the faces breadth-first from face F (default 0)
//     with OpenMesh's face-face circulator: a face joins its neighbour's
//     region when their normals differ by less than 30 degrees; a face no
//     region reached seeds the next one;
//  2. walks from face F across edges towards the mesh's farthest vertex
//     from F's centroid (a visibility walk: at each face, across the edge
//     whose opposite face's centroid is nearest the target), with the
//     half-edge circulator of each face, until no neighbour is nearer.
// Prints "faces: N\nregions: R\nlargest: L\nwalk: S steps to face G\n
// checksum: 0x...\n" (the FNV-1a of every face's region number). Exit
// status 0, or 1 with a message on a mesh it cannot read.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <vector>

typedef OpenMesh::TriMesh_ArrayKernelT<> Mesh;

static OpenMesh::Vec3f centroid(const Mesh &m, Mesh::FaceHandle f)
{
    OpenMesh::Vec3f c(0, 0, 0);
    int n = 0;
    for (Mesh::ConstFaceVertexIter v = m.cfv_iter(f); v.is_valid(); ++v, ++n)
        c += m.point(*v);
    return n ? c / float(n) : c;
}

static OpenMesh::Vec3f normal(const Mesh &m, Mesh::FaceHandle f)
{
    Mesh::ConstFaceHalfedgeIter h = m.cfh_iter(f);
    OpenMesh::Vec3f a = m.point(m.to_vertex_handle(*h));
    ++h;
    OpenMesh::Vec3f b = m.point(m.to_vertex_handle(*h));
    ++h;
    OpenMesh::Vec3f c = m.point(m.to_vertex_handle(*h));
    OpenMesh::Vec3f n = OpenMesh::cross(b - a, c - a);
    float l = n.norm();
    return l > 0 ? n / l : n;
}

int main(int argc, char **argv)
{
    const char *path = nullptr;
    long seed = 0;
    for (int i = 1; i < argc; i++) {
        if (std::strcmp(argv[i], "--seed") == 0 && i + 1 < argc)
            seed = std::strtol(argv[++i], nullptr, 10);
        else if (!path)
            path = argv[i];
        else {
            std::fprintf(stderr, "usage: openmesh_regions MESH [--seed F]\n");
            return 2;
        }
    }
    if (!path) {
        std::fprintf(stderr, "usage: openmesh_regions MESH [--seed F]\n");
        return 2;
    }
    Mesh mesh;
    if (!OpenMesh::IO::read_mesh(mesh, path) || mesh.n_faces() == 0) {
        std::fprintf(stderr, "openmesh_regions: %s: cannot read a mesh with faces\n", path);
        return 1;
    }
    size_t nf = mesh.n_faces();
    if (seed < 0 || (size_t)seed >= nf)
        seed = 0;

    // 1. Region growing over faces, breadth-first with the face-face circulator.
    std::vector<OpenMesh::Vec3f> fn(nf);
    for (size_t i = 0; i < nf; i++)
        fn[i] = normal(mesh, mesh.face_handle((unsigned)i));
    const float cos_limit = std::cos(30.0f * 3.14159265f / 180.0f);
    std::vector<int> region(nf, -1);
    std::vector<size_t> size;
    std::deque<Mesh::FaceHandle> queue;
    size_t next = (size_t)seed;
    for (size_t done = 0; done < nf; next = (next + 1) % nf) {
        if (region[next] >= 0)
            continue;
        int r = (int)size.size();
        size.push_back(0);
        region[next] = r;
        queue.push_back(mesh.face_handle((unsigned)next));
        while (!queue.empty()) {
            Mesh::FaceHandle f = queue.front();
            queue.pop_front();
            size[r]++;
            done++;
            for (Mesh::ConstFaceFaceIter g = mesh.cff_iter(f); g.is_valid(); ++g) {
                if (region[g->idx()] >= 0 || (fn[f.idx()] | fn[g->idx()]) < cos_limit)
                    continue;
                region[g->idx()] = r;
                queue.push_back(*g);
            }
        }
    }
    size_t largest = 0;
    for (size_t s : size)
        largest = s > largest ? s : largest;

    // 2. A visibility walk from the seed towards the farthest vertex.
    Mesh::FaceHandle at = mesh.face_handle((unsigned)seed);
    OpenMesh::Vec3f from = centroid(mesh, at), target = from;
    float far = -1;
    for (Mesh::ConstVertexIter v = mesh.vertices_begin(); v != mesh.vertices_end(); ++v) {
        float d = (mesh.point(*v) - from).sqrnorm();
        if (d > far) {
            far = d;
            target = mesh.point(*v);
        }
    }
    size_t steps = 0;
    for (;;) {
        float best = (centroid(mesh, at) - target).sqrnorm();
        Mesh::FaceHandle step;
        for (Mesh::ConstFaceHalfedgeIter h = mesh.cfh_iter(at); h.is_valid(); ++h) {
            Mesh::HalfedgeHandle o = mesh.opposite_halfedge_handle(*h);
            if (mesh.is_boundary(o))
                continue;
            Mesh::FaceHandle g = mesh.face_handle(o);
            float d = (centroid(mesh, g) - target).sqrnorm();
            if (d < best) {
                best = d;
                step = g;
            }
        }
        if (!step.is_valid())
            break;
        at = step;
        steps++;
    }

    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < nf; i++) {
        uint32_t r = (uint32_t)region[i];
        for (int k = 0; k < 4; k++)
            h = (h ^ ((r >> (8 * k)) & 0xff)) * 1099511628211ull;
    }
    std::printf("faces: %zu\nregions: %zu\nlargest: %zu\nwalk: %zu steps to face %d\n"
                "checksum: 0x%016llx\n",
                nf, size.size(), largest, steps, at.idx(), (unsigned long long)h);
    return 0;
}
