/* Synthetic traces of canonical traversals (thesis §5: Table 5.1's shapes —
 * random access, region growing, curves and scan lines — and the Z-order and
 * Gray-code curves of Figs. 5.2 and 5.3). Each pattern is an order of
 * triangle visits; a visit reads the triangle record and its three vertices,
 * as the thesis' workloads do.
 *
 * A mesh is seen in the plane of its bounding box's two largest extents
 * (core/geom.h). A mesh with depth — no extent of its box is zero: a
 * surface in space, not a flat mesh — is ordered in 3D instead: Z-order,
 * Gray-code and Hilbert keys take all three coordinates of the centroids
 * (21 bits each), and a curve walks straight across each triangle's own
 * plane, its direction unfolded about every edge it crosses, ending at the
 * boundary or after the length of the box's diagonal (a closed surface has
 * no boundary). Scan lines, spirals and the corner stay in the plane. */
#include "emm/synth.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "emm/trace.h"
#include "error.h"
#include "generate.h"
#include "geom.h"
#include "parse.h"
#include "synth_internal.h"

static const char *const pattern_names[EMM_PATTERN_COUNT] = {
    "region", "curve", "scanline", "zorder", "gray", "hilbert", "random", "spiral"};

const char *emm_pattern_name(emm_pattern p)
{
    return (unsigned)p < EMM_PATTERN_COUNT ? pattern_names[p] : "?";
}

emm_status emm_pattern_parse(const char *name, emm_pattern *out, emm_error *err)
{
    for (int i = 0; i < EMM_PATTERN_COUNT; i++)
        if (name && strcmp(name, pattern_names[i]) == 0) {
            *out = (emm_pattern)i;
            return EMM_OK;
        }
    return emm_fail(err, EMM_ERR_INVALID,
                    "pattern '%s' is unknown; accepted: region, curve, scanline, zorder, gray, "
                    "hilbert, random, spiral",
                    name ? name : "");
}

emm_status emm_synth_recipe_parse(const char *recipe, emm_synth_options *o, emm_error *err)
{
    char pat[32];
    const char *at = strchr(recipe, '@');
    size_t len = at ? (size_t)(at - recipe) : strlen(recipe);
    if (len >= sizeof pat)
        len = sizeof pat - 1;
    memcpy(pat, recipe, len);
    pat[len] = '\0';
    emm_pattern p;
    emm_status st = emm_pattern_parse(pat, &p, err);
    if (st != EMM_OK)
        return st;
    o->pattern = p;
    o->length = 0;
    o->corner_seed = 0;
    o->rings = 0;
    if (!at)
        return EMM_OK;
    uint64_t n;
    if (p == EMM_PATTERN_REGION && strcmp(at + 1, "corner") == 0)
        o->corner_seed = 1;
    else if (p == EMM_PATTERN_REGION && strcmp(at + 1, "ring") == 0)
        o->rings = 1;
    else if (p == EMM_PATTERN_CURVE && emm_parse_u64(at + 1, &n) && n > 0)
        o->length = n;
    else
        return emm_fail(err, EMM_ERR_INVALID,
                        "recipe '%s': after '@' comes 'corner' or 'ring' (region) or a curve "
                        "length (curve)",
                        recipe);
    return EMM_OK;
}

/* splitmix64: small, fast and good enough to pick seeds and directions. */
static uint64_t rng_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double rng_unit(uint64_t *s)
{
    return (double)(rng_next(s) >> 11) * 0x1.0p-53;
}

/* The traversal state: the mesh seen in 2D over its two largest extents. */
struct synth {
    const emm_mesh *m;
    size_t nv, nt;
    int ax, ay;          /* the two axes used */
    double lo[2], hi[2]; /* bounding box over them */
    double *cx, *cy;     /* triangle centroids */
    /* With depth: the third axis, its range, the centroids along it, and
     * the box's diagonal (a curve's longest walk). */
    bool depth;
    int az;
    double zlo, zhi, diag;
    double *cz;
};

