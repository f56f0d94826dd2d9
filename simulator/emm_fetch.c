/* EMM strategies in the machine model: a layout's cells moved whole into
 * the local store by DMA and served from there (thesis §4.1), fetched
 * naively, by convolution or by extrapolation (thesis §4.2), evicted
 * least-recently-used, with the EMM runtime's own work charged per
 * operation (thesis §6.2: "instruction cycles"). The costs and every choice
 * are in docs/fetch.md.
 *
 * The model keeps a clock: the core's time advances by every charge, DMA
 * transfers run on the engine's channels meanwhile (simulator/dma.c), and
 * an access to a cell still in flight stalls for what is left. Every
 * charge lands in exactly one bucket, so the buckets add up to the clock.
 *
 * Everything a record needs is a flat array indexed by triangle, vertex
 * copy or cell, built once from the layout; the LRU order is an intrusive
 * doubly-linked list over cell numbers (STYLE.md §5, §12). */
#include "emm_fetch.h"

#include <assert.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dma.h"
#include "error.h"
#include "fetch_scheme.h"
#include "model.h"
#include "parse.h"

#define NONE EMM_LAYOUT_NONE

enum { ARR_VERTICES = 0, ARR_TRIANGLES = 1, ARR_OTHER = 2 };

/* Per-cell flags. CELL_USELESS: the cell's last prefetch was evicted
 * unused; it is not prefetched again until the program enters it
 * (docs/fetch.md, "Prefetch filter"). */
enum { CELL_PRESENT = 1u, CELL_PREFETCHED = 2u, CELL_USELESS = 4u };

/* The schemes, from EMM_FETCH_LIST. */
#define OPS_(e, n) [EMM_FETCH_##e] = &emm_fetch_##n##_ops,
static const struct emm_fetch_ops *const schemes[EMM_FETCH_COUNT] = {EMM_FETCH_LIST(OPS_)};
#undef OPS_

struct fetch_model {
    struct emm_model base;
    const struct emm_fetch_ops *scheme;
    void *scheme_state;    /* scheme->state_bytes */
    emm_machine_params params;
    emm_layout *layout;
    emm_addr_map map;

    /* The layout, flattened. */
    uint8_t *array_kind;   /* per trace array: ARR_* */
    uint64_t nv, nt;       /* vertices and triangles with a layout index */
    uint32_t ncells;
    uint32_t *tri_cell;    /* triangle -> cell */
    uint32_t *vcopy_start; /* vertex v's copies are vcopy_cell[vcopy_start[v] .. [v+1]) */
    uint32_t *vcopy_cell;
    uint64_t *cell_bytes;
    uint32_t *cell_ntri;
    uint64_t *lookup_cost; /* emm.lookup (+ emm.quadtree_level x depth) */

    /* Costs, from the machine. */
    uint64_t residency, predict, issue_instr, local_cycles;
    uint64_t compute_per_access, compute_per_work;
    uint64_t direct_read, direct_write;
    uint32_t word_shift;
    bool filter; /* emm.prefetch_filter */
    uint64_t budget, lookup_bytes;

    /* The run. */
    emm_dma dma;
    uint64_t now;
    uint64_t cycles[EMM_BUCKET_COUNT];
    uint64_t *ready;       /* present cells: when their transfer completes */
    uint32_t *prev, *next; /* LRU list of present cells, most recent at head */
    uint8_t *flags;
    uint64_t *cell_dma;    /* bytes DMA moved per cell (emm_model_cells) */
    uint32_t head, tail;
    uint64_t used;         /* bytes of present cells (resident or in flight) */
    uint32_t cur;          /* the cell of the previous access */
    uint32_t last_tri;     /* the cell of the latest triangle access */
    uint64_t accesses;
    uint64_t cell_changes, demand_fetches, demand_bytes, prefetches, prefetch_bytes;
    uint64_t useful_prefetches, dropped_prefetches, filtered_prefetches, evictions;
    uint64_t other_accesses;

    emm_fetch_evict_hook hook;
    void *hook_ctx;
};
typedef struct fetch_model fetch_model;

/* ---- the LRU list ---------------------------------------------------------- */

static void lru_unlink(fetch_model *m, uint32_t c)
{
    uint32_t p = m->prev[c], n = m->next[c];
    if (p != NONE)
        m->next[p] = n;
    else
        m->head = n;
    if (n != NONE)
        m->prev[n] = p;
    else
        m->tail = p;
}

