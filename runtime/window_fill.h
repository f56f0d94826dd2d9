/* A window that reads on until it has filled the local store (docs/profile.md
 * "The window"): a traversal whose first element accesses revisit a few
 * hundred records — a vertex of high valence whose fan is walked again and
 * again, a small front — leaves most of the local store empty, and a window
 * that never fills the store cannot show which cells the run will evict and
 * fetch again. Past its length, the window reads on while the distinct
 * records it has read are fewer bytes than the local store, up to
 * EMM_PROFILE_FILL_REACH times its length — unless the mesh fits the store,
 * which the run then never evicts. One rule, used by the profiler
 * (offline, on traces) and by the session (online, while the window fills). */
#ifndef EMM_WINDOW_FILL_H
#define EMM_WINDOW_FILL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct window_fill {
    uint64_t bytes;   /* the bytes to touch (the local store's); 0: the window is exact */
    uint64_t touched; /* bytes of the distinct records read so far */
    uint64_t *key;    /* the distinct (array, element) pairs, open addressing; 0: empty */
    size_t n, cap;
} window_fill;

/* Starts counting towards `bytes`, the local store's (0: none; the window
 * ends at its length); f is zeroed or was started before. */
void window_fill_start(window_fill *f, uint64_t bytes);
/* The mesh's records are `mesh_bytes`: a mesh that fits the local store is
 * never evicted, and its window ends at its length. */
void window_fill_size(window_fill *f, uint64_t mesh_bytes);
/* One element access of the window proper (the leading sweep left out): its
 * record, `record_bytes` long, counts once. Without memory for the set the
 * window stops reading on (it ends at its length, as without the rule). */
void window_fill_add(window_fill *f, uint32_t array, uint64_t element, uint64_t record_bytes);
/* Whether a window of `window` element accesses that has read n of them is
 * complete. */
bool window_fill_done(const window_fill *f, uint64_t window, uint64_t n);
/* Whether the window read on past its length (n of them) and why it stopped:
 * the store filled, or the reach. */
bool window_fill_filled(const window_fill *f);
void window_fill_free(window_fill *f);

#endif
