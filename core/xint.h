/* xint.h — fixed-capacity signed integers for the exact 3D predicates (core/pred.h).
 *
 * An xint is a sign and a magnitude of at most XI_LIMBS 64-bit limbs (640 bits), little-endian,
 * with no leading zero limb (n == 0 is zero, which is never negative).  The 3D pipeline bounds
 * every quantity it builds (pred.h says how large each is: at most about 2^410), so no
 * operation here ever needs more than XI_LIMBS limbs; an operation whose result would not fit
 * is a bug of the caller, caught by assert.
 *
 * These are the slow path: the predicates first evaluate in doubles with an error bound and
 * only come here when the bound cannot decide.  Plain schoolbook arithmetic on a few limbs,
 * no allocation, reentrant.
 */
#ifndef CELLAR_XINT_H
#define CELLAR_XINT_H

#include <assert.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#define XI_LIMBS 10

typedef __int128 i128;
typedef unsigned __int128 u128;

typedef struct xint {
    int32_t n;   /* limbs in use */
    int32_t neg; /* 1: negative (never with n == 0) */
    uint64_t w[XI_LIMBS];
} xint;

static inline void xi_zero(xint *r)
{
    r->n = 0;
    r->neg = 0;
}

static inline void xi_set_i128(xint *r, i128 v)
{
    u128 m;
    r->neg = v < 0;
    m = v < 0 ? (u128)0 - (u128)v : (u128)v;
    r->w[0] = (uint64_t)m;
    r->w[1] = (uint64_t)(m >> 64);
    r->n = r->w[1] ? 2 : r->w[0] ? 1 : 0;
}

static inline void xi_set_i64(xint *r, int64_t v)
{
    xi_set_i128(r, v);
}

static inline int xi_sign(const xint *a)
{
    return a->n == 0 ? 0 : a->neg ? -1 : 1;
}

static inline void xi_neg(xint *r)
{
    if (r->n) r->neg = !r->neg;
}

/* |a| <=> |b| */
static inline int xi_cmp_mag(const xint *a, const xint *b)
{
    if (a->n != b->n) return a->n < b->n ? -1 : 1;
    for (int i = a->n - 1; i >= 0; i--)
        if (a->w[i] != b->w[i]) return a->w[i] < b->w[i] ? -1 : 1;
    return 0;
}

/* r = |a| + |b| (magnitudes; r may alias a or b) */
static inline void xi_add_mag(xint *r, const xint *a, const xint *b)
{
    const xint *l = a->n >= b->n ? a : b, *s = a->n >= b->n ? b : a;
    int n = l->n;
    uint64_t carry = 0;
    for (int i = 0; i < n; i++) {
        u128 t = (u128)l->w[i] + (i < s->n ? s->w[i] : 0) + carry;
        r->w[i] = (uint64_t)t;
        carry = (uint64_t)(t >> 64);
    }
    if (carry) {
        assert(n < XI_LIMBS);
        r->w[n++] = carry;
    }
    r->n = n;
}

/* r = |a| - |b| with |a| >= |b| (r may alias a or b) */
static inline void xi_sub_mag(xint *r, const xint *a, const xint *b)
{
    int n = a->n;
    uint64_t borrow = 0;
    for (int i = 0; i < n; i++) {
        uint64_t x = a->w[i], y = i < b->n ? b->w[i] : 0;
        uint64_t d = x - y - borrow;
        borrow = (x < y) || (x - y < borrow);
        r->w[i] = d;
    }
    while (n > 0 && r->w[n - 1] == 0) n--;
    r->n = n;
}

/* r = a + b (r may alias a or b) */
static inline void xi_add(xint *r, const xint *a, const xint *b)
{
    int an = a->neg, bn = b->neg;
    if (an == bn) {
        xi_add_mag(r, a, b);
        r->neg = r->n ? an : 0;
        return;
    }
    if (xi_cmp_mag(a, b) >= 0) {
        xi_sub_mag(r, a, b);
        r->neg = r->n ? an : 0;
    } else {
        xi_sub_mag(r, b, a);
        r->neg = r->n ? bn : 0;
    }
}

