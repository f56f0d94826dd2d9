/* The session behind libemmshim.so: profile → decide → simulate → report
 * (docs/design.md "The shim and the session": Session, Output; thesis §5, Fig. 5.6). This
 * file: its lifecycle, the tagged arrays, the window and the stream of records through
 * the models; session_decide.c decides, session_report.c writes.
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
#include "session_internal.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "error.h"
#include "pool.h"

/* Records converted per model call after the decision: large enough that
 * handing a chunk to the runner's threads costs under 1%. */
#define SESSION_CHUNK 16384
/* Window records buffered at most, per element access of the window (a
 * program that hammers one element would otherwise never fill the window),
 * and in all when the window counts iterations. */
#define SESSION_RECORDS_PER_ELEMENT 32u
#define SESSION_ITERATION_RECORDS (1u << 20)

static const struct session_transport engine_transport;
static void window_start(session *s);

/* The start of a thread the session starts (the decision's helpers, the
 * run's model workers, the phase probes): the caller's hook, then the
 * thread is scheduled below the program (emm_thread_beside), whose records
 * it works on, so that the program goes first when they compete for a
 * core. */
static void beside_start(void *ctx)
{
    const session *s = ctx;
    if (s->caller_threads.on_start)
        s->caller_threads.on_start(s->caller_threads.ctx);
    emm_thread_beside();
}

emm_status session_engine_new(const emm_session_config *sc, emm_session **out, emm_error *err)
{
    emm_status st;
    emm_error e;
    *out = NULL;
    session *s = calloc(1, sizeof *s);
    if (!s)
        return emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
    s->handle.transport = &engine_transport;
    s->plain_model = SIZE_MAX; /* until session_decide_answer */
    if (sc->config)
        s->cfg = *sc->config;
    else
        emm_config_init(&s->cfg);
    /* Each array's description comes whole (emm_array_desc): the rules
     * stay with the caller. */
    s->cfg.tags.n = 0;
    s->cfg.tags.rule = NULL;
    if (sc->memory) {
        s->mem = *sc->memory;
        s->memory = &s->mem;
    }
    clock_gettime(CLOCK_REALTIME_COARSE, &s->started);
    s->pid = sc->pid ? sc->pid : (long)getpid();
    s->program = strdup(sc->program ? sc->program : "program");
    s->capture = sc->capture;
    s->expect = sc->expect & (1u << EMM_ARRAY_VERTICES | 1u << EMM_ARRAY_TRIANGLES);
    s->caller_threads = sc->threads;
    s->threads = sc->threads;
    s->threads.on_start = beside_start;
    s->threads.ctx = s;
    s->chunk = malloc(SESSION_CHUNK * sizeof *s->chunk);
    if (!s->program || !s->chunk) {
        st = emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
        goto fail;
    }
    if (!s->cfg.window_accesses && !s->cfg.window_iterations)
        s->cfg.window_accesses = EMM_PROFILE_DEFAULT_WINDOW;
    if (s->cfg.window_accesses > (UINT64_MAX / 32) / SESSION_RECORDS_PER_ELEMENT) {
        st = emm_fail(err, EMM_ERR_RANGE, "%s: a window of %llu accesses is too large",
                      session_source(s, EMM_CONFIG_PROFILE),
                      (unsigned long long)s->cfg.window_accesses);
        goto fail;
    }
    s->last = s->last2 = -1;
    s->he_slot = s->face_slot = s->vconn_slot = s->vertex_slot = -1;

    if ((st = emm_machine_new(&s->machine, err)) != EMM_OK)
        goto fail;
    if (s->cfg.machine[0] &&
        (st = emm_machine_load(s->machine, s->cfg.machine, &e)) != EMM_OK) {
        st = emm_fail(err, st, "%s: %s", session_source(s, EMM_CONFIG_MACHINE), e.message);
        goto fail;
    }
    if ((st = emm_machine_validate(s->machine, &e)) != EMM_OK) {
        st = emm_fail(err, st, "%s: %s", session_source(s, EMM_CONFIG_MACHINE), e.message);
        goto fail;
    }
    window_start(s);
    /* The table decides unless a strategy is configured; then it only names
     * the nearest sample, and a missing default table is no error. */
    s->table = emm_table_new();
    if (!s->table) {
        st = emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
        goto fail;
    }
    const char *table = session_path(s->cfg.table);
    st = sc->table_only && table ? emm_table_load(s->table, table, &e)
                                 : emm_table_load_standard(s->table, table, &e);
    if (st != EMM_OK) {
        if (!s->cfg.has_strategy || table) {
            if (table)
                st = emm_fail(err, st, "%s: %s", session_source(s, EMM_CONFIG_TABLE), e.message);
            else
                st = emm_fail(err, st, "%s", e.message);
            goto fail;
        }
        emm_table_free(s->table);
        s->table = NULL;
    }
    *out = &s->handle;
    return EMM_OK;
fail:
    engine_transport.free(&s->handle);
    return st;
}

/* The window's bounds at its start: its records (one that reads on until
 * it fills the local store reads up to emm_profile_fill_most of its
 * length) and the store's bytes to fill (window_fill.h). */
static void window_start(session *s)
{
    uint64_t w = s->cfg.window_accesses;
    s->wlimit = w ? (size_t)(emm_profile_fill_most(w) * SESSION_RECORDS_PER_ELEMENT + 4096)
                  : SESSION_ITERATION_RECORDS;
    window_fill_start(&s->wstore, w ? emm_machine_get(s->machine, "local.bytes") : 0);
    s->wlen = 0;
    s->wsized = false;
}

static emm_session_state public_state(const session *s)
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

