/* emm replay: simulate a trace under one or more strategies on the machine
 * model (docs/machine.md, thesis §3.2, §6.2) and print where
 * the cycles went; --json writes the report of docs/report.md. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "opts.h"
#include "emm/replay.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "machine_cli.h"

#define MAX_JOBS 256

static void usage(FILE *out, const opts *o)
{
    char sweep[256];
    emm_strategy_sweep_describe(sweep, sizeof sweep);
    fprintf(out,
            "usage: emm replay TRACE [--strategy S]... [--json FILE] [--timeline FILE]\n"
            "                  [--machine FILE] [--set KEY=VALUE]... [--jobs N]\n"
            "                  [--memory BYTES] [--quiet]\n"
            "       emm replay TRACE --all [--indexed] [--json FILE] [--jobs N] ...\n"
            "\n"
            "Simulates the accesses recorded in TRACE on the machine model, once per\n"
            "strategy, in one pass over the file, and prints a table: total cycles, seconds\n"
            "at clock.mhz, and every cycle bucket with its share of the total, then the\n"
            "cache's line counts (Dinero IV's demand fetches, demand misses, prefetch\n"
            "fetches) or the DMA counts.\n"
            "\n"
            "With --all, simulates the standard sweep,\n"
            "  %s,\n"
            "and for a mesh with depth (the smallest extent of its bounding box at least\n"
            "%g of the largest) the layouts in space too (grid3d, tiles3d, octree;\n"
            "docs/layouts.md), a sweep of %zu,\n"
            "and prints one line per strategy, fastest first: total cycles, seconds,\n"
            "speed-up over direct and over cache, and the largest buckets. A\n"
            "strategy that cannot run on this trace (a cell larger than the local store, a\n"
            "trace without geometry) is listed as skipped with the reason, and the sweep\n"
            "goes on. With --indexed, the indexed variant of each of its EMM strategies\n"
            "(LAYOUT+FETCH@CELL:indexed: as if the program used the layout's numbering,\n"
            "which emm layout --write gives it, so no per-element look-up table) joins\n"
            "the sweep after it; the standard sweep itself stays as it is.\n"
            "\n",
            sweep, EMM_DEPTH_RATIO, emm_strategy_sweep_for(1, NULL, 0));
    opts_help(out, o);
    fprintf(out,
            "\n"
            "environment:\n"
            "  EMM_MACHINE      machine file used when --machine is absent\n");
}

/* What the command line asked for. */
struct replay_args {
    machine_cli mc;
    opts_list strategies; /* checked strategy strings */
    const char *trace, *json, *timeline;
    int quiet, all, indexed;
    uint64_t jobs, memory;
};

struct progress_ctx {
    int on;
};

static void progress(void *ctx, uint64_t done, uint64_t total)
{
    const struct progress_ctx *p = ctx;
    if (!p->on)
        return;
    if (total)
        fprintf(stderr, "\remm replay: %llu / %llu accesses (%.0f%%)", (unsigned long long)done,
                (unsigned long long)total, 100.0 * (double)done / (double)total);
    else
        fprintf(stderr, "\remm replay: %llu accesses", (unsigned long long)done);
}

static double pct(uint64_t part, uint64_t whole)
{
    return whole ? 100.0 * (double)part / (double)whole : 0.0;
}

/* A mesh larger than the machine's remote store: one line on stderr
 * (docs/machine.md, remote.bytes). */
static void warn_remote(const char *trace, const emm_machine *m)
{
    emm_trace_reader *r;
    emm_error err;
    char msg[256];
    if (emm_trace_reader_open(trace, &r, &err) != EMM_OK)
        return;
    if (emm_machine_remote_warning(m, emm_trace_reader_info(r), msg, sizeof msg))
        fprintf(stderr, "emm replay: %s: %s\n", trace, msg);
    emm_trace_reader_close(r);
}

