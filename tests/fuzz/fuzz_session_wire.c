/* The session server's frames (runtime/session_wire.h): what emm-session
 * reads from the shim's socket. The harness starts a session as the shim
 * would (a valid start frame, the default settings, so no file is
 * written), then sends the input as the rest of the stream: calls, the
 * arrays' bytes the server asks for, anything. The server must end when the
 * stream ends, whatever came, without a crash, a hang or an allocation the
 * bytes did not pay for. */
#include "fuzz.h"
#include "server.h"
#include "session_wire.h"

#include <pthread.h>
#include <sys/socket.h>

struct feed {
    int fd;
    const unsigned char *start, *data;
    size_t nstart, ndata;
};

static void write_all(int fd, const unsigned char *p, size_t n)
{
    while (n > 0) {
        ssize_t w = send(fd, p, n, MSG_NOSIGNAL);
        if (w <= 0)
            return; /* the server stopped reading: it refused the stream */
        p += w;
        n -= (size_t)w;
    }
}

static void *writer(void *arg)
{
    struct feed *f = arg;
    write_all(f->fd, f->start, f->nstart);
    write_all(f->fd, f->data, f->ndata);
    shutdown(f->fd, SHUT_WR);
    return NULL;
}

/* The server's replies and requests, read and dropped. */
static void *drain(void *arg)
{
    int fd = *(int *)arg;
    char buf[65536];
    while (recv(fd, buf, sizeof buf, 0) > 0) {
    }
    return NULL;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
        abort();
    emm_config cfg;
    emm_config_init(&cfg);
    emm_session_config sc = {&cfg, EMM_CAPTURE_VALGRIND, "fuzz", 0, {1, NULL, NULL}, NULL, NULL,
                             0, 0, 0};
    unsigned char *payload, *start;
    size_t npayload;
    if (!wire_start_encode(&sc, 4242, &payload, &npayload))
        abort();
    struct wire_frame head = {.op = WIRE_NEW, .wait = 1, .len = npayload};
    size_t nstart = sizeof head + npayload;
    if (!(start = malloc(nstart)))
        abort();
    memcpy(start, &head, sizeof head);
    memcpy(start + sizeof head, payload, npayload);
    free(payload);
    struct feed f = {sv[0], start, data, nstart, size};
    pthread_t w, d;
    if (pthread_create(&w, NULL, writer, &f) != 0 || pthread_create(&d, NULL, drain, &sv[0]) != 0)
        abort();
    emm_error err;
    emm_status st = emm_server_serve(sv[1], -1, &err);
    fuzz_check_error(st, &err);
    close(sv[1]); /* the drain sees the end */
    pthread_join(w, NULL);
    pthread_join(d, NULL);
    close(sv[0]);
    free(start);
    return 0;
}
