/* Internal: the EMM strategies' model (thesis §4.1–4.2; docs/fetch.md):
 * a layout of the trace's geometry, cells moved whole into the local store
 * by DMA, naive, convolution or extrapolated fetching, LRU eviction. */
#ifndef EMM_SIM_EMM_FETCH_H
#define EMM_SIM_EMM_FETCH_H

#include "emm/layout.h"
#include "machine.h"
#include "share.h"

/* A model of EMM strategy s (kind EMM_STRATEGY_EMM) on machine parameters
 * p, for a trace described by `trace`. Takes s's layout of the trace's
 * geometry, with the record sizes of its first VERTICES and TRIANGLES
 * arrays, from `share` (built there once for every model of that layout).
 * Errors: EMM_ERR_INVALID for a trace without geometry; EMM_ERR_RANGE when
 * the look-up tables (or their page frames) leave no local store or a cell
 * does not fit in what they leave (the layout's message, naming a CELL to
 * use); the layout's errors for bad geometry; EMM_ERR_NOMEM. */
emm_status emm_emm_model_new(const emm_machine_params *p, const emm_strategy *s,
                             const emm_trace_info *trace, emm_model_share *share,
                             emm_model **out, emm_error *err);

/* Test hook: called on every eviction with the cell, the model's clock and
 * the time the cell's transfer completed (never after `now`). NULL clears. */
typedef void (*emm_fetch_evict_hook)(void *ctx, uint32_t cell, uint64_t now, uint64_t ready);
void emm_fetch_set_evict_hook(emm_model *model, emm_fetch_evict_hook hook, void *ctx);

/* The local store left for cells (local.bytes minus the look-up tables or
 * their page frames) and the layout the model uses (lives as long as the
 * model). */
uint64_t emm_fetch_budget(const emm_model *model);
const emm_layout *emm_fetch_layout(const emm_model *model);

#endif
