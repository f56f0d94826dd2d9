/* emm — trace files: a streaming writer and a streaming reader; the
 * byte format is docs/trace-format.md, constants in
 * trace_format.h).
 *
 * Records are kept in blocks of up to 64Ki. A block is columnar: each field
 * (array, element delta, offset, bytes, work, write) is stored with
 * frame-of-reference bit packing, its width chosen per block from the
 * block's range of values. Traversals touch nearby elements, so element
 * deltas within one array are small and a typical record takes 3 to 5 bytes;
 * decoding is a few shifts and masks per field with no data-dependent
 * branches. The writer and the reader hold one block at a time, never the
 * whole trace.
 *
 * Version 2 adds an optional seventh column, the program counter of each
 * access (EMM_TRACE_FLAG_PC), and the table of the traced program's
 * objects that resolves them; version 1 files are still read (their
 * records have pc 0). */
#include "emm/trace.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <zstd.h>

#include "error.h"
#include "infile.h"
#include "outfile.h"
#include "trace_format.h"

#define ZSTD_LEVEL 3
/* Records decoded per pass over the columns: small enough that the unpacked
 * columns stay in the L1 cache. */
#define CHUNK 512u

/* ------------------------------------------------------------------------ */
/* Checksum                                                                   */

#define HASH_P1 0x9E3779B185EBCA87ull
#define HASH_P2 0xC2B2AE3D27D4EB4Full

static inline uint64_t rotl64(uint64_t x, unsigned r)
{
    return (x << r) | (x >> (64 - r));
}

static inline uint64_t hash_round(uint64_t h, uint64_t w)
{
    return rotl64((h ^ w) * HASH_P1, 31);
}

uint64_t emm_trace_hash(const void *data, size_t n, uint64_t seed)
{
    const uint8_t *p = (const uint8_t *)data;
    const size_t total = n;
    uint64_t h0 = seed + HASH_P1, h1 = seed + HASH_P2, h2 = seed, h3 = seed - HASH_P1;
    while (n >= 32) {
        h0 = hash_round(h0, emm_le64(p));
        h1 = hash_round(h1, emm_le64(p + 8));
        h2 = hash_round(h2, emm_le64(p + 16));
        h3 = hash_round(h3, emm_le64(p + 24));
        p += 32;
        n -= 32;
    }
    uint64_t h = hash_round(hash_round(hash_round(h0, h1), h2), h3);
    while (n >= 8) {
        h = hash_round(h, emm_le64(p));
        p += 8;
        n -= 8;
    }
    if (n > 0) {
        uint8_t tail[8] = {0};
        memcpy(tail, p, n);
        h = hash_round(h, emm_le64(tail));
    }
    h = hash_round(h, (uint64_t)total);
    /* Final avalanche; every step is invertible. */
    h ^= h >> 33;
    h *= HASH_P2;
    h ^= h >> 29;
    h *= HASH_P1;
    h ^= h >> 32;
    return h;
}

/* ------------------------------------------------------------------------ */
/* Shared helpers                                                             */

static const char *kind_name(emm_array_kind k)
{
    switch (k) {
    case EMM_ARRAY_VERTICES: return "vertices";
    case EMM_ARRAY_TRIANGLES: return "triangles";
    case EMM_ARRAY_RAW: return "raw";
    }
    return "?";
}

static unsigned width_of(uint64_t range)
{
    if (range == 0)
        return 0;
    unsigned bits = 64u - (unsigned)__builtin_clzll(range);
    return bits > EMM_TRACE_MAX_PACKED_BITS ? 64u : bits;
}

static size_t stream_bytes(uint32_t nrec, unsigned bits)
{
    return (size_t)(((uint64_t)nrec * bits + 7) / 8);
}

/* Checks the arrays and geometry a writer is given or a reader found; `what`
 * prefixes the message ("<path>: byte N: " for a reader). Returns the first
 * problem. */
static emm_status check_arrays(const emm_trace_array *arrays, uint32_t narrays,
                               const char *what, emm_status bad, emm_error *err)
{
    if (narrays > EMM_TRACE_MAX_ARRAYS)
        return emm_fail(err, bad, "%s%u arrays (at most %u)", what, narrays,
                        EMM_TRACE_MAX_ARRAYS);
    for (uint32_t i = 0; i < narrays; i++) {
        const emm_trace_array *a = &arrays[i];
        if ((unsigned)a->kind > EMM_ARRAY_RAW)
            return emm_fail(err, bad, "%sarray %u has unknown kind %u", what, i,
                            (unsigned)a->kind);
        if (a->record_size == 0)
            return emm_fail(err, bad, "%sarray %u has record size 0", what, i);
        if (a->kind == EMM_ARRAY_RAW) {
            if (a->record_size != 1)
                return emm_fail(err, bad,
                                "%sarray %u is raw memory but has record size %u (must be 1)",
                                what, i, a->record_size);
            /* Its elements are the addresses themselves. */
            if (a->base != 0)
                return emm_fail(err, bad, "%sarray %u is raw memory but has base 0x%llx (must be 0)",
                                what, i, (unsigned long long)a->base);
        } else {
            /* Every byte of the array must have a 64-bit address. */
            uint64_t span;
            if (__builtin_mul_overflow(a->count, (uint64_t)a->record_size, &span) ||
                (span > 0 && a->base > UINT64_MAX - (span - 1)))
                return emm_fail(err, bad,
                                "%sarray %u: base + count * record_size overflows 64 bits", what,
                                i);
        }
    }
    return EMM_OK;
}

/* The most bytes one record of array a may claim (trace.h). */
static uint32_t access_limit(const emm_trace_array *a)
{
    return a->kind == EMM_ARRAY_RAW || a->record_size > EMM_TRACE_MAX_ACCESS_BYTES
               ? EMM_TRACE_MAX_ACCESS_BYTES
               : a->record_size;
}

static emm_status check_geometry(const emm_trace_geometry *g, const char *what, emm_status bad,
                                 emm_error *err)
{
    for (uint64_t i = 0; i < 3 * g->nv; i++)
        if (!isfinite(g->xyz[i]))
            return emm_fail(err, bad, "%sgeometry: vertex %llu has a non-finite coordinate",
                            what, (unsigned long long)(i / 3));
    for (uint64_t i = 0; i < 3 * g->nt; i++)
        if (g->tri[i] < 0 || (uint64_t)g->tri[i] >= g->nv)
            return emm_fail(err, bad,
                            "%sgeometry: triangle %llu has vertex index %ld (%llu vertices)", what,
                            (unsigned long long)(i / 3), (long)g->tri[i],
                            (unsigned long long)g->nv);
    return EMM_OK;
}

/* The geometry region's bytes, in file order: xyz as f64, tri as i32. */
static void encode_geometry(const emm_trace_geometry *g, uint8_t *out)
{
    for (uint64_t i = 0; i < 3 * g->nv; i++) {
        uint64_t bits;
        memcpy(&bits, &g->xyz[i], 8);
        emm_put_le64(out, bits);
        out += 8;
    }
    for (uint64_t i = 0; i < 3 * g->nt; i++) {
        emm_put_le32(out, (uint32_t)g->tri[i]);
        out += 4;
    }
}

/* ------------------------------------------------------------------------ */
/* Writer                                                                     */

