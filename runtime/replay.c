/* The record -> model pipeline behind `emm replay`: one streaming pass over
 * a trace feeds every model batch by batch, so memory stays the same for any
 * trace length, with the models split over threads when there are several
 * (emm replay --all); and the JSON report of docs/report.md. */
#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "error.h"
#include "json.h"
#include "machine.h"
#include "model.h"
#include "outfile.h"
#include "report.h"

/* Records per batch: large enough that the per-batch dispatch is noise,
 * small enough to stay in the host's L2 cache. */
#define REPLAY_BATCH 8192
/* Records per window when models run on several threads: the unit the
 * threads hand over, large enough that the hand-over is noise. */
#define REPLAY_WINDOW (4 * REPLAY_BATCH)
/* Records between progress reports. */
#define REPLAY_PROGRESS_EVERY (1u << 20)

/* The threads of one replay. The calling thread reads the trace into two
 * windows in turn; the workers take the models of a window one by one
 * (next[]), run each on the whole window and count the window done when
 * every worker has taken its last model there (left[]). A model runs on
 * one thread at a time and sees the windows in order: a worker that takes
 * model i for window w waits until model i has finished window w - 1
 * (model_done[i]). */
struct pool {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    emm_model **models;
    uint64_t *model_done; /* windows model i has finished */
    size_t nmodels;
    unsigned workers;
    emm_trace_record *buf[2];
    size_t len[2];
    size_t next[2];
    unsigned left[2];
    uint64_t published; /* windows handed to the workers */
    uint64_t finished;  /* windows every worker is done with */
    int eof;            /* no more windows */
};

static void *worker_main(void *arg)
{
    struct pool *p = arg;
    for (uint64_t w = 0;; w++) {
        unsigned slot = (unsigned)(w & 1);
        pthread_mutex_lock(&p->mu);
        while (p->published <= w && !p->eof)
            pthread_cond_wait(&p->cv, &p->mu);
        if (p->published <= w) {
            pthread_mutex_unlock(&p->mu);
            return NULL;
        }
        for (;;) {
            size_t i = p->next[slot]++;
            if (i >= p->nmodels)
                break;
            while (p->model_done[i] < w)
                pthread_cond_wait(&p->cv, &p->mu);
            pthread_mutex_unlock(&p->mu);
            emm_model_run(p->models[i], p->buf[slot], p->len[slot]);
            pthread_mutex_lock(&p->mu);
            p->model_done[i] = w + 1;
            pthread_cond_broadcast(&p->cv);
        }
        if (--p->left[slot] == 0) {
            p->finished = w + 1;
            pthread_cond_broadcast(&p->cv);
        }
        pthread_mutex_unlock(&p->mu);
    }
}

/* Reads up to cap records (fewer only at the end of the trace). */
static emm_status read_window(emm_trace_reader *r, emm_trace_record *buf, size_t cap,
                              size_t *got, emm_error *err)
{
    *got = 0;
    while (*got < cap) {
        size_t n = 0;
        emm_status st = emm_trace_read(r, buf + *got, cap - *got, &n, err);
        if (st != EMM_OK)
            return st;
        if (n == 0)
            break;
        *got += n;
    }
    return EMM_OK;
}

/* Feeds every record of r to the models on `workers` threads (>= 2); falls
 * back to the calling thread alone if no thread can be started. */
static emm_status run_threaded(emm_trace_reader *r, emm_model **models, size_t n,
                               unsigned workers, const emm_replay_options *opt, uint64_t *done,
                               const char *path, emm_error *err);

