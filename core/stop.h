/* stop.h — how a long loop sees a cancel: by the work it has done, not by how it is cut.
 *
 * A loop counts its work in units of about one elementary step (a pair of boxes compared, an
 * edge visited, an entry written) with stop_poll(m, units); the cancel flag is read once every
 * STOP_WORK units, so a worker stops within about STOP_WORK steps of work (tens of
 * microseconds) whether its items are large or small.  Each thread polls its own meter (a
 * worker's is padded to a cache line of its own); reading the flag is one relaxed load.
 */
#ifndef CELLAR_STOP_H
#define CELLAR_STOP_H

#include <stdatomic.h>
#include <stddef.h>

#define STOP_WORK 4096

typedef struct stop_meter {
    _Alignas(64) const atomic_int *flag; /* borrowed, may be NULL: never stops */
    size_t work;                         /* units since the flag was last read */
} stop_meter;

/* Non-zero when the flag is set (read when the meter's units reach STOP_WORK). */
static inline int stop_poll(stop_meter *m, size_t units)
{
    if (!m->flag || (m->work += units) < STOP_WORK) return 0;
    m->work = 0;
    return atomic_load_explicit(m->flag, memory_order_relaxed) != 0;
}

#endif