struct emm_trace_writer {
    char *path;
    emm_outfile out; /* the trace, written whole or not at all */
    int compress;
    uint32_t narrays;
    emm_trace_array *arrays;
    uint64_t *limit; /* elements allowed per array (UINT64_MAX: any, for raw) */
    uint64_t *prev;  /* previous element per array in the current block */
    uint64_t nv, nt;
    uint64_t records, writes, blocks;
    emm_status failed; /* sticky: after an error only close/abort make sense */
    unsigned ncols;    /* EMM_TRACE_COLUMNS, or EMM_TRACE_MAX_COLUMNS with the pc */
    /* The block being filled, one column per field. */
    uint32_t n;
    uint64_t *col[EMM_TRACE_MAX_COLUMNS];
    uint8_t *raw;    /* encoded payload, + 8 bytes of slack */
    uint8_t *stored; /* compressed payload */
    size_t stored_cap;
    ZSTD_CCtx *cctx;
};

static size_t max_raw_size(uint32_t nrec, unsigned ncols)
{
    return emm_trace_column_table(ncols) + (size_t)ncols * 8 * nrec;
}

static emm_status writer_io_error(emm_trace_writer *w, emm_error *err, const char *what)
{
    w->failed = EMM_ERR_IO;
    return emm_fail(err, EMM_ERR_IO, "%s: %s: %s", w->path, what, strerror(errno));
}

static emm_status write_bytes(emm_trace_writer *w, const void *p, size_t n, emm_error *err)
{
    if (n > 0 && fwrite(p, 1, n, w->out.f) != n)
        return writer_io_error(w, err, "cannot write");
    return EMM_OK;
}

static void writer_free(emm_trace_writer *w)
{
    for (int c = 0; c < EMM_TRACE_MAX_COLUMNS; c++)
        free(w->col[c]);
    free(w->raw);
    free(w->stored);
    ZSTD_freeCCtx(w->cctx);
    free(w->arrays);
    free(w->limit);
    free(w->prev);
    free(w->path);
    free(w);
}

void emm_trace_writer_abort(emm_trace_writer *w)
{
    if (!w)
        return;
    emm_outfile_abort(&w->out);
    writer_free(w);
}

/* Packs values v - min, `bits` wide, LSB first, into out; returns the bytes
 * written (stream_bytes(n, bits)). */
static size_t pack_column(const uint64_t *v, uint32_t n, uint64_t min, unsigned bits, uint8_t *out)
{
    uint8_t *p = out;
    if (bits == 0)
        return 0;
    if (bits == 64) {
        for (uint32_t i = 0; i < n; i++, p += 8)
            emm_put_le64(p, v[i] - min);
        return (size_t)(p - out);
    }
    uint64_t acc = 0;
    unsigned nacc = 0;
    for (uint32_t i = 0; i < n; i++) {
        uint64_t u = v[i] - min;
        acc |= u << nacc;
        if (nacc + bits >= 64) {
            emm_put_le64(p, acc);
            p += 8;
            acc = nacc ? u >> (64 - nacc) : 0;
            nacc = nacc + bits - 64;
        } else {
            nacc += bits;
        }
    }
    for (; nacc > 0; nacc = nacc > 8 ? nacc - 8 : 0) {
        *p++ = (uint8_t)acc;
        acc >>= 8;
    }
    return (size_t)(p - out);
}

static emm_status flush_block(emm_trace_writer *w, emm_error *err)
{
    const uint32_t n = w->n;
    if (n == 0)
        return EMM_OK;
    uint8_t *raw = w->raw;
    memset(raw, 0, emm_trace_column_table(w->ncols));
    size_t pos = emm_trace_column_table(w->ncols);
    for (int c = 0; c < (int)w->ncols; c++) {
        const uint64_t *v = w->col[c];
        uint64_t min, max;
        if (c == EMM_COL_DELTA) { /* signed: the frame starts at the most negative delta */
            int64_t smin = (int64_t)v[0], smax = (int64_t)v[0];
            for (uint32_t i = 1; i < n; i++) {
                int64_t s = (int64_t)v[i];
                smin = s < smin ? s : smin;
                smax = s > smax ? s : smax;
            }
            min = (uint64_t)smin;
            max = (uint64_t)smax;
        } else {
            min = max = v[0];
            for (uint32_t i = 1; i < n; i++) {
                min = v[i] < min ? v[i] : min;
                max = v[i] > max ? v[i] : max;
            }
        }
        unsigned bits = width_of(max - min);
        raw[c] = (uint8_t)bits;
        emm_put_le64(raw + 8 + 8 * c, min);
        pos += pack_column(v, n, min, bits, raw + pos);
    }
    const uint8_t *payload = raw;
    size_t stored = pos;
    if (w->compress) {
        size_t r = ZSTD_compressCCtx(w->cctx, w->stored, w->stored_cap, raw, pos, ZSTD_LEVEL);
        if (ZSTD_isError(r)) {
            w->failed = EMM_ERR_IO;
            return emm_fail(err, EMM_ERR_IO, "%s: zstd: %s", w->path, ZSTD_getErrorName(r));
        }
        payload = w->stored;
        stored = r;
    }
    uint8_t hdr[EMM_TRACE_BLOCK_HEADER_SIZE];
    emm_put_le32(hdr + EMM_TB_MAGIC, EMM_TRACE_BLOCK_MAGIC);
    emm_put_le32(hdr + EMM_TB_RECORDS, n);
    emm_put_le32(hdr + EMM_TB_RAW, (uint32_t)pos);
    emm_put_le32(hdr + EMM_TB_STORED, (uint32_t)stored);
    emm_put_le64(hdr + EMM_TB_PAYLOAD_SUM, emm_trace_hash(payload, stored, 0));
    emm_put_le64(hdr + EMM_TB_HEADER_SUM, emm_trace_hash(hdr, EMM_TB_HEADER_SUM, 0));
    emm_status s = write_bytes(w, hdr, sizeof hdr, err);
    if (s == EMM_OK)
        s = write_bytes(w, payload, stored, err);
    if (s != EMM_OK)
        return s;
    w->blocks++;
    w->n = 0;
    memset(w->prev, 0, (size_t)w->narrays * sizeof *w->prev);
    return EMM_OK;
}

static void put_header(const emm_trace_writer *w, uint8_t *h)
{
    memset(h, 0, EMM_TRACE_HEADER_SIZE);
    memcpy(h + EMM_TH_MAGIC, EMM_TRACE_MAGIC, 8);
    emm_put_le32(h + EMM_TH_VERSION, EMM_TRACE_VERSION);
    emm_put_le32(h + EMM_TH_FLAGS, (w->compress ? EMM_TRACE_FLAG_ZSTD : 0) |
                                       (w->ncols > EMM_TRACE_COLUMNS ? EMM_TRACE_FLAG_PC : 0));
    emm_put_le32(h + EMM_TH_NARRAYS, w->narrays);
    emm_put_le64(h + EMM_TH_RECORDS, w->records);
    emm_put_le64(h + EMM_TH_WRITES, w->writes);
    emm_put_le64(h + EMM_TH_BLOCKS, w->blocks);
    emm_put_le64(h + EMM_TH_NV, w->nv);
    emm_put_le64(h + EMM_TH_NT, w->nt);
    emm_put_le64(h + EMM_TH_CHECKSUM, emm_trace_hash(h, EMM_TH_CHECKSUM, 0));
}

emm_status emm_trace_writer_open(const char *path, const emm_trace_array *arrays, uint32_t narrays,
                                 const emm_trace_geometry *geometry, int compress,
                                 emm_trace_writer **out, emm_error *err)
{
    emm_trace_options o = {compress, 0, NULL, 0};
    return emm_trace_writer_open_ex(path, arrays, narrays, geometry, &o, out, err);
}

