/* The hardware cache (thesis §3.2): set-associative, LRU, next-line
 * prefetch, counted exactly like Dinero IV's d4ref (docs/dinero.md) and
 * timed with the DMA cost formula:
 *   hit                        cache.hit cycles                 (cache hit)
 *   miss                       local.cycles                     (local access)
 *                              + a stalled DMA of one line      (cache miss stall)
 *   read miss that prefetches  local.cycles + a stalled DMA of two lines
 *   hit on a line whose always-prefetch is still in flight: the rest of the
 *                              transfer (cache miss stall), then a hit.
 *
 * The per-line loop is specialised per fetch policy (a constant argument to
 * an inline function), so the common loop carries no policy tests. */
#include "cache.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "model.h"

static unsigned log2u(uint64_t v)
{
    unsigned s = 0;
    while ((1ull << s) < v)
        s++;
    return s;
}

emm_status emm_cache_init(emm_cache *c, const emm_machine_params *p, emm_error *err)
{
    uint64_t lines = p->cache_bytes / p->cache_line;
    memset(c, 0, sizeof *c);
    c->assoc = (uint32_t)p->cache_assoc;
    c->set_mask = lines / p->cache_assoc - 1;
    c->line_shift = log2u(p->cache_line);
    c->fetch = (emm_cache_fetch)p->cache_fetch;
    c->hit_cycles = p->cache_hit;
    c->local_cycles = p->local_cycles;
    c->fill1 = emm_dma_sync_cycles(p, p->cache_line);
    c->fill2 = emm_dma_sync_cycles(p, 2 * p->cache_line);
    c->compute_per_access = p->compute_per_access;
    c->compute_per_work = p->compute_per_work;
    c->tags = malloc(lines * sizeof *c->tags);
    if (c->fetch == EMM_CACHE_FETCH_ALWAYS)
        c->ready = malloc(lines * sizeof *c->ready);
    if (!c->tags || (c->fetch == EMM_CACHE_FETCH_ALWAYS && !c->ready)) {
        emm_cache_free(c);
        return emm_fail(err, EMM_ERR_NOMEM, "cache: out of memory for %llu lines",
                        (unsigned long long)lines);
    }
    emm_cache_reset(c);
    return EMM_OK;
}

void emm_cache_reset(emm_cache *c)
{
    size_t lines = (size_t)(c->set_mask + 1) * c->assoc;
    for (size_t i = 0; i < lines; i++)
        c->tags[i] = EMM_CACHE_EMPTY;
    if (c->ready)
        memset(c->ready, 0, lines * sizeof *c->ready);
    memset(&c->n, 0, sizeof c->n);
}

void emm_cache_free(emm_cache *c)
{
    free(c->tags);
    free(c->ready);
    c->tags = c->ready = NULL;
}

/* The loop works on a copy of the cache's geometry and counts in locals
 * (struct hot, whose address never escapes the inlined loop), so the stores
 * into the tag array do not force the compiler to reload them. */
struct hot {
    uint64_t *tags, *ready;
    uint64_t set_mask;
    uint32_t assoc, line_shift;
    uint64_t hit_cycles, local_cycles, fill1, fill2;
    uint64_t compute_per_access, compute_per_work;
    struct emm_cache_counts n;
};

static inline void hot_load(struct hot *h, const emm_cache *c)
{
    h->tags = c->tags;
    h->ready = c->ready;
    h->set_mask = c->set_mask;
    h->assoc = c->assoc;
    h->line_shift = c->line_shift;
    h->hit_cycles = c->hit_cycles;
    h->local_cycles = c->local_cycles;
    h->fill1 = c->fill1;
    h->fill2 = c->fill2;
    h->compute_per_access = c->compute_per_access;
    h->compute_per_work = c->compute_per_work;
    h->n = c->n;
}

/* Finds block b in its set and makes it most recently used. Returns 1 on a
 * hit; on a miss puts b in the least recently used way (an empty way, when
 * there is one, is always at the end) and returns 0. With ready times kept,
 * *r points at the set's arrival times, whose first entry is b's. */
