/* Layouts (thesis §4.1): the invariants every layout must keep, checked on
 * jittered-grid meshes (uniform and clustered), Delaunay meshes from the
 * generator, and hand-made tiny and degenerate ones, for the three kinds in
 * the plane and several cell sizes; and for the three in space (grid3d,
 * tiles3d, octree) on closed surfaces (a sphere, a torus, a pinched
 * sphere): every triangle in one cell, cell_at agreeing, symmetric
 * neighbour lists equal to the touching boxes, 26 and 14 neighbours inside
 * the grid and the tiles, the octree's cell limit and 2:1 face balance. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "emm/layout.h"
#include "generate.h"

typedef struct mesh {
    double *xyz;
    size_t nv;
    int32_t *tri;
    size_t nt;
} mesh;

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static double rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* An (n+1) × (m+1) jittered point grid over the unit square, two triangles
 * per quad. `warp` > 1 crowds the points towards x = 0 and y = 0 (a
 * clustered mesh). */
static mesh grid_mesh(int n, int m, double warp)
{
    mesh g;
    g.nv = (size_t)(n + 1) * (size_t)(m + 1);
    g.nt = 2 * (size_t)n * (size_t)m;
    g.xyz = malloc(3 * g.nv * sizeof *g.xyz);
    g.tri = malloc(3 * g.nt * sizeof *g.tri);
    for (int j = 0; j <= m; j++)
        for (int i = 0; i <= n; i++) {
            double x = i, y = j;
            if (i > 0 && i < n)
                x += 0.3 * (rnd() - 0.5);
            if (j > 0 && j < m)
                y += 0.3 * (rnd() - 0.5);
            size_t v = (size_t)j * (size_t)(n + 1) + (size_t)i;
            g.xyz[3 * v] = pow(x / n, warp);
            g.xyz[3 * v + 1] = pow(y / m, warp);
            g.xyz[3 * v + 2] = 0;
        }
    size_t t = 0;
    for (int j = 0; j < m; j++)
        for (int i = 0; i < n; i++) {
            int32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            int32_t q[6] = {a, b, d, a, d, c};
            memcpy(g.tri + 3 * t, q, sizeof q);
            t += 2;
        }
    return g;
}

static mesh gen_mesh(size_t faces, emm_density density, uint64_t seed)
{
    emm_gen_options opt = {faces, seed, density, EMM_ORDER_INPUT};
    emm_gen_arrays a;
    emm_error err;
    mesh g = {0};
    if (emm_gen_arrays_build(&opt, &a, &err) != EMM_OK) {
        fprintf(stderr, "generator: %s\n", err.message);
        return g;
    }
    g.xyz = a.xyz;
    g.nv = a.nv;
    g.tri = a.tri;
    g.nt = a.nt;
    return g;
}

static void mesh_free(mesh *g)
{
    free(g->xyz);
    free(g->tri);
}

static emm_layout *build(const mesh *g, emm_layout_kind kind, uint32_t cell)
{
    emm_layout_options opt = {.kind = kind, .cell = cell};
    emm_layout *l = NULL;
    emm_error err;
    emm_status st = emm_layout_build(g->xyz, g->nv, g->tri, g->nt, &opt, "test", &l, &err);
    CHECKF(st == EMM_OK, "%s", err.message);
    return l;
}

static unsigned mirror(unsigned s)
{
    unsigned m = 0;
    if (s & EMM_SIDE_LEFT)
        m |= EMM_SIDE_RIGHT;
    if (s & EMM_SIDE_RIGHT)
        m |= EMM_SIDE_LEFT;
    if (s & EMM_SIDE_TOP)
        m |= EMM_SIDE_BOTTOM;
    if (s & EMM_SIDE_BOTTOM)
        m |= EMM_SIDE_TOP;
    if (s & EMM_SIDE_NEAR)
        m |= EMM_SIDE_FAR;
    if (s & EMM_SIDE_FAR)
        m |= EMM_SIDE_NEAR;
    return m;
}

typedef struct addr_span {
    uint64_t start, len;
} addr_span;

static int cmp_span(const void *a, const void *b)
{
    const addr_span *x = a, *y = b;
    return (x->start > y->start) - (x->start < y->start);
}

static int touches(const emm_layout_cell *a, const emm_layout_cell *b, uint32_t dims, double eps)
{
    int t = 1;
    for (uint32_t k = 0; k < dims; k++)
        t = t && a->lo[k] <= b->hi[k] + eps && b->lo[k] <= a->hi[k] + eps;
    return t;
}

