/* emm — the candidate arrays of a program (`emm run --list-sites`,
 * EMM_LIST_SITES; docs/design.md "The shim and the session", Tagging).
 *
 * libemmshim.so, in list mode, hands every large block the program
 * allocates to a site table with its call stack; when a block is freed,
 * and at exit for those still live, the table reads the block once to see
 * what its records look like (three floats, three indices, or one float
 * per entry: a block of a structure of arrays); at exit it
 * prints the sites, largest block first, each with its stack and a
 * suggested EMM_TAG rule. Not thread-safe: the shim serialises calls. */
#ifndef EMM_SITES_H
#define EMM_SITES_H

#include <stdio.h>

#include "emm/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct emm_sites emm_sites;

/* A table for blocks of at least min_bytes; NULL when out of memory. */
EMM_API emm_sites *emm_sites_new(uint64_t min_bytes);
EMM_API void emm_sites_free(emm_sites *t);

/* A block of `size` bytes at `block` (readable until emm_sites_release),
 * allocated from the call path `path` (a hash of its return addresses)
 * whose frames of the program's own, innermost first, are names[0..n):
 * each "name\0qualified name\0" (emm_tag_site_names), or NULL when the
 * frame has no symbol. The names are copied. */
EMM_API void emm_sites_add(emm_sites *t, uint64_t path, const char *const *names, size_t n,
                           const void *block, uint64_t size);
/* The block at `block` is about to be freed or moved: its records are read
 * now. Nothing happens for a block the table does not know. */
EMM_API void emm_sites_release(emm_sites *t, const void *block);
/* Reads the blocks still live and prints the sites, largest first, with a
 * suggested rule each, on `out` (lines start "emm: "). */
EMM_API void emm_sites_print(emm_sites *t, const char *program, FILE *out);

#ifdef __cplusplus
}
#endif
#endif
