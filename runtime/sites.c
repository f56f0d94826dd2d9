/* The candidate arrays of a program (emm/sites.h; `emm run --list-sites`).
 *
 * Blocks of the listing's size are grouped by call path. A block's bytes
 * are looked at once, when it is freed or moved and at exit; a site keeps
 * what its largest block looked like and a copy of its first bytes, and
 * the accesses the capture saw to its blocks (sites_shape.c makes the
 * records' shape of them). Two or three coordinate blocks of one type and
 * count are a mesh's x, y (and z), in allocation order.
 *
 * Every allocation of log_min bytes or more is recorded with its stack,
 * in order, with the block a realloc moved into it: the rule printed for
 * a site is the first candidate that, replayed through the rule matcher
 * (agent_rules_replay), tags the site's largest block and nothing of
 * another call path. */
#include "emm/sites.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "agent_rules.h"
#include "sites_shape.h"
#include "emm/config.h"
#include "parse.h"

#define MAX_SITES 256
#define MAX_STACK 12
/* The bytes of a site's largest block kept for typing its fields. */
#define SAMPLE_BYTES (256u * 1024)
/* The allocations recorded for the replay at most (24 bytes each). */
#define MAX_LOG (1u << 20)

struct site {
    uint64_t path;
    char name[EMM_TAG_SITE_MAX]; /* the innermost frame's own name, for the rule */
    char stack[1024];            /* qualified names, innermost first */
    uint64_t count, largest, live;
    shape g;         /* from the bytes */
    uint64_t looked; /* the size of the block g comes from */
    uint64_t used_bytes;      /* its bytes up to the last that is not zero */
    unsigned char *sample;    /* its first bytes */
    size_t sample_len;
    shape_acc acc;            /* the program's accesses to the site's blocks */
    shape sh;                 /* what is printed: from the accesses, else g */
    int order;       /* the site's place among the program's first allocations */
    int64_t target;  /* the log entry of its largest block (the first of that size) */
};

/* A call stack of the log: the frames as agent_rules_stack gave them. */
struct stack {
    uint64_t path;
    int n;
    const char *name[AGENT_MAX_FRAMES]; /* into names, or NULL */
    uintptr_t ip[AGENT_MAX_FRAMES];
    char *names;
};

/* An allocation of the run, in order: what a rule is matched against. */
struct entry {
    uint64_t size;
    int32_t stack;
    int32_t site; /* -1: below the listing's size */
    int64_t from; /* the entry realloc moved into this one, or -1 */
};

/* A live block of the log, by address (open addressing; p 0: empty, 1:
 * deleted). */
struct block {
    uintptr_t p;
    int64_t entry;
};

/* A live listed block, for the accesses (by address). */
struct span {
    uint64_t lo, hi;
    int64_t entry;
};

struct emm_sites {
    uint64_t min, log_min;
    struct span *spans; /* sorted; rebuilt when dirty */
    size_t nspans, cspans;
    bool dirty;
    struct site site[MAX_SITES];
    int nsites;
    struct stack *stacks;
    int32_t nstacks, cstacks;
    struct entry *log;
    int64_t nlog, clog;
    bool log_full; /* allocations went unrecorded: no rule can be checked */
    struct block *live;
    size_t clive, nlive, used; /* used: live + deleted slots */
};

emm_sites *emm_sites_new(uint64_t min_bytes, uint64_t log_min)
{
    emm_sites *t = calloc(1, sizeof *t);
    if (t) {
        t->min = min_bytes;
        t->log_min = log_min < min_bytes ? log_min : min_bytes;
    }
    return t;
}

void emm_sites_free(emm_sites *t)
{
    if (!t)
        return;
    for (int32_t i = 0; i < t->nstacks; i++)
        free(t->stacks[i].names);
    free(t->stacks);
    free(t->log);
    free(t->live);
    free(t->spans);
    for (int i = 0; i < t->nsites; i++)
        free(t->site[i].sample);
    free(t);
}

static size_t slot_of(uintptr_t p, size_t cap)
{
    return (size_t)((p >> 4) * 0x9E3779B97F4A7C15ull >> 20) & (cap - 1);
}

