/* util.h — the small tools every core file shares, each written once.
 *
 *   growable array    mem_grow() of core/mem.h (room doubled, the common case inline);
 *                     mem_fit() there for scratch sized exactly
 *   error message     util_seterr(): prints into the caller's buffer, returns the code
 *   union-find        uf_find() (path halving), uf_union() (the smaller root wins, so a root
 *                     is the smallest element of its set: numberings by root are stable)
 *   u32 order         u32_cmp() for qsort and bsearch
 *   radix sorts       core/sort.h (keys, keys carrying a payload, grid points)
 *   box index         core/box.h
 */
#ifndef CELLAR_UTIL_H
#define CELLAR_UTIL_H

#include <stddef.h>
#include <stdint.h>

#include "core/mem.h"

/* Writes the message (printf's format) into err[errlen] when err is not NULL and errlen > 0;
 * returns code, so that an error path reads `return util_seterr(err, errlen, -1, ...)`. */
int util_seterr(char *err, size_t errlen, int code, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* The root of x's set in the forest p (p[r] == r at a root); halves the path on the way. */
static inline uint32_t uf_find(uint32_t *p, uint32_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

/* Joins the sets of a and b under the smaller of their roots. */
static inline void uf_union(uint32_t *p, uint32_t a, uint32_t b)
{
    a = uf_find(p, a);
    b = uf_find(p, b);
    if (a < b)
        p[b] = a;
    else if (b < a)
        p[a] = b;
}

/* qsort/bsearch order of uint32_t values. */
int u32_cmp(const void *a, const void *b);

#endif