/* Every invariant that holds for any layout. */
static void check_layout(const emm_layout *l, const mesh *g)
{
    const emm_layout_options *opt = emm_layout_get_options(l);
    uint32_t nc = emm_layout_cell_count(l);
    REQUIRE(nc >= 1);
    int axes[EMM_MAX_DIMS];
    double blo[EMM_MAX_DIMS], bhi[EMM_MAX_DIMS];
    uint32_t dims = emm_layout_axes(l, axes, blo, bhi);
    CHECK(dims == emm_layout_kind_dims(opt->kind));
    double ext = 0;
    for (uint32_t k = 0; k < dims; k++)
        ext += fabs(bhi[k] - blo[k]);

    /* Every triangle in exactly one cell, and the index round trip. */
    uint32_t *seen = calloc(g->nt, sizeof *seen);
    int32_t *stamp = calloc(g->nv, sizeof *stamp);
    uint32_t *copies = calloc(g->nv, sizeof *copies);
    int bad_once = 0, bad_trip = 0, bad_vset = 0, bad_inside = 0, bad_at = 0;
    for (uint32_t c = 0; c < nc; c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        const uint32_t *tris, *verts;
        uint32_t ntri = emm_layout_cell_triangles(l, c, &tris);
        uint32_t nvert = emm_layout_cell_vertices(l, c, &verts);
        CHECK(ntri == cell->ntri && nvert == cell->nvert);
        for (uint32_t p = 0; p < ntri; p++) {
            uint32_t t = tris[p];
            seen[t]++;
            emm_layout_index ix = emm_layout_triangle_index(l, t);
            if (ix.cell != c || ix.pos != p || emm_layout_triangle_at(l, c, p) != t)
                bad_trip++;
            if (p > 0 && tris[p - 1] >= t)
                bad_trip++;
            /* The centroid lies in the cell's box and looks up to it. */
            double cen[EMM_MAX_DIMS];
            for (uint32_t k = 0; k < dims; k++)
                cen[k] = (g->xyz[3 * (size_t)g->tri[3 * t] + axes[k]] +
                          g->xyz[3 * (size_t)g->tri[3 * t + 1] + axes[k]] +
                          g->xyz[3 * (size_t)g->tri[3 * t + 2] + axes[k]]) / 3.0;
            double eps = 1e-9 * (1 + ext);
            for (uint32_t k = 0; k < dims; k++)
                if (cen[k] < cell->lo[k] - eps || cen[k] > cell->hi[k] + eps)
                    bad_inside++;
            if (emm_layout_cell_at(l, cen, NULL) != c)
                bad_at++;
        }
        /* The cell's vertices are exactly its triangles' vertices, once each. */
        for (uint32_t p = 0; p < nvert; p++) {
            uint32_t v = verts[p];
            if (v >= g->nv || stamp[v] == (int32_t)c + 1) {
                bad_vset++;
                continue;
            }
            stamp[v] = (int32_t)c + 1;
            copies[v]++;
            if (emm_layout_vertex_at(l, c, p) != v)
                bad_trip++;
            emm_layout_index vi = emm_layout_vertex_index(l, v, c);
            if (vi.cell != c || vi.pos != p)
                bad_trip++;
        }
        for (uint32_t p = 0; p < ntri; p++)
            for (int k = 0; k < 3; k++)
                if (stamp[g->tri[3 * (size_t)tris[p] + k]] != (int32_t)c + 1)
                    bad_vset++;
        for (uint32_t p = 0; p < nvert; p++) {
            int used = 0;
            for (uint32_t q = 0; q < ntri && !used; q++)
                for (int k = 0; k < 3; k++)
                    used |= g->tri[3 * (size_t)tris[q] + k] == (int32_t)verts[p];
            if (!used)
                bad_vset++;
        }
        for (uint32_t p = 0; p < nvert; p++)
            stamp[verts[p]] = 0;
    }
    for (size_t t = 0; t < g->nt; t++)
        if (seen[t] != 1)
            bad_once++;
    CHECKF(bad_once == 0, "%d triangles not in exactly one cell", bad_once);
    CHECKF(bad_trip == 0, "%d index round-trip failures", bad_trip);
    CHECKF(bad_vset == 0, "%d cell vertex-set errors", bad_vset);
    CHECKF(bad_inside == 0, "%d centroids outside their cell", bad_inside);
    CHECKF(bad_at == 0, "%d centroids look up to another cell", bad_at);

    /* Vertex copies: one per cell holding one of its triangles, ascending. */
    int bad_copy = 0;
    uint64_t ncopies = 0, used = 0;
    for (size_t v = 0; v < g->nv; v++) {
        const emm_layout_index *cp;
        uint32_t n = emm_layout_vertex_copies(l, (uint32_t)v, &cp);
        ncopies += n;
        used += n > 0;
        if (n != copies[v])
            bad_copy++;
        for (uint32_t k = 0; k < n; k++) {
            if (emm_layout_vertex_at(l, cp[k].cell, cp[k].pos) != v)
                bad_copy++;
            if (k > 0 && cp[k - 1].cell >= cp[k].cell)
                bad_copy++;
        }
        emm_layout_index home = emm_layout_vertex_home(l, (uint32_t)v);
        if (n > 0 ? (home.cell != cp[0].cell || home.pos != cp[0].pos)
                  : home.cell != EMM_LAYOUT_NONE)
            bad_copy++;
    }
    CHECKF(bad_copy == 0, "%d vertex copy-list errors", bad_copy);

    /* Sizes, offsets and addresses. */
    emm_layout_stats st;
    emm_layout_get_stats(l, &st);
    CHECK(st.cells == nc);
    CHECK(st.vertex_copies == ncopies);
    CHECK(st.duplicated_vertices == ncopies - used);
    CHECK(st.unused_vertices == g->nv - used);
    /* A triangle's slot: its record, then its 3 pointers to its vertices'
     * copies (thesis §4.1.1). */
    const uint64_t ptrs = 3ull * opt->pointer_bytes, slot = opt->triangle_bytes + ptrs;
    CHECK(opt->pointer_bytes >= 1 && st.triangle_slot_bytes == slot);
    uint64_t off = 0;
    int bad_size = 0;
    for (uint32_t c = 0; c < nc; c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        if (cell->bytes != 12u + (uint64_t)cell->nvert * opt->vertex_bytes +
                               (uint64_t)cell->ntri * slot)
            bad_size++;
        if (cell->offset != off)
            bad_size++;
        off += cell->bytes;
    }
    CHECKF(bad_size == 0, "%d cell size/offset errors", bad_size);
    CHECK(emm_layout_image_bytes(l) == off + (g->nv - used) * opt->vertex_bytes);

    size_t nspan = nc + 2 * g->nt + ncopies + (g->nv - used), ns = 0;
    addr_span *sp = malloc(nspan * sizeof *sp);
    int bad_addr = 0;
    for (uint32_t c = 0; c < nc; c++)
        sp[ns++] = (addr_span){emm_layout_cell_get(l, c)->offset, 12};
    for (size_t t = 0; t < g->nt; t++) {
        uint64_t a = emm_layout_triangle_address(l, (uint32_t)t, 0);
        uint64_t z = emm_layout_triangle_address(l, (uint32_t)t, opt->triangle_bytes - 1);
        const emm_layout_cell *cell = emm_layout_cell_get(l, emm_layout_triangle_index(l, (uint32_t)t).cell);
        if (z != a + opt->triangle_bytes - 1 || a < cell->offset + 12 ||
            z + ptrs >= cell->offset + cell->bytes)
            bad_addr++;
        sp[ns++] = (addr_span){a, opt->triangle_bytes};
        sp[ns++] = (addr_span){a + opt->triangle_bytes, ptrs}; /* its pointers */
    }
    for (size_t v = 0; v < g->nv; v++) {
        const emm_layout_index *cp;
        uint32_t n = emm_layout_vertex_copies(l, (uint32_t)v, &cp);
        for (uint32_t k = 0; k < n; k++) {
            uint64_t a = emm_layout_vertex_address(l, (uint32_t)v, cp[k].cell, 0);
            const emm_layout_cell *cell = emm_layout_cell_get(l, cp[k].cell);
            if (a < cell->offset + 12 || a + opt->vertex_bytes > cell->offset + cell->bytes)
                bad_addr++;
            sp[ns++] = (addr_span){a, opt->vertex_bytes};
        }
        if (n == 0) {
            uint64_t a = emm_layout_vertex_address(l, (uint32_t)v, EMM_LAYOUT_NONE, 0);
            if (a < off || a + opt->vertex_bytes > emm_layout_image_bytes(l))
                bad_addr++;
            sp[ns++] = (addr_span){a, opt->vertex_bytes};
        } else if (emm_layout_vertex_address(l, (uint32_t)v, EMM_LAYOUT_NONE, 3) !=
                   emm_layout_vertex_address(l, (uint32_t)v, cp[0].cell, 3)) {
            bad_addr++;
        }
    }
    REQUIRE(ns == nspan);
    qsort(sp, ns, sizeof *sp, cmp_span);
    /* Records, pointers and headers tile the image exactly: unique, no
     * overlap, no gap. */
    uint64_t at = 0;
    for (size_t i = 0; i < ns; i++) {
        if (sp[i].start != at)
            bad_addr++;
        at = sp[i].start + sp[i].len;
    }
    CHECK(at == emm_layout_image_bytes(l));
    CHECKF(bad_addr == 0, "%d address errors", bad_addr);
    free(sp);

    /* Neighbours: ascending, no self, symmetric, mirrored sides, and exactly
     * the cells whose rectangles touch (checked by brute force when small). */
    int bad_nb = 0;
    for (uint32_t c = 0; c < nc; c++) {
        const uint32_t *nb;
        const uint8_t *side;
        uint32_t n = emm_layout_neighbors(l, c, &nb, &side);
        for (uint32_t k = 0; k < n; k++) {
            if (nb[k] == c || (k > 0 && nb[k - 1] >= nb[k]) || side[k] == 0)
                bad_nb++;
            if (side[k] != emm_layout_move_side(l, c, nb[k]))
                bad_nb++;
            if (mirror(side[k]) != emm_layout_move_side(l, nb[k], c))
                bad_nb++;
            const uint32_t *back;
            uint32_t nback = emm_layout_neighbors(l, nb[k], &back, NULL);
            int found = 0;
            for (uint32_t j = 0; j < nback; j++)
                found |= back[j] == c;
            if (!found)
                bad_nb++;
        }
    }
    CHECKF(bad_nb == 0, "%d neighbour errors", bad_nb);
    if (nc <= 3000) {
        int bad_touch = 0;
        for (uint32_t a = 0; a < nc; a++) {
            const uint32_t *nb;
            uint32_t n = emm_layout_neighbors(l, a, &nb, NULL), k = 0;
            const emm_layout_cell *ca = emm_layout_cell_get(l, a);
            /* Cells that do not touch are at least a finest tree square
             * or cube (2^-24, 2^-21 of the box) apart. */
            double eps = 1e-12 * (ext > 1 ? ext : 1);
            for (uint32_t b = 0; b < nc; b++) {
                if (b == a)
                    continue;
                int t = touches(ca, emm_layout_cell_get(l, b), dims, eps);
                int listed = k < n && nb[k] == b;
                k += listed;
                if (t != listed)
                    bad_touch++;
            }
        }
        CHECKF(bad_touch == 0, "%d neighbour lists differ from touching rectangles", bad_touch);
    }
    free(seen);
    free(stamp);
    free(copies);
}

