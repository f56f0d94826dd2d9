/* A program whose vertex and triangle records are both 40 bytes, made by
 * one function: the triangle block (9,000 records, 360,000 bytes) is a
 * whole number of 48-byte records, the vertex block (4,501 records) is not.
 * A rule with the wrong stride (48) selects the triangle block as vertices:
 * the session must refuse it in one line, not simulate integers read as
 * coordinates (issue 14, "wrong stride"). Prints a checksum of a traversal.
 * usage: test_shim_records */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

struct vertex {
    double xyz[3];
    int32_t id, flags;
    int64_t mark;
};
struct triangle {
    int32_t v[3], nb[3], id, flags;
    int64_t mark;
};

#define COLS 51 /* vertices per row of the grid */
#define NV 4501
#define NT 9000

static __attribute__((noinline)) int load_records(struct vertex **vo, struct triangle **to)
{
    struct vertex *v = malloc(NV * sizeof *v);
    struct triangle *t = malloc(NT * sizeof *t);
    if (!v || !t)
        return -1;
    for (int i = 0; i < NV; i++)
        v[i] = (struct vertex){{i % COLS, i / COLS, 0}, i, 0, 0};
    /* Two triangles a quad, the grid wrapped around: any valid indices do. */
    for (int n = 0; n < NT; n++) {
        int a = (n / 2) % NV, b = (a + 1) % NV, d = (a + COLS) % NV, e = (d + 1) % NV;
        t[n] = n % 2 ? (struct triangle){{b, e, d}, {-1, -1, -1}, n, 0, 0}
                     : (struct triangle){{a, b, d}, {-1, -1, -1}, n, 0, 0};
    }
    *vo = v;
    *to = t;
    return 0;
}

int main(void)
{
    struct vertex *v;
    struct triangle *t;
    if (load_records(&v, &t) != 0)
        return 1;
    double sum = 0;
    for (int pass = 0; pass < 3; pass++)
        for (int i = 0; i < NT; i++)
            for (int k = 0; k < 3; k++)
                sum += v[t[i].v[k]].xyz[0] + 2 * v[t[i].v[k]].xyz[1];
    printf("vertices %d triangles %d checksum %.1f\n", NV, NT, sum);
    free(v);
    free(t);
    return 0;
}
