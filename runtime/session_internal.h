/* Internal to the session engine: its state, shared by the files that
 * split its jobs —
 *   session.c         lifecycle, tagged arrays, the window, the stream of
 *                     records through the models; the in-process transport
 *   session_decide.c  "freeze the data", the profile, the decision, the models
 *   session_phase.c   the run's phases, probed after the window
 *   session_lines.c   the trace, the timeline, the stall lines by source line
 *   session_report.c  the summary, the JSON report, the CSV
 * The engine is reached through the transport seam of session_transport.h
 * (in this process, or in emm-session through session_proxy.c); it never
 * asks which. include/emm/session.h has the contract. */
#ifndef EMM_RUNTIME_SESSION_INTERNAL_H
#define EMM_RUNTIME_SESSION_INTERNAL_H

#include <stdbool.h>
#include <stdio.h>

#include "emm/profile.h"
#include "emm/replay.h"
#include "emm/session.h"
#include "emm/sim.h"
#include "emm/table.h"
#include "contest.h"
#include "json.h"
#include "lead_sweep.h"
#include "window_fill.h"
#include "runner.h"
#include "session_transport.h"
#include "share.h"
#include "table_internal.h"

/* The source lines of the chosen strategy's stalls the summary and the
 * report name (when the capture knows program counters). */
#define SESSION_STALL_LINES 3

/* PHASE_DEFERRED: the geometry did not check out when the window closed
 * (an array the program had yet to finish): the window is kept, nothing
 * more is captured, and the geometry is read again at finish, from the
 * arrays as they are then or as they were when freed. */
enum session_phase {
    PHASE_PROFILING,
    PHASE_DECIDE,
    PHASE_DEFERRED,
    PHASE_SIMULATING,
    PHASE_FAILED,
    PHASE_DONE
};

enum decision_source { FROM_NONE, FROM_CONFIG, FROM_TABLE, FROM_CHECKED, FROM_SIMULATION };

/* Written records the window buffers at most: 2^20 records of 40 bytes,
 * 40 MiB, half of what a leading sweep of EMM_PROFILE_SWEEP_MAX element
 * reads (a record each at least) may buffer already. Writes after the
 * window opened are part of the simulated run (a smoother's results), so
 * they are kept, but they do not fill the window, whose length is in
 * reads: a program that writes a million records between its window's
 * reads is bounded by memory here, and the window ends with the reads it
 * has (window.ended_by "write_cap"). */
#define SESSION_WINDOW_WRITES (1u << 20)
/* Under a capture that sees the window only (fault capture pays tens of
 * microseconds an access until the decision), the window also ends after
 * this many window lengths of element accesses of either direction,
 * counted from its first profiled read: the loader's writes before the
 * window opened do not count (a loader faults once a page while it builds,
 * emm_guard_build_open), nor does a leading sweep (bounded by
 * EMM_PROFILE_SWEEP_MAX), so a converter's window is its reads. */
#define SESSION_CAPTURE_WINDOWS 2
/* A window that filled before an array of every kind the rules name was
 * tagged goes on until one is, up to this many window lengths of element
 * reads in all; the profile is still the first window's. */
#define SESSION_WAIT_WINDOWS 4

/* Why the profile window ended (docs/profile.md "The window"): WINDOW_FULL
 * is the only complete one; the others leave the decision to the reads the
 * window had (the summary and the report's window.complete say so). */
enum window_end {
    WINDOW_OPEN,     /* not ended yet */
    WINDOW_FULL,     /* its element reads (or iterations) */
    WINDOW_FINISH,   /* the run ended first */
    WINDOW_FREED,    /* the last array of a kind was freed */
    WINDOW_WRITES,   /* its written records reached SESSION_WINDOW_WRITES */
    WINDOW_RECORDS,  /* its records reached the buffer's bound (few elements, many reads) */
    WINDOW_CAPTURE   /* a window-only capture's bound on element accesses */
};

/* The most times a window starts again because its half-edge mesh did not
 * check out (session.c, window_restart): a loader's reads are a few
 * windows' worth per 10,000 faces. */
#define SESSION_HALFEDGE_RESTARTS 1024u

