/* arr3_pairs.c — the candidate pairs of the 3D arrangement (stage 2 of arr3.h): the pieces of
 * different solids whose closed boxes meet, and the pieces of one solid whose boxes meet and
 * that may cross (a surface passing through itself: the charts below, and self_apart).
 *
 * A bounding-volume hierarchy per solid, and one over the solids.  A solid's pieces are sorted
 * by their chart class and the Morton code of their boxes' centres (a 32-bit key: 29 bits of
 * code over the solid's own box), and the sorted run is split at the highest bit in which its
 * first and last keys differ (in the middle when they are equal), down to leaves of at most
 * BVH_LEAF pieces; every node keeps the box of what lies below it.  So a tree always splits,
 * whatever the shape of the input (a shell inside its mesh, long thin faces, many faces in one
 * plane: a kd-tree that stops where a split does not separate its boxes compares every pair of a
 * large bucket there), and it has depth at most 32 + log2(n).  The solids' root boxes get a tree of
 * their own; walking it against itself gives the pairs of solids whose boxes meet, and each such
 * pair's trees are walked against each other (the larger node's children first), so the work grows
 * with the node pairs whose boxes meet, not with the pieces: the parts of two surfaces far from
 * each other are left at the first nodes that separate them.  Each solid's tree is walked against
 * itself too, skipping the node pairs inside one flat chart; along the charts' boundaries most
 * pairs it meets share a vertex whose star is certified (stars, below), settled by vertex ids.
 * In a face soup each face is a solid (and nothing is walked against itself).
 *
 * Why not the box index of core/box.h (the bucket index arr2, facecheck and the cells' probes
 * share, generic over dimension): that index answers "which boxes may hold this point" and
 * "which pairs share a bucket", duplicating every box that straddles a split into both sides
 * and stopping where no split separates the boxes.  The pair walk here needs a hierarchy of
 * nested boxes walked tree against tree: two surfaces far apart are dismissed at the first
 * node pair whose boxes miss, whole subtrees at once; the Morton order always splits (many
 * pieces in one plane, a shell inside its mesh: there a bucket index keeps one large bucket
 * and compares all its pairs); the chart classes in the sort key let the self-walk skip node
 * pairs inside one flat chart; and the trees of all solids are built at once, one per solid.
 * A bucket index would compare each pair in the bucket holding its corner instead, with the
 * straddling copies and without the per-solid and per-chart pruning: not without loss on the
 * 3D bench rows, so this BVH stays.
 *
 * Threads: the trees are built on par_for() (a solid each, in chunks), and the walks of the
 * solid pairs are cut into tasks (node pairs, breadth first, until there are enough of them)
 * that run on par_for(), each writing its own list; the lists are concatenated and sorted, so
 * the pairs do not depend on the number of threads.
 */
#include "core/arr3_int.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <stdatomic.h>
#include <stdio.h>

#include "core/mem.h"
#include "core/par.h"
#include "core/sort.h"
#include "core/util.h"

#define BVH_LEAF 8
#define LEAFBIT  0x80000000u

/* A node: the box of everything below it; an inner node's children a and b, or a leaf's items
 * item[a .. a + (b & ~LEAFBIT)). */
typedef struct bnode {
    int32_t box[6];
    uint32_t a, b;
} bnode;

typedef struct bvh {
    bnode *node;
    uint32_t *item; /* piece ids (group trees) or group ids (the top tree), in leaf order */
    size_t nnode;
} bvh;

/* Branch-free: most boxes a walk compares do not meet, in no pattern a branch predictor
 * learns, and six branches mispredicted cost more than six comparisons. */
static inline int box_meet(const int32_t *a, const int32_t *b)
{
    return (a[0] <= b[3]) & (b[0] <= a[3]) & (a[1] <= b[4]) & (b[1] <= a[4]) & (a[2] <= b[5]) &
           (b[2] <= a[5]);
}

static void box_join(int32_t *r, const int32_t *a, const int32_t *b)
{
    for (int k = 0; k < 3; k++) {
        r[k] = a[k] < b[k] ? a[k] : b[k];
        r[3 + k] = a[3 + k] > b[3 + k] ? a[3 + k] : b[3 + k];
    }
}

/* The 10 bits of x spread to every third bit (bit i to bit 3 i): a table, made once. */
static uint32_t spread_tab[1024];
static pthread_once_t spread_once = PTHREAD_ONCE_INIT;

static void spread_init(void)
{
    for (uint32_t x = 0; x < 1024; x++) {
        uint32_t r = 0;
        for (int i = 0; i < 10; i++) r |= (x >> i & 1u) << (3 * i);
        spread_tab[x] = r;
    }
}

/* ---- building ---------------------------------------------------------------------------- */

typedef struct builder {
    const int32_t (*box)[6]; /* the items' boxes in sorted order (srt's) */
    uint64_t *srt;           /* code << 32 | index, sorted by code */
    uint32_t base;           /* item index i is id base + i; the tree's items and nodes are
                                numbered from base and 2 base (ids over all the trees) */
    uint32_t *ch;            /* NULL, or the items' charts in sorted order: a leaf holds one */
    uint32_t *nchart;        /* with ch: by node id, the flat chart of all below, or NONE */
    bvh *t;
} builder;

/* Of a run srt[lo .. hi) that would make a leaf, the items of the first one's chart moved to
 * the front (in order, their boxes and charts with them): how many they are. */
static size_t chart_front(builder *B, size_t lo, size_t hi)
{
    uint32_t c = B->ch[lo];
    size_t same = lo + 1;
    while (same < hi && B->ch[same] == c) same++;
    if (same == hi) return hi - lo; /* the usual run: one chart, nothing moves */
    uint64_t keep[BVH_LEAF];
    int32_t kbox[BVH_LEAF][6];
    uint32_t kch[BVH_LEAF];
    int32_t(*box)[6] = (int32_t(*)[6])B->box;
    size_t nf = lo, nk = 0;
    for (size_t i = lo; i < hi; i++) {
        if (B->ch[i] == c) {
            B->srt[nf] = B->srt[i], B->ch[nf] = B->ch[i];
            memmove(box[nf], box[i], sizeof *box);
            nf++;
        } else {
            keep[nk] = B->srt[i], kch[nk] = B->ch[i];
            memcpy(kbox[nk], box[i], sizeof *kbox);
            nk++;
        }
    }
    memcpy(B->srt + nf, keep, nk * sizeof *keep);
    memcpy(B->ch + nf, kch, nk * sizeof *kch);
    memcpy(box + nf, kbox, nk * sizeof *kbox);
    return nf - lo;
}

/* The node over srt[lo .. hi) at t->node[at]; returns 0.  Nodes are allocated in preorder from
 * t->nnode (room for 2 (hi - lo) was made).  With charts, a run that would make a leaf of
 * pieces of several charts is cut by chart instead, so that a pair of leaves either lies in
 * one chart or needs its pairs looked at.  Everything is read in sorted order (box, ch). */
static void build_node(builder *B, uint32_t at, size_t lo, size_t hi)
{
    bnode *n = &B->t->node[at];
    size_t first = hi - lo, nb = 2 * (size_t)B->base;
    if (hi - lo <= BVH_LEAF && B->ch) first = chart_front(B, lo, hi);
    if (hi - lo <= BVH_LEAF && first == hi - lo) {
        n->a = (uint32_t)(B->base + lo);
        n->b = (uint32_t)(hi - lo) | LEAFBIT;
        memcpy(n->box, B->box[lo], sizeof n->box);
        for (size_t i = lo; i < hi; i++) {
            B->t->item[i] = B->base + (uint32_t)B->srt[i];
            if (i > lo) box_join(n->box, n->box, B->box[i]);
        }
        if (B->ch) B->nchart[nb + at] = B->ch[lo];
        return;
    }
    size_t mid = lo + first; /* a leaf's run cut by chart */
    if (first == hi - lo) {
        uint64_t c0 = B->srt[lo] >> 32, c1 = B->srt[hi - 1] >> 32;
        if (c0 == c1) {
            mid = lo + (hi - lo) / 2;
        } else {
            int bit = 63 - __builtin_clzll(c0 ^ c1);
            size_t l = lo, r = hi - 1; /* the first code with the bit set lies in (l, r] */
            while (r - l > 1) {
                size_t m = l + (r - l) / 2;
                if (B->srt[m] >> 32 >> bit & 1)
                    r = m;
                else
                    l = m;
            }
            mid = r;
        }
    }
    uint32_t ca = (uint32_t)B->t->nnode++, cb = (uint32_t)B->t->nnode++;
    build_node(B, ca, lo, mid);
    build_node(B, cb, mid, hi);
    n = &B->t->node[at];
    n->a = (uint32_t)(nb + ca), n->b = (uint32_t)(nb + cb);
    box_join(n->box, B->t->node[ca].box, B->t->node[cb].box);
    if (B->ch) { /* children are built first: the nodes' charts bottom up */
        uint32_t x = B->nchart[nb + ca], y = B->nchart[nb + cb];
        B->nchart[nb + at] = x == y ? x : NONE;
    }
}

/* The tree over the ids base .. base + n (n >= 1) into t, whose arrays have room for 2n nodes
 * and n items (its leaves each of one chart when chart, by id, is not NULL; the nodes' flat
 * charts then into nchart, by node id).  ibox gets the items' boxes in item order; srt and bx
 * are scratch for n entries (bx: the boxes, read once through boxof and then in order).
 * Returns -1 out of memory. */
