/* emm — EMM mesh layouts (thesis §4.1; docs/layouts.md).
 *
 * A layout splits a triangle mesh into cells. A cell holds the triangles
 * whose centroids fall in it and a copy of every vertex of those triangles,
 * so each cell is a self-contained sub-mesh that one DMA moves. Every
 * triangle gets one layout index (cell, position); every vertex gets one
 * copy in each cell that holds one of its triangles.
 *
 * - Grid (§4.1.1): equal rectangles over the bounding box, numbered
 *   row-major from the bottom-left; up to 8 neighbours.
 * - Interleaving tiles (§4.1.2): rows of equal rectangles, every odd row
 *   shifted by half a tile, so a tile touches 2 tiles in its row, 2 above
 *   and 2 below; up to 6 neighbours.
 * - Adaptive quadtree (§4.1.3): square leaves over the bounding square,
 *   at most `cell` triangles per leaf, leaves that touch (by an edge or a
 *   corner) differ by at most 3 levels; cells in leaf (Morton) order.
 *
 * and in space, for a mesh with depth (docs/layouts.md, "Layouts in space"):
 *
 * - 3D grid (grid3d): equal boxes over the bounding box, sized so the boxes
 *   holding triangles hold CELL on average; up to 26 neighbours.
 * - 3D interleaving tiles (tiles3d): layers of interleaving tiles, odd
 *   layers offset by half a row and a quarter box; up to 14 neighbours.
 * - Adaptive octree: cube leaves, at most `cell` triangles per leaf, leaves
 *   that share a face differ by at most 1 level.
 *
 * Geometry is in the layout's own space, whose dimension each kind of layout
 * declares: the three in the plane lay a mesh out over the two axes along
 * which its bounding box is largest (x and y for a planar mesh); those in
 * space use x, y and z. Every coordinate, side and path of
 * this interface is written for up to EMM_MAX_DIMS axes (emm_layout_axes
 * says how many a layout uses). The remote "image" packs the cells one
 * after the other in cell order; each cell is a 12-byte header (the thesis'
 * struct CellData: verNr, triNr, length), its vertex records, then its
 * triangle records. docs/layouts.md explains every choice. */
#ifndef EMM_LAYOUT_H
#define EMM_LAYOUT_H

#include "emm/common.h"
#include "emm/strategy.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct emm_layout emm_layout;

/* Bytes of a cell's header: struct CellData {int verNr, triNr, length;}. */
#define EMM_LAYOUT_HEADER_BYTES 12u
/* Bytes of a pointer on the thesis' 32-bit core (the default word.bytes):
 * a cell's triangle keeps 3 of them, to its vertices' copies (§4.1.1). */
#define EMM_LAYOUT_POINTER_BYTES 4u
/* Deepest quadtree level. Centroids that still share a leaf there (closer
 * than 2^-24 of the bounding square) stay together, even beyond `cell`. */
#define EMM_LAYOUT_MAX_DEPTH 24u
/* Largest depth difference between quadtree leaves that touch (§4.1.3). */
#define EMM_LAYOUT_MAX_LEVEL_GAP 3u
/* Deepest octree level (3 bits a level of a 64-bit Morton code), and the
 * largest depth difference between octree leaves that share a face (the
 * 2:1 rule). */
#define EMM_LAYOUT_OCTREE_MAX_DEPTH 21u
#define EMM_LAYOUT_OCTREE_LEVEL_GAP 1u
/* "No cell": a vertex that no triangle uses. */
#define EMM_LAYOUT_NONE UINT32_MAX

/* Relative positions of a cell seen from another, as bits: a grid's corner
 * neighbour is two sides at once. In the plane the bits follow the
 * thesis' numbering of the sides (§4.2.2: left 1, top 2, right 3, bottom
 * 4); a third axis adds near and far. EMM_SIDE_MINUS(a) and EMM_SIDE_PLUS(a)
 * are the sides below and above along axis a of the layout's space (top is
 * +y). */
