/* arr3_cells.c — the 3-cells of the arrangement and the lar3 it returns (stage 5 of arr3.h).
 *
 * Fans.  The faces around an edge are sorted by angle about the edge's direction d (integer:
 * n_P x n_S of a plane pair the edge lies on, oriented from its lower to its higher vertex).
 * Face f meets the edge walking along d (s = +1) or against it (s = -1); it leaves the edge in
 * direction t = s (n_f x d).  With the identities (n_a x d) x (n_b x d) = d det(n_a, n_b, d) and
 * (n_a x d) . (n_b x d) = (n_a . n_b) |d|^2, the order of two faces about d is decided by the
 * signs of det(n_a, n_b, d) and n_a . n_b only: exact integers, no point involved.  Between two
 * consecutive faces a and b (counter-clockwise about d) lies one cell: a's side s_a and b's side
 * -s_b face it.  Face sides so linked form the shells.
 *
 * Nesting.  Each connected part (faces linked through edges) has one outside shell, and a part
 * lying inside a cell of another must become a cavity of that cell.  Both questions are answered
 * by rays: a line parallel to axis k through a rational point q strictly inside an input piece
 * of the part (the centroid of a triangle of it), perturbed symbolically to q + (eps, eps^2) in
 * the other two coordinates, so that it meets no edge and no vertex.  A face is hit when the
 * perturbed point lies in its projection (even-odd crossings, exact: an edge's side is the sign
 * of q against the plane through the edge parallel to e_k, a combination of the face's plane and
 * the edge's side plane); hits are ordered by where they meet the line (exact fractions, ties
 * broken by the perturbation's derivatives).  The part's own first hit from -infinity shows its
 * outside shell; the nearest hit of another part below q shows the cell holding the part.
 *
 * The probes find the faces they may hit through a grid over the input pieces' boxes (a face
 * lies inside each piece covering it).
 *
 * Volumes are sums of cones over the faces' cycles from the points' approximations (each within
 * 2^-50 of the exact point), so a cell's volume is exact up to rounding.
 *
 * Threads: the edges' fans, the points' approximations and the cells' volumes run on par_for()
 * in fixed chunks, each writing only its own items; the rest runs on the calling thread.
 */
#include "core/arr3_int.h"
#include "core/par.h"
#include "core/sort.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define U (DBL_EPSILON / 2)

/* ---- small tools ------------------------------------------------------------------------ */

static int cmpu32(const void *pa, const void *pb)
{
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    return (a > b) - (a < b);
}

static int cmpi32(const void *pa, const void *pb)
{
    int32_t a = *(const int32_t *)pa, b = *(const int32_t *)pb;
    return (a > b) - (a < b);
}

static int sgn128(i128 v)
{
    return (v > 0) - (v < 0);
}

/* sign(a/b - c/d) for b, d != 0 */
static int cmp_frac(i128 a, i128 b, i128 c, i128 d)
{
    double l = (double)a * (double)d, r = (double)c * (double)b;
    double e = (fabs(l) + fabs(r)) * (8 * U);
    int s;
    if (l - r > e)
        s = 1;
    else if (r - l > e)
        s = -1;
    else {
        xint x, y;
        xi_mul_i128(&x, a, d);
        xi_mul_i128(&y, c, b);
        s = xi_cmp(&x, &y);
    }
    return s * sgn128(b) * sgn128(d);
}

/* ---- fans ----------------------------------------------------------------------------------- */

typedef struct inc {
    uint32_t e, f;
    int s; /* +1: f walks e from its lower to its higher vertex */
} inc;

typedef struct fanctx {
    const a3 *A;
    i128 d[3];
    const int64_t *n0; /* the first face's normal */
    int s0;
} fanctx;

/* The normal of face f (its anchor plane's when it has no canonical plane). */
static const int64_t *face_n(const a3 *A, uint32_t f, plane3 *tmp)
{
    return a3_face_plane(A, f, tmp)->n;
}

static int fan_half(const fanctx *x, const inc *a)
{
    plane3 tmp;
    const int64_t *na = face_n(x->A, a->f, &tmp);
    int s = det3_sign(x->n0, na, x->d) * x->s0 * a->s;
    if (s > 0) return 0;
    if (s < 0) return 1;
    i128 dot = (i128)x->n0[0] * na[0] + (i128)x->n0[1] * na[1] + (i128)x->n0[2] * na[2];
    return sgn128(dot) * x->s0 * a->s > 0 ? 0 : 1;
}

static int fan_cmp(const void *pa, const void *pb, void *vx)
{
    const fanctx *x = vx;
    const inc *a = pa, *b = pb;
    int ha = fan_half(x, a), hb = fan_half(x, b);
    if (ha != hb) return ha - hb;
    plane3 ta, tb;
    int s = det3_sign(face_n(x->A, a->f, &ta), face_n(x->A, b->f, &tb), x->d) * a->s * b->s;
    if (s > 0) return -1;
    if (s < 0) return 1;
    return (a->f > b->f) - (a->f < b->f);
}

/* For solids: around an edge, each solid's winding number in the wedges between consecutive
 * faces is 0 or 1 (outside or inside).  Face f (walking the edge s = +-1) has its side s toward
 * the next wedge counter-clockwise; a piece covering it, of outward orientation g about f's
 * normal, enters its solid toward the next wedge when s != g (+1) and leaves it when s == g
 * (-1).  Two pieces of one solid on one face turning opposite ways (a surface touching itself
 * face to face: an inner wall) add up to 0.  A solid whose winding about the edge takes more
 * than two values, or does not come back to where it started, passes through itself along this
 * edge: an input that intersects itself (or that the grid makes so), reported with where. */
typedef struct fanside {
    uint32_t solid;
    int w, lo, hi; /* winding after the last face, relative to the first wedge; its range */
    int dw;        /* of the current face */
    size_t face;   /* the face dw belongs to */
} fanside;

static int fan_check(const a3 *A, const inc *F, size_t n, const uint32_t *ends, const lar3 *out,
                     char *err, size_t errlen)
{
    fanside st[8];
    size_t ns = 0;
    for (size_t k = 0; k <= n; k++) {
        /* the face before k is complete: its windings apply */
        for (size_t j = 0; j < ns; j++) {
            if (st[j].face + 1 != k || !st[j].dw) continue;
            st[j].w += st[j].dw;
            st[j].dw = 0;
            if (st[j].w < st[j].lo) st[j].lo = st[j].w;
            if (st[j].w > st[j].hi) st[j].hi = st[j].w;
            if (st[j].hi - st[j].lo > 1) goto bad;
        }
        if (k == n) break;
        uint32_t f = F[k].f;
        for (uint32_t i = A->f_cov[f]; i < A->f_cov[f + 1]; i++) {
            const piece *pc = &A->pc[A->cov[i]];
            size_t j = 0;
            while (j < ns && st[j].solid != pc->solid) j++;
            if (j == ns) {
                if (ns == sizeof st / sizeof *st) continue; /* only in a pile of 8 solids */
                st[ns] = (fanside){pc->solid, 0, 0, 0, 0, k};
                ns++;
            }
            st[j].dw += F[k].s != pc->sgn ? 1 : -1;
            st[j].face = k;
        }
    }
    for (size_t j = 0; j < ns; j++)
        if (st[j].w != 0) goto bad;
    return ARR_OK;
bad : {
    const piece *pc = &A->pc[A->cov[A->f_cov[F[0].f]]];
    const xpt *a = &A->pt[ends[0]], *b = &A->pt[ends[1]];
    snprintf(err, errlen,
             "solids[%u]: face %u: the surface passes through itself along the edge (%.9g, %.9g, "
             "%.9g)-(%.9g, %.9g, %.9g): the solid intersects itself on the grid of step %g",
             pc->solid, pc->face - out->solid_face_off[pc->solid],
             ((double)A->oi[0] + a->x[0]) * A->step, ((double)A->oi[1] + a->x[1]) * A->step,
             ((double)A->oi[2] + a->x[2]) * A->step, ((double)A->oi[0] + b->x[0]) * A->step,
             ((double)A->oi[1] + b->x[1]) * A->step, ((double)A->oi[2] + b->x[2]) * A->step,
             A->step);
    return ARR_EINVAL;
}
}