/* The ring the fetch schemes prefetch from: in the plane the neighbour
 * list itself; in space exactly the neighbours that hold a copy of one of
 * the cell's vertices, in the neighbours' order and with their sides.
 * Returns the ring entries less the neighbour entries (0 in the plane). */
static uint64_t check_ring(const emm_layout *l)
{
    uint32_t nc = emm_layout_cell_count(l);
    uint64_t nb_total = 0, ring_total = 0;
    int bad = 0;
    for (uint32_t c = 0; c < nc; c++) {
        const uint32_t *nb, *ring, *verts;
        const uint8_t *nside, *rside;
        uint32_t n = emm_layout_neighbors(l, c, &nb, &nside);
        uint32_t r = emm_layout_ring(l, c, &ring, &rside), k = 0;
        uint32_t nv = emm_layout_cell_vertices(l, c, &verts);
        nb_total += n;
        ring_total += r;
        for (uint32_t i = 0; i < n; i++) {
            int shares = 0;
            for (uint32_t j = 0; j < nv && !shares; j++) {
                const emm_layout_index *cp;
                uint32_t m = emm_layout_vertex_copies(l, verts[j], &cp);
                for (uint32_t q = 0; q < m; q++)
                    shares |= cp[q].cell == nb[i];
            }
            int in = k < r && ring[k] == nb[i];
            if (in && rside[k] != nside[i])
                bad++;
            k += (uint32_t)in;
            if (emm_layout_axes(l, NULL, NULL, NULL) == 2 ? !in : in != shares)
                bad++;
        }
        if (k != r)
            bad++;
    }
    CHECKF(bad == 0, "%d ring entries differ from the neighbours sharing a vertex", bad);
    return nb_total - ring_total;
}

/* Interior grid cells have 8 neighbours, interior tiles 6; sides per §4.2.2. */
static void check_grid_shape(const emm_layout *l)
{
    uint32_t per[EMM_MAX_DIMS];
    CHECK(emm_layout_cells_per_axis(l, per) == 2);
    uint32_t cols = per[0], rows = per[1];
    int tiles = emm_layout_get_options(l)->kind == EMM_LAYOUT_TILES;
    int interior = 0, bad = 0;
    for (uint32_t c = 0; c < emm_layout_cell_count(l); c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        uint32_t len = tiles ? cols + ((uint32_t)cell->coord[1] & 1u) : cols;
        if (cell->coord[1] == 0 || (uint32_t)cell->coord[1] + 1 >= rows || cell->coord[0] == 0 ||
            (uint32_t)cell->coord[0] + 1 >= len)
            continue;
        interior++;
        const uint8_t *side;
        uint32_t n = emm_layout_neighbors(l, c, NULL, &side);
        int count[4] = {0};
        for (uint32_t k = 0; k < n; k++)
            for (int b = 0; b < 4; b++)
                count[b] += (side[k] >> b) & 1;
        if (!tiles) {
            /* left, top, right, bottom: 3 cells each (corners count twice). */
            if (n != 8 || count[0] != 3 || count[1] != 3 || count[2] != 3 || count[3] != 3)
                bad++;
        } else {
            /* left and right 3 (row + diagonals), top and bottom 2. */
            if (n != 6 || count[0] != 3 || count[1] != 2 || count[2] != 3 || count[3] != 2)
                bad++;
        }
    }
    CHECKF(bad == 0, "%d interior cells with the wrong neighbours", bad);
    if (cols >= 3 && rows >= 3)
        CHECK(interior > 0);
}

