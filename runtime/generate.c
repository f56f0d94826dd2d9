/* The mesh generator (docs/design.md "Workloads"): a planar Delaunay
 * triangulation of non-uniformly distributed points, like the thesis' test
 * mesh (§6.1: a 2D triangle mesh of 20,000 faces whose elements are not
 * uniformly distributed).
 *
 * Points. A fixed convex hull — h points spread evenly around the unit
 * square's border and pushed out radially onto the squircle |2x−1|⁴ +
 * |2y−1|⁴ = 1, so that they are strictly convex, h ≈ √(2·faces), about the
 * spacing of the points inside — plus interior points drawn strictly inside
 * it from one deterministic stream (xoshiro256**). (A hull of the square's
 * four corners alone made each side one edge, fanned by slivers from the
 * corners to points along it: a traversal that entered a corner went all
 * along the side.) `clustered` draws a seed-dependent
 * handful of Gaussian clusters (count, centres, widths and weights come from
 * the seed) over a uniform background share; `uniform` draws everything
 * uniformly. Points falling outside are redrawn (rejection, not clamping,
 * so nothing piles up on the border).
 *
 * Face count. A planar triangulation of n points with h of them on the hull
 * has 2n - h - 2 triangles. The hull is fixed, so n follows from the wanted
 * count exactly, and h has the count's parity.
 * Because the stream is drawn in order, asking for more points only appends
 * to the same set; if qhull leaves a point out (an exact duplicate) the
 * count is corrected by drawing more and triangulating again.
 *
 * Triangulation. qhull ("qhull d Qbb Qz Qt"): 'd' Delaunay by lifting to
 * the paraboloid, 'Qbb' scales the lifted coordinate for precision, 'Qz'
 * adds a point at infinity so cocircular sites do not cost precision, 'Qt' triangulates any merged (cocircular) region so the
 * output is all triangles. None of these options use qhull's random
 * generator, so a run is repeatable. Facets of the upper hull are skipped;
 * each triangle is turned counter-clockwise; a zero-area triangle (which
 * 'Qt' may produce for nearly collinear sites) is dropped and counted.
 *
 * Order. By default (EMM_ORDER_MADE) vertices keep the order of the point
 * stream and triangles qhull's facet order, which is spatially coherent.
 * EMM_ORDER_RANDOM numbers both in a seeded random order: the unorganised
 * "original layout" the thesis' cache baseline runs on (§6.3). With
 * EMM_ORDER_HILBERT
 * vertices are numbered along a Hilbert curve and triangles by the Hilbert
 * index of their centroid, as a mesher that renumbers for locality would
 * write them. */
#include "generate.h"

#include <assert.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <libqhull_r/qhull_ra.h>

#include "error.h"

/* ---------------------------------------------------------------- random */

static uint64_t splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return z ^ (z >> 31);
}

void emm_rng_seed(emm_rng *r, uint64_t seed)
{
    uint64_t x = seed;
    for (int i = 0; i < 4; i++)
        r->s[i] = splitmix64(&x);
}

static uint64_t rotl(uint64_t x, int k)
{
    return (x << k) | (x >> (64 - k));
}

