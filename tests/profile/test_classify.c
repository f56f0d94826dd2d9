/* The shapes of thesis Table 5.1 (random access, region growing, curves,
 * scan lines) are each recognised by the nearest sample of a table built in
 * this test from OTHER meshes and seeds, across three meshes and three
 * window lengths; the Z-order and Gray-code orders of thesis Fig. 5.3 land
 * on the same strategy. `-v` prints every feature vector and decision. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "emm/mesh.h"
#include "emm/profile.h"
#include "emm/synth.h"
#include "emm/table.h"
#include "emm/trace.h"

static int verbose;

static const struct {
    emm_pattern pattern;
    const char *cls, *strategy;
} classes[] = {
    {EMM_PATTERN_RANDOM, "random", "cache"},
    {EMM_PATTERN_REGION, "region", "tiles+convolution@64"},
    {EMM_PATTERN_CURVE, "curve", "grid+naive@16"},
    {EMM_PATTERN_SCANLINE, "scanline", "tiles+extrapolated@64"},
    /* Not one of Table 5.1's shapes, but the shipped table samples every
     * synthetic pattern (emm table build), so this one does too. Z-order and
     * Gray code are left out: they must land on one strategy without samples
     * of their own. */
    {EMM_PATTERN_HILBERT, "hilbert", "tiles+convolution@64"},
};
#define NCLASS (sizeof classes / sizeof classes[0])
#define NTESTED 4 /* the classes checked: Table 5.1's */

static const uint64_t windows[] = {4096, 16384, 65536};
#define NWIN 3
/* The table samples more window lengths than the test asks about, as the
 * shipped table does: a short window on a large mesh looks like a shorter
 * one on a smaller mesh. */
static const uint64_t train_windows[] = {2048, 4096, 8192, 16384, 32768, 65536};
#define NTRAIN_WIN 6
/* Traversals per pattern and training mesh (other start points and walks). */
#define NTRAIN_RUNS 2

/* The profile of a pattern over a mesh, up to the longest window; the
 * shorter windows are its prefixes (D_i depends only on earlier accesses). */
static double *profile_of(const emm_mesh *m, emm_pattern p, uint64_t seed, size_t *n)
{
    emm_error err;
    char path[256];
    snprintf(path, sizeof path, "profile_classify_%d_%llu.emmt", (int)p, (unsigned long long)seed);
    emm_synth_options so = {.pattern = p, .seed = seed};
    REQUIRE(emm_synth_trace(m, &so, path, NULL, &err) == EMM_OK);
    emm_trace_reader *r;
    REQUIRE(emm_trace_reader_open(path, &r, &err) == EMM_OK);
    double *xy;
    REQUIRE(emm_profile_trace_positions(r, windows[NWIN - 1], EMM_PROFILE_PLANE, path, &xy, n,
                                        &err) == EMM_OK);
    emm_trace_reader_close(r);
    remove(path);
    double *D = malloc(*n * sizeof *D);
    REQUIRE(D);
    REQUIRE(emm_profile_compute(xy, *n, EMM_PROFILE_PLANE, D, NULL, NULL, &err) == EMM_OK);
    free(xy);
    return D;
}

static void features(const double *D, size_t n, uint64_t w, double *f)
{
    emm_error err;
    size_t len = n < w ? n : (size_t)w;
    REQUIRE(emm_profile_features(D, len, "profile", f, &err) == EMM_OK);
}

static void print_f(const char *tag, const double *f)
{
    printf("%-28s", tag);
    for (int k = 0; k < EMM_FEATURES; k++)
        printf(" %6.3f", f[k]);
    printf("\n");
}

static emm_mesh *mesh(size_t faces, emm_density d, uint64_t seed)
{
    emm_error err;
    emm_gen_options go = {faces, seed, d, EMM_ORDER_INPUT};
    emm_mesh *m;
    REQUIRE(emm_mesh_generate(&go, &m, &err) == EMM_OK);
    return m;
}

