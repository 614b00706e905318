/* pred.c — see pred.h.
 *
 * Filters, and their error bounds derived once.  u = 2^-53 is the unit roundoff.  A filter
 * computes a value v in doubles from terms t_1 .. t_m and a bound e = B (|t_1| + ... + |t_m|)
 * from the computed terms; its *_fast function returns the sign of v when |v| > e, else
 * PRED_UNKNOWN, and the *_exact function beside it then rebuilds the operands as integers
 * (xint, core/xint.h) and decides exactly.  B covers the error of v relative to T = sum |t_i|,
 * and the roundings of T and e themselves; there are three, each named once:
 *
 * ERR_INT_SUM = 8u.  v is a sum or difference of at most four terms, each a product of
 *   integers with at most four roundings in all (an integer converted to a double rounds once
 *   when it exceeds 2^53, each multiplication once; multiplying by 3 rounds too).  A term then
 *   carries a relative error below (1 + u)^4 - 1 < 4.01u, the at most three additions add at
 *   most 3u (1 + 4.01u) T, so |v - exact| < 7.02u T; the computed T and e lose at most five
 *   more roundings, e >= 8u (1 - u)^5 T > 7.9u T.  Used by dot3 (three terms of three
 *   roundings: dot_sign, det3_sign), prod2_diff (two of three: orient_plane of an LPI,
 *   cmp_frac_exact) and axis_plane_side_exact (four of at most four).
 *
 * ERR_APPROX_DIFF = XPT_REL + 4u.  v = a - b where each of a and b is exact or an LPI's or
 *   TPI's approximated coordinate (within XPT_REL of the exact, pred.h) or 3 times one (one
 *   more rounding); T sums only the approximated ones.  The operands err by at most
 *   (XPT_REL + u + u^2) T, the subtraction by u |v| <= u T: (XPT_REL + 2.01u) T in all, and the
 *   roundings of T and e cost less than the 2u to spare.  Used by cmp_coord and
 *   xpt_cmp_q3_exact.
 *
 * ERR_APPROX_SUM = XPT_REL + 16u.  v = n . x + d with n and d a plane's coefficients (each
 *   rounded once) and x an approximated point: each product within XPT_REL + 2.01u of its
 *   exact value, the offset within u, the three additions 3u T: below (XPT_REL + 5.01u) T,
 *   with room to spare.  Used by orient_plane of a TPI.
 *
 * When the filter cannot decide, the exact path does; so a bound too large costs time only,
 * one too small would be a wrong answer: each is derived above with its largest case.
 */
#include "core/pred.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

#define U               (DBL_EPSILON / 2)
#define ERR_INT_SUM     (8 * U)
#define ERR_APPROX_DIFF (XPT_REL + 4 * U)
#define ERR_APPROX_SUM  (XPT_REL + 16 * U)

/* The sign of v when the bound e decides it, else PRED_UNKNOWN: every filter's last step. */
static inline int sign_fast(double v, double e)
{
    return v > e ? 1 : v < -e ? -1 : PRED_UNKNOWN;
}

/* ---- small integer tools ---------------------------------------------------------------- */

static u128 uabs128(i128 v)
{
    return v < 0 ? (u128)0 - (u128)v : (u128)v;
}

static u128 gcd128(u128 a, u128 b)
{
    while (b) {
        u128 t = a % b;
        a = b;
        b = t;
    }
    return a;
}

static int sgn128(i128 v)
{
    return (v > 0) - (v < 0);
}

/* ---- planes ----------------------------------------------------------------------------- */

/* Binary gcd on 64 bits (no division). */
static uint64_t gcd64(uint64_t a, uint64_t b)
{
    if (!a) return b;
    if (!b) return a;
    int s = __builtin_ctzll(a | b);
    a >>= __builtin_ctzll(a);
    do {
        b >>= __builtin_ctzll(b);
        if (a > b) {
            uint64_t t = a;
            a = b, b = t;
        }
        b -= a;
    } while (b);
    return a << s;
}

void plane_reduce(plane3 *p)
{
    u128 g = gcd64(gcd64((uint64_t)uabs128(p->n[0]), (uint64_t)uabs128(p->n[1])),
                   (uint64_t)uabs128(p->n[2]));
    u128 ad = uabs128(p->d);
    if (g > 1) { /* most normals are already primitive: then so is the plane */
        if (ad >> 64 == 0)
            g = gcd64((uint64_t)g, (uint64_t)ad);
        else
            g = gcd128(ad % g, g);
    }
    if (g > 1) {
        for (int i = 0; i < 3; i++) p->n[i] = (int64_t)((i128)p->n[i] / (i128)g);
        p->d /= (i128)g;
    }
    for (int i = 0; i < 3; i++) p->nd[i] = (double)p->n[i];
    p->dd = (double)p->d;
}

