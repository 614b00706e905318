/* facecheck.c — is a face, on the grid, a polygon with holes? (core/facecheck.h)
 *
 * The face is looked at in 2D: along the largest axis of its exact normal when its vertices lie
 * in one plane (the projection is then one to one), else along face_newell_axis() (the
 * projection the pipeline triangulates).  Coordinates are taken relative to the face's lowest
 * corner, so that they are below 2^40 (FACE_CHECK_LIMIT) and twice them below 2^41: every
 * orientation below is an exact 128-bit integer.  In stages, each stopping at the first problem:
 *   pairs    every pair of edges whose boxes meet (all pairs up to SMALL edges, else from a
 *            box-kd-tree, each pair once, in the bucket holding the corner of their boxes'
 *            intersection): a proper crossing or a positive-length overlap is an error (two
 *            consecutive edges of a cycle: only an overlap, i.e. the cycle turning back); an end
 *            of one strictly inside the other is a vertex on an edge: an error in its own cycle
 *            (and under FACE_SOLID, or for a face not planar, in any), else a touch, kept.
 *   points   every entry and every touch, sorted by point: a point passed twice by one cycle is
 *            a pinch; where several cycles meet, their edges' directions sorted by angle about
 *            the point must nest (each cycle's two directions adjacent once the others' inner
 *            pairs are removed: a stack), or two of them cross there.
 *   nesting  each hole's point (a vertex of it that meets no other cycle, else a point inside
 *            one of its edges that does not) lies inside the outer cycle and inside no other
 *            hole: parities of the edges of the other cycles crossing a ray from it along +u,
 *            perturbed to pass just above the point (an edge counts when one end is above the
 *            point's height and the other not).  The ray's edges come from the tree's leaves
 *            along the ray (each counted once: a stamp per hole).  Cycles that do not cross and
 *            touch only at points are nested or apart as a whole, so one point decides.
 *   turn     (FACE_SOLID) each hole's signed area is of the other sign than the outer cycle's.
 */
#include "core/facecheck.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/num.h"
#include "core/mem.h"

#define SMALL 48 /* faces of at most this many edges: all pairs */
#define LEAF  16 /* bucket size aimed at */
#define NONE  UINT32_MAX

typedef struct trec { /* an entry, or a touch: a point inside an edge of another cycle */
    int64_t u, v;
    uint32_t cyc;
    uint32_t entry; /* the entry at the point, or NONE for a touch */
    uint32_t edge;  /* a touch: the edge whose inside holds the point */
} trec;

typedef struct fc {
    const face_cycles *f;
    face_work *w;
    int strict; /* a vertex inside another cycle's edge is an error */
    size_t n;   /* entries (= edges) */
    face_verdict *out;
    size_t ninc;
} fc;

void face_work_free(face_work *w)
{
    if (!w) return;
    free(w->P);
    free(w->cyc);
    free(w->start);
    free(w->touched);
    free(w->stamp);
    free(w->rec);
    free(w->inc);
    free(w->box);
    box_tree_free(&w->tree);
    memset(w, 0, sizeof *w);
}

int face_newell_axis(const int64_t *g, const uint32_t *v, size_t n)
{
    i128 N[3] = {0, 0, 0};
    const int64_t *o = g + 3 * (size_t)v[0];
    for (size_t i = 1; i + 1 < n; i++) {
        const int64_t *p = g + 3 * (size_t)v[i], *q = g + 3 * (size_t)v[i + 1];
        int64_t a[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]};
        int64_t b[3] = {q[0] - o[0], q[1] - o[1], q[2] - o[2]};
        N[0] += (i128)a[1] * b[2] - (i128)a[2] * b[1];
        N[1] += (i128)a[2] * b[0] - (i128)a[0] * b[2];
        N[2] += (i128)a[0] * b[1] - (i128)a[1] * b[0];
    }
    int k = 0;
    for (int a = 1; a < 3; a++)
        if ((N[a] < 0 ? -N[a] : N[a]) > (N[k] < 0 ? -N[k] : N[k])) k = a;
    return k;
}

/* ---- entries ------------------------------------------------------------------------------ */

static ipt pt(const fc *c, size_t e)
{
    return (ipt){c->w->P[2 * e], c->w->P[2 * e + 1]};
}

