/* The program's phases (docs/profile.md "Phases"; beyond the thesis, which
 * profiles one window): after the window the session keeps a cheap running
 * profile — a probe as long as the window every SESSION_PROBE_GAP + 1
 * window lengths of element reads, its Eq. 5.1 profile and nearest sample,
 * worked out beside the run and acted on SESSION_PROBE_LAG records after
 * the probe filled (the detection) — and when two probes in a row find the
 * same pattern, other than the current phase's, a phase begins at the
 * first of them; a weak match counts only when its probe runs new code
 * (SESSION_PHASE_NEW_CODE), and a probe of old code is profiled only when
 * its moves are new to the phase (SESSION_PROBE_MOVED) or now and then
 * (SESSION_PROBE_OLD_SKIP). Its best candidate is decided on the probe as the
 * window's was (emm_decide_features) and, when it differs from the chosen
 * strategy, simulated from the detection on in a model of its own that starts cold:
 * exactly what switching strategy would do (the local store flushed). At
 * the phase's end its cycles are set against the chosen strategy's over
 * the same span plus the cost of re-laying out the mesh. */
#include "session_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "pool.h"

static void finish_probe(session *s);

/* ---- the code a phase runs --------------------------------------------- */

/* A read of the mesh (not of a raw array): what a phase's code is. */
static bool mesh_read(const session *s, const emm_trace_record *r)
{
    return !r->write && s->info.arrays[r->array].kind != EMM_ARRAY_RAW;
}

/* Slots of the direct-mapped memories of program counters below. */
#define PC_MEMO 256u

static size_t pc_slot(uint64_t pc)
{
    return (size_t)(pc ^ pc >> 8 ^ pc >> 16) & (PC_MEMO - 1);
}

static int cmp_pc(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* The distinct program counters of the mesh reads in recs; false without
 * memory. */
static bool pcs_of(const session *s, const emm_trace_record *recs, size_t n, pc_set *out)
{
    out->pc = NULL;
    out->n = 0;
    uint64_t *v = malloc((n ? n : 1) * sizeof *v);
    if (!v)
        return false;
    /* A loop's few counters repeat: a small direct-mapped memory of those
     * seen keeps most repeats out of the sort. */
    uint64_t recent[PC_MEMO] = {0};
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        uint64_t pc = recs[i].pc;
        uint64_t *slot = &recent[pc_slot(pc)];
        if (pc && *slot != pc && mesh_read(s, &recs[i])) {
            *slot = pc;
            v[m++] = pc;
        }
    }
    qsort(v, m, sizeof *v, cmp_pc);
    size_t u = 0;
    for (size_t i = 0; i < m; i++)
        if (u == 0 || v[i] != v[u - 1])
            v[u++] = v[i];
    out->pc = v;
    out->n = u;
    return true;
}

static bool pcs_has(const pc_set *set, uint64_t pc)
{
    return set->n && bsearch(&pc, set->pc, set->n, sizeof pc, cmp_pc) != NULL;
}

/* add's counters joined to into (add emptied), up to SESSION_PHASE_PCS_MAX;
 * without memory, into stays as it was. */
static void pcs_join(pc_set *into, pc_set *add)
{
    size_t cap = into->n + add->n;
    if (cap > SESSION_PHASE_PCS_MAX)
        cap = SESSION_PHASE_PCS_MAX;
    uint64_t *v = cap > into->n ? malloc(cap * sizeof *v) : NULL;
    if (v) {
        size_t a = 0, b = 0, m = 0;
        while (m < cap && (a < into->n || b < add->n)) {
            uint64_t x = a < into->n ? into->pc[a] : UINT64_MAX;
            uint64_t y = b < add->n ? add->pc[b] : UINT64_MAX;
            v[m++] = x <= y ? x : y;
            a += x <= y;
            b += y <= x;
        }
        free(into->pc);
        into->pc = v;
        into->n = m;
    }
    free(add->pc);
    add->pc = NULL;
    add->n = 0;
}

static void pcs_free(pc_set *set)
{
    free(set->pc);
    set->pc = NULL;
    set->n = 0;
}

/* The share of recs' mesh reads whose code is not in set; -1 when none of
 * them has a known program counter (the capture does not say). */