static bool live_put(emm_sites *t, uintptr_t p, int64_t entry)
{
    if (2 * (t->used + 1) > t->clive) {
        size_t cap = t->clive ? t->clive : 1024;
        while (4 * (t->nlive + 1) > cap)
            cap *= 2;
        struct block *grown = calloc(cap, sizeof *grown);
        if (!grown)
            return false;
        for (size_t i = 0; i < t->clive; i++)
            if (t->live[i].p > 1) {
                size_t s = slot_of(t->live[i].p, cap);
                while (grown[s].p)
                    s = (s + 1) & (cap - 1);
                grown[s] = t->live[i];
            }
        free(t->live);
        t->live = grown;
        t->clive = cap;
        t->used = t->nlive;
    }
    size_t s = slot_of(p, t->clive);
    while (t->live[s].p > 1 && t->live[s].p != p)
        s = (s + 1) & (t->clive - 1);
    if (t->live[s].p != p) {
        t->nlive++;
        t->used++;
    }
    t->live[s] = (struct block){p, entry};
    return true;
}

/* The slot of the live block at p, or SIZE_MAX. */
static size_t live_find(const emm_sites *t, uintptr_t p)
{
    if (!t->clive || p <= 1)
        return SIZE_MAX;
    for (size_t s = slot_of(p, t->clive), k = 0; k < t->clive; s = (s + 1) & (t->clive - 1), k++) {
        if (t->live[s].p == p)
            return s;
        if (t->live[s].p == 0)
            break;
    }
    return SIZE_MAX;
}

/* The stack of path, recorded once. */
static int32_t stack_of(emm_sites *t, uint64_t path, const char *const *names,
                        const uintptr_t *ips, size_t n)
{
    for (int32_t i = t->nstacks - 1; i >= 0; i--)
        if (t->stacks[i].path == path)
            return i;
    if (t->nstacks == t->cstacks) {
        int32_t cap = t->cstacks ? 2 * t->cstacks : 64;
        struct stack *grown = realloc(t->stacks, (size_t)cap * sizeof *grown);
        if (!grown)
            return -1;
        t->stacks = grown;
        t->cstacks = cap;
    }
    if (n > AGENT_MAX_FRAMES)
        n = AGENT_MAX_FRAMES;
    size_t bytes = 1;
    for (size_t k = 0; k < n; k++)
        if (names[k])
            bytes += strlen(names[k]) + 1 + strlen(names[k] + strlen(names[k]) + 1) + 1;
    struct stack *st = &t->stacks[t->nstacks];
    memset(st, 0, sizeof *st);
    if (!(st->names = malloc(bytes)))
        return -1;
    st->path = path;
    st->n = (int)n;
    char *w = st->names;
    for (size_t k = 0; k < n; k++) {
        st->ip[k] = ips[k];
        if (!names[k])
            continue;
        size_t l1 = strlen(names[k]) + 1, l2 = strlen(names[k] + l1) + 1;
        memcpy(w, names[k], l1 + l2);
        st->name[k] = w;
        w += l1 + l2;
    }
    return t->nstacks++;
}

