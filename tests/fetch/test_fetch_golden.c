/* The models' results, number for number, against a stored listing
 * (tests/data/fetch_golden.txt): a change meant to make the models faster
 * must leave every cycle bucket and counter as it was. Synthetic region
 * and curve traces on a 3,000-face mesh, each vertex record followed by
 * further loads of the same record (as a program reads x, y, z) and some
 * writes, simulated under EMM strategies of every layout, scheme and
 * variant, the cache (each fetch policy) and direct reads, on machines
 * whose look-up tables fit, are paged over a few frames, over many frames,
 * and by pages of a size that is no power of two. Each
 * model also runs the trace in irregular pieces, which must not change a
 * number either.
 *
 * usage: test_fetch_golden LISTING          compare
 *        test_fetch_golden --write LISTING  write it (after a change of the
 *                                           model that is meant) */
#include "fetch_util.h"

/* Each record, then up to `extra` further loads of the same record at the
 * next 8-byte fields; every 7th record a write. */
static void expand(const loaded_trace *t, emm_trace_record **out, size_t *n)
{
    size_t cap = 4 * t->n, k = 0;
    emm_trace_record *o = malloc(cap * sizeof *o);
    REQUIRE(o);
    for (size_t i = 0; i < t->n; i++) {
        emm_trace_record r = t->recs[i];
        uint32_t size = t->info->arrays[r.array].record_size;
        uint32_t extra = t->info->arrays[r.array].kind == EMM_ARRAY_VERTICES ? 2 : (uint32_t)(i % 2);
        r.write = i % 7 == 3;
        o[k++] = r;
        for (uint32_t e = 0; e < extra && r.offset + 8 * (e + 1) + r.bytes <= size; e++) {
            emm_trace_record x = r;
            x.offset = r.offset + 8 * (e + 1);
            x.write = 0;
            o[k++] = x;
        }
    }
    *out = o;
    *n = k;
}

static void print_result(FILE *f, const char *what, const char *name, const emm_result *r)
{
    fprintf(f, "%s %s total %llu acc %llu", what, name, (unsigned long long)r->total,
            (unsigned long long)r->accesses);
    for (int b = 0; b < EMM_BUCKET_COUNT; b++)
        fprintf(f, " %llu", (unsigned long long)r->cycles[b]);
    if (r->has_dma)
        fprintf(f, " dma %llu %llu", (unsigned long long)r->dma.transfers,
                (unsigned long long)r->dma.bytes);
    if (r->has_emm) {
        const uint64_t e[] = {r->emm.cell_changes, r->emm.demand_fetches, r->emm.demand_bytes,
                              r->emm.prefetches, r->emm.prefetch_bytes, r->emm.useful_prefetches,
                              r->emm.dropped_prefetches, r->emm.filtered_prefetches,
                              r->emm.evictions, r->emm.other_accesses, r->emm.local_budget,
                              r->emm.lookup_bytes, r->emm.lookups, r->emm.pointer_accesses,
                              r->emm.same_record, r->emm.lookup_paged, r->emm.lookup_pages,
                              r->emm.lookup_page_bytes, r->emm.refetches, r->emm.refetch_bytes,
                              r->emm.unused_prefetches, r->emm.prefetch_checks,
                              r->emm.resident_cells};
        fprintf(f, " emm");
        for (size_t i = 0; i < sizeof e / sizeof e[0]; i++)
            fprintf(f, " %llu", (unsigned long long)e[i]);
    }
    if (r->has_cache)
        fprintf(f, " cache %llu %llu %llu %llu %llu", (unsigned long long)r->cache.demand_fetches,
                (unsigned long long)r->cache.demand_misses,
                (unsigned long long)r->cache.prefetch_fetches,
                (unsigned long long)r->cache.prefetch_misses,
                (unsigned long long)r->cache.late_prefetches);
    if (r->has_direct)
        fprintf(f, " direct %llu %llu", (unsigned long long)r->direct.words_read,
                (unsigned long long)r->direct.words_written);
    fputc('\n', f);
}

static const char *const strategies[] = {
    "grid+naive@16",          "grid+extrapolated@8",       "tiles+convolution@32",
    "tiles+extrapolated@64:indexed", "quadtree+naive@32:indexed", "quadtree+convolution@8",
    "quadtree+extrapolated@16", "quadtree+convolution@64:indexed", "cache", "cache@tiles@32",
    "cache@quadtree@16",      "direct",
};