static emm_status run_inline(emm_trace_reader *r, emm_model **models, size_t n,
                             const emm_replay_options *opt, uint64_t *done, const char *path,
                             emm_error *err)
{
    const emm_trace_info *info = emm_trace_reader_info(r);
    emm_trace_record *buf = malloc(REPLAY_BATCH * sizeof *buf);
    uint64_t next_report = 0;
    emm_status st = EMM_OK;
    if (!buf)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    for (;;) {
        size_t got = 0;
        if ((st = emm_trace_read(r, buf, REPLAY_BATCH, &got, err)) != EMM_OK || got == 0)
            break;
        for (size_t i = 0; i < n; i++)
            emm_model_run(models[i], buf, got);
        *done += got;
        if (opt->progress && *done >= next_report) {
            opt->progress(opt->progress_ctx, *done, info->accesses);
            next_report = *done + REPLAY_PROGRESS_EVERY;
        }
    }
    free(buf);
    return st;
}

static emm_status run_threaded(emm_trace_reader *r, emm_model **models, size_t n,
                               unsigned workers, const emm_replay_options *opt, uint64_t *done,
                               const char *path, emm_error *err)
{
    const emm_trace_info *info = emm_trace_reader_info(r);
    struct pool p;
    pthread_t *tids = calloc(workers, sizeof *tids);
    uint64_t next_report = 0;
    unsigned started = 0;
    emm_status st = EMM_OK;

    memset(&p, 0, sizeof p);
    p.models = models;
    p.nmodels = n;
    p.model_done = calloc(n, sizeof *p.model_done);
    p.buf[0] = malloc(REPLAY_WINDOW * sizeof *p.buf[0]);
    p.buf[1] = malloc(REPLAY_WINDOW * sizeof *p.buf[1]);
    if (!tids || !p.model_done || !p.buf[0] || !p.buf[1]) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
        goto out;
    }
    pthread_mutex_init(&p.mu, NULL);
    pthread_cond_init(&p.cv, NULL);
    {
        /* Workers must not take the signals meant for the program. */
        sigset_t all, old;
        sigfillset(&all);
        pthread_sigmask(SIG_SETMASK, &all, &old);
        for (started = 0; started < workers; started++)
            if (pthread_create(&tids[started], NULL, worker_main, &p) != 0)
                break;
        pthread_sigmask(SIG_SETMASK, &old, NULL);
    }
    if (started == 0) {
        pthread_cond_destroy(&p.cv);
        pthread_mutex_destroy(&p.mu);
        st = run_inline(r, models, n, opt, done, path, err);
        goto out;
    }
    /* Read before taking the lock: only the workers' windows are shared. */
    p.workers = started;
    for (uint64_t w = 0;; w++) {
        unsigned slot = (unsigned)(w & 1);
        size_t got = 0;
        pthread_mutex_lock(&p.mu);
        while (p.finished + 2 <= w)
            pthread_cond_wait(&p.cv, &p.mu);
        pthread_mutex_unlock(&p.mu);
        st = read_window(r, p.buf[slot], REPLAY_WINDOW, &got, err);
        pthread_mutex_lock(&p.mu);
        if (st != EMM_OK || got == 0) {
            p.eof = 1;
            pthread_cond_broadcast(&p.cv);
            pthread_mutex_unlock(&p.mu);
            break;
        }
        p.len[slot] = got;
        p.next[slot] = 0;
        p.left[slot] = p.workers;
        p.published = w + 1;
        pthread_cond_broadcast(&p.cv);
        pthread_mutex_unlock(&p.mu);
        *done += got;
        if (opt->progress && *done >= next_report) {
            opt->progress(opt->progress_ctx, *done, info->accesses);
            next_report = *done + REPLAY_PROGRESS_EVERY;
        }
    }
    for (unsigned i = 0; i < started; i++)
        pthread_join(tids[i], NULL);
    pthread_cond_destroy(&p.cv);
    pthread_mutex_destroy(&p.mu);
out:
    free(tids);
    free(p.model_done);
    free(p.buf[0]);
    free(p.buf[1]);
    return st;
}

static unsigned online_cpus(void)
{
    long c = sysconf(_SC_NPROCESSORS_ONLN);
    return c > 0 ? (unsigned)c : 1;
}

