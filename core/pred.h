/* pred.h — exact geometry of the 3D pipeline: integer planes, implicit points, and the
 * predicates every decision of core/arr3.c goes through.
 *
 * Everything lives on the snapping grid: an input vertex is an integer triple g with |g_i| <=
 * 2^29 + 1 (arr3 centres the grid; extent / precision <= 2^30).  Nothing is ever rounded after
 * that.  Objects and their sizes (|.| bounds, which fix the widths below):
 *   plane     n . x + d = 0, integers reduced by their gcd.  A face plane through three grid
 *             points has |n_i| < 2^62, |d| < 2^93; the "vertical" plane of an edge (through the
 *             edge, parallel to a coordinate axis) has |n_i| <= 2^31, |d| < 2^62.
 *   point     an xpt: the approximation x[] (doubles) and how the point is defined, from which
 *             its exact homogeneous coordinates (X, Y, Z, W), W > 0, are rebuilt when needed:
 *     GRID    an input vertex: (g, 1).
 *     LPI     where the segment between grid vertices a and b crosses plane c (a line-plane
 *             intersection): with s_a = n . g_a + d, W = s_a - s_b (< 2^95), X = s_a g_b - s_b
 *             g_a (< 2^124).
 *     TPI     where planes a, b, c meet: W = det(n_a, n_b, n_c) (< 2^187), X = -(d_a n_b x n_c
 *             + d_b n_c x n_a + d_c n_a x n_b) (< 2^218).
 *   No point is ever built from a built point: every LPI and TPI refers to input vertices and
 *   planes only, so the sizes above hold whatever the depth of the computation.
 *
 * Predicates name their contract as Shewchuk's do.  A *_fast function may be wrong or say
 * PRED_UNKNOWN (doubles and an error bound: a filter); a *_exact function is exact.  The exact
 * predicates are those named *_exact and, keeping the names the other modules call them by,
 * orient_plane, cmp_coord, xpt_equal, det3_sign, dot_sign, orient3_grid and tri_tri_apart; no
 * *_fast function is exported today (each filter is a static *_fast beside its *_exact in
 * pred.c, which derives every error bound once, with its proof).  Each exact predicate first
 * evaluates in doubles with a forward error bound and returns that sign when the value is
 * farther from zero than the bound; only then does it rebuild the operands in xint
 * (core/xint.h) and decide exactly.  Known zeros are symbolic: a point defined by plane p lies
 * on p, and a point of the segment ab (a, b, or an LPI of ab) lies on every plane through a
 * and b, without arithmetic.  The largest exact quantity is a coordinate comparison of two
 * TPIs, X1 W2 - X2 W1 < 2^406, well inside XI_LIMBS.
 *
 * Threads: everything here is reentrant and reads only what it is given.
 */
#ifndef CELLAR_PRED_H
#define CELLAR_PRED_H

#include <stddef.h>
#include <stdint.h>

#include "core/xint.h"

typedef struct plane3 {
    int64_t n[3];     /* normal */
    i128 d;           /* offset: n . x + d = 0 */
    double nd[3], dd; /* n and d as doubles (each within half an ulp) */
} plane3;

enum { PT_GRID = 0, PT_LPI = 1, PT_TPI = 2 };

typedef struct xpt {
    double x[3];  /* approximation: exact for GRID, else within XPT_REL * |x| of each coordinate */
    uint32_t a;   /* GRID: vertex; LPI: vertex a; TPI: plane a */
    uint32_t b;   /* LPI: vertex b; TPI: plane b */
    uint32_t c;   /* LPI and TPI: plane c */
    uint8_t kind; /* PT_* */
} xpt;

#define XPT_REL 0x1p-50 /* relative error of an LPI's or TPI's approximation (3 roundings) */

/* What the definitions refer to (borrowed). */
typedef struct geo {
    const int64_t *g; /* 3 per input vertex: grid coordinates */
    const plane3 *pl; /* planes */
} geo;

/* Exact homogeneous coordinates of a point. */
typedef struct xhom {
    xint X[3], W; /* W > 0 */
} xhom;

/* ---- planes ---------------------------------------------------------------------------- */

/* The plane through grid points p, q, r (not collinear): normal (q - p) x (r - p), reduced.
 * Returns 0, or -1 when they are collinear. */
int plane_through(const int64_t *p, const int64_t *q, const int64_t *r, plane3 *out);
/* The same, not reduced: the normal (q - p) x (r - p) as it is (its direction and orientation
 * are those of the triangle pqr), and d = -n . p.  The bounds above hold; every predicate takes
 * such a plane.  Returns -1 when p, q, r are collinear. */
int plane_through_raw(const int64_t *p, const int64_t *q, const int64_t *r, plane3 *out);

/* The plane through grid points a != b parallel to axis k (0, 1, 2), reduced: normal
 * (b - a) x e_k.  Returns -1 when ab is parallel to e_k. */
int plane_vertical(const int64_t *a, const int64_t *b, int k, plane3 *out);

/* Reduces (n, d) by their gcd and fills the doubles.  Canonical up to sign; plane_canon also
 * makes the first non-zero normal component positive and returns the sign it applied (+1/-1). */
