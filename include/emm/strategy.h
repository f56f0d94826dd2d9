/* emm — strategy strings (DESIGN.md "Strategies"), one parser used
 * everywhere: environment, command line, tables, reports.
 *
 *   direct                      word-by-word remote reads
 *   cache[@LAYOUT]              the hardware cache, on the original or a reordered layout
 *   LAYOUT+FETCH[@CELL]         an EMM strategy, CELL = triangles per cell
 *   LAYOUT = grid | tiles | quadtree     FETCH = naive | convolution | extrapolated
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

typedef enum emm_layout_kind {
    EMM_LAYOUT_ORIGINAL = 0, /* the program's own arrays (cache only) */
    EMM_LAYOUT_GRID,
    EMM_LAYOUT_TILES,
    EMM_LAYOUT_QUADTREE
} emm_layout_kind;

typedef enum emm_fetch_kind {
    EMM_FETCH_NONE = 0, /* direct and cache */
    EMM_FETCH_NAIVE,
    EMM_FETCH_CONVOLUTION,
    EMM_FETCH_EXTRAPOLATED
} emm_fetch_kind;

/* Triangles per cell when an EMM strategy string gives no @CELL, and for
 * cache@LAYOUT. */
#define EMM_DEFAULT_CELL 64u
/* Largest accepted CELL. */
#define EMM_MAX_CELL 1048576u

typedef struct emm_strategy {
    emm_strategy_kind kind;
    emm_layout_kind layout; /* ORIGINAL for direct and plain cache */
    emm_fetch_kind fetch;   /* NONE unless kind == EMM_STRATEGY_EMM */
    uint32_t cell;          /* triangles per cell; 0 for direct and plain cache */
} emm_strategy;

/* Parses a strategy string. On failure err names the string, the bad part
 * and the accepted values. */
EMM_API emm_status emm_strategy_parse(const char *text, emm_strategy *out, emm_error *err);

/* Writes the canonical string of s into buf (always NUL-terminated when
 * cap > 0); returns the length it needed, as snprintf does. */
EMM_API size_t emm_strategy_format(const emm_strategy *s, char *buf, size_t cap);

EMM_API const char *emm_layout_name(emm_layout_kind k);
EMM_API const char *emm_fetch_name(emm_fetch_kind k);

/* The standard sweep: 3 layouts × 3 fetch schemes × cells 16, 32, 64, 128,
 * 256, then direct, cache and cache@ each layout (50 strategies). Fills up to
 * cap entries and returns the sweep's full length. */
EMM_API size_t emm_strategy_sweep(emm_strategy *out, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
