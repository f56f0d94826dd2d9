/* EMM_TAG rules (DESIGN.md "The shim", Tagging): which allocations are mesh
 * arrays, found by the name of a function on the allocation's call stack, by
 * size or by rank, and where the coordinates or vertex indices sit in each
 * record.
 *
 *   EMM_TAG='vertices:site=read_mesh,stride=80,xyz=8:f64;triangles:site=read_mesh,stride=28,vidx=4:i32'
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
#include <stdarg.h>
#include <stdio.h>
#include <pthread.h>
#include <string.h>

#include "parse.h"
#include "shim.h"

#define MAX_RULES 16
#define SITE_MAX 128
#define MAX_FRAMES 32
/* Without min=, a rule looks at blocks of at least this many bytes (and at
 * least one record): the fast path skips the unwinding for the small
 * blocks that make up most allocations. */
#define DEFAULT_MIN 4096u

struct rule {
    emm_array_kind kind;
    char site[SITE_MAX];    /* "" when there is no site= */
    uint64_t min;           /* effective minimum size */
    uint64_t nth;           /* 0: every block; else only the nth selected */
    uint64_t seen;          /* atomic: blocks the other selectors selected */
    uintptr_t bound;        /* atomic: the call site in `site` this rule follows, 0: none yet */
    size_t stride, offset;
    emm_scalar type;
};

struct shim_rules {
    struct rule r[MAX_RULES];
    size_t n;
};

const char shim_rules_grammar[] =
    "KIND:key=value,...[;...], KIND vertices|triangles, keys site=FUNCTION min=BYTES nth=N "
    "stride=BYTES xyz=OFFSET:f32|f64 vidx=OFFSET:i32|u32|i64";

static struct shim_rules rules_storage;

static bool fail(char *msg, size_t cap, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static bool fail(char *msg, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, cap, fmt, ap);
    va_end(ap);
    return false;
}

static bool parse_field(const char *v, size_t len, bool vertices, size_t *offset, emm_scalar *type)
{
    char buf[64];
    if (len >= sizeof buf)
        return false;
    memcpy(buf, v, len);
    buf[len] = '\0';
    char *colon = strchr(buf, ':');
    if (!colon)
        return false;
    *colon = '\0';
    uint64_t off;
    if (!emm_parse_u64(buf, &off) || off > UINT32_MAX)
        return false;
    const char *t = colon + 1;
    if (vertices && strcmp(t, "f32") == 0)
        *type = EMM_F32;
    else if (vertices && strcmp(t, "f64") == 0)
        *type = EMM_F64;
    else if (!vertices && strcmp(t, "i32") == 0)
        *type = EMM_I32;
    else if (!vertices && strcmp(t, "u32") == 0)
        *type = EMM_U32;
    else if (!vertices && strcmp(t, "i64") == 0)
        *type = EMM_I64;
    else
        return false;
    *offset = (size_t)off;
    return true;
}

static size_t scalar_size(emm_scalar t)
{
    return t == EMM_F64 || t == EMM_I64 ? 8 : 4;
}

