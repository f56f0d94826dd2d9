/* Decision quality of the distance profiler (thesis §5, Table 5.1): on
 * synthetic traces that are NOT in the strategy table (other meshes, seeds
 * and window lengths; spiral and corner-seeded region growth; Hilbert
 * order), how the strategy chosen from the profile window fares over the
 * whole trace against the best candidate of the standard sweep (direct or
 * an EMM strategy: the default machine has no cache), and against the
 * reference cache. Prints each case's regret (chosen / best − 1) and the
 * summary: mean regret within 3 %, none above 15 %. A benchmark, not a
 * test.
 *
 * It also holds the run's contest over each whole trace, as a session that
 * sees the whole run does (emm_contest_trace: every candidate from the
 * start, the slower half dropped at 2, 4, 8, ... windows until
 * EMM_FINALISTS remain, the fastest of those the answer), and counts how
 * often and by how much its answer misses the best candidate, which
 * --finalists all (none dropped) would answer: the price of halving.
 *
 * usage: decision_quality [--table FILE] [--quick] [--window-only]
 *                         [--seed-offset K] [--finalists N]
 * (--window-only: decide by the sweep on the window alone, for comparison;
 * --seed-offset K: other meshes and traversals again — every seed plus K;
 * --finalists N: the contest's, default EMM_FINALISTS's default, 4)
 * (the default table, plus FILE or $EMM_TABLE when given) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/config.h"
#include "emm/mesh.h"
#include "emm/profile.h"
#include "emm/replay.h"
#include "emm/sim.h"
#include "emm/synth.h"
#include "emm/table.h"
#include "emm/trace.h"

static const struct {
    const char *name;
    emm_pattern pattern;
    uint64_t length;
    int corner;
} patterns[] = {
    {"random", EMM_PATTERN_RANDOM, 0, 0},
    {"region", EMM_PATTERN_REGION, 0, 0},
    {"region-corner", EMM_PATTERN_REGION, 0, 1},
    {"curve", EMM_PATTERN_CURVE, 0, 0},
    {"curve-40", EMM_PATTERN_CURVE, 40, 0},
    {"scanline", EMM_PATTERN_SCANLINE, 0, 0},
    {"zorder", EMM_PATTERN_ZORDER, 0, 0},
    {"gray", EMM_PATTERN_GRAY, 0, 0},
    {"hilbert", EMM_PATTERN_HILBERT, 0, 0},
    {"spiral", EMM_PATTERN_SPIRAL, 0, 0},
};

/* Meshes and seeds that `emm table build` does not use (it uses 6k, 12k,
 * 20k and 24k faces, seeds 11–14). */
static const struct {
    size_t faces;
    emm_density density;
    uint64_t seed;
} meshes[] = {
    {9000, EMM_DENSITY_UNIFORM, 21},
    {16000, EMM_DENSITY_CLUSTERED, 22},
    {30000, EMM_DENSITY_UNIFORM, 23},
};

/* Window lengths the table does not sample (it has 4096, 16384, 65536). */
static const uint64_t windows[] = {8192, 32768};

static void die(const char *what, const emm_error *err)
{
    fprintf(stderr, "decision_quality: %s: %s\n", what, err->message);
    exit(1);
}

static const char *get_env(const char *name)
{
    return getenv(name);
}

static int same(const emm_strategy *a, const emm_strategy *b)
{
    return a->kind == b->kind && a->layout == b->layout && a->fetch == b->fetch &&
           a->cell == b->cell && a->indexed == b->indexed;
}

