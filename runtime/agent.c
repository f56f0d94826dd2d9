/* The runtime's side of libemmshim.so (include/emm/agent.h): the tagged
 * blocks, the rules, the session's driving, list mode.
 *
 * - The tag table grows as blocks are tagged. free() asks every pointer,
 *   so its quick test reads no table: a counting filter of the tagged
 *   bases' hashes, updated with atomics, answers "certainly not" without a
 *   lock; a maybe takes the lock and the table.
 * - The session is not thread-safe: every call into it is made under the
 *   agent's lock, and so are the backend's hooks.
 * - A block moved by realloc stays the same array: the session keeps its
 *   place and its window (a loader growing its arrays does not end the
 *   window). The backend's untag side runs before the copy (the fault
 *   backend's pages open, the valgrind tool told no ranges: the copy is not
 *   the program's access) and its tag side after.
 * - A fork's child goes quiet: no session, no report (the parent's report
 *   covers the run); an exec'd program starts its own session, and says
 *   nothing at its end when it tagged nothing (a tool the program runs is
 *   none of its answer). Helpers, symbolizers, are not entered at all. */
#include "emm/agent.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <elf.h>
#include <errno.h>
#include <link.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "agent_rules.h"
#include "emm/mesh.h"
#include "emm/sites.h"
#include "error.h"

/* EMM_LIST_SITES: the smallest block listed, and the smallest recorded
 * for the replay of the suggested rules (the least a rule without min=
 * selects). */
#define LIST_MIN (64 * 1024)
#define LIST_LOG_MIN 4096
/* List mode: reallocs in flight, one per thread at most. */
#define MOVES 16
/* The quick test's filter: counts of tagged bases by hash. */
#define FILTER_BITS 12

struct tag {
    uintptr_t base; /* the pointer the program holds (and frees) */
    size_t bytes;   /* bytes the array spans: count * stride */
    emm_array_kind kind;
    size_t stride, offset;
    emm_scalar type;
    int rule;       /* the EMM_TAG rule that selected it (count follows the block's size on
                       realloc), or -1 for an emm_tag_* call */
    void *map;      /* the block's own pages (the backend's map), or NULL */
    size_t map_len;
};

struct emm_agent {
    pthread_mutex_t lock;
    emm_config cfg;
    emm_capture capture;
    emm_agent_hooks hooks;
    char *program;
    emm_session *session; /* NULL in list mode */
    struct timespec started; /* CLOCK_REALTIME_COARSE at its start (list mode's report) */
    emm_sites *sites;      /* list mode: the candidate arrays */
    agent_rules *rules;
    size_t min_block;
    emm_session_state state;
    int active;            /* atomic: not finished, not a forked child's */
    int finishing;         /* atomic: finish has begun */
    bool failed;           /* decide failed: stop feeding the session */
    bool child;            /* a process the program started (EMM_AGENT_ROOT_VAR) */
    uint64_t listed;       /* list mode: blocks noted */
    struct move {
        pthread_t thread;
        int64_t from;      /* the recorded block a realloc of this thread moves */
        bool used;
    } moves[MOVES];        /* list mode, under lock */
    bool last_drain;       /* list mode: the accesses drained at the end are taken */
    struct tag *tags;      /* ntags of them, ctags allocated */
    size_t ntags, ctags;
    uint64_t tagged_total; /* tag events, for the log */
    uint16_t filter[1u << FILTER_BITS]; /* atomic */
    uint64_t libc_memo[64];  /* atomic: (caller << 1) | whether the C library's (libc_block) */
    emm_agent_filter ranges; /* the backends' hot-path snapshot */
    size_t ranges_cap;
    struct retired {
        struct retired *next;
        uint64_t *lo, *len;
    } *retired;            /* snapshots replaced while a hot path might read them */
};

/* Where emm's words go: a duplicate of the stderr the process started with,
 * taken when the agent starts (close-on-exec, numbered high), and what it
 * pointed at. A program that closes its stderr and opens a file gets that
 * file as fd 2: emm's lines must not land in it. They go to the stderr the
 * user gave the program, or nowhere when that is gone (never opened, or
 * the program closed the duplicate too and the number now names another
 * file). One per process, as fd 2 is: the agent is the process's. */
#define SAY_FD_MIN 700
static struct {
    bool opened;
    int fd; /* -1: nowhere */
    dev_t dev;
    ino_t ino;
} say_to = {false, -1, 0, 0};

static void say_open(void)
{
    struct stat st;
    if (say_to.fd >= 0 && fstat(say_to.fd, &st) == 0 && st.st_dev == say_to.dev &&
        st.st_ino == say_to.ino)
        return; /* a forked child's agent keeps its parent's */
    int fd = fcntl(2, F_DUPFD_CLOEXEC, SAY_FD_MIN);
    if (fd >= 0 && fstat(fd, &st) != 0) {
        close(fd);
        fd = -1;
    }
    say_to.opened = true;
    say_to.fd = fd;
    say_to.dev = fd >= 0 ? st.st_dev : 0;
    say_to.ino = fd >= 0 ? st.st_ino : 0;
}