int64_t emm_sites_add(emm_sites *t, uint64_t path, const char *const *names,
                      const uintptr_t *ips, size_t n, const void *block, uint64_t size,
                      int64_t from)
{
    if (size < t->log_min)
        return -1;
    int64_t e = -1;
    int32_t sk = t->log_full ? -1 : stack_of(t, path, names, ips, n);
    if (sk < 0 || (t->nlog == t->clog && t->clog >= MAX_LOG)) {
        t->log_full = true;
    } else {
        if (t->nlog == t->clog) {
            int64_t cap = t->clog ? 2 * t->clog : 1024;
            struct entry *grown = realloc(t->log, (size_t)cap * sizeof *grown);
            if (!grown) {
                t->log_full = true;
                goto listed;
            }
            t->log = grown;
            t->clog = cap;
        }
        e = t->nlog++;
        t->log[e] = (struct entry){size, sk, -1, from < e ? from : -1};
        if (!live_put(t, (uintptr_t)block, e))
            t->log_full = true;
    }
listed:
    if (size < t->min)
        return e;
    int i = 0;
    while (i < t->nsites && t->site[i].path != path)
        i++;
    if (i == t->nsites) {
        if (t->nsites == MAX_SITES)
            return e;
        struct site *s = &t->site[t->nsites++];
        memset(s, 0, sizeof *s);
        s->path = path;
        s->order = t->nsites - 1;
        s->target = -1;
        snprintf(s->name, sizeof s->name, "%s", n && names[0] ? names[0] : "?");
        size_t used = 0;
        for (size_t k = 0; k < n && k < MAX_STACK && used + 1 < sizeof s->stack; k++) {
            const char *q = names[k] ? names[k] + strlen(names[k]) + 1 : "?";
            int w = snprintf(s->stack + used, sizeof s->stack - used, "%s%s", k ? " < " : "", q);
            if (w < 0)
                break;
            used += (size_t)w;
        }
    }
    struct site *s = &t->site[i];
    s->count++;
    s->live++;
    if (size > s->largest) {
        s->largest = size;
        s->target = e;
    }
    if (e >= 0) {
        t->log[e].site = i;
        t->dirty = true;
    }
    return e;
}

static int by_lo(const void *a, const void *b)
{
    const struct span *x = a, *y = b;
    return x->lo < y->lo ? -1 : x->lo > y->lo;
}

/* The live listed blocks by address. */
static void refresh_spans(emm_sites *t)
{
    if (!t->dirty)
        return;
    t->nspans = 0;
    for (size_t i = 0; i < t->clive; i++) {
        const struct block *b = &t->live[i];
        if (b->p <= 1 || t->log[b->entry].site < 0)
            continue;
        if (t->nspans == t->cspans) {
            size_t cap = t->cspans ? 2 * t->cspans : 64;
            struct span *grown = realloc(t->spans, cap * sizeof *grown);
            if (!grown)
                break;
            t->spans = grown;
            t->cspans = cap;
        }
        t->spans[t->nspans++] = (struct span){b->p, b->p + t->log[b->entry].size, b->entry};
    }
    qsort(t->spans, t->nspans, sizeof *t->spans, by_lo);
    t->dirty = false;
}

size_t emm_sites_ranges(emm_sites *t, uint64_t *lo, uint64_t *hi, size_t cap)
{
    refresh_spans(t);
    for (size_t i = 0; i < t->nspans && i < cap && lo && hi; i++) {
        lo[i] = t->spans[i].lo;
        hi[i] = t->spans[i].hi;
    }
    return t->nspans;
}

int emm_sites_listed(const emm_sites *t, const void *block)
{
    size_t s = live_find(t, (uintptr_t)block);
    return s != SIZE_MAX && t->log[t->live[s].entry].site >= 0;
}

void emm_sites_access(emm_sites *t, const emm_raw_access *r, size_t n)
{
    refresh_spans(t);
    for (size_t i = 0; i < n && t->nspans; i++) {
        uint64_t a = r[i].addr;
        size_t lo = 0, hi = t->nspans;
        while (hi - lo > 1) {
            size_t mid = (lo + hi) / 2;
            if (t->spans[mid].lo <= a)
                lo = mid;
            else
                hi = mid;
        }
        const struct span *sp = &t->spans[lo];
        if (a < sp->lo || a >= sp->hi)
            continue;
        struct site *s = &t->site[t->log[sp->entry].site];
        shape_note(&s->acc, sp->entry, a - sp->lo, r[i].bytes_write & ~EMM_RAW_WRITE,
                   (r[i].bytes_write & EMM_RAW_WRITE) != 0, r[i].pc);
    }
}

/* Reads the block at p, entry e of the log, for its site's guess: the
 * largest block that reads as records wins, one that does not counts only
 * while none did. The winner's first bytes are kept for the accesses'
 * fields, typed at the end. */