int plane_canon(plane3 *p)
{
    int s = 1;
    for (int i = 0; i < 3; i++)
        if (p->n[i]) {
            s = p->n[i] > 0 ? 1 : -1;
            break;
        }
    if (s < 0) {
        for (int i = 0; i < 3; i++) p->n[i] = -p->n[i], p->nd[i] = -p->nd[i];
        p->d = -p->d;
        p->dd = -p->dd;
    }
    return s;
}

int plane_axis(const plane3 *p)
{
    int k = 0;
    for (int i = 1; i < 3; i++)
        if (llabs(p->n[i]) > llabs(p->n[k])) k = i;
    return k;
}

int plane_through_raw(const int64_t *p, const int64_t *q, const int64_t *r, plane3 *out)
{
    /* grid coordinates at most 2^29 + 1 in magnitude: differences at most 2^30 + 2, each
     * product below 2^61 and each component below 2^62: int64 throughout */
    int64_t u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
    int64_t v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    int64_t n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0]};
    if (!n[0] && !n[1] && !n[2]) return -1;
    for (int i = 0; i < 3; i++) out->n[i] = n[i], out->nd[i] = (double)n[i];
    out->d = -((i128)n[0] * p[0] + (i128)n[1] * p[1] + (i128)n[2] * p[2]);
    out->dd = (double)out->d;
    return 0;
}

int plane_through(const int64_t *p, const int64_t *q, const int64_t *r, plane3 *out)
{
    if (plane_through_raw(p, q, r, out)) return -1;
    plane_reduce(out);
    return 0;
}

int plane_vertical(const int64_t *a, const int64_t *b, int k, plane3 *out)
{
    int64_t d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    int i = (k + 1) % 3, j = (k + 2) % 3;
    /* d x e_k: component i is d_j, component j is -d_i, component k is 0 */
    out->n[i] = d[j];
    out->n[j] = -d[i];
    out->n[k] = 0;
    if (!out->n[i] && !out->n[j]) return -1;
    out->d = -((i128)out->n[0] * a[0] + (i128)out->n[1] * a[1] + (i128)out->n[2] * a[2]);
    plane_reduce(out);
    return 0;
}

/* n . g + d of a grid point: |.| < 2^62 2^30 3 + 2^93 < 2^95 */
static i128 plane_eval(const plane3 *p, const int64_t *g)
{
    return (i128)p->n[0] * g[0] + (i128)p->n[1] * g[1] + (i128)p->n[2] * g[2] + p->d;
}

/* ---- points ----------------------------------------------------------------------------- */

xpt xpt_grid(const geo *G, uint32_t v)
{
    xpt p = {{0, 0, 0}, v, 0, 0, PT_GRID};
    for (int i = 0; i < 3; i++) p.x[i] = (double)G->g[3 * (size_t)v + i];
    return p;
}

/* LPI: s_a, s_b and the homogeneous coordinates in 128 bits. */
static void lpi_parts(const geo *G, const xpt *p, i128 *X, i128 *W)
{
    const int64_t *ga = G->g + 3 * (size_t)p->a, *gb = G->g + 3 * (size_t)p->b;
    const plane3 *pl = G->pl + p->c;
    i128 sa = plane_eval(pl, ga), sb = plane_eval(pl, gb);
    i128 w = sa - sb;
    for (int i = 0; i < 3; i++) X[i] = sa * gb[i] - sb * ga[i];
    if (w < 0) {
        w = -w;
        for (int i = 0; i < 3; i++) X[i] = -X[i];
    }
    *W = w;
}

xpt xpt_lpi(const geo *G, uint32_t a, uint32_t b, uint32_t c)
{
    xpt p = {{0, 0, 0}, a < b ? a : b, a < b ? b : a, c, PT_LPI};
    i128 X[3], W;
    lpi_parts(G, &p, X, &W);
    for (int i = 0; i < 3; i++) p.x[i] = (double)X[i] / (double)W;
    return p;
}

