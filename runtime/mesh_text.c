/* ASCII OFF and OBJ readers (see mesh_io.h for why emm parses these two
 * itself rather than through OpenMesh). They produce the raw polygon soup of
 * mesh_io.h with the line of every face, so mesh.c can point at it. Numbers
 * are read with strtod into doubles, so an OFF file written by
 * emm_mesh_write_off (%.17g) reads back bit for bit. Each vertex and face is
 * one line, as OFF and OBJ writers emit them; '#' starts a comment. */
#include "mesh_io.h"

#include "error.h"

#include <ctype.h>
#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/* ---- lines and numbers -------------------------------------------------- */

typedef struct cursor {
    const char *p, *end;
    size_t line;  /* number of the line last returned */
    char *buf;    /* that line, without its comment, NUL-terminated */
    size_t cap;
    bool nomem;
} cursor;

/* Moves to the next line that has something besides blanks and a comment
 * and copies it into c->buf without the comment (so strtod stops at its
 * end); false at the end of the data or when memory runs out (c->nomem). */
static bool next_line(cursor *c)
{
    while (c->p < c->end) {
        const char *nl = memchr(c->p, '\n', (size_t)(c->end - c->p));
        const char *stop = nl ? nl : c->end;
        const char *hash = memchr(c->p, '#', (size_t)(stop - c->p));
        const char *text_end = hash ? hash : stop;
        size_t n = (size_t)(text_end - c->p);
        if (!emm_raw_grow((void **)&c->buf, &c->cap, n + 1, 1)) {
            c->nomem = true;
            return false;
        }
        memcpy(c->buf, c->p, n);
        c->buf[n] = '\0';
        c->line++;
        c->p = nl ? nl + 1 : c->end;
        for (size_t i = 0; i < n; i++)
            if (!isspace((unsigned char)c->buf[i]))
                return true;
    }
    return false;
}

static bool at_token_end(const char *s)
{
    return *s == '\0' || *s == ' ' || *s == '\t' || *s == '\r' || *s == '\f' || *s == '\v';
}

static bool read_double(const char **s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(*s, &end);
    if (end == *s || !at_token_end(end))
        return false;
    /* An underflow to a tiny number is still the number the file wrote;
     * an overflow becomes infinity and is reported as non-finite later. */
    *out = v;
    *s = end;
    return true;
}

static bool read_int(const char **s, long long *out, bool token_end)
{
    char *end;
    errno = 0;
    long long v = strtoll(*s, &end, 10);
    if (end == *s || errno == ERANGE || (token_end && !at_token_end(end)))
        return false;
    *out = v;
    *s = end;
    return true;
}

static const char *skip_blank(const char *s)
{
    while (*s == ' ' || *s == '\t' || *s == '\r' || *s == '\f' || *s == '\v')
        s++;
    return s;
}

static emm_status out_of_memory(const char *path, emm_error *err)
{
    return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
}

/* ---- OFF ---------------------------------------------------------------- */

/* The header keyword: OFF with the optional ST (texture), C (colour) and N
 * (normal) prefixes, whose extra per-vertex values are skipped. 4OFF and
 * nOFF (other dimensions) are not 3D triangle meshes. */
static bool off_keyword(const char *s, size_t n)
{
    size_t i = 0;
    if (n - i >= 2 && s[i] == 'S' && s[i + 1] == 'T')
        i += 2;
    if (i < n && s[i] == 'C')
        i++;
    if (i < n && s[i] == 'N')
        i++;
    return n - i == 3 && memcmp(s + i, "OFF", 3) == 0;
}

