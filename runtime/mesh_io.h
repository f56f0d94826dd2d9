/* Internal: reading mesh files into a raw polygon soup, before the checks and
 * the fan triangulation of mesh.c (thesis §3.1 is the model they feed).
 *
 * OpenMesh 9 reads PLY (ascii and binary), STL (ascii and binary) and binary
 * OFF (mesh_io.cpp, an extern "C" bridge). ASCII OFF and OBJ are parsed by emm
 * itself (mesh_text.c), because OpenMesh's readers for them lose what the
 * checks need: they read coordinates as float, turn an unreadable number
 * ("nan") into zeros or stale indices, repeat the previous index when a face
 * line is cut short (OFF), and silently drop an OBJ vertex they cannot parse
 * (shifting every later index) and OBJ faces with a repeated vertex. */
#ifndef EMM_INTERNAL_MESH_IO_H
#define EMM_INTERNAL_MESH_IO_H

#include "emm/common.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Faces as the file lists them: face f has the corners
 * corner[face_start[f]] .. corner[face_start[f + 1] - 1], 0-based vertex
 * indices exactly as read (not yet checked against nv). All arrays are
 * malloc'ed and owned by the struct. */
typedef struct emm_raw_mesh {
    double *xyz;        /* 3 * nv coordinates */
    size_t nv;
    int64_t *corner;
    size_t *face_start; /* nf + 1 entries (NULL when nf == 0) */
    size_t nf;
    size_t *face_line;  /* line of each face in a text file, or NULL */
    int index_base;     /* how the file numbers vertices: 0, or 1 for OBJ */
} emm_raw_mesh;

void emm_raw_mesh_free(emm_raw_mesh *raw);

/* ASCII OFF and OBJ from a file's bytes (`data`, `len`); `path` names the file
 * in messages. emm_read_off returns EMM_ERR_UNSUPPORTED without a message
 * when the header says the file is binary OFF (for OpenMesh to read). */
emm_status emm_read_off(const char *path, const char *data, size_t len,
                        emm_raw_mesh *raw, emm_error *err);
emm_status emm_read_obj(const char *path, const char *data, size_t len,
                        emm_raw_mesh *raw, emm_error *err);

/* PLY, STL and binary OFF through OpenMesh (mesh_io.cpp). OpenMesh's own
 * messages are silenced; failures are reported in emm's words. Reads are
 * serialised by a lock because OpenMesh's readers are process-wide
 * singletons with mutable state. */
emm_status emm_read_openmesh(const char *path, emm_raw_mesh *raw, emm_error *err);

#ifdef __cplusplus
}
#endif
#endif