static void print_table(const char *trace, uint64_t accesses, const emm_machine *m,
                        const emm_result *res, size_t n)
{
    double hz = (double)emm_machine_get(m, "clock.mhz") * 1e6;
    printf("trace %s: %llu accesses\n\n", trace, (unsigned long long)accesses);
    printf("%-18s", "");
    for (size_t i = 0; i < n; i++) {
        char name[64];
        emm_strategy_format(&res[i].strategy, name, sizeof name);
        printf(" %21s", name);
    }
    printf("\n%-18s", "total cycles");
    for (size_t i = 0; i < n; i++)
        printf(" %21llu", (unsigned long long)res[i].total);
    printf("\n%-18s", "seconds");
    for (size_t i = 0; i < n; i++)
        printf(" %21.6f", (double)res[i].total / hz);
    printf("\n");
    for (int b = 0; b < EMM_BUCKET_COUNT; b++) {
        printf("  %-16s", emm_bucket_name((emm_bucket)b));
        for (size_t i = 0; i < n; i++)
            printf(" %14llu %5.1f%%", (unsigned long long)res[i].cycles[b],
                   pct(res[i].cycles[b], res[i].total));
        printf("\n");
    }
    for (size_t i = 0; i < n; i++) {
        char name[64];
        emm_strategy_format(&res[i].strategy, name, sizeof name);
        if (res[i].has_cache)
            printf("\n%s: demand fetches %llu, demand misses %llu (%.2f%%), prefetch fetches %llu, "
                   "prefetch misses %llu, late prefetches %llu",
                   name, (unsigned long long)res[i].cache.demand_fetches,
                   (unsigned long long)res[i].cache.demand_misses,
                   pct(res[i].cache.demand_misses, res[i].cache.demand_fetches),
                   (unsigned long long)res[i].cache.prefetch_fetches,
                   (unsigned long long)res[i].cache.prefetch_misses,
                   (unsigned long long)res[i].cache.late_prefetches);
        if (res[i].has_dma)
            printf("\n%s: DMA transfers %llu, DMA bytes %llu", name,
                   (unsigned long long)res[i].dma.transfers, (unsigned long long)res[i].dma.bytes);
        if (res[i].has_emm)
            printf("\n%s: cell changes %llu, demand fetches %llu, prefetches %llu "
                   "(useful %llu, dropped %llu, filtered %llu, evicted unused %llu), evictions %llu, "
                   "refetches %llu",
                   name, (unsigned long long)res[i].emm.cell_changes,
                   (unsigned long long)res[i].emm.demand_fetches,
                   (unsigned long long)res[i].emm.prefetches,
                   (unsigned long long)res[i].emm.useful_prefetches,
                   (unsigned long long)res[i].emm.dropped_prefetches,
                   (unsigned long long)res[i].emm.filtered_prefetches,
                   (unsigned long long)res[i].emm.unused_prefetches,
                   (unsigned long long)res[i].emm.evictions,
                   (unsigned long long)res[i].emm.refetches);
        if (res[i].has_direct)
            printf("\n%s: words read %llu, words written %llu", name,
                   (unsigned long long)res[i].direct.words_read,
                   (unsigned long long)res[i].direct.words_written);
    }
    printf("\n");
}

/* --all: one line per strategy, fastest first, then the skipped ones. */
struct ranked {
    const emm_result *res;
    const emm_error *skip;
};

static int by_total(const void *a, const void *b)
{
    const struct ranked *x = a, *y = b;
    int xs = x->skip->status != EMM_OK, ys = y->skip->status != EMM_OK;
    if (xs != ys)
        return xs - ys;
    if (!xs && x->res->total != y->res->total)
        return x->res->total < y->res->total ? -1 : 1;
    return x->res < y->res ? -1 : x->res > y->res; /* the sweep's order */
}

