/* A program that tags a mesh (allocated in load_grid, for an EMM_TAG rule),
 * walks it, prints a line and then dies of SIGSEGV (a store through a null
 * pointer). Under emm its exit status is the native one and its report is
 * written, up to its last access, saying how the run ended. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

struct vert { uint32_t id; double xyz[3]; };
struct tri { uint32_t id; int32_t v[3]; };

#define N 48

/* Volatile, so the compiler neither sees the null nor drops the store. */
static int *volatile null_pointer;

static __attribute__((noinline)) int load_grid(struct vert **vs, struct tri **ts, size_t *nt)
{
    struct vert *v = malloc(sizeof *v * N * N);
    struct tri *t = malloc(sizeof *t * 2 * (N - 1) * (N - 1));
    if (!v || !t)
        return -1;
    for (int i = 0; i < N * N; i++)
        v[i] = (struct vert){(uint32_t)i, {i % N, i / N, 0}};
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
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < nt; i++)
            for (int c = 0; c < 3; c++)
                sum += v[t[i].v[c]].xyz[0] + 2 * v[t[i].v[c]].xyz[1];
    printf("sum: %.1f\n", sum);
    fflush(stdout);
    *null_pointer = 1;
    return 0;
}
