/* The session's helper threads must be the shim's own (issue: a deadlock
 * under fault capture). A program with the thesis' record sizes (80-byte
 * vertices, 28-byte triangles), no emm calls, a 100 x 100 grid (19,602
 * triangles): the decision's sweep builds layouts on helper threads, and a
 * layout of this mesh allocates nt * 4 = 78,408 bytes — a whole number of
 * 28-byte records, so a `triangles:` rule with min=4K matches it. Were the
 * helpers not marked, that block would be tagged from a helper thread
 * while the main thread holds the shim's lock waiting for them. The program
 * walks the triangles breadth-first from the corner and prints a checksum. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct vert { uint32_t id; double xyz[3]; int32_t tris[12]; };  /* 80 bytes */
struct tri { uint32_t id; int32_t v[3]; int32_t n[3]; };         /* 28 bytes */

#define N 100

int main(void)
{
    size_t nv = N * N, nt = 2 * (N - 1) * (N - 1);
    struct vert *v = malloc(nv * sizeof *v);
    struct tri *t = malloc(nt * sizeof *t);
    int32_t *queue = malloc(nt * sizeof *queue);
    unsigned char *seen = calloc(nt, 1);
    if (!v || !t || !queue || !seen)
        return 1;
    memset(v, 0, nv * sizeof *v);
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++)
            v[y * N + x] = (struct vert){(uint32_t)(y * N + x), {x, y, 0}, {0}};
    size_t k = 0;
    for (int y = 0; y + 1 < N; y++)
        for (int x = 0; x + 1 < N; x++) {
            int a = y * N + x, q = 2 * (y * (N - 1) + x);
            /* lower triangle q: right neighbour q+1 (shared diagonal), below
             * the upper triangle of the cell beneath; upper q+1: left q,
             * right the lower triangle of the next cell, above the lower of
             * the cell above. */
            t[k] = (struct tri){(uint32_t)k, {a, a + 1, a + N},
                                {y > 0 ? q - 2 * (N - 1) + 1 : -1, q + 1, x > 0 ? q - 1 : -1}};
            k++;
            t[k] = (struct tri){(uint32_t)k, {a + 1, a + N + 1, a + N},
                                {x + 2 < N ? q + 2 : -1, y + 2 < N ? q + 2 * (N - 1) : -1, q}};
            k++;
        }
    size_t head = 0, tail = 0;
    double sum = 0;
    queue[tail++] = 0;
    seen[0] = 1;
    while (head < tail) {
        const struct tri *r = &t[queue[head++]];
        for (int c = 0; c < 3; c++) {
            const struct vert *p = &v[r->v[c]];
            sum += p->xyz[0] + 2 * p->xyz[1];
            if (r->n[c] >= 0 && !seen[r->n[c]]) {
                seen[r->n[c]] = 1;
                queue[tail++] = r->n[c];
            }
        }
    }
    printf("triangles: %zu, reached: %zu\nsum: %.1f\n", nt, tail, sum);
    free(v);
    free(t);
    free(queue);
    free(seen);
    return 0;
}
