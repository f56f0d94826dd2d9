/* The model runner (runner.h) on the thread pool of core/pool.h. */
#include "runner.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "model.h"
#include "pool.h"
#include "share.h"

struct emm_runner {
    emm_pool *pool;
    emm_model_share *share; /* layouts built once for all the models */
    emm_model **models; /* NULL entries: strategies that could not be built */
    emm_model **live;   /* the built ones, for the run */
    size_t n, nlive, cap;
    emm_model *costed;  /* the model that runs costed (emm_runner_costs), or NULL */
    emm_cost_fn cost_fn;
    void *cost_ctx;
    emm_record_cost *cost; /* RUNNER_COST_BATCH */
};

/* Records costed per call of the cost callback. */
#define RUNNER_COST_BATCH 4096u

emm_status emm_runner_new(const emm_threads *t, emm_runner **out, emm_error *err)
{
    return emm_runner_new_shared(t, NULL, out, err);
}

emm_status emm_runner_new_shared(const emm_threads *t, emm_model_share *share, emm_runner **out,
                                 emm_error *err)
{
    emm_runner *r = calloc(1, sizeof *r);
    if (!r)
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the model runner");
    if (share)
        emm_model_share_ref(share);
    r->share = share ? share : emm_model_share_new();
    if (!r->share) {
        free(r);
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the model runner");
    }
    /* No pool is no failure: the work then runs on the calling thread. */
    r->pool = emm_pool_new(t, 0);
    *out = r;
    return EMM_OK;
}

struct build_job {
    emm_model_share *share;
    const emm_machine *m;
    const emm_strategy *s;
    const emm_trace_info *info;
    emm_model **models;
    emm_error *errs;
};

static void build_one(void *ctx, size_t i)
{
    struct build_job *j = ctx;
    emm_error_clear(&j->errs[i]);
    if (emm_model_create(j->m, &j->s[i], j->info, j->share, &j->models[i], &j->errs[i]) != EMM_OK)
        j->models[i] = NULL;
}

emm_status emm_runner_add(emm_runner *r, const emm_machine *m, const emm_strategy *s, size_t n,
                          const emm_trace_info *info, emm_error *errs, emm_error *err)
{
    if (n == 0)
        return EMM_OK;
    if (r->n + n > r->cap) {
        size_t cap = r->cap ? r->cap : 8;
        while (cap < r->n + n)
            cap *= 2;
        emm_model **mm = realloc(r->models, cap * sizeof *mm);
        if (mm)
            r->models = mm;
        emm_model **ll = mm ? realloc(r->live, cap * sizeof *ll) : NULL;
        if (ll)
            r->live = ll;
        if (!mm || !ll)
            return emm_fail(err, EMM_ERR_NOMEM, "out of memory for %zu models", r->n + n);
        r->cap = cap;
    }
    emm_error *e = errs ? errs : calloc(n, sizeof *e);
    if (!e)
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for %zu models", n);
    struct build_job job = {r->share, m, s, info, r->models + r->n, e};
    emm_pool_for(r->pool, n, build_one, &job);
    emm_status st = EMM_OK;
    for (size_t i = 0; i < n && st == EMM_OK; i++)
        if (!job.models[i] && (e[i].status == EMM_ERR_NOMEM || !errs)) {
            st = e[i].status;
            if (err)
                *err = e[i];
        }
    if (st != EMM_OK) {
        for (size_t i = 0; i < n; i++)
            emm_model_free(job.models[i]);
    } else {
        for (size_t i = 0; i < n; i++)
            if (job.models[i])
                r->live[r->nlive++] = job.models[i];
        r->n += n;
    }
    if (!errs)
        free(e);
    return st;
}

size_t emm_runner_count(const emm_runner *r)
{
    return r->n;
}

emm_model *emm_runner_model(const emm_runner *r, size_t i)
{
    return i < r->n ? r->models[i] : NULL;
}

void emm_runner_retire(emm_runner *r, size_t i)
{
    if (i >= r->n || !r->models[i])
        return;
    for (size_t k = 0; k < r->nlive; k++)
        if (r->live[k] == r->models[i]) {
            memmove(r->live + k, r->live + k + 1, (r->nlive - k - 1) * sizeof *r->live);
            r->nlive--;
            return;
        }
}

emm_status emm_runner_costs(emm_runner *r, size_t i, emm_cost_fn fn, void *ctx, emm_error *err)
{
    if (fn && !r->cost && !(r->cost = malloc(RUNNER_COST_BATCH * sizeof *r->cost)))
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the records' costs");
    r->costed = fn ? emm_runner_model(r, i) : NULL;
    r->cost_fn = fn;
    r->cost_ctx = ctx;
    return EMM_OK;
}

struct run_job {
    const emm_runner *r;
    const emm_trace_record *recs;
    size_t n;
};

static void run_one(void *ctx, size_t i)
{
    const struct run_job *j = ctx;
    const emm_runner *r = j->r;
    emm_model *m = r->live[i];
    if (m != r->costed) {
        emm_model_run(m, j->recs, j->n);
        return;
    }
    for (size_t k = 0; k < j->n; k += RUNNER_COST_BATCH) {
        size_t n = j->n - k < RUNNER_COST_BATCH ? j->n - k : RUNNER_COST_BATCH;
        emm_model_run_costed(m, j->recs + k, n, r->cost);
        r->cost_fn(r->cost_ctx, j->recs + k, r->cost, n);
    }
}

void emm_runner_run(emm_runner *r, const emm_trace_record *recs, size_t n)
{
    if (n == 0 || r->nlive == 0)
        return;
    struct run_job job = {r, recs, n};
    emm_pool_for(r->pool, r->nlive, run_one, &job);
}

struct bounded_job {
    const emm_runner *r;
    const size_t *idx;
    const emm_trace_record *recs;
    size_t n, chunk;
    uint64_t bound;
    size_t *ran;
};

static void run_bounded_one(void *ctx, size_t k)
{
    const struct bounded_job *j = ctx;
    emm_model *m = j->r->models[j->idx[k]];
    size_t done = 0;
    while (done < j->n) {
        size_t len = j->n - done < j->chunk ? j->n - done : j->chunk;
        emm_model_run(m, j->recs + done, len);
        done += len;
        if (done < j->n && emm_model_total(m) > j->bound)
            break;
    }
    j->ran[k] = done;
}

void emm_runner_run_bounded(emm_runner *r, const size_t *idx, size_t k,
                            const emm_trace_record *recs, size_t n, size_t chunk, uint64_t bound,
                            size_t *ran)
{
    struct bounded_job job = {r, idx, recs, n, chunk ? chunk : n, bound, ran};
    emm_pool_for(r->pool, k, run_bounded_one, &job);
}

void emm_runner_free(emm_runner *r)
{
    if (!r)
        return;
    emm_pool_free(r->pool);
    for (size_t i = 0; i < r->n; i++)
        emm_model_free(r->models[i]);
    emm_model_share_unref(r->share);
    free(r->cost);
    free(r->models);
    free(r->live);
    free(r);
}
