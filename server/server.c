/* emm-session's body: the engine of one program's session, run natively,
 * served over a socket to the proxy inside the program
 * (runtime/session_proxy.c; the frames are runtime/session_wire.h). It uses
 * the public session API like any caller: the program's memory is read
 * through the session's memory seam (emm_session_memory), which asks the
 * waiting proxy for the bytes.
 *
 * A reader thread takes the frames off the socket into a queue while the
 * session works (the decision's profile and sweeps, the models), so the
 * program is not held up by a full socket; the queue holds at most
 * SERVER_QUEUE_BYTES before the program waits. A client that goes away
 * ends the service quietly; a frame that makes no sense ends it with an
 * error. */
#include "server.h"

#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "emm/session.h"
#include "error.h"
#include "pool.h"
#include "session_wire.h"

/* Bytes the reader may hold before the program waits. */
#define SERVER_QUEUE_BYTES ((size_t)64 << 20)

struct message {
    struct message *next;
    struct wire_frame f;
    unsigned char *data; /* f.len bytes */
};

struct server {
    int fd;
    int done;            /* closed once the finish has answered (-1: none) */
    emm_session *s;
    emm_config cfg;
    char *strings;       /* the config's source names, owned */
    emm_session_memory memory;
    /* the reader thread's queue */
    pthread_mutex_t lock;
    pthread_cond_t more, room;
    struct message *head, *tail;
    size_t queued;
    bool ended;          /* the client closed, or a frame was malformed */
    bool waiting;        /* the client waits for a REPLY: it answers READs */
    bool stop;           /* the service is over: the reader leaves */
    bool finished;       /* the client's FINISH came */
};

static void drop_message(struct message *m)
{
    if (m)
        free(m->data);
    free(m);
}

