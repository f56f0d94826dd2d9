/* The EMM model on meshes small enough to compute by hand: a naive
 * strategy's cycles bucket by bucket, a local store that holds one cell
 * (prefetch dropped, LRU eviction), and the errors. */
#include <string.h>

#include "check.h"
#include "emm/sim.h"
#include "emm_fetch.h"

/* Two triangles of the unit square: with CELL 1 the grid has one column and
 * two rows, triangle 0 (centroid y = 1/3) in cell 0, triangle 1 in cell 1.
 * Each cell: 12 + 3 x 80 + 28 + 3 x 4 = 292 bytes (header, vertices, the
 * triangle's record and its 3 pointers to its vertices' copies, §4.1.1). */
static const double xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
static const int32_t tri[] = {0, 1, 2, 1, 3, 2};
static const emm_trace_array arrays[2] = {
    {EMM_ARRAY_VERTICES, 80, 4, 0x10000},
    {EMM_ARRAY_TRIANGLES, 28, 2, 0x20000},
};

static emm_trace_info info_of(int geometry)
{
    emm_trace_info t;
    memset(&t, 0, sizeof t);
    t.version = 1;
    t.narrays = 2;
    t.arrays = arrays;
    if (geometry) {
        t.geometry.nv = 4;
        t.geometry.nt = 2;
        t.geometry.xyz = xyz;
        t.geometry.tri = tri;
    }
    return t;
}

static emm_trace_record rec(uint32_t array, uint64_t element)
{
    emm_trace_record r;
    memset(&r, 0, sizeof r);
    r.array = array;
    r.element = element;
    r.offset = array == 1 ? 4 : 8; /* 24 bytes span 6 words either way */
    r.bytes = 24;
    return r;
}

static emm_model *model_of(const emm_machine *m, const char *name, const emm_trace_info *t)
{
    emm_strategy s;
    emm_model *model;
    emm_error err;
    REQUIRE(emm_strategy_parse(name, &s, &err) == EMM_OK);
    if (emm_model_new(m, &s, t, &model, &err) != EMM_OK) {
        fprintf(stderr, "%s: %s\n", name, err.message);
        exit(1);
    }
    return model;
}

/* The costs these by-hand numbers use: the core pays all 266 cycles of a
 * DMA's programming (dma.issue, the alias), a look-up costs 4. */
static emm_machine *hand_machine(void)
{
    emm_machine *m;
    emm_error err;
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "dma.issue=266", &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "emm.lookup=4", &err) == EMM_OK);
    return m;
}