static size_t next_of(const fc *c, size_t e)
{
    uint32_t k = c->w->cyc[e];
    return e + 1 < c->w->start[k + 1] ? e + 1 : c->w->start[k];
}

static size_t prev_of(const fc *c, size_t e)
{
    uint32_t k = c->w->cyc[e];
    return e > c->w->start[k] ? e - 1 : c->w->start[k + 1] - 1;
}

static uint32_t vid(const fc *c, size_t e)
{
    uint32_t k = c->w->cyc[e];
    return c->f->cyc[k][e - c->w->start[k]];
}

static int fail(fc *c, int what, size_t e1, size_t e2)
{
    face_verdict *o = c->out;
    o->what = what;
    o->c1 = c->w->cyc[e1];
    o->i1 = e1 - c->w->start[o->c1];
    o->c2 = c->w->cyc[e2];
    o->i2 = e2 - c->w->start[o->c2];
    return 1;
}

static int same(ipt a, ipt b)
{
    return a.x == b.x && a.y == b.y;
}

/* Is p, on the line through a and b, strictly between them? */
static int strictly_inside(ipt p, ipt a, ipt b)
{
    if (same(p, a) || same(p, b)) return 0;
    return (p.x >= (a.x < b.x ? a.x : b.x)) && (p.x <= (a.x < b.x ? b.x : a.x)) &&
           (p.y >= (a.y < b.y ? a.y : b.y)) && (p.y <= (a.y < b.y ? b.y : a.y));
}

/* ---- pairs -------------------------------------------------------------------------------- */

/* Entry x lies strictly inside edge e.  1 (an error, in c->out), 0, or -1 out of memory. */
static int on_edge(fc *c, size_t x, size_t e)
{
    if (c->w->cyc[x] == c->w->cyc[e] || c->strict) return fail(c, FACE_ON_EDGE, x, e);
    if (mem_grow(&c->w->inc, &c->w->capinc, c->ninc + 1, sizeof(trec))) return -1;
    ipt p = pt(c, x);
    ((trec *)c->w->inc)[c->ninc++] = (trec){p.x, p.y, c->w->cyc[e], NONE, (uint32_t)e};
    return 0;
}

/* Edges e != f: 1 (what is wrong in c->out), 0, or -1 out of memory. */
static int pair_test(fc *c, size_t e, size_t f)
{
    size_t ne = next_of(c, e), nf = next_of(c, f);
    ipt a = pt(c, e), b = pt(c, ne), p = pt(c, f), q = pt(c, nf);
    if (ne == f || nf == e) { /* consecutive: they share a point; only turning back is wrong */
        ipt x = ne == f ? a : p, m = ne == f ? b : a, y = ne == f ? q : b;
        if (orient2(x, m, y) == 0 &&
            (i128)(x.x - m.x) * (y.x - m.x) + (i128)(x.y - m.y) * (y.y - m.y) > 0)
            return fail(c, FACE_OVERLAP, e, f);
        return 0;
    }
    i128 o1 = orient2(a, b, p), o2 = orient2(a, b, q);
    if (o1 == 0 && o2 == 0) { /* on one line: along the axis where ab is longer */
        int ax = llabs(b.x - a.x) >= llabs(b.y - a.y) ? 0 : 1;
        int64_t a0 = ax ? a.y : a.x, a1 = ax ? b.y : b.x, p0 = ax ? p.y : p.x, p1 = ax ? q.y : q.x;
        int64_t lo1 = a0 < a1 ? a0 : a1, hi1 = a0 ^ a1 ^ lo1, lo2 = p0 < p1 ? p0 : p1,
                hi2 = p0 ^ p1 ^ lo2;
        if ((hi1 < hi2 ? hi1 : hi2) > (lo1 > lo2 ? lo1 : lo2)) return fail(c, FACE_OVERLAP, e, f);
        return 0; /* apart, or meeting at an end of both (the points stage) */
    }
    i128 o3 = orient2(p, q, a), o4 = orient2(p, q, b);
    if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
        return fail(c, FACE_CROSS, e, f);
    int r;
    if (o1 == 0 && strictly_inside(p, a, b) && (r = on_edge(c, f, e))) return r;
    if (o2 == 0 && strictly_inside(q, a, b) && (r = on_edge(c, nf, e))) return r;
    if (o3 == 0 && strictly_inside(a, p, q) && (r = on_edge(c, e, f))) return r;
    if (o4 == 0 && strictly_inside(b, p, q) && (r = on_edge(c, ne, f))) return r;
    return 0;
}

