/* libemmshim.so: interposition and forwarding (docs/architecture.md "The
 * shim"; after heaptrack's preload layer). The settings are core's
 * configuration table, the tag table, the rules and the session's driving
 * the runtime's agent (emm/agent.h), and each capture backend an ops table
 * in its own file (capture_*.c).
 *
 * - malloc and friends are resolved with dlsym(RTLD_NEXT); dlsym allocates,
 *   so while it runs allocations come from a static bootstrap arena that is
 *   never handed to the real free.
 * - An initial-exec TLS counter (shim_busy) marks the shim's own work: its
 *   allocations and the runtime's go straight to the C library, never
 *   tagged and never re-entering the agent. The session's helper threads
 *   set it for good when they start (emm_threads.on_start).
 * - The fast path of an allocation is a size test against the smallest block
 *   any EMM_TAG rule can select; only larger blocks reach the agent, and
 *   free() asks the agent's lock-free filter.
 * - fork: the child goes quiet (no session, no report: the parent's report
 *   covers the run); exec: LD_PRELOAD carries the shim into the new image,
 *   which starts its own session.
 * - The session is finished at exit (a destructor, which runs after the
 *   program's atexit handlers), in _exit/_Exit, and on SIGTERM, SIGINT,
 *   SIGSEGV, SIGBUS, SIGFPE, SIGILL and SIGABRT when the program has no
 *   handler of its own (on_terminate says when it cannot).
 * - Each thread's buffer is flushed when it fills, when the thread exits and
 *   before the thread tags, frees or ends an iteration. At finish only the
 *   finishing thread's buffer is flushed: threads still running then (not
 *   joined before exit) lose up to SHIM_TBUF_CAP - 1 records each, because
 *   reading a buffer its owner may be writing would need a lock or atomics
 *   on every recorded access. */
#include <dlfcn.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "shim.h"

/* The libc allocator, resolved with dlsym(RTLD_NEXT). */
static struct {
    void *(*malloc)(size_t);
    void *(*calloc)(size_t, size_t);
    void *(*realloc)(void *, size_t);
    void (*free)(void *);
    int (*posix_memalign)(void **, size_t, size_t);
    void *(*aligned_alloc)(size_t, size_t);
    void *(*memalign)(size_t, size_t);
    void *(*valloc)(size_t);
    size_t (*malloc_usable_size)(void *);
} real;
struct shim shim = {.min_block = SIZE_MAX};
__thread int shim_busy SHIM_TLS;
__thread struct shim_tbuf shim_tbuf SHIM_TLS;
__thread int shim_in_alloc SHIM_TLS;
int shim_pending_signal;

static pthread_key_t thread_key;

/* --- the bootstrap arena ------------------------------------------------- */

#define ARENA_BYTES (256 * 1024)
static _Alignas(64) unsigned char arena[ARENA_BYTES];
static size_t arena_used;
static int resolving;

static bool in_arena(const void *p)
{
    return (const unsigned char *)p >= arena && (const unsigned char *)p < arena + ARENA_BYTES;
}

/* A block from the arena: a 16-byte header holds its size. */
static void *arena_alloc(size_t size, size_t align)
{
    if (align < 16)
        align = 16;
    size_t at = __atomic_load_n(&arena_used, __ATOMIC_RELAXED), start, end;
    do {
        start = (at + 16 + align - 1) & ~(align - 1);
        end = start + ((size + 15) & ~(size_t)15);
        if (end > ARENA_BYTES || end < start)
            return NULL;
    } while (!__atomic_compare_exchange_n(&arena_used, &at, end, false, __ATOMIC_RELAXED,
                                          __ATOMIC_RELAXED));
    memcpy(arena + start - 16, &size, sizeof size);
    return arena + start;
}

static size_t arena_size(const void *p)
{
    size_t s;
    memcpy(&s, (const unsigned char *)p - 16, sizeof s);
    return s;
}

