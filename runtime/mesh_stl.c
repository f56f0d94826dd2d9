/* STL files, binary and ASCII. STL lists each facet's three corners by
 * their coordinates; corners with the same coordinates (-0 taken as 0)
 * become one vertex, through an open-addressing table, so the triangles
 * share vertices and edges as the surface does.
 *
 * A file of exactly 84 + 50 x (its facet count) bytes is binary; otherwise
 * one that starts with "solid" is ASCII (binary files often start with
 * "solid" too, hence the size test first). */
#include "mesh_io.h"

#include "error.h"

#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#define STL_TOKEN_MAX 64

typedef struct stl_reader {
    const char *path;
    emm_raw_builder b;
    uint32_t *slot; /* vertex index + 1, 0 for an empty slot */
    size_t nslot;
    emm_error *err;
} stl_reader;

static uint64_t mix(const double v[3])
{
    uint64_t h = 0x9e3779b97f4a7c15u;
    for (int k = 0; k < 3; k++) {
        uint64_t bits;
        double c = v[k] == 0 ? 0.0 : v[k];
        memcpy(&bits, &c, 8);
        h = (h ^ bits) * 0xff51afd7ed558ccdu;
        h ^= h >> 32;
    }
    return h;
}

static bool same(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++) {
        double x = a[k] == 0 ? 0.0 : a[k], y = b[k] == 0 ? 0.0 : b[k];
        if (memcmp(&x, &y, 8) != 0)
            return false;
    }
    return true;
}

/* The vertex at v, added when new; -1 when memory runs out. */
static int64_t vertex_at(stl_reader *r, const double v[3])
{
    emm_raw_mesh *raw = r->b.raw;
    if (2 * (raw->nv + 1) > r->nslot) {
        size_t n = r->nslot ? 2 * r->nslot : 1024;
        uint32_t *slot = calloc(n, sizeof *slot);
        if (!slot || raw->nv >= UINT32_MAX - 1) {
            free(slot);
            return -1;
        }
        for (size_t i = 0; i < raw->nv; i++) {
            size_t h = (size_t)mix(raw->xyz + 3 * i) & (n - 1);
            while (slot[h])
                h = (h + 1) & (n - 1);
            slot[h] = (uint32_t)i + 1;
        }
        free(r->slot);
        r->slot = slot;
        r->nslot = n;
    }
    size_t h = (size_t)mix(v) & (r->nslot - 1);
    while (r->slot[h]) {
        uint32_t i = r->slot[h] - 1;
        if (same(raw->xyz + 3 * (size_t)i, v))
            return i;
        h = (h + 1) & (r->nslot - 1);
    }
    if (!emm_raw_add_vertex(&r->b, v))
        return -1;
    r->slot[h] = (uint32_t)raw->nv;
    return (int64_t)raw->nv - 1;
}

static emm_status add_facet(stl_reader *r, double corner[3][3], size_t line)
{
    for (int k = 0; k < 3; k++) {
        int64_t v = vertex_at(r, corner[k]);
        if (v < 0 || !emm_raw_add_corner(&r->b, v))
            return emm_fail(r->err, EMM_ERR_NOMEM, "%s: out of memory", r->path);
    }
    if (!emm_raw_end_face(&r->b, line))
        return emm_fail(r->err, EMM_ERR_NOMEM, "%s: out of memory", r->path);
    return EMM_OK;
}

static emm_status read_binary(stl_reader *r, const unsigned char *data, uint32_t facets)
{
    for (uint32_t f = 0; f < facets; f++) {
        const unsigned char *rec = data + 84 + 50 * (size_t)f + 12; /* after the normal */
        double corner[3][3];
        for (int k = 0; k < 9; k++) {
            uint32_t bits = emm_raw_le32(rec + 4 * k);
            float c;
            memcpy(&c, &bits, 4);
            corner[k / 3][k % 3] = c;
        }
        emm_status st = add_facet(r, corner, 0);
        if (st != EMM_OK)
            return st;
    }
    return EMM_OK;
}

/* ---- ASCII -------------------------------------------------------------- */

typedef struct stl_text {
    const char *p, *end;
    size_t line; /* of the token last read */
    char tok[STL_TOKEN_MAX + 1];
} stl_text;

/* The next blank-separated token; false at the end of the data or for a
 * token too long to be a keyword or a number. */
static bool token(stl_text *t)
{
    while (t->p < t->end && isspace((unsigned char)*t->p)) {
        if (*t->p == '\n')
            t->line++;
        t->p++;
    }
    size_t n = 0;
    while (t->p < t->end && !isspace((unsigned char)*t->p)) {
        if (n == STL_TOKEN_MAX)
            return false;
        t->tok[n++] = *t->p++;
    }
    t->tok[n] = '\0';
    return n > 0;
}

static void skip_line(stl_text *t)
{
    const char *nl = memchr(t->p, '\n', (size_t)(t->end - t->p));
    t->p = nl ? nl : t->end;
}

