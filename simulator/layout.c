/* EMM mesh layouts (thesis §4.1): what every layout shares — the layout's
 * space (as many axes as its kind declares), cells by triangle centroid,
 * vertex copies, layout indices both ways, cell sizes and the packed remote
 * image (§4.1: struct CellData), the neighbour lists the fetch schemes read
 * (§4.2) — and the dispatch to each kind's ops table:
 * layout_grid.c (§4.1.1), layout_tiles.c (§4.1.2), both on layout_rows.c,
 * and layout_quadtree.c (§4.1.3). docs/layouts.md explains the choices. */
#include "layout_internal.h"

#include <assert.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "geom.h"
#include "parse.h"

/* Ids are 32-bit; vertex copies (at most 3 per triangle) must fit too. */
#define MAX_TRIANGLES (UINT32_MAX / 3u - 1u)

/* The kinds, from EMM_LAYOUT_LIST. */
#define OPS_(e, n, d, w) [EMM_LAYOUT_##e] = &emm_layout_##n##_ops,
static const struct emm_layout_ops *const kinds[EMM_LAYOUT_COUNT] = {EMM_LAYOUT_LIST(OPS_)};
#undef OPS_

void emm_layout_free(emm_layout *l)
{
    if (!l)
        return;
    if (l->ops && l->ops->destroy)
        l->ops->destroy(l);
    else
        free(l->priv);
    free(l->cells);
    free(l->tri_cell);
    free(l->tri_pos);
    free(l->cell_tri_start);
    free(l->cell_tris);
    free(l->cell_vert_start);
    free(l->cell_verts);
    free(l->vcopy_start);
    free(l->vcopy);
    free(l->unused_rank);
    free(l->nb_start);
    free(l->nb);
    free(l->nb_side);
    free(l->ring_start);
    free(l->ring);
    free(l->ring_side);
    free(l->cell_of);
    free(l);
}


emm_status emm_layout_nomem(emm_error *err, const char *name)
{
    return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory building the layout", name);
}

/* A side is a bit of a byte: two per axis. */
_Static_assert(EMM_SIDE_BITS <= 8, "neighbour sides are stored in a byte");

emm_status emm_layout_fill_sides(emm_layout *l, const char *name, emm_error *err)
{
    uint32_t n = l->nb_start[l->ncells];
    l->nb_side = malloc((size_t)n + 1);
    if (!l->nb_side)
        return emm_layout_nomem(err, name);
    for (uint32_t c = 0; c < l->ncells; c++)
        for (uint32_t k = l->nb_start[c]; k < l->nb_start[c + 1]; k++)
            l->nb_side[k] = (uint8_t)l->ops->move_side(l, c, l->nb[k]);
    return EMM_OK;
}

/* The layout's space: as many axes as its kind declares, those along which
 * the bounding box of the vertices triangles use is largest (core/geom.h:
 * the one choice every layer makes; all three in space). */
static void choose_space(emm_layout *l, const emm_layout_geometry *g)
{
    l->dims = l->ops->dims;
    assert(l->dims >= 2 && l->dims <= EMM_MAX_DIMS);
    emm_axes_largest(g->lo, g->hi, l->dims, l->axes);
    for (uint32_t k = 0; k < l->dims; k++) {
        l->lo[k] = g->lo[l->axes[k]];
        l->hi[k] = g->hi[l->axes[k]];
    }
}

/* ops->compact: drops the cells without triangles, keeping the others in
 * the kind's order, and their neighbours that hold triangles. The kind's
 * data keeps its own numbering; cell_of translates. */
