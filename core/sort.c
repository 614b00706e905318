/* sort.c — see sort.h.  11-bit digits: 6 passes for a 64-bit key at most. */
#include "core/sort.h"

#include <stdlib.h>
#include <string.h>

#define RBITS 11
#define RSIZE (1u << RBITS)

/* One stable counting pass of elements of size `size` whose key is key(elem); returns 1 when
 * it moved the data to dst, 0 when every key had the same digit (nothing to do). */
#define RADIX_PASS(T, KEY)                                                                         \
    static int pass_##T(const T *src, T *dst, size_t n, unsigned shift, size_t *cnt)               \
    {                                                                                              \
        memset(cnt, 0, RSIZE * sizeof *cnt);                                                       \
        for (size_t i = 0; i < n; i++) cnt[(KEY(src[i]) >> shift) & (RSIZE - 1)]++;                \
        for (size_t d = 0; d < RSIZE; d++)                                                         \
            if (cnt[d] == n) return 0;                                                             \
        size_t s = 0;                                                                              \
        for (size_t d = 0; d < RSIZE; d++) {                                                       \
            size_t c = cnt[d];                                                                     \
            cnt[d] = s;                                                                            \
            s += c;                                                                                \
        }                                                                                          \
        for (size_t i = 0; i < n; i++) dst[cnt[(KEY(src[i]) >> shift) & (RSIZE - 1)]++] = src[i];  \
        return 1;                                                                                  \
    }

#define KEY_U64(e)   (e)
#define KEY_HI32(e)  ((e) >> 32)
#define KEY_IPT_X(e) ((uint64_t)(e).x ^ (UINT64_C(1) << 63))
#define KEY_IPT_Y(e) ((uint64_t)(e).y ^ (UINT64_C(1) << 63))
#define KEY_KV(e)    ((e).k)
typedef ipt ipt_x;
typedef ipt ipt_y;
RADIX_PASS(ipt_x, KEY_IPT_X)
RADIX_PASS(ipt_y, KEY_IPT_Y)

/* Below this many elements an insertion sort beats the passes' fixed cost (a histogram of
 * 2^RBITS counts each): the 3D core sorts many tiny arrangements. */
#define SMALL 48
/* Below this many a merge sort does (runs of SMALL sorted by insertion, merged pairwise): the
 * passes' histograms, NDIG * 2^RBITS counts zeroed and summed, cost more than n log n
 * comparisons up to about here (the charts' boundaries: hundreds of sorts of hundreds). */
#define MEDIUM 1024

/* A sort of T by the key KEY(elem) of KEYBITS bits (64 at most), stable: insertion below SMALL,
 * merging below MEDIUM, else the passes.  The histograms of every digit are counted in one read of
 * the data; a digit that every key shares costs no pass. */
#define NDIG ((64 + RBITS - 1) / RBITS)
#define RADIX_SORT(NAME, T, KEY, KEYBITS)                                                          \
    int NAME(T *a, size_t n)                                                                       \
    {                                                                                              \
        if (n < 2) return 0;                                                                       \
        if (n <= MEDIUM) { /* runs of SMALL by insertion (all of it below SMALL) */                \
            for (size_t r = 0; r < n; r += SMALL) {                                                \
                size_t e = r + SMALL < n ? r + SMALL : n;                                          \
                for (size_t i = r + 1; i < e; i++) {                                               \
                    T x = a[i];                                                                    \
                    size_t j = i;                                                                  \
                    for (; j > r && KEY(a[j - 1]) > KEY(x); j--) a[j] = a[j - 1];                  \
                    a[j] = x;                                                                      \
                }                                                                                  \
            }                                                                                      \
            if (n <= SMALL) return 0;                                                              \
        }                                                                                          \
        T *tmp = malloc(n * sizeof *tmp), *src = a, *dst = tmp;                                    \
        size_t *cnt = NULL;                                                                        \
        if (tmp && n <= MEDIUM) {                                                                  \
            /* the runs merged pairwise, stable: ties from the left run first */                   \
            for (size_t w = SMALL; w < n; w *= 2) {                                                \
                for (size_t lo = 0; lo < n; lo += 2 * w) {                                         \
                    size_t mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n;    \
                    size_t i = lo, j = mid, k = lo;                                                \
                    while (i < mid && j < hi)                                                      \
                        dst[k++] = KEY(src[j]) < KEY(src[i]) ? src[j++] : src[i++];                \
                    while (i < mid) dst[k++] = src[i++];                                           \
                    while (j < hi) dst[k++] = src[j++];                                            \
                }                                                                                  \
                T *t = src;                                                                        \
                src = dst;                                                                         \
                dst = t;                                                                           \
            }                                                                                      \
            goto done;                                                                             \
        }                                                                                          \
        cnt = calloc(NDIG * RSIZE, sizeof *cnt);                                                   \
        if (!tmp || !cnt) {                                                                        \
            free(tmp);                                                                             \
            free(cnt);                                                                             \
            return -1;                                                                             \
        }                                                                                          \
        enum { nd = ((KEYBITS) + RBITS - 1) / RBITS }; /* the key's digits: no more counted */     \
        for (size_t i = 0; i < n; i++) {                                                           \
            uint64_t k = KEY(a[i]);                                                                \
            for (unsigned d = 0; d < nd; d++)                                                      \
                cnt[d * RSIZE + ((k >> (d * RBITS)) & (RSIZE - 1))]++;                             \
        }                                                                                          \
        for (unsigned d = 0; d < nd; d++) {                                                        \
            size_t *c = cnt + d * RSIZE, s = 0;                                                    \
            unsigned sh = d * RBITS;                                                               \
            if (c[(KEY(a[0]) >> sh) & (RSIZE - 1)] == n) continue; /* one digit for all */         \
            for (size_t q = 0; q < RSIZE; q++) {                                                   \
                size_t t = c[q];                                                                   \
                c[q] = s;                                                                          \
                s += t;                                                                            \
            }                                                                                      \
            for (size_t i = 0; i < n; i++) dst[c[(KEY(src[i]) >> sh) & (RSIZE - 1)]++] = src[i];   \
            T *t = src;                                                                            \
            src = dst;                                                                             \
            dst = t;                                                                               \
        }                                                                                          \
    done:                                                                                          \
        if (src != a) memcpy(a, src, n * sizeof *a);                                               \
        free(tmp);                                                                                 \
        free(cnt);                                                                                 \
        return 0;                                                                                  \
    }