static emm_status expect(stl_reader *r, stl_text *t, const char *want, size_t facet)
{
    if (token(t) && strcmp(t->tok, want) == 0)
        return EMM_OK;
    if (t->p >= t->end && t->tok[0] == '\0')
        return emm_fail(r->err, EMM_ERR_FORMAT, "%s: truncated: the data ends in facet %zu", r->path, facet);
    return emm_fail(r->err, EMM_ERR_FORMAT, "%s: line %zu: facet %zu: expected '%s'", r->path, t->line,
                    facet, want);
}

static emm_status numbers(stl_reader *r, stl_text *t, double *v, size_t facet)
{
    for (int k = 0; k < 3; k++) {
        char *stop;
        if (!token(t)) {
            if (t->p >= t->end && t->tok[0] == '\0')
                return emm_fail(r->err, EMM_ERR_FORMAT, "%s: truncated: the data ends in facet %zu", r->path,
                                facet);
            return emm_fail(r->err, EMM_ERR_FORMAT, "%s: line %zu: facet %zu: expected a number", r->path,
                            t->line, facet);
        }
        v[k] = strtod(t->tok, &stop);
        if (*stop != '\0')
            return emm_fail(r->err, EMM_ERR_FORMAT, "%s: line %zu: facet %zu: '%s' is not a number",
                            r->path, t->line, facet, t->tok);
    }
    return EMM_OK;
}

static emm_status read_ascii(stl_reader *r, const char *data, size_t len)
{
    stl_text t = { .p = data, .end = data + len, .line = 1 };
    size_t facet = 0;
    bool in_solid = false;
    emm_status st = EMM_OK;
    while (st == EMM_OK) {
        if (!token(&t)) {
            if (t.p < t.end)
                return emm_fail(r->err, EMM_ERR_FORMAT, "%s: line %zu: a word too long for STL", r->path,
                                t.line);
            if (in_solid)
                return emm_fail(r->err, EMM_ERR_FORMAT, "%s: truncated: no 'endsolid' after facet %zu",
                                r->path, facet);
            return EMM_OK;
        }
        if (!in_solid) {
            if (strcmp(t.tok, "solid") != 0)
                return emm_fail(r->err, EMM_ERR_FORMAT, "%s: line %zu: expected 'solid'", r->path, t.line);
            skip_line(&t); /* the solid's name */
            in_solid = true;
            continue;
        }
        if (strcmp(t.tok, "endsolid") == 0) {
            skip_line(&t);
            in_solid = false;
            continue;
        }
        if (strcmp(t.tok, "facet") != 0)
            return emm_fail(r->err, EMM_ERR_FORMAT, "%s: line %zu: expected 'facet' or 'endsolid'", r->path,
                            t.line);
        facet++;
        double normal[3], corner[3][3];
        size_t line = t.line;
        if ((st = expect(r, &t, "normal", facet)) != EMM_OK || (st = numbers(r, &t, normal, facet)) != EMM_OK ||
            (st = expect(r, &t, "outer", facet)) != EMM_OK || (st = expect(r, &t, "loop", facet)) != EMM_OK)
            return st;
        for (int k = 0; k < 3; k++)
            if ((st = expect(r, &t, "vertex", facet)) != EMM_OK ||
                (st = numbers(r, &t, corner[k], facet)) != EMM_OK)
                return st;
        if ((st = expect(r, &t, "endloop", facet)) != EMM_OK || (st = expect(r, &t, "endfacet", facet)) != EMM_OK)
            return st;
        st = add_facet(r, corner, line);
    }
    return st;
}

emm_status emm_read_stl(const char *path, const char *data, size_t len, emm_raw_mesh *raw, emm_error *err)
{
    memset(raw, 0, sizeof *raw);
    stl_reader r = { .path = path, .b = { .raw = raw }, .err = err };
    size_t skip = 0;
    while (skip < len && isspace((unsigned char)data[skip]))
        skip++;
    bool says_solid = len - skip >= 5 && memcmp(data + skip, "solid", 5) == 0;
    emm_status st;
    uint32_t facets = len >= 84 ? emm_raw_le32((const unsigned char *)data + 80) : 0;
    uint64_t want = 84 + 50 * (uint64_t)facets;
    if (len >= 84 && len == want) {
        st = read_binary(&r, (const unsigned char *)data, facets);
    } else if (says_solid) {
        r.b.lines = true;
        st = read_ascii(&r, data, len);
    } else if (len < 84) {
        st = emm_fail(err, EMM_ERR_FORMAT, "%s: not an STL file (too short for a binary STL and not ASCII STL)",
                      path);
    } else if (len < want) {
        st = emm_fail(err, EMM_ERR_FORMAT, "%s: truncated: header declares %u facets, file has %llu", path,
                      facets, (unsigned long long)(len - 84) / 50);
    } else {
        st = emm_fail(err, EMM_ERR_FORMAT,
                      "%s: malformed binary STL: header declares %u facets (%llu bytes), file has %zu bytes",
                      path, facets, (unsigned long long)want, len);
    }
    free(r.slot);
    if (st != EMM_OK)
        emm_raw_mesh_free(raw);
    return st;
}
