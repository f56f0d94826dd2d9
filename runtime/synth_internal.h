/* Synthetic traversals in memory, for the session's decision (runtime/table.c):
 * the canonical pattern a profile was recognised as, replayed over the
 * program's own mesh and arrays. */
#ifndef EMM_SYNTH_INTERNAL_H
#define EMM_SYNTH_INTERNAL_H

#include "emm/synth.h"
#include "emm/trace.h"

/* Where a visit's records land: the triangle array's index in the trace,
 * the offset and bytes read from a triangle record, and the same for the
 * vertex array. */
struct synth_arrays {
    uint32_t tri, tri_offset, tri_bytes;
    uint32_t vert, vert_offset, vert_bytes;
};

/* The records of the pattern over m (4 per triangle visit), against
 * `arrays` (NULL: the thesis' record layout of emm_synth_trace, vertices
 * array 0 and triangles array 1). *out is malloc'ed; the caller frees it.
 * `name` names the run in messages. */
emm_status emm_synth_records(const emm_mesh *m, const emm_synth_options *opt,
                             const struct synth_arrays *arrays, const char *name,
                             emm_trace_record **out, size_t *nrec, emm_error *err);

/* A recipe names a canonical traversal in the strategy table: a pattern
 * (emm_pattern_parse), optionally "@corner" (region from the corner) or
 * "@N" (curves of N triangles). Fills pattern, length and corner_seed of
 * *o (other fields untouched). */
emm_status emm_synth_recipe_parse(const char *recipe, emm_synth_options *o, emm_error *err);

#endif