static const int64_t *ebox(const fc *c, size_t e)
{
    return c->w->box + 4 * e;
}

static int boxes_meet(const int64_t *a, const int64_t *b)
{
    return !(a[2] < b[0] || b[2] < a[0] || a[3] < b[1] || b[3] < a[1]);
}

static int stage_pairs(fc *c)
{
    face_work *w = c->w;
    size_t n = c->n;
    if (mem_grow(&w->box, &w->capbox, 4 * n, sizeof *w->box)) return -1;
    for (size_t e = 0; e < n; e++) {
        ipt a = pt(c, e), b = pt(c, next_of(c, e));
        int64_t *bx = w->box + 4 * e;
        bx[0] = a.x < b.x ? a.x : b.x, bx[2] = a.x ^ b.x ^ bx[0];
        bx[1] = a.y < b.y ? a.y : b.y, bx[3] = a.y ^ b.y ^ bx[1];
    }
    if (n <= SMALL) {
        for (size_t e = 0; e < n; e++)
            for (size_t f = e + 1; f < n; f++) {
                if (!boxes_meet(ebox(c, e), ebox(c, f))) continue;
                int r = pair_test(c, e, f);
                if (r) return r;
            }
        return 0;
    }
    box_tree_free(&w->tree);
    if (box_tree_build(&w->tree, w->box, n, LEAF)) return -1;
    for (size_t l = 0; l < w->tree.nleaves; l++) {
        const uint32_t *it = w->tree.items + w->tree.leaf_off[l];
        size_t k = w->tree.leaf_off[l + 1] - w->tree.leaf_off[l];
        const double *rg = w->tree.region + 4 * l;
        for (size_t i = 0; i < k; i++)
            for (size_t j = i + 1; j < k; j++) {
                const int64_t *bi = ebox(c, it[i]), *bj = ebox(c, it[j]);
                if (!boxes_meet(bi, bj)) continue;
                double rx = (double)(bi[0] > bj[0] ? bi[0] : bj[0]);
                double ry = (double)(bi[1] > bj[1] ? bi[1] : bj[1]);
                if (!(rx > rg[0] && rx <= rg[2] && ry > rg[1] && ry <= rg[3])) continue;
                int r = pair_test(c, it[i], it[j]);
                if (r) return r;
            }
    }
    return 0;
}

/* ---- points ------------------------------------------------------------------------------- */

static int trec_cmp(const void *pa, const void *pb)
{
    const trec *a = pa, *b = pb;
    if (a->u != b->u) return a->u < b->u ? -1 : 1;
    if (a->v != b->v) return a->v < b->v ? -1 : 1;
    if (a->cyc != b->cyc) return a->cyc < b->cyc ? -1 : 1;
    if (a->entry != b->entry) return a->entry < b->entry ? -1 : 1;
    return (a->edge > b->edge) - (a->edge < b->edge);
}

/* The two directions of a cycle at the point of record r (to its neighbours, or along the edge
 * whose inside holds the point). */
static void dirs(const fc *c, const trec *r, ipt d[2])
{
    size_t a, b;
    if (r->entry != NONE)
        a = prev_of(c, r->entry), b = next_of(c, r->entry);
    else
        a = r->edge, b = next_of(c, r->edge);
    ipt pa = pt(c, a), pb = pt(c, b);
    d[0] = (ipt){pa.x - r->u, pa.y - r->v};
    d[1] = (ipt){pb.x - r->u, pb.y - r->v};
}

typedef struct ray {
    ipt d;
    uint32_t k; /* the record it belongs to */
} ray;

static int ray_cmp(const void *pa, const void *pb)
{
    const ray *a = pa, *b = pb;
    int r = dir_cmp(a->d.x, a->d.y, b->d.x, b->d.y); /* counter-clockwise from +u */
    return r ? r : (a->k > b->k) - (a->k < b->k);
}

