/* The exact method against a naive double loop and, bit for bit, against
 * its kernel's lane-order row sums, the fast method within its
 * stated bound (thesis Eq. 5.1), the profiler's position extraction, and the
 * features' argument checks; then the same in space (positions of 3
 * coordinates, the fast method's octree), a plane laid in space against
 * the plane, and the plane's profiles against values the 2D-only profiler
 * gave. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "emm/profile.h"

static uint64_t rng = 12345;
static double unit(void)
{
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng >> 11) * 0x1.0p-53;
}

/* The naive double loop, in index order. Each distance is the square root
 * of the sum of squares, within an ulp or two of the true distance for
 * positions in the unit square (no overflow or underflow to guard against,
 * which is all hypot adds, at ten times the cost), far inside the 1e-12
 * the exact method is held to. */
static void brute(const double *xy, size_t n, double *D)
{
    for (size_t i = 0; i < n; i++) {
        double s = 0;
        for (size_t k = 0; k < i; k++) {
            double dx = xy[2 * i] - xy[2 * k], dy = xy[2 * i + 1] - xy[2 * k + 1];
            s += sqrt(dx * dx + dy * dy);
        }
        D[i] = s;
    }
}

enum { UNIFORM, CLUSTERED, CURVES, DUPLICATES };

static void points(int kind, double *xy, size_t n)
{
    double cx[5], cy[5];
    for (int c = 0; c < 5; c++) {
        cx[c] = unit();
        cy[c] = unit();
    }
    double x = unit(), y = unit(), a = unit() * 6.28;
    for (size_t i = 0; i < n; i++) {
        switch (kind) {
        case UNIFORM:
            x = unit();
            y = 0.6 * unit();
            break;
        case CLUSTERED: {
            int c = (int)(unit() * 5);
            double r = 0.02 * sqrt(-2 * log(unit() + 1e-300)), t = 6.283185 * unit();
            x = cx[c] + r * cos(t);
            y = cy[c] + r * sin(t);
            break;
        }
        case CURVES:
            /* straight walks that restart at random places */
            if (unit() < 0.002 || x < 0 || x > 1 || y < 0 || y > 1) {
                x = unit();
                y = unit();
                a = unit() * 6.283185;
            }
            x += 0.001 * cos(a);
            y += 0.001 * sin(a);
            break;
        case DUPLICATES:
            /* few distinct positions, each visited many times */
            x = (double)(int)(unit() * 4) / 4;
            y = (double)(int)(unit() * 4) / 4;
            break;
        }
        xy[2 * i] = x;
        xy[2 * i + 1] = y;
    }
}

static double max_rel(const double *a, const double *b, size_t n)
{
    double m = 0;
    for (size_t i = 0; i < n; i++) {
        double e = fabs(a[i] - b[i]);
        double r = b[i] > 0 ? e / b[i] : e;
        if (r > m)
            m = r;
    }
    return m;
}

static void test_exact(void)
{
    static const size_t sizes[] = {0, 1, 2, 3, 7, 8, 9, 100, 1000, 2047, 2048, 2049, 5000};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (int kind = UNIFORM; kind <= DUPLICATES; kind++) {
            size_t n = sizes[s];
            double *xy = malloc((2 * n + 2) * sizeof *xy);
            double *D = malloc((n + 1) * sizeof *D), *R = malloc((n + 1) * sizeof *R);
            points(kind, xy, n);
            emm_profile_exact(xy, n, 2, D, NULL);
            brute(xy, n, R);
            double e = max_rel(D, R, n);
            CHECKF(e <= 1e-12, "exact n=%zu kind=%d: relative error %g", n, kind, e);
            if (n > 0)
                CHECK(D[0] == 0);
            free(xy);
            free(D);
            free(R);
        }
}

/* Row i as the kernel sums it: the terms round L lanes (8 with AVX2, 4
 * without) over whole blocks of L, the lanes added pairwise, then the
 * tail's terms one by one. The exact method shares the work of the rows of
 * a point that recurs; its rows must still be these, bit for bit. */
