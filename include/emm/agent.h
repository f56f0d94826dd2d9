/* emm — the runtime's side of libemmshim.so (docs/architecture.md "The
 * shim"): what the preloaded library forwards to.
 *
 * libemmshim.so only interposes — the allocator, emm_tag_*, the capture
 * hooks, exit and signals — and forwards here. The agent keeps the tagged
 * blocks, applies the EMM_TAG rules (unwinding an allocation's stack for
 * site=), drives the session (records in, the decision when it asks, the
 * finish), and in list mode (EMM_LIST_SITES) notes the candidate arrays.
 * A capture backend meets the agent through hooks (emm_agent_hooks) that
 * the agent calls at its events; it asks the backend's capabilities
 * (emm_capture_caps), never which backend it is.
 *
 * One lock serialises everything but emm_agent_maybe_tagged and
 * emm_agent_active: the session is not thread-safe. The caller guards
 * against re-entry: while a thread is inside an agent call, or is one of
 * the agent's helper threads (emm_threads.on_start), its allocations must
 * go straight to the C library's allocator — the agent allocates, and
 * frees the blocks it untags with free(). */
#ifndef EMM_AGENT_H
#define EMM_AGENT_H

#include <stddef.h>
#include <stdint.h>

#include "emm/common.h"
#include "emm/config.h"
#include "emm/session.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct emm_agent emm_agent;

/* A tagged block as a capture backend sees it. */
typedef struct emm_agent_block {
    uintptr_t base; /* the program's pointer */
    size_t bytes;   /* the array's bytes */
    void *map;      /* the block's own pages (the backend's map hook), or NULL */
    size_t map_len;
} emm_agent_block;

/* A capture backend's side of the agent's events; each may be NULL. All
 * but map are called with the agent's lock held. */
typedef struct emm_agent_hooks {
    /* Pages of the backend's own for a block a rule is about to tag (the
     * fault capture protects them), or NULL; *map_len gets their length. */
    void *(*map)(size_t size, size_t align, size_t *map_len);
    /* A block was tagged, or moved to where b says. */
    void (*on_tag)(const emm_agent_block *b);
    /* A block is about to be untagged, or moved: the session may read it
     * now (a copy of a leaving array's fields), and those reads are not
     * the program's. */
    void (*on_untag)(const emm_agent_block *b);
    /* The tagged ranges changed: emm_agent_ranges_locked has them. */
    void (*ranges)(emm_agent *a);
    /* The window closed: the session reads the arrays for its decision;
     * they must be readable and the reads are not the program's. */
    void (*before_decide)(void);
    /* Records held outside the threads' buffers go to the session
     * (emm_agent_feed_locked); called by every emm_agent_feed. */
    void (*drain)(emm_agent *a);
} emm_agent_hooks;

typedef struct emm_agent_config {
    const emm_config *config;     /* the settings (copied) */
    emm_capture capture;          /* the backend in use */
    const emm_agent_hooks *hooks; /* its side of the events (copied; NULL: none) */
    const char *program;          /* the program's name, for messages and the report */
    emm_threads threads;          /* the session's helper threads */
    const char *server;           /* emm-session's path: the session runs there, natively
                                     (the backend runs the program under Valgrind); when it
                                     cannot start, here. NULL: here */
} emm_agent_config;

/* ---- the process tree ---------------------------------------------------- */

/* Three variables of emm run's and the shim's own, not settings (the
 * configuration table holds those): each is set and taken out of the
 * environment by emm and never read from the user.
 *
 * EMM_AGENT_READY_VAR, "FD:PID": emm run started the program as process PID
 * with FD the write end of a pipe. The shim in that process writes one byte
 * there and closes it, so that emm run can tell a program the shim never
 * loaded into (statically linked, set-user-ID: the loader preloads nothing
 * into them) and say so.
 * EMM_AGENT_ROOT_VAR: the pid of the program, the first process of the tree
 * the shim loaded into (emm run clears it for the program it starts). A
 * process of another pid is one the program started (an exec'd tool): it
 * says nothing unless it tagged an array. */
#define EMM_AGENT_READY_VAR "EMM_RUN_READY"
#define EMM_AGENT_ROOT_VAR "EMM_SHIM_ROOT"
/* EMM_AGENT_SESSION_VAR, "FD:PID": emm run started emm-session for the
 * valgrind capture with FD, in process PID (the program), a socket to it,
 * while Valgrind was starting. The agent of that process takes it over
 * instead of starting one (emm_agent_config.server); any other process
 * drops the variable, and none of them passes the socket on to what it
 * executes. */