static void lru_push_front(fetch_model *m, uint32_t c)
{
    m->prev[c] = NONE;
    m->next[c] = m->head;
    if (m->head != NONE)
        m->prev[m->head] = c;
    else
        m->tail = c;
    m->head = c;
}

static void evict(fetch_model *m, uint32_t c)
{
    assert(m->ready[c] <= m->now); /* a cell in flight is never evicted */
    if (m->hook)
        m->hook(m->hook_ctx, c, m->now, m->ready[c]);
    lru_unlink(m, c);
    m->flags[c] = m->flags[c] & CELL_PREFETCHED ? CELL_USELESS : 0;
    m->used -= m->cell_bytes[c];
    m->evictions++;
}

/* Makes room for `bytes` more by evicting least-recently-used resident
 * cells other than `keep` and other than cells in flight. Evicts nothing
 * and returns 0 when that cannot make enough room. */
static int make_room(fetch_model *m, uint64_t bytes, uint32_t keep)
{
    uint64_t need, freeable = 0;
    if (m->used + bytes <= m->budget)
        return 1;
    need = m->used + bytes - m->budget;
    for (uint32_t c = m->tail; c != NONE && freeable < need; c = m->prev[c])
        if (c != keep && m->ready[c] <= m->now)
            freeable += m->cell_bytes[c];
    if (freeable < need)
        return 0;
    for (uint32_t c = m->tail; m->used + bytes > m->budget;) {
        uint32_t p = m->prev[c];
        if (c != keep && m->ready[c] <= m->now)
            evict(m, c);
        c = p;
    }
    return 1;
}

/* ---- charging ---------------------------------------------------------------- */

static inline void charge(fetch_model *m, emm_bucket b, uint64_t cycles)
{
    m->cycles[b] += cycles;
    m->now += cycles;
}

static void stall_until(fetch_model *m, uint64_t t)
{
    if (t > m->now)
        charge(m, EMM_BUCKET_DMA_STALL, t - m->now);
}

/* The runtime's bookkeeping, then the core programs the engine; the cell is
 * present (in flight) from now on and most recently used. */
static void issue(fetch_model *m, uint32_t c)
{
    uint64_t core_free, done;
    charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->issue_instr);
    done = emm_dma_start(&m->dma, m->now, m->cell_bytes[c], &core_free);
    charge(m, EMM_BUCKET_DMA_ISSUE, core_free - m->now);
    m->ready[c] = done;
    m->cell_dma[c] += m->cell_bytes[c];
    m->used += m->cell_bytes[c];
    lru_push_front(m, c);
}

/* A cell the program needs now. Any resident cell but those in flight may
 * make room; when only cells in flight stand in the way the core waits for
 * the earliest of them to land. A cell never exceeds the budget (checked at
 * construction), so this ends. */
static void demand_fetch(fetch_model *m, uint32_t c)
{
    while (!make_room(m, m->cell_bytes[c], NONE)) {
        uint64_t first = UINT64_MAX;
        for (uint32_t x = m->head; x != NONE; x = m->next[x])
            if (m->ready[x] > m->now && m->ready[x] < first)
                first = m->ready[x];
        assert(first != UINT64_MAX);
        stall_until(m, first);
    }
    issue(m, c);
    m->flags[c] = CELL_PRESENT;
    m->demand_fetches++;
    m->demand_bytes += m->cell_bytes[c];
}

/* A cell the scheme expects the program to need soon (`entered` is the cell
 * being worked on, which stays). Finding the cell is a look-up; an empty
 * cell holds nothing to fetch; a present one needs nothing. Nor does a cell
 * whose last prefetch was evicted unused, until the program enters it: the
 * prefetch pollution filter of Zhuang & Lee (ICPP 2003), one bit per cell
 * beside the residency bit, so a guess that already failed once cannot
 * keep pushing the cells in use out. A prefetch that finds no room without
 * evicting a cell in flight is dropped: waiting would stall the core for a
 * guess. */
void emm_fetcher_prefetch(fetch_model *m, uint32_t c, uint32_t entered)
{
    charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->lookup_cost[c]);
    if (m->cell_ntri[c] == 0)
        return;
    charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->residency);
    if (m->flags[c] & CELL_PRESENT)
        return;
    if ((m->flags[c] & CELL_USELESS) && m->filter) {
        m->filtered_prefetches++;
        return;
    }
    if (!make_room(m, m->cell_bytes[c], entered)) {
        m->dropped_prefetches++;
        return;
    }
    issue(m, c);
    m->flags[c] = CELL_PRESENT | CELL_PREFETCHED;
    m->prefetches++;
    m->prefetch_bytes += m->cell_bytes[c];
}