/* Quadtree: leaf limit (except at the maximum depth), 3-level balance
 * between touching leaves, paths that spell each leaf's square. */
static void check_quadtree(const emm_layout *l, uint32_t cell_limit, uint32_t *depth_span)
{
    int bad_limit = 0, bad_gap = 0, bad_path = 0;
    uint32_t dmin = UINT32_MAX, dmax = 0;
    double area = 0;
    for (uint32_t c = 0; c < emm_layout_cell_count(l); c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        if (cell->ntri > cell_limit && cell->depth < EMM_LAYOUT_MAX_DEPTH)
            bad_limit++;
        dmin = cell->depth < dmin ? cell->depth : dmin;
        dmax = cell->depth > dmax ? cell->depth : dmax;
        area += ldexp(1.0, -2 * (int)cell->depth);
        const uint32_t *nb;
        uint32_t n = emm_layout_neighbors(l, c, &nb, NULL);
        for (uint32_t k = 0; k < n; k++) {
            uint32_t d2 = emm_layout_cell_get(l, nb[k])->depth;
            if ((d2 > cell->depth ? d2 - cell->depth : cell->depth - d2) > 3)
                bad_gap++;
        }
        /* The path's digits give the square's position from the root. */
        uint32_t ix = 0, iy = 0;
        for (uint32_t d = 0; d < cell->depth; d++) {
            uint64_t k = (cell->path >> (2 * (cell->depth - 1 - d))) & 3u;
            ix = 2 * ix + (uint32_t)(k & 1u);
            iy = 2 * iy + (uint32_t)(k >> 1);
        }
        uint32_t levels;
        double mid[2] = {(cell->lo[0] + cell->hi[0]) / 2, (cell->lo[1] + cell->hi[1]) / 2};
        if (emm_layout_cell_at(l, mid, &levels) != c || levels != cell->depth)
            bad_path++;
        double size = cell->hi[0] - cell->lo[0];
        double lo[EMM_MAX_DIMS], hi[EMM_MAX_DIMS];
        emm_layout_axes(l, NULL, lo, hi);
        double tol = 1e-12 * (1 + hi[0] - lo[0] + hi[1] - lo[1]);
        if (fabs(cell->lo[0] - (lo[0] + ix * size)) > tol ||
            fabs(cell->lo[1] - (lo[1] + iy * size)) > tol)
            bad_path++;
    }
    CHECKF(bad_limit == 0, "%d leaves above the cell limit", bad_limit);
    CHECKF(bad_gap == 0, "%d touching leaves more than 3 levels apart", bad_gap);
    CHECKF(bad_path == 0, "%d leaves whose path or look-up disagrees", bad_path);
    CHECKF(fabs(area - 1.0) < 1e-12, "leaves cover %.15f of the square", area);
    if (depth_span)
        *depth_span = dmax - dmin;
}

static void check_all(const mesh *g, const char *what, uint32_t cell)
{
    static const emm_layout_kind kinds[] = {EMM_LAYOUT_GRID, EMM_LAYOUT_TILES,
                                            EMM_LAYOUT_QUADTREE};
    for (int k = 0; k < 3; k++) {
        emm_layout *l = build(g, kinds[k], cell);
        if (!l)
            continue;
        check_layout(l, g);
        CHECK(check_ring(l) == 0);
        if (kinds[k] == EMM_LAYOUT_QUADTREE)
            check_quadtree(l, cell, NULL);
        else
            check_grid_shape(l);
        emm_layout_stats st;
        emm_layout_get_stats(l, &st);
        printf("%-9s %-8s cell %-4u: %6u cells, tri %u/%u/%u, bytes %llu/%llu/%llu, dup %llu, "
               "depth %u..%u\n",
               what, emm_layout_name(kinds[k]), cell, st.cells, st.tri_min, st.tri_median,
               st.tri_max, (unsigned long long)st.bytes_min, (unsigned long long)st.bytes_median,
               (unsigned long long)st.bytes_max, (unsigned long long)st.duplicated_vertices,
               st.depth_min, st.depth_max);
        emm_layout_free(l);
    }
}

/* ---- layouts in space ------------------------------------------------ */

/* A closed surface of revolution, (n lat) x (m lon) quads with jittered
 * vertices: kind 0 a sphere of radius 1, 1 a torus (radii 1 and 0.35), 2 a
 * sphere pinched towards one pole (dense triangles there). */
static mesh surface_mesh(int n, int m, int kind)
{
    mesh g;
    int torus = kind == 1;
    int rows = torus ? n : n - 1; /* vertex rings; a sphere adds 2 poles */
    g.nv = (size_t)rows * (size_t)m + (torus ? 0 : 2);
    g.nt = 2 * (size_t)n * (size_t)m - (torus ? 0 : 2 * (size_t)m);
    g.xyz = malloc(3 * g.nv * sizeof *g.xyz);
    g.tri = malloc(3 * g.nt * sizeof *g.tri);
    const double pi = 3.14159265358979323846;
    for (int i = 0; i < rows; i++)
        for (int j = 0; j < m; j++) {
            double u = (i + (torus ? 0 : 1) + 0.2 * (rnd() - 0.5)) / n;
            double v = (j + 0.2 * (rnd() - 0.5)) / m;
            double *p = g.xyz + 3 * ((size_t)i * (size_t)m + (size_t)j);
            if (torus) {
                double r = 1 + 0.35 * cos(2 * pi * u);
                p[0] = r * cos(2 * pi * v);
                p[1] = r * sin(2 * pi * v);
                p[2] = 0.35 * sin(2 * pi * u);
            } else {
                double th = pi * (kind == 2 ? pow(u, 2.5) : u);
                p[0] = sin(th) * cos(2 * pi * v);
                p[1] = sin(th) * sin(2 * pi * v);
                p[2] = cos(th);
            }
        }
    size_t t = 0;
    int32_t north = (int32_t)(rows * m), south = north + 1;
    if (!torus) {
        double *p = g.xyz + 3 * (size_t)north;
        p[0] = p[1] = 0, p[2] = 1;
        p = g.xyz + 3 * (size_t)south;
        p[0] = p[1] = 0, p[2] = -1;
        for (int j = 0; j < m; j++) {
            int32_t a = j, b = (j + 1) % m;
            int32_t q[3] = {north, a, b};
            memcpy(g.tri + 3 * t++, q, sizeof q);
            int32_t c = (rows - 1) * m + j, d = (rows - 1) * m + (j + 1) % m;
            int32_t r[3] = {south, d, c};
            memcpy(g.tri + 3 * t++, r, sizeof r);
        }
    }
    for (int i = 0; i < (torus ? n : rows - 1); i++)
        for (int j = 0; j < m; j++) {
            int32_t a = i * m + j, b = i * m + (j + 1) % m;
            int32_t c = ((i + 1) % rows) * m + j, d = ((i + 1) % rows) * m + (j + 1) % m;
            int32_t q[6] = {a, c, d, a, d, b};
            memcpy(g.tri + 3 * t, q, sizeof q);
            t += 2;
        }
    g.nt = t;
    return g;
}