static void look_at(emm_sites *t, const void *p, int64_t e)
{
    struct entry *k = &t->log[e];
    if (k->site < 0)
        return;
    struct site *s = &t->site[k->site];
    s->live--;
    if (k->size < s->looked && s->g.found)
        return;
    const unsigned char *b = p;
    uint64_t used = k->size;
    while (used > 0 && !b[used - 1])
        used--;
    shape g;
    bool found = shape_from_bytes(b, (size_t)k->size, k->size, used, &g);
    if (found ? k->size >= s->looked || !s->g.found : !s->g.found && k->size >= s->looked) {
        s->g = g;
        s->g.found = found;
        s->looked = k->size;
        s->used_bytes = used;
        size_t keep = k->size < SAMPLE_BYTES ? (size_t)k->size : SAMPLE_BYTES;
        unsigned char *copy = realloc(s->sample, keep);
        if (copy) {
            memcpy(copy, b, keep);
            s->sample = copy;
            s->sample_len = keep;
        }
    }
}

int64_t emm_sites_release(emm_sites *t, const void *block)
{
    size_t s = live_find(t, (uintptr_t)block);
    if (s == SIZE_MAX)
        return -1;
    int64_t e = t->live[s].entry;
    t->live[s].p = 1;
    t->dirty |= t->log[e].site >= 0;
    t->nlive--;
    look_at(t, block, e);
    return e;
}

static int by_size(const void *a, const void *b)
{
    const struct site *x = a, *y = b;
    return x->largest < y->largest ? 1 : x->largest > y->largest ? -1 : x->order - y->order;
}

/* The axis of site i's blocks when two or three axis-looking sites of the
 * same type and count look like one mesh's x, y (and z): in the order the
 * program first allocated them; 0 when that cannot be told. */
static char axis_of(const emm_sites *t, int i)
{
    const struct site *s = &t->site[i];
    int before = 0, same = 0;
    for (int j = 0; j < t->nsites; j++) {
        const struct site *o = &t->site[j];
        if (!o->sh.found || o->sh.kind != SHAPE_AXIS || o->sh.type != s->sh.type ||
            o->sh.records != s->sh.records)
            continue;
        same++;
        before += o->order < s->order;
    }
    return same >= 2 && same <= 3 ? "xyz"[before] : 0;
}

/* ---- rules that work: the run's allocations replayed -------------------- */

/* Replays the log through the rules rs (one matcher, agent_rules, as a
 * run under EMM_TAG uses): a block a rule selects is tagged, and a
 * realloc that moves it is the same array, not matched again. Rule i
 * works when it tags entry target[i] (selecting it, or a block realloc
 * moved into it) and no block of another call path than path[i]. With
 * `rank` (one rule, its nth= beyond any count) *rank gets the nth= that
 * selects target[0]'s first block, 0 when none. owner: nlog ints. */
static bool replay(const emm_sites *t, const emm_tag_rules *rs, const int64_t *target,
                   const uint64_t *path, int32_t *owner, uint64_t *rank)
{
    agent_rules *m;
    emm_error err;
    if (t->log_full || agent_rules_replayer(rs, &m, &err) != EMM_OK)
        return false;
    uint64_t *ranks = rank ? calloc((size_t)t->nlog + 1, sizeof *ranks) : NULL;
    if (rank && !ranks) {
        agent_rules_free(m);
        return false;
    }
    for (int64_t e = 0; e < t->nlog; e++) {
        const struct entry *k = &t->log[e];
        owner[e] = 0;
        if (k->from >= 0 && owner[k->from]) { /* the tagged block, moved */
            owner[e] = -abs(owner[k->from]);
            continue;
        }
        const struct stack *st = &t->stacks[k->stack];
        const char *site;
        uint64_t before = rank ? agent_rules_counted(m, 0) : 0;
        int r = agent_rules_replay(m, (size_t)k->size, st->name, st->ip, st->n, &site);
        if (r >= 0)
            owner[e] = r + 1;
        if (rank && agent_rules_counted(m, 0) != before)
            ranks[e] = agent_rules_counted(m, 0);
    }
    agent_rules_free(m);
    bool ok = true;
    for (size_t i = 0; i < rs->n && ok; i++) {
        int64_t g = target[i];
        ok = g >= 0 && g < t->nlog && abs(owner[g]) == (int)i + 1;
        for (int64_t e = 0; e < t->nlog && ok; e++)
            ok = owner[e] != (int)i + 1 || t->stacks[t->log[e].stack].path == path[i];
    }
    if (rank) {
        *rank = 0;
        for (int64_t e = target[0]; e >= 0 && e < t->nlog; e = t->log[e].from)
            if (ranks[e])
                *rank = ranks[e];
        free(ranks);
    }
    return ok;
}

