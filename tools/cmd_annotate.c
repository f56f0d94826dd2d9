/* emm annotate: where a strategy's cycles went in the program's source, as
 * cg_annotate shows Cachegrind's counts: the trace's records are replayed
 * costed (emm_model_run_costed: each record's cycles by bucket and its
 * look-ups), summed by the program counter the capture recorded, resolved
 * to source lines and functions with libdw, and printed largest first; with
 * --source FILE, the file with the counts in the margin. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "annotate.h"
#include "cli.h"
#include "infile.h"
#include "opts.h"
#include "emm/replay.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "machine_cli.h"

#define DEFAULT_TOP 10

static void usage(FILE *out, const opts *o)
{
    fprintf(out,
            "usage: emm annotate TRACE --strategy S [--top N] [--sort KEY] [--source FILE]\n"
            "                    [--machine FILE] [--set KEY=VALUE]...\n"
            "\n"
            "Simulates TRACE under strategy S and shows where its cycles went in the\n"
            "program's source, as cg_annotate does for Cachegrind: for each source line and\n"
            "each function, the total cycles, the DMA stall, DMA issue and EMM instruction\n"
            "cycles, the EMM runtime's look-ups and the accesses, largest first. Each\n"
            "access's cycles are those the model charged while simulating it (a stall\n"
            "lands on the access that waited). A function's row includes the functions\n"
            "the compiler inlined into it (a line counts once, for each function it lies\n"
            "in), so an inlined helper shows under its own name and its caller's. The trace\n"
            "must hold the accesses' program counters: a program built for the sancov\n"
            "capture and run with\n"
            "  emm run --capture sancov --trace TRACE -- PROGRAM ...\n"
            "Lines and functions come from the program's debug information (libdw); an\n"
            "object without it is shown by its path.\n"
            "\n");
    opts_help(out, o);
}

static void on_costs(void *ctx, const emm_trace_record *recs, const emm_record_cost *cost,
                     size_t n)
{
    emm_annotation_add(ctx, recs, cost, n);
}

static double pct(uint64_t part, uint64_t whole)
{
    return whole ? 100.0 * (double)part / (double)whole : 0.0;
}

static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

static void print_header(const char *what, int key, size_t shown, size_t n)
{
    printf("\n-- %s, by %s (%zu of %zu)\n", what, emm_annotate_key_name(key), shown, n);
    printf("%15s %15s %6s %13s %13s %10s %10s  %s\n", "total", "dma_stall", "", "dma_issue",
           "emm_instr", "lookups", "accesses", what[0] == 'f' ? "function (file)" : "file:line (function)");
}

static void print_row(const emm_annotate_row *r, const emm_annotate_row *total, int line)
{
    char where[512];
    const char *fn = r->function ? r->function : "???";
    if (!r->file && !r->function && r->accesses && !line)
        snprintf(where, sizeof where, "(no program counter)");
    else if (line)
        snprintf(where, sizeof where, "%s:%d (%s)", r->file ? base_name(r->file) : "???",
                 r->line, fn);
    else
        snprintf(where, sizeof where, "%s (%s)", fn, r->file ? base_name(r->file) : "???");
    printf("%15llu %15llu %5.1f%% %13llu %13llu %10llu %10llu  %s\n",
           (unsigned long long)r->total,
           (unsigned long long)r->cycles[EMM_BUCKET_DMA_STALL],
           pct(r->cycles[EMM_BUCKET_DMA_STALL], total->cycles[EMM_BUCKET_DMA_STALL]),
           (unsigned long long)r->cycles[EMM_BUCKET_DMA_ISSUE],
           (unsigned long long)r->cycles[EMM_BUCKET_EMM_INSTRUCTIONS],
           (unsigned long long)r->lookups, (unsigned long long)r->accesses, where);
}

/* Whether `resolved` (a path from the debug information) names `want`:
 * equal, or ending in want's components. */
static int same_file(const char *resolved, const char *want)
{
    size_t a = strlen(resolved), b = strlen(want);
    if (a < b)
        return 0;
    return strcmp(resolved + a - b, want) == 0 && (a == b || resolved[a - b - 1] == '/' ||
                                                    want[0] == '/');
}

/* --source: the file with the line rows in the margin. */
static int print_source(const char *want, const emm_annotate_row *rows, size_t n)
{
    const char *path = NULL;
    for (size_t i = 0; i < n && !path; i++)
        if (rows[i].file && same_file(rows[i].file, want))
            path = rows[i].file;
    if (!path) {
        cli_error("annotate: --source %s: no access of the trace lies in that file", want);
        fprintf(stderr, "emm: the files with accesses:");
        for (size_t i = 0, shown = 0; i < n && shown < 12; i++) {
            int seen = 0;
            for (size_t k = 0; k < i && !seen; k++)
                seen = rows[k].file && rows[i].file && strcmp(rows[k].file, rows[i].file) == 0;
            if (rows[i].file && !seen) {
                fprintf(stderr, " %s", rows[i].file);
                shown++;
            }
        }
        fputc('\n', stderr);
        return EMM_EXIT_FAIL;
    }
    emm_error err;
    FILE *f = emm_infile_fopen(path, "source file", &err);
    if (!f && !(f = emm_infile_fopen(want, "source file", &err))) {
        cli_error("annotate: --source: %s", err.message);
        return EMM_EXIT_FAIL;
    }
    printf("\n-- %s (total, dma_stall, lookups per line)\n", path);
    char buf[4096];
    int line = 0, fresh = 1;
    while (fgets(buf, sizeof buf, f)) {
        if (fresh) {
            line++;
            const emm_annotate_row *r = NULL;
            for (size_t i = 0; i < n && !r; i++)
                if (rows[i].line == line && rows[i].file && strcmp(rows[i].file, path) == 0)
                    r = &rows[i];
            if (r)
                printf("%13llu %13llu %9llu  ", (unsigned long long)r->total,
                       (unsigned long long)r->cycles[EMM_BUCKET_DMA_STALL],
                       (unsigned long long)r->lookups);
            else
                printf("%13s %13s %9s  ", ".", ".", ".");
        }
        fputs(buf, stdout);
        fresh = strchr(buf, '\n') != NULL;
    }
    if (!fresh)
        putchar('\n');
    fclose(f);
    return EMM_EXIT_OK;
}