static double new_code(const session *s, const pc_set *set, const emm_trace_record *recs,
                       size_t n)
{
    size_t known = 0, fresh = 0;
    /* A loop's few counters repeat: each slot remembers a counter and
     * whether set has it, and the search runs once per change of slot. */
    uint64_t memo_pc[PC_MEMO] = {0};
    bool memo_new[PC_MEMO];
    for (size_t i = 0; i < n; i++) {
        uint64_t pc = recs[i].pc;
        if (!pc || !mesh_read(s, &recs[i]))
            continue;
        size_t k = pc_slot(pc);
        if (memo_pc[k] != pc) {
            memo_pc[k] = pc;
            memo_new[k] = !pcs_has(set, pc);
        }
        known++;
        fresh += memo_new[k];
    }
    return known ? (double)fresh / (double)known : -1;
}

/* The probe's moves, in a cheap form (docs/profile.md "Phases"): for each
 * kind of mesh array (vertices, triangles), the share of its element reads
 * that move by 2^b - 1 to 2^(b+1) - 2 ids from the element of that kind
 * read before, for each band b (a record's further loads, the same
 * element again, are no move). h[kind * SESSION_MOVE_BUCKETS + b]; a kind
 * not read has all zeros. */
static void moves_of(const session *s, const emm_trace_record *recs, size_t n,
                     double h[SESSION_MOVE_SIZE])
{
    uint64_t count[SESSION_MOVE_SIZE] = {0}, total[2] = {0, 0};
    uint64_t last[2] = {0, 0};
    bool any[2] = {false, false};
    for (size_t i = 0; i < n; i++) {
        const emm_trace_record *r = &recs[i];
        if (!mesh_read(s, r))
            continue;
        int k = s->info.arrays[r->array].kind == EMM_ARRAY_TRIANGLES;
        if (any[k] && r->element == last[k])
            continue;
        if (any[k]) {
            uint64_t d = r->element > last[k] ? r->element - last[k] : last[k] - r->element;
            int b = 0;
            while (b + 1 < SESSION_MOVE_BUCKETS && d + 1 >= (uint64_t)2 << b)
                b++;
            count[k * SESSION_MOVE_BUCKETS + b]++;
            total[k]++;
        }
        any[k] = true;
        last[k] = r->element;
    }
    for (int k = 0; k < 2; k++)
        for (int b = 0; b < SESSION_MOVE_BUCKETS; b++)
            h[k * SESSION_MOVE_BUCKETS + b] =
                total[k] ? (double)count[k * SESSION_MOVE_BUCKETS + b] / (double)total[k] : 0;
}

/* How far apart two probes' moves are: over the kinds, the largest half L1
 * distance of their bands (0 the same, 1 disjoint; 1 for a kind one of them
 * reads and the other does not). */
static double moves_apart(const double *a, const double *b)
{
    double worst = 0;
    for (int k = 0; k < 2; k++) {
        double d = 0, sa = 0, sb = 0;
        for (int i = k * SESSION_MOVE_BUCKETS; i < (k + 1) * SESSION_MOVE_BUCKETS; i++) {
            d += fabs(a[i] - b[i]);
            sa += a[i];
            sb += b[i];
        }
        d = (sa > 0) != (sb > 0) ? 1 : d / 2;
        worst = d > worst ? d : worst;
    }
    return worst;
}

/* Whether moves h are new to the current phase: farther than
 * SESSION_PROBE_MOVED (moves_apart) from every moves it remembers. */
static bool moved(const session *s, const double h[SESSION_MOVE_SIZE])
{
    for (uint32_t r = 0; r < s->nmoves; r++)
        if (moves_apart(s->moves[r], h) <= SESSION_PROBE_MOVED)
            return false;
    return true;
}

/* Moves h become the current phase's (the oldest forgotten past
 * SESSION_MOVE_REFS). */
static void remember_moves(session *s, const double h[SESSION_MOVE_SIZE])
{
    memcpy(s->moves[s->moves_next], h, sizeof s->moves[0]);
    s->moves_next = (s->moves_next + 1) % SESSION_MOVE_REFS;
    if (s->nmoves < SESSION_MOVE_REFS)
        s->nmoves++;
}

