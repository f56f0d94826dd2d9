/* Internal: the DMA engine (thesis §3.2): a few channels that move data
 * while the core goes on. The core pays the programming (dma.program); a
 * transfer starts on the earliest-free channel once the core has issued it,
 * spends the controller's latency (dma.latency) there, and occupies that
 * channel until it completes; the core waits only when it needs the data,
 * and only for what is left. Times are in core cycles since the model
 * started. */
#ifndef EMM_SIM_DMA_H
#define EMM_SIM_DMA_H

#include "machine.h"

typedef struct emm_dma {
    uint64_t issue;                          /* cycles the core pays per transfer */
    uint64_t latency;                        /* the controller's, on the channel */
    uint32_t channels;
    uint64_t free_at[EMM_DMA_MAX_CHANNELS];  /* when each channel is next idle */
    emm_machine_params params;
    uint64_t transfers;
    uint64_t bytes;
    uint32_t last_channel; /* the latest transfer's channel and the time it took it */
    uint64_t last_start;
} emm_dma;

/* An idle engine for machine parameters p. */
void emm_dma_init(emm_dma *d, const emm_machine_params *p);
/* Idle again, counts cleared. */
void emm_dma_reset(emm_dma *d);

/* The core, at time `now`, issues a transfer of `bytes`. Returns the time the
 * core is free again (now + issue) in *core_free and the time the data has
 * arrived; last_channel and last_start say where and from when it ran. The
 * caller charges the issue to EMM_BUCKET_DMA_ISSUE. */
uint64_t emm_dma_start(emm_dma *d, uint64_t now, uint64_t bytes, uint64_t *core_free);

/* Cycles the core stalls at time `now` waiting for data that arrives at
 * `done` (0 when it is already there). Charge to EMM_BUCKET_DMA_STALL. */
static inline uint64_t emm_dma_wait(uint64_t now, uint64_t done)
{
    return done > now ? done - now : 0;
}

#endif