static emm_status drop_empty(emm_layout *l, const char *name, emm_error *err)
{
    uint32_t nraw = l->ncells, n = 0;
    uint32_t *cell_of = calloc((size_t)nraw + 1, sizeof *cell_of);
    if (!cell_of)
        return emm_layout_nomem(err, name);
    for (size_t t = 0; t < l->nt; t++)
        cell_of[l->tri_cell[t]] = 1;
    for (uint32_t r = 0; r < nraw; r++)
        cell_of[r] = cell_of[r] ? n++ : EMM_LAYOUT_NONE;
    /* In place: a kept cell's new place is never after its old one, and a
     * kept neighbour's entry never after where it was read. */
    uint32_t k = 0;
    for (uint32_t r = 0; r < nraw; r++) {
        uint32_t c = cell_of[r], from = l->nb_start[r], to = l->nb_start[r + 1];
        if (c == EMM_LAYOUT_NONE)
            continue;
        l->cells[c] = l->cells[r];
        l->nb_start[c] = k;
        for (uint32_t j = from; j < to; j++) {
            uint32_t d = cell_of[l->nb[j]];
            if (d == EMM_LAYOUT_NONE)
                continue;
            if (l->nb_side)
                l->nb_side[k] = l->nb_side[j];
            l->nb[k++] = d;
        }
    }
    l->nb_start[n] = k;
    for (size_t t = 0; t < l->nt; t++)
        l->tri_cell[t] = cell_of[l->tri_cell[t]];
    /* Shrinking never fails in practice; when it does the larger blocks
     * serve as well. */
    emm_layout_cell *cells = realloc(l->cells, ((size_t)n + 1) * sizeof *cells);
    if (cells)
        l->cells = cells;
    uint32_t *starts = realloc(l->nb_start, ((size_t)n + 1) * sizeof *starts);
    if (starts)
        l->nb_start = starts;
    l->ncells = n;
    l->nraw = nraw;
    l->cell_of = cell_of;
    return EMM_OK;
}

/* Counting sort of the triangles by cell: positions follow ascending ids. */
static emm_status fill_triangles(emm_layout *l, const char *name, emm_error *err)
{
    l->cell_tri_start = calloc((size_t)l->ncells + 1, sizeof *l->cell_tri_start);
    l->cell_tris = malloc(l->nt * sizeof *l->cell_tris);
    l->tri_pos = malloc(l->nt * sizeof *l->tri_pos);
    if (!l->cell_tri_start || !l->cell_tris || !l->tri_pos)
        return emm_layout_nomem(err, name);
    for (size_t t = 0; t < l->nt; t++)
        l->cell_tri_start[l->tri_cell[t] + 1]++;
    for (uint32_t c = 0; c < l->ncells; c++)
        l->cell_tri_start[c + 1] += l->cell_tri_start[c];
    uint32_t *next = malloc((size_t)l->ncells * sizeof *next);
    if (!next)
        return emm_layout_nomem(err, name);
    memcpy(next, l->cell_tri_start, (size_t)l->ncells * sizeof *next);
    for (size_t t = 0; t < l->nt; t++) {
        uint32_t c = l->tri_cell[t];
        l->tri_pos[t] = next[c] - l->cell_tri_start[c];
        l->cell_tris[next[c]++] = (uint32_t)t;
    }
    free(next);
    for (uint32_t c = 0; c < l->ncells; c++)
        l->cells[c].ntri = l->cell_tri_start[c + 1] - l->cell_tri_start[c];
    return EMM_OK;
}

/* Each cell gets a copy of every vertex of its triangles, in order of first
 * use; then the copies are indexed by vertex (ascending cell). */
