/* emm — synthetic traces of canonical traversals over a mesh
 * (docs/profile.md; thesis §5, Table 5.1, Figs
 * 5.2–5.3). They feed the tests, the profiler's table and users who want to
 * see how a pattern fares without writing the program.
 *
 * A synthetic trace has two arrays laid out as the thesis' structs (§3.1):
 * vertices (80-byte records, coordinates at byte 8) and triangles (28-byte
 * records, vertex indices at byte 4, neighbours at byte 16), and the mesh's
 * geometry. Visiting a triangle reads its indices and neighbours (24 bytes
 * at offset 4), then the coordinates of its three vertices (24 bytes at
 * offset 8 each): four records per visit. */
#ifndef EMM_SYNTH_H
#define EMM_SYNTH_H

#include "emm/common.h"
#include "emm/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum emm_pattern {
    EMM_PATTERN_REGION = 0, /* breadth-first growth over edge neighbours from a seed triangle */
    EMM_PATTERN_CURVE,      /* straight walks across triangles from random starts */
    EMM_PATTERN_SCANLINE,   /* rows of triangles by centroid, left to right, bottom to top */
    EMM_PATTERN_ZORDER,     /* triangles in Z-order (Morton) of their centroids */
    EMM_PATTERN_GRAY,       /* triangles in Gray-code order of their centroids (thesis Fig. 5.3) */
    EMM_PATTERN_HILBERT,    /* triangles in Hilbert order of their centroids */
    EMM_PATTERN_RANDOM,     /* triangles in a uniformly random order */
    EMM_PATTERN_SPIRAL,     /* triangles by angle-then-radius around the centre: a spiral sweep */
    EMM_PATTERN_COUNT
} emm_pattern;

typedef struct emm_synth_options {
    emm_pattern pattern;
    uint64_t seed;
    /* Stop after this many triangle visits (0: one visit per triangle for the
     * ordering patterns; nt visits for curves). */
    uint64_t visits;
    /* curve: triangles per walk before a new walk starts (0: walk to the boundary). */
    uint64_t length;
    /* region: start in the corner of the bounding box (the lowest x + y
     * centroid) instead of a triangle chosen by the seed. */
    int corner_seed;
    /* region: grow over vertices instead, a vertex's visit visiting each
     * triangle of its one-ring (so a triangle once a corner: 3 visits a
     * triangle over the whole mesh, 3 × nt by default), as a program that
     * conquers vertices does (recipe region@ring). */
    int rings;
    /* Work recorded before each record (its work field), charged at
     * compute.per_work cycles a unit (0 by default: docs/machine.md). */
    uint32_t work;
    int compress;
    /* region: when has_start, grow from triangle `start` (over corner_seed
     * and seed), as the session does to follow the program's own start. */
    int has_start;
    uint32_t start;
} emm_synth_options;

/* Parses a pattern name (region, curve, scanline, zorder, gray, hilbert,
 * random, spiral). */
EMM_API emm_status emm_pattern_parse(const char *name, emm_pattern *out, emm_error *err);
EMM_API const char *emm_pattern_name(emm_pattern p);

/* Writes the trace of the pattern over m to path (whole or not at all).
 * *records, when not NULL, receives the number of access records. */
EMM_API emm_status emm_synth_trace(const emm_mesh *m, const emm_synth_options *opt,
                                   const char *path, uint64_t *records, emm_error *err);

#ifdef __cplusplus
}
#endif
#endif