const emm_layout *emm_fetcher_layout(const emm_fetcher *f)
{
    return f->layout;
}

const emm_machine_params *emm_fetcher_params(const emm_fetcher *f)
{
    return &f->params;
}

void emm_fetcher_instructions(emm_fetcher *f, uint64_t cycles)
{
    charge(f, EMM_BUCKET_EMM_INSTRUCTIONS, cycles);
}

/* ---- the record loop --------------------------------------------------------- */

static inline uint32_t vertex_cell(const fetch_model *m, uint64_t v)
{
    uint32_t lo, hi;
    if (v >= m->nv)
        return NONE;
    lo = m->vcopy_start[v];
    hi = m->vcopy_start[v + 1];
    if (lo == hi)
        return NONE;
    /* The copy in the cell of the triangle just read: the thesis' triangles
     * point at their local vertex copies (§4.1.1, Fig. 4.4). */
    for (uint32_t i = lo; i < hi; i++)
        if (m->vcopy_cell[i] == m->last_tri)
            return m->last_tri;
    return m->vcopy_cell[lo];
}

static void direct_access(fetch_model *m, const emm_trace_record *r)
{
    uint64_t a = emm_addr_of(&m->map, r);
    uint64_t words = ((a + r->bytes - 1) >> m->word_shift) - (a >> m->word_shift) + 1;
    charge(m, EMM_BUCKET_REMOTE_ACCESS, words * (r->write ? m->direct_write : m->direct_read));
    m->other_accesses++;
}

static void access_one(fetch_model *m, const emm_trace_record *r)
{
    uint32_t c;
    charge(m, EMM_BUCKET_COMPUTE, m->compute_per_access + (uint64_t)r->work * m->compute_per_work);
    switch (m->array_kind[r->array]) {
    case ARR_TRIANGLES:
        c = r->element < m->nt ? m->tri_cell[r->element] : NONE;
        if (c != NONE)
            m->last_tri = c;
        break;
    case ARR_VERTICES:
        c = vertex_cell(m, r->element);
        break;
    default:
        c = NONE;
        break;
    }
    if (c == NONE) {
        direct_access(m, r);
        return;
    }
    charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->lookup_cost[c] + m->residency);
    if (c != m->cur) {
        uint32_t from = m->cur;
        m->cell_changes++;
        m->cur = c;
        if (!(m->flags[c] & CELL_PRESENT))
            demand_fetch(m, c);
        else if (m->flags[c] & CELL_PREFETCHED) {
            m->useful_prefetches++;
            m->flags[c] &= (uint8_t)~CELL_PREFETCHED;
        }
        if (m->scheme->enter)
            m->scheme->enter(m, m->scheme_state, from, c);
    } else if (!(m->flags[c] & CELL_PRESENT)) {
        demand_fetch(m, c); /* only after a reset of the residency by hand */
    }
    stall_until(m, m->ready[c]);
    if (m->head != c) {
        lru_unlink(m, c);
        lru_push_front(m, c);
    }
    /* One local access per record, whatever its size: the cache model
     * charges a hit once per line reference, "as if the data was in local
     * memory" (thesis §3.2), and the same local store must cost the same. */
    charge(m, EMM_BUCKET_LOCAL_ACCESS, m->local_cycles);
}

static void fetch_run(emm_model *model, const emm_trace_record *recs, size_t n)
{
    fetch_model *m = (fetch_model *)model;
    for (size_t i = 0; i < n; i++)
        access_one(m, &recs[i]);
    m->accesses += n;
}

static void fetch_reset(emm_model *model)
{
    fetch_model *m = (fetch_model *)model;
    emm_dma_reset(&m->dma);
    m->now = 0;
    memset(m->cycles, 0, sizeof m->cycles);
    memset(m->flags, 0, m->ncells);
    memset(m->cell_dma, 0, m->ncells * sizeof *m->cell_dma);
    m->head = m->tail = NONE;
    m->used = 0;
    m->cur = m->last_tri = NONE;
    if (m->scheme->state_bytes)
        memset(m->scheme_state, 0, m->scheme->state_bytes);
    if (m->scheme->reset)
        m->scheme->reset(m->scheme_state, &m->params);
    m->accesses = 0;
    m->cell_changes = m->demand_fetches = m->demand_bytes = 0;
    m->prefetches = m->prefetch_bytes = 0;
    m->useful_prefetches = m->dropped_prefetches = m->filtered_prefetches = 0;
    m->evictions = m->other_accesses = 0;
}