static uint64_t model_total(const session *s, size_t i)
{
    emm_model *m = emm_runner_model(s->runner, i);
    if (!m)
        return 0;
    emm_result r;
    emm_model_result(m, &r);
    uint64_t t = r.total;
    emm_result_release(&r);
    return t;
}

uint64_t session_mesh_bytes(const session *s)
{
    uint64_t bytes = 0;
    for (uint32_t a = 0; a < s->ntarrays; a++)
        if (s->tarrays[a].kind != EMM_ARRAY_RAW)
            bytes += s->tarrays[a].count * s->tarrays[a].record_size;
    return bytes;
}

uint64_t session_switch_cycles(const session *s)
{
    return 2 * emm_machine_dma_cycles(s->machine, session_mesh_bytes(s));
}

void session_phases_start(session *s)
{
    program_phase *p = &s->phases[0];
    memset(p, 0, sizeof *p);
    snprintf(p->pattern, sizeof p->pattern, "%s",
             s->has_profile ? (s->decision.novel ? "novel" : s->decision.pattern) : "unknown");
    snprintf(p->nearest, sizeof p->nearest, "%s", s->has_profile ? s->decision.nearest : "");
    p->distance = s->has_profile ? s->decision.distance : 0;
    p->has_best = s->has_chosen;
    p->best = s->chosen;
    p->model = SIZE_MAX;
    s->nphases = 1;
    s->old_probes = 0;
    s->probes_taken = s->probes_profiled = 0;
    s->nmoves = s->moves_next = 0;
    /* The first phase's moves and code: the window proper's. */
    size_t proper = session_window_proper(s);
    double h[SESSION_MOVE_SIZE];
    moves_of(s, s->window, proper, h);
    remember_moves(s, h);
    pcs_free(&s->phase_pcs);
    pcs_free(&s->pending_pcs);
    pc_set w;
    if (pcs_of(s, s->window, proper, &w))
        pcs_join(&s->phase_pcs, &w);
    /* A probe is as long as the window asked for: the window proper may
     * have read on to fill the local store, which a probe, taken where the
     * run has long filled it, has no need to. */
    s->probe_len = s->cfg.window_accesses && s->nD > s->cfg.window_accesses
                       ? s->cfg.window_accesses
                       : s->nD;
    s->gap = SESSION_PROBE_GAP * s->probe_len;
    /* Probes need EMM_PHASES, a table, a chosen strategy to weigh a switch
     * against, and the rest of the run (fault capture stops at the
     * decision). */
    s->probing = s->cfg.phases && s->has_profile && s->table && s->has_chosen &&
                 s->probe_len >= EMM_PROFILE_MIN && !session_window_only(s);
    s->probed = s->probing;
}

/* Every model's cycles now (those of a retired model stopped where it
 * was dropped; only the answer's, which never is, are read). */
static uint64_t *totals(const session *s, size_t n)
{
    uint64_t *t = malloc((n ? n : 1) * sizeof *t);
    for (size_t i = 0; t && i < n; i++)
        t[i] = model_total(s, i);
    return t;
}

static void close_phase(session *s, program_phase *p)
{
    if (p->closed)
        return;
    p->closed = true;
    if (p->model == SIZE_MAX)
        return;
    if (p->at)
        p->end = totals(s, p->nat);
    p->chosen_span = model_total(s, 0) - p->chosen_at;
    p->best_span = model_total(s, p->model);
    /* The next phase measures from its own detection, and nothing else
     * reads this model (it is no model of the report's): it stops here
     * instead of running on to the end of the run. */
    emm_runner_retire(s->runner, p->model);
}

void session_phases_close(session *s)
{
    finish_probe(s);
    if (s->nphases > 0)
        close_phase(s, &s->phases[s->nphases - 1]);
}

/* A full probe, evaluated beside the run (emm_task): its Eq. 5.1 profile,
 * features and nearest sample, and — when that makes it the second probe
 * in a row with the same new pattern — the new phase's best candidate.
 * What it reads of the session does not change while it runs (the trace's
 * arrays, the table, the machine; the decisions' cache and layouts are the
 * phases' alone by then, the layouts' share locks itself); its outcome is
 * applied (apply) on the session's thread. */