/* Interior boxes of the 3D grid have 26 neighbours, of the 3D tiles 14 (2
 * in the row, 4 in the rows beside it, 4 in each layer beside it), when
 * every box holds triangles; otherwise the boxes without triangles are no
 * cells and no neighbours, so an interior box has at most as many, and at
 * most 9 (grid) or 4 (tiles, near and far) on a side. Every cell holds
 * triangles, which hold CELL on average, at most. */
static void check_boxes_shape(const emm_layout *l, const mesh *g, uint32_t cell_limit)
{
    uint32_t per[EMM_MAX_DIMS];
    CHECK(emm_layout_cells_per_axis(l, per) == 3);
    int tiles = emm_layout_get_options(l)->kind == EMM_LAYOUT_TILES3D;
    int interior = 0, bad = 0;
    emm_layout_stats st;
    emm_layout_get_stats(l, &st);
    uint32_t occupied = 0;
    for (uint32_t c = 0; c < emm_layout_cell_count(l); c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        occupied += cell->ntri > 0;
        uint32_t i = (uint32_t)cell->coord[0], j = (uint32_t)cell->coord[1],
                 k = (uint32_t)cell->coord[2];
        uint32_t rows = per[1] + (tiles ? (k & 1u) : 0u);
        uint32_t len = per[0] + (tiles ? ((j | k) & 1u) : 0u);
        if (k == 0 || k + 1 >= per[2] || j <= 1 || j + 2 >= rows || i <= 1 || i + 2 >= len)
            continue;
        interior++;
        const uint8_t *side;
        uint32_t n = emm_layout_neighbors(l, c, NULL, &side);
        int count[6] = {0};
        for (uint32_t q = 0; q < n; q++)
            for (int b = 0; b < 6; b++)
                count[b] += (side[q] >> b) & 1;
        int full = st.dropped_cells == 0;
        if (!tiles) {
            /* 9 boxes on each of the 6 sides. */
            int ok = full ? n == 26 : n <= 26;
            for (int b = 0; b < 6; b++)
                ok = ok && (full ? count[b] == 9 : count[b] <= 9);
            bad += !ok;
        } else {
            /* Near and far: the 4 of each layer. */
            bad += full ? n != 14 || count[4] != 4 || count[5] != 4
                        : n > 14 || count[4] > 4 || count[5] > 4;
        }
    }
    CHECKF(bad == 0, "%d interior boxes with the wrong neighbours", bad);
    if (st.dropped_cells == 0 && per[0] >= 5 && per[1] >= 5 && per[2] >= 3)
        CHECK(interior > 0);
    CHECKF(occupied == emm_layout_cell_count(l), "%u of %u cells hold triangles", occupied,
           emm_layout_cell_count(l));
    uint64_t boxes = tiles ? 0 : (uint64_t)per[0] * per[1] * per[2];
    if (!tiles)
        CHECKF(occupied + st.dropped_cells == boxes, "%u cells and %u dropped of %llu boxes",
               occupied, st.dropped_cells, (unsigned long long)boxes);
    REQUIRE(occupied > 0);
    double mean = (double)g->nt / occupied;
    CHECKF(mean <= cell_limit * 1.0001 && (g->nt < 4 * cell_limit || mean >= cell_limit / 3.0),
           "boxes holding triangles hold %.1f on average, CELL %u", mean, cell_limit);
}

/* Octree: leaf limit (except at the maximum depth), leaves sharing a face
 * at most 1 level apart, paths that spell each leaf's cube, leaves that
 * fill the cube with those dropped for holding no triangles, and every
 * cell holding triangles. */
static void check_octree(const emm_layout *l, uint32_t cell_limit)
{
    int bad_limit = 0, bad_gap = 0, bad_path = 0;
    double volume = 0;
    double lo[EMM_MAX_DIMS], hi[EMM_MAX_DIMS];
    emm_layout_axes(l, NULL, lo, hi);
    double tol = 1e-12 * (1 + hi[0] - lo[0] + hi[1] - lo[1] + hi[2] - lo[2]);
    for (uint32_t c = 0; c < emm_layout_cell_count(l); c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        if (cell->ntri > cell_limit && cell->depth < EMM_LAYOUT_OCTREE_MAX_DEPTH)
            bad_limit++;
        volume += ldexp(1.0, -3 * (int)cell->depth);
        const uint32_t *nb;
        uint32_t n = emm_layout_neighbors(l, c, &nb, NULL);
        for (uint32_t q = 0; q < n; q++) {
            const emm_layout_cell *o = emm_layout_cell_get(l, nb[q]);
            /* A shared face: the boxes meet along one axis and overlap with
             * positive length along both others. */
            int meet = 0, overlap = 0;
            for (int a = 0; a < 3; a++) {
                double in = fmin(cell->hi[a], o->hi[a]) - fmax(cell->lo[a], o->lo[a]);
                meet += fabs(in) <= tol;
                overlap += in > tol;
            }
            uint32_t gap = o->depth > cell->depth ? o->depth - cell->depth : cell->depth - o->depth;
            if (meet == 1 && overlap == 2 && gap > EMM_LAYOUT_OCTREE_LEVEL_GAP)
                bad_gap++;
        }
        uint32_t ix[3] = {0, 0, 0};
        for (uint32_t d = 0; d < cell->depth; d++) {
            uint64_t k = (cell->path >> (3 * (cell->depth - 1 - d))) & 7u;
            for (int a = 0; a < 3; a++)
                ix[a] = 2 * ix[a] + (uint32_t)((k >> a) & 1u);
        }
        double size = cell->hi[0] - cell->lo[0];
        double mid[3];
        for (int a = 0; a < 3; a++) {
            mid[a] = (cell->lo[a] + cell->hi[a]) / 2;
            if (fabs(cell->lo[a] - (lo[a] + ix[a] * size)) > tol ||
                fabs(cell->hi[a] - cell->lo[a] - size) > tol)
                bad_path++;
        }
        uint32_t levels;
        if (emm_layout_cell_at(l, mid, &levels) != c || levels != cell->depth)
            bad_path++;
    }
    CHECKF(bad_limit == 0, "%d leaves above the cell limit", bad_limit);
    CHECKF(bad_gap == 0, "%d leaves sharing a face more than 1 level apart", bad_gap);
    CHECKF(bad_path == 0, "%d leaves whose path or look-up disagrees", bad_path);
    emm_layout_stats st;
    emm_layout_get_stats(l, &st);
    if (st.dropped_cells == 0)
        CHECKF(fabs(volume - 1.0) < 1e-12, "leaves fill %.15f of the cube", volume);
    else
        CHECKF(volume < 1.0, "leaves fill %.15f of the cube with %u dropped", volume,
               st.dropped_cells);
    CHECKF(st.empty_cells == 0, "%u octree cells without triangles", st.empty_cells);
    CHECK(st.quadtree_nodes >= st.cells + st.dropped_cells);
}

