/* Models: one per strategy, created by strategy kind; the caller sees only
 * the opaque emm_model (include/emm/sim.h). */
#include "model.h"

#include <stdlib.h>
#include <string.h>

#include "cache_layout.h"
#include "emm_fetch.h"
#include "error.h"

emm_status emm_addr_map_init(emm_addr_map *map, const emm_trace_info *trace, emm_error *err)
{
    uint32_t n = trace ? trace->narrays : 0;
    map->narrays = n;
    map->base = calloc(n ? n : 1, sizeof *map->base);
    map->size = calloc(n ? n : 1, sizeof *map->size);
    if (!map->base || !map->size) {
        emm_addr_map_free(map);
        return emm_fail(err, EMM_ERR_NOMEM, "model: out of memory");
    }
    for (uint32_t i = 0; i < n; i++)
        map->size[i] = trace->arrays[i].record_size;
    emm_status st = n ? emm_trace_place(trace, map->base, err) : EMM_OK;
    if (st != EMM_OK)
        emm_addr_map_free(map);
    return st;
}

void emm_addr_map_free(emm_addr_map *map)
{
    free(map->base);
    free(map->size);
    map->base = map->size = NULL;
}

emm_status emm_model_new(const emm_machine *m, const emm_strategy *s,
                         const emm_trace_info *trace, emm_model **out, emm_error *err)
{
    emm_model_share *sh = emm_model_share_new();
    if (!sh)
        return emm_fail(err, EMM_ERR_NOMEM, "model: out of memory");
    emm_status st = emm_model_create(m, s, trace, sh, out, err);
    emm_model_share_unref(sh);
    return st;
}

emm_status emm_model_create(const emm_machine *m, const emm_strategy *s,
                            const emm_trace_info *trace, emm_model_share *share,
                            emm_model **out, emm_error *err)
{
    emm_status st;
    char name[64];
    if ((st = emm_machine_validate(m, err)) != EMM_OK)
        return st;
    emm_strategy_format(s, name, sizeof name);
    if (s->kind == EMM_STRATEGY_DIRECT)
        st = emm_direct_model_new(&m->p, trace, out, err);
    else if (s->kind == EMM_STRATEGY_CACHE && s->layout == EMM_LAYOUT_ORIGINAL)
        st = emm_cache_model_new(&m->p, trace, out, err);
    else if (s->kind == EMM_STRATEGY_CACHE)
        st = emm_cache_layout_model_new(&m->p, s, trace, share, out, err);
    else if (s->kind == EMM_STRATEGY_EMM)
        st = emm_emm_model_new(&m->p, s, trace, share, out, err);
    else
        return emm_fail(err, EMM_ERR_UNSUPPORTED,
                        "strategy '%s': not implemented in this build (only 'direct' and 'cache')",
                        name);
    if (st == EMM_OK)
        (*out)->strategy = *s;
    return st;
}

void emm_model_run(emm_model *model, const emm_trace_record *recs, size_t n)
{
    model->ops->run(model, recs, n);
}

/* The model's counters so far. */
static void costs_so_far(const emm_model *model, emm_record_cost *c)
{
    if (model->ops->costs) {
        model->ops->costs(model, c);
        return;
    }
    emm_result r;
    emm_model_result(model, &r);
    memcpy(c->cycles, r.cycles, sizeof c->cycles);
    c->lookups = r.emm.lookups;
}

uint64_t emm_model_total(const emm_model *model)
{
    emm_record_cost c;
    costs_so_far(model, &c);
    uint64_t t = 0;
    for (int b = 0; b < EMM_BUCKET_COUNT; b++)
        t += c.cycles[b];
    return t;
}

/* One record at a time, each followed by a look at the counters: the
 * models have no batch-wide state, so the run is the same as in batches. */
void emm_model_run_costed(emm_model *model, const emm_trace_record *recs, size_t n,
                          emm_record_cost *cost)
{
    emm_record_cost prev, now;
    costs_so_far(model, &prev);
    for (size_t i = 0; i < n; i++) {
        model->ops->run(model, &recs[i], 1);
        costs_so_far(model, &now);
        for (int b = 0; b < EMM_BUCKET_COUNT; b++)
            cost[i].cycles[b] = now.cycles[b] - prev.cycles[b];
        cost[i].lookups = now.lookups - prev.lookups;
        prev = now;
    }
}

int emm_model_observe(emm_model *model, const emm_observer *obs, void *ctx)
{
    if (!model->ops->observe)
        return 0;
    model->ops->observe(model, obs, ctx);
    return 1;
}

int emm_model_stalls(emm_model *model, emm_stall_fn fn, void *ctx)
{
    if (!model->ops->stalls)
        return 0;
    model->ops->stalls(model, fn, ctx);
    return 1;
}

void emm_model_reset(emm_model *model)
{
    model->ops->reset(model);
}

void emm_model_result(const emm_model *model, emm_result *out)
{
    memset(out, 0, sizeof *out);
    model->ops->result(model, out);
    out->strategy = model->strategy;
}

void emm_model_free(emm_model *model)
{
    if (model)
        model->ops->destroy(model);
}

const char *emm_bucket_name(emm_bucket b)
{
    static const char *const names[EMM_BUCKET_COUNT] = {
        "local_access", "remote_access", "compute", "emm_instructions",
        "dma_issue", "dma_stall", "cache_hit", "cache_miss_stall",
    };
    return (unsigned)b < EMM_BUCKET_COUNT ? names[b] : "unknown";
}