static int build_tree(const int32_t *(*boxof)(const void *, uint32_t), const void *ctx,
                      uint32_t base, size_t n, const uint32_t *chart, const uint8_t *first,
                      uint64_t *srt, int32_t (*bx)[6], int32_t (*ibox)[6], uint32_t *nchart, bvh *t)
{
    int64_t lo[3] = {INT64_MAX, INT64_MAX, INT64_MAX}, hi[3] = {INT64_MIN, INT64_MIN, INT64_MIN};
    for (size_t i = 0; i < n; i++) {
        const int32_t *b = boxof(ctx, base + (uint32_t)i);
        memcpy(bx[i], b, sizeof bx[i]);
        for (int k = 0; k < 3; k++) {
            int64_t c = (int64_t)b[k] + b[3 + k];
            if (c < lo[k]) lo[k] = c;
            if (c > hi[k]) hi[k] = c;
        }
    }
    int sh[3];
    for (int k = 0; k < 3; k++) { /* the centres' spread down to 10 bits (a 30-bit code, its
                                   * last bit dropped; equal codes split in the middle) */
        uint64_t ext = (uint64_t)(hi[k] - lo[k]);
        sh[k] = 0;
        while ((ext >> sh[k]) >= ((uint64_t)1 << 10)) sh[k]++;
    }
    pthread_once(&spread_once, spread_init);
    for (size_t i = 0; i < n; i++) {
        const int32_t *b = bx[i];
        uint64_t code = 0;
        for (int k = 0; k < 3; k++)
            code |= (uint64_t)spread_tab[(uint64_t)((int64_t)b[k] + b[3 + k] - lo[k]) >> sh[k]]
                    << (2 - k);
        code >>= 1; /* 29 bits, and the class above them: keys of 32 bits */
        if (first) code |= (uint64_t)first[base + i] << 29;
        srt[i] = code << 32 | (uint32_t)i;
    }
    if (sort_u64_hi32(srt, n)) return -1; /* records of 8 bytes: half the radix passes' traffic */
    /* the boxes (into ibox) and the charts (into bx, free then) gathered in sorted order in
     * tight loops, whose independent loads the processor overlaps, not one by one down the
     * recursion */
    for (size_t i = 0; i < n; i++) memcpy(ibox[i], bx[(uint32_t)srt[i]], sizeof *ibox);
    uint32_t *ch = chart ? (uint32_t *)bx : NULL;
    for (size_t i = 0; ch && i < n; i++) ch[i] = chart[base + (uint32_t)srt[i]];
    builder B = {(const int32_t(*)[6])ibox, srt, base, ch, nchart, t};
    t->nnode = 1;
    build_node(&B, 0, 0, n);
    return 0;
}

/* ---- the groups (solids) and their trees ------------------------------------------------- */

typedef struct forest {
    const a3 *A;
    size_t ng;
    uint32_t *g_off;           /* ng + 1: group g holds pieces g_off[g] .. g_off[g + 1) */
    const uint32_t *chart;     /* by piece: its flat chart, or NONE (solids only; else NULL) */
    const uint8_t *pclass;     /* by piece: its chart's class, 7 when not flat (solids only) */
    uint32_t *nchart;          /* by node: the flat chart of every piece below it, or NONE */
    int32_t (*ibox)[6];        /* by item: its piece's box */
    uint32_t *isol;            /* by item: its piece's solid */
    uint32_t (*itri)[3];       /* by item: a triangle's vertices, or NONE (solids only) */
    const atomic_uchar *vcert; /* by vertex: 1 when its star is certified (star_cert) */
    uint32_t *root;            /* ng: its tree's root in node[] */
    bnode *node;               /* every group's nodes: group g's from 2 g_off[g] */
    uint32_t *item;            /* every group's items: group g's at g_off[g] .. */
    uint64_t *srt;
    int32_t (*bx)[6]; /* build_tree's scratch, by piece */
    size_t chunk;     /* groups a task */
    int fail;
} forest;

/* The entries of the pieces s0 .. s0 + n (n >= 1) of one solid: *e0 .. *e1.  1 when every
 * piece is a triangle (exactly 3 entries a piece, as each has 3 or more): piece s0 + i then has
 * the entries *e0 + 3 i .. *e0 + 3 i + 3. */
static int solid_entries(const a3 *A, uint32_t s0, uint32_t n, uint32_t *e0, uint32_t *e1)
{
    const piece *L = &A->pc[s0 + n - 1];
    *e0 = A->pc_off[A->pc[s0].c0], *e1 = A->pc_off[L->c0 + L->nc];
    return (size_t)*e1 - *e0 == 3 * (size_t)n;
}

static const int32_t *piece_box(const void *ctx, uint32_t id)
{
    const a3 *A = ctx;
    return A->pc[id].box;
}

static const int32_t *group_box(const void *ctx, uint32_t id)
{
    const forest *F = ctx;
    return F->node[F->root[id]].box;
}

static void build_groups(void *ctx, size_t item, int worker)
{
    (void)worker;
    forest *F = ctx;
    size_t g1 = (item + 1) * F->chunk < F->ng ? (item + 1) * F->chunk : F->ng;
    for (size_t g = item * F->chunk; g < g1 && !F->fail; g++) {
        if (a3_cancelled(F->A)) {
            F->fail = 3; /* the same value, whichever worker writes it */
            return;
        }
        uint32_t o = F->g_off[g], n = F->g_off[g + 1] - o;
        bvh t = {F->node + 2 * (size_t)o, F->item + o, 0}; /* the pieces o .. o + n */
        if (build_tree(piece_box, F->A, o, n, F->chart, F->pclass, F->srt + o, F->bx + o,
                       F->ibox + o, F->nchart, &t)) {
            F->fail = 1;
            return;
        }
        F->root[g] = 2 * o; /* node ids are global: from the group's start */
        if (F->A->soup)     /* the items' solids: a face soup's differ within a group */
            for (uint32_t k = o; k < o + n; k++) F->isol[k] = F->A->pc[F->item[k]].solid;
        else
            for (uint32_t k = o, sol = F->A->pc[o].solid; k < o + n; k++) F->isol[k] = sol;
        if (F->itri) { /* the items' vertices, when triangles, in item order */
            const a3 *A = F->A;
            uint32_t e0, e1;
            if (solid_entries(A, o, n, &e0, &e1)) /* all triangles: piece o + i at e0 + 3 i */
                for (uint32_t k = o; k < o + n; k++)
                    memcpy(F->itri[k], A->pcv + e0 + 3 * (size_t)(F->item[k] - o), sizeof *F->itri);
            else
                for (uint32_t k = o; k < o + n; k++) {
                    const uint32_t *t = a3_piece_tri(A, &A->pc[F->item[k]]);
                    if (t)
                        memcpy(F->itri[k], t, sizeof *F->itri);
                    else
                        F->itri[k][0] = F->itri[k][1] = F->itri[k][2] = NONE;
                }
        }
    }
}

/* ---- walking ----------------------------------------------------------------------------- */

typedef struct out64 {
    uint64_t *v;
    size_t n, cap;
    A3_PAD;
} out64;

static int push64(out64 *o, uint64_t x)
{
    return A3_PUSH(o->v, o->n, o->cap, x);
}

static int is_leaf(const bnode *n)
{
    return (n->b & LEAFBIT) != 0;
}

static int64_t extent(const bnode *n)
{
    return (int64_t)n->box[3] - n->box[0] + n->box[4] - n->box[1] + n->box[5] - n->box[2];
}

/* ---- pairs of one solid ----------------------------------------------------------------- */

int a3_piece_vertex(const a3 *A, const piece *P, uint32_t v)
{
    for (uint32_t x = A->pc_off[P->c0]; x < A->pc_off[P->c0 + 1]; x++)
        if (A->pcv[x] == v) return 1;
    return 0;
}

int a3_piece_edge(const a3 *A, const piece *P, uint32_t a, uint32_t b)
{
    uint32_t o = A->pc_off[P->c0], n = A->pc_off[P->c0 + 1] - o;
    for (uint32_t t = 0; t < n; t++) {
        uint32_t u = A->pcv[o + t], w = A->pcv[o + (t + 1 < n ? t + 1 : 0)];
        if ((u == a && w == b) || (u == b && w == a)) return 1;
    }
    return 0;
}

/* Does Q lie on one side of P's anchor plane but for vertices and edges of P?  Then Q meets
 * that plane, and so P, only in P's own vertices and edges: the two meet as the neighbouring
 * faces of a surface do (Q is planar: on one closed side of the plane, it meets it only in its
 * boundary, the vertices on it and the edges between two of them).  1: so it does; -1: Q lies
 * in P's plane; 0: neither. */
static int beside(const a3 *A, const piece *P, const piece *Q)
{
    const int64_t *a = A->g + 3 * (size_t)P->av[0], *b = A->g + 3 * (size_t)P->av[1],
                  *c = A->g + 3 * (size_t)P->av[2];
    /* the anchor normal fits 64 bits (grid coordinates below 2^30: grid_normal) */
    int64_t u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]},
            v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    int64_t n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                    u[0] * v[1] - u[1] * v[0]};
    uint32_t o = A->pc_off[Q->c0], m = A->pc_off[Q->c0 + 1] - o;
    int side = 0, other = 0; /* other: Q touches the plane elsewhere than in P's vertices, edges */
    uint8_t on[2] = {0, 0};  /* the first vertex on the plane, the one before */
    for (uint32_t t = 0; t < m; t++) {
        uint32_t w = A->pcv[o + t];
        const int64_t *x = A->g + 3 * (size_t)w;
        i128 d =
            (i128)n[0] * (x[0] - a[0]) + (i128)n[1] * (x[1] - a[1]) + (i128)n[2] * (x[2] - a[2]);
        int sg = (d > 0) - (d < 0);
        if (sg) {
            if (side && sg != side) return 0;
            side = sg;
            on[1] = 0;
            continue;
        }
        if (!a3_piece_vertex(A, P, w) || (on[1] && !a3_piece_edge(A, P, A->pcv[o + t - 1], w)))
            other = 1;
        if (t == 0) on[0] = 1;
        on[1] = 1;
    }
    if (!side) return -1;
    if (on[0] && on[1] && !a3_piece_edge(A, P, A->pcv[o + m - 1], A->pcv[o])) other = 1;
    return !other;
}

/* A triangle's corner at u: its two other vertices a, b in its turning order. */
static int corner(const a3 *A, const piece *P, uint32_t u, uint32_t *a, uint32_t *b)
{
    const uint32_t *v = A->pcv + A->pc_off[P->c0];
    for (int t = 0; t < 3; t++)
        if (v[t] == u) {
            *a = v[(t + 1) % 3], *b = v[(t + 2) % 3];
            return 1;
        }
    return 0;
}

