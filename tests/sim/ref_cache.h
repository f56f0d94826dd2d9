/* A deliberately simple reference model of Dinero IV's counting, written
 * apart from simulator/cache.c to check it: per-set arrays of (block, last
 * use time), a linear search, the least recent use time evicted. The rules
 * (docs/dinero.md): a reference is split at block boundaries, each block is
 * one demand fetch; a read (never a write) prefetches block+1 on a miss
 * (fetch 'm') or always (fetch 'a'), after the demand block is placed; a
 * prefetch that hits refreshes its block's use time; writes allocate. */
#ifndef EMM_TESTS_REF_CACHE_H
#define EMM_TESTS_REF_CACHE_H

#include <stdint.h>
#include <stdlib.h>

typedef struct ref_cache {
    uint64_t nsets, assoc, line;
    char fetch; /* 'd', 'm', 'a' */
    uint64_t *block, *used;
    int *valid;
    uint64_t clock;
    uint64_t demand_fetches, demand_misses, prefetch_fetches, prefetch_misses;
} ref_cache;

static inline void ref_init(ref_cache *r, uint64_t bytes, uint64_t assoc, uint64_t line, char fetch)
{
    r->nsets = bytes / line / assoc;
    r->assoc = assoc;
    r->line = line;
    r->fetch = fetch;
    r->block = calloc(r->nsets * assoc, sizeof *r->block);
    r->used = calloc(r->nsets * assoc, sizeof *r->used);
    r->valid = calloc(r->nsets * assoc, sizeof *r->valid);
    r->clock = 0;
    r->demand_fetches = r->demand_misses = r->prefetch_fetches = r->prefetch_misses = 0;
}

static inline void ref_free(ref_cache *r)
{
    free(r->block);
    free(r->used);
    free(r->valid);
}

/* Returns 1 when block b was present. */
static inline int ref_touch(ref_cache *r, uint64_t b)
{
    uint64_t s = (b % r->nsets) * r->assoc, victim = s;
    r->clock++;
    for (uint64_t w = s; w < s + r->assoc; w++) {
        if (r->valid[w] && r->block[w] == b) {
            r->used[w] = r->clock;
            return 1;
        }
    }
    for (uint64_t w = s; w < s + r->assoc; w++) {
        if (!r->valid[w]) {
            victim = w;
            break;
        }
        if (r->used[w] < r->used[victim])
            victim = w;
    }
    r->valid[victim] = 1;
    r->block[victim] = b;
    r->used[victim] = r->clock;
    return 0;
}

static inline void ref_access(ref_cache *r, uint64_t addr, uint64_t size, int write)
{
    for (uint64_t b = addr / r->line; b <= (addr + size - 1) / r->line; b++) {
        int hit = ref_touch(r, b);
        r->demand_fetches++;
        if (!hit)
            r->demand_misses++;
        if (!write && (r->fetch == 'a' || (r->fetch == 'm' && !hit))) {
            r->prefetch_fetches++;
            if (!ref_touch(r, b + 1))
                r->prefetch_misses++;
        }
    }
}

#endif