static emm_status parse_off(const char *path, cursor *c, emm_raw_builder *b, emm_error *err)
{
    if (!next_line(c))
        return emm_fail(err, EMM_ERR_FORMAT, "%s: empty file (no OFF header)", path);
    const char *s = skip_blank(c->buf);
    size_t kw = strcspn(s, " \t\r\f\v");
    if (!off_keyword(s, kw))
        return emm_fail(err, EMM_ERR_FORMAT, "%s: line %zu: not an OFF file (the header is not \"OFF\")",
                        path, c->line);
    s = skip_blank(s + kw);
    if (strncmp(s, "BINARY", 6) == 0)
        return EMM_ERR_UNSUPPORTED;
    if (*s == '\0') {
        if (!next_line(c))
            return emm_fail(err, EMM_ERR_FORMAT,
                            "%s: truncated: the OFF header has no vertex and face counts", path);
        s = c->buf;
    }
    long long nv, nf, ne = 0;
    s = skip_blank(s);
    if (!read_int(&s, &nv, true) || !read_int(&s, &nf, true) || nv < 0 || nf < 0 ||
        (*skip_blank(s) && !read_int(&s, &ne, true)) || *skip_blank(s))
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: line %zu: malformed OFF counts (want \"vertices faces edges\")", path, c->line);
    if (nv > INT32_MAX || nf > INT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE, "%s: line %zu: the header declares %lld vertices and %lld faces; "
                        "emm takes at most %d of each", path, c->line, nv, nf, INT32_MAX);

    for (long long i = 0; i < nv; i++) {
        if (!next_line(c))
            return emm_fail(err, EMM_ERR_FORMAT, "%s: truncated: header declares %lld vertices, file has %lld",
                            path, nv, i);
        double v[3];
        s = skip_blank(c->buf);
        for (int k = 0; k < 3; k++) {
            if (!read_double(&s, &v[k]))
                return emm_fail(err, EMM_ERR_FORMAT,
                                "%s: line %zu: vertex %lld: expected three coordinates", path, c->line, i);
            s = skip_blank(s);
        }
        if (!emm_raw_add_vertex(b, v))
            return out_of_memory(path, err);
    }
    for (long long f = 0; f < nf; f++) {
        if (!next_line(c))
            return emm_fail(err, EMM_ERR_FORMAT, "%s: truncated: header declares %lld faces, file has %lld",
                            path, nf, f);
        long long k;
        s = skip_blank(c->buf);
        if (!read_int(&s, &k, true) || k < 0)
            return emm_fail(err, EMM_ERR_FORMAT,
                            "%s: line %zu: face %lld: expected a corner count", path, c->line, f);
        for (long long j = 0; j < k; j++) {
            long long idx;
            s = skip_blank(s);
            if (!read_int(&s, &idx, true))
                return emm_fail(err, EMM_ERR_FORMAT,
                                "%s: line %zu: face %lld: expected %lld vertex indices, found %lld",
                                path, c->line, f, k, j);
            if (!emm_raw_add_corner(b, idx))
                return out_of_memory(path, err);
        }
        /* Anything after the indices is a face colour, which emm ignores. */
        if (!emm_raw_end_face(b, c->line))
            return out_of_memory(path, err);
    }
    if (next_line(c))
        return emm_fail(err, EMM_ERR_FORMAT, "%s: line %zu: unexpected data after the %lld faces the header declares",
                        path, c->line, nf);
    return EMM_OK;
}

emm_status emm_read_off(const char *path, const char *data, size_t len, emm_raw_mesh *raw, emm_error *err)
{
    memset(raw, 0, sizeof *raw);
    cursor c = { .p = data, .end = data + len };
    emm_raw_builder b = { .raw = raw, .lines = true };
    emm_status st = parse_off(path, &c, &b, err);
    if (st != EMM_OK && st != EMM_ERR_NOMEM && c.nomem)
        st = out_of_memory(path, err);
    free(c.buf);
    if (st != EMM_OK)
        emm_raw_mesh_free(raw);
    return st;
}

/* ---- OBJ ---------------------------------------------------------------- */

static emm_status parse_obj(const char *path, cursor *c, emm_raw_builder *b, emm_error *err)
{
    emm_raw_mesh *r = b->raw;
    while (next_line(c)) {
        const char *s = skip_blank(c->buf);
        size_t kw = strcspn(s, " \t\r\f\v");
        if (kw == 1 && s[0] == 'v') {
            double v[3];
            s = skip_blank(s + 1);
            for (int k = 0; k < 3; k++) {
                if (!read_double(&s, &v[k]))
                    return emm_fail(err, EMM_ERR_FORMAT, "%s: line %zu: vertex %zu: expected three coordinates",
                                    path, c->line, r->nv + 1);
                s = skip_blank(s);
            }
            if (!emm_raw_add_vertex(b, v))
                return out_of_memory(path, err);
        } else if (kw == 1 && s[0] == 'f') {
            s = skip_blank(s + 1);
            while (*s) {
                /* A corner is v, v/vt, v//vn or v/vt/vn; only v matters.
                 * Negative indices count back from the latest vertex. */
                long long idx;
                if (!read_int(&s, &idx, false) || !(at_token_end(s) || *s == '/'))
                    return emm_fail(err, EMM_ERR_FORMAT, "%s: line %zu: face %zu: malformed vertex index",
                                    path, c->line, r->nf + 1);
                if (idx == 0)
                    return emm_fail(err, EMM_ERR_FORMAT,
                                    "%s: line %zu: face %zu: vertex index 0 (OBJ counts from 1)",
                                    path, c->line, r->nf + 1);
                int64_t v = idx > 0 ? idx - 1 : (int64_t)r->nv + idx;
                if (idx < 0 && v < 0)
                    return emm_fail(err, EMM_ERR_MESH,
                                    "%s: line %zu: face %zu refers to vertex %lld, but only %zu vertices precede it",
                                    path, c->line, r->nf + 1, idx, r->nv);
                if (!emm_raw_add_corner(b, v))
                    return out_of_memory(path, err);
                s += strcspn(s, " \t\r\f\v");
                s = skip_blank(s);
            }
            if (!emm_raw_end_face(b, c->line))
                return out_of_memory(path, err);
        }
        /* vt, vn, g, o, s, usemtl, mtllib, l, p: not part of the model. */
    }
    return EMM_OK;
}