static void resolve(void)
{
    if (__atomic_load_n(&real.malloc, __ATOMIC_ACQUIRE))
        return;
    resolving = 1;
    __typeof__(real) r;
    *(void **)&r.malloc = dlsym(RTLD_NEXT, "malloc");
    *(void **)&r.calloc = dlsym(RTLD_NEXT, "calloc");
    *(void **)&r.realloc = dlsym(RTLD_NEXT, "realloc");
    *(void **)&r.free = dlsym(RTLD_NEXT, "free");
    *(void **)&r.posix_memalign = dlsym(RTLD_NEXT, "posix_memalign");
    *(void **)&r.aligned_alloc = dlsym(RTLD_NEXT, "aligned_alloc");
    *(void **)&r.memalign = dlsym(RTLD_NEXT, "memalign");
    *(void **)&r.valloc = dlsym(RTLD_NEXT, "valloc");
    *(void **)&r.malloc_usable_size = dlsym(RTLD_NEXT, "malloc_usable_size");
    if (!r.malloc || !r.calloc || !r.realloc || !r.free) {
        shim_log("libemmshim.so: cannot find the C library's allocator");
        abort();
    }
    void *(*m)(size_t) = r.malloc;
    r.malloc = NULL;
    real = r;
    __atomic_store_n(&real.malloc, m, __ATOMIC_RELEASE);
    resolving = 0;
}

/* The allocator is not resolved yet: while dlsym runs, the arena serves. */
#define BOOTSTRAP(arena_call)                                                                 \
    if (!real.malloc) {                                                                       \
        if (resolving)                                                                        \
            return arena_call;                                                                \
        resolve();                                                                            \
    }

/* --- the threads' buffers ------------------------------------------------ */

void shim_flush_thread(void)
{
    struct shim_tbuf *b = &shim_tbuf;
    if (!shim.enabled || (b->n == 0 && !shim.ops->hooks.drain))
        return;
    shim_busy++;
    emm_agent_feed(shim.agent, b->rec, b->n);
    b->n = 0;
    shim_leave();
}

static void thread_exit(void *arg)
{
    (void)arg;
    shim_flush_thread();
    shim_tbuf.registered = false;
}

void shim_register_thread(void)
{
    shim_tbuf.registered = true;
    shim_busy++;
    pthread_setspecific(thread_key, (void *)1);
    shim_leave();
}

/* --- the allocator --------------------------------------------------------- */

/* The return address of the outermost interposed allocator call: who asked
 * for the block. */
static __thread const void *alloc_caller SHIM_TLS;

/* What the slow path of one allocation decided. */
struct pending {
    int rule; /* the rule that selects the block, or -1 */
    void *map;
    size_t map_len;
};

/* The fast path's test, then the agent's rules. Returns true when the slow
 * path was taken (shim_busy is then raised until alloc_end). */
static bool alloc_begin(size_t size, size_t align, struct pending *pd)
{
    if (size < shim.min_block || shim_busy || !emm_agent_active(shim.agent))
        return false;
    shim_busy++;
    pd->rule = emm_agent_select(shim.agent, size, alloc_caller);
    pd->map = pd->rule >= 0 && shim.ops->hooks.map ? shim.ops->hooks.map(size, align, &pd->map_len)
                                                   : NULL;
    return true;
}

static void *alloc_end(struct pending *pd, void *p, size_t size)
{
    if (pd->rule >= 0)
        shim_flush_thread(); /* records before the tag are not the array's */
    emm_agent_allocated(shim.agent, pd->rule, p, size, pd->map, pd->map_len, alloc_caller);
    shim_leave();
    return p;
}

/* A block about to be freed or moved: list mode reads it first. */
static void release_begin(const void *p, size_t moving_to)
{
    if (shim.config.list_sites && !shim_busy && shim.enabled) {
        shim_busy++;
        emm_agent_release(shim.agent, p, moving_to);
        shim_leave();
    }
}

/* Leaves an allocator function; the outermost acts on a pending signal. */
static inline void alloc_leave(void)
{
    if (--shim_in_alloc == 0 && !shim_busy &&
        __atomic_load_n(&shim_pending_signal, __ATOMIC_RELAXED))
        shim_deliver_pending();
}

