/* The sancov capture backend (docs/design.md "The shim and the session", Capture backends:
 * sancov). A program compiled with
 *   clang -fsanitize-coverage=trace-pc-guard,trace-loads,trace-stores
 *         -fno-vectorize -fno-slp-vectorize -mllvm -disable-machine-sink
 * calls __sanitizer_cov_load/store<N>(addr) before every load and store and
 * __sanitizer_cov_trace_pc_guard at every edge. It is linked against
 * libemmhooks.so, whose definitions are no-ops; the preloaded shim's come
 * first and win.
 *
 * The hot path: test the address against a small snapshot of the tagged
 * ranges (refreshed under the lock whenever a tag changes), append to the
 * thread's buffer, with the hook's return address: the program counter of
 * the access, for emm annotate. Edges between two recorded accesses are
 * counted as the record's `work`. (clang 14's `edge` alone emits no callbacks; trace-pc-guard
 * is edge coverage with a callback.) */
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>

#include "shim.h"

/* The agent's snapshot of the tagged ranges (emm_agent_filter_of), read
 * on every access without a lock. */
static const emm_agent_filter *filter; /* atomic */

static void ranges(emm_agent *a)
{
    __atomic_store_n(&filter, emm_agent_filter_of(a), __ATOMIC_RELEASE);
}

static void fork_child(void)
{
    __atomic_store_n(&filter, NULL, __ATOMIC_RELEASE);
}

/* A program built with emm_sancov_executable links libemmhooks.so. */
static bool wanted(void)
{
    return dlsym(RTLD_DEFAULT, "emm_sancov_hooks_present") != NULL;
}

static bool init(char *msg, size_t msg_cap)
{
    (void)msg;
    (void)msg_cap;
    if (!wanted() && shim.config.log >= 1)
        shim_log("EMM_CAPTURE=sancov, but %s was not built with emm_sancov_executable: "
                 "no accesses will be seen", program_invocation_short_name);
    return true;
}

const struct shim_capture_ops shim_capture_sancov = {
    .wanted = wanted,
    .init = init,
    .hooks = {.ranges = ranges},
    .fork_child = fork_child,
};

static inline void hit(const void *p, uint32_t bytes, bool write, const void *pc)
{
    uint64_t a = (uint64_t)(uintptr_t)p;
    const emm_agent_filter *f = __atomic_load_n(&filter, __ATOMIC_ACQUIRE);
    if (!f)
        return;
    size_t n = __atomic_load_n(&f->n, __ATOMIC_ACQUIRE);
    const uint64_t *lo = __atomic_load_n(&f->lo, __ATOMIC_ACQUIRE),
                   *len = __atomic_load_n(&f->len, __ATOMIC_ACQUIRE);
    for (size_t i = 0; i < n; i++) {
        if (a - __atomic_load_n(&lo[i], __ATOMIC_RELAXED) <
            __atomic_load_n(&len[i], __ATOMIC_RELAXED)) {
            if (!shim_busy)
                shim_record_pc(a, bytes, write, (uint64_t)(uintptr_t)pc);
            return;
        }
    }
}

#define HOOKS(N, T)                                                                          \
    SHIM_API void __sanitizer_cov_load##N(T *p);                                              \
    SHIM_API void __sanitizer_cov_store##N(T *p);                                             \
    void __sanitizer_cov_load##N(T *p) { hit(p, N, false, __builtin_return_address(0)); }     \
    void __sanitizer_cov_store##N(T *p) { hit(p, N, true, __builtin_return_address(0)); }
HOOKS(1, uint8_t)
HOOKS(2, uint16_t)
HOOKS(4, uint32_t)
HOOKS(8, uint64_t)
HOOKS(16, __int128)

SHIM_API void __sanitizer_cov_trace_pc_guard(uint32_t *guard);
SHIM_API void __sanitizer_cov_trace_pc_guard_init(uint32_t *start, uint32_t *stop);

void __sanitizer_cov_trace_pc_guard(uint32_t *guard)
{
    (void)guard;
    struct shim_tbuf *b = &shim_tbuf;
    if (b->work != UINT32_MAX)
        b->work++;
}

/* Guards need not be numbered: every edge counts the same. */
void __sanitizer_cov_trace_pc_guard_init(uint32_t *start, uint32_t *stop)
{
    for (uint32_t *g = start; g < stop; g++)
        *g = 1;
}