/* ---- the fans of all edges, in parallel ----------------------------------------------------- */

#define FAN_CHUNK 8192
typedef struct fanjob {
    const a3 *A;
    inc *I;
    const uint32_t *ioff, *ev, *eside, *eface;
    const lar3 *out;
    size_t ne;
    size_t *bad; /* by chunk: 1 + its first edge that failed, or 0 */
} fanjob;

/* Edge e's incidences sorted around it (counter-clockwise seen along it), and for solids the
 * windings checked (fan_check). */
static int fan_sort(const fanjob *j, size_t e, char *err, size_t errlen)
{
    const a3 *A = j->A;
    const uint32_t *ev = j->ev;
    inc *F = j->I + j->ioff[e];
    size_t n = j->ioff[e + 1] - j->ioff[e];
    if (n >= 3) {
        fanctx x = {A, {0, 0, 0}, NULL, 0};
        plane3 tp, tmp, t0;
        const plane3 *P = a3_face_plane(A, j->eface[e], &tp);
        const plane3 *SP = a3_side(A, P, ev[2 * e], ev[2 * e + 1], j->eside[e], &tmp);
        if (!SP) {
            snprintf(err, errlen, "solids: an edge of %zu faces has no line (a bug)", n);
            return ARR_EINTERNAL;
        }
        cross_ll(P->n, SP->n, x.d);
        int ax = 0;
        for (int a = 1; a < 3; a++)
            if ((x.d[a] < 0 ? -x.d[a] : x.d[a]) > (x.d[ax] < 0 ? -x.d[ax] : x.d[ax])) ax = a;
        int c = cmp_coord(&A->G, &A->pt[ev[2 * e + 1]], &A->pt[ev[2 * e]], ax);
        if ((c > 0) != (x.d[ax] > 0))
            for (int a = 0; a < 3; a++) x.d[a] = -x.d[a];
        x.n0 = face_n(A, F[0].f, &t0);
        x.s0 = F[0].s;
        qsort_r(F + 1, n - 1, sizeof *F, fan_cmp, &x);
    }
    return A->soup ? ARR_OK : fan_check(A, F, n, ev + 2 * e, j->out, err, errlen);
}

static void fans_sort(void *ctx, size_t item, int worker)
{
    (void)worker;
    const fanjob *j = ctx;
    size_t e1 = (item + 1) * FAN_CHUNK < j->ne ? (item + 1) * FAN_CHUNK : j->ne;
    char err[8];
    for (size_t e = item * FAN_CHUNK; e < e1; e++)
        if (fan_sort(j, e, err, sizeof err) != ARR_OK) {
            j->bad[item] = e + 1;
            return;
        }
}

/* ---- probes --------------------------------------------------------------------------------- */

typedef struct probe {
    int64_t Q[3]; /* the point is Q / 3 */
    int k, i, j;
} probe;

/* sign(p_ax - Q_ax / 3) */
static int cmp_q(const a3 *A, const xpt *p, const probe *pr, int ax)
{
    if (p->kind == PT_GRID) {
        i128 v = 3 * (i128)A->g[3 * (size_t)p->a + ax] - pr->Q[ax];
        return sgn128(v);
    }
    double v = 3 * p->x[ax] - (double)pr->Q[ax];
    double e = (3 * fabs(p->x[ax]) + fabs((double)pr->Q[ax])) * (XPT_REL + 8 * U);
    if (v > e) return 1;
    if (v < -e) return -1;
    xhom h;
    xint l, r, q;
    xpt_hom(&A->G, p, &h);
    xi_set_i64(&q, 3);
    xi_mul(&l, &q, &h.X[ax]);
    xi_set_i64(&q, pr->Q[ax]);
    xi_mul(&r, &q, &h.W);
    return xi_cmp(&l, &r);
}

/* Sign of the plane through line (P, S) parallel to e_k at the probe point, and the sign of that
 * plane's i coefficient. */
static int pi_side(const a3 *A, const plane3 *P, const plane3 *S, const probe *pr, int *si)
{
    int k = pr->k, i = pr->i, j = pr->j;
    i128 pi_i = (i128)S->n[k] * P->n[i] - (i128)P->n[k] * S->n[i];
    i128 pi_j = (i128)S->n[k] * P->n[j] - (i128)P->n[k] * S->n[j];
    *si = sgn128(pi_i);
    /* value = pi_i Q_i + pi_j Q_j + 3 (S_k d_P - P_k d_S) */
    double t0 = (double)pi_i * (double)pr->Q[i], t1 = (double)pi_j * (double)pr->Q[j];
    double t2 = 3 * (double)S->n[k] * (double)P->d, t3 = 3 * (double)P->n[k] * (double)S->d;
    double v = t0 + t1 + t2 - t3;
    double e = (fabs(t0) + fabs(t1) + fabs(t2) + fabs(t3)) * (16 * U);
    (void)A;
    if (v > e) return 1;
    if (v < -e) return -1;
    xint s, t, a, b;
    xi_mul_i128(&s, pi_i, pr->Q[i]);
    xi_mul_i128(&t, pi_j, pr->Q[j]);
    xi_add(&s, &s, &t);
    xi_mul_i128(&a, (i128)3 * S->n[k], P->d);
    xi_mul_i128(&b, (i128)3 * P->n[k], S->d);
    xi_add(&s, &s, &a);
    xi_sub(&s, &s, &b);
    return xi_sign(&s);
}

/* Does the perturbed probe line meet face f? */
static int probe_hits(const a3 *A, uint32_t f, const probe *pr)
{
    plane3 tp;
    const plane3 *P = a3_face_plane(A, f, &tp);
    if (P->n[pr->k] == 0) return 0;
    int par = 0;
    for (uint32_t cy = A->f_cyc[f]; cy < A->f_cyc[f + 1]; cy++) {
        uint32_t o = A->cyc_off[cy], n = A->cyc_off[cy + 1] - o;
        if (n < 2) continue;
        for (uint32_t t = 0; t < n; t++) {
            uint32_t a = A->ent[o + t], b = A->ent[o + (t + 1) % n], S = A->side[o + t];
            int sa = cmp_q(A, &A->pt[a], pr, pr->j) > 0, sb = cmp_q(A, &A->pt[b], pr, pr->j) > 0;
            if (sa == sb || S == NONE) continue;
            plane3 tmp;
            const plane3 *SP = a3_side(A, P, a, b, S, &tmp);
            if (!SP) continue;
            int si, s = pi_side(A, P, SP, pr, &si);
            if (s == 0) s = si;
            par ^= s == -si;
        }
    }
    return par;
}

/* Where the probe line meets plane P: x_k = num / den. */
static void probe_t(const plane3 *P, const probe *pr, i128 *num, i128 *den)
{
    *num = -((i128)P->n[pr->i] * pr->Q[pr->i] + (i128)P->n[pr->j] * pr->Q[pr->j] + 3 * P->d);
    *den = 3 * (i128)P->n[pr->k];
}