/* An interposed allocator function: impl's result, with the in-allocator
 * mark around it. */
#define INTERPOSE(ret, name, params, args)                                                    \
    SHIM_API ret name params;                                                                 \
    ret name params                                                                           \
    {                                                                                         \
        if (shim_in_alloc++ == 0)                                                             \
            alloc_caller = __builtin_return_address(0);                                       \
        ret r = name##_impl args;                                                             \
        alloc_leave();                                                                        \
        return r;                                                                             \
    }

static void *malloc_impl(size_t size)
{
    BOOTSTRAP(arena_alloc(size, 16));
    struct pending pd;
    if (!alloc_begin(size, 16, &pd))
        return real.malloc(size);
    return alloc_end(&pd, pd.map ? pd.map : real.malloc(size), size);
}
INTERPOSE(void *, malloc, (size_t size), (size))

static void *calloc_impl(size_t n, size_t size)
{
    if (size && n > SIZE_MAX / size) {
        errno = ENOMEM;
        return NULL;
    }
    BOOTSTRAP(arena_alloc(n * size, 16)); /* static storage: already zero */
    struct pending pd;
    if (!alloc_begin(n * size, 16, &pd))
        return real.calloc(n, size);
    /* Fresh anonymous pages are already zero. */
    return alloc_end(&pd, pd.map ? pd.map : real.calloc(n, size), n * size);
}
INTERPOSE(void *, calloc, (size_t n, size_t size), (n, size))

/* Whether p may be a tagged block, for the agent to take care of: inside
 * the shim a block never is (the shim and the runtime free only their own).
 * When it may, the thread's records go first: those before the untag or
 * the move are the array's. */
static bool maybe_tagged(const void *p)
{
    if (shim_busy || !emm_agent_maybe_tagged(shim.agent, p))
        return false;
    shim_flush_thread();
    return true;
}

SHIM_API void free(void *p);
void free(void *p)
{
    shim_in_alloc++;
    if (p && !in_arena(p)) {
        if (!real.malloc)
            resolve();
        release_begin(p, 0);
        int handled = 0;
        if (maybe_tagged(p)) {
            shim_busy++;
            handled = emm_agent_on_free(shim.agent, p);
            shim_leave();
        }
        if (!handled)
            real.free(p);
    }
    alloc_leave();
}

static void *realloc_impl(void *p, size_t size)
{
    if (!real.malloc) {
        if (resolving) {
            void *q = arena_alloc(size, 16);
            if (q && p)
                memcpy(q, p, arena_size(p) < size ? arena_size(p) : size);
            return q;
        }
        resolve();
    }
    if (!p)
        return malloc(size);
    if (in_arena(p)) {
        void *q = malloc(size);
        if (q)
            memcpy(q, p, arena_size(p) < size ? arena_size(p) : size);
        return q;
    }
    void *q = NULL;
    int handled = 0;
    if (maybe_tagged(p)) {
        shim_busy++;
        q = emm_agent_on_realloc(shim.agent, p, size, &handled);
        shim_leave();
        if (handled)
            return q;
    }
    release_begin(p, size);
    struct pending pd;
    if (!alloc_begin(size, 16, &pd))
        return real.realloc(p, size);
    if (pd.map) {
        size_t old = real.malloc_usable_size ? real.malloc_usable_size(p) : size;
        memcpy(pd.map, p, old < size ? old : size);
        real.free(p);
        q = pd.map;
    } else {
        q = real.realloc(p, size);
    }
    return alloc_end(&pd, q, size);
}
INTERPOSE(void *, realloc, (void *p, size_t size), (p, size))

static void *aligned_common(size_t align, size_t size, void *(*fn)(size_t, size_t))
{
    struct pending pd;
    if (!alloc_begin(size, align, &pd))
        return fn(align, size);
    return alloc_end(&pd, pd.map ? pd.map : fn(align, size), size);
}

