/* The session's public entry points (include/emm/session.h): each calls
 * through the handle's transport (session_transport.h), chosen once here
 * when the session is made. */
#include "session_transport.h"

emm_status emm_session_new(const emm_session_config *sc, emm_session **out, emm_error *err)
{
    return sc->server ? session_proxy_new(sc, out, err) : session_engine_new(sc, out, err);
}

int emm_session_tag(emm_session *s, const emm_array_desc *d)
{
    return s->transport->tag(s, d);
}

emm_session_state emm_session_move(emm_session *s, const void *old, const void *base,
                                   size_t count)
{
    return s->transport->move(s, (uint64_t)(uintptr_t)old, (uint64_t)(uintptr_t)base, count);
}

emm_session_state emm_session_untag(emm_session *s, const void *base)
{
    return s->transport->untag(s, (uint64_t)(uintptr_t)base);
}

size_t emm_session_ranges(const emm_session *s, uint64_t *lo, uint64_t *hi, size_t cap)
{
    return s->transport->ranges(s, lo, hi, cap);
}

emm_session_state emm_session_access(emm_session *s, const emm_raw_access *a, size_t n)
{
    return s->transport->access(s, a, n);
}

emm_session_state emm_session_iteration(emm_session *s)
{
    return s->transport->iteration(s);
}

emm_status emm_session_decide_read(emm_session *s, emm_error *err)
{
    return s->transport->decide_read(s, err);
}

emm_status emm_session_decide_rest(emm_session *s, emm_error *err)
{
    return s->transport->decide_rest(s, err);
}

emm_status emm_session_decide(emm_session *s, emm_error *err)
{
    emm_status st = s->transport->decide_read(s, err);
    return st == EMM_OK ? s->transport->decide_rest(s, err) : st;
}

emm_status emm_session_finish(emm_session *s, FILE *summary, emm_error *err)
{
    return s->transport->finish(s, summary, NULL, err);
}

emm_status emm_session_finish_ended(emm_session *s, FILE *summary, const char *ended,
                                    emm_error *err)
{
    return s->transport->finish(s, summary, ended, err);
}

void emm_session_discard(emm_session *s)
{
    if (s)
        s->transport->discard(s);
}

void emm_session_forked(emm_session *s)
{
    if (s)
        s->transport->forked(s);
}

void emm_session_free(emm_session *s)
{
    if (s)
        s->transport->free(s);
}