static inline int touch(const struct hot *h, uint64_t b, const int keep_ready, uint64_t **r)
{
    uint64_t *set = h->tags + (b & h->set_mask) * h->assoc;
    uint32_t i = 0, n = h->assoc;
    int hit;
    if (set[0] == b) {
        if (keep_ready)
            *r = h->ready + (b & h->set_mask) * h->assoc;
        return 1;
    }
    while (i < n && set[i] != b)
        i++;
    hit = i < n;
    if (!hit)
        i = n - 1;
    for (uint32_t j = i; j > 0; j--)
        set[j] = set[j - 1];
    set[0] = b;
    if (keep_ready) {
        uint64_t *rs = h->ready + (b & h->set_mask) * h->assoc;
        uint64_t rt = hit ? rs[i] : 0;
        for (uint32_t j = i; j > 0; j--)
            rs[j] = rs[j - 1];
        rs[0] = rt;
        *r = rs;
    }
    return hit;
}

/* One demand reference to block b, in Dinero's order: the demand line is
 * placed first, then the prefetch reference to b+1 is made. */
static inline void line_ref(struct hot *h, uint64_t b, int write, const emm_cache_fetch policy)
{
    const int keep_ready = policy == EMM_CACHE_FETCH_ALWAYS;
    uint64_t *rdy = NULL, *prdy = NULL;
    h->n.demand_fetches++;
    if (touch(h, b, keep_ready, &rdy)) {
        if (keep_ready) {
            if (rdy[0] > h->n.now) {
                h->n.late_stall += rdy[0] - h->n.now;
                h->n.late_prefetches++;
                h->n.now = rdy[0];
            }
            h->n.now += h->hit_cycles;
            if (!write) {
                h->n.prefetch_fetches++;
                if (!touch(h, b + 1, keep_ready, &prdy)) {
                    h->n.prefetch_misses++;
                    /* The prefetch runs while the core goes on. */
                    prdy[0] = h->n.now + h->fill1;
                }
            }
        }
        return;
    }
    h->n.demand_misses++;
    if (policy != EMM_CACHE_FETCH_DEMAND && !write) {
        h->n.prefetch_fetches++;
        if (!touch(h, b + 1, keep_ready, &prdy)) {
            h->n.prefetch_misses++;
            /* Both lines come in one stalled transfer, so the prefetched
             * line is there when the core resumes. */
            h->n.double_fills++;
            if (keep_ready)
                h->n.now += h->fill2 - h->fill1;
        }
    }
    if (keep_ready)
        h->n.now += h->local_cycles + h->fill1;
}

static inline void access_one(struct hot *h, uint64_t addr, uint32_t bytes, int write,
                              uint32_t work, const emm_cache_fetch policy)
{
    uint64_t compute = h->compute_per_access + (uint64_t)work * h->compute_per_work;
    uint64_t b = addr >> h->line_shift;
    uint64_t last = emm_last_byte(addr, bytes) >> h->line_shift;
    h->n.compute += compute;
    if (policy == EMM_CACHE_FETCH_ALWAYS)
        h->n.now += compute;
    h->n.accesses++;
    line_ref(h, b, write, policy);
    while (b != last)
        line_ref(h, ++b, write, policy);
}

void emm_cache_access(emm_cache *c, uint64_t addr, uint32_t bytes, int write, uint32_t work)
{
    struct hot h;
    assert(bytes >= 1);
    hot_load(&h, c);
    switch (c->fetch) {
    case EMM_CACHE_FETCH_DEMAND: access_one(&h, addr, bytes, write, work, EMM_CACHE_FETCH_DEMAND); break;
    case EMM_CACHE_FETCH_MISS: access_one(&h, addr, bytes, write, work, EMM_CACHE_FETCH_MISS); break;
    case EMM_CACHE_FETCH_ALWAYS: access_one(&h, addr, bytes, write, work, EMM_CACHE_FETCH_ALWAYS); break;
    }
    c->n = h.n;
}

