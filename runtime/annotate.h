/* Internal: cycles by program counter, source line and function — what
 * emm annotate prints and what a session's summary names (its stall
 * lines). Records and their costs (emm_model_run_costed) are summed by
 * program counter as the run goes; at the end the counters are resolved
 * to lines and functions (srcline.h) and summed again. */
#ifndef EMM_RUNTIME_ANNOTATE_H
#define EMM_RUNTIME_ANNOTATE_H

#include <stddef.h>
#include <stdint.h>

#include "emm/sim.h"
#include "emm/trace.h"

/* What a line or a function cost. `key` picks what rows are sorted by:
 * 0 .. EMM_BUCKET_COUNT-1 a bucket, EMM_ANNOTATE_TOTAL, _LOOKUPS,
 * _ACCESSES. */
typedef struct emm_annotate_row {
    const char *file;     /* the source file (a function's: where it is defined; NULL: unknown) */
    int line;             /* 0 for a function's row, or unknown */
    const char *function; /* NULL: unknown */
    uint64_t cycles[EMM_BUCKET_COUNT];
    uint64_t total, lookups, accesses;
} emm_annotate_row;

enum {
    EMM_ANNOTATE_TOTAL = EMM_BUCKET_COUNT,
    EMM_ANNOTATE_LOOKUPS,
    EMM_ANNOTATE_ACCESSES,
    EMM_ANNOTATE_KEYS
};

/* "total", the bucket names, "lookups", "accesses"; the key of a name, or
 * -1. */
const char *emm_annotate_key_name(int key);
int emm_annotate_key(const char *name);
uint64_t emm_annotate_value(const emm_annotate_row *r, int key);

typedef struct emm_annotation emm_annotation;

/* An empty annotation; NULL when memory runs out. */
emm_annotation *emm_annotation_new(void);
void emm_annotation_free(emm_annotation *a);

/* Adds records recs[0..n) and what each cost (a costed run's callback). A
 * record without a pc counts in the totals and in the "no pc" row. Returns
 * 0 when memory ran out (the rows then miss some records). */
int emm_annotation_add(emm_annotation *a, const emm_trace_record *recs,
                       const emm_record_cost *cost, size_t n);

/* Adds a DMA stall of `cycles` at program counter pc (0: none) alone: the
 * stall lines of a run whose model reports its stalls (emm_model_stalls),
 * whose rows then hold DMA stalls and nothing else. Returns 0 when memory
 * ran out. */
int emm_annotation_add_stall(emm_annotation *a, uint64_t pc, uint64_t cycles);

/* The sums so far, every record included (a row with file, line and
 * function NULL). */
const emm_annotate_row *emm_annotation_total(const emm_annotation *a);

/* Resolves the counters through the modules m[0..n) into rows by source
 * line and by function, each sorted by `key`, largest first; counters that
 * resolve to no line go to one row of unknown place. Call once. */
emm_status emm_annotation_resolve(emm_annotation *a, const emm_trace_module *m, uint32_t n,
                                  int key, emm_error *err);
/* The rows resolve made: by line, and by function. A function's row
 * counts its own lines and those of the functions inlined into it (so the
 * function rows overlap where code was inlined; the line rows do not). */
size_t emm_annotation_lines(const emm_annotation *a, const emm_annotate_row **rows);
size_t emm_annotation_functions(const emm_annotation *a, const emm_annotate_row **rows);

#endif
