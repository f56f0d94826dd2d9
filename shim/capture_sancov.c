/* The sancov capture backend (DESIGN.md "The shim", Capture backends:
 * sancov). A program compiled with
 *   clang -fsanitize-coverage=trace-pc-guard,trace-loads,trace-stores
 *         -fno-vectorize -fno-slp-vectorize
 * calls __sanitizer_cov_load/store<N>(addr) before every load and store and
 * __sanitizer_cov_trace_pc_guard at every edge. It is linked against
 * libemmhooks.so, whose definitions are no-ops; the preloaded shim's come
 * first and win.
 *
 * The hot path: test the address against a small snapshot of the tagged
 * ranges (refreshed under the lock whenever a tag changes), append to the
 * thread's buffer. Edges between two recorded accesses are counted as the
 * record's `work`. (clang 14's `edge` alone emits no callbacks; trace-pc-guard
 * is edge coverage with a callback.) */
#include "shim.h"

#define SANCOV_API __attribute__((visibility("default")))

static inline void hit(const void *p, uint32_t bytes, bool write)
{
    uint64_t a = (uint64_t)(uintptr_t)p;
    size_t n = __atomic_load_n(&shim.nranges, __ATOMIC_ACQUIRE);
    for (size_t i = 0; i < n; i++) {
        if (a - __atomic_load_n(&shim.range_lo[i], __ATOMIC_RELAXED)
            < __atomic_load_n(&shim.range_len[i], __ATOMIC_RELAXED)) {
            if (!shim_busy)
                shim_record(a, bytes, write);
            return;
        }
    }
}

SANCOV_API void __sanitizer_cov_load1(uint8_t *p);
SANCOV_API void __sanitizer_cov_load2(uint16_t *p);
SANCOV_API void __sanitizer_cov_load4(uint32_t *p);
SANCOV_API void __sanitizer_cov_load8(uint64_t *p);
SANCOV_API void __sanitizer_cov_load16(__int128 *p);
SANCOV_API void __sanitizer_cov_store1(uint8_t *p);
SANCOV_API void __sanitizer_cov_store2(uint16_t *p);
SANCOV_API void __sanitizer_cov_store4(uint32_t *p);
SANCOV_API void __sanitizer_cov_store8(uint64_t *p);
SANCOV_API void __sanitizer_cov_store16(__int128 *p);
SANCOV_API void __sanitizer_cov_trace_pc_guard(uint32_t *guard);
SANCOV_API void __sanitizer_cov_trace_pc_guard_init(uint32_t *start, uint32_t *stop);

void __sanitizer_cov_load1(uint8_t *p) { hit(p, 1, false); }
void __sanitizer_cov_load2(uint16_t *p) { hit(p, 2, false); }
void __sanitizer_cov_load4(uint32_t *p) { hit(p, 4, false); }
void __sanitizer_cov_load8(uint64_t *p) { hit(p, 8, false); }
void __sanitizer_cov_load16(__int128 *p) { hit(p, 16, false); }
void __sanitizer_cov_store1(uint8_t *p) { hit(p, 1, true); }
void __sanitizer_cov_store2(uint16_t *p) { hit(p, 2, true); }
void __sanitizer_cov_store4(uint32_t *p) { hit(p, 4, true); }
void __sanitizer_cov_store8(uint64_t *p) { hit(p, 8, true); }
void __sanitizer_cov_store16(__int128 *p) { hit(p, 16, true); }

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
