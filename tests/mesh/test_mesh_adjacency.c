/* Adjacency on hand-made meshes, one per CTest entry. Every expected value
 * below was worked out by hand from the drawing in the comment; n[i] is the
 * triangle across the edge (v[i], v[(i+1) % 3]). */
#include "check.h"

#include "emm/mesh.h"

#include <math.h>
#include <string.h>

static emm_mesh *make(const double *xyz, size_t nv, const int32_t *tri, size_t nt)
{
    emm_mesh *m = NULL;
    emm_error err;
    emm_status st = emm_mesh_from_arrays(xyz, nv, tri, nt, "hand-made", &m, &err);
    if (st != EMM_OK)
        fprintf(stderr, "%s\n", err.message);
    REQUIRE(st == EMM_OK && m != NULL);
    REQUIRE(emm_mesh_vertex_count(m) == nv && emm_mesh_triangle_count(m) == nt);
    return m;
}

static void expect_neighbours(const emm_mesh *m, uint32_t t, int32_t a, int32_t b, int32_t c)
{
    int32_t n[3];
    emm_triangle_neighbors(m, t, n);
    CHECKF(n[0] == a && n[1] == b && n[2] == c, "triangle %u: neighbours (%d %d %d), want (%d %d %d)", t, n[0],
           n[1], n[2], a, b, c);
    const emm_triangle *tr = emm_mesh_triangle(m, t);
    CHECK(tr->id == t && memcmp(tr->n, n, sizeof n) == 0);
}

/* want: the expected ascending list, ended by -1. */
static void expect_incident(const emm_mesh *m, uint32_t v, const int32_t *want)
{
    const int32_t *got;
    size_t n = emm_vertex_triangles(m, v, &got), k = 0;
    while (want[k] >= 0)
        k++;
    CHECKF(n == k, "vertex %u: %zu incident triangles, want %zu", v, n, k);
    for (size_t i = 0; i < n && i < k; i++)
        CHECKF(got[i] == want[i], "vertex %u: incident[%zu] = %d, want %d", v, i, got[i], want[i]);
}

#define INC(v, ...) expect_incident(m, v, (const int32_t[]){ __VA_ARGS__, -1 })

/*  3 ---- 2      t0 = (0 1 2), t1 = (0 2 3): the diagonal (0, 2) is shared,
 *  | t1 / |      the four sides are boundary. Edges: 4 of length 1 and the
 *  |  / t0|      diagonal of length sqrt(2).
 *  0 ---- 1 */
static int two_triangles(void)
{
    const double xyz[] = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0 };
    const int32_t tri[] = { 0, 1, 2, 0, 2, 3 };
    emm_mesh *m = make(xyz, 4, tri, 2);
    expect_neighbours(m, 0, -1, -1, 1); /* (0 1) side, (1 2) side, (2 0) diagonal */
    expect_neighbours(m, 1, 0, -1, -1); /* (0 2) diagonal, (2 3), (3 0) sides */
    INC(0, 0, 1);
    INC(1, 0);
    INC(2, 0, 1);
    INC(3, 1);
    CHECK(emm_mesh_boundary_edges(m) == 4);
    CHECK(fabs(emm_mesh_mean_edge_length(m) - (4 + sqrt(2)) / 5) < 1e-15);
    double lo[3], hi[3];
    emm_mesh_bbox(m, lo, hi);
    CHECK(lo[0] == 0 && lo[1] == 0 && lo[2] == 0 && hi[0] == 1 && hi[1] == 1 && hi[2] == 0);
    int32_t v[3];
    emm_triangle_vertices(m, 1, v);
    CHECK(v[0] == 0 && v[1] == 2 && v[2] == 3);
    CHECK(emm_mesh_vertex(m, 2)->id == 2 && emm_mesh_vertex(m, 2)->xyz[0] == 1 && emm_mesh_vertex(m, 2)->xyz[1] == 1);
    CHECK(emm_mesh_polygons_split(m) == 0);
    CHECK(memcmp(emm_mesh_positions(m), xyz, sizeof xyz) == 0);
    CHECK(memcmp(emm_mesh_indices(m), tri, sizeof tri) == 0);
    emm_mesh_free(m);
    return check_done();
}

/* A closed fan: centre 0, ring 1..6 on the unit hexagon, t_k = (0, k+1,
 * k%6+2) for k = 0..5. t_k's edge (0, k+1) is shared with t_{k-1}, its rim
 * edge is boundary, its edge (k+2, 0) is shared with t_{k+1} (mod 6). The
 * centre touches all six; ring vertex i touches t_{i-2} and t_{i-1} (mod 6).
 * All twelve edges have length 1; the six rim edges are boundary. */