/* Order of faces f and g along the perturbed probe line (both hit). */
static int probe_cmp(const a3 *A, uint32_t f, uint32_t g, const probe *pr)
{
    plane3 tf, tg;
    const plane3 *F = a3_face_plane(A, f, &tf), *G = a3_face_plane(A, g, &tg);
    i128 nf, df, ng, dg;
    probe_t(F, pr, &nf, &df);
    probe_t(G, pr, &ng, &dg);
    int c = cmp_frac(nf, df, ng, dg);
    if (c) return c;
    c = cmp_frac(-F->n[pr->i], F->n[pr->k], -G->n[pr->i], G->n[pr->k]);
    if (c) return c;
    return cmp_frac(-F->n[pr->j], F->n[pr->k], -G->n[pr->j], G->n[pr->k]);
}

typedef struct probe_sort {
    const a3 *A;
    const probe *pr;
} probe_sort;

/* Faces hit by a probe, from the highest to the lowest along the line. */
static int probe_desc(const void *pa, const void *pb, void *vx)
{
    const probe_sort *x = vx;
    return probe_cmp(x->A, *(const uint32_t *)pb, *(const uint32_t *)pa, x->pr);
}

/* The triangles of piece pi (a3_triangulate along its normal's axis *k, into *tri): 0, -1 out
 * of memory, -2 none (not a polygon). */
static int piece_tris(const a3 *A, uint32_t pi, uint32_t **tri, size_t *ntri, size_t *captri,
                      int *k)
{
    const piece *pc = &A->pc[pi];
    uint32_t *cyc[64], **cp = cyc;
    size_t len[64], *lp = len;
    int rc = -1;
    plane3 tp;
    *k = plane_axis(a3_piece_plane(A, pi, &tp));
    *ntri = 0;
    if (pc->nc > 64) {
        cp = malloc(pc->nc * sizeof *cp);
        lp = malloc(pc->nc * sizeof *lp);
        if (!cp || !lp) goto done;
    }
    for (uint32_t c = 0; c < pc->nc; c++) {
        uint32_t o = A->pc_off[pc->c0 + c];
        cp[c] = A->pcv + o;
        lp[c] = A->pc_off[pc->c0 + c + 1] - o;
    }
    int r = a3_triangulate(A, *k, cp, lp, pc->nc, tri, ntri, captri);
    rc = r == -1 ? -1 : r || !*ntri ? -2 : 0;
done:
    if (cp != cyc) free(cp);
    if (lp != len) free(lp);
    return rc;
}

/* The probe through the centroid of triangle tri[0..3), on a line along axis k. */
static void tri_probe(const a3 *A, const uint32_t *tri, int k, probe *pr)
{
    for (int a = 0; a < 3; a++)
        pr->Q[a] = A->g[3 * (size_t)tri[0] + a] + A->g[3 * (size_t)tri[1] + a] +
                   A->g[3 * (size_t)tri[2] + a];
    pr->k = k;
    pr->i = (k + 1) % 3;
    pr->j = (k + 2) % 3;
}

/* ---- cells and output ------------------------------------------------------------------ */

static int vcmp(const void *pa, const void *pb, void *vx)
{
    const a3 *A = vx;
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    for (int k = 0; k < 3; k++) {
        int c = cmp_coord(&A->G, &A->pt[a], &A->pt[b], k);
        if (c) return c;
    }
    return (a > b) - (a < b);
}

/* ---- double-double: volumes from points known to 2^-100 ---------------------------------- */

typedef struct dd {
    double hi, lo;
} dd;

static dd two_sum(double a, double b)
{
    double s = a + b, bb = s - a;
    dd r = {s, (a - (s - bb)) + (b - bb)};
    return r;
}

/* Dekker's exact product (no fused multiply-add needed) */
static void split(double a, double *h, double *l)
{
    double t = 134217729.0 * a; /* 2^27 + 1 */
    *h = t - (t - a);
    *l = a - *h;
}

static dd two_prod(double a, double b)
{
    double p = a * b, ah, al, bh, bl;
    split(a, &ah, &al);
    split(b, &bh, &bl);
    dd r = {p, ((ah * bh - p) + ah * bl + al * bh) + al * bl};
    return r;
}

static dd dd_add(dd a, dd b)
{
    dd s = two_sum(a.hi, b.hi);
    s.lo += a.lo + b.lo;
    return two_sum(s.hi, s.lo);
}

static dd dd_neg(dd a)
{
    dd r = {-a.hi, -a.lo};
    return r;
}

static dd dd_mul(dd a, dd b)
{
    dd p = two_prod(a.hi, b.hi);
    p.lo += a.hi * b.lo + a.lo * b.hi;
    return two_sum(p.hi, p.lo);
}

/* Point v's coordinates minus the origin org, in double-double. */
static void dd_rel(const double *dh, const double *dl, uint32_t v, const dd *org, dd *p)
{
    for (int k = 0; k < 3; k++) {
        dd x = {dh[3 * (size_t)v + k], dl[3 * (size_t)v + k]};
        p[k] = dd_add(x, dd_neg(org[k]));
    }
}

/* Six times the cone volume over face f's cycles from org, in double-double: taken from a
 * vertex of the cell, the terms are as small as the cell, so a sliver keeps its volume. */
static dd face_cone6(const a3 *A, const double *dh, const double *dl, uint32_t f, const dd *org,
                     const int64_t *gorg)
{
    dd s = {0, 0};
    for (uint32_t cy = A->f_cyc[f]; cy < A->f_cyc[f + 1]; cy++) {
        uint32_t o = A->cyc_off[cy], n = A->cyc_off[cy + 1] - o;
        dd p[3][3];
        if (gorg && n >= 3) {
            /* the origin and every point of the cycle on the grid: exact in 128 bits (grid
             * coordinates below 2^31 in magnitude: differences below 2^32, each term below
             * 2^96, the sum of a cycle's 3 (n - 2) terms far below 2^127) */
            uint32_t i = 0;
            while (i < n && A->pt[A->ent[o + i]].kind == PT_GRID) i++;
            if (i == n) {
                i128 acc = 0;
                int64_t q[3][3];
                for (int k = 0; k < 3; k++)
                    q[0][k] = A->g[3 * (size_t)A->pt[A->ent[o]].a + k] - gorg[k];
                for (i = 1; i + 1 < n; i++) {
                    for (int k = 0; k < 3; k++) {
                        q[1][k] = A->g[3 * (size_t)A->pt[A->ent[o + i]].a + k] - gorg[k];
                        q[2][k] = A->g[3 * (size_t)A->pt[A->ent[o + i + 1]].a + k] - gorg[k];
                    }
                    i128 c0 = (i128)q[1][1] * q[2][2] - (i128)q[1][2] * q[2][1];
                    i128 c1 = (i128)q[1][2] * q[2][0] - (i128)q[1][0] * q[2][2];
                    i128 c2 = (i128)q[1][0] * q[2][1] - (i128)q[1][1] * q[2][0];
                    acc += q[0][0] * c0 + q[0][1] * c1 + q[0][2] * c2;
                }
                double hi = (double)acc;
                dd t = {hi, (double)(acc - (i128)hi)};
                s = dd_add(s, t);
                continue;
            }
        }
        if (n >= 3) dd_rel(dh, dl, A->ent[o], org, p[0]);
        for (uint32_t i = 1; i + 1 < n; i++) {
            dd_rel(dh, dl, A->ent[o + i], org, p[1]);
            dd_rel(dh, dl, A->ent[o + i + 1], org, p[2]);
            dd c0 = dd_add(dd_mul(p[1][1], p[2][2]), dd_neg(dd_mul(p[1][2], p[2][1])));
            dd c1 = dd_add(dd_mul(p[1][2], p[2][0]), dd_neg(dd_mul(p[1][0], p[2][2])));
            dd c2 = dd_add(dd_mul(p[1][0], p[2][1]), dd_neg(dd_mul(p[1][1], p[2][0])));
            s = dd_add(s, dd_mul(p[0][0], c0));
            s = dd_add(s, dd_mul(p[0][1], c1));
            s = dd_add(s, dd_mul(p[0][2], c2));
        }
    }
    return s;
}

