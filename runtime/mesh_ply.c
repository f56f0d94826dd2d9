/* PLY files (Greg Turk's format, version 1.0): ascii, binary_little_endian
 * and binary_big_endian. The header is read first and checked as a whole
 * — known keywords and types, an end_header within the first
 * PLY_HEADER_MAX bytes, every element's count against the bytes that are
 * left — before any element is read; the data is then walked element by
 * element, every list's length checked against what is left before its
 * items are read. Only the vertex positions and the face corner lists are
 * kept (mesh_io.h says why emm reads PLY itself). */
#include "mesh_io.h"

#include "error.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PLY_HEADER_MAX (64 * 1024) /* bytes before end_header */
#define PLY_MAX_ELEMENTS 16
#define PLY_MAX_PROPERTIES 64      /* per element */
#define PLY_TOKEN_MAX 64           /* an ASCII number's characters */

typedef enum ply_type { T_NONE, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 } ply_type;

static const struct {
    const char *name, *alias;
    unsigned size;
} types[] = {
    [T_I8] = { "char", "int8", 1 },     [T_U8] = { "uchar", "uint8", 1 },
    [T_I16] = { "short", "int16", 2 },  [T_U16] = { "ushort", "uint16", 2 },
    [T_I32] = { "int", "int32", 4 },    [T_U32] = { "uint", "uint32", 4 },
    [T_F32] = { "float", "float32", 4 }, [T_F64] = { "double", "float64", 8 },
};

typedef enum ply_role { R_OTHER, R_X, R_Y, R_Z, R_CORNERS } ply_role;

typedef struct ply_property {
    ply_type type;       /* a scalar's type, or a list's item type */
    ply_type count_type; /* T_NONE for a scalar */
    ply_role role;
} ply_property;

typedef struct ply_element {
    char name[32];
    uint64_t count;
    int nprop;
    ply_property prop[PLY_MAX_PROPERTIES];
    bool vertex, face;
} ply_element;

typedef enum ply_format { F_ASCII, F_LE, F_BE } ply_format;

typedef struct ply_reader {
    const char *path;
    const unsigned char *p, *end; /* the data after end_header */
    ply_format format;
    int nelem;
    ply_element elem[PLY_MAX_ELEMENTS];
    emm_raw_builder b;
    emm_error *err;
} ply_reader;

static emm_status bad_header(ply_reader *r, unsigned line, const char *why, const char *word)
{
    return emm_fail(r->err, EMM_ERR_FORMAT, "%s: not a readable PLY file: header line %u: %s%s%.40s%s",
                    r->path, line, why, word ? " '" : "", word ? word : "", word ? "'" : "");
}

static ply_type type_named(const char *s)
{
    for (int t = T_I8; t <= T_F64; t++)
        if (strcmp(s, types[t].name) == 0 || strcmp(s, types[t].alias) == 0)
            return (ply_type)t;
    return T_NONE;
}

/* The next blank-separated word of a header line into w (at most cap - 1
 * characters); false at the end of the line or for a longer word. */
static bool word(const char **s, const char *end, char *w, size_t cap)
{
    const char *p = *s;
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r'))
        p++;
    size_t n = 0;
    while (p < end && *p != ' ' && *p != '\t' && *p != '\r') {
        if (n + 1 >= cap)
            return false;
        w[n++] = *p++;
    }
    w[n] = '\0';
    *s = p;
    return n > 0;
}

/* The fewest bytes one record of e can take: binary sizes, or in ASCII two
 * characters (a digit and a separator) per value. */
static uint64_t min_record(const ply_reader *r, const ply_element *e)
{
    uint64_t n = 0;
    for (int i = 0; i < e->nprop; i++) {
        const ply_property *q = &e->prop[i];
        ply_type t = q->count_type != T_NONE ? q->count_type : q->type;
        n += r->format == F_ASCII ? 2 : types[t].size;
    }
    return n;
}

