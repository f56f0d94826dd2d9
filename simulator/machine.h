/* Internal: the machine's parameters as a plain struct, for the models. */
#ifndef EMM_SIM_MACHINE_H
#define EMM_SIM_MACHINE_H

#include "emm/sim.h"

typedef struct emm_machine_params {
    uint64_t clock_mhz;
    uint64_t word_bytes;
    uint64_t local_bytes;
    uint64_t local_cycles;
    uint64_t remote_bytes;
    uint64_t direct_cycles_per_word;
    uint64_t direct_write_cycles;
    uint64_t direct_granularity; /* emm_direct_granularity */
    uint64_t dma_program;  /* the core's part of starting a transfer */
    uint64_t dma_latency;  /* the controller's part, on the channel */
    uint64_t dma_cycles_per_8b;
    uint64_t dma_chunk_bytes;
    uint64_t dma_chunk_cycles;
    uint64_t dma_channels;
    uint64_t cache_bytes;
    uint64_t cache_assoc;
    uint64_t cache_line;
    uint64_t cache_fetch; /* emm_cache_fetch */
    uint64_t cache_hit;
    uint64_t cache_present; /* 1: the target has the cache (a candidate), 0: a reference */
    uint64_t compute_per_access;
    uint64_t compute_per_work;
    uint64_t emm_lookup;
    uint64_t emm_residency;
    uint64_t emm_quadtree_level;
    uint64_t emm_predict;
    uint64_t emm_dma_issue_instr;
    uint64_t emm_fifo; /* extrapolated fetching: moves remembered */
    uint64_t emm_prefetch_filter; /* 1: the prefetch pollution filter is on */
    uint64_t emm_lookup_budget;   /* local store bytes the look-up tables may hold */
    uint64_t emm_lookup_page;     /* bytes of one page of the look-up tables */
} emm_machine_params;

struct emm_machine {
    emm_machine_params p;
};

/* Cycles of a synchronous DMA of `bytes`: programming, the controller's
 * latency, the transfer. */
static inline uint64_t emm_dma_sync_cycles(const emm_machine_params *p, uint64_t bytes);

/* The largest number of DMA channels a machine may have. */
#define EMM_DMA_MAX_CHANNELS 16u

/* Cycles of the transfer part of a DMA of `bytes` (no issue cost). */
static inline uint64_t emm_dma_transfer_cycles(const emm_machine_params *p, uint64_t bytes)
{
    if (bytes == 0)
        return 0;
    return p->dma_cycles_per_8b * ((bytes + 7) / 8) +
           p->dma_chunk_cycles * ((bytes + p->dma_chunk_bytes - 1) / p->dma_chunk_bytes - 1);
}

static inline uint64_t emm_dma_sync_cycles(const emm_machine_params *p, uint64_t bytes)
{
    return bytes ? p->dma_program + p->dma_latency + emm_dma_transfer_cycles(p, bytes) : 0;
}

#endif
