/* Internal: the run confirms the window's prediction (docs/profile.md "The
 * contest"). The thesis decides on the window alone and runs one strategy;
 * a window sees the start of a run, cold, and a canonical traversal over the
 * program's mesh is only a proxy for the program. When the whole run is
 * captured, emm goes beyond that: every candidate runs from the window's
 * first record, and each time the run reaches 2, 4, 8, ... window lengths
 * of records the slower half of the candidates still in is dropped (never
 * fewer than `finalists` stay) — successive halving (Jamieson & Talwalkar,
 * 2016). The finalists run to the end, and the fastest is the answer: a
 * measurement over the program's own run, not a prediction.
 *
 * A confident prediction is confirmed cheaply: once halving has left the
 * finalists (from the second check on), a finalist more than
 * CONTEST_MARGIN_PERCENT behind the leader (the fastest so far), both over
 * the records so far and since the previous check, is stopped instead of
 * running to the end (docs/profile.md "The contest"). It
 * could still have won only by taking, over the rest of the run, fewer
 * cycles than the leader by more than that gap; the report lists it as
 * stopped by the margin with its cycles and the leader's then.
 *
 * The session and `emm profile` (which replays a trace the session wrote)
 * run the same contest over the same records, so they give the same answer
 * whatever their batch sizes: a batch is cut at each check. */
#ifndef EMM_RUNTIME_CONTEST_H
#define EMM_RUNTIME_CONTEST_H

#include <stdbool.h>

#include "emm/trace.h"
#include "runner.h"

/* At most this many halvings are recorded (2^CONTEST_MAX_ROUNDS windows). */
#define CONTEST_MAX_ROUNDS 40

/* The margin, in percent of the leader's cycles so far. */
#define CONTEST_MARGIN_PERCENT 25u

typedef struct contest contest;

/* A contest among models[0..n) of runner r (indices into the runner; a model
 * that could not be built is left out). It checks when the records run
 * reach lead + unit·2, lead + unit·4, ... (lead: the records of the
 * window's leading sweep, which the profile leaves out; unit > 0: the
 * window's other records), and drops the slower half. A model pinned[j]
 * (pinned may be NULL) runs to the end for something else (a comparison
 * the report shows) and so is never dropped: the answer is the fastest of
 * every model that ran the whole run. EMM_ERR_NOMEM only. */
emm_status contest_new(emm_runner *r, const size_t *models, const bool *pinned, size_t n,
                       uint64_t lead, uint64_t unit, size_t finalists, contest **out,
                       emm_error *err);

/* Whether a candidate always runs to the end, whatever is compared: the
 * baselines (direct reads, the reference cache), which cost little beside
 * an EMM model and against which the answer is set; the session and
 * emm_contest_trace pin them alike, so that both reach the same answer. */
bool contest_pins(const emm_strategy *s);

/* Runs recs[0..n) through the runner, checking at every check point. */
void contest_run(contest *c, const emm_trace_record *recs, size_t n);

/* The contenders still in, fastest first over the records run so far (ties
 * by their order in models[]): up to cap runner indices in idx; returns how
 * many are in. */
size_t contest_standing(const contest *c, size_t *idx, size_t cap);

/* The models that entered, and the checks made: at[k] records run when
 * kept[k] contenders stayed in. */
size_t contest_entrants(const contest *c);
/* The window's records past its leading sweep: the checks come at 2, 4,
 * 8, ... times this, after the sweep's records (contest_lead). */
uint64_t contest_unit(const contest *c);
uint64_t contest_lead(const contest *c);
size_t contest_rounds(const contest *c, const uint64_t **at, const size_t **kept);

/* Whether runner model i was dropped and retired: its results stop where
 * it was dropped, short of the run. */
bool contest_retired(const contest *c, size_t i);

/* The candidates dropped, in the order they were: their runner indices,
 * the records run when each was dropped and its cycles then (the slower
 * half at that point; not its cycles over the run, which were not
 * measured). Returns how many. */
size_t contest_dropped(const contest *c, const size_t **idx, const uint64_t **at,
                       const uint64_t **cycles);

/* Whether the k-th candidate dropped (contest_dropped's order) was stopped
 * by the margin rather than halved; *leader: the leader's cycles then (0
 * when halved). */
bool contest_stopped(const contest *c, size_t k, uint64_t *leader);

void contest_free(contest *c);

#endif
