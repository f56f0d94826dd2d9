/* Internal: reading a whole input file with a size cap — the one way every
 * reader of a file from outside (machine files, strategy tables, reports,
 * meshes) brings it into memory, so no input makes emm grow without bound.
 *
 * A regular file larger than the reader's cap is refused before a byte is
 * read. A file that is not regular (a pipe, /dev/stdin, a device such as
 * /dev/zero) has no size to check first: it is read in growing steps and
 * refused as soon as it passes the smaller of the reader's cap and
 * EMM_INFILE_STREAM_MAX, so an endless stream costs at most that much
 * memory. A directory is refused as one. */
#ifndef EMM_INTERNAL_INFILE_H
#define EMM_INTERNAL_INFILE_H

#include <stddef.h>

#include "emm/common.h"

/* The most any reader takes from a file that is not regular: 16 MiB. */
#define EMM_INFILE_STREAM_MAX ((size_t)16 << 20)

/* Reads the file at `path` whole into a malloc'ed buffer (*data, freed by
 * the caller) with a NUL after its *len bytes. `what` names the kind of
 * file in messages ("machine file"); `max` is the reader's cap in bytes.
 * Errors, each one line that starts with the path: EMM_ERR_IO (cannot open
 * or read; "is a directory"), EMM_ERR_RANGE ("too large for a <what>
 * (more than N)"), EMM_ERR_NOMEM. On failure *data is NULL. */
emm_status emm_infile_read(const char *path, const char *what, size_t max, char **data,
                           size_t *len, emm_error *err);

/* "16 MiB", "1 MiB", "4 KiB" or "N bytes": a cap as messages print it. */
void emm_infile_size_text(size_t bytes, char *buf, size_t cap);

#endif
