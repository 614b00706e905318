/* arr3_plane.c — the exact arrangement of one plane (stage 4 of arr3.h).
 *
 * Input: the pieces lying in plane P (their edges, each with the vertical plane through it), the
 * cuts given to P (each with the other piece's plane as its side plane) and the contact points
 * given to P.  Every segment lies on the line where P meets its side plane S, so every 2D
 * question is a 3D predicate of core/pred.h:
 *   side     which side of a segment's line a point of P lies on is the sign of the point
 *            against S (orient_plane), known to be zero for the segment's own points;
 *   order    points on one line are ordered by one coordinate (the largest component of the
 *            line's direction n_P x n_S);
 *   cross    two segments crossing properly meet at an LPI (when one is an input edge: that
 *            edge against the other's side plane) or at the TPI of P and both side planes;
 *   angle    the direction of an edge is +-(n_P x n_S); two directions compare by the sign of
 *            det(n_P, n_S1, n_S2) (the cross product of two such directions is n_P times it).
 * Steps: all pairs of segments (and contact points) whose boxes meet, from a sweep along u,
 * give the split points; equal points are merged (pset); the segments are cut at their split
 * points into edges, equal edges merged (the pieces whose boundary an edge lies on are kept);
 * the half-edges around each vertex are sorted by angle and walked into cycles, counter-
 * clockwise in the projection along the normal's largest axis k (u = k+1, v = k+2).  Each
 * connected component's outside cycle is the one left of the highest-angle half-edge at its
 * lowest vertex (v, then u); a component is placed in the face holding it by a ray down from
 * that vertex to the nearest edge of another component below (exact comparisons of edges that
 * straddle the ray).  Which pieces cover a face follows from walking from the unbounded face
 * across edges, each crossing toggling the pieces whose boundary that edge is: no sample point.
 * The topology is core/planar.c's half-edge kernel, this file being one model of it (traits:
 * model_around, model_espan, model_qspan, model_scan): sort around points, successors, cycles,
 * and the placement over its slab index (each component scans the edges of its slab, whose keys
 * come from the conservative u spans of span_fast of core/pred.c, scaled to int64); the coverage
 * walk is member_walk_ws (core/member.h, its scratch kept in pwork from plane to plane).  plane_run
 * is stages: segments, split, cycles, components, faces, coverage, output. The faces covered by at
 * least one piece are P's faces of the complex, their cycles turned to run counter-clockwise about
 * P's normal.
 *
 * Threads: planes run on par_for(); each worker has its own scratch (pwork) and writes only its
 * plane's pfaces.  Nothing here depends on the number of threads.
 */
#include "core/arr3_int.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/mem.h"
#include "core/member.h"
#include "core/par.h"
#include "core/planar.h"
#include "core/util.h"

#define NEWBASE 0x80000000u /* output ids from here are the plane's new points */
#define UNB     UINT32_MAX  /* the unbounded face */
/* The placement keys run over [0, KEY_SPAN] (a scale, not a tolerance): room for any slab count
 * the kernel's index takes, and far from int64's end. */
#define KEY_SPAN 0x1p40

typedef struct pseg {
    uint32_t p0, p1; /* local points; p0 == p1: a contact point, not a segment */
    uint32_t side;
    uint32_t va, vb;      /* input edge (va < vb), or NONE */
    uint32_t prov, nprov; /* the pieces whose boundary it is: sprov[prov .. prov + nprov) */
    int ax;               /* largest |component| of n_P x n_side */
    double lo[2], hi[2];
} pseg;

typedef struct split {
    uint32_t seg, pt;
} split;

typedef struct pedge {
    uint32_t a, b; /* a < b */
    uint32_t side, va, vb;
    uint32_t prov, nprov; /* pieces: prov[prov .. prov + nprov) */
    int sig;              /* +1: a -> b runs along n_P x n_side */
    i128 du, dv;          /* n_P x n_side projected (u, v) */
} pedge;

typedef struct pwork {
    const a3 *A;
    uint32_t P; /* the plane */
    int k, u, v, sgnk;
    /* local points */
    xpt *lp;
    uint32_t *lg; /* global id, or NONE for a new point */
    size_t nlp, caplp, caplg;
    uint32_t *htab; /* global -> local */
    size_t hcap;
    uint32_t *hused;
    size_t nhused, caphused;
    uint32_t *alias;
    size_t capalias;
    pset ps;
    /* segments and splits */
    pseg *sg;
    size_t nsg, capsg;
    split *sp;
    size_t nsp, capsp;
    uint32_t *sprov; /* the segments' pieces */
    size_t nsprov, capsprov;
    uint32_t *grp, *rank;
    size_t capgrp, caprank;
    uint32_t *order, *active;
    size_t caporder, capactive;
    uint32_t *tmp;
    size_t captmp;
    /* edges */
    pedge *ed;
    size_t ned, caped;
    uint32_t *prov;
    size_t nprov, capprov;
    /* half-edges */
    uint32_t *voff, *vh; /* outgoing half-edges by vertex */
    size_t capvoff, capvh;
    uint32_t *pos, *next, *hcyc;
    size_t cappos, capnext, caphcyc;
    uint32_t *hes, *hoff; /* the cycles' half-edges (planar_cycles), hoff: ncyc + 1 offsets */
    size_t ncyc, caphes, caphoff;
    uint32_t *comp, *low, *ext, *host, *iso;
    size_t capcomp, caplow, capext, caphost, capiso;
    uint8_t *used;
    size_t capused;
    /* faces, coverage */
    uint32_t *fof, *aoff, *adj; /* faces; their adjacency: neighbours, then the edges crossed */
    uint32_t *covo, *covn;      /* coverage: each cycle's cell, each edge's first piece */
    size_t capfof, capaoff, capadj, capcovo, capcovn;
    uint32_t *x1, *x2;
    size_t capx1, capx2;
    double *span; /* placement: the edges' and queries' conservative spans */
    size_t capspan, nq;
    double kx0, ks;   /* placement keys: (x - kx0) * ks */
    planar_ws pws;    /* placement scratch */
    uint8_t *reached; /* by piece of the plane: goes through the arrangement */
    size_t capreached;
    member_ws mws; /* the coverage walk's scratch, and its rows */
    int fail;
    A3_PAD;
} pwork;

#define GROW(w, arr, need) mem_grow(&(w)->arr, &(w)->cap##arr, (need), sizeof *(w)->arr)

/* ---- local points -------------------------------------------------------------------- */

static uint32_t lp_new(pwork *w, xpt p, uint32_t gid)
{
    if (GROW(w, lp, w->nlp + 1) || GROW(w, lg, w->nlp + 1)) return NONE;
    w->lp[w->nlp] = p;
    w->lg[w->nlp] = gid;
    return (uint32_t)w->nlp++;
}

