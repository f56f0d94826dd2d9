/* Internal: the hardware cache on a reordered layout (cache@LAYOUT). */
#ifndef EMM_SIM_CACHE_LAYOUT_H
#define EMM_SIM_CACHE_LAYOUT_H

#include "machine.h"
#include "share.h"

/* The cache model of strategy s (kind CACHE, layout GRID, TILES or QUADTREE;
 * cell 0 means EMM_DEFAULT_CELL) over the trace's geometry. Errors:
 * EMM_ERR_INVALID for an address-only trace (no geometry), a trace without
 * vertex or triangle arrays, or mesh arrays with more records than the
 * geometry has elements; the layout's own errors; EMM_ERR_NOMEM. */
emm_status emm_cache_layout_model_new(const emm_machine_params *p, const emm_strategy *s,
                                      const emm_trace_info *trace, emm_model_share *share,
                                      emm_model **out, emm_error *err);

#endif
