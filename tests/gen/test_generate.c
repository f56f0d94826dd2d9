/* The generator's stages: qhull's Delaunay triangulation and the point set
 * and face count of emm_gen_arrays_build, checked without an emm_mesh. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "generate.h"

static double orient(const double *xyz, const int32_t *t)
{
    const double *a = xyz + 3 * t[0], *b = xyz + 3 * t[1], *c = xyz + 3 * t[2];
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

typedef struct edge {
    int32_t a, b; /* a < b */
    int32_t tri, opp; /* a triangle holding it and its third vertex */
} edge;

static int edge_cmp(const void *pa, const void *pb)
{
    const edge *x = pa, *y = pb;
    if (x->a != y->a)
        return x->a < y->a ? -1 : 1;
    if (x->b != y->b)
        return x->b < y->b ? -1 : 1;
    return (x->tri > y->tri) - (x->tri < y->tri);
}

/* True when d lies strictly inside the circle through a, b, c (a, b, c
 * counter-clockwise), with a relative tolerance. */
static bool in_circle(const double *a, const double *b, const double *c, const double *d)
{
    double adx = a[0] - d[0], ady = a[1] - d[1];
    double bdx = b[0] - d[0], bdy = b[1] - d[1];
    double cdx = c[0] - d[0], cdy = c[1] - d[1];
    double ad = adx * adx + ady * ady, bd = bdx * bdx + bdy * bdy, cd = cdx * cdx + cdy * cdy;
    double det = adx * (bdy * cd - bd * cdy) - ady * (bdx * cd - bd * cdx) + ad * (bdx * cdy - bdy * cdx);
    double scale = (fabs(adx) + fabs(ady)) * (fabs(bdx) + fabs(bdy)) * (fabs(cdx) + fabs(cdy)) *
                   (ad + bd + cd);
    return det > 1e-10 * scale;
}

struct shape {
    size_t boundary, interior, nonmanifold, not_delaunay, unused;
};

/* Edge structure, local Delaunay property of every interior edge, and
 * vertex use. */
static struct shape shape_of(const emm_gen_arrays *g)
{
    struct shape s = {0};
    edge *e = malloc(3 * g->nt * sizeof *e);
    char *used = calloc(g->nv, 1);
    REQUIRE(e && used);
    for (size_t t = 0; t < g->nt; t++)
        for (int k = 0; k < 3; k++) {
            int32_t u = g->tri[3 * t + k], v = g->tri[3 * t + (k + 1) % 3];
            used[u] = 1;
            e[3 * t + k] = (edge){u < v ? u : v, u < v ? v : u, (int32_t)t, g->tri[3 * t + (k + 2) % 3]};
        }
    qsort(e, 3 * g->nt, sizeof *e, edge_cmp);
    for (size_t i = 0; i < 3 * g->nt;) {
        size_t j = i + 1;
        while (j < 3 * g->nt && e[j].a == e[i].a && e[j].b == e[i].b)
            j++;
        if (j - i == 1) {
            s.boundary++;
        } else if (j - i == 2) {
            s.interior++;
            const int32_t *t = g->tri + 3 * e[i].tri;
            const double *d = g->xyz + 3 * e[i + 1].opp;
            if (in_circle(g->xyz + 3 * t[0], g->xyz + 3 * t[1], g->xyz + 3 * t[2], d))
                s.not_delaunay++;
        } else {
            s.nonmanifold++;
        }
        i = j;
    }
    for (size_t v = 0; v < g->nv; v++)
        s.unused += !used[v];
    free(e);
    free(used);
    return s;
}