static void speedup(char *buf, size_t cap, const emm_result *base, const emm_result *r)
{
    if (!base || r->total == 0)
        snprintf(buf, cap, "-");
    else
        snprintf(buf, cap, "%.2fx", (double)base->total / (double)r->total);
}

static void print_sweep(const char *trace, uint64_t accesses, const emm_machine *m,
                        const emm_result *res, const emm_error *skipped, size_t n)
{
    double hz = (double)emm_machine_get(m, "clock.mhz") * 1e6;
    const emm_result *direct = NULL, *cache = NULL;
    struct ranked *order = calloc(n ? n : 1, sizeof *order);
    size_t ran = 0;
    if (!order) {
        cli_error("replay: out of memory");
        return;
    }
    for (size_t i = 0; i < n; i++) {
        order[i].res = &res[i];
        order[i].skip = &skipped[i];
        if (skipped[i].status != EMM_OK)
            continue;
        ran++;
        if (res[i].strategy.kind == EMM_STRATEGY_DIRECT && !direct)
            direct = &res[i];
        if (res[i].strategy.kind == EMM_STRATEGY_CACHE &&
            res[i].strategy.layout == EMM_LAYOUT_ORIGINAL && !cache)
            cache = &res[i];
    }
    qsort(order, n, sizeof *order, by_total);
    printf("trace %s: %llu accesses, %zu strategies (%zu skipped)\n\n", trace,
           (unsigned long long)accesses, n, n - ran);
    printf("%4s  %-26s %15s %11s %9s %9s  %s\n", "rank", "strategy", "total cycles", "seconds",
           "vs direct", "vs cache", "largest buckets");
    for (size_t k = 0; k < ran; k++) {
        const emm_result *r = order[k].res;
        char name[64], vd[32], vc[32], top[128] = "";
        int used[EMM_BUCKET_COUNT] = {0};
        size_t len = 0;
        emm_strategy_format(&r->strategy, name, sizeof name);
        speedup(vd, sizeof vd, direct, r);
        speedup(vc, sizeof vc, cache, r);
        /* The three largest non-empty buckets. */
        for (int t = 0; t < 3; t++) {
            int best = -1;
            for (int b = 0; b < EMM_BUCKET_COUNT; b++)
                if (!used[b] && r->cycles[b] > 0 && (best < 0 || r->cycles[b] > r->cycles[best]))
                    best = b;
            if (best < 0)
                break;
            used[best] = 1;
            len += (size_t)snprintf(top + len, sizeof top - len, "%s%s %.0f%%", t ? ", " : "",
                                    emm_bucket_name((emm_bucket)best),
                                    pct(r->cycles[best], r->total));
            if (len >= sizeof top)
                break;
        }
        printf("%4zu  %-26s %15llu %11.6f %9s %9s  %s\n", k + 1, name,
               (unsigned long long)r->total, (double)r->total / hz, vd, vc, top);
    }
    if (ran < n) {
        printf("\nskipped:\n");
        for (size_t k = ran; k < n; k++) {
            char name[64];
            emm_strategy_format(&order[k].res->strategy, name, sizeof name);
            /* Messages usually name the strategy already. */
            if (strstr(order[k].skip->message, name))
                printf("  %s\n", order[k].skip->message);
            else
                printf("  %s: %s\n", name, order[k].skip->message);
        }
    }
    free(order);
}

/* Whether the trace's mesh has depth, for the sweep; a trace that cannot
 * be opened has none here (the replay says why it cannot be read). */
static int trace_depth(const char *path)
{
    emm_trace_reader *r;
    if (emm_trace_reader_open(path, &r, NULL) != EMM_OK)
        return 0;
    const emm_trace_geometry *g = &emm_trace_reader_info(r)->geometry;
    int depth = emm_geometry_has_depth(g->xyz, g->nv, g->tri, g->nt);
    emm_trace_reader_close(r);
    return depth;
}

/* emm replay with its arrays: strategies, results and skipped hold `cap`
 * entries (one per --strategy, or the sweep). */