uint64_t emm_rng_next(emm_rng *r)
{
    uint64_t *s = r->s;
    uint64_t result = rotl(s[1] * 5, 7) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

double emm_rng_uniform(emm_rng *r)
{
    return (double)(emm_rng_next(r) >> 11) * 0x1.0p-53;
}

/* ---------------------------------------------------------------- points */

#define MAX_CLUSTERS 8
/* Interior points keep this share of the hull's point spacing from it, so
 * that no triangle along the border is close to degenerate. */
#define MARGIN 0.25

struct cluster {
    double cx, cy, sigma;
    double cumulative; /* cumulative weight, the last one is 1 */
};

struct sampler {
    emm_rng rng;
    emm_density density;
    const double *hull; /* the hull's points, counter-clockwise */
    double *angle;      /* each hull point's angle around the centre, increasing */
    size_t h;
    double margin;      /* interior points keep this distance from every hull edge */
    double background; /* share of uniform points in `clustered` */
    size_t clusters;
    struct cluster c[MAX_CLUSTERS];
    bool have_spare;   /* Box-Muller makes normals in pairs */
    double spare;
};

static void sampler_init(struct sampler *s, const emm_gen_options *opt, const double *hull,
                         double *angle, size_t h)
{
    memset(s, 0, sizeof *s);
    emm_rng_seed(&s->rng, opt->seed);
    s->density = opt->density;
    s->hull = hull;
    s->angle = angle;
    s->h = h;
    for (size_t i = 0; i < h; i++) {
        angle[i] = atan2(hull[2 * i + 1] - 0.5, hull[2 * i] - 0.5);
        if (i > 0)
            while (angle[i] < angle[i - 1])
                angle[i] += 2 * 3.14159265358979323846;
    }
    s->margin = MARGIN * hypot(hull[2] - hull[0], hull[3] - hull[1]);
    if (opt->density != EMM_DENSITY_CLUSTERED)
        return;
    /* 3 to 8 clusters, 30-45% background; widths 0.04-0.12 (log-uniform),
     * centres away from the border so that clusters are mostly inside. The
     * densest regions are then a few times denser than the mean and some 20
     * times denser than the sparsest: non-uniform as the thesis' mesh (§6.1),
     * yet a grid cell of a few hundred triangles on average still fits the
     * local store, as the thesis' grid strategies did. */
    s->clusters = 3 + (size_t)(emm_rng_next(&s->rng) % 6);
    s->background = 0.30 + 0.15 * emm_rng_uniform(&s->rng);
    double total = 0;
    for (size_t i = 0; i < s->clusters; i++) {
        struct cluster *c = &s->c[i];
        c->cx = 0.12 + 0.76 * emm_rng_uniform(&s->rng);
        c->cy = 0.12 + 0.76 * emm_rng_uniform(&s->rng);
        c->sigma = 0.04 * pow(0.12 / 0.04, emm_rng_uniform(&s->rng));
        total += 0.5 + emm_rng_uniform(&s->rng);
        c->cumulative = total;
    }
    for (size_t i = 0; i < s->clusters; i++)
        s->c[i].cumulative /= total;
    s->c[s->clusters - 1].cumulative = 1.0;
}

static double sampler_normal(struct sampler *s)
{
    if (s->have_spare) {
        s->have_spare = false;
        return s->spare;
    }
    double u1 = emm_rng_uniform(&s->rng), u2 = emm_rng_uniform(&s->rng);
    double r = sqrt(-2.0 * log(1.0 - u1)); /* 1 - u1 is in (0, 1] */
    double a = 2.0 * 3.14159265358979323846 * u2;
    s->spare = r * sin(a);
    s->have_spare = true;
    return r * cos(a);
}

/* Strictly inside the hull, at least `margin` from its edges: the edge is
 * the one whose angular sector around the centre holds the point. */
static bool inside(const struct sampler *s, double x, double y)
{
    double a = atan2(y - 0.5, x - 0.5);
    while (a < s->angle[0])
        a += 2 * 3.14159265358979323846;
    size_t lo = 0, hi = s->h; /* the last i with angle[i] <= a */
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (s->angle[mid] <= a)
            lo = mid;
        else
            hi = mid;
    }
    const double *p = s->hull + 2 * lo, *q = s->hull + 2 * ((lo + 1) % s->h);
    double ex = q[0] - p[0], ey = q[1] - p[1];
    double cross = ex * (y - p[1]) - ey * (x - p[0]);
    return cross > s->margin * hypot(ex, ey);
}

/* h hull points, evenly spaced along the square's border (starting at the
 * middle of the bottom side, so that when 4 divides h the four sides'
 * middles are among them and the bounding box is the unit square), pushed
 * out radially onto the squircle: in convex position, counter-clockwise. */
