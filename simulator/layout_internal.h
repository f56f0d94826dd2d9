/* Internal to the layouts (runtime/layout.c, runtime/layout_quadtree.c):
 * the layout object and the quadtree's build, neighbour and look-up
 * helpers. */
#ifndef EMM_INTERNAL_LAYOUT_H
#define EMM_INTERNAL_LAYOUT_H

#include "emm/layout.h"

/* A quadtree node. (ix, iy) is the node's square at its own depth: it
 * spans [ix, ix + 1) * 2^-depth of the bounding square in each axis. */
typedef struct emm_qt_node {
    uint32_t ix, iy;
    uint32_t depth;
    int32_t child;  /* index of the first of 4 consecutive children; -1 for a leaf */
    uint32_t first; /* the node's triangles: [first, first + count) of the Morton order */
    uint32_t count;
    uint32_t cell;  /* leaf: its cell */
    uint64_t path;  /* child indices from the root, 2 bits per level */
} emm_qt_node;

struct emm_layout {
    emm_layout_options opt;
    size_t nv, nt;
    int axes[2];
    double lo[2], hi[2];

    /* grid and tiles */
    uint32_t cols, rows;
    double cw, ch; /* a cell's width and height */

    /* quadtree */
    emm_qt_node *nodes;
    uint32_t nnodes;
    uint32_t *leaf_node;  /* ncells: each cell's leaf */
    double qlo[2], qside; /* the bounding square */
    uint32_t overfull;

    uint32_t ncells;
    emm_layout_cell *cells;
    uint32_t *tri_cell;        /* nt */
    uint32_t *tri_pos;         /* nt */
    uint32_t *cell_tri_start;  /* ncells + 1 */
    uint32_t *cell_tris;       /* nt */
    uint32_t *cell_vert_start; /* ncells + 1 */
    uint32_t *cell_verts;      /* vertex copies */
    uint32_t *vcopy_start;     /* nv + 1 */
    emm_layout_index *vcopy;   /* vertex copies, by vertex, then cell */
    uint32_t *unused_rank;     /* nv, or NULL when every vertex is used */
    uint64_t nunused;
    uint64_t ncopies;
    uint64_t cells_bytes;
    uint32_t *nb_start;        /* ncells + 1 */
    uint32_t *nb;
    uint8_t *nb_side;
};

/* Builds the quadtree over the triangles' centroids (cx, cy in the layout
 * plane), balances it, numbers its leaves as cells (filling l->ncells,
 * l->cells' geometry fields, l->tri_cell) and its neighbour lists. */
emm_status emm_layout_quadtree_build(emm_layout *l, const double *cx, const double *cy,
                                     const char *name, emm_error *err);
/* The leaf containing quantised point (qx, qy) at EMM_LAYOUT_MAX_DEPTH. */
uint32_t emm_layout_quadtree_cell_at(const emm_layout *l, uint32_t qx, uint32_t qy,
                                     uint32_t *levels);
/* Quantises a coordinate of the layout plane onto the quadtree's finest
 * level (clamped). */
uint32_t emm_layout_quadtree_quantise(const emm_layout *l, int axis, double v);

#endif