static void fetch_result(const emm_model *model, emm_result *out)
{
    const fetch_model *m = (const fetch_model *)model;
    out->accesses = m->accesses;
    out->total = 0;
    for (int b = 0; b < EMM_BUCKET_COUNT; b++) {
        out->cycles[b] = m->cycles[b];
        out->total += m->cycles[b];
    }
    assert(out->total == m->now);
    out->has_dma = 1;
    out->dma.transfers = m->dma.transfers;
    out->dma.bytes = m->dma.bytes;
    out->has_emm = 1;
    out->emm.cell_changes = m->cell_changes;
    out->emm.demand_fetches = m->demand_fetches;
    out->emm.demand_bytes = m->demand_bytes;
    out->emm.prefetches = m->prefetches;
    out->emm.prefetch_bytes = m->prefetch_bytes;
    out->emm.useful_prefetches = m->useful_prefetches;
    out->emm.dropped_prefetches = m->dropped_prefetches;
    out->emm.filtered_prefetches = m->filtered_prefetches;
    out->emm.evictions = m->evictions;
    out->emm.other_accesses = m->other_accesses;
    out->emm.local_budget = m->budget;
    out->emm.lookup_bytes = m->lookup_bytes;
}

static void fetch_destroy(emm_model *model)
{
    fetch_model *m = (fetch_model *)model;
    emm_layout_free(m->layout);
    emm_addr_map_free(&m->map);
    free(m->array_kind);
    free(m->tri_cell);
    free(m->vcopy_start);
    free(m->vcopy_cell);
    free(m->cell_bytes);
    free(m->cell_ntri);
    free(m->lookup_cost);
    free(m->ready);
    free(m->prev);
    free(m->next);
    free(m->flags);
    free(m->cell_dma);
    free(m->scheme_state);
    free(m);
}

static const struct emm_model_ops fetch_ops = {fetch_run, fetch_reset, fetch_result, fetch_destroy};

/* ---- construction ------------------------------------------------------------ */

/* Builds the layout and the local store its cells may use: local.bytes
 * minus the layout's own look-up tables (docs/fetch.md, "The local store").
 * Those tables depend on the layout, so the layout is built unchecked
 * first; a cell that does not fit what the tables leave is reported by a
 * second build checked against exactly that, whose message names a CELL
 * that fits. */
static emm_status build_layout(fetch_model *m, const emm_machine_params *p, const emm_strategy *s,
                               const emm_trace_info *t, uint32_t vbytes, uint32_t tbytes,
                               emm_error *err)
{
    const emm_trace_geometry *g = &t->geometry;
    char name[64], where[160], b1[32], b2[32];
    uint64_t largest = 0;
    emm_layout_options o;
    emm_status st;

    emm_strategy_format(s, name, sizeof name);
    memset(&o, 0, sizeof o);
    o.kind = s->layout;
    o.cell = s->cell;
    o.vertex_bytes = vbytes;
    o.triangle_bytes = tbytes;
    o.local_store = 0;
    o.fetch = s->fetch;
    st = emm_layout_build(g->xyz, (size_t)g->nv, g->tri, (size_t)g->nt, &o, name, &m->layout, err);
    if (st != EMM_OK)
        return st;
    m->lookup_bytes = emm_layout_lookup_bytes(m->layout);
    if (m->lookup_bytes >= p->local_bytes)
        return emm_fail(err, EMM_ERR_RANGE,
                        "%s: the layout's look-up tables take %s bytes, more than the %s-byte "
                        "local store (local.bytes)",
                        name, emm_grouped(m->lookup_bytes, b1),
                        emm_grouped(p->local_bytes, b2));
    m->budget = p->local_bytes - m->lookup_bytes;
    for (uint32_t c = 0; c < emm_layout_cell_count(m->layout); c++)
        if (emm_layout_cell_get(m->layout, c)->bytes > largest)
            largest = emm_layout_cell_get(m->layout, c)->bytes;
    if (largest > m->budget) {
        emm_layout *again = NULL;
        o.local_store = m->budget;
        snprintf(where, sizeof where, "%s (local store less %s bytes of look-up tables)", name,
                 emm_grouped(m->lookup_bytes, b1));
        st = emm_layout_build(g->xyz, (size_t)g->nv, g->tri, (size_t)g->nt, &o, where, &again,
                              err);
        if (st == EMM_OK) { /* cannot happen: the same build, now checked */
            emm_layout_free(again);
            return emm_fail(err, EMM_ERR_RANGE,
                            "%s: a cell of %s bytes does not fit the %s bytes of local store "
                            "left by the look-up tables: use a smaller CELL than %u",
                            name, emm_grouped(largest, b1),
                            emm_grouped(m->budget, b2), s->cell);
        }
        return st;
    }
    return EMM_OK;
}

