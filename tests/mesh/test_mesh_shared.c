/* A program linked against libemm.so (not the static library the other
 * tests use) reads every format: the readers are all there for a
 * shared-library user too. Only EMM_API names are used. */
#include "emm/mesh.h"

#include <stdio.h>

int main(int argc, char **argv)
{
    int failed = 0;
    for (int i = 1; i < argc; i++) {
        emm_mesh *m = NULL;
        emm_error err;
        if (emm_mesh_open(argv[i], &m, &err) != EMM_OK) {
            fprintf(stderr, "%s\n", err.message);
            failed = 1;
            continue;
        }
        printf("%s: %zu vertices, %zu triangles\n", argv[i], emm_mesh_vertex_count(m), emm_mesh_triangle_count(m));
        if (emm_mesh_vertex_count(m) != 4 || emm_mesh_triangle_count(m) != 2)
            failed = 1;
        emm_mesh_free(m);
    }
    return failed;
}