static void synth_init_axes(struct synth *s)
{
    double lo[3], hi[3];
    int axes[2];
    emm_mesh_bbox(s->m, lo, hi);
    emm_axes_largest(lo, hi, 2, axes); /* the plane every layer sees (core/geom.h) */
    s->ax = axes[0];
    s->ay = axes[1];
    s->lo[0] = lo[s->ax];
    s->hi[0] = hi[s->ax];
    s->lo[1] = lo[s->ay];
    s->hi[1] = hi[s->ay];
    s->az = 3 - s->ax - s->ay;
    s->zlo = lo[s->az];
    s->zhi = hi[s->az];
    s->depth = s->zhi > s->zlo;
    s->diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

static void vertex_2d(const struct synth *s, int32_t v, double *x, double *y)
{
    const emm_vertex *p = emm_mesh_vertex(s->m, (uint32_t)v);
    *x = p->xyz[s->ax];
    *y = p->xyz[s->ay];
}

/* Quantises a centroid to 16 bits per axis. */
static void quantise(const struct synth *s, size_t t, uint32_t *qx, uint32_t *qy)
{
    double w = s->hi[0] - s->lo[0], h = s->hi[1] - s->lo[1];
    double fx = w > 0 ? (s->cx[t] - s->lo[0]) / w : 0.0;
    double fy = h > 0 ? (s->cy[t] - s->lo[1]) / h : 0.0;
    *qx = (uint32_t)fmin(65535.0, fmax(0.0, fx * 65536.0));
    *qy = (uint32_t)fmin(65535.0, fmax(0.0, fy * 65536.0));
}

/* With depth: the centroid's three coordinates to 21 bits each. */
static void quantise3(const struct synth *s, size_t t, uint32_t q[3])
{
    const double top = (double)((1u << 21) - 1);
    double c[3] = {s->cx[t], s->cy[t], s->cz[t]};
    double lo[3] = {s->lo[0], s->lo[1], s->zlo}, hi[3] = {s->hi[0], s->hi[1], s->zhi};
    for (int i = 0; i < 3; i++) {
        double f = hi[i] > lo[i] ? (c[i] - lo[i]) / (hi[i] - lo[i]) : 0.0;
        q[i] = (uint32_t)fmin(top, fmax(0.0, f * top));
    }
}

/* 21 bits spread to every third bit. */
static uint64_t spread3(uint32_t v)
{
    uint64_t x = v & 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

static uint64_t morton3(const uint32_t q[3])
{
    return spread3(q[0]) | spread3(q[1]) << 1 | spread3(q[2]) << 2;
}

static uint64_t spread_bits(uint32_t v)
{
    uint64_t x = v & 0xffff;
    x = (x | (x << 8)) & 0x00ff00ffull;
    x = (x | (x << 4)) & 0x0f0f0f0full;
    x = (x | (x << 2)) & 0x33333333ull;
    x = (x | (x << 1)) & 0x55555555ull;
    return x;
}

static uint64_t morton(uint32_t x, uint32_t y)
{
    return spread_bits(x) | (spread_bits(y) << 1);
}

/* The rank of a code in the reflected binary Gray sequence. */
static uint64_t gray_rank(uint64_t g)
{
    for (uint64_t shift = 1; shift < 64; shift <<= 1)
        g ^= g >> shift;
    return g;
}

/* Position along a Hilbert curve of order 16 (the classic xy → d walk). */
static uint64_t hilbert(uint32_t x, uint32_t y)
{
    uint64_t d = 0;
    for (uint32_t sbit = 1u << 15; sbit > 0; sbit >>= 1) {
        uint32_t rx = (x & sbit) > 0, ry = (y & sbit) > 0;
        d += (uint64_t)sbit * sbit * ((3 * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                x = 65535 - x;
                y = 65535 - y;
            }
            uint32_t t = x;
            x = y;
            y = t;
        }
    }
    return d;
}

struct keyed {
    uint64_t key;
    uint32_t t;
};

static int cmp_keyed(const void *a, const void *b)
{
    const struct keyed *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->t < y->t ? -1 : x->t > y->t;
}

/* Orders all triangles by a key computed from their centroids. */
static void order_by_key(const struct synth *s, emm_pattern p, double band, uint32_t *order)
{
    struct keyed *k = malloc(s->nt * sizeof *k);
    double mx = 0.5 * (s->lo[0] + s->hi[0]), my = 0.5 * (s->lo[1] + s->hi[1]);
    for (size_t t = 0; t < s->nt; t++) {
        uint32_t qx, qy;
        quantise(s, t, &qx, &qy);
        uint64_t key = 0;
        uint32_t q[3];
        emm_pattern plane = p; /* the pattern in the plane; COUNT: none */
        if (s->depth && (p == EMM_PATTERN_ZORDER || p == EMM_PATTERN_GRAY ||
                         p == EMM_PATTERN_HILBERT)) {
            quantise3(s, t, q);
            key = p == EMM_PATTERN_HILBERT ? emm_hilbert3(q, 21)
                  : p == EMM_PATTERN_GRAY  ? gray_rank(morton3(q))
                                           : morton3(q);
            plane = EMM_PATTERN_COUNT;
        }
        switch (plane) {
        case EMM_PATTERN_ZORDER: key = morton(qx, qy); break;
        case EMM_PATTERN_GRAY: key = gray_rank(morton(qx, qy)); break;
        case EMM_PATTERN_HILBERT: key = hilbert(qx, qy); break;
        case EMM_PATTERN_SCANLINE: {
            uint64_t row = (uint64_t)((s->cy[t] - s->lo[1]) / band);
            key = (row << 16) | qx;
            break;
        }
        case EMM_PATTERN_SPIRAL: {
            double dx = s->cx[t] - mx, dy = s->cy[t] - my;
            uint64_t ring = (uint64_t)(sqrt(dx * dx + dy * dy) / band);
            double a = atan2(dy, dx) + M_PI; /* 0 .. 2π */
            key = (ring << 20) | (uint64_t)(a / (2 * M_PI) * 1048575.0);
            break;
        }
        default: break;
        }
        k[t].key = key;
        k[t].t = (uint32_t)t;
    }
    qsort(k, s->nt, sizeof *k, cmp_keyed);
    for (size_t t = 0; t < s->nt; t++)
        order[t] = k[t].t;
    free(k);
}

/* Breadth-first growth over edge neighbours from `seed`, then from the
 * lowest-numbered unreached triangle of each further component. */
static size_t order_region(const struct synth *s, uint32_t seed, uint32_t *order)
{
    unsigned char *seen = calloc(s->nt, 1);
    size_t head = 0, tail = 0, next_start = 0;
    order[tail++] = seed;
    seen[seed] = 1;
    while (tail < s->nt || head < tail) {
        if (head == tail) {
            while (seen[next_start])
                next_start++;
            order[tail++] = (uint32_t)next_start;
            seen[next_start] = 1;
        }
        const emm_triangle *tr = emm_mesh_triangle(s->m, order[head++]);
        for (int i = 0; i < 3; i++) {
            int32_t n = tr->n[i];
            if (n >= 0 && !seen[n]) {
                seen[n] = 1;
                order[tail++] = (uint32_t)n;
            }
        }
    }
    free(seen);
    return tail;
}

/* Breadth-first growth over vertices from `seed`'s corners: each vertex
 * visits its one-ring, every incident triangle in turn (so a triangle is
 * visited once a corner), and enqueues their corners; then the lowest
 * unreached vertex of each further component. At most cap visits, their
 * count in *n; false without memory. */
static bool order_ring(const struct synth *s, uint32_t seed, uint32_t *order, size_t cap,
                       size_t *n_out)
{
    size_t nv = s->nv, nt = s->nt, n = 0;
    bool ok = false;
    uint32_t *start = calloc(nv + 1, sizeof *start), *inc = malloc(3 * nt * sizeof *inc);
    uint32_t *queue = malloc((nv ? nv : 1) * sizeof *queue), *fill = NULL;
    unsigned char *seen = calloc(nv ? nv : 1, 1);
    if (!start || !inc || !queue || !seen)
        goto done;
    for (size_t t = 0; t < nt; t++)
        for (int i = 0; i < 3; i++)
            start[emm_mesh_triangle(s->m, (uint32_t)t)->v[i] + 1]++;
    for (size_t v = 0; v < nv; v++)
        start[v + 1] += start[v];
    if (!(fill = malloc((nv ? nv : 1) * sizeof *fill)))
        goto done;
    memcpy(fill, start, nv * sizeof *fill);
    for (size_t t = 0; t < nt; t++)
        for (int i = 0; i < 3; i++)
            inc[fill[emm_mesh_triangle(s->m, (uint32_t)t)->v[i]]++] = (uint32_t)t;
    size_t head = 0, tail = 0, next = 0;
    const emm_triangle *st = emm_mesh_triangle(s->m, seed);
    for (int i = 0; i < 3; i++)
        if (!seen[st->v[i]])
            seen[st->v[i]] = 1, queue[tail++] = (uint32_t)st->v[i];
    while (n < cap) {
        if (head == tail) {
            while (next < nv && (seen[next] || start[next] == start[next + 1]))
                next++;
            if (next >= nv)
                break;
            seen[next] = 1;
            queue[tail++] = (uint32_t)next;
        }
        uint32_t v = queue[head++];
        for (uint32_t k = start[v]; k < start[v + 1] && n < cap; k++) {
            uint32_t t = inc[k];
            order[n++] = t;
            const emm_triangle *tr = emm_mesh_triangle(s->m, t);
            for (int i = 0; i < 3; i++)
                if (!seen[tr->v[i]])
                    seen[tr->v[i]] = 1, queue[tail++] = (uint32_t)tr->v[i];
        }
    }
    *n_out = n;
    ok = true;
done:
    free(start);
    free(inc);
    free(queue);
    free(fill);
    free(seen);
    return ok;
}

/* One straight walk: from the centroid of `t` in direction (dx, dy), crossing
 * into the edge neighbour of the edge the ray leaves through, until the
 * boundary or `max` triangles. Appends the visited triangles to out. */
static size_t walk(const struct synth *s, uint32_t t, double dx, double dy, size_t max,
                   uint32_t *out)
{
    double px = s->cx[t], py = s->cy[t];
    int32_t from = -1;
    size_t n = 0;
    while (n < max) {
        out[n++] = t;
        const emm_triangle *tr = emm_mesh_triangle(s->m, t);
        double best = INFINITY;
        int exit_edge = -1;
        for (int i = 0; i < 3; i++) {
            if (tr->n[i] == from && from >= 0)
                continue;
            double ax, ay, bx, by;
            vertex_2d(s, tr->v[i], &ax, &ay);
            vertex_2d(s, tr->v[(i + 1) % 3], &bx, &by);
            /* Solve p + r·d = a + u·(b − a) for r > 0, 0 ≤ u ≤ 1. */
            double ex = bx - ax, ey = by - ay;
            double den = dx * ey - dy * ex;
            if (fabs(den) < 1e-300)
                continue;
            double r = ((ax - px) * ey - (ay - py) * ex) / den;
            double u = ((ax - px) * dy - (ay - py) * dx) / den;
            if (r > 0 && u >= -1e-12 && u <= 1 + 1e-12 && r < best) {
                best = r;
                exit_edge = i;
            }
        }
        if (exit_edge < 0 || tr->n[exit_edge] < 0)
            break;
        px += best * dx;
        py += best * dy;
        from = (int32_t)t;
        t = (uint32_t)tr->n[exit_edge];
    }
    return n;
}

static void sub3(const double *a, const double *b, double *o)
{
    for (int i = 0; i < 3; i++)
        o[i] = a[i] - b[i];
}

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double *a, const double *b, double *o)
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static void unit3(double *a)
{
    double l = sqrt(dot3(a, a));
    if (l > 0)
        for (int i = 0; i < 3; i++)
            a[i] /= l;
}

/* Triangle t's plane: corner 0, and two orthonormal axes in it. */
static void plane_frame(const emm_mesh *m, const emm_triangle *tr, const double **o, double u[3],
                        double w[3])
{
    const double *a = emm_mesh_vertex(m, (uint32_t)tr->v[0])->xyz;
    const double *b = emm_mesh_vertex(m, (uint32_t)tr->v[1])->xyz;
    const double *c = emm_mesh_vertex(m, (uint32_t)tr->v[2])->xyz;
    double e2[3], n[3];
    sub3(b, a, u);
    sub3(c, a, e2);
    cross3(u, e2, n);
    cross3(n, u, w);
    unit3(u);
    unit3(w);
    *o = a;
}

/* walk in space: the same rule in each triangle's plane (its own 2D frame);
 * where the ray leaves across an edge, its direction is unfolded about the
 * edge into the neighbour's plane (same component along the edge, the rest
 * pointing into the neighbour). Ends at the boundary, after `max`
 * triangles, or once it has gone `reach`. */
static size_t walk3(const struct synth *s, uint32_t t, double angle, size_t max, double reach,
                    uint32_t *out)
{
    const emm_triangle *tr = emm_mesh_triangle(s->m, t);
    const double *o;
    double u[3], w[3], p[3] = {0, 0, 0}, dir[3];
    plane_frame(s->m, tr, &o, u, w);
    for (int k = 0; k < 3; k++)
        for (int i = 0; i < 3; i++)
            p[i] += emm_mesh_vertex(s->m, (uint32_t)tr->v[k])->xyz[i] / 3;
    for (int i = 0; i < 3; i++)
        dir[i] = cos(angle) * u[i] + sin(angle) * w[i];
    int32_t from = -1;
    double gone = 0;
    size_t n = 0;
    while (n < max) {
        out[n++] = t;
        tr = emm_mesh_triangle(s->m, t);
        plane_frame(s->m, tr, &o, u, w);
        double rel[3];
        sub3(p, o, rel);
        double px = dot3(rel, u), py = dot3(rel, w), dx = dot3(dir, u), dy = dot3(dir, w);
        double best = INFINITY;
        int exit_edge = -1;
        for (int i = 0; i < 3; i++) {
            if (tr->n[i] == from && from >= 0)
                continue;
            double ra[3], rb[3];
            sub3(emm_mesh_vertex(s->m, (uint32_t)tr->v[i])->xyz, o, ra);
            sub3(emm_mesh_vertex(s->m, (uint32_t)tr->v[(i + 1) % 3])->xyz, o, rb);
            double ax = dot3(ra, u), ay = dot3(ra, w), bx = dot3(rb, u), by = dot3(rb, w);
            double ex = bx - ax, ey = by - ay;
            double den = dx * ey - dy * ex;
            if (fabs(den) < 1e-300)
                continue;
            double r = ((ax - px) * ey - (ay - py) * ex) / den;
            double f = ((ax - px) * dy - (ay - py) * dx) / den;
            if (r > 0 && f >= -1e-12 && f <= 1 + 1e-12 && r < best) {
                best = r;
                exit_edge = i;
            }
        }
        if (exit_edge < 0 || tr->n[exit_edge] < 0)
            break;
        gone += best;
        if (gone > reach)
            break;
        for (int i = 0; i < 3; i++)
            p[i] += best * dir[i];
        /* Unfold about the edge into the neighbour. */
        const double *a = emm_mesh_vertex(s->m, (uint32_t)tr->v[exit_edge])->xyz;
        const double *b = emm_mesh_vertex(s->m, (uint32_t)tr->v[(exit_edge + 1) % 3])->xyz;
        const emm_triangle *nx = emm_mesh_triangle(s->m, (uint32_t)tr->n[exit_edge]);
        const double *c = NULL;
        for (int k = 0; k < 3; k++)
            if (nx->v[k] != tr->v[exit_edge] && nx->v[k] != tr->v[(exit_edge + 1) % 3])
                c = emm_mesh_vertex(s->m, (uint32_t)nx->v[k])->xyz;
        double e[3], into[3];
        sub3(b, a, e);
        unit3(e);
        double along = dot3(dir, e), across[3];
        for (int i = 0; i < 3; i++)
            across[i] = dir[i] - along * e[i];
        double width = sqrt(dot3(across, across));
        if (c) {
            sub3(c, a, into);
            double k = dot3(into, e);
            for (int i = 0; i < 3; i++)
                into[i] -= k * e[i];
            unit3(into);
            for (int i = 0; i < 3; i++)
                dir[i] = along * e[i] + width * into[i];
        }
        from = (int32_t)t;
        t = (uint32_t)tr->n[exit_edge];
    }
    return n;
}

static size_t order_curves(const struct synth *s, uint64_t *rng, uint64_t visits,
                           uint64_t length, uint32_t *order)
{
    size_t n = 0;
    while (n < visits) {
        uint32_t t = (uint32_t)(rng_next(rng) % s->nt);
        double a = rng_unit(rng) * 2 * M_PI;
        size_t room = (size_t)(visits - n);
        size_t max = length && length < room ? (size_t)length : room;
        n += s->depth ? walk3(s, t, a, max, s->diag, order + n)
                      : walk(s, t, cos(a), sin(a), max, order + n);
    }
    return n;
}

#define VERTEX_BYTES EMM_THESIS_VERTEX_BYTES
#define TRIANGLE_BYTES EMM_THESIS_TRIANGLE_BYTES

/* The pattern's triangle visits over m: *order (malloc'ed, the caller frees)
 * receives *n triangle indices; the mesh's positions and triangle indices
 * go to *xyz and *tri when those are not NULL (malloc'ed too). */
static emm_status synth_order(const emm_mesh *m, const emm_synth_options *opt, const char *name,
                              uint32_t **order_out, size_t *n_out, double **xyz_out,
                              int32_t **tri_out, emm_error *err)
{
    struct synth s = {.m = m, .nv = emm_mesh_vertex_count(m), .nt = emm_mesh_triangle_count(m)};
    uint64_t rng = opt->seed;
    emm_status st = EMM_OK;
    uint64_t visits = opt->visits ? opt->visits : s.nt;
    if (opt->pattern == EMM_PATTERN_REGION && opt->rings && !opt->visits)
        visits = 3 * (uint64_t)s.nt;
    size_t order_cap = (size_t)(visits > s.nt ? visits : s.nt);

    if (s.nt == 0)
        return emm_fail(err, EMM_ERR_INVALID, "%s: the mesh has no triangles", name);
    if ((unsigned)opt->pattern >= EMM_PATTERN_COUNT)
        return emm_fail(err, EMM_ERR_INVALID, "%s: unknown pattern", name);
    synth_init_axes(&s);

    double *xyz = xyz_out ? malloc(s.nv * 3 * sizeof *xyz) : NULL;
    int32_t *tri = tri_out ? malloc(s.nt * 3 * sizeof *tri) : NULL;
    s.cx = malloc(s.nt * sizeof *s.cx);
    s.cy = malloc(s.nt * sizeof *s.cy);
    s.cz = s.depth ? malloc(s.nt * sizeof *s.cz) : NULL;
    uint32_t *order = malloc(order_cap * sizeof *order);
    if ((xyz_out && !xyz) || (tri_out && !tri) || !s.cx || !s.cy || (s.depth && !s.cz) ||
        !order) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for a %zu-triangle mesh", name, s.nt);
        goto done;
    }
    for (size_t v = 0; xyz && v < s.nv; v++)
        memcpy(xyz + 3 * v, emm_mesh_vertex(m, (uint32_t)v)->xyz, 3 * sizeof *xyz);
    for (size_t t = 0; t < s.nt; t++) {
        const emm_triangle *tr = emm_mesh_triangle(m, (uint32_t)t);
        double sx = 0, sy = 0;
        for (int i = 0; i < 3; i++) {
            double x, y;
            if (tri)
                tri[3 * t + i] = tr->v[i];
            vertex_2d(&s, tr->v[i], &x, &y);
            sx += x;
            sy += y;
        }
        s.cx[t] = sx / 3;
        s.cy[t] = sy / 3;
        if (s.cz)
            s.cz[t] = (emm_mesh_vertex(m, (uint32_t)tr->v[0])->xyz[s.az] +
                       emm_mesh_vertex(m, (uint32_t)tr->v[1])->xyz[s.az] +
                       emm_mesh_vertex(m, (uint32_t)tr->v[2])->xyz[s.az]) /
                      3;
    }

    /* Scan-line rows and spiral rings are one mean edge length apart. */
    double band = emm_mesh_mean_edge_length(m);
    if (!(band > 0))
        band = 1;

    size_t n;
    switch (opt->pattern) {
    case EMM_PATTERN_REGION: {
        uint32_t seed = (uint32_t)(rng_next(&rng) % s.nt);
        if (opt->corner_seed) {
            seed = 0;
            for (size_t t = 1; t < s.nt; t++)
                if (s.cx[t] + s.cy[t] < s.cx[seed] + s.cy[seed])
                    seed = (uint32_t)t;
        }
        if (opt->has_start && opt->start < s.nt)
            seed = opt->start;
        if (!opt->rings)
            n = order_region(&s, seed, order);
        else if (!order_ring(&s, seed, order, order_cap, &n)) {
            st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for a %zu-vertex mesh", name,
                          s.nv);
            goto done;
        }
        break;
    }
    case EMM_PATTERN_CURVE:
        n = order_curves(&s, &rng, visits, opt->length, order);
        break;
    case EMM_PATTERN_RANDOM:
        for (size_t t = 0; t < s.nt; t++)
            order[t] = (uint32_t)t;
        for (size_t t = s.nt; t > 1; t--) {
            size_t j = (size_t)(rng_next(&rng) % t);
            uint32_t x = order[t - 1];
            order[t - 1] = order[j];
            order[j] = x;
        }
        n = s.nt;
        break;
    default:
        order_by_key(&s, opt->pattern, band, order);
        n = s.nt;
        break;
    }
    if (n > visits)
        n = (size_t)visits;
    *order_out = order;
    *n_out = n;
    order = NULL;
    if (xyz_out)
        *xyz_out = xyz, xyz = NULL;
    if (tri_out)
        *tri_out = tri, tri = NULL;