int main(int argc, char **argv)
{
    verbose = argc > 1 && strcmp(argv[1], "-v") == 0;
    emm_error err;
    emm_table *t = emm_table_new();
    REQUIRE(t);

    /* The table: other meshes, other seeds. */
    static const struct { size_t faces; emm_density d; uint64_t seed; } train[] = {
        {10000, EMM_DENSITY_UNIFORM, 101},
        {30000, EMM_DENSITY_CLUSTERED, 102},
        {8000, EMM_DENSITY_CLUSTERED, 103},
        {60000, EMM_DENSITY_UNIFORM, 104},
    };
    for (size_t g = 0; g < sizeof train / sizeof train[0]; g++) {
        emm_mesh *m = mesh(train[g].faces, train[g].d, train[g].seed);
        for (size_t c = 0; c < NCLASS; c++)
        for (uint64_t run = 0; run < NTRAIN_RUNS; run++) {
            size_t n;
            double *D = profile_of(m, classes[c].pattern, 1000 * (run + 1) + g, &n);
            for (int w = 0; w < NTRAIN_WIN; w++) {
                emm_table_sample s;
                memset(&s, 0, sizeof s);
                snprintf(s.name, sizeof s.name, "%s-%zuk-%c-%llu-%llu", classes[c].cls,
                         train[g].faces / 1000, train[g].d == EMM_DENSITY_UNIFORM ? 'u' : 'c',
                         (unsigned long long)train_windows[w], (unsigned long long)run);
                snprintf(s.pattern, sizeof s.pattern, "%s", classes[c].cls);
                REQUIRE(emm_strategy_parse(classes[c].strategy, &s.strategy, &err) == EMM_OK);
                features(D, n, train_windows[w], s.f);
                REQUIRE(emm_table_add(t, &s, &err) == EMM_OK);
                if (verbose)
                    print_f(s.name, s.f);
            }
            free(D);
        }
        emm_mesh_free(m);
    }

    static const struct { size_t faces; emm_density d; uint64_t seed; } test[] = {
        {5000, EMM_DENSITY_CLUSTERED, 1},
        {20000, EMM_DENSITY_UNIFORM, 2},
        {50000, EMM_DENSITY_CLUSTERED, 3},
    };
    int wrong = 0, total = 0;
    for (size_t g = 0; g < sizeof test / sizeof test[0]; g++) {
        emm_mesh *m = mesh(test[g].faces, test[g].d, test[g].seed);
        for (size_t c = 0; c < NTESTED; c++) {
            size_t n;
            double *D = profile_of(m, classes[c].pattern, 7 + g, &n);
            for (int w = 0; w < NWIN; w++) {
                double f[EMM_FEATURES];
                features(D, n, windows[w], f);
                emm_decision d;
                REQUIRE(emm_table_decide(t, f, 0, &d, &err) == EMM_OK);
                char tag[64];
                snprintf(tag, sizeof tag, "%s %zuk w%llu", classes[c].cls, test[g].faces / 1000,
                         (unsigned long long)windows[w]);
                if (verbose) {
                    print_f(tag, f);
                    printf("    -> %s (%s, %.3f)%s\n", d.pattern, d.nearest, d.distance,
                           d.novel ? " novel" : "");
                }
                total++;
                wrong += strcmp(d.pattern, classes[c].cls) != 0;
                CHECKF(strcmp(d.pattern, classes[c].cls) == 0, "%s: classified as %s (nearest %s, %.3f)",
                       tag, d.pattern, d.nearest, d.distance);
                CHECKF(!d.novel, "%s: novel at %.3f", tag, d.distance);
            }
            free(D);
        }

        /* Fig. 5.3: Z-order and Gray code are one strategy. */
        size_t nz, ng;
        double *Dz = profile_of(m, EMM_PATTERN_ZORDER, 50 + g, &nz);
        double *Dg = profile_of(m, EMM_PATTERN_GRAY, 50 + g, &ng);
        for (int w = 0; w < NWIN; w++) {
            double fz[EMM_FEATURES], fg[EMM_FEATURES];
            emm_decision dz, dg;
            features(Dz, nz, windows[w], fz);
            features(Dg, ng, windows[w], fg);
            REQUIRE(emm_table_decide(t, fz, 0, &dz, &err) == EMM_OK);
            REQUIRE(emm_table_decide(t, fg, 0, &dg, &err) == EMM_OK);
            char a[96], b[96];
            emm_strategy_format(&dz.strategy, a, sizeof a);
            emm_strategy_format(&dg.strategy, b, sizeof b);
            if (verbose)
                printf("zorder/gray %zuk w%llu: %s (%s %.3f) / %s (%s %.3f)\n", test[g].faces / 1000,
                       (unsigned long long)windows[w], a, dz.nearest, dz.distance, b, dg.nearest,
                       dg.distance);
            CHECKF(strcmp(a, b) == 0, "%zuk w%llu: zorder -> %s, gray -> %s", test[g].faces / 1000,
                   (unsigned long long)windows[w], a, b);
        }
        free(Dz);
        free(Dg);
        emm_mesh_free(m);
    }
    printf("%d of %d classified correctly\n", total - wrong, total);
    emm_table_free(t);
    return check_done();
}
