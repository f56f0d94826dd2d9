/* The exact method against a naive double loop and, bit for bit, against
 * its kernel's lane-order row sums, the fast method within its
 * stated bound (thesis Eq. 5.1), the profiler's position extraction, and the
 * features' argument checks. */
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

static void brute(const double *xy, size_t n, double *D)
{
    for (size_t i = 0; i < n; i++) {
        double s = 0;
        for (size_t k = 0; k < i; k++)
            s += hypot(xy[2 * i] - xy[2 * k], xy[2 * i + 1] - xy[2 * k + 1]);
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
            emm_profile_exact(xy, n, D, NULL);
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
            emm_profile_exact(xy, n, D, NULL);
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
        emm_profile_exact(xy, n, R, NULL);
        for (size_t t = 0; t < sizeof thetas / sizeof thetas[0]; t++) {
            emm_error err;
            REQUIRE(emm_profile_fast(xy, n, thetas[t], D, NULL, &err) == EMM_OK);
            double e = max_rel(D, R, n), bound = emm_profile_fast_bound(thetas[t]);
            printf("fast kind=%d n=%zu theta=%.3f: max relative error %.3g (bound %.3g)\n", kind,
                   n, thetas[t], e, bound);
            CHECKF(e <= bound, "fast kind=%d theta=%g: %g > bound %g", kind, thetas[t], e, bound);
            /* What the default is chosen for: 1e-3 on access-like sequences
             * (the 4x4 lattice of DUPLICATES is adversarial, not access-like). */
            if (thetas[t] == EMM_PROFILE_THETA && kind != DUPLICATES)
                CHECKF(e <= 1e-3, "fast kind=%d at the default theta: %g > 1e-3", kind, e);
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
        REQUIRE(emm_profile_fast(xy, n, EMM_PROFILE_THETA, D1, &one, &err) == EMM_OK);
        REQUIRE(emm_profile_fast(xy, n, EMM_PROFILE_THETA, D2, &two, &err) == EMM_OK);
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
    CHECK(emm_profile_fast(xy, 2, 0.0, D, NULL, &err) == EMM_ERR_RANGE);
    CHECK(emm_profile_fast(xy, 2, 1.0, D, NULL, &err) == EMM_ERR_RANGE);
    CHECK(strstr(err.message, "opening angle") != NULL);
    CHECK(emm_profile_fast(xy, 2, 0.5, D, NULL, &err) == EMM_OK);
    CHECK(D[0] == 0 && fabs(D[1] - sqrt(2.0)) < 1e-15);
}

static void test_compute(void)
{
    size_t n = EMM_PROFILE_EXACT_MAX + 1000;
    double *xy = malloc(2 * n * sizeof *xy), *D = malloc(n * sizeof *D);
    points(UNIFORM, xy, n);
    int exact = -1;
    emm_error err;
    REQUIRE(emm_profile_compute(xy, 1000, D, &exact, NULL, &err) == EMM_OK);
    CHECK(exact == 1);
    REQUIRE(emm_profile_compute(xy, n, D, &exact, NULL, &err) == EMM_OK);
    CHECK(exact == 0);
    double *R = malloc(n * sizeof *R);
    emm_profile_exact(xy, n, R, NULL);
    CHECK(max_rel(D, R, n) <= emm_profile_fast_bound(EMM_PROFILE_THETA));
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
    REQUIRE(emm_profiler_new(&info, 3, "t", &p, &err) == EMM_OK);
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
    REQUIRE(emm_profiler_new(&info, 3, "t", &p, &err) == EMM_OK);
    emm_trace_record jump[] = {{1, 0, 8, 8, 0, 0, 0}, {0, 0, 8, 8, 0, 0, 0}, {0, 1, 4, 24, 0, 0, 0}};
    REQUIRE(emm_profiler_add(p, jump, 3, &err) == EMM_OK);
    CHECK(emm_profiler_full(p));
    CHECK(emm_profiler_swept(p, &sweep_records) == 0 && sweep_records == 0);
    xy = emm_profiler_positions(p, &n);
    CHECK(n == 3 && fabs(xy[0] - 0.6) < 1e-15 && fabs(xy[1]) < 1e-15);
    emm_profiler_free(p);

    REQUIRE(emm_profiler_new(&info, 10, "t", &p, &err) == EMM_OK);
    emm_trace_record bad = {9, 0, 8, 8, 0, 0, 0};
    CHECK(emm_profiler_add(p, &bad, 1, &err) == EMM_ERR_FORMAT);
    CHECK(strstr(err.message, "vertex 9") != NULL);
    emm_profiler_free(p);

    /* An address-only trace has nothing to profile. */
    emm_trace_info raw = {.version = 1, .narrays = 1, .arrays = &arrays[2]};
    CHECK(emm_profiler_new(&raw, 10, "addr.emmt", &p, &err) == EMM_ERR_UNSUPPORTED);
    CHECK(strstr(err.message, "addr.emmt: an address-only trace") != NULL);
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
    test_features();
    return check_done();
}
