/* Internal: reading mesh files into a raw polygon soup, before the checks and
 * the fan triangulation of mesh.c (thesis §3.1 is the model they feed).
 *
 * emm parses every format itself, from the file's bytes in memory (read
 * whole, with infile.h's cap): ASCII OFF and OBJ (mesh_text.c), binary OFF
 * (mesh_text.c), PLY in ASCII and both binary byte orders (mesh_ply.c), and
 * ASCII and binary STL (mesh_stl.c). OpenMesh's readers were the first
 * choice for the last three and were dropped: on a few dozen bytes they
 * crashed (a PLY header naming no property type), looped forever (a PLY
 * header without end_header) or allocated gigabytes (a binary OFF
 * declaring 2e9 faces), and they read coordinates as float, turn an
 * unreadable number into zeros or stale values and drop what they cannot
 * parse. These readers check every count against the bytes left before
 * looping over it and allocate only for what they have read, so no file
 * makes them hang or take memory beyond a small multiple of its size
 * (tests/fuzz runs them under libFuzzer). */
#ifndef EMM_INTERNAL_MESH_IO_H
#define EMM_INTERNAL_MESH_IO_H

#include "emm/common.h"

#include <stdbool.h>
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

/* Fills an emm_raw_mesh as a reader meets vertices and faces. With `lines`
 * each face keeps the line it came from (text formats). Zero-initialise
 * with .raw set. Each call returns false when memory runs out. */
typedef struct emm_raw_builder {
    emm_raw_mesh *raw;
    bool lines;
    size_t ncorner;
    size_t cap_v, cap_c, cap_f, cap_l;
} emm_raw_builder;

bool emm_raw_add_vertex(emm_raw_builder *b, const double v[3]);
bool emm_raw_add_corner(emm_raw_builder *b, int64_t v);
/* Closes the face whose corners were added since the previous one. */
bool emm_raw_end_face(emm_raw_builder *b, size_t line);
/* The little-endian 32-bit value at p (binary OFF and STL). */
static inline uint32_t emm_raw_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
/* Grows *p (of *cap elements of `elem` bytes) to hold `need`, doubling. */
bool emm_raw_grow(void **p, size_t *cap, size_t need, size_t elem);

/* Each reader parses a file's bytes (`data`, `len`); `path` names the file
 * in messages. On failure *raw is empty and err says what is wrong.
 * emm_read_off returns EMM_ERR_UNSUPPORTED without a message when the
 * header says the file is binary OFF, which emm_read_off_binary reads:
 * "OFF BINARY" (with the optional ST and N prefixes) on the first line,
 * then little-endian 32-bit vertex, face and edge counts, float
 * coordinates, and per face a 32-bit count and that many 32-bit indices,
 * as OpenMesh writes it. */
emm_status emm_read_off(const char *path, const char *data, size_t len,
                        emm_raw_mesh *raw, emm_error *err);
emm_status emm_read_off_binary(const char *path, const char *data, size_t len,
                               emm_raw_mesh *raw, emm_error *err);
emm_status emm_read_obj(const char *path, const char *data, size_t len,
                        emm_raw_mesh *raw, emm_error *err);
/* PLY 1.0, ascii, binary_little_endian or binary_big_endian: the x, y, z
 * of element "vertex" and the list "vertex_indices" (or "vertex_index") of
 * element "face"; other elements and properties are skipped. */
emm_status emm_read_ply(const char *path, const char *data, size_t len,
                        emm_raw_mesh *raw, emm_error *err);
/* STL, ASCII or binary (a file of exactly 84 + 50 x its facet count bytes);
 * corners with the same coordinates become one vertex. */
emm_status emm_read_stl(const char *path, const char *data, size_t len,
                        emm_raw_mesh *raw, emm_error *err);

#ifdef __cplusplus
}
#endif
#endif
