/* emm — the machine model (docs/machine.md; thesis §3.2, §6.1–6.2).
 *
 * A simulated STHORM-class core: a local store, a remote store reached by
 * word-by-word direct reads or by an asynchronous 2-channel DMA engine, and,
 * for comparison, a set-associative hardware cache whose hit and miss counts
 * equal Dinero IV's (docs/dinero.md). Every cycle lands in one named bucket;
 * the buckets add up to the total.
 *
 * Use: build a machine (defaults, then a machine file and single overrides),
 * validate it once, create one model per strategy, feed the models batches of
 * trace records, read the results. Nothing here is global: two simulations
 * can run side by side. */
#ifndef EMM_SIM_H
#define EMM_SIM_H

#include "emm/common.h"
#include "emm/strategy.h"
#include "emm/trace.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- the machine's configuration ------------------------------------------ */

typedef struct emm_machine emm_machine;

/* The cache's fetch policies, Dinero IV's -dfetch d, m and a. */
typedef enum emm_cache_fetch {
    EMM_CACHE_FETCH_DEMAND = 0, /* no prefetch */
    EMM_CACHE_FETCH_MISS,       /* prefetch the next line on a read miss (default) */
    EMM_CACHE_FETCH_ALWAYS      /* prefetch the next line on every read */
} emm_cache_fetch;

/* What one direct read of an element moves (direct.granularity): the
 * words of the field the program loads, or the element's whole record on
 * its first load (as an STL-style `Vertex getVertex(id)` copies it; later
 * loads of the same record are then local). */
typedef enum emm_direct_granularity {
    EMM_DIRECT_FIELD = 0,
    EMM_DIRECT_RECORD
} emm_direct_granularity;

/* One configuration key, as documented in docs/machine.md. */
typedef struct emm_machine_key {
    const char *name;     /* "dma.issue" */
    const char *unit;     /* "cycles", "bytes", ... */
    const char *help;     /* one line */
    const char *fallback; /* the default, as text */
} emm_machine_key;

/* A machine with every parameter at its default. Free with emm_machine_free. */
EMM_API emm_status emm_machine_new(emm_machine **out, emm_error *err);
EMM_API void emm_machine_free(emm_machine *m);
/* A copy of m (for a model that outlives its caller's machine). */
EMM_API emm_status emm_machine_clone(const emm_machine *m, emm_machine **out, emm_error *err);

/* Reads an INI-style machine file: "[section]" lines, "key = value" lines
 * (a key outside a section is written in full: "dma.issue = 266"), comments
 * from '#' or ';'. A file names each key at most once. On failure err reads
 * "FILE:LINE: problem" and m keeps the keys set before the bad line. */
EMM_API emm_status emm_machine_load(emm_machine *m, const char *path, emm_error *err);
/* The same for text in memory; `name` stands for the file in messages. */
EMM_API emm_status emm_machine_load_text(emm_machine *m, const char *name, const char *text,
                                         emm_error *err);
/* Applies one "KEY=VALUE" override (the --set option). */
EMM_API emm_status emm_machine_set(emm_machine *m, const char *assignment, emm_error *err);
/* Sets one key to a value given as text. `where` prefixes messages. */
EMM_API emm_status emm_machine_set_key(emm_machine *m, const char *key, const char *value,
                                       const char *where, emm_error *err);
/* Checks the rules that tie keys together (cache geometry, powers of two).
 * Each key's own range is checked when it is set. Models require a
 * validated machine. */
EMM_API emm_status emm_machine_validate(const emm_machine *m, emm_error *err);

/* The keys, in the order `emm machine show` prints them. */
EMM_API size_t emm_machine_key_count(void);
EMM_API const emm_machine_key *emm_machine_key_at(size_t i);
/* The value of `key` in m as text (as a machine file would spell it);
 * returns the length needed, as snprintf does; 0 for an unknown key. */
EMM_API size_t emm_machine_format(const emm_machine *m, const char *key, char *buf, size_t cap);
/* The value of `key` as a number (an emm_cache_fetch for cache.fetch, an
 * emm_direct_granularity for direct.granularity).
 * `key` must be one of the keys (assert). */
EMM_API uint64_t emm_machine_get(const emm_machine *m, const char *key);
/* True when `key` holds a word (cache.fetch, direct.granularity) rather
 * than a number. */
EMM_API int emm_machine_key_is_text(const char *key);

/* True when the machine has what strategy s needs (docs/machine.md,
 * cache.present): direct reads and the EMM strategies always; the cache
 * strategies only when the machine declares its cache. The others are
 * simulated as references, never chosen. */
EMM_API int emm_machine_offers(const emm_machine *m, const emm_strategy *s);

/* The thesis' remote store (remote.bytes, §6.1: 6 MB) is a size, not a
 * limit of the model: a mesh beyond it is simulated as if it fitted, with
 * a warning. When the mesh arrays of `trace` (every array but raw memory,
 * count × record size) take more than remote.bytes, writes that warning,
 * one line naming both sizes and the key, into msg and returns 1; else 0
 * and msg is "". */
