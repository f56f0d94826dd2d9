/* 8 threads allocate and free blocks of many sizes (some as large as the
 * tagged array, so they take the shim's slow path) while 2 of them also read
 * the tagged vertex array. Prints a checksum that does not depend on
 * scheduling; must finish with the same output under the shim, without
 * deadlock. */
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/tag.h"

struct vert { uint32_t id; double xyz[3]; };
#define NV 20000
static struct vert *verts;

struct job { int id; double sum; uint64_t allocs; };

static void *work(void *arg)
{
    struct job *j = arg;
    uint64_t x = 0x9e3779b97f4a7c15ull * (uint64_t)(j->id + 1);
    for (int round = 0; round < 4000; round++) {
        x ^= x << 13; x ^= x >> 7; x ^= x << 17;
        size_t size = (x % 5 == 0) ? 8192 + x % 65536 : 16 + x % 512;
        unsigned char *p = malloc(size);
        if (!p)
            abort();
        memset(p, j->id, size);
        j->allocs += p[size - 1] == (unsigned char)j->id;
        if (x % 3 == 0)
            p = realloc(p, size * 2);
        free(p);
        if (j->id < 2)
            for (int k = 0; k < 50; k++) {
                const struct vert *v = &verts[(x + (uint64_t)k * 7919) % NV];
                j->sum += v->xyz[0] + v->xyz[1];
            }
    }
    return NULL;
}

int main(void)
{
    verts = malloc(sizeof *verts * NV);
    if (!verts)
        return 1;
    for (uint32_t i = 0; i < NV; i++)
        verts[i] = (struct vert){i, {i % 141, i / 141, 0}};
    emm_tag_vertices(verts, NV, sizeof *verts, offsetof(struct vert, xyz), EMM_F64);
    pthread_t th[8];
    struct job jobs[8];
    for (int i = 0; i < 8; i++) {
        jobs[i] = (struct job){i, 0, 0};
        if (pthread_create(&th[i], NULL, work, &jobs[i]) != 0)
            return 1;
    }
    double sum = 0;
    uint64_t allocs = 0;
    for (int i = 0; i < 8; i++) {
        pthread_join(th[i], NULL);
        sum += jobs[i].sum;
        allocs += jobs[i].allocs;
    }
    printf("allocs: %llu\nsum: %.1f\n", (unsigned long long)allocs, sum);
    free(verts);
    return 0;
}