static double lane_row(const double *xy, size_t i)
{
    __builtin_cpu_init();
    size_t L = __builtin_cpu_supports("avx2") ? 8 : 4, k = 0;
    double acc[8] = {0};
    double px = xy[2 * i], py = xy[2 * i + 1];
    for (; k + L <= i; k += L)
        for (size_t j = 0; j < L; j++) {
            double dx = xy[2 * (k + j)] - px, dy = xy[2 * (k + j) + 1] - py;
            acc[j] += sqrt(dx * dx + dy * dy);
        }
    double s;
    if (L == 8) {
        double l0 = acc[0] + acc[4], l1 = acc[1] + acc[5], l2 = acc[2] + acc[6],
               l3 = acc[3] + acc[7];
        s = (l0 + l1) + (l2 + l3);
    } else {
        s = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    }
    for (; k < i; k++) {
        double dx = xy[2 * k] - px, dy = xy[2 * k + 1] - py;
        s += sqrt(dx * dx + dy * dy);
    }
    return s;
}

static void test_exact_rows(void)
{
    static const size_t sizes[] = {1, 9, 17, 100, 2047, 2048, 4099};
    uint64_t saved = rng; /* the other tests' points stay as they were */
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (int kind = UNIFORM; kind <= DUPLICATES + 1; kind++) {
            size_t n = sizes[s];
            double *xy = malloc(2 * n * sizeof *xy), *D = malloc(n * sizeof *D);
            if (kind <= DUPLICATES) {
                points(kind, xy, n);
            } else {
                /* a mesh traversal: each position read again a few accesses on */
                points(UNIFORM, xy, n);
                for (size_t i = 4; i < n; i++)
                    if (unit() < 0.7) {
                        size_t from = i - 1 - (size_t)(unit() * 4);
                        xy[2 * i] = xy[2 * from];
                        xy[2 * i + 1] = xy[2 * from + 1];
                    }
            }
            emm_profile_exact(xy, n, 2, D, NULL);
            size_t bad = 0;
            for (size_t i = 0; i < n; i++)
                bad += memcmp(&D[i], &(double){lane_row(xy, i)}, sizeof D[i]) != 0;
            CHECKF(bad == 0, "exact n=%zu kind=%d: %zu rows differ from the lane-order sum", n,
                   kind, bad);
            free(xy);
            free(D);
        }
    rng = saved;
}

static void test_fast(void)
{
    static const double thetas[] = {0.1, 0.147, 0.3, EMM_PROFILE_THETA, 0.7};
    for (int kind = UNIFORM; kind <= DUPLICATES; kind++) {
        size_t n = kind == CURVES ? 100000 : 20000;
        double *xy = malloc(2 * n * sizeof *xy);
        double *D = malloc(n * sizeof *D), *R = malloc(n * sizeof *R);
        points(kind, xy, n);
        emm_profile_exact(xy, n, 2, R, NULL);
        for (size_t t = 0; t < sizeof thetas / sizeof thetas[0]; t++) {
            emm_error err;
            REQUIRE(emm_profile_fast(xy, n, 2, thetas[t], D, NULL, &err) == EMM_OK);
            double e = max_rel(D, R, n), bound = emm_profile_fast_bound(thetas[t]);
            printf("fast kind=%d n=%zu theta=%.3f: max relative error %.3g (bound %.3g)\n", kind,
                   n, thetas[t], e, bound);
            CHECKF(e <= bound, "fast kind=%d theta=%g: %g > bound %g", kind, thetas[t], e, bound);
            /* What the default is chosen for: 1e-3 on access-like sequences
             * (the 4x4 lattice of DUPLICATES is adversarial, not access-like). */
            if (thetas[t] == EMM_PROFILE_THETA && kind != DUPLICATES)
                CHECKF(e <= 1e-3, "fast kind=%d at the default theta: %g > 1e-3", kind, e);
        }
        /* Beyond EMM_PROFILE_EXACT_MAX, emm_profile_compute runs the fast
         * method within its bound (checked here, where the exact profile
         * to compare with is already computed). */
        if (n > EMM_PROFILE_EXACT_MAX) {
            int exact = -1;
            emm_error err;
            REQUIRE(emm_profile_compute(xy, n, 2, D, &exact, NULL, &err) == EMM_OK);
            CHECK(exact == 0);
            CHECK(max_rel(D, R, n) <= emm_profile_fast_bound(EMM_PROFILE_THETA));
        }
        free(xy);
        free(D);
        free(R);
    }
    /* One thread or two: the same profile, to the bit. */
    {
        size_t n = 30000;
        double *xy = malloc(2 * n * sizeof *xy), *D1 = malloc(n * sizeof *D1),
               *D2 = malloc(n * sizeof *D2);
        points(CURVES, xy, n);
        emm_threads one = {1, NULL, NULL}, two = {2, NULL, NULL};
        emm_error err;
        REQUIRE(emm_profile_fast(xy, n, 2, EMM_PROFILE_THETA, D1, &one, &err) == EMM_OK);
        REQUIRE(emm_profile_fast(xy, n, 2, EMM_PROFILE_THETA, D2, &two, &err) == EMM_OK);
        CHECK(memcmp(D1, D2, n * sizeof *D1) == 0);
        free(xy);
        free(D1);
        free(D2);
    }
    CHECK(emm_profile_fast_bound(0.147) <= 1e-3);
    CHECK(emm_profile_fast_bound(0.5) > emm_profile_fast_bound(0.3));
    CHECK(isinf(emm_profile_fast_bound(1.0)));

    emm_error err;
    double xy[4] = {0, 0, 1, 1}, D[2];
    CHECK(emm_profile_fast(xy, 2, 2, 0.0, D, NULL, &err) == EMM_ERR_RANGE);
    CHECK(emm_profile_fast(xy, 2, 2, 1.0, D, NULL, &err) == EMM_ERR_RANGE);
    CHECK(strstr(err.message, "opening angle") != NULL);
    CHECK(emm_profile_fast(xy, 2, 2, 0.5, D, NULL, &err) == EMM_OK);
    CHECK(D[0] == 0 && fabs(D[1] - sqrt(2.0)) < 1e-15);
}

