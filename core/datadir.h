/* Internal: where the files emm ships (the strategy table) are found, so a
 * build tree, an install and a moved install each find their own. */
#ifndef EMM_INTERNAL_DATADIR_H
#define EMM_INTERNAL_DATADIR_H

#include <stdbool.h>
#include <stddef.h>

/* The path of the shipped data file `name` ("table.txt"). The candidates,
 * in order:
 *   - NAME in the share/emm directory beside the module (the library or
 *     program this code is linked into), found from the module's own
 *     location (dladdr): <bindir>/../share/emm for a program,
 *     <libdir>/../share/emm for a library — so an install works from any
 *     prefix and after it is moved, and the build tree, laid out the same
 *     way, finds the source tree's data/ through its share/emm links;
 *   - the configured <datadir>/emm/NAME.
 * Writes the first candidate that exists to out (cap bytes; symbolic links
 * resolved), or the last one when none does, and returns whether it
 * exists. `tried` (may be NULL,
 * tcap bytes) gets every candidate looked at, separated by ", ". */
bool emm_data_file(const char *name, char *out, size_t cap, char *tried, size_t tcap);

#endif