static void hull_points(size_t h, double *xy)
{
    for (size_t i = 0; i < h; i++) {
        double t = fmod(0.5 + 4.0 * (double)i / (double)h, 4.0), u, v; /* along [-1, 1]^2's border */
        if (t < 1)
            u = -1 + 2 * t, v = -1;
        else if (t < 2)
            u = 1, v = -1 + 2 * (t - 1);
        else if (t < 3)
            u = 1 - 2 * (t - 2), v = 1;
        else
            u = -1, v = 1 - 2 * (t - 3);
        double r = pow(u * u * u * u + v * v * v * v, -0.25);
        xy[2 * i] = (1 + u * r) / 2;
        xy[2 * i + 1] = (1 + v * r) / 2;
    }
}

static void sampler_point(struct sampler *s, double *xy)
{
    for (;;) {
        double x, y;
        if (s->density != EMM_DENSITY_CLUSTERED || emm_rng_uniform(&s->rng) < s->background) {
            x = emm_rng_uniform(&s->rng);
            y = emm_rng_uniform(&s->rng);
        } else {
            double u = emm_rng_uniform(&s->rng);
            size_t k = 0;
            while (k + 1 < s->clusters && u >= s->c[k].cumulative)
                k++;
            x = s->c[k].cx + s->c[k].sigma * sampler_normal(s);
            y = s->c[k].cy + s->c[k].sigma * sampler_normal(s);
        }
        if (inside(s, x, y)) {
            xy[0] = x;
            xy[1] = y;
            return;
        }
    }
}

/* ----------------------------------------------------------- triangulate */

/* Copies the first line qhull wrote to its error stream into err. */
static emm_status qhull_fail(emm_error *err, emm_status status, int code, char *text)
{
    char *line = text ? text : "";
    while (*line == '\n' || *line == ' ')
        line++;
    line[strcspn(line, "\n")] = '\0';
    if (!*line)
        return emm_fail(err, status, "delaunay: qhull failed (exit code %d)", code);
    return emm_fail(err, status, "delaunay: %s", line);
}

emm_status emm_delaunay_2d(const double *xy, size_t n, int32_t **tri, size_t *nt,
                           size_t *degenerate, emm_error *err)
{
    assert(xy && tri && nt);
    *tri = NULL;
    *nt = 0;
    if (degenerate)
        *degenerate = 0;
    if (n < 3)
        return emm_fail(err, EMM_ERR_INVALID, "delaunay: %zu points, at least 3 are needed", n);
    if (n > (size_t)INT32_MAX / 2)
        return emm_fail(err, EMM_ERR_RANGE, "delaunay: %zu points, at most %d are accepted", n,
                        INT32_MAX / 2);

    /* qhull takes a non-const array; keep the caller's untouched. */
    coordT *pts = malloc(2 * n * sizeof *pts);
    qhT *qh = calloc(1, sizeof *qh);
    char *errtext = NULL;
    size_t errlen = 0;
    FILE *errfile = open_memstream(&errtext, &errlen); /* qhull never prints */
    if (!pts || !qh || !errfile) {
        free(pts);
        free(qh);
        if (errfile)
            fclose(errfile);
        free(errtext);
        return emm_fail(err, EMM_ERR_NOMEM, "delaunay: out of memory for %zu points", n);
    }
    for (size_t i = 0; i < 2 * n; i++)
        pts[i] = xy[i];

    char options[] = "qhull d Qbb Qz Qt";
    emm_status st = EMM_OK;
    int32_t *out = NULL;
    size_t count = 0, dropped = 0;
    qh_zero(qh, errfile);
    int code = qh_new_qhull(qh, 2, (int)n, pts, False, options, NULL, errfile);
    if (code != 0) {
        fflush(errfile);
        st = qhull_fail(err, code == qh_ERRmem ? EMM_ERR_NOMEM : EMM_ERR_INVALID, code, errtext);
    } else {
        facetT *facet;
        vertexT *vertex, **vertexp;
        size_t lower = 0;
        FORALLfacets {
            if (!facet->upperdelaunay)
                lower++;
        }
        out = malloc((lower ? lower : 1) * 3 * sizeof *out);
        if (!out) {
            st = emm_fail(err, EMM_ERR_NOMEM, "delaunay: out of memory for %zu triangles", lower);
        } else {
            FORALLfacets {
                if (facet->upperdelaunay)
                    continue;
                int32_t v[3];
                int k = 0;
                FOREACHvertex_(facet->vertices) {
                    if (k < 3)
                        v[k] = (int32_t)qh_pointid(qh, vertex->point);
                    k++;
                }
                /* 'Qt' makes every facet a triangle; 'Qz''s point at infinity
                 * is only on upper facets. Anything else is qhull's bug, but
                 * costs nothing to survive. */
                if (k != 3 || v[0] < 0 || v[1] < 0 || v[2] < 0 || (size_t)v[0] >= n ||
                    (size_t)v[1] >= n || (size_t)v[2] >= n) {
                    dropped++;
                    continue;
                }
                const double *a = xy + 2 * v[0], *b = xy + 2 * v[1], *c = xy + 2 * v[2];
                double area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
                if (area2 == 0.0) {
                    dropped++;
                    continue;
                }
                if (area2 < 0) {
                    int32_t t = v[1];
                    v[1] = v[2];
                    v[2] = t;
                }
                memcpy(out + 3 * count, v, sizeof v);
                count++;
            }
        }
    }
    int curlong, totlong;
    qh_freeqhull(qh, !qh_ALL);
    qh_memfreeshort(qh, &curlong, &totlong);
    fclose(errfile);
    free(errtext);
    free(qh);
    free(pts);
    if (st != EMM_OK) {
        free(out);
        return st;
    }
    *tri = out;
    *nt = count;
    if (degenerate)
        *degenerate = dropped;
    return EMM_OK;
}