/* Do pieces p and q of one solid certainly meet only in vertices and edges they share (as
 * every two neighbouring faces of a surface do)?  Decided here for almost every pair of a clean
 * surface, by the sides of one piece's vertices about the other's plane; a pair left undecided
 * (0) goes to the cuts, which decide it exactly. */
static int self_apart(const a3 *A, uint32_t p, uint32_t q)
{
    const piece *P = &A->pc[p], *Q = &A->pc[q];
    if (P->nc != 1 || Q->nc != 1) return 0;
    const uint32_t *pv = a3_piece_tri(A, P), *qv = a3_piece_tri(A, Q);
    if (pv && qv) { /* two triangles (most pairs): by their shared vertices */
        uint32_t shared = 0, ins = 0, inq = 0; /* bit t: P's vertex t (Q's) is shared */
        for (int t = 0; t < 3; t++)
            for (int r = 0; r < 3; r++)
                if (pv[t] == qv[r]) shared++, ins |= 1u << t, inq |= 1u << r;
        const int64_t *g = A->g;
        if (shared == 2) { /* an edge: apart unless in one plane */
            int x = ins == 6 ? 0 : ins == 5 ? 1 : 2, y = inq == 6 ? 0 : inq == 5 ? 1 : 2;
            if (orient3_grid(g + 3 * (size_t)pv[(x + 1) % 3], g + 3 * (size_t)pv[(x + 2) % 3],
                             g + 3 * (size_t)pv[x], g + 3 * (size_t)qv[y]))
                return 1;
            return a3_flat_apart(A, p, q) == 1;
        }
        if (shared == 1) {
            /* only vertex u: each triangle meets the other's plane in u alone (then apart), or
             * both meet the line L of the two planes in a segment from u.  With nP = (a - u) x
             * (b - u), nQ likewise and L directed along nP x nQ, P's segment runs forward when
             * a lies above Q's plane and b below (a - u and b - u turn about nP on either side
             * of L), backward when the other way; Q's the other way round.  Segments running
             * opposite ways meet only in u. */
            uint32_t u = NONE;
            for (int t = 0; t < 3; t++)
                if (ins >> t & 1) u = pv[t];
            uint32_t a, b, c, d;
            corner(A, P, u, &a, &b);
            corner(A, Q, u, &c, &d);
            const int64_t *pu = g + 3 * (size_t)u, *pa = g + 3 * (size_t)a, *pb = g + 3 * (size_t)b,
                          *pc = g + 3 * (size_t)c, *pd = g + 3 * (size_t)d;
            int sc = orient3_grid(pu, pa, pb, pc), sd = orient3_grid(pu, pa, pb, pd);
            if (sc && sc == sd) return 1; /* Q beside P's plane but for u */
            int sa = orient3_grid(pu, pc, pd, pa), sb = orient3_grid(pu, pc, pd, pb);
            if (sa && sa == sb) return 1;
            if (!sa && !sb && !sc && !sd) return a3_flat_apart(A, p, q) == 1;
            int dp = sa > 0 && sb < 0 ? 1 : sa < 0 && sb > 0 ? -1 : 0;
            int dq = sc > 0 && sd < 0 ? -1 : sc < 0 && sd > 0 ? 1 : 0;
            return dp && dq && dp != dq; /* their segments on the planes' line run apart */
        }
        if (shared == 3) return 0;
    }
    int r = beside(A, P, Q);
    if (r < 0) return a3_flat_apart(A, p, q) == 1;
    return r || beside(A, Q, P) == 1;
}

/* Coordinates of vertex v projected along axis k, times two (so that a midpoint is exact). */
static void proj2x(const a3 *A, uint32_t v, int k, int64_t *u)
{
    const int64_t *p = A->g + 3 * (size_t)v;
    u[0] = 2 * p[(k + 1) % 3];
    u[1] = 2 * p[(k + 2) % 3];
}

static int orient2x(const int64_t *a, const int64_t *b, const int64_t *c)
{
    i128 x = (i128)(b[0] - a[0]) * (c[1] - a[1]) - (i128)(b[1] - a[1]) * (c[0] - a[0]);
    return (x > 0) - (x < 0);
}

/* Do the closed edges ab and cd (vertex ids, projected along k) meet anywhere but in an end
 * they share?  0 no; EDGES_CROSS where their insides cross; EDGES_ALONG where they overlap on
 * one line (*same: running the same way); EDGES_TOUCH where an end of one lies on the other. */
enum { EDGES_APART = 0, EDGES_CROSS, EDGES_ALONG, EDGES_TOUCH };
static int edges_meet(const a3 *A, int k, uint32_t a, uint32_t b, uint32_t c, uint32_t d, int *same)
{
    int64_t pa[2], pb[2], pc[2], pd[2];
    proj2x(A, a, k, pa), proj2x(A, b, k, pb), proj2x(A, c, k, pc), proj2x(A, d, k, pd);
    *same = (i128)(pb[0] - pa[0]) * (pd[0] - pc[0]) + (i128)(pb[1] - pa[1]) * (pd[1] - pc[1]) > 0;
    if (a == c || a == d || b == c || b == d) { /* one shared end: beyond it only along it */
        const int64_t *o = a == c || a == d ? pa : pb, *x = a == c || a == d ? pb : pa,
                      *y = c == a || c == b ? pd : pc;
        if (orient2x(o, x, y)) return EDGES_APART;
        return (i128)(x[0] - o[0]) * (y[0] - o[0]) + (i128)(x[1] - o[1]) * (y[1] - o[1]) > 0
                   ? EDGES_ALONG
                   : EDGES_APART;
    }
    int o1 = orient2x(pa, pb, pc), o2 = orient2x(pa, pb, pd);
    int o3 = orient2x(pc, pd, pa), o4 = orient2x(pc, pd, pb);
    if (o1 * o2 > 0 || o3 * o4 > 0) return EDGES_APART;
    if (o1 * o2 < 0 && o3 * o4 < 0) return EDGES_CROSS;
    if (o1 || o2 || o3 || o4) return EDGES_TOUCH;
    for (int t = 0; t < 2; t++) { /* on one line: do the spans overlap? */
        int64_t l0 = pa[t] < pb[t] ? pa[t] : pb[t], h0 = pa[t] < pb[t] ? pb[t] : pa[t];
        int64_t l1 = pc[t] < pd[t] ? pc[t] : pd[t], h1 = pc[t] < pd[t] ? pd[t] : pc[t];
        if (h0 < l1 || h1 < l0) return EDGES_APART;
    }
    /* on one line, touching at a point or overlapping */
    for (int t = 0; t < 2; t++) {
        int64_t l0 = pa[t] < pb[t] ? pa[t] : pb[t], h0 = pa[t] < pb[t] ? pb[t] : pa[t];
        int64_t l1 = pc[t] < pd[t] ? pc[t] : pd[t], h1 = pc[t] < pd[t] ? pd[t] : pc[t];
        if (h0 == l1 || h1 == l0) return EDGES_TOUCH;
    }
    return EDGES_ALONG;
}

/* Is the midpoint of vertices a, b strictly inside the outer cycle of X (projected along k)?
 * The caller knows it is on no edge of X: -1 if it is found on the line of one anyway. */
static int mid_inside(const a3 *A, int k, uint32_t a, uint32_t b, const piece *X)
{
    int64_t pa[2], pb[2], m[2];
    proj2x(A, a, k, pa), proj2x(A, b, k, pb);
    m[0] = (pa[0] + pb[0]) / 2, m[1] = (pa[1] + pb[1]) / 2;
    uint32_t o = A->pc_off[X->c0], n = A->pc_off[X->c0 + 1] - o;
    int in = 0;
    for (uint32_t t = 0; t < n; t++) {
        int64_t p[2], q[2];
        proj2x(A, A->pcv[o + t], k, p);
        proj2x(A, A->pcv[o + (t + 1 < n ? t + 1 : 0)], k, q);
        if ((p[1] > m[1]) == (q[1] > m[1])) continue;
        int c = orient2x(p, q, m);
        if (!c) return -1;
        if (q[1] > p[1] ? c > 0 : c < 0) in ^= 1;
    }
    return in;
}

/* Coplanar pieces of one solid: is every edge of one that is no edge of the other, and runs
 * along none of its edges (bit t of along: edge t of P does), outside it? */
static int mids_outside(const a3 *A, int k, const piece *P, const piece *Q, uint64_t along)
{
    uint32_t o = A->pc_off[P->c0], n = A->pc_off[P->c0 + 1] - o;
    for (uint32_t t = 0; t < n; t++) {
        uint32_t a = A->pcv[o + t], b = A->pcv[o + (t + 1 < n ? t + 1 : 0)];
        if (t < 64 && (along >> t & 1)) continue;
        if (!a3_piece_edge(A, Q, a, b) && mid_inside(A, k, a, b, Q)) return 0;
    }
    return 1;
}

int a3_flat_apart(const a3 *A, uint32_t p, uint32_t q)
{
    const piece *P = &A->pc[p], *Q = &A->pc[q];
    if (P->nc != 1 || Q->nc != 1) return 0;
    uint32_t po = A->pc_off[P->c0], pn = A->pc_off[P->c0 + 1] - po;
    uint32_t qo = A->pc_off[Q->c0], qn = A->pc_off[Q->c0 + 1] - qo;
    if ((uint64_t)pn * qn > 4096 || pn > 64 || qn > 64) return 0; /* for the arrangement */
    /* each piece's turning in the projection along k: its sign about its own plane (canonical
     * or anchor), times the sign of that plane's normal along k */
    plane3 tp, tq;
    const plane3 *pl = a3_piece_plane(A, p, &tp), *ql = a3_piece_plane(A, q, &tq);
    int k = 0;
    for (int a = 1; a < 3; a++)
        if ((pl->n[a] < 0 ? -pl->n[a] : pl->n[a]) > (pl->n[k] < 0 ? -pl->n[k] : pl->n[k])) k = a;
    int oP = P->sgn * (pl->n[k] > 0 ? 1 : -1), oQ = Q->sgn * (ql->n[k] > 0 ? 1 : -1);
    const uint32_t *pv = A->pcv + po, *qv = A->pcv + qo;
    uint64_t alongP = 0, alongQ = 0; /* the edges that run along an edge of the other */
    int touch = 0;
    for (uint32_t i = 0; i < pn; i++) {
        uint32_t a = pv[i], b = pv[i + 1 < pn ? i + 1 : 0];
        for (uint32_t j = 0; j < qn; j++) {
            uint32_t c = qv[j], d = qv[j + 1 < qn ? j + 1 : 0];
            int same;
            if ((a == c && b == d) || (a == d && b == c)) {
                /* a shared edge: the insides of the two on its two sides */
                if (oP == (a == c ? oQ : -oQ)) return 0;
                continue;
            }
            switch (edges_meet(A, k, a, b, c, d, &same)) {
            case EDGES_CROSS:
                return 0;
            case EDGES_ALONG: /* on one line: the insides on its two sides, or they overlap */
                if (oP == (same ? oQ : -oQ)) return 0;
                alongP |= 1ull << i, alongQ |= 1ull << j, touch = 1;
                break;
            case EDGES_TOUCH:
                touch = 1;
                break;
            default:
                break;
            }
        }
    }
    if (!mids_outside(A, k, P, Q, alongP) || !mids_outside(A, k, Q, P, alongQ)) return 0;
    return touch ? 2 : 1;
}

