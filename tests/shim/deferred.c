/* A program whose triangle array holds no mesh yet when the profiling
 * window closes: its loader keeps the file's 1-based indices (as an OBJ
 * reader that renumbers later would), the first passes read vertices
 * through them shifted by hand, and only then are the indices made 0-based.
 * It frees its arrays before exit, so what emm reads again at the end is
 * what they held when freed. Prints a checksum, the same with and without
 * the shim. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define N 64 /* grid side: N*N vertices, 2*(N-1)^2 triangles */

static __attribute__((noinline)) int load_grid(double **vs, int32_t **ts, size_t *nt)
{
    double *v = malloc(sizeof *v * 3 * N * N);
    int32_t *t = malloc(sizeof *t * 3 * 2 * (N - 1) * (N - 1));
    if (!v || !t)
        return -1;
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            v[3 * (y * N + x)] = x;
            v[3 * (y * N + x) + 1] = y;
            v[3 * (y * N + x) + 2] = 0;
        }
    size_t k = 0;
    for (int y = 0; y + 1 < N; y++)
        for (int x = 0; x + 1 < N; x++) {
            int32_t a = y * N + x + 1; /* 1-based, as in the file */
            int32_t c[6] = {a, a + 1, a + N, a + 1, a + N + 1, a + N};
            for (int j = 0; j < 6; j++)
                t[3 * k + (size_t)j] = c[j];
            k += 2;
        }
    *vs = v;
    *ts = t;
    *nt = k;
    return 0;
}

int main(void)
{
    double *v;
    int32_t *t;
    size_t nt;
    if (load_grid(&v, &t, &nt) != 0)
        return 1;
    double sum = 0;
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < nt; i++)
            for (int c = 0; c < 3; c++) {
                int32_t j = t[3 * i + (size_t)c] - 1;
                sum += v[3 * j] + 2 * v[3 * j + 1];
            }
    for (size_t i = 0; i < 3 * nt; i++)
        t[i] -= 1;
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < nt; i++)
            for (int c = 0; c < 3; c++) {
                int32_t j = t[3 * i + (size_t)c];
                sum += v[3 * j] + 2 * v[3 * j + 1];
            }
    printf("triangles: %zu\nsum: %.1f\n", nt, sum);
    free(v);
    free(t);
    return 0;
}
