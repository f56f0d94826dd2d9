/* The frames between a session's proxy and emm-session (session_wire.h). */
#include "session_wire.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>

#include "error.h"

bool wire_send(int fd, const struct wire_frame *f, const void *a, size_t alen, const void *b,
               size_t blen)
{
    struct iovec iov[3] = {{(void *)f, sizeof *f}, {(void *)a, alen}, {(void *)b, blen}};
    struct msghdr m = {0};
    m.msg_iov = iov;
    m.msg_iovlen = 3;
    while (m.msg_iovlen > 0) {
        ssize_t w = sendmsg(fd, &m, MSG_NOSIGNAL);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            return false;
        }
        size_t left = (size_t)w;
        while (m.msg_iovlen > 0 && left >= m.msg_iov[0].iov_len) {
            left -= m.msg_iov[0].iov_len;
            m.msg_iov++;
            m.msg_iovlen--;
        }
        if (m.msg_iovlen > 0) {
            m.msg_iov[0].iov_base = (char *)m.msg_iov[0].iov_base + left;
            m.msg_iov[0].iov_len -= left;
        }
    }
    return true;
}

bool wire_recv(int fd, void *buf, size_t len)
{
    char *p = buf;
    while (len > 0) {
        ssize_t r = recv(fd, p, len, 0);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return false;
        p += r;
        len -= (size_t)r;
    }
    return true;
}

bool wire_recv_data(int fd, const struct wire_frame *f, unsigned char **data)
{
    uint64_t have = 0, cap = 0;
    *data = NULL;
    while (have < f->len) {
        if (have == cap) {
            cap = cap ? 2 * cap : 65536;
            if (cap > f->len)
                cap = f->len;
            unsigned char *d = realloc(*data, cap);
            if (!d)
                return false;
            *data = d;
        }
        if (!wire_recv(fd, *data + have, cap - have))
            return false;
        have = cap;
    }
    return true;
}

/* ---- a growing payload ---------------------------------------------------- */

struct buf {
    unsigned char *p;
    size_t len, cap;
    bool failed;
};

static void put(struct buf *b, const void *data, size_t n)
{
    if (b->failed)
        return;
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->len + n)
            cap *= 2;
        unsigned char *p = realloc(b->p, cap);
        if (!p) {
            b->failed = true;
            return;
        }
        b->p = p;
        b->cap = cap;
    }
    memcpy(b->p + b->len, data, n);
    b->len += n;
}

static void put_u64(struct buf *b, uint64_t v)
{
    put(b, &v, sizeof v);
}

static void put_str(struct buf *b, const char *s)
{
    put(b, s ? s : "", strlen(s ? s : "") + 1);
}

static bool done(struct buf *b, unsigned char **out, size_t *len)
{
    if (b->failed) {
        free(b->p);
        return false;
    }
    *out = b->p;
    *len = b->len;
    return true;
}

/* A reader of a payload: each get fails once the bytes run out. */
struct cursor {
    const unsigned char *p, *end;
};

static bool get_u64(struct cursor *c, uint64_t *v)
{
    if ((size_t)(c->end - c->p) < sizeof *v)
        return false;
    memcpy(v, c->p, sizeof *v);
    c->p += sizeof *v;
    return true;
}

static bool get_str(struct cursor *c, const char **s)
{
    const unsigned char *z = c->p < c->end ? memchr(c->p, 0, (size_t)(c->end - c->p)) : NULL;
    if (!z)
        return false;
    *s = (const char *)c->p;
    c->p = z + 1;
    return true;
}

/* ---- the start ------------------------------------------------------------ */

bool wire_start_encode(const emm_session_config *sc, long pid, unsigned char **out, size_t *len)
{
    struct buf b = {0};
    emm_config defaults;
    const emm_config *c = sc->config;
    if (!c) {
        emm_config_init(&defaults);
        c = &defaults;
    }
    put_u64(&b, WIRE_VERSION);
    put_u64(&b, (uint64_t)sc->capture);
    put_u64(&b, (uint64_t)sc->table_only);
    put_u64(&b, (uint64_t)sc->expect);
    put_u64(&b, (uint64_t)pid);
    put_str(&b, sc->program ? sc->program : "program");
    char text[2 * EMM_CONFIG_PATH_MAX + 16];
    /* The rows that were set, counted first: a start is whole or refused. */
    bool sent[EMM_CONFIG_COUNT];
    uint64_t count = 0;
    for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
        sent[k] = c->source[k] && k != EMM_CONFIG_TAG &&
                  emm_config_format(c, (emm_config_key)k, text, sizeof text);
        count += sent[k];
    }
    put_u64(&b, count);
    for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
        if (!sent[k])
            continue;
        emm_config_format(c, (emm_config_key)k, text, sizeof text);
        put_u64(&b, (uint64_t)k);
        put_str(&b, c->source[k]);
        put_str(&b, text);
    }
    return done(&b, out, len);
}

