/* A session in another process (docs/design.md "The valgrind capture"):
 * under Valgrind every instruction of the client is translated, the
 * session's profiling and simulation too, which made them about nine times
 * slower than natively. With emm_session_config.server set, emm_session_new
 * starts that executable (emm-session, beside the Valgrind tool) as a
 * native process and the handle becomes a proxy: each entry point sends its
 * call over a socket and the server runs the real session. The program
 * goes on while the server simulates, on the other core.
 *
 * The calls keep the in-process session's results exactly:
 * - until the decision every call waits for the server's answer, so the
 *   window closes at the same record and the caller decides at the same
 *   moment; after it, accesses and iterations are sent without waiting
 *   (their answer can only be SIMULATING) and the socket's back-pressure
 *   bounds what is in flight;
 * - the decision answers once it has read the program (the geometry, the
 *   arrays frozen, the objects a trace will name), with the ranges the
 *   program asks for next; the profile, the sweeps and the models follow
 *   while the program goes on, its accesses queued;
 * - the session reads the program's memory only inside a call that waits
 *   (the geometry at the decision, an array's fields when it leaves before
 *   it): the server then asks for those bytes (a READ), and for the
 *   program's loaded objects (MODULES, for program counters' source lines),
 *   and the waiting client sends them from its memory as it is right then.
 * The server's summary goes to its stderr, which is the program's.
 *
 * Frames, both ways, are a fixed header and `len` bytes; both ends are the
 * same build (SESSION_WIRE_VERSION and the config's size are checked). A
 * client that loses its server (it died, or never started) gets
 * EMM_SESSION_OFF and says why at finish; a server whose client goes away
 * ends quietly. SIGPIPE is never raised in the program (MSG_NOSIGNAL). */
#include "session_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/wait.h>
#include <unistd.h>

#include "error.h"
#include "srcline.h"

#define SESSION_WIRE_VERSION 2
/* Bytes the server's reader may hold before the program waits. */
#define SERVER_QUEUE_BYTES ((size_t)64 << 20)
/* The largest frame either side accepts: a mesh array's bytes. */
#define FRAME_MAX ((uint64_t)1 << 40)

enum wire_op {
    OP_NEW = 1,
    OP_TAG,
    OP_MOVE,
    OP_UNTAG,
    OP_RANGES,
    OP_ACCESS,
    OP_ITERATION,
    OP_DECIDE,
    OP_FINISH,
    OP_BYTES,   /* the answer to a READ or MODULES */
    /* server to client */
    OP_REPLY,
    OP_READ,
    OP_MODULES
};

struct frame {
    uint32_t op;
    uint32_t wait;  /* client to server: the client waits for a REPLY */
    int64_t value;  /* a REPLY's answer; a READ's address */
    int32_t status; /* a REPLY's emm_status */
    uint32_t pad;
    uint64_t len;   /* bytes that follow */
};

struct wire_tag {
    uint64_t base, count, stride, field;
    int32_t kind, type, rule, pad;
};

struct wire_new {
    uint32_t version, config_bytes;
    int32_t capture, table_only;
    /* then the emm_config's bytes, its EMM_CONFIG_COUNT source names and the
     * program's name, each a string ended by '\0' */
};

/* ---- both ends ------------------------------------------------------------ */

