/* The cache model against hand-worked cases and against the reference model
 * of ref_cache.h on thousands of random and structured traces, for the three
 * fetch policies (docs/dinero.md); and the cache timing of thesis §3.2. */
#include <string.h>

#include "check.h"
#include "emm/sim.h"
#include "ref_cache.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static uint64_t rnd(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static const emm_trace_array raw = {EMM_ARRAY_RAW, 1, 0, 0};
static const emm_trace_info raw_info = {.version = 1, .narrays = 1, .arrays = &raw};

static emm_machine *machine(uint64_t bytes, uint64_t assoc, uint64_t line, const char *fetch)
{
    emm_machine *m;
    emm_error err;
    char kv[64];
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    snprintf(kv, sizeof kv, "cache.bytes=%llu", (unsigned long long)bytes);
    REQUIRE(emm_machine_set(m, kv, &err) == EMM_OK);
    snprintf(kv, sizeof kv, "cache.assoc=%llu", (unsigned long long)assoc);
    REQUIRE(emm_machine_set(m, kv, &err) == EMM_OK);
    snprintf(kv, sizeof kv, "cache.line=%llu", (unsigned long long)line);
    REQUIRE(emm_machine_set(m, kv, &err) == EMM_OK);
    snprintf(kv, sizeof kv, "cache.fetch=%s", fetch);
    REQUIRE(emm_machine_set(m, kv, &err) == EMM_OK);
    REQUIRE(emm_machine_validate(m, &err) == EMM_OK);
    return m;
}

static emm_model *cache_model(const emm_machine *m)
{
    emm_strategy s;
    emm_model *model;
    emm_error err;
    REQUIRE(emm_strategy_parse("cache", &s, &err) == EMM_OK);
    REQUIRE(emm_model_new(m, &s, &raw_info, &model, &err) == EMM_OK);
    return model;
}

static emm_trace_record rec(uint64_t addr, uint32_t bytes, int write)
{
    emm_trace_record r;
    memset(&r, 0, sizeof r);
    r.element = addr;
    r.bytes = bytes;
    r.write = (uint8_t)write;
    return r;
}

struct counts { uint64_t df, dm, pf, pm; };

static struct counts run(uint64_t bytes, uint64_t assoc, uint64_t line, const char *fetch,
                         const emm_trace_record *recs, size_t n)
{
    emm_machine *m = machine(bytes, assoc, line, fetch);
    emm_model *model = cache_model(m);
    emm_result res;
    struct counts c;
    emm_model_run(model, recs, n);
    emm_model_result(model, &res);
    CHECK(res.has_cache);
    c.df = res.cache.demand_fetches;
    c.dm = res.cache.demand_misses;
    c.pf = res.cache.prefetch_fetches;
    c.pm = res.cache.prefetch_misses;
    emm_model_free(model);
    emm_machine_free(m);
    return c;
}