/* Arrays tagged after the decision that the run's trace has no place for
 * (docs/profile.md "Arrays tagged late"): the summary and the report name
 * the first SESSION_LATE_KEPT. */
#define SESSION_LATE_KEPT 4
typedef struct late_array {
    emm_array_kind kind;
    uint64_t count, stride;
    char origin[200];
} late_array;

/* Phases (docs/profile.md "Phases"): after the window the session profiles
 * probes of the run as long as the window, one every SESSION_PROBE_GAP + 1
 * window lengths; two probes in a row whose pattern differs from the
 * current phase's (the same new pattern; a weak match only with new code)
 * start a phase, whose best candidate is decided on the probe and
 * simulated from there on, cold, as a switch would start. */
#define SESSION_MAX_PHASES 8
#define SESSION_PROBE_GAP 7
/* A probe's outcome is applied this many records after the one that
 * filled it, to the record (session_simulate cuts its batch there): its
 * profile is worked out meanwhile beside the run, and what it finds does
 * not depend on the capture's batches. */
#define SESSION_PROBE_LAG 262144
/* A phase's pattern check synthesises its long run at most this many probe
 * lengths (of element accesses) long, an eighth of the window's at the
 * default window: the phase's candidate is a proposal that its own model
 * then measures from the detection on, not the answer. */
#define SESSION_PHASE_SYNTH_PROBES 2
/* A probe whose pattern differs from the current phase's, but only weakly
 * (farther than EMM_WEAK_MATCH from its sample), argues for a new phase
 * only when at least this share of its mesh reads come from program
 * counters the current phase has not run: new code. A periodic program's
 * probes land on different stretches of the same loops and their weak
 * matches scatter over every pattern; a new traversal runs new code. */
#define SESSION_PHASE_NEW_CODE 0.5
/* A probe of the current phase's code (less than SESSION_PHASE_NEW_CODE of
 * new code) can argue for a phase only by a strong match: its profile, most
 * of a probe's cost, is worked out only when its moves are new to the
 * phase (below), and otherwise for every (SESSION_PROBE_OLD_SKIP + 1)th
 * such probe in a row. */
#define SESSION_PROBE_OLD_SKIP 15
/* The program counters a phase's set keeps at most (past it, the set stops
 * growing, and unseen code counts as new). */
#define SESSION_PHASE_PCS_MAX 65536u
/* A probe's moves (session_phase.c, moves_of): for vertices and for
 * triangles, the share of its element reads in each power-of-two band of id
 * distance from the read of that kind before. A probe of old code whose
 * moves lie within SESSION_PROBE_MOVED (the larger of the two kinds' half
 * L1 distances) of moves the current phase already showed — the window's, or
 * a probe's that was profiled and found the phase's own pattern — has not
 * moved and is left unprofiled, but for one in SESSION_PROBE_OLD_SKIP + 1
 * in a row; the phase remembers the last SESSION_MOVE_REFS such moves. */
#define SESSION_MOVE_BUCKETS 34
#define SESSION_MOVE_SIZE (2 * SESSION_MOVE_BUCKETS)
#define SESSION_MOVE_REFS 8
#define SESSION_PROBE_MOVED 0.1

/* Distinct program counters (sorted; 0, unknown, left out). */
typedef struct pc_set {
    uint64_t *pc;
    size_t n;
} pc_set;

typedef struct program_phase {
    uint64_t start;       /* accesses simulated before its first probe */
    char pattern[EMM_TABLE_NAME_MAX];
    char nearest[EMM_TABLE_NAME_MAX];
    double distance;
    bool has_best;        /* the best candidate on its probe is known */
    emm_strategy best;
    size_t model;         /* the runner's model of `best` started at detection, or SIZE_MAX */
    uint64_t detected;    /* accesses simulated when it was detected */
    uint64_t chosen_at;   /* the chosen strategy's cycles then */
    uint64_t chosen_span; /* at its end: the answer's cycles since detection (the chosen
                             strategy's until the answer is known) */
    uint64_t best_span;   /* and `best`'s, started cold at detection */
    uint64_t *at, *end;   /* every model's cycles at detection and at its end (nat of
                             them; NULL without memory): the answer's span, once the
                             contest has named it */
    size_t nat;
    bool best_is_answer;  /* `best` is the answer's strategy: nothing to switch to */
    bool closed;
} program_phase;

