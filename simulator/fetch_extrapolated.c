/* Extrapolated fetching (thesis §4.2.2): the moves between consecutive
 * cells go into a short FIFO (emm.fifo entries); the side that most of them
 * point to is where the program goes next, and the neighbours on that side
 * are prefetched. A grid's diagonal move counts for both its sides. Ties go
 * to the side of the most recent move that has one. */
#include "fetch_scheme.h"

#define MAX_FIFO 64u

struct fifo {
    uint8_t move[MAX_FIFO]; /* EMM_SIDE_* bits of each move */
    uint32_t len, pos, cap;
};

static void reset(void *state, const emm_machine_params *p)
{
    struct fifo *q = state;
    q->cap = p->emm_fifo >= 1 && p->emm_fifo <= MAX_FIFO ? (uint32_t)p->emm_fifo : 4;
}

static void enter(emm_fetcher *f, void *state, uint32_t from, uint32_t to)
{
    struct fifo *q = state;
    const emm_layout *l = emm_fetcher_layout(f);
    unsigned count[EMM_SIDE_BITS] = {0}, best = 0, side = 0, top = 0;
    if (from == EMM_LAYOUT_NONE)
        return;
    q->move[q->pos] = (uint8_t)emm_layout_move_side(l, from, to);
    if (++q->pos == q->cap)
        q->pos = 0;
    if (q->len < q->cap)
        q->len++;
    emm_fetcher_instructions(f, emm_fetcher_params(f)->emm_predict);
    /* Each side's moves (counted without a branch per bit), the most of
     * them, and the sides that have that many. */
    for (uint32_t i = 0; i < q->len; i++)
        for (unsigned b = 0; b < EMM_SIDE_BITS; b++)
            count[b] += (q->move[i] >> b) & 1u;
    for (unsigned b = 0; b < EMM_SIDE_BITS; b++)
        best = count[b] > best ? count[b] : best;
    for (unsigned b = 0; b < EMM_SIDE_BITS; b++)
        top |= (count[b] == best) << b;
    /* Of those, the lowest side of the most recent move that has one. */
    for (uint32_t k = 1; k <= q->len && !side; k++) {
        unsigned mv = q->move[q->pos >= k ? q->pos - k : q->pos + q->cap - k] & top;
        side = mv & -mv;
    }
    if (!side)
        return;
    const uint32_t *nb;
    const uint8_t *sides;
    uint32_t n = emm_layout_neighbors(l, to, &nb, &sides);
    for (uint32_t i = 0; i < n; i++)
        if (sides[i] & side)
            emm_fetcher_prefetch(f, nb[i], to);
}

const struct emm_fetch_ops emm_fetch_extrapolated_ops = {sizeof(struct fifo), reset, enter};