/* ---- charts: where a solid's surface lies flat --------------------------------------------
 *
 * A solid's pieces fall into charts: the pieces whose anchor normals have their largest
 * component on one axis k with one sign (so each turns one way, sigma, when projected along k),
 * joined across the twin edges between two such pieces.  A chart's projection along k counts
 * how many of its pieces cover a point, with sign sigma: that count is the winding number about
 * the point of the chart's boundary, the entries whose twin is not in the chart (the twin
 * entries, one edge walked both ways, cancel).  When that boundary is a set of simple closed
 * polygons, apart from one another, exactly one of them turning the way sigma does, the count
 * is at most 1 everywhere: no two pieces of the chart overlap, nor touch but in vertices and
 * edges they share (a vertex of one inside an edge of the other would leave the count 2 on one
 * side of that edge).  Such a chart is *flat*, and its pieces are never paired with each other:
 * on a clean surface nearly every chart is, so the pairs of one solid cost only along the
 * charts' boundaries and where a surface really meets itself. */

#define CHART_WORK 64 /* edge pairs a boundary edge may cost its chart's check, beyond 4096 */

typedef struct chartjob {
    const a3 *A;
    const uint32_t *s_off; /* by solid: its first piece; ns + 1 */
    uint32_t *of;          /* by piece: its chart, numbered within its solid */
    uint32_t *nch;         /* by solid: its charts */
    uint8_t **flat;        /* by solid: by chart, 1 when flat */
    uint8_t *pclass;       /* by piece: its chart's class */
    const uint32_t *deg;   /* by vertex: the pieces' corners at it, all solids' */
    atomic_uchar *vcert;   /* by vertex: 1 when its star is certified, 2 when not (star_cert) */
    int fail;
} chartjob;

typedef struct bedge {
    uint32_t a, b; /* vertex ids, a to b */
} bedge;

typedef struct bseg {
    int64_t lo[2], hi[2]; /* projected box, coordinates times two */
    uint32_t a, b;
} bseg;

/* Turning clockwise (sigma > 0) or counter-clockwise (sigma < 0) from direction f, the class
 * of direction d: 0 along f, then 1, 2 (opposite f), 3; within 1 and 3 by cross products. */
static int turn_class(const int64_t *f, const int64_t *d, int sigma)
{
    i128 c = ((i128)f[0] * d[1] - (i128)f[1] * d[0]) * -sigma;
    i128 t = (i128)f[0] * d[0] + (i128)f[1] * d[1];
    return c > 0 ? 1 : c < 0 ? 3 : t > 0 ? 0 : 2;
}

/* Turning from f the way sigma says, is d1 met before d2 (1)? */
static int turns_before(const int64_t *f, const int64_t *d1, const int64_t *d2, int sigma)
{
    int c1 = turn_class(f, d1, sigma), c2 = turn_class(f, d2, sigma);
    if (c1 != c2) return c1 < c2;
    i128 x = ((i128)d1[0] * d2[1] - (i128)d1[1] * d2[0]) * -sigma;
    return x > 0;
}

static void dir2(const a3 *A, int k, uint32_t from, uint32_t to, int64_t *d)
{
    const int64_t *p = A->g + 3 * (size_t)from, *q = A->g + 3 * (size_t)to;
    d[0] = q[(k + 1) % 3] - p[(k + 1) % 3];
    d[1] = q[(k + 2) % 3] - p[(k + 2) % 3];
}

/* Is the chart with boundary edges e[0 .. n) (projected along k, its pieces turning sigma)
 * flat?  Its boundary is cut into simple loops: walked edge by edge (at a vertex it passes more
 * than once, where the chart touches itself, going on along the edge going out that bounds the
 * same wedge of the chart: the first met turning from the way it came in, clockwise when
 * sigma > 0, as the chart lies on each edge's left), a loop is cut off wherever the walk comes
 * back to a vertex on it.  The count of pieces over a point is the sum of the loops' winding
 * numbers about it, 0 or 1 for a simple loop turning the way sigma does, 0 or -1 for one turning
 * the other way: flat when exactly one loop turns sigma's way and no two edges meet but in an
 * end they share.  e is sorted here, its b top bit used; seg and on (each edge's place on the
 * walk) are scratch for n. */
#define TAKEN 0x80000000u
static int chart_flat(const a3 *A, bedge *e, size_t n, int k, int sigma, bseg *seg, uint32_t *on,
                      kv *ks)
{
    if (n < 3) return 0;
    uint64_t *u = (uint64_t *)ks; /* e sorted by a (then b), through ks (not in use yet) */
    for (size_t i = 0; i < n; i++) u[i] = (uint64_t)e[i].a << 32 | e[i].b;
    if (sort_u64(u, n)) return 0; /* out of memory: taken as not flat */
    for (size_t i = 0; i < n; i++) e[i] = (bedge){(uint32_t)(u[i] >> 32), (uint32_t)u[i]};
    for (size_t i = 0; i < n; i++) on[i] = NONE;
    uint32_t *path = (uint32_t *)seg; /* the walk's edges (seg is not in use yet) */
    int positive = 0;
    for (size_t i = 0; i < n; i++) {
        if (e[i].b & TAKEN) continue;
        size_t top = 0, at = i;
        for (;;) {
            uint32_t b = e[at].b & ~TAKEN;
            e[at].b |= TAKEN;
            on[at] = (uint32_t)top;
            path[top++] = (uint32_t)at;
            /* the edges going out of b: a run in e, from the first whose a is not below b */
            size_t r0 = 0, r1 = n;
            while (r0 < r1) {
                size_t mid = r0 + (r1 - r0) / 2;
                if (e[mid].a < b)
                    r0 = mid + 1;
                else
                    r1 = mid;
            }
            if (r0 == n || e[r0].a != b) return 0; /* the boundary does not close (a bug) */
            r1 = r0 + 1;
            while (r1 < n && e[r1].a == b) r1++;
            for (size_t r = r0; r < r1; r++) {
                if (on[r] == NONE) continue;
                /* back at b: the walk from there is a loop */
                i128 area = 0;
                for (size_t t = on[r]; t < top; t++) {
                    const int64_t *p = A->g + 3 * (size_t)e[path[t]].a,
                                  *q = A->g + 3 * (size_t)(e[path[t]].b & ~TAKEN);
                    area += (i128)p[(k + 1) % 3] * q[(k + 2) % 3] -
                            (i128)p[(k + 2) % 3] * q[(k + 1) % 3];
                    on[path[t]] = NONE;
                }
                int sg = (area > 0) - (area < 0);
                if (!sg) return 0;
                if (sg == sigma && ++positive > 1) return 0;
                break;
            }
            /* the loop just cut off began with the edge out of b found above: the walk goes
             * back to where it was before it */
            while (top && on[path[top - 1]] == NONE) top--;
            if (!top) break;
            size_t next = SIZE_MAX;
            int64_t f[2], d1[2], d2[2];
            dir2(A, k, b, e[path[top - 1]].a, f); /* back along the edge that came in */
            for (size_t r = r0; r < r1; r++) {
                if (e[r].b & TAKEN) continue;
                if (next == SIZE_MAX) {
                    next = r;
                    dir2(A, k, b, e[r].b, d1);
                    continue;
                }
                dir2(A, k, b, e[r].b, d2);
                if (turns_before(f, d2, d1, sigma)) next = r, d1[0] = d2[0], d1[1] = d2[1];
            }
            if (next == SIZE_MAX) return 0;
            at = next;
        }
    }
    if (positive != 1) return 0;
    /* no two edges meet but in an end they share: a sweep along the first projected
     * coordinate */
    for (size_t i = 0; i < n; i++) {
        uint32_t a = e[i].a, b = e[i].b & ~TAKEN;
        const int64_t *p = A->g + 3 * (size_t)a, *q = A->g + 3 * (size_t)b;
        for (int t = 0; t < 2; t++) {
            int64_t x = p[(k + 1 + t) % 3], y = q[(k + 1 + t) % 3];
            seg[i].lo[t] = x < y ? x : y, seg[i].hi[t] = x < y ? y : x;
        }
        seg[i].a = a, seg[i].b = b;
        ks[i] = (kv){(uint64_t)(seg[i].lo[0] + ((int64_t)1 << 62)), (uint32_t)i};
    }
    if (sort_kv(ks, n)) return 0;
    size_t budget = 4096 + CHART_WORK * n;
    for (size_t i = 0; i < n; i++) {
        const bseg *si = &seg[ks[i].v];
        for (size_t j = i + 1; j < n && seg[ks[j].v].lo[0] <= si->hi[0]; j++) {
            const bseg *sj = &seg[ks[j].v];
            if (!budget--) return 0;
            if (sj->lo[1] > si->hi[1] || sj->hi[1] < si->lo[1]) continue;
            int same;
            if (edges_meet(A, k, si->a, si->b, sj->a, sj->b, &same)) return 0;
        }
    }
    return 1;
}

