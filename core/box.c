/* box.c — the box-kd-tree buckets; see box.h for the splitting rule and the invariants.
 * Built iteratively (an explicit stack), so depth never costs C stack. */
#include "core/box.h"
#include "core/mem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define BOX_MAX_DEPTH 60

typedef struct pending {
    int32_t node;    /* index of the node to fill, or -1 for the root */
    int32_t side;    /* which child slot of node */
    size_t off, cnt; /* the bucket: pool[off .. off+cnt) */
    double lo[2], hi[2];
    int depth;
} pending;

typedef struct leafrec {
    size_t off, cnt;
    double lo[2], hi[2];
} leafrec;

/* The candidate thresholds of a bucket, for both axes: the mean of the box centres (the
 * seeds' rule) and the middle of the region clipped to the boxes' extent, which still halves
 * the short boxes where the mean fails (long boxes all centred alike).  One pass. */
static void split_candidates(const int64_t *box, const uint32_t *ids, size_t cnt,
                             const double lo[2], const double hi[2], double cand[4])
{
    double sum[2] = {0, 0};
    int64_t mn[2] = {INT64_MAX, INT64_MAX}, mx[2] = {INT64_MIN, INT64_MIN};
    for (size_t i = 0; i < cnt; i++) {
        const int64_t *b = box + 4 * (size_t)ids[i];
        for (int a = 0; a < 2; a++) {
            sum[a] += (double)b[a] + (double)b[a + 2];
            mn[a] = b[a] < mn[a] ? b[a] : mn[a];
            mx[a] = b[a + 2] > mx[a] ? b[a + 2] : mx[a];
        }
    }
    for (int a = 0; a < 2; a++) {
        double l = (double)mn[a] > lo[a] ? (double)mn[a] : lo[a];
        double h = (double)mx[a] < hi[a] ? (double)mx[a] : hi[a];
        cand[2 * a] = sum[a] / (2.0 * (double)cnt);
        cand[2 * a + 1] = floor(l / 2 + h / 2) + 0.5; /* between grid lines */
    }
}

/* Sizes of both sides for the four candidates (two per axis).  One pass. */
static void split_counts(const int64_t *box, const uint32_t *ids, size_t cnt, const double cand[4],
                         size_t nb[4], size_t na[4])
{
    for (int k = 0; k < 4; k++) nb[k] = na[k] = 0;
    for (size_t i = 0; i < cnt; i++) {
        const int64_t *b = box + 4 * (size_t)ids[i];
        for (int k = 0; k < 4; k++) {
            int a = k / 2;
            nb[k] += (double)b[a] <= cand[k];
            na[k] += (double)b[a + 2] > cand[k];
        }
    }
}

int box_tree_build(box_tree *t, const int64_t *box, size_t n, size_t leaf_max)
{
    uint32_t *pool = NULL;
    size_t pool_n = 0, pool_cap = 0;
    pending *stack = NULL;
    size_t sn = 0, scap = 0;
    leafrec *leaves = NULL;
    size_t ln = 0, lcap = 0;
    box_node *nodes = NULL;
    size_t nn = 0, ncap = 0;

    memset(t, 0, sizeof *t);
    if (mem_grow(&pool, &pool_cap, n ? n : 1, sizeof *pool)) goto fail;
    for (size_t i = 0; i < n; i++) pool[i] = (uint32_t)i;
    pool_n = n;
    if (mem_grow(&stack, &scap, 1, sizeof *stack)) goto fail;
    stack[sn++] = (pending){
        .node = -1, .off = 0, .cnt = n, .lo = {-INFINITY, -INFINITY}, .hi = {INFINITY, INFINITY}};
    while (sn) {
        pending p = stack[--sn];
        int axis = -1;
        double thr = 0;
        size_t best = p.cnt;
        if (p.cnt > leaf_max && p.depth < BOX_MAX_DEPTH) {
            double cand[4];
            size_t nb[4], na[4];
            split_candidates(box, pool + p.off, p.cnt, p.lo, p.hi, cand);
            split_counts(box, pool + p.off, p.cnt, cand, nb, na);
            for (int k = 0; k < 4; k++) {
                int a = k / 2;
                size_t worst = nb[k] > na[k] ? nb[k] : na[k];
                if (worst < best && cand[k] > p.lo[a] && cand[k] < p.hi[a]) {
                    best = worst;
                    axis = a;
                    thr = cand[k];
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
        size_t boff = pool_n, aoff;
        for (size_t i = 0; i < p.cnt; i++) {
            uint32_t id = pool[p.off + i];
            if ((double)box[4 * (size_t)id + axis] <= thr) pool[pool_n++] = id;
        }
        aoff = pool_n;
        for (size_t i = 0; i < p.cnt; i++) {
            uint32_t id = pool[p.off + i];
            if ((double)box[4 * (size_t)id + axis + 2] > thr) pool[pool_n++] = id;
        }
        if (mem_grow(&stack, &scap, sn + 2, sizeof *stack)) goto fail;
        pending below = p, above = p;
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
    return 0;
fail:
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