static emm_status parse_header(ply_reader *r, const char *data, size_t len)
{
    const char *p = data, *end = data + len;
    const char *limit = len < PLY_HEADER_MAX ? end : data + PLY_HEADER_MAX;
    bool format = false, done = false;
    unsigned line = 0;
    while (!done) {
        const char *nl = memchr(p, '\n', (size_t)(limit - p));
        if (!nl && limit == end)
            return emm_fail(r->err, EMM_ERR_FORMAT,
                            "%s: not a readable PLY file: the file ends before an end_header line", r->path);
        if (!nl)
            return emm_fail(r->err, EMM_ERR_FORMAT,
                            "%s: not a readable PLY file: no end_header line in the first %d bytes", r->path,
                            PLY_HEADER_MAX);
        line++;
        const char *s = p;
        p = nl + 1;
        char kw[32], a[32], b[32], c[32], d[32];
        if (!word(&s, nl, kw, sizeof kw)) {
            if (line == 1 || s < nl)
                return bad_header(r, line, line == 1 ? "the file does not start with \"ply\""
                                                     : "unknown keyword (too long)", NULL);
            continue; /* a blank line */
        }
        if (line == 1) {
            if (strcmp(kw, "ply") != 0 || word(&s, nl, a, sizeof a))
                return bad_header(r, line, "the file does not start with \"ply\"", NULL);
            continue;
        }
        if (strcmp(kw, "comment") == 0 || strcmp(kw, "obj_info") == 0)
            continue;
        if (strcmp(kw, "format") == 0) {
            if (format || !word(&s, nl, a, sizeof a) || !word(&s, nl, b, sizeof b) || word(&s, nl, c, sizeof c))
                return bad_header(r, line, "expected one \"format FORMAT 1.0\"", NULL);
            if (strcmp(a, "ascii") == 0)
                r->format = F_ASCII;
            else if (strcmp(a, "binary_little_endian") == 0)
                r->format = F_LE;
            else if (strcmp(a, "binary_big_endian") == 0)
                r->format = F_BE;
            else
                return bad_header(r, line, "unknown format", a);
            if (strcmp(b, "1.0") != 0 && strcmp(b, "1") != 0)
                return bad_header(r, line, "unsupported version", b);
            format = true;
        } else if (strcmp(kw, "element") == 0) {
            char *stop;
            if (!word(&s, nl, a, sizeof a) || !word(&s, nl, b, sizeof b) || word(&s, nl, c, sizeof c))
                return bad_header(r, line, "expected \"element NAME COUNT\"", NULL);
            errno = 0;
            unsigned long long count = strtoull(b, &stop, 10);
            if (*stop || b[0] == '-' || errno == ERANGE)
                return bad_header(r, line, "bad element count", b);
            if (r->nelem == PLY_MAX_ELEMENTS)
                return bad_header(r, line, "too many elements (emm reads at most 16)", NULL);
            ply_element *e = &r->elem[r->nelem++];
            snprintf(e->name, sizeof e->name, "%s", a);
            e->count = count;
            for (int i = 0; i < r->nelem - 1; i++)
                if (strcmp(r->elem[i].name, a) == 0)
                    return bad_header(r, line, "element named twice:", a);
            e->vertex = strcmp(a, "vertex") == 0;
            e->face = strcmp(a, "face") == 0;
        } else if (strcmp(kw, "property") == 0) {
            if (r->nelem == 0)
                return bad_header(r, line, "a property before any element", NULL);
            ply_element *e = &r->elem[r->nelem - 1];
            if (e->nprop == PLY_MAX_PROPERTIES)
                return bad_header(r, line, "too many properties (emm reads at most 64 per element)", NULL);
            ply_property *q = &e->prop[e->nprop++];
            const char *name;
            if (!word(&s, nl, a, sizeof a))
                return bad_header(r, line, "expected \"property TYPE NAME\"", NULL);
            if (strcmp(a, "list") == 0) {
                if (!word(&s, nl, b, sizeof b) || !word(&s, nl, c, sizeof c) || !word(&s, nl, d, sizeof d) ||
                    word(&s, nl, a, sizeof a))
                    return bad_header(r, line, "expected \"property list COUNT_TYPE ITEM_TYPE NAME\"", NULL);
                q->count_type = type_named(b);
                q->type = type_named(c);
                if (q->count_type == T_NONE || q->count_type == T_F32 || q->count_type == T_F64)
                    return bad_header(r, line, "a list's count type must be an integer type, not", b);
                if (q->type == T_NONE)
                    return bad_header(r, line, "unknown type", c);
                name = d;
                q->role = e->face && (strcmp(d, "vertex_indices") == 0 || strcmp(d, "vertex_index") == 0)
                              ? R_CORNERS : R_OTHER;
                if (q->role == R_CORNERS && (q->type == T_F32 || q->type == T_F64))
                    return bad_header(r, line, "vertex indices must be of an integer type, not", c);
            } else {
                if (!word(&s, nl, b, sizeof b) || word(&s, nl, c, sizeof c))
                    return bad_header(r, line, "expected \"property TYPE NAME\"", NULL);
                q->type = type_named(a);
                q->count_type = T_NONE;
                if (q->type == T_NONE)
                    return bad_header(r, line, "unknown type", a);
                name = b;
                q->role = !e->vertex ? R_OTHER
                          : strcmp(b, "x") == 0 ? R_X
                          : strcmp(b, "y") == 0 ? R_Y
                          : strcmp(b, "z") == 0 ? R_Z : R_OTHER;
            }
            for (int i = 0; i < e->nprop - 1; i++)
                if (q->role != R_OTHER && e->prop[i].role == q->role)
                    return bad_header(r, line, "property named twice:", name);
        } else if (strcmp(kw, "end_header") == 0) {
            done = true;
        } else {
            return bad_header(r, line, "unknown keyword", kw);
        }
    }
    if (!format)
        return emm_fail(r->err, EMM_ERR_FORMAT, "%s: not a readable PLY file: the header has no format line",
                        r->path);
    r->p = (const unsigned char *)p;
    r->end = (const unsigned char *)end;
    /* Every element must be able to fit in what is left, before a loop
     * runs over its declared count. */
    /* An ASCII file's last value may end the file without a separator. */
    uint64_t left = (uint64_t)(end - p) + (r->format == F_ASCII), need = 0;
    bool vertices = false, faces = false;
    for (int i = 0; i < r->nelem; i++) {
        ply_element *e = &r->elem[i];
        uint64_t m = min_record(r, e);
        if (e->count > 0 && m == 0)
            return emm_fail(r->err, EMM_ERR_FORMAT,
                            "%s: not a readable PLY file: element '%s' has %llu records and no properties",
                            r->path, e->name, (unsigned long long)e->count);
        if (e->count > (left - need) / (m ? m : 1))
            return emm_fail(r->err, EMM_ERR_FORMAT,
                            "%s: truncated: the header declares %llu '%s' records, which need at least "
                            "%llu bytes each, and %llu bytes follow the header",
                            r->path, (unsigned long long)e->count, e->name, (unsigned long long)m,
                            (unsigned long long)(end - p));
        need += e->count * m;
        if (e->vertex) {
            int xyz = 0;
            for (int k = 0; k < e->nprop; k++)
                xyz += e->prop[k].role >= R_X && e->prop[k].role <= R_Z;
            if (xyz != 3)
                return emm_fail(r->err, EMM_ERR_FORMAT,
                                "%s: not a readable PLY file: element 'vertex' lacks an x, y or z property",
                                r->path);
            vertices = true;
        }
        if (e->face) {
            bool corners = false;
            for (int k = 0; k < e->nprop; k++)
                corners |= e->prop[k].role == R_CORNERS;
            if (!corners)
                return emm_fail(r->err, EMM_ERR_FORMAT,
                                "%s: not a readable PLY file: element 'face' has no vertex_indices list",
                                r->path);
            faces = true;
        }
    }
    if (!vertices || !faces)
        return emm_fail(r->err, EMM_ERR_FORMAT, "%s: not a readable PLY file: no '%s' element", r->path,
                        vertices ? "face" : "vertex");
    return EMM_OK;
}