/* One rule, text[0..len). */
static bool parse_rule(const char *text, size_t len, struct rule *r, char *msg, size_t cap)
{
    memset(r, 0, sizeof *r);
    const char *colon = memchr(text, ':', len);
    if (!colon)
        return fail(msg, cap, "rule '%.*s' has no KIND: (vertices: or triangles:)", (int)(len), text);
    size_t klen = (size_t)(colon - text);
    if (klen == 8 && memcmp(text, "vertices", 8) == 0)
        r->kind = EMM_ARRAY_VERTICES;
    else if (klen == 9 && memcmp(text, "triangles", 9) == 0)
        r->kind = EMM_ARRAY_TRIANGLES;
    else
        return fail(msg, cap, "unknown kind '%.*s' (expected vertices or triangles)", (int)(klen), text);
    bool vertices = r->kind == EMM_ARRAY_VERTICES;
    bool have_min = false, have_field = false;
    const char *p = colon + 1, *end = text + len;
    while (p < end) {
        const char *comma = memchr(p, ',', (size_t)(end - p));
        const char *e = comma ? comma : end;
        const char *eq = memchr(p, '=', (size_t)(e - p));
        if (!eq || eq == p)
            return fail(msg, cap, "'%.*s' is not key=value", (int)((size_t)(e - p)), p);
        size_t kl = (size_t)(eq - p), vl = (size_t)(e - eq - 1);
        const char *v = eq + 1;
        char num[32];
        uint64_t x = 0;
        bool numeric = kl != 4 || (memcmp(p, "site", 4) != 0 && memcmp(p, "vidx", 4) != 0);
        numeric = numeric && !(kl == 3 && memcmp(p, "xyz", 3) == 0);
        if (numeric) {
            if (vl == 0 || vl >= sizeof num)
                return fail(msg, cap, "'%.*s' needs a number", (int)((size_t)(e - p)), p);
            memcpy(num, v, vl);
            num[vl] = '\0';
        }
        if (kl == 4 && memcmp(p, "site", 4) == 0) {
            if (vl == 0 || vl >= SITE_MAX)
                return fail(msg, cap, "'%.*s' needs a function name", (int)((size_t)(e - p)), p);
            memcpy(r->site, v, vl);
            r->site[vl] = '\0';
        } else if (kl == 3 && memcmp(p, "min", 3) == 0) {
            if (!emm_parse_size(num, &x))
                return fail(msg, cap, "'%.*s' is not a size in bytes (K/M/G allowed)", (int)((size_t)(e - p)), p);
            r->min = x;
            have_min = true;
        } else if (kl == 3 && memcmp(p, "nth", 3) == 0) {
            if (!emm_parse_u64(num, &x) || x == 0)
                return fail(msg, cap, "'%.*s' is not a rank from 1", (int)((size_t)(e - p)), p);
            r->nth = x;
        } else if (kl == 6 && memcmp(p, "stride", 6) == 0) {
            if (!emm_parse_size(num, &x) || x == 0 || x > UINT32_MAX)
                return fail(msg, cap, "'%.*s' is not a record size in bytes", (int)((size_t)(e - p)), p);
            r->stride = (size_t)x;
        } else if (kl == 3 && memcmp(p, "xyz", 3) == 0 && vertices) {
            if (!parse_field(v, vl, true, &r->offset, &r->type))
                return fail(msg, cap, "'%.*s': expected xyz=OFFSET:f32|f64", (int)((size_t)(e - p)), p);
            have_field = true;
        } else if (kl == 4 && memcmp(p, "vidx", 4) == 0 && !vertices) {
            if (!parse_field(v, vl, false, &r->offset, &r->type))
                return fail(msg, cap, "'%.*s': expected vidx=OFFSET:i32|u32|i64", (int)((size_t)(e - p)), p);
            have_field = true;
        } else {
            return fail(msg, cap, "unknown key in '%.*s'", (int)((size_t)(e - p)), p);
        }
        p = comma ? comma + 1 : end;
    }
    if (r->stride == 0)
        return fail(msg, cap, "rule '%.*s' needs stride=BYTES", (int)(len), text);
    if (!have_field)
        return fail(msg, cap, vertices ? "rule '%.*s' needs xyz=OFFSET:f32|f64"
                                       : "rule '%.*s' needs vidx=OFFSET:i32|u32|i64", (int)(len), text);
    if (r->offset + 3 * scalar_size(r->type) > r->stride)
        return fail(msg, cap, "rule '%.*s': the three fields do not fit in stride bytes", (int)(len), text);
    if (!have_min)
        r->min = r->stride > DEFAULT_MIN ? r->stride : DEFAULT_MIN;
    if (r->min < r->stride)
        r->min = r->stride;
    return true;
}

static bool parse_into(struct shim_rules *rs, const char *text, char *msg, size_t cap)
{
    memset(rs, 0, sizeof *rs);
    const char *p = text;
    while (*p) {
        const char *semi = strchr(p, ';');
        size_t len = semi ? (size_t)(semi - p) : strlen(p);
        if (len > 0) {
            if (rs->n == MAX_RULES) {
                snprintf(msg, cap, "more than %d rules", MAX_RULES);
                return false;
            }
            if (!parse_rule(p, len, &rs->r[rs->n], msg, cap))
                return false;
            rs->n++;
        }
        p += len + (semi ? 1 : 0);
    }
    if (rs->n == 0) {
        snprintf(msg, cap, "expected %s", shim_rules_grammar);
        return false;
    }
    return true;
}

struct shim_rules *shim_rules_parse(const char *text, char *msg, size_t cap)
{
    return parse_into(&rules_storage, text, msg, cap) ? &rules_storage : NULL;
}

size_t shim_rules_min(const struct shim_rules *rs)
{
    size_t m = SIZE_MAX;
    for (size_t i = 0; i < rs->n; i++)
        if (rs->r[i].min < m)
            m = (size_t)rs->r[i].min;
    return m;
}

bool shim_rules_need_stack(const struct shim_rules *rs)
{
    for (size_t i = 0; i < rs->n; i++)
        if (rs->r[i].site[0])
            return true;
    return false;
}

/* --- call-site names --------------------------------------------------- */

