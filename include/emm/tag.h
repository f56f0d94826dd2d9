/* emm — tagging a program's mesh arrays (docs/design.md "The shim and the session").
 *
 * A program calls these after it has allocated (and usually filled) its
 * vertex and triangle arrays. In libemm they do nothing, so a program linked
 * against libemm runs unchanged; libemmshim.so, when preloaded, defines them
 * for real and starts watching the arrays. */
#ifndef EMM_TAG_H
#define EMM_TAG_H

#include "emm/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The vertex array: `count` records of `stride` bytes starting at `ptr`;
 * the x, y, z coordinates are consecutive scalars of `type` (EMM_F32 or
 * EMM_F64) at `xyz_offset` in each record. */
EMM_API void emm_tag_vertices(const void *ptr, size_t count, size_t stride,
                              size_t xyz_offset, emm_scalar type);

/* The triangle array: `count` records of `stride` bytes; the three vertex
 * indices are consecutive integers of `type` (EMM_I32, EMM_U32, EMM_I64) at
 * `index_offset` in each record. */
EMM_API void emm_tag_triangles(const void *ptr, size_t count, size_t stride,
                               size_t index_offset, emm_scalar type);

/* Marks the end of one iteration of the program's main loop; EMM_PROFILE can
 * count its window in iterations instead of accesses. */
EMM_API void emm_iteration(void);

#ifdef __cplusplus
}
#endif
#endif
