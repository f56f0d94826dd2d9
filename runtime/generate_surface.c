/* The generator's 3D surfaces (emm_surface): a sphere, a torus
 * and a terrain, for workloads on surfaces in space rather than the planar
 * mesh of generate.c. Each is a grid, so any size is made in time and memory
 * linear in the face count, and the face count is exact:
 *
 * Torus. One helical strip: vertex i (of V = faces / 2) goes around the
 * tube k times as i runs through all V (tube angle 2 pi i k / V, major
 * angle 2 pi i / V), so vertex i + a, a = round(V / k), lies about one
 * ring further along the major circle. The triangles (i, i+1, i+a+1) and
 * (i, i+a+1, i+a), indices mod V, are the lattice's parallelograms split
 * along one diagonal: 2V faces for any V, a sheared grid (by at most half
 * a cell) that needs no factorisation of V. a is chosen so that cells are
 * about square on radii 1 and 0.4.
 *
 * Sphere. The same strip, not closed on itself but wound from the south
 * pole to the north one: L = faces / 2 vertices, m of them per turn, 2(L -
 * m - 1) strip triangles; its two boundary loops (the first and the last
 * m + 1 vertices) are closed by a fan of m + 1 triangles around a pole
 * vertex each: 2L faces, L + 2 vertices (F = 2V - 4, genus 0). Latitudes
 * are evenly spaced, so the triangles near the poles are thin, as on any
 * UV sphere; m makes them about equilateral at the equator.
 *
 * Terrain. A grid of a x b quads over the unit square (a = round(sqrt(faces
 * / 2))), the faces / 2 mod a quads left over in one partial row on top and,
 * for an odd count, one triangle after them; each quad is split along its
 * shorter diagonal. Heights are a sum of 4 to 8 Gaussian hills and hollows
 * whose places, widths and heights come from the seed.
 *
 * The seed also jitters every vertex (the terrain's inner ones) by up to a
 * tenth of a cell in its grid's parameters (a fifth in x and y for the
 * terrain), which keeps every triangle's orientation and area. The
 * triangles are built consistently oriented; the closed surfaces are then
 * turned, all at once, so that their signed volume is positive (normals
 * outward). Orders: `made` is the construction order above, `random` and
 * `hilbert` number vertices by position and triangles by centroid as the
 * planar generator does, `hilbert` along a 3D Hilbert curve (Skilling's
 * transpose form, 21 bits per axis over the bounding cube). */
#include "generate.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"

#define PI 3.14159265358979323846
/* Share of a cell (of the grid's parameter step) a vertex may move. */
#define JITTER 0.1

static const char *const surface_names[] = {"plane", "sphere", "torus", "terrain"};

/* A symmetric jitter in [-amount, amount). */
static double jitter(emm_rng *r, double amount)
{
    return (2.0 * emm_rng_uniform(r) - 1.0) * amount;
}

/* ------------------------------------------------------------- surfaces */

struct built {
    double *xyz;
    size_t nv;
    int32_t *tri;
    size_t nt;
};

static emm_status alloc_built(struct built *b, size_t nv, size_t nt, emm_error *err)
{
    b->xyz = malloc(3 * nv * sizeof *b->xyz);
    b->tri = malloc(3 * nt * sizeof *b->tri);
    b->nv = nv;
    b->nt = nt;
    if (b->xyz && b->tri)
        return EMM_OK;
    free(b->xyz);
    free(b->tri);
    memset(b, 0, sizeof *b);
    return emm_fail(err, EMM_ERR_NOMEM, "generator: out of memory for %zu faces", nt);
}

static void put_tri(int32_t *t, size_t a, size_t b, size_t c)
{
    t[0] = (int32_t)a;
    t[1] = (int32_t)b;
    t[2] = (int32_t)c;
}

