/* The hardware cache on a reordered layout, `cache@LAYOUT` (thesis §6.3:
 * "Cache(Grid) runs on the grid layout same as in EMM(Grid)"; layouts of
 * §4.1). The program's element accesses are replayed against the addresses
 * the elements have in the layout's remote image (docs/layouts.md "Bytes"),
 * through the same Dinero-exact cache as the plain `cache` model.
 *
 * Which copy of a vertex an access reads: the copy in the cell of the most
 * recent triangle access when the vertex has one there, else its home copy
 * (the lowest-numbered cell holding it). That is how the thesis' triangles
 * point at their own cell's vertex copies (§4.1.1, Fig. 4.4), and it is the
 * rule the EMM models use too (docs/fetch.md, docs/layouts.md). Accesses
 * to arrays other than the mesh's first vertex and triangle arrays keep
 * their original addresses.
 *
 * No cells move, so the local-store size check of the EMM strategies does
 * not apply. Everything the loop needs is precomputed into flat arrays and
 * the (shared) layout is released after construction. */
#include "cache_layout.h"

#include <stdlib.h>
#include <string.h>

#include "cache.h"
#include "emm/layout.h"
#include "error.h"
#include "layout_internal.h"
#include "model.h"

#define NO_ARRAY UINT32_MAX
#define NO_TRI UINT32_MAX

typedef struct cache_layout_model {
    struct emm_model base;
    emm_addr_map map;          /* original addresses, for the other arrays */
    uint32_t varray, tarray;   /* the mesh's vertex and triangle arrays, or NO_ARRAY */
    uint64_t *tri_addr;        /* triangle t's record in the image */
    uint32_t *tri_cell;        /* triangle t's cell */
    uint32_t *vcopy_start;     /* vertex v's copies: [vcopy_start[v], vcopy_start[v + 1]) */
    uint32_t *vcopy_cell;      /* by ascending cell */
    uint64_t *vcopy_addr;
    uint64_t *vhome_addr;      /* the home copy (an unused vertex's own record) */
    uint32_t *tri_v;           /* triangle t's three vertices */
    uint64_t *tri_vaddr;       /* and the addresses vertex_addr finds for them right after
                                  an access to t */
    uint32_t cur_cell;         /* cell of the most recent triangle access */
    uint32_t cur_tri;          /* that triangle, or NO_TRI */
    /* The look-up of an element request (thesis §4.1.1: the program keeps
     * the original ids, so a request goes through the id -> layout index
     * table and the cell table to the record, as the EMM runtime's does):
     * the tables in remote memory after the image, read through the cache,
     * and the look-up's instructions. */
    uint64_t tri_table, vert_table, cell_table, node_table;
    uint64_t *find;            /* per cell: emm.lookup + emm.quadtree_level x its depth */
    uint32_t *path_start;      /* a tree's: ncells + 1, each cell's descent in path */
    uint32_t *path;            /* the nodes each descent reads, root first (NULL: no tree) */
    uint64_t lookup_cycles, lookups, table_reads;
    uint32_t last_array;       /* the previous record's element, or NO_ARRAY */
    uint64_t last_element;
    emm_cache cache;
} cache_layout_model;

static inline uint64_t vertex_addr(const cache_layout_model *m, uint64_t v)
{
    /* A vertex of the triangle just accessed: the address the search below
     * finds, computed once per triangle at construction and read off the
     * triangle (warm) instead of the vertex's copies (cold). */
    if (m->cur_tri != NO_TRI) {
        const uint32_t *tv = m->tri_v + 3 * (size_t)m->cur_tri;
        for (int k = 0; k < 3; k++)
            if (tv[k] == v)
                return m->tri_vaddr[3 * (size_t)m->cur_tri + (size_t)k];
    }
    uint32_t i = m->vcopy_start[v], end = m->vcopy_start[v + 1], cell = m->cur_cell;
    /* A vertex has copies in a handful of cells, sorted by cell. */
    for (; i < end && m->vcopy_cell[i] <= cell; i++)
        if (m->vcopy_cell[i] == cell)
            return m->vcopy_addr[i];
    return m->vhome_addr[v];
}

/* The cell whose copy of vertex v vertex_addr reads. */
static inline uint32_t vertex_cell(const cache_layout_model *m, uint64_t v)
{
    uint32_t i = m->vcopy_start[v], end = m->vcopy_start[v + 1];
    for (uint32_t k = i; k < end && m->vcopy_cell[k] <= m->cur_cell; k++)
        if (m->vcopy_cell[k] == m->cur_cell)
            return m->cur_cell;
    return i < end ? m->vcopy_cell[i] : EMM_LAYOUT_NONE;
}

