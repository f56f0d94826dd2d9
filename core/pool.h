/* Internal: the one place the library starts threads (docs/architecture.md,
 * "Threads"). A pool of helper threads, started with every signal blocked
 * and calling the caller's on_start hook first (emm_threads), runs
 * fn(ctx, i) for i in [0, n) on the helpers and the calling thread, each i
 * once, in no fixed order. Everything that runs work in parallel — the model
 * runner, the profile's two halves — goes through it. */
#ifndef EMM_INTERNAL_POOL_H
#define EMM_INTERNAL_POOL_H

#include <pthread.h>
#include <stddef.h>

#include "emm/common.h"

/* Starts a thread of emm's: the program's signals must never land on it, so
 * every signal is blocked while it is created and it inherits a full mask.
 * Returns pthread_create's status; the caller joins it. Every thread the
 * library (and emm-session) starts comes from here. */
int emm_thread_start(pthread_t *tid, void *(*fn)(void *), void *arg);

/* How much lower a thread of emm's that works beside the program is
 * scheduled (a nice value added to its own): every thread a session starts
 * (runtime/session.c, beside_start). The program's thread, which produces
 * what they consume, then comes first when they compete for a core,
 * instead of waiting its turn among them; what they compute does not
 * depend on when it runs. */
#define EMM_BESIDE_NICE 5

/* Lowers the calling thread's priority by EMM_BESIDE_NICE (up to nice 19);
 * nothing when the system refuses. Only the calling thread changes. */
void emm_thread_beside(void);

typedef struct emm_pool emm_pool;

/* The threads `t` asks for (NULL: the online CPUs), at least 1. */
unsigned emm_threads_jobs(const emm_threads *t);

/* A pool of up to min(jobs, max_jobs) - 1 helpers (max_jobs 0: no limit),
 * started on first use. NULL when memory runs out: the caller then runs its
 * work inline (emm_pool_for accepts a NULL pool and does just that). */
emm_pool *emm_pool_new(const emm_threads *t, unsigned max_jobs);

/* Threads that take part in emm_pool_for, the caller included (1 for a NULL
 * pool, or when no helper could be started). */
unsigned emm_pool_jobs(emm_pool *p);

/* Calls fn(ctx, i) once for every i in [0, n), spread over the helpers and
 * the calling thread, and returns when all are done. Not reentrant: one
 * emm_pool_for at a time per pool. */
void emm_pool_for(emm_pool *p, size_t n, void (*fn)(void *ctx, size_t i), void *ctx);

/* Stops and joins the helpers. NULL is allowed. */
void emm_pool_free(emm_pool *p);

/* One piece of work beside the caller's: fn(ctx) on a thread of its own,
 * started as the pool's helpers are (signals blocked, on_start first).
 * Returns NULL — and has run fn(ctx) on the calling thread before
 * returning — when `t` allows one thread only, or no thread can be had:
 * either way the work is done once emm_task_join returns. */
typedef struct emm_task emm_task;
emm_task *emm_task_start(const emm_threads *t, void (*fn)(void *ctx), void *ctx);

/* Waits for the task's work and frees it. NULL is allowed. */
void emm_task_join(emm_task *task);

#endif
