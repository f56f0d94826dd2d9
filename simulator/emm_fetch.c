/* EMM strategies in the machine model: a layout's cells moved whole into
 * the local store by DMA and served from there (thesis §4.1), fetched by a
 * scheme (fetch_*.c, thesis §4.2), evicted least-recently-used, with the EMM
 * runtime's own work charged per operation (thesis §6.2: "instruction
 * cycles") — and the operations are the thesis' (§4.1.1): a look-up per
 * element *request*, not per word; a vertex that the triangle just
 * requested names is reached through the triangle's pointer to its copy in
 * the same cell; the look-up tables in the local store while they fit their
 * budget, paged in by DMA beyond it. The indexed variant (":indexed", the
 * program renumbered by the layout) has no per-element table: a renumbered
 * id's cell is its own cell when it falls in the cell of the previous
 * access, else a binary search of the per-cell table. The costs and every
 * choice are in docs/fetch.md and docs/layouts.md.
 *
 * The model keeps a clock: the core's time advances by every charge, DMA
 * transfers run on the engine's channels meanwhile (simulator/dma.c), and
 * an access to a cell still in flight stalls for what is left. Every
 * charge lands in exactly one bucket, so the buckets add up to the clock.
 *
 * The layout is shared by every model of the same layout and cell size
 * (simulator/share.h) and read directly; a model keeps only per-cell state:
 * residency, the LRU list, DMA bytes. */
#include "emm_fetch.h"

#include <assert.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dma.h"
#include "error.h"
#include "fetch_scheme.h"
#include "layout_internal.h"
#include "model.h"
#include "parse.h"

#define NONE EMM_LAYOUT_NONE

/* The schemes, from EMM_FETCH_LIST. */
#define OPS_(e, n, w) [EMM_FETCH_##e] = &emm_fetch_##n##_ops,
static const struct emm_fetch_ops *const schemes[EMM_FETCH_COUNT] = {EMM_FETCH_LIST(OPS_)};
#undef OPS_

enum { ARR_VERTICES = 0, ARR_TRIANGLES = 1, ARR_OTHER = 2 };

/* Per-cell flags. CELL_USELESS: the cell's last prefetch was evicted
 * unused; it is not prefetched again until the program enters it
 * (docs/fetch.md, "Prefetch filter"). */
enum { CELL_PRESENT = 1u, CELL_PREFETCHED = 2u, CELL_USELESS = 4u };

/* The look-up tables in remote memory, when they are paged: the triangle
 * and vertex id tables (4 bytes an entry), then the cell table (8 bytes a
 * cell), then the rest (quadtree nodes); for the indexed variant, the
 * per-cell table alone (EMM_INDEXED_CELL_BYTES a cell). A frame holds one
 * page; the frames are kept least-recently-used. */
/* Transfers noted before the per-cell counters are brought up to date. */
#define DMA_LOG 256u

/* A model's state of one cell, everything the record loop, a prefetch and
 * an eviction read of it in one 32-byte slot (one cache line, never two):
 * the layout's cells are large and cold, and separate arrays cost a miss
 * each. */
typedef struct cell_state {
    uint64_t ready;       /* present cells: when their transfer completes */
    uint64_t bytes;       /* the cell's (the layout's emm_layout_cell.bytes) */
    uint32_t prev, next;  /* LRU list of present cells, most recent at head */
    uint32_t find;        /* emm.lookup + emm.quadtree_level x the leaf's depth: the
                             look-up's cost (at most 25 M: fits) */
    uint8_t flags;        /* CELL_* */
    uint8_t empty;        /* the cell holds no triangle */
    uint8_t fetched;      /* cell_dma[c] > 0, where the refetch count reads it: the
                             counters are cold */
} cell_state;
_Static_assert(sizeof(cell_state) == 32, "a cell's state is one aligned 32-byte slot");

typedef struct pager {
    uint64_t page;                  /* bytes per page */
    uint32_t page_shift;            /* log2(page) when page is a power of two, else 0 */
    uint32_t frames, used;
    uint64_t tri_off, vert_off, cell_off, cell_entry;
    uint64_t node_off;              /* a tree's nodes, 16 bytes each */
    const uint32_t *path_start;     /* ncells + 1: each cell's descent in path (shared) */
    const uint32_t *path;           /* the pages of the nodes each descent reads, root
                                       first, a page that the node before was on left out
                                       (touching it again changes nothing) */
    uint32_t npages;
    uint32_t *page_frame;           /* npages: the frame holding the page, or NONE */
    uint32_t *frame_page;           /* frames */
    uint32_t *prev, *next;          /* LRU list of frames, most recent at head */
    uint32_t head, tail;
    uint64_t fetches, bytes;
} pager;

struct fetch_model {
    struct emm_model base;
    const struct emm_fetch_ops *scheme;
    void *scheme_state;    /* scheme->state_bytes */
    emm_machine_params params;
    emm_model_share *share;
    const emm_layout *layout; /* shared; read-only */
    const int32_t *tri;       /* the triangles' vertex ids, shared */
    emm_addr_map map;
    uint8_t *array_kind;      /* per trace array: ARR_* */