/* The flat arrays the record loop reads. */
static emm_status flatten(fetch_model *m, const emm_machine_params *p, emm_error *err)
{
    const emm_layout *l = m->layout;
    uint32_t nc = emm_layout_cell_count(l);
    uint64_t copies = 0;
    m->ncells = nc;
    m->nt = emm_layout_triangle_count(l);
    m->nv = emm_layout_vertex_count(l);
    m->tri_cell = malloc((m->nt ? m->nt : 1) * sizeof *m->tri_cell);
    m->vcopy_start = malloc((m->nv + 1) * sizeof *m->vcopy_start);
    m->cell_bytes = malloc(nc * sizeof *m->cell_bytes);
    m->cell_ntri = malloc(nc * sizeof *m->cell_ntri);
    m->lookup_cost = malloc(nc * sizeof *m->lookup_cost);
    m->ready = calloc(nc, sizeof *m->ready);
    m->prev = malloc(nc * sizeof *m->prev);
    m->next = malloc(nc * sizeof *m->next);
    m->flags = calloc(nc, 1);
    m->cell_dma = calloc(nc, sizeof *m->cell_dma);
    if (!m->tri_cell || !m->vcopy_start || !m->cell_bytes || !m->cell_ntri || !m->lookup_cost ||
        !m->ready || !m->prev || !m->next || !m->flags || !m->cell_dma)
        return emm_fail(err, EMM_ERR_NOMEM, "EMM model: out of memory for %u cells", nc);
    for (uint64_t t = 0; t < m->nt; t++)
        m->tri_cell[t] = emm_layout_triangle_index(l, (uint32_t)t).cell;
    for (uint64_t v = 0; v < m->nv; v++) {
        const emm_layout_index *cp;
        m->vcopy_start[v] = (uint32_t)copies;
        copies += emm_layout_vertex_copies(l, (uint32_t)v, &cp);
    }
    m->vcopy_start[m->nv] = (uint32_t)copies;
    m->vcopy_cell = malloc((copies ? copies : 1) * sizeof *m->vcopy_cell);
    if (!m->vcopy_cell)
        return emm_fail(err, EMM_ERR_NOMEM, "EMM model: out of memory for %llu vertex copies",
                        (unsigned long long)copies);
    for (uint64_t v = 0; v < m->nv; v++) {
        const emm_layout_index *cp;
        uint32_t k = emm_layout_vertex_copies(l, (uint32_t)v, &cp);
        for (uint32_t i = 0; i < k; i++)
            m->vcopy_cell[m->vcopy_start[v] + i] = cp[i].cell;
    }
    for (uint32_t c = 0; c < nc; c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        m->cell_bytes[c] = cell->bytes;
        m->cell_ntri[c] = cell->ntri;
        m->lookup_cost[c] = p->emm_lookup + p->emm_quadtree_level * cell->depth;
    }
    return EMM_OK;
}