/* Ratio of the fullest to the emptiest 8x8 bin of triangle centroids. */
static double bin_ratio(const emm_gen_arrays *g)
{
    size_t bins[64] = {0};
    for (size_t t = 0; t < g->nt; t++) {
        const int32_t *v = g->tri + 3 * t;
        double cx = (g->xyz[3 * v[0]] + g->xyz[3 * v[1]] + g->xyz[3 * v[2]]) / 3;
        double cy = (g->xyz[3 * v[0] + 1] + g->xyz[3 * v[1] + 1] + g->xyz[3 * v[2] + 1]) / 3;
        int bx = (int)(cx * 8), by = (int)(cy * 8);
        bx = bx < 0 ? 0 : bx > 7 ? 7 : bx;
        by = by < 0 ? 0 : by > 7 ? 7 : by;
        bins[by * 8 + bx]++;
    }
    /* The inner 6x6 bins: the outer ones are cut by the rounded hull. */
    size_t lo = bins[9], hi = bins[9];
    for (int i = 0; i < 64; i++) {
        if (i / 8 == 0 || i / 8 == 7 || i % 8 == 0 || i % 8 == 7)
            continue;
        lo = bins[i] < lo ? bins[i] : lo;
        hi = bins[i] > hi ? bins[i] : hi;
    }
    return (double)hi / (double)(lo ? lo : 1);
}