static emm_status fill_vertices(emm_layout *l, const int32_t *tri, const char *name,
                                emm_error *err)
{
    uint32_t *stamp = malloc(l->nv * sizeof *stamp);
    l->cell_vert_start = malloc(((size_t)l->ncells + 1) * sizeof *l->cell_vert_start);
    l->cell_verts = malloc(3 * l->nt * sizeof *l->cell_verts);
    l->vcopy_start = calloc(l->nv + 1, sizeof *l->vcopy_start);
    if (!stamp || !l->cell_vert_start || !l->cell_verts || !l->vcopy_start) {
        free(stamp);
        return emm_layout_nomem(err, name);
    }
    memset(stamp, 0xff, l->nv * sizeof *stamp);
    uint32_t n = 0;
    for (uint32_t c = 0; c < l->ncells; c++) {
        l->cell_vert_start[c] = n;
        for (uint32_t i = l->cell_tri_start[c]; i < l->cell_tri_start[c + 1]; i++) {
            const int32_t *v = tri + 3 * (size_t)l->cell_tris[i];
            for (int k = 0; k < 3; k++)
                if (stamp[v[k]] != c) {
                    stamp[v[k]] = c;
                    l->cell_verts[n++] = (uint32_t)v[k];
                    l->vcopy_start[v[k] + 1]++;
                }
        }
        l->cells[c].nvert = n - l->cell_vert_start[c];
    }
    l->cell_vert_start[l->ncells] = n;
    l->ncopies = n;
    free(stamp);
    uint32_t *shrunk = realloc(l->cell_verts, ((size_t)n + 1) * sizeof *shrunk);
    if (shrunk)
        l->cell_verts = shrunk;

    l->nunused = 0;
    for (size_t v = 0; v < l->nv; v++) {
        if (l->vcopy_start[v + 1] == 0)
            l->nunused++;
        l->vcopy_start[v + 1] += l->vcopy_start[v];
    }
    l->vcopy = malloc(((size_t)n + 1) * sizeof *l->vcopy);
    uint32_t *next = malloc((l->nv + 1) * sizeof *next);
    if (!l->vcopy || !next) {
        free(next);
        return emm_layout_nomem(err, name);
    }
    memcpy(next, l->vcopy_start, (l->nv + 1) * sizeof *next);
    for (uint32_t c = 0; c < l->ncells; c++)
        for (uint32_t i = l->cell_vert_start[c]; i < l->cell_vert_start[c + 1]; i++) {
            uint32_t v = l->cell_verts[i];
            l->vcopy[next[v]++] = (emm_layout_index){c, i - l->cell_vert_start[c]};
        }
    free(next);
    if (l->nunused > 0) {
        l->unused_rank = malloc(l->nv * sizeof *l->unused_rank);
        if (!l->unused_rank)
            return emm_layout_nomem(err, name);
        uint32_t k = 0;
        for (size_t v = 0; v < l->nv; v++)
            l->unused_rank[v] = l->vcopy_start[v + 1] == l->vcopy_start[v] ? k++ : UINT32_MAX;
    }
    return EMM_OK;
}

/* A layout in space: the ring of cell c is its neighbours that hold a copy
 * of one of c's vertices — the cells the surface continues into from c.
 * Boxes touch boxes the surface in c never reaches (on a 1,000,000-face
 * sphere, octree@64: 12.8 neighbours with triangles a cell, 7.3 of them
 * sharing a vertex); in the plane every neighbour is the mesh's next step
 * and the ring is the neighbour list (docs/layouts.md "The ring in
 * space"). Not for cells of vertices (vertex_cells), which share none. */
static emm_status fill_ring(emm_layout *l, const char *name, emm_error *err)
{
    uint32_t n = l->nb_start[l->ncells];
    uint32_t *mark = malloc(((size_t)l->ncells + 1) * sizeof *mark);
    l->ring_start = malloc(((size_t)l->ncells + 1) * sizeof *l->ring_start);
    l->ring = malloc(((size_t)n + 1) * sizeof *l->ring);
    l->ring_side = malloc((size_t)n + 1);
    if (!mark || !l->ring_start || !l->ring || !l->ring_side) {
        free(mark);
        return emm_layout_nomem(err, name);
    }
    memset(mark, 0xff, ((size_t)l->ncells + 1) * sizeof *mark);
    uint32_t k = 0;
    for (uint32_t c = 0; c < l->ncells; c++) {
        for (uint32_t i = l->cell_vert_start[c]; i < l->cell_vert_start[c + 1]; i++) {
            uint32_t v = l->cell_verts[i];
            for (uint32_t j = l->vcopy_start[v]; j < l->vcopy_start[v + 1]; j++)
                mark[l->vcopy[j].cell] = c;
        }
        l->ring_start[c] = k;
        for (uint32_t j = l->nb_start[c]; j < l->nb_start[c + 1]; j++)
            if (mark[l->nb[j]] == c) {
                l->ring[k] = l->nb[j];
                l->ring_side[k++] = l->nb_side[j];
            }
    }
    l->ring_start[l->ncells] = k;
    free(mark);
    return EMM_OK;
}

