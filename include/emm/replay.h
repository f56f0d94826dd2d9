/* emm — replaying traces and writing reports (docs/trace-format.md;
 * docs/design.md "The command line"): the driver that feeds a trace file's records to one
 * model per strategy (include/emm/sim.h) and the JSON report of docs/report.md. Part of
 * the runtime layer: the models are the simulator's, the trace reading and the report are
 * built on top of them. */
#ifndef EMM_REPLAY_H
#define EMM_REPLAY_H

#include "emm/common.h"
#include "emm/config.h"
#include "emm/sim.h"
#include "emm/strategy.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- timelines -------------------------------------------------------------- */

/* A strategy's simulated run as Chrome/Perfetto trace-event JSON
 * (docs/report.md "Timelines"): one process, a track (thread) for the core
 * — its DMA stalls and its entries into layout cells — one per DMA channel
 * with every transfer as a complete event, and one for phases. At most
 * `max_events` events are written (EMM_TIMELINE_MAX_EVENTS by default); the
 * file's metadata ("otherData") says how many were left out. The file is
 * written whole or not at all, streamed (memory does not grow with it). */
typedef struct emm_timeline emm_timeline;

/* Starts a timeline of strategy s on machine m at `path`; max_events 0 is
 * EMM_TIMELINE_MAX_EVENTS. */
EMM_API emm_status emm_timeline_open(const char *path, const emm_machine *m,
                                     const emm_strategy *s, uint64_t max_events,
                                     emm_timeline **out, emm_error *err);
/* Records what `model` (of the timeline's strategy) does from now on, until
 * the timeline is closed. Returns 0 for a model with nothing to show
 * (direct reads, the cache: no DMA engine), which the file then says. */
EMM_API int emm_timeline_watch(emm_timeline *t, emm_model *model);
/* A phase of the run: `name` from cycle `start` to `end`. */
EMM_API void emm_timeline_phase(emm_timeline *t, const char *name, uint64_t start, uint64_t end);
/* Ends the run at cycle `end`, writes the metadata, and renames the file
 * into place; frees t, and stops the watched model's reports, whatever the
 * outcome. */
EMM_API emm_status emm_timeline_close(emm_timeline *t, emm_model *watched, uint64_t end,
                                      emm_error *err);
/* Drops an unfinished timeline (no file is left); NULL is allowed. */
EMM_API void emm_timeline_abort(emm_timeline *t, emm_model *watched);

/* ---- replay ---------------------------------------------------------------- */

/* Called now and then during emm_replay with the records done so far. */
typedef void (*emm_progress_fn)(void *ctx, uint64_t done, uint64_t total);

/* Simulates every strategy of s[0..n) over the trace at `path` in one
 * streaming pass (memory does not grow with the trace) and fills
 * results[0..n). *accesses (when not NULL) receives the records read.
 * `progress` may be NULL. */
EMM_API emm_status emm_replay(const char *path, const emm_machine *m, const emm_strategy *s,
                              size_t n, emm_result *results, uint64_t *accesses,
                              emm_progress_fn progress, void *progress_ctx, emm_error *err);

/* How emm_replay_ex runs; zero-initialise, then set what you need. */
enum { EMM_REPLAY_CELLS_NONE, EMM_REPLAY_CELLS_ALL, EMM_REPLAY_CELLS_FASTEST };

