/* Internal to the layouts (simulator/layout*.c): the layout object and the
 * ops table each kind of layout fills (docs/architecture.md, "Adding a
 * part"). layout.c holds what every layout shares — validation, the
 * layout's space, centroids, triangles and vertex copies per cell, sizes,
 * the image, the public queries — and dispatches to the kind's ops for what
 * differs: its dimension, how cells are cut, neighbours, relative sides,
 * point location. */
#ifndef EMM_INTERNAL_LAYOUT_H
#define EMM_INTERNAL_LAYOUT_H

#include "emm/layout.h"

struct emm_layout_ops {
    /* The axes of the layout's space, 2 to EMM_MAX_DIMS: 2 lays a mesh out
     * over the two axes along which its bounding box is largest (x and y
     * for a planar mesh), 3 over x, y and z. layout.c sets l->dims, l->axes
     * and the bounding box l->lo, l->hi from it before build. */
    uint32_t dims;
    /* Cuts the cells from the triangles' centroids (c[a][t]: coordinate a
     * of triangle t's centroid in the layout's space, a < l->dims): fills
     * l->ncells, l->cells' geometry (lo, hi, coord, depth, path),
     * l->tri_cell and the neighbour lists (l->nb_start, l->nb, l->nb_side),
     * and l->priv. */
    emm_status (*build)(emm_layout *l, const double *const *c, const char *name, emm_error *err);
    /* EMM_SIDE_* bits of where `to` lies seen from `from`, over the
     * layout's dims axes (EMM_SIDE_MINUS(a), EMM_SIDE_PLUS(a)). */
    unsigned (*move_side)(const emm_layout *l, uint32_t from, uint32_t to);
    /* The cell holding point p (dims coordinates, clamped); *levels: tree
     * levels descended. */
    uint32_t (*cell_at)(const emm_layout *l, const double *p, uint32_t *levels);
    /* Cells along each axis of a regular array, or 0 (NULL: 0). */
    uint32_t (*per_axis)(const emm_layout *l, uint32_t n[EMM_MAX_DIMS]);
    /* Bytes of the kind's own look-up tables in the local store, beyond the
     * id tables every layout has (NULL: none). */
    uint64_t (*lookup_bytes)(const emm_layout *l);
    /* The tree nodes a look-up of cell c reads on its way down, root
     * first: their indices in the kind's look-up table (lookup_bytes, 16
     * bytes a node), at most EMM_LAYOUT_MAX_DEPTH + 1 of them; returns how
     * many (NULL: no tree, nothing read). */
    uint32_t (*path_nodes)(const emm_layout *l, uint32_t c, uint32_t *nodes);
    /* The kind's own statistics (NULL: none). */
    void (*stats)(const emm_layout *l, emm_layout_stats *out);
    /* Frees l->priv (NULL: free()). */
    void (*destroy)(emm_layout *l);
    /* Nonzero when CELL bounds the triangles of every cell (a tree that
     * splits until it does); used to suggest a layout in messages. */
    int bounded;
    /* Nonzero: the cells build cuts that hold no triangle are dropped
     * (layout.c, drop_empty; the octree's — the boxes of grid3d and tiles3d
     * make cells of the boxes that hold triangles only, themselves): in
     * space a surface meets few of the boxes or
     * octants that fill its bounding box, and an empty cell would still
     * take a header in the image, an entry in every per-cell table and
     * state in every model. The kind's own data keeps its numbering (its
     * "raw" cells): cell_at gives a raw cell, which layout.c translates;
     * move_side takes the layout's cells and reads their geometry
     * (l->cells), never the kind's per-raw-cell data. */
    int compact;
};

/* One table per kind, named from EMM_LAYOUT_LIST: emm_layout_grid_ops, ... */
#define EMM_LAYOUT_OPS_DECL_(e, n, d, w) extern const struct emm_layout_ops emm_layout_##n##_ops;
EMM_LAYOUT_LIST(EMM_LAYOUT_OPS_DECL_)
#undef EMM_LAYOUT_OPS_DECL_