static void check_all3d(const mesh *g, const char *what, uint32_t cell)
{
    static const emm_layout_kind kinds[] = {EMM_LAYOUT_GRID3D, EMM_LAYOUT_TILES3D,
                                            EMM_LAYOUT_OCTREE};
    for (int k = 0; k < 3; k++) {
        emm_layout *l = build(g, kinds[k], cell);
        if (!l)
            continue;
        check_layout(l, g);
        uint64_t outside = check_ring(l);
        if (kinds[k] == EMM_LAYOUT_OCTREE)
            check_octree(l, cell);
        else
            check_boxes_shape(l, g, cell);
        emm_layout_stats st;
        emm_layout_get_stats(l, &st);
        printf("%-9s %-8s cell %-4u: %6u cells (%u dropped), tri %u/%u/%u, dup %llu, depth %u..%u, "
               "%llu neighbours off the ring\n",
               what, emm_layout_name(kinds[k]), cell, st.cells, st.dropped_cells, st.tri_min,
               st.tri_median, st.tri_max, (unsigned long long)st.duplicated_vertices,
               st.depth_min, st.depth_max, (unsigned long long)outside);
        /* A closed surface passes near boxes it does not enter from a
         * cell: some neighbours are off every ring. */
        if (strcmp(what, "sphere") == 0 && cell == 16)
            CHECKF(outside > 0, "sphere: %s's rings are its neighbour lists", emm_layout_name(kinds[k]));
        emm_layout_free(l);
    }
}

/* n x n x n tiny triangles on a jittered lattice in the unit cube: centroids
 * that fill space, so that every box and octant holds triangles. */
static mesh cloud_mesh(int n)
{
    mesh g;
    g.nt = (size_t)n * (size_t)n * (size_t)n;
    g.nv = 3 * g.nt;
    g.xyz = malloc(3 * g.nv * sizeof *g.xyz);
    g.tri = malloc(3 * g.nt * sizeof *g.tri);
    size_t t = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            for (int k = 0; k < n; k++, t++) {
                double c[3] = {(i + 0.5 + 0.3 * (rnd() - 0.5)) / n,
                               (j + 0.5 + 0.3 * (rnd() - 0.5)) / n,
                               (k + 0.5 + 0.3 * (rnd() - 0.5)) / n};
                for (int v = 0; v < 3; v++) {
                    double *p = g.xyz + 3 * (3 * t + (size_t)v);
                    for (int a = 0; a < 3; a++)
                        p[a] = c[a] + (a == v ? 0.01 / n : 0);
                    g.tri[3 * t + (size_t)v] = (int32_t)(3 * t + (size_t)v);
                }
            }
    return g;
}

/* A closed surface has depth; a planar mesh, or one barely off its plane,
 * has none, and its sweep is the standard one. */
static void test_depth(void)
{
    mesh s = surface_mesh(12, 16, 0), t = surface_mesh(12, 16, 1), p = grid_mesh(10, 10, 1.0);
    CHECK(emm_geometry_has_depth(s.xyz, s.nv, s.tri, s.nt));
    CHECK(emm_geometry_has_depth(t.xyz, t.nv, t.tri, t.nt));
    CHECK(!emm_geometry_has_depth(p.xyz, p.nv, p.tri, p.nt));
    for (size_t v = 0; v < p.nv; v++) /* a height field 5% of its width high */
        p.xyz[3 * v + 2] = 0.05 * sin(7 * p.xyz[3 * v]);
    CHECK(!emm_geometry_has_depth(p.xyz, p.nv, p.tri, p.nt));
    for (size_t v = 0; v < p.nv; v++) /* ... and 30% */
        p.xyz[3 * v + 2] *= 6;
    CHECK(emm_geometry_has_depth(p.xyz, p.nv, p.tri, p.nt));
    CHECK(!emm_geometry_has_depth(s.xyz, s.nv, s.tri, 0));
    mesh_free(&s);
    mesh_free(&t);
    mesh_free(&p);
}

/* Grid and tiles choose about ceil(nt / cell) cells in square-ish cells. */
static void test_cell_counts(void)
{
    mesh g = grid_mesh(60, 30, 1.0); /* 3600 triangles */
    for (uint32_t cell = 16; cell <= 256; cell *= 2) {
        emm_layout *l = build(&g, EMM_LAYOUT_GRID, cell);
        REQUIRE(l);
        uint32_t want = (uint32_t)((g.nt + cell - 1) / cell), n[EMM_MAX_DIMS];
        emm_layout_cells_per_axis(l, n);
        uint32_t cols = n[0];
        CHECKF(emm_layout_cell_count(l) >= want && emm_layout_cell_count(l) < want + cols + 1,
               "cell %u: %u cells for %u wanted", cell, emm_layout_cell_count(l), want);
        const emm_layout_cell *c0 = emm_layout_cell_get(l, 0);
        double w = c0->hi[0] - c0->lo[0], h = c0->hi[1] - c0->lo[1];
        CHECKF(w / h < 2.5 && h / w < 2.5, "cell %u: %g x %g cells", cell, w, h);
        emm_layout_free(l);
    }
    mesh_free(&g);
}

/* The quadtree adapts: on a clustered mesh its leaves span several levels,
 * and the balance rule still holds. With cell = 1 the leaves go deep. */