/* ------------------------------------------------------------- ordering */

/* Hilbert index of (x, y) on a 2^16 x 2^16 grid over the unit square. */
static uint64_t hilbert_key(double x, double y)
{
    const uint32_t side = 1u << 16;
    double fx = x * side, fy = y * side;
    uint32_t ix = fx <= 0 ? 0 : fx >= side - 1 ? side - 1 : (uint32_t)fx;
    uint32_t iy = fy <= 0 ? 0 : fy >= side - 1 ? side - 1 : (uint32_t)fy;
    uint64_t d = 0;
    for (uint32_t s = side / 2; s > 0; s /= 2) {
        uint32_t rx = (ix & s) ? 1 : 0, ry = (iy & s) ? 1 : 0;
        d += (uint64_t)s * s * ((3 * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                ix = side - 1 - ix;
                iy = side - 1 - iy;
            }
            uint32_t t = ix;
            ix = iy;
            iy = t;
        }
    }
    return d;
}

/* Ties keep the earlier element first. */
int emm_gen_keyed_cmp(const void *pa, const void *pb)
{
    const emm_gen_keyed *a = pa, *b = pb;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return a->index < b->index ? -1 : a->index > b->index;
}

/* A random key for element i under `seed` (splitmix64): the `random`
 * order, the same for the same seed. */
