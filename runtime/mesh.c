/* The mesh model (thesis §3.1) and the thesis' access interface (§5) in C.
 *
 * A mesh is built once, from arrays or from a file, and checked as it is
 * built: finite coordinates, in-range indices, no repeated vertex in a face,
 * no edge in more than two triangles. Whatever cannot pass is an error that
 * names the input and the problem, so every emm_mesh is one the layouts and
 * the workloads can trust.
 *
 * Decisions:
 * - Polygons are fan-triangulated around their first corner (v0 v1 v2,
 *   v0 v2 v3, ...); emm_mesh_polygons_split counts them. A non-convex
 *   polygon's fan can fold over itself; the file is taken as it says.
 * - Orientation is not checked: neighbours are found by undirected edge, so
 *   a mesh whose faces disagree on winding still gets every neighbour (the
 *   thesis' workloads walk adjacency, not normals).
 * - Only edges must be manifold. Two fans that touch at one vertex (a
 *   "bow-tie" vertex) and vertices no face uses are accepted; such a vertex
 *   simply has a split or empty triangle list.
 * - Adjacency is built in O(V + T): triangles are bucketed per vertex (the
 *   offsets of the incidence table), then each edge is met from its lower
 *   vertex with a per-vertex stamp, so even a vertex with a million
 *   triangles costs linear time. */
#include "mesh_internal.h"

#include "error.h"
#include "infile.h"
#include "mesh_io.h"
#include "outfile.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#define MESH_NAME(name) ((name) ? (name) : "mesh")

static emm_status out_of_memory(const char *name, emm_error *err)
{
    return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
}

void emm_mesh_free(emm_mesh *m)
{
    if (!m)
        return;
    free(m->vertex);
    free(m->triangle);
    free(m->xyz);
    free(m->index);
    free(m->vt_start);
    free(m->vt);
    free(m->vertex_data);
    free(m->triangle_data);
    free(m);
}

/* ---- building ----------------------------------------------------------- */

/* Finds every triangle's three edge neighbours and the edge statistics.
 * Each undirected edge (a, b), a < b, is met while scanning the triangles
 * around a: stamp[b] == a says it was met before at first[b]. */
static emm_status link_neighbours(emm_mesh *m, const char *name, int base, emm_error *err)
{
    int32_t *stamp = malloc(m->nv * sizeof *stamp);
    size_t *first = malloc(m->nv * sizeof *first);
    uint32_t *count = malloc(m->nv * sizeof *count);
    if (!stamp || !first || !count) {
        free(stamp);
        free(first);
        free(count);
        return out_of_memory(name, err);
    }
    for (size_t i = 0; i < m->nv; i++)
        stamp[i] = -1;

    emm_status st = EMM_OK;
    size_t edges = 0, interior = 0;
    double length = 0;
    for (size_t a = 0; a < m->nv && st == EMM_OK; a++) {
        int32_t bad = -1;
        for (size_t k = m->vt_start[a]; k < m->vt_start[a + 1]; k++) {
            size_t t = (size_t)m->vt[k];
            const int32_t *v = m->triangle[t].v;
            for (int s = 0; s < 3; s++) {
                int32_t x = v[s], y = v[(s + 1) % 3];
                if ((size_t)(x < y ? x : y) != a)
                    continue;
                int32_t b = x < y ? y : x;
                if (stamp[b] != (int32_t)a) {
                    stamp[b] = (int32_t)a;
                    first[b] = 3 * t + (size_t)s;
                    count[b] = 1;
                    edges++;
                    const double *p = m->vertex[a].xyz, *q = m->vertex[b].xyz;
                    length += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                   (p[2] - q[2]) * (p[2] - q[2]));
                } else if (++count[b] == 2) {
                    size_t u = first[b] / 3;
                    m->triangle[u].n[first[b] % 3] = (int32_t)t;
                    m->triangle[t].n[s] = (int32_t)u;
                    interior++;
                } else if (bad < 0) {
                    bad = b;
                }
            }
        }
        if (bad >= 0)
            st = emm_fail(err, EMM_ERR_MESH, "%s: edge (%lld, %lld) is shared by %u faces (non-manifold)",
                          name, (long long)a + base, (long long)bad + base, count[bad]);
    }
    m->edges = edges;
    m->boundary_edges = edges - interior;
    m->mean_edge = edges ? length / (double)edges : 0.0;
    free(stamp);
    free(first);
    free(count);
    return st;
}