struct emm_layout {
    emm_layout_options opt;
    const struct emm_layout_ops *ops;
    size_t nv, nt;
    uint32_t dims;                    /* axes of the layout's space: ops->dims */
    int axes[EMM_MAX_DIMS];
    double lo[EMM_MAX_DIMS], hi[EMM_MAX_DIMS];
    void *priv;                       /* the kind's own data */

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
    /* Layouts in space: the neighbours that share a vertex with the cell
     * (emm_layout_ring), with their sides; NULL in the plane, where the
     * ring is the neighbour list */
    uint32_t *ring_start;      /* ncells + 1 */
    uint32_t *ring;
    uint8_t *ring_side;
    /* Layouts in space: the boxes or leaves cut (nraw), of which the
     * ncells that hold triangles are cells (0 in the plane); with
     * ops->compact, cell_of maps the kind's own numbers to cells (the boxes
     * number their cells themselves) */
    uint32_t nraw;
    uint32_t *cell_of;         /* nraw: the cell of each of the kind's, or EMM_LAYOUT_NONE */
};

/* What every layout of one mesh starts from, found once: the geometry
 * checked (finite coordinates, vertex ids in range), the bounding box of the
 * vertices triangles use, and each triangle's centroid on every axis. A
 * share (share.h) keeps one for all the layouts of a trace, which cut the
 * same triangles by kind and cell size. It refers to tri (3 vertex ids a
 * triangle), which must outlive it; xyz is read by init only. */
typedef struct emm_layout_geometry {
    const int32_t *tri;
    size_t nv, nt;
    double lo[3], hi[3];
    double *centroid[3]; /* nt each */
} emm_layout_geometry;

/* Checks the geometry and fills g; on failure (an invalid mesh, memory) g
 * holds nothing to free. */
emm_status emm_layout_geometry_init(emm_layout_geometry *g, const double *xyz, size_t nv,
                                    const int32_t *tri, size_t nt, const char *name,
                                    emm_error *err);
void emm_layout_geometry_free(emm_layout_geometry *g);
/* The options' one check that needs no geometry: a CELL of at least 1. */
emm_status emm_layout_check_cell(const emm_layout_options *opt, const char *name, emm_error *err);
/* emm_layout_build over a checked geometry. */
emm_status emm_layout_build_from(const emm_layout_geometry *g, const emm_layout_options *opt,
                                 const char *name, emm_layout **out, emm_error *err);

/* A CELL for l's kind whose every cell fits `local` bytes: cell bytes grow
 * about linearly with CELL, which gives a first guess, and the guess is
 * halved until a build of it fits (largest grid cells do not shrink exactly
 * in proportion); *suggest 0 when none does. The geometry is l's. Fails
 * only when a trial build does. */
emm_status emm_layout_fit_cell(const emm_layout_geometry *g, const emm_layout *l, uint64_t local,
                               uint32_t *suggest, const char *name, emm_error *err);
/* The error for l's largest cell exceeding `local` bytes, naming `suggest`
 * (emm_layout_fit_cell) with `fetch` as the strategy to use instead. */
emm_status emm_layout_too_large(const emm_layout *l, emm_fetch_kind fetch, uint64_t local,
                                uint32_t suggest, const char *name, emm_error *err);

/* "NAME: out of memory building the layout". */
emm_status emm_layout_nomem(emm_error *err, const char *name);
/* Fills l->nb_side from the kind's move_side, for lists already in l->nb. */
emm_status emm_layout_fill_sides(emm_layout *l, const char *name, emm_error *err);

/* Rows of equal boxes in the plane (dims 2), shared by the grid and the
 * interleaving tiles (layout_rows.c): `shift` nonzero shifts odd rows by
 * half a cell. */
emm_status emm_rows_build(emm_layout *l, const double *const *c, int shift, const char *name,
                          emm_error *err);
unsigned emm_rows_move_side(const emm_layout *l, uint32_t from, uint32_t to);
uint32_t emm_rows_cell_at(const emm_layout *l, const double *p, uint32_t *levels);
uint32_t emm_rows_per_axis(const emm_layout *l, uint32_t n[EMM_MAX_DIMS]);

/* Layers of rows of equal boxes in space (dims 3), shared by the 3D grid
 * and the 3D interleaving tiles (layout_boxes.c): `shift` nonzero offsets
 * odd rows and odd layers so a box has 14 neighbours instead of 26. */
emm_status emm_boxes_build(emm_layout *l, const double *const *c, int shift, const char *name,
                           emm_error *err);
unsigned emm_boxes_move_side(const emm_layout *l, uint32_t from, uint32_t to);
uint32_t emm_boxes_cell_at(const emm_layout *l, const double *p, uint32_t *levels);
uint32_t emm_boxes_per_axis(const emm_layout *l, uint32_t n[EMM_MAX_DIMS]);
void emm_boxes_destroy(emm_layout *l);

#endif
