/* Internal: an output file written whole or not at all. The data goes to a
 * temporary file beside the destination (same directory, so same file
 * system), which is flushed, synced and renamed over the destination only
 * when every write succeeded; a reader sees the old file or the new one,
 * never half of one, and a failure leaves nothing behind. */
#ifndef EMM_INTERNAL_OUTFILE_H
#define EMM_INTERNAL_OUTFILE_H

#include <stdio.h>

#include "emm/common.h"

typedef struct emm_outfile {
    FILE *f;    /* open for writing (binary) between open and commit/abort */
    char *path; /* the destination (a copy) */
    char *tmp;  /* the temporary file, "<path>.tmp.XXXXXX" */
} emm_outfile;

/* Creates a unique temporary file beside `path`, with the mode an ordinary
 * fopen would give (0666 less the umask), open for writing as o->f. `what`
 * names the output in messages ("the report"): "<path>: cannot write <what>:
 * <errno text>". On failure o holds nothing to release (abort is a no-op). */
emm_status emm_outfile_open(emm_outfile *o, const char *path, const char *what, emm_error *err);

/* Flushes, checks every write (ferror), syncs, closes and renames into
 * place; on any failure removes the temporary file and says `what`, the
 * path and the errno text. Either way o is released. */
emm_status emm_outfile_commit(emm_outfile *o, const char *what, emm_error *err);

/* Closes and removes the temporary file; safe after a failed open or commit
 * and on a zeroed emm_outfile. */
void emm_outfile_abort(emm_outfile *o);

#endif