/* The incidence table: per vertex, its triangles in ascending id (a
 * counting sort, so ascending falls out of scanning triangles in order). */
static emm_status build_incidence(emm_mesh *m, const char *name, emm_error *err)
{
    m->vt_start = calloc(m->nv + 1, sizeof *m->vt_start);
    m->vt = malloc(3 * m->nt * sizeof *m->vt);
    if (!m->vt_start || !m->vt)
        return out_of_memory(name, err);
    for (size_t i = 0; i < 3 * m->nt; i++)
        m->vt_start[m->index[i] + 1]++;
    for (size_t v = 0; v < m->nv; v++)
        m->vt_start[v + 1] += m->vt_start[v];
    size_t *fill = malloc((m->nv ? m->nv : 1) * sizeof *fill);
    if (!fill)
        return out_of_memory(name, err);
    memcpy(fill, m->vt_start, m->nv * sizeof *fill);
    for (size_t t = 0; t < m->nt; t++)
        for (int c = 0; c < 3; c++)
            m->vt[fill[m->index[3 * t + (size_t)c]]++] = (int32_t)t;
    free(fill);
    return EMM_OK;
}

/* Builds a mesh from arrays whose indices are already known to be in range
 * and distinct within each triangle; checks coordinates and edges. `base` is
 * how the input numbers vertices (1 for OBJ), used in messages. */
static emm_status build(const double *xyz, size_t nv, const int32_t *tri, size_t nt, const char *name,
                        int base, size_t split, emm_mesh **out, emm_error *err)
{
    for (size_t v = 0; v < nv; v++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(xyz[3 * v + (size_t)k]))
                return emm_fail(err, EMM_ERR_MESH, "%s: vertex %zu has a non-finite coordinate (%g)", name,
                                v + (size_t)base, xyz[3 * v + (size_t)k]);

    emm_mesh *m = calloc(1, sizeof *m);
    if (!m)
        return out_of_memory(name, err);
    m->nv = nv;
    m->nt = nt;
    m->polygons_split = split;
    m->vertex = malloc(nv * sizeof *m->vertex);
    m->triangle = malloc(nt * sizeof *m->triangle);
    m->xyz = malloc(3 * nv * sizeof *m->xyz);
    m->index = malloc(3 * nt * sizeof *m->index);
    m->vertex_data = calloc(nv, sizeof *m->vertex_data);
    m->triangle_data = calloc(nt, sizeof *m->triangle_data);
    if (!m->vertex || !m->triangle || !m->xyz || !m->index || !m->vertex_data || !m->triangle_data) {
        emm_mesh_free(m);
        return out_of_memory(name, err);
    }
    memcpy(m->xyz, xyz, 3 * nv * sizeof *m->xyz);
    memcpy(m->index, tri, 3 * nt * sizeof *m->index);
    for (int k = 0; k < 3; k++) {
        m->lo[k] = INFINITY;
        m->hi[k] = -INFINITY;
    }
    for (size_t v = 0; v < nv; v++) {
        m->vertex[v].id = (uint32_t)v;
        for (int k = 0; k < 3; k++) {
            double c = xyz[3 * v + (size_t)k];
            m->vertex[v].xyz[k] = c;
            if (c < m->lo[k]) m->lo[k] = c;
            if (c > m->hi[k]) m->hi[k] = c;
        }
    }
    for (size_t t = 0; t < nt; t++) {
        m->triangle[t].id = (uint32_t)t;
        for (int k = 0; k < 3; k++) {
            m->triangle[t].v[k] = tri[3 * t + (size_t)k];
            m->triangle[t].n[k] = -1;
        }
    }
    emm_status st = build_incidence(m, name, err);
    if (st == EMM_OK)
        st = link_neighbours(m, name, base, err);
    if (st != EMM_OK) {
        emm_mesh_free(m);
        return st;
    }
    *out = m;
    return EMM_OK;
}