    /* The layout, as the record loop reads it. */
    uint64_t nv, nt;          /* vertices and triangles with a layout index */
    uint32_t ncells;
    const uint32_t *tri_cell;
    const uint32_t *vcopy_start;
    const emm_layout_index *vcopy;
    const emm_layout_cell *cells;
    cell_state *cell;         /* per cell: the model's state of it */

    /* Costs, from the machine. */
    uint64_t residency, issue_instr, local_cycles;
    uint64_t compute_per_access, compute_per_work;
    uint64_t direct_read, direct_write;
    uint32_t word_shift;
    bool filter;              /* emm.prefetch_filter */
    uint64_t budget, lookup_bytes;
    bool paged;
    bool indexed;             /* the ":indexed" variant */
    uint64_t search;          /* indexed: emm.quadtree_level x the binary search's steps */
    pager pg;

    /* The run. */
    emm_dma dma;
    uint64_t cycles[EMM_BUCKET_COUNT];
    /* Not beside cycles: a charge then adds to both in one 16-byte load and
     * store, which cannot take the 8-byte store just made to either (a
     * store-forwarding stall on every record). */
    uint64_t now;
    uint64_t *cell_dma;       /* bytes DMA moved per cell (emm_model_cells), but for */
    uint32_t dma_log[DMA_LOG]; /* the cells fetched since it was last brought up to date:
                                  added in one go, their misses overlap (one at every
                                  transfer stalled the record loop) */
    uint32_t ndma_log;
    uint32_t head, tail;
    uint64_t used;            /* bytes of present cells (resident or in flight) */
    uint64_t last_ready;      /* the latest arrival of a cell's transfer: none in flight
                                 once the clock has passed it */
    uint32_t cur;             /* the cell of the previous access */
    uint32_t last_tri;        /* the cell of the latest triangle request */
    uint64_t last_tv[3];      /* that triangle's vertex ids (as the record loop compares
                                 them with a vertex's), or UINT64_MAX: none */
    bool any;                 /* a record was seen */
    uint32_t last_array;      /* the previous record's element */
    uint64_t last_element;
    uint32_t last_cell;       /* the cell that served it, or NONE */
    uint64_t accesses, lookups, pointers, same_record;
    uint64_t cell_changes, demand_fetches, demand_bytes, prefetches, prefetch_bytes;
    uint64_t useful_prefetches, dropped_prefetches, filtered_prefetches, evictions;
    uint64_t other_accesses;
    uint64_t refetches, refetch_bytes, unused_prefetches, prefetch_checks;
    uint32_t present;         /* cells present (resident or in flight) */
    uint64_t resident_sum;    /* present, summed at every cell change */

    emm_fetch_evict_hook hook;
    void *hook_ctx;
    emm_stall_fn stall_fn;    /* emm_model_stalls, or NULL */
    void *stall_ctx;
    const emm_trace_record *rec; /* the record being served (for stall_fn) */
    bool observed;            /* obs is set (emm_model_observe) */
    emm_observer obs;
    void *obs_ctx;
};
typedef struct fetch_model fetch_model;

/* ---- the LRU list ---------------------------------------------------------- */

static void lru_unlink(fetch_model *m, uint32_t c)
{
    uint32_t p = m->cell[c].prev, n = m->cell[c].next;
    if (p != NONE)
        m->cell[p].next = n;
    else
        m->head = n;
    if (n != NONE)
        m->cell[n].prev = p;
    else
        m->tail = p;
}

static void lru_push_front(fetch_model *m, uint32_t c)
{
    m->cell[c].prev = NONE;
    m->cell[c].next = m->head;
    if (m->head != NONE)
        m->cell[m->head].prev = c;
    else
        m->tail = c;
    m->head = c;
}

