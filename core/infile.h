/* Internal: reading a whole input file with a size cap — the one way every
 * reader of a file from outside (machine files, strategy tables, reports,
 * meshes) brings it into memory, so no input makes emm grow without bound.
 *
 * A regular file larger than the reader's cap is refused before a byte is
 * read. A file that is not regular (a pipe, /dev/stdin, a device such as
 * /dev/zero) has no size to check first: it is read in growing steps and
 * refused as soon as it passes the smaller of the reader's cap and
 * EMM_INFILE_STREAM_MAX, so an endless stream costs at most that much
 * memory. A directory is refused as one.
 *
 * No input can block the program that reads it: every file is opened
 * non-blocking (a FIFO with no writer would otherwise hold open() for ever,
 * and under the shim that is the host program's constructor). A pipe or
 * FIFO is then read with a bound in time: EMM_INFILE_STREAM_WAIT_MS without
 * a byte (a FIFO nobody writes to, or a silent writer) and it is refused;
 * readers that need a regular file (traces are read with random access)
 * refuse anything else at once. */
#ifndef EMM_INTERNAL_INFILE_H
#define EMM_INTERNAL_INFILE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <sys/stat.h>

#include "emm/common.h"

/* The most any reader takes from a file that is not regular: 16 MiB. */
#define EMM_INFILE_STREAM_MAX ((size_t)16 << 20)

/* How long a pipe or FIFO may stay silent before its reader gives up: 2 s. */
#define EMM_INFILE_STREAM_WAIT_MS 2000

/* Opens `path` for reading without blocking: *fd is its descriptor
 * (close-on-exec) and *st its fstat. Errors (EMM_ERR_IO, *fd -1): "cannot
 * open", "is a directory, not a <what>", and, when `regular_only`, "is a
 * pipe or FIFO, not a <what>" or "is a device ...". A regular file's
 * descriptor is blocking again, ready for read() or fdopen(); any other
 * stays non-blocking. */
emm_status emm_infile_open(const char *path, const char *what, bool regular_only, int *fd,
                           struct stat *st, emm_error *err);

/* fopen(path, "rb") of a regular file only, through emm_infile_open (no
 * wait on a FIFO): NULL with err set otherwise. */
FILE *emm_infile_fopen(const char *path, const char *what, emm_error *err);

/* Reads the file at `path` whole into a malloc'ed buffer (*data, freed by
 * the caller) with a NUL after its *len bytes. `what` names the kind of
 * file in messages ("machine file"); `max` is the reader's cap in bytes.
 * Errors, each one line that starts with the path: EMM_ERR_IO (cannot open
 * or read; "is a directory"), EMM_ERR_RANGE ("too large for a <what>
 * (more than N)"), EMM_ERR_NOMEM; a pipe or FIFO also EMM_ERR_IO with
 * "nothing to read" (no writer) or "nothing to read for 2 s".  On failure *data is NULL. */
emm_status emm_infile_read(const char *path, const char *what, size_t max, char **data,
                           size_t *len, emm_error *err);

/* "16 MiB", "1 MiB", "4 KiB" or "N bytes": a cap as messages print it. */
void emm_infile_size_text(size_t bytes, char *buf, size_t cap);

#endif