int main(int argc, char **argv)
{
    const char *user = NULL;
    int quick = 0, simulate = 0;
    uint64_t offset = 0;
    unsigned finalists = EMM_CONFIG_DEFAULT_FINALISTS;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--table") == 0 && i + 1 < argc)
            user = argv[++i];
        else if (strcmp(argv[i], "--quick") == 0)
            quick = 1;
        else if (strcmp(argv[i], "--window-only") == 0)
            simulate = 1;
        else if (strcmp(argv[i], "--seed-offset") == 0 && i + 1 < argc)
            offset = strtoull(argv[++i], NULL, 10);
        else if (strcmp(argv[i], "--finalists") == 0 && i + 1 < argc)
            finalists = (unsigned)strtoul(argv[++i], NULL, 10);
        else {
            fprintf(stderr, "usage: decision_quality [--table FILE] [--quick] [--window-only] "
                            "[--seed-offset K] [--finalists N]\n");
            return 2;
        }
    }
    emm_error err;
    /* Without --table, EMM_TABLE as the configuration table reads it. */
    static emm_config cfg;
    emm_config_init(&cfg);
    if (!user && emm_config_from_env(&cfg, get_env, 0, ~(1u << EMM_CONFIG_TABLE), &err) != EMM_OK)
        die("table", &err);
    if (!user && cfg.table[0])
        user = cfg.table;
    emm_machine *m;
    emm_table *t = emm_table_new();
    if (emm_machine_new(&m, &err) != EMM_OK)
        die("machine", &err);
    if (!t || emm_table_load_standard(t, user, &err) != EMM_OK)
        die("table", &err);
    const char *path = "decision_quality.emmt";
    char def[4096];
    emm_table_default_path(def, sizeof def);
    printf("table: %zu samples (%s%s%s)\n", emm_table_count(t), def,
           user ? " + " : "", user ? user : "");
    printf("%-30s %6s %-7s %-24s %-24s %8s %8s %7s %-24s %8s %s\n", "case", "window", "how",
           "chosen", "best", "regret", "vs cache", "dist", "contest", "regret", "nearest");

    size_t nmesh = quick ? 1 : sizeof meshes / sizeof meshes[0];
    size_t cases = 0, worse_than_cache = 0, skipped = 0, contests = 0, missed = 0;
    size_t pred_off = 0, fixed = 0; /* predictions not the best; of them, the contest's best */
    double sum_regret = 0, max_regret = 0, max_vs_cache = -1, sum_contest = 0, max_contest = 0;
    for (size_t g = 0; g < nmesh; g++) {
        emm_gen_options go = {meshes[g].faces, meshes[g].seed + offset, meshes[g].density,
                              EMM_ORDER_INPUT};
        emm_mesh *mesh;
        if (emm_mesh_generate(&go, &mesh, &err) != EMM_OK)
            die("mesh", &err);
        for (size_t p = 0; p < sizeof patterns / sizeof patterns[0]; p++) {
            emm_synth_options so = {.pattern = patterns[p].pattern,
                                    .seed = 300 + meshes[g].seed + offset,
                                    .length = patterns[p].length,
                                    .corner_seed = patterns[p].corner};
            emm_trace_reader *r = NULL;
            if (emm_synth_trace(mesh, &so, path, NULL, &err) != EMM_OK ||
                emm_trace_reader_open(path, &r, &err) != EMM_OK)
                die(patterns[p].name, &err);
            const emm_trace_info *info = emm_trace_reader_info(r);

            /* The whole trace under every strategy of the sweep. */
            emm_trace_record *all;
            size_t nall;
            if (emm_profile_trace_window(r, UINT64_MAX, path, &all, &nall, &err) != EMM_OK)
                die(patterns[p].name, &err);
            emm_sweep *whole = NULL;
            if (emm_sweep_records(m, info, all, nall, NULL, &whole, &err) != EMM_OK)
                die(patterns[p].name, &err);
            uint64_t best = whole->result[whole->best].total;
            uint64_t cache = whole->result[whole->cache].total;

            for (size_t w = 0; w < sizeof windows / sizeof windows[0]; w++) {
                emm_trace_record *recs;
                size_t n;
                emm_window_decision d;
                size_t length; /* the window as asked for: the contest's unit */
                if (emm_profile_trace_window_fill(r, windows[w], emm_machine_get(m, "local.bytes"),
                                                  path, &recs, &n, &length, &err) != EMM_OK)
                    die(patterns[p].name, &err);
                /* The window's leading index-order sweep, which the profile
                 * leaves out: the contest counts its windows after it. */
                size_t lead = 0;
                emm_profiler *pf;
                if (emm_profiler_new(info, windows[w], EMM_PROFILE_PLANE, path, &pf, &err) !=
                        EMM_OK ||
                    emm_profiler_add(pf, recs, n, &err) != EMM_OK)
                    die(patterns[p].name, &err);
                emm_profiler_swept(pf, &lead);
                emm_profiler_free(pf);
                if (n >= nall) {
                    /* The window is the whole trace: not a decision ahead of time. */
                    free(recs);
                    skipped++;
                    continue;
                }
                emm_decide_options dopt = {.simulate = simulate};
                if (emm_decide_window(t, m, info, recs, n, path, &dopt, &d, &err) != EMM_OK)
                    die(patterns[p].name, &err);
                emm_window_decision_release(&d); /* the classes checked are not used */
                free(recs);
                size_t k = whole->count;
                for (size_t i = 0; i < whole->count; i++)
                    if (same(&whole->result[i].strategy, &d.strategy))
                        k = i;
                char cname[64], chosen[96], bestname[96];
                snprintf(cname, sizeof cname, "%s %zuk%c", patterns[p].name,
                         meshes[g].faces / 1000,
                         meshes[g].density == EMM_DENSITY_UNIFORM ? 'u' : 'c');
                emm_strategy_format(&d.strategy, chosen, sizeof chosen);
                emm_strategy_format(&whole->result[whole->best].strategy, bestname,
                                    sizeof bestname);
                if (k == whole->count || !whole->ran[k]) {
                    printf("%-30s %6zu %-7s %-24s %-24s %8s %8s %7.3f\n", cname, d.accesses,
                           emm_decided_name(d.how), chosen, bestname, "n/a", "n/a",
                           d.table.distance);
                    skipped++;
                    continue;
                }
                uint64_t c = whole->result[k].total;
                double regret = (double)c / (double)best - 1;
                double vs_cache = (double)c / (double)cache - 1;
                /* The run's contest over the whole trace from this
                 * window's prediction, the halvings at 2, 4, 8, ... of its
                 * records past the leading sweep (up to its length, before
                 * it read on), as the session counts. */
                emm_contest_result cr;
                if (emm_contest_trace(path, m, &d.strategy, lead, length > lead ? length - lead : 1,
                                      finalists, NULL, &cr, &err) != EMM_OK)
                    die(patterns[p].name, &err);
                char cwin[96];
                emm_strategy_format(&cr.answer.strategy, cwin, sizeof cwin);
                double cregret = (double)cr.answer.total / (double)best - 1;
                emm_result_release(&cr.answer);
                emm_result_release(&cr.runner_up);
                emm_result_release(&cr.predicted);
                contests++;
                missed += cregret > 0;
                pred_off += regret > 0;
                fixed += regret > 0 && cregret <= 0;
                sum_contest += cregret;
                if (cregret > max_contest)
                    max_contest = cregret;
                printf("%-30s %6zu %-7s %-24s %-24s %7.2f%% %7.2f%% %7.3f %-24s %7.2f%% %s\n",
                       cname, d.accesses, emm_decided_name(d.how), chosen, bestname,
                       100 * regret, 100 * vs_cache, d.table.distance, cwin, 100 * cregret,
                       d.table.nearest);
                cases++;
                sum_regret += regret;
                if (regret > max_regret)
                    max_regret = regret;
                if (vs_cache > max_vs_cache)
                    max_vs_cache = vs_cache;
                worse_than_cache += vs_cache > 0.05;
            }
            emm_sweep_free(whole);
            free(all);
            emm_trace_reader_close(r);
        }
        emm_mesh_free(mesh);
    }
    remove(path);
    double mean = cases ? sum_regret / (double)cases : 0;
    printf("\n%zu cases (%zu skipped: window covers the trace, or strategy not simulated)\n", cases,
           skipped);
    printf("mean regret %.2f%% (goal <= 3%%), largest %.2f%% (goal <= 15%%), against the best "
           "candidate (direct or EMM: the machine has no cache)\n",
           100 * mean, 100 * max_regret);
    printf("against the reference cache: worst %+.2f%%; %zu cases more than 5%% slower than it\n",
           100 * max_vs_cache, worse_than_cache);
    printf("the run's contest (halving to %u finalist%s) over the whole trace: %zu of %zu answers "
           "slower than the best candidate (what --finalists all answers); mean regret %.2f%%, "
           "largest %.2f%%\n",
           finalists, finalists == 1 ? "" : "s", missed, contests,
           contests ? 100 * sum_contest / (double)contests : 0, 100 * max_contest);
    printf("  (the prediction, which runs to the end beside the finalists, was the best in %zu of "
           "them; of the other %zu, the contest found the best in %zu)\n",
           contests - pred_off, pred_off, fixed);
    printf("goals met: %s\n", cases && mean <= 0.03 && max_regret <= 0.15 ? "yes" : "no");
    emm_table_free(t);
    emm_machine_free(m);
    return 0;
}
