/* The tables and verdicts of bench/thesis: reads the JSON reports
 * (docs/report.md) of the four workloads run with EMM_COMPARE=all and prints
 * the table behind each of the thesis' Figs. 6.1–6.9 (chapter 6.3), checks
 * each statement of chapter 6 with a number or an ordering (docs/design.md
 * "What the thesis reports, and what emm reproduces": claims 1-5 and the
 * Tiles statement, 6), and
 * says what the distance profiler chose (thesis §5) and how far that is from the best of
 * the sweep. A report, not a test: it exits 0 whatever the verdicts, and 1 only when a
 * report cannot be read.
 *
 * "The EMM strategy" of a layout and fetch scheme is, as in thesis §6.3
 * ("we pick the EMM strategy with best performance"), the one with the best
 * cell size of the sweep.
 *
 * usage: thesis_report [--tolerance T] DIR
 *          (DIR holds curves-short.json, curves-long.json, region.json,
 *           random.json)
 *          and, beside each, NAME-cache.json: emm replay of cache@grid@CELL
 *          and cache@tiles@CELL at every cell of the sweep, the cache on the
 *          layout of the EMM strategy it is compared with, §6.3)
 *        thesis_report --fit REPORT
 *          (one line for the calibration search of bench/thesis --calibrate:
 *           direct / best tiles+convolution, cache / best tiles+convolution) */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/strategy.h"
#include "json_read.h"

/* ---- reports ----------------------------------------------------------- */

enum { NBUCKET = 8 };
static const char *const bucket_keys[NBUCKET] = {
    "local_access", "remote_access", "compute", "emm_instructions",
    "dma_issue", "dma_stall", "cache_hit", "cache_miss_stall"};
static const char *const bucket_heads[NBUCKET] = {
    "local", "remote", "compute", "emm_instr", "dma_issue", "dma_stall", "cache_hit", "miss_stall"};

typedef struct result {
    char name[64];
    emm_strategy s;
    double total;
    double bucket[NBUCKET];
    double dma_bytes;
} result;

typedef struct report {
    const char *title;
    char path[4096];
    char program[128], pattern[64], chosen[64], source[32], nearest[96], predicted[64];
    double distance;
    bool has_distance, novel;
    double accesses;
    double mesh_bytes; /* the traced mesh's records (0: unknown) */
    result *r;
    size_t n;
} report;

static void copy(char *dst, size_t cap, const char *src)
{
    snprintf(dst, cap, "%s", src ? src : "-");
}

static bool load_report(report *rep, const char *path)
{
    emm_error err;
    jr_value *root;
    if (jr_parse_file(path, &root, &err) != EMM_OK) {
        /* err names the file: "PATH: line L, column C: problem" */
        fprintf(stderr, "thesis_report: %s\n", err.message);
        return false;
    }
    const jr_value *results = jr_get(root, "results");
    if (!jr_is(root, JR_OBJECT) || jr_number(jr_get(root, "emm_report")) != 1 ||
        !jr_is(results, JR_ARRAY)) {
        fprintf(stderr, "thesis_report: %s: not an emm report (docs/report.md)\n", path);
        jr_free(root);
        return false;
    }
    copy(rep->path, sizeof rep->path, path);
    copy(rep->program, sizeof rep->program, jr_string(jr_get(root, "program")));
    copy(rep->pattern, sizeof rep->pattern, jr_string(jr_get(root, "pattern")));
    copy(rep->chosen, sizeof rep->chosen, jr_string(jr_get(root, "strategy")));
    const jr_value *d = jr_get(root, "decision");
    copy(rep->source, sizeof rep->source, jr_string(jr_get(d, "source")));
    copy(rep->nearest, sizeof rep->nearest, jr_string(jr_get(d, "nearest")));
    copy(rep->predicted, sizeof rep->predicted, jr_string(jr_get(d, "predicted")));
    const jr_value *dist = jr_get(d, "distance");
    rep->has_distance = jr_is(dist, JR_NUMBER);
    rep->distance = jr_number(dist);
    rep->novel = jr_bool(jr_get(d, "novel"));
    rep->accesses = jr_number(jr_get(root, "accesses"));
    rep->mesh_bytes = jr_number(jr_get(jr_get(root, "mesh"), "bytes"));
    size_t n = jr_len(results);
    rep->r = calloc(n ? n : 1, sizeof *rep->r);
    if (!rep->r) {
        jr_free(root);
        fprintf(stderr, "thesis_report: out of memory\n");
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        const jr_value *o = jr_at(results, i);
        const char *name = jr_string(jr_get(o, "strategy"));
        const jr_value *cycles = jr_get(o, "cycles");
        result x = {0};
        /* A strategy that did not run has only its name and an error. */
        if (!name || !cycles || emm_strategy_parse(name, &x.s, &err) != EMM_OK)
            continue;
        bool seen = false; /* a session report lists its chosen strategy twice */
        for (size_t k = 0; k < rep->n; k++)
            seen |= strcmp(rep->r[k].name, name) == 0;
        if (seen)
            continue;
        copy(x.name, sizeof x.name, name);
        x.total = jr_number(jr_get(cycles, "total"));
        for (int b = 0; b < NBUCKET; b++)
            x.bucket[b] = jr_number(jr_get(cycles, bucket_keys[b]));
        x.dma_bytes = jr_number(jr_get(jr_get(o, "dma"), "bytes"));
        rep->r[rep->n++] = x;
    }
    jr_free(root);
    return true;
}

