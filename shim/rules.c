/* EMM_TAG rules at allocation time (docs/design.md "The shim and the session", Tagging):
 * which allocation a rule selects, by a function on its call stack, by size or by rank.
 * The grammar, the names a frame answers to and the messages are below the shim
 * (core/tag_rules.c, emm/config.h); what stays here needs the live call stack.
 *
 * Call-site names come from libunwind (unw_get_proc_name reads .symtab, so a
 * static function is found in a binary that is not stripped), demangled by
 * the C++ runtime's __cxa_demangle when the process has one (libemm brings
 * libstdc++). libunwind is dlopen'ed RTLD_LOCAL rather than linked:
 * libunwind.so.8 also defines the _Unwind_* ABI, and a preloaded dependency
 * would put those ahead of libgcc_s's for the program's C++ exceptions.
 * Names are cached by return address, so each frame is named once.
 *
 * site= matches any frame of the stack that is the program's (not an
 * allocator's or the standard library's), by its name or its qualified
 * name. A rule follows the first call path (the return addresses from the
 * innermost frame of the program's to the frame it names) it selects: a
 * growing array reallocates from that same path, and the site's other
 * allocations are left to later rules. What the rules saw is kept for the
 * line at exit that says a rule matched nothing. */
#define UNW_LOCAL_ONLY
#include <libunwind.h>

#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shim.h"

#define MAX_FRAMES 32

/* Per rule: blocks the other selectors selected (nth=), the call path the
 * rule follows (a hash; 0: none yet) and the blocks it selected. Atomic. */
static uint64_t seen[EMM_TAG_RULES_MAX];
static uint64_t bound[EMM_TAG_RULES_MAX];
static uint64_t selected[EMM_TAG_RULES_MAX];

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
    char *(*demangle)(const char *, char *, size_t *, int *);
} unw;

