/* Internal to libemmshim.so: the one process-wide context the preloaded
 * library needs (docs/architecture.md "The shim").
 *
 * A preloaded allocator cannot take an explicit context: malloc has no
 * handle argument. So the shim keeps exactly one struct, `shim`, written
 * once at start-up (before main) and read after. Everything else is the
 * runtime's: the settings are core's configuration table (emm/config.h),
 * the tag table, the rules and the session's driving are the agent's
 * (emm/agent.h), and each capture backend is an ops table in its own file,
 * one per line of EMM_CAPTURE_LIST. */
#ifndef EMM_SHIM_H
#define EMM_SHIM_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "emm/agent.h"
#include "emm/config.h"

#define SHIM_TLS __attribute__((tls_model("initial-exec")))
#define SHIM_HIDDEN __attribute__((visibility("hidden")))
#define SHIM_API __attribute__((visibility("default")))
#define SHIM_TBUF_CAP 1024 /* records per thread buffer before a flush */

struct shim_tbuf {
    emm_raw_access rec[SHIM_TBUF_CAP];
    uint32_t n;
    uint32_t work;   /* instrumented basic blocks since the last record */
    bool registered; /* the thread-exit flush is armed */
};

/* A capture backend (docs/architecture.md, "Adding a part"): every field
 * may be NULL. */
struct shim_capture_ops {
    /* EMM_CAPTURE=auto: whether this backend suits the program. */
    bool (*wanted)(void);
    /* Before main, before the agent starts; false with msg filled: the
     * shim steps aside. */
    bool (*init)(char *msg, size_t cap);
    /* Its side of the agent's events (emm/agent.h). */
    emm_agent_hooks hooks;
    /* In a forked child, which never records. */
    void (*fork_child)(void);
};

/* One per backend of EMM_CAPTURE_LIST (emm/config.h): shim_capture_NAME,
 * defined in shim/capture_NAME.c. */
#define SHIM_CAPTURE_DECLARE(N, n, caps, work, help) \
    extern const struct shim_capture_ops shim_capture_##n SHIM_HIDDEN;
EMM_CAPTURE_LIST(SHIM_CAPTURE_DECLARE)
#undef SHIM_CAPTURE_DECLARE

struct shim {
    bool enabled;                       /* the agent exists */
    emm_config config;                  /* the EMM_* settings */
    const struct shim_capture_ops *ops; /* the backend in use */
    emm_capture capture;                /* which it is */
    emm_agent *agent;
    size_t min_block;                   /* the fast path: smaller blocks never need the agent */
};
extern struct shim shim SHIM_HIDDEN;

/* The recursion guard: set while the shim (or the runtime it calls) runs,
 * and for good in the session's helper threads, so their allocations are
 * never tagged and never re-enter the agent. */
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
#define shim_log emm_agent_say

/* Sends the calling thread's buffer, and the backend's records (its drain
 * hook), to the agent. */
void shim_flush_thread(void) SHIM_HIDDEN;
void shim_register_thread(void) SHIM_HIDDEN;
/* The libc sigaction (the fault backend interposes sigaction and signal). */
struct sigaction;
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

#endif
