/* The model runner (runner.h) on the thread pool of core/pool.h, and its
 * pipeline (emm_runner_pipeline): workers of its own that take the queued
 * batches model by model. */
#include "runner.h"

#include <pthread.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "model.h"
#include "pool.h"
#include "share.h"

/* A batch queued in the pipeline: its own copy of the records, and how
 * many of the models that were live when it was queued have yet to run
 * it. */
struct pipe_batch {
    emm_trace_record *recs;
    size_t n, cap, left;
};

/* The pipeline. Batches [head, tail) (sequence numbers; slot seq % PIPE_SLOTS)
 * are queued; live model k has run every batch before cursor[k], and runs
 * batch cursor[k] when busy[k]. A batch leaves the queue when every model
 * has run it, oldest first. Retiring and adding models, and reading one,
 * happen only with the queue empty (pipe_sync), so the live list and the
 * cursors never change under a worker. */
#define PIPE_SLOTS 64u
struct pipe {
    pthread_mutex_t mu;
    pthread_cond_t work, done;
    emm_threads t;
    pthread_t *tids;
    unsigned nthreads;
    struct pipe_batch q[PIPE_SLOTS];
    uint64_t head, tail;
    size_t queued;     /* records in the queue */
    size_t held;       /* records the slots' buffers hold room for */
    uint64_t *cursor;  /* per live slot */
    bool *busy;        /* per live slot */
    size_t rr;         /* where the next worker starts looking */
    bool stop;
};

struct emm_runner {
    emm_pool *pool;
    struct pipe *pipe;  /* NULL: batches run before emm_runner_run returns */
    emm_threads t;      /* the threads it may use */
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

/* At most this many records queued in the pipeline (40 bytes each: 2.5
 * MiB): a producer faster than the models waits for them. A queue that
 * fits the caches keeps the records there from the copy to the models'
 * reads; on the 100,000-face smoothing run under sancov 2^16 took as long
 * as 2^19 (0.99x, 16 alternating pairs twice) with 36 MB less peak memory,
 * 2^15 as long again, 2^14 1.08x (the producer waits). */
#define PIPE_MAX_RECORDS (1u << 16)

static void run_model(const emm_runner *r, emm_model *m, const emm_trace_record *recs, size_t n);

/* Waits until every queued batch has been run by every live model. */
static void pipe_sync(struct pipe *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->mu);
    while (p->head < p->tail)
        pthread_cond_wait(&p->done, &p->mu);
    pthread_mutex_unlock(&p->mu);
}

void emm_runner_sync(emm_runner *r)
{
    if (r)
        pipe_sync(r->pipe);
}

/* A worker: runs the next batch of a live model that has one and that no
 * other worker is running, round robin over the models, until stopped. */