/* ---- values ------------------------------------------------------------- */

static emm_status truncated(ply_reader *r, const ply_element *e, uint64_t i)
{
    return emm_fail(r->err, EMM_ERR_FORMAT, "%s: truncated: the data ends in '%s' record %llu of %llu",
                    r->path, e->name, (unsigned long long)i + 1, (unsigned long long)e->count);
}

/* One binary value of type t, converted to double; false when the data
 * ends first. */
static bool binary_value(ply_reader *r, ply_type t, double *out, int64_t *iout)
{
    unsigned n = types[t].size;
    if ((size_t)(r->end - r->p) < n)
        return false;
    unsigned char b[8];
    for (unsigned k = 0; k < n; k++)
        b[k] = r->p[r->format == F_BE ? n - 1 - k : k];
    r->p += n;
    uint64_t u = 0;
    for (unsigned k = 0; k < n; k++)
        u |= (uint64_t)b[k] << (8 * k);
    switch (t) {
    case T_I8: *iout = (int8_t)u; break;
    case T_U8: *iout = (uint8_t)u; break;
    case T_I16: *iout = (int16_t)u; break;
    case T_U16: *iout = (uint16_t)u; break;
    case T_I32: *iout = (int32_t)u; break;
    case T_U32: *iout = (uint32_t)u; break;
    case T_F32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, 4);
        *out = f;
        *iout = 0;
        return true;
    }
    case T_F64:
        memcpy(out, &u, 8);
        *iout = 0;
        return true;
    default: return false;
    }
    *out = (double)*iout;
    return true;
}

/* One ASCII value: a number token; integer types must be integers. 0 when
 * the data ends, -1 for a malformed token, 1 when read. */