/* The module table's bytes (trace_format.h), into *out (malloc'ed). */
static emm_status encode_modules(const char *path, const emm_trace_module *m, uint32_t n,
                                 uint8_t **out, size_t *len, emm_error *err)
{
    size_t paths = 0;
    if (n > EMM_TRACE_MAX_MODULES)
        return emm_fail(err, EMM_ERR_INVALID, "%s: %u modules (at most %u)", path, n,
                        EMM_TRACE_MAX_MODULES);
    for (uint32_t i = 0; i < n; i++)
        paths += strlen(m[i].path ? m[i].path : "");
    if (paths > EMM_TRACE_MAX_MODULE_PATHS)
        return emm_fail(err, EMM_ERR_INVALID, "%s: the modules' paths take %zu bytes (at most %u)",
                        path, paths, EMM_TRACE_MAX_MODULE_PATHS);
    *len = EMM_TRACE_MODULES_HEADER + (size_t)n * EMM_TRACE_MODULE_SIZE + paths;
    uint8_t *b = malloc(*len + 8);
    if (!b)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    emm_put_le32(b, n);
    emm_put_le32(b + 4, (uint32_t)paths);
    uint8_t *e = b + EMM_TRACE_MODULES_HEADER, *text = e + (size_t)n * EMM_TRACE_MODULE_SIZE;
    uint32_t at = 0;
    for (uint32_t i = 0; i < n; i++, e += EMM_TRACE_MODULE_SIZE) {
        size_t l = strlen(m[i].path ? m[i].path : "");
        emm_put_le64(e, m[i].bias);
        emm_put_le64(e + 8, m[i].lo);
        emm_put_le64(e + 16, m[i].hi);
        emm_put_le32(e + 24, at);
        emm_put_le32(e + 28, (uint32_t)l);
        memcpy(text + at, m[i].path ? m[i].path : "", l);
        at += (uint32_t)l;
    }
    emm_put_le64(b + *len, emm_trace_hash(b, *len, 0));
    *out = b;
    return EMM_OK;
}

emm_status emm_trace_writer_open_ex(const char *path, const emm_trace_array *arrays,
                                    uint32_t narrays, const emm_trace_geometry *geometry,
                                    const emm_trace_options *opt, emm_trace_writer **out,
                                    emm_error *err)
{
    static const emm_trace_options none_opt = {0, 0, NULL, 0};
    assert(path && out && (arrays || narrays == 0));
    *out = NULL;
    if (!opt)
        opt = &none_opt;
    const int compress = opt->compress;
    emm_trace_geometry none = {0, 0, NULL, NULL};
    const emm_trace_geometry *g = geometry ? geometry : &none;
    char what[600];
    snprintf(what, sizeof what, "%s: ", path);
    emm_status s = check_arrays(arrays, narrays, what, EMM_ERR_INVALID, err);
    if (s != EMM_OK)
        return s;
    if (g->nv > UINT64_MAX / 48 || g->nt > UINT64_MAX / 24 ||
        (g->nv && !g->xyz) || (g->nt && !g->tri))
        return emm_fail(err, EMM_ERR_INVALID, "%s: geometry sizes are not valid", path);
    if ((s = check_geometry(g, what, EMM_ERR_INVALID, err)) != EMM_OK)
        return s;

    emm_trace_writer *w = calloc(1, sizeof *w);
    if (!w)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    w->compress = compress != 0;
    w->ncols = opt->pcs ? EMM_TRACE_MAX_COLUMNS : EMM_TRACE_COLUMNS;
    w->narrays = narrays;
    size_t plen = strlen(path);
    w->path = malloc(plen + 1);
    w->arrays = malloc((narrays ? narrays : 1) * sizeof *w->arrays);
    w->limit = malloc((narrays ? narrays : 1) * sizeof *w->limit);
    w->prev = calloc(narrays ? narrays : 1, sizeof *w->prev);
    w->raw = malloc(max_raw_size(EMM_TRACE_BLOCK_RECORDS, w->ncols) + 8);
    int ok = w->path && w->arrays && w->limit && w->prev && w->raw;
    for (int c = 0; c < (int)w->ncols; c++)
        ok = ok && (w->col[c] = malloc(EMM_TRACE_BLOCK_RECORDS * sizeof(uint64_t))) != NULL;
    if (ok && w->compress) {
        w->stored_cap = ZSTD_compressBound(max_raw_size(EMM_TRACE_BLOCK_RECORDS, w->ncols));
        w->stored = malloc(w->stored_cap);
        w->cctx = ZSTD_createCCtx();
        ok = w->stored && w->cctx;
    }
    if (!ok) {
        writer_free(w);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    }
    memcpy(w->path, path, plen + 1);
    if (narrays)
        memcpy(w->arrays, arrays, narrays * sizeof *arrays);
    for (uint32_t i = 0; i < narrays; i++)
        w->limit[i] = arrays[i].kind == EMM_ARRAY_RAW ? UINT64_MAX : arrays[i].count;

    s = emm_outfile_open(&w->out, path, "the trace", err);
    if (s != EMM_OK) {
        writer_free(w);
        return s;
    }
    /* Header (counts filled in at close), array table, geometry. */
    uint8_t h[EMM_TRACE_HEADER_SIZE];
    w->nv = g->nv;
    w->nt = g->nt;
    put_header(w, h);
    s = write_bytes(w, h, sizeof h, err);

    uint8_t *table = malloc((size_t)narrays * EMM_TRACE_ARRAY_SIZE + 8);
    size_t geo_len = (size_t)(g->nv * 24 + g->nt * 12);
    uint8_t *geo = malloc(geo_len + 8);
    if (s == EMM_OK && (!table || !geo))
        s = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    if (s == EMM_OK) {
        for (uint32_t i = 0; i < narrays; i++) {
            uint8_t *e = table + (size_t)i * EMM_TRACE_ARRAY_SIZE;
            emm_put_le32(e, (uint32_t)arrays[i].kind);
            emm_put_le32(e + 4, arrays[i].record_size);
            emm_put_le64(e + 8, arrays[i].count);
            emm_put_le64(e + 16, arrays[i].base);
        }
        size_t tlen = (size_t)narrays * EMM_TRACE_ARRAY_SIZE;
        emm_put_le64(table + tlen, emm_trace_hash(table, tlen, 0));
        s = write_bytes(w, table, tlen + 8, err);
    }
    if (s == EMM_OK) {
        encode_geometry(g, geo);
        emm_put_le64(geo + geo_len, emm_trace_hash(geo, geo_len, 0));
        s = write_bytes(w, geo, geo_len + 8, err);
    }
    uint8_t *mods = NULL;
    size_t mods_len = 0;
    if (s == EMM_OK &&
        (s = encode_modules(path, opt->modules, opt->nmodules, &mods, &mods_len, err)) == EMM_OK)
        s = write_bytes(w, mods, mods_len + 8, err);
    free(mods);
    free(table);
    free(geo);
    if (s != EMM_OK) {
        emm_trace_writer_abort(w);
        return s;
    }
    *out = w;
    return EMM_OK;
}

