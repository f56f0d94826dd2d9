/* Internal: the one model runner (docs/architecture.md). Every "run these
 * strategies over these records" in emm — the session, the decision's
 * sweeps, `emm table build`, `emm replay` — builds its models here and
 * feeds them here. Models are built in parallel (a layout of a large mesh
 * takes a while) and each batch of records goes through every model, the
 * models spread over the pool's threads; a model sees the batches in
 * order, on one thread at a time, so results never depend on the number of
 * threads. With one job everything runs on the calling thread. */
#ifndef EMM_SIM_RUNNER_H
#define EMM_SIM_RUNNER_H

#include "emm/sim.h"

typedef struct emm_runner emm_runner;

/* An empty runner whose work may use the threads `t` allows (NULL: the
 * online CPUs, no start hook). EMM_ERR_NOMEM when memory runs out. */
emm_status emm_runner_new(const emm_threads *t, emm_runner **out, emm_error *err);

/* The same, building its models' layouts in `share` (which it holds a
 * reference to; NULL: a share of its own), so that runners over one trace
 * can build each layout once (emm_model_share_keep). */
struct emm_model_share;
emm_status emm_runner_new_shared(const emm_threads *t, struct emm_model_share *share,
                                 emm_runner **out, emm_error *err);

/* Adds one model per strategy s[0..n) on machine m (validated) for a trace
 * described by `info`, built in parallel. A strategy whose model cannot be
 * built gets the reason in errs[i] (status != EMM_OK) and no model; the
 * others get errs[i].status == EMM_OK. errs may be NULL: then any such
 * failure fails the call. Running out of memory always fails the call
 * (with the runner unchanged). Models are numbered in the order added. */
emm_status emm_runner_add(emm_runner *r, const emm_machine *m, const emm_strategy *s, size_t n,
                          const emm_trace_info *info, emm_error *errs, emm_error *err);

/* Models added (built or not), and model i (NULL when it could not be
 * built). The runner owns them. */
size_t emm_runner_count(const emm_runner *r);
emm_model *emm_runner_model(const emm_runner *r, size_t i);

/* What model i's records cost, batch by batch (emm_model_run_costed):
 * called after each batch's run with the batch and cost[k] for recs[k],
 * on the thread that ran the model, one batch at a time, in order. */
typedef void (*emm_cost_fn)(void *ctx, const emm_trace_record *recs,
                            const emm_record_cost *cost, size_t n);

/* From now on model i (built) runs costed and reports to fn (NULL: back to
 * the plain run). The other models run as before. EMM_ERR_NOMEM when the
 * cost buffer cannot be had. */
emm_status emm_runner_costs(emm_runner *r, size_t i, emm_cost_fn fn, void *ctx, emm_error *err);

/* Stops running model i: later batches skip it, and its results stay as
 * they were (readable until the runner is freed). Retiring a model twice,
 * or one that could not be built, does nothing. */
void emm_runner_retire(emm_runner *r, size_t i);

/* Runs recs[0..n) through every model not retired. */
void emm_runner_run(emm_runner *r, const emm_trace_record *recs, size_t n);

/* Runs recs[0..n) through models idx[0..k) (built, not retired, not
 * costed), each on one thread at a time, in pieces of `chunk` records: a
 * model whose total exceeds `bound` at the end of a piece stops there (a
 * model's cycles never go down, so it ends above the bound). ran[j]: the
 * records model idx[j] ran, n when it ran them all. Deterministic: where a
 * model stops depends on its own cycles only. */
void emm_runner_run_bounded(emm_runner *r, const size_t *idx, size_t k,
                            const emm_trace_record *recs, size_t n, size_t chunk, uint64_t bound,
                            size_t *ran);

/* From now on emm_runner_run queues a copy of its batch and returns: the
 * models run the queued batches on threads of the runner's own (as many as
 * its threads allow, started as the pool's are), each model its batches in
 * order on one thread at a time, so a model's results are those of the
 * plain run; models do not wait for each other between batches, and the
 * caller goes on with its own work (the program, under a capture) while
 * they run. At most PIPE_MAX_RECORDS records are queued: a caller ahead of
 * the models waits. Every call that reads or changes the models
 * (emm_runner_model, _retire, _add, _costs, _run_bounded, _free) first
 * waits for the queue to empty, so what it sees is every batch run. With
 * one thread, or when no thread can be started, nothing changes.
 * EMM_ERR_NOMEM when memory runs out (the runner is as before). */
emm_status emm_runner_pipeline(emm_runner *r, emm_error *err);

/* Waits until the models have run every batch queued (nothing without a
 * pipeline): what the models' hooks wrote as they ran (emm_model_stalls'
 * counts) is complete after it. NULL is allowed. */
void emm_runner_sync(emm_runner *r);

/* Frees the runner and its models; NULL is allowed. */
void emm_runner_free(emm_runner *r);

#endif
