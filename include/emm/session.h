/* emm — the session: profile → decide → simulate → report (docs/design.md "The shim and
 * the session", "Session" and "Output"; thesis Fig. 5.6).
 *
 * libemmshim.so is thin: it interposes the allocator, applies the tag rules,
 * captures accesses into per-thread buffers and forwards them here. The
 * session owns everything else. It is not thread-safe: the shim serialises
 * calls (one lock around each call).
 *
 * Life of a session:
 *   emm_session_new(config)            validate everything once
 *   emm_session_tag(...) / _untag(...)  as the program allocates and frees
 *   emm_session_access(batch) ...      until it returns EMM_SESSION_DECIDE
 *   emm_session_decide()               "freeze the data": read the geometry
 *                                      from the tagged arrays, profile the
 *                                      window, choose the strategy, build the
 *                                      models, replay the window through them
 *   emm_session_access(batch) ...      streamed through the models
 *   emm_session_finish()               summary on stderr, report, CSV, trace
 *   emm_session_free()
 * The caller must make the tagged arrays readable before emm_session_decide
 * (the fault backend lifts its page protection first). Nothing grows with the
 * run's length unless the config asks for a trace.
 *
 * The session's work happens in one engine, reached in this process or, with
 * config.server, in a native process of its own (emm-session) that serves
 * the calls made here; both give the same results. */
#ifndef EMM_SESSION_H
#define EMM_SESSION_H

#include <stdio.h>

#include <stdint.h>
#include <time.h>

#include "emm/common.h"
#include "emm/config.h"
#include "emm/trace.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct emm_session emm_session;

/* How a session reads a program that is not this process (emm-session
 * serving a program under Valgrind). */
typedef struct emm_session_memory {
    /* A copy of the program's bytes [addr, addr + len), malloc'ed (the
     * session frees it), or NULL when they cannot be had now. */
    void *(*read)(void *ctx, uint64_t addr, uint64_t len);
    /* The program's loaded objects (emm/trace.h), malloc'ed as one block
     * the session frees, into *out and *n; false when they cannot be had
     * now (the session keeps those it had). May be NULL. */
    int (*modules)(void *ctx, emm_trace_module **out, uint32_t *n);
    void *ctx;
} emm_session_memory;

typedef struct emm_session_config {
    const emm_config *config; /* the settings (emm/config.h), copied; NULL: the defaults */
    emm_capture capture;      /* the backend that captures, for the report */
    const char *program;      /* the program's name, for the summary and report */
    int table_only;           /* 1: config->table replaces the shipped table instead of adding
                               * to it (for tests and experiments with a table of one's own) */
    emm_threads threads;      /* the session's helper threads: how many (0: the online CPUs)
                               * and the hook that marks them (libemmshim.so's own) */
    const char *server;       /* NULL: the session runs in this process. Else the path of
                               * emm-session: the session runs there, a native process of its
                               * own, and this handle forwards every call to it (the valgrind
                               * capture, whose program runs under Valgrind). Its summary goes
                               * to this process's stderr. */
    const emm_session_memory *memory; /* NULL: the tagged arrays are this process's memory;
                               * else how to read the program's (copied) */
    long pid;                 /* the program's pid (0: this process's), for the name of a
                               * report another process of the run already wrote */
    unsigned expect;          /* the kinds of array the tag rules name, a set of
                               * 1u << emm_array_kind (0: none known): a window that filled
                               * before an array of each was tagged goes on, for a bounded
                               * while, until one is (docs/profile.md "Arrays tagged late") */
    int server_sock;          /* with server: a socket (above 2) to an emm-session emm run
                               * already started for this process, which the handle takes
                               * over; 0: the handle starts one */
} emm_session_config;

/* One captured access, as the capture backends record it: the address, the
 * bytes (low 31 bits) and write flag (bit 31), the work since the previous
 * access (instrumented basic blocks, or 0), and the program counter of the
 * access where the backend knows it, one byte past the access's code
 * (sancov: its hook's return address; valgrind: the instruction's address
 * + 1, so that pc - 1 lies in the access's code for both), or 0. A session
 * that is given program counters writes them, and the program's mapped
 * objects, into its trace (emm annotate reads them). */
typedef struct emm_raw_access {
    uint64_t addr;
    uint32_t bytes_write;
    uint32_t work;
    uint64_t pc;
} emm_raw_access;

#define EMM_RAW_WRITE 0x80000000u

/* emm_session_access's answer. */
typedef enum emm_session_state {
    EMM_SESSION_PROFILING = 0, /* still filling the window */
    EMM_SESSION_DECIDE,        /* the window is full: call emm_session_decide */
    EMM_SESSION_SIMULATING,    /* decided; accesses go through the models */
    EMM_SESSION_OFF            /* the session stepped aside (a failure, or finished):
                                  capturing more is useless */
} emm_session_state;

/* Validates everything once: the machine file, the tables, the output
 * directories; a failure names the variable or option the bad value came
 * from (emm_config.source). */
EMM_API emm_status emm_session_new(const emm_session_config *cfg, emm_session **out,
                                   emm_error *err);

/* A tagged array. Returns the array's index (>= 0), or -1 when the session
 * ignores it (a description that does not hold together: a field past the
 * stride, a type the kind cannot have, no records; or the session is off).
 * A range already tagged is re-tagged (realloc keeps tags right). */
EMM_API int emm_session_tag(emm_session *s, const emm_array_desc *d);
/* The array at `old` moved to `base` and now holds `count` records (realloc):
 * the same array, its window records and its place kept — the window does
 * not close. Nothing happens when `old` is not a tagged array. */