void plane_reduce(plane3 *p);
int plane_canon(plane3 *p);

/* Index (0..2) of the largest |n_i| (the first of equals). */
int plane_axis(const plane3 *p);

/* ---- points ---------------------------------------------------------------------------- */

/* A GRID point of vertex v; an LPI of the segment between vertices a and b (whose ends lie
 * strictly on opposite sides of plane c); a TPI of three planes whose normals are independent.
 * Each computes the approximation exactly rounded from the exact value (see XPT_REL). */
xpt xpt_grid(const geo *G, uint32_t v);
xpt xpt_lpi(const geo *G, uint32_t a, uint32_t b, uint32_t c);
xpt xpt_tpi(const geo *G, uint32_t pa, uint32_t pb, uint32_t pc);

void xpt_hom(const geo *G, const xpt *p, xhom *h);

/* The point's coordinates as unevaluated sums hi + lo of two doubles (within 2^-100 of each
 * coordinate): what volumes and written coordinates are computed from. */
void xpt_dd(const geo *G, const xpt *p, double hi[3], double lo[3]);

/* ---- exact predicates ------------------------------------------------------------------ */

/* What a *_fast predicate returns when its error bound cannot decide. */
#define PRED_UNKNOWN 2

/* Sign of n . p + d for plane id pl: which side of the plane p lies on (0: on it). */
int orient_plane(const geo *G, const xpt *p, uint32_t pl);

/* Sign of p_k - q_k. */
int cmp_coord(const geo *G, const xpt *p, const xpt *q, int k);

/* 1 when p and q are the same point. */
int xpt_equal(const geo *G, const xpt *p, const xpt *q);

/* Sign of det(a, b, c) for integer vectors (|a_i|, |b_i| < 2^63, |c_i| < 2^127). */
int det3_sign(const int64_t *a, const int64_t *b, const i128 *c);

/* n_a x n_b (each component < 2^125). */
void cross_ll(const int64_t *a, const int64_t *b, i128 *out);

/* Sign of a . b for an integer vector a and b (|b_i| < 2^127). */
int dot_sign(const int64_t *a, const i128 *b);

/* Of the cells stage (core/arr3_cells.c: the fans about an edge, the probes' rays). */

/* Sign of a/b - c/d for b, d != 0 (|a|, |b|, |c|, |d| < 2^127). */
int cmp_frac_exact(i128 a, i128 b, i128 c, i128 d);

/* Sign of 3 p_k - q: p's coordinate k against the rational q / 3 (|q| < 2^53). */
int xpt_cmp_q3_exact(const geo *G, const xpt *p, int k, int64_t q);

/* P and S meet in a line; Pi = S_k P - P_k S is the plane through that line parallel to e_k.
 * Returns the sign of Pi at the point Q / 3 (|Q_i| < 2^53; Q_k does not matter), and in *si the
 * sign of Pi's coefficient (k + 1) % 3. */
int axis_plane_side_exact(const plane3 *P, const plane3 *S, int k, const int64_t *Q, int *si);

/* Sign of det(b - a, c - a, d - a) for grid points (coordinates below 2^30 in magnitude: the
 * differences below 2^31, their cross product in 64 bits, the product in 128), exactly. */
static inline int orient3_grid(const int64_t *a, const int64_t *b, const int64_t *c,
                               const int64_t *d)
{
    int64_t v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2];
    int64_t w0 = d[0] - a[0], w1 = d[1] - a[1], w2 = d[2] - a[2];
    i128 e = (i128)(v1 * w2 - v2 * w1) * (b[0] - a[0]) + (i128)(v2 * w0 - v0 * w2) * (b[1] - a[1]) +
             (i128)(v0 * w1 - v1 * w0) * (b[2] - a[2]);
    return (e > 0) - (e < 0);
}

/* Are triangles p and q (grid points, each spanning a plane) apart: 1 when they share no point,
 * proven by exact orientation tests (Devillers and Guigue, "Faster triangle-triangle
 * intersection tests", 2002): one wholly on one side of the other's plane, or each crossing the
 * other's plane with the two stretches on the planes' line apart.  0 when they may meet, or when
 * a vertex lies on the other's plane (touching and coplanar cases are left to the caller). */
int tri_tri_apart(const int64_t *const p[3], const int64_t *const q[3]);

/* ---- planar predicates ------------------------------------------------------------------
 * Filters of the arrangement of one plane (core/arr3_plane.c) on the points' approximations,
 * each conservative: a box or an answer that holds for the exact points, whatever the
 * approximations' errors (the bound is derived once, in pred.c).  "_fast": they may say
 * "maybe" where the exact answer is "no"; never "no" where it is "yes". */

/* The closed interval [*lo, *hi] holding the exact coordinate (on one axis) of every point of a
 * segment whose ends' approximations on that axis are a and b. */
void span_fast(double a, double b, double *lo, double *hi);

/* The integer box [lo, hi] (grid units, one unit of room) holding the exact point p. */
void xpt_grid_box_fast(const xpt *p, int64_t lo[3], int64_t hi[3]);

#endif
