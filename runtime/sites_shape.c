/* The shape of a candidate array's records (sites_shape.h).
 *
 * From the accesses: every instruction of the program's own (not the C or
 * C++ library's: a memcpy steps by its vector width) that touches a
 * site's blocks is followed — how many bytes it reads or writes and the
 * greatest common divisor of the distances between its successive
 * offsets in one block. An instruction that reads one field of record
 * after record, in order or by index, steps by multiples of the record's
 * size: the stride is the step most accesses take, and each instruction
 * whose step is a multiple of it touches one field, at its offset modulo
 * the stride. Valgrind runs the program's threads one at a time, so the
 * same run gives the same accesses and the same shape.
 *
 * From the bytes: three indices in 12 bytes (u32), three coordinates in 12
 * (f32) or 24 bytes (f64), a binary STL facet (50 or 52 bytes: normal and
 * nine corner coordinates), one coordinate per entry, over the records up
 * to the last one that is not all zero. A 12-byte reading gives way to a
 * stride that is not a multiple of 12 when the bytes repeat far more
 * regularly at it (16-byte neighbour records hold three small integers and
 * three bytes: read 12 bytes at a time they look like index triples).
 *
 * Either way each field is typed from the bytes: integers read as floats
 * are subnormal, floats read as integers are huge, text read as floats is
 * tiny; an index field holding -1 is a handle (a neighbour, a half-edge's
 * twin), not a vertex index. */
#include "sites_shape.h"

#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/config.h"
#include "parse.h"

/* Records read per field at most. */
#define LOOK 65536u

static uint64_t gcd(uint64_t a, uint64_t b)
{
    while (b) {
        uint64_t t = a % b;
        a = b;
        b = t;
    }
    return a;
}

void shape_note(shape_acc *a, int64_t block, uint64_t off, uint32_t size, bool write, uint64_t pc)
{
    a->n++;
    shape_pc *q = NULL;
    for (int i = 0; i < a->npc && !q; i++)
        if (a->pc[i].pc == pc)
            q = &a->pc[i];
    if (!q) {
        if (a->npc == SHAPE_PCS) {
            a->other++;
            return;
        }
        q = &a->pc[a->npc++];
        *q = (shape_pc){pc, 0, 0, off, off, block, size, false, false};
    }
    q->n++;
    if (write)
        q->write = true;
    else
        q->read = true;
    if (q->last_block == block && off != q->last_off)
        q->g = gcd(q->g, off > q->last_off ? off - q->last_off : q->last_off - off);
    q->last_off = off;
    q->last_block = block;
}

/* ---- typing a field from the bytes ------------------------------------- */

/* A coordinate: finite, not subnormal, neither huge nor tiny (text read as
 * f32 is 1e-10 to 1e-4). */
static bool coordinate(double x, emm_scalar type)
{
    double tiny = type == EMM_F32 ? 1.1754943508222875e-38 : 2.2250738585072014e-308;
    return isfinite(x) && (x == 0 || (fabs(x) >= tiny && fabs(x) >= 1e-6)) && fabs(x) < 1e7;
}

/* What field (off, size) of records of `stride` bytes holds over the
 * records 0..n of the sample p (len bytes): 'f', 'i', 'h', '0' or '?'. */