/* Whether the rules `text` (split by ';') work as replay says, each rule
 * k for target[k] on path[k]. */
static bool works(const emm_sites *t, const char *text, const int64_t *target,
                  const uint64_t *path, int32_t *owner)
{
    emm_tag_rule rule[3];
    emm_tag_rules rs = {0, rule};
    emm_error err;
    char buf[3 * 512];
    snprintf(buf, sizeof buf, "%s", text);
    for (char *save = NULL, *one = strtok_r(buf, ";", &save); one;
         one = strtok_r(NULL, ";", &save)) {
        if (rs.n == 3 || emm_tag_rule_parse(one, &rule[rs.n], &err) != EMM_OK)
            return false;
        rs.n++;
    }
    return rs.n && replay(t, &rs, target, path, owner, NULL);
}

/* A rule KIND:SELECTORS,BODY that tags site s's largest block and nothing
 * of another call path, into out; false when none is found. Tried in
 * turn, the first that works wins: a frame of the stack, innermost first
 * (a function's name does not depend on the input), then with nth=, then
 * with min= (the block's size: it does), then with both, then no site=. */
static bool suggest(const emm_sites *t, const struct site *s, const char *kind,
                    const char *body, int32_t *owner, char *out, size_t cap)
{
    if (s->target < 0 || t->log_full)
        return false;
    const struct stack *st = &t->stacks[t->log[s->target].stack];
    int64_t target[1] = {s->target};
    uint64_t path[1] = {s->path};
    char min[48];
    snprintf(min, sizeof min, "min=%llu,", (unsigned long long)t->log[s->target].size);
    for (int variant = 0; variant < 4; variant++) {
        bool with_min = variant >= 2, with_nth = variant & 1;
        int nf = st->n < 12 ? st->n : 12;
        for (int f = 0; f <= nf; f++) {
            if (f == nf && variant < 2)
                continue; /* no site= at all: with min=, last */
            const char *name = f < nf ? st->name[f] : NULL;
            if (f < nf && !name)
                continue;
            bool again = false; /* a frame named before (recursion) */
            for (int g = 0; name && g < f && !again; g++)
                again = st->name[g] && strcmp(st->name[g], name) == 0;
            if (again)
                continue;
            char sel[EMM_TAG_SITE_MAX + 64];
            snprintf(sel, sizeof sel, "%s%s%s", name ? "site=" : "", name ? name : "",
                     name ? "," : "");
            if (with_min)
                snprintf(sel + strlen(sel), sizeof sel - strlen(sel), "%s", min);
            char text[512];
            if (!with_nth) {
                snprintf(text, sizeof text, "%s:%s%s", kind, sel, body);
                if (works(t, text, target, path, owner)) {
                    snprintf(out, cap, "%s", text);
                    return true;
                }
                continue;
            }
            /* The rank the target's block has among those the rule selects. */
            emm_tag_rule r;
            emm_error err;
            uint64_t rank = 0;
            snprintf(text, sizeof text, "%s:%s%s", kind, sel, body);
            if (emm_tag_rule_parse(text, &r, &err) != EMM_OK)
                continue;
            r.nth = UINT64_MAX;
            emm_tag_rules one = {1, &r};
            replay(t, &one, target, path, owner, &rank);
            if (!rank)
                continue;
            snprintf(text, sizeof text, "%s:%snth=%llu,%s", kind, sel, (unsigned long long)rank,
                     body);
            if (works(t, text, target, path, owner)) {
                snprintf(out, cap, "%s", text);
                return true;
            }
        }
    }
    return false;
}

/* The axis rules for a site whose one call made two or three axis blocks:
 * x, y (and z), one block each in the order they were allocated, if they
 * work together. */
