/* The raw polygon soup every mesh reader fills (mesh_io.h): growing arrays
 * that hold only what the reader has met in the file, so memory follows the
 * bytes read, never a count a header declares. */
#include "mesh_io.h"

#include <stdlib.h>
#include <string.h>

void emm_raw_mesh_free(emm_raw_mesh *raw)
{
    if (!raw)
        return;
    free(raw->xyz);
    free(raw->corner);
    free(raw->face_start);
    free(raw->face_line);
    memset(raw, 0, sizeof *raw);
}

bool emm_raw_grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return true;
    size_t n = *cap ? *cap : 256;
    while (n < need) {
        if (n > SIZE_MAX / 4 / elem)
            return false;
        n *= 2;
    }
    void *q = realloc(*p, n * elem);
    if (!q)
        return false;
    *p = q;
    *cap = n;
    return true;
}

bool emm_raw_add_vertex(emm_raw_builder *b, const double v[3])
{
    emm_raw_mesh *r = b->raw;
    if (!emm_raw_grow((void **)&r->xyz, &b->cap_v, 3 * (r->nv + 1), sizeof(double)))
        return false;
    memcpy(r->xyz + 3 * r->nv, v, 3 * sizeof(double));
    r->nv++;
    return true;
}

bool emm_raw_add_corner(emm_raw_builder *b, int64_t v)
{
    if (!emm_raw_grow((void **)&b->raw->corner, &b->cap_c, b->ncorner + 1, sizeof(int64_t)))
        return false;
    b->raw->corner[b->ncorner++] = v;
    return true;
}

bool emm_raw_end_face(emm_raw_builder *b, size_t line)
{
    emm_raw_mesh *r = b->raw;
    if (!emm_raw_grow((void **)&r->face_start, &b->cap_f, r->nf + 2, sizeof(size_t)))
        return false;
    if (b->lines && !emm_raw_grow((void **)&r->face_line, &b->cap_l, r->nf + 2, sizeof(size_t)))
        return false;
    if (r->nf == 0)
        r->face_start[0] = 0;
    if (b->lines)
        r->face_line[r->nf] = line;
    r->face_start[++r->nf] = b->ncorner;
    return true;
}