typedef struct session_array {
    emm_array_kind kind;
    uint64_t base, end;  /* [base, end) */
    uint64_t count, stride, field;
    uint64_t stride_m;   /* for rel / stride by a multiply (session.c, div_stride); 0: divide */
    emm_scalar type;
    emm_tag_shape shape; /* records, columns or a soup (its EMM_TAG rule's; records for an
                            emm_tag_* call) */
    uint64_t plane;      /* columns: the bytes from the x column to the y column (the
                            block's capacity of entries times stride); 0 otherwise */
    int axis;            /* an axis block (EMM_TAG x=, y=, z=): its coordinate, 0..2; else -1 */
    int lead;            /* the slot that stands for its group in the window's element
                            counts: an axis block's, the first of the x, y, z blocks of one
                            count, stride and type tagged together (one mesh's vertices);
                            the slot itself otherwise */
    bool live;           /* tagged now */
    unsigned char *snap; /* the fields, copied when the array went away before the
                            decision while the window named it; else NULL */
    uint64_t refs;       /* window records that name this slot */
    int32_t trace_index; /* the trace array it feeds after the decision, or -1 */
    int rule;            /* the EMM_TAG rule that selected the block, from 0 (count is its
                            capacity), or -1 for an emm_tag_* call */
    char *origin;        /* who described it (emm_array_desc.origin), malloc'ed, or NULL */
    uint64_t top;        /* 1 + the highest element accessed since it was tagged */
    unsigned moves;      /* reallocations since it was tagged */
    unsigned char *view; /* a program in another process (emm_session_config.memory): a
                            copy of [base, end) as it was last read, owned; else NULL */
    uint32_t hoff[1 + EMM_TAG_LINKS]; /* EMM_TAG_HALFEDGES: the offsets of to, next, prev,
                            face, opp in a record (an absent field: the to field's offset) */
    unsigned hhas;       /* of them, bit k: field k is in the record */
    int part;            /* connectivity after the decision: its part of a trace array
                            (session.parts), or -1 */
} session_array;

/* Half-edge connectivity in the trace (session_halfedge.c): a program's
 * faces, half-edges or vertex connectivity records are a part of another
 * trace array's records — a face's record and its cycle's three half-edges
 * are the derived triangle's record, a vertex's connectivity record follows
 * its position — so the layouts place them in their triangle's (vertex's)
 * cell. An access to element e of the program's array is one to element
 * remap[e] (e without remap; UINT32_MAX: none, not simulated) of the trace
 * array, at `base` + pos[e] * stride (pos NULL: 0) + its own offset. */
typedef struct session_part {
    emm_tag_shape shape;
    int32_t trace;       /* the trace array */
    uint32_t base, stride;
    uint64_t count;      /* the program's records in it */
    uint32_t *remap;     /* count of them, or NULL */
    uint8_t *pos;        /* count of them, or NULL */
    uint64_t accesses;   /* simulated */
} session_part;

/* The element read last (session_phase.c, element_read). */
struct last_read {
    bool any;
    uint32_t array;
    uint64_t element;
};