/* Is direction x strictly inside the counter-clockwise turn from a to b? */
static int in_turn(ipt a, ipt b, ipt x)
{
    int ab = dir_cmp(a.x, a.y, b.x, b.y), ax = dir_cmp(a.x, a.y, x.x, x.y),
        xb = dir_cmp(x.x, x.y, b.x, b.y);
    if (ab < 0) return ax < 0 && xb < 0;
    return ax < 0 || xb < 0; /* the turn passes +u */
}

/* Do the cycles of records r and s cross at their point? */
static int cross_at(const fc *c, const trec *r, const trec *s)
{
    ipt a[2], b[2];
    dirs(c, r, a);
    dirs(c, s, b);
    return in_turn(a[0], a[1], b[0]) != in_turn(a[0], a[1], b[1]);
}

/* The entry of a record, for messages: its own, or the start of its edge. */
static size_t rec_entry(const trec *r)
{
    return r->entry != NONE ? r->entry : r->edge;
}

/* Records g[0..m) at one point, of m distinct cycles (m >= 2): 1 when two cross there. */
static int group_crosses(fc *c, trec *g, size_t m)
{
    if (m == 2) {
        if (!cross_at(c, &g[0], &g[1])) return 0;
        return fail(c, FACE_CROSS_AT, rec_entry(&g[0]), rec_entry(&g[1]));
    }
    ray *rs = malloc(2 * m * sizeof *rs);
    uint32_t *stack = malloc(2 * m * sizeof *stack);
    if (!rs || !stack) {
        free(rs), free(stack);
        return -1;
    }
    for (size_t i = 0; i < m; i++) {
        ipt d[2];
        dirs(c, &g[i], d);
        rs[2 * i] = (ray){d[0], (uint32_t)i};
        rs[2 * i + 1] = (ray){d[1], (uint32_t)i};
    }
    qsort(rs, 2 * m, sizeof *rs, ray_cmp);
    size_t sp = 0;
    for (size_t i = 0; i < 2 * m; i++) {
        if (sp && stack[sp - 1] == rs[i].k)
            sp--;
        else
            stack[sp++] = rs[i].k;
    }
    free(rs);
    free(stack);
    if (sp == 0) return 0;
    for (size_t i = 0; i < m; i++) /* which two: the first pair that crosses */
        for (size_t j = i + 1; j < m; j++)
            if (cross_at(c, &g[i], &g[j]))
                return fail(c, FACE_CROSS_AT, rec_entry(&g[i]), rec_entry(&g[j]));
    return fail(c, FACE_CROSS_AT, rec_entry(&g[0]), rec_entry(&g[1]));
}

static int stage_points(fc *c, int planar)
{
    face_work *w = c->w;
    size_t n = c->n, m = n + c->ninc;
    if (mem_grow(&w->rec, &w->caprec, m, sizeof(trec)) ||
        mem_grow(&w->touched, &w->captouched, n, 1))
        return -1;
    trec *R = w->rec;
    memset(w->touched, 0, n);
    for (size_t e = 0; e < n; e++) {
        ipt p = pt(c, e);
        R[e] = (trec){p.x, p.y, w->cyc[e], (uint32_t)e, NONE};
    }
    /* a touch is found from both edges at its point: once each */
    trec *I = w->inc;
    size_t ni = 0;
    if (c->ninc) qsort(I, c->ninc, sizeof *I, trec_cmp);
    for (size_t i = 0; i < c->ninc; i++)
        if (i == 0 || trec_cmp(&I[i], &I[i - 1])) R[n + ni++] = I[i];
    m = n + ni;
    qsort(R, m, sizeof *R, trec_cmp);
    for (size_t i = 0, j; i < m; i = j) {
        size_t cycles = 1;
        for (j = i + 1; j < m && R[j].u == R[i].u && R[j].v == R[i].v; j++) {
            if (R[j].cyc != R[j - 1].cyc) {
                cycles++;
                continue;
            }
            /* one cycle twice at a point: passed twice, or (not planar) two vertices above one
             * another; a touch of its own edge was an error of the pairs already */
            size_t x = rec_entry(&R[j - 1]), y = rec_entry(&R[j]);
            if (R[j - 1].entry == NONE || R[j].entry == NONE) return fail(c, FACE_CROSS_AT, x, y);
            if (!planar && vid(c, x) != vid(c, y)) return fail(c, FACE_PROJ_POINT, x, y);
            return fail(c, FACE_PINCH, x, y);
        }
        if (cycles < 2) continue;
        if (!planar) /* cycles may meet only at a vertex they share */
            for (size_t k = i + 1; k < j; k++)
                if (R[k].entry != NONE && vid(c, R[k].entry) != vid(c, R[i].entry))
                    return fail(c, FACE_PROJ_POINT, R[i].entry, R[k].entry);
        int r = group_crosses(c, R + i, j - i);
        if (r) return r;
        for (size_t k = i; k < j; k++)
            if (R[k].entry != NONE) w->touched[R[k].entry] = 1;
    }
    return 0;
}