emm_status emm_read_obj(const char *path, const char *data, size_t len, emm_raw_mesh *raw, emm_error *err)
{
    memset(raw, 0, sizeof *raw);
    raw->index_base = 1;
    cursor c = { .p = data, .end = data + len };
    emm_raw_builder b = { .raw = raw, .lines = true };
    emm_status st = parse_obj(path, &c, &b, err);
    if (st == EMM_OK && c.nomem)
        st = out_of_memory(path, err);
    else if (st != EMM_OK && st != EMM_ERR_NOMEM && c.nomem)
        st = out_of_memory(path, err);
    free(c.buf);
    if (st != EMM_OK) {
        emm_raw_mesh_free(raw);
        raw->index_base = 1;
    }
    return st;
}

/* ---- binary OFF ---------------------------------------------------------- */

static emm_status parse_off_binary(const char *path, const char *data, size_t len, emm_raw_builder *b,
                                   emm_error *err)
{
    /* The first line: [ST][N]OFF BINARY, nothing else. */
    const char *nl = memchr(data, '\n', len);
    size_t head = nl ? (size_t)(nl - data) : len;
    const char *s = skip_blank(data);
    size_t kw = 0;
    while (s + kw < data + head && !isspace((unsigned char)s[kw]))
        kw++;
    const char *rest = s + kw;
    while (rest < data + head && isspace((unsigned char)*rest))
        rest++;
    const char *word_end = rest;
    while (word_end < data + head && !isspace((unsigned char)*word_end))
        word_end++;
    const char *after = word_end;
    while (after < data + head && isspace((unsigned char)*after))
        after++;
    if (!off_keyword(s, kw) || word_end - rest != 6 || memcmp(rest, "BINARY", 6) != 0 ||
        after != data + head)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: line 1: not an OFF file (expected \"OFF BINARY\")", path);
    if (memchr(s, 'C', kw))
        return emm_fail(err, EMM_ERR_UNSUPPORTED,
                        "%s: binary OFF with vertex colours (COFF) is not supported", path);
    size_t st_extra = kw >= 2 && s[0] == 'S' && s[1] == 'T' ? 2 : 0; /* texture u, v */
    size_t n_extra = memchr(s, 'N', kw) ? 3 : 0;                      /* a normal */
    size_t vertex_bytes = 4 * (3 + n_extra + st_extra);

    const unsigned char *p = (const unsigned char *)data + head + (nl ? 1 : 0);
    const unsigned char *end = (const unsigned char *)data + len;
    if (end - p < 12)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: truncated: the binary OFF header has no vertex and face counts",
                        path);
    uint32_t nv = emm_raw_le32(p), nf = emm_raw_le32(p + 4);
    p += 12; /* and the edge count, which nothing needs */
    if (nv > INT32_MAX || nf > INT32_MAX)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: the header declares %u vertices and %u faces; "
                        "emm takes at most %d of each", path, nv, nf, INT32_MAX);
    /* Every vertex and face must fit in what follows (a face takes at least
     * its 4-byte count) before anything is read. */
    uint64_t left = (uint64_t)(end - p);
    if ((uint64_t)nv * vertex_bytes + (uint64_t)nf * 4 > left)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: truncated: the data ends before the %u vertices and %u faces the header declares",
                        path, nv, nf);
    for (uint32_t i = 0; i < nv; i++, p += vertex_bytes) {
        double v[3];
        for (int k = 0; k < 3; k++) {
            uint32_t bits = emm_raw_le32(p + 4 * k);
            float c;
            memcpy(&c, &bits, 4);
            v[k] = c;
        }
        if (!emm_raw_add_vertex(b, v))
            return out_of_memory(path, err);
    }
    for (uint32_t f = 0; f < nf; f++) {
        uint32_t k = (uint32_t)(end - p) >= 4 ? emm_raw_le32(p) : UINT32_MAX;
        if (k == UINT32_MAX || (uint64_t)k * 4 > (uint64_t)(end - p) - 4 ||
            (uint64_t)(nf - f - 1) * 4 > (uint64_t)(end - p) - 4 - (uint64_t)k * 4)
            return emm_fail(err, EMM_ERR_FORMAT,
                            "%s: truncated: the data ends before the %u vertices and %u faces the header declares",
                            path, nv, nf);
        p += 4;
        for (uint32_t j = 0; j < k; j++, p += 4)
            if (!emm_raw_add_corner(b, (int32_t)emm_raw_le32(p)))
                return out_of_memory(path, err);
        if (!emm_raw_end_face(b, 0))
            return out_of_memory(path, err);
    }
    if (p != end)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: %zu unexpected bytes after the %u faces the header declares",
                        path, (size_t)(end - p), nf);
    return EMM_OK;
}

emm_status emm_read_off_binary(const char *path, const char *data, size_t len, emm_raw_mesh *raw,
                               emm_error *err)
{
    memset(raw, 0, sizeof *raw);
    emm_raw_builder b = { .raw = raw };
    emm_status st = parse_off_binary(path, data, len, &b, err);
    if (st != EMM_OK)
        emm_raw_mesh_free(raw);
    return st;
}