typedef int (*unw_getcontext_fn)(unw_context_t *);
typedef int (*unw_init_local_fn)(unw_cursor_t *, unw_context_t *);
typedef int (*unw_step_fn)(unw_cursor_t *);
typedef int (*unw_get_reg_fn)(unw_cursor_t *, int, unw_word_t *);
typedef int (*unw_get_proc_name_fn)(unw_cursor_t *, char *, size_t, unw_word_t *);

static struct {
    unw_getcontext_fn getcontext;
    unw_init_local_fn init_local;
    unw_step_fn step;
    unw_get_reg_fn get_reg;
    unw_get_proc_name_fn get_proc_name;
} unw;

bool shim_rules_unwind_init(char *msg, size_t cap)
{
#if defined(__x86_64__)
    void *h = dlopen("libunwind.so.8", RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        snprintf(msg, cap, "site= needs libunwind.so.8: %s", dlerror());
        return false;
    }
    unw.getcontext = (unw_getcontext_fn)dlsym(h, "_Ux86_64_getcontext");
    unw.init_local = (unw_init_local_fn)dlsym(h, "_ULx86_64_init_local");
    unw.step = (unw_step_fn)dlsym(h, "_ULx86_64_step");
    unw.get_reg = (unw_get_reg_fn)dlsym(h, "_ULx86_64_get_reg");
    unw.get_proc_name = (unw_get_proc_name_fn)dlsym(h, "_ULx86_64_get_proc_name");
    if (!unw.getcontext || !unw.init_local || !unw.step || !unw.get_reg || !unw.get_proc_name) {
        snprintf(msg, cap, "site= needs libunwind.so.8, which lacks the local unwinder");
        return false;
    }
    return true;
#else
    snprintf(msg, cap, "site= is supported on x86-64 only");
    return false;
#endif
}

/* The name cache: return address -> normalised name in a pool. */
#define CACHE_SLOTS 4096
#define POOL_BYTES (128 * 1024)
static struct {
    pthread_mutex_t lock;
    uintptr_t ip[CACHE_SLOTS];
    uint32_t name[CACHE_SLOTS];   /* offset in pool; UINT32_MAX: no name */
    bool skip[CACHE_SLOTS];       /* an allocator or standard-library frame */
    char pool[POOL_BYTES];
    size_t used;
} cache = {.lock = PTHREAD_MUTEX_INITIALIZER};

/* Reads one <length><identifier> of the Itanium mangling at *p. */
static bool mangled_id(const char **p, const char **id, size_t *len)
{
    size_t n = 0;
    if (**p < '0' || **p > '9')
        return false;
    while (**p >= '0' && **p <= '9')
        n = n * 10 + (size_t)(*(*p)++ - '0');
    if (n == 0 || strnlen(*p, n) < n)
        return false;
    *id = *p;
    *len = n;
    *p += n;
    return true;
}

/* A function's name as a rule's site= spells it: compiler clone suffixes
 * (.constprop.0, .isra.0, .part.0, .cold) dropped, and a C++ name reduced
 * to its unqualified identifier (_ZN4mesh4loadEv -> load). */
static void normalise(const char *raw, char *out, size_t cap)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", raw);
    char *dot = strchr(buf, '.');
    if (dot && dot != buf)
        *dot = '\0';
    const char *p = buf, *id = NULL;
    size_t len = 0;
    if (p[0] == '_' && p[1] == 'Z') {
        p += 2;
        if (*p == 'L')
            p++;
        if (*p == 'N') {
            p++;
            while (*p == 'K' || *p == 'V' || *p == 'r')
                p++;
            if (p[0] == 'S' && p[1] == 't')
                p += 2;
            const char *cid;
            size_t clen;
            while (mangled_id(&p, &cid, &clen)) {
                id = cid;
                len = clen;
            }
        } else {
            mangled_id(&p, &id, &len);
        }
    }
    if (id && len < cap) {
        memcpy(out, id, len);
        out[len] = '\0';
    } else {
        /* Too long for any site= (SITE_MAX): cut, it will match nothing. */
        size_t n = strnlen(buf, cap - 1);
        memcpy(out, buf, n);
        out[n] = '\0';
    }
}

/* Frames that are not the program's allocation site: the C library, the C++
 * runtime, this shim, the loader, and the standard library's templates
 * instantiated in the program (std::vector growth, operator new). */