/* r = a - b */
static inline void xi_sub(xint *r, const xint *a, const xint *b)
{
    xint nb = *b;
    xi_neg(&nb);
    xi_add(r, a, &nb);
}

/* r = a * b (r must not alias a or b) */
static inline void xi_mul(xint *r, const xint *a, const xint *b)
{
    int n = a->n + b->n;
    if (a->n == 0 || b->n == 0) {
        xi_zero(r);
        return;
    }
    assert(n <= XI_LIMBS);
    memset(r->w, 0, (size_t)n * sizeof r->w[0]);
    for (int i = 0; i < a->n; i++) {
        uint64_t carry = 0;
        for (int j = 0; j < b->n; j++) {
            u128 t = (u128)a->w[i] * b->w[j] + r->w[i + j] + carry;
            r->w[i + j] = (uint64_t)t;
            carry = (uint64_t)(t >> 64);
        }
        r->w[i + b->n] = carry;
    }
    while (n > 0 && r->w[n - 1] == 0) n--;
    r->n = n;
    r->neg = n ? (a->neg ^ b->neg) : 0;
}

/* r += a * b */
static inline void xi_addmul(xint *r, const xint *a, const xint *b)
{
    xint t;
    xi_mul(&t, a, b);
    xi_add(r, r, &t);
}

/* r += a * v, v a small signed integer */
static inline void xi_addmul_i128(xint *r, const xint *a, i128 v)
{
    xint b, t;
    xi_set_i128(&b, v);
    xi_mul(&t, a, &b);
    xi_add(r, r, &t);
}

static inline int xi_cmp(const xint *a, const xint *b)
{
    xint d;
    xi_sub(&d, a, b);
    return xi_sign(&d);
}

/* The nearest double or one of its neighbours: relative error below 2^-52. */
static inline double xi_to_double(const xint *a)
{
    double v;
    if (a->n == 0) return 0;
    if (a->n <= 2) {
        u128 m = ((u128)(a->n == 2 ? a->w[1] : 0) << 64) | a->w[0];
        v = (double)m;
    } else {
        u128 m = ((u128)a->w[a->n - 1] << 64) | a->w[a->n - 2];
        /* the limbs below add less than 2^-64 relative: the sticky bit keeps rounding honest */
        int sticky = 0;
        for (int i = a->n - 3; i >= 0 && !sticky; i--) sticky = a->w[i] != 0;
        v = ldexp((double)(m | (u128)sticky), 64 * (a->n - 2));
    }
    return a->neg ? -v : v;
}

/* r = a * 2^bits (r may alias a) */
static inline void xi_shl(xint *r, const xint *a, int bits)
{
    int limbs = bits / 64, sh = bits % 64, n = a->n;
    uint64_t w[XI_LIMBS + 1];
    if (n == 0) {
        xi_zero(r);
        return;
    }
    assert(n + limbs + 1 <= XI_LIMBS + 1);
    memset(w, 0, sizeof w);
    for (int i = 0; i < n; i++) {
        w[i + limbs] |= sh ? a->w[i] << sh : a->w[i];
        if (sh) w[i + limbs + 1] |= a->w[i] >> (64 - sh);
    }
    n = n + limbs + 1;
    while (n > 0 && w[n - 1] == 0) n--;
    assert(n <= XI_LIMBS);
    r->neg = a->neg;
    memcpy(r->w, w, (size_t)n * sizeof *w);
    r->n = n;
}

/* a * b of two 128-bit values, as an xint */
static inline void xi_mul_i128(xint *r, i128 a, i128 b)
{
    xint x, y;
    xi_set_i128(&x, a);
    xi_set_i128(&y, b);
    xi_mul(r, &x, &y);
}

#endif
