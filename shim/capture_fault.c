/* The fault capture backend (docs/design.md "The shim and the session", Capture backends:
 * fault): an unmodified binary's accesses to the tagged arrays, seen by protecting their
 * pages and single-stepping each access.
 *
 * - Arrays that EMM_TAG rules select get pages of their own (the allocator
 *   serves them with mmap); the whole mapping is protected. An array tagged
 *   after its allocation (emm_tag_*) shares its first and last pages with
 *   other heap data: only the pages wholly inside it are protected, so the
 *   C library never meets a protected page in its own data (a stdio buffer
 *   beside the array would make the kernel's write fail with EFAULT). The
 *   records on those edge pages are not seen.
 * - SIGSEGV on a protected page: record the access (address from si_addr;
 *   8 bytes, the size of a coordinate or a pointer, since decoding the
 *   instruction is not worth it; write from the page-fault error code),
 *   unprotect the page, set the trap flag so that SIGTRAP follows the one
 *   instruction, then protect the page again and clear the flag.
 * - Costs tens of microseconds per access, so it covers the profiling window
 *   only: when the session wants to decide, every protection is lifted and
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
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <ucontext.h>
#include <unistd.h>

#include "shim.h"

#define TRAP_FLAG 0x100

/* The protected pages of tag slot i; plo == phi: none. Read by the signal
 * handlers without the lock. */
static struct {
    uintptr_t plo, phi;   /* protected pages */
    uintptr_t lo, hi;     /* the array's bytes */
    int io;               /* system calls that have the pages open */
} reg[SHIM_MAX_TAGS];

static bool watching;     /* profiling: protect new arrays, reprotect pages */
static bool installed;    /* our SIGSEGV/SIGTRAP handlers are in place */
static struct sigaction saved_segv, saved_trap;  /* the program's */

static __thread uintptr_t pending[4] SHIM_TLS;
static __thread int npending SHIM_TLS;

static size_t page_size(void)
{
    static size_t ps;
    if (!ps)
        ps = (size_t)sysconf(_SC_PAGESIZE);
    return ps;
}

static bool watching_now(void)
{
    return __atomic_load_n(&watching, __ATOMIC_RELAXED);
}

/* A block a rule tags while profiling gets pages of its own. */
static void *map(size_t size, size_t align, size_t *map_len)
{
    size_t ps = page_size();
    if (!watching_now() || align > ps)
        return NULL;
    size_t len = (size + ps - 1) & ~(ps - 1);
    if (len < size)
        return NULL;
    void *p = mmap(NULL, len, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED)
        return NULL;
    *map_len = len;
    return p;
}

static void protect(struct shim_tag *t)
{
    size_t i = (size_t)(t - shim.tags), ps = page_size();
    uintptr_t plo, phi;
    if (t->map) {
        plo = (uintptr_t)t->map;
        phi = plo + t->map_len;
    } else {
        plo = (t->base + ps - 1) & ~(uintptr_t)(ps - 1);
        phi = (t->base + t->bytes) & ~(uintptr_t)(ps - 1);
    }
    if (plo >= phi)
        return;
    __atomic_store_n(&reg[i].lo, t->base, __ATOMIC_RELAXED);
    __atomic_store_n(&reg[i].hi, t->base + t->bytes, __ATOMIC_RELAXED);
    __atomic_store_n(&reg[i].plo, plo, __ATOMIC_RELAXED);
    __atomic_store_n(&reg[i].phi, phi, __ATOMIC_RELEASE);
    if (reg[i].io == 0)
        mprotect((void *)plo, phi - plo, PROT_NONE);
    t->protected_ = true;
}

/* Pages opened for good lately: a thread's fault on one of them whose
 * handler ran only after the pages opened and the region left `reg` is
 * retried, not taken for the program's own. */
#define LIFTED 16
static struct {
    uintptr_t lo, hi;
} lifted[LIFTED];
static unsigned nlifted; /* atomic: lifted ranges ever recorded */
static __thread uintptr_t retried SHIM_TLS; /* the address last retried by this thread */

static void unprotect(struct shim_tag *t)
{
    size_t i = (size_t)(t - shim.tags);
    uintptr_t plo = reg[i].plo, phi = reg[i].phi;
    /* Open the pages before the region leaves `reg`: another thread that
     * faults on them meanwhile must still find its region (a fault on a
     * page no region claims is the program's own). */
    if (plo < phi) {
        mprotect((void *)plo, phi - plo, PROT_READ | PROT_WRITE);
        unsigned k = __atomic_load_n(&nlifted, __ATOMIC_RELAXED) % LIFTED;
        __atomic_store_n(&lifted[k].lo, 0, __ATOMIC_RELAXED);
        __atomic_store_n(&lifted[k].hi, phi, __ATOMIC_RELAXED);
        __atomic_store_n(&lifted[k].lo, plo, __ATOMIC_RELEASE);
        __atomic_add_fetch(&nlifted, 1, __ATOMIC_RELEASE);
    }
    __atomic_store_n(&reg[i].phi, 0, __ATOMIC_RELEASE);
    __atomic_store_n(&reg[i].plo, 0, __ATOMIC_RELAXED);
    reg[i].io = 0;
    t->protected_ = false;
}

