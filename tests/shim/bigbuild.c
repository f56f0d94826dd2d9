/* A loader at scale: builds a planar grid of N x N vertices (f32 xyz,
 * 12-byte records) and its 2 (N-1)^2 triangles (u32, 12 bytes) in
 * build_mesh, then walks the first triangles and prints a checksum. With
 * N = 1500, 2.25 M vertices and 4.5 M triangles (81 MB): under the fault
 * capture the build must reach the window in a small multiple of its
 * native time (one fault a page, not a write).
 *   test_shim_bigbuild [N] */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

static __attribute__((noinline)) int build_mesh(int n, float **vs, uint32_t **ts, size_t *nt)
{
    float *v = malloc(sizeof *v * 3 * (size_t)n * (size_t)n);
    uint32_t *t = malloc(sizeof *t * 6 * (size_t)(n - 1) * (size_t)(n - 1));
    if (!v || !t)
        return -1;
    for (size_t i = 0; i < (size_t)n * (size_t)n; i++) {
        v[3 * i] = (float)(i % (size_t)n);
        v[3 * i + 1] = (float)(i / (size_t)n);
        v[3 * i + 2] = 0;
    }
    size_t k = 0;
    for (uint32_t y = 0; y + 1 < (uint32_t)n; y++)
        for (uint32_t x = 0; x + 1 < (uint32_t)n; x++) {
            uint32_t a = y * (uint32_t)n + x;
            uint32_t tri[6] = {a, a + 1, a + (uint32_t)n, a + 1, a + (uint32_t)n + 1,
                               a + (uint32_t)n};
            for (int c = 0; c < 6; c++)
                t[6 * k / 2 + c] = tri[c];
            k += 2;
        }
    *vs = v;
    *ts = t;
    *nt = k;
    return 0;
}

int main(int argc, char **argv)
{
    int n = argc > 1 ? atoi(argv[1]) : 1500;
    if (n < 2 || n > 20000)
        return 2;
    float *v;
    uint32_t *t;
    size_t nt;
    if (build_mesh(n, &v, &t, &nt) != 0)
        return 1;
    double sum = 0;
    for (size_t i = 0; i < nt && i < 200000; i++)
        for (int c = 0; c < 3; c++)
            sum += v[3 * t[3 * i + c]] + 2 * v[3 * t[3 * i + c] + 1];
    printf("triangles: %zu\nsum: %.1f\n", nt, sum);
    free(v);
    free(t);
    return 0;
}