static bool loop_rules(const emm_sites *t, const struct site *s, const char *type,
                       int32_t *owner, char *buf, size_t cap)
{
    int64_t target[3];
    uint64_t path[3] = {s->path, s->path, s->path};
    int n = 0;
    for (int64_t e = 0; e < t->nlog && n < 3; e++)
        if (t->log[e].site >= 0 && t->site[t->log[e].site].path == s->path)
            target[n++] = e;
    size_t used = 0;
    buf[0] = 0;
    for (int k = 0; k < n && used < cap; k++) {
        int w = snprintf(buf + used, cap - used, "%svertices:site=%s,%c=0:%s,nth=1", k ? ";" : "",
                         s->name, "xyz"[k], type);
        if (w < 0)
            return false;
        used += (size_t)w;
    }
    return n >= 2 && used < cap && works(t, buf, target, path, owner);
}

/* An axis rule is used with the rules of the mesh's other axis blocks (a
 * rule set needs x and y): site i's part of the set "vertices:site=NAME,
 * A=0:T" for each such block, when they work together, into out. */
static bool axis_set_rule(const emm_sites *t, int i, int32_t *owner, char *out, size_t cap)
{
    const struct site *s = &t->site[i];
    int member[3], n = 0;
    for (int k = 0; k < 3; k++) /* x, y, z: in the order they were allocated */
        for (int j = 0; j < t->nsites; j++) {
            const struct site *o = &t->site[j];
            if (o->sh.found && o->sh.kind == SHAPE_AXIS && o->sh.type == s->sh.type &&
                o->sh.records == s->sh.records && axis_of(t, j) == "xyz"[k] && o->target >= 0)
                member[n++] = j;
        }
    if (n < 2)
        return false;
    char text[3 * 256], mine[256] = "";
    int64_t target[3];
    uint64_t path[3];
    size_t used = 0;
    for (int k = 0; k < n; k++) {
        const struct site *o = &t->site[member[k]];
        char one[256];
        snprintf(one, sizeof one, "vertices:site=%s,%c=0:%s", o->name, "xyz"[k],
                 o->sh.type == EMM_F64 ? "f64" : "f32");
        if (member[k] == i)
            snprintf(mine, sizeof mine, "%s", one);
        used += (size_t)snprintf(text + used, sizeof text - used, "%s%s", k ? ";" : "", one);
        target[k] = o->target;
        path[k] = o->path;
    }
    if (!mine[0] || used >= sizeof text || !works(t, text, target, path, owner))
        return false;
    snprintf(out, cap, "%s", mine);
    return true;
}

static int by_entry(const void *a, const void *b)
{
    const struct block *x = a, *y = b;
    return x->entry < y->entry ? -1 : x->entry > y->entry;
}

/* The site's rule line: a rule that works, or why there is none. */
static void rule_line(FILE *out, const emm_sites *t, const struct site *s, const char *kind,
                      const char *body, int32_t *owner, const char *note)
{
    char rule[512];
    if (suggest(t, s, kind, body, owner, rule, sizeof rule)) {
        fprintf(out, "emm:      rule: %s\n", rule);
        if (note[0])
            fprintf(out, "emm:      note: %s\n", note);
    }
    else
        fprintf(out, "emm:      rule: none works: %s\n",
                t->log_full ? "the run made more allocations than were recorded"
                            : "no site=, nth= or min= selects this block alone and nothing "
                              "of another call path (tag it with emm_tag_* calls)");
}

/* The preset rules (of emm_tag_preset(preset)) that may tag a site's
 * blocks, a bit per rule: its site= names the stack's innermost frame
 * (^NAME) or any of its frames, and its largest block is whole records.
 * The stack is --list-sites' "A < B < C", qualified names innermost
 * first. */
