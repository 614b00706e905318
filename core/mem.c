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
