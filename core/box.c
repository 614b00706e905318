/* box.c — the box-kd-tree buckets; see box.h for the splitting rule and the invariants.
 * Built iteratively (an explicit stack), so depth never costs C stack.  One code for every
 * dimension: the build takes the dimension as a constant (build_dim is inlined into build once
 * for 2 and once for 3), so the 2D tree compiles to what it was before the 3D one shared its
 * code, and the 2D candidates' count keeps its unrolled loop. */
#include "core/box.h"
#include "core/mem.h"
#include "core/par.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* What split_candidates needs of a bucket, gathered in the order of its ids: the sum of its
 * boxes' centres (twice) and their extent per axis. */
typedef struct bstats {
    double sum[BOX_DIM_MAX];
    double mn[BOX_DIM_MAX], mx[BOX_DIM_MAX];
} bstats;

static const bstats stats0 = {
    {0, 0, 0}, {INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};

/* b: a box of dimension dim as doubles (exact: grid coordinates are below 2^53) */
static inline void stats_add(bstats *st, const double *b, int dim)
{
    for (int a = 0; a < dim; a++) {
        st->sum[a] += b[a] + b[a + dim];
        st->mn[a] = b[a] < st->mn[a] ? b[a] : st->mn[a];
        st->mx[a] = b[a + dim] > st->mx[a] ? b[a + dim] : st->mx[a];
    }
}

typedef struct pending {
    int32_t node;    /* index of the node to fill, or -1 for the root */
    int32_t side;    /* which child slot of node */
    size_t off, cnt; /* the bucket: pool[off .. off+cnt) */
    double lo[BOX_DIM_MAX], hi[BOX_DIM_MAX];
    int depth;
    bstats st; /* of its boxes, taken as its parent split (one pass for the root) */
} pending;

typedef struct leafrec {
    size_t off, cnt;
    double lo[BOX_DIM_MAX], hi[BOX_DIM_MAX];
} leafrec;

/* The candidate thresholds of a bucket of cnt boxes with statistics st, for every axis: the
 * mean of the box centres (the seeds' rule) and the middle of the region clipped to the boxes'
 * extent, which still halves the short boxes where the mean fails (long boxes all centred
 * alike).  cand[2a] and cand[2a + 1] are axis a's. */
static inline void split_candidates(const bstats *st, size_t cnt, const double *lo,
                                    const double *hi, double *cand, int dim)
{
    for (int a = 0; a < dim; a++) {
        double l = st->mn[a] > lo[a] ? st->mn[a] : lo[a];
        double h = st->mx[a] < hi[a] ? st->mx[a] : hi[a];
        cand[2 * a] = st->sum[a] / (2.0 * (double)cnt);
        cand[2 * a + 1] = floor(l / 2 + h / 2) + 0.5; /* between grid lines */
    }
}

/* Sizes of both sides for the four candidates of a 2D bucket (two per axis).  One pass. */
static void split_counts2(const double *box, const uint32_t *ids, size_t cnt, const double cand[4],
                          size_t nb[4], size_t na[4])
{
    size_t b0 = 0, b1 = 0, b2 = 0, b3 = 0, a0 = 0, a1 = 0, a2 = 0, a3 = 0;
    const double c0 = cand[0], c1 = cand[1], c2 = cand[2], c3 = cand[3];
    for (size_t i = 0; i < cnt; i++) { /* unrolled: the counters stay in registers */
        const double *b = box + 4 * (size_t)ids[i];
        double x0 = b[0], y0 = b[1], x1 = b[2], y1 = b[3];
        b0 += x0 <= c0, b1 += x0 <= c1, b2 += y0 <= c2, b3 += y0 <= c3;
        a0 += x1 > c0, a1 += x1 > c1, a2 += y1 > c2, a3 += y1 > c3;
    }
    nb[0] = b0, nb[1] = b1, nb[2] = b2, nb[3] = b3;
    na[0] = a0, na[1] = a1, na[2] = a2, na[3] = a3;
}

/* The same for the six candidates of a 3D bucket. */
static void split_counts3(const double *box, const uint32_t *ids, size_t cnt, const double cand[6],
                          size_t nb[6], size_t na[6])
{
    size_t b[6] = {0}, a[6] = {0};
    for (size_t i = 0; i < cnt; i++) {
        const double *x = box + 6 * (size_t)ids[i];
        for (int k = 0; k < 6; k++) b[k] += x[k / 2] <= cand[k], a[k] += x[3 + k / 2] > cand[k];
    }
    memcpy(nb, b, sizeof b);
    memcpy(na, a, sizeof a);
}

/* One build: the buckets still to split (stack), the nodes and leaves made, the ids of every
 * bucket (pool).  A builder may build a whole tree or one subtree (root: its root's reference,
 * a node index or ~leaf). */
typedef struct builder {
    const double *dbox; /* 2 dim a box: lo[dim], hi[dim] */
    int dim;
    size_t leaf_max;
    uint32_t *pool;
    size_t pool_n, pool_cap;
    pending *stack;
    size_t sn, scap;
    leafrec *leaves;
    size_t ln, lcap;
    box_node *nodes;
    size_t nn, ncap;
    int32_t root;
    int failed;
} builder;

static void builder_free(builder *b)
{
    free(b->pool);
    free(b->stack);
    free(b->leaves);
    free(b->nodes);
}

/* Splits buckets until the stack is empty (or, with one_split, after the first split: its two
 * sides are left on the stack).  0, or -1 out of memory.  dim is b->dim, a constant where this
 * is inlined (build). */
static inline __attribute__((always_inline)) int build_dim(builder *b, int one_split, const int dim)
{
    while (b->sn) {
        pending p = b->stack[--b->sn];
        int axis = -1;
        double thr = 0;
        size_t best = p.cnt, nbelow = 0, nabove = 0;
        if (p.cnt > b->leaf_max && p.depth < BOX_DEPTH_MAX) {
            double cand[2 * BOX_DIM_MAX];
            size_t nb[2 * BOX_DIM_MAX], na[2 * BOX_DIM_MAX];
            split_candidates(&p.st, p.cnt, p.lo, p.hi, cand, dim);
            if (dim == 2)
                split_counts2(b->dbox, b->pool + p.off, p.cnt, cand, nb, na);
            else
                split_counts3(b->dbox, b->pool + p.off, p.cnt, cand, nb, na);
            for (int k = 0; k < 2 * dim; k++) {
                int a = k / 2;
                size_t worst = nb[k] > na[k] ? nb[k] : na[k];
                if (worst < best && cand[k] > p.lo[a] && cand[k] < p.hi[a]) {
                    best = worst;
                    axis = a;
                    thr = cand[k];
                    nbelow = nb[k];
                    nabove = na[k];
                }
            }
            if (best + p.cnt / 8 + 1 > p.cnt) axis = -1; /* not worth a split */
        }
        if (axis < 0) {
            if (mem_grow(&b->leaves, &b->lcap, b->ln + 1, sizeof *b->leaves)) return -1;
            b->leaves[b->ln] = (leafrec){.off = p.off, .cnt = p.cnt};
            memcpy(b->leaves[b->ln].lo, p.lo, sizeof p.lo);
            memcpy(b->leaves[b->ln].hi, p.hi, sizeof p.hi);
            int32_t ref = ~(int32_t)b->ln;
            b->ln++;
            if (p.node >= 0)
                b->nodes[p.node].child[p.side] = ref;
            else
                b->root = ref;
            continue;
        }
        if (mem_grow(&b->nodes, &b->ncap, b->nn + 1, sizeof *b->nodes)) return -1;
        int32_t me = (int32_t)b->nn++;
        b->nodes[me] = (box_node){.t = thr, .axis = axis, .child = {0, 0}};
        if (p.node >= 0)
            b->nodes[p.node].child[p.side] = me;
        else
            b->root = me;
        if (mem_grow(&b->pool, &b->pool_cap, b->pool_n + 2 * best, sizeof *b->pool)) return -1;
        /* both sides in one pass, in order, each gathering its statistics as it grows */
        size_t boff = b->pool_n, aoff = b->pool_n + nbelow, bn = 0, an = 0;
        bstats sb = stats0, sa = stats0;
        /* a side that will be a leaf needs no statistics (only a split reads them) */
        int split_b = nbelow > b->leaf_max && p.depth + 1 < BOX_DEPTH_MAX;
        int split_a = nabove > b->leaf_max && p.depth + 1 < BOX_DEPTH_MAX;
        for (size_t i = 0; i < p.cnt; i++) {
            uint32_t id = b->pool[p.off + i];
            const double *bx = b->dbox + 2 * dim * (size_t)id;
            if (bx[axis] <= thr) {
                b->pool[boff + bn++] = id;
                if (split_b) stats_add(&sb, bx, dim);
            }
            if (bx[axis + dim] > thr) {
                b->pool[aoff + an++] = id;
                if (split_a) stats_add(&sa, bx, dim);
            }
        }
        b->pool_n = aoff + an;
        if (mem_grow(&b->stack, &b->scap, b->sn + 2, sizeof *b->stack)) return -1;
        pending below = p, above = p;
        below.st = sb, above.st = sa;
        below.node = above.node = me;
        below.side = 0;
        above.side = 1;
        below.off = boff;
        below.cnt = aoff - boff;
        above.off = aoff;
        above.cnt = b->pool_n - aoff;
        below.hi[axis] = thr;
        above.lo[axis] = thr;
        below.depth = above.depth = p.depth + 1;
        b->stack[b->sn++] = above;
        b->stack[b->sn++] = below;
        if (one_split) return 0;
    }
    return 0;
}

static int build(builder *b, int one_split)
{
    return b->dim == 2 ? build_dim(b, one_split, 2) : build_dim(b, one_split, 3);
}

/* A subtree's builder: the bucket p of parent's pool, copied into its own, as its root. */
static int sub_builder(builder *s, const builder *parent, pending p)
{
    memset(s, 0, sizeof *s);
    s->dbox = parent->dbox;
    s->dim = parent->dim;
    s->leaf_max = parent->leaf_max;
    if (mem_grow(&s->pool, &s->pool_cap, p.cnt ? p.cnt : 1, sizeof *s->pool) ||
        mem_grow(&s->stack, &s->scap, 1, sizeof *s->stack))
        return -1;
    memcpy(s->pool, parent->pool + p.off, p.cnt * sizeof *s->pool);
    s->pool_n = p.cnt;
    p.off = 0;
    p.node = -1;
    s->stack[s->sn++] = p;
    return 0;
}

static void build_item(void *vb, size_t i, int w)
{
    builder *b = (builder *)vb + i;
    (void)w;
    if (build(b, 0)) b->failed = 1;
}

/* A reference of subtree builder s moved by its node and leaf offsets in the whole tree. */
static int32_t moved(int32_t ref, size_t node0, size_t leaf0)
{
    return ref >= 0 ? ref + (int32_t)node0 : ~(~ref + (int32_t)leaf0);
}

/* Below this many boxes the tree is built on one thread. */
#define BOX_PAR_MIN 20000

int box_tree_build(box_tree *t, const int64_t *ibox, size_t n, size_t leaf_max)
{
    return box_tree_build_dim(t, 2, ibox, n, leaf_max, 1);
}

int box_tree_build_par(box_tree *t, const int64_t *ibox, size_t n, size_t leaf_max, int threads)
{
    return box_tree_build_dim(t, 2, ibox, n, leaf_max, threads);
}

int box_tree_build_dim(box_tree *t, int dim, const int64_t *ibox, size_t n, size_t leaf_max,
                       int threads)
{
    /* the boxes as doubles, once: every pass compares them with the thresholds */
    assert(dim == 2 || dim == 3);
    size_t bw = 2 * (size_t)dim;
    double *dbox = mem_malloc((bw * n + 1) * sizeof *dbox);
    builder m = {.dbox = dbox, .dim = dim, .leaf_max = leaf_max}, sub[2];
    size_t nsub = 0;
    memset(t, 0, sizeof *t);
    memset(sub, 0, sizeof sub);
    if (!dbox || mem_grow(&m.pool, &m.pool_cap, n ? n : 1, sizeof *m.pool) ||
        mem_grow(&m.stack, &m.scap, 1, sizeof *m.stack))
        goto fail;
    for (size_t i = 0; i < n; i++) m.pool[i] = (uint32_t)i;
    m.pool_n = n;
    m.stack[m.sn++] = (pending){.node = -1,
                                .off = 0,
                                .cnt = n,
                                .lo = {-INFINITY, -INFINITY, -INFINITY},
                                .hi = {INFINITY, INFINITY, INFINITY},
                                .st = stats0};
    for (size_t i = 0; i < bw * n; i++) dbox[i] = (double)ibox[i];
    for (size_t i = 0; i < n; i++) stats_add(&m.stack[0].st, dbox + bw * i, dim);
    if (threads > 1 && n >= BOX_PAR_MIN) {
        /* the root split here, then its two sides on two threads: the same nodes and leaves,
         * numbered as one thread numbers them (depth first, below before above) */
        if (build(&m, 1)) goto fail;
        if (m.sn == 2) {
            if (sub_builder(&sub[0], &m, m.stack[1]) || sub_builder(&sub[1], &m, m.stack[0]))
                goto fail;
            m.sn = 0;
            nsub = 2;
            par_for(threads, 2, build_item, sub);
            if (sub[0].failed || sub[1].failed) goto fail;
        }
    }
    if (build(&m, 0)) goto fail;
    /* the whole tree: m's nodes and leaves, then each subtree's, moved */
    builder *parts[3] = {&m, &sub[0], &sub[1]};
    size_t np = 1 + nsub, nn = 0, ln = 0, total = 0;
    size_t node0[3], leaf0[3];
    for (size_t k = 0; k < np; k++) {
        node0[k] = nn;
        leaf0[k] = ln;
        nn += parts[k]->nn;
        ln += parts[k]->ln;
        for (size_t l = 0; l < parts[k]->ln; l++) total += parts[k]->leaves[l].cnt;
    }
    if (nn == 0) nn = 1; /* the root is a leaf: a one-node tree whose both sides are it */
    t->nodes = malloc(nn * sizeof *t->nodes);
    t->leaf_off = malloc((ln + 1) * sizeof *t->leaf_off);
    t->items = malloc((total ? total : 1) * sizeof *t->items);
    t->region = malloc((ln ? ln : 1) * bw * sizeof *t->region);
    if (!t->nodes || !t->leaf_off || !t->items || !t->region) goto fail;
    if (m.nn == 0) {
        t->nodes[0] = (box_node){.t = INFINITY, .axis = 0, .child = {m.root, m.root}};
    } else {
        for (size_t k = 0; k < np; k++)
            for (size_t i = 0; i < parts[k]->nn; i++) {
                box_node nd = parts[k]->nodes[i];
                nd.child[0] = moved(nd.child[0], node0[k], leaf0[k]);
                nd.child[1] = moved(nd.child[1], node0[k], leaf0[k]);
                t->nodes[node0[k] + i] = nd;
            }
        for (size_t k = 1; k < np; k++) /* the root's sides: below (k 1), above (k 2) */
            t->nodes[0].child[k - 1] = moved(parts[k]->root, node0[k], leaf0[k]);
    }
    total = 0;
    for (size_t k = 0, l0 = 0; k < np; k++)
        for (size_t l = 0; l < parts[k]->ln; l++, l0++) {
            const leafrec *lr = &parts[k]->leaves[l];
            t->leaf_off[l0] = (uint32_t)total;
            memcpy(t->items + total, parts[k]->pool + lr->off, lr->cnt * sizeof *t->items);
            total += lr->cnt;
            for (int a = 0; a < dim; a++) {
                t->region[bw * l0 + (size_t)a] = lr->lo[a];
                t->region[bw * l0 + (size_t)dim + (size_t)a] = lr->hi[a];
            }
        }
    t->leaf_off[ln] = (uint32_t)total;
    t->nleaves = ln;
    t->nnodes = nn;
    t->dim = dim;
    builder_free(&m);
    builder_free(&sub[0]);
    builder_free(&sub[1]);
    free(dbox);
    return 0;
fail:
    free(dbox);
    builder_free(&m);
    builder_free(&sub[0]);
    builder_free(&sub[1]);
    box_tree_free(t);
    return -1;
}

uint32_t box_tree_locate(const box_tree *t, double x, double y)
{
    int32_t i = 0;
    for (;;) {
        const box_node *nd = &t->nodes[i];
        double c = nd->axis ? y : x;
        int32_t next = nd->child[c <= nd->t ? 0 : 1];
        if (next < 0) return (uint32_t)~next;
        i = next;
    }
}

uint32_t box_tree_locate_pt(const box_tree *t, const double *p)
{
    int32_t i = 0;
    for (;;) {
        const box_node *nd = &t->nodes[i];
        int32_t next = nd->child[p[nd->axis] <= nd->t ? 0 : 1];
        if (next < 0) return (uint32_t)~next;
        i = next;
    }
}

void box_tree_free(box_tree *t)
{
    free(t->leaf_off);
    free(t->items);
    free(t->region);
    free(t->nodes);
    memset(t, 0, sizeof *t);
}
