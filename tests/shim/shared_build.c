/* Eight threads build one mesh together, then walk it: each writes every
 * eighth vertex and triangle, so all of them write every page of the tagged
 * arrays at once, and the first to finish starts reading while the others
 * still write. Under the fault capture this makes the loader's open pages
 * (emm_guard_build_open) shared between threads and closed while others
 * open them, and the build end while pages open. Prints the walk's
 * checksum, the same in every thread and every run. */
#define _POSIX_C_SOURCE 200809L /* pthread_barrier_t */
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

struct vert { uint32_t id; double xyz[3]; };
struct tri { uint32_t id; int32_t v[3]; };

#define THREADS 8
#define SIDE 96 /* vertices a side: 288 KiB of vertices, 566 KiB of triangles */
#define NT (2 * (SIDE - 1) * (SIDE - 1))

static struct vert *verts;
static struct tri *tris;
static pthread_barrier_t start;

/* The tagged arrays' allocation site. */
static __attribute__((noinline)) int make_mesh(void)
{
    verts = malloc(sizeof *verts * SIDE * SIDE);
    tris = malloc(sizeof *tris * NT);
    return verts && tris ? 0 : -1;
}

struct job { int id; double sum; };

static void *work(void *arg)
{
    struct job *j = arg;
    pthread_barrier_wait(&start);
    for (int i = j->id; i < SIDE * SIDE; i += THREADS)
        verts[i] = (struct vert){(uint32_t)i, {i % SIDE, i / SIDE, 0}};
    for (int k = j->id; k < NT; k += THREADS) {
        int q = k / 2, a = q / (SIDE - 1) * SIDE + q % (SIDE - 1);
        tris[k] = k % 2 ? (struct tri){(uint32_t)k, {a + 1, a + SIDE + 1, a + SIDE}}
                        : (struct tri){(uint32_t)k, {a, a + 1, a + SIDE}};
    }
    /* Only this thread's own records: the others may still be writing. */
    for (int k = j->id; k < NT; k += THREADS)
        j->sum += tris[k].v[0] + tris[k].v[1] - tris[k].v[2];
    for (int i = j->id; i < SIDE * SIDE; i += THREADS)
        j->sum += verts[i].xyz[0] + 2 * verts[i].xyz[1];
    return NULL;
}

int main(void)
{
    pthread_t th[THREADS];
    struct job jobs[THREADS];
    if (make_mesh() != 0 || pthread_barrier_init(&start, NULL, THREADS) != 0)
        return 1;
    for (int i = 0; i < THREADS; i++) {
        jobs[i] = (struct job){i, 0};
        if (pthread_create(&th[i], NULL, work, &jobs[i]) != 0)
            return 1;
    }
    double sum = 0;
    for (int i = 0; i < THREADS; i++) {
        pthread_join(th[i], NULL);
        sum += jobs[i].sum;
    }
    printf("sum %.1f\n", sum);
    return 0;
}