/* The one place that decides what a triangle takes in its cell: its
 * record and the 3 pointers to its vertices' copies in the same cell
 * (thesis §4.1.1), through which the models reach a vertex of the triangle
 * just requested without a look-up (emm_fetch.c, cache_layout.c). Cells of
 * vertices have no triangle records, so no pointers either. */
uint32_t emm_layout_triangle_slot_bytes(const emm_layout *l)
{
    return l->opt.vertex_cells ? 0 : l->opt.triangle_bytes + 3 * l->opt.pointer_bytes;
}

static void fill_sizes(emm_layout *l)
{
    uint64_t off = 0;
    const uint64_t slot = emm_layout_triangle_slot_bytes(l);
    for (uint32_t c = 0; c < l->ncells; c++) {
        emm_layout_cell *cell = &l->cells[c];
        cell->bytes = EMM_LAYOUT_HEADER_BYTES + (uint64_t)cell->nvert * l->opt.vertex_bytes +
                      (uint64_t)cell->ntri * slot;
        cell->offset = off;
        off += cell->bytes;
    }
    l->cells_bytes = off;
}

void emm_layout_geometry_free(emm_layout_geometry *g)
{
    for (int a = 0; a < 3; a++) {
        free(g->centroid[a]);
        g->centroid[a] = NULL;
    }
}

emm_status emm_layout_geometry_init(emm_layout_geometry *g, const double *xyz, size_t nv,
                                    const int32_t *tri, size_t nt, const char *name,
                                    emm_error *err)
{
    memset(g, 0, sizeof *g);
    if (nt == 0)
        return emm_fail(err, EMM_ERR_INVALID, "%s: no triangles to lay out", name);
    if (nt > MAX_TRIANGLES || nv > (size_t)INT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE,
                        "%s: %zu vertices and %zu triangles are more than a layout indexes "
                        "(at most %u triangles)",
                        name, nv, nt, (unsigned)MAX_TRIANGLES);
    for (size_t i = 0; i < 3 * nv; i++)
        if (!isfinite(xyz[i]))
            return emm_fail(err, EMM_ERR_MESH, "%s: vertex %zu has a non-finite coordinate",
                            name, i / 3);
    for (size_t i = 0; i < 3 * nt; i++)
        if (tri[i] < 0 || (size_t)tri[i] >= nv)
            return emm_fail(err, EMM_ERR_MESH,
                            "%s: triangle %zu refers to vertex %lld; the mesh has %zu vertices",
                            name, i / 3, (long long)tri[i], nv);
    g->tri = tri;
    g->nv = nv;
    g->nt = nt;
    for (int a = 0; a < 3; a++) {
        g->lo[a] = INFINITY;
        g->hi[a] = -INFINITY;
        if (!(g->centroid[a] = malloc(nt * sizeof *g->centroid[a]))) {
            emm_layout_geometry_free(g);
            return emm_layout_nomem(err, name);
        }
    }
    for (size_t t = 0; t < nt; t++) {
        const double *p[3] = {xyz + 3 * (size_t)tri[3 * t], xyz + 3 * (size_t)tri[3 * t + 1],
                              xyz + 3 * (size_t)tri[3 * t + 2]};
        for (int a = 0; a < 3; a++) {
            for (int k = 0; k < 3; k++) {
                if (p[k][a] < g->lo[a])
                    g->lo[a] = p[k][a];
                if (p[k][a] > g->hi[a])
                    g->hi[a] = p[k][a];
            }
            g->centroid[a][t] = (p[0][a] + p[1][a] + p[2][a]) / 3.0;
        }
    }
    return EMM_OK;
}