static int fan(void)
{
    double xyz[7 * 3] = { 0 };
    int32_t tri[6 * 3];
    for (int i = 0; i < 6; i++) {
        xyz[3 * (i + 1)] = cos(i * M_PI / 3);
        xyz[3 * (i + 1) + 1] = sin(i * M_PI / 3);
        tri[3 * i] = 0;
        tri[3 * i + 1] = i + 1;
        tri[3 * i + 2] = i == 5 ? 1 : i + 2;
    }
    emm_mesh *m = make(xyz, 7, tri, 6);
    for (int k = 0; k < 6; k++)
        expect_neighbours(m, (uint32_t)k, (k + 5) % 6, -1, (k + 1) % 6);
    INC(0, 0, 1, 2, 3, 4, 5);
    INC(1, 0, 5);
    INC(2, 0, 1);
    INC(3, 1, 2);
    INC(6, 4, 5);
    CHECK(emm_mesh_boundary_edges(m) == 6);
    CHECK(fabs(emm_mesh_mean_edge_length(m) - 1) < 1e-12);
    emm_mesh_free(m);

    /* Two fans that touch only at vertex 0 (a bow-tie) are accepted: no
     * edge is shared, every edge is boundary. */
    const double bow[] = { 0, 0, 0, 1, 1, 0, 1, -1, 0, -1, 1, 0, -1, -1, 0 };
    const int32_t bt[] = { 0, 1, 2, 0, 3, 4 };
    m = make(bow, 5, bt, 2);
    expect_neighbours(m, 0, -1, -1, -1);
    expect_neighbours(m, 1, -1, -1, -1);
    INC(0, 0, 1);
    CHECK(emm_mesh_boundary_edges(m) == 6);
    emm_mesh_free(m);
    return check_done();
}

/* A strip of six triangles over two rows:
 *   4 --- 5 --- 6 --- 7        t0 = (0 1 4)  t1 = (1 5 4)
 *   | \ t1| \ t3| \ t5|        t2 = (1 2 5)  t3 = (2 6 5)
 *   |t0 \ |t2 \ |t4 \ |        t4 = (2 3 6)  t5 = (3 7 6)
 *   0 --- 1 --- 2 --- 3
 * Shared: (1 4) t0|t1, (1 5) t1|t2, (2 5) t2|t3, (2 6) t3|t4, (3 6) t4|t5.
 * Boundary: 3 bottom + 3 top + 2 ends = 8 edges. 13 edges: 10 of length 1
 * and 3 diagonals of length sqrt(2). */
static int strip(void)
{
    const double xyz[] = { 0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0, 3, 1, 0 };
    int32_t tri[] = { 0, 1, 4, 1, 5, 4, 1, 2, 5, 2, 6, 5, 2, 3, 6, 3, 7, 6 };
    emm_mesh *m = make(xyz, 8, tri, 6);
    expect_neighbours(m, 0, -1, 1, -1);
    expect_neighbours(m, 1, 2, -1, 0);
    expect_neighbours(m, 2, -1, 3, 1);
    expect_neighbours(m, 3, 4, -1, 2);
    expect_neighbours(m, 4, -1, 5, 3);
    expect_neighbours(m, 5, -1, -1, 4);
    INC(0, 0);
    INC(1, 0, 1, 2);
    INC(2, 2, 3, 4);
    INC(3, 4, 5);
    INC(4, 0, 1);
    INC(5, 1, 2, 3);
    INC(6, 3, 4, 5);
    INC(7, 5);
    CHECK(emm_mesh_boundary_edges(m) == 8);
    CHECK(fabs(emm_mesh_mean_edge_length(m) - (10 + 3 * sqrt(2)) / 13) < 1e-15);
    emm_mesh_free(m);

    /* Orientation is not checked: t1 wound the other way, (1 4 5), still
     * finds its neighbours by undirected edge: (1 4) t0, (4 5) boundary,
     * (5 1) t2. */
    tri[4] = 4;
    tri[5] = 5;
    m = make(xyz, 8, tri, 6);
    expect_neighbours(m, 1, 0, -1, 2);
    expect_neighbours(m, 0, -1, 1, -1);
    expect_neighbours(m, 2, -1, 3, 1);
    CHECK(emm_mesh_boundary_edges(m) == 8);
    emm_mesh_free(m);
    return check_done();
}

int main(int argc, char **argv)
{
    if (argc >= 2 && strcmp(argv[1], "two_triangles") == 0)
        return two_triangles();
    if (argc >= 2 && strcmp(argv[1], "fan") == 0)
        return fan();
    if (argc >= 2 && strcmp(argv[1], "strip") == 0)
        return strip();
    fprintf(stderr, "usage: %s two_triangles|fan|strip\n", argv[0]);
    return 2;
}
