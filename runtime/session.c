/* The session behind libemmshim.so: profile → decide → simulate → report
 * (DESIGN.md "The shim": Session, Output; thesis §5, Fig. 5.6).
 *
 * Raw accesses become trace records by address: the few tagged arrays sit in
 * a small table searched linearly (a program tags two or three arrays), the
 * element is (addr − base) / stride and the offset the remainder. An access
 * that runs past the end of its record is attributed whole to the record it
 * starts in: the address-based models (direct, cache) see exactly what the
 * program did, and an EMM model sees the element the access was aimed at.
 *
 * The profile window's records are buffered (bounded by the window) until
 * the decision, because the positions that the profile needs are read from
 * the tagged arrays only then — the thesis' "freeze the data" — and because
 * the models that simulate the run cannot be built before the strategy and
 * the geometry are known. The window is then replayed through the models, so
 * the totals cover the whole run, and freed; after that each batch is
 * converted and streamed through the models, and memory no longer grows. */
#include "emm/session.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "emm/profile.h"
#include "emm/replay.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "emm/table.h"
#include "error.h"
#include "lead_sweep.h"
#include "json.h"
#include "outfile.h"
#include "report.h"

/* Arrays the session keeps at once (live or still referenced by the window). */
#define SESSION_MAX_ARRAYS 16
/* Records converted per model call after the decision: large enough that
 * starting a helper thread per chunk (the whole sweep) costs under 1%. */
#define SESSION_CHUNK 16384
/* From this many models on, a second thread runs half of them. */
#define SESSION_THREAD_MODELS 8
/* Window records buffered at most, per element access of the window (a
 * program that hammers one element would otherwise never fill the window),
 * and in all when the window counts iterations. */
#define SESSION_RECORDS_PER_ELEMENT 32u
#define SESSION_ITERATION_RECORDS (1u << 20)

enum session_phase { PHASE_PROFILING, PHASE_DECIDE, PHASE_SIMULATING, PHASE_FAILED, PHASE_DONE };

enum decision_source { FROM_NONE, FROM_CONFIG, FROM_TABLE, FROM_CHECKED, FROM_SIMULATION };

typedef struct session_array {
    emm_array_kind kind;
    uint64_t base, end;  /* [base, end) */
    uint64_t count, stride, field;
    emm_scalar type;
    bool live;           /* tagged now */
    unsigned char *snap; /* the fields, copied when the array went away before the
                            decision while the window named it; else NULL */
    uint64_t refs;       /* window records that name this slot */
    int32_t trace_index; /* the trace array it feeds after the decision, or -1 */
} session_array;

struct emm_session {
    /* configuration (strings copied) */
    char *strategy_text, *machine_path, *table_path, *report_path, *profile_dump, *trace_path;
    char *capture, *program;
    uint64_t window_accesses, window_iterations;
    emm_compare compare;
    int log;
    emm_machine *machine;
    emm_table *table; /* NULL: no table (a configured strategy without one) */
    bool forced;
    emm_strategy forced_strategy;

    enum session_phase phase;
    emm_error failure; /* why the session stepped aside (PHASE_FAILED) */

    session_array arrays[SESSION_MAX_ARRAYS];
    int narrays;
    int last; /* the slot the previous access hit */
    uint64_t pending_work; /* work of dropped accesses, carried to the next record */

    /* the window */
    emm_trace_record *window;
    size_t wn, wcap, wlimit;
    uint64_t welements, iterations;
    bool wany;
    uint32_t wlast_array;
    uint64_t wlast_element;
    lead_sweep sweep;     /* the leading index-order sweep */
    size_t wskip;         /* window records of that sweep (the profiler's count) */

    /* frozen at the decision */
    emm_trace_array *tarrays;
    uint32_t ntarrays;
    double *xyz;
    int32_t *tri;
    emm_trace_info info;
    double *D;        /* the window's distance profile, nD values */
    size_t nD;
    bool has_profile; /* features and a table decision exist */
    double features[EMM_FEATURES];
    emm_decision decision;
    enum decision_source source;
    char strategy_note[512]; /* why the chosen strategy has no model, or "" */
    emm_strategy chosen;
    bool has_chosen;
    emm_model **models;
    size_t nmodels, skipped;
    emm_trace_writer *trace;
    emm_error trace_error;
    bool trace_failed;
    emm_trace_record *chunk;
    size_t nchunk;
    uint64_t accesses; /* records simulated */
    uint64_t dropped;  /* records of arrays left out of the trace */
};

static char *dup_or_null(const char *s)
{
    return s ? strdup(s) : NULL;
}

/* The directory part of path must exist and be writable: a report that
 * cannot be written is a configuration error found at start, not at exit. */
static emm_status check_output(const char *var, const char *path, emm_error *err)
{
    if (!path)
        return EMM_OK;
    if (!*path)
        return emm_fail(err, EMM_ERR_INVALID, "%s: empty path", var);
    const char *slash = strrchr(path, '/');
    char dir[4096];
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else if ((size_t)(slash - path) < sizeof dir)
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    else
        return emm_fail(err, EMM_ERR_INVALID, "%s: %s: path too long", var, path);
    if (slash && slash[1] == '\0')
        return emm_fail(err, EMM_ERR_INVALID, "%s: %s: names a directory, not a file", var, path);
    if (access(dir, W_OK | X_OK) != 0)
        return emm_fail(err, EMM_ERR_IO, "%s: %s: cannot write in directory %s: %s", var, path,
                        dir, strerror(errno));
    return EMM_OK;
}