/* emm_profile_compute picks by length: exact up to EMM_PROFILE_EXACT_MAX,
 * beyond it the fast method at EMM_PROFILE_THETA, to the bit (its error
 * against the exact profile beyond the limit: test_fast, on the curves). */
static void test_compute(void)
{
    size_t n = EMM_PROFILE_EXACT_MAX + 1000;
    double *xy = malloc(2 * n * sizeof *xy), *D = malloc(n * sizeof *D);
    points(UNIFORM, xy, n);
    int exact = -1;
    emm_error err;
    REQUIRE(emm_profile_compute(xy, 1000, 2, D, &exact, NULL, &err) == EMM_OK);
    CHECK(exact == 1);
    double *R = malloc(1000 * sizeof *R);
    emm_profile_exact(xy, 1000, 2, R, NULL);
    CHECK(memcmp(D, R, 1000 * sizeof *D) == 0);
    REQUIRE(emm_profile_compute(xy, n, 2, D, &exact, NULL, &err) == EMM_OK);
    CHECK(exact == 0);
    double *F = malloc(n * sizeof *F);
    REQUIRE(emm_profile_fast(xy, n, 2, EMM_PROFILE_THETA, F, NULL, &err) == EMM_OK);
    CHECK(memcmp(D, F, n * sizeof *D) == 0);
    free(F);
    free(R);
    free(xy);
    free(D);
}