EMM_API int emm_machine_remote_warning(const emm_machine *m, const emm_trace_info *trace,
                                       char *msg, size_t cap);

/* Cycles of one synchronous DMA of `bytes` bytes on an idle engine:
 * program + latency + cycles_per_8b*ceil(bytes/8) +
 * chunk_cycles*(ceil(bytes/chunk)-1); 0 bytes cost nothing. */
EMM_API uint64_t emm_machine_dma_cycles(const emm_machine *m, uint64_t bytes);

/* ---- cycles and results ---------------------------------------------------- */

typedef enum emm_bucket {
    EMM_BUCKET_LOCAL_ACCESS = 0, /* local store accesses (and a cache miss's local access) */
    EMM_BUCKET_REMOTE_ACCESS,    /* direct reads and writes of remote memory */
    EMM_BUCKET_COMPUTE,          /* the program's own work between accesses */
    EMM_BUCKET_EMM_INSTRUCTIONS, /* the EMM runtime's look-ups, checks, predictions */
    EMM_BUCKET_DMA_ISSUE,        /* the core programming the DMA engine */
    EMM_BUCKET_DMA_STALL,        /* the core waiting for a transfer it needs */
    EMM_BUCKET_CACHE_HIT,        /* cache hits */
    EMM_BUCKET_CACHE_MISS_STALL, /* waiting for cache line fills and late prefetches */
    EMM_BUCKET_COUNT
} emm_bucket;

/* "local_access", "remote_access", ... (the JSON report's keys). */
EMM_API const char *emm_bucket_name(emm_bucket b);

/* One layout cell of an EMM strategy and the DMA traffic it caused. */
typedef struct emm_cell_dma {
    double lo[EMM_MAX_DIMS], hi[EMM_MAX_DIMS]; /* the cell's box in the layout's space */
    uint64_t bytes; /* bytes DMA moved for the cell: its demand fetches and prefetches */
} emm_cell_dma;

typedef struct emm_result {
    emm_strategy strategy;
    uint64_t accesses;                   /* records simulated */
    uint64_t total;                      /* == the sum of cycles[] */
    uint64_t cycles[EMM_BUCKET_COUNT];
    int has_cache;                       /* the cache counts below are meaningful */
    struct {
        uint64_t demand_fetches;         /* line references by the program (Dinero's "Demand Fetches") */
        uint64_t demand_misses;
        uint64_t prefetch_fetches;       /* Dinero's "Prefetch Fetches" */
        uint64_t prefetch_misses;        /* prefetches that brought a line in */
        uint64_t late_prefetches;        /* demand hits that waited for a prefetch in flight */
    } cache;
    int has_dma;                         /* the DMA counts below are meaningful */
    struct {
        uint64_t transfers;
        uint64_t bytes;
    } dma;
    int has_direct;                      /* the direct-read counts below are meaningful */
    struct {
        uint64_t words_read;
        uint64_t words_written;
    } direct;
    int has_emm;                         /* the EMM counts below are meaningful (docs/fetch.md) */
    struct {
        uint64_t cell_changes;           /* accesses in a different cell than the access before */
        uint64_t demand_fetches;         /* cells fetched because an access needed them */
        uint64_t demand_bytes;
        uint64_t prefetches;             /* cells fetched ahead by the fetch scheme */
        uint64_t prefetch_bytes;
        uint64_t useful_prefetches;      /* prefetched cells entered before their eviction */
        uint64_t dropped_prefetches;     /* prefetches skipped: no room without evicting a cell in flight */
        uint64_t evictions;              /* resident cells evicted to make room */
        uint64_t other_accesses;         /* records outside the layout (RAW arrays, unused
                                            vertices), read directly from remote memory */
        uint64_t local_budget;           /* local store bytes for cells: local.bytes minus look-up bytes */
        uint64_t lookup_bytes;           /* the layout's look-up tables in the local store */
        uint64_t filtered_prefetches;    /* prefetches skipped: the cell's last prefetch was
                                            evicted unused (docs/fetch.md, "Prefetch filter") */
        uint64_t lookups;                /* element requests found through the look-up tables */
        uint64_t pointer_accesses;       /* vertex requests through the triangle's pointer */
        uint64_t same_record;            /* further loads of the record just requested */
        int lookup_paged;                /* the tables exceed emm.lookup_budget: paged */
        uint64_t lookup_pages;           /* pages of the tables brought in by DMA */
        uint64_t lookup_page_bytes;      /* their bytes (part of dma.bytes) */
        uint64_t refetches;              /* cell transfers (demand or prefetch) of a cell
                                            transferred before in the run: evicted, then
                                            needed or guessed again */
        uint64_t refetch_bytes;
        uint64_t unused_prefetches;      /* prefetched cells evicted before the program
                                            entered them */
        uint64_t prefetch_checks;        /* cells the fetch scheme named (each a look-up and,
                                            for a cell with triangles, a residency check) */
        uint64_t resident_cells;         /* cells present (resident or in flight) summed over
                                            the cell changes: / cell_changes is the mean */
    } emm;
    /* Per-cell DMA traffic of an EMM strategy, filled only on request
     * (emm_model_cells, emm_replay_options.cells); cell == NULL otherwise.
     * The result owns `cell`: emm_result_release frees it. The sum of the
     * cells' bytes plus emm.lookup_page_bytes equals dma.bytes. */
    struct {
        uint32_t count;      /* the layout's cells: cell[0..count), in cell order */
        uint32_t dims;       /* coordinates per box (emm_layout_axes) */
        double lo[EMM_MAX_DIMS], hi[EMM_MAX_DIMS]; /* the layout's bounding box */
        emm_cell_dma *cell;
    } cells;
} emm_result;