emm_status emm_session_new(const emm_session_config *cfg, emm_session **out, emm_error *err)
{
    emm_status st;
    emm_error e;
    *out = NULL;
    emm_session *s = calloc(1, sizeof *s);
    if (!s)
        return emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
    s->strategy_text = dup_or_null(cfg->strategy);
    s->machine_path = dup_or_null(cfg->machine_path);
    s->table_path = dup_or_null(cfg->table_path);
    s->report_path = dup_or_null(cfg->report_path);
    s->profile_dump = dup_or_null(cfg->profile_dump);
    s->trace_path = dup_or_null(cfg->trace_path);
    s->capture = strdup(cfg->capture ? cfg->capture : "");
    s->program = strdup(cfg->program ? cfg->program : "program");
    s->chunk = malloc(SESSION_CHUNK * sizeof *s->chunk);
    if ((cfg->strategy && !s->strategy_text) || (cfg->machine_path && !s->machine_path) ||
        (cfg->table_path && !s->table_path) || (cfg->report_path && !s->report_path) ||
        (cfg->profile_dump && !s->profile_dump) || (cfg->trace_path && !s->trace_path) ||
        !s->capture || !s->program || !s->chunk) {
        st = emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
        goto fail;
    }
    s->window_accesses = cfg->window_accesses;
    s->window_iterations = cfg->window_accesses ? 0 : cfg->window_iterations;
    if (!s->window_accesses && !s->window_iterations)
        s->window_accesses = EMM_PROFILE_DEFAULT_WINDOW;
    if (s->window_accesses > (UINT64_MAX / 32) / SESSION_RECORDS_PER_ELEMENT) {
        st = emm_fail(err, EMM_ERR_RANGE, "EMM_PROFILE: a window of %llu accesses is too large",
                      (unsigned long long)s->window_accesses);
        goto fail;
    }
    s->wlimit = s->window_accesses ? (size_t)(s->window_accesses * SESSION_RECORDS_PER_ELEMENT + 4096)
                                   : SESSION_ITERATION_RECORDS;
    if ((unsigned)cfg->compare > EMM_COMPARE_NONE) {
        st = emm_fail(err, EMM_ERR_INVALID, "EMM_COMPARE: unknown value %d", (int)cfg->compare);
        goto fail;
    }
    s->compare = cfg->compare;
    s->log = cfg->log;
    s->last = -1;

    if ((st = emm_machine_new(&s->machine, err)) != EMM_OK)
        goto fail;
    if (s->machine_path) {
        if ((st = emm_machine_load(s->machine, s->machine_path, &e)) != EMM_OK) {
            st = emm_fail(err, st, "EMM_MACHINE: %s", e.message);
            goto fail;
        }
    }
    if ((st = emm_machine_validate(s->machine, &e)) != EMM_OK) {
        st = emm_fail(err, st, "EMM_MACHINE: %s", e.message);
        goto fail;
    }
    if (s->strategy_text) {
        if ((st = emm_strategy_parse(s->strategy_text, &s->forced_strategy, &e)) != EMM_OK) {
            st = emm_fail(err, st, "EMM_STRATEGY: %s", e.message);
            goto fail;
        }
        s->forced = true;
    }
    /* The table decides unless a strategy is configured; then it only names
     * the nearest sample, and a missing default table is no error. */
    s->table = emm_table_new();
    if (!s->table) {
        st = emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
        goto fail;
    }
    st = cfg->table_only && s->table_path ? emm_table_load(s->table, s->table_path, &e)
                                          : emm_table_load_standard(s->table, s->table_path, &e);
    if (st != EMM_OK) {
        if (!s->forced || s->table_path) {
            st = emm_fail(err, st, "%s%s", s->table_path ? "EMM_TABLE: " : "", e.message);
            goto fail;
        }
        emm_table_free(s->table);
        s->table = NULL;
    }
    if ((st = check_output("EMM_REPORT", s->report_path, err)) != EMM_OK ||
        (st = check_output("EMM_PROFILE_DUMP", s->profile_dump, err)) != EMM_OK ||
        (st = check_output("EMM_TRACE", s->trace_path, err)) != EMM_OK)
        goto fail;
    *out = s;
    return EMM_OK;
fail:
    emm_session_free(s);
    return st;
}

/* ---- tagged arrays ------------------------------------------------------- */

static bool valid_field(emm_array_kind kind, emm_scalar type)
{
    if (kind == EMM_ARRAY_VERTICES)
        return type == EMM_F32 || type == EMM_F64;
    if (kind == EMM_ARRAY_TRIANGLES)
        return type == EMM_I32 || type == EMM_U32 || type == EMM_I64;
    return false;
}

static size_t scalar_bytes(emm_scalar t)
{
    return t == EMM_F32 || t == EMM_I32 || t == EMM_U32 ? 4 : 8;
}

/* The address of record i's three scalars, in the program's memory or in
 * the slot's snapshot. */
static const unsigned char *field_at(const session_array *a, uint64_t i)
{
    if (a->snap)
        return a->snap + i * 3 * scalar_bytes(a->type);
    return (const unsigned char *)(uintptr_t)(a->base + i * a->stride + a->field);
}

/* An array leaves (freed, moved, re-tagged). When the window holds records
 * of it and the decision is still to come, its coordinates or indices are
 * copied first — a program that frees its mesh before exit still gets its
 * short run decided at finish; without memory for that, those records are
 * dropped at the decision. */
static void drop_slot(emm_session *s, int i)
{
    session_array *a = &s->arrays[i];
    if ((s->phase == PHASE_PROFILING || s->phase == PHASE_DECIDE) && a->refs > 0 && !a->snap) {
        size_t sb = 3 * scalar_bytes(a->type);
        a->snap = malloc(a->count * sb);
        for (uint64_t k = 0; a->snap && k < a->count; k++)
            memcpy(a->snap + k * sb,
                   (const unsigned char *)(uintptr_t)(a->base + k * a->stride + a->field), sb);
    }
    a->live = false;
    if (s->last == i)
        s->last = -1;
}

/* Live, or gone with its fields kept for the decision. */
static bool usable(const session_array *a)
{
    return a->live || a->snap;
}