static bool send_all(int fd, const struct iovec *iov_in, int n)
{
    struct iovec iov[4];
    memcpy(iov, iov_in, (size_t)n * sizeof *iov);
    struct msghdr m = {0};
    m.msg_iov = iov;
    m.msg_iovlen = (size_t)n;
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

static bool send_frame(int fd, const struct frame *f, const void *a, size_t alen, const void *b,
                       size_t blen)
{
    struct iovec iov[3] = {{(void *)f, sizeof *f}, {(void *)a, alen}, {(void *)b, blen}};
    return send_all(fd, iov, 3);
}

static bool recv_all(int fd, void *buf, size_t len)
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

/* ---- the client: a proxy inside the program -------------------------------- */

struct session_remote {
    int fd;
    bool broken;          /* the server is gone: every call answers OFF */
    bool quiet;           /* a forked child's copy: nothing to say */
    bool decided;         /* the decision was made: accesses no longer wait */
    bool have_ranges;     /* ranges holds the session's ranges (from the decision) */
    uint64_t nranges, ranges[2 * SESSION_MAX_ARRAYS];
    emm_session_state state;
    emm_error why;        /* why the server is gone */
    char program[256];
};

static void lost(struct session_remote *r, const char *what)
{
    if (r->broken)
        return;
    r->broken = true;
    emm_fail(&r->why, EMM_ERR_IO,
             "%s: the session's process (emm-session) stopped %s: no report", r->program, what);
    if (r->fd >= 0)
        close(r->fd);
    r->fd = -1;
}

/* Answers a READ: the program's bytes [addr, addr + len). */
static bool send_bytes(struct session_remote *r, const void *p, size_t len)
{
    struct frame f = {.op = OP_BYTES, .len = len};
    return send_frame(r->fd, &f, p, len, NULL, 0);
}

static bool send_modules(struct session_remote *r)
{
    emm_trace_module *m = NULL;
    uint32_t n = 0;
    if (emm_process_modules(&m, &n, NULL) != EMM_OK)
        n = 0;
    /* Each module: bias, lo, hi, then its path and '\0'. */
    size_t bytes = 0;
    for (uint32_t i = 0; i < n; i++)
        bytes += 3 * sizeof(uint64_t) + strlen(m[i].path) + 1;
    char *buf = malloc(bytes ? bytes : 1);
    if (!buf) {
        free(m);
        return send_bytes(r, NULL, 0);
    }
    char *p = buf;
    for (uint32_t i = 0; i < n; i++) {
        uint64_t v[3] = {m[i].bias, m[i].lo, m[i].hi};
        memcpy(p, v, sizeof v);
        p += sizeof v;
        size_t l = strlen(m[i].path) + 1;
        memcpy(p, m[i].path, l);
        p += l;
    }
    bool ok = send_bytes(r, buf, bytes);
    free(buf);
    free(m);
    return ok;
}

/* Sends a call; when it waits, serves the server's READs until its REPLY,
 * whose payload (at most `cap` bytes) goes to `out`. */
static bool call(struct session_remote *r, uint32_t op, bool wait, const void *a, size_t alen,
                 const void *b, size_t blen, struct frame *reply, void *out, size_t cap)
{
    if (r->broken)
        return false;
    if (op != OP_ACCESS && op != OP_ITERATION && op != OP_RANGES)
        r->have_ranges = false; /* a call that may change them */
    struct frame f = {.op = op, .wait = wait, .len = alen + blen};
    if (!send_frame(r->fd, &f, a, alen, b, blen)) {
        lost(r, "(the socket closed)");
        return false;
    }
    while (wait) {
        if (!recv_all(r->fd, reply, sizeof *reply) || reply->len > FRAME_MAX) {
            lost(r, "before answering");
            return false;
        }
        if (reply->op == OP_READ) {
            if (!send_bytes(r, (const void *)(uintptr_t)reply->value, reply->len)) {
                lost(r, "(the program's arrays could not be sent)");
                return false;
            }
        } else if (reply->op == OP_MODULES) {
            if (!send_modules(r)) {
                lost(r, "(the program's objects could not be sent)");
                return false;
            }
        } else if (reply->op == OP_REPLY) {
            size_t keep = reply->len < cap ? (size_t)reply->len : cap;
            char sink[256];
            if (!recv_all(r->fd, out, keep)) {
                lost(r, "while answering");
                return false;
            }
            for (uint64_t left = reply->len - keep; left > 0;) {
                size_t k = left < sizeof sink ? (size_t)left : sizeof sink;
                if (!recv_all(r->fd, sink, k)) {
                    lost(r, "while answering");
                    return false;
                }
                left -= k;
            }
            return true;
        } else {
            lost(r, "(it sent something unexpected)");
            return false;
        }
    }
    return true;
}

/* A REPLY that carries a status and a message; on success its payload (at
 * most `cap` bytes, and no more than a message's) goes to `ok` and its
 * value to *value (either may be NULL). */
static emm_status status_call(struct session_remote *r, uint32_t op, const void *a, size_t alen,
                              void *ok, size_t cap, int64_t *value, emm_error *err)
{
    struct frame reply;
    char msg[sizeof err->message];
    memset(msg, 0, sizeof msg);
    if (!call(r, op, true, a, alen, NULL, 0, &reply, msg, sizeof msg - 1)) {
        if (err)
            *err = r->why;
        return r->why.status;
    }
    if (reply.status != EMM_OK && err) {
        err->status = (emm_status)reply.status;
        snprintf(err->message, sizeof err->message, "%s", msg);
    }
    if (reply.status == EMM_OK) {
        if (ok)
            memcpy(ok, msg, cap < sizeof msg ? cap : sizeof msg);
        if (value)
            *value = reply.value;
    }
    return (emm_status)reply.status;
}

/* Starts `path` with one end of a socket pair as its fd 3, stdin and stdout
 * on /dev/null, stderr the program's, without LD_PRELOAD (the shim has no
 * business in it). Its parent is not the program: a program that waits for
 * any child, or counts them, never meets it. */
static emm_status spawn(const char *path, int *fd, emm_error *err)
{
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
        return emm_fail(err, EMM_ERR_IO, "session server: socketpair: %s", strerror(errno));
    extern char **environ;
    size_t n = 0;
    for (char **e = environ; e && *e; e++)
        n++;
    char **env = malloc((n + 1) * sizeof *env);
    if (!env) {
        close(sv[0]);
        close(sv[1]);
        return emm_fail(err, EMM_ERR_NOMEM, "session server: out of memory");
    }
    size_t k = 0;
    for (char **e = environ; e && *e; e++)
        if (strncmp(*e, "LD_PRELOAD=", 11) != 0)
            env[k++] = *e;
    env[k] = NULL;
    char *argv[] = {(char *)path, (char *)"3", NULL};
    int devnull = open("/dev/null", O_RDWR | O_CLOEXEC);
    pid_t mid = fork();
    if (mid == 0) {
        if (fork() == 0) {
            if (devnull >= 0) {
                dup2(devnull, 0);
                dup2(devnull, 1);
            }
            if (dup2(sv[1], 3) == 3)
                execve(path, argv, env);
            _exit(127);
        }
        _exit(0);
    }
    int e = errno;
    if (devnull >= 0)
        close(devnull);
    free(env);
    close(sv[1]);
    if (mid < 0) {
        close(sv[0]);
        return emm_fail(err, EMM_ERR_IO, "session server: fork: %s", strerror(e));
    }
    while (waitpid(mid, NULL, 0) < 0 && errno == EINTR) {
    }
    *fd = sv[0];
    return EMM_OK;
}

/* The start's payload: the versions, the config's bytes, its source names
 * (pointers: they travel as strings) and the program's name. */
static bool start_payload(const emm_session_config *sc, const char *program, unsigned char **out,
                          size_t *len)
{
    emm_config cfg;
    if (sc->config)
        cfg = *sc->config;
    else
        emm_config_init(&cfg);
    size_t bytes = sizeof(struct wire_new) + sizeof cfg + strlen(program) + 1;
    for (int k = 0; k < EMM_CONFIG_COUNT; k++)
        bytes += (cfg.source[k] ? strlen(cfg.source[k]) : 0) + 1;
    unsigned char *msg = malloc(bytes), *p = msg;
    if (!msg)
        return false;
    struct wire_new w = {SESSION_WIRE_VERSION, sizeof cfg, sc->capture, sc->table_only};
    memcpy(p, &w, sizeof w);
    p += sizeof w;
    memcpy(p, &cfg, sizeof cfg);
    p += sizeof cfg;
    for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
        size_t l = cfg.source[k] ? strlen(cfg.source[k]) : 0;
        memcpy(p, cfg.source[k] ? cfg.source[k] : "", l + 1);
        p += l + 1;
    }
    memcpy(p, program, strlen(program) + 1);
    *out = msg;
    *len = bytes;
    return true;
}