static void hand_cases(void)
{
    /* 2 sets x 2 ways of 64 B, demand: blocks 0, 2, 4 share set 0; 4 evicts
     * the least recently used (0), so the last 0 misses. */
    {
        emm_trace_record t[] = {rec(0, 4, 0), rec(128, 4, 0), rec(256, 4, 0), rec(0, 4, 0)};
        struct counts c = run(256, 2, 64, "demand", t, 4);
        CHECK(c.df == 4 && c.dm == 4 && c.pf == 0);
    }
    /* Touching 0 again before 4 makes 2 the victim: 0 then hits. */
    {
        emm_trace_record t[] = {rec(0, 4, 0), rec(128, 4, 0), rec(0, 4, 0), rec(256, 4, 0), rec(0, 4, 0)};
        struct counts c = run(256, 2, 64, "demand", t, 5);
        CHECK(c.df == 5 && c.dm == 3);
    }
    /* Miss prefetch: the miss on block 0 brings block 1, which then hits. */
    {
        emm_trace_record t[] = {rec(0, 4, 0), rec(64, 4, 0)};
        struct counts c = run(256, 2, 64, "miss", t, 2);
        CHECK(c.df == 2 && c.dm == 1 && c.pf == 1 && c.pm == 1);
    }
    /* A reference across a line boundary is two demand fetches; the second
     * block was just prefetched by the first. */
    {
        emm_trace_record t[] = {rec(62, 4, 0)};
        struct counts c = run(256, 2, 64, "miss", t, 1);
        CHECK(c.df == 2 && c.dm == 1 && c.pf == 1 && c.pm == 1);
        c = run(256, 2, 64, "always", t, 1);
        CHECK(c.df == 2 && c.dm == 1 && c.pf == 2 && c.pm == 2);
        c = run(256, 2, 64, "demand", t, 1);
        CHECK(c.df == 2 && c.dm == 2 && c.pf == 0);
    }
    /* Writes allocate and never prefetch. */
    {
        emm_trace_record t[] = {rec(0, 4, 1), rec(0, 4, 0), rec(64, 4, 1)};
        struct counts c = run(256, 2, 64, "always", t, 3);
        /* write 0: miss; read 0: hit, prefetch 1 (miss); write 64: hit. */
        CHECK(c.df == 3 && c.dm == 1 && c.pf == 1 && c.pm == 1);
    }
    /* A prefetch that hits refreshes LRU (fully associative, 3 ways):
     * b0 miss [pf b1 miss] -> (1 0); b1 hit [pf b2 miss] -> (2 1 0);
     * b0 hit [pf b1 hit] -> (1 0 2); b3 miss evicts 2 [pf b4 miss evicts 0]
     * -> (4 3 1); b1 hits only because the prefetch refreshed it
     * [pf b2 miss]. */
    {
        emm_trace_record t[] = {rec(0, 4, 0), rec(64, 4, 0), rec(0, 4, 0), rec(192, 4, 0), rec(64, 4, 0)};
        struct counts c = run(192, 3, 64, "always", t, 5);
        CHECKF(c.df == 5 && c.dm == 2 && c.pf == 5 && c.pm == 4, "df %llu dm %llu pf %llu pm %llu",
               (unsigned long long)c.df, (unsigned long long)c.dm, (unsigned long long)c.pf,
               (unsigned long long)c.pm);
    }
}

static void timing(void)
{
    emm_machine *m = machine(256 * 1024, 4, 64, "miss");
    emm_model *model = cache_model(m);
    emm_result r;
    emm_trace_record t[3] = {rec(0, 4, 0), rec(4, 4, 0), rec(64, 4, 0)};
    /* miss + prefetch: 1 compute + 1 local + DMA(128) = 266 + 32 */
    emm_model_run(model, t, 1);
    emm_model_result(model, &r);
    CHECK(r.total == 1 + 1 + 298);
    CHECK(r.cycles[EMM_BUCKET_LOCAL_ACCESS] == 1 && r.cycles[EMM_BUCKET_CACHE_MISS_STALL] == 298);
    emm_model_run(model, t + 1, 2);
    emm_model_result(model, &r);
    CHECK(r.total == 300 + 2 + 2 && r.cycles[EMM_BUCKET_CACHE_HIT] == 2);
    emm_model_free(model);
    emm_machine_free(m);

    m = machine(256 * 1024, 4, 64, "demand");
    model = cache_model(m);
    emm_model_run(model, t, 1);
    emm_model_result(model, &r);
    CHECK(r.total == 1 + 1 + 282);
    emm_model_free(model);
    emm_machine_free(m);

    /* Always-prefetch: the hit on line 1 starts line 2 asynchronously; the
     * next access, 1 cycle of compute later, waits for the rest. */
    m = machine(256 * 1024, 4, 64, "always");
    model = cache_model(m);
    {
        emm_trace_record u[3] = {rec(0, 4, 0), rec(64, 4, 0), rec(128, 4, 0)};
        emm_model_run(model, u, 3);
    }
    emm_model_result(model, &r);
    CHECK(r.cycles[EMM_BUCKET_COMPUTE] == 3);
    CHECK(r.cycles[EMM_BUCKET_LOCAL_ACCESS] == 1);
    CHECK(r.cycles[EMM_BUCKET_CACHE_HIT] == 2);
    CHECK(r.cycles[EMM_BUCKET_CACHE_MISS_STALL] == 298 + 281);
    CHECK(r.total == 585);
    CHECK(r.cache.late_prefetches == 1);
    emm_model_free(model);
    emm_machine_free(m);
}

