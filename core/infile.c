/* Whole input files with a size cap (infile.h). */
#include "infile.h"

#include "error.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

void emm_infile_size_text(size_t bytes, char *buf, size_t cap)
{
    if (bytes >= ((size_t)1 << 30) && bytes % ((size_t)1 << 30) == 0)
        snprintf(buf, cap, "%zu GiB", bytes >> 30);
    else if (bytes >= ((size_t)1 << 20) && bytes % ((size_t)1 << 20) == 0)
        snprintf(buf, cap, "%zu MiB", bytes >> 20);
    else if (bytes >= ((size_t)1 << 10) && bytes % ((size_t)1 << 10) == 0)
        snprintf(buf, cap, "%zu KiB", bytes >> 10);
    else
        snprintf(buf, cap, "%zu bytes", bytes);
}

static emm_status too_large(const char *path, const char *what, size_t limit, bool regular,
                            emm_error *err)
{
    char size[32];
    emm_infile_size_text(limit, size, sizeof size);
    return emm_fail(err, EMM_ERR_RANGE, "%s: too large for a %s (more than %s%s)", path, what,
                    size, regular ? "" : " from a pipe or device");
}

emm_status emm_infile_open(const char *path, const char *what, bool regular_only, int *out,
                           struct stat *st, emm_error *err)
{
    *out = -1;
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0)
        return emm_fail(err, EMM_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    const char *why = NULL, *kind = NULL;
    if (fstat(fd, st) != 0)
        why = strerror(errno);
    else if (S_ISDIR(st->st_mode))
        kind = "is a directory";
    else if (regular_only && !S_ISREG(st->st_mode))
        kind = S_ISFIFO(st->st_mode) ? "is a pipe or FIFO" : "is a device";
    else if (S_ISREG(st->st_mode) && fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK) != 0)
        why = strerror(errno);
    if (why || kind) {
        close(fd);
        return kind ? emm_fail(err, EMM_ERR_IO, "%s: %s, not a %s", path, kind, what)
                    : emm_fail(err, EMM_ERR_IO, "%s: %s", path, why);
    }
    *out = fd;
    return EMM_OK;
}

FILE *emm_infile_fopen(const char *path, const char *what, emm_error *err)
{
    struct stat st;
    int fd;
    if (emm_infile_open(path, what, true, &fd, &st, err) != EMM_OK)
        return NULL;
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        emm_fail(err, EMM_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
        close(fd);
    }
    return f;
}

/* Waits until `fd` (a pipe, FIFO or device) has something to read or its
 * writer has gone, at most EMM_INFILE_STREAM_WAIT_MS: false when it stayed
 * silent (a FIFO nobody opened for writing stays so on Linux). */
static bool stream_ready(int fd)
{
    struct pollfd p = {.fd = fd, .events = POLLIN};
    for (;;) {
        int r = poll(&p, 1, EMM_INFILE_STREAM_WAIT_MS);
        if (r < 0 && errno == EINTR)
            continue;
        return r != 0; /* an error shows in the read that follows */
    }
}

emm_status emm_infile_read(const char *path, const char *what, size_t max, char **data,
                           size_t *len, emm_error *err)
{
    *data = NULL;
    *len = 0;
    if (max > SIZE_MAX / 4)
        max = SIZE_MAX / 4; /* "no cap": the file's own size is the limit */
    struct stat st;
    int fd;
    emm_status opened = emm_infile_open(path, what, false, &fd, &st, err);
    if (opened != EMM_OK)
        return opened;
    bool regular = S_ISREG(st.st_mode);
    size_t limit = regular || max < EMM_INFILE_STREAM_MAX ? max : EMM_INFILE_STREAM_MAX;
    if (regular && (uint64_t)st.st_size > limit) {
        close(fd);
        return too_large(path, what, limit, true, err);
    }
    /* A regular file is read in one buffer of its size (plus one byte to
     * see it did not grow); anything else in doubling steps up to the cap. */
    size_t cap = regular ? (size_t)st.st_size + 1 : 64 * 1024;
    if (cap > limit + 1)
        cap = limit + 1;
    char *buf = malloc(cap + 1);
    size_t n = 0;
    emm_status s = buf ? EMM_OK : emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    while (s == EMM_OK) {
        if (n == cap) {
            if (n > limit) {
                s = too_large(path, what, limit, regular, err);
                break;
            }
            size_t grown = cap > (limit + 1) / 2 ? limit + 1 : 2 * cap;
            char *nb = realloc(buf, grown + 1);
            if (!nb) {
                s = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
                break;
            }
            buf = nb;
            cap = grown;
        }
        if (!regular && !stream_ready(fd)) {
            s = emm_fail(err, EMM_ERR_IO,
                         "%s: nothing to read for %d s (a pipe or FIFO with no writer, or a "
                         "silent one)", path, EMM_INFILE_STREAM_WAIT_MS / 1000);
            break;
        }
        ssize_t got = read(fd, buf + n, cap - n);
        if (got < 0 && (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK))
            continue;
        if (got < 0)
            s = emm_fail(err, EMM_ERR_IO, "%s: cannot read: %s", path, strerror(errno));
        else if (got == 0)
            break;
        else
            n += (size_t)got;
    }
    close(fd);
    if (s != EMM_OK) {
        free(buf);
        return s;
    }
    buf[n] = '\0';
    *data = buf;
    *len = n;
    return EMM_OK;
}
