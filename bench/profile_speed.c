/* Speed of the distance profiler (thesis Eq. 5.1), a benchmark and not a
 * timed test: the exact method on a 65,536-access window and the fast
 * method on 1,000,000 accesses, each meant to take under a second on the
 * project's 2-core machine, and the fast method's largest relative error
 * against exact values on a sample of accesses (meant to be ≤ 1e-3).
 *
 * usage: profile_speed [ACCESSES_FAST] [THETA] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "emm/profile.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static uint64_t rng = 42;
static double unit(void)
{
    rng = rng * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng >> 11) * 0x1.0p-53;
}

/* Clustered positions visited by a mix of local walks and jumps: the
 * shapes a profile window sees. */
static void positions(double *xy, size_t n)
{
    double x = 0.5, y = 0.3, a = 0;
    for (size_t i = 0; i < n; i++) {
        if (unit() < 0.001) {
            x = unit();
            y = 0.7 * unit();
            a = 6.283185307 * unit();
        }
        x += 0.0005 * cos(a) + 0.0002 * (unit() - 0.5);
        y += 0.0005 * sin(a) + 0.0002 * (unit() - 0.5);
        xy[2 * i] = x;
        xy[2 * i + 1] = y;
    }
}

int main(int argc, char **argv)
{
    size_t nfast = argc > 1 ? strtoull(argv[1], NULL, 10) : 1000000;
    double theta = argc > 2 ? atof(argv[2]) : EMM_PROFILE_THETA;
    size_t nexact = EMM_PROFILE_EXACT_MAX;
    double *xy = malloc(2 * nfast * sizeof *xy), *D = malloc(nfast * sizeof *D);
    if (!xy || !D)
        return 1;
    positions(xy, nfast);

    double t0 = now();
    emm_profile_exact(xy, nexact, 2, D, NULL);
    double te = now() - t0;
    printf("exact: %zu accesses in %.3f s\n", nexact, te);

    emm_error err;
    t0 = now();
    if (emm_profile_fast(xy, nfast, 2, theta, D, NULL, &err) != EMM_OK) {
        fprintf(stderr, "profile_speed: %s\n", err.message);
        return 1;
    }
    double tf = now() - t0;
    printf("fast:  %zu accesses in %.3f s (theta %.3f, stated bound %.3g)\n", nfast, tf, theta,
           emm_profile_fast_bound(theta));

    /* Exact values of a sample of accesses, spread over the whole range. */
    double worst = 0;
    size_t worst_i = 0, samples = 200;
    for (size_t s = 1; s <= samples; s++) {
        size_t i = (size_t)((double)(nfast - 1) * s / samples);
        double e = 0;
        for (size_t k = 0; k < i; k++)
            e += hypot(xy[2 * i] - xy[2 * k], xy[2 * i + 1] - xy[2 * k + 1]);
        double r = e > 0 ? fabs(D[i] - e) / e : fabs(D[i]);
        if (r > worst) {
            worst = r;
            worst_i = i;
        }
    }
    printf("fast:  largest relative error %.3g over %zu sampled accesses (at i = %zu)\n", worst,
           samples, worst_i);
    free(xy);
    free(D);
    return 0;
}