/* Room for n boundary edges in a solid's scratch for chart_flat. */
typedef struct flatwork {
    bedge *e;
    bseg *seg;
    uint32_t *on;
    kv *ks;
    size_t cap;
} flatwork;

static int flatwork_room(flatwork *w, size_t n)
{
    if (n < w->cap) return 0;
    size_t c = w->cap ? 2 * w->cap : 1024;
    while (c <= n) c *= 2;
    bedge *e = realloc(w->e, c * sizeof *e);
    if (e) w->e = e;
    bseg *sg = realloc(w->seg, c * sizeof *sg);
    if (sg) w->seg = sg;
    uint32_t *on = realloc(w->on, c * sizeof *on);
    if (on) w->on = on;
    kv *ks = realloc(w->ks, c * sizeof *ks);
    if (ks) w->ks = ks;
    if (!e || !sg || !on || !ks) return -1;
    w->cap = c;
    return 0;
}

/* One solid's charts being made: its pieces s0 .. s0 + n (local ids 0 .. n), its entries
 * e0 .. e1.  Only the small arrays below are read piece by piece, never the 64-byte pieces. */
typedef struct solchart {
    const a3 *A;
    uint32_t s0, n, e0, e1;
    int tri;      /* every piece a triangle: piece i's entries are e0 + 3 i .. e0 + 3 i + 3 */
    uint32_t *pe; /* n + 1: piece i's entries pe[i] .. pe[i + 1) (NULL when tri) */
    uint32_t *ep; /* by entry - e0: its piece (NULL when tri) */
    uint8_t *one; /* by piece: one cycle (NULL when tri) */
    uint8_t *cls; /* by piece: its class (piece.cls, or a neighbour's) */
    uint32_t *uf, *grp, *of, *cnt; /* by piece; cnt: n + 2 */
    uint32_t stamp, m;             /* the last set's stamp (grp), the charts made */
    uint8_t *flat;                 /* by chart */
    size_t capflat;
    flatwork w;
} solchart;

#define CHART_SPLITS 3  /* cuts into slabs of a chart that is not flat, at most */
#define CHART_SLABS  8  /* slabs a cut makes */
#define CHART_SMALL  64 /* pieces of a chart not halved further */

static inline uint32_t piece_of(const solchart *C, uint32_t x)
{
    return C->tri ? (x - C->e0) / 3 : C->ep[x - C->e0];
}

static inline uint32_t ent_lo(const solchart *C, uint32_t i)
{
    return C->tri ? C->e0 + 3 * i : C->pe[i];
}

static inline uint32_t ent_hi(const solchart *C, uint32_t i)
{
    return C->tri ? C->e0 + 3 * i + 3 : C->pe[i + 1];
}

/* The entry after x in its cycle (x of local piece i). */
static inline uint32_t ent_next(const solchart *C, uint32_t i, uint32_t x)
{
    if (C->tri || C->one[i]) {
        uint32_t lo = ent_lo(C, i), hi = ent_hi(C, i);
        return x + 1 < hi ? x + 1 : lo;
    }
    const a3 *A = C->A;
    uint32_t cy = A->pc[C->s0 + i].c0;
    while (A->pc_off[cy + 1] <= x) cy++;
    return x + 1 < A->pc_off[cy + 1] ? x + 1 : A->pc_off[cy];
}

/* The twin of entry x as a local piece in the solid, or NONE. */
static inline uint32_t twin_piece(const solchart *C, uint32_t x)
{
    uint32_t y = C->A->ptwin[x];
    return y == NONE || y < C->e0 || y >= C->e1 ? NONE : piece_of(C, y);
}

/* Does no neighbour of local piece i across a twin share its class (cls0)? */
static int lone(const solchart *C, const uint8_t *cls0, uint32_t i)
{
    for (uint32_t x = ent_lo(C, i); x < ent_hi(C, i); x++) {
        uint32_t q = twin_piece(C, x);
        if (q != NONE && cls0[q] == cls0[i]) return 0;
    }
    return 1;
}

/* Is local piece i lone, with a neighbour whose class it may join (cm: piece.cmask)? */
static int lone_joins(const solchart *C, const uint8_t *cls0, const uint8_t *cm, uint32_t i)
{
    int join = 0;
    for (uint32_t x = ent_lo(C, i); x < ent_hi(C, i); x++) {
        uint32_t q = twin_piece(C, x);
        if (q == NONE) continue;
        if (cls0[q] == cls0[i]) return 0;
        if (cm[i] >> cls0[q] & 1) join = 1;
    }
    return join;
}

/* The set of pieces list[0 .. n) (stamped alike in grp), flat?  -1 out of memory. */
static int set_flat(solchart *C, const uint32_t *list, uint32_t n)
{
    const a3 *A = C->A;
    uint32_t st = C->grp[list[0]];
    size_t nb = 0;
    for (uint32_t t = 0; t < n; t++) {
        uint32_t i = list[t];
        for (uint32_t x = ent_lo(C, i); x < ent_hi(C, i); x++) {
            uint32_t q = twin_piece(C, x);
            if (q != NONE && C->grp[q] == st) continue;
            if (flatwork_room(&C->w, nb)) return -1;
            C->w.e[nb++] = (bedge){A->pcv[x], A->pcv[ent_next(C, i, x)]};
        }
    }
    uint32_t cl = C->cls[list[0]];
    return chart_flat(A, C->w.e, nb, (int)(cl / 2), cl & 1 ? 1 : -1, C->w.seg, C->w.on, C->w.ks);
}

static int settle(solchart *C, uint32_t *list, uint32_t n, int depth);

/* The pieces list[0 .. n), stamped alike in grp, cut into their parts joined across twins
 * (a counting sort by part), each settled. */
static int settle_parts(solchart *C, uint32_t *list, uint32_t n, int depth)
{
    uint32_t st = C->grp[list[0]], np = 0;
    for (uint32_t t = 0; t < n; t++) C->uf[list[t]] = list[t];
    for (uint32_t t = 0; t < n; t++) {
        uint32_t i = list[t];
        for (uint32_t x = ent_lo(C, i); x < ent_hi(C, i); x++) {
            uint32_t q = twin_piece(C, x);
            if (q != NONE && q > i && C->grp[q] == st) uf_union(C->uf, i, q);
        }
    }
    /* parts numbered by their first pieces in list; cnt[] counts them */
    for (uint32_t t = 0; t < n; t++) {
        uint32_t i = list[t], r = uf_find(C->uf, i);
        if (r == i) C->grp[i] = np++; /* a root: its part's number (grp is re-stamped below) */
    }
    uint32_t *part = mem_malloc(((size_t)n + 1) * sizeof *part);
    uint32_t *off = mem_calloc((size_t)np + 2, sizeof *off);
    int rc = -1;
    if (!part || !off) goto done;
    for (uint32_t t = 0; t < n; t++) {
        part[t] = C->grp[uf_find(C->uf, list[t])];
        off[part[t] + 2]++;
    }
    for (uint32_t k = 0; k < np; k++) off[k + 2] += off[k + 1];
    uint32_t *tmp = (uint32_t *)C->cnt; /* n + 2 room */
    for (uint32_t t = 0; t < n; t++) tmp[off[part[t] + 1]++] = list[t];
    memcpy(list, tmp, n * sizeof *list);
    free(part);
    part = NULL;
    for (uint32_t k = 0; k < np; k++) {
        uint32_t a = off[k], b = off[k + 1];
        C->stamp++;
        for (uint32_t t = a; t < b; t++) C->grp[list[t]] = C->stamp;
    }
    for (uint32_t k = 0; k < np; k++)
        if (settle(C, list + off[k], off[k + 1] - off[k], depth)) goto done;
    rc = 0;
done:
    free(part), free(off);
    return rc;
}

/* One set of pieces, joined across twins and stamped alike: a chart if flat (or small, or cut
 * enough), else cut into slabs of as many pieces along its projection axis (a chart that is
 * not flat mostly lies over itself, as a bridge over its bank) and each slab's parts settled. */
static int settle(solchart *C, uint32_t *list, uint32_t n, int depth)
{
    /* depth < 0: known not to be flat (solid_charts found so) */
    int f = depth < 0 ? 0 : n < 2 ? 1 : set_flat(C, list, n);
    if (depth < 0) depth = 0;
    if (f < 0) return -1;
    if (!f && depth < CHART_SPLITS && n > CHART_SMALL) {
        const a3 *A = C->A;
        int k = (int)(C->cls[list[0]] / 2);
        /* CHART_SLABS slabs of equal width along k, by the pieces' box centres (a counting
         * sort, through cnt), each stamped, then each one's parts */
        int64_t lo = INT64_MAX, hi = INT64_MIN;
        for (uint32_t t = 0; t < n; t++) {
            const int32_t *b = A->pc[C->s0 + list[t]].box;
            int64_t c = (int64_t)b[k] + b[3 + k];
            lo = c < lo ? c : lo, hi = c > hi ? c : hi;
        }
        uint32_t at[CHART_SLABS + 2] = {0};
        uint8_t *slab = mem_malloc((size_t)n + 1);
        if (!slab) return -1;
        for (uint32_t t = 0; t < n; t++) {
            const int32_t *b = A->pc[C->s0 + list[t]].box;
            int64_t c = (int64_t)b[k] + b[3 + k];
            slab[t] = (uint8_t)((double)(c - lo) * CHART_SLABS / ((double)(hi - lo) + 1));
            at[slab[t] + 2]++;
        }
        for (uint32_t sl = 0; sl < CHART_SLABS; sl++) at[sl + 2] += at[sl + 1];
        uint32_t *tmp = C->cnt; /* n + 2 room */
        for (uint32_t t = 0; t < n; t++) tmp[at[slab[t] + 1]++] = list[t];
        memcpy(list, tmp, n * sizeof *list);
        free(slab);
        for (uint32_t sl = 0; sl < CHART_SLABS; sl++) {
            C->stamp++;
            for (uint32_t t = at[sl]; t < at[sl + 1]; t++) C->grp[list[t]] = C->stamp;
        }
        for (uint32_t sl = 0; sl < CHART_SLABS; sl++)
            if (at[sl + 1] > at[sl] &&
                settle_parts(C, list + at[sl], at[sl + 1] - at[sl], depth + 1))
                return -1;
        return 0;
    }
    if (mem_grow(&C->flat, &C->capflat, (size_t)C->m + 1, 1)) return -1;
    C->flat[C->m] = (uint8_t)f;
    for (uint32_t t = 0; t < n; t++) C->of[list[t]] = C->m;
    C->m++;
    return 0;
}