typedef struct emm_replay_options {
    /* Threads simulating models; 0: the online CPUs. Never more than the
     * models. Each model runs on one thread at a time and sees every record
     * in order, so the results do not depend on `jobs`. */
    unsigned jobs;
    emm_progress_fn progress; /* may be NULL; called from the calling thread */
    void *progress_ctx;
    /* EMM_REPLAY_CELLS_ALL: also fill each EMM strategy's per-cell DMA
     * bytes (emm_model_cells); EMM_REPLAY_CELLS_FASTEST: only the fastest
     * EMM strategy's (a sweep's per-cell data for every strategy grows with
     * strategies x cells: gigabytes on a mesh of millions of faces). The
     * caller then releases every result with emm_result_release. */
    int cells;
    /* Bytes the models may take together (0: emm_replay_default_memory).
     * Strategies that do not fit together run in further passes over the
     * trace, those of one layout and cell size in the same pass; the results
     * do not depend on it. */
    uint64_t memory;
    /* When not NULL: the timeline records the first strategy's model. */
    emm_timeline *timeline;
    /* When not NULL: the first strategy's model runs costed
     * (emm_model_run_costed) and reports each batch's records and their
     * costs to cost_fn, in order, from the thread that ran it. */
    void (*cost_fn)(void *ctx, const emm_trace_record *recs, const emm_record_cost *cost,
                    size_t n);
    void *cost_ctx;
} emm_replay_options;

/* Half the physical memory, at most 4 GiB. */
EMM_API uint64_t emm_replay_default_memory(void);

/* emm_replay with options (opt may be NULL: defaults). The trace is read
 * once per pass (one, unless the models would exceed opt->memory); its
 * records go to every model in windows, the models split over opt->jobs
 * threads. With `skipped` NULL a strategy whose model cannot be
 * built fails the replay, as in emm_replay. With `skipped` (n entries), such
 * a strategy gets its error in skipped[i] (status != EMM_OK) and a result
 * with only the strategy set, and the others go on; skipped[i].status is
 * EMM_OK for the strategies that ran. */
EMM_API emm_status emm_replay_ex(const char *path, const emm_machine *m, const emm_strategy *s,
                                 size_t n, const emm_replay_options *opt, emm_result *results,
                                 emm_error *skipped, uint64_t *accesses, emm_error *err);

/* ---- the run's contest (docs/profile.md "The contest") ------------------- */

typedef struct emm_contest_result {
    emm_result answer;    /* the fastest finalist over the whole trace */
    emm_result runner_up; /* the next (valid when has_runner_up) */
    int has_runner_up;
    emm_result predicted; /* the prediction over the whole trace (valid when has_predicted) */
    int has_predicted;
    size_t entrants;      /* candidates that entered */
    size_t finalists;     /* those that ran to the end */
    size_t rounds;        /* halvings made */
    uint64_t accesses;    /* records run */
} emm_contest_result;

/* The contest a session runs when it sees the whole run, over the trace at
 * `path`: the prediction and every other candidate machine m offers (the
 * standard sweep) from the trace's first record; when the records run
 * reach lead + 2·unit, lead + 4·unit, ... (lead: the records of the
 * window's leading sweep; unit: the window's other records) the slower
 * half is dropped, never below `finalists` (at least 1); the fastest
 * finalist is the answer. A candidate that cannot run on the trace does
 * not enter. `threads` may be NULL (the online CPUs). On the trace a
 * session wrote, with its window's lead and unit, the answer is the
 * session's. */
EMM_API emm_status emm_contest_trace(const char *path, const emm_machine *m,
                                     const emm_strategy *predicted, uint64_t lead, uint64_t unit,
                                     unsigned finalists, const emm_threads *threads,
                                     emm_contest_result *out, emm_error *err);

/* Writes the JSON report of docs/report.md to `path` (whole or not at all).
 * A result with cells (emm_model_cells) gets its "cells" key. */
EMM_API emm_status emm_report_write(const char *path, const char *trace_name,
                                    const emm_machine *m, uint64_t accesses,
                                    const emm_result *results, size_t n, emm_error *err);
/* The same, where skipped (may be NULL) marks strategies that did not run,
 * as emm_replay_ex fills it: they are written as {"strategy": ..., "error": ...}. */
EMM_API emm_status emm_report_write_ex(const char *path, const char *trace_name,
                                       const emm_machine *m, uint64_t accesses,
                                       const emm_result *results, const emm_error *skipped,
                                       size_t n, emm_error *err);

#ifdef __cplusplus
}
#endif
#endif