emm_status emm_mesh_from_arrays(const double *xyz, size_t nv, const int32_t *tri, size_t nt, const char *name,
                                emm_mesh **out, emm_error *err)
{
    assert(out);
    assert(xyz || nv == 0);
    assert(tri || nt == 0);
    *out = NULL;
    name = MESH_NAME(name);
    if (nt == 0)
        return emm_fail(err, EMM_ERR_MESH, "%s: no triangles", name);
    if (nv > INT32_MAX || nt > INT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE, "%s: %zu vertices and %zu triangles; emm takes at most %d of each",
                        name, nv, nt, INT32_MAX);
    for (size_t t = 0; t < nt; t++) {
        const int32_t *v = tri + 3 * t;
        for (int k = 0; k < 3; k++)
            if (v[k] < 0 || (size_t)v[k] >= nv)
                return emm_fail(err, EMM_ERR_MESH, "%s: triangle %zu refers to vertex %d, but the mesh has %zu vertices",
                                name, t, v[k], nv);
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            return emm_fail(err, EMM_ERR_MESH, "%s: triangle %zu (%d, %d, %d) repeats a vertex (degenerate face)",
                            name, t, v[0], v[1], v[2]);
    }
    return build(xyz, nv, tri, nt, name, 0, 0, out, err);
}

/* ---- reading files ------------------------------------------------------ */

typedef enum file_kind { KIND_OFF, KIND_OBJ, KIND_PLY, KIND_STL, KIND_UNKNOWN } file_kind;

static file_kind kind_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash : path, '.');
    if (!dot)
        return KIND_UNKNOWN;
    static const char *const ext[] = { ".off", ".obj", ".ply", ".stl" };
    for (int k = 0; k < 4; k++)
        if (strcasecmp(dot, ext[k]) == 0)
            return (file_kind)k;
    return KIND_UNKNOWN;
}

/* "<path>: line L: face F" or "<path>: face F" where the reader knows no lines. */
static void face_place(char *buf, size_t cap, const char *path, const emm_raw_mesh *r, size_t f)
{
    if (r->face_line)
        snprintf(buf, cap, "%s: line %zu: face %zu", path, r->face_line[f], f + (size_t)r->index_base);
    else
        snprintf(buf, cap, "%s: face %zu", path, f + (size_t)r->index_base);
}

/* A vertex that face f lists twice, found in O(k) with a stamp per vertex
 * (stamp[v] == f + 1: v already met in f), so a face with a million
 * corners costs a million steps, not 10^12. */
static bool has_repeat(const int64_t *c, size_t k, size_t f, size_t *stamp, int64_t *which)
{
    for (size_t i = 0; i < k; i++) {
        if (stamp[c[i]] == f + 1) {
            *which = c[i];
            return true;
        }
        stamp[c[i]] = f + 1;
    }
    return false;
}

static emm_status check_face_list(const char *path, const emm_raw_mesh *r, size_t *stamp, size_t *nt,
                                  size_t *split, emm_error *err);

static emm_status check_faces(const char *path, const emm_raw_mesh *r, size_t *nt, size_t *split, emm_error *err)
{
    *nt = 0;
    *split = 0;
    size_t *stamp = calloc(r->nv ? r->nv : 1, sizeof *stamp);
    if (!stamp)
        return out_of_memory(path, err);
    emm_status st = check_face_list(path, r, stamp, nt, split, err);
    free(stamp);
    return st;
}

static emm_status check_face_list(const char *path, const emm_raw_mesh *r, size_t *stamp, size_t *nt,
                                  size_t *split, emm_error *err)
{
    char place[600];
    long long base = r->index_base;
    for (size_t f = 0; f < r->nf; f++) {
        size_t k = r->face_start[f + 1] - r->face_start[f];
        if (k < 3) {
            face_place(place, sizeof place, path, r, f);
            return emm_fail(err, EMM_ERR_MESH, "%s has %zu corners; a face needs at least 3", place, k);
        }
        /* Only now: with no corner in the whole file, corner is NULL. */
        const int64_t *c = r->corner + r->face_start[f];
        for (size_t i = 0; i < k; i++)
            if (c[i] < 0 || (uint64_t)c[i] >= r->nv) {
                face_place(place, sizeof place, path, r, f);
                return emm_fail(err, EMM_ERR_MESH, "%s refers to vertex %lld, but the file has %zu vertices",
                                place, (long long)c[i] + base, r->nv);
            }
        int64_t v;
        if (has_repeat(c, k, f, stamp, &v)) {
            face_place(place, sizeof place, path, r, f);
            return emm_fail(err, EMM_ERR_MESH, "%s repeats vertex %lld (degenerate face)", place,
                            (long long)v + base);
        }
        *nt += k - 2;
        *split += k > 3;
    }
    if (*nt > INT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE, "%s: %zu triangles; emm takes at most %d", path, *nt, INT32_MAX);
    return EMM_OK;
}