enum {
    EMM_SIDE_LEFT = 1u << 0,
    EMM_SIDE_TOP = 1u << 1,
    EMM_SIDE_RIGHT = 1u << 2,
    EMM_SIDE_BOTTOM = 1u << 3,
    EMM_SIDE_NEAR = 1u << 4,
    EMM_SIDE_FAR = 1u << 5
};
#define EMM_SIDE_BITS (2 * EMM_MAX_DIMS)
#define EMM_SIDE_MINUS(axis) \
    ((axis) == 0 ? EMM_SIDE_LEFT : (axis) == 1 ? EMM_SIDE_BOTTOM : EMM_SIDE_NEAR)
#define EMM_SIDE_PLUS(axis) ((axis) == 0 ? EMM_SIDE_RIGHT : (axis) == 1 ? EMM_SIDE_TOP : EMM_SIDE_FAR)

typedef struct emm_layout_options {
    emm_layout_kind kind;    /* an EMM layout (ORIGINAL is a misuse) */
    uint32_t cell;           /* triangles per cell: the mean for grid and tiles,
                                the most per leaf for the quadtree and octree; >= 1 */
    uint32_t vertex_bytes;   /* bytes of a vertex record; 0 = 80 (thesis) */
    uint32_t triangle_bytes; /* bytes of a triangle record; 0 = 28 (thesis) */
    uint32_t pointer_bytes;  /* bytes of each of the 3 pointers a cell's triangle keeps to
                                its vertices' copies in the cell (thesis §4.1.1: the
                                layout's struct Triangle adds struct Vertex *vertices[3]);
                                the machine's word.bytes; 0 = EMM_LAYOUT_POINTER_BYTES */
    uint64_t local_store;    /* bytes; a larger cell is an error; 0 = no check */
    emm_fetch_kind fetch;    /* only to name a strategy in that error; NONE if unknown */
    uint32_t vertex_cells;   /* 1: the program keeps vertices only (no triangle array), and
                                the triangles given are its vertices, each (v, v, v): cells
                                of vertices, whose triangles take no bytes */
} emm_layout_options;

/* One cell. Coordinates are in the layout's space (emm_layout_axes); only
 * the first `dims` entries of each array are used. */
typedef struct emm_layout_cell {
    uint32_t ntri;                /* triangles */
    uint32_t nvert;               /* vertex copies */
    uint64_t bytes;               /* header + nvert * vertex_bytes +
                                     ntri * emm_layout_triangle_slot_bytes */
    uint64_t offset;              /* byte offset of the cell in the remote image */
    double lo[EMM_MAX_DIMS];      /* the cell's box (tiles at a row's ends reach */
    double hi[EMM_MAX_DIMS];      /* half a tile past the bounding box) */
    int32_t coord[EMM_MAX_DIMS];  /* grid and tiles: position in the cell array along
                                     each axis (column, row); -1 for a tree layout */
    uint32_t depth;               /* quadtree, octree: the leaf's depth (root 0); 0 otherwise */
    uint64_t path;                /* quadtree, octree: child indices from the root, `dims` bits
                                     per level, the root's child in the highest group
                                     used; bit a of a child index: the upper half along
                                     axis a (in the plane: 0 lower-left, 1 lower-right,
                                     2 upper-left, 3 upper-right, thesis Fig. 4.7) */
} emm_layout_cell;

/* A layout index: cell and position in the cell. */
typedef struct emm_layout_index {
    uint32_t cell;
    uint32_t pos;
} emm_layout_index;

