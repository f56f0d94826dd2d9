/* Direct reads, and the rule that every cycle lands in one bucket and the
 * buckets add up to the total, for every model, policy and machine. */
#include <string.h>

#include "check.h"
#include "emm/sim.h"

static uint64_t rng_state = 12345;
static uint64_t rnd(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static const emm_trace_array arrays[2] = {
    {EMM_ARRAY_VERTICES, 40, 1000, 0x10000},
    {EMM_ARRAY_TRIANGLES, 24, 2000, 0x80000},
};
static const emm_trace_info info = {.version = 1, .narrays = 2, .arrays = arrays};

static emm_model *model_of(const emm_machine *m, const char *name)
{
    emm_strategy s;
    emm_model *model;
    emm_error err;
    REQUIRE(emm_strategy_parse(name, &s, &err) == EMM_OK);
    REQUIRE(emm_model_new(m, &s, &info, &model, &err) == EMM_OK);
    return model;
}

static emm_trace_record rec(uint32_t array, uint64_t element, uint32_t offset, uint32_t bytes,
                            int write, uint32_t work)
{
    emm_trace_record r;
    memset(&r, 0, sizeof r);
    r.array = array;
    r.element = element;
    r.offset = offset;
    r.bytes = bytes;
    r.write = (uint8_t)write;
    r.work = work;
    return r;
}

static void direct(void)
{
    emm_machine *m;
    emm_error err;
    emm_model *d;
    emm_result r;
    /* address 0x10000 + 2*40 + 0: one aligned word; then 8 bytes at an
     * address 2 bytes into a word: 3 words; then a 4-byte write. */
    emm_trace_record t[3] = {rec(0, 2, 0, 4, 0, 0), rec(0, 2, 2, 8, 0, 5), rec(1, 7, 4, 4, 1, 0)};
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    d = model_of(m, "direct");
    emm_model_run(d, t, 3);
    emm_model_result(d, &r);
    CHECK(r.has_direct && !r.has_cache && !r.has_dma);
    CHECK(r.direct.words_read == 4 && r.direct.words_written == 1);
    CHECK(r.cycles[EMM_BUCKET_REMOTE_ACCESS] == 4 * 32 + 1);
    /* Compute is per access by default (docs/machine.md "Compute"): the
     * second record's work of 5 is not charged... */
    CHECK(r.cycles[EMM_BUCKET_COMPUTE] == 3);
    CHECK(r.total == 4 * 32 + 1 + 3);
    CHECK(r.accesses == 3);
    emm_model_reset(d);
    emm_model_result(d, &r);
    CHECK(r.total == 0 && r.accesses == 0);
    emm_model_free(d);
    /* ...unless compute.per_work says so. */
    REQUIRE(emm_machine_set(m, "compute.per_work=1", &err) == EMM_OK);
    d = model_of(m, "direct");
    emm_model_run(d, t, 3);
    emm_model_result(d, &r);
    CHECK(r.cycles[EMM_BUCKET_COMPUTE] == 3 + 5);
    CHECK(r.total == 4 * 32 + 1 + 8);
    emm_model_free(d);

    /* Unsupported strategies say so. */
    {
        emm_strategy s;
        emm_model *x = NULL;
        /* EMM strategies need geometry too (tests/fetch covers them). */
        REQUIRE(emm_strategy_parse("grid+naive@64", &s, &err) == EMM_OK);
        CHECK(emm_model_new(m, &s, &info, &x, &err) == EMM_ERR_INVALID);
        CHECK(strstr(err.message, "address-only") != NULL);
        /* cache@LAYOUT needs geometry, which this trace lacks. */
        REQUIRE(emm_strategy_parse("cache@tiles", &s, &err) == EMM_OK);
        CHECK(emm_model_new(m, &s, &info, &x, &err) == EMM_ERR_INVALID);
        CHECK(strstr(err.message, "address-only") != NULL);
    }
    emm_machine_free(m);
}

static void sums(void)
{
    static const char *const fetch[] = {"demand", "miss", "always"};
    enum { N = 5000 };
    static emm_trace_record t[N];
    for (int trial = 0; trial < 60; trial++) {
        emm_machine *m;
        emm_error err;
        char kv[64];
        emm_model *models[2];
        REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
        snprintf(kv, sizeof kv, "cache.fetch=%s", fetch[trial % 3]);
        REQUIRE(emm_machine_set(m, kv, &err) == EMM_OK);
        snprintf(kv, sizeof kv, "cache.bytes=%u", 1024u << (trial % 6));
        REQUIRE(emm_machine_set(m, kv, &err) == EMM_OK);
        snprintf(kv, sizeof kv, "compute.per_work=%u", (unsigned)(rnd() % 5));
        REQUIRE(emm_machine_set(m, kv, &err) == EMM_OK);
        snprintf(kv, sizeof kv, "cache.hit=%u", (unsigned)(rnd() % 3));
        REQUIRE(emm_machine_set(m, kv, &err) == EMM_OK);
        models[0] = model_of(m, "direct");
        models[1] = model_of(m, "cache");
        for (size_t i = 0; i < N; i++) {
            uint32_t a = (uint32_t)(rnd() % 2);
            t[i] = rec(a, rnd() % arrays[a].count, (uint32_t)(rnd() % arrays[a].record_size),
                       1 + (uint32_t)(rnd() % 12), (int)(rnd() % 5 == 0), (uint32_t)(rnd() % 50));
        }
        for (int k = 0; k < 2; k++) {
            emm_result r;
            uint64_t sum = 0;
            /* in uneven batches */
            for (size_t i = 0; i < N;) {
                size_t n = 1 + (size_t)(rnd() % 700);
                if (n > N - i)
                    n = N - i;
                emm_model_run(models[k], t + i, n);
                i += n;
            }
            emm_model_result(models[k], &r);
            for (int b = 0; b < EMM_BUCKET_COUNT; b++)
                sum += r.cycles[b];
            CHECK(sum == r.total);
            CHECK(r.total > 0 && r.accesses == N);
            emm_model_free(models[k]);
        }
        emm_machine_free(m);
    }
}

int main(void)
{
    direct();
    sums();
    for (int b = 0; b < EMM_BUCKET_COUNT; b++)
        CHECK(strcmp(emm_bucket_name((emm_bucket)b), "unknown") != 0);
    CHECK(strcmp(emm_bucket_name(EMM_BUCKET_CACHE_MISS_STALL), "cache_miss_stall") == 0);
    return check_done();
}