/* ---- nesting ------------------------------------------------------------------------------ */

/* Does edge f cross the ray from Q2 / 2 along +u (dir 1) or -u (dir -1), just above Q2's
 * height? (Q2: twice the point; the point is on no edge of f's cycle.) */
static int ray_crosses(const fc *c, size_t f, ipt Q2, int dir)
{
    ipt a = pt(c, f), b = pt(c, next_of(c, f));
    a.x *= 2, a.y *= 2, b.x *= 2, b.y *= 2;
    if ((a.y > Q2.y) == (b.y > Q2.y)) return 0;
    if (a.y > b.y) {
        ipt t = a;
        a = b, b = t;
    }
    i128 o = orient2(a, b, Q2); /* > 0: the upward edge passes right of the point */
    return dir > 0 ? o > 0 : o < 0;
}

/* The leaves of the tree whose regions meet the ray from (x, y) along +u (dir 1) or -u (dir
 * -1), y just above the point's height: a descent into the children the ray meets, each leaf
 * once (regions are (lo, t] below a threshold t and (t, hi] above). */
static int ray_leaves(face_work *w, double x, double y, int dir, size_t *nl)
{
    const box_tree *t = &w->tree;
    int32_t *st = (int32_t *)w->rec; /* scratch: free once the points stage is done */
    size_t n = 0, ns = 0;
    if (mem_grow(&w->rec, &w->caprec, 2 * (t->nnodes + t->nleaves) + 2, sizeof(int32_t))) return -1;
    st = (int32_t *)w->rec;
    uint32_t *out = (uint32_t *)(st + t->nnodes + 1);
    st[ns++] = 0;
    while (ns) {
        const box_node *nd = &t->nodes[st[--ns]];
        int go[2];
        if (nd->axis == 0) {
            go[0] = dir > 0 ? x <= nd->t : 1;
            go[1] = dir > 0 ? 1 : x > nd->t;
        } else {
            go[0] = y <= nd->t;
            go[1] = !go[0];
        }
        for (int k = 0; k < 2; k++) {
            if (!go[k]) continue;
            int32_t ch = nd->child[k];
            if (ch < 0) {
                uint32_t l = (uint32_t)~ch;
                if (!n || out[n - 1] != l) out[n++] = l; /* a one-leaf root names it twice */
            } else {
                st[ns++] = ch;
            }
        }
    }
    *nl = n;
    return 0;
}

/* The point of hole h to test (twice it): a vertex meeting no other cycle, else a point inside
 * its first edge before the first touch on that edge. */
static ipt hole_point(const fc *c, uint32_t h)
{
    face_work *w = c->w;
    for (size_t e = w->start[h]; e < w->start[h + 1]; e++)
        if (!w->touched[e]) {
            ipt p = pt(c, e);
            return (ipt){2 * p.x, 2 * p.y};
        }
    size_t e = w->start[h];
    ipt a = pt(c, e), b = pt(c, next_of(c, e));
    const trec *I = w->inc;
    for (size_t i = 0; i < c->ninc; i++) { /* touches inside this edge (only without strict) */
        if (I[i].edge != e) continue;
        ipt p = {I[i].u, I[i].v};
        if (llabs(p.x - a.x) + llabs(p.y - a.y) < llabs(b.x - a.x) + llabs(b.y - a.y)) b = p;
    }
    return (ipt){a.x + b.x, a.y + b.y};
}

