/* The fault capture backend (docs/design.md "The shim and the session",
 * Capture backends: fault): an unmodified binary's accesses to the tagged
 * arrays, seen by protecting their pages and single-stepping each access.
 * Which pages are protected, and which a fault belongs to, is the runtime's
 * page guard (emm/guard.h); this file is the signal plumbing around it.
 *
 * - Arrays that EMM_TAG rules select get pages of their own (the allocator
 *   serves them with mmap); the whole mapping is protected. An array tagged
 *   after its allocation (emm_tag_*) keeps only the pages wholly inside it
 *   protected; the records on its edge pages are not seen.
 * - SIGSEGV on a protected page: record the access (address from si_addr;
 *   8 bytes, the size of a coordinate or a pointer, since decoding the
 *   instruction is not worth it; write from the page-fault error code),
 *   unprotect the page, run the one instruction — copied into a slot of
 *   the thread's ending in int3, or in place under the trap flag
 *   (emm_guard_step) — and at its SIGTRAP protect the page again.
 * - Until the first read, writes open their page for the next ones
 *   (emm_guard_build_open): a loader faults once a page, not once a write.
 * - Costs tens of microseconds per access (bench/fault_overhead.sh), so it
 *   covers the profiling window only: when the session wants to decide, every protection is lifted and
 *   capture stops (the report says capture "fault").
 * - Threads other than the faulting one may slip through a page while it is
 *   open: capture is exact single-threaded, approximate otherwise.
 * - System calls that pass protected memory to the kernel would fail with
 *   EFAULT instead of faulting: read, write, pread, pwrite, recv, send,
 *   fread and fwrite open the pages they touch for the call.
 * - The program's own SIGSEGV and SIGTRAP handlers are kept (sigaction and
 *   signal are interposed) and called for every fault that is not ours. */
#include <dlfcn.h>
#include <signal.h>
#include <stdio.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <ucontext.h>
#include <unistd.h>

#include "emm/guard.h"
#include "shim.h"

#define TRAP_FLAG 0x100

static emm_guard *guard;
static bool installed; /* our SIGSEGV/SIGTRAP handlers are in place */
static size_t page_size;

/* The calling thread's step: the pages its fault opened, until it ends. */
static __thread emm_guard_step step SHIM_TLS;
static __thread uintptr_t retried[2] SHIM_TLS; /* the address last retried, and how often */

/* A block a rule tags while profiling gets pages of its own. */
static void *map(size_t size, size_t align, size_t *map_len)
{
    if (!emm_guard_watching(guard) || align > page_size)
        return NULL;
    size_t len = (size + page_size - 1) & ~(page_size - 1);
    if (len < size)
        return NULL;
    void *p = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED)
        return NULL;
    *map_len = len;
    return p;
}

static void on_tag(const emm_agent_block *b)
{
    emm_guard_protect(guard, b->base, b->bytes, b->map, b->map_len);
}

static void on_untag(const emm_agent_block *b)
{
    emm_guard_unprotect(guard, b->base);
}

/* The window closed: every protection is lifted and capture stops. */
static void lift(void)
{
    emm_guard_lift(guard);
}

static void fork_child(void)
{
    emm_guard_lift(guard);
    step.n = 0;
}

/* The end of what a loader wrote on a page it had open (emm_guard_build_open). */
static void note_written(uintptr_t a)
{
    if (emm_guard_watching(guard) && !shim_busy)
        shim_record(a, 8, true);
}

static void on_segv(int sig, siginfo_t *si, void *uctx)
{
    uintptr_t a = (uintptr_t)si->si_addr;
    ucontext_t *uc = uctx;
    uintptr_t *pc = (uintptr_t *)&uc->uc_mcontext.gregs[REG_RIP];
    int in_array = 0;
    emm_guard_region *r = si->si_code == SEGV_ACCERR ? emm_guard_find(guard, a, &in_array) : NULL;
    if (!r) {
        /* A fault on pages opened lately: its handler ran late. */
        if (si->si_code == SEGV_ACCERR && emm_guard_retry(guard, a, retried))
            return;
        emm_guard_step_abandon(guard, &step, pc);
        emm_guard_chain(guard, sig, si, uctx);
        return;
    }
    retried[0] = 0;
    uintptr_t page = a & ~(uintptr_t)(page_size - 1);
    bool write = (uc->uc_mcontext.gregs[REG_ERR] & 2) != 0;
    if (emm_guard_watching(guard) && !shim_busy && in_array)
        shim_record(a, 8, write);
    if (emm_guard_build_open(guard, r, page, write, note_written))
        return; /* the mesh is being built: the page stays open, no single step */
    if (emm_guard_step_begin(guard, &step, r, page, pc))
        uc->uc_mcontext.gregs[REG_EFL] |= TRAP_FLAG;
}