static int replay_main(struct replay_args *a, emm_strategy *strategies, emm_result *results,
                       emm_error *skipped, size_t cap)
{
    size_t nstrategies = 0;
    const char *trace = a->trace, *json = a->json, *timeline = a->timeline;
    int quiet = a->quiet, all = a->all, rc;
    emm_machine *m = NULL;
    emm_error err;
    uint64_t accesses = 0;
    struct progress_ctx pctx;

    if (all && a->strategies.n > 0)
        return cli_usage_error("replay", "--all and --strategy do not go together");
    if (a->indexed && !all)
        return cli_usage_error("replay", "--indexed goes with --all");
    if (all) {
        int depth = trace_depth(trace);
        nstrategies = emm_strategy_sweep_for(depth, strategies, cap);
        if (a->indexed)
            nstrategies += emm_strategy_sweep_indexed(depth, strategies + nstrategies,
                                                      cap - nstrategies);
    } else if (a->strategies.n == 0) {
        emm_strategy_parse("direct", &strategies[nstrategies++], NULL);
        emm_strategy_parse("cache", &strategies[nstrategies++], NULL);
    }
    for (size_t i = 0; i < a->strategies.n; i++) /* checked by opts_parse */
        emm_strategy_parse(a->strategies.v[i], &strategies[nstrategies++], NULL);
    if ((rc = machine_cli_build(&a->mc, "replay", &m)) != 0)
        return rc;

    pctx.on = !quiet && isatty(STDERR_FILENO);
    /* A sweep's report carries the per-cell data of its fastest EMM
     * strategy only: every strategy's would grow with strategies x cells. */
    int cells = !json ? EMM_REPLAY_CELLS_NONE
                      : all ? EMM_REPLAY_CELLS_FASTEST : EMM_REPLAY_CELLS_ALL;
    emm_replay_options ropt = {(unsigned)a->jobs, progress, &pctx, cells, a->memory,
                               NULL, NULL, NULL};
    if (timeline && emm_timeline_open(timeline, m, &strategies[0], 0, &ropt.timeline, &err) !=
                        EMM_OK) {
        emm_machine_free(m);
        return cli_fail(&err);
    }
    if (emm_replay_ex(trace, m, strategies, nstrategies, &ropt, results, all ? skipped : NULL,
                      &accesses, &err) != EMM_OK) {
        if (pctx.on)
            fputc('\n', stderr);
        emm_timeline_abort(ropt.timeline, NULL);
        emm_machine_free(m);
        return cli_fail(&err);
    }
    if (pctx.on)
        fprintf(stderr, "\r\033[K");
    if (!quiet)
        warn_remote(trace, m);
    if (ropt.timeline) {
        emm_status ts = emm_timeline_close(ropt.timeline, NULL, results[0].total, &err);
        if (ts == EMM_OK && !quiet) {
            char name[64];
            emm_strategy_format(&strategies[0], name, sizeof name);
            fprintf(stderr, "emm replay: wrote %s's timeline to %s\n", name, timeline);
        }
        if (ts != EMM_OK) {
            for (size_t i = 0; i < nstrategies; i++)
                emm_result_release(&results[i]);
            emm_machine_free(m);
            return cli_fail(&err);
        }
    }
    if (json && emm_report_write_ex(json, trace, m, accesses, results, all ? skipped : NULL,
                                    nstrategies, &err) != EMM_OK) {
        for (size_t i = 0; i < nstrategies; i++)
            emm_result_release(&results[i]);
        emm_machine_free(m);
        return cli_fail(&err);
    }
    for (size_t i = 0; i < nstrategies; i++)
        emm_result_release(&results[i]);
    if (!quiet && all)
        print_sweep(trace, accesses, m, results, skipped, nstrategies);
    else if (!quiet)
        print_table(trace, accesses, m, results, nstrategies);
    emm_machine_free(m);
    return EMM_EXIT_OK;
}