/* ---- models ---------------------------------------------------------------- */

/* A model simulates one strategy over a stream of trace records. */
typedef struct emm_model emm_model;

/* A model of strategy s on machine m (validated; copied, so m may be freed)
 * for records of a trace whose arrays are described by `trace` (copied).
 * EMM strategies (docs/fetch.md) and cache@LAYOUT need the trace's
 * geometry (EMM_ERR_INVALID for an address-only trace); an EMM strategy
 * whose cells do not fit the local store left by the layout's look-up
 * tables is EMM_ERR_RANGE, with a message naming a CELL that fits. */
EMM_API emm_status emm_model_new(const emm_machine *m, const emm_strategy *s,
                                 const emm_trace_info *trace, emm_model **out, emm_error *err);
/* Simulates n records in order. The records must be valid for the trace
 * (array index and element in range, bytes >= 1): the reader guarantees it
 * and this loop does not check. */
EMM_API void emm_model_run(emm_model *model, const emm_trace_record *recs, size_t n);
/* Back to the state of a new model (empty cache, idle DMA, zero cycles). */
EMM_API void emm_model_reset(emm_model *model);
/* The result so far (out->cells stays empty: see emm_model_cells). */
EMM_API void emm_model_result(const emm_model *model, emm_result *out);
/* Adds to `out` (a result of this model) the layout's cells and the DMA
 * bytes moved for each since the model's last reset: allocates
 * out->cells.cell, which emm_result_release frees. A model of a strategy
 * without cells (direct, cache, cache@LAYOUT) leaves out->cells empty.
 * EMM_ERR_NOMEM when memory runs out (out->cells stays empty). */
EMM_API emm_status emm_model_cells(const emm_model *model, emm_result *out, emm_error *err);
/* Frees what emm_model_cells allocated in r and empties r->cells; any
 * result may be passed (one without cells is left as it is). */
EMM_API void emm_result_release(emm_result *r);
EMM_API void emm_model_free(emm_model *model);

/* ---- what each record cost, and what the machine did when ------------------ */

/* The cycles one record cost, bucket by bucket, and the EMM runtime's
 * look-ups it made (emm.lookups). */
typedef struct emm_record_cost {
    uint64_t cycles[EMM_BUCKET_COUNT];
    uint64_t lookups;
} emm_record_cost;

/* Simulates n records as emm_model_run does — the same state and results
 * after — and sets cost[i] to what record i cost: the change of the
 * model's buckets and look-ups across it, so the costs add up to the
 * result's. A cell's DMA stall lands on the record that waited for it.
 * Slower than emm_model_run (the counters are read after each record), and
 * the plain path does not pay for it: only callers that attribute cycles
 * (emm annotate) use it. */
EMM_API void emm_model_run_costed(emm_model *model, const emm_trace_record *recs, size_t n,
                                  emm_record_cost *cost);

/* What a DMA transfer moved. */
typedef enum emm_transfer_kind {
    EMM_TRANSFER_DEMAND = 0, /* a cell the program needed */
    EMM_TRANSFER_PREFETCH,   /* a cell the fetch scheme expects it to need */
    EMM_TRANSFER_TABLE_PAGE  /* a page of the paged look-up tables */
} emm_transfer_kind;

/* Callbacks a model makes as the simulated machine works, in the order of
 * the model's clock (cycles since its reset), for timelines. Any may be
 * NULL. They run on the thread that runs the model. */
typedef struct emm_observer {
    /* A DMA transfer: on `channel`, from `start` (the channel takes it) to
     * `end` (the data has arrived); `cell` is the layout cell (a page index
     * for a table page). */
    void (*transfer)(void *ctx, uint32_t channel, uint64_t start, uint64_t end, uint64_t bytes,
                     emm_transfer_kind kind, uint64_t cell);
    /* The core waits from `start` for `cycles` (EMM_BUCKET_DMA_STALL). */
    void (*stall)(void *ctx, uint64_t start, uint64_t cycles);
    /* The program enters layout cell `cell` at `time`. */
    void (*enter)(void *ctx, uint64_t time, uint64_t cell);
} emm_observer;

/* Makes `model` report to obs (copied; NULL stops it). Returns nonzero
 * when the model has events to report: the EMM strategies (their DMA
 * engine, stalls and cells); direct reads and the cache have none. */
EMM_API int emm_model_observe(emm_model *model, const emm_observer *obs, void *ctx);

#ifdef __cplusplus
}
#endif
#endif
