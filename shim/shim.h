/* Internal to libemmshim.so: the one process-wide context the preloaded
 * library needs (docs/design.md "The shim and the session").
 *
 * A preloaded allocator cannot take an explicit context: malloc has no
 * handle argument. So the shim keeps exactly one struct, `shim`, and every
 * piece of it is either written once at start-up (before main) or guarded by
 * shim.lock; the capture fast paths read a small snapshot with relaxed
 * atomics. The settings are core's configuration table (emm/config.h), the
 * analysis is the runtime's session (emm/session.h), and each capture
 * backend is an ops table in its own file. */
#ifndef EMM_SHIM_H
#define EMM_SHIM_H

#include <pthread.h>
#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "emm/config.h"
#include "emm/session.h"
#include "emm/sites.h"

#define SHIM_TLS __attribute__((tls_model("initial-exec")))
#define SHIM_HIDDEN __attribute__((visibility("hidden")))
#define SHIM_API __attribute__((visibility("default")))
/* The exit status of a program stopped by EMM_STRICT=1. */
#define SHIM_STRICT_EXIT 125

/* The libc allocator, resolved with dlsym(RTLD_NEXT). */
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

/* One array the shim has told the session about. */
struct shim_tag {
    uintptr_t base;  /* the pointer the program holds (and frees) */
    size_t bytes;    /* bytes the array spans: count * stride */
    emm_array_kind kind;
    size_t stride, offset;
    emm_scalar type;
    int rule;        /* the EMM_TAG rule that selected it (count follows the block's
                        size on realloc), or -1 for an emm_tag_* call */
    void *map;       /* the block's own pages (a backend's map), or NULL */
    size_t map_len;
    bool protected_; /* its pages are PROT_NONE right now (fault) */
};

#define SHIM_MAX_TAGS 64
#define SHIM_TBUF_CAP 1024 /* records per thread buffer before a flush */

struct shim_tbuf {
    emm_raw_access rec[SHIM_TBUF_CAP];
    uint32_t n;
    uint32_t work;   /* instrumented basic blocks since the last record */
    bool registered; /* the thread-exit flush is armed */
};

/* A capture backend (docs/architecture.md, "Adding a capture backend").
 * Every hook may be NULL. Hooks named _locked run with shim.lock held. */
struct shim_capture_ops {
    emm_capture kind;
    /* EMM_CAPTURE=auto: whether this backend suits the program (NULL: as a
     * last resort). */
    bool (*wanted)(void);
    /* Before main, once the session exists; false with msg filled: step aside. */
    bool (*init)(char *msg, size_t cap);
    /* Pages of its own for a block a rule is about to tag (fault), or NULL. */
    void *(*map)(size_t size, size_t align, size_t *map_len);
    void (*on_tag_locked)(struct shim_tag *t);
    void (*on_untag_locked)(struct shim_tag *t);
    /* The tagged ranges changed (sancov's filter snapshot). */
    void (*ranges_locked)(void);
    /* The window closed: the arrays must be readable for the decision. */
    void (*before_decide_locked)(void);
    /* Records held outside the threads' buffers (the valgrind tool's) go to
     * the session (shim_feed_locked); called by every flush. */
    void (*drain_locked)(void);
    /* In a forked child, which never records. */
    void (*fork_child)(void);
};
extern const struct shim_capture_ops shim_capture_sancov SHIM_HIDDEN;
extern const struct shim_capture_ops shim_capture_fault SHIM_HIDDEN;
extern const struct shim_capture_ops shim_capture_api SHIM_HIDDEN;
extern const struct shim_capture_ops shim_capture_valgrind SHIM_HIDDEN;

struct shim {
    /* Set once before main. */
    bool enabled;                       /* a session exists */
    emm_config config;                  /* the EMM_* settings */
    const struct shim_capture_ops *ops; /* the backend in use */
    size_t rule_min;                    /* the fast path: smaller blocks are never tagged */

    pthread_mutex_t lock;               /* the session, the tag table, the rules' counters */
    emm_session *session;
    emm_sites *sites;                   /* EMM_LIST_SITES: the candidate arrays (no session) */
    emm_session_state state;
    bool finished;                      /* finish ran, or a forked child went quiet */
    bool failed;                        /* decide failed: stop capturing */
    struct shim_tag tags[SHIM_MAX_TAGS];
    uint64_t tagged_total;              /* arrays ever tagged, for the log */

    /* Read without the lock. */
    uintptr_t tag_base[SHIM_MAX_TAGS];  /* atomic: free()'s quick check, 0 = empty slot */
    int live_tags;                      /* atomic: entries in tag_base */
};
extern struct shim shim SHIM_HIDDEN;