static void on_trap(int sig, siginfo_t *si, void *uctx)
{
    ucontext_t *uc = uctx;
    if (!emm_guard_step_end(guard, &step, (uintptr_t *)&uc->uc_mcontext.gregs[REG_RIP],
                            (uc->uc_mcontext.gregs[REG_EFL] & TRAP_FLAG) != 0)) {
        emm_guard_chain(guard, sig, si, uctx);
        return;
    }
    uc->uc_mcontext.gregs[REG_EFL] &= ~(greg_t)TRAP_FLAG;
}

static bool init(char *msg, size_t cap)
{
    page_size = (size_t)sysconf(_SC_PAGESIZE);
    snprintf(msg, cap, "EMM_CAPTURE=fault: cannot install the SIGSEGV/SIGTRAP handlers");
    if (!(guard = emm_guard_new()) ||
        !emm_guard_install(guard, shim_real_sigaction, on_segv, on_trap))
        return false;
    __atomic_store_n(&installed, true, __ATOMIC_RELEASE);
    return true;
}

const struct shim_capture_ops shim_capture_fault = {
    .init = init,
    .hooks = {.map = map, .on_tag = on_tag, .on_untag = on_untag, .before_decide = lift},
    .fork_child = fork_child,
};

/* --- the program's signal handlers ------------------------------------- */

SHIM_API int sigaction(int sig, const struct sigaction *act, struct sigaction *old);
SHIM_API sighandler_t signal(int sig, sighandler_t handler);

int sigaction(int sig, const struct sigaction *act, struct sigaction *old)
{
    if (__atomic_load_n(&installed, __ATOMIC_ACQUIRE) && (sig == SIGSEGV || sig == SIGTRAP))
        return emm_guard_sigaction(guard, sig, act, old);
    return shim_real_sigaction(sig, act, old);
}

sighandler_t signal(int sig, sighandler_t handler)
{
    static sighandler_t (*next)(int, sighandler_t);
    if (__atomic_load_n(&installed, __ATOMIC_ACQUIRE) && (sig == SIGSEGV || sig == SIGTRAP))
        return emm_guard_signal(guard, sig, handler);
    if (!next)
        next = (sighandler_t (*)(int, sighandler_t))dlsym(RTLD_NEXT, "signal");
    return next(sig, handler);
}

/* --- system calls on protected memory ---------------------------------- */

/* Opens the protected pages that [p, p + n) touches; returns which. */
static void *io_begin(const void *p, size_t n)
{
    if (!__atomic_load_n(&installed, __ATOMIC_RELAXED) || shim_busy || n == 0)
        return NULL;
    shim_busy++;
    void *t = emm_guard_io_begin(guard, p, n);
    shim_busy--;
    return t;
}

static void io_end(void *t)
{
    if (!t)
        return;
    shim_busy++;
    emm_guard_io_end(guard, t);
    shim_busy--;
}

/* The next definition of `name` (the C library's, or libemm's). */
#define REAL(name)                                        \
    static __typeof__(name) *real_##name;                 \
    if (!real_##name)                                     \
        real_##name = (__typeof__(name) *)dlsym(RTLD_NEXT, #name)

/* Each wrapper opens the pages its buffer touches for the call. */
#define IO_WRAP(ret, name, params, args, buf, len)                                            \
    SHIM_API ret name params;                                                                 \
    ret name params                                                                           \
    {                                                                                         \
        REAL(name);                                                                           \
        void *t = io_begin(buf, len);                                                         \
        ret r = real_##name args;                                                             \
        io_end(t);                                                                            \
        return r;                                                                             \
    }
IO_WRAP(ssize_t, read, (int fd, void *b, size_t n), (fd, b, n), b, n)
IO_WRAP(ssize_t, write, (int fd, const void *b, size_t n), (fd, b, n), b, n)
IO_WRAP(ssize_t, pread, (int fd, void *b, size_t n, off_t o), (fd, b, n, o), b, n)
IO_WRAP(ssize_t, pwrite, (int fd, const void *b, size_t n, off_t o), (fd, b, n, o), b, n)
IO_WRAP(ssize_t, recv, (int fd, void *b, size_t n, int fl), (fd, b, n, fl), b, n)
IO_WRAP(ssize_t, send, (int fd, const void *b, size_t n, int fl), (fd, b, n, fl), b, n)
IO_WRAP(size_t, fread, (void *b, size_t s, size_t n, FILE *f), (b, s, n, f), b,
        s && n <= SIZE_MAX / s ? s * n : 0)
IO_WRAP(size_t, fwrite, (const void *b, size_t s, size_t n, FILE *f), (b, s, n, f), b,
        s && n <= SIZE_MAX / s ? s * n : 0)