static uint32_t lp_global(pwork *w, uint32_t gid)
{
    if (2 * (w->nhused + 1) > w->hcap) {
        size_t ncap = w->hcap ? 2 * w->hcap : 256;
        uint32_t *t = mem_malloc(ncap * sizeof *t);
        if (!t) return NONE;
        memset(t, 0xff, ncap * sizeof *t);
        for (size_t i = 0; i < w->nhused; i++) {
            uint32_t l = w->hused[i];
            size_t h = a3_mix64(w->lg[l]) & (ncap - 1);
            while (t[h] != NONE) h = (h + 1) & (ncap - 1);
            t[h] = l;
        }
        free(w->htab);
        w->htab = t;
        w->hcap = ncap;
    }
    size_t h = a3_mix64(gid) & (w->hcap - 1);
    while (w->htab[h] != NONE) {
        if (w->lg[w->htab[h]] == gid) return w->htab[h];
        h = (h + 1) & (w->hcap - 1);
    }
    uint32_t l = lp_new(w, w->A->pt[gid], gid);
    if (l == NONE || GROW(w, hused, w->nhused + 1)) return NONE;
    w->htab[h] = l;
    w->hused[w->nhused++] = l;
    return l;
}

static void lp_reset(pwork *w)
{
    if (a3_table_oversized(w->hcap, w->nhused)) {
        free(w->htab);
        w->htab = NULL, w->hcap = 0;
    } else if (w->htab && w->nhused) {
        memset(w->htab, 0xff, w->hcap * sizeof *w->htab);
    }
    w->nhused = 0;
    w->nlp = 0;
}

/* ---- predicates on segments ---------------------------------------------------------- */

/* Sign of local point x against segment s's side plane (0: on s's line). */
static int seg_side(const pwork *w, const pseg *s, uint32_t x)
{
    if (x == s->p0 || x == s->p1) return 0;
    const xpt *p = &w->lp[x];
    if (s->va != NONE) {
        if (p->kind == PT_GRID && (p->a == s->va || p->a == s->vb)) return 0;
        if (p->kind == PT_LPI && p->a == s->va && p->b == s->vb) return 0;
    }
    return orient_plane(&w->A->G, p, s->side);
}

static int lcmp(const pwork *w, uint32_t a, uint32_t b, int ax)
{
    if (a == b) return 0;
    return cmp_coord(&w->A->G, &w->lp[a], &w->lp[b], ax);
}

/* Is x (on s's line) strictly between s's endpoints? */
static int strictly_inside(const pwork *w, const pseg *s, uint32_t x)
{
    if (x == s->p0 || x == s->p1) return 0;
    int a = lcmp(w, x, s->p0, s->ax), b = lcmp(w, x, s->p1, s->ax);
    return a * b < 0;
}

static int add_split(pwork *w, uint32_t seg, uint32_t pt)
{
    split s = {seg, pt};
    return A3_PUSH(w->sp, w->nsp, w->capsp, s);
}

static int axis_of(const i128 *d)
{
    int ax = 0;
    for (int i = 1; i < 3; i++)
        if ((d[i] < 0 ? -d[i] : d[i]) > (d[ax] < 0 ? -d[ax] : d[ax])) ax = i;
    return ax;
}

/* The point where the lines of s and t (crossing properly inside both) meet. */
static xpt crossing(const pwork *w, const pseg *s, const pseg *t)
{
    const geo *G = &w->A->G;
    if (s->va != NONE) return xpt_lpi(G, s->va, s->vb, t->side);
    if (t->va != NONE) return xpt_lpi(G, t->va, t->vb, s->side);
    uint32_t a = w->P, b = s->side, c = t->side, x;
    if (a > b) x = a, a = b, b = x;
    if (b > c) x = b, b = c, c = x;
    if (a > b) x = a, a = b, b = x;
    return xpt_tpi(G, a, b, c);
}

static int test_pair(pwork *w, uint32_t i, uint32_t j)
{
    const pseg *s = &w->sg[i], *t = &w->sg[j];
    int sp = s->p0 == s->p1, tp = t->p0 == t->p1;
    if (sp && tp) return 0;
    if (sp || tp) {
        const pseg *g = sp ? t : s;
        uint32_t x = sp ? s->p0 : t->p0;
        if (seg_side(w, g, x) == 0 && strictly_inside(w, g, x)) return add_split(w, sp ? j : i, x);
        return 0;
    }
    int o1 = seg_side(w, s, t->p0), o2 = seg_side(w, s, t->p1);
    if (o1 * o2 > 0) return 0;
    int o3 = seg_side(w, t, s->p0), o4 = seg_side(w, t, s->p1);
    if (o3 * o4 > 0) return 0;
    if (o1 == 0 && o2 == 0) { /* collinear: each endpoint inside the other splits it */
        for (int e = 0; e < 2; e++) {
            uint32_t x = e ? t->p1 : t->p0;
            if (strictly_inside(w, s, x) && add_split(w, i, x)) return -1;
            x = e ? s->p1 : s->p0;
            if (strictly_inside(w, t, x) && add_split(w, j, x)) return -1;
        }
        return 0;
    }
    if (o1 == 0 && strictly_inside(w, s, t->p0) && add_split(w, i, t->p0)) return -1;
    if (o2 == 0 && strictly_inside(w, s, t->p1) && add_split(w, i, t->p1)) return -1;
    if (o3 == 0 && strictly_inside(w, t, s->p0) && add_split(w, j, s->p0)) return -1;
    if (o4 == 0 && strictly_inside(w, t, s->p1) && add_split(w, j, s->p1)) return -1;
    if (o1 * o2 < 0 && o3 * o4 < 0) {
        uint32_t x = lp_new(w, crossing(w, s, t), NONE);
        if (x == NONE || add_split(w, i, x) || add_split(w, j, x)) return -1;
    }
    return 0;
}

/* ---- the sweep ----------------------------------------------------------------------- */

static int cmp_lo(const void *pa, const void *pb, void *vw)
{
    const pwork *w = vw;
    double a = w->sg[*(const uint32_t *)pa].lo[0], b = w->sg[*(const uint32_t *)pb].lo[0];
    return (a > b) - (a < b);
}

static void seg_box(pwork *w, pseg *s)
{
    for (int d = 0; d < 2; d++) {
        int ax = d ? w->v : w->u;
        span_fast(w->lp[s->p0].x[ax], w->lp[s->p1].x[ax], &s->lo[d], &s->hi[d]);
    }
}

static int sweep(pwork *w)
{
    size_t n = w->nsg, na = 0;
    if (GROW(w, order, n + 1) || GROW(w, active, n + 1)) return -1;
    for (size_t i = 0; i < n; i++) w->order[i] = (uint32_t)i;
    if (n > 1) qsort_r(w->order, n, sizeof *w->order, cmp_lo, w);
    for (size_t q = 0; q < n; q++) {
        uint32_t i = w->order[q];
        const pseg *s = &w->sg[i];
        size_t m = 0;
        for (size_t a = 0; a < na; a++) {
            uint32_t j = w->active[a];
            const pseg *t = &w->sg[j];
            if (t->hi[0] < s->lo[0]) continue; /* done with it */
            w->active[m++] = j;
            if (t->hi[1] < s->lo[1] || s->hi[1] < t->lo[1]) continue;
            if (test_pair(w, j, i)) return -1;
        }
        na = m;
        w->active[na++] = i;
    }
    return 0;
}

/* ---- merging points, cutting segments into edges -------------------------------------- */

static const xpt *get_local(const void *ctx, uint32_t id)
{
    const pwork *w = ctx;
    return &w->lp[id];
}

