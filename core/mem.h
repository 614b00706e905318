/* mem.h — malloc, calloc and realloc for the large arrays of the 3D pipeline and its check.
 *
 * The same allocations (released with free()), with one hint: a block of MEM_HUGE_MIN bytes or
 * more is advised to the kernel as fit for transparent huge pages (madvise MADV_HUGEPAGE on the
 * 2 MiB-aligned part of it).  Arrays of hundreds of megabytes are then touched for the first
 * time in 2 MiB pages instead of 4 KiB ones: at two solids of a million triangles the run takes
 * 300 000 page faults fewer (a fifth of its time went to them).  Where the kernel has no
 * transparent huge pages, or they are off, the hint does nothing; nothing depends on it.
 */
#ifndef CELLAR_MEM_H
#define CELLAR_MEM_H

#include <stddef.h>
#include <stdlib.h>

#define MEM_HUGE_MIN ((size_t)4 << 20)

/* p, after the hint for its n bytes (p may be NULL: returned as it is). */
void *mem_huge(void *p, size_t n);

static inline void *mem_malloc(size_t n)
{
    return n >= MEM_HUGE_MIN ? mem_huge(malloc(n), n) : malloc(n);
}

static inline void *mem_calloc(size_t k, size_t size)
{
    size_t n = k * size; /* calloc itself refuses an overflow; the hint is then not given */
    return n >= MEM_HUGE_MIN && size && n / size == k ? mem_huge(calloc(k, size), n)
                                                      : calloc(k, size);
}

static inline void *mem_realloc(void *p, size_t n)
{
    return n >= MEM_HUGE_MIN ? mem_huge(realloc(p, n), n) : realloc(p, n);
}

/* The growable array *pp (the address of a pointer to *cap elements of elem bytes, or to NULL
 * with *cap 0) made to hold need elements, its room doubled as often as that takes (from 16):
 * 0, or -1 out of memory or past what a size_t counts (*pp and *cap then as they were).  The
 * common case, room enough, is inline. */
int mem_grow_slow(void *pp, size_t *cap, size_t need, size_t elem);
static inline int mem_grow(void *pp, size_t *cap, size_t need, size_t elem)
{
    return need <= *cap ? 0 : mem_grow_slow(pp, cap, need, elem);
}

/* The same array made to hold exactly need elements when it holds fewer (plain realloc, no
 * hint, no doubling): for scratch kept between calls whose sizes come in few steps, where a
 * large one-shot use must hold no more than it needs (doubling would add to the peak).  0, or
 * -1 out of memory or past what a size_t counts (*pp and *cap then as they were). */
int mem_fit(void *pp, size_t *cap, size_t need, size_t elem);

#endif