static void test_delaunay_small(void)
{
    /* A square and its centre: four triangles around the centre. */
    const double xy[] = {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0.5};
    int32_t *tri;
    size_t nt, degenerate;
    emm_error err;
    REQUIRE(emm_delaunay_2d(xy, 5, &tri, &nt, &degenerate, &err) == EMM_OK);
    CHECK(nt == 4);
    CHECK(degenerate == 0);
    for (size_t t = 0; t < nt; t++) {
        const int32_t *v = tri + 3 * t;
        CHECK(v[0] == 4 || v[1] == 4 || v[2] == 4);
        const double *a = xy + 2 * v[0], *b = xy + 2 * v[1], *c = xy + 2 * v[2];
        CHECK((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0);
    }
    free(tri);

    /* Four cocircular points alone: two triangles ('Qt'). */
    REQUIRE(emm_delaunay_2d(xy, 4, &tri, &nt, NULL, &err) == EMM_OK);
    CHECK(nt == 2);
    free(tri);

    /* Collinear and too few points are refused with a message. */
    const double line[] = {0, 0, 1, 1, 2, 2, 3, 3};
    CHECK(emm_delaunay_2d(line, 4, &tri, &nt, NULL, &err) == EMM_ERR_INVALID);
    CHECK(strncmp(err.message, "delaunay: ", 10) == 0 && strlen(err.message) > 12);
    CHECK(strchr(err.message, '\n') == NULL);
    CHECK(tri == NULL && nt == 0);
    CHECK(emm_delaunay_2d(xy, 2, &tri, &nt, NULL, &err) == EMM_ERR_INVALID);
}

/* Also gives the mesh's densest/sparsest bin ratio (test_density), so the
 * 20,000-face meshes are built once for both. */
static double test_counts(size_t faces, emm_density density, uint64_t seed)
{
    emm_gen_options opt = {faces, seed, density, EMM_ORDER_INPUT};
    emm_gen_arrays g;
    emm_error err;
    REQUIRE(emm_gen_arrays_build(&opt, &g, &err) == EMM_OK);
    CHECKF(g.nt == faces, "faces %zu density %d seed %llu: got %zu (%u attempts)", faces,
           (int)density, (unsigned long long)seed, g.nt, g.attempts);
    size_t neg = 0, outside = 0;
    for (size_t t = 0; t < g.nt; t++)
        neg += !(orient(g.xyz, g.tri + 3 * t) > 0);
    for (size_t v = 0; v < g.nv; v++) {
        const double *p = g.xyz + 3 * v;
        outside += !(p[0] >= 0 && p[0] <= 1 && p[1] >= 0 && p[1] <= 1 && p[2] == 0);
    }
    CHECKF(neg == 0, "%zu triangles not counter-clockwise", neg);
    CHECK(outside == 0);
    struct shape s = shape_of(&g);
    /* The boundary is the fixed convex hull. */
    CHECKF(s.boundary == g.hull, "boundary %zu hull %zu", s.boundary, g.hull);
    CHECK(s.nonmanifold == 0);
    CHECK(s.unused == 0);
    CHECKF(s.not_delaunay == 0, "%zu edges fail the empty-circle test", s.not_delaunay);
    /* Euler: V - E + F = 1 for a disc. */
    CHECK((long)g.nv - (long)(s.boundary + s.interior) + (long)g.nt == 1);
    double ratio = bin_ratio(&g);
    emm_gen_arrays_free(&g);
    return ratio;
}

static void test_determinism(void)
{
    emm_gen_options opt = {5000, 7, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
    emm_gen_arrays a, b, c;
    emm_error err;
    REQUIRE(emm_gen_arrays_build(&opt, &a, &err) == EMM_OK);
    REQUIRE(emm_gen_arrays_build(&opt, &b, &err) == EMM_OK);
    opt.seed = 8;
    REQUIRE(emm_gen_arrays_build(&opt, &c, &err) == EMM_OK);
    CHECK(a.nv == b.nv && a.nt == b.nt);
    CHECK(memcmp(a.xyz, b.xyz, 3 * a.nv * sizeof *a.xyz) == 0);
    CHECK(memcmp(a.tri, b.tri, 3 * a.nt * sizeof *a.tri) == 0);
    CHECK(c.nt == a.nt);
    CHECK(c.nv != a.nv || memcmp(a.xyz, c.xyz, 3 * a.nv * sizeof *a.xyz) != 0);
    emm_gen_arrays_free(&a);
    emm_gen_arrays_free(&b);
    emm_gen_arrays_free(&c);

    /* The random stream itself. */
    emm_rng r1, r2;
    emm_rng_seed(&r1, 1);
    emm_rng_seed(&r2, 1);
    for (int i = 0; i < 100; i++)
        CHECK(emm_rng_next(&r1) == emm_rng_next(&r2));
    emm_rng_seed(&r2, 2);
    CHECK(emm_rng_next(&r1) != emm_rng_next(&r2));
    double lo = 1, hi = 0;
    for (int i = 0; i < 10000; i++) {
        double u = emm_rng_uniform(&r1);
        lo = u < lo ? u : lo;
        hi = u > hi ? u : hi;
    }
    CHECK(lo >= 0 && lo < 0.01 && hi < 1 && hi > 0.99);
}

/* The 20,000-face meshes of seeds 1 to 3, clustered and uniform: their
 * bin ratios, as test_counts measured them. */
static void test_density(const double ratio[3][2])
{
    for (uint64_t seed = 1; seed <= 3; seed++) {
        double clustered = ratio[seed - 1][0], uniform = ratio[seed - 1][1];
        printf("seed %llu: densest/sparsest 8x8 bin: clustered %.1f, uniform %.2f\n",
               (unsigned long long)seed, clustered, uniform);
        CHECKF(clustered > 8.0, "clustered ratio %.2f", clustered);
        CHECKF(uniform < 2.0, "uniform ratio %.2f", uniform);
    }
}

static void test_errors(void)
{
    emm_gen_arrays g;
    emm_error err;
    emm_gen_options opt = {7, 1, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
    CHECK(emm_gen_arrays_build(&opt, &g, &err) == EMM_ERR_RANGE);
    CHECK(strstr(err.message, "7 faces") != NULL);
    opt.faces = (size_t)EMM_GEN_MAX_FACES + 1;
    CHECK(emm_gen_arrays_build(&opt, &g, &err) == EMM_ERR_RANGE);
    opt.faces = 100;
    opt.density = (emm_density)7;
    CHECK(emm_gen_arrays_build(&opt, &g, &err) == EMM_ERR_INVALID);
}

int main(void)
{
    test_delaunay_small();
    static const size_t sizes[] = {8, 9, 10, 11, 100, 101, 2000, 2001, 20000, 20001};
    double ratio[3][2] = {{0}};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++)
        for (uint64_t seed = 1; seed <= 3; seed++) {
            double c = test_counts(sizes[i], EMM_DENSITY_CLUSTERED, seed);
            double u = test_counts(sizes[i], EMM_DENSITY_UNIFORM, seed);
            if (sizes[i] == 20000) {
                ratio[seed - 1][0] = c;
                ratio[seed - 1][1] = u;
            }
        }
    test_determinism();
    test_density(ratio);
    test_errors();
    return check_done();
}