/* Appends to rep the results of the report at path that rep lacks (the
 * replays of the cache on each layout at each cell). */
static bool merge_report(report *rep, const char *path)
{
    report more = {.title = rep->title};
    if (!load_report(&more, path))
        return false;
    result *r = realloc(rep->r, (rep->n + more.n + 1) * sizeof *r);
    if (!r) {
        free(more.r);
        fprintf(stderr, "thesis_report: out of memory\n");
        return false;
    }
    rep->r = r;
    for (size_t i = 0; i < more.n; i++) {
        bool seen = false;
        for (size_t k = 0; k < rep->n; k++)
            seen |= strcmp(rep->r[k].name, more.r[i].name) == 0;
        if (!seen)
            rep->r[rep->n++] = more.r[i];
    }
    free(more.r);
    return true;
}

static const result *find(const report *rep, const char *name)
{
    for (size_t i = 0; i < rep->n; i++)
        if (strcmp(rep->r[i].name, name) == 0)
            return &rep->r[i];
    return NULL;
}

/* The EMM strategy of a layout and fetch scheme: its best cell size. */
static const result *best_of(const report *rep, emm_layout_kind l, emm_fetch_kind f)
{
    const result *best = NULL;
    for (size_t i = 0; i < rep->n; i++) {
        const result *x = &rep->r[i];
        if (x->s.kind == EMM_STRATEGY_EMM && x->s.layout == l && x->s.fetch == f &&
            (!best || x->total < best->total))
            best = x;
    }
    return best;
}

static const result *best_emm_of_layout(const report *rep, emm_layout_kind l)
{
    const result *best = NULL;
    for (size_t i = 0; i < rep->n; i++) {
        const result *x = &rep->r[i];
        if (x->s.kind == EMM_STRATEGY_EMM && (l == EMM_LAYOUT_ORIGINAL || x->s.layout == l) &&
            (!best || x->total < best->total))
            best = x;
    }
    return best;
}

/* The fastest candidate: direct reads or an EMM strategy (STHORM has no
 * cache; the cache strategies are references). */
static const result *best_candidate(const report *rep)
{
    const result *best = NULL;
    for (size_t i = 0; i < rep->n; i++)
        if (rep->r[i].s.kind != EMM_STRATEGY_CACHE && (!best || rep->r[i].total < best->total))
            best = &rep->r[i];
    return best;
}

/* The cache on layout l at cell `cell` (cache@LAYOUT@CELL): thesis §6.3,
 * "Cache(Grid) runs on the grid layout same as in EMM(Grid)" — the layout
 * of the EMM strategy it is compared with, at that strategy's cell. */
static const result *cache_at(const report *rep, emm_layout_kind l, uint32_t cell)
{
    for (size_t i = 0; i < rep->n; i++) {
        const result *x = &rep->r[i];
        if (x->s.kind == EMM_STRATEGY_CACHE && x->s.layout == l && x->s.cell == cell)
            return x;
    }
    return NULL;
}

static const result *at_cell(const report *rep, emm_layout_kind l, emm_fetch_kind f, uint32_t cell)
{
    for (size_t i = 0; i < rep->n; i++) {
        const result *x = &rep->r[i];
        if (x->s.kind == EMM_STRATEGY_EMM && x->s.layout == l && x->s.fetch == f &&
            x->s.cell == cell)
            return x;
    }
    return NULL;
}

