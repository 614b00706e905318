/* arr3_pairs.c — the candidate pairs of the 3D arrangement (stage 2 of arr3.h): the pieces of
 * different solids whose closed boxes meet.
 *
 * A bounding-volume hierarchy per solid, and one over the solids.  A solid's pieces are sorted
 * by the Morton code of their boxes' centres (63 bits: 21 per axis, over the solid's own box)
 * and the sorted run is split at the highest bit in which its first and last codes differ (in
 * the middle when they are equal), down to leaves of at most BVH_LEAF pieces; every node keeps
 * the box of what lies below it.  So a tree always splits, whatever the shape of the input (a
 * shell inside its mesh, long thin faces, many faces in one plane: a kd-tree that stops where a
 * split does not separate its boxes compares every pair of a large bucket there), and it has
 * depth at most 63 + log2(n).  The solids' root boxes get a tree of their own; walking it
 * against itself gives the pairs of solids whose boxes meet, and each such pair's trees are
 * walked against each other (the larger node's children first), so the work grows with the
 * node pairs whose boxes meet, not with the pieces: the parts of two surfaces far from each
 * other are left at the first nodes that separate them.  In a face soup each face is a solid.
 *
 * Threads: the trees are built on par_for() (a solid each, in chunks), and the walks of the
 * solid pairs are cut into tasks (node pairs, breadth first, until there are enough of them)
 * that run on par_for(), each writing its own list; the lists are concatenated and sorted, so
 * the pairs do not depend on the number of threads.
 */
#include "core/arr3_int.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "core/mem.h"
#include "core/par.h"
#include "core/sort.h"

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

static int box_meet(const int32_t *a, const int32_t *b)
{
    return a[0] <= b[3] && b[0] <= a[3] && a[1] <= b[4] && b[1] <= a[4] && a[2] <= b[5] &&
           b[2] <= a[5];
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
    const int32_t (*bx)[6]; /* the items' boxes, by index */
    const kv *srt;          /* (code, index) sorted by code */
    uint32_t base;          /* item index i is id base + i */
    bvh *t;
} builder;

/* The node over srt[lo .. hi) at t->node[at]; returns 0.  Nodes are allocated in preorder from
 * t->nnode (room for 2 (hi - lo) was made). */
static void build_node(builder *B, uint32_t at, size_t lo, size_t hi)
{
    bnode *n = &B->t->node[at];
    if (hi - lo <= BVH_LEAF) {
        n->a = (uint32_t)lo;
        n->b = (uint32_t)(hi - lo) | LEAFBIT;
        memcpy(n->box, B->bx[B->srt[lo].v], sizeof n->box);
        for (size_t i = lo; i < hi; i++) {
            B->t->item[i] = B->base + B->srt[i].v;
            if (i > lo) box_join(n->box, n->box, B->bx[B->srt[i].v]);
        }
        return;
    }
    uint64_t c0 = B->srt[lo].k, c1 = B->srt[hi - 1].k;
    size_t mid;
    if (c0 == c1) {
        mid = lo + (hi - lo) / 2;
    } else {
        int bit = 63 - __builtin_clzll(c0 ^ c1);
        size_t l = lo, r = hi - 1; /* the first code with the bit set lies in (l, r] */
        while (r - l > 1) {
            size_t m = l + (r - l) / 2;
            if (B->srt[m].k >> bit & 1)
                r = m;
            else
                l = m;
        }
        mid = r;
    }
    uint32_t ca = (uint32_t)B->t->nnode++, cb = (uint32_t)B->t->nnode++;
    build_node(B, ca, lo, mid);
    build_node(B, cb, mid, hi);
    n = &B->t->node[at];
    n->a = ca, n->b = cb;
    box_join(n->box, B->t->node[ca].box, B->t->node[cb].box);
}

/* The tree over the ids base .. base + n (n >= 1) into t, whose arrays have room for 2n nodes
 * and n items.  srt and bx are scratch for n entries (bx: the boxes, read once through boxof
 * and then in order).  Returns -1 out of memory. */
static int build_tree(const int32_t *(*boxof)(const void *, uint32_t), const void *ctx,
                      uint32_t base, size_t n, kv *srt, int32_t (*bx)[6], bvh *t)
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
    for (int k = 0; k < 3; k++) { /* the centres' spread down to 10 bits (a 30-bit code: three
                                   * passes of the radix sort; equal codes split in the middle) */
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
        srt[i] = (kv){code, (uint32_t)i};
    }
    if (sort_kv(srt, n)) return -1;
    builder B = {(const int32_t(*)[6])bx, srt, base, t};
    t->nnode = 1;
    build_node(&B, 0, 0, n);
    return 0;
}

/* ---- the groups (solids) and their trees ------------------------------------------------- */

