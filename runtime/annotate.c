/* Cycles by program counter, line and function (annotate.h). The counters
 * live in an open-addressing table keyed by pc (a program has a few
 * thousand access sites at most); lines and functions are made by sorting
 * the resolved counters and merging neighbours. */
#include "annotate.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "srcline.h"

struct pc_row {
    uint64_t pc; /* 0: empty */
    emm_annotate_row row;
};

struct emm_annotation {
    struct pc_row *t;
    size_t cap, used;
    emm_annotate_row total;
    emm_annotate_row nopc;
    emm_srcmap *map;
    emm_annotate_row *lines, *functions;
    size_t nlines, nfunctions;
};

const char *emm_annotate_key_name(int key)
{
    if (key >= 0 && key < EMM_BUCKET_COUNT)
        return emm_bucket_name((emm_bucket)key);
    return key == EMM_ANNOTATE_TOTAL     ? "total"
           : key == EMM_ANNOTATE_LOOKUPS ? "lookups"
           : key == EMM_ANNOTATE_ACCESSES ? "accesses"
                                          : "?";
}

int emm_annotate_key(const char *name)
{
    for (int k = 0; k < EMM_ANNOTATE_KEYS; k++)
        if (strcmp(name, emm_annotate_key_name(k)) == 0)
            return k;
    return -1;
}

uint64_t emm_annotate_value(const emm_annotate_row *r, int key)
{
    if (key >= 0 && key < EMM_BUCKET_COUNT)
        return r->cycles[key];
    return key == EMM_ANNOTATE_TOTAL     ? r->total
           : key == EMM_ANNOTATE_LOOKUPS ? r->lookups
                                         : r->accesses;
}

emm_annotation *emm_annotation_new(void)
{
    return calloc(1, sizeof(emm_annotation));
}

void emm_annotation_free(emm_annotation *a)
{
    if (!a)
        return;
    free(a->t);
    free(a->lines);
    free(a->functions);
    emm_srcmap_free(a->map);
    free(a);
}

static size_t slot_of(uint64_t pc, size_t cap)
{
    return (size_t)(pc * 0x9E3779B97F4A7C15ull >> 17) & (cap - 1);
}

static bool grow(emm_annotation *a)
{
    size_t cap = a->cap ? 2 * a->cap : 1024;
    struct pc_row *t = calloc(cap, sizeof *t);
    if (!t)
        return false;
    for (size_t i = 0; i < a->cap; i++) {
        if (!a->t[i].pc)
            continue;
        size_t k = slot_of(a->t[i].pc, cap);
        while (t[k].pc)
            k = (k + 1) & (cap - 1);
        t[k] = a->t[i];
    }
    free(a->t);
    a->t = t;
    a->cap = cap;
    return true;
}

static void add_cost(emm_annotate_row *r, const emm_record_cost *c)
{
    for (int b = 0; b < EMM_BUCKET_COUNT; b++) {
        r->cycles[b] += c->cycles[b];
        r->total += c->cycles[b];
    }
    r->lookups += c->lookups;
    r->accesses++;
}

/* The row of counter pc (nonzero), added when new; NULL when memory ran
 * out. */
static emm_annotate_row *row_of(emm_annotation *a, uint64_t pc)
{
    if (2 * (a->used + 1) > a->cap && !grow(a))
        return NULL;
    size_t k = slot_of(pc, a->cap);
    while (a->t[k].pc && a->t[k].pc != pc)
        k = (k + 1) & (a->cap - 1);
    if (!a->t[k].pc) {
        a->t[k].pc = pc;
        a->used++;
    }
    return &a->t[k].row;
}

int emm_annotation_add(emm_annotation *a, const emm_trace_record *recs,
                       const emm_record_cost *cost, size_t n)
{
    int ok = 1;
    for (size_t i = 0; i < n; i++) {
        add_cost(&a->total, &cost[i]);
        emm_annotate_row *r = recs[i].pc ? row_of(a, recs[i].pc) : &a->nopc;
        if (r)
            add_cost(r, &cost[i]);
        else
            ok = 0;
    }
    return ok;
}

int emm_annotation_add_stall(emm_annotation *a, uint64_t pc, uint64_t cycles)
{
    a->total.cycles[EMM_BUCKET_DMA_STALL] += cycles;
    a->total.total += cycles;
    emm_annotate_row *r = pc ? row_of(a, pc) : &a->nopc;
    if (!r)
        return 0;
    r->cycles[EMM_BUCKET_DMA_STALL] += cycles;
    r->total += cycles;
    return 1;
}