static int posix_memalign_impl(void **out, size_t align, size_t size)
{
    if (!real.malloc) {
        if (resolving) {
            *out = arena_alloc(size, align);
            return *out ? 0 : ENOMEM;
        }
        resolve();
    }
    struct pending pd;
    if (!alloc_begin(size, align, &pd))
        return real.posix_memalign(out, align, size);
    void *p = pd.map;
    int rc = p ? 0 : real.posix_memalign(&p, align, size);
    alloc_end(&pd, rc == 0 ? p : NULL, size);
    if (rc == 0)
        *out = p;
    return rc;
}
INTERPOSE(int, posix_memalign, (void **out, size_t align, size_t size), (out, align, size))

static void *aligned_alloc_impl(size_t align, size_t size)
{
    BOOTSTRAP(arena_alloc(size, align));
    return aligned_common(align, size, real.aligned_alloc);
}
INTERPOSE(void *, aligned_alloc, (size_t align, size_t size), (align, size))

static void *memalign_impl(size_t align, size_t size)
{
    BOOTSTRAP(arena_alloc(size, align));
    return aligned_common(align, size, real.memalign);
}
INTERPOSE(void *, memalign, (size_t align, size_t size), (align, size))

static void *valloc_real(size_t align, size_t size)
{
    (void)align;
    return real.valloc(size);
}

static void *valloc_impl(size_t size)
{
    BOOTSTRAP(arena_alloc(size, 4096));
    return aligned_common((size_t)sysconf(_SC_PAGESIZE), size, valloc_real);
}
INTERPOSE(void *, valloc, (size_t size), (size))

SHIM_API size_t malloc_usable_size(void *p);
size_t malloc_usable_size(void *p)
{
    if (!p)
        return 0;
    if (in_arena(p))
        return arena_size(p);
    if (!real.malloc)
        resolve();
    size_t size = 0;
    if (!shim_busy && emm_agent_maybe_tagged(shim.agent, p)) { /* on pages of its own? */
        shim_busy++;
        size = emm_agent_usable_size(shim.agent, p);
        shim_leave();
    }
    return size ? size : real.malloc_usable_size ? real.malloc_usable_size(p) : 0;
}

/* --- the explicit tags ----------------------------------------------------- */

SHIM_API void emm_tag_vertices(const void *ptr, size_t count, size_t stride, size_t xyz_offset,
                               emm_scalar type);
SHIM_API void emm_tag_triangles(const void *ptr, size_t count, size_t stride,
                                size_t index_offset, emm_scalar type);
SHIM_API void emm_iteration(void);

static void tag_call(emm_array_kind kind, const void *ptr, size_t count, size_t stride,
                     size_t offset, emm_scalar type)
{
    if (!emm_agent_active(shim.agent))
        return;
    shim_busy++;
    shim_flush_thread();
    emm_agent_tag_call(shim.agent, kind, ptr, count, stride, offset, type);
    shim_leave();
}

void emm_tag_vertices(const void *ptr, size_t count, size_t stride, size_t xyz_offset,
                      emm_scalar type)
{
    tag_call(EMM_ARRAY_VERTICES, ptr, count, stride, xyz_offset, type);
}

void emm_tag_triangles(const void *ptr, size_t count, size_t stride, size_t index_offset,
                       emm_scalar type)
{
    tag_call(EMM_ARRAY_TRIANGLES, ptr, count, stride, index_offset, type);
}

void emm_iteration(void)
{
    if (!emm_agent_active(shim.agent))
        return;
    shim_flush_thread();
    shim_busy++;
    emm_agent_iteration(shim.agent);
    shim_leave();
}

/* --- exit paths ------------------------------------------------------------ */

static void terminate_now(int sig);

static void shim_finish(void)
{
    if (!shim.enabled)
        return;
    shim_busy++;
    shim_flush_thread();
    emm_agent_finish(shim.agent);
    shim_busy--;
    /* A SIGTERM noted inside the shim and not yet acted on: the program
     * still dies of it, as it would have without the shim. */
    int sig = __atomic_exchange_n(&shim_pending_signal, 0, __ATOMIC_ACQ_REL);
    if (sig)
        terminate_now(sig);
}