int emm_session_tag(emm_session *s, emm_array_kind kind, const void *base, size_t count,
                    size_t stride, size_t field_offset, emm_scalar type)
{
    uint64_t lo = (uint64_t)(uintptr_t)base, span;
    if (s->phase == PHASE_FAILED || s->phase == PHASE_DONE || !base || count == 0 ||
        stride == 0 || !valid_field(kind, type) || field_offset > stride ||
        3 * scalar_bytes(type) > stride - field_offset ||
        __builtin_mul_overflow((uint64_t)count, (uint64_t)stride, &span) ||
        lo > UINT64_MAX - span)
        return -1;
    for (int i = 0; i < s->narrays; i++)
        if (s->arrays[i].live && s->arrays[i].base < lo + span && lo < s->arrays[i].end)
            drop_slot(s, i);
    /* A slot is free when nothing refers to it any more: not live, not named
     * by a window record, not feeding a trace array. */
    int slot = -1;
    for (int i = 0; i < s->narrays && slot < 0; i++)
        if (!s->arrays[i].live && s->arrays[i].refs == 0 && s->arrays[i].trace_index < 0 &&
            !s->arrays[i].snap)
            slot = i;
    int32_t tidx = -1;
    if (s->phase == PHASE_SIMULATING) {
        /* After the decision the trace's arrays are fixed; an array that
         * moved (realloc) keeps feeding its trace array if it is the same
         * kind of record, up to the count the trace knows. */
        for (int i = 0; i < s->narrays && tidx < 0; i++) {
            session_array *a = &s->arrays[i];
            if (a->live || a->trace_index < 0 || a->kind != kind || a->stride != stride ||
                a->field != field_offset || a->type != type)
                continue;
            bool bound = false;
            for (int j = 0; j < s->narrays; j++)
                if (s->arrays[j].live && s->arrays[j].trace_index == a->trace_index)
                    bound = true;
            if (!bound) {
                tidx = a->trace_index;
                a->trace_index = -1; /* handed over */
                if (slot < 0 && a->refs == 0)
                    slot = i;
            }
        }
    }
    if (slot < 0) {
        if (s->narrays == SESSION_MAX_ARRAYS)
            return -1;
        slot = s->narrays++;
    }
    session_array *a = &s->arrays[slot];
    a->kind = kind;
    a->base = lo;
    a->end = lo + span;
    a->count = count;
    a->stride = stride;
    a->field = field_offset;
    a->type = type;
    a->live = true;
    a->refs = 0;
    a->snap = NULL;
    a->trace_index = tidx;
    if (tidx >= 0 && a->count > s->tarrays[tidx].count) {
        a->count = s->tarrays[tidx].count; /* later elements are not in the trace */
        a->end = lo + a->count * stride;
    }
    return slot;
}

void emm_session_untag(emm_session *s, const void *base)
{
    uint64_t lo = (uint64_t)(uintptr_t)base;
    for (int i = 0; i < s->narrays; i++)
        if (s->arrays[i].live && s->arrays[i].base == lo)
            drop_slot(s, i);
}

size_t emm_session_ranges(const emm_session *s, uint64_t *lo, uint64_t *hi, size_t cap)
{
    size_t n = 0;
    if (s->phase == PHASE_FAILED || s->phase == PHASE_DONE)
        return 0;
    for (int i = 0; i < s->narrays; i++) {
        const session_array *a = &s->arrays[i];
        if (!a->live || (s->phase == PHASE_SIMULATING && a->trace_index < 0))
            continue;
        if (n < cap) {
            lo[n] = a->base;
            hi[n] = a->end;
        }
        n++;
    }
    return n;
}

/* ---- accesses ------------------------------------------------------------ */

static inline int find_array(emm_session *s, uint64_t addr)
{
    int last = s->last;
    if (last >= 0 && addr - s->arrays[last].base < s->arrays[last].end - s->arrays[last].base)
        return last;
    for (int i = 0; i < s->narrays; i++) {
        const session_array *a = &s->arrays[i];
        if (a->live && addr - a->base < a->end - a->base) {
            s->last = i;
            return i;
        }
    }
    return -1;
}

/* Converts one raw access into *r (array = the slot); false when it is not
 * a mesh access (its work is carried to the next one). */
static inline bool convert(emm_session *s, const emm_raw_access *raw, emm_trace_record *r)
{
    uint32_t bytes = raw->bytes_write & ~EMM_RAW_WRITE;
    int i = find_array(s, raw->addr);
    s->pending_work += raw->work;
    if (i < 0 || bytes == 0)
        return false;
    const session_array *a = &s->arrays[i];
    uint64_t rel = raw->addr - a->base;
    r->element = rel / a->stride;
    r->offset = (uint32_t)(rel - r->element * a->stride);
    r->array = (uint32_t)i;
    r->bytes = bytes;
    r->work = s->pending_work > UINT32_MAX ? UINT32_MAX : (uint32_t)s->pending_work;
    r->write = (raw->bytes_write & EMM_RAW_WRITE) != 0;
    s->pending_work = 0;
    return true;
}

static emm_session_state public_state(const emm_session *s)
{
    switch (s->phase) {
    case PHASE_PROFILING:
        return EMM_SESSION_PROFILING;
    case PHASE_DECIDE:
        return EMM_SESSION_DECIDE;
    case PHASE_SIMULATING:
        return EMM_SESSION_SIMULATING;
    default:
        return EMM_SESSION_OFF;
    }
}

static void window_full_check(emm_session *s)
{
    if (s->phase != PHASE_PROFILING)
        return;
    if ((s->window_accesses && s->welements >= s->window_accesses) ||
        (s->window_iterations && s->iterations >= s->window_iterations) || s->wn >= s->wlimit)
        s->phase = PHASE_DECIDE;
}

