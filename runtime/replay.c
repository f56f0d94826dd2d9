/* The replay driver behind `emm replay`: one streaming pass over a trace
 * feeds every model batch by batch through the model runner
 * (simulator/runner.h), so memory stays the same for any trace length; and
 * the JSON report of docs/report.md. */
#include <errno.h>
#include <stdbool.h>
#include <stdint.h>
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
#include "runner.h"

/* Records per batch: the unit the runner hands to its threads, large
 * enough that the hand-over and the per-batch dispatch are noise, small
 * enough to stay in the host's L2 cache. */
#define REPLAY_BATCH 32768
/* Records between progress reports. */
#define REPLAY_PROGRESS_EVERY (1u << 20)

/* The memory a strategy's model needs on a mesh of nt triangles, roughly:
 * an EMM strategy's layout (about 70 bytes per triangle and 100 per cell,
 * shared by the strategies of the same layout and cell size) and its
 * per-cell state; the cache's lines. Only used to split a sweep into
 * passes that fit the memory budget. */
static uint64_t layout_bytes(uint64_t nt, uint32_t cell)
{
    return 70 * nt + 100 * (nt / (cell ? cell : 1) + 1);
}

static uint64_t model_bytes(const emm_strategy *s, uint64_t nt)
{
    if (s->kind == EMM_STRATEGY_EMM)
        return 30 * (nt / s->cell + 1);
    if (s->kind == EMM_STRATEGY_CACHE && s->layout != EMM_LAYOUT_ORIGINAL)
        return 40 * nt + (1u << 20);
    return 1u << 20;
}

/* The pass of each strategy: strategies of one layout and cell size share
 * a pass (and the layout); a pass is closed when the next group would take
 * it past `budget`. Returns the number of passes. */
static unsigned plan_passes(const emm_strategy *s, size_t n, uint64_t nt, uint64_t budget,
                            unsigned *pass)
{
    unsigned passes = 1;
    uint64_t used = 0;
    for (size_t i = 0; i < n; i++)
        pass[i] = UINT32_MAX;
    for (size_t i = 0; i < n; i++) {
        if (pass[i] != UINT32_MAX)
            continue;
        /* The group of strategies that share s[i]'s layout. */
        uint64_t need = model_bytes(&s[i], nt);
        bool layout = s[i].kind == EMM_STRATEGY_EMM ||
                      (s[i].kind == EMM_STRATEGY_CACHE && s[i].layout != EMM_LAYOUT_ORIGINAL);
        if (layout)
            need += layout_bytes(nt, s[i].cell ? s[i].cell : EMM_DEFAULT_CELL);
        for (size_t j = i + 1; j < n; j++)
            if (s[j].kind == EMM_STRATEGY_EMM && s[i].kind == EMM_STRATEGY_EMM &&
                s[j].layout == s[i].layout && s[j].cell == s[i].cell)
                need += model_bytes(&s[j], nt);
        if (used > 0 && used + need > budget) {
            passes++;
            used = 0;
        }
        used += need;
        pass[i] = passes - 1;
        for (size_t j = i + 1; j < n; j++)
            if (s[j].kind == EMM_STRATEGY_EMM && s[i].kind == EMM_STRATEGY_EMM &&
                s[j].layout == s[i].layout && s[j].cell == s[i].cell)
                pass[j] = passes - 1;
    }
    return passes;
}

