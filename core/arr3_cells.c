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
 * The probes find the faces they may hit through the box index of core/box.h over the input
 * pieces' boxes in the probe's projection (a face lies inside each piece covering it).  Every
 * predicate here (the fans' det3_sign and dot signs, the probes' xpt_cmp_q3_exact,
 * axis_plane_side_exact and cmp_frac_exact) is core/pred.c's: this file holds no error bound.
 *
 * Stages, each a function with its contract: edges_make, fans_make, shells_make, nesting_make
 * (pindex_make, probe_candidates, part_probe, part_host), cells_make (cells_number,
 * cells_units, cells_check_sides, cells_cf, cells_points, volumes_grid, cells_volumes) and
 * output_make (output_points, output_edges, output_cycles, out_faces, output_fsol_close,
 * output_cv); a3_cells runs them in order with a cancel point between each.
 *
 * Volumes are sums of cones over the faces' cycles from the points' approximations (each within
 * 2^-50 of the exact point), so a cell's volume is exact up to rounding.
 *
 * Threads: the edges' fans, the points' approximations and the cells' volumes run on par_for()
 * in fixed chunks, each writing only its own items; the rest runs on the calling thread.
 */
#include "core/arr3_int.h"
#include "core/box.h"
#include "core/mem.h"
#include "core/par.h"
#include "core/sort.h"
#include "core/util.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* ---- small tools ------------------------------------------------------------------------ */

