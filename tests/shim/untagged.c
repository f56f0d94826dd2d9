/* A program that never calls emm_tag_*: its vertex and triangle arrays are
 * allocated in a static function (load_grid) and only an EMM_TAG rule with
 * site=load_grid can find them. It walks the triangles and prints a
 * checksum, the same with and without the shim. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "grid.h"

int main(void)
{
    struct vert *v;
    struct tri *t;
    size_t nt;
    if (load_grid(64, &v, &t, &nt) != 0)
        return 1;
    double sum = 0;
    for (int pass = 0; pass < 3; pass++)
        sum += walk_grid(v, t, nt);
    printf("triangles: %zu\nsum: %.1f\n", nt, sum);
    free(v);
    free(t);
    return 0;
}
