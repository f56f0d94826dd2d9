/* Internal to libemmshim.so: the one process-wide context the preloaded
 * library needs (DESIGN.md "The shim"; STYLE.md §6–§7).
 *
 * A preloaded allocator cannot take an explicit context: malloc has no
 * handle argument. So the shim keeps exactly one struct, `shim`, and every
 * piece of it is either written once at start-up (before main) or guarded by
 * shim.lock; the capture fast paths read a small snapshot with relaxed
 * atomics. All analysis lives in the runtime's session (include/emm/session.h);
 * the shim only forwards to it, one lock around each call. */
#ifndef EMM_SHIM_H
#define EMM_SHIM_H

#include <pthread.h>
#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "emm/session.h"
#include "emm/tag.h"
#include "emm/trace.h"

#include "env.h"

#define SHIM_TLS __attribute__((tls_model("initial-exec")))
#define SHIM_HIDDEN __attribute__((visibility("hidden")))

/* The libc functions the shim wraps, resolved with dlsym(RTLD_NEXT). */
struct shim_real {
    void *(*malloc)(size_t);
    void *(*calloc)(size_t, size_t);
    void *(*realloc)(void *, size_t);
    void (*free)(void *);
    int (*posix_memalign)(void **, size_t, size_t);
    void *(*aligned_alloc)(size_t, size_t);
    void *(*memalign)(size_t, size_t);
    void *(*valloc)(size_t);
    size_t (*malloc_usable_size)(void *);
};
extern struct shim_real shim_real SHIM_HIDDEN;
/* Resolves shim_real once (safe to call from any interposed function). */
void shim_resolve(void) SHIM_HIDDEN;

/* One array the shim has told the session about. */
struct shim_tag {
    uintptr_t base;        /* the pointer the program holds (and frees) */
    size_t bytes;          /* bytes the array spans: count * stride */
    emm_array_kind kind;
    size_t stride, offset;
    emm_scalar type;
    bool from_rule;        /* count follows the block's size on realloc */
    void *map;             /* the block's own pages (fault backend), or NULL */
    size_t map_len;
    bool protected_;       /* its pages are PROT_NONE right now */
};

#define SHIM_MAX_TAGS 64
#define SHIM_MAX_RANGES 64

/* Records per thread buffer before it is flushed to the session. */
#define SHIM_TBUF_CAP 1024

struct shim_tbuf {
    emm_raw_access rec[SHIM_TBUF_CAP];
    uint32_t n;
    uint32_t work;         /* instrumented basic blocks since the last record */
    bool registered;       /* the thread-exit flush is armed */
};

struct shim_rules;

struct shim {
    /* Set once before main. */
    bool enabled;                  /* a session exists */
    enum shim_capture capture;     /* the backend in use (never AUTO) */
    struct shim_env env;
    struct shim_rules *rules;      /* NULL: EMM_TAG unset */
    size_t rule_min;               /* the fast path: smaller blocks are never tagged */

    pthread_mutex_t lock;          /* the session, the tag table, the rules' counters */
    emm_session *session;
    emm_session_state state;
    bool finished;                 /* finish ran, or a forked child went quiet */
    bool failed;                   /* decide failed: stop capturing */
    struct shim_tag tags[SHIM_MAX_TAGS];
    size_t ntags;
    uint64_t tagged_total;         /* arrays ever tagged, for the log */

    /* Read without the lock. */
    uintptr_t tag_base[SHIM_MAX_TAGS]; /* atomic: free()'s quick check, 0 = empty slot */
    int live_tags;                 /* atomic: entries in tag_base */
    uint64_t range_lo[SHIM_MAX_RANGES];
    uint64_t range_len[SHIM_MAX_RANGES];
    size_t nranges;                /* atomic: the sancov filter's snapshot */
};
extern struct shim shim SHIM_HIDDEN;

/* The recursion guard: set while the shim (or the runtime it calls) runs, so
 * their own allocations are never tagged and never re-enter the session. */
extern __thread int shim_busy SHIM_TLS SHIM_HIDDEN;

/* Set while the calling thread is inside one of the shim's allocator
 * functions (and so, maybe, inside the C library's allocator). */
extern __thread int shim_in_alloc SHIM_TLS SHIM_HIDDEN;

/* A SIGTERM/SIGINT that arrived while its thread was inside the shim or the
 * allocator, where finishing the session could deadlock: it is acted on
 * when the thread leaves (shim_leave, the allocator's return). 0: none. */
extern int shim_pending_signal SHIM_HIDDEN;
/* Finishes the session for the pending signal and dies of it. */
void shim_deliver_pending(void) SHIM_HIDDEN;