bool shim_rules_init(char *msg, size_t cap)
{
    bool need = shim.config.list_sites;
    for (size_t i = 0; i < shim.config.tags.n; i++)
        need = need || shim.config.tags.rule[i].site[0];
    if (!need)
        return true;
#if defined(__x86_64__)
    void *h = dlopen("libunwind.so.8", RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        snprintf(msg, cap, "%s needs libunwind.so.8: %s",
                 shim.config.list_sites ? "EMM_LIST_SITES" : "EMM_TAG: site=", dlerror());
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
    *(void **)&unw.demangle = dlsym(RTLD_DEFAULT, "__cxa_demangle");
    return true;
#else
    snprintf(msg, cap, "EMM_TAG: site= is supported on x86-64 only");
    return false;
#endif
}

/* The name cache: return address -> the frame's two names in a pool. */
#define CACHE_SLOTS 4096
#define POOL_BYTES (256 * 1024)
static struct {
    pthread_mutex_t lock;
    uintptr_t ip[CACHE_SLOTS];
    uint32_t name[CACHE_SLOTS]; /* offset in pool of "name\0qualified\0"; UINT32_MAX: none */
    bool skip[CACHE_SLOTS];     /* an allocator or standard-library frame */
    char pool[POOL_BYTES];
    size_t used;
    /* the sites seen: the innermost frame of the program's, by name */
    emm_tag_site_seen sites[64];
    size_t nsites;
} cache = {.lock = PTHREAD_MUTEX_INITIALIZER};

/* The names of the function at the cursor's frame ("name\0qualified\0"), or
 * NULL; *skip says whether the frame belongs to an allocator or a library. */
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
    char raw[1024], names[2 * EMM_TAG_SITE_MAX + 256];
    unw_word_t off;
    Dl_info info;
    bool named = unw.get_proc_name(cur, raw, sizeof raw, &off) == 0;
    size_t need = 0;
    if (named) {
        int status = -1;
        char *dm = unw.demangle && raw[0] == '_' && raw[1] == 'Z'
                       ? unw.demangle(raw, NULL, NULL, &status)
                       : NULL;
        char qual[EMM_TAG_SITE_MAX + 256];
        emm_tag_site_names(raw, status == 0 ? dm : NULL, names, EMM_TAG_SITE_MAX, qual,
                           sizeof qual);
        free(dm);
        size_t ln = strlen(names) + 1, lq = strlen(qual) + 1;
        memcpy(names + ln, qual, lq);
        need = ln + lq;
    }
    *skip = emm_tag_site_is_library(named ? raw : NULL,
                                    dladdr((void *)ip, &info) ? info.dli_fname : NULL);

    const char *result = NULL;
    pthread_mutex_lock(&cache.lock);
    uint32_t at = UINT32_MAX;
    if (named && cache.used + need <= POOL_BYTES) {
        at = (uint32_t)cache.used;
        memcpy(cache.pool + at, names, need);
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
    /* A full pool: compare against names that live on in no cache. */
    if (named && !result) {
        static __thread char spill[sizeof names] SHIM_TLS;
        memcpy(spill, names, need);
        result = spill;
    }
    return result;
}

/* The program's frames of the allocation's stack (allocator and
 * standard-library frames left out), innermost first: names and return
 * addresses; returns how many. */
static int stack_frames(const char **name, uintptr_t *ip)
{
    unw_context_t ctx;
    unw_cursor_t cur;
    int n = 0;
    if (unw.getcontext(&ctx) != 0 || unw.init_local(&cur, &ctx) != 0)
        return 0;
    for (int depth = 0; depth < MAX_FRAMES && unw.step(&cur) > 0; depth++) {
        unw_word_t w;
        bool skip = false;
        if (unw.get_reg(&cur, UNW_REG_IP, &w) != 0 || w == 0)
            break;
        const char *nm = frame_name(&cur, (uintptr_t)w, &skip);
        if (!skip) {
            name[n] = nm;
            ip[n++] = (uintptr_t)w;
        }
    }
    return n;
}

/* Counts a block at the innermost frame's site, for the line at exit. */
static void note_site(const char *name, size_t size)
{
    if (!name)
        return;
    pthread_mutex_lock(&cache.lock);
    size_t i = 0;
    while (i < cache.nsites && strcmp(cache.sites[i].name, name) != 0)
        i++;
    if (i == cache.nsites && cache.nsites < sizeof cache.sites / sizeof *cache.sites) {
        snprintf(cache.sites[i].name, sizeof cache.sites[i].name, "%s", name);
        cache.nsites++;
    }
    if (i < cache.nsites) {
        cache.sites[i].count++;
        if (size > cache.sites[i].largest)
            cache.sites[i].largest = size;
    }
    pthread_mutex_unlock(&cache.lock);
}

int shim_rules_match(size_t size, const char **site)
{
    const char *name[MAX_FRAMES];
    uintptr_t ip[MAX_FRAMES];
    int nframes = -1;
    *site = NULL;
    for (size_t i = 0; i < shim.config.tags.n; i++) {
        const emm_tag_rule *r = &shim.config.tags.rule[i];
        if (size < r->min)
            continue;
        uint64_t path = 0;
        if (r->site[0]) {
            if (nframes < 0) {
                nframes = stack_frames(name, ip);
                note_site(nframes > 0 ? name[0] : NULL, size);
            }
            int f = 0;
            while (f < nframes && !(name[f] && emm_tag_site_matches(r->site, name[f],
                                                                    name[f] + strlen(name[f]) + 1)))
                f++;
            if (f == nframes)
                continue;
            /* The call path, innermost frame of the program's to the site. */
            path = 14695981039346656037ull;
            for (int k = 0; k <= f; k++)
                path = (path ^ ip[k]) * 1099511628211ull;
            path |= 1;
            /* Not the array, or a wrong stride (or n=): never tagged; the
             * line at exit names the site's blocks that do not fit. */
            if (!emm_tag_rule_fits(r, size))
                continue;
            /* A rule follows the first call path it selects; the site's
             * other allocations are left to the later rules. */
            uint64_t expect = 0;
            if (!__atomic_compare_exchange_n(&bound[i], &expect, path, false, __ATOMIC_RELAXED,
                                             __ATOMIC_RELAXED) &&
                expect != path)
                continue;
            *site = name[f];
        } else if (!emm_tag_rule_fits(r, size)) {
            continue;
        }
        if (r->nth && __atomic_add_fetch(&seen[i], 1, __ATOMIC_RELAXED) != r->nth)
            continue;
        __atomic_add_fetch(&selected[i], 1, __ATOMIC_RELAXED);
        return (int)i;
    }
    return -1;
}

void shim_rules_report(void)
{
    for (size_t i = 0; i < shim.config.tags.n; i++) {
        if (__atomic_load_n(&selected[i], __ATOMIC_RELAXED))
            continue;
        char line[1024];
        pthread_mutex_lock(&cache.lock);
        emm_tag_unmatched_message(&shim.config.tags.rule[i], i, cache.sites, cache.nsites, line,
                                  sizeof line);
        pthread_mutex_unlock(&cache.lock);
        shim_log("%s", line);
    }
}

void shim_rules_list(const void *block, size_t size)
{
    const char *name[MAX_FRAMES];
    uintptr_t ip[MAX_FRAMES];
    int n = stack_frames(name, ip);
    uint64_t path = 14695981039346656037ull;
    for (int k = 0; k < n; k++)
        path = (path ^ ip[k]) * 1099511628211ull;
    pthread_mutex_lock(&shim.lock);
    if (shim.sites && !shim.finished)
        emm_sites_add(shim.sites, path, name, (size_t)n, block, size);
    pthread_mutex_unlock(&shim.lock);
}
