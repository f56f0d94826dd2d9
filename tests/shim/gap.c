/* Two tagged arrays with the program's hottest data between them: the
 * vertices, then a scratch block, then the triangles, each in the heap in
 * that order (small blocks, below the C library's mmap threshold). The
 * valgrind capture tests one interval over the tagged ranges first, so
 * every scratch access is a helper call that finds nothing (a miss); past
 * a million of them, more than the records, it tests two (tests/shim
 * gap.sh). Prints how many element reads it made: the report's count.
 *   test_shim_gap [PASSES]   (default 40) */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define SIDE 64 /* vertices per row */
#define SCRATCH 16384

__attribute__((noinline)) static void make_mesh(float **xyz, uint32_t **tri, size_t *nv, size_t *nt, uint32_t **scratch)
{
    *nv = SIDE * SIDE;
    *nt = 2 * (SIDE - 1) * (SIDE - 1);
    *xyz = malloc(*nv * 3 * sizeof **xyz);
    *scratch = calloc(SCRATCH, sizeof **scratch);
    *tri = malloc(*nt * 3 * sizeof **tri);
    if (!*xyz || !*scratch || !*tri) {
        fprintf(stderr, "test_shim_gap: out of memory\n");
        exit(1);
    }
    for (size_t v = 0; v < *nv; v++) {
        (*xyz)[3 * v] = (float)(v % SIDE);
        (*xyz)[3 * v + 1] = (float)(v / SIDE);
        (*xyz)[3 * v + 2] = 0;
    }
    size_t t = 0;
    for (uint32_t y = 0; y + 1 < SIDE; y++)
        for (uint32_t x = 0; x + 1 < SIDE; x++) {
            uint32_t a = y * SIDE + x, b = a + 1, c = a + SIDE, d = c + 1;
            uint32_t *p = *tri + 3 * t++;
            p[0] = a, p[1] = b, p[2] = d;
            p = *tri + 3 * t++;
            p[0] = a, p[1] = d, p[2] = c;
        }
}

int main(int argc, char **argv)
{
    long passes = argc > 1 ? strtol(argv[1], NULL, 10) : 40;
    float *xyz;
    uint32_t *tri, *scratch;
    size_t nv, nt;
    make_mesh(&xyz, &tri, &nv, &nt, &scratch);
    const volatile float *vx = xyz;
    const volatile uint32_t *vt = tri;
    volatile uint32_t *vs = scratch;
    double sum = 0;
    unsigned long reads = 0;
    for (long p = 0; p < passes; p++) {
        /* the hot scratch: 4 accesses a step, none of them the mesh's */
        for (uint32_t i = 0; i < 4 * SCRATCH; i++) {
            uint32_t k = (i * 2654435761u) % SCRATCH;
            vs[k] = vs[k] + vs[(k + 1) % SCRATCH] + i;
        }
        /* the mesh: a triangle's first corner, then that corner's x */
        for (size_t t = 0; t < nt; t += 7) {
            uint32_t a = vt[3 * t];
            sum += vx[3 * a];
            reads += 2;
        }
    }
    printf("element reads %lu sum %.1f scratch %u\n", reads, sum, scratch[0]);
    free(xyz);
    free(scratch);
    free(tri);
    return 0;
}
