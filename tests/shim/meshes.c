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

#include "grid.h"

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
        j->sum += walk_grid(v, t, nt);
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
