/* The candidate arrays of a program (emm/sites.h; `emm run --list-sites`).
 *
 * Blocks are grouped by call path. A block's records are looked at once,
 * when it is freed or moved and at exit: the table tries three indices in
 * 12 bytes (i32/u32), then three coordinates in 12 bytes (f32) or 24 bytes
 * (f64), then one coordinate per entry (a block of a structure of arrays,
 * f32 or f64), over its records up to the last one that is not all zero
 * (the rest is spare capacity). Integers read as floats are subnormal,
 * floats read as indices are huge: the tests tell them apart. A site keeps
 * what its largest block looked like; two or three coordinate blocks of
 * one type and count are a mesh's x, y (and z), in allocation order. */
#include "emm/sites.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "emm/config.h"
#include "parse.h"

#define MAX_SITES 256
#define MAX_BLOCKS 4096
#define MAX_STACK 12
/* Records read per block at most. */
#define SAMPLE 65536u

struct guess {
    emm_array_kind kind;
    bool found;
    bool axis; /* one coordinate per entry: a block of a structure of arrays */
    unsigned stride;
    emm_scalar type;
    uint64_t records, in_use;
};

struct site {
    uint64_t path;
    char name[EMM_TAG_SITE_MAX]; /* the innermost frame's own name, for the rule */
    char stack[1024];            /* qualified names, innermost first */
    uint64_t count, largest, live;
    struct guess g;
    uint64_t looked; /* the size of the block g comes from */
    int order;       /* the site's place among the program's first allocations */
};

struct block {
    const void *p;
    uint64_t size;
    int site;
};

struct emm_sites {
    uint64_t min;
    struct site site[MAX_SITES];
    int nsites;
    struct block block[MAX_BLOCKS];
    int nblocks;
};

emm_sites *emm_sites_new(uint64_t min_bytes)
{
    emm_sites *t = calloc(1, sizeof *t);
    if (t)
        t->min = min_bytes;
    return t;
}

void emm_sites_free(emm_sites *t)
{
    free(t);
}

void emm_sites_add(emm_sites *t, uint64_t path, const char *const *names, size_t n,
                   const void *block, uint64_t size)
{
    if (size < t->min)
        return;
    int i = 0;
    while (i < t->nsites && t->site[i].path != path)
        i++;
    if (i == t->nsites) {
        if (t->nsites == MAX_SITES)
            return;
        struct site *s = &t->site[t->nsites++];
        memset(s, 0, sizeof *s);
        s->path = path;
        s->order = t->nsites - 1;
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
    if (size > s->largest)
        s->largest = size;
    if (t->nblocks < MAX_BLOCKS)
        t->block[t->nblocks++] = (struct block){block, size, i};
}

static bool plausible(double x, emm_scalar type)
{
    double tiny = type == EMM_F32 ? 1.1754943508222875e-38 : 2.2250738585072014e-308;
    return isfinite(x) && (x == 0 || fabs(x) >= tiny) && fabs(x) < 1e7;
}

/* Whether the block reads as records of `stride` bytes with `scalars` (3,
 * or 1 for one coordinate per entry) scalars of `type` at their start,
 * over its records in use. */
static bool reads_as_n(const unsigned char *p, uint64_t size, unsigned stride, emm_scalar type,
                       int scalars, struct guess *g)
{
    if (size % stride)
        return false;
    uint64_t n = size / stride, used = 0;
    for (uint64_t i = n; i > 0 && !used; i--)
        for (unsigned b = 0; b < stride; b++)
            if (p[(i - 1) * stride + b]) {
                used = i;
                break;
            }
    if (used < 2)
        return false;
    uint64_t look = used < SAMPLE ? used : SAMPLE, good = 0;
    for (uint64_t i = 0; i < look; i++) {
        const unsigned char *r = p + i * stride;
        bool ok = true;
        if (type == EMM_U32) {
            uint32_t v[3];
            memcpy(v, r, sizeof v);
            ok = v[0] < (1u << 26) && v[1] < (1u << 26) && v[2] < (1u << 26) &&
                 (v[0] != v[1] || v[1] != v[2]);
        } else {
            for (int c = 0; c < scalars && ok; c++) {
                double x;
                if (type == EMM_F32) {
                    float f;
                    memcpy(&f, r + 4 * c, sizeof f);
                    x = f;
                } else {
                    memcpy(&x, r + 8 * c, sizeof x);
                }
                ok = plausible(x, type);
            }
        }
        good += ok;
    }
    if (good * 100 < look * 98)
        return false;
    *g = (struct guess){type == EMM_U32 ? EMM_ARRAY_TRIANGLES : EMM_ARRAY_VERTICES, true,
                        scalars == 1, stride, type, n, used};
    return true;
}

static bool reads_as(const unsigned char *p, uint64_t size, unsigned stride, emm_scalar type,
                     struct guess *g)
{
    return reads_as_n(p, size, stride, type, 3, g);
}

/* One coordinate per entry (a structure of arrays), f32 or f64. Small
 * coordinates read either way: f64 data read as f32 shows its low words
 * (zero for round values), f32 data read as f64 pairs of floats. f32 wins
 * unless nearly every other f32 entry is exactly zero. */
static bool reads_as_axis(const unsigned char *p, uint64_t size, struct guess *g)
{
    struct guess g32, g64;
    bool f32 = reads_as_n(p, size, 4, EMM_F32, 1, &g32);
    bool f64 = reads_as_n(p, size, 8, EMM_F64, 1, &g64);
    if (f32 && f64) {
        uint64_t look = g64.in_use < SAMPLE ? g64.in_use : SAMPLE, zero = 0;
        for (uint64_t i = 0; i < look; i++) {
            uint32_t low;
            memcpy(&low, p + 8 * i, sizeof low);
            zero += low == 0;
        }
        f32 = zero * 10 < look * 9;
    }
    if (f32)
        *g = g32;
    else if (f64)
        *g = g64;
    return f32 || f64;
}

static void look_at(emm_sites *t, int b)
{
    struct block *k = &t->block[b];
    struct site *s = &t->site[k->site];
    /* The largest block that reads as records wins; one that does not
     * counts only while none did. */
    if (k->size >= s->looked || !s->g.found) {
        const unsigned char *p = k->p;
        struct guess g = {0};
        bool found = reads_as(p, k->size, 12, EMM_U32, &g) ||
                     reads_as(p, k->size, 12, EMM_F32, &g) || reads_as(p, k->size, 24, EMM_F64, &g) ||
                     reads_as_axis(p, k->size, &g);
        if (found ? k->size >= s->looked || !s->g.found : !s->g.found && k->size >= s->looked) {
            s->g = g;
            s->looked = k->size;
        }
    }
    s->live--;
    t->block[b] = t->block[--t->nblocks];
}

void emm_sites_release(emm_sites *t, const void *block)
{
    for (int b = 0; b < t->nblocks; b++)
        if (t->block[b].p == block) {
            look_at(t, b);
            return;
        }
}

static int by_size(const void *a, const void *b)
{
    const struct site *x = a, *y = b;
    return x->largest < y->largest ? 1 : x->largest > y->largest ? -1 : 0;
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
        if (!o->g.found || !o->g.axis || o->g.type != s->g.type ||
            o->g.records != s->g.records)
            continue;
        same++;
        before += o->order < s->order;
    }
    return same >= 2 && same <= 3 ? "xyz"[before] : 0;
}

