/* The thread pool (pool.h). Helpers wait on a condition variable for a
 * round of work; in a round every thread, the caller included, takes the
 * next index from a shared counter until none is left, so long and short
 * items balance themselves. The caller returns when every helper has
 * finished the round. */
#include "pool.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdbool.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

struct emm_pool {
    pthread_mutex_t mu;
    pthread_cond_t work, done;
    emm_threads t;
    unsigned want;       /* helpers wanted */
    unsigned started;    /* helpers running */
    bool tried;          /* the helpers were started (or could not be) */
    pthread_t *tids;

    /* the round */
    unsigned long round; /* bumped for each emm_pool_for */
    void (*fn)(void *ctx, size_t i);
    void *ctx;
    size_t n, next;
    unsigned busy;       /* helpers still in the round */
    bool stop;
};

unsigned emm_threads_jobs(const emm_threads *t)
{
    if (t && t->jobs)
        return t->jobs;
    long c = sysconf(_SC_NPROCESSORS_ONLN);
    return c > 0 ? (unsigned)c : 1;
}

emm_pool *emm_pool_new(const emm_threads *t, unsigned max_jobs)
{
    emm_pool *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    unsigned jobs = emm_threads_jobs(t);
    if (max_jobs && jobs > max_jobs)
        jobs = max_jobs;
    p->want = jobs - 1;
    if (t)
        p->t = *t;
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->work, NULL);
    pthread_cond_init(&p->done, NULL);
    return p;
}

/* Takes indices of the current round until none is left. Called with the
 * lock held; returns with it held. */
static void take(emm_pool *p)
{
    while (p->next < p->n) {
        size_t i = p->next++;
        pthread_mutex_unlock(&p->mu);
        p->fn(p->ctx, i);
        pthread_mutex_lock(&p->mu);
    }
}

static void *helper(void *arg)
{
    emm_pool *p = arg;
    if (p->t.on_start)
        p->t.on_start(p->t.ctx);
    unsigned long seen = 0;
    pthread_mutex_lock(&p->mu);
    for (;;) {
        while (p->round == seen && !p->stop)
            pthread_cond_wait(&p->work, &p->mu);
        if (p->stop)
            break;
        seen = p->round;
        take(p);
        if (--p->busy == 0)
            pthread_cond_signal(&p->done);
    }
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

int emm_thread_start(pthread_t *tid, void *(*fn)(void *), void *arg)
{
    sigset_t all, old;
    sigfillset(&all);
    pthread_sigmask(SIG_SETMASK, &all, &old);
    int e = pthread_create(tid, NULL, fn, arg);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    return e;
}

void emm_thread_beside(void)
{
    int saved = errno;
    id_t tid = (id_t)syscall(SYS_gettid);
    errno = 0;
    int now = getpriority(PRIO_PROCESS, tid);
    if (errno == 0) {
        int want = now + EMM_BESIDE_NICE > 19 ? 19 : now + EMM_BESIDE_NICE;
        if (want > now)
            (void)setpriority(PRIO_PROCESS, tid, want);
    }
    errno = saved;
}

/* Starts the helpers, once. */
static void start(emm_pool *p)
{
    p->tried = true;
    if (p->want == 0)
        return;
    p->tids = calloc(p->want, sizeof *p->tids);
    if (!p->tids)
        return;
    while (p->started < p->want && emm_thread_start(&p->tids[p->started], helper, p) == 0)
        p->started++;
}

unsigned emm_pool_jobs(emm_pool *p)
{
    if (!p)
        return 1;
    if (!p->tried)
        start(p);
    return p->started + 1;
}

void emm_pool_for(emm_pool *p, size_t n, void (*fn)(void *ctx, size_t i), void *ctx)
{
    if (n == 0)
        return;
    if (!p || n == 1 || emm_pool_jobs(p) == 1) {
        for (size_t i = 0; i < n; i++)
            fn(ctx, i);
        return;
    }
    pthread_mutex_lock(&p->mu);
    p->fn = fn;
    p->ctx = ctx;
    p->n = n;
    p->next = 0;
    p->busy = p->started;
    p->round++;
    pthread_cond_broadcast(&p->work);
    take(p);
    while (p->busy > 0)
        pthread_cond_wait(&p->done, &p->mu);
    pthread_mutex_unlock(&p->mu);
}

struct emm_task {
    pthread_t tid;
    emm_threads t;
    void (*fn)(void *ctx);
    void *ctx;
};

static void *task_main(void *arg)
{
    emm_task *k = arg;
    if (k->t.on_start)
        k->t.on_start(k->t.ctx);
    k->fn(k->ctx);
    return NULL;
}

emm_task *emm_task_start(const emm_threads *t, void (*fn)(void *ctx), void *ctx)
{
    emm_task *k = emm_threads_jobs(t) > 1 ? calloc(1, sizeof *k) : NULL;
    if (k) {
        if (t)
            k->t = *t;
        k->fn = fn;
        k->ctx = ctx;
        if (emm_thread_start(&k->tid, task_main, k) == 0)
            return k;
        free(k);
    }
    fn(ctx);
    return NULL;
}

void emm_task_join(emm_task *task)
{
    if (!task)
        return;
    pthread_join(task->tid, NULL);
    free(task);
}

void emm_pool_free(emm_pool *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&p->mu);
    p->stop = true;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->mu);
    for (unsigned i = 0; i < p->started; i++)
        pthread_join(p->tids[i], NULL);
    pthread_cond_destroy(&p->work);
    pthread_cond_destroy(&p->done);
    pthread_mutex_destroy(&p->mu);
    free(p->tids);
    free(p);
}
