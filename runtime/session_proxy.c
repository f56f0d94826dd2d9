/* A session whose engine runs in another process (docs/architecture.md
 * "The session"): under Valgrind every instruction of the client is
 * translated, the session's profiling and simulation too, which made them
 * about nine times slower than natively. With emm_session_config.server
 * set, emm_session_new starts that executable (emm-session, server/) as a
 * native process and the handle becomes this proxy: each call goes over a
 * socket (session_wire.h) and the server runs the engine. The program goes
 * on while the server simulates, on the other core.
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
 * - the engine reads the program's memory only inside a call that waits
 *   (the geometry at the decision, an array's fields when it leaves before
 *   it): the server then asks for those bytes (a READ), and for the
 *   program's loaded objects (MODULES, for program counters' source lines),
 *   and the waiting proxy sends them from its memory as it is right then.
 * The server's summary goes to its stderr, which is the program's. A proxy
 * that loses its server (it died, or never started) answers
 * EMM_SESSION_OFF and says why at finish. SIGPIPE is never raised in the
 * program (MSG_NOSIGNAL). */
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "error.h"
#include "session_transport.h"
#include "session_wire.h"
#include "srcline.h"

typedef struct proxy {
    emm_session handle;   /* first: the handle is the proxy's address */
    int fd;
    bool broken;          /* the server is gone: every call answers OFF */
    bool quiet;           /* a forked child's copy: nothing to say */
    bool decided;         /* the decision was made: accesses no longer wait */
    bool have_ranges;     /* ranges holds the session's ranges (from the decision) */
    uint64_t nranges;     /* the session's count */
    uint64_t *ranges;     /* [lo, hi) pairs, malloc'ed; min(nranges, what came) of them */
    size_t got;
    emm_session_state state;
    emm_error why;        /* why the server is gone */
    char program[256];
} proxy;

static void lost(proxy *r, const char *what)
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

static bool send_bytes(proxy *r, const void *p, size_t len)
{
    struct wire_frame f = {.op = WIRE_BYTES, .len = len};
    return wire_send(r->fd, &f, p, len, NULL, 0);
}

static bool send_modules(proxy *r)
{
    emm_trace_module *m = NULL;
    uint32_t n = 0;
    unsigned char *b = NULL;
    size_t len = 0;
    if (emm_process_modules(&m, &n, NULL) != EMM_OK)
        n = 0;
    bool ok = wire_modules_encode(m, n, &b, &len) ? send_bytes(r, b, len) : send_bytes(r, NULL, 0);
    free(b);
    free(m);
    return ok;
}

/* Sends a call; when it waits, serves the server's READs and MODULES until
 * its REPLY, whose payload goes to *payload (malloc'ed, *plen bytes) when
 * payload is not NULL, and is dropped otherwise. */
static bool call(proxy *r, uint32_t op, bool wait, const void *a, size_t alen,
                 struct wire_frame *reply, unsigned char **payload, size_t *plen)
{
    if (payload)
        *payload = NULL;
    if (r->broken)
        return false;
    if (op != WIRE_ACCESS && op != WIRE_ITERATION && op != WIRE_RANGES)
        r->have_ranges = false; /* a call that may change them */
    struct wire_frame f = {.op = op, .wait = wait, .len = alen};
    if (!wire_send(r->fd, &f, a, alen, NULL, 0)) {
        lost(r, "(the socket closed)");
        return false;
    }
    while (wait) {
        if (!wire_recv(r->fd, reply, sizeof *reply) || reply->len > WIRE_FRAME_MAX) {
            lost(r, "before answering");
            return false;
        }
        if (reply->op == WIRE_READ) {
            if (!send_bytes(r, (const void *)(uintptr_t)reply->value, reply->len)) {
                lost(r, "(the program's arrays could not be sent)");
                return false;
            }
        } else if (reply->op == WIRE_MODULES) {
            if (!send_modules(r)) {
                lost(r, "(the program's objects could not be sent)");
                return false;
            }
        } else if (reply->op == WIRE_REPLY) {
            unsigned char *data;
            if (!wire_recv_data(r->fd, reply, &data)) {
                free(data);
                lost(r, "while answering");
                return false;
            }
            if (payload) {
                *payload = data;
                *plen = (size_t)reply->len;
            } else {
                free(data);
            }
            return true;
        } else {
            lost(r, "(it sent something unexpected)");
            return false;
        }
    }
    return true;
}

