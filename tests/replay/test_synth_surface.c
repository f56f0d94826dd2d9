/* The synthetic patterns over a surface in space (runtime/synth.c): on a
 * sphere of the generator, zorder, gray and hilbert visit every triangle
 * once with consecutive triangles close in 3D (about one mean edge apart;
 * ordered over two axes alone, the sphere's two halves interleave and the
 * mean step is about seven edges); curve walks go from triangle to edge neighbour and end after the
 * box's diagonal on a surface with no boundary; region reaches everything.
 * The same over a planar mesh is what tests/replay/synth.sh and the table
 * tests pin. */
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include "check.h"
#include "emm/mesh.h"
#include "emm/synth.h"
#include "synth_internal.h"

static void centroid(const emm_mesh *m, uint64_t t, double c[3])
{
    const emm_triangle *tr = emm_mesh_triangle(m, (uint32_t)t);
    for (int i = 0; i < 3; i++) {
        c[i] = 0;
        for (int k = 0; k < 3; k++)
            c[i] += emm_mesh_vertex(m, (uint32_t)tr->v[k])->xyz[i] / 3;
    }
}

static bool edge_neighbours(const emm_mesh *m, uint64_t a, uint64_t b)
{
    const emm_triangle *tr = emm_mesh_triangle(m, (uint32_t)a);
    for (int i = 0; i < 3; i++)
        if ((uint64_t)tr->n[i] == b)
            return true;
    return false;
}

int main(void)
{
    emm_gen_options go = {4000, 2, EMM_DENSITY_CLUSTERED, EMM_ORDER_MADE};
    emm_mesh *m;
    emm_error err;
    REQUIRE(emm_mesh_generate_surface(&go, EMM_SURFACE_SPHERE, &m, &err) == EMM_OK);
    size_t nt = emm_mesh_triangle_count(m);
    double edge = emm_mesh_mean_edge_length(m);
    const emm_pattern patterns[] = {EMM_PATTERN_ZORDER, EMM_PATTERN_GRAY, EMM_PATTERN_HILBERT,
                                    EMM_PATTERN_CURVE, EMM_PATTERN_REGION};
    for (size_t k = 0; k < sizeof patterns / sizeof patterns[0]; k++) {
        emm_synth_options so = {.pattern = patterns[k], .seed = 1};
        emm_trace_record *r;
        size_t n;
        REQUIRE(emm_synth_records(m, &so, NULL, "sphere", &r, &n, &err) == EMM_OK);
        CHECK(n == 4 * nt);
        unsigned char *seen = calloc(nt, 1);
        size_t distinct = 0, neighbours = 0;
        double step = 0;
        for (size_t i = 0; i < n; i += 4) {
            uint64_t t = r[i].element;
            REQUIRE(r[i].array == 1 && t < nt);
            distinct += !seen[t];
            seen[t] = 1;
            if (i) {
                double a[3], b[3];
                centroid(m, r[i - 4].element, a);
                centroid(m, t, b);
                step += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                             (a[2] - b[2]) * (a[2] - b[2]));
                neighbours += edge_neighbours(m, r[i - 4].element, t);
            }
        }
        double mean = step / (double)(n / 4 - 1) / edge;
        double share = (double)neighbours / (double)(n / 4 - 1);
        printf("%-8s %zu of %zu triangles, mean step %.2f edges, %.1f%% to an edge neighbour\n",
               emm_pattern_name(patterns[k]), distinct, nt, mean, 100 * share);
        if (patterns[k] == EMM_PATTERN_CURVE) {
            /* Walks of the box's diagonal (about 30 triangles here), not one
             * walk around and around. */
            CHECKF(share > 0.9 && share < 0.995, "curve: %.3f of steps to a neighbour", share);
            CHECKF(distinct > nt / 3, "curve: %zu distinct triangles", distinct);
        } else if (patterns[k] == EMM_PATTERN_REGION) {
            CHECK(distinct == nt); /* ring by ring: its steps are not short */
        } else {
            CHECK(distinct == nt);
            CHECKF(mean < 3, "%s: mean step %.2f edges", emm_pattern_name(patterns[k]), mean);
        }
        free(seen);
        free(r);
    }
    emm_mesh_free(m);
    return check_done();
}