static void torus(size_t faces, emm_rng *r, struct built *b)
{
    const double R = 1.0, rt = 0.4;
    size_t V = faces / 2;
    /* Square cells: a vertices around the tube, k rings, k / a = R / r. */
    size_t a = (size_t)llround(sqrt((double)V * rt / R));
    if (a < 3)
        a = 3;
    size_t k = (V + a / 2) / a;
    double dtheta = 2 * PI / (double)a, dphi = 2 * PI / (double)k;
    for (size_t i = 0; i < V; i++) {
        double theta = 2 * PI * (double)((uint64_t)i * k % V) / (double)V;
        double phi = 2 * PI * (double)i / (double)V;
        theta += jitter(r, JITTER * dtheta);
        phi += jitter(r, JITTER * dphi);
        double ring = R + rt * cos(theta);
        b->xyz[3 * i] = ring * cos(phi);
        b->xyz[3 * i + 1] = ring * sin(phi);
        b->xyz[3 * i + 2] = rt * sin(theta);
    }
    for (size_t i = 0; i < V; i++) {
        size_t i1 = (i + 1) % V, ia = (i + a) % V, ia1 = (i + a + 1) % V;
        put_tri(b->tri + 6 * i, i, i1, ia1);
        put_tri(b->tri + 6 * i + 3, i, ia1, ia);
    }
}

static void sphere(size_t faces, emm_rng *r, struct built *b)
{
    size_t L = faces / 2;
    /* About equilateral at the equator: the vertical step of a turn, pi /
     * (turns + 2), is sqrt(3)/2 of the horizontal one, 2 pi / (m + 1/2). */
    size_t m = (size_t)llround(sqrt(sqrt(3.0) * (double)L));
    if (2 * m + 2 > L) /* the two boundary loops must not share a vertex */
        m = (L - 2) / 2;
    double per_turn = (double)m + 0.5;
    double turns = (double)(L - 1) / per_turn;
    double dlat = PI / (turns + 2), dlon = 2 * PI / per_turn;
    size_t south = 0, north = L + 1;
    b->xyz[0] = 0, b->xyz[1] = 0, b->xyz[2] = -1;
    for (size_t i = 0; i < L; i++) {
        double lat = -PI / 2 + dlat * (1 + (double)i / per_turn) + jitter(r, JITTER * dlat);
        double lon = dlon * (double)i + jitter(r, JITTER * dlon);
        double *p = b->xyz + 3 * (i + 1);
        p[0] = cos(lat) * cos(lon);
        p[1] = cos(lat) * sin(lon);
        p[2] = sin(lat);
    }
    double *p = b->xyz + 3 * north;
    p[0] = 0, p[1] = 0, p[2] = 1;
    /* Strip vertex i is vertex i + 1. */
    int32_t *t = b->tri;
    for (size_t i = 0; i + m + 1 < L; i++) {
        put_tri(t, i + 1, i + 2, i + m + 2);
        put_tri(t + 3, i + 1, i + m + 2, i + m + 1);
        t += 6;
    }
    /* The caps run their loop's edges the other way round. */
    for (size_t i = 0; i < m; i++, t += 3)
        put_tri(t, south, i + 2, i + 1);
    put_tri(t, south, 1, m + 1);
    t += 3;
    for (size_t j = L - m - 1; j + 1 < L; j++, t += 3)
        put_tri(t, north, j + 1, j + 2);
    put_tri(t, north, L, L - m);
    t += 3;
    assert((size_t)(t - b->tri) == 3 * b->nt);
}

#define MAX_HILLS 8