emm_status emm_replay_ex(const char *path, const emm_machine *m, const emm_strategy *s,
                         size_t n, const emm_replay_options *opt, emm_result *results,
                         emm_error *skipped, uint64_t *accesses, emm_error *err)
{
    static const emm_replay_options defaults = {0, NULL, NULL, 0};
    emm_trace_reader *r = NULL;
    emm_model **models = NULL, **run = NULL;
    const emm_trace_info *info;
    uint64_t done = 0;
    size_t nrun = 0;
    unsigned jobs;
    emm_status st;

    if (!opt)
        opt = &defaults;
    if ((st = emm_machine_validate(m, err)) != EMM_OK)
        return st;
    if ((st = emm_trace_reader_open(path, &r, err)) != EMM_OK)
        return st;
    info = emm_trace_reader_info(r);
    models = calloc(n ? n : 1, sizeof *models);
    run = calloc(n ? n : 1, sizeof *run);
    if (!models || !run) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
        goto out;
    }
    for (size_t i = 0; i < n; i++) {
        emm_error e;
        st = emm_model_new(m, &s[i], info, &models[i], skipped ? &e : err);
        if (st == EMM_ERR_NOMEM || (st != EMM_OK && !skipped)) {
            if (skipped && err)
                *err = e;
            models[i] = NULL;
            goto out;
        }
        if (st != EMM_OK) {
            models[i] = NULL;
            skipped[i] = e;
        } else {
            if (skipped)
                emm_error_clear(&skipped[i]);
            run[nrun++] = models[i];
        }
    }
    jobs = opt->jobs ? opt->jobs : online_cpus();
    if (jobs > nrun)
        jobs = (unsigned)nrun;
    if (jobs >= 2)
        st = run_threaded(r, run, nrun, jobs, opt, &done, path, err);
    else
        st = run_inline(r, run, nrun, opt, &done, path, err);
    if (st != EMM_OK)
        goto out;
    if (opt->progress)
        opt->progress(opt->progress_ctx, done, info->accesses);
    for (size_t i = 0; i < n; i++) {
        if (models[i]) {
            emm_model_result(models[i], &results[i]);
            if (opt->cells && (st = emm_model_cells(models[i], &results[i], err)) != EMM_OK) {
                for (size_t j = 0; j <= i; j++)
                    emm_result_release(&results[j]);
                goto out;
            }
        } else {
            memset(&results[i], 0, sizeof results[i]);
            results[i].strategy = s[i];
        }
    }
    if (accesses)
        *accesses = done;
out:
    for (size_t i = 0; i < n && models; i++)
        emm_model_free(models[i]);
    free(models);
    free(run);
    emm_trace_reader_close(r);
    return st;
}

