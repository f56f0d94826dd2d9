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
    bool seen[LEAD_SWEEP_ARRAYS];     /* the array has been touched */
    uint64_t next[LEAD_SWEEP_ARRAYS]; /* the element its sweep touches next */
} lead_sweep;

/* One element access (consecutive accesses to one element already counted
 * once by the caller); returns how many element accesses enter the window:
 * 0 while the leading sweep lasts — element k, k+1, k+2, ... of its array,
 * the arrays possibly interleaved, at most EMM_PROFILE_SWEEP_MAX element
 * accesses — and 1 from the first that breaks it on; or 2 when the sweep
 * was a single access, which a sweep of one is not: it is given back to the
 * window with the access that broke it. An array joins the sweep at its
 * element 0, except the very first access, which may start it anywhere
 * (the fault capture misses the elements that share a page with other
 * data). */
static inline int lead_sweep_step(lead_sweep *s, uint32_t array, uint64_t element)
{
    if (s->over)
        return 1;
    if (array < LEAD_SWEEP_ARRAYS && s->elements < EMM_PROFILE_SWEEP_MAX &&
        (s->seen[array] ? element == s->next[array] : element == 0 || s->elements == 0)) {
        s->seen[array] = true;
        s->next[array] = element + 1;
        s->elements++;
        return 0;
    }
    s->over = true;
    if (s->elements == 1) {
        s->elements = 0;
        return 2;
    }
    return 1;
}

/* The session's window held nothing but a leading sweep (a converter that
 * reads its mesh once, in order): the sweep is the traversal, and the
 * profiler p, before its first record, leaves nothing out. */
void profiler_keep_sweep(emm_profiler *p);

#endif
