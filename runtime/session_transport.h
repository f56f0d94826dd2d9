/* Internal to the runtime: the one seam between a session's handle and
 * the engine that does its work (docs/architecture.md "The session").
 *
 * An emm_session is a pointer to a transport, chosen once by
 * emm_session_new: the engine in this process (session.c), or a proxy that
 * sends each call to the engine in emm-session, a native process of its own
 * (session_proxy.c; the valgrind capture, whose program runs under
 * Valgrind). Every public entry point (session_api.c) calls through it; the
 * engine never asks which transport reached it. */
#ifndef EMM_RUNTIME_SESSION_TRANSPORT_H
#define EMM_RUNTIME_SESSION_TRANSPORT_H

#include <stdbool.h>
#include <sys/types.h>

#include "emm/session.h"

/* The calls of include/emm/session.h, each with its contract there. */
struct session_transport {
    int (*tag)(emm_session *s, const emm_array_desc *d);
    emm_session_state (*move)(emm_session *s, uint64_t old, uint64_t base, uint64_t count);
    emm_session_state (*untag)(emm_session *s, uint64_t base);
    size_t (*ranges)(const emm_session *s, uint64_t *lo, uint64_t *hi, size_t cap);
    emm_session_state (*access)(emm_session *s, const emm_raw_access *a, size_t n);
    emm_session_state (*iteration)(emm_session *s);
    emm_status (*decide_read)(emm_session *s, emm_error *err);
    emm_status (*decide_rest)(emm_session *s, emm_error *err);
    emm_status (*finish)(emm_session *s, FILE *summary, const char *ended, emm_error *err);
    void (*discard)(emm_session *s);
    void (*forked)(emm_session *s);
    void (*free)(emm_session *s);
};

/* The handle: what each transport's own state begins with. */
struct emm_session {
    const struct session_transport *transport;
};

/* The engine in this process (session.c). */
emm_status session_engine_new(const emm_session_config *sc, emm_session **out, emm_error *err);
/* A proxy for the engine in the process sc->server starts (session_proxy.c). */
emm_status session_proxy_new(const emm_session_config *sc, emm_session **out, emm_error *err);
/* Starts emm-session at `path` (session_proxy.c): without LD_PRELOAD (the
 * shim has no business in it), stdin and stdout on /dev/null, stderr the
 * caller's, fd 3 its end of a new socket, whose other end goes to *sock;
 * with `done`, fd 4 the write end of a new pipe, which it closes once its
 * outputs are written and whose read end goes to *done. `detach`: started
 * through a second fork, so that a program that waits for any child, or
 * counts them, never meets it; else the caller's child, *pid (pid may be
 * NULL). Fit for a forked child of a threaded program: nothing but
 * async-signal-safe calls after the fork. */
emm_status session_server_start(const char *path, bool detach, int *sock, int *done, pid_t *pid,
                                emm_error *err);

#endif
