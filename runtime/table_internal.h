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

#include "emm/table.h"
#include "share.h"

/* emm_sweep_records with the share's layouts; offered_only: the strategies
 * the machine does not offer are not simulated (ran = 0), for a caller
 * that reads only the offered ones. */
emm_status sweep_records_shared(const emm_machine *m, const emm_trace_info *info,
                                const emm_trace_record *recs, size_t n,
                                const emm_threads *threads, emm_model_share *share,
                                bool offered_only, emm_sweep **out, emm_error *err);

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