static int sgn128(i128 v)
{
    return (v > 0) - (v < 0);
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

/* The normal of face f (its anchor plane's when it has no canonical plane), in tmp->n. */
static const int64_t *face_n(const a3 *A, uint32_t f, plane3 *tmp)
{
    a3_face_normal(A, f, tmp->n);
    return tmp->n;
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

/* For solids: around an edge, each solid's winding number changes face by face.  Face f
 * (walking the edge s = +-1) has its side s toward the next wedge counter-clockwise; a piece
 * covering it, of outward orientation g about f's normal, enters its solid toward the next
 * wedge when s != g (+1) and leaves it when s == g (-1).  Two pieces of one solid on one face
 * turning opposite ways (a surface touching itself face to face: an inner wall) add up to 0.
 * Its surface closed, every solid comes back around the edge to the winding number it started
 * with (a surface passing through itself there has been cut into faces meeting at the edge,
 * and may wind 2 or more, or below 0, between them); one that does not is reported with where
 * (a bug: the check found every surface closed). */
typedef struct fanside {
    uint32_t solid;
    int w;       /* winding after the last face, relative to the first wedge */
    int dw;      /* of the current face */
    size_t face; /* the face dw belongs to */
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
        }
        if (k == n) break;
        uint32_t f = F[k].f;
        for (uint32_t i = A->f_cov[f]; i < A->f_cov[f + 1]; i++) {
            const piece *pc = &A->pc[A->cov[i]];
            size_t j = 0;
            while (j < ns && st[j].solid != pc->solid) j++;
            if (j == ns) {
                if (ns == sizeof st / sizeof *st) continue; /* only in a pile of 8 solids */
                st[ns] = (fanside){pc->solid, 0, 0, k};
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
             "solids[%u]: face %u: the surface is not closed about the edge (%.9g, %.9g, "
             "%.9g)-(%.9g, %.9g, %.9g) on the grid of step %g (a bug: please report it)",
             pc->solid, pc->face - out->solid_face_off[pc->solid],
             ((double)A->oi[0] + a->x[0]) * A->step, ((double)A->oi[1] + a->x[1]) * A->step,
             ((double)A->oi[2] + a->x[2]) * A->step, ((double)A->oi[0] + b->x[0]) * A->step,
             ((double)A->oi[1] + b->x[1]) * A->step, ((double)A->oi[2] + b->x[2]) * A->step,
             A->step);
    return ARR_EINTERNAL;
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
    if (A->soup) return ARR_OK;
    if (n == 2 && A->f_cov[F[0].f + 1] - A->f_cov[F[0].f] == 1 &&
        A->f_cov[F[1].f + 1] - A->f_cov[F[1].f] == 1) {
        /* two faces of one piece each (most edges): a solid's winding goes up across one and
         * down across the other, or the surface passes through itself */
        const piece *p0 = &A->pc[A->cov[A->f_cov[F[0].f]]], *p1 = &A->pc[A->cov[A->f_cov[F[1].f]]];
        if (p0->solid == p1->solid && (F[0].s != p0->sgn) != (F[1].s != p1->sgn)) return ARR_OK;
    }
    return fan_check(A, F, n, ev + 2 * e, j->out, err, errlen);
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
        /* each point's side of the line's j coordinate, once: an edge's end is the next's
         * start */
        int s0 = xpt_cmp_q3_exact(&A->G, &A->pt[A->ent[o]], pr->j, pr->Q[pr->j]) > 0, sb = s0;
        for (uint32_t t = 0; t < n; t++) {
            uint32_t a = A->ent[o + t], b = A->ent[o + (t + 1) % n], S = A->side[o + t];
            int sa = sb;
            sb = t + 1 < n ? xpt_cmp_q3_exact(&A->G, &A->pt[b], pr->j, pr->Q[pr->j]) > 0 : s0;
            if (sa == sb || S == NONE) continue;
            plane3 tmp;
            const plane3 *SP = a3_side(A, P, a, b, S, &tmp);
            if (!SP) continue;
            int si, s = axis_plane_side_exact(P, SP, pr->k, pr->Q, &si);
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
    int c = cmp_frac_exact(nf, df, ng, dg);
    if (c) return c;
    c = cmp_frac_exact(-F->n[pr->i], F->n[pr->k], -G->n[pr->i], G->n[pr->k]);
    if (c) return c;
    return cmp_frac_exact(-F->n[pr->j], F->n[pr->k], -G->n[pr->j], G->n[pr->k]);
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
        cp = mem_malloc(pc->nc * sizeof *cp);
        lp = mem_malloc(pc->nc * sizeof *lp);
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

/* ---- the probes' index ----------------------------------------------------------------------
 * Which faces may a ray along -k through (Q_i, Q_j) / 3 cross?  Those whose covering pieces'
 * boxes hold the point in projection (a face lies inside each piece covering it).  Few parts:
 * every face is looked at.  Many: a box index (core/box.h) over the pieces' boxes projected
 * along k, scaled by 3 so that the point Q is exact as doubles and the leaf box_tree_locate
 * gives holds every box containing it (no margin); its boxes are then tested exactly and their
 * pieces' faces taken (a list of faces by first piece).  Built once per axis, when a probe first
 * needs it.  Only a filter: probe_hits decides. */
#define PROBE_LEAF 256 /* boxes a leaf aimed at: few probes query many boxes */

typedef struct pindex {
    int use_tree;          /* 0: every face is a candidate */
    uint32_t *pf_off, *pf; /* the faces by their first piece: pf[pf_off[q] .. pf_off[q + 1]) */
    box_tree tree[3];      /* by axis k: the pieces' boxes projected along k (dim 0: not built) */
} pindex;

static void pindex_free(pindex *X)
{
    free(X->pf_off), free(X->pf);
    for (int k = 0; k < 3; k++) box_tree_free(&X->tree[k]);
    memset(X, 0, sizeof *X);
}

/* The index of the probes: the tree when there are more than 8 parts.  -1 out of memory. */
static int pindex_make(const a3 *A, size_t ncomp, pindex *X)
{
    size_t nf = A->nf;
    memset(X, 0, sizeof *X);
    X->use_tree = ncomp > 8;
    if (!X->use_tree) return 0;
    X->pf_off = mem_calloc(A->npc + 2, sizeof *X->pf_off);
    X->pf = mem_malloc((nf + 1) * sizeof *X->pf);
    if (!X->pf_off || !X->pf) return -1;
    for (size_t f = 0; f < nf; f++) X->pf_off[A->cov[A->f_cov[f]] + 2]++;
    for (size_t q = 0; q < A->npc; q++) X->pf_off[q + 2] += X->pf_off[q + 1];
    for (size_t f = 0; f < nf; f++) X->pf[X->pf_off[A->cov[A->f_cov[f]] + 1]++] = (uint32_t)f;
    return 0;
}

/* The tree of axis k, built on first use.  -1 out of memory. */
static int pindex_tree(const a3 *A, pindex *X, int k)
{
    if (X->tree[k].dim) return 0;
    int i = (k + 1) % 3, j = (k + 2) % 3;
    int64_t *box = mem_malloc((4 * A->npc + 1) * sizeof *box);
    if (!box) return -1;
    for (size_t q = 0; q < A->npc; q++) {
        const int32_t *b = A->pc[q].box;
        int64_t *bx = box + 4 * q;
        bx[0] = 3 * (int64_t)b[i], bx[1] = 3 * (int64_t)b[j];
        bx[2] = 3 * (int64_t)b[3 + i], bx[3] = 3 * (int64_t)b[3 + j];
    }
    int rc = box_tree_build_dim(&X->tree[k], 2, box, A->npc, PROBE_LEAF, 1);
    free(box);
    return rc;
}

/* Does piece q's box hold the probe's point in projection? (exact) */
static inline int box_holds(const int32_t *b, const probe *pr)
{
    return (int64_t)pr->Q[pr->i] >= 3 * (int64_t)b[pr->i] &&
           (int64_t)pr->Q[pr->i] <= 3 * (int64_t)b[3 + pr->i] &&
           (int64_t)pr->Q[pr->j] >= 3 * (int64_t)b[pr->j] &&
           (int64_t)pr->Q[pr->j] <= 3 * (int64_t)b[3 + pr->j];
}

/* The faces the probe's ray may cross, ascending, into *ff (grown as needed).  -1 out of
 * memory. */
static int probe_candidates(const a3 *A, pindex *X, const probe *pr, uint32_t **ff, size_t *capff,
                            size_t *nff)
{
    size_t n = 0;
    if (!X->use_tree) {
        for (size_t f = 0; f < A->nf; f++)
            if (box_holds(A->pc[A->cov[A->f_cov[f]]].box, pr) &&
                A3_PUSH(*ff, n, *capff, (uint32_t)f))
                return -1;
        *nff = n;
        return 0;
    }
    if (pindex_tree(A, X, pr->k)) return -1;
    const box_tree *t = &X->tree[pr->k];
    double q[2] = {(double)pr->Q[pr->i], (double)pr->Q[pr->j]};
    uint32_t l = box_tree_locate_pt(t, q);
    for (uint32_t x = t->leaf_off[l]; x < t->leaf_off[l + 1]; x++) {
        uint32_t pc = t->items[x], m = X->pf_off[pc + 1] - X->pf_off[pc];
        if (!box_holds(A->pc[pc].box, pr)) continue;
        if (mem_grow(ff, capff, n + m + 1, sizeof **ff)) return -1;
        memcpy(*ff + n, X->pf + X->pf_off[pc], m * sizeof **ff);
        n += m;
    }
    if (n > 1) qsort(*ff, n, sizeof **ff, u32_cmp);
    *nff = n;
    return 0;
}

/* ==== the stages ====================================================================== *
 * Each stage reads what the ones before made and makes one typed product; the faces that the
 * arrangement kept whole (most of them, where nothing reaches) cost each stage a few linear
 * passes and no predicate:
 *   edges     the cycle entries grouped by edge (a counting sort by lower endpoint)
 *   fans      the faces about every edge of three or more, sorted; windings checked
 *   shells    face sides linked across the edges; parts linked through edges
 *   nesting   each part's outside shell and the cell holding it, by exact probes
 *   cells     shells into cells, each cell's faces, volumes
 *   output    the lar3: vertices sorted by position, edges sorted, faces, cells' vertices */

typedef struct cedges {
    size_t ne;
    uint32_t *ev;    /* 2 ne: lower and higher point */
    uint32_t *eface; /* ne: a face on the edge (with eside: the edge's line) */
    uint32_t *eside; /* ne: that face's side plane entry of the edge */
    uint32_t *ioff;  /* ne + 1: the edge's incidences I[ioff[e] .. ioff[e + 1]) */
    inc *I;
    uint32_t *ent_e; /* by cycle entry: the edge to the next entry (NONE: a cycle of one point) */
} cedges;

static void cedges_free(cedges *E)
{
    free(E->ev), free(E->eface), free(E->eside), free(E->ioff), free(E->I), free(E->ent_e);
    memset(E, 0, sizeof *E);
}

/* The entries whose edges are not inside a patch (those are made with the output), in chunks of
 * faces on the threads: a chunk writes them from its own first entry on (there are no more of
 * them than its entries), and their count; edges_make closes the gaps in chunk order. */
#define EDGE_CHUNK 8192 /* faces */
typedef struct edgejob {
    const a3 *A;
    uint32_t *xs, *xf, *lo_e, *hi_e; /* by entry: the entry, its face, its edge's two ends */
    uint32_t *ent_e;
    uint32_t *cnt; /* by chunk */
} edgejob;

static void edge_scan(void *ctx, size_t item, int worker)
{
    (void)worker;
    const edgejob *j = ctx;
    const a3 *A = j->A;
    size_t f0 = item * EDGE_CHUNK, f1 = f0 + EDGE_CHUNK < A->nf ? f0 + EDGE_CHUNK : A->nf;
    uint32_t at = A->cyc_off[A->f_cyc[f0]], m = at;
    memset(j->ent_e + at, 0xff, (A->cyc_off[A->f_cyc[f1]] - at) * sizeof *j->ent_e);
    for (size_t f = f0; f < f1; f++)
        for (uint32_t cy = A->f_cyc[f]; cy < A->f_cyc[f + 1]; cy++) {
            uint32_t o = A->cyc_off[cy], n = A->cyc_off[cy + 1] - o;
            if (n < 2) continue;
            for (uint32_t t = 0; t < n; t++) {
                uint32_t x = o + t;
                if (A->etwin[x] != NONE) continue;
                uint32_t a = A->ent[x], b = A->ent[t + 1 < n ? x + 1 : o];
                uint32_t lo = a < b ? a : b;
                j->xs[m] = x, j->xf[m] = (uint32_t)f, j->lo_e[m] = lo, j->hi_e[m] = a ^ b ^ lo;
                m++;
            }
        }
    j->cnt[item] = m - at;
}

/* Stage "edges".  Returns -1 out of memory. */
A3_STAGE static int edges_make(const a3 *A, cedges *E)
{
    size_t npt = A->npt, nent = A->nent, nf = A->nf, nch = (nf + EDGE_CHUNK - 1) / EDGE_CHUNK;
    uint32_t *pos = mem_calloc(npt + 2, sizeof *pos), *xs = mem_malloc((nent + 1) * sizeof *xs);
    uint32_t *lo_e = mem_malloc((nent + 1) * sizeof *lo_e),
             *hi_e = mem_malloc((nent + 1) * sizeof *hi_e);
    uint32_t *xf = mem_malloc((nent + 1) * sizeof *xf), *cnt = mem_malloc((nch + 1) * sizeof *cnt);
    uint32_t *sk = NULL, *sx = NULL;
    int rc = -1;
    E->ent_e = mem_malloc((nent + 1) * sizeof *E->ent_e);
    if (!pos || !xs || !lo_e || !hi_e || !xf || !cnt || !E->ent_e) goto done;
    E->ent_e[nent] = NONE;
    edgejob ej = {A, xs, xf, lo_e, hi_e, E->ent_e, cnt};
    par_for(A->threads, nch, edge_scan, &ej);
    /* the chunks' entries joined in order (so the entries of an edge come in face order), by
     * their edge's lower end */
    size_t m = 0;
    for (size_t ch = 0; ch < nch; ch++) {
        uint32_t at = A->cyc_off[A->f_cyc[ch * EDGE_CHUNK]], c = cnt[ch];
        if (at != m) {
            memmove(xs + m, xs + at, c * sizeof *xs);
            memmove(xf + m, xf + at, c * sizeof *xf);
            memmove(lo_e + m, lo_e + at, c * sizeof *lo_e);
            memmove(hi_e + m, hi_e + at, c * sizeof *hi_e);
        }
        for (size_t i = m; i < m + c; i++) pos[lo_e[i] + 2]++;
        m += c;
    }
    for (size_t p = 0; p < npt; p++) pos[p + 2] += pos[p + 1];
    sk = mem_malloc((m + 1) * sizeof *sk);
    sx = mem_malloc((m + 1) * sizeof *sx);
    E->I = mem_malloc((m + 1) * sizeof *E->I);
    if (!sk || !sx || !E->I) goto done;
    for (size_t i = 0; i < m; i++) {
        uint32_t slot = pos[lo_e[i] + 1]++;
        sk[slot] = hi_e[i], sx[slot] = (uint32_t)i;
    }
    /* by lower endpoint, then by higher (insertion: a handful a point; stable, so the entries of
     * an edge stay in face order), then edges */
    size_t ne = 0;
    for (size_t p = 0; p < npt; p++) {
        uint32_t r0 = pos[p], r1 = pos[p + 1];
        for (uint32_t i = r0 + 1; i < r1; i++) {
            uint32_t k = sk[i], x = sx[i], j = i;
            for (; j > r0 && sk[j - 1] > k; j--) sk[j] = sk[j - 1], sx[j] = sx[j - 1];
            sk[j] = k, sx[j] = x;
        }
        for (uint32_t i = r0; i < r1; i++) ne += i == r0 || sk[i] != sk[i - 1];
    }
    E->ev = mem_malloc((2 * ne + 2) * sizeof *E->ev);
    E->eface = mem_malloc((ne + 1) * sizeof *E->eface);
    E->eside = mem_malloc((ne + 1) * sizeof *E->eside);
    E->ioff = mem_malloc((ne + 2) * sizeof *E->ioff);
    if (!E->ev || !E->eface || !E->eside || !E->ioff) goto done;
    ne = 0;
    for (size_t p = 0; p < npt; p++)
        for (uint32_t i = pos[p]; i < pos[p + 1]; i++) {
            uint32_t k = sx[i], x = xs[k];
            if (i == pos[p] || sk[i] != sk[i - 1]) {
                E->ev[2 * ne] = (uint32_t)p, E->ev[2 * ne + 1] = sk[i];
                E->eside[ne] = A->side[x];
                E->eface[ne] = xf[k];
                E->ioff[ne] = i;
                ne++;
            }
            E->I[i] = (inc){(uint32_t)ne - 1, xf[k], A->ent[x] == p ? 1 : -1};
            E->ent_e[x] = (uint32_t)ne - 1;
        }
    E->ioff[ne] = (uint32_t)m;
    E->ne = ne;
    rc = 0;
done:
    free(pos), free(xs), free(lo_e), free(hi_e), free(xf), free(cnt), free(sk), free(sx);
    return rc;
}

/* Stage "fans": every edge's faces sorted about it and its windings checked, in chunks on the
 * threads; the first failing edge is checked again here for its message. */
A3_STAGE static int fans_make(const a3 *A, cedges *E, const lar3 *out, char *err, size_t errlen)
{
    size_t nch = (E->ne + FAN_CHUNK - 1) / FAN_CHUNK;
    fanjob j = {A,     E->I,     E->ioff,
                E->ev, E->eside, E->eface,
                out,   E->ne,    mem_calloc(nch + 1, sizeof *j.bad)};
    if (!j.bad) return ARR_ENOMEM;
    a3_span span = {A, "cells", 0.1, 0.25};
    par_for_ex(A->threads, nch, fans_sort, &j, a3_span_tick, &span);
    size_t bad = SIZE_MAX;
    for (size_t ch = 0; ch < nch && bad == SIZE_MAX; ch++)
        if (j.bad[ch]) bad = j.bad[ch] - 1;
    free(j.bad);
    if (bad != SIZE_MAX) return fan_sort(&j, bad, err, errlen);
    return ARR_OK;
}

typedef struct cshells {
    uint32_t *shell; /* by node (2 a unit: its faces' sides, fnode()): its shell */
    size_t nsh;
    uint32_t *ucomp; /* by unit: its part (units linked through edges) */
    size_t ncomp;
    uint32_t *cpiece; /* ncomp: the lowest input piece covering a face of each part */
} cshells;

static void cshells_free(cshells *S)
{
    free(S->shell), free(S->ucomp), free(S->cpiece);
    memset(S, 0, sizeof *S);
}

/* The node of side s (0: the normal's side, 1: the other) of face f.  A patch has two nodes for
 * all its faces, 2u its solid's outside and 2u + 1 its inside (every edge inside a patch joins
 * two of its faces, walked both ways: their outward sides face one wedge, their inward sides
 * the other); any other face has its own two. */
static inline uint32_t fnode(const a3 *A, uint32_t f, int s)
{
    uint32_t u = A->f_unit[f];
    return 2 * u + (uint32_t)(u < A->npatch ? s ^ !A->f_out[f] : s);
}

/* The shell of side s of face f; its part. */
static inline uint32_t fshell(const a3 *A, const cshells *S, uint32_t f, int s)
{
    return S->shell[fnode(A, f, s)];
}

static inline uint32_t fcomp(const a3 *A, const cshells *S, uint32_t f)
{
    return S->ucomp[A->f_unit[f]];
}

/* Stage "shells": the units' nodes linked across the edges between units (the edges inside a
 * patch link nothing new).  Returns -1 out of memory. */
A3_STAGE static int shells_make(a3 *A, const cedges *E, cshells *S)
{
    size_t nn = 2 * A->nunit, nu = A->nunit;
    uint32_t *sp = mem_malloc((nn + 1) * sizeof *sp), *uu = mem_malloc((nu + 1) * sizeof *uu);
    S->shell = mem_malloc((nn + 1) * sizeof *S->shell);
    S->ucomp = mem_malloc((nu + 1) * sizeof *S->ucomp);
    int rc = -1;
    if (!sp || !uu || !S->shell || !S->ucomp) goto done;
    for (size_t i = 0; i < nn; i++) sp[i] = (uint32_t)i;
    for (size_t i = 0; i < nu; i++) uu[i] = (uint32_t)i;
    for (size_t e = 0; e < E->ne; e++) {
        const inc *F = E->I + E->ioff[e];
        size_t n = E->ioff[e + 1] - E->ioff[e];
        for (size_t k = 0; k < n; k++) {
            const inc *f0 = &F[k], *f1 = &F[k + 1 < n ? k + 1 : 0];
            uf_union(sp, fnode(A, f0->f, f0->s > 0 ? 0 : 1), fnode(A, f1->f, f1->s > 0 ? 1 : 0));
            if (k + 1 < n) uf_union(uu, A->f_unit[f0->f], A->f_unit[f1->f]);
        }
    }
    /* shells and parts numbered in order of their first node (a root's number kept at the
     * root, which may come later) */
    size_t nsh = 0, ncomp = 0;
    for (size_t i = 0; i < nn; i++) S->shell[i] = NONE;
    for (size_t i = 0; i < nn; i++) {
        uint32_t r = uf_find(sp, (uint32_t)i);
        if (S->shell[r] == NONE) S->shell[r] = (uint32_t)nsh++;
        S->shell[i] = S->shell[r];
    }
    for (size_t u = 0; u < nu; u++) S->ucomp[u] = NONE;
    for (size_t u = 0; u < nu; u++) {
        uint32_t r = uf_find(uu, (uint32_t)u);
        if (S->ucomp[r] == NONE) S->ucomp[r] = (uint32_t)ncomp++;
        S->ucomp[u] = S->ucomp[r];
    }
    S->nsh = nsh, S->ncomp = ncomp;
    S->cpiece = mem_malloc((ncomp + 1) * sizeof *S->cpiece);
    if (!S->cpiece) goto done;
    for (size_t c = 0; c < ncomp; c++) S->cpiece[c] = NONE;
    for (size_t u = 0; u < nu; u++) {
        /* a patch's pieces come in ascending order: its first face's is its lowest */
        uint32_t c = S->ucomp[u], f1 = u < A->npatch ? A->u_off[u] + 1 : A->u_off[u + 1];
        for (uint32_t f = A->u_off[u]; f < f1; f++)
            for (uint32_t i = A->f_cov[f]; i < A->f_cov[f + 1]; i++)
                if (A->cov[i] < S->cpiece[c]) S->cpiece[c] = A->cov[i];
    }
    A->st->shells = nsh;
    /* reported: parts connected through any shared point (solids that touch at a point are one);
     * the probes work on parts connected through edges */
    A->st->components = ncomp;
    if (ncomp > 1) {
        uint32_t *pf = mem_malloc((A->npt + 1) * sizeof *pf),
                 *vu = mem_malloc((ncomp + 1) * sizeof *vu);
        if (!pf || !vu) {
            free(pf), free(vu);
            goto done;
        }
        for (size_t p = 0; p < A->npt; p++) pf[p] = NONE;
        for (size_t c = 0; c < ncomp; c++) vu[c] = (uint32_t)c;
        for (size_t f = 0; f < A->nf; f++) {
            uint32_t c = fcomp(A, S, (uint32_t)f);
            for (uint32_t x = A->cyc_off[A->f_cyc[f]]; x < A->cyc_off[A->f_cyc[f + 1]]; x++) {
                uint32_t p = A->ent[x];
                if (pf[p] == NONE)
                    pf[p] = c;
                else if (pf[p] != c)
                    uf_union(vu, pf[p], c);
            }
        }
        size_t nvc = 0;
        for (size_t c = 0; c < ncomp; c++) nvc += uf_find(vu, (uint32_t)c) == c;
        free(pf), free(vu);
        A->st->components = nvc;
    }
    rc = 0;
done:
    free(sp);
    free(uu);
    return rc;
}

/* The nesting stage's work: the probes, each part's outside shell, the faces of other parts
 * each probe hits beyond its part's first face (hits[hoff[c] .. hoff[c + 1])), and scratch. */
typedef struct nest {
    const a3 *A;
    const cshells *S;
    pindex X;
    probe *probes;   /* by part */
    uint32_t *outer; /* by part: its outside shell */
    uint32_t *hits, *hoff;
    size_t nhit, caphits;
    uint32_t *ptri, *ff, *stack;
    size_t nptri, capptri, capff, capstack;
} nest;

static void nest_free(nest *N)
{
    pindex_free(&N->X);
    free(N->probes), free(N->outer), free(N->hits), free(N->hoff), free(N->ptri), free(N->ff);
    free(N->stack);
}

/* Pass 1 for part c: its probe (through the centroid of its lowest piece's first triangle, or
 * of the next one while the line misses every face of the part: a piece whose inside is in two
 * parts, holes touching each other and the outer cycle across it, may lie in two parts of the
 * complex), its first own face along -k (beyond it lies its outside: outer[c]), and the faces
 * of other parts it hits beyond that, appended to hits.  Returns an ARR_* code. */
static int part_probe(nest *N, size_t c, char *err, size_t errlen)
{
    const a3 *A = N->A;
    const cshells *S = N->S;
    probe *pr = &N->probes[c];
    int pk, r = piece_tris(A, S->cpiece[c], &N->ptri, &N->nptri, &N->capptri, &pk);
    if (r == -1) return ARR_ENOMEM;
    if (r) {
        snprintf(err, errlen, "solids: no point found inside input face %u",
                 A->pc[S->cpiece[c]].face);
        return ARR_EINTERNAL;
    }
    uint32_t own = NONE;
    size_t h0 = N->nhit;
    for (size_t t = 0; t < N->nptri && own == NONE; t++) {
        tri_probe(A, N->ptri + 3 * t, pk, pr);
        N->nhit = h0;
        size_t nff;
        if (probe_candidates(A, &N->X, pr, &N->ff, &N->capff, &nff)) return ARR_ENOMEM;
        for (size_t ci = 0; ci < nff; ci++) {
            uint32_t f = N->ff[ci];
            if (S->ncomp == 1 && fcomp(A, S, f) != c) continue;
            if (!probe_hits(A, f, pr)) continue;
            if (fcomp(A, S, f) == c) {
                if (own == NONE || probe_cmp(A, f, own, pr) < 0) own = f;
            } else {
                if (mem_grow(&N->hits, &N->caphits, N->nhit + 1, sizeof *N->hits))
                    return ARR_ENOMEM;
                N->hits[N->nhit++] = f;
            }
        }
    }
    if (own == NONE) {
        snprintf(err, errlen, "solids: a part's own ray hits none of its faces (a bug)");
        return ARR_EINTERNAL;
    }
    plane3 town;
    int up = a3_face_plane(A, own, &town)->n[pr->k] > 0;
    N->outer[c] = fshell(A, S, own, up ? 1 : 0); /* the side facing -k */
    size_t m = h0;
    for (size_t h = h0; h < N->nhit; h++)
        if (probe_cmp(A, N->hits[h], own, pr) < 0) N->hits[m++] = N->hits[h];
    N->nhit = m;
    N->hoff[c + 1] = (uint32_t)m;
    return ARR_OK;
}

/* Pass 2 for part c: down its ray from just beyond its first face.  Entering another part from
 * its outside (the side we come from is that part's outer shell) and leaving it again are
 * skipped (a stack of parts); the first face met outside every part whose side toward us is not
 * an outer shell is the wall of the cell holding the part: its shell, into *host.  No such
 * face: the part lies in the exterior (*host unchanged).  -1 out of memory. */
static int part_host(nest *N, size_t c, uint32_t *host)
{
    const a3 *A = N->A;
    const cshells *S = N->S;
    const probe *pr = &N->probes[c];
    uint32_t *H = N->hits ? N->hits + N->hoff[c] : NULL, nh = N->hoff[c + 1] - N->hoff[c];
    size_t depth = 0;
    if (nh > 1) qsort_r(H, nh, sizeof *H, probe_desc, &(probe_sort){A, pr});
    for (uint32_t h = 0; h < nh; h++) {
        uint32_t f = H[h], d = fcomp(A, S, f);
        plane3 tf;
        int fup = a3_face_plane(A, f, &tf)->n[pr->k] > 0;
        uint32_t s_up = fshell(A, S, f, fup ? 0 : 1), s_down = fshell(A, S, f, fup ? 1 : 0);
        if (depth && s_down == N->outer[N->stack[depth - 1]] && d == N->stack[depth - 1]) {
            depth--; /* leaving the part we were inside */
            continue;
        }
        if (s_up == N->outer[d]) { /* entering part d from its outside */
            if (mem_grow(&N->stack, &N->capstack, depth + 1, sizeof *N->stack)) return -1;
            N->stack[depth++] = d;
            continue;
        }
        if (!depth) {
            *host = s_up;
            break;
        }
    }
    return 0;
}

/* Stage "nesting": into cu (a union-find over the shells and the exterior, nsh + 1 entries, the
 * exterior last), each part's outside shell joined to the cell holding the part.  Returns an
 * ARR_* code. */
A3_STAGE static int nesting_make(const a3 *A, const cshells *S, uint32_t *cu, char *err,
                                 size_t errlen)
{
    size_t ncomp = S->ncomp, nsh = S->nsh;
    nest N = {.A = A, .S = S};
    int rc = ARR_ENOMEM;
    N.outer = mem_malloc((ncomp + 1) * sizeof *N.outer);
    N.probes = mem_malloc((ncomp + 1) * sizeof *N.probes);
    N.hoff = mem_calloc(ncomp + 2, sizeof *N.hoff);
    if (!N.outer || !N.probes || !N.hoff || pindex_make(A, ncomp, &N.X)) goto done;
    for (uint32_t s = 0; s <= nsh; s++) cu[s] = s;
    for (size_t c = 0; c < ncomp; c++)
        if ((rc = part_probe(&N, c, err, errlen)) != ARR_OK) goto done;
    a3_progress(A, "cells", 0.45);
    rc = ARR_ENOMEM;
    for (size_t c = 0; c < ncomp; c++) {
        uint32_t host = (uint32_t)nsh; /* the exterior */
        if (part_host(&N, c, &host)) goto done;
        uf_union(cu, N.outer[c], host);
    }
    rc = ARR_OK;
done:
    if (rc == ARR_ENOMEM && err && errlen) snprintf(err, errlen, "out of memory");
    nest_free(&N);
    return rc;
}

/* ---- volumes ------------------------------------------------------------------------------
 * Six times a cell's volume is the sum over its faces of the cones from any one point o.  A
 * cycle whose points are all on the grid contributes exactly, in 128-bit integers: its fan's
 * determinants from the grid's origin, C = sum det(p0, pi, pi+1), less o . S with S = sum
 * p_i x p_i+1 (det(a - o, b - o, c - o) = det(a, b, c) - o . (a x b + b x c + c x a));
 * coordinates are below 2^30, so C < 2^90 and S < 2^60 a cycle, with room for 2^25 faces a
 * cell.  A cycle with points made by the arrangement contributes in double-double from o, a
 * vertex of the cell (on the grid when one is), so a sliver keeps its volume.  The CF entries
 * run on the threads in fixed chunks, each summing per cell run (CF is sorted by cell); the
 * runs are then added in chunk order: the result does not depend on the number of threads. */

typedef struct volrun {
    i128 C, S[3]; /* the unit's grid cycles, each face turned to point into its unit's cell 2u */
} volrun;

typedef struct voljob {
    const a3 *A;
    const size_t *roff; /* by chunk of faces: its first run (a run a unit the chunk touches) */
    volrun *run;
} voljob;

#define VOL_CHUNK 4096
/* The grid cycles of one chunk of faces, summed per unit. */
static void vol_chunk(void *ctx, size_t item, int worker)
{
    (void)worker;
    const voljob *j = ctx;
    const a3 *A = j->A;
    size_t f0 = item * VOL_CHUNK, f1 = f0 + VOL_CHUNK < A->nf ? f0 + VOL_CHUNK : A->nf;
    uint32_t u0 = A->f_unit[f0], cur = u0;
    /* the sums of the current unit's run stay here, and go to the shared array when the unit
     * changes: neighbouring chunks' runs share cache lines there (writing them face by face
     * made two threads slower than one) */
    volrun acc = {0, {0, 0, 0}};
    for (size_t f = f0; f < f1; f++) {
        uint32_t u = A->f_unit[f];
        if (u != cur) {
            j->run[j->roff[item] + (cur - u0)] = acc;
            acc = (volrun){0, {0, 0, 0}};
            cur = u;
        }
        int neg = u < A->npatch && !A->f_out[f];
        for (uint32_t cy = A->f_cyc[f]; cy < A->f_cyc[f + 1]; cy++) {
            uint32_t o = A->cyc_off[cy], m = A->cyc_off[cy + 1] - o, t = 0;
            if (m < 3) continue;
            /* point ids below nv are the vertices; a cycle with a made point is summed in
             * double-double, per cell.  A triangle, the common case, in closed form:
             * C = det(p0, p1, p2), S = (p1 - p0) x (p2 - p0) */
            if (m == 3) {
                uint32_t e0 = A->ent[o], e1 = A->ent[o + 1], e2 = A->ent[o + 2];
                if (e0 >= A->nv || e1 >= A->nv || e2 >= A->nv) continue;
                const int64_t *p0 = A->g + 3 * (size_t)e0, *p1 = A->g + 3 * (size_t)e1,
                              *p2 = A->g + 3 * (size_t)e2;
                /* |coordinates| <= 2^29 + 1: each component of p1 x p2 below 2^60, and of the
                 * differences (below 2^31) their cross product below 2^62 (64 bits) */
                int64_t c0 = p1[1] * p2[2] - p1[2] * p2[1];
                int64_t c1 = p1[2] * p2[0] - p1[0] * p2[2];
                int64_t c2 = p1[0] * p2[1] - p1[1] * p2[0];
                i128 C = (i128)p0[0] * c0 + (i128)p0[1] * c1 + (i128)p0[2] * c2;
                int64_t u0 = p1[0] - p0[0], u1 = p1[1] - p0[1], u2 = p1[2] - p0[2];
                int64_t v0 = p2[0] - p0[0], v1 = p2[1] - p0[1], v2 = p2[2] - p0[2];
                int64_t S0 = u1 * v2 - u2 * v1, S1 = u2 * v0 - u0 * v2, S2 = u0 * v1 - u1 * v0;
                if (neg) C = -C, S0 = -S0, S1 = -S1, S2 = -S2;
                acc.C += C, acc.S[0] += S0, acc.S[1] += S1, acc.S[2] += S2;
                continue;
            }
            while (t < m && A->ent[o + t] < A->nv) t++;
            if (t < m) continue;
            /* |coordinates| <= 2^29 + 1: each cross product component below 2^60 */
            i128 C = 0, S[3] = {0, 0, 0};
            const int64_t *p0 = A->g + 3 * (size_t)A->ent[o], *q = p0;
            for (t = 1; t <= m; t++) {
                const int64_t *p = t < m ? A->g + 3 * (size_t)A->ent[o + t] : p0;
                int64_t c0 = q[1] * p[2] - q[2] * p[1];
                int64_t c1 = q[2] * p[0] - q[0] * p[2];
                int64_t c2 = q[0] * p[1] - q[1] * p[0];
                S[0] += c0, S[1] += c1, S[2] += c2;
                if (t >= 2 && t < m) C += (i128)p0[0] * c0 + (i128)p0[1] * c1 + (i128)p0[2] * c2;
                q = p;
            }
            if (neg) C = -C, S[0] = -S[0], S[1] = -S[1], S[2] = -S[2];
            acc.C += C, acc.S[0] += S[0], acc.S[1] += S[1], acc.S[2] += S[2];
        }
    }
    j->run[j->roff[item] + (cur - u0)] = acc;
}

/* Six times the cone from org over the cycle's fan, in double-double. */
static dd cycle_cone6(const a3 *A, const double *dh, const double *dl, uint32_t cy, const dd *org)
{
    uint32_t o = A->cyc_off[cy], m = A->cyc_off[cy + 1] - o;
    dd p[3][3], c = {0, 0};
    if (m < 3) return c;
    dd_rel(dh, dl, A->ent[o], org, p[0]);
    for (uint32_t t = 1; t + 1 < m; t++) {
        dd_rel(dh, dl, A->ent[o + t], org, p[1]);
        dd_rel(dh, dl, A->ent[o + t + 1], org, p[2]);
        dd c0 = dd_add(dd_mul(p[1][1], p[2][2]), dd_neg(dd_mul(p[1][2], p[2][1])));
        dd c1 = dd_add(dd_mul(p[1][2], p[2][0]), dd_neg(dd_mul(p[1][0], p[2][2])));
        dd c2 = dd_add(dd_mul(p[1][0], p[2][1]), dd_neg(dd_mul(p[1][1], p[2][0])));
        c = dd_add(c, dd_mul(p[0][0], c0));
        c = dd_add(c, dd_mul(p[0][1], c1));
        c = dd_add(c, dd_mul(p[0][2], c2));
    }
    return c;
}

/* An exact 128-bit integer as a double-double. */
static dd dd_of(i128 v)
{
    double hi = (double)v;
    dd r = {hi, (double)(v - (i128)hi)};
    return r;
}

/* The cell of every shell, into cellof (nsh entries): its class's number in cu, numbered in
 * order of the faces' sides (a unit's faces come together, its first face first); the
 * exterior's class is NONE.  Sets out->nc.  -1 out of memory. */
static int cells_number(const a3 *A, const cshells *S, uint32_t *cu, uint32_t *cellof, lar3 *out)
{
    size_t nsh = S->nsh, nc = 0;
    uint32_t ext_root = uf_find(cu, (uint32_t)nsh);
    uint32_t *lab = mem_malloc((nsh + 2) * sizeof *lab);
    if (!lab) return -1;
    for (size_t s = 0; s <= nsh; s++) lab[s] = NONE - 1;
    for (size_t u = 0; u < A->nunit; u++)
        for (int sd = 0; sd < 2; sd++) {
            uint32_t r = uf_find(cu, fshell(A, S, A->u_off[u], sd));
            if (lab[r] == NONE - 1) lab[r] = r == ext_root ? NONE : (uint32_t)nc++;
        }
    for (size_t s = 0; s < nsh; s++) cellof[s] = lab[uf_find(cu, (uint32_t)s)];
    free(lab);
    out->nc = nc;
    return 0;
}

/* The units and the cells on their two sides (out->u_off, ucell: the exterior is nc) and the
 * faces turned against their unit (frev).  -1 out of memory. */
static int cells_units(const a3 *A, const cshells *S, const uint32_t *cellof, lar3 *out)
{
    size_t nc = out->nc;
    out->nunit = A->nunit;
    out->u_off = mem_malloc((A->nunit + 1) * sizeof *out->u_off);
    out->ucell = mem_malloc((2 * A->nunit + 1) * sizeof *out->ucell);
    out->frev = mem_malloc(A->nf + 1);
    if (!out->u_off || !out->ucell || !out->frev) return -1;
    memcpy(out->u_off, A->u_off, (A->nunit + 1) * sizeof *out->u_off);
    for (size_t u = 0; u < A->nunit; u++)
        for (int sd = 0; sd < 2; sd++) {
            uint32_t k = cellof[S->shell[2 * u + (uint32_t)sd]];
            out->ucell[2 * u + (uint32_t)sd] = k == NONE ? (uint32_t)nc : k;
        }
    for (size_t f = 0; f < A->nf; f++)
        out->frev[f] = (uint8_t)(A->f_unit[f] < A->npatch && !A->f_out[f]);
    return 0;
}

/* Closed solids: a face across which some solid's winding number changes has two cells on its
 * sides; one cell on both sides is only for a face whose solids' faces cancel (a surface
 * touching itself face to face inside itself, as a tube whose two end caps meet): else the
 * arrangement is broken (ARR_EINTERNAL, with where).  ARR_OK otherwise. */
static int cells_check_sides(const a3 *A, const cshells *S, const uint32_t *cellof, const lar3 *out,
                             char *err, size_t errlen)
{
    for (size_t u = 0; u < A->nunit && !A->soup; u++) {
        uint32_t f = A->u_off[u]; /* a unit's faces share its two sides */
        if (cellof[fshell(A, S, f, 0)] != cellof[fshell(A, S, f, 1)]) continue;
        int cancel = 1;
        for (uint32_t i = A->f_cov[f]; i < A->f_cov[f + 1] && cancel; i++) {
            int w = 0;
            for (uint32_t k = A->f_cov[f]; k < A->f_cov[f + 1]; k++)
                if (A->pc[A->cov[k]].solid == A->pc[A->cov[i]].solid) w += A->pc[A->cov[k]].sgn;
            cancel = w == 0;
        }
        if (cancel) continue;
        const piece *pc = &A->pc[A->cov[A->f_cov[f]]];
        const xpt *x = &A->pt[A->ent[A->cyc_off[A->f_cyc[f]]]];
        snprintf(err, errlen,
                 "solids[%u]: face %u: one cell on both sides near (%.9g, %.9g, %.9g) on the "
                 "grid of step %g (a bug: please report it)",
                 pc->solid, pc->face - out->solid_face_off[pc->solid],
                 ((double)A->oi[0] + x->x[0]) * A->step, ((double)A->oi[1] + x->x[1]) * A->step,
                 ((double)A->oi[2] + x->x[2]) * A->step, A->step);
        return ARR_EINTERNAL;
    }
    return ARR_OK;
}

/* CF: each cell's signed faces, ascending as integers (the - entries by falling face, then the
 * + entries by rising face); the exterior's likewise (out->ext).  -1 out of memory. */
static int cells_cf(const a3 *A, const cshells *S, const uint32_t *cellof, lar3 *out)
{
    size_t nf = A->nf, nc = out->nc, next = 0;
    uint32_t *fill = NULL;
    out->cf_off = mem_calloc(nc + 2, sizeof *out->cf_off);
    if (!out->cf_off) return -1;
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t f = (uint32_t)(i / 2);
        uint32_t k = cellof[fshell(A, S, f, (int)(i & 1))], o = cellof[fshell(A, S, f, !(i & 1))];
        if (k == o) continue;
        if (k == NONE)
            next++;
        else
            out->cf_off[k + 1]++;
    }
    for (size_t k = 0; k < nc; k++) out->cf_off[k + 1] += out->cf_off[k];
    out->cf = mem_malloc((out->cf_off[nc] + 1) * sizeof *out->cf);
    out->ext = mem_malloc((next + 1) * sizeof *out->ext);
    fill = mem_calloc(nc + 1, sizeof *fill);
    if (!out->cf || !out->ext || !fill) {
        free(fill);
        return -1;
    }
    out->next = 0;
    /* the - sides (face normal out of the cell: +(f+1)) are odd i; -(f+1) for the + sides */
    for (int pass = 0; pass < 2; pass++)
        for (size_t t = 0; t < nf; t++) {
            size_t f = pass == 0 ? nf - 1 - t : t, i = 2 * f + (pass == 0 ? 0 : 1);
            uint32_t k = cellof[fshell(A, S, (uint32_t)f, (int)(i & 1))];
            if (k == cellof[fshell(A, S, (uint32_t)f, !(i & 1))]) continue;
            int32_t sf = pass == 0 ? -(int32_t)(f + 1) : (int32_t)(f + 1);
            if (k == NONE)
                out->ext[out->next++] = sf;
            else
                out->cf[out->cf_off[k] + fill[k]++] = sf;
        }
    free(fill);
    return 0;
}

/* Each cell's origin (orgv, nc entries): a point of the first face that bounds it (in unit
 * order), on the grid when one is; the double-double cones start from it (a vertex of the cell:
 * the terms are as small as the cell, so a sliver keeps its volume).  Then the points wanted to
 * 2^-100 into dh, dl (NAN in dh[3p]: not wanted): every point of a face when the coordinates
 * are written, else only those of the faces of no patch (the cones in double-double are
 * theirs) and the cells' origins (a patch's faces are summed exactly from their grid points).
 * ARR_OK, or ARR_ECANCELED. */
static int cells_points(const a3 *A, const lar3 *out, uint32_t *orgv, double *dh, double *dl)
{
    size_t nc = out->nc, nf = A->nf;
    int want_coords = !A->o->want || (A->o->want & ARR3_WANT_COORDS);
    for (size_t k = 0; k < nc; k++) orgv[k] = NONE;
    for (size_t u = 0; u < A->nunit; u++)
        for (int sd = 0; sd < 2; sd++) {
            uint32_t k = out->ucell[2 * u + (uint32_t)sd];
            if (k >= nc || orgv[k] != NONE) continue;
            uint32_t f0 = A->u_off[u], o0 = A->cyc_off[A->f_cyc[f0]];
            uint32_t n0 = A->cyc_off[A->f_cyc[f0] + 1] - o0;
            orgv[k] = A->ent[o0];
            for (uint32_t i = 0; i < n0; i++)
                if (A->ent[o0 + i] < A->nv) {
                    orgv[k] = A->ent[o0 + i];
                    break;
                }
        }
    for (size_t p = 0; p < A->npt; p++) dh[3 * p] = NAN; /* not wanted */
    if (want_coords) {
        for (size_t i = 0; i < A->nent; i++) dh[3 * (size_t)A->ent[i]] = 0;
    } else {
        size_t f0 = A->npatch ? A->u_off[A->npatch] : 0;
        for (size_t i = f0 < nf ? A->cyc_off[A->f_cyc[f0]] : A->nent; i < A->nent; i++)
            dh[3 * (size_t)A->ent[i]] = 0;
        for (size_t k = 0; k < nc; k++)
            if (orgv[k] != NONE) dh[3 * (size_t)orgv[k]] = 0;
    }
    ddjob j = {A, dh, dl, NULL, 0};
    a3_span span = {A, "cells", 0.45, 0.5};
    par_for_ex(A->threads, (A->npt + DD_CHUNK - 1) / DD_CHUNK, points_dd, &j, a3_span_tick, &span);
    /* a bounded part of the stage: the cancel is read here */
    return a3_cancelled(A) ? ARR_ECANCELED : ARR_OK;
}

/* The grid cycles summed per unit into UC (4 a unit: C, S; on the threads, in fixed chunks of
 * faces, the chunks' runs then added in chunk order).  ARR_OK, ARR_ENOMEM or ARR_ECANCELED. */
static int volumes_grid(const a3 *A, i128 *UC)
{
    size_t nf = A->nf, nch = (nf + VOL_CHUNK - 1) / VOL_CHUNK, nrun = 0;
    size_t *roff = mem_malloc((nch + 1) * sizeof *roff);
    volrun *run = NULL;
    int rc = ARR_ENOMEM;
    if (!roff) goto done;
    for (size_t c = 0; c < nch; c++) {
        size_t f0 = c * VOL_CHUNK, f1 = f0 + VOL_CHUNK < nf ? f0 + VOL_CHUNK : nf;
        roff[c] = nrun;
        nrun += A->f_unit[f1 - 1] - A->f_unit[f0] + 1;
    }
    run = mem_calloc(nrun + 1, sizeof *run);
    if (!run) goto done;
    voljob j = {A, roff, run};
    par_for(A->threads, nch, vol_chunk, &j);
    if (a3_cancelled(A)) {
        rc = ARR_ECANCELED;
        goto done;
    }
    for (size_t c = 0; c < nch; c++) {
        size_t f0 = c * VOL_CHUNK, f1 = f0 + VOL_CHUNK < nf ? f0 + VOL_CHUNK : nf;
        for (uint32_t u = A->f_unit[f0]; u <= A->f_unit[f1 - 1]; u++) {
            const volrun *r = &run[roff[c] + (u - A->f_unit[f0])];
            UC[4 * u] += r->C;
            for (int a = 0; a < 3; a++) UC[4 * u + 1 + a] += r->S[a];
        }
    }
    rc = ARR_OK;
done:
    free(roff), free(run);
    return rc;
}

/* The cells' volumes (out->cvol, allocated): the grid cycles per unit (volumes_grid), the
 * cycles with made points (faces of no patch: few) in double-double per cell from its origin,
 * and each unit's grid part into its two cells, from each cell's own origin when it is on the
 * grid (C - o . S, exact), else from the grid's origin and o . S in double-double.  ARR_OK,
 * ARR_ENOMEM or ARR_ECANCELED. */
static int cells_volumes(const a3 *A, lar3 *out, const uint32_t *orgv, const double *dh,
                         const double *dl)
{
    size_t nf = A->nf, nc = out->nc;
    i128 *UC = mem_calloc(4 * A->nunit + 1, sizeof *UC), *V6 = mem_calloc(nc + 1, sizeof *V6);
    dd *X = mem_calloc(nc + 1, sizeof *X);
    int rc = ARR_ENOMEM;
    out->cvol = mem_calloc(nc + 1, sizeof *out->cvol);
    if (!UC || !V6 || !X || !out->cvol) goto done;
    if ((rc = volumes_grid(A, UC)) != ARR_OK) goto done;
    for (size_t f = A->npatch ? A->u_off[A->npatch] : 0; f < nf; f++)
        for (uint32_t cy = A->f_cyc[f]; cy < A->f_cyc[f + 1]; cy++) {
            uint32_t o = A->cyc_off[cy], m = A->cyc_off[cy + 1] - o, t = 0;
            while (t < m && A->ent[o + t] < A->nv) t++;
            if (m < 3 || t == m) continue;
            uint32_t u = A->f_unit[f];
            for (int sd = 0; sd < 2; sd++) {
                /* into 2u (its normal's side: -) and out of 2u + 1 (+) */
                uint32_t k = out->ucell[2 * u + (uint32_t)sd];
                if (k >= nc) continue;
                dd org[3];
                for (int a = 0; a < 3; a++)
                    org[a].hi = dh[3 * (size_t)orgv[k] + a],
                    org[a].lo = dl[3 * (size_t)orgv[k] + a];
                dd c = cycle_cone6(A, dh, dl, cy, org);
                X[k] = dd_add(X[k], sd ? c : dd_neg(c));
            }
        }
    double h3 = A->step * A->step * A->step / 6;
    for (size_t u = 0; u < A->nunit; u++)
        for (int sd = 0; sd < 2; sd++) {
            uint32_t k = out->ucell[2 * u + (uint32_t)sd];
            if (k >= nc) continue;
            const i128 *Uu = UC + 4 * u;
            i128 v = Uu[0];
            if (orgv[k] < A->nv) {
                const int64_t *g = A->g + 3 * (size_t)orgv[k];
                v -= g[0] * Uu[1] + g[1] * Uu[2] + g[2] * Uu[3];
            } else {
                for (int a = 0; a < 3; a++) {
                    dd oa = {dh[3 * (size_t)orgv[k] + a], dl[3 * (size_t)orgv[k] + a]};
                    dd t = dd_mul(oa, dd_of(Uu[1 + a]));
                    X[k] = dd_add(X[k], sd ? dd_neg(t) : t);
                }
            }
            V6[k] += sd ? v : -v;
        }
    for (size_t k = 0; k < nc; k++) {
        dd vol = dd_add(X[k], dd_of(V6[k]));
        out->cvol[k] = (vol.hi + vol.lo) * h3;
    }
    rc = ARR_OK;
done:
    free(UC), free(V6), free(X);
    return rc;
}

/* Stage "cells": cell ids from cu (the class of the exterior is none: cells_number), the units'
 * cells (cells_units, checked: cells_check_sides), each cell's faces (CF, in order of face: the
 * - side first) and the exterior's when asked for (cells_cf), the points to 2^-100
 * (cells_points: volumes and the written coordinates come from these, handed back in *dh_out,
 * *dl_out) and the volumes (cells_volumes).  Returns an ARR_* code. */
A3_STAGE static int cells_make(a3 *A, const cshells *S, uint32_t *cu, lar3 *out, double **dh_out,
                               double **dl_out, char *err, size_t errlen)
{
    uint32_t *cellof = mem_malloc((S->nsh + 2) * sizeof *cellof), *orgv = NULL;
    double *dh = NULL, *dl = NULL;
    unsigned want = A->o->want ? A->o->want : ~0u;
    int rc = ARR_ENOMEM;
    if (!cellof || cells_number(A, S, cu, cellof, out) || cells_units(A, S, cellof, out)) goto done;
    if ((rc = cells_check_sides(A, S, cellof, out, err, errlen)) != ARR_OK) goto done;
    rc = ARR_ENOMEM;
    if ((want & ARR3_WANT_CF) && cells_cf(A, S, cellof, out)) goto done;
    dh = mem_malloc((3 * A->npt + 1) * sizeof *dh);
    dl = mem_malloc((3 * A->npt + 1) * sizeof *dl);
    orgv = mem_malloc((out->nc + 1) * sizeof *orgv);
    if (!dh || !dl || !orgv) goto done;
    if ((rc = cells_points(A, out, orgv, dh, dl)) != ARR_OK) goto done;
    if ((rc = cells_volumes(A, out, orgv, dh, dl)) != ARR_OK) goto done;
    *dh_out = dh, *dl_out = dl;
    dh = dl = NULL;
    rc = ARR_OK;
done:
    if (rc == ARR_ENOMEM && err && errlen) snprintf(err, errlen, "out of memory");
    free(cellof), free(orgv), free(dh), free(dl);
    return rc;
}

/* ---- output ------------------------------------------------------------------------------ */

/* The used points sorted by position: the grid points by sort_kv_xyz (point ids below nv are
 * the vertices, pt[v] the grid point v; equal points cannot occur, they are one point), the
 * others (few: where surfaces meet) by the exact comparison, then the two runs merged by it. */
static int sort_points(const a3 *A, uint32_t *used, size_t nu)
{
    size_t ng = 0, nx = 0;
    kv *g = mem_malloc((nu + 1) * sizeof *g);
    uint32_t *x = mem_malloc((nu + 1) * sizeof *x);
    int rc = -1;
    if (!g || !x) goto done;
    for (size_t i = 0; i < nu; i++)
        if (A->pt[used[i]].kind == PT_GRID) {
            assert(A->pt[used[i]].a == used[i]);
            g[ng++] = (kv){0, used[i]};
        } else
            x[nx++] = used[i];
    if (sort_kv_xyz(g, ng, A->g)) goto done;
    if (nx > 1) qsort_r(x, nx, sizeof *x, vcmp, (void *)A);
    size_t i = 0, j = 0, m = 0;
    while (i < ng || j < nx) {
        if (j == nx || (i < ng && vcmp(&g[i].v, &x[j], (void *)A) < 0))
            used[m++] = g[i++].v;
        else
            used[m++] = x[j++];
    }
    rc = 0;
done:
    free(g), free(x);
    return rc;
}

#define OUT_CHUNK 8192
typedef struct outjob {
    const a3 *A;
    lar3 *out;
    const uint32_t *newid, *newe, *ent_e;
} outjob;

/* One chunk of faces written: FN, fsrc, FE, fsol and fwind (the solids whose faces over f do
 * not cancel, ascending, and their sums), fc; fsol_off and fe_off are known. */
static void out_faces(void *ctx, size_t item, int worker)
{
    (void)worker;
    const outjob *j = ctx;
    const a3 *A = j->A;
    lar3 *out = j->out;
    size_t f1 = (item + 1) * OUT_CHUNK < A->nf ? (item + 1) * OUT_CHUNK : A->nf;
    for (size_t f = item * OUT_CHUNK; f < f1; f++) {
        if (out->FN) {
            int64_t nn[3];
            a3_face_normal(A, (uint32_t)f, nn);
            double nd[3] = {(double)nn[0], (double)nn[1], (double)nn[2]};
            double len = sqrt(nd[0] * nd[0] + nd[1] * nd[1] + nd[2] * nd[2]);
            for (int k = 0; k < 3; k++) out->FN[3 * f + k] = nd[k] / len;
            out->fsrc[f] = A->pc[A->cov[A->f_cov[f]]].face;
        }
        uint32_t nfe = out->fe ? out->fe_off[f] : 0;
        for (uint32_t cy = A->f_cyc[f]; out->fe && cy < A->f_cyc[f + 1]; cy++) {
            out->fc[cy] = cy;
            uint32_t o = A->cyc_off[cy], n = A->cyc_off[cy + 1] - o;
            if (n < 2) continue;
            for (uint32_t t = 0; t < n; t++) {
                uint32_t a = j->newid[A->ent[o + t]],
                         b = j->newid[A->ent[t + 1 < n ? o + t + 1 : o]];
                uint32_t e = j->newe[j->ent_e[o + t]];
                out->fe[nfe++] = a < b ? (int32_t)(e + 1) : -(int32_t)(e + 1);
            }
        }
        uint32_t s0 = out->fsol_off[f], c0 = A->f_cov[f], c1 = A->f_cov[f + 1];
        if (c1 - c0 == 1) {
            const piece *pc = &A->pc[A->cov[c0]];
            out->fsol[s0] = pc->solid;
            out->fwind[s0] = pc->sgn; /* the piece's outward normal about f's (fan_check) */
            continue;
        }
        /* several pieces: each solid's pieces' turnings summed, the solids of a non-zero sum
         * ascending (at most a few) */
        uint32_t nfs = s0;
        for (uint32_t i = c0; i < c1; i++) {
            const piece *pc = &A->pc[A->cov[i]];
            uint32_t so = pc->solid, q = s0;
            while (q < nfs && out->fsol[q] < so) q++;
            if (q < nfs && out->fsol[q] == so) {
                out->fwind[q] += pc->sgn;
                continue;
            }
            memmove(out->fsol + q + 1, out->fsol + q, (nfs - q) * sizeof *out->fsol);
            memmove(out->fwind + q + 1, out->fwind + q, (nfs - q) * sizeof *out->fwind);
            out->fsol[q] = so;
            out->fwind[q] = pc->sgn;
            nfs++;
        }
        uint32_t w = s0;
        for (uint32_t q = s0; q < nfs; q++) /* the sums of 0 out (a wall: both ways) */
            if (out->fwind[q]) out->fsol[w] = out->fsol[q], out->fwind[w++] = out->fwind[q];
        for (uint32_t q = w; q < out->fsol_off[f + 1]; q++) out->fsol[q] = NONE; /* gap */
    }
}

/* The used points numbered in order of position (newid: from 0 for used, NONE for the others,
 * to their number) and, when asked for, their coordinates V from dh + dl.  -1 out of memory. */
static int output_points(const a3 *A, uint32_t *newid, size_t nu, const double *dh,
                         const double *dl, lar3 *out, unsigned want)
{
    uint32_t *used = mem_malloc((nu + 1) * sizeof *used);
    int rc = -1;
    if (!used) goto done;
    nu = 0;
    for (size_t p = 0; p < A->npt; p++)
        if (newid[p] == 0) used[nu++] = (uint32_t)p;
    if (sort_points(A, used, nu)) goto done;
    A3_TICK("out/sort points");
    for (size_t i = 0; i < nu; i++) newid[used[i]] = (uint32_t)i;
    if (want & ARR3_WANT_COORDS) {
        out->V = mem_malloc((3 * nu + 1) * sizeof *out->V);
        if (!out->V) goto done;
        for (size_t i = 0; i < nu; i++)
            for (int k = 0; k < 3; k++)
                out->V[3 * i + k] =
                    ((double)A->oi[k] + dh[3 * (size_t)used[i] + k] + dl[3 * (size_t)used[i] + k]) *
                    A->step;
    }
    rc = 0;
done:
    free(used);
    return rc;
}

/* The edges inside the patches (one a twin pair, after the ne edges of E) added to E, then
 * every edge numbered in the order of its new ends: EV, and newe (by old edge: its number).
 * -1 out of memory. */
static int output_edges(const a3 *A, cedges *E, const uint32_t *newid, size_t nin, uint32_t *newe,
                        lar3 *out)
{
    size_t ne = E->ne, pe = A->npatch ? A->u_off[A->npatch] : 0;
    uint32_t *ev = mem_realloc(E->ev, (2 * (ne + nin) + 2) * sizeof *ev);
    if (!ev) return -1;
    E->ev = ev;
    for (size_t f = 0; f < pe; f++) {
        uint32_t o = A->cyc_off[A->f_cyc[f]], n = A->cyc_off[A->f_cyc[f] + 1] - o;
        for (uint32_t t = 0; t < n; t++) {
            uint32_t x = o + t, y = A->etwin[x];
            if (y == NONE || x > y) continue;
            uint32_t a = A->ent[x], b = A->ent[t + 1 < n ? x + 1 : o];
            ev[2 * ne] = a < b ? a : b, ev[2 * ne + 1] = a < b ? b : a;
            E->ent_e[x] = E->ent_e[y] = (uint32_t)ne++;
        }
    }
    E->ne = ne;
    kv *ek = mem_malloc((ne + 1) * sizeof *ek);
    out->EV = mem_malloc((2 * ne + 1) * sizeof *out->EV);
    if (!ek || !out->EV) {
        free(ek);
        return -1;
    }
    for (size_t e = 0; e < ne; e++) {
        uint32_t a = newid[E->ev[2 * e]], b = newid[E->ev[2 * e + 1]];
        ek[e] = (kv){a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a, (uint32_t)e};
    }
    if (sort_kv(ek, ne)) {
        free(ek);
        return -1;
    }
    for (size_t i = 0; i < ne; i++) {
        out->EV[2 * i] = (uint32_t)(ek[i].k >> 32);
        out->EV[2 * i + 1] = (uint32_t)ek[i].k;
        newe[ek[i].v] = (uint32_t)i;
    }
    free(ek);
    return 0;
}

/* The faces' cycles in the new numbering (fc_off, fc, cyc_off, cyc) and the room of their
 * edges (fe_off, fe; out_faces fills them).  -1 out of memory. */
static int output_cycles(const a3 *A, const uint32_t *newid, lar3 *out)
{
    size_t nf = A->nf;
    out->fc_off = mem_malloc((nf + 1) * sizeof *out->fc_off);
    out->fc = mem_malloc((A->ncyc + 1) * sizeof *out->fc);
    out->fe_off = mem_malloc((nf + 1) * sizeof *out->fe_off);
    out->ncyc = A->ncyc;
    out->cyc_off = mem_malloc((A->ncyc + 1) * sizeof *out->cyc_off);
    out->cyc = mem_malloc((A->nent + 1) * sizeof *out->cyc);
    if (!out->fc_off || !out->fc || !out->fe_off || !out->cyc_off || !out->cyc) return -1;
    out->fc_off[0] = out->fe_off[0] = 0;
    for (size_t f = 0; f < nf; f++) {
        uint32_t nfe = 0;
        for (uint32_t cy = A->f_cyc[f]; cy < A->f_cyc[f + 1]; cy++) {
            uint32_t n = A->cyc_off[cy + 1] - A->cyc_off[cy];
            nfe += n < 2 ? 0 : n;
        }
        out->fc_off[f + 1] = A->f_cyc[f + 1];
        out->fe_off[f + 1] = out->fe_off[f] + nfe;
    }
    out->fe = mem_malloc((out->fe_off[nf] + 1) * sizeof *out->fe);
    if (!out->fe) return -1;
    for (size_t cy = 0; cy <= A->ncyc; cy++) out->cyc_off[cy] = A->cyc_off[cy];
    for (size_t i = 0; i < A->nent; i++) out->cyc[i] = newid[A->ent[i]];
    return 0;
}

/* fsol: the room a face with several pieces left unused (NONE) closed up. */
static void output_fsol_close(size_t nf, lar3 *out)
{
    uint32_t w = 0;
    for (size_t f = 0; f < nf; f++) {
        uint32_t r0 = out->fsol_off[f], r1 = out->fsol_off[f + 1];
        out->fsol_off[f] = w;
        for (uint32_t i = r0; i < r1 && out->fsol[i] != NONE; i++)
            out->fsol[w] = out->fsol[i], out->fwind[w++] = out->fwind[i];
    }
    out->fsol_off[nf] = w;
}

/* CV: the sorted vertices of each cell's faces (each once: a stamp per vertex; a large cell is
 * read off in vertex order, a small one sorted).  -1 out of memory. */
static int output_cv(const a3 *A, lar3 *out)
{
    size_t nc = out->nc, ncv = 0, capcv = 0, step = nc / 50 + 1;
    uint32_t *cv = NULL, *stamp = mem_calloc(out->nv + 1, sizeof *stamp);
    out->cv_off = mem_calloc(nc + 1, sizeof *out->cv_off);
    if (!out->cv_off || !stamp) goto fail;
    for (size_t k = 0; k < nc; k++) {
        size_t start = ncv;
        if (k % step == 0) a3_progress(A, "cells", 0.8 + 0.2 * (double)k / (double)nc);
        for (uint32_t i = out->cf_off[k]; i < out->cf_off[k + 1]; i++) {
            uint32_t f = (uint32_t)abs(out->cf[i]) - 1;
            for (uint32_t x = out->cyc_off[out->fc_off[f]]; x < out->cyc_off[out->fc_off[f + 1]];
                 x++) {
                uint32_t v = out->cyc[x];
                if (stamp[v] == k + 1) continue;
                stamp[v] = (uint32_t)k + 1;
                if (A3_PUSH(cv, ncv, capcv, v)) goto fail;
            }
        }
        size_t m = ncv - start;
        if (m > out->nv / 16) {
            size_t w = start;
            for (uint32_t v = 0; v < out->nv; v++)
                if (stamp[v] == k + 1) cv[w++] = v;
        } else if (m > 1) {
            qsort(cv + start, m, sizeof *cv, u32_cmp);
        }
        out->cv_off[k + 1] = (uint32_t)ncv;
    }
    free(stamp);
    out->cv = cv ? cv : mem_malloc(sizeof *out->cv);
    return out->cv ? 0 : -1;
fail:
    free(stamp), free(cv);
    return -1;
}

/* Stage "output": the faces' solids (fsol); with ARR3_WANT_FACES the points numbered in order
 * of position and V (output_points), the edges in order of their ends and EV (output_edges),
 * and the faces' cycles and edges (output_cycles, out_faces); FN and fsrc, CV when asked for
 * (output_cv).  Returns 0, -1 out of memory, -3 cancelled. */
A3_STAGE static int output_make(a3 *A, cedges *E, const double *dh, const double *dl, lar3 *out)
{
    size_t nf = A->nf, nin = 0, pe = A->npatch ? A->u_off[A->npatch] : 0;
    unsigned want = A->o->want ? A->o->want : ~0u;
    uint32_t *newid = mem_malloc((A->npt + 1) * sizeof *newid), *newe = NULL;
    int rc = -1;
/* Between the bounded parts of the output: a cancel ends it (-3). */
#define OUTPUT_CANCEL_POINT                                                                        \
    do {                                                                                           \
        if (a3_cancelled(A)) {                                                                     \
            rc = -3;                                                                               \
            goto done;                                                                             \
        }                                                                                          \
    } while (0)
    if (!newid) goto done;
    /* the points the faces use, and the edges inside the patches: one a twin pair */
    for (size_t p = 0; p < A->npt; p++) newid[p] = NONE;
    size_t nu = 0;
    for (size_t i = 0; i < A->nent; i++)
        nu += newid[A->ent[i]] == NONE ? (newid[A->ent[i]] = 0, 1) : 0;
    for (size_t f = 0; f < pe; f++)
        for (uint32_t x = A->cyc_off[A->f_cyc[f]]; x < A->cyc_off[A->f_cyc[f + 1]]; x++)
            nin += A->etwin[x] != NONE && x < A->etwin[x];
    out->nv = nu;
    out->ne = E->ne + nin;
    out->nf = nf;
    /* the faces' solids: those covering it an odd number of times (room first, then closed up) */
    out->fsol_off = mem_malloc((nf + 1) * sizeof *out->fsol_off);
    if (!out->fsol_off) goto done;
    out->fsol_off[0] = 0;
    for (size_t f = 0; f < nf; f++)
        out->fsol_off[f + 1] = out->fsol_off[f] + (A->f_cov[f + 1] - A->f_cov[f]);
    out->fsol = mem_malloc((out->fsol_off[nf] + 1) * sizeof *out->fsol);
    out->fwind = mem_malloc((out->fsol_off[nf] + 1) * sizeof *out->fwind);
    if (!out->fsol || !out->fwind) goto done;
    A3_TICK("out/points used");
    if (want & ARR3_WANT_FACES) {
        OUTPUT_CANCEL_POINT;
        if (output_points(A, newid, nu, dh, dl, out, want)) goto done;
        a3_progress(A, "cells", 0.6);
        OUTPUT_CANCEL_POINT;
        newe = mem_malloc((E->ne + nin + 1) * sizeof *newe);
        if (!newe || output_edges(A, E, newid, nin, newe, out)) goto done;
        A3_TICK("out/edges");
        OUTPUT_CANCEL_POINT;
        a3_progress(A, "cells", 0.7);
        if (output_cycles(A, newid, out)) goto done;
    }
    if (want & ARR3_WANT_NORMALS) {
        out->FN = mem_malloc((3 * nf + 1) * sizeof *out->FN);
        out->fsrc = mem_malloc((nf + 1) * sizeof *out->fsrc);
        if (!out->FN || !out->fsrc) goto done;
    }
    {
        outjob j = {A, out, newid, newe, E->ent_e};
        par_for(A->threads, (nf + OUT_CHUNK - 1) / OUT_CHUNK, out_faces, &j);
        A3_TICK("out/faces");
        OUTPUT_CANCEL_POINT;
    }
    output_fsol_close(nf, out);
    a3_progress(A, "cells", 0.8);
    if ((want & ARR3_WANT_CV) && out->cyc && out->cf && output_cv(A, out)) goto done;
    out->stats.nv = out->nv;
    out->stats.ne = out->ne;
    out->stats.nf = out->nf;
    out->stats.nc = out->nc;
    rc = 0;
#undef OUTPUT_CANCEL_POINT
done:
    free(newid), free(newe);
    return rc;
}

int a3_cells(a3 *A, lar3 *out, char *err, size_t errlen)
{
    cedges E = {0};
    cshells S = {0};
    uint32_t *cu = NULL;
    double *dh = NULL, *dl = NULL;
    int rc = ARR_ENOMEM;

/* Between the stages: a cancel ends the run (each stage is a bounded part of it). */
#define CELLS_CANCEL_POINT                                                                         \
    do {                                                                                           \
        if (a3_cancelled(A)) {                                                                     \
            rc = ARR_ECANCELED;                                                                    \
            goto done;                                                                             \
        }                                                                                          \
    } while (0)
    if (edges_make(A, &E)) goto done;
    A3_TICK("cells/edges");
    CELLS_CANCEL_POINT;
    a3_progress(A, "cells", 0.1);
    if ((rc = fans_make(A, &E, out, err, errlen)) != ARR_OK) goto done;
    A3_TICK("cells/fans");
    CELLS_CANCEL_POINT;
    rc = ARR_ENOMEM;
    if (shells_make(A, &E, &S)) goto done;
    A3_TICK("cells/shells");
    CELLS_CANCEL_POINT;
    a3_progress(A, "cells", 0.3);
    rc = ARR_ENOMEM;
    if (!(cu = mem_malloc((S.nsh + 2) * sizeof *cu))) goto done;
    if ((rc = nesting_make(A, &S, cu, err, errlen)) != ARR_OK) goto done;
    A3_TICK("cells/nesting");
    CELLS_CANCEL_POINT;
    if ((rc = cells_make(A, &S, cu, out, &dh, &dl, err, errlen)) != ARR_OK) goto done;
    A3_TICK("cells/cells");
    CELLS_CANCEL_POINT;
    cshells_free(&S);
    a3_progress(A, "cells", 0.55);
    rc = ARR_ENOMEM;
    int om = output_make(A, &E, dh, dl, out);
    if (om == -3) rc = ARR_ECANCELED;
    if (om) goto done;
    A3_TICK("cells/output");
    CELLS_CANCEL_POINT;
    rc = ARR_OK;
#undef CELLS_CANCEL_POINT
done:
    if (rc == ARR_ENOMEM && err && errlen) snprintf(err, errlen, "out of memory");
    cedges_free(&E);
    cshells_free(&S);
    free(cu);
    free(dh);
    free(dl);
    return rc;
}
