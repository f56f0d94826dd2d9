/* Where the models put a trace's arrays (docs/machine.md "Addresses").
 *
 * A trace records each array's base as the program had it, and those move
 * from run to run: ASLR places the heap and the mmap area anew each time,
 * and where a block lands within its page depends on what was allocated
 * before it, the shim's own allocations included (a --machine file read or
 * not moved the triangles of region growing by 0xd0 bytes). With them moved
 * which lines two arrays share, which cache sets they fight over and
 * whether a next-line prefetch runs from one into the other: the reference
 * cache's totals changed by about 0.1-0.4 % between two runs of the same
 * program. The models use these addresses instead: the arrays laid out
 * again from a fixed start, in the trace's order, each starting a fresh
 * 4 KiB page, as a page-aligned allocator would give them. Arrays whose
 * bytes overlapped in the program keep their distance to each other (the
 * group's lowest byte starts the page). Raw memory (an imported din trace)
 * keeps its addresses: they are the data. */
#include <stdbool.h>
#include <stdlib.h>

#include "emm/trace.h"
#include "error.h"

#define PAGE 4096u

struct span {
    uint32_t index;
    uint64_t lo, hi; /* the program's bytes [lo, hi) */
};

/* By array: the first array of its group; for that first array, the
 * group's bytes in the program [lo, hi) and where it is placed. */
struct group {
    uint32_t first;
    uint64_t lo, hi, at;
    bool placed;
};

static int by_address(const void *pa, const void *pb)
{
    const struct span *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    return a->index < b->index ? -1 : a->index > b->index;
}

emm_status emm_trace_place(const emm_trace_info *info, uint64_t *base, emm_error *err)
{
    uint32_t n = info->narrays;
    struct span *s = malloc((n ? n : 1) * sizeof *s);
    struct group *g = malloc((n ? n : 1) * sizeof *g); /* by array */
    if (!s || !g) {
        free(s);
        free(g);
        return emm_fail(err, EMM_ERR_NOMEM, "placing the trace's arrays: out of memory");
    }
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; i++) {
        const emm_trace_array *a = &info->arrays[i];
        base[i] = a->base;
        g[i].first = i;
        if (a->kind != EMM_ARRAY_RAW) /* the reader checked that the span fits */
            s[m++] = (struct span){i, a->base, a->base + a->count * a->record_size};
    }
    /* Groups of arrays whose bytes overlap, each named by its first array in
     * the trace's order, which holds the group's extent. */
    qsort(s, m, sizeof *s, by_address);
    for (uint32_t k = 0; k < m;) {
        uint32_t end = k + 1, first = s[k].index;
        uint64_t hi = s[k].hi;
        for (; end < m && s[end].lo < hi; end++) {
            if (s[end].hi > hi)
                hi = s[end].hi;
            if (s[end].index < first)
                first = s[end].index;
        }
        for (uint32_t j = k; j < end; j++)
            g[s[j].index].first = first;
        g[first].lo = s[k].lo;
        g[first].hi = hi;
        k = end;
    }
    /* Each group, in the order of its first array, on fresh pages from the
     * start. */
    uint64_t cursor = EMM_TRACE_PLACE_START;
    bool full = false;
    for (uint32_t i = 0; i < n; i++) {
        g[i].placed = false;
        if (info->arrays[i].kind == EMM_ARRAY_RAW || g[i].first != i || full)
            continue;
        uint64_t at = (cursor + PAGE - 1) & ~(uint64_t)(PAGE - 1);
        if (at < cursor || g[i].hi - g[i].lo > UINT64_MAX - at) {
            full = true; /* past the top of the address space: the rest keep theirs */
            continue;
        }
        g[i].at = at;
        g[i].placed = true;
        cursor = at + (g[i].hi - g[i].lo);
    }
    /* Each array at its distance from its group's lowest byte. */
    for (uint32_t i = 0; i < n; i++) {
        const struct group *f = &g[g[i].first];
        if (info->arrays[i].kind != EMM_ARRAY_RAW && f->placed)
            base[i] = f->at + (info->arrays[i].base - f->lo);
    }
    free(s);
    free(g);
    return EMM_OK;
}
