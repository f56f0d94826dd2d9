/* A small strict JSON reader (RFC 8259), the counterpart of runtime/json.c:
 * `emm plot` reads the reports back with it. Recursive descent over the
 * text with a depth limit; each value is one node, arrays and objects hold
 * their children in a growing array. The first problem stops the parse and
 * names its line and column, as a user fixing a file by hand needs. */
#include "json_read.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "infile.h"

struct jr_value {
    jr_type type;
    bool b;
    double num;
    char *str;        /* JR_STRING */
    size_t n, cap;    /* JR_ARRAY, JR_OBJECT: children */
    jr_value **items;
    char **keys;      /* JR_OBJECT */
};

typedef struct parser {
    const char *p, *end, *start;
    const char *name;
    emm_error *err;
    emm_status status; /* EMM_OK until the first problem */
} parser;

static emm_status fail_at(parser *ps, const char *at, emm_status st, const char *problem)
{
    size_t line = 1, col = 1;
    if (ps->status != EMM_OK)
        return ps->status;
    for (const char *q = ps->start; q < at && q < ps->end; q++) {
        if (*q == '\n') {
            line++;
            col = 1;
        } else {
            col++;
        }
    }
    ps->status = st;
    if (st == EMM_ERR_NOMEM)
        return emm_fail(ps->err, st, "%s: out of memory", ps->name);
    return emm_fail(ps->err, st, "%s: line %zu, column %zu: %s", ps->name, line, col, problem);
}

static emm_status fail(parser *ps, const char *problem)
{
    return fail_at(ps, ps->p, EMM_ERR_FORMAT, problem);
}

static void skip_ws(parser *ps)
{
    while (ps->p < ps->end &&
           (*ps->p == ' ' || *ps->p == '\t' || *ps->p == '\n' || *ps->p == '\r'))
        ps->p++;
}

static jr_value *node(parser *ps, jr_type t)
{
    jr_value *v = calloc(1, sizeof *v);
    if (!v)
        fail_at(ps, ps->p, EMM_ERR_NOMEM, NULL);
    else
        v->type = t;
    return v;
}

void jr_free(jr_value *v)
{
    if (!v)
        return;
    for (size_t i = 0; i < v->n; i++) {
        jr_free(v->items[i]);
        if (v->keys)
            free(v->keys[i]);
    }
    free(v->items);
    free(v->keys);
    free(v->str);
    free(v);
}

static int hex4(const char *s, unsigned *out)
{
    unsigned v = 0;
    for (int i = 0; i < 4; i++) {
        char c = s[i];
        v <<= 4;
        if (c >= '0' && c <= '9')
            v |= (unsigned)(c - '0');
        else if (c >= 'a' && c <= 'f')
            v |= (unsigned)(c - 'a' + 10);
        else if (c >= 'A' && c <= 'F')
            v |= (unsigned)(c - 'A' + 10);
        else
            return 0;
    }
    *out = v;
    return 1;
}

