/* emm — the mesh model (thesis §3.1) and the thesis' interface (§5) in C.
 *
 * A triangle mesh: a vertex array (id, coordinates) and a triangle array
 * (id, three vertex ids, three edge-neighbour ids). Vertex→triangle incidence
 * is stored with offsets (no fixed slot count). Files are read by emm's own
 * parsers (OFF, OBJ, PLY ascii and binary, STL); polygons are
 * fan-triangulated around their first vertex. Every mesh this API returns is
 * valid: finite coordinates, in-range indices, no repeated vertex in a face,
 * every edge shared by at most two triangles. */
#ifndef EMM_MESH_H
#define EMM_MESH_H

#include "emm/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct emm_mesh emm_mesh;

typedef struct emm_vertex {
    uint32_t id;
    double xyz[3];
} emm_vertex;

/* n[i] is the triangle across the edge (v[i], v[(i+1) % 3]), or -1 where that
 * edge is on the boundary. */
typedef struct emm_triangle {
    uint32_t id;
    int32_t v[3];
    int32_t n[3];
} emm_triangle;

/* EMM_THESIS_VERTEX_BYTES and EMM_THESIS_TRIANGLE_BYTES: emm/common.h. */

/* Reads a mesh file. On success *out owns a new mesh (free it with
 * emm_mesh_free). On failure *out is NULL and err names the file and the
 * problem: missing or empty file, truncated file, out-of-range index, NaN or
 * infinite coordinate, non-manifold edge, degenerate (repeated-vertex) face. */
EMM_API emm_status emm_mesh_open(const char *path, emm_mesh **out, emm_error *err);

/* Builds a mesh from arrays the caller keeps owning: `xyz` holds 3*nv
 * coordinates, `tri` 3*nt vertex indices. `name` (may be NULL) is used in
 * error messages. Validates exactly as emm_mesh_open does. */
EMM_API emm_status emm_mesh_from_arrays(const double *xyz, size_t nv,
                                        const int32_t *tri, size_t nt,
                                        const char *name, emm_mesh **out,
                                        emm_error *err);

/* Frees a mesh; NULL is allowed. */
EMM_API void emm_mesh_free(emm_mesh *m);

/* Writes the mesh as an ASCII OFF file, whole or not at all (a temporary
 * file renamed into place). */
EMM_API emm_status emm_mesh_write_off(const emm_mesh *m, const char *path, emm_error *err);
/* The same as a Wavefront OBJ file ("v x y z" lines, then "f a b c" with
 * 1-based indices). */
EMM_API emm_status emm_mesh_write_obj(const emm_mesh *m, const char *path, emm_error *err);

EMM_API size_t emm_mesh_vertex_count(const emm_mesh *m);
EMM_API size_t emm_mesh_triangle_count(const emm_mesh *m);
/* Number of edges that belong to exactly one triangle. */
EMM_API size_t emm_mesh_boundary_edges(const emm_mesh *m);
/* Number of faces in the file that had more than three corners and were
 * fan-triangulated (0 for a mesh built from arrays). */
EMM_API size_t emm_mesh_polygons_split(const emm_mesh *m);
/* Axis-aligned bounding box. */
EMM_API void emm_mesh_bbox(const emm_mesh *m, double lo[3], double hi[3]);
/* Mean length of the mesh's edges (each edge counted once). */
EMM_API double emm_mesh_mean_edge_length(const emm_mesh *m);

/* The mesh as two packed arrays, for code that walks it in bulk (layouts,
 * the shim's geometry snapshot): 3 * vertex_count coordinates (x, y, z per
 * vertex) and 3 * triangle_count vertex indices. Owned by the mesh, valid
 * until it is freed. */
EMM_API const double *emm_mesh_positions(const emm_mesh *m);
EMM_API const int32_t *emm_mesh_indices(const emm_mesh *m);

/* The thesis' interface (§5). Ids are checked by assert. The returned
 * pointers stay valid until the mesh is freed. */
EMM_API const emm_vertex *emm_mesh_vertex(const emm_mesh *m, uint32_t id);
EMM_API const emm_triangle *emm_mesh_triangle(const emm_mesh *m, uint32_t id);
/* The triangles incident to vertex v, in ascending id; returns their count
 * and points *tris at them. */