emm_status session_wire_start(const emm_session_config *sc, unsigned char **frame, size_t *len)
{
    unsigned char *msg;
    size_t bytes;
    if (!start_payload(sc, sc->program ? sc->program : "program", &msg, &bytes))
        return EMM_ERR_NOMEM;
    struct frame f = {.op = OP_NEW, .wait = 1, .len = bytes};
    unsigned char *out = malloc(sizeof f + bytes);
    if (out) {
        memcpy(out, &f, sizeof f);
        memcpy(out + sizeof f, msg, bytes);
        *frame = out;
        *len = sizeof f + bytes;
    }
    free(msg);
    return out ? EMM_OK : EMM_ERR_NOMEM;
}

emm_status session_remote_new(const emm_session_config *sc, emm_session **out, emm_error *err)
{
    emm_session *s = calloc(1, sizeof *s);
    struct session_remote *r = calloc(1, sizeof *r);
    if (!s || !r) {
        free(s);
        free(r);
        return emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
    }
    s->remote = r;
    r->fd = -1;
    r->state = EMM_SESSION_PROFILING;
    snprintf(r->program, sizeof r->program, "%s", sc->program ? sc->program : "program");
    emm_status st = spawn(sc->server, &r->fd, err);
    if (st != EMM_OK)
        goto fail;
    unsigned char *msg;
    size_t bytes;
    if (!start_payload(sc, r->program, &msg, &bytes)) {
        st = emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
        goto fail;
    }
    st = status_call(r, OP_NEW, msg, bytes, NULL, 0, NULL, err);
    free(msg);
    if (st != EMM_OK)
        goto fail;
    *out = s;
    return EMM_OK;
fail:
    session_remote_free(s);
    return st;
}

