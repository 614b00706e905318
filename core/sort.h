/* sort.h — LSD radix sorts for the big arrays of the pipeline (keys, grid points).
 * Each allocates its own scratch buffer and returns 0, or -1 when out of memory (the array
 * is then left unsorted but intact).  Passes whose digit is the same for every key are
 * skipped, so keys that use few bits cost few passes. */
#ifndef CELLAR_SORT_H
#define CELLAR_SORT_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "core/num.h"

int sort_u64(uint64_t *a, size_t n);
/* By the high 32 bits only, stable (the low bits, an index, keep their order among equals). */
int sort_u64_hi32(uint64_t *a, size_t n);
/* A key and the value it carries (an index), sorted by key; stable: equal keys keep their
 * order. */
typedef struct kv {
    uint64_t k;
    uint32_t v;
} kv;
int sort_kv(kv *a, size_t n);
/* Lexicographic (x, then y); coordinates must satisfy |c| < 2^62. */
int sort_ipt(ipt *a, size_t n);
/* The same, reading *stop (may be NULL) before each of its passes: -2 once it is set (a is then
 * left in some order). */
int sort_ipt_stop(ipt *a, size_t n, const atomic_int *stop);
/* By the grid point xyz + 3 a[i].v (|coordinates| < 2^40), lexicographic (x, then y, then z):
 * an LSD pass of sort_kv per coordinate, z first; stable.  The keys a[i].k are overwritten. */
int sort_kv_xyz(kv *a, size_t n, const int64_t *xyz);

/* Parallel arrays key[n] and val[n] sorted together by (key, then val): LSD radix on bytes, the
 * values' 4 first, then the keys' 8, each pass stable and skipped when its byte is the same
 * everywhere (arr2's edges with their tags).  0, or -1 out of memory (left as they were). */
int sort_u64_u32(uint64_t *key, uint32_t *val, size_t n);

#endif