/* The axis rules for a site whose one call made two or three axis blocks:
 * x, y (and z), one block each in the order they were allocated. */
static const char *loop_rules(const struct site *s, const char *type, char *buf, size_t cap)
{
    size_t used = 0;
    buf[0] = 0;
    for (uint64_t k = 0; k < s->count && k < 3 && used < cap; k++) {
        int w = snprintf(buf + used, cap - used, "%svertices:site=%s,%c=0:%s,nth=1", k ? ";" : "",
                         s->name, "xyz"[k], type);
        if (w < 0)
            break;
        used += (size_t)w;
    }
    return buf;
}

void emm_sites_print(emm_sites *t, const char *program, FILE *out)
{
    char b1[32], b2[32], b3[32];
    uint64_t live_at_exit[MAX_SITES] = {0};
    for (int b = 0; b < t->nblocks; b++)
        live_at_exit[t->block[b].site]++;
    while (t->nblocks > 0)
        look_at(t, t->nblocks - 1);
    for (int i = 0; i < t->nsites; i++)
        t->site[i].live = live_at_exit[i];
    qsort(t->site, (size_t)t->nsites, sizeof *t->site, by_size);
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
        if (s->g.found && s->g.axis) {
            const char *type = s->g.type == EMM_F32 ? "f32" : "f64";
            char rules[3 * (EMM_TAG_SITE_MAX + 48)];
            fprintf(out, "emm:      records: one %s coordinate per %u bytes (a structure of "
                         "arrays: a block per axis), %s in use of %s\n",
                    type, s->g.stride, emm_grouped(s->g.in_use, b1), emm_grouped(s->g.records, b2));
            char axis = axis_of(t, i);
            if (s->count >= 2 && s->count <= 3 && !axis)
                /* One call made them all (a loop over the axes): the rules
                 * take its blocks in turn, one each (nth=1). */
                fprintf(out, "emm:      rule: %s\n", loop_rules(s, type, rules, sizeof rules));
            else if (axis)
                fprintf(out, "emm:      rule: vertices:site=%s,%c=0:%s\n", s->name, axis, type);
            else
                fprintf(out, "emm:      rule: vertices:site=%s,x=0:%s (or y=, z=: the block's "
                             "axis)\n",
                        s->name, type);
        } else if (s->g.found) {
            bool v = s->g.kind == EMM_ARRAY_VERTICES;
            const char *type = s->g.type == EMM_F32 ? "f32" : s->g.type == EMM_F64 ? "f64" : "u32";
            fprintf(out, "emm:      records: 3 x %s in %u bytes (%s), %s in use of %s\n", type,
                    s->g.stride, v ? "coordinates" : "vertex indices",
                    emm_grouped(s->g.in_use, b1), emm_grouped(s->g.records, b2));
            fprintf(out, "emm:      rule: %s:site=%s,stride=%u,%s=0:%s\n",
                    v ? "vertices" : "triangles", s->name, s->g.stride, v ? "xyz" : "vidx", type);
        } else {
            fprintf(out, "emm:      records: not three floats or three indices in a row (a record "
                         "of several fields: take stride and offsets from the program's type)\n");
            fprintf(out, "emm:      rule: vertices:site=%s,stride=BYTES,xyz=OFFSET:f32|f64, or "
                         "triangles:site=%s,stride=BYTES,vidx=OFFSET:i32|u32|u16|i64\n",
                    s->name, s->name);
        }
    }
    fflush(out);
}