/* ---- the parallel parts of the output ---------------------------------------------------- */

#define DD_CHUNK 4096
typedef struct ddjob {
    const a3 *A;
    double *dh, *dl;
    const lar3 *out;
    double h3;
} ddjob;

/* The wanted points (dh[3p] == 0) of one chunk to 2^-100. */
static void points_dd(void *ctx, size_t item, int worker)
{
    (void)worker;
    const ddjob *j = ctx;
    const a3 *A = j->A;
    size_t p1 = (item + 1) * DD_CHUNK < A->npt ? (item + 1) * DD_CHUNK : A->npt;
    for (size_t p = item * DD_CHUNK; p < p1; p++)
        if (!isnan(j->dh[3 * p])) xpt_dd(&A->G, &A->pt[p], j->dh + 3 * p, j->dl + 3 * p);
}

/* The volumes of one chunk of cells: the sum of their faces' cones from a vertex of the cell. */
static void cells_volume(void *ctx, size_t item, int worker)
{
    (void)worker;
    const ddjob *j = ctx;
    const a3 *A = j->A;
    const lar3 *out = j->out;
    const double *dh = j->dh, *dl = j->dl;
    double h3 = j->h3;
    size_t k0 = item * DD_CHUNK, k1 = k0 + DD_CHUNK < out->nc ? k0 + DD_CHUNK : out->nc;
    for (size_t k = k0; k < k1; k++) {
        dd org[3] = {{0, 0}, {0, 0}, {0, 0}}, vol = {0, 0};
        const int64_t *gorg = NULL; /* the origin's grid point, when it is one */
        if (out->cf_off[k + 1] > out->cf_off[k]) {
            /* a vertex of the cell's first face, on the grid when one is */
            int32_t s0 = out->cf[out->cf_off[k]];
            uint32_t f0 = (uint32_t)(s0 > 0 ? s0 : -s0) - 1, o0 = A->cyc_off[A->f_cyc[f0]];
            uint32_t n0 = A->cyc_off[A->f_cyc[f0] + 1] - o0, v0 = A->ent[o0];
            for (uint32_t i = 0; i < n0; i++)
                if (A->pt[A->ent[o0 + i]].kind == PT_GRID) {
                    v0 = A->ent[o0 + i];
                    gorg = A->g + 3 * (size_t)A->pt[v0].a;
                    break;
                }
            for (int a = 0; a < 3; a++)
                org[a].hi = dh[3 * (size_t)v0 + a], org[a].lo = dl[3 * (size_t)v0 + a];
        }
        for (uint32_t i = out->cf_off[k]; i < out->cf_off[k + 1]; i++) {
            int32_t sf = out->cf[i];
            uint32_t f = (uint32_t)(sf > 0 ? sf : -sf) - 1;
            dd c = face_cone6(A, dh, dl, f, org, gorg);
            vol = dd_add(vol, sf > 0 ? c : dd_neg(c));
        }
        out->cvol[k] = (vol.hi + vol.lo) * h3;
    }
}

/* ---- a grid over the pieces' boxes in a probe's projection ----------------------------------
 * Which faces may a ray along -k through (qi, qj) cross?  Those whose projected box holds the
 * point: a uniform grid over the boxes (about two faces per cell) answers with the boxes of one
 * cell plus the few big ones, instead of every face for every part (parts x faces grew faster
 * than the arrangement on scenes of many solids).  Only a filter: the exact test follows. */
typedef struct fgrid {
    double x0, y0, cw, ch;
    int nx, ny;
    uint32_t *off, *items; /* cell c holds items[off[c] .. off[c+1]) */
    uint32_t *big;         /* boxes over more than FGRID_BIG cells: checked for every query */
    size_t nbig;
} fgrid;
#define FGRID_BIG 64

static void fgrid_free(fgrid *g)
{
    free(g->off);
    free(g->items);
    free(g->big);
    memset(g, 0, sizeof *g);
}

static void fgrid_span(const fgrid *g, const double *bx, int *c0, int *r0, int *c1, int *r1)
{
    double a = (bx[0] - g->x0) / g->cw, b = (bx[2] - g->x0) / g->cw;
    double c = (bx[1] - g->y0) / g->ch, d = (bx[3] - g->y0) / g->ch;
    *c0 = a < 0 ? 0 : a >= g->nx ? g->nx - 1 : (int)a;
    *c1 = b < 0 ? 0 : b >= g->nx ? g->nx - 1 : (int)b;
    *r0 = c < 0 ? 0 : c >= g->ny ? g->ny - 1 : (int)c;
    *r1 = d < 0 ? 0 : d >= g->ny ? g->ny - 1 : (int)d;
}

static int fgrid_build(fgrid *g, const double *box, size_t n)
{
    double x0 = DBL_MAX, y0 = DBL_MAX, x1 = -DBL_MAX, y1 = -DBL_MAX;
    fgrid_free(g);
    for (size_t f = 0; f < n; f++) {
        const double *b = box + 4 * f;
        if (b[0] < x0) x0 = b[0];
        if (b[1] < y0) y0 = b[1];
        if (b[2] > x1) x1 = b[2];
        if (b[3] > y1) y1 = b[3];
    }
    int side = (int)sqrt((double)n / 2) + 1;
    if (side > 4096) side = 4096;
    g->nx = g->ny = side;
    g->x0 = x0, g->y0 = y0;
    g->cw = x1 > x0 ? (x1 - x0) / side : 1;
    g->ch = y1 > y0 ? (y1 - y0) / side : 1;
    if (!(g->cw > 0) || !isfinite(g->cw)) g->cw = 1;
    if (!(g->ch > 0) || !isfinite(g->ch)) g->ch = 1;
    size_t ncell = (size_t)side * (size_t)side, total = 0;
    g->off = calloc(ncell + 2, sizeof *g->off);
    g->big = malloc((n + 1) * sizeof *g->big);
    if (!g->off || !g->big) return -1;
    for (int pass = 0; pass < 2; pass++) {
        g->nbig = 0;
        for (size_t f = 0; f < n; f++) {
            int c0, r0, c1, r1;
            fgrid_span(g, box + 4 * f, &c0, &r0, &c1, &r1);
            if ((size_t)(c1 - c0 + 1) * (size_t)(r1 - r0 + 1) > FGRID_BIG) {
                g->big[g->nbig++] = (uint32_t)f;
                continue;
            }
            for (int r = r0; r <= r1; r++)
                for (int c = c0; c <= c1; c++) {
                    size_t cell = (size_t)r * (size_t)side + (size_t)c;
                    if (pass == 0)
                        g->off[cell + 2]++;
                    else
                        g->items[g->off[cell + 1]++] = (uint32_t)f;
                }
        }
        if (pass == 0) {
            for (size_t c = 0; c < ncell; c++) g->off[c + 2] += g->off[c + 1];
            total = g->off[ncell + 1];
            if (total > UINT32_MAX) return -1;
            g->items = malloc((total + 1) * sizeof *g->items);
            if (!g->items) return -1;
        }
    }
    return 0;
}

/* The faces whose boxes may hold (qi, qj), ascending, into *out (grown as needed). */
static int fgrid_query(const fgrid *g, double qi, double qj, uint32_t **out, size_t *cap, size_t *n)
{
    size_t k = 0, m = g->nbig;
    double a = (qi - g->x0) / g->cw, b = (qj - g->y0) / g->ch;
    int inside = a >= 0 && b >= 0 && a <= g->nx && b <= g->ny;
    size_t cell = 0;
    if (inside) {
        int c = a >= g->nx ? g->nx - 1 : (int)a, r = b >= g->ny ? g->ny - 1 : (int)b;
        cell = (size_t)r * (size_t)g->nx + (size_t)c;
        m += g->off[cell + 1] - g->off[cell];
    }
    if (a3_grow(out, cap, m + 1, sizeof **out)) return -1;
    for (size_t i = 0; i < g->nbig; i++) (*out)[k++] = g->big[i];
    if (inside)
        for (uint32_t i = g->off[cell]; i < g->off[cell + 1]; i++) (*out)[k++] = g->items[i];
    qsort(*out, k, sizeof **out, a3_cmp_u32);
    *n = k;
    return 0;
}