/* ---- tagged arrays ------------------------------------------------------- */

static bool valid_field(emm_array_kind kind, emm_tag_shape shape, emm_scalar type)
{
    if (emm_tag_shape_is_connectivity(shape))
        return type == EMM_I32 || type == EMM_U32 || type == EMM_I64 || type == EMM_U16;
    if (kind == EMM_ARRAY_VERTICES || shape == EMM_TAG_SOUP)
        return type == EMM_F32 || type == EMM_F64;
    if (kind == EMM_ARRAY_TRIANGLES)
        return type == EMM_I32 || type == EMM_U32 || type == EMM_I64 || type == EMM_U16;
    return false;
}


/* The copy of the array's bytes a program in another process sent goes:
 * the array changed (or left), and it is asked for again when needed. */
static void forget_view(session_array *a)
{
    free(a->view);
    a->view = NULL;
}

/* An array leaves (freed, moved, re-tagged). When the window holds records
 * of it and the decision is still to come, its coordinates or indices are
 * copied first — a program that frees its mesh before exit still gets its
 * short run decided at finish; without memory for that, those records are
 * dropped at the decision. */
/* The mesh a decision read from the arrays (its triangles, coordinates,
 * half-edge connectivity): gone, to be read again at the next decision. */
static void forget_geometry(session *s)
{
    free(s->tri);
    free(s->xyz);
    s->tri = NULL;
    s->xyz = NULL;
    session_halfedge_free(s);
    memset(&s->info.geometry, 0, sizeof s->info.geometry);
    s->vertex_only = false;
}

static void drop_slot(session *s, int i, bool keep)
{
    session_array *a = &s->arrays[i];
    const unsigned char *bytes = session_bytes(s, a);
    if ((s->phase == PHASE_PROFILING || s->phase == PHASE_DECIDE ||
         s->phase == PHASE_DEFERRED) &&
        (a->refs > 0 || keep) && !a->snap && bytes) {
        size_t sb = session_scalar_bytes(a->type);
        unsigned ns = session_scalars(a);
        unsigned char *snap = malloc(a->count * ns * sb);
        for (uint64_t k = 0; snap && k < a->count; k++)
            for (unsigned c = 0; c < ns; c++)
                memcpy(snap + (k * ns + c) * sb, session_scalar_at(s, a, k, c), sb);
        a->snap = snap;
    }
    forget_view(a);
    a->live = false;
    if (s->last == i)
        s->last = -1;
    if (s->last2 == i)
        s->last2 = -1;
}

const char *session_origin(const session *s, const session_array *a, char *buf, size_t cap)
{
    (void)s;
    if (a->origin)
        snprintf(buf, cap, "%s", a->origin);
    else
        snprintf(buf, cap, "the emm_tag_%s call",
                 a->kind == EMM_ARRAY_VERTICES ? "vertices" : "triangles");
    return buf;
}

/* Drops the live arrays other than `keep` that overlap [lo, hi). */
static void drop_overlaps(session *s, uint64_t lo, uint64_t hi, int keep)
{
    for (int i = 0; i < s->narrays; i++)
        if (i != keep && s->arrays[i].live && s->arrays[i].base < hi && lo < s->arrays[i].end)
            drop_slot(s, i, false);
}

/* Whether slot i is the lead of another slot's group (it must then stay). */
static bool leads_others(const session *s, int i)
{
    for (int j = 0; j < s->narrays; j++) {
        const session_array *b = &s->arrays[j];
        if (j != i && b->lead == i && (b->live || b->refs || b->snap || b->trace_index >= 0))
            return true;
    }
    return false;
}

/* The group the axis block in slot i (its fields set but for `lead`)
 * joins: that of a live axis block of another axis, the same count,
 * stride and type, whose group has no live block of slot i's axis yet; or
 * its own. */
static int group_of(const session *s, int i)
{
    const session_array *a = &s->arrays[i];
    for (int j = 0; j < s->narrays; j++) {
        const session_array *b = &s->arrays[j];
        if (j == i || !b->live || b->axis < 0 || b->axis == a->axis || b->count != a->count ||
            b->stride != a->stride || b->type != a->type)
            continue;
        bool taken = false;
        for (int k = 0; k < s->narrays && !taken; k++)
            taken = k != i && s->arrays[k].live && s->arrays[k].lead == b->lead &&
                    s->arrays[k].axis == a->axis;
        if (!taken)
            return b->lead;
    }
    return i;
}