/* The recursion guard: set while the shim (or the runtime it calls) runs,
 * and for good in the session's helper threads, so their allocations are
 * never tagged and never re-enter the session. */
extern __thread int shim_busy SHIM_TLS SHIM_HIDDEN;
/* Set while the calling thread is inside one of the shim's allocator
 * functions (and so, maybe, inside the C library's allocator). */
extern __thread int shim_in_alloc SHIM_TLS SHIM_HIDDEN;
/* A SIGTERM/SIGINT that arrived while its thread was inside the shim or the
 * allocator, where finishing could deadlock: acted on when the thread
 * leaves (shim_leave, the allocator's return). 0: none. */
extern int shim_pending_signal SHIM_HIDDEN;
void shim_deliver_pending(void) SHIM_HIDDEN;

static inline void shim_leave(void)
{
    if (--shim_busy == 0 && !shim_in_alloc
        && __atomic_load_n(&shim_pending_signal, __ATOMIC_RELAXED))
        shim_deliver_pending();
}

extern __thread struct shim_tbuf shim_tbuf SHIM_TLS SHIM_HIDDEN;

/* Writes one line "emm: ..." to stderr without allocating. */
void shim_log(const char *fmt, ...) __attribute__((format(printf, 1, 2))) SHIM_HIDDEN;

/* --- preload.c ---------------------------------------------------------- */
void shim_resolve(void) SHIM_HIDDEN;
/* Tags / untags an array (explicit calls with rule -1, rules, the api
 * backend). */
void shim_tag_array(emm_array_kind kind, const void *base, size_t bytes, size_t stride,
                    size_t offset, emm_scalar type, int rule, void *map,
                    size_t map_len) SHIM_HIDDEN;
void shim_untag_array(const void *base) SHIM_HIDDEN;
/* Sends the calling thread's buffer, and the backend's records
 * (drain_locked), to the session (takes the lock). */
void shim_flush_thread(void) SHIM_HIDDEN;
/* Feeds records to the session while it captures, and decides when it
 * asks; with shim.lock held. */
void shim_feed_locked(const emm_raw_access *rec, size_t n) SHIM_HIDDEN;
void shim_register_thread(void) SHIM_HIDDEN;
/* The session's ranges, [lo, hi) pairs (up to cap; returns how many). */
size_t shim_ranges_locked(uint64_t *lo, uint64_t *hi, size_t cap) SHIM_HIDDEN;
/* The libc sigaction (the fault backend interposes sigaction and signal). */
int shim_real_sigaction(int sig, const struct sigaction *act, struct sigaction *old) SHIM_HIDDEN;

/* Appends one access to the calling thread's buffer (all backends), with
 * its program counter where the backend knows it (else 0). */
static inline void shim_record_pc(uint64_t addr, uint32_t bytes, bool write, uint64_t pc)
{
    struct shim_tbuf *b = &shim_tbuf;
    if (!b->registered)
        shim_register_thread();
    emm_raw_access *r = &b->rec[b->n++];
    r->addr = addr;
    r->bytes_write = bytes | (write ? EMM_RAW_WRITE : 0u);
    r->work = b->work;
    r->pc = pc;
    b->work = 0;
    if (b->n == SHIM_TBUF_CAP)
        shim_flush_thread();
}

static inline void shim_record(uint64_t addr, uint32_t bytes, bool write)
{
    shim_record_pc(addr, bytes, write, 0);
}

/* --- rules.c: which allocation an EMM_TAG rule selects ------------------- */
/* The smallest block any rule can select (SIZE_MAX: no rules). */
size_t shim_rules_min(void) SHIM_HIDDEN;
/* Opens libunwind when a rule uses site= (once, before main); false with
 * msg filled. */
bool shim_rules_init(char *msg, size_t cap) SHIM_HIDDEN;
/* The rule (index, >= 0) that selects an allocation of `size` bytes made
 * now, from this call stack, or -1; counts nth= selectors; *site gets the
 * name of the frame a site= rule matched (else NULL). Called with
 * shim_busy set, without the lock. */
int shim_rules_match(size_t size, const char **site) SHIM_HIDDEN;
/* One line per rule that selected no block, with the sites seen. */
void shim_rules_report(void) SHIM_HIDDEN;
/* EMM_LIST_SITES: a block of `size` bytes just allocated at `block`, from
 * this call stack, into shim.sites (takes the lock). */
void shim_rules_list(const void *block, size_t size) SHIM_HIDDEN;

#endif
