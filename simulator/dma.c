/* The DMA engine of thesis §3.2: 266 cycles of initial programming — the
 * core's part (dma.program: the runtime's call, the controller's registers)
 * and the controller's own latency (dma.latency) — then 2 cycles per 8 bytes
 * and 208 cycles per further 1 KiB chunk on one of two channels, while the
 * core goes on. */
#include "dma.h"

#include <assert.h>
#include <string.h>

void emm_dma_init(emm_dma *d, const emm_machine_params *p)
{
    memset(d, 0, sizeof *d);
    assert(p->dma_channels >= 1 && p->dma_channels <= EMM_DMA_MAX_CHANNELS);
    d->params = *p;
    d->issue = p->dma_program;
    d->latency = p->dma_latency;
    d->channels = (uint32_t)p->dma_channels;
}

void emm_dma_reset(emm_dma *d)
{
    memset(d->free_at, 0, sizeof d->free_at);
    d->transfers = 0;
    d->bytes = 0;
}

uint64_t emm_dma_start(emm_dma *d, uint64_t now, uint64_t bytes, uint64_t *core_free)
{
    uint32_t best = 0;
    uint64_t issued = now + d->issue, start, done;
    for (uint32_t c = 1; c < d->channels; c++)
        if (d->free_at[c] < d->free_at[best])
            best = c;
    start = d->free_at[best] > issued ? d->free_at[best] : issued;
    done = start + d->latency + emm_dma_transfer_cycles(&d->params, bytes);
    d->free_at[best] = done;
    d->last_channel = best;
    d->last_start = start;
    d->transfers++;
    d->bytes += bytes;
    *core_free = issued;
    return done;
}
