/* emm — trace files (docs/trace-format.md).
 *
 * A trace is self-contained: a versioned header, the tagged arrays'
 * descriptions, a snapshot of the geometry the layouts need (vertex
 * positions, triangle vertex indices), then the access records in
 * checksummed, compactly encoded blocks (optionally zstd-compressed).
 * The writer and the reader stream: neither holds the access records of the
 * whole trace in memory. A truncated or corrupted file gets an error naming
 * the byte offset and what was wrong. */
#ifndef EMM_TRACE_H
#define EMM_TRACE_H

#include "emm/common.h"

#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* One tagged array. The original address of byte `offset` of element `e` is
 * base + e * record_size + offset. */
typedef struct emm_trace_array {
    emm_array_kind kind;
    uint32_t record_size; /* bytes per record (1 for EMM_ARRAY_RAW) */
    uint64_t count;       /* records */
    uint64_t base;        /* original address of record 0 */
} emm_trace_array;

/* The most bytes one access may claim: an access of a tagged array also
 * stays within one record (bytes <= record_size). Captured accesses are
 * loads and stores of at most 64 bytes; the bound keeps a model's work per
 * record small whatever a trace file says (the cache walks bytes / 64 lines
 * per record). */
#define EMM_TRACE_MAX_ACCESS_BYTES 4096u

/* One access. `work` is the compute (in cycles, or instrumented basic blocks
 * where the capture counts them) since the previous record. */
typedef struct emm_trace_record {
    uint64_t element;
    uint32_t array;   /* index into the trace's arrays */
    uint32_t offset;  /* byte offset inside the record */
    uint32_t bytes;   /* bytes accessed, 1 .. EMM_TRACE_MAX_ACCESS_BYTES and <= record_size */
    uint32_t work;
    uint8_t write;    /* 0 read, 1 write */
    uint64_t pc;      /* the program counter of the access, one byte past the
                         access's code (sancov: its hook's return address;
                         valgrind: the instruction's address + 1), or 0 when the
                         capture does not know it; emm_trace_module says which
                         object it falls in */
} emm_trace_record;

/* An object mapped in the traced program (its executable, a shared
 * library), for resolving the records' program counters offline: a pc in
 * [lo, hi) lies in the file at `path`, at file address pc - bias. */
typedef struct emm_trace_module {
    uint64_t bias; /* the load bias: run-time address minus file address */
    uint64_t lo, hi;
    const char *path;
} emm_trace_module;

/* The geometry snapshot: may be empty (nv == nt == 0) for an address-only
 * trace, in which case only the `direct` and `cache` strategies apply. */
typedef struct emm_trace_geometry {
    uint64_t nv;
    uint64_t nt;
    const double *xyz;   /* 3 * nv */
    const int32_t *tri;  /* 3 * nt */
} emm_trace_geometry;

typedef struct emm_trace_info {
    uint32_t version;
    uint32_t narrays;
    const emm_trace_array *arrays;
    emm_trace_geometry geometry;
    uint64_t accesses;   /* records in the file (known once the writer closed) */
    int compressed;      /* blocks are zstd-compressed */
    uint64_t writes;     /* records with write = 1 (known once the writer closed) */
    uint64_t blocks;     /* record blocks in the file */
    int has_pc;          /* the records carry program counters (version 2 and later) */
    uint32_t nmodules;   /* the traced program's objects, for those pcs */
    const emm_trace_module *modules;
} emm_trace_info;

typedef struct emm_trace_writer emm_trace_writer;
typedef struct emm_trace_reader emm_trace_reader;

/* Starts a trace at `path` (written to a temporary file beside it and renamed
 * into place by emm_trace_writer_close). The arrays and geometry are copied.
 * `compress` asks for zstd blocks. */
EMM_API emm_status emm_trace_writer_open(const char *path, const emm_trace_array *arrays,
                                         uint32_t narrays, const emm_trace_geometry *geometry,
                                         int compress, emm_trace_writer **out, emm_error *err);