static char type_field(const unsigned char *p, size_t len, unsigned stride, uint64_t n, unsigned off,
                       unsigned size, emm_scalar *type)
{
    if (stride == 0 || off + size > stride)
        return '?';
    uint64_t fit = len >= off + size ? (len - off - size) / stride + 1 : 0;
    if (n > fit)
        n = fit;
    if (n > LOOK)
        n = LOOK;
    if (n < 2)
        return '?';
    uint64_t zero = 0, idx = 0, neg = 0, flt = 0, ptr = 0;
    uint32_t his[4];
    int nhi = 0; /* the distinct high words of addresses; 5: more */
    for (uint64_t r = 0; r < n; r++) {
        const unsigned char *q = p + r * stride + off;
        if (size == 4) {
            uint32_t v;
            float f;
            memcpy(&v, q, 4);
            memcpy(&f, q, 4);
            zero += v == 0;
            idx += v != 0 && v < (1u << 26);
            neg += v == UINT32_MAX;
            flt += v != 0 && coordinate(f, EMM_F32);
        } else if (size == 8) {
            uint64_t v;
            double d;
            memcpy(&v, q, 8);
            memcpy(&d, q, 8);
            zero += v == 0;
            /* An address: in the upper part of the address space (the heap
             * and the libraries, in one or a few regions: few high words;
             * two indices side by side have as many as indices), or
             * under Valgrind's low heap 8-aligned. */
            uint32_t hi = (uint32_t)(v >> 32);
            if (v >= (1ull << 40) && v < (1ull << 48)) {
                int k = 0;
                while (k < nhi && k < 4 && his[k] != hi)
                    k++;
                if (k == nhi && nhi < 5) {
                    if (nhi < 4)
                        his[nhi] = hi;
                    nhi++;
                }
                ptr++;
            } else {
                ptr += v >= (1u << 20) && v < (1ull << 32) && v % 8 == 0;
            }
            idx += v != 0 && v < (1ull << 40);
            neg += v == UINT64_MAX;
            flt += v != 0 && coordinate(d, EMM_F64);
        } else {
            bool z = true;
            for (unsigned b = 0; b < size; b++)
                z = z && q[b] == 0;
            zero += z;
        }
    }
    uint64_t nz = n - zero;
    if (nz == 0)
        return '0';
    if (size != 4 && size != 8)
        return '?';
    /* Addresses: three in four of the values that are not zero (a
     * program's pool keeps counts or flags in some records: tetgen's
     * tetrahedra, one in nine). Where the system put the block decides
     * how its addresses' low words read, so an address field read as two
     * words would read differently from run to run. */
    if (size == 8 && ptr * 4 >= nz * 3 && nhi <= 4)
        return 'p';
    if ((idx + neg) * 100 >= nz * 98 && idx) {
        *type = size == 4 ? EMM_U32 : EMM_I64;
        return neg ? 'h' : 'i';
    }
    if (flt * 100 >= nz * 98) {
        *type = size == 4 ? EMM_F32 : EMM_F64;
        return 'f';
    }
    return '?';
}

/* Types the fields, splits an 8-byte field that is no f64 into two 4-byte
 * ones, and drops fields that overlap an earlier one. */
static void type_fields(shape *s, const unsigned char *p, size_t len)
{
    shape_field out[SHAPE_FIELDS];
    int n = 0;
    for (int i = 0; i < s->nf && n < SHAPE_FIELDS; i++) {
        shape_field f = s->f[i];
        if (n && f.off < out[n - 1].off + out[n - 1].size)
            continue;
        f.cls = type_field(p, len, s->stride, s->in_use, f.off, f.size, &f.type);
        if (f.size == 8 && f.cls != 'f' && f.cls != '0' && f.cls != 'i' && f.cls != 'p' &&
            n + 2 <= SHAPE_FIELDS) {
            for (unsigned h = 0; h < 2; h++) {
                shape_field g = f;
                g.off = f.off + 4 * h;
                g.size = 4;
                g.cls = type_field(p, len, s->stride, s->in_use, g.off, 4, &g.type);
                out[n++] = g;
            }
            continue;
        }
        out[n++] = f;
    }
    memcpy(s->f, out, (size_t)n * sizeof *out);
    s->nf = n;
}

static size_t scalar_bytes(emm_scalar t)
{
    return t == EMM_F64 || t == EMM_I64 ? 8 : t == EMM_U16 ? 2 : 4;
}

/* The longest run of fields of class c and one type, each right after the
 * one before: its first field and length. A coordinate run takes zero
 * fields of its size (a planar mesh's z). */
static int run_of(const shape *s, char c, int *start)
{
    int best = 0;
    for (int i = 0; i < s->nf; i++) {
        if (s->f[i].cls != c)
            continue;
        int k = 1;
        while (i + k < s->nf &&
               ((s->f[i + k].cls == c && s->f[i + k].type == s->f[i].type) ||
                (c == 'f' && s->f[i + k].cls == '0' && s->f[i + k].size == s->f[i].size)) &&
               s->f[i + k].off == s->f[i + k - 1].off + s->f[i + k - 1].size)
            k++;
        if (k > best) {
            best = k;
            *start = i;
        }
    }
    return best;
}

