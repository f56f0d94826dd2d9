/* Reading, writing and building meshes, one case per CTest entry:
 *   formats     the same square from OFF (ascii, binary), OBJ (one quad, fan-split), PLY
 *               ascii and binary, STL ascii and binary gives the same
 *               vertices and triangles
 *   roundtrip   write_off then open gives the same doubles, bit for bit
 *   user_data   per-vertex and per-triangle pointers
 *   arrays_bad  emm_mesh_from_arrays rejects what emm_mesh_open rejects
 *   bunny       the Stanford bunny that glmark2-data installs
 *   large       a 1,002,528-triangle grid, built, written and read back */
#include "check.h"
#include "fixtures.h"

#include "emm/mesh.h"

#include <math.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static const char *gen_dir;

static emm_mesh *open_ok(const char *path)
{
    emm_mesh *m = NULL;
    emm_error err;
    emm_status st = emm_mesh_open(path, &m, &err);
    if (st != EMM_OK)
        fprintf(stderr, "%s\n", err.message);
    REQUIRE(st == EMM_OK && m != NULL);
    return m;
}

static int formats(void)
{
    char ply[4096], stl[4096], off[4096];
    snprintf(off, sizeof off, "%s/square_binary.off", gen_dir);
    snprintf(ply, sizeof ply, "%s/square_binary.ply", gen_dir);
    snprintf(stl, sizeof stl, "%s/square_binary.stl", gen_dir);
    write_binary_ply(ply, 0, -1);
    write_binary_stl(stl, 0);
    write_binary_off(off, 0);
    const char *files[] = { EMM_TEST_DATA "/mesh/square.off", off, EMM_TEST_DATA "/mesh/square.obj",
                            EMM_TEST_DATA "/mesh/square_ascii.ply", ply,
                            EMM_TEST_DATA "/mesh/square_ascii.stl", stl };
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        emm_mesh *m = open_ok(files[f]);
        printf("%s: %zu vertices, %zu triangles, %zu polygons split\n", files[f], emm_mesh_vertex_count(m),
               emm_mesh_triangle_count(m), emm_mesh_polygons_split(m));
        /* STL lists each facet's corners; the STL reader merges equal
         * positions in order of first appearance, which gives back the
         * four shared vertices in the OFF file's order. */
        CHECKF(emm_mesh_vertex_count(m) == 4, "%s", files[f]);
        CHECKF(emm_mesh_triangle_count(m) == 2, "%s", files[f]);
        CHECKF(emm_mesh_polygons_split(m) == (strstr(files[f], ".obj") ? 1u : 0u), "%s", files[f]);
        if (emm_mesh_vertex_count(m) == 4)
            for (uint32_t v = 0; v < 4; v++)
                for (int k = 0; k < 3; k++)
                    CHECKF(emm_mesh_vertex(m, v)->xyz[k] == (double)square_xyz[v][k], "%s vertex %u", files[f], v);
        if (emm_mesh_triangle_count(m) == 2)
            CHECKF(memcmp(emm_mesh_indices(m), square_tri, sizeof square_tri) == 0, "%s triangles", files[f]);
        emm_mesh_free(m);
    }
    return check_done();
}

static int roundtrip(void)
{
    /* Coordinates with no short decimal or float form. */
    const double xyz[] = { 0.1, 1.0 / 3, -2e-300, 1e300, M_PI, 0, -0.0, 2.0 / 3, M_E, 5, 6, 7 };
    const int32_t tri[] = { 0, 1, 2, 0, 2, 3 };
    emm_mesh *m = NULL;
    emm_error err;
    REQUIRE(emm_mesh_from_arrays(xyz, 4, tri, 2, "roundtrip", &m, &err) == EMM_OK);
    char path[4096];
    snprintf(path, sizeof path, "%s/roundtrip.off", gen_dir);
    unlink(path);
    REQUIRE(emm_mesh_write_off(m, path, &err) == EMM_OK);
    emm_mesh *back = open_ok(path);
    CHECK(emm_mesh_vertex_count(back) == 4 && emm_mesh_triangle_count(back) == 2);
    CHECK(memcmp(emm_mesh_positions(back), xyz, sizeof xyz) == 0);
    CHECK(memcmp(emm_mesh_indices(back), tri, sizeof tri) == 0);
    emm_mesh_free(back);

    /* Writing into a missing directory fails, names the path, and leaves
     * nothing behind. */
    char bad[4096];
    snprintf(bad, sizeof bad, "%s/no/such/dir/x.off", gen_dir);
    emm_status st = emm_mesh_write_off(m, bad, &err);
    printf("write to a missing directory: %s\n", err.message);
    CHECK(st == EMM_ERR_IO);
    CHECK(strncmp(err.message, bad, strlen(bad)) == 0);
    emm_mesh_free(m);
    return check_done();
}

