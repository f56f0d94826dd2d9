/* The workloads' shared mesh code; see workload.h. */
#include "workload.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "emm/mesh.h"
#include "emm/tag.h"

/* The number of fans vertex v's triangles form, counted through libemm's
 * copy of the mesh (before the arrays are tagged, so the check is not part of
 * what the shim watches): 1 for a manifold vertex. */
static size_t fan_count(const emm_mesh *em, uint32_t v, unsigned char *seen)
{
    const int32_t *inc;
    size_t n = emm_vertex_triangles(em, v, &inc);
    size_t fans = 0;
    for (size_t i = 0; i < n; i++)
        seen[i] = 0;
    for (size_t i = 0; i < n; i++) {
        if (seen[i])
            continue;
        fans++;
        /* Both directions from inc[i], marking every triangle reached. */
        for (int dir = 0; dir < 2; dir++) {
            int32_t t = inc[i];
            const emm_triangle *T = emm_mesh_triangle(em, (uint32_t)t);
            int k = T->v[0] == (int32_t)v ? 0 : T->v[1] == (int32_t)v ? 1 : 2;
            int32_t w = T->v[dir == 0 ? (k + 1) % 3 : (k + 2) % 3];
            for (size_t guard = 0; guard <= n; guard++) {
                for (size_t j = 0; j < n; j++)
                    if (inc[j] == t)
                        seen[j] = 1;
                T = emm_mesh_triangle(em, (uint32_t)t);
                k = T->v[0] == (int32_t)v ? 0 : T->v[1] == (int32_t)v ? 1 : 2;
                int e = T->v[(k + 1) % 3] == w ? k : (k + 2) % 3;
                int32_t next = T->n[e];
                if (next < 0 || next == inc[i])
                    break;
                const emm_triangle *N = emm_mesh_triangle(em, (uint32_t)next);
                int kn = N->v[0] == (int32_t)v ? 0 : N->v[1] == (int32_t)v ? 1 : 2;
                int32_t a = N->v[(kn + 1) % 3], b = N->v[(kn + 2) % 3];
                w = a == w ? b : a;
                t = next;
            }
        }
    }
    return fans;
}