/* One pass: the strategies s[k] with pass[k] == p, over every record. */
static emm_status replay_pass(emm_trace_reader *r, const emm_machine *m, const emm_strategy *s,
                              size_t n, const unsigned *pass, unsigned p, unsigned passes,
                              const emm_replay_options *opt, emm_trace_record *buf,
                              emm_result *results, emm_error *skipped, uint64_t *done,
                              size_t *fastest, const char *path, emm_error *err)
{
    const emm_trace_info *info = emm_trace_reader_info(r);
    emm_threads threads = {opt->jobs, NULL, NULL};
    emm_runner *run = NULL;
    size_t k = 0, *index = malloc((n ? n : 1) * sizeof *index);
    emm_strategy *mine = malloc((n ? n : 1) * sizeof *mine);
    emm_error *errs = skipped ? calloc(n ? n : 1, sizeof *errs) : NULL;
    uint64_t next_report = 0, total = info->accesses * passes;
    emm_status st = EMM_OK;
    if (!index || !mine || (skipped && !errs)) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
        goto out;
    }
    for (size_t i = 0; i < n; i++)
        if (pass[i] == p) {
            index[k] = i;
            mine[k++] = s[i];
        }
    if ((st = emm_trace_rewind(r, err)) != EMM_OK ||
        (st = emm_runner_new(&threads, &run, err)) != EMM_OK ||
        (st = emm_runner_add(run, m, mine, k, info, errs, err)) != EMM_OK)
        goto out;
    /* The first strategy is the one a timeline shows and whose records
     * are costed (it is always in the first pass). */
    if (k > 0 && index[0] == 0 && emm_runner_model(run, 0)) {
        if (opt->timeline)
            emm_timeline_watch(opt->timeline, emm_runner_model(run, 0));
        if (opt->cost_fn &&
            (st = emm_runner_costs(run, 0, opt->cost_fn, opt->cost_ctx, err)) != EMM_OK)
            goto out;
    }
    for (;;) {
        size_t got = 0;
        /* A batch is filled whole (but at the end), so the models always see
         * the same batches. */
        while (got < REPLAY_BATCH) {
            size_t c = 0;
            if ((st = emm_trace_read(r, buf + got, REPLAY_BATCH - got, &c, err)) != EMM_OK)
                goto out;
            if (c == 0)
                break;
            got += c;
        }
        if (got == 0)
            break;
        emm_runner_run(run, buf, got);
        *done += got;
        if (opt->progress && *done >= next_report) {
            opt->progress(opt->progress_ctx, *done, total);
            next_report = *done + REPLAY_PROGRESS_EVERY;
        }
    }
    for (size_t j = 0; j < k; j++) {
        size_t i = index[j];
        emm_model *model = emm_runner_model(run, j);
        if (skipped)
            skipped[i] = errs[j];
        memset(&results[i], 0, sizeof results[i]);
        results[i].strategy = s[i];
        if (!model)
            continue;
        emm_model_result(model, &results[i]);
        bool cells = opt->cells == EMM_REPLAY_CELLS_ALL;
        if (opt->cells == EMM_REPLAY_CELLS_FASTEST && results[i].strategy.kind == EMM_STRATEGY_EMM &&
            (*fastest == SIZE_MAX || results[i].total < results[*fastest].total)) {
            if (*fastest != SIZE_MAX)
                emm_result_release(&results[*fastest]);
            *fastest = i;
            cells = true;
        }
        if (cells && (st = emm_model_cells(model, &results[i], err)) != EMM_OK)
            goto out;
    }
out:
    if (opt->timeline && k > 0 && index[0] == 0 && emm_runner_model(run, 0))
        emm_model_observe(emm_runner_model(run, 0), NULL, NULL);
    emm_runner_free(run);
    free(index);
    free(mine);
    free(errs);
    return st;
}

uint64_t emm_replay_default_memory(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    uint64_t half = pages > 0 && size > 0 ? (uint64_t)pages * (uint64_t)size / 2 : UINT64_MAX;
    uint64_t cap = (uint64_t)4 << 30;
    return half < cap ? half : cap;
}