/* Builds without the local-store check; the geometry is checked. */
static emm_status build_once(const emm_layout_geometry *g, const emm_layout_options *opt,
                             const char *name, emm_layout **out, emm_error *err)
{
    emm_status st = EMM_OK;
    emm_layout *l = calloc(1, sizeof *l);
    if (!l)
        return emm_layout_nomem(err, name);
    l->opt = *opt;
    l->ops = kinds[opt->kind];
    l->nv = g->nv;
    l->nt = g->nt;
    choose_space(l, g);

    const double *c[EMM_MAX_DIMS] = {NULL, NULL, NULL};
    /* Cells divide the bounding box: past ±1e300 its extent, or a sum of
     * three coordinates, can overflow to infinity and every cell index
     * would be meaningless (a fuzzed trace's geometry found this). */
    for (uint32_t k = 0; k < l->dims; k++)
        if (!(fabs(l->lo[k]) <= 1e300 && fabs(l->hi[k]) <= 1e300)) {
            st = emm_fail(err, EMM_ERR_RANGE, "%s: coordinates beyond +-1e300 cannot be laid out in cells",
                          name);
            goto done;
        }
    l->tri_cell = malloc(g->nt * sizeof *l->tri_cell);
    if (!l->tri_cell) {
        st = emm_layout_nomem(err, name);
        goto done;
    }
    for (uint32_t k = 0; k < l->dims; k++)
        c[k] = g->centroid[l->axes[k]];
    st = l->ops->build(l, c, name, err);
    if (st == EMM_OK && l->ops->compact)
        st = drop_empty(l, name, err);
    if (st == EMM_OK)
        st = fill_triangles(l, name, err);
    if (st == EMM_OK)
        st = fill_vertices(l, g->tri, name, err);
    if (st == EMM_OK && l->dims == 3 && !l->opt.vertex_cells)
        st = fill_ring(l, name, err);
    if (st == EMM_OK)
        fill_sizes(l);

done:
    if (st != EMM_OK) {
        emm_layout_free(l);
        return st;
    }
    *out = l;
    return EMM_OK;
}

static uint32_t largest_cell(const emm_layout *l)
{
    uint32_t worst = 0;
    for (uint32_t c = 1; c < l->ncells; c++)
        if (l->cells[c].bytes > l->cells[worst].bytes)
            worst = c;
    return worst;
}

/* The largest power of two not above x (x >= 1). */
static uint32_t floor_pow2(uint64_t x)
{
    uint32_t p = 1;
    while ((uint64_t)p * 2 <= x && p < (1u << 31))
        p *= 2;
    return p;
}

emm_status emm_layout_fit_cell(const emm_layout_geometry *g, const emm_layout *l, uint64_t local,
                               uint32_t *suggest, const char *name, emm_error *err)
{
    uint64_t bytes = l->cells[largest_cell(l)].bytes;
    uint64_t fit = (uint64_t)((double)l->opt.cell * (double)local / (double)bytes);
    uint32_t s = fit >= 1 ? floor_pow2(fit) : 1;
    if (s >= l->opt.cell)
        s = l->opt.cell / 2;
    for (; s >= 1; s /= 2) {
        emm_layout_options o = l->opt;
        o.cell = s;
        o.local_store = 0;
        emm_layout *trial = NULL;
        emm_status st = build_once(g, &o, name, &trial, err);
        if (st != EMM_OK)
            return st;
        int fits = trial->cells[largest_cell(trial)].bytes <= local;
        emm_layout_free(trial);
        if (fits)
            break;
    }
    *suggest = s;
    return EMM_OK;
}

emm_status emm_layout_too_large(const emm_layout *l, emm_fetch_kind fetch, uint64_t local,
                                uint32_t suggest, const char *name, emm_error *err)
{
    uint32_t worst = largest_cell(l);
    uint64_t bytes = l->cells[worst].bytes;
    char b1[32], b2[32];
    const char *layout = emm_layout_name(l->opt.kind);
    if (suggest == 0)
        return emm_fail(err, EMM_ERR_RANGE,
                        "%s: %s cell %u takes %s bytes, more than the %s-byte local store, "
                        "and no CELL makes every %s cell fit%s",
                        name, layout, worst, emm_grouped(bytes, b1), emm_grouped(local, b2), layout,
                        l->ops->bounded ? "" : " (the quadtree bounds triangles per cell)");
    const char *f = fetch != EMM_FETCH_NONE ? emm_fetch_name(fetch) : "FETCH";
    return emm_fail(err, EMM_ERR_RANGE,
                    "%s: %s cell %u takes %s bytes, more than the %s-byte local store: "
                    "use a smaller CELL than %u (e.g. %s+%s@%u)",
                    name, layout, worst, emm_grouped(bytes, b1), emm_grouped(local, b2), l->opt.cell,
                    layout, f, suggest);
}

