/* emm — replaying traces and writing reports (DESIGN.md "Traces", "The
 * command line"): the driver that feeds a trace file's records to one model
 * per strategy (include/emm/sim.h) and the JSON report of docs/report.md.
 * Part of the runtime layer: the models are the simulator's, the trace
 * reading and the report are built on top of them. */
#ifndef EMM_REPLAY_H
#define EMM_REPLAY_H

#include "emm/common.h"
#include "emm/sim.h"
#include "emm/strategy.h"

#ifdef __cplusplus
extern "C" {
#endif

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
typedef struct emm_replay_options {
    /* Threads simulating models; 0: the online CPUs. Never more than the
     * models. Each model runs on one thread at a time and sees every record
     * in order, so the results do not depend on `jobs`. */
    unsigned jobs;
    emm_progress_fn progress; /* may be NULL; called from the calling thread */
    void *progress_ctx;
    /* Nonzero: also fill each EMM strategy's per-cell DMA bytes
     * (emm_model_cells); the caller then releases every result with
     * emm_result_release. */
    int cells;
    /* Bytes the models may take together (0: emm_replay_default_memory).
     * Strategies that do not fit together run in further passes over the
     * trace, those of one layout and cell size in the same pass; the results
     * do not depend on it. */
    uint64_t memory;
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