static int dedup_local(pwork *w)
{
    if (GROW(w, alias, w->nlp + 1)) return -1;
    pset_clear(&w->ps, 0);
    for (size_t i = 0; i < w->nlp; i++) {
        w->alias[i] = (uint32_t)i;
        if (w->lg[i] == NONE) {
            uint32_t q = pset_find(&w->ps, &w->A->G, &w->lp[i], get_local, w);
            if (q != NONE) {
                w->alias[i] = q;
                continue;
            }
        }
        if (pset_add(&w->ps, &w->lp[i], (uint32_t)i)) return -1;
    }
    return 0;
}

typedef struct sortctx {
    const pwork *w;
    int ax;
} sortctx;

static int cmp_along(const void *pa, const void *pb, void *vc)
{
    const sortctx *c = vc;
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    int r = lcmp(c->w, a, b, c->ax);
    return r ? r : (a > b) - (a < b);
}

static int cmp_split(const void *pa, const void *pb)
{
    const split *a = pa, *b = pb;
    if (a->seg != b->seg) return a->seg < b->seg ? -1 : 1;
    return (a->pt > b->pt) - (a->pt < b->pt);
}

static int add_edge(pwork *w, const pseg *s, uint32_t a, uint32_t b)
{
    if (a == b) return 0;
    /* prov/nprov refer to the segment's pieces (sprov) until the edges are merged */
    pedge e = {a < b ? a : b, a < b ? b : a, s->side, s->va, s->vb, s->prov, s->nprov, 0, 0, 0};
    return A3_PUSH(w->ed, w->ned, w->caped, e);
}

static int cmp_edge(const void *pa, const void *pb)
{
    const pedge *a = pa, *b = pb;
    if (a->a != b->a) return a->a < b->a ? -1 : 1;
    if (a->b != b->b) return a->b < b->b ? -1 : 1;
    return (a->prov > b->prov) - (a->prov < b->prov);
}

static int cmp_side(const void *pa, const void *pb, void *vw)
{
    const pwork *w = vw;
    uint32_t x = *(const uint32_t *)pa, y = *(const uint32_t *)pb;
    const pseg *a = &w->sg[x], *b = &w->sg[y];
    if (a->side != b->side) return a->side < b->side ? -1 : 1;
    return (x > y) - (x < y);
}

/* Segments with one side plane lie on one line: their union is cut at all their endpoints
 * into elementary pieces, each with the pieces (XOR) of the segments covering it.  Overlapping
 * collinear edges (coplanar faces' shared lines) then cost one sort, not a test per pair. */
static int merge_collinear(pwork *w)
{
    size_t n = w->nsg, ng = 0;
    if (GROW(w, grp, n + 1)) return -1;
    for (size_t i = 0; i < n; i++)
        if (w->sg[i].p0 != w->sg[i].p1) w->grp[ng++] = (uint32_t)i;
    if (ng > 1) qsort_r(w->grp, ng, sizeof *w->grp, cmp_side, w);
    for (size_t g0 = 0; g0 < ng;) {
        size_t g1 = g0 + 1;
        while (g1 < ng && w->sg[w->grp[g1]].side == w->sg[w->grp[g0]].side) g1++;
        if (g1 - g0 < 2) {
            g0 = g1;
            continue;
        }
        int ax = w->sg[w->grp[g0]].ax;
        uint32_t side = w->sg[w->grp[g0]].side;
        /* the group's points, sorted along the line */
        size_t m = 0;
        if (GROW(w, tmp, 2 * (g1 - g0))) return -1;
        for (size_t k = g0; k < g1; k++) {
            w->tmp[m++] = w->sg[w->grp[k]].p0;
            w->tmp[m++] = w->sg[w->grp[k]].p1;
        }
        sortctx c = {w, ax};
        qsort_r(w->tmp, m, sizeof *w->tmp, cmp_along, &c);
        size_t u = 0;
        for (size_t k = 0; k < m; k++)
            if (!u || w->tmp[k] != w->tmp[u - 1]) w->tmp[u++] = w->tmp[k];
        m = u;
        /* each segment's range of ranks over the elementary intervals */
        if (GROW(w, rank, 2 * (g1 - g0))) return -1;
        for (size_t k = g0; k < g1; k++) {
            const pseg *sg = &w->sg[w->grp[k]];
            for (int e = 0; e < 2; e++) {
                uint32_t x = e ? sg->p1 : sg->p0;
                size_t lo = 0, hi = m;
                while (lo < hi) { /* the rank of x: the first not before it */
                    size_t mid = (lo + hi) / 2;
                    if (cmp_along(&w->tmp[mid], &x, &c) < 0)
                        lo = mid + 1;
                    else
                        hi = mid;
                }
                w->rank[2 * (k - g0) + (size_t)e] = (uint32_t)lo;
            }
            if (w->rank[2 * (k - g0)] > w->rank[2 * (k - g0) + 1]) {
                uint32_t t = w->rank[2 * (k - g0)];
                w->rank[2 * (k - g0)] = w->rank[2 * (k - g0) + 1];
                w->rank[2 * (k - g0) + 1] = t;
            }
        }
        /* the elementary intervals, each with the XOR of its covering segments' pieces */
        for (size_t i = 0; i + 1 < m; i++) {
            size_t cover = 0, p0 = w->nsprov;
            uint32_t va = NONE, vb = NONE;
            for (size_t k = g0; k < g1; k++) {
                if (!(w->rank[2 * (k - g0)] <= i && i < w->rank[2 * (k - g0) + 1])) continue;
                const pseg *sg = &w->sg[w->grp[k]];
                cover++;
                if (sg->va != NONE) va = sg->va, vb = sg->vb;
                size_t have = w->nsprov - p0;
                if (GROW(w, sprov, w->nsprov + sg->nprov + 1) || GROW(w, x2, have + sg->nprov + 1))
                    return -1;
                size_t nx =
                    member_symdiff(w->sprov + p0, have, w->sprov + sg->prov, sg->nprov, w->x2);
                memcpy(w->sprov + p0, w->x2, nx * sizeof *w->x2);
                w->nsprov = p0 + nx;
            }
            if (!cover) continue;
            pseg ns = {
                w->tmp[i], w->tmp[i + 1], side,  va, vb, (uint32_t)p0, (uint32_t)(w->nsprov - p0),
                ax,        {0, 0},        {0, 0}};
            if (A3_PUSH(w->sg, w->nsg, w->capsg, ns)) return -1;
        }
        for (size_t k = g0; k < g1; k++) w->sg[w->grp[k]].side = NONE; /* replaced */
        g0 = g1;
    }
    size_t k = 0;
    for (size_t i = 0; i < w->nsg; i++)
        if (w->sg[i].side != NONE || w->sg[i].p0 == w->sg[i].p1) w->sg[k++] = w->sg[i];
    w->nsg = k;
    for (size_t i = 0; i < w->nsg; i++) seg_box(w, &w->sg[i]);
    return 0;
}