static int stage_nesting(fc *c)
{
    face_work *w = c->w;
    size_t n = c->n, ncyc = c->f->ncyc;
    if (n > SMALL && mem_grow(&w->stamp, &w->capstamp, n, sizeof *w->stamp)) return -1;
    if (n > SMALL) memset(w->stamp, 0, n * sizeof *w->stamp);
    /* the face's box in u, to send each ray the shorter way out */
    int64_t umax = 0;
    for (size_t e = 0; e < n; e++) umax = w->P[2 * e] > umax ? w->P[2 * e] : umax;
    for (uint32_t h = 1; h < ncyc; h++) {
        ipt Q2 = hole_point(c, h);
        int in_outer = 0, in_holes = 0, dir = Q2.x > umax ? 1 : -1;
        if (n <= SMALL) {
            for (size_t f = 0; f < n; f++)
                if (w->cyc[f] != h && ray_crosses(c, f, Q2, dir)) {
                    if (w->cyc[f] == 0)
                        in_outer ^= 1;
                    else
                        in_holes ^= 1;
                }
        } else {
            /* the leaves along the ray, at a height just above the point's */
            size_t nl;
            if (ray_leaves(w, (double)Q2.x / 2, nextafter((double)Q2.y / 2, INFINITY), dir, &nl))
                return -1;
            const uint32_t *L = (const uint32_t *)w->rec + w->tree.nnodes + 1;
            for (size_t k = 0; k < nl; k++)
                for (uint32_t i = w->tree.leaf_off[L[k]]; i < w->tree.leaf_off[L[k] + 1]; i++) {
                    uint32_t f = w->tree.items[i];
                    if (w->stamp[f] == h || w->cyc[f] == h) continue;
                    w->stamp[f] = h;
                    if (!ray_crosses(c, f, Q2, dir)) continue;
                    if (w->cyc[f] == 0)
                        in_outer ^= 1;
                    else
                        in_holes ^= 1;
                }
        }
        size_t e = w->start[h];
        if (!in_outer) return fail(c, FACE_HOLE_OUT, e, e);
        if (!in_holes) continue;
        for (uint32_t k = 1; k < ncyc; k++) { /* which hole: each on its own */
            if (k == h) continue;
            int in = 0;
            for (size_t f = w->start[k]; f < w->start[k + 1]; f++) in ^= ray_crosses(c, f, Q2, dir);
            if (in) return fail(c, FACE_HOLE_IN, e, w->start[k]);
        }
        return fail(c, FACE_HOLE_IN, e, e); /* not reached: the parity says one holds it */
    }
    return 0;
}

/* ---- turn --------------------------------------------------------------------------------- */

static int area_sign(const fc *c, uint32_t k)
{
    i128 s = 0;
    for (size_t e = c->w->start[k]; e < c->w->start[k + 1]; e++) {
        ipt p = pt(c, e), q = pt(c, next_of(c, e));
        s += (i128)p.x * q.y - (i128)p.y * q.x;
    }
    return s > 0 ? 1 : s < 0 ? -1 : 0;
}

/* ---- the face ----------------------------------------------------------------------------- */

