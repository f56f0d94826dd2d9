/* Whole input files with a size cap (infile.h). */
#include "infile.h"

#include "error.h"

#include <errno.h>
#include <fcntl.h>
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

emm_status emm_infile_read(const char *path, const char *what, size_t max, char **data,
                           size_t *len, emm_error *err)
{
    *data = NULL;
    *len = 0;
    if (max > SIZE_MAX / 4)
        max = SIZE_MAX / 4; /* "no cap": the file's own size is the limit */
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return emm_fail(err, EMM_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return emm_fail(err, EMM_ERR_IO, "%s: %s", path, strerror(e));
    }
    if (S_ISDIR(st.st_mode)) {
        close(fd);
        return emm_fail(err, EMM_ERR_IO, "%s: is a directory, not a %s", path, what);
    }
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
        ssize_t got = read(fd, buf + n, cap - n);
        if (got < 0 && errno == EINTR)
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