/* The error for a cell larger than the local store, with a CELL that fits
 * (emm_layout_fit_cell). */
static emm_status too_large(const emm_layout_geometry *g, const emm_layout *l, const char *name,
                            emm_error *err)
{
    uint32_t suggest = 0;
    emm_status st = emm_layout_fit_cell(g, l, l->opt.local_store, &suggest, name, err);
    if (st != EMM_OK)
        return st;
    return emm_layout_too_large(l, l->opt.fetch, l->opt.local_store, suggest, name, err);
}

emm_status emm_layout_check_cell(const emm_layout_options *opt, const char *name, emm_error *err)
{
    if (opt->cell == 0)
        return emm_fail(err, EMM_ERR_INVALID, "%s: a layout needs at least 1 triangle per cell",
                        name);
    return EMM_OK;
}

emm_status emm_layout_build_from(const emm_layout_geometry *g, const emm_layout_options *opt,
                                 const char *name, emm_layout **out, emm_error *err)
{
    assert(opt && out && g);
    assert(opt->kind > EMM_LAYOUT_ORIGINAL && opt->kind < EMM_LAYOUT_COUNT);
    *out = NULL;
    if (!name)
        name = "mesh";
    emm_status cst = emm_layout_check_cell(opt, name, err);
    if (cst != EMM_OK)
        return cst;
    emm_layout_options o = *opt;
    if (o.vertex_bytes == 0)
        o.vertex_bytes = EMM_THESIS_VERTEX_BYTES;
    if (o.triangle_bytes == 0)
        o.triangle_bytes = EMM_THESIS_TRIANGLE_BYTES;
    if (o.pointer_bytes == 0)
        o.pointer_bytes = EMM_LAYOUT_POINTER_BYTES;
    emm_layout *l = NULL;
    emm_status st = build_once(g, &o, name, &l, err);
    if (st != EMM_OK)
        return st;
    if (o.local_store > 0 && l->cells[largest_cell(l)].bytes > o.local_store) {
        st = too_large(g, l, name, err);
        emm_layout_free(l);
        return st;
    }
    *out = l;
    return EMM_OK;
}

emm_status emm_layout_build(const double *xyz, size_t nv, const int32_t *tri, size_t nt,
                            const emm_layout_options *opt, const char *name, emm_layout **out,
                            emm_error *err)
{
    assert(opt && out && (xyz || nv == 0) && (tri || nt == 0));
    *out = NULL;
    if (!name)
        name = "mesh";
    emm_status cst = emm_layout_check_cell(opt, name, err);
    if (cst != EMM_OK)
        return cst;
    emm_layout_geometry g;
    emm_status st = emm_layout_geometry_init(&g, xyz, nv, tri, nt, name, err);
    if (st != EMM_OK)
        return st;
    st = emm_layout_build_from(&g, opt, name, out, err);
    emm_layout_geometry_free(&g);
    return st;
}

const emm_layout_options *emm_layout_get_options(const emm_layout *l)
{
    return &l->opt;
}

uint32_t emm_layout_cell_count(const emm_layout *l)
{
    return l->ncells;
}

size_t emm_layout_triangle_count(const emm_layout *l)
{
    return l->nt;
}

size_t emm_layout_vertex_count(const emm_layout *l)
{
    return l->nv;
}

uint32_t emm_layout_axes(const emm_layout *l, int axes[EMM_MAX_DIMS], double lo[EMM_MAX_DIMS],
                         double hi[EMM_MAX_DIMS])
{
    for (uint32_t k = 0; k < l->dims; k++) {
        if (axes)
            axes[k] = l->axes[k];
        if (lo)
            lo[k] = l->lo[k];
        if (hi)
            hi[k] = l->hi[k];
    }
    return l->dims;
}

uint32_t emm_layout_cells_per_axis(const emm_layout *l, uint32_t n[EMM_MAX_DIMS])
{
    return l->ops->per_axis ? l->ops->per_axis(l, n) : 0;
}