int session_remote_tag(emm_session *s, emm_array_kind kind, const void *base, size_t count,
                       size_t stride, size_t field_offset, emm_scalar type, int rule)
{
    struct wire_tag t = {(uint64_t)(uintptr_t)base, count, stride, field_offset, kind, type, rule, 0};
    struct frame reply;
    if (!call(s->remote, OP_TAG, true, &t, sizeof t, NULL, 0, &reply, NULL, 0))
        return -1;
    return (int)reply.value;
}

/* A call whose answer is the session's state. */
static emm_session_state state_call(struct session_remote *r, uint32_t op, bool wait,
                                    const void *a, size_t alen)
{
    struct frame reply;
    if (!call(r, op, wait, a, alen, NULL, 0, &reply, NULL, 0))
        return EMM_SESSION_OFF;
    if (wait)
        r->state = (emm_session_state)reply.value;
    return r->state;
}

emm_session_state session_remote_move(emm_session *s, const void *old, const void *base,
                                      size_t count)
{
    uint64_t m[3] = {(uint64_t)(uintptr_t)old, (uint64_t)(uintptr_t)base, count};
    return state_call(s->remote, OP_MOVE, true, m, sizeof m);
}

emm_session_state session_remote_untag(emm_session *s, const void *base)
{
    uint64_t b = (uint64_t)(uintptr_t)base;
    return state_call(s->remote, OP_UNTAG, true, &b, sizeof b);
}

size_t session_remote_ranges(const emm_session *s, uint64_t *lo, uint64_t *hi, size_t cap)
{
    struct session_remote *r = s->remote;
    uint64_t c = cap, pairs[2 * SESSION_MAX_ARRAYS];
    struct frame reply;
    size_t n, got;
    if (r->have_ranges && !r->broken) {
        n = (size_t)r->nranges;
        got = n < SESSION_MAX_ARRAYS ? n : SESSION_MAX_ARRAYS;
        memcpy(pairs, r->ranges, sizeof pairs);
    } else if (!call(r, OP_RANGES, true, &c, sizeof c, NULL, 0, &reply, pairs, sizeof pairs)) {
        return 0;
    } else {
        n = (size_t)reply.value;
        got = reply.len / (2 * sizeof *pairs);
    }
    for (size_t i = 0; i < n && i < cap && i < got; i++) {
        lo[i] = pairs[2 * i];
        hi[i] = pairs[2 * i + 1];
    }
    return n;
}

