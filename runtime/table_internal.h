/* Internal: the decision of runtime/table.c with its layouts built in a
 * share the caller keeps (simulator/share.h), so that a session builds each
 * layout of its mesh once — for the decision's sweeps, its own models and
 * its probes' decisions — instead of once per sweep, and a cache of what
 * those decisions share (decide_cache). The public
 * emm_decide_features and emm_sweep_records are these with a share of
 * their own. */
#ifndef EMM_RUNTIME_TABLE_INTERNAL_H
#define EMM_RUNTIME_TABLE_INTERNAL_H

#include <stdbool.h>
#include <stdint.h>

#include "emm/table.h"
#include "share.h"

/* emm_sweep_records with the share's layouts; offered_only: the strategies
 * the machine does not offer are not simulated (ran = 0), for a caller
 * that reads only the offered ones. */
emm_status sweep_records_shared(const emm_machine *m, const emm_trace_info *info,
                                const emm_trace_record *recs, size_t n,
                                const emm_threads *threads, emm_model_share *share,
                                bool offered_only, emm_sweep **out, emm_error *err);

/* sweep_records_shared over the offered strategies, bounded: what the
 * pattern check reads of a long run is its two fewest cycles (the pick and
 * the runner-up, W breaking near-ties) and the reference cache's, so once
 * those are known a strategy stops as soon as its cycles exceed the
 * larger of the two by more than a thousandth — it ends there or above
 * (cycles never go down). The two run first: the two fewest after the
 * first sixteenth of the records; then the others, in parallel, each on
 * its own. *partial (count flags, malloc'ed, free it): 1 where the result
 * is such a lower bound. Exact for every strategy within that margin of
 * the second fewest, the fewest and the cache; a caller that ranks by more
 * than the cycles must check that no stopped strategy could have ranked
 * first or second (check_pattern does, and sweeps again in full if so). */
emm_status sweep_records_bounded(const emm_machine *m, const emm_trace_info *info,
                                 const emm_trace_record *recs, size_t n,
                                 const emm_threads *threads, emm_model_share *share,
                                 emm_sweep **out, uint8_t **partial, emm_error *err);

/* A leading sweep's price (the window follows an index-order pass the
 * run pays too): each strategy's cycles over the sweep (indexed as the
 * window's sweep; INFINITY where it could not run) and the rest of the run
 * in cycles, priced at the window's best: a strategy's score, a ratio to
 * the best, times rest, plus its sweep's cycles. */
struct lead_price {
    const double *cycles;
    double rest;
};

/* Whether the pattern check's pick and second (check_pattern's ranking of
 * S and W, priced with lp when it is not NULL) stand on a bounded S: none
 * of them, S's best or the cache was stopped early, and every strategy that
 * was scores (on its lower bound) above score2. partial NULL: all exact, so
 * they stand. */
int check_bounds_hold(const emm_machine *m, const emm_sweep *S, const uint8_t *partial,
                      const emm_sweep *W, const struct lead_price *lp, size_t pick,
                      size_t second, double score2);

/* What a session's decisions over one trace share (runtime/table.c): the
 * geometry as a mesh, and each canonical traversal's profile and sweep,
 * which depend on the traversal, the mesh, the arrays and the machine but
 * not on the window (its start aside, for a region) — the window's
 * decision and each phase's compute them once. A cache serves the trace
 * `info` of the first decision it is given to; NULL: nothing is kept. */
typedef struct decide_cache decide_cache;
decide_cache *decide_cache_new(void);
void decide_cache_free(decide_cache *c);

emm_status decide_features_shared(const emm_table *t, const emm_machine *m,
                                  const emm_trace_info *info, const emm_trace_record *recs,
                                  size_t n, const double f[EMM_FEATURES], size_t accesses,
                                  const char *name, const emm_decide_options *opt,
                                  emm_model_share *share, decide_cache *cache,
                                  emm_window_decision *out, emm_error *err);

#endif
