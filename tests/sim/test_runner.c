/* The model runner's pipeline (simulator/runner.c, emm_runner_pipeline):
 * the same strategies over the same records, fed in batches of uneven
 * sizes, once through a plain runner and once through a pipelined one,
 * with a model retired and one added part way and one model costed: every
 * model's cycles, buckets and counts come out the same, the costs reported
 * add up alike and in order, and the pipeline's workers called the start
 * hook with every signal blocked. */
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "emm/sim.h"
#include "runner.h"

static uint64_t rng_state = 7;
static uint64_t rnd(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* A W x W grid of squares, two triangles each. */
#define W 60
#define NV ((W + 1) * (W + 1))
#define NT (2 * W * W)
static double xyz[3 * NV];
static int32_t tri[3 * NT];

static const emm_trace_array arrays[2] = {
    {EMM_ARRAY_VERTICES, 24, NV, 0x100000},
    {EMM_ARRAY_TRIANGLES, 12, NT, 0x800000},
};

static void grid(void)
{
    for (int y = 0; y <= W; y++)
        for (int x = 0; x <= W; x++) {
            double *p = &xyz[3 * (y * (W + 1) + x)];
            p[0] = x, p[1] = y, p[2] = 0;
        }
    for (int y = 0, t = 0; y < W; y++)
        for (int x = 0; x < W; x++, t += 2) {
            int32_t a = y * (W + 1) + x, b = a + 1, c = a + W + 1, d = c + 1;
            int32_t *q = &tri[3 * t];
            q[0] = a, q[1] = b, q[2] = d, q[3] = a, q[4] = d, q[5] = c;
        }
}

/* A walk over the triangles that mostly steps to a neighbour and now and
 * then jumps, each triangle followed by its vertices' x, y and z. */
static size_t walk(emm_trace_record *r, size_t cap)
{
    size_t n = 0;
    int64_t t = 0;
    while (n + 10 <= cap) {
        t = rnd() % 50 == 0 ? (int64_t)(rnd() % NT) : (t + 1 + (int64_t)(rnd() % 3)) % NT;
        memset(&r[n], 0, sizeof r[n]);
        r[n].array = 1, r[n].element = (uint64_t)t, r[n].bytes = 12, r[n].work = 3;
        n++;
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++, n++) {
                memset(&r[n], 0, sizeof r[n]);
                r[n].array = 0, r[n].element = (uint64_t)tri[3 * t + k];
                r[n].offset = (uint32_t)(8 * c), r[n].bytes = 8, r[n].work = 1;
                r[n].write = c == 2 && rnd() % 7 == 0;
            }
    }
    return n;
}

static _Thread_local int marked;
static int hooks, wrong_ctx;
static void hook(void *ctx)
{
    if (ctx != &hooks)
        __atomic_add_fetch(&wrong_ctx, 1, __ATOMIC_RELAXED);
    marked = 1;
    __atomic_add_fetch(&hooks, 1, __ATOMIC_RELAXED);
}

/* What a costed model reported, batch by batch. */
struct costs {
    uint64_t records, cycles, order; /* order: a hash of the records in the order reported */
    int off_worker, unblocked;
};

static void on_costs(void *ctx, const emm_trace_record *recs, const emm_record_cost *cost,
                     size_t n)
{
    struct costs *c = ctx;
    for (size_t k = 0; k < n; k++) {
        c->records++;
        for (int b = 0; b < EMM_BUCKET_COUNT; b++)
            c->cycles += cost[k].cycles[b];
        c->order = c->order * 1099511628211ull + recs[k].element * 3 + recs[k].array;
    }
    sigset_t now;
    pthread_sigmask(SIG_SETMASK, NULL, &now);
    c->unblocked += !sigismember(&now, SIGINT);
    c->off_worker += !marked;
}

static const char *const names[] = {"direct",           "cache",           "grid+naive@8",
                                    "tiles+convolution@16", "quadtree+extrapolated@32",
                                    "tiles+naive@4:indexed"};
#define NS (sizeof names / sizeof *names)

static void same(emm_model *a, emm_model *b, const char *what)
{
    emm_result x, y;
    emm_model_result(a, &x);
    emm_model_result(b, &y);
    CHECK(x.total == y.total);
    CHECK(x.accesses == y.accesses);
    CHECK(memcmp(x.cycles, y.cycles, sizeof x.cycles) == 0);
    CHECK(x.has_dma == y.has_dma && (!x.has_dma || x.dma.transfers == y.dma.transfers));
    if (x.total != y.total)
        fprintf(stderr, "%s: %llu against %llu\n", what, (unsigned long long)x.total,
                (unsigned long long)y.total);
    emm_result_release(&x);
    emm_result_release(&y);
}