struct probe_job {
    session *s;
    emm_task *task;
    emm_trace_record *recs; /* the probe's records (owned) */
    size_t n;
    uint64_t reads, start;  /* its element reads; the access it starts at */
    char cur[EMM_TABLE_NAME_MAX], pending[EMM_TABLE_NAME_MAX]; /* the patterns when it filled */
    bool full;              /* no room for another phase */
    /* out */
    bool off;               /* it failed (memory): probing ends */
    bool opinion;           /* enough positions to name a pattern */
    emm_decision d;
    bool sample;            /* profiled even when its code is old (SESSION_PROBE_OLD_SKIP) */
    bool skipped;           /* old code, not profiled: no opinion */
    bool argues;            /* its pattern is a new phase's (new, and a strong match or new code) */
    pc_set pcs;             /* the code of its mesh reads */
    double moves[SESSION_MOVE_SIZE]; /* its moves (moves_of) */
    bool decided;           /* the best candidate of a new phase is in wd */
    emm_window_decision wd;
};

static const char *job_pattern(const struct probe_job *j)
{
    return j->d.novel ? "novel" : j->d.pattern;
}

static void evaluate(void *ctx)
{
    struct probe_job *j = ctx;
    const session *s = j->s;
    emm_profiler *pr = NULL;
    emm_error e;
    double *D = NULL, f[EMM_FEATURES];
    size_t n;
    if (!pcs_of(s, j->recs, j->n, &j->pcs))
        goto off;
    /* The current phase's code argues for a new phase only by a strong
     * match, which a probe is profiled for when its moves are new to the
     * phase, and one in SESSION_PROBE_OLD_SKIP + 1 in a row otherwise. */
    double fresh = new_code(s, &s->phase_pcs, j->recs, j->n);
    bool old_code = fresh >= 0 && fresh < SESSION_PHASE_NEW_CODE;
    moves_of(s, j->recs, j->n, j->moves);
    if (old_code && !j->sample && !moved(s, j->moves)) {
        j->skipped = true;
        goto done;
    }
    if (emm_profiler_new(&s->info, j->reads, EMM_PROFILE_PLANE, s->program, &pr, &e) != EMM_OK ||
        emm_profiler_add(pr, j->recs, j->n, &e) != EMM_OK)
        goto off;
    const double *xy = emm_profiler_positions(pr, &n);
    if (n < EMM_PROFILE_MIN)
        goto done; /* a probe that was mostly a sweep: no opinion */
    /* On this thread alone: it runs beside the run's models, which keep the
     * others busy, and one thread inserts no point twice. */
    emm_threads one = s->threads;
    one.jobs = 1;
    if (!(D = malloc(n * sizeof *D)) ||
        emm_profile_fast(xy, n, emm_profiler_dims(pr), EMM_PROFILE_THETA, D, &one, &e) != EMM_OK ||
        emm_profile_features(D, n, s->program, f, &e) != EMM_OK ||
        emm_table_decide(s->table, f, 0, &j->d, &e) != EMM_OK)
        goto off;
    j->opinion = true;
    const char *pattern = job_pattern(j);
    j->argues = strcmp(pattern, j->cur) != 0 && (!old_code || j->d.distance <= EMM_WEAK_MATCH);
    if (j->argues && !j->full && strcmp(pattern, j->pending) == 0) {
        emm_decide_options opt = {.threads = &s->threads,
                                  .synth_visits = SESSION_PHASE_SYNTH_PROBES * j->reads};
        j->decided = decide_features_shared(s->table, s->machine, &s->info, j->recs, j->n, f, n,
                                            s->program, &opt, s->layouts, s->decisions, &j->wd,
                                            &e) == EMM_OK;
    }
done:
    emm_profiler_free(pr);
    free(D);
    return;
off:
    j->off = true;
    goto done;
}

/* The probe's outcome: a new phase when its pattern differs. Failures
 * (memory) end the probing quietly: phases are an addition to the answer,
 * never a reason to lose it. */