unsigned emm_layout_move_side(const emm_layout *l, uint32_t from, uint32_t to)
{
    assert(from < l->ncells && to < l->ncells);
    return l->ops->move_side(l, from, to);
}

const emm_layout_cell *emm_layout_cell_get(const emm_layout *l, uint32_t c)
{
    assert(c < l->ncells);
    return &l->cells[c];
}

uint32_t emm_layout_cell_triangles(const emm_layout *l, uint32_t c, const uint32_t **tris)
{
    assert(c < l->ncells);
    if (tris)
        *tris = l->cell_tris + l->cell_tri_start[c];
    return l->cell_tri_start[c + 1] - l->cell_tri_start[c];
}

uint32_t emm_layout_cell_vertices(const emm_layout *l, uint32_t c, const uint32_t **verts)
{
    assert(c < l->ncells);
    if (verts)
        *verts = l->cell_verts + l->cell_vert_start[c];
    return l->cell_vert_start[c + 1] - l->cell_vert_start[c];
}

uint32_t emm_layout_neighbors(const emm_layout *l, uint32_t c, const uint32_t **cells,
                              const uint8_t **sides)
{
    assert(c < l->ncells);
    if (cells)
        *cells = l->nb + l->nb_start[c];
    if (sides)
        *sides = l->nb_side + l->nb_start[c];
    return l->nb_start[c + 1] - l->nb_start[c];
}

uint32_t emm_layout_ring(const emm_layout *l, uint32_t c, const uint32_t **cells,
                         const uint8_t **sides)
{
    assert(c < l->ncells);
    if (!l->ring_start)
        return emm_layout_neighbors(l, c, cells, sides);
    if (cells)
        *cells = l->ring + l->ring_start[c];
    if (sides)
        *sides = l->ring_side + l->ring_start[c];
    return l->ring_start[c + 1] - l->ring_start[c];
}

uint32_t emm_layout_cell_at(const emm_layout *l, const double *p, uint32_t *levels)
{
    uint32_t r = l->ops->cell_at(l, p, levels);
    return l->cell_of ? l->cell_of[r] : r;
}

emm_layout_index emm_layout_triangle_index(const emm_layout *l, uint32_t t)
{
    assert(t < l->nt);
    return (emm_layout_index){l->tri_cell[t], l->tri_pos[t]};
}

uint32_t emm_layout_triangle_at(const emm_layout *l, uint32_t cell, uint32_t pos)
{
    assert(cell < l->ncells && pos < l->cells[cell].ntri);
    return l->cell_tris[l->cell_tri_start[cell] + pos];
}

uint32_t emm_layout_vertex_copies(const emm_layout *l, uint32_t v,
                                  const emm_layout_index **copies)
{
    assert(v < l->nv);
    if (copies)
        *copies = l->vcopy + l->vcopy_start[v];
    return l->vcopy_start[v + 1] - l->vcopy_start[v];
}

emm_layout_index emm_layout_vertex_home(const emm_layout *l, uint32_t v)
{
    assert(v < l->nv);
    if (l->vcopy_start[v + 1] == l->vcopy_start[v])
        return (emm_layout_index){EMM_LAYOUT_NONE, l->unused_rank ? l->unused_rank[v] : 0};
    return l->vcopy[l->vcopy_start[v]];
}

emm_layout_index emm_layout_vertex_index(const emm_layout *l, uint32_t v, uint32_t cell)
{
    assert(v < l->nv);
    /* Copies are few (a vertex's triangles span a handful of cells) and
     * sorted by cell. */
    for (uint32_t i = l->vcopy_start[v]; i < l->vcopy_start[v + 1]; i++) {
        if (l->vcopy[i].cell == cell)
            return l->vcopy[i];
        if (l->vcopy[i].cell > cell)
            break;
    }
    return emm_layout_vertex_home(l, v);
}

uint32_t emm_layout_vertex_at(const emm_layout *l, uint32_t cell, uint32_t pos)
{
    assert(cell < l->ncells && pos < l->cells[cell].nvert);
    return l->cell_verts[l->cell_vert_start[cell] + pos];
}

