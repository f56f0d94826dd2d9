/* emm_mesh_generate end to end: the mesh it returns is valid, counter-
 * clockwise, bounded by the fixed hull, and survives an OFF round trip bit
 * for bit. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "emm/mesh.h"
#include "generate.h"

static double orient(const emm_mesh *m, const emm_triangle *t)
{
    const double *a = emm_mesh_vertex(m, (uint32_t)t->v[0])->xyz;
    const double *b = emm_mesh_vertex(m, (uint32_t)t->v[1])->xyz;
    const double *c = emm_mesh_vertex(m, (uint32_t)t->v[2])->xyz;
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

static void test_one(size_t faces, emm_density density, uint64_t seed)
{
    emm_gen_options opt = {faces, seed, density, EMM_ORDER_INPUT};
    emm_mesh *m;
    emm_error err;
    emm_status st = emm_mesh_generate(&opt, &m, &err);
    REQUIRE(st == EMM_OK || (fprintf(stderr, "%s\n", err.message), 0));
    size_t nt = emm_mesh_triangle_count(m), nv = emm_mesh_vertex_count(m);
    CHECKF(nt == faces, "%zu faces asked, %zu made", faces, nt);
    CHECK(emm_mesh_boundary_edges(m) == emm_gen_hull_points(faces));
    CHECK(emm_mesh_polygons_split(m) == 0);
    double lo[3], hi[3];
    emm_mesh_bbox(m, lo, hi);
    /* Inside the unit square, touching it on all four sides when 4 divides
     * the hull's point count (the sides' middles are hull points). */
    CHECK(lo[0] >= 0 && lo[1] >= 0 && lo[2] == 0 && hi[0] <= 1 && hi[1] <= 1 && hi[2] == 0);
    if (emm_gen_hull_points(faces) >= 64)
        CHECK(hi[0] - lo[0] > 0.99 && hi[1] - lo[1] > 0.99);
    if (emm_gen_hull_points(faces) % 4 == 0)
        CHECK(lo[0] == 0 && lo[1] == 0 && hi[0] == 1 && hi[1] == 1);

    size_t cw = 0, asym = 0, boundary = 0;
    for (uint32_t t = 0; t < nt; t++) {
        const emm_triangle *tr = emm_mesh_triangle(m, t);
        cw += !(orient(m, tr) > 0);
        for (int k = 0; k < 3; k++) {
            int32_t nb = tr->n[k];
            if (nb < 0) {
                boundary++;
                continue;
            }
            /* A consistently oriented neighbour holds the edge reversed. */
            const emm_triangle *o = emm_mesh_triangle(m, (uint32_t)nb);
            int32_t a = tr->v[k], b = tr->v[(k + 1) % 3];
            int found = 0;
            for (int j = 0; j < 3; j++)
                found |= o->v[j] == b && o->v[(j + 1) % 3] == a && o->n[j] == (int32_t)t;
            asym += !found;
        }
    }
    CHECKF(cw == 0, "%zu triangles not counter-clockwise", cw);
    CHECK(asym == 0);
    CHECK(boundary == emm_gen_hull_points(faces));

    /* Write, read back: same counts, same coordinates, same triangles. */
    char path[] = "/tmp/emm-test-gen-XXXXXX.off";
    int fd = mkstemps(path, 4);
    REQUIRE(fd >= 0);
    close(fd);
    REQUIRE(emm_mesh_write_off(m, path, &err) == EMM_OK);
    emm_mesh *r;
    st = emm_mesh_open(path, &r, &err);
    REQUIRE(st == EMM_OK || (fprintf(stderr, "%s\n", err.message), 0));
    CHECK(emm_mesh_vertex_count(r) == nv && emm_mesh_triangle_count(r) == nt);
    CHECK(memcmp(emm_mesh_positions(r), emm_mesh_positions(m), 3 * nv * sizeof(double)) == 0);
    CHECK(memcmp(emm_mesh_indices(r), emm_mesh_indices(m), 3 * nt * sizeof(int32_t)) == 0);
    emm_mesh_free(r);
    unlink(path);
    emm_mesh_free(m);
}

int main(void)
{
    static const size_t sizes[] = {8, 9, 100, 2000, 20000, 20001};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        test_one(sizes[i], EMM_DENSITY_CLUSTERED, 1);
        test_one(sizes[i], EMM_DENSITY_UNIFORM, 2);
    }
    emm_gen_options bad = {3, 1, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
    emm_mesh *m = (emm_mesh *)&bad;
    emm_error err;
    CHECK(emm_mesh_generate(&bad, &m, &err) == EMM_ERR_RANGE);
    CHECK(m == NULL);
    return check_done();
}
