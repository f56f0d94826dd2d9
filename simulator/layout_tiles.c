/* The interleaving-tiles layout (thesis §4.1.2): rows of equal rectangles,
 * every odd row shifted by half a tile, so a tile touches 2 tiles in its
 * row, 2 above and 2 below; up to 6 neighbours, which is what convolution
 * prefetching (§4.2.1) loads. The rows machinery is layout_rows.c. */
#include "layout_internal.h"

static emm_status build(emm_layout *l, const double *const *c, const char *name, emm_error *err)
{
    return emm_rows_build(l, c, 1, name, err);
}

const struct emm_layout_ops emm_layout_tiles_ops = {
    .dims = 2,
    .build = build,
    .move_side = emm_rows_move_side,
    .cell_at = emm_rows_cell_at,
    .per_axis = emm_rows_per_axis,
};