emm_session_state session_remote_access(emm_session *s, const emm_raw_access *a, size_t n)
{
    struct session_remote *r = s->remote;
    if (n == 0)
        return r->broken ? EMM_SESSION_OFF : r->state;
    return state_call(r, OP_ACCESS, !r->decided, a, n * sizeof *a);
}

emm_session_state session_remote_iteration(emm_session *s)
{
    struct session_remote *r = s->remote;
    return state_call(r, OP_ITERATION, !r->decided, NULL, 0);
}

/* The server answers as soon as it has read what the decision needs of the
 * program, with the arrays' ranges from then on (the program asks for them
 * next), and decides while the program goes on. */
emm_status session_remote_decide(emm_session *s, emm_error *err)
{
    struct session_remote *r = s->remote;
    int64_t n = 0;
    _Static_assert(sizeof r->ranges < sizeof err->message, "the ranges fit a reply's message");
    emm_status st = status_call(r, OP_DECIDE, NULL, 0, r->ranges, sizeof r->ranges, &n, err);
    if (st == EMM_OK) {
        r->nranges = (uint64_t)n;
        r->have_ranges = true;
    }
    r->decided = true;
    r->state = st == EMM_OK ? EMM_SESSION_SIMULATING : EMM_SESSION_OFF;
    return st;
}

emm_status session_remote_finish(emm_session *s, FILE *summary, emm_error *err)
{
    struct session_remote *r = s->remote;
    if (r->quiet)
        return EMM_OK;
    if (summary)
        fflush(summary);
    uint32_t say = summary != NULL;
    emm_status st = status_call(r, OP_FINISH, &say, sizeof say, NULL, 0, NULL, err);
    if (r->broken && summary) {
        fprintf(summary, "emm: %s\n", r->why.message);
        fflush(summary);
    }
    r->decided = true;
    r->state = EMM_SESSION_OFF;
    return st;
}

void session_remote_forked(emm_session *s)
{
    struct session_remote *r = s->remote;
    if (r->fd >= 0)
        close(r->fd);
    r->fd = -1;
    r->broken = r->quiet = true;
}

void session_remote_free(emm_session *s)
{
    if (s->remote && s->remote->fd >= 0)
        close(s->remote->fd); /* the server sees the end and leaves */
    free(s->remote);
    free(s);
}

/* ---- the server: the real session, natively -------------------------------- */

struct message {
    struct message *next;
    struct frame f;
    unsigned char *data; /* f.len bytes */
};

struct server {
    int fd;
    emm_session *s;
    char **sources;      /* the config's source names, owned */
    /* the reader thread's queue */
    pthread_mutex_t lock;
    pthread_cond_t more, room;
    struct message *head, *tail;
    size_t queued;
    bool ended;          /* the client closed, or a frame was malformed */
    bool waiting;        /* the client waits for a REPLY: it answers READs */
    bool stop;           /* the service is over: the reader leaves */
};

static void drop_message(struct message *m)
{
    if (m)
        free(m->data);
    free(m);
}

/* A frame's bytes, in memory that grows as they arrive: a header that
 * claims more than comes costs no more than what came. */
static bool recv_data(int fd, struct message *m)
{
    uint64_t have = 0, cap = 0;
    while (have < m->f.len) {
        if (have == cap) {
            cap = cap ? 2 * cap : 65536;
            if (cap > m->f.len)
                cap = m->f.len;
            unsigned char *d = realloc(m->data, cap);
            if (!d)
                return false;
            m->data = d;
        }
        if (!recv_all(fd, m->data + have, cap - have))
            return false;
        have = cap;
    }
    return true;
}

