/* The 3D interleaving-tiles layout: the tiles of the plane (thesis §4.1.2)
 * carried up one axis. Each layer is a plane of interleaving tiles (odd
 * rows shifted by half a box); odd layers are moved by half a row and a
 * quarter box, so a box touches 2 boxes in its row, 4 in the neighbouring
 * rows and 4 in each neighbouring layer: up to 14 neighbours against the
 * 3D grid's 26, which is what convolution prefetching loads. The boxes
 * machinery is layout_boxes.c; docs/layouts.md counts the neighbours. */
#include "layout_internal.h"

static emm_status build(emm_layout *l, const double *const *c, const char *name, emm_error *err)
{
    return emm_boxes_build(l, c, 1, name, err);
}

const struct emm_layout_ops emm_layout_tiles3d_ops = {
    .dims = 3,
    .build = build,
    .move_side = emm_boxes_move_side,
    .cell_at = emm_boxes_cell_at,
    .per_axis = emm_boxes_per_axis,
    .destroy = emm_boxes_destroy,
};