static int make_edges(pwork *w)
{
    w->ned = 0;
    for (size_t i = 0; i < w->nsp; i++) w->sp[i].pt = w->alias[w->sp[i].pt];
    if (w->nsp > 1) qsort(w->sp, w->nsp, sizeof *w->sp, cmp_split);
    size_t j = 0;
    for (size_t i = 0; i < w->nsg; i++) {
        pseg *s = &w->sg[i];
        s->p0 = w->alias[s->p0];
        s->p1 = w->alias[s->p1];
        size_t n = 0;
        while (j < w->nsp && w->sp[j].seg < i) j++;
        if (s->p0 == s->p1) {
            while (j < w->nsp && w->sp[j].seg == i) j++;
            continue;
        }
        if (GROW(w, tmp, 2)) return -1;
        w->tmp[n++] = s->p0;
        w->tmp[n++] = s->p1;
        for (; j < w->nsp && w->sp[j].seg == i; j++) {
            if (GROW(w, tmp, n + 1)) return -1;
            w->tmp[n++] = w->sp[j].pt;
        }
        if (n > 2) {
            sortctx c = {w, s->ax};
            qsort_r(w->tmp, n, sizeof *w->tmp, cmp_along, &c);
        } else if (lcmp(w, w->tmp[0], w->tmp[1], s->ax) > 0) {
            uint32_t t = w->tmp[0];
            w->tmp[0] = w->tmp[1], w->tmp[1] = t;
        }
        for (size_t q = 0; q + 1 < n; q++)
            if (w->tmp[q] != w->tmp[q + 1] && add_edge(w, s, w->tmp[q], w->tmp[q + 1])) return -1;
    }
    /* equal edges: one, with the pieces whose boundary it is (each counted modulo 2) */
    if (w->ned > 1) qsort(w->ed, w->ned, sizeof *w->ed, cmp_edge);
    size_t m = 0;
    w->nprov = 0;
    for (size_t i = 0; i < w->ned;) {
        size_t k = i;
        pedge e = w->ed[i];
        e.nprov = 0;
        e.prov = (uint32_t)w->nprov;
        for (; k < w->ned && w->ed[k].a == e.a && w->ed[k].b == e.b; k++) {
            const pedge *x = &w->ed[k];
            if (x->va != NONE && e.va == NONE) {
                e.va = x->va;
                e.vb = x->vb;
                e.side = x->side;
            }
            if (GROW(w, prov, w->nprov + e.nprov + x->nprov + 1) ||
                GROW(w, x2, e.nprov + x->nprov + 1))
                return -1;
            size_t nx =
                member_symdiff(w->prov + e.prov, e.nprov, w->sprov + x->prov, x->nprov, w->x2);
            memcpy(w->prov + e.prov, w->x2, nx * sizeof *w->x2);
            e.nprov = (uint32_t)nx;
        }
        w->nprov = e.prov + e.nprov;
        w->ed[m++] = e;
        i = k;
    }
    w->ned = m;
    return 0;
}

/* ---- half-edges, cycles ---------------------------------------------------------------- */

/* Half-edge h: edge h/2, from a to b when h is even.  Its direction is dsig(h) (n_P x n_side). */
static uint32_t h_from(const pwork *w, uint32_t h)
{
    const pedge *e = &w->ed[h >> 1];
    return (h & 1) ? e->b : e->a;
}

static int h_sig(const pwork *w, uint32_t h)
{
    int s = w->ed[h >> 1].sig;
    return (h & 1) ? -s : s;
}

static int h_half(const pwork *w, uint32_t h)
{
    const pedge *e = &w->ed[h >> 1];
    int s = h_sig(w, h);
    i128 du = s > 0 ? e->du : -e->du, dv = s > 0 ? e->dv : -e->dv;
    return (dv > 0 || (dv == 0 && du > 0)) ? 0 : 1;
}

/* The model's "around" (planar_traits): half-edges a, b leaving one point, by angle
 * counter-clockwise in the projection; equal directions by number (never 0). */
static int model_around(void *vw, uint32_t a, uint32_t b)
{
    const pwork *w = vw;
    int ha = h_half(w, a), hb = h_half(w, b);
    if (ha != hb) return ha - hb;
    const plane3 *pl = w->A->pl;
    const pedge *ea = &w->ed[a >> 1], *eb = &w->ed[b >> 1];
    i128 nb[3] = {pl[eb->side].n[0], pl[eb->side].n[1], pl[eb->side].n[2]};
    int d = det3_sign(pl[w->P].n, pl[ea->side].n, nb) * h_sig(w, a) * h_sig(w, b) * w->sgnk;
    if (d > 0) return -1; /* b is counter-clockwise from a */
    if (d < 0) return 1;
    return (a > b) - (a < b);
}

static int make_cycles(pwork *w)
{
    const plane3 *pl = w->A->pl;
    size_t nh = 2 * w->ned, np = w->nlp;
    if (GROW(w, voff, np + 2) || GROW(w, vh, nh + 1) || GROW(w, pos, nh + 1) ||
        GROW(w, next, nh + 1) || GROW(w, hcyc, nh + 1) || GROW(w, hes, nh + 1))
        return -1;
    for (size_t i = 0; i < w->ned; i++) {
        pedge *e = &w->ed[i];
        i128 d[3];
        cross_ll(pl[w->P].n, pl[e->side].n, d);
        int ax = axis_of(d);
        int c = lcmp(w, e->b, e->a, ax);
        e->sig = (c > 0) == (d[ax] > 0) ? 1 : -1;
        e->du = d[w->u];
        e->dv = d[w->v];
    }
    memset(w->voff, 0, (np + 2) * sizeof *w->voff);
    for (size_t h = 0; h < nh; h++) w->voff[h_from(w, (uint32_t)h) + 2]++;
    for (size_t p = 0; p < np; p++) w->voff[p + 2] += w->voff[p + 1];
    for (size_t h = 0; h < nh; h++) w->vh[w->voff[h_from(w, (uint32_t)h) + 1]++] = (uint32_t)h;
    planar_traits T = {w, model_around, NULL, NULL, NULL, NULL};
    if (planar_sort_around(&T, w->voff, w->vh, w->pos, 0, np)) return -2;
    for (size_t h = 0; h < nh; h++)
        w->next[h] = planar_next(w->voff, w->vh, w->pos, h_from(w, (uint32_t)h ^ 1), (uint32_t)h);
    return planar_cycles(nh, w->next, w->hcyc, w->hes, &w->hoff, &w->caphoff, &w->ncyc);
}

/* ---- components, placement --------------------------------------------------------------- */

/* Is a lower than b: v first, then u. */
static int lower(const pwork *w, uint32_t a, uint32_t b)
{
    int c = lcmp(w, a, b, w->v);
    if (c) return c < 0;
    return lcmp(w, a, b, w->u) < 0;
}

/* Side of local point x against edge e directed along +u: > 0 above (left), < 0 below. */
static int above_edge(const pwork *w, const pedge *e, uint32_t x)
{
    if (x == e->a || x == e->b) return 0;
    const xpt *p = &w->lp[x];
    int o;
    if (e->va != NONE && ((p->kind == PT_GRID && (p->a == e->va || p->a == e->vb)) ||
                          (p->kind == PT_LPI && p->a == e->va && p->b == e->vb)))
        o = 0;
    else
        o = orient_plane(&w->A->G, p, e->side);
    /* left of n_P x n_side about n_P is orient < 0; about the projection, times sgnk; along +u,
     * times the sign of du */
    int su = e->du > 0 ? 1 : -1;
    return -o * w->sgnk * su;
}