static void evict(fetch_model *m, uint32_t c)
{
    assert(m->cell[c].ready <= m->now); /* a cell in flight is never evicted */
    if (m->hook)
        m->hook(m->hook_ctx, c, m->now, m->cell[c].ready);
    lru_unlink(m, c);
    m->unused_prefetches += (m->cell[c].flags & CELL_PREFETCHED) != 0;
    m->cell[c].flags = m->cell[c].flags & CELL_PREFETCHED ? CELL_USELESS : 0;
    m->used -= m->cell[c].bytes;
    m->present--;
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
    if (m->last_ready <= m->now) {
        /* No cell in flight: every present cell but `keep` may go. */
        freeable = m->used;
        if (keep != NONE && (m->cell[keep].flags & CELL_PRESENT))
            freeable -= m->cell[keep].bytes;
    } else {
        for (uint32_t c = m->tail; c != NONE && freeable < need; c = m->cell[c].prev)
            if (c != keep && m->cell[c].ready <= m->now)
                freeable += m->cell[c].bytes;
    }
    if (freeable < need)
        return 0;
    for (uint32_t c = m->tail; m->used + bytes > m->budget;) {
        uint32_t p = m->cell[c].prev;
        if (c != keep && m->cell[c].ready <= m->now)
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

static void __attribute__((noinline)) stall(fetch_model *m, uint64_t t)
{
    if (m->observed && m->obs.stall)
        m->obs.stall(m->obs_ctx, m->now, t - m->now);
    if (m->stall_fn)
        m->stall_fn(m->stall_ctx, m->rec, t - m->now);
    charge(m, EMM_BUCKET_DMA_STALL, t - m->now);
}

/* The core waits for time t, if it is still to come (on every record: the
 * test inline, the wait not). */
static inline void stall_until(fetch_model *m, uint64_t t)
{
    if (t > m->now)
        stall(m, t);
}

/* The runtime's bookkeeping, then the core programs the engine for `what`
 * (a cell, or a page of the tables); returns when the data will have
 * arrived. */
static uint64_t start_dma(fetch_model *m, uint64_t bytes, emm_transfer_kind kind, uint64_t what)
{
    uint64_t core_free, done;
    charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->issue_instr);
    done = emm_dma_start(&m->dma, m->now, bytes, &core_free);
    if (m->observed && m->obs.transfer)
        m->obs.transfer(m->obs_ctx, m->dma.last_channel, m->dma.last_start, done, bytes, kind,
                        what);
    charge(m, EMM_BUCKET_DMA_ISSUE, core_free - m->now);
    return done;
}

/* ---- the look-up tables ------------------------------------------------------ */

static void frame_unlink(pager *g, uint32_t f)
{
    uint32_t p = g->prev[f], n = g->next[f];
    if (p != NONE)
        g->next[p] = n;
    else
        g->head = n;
    if (n != NONE)
        g->prev[n] = p;
    else
        g->tail = p;
}

static void frame_push_front(pager *g, uint32_t f)
{
    g->prev[f] = NONE;
    g->next[f] = g->head;
    if (g->head != NONE)
        g->prev[g->head] = f;
    else
        g->tail = f;
    g->head = f;
}

/* A page of the tables not in a frame: brought in by a DMA the core waits
 * for, into the least recently used frame. */
static void __attribute__((noinline)) page_in(fetch_model *m, uint32_t p)
{
    pager *g = &m->pg;
    uint32_t f;
    if (g->used < g->frames) {
        f = g->used++;
    } else {
        f = g->tail;
        frame_unlink(g, f);
        g->page_frame[g->frame_page[f]] = NONE;
    }
    g->frame_page[f] = p;
    g->page_frame[p] = f;
    frame_push_front(g, f);
    stall_until(m, start_dma(m, g->page, EMM_TRANSFER_TABLE_PAGE, p));
    g->fetches++;
    g->bytes += g->page;
}

/* The table entry at byte `off` of the tables: a resident page is a local
 * access to it, and its frame becomes the most recently used; a missing one
 * is paged in. (The page by a shift when its size is a power of two: a
 * division on every look-up is dear.) */
static inline void touch_page(fetch_model *m, uint32_t p)
{
    pager *g = &m->pg;
    uint32_t f = g->page_frame[p];
    if (f == NONE) {
        page_in(m, p);
    } else if (g->head != f) {
        frame_unlink(g, f);
        frame_push_front(g, f);
    }
}

static inline void touch_table(fetch_model *m, uint64_t off)
{
    const pager *g = &m->pg;
    touch_page(m, (uint32_t)(g->page_shift ? off >> g->page_shift : off / g->page));
}

/* The descent to cell c's leaf reads the tree's nodes on its path, which
 * are part of the paged tables (emm_layout_lookup_bytes counts them): their
 * pages. Nothing for a layout without a tree. */
static void touch_path(fetch_model *m, uint32_t c)
{
    const pager *g = &m->pg;
    if (!g->path)
        return;
    for (uint32_t k = g->path_start[c]; k < g->path_start[c + 1]; k++)
        touch_page(m, g->path[k]);
}

/* A look-up of element `e` of an array of `kind` in cell c (the id table
 * gives its layout index; a tree's nodes on the way down, or the cell
 * table, its cell's place and residency): emm.lookup, plus
 * emm.quadtree_level per level descended, plus emm.residency; with paged
 * tables, the pages those entries live in. */
static void lookup(fetch_model *m, int kind, uint64_t e, uint32_t c)
{
    charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->cell[c].find + m->residency);
    m->lookups++;
    if (m->indexed) {
        /* The renumbered id against the previous access's cell, one
         * compare; outside it, a binary search of the cells' starts. */
        if (c != m->cur)
            charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->search);
        if (m->paged)
            touch_table(m, m->pg.cell_off + m->pg.cell_entry * (uint64_t)c);
        return;
    }
    if (m->paged) {
        touch_table(m, (kind == ARR_TRIANGLES ? m->pg.tri_off : m->pg.vert_off) + 4 * e);
        touch_path(m, c);
        touch_table(m, m->pg.cell_off + 8 * (uint64_t)c);
    }
}

/* ---- fetching ---------------------------------------------------------------- */

static void __attribute__((noinline)) flush_dma_log(fetch_model *m)
{
    for (uint32_t i = 0; i < m->ndma_log; i++)
        m->cell_dma[m->dma_log[i]] += m->cell[m->dma_log[i]].bytes;
    m->ndma_log = 0;
}

