/* The session API driven as the shim drives it: a generated mesh copied
 * into arrays laid out as a program would hold them, a synthetic region
 * growth turned into raw addresses, fed in batches. Checks the decision
 * from a table written here, that the totals cover window and rest (equal
 * to emm_replay of the same records), that EMM_TRACE replays to the same
 * numbers and holds the same records, the CSV, a window that never fills,
 * novelty, iteration windows, bad geometry, bad configuration, reports
 * that are whole or absent, and the column-major and soup shapes. */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "emm/mesh.h"
#include "emm/profile.h"
#include "emm/session.h"
#include "emm/table.h"
#include "emm/replay.h"
#include "emm/sim.h"
#include "emm/synth.h"
#include "emm/trace.h"

#define VSTRIDE 80
#define TSTRIDE 28
#define WINDOW 1000

static unsigned char *vmem, *tmem;
static size_t nv, nt;
static emm_trace_record *recs;
static size_t nrecs;
static double feat[EMM_FEATURES];
static emm_result expect_direct, expect_cache;
static uint64_t vbase, tbase;

static uint64_t addr_of(const emm_trace_record *r)
{
    return (r->array == 0 ? vbase : tbase) + r->element * (r->array == 0 ? VSTRIDE : TSTRIDE) +
           r->offset;
}

/* The mesh, the program's arrays, the access records, the expected results
 * (a trace of the same records at the arrays' real addresses, replayed) and
 * the window's features. */