done:
    free(xyz);
    free(tri);
    free(s.cx);
    free(s.cy);
    free(s.cz);
    free(order);
    return st;
}

/* The records of one visit: the triangle's record, then its vertices'. */
static size_t visit_records(const emm_mesh *m, uint32_t t, const struct synth_arrays *a,
                            uint32_t work, emm_trace_record *out)
{
    const emm_triangle *tr = emm_mesh_triangle(m, t);
    out[0] = (emm_trace_record){t, a->tri, a->tri_offset, a->tri_bytes, work, 0, 0};
    for (int k = 0; k < 3; k++)
        out[1 + k] = (emm_trace_record){(uint64_t)tr->v[k], a->vert, a->vert_offset,
                                        a->vert_bytes, work, 0, 0};
    return 4;
}

static const struct synth_arrays thesis_arrays = {1, 4, 24, 0, 8, 24};

emm_status emm_synth_trace(const emm_mesh *m, const emm_synth_options *opt, const char *path,
                           uint64_t *records, emm_error *err)
{
    uint32_t *order;
    size_t n;
    double *xyz;
    int32_t *tri;
    emm_status st = synth_order(m, opt, path, &order, &n, &xyz, &tri, err);
    if (st != EMM_OK)
        return st;
    size_t nv = emm_mesh_vertex_count(m), nt = emm_mesh_triangle_count(m);
    emm_trace_array arrays[2] = {
        {EMM_ARRAY_VERTICES, VERTEX_BYTES, nv, 0x10000000u},
        {EMM_ARRAY_TRIANGLES, TRIANGLE_BYTES, nt, 0},
    };
    /* The triangle array follows the vertex array, 4 KiB aligned, as malloc
     * would place two large blocks. */
    arrays[1].base = (arrays[0].base + nv * VERTEX_BYTES + 8191) & ~(uint64_t)4095;
    emm_trace_geometry geo = {nv, nt, xyz, tri};
    emm_trace_writer *w;
    st = emm_trace_writer_open(path, arrays, 2, &geo, opt->compress, &w, err);
    if (st != EMM_OK)
        goto done;

    enum { CHUNK = 4096 };
    emm_trace_record buf[CHUNK];
    size_t nb = 0;
    for (size_t i = 0; i < n && st == EMM_OK; i++) {
        nb += visit_records(m, order[i], &thesis_arrays, opt->work, buf + nb);
        if (nb + 4 > CHUNK) {
            st = emm_trace_write(w, buf, nb, err);
            nb = 0;
        }
    }
    if (st == EMM_OK && nb)
        st = emm_trace_write(w, buf, nb, err);
    if (st != EMM_OK) {
        emm_trace_writer_abort(w);
        goto done;
    }
    st = emm_trace_writer_close(w, err);
    if (st == EMM_OK && records)
        *records = (uint64_t)n * 4;
done:
    free(xyz);
    free(tri);
    free(order);
    return st;
}

emm_status emm_synth_records(const emm_mesh *m, const emm_synth_options *opt,
                             const struct synth_arrays *arrays, const char *name,
                             emm_trace_record **out, size_t *nrec, emm_error *err)
{
    uint32_t *order;
    size_t n;
    emm_status st = synth_order(m, opt, name, &order, &n, NULL, NULL, err);
    if (st != EMM_OK)
        return st;
    emm_trace_record *recs = malloc((n ? n : 1) * 4 * sizeof *recs);
    if (!recs) {
        free(order);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for %zu synthetic visits", name, n);
    }
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        k += visit_records(m, order[i], arrays ? arrays : &thesis_arrays, opt->work, recs + k);
    free(order);
    *out = recs;
    *nrec = k;
    return EMM_OK;
}