#define EXIT_WRAP(name)                                                                       \
    SHIM_API void name(int status);                                                           \
    void name(int status)                                                                     \
    {                                                                                         \
        static __typeof__(name) *next;                                                        \
        shim_finish();                                                                        \
        if (!next)                                                                            \
            *(void **)&next = dlsym(RTLD_NEXT, #name);                                        \
        next(status);                                                                         \
        __builtin_unreachable();                                                              \
    }
EXIT_WRAP(_exit)
EXIT_WRAP(_Exit)

int shim_real_sigaction(int sig, const struct sigaction *act, struct sigaction *old)
{
    static int (*next)(int, const struct sigaction *, struct sigaction *);
    if (!next)
        *(void **)&next = dlsym(RTLD_NEXT, "sigaction");
    return next(sig, act, old);
}

/* SIGTERM, SIGINT and the fatal signals with the default action: finish
 * (the report says the run "ended" by the signal), then die of it.
 * Finishing allocates and takes the agent's lock, so when the signal lands
 * in a thread that is inside the shim (perhaps holding the lock) or inside
 * the allocator, the handler only notes it, and the thread acts on it as it
 * leaves (shim_leave, alloc_leave) — a fault there would only come back, so
 * the program dies of it unreported; a thread that is not waits for the lock
 * another thread may hold. Finishing here is still not async-signal-safe
 * (the interrupted code may hold another library's lock): session.h says
 * what that trades. */
static void terminate_now(int sig)
{
    /* The thread's own buffer is not flushed: the signal may have landed
     * in shim_record, between taking a slot and filling it. */
    shim_busy++;
    emm_agent_finish_signal(shim.agent, sig);
    shim_busy--;
    struct sigaction dfl;
    memset(&dfl, 0, sizeof dfl);
    dfl.sa_handler = SIG_DFL;
    shim_real_sigaction(sig, &dfl, NULL);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, sig);
    raise(sig);
    pthread_sigmask(SIG_UNBLOCK, &set, NULL); /* in a handler: dies here */
}

void shim_deliver_pending(void)
{
    int sig = __atomic_exchange_n(&shim_pending_signal, 0, __ATOMIC_ACQ_REL);
    if (sig)
        terminate_now(sig);
}

static void on_terminate(int sig)
{
    if (!emm_agent_active(shim.agent) || !(shim_busy || shim_in_alloc))
        terminate_now(sig);
    else if (sig == SIGTERM || sig == SIGINT)
        __atomic_store_n(&shim_pending_signal, sig, __ATOMIC_RELEASE);
    else /* a fault in the shim or the allocator would come back: die without a report */
        shim.enabled = false, shim.agent = NULL, terminate_now(sig);
}

static void install_terminate(int sig)
{
    struct sigaction old, act;
    if (shim_real_sigaction(sig, NULL, &old) != 0 || (old.sa_flags & SA_SIGINFO) ||
        old.sa_handler != SIG_DFL)
        return;
    memset(&act, 0, sizeof act);
    act.sa_handler = on_terminate;
    sigemptyset(&act.sa_mask);
    shim_real_sigaction(sig, &act, NULL);
}

/* --- fork ------------------------------------------------------------------ */

static void fork_prepare(void)
{
    shim_busy++;
    emm_agent_lock(shim.agent);
}

static void fork_parent(void)
{
    emm_agent_unlock(shim.agent);
    shim_leave();
}

static void fork_child(void)
{
    shim_tbuf.n = 0;
    emm_agent_forked(shim.agent);
    if (shim.ops->fork_child)
        shim.ops->fork_child();
    shim_leave();
}

/* --- start-up -------------------------------------------------------------- */

/* The session's helper threads are the shim's own for their whole life:
 * what they allocate (layouts, models) is never a tag rule's block, and a
 * rule matching it would wait on the lock their parent holds. */
static void helper_start(void *ctx)
{
    (void)ctx;
    shim_busy++;
}

