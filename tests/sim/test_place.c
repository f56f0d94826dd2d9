/* Where the models put a trace's arrays (emm_trace_place, docs/machine.md
 * "Addresses"): the same places whatever the program's own addresses were
 * (ASLR moves the heap and the mmap area apart by different amounts each
 * run, and the allocations before an array move it within its page), each
 * array on pages of its own, overlapping arrays at their distance, raw
 * memory where it was; and so the reference cache and direct reads give
 * the same counts on two runs of one program. */
#include <stdint.h>

#include "check.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "emm/trace.h"

static uint64_t rng_state = 0x243f6a8885a308d3ull;
static uint64_t rnd(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static void place(const emm_trace_array *a, uint32_t n, uint64_t *base)
{
    emm_trace_info info = {.version = 1, .narrays = n, .arrays = a};
    emm_error err;
    REQUIRE(emm_trace_place(&info, base, &err) == EMM_OK);
}

static void placement(void)
{
    /* Two runs of one program: a vertex array on the heap, a triangle array
     * and a second vertex array in the mmap area, moved by ASLR by
     * different whole pages, and the heap block within its page by what
     * was allocated before it. */
    emm_trace_array run1[3] = {{EMM_ARRAY_VERTICES, 80, 5000, 0x55d0c2a1e2a0ull},
                               {EMM_ARRAY_TRIANGLES, 28, 10000, 0x7f3a10000010ull},
                               {EMM_ARRAY_VERTICES, 12, 100, 0x7f3a10200010ull}};
    emm_trace_array run2[3] = {{EMM_ARRAY_VERTICES, 80, 5000, 0x5612004bd490ull},
                               {EMM_ARRAY_TRIANGLES, 28, 10000, 0x7fe4c8911010ull},
                               {EMM_ARRAY_VERTICES, 12, 100, 0x7fe4c8b11010ull}};
    uint64_t b1[3], b2[3];
    place(run1, 3, b1);
    place(run2, 3, b2);
    for (int i = 0; i < 3; i++)
        CHECKF(b1[i] == b2[i], "array %d: 0x%llx and 0x%llx", i, (unsigned long long)b1[i],
               (unsigned long long)b2[i]);
    /* In the trace's order from the start, each starting a page. */
    CHECK(b1[0] == EMM_TRACE_PLACE_START);
    CHECK(b1[1] == ((b1[0] + 5000 * 80 + 4095) & ~4095ull));
    CHECK(b1[2] == ((b1[1] + 10000 * 28 + 4095) & ~4095ull));

    /* Overlapping arrays (one block tagged twice) keep their distance, the
     * group placed where its first array in the trace's order would be;
     * raw memory keeps its addresses. */
    emm_trace_array ov[4] = {{EMM_ARRAY_TRIANGLES, 16, 100, 0x7000000100ull},
                             {EMM_ARRAY_RAW, 1, 1 << 20, 0},
                             {EMM_ARRAY_VERTICES, 16, 100, 0x70000000c0ull},
                             {EMM_ARRAY_VERTICES, 8, 10, 0x9000000008ull}};
    uint64_t b[4];
    place(ov, 4, b);
    CHECK(b[1] == 0);
    CHECK(b[0] - b[2] == 0x40);
    CHECK(b[2] == EMM_TRACE_PLACE_START);
    CHECK(b[3] == ((b[0] + 1600 + 4095) & ~4095ull));
}

/* One model's counts and total over recs. */
static void simulate(const char *strategy, const emm_trace_info *info,
                     const emm_trace_record *recs, size_t n, emm_result *out)
{
    emm_machine *m;
    emm_model *model;
    emm_strategy s;
    emm_error err;
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    REQUIRE(emm_strategy_parse(strategy, &s, &err) == EMM_OK);
    REQUIRE(emm_model_new(m, &s, info, &model, &err) == EMM_OK);
    emm_model_run(model, recs, n);
    emm_model_result(model, out);
    emm_model_free(model);
    emm_machine_free(m);
}

static void models(void)
{
    /* Arrays larger than the 256 KiB cache, so that where they lie against
     * each other decides which lines conflict; the two runs' arrays apart
     * by distances that differ in the cache's set index (bits 12-15), as
     * ASLR's are, and the heap array at another offset in its page. */
    emm_trace_array a1[2] = {{EMM_ARRAY_VERTICES, 80, 8000, 0x55d0c2a1e2a0ull},
                             {EMM_ARRAY_TRIANGLES, 28, 16000, 0x7f3a10000010ull}};
    emm_trace_array a2[2] = {{EMM_ARRAY_VERTICES, 80, 8000, 0x5612004b9490ull},
                             {EMM_ARRAY_TRIANGLES, 28, 16000, 0x7fe4c8917010ull}};
    emm_trace_info i1 = {.version = 1, .narrays = 2, .arrays = a1};
    emm_trace_info i2 = {.version = 1, .narrays = 2, .arrays = a2};
    enum { N = 200000 };
    static emm_trace_record recs[N];
    /* A triangle, then its vertices, then a neighbour: element accesses of
     * a traversal, 8-byte loads that sometimes cross a line. */
    uint64_t t = 0;
    for (size_t k = 0; k < N; k++) {
        if (k % 4 == 0) {
            t = (t + 1 + rnd() % 64) % 16000;
            recs[k] = (emm_trace_record){.element = t, .array = 1, .offset = 4, .bytes = 12};
        } else {
            recs[k] = (emm_trace_record){.element = (t / 2 + rnd() % 32) % 8000, .array = 0,
                                         .offset = 8 * (uint32_t)(rnd() % 3), .bytes = 8};
        }
    }
    static const char *const strategies[] = {"cache", "direct"};
    for (size_t k = 0; k < sizeof strategies / sizeof *strategies; k++) {
        emm_result r1, r2;
        simulate(strategies[k], &i1, recs, N, &r1);
        simulate(strategies[k], &i2, recs, N, &r2);
        CHECKF(r1.total == r2.total, "%s: %llu and %llu cycles", strategies[k],
               (unsigned long long)r1.total, (unsigned long long)r2.total);
        CHECK(r1.cache.demand_misses == r2.cache.demand_misses);
        CHECK(r1.cache.prefetch_misses == r2.cache.prefetch_misses);
        CHECK(r1.direct.words_read == r2.direct.words_read);
    }
}

int main(void)
{
    placement();
    models();
    return check_done();
}