static void *reader(void *arg)
{
    struct server *v = arg;
    for (;;) {
        struct message *m = calloc(1, sizeof *m);
        if (!m || !wire_recv(v->fd, &m->f, sizeof m->f) || m->f.len > WIRE_FRAME_MAX ||
            !wire_recv_data(v->fd, &m->f, &m->data)) {
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
    struct wire_frame f = {.op = WIRE_REPLY, .value = value, .status = st, .len = len};
    v->waiting = false;
    return wire_send(v->fd, &f, data, len, NULL, 0);
}

static bool reply_status(struct server *v, emm_status st, const emm_error *e)
{
    return reply(v, 0, st, e->message, st == EMM_OK ? 0 : strlen(e->message) + 1);
}

/* Asks the waiting client for something (READ, MODULES) and takes the
 * BYTES it answers with: malloc'ed, *len bytes; NULL when it sent none. */
static unsigned char *ask(struct server *v, uint32_t op, uint64_t addr, uint64_t want,
                          uint64_t *len)
{
    struct wire_frame f = {.op = op, .value = (int64_t)addr, .len = want};
    *len = 0;
    /* A client that does not wait reads no request: the session goes
     * without (the decision's reading part has fetched what the rest
     * needs). */
    if (!v->waiting || !wire_send(v->fd, &f, NULL, 0, NULL, 0))
        return NULL;
    struct message *m = next_message(v);
    if (!m || m->f.op != WIRE_BYTES) {
        drop_message(m);
        return NULL;
    }
    unsigned char *data = m->data;
    *len = m->f.len;
    m->data = NULL;
    drop_message(m);
    return data;
}

/* The memory seam: the program's bytes, whole or not at all. */
static void *read_program(void *ctx, uint64_t addr, uint64_t want)
{
    uint64_t len;
    unsigned char *b = ask(ctx, WIRE_READ, addr, want, &len);
    if (b && len == want)
        return b;
    free(b);
    return NULL;
}

static int program_modules(void *ctx, emm_trace_module **out, uint32_t *n)
{
    uint64_t len;
    unsigned char *b = ask(ctx, WIRE_MODULES, 0, 0, &len);
    bool ok = b && wire_modules_decode(b, (size_t)len, out, n);
    free(b);
    return ok;
}

static emm_status serve_new(struct server *v, const struct message *m, emm_error *err)
{
    emm_capture capture;
    int table_only;
    unsigned expect;
    const char *program;
    long pid;
    emm_status st = wire_start_decode(m->data, (size_t)m->f.len, &v->cfg, &v->strings, &capture,
                                      &table_only, &expect, &program, &pid, err);
    if (st != EMM_OK)
        return st;
    v->memory = (emm_session_memory){read_program, program_modules, v};
    emm_session_config sc = {&v->cfg, capture, program, table_only, {0, NULL, NULL}, NULL,
                             &v->memory, pid, expect, 0};
    return emm_session_new(&sc, &v->s, err);
}

/* The session's ranges, as the answer. */
static bool reply_ranges(struct server *v)
{
    size_t n = emm_session_ranges(v->s, NULL, NULL, 0);
    uint64_t *pairs = malloc((n ? n : 1) * 2 * sizeof *pairs);
    uint64_t *lo = malloc((n ? n : 1) * sizeof *lo), *hi = malloc((n ? n : 1) * sizeof *hi);
    size_t k = 0;
    if (pairs && lo && hi) {
        k = emm_session_ranges(v->s, lo, hi, n);
        k = k < n ? k : n;
        for (size_t i = 0; i < k; i++) {
            pairs[2 * i] = lo[i];
            pairs[2 * i + 1] = hi[i];
        }
    }
    bool ok = reply(v, (int64_t)n, EMM_OK, pairs, k * 2 * sizeof *pairs);
    free(pairs);
    free(lo);
    free(hi);
    return ok;
}

/* One call; false ends the service: a malformed frame (*quiet false), or a
 * session that could not start, which the client reports (*quiet set). */
static bool serve_one(struct server *v, const struct message *m, bool *quiet)
{
    emm_error e = {0};
    emm_session *s = v->s;
    v->waiting = m->f.wait != 0;
    if (m->f.op == WIRE_NEW) {
        emm_status st = s ? emm_fail(&e, EMM_ERR_FORMAT, "emm-session: started twice")
                          : serve_new(v, m, &e);
        reply_status(v, st, &e);
        *quiet = !s;
        return st == EMM_OK;
    }
    if (!s)
        return false;
    switch (m->f.op) {
    case WIRE_TAG: {
        emm_array_desc d;
        if (!wire_tag_decode(m->data, (size_t)m->f.len, &d))
            return false;
        return reply(v, emm_session_tag(s, &d), EMM_OK, NULL, 0);
    }
    case WIRE_MOVE: {
        uint64_t a[3];
        if (m->f.len != sizeof a)
            return false;
        memcpy(a, m->data, sizeof a);
        emm_session_state st = emm_session_move(s, (const void *)(uintptr_t)a[0],
                                                (const void *)(uintptr_t)a[1], (size_t)a[2]);
        return reply(v, st, EMM_OK, NULL, 0);
    }
    case WIRE_UNTAG: {
        uint64_t b;
        if (m->f.len != sizeof b)
            return false;
        memcpy(&b, m->data, sizeof b);
        return reply(v, emm_session_untag(s, (const void *)(uintptr_t)b), EMM_OK, NULL, 0);
    }
    case WIRE_RANGES:
        return reply_ranges(v);
    case WIRE_ACCESS: {
        if (m->f.len % sizeof(emm_raw_access))
            return false;
        /* The frame's bytes are malloc'ed: aligned for the records. */
        emm_session_state st = emm_session_access(s, (const emm_raw_access *)(void *)m->data,
                                                  m->f.len / sizeof(emm_raw_access));
        return !m->f.wait || reply(v, st, EMM_OK, NULL, 0);
    }
    case WIRE_ITERATION: {
        emm_session_state st = emm_session_iteration(s);
        return !m->f.wait || reply(v, st, EMM_OK, NULL, 0);
    }
    case WIRE_DECIDE: {
        /* The program goes on once the decision has read it; the rest of
         * the decision overlaps with its run (its accesses queue up). A
         * failure then is the summary's, at finish, as in the program. */
        emm_status st = emm_session_decide_read(s, &e);
        if (st != EMM_OK)
            return reply_status(v, st, &e);
        /* No decision: the window starts again (a half-edge mesh still
         * being built), and the program's accesses are awaited again. */
        if (emm_session_access(s, NULL, 0) == EMM_SESSION_PROFILING)
            return reply(v, -1, EMM_OK, NULL, 0);
        if (!reply_ranges(v))
            return false;
        emm_session_decide_rest(s, &e);
        return true;
    }
    case WIRE_FINISH: {
        /* Flags (1: print the summary; 2: discard the session, no output),
         * then how the run ended, if not normally. */
        uint32_t say = 0;
        char ended[96] = "";
        if (m->f.len < sizeof say || m->f.len >= sizeof say + sizeof ended)
            return false;
        memcpy(&say, m->data, sizeof say);
        memcpy(ended, m->data + sizeof say, (size_t)m->f.len - sizeof say);
        v->finished = true;
        if (say & 2) {
            emm_session_discard(s);
            return reply_status(v, EMM_OK, &e);
        }
        emm_status st = emm_session_finish_ended(s, say ? stderr : NULL, ended[0] ? ended : NULL,
                                                 &e);
        bool ok = reply_status(v, st, &e);
        /* Every output is written (and the program has its answer). */
        if (v->done >= 0)
            close(v->done);
        v->done = -1;
        return ok;
    }
    default:
        return false;
    }
}

emm_status emm_server_serve(int fd, int done, emm_error *err)
{
    struct server v = {.fd = fd, .done = done};
    pthread_t th;
    signal(SIGPIPE, SIG_IGN);
    emm_config_init(&v.cfg);
    pthread_mutex_init(&v.lock, NULL);
    pthread_cond_init(&v.more, NULL);
    pthread_cond_init(&v.room, NULL);
    if (emm_thread_start(&th, reader, &v) != 0)
        return emm_fail(err, EMM_ERR_NOMEM, "emm-session: cannot start its reader thread");
    emm_status st = EMM_OK;
    struct message *m;
    while ((m = next_message(&v)) != NULL) {
        bool quiet = false, ok = serve_one(&v, m, &quiet);
        drop_message(m);
        if (!ok) {
            if (!quiet)
                st = emm_fail(err, EMM_ERR_FORMAT, "emm-session: a call it could not serve");
            break;
        }
    }
    /* The client left before its FINISH — the program closed the socket
     * with its other descriptors, or died: the run so far is still the
     * program's, and its report is written. */
    if (v.s && !v.finished) {
        emm_error e;
        emm_session_finish_ended(v.s, v.cfg.log >= 1 ? stderr : NULL,
                                 st == EMM_OK ? "the end of the program's connection to "
                                                "emm-session, before its exit"
                                              : "a call emm-session could not serve",
                                 &e);
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
    emm_config_free(&v.cfg);
    free(v.strings);
    pthread_mutex_destroy(&v.lock);
    pthread_cond_destroy(&v.more);
    pthread_cond_destroy(&v.room);
    return st;
}
