/* The leading index-order sweep (docs/profile.md "The leading sweep"): a
 * program that first walks its arrays in index order — reading the file,
 * initialising per-element data — shows its layout, not its traversal, so
 * the profile window opens at the first element access that breaks such a
 * sweep. One rule, used by the profiler (offline, on traces) and by the
 * session (online, while the window fills). */
#ifndef EMM_LEAD_SWEEP_H
#define EMM_LEAD_SWEEP_H

#include <stdbool.h>
#include <stdint.h>

#include "emm/profile.h"

enum { LEAD_SWEEP_ARRAYS = 64 };

typedef struct lead_sweep {
    bool over;
    uint64_t elements;                /* element accesses in the sweep */
    uint64_t next[LEAD_SWEEP_ARRAYS]; /* the element each array's sweep touches next */
} lead_sweep;

/* One element access (consecutive accesses to one element already counted
 * once by the caller): true while it continues the leading sweep — element
 * 0, 1, 2, ... of its array, the arrays possibly interleaved — for at most
 * EMM_PROFILE_SWEEP_MAX element accesses; false from the first that breaks
 * it on. */
static inline bool lead_sweep_step(lead_sweep *s, uint32_t array, uint64_t element)
{
    if (!s->over && array < LEAD_SWEEP_ARRAYS && element == s->next[array] &&
        s->elements < EMM_PROFILE_SWEEP_MAX) {
        s->next[array]++;
        s->elements++;
        return true;
    }
    s->over = true;
    return false;
}

#endif
