/* Internal: the JSON report of docs/report.md with extra top-level keys, for
 * writers that add their own (the session's "pattern", "strategy", ...). */
#ifndef EMM_SIM_REPORT_H
#define EMM_SIM_REPORT_H

#include "emm/replay.h"
#include "emm/sim.h"
#include "json.h"

/* Writes further keys (json_key, then the value) into the report's
 * top-level object, after "results". */
typedef void (*emm_report_extra_fn)(json_writer *w, void *ctx);

/* emm_report_write_ex (skipped may be NULL), plus `extra` (may be NULL)
 * called before the object closes. Whole or not at all, as emm_report_write. */
emm_status emm_report_write_extra(const char *path, const char *trace_name, const emm_machine *m,
                                  uint64_t accesses, const emm_result *results,
                                  const emm_error *skipped, size_t n, emm_report_extra_fn extra,
                                  void *extra_ctx, emm_error *err);

#endif
