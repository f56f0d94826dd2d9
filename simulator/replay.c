/* The record -> model pipeline behind `emm replay`: one streaming pass over
 * a trace feeds every model batch by batch, so memory stays the same for any
 * trace length; and the JSON report of docs/report.md. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "error.h"
#include "json.h"
#include "machine.h"
#include "model.h"

/* Records per batch: large enough that the per-batch dispatch is noise,
 * small enough to stay in the host's L2 cache. */
#define REPLAY_BATCH 8192

emm_status emm_replay(const char *path, const emm_machine *m, const emm_strategy *s,
                      size_t n, emm_result *results, uint64_t *accesses,
                      emm_progress_fn progress, void *progress_ctx, emm_error *err)
{
    emm_trace_reader *r = NULL;
    emm_model **models = NULL;
    emm_trace_record *buf = NULL;
    const emm_trace_info *info;
    uint64_t done = 0, next_report = 0;
    size_t built = 0;
    emm_status st;

    if ((st = emm_machine_validate(m, err)) != EMM_OK)
        return st;
    if ((st = emm_trace_reader_open(path, &r, err)) != EMM_OK)
        return st;
    info = emm_trace_reader_info(r);
    models = calloc(n ? n : 1, sizeof *models);
    buf = malloc(REPLAY_BATCH * sizeof *buf);
    if (!models || !buf) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
        goto out;
    }
    for (built = 0; built < n; built++)
        if ((st = emm_model_new(m, &s[built], info, &models[built], err)) != EMM_OK)
            goto out;
    for (;;) {
        size_t got = 0;
        if ((st = emm_trace_read(r, buf, REPLAY_BATCH, &got, err)) != EMM_OK)
            goto out;
        if (got == 0)
            break;
        for (size_t i = 0; i < n; i++)
            emm_model_run(models[i], buf, got);
        done += got;
        if (progress && done >= next_report) {
            progress(progress_ctx, done, info->accesses);
            next_report = done + (1u << 22);
        }
    }
    if (progress)
        progress(progress_ctx, done, info->accesses);
    for (size_t i = 0; i < n; i++)
        emm_model_result(models[i], &results[i]);
    if (accesses)
        *accesses = done;
    st = EMM_OK;
out:
    for (size_t i = 0; i < built; i++)
        emm_model_free(models[i]);
    free(models);
    free(buf);
    emm_trace_reader_close(r);
    return st;
}

static void write_machine(json_writer *w, const emm_machine *m)
{
    json_begin_object(w);
    for (size_t i = 0; i < emm_machine_key_count(); i++) {
        const char *key = emm_machine_key_at(i)->name;
        json_key(w, key);
        if (emm_machine_key_is_text(key)) {
            char buf[64];
            emm_machine_format(m, key, buf, sizeof buf);
            json_string(w, buf);
        } else {
            json_u64(w, emm_machine_get(m, key));
        }
    }
    json_end_object(w);
}

static void write_result(json_writer *w, const emm_machine *m, const emm_result *res)
{
    char name[64];
    emm_strategy_format(&res->strategy, name, sizeof name);
    json_begin_object(w);
    json_key(w, "strategy");
    json_string(w, name);
    json_key(w, "accesses");
    json_u64(w, res->accesses);
    json_key(w, "cycles");
    json_begin_object(w);
    json_key(w, "total");
    json_u64(w, res->total);
    for (int b = 0; b < EMM_BUCKET_COUNT; b++) {
        json_key(w, emm_bucket_name((emm_bucket)b));
        json_u64(w, res->cycles[b]);
    }
    json_end_object(w);
    json_key(w, "seconds");
    json_double(w, (double)res->total / ((double)m->p.clock_mhz * 1e6));
    if (res->has_cache) {
        json_key(w, "cache");
        json_begin_object(w);
        json_key(w, "demand_fetches");
        json_u64(w, res->cache.demand_fetches);
        json_key(w, "demand_misses");
        json_u64(w, res->cache.demand_misses);
        json_key(w, "prefetch_fetches");
        json_u64(w, res->cache.prefetch_fetches);
        json_key(w, "prefetch_misses");
        json_u64(w, res->cache.prefetch_misses);
        json_key(w, "late_prefetches");
        json_u64(w, res->cache.late_prefetches);
        json_end_object(w);
    }
    if (res->has_dma) {
        json_key(w, "dma");
        json_begin_object(w);
        json_key(w, "transfers");
        json_u64(w, res->dma.transfers);
        json_key(w, "bytes");
        json_u64(w, res->dma.bytes);
        json_end_object(w);
    }
    if (res->has_direct) {
        json_key(w, "direct");
        json_begin_object(w);
        json_key(w, "words_read");
        json_u64(w, res->direct.words_read);
        json_key(w, "words_written");
        json_u64(w, res->direct.words_written);
        json_end_object(w);
    }
    json_end_object(w);
}

emm_status emm_report_write(const char *path, const char *trace_name, const emm_machine *m,
                            uint64_t accesses, const emm_result *results, size_t n,
                            emm_error *err)
{
    size_t len = strlen(path);
    char *tmp = malloc(len + 16);
    FILE *f;
    int fd;
    json_writer w;
    bool bad;

    if (!tmp)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    memcpy(tmp, path, len);
    memcpy(tmp + len, ".tmp.XXXXXX", 12);
    fd = mkstemp(tmp);
    if (fd < 0) {
        emm_status st = emm_fail(err, EMM_ERR_IO, "%s: %s", path, strerror(errno));
        free(tmp);
        return st;
    }
    f = fdopen(fd, "w");
    if (!f) {
        emm_status st = emm_fail(err, EMM_ERR_IO, "%s: %s", path, strerror(errno));
        close(fd);
        unlink(tmp);
        free(tmp);
        return st;
    }
    json_init(&w, f, true);
    json_begin_object(&w);
    json_key(&w, "emm_report");
    json_u64(&w, 1);
    json_key(&w, "trace");
    json_string(&w, trace_name ? trace_name : "");
    json_key(&w, "accesses");
    json_u64(&w, accesses);
    json_key(&w, "machine");
    write_machine(&w, m);
    json_key(&w, "results");
    json_begin_array(&w);
    for (size_t i = 0; i < n; i++)
        write_result(&w, m, &results[i]);
    json_end_array(&w);
    json_end_object(&w);
    json_finish(&w);
    bad = json_failed(&w);
    if (fclose(f) != 0)
        bad = true;
    if (bad || rename(tmp, path) != 0) {
        emm_status st = emm_fail(err, EMM_ERR_IO, "%s: cannot write the report: %s", path,
                                 strerror(errno ? errno : EIO));
        unlink(tmp);
        free(tmp);
        return st;
    }
    free(tmp);
    return EMM_OK;
}