EMM_API size_t emm_vertex_triangles(const emm_mesh *m, uint32_t v, const int32_t **tris);
EMM_API void emm_triangle_vertices(const emm_mesh *m, uint32_t t, int32_t out[3]);
EMM_API void emm_triangle_neighbors(const emm_mesh *m, uint32_t t, int32_t out[3]);
/* Per-vertex and per-triangle user data: one pointer each, NULL at first;
 * the mesh never dereferences or frees it. */
EMM_API void emm_vertex_set_data(emm_mesh *m, uint32_t v, void *data);
EMM_API void *emm_vertex_data(const emm_mesh *m, uint32_t v);
EMM_API void emm_triangle_set_data(emm_mesh *m, uint32_t t, void *data);
EMM_API void *emm_triangle_data(const emm_mesh *m, uint32_t t);

/* The generator (docs/design.md "Workloads"): a planar (z = 0) Delaunay
 * triangulation, computed with libqhull, of points drawn in the unit square.
 * `clustered` draws most points around a few Gaussian clusters over a uniform
 * background (the thesis' non-uniform mesh); `uniform` draws them all
 * uniformly. The face count lands within 1% of `faces`; the same options give
 * the same mesh, bit for bit. */
typedef enum emm_density { EMM_DENSITY_CLUSTERED = 0, EMM_DENSITY_UNIFORM } emm_density;

/* How the generated mesh's vertices and triangles are numbered: `made`
 * keeps the order the points were drawn in and qhull's facet order (qhull
 * builds facets as it sweeps, so the faces come out spatially coherent);
 * `random` numbers both in a random order drawn from the seed — the
 * "unorganized (or unknown)" original of the thesis (§3.1, §6.3); `hilbert`
 * renumbers both along a Hilbert curve, as a mesher that orders for
 * locality would. */
typedef enum emm_order {
    EMM_ORDER_MADE = 0,
    EMM_ORDER_RANDOM,
    EMM_ORDER_HILBERT
} emm_order;
/* The name used before `random` existed. */
#define EMM_ORDER_INPUT EMM_ORDER_MADE

/* The shape emm_mesh_generate_surface makes. `plane` is the planar
 * Delaunay mesh of emm_mesh_generate. The others are 3D surfaces
 * built as grids, exactly `faces` triangles, consistently oriented (normals
 * outward, or up for the terrain), vertices jittered from the seed:
 * `sphere` (radius 1; genus 0, faces even and >= 20) is one spiral strip of
 * triangles wound from pole to pole and closed by a fan at each pole, a UV
 * sphere without seams; `torus` (radii 1 and 0.4; faces even and >= 20) is
 * one helical strip closed on itself; `terrain` (faces >= 8) is an open
 * height field z = f(x, y) over the unit square, Gaussian hills from the
 * seed, a grid of quads split along their shorter diagonal (the last row
 * may be partial, and an odd count ends in one triangle). `density` applies
 * to `plane` only. With EMM_ORDER_HILBERT a surface is numbered along a 3D
 * Hilbert curve (vertices by position, triangles by centroid). */
typedef enum emm_surface {
    EMM_SURFACE_PLANE = 0,
    EMM_SURFACE_SPHERE,
    EMM_SURFACE_TORUS,
    EMM_SURFACE_TERRAIN
} emm_surface;

typedef struct emm_gen_options {
    size_t faces;        /* wanted triangle count, >= 8 */
    uint64_t seed;
    emm_density density;
    emm_order order;
} emm_gen_options;

/* The thesis' mesh: 20,000 faces, clustered, seed 1. */
#define EMM_DEFAULT_FACES 20000u
#define EMM_DEFAULT_SEED 1u

EMM_API emm_status emm_mesh_generate(const emm_gen_options *opt, emm_mesh **out, emm_error *err);

/* The same for `surface` (see emm_surface; EMM_SURFACE_PLANE is
 * emm_mesh_generate). Fails with EMM_ERR_RANGE, naming the surface, for a
 * face count it cannot make exactly. */
EMM_API emm_status emm_mesh_generate_surface(const emm_gen_options *opt, emm_surface surface,
                                             emm_mesh **out, emm_error *err);

#ifdef __cplusplus
}
#endif
#endif