void emm_cache_result(const emm_cache *c, emm_result *out)
{
    const struct emm_cache_counts *n = &c->n;
    uint64_t single = n->demand_misses - n->double_fills;
    memset(out->cycles, 0, sizeof out->cycles);
    out->accesses = n->accesses;
    out->cycles[EMM_BUCKET_COMPUTE] = n->compute;
    out->cycles[EMM_BUCKET_CACHE_HIT] = (n->demand_fetches - n->demand_misses) * c->hit_cycles;
    out->cycles[EMM_BUCKET_LOCAL_ACCESS] = n->demand_misses * c->local_cycles;
    out->cycles[EMM_BUCKET_CACHE_MISS_STALL] =
        single * c->fill1 + n->double_fills * c->fill2 + n->late_stall;
    out->total = 0;
    for (int i = 0; i < EMM_BUCKET_COUNT; i++)
        out->total += out->cycles[i];
    /* The clock of always-prefetch runs with the same costs. */
    assert(c->fetch != EMM_CACHE_FETCH_ALWAYS || out->total == n->now);
    out->has_cache = 1;
    out->cache.demand_fetches = n->demand_fetches;
    out->cache.demand_misses = n->demand_misses;
    out->cache.prefetch_fetches = n->prefetch_fetches;
    out->cache.prefetch_misses = n->prefetch_misses;
    out->cache.late_prefetches = n->late_prefetches;
}

/* ---- the cache model: records on their original addresses ---------------- */

typedef struct cache_model {
    struct emm_model base;
    emm_addr_map map;
    emm_cache cache;
} cache_model;

static void run_records(cache_model *m, const emm_trace_record *recs, size_t n,
                        const emm_cache_fetch policy)
{
    const uint64_t *base = m->map.base, *size = m->map.size;
    struct hot h;
    hot_load(&h, &m->cache);
    for (size_t i = 0; i < n; i++) {
        const emm_trace_record *r = &recs[i];
        uint64_t addr = base[r->array] + r->element * size[r->array] + r->offset;
        access_one(&h, addr, r->bytes, r->write, r->work, policy);
    }
    m->cache.n = h.n;
}

static void cache_run(emm_model *model, const emm_trace_record *recs, size_t n)
{
    cache_model *m = (cache_model *)model;
    switch (m->cache.fetch) {
    case EMM_CACHE_FETCH_DEMAND: run_records(m, recs, n, EMM_CACHE_FETCH_DEMAND); break;
    case EMM_CACHE_FETCH_MISS: run_records(m, recs, n, EMM_CACHE_FETCH_MISS); break;
    case EMM_CACHE_FETCH_ALWAYS: run_records(m, recs, n, EMM_CACHE_FETCH_ALWAYS); break;
    }
}

static void cache_reset(emm_model *model)
{
    emm_cache_reset(&((cache_model *)model)->cache);
}

static void cache_result(const emm_model *model, emm_result *out)
{
    emm_cache_result(&((const cache_model *)model)->cache, out);
}

static void cache_destroy(emm_model *model)
{
    cache_model *m = (cache_model *)model;
    emm_cache_free(&m->cache);
    emm_addr_map_free(&m->map);
    free(m);
}

static const struct emm_model_ops cache_ops = {cache_run, cache_reset, cache_result, cache_destroy,
                                               NULL,      NULL,        NULL};

emm_status emm_cache_model_new(const emm_machine_params *p, const emm_trace_info *trace,
                               emm_model **out, emm_error *err)
{
    cache_model *m = calloc(1, sizeof *m);
    emm_status st;
    if (!m)
        return emm_fail(err, EMM_ERR_NOMEM, "cache model: out of memory");
    m->base.ops = &cache_ops;
    if ((st = emm_addr_map_init(&m->map, trace, err)) != EMM_OK) {
        free(m);
        return st;
    }
    if ((st = emm_cache_init(&m->cache, p, err)) != EMM_OK) {
        emm_addr_map_free(&m->map);
        free(m);
        return st;
    }
    *out = &m->base;
    return EMM_OK;
}