/* The engine behind an emm_session handle in this process. */
typedef struct session {
    emm_session handle;  /* first: the public handle is the engine's address */
    /* A program in another process (emm_session_config.memory): the tagged
     * arrays are readable only through copies of them, and the program's
     * objects are those it reports; NULL: this process. */
    const emm_session_memory *memory;
    emm_session_memory mem; /* the copy memory points to */
    emm_trace_module *modules; /* the objects it reported: malloc'ed, one block */
    uint32_t nmodules;
    emm_config cfg;      /* the settings, parsed (a copy, without the tag rules: each
                            array's description comes whole) */
    char *program;
    long pid;            /* the program's */
    char ended[96];      /* how the run ended when not normally ("": an exit) */
    emm_capture capture;
    struct timespec started; /* CLOCK_REALTIME_COARSE at its start: a report written
                                since is another process's (session_write_nothing) */
    struct timespec wclock; /* CLOCK_MONOTONIC at the first record (session_window_clock) */
    uint64_t wraw;       /* records given until the decision */
    double wseconds;     /* from the first record to the decision; < 0: not timed */
    emm_threads threads;  /* the caller's, with on_start wrapped (session.c, beside_start) */
    emm_threads caller_threads; /* the caller's as given */
    emm_machine *machine;
    emm_table *table;    /* NULL: no table (a configured strategy without one) */

    enum session_phase phase;
    emm_error failure;   /* why the session stepped aside (PHASE_FAILED) */
    bool geometry_failed; /* the last decision failed reading the geometry */
    bool deferred;       /* the decision waited for the program's end (PHASE_DEFERRED) */
    bool deciding;       /* session_decide_begin read the program: _end is due */
    emm_error deferred_why; /* what the geometry was when the window closed */

    session_array *arrays; /* narrays of them in use, carrays allocated */
    int narrays, carrays;
    int last;            /* the slot the previous access hit */
    int last2;           /* and the one before it, of another slot (a triangle's index
                            and then its vertices: two arrays by turns) */
    uint64_t pending_work; /* work of dropped accesses, carried to the next record */

    /* the window */
    emm_trace_record *window;
    size_t wn, wcap, wlimit;
    uint64_t welements, iterations;
    uint64_t wreads, wwrites; /* the window's records by direction */
    uint64_t wactivity;  /* its element accesses of either direction, counted alike, from
                            the first profiled read on */
    bool wwany;
    uint32_t wwlast_array;
    uint64_t wwlast_element;
    bool wopen;          /* the first read of the mesh came: the window is open */
    uint64_t loader_writes; /* writes before it: the loader's, not simulated */
    bool wany;
    uint32_t wlast_array;
    uint64_t wlast_element;
    enum window_end wend; /* why the window ended (WINDOW_OPEN until it did) */
    unsigned expect;     /* the kinds of array the tag rules name (1 << emm_array_kind) */
    unsigned missing;    /* of them, those with no array at the decision */
    uint64_t waited;     /* element reads the window went on for, past its length, waiting
                            for an array of an expected kind to be tagged (0: none) */
    bool sweep_profiled; /* every read was a leading index-order sweep: it was profiled as
                            the traversal */
    late_array late[SESSION_LATE_KEPT]; /* tagged after the decision, not simulated */
    int nlate;           /* of them kept */
    uint64_t late_total; /* and in all */
    lead_sweep sweep;    /* the leading index-order sweep */
    size_t wskip;        /* window records of that sweep (the profiler's count) */
    size_t wfill;        /* records when the window's element reads filled it (0: never) */
    uint64_t wlen;       /* its element reads then: its length, or more when it read on
                            until it filled the local store (0: never) */
    window_fill wstore;  /* the bytes of the distinct records it has read */
    bool wsized;         /* the mesh's bytes were weighed against the store's */
    size_t wunit;        /* the same once the window is frozen: the decision's window */
    size_t wlength;      /* records when its element reads reached its length, before it
                            read on (0: never) */
    size_t wstep;        /* the same once frozen: the contest's unit, as long as the
                            window asked for whether or not it read on */

    /* frozen at the decision */
    emm_trace_array *tarrays;
    uint32_t ntarrays;
    double *xyz;
    int32_t *tri;
    /* a half-edge mesh (session_halfedge.c): the slots read for it at the
     * decision (-1: none), the parts they feed, the accesses of each trace
     * array */
    int he_slot, face_slot, vconn_slot, vertex_slot;
    session_part parts[3];
    int nparts;
    uint32_t *he_owner;  /* per half-edge: its triangle, or UINT32_MAX */
    uint8_t *he_pos;     /* and its place in the triangle's record (0..2) */
    uint32_t *face_tri;  /* per face: its first triangle (a polygon is a fan of them) */
    uint64_t nfaces;
    uint64_t *taccesses; /* per trace array, simulated records */
    unsigned restarts;   /* windows started again: the half-edge mesh was being built */
    uint64_t restart_records; /* the records of those windows, left out */
    uint64_t he_grew;    /* connectivity records appended since the window opened */
    char pick_note[1024]; /* which of a rule's several arrays is the mesh, what a soup's
                             corners made, or "" */
    bool soup;           /* the triangles are a soup's: the vertices are their corners */
    bool vertex_only;    /* no triangle array: the geometry's triangles are the vertices,
                            each (v, v, v), and the layouts cut cells of vertices */
    emm_trace_info info;
    double *D;           /* the window's distance profile, nD values */
    size_t nD;
    bool has_profile;    /* features and a table decision exist */
    double features[EMM_FEATURES];
    emm_decision decision;
    emm_window_decision wd; /* the decision's simulation: runner-up, tie (has_wd) */
    bool has_wd;
    enum decision_source source;
    char strategy_note[512]; /* why the chosen strategy has no model, or "" */
    emm_strategy chosen;
    bool has_chosen;
    emm_runner *runner;  /* the chosen strategy first (when has_chosen), then the comparison,
                            then the contest's other candidates */
    emm_model_share *layouts; /* every layout built for this mesh, kept: the decision's
                                 sweeps, the models and the probes build each once */
    decide_cache *decisions; /* the canonical traversals' profiles and sweeps over this
                                mesh: the window's decision and the phases' compute each once */
    contest *contest;    /* the run's confirmation of the choice, or NULL (docs/profile.md
                            "The contest") */
    /* A capture that sees the window only: every candidate is simulated
     * over it beside the prediction, and an EMM strategy slower than direct
     * reads there is never the answer (session_decide_answer). */
    bool window_check;
    contest *window_rank; /* with it: every candidate over the window, none dropped (only
                             ranked at the end: contest_standing) */
    size_t direct_model; /* the runner's model of direct reads, or SIZE_MAX */
    /* At finish, with a contest or a window check: the models of the
     * answer and of the runner-up (SIZE_MAX: none); `ranked`: they are the
     * first two of the candidates ranked by their cycles (the contest's
     * finalists, or every candidate over the window when the prediction
     * lost to direct reads there), not the window's prediction. */
    size_t answer_model, runner_model;
    bool ranked;
    /* When the answer is an indexed variant (":indexed"): the best of the
     * ranked candidates that keeps the look-up table (an EMM strategy
     * without :indexed), whose cycles the summary sets against the
     * answer's; SIZE_MAX otherwise. Its total, read at finish. */
    size_t plain_model;
    uint64_t plain_total;
    size_t nmodels;      /* models added to the runner (built or skipped) */
    emm_strategy *mstrat; /* their strategies, nmodels */
    emm_error *merr;     /* why each could not be built (status != EMM_OK), nmodels */
    size_t skipped;      /* of them, the comparison's that cannot run on this mesh */
    emm_trace_writer *trace; /* EMM_TRACE, or the timeline's own (trace_private) */
    char trace_path[EMM_CONFIG_PATH_MAX];
    bool trace_private;  /* written for the timeline alone, in TMPDIR: removed at the end */
    emm_error trace_error;
    bool trace_failed;
    emm_trace_record *chunk;
    size_t nchunk;
    uint64_t accesses;   /* records simulated */
    uint64_t elements;   /* of them, element accesses (consecutive ones to one element count
                            once) */
    uint64_t work;       /* their work fields summed: the capture's count between accesses,
                            in its unit (emm_capture_work_unit) */
    bool eany;
    uint32_t elast_array;
    uint64_t elast_element;
    /* phases */
    program_phase phases[SESSION_MAX_PHASES];
    int nphases;
    bool probing;        /* after the window's replay, with a profile and a table */
    bool probed;         /* probing began after the window (the report's phases_probed) */
    emm_trace_record *probe;
    size_t pn, pcap;
    uint64_t probe_reads, probe_len, gap, probe_start;
    struct last_read plast; /* the element read last, for the probes' count */
    char pending[EMM_TABLE_NAME_MAX]; /* a probe's new pattern awaiting a second probe */
    uint64_t pending_start;
    pc_set phase_pcs;    /* the code of the current phase's mesh reads (window and probes) */
    pc_set pending_pcs;  /* and of the pending probe's, until it is confirmed or dropped */
    uint32_t old_probes; /* probes in a row of old code left unprofiled */
    double moves[SESSION_MOVE_REFS][SESSION_MOVE_SIZE]; /* the current phase's moves */
    uint32_t nmoves, moves_next;
    double pending_moves[SESSION_MOVE_SIZE]; /* the pending probe's */
    uint64_t probes_taken, probes_profiled; /* the report's "probes" */
    struct probe_job *probe_job; /* a full probe evaluated beside the run, or NULL */
    uint64_t probe_apply; /* the accesses after which its outcome is applied */
    uint64_t dropped;    /* records of arrays left out of the trace */
    /* session_lines.c: the stalls by program counter of every model that
     * may be the answer, and the answer's stall lines */
    uint64_t window_records; /* records simulated when the window's replay ended */
    struct emm_annotation **annotations; /* nmodels of them, NULL where not kept */
    uint64_t stall_total;   /* the answer's DMA stall cycles */
    bool stall_lines_done;
    size_t nstall_lines;
    struct stall_line {
        char file[256];
        int line;
        char function[128];
        uint64_t cycles;
    } stall_lines[SESSION_STALL_LINES];
} session;