/* Which rule the fields fit. */
static void decide(shape *s)
{
    int fs = 0, is = 0, handles = 0, index = 0, other = 0;
    int nfl = run_of(s, 'f', &fs), nix = run_of(s, 'i', &is);
    for (int i = 0; i < s->nf; i++) {
        index += s->f[i].cls == 'i' || s->f[i].cls == 'h';
        handles += s->f[i].cls == 'h';
        other += s->f[i].cls == '?';
    }
    s->kind = SHAPE_NONE;
    if (nfl >= 9 && s->stride > 9 * scalar_bytes(s->f[fs].type) - 1) {
        /* A facet: its corners are the last nine (a normal may lead). */
        s->kind = SHAPE_SOUP;
        s->at = s->f[fs + nfl - 9].off;
        s->type = s->f[fs].type;
    } else if (nfl == 1 && s->nf == 1 && s->stride == scalar_bytes(s->f[fs].type)) {
        s->kind = SHAPE_AXIS;
        s->at = 0;
        s->type = s->f[fs].type;
    } else if (nfl >= 3) {
        s->kind = SHAPE_VERTICES;
        s->at = s->f[fs].off;
        s->type = s->f[fs].type;
    } else if (index >= 4) {
        s->kind = SHAPE_HALFEDGE;
    } else if (nix >= 3 && !handles && !other && s->f[is].type == EMM_U32) {
        s->kind = SHAPE_TRIANGLES;
        s->at = s->f[is].off;
        s->type = EMM_U32;
    }
}

/* Fields every 4 bytes of a stride (8 where an f64 fits), for the bytes. */
static void all_columns(shape *s)
{
    s->nf = 0;
    for (unsigned c = 0; c < s->stride && s->nf < SHAPE_FIELDS; c += 4) {
        unsigned size = s->stride - c < 4 ? s->stride - c : 4;
        s->f[s->nf++] = (shape_field){c, size, '?', EMM_U32, false, false};
    }
}

/* How irregular the bytes are at a stride: the mean over its byte columns
 * of log2(distinct values) over n records. */
static double irregularity(const unsigned char *p, unsigned stride, uint64_t n)
{
    double sum = 0;
    for (unsigned c = 0; c < stride; c++) {
        bool seen[256] = {false};
        unsigned d = 0;
        for (uint64_t r = 0; r < n; r++) {
            unsigned char b = p[r * stride + c];
            d += !seen[b];
            seen[b] = true;
        }
        sum += log2((double)d);
    }
    return sum / stride;
}

/* A stride that is no multiple or divisor of 12 at which the bytes repeat
 * far more regularly than at 12, or 0. */
static unsigned other_period(const unsigned char *p, size_t len, uint64_t size, uint64_t used)
{
    static const unsigned cand[] = {16, 20, 28, 32, 40, 44, 52, 56, 64};
    uint64_t n = (used < len ? used : len) / 64;
    if (n > 1024)
        n = 1024;
    if (n < 16)
        return 0;
    double base = irregularity(p, 12, n), best = base;
    unsigned pick = 0;
    for (size_t i = 0; i < sizeof cand / sizeof *cand; i++) {
        if (size % cand[i])
            continue;
        double x = irregularity(p, cand[i], n);
        if (x < best - 0.05 && x < base * 0.85) {
            best = x;
            pick = cand[i];
        }
    }
    return pick;
}

static void set_counts(shape *s, uint64_t size, uint64_t used)
{
    s->records = size / s->stride;
    s->in_use = (used + s->stride - 1) / s->stride;
    if (s->in_use > s->records)
        s->in_use = s->records;
}