/* A call whose REPLY carries a status, and a message when it failed; on
 * success the payload goes to *payload (may be NULL: dropped) and the
 * value to *value (may be NULL). */
static emm_status status_call(proxy *r, uint32_t op, const void *a, size_t alen,
                              unsigned char **payload, size_t *plen, int64_t *value,
                              emm_error *err)
{
    struct wire_frame reply;
    unsigned char *data;
    size_t len = 0;
    if (payload)
        *payload = NULL;
    if (!call(r, op, true, a, alen, &reply, &data, &len)) {
        if (err)
            *err = r->why;
        return r->why.status;
    }
    if (reply.status != EMM_OK) {
        if (err) {
            err->status = (emm_status)reply.status;
            snprintf(err->message, sizeof err->message, "%.*s",
                     (int)(len < sizeof err->message ? len : sizeof err->message - 1),
                     data ? (const char *)data : "");
        }
        free(data);
        return (emm_status)reply.status;
    }
    if (value)
        *value = reply.value;
    if (payload) {
        *payload = data;
        *plen = len;
    } else {
        free(data);
    }
    return EMM_OK;
}

emm_status session_server_start(const char *path, bool detach, int *sock, int *done, pid_t *pid,
                                emm_error *err)
{
    int sv[2], dp[2] = {-1, -1};
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
        return emm_fail(err, EMM_ERR_IO, "session server: socketpair: %s", strerror(errno));
    if (done && pipe2(dp, O_CLOEXEC) != 0) {
        int e = errno;
        close(sv[0]);
        close(sv[1]);
        return emm_fail(err, EMM_ERR_IO, "session server: pipe: %s", strerror(e));
    }
    /* Everything the child needs is made before the fork: it may be the
     * child of a threaded program, where only async-signal-safe calls are. */
    extern char **environ;
    size_t n = 0;
    for (char **e = environ; e && *e; e++)
        n++;
    char **env = malloc((n + 1) * sizeof *env);
    if (!env) {
        close(sv[0]);
        close(sv[1]);
        if (done) {
            close(dp[0]);
            close(dp[1]);
        }
        return emm_fail(err, EMM_ERR_NOMEM, "session server: out of memory");
    }
    size_t k = 0;
    for (char **e = environ; e && *e; e++)
        if (strncmp(*e, "LD_PRELOAD=", 11) != 0)
            env[k++] = *e;
    env[k] = NULL;
    char *argv[] = {(char *)path, (char *)"3", done ? (char *)"4" : NULL, NULL};
    int devnull = open("/dev/null", O_RDWR | O_CLOEXEC);
    pid_t child = fork();
    if (child == 0 && (!detach || fork() == 0)) {
        if (devnull >= 0) {
            dup2(devnull, 0);
            dup2(devnull, 1);
        }
        /* Out of 3 and 4's way first: dup2 then leaves them open at exec
         * (onto itself it would leave the close-on-exec flag). */
        int s3 = fcntl(sv[1], F_DUPFD_CLOEXEC, 10), s4 = done ? fcntl(dp[1], F_DUPFD_CLOEXEC, 10) : 0;
        if (s3 >= 0 && s4 >= 0 && dup2(s3, 3) == 3 && (!done || dup2(s4, 4) == 4))
            execve(path, argv, env);
        _exit(127);
    }
    if (child == 0)
        _exit(0); /* the detached server's first parent */
    int e = errno;
    if (devnull >= 0)
        close(devnull);
    free(env);
    close(sv[1]);
    if (done)
        close(dp[1]);
    if (child < 0) {
        close(sv[0]);
        if (done)
            close(dp[0]);
        return emm_fail(err, EMM_ERR_IO, "session server: fork: %s", strerror(e));
    }
    if (detach)
        while (waitpid(child, NULL, 0) < 0 && errno == EINTR) {
        }
    *sock = sv[0];
    if (done)
        *done = dp[0];
    if (pid)
        *pid = detach ? 0 : child;
    return EMM_OK;
}