uint64_t emm_layout_image_bytes(const emm_layout *l)
{
    return l->cells_bytes + l->nunused * l->opt.vertex_bytes;
}

uint64_t emm_layout_triangle_address(const emm_layout *l, uint32_t t, uint32_t offset)
{
    assert(t < l->nt && offset < l->opt.triangle_bytes);
    const emm_layout_cell *c = &l->cells[l->tri_cell[t]];
    return c->offset + EMM_LAYOUT_HEADER_BYTES + (uint64_t)c->nvert * l->opt.vertex_bytes +
           (uint64_t)l->tri_pos[t] * emm_layout_triangle_slot_bytes(l) + offset;
}

uint64_t emm_layout_vertex_address(const emm_layout *l, uint32_t v, uint32_t from_cell,
                                   uint32_t offset)
{
    assert(v < l->nv && offset < l->opt.vertex_bytes);
    emm_layout_index ix = from_cell == EMM_LAYOUT_NONE ? emm_layout_vertex_home(l, v)
                                                       : emm_layout_vertex_index(l, v, from_cell);
    if (ix.cell == EMM_LAYOUT_NONE)
        return l->cells_bytes + (uint64_t)ix.pos * l->opt.vertex_bytes + offset;
    return l->cells[ix.cell].offset + EMM_LAYOUT_HEADER_BYTES +
           (uint64_t)ix.pos * l->opt.vertex_bytes + offset;
}

uint64_t emm_layout_lookup_bytes(const emm_layout *l)
{
    uint64_t b = 4 * (uint64_t)l->nt + 4 * (uint64_t)l->nv + 8 * (uint64_t)l->ncells;
    return b + (l->ops->lookup_bytes ? l->ops->lookup_bytes(l) : 0);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

void emm_layout_get_stats(const emm_layout *l, emm_layout_stats *out)
{
    memset(out, 0, sizeof *out);
    out->cells = l->ncells;
    out->dropped_cells = l->nraw > l->ncells ? l->nraw - l->ncells : 0;
    uint64_t *v = malloc((size_t)l->ncells * sizeof *v);
    /* Without memory for the medians, report them as 0 rather than fail a
     * query. */
    uint32_t mid = (l->ncells - 1) / 2; /* the lower median */
    out->tri_min = UINT32_MAX;
    out->bytes_min = UINT64_MAX;
    out->depth_min = UINT32_MAX;
    for (uint32_t c = 0; c < l->ncells; c++) {
        const emm_layout_cell *cell = &l->cells[c];
        if (cell->ntri == 0)
            out->empty_cells++;
        if (cell->ntri < out->tri_min)
            out->tri_min = cell->ntri;
        if (cell->ntri > out->tri_max)
            out->tri_max = cell->ntri;
        if (cell->bytes < out->bytes_min)
            out->bytes_min = cell->bytes;
        if (cell->bytes > out->bytes_max)
            out->bytes_max = cell->bytes;
        if (cell->depth < out->depth_min)
            out->depth_min = cell->depth;
        if (cell->depth > out->depth_max)
            out->depth_max = cell->depth;
    }
    if (v) {
        for (uint32_t c = 0; c < l->ncells; c++)
            v[c] = l->cells[c].ntri;
        qsort(v, l->ncells, sizeof *v, cmp_u64);
        out->tri_median = (uint32_t)v[mid];
        for (uint32_t c = 0; c < l->ncells; c++)
            v[c] = l->cells[c].bytes;
        qsort(v, l->ncells, sizeof *v, cmp_u64);
        out->bytes_median = v[mid];
        free(v);
    }
    out->vertex_copies = l->ncopies;
    out->unused_vertices = l->nunused;
    out->duplicated_vertices = l->ncopies - (l->nv - l->nunused);
    out->image_bytes = emm_layout_image_bytes(l);
    out->triangle_slot_bytes = emm_layout_triangle_slot_bytes(l);
    out->lookup_bytes = emm_layout_lookup_bytes(l);
    if (l->ops->stats)
        l->ops->stats(l, out);
    else
        out->depth_min = out->depth_max = 0;
}
