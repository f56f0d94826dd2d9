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

void emm_raw_mesh_free(emm_raw_mesh *raw)
{
    if (!raw)
        return;
    free(raw->xyz);
    free(raw->corner);
    free(raw->face_start);
    free(raw->face_line);
    memset(raw, 0, sizeof *raw);
}

/* ---- growing the raw arrays ---------------------------------------------- */

typedef struct builder {
    emm_raw_mesh *raw;
    size_t ncorner;
    size_t cap_v, cap_c, cap_f, cap_l;
} builder;

static bool grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return true;
    size_t n = *cap ? *cap : 256;
    while (n < need) {
        if (n > SIZE_MAX / 4 / elem)
            return false;
        n *= 2;
    }
    void *q = realloc(*p, n * elem);
    if (!q)
        return false;
    *p = q;
    *cap = n;
    return true;
}

static bool add_vertex(builder *b, const double v[3])
{
    emm_raw_mesh *r = b->raw;
    if (!grow((void **)&r->xyz, &b->cap_v, 3 * (r->nv + 1), sizeof(double)))
        return false;
    memcpy(r->xyz + 3 * r->nv, v, 3 * sizeof(double));
    r->nv++;
    return true;
}

static bool add_corner(builder *b, int64_t v)
{
    if (!grow((void **)&b->raw->corner, &b->cap_c, b->ncorner + 1, sizeof(int64_t)))
        return false;
    b->raw->corner[b->ncorner++] = v;
    return true;
}

/* Closes the face whose corners were added since the previous one. */
static bool end_face(builder *b, size_t line)
{
    emm_raw_mesh *r = b->raw;
    if (!grow((void **)&r->face_start, &b->cap_f, r->nf + 2, sizeof(size_t)))
        return false;
    if (!grow((void **)&r->face_line, &b->cap_l, r->nf + 2, sizeof(size_t)))
        return false;
    if (r->nf == 0)
        r->face_start[0] = 0;
    r->face_line[r->nf] = line;
    r->face_start[++r->nf] = b->ncorner;
    return true;
}

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
        if (!grow((void **)&c->buf, &c->cap, n + 1, 1)) {
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

static emm_status parse_off(const char *path, cursor *c, builder *b, emm_error *err)
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
        if (!add_vertex(b, v))
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
            if (!add_corner(b, idx))
                return out_of_memory(path, err);
        }
        /* Anything after the indices is a face colour, which emm ignores. */
        if (!end_face(b, c->line))
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
    builder b = { .raw = raw };
    emm_status st = parse_off(path, &c, &b, err);
    if (st != EMM_OK && st != EMM_ERR_NOMEM && c.nomem)
        st = out_of_memory(path, err);
    free(c.buf);
    if (st != EMM_OK)
        emm_raw_mesh_free(raw);
    return st;
}

/* ---- OBJ ---------------------------------------------------------------- */

static emm_status parse_obj(const char *path, cursor *c, builder *b, emm_error *err)
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
            if (!add_vertex(b, v))
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
                if (!add_corner(b, v))
                    return out_of_memory(path, err);
                s += strcspn(s, " \t\r\f\v");
                s = skip_blank(s);
            }
            if (!end_face(b, c->line))
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
    builder b = { .raw = raw };
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