emm_status emm_emm_model_new(const emm_machine_params *p, const emm_strategy *s,
                             const emm_trace_info *trace, emm_model **out, emm_error *err)
{
    fetch_model *m;
    emm_status st;
    uint32_t vbytes = 0, tbytes = 0;
    int have_v = 0, have_t = 0;
    char name[64];

    assert(s->kind == EMM_STRATEGY_EMM && s->cell >= 1);
    emm_strategy_format(s, name, sizeof name);
    if (!trace || trace->geometry.nt == 0 || !trace->geometry.xyz || !trace->geometry.tri)
        return emm_fail(err, EMM_ERR_INVALID,
                        "%s: the trace has no mesh geometry; only direct and cache apply to an "
                        "address-only trace",
                        name);
    m = calloc(1, sizeof *m);
    if (!m)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
    m->base.ops = &fetch_ops;
    m->scheme = schemes[s->fetch];
    m->params = *p;
    m->scheme_state = calloc(1, m->scheme->state_bytes ? m->scheme->state_bytes : 1);
    if (!m->scheme_state) {
        free(m);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
    }
    if ((st = emm_addr_map_init(&m->map, trace, err)) != EMM_OK) {
        free(m->scheme_state);
        free(m);
        return st;
    }
    m->array_kind = malloc(trace->narrays ? trace->narrays : 1);
    if (!m->array_kind) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
        goto fail;
    }
    /* The first vertex array and the first triangle array are the mesh the
     * geometry describes; any other array is plain memory, read directly. */
    for (uint32_t a = 0; a < trace->narrays; a++) {
        const emm_trace_array *arr = &trace->arrays[a];
        m->array_kind[a] = ARR_OTHER;
        if (arr->kind == EMM_ARRAY_VERTICES && !have_v) {
            have_v = 1;
            vbytes = arr->record_size;
            m->array_kind[a] = ARR_VERTICES;
        } else if (arr->kind == EMM_ARRAY_TRIANGLES && !have_t) {
            have_t = 1;
            tbytes = arr->record_size;
            m->array_kind[a] = ARR_TRIANGLES;
        }
    }
    if ((st = build_layout(m, p, s, trace, vbytes, tbytes, err)) != EMM_OK)
        goto fail;
    if ((st = flatten(m, p, err)) != EMM_OK)
        goto fail;
    m->residency = p->emm_residency;
    m->predict = p->emm_predict;
    m->issue_instr = p->emm_dma_issue_instr;
    m->local_cycles = p->local_cycles;
    m->compute_per_access = p->compute_per_access;
    m->compute_per_work = p->compute_per_work;
    m->direct_read = p->direct_cycles_per_word;
    m->direct_write = p->direct_write_cycles;
    while ((1ull << m->word_shift) < p->word_bytes)
        m->word_shift++;
    m->filter = p->emm_prefetch_filter != 0;
    emm_dma_init(&m->dma, p);
    fetch_reset(&m->base);
    *out = &m->base;
    return EMM_OK;
fail:
    fetch_destroy(&m->base);
    return st;
}

void emm_fetch_set_evict_hook(emm_model *model, emm_fetch_evict_hook hook, void *ctx)
{
    fetch_model *m = (fetch_model *)model;
    assert(model->ops == &fetch_ops);
    m->hook = hook;
    m->hook_ctx = ctx;
}

uint64_t emm_fetch_budget(const emm_model *model)
{
    assert(model->ops == &fetch_ops);
    return ((const fetch_model *)model)->budget;
}

const emm_layout *emm_fetch_layout(const emm_model *model)
{
    assert(model->ops == &fetch_ops);
    return ((const fetch_model *)model)->layout;
}

/* Per-cell traffic, for the report's "cells" key and `emm plot`'s map of
 * the mesh: only the cells' rectangles and counters, so a caller that
 * never asks pays one add per transfer. */
emm_status emm_model_cells(const emm_model *model, emm_result *out, emm_error *err)
{
    const fetch_model *m = (const fetch_model *)model;
    assert(model && out && !out->cells.cell);
    if (model->ops != &fetch_ops)
        return EMM_OK;
    out->cells.cell = malloc((m->ncells ? m->ncells : 1) * sizeof *out->cells.cell);
    if (!out->cells.cell)
        return emm_fail(err, EMM_ERR_NOMEM, "EMM model: out of memory for %u cells", m->ncells);
    out->cells.count = m->ncells;
    out->cells.dims = emm_layout_axes(m->layout, NULL, out->cells.lo, out->cells.hi);
    for (uint32_t c = 0; c < m->ncells; c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(m->layout, c);
        emm_cell_dma *o = &out->cells.cell[c];
        memcpy(o->lo, cell->lo, sizeof o->lo);
        memcpy(o->hi, cell->hi, sizeof o->hi);
        o->bytes = m->cell_dma[c];
    }
    return EMM_OK;
}

void emm_result_release(emm_result *r)
{
    free(r->cells.cell);
    memset(&r->cells, 0, sizeof r->cells);
}
