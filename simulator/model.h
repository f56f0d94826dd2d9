/* Internal: what every model implements. A model sees records in batches;
 * the dispatch through `ops` happens once per batch, never per access, so
 * each model's loop stays tight.
 *
 * A later model (an EMM strategy, or the cache on a reordered layout) embeds
 * `struct emm_model` as its first member, fills `ops`, and is created from
 * emm_model_new's dispatch; the replay pipeline does not change. */
#ifndef EMM_SIM_MODEL_H
#define EMM_SIM_MODEL_H

#include "machine.h"
#include "share.h"

/* A DMA stall of `cycles` (EMM_BUCKET_DMA_STALL) while the model served
 * record r: the record emm_model_run_costed would charge it to. */
typedef void (*emm_stall_fn)(void *ctx, const emm_trace_record *r, uint64_t cycles);

struct emm_model_ops {
    void (*run)(emm_model *m, const emm_trace_record *recs, size_t n);
    void (*reset)(emm_model *m);
    void (*result)(const emm_model *m, emm_result *out);
    void (*destroy)(emm_model *m);
    /* Optional. The live counters of what the records cost so far, read
     * after each record by emm_model_run_costed (without it, the result). */
    void (*costs)(const emm_model *m, emm_record_cost *out);
    /* Optional. Sets (or, with NULL, clears) the observer; a model without
     * it has no events to report. */
    void (*observe)(emm_model *m, const emm_observer *obs, void *ctx);
    /* Optional. Sets (or, with NULL, clears) where the core's DMA stalls
     * are reported with the record that waited (emm_model_stalls). */
    void (*stalls)(emm_model *m, emm_stall_fn fn, void *ctx);
};

struct emm_model {
    const struct emm_model_ops *ops;
    emm_strategy strategy;
};

/* Where each array's records start and how long they are, for turning a
 * record into its address: base[a] + element * size[a] + offset, with the
 * arrays placed by emm_trace_place (the same every run, whatever the
 * program's own addresses were). */
typedef struct emm_addr_map {
    uint32_t narrays;
    uint64_t *base;
    uint64_t *size;
} emm_addr_map;

emm_status emm_addr_map_init(emm_addr_map *map, const emm_trace_info *trace, emm_error *err);
void emm_addr_map_free(emm_addr_map *map);

static inline uint64_t emm_addr_of(const emm_addr_map *map, const emm_trace_record *r)
{
    return map->base[r->array] + r->element * map->size[r->array] + r->offset;
}

/* The last byte an access of `bytes` (>= 1) at `addr` touches, clamped to
 * the top of the 64-bit address space: an access that would wrap past 2^64
 * (a raw address from an imported or damaged trace can) ends at the last
 * address, so the lines and words a model counts for it stay bounded by
 * its size. Every model counts its units from here. */
static inline uint64_t emm_last_byte(uint64_t addr, uint32_t bytes)
{
    uint64_t last;
    return __builtin_add_overflow(addr, (uint64_t)bytes - 1, &last) ? UINT64_MAX : last;
}

/* emm_model_new with the layouts and geometry the models of one run share
 * (the model runner passes its own share; emm_model_new a fresh one). */
emm_status emm_model_create(const emm_machine *m, const emm_strategy *s,
                            const emm_trace_info *trace, emm_model_share *share,
                            emm_model **out, emm_error *err);

/* The constructors of the models this build has. */
emm_status emm_direct_model_new(const emm_machine_params *p, const emm_trace_info *trace,
                                emm_model **out, emm_error *err);
emm_status emm_cache_model_new(const emm_machine_params *p, const emm_trace_info *trace,
                               emm_model **out, emm_error *err);

/* The model's cycles so far: its result's total, read cheaply. */
uint64_t emm_model_total(const emm_model *model);

/* From now on `model` reports each DMA stall to fn (NULL: stops it), on
 * the thread that runs it, while it runs at full speed: what the session
 * needs of emm_model_run_costed (its stall lines) at the price of a call
 * per stall instead of a look at the counters after every record. Returns
 * 0 when the model has no stalls to report (direct reads, the cache). */
int emm_model_stalls(emm_model *model, emm_stall_fn fn, void *ctx);

#endif