emm_status emm_trace_write(emm_trace_writer *w, const emm_trace_record *recs, size_t n,
                           emm_error *err)
{
    if (w->failed)
        return emm_fail(err, w->failed, "%s: the trace writer failed earlier", w->path);
    for (size_t i = 0; i < n; i++) {
        const emm_trace_record *r = &recs[i];
        uint64_t index = w->records;
        if (r->array >= w->narrays)
            return emm_fail(err, EMM_ERR_RANGE, "%s: record %llu: array %u out of range (%u arrays)",
                            w->path, (unsigned long long)index, r->array, w->narrays);
        const emm_trace_array *a = &w->arrays[r->array];
        if (r->element >= w->limit[r->array] && a->kind != EMM_ARRAY_RAW)
            return emm_fail(err, EMM_ERR_RANGE,
                            "%s: record %llu: element %llu out of range (array %u has %llu records)",
                            w->path, (unsigned long long)index, (unsigned long long)r->element,
                            r->array, (unsigned long long)a->count);
        if (r->offset >= a->record_size)
            return emm_fail(err, EMM_ERR_RANGE,
                            "%s: record %llu: offset %u outside the %u-byte record of array %u",
                            w->path, (unsigned long long)index, r->offset, a->record_size,
                            r->array);
        if (r->bytes == 0 || r->bytes > access_limit(a))
            return emm_fail(err, EMM_ERR_RANGE, "%s: record %llu: access of %u bytes (array %u takes 1 to %u)",
                            w->path, (unsigned long long)index, r->bytes, r->array, access_limit(a));
        if (r->element + (r->bytes - 1) < r->element)
            return emm_fail(err, EMM_ERR_RANGE,
                            "%s: record %llu: an access of %u bytes at 0x%llx runs past the end of the "
                            "64-bit address space",
                            w->path, (unsigned long long)index, r->bytes, (unsigned long long)r->element);
        if (r->write > 1)
            return emm_fail(err, EMM_ERR_RANGE, "%s: record %llu: write flag %u (must be 0 or 1)",
                            w->path, (unsigned long long)index, r->write);
        uint32_t k = w->n;
        w->col[EMM_COL_ARRAY][k] = r->array;
        w->col[EMM_COL_DELTA][k] = r->element - w->prev[r->array];
        w->prev[r->array] = r->element;
        w->col[EMM_COL_OFFSET][k] = r->offset;
        w->col[EMM_COL_BYTES][k] = r->bytes;
        w->col[EMM_COL_WORK][k] = r->work;
        w->col[EMM_COL_WRITE][k] = r->write;
        if (w->ncols > EMM_COL_PC)
            w->col[EMM_COL_PC][k] = r->pc;
        w->records++;
        w->writes += r->write;
        if (++w->n == EMM_TRACE_BLOCK_RECORDS) {
            emm_status s = flush_block(w, err);
            if (s != EMM_OK)
                return s;
        }
    }
    return EMM_OK;
}

emm_status emm_trace_writer_close(emm_trace_writer *w, emm_error *err)
{
    emm_status s = w->failed ? emm_fail(err, w->failed, "%s: the trace writer failed earlier", w->path)
                             : flush_block(w, err);
    if (s == EMM_OK) {
        /* The counts are known now: rewrite the header. */
        uint8_t h[EMM_TRACE_HEADER_SIZE];
        put_header(w, h);
        if (fflush(w->out.f) != 0 || fseeko(w->out.f, 0, SEEK_SET) != 0)
            s = writer_io_error(w, err, "cannot seek");
        else
            s = write_bytes(w, h, sizeof h, err);
    }
    if (s == EMM_OK)
        s = emm_outfile_commit(&w->out, "the trace", err);
    if (s != EMM_OK) {
        emm_trace_writer_abort(w);
        return s;
    }
    writer_free(w);
    return EMM_OK;
}

/* ------------------------------------------------------------------------ */
/* Reader                                                                     */

struct emm_trace_reader {
    char *path;
    FILE *f;
    uint64_t file_size;
    uint64_t pos;        /* file offset of the next unread byte */
    uint64_t data_start; /* offset of the first block */
    emm_trace_info info;
    unsigned ncols;      /* columns per block */
    emm_trace_array *arrays;
    emm_trace_module *modules;
    char *module_paths;  /* the modules' paths, each NUL-terminated */
    double *xyz;
    int32_t *tri;
    uint64_t *limit; /* elements allowed per array; UINT64_MAX = any (raw) */
    uint64_t *maxe;  /* largest element allowed (raw: UINT64_MAX) */
    uint64_t *rsize; /* record size per array; 0 for an empty array, so no record passes */
    uint64_t *maxb;  /* the most bytes one access of the array may claim */
    uint64_t *prev;
    /* Progress through the blocks. */
    uint64_t block;      /* blocks decoded so far */
    uint64_t seen, seen_writes;
    emm_status failed;   /* sticky, with the message kept for repeats */
    char failed_msg[sizeof(((emm_error *)0)->message)];
    /* Buffers for one block. */
    uint8_t *stored;
    size_t stored_cap;
    uint8_t *raw;
    size_t raw_cap;
    emm_trace_record *recs; /* a decoded block, when the caller's buffer is too small */
    uint32_t nrecs, next;
    ZSTD_DCtx *dctx;
    uint64_t tmp[EMM_TRACE_MAX_COLUMNS][CHUNK];
};

/* Reads exactly n bytes at r->pos, or reports how many were left. */
static emm_status read_exact(emm_trace_reader *r, void *buf, size_t n, const char *what,
                             emm_error *err)
{
    uint64_t left = r->file_size > r->pos ? r->file_size - r->pos : 0;
    if (left < n)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: byte %llu: truncated in %s (expected %zu bytes, %llu left)", r->path,
                        (unsigned long long)r->pos, what, n, (unsigned long long)left);
    if (fread(buf, 1, n, r->f) != n)
        return emm_fail(err, ferror(r->f) ? EMM_ERR_IO : EMM_ERR_FORMAT,
                        "%s: byte %llu: cannot read %s%s%s", r->path, (unsigned long long)r->pos,
                        what, ferror(r->f) ? ": " : " (file shrank)",
                        ferror(r->f) ? strerror(errno) : "");
    r->pos += n;
    return EMM_OK;
}

static void reader_free(emm_trace_reader *r)
{
    if (r->f)
        fclose(r->f);
    free(r->path);
    free(r->arrays);
    free(r->modules);
    free(r->module_paths);
    free(r->xyz);
    free(r->tri);
    free(r->limit);
    free(r->maxe);
    free(r->rsize);
    free(r->maxb);
    free(r->prev);
    free(r->stored);
    free(r->raw);
    free(r->recs);
    ZSTD_freeDCtx(r->dctx);
    free(r);
}

void emm_trace_reader_close(emm_trace_reader *r)
{
    if (r)
        reader_free(r);
}

