/* EMM_TAG rules at allocation time (runtime/agent_rules.h; docs/design.md
 * "The shim and the session", Tagging).
 *
 * Call-site names come from libunwind (unw_get_proc_name reads .symtab, so a
 * static function is found in a binary that is not stripped), demangled by
 * the C++ runtime's __cxa_demangle when the process has one (libemm brings
 * libstdc++). libunwind is dlopen'ed RTLD_LOCAL rather than linked:
 * libunwind.so.8 also defines the _Unwind_* ABI, and a dependency of the
 * preloaded shim would put those ahead of libgcc_s's for the program's C++
 * exceptions. A symbol names a frame only when it starts the function the
 * pc lies in, as the unwind information (.eh_frame, present in stripped
 * binaries too) bounds it; otherwise the nearest symbol is some other
 * function's (a stripped binary's exported destructor 20 KB before the pc)
 * and the frame is named MODULE+0xOFFSET instead: the object's file name
 * and the function's start as an offset from the object's load base (the
 * address objdump shows, the same under ASLR). Names are cached by return
 * address, so each frame is named once.
 *
 * The stack is unwound from inside this library: its own frames come first
 * and are left out, then the shim's and the allocator's (library frames),
 * then the program's. site= matches any frame of the program's, by its name
 * or its qualified name. A rule follows the first call path (the return
 * addresses from the innermost frame of the program's to the frame it
 * names) it selects: a growing array reallocates from that same path, and
 * the site's other allocations are left to later rules. What the rules saw
 * is kept for the line at exit that says a rule matched nothing. */
#define UNW_LOCAL_ONLY
#include <libunwind.h>

#include "agent_rules.h"

#include <dlfcn.h>
#include <link.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "error.h"

/* The name cache: return address -> the frame's two names in a pool. */
#define CACHE_SLOTS 4096
#define POOL_BYTES (256 * 1024)

struct unwinder {
    int (*getcontext)(unw_context_t *);
    int (*init_local)(unw_cursor_t *, unw_context_t *);
    int (*step)(unw_cursor_t *);
    int (*get_reg)(unw_cursor_t *, int, unw_word_t *);
    int (*get_proc_name)(unw_cursor_t *, char *, size_t, unw_word_t *);
    int (*get_proc_info)(unw_cursor_t *, unw_proc_info_t *);
    char *(*demangle)(const char *, char *, size_t *, int *);
};

struct agent_rules {
    const emm_tag_rules *rs;
    /* Per rule: blocks the other selectors selected (nth=), the call path
     * the rule follows (a hash; 0: none yet) and the blocks it selected.
     * Atomic. */
    uint64_t *seen, *bound, *selected;
    /* Per rule: the blocks it would have taken that an earlier rule took
     * first — the first such rule (index + 1), how many, the largest. Atomic. */
    uint64_t *shadow_by, *shadow_n, *shadow_size;
    /* Per rule: blocks of its min= or more, the largest, and those of them
     * that are whole records; and the largest block looked at. Atomic. */
    uint64_t *big_n, *big_size, *fit_n;
    uint64_t largest;
    bool have_unwinder;
    struct unwinder unw;
    const void *own_base; /* this library's load address: its frames are left out */
    pthread_mutex_t lock; /* the cache and the sites seen */
    uintptr_t ip[CACHE_SLOTS];
    uint32_t name[CACHE_SLOTS]; /* offset in pool of "name\0qualified\0"; UINT32_MAX: none */
    bool skip[CACHE_SLOTS];     /* an allocator or standard-library frame */
    char pool[POOL_BYTES];
    size_t used;
    /* the sites seen: the innermost frame of the program's, by name */
    emm_tag_site_seen *sites;
    size_t nsites, csites;
};

