/* A program outside the project using the installed libemm: it generates a
 * small mesh and prints its counts. */
#include <stdio.h>

#include <emm/mesh.h>

int main(void)
{
    emm_gen_options opt = {200, 7, EMM_DENSITY_UNIFORM, EMM_ORDER_INPUT};
    emm_mesh *m;
    emm_error err;
    if (emm_mesh_generate(&opt, &m, &err) != EMM_OK) {
        fprintf(stderr, "consumer: %s\n", err.message);
        return 1;
    }
    printf("emm %s: %zu faces\n", emm_version(), emm_mesh_triangle_count(m));
    emm_mesh_free(m);
    return 0;
}