const emm_annotate_row *emm_annotation_total(const emm_annotation *a)
{
    return &a->total;
}

static int strcmp_null(const char *x, const char *y)
{
    return !x || !y ? (x != NULL) - (y != NULL) : strcmp(x, y);
}

static int by_place(const void *p, const void *q)
{
    const emm_annotate_row *a = p, *b = q;
    int c = strcmp_null(a->file, b->file);
    return c ? c : (a->line > b->line) - (a->line < b->line);
}

static int by_function(const void *p, const void *q)
{
    const emm_annotate_row *a = p, *b = q;
    int c = strcmp_null(a->function, b->function);
    return c ? c : strcmp_null(a->file, b->file);
}

static int by_key(const void *p, const void *q, void *ctx)
{
    const int key = *(const int *)ctx;
    uint64_t a = emm_annotate_value(p, key), b = emm_annotate_value(q, key);
    if (a != b)
        return a > b ? -1 : 1;
    return by_place(p, q);
}

static void merge_into(emm_annotate_row *dst, const emm_annotate_row *src)
{
    for (int b = 0; b < EMM_BUCKET_COUNT; b++)
        dst->cycles[b] += src->cycles[b];
    dst->total += src->total;
    dst->lookups += src->lookups;
    dst->accesses += src->accesses;
}

/* Sorts rows[0..n) with `same`, merges neighbours that compare equal, and
 * returns the count left. */
static size_t merge(emm_annotate_row *rows, size_t n, int (*same)(const void *, const void *))
{
    if (n == 0)
        return 0;
    qsort(rows, n, sizeof *rows, same);
    size_t k = 0;
    for (size_t i = 1; i < n; i++) {
        if (same(&rows[k], &rows[i]) == 0)
            merge_into(&rows[k], &rows[i]);
        else
            rows[++k] = rows[i];
    }
    return k + 1;
}

emm_status emm_annotation_resolve(emm_annotation *a, const emm_trace_module *m, uint32_t n,
                                  int key, emm_error *err)
{
    emm_status st = emm_srcmap_new(m, n, &a->map, err);
    if (st != EMM_OK)
        return st;
    size_t rows = a->used + 1;
    a->lines = malloc(rows * sizeof *a->lines);
    a->functions = malloc(rows * EMM_SRCLOC_CHAIN * sizeof *a->functions);
    if (!a->lines || !a->functions)
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the annotation");
    size_t k = 0, f = 0;
    for (size_t i = 0; i < a->cap; i++) {
        if (!a->t[i].pc)
            continue;
        emm_srcloc loc;
        emm_srcmap_lookup(a->map, a->t[i].pc, &loc);
        emm_annotate_row r = a->t[i].row;
        r.file = loc.file;
        r.line = loc.file ? loc.line : 0;
        r.function = loc.function;
        a->lines[k++] = r;
        /* A function's row counts the code inlined into it too: each
         * function of the chain once. */
        for (int c = 0; c < loc.nchain; c++) {
            bool again = false;
            for (int d = 0; d < c && !again; d++)
                again = strcmp(loc.chain[d], loc.chain[c]) == 0;
            if (again)
                continue;
            a->functions[f] = r;
            a->functions[f].file = loc.chain_file[c];
            a->functions[f++].function = loc.chain[c];
        }
        if (loc.nchain == 0)
            a->functions[f++] = r;
    }
    if (a->nopc.accesses) {
        a->lines[k++] = a->nopc;
        a->functions[f++] = a->nopc;
    }
    a->nlines = merge(a->lines, k, by_place);
    a->nfunctions = merge(a->functions, f, by_function);
    for (size_t i = 0; i < a->nfunctions; i++)
        a->functions[i].line = 0;
    qsort_r(a->lines, a->nlines, sizeof *a->lines, by_key, &key);
    qsort_r(a->functions, a->nfunctions, sizeof *a->functions, by_key, &key);
    return EMM_OK;
}

size_t emm_annotation_lines(const emm_annotation *a, const emm_annotate_row **rows)
{
    *rows = a->lines;
    return a->nlines;
}

size_t emm_annotation_functions(const emm_annotation *a, const emm_annotate_row **rows)
{
    *rows = a->functions;
    return a->nfunctions;
}