/* A fault no region claims on pages opened lately: its handler ran late.
 * Retried once per address and thread (returning re-runs the access on
 * the open page); a second fault there is the program's own. */
static bool retry_lifted(uintptr_t a)
{
    if (retried == a)
        return false;
    for (unsigned k = 0; k < LIFTED; k++) {
        uintptr_t lo = __atomic_load_n(&lifted[k].lo, __ATOMIC_ACQUIRE);
        if (lo && a >= lo && a < __atomic_load_n(&lifted[k].hi, __ATOMIC_RELAXED)) {
            retried = a;
            return true;
        }
    }
    return false;
}

static void on_tag_locked(struct shim_tag *t)
{
    if (t->protected_)
        unprotect(t);
    if (watching_now())
        protect(t);
}

static void on_untag_locked(struct shim_tag *t)
{
    if (t->protected_)
        unprotect(t);
}

/* The window closed: every protection is lifted and capture stops. */
static void lift_locked(void)
{
    /* Before the pages open: a trap handler that protects a page again
     * after this store sees it and opens the page (on_trap). */
    __atomic_store_n(&watching, false, __ATOMIC_SEQ_CST);
    for (size_t i = 0; i < SHIM_MAX_TAGS; i++)
        if (shim.tags[i].base && shim.tags[i].protected_)
            unprotect(&shim.tags[i]);
}

static void fork_child(void)
{
    lift_locked();
    npending = 0;
}

static int region_of(uintptr_t a)
{
    for (int i = 0; i < SHIM_MAX_TAGS; i++) {
        uintptr_t plo = __atomic_load_n(&reg[i].plo, __ATOMIC_RELAXED);
        uintptr_t phi = __atomic_load_n(&reg[i].phi, __ATOMIC_ACQUIRE);
        if (a >= plo && a < phi)
            return i;
    }
    return -1;
}

/* A signal that is not ours goes to the program's handler, or gets the
 * default action. */
static void chain(int sig, siginfo_t *si, void *uctx)
{
    struct sigaction *pa = sig == SIGSEGV ? &saved_segv : &saved_trap;
    if (pa->sa_flags & SA_SIGINFO) {
        void (*h)(int, siginfo_t *, void *) = pa->sa_sigaction;
        if (pa->sa_flags & SA_RESETHAND)
            pa->sa_handler = SIG_DFL, pa->sa_flags &= ~SA_SIGINFO;
        h(sig, si, uctx);
        return;
    }
    void (*h)(int) = pa->sa_handler;
    if (h == SIG_IGN && sig == SIGTRAP)
        return;
    if (h == SIG_DFL || h == SIG_IGN) {
        /* The default action: for a real fault, returning re-runs the
         * instruction, which faults again without us; a sent or trap-made
         * signal is raised again. */
        struct sigaction dfl;
        memset(&dfl, 0, sizeof dfl);
        dfl.sa_handler = SIG_DFL;
        shim_real_sigaction(sig, &dfl, NULL);
        if (sig == SIGTRAP || si->si_code <= 0)
            raise(sig);
        return;
    }
    if (pa->sa_flags & SA_RESETHAND)
        pa->sa_handler = SIG_DFL;
    h(sig);
}

static void on_segv(int sig, siginfo_t *si, void *uctx)
{
    uintptr_t a = (uintptr_t)si->si_addr;
    int r = si->si_code == SEGV_ACCERR ? region_of(a) : -1;
    if (r < 0) {
        if (si->si_code == SEGV_ACCERR && retry_lifted(a))
            return;
        chain(sig, si, uctx);
        return;
    }
    retried = 0;
    ucontext_t *uc = uctx;
    uintptr_t page = a & ~(uintptr_t)(page_size() - 1);
    bool write = (uc->uc_mcontext.gregs[REG_ERR] & 2) != 0;
    if (watching_now() && !shim_busy && a >= reg[r].lo && a < reg[r].hi)
        shim_record(a, 8, write);
    mprotect((void *)page, page_size(), PROT_READ | PROT_WRITE);
    if (npending < 4)
        pending[npending++] = page;
    uc->uc_mcontext.gregs[REG_EFL] |= TRAP_FLAG;
}

static void on_trap(int sig, siginfo_t *si, void *uctx)
{
    ucontext_t *uc = uctx;
    if (npending == 0 || !(uc->uc_mcontext.gregs[REG_EFL] & TRAP_FLAG)) {
        chain(sig, si, uctx);
        return;
    }
    for (int i = 0; i < npending; i++) {
        int r = region_of(pending[i]);
        if (r >= 0 && watching_now() && __atomic_load_n(&reg[r].io, __ATOMIC_RELAXED) == 0) {
            mprotect((void *)pending[i], page_size(), PROT_NONE);
            /* The window closed meanwhile (lift_locked) or the region
             * left: its pages stay open. */
            if (!__atomic_load_n(&watching, __ATOMIC_SEQ_CST) || region_of(pending[i]) != r)
                mprotect((void *)pending[i], page_size(), PROT_READ | PROT_WRITE);
        }
    }
    npending = 0;
    uc->uc_mcontext.gregs[REG_EFL] &= ~(greg_t)TRAP_FLAG;
}