static void test_profiler(void)
{
    /* Two vertices and a triangle; a RAW array in between is skipped. */
    double xyz[] = {0, 0, 5, 3, 0, 5, 0, 4, 5};
    int32_t tri[] = {0, 1, 2};
    emm_trace_array arrays[3] = {
        {EMM_ARRAY_VERTICES, 80, 3, 0}, {EMM_ARRAY_TRIANGLES, 28, 1, 4096}, {EMM_ARRAY_RAW, 1, 0, 0}};
    emm_trace_info info = {.version = 1, .narrays = 3, .arrays = arrays,
                           .geometry = {3, 1, xyz, tri}};
    emm_profiler *p;
    emm_error err;
    REQUIRE(emm_profiler_new(&info, 3, 2, "t", &p, &err) == EMM_OK);
    emm_trace_record recs[] = {
        {0, 0, 8, 8, 0, 0, 0}, {1, 0, 8, 8, 0, 0, 0}, /* a leading index-order sweep: left out */
        {77, 2, 0, 4, 0, 0, 0},                     /* RAW: no position */
        {0, 0, 8, 8, 0, 0, 0}, {0, 0, 16, 8, 0, 0, 0}, /* breaks the sweep; one element access */
        {0, 1, 4, 24, 0, 0, 0},                     /* the triangle: its centroid */
        {2, 0, 8, 8, 0, 0, 0},
        {1, 0, 8, 8, 0, 0, 0},                      /* past the window */
    };
    REQUIRE(emm_profiler_add(p, recs, 8, &err) == EMM_OK);
    CHECK(emm_profiler_full(p));
    size_t sweep_records;
    CHECK(emm_profiler_swept(p, &sweep_records) == 2);
    CHECK(sweep_records == 3);
    size_t n;
    const double *xy = emm_profiler_positions(p, &n);
    REQUIRE(n == 3);
    /* The plane is x, y (z has no extent); the diagonal is 5. */
    CHECK(fabs(xy[0]) < 1e-15 && fabs(xy[1]) < 1e-15);
    CHECK(fabs(xy[2] - 0.2) < 1e-15 && fabs(xy[3] - 4.0 / 15) < 1e-15);
    CHECK(fabs(xy[4]) < 1e-15 && fabs(xy[5] - 0.8) < 1e-15);
    emm_profiler_free(p);

    /* A sweep of one access is none: the first access is given back. */
    REQUIRE(emm_profiler_new(&info, 3, 2, "t", &p, &err) == EMM_OK);
    emm_trace_record jump[] = {{1, 0, 8, 8, 0, 0, 0}, {0, 0, 8, 8, 0, 0, 0}, {0, 1, 4, 24, 0, 0, 0}};
    REQUIRE(emm_profiler_add(p, jump, 3, &err) == EMM_OK);
    CHECK(emm_profiler_full(p));
    CHECK(emm_profiler_swept(p, &sweep_records) == 0 && sweep_records == 0);
    xy = emm_profiler_positions(p, &n);
    CHECK(n == 3 && fabs(xy[0] - 0.6) < 1e-15 && fabs(xy[1]) < 1e-15);
    emm_profiler_free(p);

    REQUIRE(emm_profiler_new(&info, 10, 2, "t", &p, &err) == EMM_OK);
    emm_trace_record bad = {9, 0, 8, 8, 0, 0, 0};
    CHECK(emm_profiler_add(p, &bad, 1, &err) == EMM_ERR_FORMAT);
    CHECK(strstr(err.message, "vertex 9") != NULL);
    emm_profiler_free(p);

    /* An address-only trace has nothing to profile. */
    emm_trace_info raw = {.version = 1, .narrays = 1, .arrays = &arrays[2]};
    CHECK(emm_profiler_new(&raw, 10, 2, "addr.emmt", &p, &err) == EMM_ERR_UNSUPPORTED);
    CHECK(strstr(err.message, "addr.emmt: an address-only trace") != NULL);
}

/* A window reads on past its length until its distinct records fill the
 * local store, to at most EMM_PROFILE_FILL_REACH times its length; not for
 * a mesh the store holds. */
static void test_profiler_fill(void)
{
    enum { NV = 1000, WINDOW = 100 };
    double *xyz = calloc(3 * NV, sizeof *xyz);
    REQUIRE(xyz);
    for (int v = 0; v < NV; v++)
        xyz[3 * v] = v, xyz[3 * v + 1] = v % 7;
    emm_trace_array arrays[1] = {{EMM_ARRAY_VERTICES, 80, NV, 0}}; /* 80,000 bytes */
    emm_trace_info info = {.version = 1, .narrays = 1, .arrays = arrays,
                           .geometry = {NV, 0, xyz, NULL}};
    CHECK(emm_profile_fill_most(WINDOW) == 150);
    emm_trace_record *recs = calloc(400, sizeof *recs);
    REQUIRE(recs);
    struct {
        unsigned step, distinct; /* element i is 500 + (i * step) % distinct */
        uint64_t store;
        size_t want;
    } cases[] = {
        {7, 10, 8000, 150},    /* 10 records, 800 bytes: it reads on to 1.5 times its length */
        {3, 1000, 10000, 125}, /* a new record each access: 125 fill 10,000 bytes */
        {3, 1000, 4000, 100},  /* the store filled before the window's length: exact */
        {7, 10, 80000, 100},   /* the mesh fits the store: exact */
        {7, 10, 0, 100},       /* no store: exact */
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        for (unsigned i = 0; i < 400; i++)
            recs[i] = (emm_trace_record){.element = 500 + (i * cases[c].step) % cases[c].distinct,
                                         .array = 0, .offset = 0, .bytes = 8};
        emm_profiler *p;
        emm_error err;
        REQUIRE(emm_profiler_new(&info, WINDOW, 2, "t", &p, &err) == EMM_OK);
        emm_profiler_fill(p, cases[c].store);
        REQUIRE(emm_profiler_add(p, recs, 400, &err) == EMM_OK);
        size_t n;
        emm_profiler_positions(p, &n);
        CHECK(emm_profiler_full(p));
        if (n != cases[c].want)
            fprintf(stderr, "fill case %zu: %zu element accesses, wanted %zu\n", c, n,
                    cases[c].want);
        CHECK(n == cases[c].want);
        emm_profiler_free(p);
    }
    free(recs);
    free(xyz);
}

