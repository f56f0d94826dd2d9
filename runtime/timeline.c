/* Timelines (include/emm/replay.h): a model's observer (emm_model_observe)
 * streams the simulated machine's events as Chrome's trace-event JSON,
 * which Perfetto's UI and chrome://tracing open. Times are the model's
 * cycles turned into microseconds at the machine's clock. Tracks: the core
 * (tid 1: DMA stalls as complete events, cell entries as instant events),
 * DMA channel k (tid 2 + k: every transfer as a complete event), phases
 * (the last tid). The writer is core's JSON writer on core's whole-or-
 * nothing output file. */
#include "emm/replay.h"

#include <inttypes.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "json.h"
#include "machine.h"
#include "outfile.h"

struct emm_timeline {
    emm_outfile out;
    json_writer w;
    char strategy[64];
    double us_per_cycle;
    uint32_t channels;
    uint64_t max_events, events, dropped;
    uint64_t transfers, stalls, entries, phases;
    bool watched;  /* a model with events reports here */
    bool watching; /* emm_timeline_watch was called */
};

/* Microseconds, to 0.1 ns. */
static void put_time(emm_timeline *t, const char *key, uint64_t cycles)
{
    json_key(&t->w, key);
    json_fixed(&t->w, (double)cycles * t->us_per_cycle, 4);
}

/* Starts an event, or says no when the cap is reached. */
static bool begin_event(emm_timeline *t, const char *name, const char *cat, const char *ph,
                        uint32_t tid)
{
    if (t->events == t->max_events) {
        t->dropped++;
        return false;
    }
    t->events++;
    json_begin_object(&t->w);
    json_key(&t->w, "name");
    json_string(&t->w, name);
    json_key(&t->w, "cat");
    json_string(&t->w, cat);
    json_key(&t->w, "ph");
    json_string(&t->w, ph);
    json_key(&t->w, "pid");
    json_u64(&t->w, 1);
    json_key(&t->w, "tid");
    json_u64(&t->w, tid);
    return true;
}

static void metadata(emm_timeline *t, const char *what, uint32_t tid, const char *name,
                     uint64_t sort)
{
    json_begin_object(&t->w);
    json_key(&t->w, "name");
    json_string(&t->w, what);
    json_key(&t->w, "ph");
    json_string(&t->w, "M");
    json_key(&t->w, "pid");
    json_u64(&t->w, 1);
    if (tid) {
        json_key(&t->w, "tid");
        json_u64(&t->w, tid);
    }
    json_key(&t->w, "args");
    json_begin_object(&t->w);
    if (name) {
        json_key(&t->w, "name");
        json_string(&t->w, name);
    } else {
        json_key(&t->w, "sort_index");
        json_u64(&t->w, sort);
    }
    json_end_object(&t->w);
    json_end_object(&t->w);
}

static void on_transfer(void *ctx, uint32_t channel, uint64_t start, uint64_t end,
                        uint64_t bytes, emm_transfer_kind kind, uint64_t cell)
{
    emm_timeline *t = ctx;
    static const char *const cats[] = {"demand", "prefetch", "table page"};
    char name[48];
    t->transfers++;
    if (kind == EMM_TRANSFER_TABLE_PAGE)
        snprintf(name, sizeof name, "table page %" PRIu64, cell);
    else
        snprintf(name, sizeof name, "cell %" PRIu64, cell);
    if (!begin_event(t, name, cats[kind], "X", 2 + channel))
        return;
    put_time(t, "ts", start);
    put_time(t, "dur", end - start);
    json_key(&t->w, "args");
    json_begin_object(&t->w);
    json_key(&t->w, "bytes");
    json_u64(&t->w, bytes);
    json_key(&t->w, kind == EMM_TRANSFER_TABLE_PAGE ? "page" : "cell");
    json_u64(&t->w, cell);
    json_key(&t->w, "cycles");
    json_u64(&t->w, end - start);
    json_end_object(&t->w);
    json_end_object(&t->w);
}

static void on_stall(void *ctx, uint64_t start, uint64_t cycles)
{
    emm_timeline *t = ctx;
    t->stalls++;
    if (!begin_event(t, "DMA stall", "stall", "X", 1))
        return;
    put_time(t, "ts", start);
    put_time(t, "dur", cycles);
    json_key(&t->w, "args");
    json_begin_object(&t->w);
    json_key(&t->w, "cycles");
    json_u64(&t->w, cycles);
    json_end_object(&t->w);
    json_end_object(&t->w);
}

static void on_enter(void *ctx, uint64_t time, uint64_t cell)
{
    emm_timeline *t = ctx;
    char name[48];
    t->entries++;
    snprintf(name, sizeof name, "enter cell %" PRIu64, cell);
    if (!begin_event(t, name, "cell", "i", 1))
        return;
    json_key(&t->w, "s");
    json_string(&t->w, "t");
    put_time(t, "ts", time);
    json_key(&t->w, "args");
    json_begin_object(&t->w);
    json_key(&t->w, "cell");
    json_u64(&t->w, cell);
    json_end_object(&t->w);
    json_end_object(&t->w);
}

