/* Binary mesh files for the mesh tests, written at test time into the build
 * tree (they are easier to read as code than as checked-in bytes). Every
 * file holds the unit square at z = 0.5 as the triangles (0 1 2) and
 * (0 2 3), the same mesh as tests/data/mesh/square.off. */
#ifndef EMM_TESTS_MESH_FIXTURES_H
#define EMM_TESTS_MESH_FIXTURES_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const float square_xyz[4][3] = { { 0, 0, 0.5f }, { 1, 0, 0.5f }, { 1, 1, 0.5f }, { 0, 1, 0.5f } };
static const int32_t square_tri[2][3] = { { 0, 1, 2 }, { 0, 2, 3 } };

/* Little-endian binary PLY; `cut` bytes are dropped from the end; `nan_at`
 * >= 0 replaces that vertex's x with NaN. */
static inline void write_binary_ply(const char *path, size_t cut, int nan_at)
{
    unsigned char body[4 * 12 + 2 * 13];
    size_t n = 0;
    for (int v = 0; v < 4; v++)
        for (int k = 0; k < 3; k++) {
            float c = (v == nan_at && k == 0) ? __builtin_nanf("") : square_xyz[v][k];
            memcpy(body + n, &c, 4);
            n += 4;
        }
    for (int t = 0; t < 2; t++) {
        body[n++] = 3;
        for (int k = 0; k < 3; k++) {
            memcpy(body + n, &square_tri[t][k], 4);
            n += 4;
        }
    }
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        exit(2);
    }
    fputs("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
          "property float y\nproperty float z\nelement face 2\n"
          "property list uchar int vertex_indices\nend_header\n", f);
    fwrite(body, 1, n - cut, f);
    fclose(f);
}

/* Binary STL: 80-byte header, facet count, 50 bytes per facet. */
static inline void write_binary_stl(const char *path, size_t cut)
{
    unsigned char data[84 + 2 * 50];
    memset(data, 0, sizeof data);
    memcpy(data, "binary square", 13);
    uint32_t facets = 2;
    memcpy(data + 80, &facets, 4);
    for (int t = 0; t < 2; t++) {
        float rec[12] = { 0, 0, 1 };
        for (int k = 0; k < 3; k++)
            memcpy(rec + 3 + 3 * k, square_xyz[square_tri[t][k]], 12);
        memcpy(data + 84 + 50 * t, rec, 48);
    }
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        exit(2);
    }
    fwrite(data, 1, sizeof data - cut, f);
    fclose(f);
}

/* Binary OFF as OpenMesh writes it: "OFF BINARY", then little-endian
 * 32-bit counts, float coordinates and per face a count and indices. */
static inline void write_binary_off(const char *path, size_t cut)
{
    unsigned char data[64 + 4 * 12 + 2 * 16];
    size_t n = 0;
    memcpy(data, "OFF BINARY\n", 11);
    n = 11;
    const uint32_t counts[3] = { 4, 2, 0 };
    memcpy(data + n, counts, sizeof counts);
    n += sizeof counts;
    memcpy(data + n, square_xyz, sizeof square_xyz);
    n += sizeof square_xyz;
    for (int t = 0; t < 2; t++) {
        uint32_t rec[4] = { 3, (uint32_t)square_tri[t][0], (uint32_t)square_tri[t][1], (uint32_t)square_tri[t][2] };
        memcpy(data + n, rec, sizeof rec);
        n += sizeof rec;
    }
    FILE *f = fopen(path, "wb");
    if (!f) {
        perror(path);
        exit(2);
    }
    fwrite(data, 1, n - cut, f);
    fclose(f);
}

#endif
