/* Helpers shared by the libFuzzer harnesses (tests/fuzz/README.md). Each
 * harness feeds one reader of outside input with libFuzzer's bytes and
 * checks that it answers with EMM_OK or one error line: ASan, UBSan,
 * libFuzzer's -timeout and -rss_limit_mb catch a crash, a hang or a memory
 * blow-up. */
#ifndef EMM_TESTS_FUZZ_H
#define EMM_TESTS_FUZZ_H

#include "emm/common.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A message must be one non-empty line. */
static inline void fuzz_check_error(emm_status st, const emm_error *err)
{
    if (st == EMM_OK)
        return;
    if (err->status != st || err->message[0] == '\0' || strchr(err->message, '\n')) {
        fprintf(stderr, "fuzz: bad error report: status %d/%d, message '%s'\n", (int)st, (int)err->status,
                err->message);
        abort();
    }
}

/* The bytes as a NUL-terminated string (a copy; free it). */
static inline char *fuzz_string(const uint8_t *data, size_t size)
{
    char *s = malloc(size + 1);
    if (!s)
        abort();
    memcpy(s, data, size);
    s[size] = '\0';
    return s;
}

/* A path whose file holds exactly the bytes: a memfd reopened through
 * /proc, so readers that take a path run on the input without touching the
 * disk. The path stays the same for the whole run. */
static inline const char *fuzz_file(const uint8_t *data, size_t size)
{
    static int fd = -1;
    static char path[64];
    if (fd < 0) {
        fd = memfd_create("emm-fuzz", MFD_CLOEXEC);
        if (fd < 0) {
            perror("memfd_create");
            abort();
        }
        snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    }
    if (ftruncate(fd, 0) != 0 || (size && pwrite(fd, data, size, 0) != (ssize_t)size)) {
        perror("fuzz_file");
        abort();
    }
    return path;
}

#endif
