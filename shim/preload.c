/* libemmshim.so: allocator interposition, the tag table, start-up and exit
 * (docs/design.md "The shim and the session"; after heaptrack's preload layer).
 * Interposition and forwarding only: the settings are core's configuration
 * table, the analysis is the runtime's session, and each capture backend is
 * an ops table in its own file (capture_*.c).
 *
 * - malloc and friends are resolved with dlsym(RTLD_NEXT); dlsym allocates,
 *   so while it runs allocations come from a static bootstrap arena that is
 *   never handed to the real free.
 * - An initial-exec TLS counter (shim_busy) marks the shim's own work: its
 *   allocations and the runtime's are never tagged and never re-enter the
 *   session. The session's helper threads set it for good when they start
 *   (emm_threads.on_start): their allocations are never the program's.
 * - The fast path of an allocation is a size test against the smallest block
 *   any EMM_TAG rule can select; only larger blocks take a lock or unwind.
 * - The session is not thread-safe: every call into it is made under
 *   shim.lock.
 * - fork: the child goes quiet (no session, no report: the parent's report
 *   covers the run); exec: LD_PRELOAD carries the shim into the new image,
 *   which starts its own session.
 * - The session is finished at exit (a destructor, which runs after the
 *   program's atexit handlers), in _exit/_Exit, and on SIGTERM/SIGINT when
 *   the program has no handler of its own (deferred while the signalled
 *   thread is inside the shim or the allocator: on_terminate says why).
 * - Each thread's buffer is flushed when it fills, when the thread exits and
 *   before the thread tags, frees or ends an iteration. At finish only the
 *   finishing thread's buffer is flushed: threads still running then (not
 *   joined before exit) lose up to SHIM_TBUF_CAP - 1 records each, because
 *   reading a buffer its owner may be writing would need a lock or atomics
 *   on every recorded access. */
#include <dlfcn.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "shim.h"

struct shim_real shim_real;
struct shim shim = {.lock = PTHREAD_MUTEX_INITIALIZER, .rule_min = SIZE_MAX};
__thread int shim_busy SHIM_TLS;
__thread struct shim_tbuf shim_tbuf SHIM_TLS;
__thread int shim_in_alloc SHIM_TLS;
int shim_pending_signal;

/* EMM_LIST_SITES: the smallest block listed. */
#define SHIM_LIST_MIN (64 * 1024)

static pthread_key_t thread_key;
static int finishing;

