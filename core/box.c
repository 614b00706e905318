/* box.c — the box-kd-tree buckets; see box.h for the splitting rule and the invariants.
 * Built iteratively (an explicit stack), so depth never costs C stack. */
#include "core/box.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* What split_candidates needs of a bucket, gathered in the order of its ids: the sum of its
 * boxes' centres (twice) and their extent per axis. */
typedef struct bstats {
    double sum[2];
    double mn[2], mx[2];
} bstats;

static const bstats stats0 = {{0, 0}, {INFINITY, INFINITY}, {-INFINITY, -INFINITY}};

/* b: a box as doubles (exact: grid coordinates are below 2^53) */
static inline void stats_add(bstats *st, const double *b)
{
    for (int a = 0; a < 2; a++) {
        st->sum[a] += b[a] + b[a + 2];
        st->mn[a] = b[a] < st->mn[a] ? b[a] : st->mn[a];
        st->mx[a] = b[a + 2] > st->mx[a] ? b[a + 2] : st->mx[a];
    }
}

typedef struct pending {
    int32_t node;    /* index of the node to fill, or -1 for the root */
    int32_t side;    /* which child slot of node */
    size_t off, cnt; /* the bucket: pool[off .. off+cnt) */
    double lo[2], hi[2];
    int depth;
    bstats st; /* of its boxes, taken as its parent split (one pass for the root) */
} pending;

typedef struct leafrec {
    size_t off, cnt;
    double lo[2], hi[2];
} leafrec;

/* The candidate thresholds of a bucket of cnt boxes with statistics st, for both axes: the mean
 * of the box centres (the seeds' rule) and the middle of the region clipped to the boxes'
 * extent, which still halves the short boxes where the mean fails (long boxes all centred
 * alike). */
static void split_candidates(const bstats *st, size_t cnt, const double lo[2], const double hi[2],
                             double cand[4])
{
    for (int a = 0; a < 2; a++) {
        double l = st->mn[a] > lo[a] ? st->mn[a] : lo[a];
        double h = st->mx[a] < hi[a] ? st->mx[a] : hi[a];
        cand[2 * a] = st->sum[a] / (2.0 * (double)cnt);
        cand[2 * a + 1] = floor(l / 2 + h / 2) + 0.5; /* between grid lines */
    }
}

