/* The grid layout (thesis §4.1.1): equal rectangles over the bounding box,
 * about CELL triangles each on average, numbered row-major from the
 * bottom-left; up to 8 neighbours. The rows machinery is layout_rows.c. */
#include "layout_internal.h"

static emm_status build(emm_layout *l, const double *const *c, const char *name, emm_error *err)
{
    return emm_rows_build(l, c, 0, name, err);
}

const struct emm_layout_ops emm_layout_grid_ops = {
    .dims = 2,
    .build = build,
    .move_side = emm_rows_move_side,
    .cell_at = emm_rows_cell_at,
    .per_axis = emm_rows_per_axis,
};