static uint64_t preset_rules(const emm_tag_rules *rs, const char *stack, uint64_t largest)
{
    uint64_t bits = 0;
    for (size_t i = 0; i < rs->n && i < 64; i++) {
        const emm_tag_rule *r = &rs->rule[i];
        bool innermost = r->site[0] == '^';
        const char *site = r->site + innermost, *p = stack;
        if (!emm_tag_rule_fits(r, largest))
            continue;
        while (*p) {
            const char *end = strstr(p, " < ");
            size_t len = end ? (size_t)(end - p) : strlen(p);
            char q[512];
            snprintf(q, sizeof q, "%.*s", (int)(len < sizeof q ? len : sizeof q - 1), p);
            const char *name = q, *sep;
            while ((sep = strstr(name, "::")))
                name = sep + 2;
            if (emm_tag_site_matches(site, name, q)) {
                bits |= 1ull << i;
                break;
            }
            if (innermost || !end)
                break;
            p = end + 3;
        }
    }
    return bits;
}

/* What OpenMesh array a site is, from the preset rules that may tag it and
 * its records: "" when none. Half-edge-like records are edges_; the
 * 4-byte records of a function that allocates both vertices_ and faces_
 * (ArrayKernel::reserve, in the order vertices_, edges_, faces_) are
 * either. */
static const char *openmesh_array(const emm_tag_rules *rs, uint64_t bits, bool halfedge_like,
                                  bool coordinates)
{
    unsigned shapes = 0;
    for (size_t i = 0; i < rs->n && i < 64; i++)
        if (bits >> i & 1)
            shapes |= 1u << rs->rule[i].shape;
    if (halfedge_like)
        return shapes & 1u << EMM_TAG_HALFEDGES ? "edges_ (its half-edges)" : "";
    shapes &= ~(1u << EMM_TAG_HALFEDGES);
    if (coordinates)
        return shapes & 1u << EMM_TAG_RECORDS ? "points" : "";
    shapes &= ~(1u << EMM_TAG_RECORDS);
    if (shapes == (1u << EMM_TAG_FACES | 1u << EMM_TAG_VCONN))
        return "vertices_ or faces_ (one half-edge index a record)";
    return shapes & 1u << EMM_TAG_FACES   ? "faces_"
           : shapes & 1u << EMM_TAG_VCONN ? "vertices_"
                                          : "";
}