static int user_data(void)
{
    emm_mesh *m = open_ok(EMM_TEST_DATA "/mesh/square.off");
    int a = 1, b = 2, c = 3;
    for (uint32_t v = 0; v < 4; v++)
        CHECK(emm_vertex_data(m, v) == NULL);
    CHECK(emm_triangle_data(m, 0) == NULL && emm_triangle_data(m, 1) == NULL);
    emm_vertex_set_data(m, 3, &a);
    emm_triangle_set_data(m, 1, &b);
    emm_triangle_set_data(m, 0, &c);
    CHECK(emm_vertex_data(m, 3) == &a && emm_vertex_data(m, 2) == NULL);
    CHECK(emm_triangle_data(m, 1) == &b && emm_triangle_data(m, 0) == &c);
    emm_triangle_set_data(m, 0, NULL);
    CHECK(emm_triangle_data(m, 0) == NULL);
    emm_mesh_free(m);
    return check_done();
}

static void expect_error(const double *xyz, size_t nv, const int32_t *tri, size_t nt, emm_status want,
                         const char *problem)
{
    emm_mesh *m = (emm_mesh *)1;
    emm_error err;
    emm_status st = emm_mesh_from_arrays(xyz, nv, tri, nt, "arrays", &m, &err);
    printf("%s\n", err.message);
    CHECKF(st == want, "status %d, want %d (%s)", (int)st, (int)want, problem);
    CHECK(m == NULL);
    CHECKF(strncmp(err.message, "arrays: ", 8) == 0 && strstr(err.message, problem), "message \"%s\" lacks \"%s\"",
           err.message, problem);
}

static int arrays_bad(void)
{
    const double xyz[] = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 1 };
    const int32_t ok[] = { 0, 1, 2, 0, 2, 3 };
    expect_error(xyz, 4, ok, 0, EMM_ERR_MESH, "no triangles");
    const int32_t range[] = { 0, 1, 2, 0, 2, 4 };
    expect_error(xyz, 4, range, 2, EMM_ERR_MESH, "triangle 1 refers to vertex 4, but the mesh has 4 vertices");
    const int32_t neg[] = { 0, 1, -3 };
    expect_error(xyz, 4, neg, 1, EMM_ERR_MESH, "triangle 0 refers to vertex -3");
    const int32_t degen[] = { 0, 1, 2, 3, 0, 3 };
    expect_error(xyz, 4, degen, 2, EMM_ERR_MESH, "triangle 1 (3, 0, 3) repeats a vertex (degenerate face)");
    const int32_t nm[] = { 0, 1, 2, 1, 0, 3, 4, 0, 1, 0, 2, 3 };
    expect_error(xyz, 5, nm, 4, EMM_ERR_MESH, "edge (0, 1) is shared by 3 faces (non-manifold)");
    double bad[15];
    memcpy(bad, xyz, sizeof bad);
    bad[7] = -INFINITY;
    expect_error(bad, 4, ok, 2, EMM_ERR_MESH, "vertex 2 has a non-finite coordinate (-inf)");
    bad[7] = NAN;
    expect_error(bad, 4, ok, 2, EMM_ERR_MESH, "vertex 2 has a non-finite coordinate (nan)");
    /* NULL name: messages still name something. */
    emm_mesh *m = NULL;
    emm_error err;
    CHECK(emm_mesh_from_arrays(xyz, 4, range, 2, NULL, &m, &err) == EMM_ERR_MESH);
    CHECK(strncmp(err.message, "mesh: ", 6) == 0);
    return check_done();
}

/* glmark2-data's bunny.obj: 34,835 "v" lines and 69,666 "f" lines
 * (counted with grep), all triangles. It loads as a valid mesh; this test
 * printed 0 boundary edges, i.e. the bunny is closed, and then Euler's
 * formula V - E + F = 2 with E = 3F/2 holds (34835 - 104499 + 69666):
 * a closed genus-0 surface, as a watertight bunny should be. */