static void *pipe_worker(void *arg)
{
    emm_runner *r = arg;
    struct pipe *p = r->pipe;
    if (p->t.on_start)
        p->t.on_start(p->t.ctx);
    pthread_mutex_lock(&p->mu);
    for (;;) {
        size_t k = SIZE_MAX;
        for (size_t j = 0; j < r->nlive && k == SIZE_MAX; j++) {
            size_t x = (p->rr + j) % r->nlive;
            if (!p->busy[x] && p->cursor[x] < p->tail)
                k = x;
        }
        if (k == SIZE_MAX) {
            if (p->stop)
                break;
            pthread_cond_wait(&p->work, &p->mu);
            continue;
        }
        p->rr = k + 1;
        p->busy[k] = true;
        struct pipe_batch *b = &p->q[p->cursor[k] % PIPE_SLOTS];
        emm_model *m = r->live[k];
        pthread_mutex_unlock(&p->mu);
        run_model(r, m, b->recs, b->n);
        pthread_mutex_lock(&p->mu);
        p->busy[k] = false;
        p->cursor[k]++;
        if (--b->left == 0) {
            bool freed = false;
            while (p->head < p->tail && p->q[p->head % PIPE_SLOTS].left == 0) {
                struct pipe_batch *h = &p->q[p->head % PIPE_SLOTS];
                p->queued -= h->n;
                /* The buffers keep their room for the next batches, up to
                 * twice what may be queued. */
                if (p->held > 2 * (size_t)PIPE_MAX_RECORDS) {
                    p->held -= h->cap;
                    free(h->recs);
                    h->recs = NULL;
                    h->cap = 0;
                }
                p->head++;
                freed = true;
            }
            if (freed)
                pthread_cond_broadcast(&p->done);
        }
    }
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

/* Queues a copy of recs[0..n) for every live model; waits while the queue
 * is full. Returns false (nothing queued) when memory runs out: the caller
 * then runs the batch itself. */
static bool pipe_push(emm_runner *r, const emm_trace_record *recs, size_t n)
{
    struct pipe *p = r->pipe;
    pthread_mutex_lock(&p->mu);
    while (p->head < p->tail &&
           (p->tail - p->head == PIPE_SLOTS || p->queued + n > PIPE_MAX_RECORDS))
        pthread_cond_wait(&p->done, &p->mu);
    struct pipe_batch *b = &p->q[p->tail % PIPE_SLOTS];
    pthread_mutex_unlock(&p->mu);
    /* The slot is free (no worker reads it until it is queued) and this is
     * the one thread that queues. */
    if (b->cap < n) {
        emm_trace_record *x = realloc(b->recs, n * sizeof *x);
        if (!x)
            return false;
        pthread_mutex_lock(&p->mu);
        p->held += n - b->cap;
        pthread_mutex_unlock(&p->mu);
        b->recs = x;
        b->cap = n;
    }
    memcpy(b->recs, recs, n * sizeof *recs);
    b->n = n;
    b->left = r->nlive;
    pthread_mutex_lock(&p->mu);
    p->queued += n;
    p->tail++;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->mu);
    return true;
}

static void pipe_free(emm_runner *r)
{
    struct pipe *p = r->pipe;
    if (!p)
        return;
    pipe_sync(p);
    pthread_mutex_lock(&p->mu);
    p->stop = true;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->mu);
    for (unsigned i = 0; i < p->nthreads; i++)
        pthread_join(p->tids[i], NULL);
    for (unsigned i = 0; i < PIPE_SLOTS; i++)
        free(p->q[i].recs);
    pthread_mutex_destroy(&p->mu);
    pthread_cond_destroy(&p->work);
    pthread_cond_destroy(&p->done);
    free(p->tids);
    free(p->cursor);
    free(p->busy);
    free(p);
    r->pipe = NULL;
}

/* The pipeline's lock, held while the live list changes (a worker reads
 * it under the lock); nothing without a pipeline. */
static void pipe_hold(const emm_runner *r)
{
    if (r->pipe)
        pthread_mutex_lock(&r->pipe->mu);
}

static void pipe_release(const emm_runner *r)
{
    if (r->pipe)
        pthread_mutex_unlock(&r->pipe->mu);
}

/* The cursors and flags sized for r->cap models, with the lock held (or
 * before the workers start). */
static bool pipe_size(emm_runner *r)
{
    struct pipe *p = r->pipe;
    if (!p)
        return true;
    size_t cap = r->cap ? r->cap : 1;
    uint64_t *c = realloc(p->cursor, cap * sizeof *c);
    if (c)
        p->cursor = c;
    bool *b = c ? realloc(p->busy, cap * sizeof *b) : NULL;
    if (b)
        p->busy = b;
    return c && b;
}

/* With the lock held and every live model through every batch (after
 * pipe_sync, or before the workers start): the live list may have
 * changed, every cursor starts at the queue's end. */
static void pipe_reset(emm_runner *r)
{
    struct pipe *p = r->pipe;
    if (!p)
        return;
    for (size_t k = 0; k < r->cap; k++) {
        p->cursor[k] = p->tail;
        p->busy[k] = false;
    }
}