static emm_status reader_header(emm_trace_reader *r, emm_error *err)
{
    uint8_t h[EMM_TRACE_HEADER_SIZE];
    const char *p = r->path;
    uint64_t left = r->file_size;
    /* Magic and version first, so a file from elsewhere or from a newer emm
     * says so rather than failing a checksum. */
    size_t head = left < 8 ? (size_t)left : 8;
    if (fread(h, 1, head, r->f) != head)
        return emm_fail(err, EMM_ERR_IO, "%s: byte 0: cannot read: %s", p, strerror(errno));
    if (head == 0 || memcmp(h, EMM_TRACE_MAGIC, head) != 0)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte 0: not an emm trace (bad magic)", p);
    rewind(r->f);
    emm_status s = read_exact(r, h, sizeof h, "file header", err);
    if (s != EMM_OK)
        return s;
    uint32_t version = emm_le32(h + EMM_TH_VERSION);
    if (version > EMM_TRACE_VERSION)
        return emm_fail(err, EMM_ERR_UNSUPPORTED,
                        "%s: byte %d: unsupported trace version %u (this emm reads up to %u)", p,
                        EMM_TH_VERSION, version, EMM_TRACE_VERSION);
    if (emm_le64(h + EMM_TH_CHECKSUM) != emm_trace_hash(h, EMM_TH_CHECKSUM, 0))
        return emm_fail(err, EMM_ERR_CORRUPT, "%s: byte 0: file header checksum mismatch", p);
    if (version == 0)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %d: invalid trace version 0", p,
                        EMM_TH_VERSION);
    uint32_t flags = emm_le32(h + EMM_TH_FLAGS);
    uint32_t known = EMM_TRACE_FLAG_ZSTD | (version >= 2 ? EMM_TRACE_FLAG_PC : 0);
    if (flags & ~known)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %d: unknown flags 0x%x", p, EMM_TH_FLAGS,
                        flags);
    if (emm_le32(h + EMM_TH_RESERVED) != 0)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %d: reserved field is not 0", p,
                        EMM_TH_RESERVED);
    uint32_t narrays = emm_le32(h + EMM_TH_NARRAYS);
    uint64_t records = emm_le64(h + EMM_TH_RECORDS), writes = emm_le64(h + EMM_TH_WRITES);
    uint64_t blocks = emm_le64(h + EMM_TH_BLOCKS);
    uint64_t nv = emm_le64(h + EMM_TH_NV), nt = emm_le64(h + EMM_TH_NT);
    if (narrays > EMM_TRACE_MAX_ARRAYS)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %d: %u arrays (at most %u)", p,
                        EMM_TH_NARRAYS, narrays, EMM_TRACE_MAX_ARRAYS);
    if (writes > records)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %d: %llu writes among %llu records", p,
                        EMM_TH_WRITES, (unsigned long long)writes, (unsigned long long)records);
    if (blocks > records || records > blocks * (uint64_t)EMM_TRACE_BLOCK_RECORDS)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %d: %llu records cannot fill %llu blocks", p,
                        EMM_TH_RECORDS, (unsigned long long)records, (unsigned long long)blocks);
    /* Everything after the header must fit in the file. */
    uint64_t rest = r->file_size - r->pos;
    uint64_t need = (uint64_t)narrays * EMM_TRACE_ARRAY_SIZE + 16;
    if (need > rest || nv > rest / 24 || nt > rest / 12 || nv * 24 + nt * 12 > rest - need)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: byte %d: truncated: %u arrays, %llu vertices and %llu triangles "
                        "need more than the %llu bytes left",
                        p, EMM_TH_NARRAYS, narrays, (unsigned long long)nv, (unsigned long long)nt,
                        (unsigned long long)rest);
    r->info.version = version;
    r->info.narrays = narrays;
    r->info.accesses = records;
    r->info.writes = writes;
    r->info.blocks = blocks;
    r->info.compressed = (flags & EMM_TRACE_FLAG_ZSTD) != 0;
    r->info.has_pc = (flags & EMM_TRACE_FLAG_PC) != 0;
    r->ncols = r->info.has_pc ? EMM_TRACE_MAX_COLUMNS : EMM_TRACE_COLUMNS;
    r->info.geometry.nv = nv;
    r->info.geometry.nt = nt;
    return EMM_OK;
}

/* Version 2's module table (trace_format.h). */
static emm_status reader_modules(emm_trace_reader *r, emm_error *err)
{
    const char *p = r->path;
    uint64_t at = r->pos;
    uint8_t h[EMM_TRACE_MODULES_HEADER];
    emm_status s = read_exact(r, h, sizeof h, "module table", err);
    if (s != EMM_OK)
        return s;
    uint32_t n = emm_le32(h), paths = emm_le32(h + 4);
    if (n > EMM_TRACE_MAX_MODULES || paths > EMM_TRACE_MAX_MODULE_PATHS)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: %u modules with %u bytes of paths "
                        "(at most %u and %u)", p, (unsigned long long)at, n, paths,
                        EMM_TRACE_MAX_MODULES, EMM_TRACE_MAX_MODULE_PATHS);
    size_t len = EMM_TRACE_MODULES_HEADER + (size_t)n * EMM_TRACE_MODULE_SIZE + paths;
    uint8_t *b = malloc(len + 8);
    r->modules = malloc((n ? n : 1) * sizeof *r->modules);
    r->module_paths = malloc((size_t)paths + n + 1);
    if (!b || !r->modules || !r->module_paths) {
        free(b);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the module table", p);
    }
    memcpy(b, h, sizeof h);
    s = read_exact(r, b + sizeof h, len + 8 - sizeof h, "module table", err);
    if (s == EMM_OK && emm_le64(b + len) != emm_trace_hash(b, len, 0))
        s = emm_fail(err, EMM_ERR_CORRUPT, "%s: byte %llu: module table checksum mismatch", p,
                     (unsigned long long)at);
    const uint8_t *e = b + EMM_TRACE_MODULES_HEADER, *text = e + (size_t)n * EMM_TRACE_MODULE_SIZE;
    char *out = r->module_paths;
    for (uint32_t i = 0; s == EMM_OK && i < n; i++, e += EMM_TRACE_MODULE_SIZE) {
        uint32_t off = emm_le32(e + 24), l = emm_le32(e + 28);
        if (off > paths || l > paths - off) {
            s = emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: module %u's path lies outside "
                         "the table", p, (unsigned long long)at, i);
            break;
        }
        r->modules[i].bias = emm_le64(e);
        r->modules[i].lo = emm_le64(e + 8);
        r->modules[i].hi = emm_le64(e + 16);
        memcpy(out, text + off, l);
        out[l] = '\0';
        r->modules[i].path = out;
        out += l + 1;
    }
    free(b);
    if (s == EMM_OK) {
        r->info.nmodules = n;
        r->info.modules = r->modules;
    }
    return s;
}