static const char *const machines[][5] = {
    {"default", NULL},
    /* Tables paged over a few frames. */
    {"paged", "local.bytes=48K", "emm.lookup_budget=4K", NULL},
    /* Many frames of small pages; one channel; demand-fetching cache. */
    {"frames", "emm.lookup_budget=24K", "emm.lookup_page=64", "dma.channels=1",
     "cache.fetch=demand"},
    /* Pages of a size that is no power of two; always-prefetch cache,
     * records moved whole by direct reads. */
    {"odd", "emm.lookup_budget=6K", "emm.lookup_page=1000", "cache.fetch=always",
     "direct.granularity=record"},
};

static void run_all(FILE *f, const emm_machine *mc, const char *mname, const char *tname,
                    const loaded_trace *t, const emm_trace_record *recs, size_t n)
{
    for (size_t i = 0; i < sizeof strategies / sizeof strategies[0]; i++) {
        char what[64];
        emm_strategy s;
        emm_model *whole, *pieces;
        emm_result a, b;
        emm_error err;
        snprintf(what, sizeof what, "%s %s", tname, mname);
        REQUIRE(emm_strategy_parse(strategies[i], &s, &err) == EMM_OK);
        if (emm_model_new(mc, &s, t->info, &whole, &err) != EMM_OK) {
            fprintf(f, "%s %s skipped\n", what, strategies[i]);
            continue;
        }
        REQUIRE(emm_model_new(mc, &s, t->info, &pieces, &err) == EMM_OK);
        emm_model_run(whole, recs, n);
        for (size_t k = 0, len = 1; k < n; k += len, len = len * 3 % 1001 + 1)
            emm_model_run(pieces, recs + k, n - k < len ? n - k : len);
        emm_model_result(whole, &a);
        emm_model_result(pieces, &b);
        print_result(f, what, strategies[i], &a);
        CHECKF(a.total == b.total && memcmp(a.cycles, b.cycles, sizeof a.cycles) == 0 &&
                   memcmp(&a.emm, &b.emm, sizeof a.emm) == 0 &&
                   memcmp(&a.cache, &b.cache, sizeof a.cache) == 0 &&
                   memcmp(&a.dma, &b.dma, sizeof a.dma) == 0,
               "%s %s: the trace in pieces gives other results", what, strategies[i]);
        emm_model_free(whole);
        emm_model_free(pieces);
    }
}

int main(int argc, char **argv)
{
    int write = argc == 3 && strcmp(argv[1], "--write") == 0;
    REQUIRE(argc == 2 || write);
    const char *listing = argv[argc - 1];
    char *got = NULL;
    size_t got_len = 0;
    FILE *f = open_memstream(&got, &got_len);
    REQUIRE(f);
    emm_mesh *mesh = thesis_mesh(3000);
    const emm_synth_options opts[] = {
        {.pattern = EMM_PATTERN_REGION, .seed = 2},
        {.pattern = EMM_PATTERN_CURVE, .seed = 3, .visits = 4000, .length = 30},
    };
    const char *const tnames[] = {"region", "curve"};
    for (size_t k = 0; k < 2; k++) {
        loaded_trace t;
        emm_trace_record *recs;
        size_t n;
        synth_load(mesh, &opts[k], "fetch_golden.emmt", &t);
        expand(&t, &recs, &n);
        for (size_t j = 0; j < sizeof machines / sizeof machines[0]; j++) {
            emm_machine *mc;
            emm_error err;
            REQUIRE(emm_machine_new(&mc, &err) == EMM_OK);
            for (size_t a = 1; a < 5 && machines[j][a]; a++)
                REQUIRE(emm_machine_set(mc, machines[j][a], &err) == EMM_OK);
            run_all(f, mc, machines[j][0], tnames[k], &t, recs, n);
            emm_machine_free(mc);
        }
        free(recs);
        free_trace(&t);
    }
    emm_mesh_free(mesh);
    fclose(f);
    if (write) {
        FILE *o = fopen(listing, "w");
        REQUIRE(o && fwrite(got, 1, got_len, o) == got_len && fclose(o) == 0);
        printf("wrote %s\n", listing);
    } else {
        FILE *i = fopen(listing, "r");
        REQUIRE(i);
        char *want = malloc(got_len + 2);
        REQUIRE(want);
        size_t want_len = fread(want, 1, got_len + 1, i);
        fclose(i);
        /* The first line that differs, to say what changed. */
        size_t at = 0, line = 1;
        while (at < got_len && at < want_len && got[at] == want[at])
            line += got[at++] == '\n';
        while (at > 0 && got[at - 1] != '\n')
            at--;
        CHECKF(want_len == got_len && memcmp(got, want, got_len) == 0,
               "%s differs from line %zu; this build gives\n%.*s", listing, line,
               (int)strcspn(got + at, "\n"), got + at);
        free(want);
    }
    free(got);
    return check_done();
}