static void tpi_hom(const geo *G, const xpt *p, xhom *h)
{
    const plane3 *A = G->pl + p->a, *B = G->pl + p->b, *C = G->pl + p->c;
    i128 cbc[3], cca[3], cab[3];
    cross_ll(B->n, C->n, cbc);
    cross_ll(C->n, A->n, cca);
    cross_ll(A->n, B->n, cab);
    xint t;
    xi_zero(&h->W);
    for (int i = 0; i < 3; i++) {
        xi_mul_i128(&t, A->n[i], cbc[i]);
        xi_add(&h->W, &h->W, &t);
    }
    for (int i = 0; i < 3; i++) {
        xi_zero(&h->X[i]);
        xi_mul_i128(&t, A->d, cbc[i]);
        xi_add(&h->X[i], &h->X[i], &t);
        xi_mul_i128(&t, B->d, cca[i]);
        xi_add(&h->X[i], &h->X[i], &t);
        xi_mul_i128(&t, C->d, cab[i]);
        xi_add(&h->X[i], &h->X[i], &t);
        xi_neg(&h->X[i]);
    }
    if (h->W.neg) {
        xi_neg(&h->W);
        for (int i = 0; i < 3; i++) xi_neg(&h->X[i]);
    }
}

xpt xpt_tpi(const geo *G, uint32_t pa, uint32_t pb, uint32_t pc)
{
    xpt p = {{0, 0, 0}, pa, pb, pc, PT_TPI};
    xhom h;
    tpi_hom(G, &p, &h);
    double w = xi_to_double(&h.W);
    for (int i = 0; i < 3; i++) p.x[i] = xi_to_double(&h.X[i]) / w;
    return p;
}

void xpt_hom(const geo *G, const xpt *p, xhom *h)
{
    if (p->kind == PT_GRID) {
        for (int i = 0; i < 3; i++) xi_set_i64(&h->X[i], G->g[3 * (size_t)p->a + i]);
        xi_set_i64(&h->W, 1);
    } else if (p->kind == PT_LPI) {
        i128 X[3], W;
        lpi_parts(G, p, X, &W);
        for (int i = 0; i < 3; i++) xi_set_i128(&h->X[i], X[i]);
        xi_set_i128(&h->W, W);
    } else {
        tpi_hom(G, p, h);
    }
}

/* X / W as hi + lo: hi the nearest-ish double, lo the rounded rest, from the exact residual
 * X - hi W (hi = m 2^e with m an integer of 53 bits). */
static void quot_dd(const xint *X, const xint *W, double *hi, double *lo)
{
    double w = xi_to_double(W), h = xi_to_double(X) / w;
    int ex;
    *hi = h;
    *lo = 0;
    if (h == 0 || !isfinite(h)) return;
    double f = frexp(h, &ex);
    int64_t m = (int64_t)ldexp(f, 53);
    int e = ex - 53;
    xint M, T, R, Xs;
    xi_set_i64(&M, m);
    xi_mul(&T, W, &M);
    if (e >= 0) {
        xi_shl(&T, &T, e);
        xi_sub(&R, X, &T);
        *lo = xi_to_double(&R) / w;
    } else {
        xi_shl(&Xs, X, -e);
        xi_sub(&R, &Xs, &T);
        *lo = ldexp(xi_to_double(&R) / w, e);
    }
}

void xpt_dd(const geo *G, const xpt *p, double hi[3], double lo[3])
{
    if (p->kind == PT_GRID) {
        for (int i = 0; i < 3; i++) hi[i] = (double)G->g[3 * (size_t)p->a + i], lo[i] = 0;
        return;
    }
    xhom h;
    xpt_hom(G, p, &h);
    for (int i = 0; i < 3; i++) quot_dd(&h.X[i], &h.W, &hi[i], &lo[i]);
}

/* ---- predicates ------------------------------------------------------------------------- */

/* sign(a b - c d) of 128-bit integers: in doubles (ERR_INT_SUM: two terms of three roundings),
 * may say PRED_UNKNOWN; exactly. */
static inline int prod2_diff_fast(i128 a, i128 b, i128 c, i128 d)
{
    double t1 = (double)a * (double)b, t2 = (double)c * (double)d;
    return sign_fast(t1 - t2, (fabs(t1) + fabs(t2)) * ERR_INT_SUM);
}

static int prod2_diff_exact(i128 a, i128 b, i128 c, i128 d)
{
    int s = prod2_diff_fast(a, b, c, d);
    if (s != PRED_UNKNOWN) return s;
    xint x, y;
    xi_mul_i128(&x, a, b);
    xi_mul_i128(&y, c, d);
    return xi_cmp(&x, &y);
}