static emm_status open_unwinder(agent_rules *m, bool stacks, emm_error *err)
{
#if defined(__x86_64__)
    void *h = dlopen("libunwind.so.8", RTLD_NOW | RTLD_LOCAL);
    if (!h)
        return emm_fail(err, EMM_ERR_IO, "%s needs libunwind.so.8: %s",
                        stacks ? "EMM_LIST_SITES" : "EMM_TAG: site=", dlerror());
    struct unwinder *u = &m->unw;
    *(void **)&u->getcontext = dlsym(h, "_Ux86_64_getcontext");
    *(void **)&u->init_local = dlsym(h, "_ULx86_64_init_local");
    *(void **)&u->step = dlsym(h, "_ULx86_64_step");
    *(void **)&u->get_reg = dlsym(h, "_ULx86_64_get_reg");
    *(void **)&u->get_proc_name = dlsym(h, "_ULx86_64_get_proc_name");
    *(void **)&u->get_proc_info = dlsym(h, "_ULx86_64_get_proc_info");
    if (!u->getcontext || !u->init_local || !u->step || !u->get_reg || !u->get_proc_name ||
        !u->get_proc_info)
        return emm_fail(err, EMM_ERR_IO,
                        "EMM_TAG: site= needs libunwind.so.8, which lacks the local unwinder");
    *(void **)&u->demangle = dlsym(RTLD_DEFAULT, "__cxa_demangle");
    Dl_info self;
    if (dladdr((void *)open_unwinder, &self))
        m->own_base = self.dli_fbase;
    m->have_unwinder = true;
    return EMM_OK;
#else
    (void)m;
    (void)stacks;
    return emm_fail(err, EMM_ERR_INVALID, "EMM_TAG: site= is supported on x86-64 only");
#endif
}

static emm_status rules_new(const emm_tag_rules *rs, bool stacks, bool unwind, agent_rules **out,
                            emm_error *err)
{
    *out = NULL;
    agent_rules *m = calloc(1, sizeof *m);
    size_t n = rs->n ? rs->n : 1;
    if (m) {
        m->seen = calloc(n, sizeof *m->seen);
        m->bound = calloc(n, sizeof *m->bound);
        m->selected = calloc(n, sizeof *m->selected);
        m->shadow_by = calloc(n, sizeof *m->shadow_by);
        m->shadow_n = calloc(n, sizeof *m->shadow_n);
        m->shadow_size = calloc(n, sizeof *m->shadow_size);
        m->big_n = calloc(n, sizeof *m->big_n);
        m->big_size = calloc(n, sizeof *m->big_size);
        m->fit_n = calloc(n, sizeof *m->fit_n);
    }
    if (!m || !m->seen || !m->bound || !m->selected || !m->shadow_by || !m->shadow_n ||
        !m->shadow_size || !m->big_n || !m->big_size || !m->fit_n) {
        agent_rules_free(m);
        return emm_fail(err, EMM_ERR_NOMEM, "libemmshim.so: out of memory for the rules");
    }
    m->rs = rs;
    pthread_mutex_init(&m->lock, NULL);
    bool need = stacks;
    for (size_t i = 0; i < rs->n; i++)
        need = need || rs->rule[i].site[0];
    emm_status st = need && unwind ? open_unwinder(m, stacks, err) : EMM_OK;
    if (st != EMM_OK) {
        agent_rules_free(m);
        return st;
    }
    *out = m;
    return EMM_OK;
}

emm_status agent_rules_new(const emm_tag_rules *rs, bool stacks, agent_rules **out,
                           emm_error *err)
{
    return rules_new(rs, stacks, true, out, err);
}

void agent_rules_free(agent_rules *m)
{
    if (!m)
        return;
    free(m->seen);
    free(m->bound);
    free(m->selected);
    free(m->shadow_by);
    free(m->shadow_n);
    free(m->shadow_size);
    free(m->big_n);
    free(m->big_size);
    free(m->fit_n);
    free(m->sites);
    free(m);
}

size_t agent_rules_min(const agent_rules *m)
{
    size_t least = SIZE_MAX;
    for (size_t i = 0; i < m->rs->n; i++)
        if (m->rs->rule[i].min < least)
            least = (size_t)m->rs->rule[i].min;
    return least;
}

/* "MODULE+0xOFFSET" for code at `pc`: the object's file name and the
 * pc's offset from its load base (the address objdump shows for it, the
 * same under ASLR), or false when no object holds it. */
