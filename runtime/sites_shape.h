/* Internal to list mode (runtime/sites.c): what a candidate array's records
 * look like — their size, their fields and what each holds — from how the
 * program accesses the block (a capture that sees accesses: valgrind,
 * sancov), else guessed from the block's bytes. The shape decides the rule
 * --list-sites suggests: vertices:, triangles: or soup: only when the
 * fields fit. */
#ifndef EMM_RUNTIME_SITES_SHAPE_H
#define EMM_RUNTIME_SITES_SHAPE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "emm/common.h"

/* Instructions followed per site at most. */
#define SHAPE_PCS 64
#define SHAPE_FIELDS 24

/* One instruction's accesses to a site's blocks. */
typedef struct shape_pc {
    uint64_t pc, n;
    uint64_t g;          /* gcd of the distances between its successive offsets in a block */
    uint64_t first_off;  /* its first offset */
    uint64_t last_off;
    int64_t last_block;  /* the block of last_off */
    uint32_t size;       /* its access size (the first) */
    bool read, write;
} shape_pc;

typedef struct shape_acc {
    shape_pc pc[SHAPE_PCS];
    int npc;
    uint64_t n;     /* accesses noted */
    uint64_t other; /* by instructions beyond SHAPE_PCS */
} shape_acc;

/* An access of `size` bytes at offset `off` of block `block` (any number
 * that tells the site's blocks apart) by the instruction at pc. */
void shape_note(shape_acc *a, int64_t block, uint64_t off, uint32_t size, bool write, uint64_t pc);

typedef enum shape_kind {
    SHAPE_NONE,      /* no rule fits */
    SHAPE_VERTICES,  /* three coordinates in a row at `at` */
    SHAPE_TRIANGLES, /* three vertex indices in a row at `at` */
    SHAPE_SOUP,      /* a triangle's nine corner coordinates in a row at `at` */
    SHAPE_AXIS,      /* one coordinate per entry: a block of a structure of arrays */
    SHAPE_HALFEDGE   /* four or more index fields a record: half-edges, edges; never triangles */
} shape_kind;

typedef struct shape_field {
    uint32_t off, size;
    char cls;        /* 'f' coordinate-like, 'i' index-like, 'h' index or -1 (a handle), 'p' an
                        address, '0' zero, '?' other */
    emm_scalar type; /* for 'f' and 'i' */
    bool read, write;
} shape_field;

typedef struct shape {
    bool found;
    bool from_accesses; /* else a guess from the bytes */
    uint64_t accesses;  /* the accesses it comes from */
    int instructions;
    unsigned stride;
    int nf;
    shape_field f[SHAPE_FIELDS]; /* by offset */
    uint64_t records, in_use;
    shape_kind kind;
    unsigned at;
    emm_scalar type;
} shape;

/* The shape the accesses in `a` say (the stride most of the program's own
 * instructions step by, the fields they touch, typed from the block's
 * bytes); false when they say none (too few accesses). p: the block's
 * first len bytes; size: its size; used: its bytes up to the last that is
 * not zero. */
bool shape_from_accesses(const shape_acc *a, const unsigned char *p, size_t len, uint64_t size,
                         uint64_t used, shape *out);
/* The shape guessed from the bytes alone; false when nothing fits. */
bool shape_from_bytes(const unsigned char *p, size_t len, uint64_t size, uint64_t used,
                      shape *out);
/* The "records:" text. */
void shape_describe(const shape *s, char *out, size_t cap);
/* The rule's kind and its record part ("stride=12,vidx=0:u32"; an axis
 * block's "x=0:f32" with `axis`), or false when no kind fits. */
bool shape_rule(const shape *s, char axis, const char **kind, char *body, size_t cap);

#endif
