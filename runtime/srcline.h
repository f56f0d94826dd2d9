/* Internal: program counters to source lines and functions (emm annotate,
 * the session's stall lines), through elfutils' libdwfl over the objects a
 * trace names (emm_trace_module). Used offline or at a session's finish,
 * never on a capture path. */
#ifndef EMM_RUNTIME_SRCLINE_H
#define EMM_RUNTIME_SRCLINE_H

#include <stdbool.h>
#include <stdint.h>

#include "emm/common.h"
#include "emm/trace.h"

typedef struct emm_srcmap emm_srcmap;

/* Where a program counter lies in the program's source. The strings belong
 * to the map and live as long as it. */
#define EMM_SRCLOC_CHAIN 8

typedef struct emm_srcloc {
    const char *function; /* the innermost function, inlined ones included, or NULL */
    /* The functions the code lies in, innermost first: an inlined function,
     * the one it was inlined into, ... up to the function the object's
     * symbol names (chain[0] == function). */
    const char *chain[EMM_SRCLOC_CHAIN];
    const char *chain_file[EMM_SRCLOC_CHAIN]; /* where each is defined, or NULL */
    int nchain;
    const char *file;     /* the source file, or NULL */
    int line;             /* 0 when unknown */
    const char *module;   /* the object's path, or NULL when no module holds the pc */
} emm_srcloc;

/* A map over the modules m[0..n) (copied). EMM_ERR_NOMEM, or
 * EMM_ERR_UNSUPPORTED when libdwfl cannot start. */
emm_status emm_srcmap_new(const emm_trace_module *m, uint32_t n, emm_srcmap **out,
                          emm_error *err);

/* Resolves `pc`, a return address as the capture records it: the call
 * before it (pc - 1) is what is looked up. Fills what is known (the
 * module alone when the object has no debug information) and returns
 * whether a source line was found. */
bool emm_srcmap_lookup(emm_srcmap *map, uint64_t pc, emm_srcloc *out);

void emm_srcmap_free(emm_srcmap *map);

/* Modules of the calling process, for a trace's module table: its loaded
 * objects (dl_iterate_phdr), the executable by its /proc/self/exe path.
 * *out is malloc'ed (one block; free() it), *n its count. */
emm_status emm_process_modules(emm_trace_module **out, uint32_t *n, emm_error *err);

#endif
