/* fastfloat.c — see fastfloat.h.
 *
 * A decimal w * 10^q (w of at most 19 digits) is w * 5^q * 2^q.  The table of core/pow5.h
 * holds 5^q scaled into [2^127, 2^128) as T (truncated for q >= 0, exact up to q = 55; rounded
 * up for q < 0), so with w' = w shifted left until its top bit is set, P = w' T approximates
 * the value scaled by a power of two, and the top 128 bits of P, H = floor(P / 2^64) (two
 * 64 x 64-bit products), are within one unit of those of the exact product (T differs from
 * the exact scaled 5^q by less than one, so P by less than w' < 2^64).  The 54 top bits of H
 * are the double's 53-bit significand and its rounding bit; the rounding is decided by the
 * bits below, and only when H lies within one unit of a point where those bits are all zero
 * (a tie, or an exact value, or a carry into the significand) can the approximation decide
 * wrongly: then, and for results that are subnormal, infinite, or of more than 19 significant
 * digits, the number goes to strtod.  Where w <= 2^53 and |q| <= 22 both w and 10^|q| are exact
 * doubles and one IEEE product or quotient is correctly rounded (Clinger's fast path). */
#include "core/fastfloat.h"

#include <locale.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/pow5.h"

typedef unsigned __int128 u128;

static const double P10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                               1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                               1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* strtod in the "C" locale on [p, end) (at most 400 bytes; -1 beyond). */
static int slow(const char *p, const char *end, double *out)
{
    static locale_t cl;
    char buf[401];
    size_t n = (size_t)(end - p);
    if (n > 400) return -1;
    if (!cl) {
        locale_t l = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
        if (!l) return -1;
        if (!__atomic_compare_exchange_n(&cl, &(locale_t){0}, l, 0, __ATOMIC_ACQ_REL,
                                         __ATOMIC_ACQUIRE))
            freelocale(l);
    }
    memcpy(buf, p, n);
    buf[n] = 0;
    char *e;
    double v = strtod_l(buf, &e, cl);
    if (e != buf + n || !isfinite(v)) return -1;
    *out = v;
    return 0;
}

/* The Eisel-Lemire step: 0 and *out, or 1 (undecided: the caller falls back). */
static int eisel_lemire(uint64_t w, int q, int neg, double *out)
{
    if (q < POW5_QMIN || q > POW5_QMAX) return 1;
    int l = __builtin_clzll(w);
    uint64_t ws = w << l;
    const uint64_t *T = POW5 + 2 * (q - POW5_QMIN);
    u128 a = (u128)ws * T[0], b = (u128)ws * T[1];
    uint64_t hi = (uint64_t)(a >> 64), lo = (uint64_t)a, c = (uint64_t)(b >> 64);
    lo += c;
    hi += lo < c;
    int up = (int)(hi >> 63), sh = up + 9;
    uint64_t mask = ((uint64_t)1 << sh) - 1, r = hi & mask;
    if ((r == 0 && lo <= 1) || (r == mask && lo >= UINT64_MAX - 1)) return 1;
    uint64_t m = hi >> sh; /* 54 bits: the significand and the rounding bit */
    /* the value is m 2^(e2 - 53) with e2 = floor(q log2 10) + up - l + 63 + 1 - 1 */
    int e2 = (int)(((int64_t)217706 * q) >> 16) + 63 + up - l;
    m = (m + 1) >> 1; /* the bits below the rounding bit are not zero: round half up */
    if (m >> 53) {
        m >>= 1;
        e2++;
    }
    int biased = e2 + 1023;
    if (biased <= 0 || biased >= 2047) return 1; /* subnormal or infinite */
    uint64_t bits = (uint64_t)biased << 52 | (m & (((uint64_t)1 << 52) - 1));
    if (neg) bits |= (uint64_t)1 << 63;
    memcpy(out, &bits, sizeof *out);
    return 0;
}

/* Eight digits at once (coordinates are written with up to 17 significant digits): the bytes
 * as a little-endian word, less '0' each; then pairs, quadruples and the octet are formed by
 * one multiply-add each, every lane keeping its low part. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define FF_SWAR 1
static uint64_t load8(const char *s)
{
    uint64_t v;
    memcpy(&v, s, 8);
    return v;
}

/* Are all eight bytes '0' to '9'?  (a byte below '0' borrows in v - '0'; above '9' carries
 * into bit 7 when 0x46 is added) */
static int all_digits8(uint64_t v)
{
    return (((v - 0x3030303030303030u) | (v + 0x4646464646464646u)) & 0x8080808080808080u) == 0;
}

