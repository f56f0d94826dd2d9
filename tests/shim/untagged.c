/* A program that never calls emm_tag_*: its vertex and triangle arrays are
 * allocated in a static function (load_grid) and only an EMM_TAG rule with
 * site=load_grid can find them. It walks the triangles and prints a
 * checksum, the same with and without the shim. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

struct vert { uint32_t id; double xyz[3]; };
struct tri { uint32_t id; int32_t v[3]; };

#define N 64 /* grid side: N*N vertices, 2*(N-1)^2 triangles */

static __attribute__((noinline)) int load_grid(struct vert **vs, struct tri **ts, size_t *nt)
{
    struct vert *v = malloc(sizeof *v * N * N);
    struct tri *t = malloc(sizeof *t * 2 * (N - 1) * (N - 1));
    if (!v || !t)
        return -1;
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            struct vert *p = &v[y * N + x];
            p->id = (uint32_t)(y * N + x);
            p->xyz[0] = x;
            p->xyz[1] = y;
            p->xyz[2] = 0;
        }
    size_t k = 0;
    for (int y = 0; y + 1 < N; y++)
        for (int x = 0; x + 1 < N; x++) {
            int a = y * N + x;
            t[k] = (struct tri){(uint32_t)k, {a, a + 1, a + N}};
            k++;
            t[k] = (struct tri){(uint32_t)k, {a + 1, a + N + 1, a + N}};
            k++;
        }
    *vs = v;
    *ts = t;
    *nt = k;
    return 0;
}

int main(void)
{
    struct vert *v;
    struct tri *t;
    size_t nt;
    if (load_grid(&v, &t, &nt) != 0)
        return 1;
    double sum = 0;
    for (int pass = 0; pass < 3; pass++)
        for (size_t i = 0; i < nt; i++)
            for (int c = 0; c < 3; c++)
                sum += v[t[i].v[c]].xyz[0] + 2 * v[t[i].v[c]].xyz[1];
    printf("triangles: %zu\nsum: %.1f\n", nt, sum);
    free(v);
    free(t);
    return 0;
}