/* Sizes of both sides for the four candidates (two per axis).  One pass. */
static void split_counts(const double *box, const uint32_t *ids, size_t cnt, const double cand[4],
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

int box_tree_build(box_tree *t, const int64_t *ibox, size_t n, size_t leaf_max)
{
    /* the boxes as doubles, once: every pass compares them with the thresholds */
    double *dbox = mem_malloc((4 * n + 1) * sizeof *dbox);
    uint32_t *pool = NULL;
    size_t pool_n = 0, pool_cap = 0;
    pending *stack = NULL;
    size_t sn = 0, scap = 0;
    leafrec *leaves = NULL;
    size_t ln = 0, lcap = 0;
    box_node *nodes = NULL;
    size_t nn = 0, ncap = 0;

    memset(t, 0, sizeof *t);
    if (!dbox || mem_grow(&pool, &pool_cap, n ? n : 1, sizeof *pool)) goto fail;
    for (size_t i = 0; i < n; i++) pool[i] = (uint32_t)i;
    pool_n = n;
    if (mem_grow(&stack, &scap, 1, sizeof *stack)) goto fail;
    stack[sn++] = (pending){.node = -1,
                            .off = 0,
                            .cnt = n,
                            .lo = {-INFINITY, -INFINITY},
                            .hi = {INFINITY, INFINITY},
                            .st = stats0};
    for (size_t i = 0; i < 4 * n; i++) dbox[i] = (double)ibox[i];
    for (size_t i = 0; i < n; i++) stats_add(&stack[0].st, dbox + 4 * i);
    while (sn) {
        pending p = stack[--sn];
        int axis = -1;
        double thr = 0;
        size_t best = p.cnt, nbelow = 0;
        if (p.cnt > leaf_max && p.depth < BOX_DEPTH_MAX) {
            double cand[4];
            size_t nb[4], na[4];
            split_candidates(&p.st, p.cnt, p.lo, p.hi, cand);
            split_counts(dbox, pool + p.off, p.cnt, cand, nb, na);
            for (int k = 0; k < 4; k++) {
                int a = k / 2;
                size_t worst = nb[k] > na[k] ? nb[k] : na[k];
                if (worst < best && cand[k] > p.lo[a] && cand[k] < p.hi[a]) {
                    best = worst;
                    axis = a;
                    thr = cand[k];
                    nbelow = nb[k];
                }
            }
            if (best + p.cnt / 8 + 1 > p.cnt) axis = -1; /* not worth a split */
        }
        if (axis < 0) {
            if (mem_grow(&leaves, &lcap, ln + 1, sizeof *leaves)) goto fail;
            leaves[ln] = (leafrec){.off = p.off, .cnt = p.cnt};
            memcpy(leaves[ln].lo, p.lo, sizeof p.lo);
            memcpy(leaves[ln].hi, p.hi, sizeof p.hi);
            int32_t ref = ~(int32_t)ln;
            ln++;
            if (p.node >= 0)
                nodes[p.node].child[p.side] = ref;
            else if (mem_grow(&nodes, &ncap, 1, sizeof *nodes))
                goto fail;
            else { /* the root is a leaf: a one-node tree whose both sides are that leaf */
                nodes[0] = (box_node){.t = INFINITY, .axis = 0, .child = {ref, ref}};
                nn = 1;
            }
            continue;
        }
        if (mem_grow(&nodes, &ncap, nn + 1, sizeof *nodes)) goto fail;
        int32_t me = (int32_t)nn++;
        nodes[me] = (box_node){.t = thr, .axis = axis, .child = {0, 0}};
        if (p.node >= 0) nodes[p.node].child[p.side] = me;
        if (mem_grow(&pool, &pool_cap, pool_n + 2 * best, sizeof *pool)) goto fail;
        /* both sides in one pass, in order, each gathering its statistics as it grows */
        size_t boff = pool_n, aoff = pool_n + nbelow, bn = 0, an = 0;
        bstats sb = stats0, sa = stats0;
        for (size_t i = 0; i < p.cnt; i++) {
            uint32_t id = pool[p.off + i];
            const double *b = dbox + 4 * (size_t)id;
            if (b[axis] <= thr) pool[boff + bn++] = id, stats_add(&sb, b);
            if (b[axis + 2] > thr) pool[aoff + an++] = id, stats_add(&sa, b);
        }
        pool_n = aoff + an;
        if (mem_grow(&stack, &scap, sn + 2, sizeof *stack)) goto fail;
        pending below = p, above = p;
        below.st = sb, above.st = sa;
        below.node = above.node = me;
        below.side = 0;
        above.side = 1;
        below.off = boff;
        below.cnt = aoff - boff;
        above.off = aoff;
        above.cnt = pool_n - aoff;
        below.hi[axis] = thr;
        above.lo[axis] = thr;
        below.depth = above.depth = p.depth + 1;
        stack[sn++] = above;
        stack[sn++] = below;
    }
    size_t total = 0;
    for (size_t l = 0; l < ln; l++) total += leaves[l].cnt;
    t->leaf_off = malloc((ln + 1) * sizeof *t->leaf_off);
    t->items = malloc((total ? total : 1) * sizeof *t->items);
    t->region = malloc((ln ? ln : 1) * 4 * sizeof *t->region);
    if (!t->leaf_off || !t->items || !t->region) goto fail;
    total = 0;
    for (size_t l = 0; l < ln; l++) {
        t->leaf_off[l] = (uint32_t)total;
        memcpy(t->items + total, pool + leaves[l].off, leaves[l].cnt * sizeof *pool);
        total += leaves[l].cnt;
        t->region[4 * l + 0] = leaves[l].lo[0];
        t->region[4 * l + 1] = leaves[l].lo[1];
        t->region[4 * l + 2] = leaves[l].hi[0];
        t->region[4 * l + 3] = leaves[l].hi[1];
    }
    t->leaf_off[ln] = (uint32_t)total;
    t->nleaves = ln;
    t->nodes = nodes;
    t->nnodes = nn;
    free(pool);
    free(stack);
    free(leaves);
    free(dbox);
    return 0;
fail:
    free(dbox);
    free(pool);
    free(stack);
    free(leaves);
    free(nodes);
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

void box_tree_free(box_tree *t)
{
    free(t->leaf_off);
    free(t->items);
    free(t->region);
    free(t->nodes);
    memset(t, 0, sizeof *t);
}