static void window_add(emm_session *s, const emm_raw_access *a, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        emm_trace_record r;
        if (!convert(s, &a[k], &r))
            continue;
        if (s->wn == s->wcap) {
            /* Past the limit only while the caller has yet to decide. */
            size_t cap = s->wcap ? 2 * s->wcap : 4096;
            if (s->phase == PHASE_PROFILING && cap > s->wlimit)
                cap = s->wlimit > s->wcap ? s->wlimit : s->wcap + 4096;
            emm_trace_record *w = realloc(s->window, cap * sizeof *w);
            if (!w) {
                emm_fail(&s->failure, EMM_ERR_NOMEM,
                         "%s: out of memory for the profile window (%zu records)", s->program,
                         s->wn);
                s->phase = PHASE_FAILED;
                return;
            }
            s->window = w;
            s->wcap = cap;
        }
        s->window[s->wn++] = r;
        s->arrays[r.array].refs++;
        /* An element access as the profiler counts it: consecutive accesses
         * to one element count once. */
        if (s->phase == PHASE_PROFILING &&
            (!s->wany || r.array != s->wlast_array || r.element != s->wlast_element)) {
            s->wany = true;
            s->wlast_array = r.array;
            s->wlast_element = r.element;
            /* The profile starts after a leading index-order sweep (reading
             * the file, initialising per-element data), whose records are
             * still simulated: runtime/lead_sweep.h. */
            s->welements += (uint64_t)lead_sweep_step(&s->sweep, r.array, r.element);
        }
        if (!s->sweep.over)
            s->wlimit++; /* the sweep's records do not count against the window */
        window_full_check(s);
    }
}

typedef struct model_share {
    emm_model **models;
    size_t n;
    const emm_trace_record *recs;
    size_t nrecs;
} model_share;

static void *run_share(void *arg)
{
    const model_share *sh = arg;
    for (size_t i = 0; i < sh->n; i++)
        emm_model_run(sh->models[i], sh->recs, sh->nrecs);
    return NULL;
}

/* Runs records through every model. With the whole sweep (50 models) that
 * is most of the session's time, so a second thread takes half the models
 * for each chunk (models are independent). The helper starts with every
 * signal blocked, so the program's signals never land on it; when it cannot
 * start, this thread does all the work. */
static void run_models(emm_model **models, size_t nmodels, const emm_trace_record *recs,
                       size_t n)
{
    model_share mine = {models, nmodels, recs, n};
    if (nmodels >= SESSION_THREAD_MODELS && n >= 1024) {
        model_share theirs = {models + nmodels / 2, nmodels - nmodels / 2, recs, n};
        sigset_t all, old;
        pthread_t helper;
        sigfillset(&all);
        pthread_sigmask(SIG_SETMASK, &all, &old);
        int started = pthread_create(&helper, NULL, run_share, &theirs) == 0;
        pthread_sigmask(SIG_SETMASK, &old, NULL);
        if (started) {
            mine.n = nmodels / 2;
            run_share(&mine);
            pthread_join(helper, NULL);
            return;
        }
    }
    run_share(&mine);
}

static void simulate(emm_session *s, const emm_trace_record *recs, size_t n)
{
    run_models(s->models, s->nmodels, recs, n);
    if (s->trace && !s->trace_failed && emm_trace_write(s->trace, recs, n, &s->trace_error) != EMM_OK) {
        s->trace_failed = true;
        emm_trace_writer_abort(s->trace);
        s->trace = NULL;
    }
    s->accesses += n;
}

static void flush_chunk(emm_session *s)
{
    if (s->nchunk) {
        simulate(s, s->chunk, s->nchunk);
        s->nchunk = 0;
    }
}

emm_session_state emm_session_access(emm_session *s, const emm_raw_access *a, size_t n)
{
    if (s->phase == PHASE_PROFILING || s->phase == PHASE_DECIDE) {
        window_add(s, a, n);
        return public_state(s);
    }
    if (s->phase != PHASE_SIMULATING)
        return public_state(s);
    /* Records gather in the chunk across calls (the shim's batches are
     * small) and go through the models when it is full, and at finish. */
    size_t m = s->nchunk;
    for (size_t k = 0; k < n; k++) {
        emm_trace_record *r = &s->chunk[m];
        if (!convert(s, &a[k], r))
            continue;
        int32_t t = s->arrays[r->array].trace_index;
        if (t < 0) {
            s->dropped++;
            continue;
        }
        r->array = (uint32_t)t;
        if (++m == SESSION_CHUNK) {
            simulate(s, s->chunk, m);
            m = 0;
        }
    }
    s->nchunk = m;
    return EMM_SESSION_SIMULATING;
}

emm_session_state emm_session_iteration(emm_session *s)
{
    s->iterations++;
    window_full_check(s);
    return public_state(s);
}

/* ---- the decision -------------------------------------------------------- */

static double read_coord(const unsigned char *p, emm_scalar t)
{
    if (t == EMM_F32) {
        float f;
        memcpy(&f, p, sizeof f);
        return f;
    }
    double d;
    memcpy(&d, p, sizeof d);
    return d;
}