static int proxy_tag(emm_session *h, const emm_array_desc *d)
{
    proxy *r = (proxy *)h;
    unsigned char *b;
    size_t len;
    struct wire_frame reply;
    if (!wire_tag_encode(d, &b, &len))
        return -1;
    bool ok = call(r, WIRE_TAG, true, b, len, &reply, NULL, NULL);
    free(b);
    return ok ? (int)reply.value : -1;
}

/* A call whose answer is the session's state. */
static emm_session_state state_call(proxy *r, uint32_t op, bool wait, const void *a, size_t alen)
{
    struct wire_frame reply;
    if (!call(r, op, wait, a, alen, &reply, NULL, NULL))
        return EMM_SESSION_OFF;
    if (wait)
        r->state = (emm_session_state)reply.value;
    return r->state;
}

static emm_session_state proxy_move(emm_session *h, uint64_t old, uint64_t base, uint64_t count)
{
    uint64_t m[3] = {old, base, count};
    return state_call((proxy *)h, WIRE_MOVE, true, m, sizeof m);
}

static emm_session_state proxy_untag(emm_session *h, uint64_t base)
{
    return state_call((proxy *)h, WIRE_UNTAG, true, &base, sizeof base);
}

/* The ranges a reply carries: its value the session's count, its payload
 * as many [lo, hi) pairs as it holds. */
static void take_ranges(proxy *r, int64_t n, unsigned char *payload, size_t len)
{
    free(r->ranges);
    r->ranges = (uint64_t *)(void *)payload; /* malloc'ed: aligned */
    r->nranges = n > 0 ? (uint64_t)n : 0;
    r->got = len / (2 * sizeof(uint64_t));
    r->have_ranges = true;
}

static size_t proxy_ranges(const emm_session *h, uint64_t *lo, uint64_t *hi, size_t cap)
{
    proxy *r = (proxy *)(uintptr_t)h;
    if (!r->have_ranges || r->broken) {
        unsigned char *payload;
        size_t len;
        int64_t n;
        uint64_t c = cap;
        if (status_call(r, WIRE_RANGES, &c, sizeof c, &payload, &len, &n, NULL) != EMM_OK)
            return 0;
        take_ranges(r, n, payload, len);
        r->have_ranges = false; /* only the decision's stand until the next call */
    }
    for (size_t i = 0; i < r->nranges && i < cap && i < r->got; i++) {
        lo[i] = r->ranges[2 * i];
        hi[i] = r->ranges[2 * i + 1];
    }
    return (size_t)r->nranges;
}

static emm_session_state proxy_access(emm_session *h, const emm_raw_access *a, size_t n)
{
    proxy *r = (proxy *)h;
    if (n == 0)
        return r->broken ? EMM_SESSION_OFF : r->state;
    return state_call(r, WIRE_ACCESS, !r->decided, a, n * sizeof *a);
}

static emm_session_state proxy_iteration(emm_session *h)
{
    proxy *r = (proxy *)h;
    return state_call(r, WIRE_ITERATION, !r->decided, NULL, 0);
}

/* The server answers as soon as it has read what the decision needs of the
 * program, with the arrays' ranges from then on (the program asks for them
 * next), and decides while the program goes on. */