emm_status emm_mesh_open(const char *path, emm_mesh **out, emm_error *err)
{
    assert(path && out);
    *out = NULL;
    struct stat sb;
    if (stat(path, &sb) != 0)
        return emm_fail(err, EMM_ERR_IO, "%s: %s", path, strerror(errno));
    if (S_ISDIR(sb.st_mode))
        return emm_fail(err, EMM_ERR_IO, "%s: is a directory, not a mesh file", path);
    file_kind kind = kind_of(path);
    if (kind == KIND_UNKNOWN)
        return emm_fail(err, EMM_ERR_UNSUPPORTED,
                        "%s: unknown mesh file extension (emm reads .off, .obj, .ply and .stl)", path);

    /* The whole file in memory: every reader parses bytes, and allocates
     * only for what the bytes hold, so memory stays a small multiple of the
     * file's size whatever its header declares. */
    char *data;
    size_t len;
    emm_status st = emm_infile_read(path, "mesh file", SIZE_MAX, &data, &len, err);
    if (st != EMM_OK)
        return st;
    st = emm_mesh_parse(path, data, len, out, err);
    free(data);
    return st;
}

emm_status emm_mesh_parse(const char *path, const char *data, size_t len, emm_mesh **out, emm_error *err)
{
    *out = NULL;
    file_kind kind = kind_of(path);
    if (kind == KIND_UNKNOWN)
        return emm_fail(err, EMM_ERR_UNSUPPORTED,
                        "%s: unknown mesh file extension (emm reads .off, .obj, .ply and .stl)", path);
    if (len == 0)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: empty file", path);
    emm_raw_mesh raw;
    memset(&raw, 0, sizeof raw);
    emm_status st;
    switch (kind) {
    case KIND_OFF:
        st = emm_read_off(path, data, len, &raw, err);
        if (st == EMM_ERR_UNSUPPORTED)
            st = emm_read_off_binary(path, data, len, &raw, err);
        break;
    case KIND_OBJ: st = emm_read_obj(path, data, len, &raw, err); break;
    case KIND_PLY: st = emm_read_ply(path, data, len, &raw, err); break;
    default: st = emm_read_stl(path, data, len, &raw, err); break;
    }
    if (st != EMM_OK)
        return st;

    size_t nt = 0, split = 0;
    if (raw.nf == 0)
        st = emm_fail(err, EMM_ERR_MESH, "%s: no faces (%zu vertices and no faces: not a surface mesh)", path, raw.nv);
    else if (raw.nv > INT32_MAX)
        st = emm_fail(err, EMM_ERR_RANGE, "%s: %zu vertices; emm takes at most %d", path, raw.nv, INT32_MAX);
    else
        st = check_faces(path, &raw, &nt, &split, err);
    int32_t *tri = NULL;
    if (st == EMM_OK && !(tri = malloc(3 * nt * sizeof *tri)))
        st = out_of_memory(path, err);
    if (st == EMM_OK) {
        /* Fan triangulation around each face's first corner. */
        size_t t = 0;
        for (size_t f = 0; f < raw.nf; f++) {
            const int64_t *c = raw.corner + raw.face_start[f];
            size_t k = raw.face_start[f + 1] - raw.face_start[f];
            for (size_t i = 1; i + 1 < k; i++, t++) {
                tri[3 * t] = (int32_t)c[0];
                tri[3 * t + 1] = (int32_t)c[i];
                tri[3 * t + 2] = (int32_t)c[i + 1];
            }
        }
        st = build(raw.xyz, raw.nv, tri, nt, path, raw.index_base, split, out, err);
    }
    free(tri);
    emm_raw_mesh_free(&raw);
    return st;
}

/* ---- writing ------------------------------------------------------------ */

/* OFF or OBJ text: the same vertices (%.17g, read back bit for bit) and
 * faces, with each format's header, prefixes and index base. */