emm_status emm_replay_ex(const char *path, const emm_machine *m, const emm_strategy *s,
                         size_t n, const emm_replay_options *opt, emm_result *results,
                         emm_error *skipped, uint64_t *accesses, emm_error *err)
{
    static const emm_replay_options defaults = {0, NULL, NULL, 0, 0, NULL, NULL, NULL};
    emm_trace_reader *r = NULL;
    emm_trace_record *buf = NULL;
    unsigned *pass = NULL;
    uint64_t done = 0;
    size_t fastest = SIZE_MAX; /* EMM_REPLAY_CELLS_FASTEST: the result holding cells */
    emm_status st;

    if (!opt)
        opt = &defaults;
    if ((st = emm_machine_validate(m, err)) != EMM_OK)
        return st;
    if ((st = emm_trace_reader_open(path, &r, err)) != EMM_OK)
        return st;
    const emm_trace_info *info = emm_trace_reader_info(r);
    buf = malloc(REPLAY_BATCH * sizeof *buf);
    pass = malloc((n ? n : 1) * sizeof *pass);
    if (!buf || !pass) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
        goto out;
    }
    memset(results, 0, n * sizeof *results);
    /* The sweep in passes over the trace when its models would not fit the
     * memory budget together; the results do not depend on the passes. */
    unsigned passes = plan_passes(s, n, info->geometry.nt,
                                  opt->memory ? opt->memory : emm_replay_default_memory(), pass);
    for (unsigned p = 0; p < passes && st == EMM_OK; p++)
        st = replay_pass(r, m, s, n, pass, p, passes, opt, buf, results, skipped, &done, &fastest,
                         path, err);
    if (st != EMM_OK) {
        for (size_t i = 0; i < n; i++)
            emm_result_release(&results[i]);
        goto out;
    }
    if (opt->progress)
        opt->progress(opt->progress_ctx, done, done);
    if (accesses)
        *accesses = done / passes;
out:
    free(buf);
    free(pass);
    emm_trace_reader_close(r);
    return st;
}

emm_status emm_replay(const char *path, const emm_machine *m, const emm_strategy *s,
                      size_t n, emm_result *results, uint64_t *accesses,
                      emm_progress_fn progress, void *progress_ctx, emm_error *err)
{
    emm_replay_options opt = {1, progress, progress_ctx, 0, 0, NULL, NULL, NULL};
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
/* A box as its low corner, then its high corner (x0, y0, x1, y1 in the plane). */
static void write_box(json_writer *w, uint32_t dims, const double *lo, const double *hi)
{
    for (uint32_t k = 0; k < dims; k++)
        json_double(w, lo[k]);
    for (uint32_t k = 0; k < dims; k++)
        json_double(w, hi[k]);
}

static void write_cells(json_writer *w, const emm_result *res)
{
    bool pretty = w->pretty;
    uint32_t dims = res->cells.dims;
    json_key(w, "cells");
    json_begin_object(w);
    json_key(w, "count");
    json_u64(w, res->cells.count);
    json_key(w, "bbox");
    json_begin_array(w);
    w->pretty = false;
    write_box(w, dims, res->cells.lo, res->cells.hi);
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
        write_box(w, dims, cell->lo, cell->hi);
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
            {"lookups", res->emm.lookups},
            {"pointer_accesses", res->emm.pointer_accesses},
            {"same_record", res->emm.same_record},
            {"lookup_paged", (uint64_t)res->emm.lookup_paged},
            {"lookup_pages", res->emm.lookup_pages},
            {"lookup_page_bytes", res->emm.lookup_page_bytes},
            {"refetches", res->emm.refetches},
            {"refetch_bytes", res->emm.refetch_bytes},
            {"unused_prefetches", res->emm.unused_prefetches},
            {"prefetch_checks", res->emm.prefetch_checks},
            {"resident_cells", res->emm.resident_cells},
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

static emm_status report_write(const char *path, const char *trace_name, const emm_machine *m,
                               uint64_t accesses, const emm_result *results,
                               const emm_error *skipped, size_t n, emm_report_extra_fn extra,
                               void *extra_ctx, emm_error *err);

emm_status emm_report_write(const char *path, const char *trace_name, const emm_machine *m,
                            uint64_t accesses, const emm_result *results, size_t n,
                            emm_error *err)
{
    return report_write(path, trace_name, m, accesses, results, NULL, n, NULL, NULL, err);
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
                                  uint64_t accesses, const emm_result *results,
                                  const emm_error *skipped, size_t n, emm_report_extra_fn extra,
                                  void *extra_ctx, emm_error *err)
{
    return report_write(path, trace_name, m, accesses, results, skipped, n, extra, extra_ctx, err);
}

emm_status emm_report_write_ex(const char *path, const char *trace_name, const emm_machine *m,
                               uint64_t accesses, const emm_result *results,
                               const emm_error *skipped, size_t n, emm_error *err)
{
    return report_write(path, trace_name, m, accesses, results, skipped, n, NULL, NULL, err);
}