/* sign(a . b) of 3-vectors of 128-bit integers: in doubles (ERR_INT_SUM: three terms of three
 * roundings), may say PRED_UNKNOWN; exactly. */
static inline int dot3_fast(const i128 *a, const i128 *b)
{
    double t0 = (double)a[0] * (double)b[0], t1 = (double)a[1] * (double)b[1],
           t2 = (double)a[2] * (double)b[2];
    return sign_fast(t0 + t1 + t2, (fabs(t0) + fabs(t1) + fabs(t2)) * ERR_INT_SUM);
}

static inline int dot3_exact(const i128 *a, const i128 *b)
{
    int s = dot3_fast(a, b);
    if (s != PRED_UNKNOWN) return s;
    xint x, t;
    xi_zero(&x);
    for (int i = 0; i < 3; i++) {
        xi_mul_i128(&t, a[i], b[i]);
        xi_add(&x, &x, &t);
    }
    return xi_sign(&x);
}

/* n . x + d of plane P at a TPI's approximation, in doubles (ERR_APPROX_SUM): may say
 * PRED_UNKNOWN. */
static inline int orient_plane_tpi_fast(const plane3 *P, const xpt *p)
{
    double t0 = P->nd[0] * p->x[0], t1 = P->nd[1] * p->x[1], t2 = P->nd[2] * p->x[2];
    double v = t0 + t1 + t2 + P->dd;
    return sign_fast(v, (fabs(t0) + fabs(t1) + fabs(t2) + fabs(P->dd)) * ERR_APPROX_SUM);
}

int orient_plane(const geo *G, const xpt *p, uint32_t pl)
{
    const plane3 *P = G->pl + pl;
    if (p->kind == PT_GRID) return sgn128(plane_eval(P, G->g + 3 * (size_t)p->a));
    if (p->kind == PT_LPI) {
        if (p->c == pl) return 0;
        /* on the line ab: o = (s_a o_b - s_b o_a) / (s_a - s_b), s about plane c, o about pl */
        const int64_t *ga = G->g + 3 * (size_t)p->a, *gb = G->g + 3 * (size_t)p->b;
        i128 oa = plane_eval(P, ga), ob = plane_eval(P, gb);
        if (oa == 0 && ob == 0) return 0;
        const plane3 *C = G->pl + p->c;
        i128 sa = plane_eval(C, ga), sb = plane_eval(C, gb);
        return prod2_diff_exact(sa, ob, sb, oa) * sgn128(sa - sb);
    }
    if (p->a == pl || p->b == pl || p->c == pl) return 0;
    int f = orient_plane_tpi_fast(P, p);
    if (f != PRED_UNKNOWN) return f;
    xhom h;
    xint s, t, c;
    xpt_hom(G, p, &h);
    xi_zero(&s);
    for (int i = 0; i < 3; i++) {
        xi_set_i64(&c, P->n[i]);
        xi_mul(&t, &c, &h.X[i]);
        xi_add(&s, &s, &t);
    }
    xi_set_i128(&c, P->d);
    xi_mul(&t, &c, &h.W);
    xi_add(&s, &s, &t);
    return xi_sign(&s);
}

/* p_k - q_k from the approximations (ERR_APPROX_DIFF): may say PRED_UNKNOWN. */
static inline int cmp_coord_fast(const xpt *p, const xpt *q, int k)
{
    double a = p->x[k], b = q->x[k];
    double e = (p->kind == PT_GRID ? 0 : fabs(a)) + (q->kind == PT_GRID ? 0 : fabs(b));
    return sign_fast(a - b, e * ERR_APPROX_DIFF);
}

int cmp_coord(const geo *G, const xpt *p, const xpt *q, int k)
{
    if (p->kind == PT_GRID && q->kind == PT_GRID) {
        int64_t a = G->g[3 * (size_t)p->a + k], b = G->g[3 * (size_t)q->a + k];
        return (a > b) - (a < b);
    }
    int f = cmp_coord_fast(p, q, k);
    if (f != PRED_UNKNOWN) return f;
    if (p->kind == PT_LPI && q->kind == PT_GRID) {
        i128 X[3], W;
        lpi_parts(G, p, X, &W);
        return sgn128(X[k] - W * G->g[3 * (size_t)q->a + k]);
    }
    if (q->kind == PT_LPI && p->kind == PT_GRID) return -cmp_coord(G, q, p, k);
    xhom hp, hq;
    xint l, r;
    xpt_hom(G, p, &hp);
    xpt_hom(G, q, &hq);
    xi_mul(&l, &hp.X[k], &hq.W);
    xi_mul(&r, &hq.X[k], &hp.W);
    return xi_cmp(&l, &r);
}