/* Ends a stretch of shim_busy; the outermost one acts on a pending signal. */
static inline void shim_leave(void)
{
    if (--shim_busy == 0 && !shim_in_alloc
        && __atomic_load_n(&shim_pending_signal, __ATOMIC_RELAXED))
        shim_deliver_pending();
}

/* The calling thread's capture buffer. */
extern __thread struct shim_tbuf shim_tbuf SHIM_TLS SHIM_HIDDEN;

/* Writes one line "emm: ..." to stderr without allocating. */
void shim_log(const char *fmt, ...) __attribute__((format(printf, 1, 2))) SHIM_HIDDEN;

/* --- preload.c --------------------------------------------------------- */
/* Tags an array (explicit calls, rules, the api backend). Takes the lock. */
void shim_tag_array(emm_array_kind kind, const void *base, size_t bytes, size_t stride,
                    size_t offset, emm_scalar type, bool from_rule, void *map,
                    size_t map_len) SHIM_HIDDEN;
/* Forgets the array at base (free, emm_mesh_free). Takes the lock. */
void shim_untag_array(const void *base) SHIM_HIDDEN;
/* Sends the calling thread's buffer to the session (takes the lock). */
void shim_flush_thread(void) SHIM_HIDDEN;
/* Arms the thread-exit flush for the calling thread. */
void shim_register_thread(void) SHIM_HIDDEN;
/* Ends the session once: flush, finish, summary. Safe to call twice. */
void shim_finish(void) SHIM_HIDDEN;

/* Appends one access to the calling thread's buffer (all backends). */
static inline void shim_record(uint64_t addr, uint32_t bytes, bool write)
{
    struct shim_tbuf *b = &shim_tbuf;
    if (!b->registered)
        shim_register_thread();
    emm_raw_access *r = &b->rec[b->n++];
    r->addr = addr;
    r->bytes_write = bytes | (write ? EMM_RAW_WRITE : 0u);
    r->work = b->work;
    b->work = 0;
    if (b->n == SHIM_TBUF_CAP)
        shim_flush_thread();
}

/* --- rules.c ----------------------------------------------------------- */
/* Parses EMM_TAG; NULL with msg filled on a malformed value. */
struct shim_rules *shim_rules_parse(const char *text, char *msg, size_t cap) SHIM_HIDDEN;
/* The smallest block any rule can select. */
size_t shim_rules_min(const struct shim_rules *r) SHIM_HIDDEN;
/* Whether any rule uses site= (the call stack is needed). */
bool shim_rules_need_stack(const struct shim_rules *r) SHIM_HIDDEN;

/* What a matching rule says about a block. */
struct shim_match {
    emm_array_kind kind;
    size_t stride, offset;
    emm_scalar type;
    int rule;              /* the rule's number, from 1, for the log */
};
/* Whether an allocation of `size` bytes made now (this call stack) is one a
 * rule selects; counts nth= selectors. Called with shim_busy set, without
 * the lock. */
bool shim_rules_match(struct shim_rules *r, size_t size, struct shim_match *out) SHIM_HIDDEN;
/* Opens libunwind for site= (once, before main); false with msg filled. */
bool shim_rules_unwind_init(char *msg, size_t cap) SHIM_HIDDEN;
/* EMM_TAG's check for the env table (shim_env_tag_check). */
bool shim_rules_check(const char *value, char *why, size_t cap) SHIM_HIDDEN;
/* The rules' grammar, for the help text. */
extern const char shim_rules_grammar[] SHIM_HIDDEN;

/* --- capture_fault.c --------------------------------------------------- */
/* Installs the SIGSEGV/SIGTRAP handlers (fault backend). */
bool shim_fault_init(void) SHIM_HIDDEN;
/* Page-aligned private pages for a block a rule tags: NULL on failure. */
void *shim_fault_map(size_t size, size_t *map_len) SHIM_HIDDEN;
/* Protects / unprotects a tagged array's pages (called with the lock). */
void shim_fault_protect(struct shim_tag *t) SHIM_HIDDEN;
void shim_fault_unprotect(struct shim_tag *t) SHIM_HIDDEN;
/* Lifts every protection and stops fault capture (window closed). */
void shim_fault_lift(void) SHIM_HIDDEN;
/* Whether fault capture is still watching (profiling). */
bool shim_fault_watching(void) SHIM_HIDDEN;
/* The C library's sigaction (the shim interposes sigaction and signal). */
int shim_real_sigaction(int sig, const struct sigaction *act, struct sigaction *old) SHIM_HIDDEN;
/* A forked child: unprotect everything, never record. */
void shim_fault_child(void) SHIM_HIDDEN;

/* --- capture_api.c ----------------------------------------------------- */
/* Whether the main program imports `name` (an undefined dynamic symbol). */
bool shim_program_imports(const char *name) SHIM_HIDDEN;

#endif