/* The window's choice (model 0) when the run's contest (or the window's
 * check) answered otherwise, else NULL (and NULL until the session's
 * finish). */
static inline const emm_strategy *session_overruled(const session *s)
{
    return s->answer_model != SIZE_MAX && s->answer_model != 0 ? &s->mstrat[0] : NULL;
}

/* The runner's model of the answer: the one the contest or the window's
 * check named at finish, else the chosen strategy's (model 0); SIZE_MAX
 * when nothing was chosen. */
static inline size_t session_answer_model(const session *s)
{
    return s->answer_model != SIZE_MAX ? s->answer_model : s->has_chosen ? 0 : SIZE_MAX;
}

/* Whether the runner's model i may turn out to be the answer: the
 * prediction's, or any candidate's when a contest or the window's check
 * ranks them at the end. */
static inline bool session_may_answer(const session *s, size_t i)
{
    return i == 0 || s->contest || s->window_check;
}

/* Live, or gone with its fields kept for the decision. */
static inline bool session_usable(const session_array *a)
{
    return a->live || a->snap;
}

static inline size_t session_scalar_bytes(emm_scalar t)
{
    return t == EMM_U16 ? 2 : t == EMM_F32 || t == EMM_I32 || t == EMM_U32 ? 4 : 8;
}