static void naive_by_hand(void)
{
    emm_machine *m = hand_machine();
    emm_error err;
    emm_result r;
    emm_trace_info t = info_of(1);
    /* triangle 0, its vertex 0, triangle 1, its vertex 3, triangle 0 */
    emm_trace_record recs[5] = {rec(1, 0), rec(0, 0), rec(1, 1), rec(0, 3), rec(1, 0)};
    emm_model *model = model_of(m, "grid+naive@1", &t);
    emm_model_run(model, recs, 5);
    emm_model_result(model, &r);
    /* Every access: compute 1 and one local access of local.cycles = 1
     * however many words the record spans (6 here), as a cache hit costs
     * once per line. A triangle request pays the look-up, 4 + residency 2;
     * a vertex the triangle just requested names is reached through its
     * pointer, for nothing (thesis §4.1.1). Entering a cell not resident:
     * bookkeeping 20, programming 266, then the transfer of 292 bytes (2 x
     * ceil(292 / 8) = 74 cycles) is waited for. Total: 5 x 2 + 3 x 6 = 28,
     * 2 x (20 + 266 + 74) = 720 for the two fetches: 748. */
    CHECK(r.cycles[EMM_BUCKET_COMPUTE] == 5);
    CHECK(r.cycles[EMM_BUCKET_EMM_INSTRUCTIONS] == 3 * 6 + 2 * 20);
    CHECK(r.cycles[EMM_BUCKET_DMA_ISSUE] == 2 * 266);
    CHECK(r.cycles[EMM_BUCKET_DMA_STALL] == 2 * 74);
    CHECK(r.cycles[EMM_BUCKET_LOCAL_ACCESS] == 5 * 1);
    CHECKF(r.total == 748, "total %llu", (unsigned long long)r.total);
    CHECK(r.emm.lookups == 3 && r.emm.pointer_accesses == 2 && r.emm.same_record == 0);
    CHECK(!r.emm.lookup_paged && r.emm.lookup_pages == 0);
    CHECK(r.has_dma && r.dma.transfers == 2 && r.dma.bytes == 584);
    CHECK(r.has_emm && r.emm.cell_changes == 3 && r.emm.demand_fetches == 2);
    CHECK(r.emm.prefetches == 0 && r.emm.evictions == 0);
    /* 4 bytes per triangle and vertex, 8 per cell. */
    CHECK(r.emm.lookup_bytes == 4 * 2 + 4 * 4 + 8 * 2);
    CHECK(r.emm.local_budget == 256 * 1024 - r.emm.lookup_bytes);
    CHECK(r.accesses == 5);

    /* Reset, then the same records in two batches: the same result. */
    emm_model_reset(model);
    emm_model_result(model, &r);
    CHECK(r.total == 0 && r.accesses == 0 && r.dma.transfers == 0);
    emm_model_run(model, recs, 2);
    emm_model_run(model, recs + 2, 3);
    emm_model_result(model, &r);
    CHECK(r.total == 748);
    emm_model_free(model);

    /* Quadtree look-ups descend: the two leaves sit at depth 1 or deeper. */
    model = model_of(m, "quadtree+naive@1", &t);
    emm_model_run(model, recs, 5);
    emm_model_result(model, &r);
    CHECK(r.cycles[EMM_BUCKET_EMM_INSTRUCTIONS] >= 3 * (6 + 6) + 2 * 20);
    emm_model_free(model);

    /* The descent reads the tree's nodes, which are part of the tables: the
     * root splits once (tri 0 in child 0, tri 1 in child 3), so 4 cells and
     * 5 nodes: 8 + 16 + 32 bytes of id and cell tables, then the nodes at
     * 56 (16 bytes each). Paged in 64-byte pages with two frames (the 136
     * bytes exceed a 128-byte budget), every look-up reads page 0 (ids,
     * cells, the root) and page 1 (both leaves, at 72 and 120): 2 pages
     * fetched, where the ids and cells alone would need 1. */
    REQUIRE(emm_machine_set(m, "emm.lookup_page=64", &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "emm.lookup_budget=128", &err) == EMM_OK);
    model = model_of(m, "quadtree+naive@1", &t);
    emm_model_run(model, recs, 5);
    emm_model_result(model, &r);
    CHECK(r.emm.lookup_bytes == 8 + 16 + 32 + 5 * 16);
    CHECK(r.emm.lookup_paged);
    CHECKF(r.emm.lookup_pages == 2, "lookup pages %llu", (unsigned long long)r.emm.lookup_pages);
    emm_model_free(model);
    REQUIRE(emm_machine_set(m, "emm.lookup_page=1K", &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "emm.lookup_budget=128K", &err) == EMM_OK);

    /* Further loads of the record just requested are local accesses: the
     * triangle's three field loads pay one look-up. A vertex that triangle
     * 1 does not name (vertex 0) is looked up. */
    emm_trace_record again[5] = {rec(1, 1), rec(1, 1), rec(1, 1), rec(0, 0), rec(0, 0)};
    model = model_of(m, "grid+naive@1", &t);
    emm_model_run(model, again, 5);
    emm_model_result(model, &r);
    CHECK(r.emm.lookups == 2 && r.emm.same_record == 3 && r.emm.pointer_accesses == 0);
    CHECK(r.cycles[EMM_BUCKET_LOCAL_ACCESS] == 5);
    emm_model_free(model);

    /* The programming split: the core pays dma.program (bucket DMA issue);
     * dma.latency runs on the channel, and a demand fetch waits for it. */
    REQUIRE(emm_machine_set(m, "dma.program=100", &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "dma.latency=166", &err) == EMM_OK);
    model = model_of(m, "grid+naive@1", &t);
    emm_model_run(model, recs, 5);
    emm_model_result(model, &r);
    CHECK(r.cycles[EMM_BUCKET_DMA_ISSUE] == 2 * 100);
    CHECK(r.cycles[EMM_BUCKET_DMA_STALL] == 2 * (166 + 74));
    CHECK(r.total == 748);
    emm_model_free(model);
    emm_machine_free(m);
}

/* local.cycles is charged once per record: 5 records at 3 cycles add
 * 5 x (3 - 1) = 10 to the 748 above, whatever the records span. */
static void local_per_access(void)
{
    emm_machine *m = hand_machine();
    emm_error err;
    emm_result r;
    emm_trace_info t = info_of(1);
    emm_trace_record recs[5] = {rec(1, 0), rec(0, 0), rec(1, 1), rec(0, 3), rec(1, 0)};
    recs[1].bytes = 80; /* a whole vertex: 20 or 21 words */
    REQUIRE(emm_machine_set(m, "local.cycles=3", &err) == EMM_OK);
    emm_model *model = model_of(m, "grid+naive@1", &t);
    emm_model_run(model, recs, 5);
    emm_model_result(model, &r);
    CHECK(r.cycles[EMM_BUCKET_LOCAL_ACCESS] == 5 * 3);
    CHECKF(r.total == 758, "total %llu", (unsigned long long)r.total);
    emm_model_free(model);
    emm_machine_free(m);
}

/* The prefetch filter counts only prefetches evicted unused: a prefetch
 * that was used, or dropped for want of room, is not filtered. (Filtering
 * itself needs a third cell: test_fetch_sweep and the thesis ratio check
 * it on real meshes.) */