static void *reader(void *arg)
{
    struct server *v = arg;
    for (;;) {
        struct message *m = calloc(1, sizeof *m);
        if (!m || !recv_all(v->fd, &m->f, sizeof m->f) || m->f.len > FRAME_MAX ||
            !recv_data(v->fd, m)) {
            drop_message(m);
            break;
        }
        pthread_mutex_lock(&v->lock);
        while (v->queued > SERVER_QUEUE_BYTES && v->head && !v->stop)
            pthread_cond_wait(&v->room, &v->lock);
        if (v->stop) {
            pthread_mutex_unlock(&v->lock);
            drop_message(m);
            break;
        }
        if (v->tail)
            v->tail->next = m;
        else
            v->head = m;
        v->tail = m;
        v->queued += m->f.len;
        pthread_cond_signal(&v->more);
        pthread_mutex_unlock(&v->lock);
    }
    pthread_mutex_lock(&v->lock);
    v->ended = true;
    pthread_cond_signal(&v->more);
    pthread_mutex_unlock(&v->lock);
    return NULL;
}

/* The next frame, or NULL at the end. */
static struct message *next_message(struct server *v)
{
    pthread_mutex_lock(&v->lock);
    while (!v->head && !v->ended)
        pthread_cond_wait(&v->more, &v->lock);
    struct message *m = v->head;
    if (m) {
        v->head = m->next;
        if (!v->head)
            v->tail = NULL;
        v->queued -= m->f.len;
        pthread_cond_signal(&v->room);
    }
    pthread_mutex_unlock(&v->lock);
    return m;
}

static bool reply(struct server *v, int64_t value, emm_status st, const void *data, size_t len)
{
    struct frame f = {.op = OP_REPLY, .value = value, .status = st, .len = len};
    v->waiting = false;
    return send_frame(v->fd, &f, data, len, NULL, 0);
}

/* Asks the waiting client for something (READ, MODULES) and takes the
 * BYTES it answers with: malloc'ed, *len bytes; NULL when it sent none. */
static unsigned char *ask(struct server *v, uint32_t op, uint64_t addr, uint64_t want,
                          uint64_t *len)
{
    struct frame f = {.op = op, .value = (int64_t)addr, .len = want};
    *len = 0;
    /* A client that does not wait reads no request: the session goes
     * without (session_decide_read has fetched what the rest needs). */
    if (!v->waiting || !send_frame(v->fd, &f, NULL, 0, NULL, 0))
        return NULL;
    struct message *m = next_message(v);
    if (!m || m->f.op != OP_BYTES) {
        drop_message(m);
        return NULL;
    }
    unsigned char *data = m->data;
    *len = m->f.len;
    m->data = NULL;
    drop_message(m);
    return data;
}

/* session_internal.h's pull: the array's bytes from the program. */
static void pull_array(emm_session *s, session_array *a)
{
    struct server *v = s->pull_ctx;
    uint64_t len, want = a->end - a->base;
    unsigned char *b = ask(v, OP_READ, a->base, want, &len);
    if (b && len == want)
        a->view = b;
    else
        free(b);
}

static void pull_modules(emm_session *s)
{
    struct server *v = s->pull_ctx;
    uint64_t len;
    unsigned char *b = ask(v, OP_MODULES, 0, 0, &len);
    uint32_t n = 0;
    size_t text = 0;
    for (uint64_t o = 0; b && o + 3 * sizeof(uint64_t) < len; n++) {
        o += 3 * sizeof(uint64_t);
        const unsigned char *z = memchr(b + o, 0, len - o);
        if (!z)
            break;
        text += (size_t)(z - (b + o)) + 1;
        o = (uint64_t)(z - b) + 1;
    }
    emm_trace_module *m = n ? malloc(n * sizeof *m + text) : NULL;
    if (m) {
        char *t = (char *)(m + n);
        uint64_t o = 0;
        for (uint32_t i = 0; i < n; i++) {
            uint64_t x[3];
            memcpy(x, b + o, sizeof x);
            o += sizeof x;
            size_t l = strlen((const char *)b + o) + 1;
            memcpy(t, b + o, l);
            m[i] = (emm_trace_module){x[0], x[1], x[2], t};
            t += l;
            o += l;
        }
        free(s->modules);
        s->modules = m;
        s->nmodules = n;
    }
    free(b);
}