static int ascii_value(ply_reader *r, ply_type t, double *out, int64_t *iout)
{
    while (r->p < r->end && (*r->p == ' ' || *r->p == '\t' || *r->p == '\r' || *r->p == '\n' ||
                             *r->p == '\f' || *r->p == '\v'))
        r->p++;
    if (r->p == r->end)
        return 0;
    char tok[PLY_TOKEN_MAX + 1];
    size_t n = 0;
    while (r->p < r->end && *r->p > ' ' && n < PLY_TOKEN_MAX)
        tok[n++] = (char)*r->p++;
    if (r->p < r->end && *r->p > ' ')
        return -1; /* longer than any number */
    tok[n] = '\0';
    char *stop;
    errno = 0;
    if (t == T_F32 || t == T_F64) {
        *out = strtod(tok, &stop);
        *iout = 0;
        return *stop == '\0' ? 1 : -1;
    }
    long long v = strtoll(tok, &stop, 10);
    if (*stop != '\0' || errno == ERANGE)
        return -1;
    static const long long lo[] = { [T_I8] = INT8_MIN, [T_U8] = 0, [T_I16] = INT16_MIN, [T_U16] = 0,
                                    [T_I32] = INT32_MIN, [T_U32] = 0 };
    static const long long hi[] = { [T_I8] = INT8_MAX, [T_U8] = UINT8_MAX, [T_I16] = INT16_MAX,
                                    [T_U16] = UINT16_MAX, [T_I32] = INT32_MAX, [T_U32] = UINT32_MAX };
    if (v < lo[t] || v > hi[t])
        return -1;
    *iout = v;
    *out = (double)v;
    return 1;
}

/* Reads one value; on failure says which record of e went wrong. */
static emm_status value(ply_reader *r, const ply_element *e, uint64_t i, ply_type t, double *out,
                        int64_t *iout)
{
    if (r->format != F_ASCII)
        return binary_value(r, t, out, iout) ? EMM_OK : truncated(r, e, i);
    int got = ascii_value(r, t, out, iout);
    if (got == 0)
        return truncated(r, e, i);
    if (got < 0)
        return emm_fail(r->err, EMM_ERR_FORMAT, "%s: '%s' record %llu: malformed %s value", r->path,
                        e->name, (unsigned long long)i + 1, types[t].name);
    return EMM_OK;
}

static emm_status read_element(ply_reader *r, const ply_element *e)
{
    for (uint64_t i = 0; i < e->count; i++) {
        double xyz[3] = { 0, 0, 0 };
        for (int k = 0; k < e->nprop; k++) {
            const ply_property *q = &e->prop[k];
            double d;
            int64_t v;
            emm_status st;
            if (q->count_type == T_NONE) {
                if ((st = value(r, e, i, q->type, &d, &v)) != EMM_OK)
                    return st;
                if (q->role >= R_X && q->role <= R_Z)
                    xyz[q->role - R_X] = d;
                continue;
            }
            if ((st = value(r, e, i, q->count_type, &d, &v)) != EMM_OK)
                return st;
            if (v < 0)
                return emm_fail(r->err, EMM_ERR_FORMAT, "%s: '%s' record %llu: a list of %lld items",
                                r->path, e->name, (unsigned long long)i + 1, (long long)v);
            /* The items must fit in what is left before they are read. */
            uint64_t each = r->format == F_ASCII ? 2 : types[q->type].size;
            if ((uint64_t)v > (uint64_t)(r->end - r->p) / each)
                return truncated(r, e, i);
            for (int64_t j = 0; j < v; j++) {
                int64_t idx;
                if ((st = value(r, e, i, q->type, &d, &idx)) != EMM_OK)
                    return st;
                if (q->role == R_CORNERS && !emm_raw_add_corner(&r->b, idx))
                    return emm_fail(r->err, EMM_ERR_NOMEM, "%s: out of memory", r->path);
            }
        }
        if (e->vertex && !emm_raw_add_vertex(&r->b, xyz))
            return emm_fail(r->err, EMM_ERR_NOMEM, "%s: out of memory", r->path);
        if (e->face && !emm_raw_end_face(&r->b, 0))
            return emm_fail(r->err, EMM_ERR_NOMEM, "%s: out of memory", r->path);
    }
    return EMM_OK;
}

emm_status emm_read_ply(const char *path, const char *data, size_t len, emm_raw_mesh *raw, emm_error *err)
{
    memset(raw, 0, sizeof *raw);
    ply_reader *r = calloc(1, sizeof *r);
    if (!r)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    r->path = path;
    r->err = err;
    r->b.raw = raw;
    emm_status st = parse_header(r, data, len);
    for (int i = 0; i < r->nelem && st == EMM_OK; i++)
        st = read_element(r, &r->elem[i]);
    if (st == EMM_OK && r->format == F_ASCII) {
        while (r->p < r->end && (*r->p == ' ' || *r->p == '\t' || *r->p == '\r' || *r->p == '\n'))
            r->p++;
        if (r->p < r->end)
            st = emm_fail(err, EMM_ERR_FORMAT, "%s: unexpected data after the last element", path);
    }
    free(r);
    if (st != EMM_OK)
        emm_raw_mesh_free(raw);
    return st;
}