/* Fields at every column of `stride`, typed, and the rule they fit. */
static bool by_columns(const unsigned char *p, size_t len, uint64_t size, uint64_t used,
                       unsigned stride, shape *out)
{
    shape s = {0};
    s.stride = stride;
    set_counts(&s, size, used);
    if (s.in_use < 2)
        return false;
    all_columns(&s);
    type_fields(&s, p, len);
    /* Two 4-byte halves that read as an f64 or an address are one. */
    for (int i = 0; i + 1 < s.nf; i++) {
        emm_scalar t;
        char c8 = s.f[i].off % 8 == 0 && s.f[i].size == 4 && s.f[i + 1].size == 4
                      ? type_field(p, len, stride, s.in_use, s.f[i].off, 8, &t)
                      : 0;
        if ((c8 == 'f' && s.f[i].cls != 'f') || c8 == 'p') {
            s.f[i].size = 8;
            s.f[i].cls = c8;
            s.f[i].type = c8 == 'f' ? EMM_F64 : EMM_I64;
            memmove(&s.f[i + 1], &s.f[i + 2], (size_t)(s.nf - i - 2) * sizeof *s.f);
            s.nf--;
        }
    }
    decide(&s);
    s.found = true;
    *out = s;
    return true;
}

/* Records of `stride` bytes with `k` scalars of type t in a row at 0 over
 * the records in use (98% of them). */
static bool reads_as(const unsigned char *p, size_t len, uint64_t size, uint64_t used,
                     unsigned stride, emm_scalar t, int k, shape *out)
{
    if (size % stride)
        return false;
    shape s = {0};
    s.stride = stride;
    set_counts(&s, size, used);
    if (s.in_use < 2)
        return false;
    unsigned sz = (unsigned)scalar_bytes(t);
    for (int c = 0; c < k; c++) {
        emm_scalar got = t;
        char cls = type_field(p, len, stride, s.in_use, (unsigned)c * sz, sz, &got);
        bool ok = t == EMM_U32 ? cls == 'i' : cls == 'f' || cls == '0';
        if (!ok || (cls != '0' && got != t))
            return false;
        s.f[s.nf++] = (shape_field){(unsigned)c * sz, sz, cls == '0' ? 'f' : cls, t, false, false};
    }
    if (t != EMM_U32 && run_of(&s, 'f', &(int){0}) < k)
        return false;
    s.found = true;
    s.kind = k == 1 ? SHAPE_AXIS : t == EMM_U32 ? SHAPE_TRIANGLES : SHAPE_VERTICES;
    s.type = t;
    *out = s;
    return true;
}

/* A binary STL facet: 12 f32 (normal, three corners) and 2 or 4 bytes that
 * do not change (the attribute count, padding). */
static bool reads_as_facets(const unsigned char *p, size_t len, uint64_t size, uint64_t used,
                            shape *out)
{
    static const unsigned strides[] = {50, 52};
    for (size_t i = 0; i < 2; i++) {
        unsigned st = strides[i];
        shape s;
        if (size % st || !reads_as(p, len, size, used, st, EMM_F32, 12, &s))
            continue;
        uint64_t n = s.in_use < LOOK ? s.in_use : LOOK, same = 0;
        if ((n - 1) * st + st > len)
            n = len / st;
        for (uint64_t r = 0; r < n; r++)
            same += memcmp(p + r * st + 48, p + 48, st - 48) == 0;
        if (n < 2 || same * 100 < n * 98)
            continue;
        s.f[s.nf++] = (shape_field){48, st - 48, '?', EMM_U16, false, false};
        s.kind = SHAPE_SOUP;
        s.at = 12;
        *out = s;
        return true;
    }
    return false;
}