static int replay(void *p)
{
    struct replay_args *a = p;
    /* One strategy per --strategy, or the sweep (with room for the layouts
     * in space). */
    size_t cap = a->strategies.n + emm_strategy_sweep_for(1, NULL, 0) +
                 emm_strategy_sweep_indexed(1, NULL, 0);
    emm_strategy *strategies = calloc(cap, sizeof *strategies);
    emm_result *results = calloc(cap, sizeof *results);
    emm_error *skipped = calloc(cap, sizeof *skipped);
    int rc;
    if (strategies && results && skipped) {
        rc = replay_main(a, strategies, results, skipped, cap);
    } else {
        cli_error("replay: out of memory");
        rc = EMM_EXIT_FAIL;
    }
    free(strategies);
    free(results);
    free(skipped);
    return rc;
}

int emm_cmd_replay(int argc, char **argv)
{
    struct replay_args a = {0};
    opts_row rows[] = {
        {.name = "--strategy", .alias = "-s", .metavar = "S", .kind = OPT_STRATEGY,
         .repeat = true, .dst = &a.strategies,
         .help = "direct (word-by-word remote reads), cache (the hardware cache on the original "
                 "addresses), cache@LAYOUT[@CELL] (the cache on the addresses of a reordered "
                 "layout: grid, tiles, quadtree, grid3d, tiles3d, octree; CELL as below) or LAYOUT+FETCH[@CELL] (an "
                 "EMM strategy), with :indexed after it for the program renumbered by the layout "
                 "(emm layout --write); may be "
                 "repeated; default: direct and cache"},
        {.name = "--all", .kind = OPT_FLAG, .dst = &a.all,
         .help = "the standard sweep, with the layouts in space for a mesh with depth (not "
                 "with --strategy)"},
        {.name = "--indexed", .kind = OPT_FLAG, .dst = &a.indexed,
         .help = "with --all: the indexed variant (:indexed) of each EMM strategy of the sweep "
                 "joins it"},
        {.name = "--jobs", .alias = "-j", .metavar = "N", .kind = OPT_U64, .dst = &a.jobs,
         .min = 1, .max = MAX_JOBS,
         .help = "threads simulating strategies (default: the online CPUs, at most one per "
                 "strategy); results do not depend on N"},
        {.name = "--json", .metavar = "FILE", .kind = OPT_TEXT, .dst = &a.json,
         .help = "also write the JSON report (docs/report.md), whole or not at all; "
                 "with --all, the per-cell data of the fastest EMM strategy only"},
        {.name = "--timeline", .metavar = "FILE", .kind = OPT_TEXT, .dst = &a.timeline,
         .help = "write the first strategy's simulated run as Chrome/Perfetto trace-event JSON "
                 "(open it in ui.perfetto.dev or chrome://tracing): a track per DMA channel with "
                 "every transfer, the core's DMA stalls and cell entries; at most "
                 EMM_TIMELINE_MAX_EVENTS_TEXT " events, and its \"otherData\" says when the cap "
                 "was hit (docs/report.md \"Timelines\")"},
        {.name = "--memory", .metavar = "BYTES", .kind = OPT_SIZE, .dst = &a.memory, .min = 1,
         .help = "memory the models may take together (K/M/G; default half the physical "
                 "memory, at most 4G): a sweep that needs more runs in passes over the trace, "
                 "with the same results"},
        {.name = "--quiet", .alias = "-q", .kind = OPT_FLAG, .dst = &a.quiet,
         .help = "no table, no progress"},
        MACHINE_CLI_OPTS(&a.mc),
        {.metavar = "TRACE", .kind = OPT_TEXT, .dst = &a.trace, .required = true},
        OPTS_END,
    };
    opts o = {"replay", rows, usage};
    return opts_run(&o, argc, argv, replay, &a);
}
