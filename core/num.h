/* num.h — exact integer geometry on the snapping grid.
 *
 * Grid coordinates are int64 with |x|, |y| <= 2^39 (arr2 keeps them below 2^38 + 1), so
 * differences fit in 40 bits and every product below fits in a signed 128-bit integer:
 * orient2 is exact (|result| < 2^82), and so are the intersection numerators (< 2^122).
 * There is no epsilon here: the only tolerance of the 2D pipeline is the grid step itself.
 */
#ifndef CELLAR_NUM_H
#define CELLAR_NUM_H

#include <stdint.h>
#include <stdlib.h>

typedef __int128 i128;

typedef struct ipt {
    int64_t x, y;
} ipt;

/* Twice the signed area of triangle abc: > 0 when a, b, c turn counter-clockwise. */
static inline i128 orient2(ipt a, ipt b, ipt c)
{
    return (i128)(b.x - a.x) * (c.y - a.y) - (i128)(b.y - a.y) * (c.x - a.x);
}

/* llround(q) (to nearest, halves away from zero), inline: q - trunc(q) is exact below 2^53, and
 * a larger q is a whole number already.  |q| must be below 2^63. */
static inline int64_t round_half_away(double q)
{
    int64_t t = (int64_t)q;
    double f = q - (double)t;
    return t + (f >= 0.5) - (f <= -0.5);
}

static inline int sign128(i128 v)
{
    return (v > 0) - (v < 0);
}

static inline i128 cross2(int64_t ax, int64_t ay, int64_t bx, int64_t by)
{
    return (i128)ax * by - (i128)ay * bx;
}

/* floor(n / d) for d > 0 */
static inline i128 floordiv128(i128 n, i128 d)
{
    i128 q = n / d;
    if ((n % d != 0) && (n < 0)) q--;
    return q;
}

/* n / d rounded to the nearest integer, halves rounded up (floor(n/d + 1/2)); d > 0.
 * This is the pixel convention: the pixel of grid point X is [X - 1/2, X + 1/2). */
static inline int64_t rounddiv128(i128 n, i128 d)
{
    return (int64_t)floordiv128(2 * n + d, 2 * d);
}

/* Lexicographic order of grid points (x, then y). */
static inline int ipt_cmp(ipt a, ipt b)
{
    if (a.x != b.x) return a.x < b.x ? -1 : 1;
    if (a.y != b.y) return a.y < b.y ? -1 : 1;
    return 0;
}

/* Angular order of direction vectors counter-clockwise from the +x axis, exact.
 * Returns < 0 when a comes first, 0 when a and b point the same way. */
static inline int dir_cmp(int64_t ax, int64_t ay, int64_t bx, int64_t by)
{
    int ha = ay < 0 || (ay == 0 && ax < 0);
    int hb = by < 0 || (by == 0 && bx < 0);
    if (ha != hb) return ha - hb;
    return -sign128(cross2(ax, ay, bx, by));
}

/* Does segment ab pass through the half-open pixel [p - 1/2, p + 1/2)^2?  The caller has
 * checked that p lies in the segment's (integer) bounding box, which is exactly the condition
 * for the segment's box to meet the pixel.  Works in doubled coordinates, where endpoints are
 * even and pixel sides odd, so an endpoint never lies on a pixel side and a segment can only
 * graze a pixel at a corner. */
static inline int seg_hits_pixel(ipt a, ipt b, ipt p)
{
    if ((a.x == p.x && a.y == p.y) || (b.x == p.x && b.y == p.y)) return 1;
    /* In doubled coordinates the corner 2p + (sx, sy) has orientation
     * 4 O + 2 (dx sy - dy sx), O = orient(a, b, p): the four values spread by +-2(|dx|+|dy|)
     * around 4 O.  So the line crosses the open pixel iff 2|O| < |dx| + |dy|, and touches
     * only a corner iff 2|O| == |dx| + |dy|. */
    int64_t dx = b.x - a.x, dy = b.y - a.y, L = llabs(dx) + llabs(dy);
    i128 o2 = 2 * orient2(a, b, p);
    if (o2 < 0) o2 = -o2;
    if (o2 < L) return 1; /* the segment crosses the open pixel (p is in its box) */
    if (o2 > L) return 0; /* the line misses the pixel */
    /* the line only touches one corner: inside the half-open pixel only if it is the
     * lower-left one and lies on the segment (not just on its line) */
    int64_t O2 = 2 * (int64_t)orient2(a, b, p);
    if (dx * -1 - dy * -1 != -O2) return 0;
    int64_t qx = 2 * p.x - 1, qy = 2 * p.y - 1;
    int64_t x0 = 2 * (a.x < b.x ? a.x : b.x), x1 = 2 * (a.x < b.x ? b.x : a.x);
    int64_t y0 = 2 * (a.y < b.y ? a.y : b.y), y1 = 2 * (a.y < b.y ? b.y : a.y);
    return qx >= x0 && qx <= x1 && qy >= y0 && qy <= y1;
}

#endif