static void setup(void)
{
    emm_error err;
    emm_gen_options go = {2000, 7, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
    emm_mesh *m;
    REQUIRE(emm_mesh_generate(&go, &m, &err) == EMM_OK);
    emm_synth_options so = {.pattern = EMM_PATTERN_REGION, .seed = 3, .work = 3};
    REQUIRE(emm_synth_trace(m, &so, "synth.emmt", NULL, &err) == EMM_OK);
    nv = emm_mesh_vertex_count(m);
    nt = emm_mesh_triangle_count(m);
    vmem = calloc(nv, VSTRIDE);
    tmem = calloc(nt, TSTRIDE);
    REQUIRE(vmem && tmem);
    const double *xyz = emm_mesh_positions(m);
    const int32_t *tri = emm_mesh_indices(m);
    for (size_t v = 0; v < nv; v++)
        memcpy(vmem + v * VSTRIDE + 8, xyz + 3 * v, 24);
    for (size_t t = 0; t < nt; t++)
        memcpy(tmem + t * TSTRIDE + 4, tri + 3 * t, 12);
    vbase = (uint64_t)(uintptr_t)vmem;
    tbase = (uint64_t)(uintptr_t)tmem;

    emm_trace_reader *r;
    REQUIRE(emm_trace_reader_open("synth.emmt", &r, &err) == EMM_OK);
    const emm_trace_info *info = emm_trace_reader_info(r);
    REQUIRE(info->narrays == 2 && info->arrays[0].kind == EMM_ARRAY_VERTICES);
    REQUIRE(info->arrays[0].record_size == VSTRIDE && info->arrays[1].record_size == TSTRIDE);
    recs = malloc(info->accesses * sizeof *recs);
    REQUIRE(recs);
    size_t got;
    while (emm_trace_read(r, recs + nrecs, info->accesses - nrecs, &got, &err) == EMM_OK && got)
        nrecs += got;
    REQUIRE(nrecs == info->accesses && nrecs > 4 * WINDOW);
    emm_trace_array arrays[2] = {info->arrays[0], info->arrays[1]};
    arrays[0].base = vbase;
    arrays[1].base = tbase;
    emm_trace_writer *w;
    REQUIRE(emm_trace_writer_open("expect.emmt", arrays, 2, &info->geometry, 0, &w, &err) ==
            EMM_OK);
    REQUIRE(emm_trace_write(w, recs, nrecs, &err) == EMM_OK);
    REQUIRE(emm_trace_writer_close(w, &err) == EMM_OK);
    emm_trace_reader_close(r);
    emm_mesh_free(m);

    emm_machine *mach;
    REQUIRE(emm_machine_new(&mach, &err) == EMM_OK);
    emm_strategy s[2];
    emm_strategy_parse("direct", &s[0], NULL);
    emm_strategy_parse("cache", &s[1], NULL);
    emm_result res[2];
    REQUIRE(emm_replay("expect.emmt", mach, s, 2, res, NULL, NULL, NULL, &err) == EMM_OK);
    expect_direct = res[0];
    expect_cache = res[1];
    emm_machine_free(mach);

    REQUIRE(emm_trace_reader_open("expect.emmt", &r, &err) == EMM_OK);
    double *xy, *D;
    size_t n;
    REQUIRE(emm_profile_trace_positions(r, WINDOW, EMM_PROFILE_PLANE, "expect", &xy, &n, &err) ==
            EMM_OK);
    REQUIRE(n == WINDOW);
    D = malloc(n * sizeof *D);
    REQUIRE(D);
    REQUIRE(emm_profile_compute(xy, n, EMM_PROFILE_PLANE, D, NULL, NULL, &err) == EMM_OK);
    REQUIRE(emm_profile_features(D, n, "expect", feat, &err) == EMM_OK);
    free(xy);
    free(D);
    emm_trace_reader_close(r);
}

/* A table of two samples: this window's own features (strategy `near`,
 * synthetic recipe `synth`) and a far one; or, with `only_far`, just far ones.
 * Without a recipe the sample's class is `grown`, which names no canonical
 * traversal, so its strategy stands as in the thesis (a sample of a known
 * class is checked by that class's traversal). */
static void write_table_synth(const char *path, const char *near, const char *synth,
                              int only_far)
{
    FILE *f = fopen(path, "w");
    REQUIRE(f);
    fprintf(f, "emm-table %d features=%d\n", EMM_TABLE_VERSION, EMM_FEATURES);
    if (!only_far) {
        fprintf(f, "mine %s %s - %s", strcmp(synth, "-") == 0 ? "grown" : "region", synth, near);
        for (int k = 0; k < EMM_FEATURES; k++)
            fprintf(f, " %.17g", feat[k]);
        fputc('\n', f);
    }
    fprintf(f, "far random - - cache");
    for (int k = 0; k < EMM_FEATURES; k++)
        fprintf(f, " %.17g", feat[k] + 5.0);
    fputc('\n', f);
    fclose(f);
}

static void write_table(const char *path, const char *near, int only_far)
{
    write_table_synth(path, near, "-", only_far);
}

/* The settings the sessions of these tests start from (reset by each
 * base_config); tests change fields of tcfg, or set them through the
 * configuration table where the parsing is what they test. */
static emm_config tcfg;

static emm_session_config base_config(void)
{
    emm_session_config c = {0};
    emm_config_free(&tcfg); /* the rules of the test before, if any; then the defaults */
    tcfg.window_accesses = WINDOW;
    tcfg.compare = EMM_COMPARE_BASELINES;
    /* These tests check the window's prediction; test_contest the run's
     * contest that confirms it. */
    tcfg.finalists = 0;
    strcpy(tcfg.table, "table.txt");
    tcfg.log = 1;
    c.config = &tcfg;
    c.capture = EMM_CAPTURE_API;
    c.program = "test_session";
    return c;
}

/* An emm_tag_* call's array, as the shim hands it over. */
static int tag_call(emm_session *s, emm_array_kind kind, const void *base, size_t count,
                    size_t stride, size_t offset, emm_scalar type)
{
    emm_array_desc d = {kind, EMM_TAG_RECORDS, -1, base, count, stride, offset, type, 0, NULL,
                        {EMM_TAG_NO_LINK, EMM_TAG_NO_LINK, EMM_TAG_NO_LINK, EMM_TAG_NO_LINK}};
    return emm_session_tag(s, &d);
}

/* A block of `count` entries that rule `rule` (from 0) of the session's
 * EMM_TAG selected, described as the shim describes it. */
static int tag_rule(emm_session *s, const void *base, uint64_t count, size_t rule)
{
    emm_array_desc d;
    char origin[600];
    REQUIRE(rule < tcfg.tags.n);
    const emm_tag_rule *r = &tcfg.tags.rule[rule];
    emm_tag_rule_describe(r, rule, base, count * r->stride, &d, origin, sizeof origin);
    return emm_session_tag(s, &d);
}

static void set_strategy(const char *text)
{
    emm_error err;
    REQUIRE(emm_config_set(&tcfg, EMM_CONFIG_STRATEGY, text, NULL, 0, &err) == EMM_OK);
}

static void tag_all(emm_session *s)
{
    CHECK(tag_call(s, EMM_ARRAY_VERTICES, vmem, nv, VSTRIDE, 8, EMM_F64) >= 0);
    CHECK(tag_call(s, EMM_ARRAY_TRIANGLES, tmem, nt, TSTRIDE, 4, EMM_I32) >= 0);
}

/* Feeds every record as raw accesses in batches of `batch`, deciding when
 * asked; between two records, an access outside the arrays carries some of
 * the work (the session must hand it to the next record). Returns how many
 * times DECIDE came back. */
static int feed(emm_session *s, size_t batch, int iterations_every)
{
    emm_raw_access *raw = malloc(2 * batch * sizeof *raw);
    static uint64_t stray;
    int decides = 0;
    REQUIRE(raw);
    for (size_t i = 0; i < nrecs; i += batch) {
        size_t n = 0;
        for (size_t k = i; k < nrecs && k < i + batch; k++) {
            uint32_t w = recs[k].work;
            if (w > 0 && k % 5 == 0) {
                raw[n++] = (emm_raw_access){(uint64_t)(uintptr_t)&stray, 8, 1, 0};
                w -= 1;
            }
            raw[n++] = (emm_raw_access){addr_of(&recs[k]),
                                        recs[k].bytes | (recs[k].write ? EMM_RAW_WRITE : 0), w, 0};
        }
        emm_session_state st = emm_session_access(s, raw, n);
        if (iterations_every && (i / batch) % (size_t)iterations_every == 0)
            st = emm_session_iteration(s);
        if (st == EMM_SESSION_DECIDE) {
            emm_error err;
            decides++;
            CHECKF(emm_session_decide(s, &err) == EMM_OK, "%s", err.message);
        }
    }
    free(raw);
    return decides;
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    char *buf = calloc(1, 1 << 20);
    REQUIRE(buf);
    size_t n = fread(buf, 1, (1 << 20) - 1, f);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

static int has(const char *text, const char *needle)
{
    return text && strstr(text, needle) != NULL;
}

static int has_u64(const char *text, const char *key, uint64_t v)
{
    char needle[96];
    snprintf(needle, sizeof needle, "\"%s\": %llu", key, (unsigned long long)v);
    return has(text, needle);
}

static void same_result(const emm_result *a, const emm_result *b)
{
    CHECKF(a->total == b->total, "total %llu vs %llu", (unsigned long long)a->total,
           (unsigned long long)b->total);
    CHECK(a->accesses == b->accesses);
    for (int k = 0; k < EMM_BUCKET_COUNT; k++)
        CHECK(a->cycles[k] == b->cycles[k]);
    CHECK(a->cache.demand_misses == b->cache.demand_misses);
}

static void test_decide_from_table(void)
{
    emm_error err;
    emm_session *s;
    write_table("table.txt", "direct", 0);
    emm_session_config c = base_config();
    strcpy(tcfg.report, "run.json");
    strcpy(tcfg.profile_dump, "run.csv");
    strcpy(tcfg.trace, "run.emmt");
    remove("run.json");
    remove("run.csv");
    remove("run.emmt");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    uint64_t lo[4], hi[4];
    CHECK(emm_session_ranges(s, lo, hi, 4) == 2);
    CHECK(lo[0] == vbase && hi[0] == vbase + nv * VSTRIDE);
    CHECK(feed(s, 777, 0) == 1);
    FILE *sum = tmpfile();
    REQUIRE(sum);
    CHECKF(emm_session_finish(s, sum, &err) == EMM_OK, "%s", err.message);
    rewind(sum);
    char text[4096] = {0};
    CHECK(fread(text, 1, sizeof text - 1, sum) > 0);
    fclose(sum);
    printf("%s", text);
    CHECK(has(text, "emm: test_session: pattern grown (nearest mine, distance 0.00)"));
    CHECK(has(text, "emm: answer: direct (the nearest sample's strategy)"));
    CHECK(has(text, "emm:   direct reads of remote memory, word by word"));
    CHECK(has(text, "emm:   reference: a 256 KiB 4-way cache (not on this machine) would take"));
    CHECK(has(text, "emm:   simulated: the whole run from the frozen mesh on, 8,000 accesses"));
    CHECK(has(text, "emm:   next: emm replay run.emmt --all --json all.json"));
    emm_session_free(s);

    /* The report: the session's keys and the totals of the whole run. */
    char *json = slurp("run.json");
    CHECK(json != NULL);
    CHECK(has(json, "\"pattern\": \"grown\""));
    CHECK(has(json, "\"strategy\": \"direct\""));
    CHECK(has(json, "\"nearest\": \"mine\""));
    CHECK(has(json, "\"novel\": false"));
    CHECK(has(json, "\"source\": \"table\""));
    CHECK(has(json, "\"capture\": \"api\""));
    /* Compute per access; the records' work (3 a record, some of it on
     * strays the session hands on) is summed, not charged. */
    CHECK(has(json, "\"counted\": \"per access\""));
    CHECK(has(json, "\"work_unit\": null"));
    CHECK(has_u64(json, "work", 3 * (uint64_t)nrecs));
    CHECK(has_u64(json, "compute", nrecs));
    CHECK(has_u64(json, "element_accesses", WINDOW));
    CHECK(has_u64(json, "accesses", nrecs));
    CHECK(has_u64(json, "total", expect_direct.total));
    CHECK(has_u64(json, "total", expect_cache.total));
    free(json);

    /* The CSV: i,D for the window's element accesses. */
    char *csv = slurp("run.csv");
    CHECK(has(csv, "i,D\n0,0\n1,"));
    size_t lines = 0;
    for (const char *p = csv; p && *p; p++)
        lines += *p == '\n';
    CHECK(lines == WINDOW + 1);
    free(csv);

    /* EMM_TRACE: the same records, and replay gives the same numbers. */
    emm_trace_reader *r;
    REQUIRE(emm_trace_reader_open("run.emmt", &r, &err) == EMM_OK);
    const emm_trace_info *info = emm_trace_reader_info(r);
    CHECK(info->accesses == nrecs);
    CHECK(info->narrays == 2 && info->arrays[0].base == vbase && info->arrays[1].base == tbase);
    CHECK(info->geometry.nv == nv && info->geometry.nt == nt);
    emm_trace_record buf[512];
    size_t got, at = 0, same = 0;
    while (emm_trace_read(r, buf, 512, &got, &err) == EMM_OK && got) {
        for (size_t k = 0; k < got && at + k < nrecs; k++) {
            const emm_trace_record *a = &buf[k], *b = &recs[at + k];
            same += a->array == b->array && a->element == b->element && a->offset == b->offset &&
                    a->bytes == b->bytes && a->work == b->work && a->write == b->write;
        }
        at += got;
    }
    CHECKF(same == nrecs, "%zu of %zu records equal", same, nrecs);
    emm_trace_reader_close(r);
    emm_machine *mach;
    REQUIRE(emm_machine_new(&mach, &err) == EMM_OK);
    emm_result res[2];
    emm_strategy st[2] = {expect_direct.strategy, expect_cache.strategy};
    REQUIRE(emm_replay("run.emmt", mach, st, 2, res, NULL, NULL, NULL, &err) == EMM_OK);
    same_result(&res[0], &expect_direct);
    same_result(&res[1], &expect_cache);
    emm_machine_free(mach);
}

/* A sample with a synthetic recipe: the session simulates that pattern over
 * this mesh on this machine (docs/profile.md "The decision"),
 * so the table's `direct` gives way to a strategy that is faster on both. */
static void test_decide_checked(void)
{
    emm_error err;
    emm_session *s;
    write_table_synth("table.txt", "direct", "region", 0);
    emm_session_config c = base_config();
    strcpy(tcfg.report, "checked.json");
    remove("checked.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    /* A leading index-order sweep (a program initialising per-vertex data):
     * left out of the profile, which still matches `mine` exactly. */
    for (size_t v = 0; v < nv; v++) {
        emm_raw_access a = {vbase + v * VSTRIDE + 8, 8, 0, 0};
        CHECK(emm_session_access(s, &a, 1) == EMM_SESSION_PROFILING);
    }
    CHECK(feed(s, 777, 0) == 1);
    FILE *sum = tmpfile();
    REQUIRE(sum);
    CHECKF(emm_session_finish(s, sum, &err) == EMM_OK, "%s", err.message);
    rewind(sum);
    char text[4096] = {0};
    CHECK(fread(text, 1, sizeof text - 1, sum) > 0);
    fclose(sum);
    printf("%s", text);
    CHECK(has(text, "emm: test_session: pattern region (nearest mine, distance 0.00)"));
    /* The sweep is the run's too: the check prices it. */
    CHECK(has(text, "(the table's pattern simulated over this mesh on this machine, and the "
                    "leading sweep's own cycles)"));
    CHECK(!has(text, "emm: answer: direct"));
    CHECK(has(text, "emm:   runner-up "));
    emm_session_free(s);
    char *json = slurp("checked.json");
    CHECK(json != NULL);
    CHECK(has(json, "\"source\": \"checked\""));
    CHECK(has(json, "\"nearest\": \"mine\""));
    CHECK(has_u64(json, "leading_sweep", nv));
    free(json);
}

/* The session's helper threads are the caller's own (the shim's): each one
 * calls the start hook before it does any work, with every signal blocked,
 * and the session's work — the decision's sweep and the whole comparison —
 * runs on them while the calling thread holds its own lock, as the shim
 * does. The shim's deadlock (a helper's allocation matching a tag rule
 * while the main thread held the shim's lock) came from helpers that did
 * not call the hook; tests/shim/helpers.sh runs that program under the
 * shim, and this checks the contract in every build, sanitizers included. */
static _Thread_local int marked;
static int hooked, unblocked;
static pthread_mutex_t caller_lock = PTHREAD_MUTEX_INITIALIZER;

static void helper_hook(void *ctx)
{
    sigset_t now;
    CHECK(ctx == &hooked);
    marked = 1;
    __atomic_add_fetch(&hooked, 1, __ATOMIC_RELAXED);
    pthread_sigmask(SIG_SETMASK, NULL, &now);
    if (!sigismember(&now, SIGTERM) || !sigismember(&now, SIGINT) || !sigismember(&now, SIGSEGV))
        __atomic_add_fetch(&unblocked, 1, __ATOMIC_RELAXED);
    /* The shim's hook never takes the lock its caller holds; a hook that
     * did would hang here, so the test holds it throughout. */
    CHECK(pthread_mutex_trylock(&caller_lock) == EBUSY);
}

static void test_helpers_marked(void)
{
    emm_error err;
    emm_session *s;
    write_table_synth("table.txt", "direct", "region", 0);
    emm_session_config c = base_config();
    tcfg.compare = EMM_COMPARE_ALL;
    c.threads = (emm_threads){2, helper_hook, &hooked};
    pthread_mutex_lock(&caller_lock);
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    CHECK(feed(s, 1000, 0) == 1);
    CHECKF(emm_session_finish(s, NULL, &err) == EMM_OK, "%s", err.message);
    emm_session_free(s);
    pthread_mutex_unlock(&caller_lock);
    CHECKF(hooked >= 1, "no helper thread called the hook (%d)", hooked);
    CHECKF(unblocked == 0, "%d helpers ran with signals unblocked", unblocked);
    CHECK(marked == 0); /* the calling thread is not a helper */
}

/* A short program: the window never fills, the decision comes at finish,
 * after the program has freed its arrays. */
static void test_window_not_filled(void)
{
    emm_error err;
    emm_session *s;
    write_table("table.txt", "direct", 0);
    emm_session_config c = base_config();
    tcfg.window_accesses = 1000000000;
    strcpy(tcfg.report, "short.json");
    set_strategy("cache");
    tcfg.compare = EMM_COMPARE_NONE;
    remove("short.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    CHECK(feed(s, 4096, 0) == 0);
    /* The program frees its mesh before exit: the session keeps what the
     * decision needs (the memory is scribbled over to prove it). */
    emm_session_untag(s, vmem);
    emm_session_untag(s, tmem);
    unsigned char *save_v = malloc(nv * VSTRIDE), *save_t = malloc(nt * TSTRIDE);
    REQUIRE(save_v && save_t);
    memcpy(save_v, vmem, nv * VSTRIDE);
    memcpy(save_t, tmem, nt * TSTRIDE);
    memset(vmem, 0xff, nv * VSTRIDE);
    memset(tmem, 0xff, nt * TSTRIDE);
    CHECKF(emm_session_finish(s, NULL, &err) == EMM_OK, "%s", err.message);
    memcpy(vmem, save_v, nv * VSTRIDE);
    memcpy(tmem, save_t, nt * TSTRIDE);
    free(save_v);
    free(save_t);
    CHECK(emm_session_finish(s, NULL, &err) == EMM_OK); /* a second call does nothing */
    emm_session_free(s);
    char *json = slurp("short.json");
    CHECK(has(json, "\"strategy\": \"cache\""));
    CHECK(has(json, "\"source\": \"configured\""));
    /* The last array left before the window filled: short, and said. */
    CHECK(has(json, "\"complete\": false"));
    CHECK(has(json, "\"ended_by\": \"array_freed\""));
    /* The table still names the nearest sample and its class: those of the
     * whole run's profile (the window never filled) among the shipped table
     * and this test's. */
    {
        emm_table *t = emm_table_new();
        emm_trace_reader *r;
        double *xy, *D, f[EMM_FEATURES];
        size_t n;
        emm_decision d;
        REQUIRE(t && emm_table_load_standard(t, "table.txt", &err) == EMM_OK);
        REQUIRE(emm_trace_reader_open("expect.emmt", &r, &err) == EMM_OK);
        REQUIRE(emm_profile_trace_positions(r, nrecs, EMM_PROFILE_PLANE, "expect", &xy, &n,
                                            &err) == EMM_OK);
        REQUIRE((D = malloc(n * sizeof *D)) != NULL);
        REQUIRE(emm_profile_compute(xy, n, EMM_PROFILE_PLANE, D, NULL, NULL, &err) == EMM_OK);
        REQUIRE(emm_profile_features(D, n, "expect", f, &err) == EMM_OK);
        REQUIRE(emm_table_decide(t, f, 0, &d, &err) == EMM_OK);
        char want[2 * EMM_TABLE_NAME_MAX + 32];
        snprintf(want, sizeof want, "\"nearest\": \"%s\"", d.nearest);
        CHECKF(has(json, want), "the report does not name %s", d.nearest);
        snprintf(want, sizeof want, "\"pattern\": \"%s\"", d.pattern);
        CHECKF(has(json, want), "the report does not name the class %s", d.pattern);
        free(xy);
        free(D);
        emm_trace_reader_close(r);
        emm_table_free(t);
    }
    CHECK(has_u64(json, "total", expect_cache.total));
    CHECK(!has_u64(json, "total", expect_direct.total)); /* compare none */
    free(json);
}

/* The window is the traversal's reads (docs/profile.md "The window"): a
 * loader that writes every record many times over (far more than two
 * windows' worth) neither opens nor ends it, and after it the window fills
 * with reads; the loader's writes are counted, not simulated. */
static void test_writes_do_not_end_window(void)
{
    emm_error err;
    emm_session *s;
    write_table("table.txt", "direct", 0);
    emm_session_config c = base_config();
    strcpy(tcfg.report, "loader.json");
    remove("loader.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    emm_raw_access w[256];
    uint64_t writes = 0;
    /* More element writes than any bound the window had on writes (65,536
     * taken for the loader, then two windows' worth). */
    while (writes < 70000)
        for (size_t v = 0; v < nv; v += 256) {
            size_t n = 0;
            for (size_t k = v; k < nv && k < v + 256; k++)
                w[n++] = (emm_raw_access){vbase + k * VSTRIDE + 8, 8 | EMM_RAW_WRITE, 0, 0};
            CHECK(emm_session_access(s, w, n) == EMM_SESSION_PROFILING);
            writes += n;
        }
    CHECK(feed(s, 512, 0) == 1);
    CHECKF(emm_session_finish(s, NULL, &err) == EMM_OK, "%s", err.message);
    emm_session_free(s);
    char *json = slurp("loader.json");
    CHECK(has_u64(json, "loader_writes", writes));
    CHECK(has(json, "\"complete\": true"));
    CHECK(has(json, "\"ended_by\": \"full\""));
    CHECK(has_u64(json, "element_accesses", WINDOW));
    CHECK(has(json, "\"strategy\": \"direct\""));
    free(json);
}

/* The run ends after fewer element reads than a profile needs: the
 * session decides on those reads (the candidates simulated over them) and
 * the summary and the report say the window was short. */
static void test_few_reads(void)
{
    emm_error err;
    emm_session *s;
    write_table("table.txt", "direct", 0);
    emm_session_config c = base_config();
    strcpy(tcfg.report, "few.json");
    remove("few.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    /* The first 120 records: fewer than 256 element reads. */
    emm_raw_access raw[120];
    size_t n = 0;
    for (size_t k = 0; k < 120; k++)
        if (!recs[k].write)
            raw[n++] = (emm_raw_access){addr_of(&recs[k]), recs[k].bytes, 0, 0};
    CHECK(emm_session_access(s, raw, n) == EMM_SESSION_PROFILING);
    FILE *sum = tmpfile();
    REQUIRE(sum);
    CHECKF(emm_session_finish(s, sum, &err) == EMM_OK, "%s", err.message);
    rewind(sum);
    char text[8192] = {0};
    CHECK(fread(text, 1, sizeof text - 1, sum) > 0);
    fclose(sum);
    printf("%s", text);
    emm_session_free(s);
    CHECK(has(text, "element reads profiled; a pattern needs at least 256: the candidates were "
                    "simulated over those reads instead)"));
    CHECK(has(text, "emm:   the run ended after "));
    CHECK(has(text, " of the window's 1,000 element reads: the answer rests on them"));
    CHECK(has(text, "emm: answer: "));
    char *json = slurp("few.json");
    CHECK(has(json, "\"complete\": false"));
    CHECK(has(json, "\"ended_by\": \"run_end\""));
    CHECK(has(json, "\"source\": \"simulated\""));
    CHECK(!has(json, "\"strategy\": null"));
    free(json);
}

/* Writes after the window opened are buffered and simulated, but bounded:
 * at 2^20 written records the window ends with the reads it has, and the
 * summary and the report say so. */
static void test_write_cap(void)
{
    emm_error err;
    emm_session *s;
    write_table("table.txt", "direct", 0);
    emm_session_config c = base_config();
    strcpy(tcfg.report, "wcap.json");
    remove("wcap.json");
    /* The window's end is what is tested, not the decision: a configured
     * strategy keeps the million records out of the decision's sweeps. */
    set_strategy("direct");
    tcfg.compare = EMM_COMPARE_NONE;
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    emm_raw_access raw[4096];
    size_t n = 0;
    for (size_t k = 0; k < 300; k++)
        if (!recs[k].write)
            raw[n++] = (emm_raw_access){addr_of(&recs[k]), recs[k].bytes, 0, 0};
    CHECK(emm_session_access(s, raw, n) == EMM_SESSION_PROFILING);
    emm_session_state st = EMM_SESSION_PROFILING;
    uint64_t writes = 0;
    while (st == EMM_SESSION_PROFILING && writes < 2u << 20) {
        for (size_t k = 0; k < 4096; k++)
            raw[k] = (emm_raw_access){vbase + ((writes + k) % nv) * VSTRIDE + 8,
                                      8 | EMM_RAW_WRITE, 0, 0};
        st = emm_session_access(s, raw, 4096);
        writes += 4096;
    }
    CHECK(st == EMM_SESSION_DECIDE);
    CHECK(writes >= 1u << 20 && writes < (1u << 20) + 4096);
    CHECKF(emm_session_decide(s, &err) == EMM_OK, "%s", err.message);
    FILE *sum = tmpfile();
    REQUIRE(sum);
    CHECKF(emm_session_finish(s, sum, &err) == EMM_OK, "%s", err.message);
    rewind(sum);
    char text[8192] = {0};
    CHECK(fread(text, 1, sizeof text - 1, sum) > 0);
    fclose(sum);
    printf("%s", text);
    emm_session_free(s);
    CHECK(has(text, "emm:   the window reached its bound of 1,048,576 written records after "));
    CHECK(has(text, " of the window's 1,000 element reads: the answer rests on them"));
    char *json = slurp("wcap.json");
    CHECK(has(json, "\"complete\": false"));
    CHECK(has(json, "\"ended_by\": \"write_cap\""));
    CHECK(has_u64(json, "writes", 1u << 20));
    free(json);
}

/* A profile far from every sample: the candidates are simulated on the
 * window and the best is taken. */
static void test_novel(void)
{
    emm_error err;
    emm_session *s;
    write_table("far.txt", NULL, 1);
    emm_session_config c = base_config();
    strcpy(tcfg.table, "far.txt");
    c.table_only = 1; /* the shipped table may hold a sample near this window */
    strcpy(tcfg.report, "novel.json");
    remove("novel.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    CHECK(feed(s, 1000, 0) == 1);
    CHECKF(emm_session_finish(s, NULL, &err) == EMM_OK, "%s", err.message);
    emm_session_free(s);
    char *json = slurp("novel.json");
    CHECK(has(json, "\"novel\": true"));
    CHECK(has(json, "\"source\": \"simulated\""));
    CHECK(has(json, "\"nearest\": \"far\""));
    CHECK(has(json, "\"pattern\": \"novel\""));
    CHECK(has(json, "\"nearest_pattern\": \"random\""));
    free(json);
}

/* The whole sweep (run on two threads): the baselines' totals are still
 * those of a replay, and every strategy is in the report. */
static void test_compare_all(void)
{
    emm_error err;
    emm_session *s;
    emm_session_config c = base_config();
    set_strategy("direct");
    tcfg.compare = EMM_COMPARE_ALL;
    strcpy(tcfg.report, "all.json");
    remove("all.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    CHECK(feed(s, 300, 0) == 1);
    CHECKF(emm_session_finish(s, NULL, &err) == EMM_OK, "%s", err.message);
    emm_session_free(s);
    char *json = slurp("all.json");
    CHECK(has_u64(json, "total", expect_direct.total));
    CHECK(has_u64(json, "total", expect_cache.total));
    size_t results = 0;
    for (const char *p = json; p && (p = strstr(p, "\"seconds\"")); p++)
        results++;
    size_t n = emm_strategy_sweep(NULL, 0);
    CHECKF(results >= 2 && results <= n, "%zu results", results);
    printf("compare all: %zu of %zu strategies simulated\n", results, n);
    free(json);
}

/* The contest's entrants on the default machine: the standard sweep's
 * strategies it offers (it has no cache), however many layouts and fetch
 * schemes the lists hold. */
static size_t offered_candidates(void)
{
    emm_error err;
    emm_machine *m;
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    size_t n = emm_strategy_sweep(NULL, 0), offered = 0;
    emm_strategy *all = malloc(n * sizeof *all);
    REQUIRE(all);
    emm_strategy_sweep(all, n);
    for (size_t i = 0; i < n; i++)
        offered += emm_machine_offers(m, &all[i]) != 0;
    free(all);
    emm_machine_free(m);
    return offered;
}

/* The run's contest (docs/profile.md "The contest"): with the whole run
 * fed, the answer is the contest's over the run, whatever the table
 * predicted — the same as emm_contest_trace over the same records (what
 * emm profile runs on the trace), and no slower than any whole-run result
 * the report shows. */
static void test_contest(void)
{
    emm_error err;
    emm_session *s;
    write_table("table.txt", "direct", 0);
    emm_session_config c = base_config();
    tcfg.finalists = 4;
    strcpy(tcfg.report, "contest.json");
    remove("contest.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    CHECK(feed(s, 300, 0) == 1);
    FILE *sum = fopen("contest.txt", "w+");
    REQUIRE(sum);
    CHECKF(emm_session_finish(s, sum, &err) == EMM_OK, "%s", err.message);
    emm_session_free(s);
    char text[8192] = "";
    rewind(sum);
    CHECK(fread(text, 1, sizeof text - 1, sum) > 0);
    fclose(sum);
    printf("%s", text);
    size_t entrants = offered_candidates();
    /* The answer is called the fastest of those that ran to the end; the
     * others are counted as dropped, each named in the report. */
    char *rj = slurp("contest.json");
    REQUIRE(rj && strstr(rj, "\"ran_to_end\": "));
    size_t ran = (size_t)strtoull(strstr(rj, "\"ran_to_end\": ") + 14, NULL, 10);
    const char *dropped = strstr(rj, "\"dropped\": [");
    size_t named = 0;
    for (const char *q = dropped; q && (q = strstr(q + 1, "\"strategy\"")) &&
                                  q < strstr(dropped, "]");)
        named++;
    free(rj);
    CHECKF(ran >= 1 && ran <= entrants && named == entrants - ran, "%zu ran, %zu named", ran,
           named);
    char fastest[200];
    if (ran == entrants)
        snprintf(fastest, sizeof fastest,
                 "(measured over the run: the fastest of %zu candidates, every one run to the end",
                 entrants);
    else
        snprintf(fastest, sizeof fastest,
                 "(measured over the run: the fastest of the %zu candidates that ran to the end; "
                 "the other %zu of %zu were dropped at ",
                 ran, entrants - ran, entrants);
    CHECKF(has(text, fastest), "%s", fastest);

    /* The same contest over the same records, from the trace. */
    emm_trace_reader *r;
    emm_trace_record *win;
    size_t unit;
    REQUIRE(emm_trace_reader_open("expect.emmt", &r, &err) == EMM_OK);
    REQUIRE(emm_profile_trace_window(r, WINDOW, "expect", &win, &unit, &err) == EMM_OK);
    free(win);
    emm_trace_reader_close(r);
    emm_machine *m;
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    emm_strategy direct;
    emm_strategy_parse("direct", &direct, NULL);
    emm_contest_result cr;
    /* The window's leading sweep, as the session counted it. */
    char *rep = slurp("contest.json");
    REQUIRE(rep && strstr(rep, "\"lead\": "));
    uint64_t lead = strtoull(strstr(rep, "\"lead\": ") + 8, NULL, 10);
    free(rep);
    CHECK(lead < unit);
    REQUIRE(emm_contest_trace("expect.emmt", m, &direct, lead, unit - lead, 4, NULL, &cr, &err) ==
            EMM_OK);
    emm_machine_free(m);
    CHECK(cr.entrants == entrants && cr.accesses == nrecs && cr.has_predicted);
    CHECK(cr.answer.total <= cr.predicted.total);
    char want[64], line[128];
    emm_strategy_format(&cr.answer.strategy, want, sizeof want);
    snprintf(line, sizeof line, "\"strategy\": \"%s\"", want);
    char *json = slurp("contest.json");
    REQUIRE(json);
    CHECKF(has(json, line), "the session's answer is not %s", want);
    CHECK(has_u64(json, "total", cr.answer.total));
    CHECK(has(json, "\"predicted\": \"direct\""));
    snprintf(line, sizeof line, "\"entrants\": %zu", entrants);
    CHECK(has(json, line));
    /* No whole-run result of a candidate in the report is faster than the
     * answer (the cache is a reference on this machine). */
    const char *p = strstr(json, "\"results\"");
    const char *end = p ? strstr(p, "\"program\"") : NULL;
    size_t seen = 0;
    REQUIRE(p && end);
    while ((p = strstr(p, "\"strategy\": \"")) && p < end) {
        p += 13;
        const char *t = strstr(p, "\"total\": ");
        if (!t || t > end)
            break;
        if (strncmp(p, "cache", 5) != 0) {
            CHECKF(strtoull(t + 9, NULL, 10) >= cr.answer.total, "%.40s", p);
            seen++;
        }
    }
    CHECK(seen >= 4); /* the answer, direct, and the other finalists */
    printf("contest: %s, %llu cycles (direct predicted: %llu)\n", want,
           (unsigned long long)cr.answer.total, (unsigned long long)cr.predicted.total);
    free(json);
}

/* EMM_FINALISTS=all: no candidate is dropped, every one is in the report's
 * results over the whole run, and the answer is the fewest cycles among
 * them (the cache is a reference on this machine). */
static void test_contest_all(void)
{
    emm_error err;
    emm_session *s;
    write_table("table.txt", "direct", 0);
    emm_session_config c = base_config();
    tcfg.finalists = EMM_CONFIG_FINALISTS_ALL;
    strcpy(tcfg.report, "contest-all.json");
    remove("contest-all.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    CHECK(feed(s, 300, 0) == 1);
    FILE *sum = fopen("contest-all.txt", "w+");
    REQUIRE(sum);
    CHECKF(emm_session_finish(s, sum, &err) == EMM_OK, "%s", err.message);
    emm_session_free(s);
    char text[8192] = "";
    rewind(sum);
    CHECK(fread(text, 1, sizeof text - 1, sum) > 0);
    fclose(sum);
    tcfg.finalists = EMM_CONFIG_DEFAULT_FINALISTS;
    size_t entrants = offered_candidates();
    char line[160];
    snprintf(line, sizeof line,
             "(measured over the run: the fastest of %zu candidates, every one run to the end",
             entrants);
    CHECKF(has(text, line), "%s", text);
    char *json = slurp("contest-all.json");
    REQUIRE(json);
    CHECK(has(json, "\"finalists\": \"all\"") && has(json, "\"dropped\": []"));
    snprintf(line, sizeof line, "\"ran_to_end\": %zu", entrants);
    CHECK(has(json, line));
    /* The answer is results[0]; no candidate's total is below it. */
    const char *p = strstr(json, "\"results\"");
    const char *end = p ? strstr(p, "\"program\"") : NULL;
    REQUIRE(p && end);
    const char *t = strstr(p, "\"total\": ");
    REQUIRE(t && t < end);
    uint64_t answer = strtoull(t + 9, NULL, 10);
    size_t seen = 0;
    while ((p = strstr(p, "\"strategy\": \"")) && p < end) {
        p += 13;
        t = strstr(p, "\"total\": ");
        const char *next = strstr(p, "\"strategy\": \"");
        if (!t || t > end || (next && t > next))
            continue; /* one that could not run: no cycles */
        if (strncmp(p, "cache", 5) != 0) {
            CHECKF(strtoull(t + 9, NULL, 10) >= answer, "%.40s", p);
            seen++;
        }
    }
    CHECKF(seen + 1 >= entrants - 8, "%zu candidates in the results of %zu", seen, entrants);
    free(json);
}

/* The window counted in emm_iteration() calls. */
static void test_iterations(void)
{
    emm_error err;
    emm_session *s;
    emm_session_config c = base_config();
    tcfg.window_accesses = 0;
    tcfg.window_iterations = 3;
    set_strategy("direct");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    CHECK(feed(s, 500, 1) == 1);
    CHECK(emm_session_finish(s, NULL, &err) == EMM_OK);
    emm_session_free(s);
}

/* A report whose directory disappears is absent, not half written; one
 * whose directory does not exist is refused at the start. */
static void test_report_whole_or_absent(void)
{
    emm_error err;
    emm_session *s;
    emm_session_config c = base_config();
    CHECK(emm_config_set(&tcfg, EMM_CONFIG_REPORT, "no-such-dir/r.json", NULL, 0, &err) ==
          EMM_ERR_INVALID);
    CHECKF(has(err.message, "EMM_REPORT") && has(err.message, "no-such-dir"), "%s", err.message);

    mkdir("gone", 0755);
    strcpy(tcfg.report, "gone/r.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    tag_all(s);
    feed(s, 2048, 0);
    REQUIRE(rmdir("gone") == 0);
    CHECK(emm_session_finish(s, NULL, &err) == EMM_ERR_IO);
    CHECKF(has(err.message, "EMM_REPORT"), "%s", err.message);
    CHECK(access("gone/r.json", F_OK) != 0);
    emm_session_free(s);
}

static void test_bad_config(void)
{
    emm_error err;
    emm_session *s;
    emm_session_config c = base_config();
    CHECK(emm_config_set(&tcfg, EMM_CONFIG_STRATEGY, "grid+sideways", NULL, 0, &err) ==
          EMM_ERR_INVALID);
    CHECKF(has(err.message, "EMM_STRATEGY"), "%s", err.message);
    CHECK(emm_config_set(&tcfg, EMM_CONFIG_MACHINE, "no-such-machine.ini", "--machine", 0, &err) ==
          EMM_ERR_INVALID);
    CHECKF(has(err.message, "--machine='no-such-machine.ini'"), "%s", err.message);
    c = base_config();
    strcpy(tcfg.machine, "no-such-machine.ini");
    CHECK(emm_session_new(&c, &s, &err) != EMM_OK);
    CHECKF(has(err.message, "EMM_MACHINE"), "%s", err.message);
    c = base_config();
    strcpy(tcfg.table, "no-such-table.txt");
    CHECK(emm_session_new(&c, &s, &err) != EMM_OK);
    CHECKF(has(err.message, "EMM_TABLE"), "%s", err.message);
}

/* Wrong vertex indices (a rule with the wrong offset): the decision waits
 * for the end (the arrays may be unfinished), capturing nothing more; read
 * again at finish they are still wrong, so the session reports it and
 * steps aside; no report is written. */
static void test_bad_geometry(void)
{
    emm_error err;
    emm_session *s;
    emm_session_config c = base_config();
    strcpy(tcfg.report, "bad.json");
    remove("bad.json");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    CHECK(tag_call(s, EMM_ARRAY_VERTICES, vmem, nv, VSTRIDE, 8, EMM_F64) >= 0);
    CHECK(tag_call(s, EMM_ARRAY_TRIANGLES, tmem, nt, TSTRIDE, 0, EMM_I64) >= 0);
    /* Not in index order: no leading sweep. */
    emm_raw_access a[WINDOW];
    for (size_t i = 0; i < WINDOW; i++)
        a[i] = (emm_raw_access){vbase + ((i * 7919 + 1) % nv) * VSTRIDE + 8, 8, 0, 0};
    CHECK(emm_session_access(s, a, WINDOW) == EMM_SESSION_DECIDE);
    CHECK(emm_session_decide(s, &err) == EMM_OK);
    uint64_t lo[4], hi[4];
    CHECK(emm_session_ranges(s, lo, hi, 4) == 0);
    CHECK(emm_session_access(s, a, 1) == EMM_SESSION_OFF);
    FILE *sum = tmpfile();
    CHECK(emm_session_finish(s, sum, &err) == EMM_ERR_MESH);
    rewind(sum);
    char text[1024] = {0};
    CHECK(fread(text, 1, sizeof text - 1, sum) > 0);
    fclose(sum);
    CHECKF(has(text, "no simulation") && has(text, "vertex index"), "%s", text);
    /* The report says nothing was simulated, and why. */
    char *bad = slurp("bad.json");
    CHECKF(bad && has(bad, "\"simulated\": \"nothing\"") && has(bad, "\"results\": []") &&
               has(bad, "vertex index"),
           "%s", bad ? bad : "no bad.json");
    free(bad);
    emm_session_free(s);
}

/* Tags: re-tagging a range replaces it; an untagged array's accesses are
 * dropped; nonsense is refused. */
static void test_tags(void)
{
    emm_error err;
    emm_session *s;
    emm_session_config c = base_config();
    set_strategy("direct");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    CHECK(tag_call(s, EMM_ARRAY_VERTICES, vmem, nv, VSTRIDE, 78, EMM_F64) < 0);
    CHECK(tag_call(s, EMM_ARRAY_VERTICES, vmem, nv, VSTRIDE, 8, EMM_I32) < 0);
    CHECK(tag_call(s, EMM_ARRAY_VERTICES, vmem, 0, VSTRIDE, 8, EMM_F64) < 0);
    int a = tag_call(s, EMM_ARRAY_VERTICES, vmem, nv / 2, VSTRIDE, 8, EMM_F64);
    int b = tag_call(s, EMM_ARRAY_VERTICES, vmem, nv, VSTRIDE, 8, EMM_F64);
    CHECK(a >= 0 && b >= 0);
    uint64_t lo[4], hi[4];
    CHECK(emm_session_ranges(s, lo, hi, 4) == 1 && hi[0] == vbase + nv * VSTRIDE);
    /* The last vertex array leaves before the window is full: the session
     * asks for the decision now, on the array's fields copied as it left
     * (the access before it is simulated; the one after, to an array no
     * longer tagged, is not). */
    emm_raw_access x = {vbase + 8, 8, 0, 0};
    CHECK(emm_session_access(s, &x, 1) == EMM_SESSION_PROFILING);
    CHECK(emm_session_untag(s, vmem) == EMM_SESSION_DECIDE);
    CHECK(emm_session_ranges(s, lo, hi, 4) == 0);
    emm_session_access(s, &x, 1);
    CHECK(emm_session_decide(s, &err) == EMM_OK);
    CHECK(emm_session_finish(s, NULL, &err) == EMM_OK);
    emm_session_free(s);

    /* Nothing tagged at the decision. */
    c = base_config();
    set_strategy("direct");
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    emm_session_access(s, &x, 1);
    CHECK(emm_session_finish(s, NULL, &err) != EMM_OK);
    CHECKF(has(err.message, "no vertex array was tagged"), "%s", err.message);
    emm_session_free(s);
}

/* The records of the trace at `path` into out (at most cap), returning how
 * many; its first two arrays, and its geometry when it is small. */
static size_t read_records(const char *path, emm_trace_record *out, size_t cap,
                           emm_trace_array *arrays, uint32_t *narrays, double *xyz, int32_t *tri,
                           uint64_t *gnv, uint64_t *gnt)
{
    emm_error err;
    emm_trace_reader *r;
    REQUIRE(emm_trace_reader_open(path, &r, &err) == EMM_OK);
    const emm_trace_info *info = emm_trace_reader_info(r);
    *narrays = info->narrays;
    for (uint32_t i = 0; i < info->narrays && i < 2; i++)
        arrays[i] = info->arrays[i];
    *gnv = info->geometry.nv;
    *gnt = info->geometry.nt;
    if (*gnv <= 8 && *gnt <= 8) {
        memcpy(xyz, info->geometry.xyz, 3 * *gnv * sizeof *xyz);
        memcpy(tri, info->geometry.tri, 3 * *gnt * sizeof *tri);
    }
    size_t n = 0, got;
    while (n < cap && emm_trace_read(r, out + n, cap - n, &got, &err) == EMM_OK && got)
        n += got;
    emm_trace_reader_close(r);
    return n;
}

/* A session deciding "direct" with EMM_TAG `rules` (the shim's blocks are
 * then tagged by rule), its trace at `trace` and its report at `report`
 * (NULL: none). */
static emm_session *new_tagged(const char *rules, const char *trace, const char *report)
{
    emm_error err;
    emm_session *s;
    emm_session_config c = base_config();
    set_strategy("direct");
    emm_tag_rules_free(&tcfg.tags);
    REQUIRE(emm_tag_rules_parse(rules, &tcfg.tags, &err) == EMM_OK);
    if (trace)
        strcpy(tcfg.trace, trace);
    if (report)
        strcpy(tcfg.report, report);
    REQUIRE(emm_session_new(&c, &s, &err) == EMM_OK);
    return s;
}

/* Issue 14 item 5 through the API, as the shim drives it for a rule: a
 * column-major block (order=columns) whose x, y and z columns are one
 * element each, the trace record's offset naming the column; and a
 * triangle soup (soup:) whose records are triangles, any byte of one that
 * triangle's, its corners the geometry's vertices merged by position. */
static void test_shapes(void)
{
    emm_error err;
    emm_session *s;
    emm_trace_record rec[16];
    emm_trace_array arr[2];
    uint32_t narr;
    double xyz[24];
    int32_t tri[24];
    uint64_t gnv, gnt;

    /* A square of two triangles, V and F column-major (libigl's). */
    static double V[12] = {0, 1, 1, 0, /* x */ 0, 0, 1, 1, /* y */ 5, 6, 7, 8 /* z */};
    static int32_t F[6] = {0, 0, /* first corners */ 1, 2, /* second */ 2, 3 /* third */};
    s = new_tagged("vertices:order=columns,xyz=0:f64;triangles:order=columns,vidx=0:i32",
                   "shapes.emmt", NULL);
    /* The shim hands a rule's block over as entries of `stride` bytes. */
    CHECK(tag_rule(s, V, 12, 0) >= 0);
    CHECK(tag_rule(s, F, 6, 1) >= 0);
    uint64_t lo[4], hi[4];
    CHECK(emm_session_ranges(s, lo, hi, 4) == 2 && lo[0] == (uintptr_t)V &&
          hi[0] == (uintptr_t)(V + 12));
    emm_raw_access a[] = {
        {(uintptr_t)&V[4 + 2], 8, 0, 0}, /* vertex 2's y */
        {(uintptr_t)&V[8 + 3], 8, 0, 0}, /* vertex 3's z */
        {(uintptr_t)&V[1], 8, 0, 0},     /* vertex 1's x */
        {(uintptr_t)&F[4 + 1], 4, 0, 0}, /* triangle 1's third corner */
    };
    emm_session_access(s, a, 4);
    CHECKF(emm_session_decide(s, &err) == EMM_OK, "%s", err.message);
    CHECKF(emm_session_finish(s, NULL, &err) == EMM_OK, "%s", err.message);
    emm_session_free(s);
    size_t n = read_records("shapes.emmt", rec, 16, arr, &narr, xyz, tri, &gnv, &gnt);
    REQUIRE(n == 4 && narr == 2);
    CHECK(arr[0].record_size == 24 && arr[0].count == 4 && arr[1].record_size == 12);
    CHECK(rec[0].array == 0 && rec[0].element == 2 && rec[0].offset == 8);
    CHECK(rec[1].array == 0 && rec[1].element == 3 && rec[1].offset == 16);
    CHECK(rec[2].array == 0 && rec[2].element == 1 && rec[2].offset == 0);
    CHECK(rec[3].array == 1 && rec[3].element == 1 && rec[3].offset == 8);
    REQUIRE(gnv == 4 && gnt == 2);
    for (int v = 0; v < 4; v++)
        CHECKF(xyz[3 * v] == V[v] && xyz[3 * v + 1] == V[4 + v] && xyz[3 * v + 2] == V[8 + v],
               "vertex %d: %g %g %g", v, xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]);
    CHECK(tri[0] == 0 && tri[1] == 1 && tri[2] == 2 && tri[3] == 0 && tri[4] == 2 && tri[5] == 3);

    /* The same square as a soup of 40-byte records: an id, then three
     * corners of three floats; -0 and 0 are one position. */
    struct facet {
        int32_t id;
        float c[3][3];
    };
    static struct facet soup[2] = {{7, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}},
                                   {8, {{0, 0, 0}, {1, 1, -0.0f}, {0, 1, 0}}}};
    s = new_tagged("soup:stride=40,corners=4:f32", "soup.emmt", NULL);
    CHECK(tag_rule(s, soup, 2, 0) >= 0);
    emm_raw_access b[] = {
        {(uintptr_t)&soup[1].id, 4, 0, 0},      /* triangle 1, not a corner */
        {(uintptr_t)&soup[0].c[2][1], 4, 0, 0}, /* triangle 0's third corner's y */
    };
    emm_session_access(s, b, 2);
    CHECKF(emm_session_decide(s, &err) == EMM_OK, "%s", err.message);
    CHECKF(emm_session_finish(s, NULL, &err) == EMM_OK, "%s", err.message);
    emm_session_free(s);
    n = read_records("soup.emmt", rec, 16, arr, &narr, xyz, tri, &gnv, &gnt);
    REQUIRE(n == 2 && narr == 1);
    CHECK(arr[0].kind == EMM_ARRAY_TRIANGLES && arr[0].record_size == 40 && arr[0].count == 2);
    CHECK(rec[0].element == 1 && rec[0].offset == 0);
    CHECK(rec[1].element == 0 && rec[1].offset == 32);
    REQUIRE(gnv == 4 && gnt == 2);
    for (int t = 0; t < 2; t++)
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++)
                CHECKF(xyz[3 * tri[3 * t + k] + d] == soup[t].c[k][d],
                       "triangle %d corner %d: %g, not %g", t, k, xyz[3 * tri[3 * t + k] + d],
                       (double)soup[t].c[k][d]);
    CHECK(tri[3] == tri[0] && tri[4] == tri[2]); /* the shared edge's corners are shared */
    emm_tag_rules_free(&tcfg.tags);
}

/* finish's summary into text (cap bytes); returns finish's status. */
static emm_status finish_summary(emm_session *s, char *text, size_t cap);

/* Issue 30 through the API: a half-edge mesh (a square of two triangles,
 * OpenMesh's 16-byte half-edges {face, to, next, prev}, a face's
 * half-edge, a vertex's) whose faces are the triangles read through their
 * cycles; an access to a half-edge is one to its face's triangle, at its
 * place in the cycle after the face's record, a vertex's vconn record one
 * to the vertex after its position; a boundary half-edge travels with its
 * opposite. A broken cycle is refused in one line naming the rule. */
static void test_halfedges(void)
{
    struct he {
        int32_t face, to, next, prev;
    };
    /* Triangles 0 (0 1 2) and 1 (0 2 3): half-edges 0..2 and 4..6 their
     * cycles, 3 and 7 the boundary opposites of 2 (2 -> 0) and 6 (3 -> 0):
     * edge e holds 2e and 2e + 1. */
    static struct he H[8] = {
        {0, 1, 1, 2}, {1, 0, 7, 3},  /* 0: 0->1 (face 0); 1: boundary 1->0 */
        {0, 2, 2, 0}, {1, 1, 0, 1},  /* 2: 1->2; 3: ... */
        {0, 0, 0, 1}, {1, 2, 6, 5},  /* placeholder, fixed below */
        {1, 3, 4, 6}, {-1, 0, 3, 1},
    };
    static int32_t F[2];
    static int32_t C[4] = {0, 2, 4, 6};
    static float P[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    /* Face 0: 0 -> 2 -> 4 -> 0 with to-vertices 1, 2, 0; face 1: 5 -> 6 ->
     * 1 -> 5 with to-vertices 2, 3, 0; 3 and 7 are boundary (-1). */
    struct he fix[8] = {{0, 1, 2, 4}, {1, 0, 5, 6}, {0, 2, 4, 0}, {-1, 1, 7, 7},
                        {0, 0, 0, 2}, {1, 2, 6, 1}, {1, 3, 1, 5}, {-1, 3, 3, 3}};
    memcpy(H, fix, sizeof H);
    F[0] = 0;
    F[1] = 5;
    const char *rules = "vertices:stride=12,xyz=0:f32;vconn:stride=4,he=0:i32;"
                        "halfedges:stride=16,to=4:i32,next=8,prev=12,face=0;"
                        "faces:stride=4,he=0:i32";
    emm_error err;
    emm_trace_record rec[16];
    emm_trace_array arr[2];
    uint32_t narr;
    double xyz[24];
    int32_t tri[24];
    uint64_t gnv, gnt;
    emm_session *s = new_tagged(rules, "halfedges.emmt", "halfedges.json");
    CHECK(tag_rule(s, P, 4, 0) >= 0);
    CHECK(tag_rule(s, C, 4, 1) >= 0);
    CHECK(tag_rule(s, H, 8, 2) >= 0);
    CHECK(tag_rule(s, F, 2, 3) >= 0);
    emm_raw_access a[] = {
        {(uintptr_t)&F[1], 4, 0, 0},        /* face 1: triangle 1, offset 0 */
        {(uintptr_t)&H[6].next, 4, 0, 0},   /* half-edge 6, face 1's second: 4 + 16 + 8 */
        {(uintptr_t)&H[3].to, 4, 0, 0},     /* boundary 3, with its opposite 2 (face 0's 2nd) */
        {(uintptr_t)&C[2], 4, 0, 0},        /* vertex 2's half-edge: after its position */
        {(uintptr_t)&P[3 * 2 + 1], 4, 0, 0} /* vertex 2's y */
    };
    emm_session_access(s, a, 5);
    CHECKF(emm_session_decide(s, &err) == EMM_OK, "%s", err.message);
    char text[8192];
    CHECKF(finish_summary(s, text, sizeof text) == EMM_OK, "%s", text);
    /* The records in use: up to the highest accessed (half-edge 6). */
    CHECKF(has(text, "connectivity: 2 face records (4 bytes, 1 accesses), 7 half-edge records "
                     "(16 bytes, 2 accesses), 3 vertex connectivity records (4 bytes, 1 "
                     "accesses)"),
           "%s", text);
    emm_session_free(s);
    size_t n = read_records("halfedges.emmt", rec, 16, arr, &narr, xyz, tri, &gnv, &gnt);
    REQUIRE(n == 5 && narr == 2);
    CHECK(arr[0].kind == EMM_ARRAY_VERTICES && arr[0].record_size == 16 && arr[0].count == 4);
    CHECK(arr[1].kind == EMM_ARRAY_TRIANGLES && arr[1].record_size == 4 + 3 * 16 &&
          arr[1].count == 2);
    CHECK(rec[0].array == 1 && rec[0].element == 1 && rec[0].offset == 0);
    CHECK(rec[1].array == 1 && rec[1].element == 1 && rec[1].offset == 4 + 16 + 8);
    CHECK(rec[2].array == 1 && rec[2].element == 0 && rec[2].offset == 4 + 16 + 4);
    CHECK(rec[3].array == 0 && rec[3].element == 2 && rec[3].offset == 12);
    CHECK(rec[4].array == 0 && rec[4].element == 2 && rec[4].offset == 4);
    REQUIRE(gnv == 4 && gnt == 2);
    CHECK(tri[0] == 1 && tri[1] == 2 && tri[2] == 0 && tri[3] == 2 && tri[4] == 3 && tri[5] == 0);
    char *report = slurp("halfedges.json");
    CHECKF(report && has(report, "\"kind\": \"halfedges\"") &&
               has(report, "\"record_bytes\": 52"),
           "%s", report ? report : "(no report)");
    free(report);

    /* Face 1's cycle broken: 6 -> 6 instead of 6 -> 1. */
    H[6].next = 6;
    s = new_tagged("vertices:stride=12,xyz=0:f32;halfedges:stride=16,to=4:i32,next=8,face=0;"
                   "faces:stride=4,he=0:i32",
                   NULL, NULL);
    CHECK(tag_rule(s, P, 4, 0) >= 0);
    CHECK(tag_rule(s, H, 8, 1) >= 0);
    CHECK(tag_rule(s, F, 2, 2) >= 0);
    emm_session_access(s, a, 2);
    emm_session_decide(s, &err);
    CHECK(finish_summary(s, text, sizeof text) != EMM_OK);
    CHECKF(has(text, "EMM_TAG rule 2 (halfedges:stride=16,to=4:i32,next=8,face=0): the "
                     "half-edge mesh is refused: half-edge 5's cycle does not close: it comes "
                     "back to half-edge 6, not to 5 (5 -> 6 -> 6)"),
           "%s", text);
    emm_session_free(s);
    emm_tag_rules_free(&tcfg.tags);
}

static emm_status finish_summary(emm_session *s, char *text, size_t cap)
{
    emm_error err;
    FILE *sum = tmpfile();
    REQUIRE(sum != NULL);
    emm_status st = emm_session_finish(s, sum, &err);
    rewind(sum);
    size_t n = fread(text, 1, cap - 1, sum);
    text[n] = '\0';
    fclose(sum);
    return st;
}

/* Structure of arrays through the API, as the shim drives it for x=, y=,
 * z= rules: three blocks of one count are one mesh's vertices, element i
 * of any of them vertex i (one trace record, its offset naming the axis);
 * the geometry combines the axes, at the decision or from the blocks'
 * copies when they left before it; a mesh without z is in the plane; a
 * missing axis, counts that disagree and a coordinate that is none are
 * one line naming the rules, and nothing is simulated. */
static void test_axes(void)
{
    emm_error err;
    emm_session *s;
    emm_trace_record rec[16];
    emm_trace_array arr[2];
    uint32_t narr;
    double xyz[24];
    int32_t tri[24];
    uint64_t gnv, gnt;
    char text[2048];

    /* A square of two triangles; each axis an array of structs holding
     * an id and one coordinate (stride 16, the double at 8). */
    struct entry {
        int64_t id;
        double c;
    };
    static struct entry X[4] = {{0, 0}, {1, 1}, {2, 1}, {3, 0}};
    static struct entry Y[4] = {{0, 0}, {1, 0}, {2, 1}, {3, 1}};
    static struct entry Z[4] = {{0, 5}, {1, 6}, {2, 7}, {3, 8}};
    static int32_t F[6] = {0, 1, 2, 0, 2, 3};
    s = new_tagged("vertices:stride=16,x=8:f64;vertices:stride=16,y=8:f64;"
                   "vertices:stride=16,z=8:f64;triangles:stride=12,vidx=0:i32",
                   "axes.emmt", NULL);
    /* The blocks in another order than their axes: the rules say which is which. */
    CHECK(tag_rule(s, Z, 4, 2) >= 0);
    CHECK(tag_rule(s, X, 4, 0) >= 0);
    CHECK(tag_rule(s, Y, 4, 1) >= 0);
    CHECK(tag_rule(s, F, 2, 3) >= 0);
    uint64_t lo[8], hi[8];
    CHECK(emm_session_ranges(s, lo, hi, 8) == 4);
    emm_raw_access a[] = {
        {(uintptr_t)&Y[2].c, 8, 0, 0},  /* vertex 2's y */
        {(uintptr_t)&Z[3].c, 8, 0, 0},  /* vertex 3's z */
        {(uintptr_t)&X[1].id, 8, 0, 0}, /* vertex 1's x block, its id */
        {(uintptr_t)&F[5], 4, 0, 0},    /* triangle 1's third corner */
    };
    emm_session_access(s, a, 4);
    CHECKF(emm_session_decide(s, &err) == EMM_OK, "%s", err.message);
    CHECK(finish_summary(s, text, sizeof text) == EMM_OK);
    CHECKF(has(text, "the vertices are 3 blocks (x, y, z) of 4 f64 each (EMM_TAG rules 1, 2, 3)"),
           "%s", text);
    emm_session_free(s);
    size_t n = read_records("axes.emmt", rec, 16, arr, &narr, xyz, tri, &gnv, &gnt);
    REQUIRE(n == 4 && narr == 2);
    CHECK(arr[0].kind == EMM_ARRAY_VERTICES && arr[0].record_size == 48 && arr[0].count == 4);
    CHECK(arr[1].kind == EMM_ARRAY_TRIANGLES && arr[1].record_size == 12);
    CHECK(rec[0].array == 0 && rec[0].element == 2 && rec[0].offset == 16 + 8);
    CHECK(rec[1].array == 0 && rec[1].element == 3 && rec[1].offset == 32 + 8);
    CHECK(rec[2].array == 0 && rec[2].element == 1 && rec[2].offset == 0);
    CHECK(rec[3].array == 1 && rec[3].element == 1 && rec[3].offset == 8);
    REQUIRE(gnv == 4 && gnt == 2);
    for (int v = 0; v < 4; v++)
        CHECKF(xyz[3 * v] == X[v].c && xyz[3 * v + 1] == Y[v].c && xyz[3 * v + 2] == Z[v].c,
               "vertex %d: %g %g %g", v, xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]);
    for (int k = 0; k < 6; k++)
        CHECK(tri[k] == F[k]);

    /* In the plane: x and y only, f32, no triangles; both blocks leave
     * before the decision, which reads the copies the session kept. */
    static float x2[4] = {0, 1, 1, 0}, y2[4] = {0, 0, 1, 1};
    s = new_tagged("vertices:x=0:f32;vertices:y=0:f32", "axes2.emmt", NULL);
    CHECK(tag_rule(s, x2, 4, 0) >= 0);
    CHECK(tag_rule(s, y2, 4, 1) >= 0);
    emm_raw_access b[] = {{(uintptr_t)&x2[3], 4, 0, 0}, {(uintptr_t)&y2[3], 4, 0, 0}};
    emm_session_access(s, b, 2);
    CHECK(emm_session_untag(s, x2) == EMM_SESSION_PROFILING); /* y is left */
    CHECK(emm_session_untag(s, y2) == EMM_SESSION_DECIDE);
    CHECKF(emm_session_decide(s, &err) == EMM_OK, "%s", err.message);
    CHECK(finish_summary(s, text, sizeof text) == EMM_OK);
    CHECKF(has(text, "the vertices are 2 blocks (x, y; z is 0) of 4 f32 each (EMM_TAG rules 1, 2)"),
           "%s", text);
    emm_session_free(s);
    n = read_records("axes2.emmt", rec, 16, arr, &narr, xyz, tri, &gnv, &gnt);
    REQUIRE(n == 2 && narr == 1 && gnv == 4);
    CHECK(arr[0].record_size == 8 && rec[0].element == 3 && rec[0].offset == 0 &&
          rec[1].element == 3 && rec[1].offset == 4);
    for (int v = 0; v < 4; v++)
        CHECK(xyz[3 * v] == x2[v] && xyz[3 * v + 1] == y2[v] && xyz[3 * v + 2] == 0);

    /* Counts that disagree: one line naming both rules; the report says
     * nothing was simulated, and why. */
    static float y3[3] = {0, 0, 1};
    remove("axes.json");
    s = new_tagged("vertices:x=0:f32;vertices:y=0:f32", NULL, "axes.json");
    CHECK(tag_rule(s, x2, 4, 0) >= 0);
    CHECK(tag_rule(s, y3, 3, 1) >= 0);
    emm_session_access(s, b, 1);
    CHECK(emm_session_decide(s, &err) != EMM_OK);
    CHECK(finish_summary(s, text, sizeof text) != EMM_OK);
    CHECKF(has(text, "no simulation: EMM_TAG rule 1 (vertices:stride=4,x=0:f32) tagged the x "
                     "block at ") &&
               has(text, ", 4 entries, but EMM_TAG rule 2 (vertices:stride=4,y=0:f32) tagged "
                         "the y block at ") &&
               has(text, "with 3: the counts disagree") && !strchr(strchr(text, '\n') + 1, '\n'),
           "%s", text);
    char *axes = slurp("axes.json");
    CHECKF(axes && has(axes, "\"simulated\": \"nothing\"") && has(axes, "the counts disagree"),
           "%s", axes ? axes : "no axes.json");
    free(axes);
    emm_session_free(s);

    /* A y that is no coordinate: the y block is refused, by its rule. */
    static float y4[4] = {0, 0, 1, 1};
    y4[1] = (float)NAN;
    s = new_tagged("vertices:x=0:f32;vertices:y=0:f32", NULL, NULL);
    CHECK(tag_rule(s, x2, 4, 0) >= 0);
    CHECK(tag_rule(s, y4, 4, 1) >= 0);
    emm_session_access(s, b, 1);
    emm_session_decide(s, &err);
    CHECK(finish_summary(s, text, sizeof text) == EMM_ERR_MESH);
    CHECKF(has(text, "EMM_TAG rule 2 (vertices:stride=4,y=0:f32): the block at ") &&
               has(text, "(4 entries of 4 bytes) is refused: vertex 1 has y = nan, not a "
                         "coordinate (is stride or y's offset or type wrong?)"),
           "%s", text);
    emm_session_free(s);
    emm_tag_rules_free(&tcfg.tags);
}

int main(void)
{
    setup();
    test_helpers_marked();
    test_decide_from_table();
    test_decide_checked();
    test_window_not_filled();
    test_writes_do_not_end_window();
    test_few_reads();
    test_write_cap();
    test_novel();
    test_contest();
    test_contest_all();
    test_compare_all();
    test_iterations();
    test_report_whole_or_absent();
    test_bad_config();
    test_bad_geometry();
    test_tags();
    test_shapes();
    test_axes();
    test_halfedges();
    free(recs);
    free(vmem);
    free(tmem);
    return check_done();
}