/* emm's stderr when it still is what it was, else -1. */
static int say_fd(void)
{
    struct stat st;
    if (!say_to.opened)
        say_open(); /* a line before the agent starts (a bad setting) */
    if (say_to.fd < 0 || fstat(say_to.fd, &st) != 0 || st.st_dev != say_to.dev ||
        st.st_ino != say_to.ino)
        return -1;
    return say_to.fd;
}

/* A stream on emm's stderr for the summary (fclose it), or NULL. */
static FILE *say_stream(void)
{
    int fd = say_fd();
    int dup = fd >= 0 ? fcntl(fd, F_DUPFD_CLOEXEC, SAY_FD_MIN) : -1;
    FILE *f = dup >= 0 ? fdopen(dup, "w") : NULL;
    if (!f && dup >= 0)
        close(dup);
    return f;
}

void emm_agent_say(const char *fmt, ...)
{
    int fd = say_fd();
    if (fd < 0)
        return;
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(line + 5, sizeof line - 6, fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    memcpy(line, "emm: ", 5);
    size_t len = 5 + ((size_t)n < sizeof line - 7 ? (size_t)n : sizeof line - 7);
    line[len++] = '\n';
    for (size_t off = 0; off < len;) {
        ssize_t w = write(fd, line + off, len - off);
        if (w <= 0 && errno != EINTR)
            return;
        if (w > 0)
            off += (size_t)w;
    }
}

static void say_line(void *ctx, const char *line)
{
    (void)ctx;
    emm_agent_say("%s", line);
}

static const char *kind_name(emm_array_kind k)
{
    return k == EMM_ARRAY_VERTICES ? "vertices" : "triangles";
}

static size_t filter_slot(uintptr_t base)
{
    return (size_t)(((uint64_t)base >> 4) * 0x9E3779B97F4A7C15ull >> (64 - FILTER_BITS));
}

static void filter_add(emm_agent *a, uintptr_t base, int delta)
{
    __atomic_add_fetch(&a->filter[filter_slot(base)], (uint16_t)delta, __ATOMIC_RELAXED);
}

int emm_agent_maybe_tagged(const emm_agent *a, const void *p)
{
    return a && __atomic_load_n(&a->filter[filter_slot((uintptr_t)p)], __ATOMIC_RELAXED) != 0;
}

int emm_agent_active(const emm_agent *a)
{
    return a && __atomic_load_n(&a->active, __ATOMIC_ACQUIRE);
}

size_t emm_agent_min_block(const emm_agent *a)
{
    return a->min_block;
}

/* ---- start-up --------------------------------------------------------------- */

static bool is_helper(const char *program)
{
    static const char *const helpers[] = {
#define HELPER_NAME(n) n,
        EMM_AGENT_HELPERS(HELPER_NAME)
#undef HELPER_NAME
    };
    for (size_t i = 0; program && i < sizeof helpers / sizeof *helpers; i++)
        if (strncmp(program, helpers[i], strlen(helpers[i])) == 0)
            return true;
    return false;
}

/* The socket of EMM_AGENT_SESSION_VAR when it is this process's (above 2),
 * else 0. */
static int session_sock(void)
{
    const char *v = getenv(EMM_AGENT_SESSION_VAR);
    if (!v)
        return 0;
    char *end;
    long fd = strtol(v, &end, 10), pid = *end == ':' ? strtol(end + 1, NULL, 10) : 0;
    struct stat st;
    return pid == (long)getpid() && fd > 2 && fd < 65536 && fstat((int)fd, &st) == 0 &&
                   S_ISSOCK(st.st_mode)
               ? (int)fd
               : 0;
}

int emm_agent_enter(const char *program)
{
    /* The session emm run started waits for this process's agent, and
     * for no process it executes. */
    int sock = session_sock();
    if (sock)
        fcntl(sock, F_SETFD, FD_CLOEXEC);
    else
        unsetenv(EMM_AGENT_SESSION_VAR);
    const char *ready = getenv(EMM_AGENT_READY_VAR);
    if (ready) {
        /* Only the process emm run started answers, and only into a pipe: a
         * static program passes the variable on to what it runs, where the
         * number may be another file's. */
        char *end;
        long fd = strtol(ready, &end, 10), pid = *end == ':' ? strtol(end + 1, NULL, 10) : 0;
        struct stat st;
        if (pid == (long)getpid() && fd > 2 && fd < 65536 && fstat((int)fd, &st) == 0 &&
            S_ISFIFO(st.st_mode)) {
            ssize_t w;
            while ((w = write((int)fd, "1", 1)) < 0 && errno == EINTR) {
            }
            close((int)fd);
        }
        unsetenv(EMM_AGENT_READY_VAR);
    }
    if (is_helper(program))
        return 0;
    if (!getenv(EMM_AGENT_ROOT_VAR)) {
        char pid[24];
        snprintf(pid, sizeof pid, "%ld", (long)getpid());
        setenv(EMM_AGENT_ROOT_VAR, pid, 1);
    }
    return 1;
}

static void agent_free(emm_agent *a)
{
    if (!a)
        return;
    for (struct retired *r = a->retired, *next; r; r = next) {
        next = r->next;
        free(r->lo);
        free(r->len);
        free(r);
    }
    free((void *)a->ranges.lo);
    free((void *)a->ranges.len);
    emm_session_free(a->session);
    emm_sites_free(a->sites);
    agent_rules_free(a->rules);
    emm_config_free(&a->cfg);
    free(a->tags);
    free(a->program);
    free(a);
}

emm_status emm_agent_new(const emm_agent_config *c, emm_agent **out, emm_error *err)
{
    *out = NULL;
    say_open();
    /* emm run's session for this process: the session's handle takes it
     * over; every other way it is closed here, and the session ends. */
    int sock = session_sock();
    unsetenv(EMM_AGENT_SESSION_VAR);
    emm_agent *a = calloc(1, sizeof *a);
    if (!a || !(a->program = strdup(c->program ? c->program : "program")) ||
        emm_config_copy(&a->cfg, c->config) != EMM_OK) {
        if (sock)
            close(sock);
        agent_free(a);
        return emm_fail(err, EMM_ERR_NOMEM, "libemmshim.so: out of memory");
    }
    pthread_mutex_init(&a->lock, NULL);
    clock_gettime(CLOCK_REALTIME_COARSE, &a->started);
    a->capture = c->capture;
    const char *root = getenv(EMM_AGENT_ROOT_VAR);
    a->child = root && strtol(root, NULL, 10) != (long)getpid();
    if (c->hooks)
        a->hooks = *c->hooks;
    emm_status st = EMM_OK;
    if (a->cfg.tags.n || a->cfg.list_sites)
        st = agent_rules_new(&a->cfg.tags, a->cfg.list_sites != 0, &a->rules, err);
    if (st != EMM_OK) {
        if (sock)
            close(sock);
        agent_free(a);
        return st;
    }
    if (a->cfg.list_sites) {
        if (sock)
            close(sock);
        /* List mode: no session, no capture; every large block is noted. */
        if (!(a->sites = emm_sites_new(LIST_MIN, LIST_LOG_MIN))) {
            agent_free(a);
            return emm_fail(err, EMM_ERR_NOMEM, "EMM_LIST_SITES: out of memory");
        }
        a->min_block = LIST_LOG_MIN;
    } else {
        /* The kinds the rules name: the window waits for them (bounded). */
        unsigned expect = 0;
        for (size_t i = 0; i < a->cfg.tags.n; i++)
            expect |= 1u << a->cfg.tags.rule[i].kind;
        emm_session_config sc = {&a->cfg, a->capture, a->program, 0, c->threads, c->server,
                                 NULL, 0, expect, c->server ? sock : 0};
        if (sock && !c->server)
            close(sock);
        st = emm_session_new(&sc, &a->session, err);
        if (st != EMM_OK && sc.server) {
            if (a->cfg.log >= 2 && !a->child)
                emm_agent_say("the session runs in the program: %s", err->message);
            sc.server = NULL;
            st = emm_session_new(&sc, &a->session, err);
        }
        if (st != EMM_OK) {
            a->session = NULL;
            agent_free(a);
            return st;
        }
        if (sc.server && a->cfg.log >= 2 && !a->child)
            emm_agent_say("the session runs natively in its own process, %s%s", sc.server,
                          sc.server_sock ? " (started by emm run)" : "");
        a->min_block = a->rules ? agent_rules_min(a->rules) : SIZE_MAX;
    }
    a->state = EMM_SESSION_PROFILING;
    /* A process the program started says one line under --verbose: the
     * settings are the program's, already shown; its end says more only
     * when it tagged an array. */
    if (a->cfg.log >= 2 && a->child) {
        emm_agent_say("libemmshim.so in %s (pid %ld, started by the program), capture %s: "
                      "silent unless it tags an array",
                      a->program, (long)getpid(), emm_capture_name(a->capture));
    } else if (a->cfg.log >= 2) {
        emm_agent_say("libemmshim.so in %s (pid %ld), capture %s", a->program, (long)getpid(),
                      emm_capture_name(a->capture));
        FILE *f = say_stream();
        if (f) {
            emm_config_dump(&a->cfg, f);
            fclose(f);
        }
    }
    __atomic_store_n(&a->active, 1, __ATOMIC_RELEASE);
    *out = a;
    return EMM_OK;
}

void emm_agent_free(emm_agent *a)
{
    if (!a)
        return;
    emm_agent_finish(a);
    pthread_mutex_destroy(&a->lock);
    agent_free(a);
}

/* ---- the session -------------------------------------------------------------- */

static bool live_locked(const emm_agent *a)
{
    return a->session && a->active && !a->failed;
}

size_t emm_agent_ranges_locked(emm_agent *a, uint64_t *lo, uint64_t *hi, size_t cap)
{
    /* List mode: the listed blocks, for their records' shape. */
    if (a->sites)
        return a->active ? emm_sites_ranges(a->sites, lo, hi, cap) : 0;
    return live_locked(a) ? emm_session_ranges(a->session, lo, hi, cap) : 0;
}

const emm_agent_filter *emm_agent_filter_of(const emm_agent *a)
{
    return &a->ranges;
}

/* Grows the snapshot's arrays to hold n ranges: new ones published, the
 * old ones kept for a reader that may still hold them. */
static bool grow_ranges(emm_agent *a, size_t n)
{
    size_t cap = a->ranges_cap ? a->ranges_cap : 16;
    while (cap < n)
        cap *= 2;
    uint64_t *lo = malloc(cap * sizeof *lo), *len = malloc(cap * sizeof *len);
    struct retired *r = malloc(sizeof *r);
    if (!lo || !len || !r) {
        free(lo);
        free(len);
        free(r);
        return false;
    }
    *r = (struct retired){a->retired, (uint64_t *)a->ranges.lo, (uint64_t *)a->ranges.len};
    a->retired = r;
    __atomic_store_n(&a->ranges.lo, lo, __ATOMIC_RELEASE);
    __atomic_store_n(&a->ranges.len, len, __ATOMIC_RELEASE);
    a->ranges_cap = cap;
    return true;
}

/* The ranges changed: the snapshot first, then the backend's hook. */
static void ranges_changed_locked(emm_agent *a)
{
    __atomic_store_n(&a->ranges.n, 0, __ATOMIC_RELEASE);
    size_t n = emm_agent_ranges_locked(a, NULL, NULL, 0);
    uint64_t *lohi = n ? malloc(2 * n * sizeof *lohi) : NULL;
    if (n && lohi && (n <= a->ranges_cap || grow_ranges(a, n))) {
        uint64_t *lo = (uint64_t *)a->ranges.lo, *len = (uint64_t *)a->ranges.len;
        size_t want = n;
        n = emm_agent_ranges_locked(a, lohi, lohi + want, want);
        n = n < want ? n : want;
        for (size_t i = 0; i < n; i++) {
            __atomic_store_n(&lo[i], lohi[i], __ATOMIC_RELAXED);
            __atomic_store_n(&len[i], lohi[want + i] - lohi[i], __ATOMIC_RELAXED);
        }
        __atomic_store_n(&a->ranges.n, n, __ATOMIC_RELEASE);
    }
    free(lohi);
    if (a->hooks.ranges)
        a->hooks.ranges(a);
}

static void decide_locked(emm_agent *a)
{
    if (a->hooks.before_decide)
        a->hooks.before_decide();
    emm_error err;
    if (emm_session_decide(a->session, &err) != EMM_OK) {
        /* The session reports why at finish; stop feeding it. */
        a->failed = true;
        if (a->cfg.log >= 2)
            emm_agent_say("%s", err.message);
    }
    /* A session whose window started again profiles on. */
    a->state = emm_session_access(a->session, NULL, 0) == EMM_SESSION_PROFILING
                   ? EMM_SESSION_PROFILING
                   : EMM_SESSION_SIMULATING;
    ranges_changed_locked(a);
}

/* The session's answer to a call: decide when it asks. */
static void answer_locked(emm_agent *a, emm_session_state st)
{
    if (st == EMM_SESSION_DECIDE && a->state != EMM_SESSION_SIMULATING)
        decide_locked(a);
    else
        a->state = st;
}

void emm_agent_feed_locked(emm_agent *a, const emm_raw_access *r, size_t n)
{
    if (a->sites && (a->active || a->last_drain))
        emm_sites_access(a->sites, r, n);
    else if (live_locked(a))
        answer_locked(a, emm_session_access(a->session, r, n));
}

void emm_agent_feed(emm_agent *a, const emm_raw_access *r, size_t n)
{
    pthread_mutex_lock(&a->lock);
    if (n)
        emm_agent_feed_locked(a, r, n);
    if (a->hooks.drain)
        a->hooks.drain(a);
    pthread_mutex_unlock(&a->lock);
}

void emm_agent_iteration(emm_agent *a)
{
    pthread_mutex_lock(&a->lock);
    if (live_locked(a))
        answer_locked(a, emm_session_iteration(a->session));
    pthread_mutex_unlock(&a->lock);
}

/* ---- the tag table ------------------------------------------------------------ */

static struct tag *find_locked(emm_agent *a, uintptr_t base)
{
    for (size_t i = 0; base && i < a->ntags; i++)
        if (a->tags[i].base == base)
            return &a->tags[i];
    return NULL;
}

static emm_agent_block block_of(const struct tag *t)
{
    return (emm_agent_block){t->base, t->bytes, t->map, t->map_len};
}

static void remove_locked(emm_agent *a, struct tag *t)
{
    filter_add(a, t->base, -1);
    *t = a->tags[--a->ntags];
}

static void tag_locked(emm_agent *a, const struct tag *nt)
{
    struct tag *t = find_locked(a, nt->base);
    if (!t) {
        if (a->ntags == a->ctags) {
            size_t cap = a->ctags ? 2 * a->ctags : 16;
            struct tag *grown = realloc(a->tags, cap * sizeof *grown);
            if (!grown) {
                if (a->cfg.log >= 1)
                    emm_agent_say("out of memory for the tag table; %s at %p ignored",
                              kind_name(nt->kind), (void *)nt->base);
                if (nt->map)
                    munmap(nt->map, nt->map_len);
                return;
            }
            a->tags = grown;
            a->ctags = cap;
        }
        t = &a->tags[a->ntags++];
        *t = *nt;
        filter_add(a, t->base, 1);
    } else {
        void *map = t->map;
        size_t len = t->map_len;
        *t = *nt;
        t->map = map; /* the block keeps its pages */
        t->map_len = len;
    }
    int idx = -1;
    if (live_locked(a)) {
        emm_array_desc d = {t->kind, EMM_TAG_RECORDS, -1, (const void *)t->base,
                            t->bytes / t->stride, t->stride, t->offset, t->type, 0, NULL,
                            {EMM_TAG_NO_LINK, EMM_TAG_NO_LINK, EMM_TAG_NO_LINK, EMM_TAG_NO_LINK}};
        char origin[640];
        if (t->rule >= 0)
            emm_tag_rule_describe(&a->cfg.tags.rule[t->rule], (size_t)t->rule,
                                  (const void *)t->base, t->bytes, &d, origin, sizeof origin);
        idx = emm_session_tag(a->session, &d);
    }
    if (a->hooks.on_tag) {
        emm_agent_block b = block_of(t);
        a->hooks.on_tag(&b);
    }
    ranges_changed_locked(a);
    a->tagged_total++;
    if (a->cfg.log >= 2)
        emm_agent_say("tagged %s at %p: %zu records of %zu bytes (%s)%s", kind_name(t->kind),
                  (void *)t->base, t->bytes / t->stride, t->stride,
                  t->rule >= 0 ? "EMM_TAG rule" : "emm_tag call", idx < 0 ? ", not watched" : "");
}

/* Untags the block at base, if it is one, into *out. */
static bool take_locked(emm_agent *a, uintptr_t base, struct tag *out)
{
    struct tag *t = find_locked(a, base);
    if (!t)
        return false;
    if (a->hooks.on_untag) {
        emm_agent_block b = block_of(t);
        a->hooks.on_untag(&b);
    }
    if (live_locked(a)) {
        emm_session_state st = emm_session_untag(a->session, (const void *)base);
        if (st == EMM_SESSION_DECIDE && a->state == EMM_SESSION_PROFILING && a->cfg.log >= 2)
            emm_agent_say("the last %s array is freed: the profile window closes early",
                      kind_name(t->kind));
        answer_locked(a, st);
    }
    *out = *t;
    remove_locked(a, t);
    ranges_changed_locked(a);
    if (a->cfg.log >= 2)
        emm_agent_say("untagged %s at %p", kind_name(out->kind), (void *)base);
    return true;
}

static void release(const struct tag *t, void *p)
{
    if (t->map)
        munmap(t->map, t->map_len);
    else
        free(p);
}

void emm_agent_tag_call(emm_agent *a, emm_array_kind kind, const void *p, size_t count,
                        size_t stride, size_t offset, emm_scalar type)
{
    if (!emm_agent_active(a) || !p || !count || !stride || count > SIZE_MAX / stride)
        return;
    struct tag t = {(uintptr_t)p, count * stride, kind, stride, offset, type, -1, NULL, 0};
    pthread_mutex_lock(&a->lock);
    tag_locked(a, &t);
    pthread_mutex_unlock(&a->lock);
}

void emm_agent_untag(emm_agent *a, const void *p)
{
    struct tag t;
    pthread_mutex_lock(&a->lock);
    take_locked(a, (uintptr_t)p, &t);
    pthread_mutex_unlock(&a->lock);
}

/* The records of a mesh are two arrays; their stride is the distance
 * between the first two records. (The calls below reach the shim's
 * emm_mesh_vertex, which records nothing while its caller is inside the
 * agent.) */
void emm_agent_tag_mesh(emm_agent *a, const emm_mesh *m)
{
    size_t nv = emm_mesh_vertex_count(m), nt = emm_mesh_triangle_count(m);
    const char *v0 = nv ? (const char *)emm_mesh_vertex(m, 0) : NULL;
    const char *t0 = nt ? (const char *)emm_mesh_triangle(m, 0) : NULL;
    size_t vs = nv > 1 ? (size_t)((const char *)emm_mesh_vertex(m, 1) - v0) : sizeof(emm_vertex);
    size_t ts = nt > 1 ? (size_t)((const char *)emm_mesh_triangle(m, 1) - t0)
                       : sizeof(emm_triangle);
    if (v0)
        emm_agent_tag_call(a, EMM_ARRAY_VERTICES, v0, nv, vs, offsetof(emm_vertex, xyz), EMM_F64);
    if (t0)
        emm_agent_tag_call(a, EMM_ARRAY_TRIANGLES, t0, nt, ts, offsetof(emm_triangle, v),
                           EMM_I32);
}

void emm_agent_untag_mesh(emm_agent *a, const emm_mesh *m)
{
    if (emm_mesh_vertex_count(m))
        emm_agent_untag(a, emm_mesh_vertex(m, 0));
    if (emm_mesh_triangle_count(m))
        emm_agent_untag(a, emm_mesh_triangle(m, 0));
}

/* ---- allocations --------------------------------------------------------------- */

/* Whether the C library asked for the block itself — a FILE and its
 * buffer, getline's line, strdup's copy: never a program's array, and a
 * FILE's 4 KiB buffer is a whole number of small records, which a rule
 * would select (under fault capture the C library's reads into it then
 * failed with EFAULT: the kernel does not fault on a protected page).
 * dladdr takes the loader's lock: the answers for recent callers are kept. */
static bool libc_block(emm_agent *a, const void *caller)
{
    uint64_t ra = (uint64_t)(uintptr_t)caller;
    uint64_t *memo = &a->libc_memo[(ra * 0x9E3779B97F4A7C15ull) >> 58];
    uint64_t seen = __atomic_load_n(memo, __ATOMIC_RELAXED);
    if (caller && seen >> 1 == ra)
        return seen & 1;
    Dl_info info;
    bool libc = false;
    if (caller && dladdr(caller, &info) && info.dli_fname) {
        const char *base = strrchr(info.dli_fname, '/');
        base = base ? base + 1 : info.dli_fname;
        libc = strncmp(base, "libc.so", 7) == 0;
    }
    __atomic_store_n(memo, ra << 1 | libc, __ATOMIC_RELAXED);
    return libc;
}

int emm_agent_select(emm_agent *a, size_t size, const void *caller)
{
    if (!emm_agent_active(a) || size < a->min_block || a->sites || !a->rules ||
        libc_block(a, caller))
        return -1;
    const char *site;
    int rule = agent_rules_match(a->rules, size, &site);
    if (rule >= 0 && a->cfg.log >= 2)
        emm_agent_say("EMM_TAG rule %d selected a block of %zu bytes%s%s", rule + 1, size,
                  site ? " allocated under " : "", site ? site : "");
    return rule;
}

/* The block this thread's realloc moves (emm_agent_release), or -1. */
static int64_t take_move(emm_agent *a)
{
    for (int i = 0; i < MOVES; i++)
        if (a->moves[i].used && pthread_equal(a->moves[i].thread, pthread_self())) {
            a->moves[i].used = false;
            return a->moves[i].from;
        }
    return -1;
}

void emm_agent_allocated(emm_agent *a, int rule, void *p, size_t size, void *map,
                         size_t map_len, const void *caller)
{
    if (p && rule >= 0 && (size_t)rule < a->cfg.tags.n) {
        const emm_tag_rule *r = &a->cfg.tags.rule[rule];
        struct tag t = {(uintptr_t)p, size - size % r->stride, r->kind, r->stride,
                        r->offset, r->type, rule, map, map_len};
        pthread_mutex_lock(&a->lock);
        tag_locked(a, &t);
        pthread_mutex_unlock(&a->lock);
    } else if (map) {
        munmap(map, map_len);
    }
    if (p && a->sites && size >= a->min_block && !libc_block(a, caller)) {
        const char *name[AGENT_MAX_FRAMES];
        uintptr_t ip[AGENT_MAX_FRAMES];
        int n = agent_rules_stack(a->rules, name, ip);
        uint64_t path = 14695981039346656037ull;
        for (int k = 0; k < n; k++)
            path = (path ^ ip[k]) * 1099511628211ull;
        pthread_mutex_lock(&a->lock);
        int64_t from = take_move(a);
        if (a->active) {
            emm_sites_add(a->sites, path, name, ip, (size_t)n, p, size, from);
            a->listed += size >= LIST_MIN;
            if (size >= LIST_MIN && a->hooks.ranges)
                ranges_changed_locked(a); /* a capture that sees accesses watches it */
        }
        pthread_mutex_unlock(&a->lock);
    } else if (a->sites) {
        pthread_mutex_lock(&a->lock);
        take_move(a);
        pthread_mutex_unlock(&a->lock);
    }
}

void emm_agent_release(emm_agent *a, const void *p, size_t moving_to)
{
    if (!a || !a->sites)
        return;
    pthread_mutex_lock(&a->lock);
    if (a->active) {
        /* The accesses so far are the block's; then the capture stops
         * watching it before it is read here (not the program's reads). */
        bool listed = emm_sites_listed(a->sites, p);
        if (listed && a->hooks.drain)
            a->hooks.drain(a);
        if (listed && a->hooks.on_untag) {
            emm_agent_block b = {(uintptr_t)p, 0, NULL, 0};
            a->hooks.on_untag(&b);
        }
        int64_t e = emm_sites_release(a->sites, p);
        if (listed && a->hooks.ranges)
            ranges_changed_locked(a);
        /* A realloc to a size the shim looks at allocates next on this
         * thread (emm_agent_allocated): the block it moves is noted. */
        if (moving_to >= a->min_block) {
            take_move(a);
            for (int i = 0; i < MOVES; i++)
                if (!a->moves[i].used) {
                    a->moves[i] = (struct move){pthread_self(), e, true};
                    break;
                }
        }
    }
    pthread_mutex_unlock(&a->lock);
}

int emm_agent_on_free(emm_agent *a, void *p)
{
    struct tag t;
    pthread_mutex_lock(&a->lock);
    bool found = take_locked(a, (uintptr_t)p, &t);
    pthread_mutex_unlock(&a->lock);
    if (found)
        release(&t, p);
    return found;
}

void *emm_agent_on_realloc(emm_agent *a, void *p, size_t size, int *handled)
{
    if (size == 0) {
        *handled = emm_agent_on_free(a, p);
        return NULL;
    }
    pthread_mutex_lock(&a->lock);
    struct tag *t = find_locked(a, (uintptr_t)p);
    *handled = t != NULL;
    if (!t) { /* untagged meanwhile by another thread */
        pthread_mutex_unlock(&a->lock);
        return NULL;
    }
    if (a->hooks.on_untag) {
        emm_agent_block b = block_of(t);
        a->hooks.on_untag(&b);
    }
    void *q, *map = NULL;
    size_t map_len = 0;
    if (t->map) {
        size_t old = t->map_len - (size_t)((uintptr_t)p - (uintptr_t)t->map);
        map = a->hooks.map ? a->hooks.map(size, 16, &map_len) : NULL;
        q = map ? map : malloc(size);
        if (q) {
            memcpy(q, p, old < size ? old : size);
            munmap(t->map, t->map_len);
        }
    } else {
        q = realloc(p, size);
    }
    size_t bytes = size - size % t->stride;
    if (t->rule < 0 && t->bytes < bytes)
        bytes = t->bytes;
    if (q) {
        if (live_locked(a))
            answer_locked(a, emm_session_move(a->session, p, q, bytes / t->stride));
        filter_add(a, t->base, -1);
        filter_add(a, (uintptr_t)q, 1);
        t->base = (uintptr_t)q;
        t->bytes = bytes;
        t->map = map;
        t->map_len = map_len;
    }
    emm_array_kind kind = t->kind;
    size_t stride = t->stride;
    if (q && bytes == 0) {
        remove_locked(a, t); /* shrunk below one record: no longer an array */
    } else if (a->hooks.on_tag) {
        /* the old block, when q is NULL, stays valid and stays the array */
        emm_agent_block b = block_of(t);
        a->hooks.on_tag(&b);
    }
    ranges_changed_locked(a);
    pthread_mutex_unlock(&a->lock);
    if (q && bytes && a->cfg.log >= 2)
        emm_agent_say("moved %s from %p to %p: %zu records of %zu bytes", kind_name(kind), p, q,
                  bytes / stride, stride);
    if (!q)
        errno = ENOMEM;
    return q;
}

size_t emm_agent_usable_size(emm_agent *a, const void *p)
{
    size_t size = 0;
    pthread_mutex_lock(&a->lock);
    struct tag *t = find_locked(a, (uintptr_t)p);
    if (t && t->map)
        size = t->map_len - (size_t)((uintptr_t)p - (uintptr_t)t->map);
    pthread_mutex_unlock(&a->lock);
    return size;
}

/* ---- the end, fork ------------------------------------------------------------- */

static void agent_finish(emm_agent *a, const char *ended);

static void report_nothing(const emm_config *c, emm_capture capture, const char *program,
                           const char *why, const struct timespec *since)
{
    emm_error err;
    if (emm_session_report_nothing(c, program, capture, why, since, &err) != EMM_OK &&
        c->log >= 1)
        emm_agent_say("%s", err.message);
}

void emm_agent_step_aside(const emm_config *c, emm_capture capture, const char *program,
                          const char *why)
{
    report_nothing(c, capture, program, why, NULL);
    if (c->strict) {
        emm_agent_say("%s (EMM_STRICT=1: not running the program)", why);
        _exit(EMM_AGENT_STRICT_EXIT);
    }
    emm_agent_say("%s", why);
}

void emm_agent_finish(emm_agent *a)
{
    agent_finish(a, NULL);
}

void emm_agent_finish_signal(emm_agent *a, int sig)
{
    char ended[64];
    const char *abbrev = sigabbrev_np(sig);
    snprintf(ended, sizeof ended, "signal %d%s%s%s", sig, abbrev ? " (SIG" : "",
             abbrev ? abbrev : "", abbrev ? ")" : "");
    agent_finish(a, ended);
}

static void agent_finish(emm_agent *a, const char *ended)
{
    if (!a || __atomic_exchange_n(&a->finishing, 1, __ATOMIC_ACQ_REL))
        return;
    pthread_mutex_lock(&a->lock);
    if (!a->active) {
        pthread_mutex_unlock(&a->lock);
        return;
    }
    __atomic_store_n(&a->active, 0, __ATOMIC_RELEASE);
    /* A tool the program ran (/bin/echo, a compiler) that tagged nothing is
     * none of the answer: the program's own lines say what was found. */
    bool quiet = a->child && !a->tagged_total && !a->listed;
    if (a->sites) { /* list mode: the candidate arrays, nothing simulated */
        a->last_drain = true;
        if (a->hooks.drain)
            a->hooks.drain(a);
        a->last_drain = false;
        if (a->hooks.before_decide) /* the blocks are read here: not the program's reads */
            a->hooks.before_decide();
        FILE *f = quiet ? NULL : say_stream();
        if (f) {
            emm_sites_print(a->sites, a->program, f);
            fclose(f);
        }
        report_nothing(&a->cfg, a->capture, a->program,
                       "list mode (--list-sites, EMM_LIST_SITES=1): the program's candidate "
                       "arrays were listed, nothing is simulated",
                       &a->started);
        pthread_mutex_unlock(&a->lock);
        return;
    }
    if (a->hooks.before_decide)
        a->hooks.before_decide();
    if (a->cfg.log >= 1 && a->rules && !quiet)
        agent_rules_report(a->rules, say_line, NULL);
    if (a->cfg.log >= 2 && !quiet) {
        for (size_t i = 0; i < a->ntags; i++)
            emm_agent_say("at exit: %s at %p, %zu records of %zu bytes", kind_name(a->tags[i].kind),
                      (void *)a->tags[i].base, a->tags[i].bytes / a->tags[i].stride,
                      a->tags[i].stride);
        emm_agent_say("at exit: %zu arrays tagged, %llu tag events", a->ntags,
                  (unsigned long long)a->tagged_total);
    }
    ranges_changed_locked(a);
    /* The summary already says why a session had nothing to simulate, and
     * names each output that could not be written. */
    if (quiet) {
        /* Its "nothing simulated" would stand in the way of the program's
         * own report at the same path. */
        emm_session_discard(a->session);
        pthread_mutex_unlock(&a->lock);
        return;
    }
    FILE *f = a->cfg.log >= 1 ? say_stream() : NULL;
    emm_session_finish_ended(a->session, f, ended, NULL);
    if (f)
        fclose(f);
    pthread_mutex_unlock(&a->lock);
}

void emm_agent_lock(emm_agent *a)
{
    pthread_mutex_lock(&a->lock);
}

void emm_agent_unlock(emm_agent *a)
{
    pthread_mutex_unlock(&a->lock);
}

void emm_agent_forked(emm_agent *a)
{
    pthread_mutex_init(&a->lock, NULL);
    __atomic_store_n(&a->active, 0, __ATOMIC_RELEASE);
    __atomic_store_n(&a->finishing, 1, __ATOMIC_RELEASE);
    if (a->session)
        emm_session_forked(a->session);
}

/* ---- what the program imports ------------------------------------------------- */

struct import_query {
    const char *name;
    bool found;
};

static uintptr_t dyn_addr(const struct dl_phdr_info *info, ElfW(Addr) v)
{
    /* ld.so relocates the main program's dynamic entries in place on most
     * targets, but not on all. */
    return v < info->dlpi_addr ? info->dlpi_addr + v : v;
}

static int first_object(struct dl_phdr_info *info, size_t size, void *arg)
{
    (void)size;
    struct import_query *q = arg;
    const ElfW(Dyn) *dyn = NULL;
    for (int i = 0; i < info->dlpi_phnum; i++)
        if (info->dlpi_phdr[i].p_type == PT_DYNAMIC)
            dyn = (const ElfW(Dyn) *)(info->dlpi_addr + info->dlpi_phdr[i].p_vaddr);
    if (!dyn)
        return 1;
    const ElfW(Sym) *symtab = NULL;
    const char *strtab = NULL;
    for (; dyn->d_tag != DT_NULL; dyn++) {
        if (dyn->d_tag == DT_SYMTAB)
            symtab = (const ElfW(Sym) *)dyn_addr(info, dyn->d_un.d_ptr);
        else if (dyn->d_tag == DT_STRTAB)
            strtab = (const char *)dyn_addr(info, dyn->d_un.d_ptr);
    }
    /* The symbol table ends where the string table starts, as the linkers
     * lay them out. */
    if (!symtab || !strtab || (const void *)strtab <= (const void *)symtab)
        return 1;
    size_t n = (size_t)((const char *)strtab - (const char *)symtab) / sizeof(ElfW(Sym));
    for (size_t i = 1; i < n; i++)
        if (symtab[i].st_shndx == SHN_UNDEF && strcmp(strtab + symtab[i].st_name, q->name) == 0) {
            q->found = true;
            break;
        }
    return 1; /* only the main program */
}

int emm_program_imports(const char *symbol)
{
    struct import_query q = {symbol, false};
    dl_iterate_phdr(first_object, &q);
    return q.found;
}