static void apply(session *s, struct probe_job *j)
{
    if (j->off) {
        s->probing = false;
        return;
    }
    s->old_probes = j->skipped ? s->old_probes + 1 : 0;
    s->probes_taken++;
    s->probes_profiled += !j->skipped;
    if (!j->opinion) {
        /* Moves a profile has nothing to say about (a sweep) are as much
         * the phase's as its code is. */
        if (!j->skipped)
            remember_moves(s, j->moves);
        pcs_join(&s->phase_pcs, &j->pcs);
        return;
    }
    const char *pattern = job_pattern(j);
    program_phase *cur = &s->phases[s->nphases - 1];
    /* A probe that does not argue for a new phase is the current phase's,
     * and so is the code of a pending probe it does not confirm. */
    if (!j->argues || s->nphases == SESSION_MAX_PHASES) {
        if (s->pending[0])
            remember_moves(s, s->pending_moves);
        remember_moves(s, j->moves);
        s->pending[0] = 0;
        pcs_join(&s->phase_pcs, &s->pending_pcs);
        pcs_join(&s->phase_pcs, &j->pcs);
        return;
    }
    /* One probe is not a phase: a short stretch of the traversal can look
     * like another pattern. The second in a row with the same new pattern
     * confirms it, and the phase starts at the first. */
    if (strcmp(pattern, s->pending) != 0) {
        if (s->pending[0])
            remember_moves(s, s->pending_moves);
        memcpy(s->pending_moves, j->moves, sizeof s->pending_moves);
        snprintf(s->pending, sizeof s->pending, "%s", pattern);
        s->pending_start = j->start;
        pcs_join(&s->phase_pcs, &s->pending_pcs);
        s->pending_pcs = j->pcs;
        j->pcs.pc = NULL;
        j->pcs.n = 0;
        return;
    }
    s->pending[0] = 0;
    /* The new phase's code is its two probes'. */
    pcs_free(&s->phase_pcs);
    s->phase_pcs = s->pending_pcs;
    s->pending_pcs.pc = NULL;
    s->pending_pcs.n = 0;
    pcs_join(&s->phase_pcs, &j->pcs);
    s->nmoves = s->moves_next = 0;
    remember_moves(s, s->pending_moves);
    remember_moves(s, j->moves);
    close_phase(s, cur);
    program_phase *p = &s->phases[s->nphases++];
    memset(p, 0, sizeof *p);
    p->start = s->pending_start;
    p->detected = s->accesses;
    snprintf(p->pattern, sizeof p->pattern, "%s", pattern);
    snprintf(p->nearest, sizeof p->nearest, "%s", j->d.nearest);
    p->distance = j->d.distance;
    p->model = SIZE_MAX;
    if (!j->decided)
        return;
    p->has_best = true;
    p->best = j->wd.strategy;
    p->best_is_answer = memcmp(&j->wd.strategy, &s->chosen, sizeof j->wd.strategy) == 0;
    /* With a contest the answer is known at the end only: the best
     * candidate's cold model runs even when it is the window's choice. */
    if (!p->best_is_answer || s->contest) {
        emm_error why, e;
        p->nat = s->nmodels;
        p->at = totals(s, p->nat);
        size_t k = emm_runner_count(s->runner);
        if (emm_runner_add(s->runner, s->machine, &j->wd.strategy, 1, &s->info, &why, &e) ==
                EMM_OK &&
            emm_runner_model(s->runner, k)) {
            p->model = k;
            p->chosen_at = model_total(s, 0);
        }
    }
}

/* The probe in flight, waited for and no longer the session's; NULL when
 * there is none. Free it with free_probe. */
static struct probe_job *take_probe(session *s)
{
    struct probe_job *j = s->probe_job;
    if (j) {
        emm_task_join(j->task);
        s->probe_job = NULL;
    }
    return j;
}

static void free_probe(struct probe_job *j)
{
    if (j) {
        free(j->recs);
        pcs_free(&j->pcs);
        emm_window_decision_release(&j->wd);
    }
    free(j);
}

/* The probe in flight, if any: waited for, applied, freed. */
static void finish_probe(session *s)
{
    struct probe_job *j = take_probe(s);
    if (j)
        apply(s, j);
    free_probe(j);
}

