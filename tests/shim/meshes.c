/* Four threads, each with a mesh of its own: thread i loads a grid of side
 * 24 + 8 i (allocated in load_grid, for one EMM_TAG rule per kind that
 * selects all four) and walks it. The tagged arrays hold four meshes; emm
 * must simulate one complete pair — a triangle array with the vertex array
 * its indices name — and never pair one thread's triangles with another's
 * vertices. Prints each thread's checksum. */
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

struct vert { uint32_t id; double xyz[3]; };
struct tri { uint32_t id; int32_t v[3]; };

static __attribute__((noinline)) int load_grid(int n, struct vert **vs, struct tri **ts, size_t *nt)
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

struct job { int id; double sum; };

static void *work(void *arg)
{
    struct job *j = arg;
    struct vert *v;
    struct tri *t;
    size_t nt;
    if (load_grid(24 + 8 * j->id, &v, &t, &nt) != 0)
        abort();
    for (int pass = 0; pass < 6; pass++)
        for (size_t i = 0; i < nt; i++)
            for (int c = 0; c < 3; c++)
                j->sum += v[t[i].v[c]].xyz[0] + 2 * v[t[i].v[c]].xyz[1];
    /* Kept alive to the end, as a program's meshes are. */
    return NULL;
}

int main(void)
{
    pthread_t th[4];
    struct job jobs[4];
    for (int i = 0; i < 4; i++) {
        jobs[i] = (struct job){i, 0};
        if (pthread_create(&th[i], NULL, work, &jobs[i]) != 0)
            return 1;
    }
    for (int i = 0; i < 4; i++)
        pthread_join(th[i], NULL);
    for (int i = 0; i < 4; i++)
        printf("mesh %d: sum %.1f\n", i, jobs[i].sum);
    return 0;
}