/* ---- positions in space (dims 3) ---------------------------------------- */

/* 3D versions of the point sets: a slab, clusters, straight walks in
 * space, a 4x4x4 lattice of duplicates. */
static void points3(int kind, double *p, size_t n)
{
    double cx[5], cy[5], cz[5];
    for (int c = 0; c < 5; c++) {
        cx[c] = unit();
        cy[c] = unit();
        cz[c] = unit();
    }
    double x = unit(), y = unit(), z = unit(), a = unit() * 6.28, b = unit() * 3.14;
    for (size_t i = 0; i < n; i++) {
        switch (kind) {
        case UNIFORM:
            x = unit();
            y = 0.6 * unit();
            z = 0.3 * unit();
            break;
        case CLUSTERED: {
            int c = (int)(unit() * 5);
            double r = 0.02 * sqrt(-2 * log(unit() + 1e-300)), t = 6.283185 * unit();
            double u = 2 * unit() - 1, w = sqrt(1 - u * u);
            x = cx[c] + r * w * cos(t);
            y = cy[c] + r * w * sin(t);
            z = cz[c] + r * u;
            break;
        }
        case CURVES:
            if (unit() < 0.002 || x < 0 || x > 1 || y < 0 || y > 1 || z < 0 || z > 1) {
                x = unit();
                y = unit();
                z = unit();
                a = unit() * 6.283185;
                b = unit() * 3.141593;
            }
            x += 0.001 * sin(b) * cos(a);
            y += 0.001 * sin(b) * sin(a);
            z += 0.001 * cos(b);
            break;
        case DUPLICATES:
            x = (double)(int)(unit() * 4) / 4;
            y = (double)(int)(unit() * 4) / 4;
            z = (double)(int)(unit() * 4) / 4;
            break;
        }
        p[3 * i] = x;
        p[3 * i + 1] = y;
        p[3 * i + 2] = z;
    }
}

/* brute in space: the naive double loop, as in the plane. */
static void brute3(const double *p, size_t n, double *D)
{
    for (size_t i = 0; i < n; i++) {
        double s = 0;
        for (size_t k = 0; k < i; k++) {
            double dx = p[3 * i] - p[3 * k], dy = p[3 * i + 1] - p[3 * k + 1],
                   dz = p[3 * i + 2] - p[3 * k + 2];
            s += sqrt(dx * dx + dy * dy + dz * dz);
        }
        D[i] = s;
    }
}

/* lane_row in space: the third axis' square added after the first two. */
static double lane_row3(const double *p, size_t i)
{
    __builtin_cpu_init();
    size_t L = __builtin_cpu_supports("avx2") ? 8 : 4, k = 0;
    double acc[8] = {0};
    const double *q = p + 3 * i;
    for (; k + L <= i; k += L)
        for (size_t j = 0; j < L; j++) {
            const double *r = p + 3 * (k + j);
            double dx = r[0] - q[0], dy = r[1] - q[1], dz = r[2] - q[2];
            acc[j] += sqrt(dx * dx + dy * dy + dz * dz);
        }
    double s;
    if (L == 8) {
        double l0 = acc[0] + acc[4], l1 = acc[1] + acc[5], l2 = acc[2] + acc[6],
               l3 = acc[3] + acc[7];
        s = (l0 + l1) + (l2 + l3);
    } else {
        s = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    }
    for (; k < i; k++) {
        const double *r = p + 3 * k;
        double dx = r[0] - q[0], dy = r[1] - q[1], dz = r[2] - q[2];
        s += sqrt(dx * dx + dy * dy + dz * dz);
    }
    return s;
}