int xpt_equal(const geo *G, const xpt *p, const xpt *q)
{
    if (p->kind == q->kind && p->a == q->a && p->b == q->b && p->c == q->c) return 1;
    if (p->kind == PT_GRID && q->kind == PT_GRID) return 0; /* vertices are unique points */
    for (int k = 0; k < 3; k++)
        if (cmp_coord(G, p, q, k) != 0) return 0;
    return 1;
}

void cross_ll(const int64_t *a, const int64_t *b, i128 *out)
{
    out[0] = (i128)a[1] * b[2] - (i128)a[2] * b[1];
    out[1] = (i128)a[2] * b[0] - (i128)a[0] * b[2];
    out[2] = (i128)a[0] * b[1] - (i128)a[1] * b[0];
}

int dot_sign(const int64_t *a, const i128 *b)
{
    const i128 a128[3] = {a[0], a[1], a[2]};
    return dot3_exact(a128, b);
}

int det3_sign(const int64_t *a, const int64_t *b, const i128 *c)
{
    i128 ab[3];
    cross_ll(a, b, ab); /* det(a, b, c) = (a x b) . c */
    return dot3_exact(ab, c);
}

/* ---- predicates of the cells stage (core/arr3_cells.c): fans and probes ----------------- */

int cmp_frac_exact(i128 a, i128 b, i128 c, i128 d)
{
    /* a/b - c/d has the sign of (a d - c b) b d */
    return prod2_diff_exact(a, d, c, b) * sgn128(b) * sgn128(d);
}

/* 3 p_k - q from p's approximation (ERR_APPROX_DIFF; q is exact): may say PRED_UNKNOWN. */
static inline int xpt_cmp_q3_fast(const xpt *p, int k, int64_t q)
{
    double v = 3 * p->x[k] - (double)q;
    return sign_fast(v, (3 * fabs(p->x[k]) + fabs((double)q)) * ERR_APPROX_DIFF);
}

int xpt_cmp_q3_exact(const geo *G, const xpt *p, int k, int64_t q)
{
    if (p->kind == PT_GRID) return sgn128(3 * (i128)G->g[3 * (size_t)p->a + k] - q);
    int f = xpt_cmp_q3_fast(p, k, q);
    if (f != PRED_UNKNOWN) return f;
    xhom h;
    xint l, r, t;
    xpt_hom(G, p, &h);
    xi_set_i64(&t, 3);
    xi_mul(&l, &t, &h.X[k]);
    xi_set_i64(&t, q);
    xi_mul(&r, &t, &h.W);
    return xi_cmp(&l, &r);
}

/* The plane through the line of P and S parallel to e_k: Pi = S_k P - P_k S (its k coefficient
 * is 0); |Pi_i| < 2^125, |S_k d_P| < 2^156.  3 Pi(Q / 3) = Pi_i Q_i + Pi_j Q_j + 3 (S_k d_P -
 * P_k d_S), in doubles (ERR_INT_SUM: four terms, the last two of four roundings): may say
 * PRED_UNKNOWN. */
static inline int axis_plane_side_fast(const plane3 *P, const plane3 *S, int k, int i, int j,
                                       i128 pi_i, i128 pi_j, const int64_t *Q)
{
    double t0 = (double)pi_i * (double)Q[i], t1 = (double)pi_j * (double)Q[j];
    double t2 = 3 * (double)S->n[k] * (double)P->d, t3 = 3 * (double)P->n[k] * (double)S->d;
    double v = t0 + t1 + t2 - t3;
    return sign_fast(v, (fabs(t0) + fabs(t1) + fabs(t2) + fabs(t3)) * ERR_INT_SUM);
}