static void ends_by_u(const pwork *w, const pedge *e, uint32_t *l, uint32_t *r)
{
    if (lcmp(w, e->a, e->b, w->u) < 0)
        *l = e->a, *r = e->b;
    else
        *l = e->b, *r = e->a;
}

/* Is e1 above e2 where both straddle one vertical line (they do not cross)? */
static int higher(const pwork *w, const pedge *e1, const pedge *e2)
{
    uint32_t l1, r1, l2, r2;
    ends_by_u(w, e1, &l1, &r1);
    ends_by_u(w, e2, &l2, &r2);
    if (lcmp(w, l2, l1, w->u) >= 0) {
        int s = above_edge(w, e1, l2);
        if (s) return s < 0;
        if (lcmp(w, r2, r1, w->u) <= 0) return above_edge(w, e1, r2) < 0;
        return above_edge(w, e2, r1) > 0;
    }
    return above_edge(w, e2, l1) > 0;
}

/* The half-edge of e that runs along +u. */
static uint32_t h_plus_u(const pwork *w, uint32_t e)
{
    uint32_t h = 2 * e;
    int su = w->ed[e].du > 0 ? 1 : -1;
    return h_sig(w, h) * su > 0 ? h : h + 1;
}

/* Does edge e straddle the vertical line through component q's lowest point x (left end
 * strictly left of it, right end not), with x strictly above it?  The conservative v spans
 * first (span_fast), then the exact tests. */
static int model_below(const pwork *w, uint32_t e, uint32_t q)
{
    const pedge *E = &w->ed[e];
    uint32_t x = w->low[q], l, r;
    if (w->span[2 * w->ned + e] > w->span[3 * w->ned + q]) return 0; /* above x */
    ends_by_u(w, E, &l, &r);
    if (!(lcmp(w, l, x, w->u) < 0 && lcmp(w, r, x, w->u) >= 0)) return 0;
    return above_edge(w, E, x) > 0;
}

/* The placement key of a conservative u bound: monotone (a subtraction, a product by ks >= 0
 * and a truncation of a non-negative value, each non-decreasing), so the keys of conservative
 * spans are conservative. */
static inline int64_t u_key(const pwork *w, double x)
{
    return (int64_t)((x - w->kx0) * w->ks);
}

/* The model's "espan" (planar_traits): the keys of the edges' u spans. */
static void model_espan(void *vw, size_t e0, size_t e1, int64_t *lo, int64_t *hi)
{
    const pwork *w = vw;
    const double *elo = w->span, *ehi = elo + w->ned;
    for (size_t e = e0; e < e1; e++) lo[e - e0] = u_key(w, elo[e]), hi[e - e0] = u_key(w, ehi[e]);
}

/* The model's "qspan": the keys of component q's lowest point's u span. */
static void model_qspan(void *vw, uint32_t q, int64_t *lo, int64_t *hi)
{
    const pwork *w = vw;
    const double *qlo = w->span + 3 * w->ned + w->nq, *qhi = qlo + w->nq;
    *lo = u_key(w, qlo[q]), *hi = u_key(w, qhi[q]);
}

/* The model's "scan": of best and the candidates, the highest edge of another component below
 * q's lowest point (model_below) by higher(); edges whose u span misses the point's are not
 * asked. */
static uint32_t model_scan(void *vw, uint32_t q, const uint32_t *cand, size_t n, uint32_t best)
{
    const pwork *w = vw;
    const double *elo = w->span, *ehi = elo + w->ned;
    const double *qlo = w->span + 3 * w->ned + w->nq, *qhi = qlo + w->nq;
    uint32_t b = best;
    for (size_t i = 0; i < n; i++) {
        uint32_t e = cand[i];
        if (w->tmp[e] == q || ehi[e] < qlo[q] || elo[e] > qhi[q]) continue;
        if (e == b || !model_below(w, e, q)) continue;
        if (b == NONE || higher(w, &w->ed[e], &w->ed[b])) b = e;
    }
    return b;
}

/* ext[c]: c's outside cycle (NONE for an isolated point); host[c]: the cycle just below its
 * lowest vertex (NONE: nothing below, the unbounded face), by the kernel's planar_place over
 * the keys of the edges' conservative u spans (span_fast). */
static int place_components(pwork *w, size_t ncomp)
{
    for (size_t c = 0; c < ncomp; c++) {
        uint32_t lw = w->low[c];
        uint32_t n = w->voff[lw + 1] - w->voff[lw];
        w->ext[c] = n ? w->hcyc[w->vh[w->voff[lw] + n - 1]] : NONE;
        w->host[c] = NONE;
    }
    if (ncomp < 2) return 0;
    /* span: u lo, u hi by edge; v lo by edge; v hi by query; u lo, u hi by query */
    size_t ne = w->ned;
    if (GROW(w, span, 3 * ne + 3 * ncomp + 1) || GROW(w, tmp, ne + 1)) return -1;
    double *elo = w->span, *ehi = elo + ne, *evlo = ehi + ne, *qvhi = evlo + ne;
    double *qlo = qvhi + ncomp, *qhi = qlo + ncomp, d, x0 = INFINITY, x1 = -INFINITY;
    for (size_t e = 0; e < ne; e++) {
        const xpt *A = &w->lp[w->ed[e].a], *B = &w->lp[w->ed[e].b];
        span_fast(A->x[w->u], B->x[w->u], &elo[e], &ehi[e]);
        span_fast(A->x[w->v], B->x[w->v], &evlo[e], &d);
        w->tmp[e] = w->comp[w->ed[e].a];
        x0 = elo[e] < x0 ? elo[e] : x0, x1 = ehi[e] > x1 ? ehi[e] : x1;
    }
    for (size_t c = 0; c < ncomp; c++) {
        const xpt *X = &w->lp[w->low[c]];
        span_fast(X->x[w->u], X->x[w->u], &qlo[c], &qhi[c]);
        span_fast(X->x[w->v], X->x[w->v], &d, &qvhi[c]);
        x0 = qlo[c] < x0 ? qlo[c] : x0, x1 = qhi[c] > x1 ? qhi[c] : x1;
    }
    w->nq = ncomp;
    w->kx0 = x0;
    w->ks = x1 > x0 ? KEY_SPAN / (x1 - x0) : 0;
    if (!isfinite(w->ks)) w->ks = 0;
    planar_traits T = {w, NULL, model_espan, model_qspan, model_scan, NULL};
    if (planar_place(&T, 1, &w->pws, ne, 0, u_key(w, x1), ncomp, w->host)) return -1;
    for (size_t c = 0; c < ncomp; c++)
        if (w->host[c] != NONE) w->host[c] = w->hcyc[h_plus_u(w, w->host[c])];
    return 0;
}

/* ---- output ------------------------------------------------------------------------------ */

typedef struct outb {
    pfaces *F;
    size_t capfc, capco, cape, caps, capfv, capcov, capn;
} outb;

static uint32_t out_id(pwork *w, outb *o, uint32_t x, uint32_t *newid)
{
    if (w->lg[x] != NONE) return w->lg[x];
    if (newid[x] == NONE) {
        if (A3_PUSH(o->F->newp, o->F->nnew, o->capn, w->lp[x])) return NONE;
        newid[x] = NEWBASE + o->F->nnew - 1;
    }
    return newid[x];
}