/* The scalars a record holds at its field: three (coordinates, indices),
 * a soup's nine corner coordinates, or an axis block's one. */
static inline unsigned session_scalars(const session_array *a)
{
    return a->shape == EMM_TAG_SOUP        ? 9
           : a->shape == EMM_TAG_HALFEDGES ? 1 + EMM_TAG_LINKS
           : a->axis >= 0 || emm_tag_shape_is_connectivity(a->shape) ? 1
                                                                     : 3;
}

/* The window's name for the array of slot i: its group's lead, so that
 * vertex k's x, y and z in three blocks are one element, as after the
 * decision, when they feed one trace array. */
static inline uint32_t session_group(const session *s, uint32_t i)
{
    return (uint32_t)s->arrays[i].lead;
}

/* The bytes of one trace record of the array: a column-major array's
 * three entries of an element (x, y, z) count as one record. */
static inline uint64_t session_record_bytes(const session_array *a)
{
    return a->plane ? 3 * a->stride : a->stride;
}

/* Element reads the window read on for past its length, to fill the local
 * store (window_fill.h); 0 when it did not. */
static inline uint64_t session_read_on(const session *s)
{
    return s->cfg.window_accesses && s->wlen > s->cfg.window_accesses
               ? s->wlen - s->cfg.window_accesses
               : 0;
}

/* The bytes of a record of a's trace array: an axis block's group has its
 * x, y, z entries side by side (session_decide.c). */
uint64_t session_trace_record_bytes(const session *s, const session_array *a);

/* One past the array's last byte: a column-major array's columns stay
 * where they are, whatever count of records is in use. */
static inline uint64_t session_array_end(const session_array *a)
{
    return a->base + (a->plane ? 3 * a->plane : a->count * a->stride);
}

/* The array's bytes: the program's memory, or a copy of a program's in
 * another process, read through the memory seam (NULL when there is none). */
