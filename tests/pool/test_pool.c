/* The thread pool (core/pool.c), the one place the library starts threads:
 * every index runs once; work that runs on a helper runs after the helper
 * called the start hook, with every signal blocked; one job runs inline;
 * rounds follow one another on the same helpers. */
#include <pthread.h>
#include <signal.h>
#include <string.h>

#include "check.h"
#include "pool.h"

static _Thread_local int marked;
static pthread_t caller;
static int hooks;

static void hook(void *ctx)
{
    CHECK(ctx == &hooks);
    marked = 1;
    __atomic_add_fetch(&hooks, 1, __ATOMIC_RELAXED);
}

struct job {
    int runs[1000];
    int unmarked, unblocked, off_caller;
};

static void work(void *ctx, size_t i)
{
    struct job *j = ctx;
    __atomic_add_fetch(&j->runs[i], 1, __ATOMIC_RELAXED);
    if (pthread_equal(pthread_self(), caller))
        return;
    __atomic_add_fetch(&j->off_caller, 1, __ATOMIC_RELAXED);
    if (!marked)
        __atomic_add_fetch(&j->unmarked, 1, __ATOMIC_RELAXED);
    sigset_t now;
    pthread_sigmask(SIG_SETMASK, NULL, &now);
    if (!sigismember(&now, SIGTERM) || !sigismember(&now, SIGCHLD))
        __atomic_add_fetch(&j->unblocked, 1, __ATOMIC_RELAXED);
    for (volatile int k = 0; k < 2000; k++) /* long enough for both threads to take part */
        ;
}

int main(void)
{
    static struct job j;
    caller = pthread_self();
    emm_threads t = {3, hook, &hooks};
    emm_pool *p = emm_pool_new(&t, 0);
    REQUIRE(p);
    CHECK(emm_pool_jobs(p) == 3);
    for (int round = 0; round < 20; round++)
        emm_pool_for(p, 1000, work, &j);
    for (int i = 0; i < 1000; i++)
        CHECKF(j.runs[i] == 20, "index %d ran %d times", i, j.runs[i]);
    CHECK(hooks == 2);
    CHECK(j.unmarked == 0 && j.unblocked == 0);
    CHECKF(j.off_caller > 0, "no work ran on a helper");
    emm_pool_free(p);

    /* One job, or a limit of one: all on the calling thread. */
    memset(&j, 0, sizeof j);
    emm_threads one = {1, hook, &hooks};
    p = emm_pool_new(&one, 0);
    CHECK(emm_pool_jobs(p) == 1);
    emm_pool_for(p, 100, work, &j);
    CHECK(j.off_caller == 0 && j.runs[99] == 1);
    emm_pool_free(p);
    p = emm_pool_new(&t, 1);
    CHECK(emm_pool_jobs(p) == 1);
    emm_pool_free(p);
    /* A NULL pool runs inline too. */
    emm_pool_for(NULL, 10, work, &j);
    CHECK(j.runs[9] == 2 && j.off_caller == 0);
    return check_done();
}