typedef struct forest {
    const a3 *A;
    size_t ng;
    uint32_t *g_off; /* ng + 1: group g holds pieces g_off[g] .. g_off[g + 1) */
    uint32_t *root;  /* ng: its tree's root in node[] */
    bnode *node;     /* every group's nodes: group g's from 2 g_off[g] */
    uint32_t *item;  /* every group's items: group g's at g_off[g] .. */
    kv *srt;
    int32_t (*bx)[6]; /* build_tree's scratch, by piece */
    size_t chunk;     /* groups a task */
    int fail;
} forest;

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
        if (build_tree(piece_box, F->A, o, n, F->srt + o, F->bx + o, &t)) {
            F->fail = 1;
            return;
        }
        F->root[g] = 2 * o; /* node ids are global: offset by the group's start */
        for (size_t i = 0; i < t.nnode; i++) {
            bnode *nd = &t.node[i];
            if (nd->b & LEAFBIT)
                nd->a += o;
            else
                nd->a += 2 * o, nd->b += 2 * o;
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

/* Item pairs of two leaves of group trees, boxes meeting: piece pairs of different solids. */
static int leaf_pairs(const forest *F, const bnode *x, const bnode *y, out64 *o)
{
    const a3 *A = F->A;
    for (uint32_t i = x->a; i < x->a + (x->b & ~LEAFBIT); i++)
        for (uint32_t j = y->a; j < y->a + (y->b & ~LEAFBIT); j++) {
            uint32_t p = F->item[i], q = F->item[j];
            if (A->pc[p].solid == A->pc[q].solid || !box_meet(A->pc[p].box, A->pc[q].box)) continue;
            if (push64(o, p < q ? (uint64_t)p << 32 | q : (uint64_t)q << 32 | p)) return -1;
        }
    return 0;
}

/* The node pairs below (x, y) of the group trees (boxes meeting), walked to the leaves. */
static int walk_pair(const forest *F, uint32_t x, uint32_t y, out64 *o, out64 *stack)
{
    stack->n = 0;
    if (push64(stack, (uint64_t)x << 32 | y)) return -1;
    while (stack->n) {
        uint64_t s = stack->v[--stack->n];
        const bnode *a = &F->node[s >> 32], *b = &F->node[(uint32_t)s];
        if (!box_meet(a->box, b->box)) continue;
        int la = is_leaf(a), lb = is_leaf(b);
        if (la && lb) {
            if (leaf_pairs(F, a, b, o)) return -1;
        } else if (la || (!lb && extent(b) > extent(a))) {
            if (push64(stack, (s & ~(uint64_t)UINT32_MAX) | b->a) ||
                push64(stack, (s & ~(uint64_t)UINT32_MAX) | b->b))
                return -1;
        } else {
            if (push64(stack, (uint64_t)a->a << 32 | (uint32_t)s) ||
                push64(stack, (uint64_t)a->b << 32 | (uint32_t)s))
                return -1;
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
    forest F = {A, 0, NULL, NULL, NULL, NULL, NULL, NULL, 0, 0};
    bvh T = {0};
    out64 gp = {0}, stack = {0}, q = {0}, all = {0};
    kv *tsrt = NULL;
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
    if (F.ng < 2) {
        rc = 0; /* one solid: nothing to pair */
        goto done;
    }
    F.root = mem_malloc(F.ng * sizeof *F.root);
    F.node = mem_malloc(2 * n * sizeof *F.node); /* pages of unused room are never touched */
    F.item = mem_malloc(n * sizeof *F.item);
    F.srt = mem_malloc(n * sizeof *F.srt);
    F.bx = mem_malloc(n * sizeof *F.bx);
    if (!F.root || !F.node || !F.item || !F.srt || !F.bx) goto done;
    F.chunk = F.ng / (8 * (size_t)A->threads) + 1;
    par_for(A->threads, (F.ng + F.chunk - 1) / F.chunk, build_groups, &F);
    if (F.fail == 3) rc = -3;
    if (F.fail) goto done;
    free(F.srt);
    F.srt = NULL;
    /* the top tree over the groups, walked against itself (F.bx has room for its boxes) */
    tsrt = mem_malloc(F.ng * sizeof *tsrt);
    T.node = mem_malloc(2 * F.ng * sizeof *T.node);
    T.item = mem_malloc(F.ng * sizeof *T.item);
    if (!tsrt || !T.node || !T.item) goto done;
    if (build_tree(group_box, &F, 0, F.ng, tsrt, F.bx, &T)) goto done;
    if (top_pairs(&F, &T, &gp, &stack)) goto done;
    /* the group pairs' root pairs, split into tasks, walked on the threads */
    if (gp.n > 1 && sort_u64(gp.v, gp.n)) goto done;
    for (size_t i = 0; i < gp.n; i++)
        if (push64(&q, (uint64_t)F.root[gp.v[i] >> 32] << 32 | F.root[(uint32_t)gp.v[i]]))
            goto done;
    if (split_tasks(&F, &q, (size_t)A->threads * 64)) goto done;
    j.task = q.v;
    j.out = mem_calloc(q.n + 1, sizeof *j.out);
    j.stack = mem_calloc((size_t)A->threads, sizeof *j.stack);
    if (!j.out || !j.stack) goto done;
    par_for(A->threads, q.n, walk_task, &j);
    if (j.fail == 3) rc = -3;
    if (j.fail) goto done;
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
    free(T.node);
    free(T.item);
    free(F.g_off);
    free(F.root);
    free(F.node);
    free(F.item);
    free(F.srt);
    free(F.bx);
    return rc;
}