static void terrain(size_t faces, emm_rng *r, struct built *b)
{
    size_t q = faces / 2;
    size_t a = (size_t)llround(sqrt((double)q));
    size_t rows = q / a, part = q % a;
    bool odd = faces % 2, extra = part > 0 || odd;
    size_t cells_y = rows + (extra ? 1 : 0);
    double dx = 1.0 / (double)a, dy = 1.0 / (double)cells_y;

    struct { double cx, cy, s, h; } hill[MAX_HILLS];
    size_t hills = 4 + (size_t)(emm_rng_next(r) % 5);
    for (size_t k = 0; k < hills; k++) {
        hill[k].cx = emm_rng_uniform(r);
        hill[k].cy = emm_rng_uniform(r);
        hill[k].s = 0.08 + 0.17 * emm_rng_uniform(r);
        hill[k].h = -0.08 + 0.28 * emm_rng_uniform(r);
    }

    /* Vertex (row, col) of the full rows is row * (a + 1) + col; the
     * partial row's follow. A vertex is inner when all four quads around
     * it exist. */
    size_t nv = 0;
    for (size_t row = 0; row <= cells_y; row++) {
        size_t cols = row <= rows ? a + 1 : part + 1;
        for (size_t col = 0; col < cols; col++, nv++) {
            bool inner = row >= 1 && row <= rows && col >= 1 && col < a &&
                         (row < rows || col < part);
            double jx = jitter(r, 2 * JITTER * dx), jy = jitter(r, 2 * JITTER * dy);
            double x = (double)col * dx + (inner ? jx : 0.0);
            double y = (double)row * dy + (inner ? jy : 0.0);
            double z = 0;
            for (size_t k = 0; k < hills; k++) {
                double ex = x - hill[k].cx, ey = y - hill[k].cy;
                z += hill[k].h * exp(-(ex * ex + ey * ey) / (2 * hill[k].s * hill[k].s));
            }
            b->xyz[3 * nv] = x;
            b->xyz[3 * nv + 1] = y;
            b->xyz[3 * nv + 2] = z;
        }
    }
    assert(nv == b->nv);
    int32_t *t = b->tri;
    size_t w = a + 1;
    for (size_t row = 0; row < cells_y; row++) {
        size_t cols = row < rows ? a : part;
        for (size_t col = 0; col < cols; col++, t += 6) {
            size_t v00 = row * w + col, v10 = v00 + 1, v01 = v00 + w, v11 = v01 + 1;
            const double *p00 = b->xyz + 3 * v00, *p10 = b->xyz + 3 * v10;
            const double *p01 = b->xyz + 3 * v01, *p11 = b->xyz + 3 * v11;
            double d1 = hypot(p11[0] - p00[0], p11[1] - p00[1]);
            double d2 = hypot(p01[0] - p10[0], p01[1] - p10[1]);
            if (d1 <= d2) {
                put_tri(t, v00, v10, v11);
                put_tri(t + 3, v00, v11, v01);
            } else {
                put_tri(t, v00, v10, v01);
                put_tri(t + 3, v10, v11, v01);
            }
        }
    }
    if (odd) /* after the partial row: (rows, part), (rows, part + 1), above the first */
        put_tri(t, rows * w + part, rows * w + part + 1, (rows + 1) * w + part), t += 3;
    assert((size_t)(t - b->tri) == 3 * b->nt);
}

/* Six times the volume the closed surface encloses, signed by its
 * orientation. */
static double signed_volume6(const struct built *b)
{
    double v = 0;
    for (size_t t = 0; t < b->nt; t++) {
        const double *p = b->xyz + 3 * b->tri[3 * t], *q = b->xyz + 3 * b->tri[3 * t + 1];
        const double *s = b->xyz + 3 * b->tri[3 * t + 2];
        v += p[0] * (q[1] * s[2] - q[2] * s[1]) - p[1] * (q[0] * s[2] - q[2] * s[0]) +
             p[2] * (q[0] * s[1] - q[1] * s[0]);
    }
    return v;
}

/* ---------------------------------------------------------------- order */

/* Skilling's transform ("Programming the Hilbert curve", 2004): the axes'
 * bits turned into the transposed Hilbert index, then interleaved. */