static emm_status serve_new(struct server *v, const struct message *m, emm_error *err)
{
    struct wire_new w;
    emm_config cfg;
    if (m->f.len < sizeof w + sizeof cfg)
        return emm_fail(err, EMM_ERR_FORMAT, "emm-session: a malformed start");
    memcpy(&w, m->data, sizeof w);
    if (w.version != SESSION_WIRE_VERSION || w.config_bytes != sizeof cfg)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "emm-session: the shim and the session server are of different builds");
    memcpy(&cfg, m->data + sizeof w, sizeof cfg);
    const char *p = (const char *)m->data + sizeof w + sizeof cfg,
               *end = (const char *)m->data + m->f.len;
    v->sources = calloc(EMM_CONFIG_COUNT, sizeof *v->sources);
    if (!v->sources)
        return emm_fail(err, EMM_ERR_NOMEM, "emm-session: out of memory");
    for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
        const char *z = p < end ? memchr(p, 0, (size_t)(end - p)) : NULL;
        if (!z)
            return emm_fail(err, EMM_ERR_FORMAT, "emm-session: a malformed start");
        cfg.source[k] = NULL;
        if (*p && !(cfg.source[k] = v->sources[k] = strdup(p)))
            return emm_fail(err, EMM_ERR_NOMEM, "emm-session: out of memory");
        p = z + 1;
    }
    if (p >= end || !memchr(p, 0, (size_t)(end - p)))
        return emm_fail(err, EMM_ERR_FORMAT, "emm-session: a malformed start");
    emm_session_config sc = {&cfg, (emm_capture)w.capture, p, w.table_only, {0, NULL, NULL},
                             NULL};
    emm_status st = emm_session_new(&sc, &v->s, err);
    if (st == EMM_OK) {
        v->s->foreign = true;
        v->s->pull = pull_array;
        v->s->pull_modules = pull_modules;
        v->s->pull_ctx = v;
    }
    return st;
}

/* One call; false ends the service (a malformed frame). */
/* The session's ranges, as the answer. */
static bool reply_ranges(struct server *v, emm_session *s)
{
    uint64_t pairs[2 * SESSION_MAX_ARRAYS];
    uint64_t lo[SESSION_MAX_ARRAYS], hi[SESSION_MAX_ARRAYS];
    size_t n = emm_session_ranges(s, lo, hi, SESSION_MAX_ARRAYS);
    size_t k = n < SESSION_MAX_ARRAYS ? n : SESSION_MAX_ARRAYS;
    for (size_t i = 0; i < k; i++) {
        pairs[2 * i] = lo[i];
        pairs[2 * i + 1] = hi[i];
    }
    return reply(v, (int64_t)n, EMM_OK, pairs, k * 2 * sizeof *pairs);
}