static int engine_tag(emm_session *h, const emm_array_desc *d)
{
    session *s = (session *)h;
    emm_array_kind kind = d->kind;
    emm_tag_shape shape = d->shape;
    emm_scalar type = d->type;
    uint64_t lo = (uint64_t)(uintptr_t)d->base, count = d->count, stride = d->stride,
             field_offset = d->offset, span;
    /* A column-major block's `count` entries are three columns of
     * count / 3. */
    uint64_t plane = 0;
    if (shape == EMM_TAG_COLUMNS) {
        count /= 3;
        plane = count * stride;
    }
    int axis = shape == EMM_TAG_AXIS ? d->axis : -1;
    int rule = (int)d->rule - 1;
    unsigned field_scalars = shape == EMM_TAG_SOUP ? 9
                             : shape == EMM_TAG_COLUMNS || shape == EMM_TAG_AXIS ||
                                     emm_tag_shape_is_connectivity(shape)
                                 ? 1
                                 : 3;
    /* A half-edge record's other fields lie in it too. */
    uint32_t hoff[1 + EMM_TAG_LINKS] = {(uint32_t)field_offset};
    unsigned hhas = 1;
    for (int k = 0; k < EMM_TAG_LINKS; k++) {
        hoff[1 + k] = (uint32_t)field_offset;
        if (shape != EMM_TAG_HALFEDGES || d->link[k] == EMM_TAG_NO_LINK)
            continue;
        if ((uint64_t)d->link[k] + session_scalar_bytes(type) > stride)
            return -1;
        hoff[1 + k] = d->link[k];
        hhas |= 1u << (1 + k);
    }
    if (shape == EMM_TAG_HALFEDGES &&
        (!(hhas & 1u << (1 + EMM_TAG_LINK_NEXT)) || !(hhas & 1u << (1 + EMM_TAG_LINK_FACE))))
        return -1;
    if (axis > 2 || d->rule > INT_MAX)
        return -1;
    if (s->phase == PHASE_FAILED || s->phase == PHASE_DONE || !lo || count == 0 ||
        stride == 0 || ((plane || axis >= 0) && stride > UINT32_MAX / 3) || !valid_field(kind, shape, type) ||
        field_offset > stride ||
        field_scalars * session_scalar_bytes(type) > stride - field_offset ||
        __builtin_mul_overflow(count, stride * (plane ? 3 : 1), &span) ||
        lo > UINT64_MAX - span)
        return -1;
    drop_overlaps(s, lo, lo + span, -1);
    /* A slot is free when nothing refers to it any more: not live, not named
     * by a window record, not feeding a trace array, not its group's lead. */
    int slot = -1;
    for (int i = 0; i < s->narrays && slot < 0; i++)
        if (!s->arrays[i].live && s->arrays[i].refs == 0 && s->arrays[i].trace_index < 0 &&
            !s->arrays[i].snap && !leads_others(s, i))
            slot = i;
    int32_t tidx = -1;
    int part = -1;
    if (s->phase == PHASE_SIMULATING) {
        /* After the decision the trace's arrays are fixed; an array that
         * moved (realloc) keeps feeding its trace array if it is the same
         * kind of record, up to the count the trace knows. */
        for (int i = 0; i < s->narrays && tidx < 0; i++) {
            session_array *a = &s->arrays[i];
            if (a->live || a->trace_index < 0 || a->kind != kind || a->stride != stride ||
                a->field != field_offset || a->type != type || a->shape != shape ||
                a->axis != axis)
                continue;
            /* An axis block's trace array is its mesh's: bound when a live
             * block of that axis feeds it. */
            bool bound = false;
            for (int j = 0; j < s->narrays; j++)
                if (s->arrays[j].live && s->arrays[j].trace_index == a->trace_index &&
                    s->arrays[j].axis == axis)
                    bound = true;
            if (!bound) {
                tidx = a->trace_index;
                part = a->part; /* a connectivity array's part goes with it */
                a->trace_index = -1; /* handed over */
                a->part = -1;
                if (slot < 0 && a->refs == 0)
                    slot = i;
            }
        }
    }
    char *origin = d->origin ? strdup(d->origin) : NULL;
    if (d->origin && !origin)
        return -1;
    if (slot < 0) {
        if (s->narrays == s->carrays) {
            int cap = s->carrays ? 2 * s->carrays : 8;
            session_array *grown = cap > s->carrays && (size_t)cap < SIZE_MAX / sizeof *grown
                                       ? realloc(s->arrays, (size_t)cap * sizeof *grown)
                                       : NULL;
            if (!grown) {
                free(origin);
                return -1;
            }
            s->arrays = grown;
            s->carrays = cap;
        }
        slot = s->narrays++;
        memset(&s->arrays[slot], 0, sizeof s->arrays[slot]);
    }
    session_array *a = &s->arrays[slot];
    free(a->origin);
    a->origin = origin;
    a->kind = kind;
    a->base = lo;
    a->end = lo + span;
    a->count = count;
    a->stride = stride;
    /* floor((2^64 - 1) / d) + 1, which is 2^64 (no multiplier) for d = 1. */
    a->stride_m = stride > 1 && stride <= UINT32_MAX ? UINT64_MAX / stride + 1 : 0;
    a->field = field_offset;
    a->type = type;
    a->shape = shape;
    a->plane = plane;
    a->axis = axis;
    a->lead = axis >= 0 ? group_of(s, slot) : slot;
    a->live = true;
    a->refs = 0;
    a->snap = NULL;
    forget_view(a);
    a->trace_index = tidx;
    a->part = part;
    memcpy(a->hoff, hoff, sizeof a->hoff);
    a->hhas = hhas;
    a->rule = rule;
    a->top = 0;
    a->moves = 0;
    if (s->phase == PHASE_SIMULATING && tidx < 0) {
        /* Tagged after the decision, and no trace array to feed: its
         * accesses are not simulated, and the summary says so. */
        if (s->nlate < SESSION_LATE_KEPT) {
            late_array *l = &s->late[s->nlate++];
            l->kind = kind;
            l->count = count;
            l->stride = stride;
            session_origin(s, a, l->origin, sizeof l->origin);
        }
        s->late_total++;
    }
    if (part >= 0 && a->count > s->parts[part].count) {
        a->count = s->parts[part].count; /* later records are not in the trace */
        a->end = session_array_end(a);
    } else if (part < 0 && tidx >= 0 && a->count > s->tarrays[tidx].count) {
        a->count = s->tarrays[tidx].count; /* later elements are not in the trace */
        a->end = session_array_end(a);
    }
    return slot;
}

