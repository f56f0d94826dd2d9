/* emm replay: simulate a trace under one or more strategies on the machine
 * model (DESIGN.md "The machine model", thesis §3.2, §6.2) and print where
 * the cycles went; --json writes the report of docs/report.md. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "machine_cli.h"

#define MAX_STRATEGIES 64

static void usage(FILE *out)
{
    fprintf(out,
            "usage: emm replay TRACE [--strategy S]... [--json FILE] [--machine FILE]\n"
            "                  [--set KEY=VALUE]... [--quiet]\n"
            "\n"
            "Simulates the accesses recorded in TRACE on the machine model, once per\n"
            "strategy, in one pass over the file, and prints a table: total cycles, seconds\n"
            "at clock.mhz, and every cycle bucket with its share of the total, then the\n"
            "cache's line counts (Dinero IV's demand fetches, demand misses, prefetch\n"
            "fetches) or the DMA counts.\n"
            "\n"
            "  --strategy S     direct (word-by-word remote reads) or cache (the hardware\n"
            "                   cache on the original addresses); may be repeated; default:\n"
            "                   both. EMM strategies (grid+naive@64, ...) and cache@LAYOUT are\n"
            "                   not implemented in this build.\n"
            "  --json FILE      also write the JSON report (docs/report.md), whole or not at all\n"
            "  --quiet          no table, no progress\n"
            MACHINE_CLI_HELP
            "\n"
            "environment:\n"
            "  EMM_MACHINE      machine file used when --machine is absent\n");
}

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
        if (res[i].has_direct)
            printf("\n%s: words read %llu, words written %llu", name,
                   (unsigned long long)res[i].direct.words_read,
                   (unsigned long long)res[i].direct.words_written);
    }
    printf("\n");
}

int emm_cmd_replay(int argc, char **argv)
{
    machine_cli mc = {0};
    emm_strategy strategies[MAX_STRATEGIES];
    emm_result results[MAX_STRATEGIES];
    size_t nstrategies = 0;
    const char *trace = NULL, *json = NULL;
    int quiet = 0, rc;
    emm_machine *m = NULL;
    emm_error err;
    uint64_t accesses = 0;
    struct progress_ctx pctx;

    for (int i = 1; i < argc; i++) {
        int r;
        const char *v;
        if (cli_is_help(argv[i])) {
            usage(stdout);
            return EMM_EXIT_OK;
        }
        r = machine_cli_option(&mc, "replay", argc, argv, &i);
        if (r < 0)
            return EMM_EXIT_USAGE;
        if (r > 0)
            continue;
        if (strcmp(argv[i], "--strategy") == 0 || strcmp(argv[i], "-s") == 0) {
            if (!(v = cli_value("replay", argc, argv, &i)))
                return EMM_EXIT_USAGE;
            if (nstrategies == MAX_STRATEGIES)
                return cli_usage_error("replay", "at most %d strategies", MAX_STRATEGIES);
            if (emm_strategy_parse(v, &strategies[nstrategies], &err) != EMM_OK)
                return cli_usage_error("replay", "%s", err.message);
            nstrategies++;
        } else if (strcmp(argv[i], "--json") == 0) {
            if (!(json = cli_value("replay", argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else if (strcmp(argv[i], "--quiet") == 0 || strcmp(argv[i], "-q") == 0) {
            quiet = 1;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            return cli_usage_error("replay", "unknown option '%s'", argv[i]);
        } else if (!trace) {
            trace = argv[i];
        } else {
            return cli_usage_error("replay", "unexpected argument '%s'", argv[i]);
        }
    }
    if (!trace)
        return cli_usage_error("replay", "missing TRACE");
    if (nstrategies == 0) {
        emm_strategy_parse("direct", &strategies[nstrategies++], NULL);
        emm_strategy_parse("cache", &strategies[nstrategies++], NULL);
    }
    if ((rc = machine_cli_build(&mc, "replay", &m)) != 0)
        return rc;

    pctx.on = !quiet && isatty(STDERR_FILENO);
    if (emm_replay(trace, m, strategies, nstrategies, results, &accesses, progress, &pctx,
                   &err) != EMM_OK) {
        if (pctx.on)
            fputc('\n', stderr);
        emm_machine_free(m);
        return cli_fail(&err);
    }
    if (pctx.on)
        fprintf(stderr, "\r\033[K");
    if (json && emm_report_write(json, trace, m, accesses, results, nstrategies, &err) != EMM_OK) {
        emm_machine_free(m);
        return cli_fail(&err);
    }
    if (!quiet)
        print_table(trace, accesses, m, results, nstrategies);
    emm_machine_free(m);
    return EMM_EXIT_OK;
}