uint64_t emm_gen_random_key(uint64_t seed, uint64_t i)
{
    uint64_t z = seed * 0x9e3779b97f4a7c15ull + i + 0x632be59bd9b4e019ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Keeps the used points only, numbers vertices and triangles in `order`,
 * and writes the result into `out`. */
static emm_status compact(const double *xy, size_t n, const int32_t *tri, size_t nt,
                          emm_order order, uint64_t seed, emm_gen_arrays *out, emm_error *err)
{
    int32_t *map = malloc(n * sizeof *map);
    emm_gen_keyed *keys = malloc((n > nt ? n : nt) * sizeof *keys);
    double *xyz = NULL;
    int32_t *ntri = malloc((nt ? nt : 1) * 3 * sizeof *ntri);
    if (!map || !keys || !ntri)
        goto nomem;
    for (size_t i = 0; i < n; i++)
        map[i] = -1;
    for (size_t i = 0; i < 3 * nt; i++)
        map[tri[i]] = 0;
    size_t nv = 0;
    for (size_t i = 0; i < n; i++)
        if (map[i] == 0) {
            keys[nv].key = order == EMM_ORDER_HILBERT ? hilbert_key(xy[2 * i], xy[2 * i + 1])
                           : order == EMM_ORDER_RANDOM ? emm_gen_random_key(seed, i)
                                                       : i;
            keys[nv].index = (uint32_t)i;
            nv++;
        }
    qsort(keys, nv, sizeof *keys, emm_gen_keyed_cmp);
    xyz = malloc((nv ? nv : 1) * 3 * sizeof *xyz);
    if (!xyz)
        goto nomem;
    for (size_t i = 0; i < nv; i++) {
        uint32_t p = keys[i].index;
        map[p] = (int32_t)i;
        xyz[3 * i] = xy[2 * p];
        xyz[3 * i + 1] = xy[2 * p + 1];
        xyz[3 * i + 2] = 0.0;
    }
    for (size_t t = 0; t < nt; t++) {
        const int32_t *v = tri + 3 * t;
        double cx = (xy[2 * v[0]] + xy[2 * v[1]] + xy[2 * v[2]]) / 3.0;
        double cy = (xy[2 * v[0] + 1] + xy[2 * v[1] + 1] + xy[2 * v[2] + 1]) / 3.0;
        keys[t].key = order == EMM_ORDER_HILBERT  ? hilbert_key(cx, cy)
                      : order == EMM_ORDER_RANDOM ? emm_gen_random_key(seed ^ 0x5bd1e995u, t)
                                                  : t;
        keys[t].index = (uint32_t)t;
    }
    qsort(keys, nt, sizeof *keys, emm_gen_keyed_cmp);
    for (size_t t = 0; t < nt; t++) {
        const int32_t *v = tri + 3 * keys[t].index;
        int32_t a = map[v[0]], b = map[v[1]], c = map[v[2]];
        /* Rotate the lowest id first; the orientation stays. */
        int32_t *o = ntri + 3 * t;
        if (a < b && a < c) {
            o[0] = a, o[1] = b, o[2] = c;
        } else if (b < c) {
            o[0] = b, o[1] = c, o[2] = a;
        } else {
            o[0] = c, o[1] = a, o[2] = b;
        }
    }
    free(map);
    free(keys);
    out->xyz = xyz;
    out->nv = nv;
    out->tri = ntri;
    out->nt = nt;
    return EMM_OK;
nomem:
    free(map);
    free(keys);
    free(xyz);
    free(ntri);
    return emm_fail(err, EMM_ERR_NOMEM, "generated mesh: out of memory for %zu points", n);
}

/* ------------------------------------------------------------- generator */

void emm_gen_arrays_free(emm_gen_arrays *a)
{
    if (!a)
        return;
    free(a->xyz);
    free(a->tri);
    memset(a, 0, sizeof *a);
}

static size_t diff(size_t a, size_t b)
{
    return a > b ? a - b : b - a;
}

size_t emm_gen_hull_points(size_t faces)
{
    /* About the spacing of the points inside: h ~ 2 sqrt(n), n ~ faces / 2. */
    size_t h = (size_t)llround(sqrt(2.0 * (double)faces));
    if (h < 4)
        h = 4;
    if ((h + faces) % 2)
        h++;
    return h;
}

emm_status emm_gen_arrays_build(const emm_gen_options *opt, emm_gen_arrays *out, emm_error *err)
{
    assert(opt && out);
    memset(out, 0, sizeof *out);
    const size_t want = opt->faces;
    if (want < EMM_GEN_MIN_FACES || want > EMM_GEN_MAX_FACES)
        return emm_fail(err, EMM_ERR_RANGE,
                        "generator: %zu faces asked for; the generator makes %u to %u", want,
                        EMM_GEN_MIN_FACES, EMM_GEN_MAX_FACES);
    if (opt->density != EMM_DENSITY_CLUSTERED && opt->density != EMM_DENSITY_UNIFORM)
        return emm_fail(err, EMM_ERR_INVALID, "generator: unknown density %d", (int)opt->density);

    const size_t hull = emm_gen_hull_points(want);
    /* faces = 2 n - hull - 2 with n = hull + interior */
    size_t interior = (want + 2 - hull) / 2;
    size_t cap = hull + interior + interior / 64 + 16, drawn = hull;
    double *xy = malloc(2 * cap * sizeof *xy);
    double *hxy = malloc(2 * hull * sizeof *hxy), *angle = malloc(hull * sizeof *angle);
    if (!xy || !hxy || !angle) {
        free(xy);
        free(hxy);
        free(angle);
        return emm_fail(err, EMM_ERR_NOMEM, "generator: out of memory for %zu points", cap);
    }
    hull_points(hull, hxy);
    memcpy(xy, hxy, 2 * hull * sizeof *xy);
    struct sampler s;
    sampler_init(&s, opt, hxy, angle, hull);

    emm_status st = EMM_OK;
    int32_t *best = NULL;
    size_t best_nt = 0, best_n = 0;
    unsigned attempt = 0;
    while (attempt < 8) {
        size_t n = hull + interior;
        if (n > cap) {
            size_t ncap = n + n / 16;
            double *grown = realloc(xy, 2 * ncap * sizeof *xy);
            if (!grown) {
                st = emm_fail(err, EMM_ERR_NOMEM, "generator: out of memory for %zu points", ncap);
                break;
            }
            xy = grown;
            cap = ncap;
        }
        for (; drawn < n; drawn++)
            sampler_point(&s, xy + 2 * drawn);
        int32_t *tri;
        size_t nt;
        attempt++;
        st = emm_delaunay_2d(xy, n, &tri, &nt, NULL, err);
        if (st != EMM_OK)
            break;
        if (!best || diff(nt, want) < diff(best_nt, want)) {
            free(best);
            best = tri;
            best_nt = nt;
            best_n = n;
        } else {
            free(tri);
        }
        if (nt == want)
            break;
        /* Each interior point adds two faces. */
        size_t step = diff(nt, want) / 2;
        if (step == 0)
            break;
        if (nt < want)
            interior += step;
        else if (step < interior)
            interior -= step;
        else
            break;
    }
    if (st == EMM_OK && diff(best_nt, want) * 100 > want)
        st = emm_fail(err, EMM_ERR_RANGE,
                      "generator: could only reach %zu faces of the %zu asked for", best_nt, want);
    if (st == EMM_OK)
        st = compact(xy, best_n, best, best_nt, opt->order, opt->seed, out, err);
    if (st == EMM_OK) {
        out->hull = hull;
        out->attempts = attempt;
    }
    free(best);
    free(xy);
    free(hxy);
    free(angle);
    return st;
}

emm_status emm_mesh_generate(const emm_gen_options *opt, emm_mesh **out, emm_error *err)
{
    assert(opt && out);
    *out = NULL;
    emm_gen_arrays a;
    emm_status st = emm_gen_arrays_build(opt, &a, err);
    if (st != EMM_OK)
        return st;
    st = emm_mesh_from_arrays(a.xyz, a.nv, a.tri, a.nt, "generated mesh", out, err);
    emm_gen_arrays_free(&a);
    return st;
}

emm_status emm_mesh_generate_surface(const emm_gen_options *opt, emm_surface surface,
                                     emm_mesh **out, emm_error *err)
{
    assert(opt && out);
    *out = NULL;
    if (surface == EMM_SURFACE_PLANE)
        return emm_mesh_generate(opt, out, err);
    emm_gen_arrays a;
    emm_status st = emm_gen_surface_build(opt, surface, &a, err);
    if (st != EMM_OK)
        return st;
    st = emm_mesh_from_arrays(a.xyz, a.nv, a.tri, a.nt, "generated mesh", out, err);
    emm_gen_arrays_free(&a);
    return st;
}