static emm_session_state engine_move(emm_session *h, uint64_t from, uint64_t lo, uint64_t count)
{
    session *s = (session *)h;
    uint64_t span;
    for (int i = 0; i < s->narrays; i++) {
        session_array *a = &s->arrays[i];
        if (!a->live || a->base != from)
            continue;
        if (a->shape == EMM_TAG_COLUMNS)
            count /= 3; /* entries: three columns */
        if (!lo || count == 0 ||
            __builtin_mul_overflow(count, session_record_bytes(a), &span) ||
            lo > UINT64_MAX - span) {
            drop_slot(s, i, false);
            break;
        }
        drop_overlaps(s, lo, lo + span, i);
        a->base = lo;
        a->count = count;
        if (a->plane)
            a->plane = count * a->stride;
        a->moves++;
        forget_view(a); /* of the old block */
        uint64_t room = a->part >= 0 ? s->parts[a->part].count
                        : a->trace_index >= 0 ? s->tarrays[a->trace_index].count
                                              : UINT64_MAX;
        if (a->count > room)
            a->count = room; /* later elements are not in the trace */
        if (a->top > a->count)
            a->top = a->count;
        a->end = session_array_end(a);
        break;
    }
    return public_state(s);
}

static emm_session_state engine_untag(emm_session *h, uint64_t lo)
{
    session *s = (session *)h;
    for (int i = 0; i < s->narrays; i++) {
        session_array *a = &s->arrays[i];
        if (!a->live || a->base != lo)
            continue;
        /* The last array of its kind leaves before the window closed: the
         * decision comes now, on its fields copied while they can still be
         * read ("freeze the data"). A growing std::vector frees its old
         * buffer after the new one is tagged, so it does not end the
         * window. */
        /* Of its kind: a half-edge mesh's faces and vertex connectivity are
         * beside its half-edges and positions, which decide alone. */
        bool last = s->phase == PHASE_PROFILING && a->shape != EMM_TAG_FACES &&
                    a->shape != EMM_TAG_VCONN;
        for (int j = 0; j < s->narrays && last; j++)
            last = j == i || !s->arrays[j].live || s->arrays[j].kind != a->kind ||
                   (s->arrays[j].shape == EMM_TAG_HALFEDGES) != (a->shape == EMM_TAG_HALFEDGES) ||
                   s->arrays[j].shape == EMM_TAG_FACES || s->arrays[j].shape == EMM_TAG_VCONN;
        drop_slot(s, i, last);
        if (last) {
            s->phase = PHASE_DECIDE;
            s->wend = s->waited ? WINDOW_FULL : WINDOW_FREED; /* a full window that waited */
        }
    }
    return public_state(s);
}