/* What the command line asked for. */
struct annotate_args {
    machine_cli mc;
    const char *trace, *strategy, *source;
    int key;
    uint64_t top;
};

static int annotate(void *p)
{
    struct annotate_args *args = p;
    const char *cmd = "annotate", *trace = args->trace, *source = args->source;
    emm_strategy s;
    int key = args->key, rc;
    uint64_t top = args->top;
    emm_error err;
    emm_strategy_parse(args->strategy, &s, NULL); /* checked by opts_parse */

    /* The trace must know where its accesses came from. */
    emm_trace_reader *r;
    if (emm_trace_reader_open(trace, &r, &err) != EMM_OK)
        return cli_fail(&err);
    if (!emm_trace_reader_info(r)->has_pc) {
        emm_trace_reader_close(r);
        cli_error("annotate: %s has no program counters: record it from a program built for "
                  "the sancov capture (emm run --capture sancov --trace FILE -- PROGRAM)",
                  trace);
        return EMM_EXIT_FAIL;
    }
    emm_machine *m = NULL;
    if ((rc = machine_cli_build(&args->mc, cmd, &m)) != 0) {
        emm_trace_reader_close(r);
        return rc;
    }
    emm_annotation *a = emm_annotation_new();
    emm_result res;
    uint64_t accesses = 0;
    emm_replay_options opt = {1, NULL, NULL, 0, 0, NULL, on_costs, a};
    rc = EMM_EXIT_FAIL;
    if (!a) {
        cli_error("annotate: out of memory");
        goto out;
    }
    if (emm_replay_ex(trace, m, &s, 1, &opt, &res, NULL, &accesses, &err) != EMM_OK) {
        cli_fail(&err);
        goto out;
    }
    const emm_trace_info *info = emm_trace_reader_info(r);
    if (emm_annotation_resolve(a, info->modules, info->nmodules, key, &err) != EMM_OK) {
        cli_fail(&err);
        goto out;
    }
    const emm_annotate_row *total = emm_annotation_total(a), *lines, *functions;
    size_t nl = emm_annotation_lines(a, &lines), nf = emm_annotation_functions(a, &functions);
    char name[64];
    emm_strategy_format(&s, name, sizeof name);
    printf("emm annotate: %s under %s: %llu accesses, %llu cycles (dma_stall %llu, "
           "lookups %llu)\n",
           trace, name, (unsigned long long)accesses, (unsigned long long)res.total,
           (unsigned long long)total->cycles[EMM_BUCKET_DMA_STALL],
           (unsigned long long)total->lookups);
    if (total->total != res.total) /* costs add up to the result by construction */
        cli_error("annotate: the records' costs add up to %llu cycles, not %llu",
                  (unsigned long long)total->total, (unsigned long long)res.total);
    size_t showf = top && top < nf ? (size_t)top : nf, showl = top && top < nl ? (size_t)top : nl;
    print_header("functions", key, showf, nf);
    for (size_t i = 0; i < showf; i++)
        print_row(&functions[i], total, 0);
    print_header("lines", key, showl, nl);
    for (size_t i = 0; i < showl; i++)
        print_row(&lines[i], total, 1);
    rc = source ? print_source(source, lines, nl) : EMM_EXIT_OK;
out:
    emm_annotation_free(a);
    emm_machine_free(m);
    emm_trace_reader_close(r);
    return rc;
}

int emm_cmd_annotate(int argc, char **argv)
{
    struct annotate_args a = {.key = EMM_ANNOTATE_TOTAL, .top = DEFAULT_TOP};
    const char *keys[EMM_ANNOTATE_KEYS + 1];
    for (int k = 0; k < EMM_ANNOTATE_KEYS; k++)
        keys[k] = emm_annotate_key_name(k);
    keys[EMM_ANNOTATE_KEYS] = NULL;
    opts_row rows[] = {
        {.name = "--strategy", .alias = "-s", .metavar = "S", .kind = OPT_STRATEGY,
         .dst = &a.strategy, .required = true,
         .help = "the strategy to simulate (required), e.g. tiles+convolution@64"},
        {.name = "--top", .metavar = "N", .kind = OPT_U64, .dst = &a.top, .show_default = true,
         .help = "lines and functions shown, 0 for all"},
        {.name = "--sort", .metavar = "KEY", .kind = OPT_WORD, .dst = &a.key, .words = keys,
         .help = "what to sort by: total (default), a bucket (dma_stall, dma_issue, "
                 "emm_instructions, local_access, remote_access, compute, cache_hit, "
                 "cache_miss_stall), lookups or accesses"},
        {.name = "--source", .metavar = "FILE", .kind = OPT_TEXT, .dst = &a.source,
         .help = "print FILE with each line's total, dma_stall and lookups in the margin (FILE "
                 "as the debug information names it, or any path ending in the same components)"},
        MACHINE_CLI_OPTS(&a.mc),
        {.metavar = "TRACE", .kind = OPT_TEXT, .dst = &a.trace, .required = true},
        OPTS_END,
    };
    opts o = {"annotate", rows, usage};
    return opts_run(&o, argc, argv, annotate, &a);
}