/* ---- stars: where a surface is one fan about a vertex ---------------------------------------
 *
 * Nearly every pair of one solid's pieces that the walk meets across two charts is a pair of
 * triangles sharing a vertex u on the charts' boundary.  When the triangles about u (its star)
 * form one closed fan that projects along some axis without folding, no two of them meet but in
 * what they share: the star is certified, and such a pair is settled by the vertex ids, without
 * reading the pieces.  The fan is walked across twins from a corner at u until it closes; it
 * must hold every corner at u there is (deg: of any solid, so that u is no vertex of a second
 * fan); along an axis k on which every triangle of it turns one way (piece.cmask), the ray from
 * u along the first projected axis lies in exactly one corner, taken half-open: the fan turns
 * once about u.  Exact: signs of coordinate differences. */

/* Does the ray from the origin along (1, 0) lie in the corner swept from a to b counter-
 * clockwise (a included, b not; a corner of less than half a turn)? */
static inline int ray_in(int64_t ax, int64_t ay, int64_t by)
{
    return (ay < 0 || (ay == 0 && ax > 0)) && by > 0;
}

/* Is the star of vertex u, entry x of local piece i starting at it, one fan of triangles turning
 * once along an axis? */
static int star_one(const solchart *C, const uint8_t *cm, const uint32_t *deg, uint32_t u,
                    uint32_t i, uint32_t x)
{
    const a3 *A = C->A;
    if (!C->tri) return 0;
    const int64_t *g = A->g, *pu = g + 3 * (size_t)u;
    /* one walk counts the corners, the axes all turn one way about (mask) and the ray's hits
     * along axis k, first that of x's chart (at a boundary between two charts' classes the
     * fan's triangles mostly turn one way about both axes); another axis costs a second walk */
    int k = C->cls[i] / 2;
    for (int attempt = 0; attempt < 2; attempt++) {
        uint32_t n = 0, y = x, p = i, mask = 0x3f, hits = 0;
        int ci = (k + 1) % 3, cj = (k + 2) % 3;
        do {
            mask &= cm[p];
            uint32_t lo = C->e0 + 3 * p, in = y == lo ? y + 2 : y - 1,
                     nx = y + 1 == lo + 3 ? lo : y + 1, t = A->ptwin[in];
            const int64_t *pa = g + 3 * (size_t)A->pcv[nx], *pb = g + 3 * (size_t)A->pcv[in];
            int64_t ax = pa[ci] - pu[ci], ay = pa[cj] - pu[cj], bx = pb[ci] - pu[ci],
                    by = pb[cj] - pu[cj];
            hits += cm[p] >> (2 * k + 1) & 1 ? ray_in(ax, ay, by) : ray_in(bx, by, ay);
            if (t == NONE || t < C->e0 || t >= C->e1 || ++n > deg[u]) return 0;
            y = t, p = (t - C->e0) / 3;
        } while (y != x);
        if (n != deg[u] || !mask) return 0;
        if (mask >> (2 * k) & 3) return hits == 1;
        for (k = 0; !(mask >> (2 * k) & 3); k++) continue;
    }
    return 0;
}

/* Settles vcert[u] for the vertex u entry x of local piece i starts at: 1 when its star is
 * certified (star_one), else 2.  Solids are settled in parallel: a vertex whose star another
 * solid shares is refused by each (its fan holds fewer corners than deg), and only the one
 * solid holding all of a star writes a 1 (relaxed atomics: the values are final once written,
 * and read after the tasks end). */
static void star_cert(const solchart *C, const uint8_t *cm, const uint32_t *deg,
                      atomic_uchar *vcert, uint32_t i, uint32_t x)
{
    uint32_t u = C->A->pcv[x];
    if (atomic_load_explicit(&vcert[u], memory_order_relaxed)) return;
    atomic_store_explicit(&vcert[u], star_one(C, cm, deg, u, i, x) ? 1 : 2, memory_order_relaxed);
}

/* One solid's charts (of[], nch, flat): each piece's class (that of its largest normal
 * component; a piece whose class no neighbour across a twin has, a tilt of the surface's
 * noise, takes the class of the first neighbour it may join, as it turns that way about that
 * axis too: else it would be a chart of its own, and its neighbours' charts would gain a
 * boundary), the parts of each class joined across twins, each part's boundary (the entries
 * whose twins lie in another class) checked by chart_flat, and a part that is not flat settled
 * (halved until its parts are). */
static int solid_charts(const chartjob *j, size_t sol)
{
    const a3 *A = j->A;
    solchart C = {0};
    uint32_t s0 = j->s_off[sol], n = j->s_off[sol + 1] - s0;
    uint32_t *list = NULL, *boff = NULL, *bx = NULL;
    uint8_t *mask = NULL;
    int rc = -1;
    C.A = A, C.s0 = s0, C.n = n, C.of = j->of + s0;
    C.tri = solid_entries(A, s0, n, &C.e0, &C.e1);
    C.cls = mem_malloc((size_t)n + 1);
    mask = mem_malloc(2 * (size_t)n + 1);
    C.uf = mem_malloc(((size_t)n + 1) * sizeof *C.uf);
    C.grp = mem_malloc(((size_t)n + 1) * sizeof *C.grp);
    C.cnt = mem_malloc(((size_t)n + 2) * sizeof *C.cnt);
    if (!C.cls || !mask || !C.uf || !C.grp || !C.cnt) goto done;
    if (!C.tri) {
        C.pe = mem_malloc(((size_t)n + 1) * sizeof *C.pe);
        C.ep = mem_malloc(((size_t)C.e1 - C.e0 + 1) * sizeof *C.ep);
        C.one = mem_malloc((size_t)n + 1);
        if (!C.pe || !C.ep || !C.one) goto done;
    }
    const uint32_t e0 = C.e0, e1 = C.e1, *ptwin = A->ptwin;
    const int tri = C.tri;
    uint8_t *cls = C.cls, *cls0 = mask, *cm = mask + n; /* piece.cls, piece.cmask by piece */
    uint32_t *uf = C.uf, *of = C.of, *ep = C.ep, *pe = C.pe;
    for (uint32_t i = 0; i < n; i++) {
        const piece *P = &A->pc[s0 + i];
        if (!tri) {
            pe[i] = A->pc_off[P->c0];
            C.one[i] = P->nc == 1;
            for (uint32_t x = pe[i]; x < A->pc_off[P->c0 + P->nc]; x++) ep[x - e0] = i;
        }
        cls0[i] = P->cls, cm[i] = P->cmask, of[i] = NONE;
    }
    if (!tri) pe[n] = e1;
    /* the charts grown one by one from a seed (uf is the stack): across twins to the pieces of
     * the seed's class, and to a piece of another class that no neighbour shares (a tilt of
     * the surface's noise) when it turns that way about that axis too (piece.cmask): else it
     * would be a chart of its own, and its neighbours' charts would gain a boundary.  Such a
     * piece is no seed while a neighbour's chart may take it.  An entry is looked at once, as
     * its piece is taken: its twin taken too, or in the chart already, or it is on the chart's
     * boundary (listed, chart by chart: boff). */
    size_t nb = 0, capb = 1024, capo = 64;
    bx = mem_malloc(capb * sizeof *bx);
    boff = mem_malloc(capo * sizeof *boff);
    if (!bx || !boff) goto done;
    uint32_t m = 0;
    for (int round = 0; round < 2; round++)
        for (uint32_t s = 0; s < n; s++) {
            if (of[s] != NONE || (round == 0 && lone_joins(&C, cls0, cm, s))) continue;
            uint32_t d = cls0[s], top = 0;
            if (mem_grow(&boff, &capo, (size_t)m + 2, sizeof *boff)) goto done;
            boff[m] = (uint32_t)nb;
            of[s] = m, cls[s] = (uint8_t)d, uf[top++] = s;
            while (top) {
                uint32_t i = uf[--top], hi = tri ? e0 + 3 * i + 3 : pe[i + 1];
                for (uint32_t x = tri ? e0 + 3 * i : pe[i]; x < hi; x++) {
                    uint32_t y = ptwin[x], q = y == NONE || y < e0 || y >= e1 ? NONE
                                               : tri                          ? (y - e0) / 3
                                                                              : ep[y - e0];
                    if (q != NONE) {
                        if (of[q] == m) continue;
                        if (of[q] == NONE &&
                            (cls0[q] == d || (cm[q] >> d & 1 && lone(&C, cls0, q)))) {
                            of[q] = m, cls[q] = (uint8_t)d, uf[top++] = q;
                            continue;
                        }
                    }
                    if (mem_grow(&bx, &capb, nb + 1, sizeof *bx)) goto done;
                    bx[nb++] = x;
                }
            }
            m++;
        }
    if (mem_grow(&boff, &capo, (size_t)m + 2, sizeof *boff)) goto done;
    boff[m] = (uint32_t)nb;
    C.m = m;
    C.flat = mem_malloc((size_t)m + 1);
    C.capflat = (size_t)m + 1;
    if (!C.flat) goto done;
    uint32_t m0 = C.m, bad = 0;
    for (uint32_t c = 0; c < m0; c++) {
        uint32_t b0 = boff[c], b1 = boff[c + 1];
        if (flatwork_room(&C.w, b1 - b0)) goto done;
        for (uint32_t t = b0; t < b1; t++) {
            uint32_t x = bx[t], i = piece_of(&C, x), nx = ent_next(&C, i, x);
            C.w.e[t - b0] = (bedge){A->pcv[x], A->pcv[nx]};
            star_cert(&C, cm, j->deg, j->vcert, i, x); /* both ends: on the boundary */
            star_cert(&C, cm, j->deg, j->vcert, i, nx);
        }
        /* a part of one piece (no boundary edge shared within it) is flat */
        C.flat[c] = b1 - b0 == 0 ? 1 : 0;
        if (!C.flat[c]) {
            uint32_t cl = C.cls[piece_of(&C, bx[b0])];
            C.flat[c] = (uint8_t)chart_flat(A, C.w.e, b1 - b0, (int)(cl / 2), cl & 1 ? 1 : -1,
                                            C.w.seg, C.w.on, C.w.ks);
        }
        bad += !C.flat[c];
    }
    if (bad) { /* the parts that are not flat settled: their pieces listed part by part */
        list = mem_malloc(((size_t)n + 1) * sizeof *list);
        uint32_t *at = mem_calloc((size_t)m0 + 2, sizeof *at);
        if (!list || !at) {
            free(at);
            goto done;
        }
        for (uint32_t i = 0; i < n; i++) at[C.of[i] + 2]++;
        for (uint32_t c = 0; c < m0; c++) at[c + 2] += at[c + 1];
        for (uint32_t i = 0; i < n; i++) list[at[C.of[i] + 1]++] = i;
        C.stamp = 1;
        for (uint32_t i = 0; i < n; i++) C.grp[i] = 0;
        int r = 0;
        for (uint32_t c = 0; c < m0 && !r; c++) {
            if (C.flat[c]) continue;
            uint32_t a = at[c], b = at[c + 1];
            C.stamp++;
            for (uint32_t t = a; t < b; t++) C.grp[list[t]] = C.stamp;
            r = settle(&C, list + a, b - a, -1); /* its parts become new charts */
        }
        free(at);
        if (r) goto done;
    }
    for (uint32_t i = 0; i < n; i++) j->pclass[s0 + i] = C.cls[i];
    j->nch[sol] = C.m;
    j->flat[sol] = C.flat;
    C.flat = NULL;
    rc = 0;
done:
    free(C.cls), free(mask), free(C.uf), free(C.grp), free(C.cnt), free(C.flat), free(list);
    free(C.pe), free(C.ep), free(C.one), free(boff), free(bx);
    free(C.w.e), free(C.w.seg), free(C.w.on), free(C.w.ks);
    return rc;
}

