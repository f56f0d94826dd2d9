/* Convolution fetching (thesis §4.2.1): on entering a cell, start
 * asynchronous fetches of all its ring-1 neighbours that are not resident;
 * the core waits only when it touches one still in flight. */
#include "fetch_scheme.h"

static void enter(emm_fetcher *f, void *state, uint32_t from, uint32_t to)
{
    (void)state;
    (void)from;
    const uint32_t *nb;
    uint32_t n = emm_layout_ring(emm_fetcher_layout(f), to, &nb, NULL);
    for (uint32_t i = 0; i < n; i++)
        emm_fetcher_prefetch(f, nb[i], to);
}

const struct emm_fetch_ops emm_fetch_convolution_ops = {0, NULL, enter};