static emm_status reader_tables(emm_trace_reader *r, emm_error *err)
{
    const char *p = r->path;
    uint32_t na = r->info.narrays;
    uint64_t nv = r->info.geometry.nv, nt = r->info.geometry.nt;
    size_t tlen = (size_t)na * EMM_TRACE_ARRAY_SIZE;
    size_t glen = (size_t)(nv * 24 + nt * 12);
    size_t big = tlen > glen ? tlen : glen;
    uint8_t *buf = malloc(big + 8);
    r->arrays = malloc((na ? na : 1) * sizeof *r->arrays);
    r->limit = malloc((na ? na : 1) * sizeof *r->limit);
    r->maxe = malloc((na ? na : 1) * sizeof *r->maxe);
    r->rsize = malloc((na ? na : 1) * sizeof *r->rsize);
    r->maxb = malloc((na ? na : 1) * sizeof *r->maxb);
    r->prev = calloc(na ? na : 1, sizeof *r->prev);
    r->xyz = malloc(nv ? (size_t)nv * 24 : 1);
    r->tri = malloc(nt ? (size_t)nt * 12 : 1);
    if (!buf || !r->arrays || !r->limit || !r->maxe || !r->rsize || !r->maxb || !r->prev || !r->xyz ||
        !r->tri) {
        free(buf);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the trace's tables", p);
    }
    uint64_t at = r->pos;
    emm_status s = read_exact(r, buf, tlen + 8, "array table", err);
    if (s == EMM_OK && emm_le64(buf + tlen) != emm_trace_hash(buf, tlen, 0))
        s = emm_fail(err, EMM_ERR_CORRUPT, "%s: byte %llu: array table checksum mismatch", p,
                     (unsigned long long)at);
    if (s == EMM_OK) {
        for (uint32_t i = 0; i < na; i++) {
            const uint8_t *e = buf + (size_t)i * EMM_TRACE_ARRAY_SIZE;
            r->arrays[i].kind = (emm_array_kind)emm_le32(e);
            r->arrays[i].record_size = emm_le32(e + 4);
            r->arrays[i].count = emm_le64(e + 8);
            r->arrays[i].base = emm_le64(e + 16);
            int raw = r->arrays[i].kind == EMM_ARRAY_RAW;
            r->limit[i] = raw ? UINT64_MAX : r->arrays[i].count;
            r->maxe[i] = raw ? UINT64_MAX : r->arrays[i].count - 1;
            r->rsize[i] = raw || r->arrays[i].count > 0 ? r->arrays[i].record_size : 0;
            r->maxb[i] = access_limit(&r->arrays[i]);
        }
        char what[600];
        snprintf(what, sizeof what, "%s: byte %llu: ", p, (unsigned long long)at);
        s = check_arrays(r->arrays, na, what, EMM_ERR_FORMAT, err);
    }
    r->info.arrays = r->arrays;
    at = r->pos;
    if (s == EMM_OK)
        s = read_exact(r, buf, glen + 8, "geometry", err);
    if (s == EMM_OK && emm_le64(buf + glen) != emm_trace_hash(buf, glen, 0))
        s = emm_fail(err, EMM_ERR_CORRUPT, "%s: byte %llu: geometry checksum mismatch", p,
                     (unsigned long long)at);
    if (s == EMM_OK) {
        for (uint64_t i = 0; i < 3 * nv; i++) {
            uint64_t bits = emm_le64(buf + 8 * i);
            memcpy(&r->xyz[i], &bits, 8);
        }
        for (uint64_t i = 0; i < 3 * nt; i++)
            r->tri[i] = (int32_t)emm_le32(buf + 24 * nv + 4 * i);
        r->info.geometry.xyz = r->xyz;
        r->info.geometry.tri = r->tri;
        char what[600];
        snprintf(what, sizeof what, "%s: byte %llu: ", p, (unsigned long long)at);
        s = check_geometry(&r->info.geometry, what, EMM_ERR_FORMAT, err);
    }
    free(buf);
    if (s == EMM_OK && r->info.version >= 2)
        s = reader_modules(r, err);
    r->data_start = r->pos;
    return s;
}

emm_status emm_trace_reader_open(const char *path, emm_trace_reader **out, emm_error *err)
{
    *out = NULL;
    emm_trace_reader *r = calloc(1, sizeof *r);
    if (!r || !(r->path = strdup(path))) {
        free(r);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    }
    struct stat st;
    emm_status s = EMM_OK;
    if (!(r->f = emm_infile_fopen(path, "trace", err)))
        s = err ? err->status : EMM_ERR_IO;
    else if (fstat(fileno(r->f), &st) != 0)
        s = emm_fail(err, EMM_ERR_IO, "%s: cannot stat: %s", path, strerror(errno));
    if (s == EMM_OK) {
        r->file_size = (uint64_t)st.st_size;
        s = reader_header(r, err);
    }
    if (s == EMM_OK)
        s = reader_tables(r, err);
    if (s == EMM_OK && r->info.compressed && !(r->dctx = ZSTD_createDCtx()))
        s = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    if (s != EMM_OK) {
        reader_free(r);
        return s;
    }
    *out = r;
    return EMM_OK;
}

const emm_trace_info *emm_trace_reader_info(const emm_trace_reader *r)
{
    return &r->info;
}

/* Unpacks `n` values of width `bits` (1..56) starting at value i0 (a
 * multiple of 8, so the group of 8 values starts on a byte) and adds the
 * frame's minimum. Always inlined into a switch over the width, so each
 * width gets constant shifts and offsets (measured: 1.5x faster decoding
 * than one loop with variable shifts). `src` has 8 readable bytes of slack. */
static inline __attribute__((always_inline)) void
unpack_fixed(const uint8_t *src, const unsigned bits, uint64_t min, uint32_t i0, uint32_t n,
             uint64_t *out)
{
    const uint64_t mask = (UINT64_C(1) << bits) - 1;
    const uint8_t *p = src + (size_t)i0 / 8 * bits;
    uint32_t i = 0;
    /* Written out: gcc -O2 does not unroll the 8-value loop by itself, and
     * unrolled it decodes 1.3x faster. */
    for (; i + 8 <= n; i += 8, p += bits) {
        out[i + 0] = ((emm_le64(p) & mask)) + min;
        out[i + 1] = ((emm_le64(p + 1 * bits / 8) >> (1 * bits % 8)) & mask) + min;
        out[i + 2] = ((emm_le64(p + 2 * bits / 8) >> (2 * bits % 8)) & mask) + min;
        out[i + 3] = ((emm_le64(p + 3 * bits / 8) >> (3 * bits % 8)) & mask) + min;
        out[i + 4] = ((emm_le64(p + 4 * bits / 8) >> (4 * bits % 8)) & mask) + min;
        out[i + 5] = ((emm_le64(p + 5 * bits / 8) >> (5 * bits % 8)) & mask) + min;
        out[i + 6] = ((emm_le64(p + 6 * bits / 8) >> (6 * bits % 8)) & mask) + min;
        out[i + 7] = ((emm_le64(p + 7 * bits / 8) >> (7 * bits % 8)) & mask) + min;
    }
    for (unsigned j = 0; i < n; i++, j++)
        out[i] = ((emm_le64(p + j * bits / 8) >> (j * bits % 8)) & mask) + min;
}

/* Unpacks values [i0, i0 + n) of a column into out, adding the frame's
 * minimum. */
static void unpack_column(const uint8_t *src, unsigned bits, uint64_t min, uint32_t i0, uint32_t n,
                          uint64_t *out)
{
    switch (bits) {
    case 0:
        for (uint32_t i = 0; i < n; i++)
            out[i] = min;
        return;
    case 64:
        for (uint32_t i = 0; i < n; i++)
            out[i] = emm_le64(src + 8 * ((size_t)i0 + i)) + min;
        return;
#define UNPACK_CASE(b)                                                                             \
    case b: unpack_fixed(src, b, min, i0, n, out); return;
#define UNPACK_CASE8(b)                                                                            \
    UNPACK_CASE(b) UNPACK_CASE(b + 1) UNPACK_CASE(b + 2) UNPACK_CASE(b + 3) UNPACK_CASE(b + 4)     \
    UNPACK_CASE(b + 5) UNPACK_CASE(b + 6) UNPACK_CASE(b + 7)
        UNPACK_CASE8(1) UNPACK_CASE8(9) UNPACK_CASE8(17) UNPACK_CASE8(25) UNPACK_CASE8(33)
        UNPACK_CASE8(41) UNPACK_CASE8(49)
#undef UNPACK_CASE8
#undef UNPACK_CASE
    default: /* 57..63 are rejected before decoding */
        assert(0);
    }
}