static void test_quadtree_adapts(void)
{
    mesh g = grid_mesh(40, 40, 4.0);
    emm_layout *l = build(&g, EMM_LAYOUT_QUADTREE, 4);
    REQUIRE(l);
    uint32_t span;
    check_quadtree(l, 4, &span);
    CHECKF(span >= 4, "depths span only %u levels on a clustered mesh", span);
    emm_layout_free(l);
    mesh_free(&g);
}

/* A clump of identical centroids cannot be split: it stops at the maximum
 * depth and is reported overfull. */
static void test_quadtree_max_depth(void)
{
    mesh g = grid_mesh(4, 4, 1.0); /* 32 triangles */
    size_t nt = g.nt + 20;
    g.tri = realloc(g.tri, 3 * nt * sizeof *g.tri);
    for (size_t t = g.nt; t < nt; t++) /* 20 copies of triangle 0 */
        memcpy(g.tri + 3 * t, g.tri, 3 * sizeof *g.tri);
    g.nt = nt;
    emm_layout *l = build(&g, EMM_LAYOUT_QUADTREE, 4);
    REQUIRE(l);
    check_layout(l, &g);
    check_quadtree(l, 4, NULL);
    emm_layout_stats st;
    emm_layout_get_stats(l, &st);
    CHECK(st.depth_max == EMM_LAYOUT_MAX_DEPTH);
    CHECK(st.overfull_leaves == 1);
    CHECK(st.tri_max == 21);
    emm_layout_free(l);
    mesh_free(&g);
}

static void test_errors(void)
{
    mesh g = grid_mesh(20, 20, 1.0);
    emm_layout_options opt = {.kind = EMM_LAYOUT_TILES, .cell = 256, .local_store = 4096,
                              .fetch = EMM_FETCH_CONVOLUTION};
    emm_layout *l = (emm_layout *)&g; /* must be reset to NULL on failure */
    emm_error err;
    CHECK(emm_layout_build(g.xyz, g.nv, g.tri, g.nt, &opt, "m.off", &l, &err) == EMM_ERR_RANGE);
    CHECK(l == NULL);
    printf("too-large cell: %s\n", err.message);
    CHECK(strstr(err.message, "m.off: tiles cell ") == err.message);
    CHECK(strstr(err.message, "4,096-byte local store") != NULL);
    CHECK(strstr(err.message, "smaller CELL than 256 (e.g. tiles+convolution@") != NULL);
    /* The suggestion is a CELL that fits. */
    const char *at = strstr(err.message, "convolution@");
    REQUIRE(at);
    opt.cell = (uint32_t)strtoul(at + strlen("convolution@"), NULL, 10);
    CHECK(opt.cell >= 1 && opt.cell < 256);
    CHECKF(emm_layout_build(g.xyz, g.nv, g.tri, g.nt, &opt, "m.off", &l, &err) == EMM_OK,
           "suggested cell %u: %s", opt.cell, err.message);
    emm_layout_free(l);

    opt = (emm_layout_options){.kind = EMM_LAYOUT_GRID, .cell = 64};
    CHECK(emm_layout_build(g.xyz, g.nv, g.tri, 0, &opt, "m", &l, &err) == EMM_ERR_INVALID);
    opt.cell = 0;
    CHECK(emm_layout_build(g.xyz, g.nv, g.tri, g.nt, &opt, "m", &l, &err) == EMM_ERR_INVALID);
    opt.cell = 64;
    int32_t saved = g.tri[7];
    g.tri[7] = (int32_t)g.nv;
    CHECK(emm_layout_build(g.xyz, g.nv, g.tri, g.nt, &opt, "m", &l, &err) == EMM_ERR_MESH);
    CHECK(strstr(err.message, "triangle 2 refers to vertex") != NULL);
    g.tri[7] = -1;
    CHECK(emm_layout_build(g.xyz, g.nv, g.tri, g.nt, &opt, "m", &l, &err) == EMM_ERR_MESH);
    g.tri[7] = saved;
    g.xyz[4] = NAN;
    CHECK(emm_layout_build(g.xyz, g.nv, g.tri, g.nt, &opt, "m", &l, &err) == EMM_ERR_MESH);
    CHECK(strstr(err.message, "vertex 1 has a non-finite") != NULL);
    mesh_free(&g);
}

/* Degenerate boxes (a line, a point), a 3D mesh in the x-z plane, tiny
 * meshes, unused vertices. */
static void test_degenerate(void)
{
    /* Collinear: every point on y = 0. */
    mesh line = grid_mesh(30, 2, 1.0);
    for (size_t v = 0; v < line.nv; v++)
        line.xyz[3 * v + 1] = 0;
    check_all(&line, "line", 8);
    /* A single point. */
    for (size_t v = 0; v < line.nv; v++)
        line.xyz[3 * v] = 0.5;
    check_all(&line, "point", 8);
    mesh_free(&line);

    /* The x-z plane: the layout works in axes 0 and 2. */
    mesh xz = grid_mesh(10, 10, 1.0);
    for (size_t v = 0; v < xz.nv; v++) {
        xz.xyz[3 * v + 2] = xz.xyz[3 * v + 1] * 3;
        xz.xyz[3 * v + 1] = 7 + 0.01 * xz.xyz[3 * v];
    }
    emm_layout *l = build(&xz, EMM_LAYOUT_GRID, 8);
    REQUIRE(l);
    int axes[EMM_MAX_DIMS];
    emm_layout_axes(l, axes, NULL, NULL);
    CHECK(axes[0] == 0 && axes[1] == 2);
    check_layout(l, &xz);
    emm_layout_free(l);
    check_all(&xz, "xz-plane", 8);
    mesh_free(&xz);

    /* One triangle, and two triangles sharing an edge, plus an unused vertex. */
    double xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 5, 5, 5};
    int32_t tri[] = {0, 1, 2, 1, 3, 2};
    mesh tiny = {xyz, 5, tri, 1};
    check_all(&tiny, "one", 1);
    tiny.nt = 2;
    check_all(&tiny, "two", 1);
    check_all(&tiny, "two", 64);
    l = build(&tiny, EMM_LAYOUT_QUADTREE, 1);
    REQUIRE(l);
    CHECK(emm_layout_vertex_copies(l, 4, NULL) == 0);
    CHECK(emm_layout_vertex_home(l, 4).cell == EMM_LAYOUT_NONE);
    emm_layout_stats st;
    emm_layout_get_stats(l, &st);
    CHECK(st.unused_vertices == 1);
    CHECK(st.duplicated_vertices == st.vertex_copies - 4);
    CHECK(emm_layout_vertex_address(l, 4, 0, 0) + 80 == emm_layout_image_bytes(l));
    emm_layout_free(l);
}

