/* The tagging calls as no-ops: a program linked against libemm runs
 * unchanged; libemmshim.so, preloaded, provides the real definitions and
 * wins symbol resolution (include/emm/tag.h). */
#include "emm/tag.h"

void emm_tag_vertices(const void *ptr, size_t count, size_t stride,
                      size_t xyz_offset, emm_scalar type)
{
    (void)ptr; (void)count; (void)stride; (void)xyz_offset; (void)type;
}

void emm_tag_triangles(const void *ptr, size_t count, size_t stride,
                       size_t index_offset, emm_scalar type)
{
    (void)ptr; (void)count; (void)stride; (void)index_offset; (void)type;
}

void emm_iteration(void)
{
}