emm_status emm_replay(const char *path, const emm_machine *m, const emm_strategy *s,
                      size_t n, emm_result *results, uint64_t *accesses,
                      emm_progress_fn progress, void *progress_ctx, emm_error *err)
{
    emm_replay_options opt = {1, progress, progress_ctx, 0};
    return emm_replay_ex(path, m, s, n, &opt, results, NULL, accesses, err);
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

/* "cells": the layout's bounding box and count, then [x0, y0, x1, y1,
 * bytes] for each cell DMA moved anything for (the others add nothing to
 * a map of the traffic and would double the report on a sparse run). One
 * cell per line even in a pretty report: five numbers a line, not one. */
static void write_cells(json_writer *w, const emm_result *res)
{
    bool pretty = w->pretty;
    json_key(w, "cells");
    json_begin_object(w);
    json_key(w, "count");
    json_u64(w, res->cells.count);
    json_key(w, "bbox");
    json_begin_array(w);
    w->pretty = false;
    json_double(w, res->cells.lo[0]);
    json_double(w, res->cells.lo[1]);
    json_double(w, res->cells.hi[0]);
    json_double(w, res->cells.hi[1]);
    json_end_array(w);
    w->pretty = pretty;
    json_key(w, "rects");
    json_begin_array(w);
    for (uint32_t c = 0; c < res->cells.count; c++) {
        const emm_cell_dma *cell = &res->cells.cell[c];
        if (cell->bytes == 0)
            continue;
        json_begin_array(w);
        w->pretty = false;
        json_double(w, cell->lo[0]);
        json_double(w, cell->lo[1]);
        json_double(w, cell->hi[0]);
        json_double(w, cell->hi[1]);
        json_u64(w, cell->bytes);
        json_end_array(w);
        w->pretty = pretty;
    }
    json_end_array(w);
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
    if (res->has_emm) {
        const struct { const char *key; uint64_t v; } emm[] = {
            {"cell_changes", res->emm.cell_changes},
            {"demand_fetches", res->emm.demand_fetches},
            {"demand_bytes", res->emm.demand_bytes},
            {"prefetches", res->emm.prefetches},
            {"prefetch_bytes", res->emm.prefetch_bytes},
            {"useful_prefetches", res->emm.useful_prefetches},
            {"dropped_prefetches", res->emm.dropped_prefetches},
            {"filtered_prefetches", res->emm.filtered_prefetches},
            {"evictions", res->emm.evictions},
            {"other_accesses", res->emm.other_accesses},
            {"local_budget", res->emm.local_budget},
            {"lookup_bytes", res->emm.lookup_bytes},
        };
        json_key(w, "emm");
        json_begin_object(w);
        for (size_t i = 0; i < sizeof emm / sizeof emm[0]; i++) {
            json_key(w, emm[i].key);
            json_u64(w, emm[i].v);
        }
        json_end_object(w);
    }
    if (res->cells.cell)
        write_cells(w, res);
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
    return emm_report_write_extra(path, trace_name, m, accesses, results, n, NULL, NULL, err);
}

/* A strategy that did not run (emm_replay_ex's skipped[]). */
static void write_skipped(json_writer *w, const emm_strategy *s, const emm_error *e)
{
    char name[64];
    emm_strategy_format(s, name, sizeof name);
    json_begin_object(w);
    json_key(w, "strategy");
    json_string(w, name);
    json_key(w, "error");
    json_string(w, e->message);
    json_end_object(w);
}

static emm_status report_write(const char *path, const char *trace_name, const emm_machine *m,
                               uint64_t accesses, const emm_result *results,
                               const emm_error *skipped, size_t n, emm_report_extra_fn extra,
                               void *extra_ctx, emm_error *err)
{
    emm_outfile o;
    json_writer w;
    emm_status st = emm_outfile_open(&o, path, "the report", err);

    if (st != EMM_OK)
        return st;
    json_init(&w, o.f, true);
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
        if (skipped && skipped[i].status != EMM_OK)
            write_skipped(&w, &results[i].strategy, &skipped[i]);
        else
            write_result(&w, m, &results[i]);
    json_end_array(&w);
    if (extra)
        extra(&w, extra_ctx);
    json_end_object(&w);
    json_finish(&w);
    if (w.failed) { /* nesting too deep; a failed write is the commit's to say */
        emm_outfile_abort(&o);
        return emm_fail(err, EMM_ERR_IO, "%s: cannot write the report: nested too deep", path);
    }
    return emm_outfile_commit(&o, "the report", err);
}

emm_status emm_report_write_extra(const char *path, const char *trace_name, const emm_machine *m,
                                  uint64_t accesses, const emm_result *results, size_t n,
                                  emm_report_extra_fn extra, void *extra_ctx, emm_error *err)
{
    return report_write(path, trace_name, m, accesses, results, NULL, n, extra, extra_ctx, err);
}

emm_status emm_report_write_ex(const char *path, const char *trace_name, const emm_machine *m,
                               uint64_t accesses, const emm_result *results,
                               const emm_error *skipped, size_t n, emm_error *err)
{
    return report_write(path, trace_name, m, accesses, results, skipped, n, NULL, NULL, err);
}
