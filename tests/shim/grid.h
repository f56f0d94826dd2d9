/* The test programs' mesh: a planar grid of n x n vertices (32-byte records,
 * f64 xyz at offset 8) and its 2 (n-1)^2 triangles (16-byte records, i32
 * vertex indices at offset 4), allocated in load_grid — the site their
 * EMM_TAG rules name:
 *   vertices:site=load_grid,stride=32,xyz=8:f64;triangles:site=load_grid,stride=16,vidx=4:i32
 * Static, so each program has a load_grid frame of its own. */
#ifndef EMM_TESTS_SHIM_GRID_H
#define EMM_TESTS_SHIM_GRID_H

#include <stdint.h>
#include <stdlib.h>

struct vert { uint32_t id; double xyz[3]; };
struct tri { uint32_t id; int32_t v[3]; };

static __attribute__((noinline, unused)) int load_grid(int n, struct vert **vs, struct tri **ts,
                                                       size_t *nt)
{
    struct vert *v = malloc(sizeof *v * (size_t)(n * n));
    struct tri *t = malloc(sizeof *t * 2 * (size_t)((n - 1) * (n - 1)));
    if (!v || !t)
        return -1;
    for (int i = 0; i < n * n; i++)
        v[i] = (struct vert){(uint32_t)i, {i % n, i / n, 0}};
    size_t k = 0;
    for (int y = 0; y + 1 < n; y++)
        for (int x = 0; x + 1 < n; x++) {
            int a = y * n + x;
            t[k] = (struct tri){(uint32_t)k, {a, a + 1, a + n}};
            k++;
            t[k] = (struct tri){(uint32_t)k, {a + 1, a + n + 1, a + n}};
            k++;
        }
    *vs = v;
    *ts = t;
    *nt = k;
    return 0;
}

/* One pass over the triangles' corners: a checksum of their x + 2 y. */
static __attribute__((unused)) double walk_grid(const struct vert *v, const struct tri *t,
                                                size_t nt)
{
    double sum = 0;
    for (size_t i = 0; i < nt; i++)
        for (int c = 0; c < 3; c++)
            sum += v[t[i].v[c]].xyz[0] + 2 * v[t[i].v[c]].xyz[1];
    return sum;
}

#endif