EMM_API emm_session_state emm_session_move(emm_session *s, const void *old, const void *base,
                                           size_t count);
/* The array at `base` was freed or moved: its later accesses are not mesh
 * accesses. Call it while the memory is still readable: before the
 * decision, the session copies the array's coordinates or indices when the
 * window holds accesses to it (a short program that frees its mesh before
 * exit is still decided at finish). When the last array of its kind leaves
 * before the window is full, the answer is EMM_SESSION_DECIDE: the caller
 * then makes the arrays readable and calls emm_session_decide. */
EMM_API emm_session_state emm_session_untag(emm_session *s, const void *base);

/* The address ranges of the tagged arrays, for the capture backends' fast
 * filter: fills up to cap [lo, hi) pairs and returns how many there are. */
EMM_API size_t emm_session_ranges(const emm_session *s, uint64_t *lo, uint64_t *hi, size_t cap);

/* A batch of captured accesses; those outside every tagged array are
 * dropped (their work is added to the next kept access). An access that runs
 * past the end of its record is attributed whole to the record it starts in.
 * Before the decision the window's records are buffered: at most 32 per
 * element access of the window (or 2^20 for a window in iterations), past
 * which the answer is EMM_SESSION_DECIDE; accesses given after that answer
 * and before emm_session_decide are still buffered. */
EMM_API emm_session_state emm_session_access(emm_session *s, const emm_raw_access *a, size_t n);
/* One iteration of the program's main loop ended (emm_iteration()). */
EMM_API emm_session_state emm_session_iteration(emm_session *s);

/* Reads the geometry from the tagged arrays, profiles the window, decides
 * (or takes the configured strategy), builds the models and replays the
 * window through them. A failure (e.g. no vertex array was tagged) is
 * returned; the session then stays quiet and finish reports why. A
 * geometry that does not check out (an index outside the vertices, a
 * coordinate that is none) is no failure yet: the program may have to
 * finish its arrays (renumber its faces). The session keeps the window,
 * captures nothing more (no ranges) and reads the arrays again at finish,
 * as they are then or as they were freed; the summary and the report
 * (coverage.geometry_read "end") say so, or why it failed again. */
EMM_API emm_status emm_session_decide(emm_session *s, emm_error *err);
/* emm_session_decide in its two parts, for a caller that lets the program
 * go on between them: _read reads everything the decision needs of the
 * program (the geometry, the arrays frozen, the objects a trace will name)
 * — after it the program's memory is not read again until the next call
 * that changes the tags — and _rest profiles, decides, builds the models
 * and replays the window. A failure of either is as emm_session_decide's. */
EMM_API emm_status emm_session_decide_read(emm_session *s, emm_error *err);
EMM_API emm_status emm_session_decide_rest(emm_session *s, emm_error *err);

/* Ends the session: decides if the window never filled, writes the summary
 * to `summary` (NULL: none; nothing at log 0), the JSON report, the CSV and
 * the trace, each whole or not at all (a temporary file renamed into place).
 * When the session had stepped aside, or nothing was simulated (no access
 * to a tagged array was seen), the summary says why (so the caller need
 * not print err again) and the failure is returned; the report, when one
 * is asked for, is written with the reason and no results (docs/report.md
 * "Nothing simulated"), and no other file. An output that cannot be written is named in one line on
 * `summary` (log >= 1) and the first such failure is returned. A second call
 * does nothing and returns EMM_OK.
 *
 * Not async-signal-safe: it allocates and uses stdio. Safe from an atexit
 * handler or a destructor. From a SIGTERM/SIGINT handler it is safe only
 * when the interrupted code was inside neither the session (take the shim's
 * lock with trylock and skip finish when that fails) nor malloc or stdio,
 * which a handler cannot know: a handler that calls it trades a rare hang
 * for the report. Either way a file is whole or absent: each is renamed
 * into place only once complete. */
EMM_API emm_status emm_session_finish(emm_session *s, FILE *summary, emm_error *err);
/* As emm_session_finish, for a run that did not end normally: `ended` says
 * how ("signal 11 (SIGSEGV)"). The summary says so, and the report's
 * "ended" holds it ("exit" after emm_session_finish): what was simulated
 * is the run up to its last access before that. */
EMM_API emm_status emm_session_finish_ended(emm_session *s, FILE *summary, const char *ended,
                                            emm_error *err);
/* Ends the session with no output at all — no summary, no report, no
 * trace: a process the program started that tagged nothing (a tool it
 * ran), whose "nothing simulated" would only stand in the way of the
 * program's own report. Later calls to finish do nothing. */
EMM_API void emm_session_discard(emm_session *s);

EMM_API void emm_session_free(emm_session *s);

/* A run in which nothing was simulated and no session could say so (the
 * shim stepped aside, list mode): when c->report names a file, writes the
 * JSON report of docs/report.md with no results, coverage.simulated
 * "nothing" and coverage.reason `why` (program and capture as given),
 * whole or not at all. With `since` (CLOCK_REALTIME_COARSE; NULL: always),
 * a report file modified since then is left as it is: another process of
 * the run (the program a wrapper such as timeout(1) started) wrote it, and
 * "nothing" is no answer to put over it. EMM_OK without a report path, or
 * when left; else the writer's error, naming the setting. */
EMM_API emm_status emm_session_report_nothing(const emm_config *c, const char *program,
                                              emm_capture capture, const char *why,
                                              const struct timespec *since, emm_error *err);

/* In a child the program forked: the session is the parent's. A session in
 * another process (config.server) lets go of its connection; every later
 * call does nothing. Call it before anything else in the child. */
EMM_API void emm_session_forked(emm_session *s);

#ifdef __cplusplus
}
#endif
#endif
