/* A mesh kept as a structure of arrays whose x, y and z blocks come from
 * one malloc call in a loop (the loop's bound is a run-time value, so the
 * compiler cannot unroll it into three calls): a grid of N x N vertices
 * (default 200) and its triangles, read over a few passes; prints a sum.
 * Knows nothing of emm. usage: soa_loop [N] [AXES] */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

static float *axis[3];
static uint32_t *tri;

static __attribute__((noinline)) int mesh_alloc(int naxes, size_t nv, size_t nt)
{
    for (int a = 0; a < naxes; a++)
        if (!(axis[a] = malloc(nv * sizeof(float))))
            return -1;
    return (tri = malloc(nt * 3 * sizeof *tri)) ? 0 : -1;
}

int main(int argc, char **argv)
{
    size_t n = argc > 1 ? (size_t)atoi(argv[1]) : 200;
    int naxes = argc > 2 ? atoi(argv[2]) : 3;
    if (n < 2 || naxes != 3) {
        fprintf(stderr, "usage: soa_loop [N>=2] [3]\n");
        return 2;
    }
    size_t nv = n * n, nt = 2 * (n - 1) * (n - 1), k = 0;
    if (mesh_alloc(naxes, nv, nt) != 0)
        return 1;
    for (size_t i = 0; i < nv; i++) {
        axis[0][i] = (float)(i % n) + 0.25f;
        axis[1][i] = (float)(i / n) + 0.5f;
        axis[2][i] = 1.0f;
    }
    for (size_t y = 0; y + 1 < n; y++)
        for (size_t x = 0; x + 1 < n; x++) {
            uint32_t a = (uint32_t)(y * n + x), r = (uint32_t)n;
            uint32_t t[6] = {a, a + 1, a + r, a + 1, a + r + 1, a + r};
            for (int c = 0; c < 6; c++)
                tri[3 * k + (size_t)c] = t[c];
            k += 2;
        }
    double s = 0;
    for (int pass = 0; pass < 4; pass++)
        for (size_t t = 0; t < nt; t++)
            for (int c = 0; c < 3; c++) {
                uint32_t v = tri[3 * t + (size_t)c];
                s += axis[0][v] + 0.5 * axis[1][v] + axis[2][v];
            }
    printf("%.2f\n", s);
    for (int a = 0; a < 3; a++)
        free(axis[a]);
    free(tri);
    return 0;
}
