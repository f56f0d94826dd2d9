/* Output files written whole or not at all (see outfile.h). */
#include "outfile.h"

#include <assert.h>
#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "error.h"

#define SUFFIX ".tmp."
#define RANDOM_CHARS 6
#define ATTEMPTS 100

static uint64_t mix(uint64_t x)
{
    x += 0x9e3779b97f4a7c15u;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9u;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebu;
    return x ^ (x >> 31);
}

/* Not mkstemp: it creates the file 0600, and giving it the ordinary mode
 * afterwards means knowing the umask, which can only be read by setting it
 * (umask twice), a race with any other thread creating a file meanwhile.
 * Creating the file ourselves with O_CREAT | O_EXCL and mode 0666 lets the
 * kernel apply the umask (and a directory's default ACL) as fopen would.
 * The name mixes the time, the process and the address of o (distinct per
 * thread and per call); O_EXCL settles the rare collision, and we retry. */
static int create_temp(emm_outfile *o, size_t len)
{
    static const char alphabet[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    uint64_t seed = mix((uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec) ^
                    mix((uint64_t)getpid() << 32 ^ (uint64_t)(uintptr_t)o);
    char *x = o->tmp + len + strlen(SUFFIX);
    for (int attempt = 0; attempt < ATTEMPTS; attempt++) {
        uint64_t r = mix(seed + (uint64_t)attempt);
        for (int i = 0; i < RANDOM_CHARS; i++, r /= sizeof alphabet - 1)
            x[i] = alphabet[r % (sizeof alphabet - 1)];
        int fd = open(o->tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0 || errno != EEXIST)
            return fd;
    }
    return -1; /* errno is EEXIST */
}

static void release(emm_outfile *o)
{
    free(o->path);
    free(o->tmp);
    o->path = o->tmp = NULL;
    o->f = NULL;
}

emm_status emm_outfile_open(emm_outfile *o, const char *path, const char *what, emm_error *err)
{
    assert(o && path && what);
    o->f = NULL;
    size_t len = strlen(path);
    o->path = malloc(len + 1);
    o->tmp = malloc(len + strlen(SUFFIX) + RANDOM_CHARS + 1);
    if (!o->path || !o->tmp) {
        release(o);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    }
    memcpy(o->path, path, len + 1);
    memcpy(o->tmp, path, len);
    memcpy(o->tmp + len, SUFFIX, strlen(SUFFIX));
    o->tmp[len + strlen(SUFFIX) + RANDOM_CHARS] = '\0';
    int fd = create_temp(o, len);
    if (fd >= 0 && !(o->f = fdopen(fd, "wb"))) {
        int e = errno;
        close(fd);
        unlink(o->tmp);
        errno = e;
    }
    if (!o->f) {
        emm_status st = emm_fail(err, EMM_ERR_IO, "%s: cannot write %s: %s", path, what,
                                 strerror(errno));
        release(o);
        return st;
    }
    return EMM_OK;
}

emm_status emm_outfile_commit(emm_outfile *o, const char *what, emm_error *err)
{
    assert(o && o->f && what);
    /* A write that failed earlier set the stream's error flag but its errno
     * may be long overwritten: then the flush usually fails again and says
     * why; if not, EIO. */
    int e = 0;
    errno = 0;
    if (fflush(o->f) != 0 || ferror(o->f))
        e = errno ? errno : EIO;
    else if (fsync(fileno(o->f)) != 0)
        e = errno;
    if (fclose(o->f) != 0 && !e)
        e = errno;
    o->f = NULL;
    if (!e && rename(o->tmp, o->path) != 0)
        e = errno;
    if (e) {
        emm_status st = emm_fail(err, EMM_ERR_IO, "%s: cannot write %s: %s", o->path, what,
                                 strerror(e));
        unlink(o->tmp);
        release(o);
        return st;
    }
    release(o);
    return EMM_OK;
}

void emm_outfile_abort(emm_outfile *o)
{
    if (!o)
        return;
    if (o->f)
        fclose(o->f);
    if (o->tmp)
        unlink(o->tmp);
    release(o);
}