__attribute__((noinline)) bool read_mesh(const char *prog, const char *path, struct Mesh *mesh)
{
    emm_mesh *em = NULL;
    emm_error err;
    emm_status st;
    memset(mesh, 0, sizeof *mesh);
    if (path) {
        st = emm_mesh_open(path, &em, &err);
    } else {
        emm_gen_options opt = {EMM_DEFAULT_FACES, EMM_DEFAULT_SEED, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
        st = emm_mesh_generate(&opt, &em, &err);
    }
    if (st != EMM_OK) {
        fprintf(stderr, "%s: %s\n", prog, err.message);
        return false;
    }
    size_t nv = emm_mesh_vertex_count(em), nt = emm_mesh_triangle_count(em);
    if (nv > INT32_MAX || nt > INT32_MAX) {
        fprintf(stderr, "%s: %s: too large for 32-bit indices\n", prog, path ? path : "mesh");
        emm_mesh_free(em);
        return false;
    }

    size_t maxdeg = 0;
    for (size_t v = 0; v < nv; v++) {
        const int32_t *inc;
        size_t d = emm_vertex_triangles(em, (uint32_t)v, &inc);
        if (d > maxdeg)
            maxdeg = d;
    }
    unsigned char *seen = malloc(maxdeg ? maxdeg : 1);
    if (!seen)
        goto nomem;
    for (size_t v = 0; v < nv; v++) {
        size_t fans = fan_count(em, (uint32_t)v, seen);
        if (fans > 1) {
            fprintf(stderr, "%s: %s: vertex %zu is non-manifold (its triangles form %zu fans)\n",
                    prog, path ? path : "mesh", v, fans);
            free(seen);
            emm_mesh_free(em);
            return false;
        }
    }
    free(seen);

    /* The two allocations EMM_TAG rules find by site=read_mesh. */
    struct Vertex *verts = malloc(nv * sizeof *verts);
    struct Triangle *tris = malloc(nt * sizeof *tris);
    if (!verts || !tris) {
        free(verts);
        free(tris);
        goto nomem;
    }
    for (size_t v = 0; v < nv; v++) {
        const emm_vertex *ev = emm_mesh_vertex(em, (uint32_t)v);
        const int32_t *inc;
        size_t d = emm_vertex_triangles(em, (uint32_t)v, &inc);
        struct Vertex *V = &verts[v];
        memset(V, 0, sizeof *V); /* the padding too, so the records are fully defined */
        V->name = (uint32_t)v;
        memcpy(V->coor, ev->xyz, sizeof V->coor);
        for (size_t i = 0; i < 12; i++)
            V->vfConnec[i] = i < d ? inc[i] : -1;
    }
    for (size_t t = 0; t < nt; t++) {
        const emm_triangle *et = emm_mesh_triangle(em, (uint32_t)t);
        struct Triangle *T = &tris[t];
        T->name = (uint32_t)t;
        memcpy(T->vertexIndices, et->v, sizeof T->vertexIndices);
        memcpy(T->neighbors, et->n, sizeof T->neighbors);
    }
    emm_tag_vertices(verts, nv, sizeof *verts, offsetof(struct Vertex, coor), EMM_F64);
    emm_tag_triangles(tris, nt, sizeof *tris, offsetof(struct Triangle, vertexIndices), EMM_I32);

    double lo[3], hi[3];
    emm_mesh_bbox(em, lo, hi);
    mesh->vertices = verts;
    mesh->triangles = tris;
    mesh->verNr = nv;
    mesh->triNr = nt;
    mesh->mean_edge = emm_mesh_mean_edge_length(em);
    memcpy(mesh->lo, lo, sizeof mesh->lo);
    memcpy(mesh->hi, hi, sizeof mesh->hi);
    mesh->flat = lo[2] == hi[2];
    emm_mesh_free(em);
    return true;

nomem:
    fprintf(stderr, "%s: %s: out of memory\n", prog, path ? path : "mesh");
    emm_mesh_free(em);
    return false;
}

void free_mesh(struct Mesh *mesh)
{
    free(mesh->vertices);
    free(mesh->triangles);
    memset(mesh, 0, sizeof *mesh);
}

/* One step of the rotation around v: from triangle t, across its edge
 * (v, *w). Returns the next triangle (-1 at a boundary) and sets *w to the
 * far end of that triangle's other edge at v. Works whatever the
 * triangles' orientation, since it goes by shared vertices. */
static int32_t fan_step(const struct Mesh *m, int32_t t, int32_t v, int32_t *w)
{
    const struct Triangle *T = &m->triangles[t];
    int k = tri_corner(T, v);
    int e = T->vertexIndices[(k + 1) % 3] == *w ? k : (k + 2) % 3;
    int32_t next = T->neighbors[e];
    if (next < 0)
        return -1;
    const struct Triangle *N = &m->triangles[next];
    int kn = tri_corner(N, v);
    int32_t a = N->vertexIndices[(kn + 1) % 3], b = N->vertexIndices[(kn + 2) % 3];
    *w = a == *w ? b : a;
    return next;
}

size_t vertex_fan(const struct Mesh *m, int32_t v, int32_t *fan, size_t cap, bool *open)
{
    int32_t t0 = m->vertices[v].vfConnec[0];
    *open = false;
    if (t0 < 0)
        return 0;
    const struct Triangle *T0 = &m->triangles[t0];
    int k0 = tri_corner(T0, v);
    int32_t w = T0->vertexIndices[(k0 + 1) % 3];
    int32_t t = t0;
    size_t n = 0;
    for (;;) {
        if (n < cap)
            fan[n] = t;
        n++;
        t = fan_step(m, t, v, &w);
        if (t == t0)
            return n;
        if (t < 0 || n > m->triNr)
            break;
    }
    /* A boundary vertex: find the other end of the fan, then walk it whole
     * from there, so the list is contiguous. */
    *open = true;
    int32_t end = t0;
    w = T0->vertexIndices[(k0 + 2) % 3];
    for (size_t guard = 0; guard <= m->triNr; guard++) {
        int32_t next = fan_step(m, end, v, &w);
        if (next < 0)
            break;
        end = next;
    }
    /* w is now the far vertex of end's boundary edge; leave by the other one. */
    const struct Triangle *E = &m->triangles[end];
    int ke = tri_corner(E, v);
    int32_t a = E->vertexIndices[(ke + 1) % 3], b = E->vertexIndices[(ke + 2) % 3];
    w = a == w ? b : a;
    n = 0;
    t = end;
    while (t >= 0 && n <= m->triNr) {
        if (n < cap)
            fan[n] = t;
        n++;
        t = fan_step(m, t, v, &w);
    }
    return n;
}

int32_t tri_across(const struct Mesh *m, int32_t t, int32_t v, int32_t w)
{
    const struct Triangle *T = &m->triangles[t];
    for (int i = 0; i < 3; i++) {
        int32_t a = T->vertexIndices[i], b = T->vertexIndices[(i + 1) % 3];
        if ((a == v && b == w) || (a == w && b == v))
            return T->neighbors[i];
    }
    return -1;
}

double workload_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

int workload_usage_error(const char *prog, const char *msg, const char *arg)
{
    fprintf(stderr, "%s: %s%s%s\nTry '%s --help'.\n", prog, msg, arg ? ": " : "", arg ? arg : "",
            prog);
    return 2;
}

int workload_common_arg(struct workload_args *args, const char *prog, const char *a)
{
    if (strcmp(a, "--times") == 0)
        args->times = true;
    else if (a[0] == '-' && a[1] != '\0')
        return workload_usage_error(prog, "unknown option", a);
    else if (args->mesh)
        return workload_usage_error(prog, "more than one mesh file given", a);
    else
        args->mesh = a;
    return 0;
}

void workload_report_times(const struct workload_args *args, double t0, double t1, double t2)
{
    if (args->times)
        fprintf(stderr, "load: %.3f s  run: %.3f s\n", t1 - t0, t2 - t1);
}

/* The tension field: the gradient of the potential
 *
 *     phi(u) = g . u + sum_k a_k exp(-|u - c_k|^2 / (2 s_k^2))
 *
 * over u, the point mapped into [0,1]^2 by the mesh's bounding box (the
 * longer side scaled to 1). A gradient field has no closed orbits, and |g|
 * exceeds the sum of the bumps' steepest slopes (a_k / s_k * e^-1/2), so
 * the field never vanishes: every curve bends around the bumps and leaves
 * through the boundary. */
static const double field_g[2] = {1.0, 0.35};
static const struct { double cx, cy, s, a; } field_bumps[] = {
    {0.30, 0.35, 0.15, 0.062},
    {0.65, 0.70, 0.12, -0.050},
    {0.70, 0.25, 0.10, 0.041},
};

void field_init(struct field *f, enum field_kind kind, const struct Mesh *m)
{
    double w = m->hi[0] - m->lo[0], h = m->hi[1] - m->lo[1];
    double side = w > h ? w : h;
    f->kind = kind;
    f->lo[0] = m->lo[0];
    f->lo[1] = m->lo[1];
    f->scale = side > 0 ? 1.0 / side : 1.0;
    double side3 = 0;
    for (int i = 0; i < 3; i++) {
        f->mid[i] = (m->lo[i] + m->hi[i]) / 2;
        if (m->hi[i] - m->lo[i] > side3)
            side3 = m->hi[i] - m->lo[i];
    }
    f->scale3 = side3 > 0 ? 1.0 / side3 : 1.0;
}

/* In space: the same ramp, tilted up a little, and the bumps at mid-height,
 * where a terrain lies and a sphere's or torus' surface passes near them. On
 * a closed surface the projected field has zeros (a sphere's has at least
 * two); a curve stops at one. */
static const double field_g3[3] = {1.0, 0.35, 0.2};
static const struct { double c[3], s, a; } field_bumps3[] = {
    {{0.30, 0.35, 0.50}, 0.15, 0.062},
    {{0.65, 0.70, 0.45}, 0.12, -0.050},
    {{0.70, 0.25, 0.55}, 0.10, 0.041},
};

void field_at3(const struct field *f, const double p[3], double out[3])
{
    if (f->kind == FIELD_UNIFORM) {
        out[0] = 1.0;
        out[1] = out[2] = 0.0;
        return;
    }
    double u[3];
    for (int i = 0; i < 3; i++) {
        u[i] = (p[i] - f->mid[i]) * f->scale3 + 0.5;
        out[i] = field_g3[i];
    }
    for (size_t k = 0; k < sizeof field_bumps3 / sizeof field_bumps3[0]; k++) {
        double d[3], r2 = 0, s2 = field_bumps3[k].s * field_bumps3[k].s;
        for (int i = 0; i < 3; i++) {
            d[i] = u[i] - field_bumps3[k].c[i];
            r2 += d[i] * d[i];
        }
        double e = field_bumps3[k].a * exp(-r2 / (2.0 * s2)) / s2;
        for (int i = 0; i < 3; i++)
            out[i] -= e * d[i];
    }
}

void field_at(const struct field *f, double x, double y, double out[2])
{
    if (f->kind == FIELD_UNIFORM) {
        out[0] = 1.0;
        out[1] = 0.0;
        return;
    }
    double ux = (x - f->lo[0]) * f->scale, uy = (y - f->lo[1]) * f->scale;
    double gx = field_g[0], gy = field_g[1];
    for (size_t k = 0; k < sizeof field_bumps / sizeof field_bumps[0]; k++) {
        double dx = ux - field_bumps[k].cx, dy = uy - field_bumps[k].cy;
        double s2 = field_bumps[k].s * field_bumps[k].s;
        double e = field_bumps[k].a * exp(-(dx * dx + dy * dy) / (2.0 * s2)) / s2;
        gx -= e * dx;
        gy -= e * dy;
    }
    out[0] = gx;
    out[1] = gy;
}

bool field_parse(const char *name, enum field_kind *out)
{
    if (strcmp(name, "tension") == 0)
        *out = FIELD_TENSION;
    else if (strcmp(name, "uniform") == 0)
        *out = FIELD_UNIFORM;
    else
        return false;
    return true;
}

uint64_t fnv1a64(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

uint64_t fnv1a64_line(uint64_t h, const char *text)
{
    h = fnv1a64(h, text, strlen(text));
    return fnv1a64(h, "\n", 1);
}