static bool init(char *msg, size_t cap)
{
    snprintf(msg, cap, "EMM_CAPTURE=fault: cannot install the SIGSEGV/SIGTRAP handlers");
    if (shim_real_sigaction(SIGSEGV, NULL, &saved_segv) != 0
        || shim_real_sigaction(SIGTRAP, NULL, &saved_trap) != 0)
        return false;
    struct sigaction act;
    memset(&act, 0, sizeof act);
    sigemptyset(&act.sa_mask);
    act.sa_flags = SA_SIGINFO;
    act.sa_sigaction = on_segv;
    if (shim_real_sigaction(SIGSEGV, &act, NULL) != 0)
        return false;
    act.sa_sigaction = on_trap;
    if (shim_real_sigaction(SIGTRAP, &act, NULL) != 0)
        return false;
    __atomic_store_n(&installed, true, __ATOMIC_RELEASE);
    __atomic_store_n(&watching, true, __ATOMIC_RELEASE);
    return true;
}

const struct shim_capture_ops shim_capture_fault = {
    .kind = EMM_CAPTURE_FAULT,
    .init = init,
    .map = map,
    .on_tag_locked = on_tag_locked,
    .on_untag_locked = on_untag_locked,
    .before_decide_locked = lift_locked,
    .fork_child = fork_child,
};

/* --- the program's signal handlers ------------------------------------- */

SHIM_API int sigaction(int sig, const struct sigaction *act, struct sigaction *old);
SHIM_API sighandler_t signal(int sig, sighandler_t handler);

int sigaction(int sig, const struct sigaction *act, struct sigaction *old)
{
    if (__atomic_load_n(&installed, __ATOMIC_ACQUIRE) && (sig == SIGSEGV || sig == SIGTRAP)) {
        struct sigaction *pa = sig == SIGSEGV ? &saved_segv : &saved_trap;
        if (old)
            *old = *pa;
        if (act)
            *pa = *act;
        return 0;
    }
    return shim_real_sigaction(sig, act, old);
}

sighandler_t signal(int sig, sighandler_t handler)
{
    static sighandler_t (*real)(int, sighandler_t);
    if (!__atomic_load_n(&installed, __ATOMIC_ACQUIRE) || (sig != SIGSEGV && sig != SIGTRAP)) {
        if (!real)
            real = (sighandler_t (*)(int, sighandler_t))dlsym(RTLD_NEXT, "signal");
        return real(sig, handler);
    }
    struct sigaction act, old;
    memset(&act, 0, sizeof act);
    act.sa_handler = handler;
    sigemptyset(&act.sa_mask);
    act.sa_flags = SA_RESTART;
    sigaction(sig, &act, &old);
    return (old.sa_flags & SA_SIGINFO) ? (sighandler_t)(void (*)(void))old.sa_sigaction : old.sa_handler;
}

/* --- system calls on protected memory ---------------------------------- */

/* Opens the protected pages that [p, p + n) touches; returns which. */
static uint64_t io_begin(const void *p, size_t n)
{
    if (!__atomic_load_n(&installed, __ATOMIC_RELAXED) || !watching_now() || shim_busy || n == 0)
        return 0;
    uintptr_t a = (uintptr_t)p, b = a + n;
    uint64_t mask = 0;
    for (int i = 0; i < SHIM_MAX_TAGS; i++)
        if (__atomic_load_n(&reg[i].phi, __ATOMIC_RELAXED) > a
            && __atomic_load_n(&reg[i].plo, __ATOMIC_RELAXED) < b)
            mask |= 1ull << i;
    if (!mask)
        return 0;
    shim_busy++;
    pthread_mutex_lock(&shim.lock);
    for (int i = 0; i < SHIM_MAX_TAGS; i++)
        if ((mask >> i & 1) && reg[i].plo < reg[i].phi) {
            if (reg[i].io++ == 0)
                mprotect((void *)reg[i].plo, reg[i].phi - reg[i].plo, PROT_READ | PROT_WRITE);
        } else {
            mask &= ~(1ull << i);
        }
    pthread_mutex_unlock(&shim.lock);
    shim_busy--;
    return mask;
}

static void io_end(uint64_t mask)
{
    if (!mask)
        return;
    shim_busy++;
    pthread_mutex_lock(&shim.lock);
    for (int i = 0; i < SHIM_MAX_TAGS; i++)
        if ((mask >> i & 1) && reg[i].io > 0 && --reg[i].io == 0 && reg[i].plo < reg[i].phi
            && watching_now())
            mprotect((void *)reg[i].plo, reg[i].phi - reg[i].plo, PROT_NONE);
    pthread_mutex_unlock(&shim.lock);
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
        uint64_t m = io_begin(buf, len);                                                      \
        ret r = real_##name args;                                                             \
        io_end(m);                                                                            \
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