bool shape_from_bytes(const unsigned char *p, size_t len, uint64_t size, uint64_t used,
                      shape *out)
{
    memset(out, 0, sizeof *out);
    if (reads_as_facets(p, len, size, used, out))
        return true;
    unsigned other = size % 12 == 0 ? other_period(p, len, size, used) : 0;
    if (other)
        return by_columns(p, len, size, used, other, out);
    if (reads_as(p, len, size, used, 12, EMM_U32, 3, out) ||
        reads_as(p, len, size, used, 12, EMM_F32, 3, out) ||
        reads_as(p, len, size, used, 24, EMM_F64, 3, out))
        return true;
    /* One coordinate per entry: f32 unless nearly every other f32 entry
     * is exactly zero (f64 of round values). */
    shape a32, a64;
    bool f32 = reads_as(p, len, size, used, 4, EMM_F32, 1, &a32);
    bool f64 = reads_as(p, len, size, used, 8, EMM_F64, 1, &a64);
    if (f32 && f64) {
        uint64_t look = a64.in_use < LOOK ? a64.in_use : LOOK, zero = 0;
        if (look * 8 > len)
            look = len / 8;
        for (uint64_t i = 0; i < look; i++) {
            uint32_t low;
            memcpy(&low, p + 8 * i, sizeof low);
            zero += low == 0;
        }
        f32 = zero * 10 < look * 9;
    }
    if (f32 || f64) {
        *out = f32 ? a32 : a64;
        return true;
    }
    /* Records of several fields: the stride at which the bytes repeat
     * most regularly (the smallest of those within 3% of the best). */
    static const unsigned cand[] = {8, 12, 16, 20, 24, 28, 32, 40, 48, 56, 64};
    uint64_t n = (used < len ? used : len) / 64;
    if (n > 1024)
        n = 1024;
    if (n < 16)
        return false;
    double score[sizeof cand / sizeof *cand], best = irregularity(p, 4, n);
    double base = best;
    for (size_t i = 0; i < sizeof cand / sizeof *cand; i++) {
        score[i] = size % cand[i] ? 1e9 : irregularity(p, cand[i], n);
        if (score[i] < best)
            best = score[i];
    }
    if (best > base * 0.85)
        return false;
    for (size_t i = 0; i < sizeof cand / sizeof *cand; i++)
        if (score[i] <= best * 1.03 + 0.01)
            return by_columns(p, len, size, used, cand[i], out);
    return false;
}

/* ---- from the accesses --------------------------------------------------- */

/* Whether the instruction at pc is the C or C++ library's (a memcpy). */
static bool library_pc(uint64_t pc)
{
    Dl_info info;
    return dladdr((void *)(uintptr_t)pc, &info) && info.dli_fname &&
           emm_tag_site_is_library(NULL, info.dli_fname);
}

static void add_field(shape *s, unsigned off, unsigned size, bool read, bool write)
{
    for (int i = 0; i < s->nf; i++)
        if (s->f[i].off == off && s->f[i].size == size) {
            s->f[i].read |= read;
            s->f[i].write |= write;
            return;
        }
    if (s->nf == SHAPE_FIELDS)
        return;
    int i = s->nf++;
    while (i > 0 && (s->f[i - 1].off > off || (s->f[i - 1].off == off && s->f[i - 1].size < size))) {
        s->f[i] = s->f[i - 1];
        i--;
    }
    s->f[i] = (shape_field){off, size, '?', EMM_U32, read, write};
}