#define EMM_AGENT_SESSION_VAR "EMM_RUN_SESSION"

/* Programs the shim never enters, by the start of their name
 * (llvm-symbolizer-14 is llvm-symbolizer): symbolizers, which a sanitizer
 * runtime or a crash handler starts to print a stack; none is the
 * program's work. emm run keeps Valgrind out of them too. */
#define EMM_AGENT_HELPERS(X) X("llvm-symbolizer") X("llvm-addr2line") X("addr2line") \
    X("eu-addr2line")

/* The shim's first call, before it reads any setting: answers emm run
 * (EMM_AGENT_READY_VAR) and marks the tree's root (EMM_AGENT_ROOT_VAR).
 * Returns 0 when `program` (the executable's name) is one of
 * EMM_AGENT_HELPERS: the shim then stays out of the process, silent. */
EMM_API int emm_agent_enter(const char *program);

/* Starts the session (or, in list mode, the site table) and opens the
 * unwinder when a rule uses site= or the mode lists sites. On failure err
 * says why in one line and *out is NULL: the caller steps aside. */
EMM_API emm_status emm_agent_new(const emm_agent_config *c, emm_agent **out, emm_error *err);
/* Finishes (emm_agent_finish) and frees the agent, its session and its
 * tables; the blocks it tagged stay the program's. NULL is allowed. (The
 * shim keeps its agent for the process's life.) */
EMM_API void emm_agent_free(emm_agent *a);

/* The smallest block a rule can select, or list mode lists: smaller ones
 * need no call at all. SIZE_MAX when nothing can be. */
EMM_API size_t emm_agent_min_block(const emm_agent *a);
/* Whether the agent still watches: not finished, nor a forked child's.
 * No lock: for the callers' fast paths. */
EMM_API int emm_agent_active(const emm_agent *a);

/* ---- allocations (the caller's re-entry guard raised) -------------------- */

/* The EMM_TAG rule (its index, >= 0) that selects a block of `size` bytes
 * allocated now, from this call stack, by the code at `caller` (the return
 * address of the outermost allocator call: a block the C library asks for
 * itself is never selected), or -1. Counts nth= selectors. */
EMM_API int emm_agent_select(emm_agent *a, size_t size, const void *caller);
/* The block an allocation got: tagged when rule >= 0 (on `map`, the
 * backend's own pages, when not NULL), noted in list mode; p NULL (the
 * allocation failed) releases the map. */
EMM_API void emm_agent_allocated(emm_agent *a, int rule, void *p, size_t size, void *map,
                                 size_t map_len, const void *caller);
/* Whether p may be a tagged block; false for certain. No lock: free()'s
 * fast path. */
EMM_API int emm_agent_maybe_tagged(const emm_agent *a, const void *p);
/* free(p) of a block that may be tagged: untags it and releases it (its own
 * pages unmapped, or free()). Returns 0 when p was not tagged: the caller
 * frees it. */
EMM_API int emm_agent_on_free(emm_agent *a, void *p);
/* realloc(p, size) of a block that may be tagged: the same array, moved
 * (the session keeps its window); returns the new block, or NULL with errno
 * ENOMEM and p kept (size 0: p freed, NULL). *handled is 0 when p was not
 * tagged: the caller reallocs. */
EMM_API void *emm_agent_on_realloc(emm_agent *a, void *p, size_t size, int *handled);
/* The bytes usable at p when it is a tagged block on its own pages, else 0. */
EMM_API size_t emm_agent_usable_size(emm_agent *a, const void *p);
/* List mode: the block at p is about to be freed (moving_to 0) or moved by
 * realloc to a block of moving_to bytes; its records are read first, and
 * the move is remembered for the next allocation of this thread (the
 * replay of the suggested rules follows a tagged block's move). Nothing
 * happens in other modes. */
EMM_API void emm_agent_release(emm_agent *a, const void *p, size_t moving_to);

/* ---- arrays the program or a backend describes --------------------------- */

/* An emm_tag_vertices / emm_tag_triangles call (or the api backend's mesh). */
EMM_API void emm_agent_tag_call(emm_agent *a, emm_array_kind kind, const void *p, size_t count,
                                size_t stride, size_t offset, emm_scalar type);