static emm_status write_text(const emm_mesh *m, const char *path, bool obj, emm_error *err)
{
    assert(m && path);
    emm_outfile o;
    emm_status st = emm_outfile_open(&o, path, "the mesh", err);
    if (st != EMM_OK)
        return st;
    const char *v_prefix = obj ? "v " : "", *f_prefix = obj ? "f " : "3 ";
    const int base = obj ? 1 : 0;
    if (obj)
        fprintf(o.f, "# emm mesh: %zu vertices, %zu faces\n", m->nv, m->nt);
    else
        fprintf(o.f, "OFF\n%zu %zu %zu\n", m->nv, m->nt, m->edges);
    for (size_t v = 0; v < m->nv; v++)
        fprintf(o.f, "%s%.17g %.17g %.17g\n", v_prefix, m->xyz[3 * v], m->xyz[3 * v + 1],
                m->xyz[3 * v + 2]);
    for (size_t t = 0; t < m->nt; t++)
        fprintf(o.f, "%s%d %d %d\n", f_prefix, m->index[3 * t] + base,
                m->index[3 * t + 1] + base, m->index[3 * t + 2] + base);
    return emm_outfile_commit(&o, "the mesh", err);
}

emm_status emm_mesh_write_off(const emm_mesh *m, const char *path, emm_error *err)
{
    return write_text(m, path, false, err);
}

emm_status emm_mesh_write_obj(const emm_mesh *m, const char *path, emm_error *err)
{
    return write_text(m, path, true, err);
}

/* ---- queries ------------------------------------------------------------ */

size_t emm_mesh_vertex_count(const emm_mesh *m) { assert(m); return m->nv; }
size_t emm_mesh_triangle_count(const emm_mesh *m) { assert(m); return m->nt; }
size_t emm_mesh_boundary_edges(const emm_mesh *m) { assert(m); return m->boundary_edges; }
size_t emm_mesh_polygons_split(const emm_mesh *m) { assert(m); return m->polygons_split; }
double emm_mesh_mean_edge_length(const emm_mesh *m) { assert(m); return m->mean_edge; }
const double *emm_mesh_positions(const emm_mesh *m) { assert(m); return m->xyz; }
const int32_t *emm_mesh_indices(const emm_mesh *m) { assert(m); return m->index; }

void emm_mesh_bbox(const emm_mesh *m, double lo[3], double hi[3])
{
    assert(m && lo && hi);
    memcpy(lo, m->lo, sizeof m->lo);
    memcpy(hi, m->hi, sizeof m->hi);
}

const emm_vertex *emm_mesh_vertex(const emm_mesh *m, uint32_t id)
{
    assert(m && id < m->nv);
    return &m->vertex[id];
}

const emm_triangle *emm_mesh_triangle(const emm_mesh *m, uint32_t id)
{
    assert(m && id < m->nt);
    return &m->triangle[id];
}

size_t emm_vertex_triangles(const emm_mesh *m, uint32_t v, const int32_t **tris)
{
    assert(m && v < m->nv && tris);
    *tris = m->vt + m->vt_start[v];
    return m->vt_start[v + 1] - m->vt_start[v];
}

void emm_triangle_vertices(const emm_mesh *m, uint32_t t, int32_t out[3])
{
    assert(m && t < m->nt && out);
    memcpy(out, m->triangle[t].v, sizeof m->triangle[t].v);
}

void emm_triangle_neighbors(const emm_mesh *m, uint32_t t, int32_t out[3])
{
    assert(m && t < m->nt && out);
    memcpy(out, m->triangle[t].n, sizeof m->triangle[t].n);
}

void emm_vertex_set_data(emm_mesh *m, uint32_t v, void *data)
{
    assert(m && v < m->nv);
    m->vertex_data[v] = data;
}

void *emm_vertex_data(const emm_mesh *m, uint32_t v)
{
    assert(m && v < m->nv);
    return m->vertex_data[v];
}

void emm_triangle_set_data(emm_mesh *m, uint32_t t, void *data)
{
    assert(m && t < m->nt);
    m->triangle_data[t] = data;
}

void *emm_triangle_data(const emm_mesh *m, uint32_t t)
{
    assert(m && t < m->nt);
    return m->triangle_data[t];
}