/* A trace of n references: random, sequential runs, strides, hot sets,
 * unaligned and multi-line sizes. */
static void make_trace(emm_trace_record *t, size_t n, uint64_t span, int kind)
{
    uint64_t a = rnd() % span;
    for (size_t i = 0; i < n; i++) {
        uint32_t bytes = 4;
        int w = (rnd() % 4) == 0;
        switch (kind) {
        case 0: a = rnd() % span; break;                       /* random */
        case 1: a = (a + 4) % span; break;                     /* sequential words */
        case 2: a = (a + 64 * (1 + rnd() % 3)) % span; break;  /* strided */
        case 3: a = (rnd() % 8) * 4096 + (rnd() % 4) * 64; break; /* conflicting sets */
        case 4: a = rnd() % span; bytes = 1 + (uint32_t)(rnd() % 200); break; /* any size */
        default:                                                /* mixed walk */
            if (rnd() % 8 == 0)
                a = rnd() % span;
            else
                a = (a + 1 + rnd() % 24) % span;
            bytes = 1 + (uint32_t)(rnd() % 16);
        }
        t[i] = rec(a, bytes, w);
    }
}

static void against_reference(void)
{
    static const struct { uint64_t bytes, assoc, line; } geo[] = {
        {256, 2, 64}, {512, 1, 64}, {1024, 4, 64}, {192, 3, 64}, {4096, 4, 32},
        {2048, 8, 16}, {256 * 1024, 4, 64}, {1024, 16, 64},
    };
    static const char *const fetch[] = {"demand", "miss", "always"};
    static const char fchar[] = {'d', 'm', 'a'};
    enum { N = 3000 };
    static emm_trace_record t[N];
    int mismatches = 0, cases = 0;

    for (int trial = 0; trial < 1200; trial++) {
        size_t g = (size_t)trial % (sizeof geo / sizeof geo[0]);
        int kind = (int)(rnd() % 6);
        size_t n = 1 + (size_t)(rnd() % N);
        uint64_t span = geo[g].bytes * (1 + rnd() % 8);
        make_trace(t, n, span, kind);
        for (int f = 0; f < 3; f++) {
            ref_cache r;
            struct counts c = run(geo[g].bytes, geo[g].assoc, geo[g].line, fetch[f], t, n);
            ref_init(&r, geo[g].bytes, geo[g].assoc, geo[g].line, fchar[f]);
            for (size_t i = 0; i < n; i++)
                ref_access(&r, t[i].element, t[i].bytes, t[i].write);
            cases++;
            if (c.df != r.demand_fetches || c.dm != r.demand_misses ||
                c.pf != r.prefetch_fetches || c.pm != r.prefetch_misses) {
                if (mismatches++ < 5)
                    fprintf(stderr, "trial %d geo %zu kind %d fetch %s: model %llu/%llu/%llu/%llu ref %llu/%llu/%llu/%llu\n",
                            trial, g, kind, fetch[f], (unsigned long long)c.df,
                            (unsigned long long)c.dm, (unsigned long long)c.pf,
                            (unsigned long long)c.pm, (unsigned long long)r.demand_fetches,
                            (unsigned long long)r.demand_misses,
                            (unsigned long long)r.prefetch_fetches,
                            (unsigned long long)r.prefetch_misses);
            }
            ref_free(&r);
        }
    }
    CHECKF(mismatches == 0, "%d of %d traces differ from the reference", mismatches, cases);
    printf("%d traces compared with the reference model\n", cases);
}

int main(void)
{
    hand_cases();
    timing();
    against_reference();
    return check_done();
}