static bool serve_one(struct server *v, const struct message *m)
{
    emm_error e = {0};
    emm_session *s = v->s;
    v->waiting = m->f.wait != 0;
    if (m->f.op == OP_NEW) {
        emm_status st = s ? emm_fail(&e, EMM_ERR_FORMAT, "emm-session: started twice")
                          : serve_new(v, m, &e);
        reply(v, 0, st, e.message, st == EMM_OK ? 0 : strlen(e.message) + 1);
        return st == EMM_OK;
    }
    if (!s)
        return false;
    switch (m->f.op) {
    case OP_TAG: {
        struct wire_tag t;
        if (m->f.len != sizeof t)
            return false;
        memcpy(&t, m->data, sizeof t);
        int idx = emm_session_tag_rule(s, (emm_array_kind)t.kind, (const void *)(uintptr_t)t.base,
                                       t.count, t.stride, t.field, (emm_scalar)t.type, t.rule);
        return reply(v, idx, EMM_OK, NULL, 0);
    }
    case OP_MOVE: {
        uint64_t a[3];
        if (m->f.len != sizeof a)
            return false;
        memcpy(a, m->data, sizeof a);
        emm_session_state st = emm_session_move(s, (const void *)(uintptr_t)a[0],
                                                (const void *)(uintptr_t)a[1], a[2]);
        return reply(v, st, EMM_OK, NULL, 0);
    }
    case OP_UNTAG: {
        uint64_t b;
        if (m->f.len != sizeof b)
            return false;
        memcpy(&b, m->data, sizeof b);
        return reply(v, emm_session_untag(s, (const void *)(uintptr_t)b), EMM_OK, NULL, 0);
    }
    case OP_RANGES:
        return reply_ranges(v, s);
    case OP_ACCESS: {
        if (m->f.len % sizeof(emm_raw_access))
            return false;
        /* The frame's bytes are malloc'ed: aligned for the records. */
        emm_session_state st = emm_session_access(s, (const emm_raw_access *)(void *)m->data,
                                                  m->f.len / sizeof(emm_raw_access));
        return !m->f.wait || reply(v, st, EMM_OK, NULL, 0);
    }
    case OP_ITERATION: {
        emm_session_state st = emm_session_iteration(s);
        return !m->f.wait || reply(v, st, EMM_OK, NULL, 0);
    }
    case OP_DECIDE: {
        /* The program goes on once the decision has read it; the rest of
         * the decision overlaps with its run (its accesses queue up). A
         * failure then is the summary's, at finish, as in the program. */
        emm_status st = session_decide_begin(s, &e);
        if (st != EMM_OK)
            return reply(v, 0, st, e.message, strlen(e.message) + 1);
        if (!reply_ranges(v, s))
            return false;
        session_decide_end(s, &e);
        return true;
    }
    case OP_FINISH: {
        uint32_t say = 0;
        if (m->f.len == sizeof say)
            memcpy(&say, m->data, sizeof say);
        emm_status st = emm_session_finish(s, say ? stderr : NULL, &e);
        return reply(v, 0, st, e.message, st == EMM_OK ? 0 : strlen(e.message) + 1);
    }
    default:
        return false;
    }
}

emm_status emm_session_serve(int fd, emm_error *err)
{
    struct server v = {.fd = fd};
    pthread_t th;
    signal(SIGPIPE, SIG_IGN);
    pthread_mutex_init(&v.lock, NULL);
    pthread_cond_init(&v.more, NULL);
    pthread_cond_init(&v.room, NULL);
    if (pthread_create(&th, NULL, reader, &v) != 0)
        return emm_fail(err, EMM_ERR_NOMEM, "emm-session: cannot start its reader thread");
    emm_status st = EMM_OK;
    struct message *m;
    while ((m = next_message(&v)) != NULL) {
        bool ok = serve_one(&v, m);
        drop_message(m);
        if (!ok) {
            st = emm_fail(err, EMM_ERR_FORMAT, "emm-session: a call it could not serve");
            break;
        }
    }
    /* The client is gone (or spoke nonsense): stop reading, free all. */
    pthread_mutex_lock(&v.lock);
    v.stop = true;
    pthread_cond_broadcast(&v.room);
    pthread_mutex_unlock(&v.lock);
    shutdown(fd, SHUT_RDWR);
    pthread_join(th, NULL);
    while ((m = next_message(&v)) != NULL)
        drop_message(m);
    emm_session_free(v.s);
    if (v.sources)
        for (int k = 0; k < EMM_CONFIG_COUNT; k++)
            free(v.sources[k]);
    free(v.sources);
    pthread_mutex_destroy(&v.lock);
    pthread_cond_destroy(&v.more);
    pthread_cond_destroy(&v.room);
    return st;
}
