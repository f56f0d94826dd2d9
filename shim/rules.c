/* EMM_TAG rules at allocation time (DESIGN.md "The shim", Tagging): which
 * allocation a rule selects, by the name of the function that makes it, by
 * size or by rank. The grammar is parsed below the shim (core/tag_rules.c,
 * emm/config.h); what stays here needs the live call stack.
 *
 * Call-site names come from libunwind (unw_get_proc_name reads .symtab, so a
 * static function is found in a binary that is not stripped). libunwind is
 * dlopen'ed RTLD_LOCAL rather than linked: libunwind.so.8 also defines the
 * _Unwind_* ABI, and a preloaded dependency would put those ahead of
 * libgcc_s's for the program's C++ exceptions. Names are cached by return
 * address, so each allocation site is named once. */
#define UNW_LOCAL_ONLY
#include <libunwind.h>

#include <dlfcn.h>
#include <stdio.h>
#include <string.h>

#include "shim.h"

#define MAX_FRAMES 32

/* Per rule: blocks the other selectors selected (nth=), and the call site in
 * `site` the rule follows (0: none yet). Atomic. */
static uint64_t seen[EMM_TAG_RULES_MAX];
static uintptr_t bound[EMM_TAG_RULES_MAX];

size_t shim_rules_min(void)
{
    size_t m = SIZE_MAX;
    for (size_t i = 0; i < shim.config.tags.n; i++)
        if (shim.config.tags.rule[i].min < m)
            m = (size_t)shim.config.tags.rule[i].min;
    return m;
}

static struct {
    int (*getcontext)(unw_context_t *);
    int (*init_local)(unw_cursor_t *, unw_context_t *);
    int (*step)(unw_cursor_t *);
    int (*get_reg)(unw_cursor_t *, int, unw_word_t *);
    int (*get_proc_name)(unw_cursor_t *, char *, size_t, unw_word_t *);
} unw;

bool shim_rules_init(char *msg, size_t cap)
{
    bool need = false;
    for (size_t i = 0; i < shim.config.tags.n; i++)
        need = need || shim.config.tags.rule[i].site[0];
    if (!need)
        return true;
#if defined(__x86_64__)
    void *h = dlopen("libunwind.so.8", RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        snprintf(msg, cap, "EMM_TAG: site= needs libunwind.so.8: %s", dlerror());
        return false;
    }
    *(void **)&unw.getcontext = dlsym(h, "_Ux86_64_getcontext");
    *(void **)&unw.init_local = dlsym(h, "_ULx86_64_init_local");
    *(void **)&unw.step = dlsym(h, "_ULx86_64_step");
    *(void **)&unw.get_reg = dlsym(h, "_ULx86_64_get_reg");
    *(void **)&unw.get_proc_name = dlsym(h, "_ULx86_64_get_proc_name");
    if (!unw.getcontext || !unw.init_local || !unw.step || !unw.get_reg || !unw.get_proc_name) {
        snprintf(msg, cap, "EMM_TAG: site= needs libunwind.so.8, which lacks the local unwinder");
        return false;
    }
    return true;
#else
    snprintf(msg, cap, "EMM_TAG: site= is supported on x86-64 only");
    return false;
#endif
}

/* The name cache: return address -> site name in a pool. */
#define CACHE_SLOTS 4096
#define POOL_BYTES (128 * 1024)
static struct {
    pthread_mutex_t lock;
    uintptr_t ip[CACHE_SLOTS];
    uint32_t name[CACHE_SLOTS]; /* offset in pool; UINT32_MAX: no name */
    bool skip[CACHE_SLOTS];     /* an allocator or standard-library frame */
    char pool[POOL_BYTES];
    size_t used;
} cache = {.lock = PTHREAD_MUTEX_INITIALIZER};

/* The site name of the function at the cursor's frame, or NULL; *skip says
 * whether the frame belongs to an allocator or a library. */
