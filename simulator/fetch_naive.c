/* Naive fetching (thesis §4.2): a cell is fetched when the program first
 * touches it, and the core waits for it. Nothing is prefetched. */
#include "fetch_scheme.h"

const struct emm_fetch_ops emm_fetch_naive_ops = {0, NULL, NULL};
