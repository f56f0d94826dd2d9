/* Internal: the layout of emm_mesh (thesis §3.1), for runtime code that
 * walks the arrays directly. Everything here is filled once by mesh.c and
 * read-only afterwards, except the user-data slots. */
#ifndef EMM_INTERNAL_MESH_H
#define EMM_INTERNAL_MESH_H

#include "emm/mesh.h"

struct emm_mesh {
    size_t nv, nt;
    emm_vertex *vertex;       /* nv records: id and coordinates */
    emm_triangle *triangle;   /* nt records: id, corners, edge neighbours */
    double *xyz;              /* 3 * nv packed coordinates (emm_mesh_positions) */
    int32_t *index;           /* 3 * nt packed corners (emm_mesh_indices) */
    size_t *vt_start;         /* nv + 1 offsets into vt */
    int32_t *vt;              /* triangles around each vertex, ascending */
    void **vertex_data;       /* nv user pointers */
    void **triangle_data;     /* nt user pointers */
    size_t boundary_edges;
    size_t edges;
    size_t polygons_split;
    double lo[3], hi[3];
    double mean_edge;
};

/* emm_mesh_open on a file's bytes already in memory: `path` names the file
 * in messages and its extension picks the format. Used by emm_mesh_open
 * and by the fuzz harnesses (tests/fuzz). */
emm_status emm_mesh_parse(const char *path, const char *data, size_t len, emm_mesh **out, emm_error *err);

#endif