static size_t engine_ranges(const emm_session *h, uint64_t *lo, uint64_t *hi, size_t cap)
{
    const session *s = (const session *)h;
    size_t n = 0;
    if (s->phase == PHASE_FAILED || s->phase == PHASE_DONE || s->phase == PHASE_DEFERRED)
        return 0;
    for (int i = 0; i < s->narrays; i++) {
        const session_array *a = &s->arrays[i];
        if (!a->live || ((s->phase == PHASE_SIMULATING || s->deciding) && a->trace_index < 0))
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

static inline bool in_slot(const session *s, int i, uint64_t addr)
{
    return i >= 0 && addr - s->arrays[i].base < s->arrays[i].end - s->arrays[i].base;
}

static inline int find_array(session *s, uint64_t addr)
{
    int last = s->last;
    if (in_slot(s, last, addr))
        return last;
    int other = s->last2;
    if (in_slot(s, other, addr)) {
        s->last2 = last;
        s->last = other;
        return other;
    }
    for (int i = 0; i < s->narrays; i++) {
        const session_array *a = &s->arrays[i];
        if (a->live && addr - a->base < a->end - a->base) {
            if (last >= 0)
                s->last2 = last;
            s->last = i;
            return i;
        }
    }
    return -1;
}

/* n / a->stride: a multiply and a shift for n and the stride below 2^32,
 * floor(n / d) = (M n) >> 64 with M = floor((2^64 - 1) / d) + 1, exact for
 * every such n and d (Lemire, Kaser & Kurz, "Faster remainder by direct
 * computation", 2019); the record loop's per-access division otherwise. */
static inline uint64_t div_stride(const session_array *a, uint64_t n)
{
    if (a->stride_m && n <= UINT32_MAX)
        return (uint64_t)(((unsigned __int128)a->stride_m * n) >> 64);
    return n / a->stride;
}

/* Converts one raw access into *r (array = the slot); false when it is not
 * a mesh access (its work is carried to the next one). */
static inline bool convert(session *s, const emm_raw_access *raw, emm_trace_record *r)
{
    uint32_t bytes = raw->bytes_write & ~EMM_RAW_WRITE;
    int i = find_array(s, raw->addr);
    s->pending_work += raw->work;
    if (i < 0 || bytes == 0)
        return false;
    session_array *a = &s->arrays[i];
    /* An axis block's entries are its coordinate of the record: the
     * record's x, y, z sit at offsets 0, stride, 2 stride, as a column-major
     * array's. */
    uint64_t rel = raw->addr - a->base, column = a->axis > 0 ? (uint64_t)a->axis : 0;
    if (a->plane) {
        /* Column-major: the same element in each of the three columns,
         * its x, y, z entries one record of the trace. */
        column = rel / a->plane;
        rel -= column * a->plane;
    }
    r->element = div_stride(a, rel);
    if (r->element >= a->count)
        return false; /* a column's entries past the records in use */
    if (r->element >= a->top) {
        /* A half-edge mesh that grows in the window is still being built. */
        s->he_grew += emm_tag_shape_is_connectivity(a->shape) && s->wopen &&
                      s->phase == PHASE_PROFILING && (raw->bytes_write & EMM_RAW_WRITE);
        a->top = r->element + 1;
    }
    r->offset = (uint32_t)(rel - r->element * a->stride + column * a->stride);
    r->array = (uint32_t)i;
    /* A trace record stays within one record of its array (trace.h): a
     * wider access, which only a tag with a stride smaller than the
     * program's loads makes, is counted as the whole record. */
    r->bytes = bytes < a->stride ? bytes : (uint32_t)a->stride;
    if (r->bytes > EMM_TRACE_MAX_ACCESS_BYTES)
        r->bytes = EMM_TRACE_MAX_ACCESS_BYTES;
    r->work = s->pending_work > UINT32_MAX ? UINT32_MAX : (uint32_t)s->pending_work;
    r->write = (raw->bytes_write & EMM_RAW_WRITE) != 0;
    r->pc = raw->pc;
    s->pending_work = 0;
    return true;
}

/* Whether an array of a kind the rules name has yet to be tagged. */
static bool expects_more(const session *s)
{
    unsigned have = 0;
    for (int i = 0; i < s->narrays; i++)
        if (session_usable(&s->arrays[i]))
            have |= 1u << s->arrays[i].kind;
    return (s->expect & ~have) != 0;
}

/* Whether the window's element reads are in: its length, read on until
 * their records fill the local store (window_fill.h). */
static bool window_reached(session *s)
{
    if (!s->cfg.window_accesses || s->welements < s->cfg.window_accesses)
        return false;
    if (!s->wsized) {
        /* At its length: read on only for a mesh the store cannot hold,
         * and not under a capture that stops at the decision (its answer
         * covers the window, and each access it captures costs the program
         * microseconds). */
        uint64_t mesh = 0;
        for (int i = 0; i < s->narrays; i++) {
            const session_array *a = &s->arrays[i];
            if (session_usable(a) && !emm_tag_shape_is_connectivity(a->shape) &&
                (a->axis < 0 || a->lead == i))
                mesh += a->count * session_trace_record_bytes(s, a);
        }
        window_fill_size(&s->wstore, session_window_only(s) ? 0 : mesh);
        s->wsized = true;
    }
    return window_fill_done(&s->wstore, s->cfg.window_accesses, s->welements);
}

/* The window ends when its element reads (or iterations) are in; writes
 * neither open, fill nor end it. It also ends, short, at the bounds that
 * keep capture in memory and time: SESSION_WINDOW_WRITES written records,
 * wlimit records in all (a program that reads few elements many times),
 * and under a window-only capture SESSION_CAPTURE_WINDOWS windows of
 * element accesses. A full window that waits for an array of a kind the
 * rules name goes on up to SESSION_WAIT_WINDOWS windows of reads. */
static void window_full_check(session *s)
{
    if (s->phase != PHASE_PROFILING)
        return;
    uint64_t w = s->cfg.window_accesses ? s->cfg.window_accesses : EMM_PROFILE_DEFAULT_WINDOW;
    enum window_end end = WINDOW_OPEN;
    if (window_reached(s) ||
        (s->cfg.window_iterations && s->iterations >= s->cfg.window_iterations))
        end = WINDOW_FULL;
    if (s->wwrites >= SESSION_WINDOW_WRITES)
        end = WINDOW_WRITES;
    else if (session_window_only(s) && s->wactivity >= SESSION_CAPTURE_WINDOWS * w)
        end = WINDOW_CAPTURE;
    else if (s->wn >= s->wlimit)
        end = WINDOW_RECORDS;
    if (end == WINDOW_OPEN)
        return;
    if (end == WINDOW_FULL && s->expect && s->welements < SESSION_WAIT_WINDOWS * w &&
        expects_more(s)) {
        s->waited = s->wlen && s->welements > s->wlen ? s->welements - s->wlen : 1;
        return;
    }
    if (s->waited && s->wlen && s->welements > s->wlen)
        s->waited = s->welements - s->wlen;
    if (s->wend == WINDOW_OPEN || s->wend == WINDOW_FULL)
        s->wend = end;
    s->phase = PHASE_DECIDE;
}

static void window_add(session *s, const emm_raw_access *a, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        emm_trace_record r;
        if (!convert(s, &a[k], &r))
            continue;
        uint32_t g = session_group(s, r.array); /* the element's array, for the counts */
        /* Until the first read of the mesh, the program is loading it: the
         * thesis measures from the moment the mesh is frozen in memory (§5),
         * so the loader's writes are counted, not buffered nor simulated. */
        /* A write before the traversal's first profiled read is the
         * loader's too: a loader that reads what it wrote (a growing
         * std::vector copies its elements, an index-order sweep) opened the
         * window, but the traversal has not begun. */
        if (!s->wopen || (r.write && s->welements == 0)) {
            /* Writes never open the window, however many: a converter
             * loads its whole mesh before it reads it once. Fault capture
             * pays for them once a page while the program builds
             * (emm_guard_build_open). */
            if (r.write) {
                s->loader_writes++;
                continue;
            }
            s->wopen = true;
        }
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
        bool next = !s->wwany || g != s->wwlast_array || r.element != s->wwlast_element;
        s->wwany = true;
        s->wwlast_array = g;
        s->wwlast_element = r.element;
        /* Counted from the traversal's first profiled read: a loader's
         * sweeps (a growing vector's copies) before it do not end the
         * window under fault capture. */
        s->wactivity += next && s->welements > 0;
        if (r.write) {
            s->wwrites++;
        } else {
            s->wreads++;
        }
        /* An element access as the profiler counts it: reads only (the
         * loader's writes are not the traversal: the window opens when the
         * mesh is frozen, thesis §5), consecutive reads of one element
         * count once. */
        if (s->phase == PHASE_PROFILING && !r.write &&
            (!s->wany || g != s->wlast_array || r.element != s->wlast_element)) {
            s->wany = true;
            s->wlast_array = g;
            s->wlast_element = r.element;
            /* The profile starts after a leading index-order sweep (reading
             * the file, initialising per-element data), whose records are
             * still simulated: runtime/lead_sweep.h. */
            int step = lead_sweep_step(&s->sweep, g, r.element);
            s->welements += (uint64_t)step;
            if (step > 0 && !s->wfill)
                window_fill_add(&s->wstore, g, r.element,
                                session_trace_record_bytes(s, &s->arrays[r.array]));
            /* Where the window filled, to the record: the batch's further
             * records join it, but the decision sees it up to here, as emm
             * profile does on the trace; the contest counts in windows of
             * its length, where it was before it read on. */
            if (!s->wlength && s->cfg.window_accesses && s->welements >= s->cfg.window_accesses)
                s->wlength = s->wn;
            if (!s->wfill && window_reached(s)) {
                s->wfill = s->wn;
                s->wlen = s->welements;
            }
        }
        if (r.write || !s->sweep.over)
            s->wlimit++; /* the sweep's reads and the writes (SESSION_WINDOW_WRITES bounds
                            them) do not count against the window's records */
        window_full_check(s);
    }
}

static void simulate_part(session *s, const emm_trace_record *recs, size_t n)
{
    if (s->contest)
        contest_run(s->contest, recs, n);
    else
        emm_runner_run(s->runner, recs, n);
    if (s->trace && !s->trace_failed &&
        emm_trace_write(s->trace, recs, n, &s->trace_error) != EMM_OK) {
        s->trace_failed = true;
        emm_trace_writer_abort(s->trace);
        s->trace = NULL;
    }
    s->accesses += n;
    for (size_t k = 0; k < n; k++) {
        if (s->taccesses && recs[k].array < s->ntarrays)
            s->taccesses[recs[k].array]++;
        s->work += recs[k].work;
        s->elements += !s->eany || recs[k].array != s->elast_array ||
                       recs[k].element != s->elast_element;
        s->eany = true;
        s->elast_array = recs[k].array;
        s->elast_element = recs[k].element;
    }
    if (s->probing)
        session_phases_see(s, recs, n);
}

/* The records through the models, the outputs and the probes, cut where a
 * probe's outcome lands (SESSION_PROBE_LAG records after it filled) and in
 * parts no longer than that, so that a probe filled in a part lands in a
 * later one: the phases found are those of the records, not of the
 * capture's batches. */
void session_simulate(session *s, const emm_trace_record *recs, size_t n)
{
    while (n > 0) {
        size_t part = n < SESSION_PROBE_LAG ? n : SESSION_PROBE_LAG;
        if (s->probing && s->probe_job && s->probe_apply > s->accesses &&
            s->probe_apply - s->accesses < part)
            part = (size_t)(s->probe_apply - s->accesses);
        simulate_part(s, recs, part);
        recs += part;
        n -= part;
    }
}

static void flush_chunk(session *s)
{
    if (s->nchunk) {
        session_simulate(s, s->chunk, s->nchunk);
        s->nchunk = 0;
    }
}

static emm_session_state engine_access(emm_session *h, const emm_raw_access *a, size_t n)
{
    session *s = (session *)h;
    if (n == 0) /* a question: the state (after a decision that started a window again) */
        return public_state(s);
    if (s->phase == PHASE_PROFILING || s->phase == PHASE_DECIDE) {
        session_window_clock(s, n);
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
        const session_array *sa = &s->arrays[r->array];
        int32_t t = sa->trace_index;
        if (t < 0 || (sa->part >= 0 && !session_part_map(s, sa, r))) {
            s->dropped++;
            continue;
        }
        r->array = (uint32_t)t;
        if (++m == SESSION_CHUNK) {
            session_simulate(s, s->chunk, m);
            m = 0;
        }
    }
    s->nchunk = m;
    return EMM_SESSION_SIMULATING;
}

static emm_session_state engine_iteration(emm_session *h)
{
    session *s = (session *)h;
    s->iterations++;
    window_full_check(s);
    return public_state(s);
}

/* The end of a decision (st: how it went): the window and the snapshots
 * are done with, and the session simulates or steps aside. */
static emm_status decide_done(session *s, emm_status st, emm_error *err)
{
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
    session_window_done(s);
    s->phase = PHASE_SIMULATING;
    return EMM_OK;
}

/* A half-edge mesh that did not check out when its window filled, or that
 * grew in it while hardly a position was read, is one still being built:
 * OpenMesh's add_face reads the half-edges it links, and those reads opened
 * the window. The window so far was the loader's: its records are left out (its writes counted as the loader's),
 * and a window starts again at the next read, up to
 * SESSION_HALFEDGE_RESTARTS times; then the decision waits for the end of
 * the run as for any mesh (PHASE_DEFERRED). */
static bool window_restart(session *s)
{
    bool connectivity = false;
    for (int i = 0; i < s->narrays && !connectivity; i++)
        connectivity = s->arrays[i].live && emm_tag_shape_is_connectivity(s->arrays[i].shape);
    if (!connectivity || s->restarts >= SESSION_HALFEDGE_RESTARTS ||
        !(emm_capture_caps(s->capture) & EMM_CAP_WHOLE_RUN) ||
        (s->wend != WINDOW_FULL && s->wend != WINDOW_RECORDS && s->wend != WINDOW_WRITES))
        return false;
    s->restarts++;
    s->restart_records += s->wn;
    s->he_grew = 0;
    s->loader_writes += s->wwrites;
    for (int i = 0; i < s->narrays; i++) {
        s->arrays[i].refs = 0;
        forget_view(&s->arrays[i]); /* read again at the next decision */
        if (!s->arrays[i].live) { /* a block the loader freed: its window's, gone with it */
            free(s->arrays[i].snap);
            s->arrays[i].snap = NULL;
        }
    }
    forget_geometry(s);
    s->soup = false;
    s->pick_note[0] = '\0';
    s->wn = 0;
    s->welements = s->iterations = s->wreads = s->wwrites = s->wactivity = 0;
    s->wopen = s->wany = s->wwany = false;
    s->wend = WINDOW_OPEN;
    s->waited = 0;
    memset(&s->sweep, 0, sizeof s->sweep);
    s->wskip = s->wfill = s->wlength = 0;
    window_start(s);
    s->phase = PHASE_PROFILING;
    return true;
}

/* Reads (or defers the decision, or fails); when it leaves s->deciding
 * set, engine_decide_rest completes it. */
static emm_status engine_decide_read(emm_session *h, emm_error *err)
{
    session *s = (session *)h;
    s->deciding = false;
    if (s->phase == PHASE_SIMULATING || s->phase == PHASE_DONE || s->phase == PHASE_DEFERRED)
        return EMM_OK;
    if (s->phase == PHASE_FAILED) {
        if (err)
            *err = s->failure;
        return s->failure.status;
    }
    /* The loader's window: its half-edge mesh grew while it filled, and
     * hardly a record of the positions it keeps was accessed (a loader's
     * growing vector copies its old blocks; a subdivider grows its mesh
     * too, but reads the positions it averages: its window is its
     * traversal's). */
    uint64_t positions = 0;
    for (int i = 0; i < s->narrays; i++)
        if (s->arrays[i].live && s->arrays[i].kind == EMM_ARRAY_VERTICES &&
            !emm_tag_shape_is_connectivity(s->arrays[i].shape))
            positions += s->arrays[i].refs;
    if (s->he_grew && positions * 100 < s->wn && !s->deferred && window_restart(s))
        return EMM_OK;
    emm_status st = session_decide_read(s, &s->failure);
    if (st == EMM_ERR_MESH && s->geometry_failed && !s->deferred && window_restart(s))
        return EMM_OK;
    if (st == EMM_ERR_MESH && s->geometry_failed && !s->deferred) {
        /* The arrays do not hold a mesh yet (a loader that renumbers its
         * faces after the first reads, a block still being filled): keep
         * the window and read them again at the end. */
        s->deferred = true;
        s->deferred_why = s->failure;
        forget_geometry(s);
        for (int i = 0; i < s->narrays; i++) /* copies of now: read again later */
            forget_view(&s->arrays[i]);
        s->phase = PHASE_DEFERRED;
        return EMM_OK;
    }
    if (st == EMM_OK) {
        s->deciding = true;
        return EMM_OK;
    }
    return decide_done(s, st, err);
}

static emm_status engine_decide_rest(emm_session *h, emm_error *err)
{
    session *s = (session *)h;
    if (!s->deciding)
        return EMM_OK;
    s->deciding = false;
    return decide_done(s, session_decide_rest(s, &s->failure), err);
}

static emm_status engine_decide(session *s, emm_error *err)
{
    emm_status st = engine_decide_read(&s->handle, err);
    if (st != EMM_OK || !s->deciding)
        return st;
    return engine_decide_rest(&s->handle, err);
}

/* An output that could not be written is said on the summary stream: the
 * program's user would otherwise look for a file that is not there. */
static void output_failed(const session *s, FILE *summary, const emm_error *e)
{
    if (summary && s->cfg.log >= 1) {
        fprintf(summary, "emm: %s\n", e->message);
        fflush(summary);
    }
}

static emm_status engine_finish(emm_session *h, FILE *summary, const char *ended,
                                emm_error *err)
{
    session *s = (session *)h;
    emm_status first = EMM_OK;
    emm_error e;
    if (s->phase == PHASE_DONE)
        return EMM_OK;
    if (ended)
        snprintf(s->ended, sizeof s->ended, "%s", ended);
    if (s->phase == PHASE_DEFERRED)
        s->phase = PHASE_DECIDE;
    if (s->phase == PHASE_PROFILING) {
        /* The run ended before the window filled: the decision rests on
         * the reads it had (a full window waiting for an array counts as
         * full, and so does one reading on to fill the local store). */
        s->phase = PHASE_DECIDE;
        bool reading_on = s->cfg.window_accesses && s->welements >= s->cfg.window_accesses;
        if (reading_on && !s->wfill) {
            s->wfill = s->wn;
            s->wlen = s->welements;
        }
        if (s->wend == WINDOW_OPEN)
            s->wend = s->waited || reading_on ? WINDOW_FULL : WINDOW_FINISH;
    }
    if (s->phase == PHASE_DECIDE)
        engine_decide(s, NULL);
    if (s->phase == PHASE_SIMULATING) {
        flush_chunk(s);
        /* Models with no record are no answer: the program ended before
         * reading its mesh, or the capture saw none of its reads. */
        if (s->accesses == 0) {
            if (s->loader_writes)
                emm_fail(&s->failure, EMM_ERR_UNSUPPORTED,
                         "%s: no read of the tagged arrays was seen, only %llu writes to them "
                         "(the loader's: the window opens at the first read, and the program "
                         "ended before one, or the %s capture saw none)",
                         s->program, (unsigned long long)s->loader_writes,
                         emm_capture_name(s->capture));
            else
                emm_fail(&s->failure, EMM_ERR_UNSUPPORTED,
                         "%s: no access to the tagged arrays was seen (the program ended before "
                         "reading them, or the %s capture saw none of their accesses)",
                         s->program, emm_capture_name(s->capture));
            s->phase = PHASE_FAILED;
        }
    }
    if (s->phase == PHASE_FAILED) {
        /* Nothing simulated: the summary says why, and so does the report
         * when one was asked for; the trace and the timeline have nothing
         * to hold. */
        session_lines_free(s);
        if (summary && s->cfg.log >= 1)
            session_print_summary(s, summary, NULL, 0);
        if (s->cfg.report[0] && session_write_nothing(s, &e) != EMM_OK)
            output_failed(s, summary, &e);
        if (err)
            *err = s->failure;
        s->phase = PHASE_DONE;
        return s->failure.status;
    }
    /* The models have run every record (their pipeline drained): what
     * their stall hooks counted is whole. */
    emm_runner_sync(s->runner);
    session_phases_close(s);
    /* The answer and the runner-up: the contest's finalists, or the
     * window's check, fastest first; then what is the answer's. */
    session_decide_answer(s);
    session_phases_answer(s);
    session_stall_lines(s);
    /* Every model, the answer first, those that could not be built with
     * only their strategy (the report says why), and without the contest's
     * dropped candidates, whose cycles stop short of the run; the summary
     * gets those that ran. */
    size_t nm = s->nmodels;
    emm_result *all = calloc(nm ? 2 * nm : 1, sizeof *all);
    emm_error *why = calloc(nm ? nm : 1, sizeof *why);
    size_t *order = calloc(nm ? nm : 1, sizeof *order);
    size_t nres = 0, nall = 0;
    if (!all || !why || !order) {
        free(all);
        free(why);
        free(order);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the results", s->program);
    }
    size_t first_model = s->answer_model != SIZE_MAX ? s->answer_model : 0;
    if (nm)
        order[nall++] = first_model;
    for (size_t i = 0; i < nm; i++)
        if (i != first_model && !(s->contest && contest_retired(s->contest, i)))
            order[nall++] = i;
    emm_result *res = all + nm;
    for (size_t j = 0; j < nall; j++) {
        size_t i = order[j];
        emm_model *m = emm_runner_model(s->runner, i);
        all[j].strategy = s->mstrat[i];
        why[j] = s->merr[i];
        if (!m)
            continue;
        emm_model_result(m, &all[j]);
        if (s->cfg.report[0]) /* the report's per-cell DMA bytes; no cells is no error */
            emm_model_cells(m, &all[j], NULL);
        res[nres++] = all[j];
    }
    if (summary && s->cfg.log >= 1) {
        session_print_summary(s, summary, res, nres);
        fflush(summary);
    }
    if (s->cfg.report[0] && session_write_report(s, all, why, nall, summary, &e) != EMM_OK) {
        output_failed(s, summary, &e);
        if (first == EMM_OK && err)
            *err = e;
        first = first == EMM_OK ? e.status : first;
    }
    if (s->cfg.profile_dump[0] && session_write_csv(s, &e) != EMM_OK) {
        output_failed(s, summary, &e);
        if (first == EMM_OK && err)
            *err = e;
        first = first == EMM_OK ? e.status : first;
    }
    /* The trace is closed first: the timeline is the answer's run
     * simulated again over it. A private trace's failure is the
     * timeline's to tell. */
    session_trace_close(s);
    if (session_timeline_write(s, &e) != EMM_OK) {
        output_failed(s, summary, &e);
        if (first == EMM_OK && err)
            *err = e;
        first = first == EMM_OK ? e.status : first;
    }
    if (s->trace_failed && !s->trace_private) {
        emm_fail(&e, s->trace_error.status, "%s: %s", session_source(s, EMM_CONFIG_TRACE),
                 s->trace_error.message);
        output_failed(s, summary, &e);
        if (first == EMM_OK && err)
            *err = e;
        first = first == EMM_OK ? e.status : first;
    }
    for (size_t j = 0; j < nall; j++)
        emm_result_release(&all[j]);
    free(all);
    free(why);
    free(order);
    s->phase = PHASE_DONE;
    return first;
}

/* No output: the trace a session writes is removed (engine_free aborts it). */
static void engine_discard(emm_session *h)
{
    ((session *)h)->phase = PHASE_DONE;
}

/* A forked child's copy of an engine in this process: nothing to let go
 * (the shim keeps the child from calling it). */
static void engine_forked(emm_session *h)
{
    (void)h;
}

static void engine_free(emm_session *h)
{
    session *s = (session *)h;
    contest_free(s->contest);
    contest_free(s->window_rank);
    session_lines_free(s);
    emm_runner_free(s->runner);
    emm_model_share_unref(s->layouts);
    decide_cache_free(s->decisions);
    emm_window_decision_release(&s->wd);
    for (int i = 0; i < s->narrays; i++) {
        free(s->arrays[i].snap);
        free(s->arrays[i].view);
        free(s->arrays[i].origin);
    }
    free(s->arrays);
    free(s->modules);
    emm_machine_free(s->machine);
    emm_table_free(s->table);
    free(s->window);
    window_fill_free(&s->wstore);
    free(s->chunk);
    free(s->tarrays);
    free(s->mstrat);
    free(s->probe);
    session_phases_free(s);
    free(s->merr);
    free(s->xyz);
    free(s->tri);
    session_halfedge_free(s);
    free(s->D);
    free(s->program);
    free(s);
}

static const struct session_transport engine_transport = {
    engine_tag,         engine_move,      engine_untag,  engine_ranges,
    engine_access,      engine_iteration, engine_decide_read,
    engine_decide_rest, engine_finish,    engine_discard, engine_forked, engine_free,
};
