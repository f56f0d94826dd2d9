/* What --list-sites says a block's records are (runtime/sites_shape.c), on
 * blocks laid out as the programs users ran lay them out: from the bytes
 * alone, and from accesses as the valgrind capture reports them. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "sites_shape.h"

#define N 4096

static uint32_t rnd(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return *s >> 8;
}

static void show(const char *what, const shape *s)
{
    char text[1024];
    shape_describe(s, text, sizeof text);
    printf("%s: %s\n", what, text);
}

int main(void)
{
    uint32_t seed = 1;
    shape s;
    char body[64];
    const char *kind;

    /* Three u32 vertex indices in 12 bytes: triangles. */
    uint32_t *tri = malloc(N * 12);
    for (unsigned i = 0; i < 3 * N; i++)
        tri[i] = rnd(&seed) % 2000;
    REQUIRE(shape_from_bytes((unsigned char *)tri, N * 12, N * 12, N * 12, &s));
    show("triangles", &s);
    CHECK(s.kind == SHAPE_TRIANGLES && s.stride == 12 && !s.from_accesses);
    CHECK(shape_rule(&s, 0, &kind, body, sizeof body) && strcmp(kind, "triangles") == 0 &&
          strcmp(body, "stride=12,vidx=0:u32") == 0);

    /* admesh's neighbours: three int neighbours (-1: none) and three
     * bytes, 16 a record. Read 12 bytes at a time they look like index
     * triples; never triangles. */
    unsigned char *nb = calloc(N, 16);
    for (unsigned i = 0; i < N; i++) {
        int32_t n[3] = {(int32_t)(rnd(&seed) % N), (int32_t)(rnd(&seed) % N),
                        i % 50 ? (int32_t)(rnd(&seed) % N) : -1};
        memcpy(nb + 16 * i, n, 12);
        for (int k = 0; k < 3; k++)
            nb[16 * i + 12 + k] = (unsigned char)(rnd(&seed) % 3);
    }
    REQUIRE(shape_from_bytes(nb, N * 16, N * 16, N * 16, &s));
    show("neighbours", &s);
    CHECK(s.stride == 16 && s.kind != SHAPE_TRIANGLES);

    /* Binary STL facets (50 bytes: normal, three corners, attribute): a
     * triangle soup with its corners at 12. */
    unsigned char *stl = calloc(N, 50);
    for (unsigned i = 0; i < N; i++)
        for (int c = 0; c < 12; c++) {
            float f = (float)(rnd(&seed) % 1000) / 100.0f + 0.5f;
            memcpy(stl + 50 * i + 4 * c, &f, 4);
        }
    REQUIRE(shape_from_bytes(stl, N * 50, N * 50, N * 50, &s));
    show("facets", &s);
    CHECK(s.kind == SHAPE_SOUP && s.stride == 50 && s.at == 12);
    CHECK(shape_rule(&s, 0, &kind, body, sizeof body) && strcmp(kind, "soup") == 0 &&
          strcmp(body, "stride=50,corners=12:f32") == 0);

    /* Text: a byte array, not one f32 coordinate per 4 bytes. */
    char *text = malloc(N * 12);
    for (unsigned i = 0; i < N * 12; i++)
        text[i] = "0123456789 .\n-"[rnd(&seed) % 14];
    CHECK(!shape_from_bytes((unsigned char *)text, N * 12, N * 12, N * 12, &s) ||
          s.kind == SHAPE_NONE);

    /* OpenMesh's edges: two half-edges of four handles (face, vertex,
     * next, prev; -1 for a boundary's face), 32 bytes: half-edge-like,
     * never triangles. */
    int32_t *he = malloc(N * 32);
    for (unsigned e = 0; e < N; e++)
        for (unsigned h = 0; h < 2; h++) {
            int32_t *r = he + 8 * e + 4 * h;
            r[0] = e % 97 == 0 && h ? -1 : (int32_t)(rnd(&seed) % (2 * N / 3)); /* face */
            r[1] = (int32_t)(rnd(&seed) % (N / 3));                          /* vertex */
            r[2] = (int32_t)((2 * e + h + 2 + rnd(&seed) % 64) % (2 * N));      /* next */
            r[3] = (int32_t)((2 * e + h + 2 * N - 2 - rnd(&seed) % 64) % (2 * N)); /* prev */
        }
    REQUIRE(shape_from_bytes((unsigned char *)he, N * 32, N * 32, N * 32, &s));
    show("half-edges", &s);
    CHECK(s.kind == SHAPE_HALFEDGE && !shape_rule(&s, 0, &kind, body, sizeof body));

    /* tetgen's tetrahedra: 56-byte records of seven addresses (of other
     * records, of vertices), one record in nine holding small numbers
     * instead. The same records at two addresses — one whose addresses'
     * low words are small, as a layout randomised by the system sometimes
     * puts them — read the same: addresses, not index-like low words. */
    enum { TETS = 4095 }; /* 56 x TETS: a multiple of 12, as tetgen's block is */
    static const uint64_t bases[2] = {0x7f1200000010ull, 0x7f1298547010ull};
    char told[2][1024];
    unsigned char *tet = malloc((size_t)TETS * 56);
    for (int b = 0; b < 2; b++) {
        uint32_t ts = 5;
        for (unsigned i = 0; i < TETS; i++)
            for (unsigned w = 0; w < 7; w++) {
                /* Four neighbours, their low bits a face; three vertices
                 * of another pool of the same region. */
                uint64_t v = i % 9 == 3  ? 7u * (i / 9 + 1)
                             : w < 4     ? (bases[b] + 56u * (rnd(&ts) % TETS)) | (rnd(&ts) % 4)
                                         : bases[b] + 0x1000000u + 48u * (rnd(&ts) % TETS);
                memcpy(tet + 56 * i + 8 * w, &v, 8);
            }
        REQUIRE(shape_from_bytes(tet, (size_t)TETS * 56, (size_t)TETS * 56, (size_t)TETS * 56, &s));
        show(b ? "addresses, high in their 4 GiB" : "addresses, low in their 4 GiB", &s);
        shape_describe(&s, told[b], sizeof told[b]);
        bool all = s.stride == 56 && s.nf == 7;
        for (int f = 0; f < s.nf; f++)
            all = all && s.f[f].cls == 'p' && s.f[f].size == 8;
        CHECK(all);
    }
    CHECK(strcmp(told[0], told[1]) == 0);

    /* From accesses: a program reads the 16-byte neighbour records'
     * three ints (three instructions, records by index) and their bytes
     * (one instruction a byte): 16-byte records, fields at 0, 4, 8 and 1-byte
     * ones at 12.., not triangles. Instructions of the C library are not
     * the program's; pcs here are no library's. */
    shape_acc *acc = calloc(1, sizeof *acc);
    for (unsigned k = 0; k < 2000; k++) {
        uint64_t r = rnd(&seed) % N;
        for (unsigned f = 0; f < 3; f++)
            shape_note(acc, 7, 16 * r + 4 * f, 4, false, 0x1000 + f);
        shape_note(acc, 7, 16 * r + 12 + k % 3, 1, false, 0x1010 + k % 3);
    }
    REQUIRE(shape_from_accesses(acc, nb, N * 16, N * 16, N * 16, &s));
    show("neighbours, accessed", &s);
    CHECK(s.from_accesses && s.stride == 16 && s.kind != SHAPE_TRIANGLES);

    /* A vertex array of f32 xyz read field by field: three coordinates. */
    float *xyz = malloc(N * 12);
    for (unsigned i = 0; i < 3 * N; i++)
        xyz[i] = (float)(rnd(&seed) % 1000) / 10.0f + 1.0f;
    memset(acc, 0, sizeof *acc);
    for (unsigned k = 0; k < 3000; k++) {
        uint64_t r = rnd(&seed) % N;
        for (unsigned f = 0; f < 3; f++)
            shape_note(acc, 3, 12 * r + 4 * f, 4, k % 5 == 0, 0x2000 + f);
    }
    REQUIRE(shape_from_accesses(acc, (unsigned char *)xyz, N * 12, N * 12, N * 12, &s));
    show("vertices, accessed", &s);
    CHECK(s.kind == SHAPE_VERTICES && s.stride == 12 && s.at == 0 && s.accesses == 9000);

    /* Too few accesses say nothing: the bytes decide. */
    memset(acc, 0, sizeof *acc);
    shape_note(acc, 1, 0, 4, false, 0x3000);
    CHECK(!shape_from_accesses(acc, (unsigned char *)xyz, N * 12, N * 12, N * 12, &s));

    free(tri);
    free(nb);
    free(stl);
    free(text);
    free(he);
    free(xyz);
    free(tet);
    free(acc);
    return check_done();
}