static void test_exact_3d(void)
{
    static const size_t sizes[] = {0, 1, 2, 3, 7, 8, 9, 100, 1000, 2047, 2048, 2049, 5000};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (int kind = UNIFORM; kind <= DUPLICATES; kind++) {
            size_t n = sizes[s];
            double *p = malloc((3 * n + 3) * sizeof *p);
            double *D = malloc((n + 1) * sizeof *D), *R = malloc((n + 1) * sizeof *R);
            points3(kind, p, n);
            emm_profile_exact(p, n, 3, D, NULL);
            brute3(p, n, R);
            double e = max_rel(D, R, n);
            CHECKF(e <= 1e-12, "exact 3D n=%zu kind=%d: relative error %g", n, kind, e);
            size_t bad = 0;
            for (size_t i = 0; i < n; i++)
                bad += memcmp(&D[i], &(double){lane_row3(p, i)}, sizeof D[i]) != 0;
            CHECKF(bad == 0, "exact 3D n=%zu kind=%d: %zu rows differ from the lane-order sum",
                   n, kind, bad);
            free(p);
            free(D);
            free(R);
        }
}

/* The octree's bound is the quadtree's (docs/profile.md "Fast method and its
 * bound"): every D_i within emm_profile_fast_bound(theta) of the exact
 * value, on each 3D set. */
static void test_fast_3d(void)
{
    static const double thetas[] = {0.1, 0.147, 0.3, EMM_PROFILE_THETA, 0.7};
    for (int kind = UNIFORM; kind <= DUPLICATES; kind++) {
        size_t n = 20000;
        double *p = malloc(3 * n * sizeof *p);
        double *D = malloc(n * sizeof *D), *R = malloc(n * sizeof *R);
        points3(kind, p, n);
        emm_profile_exact(p, n, 3, R, NULL);
        for (size_t t = 0; t < sizeof thetas / sizeof thetas[0]; t++) {
            emm_error err;
            REQUIRE(emm_profile_fast(p, n, 3, thetas[t], D, NULL, &err) == EMM_OK);
            double e = max_rel(D, R, n), bound = emm_profile_fast_bound(thetas[t]);
            printf("fast 3D kind=%d n=%zu theta=%.3f: max relative error %.3g (bound %.3g)\n",
                   kind, n, thetas[t], e, bound);
            CHECKF(e <= bound, "fast 3D kind=%d theta=%g: %g > bound %g", kind, thetas[t], e,
                   bound);
            /* Measured at the default: 0.7e-3 to 1.3e-3 (the clusters, whose
             * points are closer together in space than in the plane). */
            if (thetas[t] == EMM_PROFILE_THETA && kind != DUPLICATES)
                CHECKF(e <= 2e-3, "fast 3D kind=%d at the default theta: %g > 2e-3", kind, e);
        }
        /* One thread or two: the same profile, to the bit. */
        emm_threads one = {1, NULL, NULL}, two = {2, NULL, NULL};
        emm_error err;
        double *D2 = malloc(n * sizeof *D2);
        REQUIRE(emm_profile_fast(p, n, 3, EMM_PROFILE_THETA, D, &one, &err) == EMM_OK);
        REQUIRE(emm_profile_fast(p, n, 3, EMM_PROFILE_THETA, D2, &two, &err) == EMM_OK);
        CHECK(memcmp(D, D2, n * sizeof *D) == 0);
        /* compute: exact up to EMM_PROFILE_EXACT_MAX, fast beyond. */
        int exact = -1;
        REQUIRE(emm_profile_compute(p, n, 3, D2, &exact, NULL, &err) == EMM_OK);
        if (n <= EMM_PROFILE_EXACT_MAX)
            CHECK(exact == 1 && memcmp(D2, R, n * sizeof *D2) == 0);
        else
            CHECK(exact == 0 && memcmp(D2, D, n * sizeof *D2) == 0);
        free(D2);
        free(p);
        free(D);
        free(R);
    }
}