static int bunny(void)
{
    const char *path = "/usr/share/glmark2/models/bunny.obj";
    if (access(path, R_OK) != 0) {
        printf("%s not installed (package glmark2-data); skipping\n", path);
        return 77;
    }
    emm_mesh *m = open_ok(path);
    double lo[3], hi[3];
    emm_mesh_bbox(m, lo, hi);
    printf("bunny: %zu vertices, %zu triangles, %zu boundary edges, mean edge %.6g, "
           "bbox (%g %g %g)-(%g %g %g)\n",
           emm_mesh_vertex_count(m), emm_mesh_triangle_count(m), emm_mesh_boundary_edges(m),
           emm_mesh_mean_edge_length(m), lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    CHECK(emm_mesh_vertex_count(m) == 34835);
    CHECK(emm_mesh_triangle_count(m) == 69666);
    CHECK(emm_mesh_polygons_split(m) == 0);
    CHECK(emm_mesh_boundary_edges(m) == 0);
    size_t f = emm_mesh_triangle_count(m);
    CHECK(f % 2 == 0 && (long long)emm_mesh_vertex_count(m) - (long long)(3 * f / 2) + (long long)f == 2);
    emm_mesh_free(m);
    return check_done();
}

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A (n-1) x (n-1) grid of unit squares, each split by the diagonal (i,j)-(i+1,j+1). */
static int large(void)
{
    const size_t n = 709, cells = n - 1, nv = n * n, nt = 2 * cells * cells;
    double *xyz = malloc(3 * nv * sizeof *xyz);
    int32_t *tri = malloc(3 * nt * sizeof *tri);
    REQUIRE(xyz && tri);
    for (size_t j = 0; j < n; j++)
        for (size_t i = 0; i < n; i++) {
            double *p = xyz + 3 * (j * n + i);
            p[0] = (double)i;
            p[1] = (double)j;
            p[2] = 0;
        }
    size_t t = 0;
    for (size_t j = 0; j < cells; j++)
        for (size_t i = 0; i < cells; i++) {
            int32_t a = (int32_t)(j * n + i), b = a + 1, c = a + (int32_t)n + 1, d = a + (int32_t)n;
            int32_t q[6] = { a, b, c, a, c, d };
            memcpy(tri + 3 * t, q, sizeof q);
            t += 2;
        }
    emm_mesh *m = NULL;
    emm_error err;
    double t0 = seconds();
    REQUIRE(emm_mesh_from_arrays(xyz, nv, tri, nt, "grid", &m, &err) == EMM_OK);
    double t1 = seconds();
    char path[4096];
    snprintf(path, sizeof path, "%s/grid.off", gen_dir);
    REQUIRE(emm_mesh_write_off(m, path, &err) == EMM_OK);
    double t2 = seconds();
    emm_mesh *back = open_ok(path);
    double t3 = seconds();
    printf("grid: %zu vertices, %zu triangles; from_arrays %.3f s, write_off %.3f s, open %.3f s\n", nv, nt,
           t1 - t0, t2 - t1, t3 - t2);
    /* Edges: n rows of cells horizontal + n columns of cells vertical + one
     * diagonal per cell; boundary: the 4 sides of cells edges each. */
    size_t edges = 2 * n * cells + cells * cells;
    CHECK(emm_mesh_triangle_count(back) == nt);
    CHECK(emm_mesh_boundary_edges(m) == 4 * cells);
    CHECK(emm_mesh_boundary_edges(back) == 4 * cells);
    double mean = ((double)(2 * n * cells) + sqrt(2) * (double)(cells * cells)) / (double)edges;
    CHECK(fabs(emm_mesh_mean_edge_length(m) - mean) < 1e-9);
    CHECK(memcmp(emm_mesh_positions(back), xyz, 3 * nv * sizeof *xyz) == 0);
    /* An interior cell's lower triangle: across (a b) the cell below's
     * upper triangle, across (b c) the right cell's upper triangle, across
     * (c a) its own upper triangle. */
    size_t cell = 5 * cells + 7, lower = 2 * cell;
    int32_t nb[3];
    emm_triangle_neighbors(back, (uint32_t)lower, nb);
    CHECK(nb[0] == (int32_t)(2 * (cell - cells) + 1));
    CHECK(nb[1] == (int32_t)(2 * (cell + 1) + 1));
    CHECK(nb[2] == (int32_t)(lower + 1));
    unlink(path);
    emm_mesh_free(m);
    emm_mesh_free(back);
    free(xyz);
    free(tri);
    return check_done();
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: %s CASE GENERATED_DIR\n", argv[0]);
        return 2;
    }
    gen_dir = argv[2];
    static const struct { const char *name; int (*run)(void); } cases[] = {
        { "formats", formats }, { "roundtrip", roundtrip }, { "user_data", user_data },
        { "arrays_bad", arrays_bad }, { "bunny", bunny }, { "large", large },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        if (strcmp(argv[1], cases[i].name) == 0)
            return cases[i].run();
    fprintf(stderr, "unknown case %s\n", argv[1]);
    return 2;
}
