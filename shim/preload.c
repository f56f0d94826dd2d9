/* libemmshim.so: allocator interposition, the tag table, start-up and exit
 * (DESIGN.md "The shim"; STYLE.md §6–§7, after heaptrack's preload layer).
 *
 * - malloc and friends are resolved with dlsym(RTLD_NEXT); dlsym allocates,
 *   so while it runs allocations come from a static bootstrap arena that is
 *   never handed to the real free.
 * - An initial-exec TLS counter (shim_busy) marks the shim's own work: its
 *   allocations and the runtime's are never tagged and never re-enter the
 *   session.
 * - The fast path of an allocation is a size test against the smallest block
 *   any EMM_TAG rule can select; only larger blocks take a lock or unwind.
 * - The session (runtime/) is not thread-safe: every call into it is made
 *   under shim.lock.
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
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "shim.h"

struct shim_real shim_real;
struct shim shim = {
    .lock = PTHREAD_MUTEX_INITIALIZER,
    .rule_min = SIZE_MAX,
};
__thread int shim_busy SHIM_TLS;
__thread struct shim_tbuf shim_tbuf SHIM_TLS;
__thread int shim_in_alloc SHIM_TLS;
int shim_pending_signal;

static pthread_key_t thread_key;

/* --- logging without allocating ---------------------------------------- */

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

/* --- the bootstrap arena ----------------------------------------------- */

#define ARENA_BYTES (256 * 1024)
static _Alignas(64) unsigned char arena[ARENA_BYTES];
static size_t arena_used;

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

static int resolving;

void shim_resolve(void)
{
    if (__atomic_load_n(&shim_real.malloc, __ATOMIC_ACQUIRE))
        return;
    resolving = 1;
    struct shim_real r;
    r.malloc = (void *(*)(size_t))dlsym(RTLD_NEXT, "malloc");
    r.calloc = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "calloc");
    r.realloc = (void *(*)(void *, size_t))dlsym(RTLD_NEXT, "realloc");
    r.free = (void (*)(void *))dlsym(RTLD_NEXT, "free");
    r.posix_memalign = (int (*)(void **, size_t, size_t))dlsym(RTLD_NEXT, "posix_memalign");
    r.aligned_alloc = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "aligned_alloc");
    r.memalign = (void *(*)(size_t, size_t))dlsym(RTLD_NEXT, "memalign");
    r.valloc = (void *(*)(size_t))dlsym(RTLD_NEXT, "valloc");
    r.malloc_usable_size = (size_t (*)(void *))dlsym(RTLD_NEXT, "malloc_usable_size");
    if (!r.malloc || !r.calloc || !r.realloc || !r.free) {
        shim_log("libemmshim.so: cannot find the C library's allocator");
        abort();
    }
    shim_real.calloc = r.calloc;
    shim_real.realloc = r.realloc;
    shim_real.free = r.free;
    shim_real.posix_memalign = r.posix_memalign;
    shim_real.aligned_alloc = r.aligned_alloc;
    shim_real.memalign = r.memalign;
    shim_real.valloc = r.valloc;
    shim_real.malloc_usable_size = r.malloc_usable_size;
    __atomic_store_n(&shim_real.malloc, r.malloc, __ATOMIC_RELEASE);
    resolving = 0;
}

/* --- the tag table ----------------------------------------------------- */