/* A plane laid in space (z = 0) profiles as the plane does, to the bit, by
 * either method: the third axis adds only zeros, and the octree's points
 * all fall in its upper-z children, visited in the quadtree's order. */
static void test_plane_in_space(void)
{
    size_t n = 30000;
    double *xy = malloc(2 * n * sizeof *xy), *xyz = malloc(3 * n * sizeof *xyz);
    double *D2 = malloc(n * sizeof *D2), *D3 = malloc(n * sizeof *D3);
    uint64_t saved = rng;
    points(CURVES, xy, n);
    rng = saved;
    for (size_t i = 0; i < n; i++) {
        xyz[3 * i] = xy[2 * i];
        xyz[3 * i + 1] = xy[2 * i + 1];
        xyz[3 * i + 2] = 0;
    }
    emm_error err;
    REQUIRE(emm_profile_fast(xy, n, 2, EMM_PROFILE_THETA, D2, NULL, &err) == EMM_OK);
    REQUIRE(emm_profile_fast(xyz, n, 3, EMM_PROFILE_THETA, D3, NULL, &err) == EMM_OK);
    CHECK(memcmp(D2, D3, n * sizeof *D2) == 0);
    emm_profile_exact(xy, 5000, 2, D2, NULL);
    emm_profile_exact(xyz, 5000, 3, D3, NULL);
    CHECK(memcmp(D2, D3, 5000 * sizeof *D2) == 0);
    free(xy);
    free(xyz);
    free(D2);
    free(D3);
}

/* Positions for the golden values below: straight walks that restart every
 * 500 points, from a generator of their own. */
static void golden_points(double *pos, size_t n, uint32_t dims)
{
    uint64_t s = 2024;
    double p[3] = {0.5, 0.5, 0.5}, v[3] = {0.001, 0, 0};
    for (size_t i = 0; i < n; i++) {
        if (i % 500 == 0)
            for (uint32_t a = 0; a < dims; a++) {
                s = s * 6364136223846793005ull + 1442695040888963407ull;
                p[a] = (double)(s >> 11) * 0x1.0p-53;
                s = s * 6364136223846793005ull + 1442695040888963407ull;
                v[a] = 0.002 * ((double)(s >> 11) * 0x1.0p-53 - 0.5);
            }
        for (uint32_t a = 0; a < dims; a++)
            pos[dims * i + a] = p[a] += v[a];
    }
}

static uint64_t fnv1a(const double *D, size_t n)
{
    uint64_t h = 14695981039346656037ull;
    const unsigned char *b = (const unsigned char *)D;
    for (size_t i = 0; i < n * sizeof *D; i++) {
        h ^= b[i];
        h *= 1099511628211ull;
    }
    return h;
}

/* Positions in the plane give the profiles they gave before positions had
 * a dimension: the fast method's values (scalar code, the same on every
 * x86-64) hashed as the 2D-only profiler computed them. The exact method's
 * rows are checked against the lane-order sum above, bit for bit. */
static void test_plane_unchanged(void)
{
    size_t n = 50000;
    double *pos = malloc(2 * n * sizeof *pos), *D = malloc(n * sizeof *D);
    golden_points(pos, n, 2);
    emm_error err;
    emm_threads one = {1, NULL, NULL};
    REQUIRE(emm_profile_fast(pos, n, 2, EMM_PROFILE_THETA, D, NULL, &err) == EMM_OK);
    CHECKF(fnv1a(D, n) == 0xbe528860794ac499ull, "fast, default theta: hash %016llx",
           (unsigned long long)fnv1a(D, n));
    REQUIRE(emm_profile_fast(pos, n, 2, 0.1, D, &one, &err) == EMM_OK);
    CHECKF(fnv1a(D, n) == 0x95703cd15cf96057ull, "fast, theta 0.1: hash %016llx",
           (unsigned long long)fnv1a(D, n));
    free(pos);
    free(D);
}