static bool library_frame(uintptr_t ip, const char *raw)
{
    static const char *const prefixes[] = {"_ZNSt", "_ZNKSt", "_ZSt", "_Znw", "_Zna",
                                           "_ZN9__gnu_cxx", "_ZNK9__gnu_cxx", "__libc_"};
    if (raw)
        for (size_t i = 0; i < sizeof prefixes / sizeof *prefixes; i++)
            if (strncmp(raw, prefixes[i], strlen(prefixes[i])) == 0)
                return true;
    Dl_info info;
    if (!dladdr((void *)ip, &info) || !info.dli_fname)
        return false;
    const char *base = strrchr(info.dli_fname, '/');
    base = base ? base + 1 : info.dli_fname;
    static const char *const libs[] = {"libc.so", "libstdc++.so", "libgcc_s.so", "ld-linux",
                                       "libemmshim.so", "libunwind.so"};
    for (size_t i = 0; i < sizeof libs / sizeof *libs; i++)
        if (strncmp(base, libs[i], strlen(libs[i])) == 0)
            return true;
    return false;
}

/* The normalised name of the function at the cursor's frame, or NULL;
 * *skip says whether the frame belongs to an allocator or a library. */
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
    char raw[1024], norm[SITE_MAX];
    unw_word_t off;
    bool named = unw.get_proc_name(cur, raw, sizeof raw, &off) == 0;
    if (named)
        normalise(raw, norm, sizeof norm);
    *skip = library_frame(ip, named ? raw : NULL);

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
        if (cache.ip[s] == 0 || cache.ip[s] == ip) {
            if (cache.ip[s] == 0 && (at != UINT32_MAX || !named)) {
                cache.ip[s] = ip;
                cache.name[s] = at;
                cache.skip[s] = *skip;
            }
            break;
        }
    }
    pthread_mutex_unlock(&cache.lock);
    /* A full pool: compare against a name that lives on in no cache. */
    if (named && !result) {
        static __thread char spill[SITE_MAX] SHIM_TLS;
        memcpy(spill, norm, sizeof spill);
        result = spill;
    }
    return result;
}

/* Marks in `on_stack` (one flag per rule) the rules whose site= names the
 * allocation's call site: the first frame, going up, that is not an
 * allocator or standard-library frame (so allocations made deep inside a
 * library the site calls are not the site's). `where` gets the return
 * address in that frame, which tells the site's allocation calls apart. */
static void stack_sites(const struct shim_rules *rs, bool *on_stack, uintptr_t *where)
{
    unw_context_t ctx;
    unw_cursor_t cur;
    if (unw.getcontext(&ctx) != 0 || unw.init_local(&cur, &ctx) != 0)
        return;
    for (int depth = 0; depth < MAX_FRAMES && unw.step(&cur) > 0; depth++) {
        unw_word_t ip;
        if (unw.get_reg(&cur, UNW_REG_IP, &ip) != 0 || ip == 0)
            break;
        bool skip = false;
        const char *name = frame_name(&cur, (uintptr_t)ip, &skip);
        if (skip)
            continue;
        for (size_t i = 0; name && i < rs->n; i++)
            if (rs->r[i].site[0] && strcmp(rs->r[i].site, name) == 0) {
                on_stack[i] = true;
                where[i] = (uintptr_t)ip;
            }
        return;
    }
}

bool shim_rules_match(struct shim_rules *rs, size_t size, struct shim_match *out)
{
    bool on_stack[MAX_RULES] = {false};
    uintptr_t where[MAX_RULES] = {0};
    bool unwound = false;
    for (size_t i = 0; i < rs->n; i++) {
        struct rule *r = &rs->r[i];
        /* A block that is not a whole number of records is not the array. */
        if (size < r->min || size % r->stride != 0)
            continue;
        if (r->site[0]) {
            if (!unwound) {
                stack_sites(rs, on_stack, where);
                unwound = true;
            }
            if (!on_stack[i])
                continue;
            /* A rule follows the first call in its site function that it
             * selects (a growing vector reallocates from that same call);
             * the site's other allocations are left to the later rules. */
            uintptr_t expect = 0;
            if (!__atomic_compare_exchange_n(&r->bound, &expect, where[i], false,
                                             __ATOMIC_RELAXED, __ATOMIC_RELAXED)
                && expect != where[i])
                continue;
        }
        if (r->nth && __atomic_add_fetch(&r->seen, 1, __ATOMIC_RELAXED) != r->nth)
            continue;
        out->kind = r->kind;
        out->stride = r->stride;
        out->offset = r->offset;
        out->type = r->type;
        out->rule = (int)i + 1;
        return true;
    }
    return false;
}

/* The env table's EMM_TAG check: the same parser, into scratch storage. */
bool shim_rules_check(const char *value, char *why, size_t cap)
{
    static struct shim_rules scratch;
    return parse_into(&scratch, value, why, cap);
}