static inline const unsigned char *session_bytes(session *s, session_array *a)
{
    if (!s->memory)
        return (const unsigned char *)(uintptr_t)a->base;
    if (!a->view && s->memory->read)
        a->view = s->memory->read(s->memory->ctx, a->base, a->end - a->base);
    return a->view;
}

/* The address of record i's first scalar, in the program's memory (or the
 * copy of it) or in the slot's snapshot (which holds each record's scalars
 * in a row). The caller makes sure the array is readable
 * (session_readable). */
static inline const unsigned char *session_field_at(session *s, session_array *a, uint64_t i)
{
    if (a->snap)
        return a->snap + i * session_scalars(a) * session_scalar_bytes(a->type);
    return session_bytes(s, a) + i * a->stride + a->field;
}

/* The address of scalar c (< session_scalars(a)) of record i: in a row, or
 * for a column-major array in column c. */
static inline const unsigned char *session_scalar_at(session *s, session_array *a,
                                                     uint64_t i, unsigned c)
{
    if (a->shape == EMM_TAG_HALFEDGES && !a->snap)
        return session_bytes(s, a) + i * a->stride + a->hoff[c];
    uint64_t step = a->plane && !a->snap ? a->plane : session_scalar_bytes(a->type);
    return session_field_at(s, a, i) + c * step;
}

/* Whether the array's fields can be read: a snapshot, or its bytes. */
static inline bool session_readable(session *s, session_array *a)
{
    return a->snap || session_bytes(s, a);
}

/* Who described array a, for messages: "EMM_TAG rule 2 (triangles:...)" or
 * "the emm_tag_triangles call". */
const char *session_origin(const session *s, const session_array *a, char *buf, size_t cap);

/* The name a setting was given by (the variable or the option), for messages. */
static inline const char *session_source(const session *s, emm_config_key k)
{
    return s->cfg.source[k] ? s->cfg.source[k] : emm_config_row_get(k)->var;
}

/* A path setting, or NULL when unset. */
static inline const char *session_path(const char *p)
{
    return p[0] ? p : NULL;
}

/* session_decide.c, in two parts. session_decide_read: everything the
 * decision reads of the program — the geometry, the arrays frozen as the
 * trace's, the program's objects when a trace will name them — so that a
 * program in another process may go on once it returns. session_decide_rest:
 * the profile, the choice and the models, from the session's own copies;
 * the window's records then go through them. A failure of either leaves
 * the session to step aside. (session.c wraps them as the engine's
 * emm_session_decide_read and _rest: deferral, the window's end.) */
emm_status session_decide_read(session *s, emm_error *err);
emm_status session_decide_rest(session *s, emm_error *err);
/* At finish, the answer among the models that ran: the contest's fastest
 * finalist; under a window check the prediction unless direct reads beat
 * it over the window, then the fastest candidate there; else the chosen
 * strategy. Sets answer_model, runner_model, ranked and chosen. */
void session_decide_answer(session *s);

/* The window's clock: records given while profiling (n more now), and the
 * time of the first. The decision reads it (wseconds): under the fault
 * capture, what the window cost the program. */
void session_window_clock(session *s, size_t n);

/* Only the window was captured and simulated: a backend that sees the
 * window alone stops at the decision. */
static inline bool session_window_only(const session *s)
{
    return !(emm_capture_caps(s->capture) & EMM_CAP_WHOLE_RUN) || s->deferred;
}

/* The window's records up to the one whose read filled it (after
 * freeze_arrays): the window proper, which the decision and the first
 * phase see. The rest of the capture's batch joined the buffer and is the
 * run's (docs/profile.md "The window"). */
size_t session_window_proper(const session *s);

/* The bytes of the traced mesh's records. */
uint64_t session_mesh_bytes(const session *s);

/* session_phase.c: the first phase (the window's) and the probes of the
 * records simulated after it; session_phases_close ends the last phase. */
void session_phases_start(session *s);
void session_phases_see(session *s, const emm_trace_record *recs, size_t n);
void session_phases_close(session *s);
/* Once the answer is known (the contest's, or the chosen strategy): each
 * phase's kept cycles become the answer's over the phase. */