static int find_tag_locked(uintptr_t base)
{
    for (size_t i = 0; i < SHIM_MAX_TAGS; i++)
        if (shim.tags[i].base == base && base)
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

static void decide_locked(void);

/* The sancov filter's snapshot of the session's ranges. */
static void refresh_ranges_locked(void)
{
    if (shim.capture != SHIM_CAPTURE_SANCOV)
        return;
    __atomic_store_n(&shim.nranges, 0, __ATOMIC_RELEASE);
    if (!shim.session || shim.finished || shim.failed)
        return;
    uint64_t lo[SHIM_MAX_RANGES], hi[SHIM_MAX_RANGES];
    size_t n = emm_session_ranges(shim.session, lo, hi, SHIM_MAX_RANGES);
    if (n > SHIM_MAX_RANGES)
        n = SHIM_MAX_RANGES;
    for (size_t i = 0; i < n; i++) {
        __atomic_store_n(&shim.range_lo[i], lo[i], __ATOMIC_RELAXED);
        __atomic_store_n(&shim.range_len[i], hi[i] - lo[i], __ATOMIC_RELAXED);
    }
    __atomic_store_n(&shim.nranges, n, __ATOMIC_RELEASE);
}

static bool session_live_locked(void)
{
    return shim.session && !shim.finished && !shim.failed;
}

static const char *kind_name(emm_array_kind k)
{
    return k == EMM_ARRAY_VERTICES ? "vertices" : "triangles";
}

void shim_tag_array(emm_array_kind kind, const void *base, size_t bytes, size_t stride,
                    size_t offset, emm_scalar type, bool from_rule, void *map, size_t map_len)
{
    shim_busy++;
    shim_flush_thread();
    pthread_mutex_lock(&shim.lock);
    int slot = find_tag_locked((uintptr_t)base);
    if (slot < 0) {
        for (size_t i = 0; i < SHIM_MAX_TAGS; i++)
            if (!shim.tags[i].base) {
                slot = (int)i;
                break;
            }
    }
    if (slot < 0) {
        pthread_mutex_unlock(&shim.lock);
        if (shim.env.log >= 1)
            shim_log("more than %d arrays tagged; %s at %p ignored", SHIM_MAX_TAGS,
                     kind_name(kind), base);
        shim_leave();
        return;
    }
    struct shim_tag *t = &shim.tags[slot];
    bool fresh = t->base == 0;
    if (!fresh && t->protected_)
        shim_fault_unprotect(t);
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
    t->from_rule = from_rule;
    int idx = -1;
    if (session_live_locked())
        idx = emm_session_tag(shim.session, kind, base, bytes / stride, stride, offset, type);
    if (shim.capture == SHIM_CAPTURE_FAULT && shim_fault_watching())
        shim_fault_protect(t);
    refresh_ranges_locked();
    shim.tagged_total++;
    if (fresh) {
        __atomic_store_n(&shim.tag_base[slot], (uintptr_t)base, __ATOMIC_RELAXED);
        __atomic_add_fetch(&shim.live_tags, 1, __ATOMIC_RELAXED);
    }
    pthread_mutex_unlock(&shim.lock);
    if (shim.env.log >= 2)
        shim_log("tagged %s at %p: %zu records of %zu bytes (%s)%s", kind_name(kind), base,
                 bytes / stride, stride, from_rule ? "EMM_TAG rule" : "emm_tag call",
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
    if (slot < 0) {
        pthread_mutex_unlock(&shim.lock);
        shim_leave();
        return false;
    }
    struct shim_tag *t = &shim.tags[slot];
    if (t->protected_)
        shim_fault_unprotect(t);
    /* The last array of its kind freed before the window closed: decide now,
     * while the geometry can still be read ("freeze the data"). A growing
     * std::vector frees its old buffer after the new one is tagged, so it
     * does not end the window. */
    if (session_live_locked() && shim.state == EMM_SESSION_PROFILING) {
        size_t same = 0;
        for (size_t i = 0; i < SHIM_MAX_TAGS; i++)
            same += shim.tags[i].base && shim.tags[i].kind == t->kind;
        if (same == 1) {
            if (shim.env.log >= 2)
                shim_log("the last %s array is freed: the profile window closes early",
                         kind_name(t->kind));
            decide_locked();
        }
    }
    if (session_live_locked())
        emm_session_untag(shim.session, base);
    *out = *t;
    memset(t, 0, sizeof *t);
    __atomic_store_n(&shim.tag_base[slot], 0, __ATOMIC_RELAXED);
    __atomic_sub_fetch(&shim.live_tags, 1, __ATOMIC_RELAXED);
    refresh_ranges_locked();
    pthread_mutex_unlock(&shim.lock);
    if (shim.env.log >= 2)
        shim_log("untagged %s at %p", kind_name(out->kind), base);
    shim_leave();
    return true;
}

void shim_untag_array(const void *base)
{
    struct shim_tag t;
    take_tag(base, &t);
}

/* --- capture buffers and the session ----------------------------------- */

static void decide_locked(void)
{
    if (shim.capture == SHIM_CAPTURE_FAULT)
        shim_fault_lift();
    emm_error err;
    if (emm_session_decide(shim.session, &err) != EMM_OK) {
        /* The session reports why at finish; stop feeding it. */
        shim.failed = true;
        if (shim.env.log >= 2)
            shim_log("%s", err.message);
    }
    shim.state = EMM_SESSION_SIMULATING;
    refresh_ranges_locked();
}

void shim_flush_thread(void)
{
    struct shim_tbuf *b = &shim_tbuf;
    if (b->n == 0)
        return;
    shim_busy++;
    pthread_mutex_lock(&shim.lock);
    if (session_live_locked()) {
        emm_session_state st = emm_session_access(shim.session, b->rec, b->n);
        if (st == EMM_SESSION_DECIDE && shim.state != EMM_SESSION_SIMULATING)
            decide_locked();
        else
            shim.state = st;
    }
    b->n = 0;
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

static int finishing;
static void terminate_now(int sig);

static void finish_locked(void)
{
    if (shim.capture == SHIM_CAPTURE_FAULT)
        shim_fault_lift();
    __atomic_store_n(&shim.nranges, 0, __ATOMIC_RELEASE);
    if (shim.env.log >= 2) {
        size_t live = 0;
        for (size_t i = 0; i < SHIM_MAX_TAGS; i++)
            if (shim.tags[i].base) {
                live++;
                shim_log("at exit: %s at %p, %zu records of %zu bytes", kind_name(shim.tags[i].kind),
                         (void *)shim.tags[i].base, shim.tags[i].bytes / shim.tags[i].stride,
                         shim.tags[i].stride);
            }
        shim_log("at exit: %zu arrays tagged, %llu tag events", live,
                 (unsigned long long)shim.tagged_total);
    }
    shim.finished = true;
    emm_error err;
    /* The summary already says why a session had nothing to simulate, and
     * names each output that could not be written. */
    emm_session_finish(shim.session, shim.env.log >= 1 ? stderr : NULL, &err);
}

void shim_finish(void)
{
    if (!shim.enabled || __atomic_exchange_n(&finishing, 1, __ATOMIC_ACQ_REL))
        return;
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

/* --- the allocator ----------------------------------------------------- */

/* What the slow path of one allocation decided. */
struct pending {
    bool hit;
    struct shim_match m;
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
    pd->hit = shim_rules_match(shim.rules, size, &pd->m);
    pd->map = NULL;
    if (pd->hit && shim.capture == SHIM_CAPTURE_FAULT && shim_fault_watching()
        && align <= (size_t)sysconf(_SC_PAGESIZE))
        pd->map = shim_fault_map(size, &pd->map_len);
    return true;
}

static void *alloc_end(struct pending *pd, void *p, size_t size)
{
    if (p && pd->hit) {
        size_t bytes = size - size % pd->m.stride;
        if (bytes)
            shim_tag_array(pd->m.kind, p, bytes, pd->m.stride, pd->m.offset, pd->m.type, true,
                           pd->map, pd->map_len);
        if (shim.env.log >= 2)
            shim_log("EMM_TAG rule %d selected a block of %zu bytes", pd->m.rule, size);
    } else if (pd->map) {
        munmap(pd->map, pd->map_len);
    }
    shim_leave();
    return p;
}

/* Leaves an allocator function; the outermost acts on a pending signal. */
static inline void alloc_leave(void)
{
    if (--shim_in_alloc == 0 && !shim_busy
        && __atomic_load_n(&shim_pending_signal, __ATOMIC_RELAXED))
        shim_deliver_pending();
}

EMM_API void *malloc(size_t size);
EMM_API void *calloc(size_t n, size_t size);
EMM_API void *realloc(void *p, size_t size);
EMM_API void free(void *p);
EMM_API int posix_memalign(void **out, size_t align, size_t size);
EMM_API void *aligned_alloc(size_t align, size_t size);
EMM_API void *memalign(size_t align, size_t size);
EMM_API void *valloc(size_t size);
EMM_API size_t malloc_usable_size(void *p);

static void *malloc_impl(size_t size)
{
    if (!shim_real.malloc) {
        if (resolving)
            return arena_alloc(size, 16);
        shim_resolve();
    }
    struct pending pd;
    if (!alloc_begin(size, 16, &pd))
        return shim_real.malloc(size);
    return alloc_end(&pd, pd.map ? pd.map : shim_real.malloc(size), size);
}

void *malloc(size_t size)
{
    shim_in_alloc++;
    void *r = malloc_impl(size);
    alloc_leave();
    return r;
}

static void *calloc_impl(size_t n, size_t size)
{
    if (!shim_real.malloc) {
        if (resolving) {
            if (size && n > SIZE_MAX / size)
                return NULL;
            return arena_alloc(n * size, 16); /* static storage: already zero */
        }
        shim_resolve();
    }
    if (size && n > SIZE_MAX / size) {
        errno = ENOMEM;
        return NULL;
    }
    struct pending pd;
    if (!alloc_begin(n * size, 16, &pd))
        return shim_real.calloc(n, size);
    /* Fresh anonymous pages are already zero. */
    return alloc_end(&pd, pd.map ? pd.map : shim_real.calloc(n, size), n * size);
}

void *calloc(size_t n, size_t size)
{
    shim_in_alloc++;
    void *r = calloc_impl(n, size);
    alloc_leave();
    return r;
}

/* The block behind a mapped tag's base. */
static size_t mapped_size(const void *p, bool *found)
{
    size_t size = 0;
    *found = false;
    pthread_mutex_lock(&shim.lock);
    int slot = find_tag_locked((uintptr_t)p);
    if (slot >= 0 && shim.tags[slot].map) {
        size = shim.tags[slot].map_len - (size_t)((uintptr_t)p - (uintptr_t)shim.tags[slot].map);
        *found = true;
    }
    pthread_mutex_unlock(&shim.lock);
    return size;
}

static void release(const struct shim_tag *t, void *p)
{
    if (t->map)
        munmap(t->map, t->map_len);
    else
        shim_real.free(p);
}

static void free_impl(void *p)
{
    if (!p || in_arena(p))
        return;
    if (!shim_real.malloc)
        shim_resolve();
    /* Inside the shim (shim_busy) a block is never a tagged one: the shim
     * and the session free only their own. */
    struct shim_tag t;
    if (!shim_busy && tag_exists_quick(p) && take_tag(p, &t)) {
        release(&t, p);
        return;
    }
    shim_real.free(p);
}

void free(void *p)
{
    shim_in_alloc++;
    free_impl(p);
    alloc_leave();
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
    struct shim_tag t;
    if (!shim_busy && tag_exists_quick(p) && take_tag(p, &t)) {
        /* realloc moves the tag: the new block is the same array. */
        if (size == 0) {
            release(&t, p);
            return NULL;
        }
        void *q;
        void *map = NULL;
        size_t map_len = 0;
        if (t.map) {
            size_t old = t.map_len - (size_t)((uintptr_t)p - (uintptr_t)t.map);
            shim_busy++;
            if (shim.capture == SHIM_CAPTURE_FAULT && shim_fault_watching())
                map = shim_fault_map(size, &map_len);
            q = map ? map : shim_real.malloc(size);
            shim_leave();
            if (!q) {
                /* The old block stays valid and stays the array. */
                shim_tag_array(t.kind, p, t.bytes, t.stride, t.offset, t.type, t.from_rule,
                               t.map, t.map_len);
                errno = ENOMEM;
                return NULL;
            }
            memcpy(q, p, old < size ? old : size);
            munmap(t.map, t.map_len);
        } else {
            q = shim_real.realloc(p, size);
            if (!q) {
                shim_tag_array(t.kind, p, t.bytes, t.stride, t.offset, t.type, t.from_rule,
                               NULL, 0);
                return NULL;
            }
        }
        size_t bytes = size - size % t.stride;
        if (!t.from_rule && t.bytes < bytes)
            bytes = t.bytes;
        if (bytes)
            shim_tag_array(t.kind, q, bytes, t.stride, t.offset, t.type, t.from_rule, map, map_len);
        else if (map)
            shim_log("internal: an empty mapped block"); /* cannot happen: size >= stride */
        return q;
    }
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

void *realloc(void *p, size_t size)
{
    shim_in_alloc++;
    void *r = realloc_impl(p, size);
    alloc_leave();
    return r;
}

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
    int rc = 0;
    void *p = pd.map;
    if (!p)
        rc = shim_real.posix_memalign(&p, align, size);
    if (rc != 0)
        p = NULL;
    alloc_end(&pd, p, size);
    if (rc == 0)
        *out = p;
    return rc;
}

int posix_memalign(void **out, size_t align, size_t size)
{
    shim_in_alloc++;
    int r = posix_memalign_impl(out, align, size);
    alloc_leave();
    return r;
}

static void *aligned_alloc_impl(size_t align, size_t size)
{
    if (!shim_real.malloc) {
        if (resolving)
            return arena_alloc(size, align);
        shim_resolve();
    }
    return aligned_common(align, size, shim_real.aligned_alloc);
}

void *aligned_alloc(size_t align, size_t size)
{
    shim_in_alloc++;
    void *r = aligned_alloc_impl(align, size);
    alloc_leave();
    return r;
}

static void *memalign_impl(size_t align, size_t size)
{
    if (!shim_real.malloc) {
        if (resolving)
            return arena_alloc(size, align);
        shim_resolve();
    }
    return aligned_common(align, size, shim_real.memalign);
}

void *memalign(size_t align, size_t size)
{
    shim_in_alloc++;
    void *r = memalign_impl(align, size);
    alloc_leave();
    return r;
}

static void *valloc_real(size_t align, size_t size)
{
    (void)align;
    return shim_real.valloc(size);
}

static void *valloc_impl(size_t size)
{
    if (!shim_real.malloc) {
        if (resolving)
            return arena_alloc(size, 4096);
        shim_resolve();
    }
    return aligned_common((size_t)sysconf(_SC_PAGESIZE), size, valloc_real);
}

void *valloc(size_t size)
{
    shim_in_alloc++;
    void *r = valloc_impl(size);
    alloc_leave();
    return r;
}

size_t malloc_usable_size(void *p)
{
    if (!p)
        return 0;
    if (in_arena(p))
        return arena_size(p);
    if (!shim_real.malloc)
        shim_resolve();
    if (tag_exists_quick(p)) {
        bool found;
        size_t s = mapped_size(p, &found);
        if (found)
            return s;
    }
    return shim_real.malloc_usable_size ? shim_real.malloc_usable_size(p) : 0;
}

/* --- the explicit tags ------------------------------------------------- */

void emm_tag_vertices(const void *ptr, size_t count, size_t stride, size_t xyz_offset,
                      emm_scalar type)
{
    if (!shim.enabled || shim.finished || !ptr || !count || !stride || count > SIZE_MAX / stride)
        return;
    shim_tag_array(EMM_ARRAY_VERTICES, ptr, count * stride, stride, xyz_offset, type, false,
                   NULL, 0);
}

void emm_tag_triangles(const void *ptr, size_t count, size_t stride, size_t index_offset,
                       emm_scalar type)
{
    if (!shim.enabled || shim.finished || !ptr || !count || !stride || count > SIZE_MAX / stride)
        return;
    shim_tag_array(EMM_ARRAY_TRIANGLES, ptr, count * stride, stride, index_offset, type, false,
                   NULL, 0);
}

void emm_iteration(void)
{
    if (!shim.enabled || shim.finished)
        return;
    shim_flush_thread();
    shim_busy++;
    pthread_mutex_lock(&shim.lock);
    if (session_live_locked()) {
        emm_session_state st = emm_session_iteration(shim.session);
        if (st == EMM_SESSION_DECIDE && shim.state != EMM_SESSION_SIMULATING)
            decide_locked();
        else
            shim.state = st;
    }
    pthread_mutex_unlock(&shim.lock);
    shim_leave();
}

/* --- exit paths -------------------------------------------------------- */

EMM_API void _exit(int status);
EMM_API void _Exit(int status);

void _exit(int status)
{
    static __typeof__(_exit) *real;
    shim_finish();
    if (!real)
        real = (__typeof__(_exit) *)dlsym(RTLD_NEXT, "_exit");
    real(status);
    __builtin_unreachable();
}

void _Exit(int status)
{
    static __typeof__(_Exit) *real;
    shim_finish();
    if (!real)
        real = (__typeof__(_Exit) *)dlsym(RTLD_NEXT, "_Exit");
    real(status);
    __builtin_unreachable();
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
        return;
    }
    if (shim_busy || shim_in_alloc) {
        __atomic_store_n(&shim_pending_signal, sig, __ATOMIC_RELEASE);
        return;
    }
    terminate_now(sig);
}

static void install_terminate(int sig)
{
    struct sigaction old;
    if (shim_real_sigaction(sig, NULL, &old) != 0 || (old.sa_flags & SA_SIGINFO)
        || old.sa_handler != SIG_DFL)
        return;
    struct sigaction act;
    memset(&act, 0, sizeof act);
    act.sa_handler = on_terminate;
    sigemptyset(&act.sa_mask);
    shim_real_sigaction(sig, &act, NULL);
}

/* --- fork -------------------------------------------------------------- */

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
    __atomic_store_n(&shim.nranges, 0, __ATOMIC_RELEASE);
    shim_tbuf.n = 0;
    if (shim.capture == SHIM_CAPTURE_FAULT)
        shim_fault_child();
    shim_leave();
}

/* --- start-up ---------------------------------------------------------- */

static const char *get_env(const char *name)
{
    return getenv(name);
}

/* A bad EMM_* value or a session that cannot start: one line, then the
 * program runs untouched (or, with EMM_STRICT=1, does not run). */
static void step_aside(const char *msg)
{
    if (shim.env.strict) {
        shim_log("%s (EMM_STRICT=1: not running the program)", msg);
        _exit(SHIM_STRICT_EXIT);
    }
    shim_log("%s", msg);
}

static enum shim_capture pick_capture(void)
{
    if (dlsym(RTLD_DEFAULT, "emm_sancov_hooks_present"))
        return SHIM_CAPTURE_SANCOV;
    /* A program written against the mesh interface, that keeps no arrays of
     * its own for the shim to watch. */
    if (!shim.env.tag && !shim_program_imports("emm_tag_vertices")
        && (shim_program_imports("emm_mesh_vertex") || shim_program_imports("emm_mesh_triangle")))
        return SHIM_CAPTURE_API;
    return SHIM_CAPTURE_FAULT;
}

__attribute__((constructor(101))) static void shim_init(void)
{
    shim_resolve();
    shim_busy++;
    char msg[1024];
    if (!shim_env_parse(&shim.env, get_env, (long)getpid(), shim_rules_check, msg, sizeof msg)) {
        step_aside(msg);
        shim_leave();
        return;
    }
    if (shim.env.tag) {
        shim.rules = shim_rules_parse(shim.env.tag, msg, sizeof msg);
        if (!shim.rules || (shim_rules_need_stack(shim.rules) && !shim_rules_unwind_init(msg, sizeof msg))) {
            char line[1100];
            snprintf(line, sizeof line, "EMM_TAG: %s", msg);
            step_aside(line);
            shim_leave();
            return;
        }
    }
    shim.capture = shim.env.capture == SHIM_CAPTURE_AUTO ? pick_capture() : shim.env.capture;
    if (shim.capture == SHIM_CAPTURE_SANCOV && !dlsym(RTLD_DEFAULT, "emm_sancov_hooks_present")
        && shim.env.log >= 1)
        shim_log("EMM_CAPTURE=sancov, but %s was not built with emm_sancov_executable: "
                 "no accesses will be seen", program_invocation_short_name);

    emm_session_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.strategy = shim.env.strategy;
    cfg.window_accesses = shim.env.window_accesses;
    cfg.window_iterations = shim.env.window_iterations;
    cfg.compare = shim.env.compare;
    cfg.machine_path = shim.env.machine;
    cfg.table_path = shim.env.table;
    cfg.report_path = shim.env.report[0] ? shim.env.report : NULL;
    cfg.profile_dump = shim.env.profile_dump[0] ? shim.env.profile_dump : NULL;
    cfg.trace_path = shim.env.trace[0] ? shim.env.trace : NULL;
    cfg.capture = shim_capture_name(shim.capture);
    cfg.program = program_invocation_short_name;
    cfg.log = shim.env.log;
    emm_error err;
    if (emm_session_new(&cfg, &shim.session, &err) != EMM_OK) {
        shim.session = NULL;
        step_aside(err.message);
        shim_leave();
        return;
    }
    if (shim.capture == SHIM_CAPTURE_FAULT && !shim_fault_init()) {
        emm_session_free(shim.session);
        shim.session = NULL;
        step_aside("EMM_CAPTURE=fault: cannot install the SIGSEGV/SIGTRAP handlers");
        shim_leave();
        return;
    }
    pthread_key_create(&thread_key, thread_exit);
    pthread_atfork(fork_prepare, fork_parent, fork_child);
    install_terminate(SIGTERM);
    install_terminate(SIGINT);
    shim.rule_min = shim.rules ? shim_rules_min(shim.rules) : SIZE_MAX;
    shim.state = EMM_SESSION_PROFILING;
    if (shim.env.log >= 2) {
        shim_log("libemmshim.so in %s (pid %ld), capture %s", program_invocation_short_name,
                 (long)getpid(), shim_capture_name(shim.capture));
        shim_env_dump(&shim.env, stderr);
    }
    __atomic_store_n(&shim.enabled, true, __ATOMIC_RELEASE);
    shim_leave();
}

__attribute__((destructor(101))) static void shim_fini(void)
{
    shim_finish();
}