emm_status wire_start_decode(const unsigned char *data, size_t len, emm_config *cfg,
                             char **strings, emm_capture *capture, int *table_only,
                             unsigned *expect, const char **program, long *program_pid,
                             emm_error *err)
{
    struct cursor c = {data, data ? data + len : data};
    uint64_t version, cap, only, want, pid, count;
    emm_config_init(cfg);
    *strings = NULL;
    if (!get_u64(&c, &version) || version != WIRE_VERSION)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "emm-session: the shim and the session server are of different builds");
    if (!get_u64(&c, &cap) || !get_u64(&c, &only) || !get_u64(&c, &want) || want > UINT_MAX ||
        !get_u64(&c, &pid) ||
        !get_str(&c, program) || !get_u64(&c, &count) || cap >= EMM_CAPTURE_COUNT ||
        count > EMM_CONFIG_COUNT)
        return emm_fail(err, EMM_ERR_FORMAT, "emm-session: a malformed start");
    *capture = (emm_capture)cap;
    *table_only = only != 0;
    *expect = (unsigned)want;
    *program_pid = (long)pid;
    /* The sources must outlive cfg: one copy of the rest of the payload. */
    size_t rest = (size_t)(c.end - c.p);
    char *copy = malloc(rest ? rest : 1);
    if (!copy)
        return emm_fail(err, EMM_ERR_NOMEM, "emm-session: out of memory");
    memcpy(copy, c.p, rest);
    *strings = copy;
    struct cursor r = {(const unsigned char *)copy, (const unsigned char *)copy + rest};
    for (uint64_t i = 0; i < count; i++) {
        uint64_t k;
        const char *source, *text;
        if (!get_u64(&r, &k) || k >= EMM_CONFIG_COUNT || k == EMM_CONFIG_TAG ||
            !get_str(&r, &source) || !get_str(&r, &text))
            return emm_fail(err, EMM_ERR_FORMAT, "emm-session: a malformed start");
        emm_status st = emm_config_set(cfg, (emm_config_key)k, text, source, (long)pid, err);
        if (st != EMM_OK)
            return st;
    }
    if (r.p != r.end)
        return emm_fail(err, EMM_ERR_FORMAT, "emm-session: a malformed start");
    return EMM_OK;
}

/* ---- a tag ---------------------------------------------------------------- */

bool wire_tag_encode(const emm_array_desc *d, unsigned char **out, size_t *len)
{
    struct buf b = {0};
    put_u64(&b, (uint64_t)d->kind);
    put_u64(&b, (uint64_t)d->shape);
    put_u64(&b, (uint64_t)(int64_t)d->axis);
    put_u64(&b, (uint64_t)(uintptr_t)d->base);
    put_u64(&b, d->count);
    put_u64(&b, d->stride);
    put_u64(&b, d->offset);
    put_u64(&b, (uint64_t)d->type);
    put_u64(&b, d->rule);
    for (int k = 0; k < EMM_TAG_LINKS; k++)
        put_u64(&b, d->link[k]);
    put_u64(&b, d->origin != NULL);
    put_str(&b, d->origin);
    return done(&b, out, len);
}

bool wire_tag_decode(const unsigned char *data, size_t len, emm_array_desc *d)
{
    if (!data)
        return false;
    struct cursor c = {data, data + len};
    uint64_t v[10 + EMM_TAG_LINKS];
    const char *origin;
    for (int i = 0; i < 10 + EMM_TAG_LINKS; i++)
        if (!get_u64(&c, &v[i]))
            return false;
    if (!get_str(&c, &origin) || c.p != c.end || v[8] > UINT32_MAX || v[2] + 1 > 3)
        return false;
    for (int k = 0; k < EMM_TAG_LINKS; k++)
        if (v[9 + k] > UINT32_MAX)
            return false;
    /* The session checks the rest of the description, as it does a call's
     * in the program. */
    *d = (emm_array_desc){.kind = (emm_array_kind)v[0],
                          .shape = (emm_tag_shape)v[1],
                          .axis = (int)(int64_t)v[2],
                          .base = (const void *)(uintptr_t)v[3],
                          .count = v[4],
                          .stride = v[5],
                          .offset = v[6],
                          .type = (emm_scalar)v[7],
                          .rule = (unsigned)v[8],
                          .origin = v[9 + EMM_TAG_LINKS] ? origin : NULL};
    for (int k = 0; k < EMM_TAG_LINKS; k++)
        d->link[k] = (uint32_t)v[9 + k];
    return true;
}

/* ---- the program's objects -------------------------------------------------- */

bool wire_modules_encode(const emm_trace_module *m, uint32_t n, unsigned char **out, size_t *len)
{
    struct buf b = {0};
    for (uint32_t i = 0; i < n; i++) {
        put_u64(&b, m[i].bias);
        put_u64(&b, m[i].lo);
        put_u64(&b, m[i].hi);
        put_str(&b, m[i].path);
    }
    return done(&b, out, len); /* none: an empty payload */
}

bool wire_modules_decode(const unsigned char *data, size_t len, emm_trace_module **out,
                         uint32_t *n)
{
    if (!data || len == 0)
        return false;
    struct cursor c = {data, data + len};
    size_t count = 0, text = 0;
    while (c.p < c.end) {
        uint64_t x;
        const char *path;
        if (!get_u64(&c, &x) || !get_u64(&c, &x) || !get_u64(&c, &x) || !get_str(&c, &path) ||
            count == UINT32_MAX)
            return false;
        count++;
        text += strlen(path) + 1;
    }
    if (count == 0)
        return false;
    emm_trace_module *m = malloc(count * sizeof *m + text);
    if (!m)
        return false;
    char *t = (char *)(m + count);
    c.p = data;
    for (size_t i = 0; i < count; i++) {
        const char *path = "";
        get_u64(&c, &m[i].bias);
        get_u64(&c, &m[i].lo);
        get_u64(&c, &m[i].hi);
        get_str(&c, &path);
        size_t l = strlen(path) + 1;
        memcpy(t, path, l);
        m[i].path = t;
        t += l;
    }
    *out = m;
    *n = (uint32_t)count;
    return true;
}