static const char *frame_name(unw_cursor_t *cur, uintptr_t ip, bool *skip)
{
    size_t h = (ip >> 2) * 2654435761u % CACHE_SLOTS;
    pthread_mutex_lock(&cache.lock);
    for (size_t i = 0; i < CACHE_SLOTS; i++) {
        size_t s = (h + i) % CACHE_SLOTS;
        if (cache.ip[s] == ip) {
            uint32_t off = cache.name[s];
            *skip = cache.skip[s];
            pthread_mutex_unlock(&cache.lock);
            return off == UINT32_MAX ? NULL : cache.pool + off;
        }
        if (cache.ip[s] == 0)
            break;
    }
    pthread_mutex_unlock(&cache.lock);

    /* Named outside the lock: unw_get_proc_name may take the loader's. */
    char raw[1024], norm[EMM_TAG_SITE_MAX];
    unw_word_t off;
    Dl_info info;
    bool named = unw.get_proc_name(cur, raw, sizeof raw, &off) == 0;
    if (named)
        emm_tag_site_name(raw, norm, sizeof norm);
    *skip = emm_tag_site_is_library(named ? raw : NULL,
                                    dladdr((void *)ip, &info) ? info.dli_fname : NULL);

    const char *result = NULL;
    pthread_mutex_lock(&cache.lock);
    size_t need = named ? strlen(norm) + 1 : 0;
    uint32_t at = UINT32_MAX;
    if (named && cache.used + need <= POOL_BYTES) {
        at = (uint32_t)cache.used;
        memcpy(cache.pool + at, norm, need);
        cache.used += need;
        result = cache.pool + at;
    }
    for (size_t i = 0; i < CACHE_SLOTS; i++) {
        size_t s = (h + i) % CACHE_SLOTS;
        if (cache.ip[s] == 0 && (at != UINT32_MAX || !named)) {
            cache.ip[s] = ip;
            cache.name[s] = at;
            cache.skip[s] = *skip;
        }
        if (cache.ip[s] == 0 || cache.ip[s] == ip)
            break;
    }
    pthread_mutex_unlock(&cache.lock);
    /* A full pool: compare against a name that lives on in no cache. */
    if (named && !result) {
        static __thread char spill[EMM_TAG_SITE_MAX] SHIM_TLS;
        memcpy(spill, norm, sizeof spill);
        result = spill;
    }
    return result;
}

/* The allocation's call site: the first frame, going up, that is not an
 * allocator or standard-library frame (so allocations made deep inside a
 * library the site calls are not the site's). Its name, or NULL; *where
 * gets its return address, which tells the site's allocation calls apart. */
static const char *call_site(uintptr_t *where)
{
    unw_context_t ctx;
    unw_cursor_t cur;
    if (unw.getcontext(&ctx) != 0 || unw.init_local(&cur, &ctx) != 0)
        return NULL;
    for (int depth = 0; depth < MAX_FRAMES && unw.step(&cur) > 0; depth++) {
        unw_word_t ip;
        bool skip = false;
        if (unw.get_reg(&cur, UNW_REG_IP, &ip) != 0 || ip == 0)
            break;
        const char *name = frame_name(&cur, (uintptr_t)ip, &skip);
        if (!skip) {
            *where = (uintptr_t)ip;
            return name;
        }
    }
    return NULL;
}

int shim_rules_match(size_t size)
{
    const char *site = NULL;
    uintptr_t where = 0;
    bool unwound = false;
    for (size_t i = 0; i < shim.config.tags.n; i++) {
        const emm_tag_rule *r = &shim.config.tags.rule[i];
        /* A block that is not a whole number of records is not the array. */
        if (size < r->min || size % r->stride != 0)
            continue;
        if (r->site[0]) {
            if (!unwound) {
                site = call_site(&where);
                unwound = true;
            }
            if (!site || strcmp(site, r->site) != 0)
                continue;
            /* A rule follows the first call in its site function that it
             * selects (a growing vector reallocates from that same call);
             * the site's other allocations are left to the later rules. */
            uintptr_t expect = 0;
            if (!__atomic_compare_exchange_n(&bound[i], &expect, where, false, __ATOMIC_RELAXED,
                                             __ATOMIC_RELAXED)
                && expect != where)
                continue;
        }
        if (r->nth && __atomic_add_fetch(&seen[i], 1, __ATOMIC_RELAXED) != r->nth)
            continue;
        return (int)i;
    }
    return -1;
}