static int out_entry(outb *o, uint32_t id, uint32_t side)
{
    pfaces *F = o->F;
    if (mem_grow(&F->ent, &o->cape, F->nent + 1, sizeof *F->ent) ||
        mem_grow(&F->side, &o->caps, F->nent + 1, sizeof *F->side))
        return -1;
    F->ent[F->nent] = id;
    F->side[F->nent] = side;
    F->nent++;
    return 0;
}

static int out_close_cycle(outb *o)
{
    pfaces *F = o->F;
    if (mem_grow(&F->cyc_off, &o->capco, F->ncyc + 2, sizeof *F->cyc_off)) return -1;
    F->ncyc++;
    F->cyc_off[F->ncyc] = F->nent;
    return 0;
}

/* Writes the cycle starting at half-edge h (or the lone point x when h == NONE), turned to run
 * counter-clockwise about n_P when the projection flips it. */
static int out_cycle(pwork *w, outb *o, uint32_t h, uint32_t x, uint32_t *newid)
{
    pfaces *F = o->F;
    uint32_t start = F->nent;
    if (h == NONE) {
        uint32_t id = out_id(w, o, x, newid);
        if (id == NONE || out_entry(o, id, NONE)) return -1;
        return out_close_cycle(o);
    }
    uint32_t q = h;
    do {
        uint32_t id = out_id(w, o, h_from(w, q), newid);
        if (id == NONE || out_entry(o, id, w->ed[q >> 1].side)) return -1;
        q = w->next[q];
    } while (q != h);
    if (w->sgnk < 0) { /* reverse: points p0..pm-1 become pm-1..p0; edge i -> side of m-2-i */
        uint32_t m = F->nent - start, *E = F->ent + start, *S = F->side + start;
        for (uint32_t i = 0; i < m / 2; i++) {
            uint32_t t = E[i];
            E[i] = E[m - 1 - i], E[m - 1 - i] = t;
        }
        /* sides: new edge i runs from old point m-1-i to old point m-2-i: old edge m-2-i */
        for (uint32_t i = 0; i < (m - 1) / 2; i++) {
            uint32_t t = S[i];
            S[i] = S[m - 2 - i], S[m - 2 - i] = t;
        }
    }
    return out_close_cycle(o);
}

/* ---- one plane ------------------------------------------------------------------------- */

static int box_meets(const int64_t *lo, const int64_t *hi, const int32_t *b)
{
    for (int a = 0; a < 3; a++)
        if (hi[a] < b[a] || lo[a] > b[3 + a]) return 0;
    return 1;
}

/* Marks in w->reached the pieces of plane w->P that go through the arrangement; lists the others
 * in F->direct, to be written as they are.  Only in a plane whose pieces all belong to one solid
 * and turn one way: there a piece whose closed box meets no cut and no contact point can gain
 * no vertex (every new point lies on a cut or is a contact point, inside the closed boxes of all
 * the pieces it touches), and two such pieces meet at most along their edges, so it is a face of
 * the arrangement as it is.  Pieces with holes, and every piece of a plane shared by solids or
 * by both ways of turning, are reached. */
static int reached_pieces(pwork *w, pfaces *F)
{
    const a3 *A = w->A;
    uint32_t P = w->P, o = A->pp_off[P], m = A->pp_off[P + 1] - o;
    uint32_t nt = (A->cs_off[P + 1] - A->cs_off[P]) + (A->cp_off[P + 1] - A->cp_off[P]);
    if (GROW(w, reached, m + 1)) return -1;
    memset(w->reached, 1, m);
    if (!m) return 0;
    const piece *p0 = &A->pc[A->pp[o]];
    if (a3_plane_fold(A, P)) return 0; /* pieces of one solid overlap: all reached */
    for (uint32_t i = 0; i < m; i++) {
        const piece *pc = &A->pc[A->pp[o + i]];
        if (pc->solid != p0->solid || pc->sgn != p0->sgn) return 0; /* all reached */
    }
    if ((uint64_t)m * nt > ((uint64_t)1 << 24)) return 0; /* too many pairs to look at */
    memset(w->reached, 0, m);
    for (uint32_t i = 0; i < m; i++)
        if (A->pc[A->pp[o + i]].nc != 1) w->reached[i] = 1;
    for (uint32_t t = A->cs_off[P]; t < A->cs_off[P + 1]; t++) {
        int64_t lo[3], hi[3], l1[3], h1[3];
        xpt_grid_box_fast(&A->pt[A->cs[t].p0], lo, hi);
        xpt_grid_box_fast(&A->pt[A->cs[t].p1], l1, h1);
        for (int a = 0; a < 3; a++) {
            if (l1[a] < lo[a]) lo[a] = l1[a];
            if (h1[a] > hi[a]) hi[a] = h1[a];
        }
        for (uint32_t i = 0; i < m; i++)
            if (!w->reached[i] && box_meets(lo, hi, A->pc[A->pp[o + i]].box)) w->reached[i] = 1;
    }
    for (uint32_t t = A->cp_off[P]; t < A->cp_off[P + 1]; t++) {
        int64_t lo[3], hi[3];
        xpt_grid_box_fast(&A->pt[A->cp[t].p], lo, hi);
        for (uint32_t i = 0; i < m; i++)
            if (!w->reached[i] && box_meets(lo, hi, A->pc[A->pp[o + i]].box)) w->reached[i] = 1;
    }
    uint32_t nd = 0;
    for (uint32_t i = 0; i < m; i++) nd += !w->reached[i];
    if (!nd) return 0;
    F->direct = mem_malloc(nd * sizeof *F->direct);
    if (!F->direct) return -1;
    for (uint32_t i = 0; i < m; i++)
        if (!w->reached[i]) F->direct[F->ndirect++] = A->pp[o + i];
    return 0;
}

/* Stage "segments" of plane_run: the pieces' edges (of the reached pieces), the cuts and the
 * contact points become segments, each with its axis along the line and its conservative box. */