void session_phases_answer(session *s);
void session_phases_free(session *s);
/* The cycles a switch costs: the mesh's bytes in by DMA and the new layout
 * out (2 x one DMA of the mesh's bytes). */
uint64_t session_switch_cycles(const session *s);

/* session_lines.c: the trace (with the program counters and the program's
 * modules when the capture records them; for the timeline alone, a private
 * one) and the stall attribution of every model that may be the answer,
 * started at the decision before the window's replay; session_window_done
 * marks the window's end; session_stall_lines resolves the answer's top
 * stall lines (at finish, once the answer is known, before the summary);
 * session_trace_close ends the trace (its status: EMM_OK, or why it could
 * not be written, in s->trace_error); session_timeline_write then simulates
 * the answer again over it with the timeline watching; session_lines_free
 * frees (and removes a private trace). session_outputs_prepare, in the
 * decision's reading part, fetches what the outputs will need of a program
 * in another process (its objects). */
void session_outputs_prepare(session *s);
void session_outputs_start(session *s);
void session_window_done(session *s);
void session_stall_lines(session *s);
void session_print_stall_lines(const session *s, FILE *out);
void session_write_stall_lines(json_writer *w, const session *s);
emm_status session_trace_close(session *s);
emm_status session_timeline_write(session *s, emm_error *err);
void session_lines_free(session *s);

/* session.c: runs records through the models and the trace writer. */
void session_simulate(session *s, const emm_trace_record *recs, size_t n);

/* session_halfedge.c. session_halfedge_pick: the half-edge, faces and vconn
 * slots of the mesh (the best of each: live, most read), into s->he_slot,
 * face_slot, vconn_slot; whether there is a half-edge slot.
 * session_halfedge_triangles: the triangles of that mesh from its
 * half-edge cycles, validated against vertex array v (indices in range,
 * each face's cycle closing in 3 steps), into s->tri (nt of them), the
 * highest vertex index into *highest; a bad mesh is refused in one line
 * naming the rule and the problem. session_halfedge_freeze: the parts of
 * the trace arrays the connectivity feeds (after freeze_arrays made the
 * others): the vertices' record grows by the vconn record, and the derived
 * triangles get a trace array of their own. */
bool session_halfedge_pick(session *s);
emm_status session_halfedge_triangles(session *s, session_array *v, uint64_t *nt,
                                      int64_t *highest, emm_error *err);
emm_status session_halfedge_freeze(session *s, emm_error *err);
void session_halfedge_free(session *s);

/* An access of a slot that feeds a part: renumbered into its trace array's
 * element and offset; false when its element is not simulated. */
static inline bool session_part_map(session *s, const session_array *a, emm_trace_record *r)
{
    session_part *p = &s->parts[a->part];
    uint64_t e = r->element;
    if (e >= p->count)
        return false;
    uint32_t t = p->remap ? p->remap[e] : (uint32_t)e;
    if (t == UINT32_MAX)
        return false;
    r->offset += p->base + (p->pos ? p->pos[e] * p->stride : 0);
    r->element = t;
    r->array = (uint32_t)p->trace;
    p->accesses++;
    return true;
}

/* session_report.c: the summary on `out`, with the results of the models
 * that ran (res[0..nres), the chosen strategy first when there is one;
 * NULL when the session failed). */
void session_print_summary(const session *s, FILE *out, const emm_result *res, size_t nres);
/* The JSON report at cfg.report: res[0..nres) are the models in order, and
 * skipped[i].status != EMM_OK marks one that could not be built. When
 * another process of the run wrote that file since the session started,
 * the report goes beside it as cfg.report.PID, said on `summary`. */
emm_status session_write_report(const session *s, const emm_result *res,
                                const emm_error *skipped, size_t nres, FILE *summary,
                                emm_error *err);
/* The JSON report at cfg.report when nothing was simulated: why is
 * s->failure's message (docs/report.md "Nothing simulated"); a report
 * written since the session started is left as it is (a child's: the
 * program a wrapper ran). */
emm_status session_write_nothing(const session *s, emm_error *err);
/* The CSV of the window's profile at cfg.profile_dump. */
emm_status session_write_csv(const session *s, emm_error *err);

#endif