/* A bad EMM_* value or a session that cannot start (emm_agent_step_aside). */
static void step_aside(const char *msg)
{
    emm_agent_step_aside(&shim.config, shim.capture, program_invocation_short_name, msg);
}

/* The backend EMM_CAPTURE names; for auto, the first of the list that
 * wants the program, or the list's last. */
static emm_capture pick_capture(void)
{
    static const struct shim_capture_ops *const all[EMM_CAPTURE_COUNT] = {
        NULL,
#define SHIM_CAPTURE_ENTRY(N, n, caps, work, help) &shim_capture_##n,
        EMM_CAPTURE_LIST(SHIM_CAPTURE_ENTRY)
#undef SHIM_CAPTURE_ENTRY
    };
    emm_capture c = shim.config.capture;
    if (c == EMM_CAPTURE_AUTO)
        for (c = EMM_CAPTURE_AUTO + 1; c + 1 < EMM_CAPTURE_COUNT; c++)
            if (all[c]->wanted && all[c]->wanted())
                break;
    shim.ops = all[c];
    return c;
}

/* emm-session beside this library as the loader loaded it (for the
 * valgrind capture, the tool's directory), when it is there. */
static bool session_server(char *out, size_t cap)
{
    Dl_info info;
    if (!dladdr((void *)session_server, &info) || !info.dli_fname)
        return false;
    const char *slash = strrchr(info.dli_fname, '/');
    if (!slash)
        return false;
    int n = snprintf(out, cap, "%.*s/emm-session", (int)(slash - info.dli_fname), info.dli_fname);
    return n > 0 && (size_t)n < cap && access(out, X_OK) == 0;
}

static const char *get_env(const char *name)
{
    return getenv(name);
}

__attribute__((constructor(101))) static void shim_init(void)
{
    static const struct shim_capture_ops list_ops;
    char msg[1024];
    emm_error err;
    resolve();
    if (!emm_agent_enter(program_invocation_short_name))
        return; /* a helper, a symbolizer: not entered */
    shim_busy++;
    shim.ops = &list_ops;
    emm_config_init(&shim.config);
    if (emm_config_from_env(&shim.config, get_env, (long)getpid(), 0, &err) != EMM_OK) {
        step_aside(err.message);
        shim_leave();
        return;
    }
    /* The program dies of these as natively, after the report (a fault
     * capture's SIGSEGV handler, installed next, passes the program's own
     * faults on to it). List mode captures only with program counters (the records' shape). */
    static const int fatal[] = {SIGTERM, SIGINT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
    for (size_t i = 0; i < sizeof fatal / sizeof *fatal && !shim.config.list_sites; i++)
        install_terminate(fatal[i]);
    shim.capture = pick_capture(); /* auto's too: under Valgrind, valgrind */
    if (shim.config.list_sites && !(emm_capture_caps(shim.capture) & EMM_CAP_PCS)) {
        shim.capture = EMM_CAPTURE_AUTO;
        shim.ops = &list_ops;
    }
    if (shim.ops->init && !shim.ops->init(msg, sizeof msg)) {
        step_aside(msg);
        shim_leave();
        return;
    }
    /* Under Valgrind the session runs natively in a process of its own
     * (emm-session, beside the tool's preload, which is this library). */
    char server[4096];
    emm_agent_config ac = {&shim.config, shim.capture, &shim.ops->hooks,
                           program_invocation_short_name, {0, helper_start, NULL}, NULL};
    if ((emm_capture_caps(shim.capture) & EMM_CAP_VALGRIND) &&
        session_server(server, sizeof server))
        ac.server = server;
    if (emm_agent_new(&ac, &shim.agent, &err) != EMM_OK) {
        step_aside(err.message);
        shim_leave();
        return;
    }
    pthread_key_create(&thread_key, thread_exit);
    pthread_atfork(fork_prepare, fork_parent, fork_child);
    shim.min_block = emm_agent_min_block(shim.agent);
    __atomic_store_n(&shim.enabled, true, __ATOMIC_RELEASE);
    shim_leave();
}

__attribute__((destructor(101))) static void shim_fini(void)
{
    shim_finish();
}