/* The probe filled at access `filled` (the records run when its last
 * record was): its records go to a job evaluated beside the run, the
 * probe starts empty. Without memory for that, probing ends. */
static void launch_probe(session *s, uint64_t filled)
{
    finish_probe(s); /* never in flight here: a probe is over in SESSION_PROBE_LAG records */
    struct probe_job *j = calloc(1, sizeof *j);
    if (!j) {
        s->probing = false;
        return;
    }
    j->s = s;
    j->recs = s->probe;
    j->n = s->pn;
    j->reads = s->probe_reads;
    j->start = s->probe_start;
    snprintf(j->cur, sizeof j->cur, "%s", s->phases[s->nphases - 1].pattern);
    snprintf(j->pending, sizeof j->pending, "%s", s->pending);
    j->full = s->nphases == SESSION_MAX_PHASES;
    j->sample = s->old_probes >= SESSION_PROBE_OLD_SKIP;
    s->probe = NULL;
    s->pn = s->pcap = 0;
    s->probe_job = j;
    s->probe_apply = filled + SESSION_PROBE_LAG;
    j->task = emm_task_start(&s->threads, evaluate, j);
}

/* Whether r reads an element of the mesh other than the one read last (a
 * record's further loads are one element read), which it then is. */
static inline bool element_read(const emm_trace_array *arrays, const emm_trace_record *r,
                                struct last_read *l)
{
    bool element = !r->write && arrays[r->array].kind != EMM_ARRAY_RAW &&
                   (!l->any || r->array != l->array || r->element != l->element);
    if (element) {
        l->any = true;
        l->array = r->array;
        l->element = r->element;
    }
    return element;
}

void session_phases_see(session *s, const emm_trace_record *recs, size_t n)
{
    /* The element read last, in locals: the gap between probes, most of
     * the run, only counts element reads. */
    const emm_trace_array *arrays = s->info.arrays;
    struct last_read l = s->plast;
    for (size_t k = 0; k < n && s->probing;) {
        if (s->gap > 0) {
            uint64_t gap = s->gap;
            for (; k < n && gap > 0; k++)
                gap -= element_read(arrays, &recs[k], &l);
            s->gap = gap;
            continue;
        }
        const emm_trace_record *r = &recs[k];
        bool element = element_read(arrays, r, &l);
        if (s->pn == 0)
            s->probe_start = s->accesses - n + k;
        if (s->pn == s->pcap) {
            size_t cap = s->pcap ? 2 * s->pcap : 4096;
            emm_trace_record *b = realloc(s->probe, cap * sizeof *b);
            if (!b) {
                s->probing = false;
                break;
            }
            s->probe = b;
            s->pcap = cap;
        }
        s->probe[s->pn++] = *r;
        s->probe_reads += element;
        k++;
        if (s->probe_reads >= s->probe_len) {
            launch_probe(s, s->accesses - n + k);
            s->pn = 0;
            s->probe_reads = 0;
            s->gap = SESSION_PROBE_GAP * s->probe_len;
        }
    }
    s->plast = l;
    /* A probe's outcome lands a fixed number of records after it filled
     * (session_simulate ends a batch there), so that what it finds depends
     * neither on how fast it was evaluated nor on the capture's batches. */
    if (s->probe_job && s->accesses >= s->probe_apply)
        finish_probe(s);
}

void session_phases_answer(session *s)
{
    size_t a = s->answer_model != SIZE_MAX ? s->answer_model : 0;
    if (!s->mstrat || a >= s->nmodels)
        return;
    for (int i = 1; i < s->nphases; i++) {
        program_phase *p = &s->phases[i];
        if (!p->has_best)
            continue;
        p->best_is_answer = memcmp(&p->best, &s->mstrat[a], sizeof p->best) == 0;
        if (p->at && p->end && a < p->nat)
            p->chosen_span = p->end[a] - p->at[a];
    }
}

void session_phases_free(session *s)
{
    free_probe(take_probe(s));
    pcs_free(&s->phase_pcs);
    pcs_free(&s->pending_pcs);
    for (int i = 0; i < s->nphases; i++) {
        free(s->phases[i].at);
        free(s->phases[i].end);
        s->phases[i].at = s->phases[i].end = NULL;
    }
}