static int plane_segments(pwork *w, const plane3 *pl)
{
    const a3 *A = w->A;
    uint32_t P = w->P;
    for (uint32_t i = A->pp_off[P]; i < A->pp_off[P + 1]; i++) {
        uint32_t pi = A->pp[i];
        const piece *pc = &A->pc[pi];
        if (!w->reached[i - A->pp_off[P]]) continue; /* in F->direct */
        for (uint32_t cy = pc->c0; cy < pc->c0 + pc->nc; cy++) {
            uint32_t o = A->pc_off[cy], n = A->pc_off[cy + 1] - o;
            for (uint32_t j = 0; j < n; j++) {
                uint32_t a = A->pcv[o + j], b = A->pcv[o + (j + 1) % n];
                pseg s = {lp_global(w, a),
                          lp_global(w, b),
                          A->pcvp[o + j],
                          a < b ? a : b,
                          a < b ? b : a,
                          (uint32_t)w->nsprov,
                          1,
                          0,
                          {0, 0},
                          {0, 0}};
                if (A3_PUSH(w->sprov, w->nsprov, w->capsprov, pi)) return -1;
                if (s.p0 == NONE || s.p1 == NONE) return -1;
                if (A3_PUSH(w->sg, w->nsg, w->capsg, s)) return -1;
            }
        }
    }
    for (uint32_t i = A->cs_off[P]; i < A->cs_off[P + 1]; i++) {
        const cseg *c = &A->cs[i];
        pseg s = {
            lp_global(w, c->p0), lp_global(w, c->p1), c->side, NONE, NONE, 0, 0, 0, {0, 0}, {0, 0}};
        if (s.p0 == NONE || s.p1 == NONE) return -1;
        if (A3_PUSH(w->sg, w->nsg, w->capsg, s)) return -1;
    }
    for (uint32_t i = A->cp_off[P]; i < A->cp_off[P + 1]; i++) {
        uint32_t x = lp_global(w, A->cp[i].p);
        pseg s = {x, x, NONE, NONE, NONE, 0, 0, 0, {0, 0}, {0, 0}};
        if (x == NONE || A3_PUSH(w->sg, w->nsg, w->capsg, s)) return -1;
    }
    for (size_t i = 0; i < w->nsg; i++) {
        pseg *s = &w->sg[i];
        if (s->p0 != s->p1) {
            i128 d[3];
            cross_ll(pl->n, A->pl[s->side].n, d);
            s->ax = axis_of(d);
        }
        seg_box(w, s);
    }
    return 0;
}

/* Stage "components" of plane_run: the points in use (ends of edges, and contact points, which
 * may stand alone), comp[p] their component (NONE: unused), numbered in point order, each with
 * its lowest point low[c]; *ncomp gets their number. */
static int plane_components(pwork *w, size_t *ncomp_out)
{
    size_t np = w->nlp, ncomp = 0;
    if (GROW(w, used, np + 1) || GROW(w, comp, np + 1) || GROW(w, iso, np + 1) ||
        GROW(w, tmp, np + 1))
        return -1;
    memset(w->used, 0, np);
    for (size_t e = 0; e < w->ned; e++) w->used[w->ed[e].a] = w->used[w->ed[e].b] = 1;
    for (size_t i = 0; i < w->nsg; i++)
        if (w->sg[i].p0 == w->sg[i].p1) w->used[w->sg[i].p0] = 1;
    for (size_t p = 0; p < np; p++) w->comp[p] = (uint32_t)p;
    for (size_t e = 0; e < w->ned; e++) uf_union(w->comp, w->ed[e].a, w->ed[e].b);
    for (size_t p = 0; p < np; p++) w->iso[p] = NONE;
    for (size_t p = 0; p < np; p++) {
        if (!w->used[p]) continue;
        uint32_t r = uf_find(w->comp, (uint32_t)p);
        if (w->iso[r] == NONE) {
            if (GROW(w, low, ncomp + 1) || GROW(w, ext, ncomp + 1) || GROW(w, host, ncomp + 1))
                return -1;
            w->low[ncomp] = (uint32_t)p;
            w->iso[r] = (uint32_t)ncomp++;
        }
        uint32_t c = w->iso[r];
        if (lower(w, (uint32_t)p, w->low[c])) w->low[c] = (uint32_t)p;
    }
    for (size_t p = 0; p < np; p++) w->tmp[p] = uf_find(w->comp, (uint32_t)p);
    for (size_t p = 0; p < np; p++) w->comp[p] = w->used[p] ? w->iso[w->tmp[p]] : NONE;
    *ncomp_out = ncomp;
    return 0;
}

/* Stage "faces" of plane_run: every cycle that is not a component's outside is a bounded face.
 * fof[cy]: the face a cycle belongs to (itself, or the face holding its component, UNB for
 * none); host[c] resolved up through outside cycles to a bounded face (or UNB). */
static int plane_faces(pwork *w, size_t ncomp)
{
    size_t ncy = w->ncyc;
    if (GROW(w, fof, ncy + 1) || GROW(w, x1, ncy + 1)) return -1;
    for (size_t cy = 0; cy < ncy; cy++) w->fof[cy] = (uint32_t)cy, w->x1[cy] = NONE;
    for (size_t c = 0; c < ncomp; c++)
        if (w->ext[c] != NONE) w->x1[w->ext[c]] = (uint32_t)c; /* cycle -> its component */
    for (size_t c = 0; c < ncomp; c++) {
        uint32_t h = w->host[c];
        size_t guard = 0;
        while (h != NONE && w->x1[h] != NONE && guard++ <= ncomp) h = w->host[w->x1[h]];
        if (guard > ncomp) return -2;
        w->host[c] = h == NONE ? UNB : h;
    }
    for (size_t c = 0; c < ncomp; c++)
        if (w->ext[c] != NONE) w->fof[w->ext[c]] = w->host[c];
    return 0;
}

/* Stage "coverage" of plane_run: which pieces cover each face, by member_walk (core/member.h)
 * from the unbounded face across the edges, each listing its pieces (ascending, each once:
 * they were made by symmetric differences).  The cells are the faces: cell[cy] for each
 * bounded face cycle, the unbounded face last (cell[ncyc]).  *rows is borrowed from w->mws
 * (valid until the next plane). */
static int plane_coverage(pwork *w, member_rows *rows)
{
    size_t ncy = w->ncyc, ncell = 0;
    if (GROW(w, covo, ncy + 2) || GROW(w, aoff, ncy + 3) || GROW(w, adj, 4 * w->ned + 1) ||
        GROW(w, covn, w->ned + 2))
        return -1;
    uint32_t *cell = w->covo, *toff = w->covn;
    for (size_t cy = 0; cy < ncy; cy++) cell[cy] = w->fof[cy] == cy ? (uint32_t)ncell++ : NONE;
    cell[ncy] = (uint32_t)ncell++; /* UNB */
#define CELL(f) cell[(f) == UNB ? ncy : (f)]
    uint32_t *aoff = w->aoff, *nb = w->adj, *el = w->adj + 2 * w->ned;
    memset(aoff, 0, (ncell + 2) * sizeof *aoff);
    for (size_t e = 0; e < w->ned; e++) {
        uint32_t f1 = CELL(w->fof[w->hcyc[2 * e]]), f2 = CELL(w->fof[w->hcyc[2 * e + 1]]);
        toff[e] = w->ed[e].prov;
        if (f1 == f2) continue;
        aoff[f1 + 2]++;
        aoff[f2 + 2]++;
    }
    toff[w->ned] = (uint32_t)w->nprov;
    for (size_t f = 0; f < ncell; f++) aoff[f + 2] += aoff[f + 1];
    for (size_t e = 0; e < w->ned; e++) {
        uint32_t f1 = CELL(w->fof[w->hcyc[2 * e]]), f2 = CELL(w->fof[w->hcyc[2 * e + 1]]);
        if (f1 == f2) continue;
        nb[aoff[f1 + 1]] = f2, el[aoff[f1 + 1]++] = (uint32_t)e;
        nb[aoff[f2 + 1]] = f1, el[aoff[f2 + 1]++] = (uint32_t)e;
    }
#undef CELL
    uint32_t bad;
    int rc = member_walk_ws(&w->mws, ncell, (uint32_t)(ncell - 1), aoff, nb, el, toff, w->prov,
                            rows, &bad);
    return rc < 0 ? -1 : rc > 0 ? -2 : 0;
}