typedef struct emm_layout_stats {
    uint32_t cells;
    uint32_t empty_cells;              /* cells without triangles */
    uint32_t dropped_cells;            /* layouts in space: boxes or octants without
                                          triangles, which are no cells */
    uint32_t tri_min, tri_median, tri_max;
    uint64_t bytes_min, bytes_median, bytes_max;
    uint64_t vertex_copies;            /* sum of the cells' nvert */
    uint64_t duplicated_vertices;      /* vertex_copies - vertices used by triangles */
    uint64_t unused_vertices;          /* vertices no triangle uses */
    uint64_t image_bytes;              /* emm_layout_image_bytes */
    uint64_t lookup_bytes;             /* emm_layout_lookup_bytes */
    uint32_t triangle_slot_bytes;      /* emm_layout_triangle_slot_bytes */
    uint32_t depth_min, depth_max;     /* quadtree or octree leaves; 0 otherwise */
    uint32_t quadtree_nodes;           /* internal nodes + leaves of the quadtree or
                                          octree; 0 otherwise */
    uint32_t overfull_leaves;          /* tree leaves above `cell` (max depth only) */
} emm_layout_stats;

/* Builds a layout of the mesh given by `xyz` (3 doubles per vertex, nv
 * vertices) and `tri` (3 vertex indices per triangle, nt triangles); the
 * caller keeps owning both. `name` (may be NULL) names the input in error
 * messages. On success *out owns a new layout (emm_layout_free). Errors:
 * EMM_ERR_INVALID for no triangles or cell 0; EMM_ERR_MESH for an index
 * out of range or a non-finite coordinate; EMM_ERR_RANGE for a cell larger
 * than opt->local_store (the message names the cell, its bytes and a CELL
 * to use instead) or a mesh too large for 32-bit ids; EMM_ERR_NOMEM. */
EMM_API emm_status emm_layout_build(const double *xyz, size_t nv, const int32_t *tri, size_t nt,
                                    const emm_layout_options *opt, const char *name,
                                    emm_layout **out, emm_error *err);
/* Frees a layout; NULL is allowed. */
EMM_API void emm_layout_free(emm_layout *l);

/* The options the layout was built with (record sizes filled in). */
EMM_API const emm_layout_options *emm_layout_get_options(const emm_layout *l);
EMM_API uint32_t emm_layout_cell_count(const emm_layout *l);
EMM_API size_t emm_layout_triangle_count(const emm_layout *l);
EMM_API size_t emm_layout_vertex_count(const emm_layout *l);
/* The coordinate axes (0 x, 1 y, 2 z) the layout works in, ascending, and
 * the bounding box of the triangles' vertices in that space; returns how
 * many axes (the layout's dims). Any pointer may be NULL. */
EMM_API uint32_t emm_layout_axes(const emm_layout *l, int axes[EMM_MAX_DIMS],
                                 double lo[EMM_MAX_DIMS], double hi[EMM_MAX_DIMS]);
/* Grids and tiles: the cell array's extent along each axis (columns — for
 * tiles, of the even rows; odd rows have one more — then rows); returns the
 * layout's dims (3D: then layers). A tree layout has no array: returns 0. */
EMM_API uint32_t emm_layout_cells_per_axis(const emm_layout *l, uint32_t n[EMM_MAX_DIMS]);

/* Cell c (< emm_layout_cell_count). The pointer lives as long as l. */
EMM_API const emm_layout_cell *emm_layout_cell_get(const emm_layout *l, uint32_t c);
/* The triangles of cell c in position order (ascending triangle id);
 * returns their count. */
EMM_API uint32_t emm_layout_cell_triangles(const emm_layout *l, uint32_t c, const uint32_t **tris);
/* The vertices of cell c in position order (order of first use by the
 * cell's triangles); returns their count. */
EMM_API uint32_t emm_layout_cell_vertices(const emm_layout *l, uint32_t c, const uint32_t **verts);
/* The cells that touch cell c (by an edge or a corner), ascending, and for
 * each the EMM_SIDE_* bits of where it lies seen from c. Returns the count;
 * sides may be NULL. */
EMM_API uint32_t emm_layout_neighbors(const emm_layout *l, uint32_t c, const uint32_t **cells,
                                      const uint8_t **sides);
