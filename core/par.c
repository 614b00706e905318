/* par.c — see par.h.  No globals: each call has its own counter and threads. */
#include "core/par.h"

#include <pthread.h>
#include <stdatomic.h>
#include <unistd.h>

#define PAR_MAX_THREADS 64

typedef struct par_job {
    par_fn fn;
    void *ctx;
    size_t n;
    atomic_size_t next; /* next item to hand out */
    atomic_size_t done; /* items finished */
    par_tick tick;      /* may be NULL: told by the calling thread how far the loop is */
    void *tctx;
} par_job;

typedef struct par_worker {
    par_job *job;
    int id;
} par_worker;

static void par_drain(par_job *job, int id)
{
    for (;;) {
        size_t i = atomic_fetch_add_explicit(&job->next, 1, memory_order_relaxed);
        if (i >= job->n) return;
        job->fn(job->ctx, i, id);
        size_t done = atomic_fetch_add_explicit(&job->done, 1, memory_order_relaxed) + 1;
        if (id == 0 && job->tick) job->tick(job->tctx, (double)done / (double)job->n);
    }
}

static void *par_main(void *arg)
{
    par_worker *w = arg;
    par_drain(w->job, w->id);
    return NULL;
}

int par_ncpu(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (n > PAR_MAX_THREADS ? PAR_MAX_THREADS : (int)n);
}

void par_for(int threads, size_t n, par_fn fn, void *ctx)
{
    par_for_ex(threads, n, fn, ctx, NULL, NULL);
}

void par_for_ex(int threads, size_t n, par_fn fn, void *ctx, par_tick tick, void *tctx)
{
    par_job job = {.fn = fn, .ctx = ctx, .n = n, .tick = tick, .tctx = tctx};
    pthread_t tid[PAR_MAX_THREADS];
    par_worker w[PAR_MAX_THREADS];
    int started = 0;

    atomic_init(&job.next, 0);
    atomic_init(&job.done, 0);
    if (threads > PAR_MAX_THREADS) threads = PAR_MAX_THREADS;
    if ((size_t)threads > n) threads = (int)n;
    for (int t = 1; t < threads; t++) {
        w[started].job = &job;
        w[started].id = t;
        if (pthread_create(&tid[started], NULL, par_main, &w[started]) != 0) break;
        started++;
    }
    par_drain(&job, 0);
    for (int t = 0; t < started; t++) pthread_join(tid[t], NULL);
}
