/* emm — strategy strings (docs/design.md "Strategies"), one parser used
 * everywhere: environment, command line, tables, reports.
 *
 *   direct                      word-by-word remote reads
 *   cache[@LAYOUT]              the hardware cache, on the original or a reordered layout
 *   LAYOUT+FETCH[@CELL][:indexed]
 *                               an EMM strategy, CELL = triangles per cell;
 *                               :indexed, as if the program used the layout's
 *                               numbering (no per-element look-up table)
 *   LAYOUT = grid | tiles | quadtree            (in the plane)
 *          | grid3d | tiles3d | octree          (in space, for a mesh with depth)
 *   FETCH = naive | convolution | extrapolated
 */
#ifndef EMM_STRATEGY_H
#define EMM_STRATEGY_H

#include "emm/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum emm_strategy_kind {
    EMM_STRATEGY_DIRECT = 0,
    EMM_STRATEGY_CACHE,
    EMM_STRATEGY_EMM
} emm_strategy_kind;

/* The EMM layouts (thesis §4.1) and fetch schemes (§4.2), one entry each:
 * X(ENUM, name, words) gives the value EMM_LAYOUT_ENUM or EMM_FETCH_ENUM,
 * the name strategy strings use and what it does, in words for a summary;
 * a layout's entry also gives, before its words, the axes of its space (2:
 * the plane of the mesh's two largest extents; 3: space, tried only for a
 * mesh with depth, emm_geometry_has_depth). Adding a layout or a fetch
 * scheme is a line here, its ops file in simulator/ (layout_NAME.c,
 * fetch_NAME.c) and its documentation (docs/architecture.md, "Adding a
 * part"): the enums, the names, the parser, the standard sweep and the
 * simulator's tables of ops all follow these lists. Each list ends in a
 * comment line, so that a new last entry is one added line, ending in a
 * backslash like the others. */
#define EMM_LAYOUT_LIST(X)                                                                  \
    X(GRID, grid, 2, "a uniform grid of cells over the mesh's plane")                       \
    X(TILES, tiles, 2, "tiles: cells cut to hold about equal numbers of triangles")         \
    X(QUADTREE, quadtree, 2, "quadtree leaves: cells split where the mesh is dense")        \
    X(GRID3D, grid3d, 3, "a uniform 3D grid of boxes over the mesh's bounding box")         \
    X(TILES3D, tiles3d, 3, "3D interleaving tiles: offset layers of boxes, 14 neighbours")  \
    X(OCTREE, octree, 3, "octree leaves: boxes split where the mesh is dense")              \
    /* (the end of the layouts) */
#define EMM_FETCH_LIST(X)                                                                   \
    X(NAIVE, naive, "fetch a cell when the program needs it, and wait")                     \
    X(CONVOLUTION, convolution, "on entering a cell, prefetch its neighbours")              \
    X(EXTRAPOLATED, extrapolated, "prefetch the neighbour the recent moves point to")       \
    /* (the end of the fetch schemes) */

#define EMM_LAYOUT_ENUM_(e, n, d, w) EMM_LAYOUT_##e,
#define EMM_FETCH_ENUM_(e, n, w) EMM_FETCH_##e,

typedef enum emm_layout_kind {
    EMM_LAYOUT_ORIGINAL = 0, /* the program's own arrays (cache only) */
    EMM_LAYOUT_LIST(EMM_LAYOUT_ENUM_)
    EMM_LAYOUT_COUNT         /* the EMM layouts are 1 .. EMM_LAYOUT_COUNT - 1 */
} emm_layout_kind;

typedef enum emm_fetch_kind {
    EMM_FETCH_NONE = 0, /* direct and cache */
    EMM_FETCH_LIST(EMM_FETCH_ENUM_)
    EMM_FETCH_COUNT     /* the fetch schemes are 1 .. EMM_FETCH_COUNT - 1 */
} emm_fetch_kind;

#undef EMM_LAYOUT_ENUM_
#undef EMM_FETCH_ENUM_

/* Triangles per cell when an EMM strategy or cache@LAYOUT string gives no
 * @CELL. */
#define EMM_DEFAULT_CELL 64u
/* Largest accepted CELL. */
#define EMM_MAX_CELL 1048576u