int face_check(const face_cycles *f, int flags, face_work *w, face_verdict *out)
{
    fc c = {.f = f, .w = w, .out = out};
    memset(out, 0, sizeof *out);
    size_t n = 0;
    for (size_t k = 0; k < f->ncyc; k++) n += f->len[k];
    c.n = n;
    if (f->ncyc == 0 || n == 0) return 0;
    /* the box, and the size the predicates can take */
    int64_t lo[3], hi[3];
    const int64_t *g = f->g;
    for (int a = 0; a < 3; a++) lo[a] = hi[a] = g[3 * (size_t)f->cyc[0][0] + a];
    for (size_t k = 0; k < f->ncyc; k++)
        for (size_t i = 0; i < f->len[k]; i++)
            for (int a = 0; a < 3; a++) {
                int64_t x = g[3 * (size_t)f->cyc[k][i] + a];
                lo[a] = x < lo[a] ? x : lo[a];
                hi[a] = x > hi[a] ? x : hi[a];
            }
    for (int a = 0; a < 3; a++)
        if (hi[a] - lo[a] >= FACE_CHECK_LIMIT || hi[a] < lo[a]) {
            out->what = FACE_UNCHECKED;
            return 0;
        }
    /* planar?  (the normal of the first three points not on one line) */
    const int64_t *p0 = g + 3 * (size_t)f->cyc[0][0], *p1 = NULL;
    i128 N[3] = {0, 0, 0};
    int have_n = 0;
    for (size_t k = 0; k < f->ncyc && !have_n; k++)
        for (size_t i = 0; i < f->len[k] && !have_n; i++) {
            const int64_t *q = g + 3 * (size_t)f->cyc[k][i];
            if (!p1) {
                if (q[0] != p0[0] || q[1] != p0[1] || q[2] != p0[2]) p1 = q;
                continue;
            }
            int64_t u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
            int64_t v[3] = {q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]};
            N[0] = (i128)u[1] * v[2] - (i128)u[2] * v[1];
            N[1] = (i128)u[2] * v[0] - (i128)u[0] * v[2];
            N[2] = (i128)u[0] * v[1] - (i128)u[1] * v[0];
            have_n = N[0] || N[1] || N[2];
        }
    if (!have_n) {
        out->what = FACE_FLAT;
        return 0;
    }
    int planar = 1;
    for (size_t k = 0; k < f->ncyc && planar; k++)
        for (size_t i = 0; i < f->len[k] && planar; i++) {
            const int64_t *q = g + 3 * (size_t)f->cyc[k][i];
            planar = N[0] * (q[0] - p0[0]) + N[1] * (q[1] - p0[1]) + N[2] * (q[2] - p0[2]) == 0;
        }
    int k = 0;
    if (planar) {
        for (int a = 1; a < 3; a++)
            if ((N[a] < 0 ? -N[a] : N[a]) > (N[k] < 0 ? -N[k] : N[k])) k = a;
    } else {
        k = face_newell_axis(g, f->cyc[0], f->len[0]);
    }
    out->planar = planar;
    out->axis = k;
    /* a quad that is not planar becomes two triangles along a diagonal, each keeping the
     * quad's order: two triangles in different planes meeting along that diagonal */
    if (!planar && f->ncyc == 1 && f->len[0] == 4) return 0;
    c.strict = (flags & FACE_SOLID) || !planar;
    /* the entries in 2D */
    int ku = (k + 1) % 3, kv = (k + 2) % 3;
    if (mem_grow(&w->P, &w->capP, 2 * n, sizeof *w->P) ||
        mem_grow(&w->cyc, &w->capcyc, n, sizeof *w->cyc) ||
        mem_grow(&w->start, &w->capstart, f->ncyc + 1, sizeof *w->start))
        return -1;
    size_t e = 0;
    for (size_t q = 0; q < f->ncyc; q++) {
        w->start[q] = (uint32_t)e;
        for (size_t i = 0; i < f->len[q]; i++, e++) {
            const int64_t *x = g + 3 * (size_t)f->cyc[q][i];
            w->P[2 * e] = x[ku] - lo[ku];
            w->P[2 * e + 1] = x[kv] - lo[kv];
            w->cyc[e] = (uint32_t)q;
        }
    }
    w->start[f->ncyc] = (uint32_t)n;
    if (!planar) /* an edge along the axis: no edge in the projection */
        for (e = 0; e < n; e++)
            if (same(pt(&c, e), pt(&c, next_of(&c, e)))) {
                fail(&c, FACE_PROJ_POINT, e, next_of(&c, e));
                return 0;
            }
    int r = stage_pairs(&c);
    if (r == 0) r = stage_points(&c, planar);
    if (r == 0) r = stage_nesting(&c);
    if (r < 0) return -1;
    if (r > 0) return 0;
    if (flags & FACE_SOLID) {
        int s0 = area_sign(&c, 0);
        for (uint32_t h = 1; h < f->ncyc; h++)
            if (area_sign(&c, h) == s0) {
                fail(&c, FACE_HOLE_TURN, w->start[h], w->start[h]);
                return 0;
            }
    }
    return 0;
}