/* The core programs the engine for cell c, which is present (in flight)
 * from now on and most recently used. */
static void issue(fetch_model *m, uint32_t c, emm_transfer_kind kind)
{
    uint64_t bytes = m->cell[c].bytes;
    uint64_t ready = start_dma(m, bytes, kind, c);
    m->cell[c].ready = ready;
    if (ready > m->last_ready)
        m->last_ready = ready;
    if (m->cell[c].fetched) {
        m->refetches++;
        m->refetch_bytes += bytes;
    }
    m->cell[c].fetched |= bytes != 0;
    m->dma_log[m->ndma_log++] = c;
    if (m->ndma_log == DMA_LOG)
        flush_dma_log(m);
    m->used += bytes;
    m->present++;
    lru_push_front(m, c);
}

/* A cell the program needs now. Any resident cell but those in flight may
 * make room; when only cells in flight stand in the way the core waits for
 * the earliest of them to land. A cell never exceeds the budget (checked at
 * construction), so this ends. */
static void demand_fetch(fetch_model *m, uint32_t c)
{
    while (!make_room(m, m->cell[c].bytes, NONE)) {
        uint64_t first = UINT64_MAX;
        for (uint32_t x = m->head; x != NONE; x = m->cell[x].next)
            if (m->cell[x].ready > m->now && m->cell[x].ready < first)
                first = m->cell[x].ready;
        assert(first != UINT64_MAX);
        stall_until(m, first);
    }
    issue(m, c, EMM_TRANSFER_DEMAND);
    m->cell[c].flags = CELL_PRESENT;
    m->demand_fetches++;
    m->demand_bytes += m->cell[c].bytes;
}

/* A cell the scheme expects the program to need soon (`entered` is the cell
 * being worked on, which stays). Finding the cell is a look-up in the cell
 * table; an empty cell holds nothing to fetch; a present one needs nothing.
 * Nor does a cell whose last prefetch was evicted unused, until the program
 * enters it: the prefetch pollution filter of Zhuang & Lee (ICPP 2003), one
 * bit per cell beside the residency bit, so a guess that already failed
 * once cannot keep pushing the cells in use out. A prefetch that finds no
 * room without evicting a cell in flight is dropped: waiting would stall
 * the core for a guess. */
void emm_fetcher_prefetch(fetch_model *m, uint32_t c, uint32_t entered)
{
    m->prefetch_checks++;
    charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->cell[c].find);
    if (m->paged) {
        if (!m->indexed)
            touch_path(m, c);
        touch_table(m, m->pg.cell_off + m->pg.cell_entry * (uint64_t)c);
    }
    if (m->cell[c].empty)
        return;
    charge(m, EMM_BUCKET_EMM_INSTRUCTIONS, m->residency);
    if (m->cell[c].flags & CELL_PRESENT)
        return;
    if ((m->cell[c].flags & CELL_USELESS) && m->filter) {
        m->filtered_prefetches++;
        return;
    }
    if (!make_room(m, m->cell[c].bytes, entered)) {
        m->dropped_prefetches++;
        return;
    }
    issue(m, c, EMM_TRANSFER_PREFETCH);
    m->cell[c].flags = CELL_PRESENT | CELL_PREFETCHED;
    m->prefetches++;
    m->prefetch_bytes += m->cell[c].bytes;
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

/* The cell serving vertex v: its copy in the cell of the latest triangle
 * request when it has one there, else its home copy (NONE: a vertex no
 * triangle uses). *pointer: v is a vertex of that triangle, whose layout
 * record points at the copy (thesis §4.1.1, Fig. 4.4): no look-up. */
static inline uint32_t vertex_cell(const fetch_model *m, uint64_t v, bool *pointer)
{
    *pointer = false;
    if (v >= m->nv)
        return NONE;
    /* First the triangle just requested, which is in the cache: a vertex of
     * a triangle with a layout index has a copy in that triangle's cell
     * (layout.c, fill_vertices), so its copies need not be looked at — the
     * index table is the cold load of the record loop. The triangle's
     * vertex ids were copied when it was requested, and tested at once:
     * which of them it is does not matter and would be a branch
     * mispredicted every other time. */
    if ((m->last_tv[0] == v) | (m->last_tv[1] == v) | (m->last_tv[2] == v)) {
        assert(m->vcopy_start[v] != m->vcopy_start[v + 1]);
        *pointer = true;
        return m->last_tri;
    }
    uint32_t lo = m->vcopy_start[v], hi = m->vcopy_start[v + 1];
    if (lo == hi)
        return NONE;
    for (uint32_t i = lo; i < hi; i++)
        if (m->vcopy[i].cell == m->last_tri)
            return m->last_tri;
    return m->vcopy[lo].cell;
}