/* The message for a record that failed the decoder's checks. */
static emm_status describe_bad_record(const emm_trace_reader *r, uint64_t a, int e_known,
                                      uint64_t e, uint64_t offset, uint64_t bytes, uint64_t work,
                                      uint64_t write, uint64_t index, uint64_t at, uint64_t block,
                                      emm_error *err)
{
    char where[600];
    snprintf(where, sizeof where, "%s: byte %llu: block %llu: record %llu", r->path,
             (unsigned long long)at, (unsigned long long)block, (unsigned long long)index);
    if (a >= r->info.narrays)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: array %llu out of range (%u arrays)", where,
                        (unsigned long long)a, r->info.narrays);
    if (e_known && e >= r->limit[a] && r->limit[a] != UINT64_MAX)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: element %llu out of range (array %llu has %llu records)", where,
                        (unsigned long long)e, (unsigned long long)a,
                        (unsigned long long)r->limit[a]);
    if (offset >= r->arrays[a].record_size)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: offset %llu outside the %u-byte record of array %llu", where,
                        (unsigned long long)offset, r->arrays[a].record_size,
                        (unsigned long long)a);
    if (bytes == 0 || bytes > access_limit(&r->arrays[a]))
        return emm_fail(err, EMM_ERR_FORMAT, "%s: access of %llu bytes (array %llu takes 1 to %u)",
                        where, (unsigned long long)bytes, (unsigned long long)a,
                        access_limit(&r->arrays[a]));
    if (work > UINT32_MAX)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: work %llu exceeds 32 bits", where,
                        (unsigned long long)work);
    if (e_known && e + (bytes - 1) < e)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: an access of %llu bytes at 0x%llx runs past the end of the 64-bit address space",
                        where, (unsigned long long)bytes, (unsigned long long)e);
    return emm_fail(err, EMM_ERR_FORMAT, "%s: write flag %llu (must be 0 or 1)", where,
                    (unsigned long long)write);
}

static emm_status reader_fail(emm_trace_reader *r, emm_error *err, emm_status s)
{
    r->failed = s;
    if (err)
        memcpy(r->failed_msg, err->message, sizeof r->failed_msg);
    else
        r->failed_msg[0] = '\0';
    return s;
}

/* Reads, checks and decodes the next block into dst (room for
 * EMM_TRACE_BLOCK_RECORDS or at least the block's count, which the caller
 * learns from *nrec after the header is read: dst_cap limits it). When the
 * block does not fit in dst_cap, it goes to r->recs instead and *into_dst is 0. */
static emm_status next_block(emm_trace_reader *r, emm_trace_record *dst, size_t dst_cap,
                             uint32_t *nrec, int *into_dst, emm_error *err)
{
    const char *p = r->path;
    const uint64_t b = r->block;
    const uint64_t at = r->pos;
    char what[64];
    uint8_t h[EMM_TRACE_BLOCK_HEADER_SIZE];
    snprintf(what, sizeof what, "block %llu header", (unsigned long long)b);
    emm_status s = read_exact(r, h, sizeof h, what, err);
    if (s != EMM_OK)
        return s;
    if (emm_le32(h + EMM_TB_MAGIC) != EMM_TRACE_BLOCK_MAGIC)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: block %llu: bad block magic", p,
                        (unsigned long long)at, (unsigned long long)b);
    if (emm_le64(h + EMM_TB_HEADER_SUM) != emm_trace_hash(h, EMM_TB_HEADER_SUM, 0))
        return emm_fail(err, EMM_ERR_CORRUPT, "%s: byte %llu: block %llu header checksum mismatch",
                        p, (unsigned long long)at, (unsigned long long)b);
    const uint32_t n = emm_le32(h + EMM_TB_RECORDS);
    const uint32_t raw_size = emm_le32(h + EMM_TB_RAW), stored = emm_le32(h + EMM_TB_STORED);
    if (n == 0 || n > EMM_TRACE_BLOCK_RECORDS)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: block %llu holds %u records (1 to %u)",
                        p, (unsigned long long)at, (unsigned long long)b, n,
                        EMM_TRACE_BLOCK_RECORDS);
    if (n > r->info.accesses - r->seen)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: byte %llu: block %llu has more records than the header's %llu", p,
                        (unsigned long long)at, (unsigned long long)b,
                        (unsigned long long)r->info.accesses);
    const unsigned ncols = r->ncols;
    if (raw_size < emm_trace_column_table(ncols) || raw_size > max_raw_size(n, ncols) ||
        (r->info.compressed ? stored > ZSTD_compressBound(raw_size) || stored == 0
                            : stored != raw_size))
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: block %llu has invalid sizes (raw %u, stored %u)",
                        p, (unsigned long long)at, (unsigned long long)b, raw_size, stored);

    /* Payload: read into `stored`, decompress into `raw` (or read straight
     * into `raw`); both keep 8 bytes of slack for the unpacking loads. */
    uint8_t *in = NULL;
    if (r->info.compressed) {
        if (stored > r->stored_cap) {
            free(r->stored);
            r->stored = malloc(stored);
            r->stored_cap = r->stored ? stored : 0;
        }
        in = r->stored;
    }
    if ((size_t)raw_size + 8 > r->raw_cap) {
        free(r->raw);
        r->raw = malloc((size_t)raw_size + 8);
        r->raw_cap = r->raw ? (size_t)raw_size + 8 : 0;
    }
    if (!r->raw || (r->info.compressed && !r->stored))
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for a block", p);
    if (!in)
        in = r->raw;
    const uint64_t pat = r->pos;
    snprintf(what, sizeof what, "block %llu payload", (unsigned long long)b);
    if ((s = read_exact(r, in, stored, what, err)) != EMM_OK)
        return s;
    if (emm_le64(h + EMM_TB_PAYLOAD_SUM) != emm_trace_hash(in, stored, 0))
        return emm_fail(err, EMM_ERR_CORRUPT, "%s: byte %llu: block %llu payload checksum mismatch",
                        p, (unsigned long long)pat, (unsigned long long)b);
    uint8_t *raw = r->raw;
    if (r->info.compressed) {
        size_t got = ZSTD_decompressDCtx(r->dctx, raw, raw_size, in, stored);
        if (ZSTD_isError(got))
            return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: block %llu: zstd: %s", p,
                            (unsigned long long)pat, (unsigned long long)b, ZSTD_getErrorName(got));
        if (got != raw_size)
            return emm_fail(err, EMM_ERR_FORMAT,
                            "%s: byte %llu: block %llu decompresses to %zu bytes, not %u", p,
                            (unsigned long long)pat, (unsigned long long)b, got, raw_size);
    }
    memset(raw + raw_size, 0, 8);

    /* Column table. */
    unsigned bits[EMM_TRACE_MAX_COLUMNS];
    uint64_t min[EMM_TRACE_MAX_COLUMNS];
    const uint8_t *col[EMM_TRACE_MAX_COLUMNS];
    size_t off = emm_trace_column_table(ncols);
    int unused_widths = 0; /* the width bytes past the last column must be 0 */
    for (unsigned c = ncols; c < 8; c++)
        unused_widths |= raw[c];
    for (int c = 0; c < (int)ncols; c++) {
        bits[c] = raw[c];
        min[c] = emm_le64(raw + 8 + 8 * c);
        if (bits[c] > EMM_TRACE_MAX_PACKED_BITS && bits[c] != 64)
            return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: block %llu: column %d has width %u",
                            p, (unsigned long long)pat, (unsigned long long)b, c, bits[c]);
        col[c] = raw + off;
        off += stream_bytes(n, bits[c]);
    }
    if (unused_widths != 0 || off != raw_size)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: byte %llu: block %llu: column sizes add up to %zu bytes, payload has %u",
                        p, (unsigned long long)pat, (unsigned long long)b, off, raw_size);

    emm_trace_record *out = dst;
    *into_dst = 1;
    if (n > dst_cap) {
        if (!r->recs && !(r->recs = malloc(EMM_TRACE_BLOCK_RECORDS * sizeof *r->recs)))
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for a block", p);
        out = r->recs;
        *into_dst = 0;
    }

    /* Decode in chunks of CHUNK records: unpack every column, then assemble
     * and check the records (the checks' branches are never taken on a good
     * file, so they cost little). */
    const uint32_t na = r->info.narrays;
    if (na == 0)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: block %llu has records but the trace has no arrays",
                        p, (unsigned long long)at, (unsigned long long)b);
    const uint64_t *maxe = r->maxe, *rsize = r->rsize, *maxb = r->maxb;
    uint64_t *prev = r->prev;
    memset(prev, 0, (size_t)na * sizeof *prev);
    /* The fields with fixed bounds are checked per column: a column whose
     * frame (minimum + largest packed value) lies within the bounds needs no
     * per-value check, which is always so for files emm wrote unless a field
     * spans its whole 32-bit range. */
    static const uint64_t lo[EMM_TRACE_MAX_COLUMNS] = {0, 0, 0, 1, 0, 0, 0};
    uint64_t hi[EMM_TRACE_MAX_COLUMNS] = {0, 0, 0, EMM_TRACE_MAX_ACCESS_BYTES, UINT32_MAX, 1,
                                           UINT64_MAX};
    hi[EMM_COL_ARRAY] = na - 1;
    int scan[EMM_TRACE_MAX_COLUMNS] = {0};
    for (int c = 0; c < (int)ncols; c++) {
        if (c == EMM_COL_DELTA || c == EMM_COL_OFFSET || c == EMM_COL_PC)
            continue;
        uint64_t span = bits[c] == 64 ? UINT64_MAX : (UINT64_C(1) << bits[c]) - 1;
        scan[c] = min[c] < lo[c] || min[c] > hi[c] || span > hi[c] - min[c];
    }
    uint64_t writes = 0;
    for (uint32_t i0 = 0; i0 < n; i0 += CHUNK) {
        uint32_t m = n - i0 < CHUNK ? n - i0 : CHUNK;
        for (int c = 0; c < (int)ncols; c++)
            unpack_column(col[c], bits[c], min[c], i0, m, r->tmp[c]);
        for (int c = 0; c < (int)ncols; c++)
            if (__builtin_expect(scan[c], 0))
                for (uint32_t i = 0; i < m; i++)
                    if (r->tmp[c][i] < lo[c] || r->tmp[c][i] > hi[c]) {
                        const uint64_t *t = &r->tmp[0][i];
                        return describe_bad_record(r, t[0 * CHUNK], 0, 0, t[2 * CHUNK],
                                                   t[3 * CHUNK], t[4 * CHUNK], t[5 * CHUNK],
                                                   r->seen + i0 + i, pat, b, err);
                    }
        const uint64_t *ca = r->tmp[EMM_COL_ARRAY], *cd = r->tmp[EMM_COL_DELTA],
                       *co = r->tmp[EMM_COL_OFFSET], *cb = r->tmp[EMM_COL_BYTES],
                       *cw = r->tmp[EMM_COL_WORK], *cx = r->tmp[EMM_COL_WRITE];
        /* Element and offset depend on the array: checked per record, the
         * flag tested once per chunk. */
        uint64_t bad = 0;
        emm_trace_record *o = out + i0;
        for (uint32_t i = 0; i < m; i++) {
            uint64_t a = ca[i];
            uint64_t e = prev[a] + cd[i];
            prev[a] = e;
            /* The last test is for raw arrays (element = address): a
             * tagged array's records all lie below 2^64 (check_arrays). */
            bad |= (uint64_t)(e > maxe[a]) | (uint64_t)(co[i] >= rsize[a]) | (uint64_t)(cb[i] > maxb[a]) |
                   (uint64_t)(e + (cb[i] - 1) < e);
            o[i].element = e;
            o[i].array = (uint32_t)a;
            o[i].offset = (uint32_t)co[i];
            o[i].bytes = (uint32_t)cb[i];
            o[i].work = (uint32_t)cw[i];
            o[i].write = (uint8_t)cx[i];
            writes += cx[i];
        }
        if (ncols > EMM_COL_PC)
            for (uint32_t i = 0; i < m; i++)
                o[i].pc = r->tmp[EMM_COL_PC][i];
        else
            for (uint32_t i = 0; i < m; i++)
                o[i].pc = 0;
        if (__builtin_expect(bad != 0, 0))
            for (uint32_t i = 0; i < m; i++)
                if (o[i].element > maxe[o[i].array] || co[i] >= rsize[o[i].array] ||
                    cb[i] > maxb[o[i].array] || o[i].element + (cb[i] - 1) < o[i].element)
                    return describe_bad_record(r, o[i].array, 1, o[i].element, co[i], cb[i],
                                               cw[i], cx[i], r->seen + i0 + i, pat, b, err);
    }
    r->seen += n;
    r->seen_writes += writes;
    r->block++;
    *nrec = n;
    return EMM_OK;
}

