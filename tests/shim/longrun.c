/* A workload that runs until it is stopped, for the tests of how the shim
 * ends a session (report_whole.sh): a 128 x 128 grid mesh, tagged with the
 * explicit calls, walked at random (a triangle, then its three vertices).
 *
 *   longrun loop        walks until killed; prints "ready" (flushed) once
 *                       200,000 triangles are walked, so the window is past
 *   longrun loop-alloc  the same, and allocates and frees blocks of many
 *                       sizes as it walks (a signal often lands in malloc)
 *   longrun exit N      walks N triangles, prints a checksum, calls _exit(3)
 *
 * Output does not depend on timing except for how long "loop" runs. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "emm/tag.h"

struct vert { uint32_t id; double xyz[3]; };
struct tri { uint32_t id; int32_t v[3]; };

#define N 128 /* grid side: N*N vertices, 2*(N-1)^2 triangles */
#define READY 200000

static struct vert *verts;
static struct tri *tris;
static size_t ntris;

static void build(void)
{
    verts = malloc(sizeof *verts * N * N);
    tris = malloc(sizeof *tris * 2 * (N - 1) * (N - 1));
    if (!verts || !tris)
        exit(1);
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++)
            verts[y * N + x] = (struct vert){(uint32_t)(y * N + x), {x, y, 0}};
    for (int y = 0; y + 1 < N; y++)
        for (int x = 0; x + 1 < N; x++) {
            int32_t a = y * N + x, b = a + 1, c = a + N, d = c + 1;
            tris[ntris] = (struct tri){(uint32_t)ntris, {a, b, c}};
            ntris++;
            tris[ntris] = (struct tri){(uint32_t)ntris, {b, d, c}};
            ntris++;
        }
    emm_tag_vertices(verts, (size_t)N * N, sizeof *verts, offsetof(struct vert, xyz), EMM_F64);
    emm_tag_triangles(tris, ntris, sizeof *tris, offsetof(struct tri, v), EMM_I32);
}

static uint64_t next(uint64_t *x)
{
    *x ^= *x << 13;
    *x ^= *x >> 7;
    *x ^= *x << 17;
    return *x;
}

/* One step: a random triangle and its vertices. */
static double step(uint64_t *x)
{
    const struct tri *t = &tris[next(x) % ntris];
    double s = 0;
    for (int k = 0; k < 3; k++)
        s += verts[t->v[k]].xyz[0] + verts[t->v[k]].xyz[1];
    return s;
}

static int usage(void)
{
    fputs("usage: longrun loop | loop-alloc | exit N\n", stderr);
    return 2;
}

int main(int argc, char **argv)
{
    if (argc < 2)
        return usage();
    int loop = strcmp(argv[1], "loop") == 0, alloc = strcmp(argv[1], "loop-alloc") == 0;
    long steps = 0;
    if (!loop && !alloc) {
        if (strcmp(argv[1], "exit") != 0 || argc < 3 || (steps = atol(argv[2])) <= 0)
            return usage();
    }
    build();
    uint64_t x = 0x9e3779b97f4a7c15ull;
    volatile double sum = 0;
    if (!loop && !alloc) {
        for (long i = 0; i < steps; i++)
            sum += step(&x);
        printf("sum: %.1f\n", sum);
        fflush(stdout);
        _exit(3); /* stdio is flushed above: _exit skips atexit and destructors */
    }
    for (uint64_t i = 1;; i++) {
        sum += step(&x);
        if (alloc) {
            size_t size = next(&x) % 7 == 0 ? 4096 + next(&x) % 200000 : 16 + next(&x) % 700;
            char *p = malloc(size);
            if (!p)
                return 1;
            p[0] = p[size - 1] = 1;
            if (next(&x) % 4 == 0)
                p = realloc(p, size + 100);
            free(p);
        }
        if (i == READY) {
            puts("ready");
            fflush(stdout);
        }
    }
}