static void direct_access(fetch_model *m, const emm_trace_record *r)
{
    uint64_t a = emm_addr_of(&m->map, r);
    uint64_t words = (emm_last_byte(a, r->bytes) >> m->word_shift) - (a >> m->word_shift) + 1;
    charge(m, EMM_BUCKET_REMOTE_ACCESS, words * (r->write ? m->direct_write : m->direct_read));
    m->other_accesses++;
}

static void access_one(fetch_model *m, const emm_trace_record *r)
{
    m->rec = r;
    charge(m, EMM_BUCKET_COMPUTE, m->compute_per_access + (uint64_t)r->work * m->compute_per_work);
    m->any = true;
    m->last_array = r->array;
    m->last_element = r->element;
    int kind = m->array_kind[r->array];
    bool pointer = false;
    uint32_t c = NONE;
    if (kind == ARR_TRIANGLES && r->element < m->nt) {
        c = m->tri_cell[r->element];
        m->last_tri = c;
        const int32_t *t = m->tri + 3 * r->element;
        m->last_tv[0] = (uint64_t)t[0];
        m->last_tv[1] = (uint64_t)t[1];
        m->last_tv[2] = (uint64_t)t[2];
    } else if (kind == ARR_VERTICES) {
        c = vertex_cell(m, r->element, &pointer);
    }
    m->last_cell = c;
    if (c == NONE) {
        direct_access(m, r);
        return;
    }
    if (pointer)
        m->pointers++;
    else
        lookup(m, kind, r->element, c);
    if (c != m->cur) {
        uint32_t from = m->cur;
        m->cell_changes++;
        m->resident_sum += m->present;
        m->cur = c;
        if (m->observed && m->obs.enter)
            m->obs.enter(m->obs_ctx, m->now, c);
        if (!(m->cell[c].flags & CELL_PRESENT))
            demand_fetch(m, c);
        else if (m->cell[c].flags & CELL_PREFETCHED) {
            m->useful_prefetches++;
            m->cell[c].flags &= (uint8_t)~CELL_PREFETCHED;
        }
        if (m->scheme->enter)
            m->scheme->enter(m, m->scheme_state, from, c);
    } else if (!(m->cell[c].flags & CELL_PRESENT)) {
        demand_fetch(m, c); /* only after a reset of the residency by hand */
    }
    stall_until(m, m->cell[c].ready);
    if (m->head != c) {
        lru_unlink(m, c);
        lru_push_front(m, c);
    }
    /* One local access per record, whatever its size: the cache model
     * charges a hit once per line reference, "as if the data was in local
     * memory" (thesis §3.2), and the same local store must cost the same. */
    charge(m, EMM_BUCKET_LOCAL_ACCESS, m->local_cycles);
}

/* The further loads of the record just requested from recs[i] on, up to
 * n: the runtime has handed the program its local copy, so each is the
 * compute of an access and a local access and no more — charged as one run,
 * which starts no transfer and waits for none, so the clock and every
 * bucket come out as they do one by one. Returns where the run ends. */
static inline size_t same_run(fetch_model *m, const emm_trace_record *recs, size_t i, size_t n)
{
    const uint64_t element = m->last_element;
    const uint32_t array = m->last_array;
    uint64_t work = 0;
    size_t j = i;
    while (j < n && recs[j].element == element && recs[j].array == array)
        work += recs[j++].work;
    if (j > i) {
        uint64_t k = j - i;
        m->same_record += k;
        charge(m, EMM_BUCKET_COMPUTE, k * m->compute_per_access + work * m->compute_per_work);
        charge(m, EMM_BUCKET_LOCAL_ACCESS, k * m->local_cycles);
    }
    return j;
}

/* Record by record, each record's further loads (the most common record: a
 * vertex's y and z after its x) as one run. Only the first records of a
 * call can continue the previous call's record; within a call, a record
 * after a run is another. A record served by direct reads has no local
 * copy: its further loads are records of their own. */
static void fetch_run(emm_model *model, const emm_trace_record *recs, size_t n)
{
    fetch_model *m = (fetch_model *)model;
    size_t i = 0;
    if (m->any && m->last_cell != NONE)
        i = same_run(m, recs, 0, n);
    while (i < n) {
        access_one(m, &recs[i++]);
        if (m->last_cell != NONE)
            i = same_run(m, recs, i, n);
    }
    m->accesses += n;
}