static void test_profiler_3d(void)
{
    /* x extent 3, y 4, z 12: the plane keeps y and z, space all three. */
    double xyz[] = {0, 0, 0, 3, 0, 0, 0, 4, 12};
    int32_t tri[] = {0, 1, 2};
    emm_trace_array arrays[2] = {{EMM_ARRAY_VERTICES, 80, 3, 0},
                                 {EMM_ARRAY_TRIANGLES, 28, 1, 4096}};
    emm_trace_info info = {.version = 1, .narrays = 2, .arrays = arrays,
                           .geometry = {3, 1, xyz, tri}};
    emm_trace_record recs[] = {
        {0, 0, 8, 8, 0, 0, 0}, {2, 0, 8, 8, 0, 0, 0}, {0, 1, 4, 24, 0, 0, 0}};
    emm_profiler *p;
    emm_error err;
    size_t n;

    REQUIRE(emm_profiler_new(&info, 3, 3, "t", &p, &err) == EMM_OK);
    CHECK(emm_profiler_dims(p) == 3);
    REQUIRE(emm_profiler_add(p, recs, 3, &err) == EMM_OK);
    const double *q = emm_profiler_positions(p, &n);
    REQUIRE(n == 3);
    /* The diagonal is 13. */
    CHECK(fabs(q[0]) < 1e-15 && fabs(q[1]) < 1e-15 && fabs(q[2]) < 1e-15);
    CHECK(fabs(q[3]) < 1e-15 && fabs(q[4] - 4.0 / 13) < 1e-15 && fabs(q[5] - 12.0 / 13) < 1e-15);
    CHECK(fabs(q[6] - 1.0 / 13) < 1e-15 && fabs(q[7] - 4.0 / 39) < 1e-15 &&
          fabs(q[8] - 4.0 / 13) < 1e-15);
    emm_profiler_free(p);

    REQUIRE(emm_profiler_new(&info, 3, 2, "t", &p, &err) == EMM_OK);
    CHECK(emm_profiler_dims(p) == 2);
    REQUIRE(emm_profiler_add(p, recs, 3, &err) == EMM_OK);
    q = emm_profiler_positions(p, &n);
    REQUIRE(n == 3);
    /* y and z, over the diagonal hypot(4, 12). */
    double diag = hypot(4, 12);
    CHECK(fabs(q[2] - 4 / diag) < 1e-15 && fabs(q[3] - 12 / diag) < 1e-15);
    CHECK(fabs(q[4] - 4.0 / 3 / diag) < 1e-15 && fabs(q[5] - 4 / diag) < 1e-15);
    emm_profiler_free(p);

    /* The trace's positions in space, as the profiler gives them. */
    double D[3];
    REQUIRE(emm_profiler_new(&info, 3, 3, "t", &p, &err) == EMM_OK);
    REQUIRE(emm_profiler_add(p, recs, 3, &err) == EMM_OK);
    q = emm_profiler_positions(p, &n);
    REQUIRE(emm_profile_compute(q, n, emm_profiler_dims(p), D, NULL, NULL, &err) == EMM_OK);
    CHECK(D[0] == 0 && fabs(D[1] - sqrt(160.0) / 13) < 1e-15);
    emm_profiler_free(p);
}

static void test_features(void)
{
    double D[EMM_PROFILE_MIN], f[EMM_FEATURES];
    emm_error err;
    for (size_t i = 0; i < EMM_PROFILE_MIN; i++)
        D[i] = 0.3 * (double)i;
    CHECK(emm_profile_features(D, EMM_PROFILE_MIN - 1, "short", f, &err) == EMM_ERR_RANGE);
    CHECK(strstr(err.message, "short: a profile of") != NULL);
    CHECK(emm_profile_features(D, EMM_PROFILE_MIN, "ok", f, &err) == EMM_OK);
    for (int k = 0; k < EMM_FEATURES; k++)
        CHECK(isfinite(f[k]));
    /* A constant mean distance: no growth, no jumps. */
    CHECK(fabs(f[2]) < 1e-9);
    /* All points in one place: D = 0 everywhere, still finite features. */
    memset(D, 0, sizeof D);
    CHECK(emm_profile_features(D, EMM_PROFILE_MIN, "zero", f, &err) == EMM_OK);
    for (int k = 0; k < EMM_FEATURES; k++)
        CHECK(isfinite(f[k]));
}

int main(void)
{
    test_exact();
    test_exact_rows();
    test_fast();
    test_compute();
    test_profiler();
    test_profiler_fill();
    test_exact_3d();
    test_fast_3d();
    test_plane_in_space();
    test_plane_unchanged();
    test_profiler_3d();
    test_features();
    return check_done();
}