/* Stage "output" of plane_run: the bounded faces covered by a piece, each with the components
 * it holds and its pieces (rows: by cell, cell[cy] in w->covo). */
static int plane_output(pwork *w, pfaces *F, size_t ncomp, const member_rows *rows)
{
    size_t ncy = w->ncyc, np = w->nlp;
    outb o = {F, 0, 0, 0, 0, 0, 0, 0};
    if (GROW(w, x1, np + 1)) return -1;
    uint32_t *newid = w->x1; /* per local point */
    for (size_t p = 0; p < np; p++) newid[p] = NONE;
    if (mem_grow(&F->f_cyc, &o.capfc, 1, sizeof *F->f_cyc) ||
        mem_grow(&F->f_cov, &o.capfv, 1, sizeof *F->f_cov) ||
        mem_grow(&F->cyc_off, &o.capco, 1, sizeof *F->cyc_off))
        return -1;
    F->f_cyc[0] = 0, F->f_cov[0] = 0, F->cyc_off[0] = 0;
    for (size_t cy = 0; cy < ncy; cy++) {
        if (w->fof[cy] != cy) continue;
        uint32_t k = w->covo[cy], r0 = rows->off[k], r1 = rows->off[k + 1];
        if (r0 == r1) continue;
        if (out_cycle(w, &o, w->hes[w->hoff[cy]], NONE, newid)) return -1;
        for (size_t c = 0; c < ncomp; c++) {
            if (w->host[c] != cy) continue;
            if (out_cycle(w, &o, w->ext[c] == NONE ? NONE : w->hes[w->hoff[w->ext[c]]], w->low[c],
                          newid))
                return -1;
        }
        for (uint32_t i = r0; i < r1; i++)
            if (A3_PUSH(F->cov, F->ncov, o.capcov, rows->idx[i])) return -1;
        if (mem_grow(&F->f_cyc, &o.capfc, F->nf + 2, sizeof *F->f_cyc) ||
            mem_grow(&F->f_cov, &o.capfv, F->nf + 2, sizeof *F->f_cov))
            return -1;
        F->nf++;
        F->f_cyc[F->nf] = F->ncyc;
        F->f_cov[F->nf] = F->ncov;
    }
    return 0;
}

/* The arrangement of plane P into F: -1 out of memory, -2 an inconsistent arrangement (a bug),
 * else 0.  Stages: segments, split (merge_collinear, sweep, dedup_local, make_edges), cycles
 * (the kernel: make_cycles), components and their placement (the kernel: planar_place), faces,
 * coverage (member_walk), output. */
static int plane_run(pwork *w, uint32_t P, pfaces *F)
{
    const a3 *A = w->A;
    const plane3 *pl = &A->pl[P];
    memset(F, 0, sizeof *F);
    F->base = NEWBASE;
    if (a3_plane_simple(A, P)) {
        /* Nothing from another solid reaches this plane, and its pieces are simple polygons of
         * one solid turning the same way: they are its faces as they are (in a surface that
         * does not pass through itself, two such pieces meet at most along their edges; the
         * same side facing out, they cannot overlap).  Pieces turning both ways (a surface
         * touching itself face to face) go through the arrangement. */
        F->trivial = 1; /* merge_planes writes the pieces as they are */
        return 0;
    }
    w->P = P;
    w->k = plane_axis(pl);
    w->u = (w->k + 1) % 3;
    w->v = (w->k + 2) % 3;
    w->sgnk = pl->n[w->k] > 0 ? 1 : -1;
    lp_reset(w);
    w->nsg = w->nsp = w->nsprov = 0;
    if (reached_pieces(w, F) || plane_segments(w, pl)) return -1;
    if (merge_collinear(w) || sweep(w) || dedup_local(w) || make_edges(w)) return -1;
    size_t ncomp;
    int rc = make_cycles(w);
    if (!rc) rc = plane_components(w, &ncomp);
    if (!rc) rc = place_components(w, ncomp);
    if (!rc) rc = plane_faces(w, ncomp);
    if (rc) return rc;
    member_rows rows;
    if ((rc = plane_coverage(w, &rows))) return rc;
    return plane_output(w, F, ncomp, &rows);
}

/* ---- all planes --------------------------------------------------------------------------- */

typedef struct planesctx {
    a3 *A;
    const uint32_t *planes;
    pwork *w;
    int *rc;
} planesctx;

static void plane_item(void *vc, size_t item, int worker)
{
    planesctx *c = vc;
    pwork *w = &c->w[worker];
    uint32_t P = c->planes[item];
    if (w->fail || a3_cancelled(c->A)) {
        c->rc[item] = -3;
        return;
    }
    c->rc[item] = plane_run(w, P, &c->A->pf[P]);
}

static void pwork_free(pwork *w)
{
    free(w->lp), free(w->lg), free(w->htab), free(w->hused), free(w->alias);
    pset_free(&w->ps);
    free(w->sg), free(w->sp), free(w->order), free(w->active), free(w->tmp);
    free(w->sprov), free(w->grp), free(w->rank);
    free(w->ed), free(w->prov);
    free(w->voff), free(w->vh), free(w->pos), free(w->next), free(w->hcyc), free(w->hes),
        free(w->hoff);
    free(w->comp), free(w->low), free(w->ext), free(w->host), free(w->iso), free(w->used);
    free(w->fof), free(w->aoff), free(w->adj), free(w->covo), free(w->covn);
    free(w->x1), free(w->x2), free(w->reached), free(w->span);
    member_ws_free(&w->mws);
    planar_ws_free(&w->pws);
}

int a3_planes(a3 *A, char *err, size_t errlen)
{
    size_t n = 0;
    uint32_t *planes = mem_malloc((A->npl + 1) * sizeof *planes);
    int *rc = mem_calloc(A->npl + 1, sizeof *rc);
    pwork *w = mem_calloc((size_t)A->threads, sizeof *w);
    A->pf = mem_calloc(A->npl + 1, sizeof *A->pf);
    int r = ARR_OK;
    if (!planes || !rc || !w || !A->pf) {
        r = ARR_ENOMEM;
        goto done;
    }
    for (size_t p = 0; p < A->npl; p++)
        if (A->pp_off[p + 1] > A->pp_off[p]) planes[n++] = (uint32_t)p;
    for (int t = 0; t < A->threads; t++) w[t].A = A;
    planesctx c = {A, planes, w, rc};
    a3_span span = {A, "planes", 0, 0.95}; /* merging the planes' points follows */
    par_for_ex(A->threads, n, plane_item, &c, a3_span_tick, &span);
    for (size_t i = 0; i < n && r == ARR_OK; i++) {
        if (rc[i] == -1) r = ARR_ENOMEM;
        if (rc[i] == -3) r = ARR_ECANCELED;
        if (rc[i] == -2) r = ARR_EINTERNAL;
    }
done:
    if (r != ARR_OK && err && errlen)
        snprintf(err, errlen, "%s",
                 r == ARR_ENOMEM      ? "out of memory"
                 : r == ARR_ECANCELED ? "cancelled"
                                      : "solids: a plane's arrangement is inconsistent (a bug)");
    for (int t = 0; w && t < A->threads; t++) pwork_free(&w[t]);
    free(w);
    free(planes);
    free(rc);
    return r;
}