static void fetch_reset(emm_model *model)
{
    fetch_model *m = (fetch_model *)model;
    emm_dma_reset(&m->dma);
    m->now = 0;
    memset(m->cycles, 0, sizeof m->cycles);
    for (uint32_t c = 0; c < m->ncells; c++)
        m->cell[c].flags = m->cell[c].fetched = 0;
    memset(m->cell_dma, 0, m->ncells * sizeof *m->cell_dma);
    m->ndma_log = 0;
    m->head = m->tail = NONE;
    m->used = 0;
    m->last_ready = 0;
    m->present = 0;
    m->cur = m->last_tri = m->last_cell = NONE;
    m->last_tv[0] = m->last_tv[1] = m->last_tv[2] = UINT64_MAX;
    m->any = false;
    if (m->scheme->state_bytes)
        memset(m->scheme_state, 0, m->scheme->state_bytes);
    if (m->scheme->reset)
        m->scheme->reset(m->scheme_state, &m->params);
    if (m->paged) {
        pager *g = &m->pg;
        for (uint32_t p = 0; p < g->npages; p++)
            g->page_frame[p] = NONE;
        g->used = 0;
        g->head = g->tail = NONE;
        g->fetches = g->bytes = 0;
    }
    m->accesses = m->lookups = m->pointers = m->same_record = 0;
    m->cell_changes = m->demand_fetches = m->demand_bytes = 0;
    m->prefetches = m->prefetch_bytes = 0;
    m->useful_prefetches = m->dropped_prefetches = m->filtered_prefetches = 0;
    m->evictions = m->other_accesses = 0;
    m->refetches = m->refetch_bytes = m->unused_prefetches = m->prefetch_checks = 0;
    m->resident_sum = 0;
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
    out->emm.lookups = m->lookups;
    out->emm.pointer_accesses = m->pointers;
    out->emm.same_record = m->same_record;
    out->emm.lookup_paged = m->paged;
    out->emm.lookup_pages = m->paged ? m->pg.fetches : 0;
    out->emm.lookup_page_bytes = m->paged ? m->pg.bytes : 0;
    out->emm.refetches = m->refetches;
    out->emm.refetch_bytes = m->refetch_bytes;
    out->emm.unused_prefetches = m->unused_prefetches;
    out->emm.prefetch_checks = m->prefetch_checks;
    out->emm.resident_cells = m->resident_sum;
}

static void fetch_costs(const emm_model *model, emm_record_cost *out)
{
    const fetch_model *m = (const fetch_model *)model;
    memcpy(out->cycles, m->cycles, sizeof out->cycles);
    out->lookups = m->lookups;
}

static void fetch_observe(emm_model *model, const emm_observer *obs, void *ctx)
{
    fetch_model *m = (fetch_model *)model;
    m->observed = obs != NULL;
    if (obs)
        m->obs = *obs;
    m->obs_ctx = ctx;
}

static void fetch_stalls(emm_model *model, emm_stall_fn fn, void *ctx)
{
    fetch_model *m = (fetch_model *)model;
    m->stall_fn = fn;
    m->stall_ctx = ctx;
}

static void fetch_destroy(emm_model *model)
{
    fetch_model *m = (fetch_model *)model;
    if (m->layout)
        emm_model_share_release(m->share, m->layout);
    emm_model_share_unref(m->share);
    emm_addr_map_free(&m->map);
    free(m->array_kind);
    free(m->cell);
    free(m->cell_dma);
    free(m->scheme_state);
    free(m->pg.page_frame);
    free(m->pg.frame_page);
    free(m->pg.prev);
    free(m->pg.next);
    free(m);
}

static const struct emm_model_ops fetch_ops = {fetch_run,   fetch_reset,   fetch_result, fetch_destroy,
                                               fetch_costs, fetch_observe, fetch_stalls};

/* ---- construction ------------------------------------------------------------ */

/* The local store the cells may use (docs/fetch.md, "The local store"):
 * local.bytes less the look-up tables, when they fit emm.lookup_budget (and
 * half the local store) and leave room for the largest cell; less the
 * tables' page frames when they do not and are paged — the budget's
 * frames, or fewer (at least two) when the largest cell needs the room.
 * Those
 * tables depend on the layout, so it is built (shared, unchecked) first; a
 * cell that does not fit what the tables leave is reported with a CELL
 * that fits, searched once for the models of the layout that share that
 * local store (emm_model_share_fit). */
static emm_status plan_local_store(fetch_model *m, const emm_machine_params *p,
                                   const emm_strategy *s, const emm_trace_info *t,
                                   const emm_layout_options *o, emm_error *err)
{
    char name[64], where[200], b1[32], b2[32];
    emm_strategy_format(s, name, sizeof name);
    m->lookup_bytes = m->indexed ? (uint64_t)EMM_INDEXED_CELL_BYTES * m->ncells
                                 : emm_layout_lookup_bytes(m->layout);
    uint64_t tables = m->lookup_bytes;
    /* The tables' budget, and never more than half the local store: the
     * cells need the rest. */
    uint64_t budget = p->emm_lookup_budget < p->local_bytes / 2 ? p->emm_lookup_budget
                                                                 : p->local_bytes / 2;
    uint64_t largest = 0;
    for (uint32_t c = 0; c < m->ncells; c++)
        if (m->cells[c].bytes > largest)
            largest = m->cells[c].bytes;
    /* Tables that fit neither their budget nor beside the largest cell (where
     * two page frames would) are paged; their page frames take the budget,
     * or what the largest cell leaves when that is less (at least two): a
     * large cell costs the tables' frames, not the strategy. */
    uint64_t two = 2 * (uint64_t)p->emm_lookup_page;
    if (tables > budget || (largest + two <= p->local_bytes && tables > p->local_bytes - largest)) {
        m->paged = true;
        m->pg.page = p->emm_lookup_page;
        if ((m->pg.page & (m->pg.page - 1)) == 0)
            while ((1ull << m->pg.page_shift) < m->pg.page)
                m->pg.page_shift++;
        /* (A cell that leaves no two frames does not fit anyway: its
         * error then reads against the budget's frames.) */
        uint64_t room = largest + two <= p->local_bytes ? p->local_bytes - largest : budget;
        uint64_t frames = (budget < room ? budget : room) / p->emm_lookup_page;
        m->pg.frames = (uint32_t)(frames < 2 ? 2 : frames > UINT32_MAX ? UINT32_MAX : frames);
        tables = (uint64_t)m->pg.frames * m->pg.page;
    }
    if (tables >= p->local_bytes)
        return emm_fail(err, EMM_ERR_RANGE,
                        "%s: the layout's look-up tables take %s bytes of the %s-byte local "
                        "store (local.bytes); lower emm.lookup_budget to page them",
                        name, emm_grouped(tables, b1), emm_grouped(p->local_bytes, b2));
    m->budget = p->local_bytes - tables;
    if (largest <= m->budget)
        return EMM_OK;
    snprintf(where, sizeof where, "%s (local store less %s bytes of look-up tables)", name,
             emm_grouped(tables, b1));
    uint32_t suggest = 0;
    emm_status st = emm_model_share_fit(m->share, t, m->layout, m->budget, &suggest, where, err);
    if (st != EMM_OK)
        return st;
    return emm_layout_too_large(m->layout, o->fetch, m->budget, suggest, where, err);
}

