/* emm — the candidate arrays of a program (`emm run --list-sites`,
 * EMM_LIST_SITES; docs/design.md "The shim and the session", Tagging).
 *
 * libemmshim.so, in list mode, hands every large block the program
 * allocates to a site table with its call stack, and the accesses to them
 * a capture with program counters sees; when a block is freed, and at
 * exit for those still live, the table reads the block once; at exit it
 * prints the sites, largest block first, each with its stack, what its
 * records look like (from the accesses, else a guess from the bytes) and an
 * EMM_TAG rule that selects that block, checked by replaying the run's
 * allocations through the rule matcher, or says that none does. Not
 * thread-safe: the shim serialises calls. */
#ifndef EMM_SITES_H
#define EMM_SITES_H

#include <stdio.h>

#include "emm/common.h"
#include "emm/session.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct emm_sites emm_sites;

/* A table listing blocks of at least min_bytes; it records every
 * allocation of at least log_min bytes (the least a rule selects) with its
 * call stack, and replays them through the rules it suggests to check
 * that each selects its block. NULL when out of memory. */
EMM_API emm_sites *emm_sites_new(uint64_t min_bytes, uint64_t log_min);
EMM_API void emm_sites_free(emm_sites *t);

/* A block of `size` bytes at `block` (readable until emm_sites_release),
 * allocated from the call path `path` (a hash of its return addresses)
 * whose frames of the program's own, innermost first, are names[0..n)
 * with return addresses ips[0..n) (agent_rules_stack): each name
 * "name\0qualified name\0" (emm_tag_site_names), or NULL when the frame
 * has no name. `from` is what emm_sites_release returned for the block a
 * realloc moved into this one, else -1. The names are copied. Returns the
 * allocation's place in the record, or -1. */
EMM_API int64_t emm_sites_add(emm_sites *t, uint64_t path, const char *const *names,
                              const uintptr_t *ips, size_t n, const void *block, uint64_t size,
                              int64_t from);
/* The block at `block` is about to be freed or moved: its records are read
 * now. Returns its place in the record (for emm_sites_add's `from` when a
 * realloc moves it), or -1 for a block the table does not know. */
EMM_API int64_t emm_sites_release(emm_sites *t, const void *block);
/* The live listed blocks as [lo, hi) pairs, up to cap of them (lo, hi
 * NULL: none); returns how many there are. A capture that sees accesses
 * watches them. */
EMM_API size_t emm_sites_ranges(emm_sites *t, uint64_t *lo, uint64_t *hi, size_t cap);
/* Whether the block at `block` is a live listed block. */
EMM_API int emm_sites_listed(const emm_sites *t, const void *block);
/* The program's accesses r[0..n) (emm_raw_access: address, size, write,
 * program counter): those in listed blocks say how the program steps
 * through their records. */
EMM_API void emm_sites_access(emm_sites *t, const emm_raw_access *r, size_t n);
/* Reads the blocks still live and prints the sites, largest first, with a
 * suggested rule each, on `out` (lines start "emm: "). */
EMM_API void emm_sites_print(emm_sites *t, const char *program, FILE *out);

#ifdef __cplusplus
}
#endif
#endif