void shim_log(const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(line + 5, sizeof line - 6, fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    memcpy(line, "emm: ", 5);
    size_t len = 5 + ((size_t)n < sizeof line - 7 ? (size_t)n : sizeof line - 7);
    line[len++] = '\n';
    for (size_t off = 0; off < len;) {
        ssize_t w = write(2, line + off, len - off);
        if (w <= 0 && errno != EINTR)
            return;
        if (w > 0)
            off += (size_t)w;
    }
}

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

void shim_resolve(void)
{
    if (__atomic_load_n(&shim_real.malloc, __ATOMIC_ACQUIRE))
        return;
    resolving = 1;
    struct shim_real r;
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
    shim_real = r;
    __atomic_store_n(&shim_real.malloc, m, __ATOMIC_RELEASE);
    resolving = 0;
}

/* The allocator is not resolved yet: while dlsym runs, the arena serves. */
#define BOOTSTRAP(arena_call)                                                                 \
    if (!shim_real.malloc) {                                                                  \
        if (resolving)                                                                        \
            return arena_call;                                                                \
        shim_resolve();                                                                       \
    }

/* --- the session ----------------------------------------------------------- */

static bool session_live_locked(void)
{
    return shim.session && !shim.finished && !shim.failed;
}

static void ranges_changed_locked(void)
{
    if (shim.ops->ranges_locked)
        shim.ops->ranges_locked();
}

size_t shim_ranges_locked(uint64_t *lo, uint64_t *hi, size_t cap)
{
    if (!session_live_locked())
        return 0;
    size_t n = emm_session_ranges(shim.session, lo, hi, cap);
    return n < cap ? n : cap;
}

static void decide_locked(void)
{
    if (shim.ops->before_decide_locked)
        shim.ops->before_decide_locked();
    emm_error err;
    if (emm_session_decide(shim.session, &err) != EMM_OK) {
        /* The session reports why at finish; stop feeding it. */
        shim.failed = true;
        if (shim.config.log >= 2)
            shim_log("%s", err.message);
    }
    shim.state = EMM_SESSION_SIMULATING;
    ranges_changed_locked();
}

/* The session's answer to a call: decide when it asks. */
static void answer_locked(emm_session_state st)
{
    if (st == EMM_SESSION_DECIDE && shim.state != EMM_SESSION_SIMULATING)
        decide_locked();
    else
        shim.state = st;
}

void shim_feed_locked(const emm_raw_access *rec, size_t n)
{
    if (session_live_locked())
        answer_locked(emm_session_access(shim.session, rec, n));
}

void shim_flush_thread(void)
{
    struct shim_tbuf *b = &shim_tbuf;
    bool drain = shim.ops && shim.ops->drain_locked;
    if (b->n == 0 && !drain)
        return;
    shim_busy++;
    pthread_mutex_lock(&shim.lock);
    if (b->n)
        shim_feed_locked(b->rec, b->n);
    b->n = 0;
    if (drain)
        shim.ops->drain_locked();
    pthread_mutex_unlock(&shim.lock);
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

static const char *kind_name(emm_array_kind k)
{
    return k == EMM_ARRAY_VERTICES ? "vertices" : "triangles";
}

static void finish_locked(void)
{
    if (shim.ops->before_decide_locked)
        shim.ops->before_decide_locked();
    if (shim.config.log >= 1)
        shim_rules_report();
    if (shim.config.log >= 2) {
        size_t live = 0;
        for (size_t i = 0; i < SHIM_MAX_TAGS; i++)
            if (shim.tags[i].base) {
                live++;
                shim_log("at exit: %s at %p, %zu records of %zu bytes",
                         kind_name(shim.tags[i].kind), (void *)shim.tags[i].base,
                         shim.tags[i].bytes / shim.tags[i].stride, shim.tags[i].stride);
            }
        shim_log("at exit: %zu arrays tagged, %llu tag events", live,
                 (unsigned long long)shim.tagged_total);
    }
    shim.finished = true;
    ranges_changed_locked();
    /* The summary already says why a session had nothing to simulate, and
     * names each output that could not be written. */
    emm_session_finish(shim.session, shim.config.log >= 1 ? stderr : NULL, NULL);
}

static void terminate_now(int sig);

static void shim_finish(void)
{
    if (!shim.enabled || __atomic_exchange_n(&finishing, 1, __ATOMIC_ACQ_REL))
        return;
    if (shim.sites) { /* list mode: the candidate arrays, nothing simulated */
        shim_busy++;
        pthread_mutex_lock(&shim.lock);
        shim.finished = true;
        emm_sites_print(shim.sites, program_invocation_short_name, stderr);
        pthread_mutex_unlock(&shim.lock);
        shim_busy--;
        return;
    }
    shim_busy++;
    shim_flush_thread();
    pthread_mutex_lock(&shim.lock);
    if (!shim.finished)
        finish_locked();
    pthread_mutex_unlock(&shim.lock);
    shim_busy--;
    /* A SIGTERM noted inside the shim and not yet acted on: the program
     * still dies of it, as it would have without the shim. */
    int sig = __atomic_exchange_n(&shim_pending_signal, 0, __ATOMIC_ACQ_REL);
    if (sig)
        terminate_now(sig);
}

/* --- the tag table --------------------------------------------------------- */

static int find_tag_locked(uintptr_t base)
{
    for (size_t i = 0; base && i < SHIM_MAX_TAGS; i++)
        if (shim.tags[i].base == base)
            return (int)i;
    return -1;
}

static bool tag_exists_quick(const void *p)
{
    if (!__atomic_load_n(&shim.live_tags, __ATOMIC_RELAXED))
        return false;
    for (size_t i = 0; i < SHIM_MAX_TAGS; i++)
        if (__atomic_load_n(&shim.tag_base[i], __ATOMIC_RELAXED) == (uintptr_t)p)
            return true;
    return false;
}

void shim_tag_array(emm_array_kind kind, const void *base, size_t bytes, size_t stride,
                    size_t offset, emm_scalar type, int rule, void *map, size_t map_len)
{
    shim_busy++;
    shim_flush_thread();
    pthread_mutex_lock(&shim.lock);
    int slot = find_tag_locked((uintptr_t)base);
    for (size_t i = 0; slot < 0 && i < SHIM_MAX_TAGS; i++)
        if (!shim.tags[i].base)
            slot = (int)i;
    if (slot < 0) {
        pthread_mutex_unlock(&shim.lock);
        if (shim.config.log >= 1)
            shim_log("more than %d arrays tagged; %s at %p ignored", SHIM_MAX_TAGS,
                     kind_name(kind), base);
        shim_leave();
        return;
    }
    struct shim_tag *t = &shim.tags[slot];
    bool fresh = t->base == 0;
    if (fresh) {
        memset(t, 0, sizeof *t);
        t->map = map;
        t->map_len = map_len;
    }
    t->base = (uintptr_t)base;
    t->bytes = bytes;
    t->kind = kind;
    t->stride = stride;
    t->offset = offset;
    t->type = type;
    t->rule = rule;
    int idx = -1;
    if (session_live_locked())
        idx = emm_session_tag_rule(shim.session, kind, base, bytes / stride, stride, offset, type,
                                   rule);
    if (shim.ops->on_tag_locked)
        shim.ops->on_tag_locked(t);
    ranges_changed_locked();
    shim.tagged_total++;
    if (fresh) {
        __atomic_store_n(&shim.tag_base[slot], (uintptr_t)base, __ATOMIC_RELAXED);
        __atomic_add_fetch(&shim.live_tags, 1, __ATOMIC_RELAXED);
    }
    pthread_mutex_unlock(&shim.lock);
    if (shim.config.log >= 2)
        shim_log("tagged %s at %p: %zu records of %zu bytes (%s)%s", kind_name(kind), base,
                 bytes / stride, stride, rule >= 0 ? "EMM_TAG rule" : "emm_tag call",
                 idx < 0 ? ", not watched" : "");
    shim_leave();
}

/* Removes the entry for base, if any, and hands back a copy of it. */
static bool take_tag(const void *base, struct shim_tag *out)
{
    shim_busy++;
    shim_flush_thread();
    pthread_mutex_lock(&shim.lock);
    int slot = find_tag_locked((uintptr_t)base);
    if (slot >= 0) {
        struct shim_tag *t = &shim.tags[slot];
        if (shim.ops->on_untag_locked)
            shim.ops->on_untag_locked(t);
        if (session_live_locked()) {
            emm_session_state st = emm_session_untag(shim.session, base);
            if (st == EMM_SESSION_DECIDE && shim.state == EMM_SESSION_PROFILING &&
                shim.config.log >= 2)
                shim_log("the last %s array is freed: the profile window closes early",
                         kind_name(t->kind));
            answer_locked(st);
        }
        *out = *t;
        memset(t, 0, sizeof *t);
        __atomic_store_n(&shim.tag_base[slot], 0, __ATOMIC_RELAXED);
        __atomic_sub_fetch(&shim.live_tags, 1, __ATOMIC_RELAXED);
        ranges_changed_locked();
    }
    pthread_mutex_unlock(&shim.lock);
    if (slot >= 0 && shim.config.log >= 2)
        shim_log("untagged %s at %p", kind_name(out->kind), base);
    shim_leave();
    return slot >= 0;
}

void shim_untag_array(const void *base)
{
    struct shim_tag t;
    take_tag(base, &t);
}

/* --- the allocator --------------------------------------------------------- */

/* The return address of the outermost interposed allocator call: who asked
 * for the block. */
static __thread const void *alloc_caller SHIM_TLS;

/* Whether the C library asked for the block itself — a FILE and its
 * buffer, getline's line, strdup's copy: never a program's array, and a
 * FILE's 4 KiB buffer is a whole number of small records, which a rule
 * would select (under fault capture the C library's reads into it then
 * failed with EFAULT: the kernel does not fault on a protected page).
 * The answers for the last few callers are kept per thread. */
static bool libc_block(void)
{
    static __thread struct {
        const void *ra;
        bool libc;
    } memo[8] SHIM_TLS;
    static __thread unsigned next SHIM_TLS;
    const void *ra = alloc_caller;
    for (unsigned i = 0; i < 8; i++)
        if (memo[i].ra == ra && ra)
            return memo[i].libc;
    Dl_info info;
    bool libc = false;
    if (ra && dladdr(ra, &info) && info.dli_fname) {
        const char *base = strrchr(info.dli_fname, '/');
        base = base ? base + 1 : info.dli_fname;
        libc = strncmp(base, "libc.so", 7) == 0;
    }
    memo[next % 8].ra = ra;
    memo[next % 8].libc = libc;
    next++;
    return libc;
}

/* What the slow path of one allocation decided. */
struct pending {
    bool libc; /* the C library's own block: neither tagged nor listed */
    int rule; /* the rule that selects the block, or -1 */
    const char *site; /* the frame a site= rule matched, or NULL */
    void *map;
    size_t map_len;
};

/* The fast path's test, then the rules. Returns true when the slow path was
 * taken (shim_busy is then raised until alloc_end). */
static bool alloc_begin(size_t size, size_t align, struct pending *pd)
{
    if (size < shim.rule_min || shim_busy || !shim.enabled || shim.finished)
        return false;
    shim_busy++;
    pd->libc = libc_block();
    pd->rule = shim.sites || pd->libc ? -1 : shim_rules_match(size, &pd->site);
    pd->map = pd->rule >= 0 && shim.ops->map ? shim.ops->map(size, align, &pd->map_len) : NULL;
    return true;
}

static void *alloc_end(struct pending *pd, void *p, size_t size)
{
    if (p && pd->rule >= 0) {
        const emm_tag_rule *r = &shim.config.tags.rule[pd->rule];
        shim_tag_array(r->kind, p, size - size % r->stride, r->stride, r->offset, r->type,
                       pd->rule, pd->map, pd->map_len);
        if (shim.config.log >= 2)
            shim_log("EMM_TAG rule %d selected a block of %zu bytes%s%s", pd->rule + 1, size,
                     pd->site ? " allocated under " : "", pd->site ? pd->site : "");
    } else if (pd->map) {
        munmap(pd->map, pd->map_len);
    }
    if (p && shim.sites && !pd->libc)
        shim_rules_list(p, size);
    shim_leave();
    return p;
}

/* EMM_LIST_SITES: a block about to be freed or moved is read first. */
static void list_release(const void *p)
{
    if (!shim.sites || shim_busy)
        return;
    shim_busy++;
    pthread_mutex_lock(&shim.lock);
    if (!shim.finished)
        emm_sites_release(shim.sites, p);
    pthread_mutex_unlock(&shim.lock);
    shim_leave();
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
        return shim_real.malloc(size);
    return alloc_end(&pd, pd.map ? pd.map : shim_real.malloc(size), size);
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
        return shim_real.calloc(n, size);
    /* Fresh anonymous pages are already zero. */
    return alloc_end(&pd, pd.map ? pd.map : shim_real.calloc(n, size), n * size);
}
INTERPOSE(void *, calloc, (size_t n, size_t size), (n, size))

static void release(const struct shim_tag *t, void *p)
{
    if (t->map)
        munmap(t->map, t->map_len);
    else
        shim_real.free(p);
}

SHIM_API void free(void *p);
void free(void *p)
{
    shim_in_alloc++;
    if (p && !in_arena(p)) {
        if (!shim_real.malloc)
            shim_resolve();
        /* Inside the shim (shim_busy) a block is never a tagged one: the shim
         * and the session free only their own. */
        struct shim_tag t;
        list_release(p);
        if (!shim_busy && tag_exists_quick(p) && take_tag(p, &t))
            release(&t, p);
        else
            shim_real.free(p);
    }
    alloc_leave();
}

/* realloc of a tagged block: the same array, moved (the session keeps its
 * place and its window: a loader growing its arrays does not end the
 * window). The backend's untag side runs before the copy (the fault
 * backend's pages open, the valgrind tool told no ranges: the copy is not
 * the program's access) and its tag side after. */
static void *realloc_tagged(void *p, size_t size)
{
    if (size == 0) {
        struct shim_tag t;
        if (take_tag(p, &t))
            release(&t, p);
        else
            shim_real.free(p);
        return NULL;
    }
    shim_busy++;
    shim_flush_thread();
    pthread_mutex_lock(&shim.lock);
    int slot = find_tag_locked((uintptr_t)p);
    if (slot < 0) { /* untagged meanwhile by another thread */
        pthread_mutex_unlock(&shim.lock);
        shim_leave();
        return shim_real.realloc(p, size);
    }
    struct shim_tag *t = &shim.tags[slot];
    if (shim.ops->on_untag_locked)
        shim.ops->on_untag_locked(t);
    void *q, *map = NULL;
    size_t map_len = 0;
    if (t->map) {
        size_t old = t->map_len - (size_t)((uintptr_t)p - (uintptr_t)t->map);
        map = shim.ops->map ? shim.ops->map(size, 16, &map_len) : NULL;
        q = map ? map : shim_real.malloc(size);
        if (q) {
            memcpy(q, p, old < size ? old : size);
            munmap(t->map, t->map_len);
        }
    } else {
        q = shim_real.realloc(p, size);
    }
    size_t bytes = size - size % t->stride;
    if (t->rule < 0 && t->bytes < bytes)
        bytes = t->bytes;
    if (q) {
        if (session_live_locked())
            answer_locked(emm_session_move(shim.session, p, q, bytes / t->stride));
        t->base = (uintptr_t)q;
        t->bytes = bytes;
        t->map = map;
        t->map_len = map_len;
        __atomic_store_n(&shim.tag_base[slot], (uintptr_t)q, __ATOMIC_RELAXED);
    }
    if (q && bytes == 0) { /* shrunk below one record: no longer an array */
        memset(t, 0, sizeof *t);
        __atomic_store_n(&shim.tag_base[slot], 0, __ATOMIC_RELAXED);
        __atomic_sub_fetch(&shim.live_tags, 1, __ATOMIC_RELAXED);
    } else if (shim.ops->on_tag_locked) {
        /* the old block, when q is NULL, stays valid and stays the array */
        shim.ops->on_tag_locked(t);
    }
    ranges_changed_locked();
    pthread_mutex_unlock(&shim.lock);
    if (q && bytes && shim.config.log >= 2)
        shim_log("moved %s from %p to %p: %zu records of %zu bytes", kind_name(t->kind), p, q,
                 bytes / t->stride, t->stride);
    shim_leave();
    if (!q)
        errno = ENOMEM;
    return q;
}

static void *realloc_impl(void *p, size_t size)
{
    if (!shim_real.malloc) {
        if (resolving) {
            void *q = arena_alloc(size, 16);
            if (q && p)
                memcpy(q, p, arena_size(p) < size ? arena_size(p) : size);
            return q;
        }
        shim_resolve();
    }
    if (!p)
        return malloc(size);
    if (in_arena(p)) {
        void *q = malloc(size);
        if (q)
            memcpy(q, p, arena_size(p) < size ? arena_size(p) : size);
        return q;
    }
    if (!shim_busy && tag_exists_quick(p))
        return realloc_tagged(p, size);
    list_release(p);
    struct pending pd;
    if (!alloc_begin(size, 16, &pd))
        return shim_real.realloc(p, size);
    void *q;
    if (pd.map) {
        size_t old = shim_real.malloc_usable_size ? shim_real.malloc_usable_size(p) : size;
        memcpy(pd.map, p, old < size ? old : size);
        shim_real.free(p);
        q = pd.map;
    } else {
        q = shim_real.realloc(p, size);
    }
    return alloc_end(&pd, q, size);
}
INTERPOSE(void *, realloc, (void *p, size_t size), (p, size))

static void *aligned_common(size_t align, size_t size, void *(*real)(size_t, size_t))
{
    struct pending pd;
    if (!alloc_begin(size, align, &pd))
        return real(align, size);
    return alloc_end(&pd, pd.map ? pd.map : real(align, size), size);
}

static int posix_memalign_impl(void **out, size_t align, size_t size)
{
    if (!shim_real.malloc) {
        if (resolving) {
            *out = arena_alloc(size, align);
            return *out ? 0 : ENOMEM;
        }
        shim_resolve();
    }
    struct pending pd;
    if (!alloc_begin(size, align, &pd))
        return shim_real.posix_memalign(out, align, size);
    void *p = pd.map;
    int rc = p ? 0 : shim_real.posix_memalign(&p, align, size);
    alloc_end(&pd, rc == 0 ? p : NULL, size);
    if (rc == 0)
        *out = p;
    return rc;
}
INTERPOSE(int, posix_memalign, (void **out, size_t align, size_t size), (out, align, size))

static void *aligned_alloc_impl(size_t align, size_t size)
{
    BOOTSTRAP(arena_alloc(size, align));
    return aligned_common(align, size, shim_real.aligned_alloc);
}
INTERPOSE(void *, aligned_alloc, (size_t align, size_t size), (align, size))

static void *memalign_impl(size_t align, size_t size)
{
    BOOTSTRAP(arena_alloc(size, align));
    return aligned_common(align, size, shim_real.memalign);
}
INTERPOSE(void *, memalign, (size_t align, size_t size), (align, size))

static void *valloc_real(size_t align, size_t size)
{
    (void)align;
    return shim_real.valloc(size);
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
    if (!shim_real.malloc)
        shim_resolve();
    if (tag_exists_quick(p)) { /* a block on pages of its own */
        size_t size = 0;
        pthread_mutex_lock(&shim.lock);
        int slot = find_tag_locked((uintptr_t)p);
        if (slot >= 0 && shim.tags[slot].map)
            size = shim.tags[slot].map_len - (size_t)((uintptr_t)p - (uintptr_t)shim.tags[slot].map);
        pthread_mutex_unlock(&shim.lock);
        if (size)
            return size;
    }
    return shim_real.malloc_usable_size ? shim_real.malloc_usable_size(p) : 0;
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
    if (shim.enabled && !shim.finished && ptr && count && stride && count <= SIZE_MAX / stride)
        shim_tag_array(kind, ptr, count * stride, stride, offset, type, -1, NULL, 0);
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
    if (!shim.enabled || shim.finished)
        return;
    shim_flush_thread();
    shim_busy++;
    pthread_mutex_lock(&shim.lock);
    if (session_live_locked())
        answer_locked(emm_session_iteration(shim.session));
    pthread_mutex_unlock(&shim.lock);
    shim_leave();
}

/* --- exit paths ------------------------------------------------------------ */

#define EXIT_WRAP(name)                                                                       \
    SHIM_API void name(int status);                                                           \
    void name(int status)                                                                     \
    {                                                                                         \
        static __typeof__(name) *real;                                                        \
        shim_finish();                                                                        \
        if (!real)                                                                            \
            *(void **)&real = dlsym(RTLD_NEXT, #name);                                        \
        real(status);                                                                         \
        __builtin_unreachable();                                                              \
    }
EXIT_WRAP(_exit)
EXIT_WRAP(_Exit)

int shim_real_sigaction(int sig, const struct sigaction *act, struct sigaction *old)
{
    static int (*real)(int, const struct sigaction *, struct sigaction *);
    if (!real)
        *(void **)&real = dlsym(RTLD_NEXT, "sigaction");
    return real(sig, act, old);
}

/* SIGTERM/SIGINT with the default action: finish, then die of the signal.
 * Finishing allocates and takes the shim's lock, so when the signal lands
 * in a thread that is inside the shim (perhaps holding the lock) or inside
 * the allocator, the handler only notes it, and the thread acts on it as it
 * leaves (shim_leave, alloc_leave); a thread that is not waits for the lock
 * another thread may hold. Finishing here is still not async-signal-safe
 * (the interrupted code may hold another library's lock): session.h says
 * what that trades. */
static void terminate_now(int sig)
{
    if (!__atomic_exchange_n(&finishing, 1, __ATOMIC_ACQ_REL)) {
        /* The thread's own buffer is not flushed: the signal may have landed
         * in shim_record, between taking a slot and filling it. */
        shim_busy++;
        pthread_mutex_lock(&shim.lock);
        if (!shim.finished)
            finish_locked();
        pthread_mutex_unlock(&shim.lock);
        shim_busy--;
    }
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
    if (!shim.enabled || shim.finished) {
        __atomic_store_n(&finishing, 1, __ATOMIC_RELEASE);
        terminate_now(sig);
    } else if (shim_busy || shim_in_alloc) {
        __atomic_store_n(&shim_pending_signal, sig, __ATOMIC_RELEASE);
    } else {
        terminate_now(sig);
    }
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
    pthread_mutex_lock(&shim.lock);
}

static void fork_parent(void)
{
    pthread_mutex_unlock(&shim.lock);
    shim_leave();
}

static void fork_child(void)
{
    pthread_mutex_init(&shim.lock, NULL);
    shim.finished = true;
    finishing = 1;
    shim_tbuf.n = 0;
    if (shim.session)
        emm_session_forked(shim.session);
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

/* A bad EMM_* value or a session that cannot start: one line, then the
 * program runs untouched (or, with EMM_STRICT=1, does not run). */
static void step_aside(const char *msg)
{
    if (shim.config.strict) {
        shim_log("%s (EMM_STRICT=1: not running the program)", msg);
        _exit(SHIM_STRICT_EXIT);
    }
    shim_log("%s", msg);
}

/* EMM_CAPTURE=auto: the first backend, in this order, that wants the
 * program (valgrind: the program runs under emm's Valgrind tool). */
static const struct shim_capture_ops *pick_capture(void)
{
    static const struct shim_capture_ops *const order[] = {
        &shim_capture_valgrind, &shim_capture_sancov, &shim_capture_api, &shim_capture_fault};
    static const struct shim_capture_ops *const all[EMM_CAPTURE_COUNT] = {
        [EMM_CAPTURE_SANCOV] = &shim_capture_sancov,
        [EMM_CAPTURE_FAULT] = &shim_capture_fault,
        [EMM_CAPTURE_API] = &shim_capture_api,
        [EMM_CAPTURE_VALGRIND] = &shim_capture_valgrind};
    if (shim.config.capture != EMM_CAPTURE_AUTO)
        return all[shim.config.capture];
    for (size_t i = 0; i + 1 < sizeof order / sizeof *order; i++)
        if (order[i]->wanted && order[i]->wanted())
            return order[i];
    return order[sizeof order / sizeof *order - 1];
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
    shim_resolve();
    shim_busy++;
    char msg[1024];
    emm_error err;
    emm_config_init(&shim.config);
    if (emm_config_from_env(&shim.config, get_env, (long)getpid(), 0, &err) != EMM_OK) {
        step_aside(err.message);
        shim_leave();
        return;
    }
    if (!shim_rules_init(msg, sizeof msg)) {
        step_aside(msg);
        shim_leave();
        return;
    }
    if (shim.config.list_sites) {
        /* List mode: no session, no capture; every large block is noted. */
        static const struct shim_capture_ops list_ops = {.kind = EMM_CAPTURE_AUTO};
        shim.ops = &list_ops;
        if (!(shim.sites = emm_sites_new(SHIM_LIST_MIN))) {
            step_aside("EMM_LIST_SITES: out of memory");
            shim_leave();
            return;
        }
        pthread_atfork(fork_prepare, fork_parent, fork_child);
        shim.rule_min = SHIM_LIST_MIN;
        __atomic_store_n(&shim.enabled, true, __ATOMIC_RELEASE);
        shim_leave();
        return;
    }
    shim.ops = pick_capture();
    /* Under Valgrind the session runs natively in a process of its own
     * (emm-session, beside the tool's preload, which is this library), or
     * here when that cannot start. */
    char server[4096];
    emm_session_config sc = {&shim.config, shim.ops->kind, program_invocation_short_name, 0,
                             {0, helper_start, NULL}, NULL};
    if (shim.ops->kind == EMM_CAPTURE_VALGRIND && session_server(server, sizeof server))
        sc.server = server;
    emm_status st = emm_session_new(&sc, &shim.session, &err);
    if (st != EMM_OK && sc.server) {
        if (shim.config.log >= 2)
            shim_log("the session runs in the program: %s", err.message);
        sc.server = NULL;
        st = emm_session_new(&sc, &shim.session, &err);
    }
    if (st != EMM_OK) {
        shim.session = NULL;
        step_aside(err.message);
        shim_leave();
        return;
    }
    if (sc.server && shim.config.log >= 2)
        shim_log("the session runs natively in its own process, %s", sc.server);
    if (shim.ops->init && !shim.ops->init(msg, sizeof msg)) {
        emm_session_free(shim.session);
        shim.session = NULL;
        step_aside(msg);
        shim_leave();
        return;
    }
    pthread_key_create(&thread_key, thread_exit);
    pthread_atfork(fork_prepare, fork_parent, fork_child);
    install_terminate(SIGTERM);
    install_terminate(SIGINT);
    shim.rule_min = shim_rules_min();
    shim.state = EMM_SESSION_PROFILING;
    if (shim.config.log >= 2) {
        shim_log("libemmshim.so in %s (pid %ld), capture %s", program_invocation_short_name,
                 (long)getpid(), emm_capture_name(shim.ops->kind));
        emm_config_dump(&shim.config, stderr);
    }
    __atomic_store_n(&shim.enabled, true, __ATOMIC_RELEASE);
    shim_leave();
}

__attribute__((destructor(101))) static void shim_fini(void)
{
    shim_finish();
}
