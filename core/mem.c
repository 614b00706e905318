/* mem.c — the huge-page hint of mem.h. */
#include "core/mem.h"

#include <stdint.h>
#include <sys/mman.h>

void *mem_huge(void *p, size_t n)
{
#ifdef MADV_HUGEPAGE
    const uintptr_t huge = (uintptr_t)2 << 20;
    uintptr_t a = ((uintptr_t)p + huge - 1) & ~(huge - 1), b = ((uintptr_t)p + n) & ~(huge - 1);
    if (p && b > a) (void)madvise((void *)a, b - a, MADV_HUGEPAGE); /* a hint: errors ignored */
#endif
    return p;
}

/* *pp resized to n elements of elem bytes by re (*cap = n), or -1 with *pp as it was. */
static int resize(void **p, size_t *cap, size_t n, size_t elem, void *(*re)(void *, size_t))
{
    if (elem && n > SIZE_MAX / elem) return -1;
    void *q = re(*p, n * elem);
    if (!q) return -1;
    *p = q;
    *cap = n;
    return 0;
}

static void *hinted_realloc(void *p, size_t n)
{
    return mem_realloc(p, n);
}

int mem_grow_slow(void *pp, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return 0;
    size_t nc = *cap ? *cap : 16;
    while (nc < need) {
        if (nc > SIZE_MAX / 2) return -1;
        nc *= 2;
    }
    return resize(pp, cap, nc, elem, hinted_realloc);
}

int mem_fit(void *pp, size_t *cap, size_t need, size_t elem)
{
    return need <= *cap ? 0 : resize(pp, cap, need, elem, realloc);
}