static int64_t read_index(const unsigned char *p, emm_scalar t)
{
    if (t == EMM_I32) {
        int32_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    if (t == EMM_U32) {
        uint32_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    int64_t v;
    memcpy(&v, p, sizeof v);
    return v;
}

/* The live array of `kind` with the most records: the mesh itself; other
 * arrays of the kind are per-element data beside it. */
static int largest(const emm_session *s, emm_array_kind kind)
{
    int best = -1;
    for (int i = 0; i < s->narrays; i++)
        if (usable(&s->arrays[i]) && s->arrays[i].kind == kind &&
            (best < 0 || s->arrays[i].count > s->arrays[best].count))
            best = i;
    return best;
}

/* "Freeze the data": copies the positions and the triangles' vertex indices
 * out of the program's arrays, checking them. */
static emm_status read_geometry(emm_session *s, emm_error *err)
{
    int gv = largest(s, EMM_ARRAY_VERTICES), gt = largest(s, EMM_ARRAY_TRIANGLES);
    if (gv < 0)
        return emm_fail(err, EMM_ERR_INVALID,
                        "%s: no vertex array was tagged (emm_tag_vertices or an EMM_TAG "
                        "'vertices:' rule), so there is no geometry to lay out",
                        s->program);
    const session_array *v = &s->arrays[gv];
    if (v->count > INT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE, "%s: the vertex array has %llu records (at most %d)",
                        s->program, (unsigned long long)v->count, INT32_MAX);
    s->xyz = malloc(3 * v->count * sizeof *s->xyz);
    if (!s->xyz)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
    for (uint64_t i = 0; i < v->count; i++) {
        const unsigned char *p = field_at(v, i);
        for (int c = 0; c < 3; c++) {
            double x = read_coord(p + (size_t)c * scalar_bytes(v->type), v->type);
            if (!isfinite(x))
                return emm_fail(err, EMM_ERR_MESH,
                                "%s: tagged vertex array at 0x%llx: vertex %llu has a non-finite "
                                "coordinate (is xyz's offset or type wrong?)",
                                s->program, (unsigned long long)v->base, (unsigned long long)i);
            s->xyz[3 * i + (uint64_t)c] = x;
        }
    }
    s->info.geometry.nv = v->count;
    s->info.geometry.xyz = s->xyz;
    if (gt >= 0) {
        const session_array *t = &s->arrays[gt];
        s->tri = malloc(3 * t->count * sizeof *s->tri);
        if (!s->tri)
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
        for (uint64_t i = 0; i < t->count; i++) {
            const unsigned char *p = field_at(t, i);
            for (int c = 0; c < 3; c++) {
                int64_t x = read_index(p + (size_t)c * scalar_bytes(t->type), t->type);
                if (x < 0 || (uint64_t)x >= v->count)
                    return emm_fail(err, EMM_ERR_MESH,
                                    "%s: tagged triangle array at 0x%llx: triangle %llu has vertex "
                                    "index %lld, outside the %llu tagged vertices (is vidx's "
                                    "offset or type wrong?)",
                                    s->program, (unsigned long long)t->base,
                                    (unsigned long long)i, (long long)x,
                                    (unsigned long long)v->count);
                s->tri[3 * i + (uint64_t)c] = (int32_t)x;
            }
        }
        s->info.geometry.nt = t->count;
        s->info.geometry.tri = s->tri;
    }
    return EMM_OK;
}

/* Trace arrays for the live slots the geometry covers, in slot order; the
 * window's records are renumbered and those of other slots dropped. */
static emm_status freeze_arrays(emm_session *s, emm_error *err)
{
    s->tarrays = calloc((size_t)s->narrays + 1, sizeof *s->tarrays);
    if (!s->tarrays)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", s->program);
    for (int i = 0; i < s->narrays; i++) {
        session_array *a = &s->arrays[i];
        uint64_t limit = a->kind == EMM_ARRAY_VERTICES ? s->info.geometry.nv : s->info.geometry.nt;
        a->trace_index = -1;
        if (!usable(a) || a->count > limit)
            continue;
        a->trace_index = (int32_t)s->ntarrays;
        s->tarrays[s->ntarrays++] = (emm_trace_array){
            .kind = a->kind, .record_size = (uint32_t)a->stride, .count = a->count, .base = a->base};
    }
    s->info.version = 1;
    s->info.narrays = s->ntarrays;
    s->info.arrays = s->tarrays;
    size_t m = 0;
    uint64_t work = 0;
    for (size_t k = 0; k < s->wn; k++) {
        emm_trace_record r = s->window[k];
        int32_t t = s->arrays[r.array].trace_index;
        if (t < 0) {
            work += r.work;
            s->dropped++;
            continue;
        }
        work += r.work;
        r.work = work > UINT32_MAX ? UINT32_MAX : (uint32_t)work;
        work = 0;
        r.array = (uint32_t)t;
        s->window[m++] = r;
    }
    s->wn = m;
    return EMM_OK;
}

/* Eq. 5.1 over the window, its features and the table's nearest sample. */
static emm_status profile_window(emm_session *s, emm_error *err)
{
    emm_profiler *p;
    emm_status st = emm_profiler_new(&s->info, s->welements ? s->welements : 1, s->program, &p, err);
    if (st != EMM_OK)
        return st;
    if ((st = emm_profiler_add(p, s->window, s->wn, err)) != EMM_OK) {
        emm_profiler_free(p);
        return st;
    }
    /* The profiler leaves the leading sweep out by the same rule as
     * window_add; its count of the sweep's records is the one that holds
     * for the frozen window. */
    emm_profiler_swept(p, &s->wskip);
    size_t n;
    const double *xy = emm_profiler_positions(p, &n);
    if (n > 0) {
        s->D = malloc(n * sizeof *s->D);
        if (!s->D) {
            emm_profiler_free(p);
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the profile", s->program);
        }
        st = emm_profile_compute(xy, n, s->D, NULL, err);
        s->nD = st == EMM_OK ? n : 0;
    }
    emm_profiler_free(p);
    if (st != EMM_OK || s->nD < EMM_PROFILE_MIN || !s->table)
        return st;
    double f[EMM_FEATURES];
    if ((st = emm_profile_features(s->D, s->nD, s->program, f, err)) != EMM_OK)
        return st;
    /* The nearest sample, also when EMM_STRATEGY decides (the report names it). */
    if ((st = emm_table_decide(s->table, f, 0, &s->decision, err)) != EMM_OK)
        return st;
    memcpy(s->features, f, sizeof f);
    s->has_profile = true;
    return EMM_OK;
}

/* The decision (runtime/table.c, docs/profile.md "The decision"): the
 * nearest sample, its pattern simulated over this mesh and weighed with the
 * window, or the sweep on the window when the profile is novel. */
static emm_status choose(emm_session *s, emm_error *err)
{
    emm_window_decision wd;
    emm_status st =
        emm_decide_features(s->table, s->machine, &s->info, s->window + s->wskip, s->wn - s->wskip,
                            s->features, s->nD, s->program, 0, 0, &wd, err);
    if (st != EMM_OK)
        return st;
    s->chosen = wd.strategy;
    s->has_chosen = true;
    s->source = wd.how == EMM_DECIDED_WINDOW    ? FROM_SIMULATION
                : wd.how == EMM_DECIDED_CHECKED ? FROM_CHECKED
                                                : FROM_TABLE;
    return EMM_OK;
}

static bool same_strategy(const emm_strategy *a, const emm_strategy *b)
{
    return a->kind == b->kind && a->layout == b->layout && a->fetch == b->fetch &&
           a->cell == b->cell;
}

/* The models: the chosen strategy first, then the comparison. A comparison
 * strategy this build cannot simulate on this mesh is skipped; the chosen
 * one failing is reported, and the baselines still run. */
static emm_status build_models(emm_session *s, emm_error *err)
{
    emm_strategy list[72];
    size_t n = 0;
    if (s->has_chosen)
        list[n++] = s->chosen;
    if (s->compare == EMM_COMPARE_ALL) {
        emm_strategy sweep[64];
        size_t k = emm_strategy_sweep(sweep, 64);
        for (size_t i = 0; i < k && i < 64; i++)
            list[n++] = sweep[i];
    } else if (s->compare == EMM_COMPARE_BASELINES || !s->has_chosen) {
        emm_strategy_parse("direct", &list[n++], NULL);
        emm_strategy_parse("cache", &list[n++], NULL);
    }
    s->models = calloc(n, sizeof *s->models);
    if (!s->models)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", s->program);
    for (size_t i = 0; i < n; i++) {
        bool dup = false;
        for (size_t j = 0; j < i; j++)
            dup = dup || same_strategy(&list[i], &list[j]);
        if (dup)
            continue;
        emm_error e;
        if (emm_model_new(s->machine, &list[i], &s->info, &s->models[s->nmodels], &e) == EMM_OK) {
            s->nmodels++;
        } else if (i == 0 && s->has_chosen) {
            snprintf(s->strategy_note, sizeof s->strategy_note, "%s", e.message);
            s->has_chosen = false;
        } else {
            s->skipped++;
        }
    }
    if (s->nmodels == 0)
        return emm_fail(err, EMM_ERR_UNSUPPORTED, "%s: no strategy can be simulated: %s",
                        s->program, s->strategy_note[0] ? s->strategy_note : "none was asked for");
    return EMM_OK;
}

static emm_status decide(emm_session *s, emm_error *err)
{
    emm_status st;
    if ((st = read_geometry(s, err)) != EMM_OK || (st = freeze_arrays(s, err)) != EMM_OK)
        return st;
    if ((st = profile_window(s, err)) != EMM_OK)
        return st;
    if (s->forced) {
        s->chosen = s->forced_strategy;
        s->has_chosen = true;
        s->source = FROM_CONFIG;
    } else if (s->has_profile) {
        if ((st = choose(s, err)) != EMM_OK)
            return st;
    }
    if ((st = build_models(s, err)) != EMM_OK)
        return st;
    if (s->trace_path) {
        if ((st = emm_trace_writer_open(s->trace_path, s->tarrays, s->ntarrays, &s->info.geometry,
                                        0, &s->trace, &s->trace_error)) != EMM_OK) {
            s->trace_failed = true;
            s->trace = NULL;
        }
    }
    simulate(s, s->window, s->wn);
    return EMM_OK;
}

emm_status emm_session_decide(emm_session *s, emm_error *err)
{
    if (s->phase == PHASE_SIMULATING || s->phase == PHASE_DONE)
        return EMM_OK;
    if (s->phase == PHASE_FAILED) {
        if (err)
            *err = s->failure;
        return s->failure.status;
    }
    emm_status st = decide(s, &s->failure);
    for (int i = 0; i < s->narrays; i++) {
        free(s->arrays[i].snap);
        s->arrays[i].snap = NULL;
    }
    free(s->window);
    s->window = NULL;
    s->wn = s->wcap = 0;
    if (st != EMM_OK) {
        s->phase = PHASE_FAILED;
        if (err)
            *err = s->failure;
        return st;
    }
    s->phase = PHASE_SIMULATING;
    return EMM_OK;
}

/* ---- output -------------------------------------------------------------- */

static const char *source_name(enum decision_source src)
{
    switch (src) {
    case FROM_CONFIG:
        return "configured";
    case FROM_TABLE:
        return "table";
    case FROM_CHECKED:
        return "checked";
    case FROM_SIMULATION:
        return "simulated";
    default:
        return "none";
    }
}

typedef struct report_ctx {
    const emm_session *s;
} report_ctx;

/* The most profile points the report carries: enough for a plot of the
 * curve (emm plot, thesis Fig. 5.5), little enough for a small report. The
 * first REPORT_PROFILE_HEAD are all kept, for a plot on a log axis. */
#define REPORT_PROFILE_POINTS 2000
#define REPORT_PROFILE_HEAD 500

static void write_features(json_writer *w, const double f[EMM_FEATURES])
{
    json_begin_array(w);
    for (int k = 0; k < EMM_FEATURES; k++)
        json_double(w, f[k]);
    json_end_array(w);
}

/* "profile" (docs/report.md): the window's D_i downsampled to at most
 * REPORT_PROFILE_POINTS points (all of the first REPORT_PROFILE_HEAD, then
 * evenly spaced, the last one always included); m_end, the
 * mean of D_i / i over the last n/32 accesses that features 11-16 divide
 * by (docs/profile.md), so a plot can draw a sample's shape at this
 * window's scale; the features, and the nearest sample's. */
static void write_profile(json_writer *w, const emm_session *s)
{
    const size_t head = REPORT_PROFILE_HEAD, rest = REPORT_PROFILE_POINTS - REPORT_PROFILE_HEAD;
    size_t n = s->nD, step = n > REPORT_PROFILE_POINTS ? (n - head + rest - 1) / rest : 1;
    json_key(w, "profile");
    if (n == 0) {
        json_null(w);
        return;
    }
    json_begin_object(w);
    json_key(w, "accesses");
    json_u64(w, n);
    double sum = 0;
    size_t a = n - n / 32 > 1 ? n - n / 32 : 1, b = n > a ? n : a + 1, cnt = 0;
    for (size_t i = a; i < b && i < n; i++, cnt++)
        sum += s->D[i] / (double)i;
    json_key(w, "m_end");
    if (cnt)
        json_double(w, sum / (double)cnt);
    else
        json_null(w);
    json_key(w, "points");
    json_begin_array(w);
    bool pretty = w->pretty; /* one point a line, not one number */
    for (size_t i = 0; i < n; i += i < head ? 1 : step) {
        size_t k = i >= head && i + step >= n ? n - 1 : i;
        json_begin_array(w);
        w->pretty = false;
        json_u64(w, k);
        json_double(w, s->D[k]);
        json_end_array(w);
        w->pretty = pretty;
    }
    json_end_array(w);
    if (s->has_profile) {
        json_key(w, "features");
        write_features(w, s->features);
        for (size_t i = 0; s->table && i < emm_table_count(s->table); i++) {
            const emm_table_sample *t = emm_table_at(s->table, i);
            if (strcmp(t->name, s->decision.nearest) != 0)
                continue;
            json_key(w, "nearest");
            json_begin_object(w);
            json_key(w, "name");
            json_string(w, t->name);
            json_key(w, "pattern");
            json_string(w, t->pattern);
            json_key(w, "distance");
            json_double(w, s->decision.distance);
            json_key(w, "features");
            write_features(w, t->f);
            json_end_object(w);
            break;
        }
    }
    json_end_object(w);
}

static void report_extra(json_writer *w, void *ctx)
{
    const emm_session *s = ((const report_ctx *)ctx)->s;
    char name[64];
    json_key(w, "program");
    json_string(w, s->program);
    json_key(w, "capture");
    json_string(w, s->capture);
    json_key(w, "pattern");
    if (s->has_profile)
        json_string(w, s->decision.novel ? "novel" : s->decision.pattern);
    else
        json_null(w);
    json_key(w, "strategy");
    if (s->has_chosen) {
        emm_strategy_format(&s->chosen, name, sizeof name);
        json_string(w, name);
    } else {
        json_null(w);
    }
    json_key(w, "decision");
    json_begin_object(w);
    json_key(w, "source");
    json_string(w, source_name(s->source));
    if (s->has_profile) {
        json_key(w, "nearest");
        json_string(w, s->decision.nearest);
        json_key(w, "nearest_pattern");
        json_string(w, s->decision.pattern);
        json_key(w, "distance");
        json_double(w, s->decision.distance);
        json_key(w, "novel");
        json_bool(w, s->decision.novel != 0);
    } else {
        json_key(w, "nearest");
        json_null(w);
        json_key(w, "nearest_pattern");
        json_null(w);
        json_key(w, "distance");
        json_null(w);
        json_key(w, "novel");
        json_bool(w, false);
    }
    if (s->strategy_note[0]) {
        json_key(w, "note");
        json_string(w, s->strategy_note);
    }
    json_end_object(w);
    json_key(w, "window");
    json_begin_object(w);
    json_key(w, "unit");
    json_string(w, s->window_accesses ? "accesses" : "iterations");
    json_key(w, "size");
    json_u64(w, s->window_accesses ? s->window_accesses : s->window_iterations);
    json_key(w, "element_accesses");
    json_u64(w, s->nD);
    json_key(w, "iterations");
    json_u64(w, s->iterations);
    json_key(w, "leading_sweep");
    json_u64(w, s->sweep.elements);
    json_end_object(w);
    write_profile(w, s);
}

/* "1,234,567" */
static const char *grouped(uint64_t v, char *buf, size_t cap)
{
    char digits[32];
    int n = snprintf(digits, sizeof digits, "%llu", (unsigned long long)v);
    size_t o = 0;
    for (int i = 0; i < n && o + 2 < cap; i++) {
        if (i > 0 && (n - i) % 3 == 0)
            buf[o++] = ',';
        buf[o++] = digits[i];
    }
    buf[o] = '\0';
    return buf;
}

static void print_line(FILE *out, const emm_result *r, const emm_result *ref)
{
    char name[64], num[40];
    emm_strategy_format(&r->strategy, name, sizeof name);
    fprintf(out, "emm:   %-22s %15s cycles", name, grouped(r->total, num, sizeof num));
    if (ref && r != ref && r->total && ref->total) {
        if (r->total >= ref->total)
            fprintf(out, "  (%.2fx slower)", (double)r->total / (double)ref->total);
        else
            fprintf(out, "  (%.2fx faster)", (double)ref->total / (double)r->total);
    }
    fputc('\n', out);
}

static void print_summary(const emm_session *s, FILE *out, const emm_result *res)
{
    char name[64];
    if (s->phase == PHASE_FAILED) {
        fprintf(out, "emm: %s: no simulation: %s\n", s->program, s->failure.message);
        return;
    }
    if (s->has_profile && s->decision.novel)
        fprintf(out, "emm: %s: pattern novel (nearest %s, a %s sample, at distance %.2f)\n",
                s->program, s->decision.nearest, s->decision.pattern, s->decision.distance);
    else if (s->has_profile)
        fprintf(out, "emm: %s: pattern %s (nearest %s, distance %.2f)\n", s->program,
                s->decision.pattern, s->decision.nearest, s->decision.distance);
    else
        fprintf(out, "emm: %s: pattern unknown (%zu element accesses profiled; %s)\n", s->program,
                s->nD, s->table ? "a profile needs at least 256" : "no strategy table");
    if (s->has_chosen) {
        emm_strategy_format(&s->chosen, name, sizeof name);
        const char *why = s->source == FROM_CONFIG       ? "EMM_STRATEGY"
                          : s->source == FROM_SIMULATION ? "best of the sweep on the window"
                          : s->source == FROM_CHECKED
                              ? "the table's pattern simulated over this mesh, with the window"
                              : "from the table";
        fprintf(out, "emm: strategy %s (%s)\n", name, why);
    } else if (s->strategy_note[0]) {
        fprintf(out, "emm: strategy not simulated: %s\n", s->strategy_note);
    } else {
        fprintf(out, "emm: no strategy chosen; baselines only\n");
    }
    const emm_result *ref = s->has_chosen ? &res[0] : NULL;
    size_t shown = 0;
    if (s->compare != EMM_COMPARE_ALL) {
        for (size_t i = 0; i < s->nmodels; i++)
            print_line(out, &res[i], ref);
        shown = s->nmodels;
    } else {
        /* The whole sweep is in the report; here the chosen strategy, the
         * baselines and the best of the rest. */
        size_t best = 0;
        for (size_t i = 0; i < s->nmodels; i++)
            if (res[i].total < res[best].total)
                best = i;
        for (size_t i = 0; i < s->nmodels; i++) {
            bool baseline = res[i].strategy.kind == EMM_STRATEGY_DIRECT ||
                            (res[i].strategy.kind == EMM_STRATEGY_CACHE &&
                             res[i].strategy.layout == EMM_LAYOUT_ORIGINAL);
            if ((i == 0 && s->has_chosen) || baseline || i == best) {
                print_line(out, &res[i], ref);
                shown++;
            }
        }
        if (shown < s->nmodels)
            fprintf(out, "emm:   (%zu more in the report; the fastest is listed)\n",
                    s->nmodels - shown);
    }
    if (s->log < 2)
        return;
    for (uint32_t a = 0; a < s->ntarrays; a++)
        fprintf(out, "emm: array %u: %s, %llu records of %u bytes at 0x%llx\n", a,
                emm_trace_kind_name(s->tarrays[a].kind), (unsigned long long)s->tarrays[a].count,
                s->tarrays[a].record_size, (unsigned long long)s->tarrays[a].base);
    fprintf(out, "emm: %llu accesses simulated; window %zu element accesses, %llu iterations\n",
            (unsigned long long)s->accesses, s->nD, (unsigned long long)s->iterations);
    if (s->skipped)
        fprintf(out, "emm: %zu strategies of the comparison cannot run on this mesh\n", s->skipped);
    if (s->dropped)
        fprintf(out, "emm: %llu accesses to tagged arrays outside the traced mesh were ignored\n",
                (unsigned long long)s->dropped);
}

static emm_status write_csv(const emm_session *s, emm_error *err)
{
    emm_outfile o;
    emm_error e;
    emm_status st = emm_outfile_open(&o, s->profile_dump, "the profile", &e);
    if (st == EMM_OK) {
        fprintf(o.f, "i,D\n");
        for (size_t i = 0; i < s->nD; i++)
            fprintf(o.f, "%zu,%.17g\n", i, s->D[i]);
        st = emm_outfile_commit(&o, "the profile", &e);
    }
    return st == EMM_OK ? EMM_OK : emm_fail(err, st, "EMM_PROFILE_DUMP: %s", e.message);
}

/* An output that could not be written is said on the summary stream: the
 * program's user would otherwise look for a file that is not there. */
static void output_failed(const emm_session *s, FILE *summary, const char *prefix,
                          const emm_error *e)
{
    if (summary && s->log >= 1) {
        fprintf(summary, "emm: %s%s\n", prefix, e->message);
        fflush(summary);
    }
}

emm_status emm_session_finish(emm_session *s, FILE *summary, emm_error *err)
{
    emm_status first = EMM_OK;
    emm_error e;
    if (s->phase == PHASE_DONE)
        return EMM_OK;
    if (s->phase == PHASE_PROFILING || s->phase == PHASE_DECIDE)
        emm_session_decide(s, NULL);
    if (s->phase == PHASE_FAILED) {
        if (summary && s->log >= 1)
            print_summary(s, summary, NULL);
        if (err)
            *err = s->failure;
        s->phase = PHASE_DONE;
        return s->failure.status;
    }
    flush_chunk(s);
    emm_result *res = calloc(s->nmodels, sizeof *res);
    if (!res)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the results", s->program);
    for (size_t i = 0; i < s->nmodels; i++) {
        emm_model_result(s->models[i], &res[i]);
        if (s->report_path) /* the report's per-cell DMA bytes; no cells is no error */
            emm_model_cells(s->models[i], &res[i], NULL);
    }
    if (summary && s->log >= 1) {
        print_summary(s, summary, res);
        fflush(summary);
    }
    if (s->report_path) {
        report_ctx ctx = {s};
        emm_status st = emm_report_write_extra(s->report_path, s->trace_path ? s->trace_path : "",
                                               s->machine, s->accesses, res, s->nmodels,
                                               report_extra, &ctx, &e);
        if (st != EMM_OK) {
            output_failed(s, summary, "EMM_REPORT: ", &e);
            if (first == EMM_OK)
                first = emm_fail(err, st, "EMM_REPORT: %s", e.message);
        }
    }
    if (s->profile_dump) {
        emm_status st = write_csv(s, &e);
        if (st != EMM_OK) {
            output_failed(s, summary, "", &e);
            if (first == EMM_OK) {
                first = st;
                if (err)
                    *err = e;
            }
        }
    }
    if (s->trace) {
        emm_status st = emm_trace_writer_close(s->trace, &s->trace_error);
        s->trace = NULL;
        if (st != EMM_OK)
            s->trace_failed = true;
    }
    if (s->trace_failed) {
        output_failed(s, summary, "EMM_TRACE: ", &s->trace_error);
        if (first == EMM_OK)
            first = emm_fail(err, s->trace_error.status, "EMM_TRACE: %s", s->trace_error.message);
    }
    for (size_t i = 0; i < s->nmodels; i++)
        emm_result_release(&res[i]);
    free(res);
    s->phase = PHASE_DONE;
    return first;
}

void emm_session_free(emm_session *s)
{
    if (!s)
        return;
    for (size_t i = 0; i < s->nmodels; i++)
        emm_model_free(s->models[i]);
    free(s->models);
    if (s->trace)
        emm_trace_writer_abort(s->trace);
    for (int i = 0; i < s->narrays; i++)
        free(s->arrays[i].snap);
    emm_machine_free(s->machine);
    emm_table_free(s->table);
    free(s->window);
    free(s->chunk);
    free(s->tarrays);
    free(s->xyz);
    free(s->tri);
    free(s->D);
    free(s->strategy_text);
    free(s->machine_path);
    free(s->table_path);
    free(s->report_path);
    free(s->profile_dump);
    free(s->trace_path);
    free(s->capture);
    free(s->program);
    free(s);
}
