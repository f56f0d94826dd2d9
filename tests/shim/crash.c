/* A program that tags a mesh (allocated in load_grid, for an EMM_TAG rule),
 * walks it, prints a line and then dies of SIGSEGV (a store through a null
 * pointer). Under emm its exit status is the native one and its report is
 * written, up to its last access, saying how the run ended. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "grid.h"

/* Volatile, so the compiler neither sees the null nor drops the store. */
static int *volatile null_pointer;

int main(void)
{
    struct vert *v;
    struct tri *t;
    size_t nt;
    if (load_grid(48, &v, &t, &nt) != 0)
        return 1;
    double sum = 0;
    for (int pass = 0; pass < 2; pass++)
        sum += walk_grid(v, t, nt);
    printf("sum: %.1f\n", sum);
    fflush(stdout);
    *null_pointer = 1;
    return 0;
}
