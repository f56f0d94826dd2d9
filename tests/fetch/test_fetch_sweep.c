/* Every strategy of the sweep on synthetic traces: the buckets add up to
 * the total, the DMA counts agree with the fetches, naive never prefetches,
 * and no eviction ever takes a cell in flight, at the default local store
 * and at one small enough to force evictions everywhere. */
#include "emm_fetch.h"
#include "fetch_util.h"

struct evictions {
    uint64_t count, in_flight;
};

static void on_evict(void *ctx, uint32_t cell, uint64_t now, uint64_t ready)
{
    struct evictions *e = ctx;
    (void)cell;
    e->count++;
    if (ready > now)
        e->in_flight++;
}

static void sweep(const emm_machine *mc, const loaded_trace *t, const char *what)
{
    size_t n = emm_strategy_sweep(NULL, 0);
    emm_strategy *s = calloc(n, sizeof *s);
    REQUIRE(s && emm_strategy_sweep(s, n) == n);
    for (size_t i = 0; i < n; i++) {
        char name[64];
        emm_model *model;
        emm_result r;
        emm_error err;
        struct evictions ev = {0, 0};
        uint64_t sum = 0;
        emm_strategy_format(&s[i], name, sizeof name);
        if (s[i].kind != EMM_STRATEGY_EMM)
            continue;
        if (emm_model_new(mc, &s[i], t->info, &model, &err) != EMM_OK) {
            /* A local store too small for this CELL is an error that says so. */
            CHECKF(err.status == EMM_ERR_RANGE && strstr(err.message, "CELL"), "%s %s: %s", what,
                   name, err.message);
            continue;
        }
        emm_fetch_set_evict_hook(model, on_evict, &ev);
        emm_model_run(model, t->recs, t->n / 2);
        emm_model_run(model, t->recs + t->n / 2, t->n - t->n / 2);
        emm_model_result(model, &r);
        emm_model_free(model);
        for (int b = 0; b < EMM_BUCKET_COUNT; b++)
            sum += r.cycles[b];
        CHECKF(sum == r.total, "%s %s: buckets %llu, total %llu", what, name,
               (unsigned long long)sum, (unsigned long long)r.total);
        CHECK(r.accesses == t->n);
        CHECK(r.cycles[EMM_BUCKET_CACHE_HIT] == 0 && r.cycles[EMM_BUCKET_CACHE_MISS_STALL] == 0);
        CHECK(r.has_dma && r.has_emm);
        /* Every DMA is a cell (on demand or ahead) or a page of the look-up
         * tables. */
        CHECKF(r.dma.transfers == r.emm.demand_fetches + r.emm.prefetches + r.emm.lookup_pages,
               "%s %s", what, name);
        CHECK(r.dma.bytes == r.emm.demand_bytes + r.emm.prefetch_bytes + r.emm.lookup_page_bytes);
        CHECK(r.emm.lookup_paged || r.emm.lookup_pages == 0);
        CHECK(r.emm.useful_prefetches <= r.emm.prefetches);
        CHECK(r.emm.demand_fetches <= r.emm.cell_changes);
        CHECK(r.cycles[EMM_BUCKET_DMA_ISSUE] ==
              emm_machine_get(mc, "dma.program") * r.dma.transfers);
        if (s[i].fetch == EMM_FETCH_NAIVE)
            CHECK(r.emm.prefetches == 0 && r.emm.dropped_prefetches == 0 &&
                  r.emm.filtered_prefetches == 0);
        /* A filtered cell is one whose prefetch was evicted unused. */
        CHECK(r.emm.filtered_prefetches == 0 ||
              r.emm.useful_prefetches < r.emm.prefetches);
        CHECKF(ev.in_flight == 0, "%s %s: %llu evictions of cells in flight", what, name,
               (unsigned long long)ev.in_flight);
        CHECK(ev.count == r.emm.evictions);
    }
    free(s);
}

int main(void)
{
    emm_mesh *mesh = thesis_mesh(4000);
    emm_machine *def, *small;
    emm_error err;
    static const emm_pattern patterns[] = {EMM_PATTERN_REGION, EMM_PATTERN_CURVE,
                                           EMM_PATTERN_RANDOM, EMM_PATTERN_SCANLINE};
    REQUIRE(emm_machine_new(&def, &err) == EMM_OK);
    REQUIRE(emm_machine_new(&small, &err) == EMM_OK);
    /* About 40 KiB of look-up tables leaves 24 KiB for cells. */
    REQUIRE(emm_machine_set(small, "local.bytes=64K", &err) == EMM_OK);
    REQUIRE(emm_machine_set(small, "emm.fifo=2", &err) == EMM_OK);
    /* The traces' work of 5 a record: compute between accesses, which moves
     * the transfers' timing, on the small store; the default machine
     * charges none (docs/machine.md "Compute"), so both timings are run. */
    REQUIRE(emm_machine_set(small, "compute.per_work=1", &err) == EMM_OK);
    uint64_t small_evictions = 0, small_filtered = 0;
    for (size_t p = 0; p < sizeof patterns / sizeof patterns[0]; p++) {
        emm_synth_options so;
        loaded_trace t;
        memset(&so, 0, sizeof so);
        so.pattern = patterns[p];
        so.seed = 3;
        so.work = 5;
        synth_load(mesh, &so, "fetch_sweep.emmt", &t);
        sweep(def, &t, emm_pattern_name(patterns[p]));
        sweep(small, &t, emm_pattern_name(patterns[p]));
        {
            emm_result r;
            simulate_ok(small, "tiles+convolution@16", &t, &r);
            small_evictions += r.emm.evictions;
            small_filtered += r.emm.filtered_prefetches;
        }
        free_trace(&t);
    }
    /* The small store did exercise eviction. */
    CHECK(small_evictions > 1000);
    /* ... and the prefetch filter. */
    CHECK(small_filtered > 0);
    emm_machine_free(def);
    emm_machine_free(small);
    emm_mesh_free(mesh);
    return check_done();
}