void emm_sites_print(emm_sites *t, const char *program, FILE *out)
{
    char b1[32], b2[32], b3[32];
    uint64_t live_at_exit[MAX_SITES] = {0};
    /* The blocks still live, read in the order they were allocated. */
    struct block *left = malloc((t->nlive ? t->nlive : 1) * sizeof *left);
    size_t nleft = 0;
    for (size_t i = 0; left && i < t->clive; i++)
        if (t->live[i].p > 1)
            left[nleft++] = t->live[i];
    qsort(left, nleft, sizeof *left, by_entry);
    for (size_t i = 0; i < nleft; i++) {
        if (t->log[left[i].entry].site >= 0)
            live_at_exit[t->log[left[i].entry].site]++;
        look_at(t, (const void *)left[i].p, left[i].entry);
    }
    free(left);
    for (int i = 0; i < t->nsites; i++)
        t->site[i].live = live_at_exit[i];
    /* The log names sites by index: sorted, each entry follows its site. */
    int order[MAX_SITES];
    for (int i = 0; i < t->nsites; i++)
        order[i] = i;
    qsort(t->site, (size_t)t->nsites, sizeof *t->site, by_size);
    for (int i = 0; i < t->nsites; i++)
        order[t->site[i].order] = i;
    for (int64_t e = 0; e < t->nlog; e++)
        if (t->log[e].site >= 0)
            t->log[e].site = order[t->log[e].site];
    for (int i = 0; i < t->nsites; i++) {
        struct site *s = &t->site[i];
        if (!s->sample || !shape_from_accesses(&s->acc, s->sample, s->sample_len, s->looked,
                                               s->used_bytes, &s->sh))
            s->sh = s->g;
    }
    int32_t *owner = malloc(((size_t)t->nlog + 1) * sizeof *owner);
    if (!owner)
        t->log_full = true;
    /* A program of OpenMesh's: its ArrayKernel's arrays are the preset's. */
    emm_tag_rules openmesh = {0, NULL};
    emm_error perr;
    bool om = false;
    for (int i = 0; i < t->nsites && !om; i++)
        om = strstr(t->site[i].stack, "OpenMesh::") != NULL;
    if (om && emm_tag_rules_parse("openmesh", &openmesh, &perr) != EMM_OK)
        om = false;
    /* A rule follows the first call path it selects: of the sites of one
     * OpenMesh array, the one allocated first. */
    const char *preset_of[MAX_SITES];
    for (int i = 0; i < t->nsites; i++) {
        const struct site *s = &t->site[i];
        preset_of[i] = om ? openmesh_array(&openmesh,
                                           preset_rules(&openmesh, s->stack, s->largest),
                                           s->sh.found && s->sh.kind == SHAPE_HALFEDGE,
                                           s->sh.found && s->sh.kind == SHAPE_VERTICES)
                          : "";
        for (int j = 0; j < i && preset_of[i][0]; j++)
            if (strcmp(preset_of[j], preset_of[i]) == 0) {
                if (t->site[j].order > t->site[i].order)
                    preset_of[j] = "";
                else
                    preset_of[i] = "";
            }
    }
    fprintf(out, "emm: %s: %d candidate array site%s (blocks of %s bytes or more, by call path, "
                 "largest first)%s\n",
            program, t->nsites, t->nsites == 1 ? "" : "s", emm_grouped(t->min, b1),
            t->nsites ? ":" : "");
    for (int i = 0; i < t->nsites; i++) {
        const struct site *s = &t->site[i];
        fprintf(out, "emm: %3d. %s: %s block%s, the largest %s bytes, %s live at exit\n", i + 1,
                s->name, emm_grouped(s->count, b1), s->count == 1 ? "" : "s",
                emm_grouped(s->largest, b2), emm_grouped(s->live, b3));
        fprintf(out, "emm:      stack: %s\n", s->stack);
        if (preset_of[i][0])
            fprintf(out, "emm:      preset: OpenMesh's %s, which --tag openmesh tags\n",
                    preset_of[i]);
        char what[1024], body[64];
        const char *kind;
        if (!s->sh.found) {
            fprintf(out, "emm:      records: not three coordinates or indices in a row, no "
                         "accesses seen (a record of several fields: take stride and offsets "
                         "from the program's type)\n");
            fprintf(out, "emm:      rule: none: the records are not known\n");
            continue;
        }
        shape_describe(&s->sh, what, sizeof what);
        fprintf(out, "emm:      records: %s\n", what);
        char axis = s->sh.kind == SHAPE_AXIS ? axis_of(t, i) : 0;
        char rules[3 * (EMM_TAG_SITE_MAX + 48)];
        const char *type = s->sh.type == EMM_F64 ? "f64" : "f32";
        if (s->sh.kind == SHAPE_AXIS && s->count >= 2 && s->count <= 3 && !axis &&
            loop_rules(t, s, type, owner, rules, sizeof rules))
            /* One call made them all (a loop over the axes): the rules
             * take its blocks in turn, one each (nth=1). */
            fprintf(out, "emm:      rule: %s\n", rules);
        else if (axis && axis_set_rule(t, i, owner, rules, sizeof rules))
            /* Works with the rules of the mesh's other axis blocks, as
             * it must be used (a rule set needs an x and a y rule). */
            fprintf(out, "emm:      rule: %s\n", rules);
        else if (shape_rule(&s->sh, axis, &kind, body, sizeof body))
            rule_line(out, t, s, kind, body, owner,
                      s->sh.kind == SHAPE_AXIS && !axis
                          ? "which axis the block holds is not known: x= is a placeholder for "
                            "x=, y= or z="
                          : "");
        else
            fprintf(out, "emm:      rule: none: %s\n",
                    s->sh.kind == SHAPE_HALFEDGE
                        ? "half-edge-like records are no vertices or triangles array: a "
                          "halfedges: rule with the program's field offsets tags them "
                          "(to=, next=, face=; see emm run --help)"
                        : "the fields fit no vertices:, triangles: or soup: rule");
    }
    if (om)
        fprintf(out, "emm: %s uses OpenMesh: --tag openmesh (EMM_TAG=openmesh) tags its "
                     "points and its half-edge connectivity (vertices_, edges_, faces_), "
                     "whichever way its reader allocated them\n",
                program);
    emm_tag_rules_free(&openmesh);
    free(owner);
    fflush(out);
}