/* The array at p is gone (the api backend's emm_mesh_free). */
EMM_API void emm_agent_untag(emm_agent *a, const void *p);

/* A mesh of the interface of emm/mesh.h, opened or made (the api backend):
 * its vertex and triangle records are two tagged arrays, until
 * emm_agent_untag_mesh. */
struct emm_mesh;
EMM_API void emm_agent_tag_mesh(emm_agent *a, const struct emm_mesh *m);
EMM_API void emm_agent_untag_mesh(emm_agent *a, const struct emm_mesh *m);

/* ---- records ------------------------------------------------------------- */

/* A batch of captured accesses into the session (which decides when it
 * asks), then the backend's drain. */
EMM_API void emm_agent_feed(emm_agent *a, const emm_raw_access *r, size_t n);
/* The same from a drain hook, the lock already held. */
EMM_API void emm_agent_feed_locked(emm_agent *a, const emm_raw_access *r, size_t n);
/* The ranges to capture, [lo, hi) pairs: up to cap, and returns how many
 * there are (0 once the session has stepped aside). From a hook. */
EMM_API size_t emm_agent_ranges_locked(emm_agent *a, uint64_t *lo, uint64_t *hi, size_t cap);
/* One iteration of the program's main loop ended (emm_iteration()). */
EMM_API void emm_agent_iteration(emm_agent *a);

/* The ranges to capture as a backend's hot path reads them, without a
 * lock: n first (acquire), then the arrays; lo[i] and len[i] (the bytes
 * from lo[i]) for i < n. The agent refreshes it before the ranges hook. A
 * snapshot being refreshed may be torn (one range half new), as an access
 * racing a tag always could be: the session drops what falls outside its
 * arrays. */
typedef struct emm_agent_filter {
    size_t n;            /* atomic */
    const uint64_t *lo;  /* atomic */
    const uint64_t *len; /* atomic */
} emm_agent_filter;
EMM_API const emm_agent_filter *emm_agent_filter_of(const emm_agent *a);

/* ---- the end, fork ------------------------------------------------------- */

/* Finishes once: the summary on stderr (EMM_LOG), the outputs, the lines
 * about rules that selected nothing; in list mode the site listing (and
 * the report, when one is asked for, says nothing was simulated). A
 * process the program started (EMM_AGENT_ROOT_VAR) that tagged or listed
 * nothing prints none of these, whatever EMM_LOG (under EMM_LOG=2 it said
 * one line as it started). Takes
 * the lock (a caller in a signal handler must know no thread of its own
 * holds it). Later calls do nothing. */
EMM_API void emm_agent_finish(emm_agent *a);
/* As emm_agent_finish, from the handler of a fatal signal `sig` about to
 * kill the program: the summary and the report say the run ended by it
 * ("ended": "signal 11 (SIGSEGV)"). */
EMM_API void emm_agent_finish_signal(emm_agent *a, int sig);
/* Around fork(): the parent holds the lock across it; the child's agent
 * goes quiet (no session, no report: the parent's covers the run). */
EMM_API void emm_agent_lock(emm_agent *a);
EMM_API void emm_agent_unlock(emm_agent *a);
EMM_API void emm_agent_forked(emm_agent *a);

/* The exit status of a program stopped by EMM_STRICT=1. */
#define EMM_AGENT_STRICT_EXIT 125

/* The shim steps aside before a session could start (a bad EMM_* value, a
 * session that cannot start): `why` in one line, then the program runs
 * untouched — or, with c->strict (EMM_STRICT=1), does not run: the line
 * says so and the process exits with EMM_AGENT_STRICT_EXIT. When c names a
 * report, it is written first with nothing simulated and that reason
 * (emm_session_report_nothing, without `since`: no other process of the
 * run can have written one yet); a report that cannot be written is one
 * line on stderr (c->log >= 1). */
EMM_API void emm_agent_step_aside(const emm_config *c, emm_capture capture, const char *program,
                                  const char *why);

/* Whether the program's main object imports `symbol` (the api backend's
 * test for a program written against emm_mesh_*). */
EMM_API int emm_program_imports(const char *symbol);

/* Writes one line "emm: ..." without allocating: the shim's and the
 * agent's own words. They go to the stderr the process started with (a
 * duplicate the agent keeps), never to a file the program opened after
 * closing its stderr; nowhere when that stderr is gone. */
EMM_API void emm_agent_say(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

#ifdef __cplusplus
}
#endif
#endif
