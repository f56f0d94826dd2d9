/* Internal: the hardware cache of thesis §3.2, counting exactly as Dinero IV
 * does with -l1-dbsize LINE -l1-dassoc N -l1-drepl l -l1-dfetch d|m|a and its
 * default write-allocate, write-back, prefetch distance of one block
 * (docs/dinero.md), timed as thesis §3.2 says. */
#ifndef EMM_SIM_CACHE_H
#define EMM_SIM_CACHE_H

#include "machine.h"

typedef struct emm_cache {
    /* Each set's lines, most recently used first; EMM_CACHE_EMPTY marks an
     * unused way (block numbers never reach it). */
    uint64_t *tags;
    /* When each line's data has arrived (always-prefetch only; else NULL). */
    uint64_t *ready;
    uint64_t set_mask;
    uint32_t assoc;
    uint32_t line_shift;
    emm_cache_fetch fetch;

    /* Costs, from the machine. */
    uint64_t hit_cycles;   /* a hit */
    uint64_t local_cycles; /* the local access every miss also makes */
    uint64_t fill1;        /* a stalled DMA of one line */
    uint64_t fill2;        /* a stalled DMA of two lines (miss + prefetch) */
    uint64_t compute_per_access, compute_per_work;

    /* State of the run. Cycles follow from the counts (emm_cache_result);
     * the running clock is kept only where it matters: always-prefetch,
     * whose prefetches run while the core goes on. */
    struct emm_cache_counts {
        uint64_t accesses;
        uint64_t demand_fetches, demand_misses;
        uint64_t prefetch_fetches, prefetch_misses;
        uint64_t double_fills;    /* misses stalled for two lines (miss + prefetch) */
        uint64_t late_prefetches; /* hits on a line still in flight */
        uint64_t late_stall;      /* cycles waited for those */
        uint64_t compute;         /* compute cycles */
        uint64_t now;             /* always-prefetch: cycles so far */
    } n;
} emm_cache;

#define EMM_CACHE_EMPTY UINT64_MAX

/* A cold cache for a validated machine. */
emm_status emm_cache_init(emm_cache *c, const emm_machine_params *p, emm_error *err);
void emm_cache_reset(emm_cache *c);
void emm_cache_free(emm_cache *c);

/* One program access of `bytes` bytes at `addr` (each line it spans is one
 * demand reference, as Dinero splits references at block boundaries),
 * preceded by `work` units of compute. For models that compute addresses
 * their own way (the cache on a reordered layout); the record loop of the
 * cache model does the same inline. */
void emm_cache_access(emm_cache *c, uint64_t addr, uint32_t bytes, int write, uint32_t work);

/* Copies the counts and cycles into a result. */
void emm_cache_result(const emm_cache *c, emm_result *out);

#endif