/* ---- figures ------------------------------------------------------------ */

/* The sweep's layouts, fetch schemes and cell sizes (emm/strategy.h), so a
 * figure lists whatever the standard sweep holds: the layouts in the plane
 * (the thesis' meshes are planar; those in space join only the sweep of a
 * mesh with depth). */
static emm_layout_kind layouts[EMM_LAYOUT_COUNT];
static emm_fetch_kind fetches[EMM_FETCH_COUNT];
static const uint32_t *cells;
static size_t nlayouts, nfetches, ncells;

static void sweep_parts(void)
{
    for (int l = EMM_LAYOUT_ORIGINAL + 1; l < EMM_LAYOUT_COUNT; l++)
        if (emm_layout_kind_dims((emm_layout_kind)l) == 2)
            layouts[nlayouts++] = (emm_layout_kind)l;
    for (int f = EMM_FETCH_NONE + 1; f < EMM_FETCH_COUNT; f++)
        fetches[nfetches++] = (emm_fetch_kind)f;
    ncells = emm_strategy_sweep_cells(&cells);
}

static void row(const char *label, const result *x)
{
    if (!x) {
        printf("  %-26s %12s   (did not run)\n", label, "-");
        return;
    }
    printf("  %-26s %12.0f", label, x->total);
    for (int b = 0; b < NBUCKET; b++)
        printf(" %11.0f", x->bucket[b]);
    printf("\n");
}

static void head(const char *fig, const char *caption)
{
    printf("\n%s  %s\n  %-26s %12s", fig, caption, "strategy", "total");
    for (int b = 0; b < NBUCKET; b++)
        printf(" %11s", bucket_heads[b]);
    printf("\n");
}

/* Figs. 6.1, 6.4, 6.6: each layout and fetch scheme at its best cell. */
static void fig_layouts(const report *rep, const char *fig, const char *what)
{
    char caption[160];
    snprintf(caption, sizeof caption, "%s: EMM layouts and fetch schemes, each at its best cell "
             "(cycles by bucket)", what);
    head(fig, caption);
    for (size_t l = 0; l < nlayouts; l++)
        for (size_t f = 0; f < nfetches; f++) {
            const result *x = best_of(rep, layouts[l], fetches[f]);
            row(x ? x->name : "-", x);
        }
}

/* Figs. 6.2, 6.7: total cycles per cell size. */
static void fig_cells(const report *rep, const char *fig, const char *what)
{
    printf("\n%s  %s: total cycles per cell size (triangles per cell)\n  %-26s", fig, what,
           "layout+fetch");
    for (size_t c = 0; c < ncells; c++)
        printf(" %12u", cells[c]);
    printf("\n");
    for (size_t l = 0; l < nlayouts; l++)
        for (size_t f = 0; f < nfetches; f++) {
            char label[64];
            snprintf(label, sizeof label, "%s+%s", emm_layout_name(layouts[l]),
                     emm_fetch_name(fetches[f]));
            printf("  %-26s", label);
            for (size_t c = 0; c < ncells; c++) {
                const result *x = at_cell(rep, layouts[l], fetches[f], cells[c]);
                if (x)
                    printf(" %12.0f", x->total);
                else
                    printf(" %12s", "-");
            }
            printf("\n");
        }
}

/* Figs. 6.3, 6.5, 6.8, 6.9: direct, the cache and the EMM strategy. */
static void fig_compare(const report *rep, const char *fig, const char *what,
                        const char *cache_layout, const result *emm, const char *emm_label)
{
    char caption[160], label[96];
    snprintf(caption, sizeof caption, "%s: direct read, cache and EMM (cycles by bucket)", what);
    head(fig, caption);
    row("direct", find(rep, "direct"));
    row("cache (original layout)", find(rep, "cache"));
    if (cache_layout) {
        snprintf(label, sizeof label, "cache@%s", cache_layout);
        row(label, find(rep, label));
        emm_strategy cs;
        emm_error err;
        /* The one the thesis compares: on the EMM strategy's own cells. */
        if (emm && emm->s.cell != EMM_DEFAULT_CELL &&
            emm_strategy_parse(label, &cs, &err) == EMM_OK) {
            const result *c = cache_at(rep, cs.layout, emm->s.cell);
            snprintf(label, sizeof label, "cache@%s@%u", cache_layout, emm->s.cell);
            row(label, c);
        }
    }
    if (emm_label) {
        snprintf(label, sizeof label, "EMM %s", emm ? emm->name : emm_label);
        row(label, emm);
    }
}