emm_status emm_timeline_open(const char *path, const emm_machine *m, const emm_strategy *s,
                             uint64_t max_events, emm_timeline **out, emm_error *err)
{
    *out = NULL;
    emm_timeline *t = calloc(1, sizeof *t);
    if (!t)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    emm_status st = emm_outfile_open(&t->out, path, "the timeline", err);
    if (st != EMM_OK) {
        free(t);
        return st;
    }
    emm_strategy_format(s, t->strategy, sizeof t->strategy);
    t->us_per_cycle = 1.0 / (double)m->p.clock_mhz;
    t->channels = (uint32_t)m->p.dma_channels;
    t->max_events = max_events ? max_events : EMM_TIMELINE_MAX_EVENTS;
    json_init(&t->w, t->out.f, false);
    json_begin_object(&t->w);
    json_key(&t->w, "traceEvents");
    json_begin_array(&t->w);
    /* The tracks' names and order (metadata events, not counted). */
    char name[96];
    snprintf(name, sizeof name, "emm: %s", t->strategy);
    metadata(t, "process_name", 0, name, 0);
    metadata(t, "thread_name", 1, "core", 0);
    metadata(t, "thread_sort_index", 1, NULL, 1);
    for (uint32_t c = 0; c < t->channels; c++) {
        snprintf(name, sizeof name, "DMA channel %u", c);
        metadata(t, "thread_name", 2 + c, name, 0);
        metadata(t, "thread_sort_index", 2 + c, NULL, 2 + c);
    }
    metadata(t, "thread_name", 2 + t->channels, "phases", 0);
    metadata(t, "thread_sort_index", 2 + t->channels, NULL, 2 + t->channels);
    *out = t;
    return EMM_OK;
}

int emm_timeline_watch(emm_timeline *t, emm_model *model)
{
    static const emm_observer obs = {on_transfer, on_stall, on_enter};
    t->watching = true;
    t->watched = emm_model_observe(model, &obs, t) != 0;
    return t->watched;
}

void emm_timeline_phase(emm_timeline *t, const char *name, uint64_t start, uint64_t end)
{
    t->phases++;
    if (!begin_event(t, name, "phase", "X", 2 + t->channels))
        return;
    put_time(t, "ts", start);
    put_time(t, "dur", end > start ? end - start : 0);
    json_end_object(&t->w);
}

emm_status emm_timeline_close(emm_timeline *t, emm_model *watched, uint64_t end, emm_error *err)
{
    if (watched)
        emm_model_observe(watched, NULL, NULL);
    json_end_array(&t->w);
    json_key(&t->w, "displayTimeUnit");
    json_string(&t->w, "ns");
    json_key(&t->w, "otherData");
    json_begin_object(&t->w);
    json_key(&t->w, "strategy");
    json_string(&t->w, t->strategy);
    json_key(&t->w, "time_unit");
    json_string(&t->w, "microseconds of the simulated machine's clock");
    json_key(&t->w, "clock_mhz");
    json_fixed(&t->w, 1.0 / t->us_per_cycle, 0);
    json_key(&t->w, "cycles");
    json_u64(&t->w, end);
    json_key(&t->w, "dma_channels");
    json_u64(&t->w, t->channels);
    json_key(&t->w, "transfers");
    json_u64(&t->w, t->transfers);
    json_key(&t->w, "stalls");
    json_u64(&t->w, t->stalls);
    json_key(&t->w, "cell_entries");
    json_u64(&t->w, t->entries);
    json_key(&t->w, "event_cap");
    json_u64(&t->w, t->max_events);
    json_key(&t->w, "events");
    json_u64(&t->w, t->events);
    json_key(&t->w, "capped");
    json_bool(&t->w, t->dropped > 0);
    json_key(&t->w, "dropped_events");
    json_u64(&t->w, t->dropped);
    json_key(&t->w, "note");
    if (t->watching && !t->watched)
        json_string(&t->w, "this strategy has no DMA engine: no transfers, stalls or cells");
    else if (t->dropped)
        json_string(&t->w, "the event cap was hit: the events after the first event_cap are "
                           "left out");
    else
        json_string(&t->w, "every event of the run is here");
    json_end_object(&t->w);
    json_end_object(&t->w);
    json_finish(&t->w);
    emm_status st;
    if (json_failed(&t->w)) {
        st = emm_fail(err, EMM_ERR_IO, "%s: cannot write the timeline", t->out.path);
        emm_outfile_abort(&t->out);
    } else {
        st = emm_outfile_commit(&t->out, "the timeline", err);
    }
    free(t);
    return st;
}

void emm_timeline_abort(emm_timeline *t, emm_model *watched)
{
    if (!t)
        return;
    if (watched)
        emm_model_observe(watched, NULL, NULL);
    emm_outfile_abort(&t->out);
    free(t);
}