bool shape_from_accesses(const shape_acc *a, const unsigned char *p, size_t len, uint64_t size,
                         uint64_t used, shape *out)
{
    memset(out, 0, sizeof *out);
    bool own[SHAPE_PCS];
    uint64_t total = 0;
    int instructions = 0;
    for (int i = 0; i < a->npc; i++) {
        own[i] = a->pc[i].size > 0 && !library_pc(a->pc[i].pc);
        if (own[i]) {
            total += a->pc[i].n;
            instructions++;
        }
    }
    if (total < 16)
        return false;
    /* The step most accesses take; a multiple of it that a quarter as many
     * take is the record (a loop over a flat array steps by a scalar). */
    uint64_t stride = 0, weight = 0;
    for (int i = 0; i < a->npc; i++) {
        if (!own[i] || !a->pc[i].g || a->pc[i].g > 4096)
            continue;
        uint64_t w = 0;
        for (int j = 0; j < a->npc; j++)
            w += own[j] && a->pc[j].g == a->pc[i].g ? a->pc[j].n : 0;
        if (w > weight || (w == weight && a->pc[i].g < stride)) {
            weight = w;
            stride = a->pc[i].g;
        }
    }
    if (!stride)
        return false;
    uint64_t base = stride;
    for (int i = 0; i < a->npc; i++) {
        uint64_t g = a->pc[i].g;
        if (!own[i] || g <= stride || g % base || g / base > 16)
            continue;
        uint64_t w = 0;
        for (int j = 0; j < a->npc; j++)
            w += own[j] && a->pc[j].g == g ? a->pc[j].n : 0;
        if (4 * w >= weight && g > stride)
            stride = g;
    }
    shape s = {0};
    s.from_accesses = true;
    s.accesses = total;
    s.instructions = instructions;
    s.stride = (unsigned)stride;
    set_counts(&s, size, used);
    for (int i = 0; i < a->npc; i++) {
        const shape_pc *q = &a->pc[i];
        if (!own[i] || (q->g && q->g % stride))
            continue;
        unsigned off = (unsigned)(q->first_off % stride), sz = q->size;
        if (off + sz > stride)
            sz = (unsigned)stride - off;
        if (sz > 8) /* a vector load: its scalars */
            for (unsigned k = 0; k + 4 <= sz; k += 4)
                add_field(&s, off + k, 4, q->read, q->write);
        else
            add_field(&s, off, sz, q->read, q->write);
    }
    type_fields(&s, p, len);
    decide(&s);
    /* Instructions that step a scalar at a time (a loop over a record's
     * fields, over a flat array) say only that the record is a multiple of
     * it: where the bytes repeat at a multiple, that is the record (a
     * triangle's three vertex indices, a 16-byte neighbour record). */
    shape b;
    bool bytes = shape_from_bytes(p, len, size, used, &b);
    if (bytes && b.stride > stride && b.stride % stride == 0 && s.kind != SHAPE_SOUP &&
        s.kind != SHAPE_VERTICES && s.kind != SHAPE_TRIANGLES && b.kind != SHAPE_AXIS) {
        b.from_accesses = true;
        b.accesses = total;
        b.instructions = instructions;
        *out = b;
        return true;
    }
    if ((s.kind == SHAPE_NONE || s.kind == SHAPE_AXIS) && (stride == 4 || stride == 8) && bytes &&
        b.stride == 3 * stride && (b.kind == SHAPE_TRIANGLES || b.kind == SHAPE_VERTICES)) {
        bool ok = true;
        for (int i = 0; i < s.nf; i++)
            ok = ok && s.f[i].cls == b.f[0].cls;
        if (ok) {
            b.from_accesses = true;
            b.accesses = total;
            b.instructions = instructions;
            for (int i = 0; i < b.nf; i++)
                b.f[i].read = s.nf && s.f[0].read, b.f[i].write = s.nf && s.f[0].write;
            s = b;
        }
    }
    s.found = true;
    *out = s;
    return true;
}

/* ---- words ---------------------------------------------------------------- */

static const char *class_words(char c)
{
    return c == 'f'   ? "coordinate-like"
           : c == 'i' ? "index-like"
           : c == 'h' ? "index-or--1 (handle-like)"
           : c == '0' ? "always zero"
           : c == 'p' ? "an address (a pointer)"
                      : "not a coordinate or an index";
}