static void charts_task(void *ctx, size_t item, int worker)
{
    (void)worker;
    chartjob *j = ctx;
    if (j->fail) return;
    if (a3_cancelled(j->A)) {
        j->fail = 3;
        return;
    }
    if (solid_charts(j, item)) j->fail = 1;
}

/* Every piece's flat chart (*chartp, by piece: an id, or NONE when its chart is not flat).
 * -1 out of memory, -3 cancelled. */
static int make_charts(const a3 *A, uint32_t **chartp, uint8_t **classp, atomic_uchar *vcert)
{
    size_t n = A->npc, ns = 0;
    uint32_t *s_off = mem_malloc((n + 2) * sizeof *s_off);
    chartjob j = {.A = A, .s_off = s_off, .of = mem_malloc((n + 1) * sizeof *j.of), .vcert = vcert};
    j.pclass = *classp = mem_malloc(n + 1);
    int rc = -1;
    if (!s_off || !j.of || !j.pclass) goto done;
    for (size_t i = 0; i < n; i = a3_solid_end(A, i)) s_off[ns++] = (uint32_t)i;
    s_off[ns] = (uint32_t)n;
    j.nch = mem_calloc(n + 1, sizeof *j.nch); /* ns <= n */
    j.flat = mem_calloc(n + 1, sizeof *j.flat);
    uint32_t *deg = mem_calloc(A->nv + 1, sizeof *deg);
    j.deg = deg;
    if (!j.nch || !j.flat || !deg) goto done;
    for (size_t x = 0; x < A->pc_off[A->npcyc]; x++) deg[A->pcv[x]]++;
    par_for(A->threads, ns, charts_task, &j);
    if (j.fail) {
        rc = j.fail == 3 ? -3 : -1;
        goto done;
    }
    uint32_t base = 0;
    for (size_t s = 0; s < ns; s++) {
        for (uint32_t i = s_off[s]; i < s_off[s + 1]; i++)
            if (!j.flat[s][j.of[i]])
                j.of[i] = NONE, j.pclass[i] = 7;
            else
                j.of[i] += base;
        base += j.nch[s];
    }
    *chartp = j.of;
    j.of = NULL;
    rc = 0;
done:
    for (size_t s = 0; j.flat && s < ns; s++) free(j.flat[s]);
    free(j.flat), free(j.nch), free(j.of), free(s_off), free((void *)j.deg);
    return rc;
}

/* Are all the pieces below nodes x and y in one flat chart? */
static int same_flat(const forest *F, uint32_t x, uint32_t y)
{
    return F->nchart && F->nchart[x] != NONE && F->nchart[x] == F->nchart[y];
}

/* Do the triangles of items i and j (of one solid) share a vertex whose star is certified
 * (star_cert)?  Then they meet only in what they share. */
static inline int star_apart(const forest *F, uint32_t i, uint32_t j)
{
    const uint32_t *a = F->itri[i], *b = F->itri[j];
    if (a[0] == NONE || b[0] == NONE) return 0;
    for (int t = 0; t < 3; t++)
        if ((a[t] == b[0] || a[t] == b[1] || a[t] == b[2]) &&
            atomic_load_explicit(&F->vcert[a[t]], memory_order_relaxed) == 1)
            return 1;
    return 0;
}

/* Item pairs of two leaves of group trees (or of one leaf with itself), boxes meeting: piece
 * pairs of different solids, and of one solid where they may cross (self_apart). */
static int leaf_pairs(const forest *F, const bnode *x, const bnode *y, out64 *o)
{
    const a3 *A = F->A;
    /* the items' boxes in item order: no piece is read for a pair apart (a leaf's pieces are of
     * one chart, and two leaves of one flat chart are never walked: worth) */
    int self = !A->soup && F->isol[x->a] == F->isol[y->a];
    uint32_t nx = x->b & ~LEAFBIT, ny = y->b & ~LEAFBIT, xs[BVH_LEAF], ys[BVH_LEAF];
    if (x == y) {
        for (uint32_t t = 0; t < nx; t++) xs[t] = ys[t] = x->a + t;
    } else { /* only the items meeting the other leaf's box can meet its items */
        uint32_t kx = 0, ky = 0;
        for (uint32_t t = 0; t < nx; t++) {
            xs[kx] = x->a + t;
            kx += (uint32_t)box_meet(F->ibox[x->a + t], y->box);
        }
        for (uint32_t t = 0; t < ny; t++) {
            ys[ky] = y->a + t;
            ky += (uint32_t)box_meet(F->ibox[y->a + t], x->box);
        }
        nx = kx, ny = ky;
    }
    for (uint32_t s = 0; s < nx; s++)
        for (uint32_t r = x == y ? s + 1 : 0; r < ny; r++) {
            uint32_t i = xs[s], j = ys[r];
            if (!box_meet(F->ibox[i], F->ibox[j])) continue;
            uint32_t p = F->item[i], q = F->item[j];
            if (A->soup ? F->isol[i] == F->isol[j]
                        : self && (star_apart(F, i, j) || self_apart(A, p, q)))
                continue;
            if (push64(o, p < q ? (uint64_t)p << 32 | q : (uint64_t)q << 32 | p)) return -1;
        }
    return 0;
}

/* The node pairs below (x, y) of the group trees (boxes meeting), walked to the leaves. */
/* Is the node pair (x, y) worth a visit: not inside one flat chart, and (two nodes) their
 * boxes meeting?  Asked before a pair is pushed. */
static inline int worth(const forest *F, uint32_t x, uint32_t y)
{
    return !same_flat(F, x, y) && (x == y || box_meet(F->node[x].box, F->node[y].box));
}

static inline int push_if(const forest *F, out64 *stack, uint32_t x, uint32_t y)
{
    return worth(F, x, y) ? push64(stack, (uint64_t)x << 32 | y) : 0;
}

static int walk_pair(const forest *F, uint32_t x, uint32_t y, out64 *o, out64 *stack)
{
    stack->n = 0;
    if (push_if(F, stack, x, y)) return -1;
    while (stack->n) {
        uint64_t s = stack->v[--stack->n];
        uint32_t xi = (uint32_t)(s >> 32), yi = (uint32_t)s;
        const bnode *a = &F->node[xi], *b = &F->node[yi];
        if (a == b) { /* a node against itself: its children each, and against each other */
            if (is_leaf(a)) {
                if (leaf_pairs(F, a, a, o)) return -1;
            } else if (push_if(F, stack, a->a, a->a) || push_if(F, stack, a->b, a->b) ||
                       push_if(F, stack, a->a, a->b))
                return -1;
            continue;
        }
        int la = is_leaf(a), lb = is_leaf(b);
        if (la && lb) {
            if (leaf_pairs(F, a, b, o)) return -1;
        } else if (la || (!lb && extent(b) > extent(a))) {
            if (push_if(F, stack, xi, b->a) || push_if(F, stack, xi, b->b)) return -1;
        } else {
            if (push_if(F, stack, a->a, yi) || push_if(F, stack, a->b, yi)) return -1;
        }
    }
    return 0;
}