/* The ring of cell c, which the fetch schemes prefetch from (docs/fetch.md):
 * in the plane, its neighbours (emm_layout_neighbors); in space, those of
 * its neighbours that hold a copy of one of c's vertices, the cells the
 * surface continues into from c. Same order and sides as the neighbours;
 * returns the count. */
EMM_API uint32_t emm_layout_ring(const emm_layout *l, uint32_t c, const uint32_t **cells,
                                 const uint8_t **sides);
/* EMM_SIDE_* bits of where cell `to` lies seen from cell `from` (any two
 * cells; 0 when from == to). For neighbours it equals their entry in
 * emm_layout_neighbors. Grid and tiles compare cell centres; the quadtree
 * compares leaf squares (a side bit when `to` lies wholly beyond that edge). */
EMM_API unsigned emm_layout_move_side(const emm_layout *l, uint32_t from, uint32_t to);
/* The cell containing point p (the layout's dims coordinates, clamped into
 * the bounding box), by arithmetic for grid and tiles and by descending the
 * quadtree; *levels (may be NULL) gets the levels descended (0 for grid
 * and tiles). A layout in space has no cells where the mesh has no
 * triangles: EMM_LAYOUT_NONE for a point in such a box or octant. */
EMM_API uint32_t emm_layout_cell_at(const emm_layout *l, const double *p, uint32_t *levels);

/* Triangle t's layout index. */
EMM_API emm_layout_index emm_layout_triangle_index(const emm_layout *l, uint32_t t);
/* The triangle at (cell, pos). */
EMM_API uint32_t emm_layout_triangle_at(const emm_layout *l, uint32_t cell, uint32_t pos);
/* Vertex v's copies, by ascending cell; returns their count (0 for a vertex
 * no triangle uses). */
EMM_API uint32_t emm_layout_vertex_copies(const emm_layout *l, uint32_t v,
                                          const emm_layout_index **copies);
/* Vertex v's home copy: the one in the lowest-numbered cell; cell is
 * EMM_LAYOUT_NONE for an unused vertex. */
EMM_API emm_layout_index emm_layout_vertex_home(const emm_layout *l, uint32_t v);
/* Vertex v's copy as seen from `cell` (the copy in that cell if it has one,
 * else the home copy). */
EMM_API emm_layout_index emm_layout_vertex_index(const emm_layout *l, uint32_t v, uint32_t cell);
/* The vertex at (cell, pos). */
EMM_API uint32_t emm_layout_vertex_at(const emm_layout *l, uint32_t cell, uint32_t pos);

/* Bytes of the remote image: all cells, then one record for each unused
 * vertex (in vertex order), so that every element has an address. */
EMM_API uint64_t emm_layout_image_bytes(const emm_layout *l);
/* Bytes a triangle takes in its cell: its record, then the 3 pointers to
 * its vertices' copies in the cell (triangle_bytes + 3 * pointer_bytes);
 * 0 for cells of vertices (vertex_cells), whose triangles take no bytes. */
EMM_API uint32_t emm_layout_triangle_slot_bytes(const emm_layout *l);
/* Address in the image of byte `offset` (< triangle_bytes) of triangle t's
 * record (the start of its slot). */
EMM_API uint64_t emm_layout_triangle_address(const emm_layout *l, uint32_t t, uint32_t offset);
/* Address in the image of byte `offset` (< vertex_bytes) of vertex v's copy
 * as seen from `from_cell` (EMM_LAYOUT_NONE: the home copy). */
EMM_API uint64_t emm_layout_vertex_address(const emm_layout *l, uint32_t v, uint32_t from_cell,
                                           uint32_t offset);

/* Bytes the EMM runtime keeps in the local store to use the layout:
 * 4 per triangle and 4 per vertex (id → layout index tables), 8 per cell
 * (its remote address and length), and for the quadtree and octree 16 per node. */
EMM_API uint64_t emm_layout_lookup_bytes(const emm_layout *l);

EMM_API void emm_layout_get_stats(const emm_layout *l, emm_layout_stats *out);

#ifdef __cplusplus
}
#endif
#endif