int axis_plane_side_exact(const plane3 *P, const plane3 *S, int k, const int64_t *Q, int *si)
{
    int i = (k + 1) % 3, j = (k + 2) % 3;
    i128 pi_i = (i128)S->n[k] * P->n[i] - (i128)P->n[k] * S->n[i];
    i128 pi_j = (i128)S->n[k] * P->n[j] - (i128)P->n[k] * S->n[j];
    *si = sgn128(pi_i);
    int f = axis_plane_side_fast(P, S, k, i, j, pi_i, pi_j, Q);
    if (f != PRED_UNKNOWN) return f;
    xint s, t, a, b;
    xi_mul_i128(&s, pi_i, Q[i]);
    xi_mul_i128(&t, pi_j, Q[j]);
    xi_add(&s, &s, &t);
    xi_mul_i128(&a, (i128)3 * S->n[k], P->d);
    xi_mul_i128(&b, (i128)3 * P->n[k], S->d);
    xi_add(&s, &s, &a);
    xi_sub(&s, &s, &b);
    return xi_sign(&s);
}

/* ---- predicates of triangles ------------------------------------------------------------ */

/* The index (0..2) of the sign that differs from the other two (s has both signs, no zero). */
static int lone(const int *s)
{
    return s[0] != s[1] && s[0] != s[2] ? 0 : s[1] != s[0] ? 1 : 2;
}

int tri_tri_apart(const int64_t *const p_[3], const int64_t *const q_[3])
{
    int sp[3], sq[3]; /* sp[i]: q_i about p's plane; sq[i]: p_i about q's plane */
    for (int i = 0; i < 3; i++) sp[i] = orient3_grid(p_[0], p_[1], p_[2], q_[i]);
    if (sp[0] && sp[0] == sp[1] && sp[1] == sp[2]) return 1;
    for (int i = 0; i < 3; i++) sq[i] = orient3_grid(q_[0], q_[1], q_[2], p_[i]);
    if (sq[0] && sq[0] == sq[1] && sq[1] == sq[2]) return 1;
    if (!sp[0] || !sp[1] || !sp[2] || !sq[0] || !sq[1] || !sq[2]) return 0;
    /* each crosses the other's plane: each one's lone vertex first (a turn keeps the
     * orientation), then each turned, if need be, so that the other's lone vertex lies on the
     * positive side of its plane; the stretches on the line meet exactly when both hold */
    int a = lone(sq), b = lone(sp);
    const int64_t *p[3] = {p_[a], p_[(a + 1) % 3], p_[(a + 2) % 3]};
    const int64_t *q[3] = {q_[b], q_[(b + 1) % 3], q_[(b + 2) % 3]};
    const int64_t *t;
    if (sq[a] < 0) t = q[1], q[1] = q[2], q[2] = t;
    if (sp[b] < 0) t = p[1], p[1] = p[2], p[2] = t;
    return orient3_grid(p[0], p[1], q[0], q[1]) > 0 || orient3_grid(p[0], p[2], q[2], q[0]) > 0;
}

/* ---- planar predicates -----------------------------------------------------------------------
 * The bound.  An approximation x of an exact coordinate X (pred.h: GRID exact, LPI and TPI
 * within XPT_REL |x| = 2^-50 |x|) has |X - x| <= 2^-50 |x|.  The filters widen by
 *     m = PLANAR_REL (|a| + |b|) + PLANAR_ABS,   PLANAR_REL = 2^-45, PLANAR_ABS = 2^-30,
 * computed in doubles: the sum and the product round up to 2u relative (u = 2^-53), so the
 * computed m is at least (1 - 2u) 2^-45 max(|a|, |b|) >= 2^-50 max(|a|, |b|) with a factor 31
 * to spare, which also covers the rounding of lo - m and hi + m (at most u |lo - m|, below
 * 2^-52 |lo| + u m).  PLANAR_ABS keeps a floor of room where the coordinates are near zero
 * (there the relative bound already holds; the floor costs nothing and guards subnormals).
 * In grid units (xpt_grid_box_fast) the floor is one unit, and floor/ceil only widen. */
#define PLANAR_REL 0x1p-45
#define PLANAR_ABS 0x1p-30

void span_fast(double a, double b, double *lo, double *hi)
{
    double l = a < b ? a : b, h = a < b ? b : a;
    double m = (fabs(l) + fabs(h)) * PLANAR_REL + PLANAR_ABS;
    *lo = l - m;
    *hi = h + m;
}

void xpt_grid_box_fast(const xpt *p, int64_t lo[3], int64_t hi[3])
{
    for (int a = 0; a < 3; a++) {
        double x = p->x[a], m = fabs(x) * PLANAR_REL + 1;
        lo[a] = (int64_t)floor(x - m);
        hi[a] = (int64_t)ceil(x + m);
    }
}