/* The pages each cell's descent reads (pager.path_start, pager.path): the
 * same for every model over one layout and page size, so built once for
 * them all (emm_model_share_derived). */
struct paths {
    uint32_t *start, *path;
};

static void free_paths(void *p)
{
    struct paths *d = p;
    if (d) {
        free(d->start);
        free(d->path);
    }
    free(d);
}

/* Each descent's nodes, as pages of `page` bytes from node_off on, a page
 * the node before was on left out: one descent at a time into a list that
 * grows. */
static emm_status build_paths(const emm_layout *l, uint64_t page, uint64_t node_off, void **out,
                              emm_error *err)
{
    uint32_t nodes[EMM_LAYOUT_MAX_DEPTH + 1];
    size_t cap = (size_t)l->ncells * 4 + EMM_LAYOUT_MAX_DEPTH + 1, w = 0;
    struct paths *d = calloc(1, sizeof *d);
    if (d) {
        d->start = malloc(((size_t)l->ncells + 1) * sizeof *d->start);
        d->path = malloc(cap * sizeof *d->path);
    }
    if (!d || !d->start || !d->path)
        goto nomem;
    for (uint32_t c = 0; c < l->ncells; c++) {
        uint32_t k = l->ops->path_nodes(l, c, nodes);
        if (w + k > cap) {
            uint32_t *more = realloc(d->path, 2 * cap * sizeof *d->path);
            if (!more)
                goto nomem;
            d->path = more;
            cap *= 2;
        }
        d->start[c] = (uint32_t)w;
        for (uint32_t i = 0, last = NONE; i < k; i++) {
            uint64_t off = node_off + 16 * (uint64_t)nodes[i];
            uint32_t pg = (uint32_t)(off / page);
            if (pg != last)
                d->path[w++] = last = pg;
        }
    }
    d->start[l->ncells] = (uint32_t)w;
    *out = d;
    return EMM_OK;
nomem:
    free_paths(d);
    return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the paged tables");
}

static emm_status alloc_pager(fetch_model *m, const char *name, emm_error *err)
{
    pager *g = &m->pg;
    const emm_layout *l = m->layout;
    g->tri_off = 0;
    g->vert_off = m->indexed ? 0 : 4 * (uint64_t)l->nt;
    g->cell_off = m->indexed ? 0 : g->vert_off + 4 * (uint64_t)l->nv;
    g->cell_entry = m->indexed ? EMM_INDEXED_CELL_BYTES : 8;
    g->node_off = g->cell_off + 8 * (uint64_t)l->ncells;
    if (!m->indexed && l->ops->path_nodes) {
        const struct paths *d = NULL;
        emm_error e;
        if (emm_model_share_derived(m->share, l, g->page, g->node_off, build_paths, free_paths,
                                    (const void **)&d, &e) != EMM_OK)
            return emm_fail(err, e.status, "%s: %s", name, e.message);
        g->path_start = d->start;
        g->path = d->path;
    }
    uint64_t npages = (m->lookup_bytes + g->page - 1) / g->page;
    if (npages > UINT32_MAX - 1)
        return emm_fail(err, EMM_ERR_RANGE, "%s: %llu pages of look-up tables are too many",
                        name, (unsigned long long)npages);
    g->npages = (uint32_t)npages;
    if (g->frames > g->npages)
        g->frames = g->npages;
    g->page_frame = malloc((npages ? npages : 1) * sizeof *g->page_frame);
    g->frame_page = malloc((size_t)g->frames * sizeof *g->frame_page);
    g->prev = malloc((size_t)g->frames * sizeof *g->prev);
    g->next = malloc((size_t)g->frames * sizeof *g->next);
    if (!g->page_frame || !g->frame_page || !g->prev || !g->next)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the paged tables", name);
    return EMM_OK;
}