/* The top tree walked against itself: the pairs of groups whose root boxes meet. */
static int top_pairs(const forest *F, const bvh *T, out64 *o, out64 *stack)
{
    /* entries: (x, y) node pairs of T; x == y walks a node against itself */
    stack->n = 0;
    if (push64(stack, 0)) return -1;
    while (stack->n) {
        uint64_t s = stack->v[--stack->n];
        uint32_t xi = (uint32_t)(s >> 32), yi = (uint32_t)s;
        const bnode *x = &T->node[xi], *y = &T->node[yi];
        if (xi == yi) {
            if (is_leaf(x)) {
                for (uint32_t i = x->a; i < x->a + (x->b & ~LEAFBIT); i++)
                    for (uint32_t j = i + 1; j < x->a + (x->b & ~LEAFBIT); j++) {
                        uint32_t g = T->item[i], h = T->item[j];
                        if (!box_meet(group_box(F, g), group_box(F, h))) continue;
                        if (push64(o, g < h ? (uint64_t)g << 32 | h : (uint64_t)h << 32 | g))
                            return -1;
                    }
                continue;
            }
            if (push64(stack, (uint64_t)x->a << 32 | x->a) ||
                push64(stack, (uint64_t)x->b << 32 | x->b) ||
                push64(stack, (uint64_t)x->a << 32 | x->b))
                return -1;
            continue;
        }
        if (!box_meet(x->box, y->box)) continue;
        int lx = is_leaf(x), ly = is_leaf(y);
        if (lx && ly) {
            for (uint32_t i = x->a; i < x->a + (x->b & ~LEAFBIT); i++)
                for (uint32_t j = y->a; j < y->a + (y->b & ~LEAFBIT); j++) {
                    uint32_t g = T->item[i], h = T->item[j];
                    if (!box_meet(group_box(F, g), group_box(F, h))) continue;
                    if (push64(o, g < h ? (uint64_t)g << 32 | h : (uint64_t)h << 32 | g)) return -1;
                }
        } else if (lx || (!ly && extent(y) > extent(x))) {
            if (push64(stack, (uint64_t)xi << 32 | y->a) ||
                push64(stack, (uint64_t)xi << 32 | y->b))
                return -1;
        } else {
            if (push64(stack, (uint64_t)x->a << 32 | yi) ||
                push64(stack, (uint64_t)x->b << 32 | yi))
                return -1;
        }
    }
    return 0;
}

/* ---- the walks as tasks -------------------------------------------------------------------- */

typedef struct walkjob {
    const forest *F;
    const uint64_t *task; /* node pairs */
    out64 *out;           /* by task */
    out64 *stack;         /* by worker */
    int fail;
} walkjob;

static void walk_task(void *ctx, size_t item, int worker)
{
    walkjob *j = ctx;
    if (j->fail) return;
    if (a3_cancelled(j->F->A)) {
        j->fail = 3;
        return;
    }
    uint64_t t = j->task[item];
    if (walk_pair(j->F, (uint32_t)(t >> 32), (uint32_t)t, &j->out[item], &j->stack[worker]))
        j->fail = 1;
}

/* Splits node pairs (boxes meeting) into their children pairs, breadth first, until there are
 * at least `want` of them or only leaf pairs are left.  In place in *q. */
static int split_tasks(const forest *F, out64 *q, size_t want)
{
    out64 nx = {0};
    for (int round = 0; round < 64 && q->n < want; round++) {
        int grew = 0;
        nx.n = 0;
        for (size_t i = 0; i < q->n; i++) {
            uint64_t s = q->v[i];
            const bnode *a = &F->node[s >> 32], *b = &F->node[(uint32_t)s];
            int la = is_leaf(a), lb = is_leaf(b);
            if (same_flat(F, (uint32_t)(s >> 32), (uint32_t)s)) continue;
            if (a == b) {
                if (!la) {
                    grew = 1;
                    if (push64(&nx, (uint64_t)a->a << 32 | a->a) ||
                        push64(&nx, (uint64_t)a->b << 32 | a->b) ||
                        push64(&nx, (uint64_t)a->a << 32 | a->b))
                        goto fail;
                } else if (push64(&nx, s))
                    goto fail;
                continue;
            }
            if (!box_meet(a->box, b->box)) continue;
            if (la && lb) {
                if (push64(&nx, s)) goto fail;
                continue;
            }
            grew = 1;
            uint64_t c0, c1;
            if (la || (!lb && extent(b) > extent(a))) {
                c0 = (s & ~(uint64_t)UINT32_MAX) | b->a;
                c1 = (s & ~(uint64_t)UINT32_MAX) | b->b;
            } else {
                c0 = (uint64_t)a->a << 32 | (uint32_t)s;
                c1 = (uint64_t)a->b << 32 | (uint32_t)s;
            }
            if (push64(&nx, c0) || push64(&nx, c1)) goto fail;
        }
        out64 t = *q;
        *q = nx;
        nx = t;
        if (!grew) break;
    }
    free(nx.v);
    return 0;
fail:
    free(nx.v);
    return -1;
}

int a3_pairs(const a3 *A, uint64_t **outp, size_t *nout)
{
    forest F = {.A = A};
    uint32_t *chart = NULL;
    uint8_t *pclass = NULL;
    atomic_uchar *vcert = NULL;
    bvh T = {0};
    out64 gp = {0}, stack = {0}, q = {0}, all = {0};
    uint64_t *tsrt = NULL;
    int32_t(*tbox)[6] = NULL;
    walkjob j = {&F, NULL, NULL, NULL, 0};
    int rc = -1;
    *outp = NULL;
    *nout = 0;
    size_t n = A->npc;
    if (n == 0) return 0;
    /* groups: runs of one solid (the pieces come solid by solid: each run's end is found by
     * bisection, not by reading every piece) */
    F.g_off = mem_malloc((n + 1) * sizeof *F.g_off);
    if (!F.g_off) goto done;
    for (size_t i = 0; i < n; i = a3_solid_end(A, i)) F.g_off[F.ng++] = (uint32_t)i;
    F.g_off[F.ng] = (uint32_t)n;
    if (A->soup && F.ng < 2) {
        rc = 0; /* one face: nothing to pair */
        goto done;
    }
    /* A3_NO_SELF (a build for measuring only, as A3_PROF): no pairs of one solid, so that the
     * cost of looking for them shows (issue 26's allowance) */
#ifdef A3_NO_SELF
    const int selfp = 0;
#else
    const int selfp = !A->soup;
#endif
    if (selfp) { /* the solids' flat charts, whose pieces are never paired together */
        vcert = mem_calloc(A->nv + 1, sizeof *vcert);
        if (!vcert) goto done;
        if ((rc = make_charts(A, &chart, &pclass, vcert)) != 0) {
            if (rc != -3) rc = -1;
            goto done;
        }
        F.chart = chart;
        F.pclass = pclass;
        F.nchart = mem_malloc(2 * n * sizeof *F.nchart);
        if (!F.nchart) goto done;
    }
    rc = -1;
    A3_TICK("p/charts");
    F.root = mem_malloc(F.ng * sizeof *F.root);
    F.node = mem_malloc(2 * n * sizeof *F.node); /* pages of unused room are never touched */
    F.item = mem_malloc(n * sizeof *F.item);
    F.srt = mem_malloc(n * sizeof *F.srt);
    F.bx = mem_malloc(n * sizeof *F.bx);
    F.ibox = mem_malloc(n * sizeof *F.ibox);
    F.isol = mem_malloc(n * sizeof *F.isol);
    if (selfp) F.itri = mem_malloc(n * sizeof *F.itri), F.vcert = vcert;
    if (!F.root || !F.node || !F.item || !F.srt || !F.bx || !F.ibox || !F.isol ||
        (selfp && !F.itri))
        goto done;
    F.chunk = F.ng / (8 * (size_t)A->threads) + 1;
    par_for(A->threads, (F.ng + F.chunk - 1) / F.chunk, build_groups, &F);
    if (F.fail == 3) rc = -3;
    if (F.fail) goto done;
    free(F.srt);
    F.srt = NULL;
    A3_TICK("p/trees");
    /* the top tree over the groups, walked against itself (F.bx has room for its boxes) */
    tsrt = mem_malloc(F.ng * sizeof *tsrt);
    tbox = mem_malloc(F.ng * sizeof *tbox);
    T.node = mem_malloc(2 * F.ng * sizeof *T.node);
    T.item = mem_malloc(F.ng * sizeof *T.item);
    if (!tsrt || !tbox || !T.node || !T.item) goto done;
    if (build_tree(group_box, &F, 0, F.ng, NULL, NULL, tsrt, F.bx, tbox, NULL, &T)) goto done;
    if (top_pairs(&F, &T, &gp, &stack)) goto done;
    /* the group pairs' root pairs, split into tasks, walked on the threads */
    if (gp.n > 1 && sort_u64(gp.v, gp.n)) goto done;
    for (size_t i = 0; i < gp.n; i++)
        if (push64(&q, (uint64_t)F.root[gp.v[i] >> 32] << 32 | F.root[(uint32_t)gp.v[i]]))
            goto done;
    if (selfp) /* each solid against itself, but for its flat charts */
        for (size_t g = 0; g < F.ng; g++)
            if (push64(&q, (uint64_t)F.root[g] << 32 | F.root[g])) goto done;
    A3_TICK("p/top");
    if (split_tasks(&F, &q, (size_t)A->threads * 64)) goto done;
    j.task = q.v;
    j.out = mem_calloc(q.n + 1, sizeof *j.out);
    j.stack = mem_calloc((size_t)A->threads, sizeof *j.stack);
    if (!j.out || !j.stack) goto done;
    par_for(A->threads, q.n, walk_task, &j);
    if (j.fail == 3) rc = -3;
    if (j.fail) goto done;
    A3_TICK("p/walk");
    size_t total = 0;
    for (size_t i = 0; i < q.n; i++) total += j.out[i].n;
    all.v = mem_malloc((total + 1) * sizeof *all.v);
    if (!all.v) goto done;
    for (size_t i = 0; i < q.n; i++) {
        if (j.out[i].n) memcpy(all.v + all.n, j.out[i].v, j.out[i].n * sizeof *all.v);
        all.n += j.out[i].n;
    }
    if (sort_u64(all.v, all.n)) goto done;
    *outp = all.v;
    *nout = all.n;
    all.v = NULL;
    rc = 0;
done:
    for (size_t i = 0; j.out && i < q.n; i++) free(j.out[i].v);
    for (int t = 0; j.stack && t < A->threads; t++) free(j.stack[t].v);
    free(j.out);
    free(j.stack);
    free(all.v);
    free(q.v);
    free(gp.v);
    free(stack.v);
    free(tsrt);
    free(tbox);
    free(T.node);
    free(T.item);
    free(F.g_off);
    free(chart);
    free(pclass);
    free(F.nchart);
    free(F.ibox);
    free(F.isol);
    free(F.itri);
    free((void *)vcert);
    free(F.root);
    free(F.node);
    free(F.item);
    free(F.srt);
    free(F.bx);
    return rc;
}
