/* Internal: the decision of runtime/table.c with its layouts built in a
 * share the caller keeps (simulator/share.h), so that a session builds each
 * layout of its mesh once — for the decision's sweeps, its own models and
 * its probes' decisions — instead of once per sweep. The public
 * emm_decide_features and emm_sweep_records are these with a share of
 * their own. */
#ifndef EMM_RUNTIME_TABLE_INTERNAL_H
#define EMM_RUNTIME_TABLE_INTERNAL_H

#include "emm/table.h"
#include "share.h"

emm_status sweep_records_shared(const emm_machine *m, const emm_trace_info *info,
                                const emm_trace_record *recs, size_t n,
                                const emm_threads *threads, emm_model_share *share,
                                emm_sweep **out, emm_error *err);

emm_status decide_features_shared(const emm_table *t, const emm_machine *m,
                                  const emm_trace_info *info, const emm_trace_record *recs,
                                  size_t n, const double f[EMM_FEATURES], size_t accesses,
                                  const char *name, const emm_decide_options *opt,
                                  emm_model_share *share, emm_window_decision *out,
                                  emm_error *err);

#endif
