/* A program written against the mesh interface (include/emm/mesh.h) that
 * keeps no arrays of its own: it generates a mesh, walks it breadth-first
 * across triangle neighbours, reads each triangle's vertices, and prints a
 * checksum. Under EMM_CAPTURE=api (or auto, which picks api for such a
 * program) the shim sees every call as an access to a mesh record. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "emm/mesh.h"

int main(int argc, char **argv)
{
    emm_gen_options opt = {argc > 1 ? (size_t)atol(argv[1]) : 20000, 7, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
    emm_mesh *m;
    emm_error err;
    if (emm_mesh_generate(&opt, &m, &err) != EMM_OK) {
        fprintf(stderr, "api: %s\n", err.message);
        return 1;
    }
    size_t nt = emm_mesh_triangle_count(m);
    uint32_t *queue = malloc(nt * sizeof *queue);
    unsigned char *seen = calloc(nt, 1);
    if (!queue || !seen)
        return 1;
    size_t head = 0, tail = 0, adjacency = 0;
    double sum = 0;
    queue[tail++] = 0;
    seen[0] = 1;
    while (head < tail) {
        uint32_t t = queue[head++];
        int32_t v[3], n[3];
        emm_triangle_vertices(m, t, v);
        for (int k = 0; k < 3; k++) {
            const emm_vertex *p = emm_mesh_vertex(m, (uint32_t)v[k]);
            sum += p->xyz[0] + 2 * p->xyz[1] + 3 * p->xyz[2];
        }
        const int32_t *around;
        adjacency += emm_vertex_triangles(m, (uint32_t)v[0], &around);
        emm_triangle_neighbors(m, t, n);
        for (int k = 0; k < 3; k++)
            if (n[k] >= 0 && !seen[n[k]]) {
                seen[n[k]] = 1;
                queue[tail++] = (uint32_t)n[k];
            }
    }
    printf("triangles reached: %zu of %zu\nadjacency: %zu\nsum: %.6e\n", tail, nt, adjacency,
           sum);
    free(queue);
    free(seen);
    emm_mesh_free(m);
    return 0;
}