uint64_t emm_hilbert3(uint32_t x[3], int bits)
{
    assert(bits >= 1 && bits <= 21);
    uint32_t m = 1u << (bits - 1);
    for (uint32_t qb = m; qb > 1; qb >>= 1) {
        uint32_t p = qb - 1;
        for (int i = 0; i < 3; i++) {
            if (x[i] & qb) {
                x[0] ^= p;
            } else {
                uint32_t t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
    }
    for (int i = 1; i < 3; i++)
        x[i] ^= x[i - 1];
    uint32_t t = 0;
    for (uint32_t qb = m; qb > 1; qb >>= 1)
        if (x[2] & qb)
            t ^= qb - 1;
    for (int i = 0; i < 3; i++)
        x[i] ^= t;
    uint64_t d = 0;
    for (int bit = bits - 1; bit >= 0; bit--)
        for (int i = 0; i < 3; i++)
            d = (d << 1) | ((x[i] >> bit) & 1u);
    return d;
}

struct cube {
    double lo[3], side;
};

static uint64_t hilbert_key3(const struct cube *c, const double p[3])
{
    const double top = (double)((1u << 21) - 1);
    uint32_t x[3];
    for (int i = 0; i < 3; i++) {
        double f = c->side > 0 ? (p[i] - c->lo[i]) / c->side : 0.0;
        x[i] = (uint32_t)fmin(top, fmax(0.0, f * top));
    }
    return emm_hilbert3(x, 21);
}

/* Numbers b's vertices and triangles in `order` into out (b's arrays are
 * kept, the caller frees them). */
static emm_status number(const struct built *b, emm_order order, uint64_t seed,
                         emm_gen_arrays *out, emm_error *err)
{
    size_t n = b->nv > b->nt ? b->nv : b->nt;
    emm_gen_keyed *keys = malloc(n * sizeof *keys);
    int32_t *map = malloc(b->nv * sizeof *map);
    double *xyz = malloc(3 * b->nv * sizeof *xyz);
    int32_t *tri = malloc(3 * b->nt * sizeof *tri);
    if (!keys || !map || !xyz || !tri) {
        free(keys);
        free(map);
        free(xyz);
        free(tri);
        return emm_fail(err, EMM_ERR_NOMEM, "generator: out of memory for %zu faces", b->nt);
    }
    struct cube c = {{INFINITY, INFINITY, INFINITY}, 0};
    double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < b->nv; v++)
        for (int i = 0; i < 3; i++) {
            c.lo[i] = fmin(c.lo[i], b->xyz[3 * v + i]);
            hi[i] = fmax(hi[i], b->xyz[3 * v + i]);
        }
    for (int i = 0; i < 3; i++)
        c.side = fmax(c.side, hi[i] - c.lo[i]);

    for (size_t v = 0; v < b->nv; v++) {
        keys[v].key = order == EMM_ORDER_HILBERT  ? hilbert_key3(&c, b->xyz + 3 * v)
                      : order == EMM_ORDER_RANDOM ? emm_gen_random_key(seed, v)
                                                  : v;
        keys[v].index = (uint32_t)v;
    }
    if (order != EMM_ORDER_MADE)
        qsort(keys, b->nv, sizeof *keys, emm_gen_keyed_cmp);
    for (size_t v = 0; v < b->nv; v++) {
        map[keys[v].index] = (int32_t)v;
        memcpy(xyz + 3 * v, b->xyz + 3 * keys[v].index, 3 * sizeof *xyz);
    }
    for (size_t t = 0; t < b->nt; t++) {
        const int32_t *v = b->tri + 3 * t;
        double centroid[3];
        for (int i = 0; i < 3; i++)
            centroid[i] =
                (b->xyz[3 * v[0] + i] + b->xyz[3 * v[1] + i] + b->xyz[3 * v[2] + i]) / 3.0;
        keys[t].key = order == EMM_ORDER_HILBERT  ? hilbert_key3(&c, centroid)
                      : order == EMM_ORDER_RANDOM ? emm_gen_random_key(seed ^ 0x5bd1e995u, t)
                                                  : t;
        keys[t].index = (uint32_t)t;
    }
    if (order != EMM_ORDER_MADE)
        qsort(keys, b->nt, sizeof *keys, emm_gen_keyed_cmp);
    for (size_t t = 0; t < b->nt; t++) {
        const int32_t *v = b->tri + 3 * keys[t].index;
        int32_t x = map[v[0]], y = map[v[1]], z = map[v[2]];
        /* Lowest id first, as the planar generator writes them; the
         * orientation stays. */
        int32_t *o = tri + 3 * t;
        if (x < y && x < z)
            o[0] = x, o[1] = y, o[2] = z;
        else if (y < z)
            o[0] = y, o[1] = z, o[2] = x;
        else
            o[0] = z, o[1] = x, o[2] = y;
    }
    free(keys);
    free(map);
    out->xyz = xyz;
    out->nv = b->nv;
    out->tri = tri;
    out->nt = b->nt;
    out->hull = 0;
    out->attempts = 1;
    return EMM_OK;
}

/* ------------------------------------------------------------ generator */

emm_status emm_gen_surface_build(const emm_gen_options *opt, emm_surface s, emm_gen_arrays *out,
                                 emm_error *err)
{
    assert(opt && out);
    memset(out, 0, sizeof *out);
    if (s != EMM_SURFACE_SPHERE && s != EMM_SURFACE_TORUS && s != EMM_SURFACE_TERRAIN)
        return emm_fail(err, EMM_ERR_INVALID, "generator: unknown surface %d", (int)s);
    if (opt->order != EMM_ORDER_MADE && opt->order != EMM_ORDER_RANDOM &&
        opt->order != EMM_ORDER_HILBERT)
        return emm_fail(err, EMM_ERR_INVALID, "generator: unknown order %d", (int)opt->order);
    const char *name = surface_names[s];
    size_t faces = opt->faces;
    bool closed = s != EMM_SURFACE_TERRAIN;
    size_t least = closed ? EMM_GEN_MIN_CLOSED_FACES : EMM_GEN_MIN_FACES;
    if (faces < least || faces > EMM_GEN_MAX_FACES)
        return emm_fail(err, EMM_ERR_RANGE,
                        "generator: %zu faces asked for; a %s has %zu to %u", faces, name, least,
                        EMM_GEN_MAX_FACES);
    if (closed && faces % 2)
        return emm_fail(err, EMM_ERR_RANGE,
                        "generator: %zu faces asked for; a %s has an even number of faces (each "
                        "edge joins two, each face has three)",
                        faces, name);

    size_t nv;
    if (s == EMM_SURFACE_SPHERE) {
        nv = faces / 2 + 2;
    } else if (s == EMM_SURFACE_TORUS) {
        nv = faces / 2;
    } else {
        size_t q = faces / 2, a = (size_t)llround(sqrt((double)q)), rows = q / a;
        nv = (rows + 1) * (a + 1) + (q % a > 0 || faces % 2 ? q % a + 1 : 0);
    }
    struct built b;
    emm_status st = alloc_built(&b, nv, faces, err);
    if (st != EMM_OK)
        return st;
    emm_rng r;
    emm_rng_seed(&r, opt->seed);
    if (s == EMM_SURFACE_SPHERE)
        sphere(faces, &r, &b);
    else if (s == EMM_SURFACE_TORUS)
        torus(faces, &r, &b);
    else
        terrain(faces, &r, &b);
    if (closed && signed_volume6(&b) < 0)
        for (size_t t = 0; t < b.nt; t++) {
            int32_t x = b.tri[3 * t + 1];
            b.tri[3 * t + 1] = b.tri[3 * t + 2];
            b.tri[3 * t + 2] = x;
        }
    st = number(&b, opt->order, opt->seed, out, err);
    free(b.xyz);
    free(b.tri);
    return st;
}
