/* How far apart a trace comes back to the same cell: for every entry into
 * a cell of strategy S's layout that the trace entered before, the bytes of
 * the distinct cells entered in between, its own included — the local
 * store that least-recently-used eviction needs to still hold the cell
 * (its LRU stack distance, counted in the cells' bytes). Prints the
 * percentiles and the share of re-entries within some store sizes. The
 * cells are those of S's layout and cell size built from the trace's
 * geometry with its record sizes (docs/layouts.md "The indexed variant":
 * region growing over a 1,000,000-face sphere). Only triangle requests
 * count: a vertex request goes to its triangle's cell. Not a test.
 * usage: reentry TRACE STRATEGY */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/layout.h"
#include "emm/strategy.h"
#include "emm/trace.h"

/* A Fenwick tree over the cell entries, holding at each cell's latest
 * entry that cell's bytes. */
static void tree_add(uint64_t *t, size_t n, size_t i, uint64_t v)
{
    for (i++; i <= n; i += i & (~i + 1))
        t[i - 1] += v;
}

static uint64_t tree_sum(const uint64_t *t, size_t i) /* entries [0, i) */
{
    uint64_t s = 0;
    for (; i; i -= i & (~i + 1))
        s += t[i - 1];
    return s;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

int main(int argc, char **argv)
{
    emm_error err;
    emm_trace_reader *r;
    emm_strategy s;
    emm_layout *l;
    if (argc != 3) {
        fprintf(stderr, "usage: reentry TRACE STRATEGY\n");
        return 2;
    }
    if (emm_trace_reader_open(argv[1], &r, &err) != EMM_OK ||
        emm_strategy_parse(argv[2], &s, &err) != EMM_OK) {
        fprintf(stderr, "reentry: %s\n", err.message);
        return 1;
    }
    const emm_trace_info *ti = emm_trace_reader_info(r);
    if (s.kind != EMM_STRATEGY_EMM || ti->geometry.nt == 0) {
        fprintf(stderr, "reentry: %s: an EMM strategy and a trace with geometry are needed\n",
                argv[2]);
        return 1;
    }
    emm_layout_options o;
    memset(&o, 0, sizeof o);
    o.kind = s.layout;
    o.cell = s.cell;
    uint32_t tarr = UINT32_MAX;
    for (uint32_t a = 0; a < ti->narrays; a++) {
        if (ti->arrays[a].kind == EMM_ARRAY_TRIANGLES && tarr == UINT32_MAX) {
            tarr = a;
            o.triangle_bytes = ti->arrays[a].record_size;
        } else if (ti->arrays[a].kind == EMM_ARRAY_VERTICES && !o.vertex_bytes) {
            o.vertex_bytes = ti->arrays[a].record_size;
        }
    }
    if (emm_layout_build(ti->geometry.xyz, ti->geometry.nv, ti->geometry.tri, ti->geometry.nt,
                         &o, argv[1], &l, &err) != EMM_OK) {
        fprintf(stderr, "reentry: %s\n", err.message);
        return 1;
    }
    uint32_t nc = emm_layout_cell_count(l);
    size_t n = (size_t)ti->accesses + 1, cap = 1u << 16, entries = 0, nd = 0;
    uint64_t *tree = calloc(n, sizeof *tree), *dist = malloc(n * sizeof *dist);
    int64_t *last = malloc((size_t)nc * sizeof *last);
    emm_trace_record *buf = malloc(cap * sizeof *buf);
    if (!tree || !dist || !last || !buf) {
        fprintf(stderr, "reentry: out of memory\n");
        return 1;
    }
    for (uint32_t c = 0; c < nc; c++)
        last[c] = -1;
    uint32_t cur = EMM_LAYOUT_NONE;
    for (;;) {
        size_t got = 0;
        if (emm_trace_read(r, buf, cap, &got, &err) != EMM_OK) {
            fprintf(stderr, "reentry: %s\n", err.message);
            return 1;
        }
        if (got == 0)
            break;
        for (size_t i = 0; i < got; i++) {
            if (buf[i].array != tarr || buf[i].element >= ti->geometry.nt)
                continue;
            uint32_t c = emm_layout_triangle_index(l, (uint32_t)buf[i].element).cell;
            if (c == cur)
                continue;
            cur = c;
            uint64_t bytes = emm_layout_cell_get(l, c)->bytes;
            if (last[c] >= 0) {
                dist[nd++] = tree_sum(tree, entries) - tree_sum(tree, (size_t)last[c] + 1) + bytes;
                tree_add(tree, n, (size_t)last[c], (uint64_t)0 - bytes);
            }
            last[c] = (int64_t)entries;
            tree_add(tree, n, entries++, bytes);
        }
    }
    printf("%s, %s: %zu cell entries, %zu re-entries\n", argv[1], argv[2], entries, nd);
    if (nd == 0)
        return 0;
    qsort(dist, nd, sizeof *dist, cmp_u64);
    printf("bytes between two entries of a cell: 10%% %llu, 25%% %llu, median %llu, 75%% %llu, "
           "90%% %llu, max %llu\n",
           (unsigned long long)dist[nd / 10], (unsigned long long)dist[nd / 4],
           (unsigned long long)dist[nd / 2], (unsigned long long)dist[3 * nd / 4],
           (unsigned long long)dist[9 * nd / 10], (unsigned long long)dist[nd - 1]);
    static const unsigned kib[] = {128, 256, 512, 1024, 2048, 4096, 8192};
    size_t k = 0;
    for (size_t i = 0; i < sizeof kib / sizeof kib[0]; i++) {
        while (k < nd && dist[k] <= (uint64_t)kib[i] << 10)
            k++;
        printf("  within %5u KiB: %5.1f %%\n", kib[i], 100.0 * (double)k / (double)nd);
    }
    free(buf);
    free(last);
    free(dist);
    free(tree);
    emm_layout_free(l);
    emm_trace_reader_close(r);
    return 0;
}