emm_status emm_emm_model_new(const emm_machine_params *p, const emm_strategy *s,
                             const emm_trace_info *trace, emm_model_share *share,
                             emm_model **out, emm_error *err)
{
    fetch_model *m;
    emm_status st;
    emm_layout_options o;
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
    m->share = share;
    emm_model_share_ref(share);
    m->scheme_state = calloc(1, m->scheme->state_bytes ? m->scheme->state_bytes : 1);
    m->array_kind = malloc(trace->narrays ? trace->narrays : 1);
    if (!m->scheme_state || !m->array_kind) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
        goto fail;
    }
    if ((st = emm_addr_map_init(&m->map, trace, err)) != EMM_OK)
        goto fail;
    /* The first vertex array and the first triangle array are the mesh the
     * geometry describes; any other array is plain memory, read directly. */
    memset(&o, 0, sizeof o);
    o.kind = s->layout;
    o.cell = s->cell;
    o.fetch = s->fetch;
    bool have_v = false, have_t = false;
    for (uint32_t a = 0; a < trace->narrays; a++) {
        const emm_trace_array *arr = &trace->arrays[a];
        m->array_kind[a] = ARR_OTHER;
        if (arr->kind == EMM_ARRAY_VERTICES && !have_v) {
            have_v = true;
            o.vertex_bytes = arr->record_size;
            m->array_kind[a] = ARR_VERTICES;
        } else if (arr->kind == EMM_ARRAY_TRIANGLES && !have_t) {
            have_t = true;
            o.triangle_bytes = arr->record_size;
            m->array_kind[a] = ARR_TRIANGLES;
        }
    }
    if (o.vertex_bytes == 0)
        o.vertex_bytes = EMM_THESIS_VERTEX_BYTES;
    if (o.triangle_bytes == 0)
        o.triangle_bytes = EMM_THESIS_TRIANGLE_BYTES;
    /* A program without a triangle array: its geometry's triangles are its
     * vertices (the session's cells of vertices), carrying no records. */
    o.vertex_cells = have_v && !have_t;
    /* The triangle's pointers to its vertices' copies, which vertex_cell
     * credits, are words of this machine: they take room in the cell. */
    o.pointer_bytes = (uint32_t)p->word_bytes;
    if ((st = emm_model_share_layout(share, trace, &o, name, &m->layout, err)) != EMM_OK) {
        m->layout = NULL;
        goto fail;
    }
    if (!(m->tri = emm_model_share_triangles(share, trace, err))) {
        st = EMM_ERR_NOMEM;
        goto fail;
    }
    const emm_layout *l = m->layout;
    m->ncells = l->ncells;
    m->nt = l->nt;
    m->nv = l->nv;
    m->tri_cell = l->tri_cell;
    m->vcopy_start = l->vcopy_start;
    m->vcopy = l->vcopy;
    m->cells = l->cells;
    m->indexed = s->indexed != 0;
    if ((st = plan_local_store(m, p, s, trace, &o, err)) != EMM_OK)
        goto fail;
    if (m->paged && (st = alloc_pager(m, name, err)) != EMM_OK)
        goto fail;
    uint32_t nc = m->ncells;
    m->cell = aligned_alloc(sizeof *m->cell, (nc ? nc : 1) * sizeof *m->cell);
    m->cell_dma = calloc(nc, sizeof *m->cell_dma);
    if (!m->cell || !m->cell_dma) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for %u cells", name, nc);
        goto fail;
    }
    m->residency = p->emm_residency;
    /* The indexed variant finds a cell from the id, not by descending the
     * tree: its steps are the binary search's, and only outside the cell of
     * the previous access (lookup()). */
    for (uint32_t c = 0; c < nc; c++) {
        cell_state *x = &m->cell[c];
        memset(x, 0, sizeof *x);
        x->bytes = m->cells[c].bytes;
        x->find = (uint32_t)(p->emm_lookup +
                             (m->indexed ? 0 : p->emm_quadtree_level * m->cells[c].depth));
        x->empty = m->cells[c].ntri == 0;
    }
    uint32_t steps = 0;
    while (steps < 32 && (1ull << steps) < nc)
        steps++;
    m->search = (uint64_t)p->emm_quadtree_level * steps;
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
 * the mesh: only the cells' boxes and counters, so a caller that never
 * asks pays one add per transfer. */
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
        emm_cell_dma *o = &out->cells.cell[c];
        memcpy(o->lo, m->cells[c].lo, sizeof o->lo);
        memcpy(o->hi, m->cells[c].hi, sizeof o->hi);
        o->bytes = m->cell_dma[c];
    }
    for (uint32_t i = 0; i < m->ndma_log; i++)
        out->cells.cell[m->dma_log[i]].bytes += m->cell[m->dma_log[i]].bytes;
    return EMM_OK;
}

void emm_result_release(emm_result *r)
{
    free(r->cells.cell);
    memset(&r->cells, 0, sizeof r->cells);
}