int main(void)
{
    grid();
    emm_trace_info info = {.version = 1, .narrays = 2, .arrays = arrays};
    info.geometry = (emm_trace_geometry){NV, NT, xyz, tri};
    emm_machine *m;
    emm_error err;
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    emm_strategy s[NS + 1];
    for (size_t i = 0; i < NS; i++)
        REQUIRE(emm_strategy_parse(names[i], &s[i], &err) == EMM_OK);
    REQUIRE(emm_strategy_parse("grid+extrapolated@16", &s[NS], &err) == EMM_OK);

    emm_threads t = {3, hook, &hooks};
    emm_runner *plain, *piped;
    REQUIRE(emm_runner_new(&t, &plain, &err) == EMM_OK);
    REQUIRE(emm_runner_new(&t, &piped, &err) == EMM_OK);
    REQUIRE(emm_runner_add(plain, m, s, NS, &info, NULL, &err) == EMM_OK);
    REQUIRE(emm_runner_add(piped, m, s, NS, &info, NULL, &err) == EMM_OK);
    struct costs cp = {0}, cq = {0};
    REQUIRE(emm_runner_costs(plain, 2, on_costs, &cp, &err) == EMM_OK);
    REQUIRE(emm_runner_costs(piped, 2, on_costs, &cq, &err) == EMM_OK);
    int hooks_before = __atomic_load_n(&hooks, __ATOMIC_RELAXED);
    REQUIRE(emm_runner_pipeline(piped, &err) == EMM_OK);

    size_t cap = 400000;
    emm_trace_record *recs = malloc(cap * sizeof *recs);
    REQUIRE(recs);
    size_t n = walk(recs, cap);
    for (size_t done = 0, step = 0; done < n; step++) {
        size_t len = 1 + rnd() % (step % 3 ? 9000 : 90);
        if (len > n - done)
            len = n - done;
        emm_runner_run(plain, recs + done, len);
        emm_runner_run(piped, recs + done, len);
        /* The caller's buffer is its own again as soon as the call
         * returns: the pipeline ran a copy. */
        memset(&recs[done], 0xff, len * sizeof *recs);
        done += len;
        if (done > n / 3 && emm_runner_count(piped) == NS) {
            emm_runner_retire(plain, 3);
            emm_runner_retire(piped, 3);
            REQUIRE(emm_runner_add(plain, m, &s[NS], 1, &info, NULL, &err) == EMM_OK);
            REQUIRE(emm_runner_add(piped, m, &s[NS], 1, &info, NULL, &err) == EMM_OK);
        }
    }
    emm_runner_sync(piped);
    /* The pipeline's own workers called the hook. */
    CHECK(__atomic_load_n(&hooks, __ATOMIC_RELAXED) > hooks_before);
    CHECK(__atomic_load_n(&wrong_ctx, __ATOMIC_RELAXED) == 0);
    CHECK(emm_runner_count(plain) == NS + 1 && emm_runner_count(piped) == NS + 1);
    for (size_t i = 0; i < NS + 1; i++) {
        emm_model *a = emm_runner_model(plain, i), *b = emm_runner_model(piped, i);
        REQUIRE(a && b);
        same(a, b, i < NS ? names[i] : "grid+extrapolated@16");
    }
    CHECK(cp.records == n && cq.records == n);
    CHECK(cp.cycles == cq.cycles && cp.order == cq.order);
    CHECK(cq.unblocked == 0 && cq.off_worker == 0);
    emm_runner_free(plain);
    emm_runner_free(piped);
    /* A pipeline on one thread is no pipeline: the batch runs before the
     * call returns. */
    emm_threads one = {1, NULL, NULL};
    emm_runner *r;
    REQUIRE(emm_runner_new(&one, &r, &err) == EMM_OK);
    REQUIRE(emm_runner_add(r, m, s, 1, &info, NULL, &err) == EMM_OK);
    REQUIRE(emm_runner_pipeline(r, &err) == EMM_OK);
    n = walk(recs, 1000);
    emm_runner_run(r, recs, n);
    emm_result res;
    emm_model_result(emm_runner_model(r, 0), &res);
    CHECK(res.accesses == n);
    emm_result_release(&res);
    emm_runner_free(r);
    free(recs);
    emm_machine_free(m);
    return check_done();
}