/* ---- claims ------------------------------------------------------------- */

static double ratio(const result *a, const result *b)
{
    return a && b && b->total > 0 ? a->total / b->total : NAN;
}

static int verdict(int id, const char *text, bool ok)
{
    printf("claim %d %s: %s\n", id, text, ok ? "REPRODUCED" : "NOT REPRODUCED");
    return ok;
}

static void sub(bool ok, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sub(bool ok, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("    [%s] ", ok ? "ok" : "no");
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
}

/* Whether x is the fastest of the nine layout+fetch EMM strategies. */
static bool best_of_nine(const report *rep, const result *x, const result **winner)
{
    const result *w = best_emm_of_layout(rep, EMM_LAYOUT_ORIGINAL);
    if (winner)
        *winner = w;
    return x && w && x->total <= w->total;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, size_t n)
{
    if (!n)
        return NAN;
    qsort(v, n, sizeof v[0], cmp_double);
    return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

/* The core's cycles on DMA: programming it and waiting for it. */
static double dma_time(const result *x)
{
    return x->bucket[4] + x->bucket[5];
}

/* How often cells were fetched again: the DMA bytes of the thesis' EMM
 * strategy of each workload, and of its fastest, over the mesh's bytes. */
static void refetch(const report *reps)
{
    static const emm_layout_kind L[4] = {EMM_LAYOUT_GRID, EMM_LAYOUT_TILES, EMM_LAYOUT_TILES,
                                         EMM_LAYOUT_ORIGINAL};
    static const emm_fetch_kind F[4] = {EMM_FETCH_NAIVE, EMM_FETCH_EXTRAPOLATED,
                                        EMM_FETCH_CONVOLUTION, EMM_FETCH_NONE};
    printf("\n== DMA bytes over the mesh's bytes (how often cells are fetched again)\n");
    printf("  %-14s %12s  %-26s %8s  %-26s %8s\n", "workload", "mesh bytes", "thesis' EMM strategy",
           "DMA/mesh", "fastest EMM strategy", "DMA/mesh");
    for (int w = 0; w < 4; w++) {
        const report *rep = &reps[w];
        const result *t = L[w] != EMM_LAYOUT_ORIGINAL ? best_of(rep, L[w], F[w]) : NULL;
        const result *b = best_emm_of_layout(rep, EMM_LAYOUT_ORIGINAL);
        double mb = rep->mesh_bytes;
        printf("  %-14s %12.0f  %-26s %8.2f  %-26s %8.2f\n", rep->title, mb, t ? t->name : "-",
               t && mb > 0 ? t->dma_bytes / mb : NAN, b ? b->name : "-",
               b && mb > 0 ? b->dma_bytes / mb : NAN);
    }
}

static void claims(report *reps, double tol)
{
    const report *sh = &reps[0], *lo = &reps[1], *rg = &reps[2], *ra = &reps[3];
    printf("\n== Statements of the thesis' chapter 6 with a number or an ordering (docs/design.md "
           "\"What the thesis reports\"; tolerance ±%.0f%% on the thesis' ratios)\n", tol * 100);
    printf("   (the EMM strategy of a layout+fetch = its best cell size, thesis §6.3)\n");
    int reproduced = 0;

    /* 1: region growing. */
    {
        const result *tc = best_of(rg, EMM_LAYOUT_TILES, EMM_FETCH_CONVOLUTION);
        double rd = ratio(find(rg, "direct"), tc), rc = ratio(find(rg, "cache"), tc);
        bool a = fabs(rd / 4.5 - 1) <= tol;
        bool b = rc > 1 && fabs(rc / 1.2 - 1) <= tol;
        printf("\n");
        reproduced += verdict(1, "region growing: tiles+convolution 4.5x faster than direct, "
                                 "1.2x faster than cache", a && b);
        sub(a, "direct / %s = %.2fx (thesis 4.5x; reproduced within %.2fx..%.2fx)",
            tc ? tc->name : "tiles+convolution", rd, 4.5 * (1 - tol), 4.5 * (1 + tol));
        sub(b, "cache / %s = %.2fx (thesis 1.2x; reproduced within %.2fx..%.2fx, above 1)",
            tc ? tc->name : "tiles+convolution", rc, 1.2 * (1 - tol), 1.2 * (1 + tol));
    }
    /* 2: long curves. */
    {
        const result *te = best_of(lo, EMM_LAYOUT_TILES, EMM_FETCH_EXTRAPOLATED), *w;
        bool a = best_of_nine(lo, te, &w);
        double rc = ratio(find(lo, "cache"), te);
        bool b = rc > 1 && fabs(rc / 1.12 - 1) <= tol;
        printf("\n");
        reproduced += verdict(2, "long curves: tiles+extrapolated best of EMM and ahead of the "
                                 "cache by 12%", a && b);
        sub(a, "best EMM strategy: %s (%.0f cycles); tiles+extrapolated: %s (%.0f cycles)",
            w ? w->name : "-", w ? w->total : 0, te ? te->name : "-", te ? te->total : 0);
        sub(b, "cache / %s = %.2fx: %s the cache by %.0f%% (thesis: ahead by 12%%, 1.12x; "
               "reproduced within %.2fx..%.2fx, above 1)",
            te ? te->name : "tiles+extrapolated", rc, rc > 1 ? "ahead of" : "behind",
            fabs(rc - 1) * 100, 1.12 * (1 - tol), 1.12 * (1 + tol));
    }
    /* 3: short curves. */
    {
        const result *gn = best_of(sh, EMM_LAYOUT_GRID, EMM_FETCH_NAIVE), *w;
        bool a = best_of_nine(sh, gn, &w);
        bool b = gn && gn->s.cell <= 32;
        /* Cache(Grid): the cache on grid+naive's own grid (§6.3). */
        const result *cg = gn ? cache_at(sh, EMM_LAYOUT_GRID, gn->s.cell) : NULL;
        double rg_ = ratio(cg, gn), rc = ratio(gn, find(sh, "cache"));
        bool c = rg_ > 1;
        bool d = rc >= 1 && rc - 1 <= tol;
        printf("\n");
        reproduced += verdict(3, "short curves: grid+naive with small cells best of EMM, ahead "
                                 "of Cache(Grid), a little behind cache", a && b && c && d);
        sub(a, "best EMM strategy: %s (%.0f cycles); grid+naive: %s (%.0f cycles)",
            w ? w->name : "-", w ? w->total : 0, gn ? gn->name : "-", gn ? gn->total : 0);
        sub(b, "grid+naive's best cell (Fig 6.2): %u triangles (small: 32 or fewer)",
            gn ? gn->s.cell : 0);
        sub(c, "%s / %s = %.2fx (Cache(Grid) on the same grid; thesis: above 1)",
            cg ? cg->name : "cache@grid", gn ? gn->name : "grid+naive", rg_);
        sub(d, "%s / cache = %.2fx (thesis: a little behind; reproduced within 1..%.2fx)",
            gn ? gn->name : "grid+naive", rc, 1 + tol);
    }
    /* 4: random access. */
    {
        const result *e = best_emm_of_layout(ra, EMM_LAYOUT_ORIGINAL), *c = find(ra, "cache");
        bool a = e && c && c->total < e->total;
        printf("\n");
        reproduced += verdict(4, "random access: the cache beats every EMM strategy", a);
        sub(a, "cache %.0f cycles; fastest EMM strategy %s %.0f cycles (%.2fx the cache)",
            c ? c->total : 0, e ? e->name : "-", e ? e->total : 0, ratio(e, c));
    }
    /* 5: quadtree (§6.3): "Quadtree has bad performance in all the
     * experiments. However, as can be seen in Figure, the DMA time for
     * Quadtree is almost half less than the other two". DMA time: the
     * core's cycles on DMA (buckets DMA issue + DMA stall), quadtree against
     * the mean of grid's and tiles' with the same fetch and cell, on the
     * figure the sentence points at (Fig 6.1, short curves); the bytes and
     * the other workloads are shown beside it. "Bad performance in all the
     * experiments": in each workload the quadtree's best strategy is slower
     * than grid's and tiles'. And the reason the thesis gives ("not
     * instruction-efficient"): more EMM instruction cycles in every pair. */
    {
        size_t cap = 4 * nfetches * ncells;
        double *tr = malloc(cap * sizeof *tr), *tall = malloc(cap * sizeof *tall);
        double *br = malloc(cap * sizeof *br);
        if (!tr || !tall || !br) {
            fprintf(stderr, "thesis_report: out of memory\n");
            exit(1);
        }
        size_t ntr = 0, nall = 0, nbr = 0, pairs = 0, more_instr = 0, loses = 0, faster = 0;
        size_t slower = 0;
        size_t best_loses = 0, best_pairs = 0;
        for (int w = 0; w < 4; w++) {
            for (size_t f = 0; f < nfetches; f++) {
                for (size_t k = 0; k < ncells; k++) {
                    const result *q = at_cell(&reps[w], EMM_LAYOUT_QUADTREE, fetches[f], cells[k]);
                    const result *g = at_cell(&reps[w], EMM_LAYOUT_GRID, fetches[f], cells[k]);
                    const result *t = at_cell(&reps[w], EMM_LAYOUT_TILES, fetches[f], cells[k]);
                    if (!q || !g || !t)
                        continue;
                    double dq = dma_time(q), dg = (dma_time(g) + dma_time(t)) / 2;
                    pairs++;
                    more_instr += q->bucket[3] > g->bucket[3] && q->bucket[3] > t->bucket[3];
                    faster += q->total < g->total && q->total < t->total;
                    slower += q->total > g->total && q->total > t->total;
                    if (dg > 0) {
                        tall[nall++] = dq / dg;
                        if (w == 0)
                            tr[ntr++] = dq / dg;
                    }
                    if (g->dma_bytes + t->dma_bytes > 0)
                        br[nbr++] = q->dma_bytes / ((g->dma_bytes + t->dma_bytes) / 2);
                }
                const result *q = best_of(&reps[w], EMM_LAYOUT_QUADTREE, fetches[f]);
                const result *g = best_of(&reps[w], EMM_LAYOUT_GRID, fetches[f]);
                const result *t = best_of(&reps[w], EMM_LAYOUT_TILES, fetches[f]);
                if (q && g && t) {
                    best_pairs++;
                    best_loses += q->total > g->total && q->total > t->total;
                }
            }
            const result *q = best_emm_of_layout(&reps[w], EMM_LAYOUT_QUADTREE);
            const result *g = best_emm_of_layout(&reps[w], EMM_LAYOUT_GRID);
            const result *t = best_emm_of_layout(&reps[w], EMM_LAYOUT_TILES);
            loses += q && g && t && q->total > g->total && q->total > t->total;
        }
        double mt = median(tr, ntr), mall = median(tall, nall), mb = median(br, nbr);
        bool a = ntr && fabs(mt / 0.5 - 1) <= tol;
        bool b = loses == 4;
        bool c = pairs && more_instr == pairs;
        printf("\n");
        reproduced += verdict(5, "quadtree: DMA time almost half of grid's and tiles', bad "
                                 "performance in all the experiments (not instruction-efficient)",
                              a && b && c);
        sub(a, "quadtree DMA time (DMA issue + DMA stall) / mean of grid's and tiles' (same fetch, "
               "same cell), short curves (Fig 6.1), median of %zu: %.2f (min %.2f, max %.2f; "
               "thesis almost half, reproduced within %.2f..%.2f)",
            ntr, mt, ntr ? tr[0] : NAN, ntr ? tr[ntr - 1] : NAN, 0.5 * (1 - tol), 0.5 * (1 + tol));
        printf("         all four workloads, median of %zu: %.2f; DMA bytes, median of %zu: %.2f\n",
               nall, mall, nbr, mb);
        /* Which cell Fig 6.1 shows the text does not say; the ratio by cell
         * (the median of the three fetch schemes), short curves. */
        printf("         short curves by cell (median of the 3 fetch schemes):");
        for (size_t k = 0; k < ncells; k++) {
            double v[EMM_FETCH_COUNT];
            size_t nv = 0;
            for (size_t f = 0; f < nfetches; f++) {
                const result *q = at_cell(sh, EMM_LAYOUT_QUADTREE, fetches[f], cells[k]);
                const result *g = at_cell(sh, EMM_LAYOUT_GRID, fetches[f], cells[k]);
                const result *t = at_cell(sh, EMM_LAYOUT_TILES, fetches[f], cells[k]);
                if (q && g && t && dma_time(g) + dma_time(t) > 0)
                    v[nv++] = dma_time(q) / ((dma_time(g) + dma_time(t)) / 2);
            }
            if (nv)
                printf(" %u: %.2f", cells[k], median(v, nv));
        }
        printf("\n");
        for (size_t f = 0; f < nfetches; f++) {
            const result *q = best_of(sh, EMM_LAYOUT_QUADTREE, fetches[f]);
            const result *g = best_of(sh, EMM_LAYOUT_GRID, fetches[f]);
            const result *t = best_of(sh, EMM_LAYOUT_TILES, fetches[f]);
            if (q && g && t)
                printf("         Fig 6.1 (each at its best cell): %s DMA time / %s's and %s's = "
                       "%.2f\n", q->name, g->name, t->name,
                       dma_time(q) / ((dma_time(g) + dma_time(t)) / 2));
        }
        sub(b, "quadtree's best strategy is slower than grid's and tiles' in %zu of 4 workloads "
               "(each fetch scheme at its best cell: %zu of %zu; same fetch and cell: slower than "
               "both in %zu of %zu pairs, faster than both in %zu)",
            loses, best_loses, best_pairs, slower, pairs, faster);
        sub(c, "quadtree spends more EMM instruction cycles than grid and tiles in %zu of %zu "
               "pairs", more_instr, pairs);
        free(tr);
        free(tall);
        free(br);
    }
    /* 6: tiles on region growing (§6.3): "The Cache(Tiles) and the
     * EMM(Tiles) bar demonstrate that, even if data are organized by
     * locality, EMM fetching schemes can still outperform cache". */
    {
        const result *tc = best_of(rg, EMM_LAYOUT_TILES, EMM_FETCH_CONVOLUTION);
        const result *ct = tc ? cache_at(rg, EMM_LAYOUT_TILES, tc->s.cell) : NULL;
        double r = ratio(ct, tc);
        bool a = r > 1;
        printf("\n");
        reproduced += verdict(6, "region growing: EMM(Tiles) outperforms Cache(Tiles)", a);
        sub(a, "%s %.0f cycles / %s %.0f cycles = %.2fx (Cache(Tiles) on the same tiles; "
               "thesis: above 1)",
            ct ? ct->name : "cache@tiles", ct ? ct->total : 0, tc ? tc->name : "tiles+convolution", tc ? tc->total : 0, r);
    }
    /* Fig 6.7: the text states no cell size for region growing; shown. */
    {
        printf("\nFig 6.7 (no statement in the text): best cell per layout+fetch on region "
               "growing:");
        for (size_t l = 0; l < nlayouts; l++)
            for (size_t f = 0; f < nfetches; f++) {
                const result *x = best_of(rg, layouts[l], fetches[f]);
                if (x)
                    printf(" %s", x->name);
            }
        printf("\n");
    }
    printf("\n%d of 6 statements reproduced\n", reproduced);
}

/* ---- the profiler's choices ------------------------------------------- */

static void choices(const report *reps)
{
    printf("\n== What emm answered (regret = answer / the best candidate of the sweep - 1;\n"
           "   candidates: direct and the EMM strategies, the machine has no cache). The window\n"
           "   predicts (source: how); with the whole run captured, the run's contest answers\n"
           "   (docs/profile.md \"The contest\"); both are shown\n");
    printf("  %-14s %-9s %-26s %6s %-24s %-10s %8s %-24s %8s %-24s %12s %8s %9s\n", "workload",
           "pattern", "nearest sample", "dist", "predicted", "source", "regret", "answer",
           "regret", "best candidate", "cycles", "vs cache", "vs EMM");
    for (int w = 0; w < 4; w++) {
        const report *rep = &reps[w];
        const result *ch = find(rep, rep->chosen), *best = best_candidate(rep), *c = find(rep, "cache");
        const result *pr = rep->predicted[0] ? find(rep, rep->predicted) : ch;
        char dist[32];
        if (rep->has_distance)
            snprintf(dist, sizeof dist, "%.2f", rep->distance);
        else
            snprintf(dist, sizeof dist, "-");
        printf("  %-14s %-9s %-26s %6s %-24s %-10s %7.1f%% %-24s %7.1f%% %-24s %12.0f %7.2fx %8.1f%%\n",
               rep->title, rep->pattern, rep->nearest, dist,
               rep->predicted[0] ? rep->predicted : rep->chosen, rep->source,
               (ratio(pr, best) - 1) * 100, rep->chosen, (ratio(ch, best) - 1) * 100,
               best ? best->name : "-", best ? best->total : NAN, ratio(c, ch),
               (ratio(ch, best_emm_of_layout(rep, EMM_LAYOUT_ORIGINAL)) - 1) * 100);
    }
    printf("  (vs cache: cache cycles / answer cycles, above 1 when the answer beats the cache;\n"
           "   vs EMM: answer cycles / the fastest EMM strategy's - 1)\n");
}

int main(int argc, char **argv)
{
    double tol = 0.25;
    sweep_parts();
    const char *dir = NULL, *fit = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--tolerance") == 0 && i + 1 < argc)
            tol = strtod(argv[++i], NULL);
        else if (strcmp(argv[i], "--fit") == 0 && i + 1 < argc)
            fit = argv[++i];
        else if (argv[i][0] != '-' && !dir)
            dir = argv[i];
        else
            dir = NULL, fit = NULL, i = argc;
    }
    if ((!dir && !fit) || !(tol >= 0 && tol < 1)) {
        fprintf(stderr, "usage: thesis_report [--tolerance T] DIR | thesis_report --fit REPORT\n");
        return 2;
    }
    if (fit) {
        report rep = {.title = "fit"};
        if (!load_report(&rep, fit))
            return 1;
        const result *tc = best_of(&rep, EMM_LAYOUT_TILES, EMM_FETCH_CONVOLUTION);
        printf("%.4f %.4f %s\n", ratio(find(&rep, "direct"), tc), ratio(find(&rep, "cache"), tc),
               tc ? tc->name : "-");
        free(rep.r);
        return 0;
    }
    report reps[4] = {{.title = "short curves"}, {.title = "long curves"},
                      {.title = "region growing"}, {.title = "random access"}};
    static const char *const files[4] = {"curves-short", "curves-long", "region", "random"};
    int status = 0;
    for (int w = 0; w < 4; w++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s.json", dir, files[w]);
        if (!load_report(&reps[w], path))
            status = 1;
        snprintf(path, sizeof path, "%s/%s-cache.json", dir, files[w]);
        if (status == 0 && w != 3 && !merge_report(&reps[w], path))
            status = 1;
    }
    if (status == 0) {
        const report *sh = &reps[0], *lo = &reps[1], *rg = &reps[2], *ra = &reps[3];
        printf("== Figures 6.1-6.9 (thesis chapter 6.3), cycles on the simulated machine\n");
        printf("   (accesses simulated: short curves %.0f, long curves %.0f, region growing %.0f, "
               "random access %.0f)\n", sh->accesses, lo->accesses, rg->accesses, ra->accesses);
        fig_layouts(sh, "Fig 6.1", "short curves");
        fig_cells(sh, "Fig 6.2", "short curves");
        fig_compare(sh, "Fig 6.3", "short curves", "grid",
                    best_of(sh, EMM_LAYOUT_GRID, EMM_FETCH_NAIVE), "grid+naive");
        fig_layouts(lo, "Fig 6.4", "long curves");
        fig_compare(lo, "Fig 6.5", "long curves", "tiles",
                    best_of(lo, EMM_LAYOUT_TILES, EMM_FETCH_EXTRAPOLATED), "tiles+extrapolated");
        fig_layouts(rg, "Fig 6.6", "region growing");
        fig_cells(rg, "Fig 6.7", "region growing");
        fig_compare(rg, "Fig 6.8", "region growing", "tiles",
                    best_of(rg, EMM_LAYOUT_TILES, EMM_FETCH_CONVOLUTION), "tiles+convolution");
        fig_compare(ra, "Fig 6.9", "random access", NULL, NULL, NULL);
        for (size_t l = 0; l < nlayouts; l++) {
            const result *x = best_emm_of_layout(ra, layouts[l]);
            char label[96];
            snprintf(label, sizeof label, "EMM %s", x ? x->name : emm_layout_name(layouts[l]));
            row(label, x);
        }
        refetch(reps);
        claims(reps, tol);
        choices(reps);
    }
    for (int w = 0; w < 4; w++)
        free(reps[w].r);
    return status;
}