int a3_cells(a3 *A, lar3 *out, char *err, size_t errlen)
{
    size_t nf = A->nf;
    int rc = ARR_ENOMEM;
    inc *I = NULL;
    size_t ne = 0;
    uint32_t *ev = NULL, *eside = NULL, *eface = NULL, *ioff = NULL;
    uint32_t *sp = NULL, *fcomp = NULL, *shell = NULL, *cu = NULL, *cell = NULL, *outer = NULL;
    uint32_t *cpiece = NULL, *newid = NULL, *used = NULL, *ptri = NULL;
    size_t nptri = 0, capptri = 0;
    double *fbox = NULL, *dh = NULL, *dl = NULL;
    fgrid fgk[3] = {{0}};
    double *fboxk[3] = {NULL, NULL, NULL};
    uint32_t *cand = NULL, *pf_off = NULL, *pf = NULL, *ff = NULL;
    size_t capcand = 0, capff = 0;
    uint32_t *hits = NULL, *hoff = NULL, *stack = NULL;
    size_t caphits = 0, capstack = 0;
    probe *probes = NULL;
    uint64_t *ek = NULL;
    uint32_t *ent_e = NULL; /* the edge of each cycle entry (to the next one) */
    /* edges: the entries sorted by their (lower, higher) vertex pair (stable: by face within an
     * edge); an edge per pair, its incidences the run of entries, its side and plane from the
     * first */
    {
        uint32_t *ent_f = malloc((A->nent + 1) * sizeof *ent_f);
        kv *ek2 = malloc((A->nent + 1) * sizeof *ek2);
        ent_e = malloc((A->nent + 1) * sizeof *ent_e);
        if (!ent_f || !ek2 || !ent_e) {
            free(ent_f), free(ek2);
            goto done;
        }
        size_t m = 0;
        for (size_t f = 0; f < nf; f++)
            for (uint32_t cy = A->f_cyc[f]; cy < A->f_cyc[f + 1]; cy++) {
                uint32_t o = A->cyc_off[cy], n = A->cyc_off[cy + 1] - o;
                if (n < 2) continue;
                for (uint32_t t = 0; t < n; t++) {
                    uint32_t a = A->ent[o + t], b = A->ent[o + (t + 1) % n];
                    uint32_t lo = a < b ? a : b, hi = a ^ b ^ lo;
                    ek2[m++] = (kv){(uint64_t)lo << 32 | hi, o + t};
                    ent_f[o + t] = (uint32_t)f;
                }
            }
        if (sort_kv(ek2, m)) {
            free(ent_f), free(ek2);
            goto done;
        }
        a3_progress(A, "cells", 0.25); /* the fractions of this stage: of 2 000 turned cubes */
        for (size_t i = 0; i < m; i++) ne += i == 0 || ek2[i].k != ek2[i - 1].k;
        ev = malloc((2 * ne + 2) * sizeof *ev);
        eside = malloc((ne + 1) * sizeof *eside);
        eface = malloc((ne + 1) * sizeof *eface);
        ioff = malloc((ne + 2) * sizeof *ioff);
        I = malloc((m + 1) * sizeof *I);
        if (!ev || !eside || !eface || !ioff || !I) {
            free(ent_f), free(ek2);
            goto done;
        }
        ne = 0;
        for (size_t i = 0; i < m; i++) {
            uint32_t x = ek2[i].v, lo = (uint32_t)(ek2[i].k >> 32);
            if (i == 0 || ek2[i].k != ek2[i - 1].k) {
                ev[2 * ne] = lo, ev[2 * ne + 1] = (uint32_t)ek2[i].k;
                eside[ne] = A->side[x];
                eface[ne] = ent_f[x];
                ioff[ne] = (uint32_t)i;
                ne++;
            }
            I[i] = (inc){(uint32_t)ne - 1, ent_f[x], A->ent[x] == lo ? 1 : -1};
            ent_e[x] = (uint32_t)ne - 1;
        }
        ioff[ne] = (uint32_t)m;
        free(ent_f), free(ek2);
    }
    /* fans: face sides 2f (+, the normal's side) and 2f+1 (-) */
    sp = malloc((2 * nf + 1) * sizeof *sp);
    fcomp = malloc((nf + 1) * sizeof *fcomp);
    if (!sp || !fcomp) goto done;
    for (size_t i = 0; i < 2 * nf; i++) sp[i] = (uint32_t)i;
    for (size_t i = 0; i < nf; i++) fcomp[i] = (uint32_t)i;
    {
        /* each edge's fan sorted and checked, in chunks on the threads; the first failing edge
         * is checked again here for its message */
        size_t nch = (ne + FAN_CHUNK - 1) / FAN_CHUNK;
        fanjob j = {A, I, ioff, ev, eside, eface, out, ne, calloc(nch + 1, sizeof *j.bad)};
        if (!j.bad) goto done;
        a3_span span = {A, "cells", 0.25, 0.33};
        par_for_ex(A->threads, nch, fans_sort, &j, a3_span_tick, &span);
        size_t bad = SIZE_MAX;
        for (size_t ch = 0; ch < nch && bad == SIZE_MAX; ch++)
            if (j.bad[ch]) bad = j.bad[ch] - 1;
        free(j.bad);
        if (bad != SIZE_MAX && (rc = fan_sort(&j, bad, err, errlen)) != ARR_OK) goto done;
    }
    for (size_t e = 0; e < ne; e++) {
        inc *F = I + ioff[e];
        size_t n = ioff[e + 1] - ioff[e];
        rc = ARR_ENOMEM;
        for (size_t k = 0; k < n; k++) {
            const inc *f0 = &F[k], *f1 = &F[k + 1 < n ? k + 1 : 0];
            uint32_t n0 = 2 * f0->f + (f0->s > 0 ? 0 : 1);
            uint32_t n1 = 2 * f1->f + (f1->s > 0 ? 1 : 0);
            a3_uf_union(sp, n0, n1);
            a3_uf_union(fcomp, f0->f, f1->f);
        }
    }
    /* shells */
    a3_progress(A, "cells", 0.35);
    shell = malloc((2 * nf + 1) * sizeof *shell);
    if (!shell) goto done;
    size_t nsh = 0;
    for (size_t i = 0; i < 2 * nf; i++) shell[i] = NONE;
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t r = a3_uf_find(sp, (uint32_t)i);
        if (shell[r] == NONE) shell[r] = (uint32_t)nsh++;
        shell[i] = shell[r];
    }
    /* components, and an input piece of each */
    size_t ncomp = 0;
    outer = malloc((nf + 1) * sizeof *outer);           /* by component: its outside shell */
    cpiece = malloc((nf + 1) * sizeof *cpiece);         /* by component: a piece of it */
    uint32_t *croot = malloc((nf + 1) * sizeof *croot); /* by face root: component */
    if (!outer || !cpiece || !croot) {
        free(croot);
        goto done;
    }
    for (size_t f = 0; f < nf; f++) croot[f] = NONE;
    for (size_t f = 0; f < nf; f++) {
        uint32_t r = a3_uf_find(fcomp, (uint32_t)f);
        if (croot[r] == NONE) {
            croot[r] = (uint32_t)ncomp;
            outer[ncomp] = NONE;
            cpiece[ncomp] = NONE;
            ncomp++;
        }
    }
    for (size_t f = 0; f < nf; f++) sp[2 * f] = a3_uf_find(fcomp, (uint32_t)f); /* roots */
    for (size_t f = 0; f < nf; f++) fcomp[f] = croot[sp[2 * f]];
    free(croot);
    for (size_t f = 0; f < nf; f++) {
        uint32_t c = fcomp[f];
        for (uint32_t i = A->f_cov[f]; i < A->f_cov[f + 1]; i++)
            if (cpiece[c] == NONE || A->cov[i] < cpiece[c]) cpiece[c] = A->cov[i];
    }
    A->st->shells = nsh;
    {
        /* reported: parts connected through any shared vertex (solids that touch at a point are
         * one); the probes below work on parts connected through edges */
        uint32_t *vf = malloc((A->npt + 1) * sizeof *vf), *vu = malloc((ncomp + 1) * sizeof *vu);
        if (!vf || !vu) {
            free(vf), free(vu);
            goto done;
        }
        for (size_t p = 0; p < A->npt; p++) vf[p] = NONE;
        for (size_t c = 0; c < ncomp; c++) vu[c] = (uint32_t)c;
        for (size_t f = 0; f < nf; f++)
            for (uint32_t e = A->cyc_off[A->f_cyc[f]]; e < A->cyc_off[A->f_cyc[f + 1]]; e++) {
                uint32_t p = A->ent[e];
                if (vf[p] == NONE)
                    vf[p] = fcomp[f];
                else
                    a3_uf_union(vu, vf[p], fcomp[f]);
            }
        size_t nvc = 0;
        for (size_t c = 0; c < ncomp; c++) nvc += a3_uf_find(vu, (uint32_t)c) == c;
        free(vf);
        free(vu);
        A->st->components = nvc;
    }
    /* the cells: union-find over the shells and the exterior */
    a3_progress(A, "cells", 0.38);
    cu = malloc((nsh + 2) * sizeof *cu); /* union-find over shells + the exterior */
    if (!cu) goto done;
    for (size_t s = 0; s <= nsh; s++) cu[s] = (uint32_t)s;
    uint32_t EXT = (uint32_t)nsh;
    /* pass 1: each part's probe, its first own face (beyond it, toward -k, lies its outside:
     * outer[c]), and the faces of other parts beyond that, to be walked in pass 2 */
    /* faces by their first covering piece (a face lies inside each piece covering it, so
     * inside that piece's box): the probes find faces through the pieces' boxes */
    pf_off = calloc(A->npc + 2, sizeof *pf_off);
    pf = malloc((nf + 1) * sizeof *pf);
    if (!pf_off || !pf) goto done;
    for (size_t f = 0; f < nf; f++) pf_off[A->cov[A->f_cov[f]] + 2]++;
    for (size_t q = 0; q < A->npc; q++) pf_off[q + 2] += pf_off[q + 1];
    for (size_t f = 0; f < nf; f++) pf[pf_off[A->cov[A->f_cov[f]] + 1]++] = (uint32_t)f;
    probes = malloc((ncomp + 1) * sizeof *probes);
    hoff = calloc(ncomp + 2, sizeof *hoff);
    if (!probes || !hoff) goto done;
    size_t nhit = 0;
    for (size_t c = 0; c < ncomp; c++) {
        probe *pr = &probes[c];
        int pk, r = piece_tris(A, cpiece[c], &ptri, &nptri, &capptri, &pk);
        if (r == -1) goto done;
        if (r) {
            rc = ARR_EINTERNAL;
            snprintf(err, errlen, "solids: no point found inside input face %u",
                     A->pc[cpiece[c]].face);
            goto done;
        }
        /* the centroid of the piece's first triangle, or of the next one while the line misses
         * every face of the part: a piece whose inside is in two parts (holes touching each
         * other and the outer cycle across it) may lie in two parts of the complex */
        uint32_t own = NONE;
        size_t h0 = nhit;
        for (size_t t = 0; t < nptri && own == NONE; t++) {
            tri_probe(A, ptri + 3 * t, pk, pr);
            nhit = h0;
            if (!fgk[pr->k].off) { /* the pieces' boxes in this probe's projection, and a grid:
                                       once per axis (parts alternate between axes) */
                fbox = fboxk[pr->k] = malloc((4 * A->npc + 1) * sizeof *fbox);
                if (!fbox) goto done;
                for (size_t q = 0; q < A->npc; q++) {
                    const int32_t *b = A->pc[q].box;
                    double *bx = fbox + 4 * q;
                    bx[0] = (double)b[pr->i], bx[1] = (double)b[pr->j];
                    bx[2] = (double)b[3 + pr->i], bx[3] = (double)b[3 + pr->j];
                    /* widened by more than the rounding of the conversions */
                    double m =
                        (fabs(bx[0]) + fabs(bx[2]) + fabs(bx[1]) + fabs(bx[3]) + 1) * 0x1p-40;
                    bx[0] -= m, bx[1] -= m, bx[2] += m, bx[3] += m;
                }
                if (fgrid_build(&fgk[pr->k], fbox, A->npc)) goto done;
            }
            const fgrid *fg = &fgk[pr->k];
            double qi = (double)pr->Q[pr->i] / 3, qj = (double)pr->Q[pr->j] / 3;
            size_t ncand, nff = 0;
            if (fgrid_query(fg, qi, qj, &cand, &capcand, &ncand)) goto done;
            /* the faces of the pieces whose boxes hold the point (exactly: Q / 3 in [lo, hi]) */
            for (size_t ci = 0; ci < ncand; ci++) {
                const int32_t *b = A->pc[cand[ci]].box;
                if ((i128)pr->Q[pr->i] < (i128)3 * b[pr->i] ||
                    (i128)pr->Q[pr->i] > (i128)3 * b[3 + pr->i] ||
                    (i128)pr->Q[pr->j] < (i128)3 * b[pr->j] ||
                    (i128)pr->Q[pr->j] > (i128)3 * b[3 + pr->j])
                    continue;
                uint32_t n = pf_off[cand[ci] + 1] - pf_off[cand[ci]];
                if (a3_grow(&ff, &capff, nff + n + 1, sizeof *ff)) goto done;
                memcpy(ff + nff, pf + pf_off[cand[ci]], n * sizeof *ff);
                nff += n;
            }
            if (nff > 1) qsort(ff, nff, sizeof *ff, a3_cmp_u32);
            for (size_t ci = 0; ci < nff; ci++) {
                uint32_t f = ff[ci];
                if (fcomp[f] != c && ncomp == 1) continue;
                if (!probe_hits(A, f, pr)) continue;
                if (fcomp[f] == c) {
                    if (own == NONE || probe_cmp(A, f, own, pr) < 0) own = f;
                } else {
                    if (a3_grow(&hits, &caphits, nhit + 1, sizeof *hits)) goto done;
                    hits[nhit++] = f;
                }
            }
        }
        if (own == NONE) {
            rc = ARR_EINTERNAL;
            snprintf(err, errlen, "solids: a part's own ray hits none of its faces (a bug)");
            goto done;
        }
        plane3 town;
        int up = a3_face_plane(A, own, &town)->n[pr->k] > 0;
        outer[c] = shell[2 * own + (up ? 1 : 0)]; /* the side facing -k */
        size_t m = h0;
        for (size_t h = h0; h < nhit; h++)
            if (probe_cmp(A, hits[h], own, pr) < 0) hits[m++] = hits[h];
        nhit = m;
        hoff[c + 1] = (uint32_t)nhit;
    }
    a3_progress(A, "cells", 0.41);
    /* pass 2: walk down each part's ray from just beyond its first face.  Entering another
     * part from its outside (the side we come from is that part's outer shell) and leaving it
     * again are skipped (a stack of parts); the first face met outside every part whose side
     * toward us is not an outer shell is the wall of the cell holding the part.  No such face:
     * the part lies in the exterior. */
    for (size_t c = 0; c < ncomp; c++) {
        probe *pr = &probes[c];
        uint32_t *H = hits ? hits + hoff[c] : NULL, nh = hoff[c + 1] - hoff[c], host = EXT;
        size_t depth = 0;
        if (nh > 1) qsort_r(H, nh, sizeof *H, probe_desc, &(probe_sort){A, pr});
        for (uint32_t h = 0; h < nh && host == EXT; h++) {
            uint32_t f = H[h], d = fcomp[f];
            plane3 tf;
            int fup = a3_face_plane(A, f, &tf)->n[pr->k] > 0;
            uint32_t s_up = shell[2 * f + (fup ? 0 : 1)], s_down = shell[2 * f + (fup ? 1 : 0)];
            if (depth && s_down == outer[stack[depth - 1]] && d == stack[depth - 1]) {
                depth--; /* leaving the part we were inside */
                continue;
            }
            if (s_up == outer[d]) { /* entering part d from its outside */
                if (a3_grow(&stack, &capstack, depth + 1, sizeof *stack)) goto done;
                stack[depth++] = d;
                continue;
            }
            if (!depth) host = s_up;
        }
        a3_uf_union(cu, outer[c], host);
    }
    /* cells: classes of shells; the one holding EXT is the exterior */
    cell = malloc((nsh + 2) * sizeof *cell);
    if (!cell) goto done;
    size_t nc = 0;
    for (size_t s = 0; s <= nsh; s++) cell[s] = NONE;
    uint32_t ext_root = a3_uf_find(cu, EXT);
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t r = a3_uf_find(cu, shell[i]);
        if (r == ext_root || cell[r] != NONE) continue;
        cell[r] = (uint32_t)nc++;
    }
    /* closed solids: every face separates its solids' inside from their outside, so its two
     * sides lie in two cells; one cell on both sides means a surface that passes through
     * itself (an input that intersects itself, or that the grid makes so) */
    for (size_t f = 0; f < nf && !A->soup; f++) {
        if (a3_uf_find(cu, shell[2 * f]) != a3_uf_find(cu, shell[2 * f + 1])) continue;
        const piece *pc = &A->pc[A->cov[A->f_cov[f]]];
        const xpt *x = &A->pt[A->ent[A->cyc_off[A->f_cyc[f]]]];
        rc = ARR_EINVAL;
        snprintf(err, errlen,
                 "solids[%u]: face %u: the surface passes through itself near (%.9g, %.9g, %.9g): "
                 "the solid intersects itself on the grid of step %g",
                 pc->solid, pc->face - out->solid_face_off[pc->solid],
                 ((double)A->oi[0] + x->x[0]) * A->step, ((double)A->oi[1] + x->x[1]) * A->step,
                 ((double)A->oi[2] + x->x[2]) * A->step, A->step);
        goto done;
    }
    /* the points to 2^-100 (volumes and the written coordinates come from these) */
    dh = malloc((3 * A->npt + 1) * sizeof *dh);
    dl = malloc((3 * A->npt + 1) * sizeof *dl);
    if (!dh || !dl) goto done;
    for (size_t p = 0; p < A->npt; p++) dh[3 * p] = NAN;                /* not wanted */
    for (size_t i = 0; i < A->nent; i++) dh[3 * (size_t)A->ent[i]] = 0; /* wanted */
    {
        ddjob j = {A, dh, dl, NULL, 0};
        a3_span span = {A, "cells", 0.41, 0.45};
        par_for_ex(A->threads, (A->npt + DD_CHUNK - 1) / DD_CHUNK, points_dd, &j, a3_span_tick,
                   &span);
    }
    out->nc = nc;
    out->cf_off = calloc(nc + 1, sizeof *out->cf_off);
    out->cvol = calloc(nc + 1, sizeof *out->cvol);
    if (!out->cf_off || !out->cvol) goto done;
    size_t next = 0;
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t r = a3_uf_find(cu, shell[i]), o = a3_uf_find(cu, shell[i ^ 1]);
        if (r == o) continue; /* both sides in one cell: not on its boundary */
        if (r == ext_root)
            next++;
        else
            out->cf_off[cell[r] + 1]++;
    }
    for (size_t k = 0; k < nc; k++) out->cf_off[k + 1] += out->cf_off[k];
    out->cf = malloc((out->cf_off[nc] + 1) * sizeof *out->cf);
    out->ext = malloc((next + 1) * sizeof *out->ext);
    uint32_t *fill = calloc(nc + 1, sizeof *fill);
    if (!out->cf || !out->ext || !fill) {
        free(fill);
        goto done;
    }
    out->next = 0;
    double h3 = A->step * A->step * A->step / 6;
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t r = a3_uf_find(cu, shell[i]);
        if (r == a3_uf_find(cu, shell[i ^ 1])) continue;
        /* the - side's cell has the normal pointing out of it: +(f+1) */
        int32_t sf = (i & 1) ? (int32_t)(i / 2 + 1) : -(int32_t)(i / 2 + 1);
        if (r == ext_root) {
            out->ext[out->next++] = sf;
        } else {
            uint32_t k = cell[r];
            out->cf[out->cf_off[k] + fill[k]++] = sf;
        }
    }
    {
        ddjob j = {A, dh, dl, out, h3};
        a3_span span = {A, "cells", 0.45, 0.5};
        par_for_ex(A->threads, (nc + DD_CHUNK - 1) / DD_CHUNK, cells_volume, &j, a3_span_tick,
                   &span);
    }
    free(fill);
    /* ---- output: vertices sorted by position, edges sorted, faces */
    newid = malloc((A->npt + 1) * sizeof *newid);
    used = malloc((A->npt + 1) * sizeof *used);
    if (!newid || !used) goto done;
    for (size_t p = 0; p < A->npt; p++) newid[p] = NONE;
    size_t nu = 0;
    for (size_t i = 0; i < A->nent; i++)
        if (newid[A->ent[i]] == NONE) newid[A->ent[i]] = 0, used[nu++] = A->ent[i];
    if (nu > 1) qsort_r(used, nu, sizeof *used, vcmp, A);
    for (size_t i = 0; i < nu; i++) newid[used[i]] = (uint32_t)i;
    a3_progress(A, "cells", 0.54);
    out->nv = nu;
    out->V = malloc((3 * nu + 1) * sizeof *out->V);
    if (!out->V) goto done;
    for (size_t i = 0; i < nu; i++)
        for (int k = 0; k < 3; k++)
            out->V[3 * i + k] =
                ((double)A->oi[k] + dh[3 * (size_t)used[i] + k] + dl[3 * (size_t)used[i] + k]) *
                A->step;
    ek = malloc((ne + 1) * sizeof *ek);
    if (!ek) goto done;
    for (size_t e = 0; e < ne; e++) {
        uint32_t a = newid[ev[2 * e]], b = newid[ev[2 * e + 1]];
        ek[e] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
    }
    out->ne = ne;
    out->EV = malloc((2 * ne + 1) * sizeof *out->EV);
    if (!out->EV) goto done;
    {
        /* edges in the order of their new keys: LSD radix sort of the old ids by key, skipping
         * the bytes every key shares; newe[old] = new id */
        uint32_t *idx = malloc((ne + 1) * sizeof *idx), *buf = malloc((ne + 1) * sizeof *buf);
        uint32_t *newe = malloc((ne + 1) * sizeof *newe);
        if (!idx || !buf || !newe) {
            free(idx), free(buf), free(newe);
            goto done;
        }
        uint64_t all_or = 0, all_and = ~(uint64_t)0;
        for (size_t e = 0; e < ne; e++) idx[e] = (uint32_t)e, all_or |= ek[e], all_and &= ek[e];
        for (int pass = 0; pass < 8; pass++) {
            int sh = 8 * pass;
            if (((all_or ^ all_and) >> sh & 255) == 0) continue;
            size_t cnt[257] = {0};
            for (size_t i = 0; i < ne; i++) cnt[((ek[idx[i]] >> sh) & 255) + 1]++;
            for (int q = 0; q < 256; q++) cnt[q + 1] += cnt[q];
            for (size_t i = 0; i < ne; i++) buf[cnt[(ek[idx[i]] >> sh) & 255]++] = idx[i];
            uint32_t *t = idx;
            idx = buf, buf = t;
        }
        for (size_t i = 0; i < ne; i++) {
            out->EV[2 * i] = (uint32_t)(ek[idx[i]] >> 32);
            out->EV[2 * i + 1] = (uint32_t)ek[idx[i]];
            newe[idx[i]] = (uint32_t)i;
        }
        free(idx), free(buf);
        a3_progress(A, "cells", 0.58);
        /* faces */
        out->nf = nf;
        out->FN = malloc((3 * nf + 1) * sizeof *out->FN);
        out->fc_off = malloc((nf + 1) * sizeof *out->fc_off);
        out->fc = malloc((A->ncyc + 1) * sizeof *out->fc);
        out->fe_off = malloc((nf + 1) * sizeof *out->fe_off);
        out->fe = malloc((A->nent + 1) * sizeof *out->fe);
        out->fsrc = malloc((nf + 1) * sizeof *out->fsrc);
        out->ncyc = A->ncyc;
        out->cyc_off = malloc((A->ncyc + 1) * sizeof *out->cyc_off);
        out->cyc = malloc((A->nent + 1) * sizeof *out->cyc);
        out->fsol_off = malloc((nf + 1) * sizeof *out->fsol_off);
        out->fsol = malloc((A->f_cov[nf] + 1) * sizeof *out->fsol);
        if (!out->FN || !out->fc_off || !out->fc || !out->fe_off || !out->fe || !out->fsrc ||
            !out->cyc_off || !out->cyc || !out->fsol_off || !out->fsol) {
            free(newe);
            goto done;
        }
        size_t nfe = 0, nfs = 0;
        out->fc_off[0] = out->fe_off[0] = out->fsol_off[0] = 0;
        for (size_t f = 0; f < nf; f++) {
            plane3 tp;
            const plane3 *P = a3_face_plane(A, (uint32_t)f, &tp);
            double len = sqrt(P->nd[0] * P->nd[0] + P->nd[1] * P->nd[1] + P->nd[2] * P->nd[2]);
            for (int k = 0; k < 3; k++) out->FN[3 * f + k] = P->nd[k] / len;
            out->fsrc[f] = A->pc[A->cov[A->f_cov[f]]].face;
            for (uint32_t cy = A->f_cyc[f]; cy < A->f_cyc[f + 1]; cy++) {
                out->fc[cy] = cy;
                uint32_t o = A->cyc_off[cy], n = A->cyc_off[cy + 1] - o;
                if (n < 2) continue;
                for (uint32_t t = 0; t < n; t++) {
                    uint32_t a = newid[A->ent[o + t]], b = newid[A->ent[o + (t + 1) % n]];
                    uint32_t e = newe[ent_e[o + t]];
                    out->fe[nfe++] = a < b ? (int32_t)(e + 1) : -(int32_t)(e + 1);
                }
            }
            out->fc_off[f + 1] = A->f_cyc[f + 1];
            out->fe_off[f + 1] = (uint32_t)nfe;
            /* solids covering f an odd number of times */
            size_t s0 = nfs;
            for (uint32_t i = A->f_cov[f]; i < A->f_cov[f + 1]; i++)
                out->fsol[nfs++] = A->pc[A->cov[i]].solid;
            if (nfs - s0 > 1) qsort(out->fsol + s0, nfs - s0, sizeof *out->fsol, cmpu32);
            size_t m = s0;
            for (size_t i = s0; i < nfs;) {
                size_t j = i;
                while (j < nfs && out->fsol[j] == out->fsol[i]) j++;
                if ((j - i) & 1) out->fsol[m++] = out->fsol[i];
                i = j;
            }
            nfs = m;
            out->fsol_off[f + 1] = (uint32_t)nfs;
        }
        free(newe);
        for (size_t cy = 0; cy <= A->ncyc; cy++) out->cyc_off[cy] = A->cyc_off[cy];
        for (size_t i = 0; i < A->nent; i++) out->cyc[i] = newid[A->ent[i]];
    }
    a3_progress(A, "cells", 0.65);
    /* CV: sorted vertices of each cell's faces (each once: a stamp per vertex; a large cell is
     * read off in vertex order, a small one sorted); CF rows sorted */
    out->cv_off = calloc(nc + 1, sizeof *out->cv_off);
    if (!out->cv_off) goto done;
    {
        uint32_t *cv = NULL, *stamp = calloc(out->nv + 1, sizeof *stamp);
        size_t ncv = 0, capcv = 0, step = nc / 50 + 1;
        if (!stamp) goto done;
        for (size_t k = 0; k < nc; k++) {
            size_t start = ncv;
            if (k % step == 0) a3_progress(A, "cells", 0.65 + 0.35 * (double)k / (double)nc);
            for (uint32_t i = out->cf_off[k]; i < out->cf_off[k + 1]; i++) {
                uint32_t f = (uint32_t)abs(out->cf[i]) - 1;
                for (uint32_t cy = out->fc_off[f]; cy < out->fc_off[f + 1]; cy++)
                    for (uint32_t j = out->cyc_off[cy]; j < out->cyc_off[cy + 1]; j++) {
                        uint32_t v = out->cyc[j];
                        if (stamp[v] == k + 1) continue;
                        stamp[v] = (uint32_t)k + 1;
                        if (A3_PUSH(cv, ncv, capcv, v)) {
                            free(stamp), free(cv);
                            goto done;
                        }
                    }
            }
            size_t m = ncv - start;
            if (m > out->nv / 16) {
                size_t w = start;
                for (uint32_t v = 0; v < out->nv; v++)
                    if (stamp[v] == k + 1) cv[w++] = v;
            } else if (m > 1) {
                qsort(cv + start, m, sizeof *cv, cmpu32);
            }
            out->cv_off[k + 1] = (uint32_t)ncv;
            if (out->cf_off[k + 1] - out->cf_off[k] > 1)
                qsort(out->cf + out->cf_off[k], out->cf_off[k + 1] - out->cf_off[k],
                      sizeof *out->cf, cmpi32);
        }
        free(stamp);
        out->cv = cv ? cv : malloc(sizeof *out->cv);
        if (!out->cv) goto done;
    }
    if (out->next > 1) qsort(out->ext, out->next, sizeof *out->ext, cmpi32);
    out->stats.nv = out->nv;
    out->stats.ne = out->ne;
    out->stats.nf = out->nf;
    out->stats.nc = out->nc;
    rc = ARR_OK;
done:
    if (rc == ARR_ENOMEM && err && errlen) snprintf(err, errlen, "out of memory");
    free(I);
    free(ev);
    free(eside);
    free(eface);
    free(ioff);
    free(sp);
    free(fcomp);
    free(shell);
    free(cu);
    free(cell);
    free(outer);
    free(cpiece);
    free(ptri);
    free(newid);
    free(used);
    free(dh);
    free(dl);
    for (int k = 0; k < 3; k++) {
        fgrid_free(&fgk[k]);
        free(fboxk[k]);
    }
    free(cand);
    free(pf_off);
    free(pf);
    free(ff);
    free(hits);
    free(hoff);
    free(stack);
    free(probes);
    free(ek);
    free(ent_e);
    return rc;
}