emm_status emm_runner_pipeline(emm_runner *r, emm_error *err)
{
    if (r->pipe)
        return EMM_OK;
    unsigned jobs = emm_threads_jobs(&r->t);
    if (jobs < 2)
        return EMM_OK;
    struct pipe *p = calloc(1, sizeof *p);
    pthread_t *tids = calloc(jobs, sizeof *tids);
    if (!p || !tids) {
        free(p);
        free(tids);
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the runner's pipeline");
    }
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->work, NULL);
    pthread_cond_init(&p->done, NULL);
    p->t = r->t;
    p->tids = tids;
    r->pipe = p;
    if (!pipe_size(r)) { /* no worker yet: no lock needed */
        pipe_free(r);
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the runner's pipeline");
    }
    pipe_reset(r);
    while (p->nthreads < jobs && emm_thread_start(&p->tids[p->nthreads], pipe_worker, r) == 0)
        p->nthreads++;
    if (p->nthreads == 0)
        pipe_free(r); /* no thread: the batches run on the caller, as before */
    return EMM_OK;
}

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
    if (t)
        r->t = *t;
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
    pipe_sync(r->pipe);
    if (r->n + n > r->cap) {
        size_t cap = r->cap ? r->cap : 8;
        while (cap < r->n + n)
            cap *= 2;
        pipe_hold(r);
        emm_model **mm = realloc(r->models, cap * sizeof *mm);
        if (mm)
            r->models = mm;
        emm_model **ll = mm ? realloc(r->live, cap * sizeof *ll) : NULL;
        if (ll)
            r->live = ll;
        /* The cursors must cover every slot r->cap counts: without room
         * for them the runner keeps its old capacity. */
        size_t old = r->cap;
        if (mm && ll)
            r->cap = cap;
        bool fit = mm && ll && pipe_size(r);
        if (!fit)
            r->cap = old;
        pipe_release(r);
        if (!fit)
            return emm_fail(err, EMM_ERR_NOMEM, "out of memory for %zu models", r->n + n);
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
        pipe_hold(r);
        for (size_t i = 0; i < n; i++)
            if (job.models[i])
                r->live[r->nlive++] = job.models[i];
        r->n += n;
        pipe_reset(r);
        pipe_release(r);
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
    pipe_sync(r->pipe);
    return i < r->n ? r->models[i] : NULL;
}

void emm_runner_retire(emm_runner *r, size_t i)
{
    if (i >= r->n || !r->models[i])
        return;
    pipe_sync(r->pipe);
    pipe_hold(r);
    for (size_t k = 0; k < r->nlive; k++)
        if (r->live[k] == r->models[i]) {
            memmove(r->live + k, r->live + k + 1, (r->nlive - k - 1) * sizeof *r->live);
            r->nlive--;
            pipe_reset(r);
            break;
        }
    pipe_release(r);
}

emm_status emm_runner_costs(emm_runner *r, size_t i, emm_cost_fn fn, void *ctx, emm_error *err)
{
    pipe_sync(r->pipe);
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

/* Model m over recs[0..n): costed when it is the costed model. */
static void run_model(const emm_runner *r, emm_model *m, const emm_trace_record *recs, size_t n)
{
    if (m != r->costed) {
        emm_model_run(m, recs, n);
        return;
    }
    for (size_t k = 0; k < n; k += RUNNER_COST_BATCH) {
        size_t c = n - k < RUNNER_COST_BATCH ? n - k : RUNNER_COST_BATCH;
        emm_model_run_costed(m, recs + k, c, r->cost);
        r->cost_fn(r->cost_ctx, recs + k, r->cost, c);
    }
}

static void run_one(void *ctx, size_t i)
{
    const struct run_job *j = ctx;
    run_model(j->r, j->r->live[i], j->recs, j->n);
}

void emm_runner_run(emm_runner *r, const emm_trace_record *recs, size_t n)
{
    if (n == 0 || r->nlive == 0)
        return;
    if (r->pipe && pipe_push(r, recs, n))
        return;
    pipe_sync(r->pipe);
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
    pipe_sync(r->pipe);
    struct bounded_job job = {r, idx, recs, n, chunk ? chunk : n, bound, ran};
    emm_pool_for(r->pool, k, run_bounded_one, &job);
}

void emm_runner_free(emm_runner *r)
{
    if (!r)
        return;
    pipe_free(r);
    emm_pool_free(r->pool);
    for (size_t i = 0; i < r->n; i++)
        emm_model_free(r->models[i]);
    emm_model_share_unref(r->share);
    free(r->cost);
    free(r->models);
    free(r->live);
    free(r);
}