/* What a trace holds besides its arrays and geometry; zero-initialise. */
typedef struct emm_trace_options {
    int compress;                        /* zstd blocks */
    int pcs;                             /* store the records' pc column */
    const emm_trace_module *modules;     /* copied; may be NULL when nmodules is 0 */
    uint32_t nmodules;
} emm_trace_options;

/* emm_trace_writer_open with options (NULL: none). */
EMM_API emm_status emm_trace_writer_open_ex(const char *path, const emm_trace_array *arrays,
                                            uint32_t narrays, const emm_trace_geometry *geometry,
                                            const emm_trace_options *opt, emm_trace_writer **out,
                                            emm_error *err);
/* Appends n records. */
EMM_API emm_status emm_trace_write(emm_trace_writer *w, const emm_trace_record *recs,
                                   size_t n, emm_error *err);
/* Flushes, finishes the header and renames the file into place. Frees w. */
EMM_API emm_status emm_trace_writer_close(emm_trace_writer *w, emm_error *err);
/* Drops an unfinished trace: removes the temporary file, frees w. */
EMM_API void emm_trace_writer_abort(emm_trace_writer *w);

/* Opens a trace and reads its header, arrays and geometry. */
EMM_API emm_status emm_trace_reader_open(const char *path, emm_trace_reader **out, emm_error *err);
EMM_API const emm_trace_info *emm_trace_reader_info(const emm_trace_reader *r);
/* Reads up to `cap` records into `buf`; *n is the number read, 0 at the end.
 * A damaged block is an error naming its byte offset. */
EMM_API emm_status emm_trace_read(emm_trace_reader *r, emm_trace_record *buf, size_t cap,
                                  size_t *n, emm_error *err);
/* Starts reading the records again from the first. */
EMM_API emm_status emm_trace_rewind(emm_trace_reader *r, emm_error *err);
EMM_API void emm_trace_reader_close(emm_trace_reader *r);

/* The longest din line emm_din_import takes, in bytes (a din line is a
 * label and an address: a few dozen characters). */
#define EMM_DIN_LINE_MAX 4096

typedef struct emm_din_counts {
    uint64_t lines;    /* lines read */
    uint64_t accesses; /* records written */
    uint64_t skipped;  /* instruction fetches (label 2) left out */
} emm_din_counts;

/* Reads Dinero IV's din text from `in` (named `name` in messages, e.g. its
 * path or "stdin") and appends one record per read or write to `w`, whose
 * only array must be raw memory (docs/trace-format.md "din"). `bytes` is the
 * size of every access, 1 .. EMM_TRACE_MAX_ACCESS_BYTES, or 0 for "to the
 * end of the aligned 4-byte word", the word Dinero IV accesses. Memory
 * stays bounded whatever `in` holds: a line longer than EMM_DIN_LINE_MAX
 * is an error, as are a NUL byte, a malformed line, an unsupported label
 * and an access running past the top of the 64-bit address space, each
 * "NAME:LINE: problem". The caller aborts or closes w. */
EMM_API emm_status emm_din_import(FILE *in, const char *name, uint32_t bytes, emm_trace_writer *w,
                                  emm_din_counts *counts, emm_error *err);

/* Where the models put each array (docs/machine.md "Addresses"), so that a
 * simulation does not depend on where the program's allocations happened
 * to land in its run (ASLR, the allocations before them): every array but
 * raw memory is laid out again from EMM_TRACE_PLACE_START, in the trace's
 * order, each starting a fresh 4 KiB page; arrays whose bytes overlapped
 * keep their distance (their group's lowest byte starts the page). Raw
 * memory keeps its addresses. Fills base[0 .. info->narrays - 1]; fails
 * only for memory. */
#define EMM_TRACE_PLACE_START 0x10000000u
EMM_API emm_status emm_trace_place(const emm_trace_info *info, uint64_t *base, emm_error *err);

/* "vertices", "triangles" or "raw" (a static string; "?" for other values). */
EMM_API const char *emm_trace_kind_name(emm_array_kind kind);

#ifdef __cplusplus
}
#endif
#endif