/* The look-up of a request for element e (the EMM model's rule, emm_fetch.c:
 * not for a further load of the record just requested, nor for a vertex of
 * the triangle just requested, which that triangle points at): its id
 * table entry, a tree's nodes on the way down to its cell, and its cell's
 * entry, read through the cache, and the look-up's instructions. */
static inline void table_lookup(cache_layout_model *m, uint64_t entry, uint32_t cell)
{
    emm_cache_access(&m->cache, entry, 4, 0, 0);
    m->table_reads++;
    if (cell != EMM_LAYOUT_NONE) {
        if (m->path)
            for (uint32_t k = m->path_start[cell]; k < m->path_start[cell + 1]; k++) {
                emm_cache_access(&m->cache, m->node_table + 16 * (uint64_t)m->path[k], 16, 0, 0);
                m->table_reads++;
            }
        emm_cache_access(&m->cache, m->cell_table + 8 * (uint64_t)cell, 8, 0, 0);
        m->table_reads++;
        m->lookup_cycles += m->find[cell];
    }
    m->lookups++;
}

static void cl_run(emm_model *model, const emm_trace_record *recs, size_t n)
{
    cache_layout_model *m = (cache_layout_model *)model;
    const uint32_t varray = m->varray, tarray = m->tarray;
    for (size_t i = 0; i < n; i++) {
        const emm_trace_record *r = &recs[i];
        uint64_t addr;
        int request = r->array != m->last_array || r->element != m->last_element;
        m->last_array = r->array;
        m->last_element = r->element;
        if (r->array == tarray) {
            m->cur_cell = m->tri_cell[r->element];
            m->cur_tri = (uint32_t)r->element;
            if (request)
                table_lookup(m, m->tri_table + 4 * r->element, m->cur_cell);
            addr = m->tri_addr[r->element] + r->offset;
        } else if (r->array == varray) {
            if (request) {
                int pointer = 0;
                if (m->cur_tri != NO_TRI) {
                    const uint32_t *tv = m->tri_v + 3 * (size_t)m->cur_tri;
                    pointer = tv[0] == r->element || tv[1] == r->element || tv[2] == r->element;
                }
                if (!pointer)
                    table_lookup(m, m->vert_table + 4 * r->element, vertex_cell(m, r->element));
            }
            addr = vertex_addr(m, r->element) + r->offset;
        } else {
            addr = emm_addr_of(&m->map, r);
        }
        emm_cache_access(&m->cache, addr, r->bytes, r->write, r->work);
    }
}

static void cl_reset(emm_model *model)
{
    cache_layout_model *m = (cache_layout_model *)model;
    m->cur_cell = EMM_LAYOUT_NONE;
    m->cur_tri = NO_TRI;
    m->last_array = NO_ARRAY;
    m->last_element = 0;
    m->lookup_cycles = m->lookups = m->table_reads = 0;
    emm_cache_reset(&m->cache);
}

/* The table reads are the look-up's loads, not the program's accesses: its
 * cycles stay, the count of accesses is the program's. */
static void cl_result(const emm_model *model, emm_result *out)
{
    const cache_layout_model *m = (const cache_layout_model *)model;
    emm_cache_result(&m->cache, out);
    out->accesses -= m->table_reads;
    out->cycles[EMM_BUCKET_EMM_INSTRUCTIONS] += m->lookup_cycles;
    out->total += m->lookup_cycles;
}

static void cl_destroy(emm_model *model)
{
    cache_layout_model *m = (cache_layout_model *)model;
    if (!m)
        return;
    emm_cache_free(&m->cache);
    emm_addr_map_free(&m->map);
    free(m->tri_addr);
    free(m->tri_cell);
    free(m->tri_v);
    free(m->tri_vaddr);
    free(m->vcopy_start);
    free(m->vcopy_cell);
    free(m->vcopy_addr);
    free(m->vhome_addr);
    free(m->find);
    free(m->path_start);
    free(m->path);
    free(m);
}

static const struct emm_model_ops cache_layout_ops = {cl_run, cl_reset, cl_result, cl_destroy,
                                                      NULL,   NULL,     NULL};

/* Where the image starts: where the mesh arrays start (`base`: each
 * array's address, as the models place them), unless that overlaps another
 * array, then past every array (4 KiB aligned, as a fresh allocation would
 * be). */