void shape_describe(const shape *s, char *out, size_t cap)
{
    char b1[32], b2[32], b3[32], src[160];
    if (s->from_accesses)
        snprintf(src, sizeof src, "from %s accesses by %d instruction%s", emm_grouped(s->accesses, b3),
                 s->instructions, s->instructions == 1 ? "" : "s");
    else
        snprintf(src, sizeof src, "a guess from the bytes: no accesses seen");
    const char *use = emm_grouped(s->in_use, b1), *all = emm_grouped(s->records, b2);
    bool plain = s->nf == (s->kind == SHAPE_AXIS ? 1 : 3) && s->stride == s->nf * scalar_bytes(s->type);
    if (plain && s->kind == SHAPE_AXIS) {
        snprintf(out, cap,
                 "one %s coordinate per %u bytes (a structure of arrays: a block per axis), %s "
                 "in use of %s (%s)",
                 emm_scalar_name(s->type), s->stride, use, all, src);
        return;
    }
    if (plain && (s->kind == SHAPE_VERTICES || s->kind == SHAPE_TRIANGLES)) {
        snprintf(out, cap, "3 x %s in %u bytes (%s), %s in use of %s (%s)",
                 emm_scalar_name(s->type), s->stride,
                 s->kind == SHAPE_VERTICES ? "coordinates" : "vertex indices", use, all, src);
        return;
    }
    size_t used = 0;
    int w = snprintf(out, cap, "%u-byte records (%s): ", s->stride, src);
    used = w > 0 && (size_t)w < cap ? (size_t)w : cap;
    for (int i = 0; i < s->nf && used < cap; i++) {
        const shape_field *f = &s->f[i];
        bool same = i > 0 && s->f[i - 1].cls == f->cls && s->f[i - 1].size == f->size &&
                    (f->cls != 'f' && f->cls != 'i' && f->cls != 'h' ? true
                                                                    : s->f[i - 1].type == f->type);
        char what[96];
        if (f->cls == 'f' || f->cls == 'i' || f->cls == 'h')
            snprintf(what, sizeof what, "%s %s", emm_scalar_name(f->type), class_words(f->cls));
        else if (f->cls == 'p')
            snprintf(what, sizeof what, "addresses (pointers)");
        else
            snprintf(what, sizeof what, "%u byte%s %s", f->size, f->size == 1 ? "" : "s",
                     class_words(f->cls));
        w = same ? snprintf(out + used, cap - used, ", %u", f->off)
                 : snprintf(out + used, cap - used, "%s%s at %u", i ? "; " : "", what, f->off);
        if (w < 0)
            return;
        used += (size_t)w;
    }
    if (used >= cap)
        return;
    const char *verdict;
    char v[128];
    switch (s->kind) {
    case SHAPE_VERTICES:
        snprintf(v, sizeof v, "three %s coordinates at %u", emm_scalar_name(s->type), s->at);
        verdict = v;
        break;
    case SHAPE_TRIANGLES:
        snprintf(v, sizeof v, "three vertex indices at %u", s->at);
        verdict = v;
        break;
    case SHAPE_SOUP:
        snprintf(v, sizeof v, "a triangle soup: nine corner coordinates at %u", s->at);
        verdict = v;
        break;
    case SHAPE_AXIS:
        verdict = "one coordinate per entry (a structure of arrays)";
        break;
    case SHAPE_HALFEDGE:
        verdict = "half-edge-like (four or more index fields a record: never triangles:)";
        break;
    default:
        verdict = "no three coordinates or vertex indices in a row";
    }
    /* The records in use count a mesh's elements; of a block that is no
     * mesh array (a hash table's, a list of addresses) they depend on the
     * addresses and hashes of the run, so the block's size stands alone and
     * the listing stays the same from run to run. */
    if (s->kind == SHAPE_NONE)
        snprintf(out + used, cap - used, "; %s records: %s", all, verdict);
    else
        snprintf(out + used, cap - used, "; %s in use of %s: %s", use, all, verdict);
}

bool shape_rule(const shape *s, char axis, const char **kind, char *body, size_t cap)
{
    switch (s->kind) {
    case SHAPE_VERTICES:
        *kind = "vertices";
        snprintf(body, cap, "stride=%u,xyz=%u:%s", s->stride, s->at, emm_scalar_name(s->type));
        return true;
    case SHAPE_TRIANGLES:
        *kind = "triangles";
        snprintf(body, cap, "stride=%u,vidx=%u:%s", s->stride, s->at, emm_scalar_name(s->type));
        return true;
    case SHAPE_SOUP:
        *kind = "soup";
        snprintf(body, cap, "stride=%u,corners=%u:%s", s->stride, s->at, emm_scalar_name(s->type));
        return true;
    case SHAPE_AXIS:
        *kind = "vertices";
        snprintf(body, cap, "%c=0:%s", axis ? axis : 'x', emm_scalar_name(s->type));
        return true;
    default:
        return false;
    }
}