static size_t put_utf8(char *o, unsigned cp)
{
    if (cp < 0x80) {
        o[0] = (char)cp;
        return 1;
    }
    if (cp < 0x800) {
        o[0] = (char)(0xC0 | (cp >> 6));
        o[1] = (char)(0x80 | (cp & 0x3F));
        return 2;
    }
    if (cp < 0x10000) {
        o[0] = (char)(0xE0 | (cp >> 12));
        o[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
        o[2] = (char)(0x80 | (cp & 0x3F));
        return 3;
    }
    o[0] = (char)(0xF0 | (cp >> 18));
    o[1] = (char)(0x80 | ((cp >> 12) & 0x3F));
    o[2] = (char)(0x80 | ((cp >> 6) & 0x3F));
    o[3] = (char)(0x80 | (cp & 0x3F));
    return 4;
}

/* A string starting at the opening quote; *out gets the decoded text. The
 * decoded text is never longer than the source (an escape of 6 or 12
 * characters gives at most 4 bytes), so one allocation of the source's
 * length suffices. Bytes >= 0x80 pass through: the reports are UTF-8 and
 * this reader does not police encodings. */
static char *parse_string(parser *ps)
{
    const char *q = ps->p + 1;
    size_t len = 0;
    char *s, *o;
    while (q < ps->end && *q != '"') {
        if (*q == '\\' && q + 1 < ps->end)
            q++;
        q++;
    }
    if (q >= ps->end) {
        fail(ps, "unterminated string");
        return NULL;
    }
    len = (size_t)(q - ps->p);
    s = malloc(len + 1);
    if (!s) {
        fail_at(ps, ps->p, EMM_ERR_NOMEM, NULL);
        return NULL;
    }
    o = s;
    ps->p++;
    while (*ps->p != '"') {
        unsigned char c = (unsigned char)*ps->p;
        if (c < 0x20) {
            fail(ps, "control character in a string (escape it)");
            goto bad;
        }
        if (c != '\\') {
            *o++ = (char)c;
            ps->p++;
            continue;
        }
        ps->p++;
        switch (*ps->p) {
        case '"': *o++ = '"'; break;
        case '\\': *o++ = '\\'; break;
        case '/': *o++ = '/'; break;
        case 'b': *o++ = '\b'; break;
        case 'f': *o++ = '\f'; break;
        case 'n': *o++ = '\n'; break;
        case 'r': *o++ = '\r'; break;
        case 't': *o++ = '\t'; break;
        case 'u': {
            unsigned cp, lo;
            if (ps->end - ps->p < 5 || !hex4(ps->p + 1, &cp)) {
                fail(ps, "\\u needs four hex digits");
                goto bad;
            }
            ps->p += 4;
            if (cp >= 0xDC00 && cp <= 0xDFFF) {
                fail(ps, "unpaired low surrogate in \\u escape");
                goto bad;
            }
            if (cp >= 0xD800 && cp <= 0xDBFF) {
                if (ps->end - ps->p < 7 || ps->p[1] != '\\' || ps->p[2] != 'u' ||
                    !hex4(ps->p + 3, &lo) || lo < 0xDC00 || lo > 0xDFFF) {
                    fail(ps, "unpaired high surrogate in \\u escape");
                    goto bad;
                }
                ps->p += 6;
                cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
            }
            if (cp == 0) {
                fail(ps, "\\u0000 in a string");
                goto bad;
            }
            o += put_utf8(o, cp);
            break;
        }
        default:
            fail(ps, "invalid escape in a string");
            goto bad;
        }
        ps->p++;
    }
    ps->p++;
    *o = '\0';
    return s;
bad:
    free(s);
    return NULL;
}

static int is_digit(char c) { return c >= '0' && c <= '9'; }

/* The grammar is checked here; strtod only converts what it accepted. */
static jr_value *parse_number(parser *ps)
{
    const char *q = ps->p;
    char buf[128], *endp;
    jr_value *v;
    size_t len;
    if (q < ps->end && *q == '-')
        q++;
    if (q >= ps->end || !is_digit(*q)) {
        fail(ps, "invalid number");
        return NULL;
    }
    if (*q == '0' && q + 1 < ps->end && is_digit(q[1])) {
        fail(ps, "number with a leading zero");
        return NULL;
    }
    while (q < ps->end && is_digit(*q))
        q++;
    if (q < ps->end && *q == '.') {
        q++;
        if (q >= ps->end || !is_digit(*q)) {
            fail_at(ps, q, EMM_ERR_FORMAT, "a digit must follow the decimal point");
            return NULL;
        }
        while (q < ps->end && is_digit(*q))
            q++;
    }
    if (q < ps->end && (*q == 'e' || *q == 'E')) {
        q++;
        if (q < ps->end && (*q == '+' || *q == '-'))
            q++;
        if (q >= ps->end || !is_digit(*q)) {
            fail_at(ps, q, EMM_ERR_FORMAT, "a digit must follow the exponent");
            return NULL;
        }
        while (q < ps->end && is_digit(*q))
            q++;
    }
    len = (size_t)(q - ps->p);
    if (len >= sizeof buf) {
        fail(ps, "number too long");
        return NULL;
    }
    memcpy(buf, ps->p, len);
    buf[len] = '\0';
    if (!(v = node(ps, JR_NUMBER)))
        return NULL;
    errno = 0;
    v->num = strtod(buf, &endp);
    if (errno == ERANGE && (v->num > 1.0 || v->num < -1.0)) {
        free(v);
        fail(ps, "number out of range");
        return NULL;
    }
    ps->p = q;
    return v;
}

static int push(parser *ps, jr_value *parent, jr_value *child, char *key)
{
    if (parent->n == parent->cap) {
        size_t cap = parent->cap ? 2 * parent->cap : 4;
        jr_value **items = realloc(parent->items, cap * sizeof *items);
        if (!items)
            goto nomem;
        parent->items = items;
        if (parent->type == JR_OBJECT) {
            char **keys = realloc(parent->keys, cap * sizeof *keys);
            if (!keys)
                goto nomem;
            parent->keys = keys;
        }
        parent->cap = cap;
    }
    parent->items[parent->n] = child;
    if (parent->type == JR_OBJECT)
        parent->keys[parent->n] = key;
    parent->n++;
    return 1;
nomem:
    fail_at(ps, ps->p, EMM_ERR_NOMEM, NULL);
    return 0;
}

static jr_value *parse_value(parser *ps, int depth);

static jr_value *parse_container(parser *ps, int depth, char close)
{
    jr_value *v = node(ps, close == ']' ? JR_ARRAY : JR_OBJECT);
    if (!v)
        return NULL;
    if (depth >= JR_MAX_DEPTH) {
        fail(ps, "nested too deep");
        goto bad;
    }
    ps->p++;
    skip_ws(ps);
    if (ps->p < ps->end && *ps->p == close) {
        ps->p++;
        return v;
    }
    for (;;) {
        char *key = NULL;
        jr_value *child;
        skip_ws(ps);
        if (close == '}') {
            const char *at = ps->p;
            if (ps->p >= ps->end || *ps->p != '"') {
                fail(ps, ps->p < ps->end && *ps->p == '}' ? "trailing comma in an object"
                                                          : "expected a string key");
                goto bad;
            }
            if (!(key = parse_string(ps)))
                goto bad;
            for (size_t i = 0; i < v->n; i++)
                if (strcmp(v->keys[i], key) == 0) {
                    free(key);
                    fail_at(ps, at, EMM_ERR_FORMAT, "key repeated in an object");
                    goto bad;
                }
            skip_ws(ps);
            if (ps->p >= ps->end || *ps->p != ':') {
                free(key);
                fail(ps, "expected ':' after a key");
                goto bad;
            }
            ps->p++;
        } else if (ps->p < ps->end && *ps->p == ']') {
            fail(ps, "trailing comma in an array");
            goto bad;
        }
        if (!(child = parse_value(ps, depth + 1))) {
            free(key);
            goto bad;
        }
        if (!push(ps, v, child, key)) {
            jr_free(child);
            free(key);
            goto bad;
        }
        skip_ws(ps);
        if (ps->p < ps->end && *ps->p == ',') {
            ps->p++;
            continue;
        }
        if (ps->p < ps->end && *ps->p == close) {
            ps->p++;
            return v;
        }
        fail(ps, ps->p >= ps->end ? "unexpected end of input"
                 : close == ']'   ? "expected ',' or ']' in an array"
                                  : "expected ',' or '}' in an object");
        goto bad;
    }
bad:
    jr_free(v);
    return NULL;
}

static int word(parser *ps, const char *w)
{
    size_t n = strlen(w);
    if ((size_t)(ps->end - ps->p) >= n && memcmp(ps->p, w, n) == 0) {
        ps->p += n;
        return 1;
    }
    return 0;
}

static jr_value *parse_value(parser *ps, int depth)
{
    jr_value *v;
    skip_ws(ps);
    if (ps->p >= ps->end) {
        fail(ps, "unexpected end of input");
        return NULL;
    }
    switch (*ps->p) {
    case '{':
        return parse_container(ps, depth, '}');
    case '[':
        return parse_container(ps, depth, ']');
    case '"': {
        char *s = parse_string(ps);
        if (!s)
            return NULL;
        if (!(v = node(ps, JR_STRING))) {
            free(s);
            return NULL;
        }
        v->str = s;
        return v;
    }
    case 't':
    case 'f':
    case 'n':
        if (word(ps, "true") || word(ps, "false")) {
            if ((v = node(ps, JR_BOOL)))
                v->b = ps->p[-1] == 'e' && ps->p[-2] == 'u';
            return v;
        }
        if (word(ps, "null"))
            return node(ps, JR_NULL);
        fail(ps, "unexpected word (expected true, false or null)");
        return NULL;
    default:
        if (*ps->p == '-' || is_digit(*ps->p))
            return parse_number(ps);
        fail(ps, "unexpected character");
        return NULL;
    }
}

emm_status jr_parse(const char *text, size_t len, const char *name, jr_value **out,
                    emm_error *err)
{
    parser ps = {text, text + len, text, name ? name : "JSON", err, EMM_OK};
    jr_value *v;
    *out = NULL;
    if (len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0)
        return fail(&ps, "byte order mark (JSON text has none)");
    v = parse_value(&ps, 0);
    if (!v)
        return ps.status != EMM_OK ? ps.status : fail(&ps, "invalid JSON");
    skip_ws(&ps);
    if (ps.p < ps.end) {
        jr_free(v);
        return fail(&ps, "text after the JSON value");
    }
    *out = v;
    return EMM_OK;
}

emm_status jr_parse_file(const char *path, jr_value **out, emm_error *err)
{
    char *buf;
    size_t len;
    *out = NULL;
    emm_status st = emm_infile_read(path, "JSON report", JR_FILE_MAX, &buf, &len, err);
    if (st != EMM_OK)
        return st;
    if (len == 0) {
        free(buf);
        return emm_fail(err, EMM_ERR_FORMAT, "%s: empty file, not JSON", path);
    }
    st = jr_parse(buf, len, path, out, err);
    free(buf);
    return st;
}

jr_type jr_type_of(const jr_value *v) { return v ? v->type : JR_NULL; }

bool jr_is(const jr_value *v, jr_type t) { return v && v->type == t; }

const jr_value *jr_get(const jr_value *v, const char *key)
{
    if (!jr_is(v, JR_OBJECT))
        return NULL;
    for (size_t i = 0; i < v->n; i++)
        if (strcmp(v->keys[i], key) == 0)
            return v->items[i];
    return NULL;
}

size_t jr_len(const jr_value *v)
{
    return v && (v->type == JR_ARRAY || v->type == JR_OBJECT) ? v->n : 0;
}

const jr_value *jr_at(const jr_value *v, size_t i)
{
    return i < jr_len(v) ? v->items[i] : NULL;
}

const char *jr_key_at(const jr_value *v, size_t i)
{
    return jr_is(v, JR_OBJECT) && i < v->n ? v->keys[i] : NULL;
}

double jr_number(const jr_value *v) { return jr_is(v, JR_NUMBER) ? v->num : 0; }

const char *jr_string(const jr_value *v) { return jr_is(v, JR_STRING) ? v->str : NULL; }

bool jr_bool(const jr_value *v) { return jr_is(v, JR_BOOL) && v->b; }