RADIX_SORT(sort_u64, uint64_t, KEY_U64, 64)
RADIX_SORT(sort_u64_hi32, uint64_t, KEY_HI32, 32)
RADIX_SORT(sort_kv, kv, KEY_KV, 64)

int sort_ipt(ipt *a, size_t n)
{
    return sort_ipt_stop(a, n, NULL);
}

int sort_ipt_stop(ipt *a, size_t n, const atomic_int *stop)
{
    if (n < 2) return 0;
    if (n <= SMALL) { /* by x, then y: the order of the passes below */
        for (size_t i = 1; i < n; i++) {
            ipt x = a[i];
            size_t j = i;
            for (; j > 0 && (a[j - 1].x > x.x || (a[j - 1].x == x.x && a[j - 1].y > x.y)); j--)
                a[j] = a[j - 1];
            a[j] = x;
        }
        return 0;
    }
    ipt *tmp = malloc(n * sizeof *tmp);
    size_t *cnt = malloc(RSIZE * sizeof *cnt);
    if (!tmp || !cnt) {
        free(tmp);
        free(cnt);
        return -1;
    }
    ipt *src = a, *dst = tmp;
    /* by y, then (stable) by x; a stop is read before each pass (a is then some order of its
     * elements: each pass writes all of them) */
    for (unsigned p = 0, sh = 0; p < 2; p++, sh = 0)
        for (; sh < 64; sh += RBITS) {
            if (stop && atomic_load_explicit(stop, memory_order_relaxed)) {
                free(tmp);
                free(cnt);
                return -2;
            }
            if (p == 0 ? pass_ipt_y(src, dst, n, sh, cnt) : pass_ipt_x(src, dst, n, sh, cnt)) {
                ipt *t = src;
                src = dst;
                dst = t;
            }
        }
    if (src != a) memcpy(a, src, n * sizeof *a);
    free(tmp);
    free(cnt);
    return 0;
}

int sort_kv_xyz(kv *a, size_t n, const int64_t *xyz)
{
    for (int k = 2; k >= 0; k--) {
        for (size_t i = 0; i < n; i++)
            a[i].k = (uint64_t)(xyz[3 * (size_t)a[i].v + k] + ((int64_t)1 << 40));
        if (sort_kv(a, n)) return -1;
    }
    return 0;
}

int sort_u64_u32(uint64_t *key, uint32_t *val, size_t n)
{
    uint64_t *kb = malloc((n ? n : 1) * sizeof *kb);
    uint32_t *vb = malloc((n ? n : 1) * sizeof *vb);
    if (!kb || !vb) {
        free(kb);
        free(vb);
        return -1;
    }
    uint64_t *ks = key, *kd = kb;
    uint32_t *vs = val, *vd = vb;
    for (int part = 0; part < 2; part++) { /* the values' bytes, then the keys' */
        uint64_t all_or = 0, all_and = ~(uint64_t)0;
        for (size_t i = 0; i < n; i++) {
            uint64_t x = part ? ks[i] : vs[i];
            all_or |= x, all_and &= x;
        }
        for (int pass = 0; pass < (part ? 8 : 4); pass++) {
            int sh = 8 * pass;
            if (((all_or ^ all_and) >> sh & 255) == 0) continue;
            size_t cnt[257] = {0};
            for (size_t i = 0; i < n; i++) cnt[((part ? ks[i] : vs[i]) >> sh & 255) + 1]++;
            for (int b = 0; b < 256; b++) cnt[b + 1] += cnt[b];
            for (size_t i = 0; i < n; i++) {
                size_t d = cnt[(part ? ks[i] : vs[i]) >> sh & 255]++;
                kd[d] = ks[i], vd[d] = vs[i];
            }
            uint64_t *kt = ks;
            ks = kd, kd = kt;
            uint32_t *vt = vs;
            vs = vd, vd = vt;
        }
    }
    if (ks != key) {
        memcpy(key, ks, n * sizeof *key);
        memcpy(val, vs, n * sizeof *val);
    }
    free(kb);
    free(vb);
    return 0;
}
