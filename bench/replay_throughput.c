/* Replay throughput of the machine models (docs/machine.md):
 * writes a trace of N accesses (a random walk mixing sequential and random
 * element accesses over a vertex and a triangle array) with the trace
 * writer into a temporary directory, then times
 *   (a) each model on records already in memory, batch by batch, and
 *   (b) end-to-end replay streaming from the file (emm_replay),
 *   (c) each model run costed (emm_model_run_costed, emm annotate's path:
 *       each record's cycles by bucket), against (a),
 * printing accesses per second, and the peak RSS after a short and after
 * the full run, to show that memory does not grow with the trace. Rates are
 * per second of CPU time of the one thread doing the work.
 *
 * usage: replay_throughput [ACCESSES]   (default 50000000) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "emm/replay.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "emm/trace.h"

#define BATCH 8192

/* CPU time of this thread: on a shared, busy machine the wall clock would
 * measure the other processes too. */
static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static long peak_rss_kib(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss;
}

static uint64_t rng = 0x243f6a8885a308d3ull;
static uint64_t rnd(void)
{
    uint64_t z = (rng += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static const emm_trace_array arrays[2] = {
    {EMM_ARRAY_VERTICES, 80, 10000, 0x100000},
    {EMM_ARRAY_TRIANGLES, 40, 20000, 0x400000},
};

/* The next batch of the walk: a visit reads one to four consecutive 8-byte
 * fields of an element (as a program reads a vertex's coordinates), then
 * moves to a nearby element of the other array, or, one time in sixteen,
 * jumps anywhere; one access in eight is a write. */
static void fill(emm_trace_record *b, size_t n, uint64_t *cur)
{
    static uint32_t left, field, a;
    for (size_t i = 0; i < n; i++) {
        uint64_t r = rnd();
        if (left == 0) {
            a ^= 1;
            if ((r >> 8) % 16 == 0)
                cur[a] = rnd() % arrays[a].count;
            else
                cur[a] = (cur[a] + (r >> 16) % 5) % arrays[a].count;
            left = 1 + (uint32_t)((r >> 48) % 4);
            field = (uint32_t)((r >> 24) % (arrays[a].record_size / 8 - left + 1));
        }
        b[i].array = a;
        b[i].element = cur[a];
        b[i].offset = 8 * field++;
        b[i].bytes = 8;
        b[i].write = (r >> 40) % 8 == 0;
        b[i].work = (uint32_t)((r >> 44) % 16);
        left--;
    }
}

static int write_trace(const char *path, uint64_t n, emm_error *err)
{
    emm_trace_writer *w;
    emm_trace_geometry geo = {0, 0, NULL, NULL};
    static emm_trace_record b[BATCH];
    uint64_t cur[2] = {0, 0};
    if (emm_trace_writer_open(path, arrays, 2, &geo, 0, &w, err) != EMM_OK)
        return 1;
    rng = 0x243f6a8885a308d3ull;
    for (uint64_t done = 0; done < n;) {
        size_t k = n - done < BATCH ? (size_t)(n - done) : BATCH;
        fill(b, k, cur);
        if (emm_trace_write(w, b, k, err) != EMM_OK) {
            emm_trace_writer_abort(w);
            return 1;
        }
        done += k;
    }
    return emm_trace_writer_close(w, err) != EMM_OK;
}

/* (a): the model alone, on batches generated ahead of time (one batch of
 * 64 Ki records reused, so the timing is the model's, not the generator's). */
static double time_model(const emm_machine *m, const char *name, uint64_t n, int costed,
                         emm_result *out)
{
    static emm_trace_record b[1 << 16];
    static emm_record_cost cost[BATCH];
    const emm_trace_info info = {.version = 1, .narrays = 2, .arrays = arrays};
    uint64_t cur[2] = {0, 0};
    emm_strategy s;
    emm_model *model;
    emm_error err;
    double t0, t1;
    rng = 0x243f6a8885a308d3ull;
    fill(b, sizeof b / sizeof b[0], cur);
    emm_strategy_parse(name, &s, &err);
    if (emm_model_new(m, &s, &info, &model, &err) != EMM_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    t0 = now_s();
    for (uint64_t done = 0; done < n;) {
        size_t k = n - done < BATCH ? (size_t)(n - done) : BATCH;
        size_t off = (size_t)(done % (sizeof b / sizeof b[0] - BATCH));
        if (costed)
            emm_model_run_costed(model, b + off, k, cost);
        else
            emm_model_run(model, b + off, k);
        done += k;
    }
    t1 = now_s();
    emm_model_result(model, out);
    emm_model_free(model);
    return (double)n / (t1 - t0);
}

static void run(const emm_machine *m, const char *dir, uint64_t n)
{
    static const char *const models[] = {"direct", "cache"};
    static const char *const fetch[] = {"demand", "miss", "always"};
    char path[4096];
    emm_error err;
    double t0, t1;
    uint64_t acc = 0;
    emm_result res;

    snprintf(path, sizeof path, "%s/bench.emmt", dir);
    t0 = now_s();
    if (write_trace(path, n, &err)) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    t1 = now_s();
    printf("trace: %llu accesses written in %.2f s\n", (unsigned long long)n, t1 - t0);

    for (size_t i = 0; i < 2; i++) {
        double rate = time_model(m, models[i], n, 0, &res);
        printf("  in memory   %-14s %8.1f M accesses/s  (total %llu cycles)\n", models[i],
               rate / 1e6, (unsigned long long)res.total);
        emm_result cres;
        double crate = time_model(m, models[i], n, 1, &cres);
        printf("  costed      %-14s %8.1f M accesses/s  (%.2fx the plain run's time; same total: %s)\n",
               models[i], crate / 1e6, rate / crate, cres.total == res.total ? "yes" : "NO");
    }
    for (size_t f = 0; f < 3; f++) {
        emm_machine *c;
        char kv[64];
        emm_machine_clone(m, &c, &err);
        snprintf(kv, sizeof kv, "cache.fetch=%s", fetch[f]);
        emm_machine_set(c, kv, &err);
        double rate = time_model(c, "cache", n, 0, &res);
        char name[32];
        snprintf(name, sizeof name, "cache(%s)", fetch[f]);
        printf("  in memory   %-14s %8.1f M accesses/s  (demand miss rate %.1f%%)\n", name,
               rate / 1e6, 100.0 * (double)res.cache.demand_misses / (double)res.cache.demand_fetches);
        emm_machine_free(c);
    }
    for (size_t i = 0; i < 2; i++) {
        emm_strategy s;
        emm_strategy_parse(models[i], &s, &err);
        t0 = now_s();
        if (emm_replay(path, m, &s, 1, &res, &acc, NULL, NULL, &err) != EMM_OK) {
            fprintf(stderr, "%s\n", err.message);
            exit(1);
        }
        t1 = now_s();
        printf("  from file   %-14s %8.1f M accesses/s  (%llu accesses)\n", models[i],
               (double)acc / (t1 - t0) / 1e6, (unsigned long long)acc);
    }
    unlink(path);
    printf("  peak RSS so far: %ld KiB\n", peak_rss_kib());
}

int main(int argc, char **argv)
{
    uint64_t n = argc > 1 ? strtoull(argv[1], NULL, 10) : 50000000ull;
    char dir[] = "/tmp/emm-bench-XXXXXX";
    emm_machine *m;
    emm_error err;
    if (n < 1000) {
        fprintf(stderr, "usage: replay_throughput [ACCESSES >= 1000]\n");
        return 2;
    }
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    if (emm_machine_new(&m, &err) != EMM_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    printf("-- %llu accesses (a tenth of the full run)\n", (unsigned long long)(n / 10));
    run(m, dir, n / 10);
    printf("-- %llu accesses\n", (unsigned long long)n);
    run(m, dir, n);
    emm_machine_free(m);
    rmdir(dir);
    return 0;
}