static bool module_offset(uintptr_t pc, char *out, size_t cap)
{
    Dl_info info;
    struct link_map *lm = NULL;
    if (!dladdr1((void *)pc, &info, (void **)&lm, RTLD_DL_LINKMAP) || !lm)
        return false;
    char exe[512];
    const char *path = lm->l_name && lm->l_name[0] ? lm->l_name : NULL;
    if (!path) { /* the program itself */
        ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
        if (n <= 0)
            return false;
        exe[n] = '\0';
        path = exe;
    }
    const char *base = strrchr(path, '/');
    snprintf(out, cap, "%.100s+0x%llx", base ? base + 1 : path,
             (unsigned long long)(pc - (uintptr_t)lm->l_addr));
    return true;
}

/* The names of the function at the cursor's frame ("name\0qualified\0"), or
 * NULL; *skip says whether the frame belongs to an allocator or a library. */
static const char *frame_name(agent_rules *m, unw_cursor_t *cur, uintptr_t ip, bool *skip)
{
    size_t h = (ip >> 2) * 2654435761u % CACHE_SLOTS;
    pthread_mutex_lock(&m->lock);
    for (size_t i = 0; i < CACHE_SLOTS; i++) {
        size_t s = (h + i) % CACHE_SLOTS;
        if (m->ip[s] == ip) {
            uint32_t off = m->name[s];
            *skip = m->skip[s];
            pthread_mutex_unlock(&m->lock);
            return off == UINT32_MAX ? NULL : m->pool + off;
        }
        if (m->ip[s] == 0)
            break;
    }
    pthread_mutex_unlock(&m->lock);

    /* Named outside the lock: unw_get_proc_name may take the loader's. */
    char raw[1024], names[2 * EMM_TAG_SITE_MAX + 256];
    unw_word_t off;
    Dl_info info;
    bool named = m->unw.get_proc_name(cur, raw, sizeof raw, &off) == 0;
    /* The symbol names the frame only when it starts the function the pc
     * lies in (its unwind information says where that starts): in a
     * stripped binary the nearest exported symbol lies before it, a
     * destructor of 0x44 bytes 20 KB short of the pc. */
    unw_proc_info_t pi;
    bool have_pi = m->unw.get_proc_info(cur, &pi) == 0 && pi.start_ip && pi.start_ip <= ip &&
                   ip <= pi.end_ip;
    if (named && have_pi && ip - off != pi.start_ip)
        named = false;
    size_t need = 0;
    if (!named && module_offset(have_pi ? pi.start_ip : ip, names, EMM_TAG_SITE_MAX)) {
        /* Named by module and offset: "name\0name\0". */
        size_t ln = strlen(names) + 1;
        memcpy(names + ln, names, ln);
        need = 2 * ln;
    } else if (named) {
        int status = -1;
        char *dm = m->unw.demangle && raw[0] == '_' && raw[1] == 'Z'
                       ? m->unw.demangle(raw, NULL, NULL, &status)
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
    pthread_mutex_lock(&m->lock);
    uint32_t at = UINT32_MAX;
    if (need && m->used + need <= POOL_BYTES) {
        at = (uint32_t)m->used;
        memcpy(m->pool + at, names, need);
        m->used += need;
        result = m->pool + at;
    }
    for (size_t i = 0; i < CACHE_SLOTS; i++) {
        size_t s = (h + i) % CACHE_SLOTS;
        if (m->ip[s] == 0 && (at != UINT32_MAX || !need)) {
            m->ip[s] = ip;
            m->name[s] = at;
            m->skip[s] = *skip;
        }
        if (m->ip[s] == 0 || m->ip[s] == ip)
            break;
    }
    pthread_mutex_unlock(&m->lock);
    /* A full pool: compare against names that live on in no cache. */
    if (need && !result) {
        static __thread char spill[sizeof names];
        memcpy(spill, names, need);
        result = spill;
    }
    return result;
}

int agent_rules_stack(agent_rules *m, const char **name, uintptr_t *ip)
{
    unw_context_t ctx;
    unw_cursor_t cur;
    int n = 0;
    bool leading = true; /* still in this library's own frames */
    if (!m->have_unwinder || m->unw.getcontext(&ctx) != 0 || m->unw.init_local(&cur, &ctx) != 0)
        return 0;
    for (int depth = 0; depth < AGENT_MAX_FRAMES && m->unw.step(&cur) > 0; depth++) {
        unw_word_t w;
        bool skip = false;
        if (m->unw.get_reg(&cur, UNW_REG_IP, &w) != 0 || w == 0)
            break;
        if (leading) {
            Dl_info info;
            if (m->own_base && dladdr((void *)w, &info) && info.dli_fbase == m->own_base)
                continue;
            leading = false;
        }
        const char *nm = frame_name(m, &cur, (uintptr_t)w, &skip);
        if (!skip) {
            name[n] = nm;
            ip[n++] = (uintptr_t)w;
        }
    }
    return n;
}

/* Counts a block at the innermost frame's site, for the line at exit. */
static void note_site(agent_rules *m, const char *name, size_t size)
{
    if (!name)
        return;
    pthread_mutex_lock(&m->lock);
    size_t i = 0;
    while (i < m->nsites && strcmp(m->sites[i].name, name) != 0)
        i++;
    if (i == m->nsites) {
        if (m->nsites == m->csites) {
            size_t cap = m->csites ? 2 * m->csites : 16;
            emm_tag_site_seen *s = realloc(m->sites, cap * sizeof *s);
            if (!s) {
                pthread_mutex_unlock(&m->lock);
                return;
            }
            m->sites = s;
            m->csites = cap;
        }
        memset(&m->sites[i], 0, sizeof m->sites[i]);
        snprintf(m->sites[i].name, sizeof m->sites[i].name, "%s", name);
        m->nsites++;
    }
    m->sites[i].count++;
    if (size > m->sites[i].largest)
        m->sites[i].largest = size;
    pthread_mutex_unlock(&m->lock);
}

/* Whether rule i selects a block of `size` allocated on the stack of
 * name/ip (taken on the first rule with a site=, *nframes then >= 0): its
 * min=, its site= among the frames (*f: which; *path: the call path to
 * it, 0 without site=) and its shape. Neither nth= nor the call path the
 * rule follows is looked at. */
static bool rule_selects(agent_rules *m, size_t i, size_t size, const char **name, uintptr_t *ip,
                         int *nframes, int *f, uint64_t *path)
{
    const emm_tag_rule *r = &m->rs->rule[i];
    *path = 0;
    if (size < r->min)
        return false;
    if (r->site[0]) {
        if (*nframes < 0) {
            *nframes = agent_rules_stack(m, name, ip);
            note_site(m, *nframes > 0 ? name[0] : NULL, size);
        }
        *f = 0;
        /* site=^FUNCTION: the innermost frame of the program's own only. */
        bool innermost = r->site[0] == '^';
        const char *site = r->site + innermost;
        int frames = innermost && *nframes > 1 ? 1 : *nframes;
        while (*f < frames && !(name[*f] && emm_tag_site_matches(site, name[*f],
                                                                 name[*f] + strlen(name[*f]) + 1)))
            (*f)++;
        if (*f == frames)
            *f = *nframes;
        if (*f == *nframes)
            return false;
        /* The call path, innermost frame of the program's to the site. */
        uint64_t h = 14695981039346656037ull;
        for (int k = 0; k <= *f; k++)
            h = (h ^ ip[k]) * 1099511628211ull;
        *path = h | 1;
    }
    /* Not the array, or a wrong stride (or n=): never tagged; the line at
     * exit names the site's blocks that do not fit. */
    return emm_tag_rule_fits(r, size);
}

static void max_store(uint64_t *at, uint64_t v)
{
    uint64_t big = __atomic_load_n(at, __ATOMIC_RELAXED);
    while (v > big &&
           !__atomic_compare_exchange_n(at, &big, v, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
}

/* agent_rules_match on the stack name/ip of *nframes frames, unwound on
 * the first rule with a site= when *nframes < 0. */
static int match_on(agent_rules *m, size_t size, const char **name, uintptr_t *ip, int *nframes,
                    const char **site)
{
    int f = 0;
    uint64_t path;
    *site = NULL;
    max_store(&m->largest, size);
    for (size_t i = 0; i < m->rs->n; i++) {
        const emm_tag_rule *r = &m->rs->rule[i];
        if (size < r->min)
            continue;
        __atomic_add_fetch(&m->big_n[i], 1, __ATOMIC_RELAXED);
        max_store(&m->big_size[i], size);
        if (emm_tag_rule_fits(r, size))
            __atomic_add_fetch(&m->fit_n[i], 1, __ATOMIC_RELAXED);
    }
    for (size_t i = 0; i < m->rs->n; i++) {
        if (!rule_selects(m, i, size, name, ip, nframes, &f, &path))
            continue;
        if (path) {
            /* A rule follows the first call path it selects; the site's
             * other allocations are left to the later rules. */
            uint64_t expect = 0;
            if (!__atomic_compare_exchange_n(&m->bound[i], &expect, path, false,
                                             __ATOMIC_RELAXED, __ATOMIC_RELAXED) &&
                expect != path)
                continue;
            *site = name[f];
        }
        if (m->rs->rule[i].nth && __atomic_add_fetch(&m->seen[i], 1, __ATOMIC_RELAXED) !=
                                      m->rs->rule[i].nth)
            continue;
        __atomic_add_fetch(&m->selected[i], 1, __ATOMIC_RELAXED);
        /* A later rule that selects this block too has it taken from it:
         * noted, so the line at exit says where its block went. */
        for (size_t j = i + 1; j < m->rs->n; j++) {
            int fj = 0;
            uint64_t expect = 0, pj;
            if (__atomic_load_n(&m->selected[j], __ATOMIC_RELAXED) ||
                !rule_selects(m, j, size, name, ip, nframes, &fj, &pj))
                continue;
            __atomic_compare_exchange_n(&m->shadow_by[j], &expect, i + 1, false,
                                        __ATOMIC_RELAXED, __ATOMIC_RELAXED);
            __atomic_add_fetch(&m->shadow_n[j], 1, __ATOMIC_RELAXED);
            max_store(&m->shadow_size[j], size);
        }
        return (int)i;
    }
    return -1;
}

int agent_rules_match(agent_rules *m, size_t size, const char **site)
{
    const char *name[AGENT_MAX_FRAMES];
    uintptr_t ip[AGENT_MAX_FRAMES];
    int nframes = -1;
    return match_on(m, size, name, ip, &nframes, site);
}

uint64_t agent_rules_counted(const agent_rules *m, size_t i)
{
    return i < m->rs->n ? __atomic_load_n(&m->seen[i], __ATOMIC_RELAXED) : 0;
}

emm_status agent_rules_replayer(const emm_tag_rules *rs, agent_rules **out, emm_error *err)
{
    return rules_new(rs, false, false, out, err);
}

int agent_rules_replay(agent_rules *m, size_t size, const char *const *name, const uintptr_t *ip,
                       int nframes, const char **site)
{
    const char *nm[AGENT_MAX_FRAMES];
    uintptr_t at[AGENT_MAX_FRAMES];
    if (nframes > AGENT_MAX_FRAMES)
        nframes = AGENT_MAX_FRAMES;
    if (nframes < 0)
        nframes = 0;
    memcpy(nm, name, (size_t)nframes * sizeof *nm);
    memcpy(at, ip, (size_t)nframes * sizeof *at);
    return match_on(m, size, nm, at, &nframes, site);
}

/* Why rule i, which has no site=, selected nothing: no block was as large
 * as its min= (the largest looked at is named), none of those was whole
 * records, or its nth= is beyond the blocks it selects. */
static void unmatched_by_size(agent_rules *m, size_t i, char *line, size_t cap)
{
    const emm_tag_rule *r = &m->rs->rule[i];
    char text[256];
    emm_tag_rule_format(r, text, sizeof text);
    unsigned long long big = __atomic_load_n(&m->big_n[i], __ATOMIC_RELAXED),
                       fit = __atomic_load_n(&m->fit_n[i], __ATOMIC_RELAXED),
                       upto = __atomic_load_n(&m->big_size[i], __ATOMIC_RELAXED),
                       largest = __atomic_load_n(&m->largest, __ATOMIC_RELAXED);
    int w = snprintf(line, cap, "EMM_TAG rule %zu (%s) matched no allocation; ", i + 1, text);
    if (w < 0 || (size_t)w >= cap)
        return;
    line += w;
    cap -= (size_t)w;
    if (!big && largest)
        snprintf(line, cap,
                 "no block of %llu bytes or more was allocated (the largest block a rule "
                 "looked at was %llu bytes)",
                 (unsigned long long)r->min, largest);
    else if (!big)
        snprintf(line, cap, "no block of %llu bytes or more was allocated",
                 (unsigned long long)r->min);
    else if (!fit)
        snprintf(line, cap,
                 "the %llu block%s of %llu bytes or more (up to %llu bytes) %s not a whole "
                 "number of %u-byte records",
                 big, big == 1 ? "" : "s", (unsigned long long)r->min, upto,
                 big == 1 ? "is" : "are", r->stride);
    else
        snprintf(line, cap,
                 "%llu block%s of %llu bytes or more (up to %llu bytes) %s whole records, "
                 "fewer than its nth=%llu",
                 fit, fit == 1 ? "" : "s", (unsigned long long)r->min, upto,
                 fit == 1 ? "is" : "are", (unsigned long long)r->nth);
}

void agent_rules_report(agent_rules *m, void (*say)(void *ctx, const char *line), void *ctx)
{
    for (size_t i = 0; i < m->rs->n; i++) {
        if (__atomic_load_n(&m->selected[i], __ATOMIC_RELAXED))
            continue;
        /* A preset's other way to the same array, which tagged it. */
        const emm_tag_rule *r = &m->rs->rule[i];
        bool other = false;
        for (size_t j = 0; j < m->rs->n && r->alternative && !other; j++)
            other = j != i && m->rs->rule[j].kind == r->kind &&
                    m->rs->rule[j].shape == r->shape &&
                    __atomic_load_n(&m->selected[j], __ATOMIC_RELAXED);
        if (other)
            continue;
        char line[1024];
        uint64_t by = __atomic_load_n(&m->shadow_by[i], __ATOMIC_RELAXED);
        if (by) {
            char mine[256], theirs[256];
            emm_tag_rule_format(&m->rs->rule[i], mine, sizeof mine);
            emm_tag_rule_format(&m->rs->rule[by - 1], theirs, sizeof theirs);
            uint64_t n = __atomic_load_n(&m->shadow_n[i], __ATOMIC_RELAXED);
            snprintf(line, sizeof line,
                     "EMM_TAG rule %zu (%s) tagged nothing: the %llu block%s it selects (up to "
                     "%llu bytes) went to rule %llu (%s) first, which tagged %s as %s; narrow "
                     "rule %llu (site=, min=, nth=) or put rule %zu before it",
                     i + 1, mine, (unsigned long long)n, n == 1 ? "" : "s",
                     (unsigned long long)__atomic_load_n(&m->shadow_size[i], __ATOMIC_RELAXED),
                     (unsigned long long)by, theirs, n == 1 ? "it" : "them",
                     m->rs->rule[by - 1].kind == EMM_ARRAY_VERTICES ? "vertices" : "triangles",
                     (unsigned long long)by, i + 1);
        } else if (!m->rs->rule[i].site[0]) {
            unmatched_by_size(m, i, line, sizeof line);
        } else {
            pthread_mutex_lock(&m->lock);
            emm_tag_unmatched_message(&m->rs->rule[i], i, m->sites, m->nsites, line,
                                      sizeof line);
            pthread_mutex_unlock(&m->lock);
        }
        say(ctx, line);
    }
}
