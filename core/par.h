/* par.h — a parallel for-loop on a small pool of pthreads.
 *
 * par_for() starts (threads - 1) threads, runs items 0..n-1 on them and on the calling
 * thread, handing out items one at a time from an atomic counter (items are buckets of
 * uneven cost), and joins the threads before returning.  fn gets the worker number
 * (0..threads-1) so it can write into per-worker buffers without locks.  If a thread
 * cannot be started, the remaining workers (at least the caller) do all the work.
 */
#ifndef CELLAR_PAR_H
#define CELLAR_PAR_H

#include <stddef.h>

typedef void (*par_fn)(void *ctx, size_t item, int worker);

void par_for(int threads, size_t n, par_fn fn, void *ctx);

/* The same, and after each item the calling thread finishes, tick(tctx, f): f the fraction of
 * the items finished by all the threads (so a loop's progress can be told from the thread
 * that owns the progress callback, never from the others). */
typedef void (*par_tick)(void *tctx, double f);
void par_for_ex(int threads, size_t n, par_fn fn, void *ctx, par_tick tick, void *tctx);

/* Number of online CPUs (at least 1). */
int par_ncpu(void);

#endif
