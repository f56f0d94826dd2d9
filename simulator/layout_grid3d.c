/* The 3D grid layout: equal boxes over the mesh's bounding box in space,
 * sized so that the boxes holding triangles hold CELL on average, numbered
 * layer by layer, row by row from the low corner; up to 26 neighbours. For a
 * mesh with depth, whose front and back a grid in the plane would put in
 * the same cells. The boxes machinery is layout_boxes.c. */
#include "layout_internal.h"

static emm_status build(emm_layout *l, const double *const *c, const char *name, emm_error *err)
{
    return emm_boxes_build(l, c, 0, name, err);
}

const struct emm_layout_ops emm_layout_grid3d_ops = {
    .dims = 3,
    .build = build,
    .move_side = emm_boxes_move_side,
    .cell_at = emm_boxes_cell_at,
    .per_axis = emm_boxes_per_axis,
    .destroy = emm_boxes_destroy,
};