static uint64_t value8(uint64_t v)
{
    v -= 0x3030303030303030u;                        /* d0 in the low byte */
    v = (v * 10 + (v >> 8)) & 0x00ff00ff00ff00ffu;   /* 10 d0 + d1, ... */
    v = (v * 100 + (v >> 16)) & 0x0000ffff0000ffffu; /* four digits a lane */
    return (v * 10000 + (v >> 32)) & 0xffffffffu;    /* the eight */
}
#endif

int ff_parse(const char *p, const char *end, double *out)
{
    const char *stop;
    double v;
    if (ff_parse_prefix(p, end, &v, &stop) || stop != end) return -1;
    *out = v;
    return 0;
}

int ff_parse_prefix(const char *p, const char *end, double *out, const char **stop)
{
    const char *s = p;
    int neg = 0;
    if (s < end && (*s == '-' || *s == '+')) neg = *s++ == '-';
    uint64_t w = 0;
    int nd = 0, q = 0, any = 0, many = 0;
    while (s < end && *s >= '0' && *s <= '9') {
        any = 1;
#ifdef FF_SWAR
        if (w && nd <= 11 && end - s >= 8 && all_digits8(load8(s))) {
            w = w * 100000000u + value8(load8(s));
            nd += 8, s += 8;
            continue;
        }
#endif
        if (nd < 19) {
            w = w * 10 + (uint64_t)(*s - '0');
            nd += w != 0;
        } else {
            q++;
            many |= *s != '0';
        }
        s++;
    }
    if (s < end && *s == '.') {
        s++;
        while (s < end && *s >= '0' && *s <= '9') {
            any = 1;
#ifdef FF_SWAR
            if (w && nd <= 11 && end - s >= 8 && all_digits8(load8(s))) {
                w = w * 100000000u + value8(load8(s));
                nd += 8, q -= 8, s += 8;
                continue;
            }
#endif
            if (nd < 19) {
                w = w * 10 + (uint64_t)(*s - '0');
                nd += w != 0;
                q--;
            } else {
                many |= *s != '0';
            }
            s++;
        }
    }
    if (!any) return -1;
    if (s < end && (*s == 'e' || *s == 'E')) {
        s++;
        int eneg = 0;
        long ex = 0;
        if (s < end && (*s == '-' || *s == '+')) eneg = *s++ == '-';
        if (s >= end || *s < '0' || *s > '9') return -1; /* "1e", "1e+": malformed */
        while (s < end && *s >= '0' && *s <= '9') {
            if (ex < 100000) ex = ex * 10 + (*s - '0');
            s++;
        }
        q += (int)(eneg ? -ex : ex);
    }
    *stop = s;
    end = s; /* the number's bytes, for slow() */
    if (w == 0) {
        *out = neg ? -0.0 : 0.0;
        return 0;
    }
    if (many) return slow(p, end, out); /* more than 19 significant digits */
    if (w <= ((uint64_t)1 << 53) && q >= -22 && q <= 22) {
        double v = (double)w;
        v = q < 0 ? v / P10[-q] : v * P10[q];
        *out = neg ? -v : v;
        return 0;
    }
    if (q > POW5_QMAX) return -1; /* at least 10^309: not finite */
    if (eisel_lemire(w, q, neg, out) == 0) return 0;
    return slow(p, end, out);
}

int ff_json_number(const char *p, const char *end, double *out, int *integer, size_t *digits,
                   const char **stop)
{
    const char *q = p;
    if (q < end && *q == '-') q++;
    const char *d0 = q;
    if (q >= end || *q < '0' || *q > '9') return -1;
    if (*q == '0')
        q++;
    else
        while (q < end && *q >= '0' && *q <= '9') q++;
    *digits = (size_t)(q - d0);
    *integer = 1;
    if (q < end && *q == '.') {
        *integer = 0;
        q++;
        if (q >= end || *q < '0' || *q > '9') return -1;
        while (q < end && *q >= '0' && *q <= '9') q++;
    }
    if (q < end && (*q == 'e' || *q == 'E')) {
        *integer = 0;
        q++;
        if (q < end && (*q == '+' || *q == '-')) q++;
        if (q >= end || *q < '0' || *q > '9') return -1;
        while (q < end && *q >= '0' && *q <= '9') q++;
    }
    if (*integer && *digits <= 15) { /* exact in a double */
        int64_t v = 0;
        for (const char *r = d0; r < q; r++) v = v * 10 + (*r - '0');
        *out = *p == '-' ? -(double)v : (double)v; /* "-0" is -0.0, as strtod reads it */
    } else if (ff_parse(p, q, out)) {
        return -2;
    }
    *stop = q;
    return 0;
}
