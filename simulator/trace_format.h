/* Internal: the byte layout of trace files, version 2 (docs/trace-format.md
 * is the reference; keep the two in step), the checksum, and little-endian
 * helpers. Shared by simulator/trace.c and the trace tests, which use it to
 * build damaged files whose checksums are still right. */
#ifndef EMM_INTERNAL_TRACE_FORMAT_H
#define EMM_INTERNAL_TRACE_FORMAT_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define EMM_TRACE_MAGIC "EMMTRACE"
#define EMM_TRACE_VERSION 2u
#define EMM_TRACE_FLAG_ZSTD 1u
#define EMM_TRACE_FLAG_PC 2u /* version 2: the blocks carry the pc column */

/* File header: 72 bytes. */
enum {
    EMM_TH_MAGIC = 0,     /* 8 bytes "EMMTRACE" */
    EMM_TH_VERSION = 8,   /* u32 */
    EMM_TH_FLAGS = 12,    /* u32, EMM_TRACE_FLAG_* */
    EMM_TH_NARRAYS = 16,  /* u32 */
    EMM_TH_RESERVED = 20, /* u32, 0 */
    EMM_TH_RECORDS = 24,  /* u64 */
    EMM_TH_WRITES = 32,   /* u64, records with write = 1 */
    EMM_TH_BLOCKS = 40,   /* u64 */
    EMM_TH_NV = 48,       /* u64 */
    EMM_TH_NT = 56,       /* u64 */
    EMM_TH_CHECKSUM = 64, /* u64, emm_trace_hash of bytes [0, 64) */
    EMM_TRACE_HEADER_SIZE = 72
};

/* One array-table entry: kind u32, record_size u32, count u64, base u64.
 * The table is followed by its checksum (u64). */
enum { EMM_TRACE_ARRAY_SIZE = 24 };

/* Block header: 32 bytes. */
enum {
    EMM_TB_MAGIC = 0,      /* u32 EMM_TRACE_BLOCK_MAGIC */
    EMM_TB_RECORDS = 4,    /* u32, 1 .. EMM_TRACE_BLOCK_RECORDS */
    EMM_TB_RAW = 8,        /* u32, payload bytes before compression */
    EMM_TB_STORED = 12,    /* u32, payload bytes in the file */
    EMM_TB_PAYLOAD_SUM = 16, /* u64, emm_trace_hash of the stored payload */
    EMM_TB_HEADER_SUM = 24,  /* u64, emm_trace_hash of bytes [0, 24) */
    EMM_TRACE_BLOCK_HEADER_SIZE = 32
};
#define EMM_TRACE_BLOCK_MAGIC 0x314B4C42u /* "BLK1" read as little-endian u32 */
#define EMM_TRACE_BLOCK_RECORDS 65536u
#define EMM_TRACE_MAX_ARRAYS 4096u

/* A block's raw payload: the column table (one width byte per column, two
 * zero bytes, one u64 frame-of-reference minimum per column), then each
 * column's bit-packed stream, byte-aligned, in column order. */
enum {
    EMM_COL_ARRAY = 0,
    EMM_COL_DELTA, /* element minus the previous element of the same array in the block */
    EMM_COL_OFFSET,
    EMM_COL_BYTES,
    EMM_COL_WORK,
    EMM_COL_WRITE,
    EMM_TRACE_COLUMNS, /* the six columns of every block */
    EMM_COL_PC = EMM_TRACE_COLUMNS, /* with EMM_TRACE_FLAG_PC */
    EMM_TRACE_MAX_COLUMNS
};
/* The column table of a block of `ncols` columns: 8 width bytes (the unused
 * ones 0), then one u64 minimum per column. */
static inline size_t emm_trace_column_table(unsigned ncols)
{
    return 8 + 8 * (size_t)ncols;
}

/* Version 2's module table, after the geometry: a header (u32 modules, u32
 * bytes of paths), one entry per module (u64 bias, u64 lo, u64 hi, u32
 * offset of its path in the paths, u32 its length), the paths, then a u64
 * checksum of the whole region. */
enum { EMM_TRACE_MODULES_HEADER = 8, EMM_TRACE_MODULE_SIZE = 32 };
#define EMM_TRACE_MAX_MODULES 4096u
#define EMM_TRACE_MAX_MODULE_PATHS (1u << 20)
/* Widths 57..63 are never written: a column that needs more than 56 bits is
 * stored at 64 (plain u64 words), so a 64-bit load always holds one value. */
#define EMM_TRACE_MAX_PACKED_BITS 56u

static inline uint64_t emm_le64(const void *p)
{
    const uint8_t *b = (const uint8_t *)p;
    return (uint64_t)b[0] | (uint64_t)b[1] << 8 | (uint64_t)b[2] << 16 | (uint64_t)b[3] << 24 |
           (uint64_t)b[4] << 32 | (uint64_t)b[5] << 40 | (uint64_t)b[6] << 48 |
           (uint64_t)b[7] << 56;
}

static inline uint32_t emm_le32(const void *p)
{
    const uint8_t *b = (const uint8_t *)p;
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static inline void emm_put_le64(void *p, uint64_t v)
{
    uint8_t *b = (uint8_t *)p;
    for (int i = 0; i < 8; i++)
        b[i] = (uint8_t)(v >> (8 * i));
}

static inline void emm_put_le32(void *p, uint32_t v)
{
    uint8_t *b = (uint8_t *)p;
    for (int i = 0; i < 4; i++)
        b[i] = (uint8_t)(v >> (8 * i));
}

/* The checksum of every checksummed region: a 64-bit multiply-rotate hash
 * over little-endian 8-byte words in four interleaved lanes (fast: several
 * bytes per cycle). Each step is a bijection of the lane state for a fixed
 * word and of the word for a fixed state, so any damage confined to one
 * 8-byte word, in particular any flipped byte, always changes the result;
 * other damage goes unseen with probability about 2^-64. */
uint64_t emm_trace_hash(const void *data, size_t n, uint64_t seed);

#endif
