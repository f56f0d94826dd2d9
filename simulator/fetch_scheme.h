/* Internal: fetch schemes (thesis §4.2; docs/fetch.md), one ops table per
 * file (fetch_naive.c, fetch_convolution.c, fetch_extrapolated.c), picked
 * when an EMM model is built (docs/architecture.md, "Adding a fetch
 * scheme"). A scheme sees the model (emm_fetch.c) only through the few
 * calls below, and only when the program enters a cell: nothing of it runs
 * per access. */
#ifndef EMM_SIM_FETCH_SCHEME_H
#define EMM_SIM_FETCH_SCHEME_H

#include <stddef.h>

#include "emm/layout.h"
#include "machine.h"

/* The EMM model, as a scheme sees it. */
typedef struct fetch_model emm_fetcher;

const emm_layout *emm_fetcher_layout(const emm_fetcher *f);
const emm_machine_params *emm_fetcher_params(const emm_fetcher *f);
/* Charges the EMM runtime's own work (a prediction, say) to the core. */
void emm_fetcher_instructions(emm_fetcher *f, uint64_t cycles);
/* Starts an asynchronous fetch of cell c, which the scheme expects the
 * program to need soon; `entered` is the cell being worked on, which stays.
 * Looking c up, checking its residency and programming the DMA are charged
 * here; an empty, resident or filtered cell, or one without room, is not
 * fetched (docs/fetch.md). */
void emm_fetcher_prefetch(emm_fetcher *f, uint32_t c, uint32_t entered);

struct emm_fetch_ops {
    size_t state_bytes; /* the scheme's own state; zeroed when the model resets */
    /* After the zeroing (NULL: nothing to set). */
    void (*reset)(void *state, const emm_machine_params *p);
    /* The program entered cell `to` from cell `from` (EMM_LAYOUT_NONE: the
     * first cell of the run). NULL: the scheme fetches on demand only. */
    void (*enter)(emm_fetcher *f, void *state, uint32_t from, uint32_t to);
};

/* One table per scheme, named from EMM_FETCH_LIST: emm_fetch_naive_ops, ... */
#define EMM_FETCH_OPS_DECL_(e, n, w) extern const struct emm_fetch_ops emm_fetch_##n##_ops;
EMM_FETCH_LIST(EMM_FETCH_OPS_DECL_)
#undef EMM_FETCH_OPS_DECL_

#endif