static uint64_t image_base(const emm_trace_info *trace, const uint64_t *where, uint32_t varray,
                           uint32_t tarray, uint64_t image_bytes)
{
    uint64_t base = UINT64_MAX, end_all = 0;
    if (varray != NO_ARRAY)
        base = where[varray];
    if (tarray != NO_ARRAY && where[tarray] < base)
        base = where[tarray];
    base &= ~(uint64_t)4095;
    int clash = 0;
    for (uint32_t a = 0; a < trace->narrays; a++) {
        const emm_trace_array *x = &trace->arrays[a];
        uint64_t end = where[a] + x->count * x->record_size;
        if (end > end_all)
            end_all = end;
        if (a == varray || a == tarray || x->count == 0)
            continue;
        if (where[a] < base + image_bytes && base < end)
            clash = 1;
    }
    return clash ? (end_all + 4095) & ~(uint64_t)4095 : base;
}

emm_status emm_cache_layout_model_new(const emm_machine_params *p, const emm_strategy *s,
                                      const emm_trace_info *trace, emm_model_share *share,
                                      emm_model **out, emm_error *err)
{
    const emm_trace_geometry *g = &trace->geometry;
    emm_layout_options opt;
    const emm_layout *l = NULL;
    cache_layout_model *m;
    char name[64];
    emm_status st;

    emm_strategy_format(s, name, sizeof name);
    if (g->nv == 0 || g->nt == 0)
        return emm_fail(err, EMM_ERR_INVALID,
                        "%s: the trace has no mesh geometry; only direct and cache apply to an "
                        "address-only trace",
                        name);
    if (g->nv > UINT32_MAX || g->nt > UINT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE, "%s: the trace's mesh is too large", name);

    if (!(m = calloc(1, sizeof *m)))
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
    m->base.ops = &cache_layout_ops;
    m->varray = m->tarray = NO_ARRAY;
    for (uint32_t a = 0; a < trace->narrays; a++) {
        const emm_trace_array *x = &trace->arrays[a];
        if (x->kind == EMM_ARRAY_VERTICES && m->varray == NO_ARRAY)
            m->varray = a;
        else if (x->kind == EMM_ARRAY_TRIANGLES && m->tarray == NO_ARRAY)
            m->tarray = a;
    }
    if (m->varray == NO_ARRAY && m->tarray == NO_ARRAY) {
        st = emm_fail(err, EMM_ERR_INVALID,
                      "%s: the trace has no vertex or triangle array to lay out", name);
        goto fail;
    }
    if (m->varray != NO_ARRAY && trace->arrays[m->varray].count > g->nv) {
        st = emm_fail(err, EMM_ERR_INVALID,
                      "%s: the vertex array has %llu records but the geometry only "
                      "%llu vertices",
                      name, (unsigned long long)trace->arrays[m->varray].count,
                      (unsigned long long)g->nv);
        goto fail;
    }
    if (m->tarray != NO_ARRAY && trace->arrays[m->tarray].count > g->nt) {
        st = emm_fail(err, EMM_ERR_INVALID,
                      "%s: the triangle array has %llu records but the geometry only "
                      "%llu triangles",
                      name, (unsigned long long)trace->arrays[m->tarray].count,
                      (unsigned long long)g->nt);
        goto fail;
    }

    memset(&opt, 0, sizeof opt);
    opt.kind = s->layout;
    opt.cell = s->cell ? s->cell : EMM_DEFAULT_CELL;
    opt.vertex_bytes = m->varray != NO_ARRAY ? trace->arrays[m->varray].record_size
                                             : EMM_THESIS_VERTEX_BYTES;
    opt.triangle_bytes = m->tarray != NO_ARRAY ? trace->arrays[m->tarray].record_size
                                               : EMM_THESIS_TRIANGLE_BYTES;
    opt.vertex_cells = m->varray != NO_ARRAY && m->tarray == NO_ARRAY; /* as emm_fetch.c */
    opt.pointer_bytes = (uint32_t)p->word_bytes; /* as emm_fetch.c: cl_run credits them */
    opt.local_store = 0; /* no cell is moved as a whole */
    opt.fetch = EMM_FETCH_NONE; /* the same layout as the EMM strategies' (shared) */
    if ((st = emm_model_share_layout(share, trace, &opt, name, &l, err)) != EMM_OK) {
        l = NULL;
        goto fail;
    }

    size_t nv = (size_t)g->nv, nt = (size_t)g->nt, ncopies = 0;
    for (size_t v = 0; v < nv; v++) {
        const emm_layout_index *c;
        ncopies += emm_layout_vertex_copies(l, (uint32_t)v, &c);
    }
    m->tri_addr = malloc(nt * sizeof *m->tri_addr);
    m->tri_cell = malloc(nt * sizeof *m->tri_cell);
    m->tri_v = malloc(3 * nt * sizeof *m->tri_v);
    m->tri_vaddr = malloc(3 * nt * sizeof *m->tri_vaddr);
    m->vcopy_start = malloc((nv + 1) * sizeof *m->vcopy_start);
    m->vcopy_cell = malloc((ncopies ? ncopies : 1) * sizeof *m->vcopy_cell);
    m->vcopy_addr = malloc((ncopies ? ncopies : 1) * sizeof *m->vcopy_addr);
    m->vhome_addr = malloc(nv * sizeof *m->vhome_addr);
    uint32_t ncells = emm_layout_cell_count(l);
    m->find = malloc((ncells ? ncells : 1) * sizeof *m->find);
    if (!m->find || !m->tri_addr || !m->tri_cell || !m->tri_v || !m->tri_vaddr || !m->vcopy_start ||
        !m->vcopy_cell || !m->vcopy_addr || !m->vhome_addr || ncopies > UINT32_MAX) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the layout's addresses", name);
        goto fail;
    }

    if ((st = emm_addr_map_init(&m->map, trace, err)) != EMM_OK)
        goto fail;
    uint64_t base =
        image_base(trace, m->map.base, m->varray, m->tarray, emm_layout_image_bytes(l));
    for (size_t t = 0; t < nt; t++) {
        m->tri_addr[t] = base + emm_layout_triangle_address(l, (uint32_t)t, 0);
        m->tri_cell[t] = emm_layout_triangle_index(l, (uint32_t)t).cell;
    }
    /* The look-up tables follow the image (4 KiB aligned), laid out as the
     * EMM runtime's (emm_fetch.c): triangle ids, vertex ids, cells. */
    m->tri_table = (base + emm_layout_image_bytes(l) + 4095) & ~(uint64_t)4095;
    m->vert_table = m->tri_table + 4 * (uint64_t)nt;
    m->cell_table = m->vert_table + 4 * (uint64_t)nv;
    m->node_table = m->cell_table + 8 * (uint64_t)ncells;
    for (uint32_t c = 0; c < ncells; c++)
        m->find[c] = p->emm_lookup + p->emm_quadtree_level * (uint64_t)l->cells[c].depth;
    if (l->ops->path_nodes) {
        uint32_t nodes[EMM_LAYOUT_MAX_DEPTH + 1];
        size_t total = 0;
        m->path_start = malloc(((size_t)ncells + 1) * sizeof *m->path_start);
        for (uint32_t c = 0; m->path_start && c < ncells; c++) {
            m->path_start[c] = (uint32_t)total;
            total += l->ops->path_nodes(l, c, nodes);
        }
        m->path = m->path_start ? malloc((total ? total : 1) * sizeof *m->path) : NULL;
        if (!m->path) {
            st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the layout's tree", name);
            goto fail;
        }
        m->path_start[ncells] = (uint32_t)total;
        for (uint32_t c = 0; c < ncells; c++)
            l->ops->path_nodes(l, c, m->path + m->path_start[c]);
    }
    uint32_t k = 0;
    for (size_t v = 0; v < nv; v++) {
        const emm_layout_index *c;
        uint32_t nc = emm_layout_vertex_copies(l, (uint32_t)v, &c);
        m->vcopy_start[v] = k;
        for (uint32_t i = 0; i < nc; i++, k++) {
            m->vcopy_cell[k] = c[i].cell;
            m->vcopy_addr[k] = base + emm_layout_vertex_address(l, (uint32_t)v, c[i].cell, 0);
        }
        m->vhome_addr[v] = base + emm_layout_vertex_address(l, (uint32_t)v, EMM_LAYOUT_NONE, 0);
    }
    m->vcopy_start[nv] = k;
    /* What vertex_addr gives each vertex of each triangle right after that
     * triangle's access (the copies' search, done once here). */
    for (size_t t = 0; t < nt; t++) {
        m->cur_tri = NO_TRI;
        m->cur_cell = m->tri_cell[t];
        for (int c = 0; c < 3; c++) {
            uint32_t v = (uint32_t)g->tri[3 * t + (size_t)c];
            m->tri_v[3 * t + (size_t)c] = v;
            m->tri_vaddr[3 * t + (size_t)c] = vertex_addr(m, v);
        }
    }
    emm_model_share_release(share, l);
    l = NULL;

    if ((st = emm_cache_init(&m->cache, p, err)) != EMM_OK)
        goto fail;
    cl_reset(&m->base);
    *out = &m->base;
    return EMM_OK;
fail:
    if (l)
        emm_model_share_release(share, l);
    cl_destroy(&m->base);
    return st;
}