static void prefetch_filter(void)
{
    emm_machine *m;
    emm_error err;
    emm_result r;
    emm_trace_info t = info_of(1);
    /* Room for two cells (40 + 2 x 292). */
    emm_trace_record recs[4] = {rec(1, 0), rec(1, 0), rec(1, 1), rec(1, 0)};
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "local.bytes=624", &err) == EMM_OK);
    emm_model *model = model_of(m, "grid+convolution@1", &t);
    emm_model_run(model, recs, 4);
    emm_model_result(model, &r);
    /* Cell 0 on demand, cell 1 prefetched and then entered: useful. */
    CHECK(r.emm.demand_fetches == 1 && r.emm.prefetches == 1 && r.emm.useful_prefetches == 1);
    CHECK(r.emm.filtered_prefetches == 0 && r.emm.evictions == 0);
    /* Each of the three entries (0, 1, 0 again) names the other cell: three
     * candidates; nothing is fetched twice or evicted; no cell present at
     * the first entry, both at the other two. */
    CHECK(r.emm.prefetch_checks == 3 && r.emm.refetches == 0 && r.emm.unused_prefetches == 0);
    CHECK(r.emm.cell_changes == 3 && r.emm.resident_cells == 0 + 2 + 2);
    emm_model_free(model);

    /* Room for one cell: entering cell 0 wants cell 1, which does not fit
     * beside it (dropped, not filtered: it was never prefetched). */
    REQUIRE(emm_machine_set(m, "local.bytes=332", &err) == EMM_OK);
    model = model_of(m, "grid+convolution@1", &t);
    emm_model_run(model, recs, 1);
    emm_model_result(model, &r);
    CHECK(r.emm.dropped_prefetches == 1 && r.emm.filtered_prefetches == 0);
    emm_model_free(model);
    emm_machine_free(m);
}

struct evictions {
    int count, in_flight;
};

static void on_evict(void *ctx, uint32_t cell, uint64_t now, uint64_t ready)
{
    struct evictions *e = ctx;
    (void)cell;
    e->count++;
    if (ready > now)
        e->in_flight++;
}

/* A local store with room for one cell after the look-up tables. */
static void one_cell_store(void)
{
    emm_machine *m;
    emm_error err;
    emm_result r;
    struct evictions ev = {0, 0};
    emm_trace_info t = info_of(1);
    emm_trace_record recs[3] = {rec(1, 0), rec(1, 1), rec(1, 0)};
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "local.bytes=332", &err) == EMM_OK); /* 40 + 292 */
    emm_model *model = model_of(m, "grid+convolution@1", &t);
    CHECK(emm_fetch_budget(model) == 292);
    emm_fetch_set_evict_hook(model, on_evict, &ev);
    emm_model_run(model, recs, 3);
    emm_model_result(model, &r);
    /* Entering cell 0: its neighbour cell 1 cannot come in beside cell 0
     * (in flight and in use): dropped. Cell 1, then cell 0 again, each
     * evict the other once it has landed. */
    CHECK(r.emm.demand_fetches == 3);
    CHECK(r.emm.prefetches == 0);
    CHECK(r.emm.dropped_prefetches == 3);
    CHECK(r.emm.evictions == 2 && ev.count == 2);
    CHECK(ev.in_flight == 0);
    /* Cell 0's second fetch is a refetch of its 292 bytes; no prefetch
     * came in, so none went out unused. */
    CHECK(r.emm.refetches == 1 && r.emm.refetch_bytes == 292);
    CHECK(r.emm.unused_prefetches == 0 && r.emm.prefetch_checks == 3);
    emm_model_free(model);

    /* One byte less and no cell fits: the layout's error names a CELL. */
    REQUIRE(emm_machine_set(m, "local.bytes=331", &err) == EMM_OK);
    {
        emm_strategy s;
        emm_model *x = NULL;
        REQUIRE(emm_strategy_parse("grid+naive@1", &s, &err) == EMM_OK);
        CHECK(emm_model_new(m, &s, &t, &x, &err) == EMM_ERR_RANGE);
        CHECKF(strstr(err.message, "grid+naive@1") && strstr(err.message, "292"), "%s",
               err.message);
    }
    emm_machine_free(m);
}

static void errors(void)
{
    emm_machine *m;
    emm_error err;
    emm_strategy s;
    emm_model *x = NULL;
    emm_trace_info bare = info_of(0);
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    REQUIRE(emm_strategy_parse("tiles+extrapolated@64", &s, &err) == EMM_OK);
    CHECK(emm_model_new(m, &s, &bare, &x, &err) == EMM_ERR_INVALID);
    CHECKF(strstr(err.message, "only direct and cache apply to an address-only trace") != NULL,
           "%s", err.message);
    /* The FIFO length is a machine key with a range. */
    CHECK(emm_machine_set(m, "emm.fifo=0", &err) == EMM_ERR_RANGE);
    CHECK(emm_machine_set(m, "emm.fifo=8", &err) == EMM_OK);
    CHECK(emm_machine_get(m, "emm.fifo") == 8);
    emm_machine_free(m);
}

int main(void)
{
    naive_by_hand();
    local_per_access();
    prefetch_filter();
    one_cell_store();
    errors();
    return check_done();
}