typedef struct emm_strategy {
    emm_strategy_kind kind;
    emm_layout_kind layout; /* ORIGINAL for direct and plain cache */
    emm_fetch_kind fetch;   /* NONE unless kind == EMM_STRATEGY_EMM */
    uint32_t cell;          /* triangles per cell; 0 for direct and plain cache */
    uint32_t indexed;       /* EMM only, 1: the ":indexed" variant — the program adopts the
                               layout's numbering (emm layout --write), so the per-element
                               look-up table gives way to a per-cell table (docs/layouts.md,
                               "The indexed variant"); 0 otherwise */
} emm_strategy;

/* The suffix of an indexed variant, and its bytes per cell in the local
 * store: the cell's first renumbered triangle and vertex (4 bytes each) and
 * the cell's place and residency (8), the table a renumbered id's cell is
 * found in. */
#define EMM_INDEXED_SUFFIX ":indexed"
#define EMM_INDEXED_CELL_BYTES 16u

/* Parses a strategy string. On failure err names the string, the bad part
 * and the accepted values. */
EMM_API emm_status emm_strategy_parse(const char *text, emm_strategy *out, emm_error *err);

/* Writes the canonical string of s into buf (always NUL-terminated when
 * cap > 0); returns the length it needed, as snprintf does. */
EMM_API size_t emm_strategy_format(const emm_strategy *s, char *buf, size_t cap);

/* What s is, in words: "tiles (tiles: cells cut to hold about equal numbers
 * of triangles), naive fetching (fetch a cell when ...), 16 triangles per
 * cell"; "direct reads of remote memory, word by word"; "the hardware
 * cache". Returns the length needed, as snprintf does. */
EMM_API size_t emm_strategy_words(const emm_strategy *s, char *buf, size_t cap);

EMM_API const char *emm_layout_name(emm_layout_kind k);
EMM_API const char *emm_fetch_name(emm_fetch_kind k);

/* The standard sweep: every layout in the plane × every fetch scheme × the
 * sweep's cell sizes (emm_strategy_sweep_cells), then direct, cache and
 * cache@ each of those layouts. Fills up to cap entries (out may be NULL
 * when cap is 0) and returns the sweep's full length. */
EMM_API size_t emm_strategy_sweep(emm_strategy *out, size_t cap);
/* The indexed variant of every EMM strategy of emm_strategy_sweep_for(depth),
 * in the sweep's order (`emm replay --all --indexed`, and the run's contest
 * on a mesh whose look-up tables do not fit emm.lookup_budget). Returns
 * their count, filling up to cap. */
EMM_API size_t emm_strategy_sweep_indexed(int depth, emm_strategy *out, size_t cap);
/* Whether the indexed variants join the run's contest (and emm profile's)
 * on a mesh of nv vertices and nt triangles: when its per-element look-up
 * tables, 4 bytes a vertex and a triangle, exceed emm.lookup_budget
 * (`lookup_budget`), so that they are paged and renumbering saves their
 * pages. A smaller mesh keeps the contest of the standard sweep. */
EMM_API int emm_indexed_joins_contest(size_t nv, size_t nt, uint64_t lookup_budget);
/* The sweep for a mesh: with `depth` zero the standard sweep, exactly;
 * nonzero, the layouts in space join it (each after those in the plane, in
 * both the EMM strategies and the cache@ ones). */
EMM_API size_t emm_strategy_sweep_for(int depth, emm_strategy *out, size_t cap);
/* The axes of a layout's space: 2 (in the plane) or 3 (in space); 0 for
 * the original layout. */
EMM_API uint32_t emm_layout_kind_dims(emm_layout_kind k);
/* Whether a mesh has depth, so that layouts in space are worth trying
 * (docs/layouts.md, "Layouts in space"): the smallest extent of the
 * bounding box of the vertices its triangles use is at least
 * EMM_DEPTH_RATIO times the largest. A planar mesh, or a height field
 * barely off its plane, has none; a closed surface, whose front and back
 * share the cells of a projection, has. Indices must be in range. */
#define EMM_DEPTH_RATIO 0.1
EMM_API int emm_geometry_has_depth(const double *xyz, size_t nv, const int32_t *tri, size_t nt);
/* The standard sweep in words, for help texts: "3 layouts x 3 fetch schemes
 * x cells 16, ..., then direct, cache and cache@ each layout: 50
 * strategies" (the layouts in the plane). Returns the length needed, as
 * snprintf does. */
EMM_API size_t emm_strategy_sweep_describe(char *buf, size_t cap);
/* The sweep's cell sizes, ascending; returns their count. */
EMM_API size_t emm_strategy_sweep_cells(const uint32_t **cells);

#ifdef __cplusplus
}
#endif
#endif