/* After the last block: the counts must match the header and nothing may
 * follow. */
static emm_status check_end(emm_trace_reader *r, emm_error *err)
{
    if (r->seen != r->info.accesses)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: byte %llu: the blocks hold %llu records, the header says %llu",
                        r->path, (unsigned long long)r->pos, (unsigned long long)r->seen,
                        (unsigned long long)r->info.accesses);
    if (r->seen_writes != r->info.writes)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: byte %llu: the blocks hold %llu writes, the header says %llu", r->path,
                        (unsigned long long)r->pos, (unsigned long long)r->seen_writes,
                        (unsigned long long)r->info.writes);
    if (r->pos != r->file_size)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: byte %llu: %llu unexpected bytes after the last block",
                        r->path, (unsigned long long)r->pos,
                        (unsigned long long)(r->file_size - r->pos));
    return EMM_OK;
}

emm_status emm_trace_read(emm_trace_reader *r, emm_trace_record *buf, size_t cap, size_t *n,
                          emm_error *err)
{
    assert(buf && cap > 0);
    *n = 0;
    if (r->failed)
        return emm_fail(err, r->failed, "%s", r->failed_msg);
    size_t got = 0;
    while (got < cap) {
        if (r->next < r->nrecs) {
            size_t k = r->nrecs - r->next;
            if (k > cap - got)
                k = cap - got;
            memcpy(buf + got, r->recs + r->next, k * sizeof *buf);
            r->next += (uint32_t)k;
            got += k;
            continue;
        }
        if (r->block == r->info.blocks) {
            emm_status s = check_end(r, err);
            if (s != EMM_OK)
                return reader_fail(r, err, s);
            break;
        }
        uint32_t nb = 0;
        int direct = 0;
        emm_status s = next_block(r, buf + got, cap - got, &nb, &direct, err);
        if (s != EMM_OK)
            return reader_fail(r, err, s);
        if (direct) {
            got += nb;
        } else {
            r->nrecs = nb;
            r->next = 0;
        }
    }
    *n = got;
    return EMM_OK;
}

emm_status emm_trace_rewind(emm_trace_reader *r, emm_error *err)
{
    if (fseeko(r->f, (off_t)r->data_start, SEEK_SET) != 0)
        return emm_fail(err, EMM_ERR_IO, "%s: cannot seek: %s", r->path, strerror(errno));
    r->pos = r->data_start;
    r->block = 0;
    r->seen = r->seen_writes = 0;
    r->nrecs = r->next = 0;
    r->failed = EMM_OK;
    return EMM_OK;
}

const char *emm_trace_kind_name(emm_array_kind kind)
{
    return kind_name(kind);
}
