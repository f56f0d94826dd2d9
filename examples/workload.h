/* The workloads' shared mesh code: the thesis' records (§3.1, §4.1), loading
 * a mesh file (or generating the default mesh) into plain arrays of them,
 * walking a vertex's one-ring, the tension field (§4.3.1) and FNV-1a.
 *
 * The programs are examples of what a user of emm writes: they keep the mesh
 * in their own arrays of fixed-size records and tell libemm where those are
 * (emm_tag_vertices / emm_tag_triangles, no-ops unless libemmshim.so is
 * preloaded). After read_mesh returns, every algorithm reads mesh data only
 * through the two arrays; application data (flags, marks, lists) lives in
 * separate arrays so the shim sees exactly the mesh accesses. */
#ifndef EMM_EXAMPLES_WORKLOAD_H
#define EMM_EXAMPLES_WORKLOAD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The thesis' struct Vertex: 4-byte name, 4 bytes of padding, coordinates at
 * byte 8, then up to 12 incident triangles. A vertex of a Delaunay mesh can
 * have more than 12; read_mesh keeps the 12 lowest ids, ascending, padded
 * with -1, so vfConnec[0] is always an incident triangle (-1 only for a
 * vertex no triangle uses) and the list is never assumed complete: one-rings
 * are walked through `neighbors` (vertex_fan). */
struct Vertex {
    uint32_t name;
    double coor[3];
    int32_t vfConnec[12];
};

/* The thesis' struct Triangle. neighbors[i] is the triangle across the edge
 * (vertexIndices[i], vertexIndices[(i+1) % 3]), -1 on the boundary. */
struct Triangle {
    uint32_t name;
    int32_t vertexIndices[3];
    int32_t neighbors[3];
};

_Static_assert(sizeof(struct Vertex) == 80, "struct Vertex must be the thesis' 80 bytes");
_Static_assert(sizeof(struct Triangle) == 28, "struct Triangle must be the thesis' 28 bytes");

struct Mesh {
    struct Vertex *vertices;
    struct Triangle *triangles;
    size_t verNr, triNr;
    double mean_edge; /* mean edge length, each edge counted once */
    double lo[3], hi[3]; /* bounding box */
    bool flat;           /* every z the same: the workloads' planar code paths */
};

/* Reads `path` (NULL: generates the default mesh, 20,000 clustered faces,
 * seed 1) into malloc'ed arrays, tags them, and frees libemm's copy. Also
 * rejects vertices whose triangles form more than one fan (the one-ring walk
 * needs a single fan). On failure prints "<prog>: <problem>" on stderr and
 * returns false. Never inlined: EMM_TAG rules select the arrays by the name
 * of the function that allocates them (site=read_mesh). */
bool read_mesh(const char *prog, const char *path, struct Mesh *mesh);
void free_mesh(struct Mesh *mesh);

/* The corner (0..2) of vertex v in triangle t, or -1. */
static inline int tri_corner(const struct Triangle *t, int32_t v)
{
    return t->vertexIndices[0] == v ? 0 : t->vertexIndices[1] == v ? 1
         : t->vertexIndices[2] == v ? 2 : -1;
}

/* Up to `cap` triangles around vertex v, in rotation order: starting from
 * vfConnec[0] and stepping across the edges at v; when a boundary edge stops
 * the walk, it goes on from vfConnec[0] the other way (those triangles come
 * first, so the list is one contiguous fan). The direction depends on the
 * triangles' orientation, which need not be consistent. Returns the fan's
 * size (which may exceed cap); *open says whether v is on the boundary. */
size_t vertex_fan(const struct Mesh *m, int32_t v, int32_t *fan, size_t cap, bool *open);

/* The triangle across the edge of t that joins v and w (-1 on the boundary). */
int32_t tri_across(const struct Mesh *m, int32_t t, int32_t v, int32_t w);

/* Command-line scaffolding shared by the three programs. */
struct workload_args {
    const char *mesh;  /* NULL: the default mesh */
    bool times;        /* --times: load and traversal seconds on stderr */
};

/* "PROG: msg: arg" and "Try 'PROG --help'." on stderr; returns 2, the
 * exit status of bad usage. `arg` may be NULL. */
int workload_usage_error(const char *prog, const char *msg, const char *arg);
/* The arguments every program takes: --times, and one MESH. Returns 0 when
 * `a` was one of them, or the exit status of bad usage (an unknown option,
 * a second mesh). */
int workload_common_arg(struct workload_args *args, const char *prog, const char *a);

double workload_now(void);
/* Prints "load: Xs  run: Ys" on stderr when args->times is set. */
void workload_report_times(const struct workload_args *args, double t0, double t1, double t2);

/* The tension field (thesis §4.3.1). See curve_tracing.c for what it is. */
enum field_kind { FIELD_TENSION = 0, FIELD_UNIFORM };
struct field {
    enum field_kind kind;
    double lo[2];   /* the mesh's bounding box maps to [0,1]² by this offset */
    double scale;   /* and this factor (1 / the longer side) */
    double mid[3];  /* in space: the bounding box's centre goes to (½, ½, ½) */
    double scale3;  /* scaled by 1 / its longest side */
};
void field_init(struct field *f, enum field_kind kind, const struct Mesh *m);
/* The field's vector at point (x, y) in mesh coordinates. */
void field_at(const struct field *f, double x, double y, double out[2]);
/* The field in space, for surfaces that are not flat: the gradient of a
 * potential over the bounding box mapped into [0,1]³ (not yet projected
 * onto any surface). */
void field_at3(const struct field *f, const double p[3], double out[3]);
bool field_parse(const char *name, enum field_kind *out);

/* FNV-1a, 64 bits, over bytes: the checksums the programs print. */
#define FNV1A64_INIT 0xcbf29ce484222325ull
uint64_t fnv1a64(uint64_t h, const void *data, size_t n);
/* FNV-1a over the decimal text of `value` followed by '\n', so a checksum is
 * the FNV-1a of the listing the program prints with its --print option. */
uint64_t fnv1a64_line(uint64_t h, const char *text);

#endif
