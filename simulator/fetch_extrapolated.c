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
    uint64_t counts;        /* how many moves in the FIFO have each side: 8 bits a side */
};

#define SIDES ((1u << EMM_SIDE_BITS) - 1u)

/* A move's sides as counts of one in counts' lanes: the product puts a
 * copy of the move's bits at every 7th bit, so bit b of the copy shifted
 * by 7b lands on bit 8b, and no copy overlaps the next (the bits are fewer
 * than 7). */
_Static_assert(EMM_SIDE_BITS <= 7, "a move's side bits spread by one product");
static uint64_t spread(unsigned mv)
{
    uint64_t copies = 0, lanes = 0;
    for (unsigned b = 0; b < EMM_SIDE_BITS; b++) {
        copies |= 1ull << (7 * b);
        lanes |= 1ull << (8 * b);
    }
    return ((uint64_t)mv * copies) & lanes;
}

static void reset(void *state, const emm_machine_params *p)
{
    struct fifo *q = state;
    q->cap = p->emm_fifo >= 1 && p->emm_fifo <= MAX_FIFO ? (uint32_t)p->emm_fifo : 4;
}

static void enter(emm_fetcher *f, void *state, uint32_t from, uint32_t to)
{
    struct fifo *q = state;
    const emm_layout *l = emm_fetcher_layout(f);
    unsigned best = 0, side = 0, top = 0;
    if (from == EMM_LAYOUT_NONE)
        return;
    /* The FIFO's side counts follow it: the move that leaves, out; the new
     * one, in. */
    unsigned mv = (unsigned)emm_layout_move_side(l, from, to) & SIDES;
    if (q->len == q->cap)
        q->counts -= spread(q->move[q->pos]);
    else
        q->len++;
    q->move[q->pos] = (uint8_t)mv;
    q->counts += spread(mv);
    if (++q->pos == q->cap)
        q->pos = 0;
    emm_fetcher_instructions(f, emm_fetcher_params(f)->emm_predict);
    /* The most moves to one side, and the sides that have that many. */
    for (unsigned b = 0; b < EMM_SIDE_BITS; b++) {
        unsigned c = (unsigned)(q->counts >> (8 * b)) & 0xffu;
        best = c > best ? c : best;
    }
    for (unsigned b = 0; b < EMM_SIDE_BITS; b++)
        top |= (((unsigned)(q->counts >> (8 * b)) & 0xffu) == best) << b;
    /* Of those, the lowest side of the most recent move that has one. */
    for (uint32_t k = 1; k <= q->len && !side; k++) {
        unsigned m = q->move[q->pos >= k ? q->pos - k : q->pos + q->cap - k] & top;
        side = m & -m;
    }
    if (!side)
        return;
    const uint32_t *nb;
    const uint8_t *sides;
    uint32_t n = emm_layout_ring(l, to, &nb, &sides);
    for (uint32_t i = 0; i < n; i++)
        if (sides[i] & side)
            emm_fetcher_prefetch(f, nb[i], to);
}

const struct emm_fetch_ops emm_fetch_extrapolated_ops = {sizeof(struct fifo), reset, enter};