/* Record sizes from the trace: cell bytes follow them. */
static void test_record_sizes(void)
{
    mesh g = grid_mesh(12, 12, 2.0);
    emm_layout_options opt = {.kind = EMM_LAYOUT_QUADTREE, .cell = 16, .vertex_bytes = 24,
                              .triangle_bytes = 12};
    emm_layout *l;
    emm_error err;
    REQUIRE(emm_layout_build(g.xyz, g.nv, g.tri, g.nt, &opt, "g", &l, &err) == EMM_OK);
    CHECK(emm_layout_get_options(l)->vertex_bytes == 24);
    check_layout(l, &g);
    const emm_layout_cell *c = emm_layout_cell_get(l, emm_layout_triangle_index(l, 0).cell);
    /* The triangle's pointers default to 4 bytes each (the 32-bit core). */
    CHECK(emm_layout_triangle_slot_bytes(l) == 12 + 3 * 4);
    CHECK(c->bytes == 12 + 24u * c->nvert + (12u + 12u) * c->ntri);
    /* Look-up accounting: 4 B per triangle and vertex, 8 per cell, 16 per node. */
    emm_layout_stats st;
    emm_layout_get_stats(l, &st);
    CHECK(emm_layout_lookup_bytes(l) ==
          4 * g.nt + 4 * g.nv + 8ull * st.cells + 16ull * st.quadtree_nodes);
    CHECK(st.quadtree_nodes >= st.cells && (st.quadtree_nodes - 1) % 4 == 0);
    emm_layout_free(l);
    /* A 64-bit machine's pointers: 8 bytes each. */
    opt.pointer_bytes = 8;
    REQUIRE(emm_layout_build(g.xyz, g.nv, g.tri, g.nt, &opt, "g", &l, &err) == EMM_OK);
    check_layout(l, &g);
    CHECK(emm_layout_triangle_slot_bytes(l) == 12 + 3 * 8);
    c = emm_layout_cell_get(l, emm_layout_triangle_index(l, 0).cell);
    CHECK(c->bytes == 12 + 24u * c->nvert + (12u + 24u) * c->ntri);
    emm_layout_free(l);
    mesh_free(&g);
}

int main(void)
{
    static const uint32_t cells[] = {1, 4, 16, 64, 256};
    mesh u = grid_mesh(30, 20, 1.0);
    mesh c = grid_mesh(30, 30, 3.0);
    for (size_t i = 0; i < sizeof cells / sizeof cells[0]; i++) {
        check_all(&u, "uniform", cells[i]);
        check_all(&c, "warped", cells[i]);
    }
    mesh_free(&u);
    mesh_free(&c);

    static const struct {
        size_t faces;
        emm_density density;
    } gens[] = {{2000, EMM_DENSITY_CLUSTERED}, {2000, EMM_DENSITY_UNIFORM},
                {20000, EMM_DENSITY_CLUSTERED}};
    for (size_t i = 0; i < sizeof gens / sizeof gens[0]; i++) {
        mesh g = gen_mesh(gens[i].faces, gens[i].density, 1);
        REQUIRE(g.nt > 0);
        const char *what = gens[i].density == EMM_DENSITY_CLUSTERED ? "clustered" : "uniform";
        check_all(&g, what, 16);
        check_all(&g, what, 64);
        mesh_free(&g);
    }

    /* Layouts in space, on closed surfaces. */
    for (int kind = 0; kind < 3; kind++) {
        mesh g = surface_mesh(kind == 1 ? 24 : 30, 40, kind);
        const char *what = kind == 0 ? "sphere" : kind == 1 ? "torus" : "pinched";
        check_all3d(&g, what, 4);
        check_all3d(&g, what, 16);
        check_all3d(&g, what, 64);
        mesh_free(&g);
    }
    /* Centroids that fill space: no box or octant is dropped, and the
     * interior boxes have all their neighbours. */
    mesh cloud = cloud_mesh(16);
    for (int k = 0; k < 3; k++) {
        emm_layout_kind kinds[] = {EMM_LAYOUT_GRID3D, EMM_LAYOUT_TILES3D, EMM_LAYOUT_OCTREE};
        emm_layout *l = build(&cloud, kinds[k], 8);
        REQUIRE(l);
        emm_layout_stats st;
        emm_layout_get_stats(l, &st);
        if (kinds[k] != EMM_LAYOUT_TILES3D) /* shifted tiles overhang the box: some stay empty */
            CHECKF(st.dropped_cells == 0, "cloud: %s dropped %u cells", emm_layout_name(kinds[k]),
                   st.dropped_cells);
        emm_layout_free(l);
    }
    check_all3d(&cloud, "cloud", 8);
    mesh_free(&cloud);
    /* A planar mesh laid out in space: one layer of boxes, flat leaves. */
    mesh flat = grid_mesh(20, 20, 2.0);
    check_all3d(&flat, "flat", 16);
    mesh_free(&flat);
    check_all3d(&(mesh){(double[]){0, 0, 0, 1, 0, 0, 0, 1, 1}, 3, (int32_t[]){0, 1, 2}, 1},
                "one", 1);
    /* A needle, 1e-9 thick: the boxes stay about as many as the cells
     * wanted, all along its length. */
    mesh needle = grid_mesh(60, 2, 1.0);
    for (size_t v = 0; v < needle.nv; v++) {
        needle.xyz[3 * v + 1] *= 1e-9;
        needle.xyz[3 * v + 2] = 1e-9 * needle.xyz[3 * v];
    }
    check_all3d(&needle, "needle", 8);
    for (int k = 0; k < 2; k++) {
        emm_layout *l = build(&needle, k ? EMM_LAYOUT_TILES3D : EMM_LAYOUT_GRID3D, 8);
        REQUIRE(l);
        CHECKF(emm_layout_cell_count(l) <= 4 * (needle.nt / 8 + 1), "needle: %u boxes for %zu triangles",
               emm_layout_cell_count(l), needle.nt);
        emm_layout_free(l);
    }
    mesh_free(&needle);
    test_depth();

    test_cell_counts();
    test_quadtree_adapts();
    test_quadtree_max_depth();
    test_errors();
    test_degenerate();
    test_record_sizes();
    return check_done();
}