static emm_status proxy_decide_read(emm_session *h, emm_error *err)
{
    proxy *r = (proxy *)h;
    unsigned char *payload;
    size_t len = 0;
    int64_t n = 0;
    emm_status st = status_call(r, WIRE_DECIDE, NULL, 0, &payload, &len, &n, err);
    if (st == EMM_OK && n < 0) {
        /* The session profiles again (its window started again). */
        free(payload);
        r->state = EMM_SESSION_PROFILING;
        return EMM_OK;
    }
    if (st == EMM_OK)
        take_ranges(r, n, payload, len);
    r->decided = true;
    r->state = st == EMM_OK ? EMM_SESSION_SIMULATING : EMM_SESSION_OFF;
    return st;
}

/* The server goes on with the rest of the decision by itself. */
static emm_status proxy_decide_rest(emm_session *h, emm_error *err)
{
    (void)h;
    (void)err;
    return EMM_OK;
}

static emm_status proxy_finish(emm_session *h, FILE *summary, const char *ended,
                               emm_error *err)
{
    proxy *r = (proxy *)h;
    if (r->quiet)
        return EMM_OK;
    if (summary)
        fflush(summary);
    /* Flags (1: print the summary; 2: discard, proxy_discard), then how the
     * run ended, if not normally. */
    char msg[4 + 96] = {0};
    uint32_t say = summary != NULL;
    memcpy(msg, &say, sizeof say);
    size_t n = ended ? strnlen(ended, sizeof msg - 5) : 0;
    if (n)
        memcpy(msg + 4, ended, n);
    emm_status st = status_call(r, WIRE_FINISH, msg, 4 + n, NULL, NULL, NULL, err);
    if (r->broken && summary) {
        fprintf(summary, "emm: %s\n", r->why.message);
        fflush(summary);
    }
    r->decided = true;
    r->state = EMM_SESSION_OFF;
    return st;
}

/* FINISH with the discard flag (2): the server ends the session silently. */
static void proxy_discard(emm_session *h)
{
    proxy *r = (proxy *)h;
    uint32_t flags = 2;
    if (!r->quiet)
        status_call(r, WIRE_FINISH, &flags, sizeof flags, NULL, NULL, NULL, NULL);
    r->decided = true;
    r->state = EMM_SESSION_OFF;
}

static void proxy_forked(emm_session *h)
{
    proxy *r = (proxy *)h;
    if (r->fd >= 0)
        close(r->fd);
    r->fd = -1;
    r->broken = r->quiet = true;
}

static void proxy_free(emm_session *h)
{
    proxy *r = (proxy *)h;
    if (r->fd >= 0)
        close(r->fd); /* the server sees the end and leaves */
    free(r->ranges);
    free(r);
}

static const struct session_transport proxy_transport = {
    proxy_tag,         proxy_move,       proxy_untag,  proxy_ranges,
    proxy_access,      proxy_iteration,  proxy_decide_read,
    proxy_decide_rest, proxy_finish,     proxy_discard, proxy_forked, proxy_free,
};

emm_status session_proxy_new(const emm_session_config *sc, emm_session **out, emm_error *err)
{
    *out = NULL;
    proxy *r = calloc(1, sizeof *r);
    if (!r)
        return emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
    r->handle.transport = &proxy_transport;
    r->fd = -1;
    r->state = EMM_SESSION_PROFILING;
    snprintf(r->program, sizeof r->program, "%s", sc->program ? sc->program : "program");
    /* A session emm run started beside Valgrind, before the program: the
     * program is spared two forks under Valgrind and the session's start. */
    emm_status st = EMM_OK;
    if (sc->server_sock > 2)
        r->fd = sc->server_sock;
    else if ((st = session_server_start(sc->server, true, &r->fd, NULL, NULL, err)) != EMM_OK)
        goto fail;
    unsigned char *msg;
    size_t bytes;
    if (!wire_start_encode(sc, (long)getpid(), &msg, &bytes)) {
        st = emm_fail(err, EMM_ERR_NOMEM, "session: out of memory");
        goto fail;
    }
    st = status_call(r, WIRE_NEW, msg, bytes, NULL, NULL, NULL, err);
    free(msg);
    if (st != EMM_OK)
        goto fail;
    *out = &r->handle;
    return EMM_OK;
fail:
    proxy_free(&r->handle);
    return st;
}
