/* arr3.c — the arrangement of solids (DESIGN's 3D pipeline; interface in arr3.h): the input,
 * the candidate pairs, the cuts, and the driver.  arr3_plane.c arranges each plane and
 * arr3_cells.c makes the 3-cells; arr3_int.h says what they share.
 *
 * The one tolerance is the grid: every input vertex is snapped once (llround(x / step), the
 * same rule solid_check uses), and from then on every decision is an exact predicate of
 * core/pred.h.  Nothing is rounded again until the result is written.
 *   input   faces whose snapped vertices lie exactly in one plane are pieces as they are; a face
 *           that is not exactly planar on the grid is split into triangles (ear clipping in its
 *           projection, exact orientation tests), each a piece with its own exact plane.  So no
 *           plane is ever chosen for a group of faces: coplanarity is equality of exact planes.
 *           stage_input runs in four steps over one state (inrun): input_count (box, counts,
 *           limits), input_snap (grid, vertices), input_pieces (a task of faces a thread:
 *           in_task, face by face in_face = in_triangle | in_cycles, then a piece or in_split),
 *           input_join (the runs in order, the check's twins).  A caller that checked the solids
 *           (arr3_opts.checked: the API) spares it the re-tests of coordinates and indices.
 *   pairs   a box-kd-tree of the pieces' boxes (closed boxes: touching counts) gives the pairs
 *           of pieces of different solids (in a soup: of different faces) in different planes.
 *   cuts    for each pair, the line where the two planes meet, and on it the part of each
 *           polygon (closed intervals, found from the exact sides of its vertices: crossings
 *           are LPIs, vertices on the line are themselves).  Their intersection is a set of
 *           closed intervals: each one of positive length is a cut, given to both planes; each
 *           single point is a contact point (a vertex resting on a face, edges crossing), also
 *           given to both planes.  So every contact between solids becomes part of the complex.
 *   points  the points made by the cuts are deduplicated by position (pset: a hash over grid
 *           cells, exact equality inside), keeping the simplest definition (a vertex before an
 *           LPI); each plane's new points are deduplicated again after the planes.
 *
 * Tools: util_seterr, uf_find/uf_union, u32_cmp of core/util.h and mem_grow of core/mem.h, as
 * in every core file.
 *
 * Threads: the cuts (in chunks of pairs), the planes and parts of the cells (arr3_cells.c) run
 * on par_for(); everything else runs on the calling thread.  Results do not depend on the
 * number of threads: the chunks' and the planes' outputs are merged in their order.
 */
#include "core/arr3_int.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "core/facecheck.h"
#include "core/mem.h"
#include "core/par.h"
#include "core/sort.h"
#include "core/util.h"

/* ------------------------------------------------------------------ shared tools */

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

#ifdef A3_PROF
void a3_prof(const char *name)
{
    static double last;
    double t = now_ms();
    if (name) fprintf(stderr, "  %-16s %7.1f ms\n", name, t - last);
    last = t;
}
#endif

uint64_t a3_mix64(uint64_t x)
{
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ULL;
    x ^= x >> 33;
    return x;
}

int a3_cancelled(const a3 *A)
{
    return A->o->cancel && atomic_load(A->o->cancel);
}

void a3_progress(const a3 *A, const char *stage, double f)
{
    if (A->o->progress) A->o->progress(A->o->udata, stage, f);
}

void a3_span_tick(void *span, double f)
{
    const a3_span *sp = span;
    a3_progress(sp->A, sp->stage, sp->lo + (sp->hi - sp->lo) * f);
}

size_t a3_solid_end(const a3 *A, size_t i)
{
    size_t lo = i + 1, hi = A->npc;
    uint32_t s = A->pc[i].solid;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (A->pc[mid].solid == s)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* ------------------------------------------------------------------ point sets */

/* PSET_R: a bound, with a factor 2 to spare, on how far apart two approximations (xpt.x) of one
 * exact point lie, coordinate by coordinate, in grid units.  A point is stored in the cell of
 * its approximation and searched in every cell within PSET_R of it; so equal points always meet.
 * Derivation.  Every point the pipeline makes lies in the input's box (a vertex; an LPI on a
 * piece's edge; a TPI where cuts cross inside a piece), and the box spans at most
 * 2^ARR3_GRID_BITS grid steps on each axis (arr3_grid_step), centred on the origin oi: every
 * coordinate has |x| <= 2^(ARR3_GRID_BITS - 1) + 1 < 2^ARR3_GRID_BITS.  An approximation is within
 * XPT_REL |x| of the exact coordinate (core/pred.h), so two approximations of one point are within
 * 2 XPT_REL 2^ARR3_GRID_BITS of each other; PSET_R is twice that (2^-18 with the grid's 30 bits
 * and XPT_REL = 2^-50). */
#define PSET_R (4 * XPT_REL * (double)(1u << ARR3_GRID_BITS))

static uint64_t cell_key(int64_t x, int64_t y, int64_t z)
{
    uint64_t k = a3_mix64((uint64_t)x * 0x9e3779b97f4a7c15ULL ^ a3_mix64((uint64_t)y + 0x51ed27) ^
                          ((uint64_t)z << 23 | (uint64_t)z >> 41));
    return k ? k : 1;
}

void pset_clear(pset *s, uint32_t base)
{
    if (a3_table_oversized(s->cap, s->n)) {
        free(s->key), free(s->head);
        s->key = NULL, s->head = NULL, s->cap = 0;
    } else if (s->key && s->n) {
        memset(s->key, 0, s->cap * sizeof *s->key);
    }
    s->n = 0;
    s->base = base;
}

void pset_free(pset *s)
{
    free(s->key);
    free(s->head);
    free(s->next);
    memset(s, 0, sizeof *s);
}

static size_t pset_slot(const pset *s, uint64_t k)
{
    size_t h = a3_mix64(k) & (s->cap - 1);
    while (s->key[h] && s->key[h] != k) h = (h + 1) & (s->cap - 1);
    return h;
}

static int pset_rehash(pset *s, size_t ncap)
{
    uint64_t *ok = s->key;
    uint32_t *oh = s->head;
    size_t ocap = s->cap;
    s->key = mem_calloc(ncap, sizeof *s->key);
    s->head = mem_malloc(ncap * sizeof *s->head);
    if (!s->key || !s->head) {
        free(s->key);
        free(s->head);
        s->key = ok, s->head = oh;
        return -1;
    }
    s->cap = ncap;
    for (size_t i = 0; i < ocap; i++)
        if (ok[i]) {
            size_t h = pset_slot(s, ok[i]);
            s->key[h] = ok[i];
            s->head[h] = oh[i];
        }
    free(ok);
    free(oh);
    return 0;
}

int pset_add(pset *s, const xpt *p, uint32_t id)
{
    if (2 * (s->n + 1) > s->cap && pset_rehash(s, s->cap ? 2 * s->cap : 256)) return -1;
    if (mem_grow(&s->next, &s->capnext, id - s->base + 1, sizeof *s->next)) return -1;
    uint64_t k =
        cell_key((int64_t)floor(p->x[0]), (int64_t)floor(p->x[1]), (int64_t)floor(p->x[2]));
    size_t h = pset_slot(s, k);
    if (!s->key[h]) {
        s->key[h] = k;
        s->head[h] = NONE;
        s->n++;
    }
    s->next[id - s->base] = s->head[h];
    s->head[h] = id;
    return 0;
}

uint32_t pset_find(const pset *s, const geo *G, const xpt *p, pset_get get, const void *ctx)
{
    int64_t lo[3], hi[3];
    if (!s->n) return NONE;
    for (int i = 0; i < 3; i++) {
        lo[i] = (int64_t)floor(p->x[i] - PSET_R);
        hi[i] = (int64_t)floor(p->x[i] + PSET_R);
    }
    for (int64_t x = lo[0]; x <= hi[0]; x++)
        for (int64_t y = lo[1]; y <= hi[1]; y++)
            for (int64_t z = lo[2]; z <= hi[2]; z++) {
                size_t h = pset_slot(s, cell_key(x, y, z));
                if (!s->key[h]) continue;
                for (uint32_t id = s->head[h]; id != NONE; id = s->next[id - s->base]) {
                    const xpt *q = get(ctx, id);
                    if (fabs(q->x[0] - p->x[0]) > PSET_R || fabs(q->x[1] - p->x[1]) > PSET_R ||
                        fabs(q->x[2] - p->x[2]) > PSET_R)
                        continue;
                    if (xpt_equal(G, p, q)) return id;
                }
            }
    return NONE;
}

/* ------------------------------------------------------------------ vertices, planes */

static uint64_t hash_g(const int64_t *x)
{
    return a3_mix64((uint64_t)x[0] * 0x9e3779b97f4a7c15ULL ^ a3_mix64((uint64_t)x[1] + 0x632be5ab) ^
                    ((uint64_t)x[2] << 21 | (uint64_t)x[2] >> 43));
}

static uint64_t hash_plane(const plane3 *p)
{
    uint64_t h = a3_mix64((uint64_t)p->n[0] ^ 0x243f6a8885a308d3ULL);
    h = a3_mix64(h ^ (uint64_t)p->n[1]);
    h = a3_mix64(h ^ (uint64_t)p->n[2]);
    h = a3_mix64(h ^ (uint64_t)p->d ^ (uint64_t)((u128)p->d >> 64));
    return h;
}

static int plane_same(const plane3 *a, const plane3 *b)
{
    return a->n[0] == b->n[0] && a->n[1] == b->n[1] && a->n[2] == b->n[2] && a->d == b->d;
}

static int pltab_rehash(a3 *A, size_t ncap)
{
    uint32_t *t = mem_malloc(ncap * sizeof *t);
    if (!t) return -1;
    memset(t, 0xff, ncap * sizeof *t);
    for (size_t i = 0; i < A->npl; i++) {
        size_t h = hash_plane(&A->pl[i]) & (ncap - 1);
        while (t[h] != NONE) h = (h + 1) & (ncap - 1);
        t[h] = (uint32_t)i;
    }
    free(A->pltab);
    A->pltab = t;
    A->plcap = ncap;
    return 0;
}

/* The id of plane p (made canonical here), added when new; NONE when out of memory. */
static uint32_t plane_id(a3 *A, plane3 *p)
{
    plane_canon(p);
    if (2 * (A->npl + 1) > A->plcap && pltab_rehash(A, A->plcap ? 2 * A->plcap : 1024)) return NONE;
    size_t h = hash_plane(p) & (A->plcap - 1);
    while (A->pltab[h] != NONE) {
        if (plane_same(&A->pl[A->pltab[h]], p)) return A->pltab[h];
        h = (h + 1) & (A->plcap - 1);
    }
    if (A3_PUSH(A->pl, A->npl, A->cappl, *p)) return NONE;
    A->pltab[h] = (uint32_t)(A->npl - 1);
    return (uint32_t)(A->npl - 1);
}

/* ------------------------------------------------------------------ input: pieces */

/* 2D coordinates of vertex v projected along axis k (right-handed: (k+1, k+2)). */
static void proj2(const a3 *A, uint32_t v, int k, int64_t *u)
{
    const int64_t *p = A->g + 3 * (size_t)v;
    u[0] = p[(k + 1) % 3];
    u[1] = p[(k + 2) % 3];
}

static i128 orient2v(const a3 *A, int k, uint32_t a, uint32_t b, uint32_t c)
{
    int64_t pa[2], pb[2], pc[2];
    proj2(A, a, k, pa);
    proj2(A, b, k, pb);
    proj2(A, c, k, pc);
    return (i128)(pb[0] - pa[0]) * (pc[1] - pa[1]) - (i128)(pb[1] - pa[1]) * (pc[0] - pa[0]);
}

/* Twice the signed area of a cycle in the projection along k. */
static i128 area2(const a3 *A, int k, const uint32_t *v, size_t n)
{
    i128 s = 0;
    for (size_t i = 0; i < n; i++) {
        int64_t p[2], q[2];
        proj2(A, v[i], k, p);
        proj2(A, v[(i + 1) % n], k, q);
        s += (i128)p[0] * q[1] - (i128)p[1] * q[0];
    }
    return s;
}

/* Is point x inside or on the closed triangle abc (abc counter-clockwise)? */
static int in_tri(const a3 *A, int k, uint32_t a, uint32_t b, uint32_t c, uint32_t x)
{
    return orient2v(A, k, a, b, x) >= 0 && orient2v(A, k, b, c, x) >= 0 &&
           orient2v(A, k, c, a, x) >= 0;
}

static int same_pos(uint32_t a, uint32_t b)
{
    return a == b; /* vertices are unique grid points */
}

/* Does the open segment pq meet the closed segment ab (projected along k)? */
static int seg_meets(const a3 *A, int k, uint32_t p, uint32_t q, uint32_t a, uint32_t b)
{
    i128 o1 = orient2v(A, k, p, q, a), o2 = orient2v(A, k, p, q, b);
    i128 o3 = orient2v(A, k, a, b, p), o4 = orient2v(A, k, a, b, q);
    if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
        return 1;
    /* an endpoint of ab on the open segment pq, or p/q on ab (touching counts) */
    int64_t P[2], Q[2], X[2];
    proj2(A, p, k, P);
    proj2(A, q, k, Q);
    for (int t = 0; t < 2; t++) {
        uint32_t x = t ? b : a;
        if ((t ? o2 : o1) != 0 || same_pos(x, p) || same_pos(x, q)) continue;
        proj2(A, x, k, X);
        if (X[0] >= (P[0] < Q[0] ? P[0] : Q[0]) && X[0] <= (P[0] < Q[0] ? Q[0] : P[0]) &&
            X[1] >= (P[1] < Q[1] ? P[1] : Q[1]) && X[1] <= (P[1] < Q[1] ? Q[1] : P[1]))
            return 1;
    }
    return 0;
}

/* Is direction d (from vertex p toward vertex m) strictly inside the wedge of a counter-
 * clockwise loop at p, between its next vertex nx and its previous vertex pv? */
static int in_wedge(const a3 *A, int k, uint32_t pv, uint32_t p, uint32_t nx, uint32_t m)
{
    i128 convex = orient2v(A, k, pv, p, nx);
    i128 a = orient2v(A, k, p, nx, m), b = orient2v(A, k, p, m, pv);
    if (convex > 0) return a > 0 && b > 0;
    return !(a <= 0 && b <= 0);
}

typedef struct ring {
    uint32_t *v;
    size_t n, cap;
} ring;

/* Where direction d lies, turning counter-clockwise from direction f (projected along k):
 * a class (0: along f, 1: left of it, 2: opposite, 3: right of it), then within a class the
 * order of two directions by their cross product. */
static int turn_class(const int64_t *f, const int64_t *d)
{
    i128 c = (i128)f[0] * d[1] - (i128)f[1] * d[0];
    i128 t = (i128)f[0] * d[0] + (i128)f[1] * d[1];
    return c > 0 ? 1 : c < 0 ? 3 : t > 0 ? 0 : 2;
}

/* Turning counter-clockwise from f, is d1 met before d2 (-1), after (1), or together (0)? */
static int turn_cmp(const int64_t *f, const int64_t *d1, const int64_t *d2)
{
    int c1 = turn_class(f, d1), c2 = turn_class(f, d2);
    if (c1 != c2) return c1 < c2 ? -1 : 1;
    if (c1 == 0 || c1 == 2) return 0;
    i128 x = (i128)d1[0] * d2[1] - (i128)d1[1] * d2[0];
    return x > 0 ? -1 : x < 0 ? 1 : 0;
}

/* Two passages of a counter-clockwise loop through vertex v, from a1 to b1 and from a2 to b2:
 * are their inner wedges (from the way out, counter-clockwise to the way in) apart, sharing at
 * most a side?  (A bridge's two passages are; a hole spliced in at one vertex and touching the
 * loop again at another is not, at that other vertex, until the loop is split there.) */
static int wedges_apart(const a3 *A, int k, uint32_t v, uint32_t a1, uint32_t b1, uint32_t a2,
                        uint32_t b2)
{
    int64_t pv[2], p[4][2], d[4][2];
    uint32_t w[4] = {a1, b1, a2, b2};
    proj2(A, v, k, pv);
    for (int i = 0; i < 4; i++) {
        proj2(A, w[i], k, p[i]);
        d[i][0] = p[i][0] - pv[0], d[i][1] = p[i][1] - pv[1];
    }
    /* counter-clockwise from a1's direction: b2 (the second way out), a2, then b1 */
    return turn_cmp(d[0], d[3], d[2]) <= 0 && turn_cmp(d[0], d[2], d[1]) <= 0 &&
           turn_class(d[0], d[1]) != 0;
}

/* Ear clipping of one loop L (counter-clockwise, a vertex possibly passed twice the right way,
 * as at a bridge); appends triangles.  0, -1 out of memory, -2 no ear left. */
static int clip_loop(const a3 *A, int k, ring *L, uint32_t **tri, size_t *ntri, size_t *captri)
{
    while (L->n > 3) {
        int cut = 0;
        for (size_t i = 0; i < L->n && !cut; i++) {
            uint32_t a = L->v[(i + L->n - 1) % L->n], b = L->v[i], c = L->v[(i + 1) % L->n];
            if (orient2v(A, k, a, b, c) <= 0) continue;
            int ear = 1;
            for (size_t j = 0; j < L->n && ear; j++) {
                uint32_t x = L->v[j];
                if (x == a || x == b || x == c) continue;
                if (in_tri(A, k, a, b, c, x)) ear = 0;
            }
            if (!ear) continue;
            if (mem_grow(tri, captri, 3 * (*ntri + 1), sizeof **tri)) return -1;
            (*tri)[3 * *ntri] = a, (*tri)[3 * *ntri + 1] = b, (*tri)[3 * *ntri + 2] = c;
            (*ntri)++;
            memmove(L->v + i, L->v + i + 1, (L->n - i - 1) * sizeof *L->v);
            L->n--;
            cut = 1;
            /* where the loop passes a vertex twice (a bridge), clipping a whole side leaves it
             * passing one vertex twice in a row, or going out and back along one edge: both
             * bound nothing and are dropped */
            for (size_t j = 0; L->n > 2 && j < L->n;) {
                size_t j1 = (j + 1) % L->n, j0 = (j + L->n - 1) % L->n;
                if (L->v[j] == L->v[j1]) {
                    memmove(L->v + j1, L->v + j1 + 1, (L->n - j1 - 1) * sizeof *L->v);
                    L->n--;
                    j = 0;
                } else if (L->v[j0] == L->v[j1]) { /* drop L->v[j] and L->v[j1] */
                    if (j1 == 0) {
                        memmove(L->v, L->v + 1, (L->n - 1) * sizeof *L->v);
                    } else {
                        memmove(L->v + j, L->v + j + 2, (L->n - j - 2) * sizeof *L->v);
                    }
                    L->n -= 2;
                    j = 0;
                } else {
                    j++;
                }
            }
        }
        if (!cut) return -2;
    }
    if (L->n == 3 && orient2v(A, k, L->v[0], L->v[1], L->v[2]) > 0) {
        if (mem_grow(tri, captri, 3 * (*ntri + 1), sizeof **tri)) return -1;
        memcpy(*tri + 3 * *ntri, L->v, 3 * sizeof *L->v);
        (*ntri)++;
    }
    return 0;
}

typedef struct vpos {
    uint32_t v, i;
} vpos;

static int vpos_cmp(const void *pa, const void *pb)
{
    const vpos *a = pa, *b = pb;
    if (a->v != b->v) return a->v < b->v ? -1 : 1;
    return (a->i > b->i) - (a->i < b->i);
}

/* The loop (holes bridged or spliced in) is split where it passes a vertex twice with wedges
 * that overlap (a hole touching it at more than one vertex, holes touching each other and it:
 * a face whose inside is in several parts): then each part is one loop, whose wedges at every
 * vertex it passes twice are apart.  Each part is then ear-clipped.  Takes L's array. */
static int split_and_clip(const a3 *A, int k, ring *L, uint32_t **tri, size_t *ntri, size_t *captri)
{
    ring *st = NULL;
    size_t nst = 0, capst = 0;
    vpos *vp = NULL;
    size_t capvp = 0;
    int rc = -1;
    if (A3_PUSH(st, nst, capst, *L)) goto done;
    memset(L, 0, sizeof *L);
    while (nst) {
        ring S = st[--nst];
        if (S.n < 3) {
            free(S.v);
            continue;
        }
        if (mem_grow(&vp, &capvp, S.n, sizeof *vp)) {
            free(S.v);
            goto done;
        }
        for (size_t i = 0; i < S.n; i++) vp[i] = (vpos){S.v[i], (uint32_t)i};
        qsort(vp, S.n, sizeof *vp, vpos_cmp);
        size_t sp = SIZE_MAX, sq = 0;
        for (size_t i = 0, j; i < S.n && sp == SIZE_MAX; i = j) {
            for (j = i + 1; j < S.n && vp[j].v == vp[i].v; j++) continue;
            for (size_t x = i; x < j && sp == SIZE_MAX; x++)
                for (size_t y = x + 1; y < j; y++) {
                    size_t p = vp[x].i, q = vp[y].i;
                    if (wedges_apart(A, k, S.v[p], S.v[(p + S.n - 1) % S.n], S.v[(p + 1) % S.n],
                                     S.v[(q + S.n - 1) % S.n], S.v[(q + 1) % S.n]))
                        continue;
                    sp = p, sq = q;
                    break;
                }
        }
        if (sp == SIZE_MAX) {
            int r = clip_loop(A, k, &S, tri, ntri, captri);
            free(S.v);
            if (r) {
                rc = r;
                goto done;
            }
            continue;
        }
        /* S = [.. sp: v, X .., sq: v, Y ..]: the parts [v, X ..] and [v, Y ..] */
        ring P = {0}, Q = {0};
        int bad = 0;
        for (size_t i = sp; i < sq && !bad; i++) bad = A3_PUSH(P.v, P.n, P.cap, S.v[i]);
        for (size_t i = sq; i < sp + S.n && !bad; i++) bad = A3_PUSH(Q.v, Q.n, Q.cap, S.v[i % S.n]);
        free(S.v);
        if (bad || mem_grow(&st, &capst, nst + 2, sizeof *st)) {
            free(P.v), free(Q.v);
            goto done;
        }
        st[nst++] = P;
        st[nst++] = Q;
    }
    rc = 0;
done:
    for (size_t i = 0; i < nst; i++) free(st[i].v);
    free(st);
    free(vp);
    return rc;
}

/* a3_triangulate's splice: the passage i of the loop L at a vertex of hole h (hn vertices,
 * walked backwards when flip) whose inner wedge holds the hole's edge from there; SIZE_MAX if
 * none.  *sb: that vertex's place in h. */
static size_t splice_at(const a3 *A, int k, const ring *L, const uint32_t *h, size_t hn, int flip,
                        size_t *sb)
{
    for (size_t t = 0; t < hn; t++)
        for (size_t i = 0; i < L->n; i++) {
            uint32_t hx = h[flip ? (t + hn - 1) % hn : (t + 1) % hn];
            if (L->v[i] == h[t] &&
                in_wedge(A, k, L->v[(i + L->n - 1) % L->n], L->v[i], L->v[(i + 1) % L->n], hx)) {
                *sb = t;
                return i;
            }
        }
    return SIZE_MAX;
}

/* a3_triangulate's bridge: the place i on the loop L of the nearest vertex p (in the projection)
 * that hole cyc[best]'s vertex m = cyc[best][bi] sees: p inside the loop's wedge and m's outer
 * wedge, the segment pm meeting no edge of the loop or of a hole not yet bridged (used).
 * SIZE_MAX if none. */
static size_t bridge_at(const a3 *A, int k, const ring *L, uint32_t **cyc, const size_t *len,
                        size_t nc, const uint8_t *used, size_t best, size_t bi, int flip)
{
    size_t hn = len[best], bp = SIZE_MAX;
    uint32_t m = cyc[best][bi];
    double bd = DBL_MAX;
    for (size_t i = 0; i < L->n; i++) {
        uint32_t p = L->v[i];
        int64_t a[2], b[2];
        proj2(A, p, k, a);
        proj2(A, m, k, b);
        double dd = (double)(a[0] - b[0]) * (double)(a[0] - b[0]) +
                    (double)(a[1] - b[1]) * (double)(a[1] - b[1]);
        if (dd >= bd || p == m) continue;
        if (!in_wedge(A, k, L->v[(i + L->n - 1) % L->n], p, L->v[(i + 1) % L->n], m)) continue;
        /* the hole's own wedge at m (the region outside the hole) */
        uint32_t hp = cyc[best][flip ? (bi + 1) % hn : (bi + hn - 1) % hn];
        uint32_t hx = cyc[best][flip ? (bi + hn - 1) % hn : (bi + 1) % hn];
        if (!in_wedge(A, k, hp, m, hx, p)) continue;
        int ok = 1;
        for (size_t j = 0; j < L->n && ok; j++) {
            uint32_t a0 = L->v[j], a1 = L->v[(j + 1) % L->n];
            if (a0 == p || a1 == p) continue;
            if (seg_meets(A, k, p, m, a0, a1)) ok = 0;
        }
        for (size_t c = 1; c < nc && ok; c++) {
            if (used[c] && c != best) continue;
            for (size_t j = 0; j < len[c] && ok; j++) {
                uint32_t a0 = cyc[c][j], a1 = cyc[c][(j + 1) % len[c]];
                if (a0 == m || a1 == m) continue;
                if (seg_meets(A, k, p, m, a0, a1)) ok = 0;
            }
        }
        if (ok) bd = dd, bp = i;
    }
    return bp;
}

/* a3_triangulate (arr3_int.h): holes are bridged into the outer loop (each from its vertex of
 * largest u to the nearest loop vertex it sees: no edge met, inside both wedges), or spliced in
 * at a vertex they share with it; the loop is split where it then passes a vertex twice the
 * wrong way (split_and_clip), and ears are cut; every test is an exact orientation on the
 * projected grid coordinates.  Takes polygons with holes whose cycles touch at shared vertices
 * (core/facecheck.h's), also where that cuts the inside in parts. */
int a3_triangulate(const a3 *A, int k, uint32_t **cyc, const size_t *len, size_t nc, uint32_t **tri,
                   size_t *ntri, size_t *captri)
{
    ring L = {0};
    int rc = -1;
    uint8_t *used = NULL;
    uint32_t *order = NULL;
    /* the outer loop counter-clockwise, holes clockwise */
    int flip_outer = area2(A, k, cyc[0], len[0]) < 0;
    for (size_t i = 0; i < len[0]; i++)
        if (A3_PUSH(L.v, L.n, L.cap, cyc[0][flip_outer ? len[0] - 1 - i : i])) goto done;
    if (nc > 1) {
        order = mem_malloc(nc * sizeof *order);
        used = mem_calloc(nc, 1);
        if (!order || !used) goto done;
    }
    for (size_t h = 1; h < nc; h++) {
        /* the remaining hole with the largest u (then v) vertex */
        size_t best = 0, bi = 0;
        int64_t bu[2] = {0, 0};
        for (size_t c = 1; c < nc; c++) {
            if (used[c]) continue;
            for (size_t i = 0; i < len[c]; i++) {
                int64_t u[2];
                proj2(A, cyc[c][i], k, u);
                if (!best || u[0] > bu[0] || (u[0] == bu[0] && u[1] > bu[1]))
                    best = c, bi = i, bu[0] = u[0], bu[1] = u[1];
            }
        }
        used[best] = 1;
        int flip = area2(A, k, cyc[best], len[best]) > 0;
        size_t hn = len[best];
        /* a hole touching the loop at a vertex they share is spliced in there (the loop then
         * passes that vertex twice, the hole in between); no bridge is needed, and none might
         * be found */
        size_t sb = 0, sp = splice_at(A, k, &L, cyc[best], hn, flip, &sb);
        if (sp != SIZE_MAX) {
            if (mem_grow(&L.v, &L.cap, L.n + hn, sizeof *L.v)) goto done;
            memmove(L.v + sp + 1 + hn, L.v + sp + 1, (L.n - sp - 1) * sizeof *L.v);
            for (size_t i = 1; i <= hn; i++)
                L.v[sp + i] = cyc[best][flip ? (sb + hn - i % hn) % hn : (sb + i) % hn];
            L.n += hn;
            continue;
        }
        size_t bp = bridge_at(A, k, &L, cyc, len, nc, used, best, bi, flip);
        if (bp == SIZE_MAX) {
            rc = -2;
            goto done;
        }
        /* loop: ..., P, M, (hole from M around), M, P, ... */
        size_t ins = hn + 2;
        if (mem_grow(&L.v, &L.cap, L.n + ins, sizeof *L.v)) goto done;
        memmove(L.v + bp + 1 + ins, L.v + bp + 1, (L.n - bp - 1) * sizeof *L.v);
        for (size_t i = 0; i <= hn; i++) {
            size_t j = flip ? (bi + hn - i % hn) % hn : (bi + i) % hn;
            L.v[bp + 1 + i] = cyc[best][j];
        }
        L.v[bp + 1 + hn + 1] = L.v[bp];
        L.n += ins;
    }
    /* the loop into parts where it passes a vertex twice the wrong way, then each part's ears */
    rc = split_and_clip(A, k, &L, tri, ntri, captri);
    goto done;
done:
    free(L.v);
    free(order);
    free(used);
    return rc;
}

/* The id of the vertical plane of edge (v, w) along axis k: each edge is shared by two pieces,
 * so the plane is made once per (edge, axis).  NONE - 1 when the edge is parallel to e_k. */
static uint32_t vertical_id(a3 *A, uint32_t v, uint32_t w, int k)
{
    uint32_t lo = v < w ? v : w, hi = v ^ w ^ lo;
    uint64_t key = ((uint64_t)lo << 32 | hi) * 3 + (uint64_t)k + 1;
    if (2 * (A->nvp + 1) > A->vpcap) {
        size_t ncap = A->vpcap ? 2 * A->vpcap : 4096;
        uint64_t *nk = mem_calloc(ncap, sizeof *nk);
        uint32_t *nv = mem_malloc(ncap * sizeof *nv);
        if (!nk || !nv) {
            free(nk), free(nv);
            return NONE;
        }
        for (size_t i = 0; i < A->vpcap; i++) {
            if (!A->vpkey[i]) continue;
            size_t h = a3_mix64(A->vpkey[i]) & (ncap - 1);
            while (nk[h]) h = (h + 1) & (ncap - 1);
            nk[h] = A->vpkey[i], nv[h] = A->vpval[i];
        }
        free(A->vpkey), free(A->vpval);
        A->vpkey = nk, A->vpval = nv, A->vpcap = ncap;
    }
    size_t h = a3_mix64(key) & (A->vpcap - 1);
    while (A->vpkey[h]) {
        if (A->vpkey[h] == key) return A->vpval[h];
        h = (h + 1) & (A->vpcap - 1);
    }
    plane3 vp;
    if (plane_vertical(A->g + 3 * (size_t)lo, A->g + 3 * (size_t)hi, k, &vp)) return NONE - 1;
    uint32_t id = plane_id(A, &vp);
    if (id == NONE) return NONE;
    A->vpkey[h] = key, A->vpval[h] = id, A->nvp++;
    return id;
}

/* The normal (q - p) x (r - p) of three grid points, exactly (each component below 2^62);
 * -1 when they are collinear. */
static int grid_normal(const int64_t *p, const int64_t *q, const int64_t *r, int64_t *n)
{
    int64_t u0 = q[0] - p[0], u1 = q[1] - p[1], u2 = q[2] - p[2];
    int64_t v0 = r[0] - p[0], v1 = r[1] - p[1], v2 = r[2] - p[2];
    n[0] = u1 * v2 - u2 * v1;
    n[1] = u2 * v0 - u0 * v2;
    n[2] = u0 * v1 - u1 * v0;
    return n[0] || n[1] || n[2] ? 0 : -1;
}

/* Index (0..2) of the largest |n_i| of a normal. */
static int normal_axis(const int64_t *n)
{
    int k = 0;
    for (int i = 1; i < 3; i++)
        if (llabs(n[i]) > llabs(n[k])) k = i;
    return k;
}

/* The exact plane of a face's vertices, when they lie in one: 0 (its raw plane in *p, through
 * the anchor vertices av), 1 when they do not, -1 when all are collinear. */
static int face_plane(const a3 *A, uint32_t **cyc, const size_t *len, size_t nc, plane3 *p,
                      uint32_t *av)
{
    uint32_t v0 = cyc[0][0], v1 = NONE, v2 = NONE;
    const int64_t *p0 = A->g + 3 * (size_t)v0;
    double best = -1;
    for (size_t i = 0; i < len[0]; i++) {
        const int64_t *q = A->g + 3 * (size_t)cyc[0][i];
        double d = 0;
        for (int a = 0; a < 3; a++) d += (double)(q[a] - p0[a]) * (double)(q[a] - p0[a]);
        if (d > best) best = d, v1 = cyc[0][i];
    }
    if (v1 == v0) return -1;
    const int64_t *p1 = A->g + 3 * (size_t)v1;
    best = 0;
    for (size_t c = 0; c < nc; c++)
        for (size_t i = 0; i < len[c]; i++) {
            const int64_t *q = A->g + 3 * (size_t)cyc[c][i];
            i128 u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
            i128 w[3] = {q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]};
            i128 n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                         u[0] * w[1] - u[1] * w[0]};
            double m = fabs((double)n[0]) + fabs((double)n[1]) + fabs((double)n[2]);
            if (m > best) best = m, v2 = cyc[c][i];
        }
    if (v2 == NONE) return -1;
    if (plane_through_raw(p0, p1, A->g + 3 * (size_t)v2, p)) return -1;
    av[0] = v0, av[1] = v1, av[2] = v2;
    for (size_t c = 0; c < nc; c++)
        for (size_t i = 0; i < len[c]; i++) {
            const int64_t *q = A->g + 3 * (size_t)cyc[c][i];
            i128 s = (i128)p->n[0] * q[0] + (i128)p->n[1] * q[1] + (i128)p->n[2] * q[2] + p->d;
            if (s) return 1;
        }
    return 0;
}

/* The dot product of the normals of triangles abc and def (grid vertices): |.| < 2^124. */
static i128 tri_dot(const a3 *A, uint32_t a, uint32_t b, uint32_t c, uint32_t d, uint32_t e,
                    uint32_t f)
{
    const int64_t *P[6] = {A->g + 3 * (size_t)a, A->g + 3 * (size_t)b, A->g + 3 * (size_t)c,
                           A->g + 3 * (size_t)d, A->g + 3 * (size_t)e, A->g + 3 * (size_t)f};
    i128 n[2][3];
    for (int t = 0; t < 2; t++) {
        const int64_t *p = P[3 * t], *q = P[3 * t + 1], *r = P[3 * t + 2];
        i128 u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
        i128 v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
        n[t][0] = u[1] * v[2] - u[2] * v[1];
        n[t][1] = u[2] * v[0] - u[0] * v[2];
        n[t][2] = u[0] * v[1] - u[1] * v[0];
    }
    return n[0][0] * n[1][0] + n[0][1] * n[1][1] + n[0][2] * n[1][2];
}

static int add_contact(a3 *A, uint32_t plane, uint32_t p);

/* Is grid point c strictly inside the segment from u to w? (exact; coordinates below 2^31) */
static int inside_segment(const a3 *A, uint32_t u, uint32_t c, uint32_t w)
{
    const int64_t *gu = A->g + 3 * (size_t)u, *gc = A->g + 3 * (size_t)c,
                  *gw = A->g + 3 * (size_t)w;
    int64_t d[3], e[3];
    for (int a = 0; a < 3; a++) d[a] = gw[a] - gu[a], e[a] = gc[a] - gu[a];
    if ((i128)d[1] * e[2] != (i128)d[2] * e[1] || (i128)d[2] * e[0] != (i128)d[0] * e[2] ||
        (i128)d[0] * e[1] != (i128)d[1] * e[0])
        return 0;
    i128 de = (i128)d[0] * e[0] + (i128)d[1] * e[1] + (i128)d[2] * e[2];
    i128 dd = (i128)d[0] * d[0] + (i128)d[1] * d[1] + (i128)d[2] * d[2];
    return de > 0 && de < dd;
}

/* A face of a solid left out because its vertices lie on one line on the grid (a sliver the
 * grid flattens, or one that was flat already) leaves its neighbours meeting along that line
 * with a vertex of one inside an edge of another.  Each such vertex becomes a contact point of
 * the plane of the piece whose edge it lies in, so the plane's arrangement splits that edge
 * there and the surface stays closed.  Pieces pc0 .. pc1 are the solid's; drop[0..n) the
 * vertices of its left-out faces (sorted here).  Returns -1 out of memory. */
static int mend_dropped(a3 *A, size_t pc0, size_t pc1, uint32_t *drop, size_t n)
{
    qsort(drop, n, sizeof *drop, u32_cmp);
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (!m || drop[i] != drop[m - 1]) drop[m++] = drop[i];
    uint8_t *in = mem_calloc(A->nv + 1, 1);
    if (!in) return -1;
    for (size_t i = 0; i < m; i++) in[drop[i]] = 1;
    int rc = 0;
    for (size_t pi = pc0; pi < pc1 && !rc; pi++) {
        const piece *pc = &A->pc[pi];
        for (uint32_t cy = pc->c0; cy < pc->c0 + pc->nc && !rc; cy++) {
            uint32_t o = A->pc_off[cy], len = A->pc_off[cy + 1] - o;
            for (uint32_t j = 0; j < len && !rc; j++) {
                uint32_t u = A->pcv[o + j], w = A->pcv[o + (j + 1) % len];
                if (!in[u] || !in[w]) continue;
                for (size_t i = 0; i < m && !rc; i++)
                    if (drop[i] != u && drop[i] != w && inside_segment(A, u, drop[i], w)) {
                        cpt x = {(uint32_t)pi, drop[i]}; /* given to its plane by stage_cuts */
                        rc = A3_PUSH(A->dcp, A->ndcp, A->capdcp, x);
                    }
            }
        }
    }
    free(in);
    return rc;
}

/* The pieces of a run of faces, made on a thread with their own numbering of cycles and
 * entries (stage_input joins the runs in order and shifts it). */
typedef struct pbuf {
    piece *pc;
    size_t npc, cappc;
    uint32_t *pc_off; /* start of each of its cycles, in its own entries */
    size_t npcyc, cappc_off;
    uint32_t *pcv;
    size_t npcv, cappcv;
    uint32_t *in; /* pairs (input entry of the solid, own entry) of the faces that went as they
                     are: where the check's pairing goes */
    size_t nin, capin;
    int lazy;       /* the nin pairs are (in0 + k, k), not written (in_pairs) */
    uint32_t in0;   /* the run's first input entry */
    uint32_t *drop; /* vertices of faces left out (mend_dropped) */
    size_t ndrop, capdrop;
    size_t split_faces;
    int direct; /* pc, pc_off and pcv are the run's own place in a3's arrays (its faces as they
                   are: cappc etc. the room there), not arrays of its own */
    int rc;     /* ARR_OK, or the run's first error (msg) */
    char msg[256];
    /* scratch */
    uint32_t *tv, **cyc, *inlo, *tri;
    size_t *len, captv, capcyc, capinlo, captri, caplen;
    A3_PAD;
} pbuf;

static void pbuf_free(pbuf *B)
{
    if (!B->direct) free(B->pc), free(B->pc_off), free(B->pcv);
    free(B->in), free(B->drop);
    free(B->tv), free(B->cyc), free(B->inlo), free(B->tri), free(B->len);
    memset(B, 0, sizeof *B);
}

/* A run writing in place (direct) that needs more room than its faces as they are (a face split
 * into triangles) goes on in arrays of its own, with what it wrote copied.  -1 out of memory. */
static int pbuf_own(pbuf *B)
{
    size_t cp = 2 * B->cappc + 16, cc = 2 * B->cappc_off + 16, ce = 2 * B->cappcv + 16;
    piece *pc = mem_malloc(cp * sizeof *pc);
    uint32_t *off = mem_malloc(cc * sizeof *off), *v = mem_malloc(ce * sizeof *v);
    if (!pc || !off || !v) {
        free(pc), free(off), free(v);
        return -1;
    }
    if (B->npc) memcpy(pc, B->pc, B->npc * sizeof *pc);
    if (B->npcyc) memcpy(off, B->pc_off, B->npcyc * sizeof *off);
    if (B->npcv) memcpy(v, B->pcv, B->npcv * sizeof *v);
    B->pc = pc, B->pc_off = off, B->pcv = v;
    B->cappc = cp, B->cappc_off = cc, B->cappcv = ce;
    B->direct = 0;
    return 0;
}

/* Room in B for one more piece of nc cycles and total entries: in place, its own arrays once
 * the run outgrows its place (pbuf_own).  -1 out of memory. */
static inline int pbuf_room(pbuf *B, size_t nc, size_t total)
{
    if (B->direct &&
        (B->npc + 1 > B->cappc || B->npcyc + nc > B->cappc_off || B->npcv + total > B->cappcv) &&
        pbuf_own(B))
        return -1;
    if (!B->direct && (mem_grow(&B->pc_off, &B->cappc_off, B->npcyc + nc + 1, sizeof *B->pc_off) ||
                       mem_grow(&B->pcv, &B->cappcv, B->npcv + total, sizeof *B->pcv)))
        return -1;
    return 0;
}

/* Appends piece P (its cycles written, pbuf_room's room).  -1 out of memory. */
static inline int pbuf_push(pbuf *B, const piece *P)
{
    if (B->direct) {
        B->pc[B->npc++] = *P; /* room checked by pbuf_room */
        return 0;
    }
    return A3_PUSH(B->pc, B->npc, B->cappc, *P);
}

/* Adds a piece with the given cycles (vertex lists), anchor vertices av (their raw plane's
 * normal has its largest component on axis k) and orientation sgn about that plane; the
 * vertical planes of its edges are left to stage_sides, its canonical plane to whoever needs
 * it (piece_plane_id).  -1 out of memory, -2 an edge along axis k (not in the plane). */
static int add_piece(const a3 *A, pbuf *B, uint32_t solid, uint32_t face, const uint32_t *av,
                     const int64_t *n, int sgn, uint32_t **cyc, const size_t *len, size_t nc)
{
    piece P = {solid,
               face,
               NONE,
               (uint32_t)B->npcyc,
               (uint32_t)nc,
               {av[0], av[1], av[2]},
               {INT32_MAX, INT32_MAX, INT32_MAX, INT32_MIN, INT32_MIN, INT32_MIN},
               (int8_t)sgn,
               nc > 1,
               0,
               0,
               {0}};
    int k = normal_axis(n);
    P.cls = a3_chart_class(n, sgn, &P.cmask);
    size_t total = 0;
    for (size_t c = 0; c < nc; c++) total += len[c];
    if (pbuf_room(B, nc, total)) return -1;
    int k1 = k == 2 ? 0 : k + 1, k2 = k == 0 ? 2 : k - 1;
    for (size_t c = 0; c < nc; c++) {
        B->pc_off[B->npcyc++] = (uint32_t)B->npcv;
        for (size_t i = 0; i < len[c]; i++) {
            uint32_t v = cyc[c][i], w = cyc[c][i + 1 < len[c] ? i + 1 : 0];
            const int64_t *gv = A->g + 3 * (size_t)v, *gw = A->g + 3 * (size_t)w;
            if (gv[k1] == gw[k1] && gv[k2] == gw[k2]) return -2;
            B->pcv[B->npcv++] = v;
            for (int a = 0; a < 3; a++) {
                int32_t x = (int32_t)gv[a];
                if (x < P.box[a]) P.box[a] = x;
                if (x > P.box[3 + a]) P.box[3 + a] = x;
            }
        }
    }
    return pbuf_push(B, &P);
}

/* add_piece's work for a triangle of three points apart, not flat: none of its edges is a
 * point in the projection along its normal's axis (the normal would lie in that plane), so
 * add_piece's test has nothing to find. */
static int add_tri(const a3 *A, pbuf *B, uint32_t solid, uint32_t face, const uint32_t *t,
                   const int64_t *n)
{
    if (pbuf_room(B, 1, 3)) return -1;
    const int64_t *g0 = A->g + 3 * (size_t)t[0], *g1 = A->g + 3 * (size_t)t[1],
                  *g2 = A->g + 3 * (size_t)t[2];
    piece P = {solid, face, NONE, (uint32_t)B->npcyc, 1, {t[0], t[1], t[2]}, {0}, 1, 0, 0, 0, {0}};
    P.cls = a3_chart_class(n, 1, &P.cmask);
    for (int a = 0; a < 3; a++) {
        int32_t x = (int32_t)g0[a], y = (int32_t)g1[a], z = (int32_t)g2[a];
        int32_t lo = x < y ? x : y, hi = x < y ? y : x;
        P.box[a] = lo < z ? lo : z;
        P.box[3 + a] = hi > z ? hi : z;
    }
    B->pc_off[B->npcyc++] = (uint32_t)B->npcv;
    memcpy(B->pcv + B->npcv, t, 3 * sizeof *t);
    B->npcv += 3;
    return pbuf_push(B, &P);
}

/* A run of faces of one solid: stage_input's tasks. */
typedef struct intask {
    uint32_t s, f0, f1; /* solid, faces f0 .. f1 */
} intask;

typedef struct injob {
    const a3 *A;
    const solid *solids;
    const uint32_t *vmap; /* by input vertex of all solids (voff): its vertex */
    const size_t *voff;
    const intask *task;
    pbuf *buf;           /* by task */
    const size_t *place; /* by task: its first piece, cycle and entry in a3's arrays were every
                            face as it is (3 a task, and the totals after the last) */
} injob;

#define IN_CHUNK 16384 /* faces a task */

/* Records the pairs (input entry in + t, own entry base + t), t < n, of a cycle that went as
 * it is.  While every entry so far did, in order, the pairs stay implicit ((in0 + k, k): the
 * usual run writes none); the first that breaks the order writes them out.  -1 out of
 * memory. */
static inline int in_pairs(pbuf *B, uint32_t in, uint32_t base, uint32_t n)
{
    if (B->lazy && B->nin == base && in - B->in0 == base) {
        B->nin += n;
        return 0;
    }
    if (mem_grow(&B->in, &B->capin, 2 * (B->nin + n), sizeof *B->in)) return -1;
    if (B->lazy) {
        B->lazy = 0;
        for (size_t k = 0; k < B->nin; k++)
            B->in[2 * k] = B->in0 + (uint32_t)k, B->in[2 * k + 1] = (uint32_t)k;
    }
    for (uint32_t t = 0; t < n; t++) B->in[2 * B->nin] = in + t, B->in[2 * B->nin++ + 1] = base + t;
    return 0;
}

/* Records a task's error in its pbuf (a task stops at its first) and is -1: `return IN_FAIL(B,
 * ARR_EINVAL, "...", ...)` in the stages of in_task below. */
#define IN_FAIL(B, code, ...)                                                                      \
    ((B)->rc = util_seterr((B)->msg, sizeof(B)->msg, code, __VA_ARGS__), -1)
#define IN_OOM(B) IN_FAIL(B, ARR_ENOMEM, "%s", "out of memory")

/* in_face's first case: face f of solid s (so, its vertices mapped by map) a single cycle of
 * three entries, three points apart and not flat on the grid: a piece as it is, its entries
 * paired.  1 done, 0 not such a face (in_face goes on), -1 out of memory (B->rc). */
static int in_triangle(const a3 *A, pbuf *B, const solid *so, const uint32_t *map, size_t s,
                       size_t f)
{
    uint32_t face = A->solid_face_off[s] + (uint32_t)f;
    uint32_t i0 = so->cyc_off[so->face_off[f]];
    if (so->cyc_off[so->face_off[f] + 1] - i0 != 3 || so->cyc[i0] >= so->nv ||
        so->cyc[i0 + 1] >= so->nv || so->cyc[i0 + 2] >= so->nv)
        return 0;
    uint32_t t[3] = {map[so->cyc[i0]], map[so->cyc[i0 + 1]], map[so->cyc[i0 + 2]]};
    int64_t n[3];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0] ||
        grid_normal(A->g + 3 * (size_t)t[0], A->g + 3 * (size_t)t[1], A->g + 3 * (size_t)t[2], n))
        return 0;
    uint32_t base = (uint32_t)B->npcv;
    if (add_tri(A, B, A->soup ? face : (uint32_t)s, face, t, n) || in_pairs(B, i0, base, 3))
        return IN_OOM(B);
    return 1;
}

/* The cycles of face f on the grid, into B's scratch: each cycle's vertices without repeats
 * (B->cyc[c], B->len[c], c < *nc), with its first input entry in B->inlo[c] when every entry went
 * as it is (else NONE).  *nc is 0 when the face is left out (a soup's face that vanishes, a face
 * of two points whose edges are its neighbours').  The vertex indices are checked unless the
 * caller said the input is checked (arr3_opts.checked).  0, or -1 (B->rc). */
static int in_cycles(const a3 *A, pbuf *B, const solid *so, const uint32_t *map, size_t s, size_t f,
                     size_t *nc)
{
    size_t ncy = so->face_off[f + 1] - so->face_off[f], ntv = 0, k = 0;
    size_t total = so->cyc_off[so->face_off[f + 1]] - so->cyc_off[so->face_off[f]];
    int checked = A->o->checked;
    *nc = 0;
    if (mem_grow(&B->cyc, &B->capcyc, ncy + 1, sizeof *B->cyc) ||
        mem_grow(&B->len, &B->caplen, ncy + 1, sizeof *B->len) ||
        mem_grow(&B->inlo, &B->capinlo, ncy + 1, sizeof *B->inlo) ||
        mem_grow(&B->tv, &B->captv, total + 1, sizeof *B->tv))
        return IN_OOM(B);
    uint32_t *tv = B->tv;
    for (uint32_t cy = so->face_off[f]; cy < so->face_off[f + 1]; cy++) {
        size_t start = ntv;
        for (uint32_t i = so->cyc_off[cy]; i < so->cyc_off[cy + 1]; i++) {
            uint32_t vi = so->cyc[i];
            if (!checked && vi >= so->nv)
                return IN_FAIL(B, ARR_EINVAL, "solids[%zu]: face %zu: vertex index %u out of range",
                               s, f, vi);
            uint32_t v = map[vi];
            if (ntv > start && tv[ntv - 1] == v) continue;
            tv[ntv++] = v;
        }
        while (ntv - start > 1 && tv[ntv - 1] == tv[start]) ntv--;
        if (ntv - start < 3) {
            if (A->soup && cy == so->face_off[f]) return 0; /* a soup face may vanish */
            if (A->soup) {
                ntv = start;
                continue;
            }
            /* a face of two points on the grid: its edges are its neighbours' edges between the
             * same two points; left out */
            if (cy == so->face_off[f] && ncy == 1) return 0;
            return IN_FAIL(B, ARR_EINVAL,
                           "solids[%zu]: face %zu: fewer than 3 distinct vertices on the grid of "
                           "step %g",
                           s, f, A->step);
        }
        /* its input entries, when they all went as they are */
        B->inlo[k] = ntv - start == so->cyc_off[cy + 1] - so->cyc_off[cy] ? so->cyc_off[cy] : NONE;
        B->len[k++] = ntv - start;
    }
    for (size_t c = 0, off = 0; c < k; off += B->len[c], c++) B->cyc[c] = tv + off;
    *nc = k;
    return 0;
}

/* in_face's last case: a face of nc cycles (in B's scratch) not planar on the grid, split into
 * triangles (a quad by the better diagonal, else a3_triangulate), each a piece with its own exact
 * plane; a triangle collinear in space is left out, its vertices to mend_dropped.  0, or -1
 * (B->rc). */
static int in_split(const a3 *A, pbuf *B, uint32_t sol, size_t s, size_t f, size_t nc)
{
    uint32_t face = A->solid_face_off[s] + (uint32_t)f, **cyc = B->cyc;
    const size_t *len = B->len;
    int k = face_newell_axis(A->g, cyc[0], len[0]); /* as solid_check's */
    size_t ntri = 0;
    int r;
    int quad = nc == 1 && len[0] == 4;
    if (quad) {
        /* a quad: the diagonal whose two triangles' normals agree best (the larger dot product
         * of their normals), as CGAL's triangulate_faces chooses.  Both keep the quad's order,
         * whatever its projection looks like: two triangles in different planes (no three of
         * the four points are on one line) that share the diagonal, walked once each way */
        if (mem_grow(&B->tri, &B->captri, 6, sizeof *B->tri)) return IN_OOM(B);
        const uint32_t *q = cyc[0];
        i128 d02 = tri_dot(A, q[0], q[1], q[2], q[2], q[3], q[0]);
        i128 d13 = tri_dot(A, q[1], q[2], q[3], q[3], q[0], q[1]);
        int a = d02 > d13 ? 0 : 1;
        uint32_t t[6] = {q[a], q[a + 1], q[a + 2], q[a + 2], q[(a + 3) % 4], q[a]};
        memcpy(B->tri, t, sizeof t);
        ntri = 2;
        r = 0;
    } else {
        r = a3_triangulate(A, k, cyc, len, nc, &B->tri, &ntri, &B->captri);
    }
    if (r == -1) return IN_OOM(B);
    if (r == -2 || ntri == 0)
        return IN_FAIL(B, ARR_EINVAL,
                       "solids[%zu]: face %zu: not planar on the grid of step %g, and its "
                       "projection is not a simple polygon to split into triangles",
                       s, f, A->step);
    B->split_faces++;
    /* a3_triangulate's triangles come counter-clockwise in the projection: turned as the face's
     * outer cycle turns there */
    int ccw = quad || area2(A, k, cyc[0], len[0]) > 0;
    for (size_t t = 0; t < ntri; t++) {
        uint32_t *tc = B->tri + 3 * t;
        if (!ccw) {
            uint32_t x = tc[1];
            tc[1] = tc[2], tc[2] = x;
        }
        size_t tl = 3;
        plane3 tp;
        if (grid_normal(A->g + 3 * (size_t)tc[0], A->g + 3 * (size_t)tc[1],
                        A->g + 3 * (size_t)tc[2], tp.n)) {
            /* collinear in space: no surface, but its middle vertex may lie inside an edge of
             * a neighbour (mend_dropped) */
            if (!A->soup)
                for (int q = 0; q < 3; q++)
                    if (A3_PUSH(B->drop, B->ndrop, B->capdrop, tc[q])) return IN_OOM(B);
            continue;
        }
        if ((r = add_piece(A, B, sol, face, tc, tp.n, 1, &tc, &tl, 1)))
            return r == -1 ? IN_OOM(B)
                           : IN_FAIL(B, ARR_EINTERNAL, "solids[%zu]: face %zu: bad plane", s, f);
    }
    return 0;
}

/* Face f of solid s into B: a triangle as it is (in_triangle); else its cycles (in_cycles), and
 * a face whose vertices lie in one plane on the grid a piece as it is (its entries recorded for
 * the check's pairing when none was dropped), one all on a line left out (its vertices to
 * mend_dropped), one that is not planar split into triangles (in_split).  0, or -1 (B->rc). */
static int in_face(const a3 *A, pbuf *B, const solid *so, const uint32_t *map, size_t s, size_t f)
{
    uint32_t face = A->solid_face_off[s] + (uint32_t)f;
    size_t nc;
    if (so->face_off[f + 1] - so->face_off[f] == 1) {
        int r = in_triangle(A, B, so, map, s, f);
        if (r) return r < 0 ? -1 : 0;
    }
    if (in_cycles(A, B, so, map, s, f, &nc)) return -1;
    if (nc == 0) return 0;
    uint32_t **cyc = B->cyc, *inlo = B->inlo;
    const size_t *len = B->len;
    plane3 p;
    uint32_t sol = A->soup ? face : (uint32_t)s, av[3];
    int planar;
    if (nc == 1 && len[0] == 3) { /* a triangle: planar, or flat */
        planar = grid_normal(A->g + 3 * (size_t)cyc[0][0], A->g + 3 * (size_t)cyc[0][1],
                             A->g + 3 * (size_t)cyc[0][2], p.n);
        memcpy(av, cyc[0], sizeof av);
    } else {
        planar = face_plane(A, cyc, len, nc, &p, av);
    }
    if (planar < 0) {
        if (A->soup) return 0;
        if (nc > 1)
            return IN_FAIL(B, ARR_EINVAL,
                           "solids[%zu]: face %zu: zero area on the grid of step %g (a face with "
                           "holes whose vertices lie on one line)",
                           s, f, A->step);
        /* all on one line: left out; where its vertices lie inside its neighbours' edges, those
         * edges are split there (mend_dropped) */
        for (size_t i = 0; i < len[0]; i++)
            if (A3_PUSH(B->drop, B->ndrop, B->capdrop, cyc[0][i])) return IN_OOM(B);
        return 0;
    }
    if (planar > 0) return in_split(A, B, sol, s, f, nc);
    int k = normal_axis(p.n), r;
    int sgn =
        nc == 1 && len[0] == 3 ? 1 : ((area2(A, k, cyc[0], len[0]) > 0) == (p.n[k] > 0) ? 1 : -1);
    uint32_t base = (uint32_t)B->npcv;
    if ((r = add_piece(A, B, sol, face, av, p.n, sgn, cyc, len, nc)))
        return r == -1 ? IN_OOM(B)
                       : IN_FAIL(B, ARR_EINTERNAL, "solids[%zu]: face %zu: bad plane", s, f);
    for (size_t c = 0; c < nc; base += (uint32_t)len[c], c++)
        if (inlo[c] != NONE && in_pairs(B, inlo[c], base, (uint32_t)len[c])) return IN_OOM(B);
    return 0;
}

/* The faces of one task into its pbuf (in_face, face by face), written in place in a3's arrays
 * while they go as they are; the first error stops the task (B->rc). */
static void in_task(void *ctx, size_t item, int worker)
{
    (void)worker;
    const injob *j = ctx;
    const a3 *A = j->A;
    const intask *T = &j->task[item];
    const solid *so = &j->solids[T->s];
    const uint32_t *map = j->vmap + j->voff[T->s];
    pbuf *B = &j->buf[item];
    { /* room for the run's faces as they are (a face split into triangles grows them) */
        size_t ncy = so->face_off[T->f1] - so->face_off[T->f0];
        size_t nent = so->cyc_off[so->face_off[T->f1]] - so->cyc_off[so->face_off[T->f0]];
        /* in place: no copy to make, no second array to fault in (pbuf_own if it needs more) */
        const size_t *at = j->place + 3 * item;
        B->direct = 1;
        B->pc = A->pc + at[0], B->cappc = T->f1 - T->f0;
        B->pc_off = A->pc_off + at[1], B->cappc_off = ncy;
        B->pcv = A->pcv + at[2], B->cappcv = nent;
        /* while every entry goes as it is, in order, the pairs are implicit */
        B->lazy = 1;
        B->in0 = so->cyc_off[so->face_off[T->f0]];
    }
    for (size_t f = T->f0; f < T->f1; f++)
        if (in_face(A, B, so, map, T->s, f)) return;
}

/* The grid points of a chunk of the input's vertices. */
typedef struct snapjob {
    const a3 *A;
    const solid *solids;
    const size_t *voff;
    size_t ns, nv;
    int64_t *g; /* 3 by input vertex of all solids */
} snapjob;

#define SNAP_CHUNK 65536
static void snap_chunk(void *ctx, size_t item, int worker)
{
    (void)worker;
    const snapjob *j = ctx;
    size_t i0 = item * SNAP_CHUNK, i1 = i0 + SNAP_CHUNK < j->nv ? i0 + SNAP_CHUNK : j->nv, s = 0;
    while (s + 1 < j->ns && j->voff[s + 1] <= i0) s++;
    for (size_t i = i0; i < i1; i++) {
        while (j->voff[s + 1] <= i) s++;
        const double *x = j->solids[s].V + 3 * (i - j->voff[s]);
        for (int a = 0; a < 3; a++)
            j->g[3 * i + a] = round_half_away(x[a] / j->A->step) - j->A->oi[a];
    }
}

/* The points of a chunk of the vertices: point v is vertex v. */
static void grid_points(void *ctx, size_t item, int worker)
{
    (void)worker;
    a3 *A = ctx;
    size_t i1 = (item + 1) * SNAP_CHUNK < A->nv ? (item + 1) * SNAP_CHUNK : A->nv;
    for (size_t v = item * SNAP_CHUNK; v < i1; v++) A->pt[v] = xpt_grid(&A->G, (uint32_t)v);
}

/* The pieces' twins from the check's pairings (twins[s], by input entry of solid s). */
typedef struct twinjob {
    a3 *A;
    const uint32_t *const *twins;
    const uint32_t *in2pcv; /* by input entry of all solids (eoff) */
    const size_t *eoff;
    size_t ns, ne;
} twinjob;

static void twin_chunk(void *ctx, size_t item, int worker)
{
    (void)worker;
    const twinjob *j = ctx;
    size_t i0 = item * SNAP_CHUNK, i1 = i0 + SNAP_CHUNK < j->ne ? i0 + SNAP_CHUNK : j->ne, s = 0;
    while (s + 1 < j->ns && j->eoff[s + 1] <= i0) s++;
    for (size_t i = i0; i < i1; i++) {
        while (j->eoff[s + 1] <= i) s++;
        const uint32_t *tw = j->twins[s];
        uint32_t x = j->in2pcv[i];
        if (!tw || x == NONE || !j->A->twinned[s]) continue;
        size_t sent = j->eoff[s + 1] - j->eoff[s];
        uint32_t t = tw[i - j->eoff[s]];
        if (t != NONE && t < sent && j->in2pcv[j->eoff[s] + t] != NONE)
            j->A->ptwin[x] = j->in2pcv[j->eoff[s] + t];
    }
}

/* ---- equal items, on the threads -------------------------------------------------------- */

/* first[i] = the first item equal to item i (i itself when none before it is), for items
 * 0 .. n-1 with hashes hash[] (equal items have equal hashes; eq decides among those).  The
 * items go to FI_PARTS parts by their hash (a stable counting sort, on the threads by chunks)
 * and each part finds its firsts with a table of its own, on the threads: the result does not
 * depend on the threads.  -1 out of memory. */
#define FI_PARTS 256
#define FI_CHUNK 65536
typedef struct fijob {
    size_t n, nchunk;
    const uint64_t *hash;
    a3_eq_fn eq;
    const void *ctx;
    uint32_t *cnt;  /* [chunk][part]: counts, then where the chunk's items of the part go */
    uint32_t *idx;  /* the items by part, in order within each */
    uint32_t *poff; /* FI_PARTS + 1 */
    uint32_t *first;
    int rc;
} fijob;

static void fi_count(void *ctx, size_t item, int worker)
{
    (void)worker;
    fijob *j = ctx;
    size_t i0 = item * FI_CHUNK, i1 = i0 + FI_CHUNK < j->n ? i0 + FI_CHUNK : j->n;
    uint32_t *cnt = j->cnt + item * FI_PARTS;
    for (size_t i = i0; i < i1; i++) cnt[j->hash[i] >> 56]++;
}

static void fi_scatter(void *ctx, size_t item, int worker)
{
    (void)worker;
    fijob *j = ctx;
    size_t i0 = item * FI_CHUNK, i1 = i0 + FI_CHUNK < j->n ? i0 + FI_CHUNK : j->n;
    uint32_t *at = j->cnt + item * FI_PARTS;
    for (size_t i = i0; i < i1; i++) j->idx[at[j->hash[i] >> 56]++] = (uint32_t)i;
}

static void fi_part(void *ctx, size_t item, int worker)
{
    (void)worker;
    fijob *j = ctx;
    uint32_t lo = j->poff[item], hi = j->poff[item + 1];
    size_t cap = 16;
    while (cap < 2 * (size_t)(hi - lo)) cap *= 2;
    uint32_t *t = mem_malloc(cap * sizeof *t);
    if (!t) {
        j->rc = -1; /* the same value, whichever worker writes it */
        return;
    }
    memset(t, 0xff, cap * sizeof *t);
    for (uint32_t k = lo; k < hi; k++) {
        uint32_t i = j->idx[k];
        uint64_t h = j->hash[i];
        for (size_t s = h & (cap - 1);; s = (s + 1) & (cap - 1)) {
            uint32_t q = t[s];
            if (q == NONE) {
                t[s] = j->first[i] = i;
                break;
            }
            if (j->hash[q] == h && j->eq(j->ctx, q, i)) {
                j->first[i] = q;
                break;
            }
        }
    }
    free(t);
}

int a3_firsts(int threads, size_t n, const uint64_t *hash, a3_eq_fn eq, const void *ctx,
              uint32_t *first)
{
    fijob j = {n, (n + FI_CHUNK - 1) / FI_CHUNK, hash, eq, ctx, NULL, NULL, NULL, first, 0};
    int rc = -1;
    j.cnt = mem_calloc(j.nchunk * FI_PARTS + 1, sizeof *j.cnt);
    j.idx = mem_malloc((n + 1) * sizeof *j.idx);
    j.poff = mem_malloc((FI_PARTS + 1) * sizeof *j.poff);
    if (!j.cnt || !j.idx || !j.poff) goto done;
    par_for(threads, j.nchunk, fi_count, &j);
    uint32_t at = 0; /* parts in order, each part's chunks in order */
    for (size_t p = 0; p < FI_PARTS; p++) {
        j.poff[p] = at;
        for (size_t c = 0; c < j.nchunk; c++) {
            uint32_t k = j.cnt[c * FI_PARTS + p];
            j.cnt[c * FI_PARTS + p] = at;
            at += k;
        }
    }
    j.poff[FI_PARTS] = at;
    par_for(threads, j.nchunk, fi_scatter, &j);
    par_for(threads, FI_PARTS, fi_part, &j);
    rc = j.rc;
done:
    free(j.cnt), free(j.idx), free(j.poff);
    return rc;
}

/* One vertex per grid point, numbered in the input's order (the first input vertex on a point
 * makes it). */
static int grid_eq(const void *ctx, uint32_t a, uint32_t b)
{
    const int64_t *x = (const int64_t *)ctx + 3 * (size_t)a,
                  *y = (const int64_t *)ctx + 3 * (size_t)b;
    return x[0] == y[0] && x[1] == y[1] && x[2] == y[2];
}

typedef struct ghjob {
    const int64_t *g;
    uint64_t *hash;
    size_t n;
} ghjob;

static void grid_hashes(void *ctx, size_t item, int worker)
{
    (void)worker;
    const ghjob *j = ctx;
    size_t i1 = (item + 1) * FI_CHUNK < j->n ? (item + 1) * FI_CHUNK : j->n;
    for (size_t i = item * FI_CHUNK; i < i1; i++) j->hash[i] = hash_g(j->g + 3 * i);
}

/* A->g, A->nv and vmap (by input vertex: its vertex) from the input's grid points g. */
static int dedup_vertices(a3 *A, const int64_t *g, size_t n, uint32_t *vmap)
{
    int rc = -1;
    uint64_t *hash = mem_malloc((n + 1) * sizeof *hash);
    uint32_t *first = mem_malloc((n + 1) * sizeof *first);
    if (!hash || !first) goto done;
    ghjob hj = {g, hash, n};
    par_for(A->threads, (n + FI_CHUNK - 1) / FI_CHUNK, grid_hashes, &hj);
    if (a3_firsts(A->threads, n, hash, grid_eq, g, first)) goto done;
    size_t nv = 0;
    for (size_t i = 0; i < n; i++) nv += first[i] == i;
    if (nv > 0x7fffffffu || mem_grow(&A->g, &A->capv, 3 * nv + 3, sizeof *A->g)) goto done;
    for (size_t i = 0; i < n; i++) {
        uint32_t f = first[i];
        if (f == i) {
            memcpy(A->g + 3 * A->nv, g + 3 * i, 3 * sizeof *g);
            vmap[i] = (uint32_t)A->nv++;
        } else {
            vmap[i] = vmap[f];
        }
    }
    rc = 0;
done:
    free(hash), free(first);
    return rc;
}

/* The runs' pieces joined in order, each run on a thread at its offsets (at[3 t ..]: its first
 * piece, cycle and entry). */
typedef struct joinjob {
    a3 *A;
    pbuf *buf;
    const intask *task;
    const size_t *at, *eoff;
    const uint32_t *const *twins;
    uint32_t *in2pcv;
    int inplace; /* every run wrote in place, where the join puts it: only numbers to shift */
    const uint8_t *ident; /* by solid: its entries are its input entries (every face as it is,
                             in place): the check's twins are the pieces' own, shifted */
} joinjob;

static void join_task(void *ctx, size_t t, int worker)
{
    (void)worker;
    const joinjob *j = ctx;
    a3 *A = j->A;
    pbuf *B = &j->buf[t];
    size_t s = j->task[t].s, pc0 = j->at[3 * t];
    uint32_t cyc0 = (uint32_t)j->at[3 * t + 1], ent0 = (uint32_t)j->at[3 * t + 2];
    if (j->inplace) {
        for (size_t i = 0; i < B->npc; i++) A->pc[pc0 + i].c0 += cyc0;
        for (size_t c = 0; c < B->npcyc; c++) A->pc_off[cyc0 + c] += ent0;
    } else {
        for (size_t i = 0; i < B->npc; i++) {
            piece P = B->pc[i];
            P.c0 += cyc0;
            A->pc[pc0 + i] = P;
        }
        for (size_t c = 0; c < B->npcyc; c++) A->pc_off[cyc0 + c] = B->pc_off[c] + ent0;
        if (B->npcv) memcpy(A->pcv + ent0, B->pcv, B->npcv * sizeof *A->pcv);
    }
    for (size_t i = 0; i < B->npcv; i++) A->pcvp[ent0 + i] = SIDE_LAZY;
    if (j->ident[s]) {
        const uint32_t *tw = j->twins[s];
        size_t e0 = j->eoff[s], sent = j->eoff[s + 1] - e0;
        for (size_t i = 0; i < B->npcv; i++) {
            uint32_t x = tw[ent0 + i - e0];
            A->ptwin[ent0 + i] = x < sent ? (uint32_t)(e0 + x) : NONE;
        }
    } else {
        for (size_t i = 0; i < B->npcv; i++) A->ptwin[ent0 + i] = NONE;
    }
    for (size_t i = 0; j->in2pcv && j->twins[s] && !j->ident[s] && i < B->nin; i++)
        if (B->lazy) /* the pairs in_task kept implicit */
            j->in2pcv[j->eoff[s] + B->in0 + i] = (uint32_t)i + ent0;
        else
            j->in2pcv[j->eoff[s] + B->in[2 * i]] = B->in[2 * i + 1] + ent0;
    if (!B->direct) free(B->pc), free(B->pc_off), free(B->pcv);
    free(B->in);
    B->pc = NULL, B->pc_off = B->pcv = B->in = NULL;
    B->direct = 0;
}

/* The grid step for finite coordinates within lo .. hi (no coordinate: lo > hi): the rule of
 * arr3_grid_step on their largest extent. */
static int bounds_step(const double *lo, const double *hi, double precision, double *step,
                       char *err, size_t errlen)
{
    double ext = 0;
    for (int a = 0; a < 3; a++)
        if (hi[a] >= lo[a] && hi[a] - lo[a] > ext) ext = hi[a] - lo[a];
    if (!isfinite(ext)) ext = DBL_MAX;
    return arr3_grid_step(ext, precision, step, err, errlen);
}

/* stage_input's state, passed from step to step and freed by inrun_free. */
typedef struct inrun {
    const solid *solids;
    size_t ns;
    const uint32_t *const *twins;
    double lo[3], hi[3];                     /* the box of every input vertex */
    size_t nfaces, nvin, nein, ncyin, ntask; /* input faces, vertices, entries, cycles; tasks */
    size_t *voff,
        *eoff;      /* by solid: its first vertex and entry among all solids' (and the totals) */
    uint32_t *vmap; /* by input vertex of all solids (voff): its vertex */
    intask *task;
    pbuf *buf;               /* by task */
    size_t *place, *at;      /* 3 by task: its place were every face as it is (injob.place);
                                where the join puts its pieces (joinjob.at); then the totals */
    size_t npc, npcyc, npcv; /* the pieces, their cycles and entries the tasks made */
    piece *old_pc;           /* the arrays the tasks wrote in place, when the join moves them */
    uint32_t *old_off, *old_pcv;
    uint32_t *in2pcv; /* by input entry of all solids (eoff): its entry in a3 (NONE: none) */
    uint8_t *ident;   /* by solid: joinjob.ident */
    uint32_t *drop;   /* one solid's vertices of faces left out (mend_dropped) */
} inrun;

static void inrun_free(inrun *R)
{
    for (size_t i = 0; R->buf && i < R->ntask; i++) pbuf_free(&R->buf[i]);
    free(R->buf);
    free(R->task);
    free(R->at);
    free(R->place);
    free(R->old_pc), free(R->old_off), free(R->old_pcv);
    free(R->voff);
    free(R->eoff);
    free(R->vmap);
    free(R->in2pcv);
    free(R->ident);
    free(R->drop);
}

/* stage_input's first step: the input's box (each coordinate finite, unless arr3_opts.checked)
 * and counts, the limits of faces and memory, A's solid_face_off, twinned and nfaces.  ARR_OK
 * or the error (err). */
static int input_count(a3 *A, inrun *R, char *err, size_t el)
{
    const solid *solids = R->solids;
    size_t ns = R->ns, nfaces = 0;
    int checked = A->o->checked;
    for (int a = 0; a < 3; a++) R->lo[a] = DBL_MAX, R->hi[a] = -DBL_MAX;
    for (size_t s = 0; s < ns; s++) {
        for (size_t i = 0; i < solids[s].nv; i++)
            for (int a = 0; a < 3; a++) {
                double x = solids[s].V[3 * i + a];
                if (!checked && !isfinite(x))
                    return util_seterr(err, el, ARR_EINVAL, "solids[%zu]: vertex %zu is not finite",
                                       s, i);
                if (x < R->lo[a]) R->lo[a] = x;
                if (x > R->hi[a]) R->hi[a] = x;
            }
        nfaces += solids[s].nf;
        R->nvin += solids[s].nv;
        R->nein += solids[s].cyc_off[solids[s].ncyc];
        R->ncyin += solids[s].ncyc;
        R->ntask += (solids[s].nf + IN_CHUNK - 1) / IN_CHUNK;
    }
    R->nfaces = nfaces;
    A->st->input_solids = ns;
    A->st->input_faces = nfaces;
    if (nfaces > ARR3_MAX_FACES)
        return util_seterr(err, el, ARR_ELIMIT, "solids: %zu faces, more than the limit of %u",
                           nfaces, ARR3_MAX_FACES);
    size_t avail = A->o->max_bytes;
    if (!avail) {
        long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
        avail = pages > 0 && size > 0 ? (size_t)pages * (size_t)size : SIZE_MAX;
    }
    if (nfaces > avail / ARR3_BYTES_PER_FACE)
        return util_seterr(err, el, ARR_ELIMIT,
                           "solids: %zu faces need about %.1f GB (%u bytes a face), more than the "
                           "%.1f GB of memory this run may take",
                           nfaces, (double)nfaces * ARR3_BYTES_PER_FACE / 1e9, ARR3_BYTES_PER_FACE,
                           (double)avail / 1e9);
    A->solid_face_off = mem_calloc(ns + 1, sizeof *A->solid_face_off);
    A->twinned = mem_calloc(ns + 1, 1);
    if (!A->solid_face_off || !A->twinned) return util_seterr(err, el, ARR_ENOMEM, "out of memory");
    A->nsolids = ns;
    for (size_t s = 0; s < ns; s++)
        A->solid_face_off[s + 1] = A->solid_face_off[s] + (uint32_t)solids[s].nf;
    A->nfaces = nfaces;
    return ARR_OK;
}

/* stage_input's second step: the grid (its step from the box, its origin oi at the box's
 * centre; every coordinate within SOLID_GRID_RANGE steps of the origin, unless arr3_opts.checked),
 * the input vertices snapped (on the threads), one vertex per grid point (A->g, A->nv; R->vmap).
 * ARR_OK or the error (err). */
static int input_snap(a3 *A, inrun *R, char *err, size_t el)
{
    const solid *solids = R->solids;
    size_t ns = R->ns;
    double step;
    int rc;
    /* arr3_solids_step's rule, on the bounds just taken */
    if ((rc = bounds_step(R->lo, R->hi, A->o->precision, &step, err, el)) != ARR_OK) return rc;
    A->step = step;
    A->st->precision = step;
    for (int a = 0; a < 3 && !A->o->checked; a++)
        if (!(fabs(R->lo[a]) / step < SOLID_GRID_RANGE) ||
            !(fabs(R->hi[a]) / step < SOLID_GRID_RANGE))
            return util_seterr(err, el, ARR_ELIMIT,
                               "solids: a coordinate is too large for the grid of step %g (at most "
                               "2^62 steps from the origin)",
                               step);
    for (int a = 0; a < 3; a++) A->oi[a] = llround((R->lo[a] + R->hi[a]) / 2 / step);
    R->voff = mem_malloc((ns + 1) * sizeof *R->voff);
    R->eoff = mem_malloc((ns + 1) * sizeof *R->eoff);
    R->vmap = mem_malloc((R->nvin + 1) * sizeof *R->vmap);
    int64_t *gin = mem_malloc((3 * R->nvin + 1) * sizeof *gin);
    if (!R->voff || !R->eoff || !R->vmap || !gin) goto oom;
    R->voff[0] = R->eoff[0] = 0;
    for (size_t s = 0; s < ns; s++) {
        R->voff[s + 1] = R->voff[s] + solids[s].nv;
        R->eoff[s + 1] = R->eoff[s] + solids[s].cyc_off[solids[s].ncyc];
    }
    /* the vertices on the grid (on the threads), then one vertex per grid point (in order) */
    snapjob j = {A, solids, R->voff, ns, R->nvin, gin};
    par_for(A->threads, (R->nvin + SNAP_CHUNK - 1) / SNAP_CHUNK, snap_chunk, &j);
    A3_TICK("in/snap");
    if (dedup_vertices(A, gin, R->nvin, R->vmap)) goto oom;
    free(gin);
    if (a3_cancelled(A)) return util_seterr(err, el, ARR_ECANCELED, "cancelled");
    A3_TICK("in/vertex_at");
    return ARR_OK;
oom:
    free(gin);
    return util_seterr(err, el, ARR_ENOMEM, "out of memory");
}

/* stage_input's third step: the faces into pieces, a run of faces a task on the threads
 * (in_task).  Each run writes in place, where its faces as they are go (the common case: then
 * the join only shifts numbers); a run that needs more room goes on in arrays of its own.
 * R->npc, npcyc, npcv: what the runs made.  ARR_OK or the error (err: a task's first). */
static int input_pieces(a3 *A, inrun *R, char *err, size_t el)
{
    const solid *solids = R->solids;
    size_t ntask = 0, nfaces = R->nfaces;
    R->task = mem_malloc((R->ntask + 1) * sizeof *R->task);
    R->buf = mem_calloc(R->ntask + 1, sizeof *R->buf);
    R->place = mem_malloc((3 * R->ntask + 3) * sizeof *R->place);
    if (!R->task || !R->buf || !R->place) goto oom;
    for (size_t s = 0; s < R->ns; s++)
        for (size_t f0 = 0; f0 < solids[s].nf; f0 += IN_CHUNK)
            R->task[ntask++] =
                (intask){(uint32_t)s, (uint32_t)f0,
                         (uint32_t)(f0 + IN_CHUNK < solids[s].nf ? f0 + IN_CHUNK : solids[s].nf)};
    R->ntask = ntask;
    const intask *task = R->task;
    size_t *place = R->place;
    if (mem_grow(&A->pc, &A->cappc, nfaces + 1, sizeof *A->pc) ||
        mem_grow(&A->pc_off, &A->cappc_off, R->ncyin + 2, sizeof *A->pc_off) ||
        mem_grow(&A->pcv, &A->cappcv, R->nein + 1, sizeof *A->pcv))
        goto oom;
    for (size_t t = 0, cy0 = 0, s = 0; t < ntask; t++) {
        const solid *so = &solids[task[t].s];
        for (; s < task[t].s; s++) cy0 += solids[s].ncyc;
        place[3 * t] = A->solid_face_off[task[t].s] + task[t].f0;
        place[3 * t + 1] = cy0 + so->face_off[task[t].f0];
        place[3 * t + 2] = R->eoff[task[t].s] + so->cyc_off[so->face_off[task[t].f0]];
    }
    place[3 * ntask] = nfaces, place[3 * ntask + 1] = R->ncyin, place[3 * ntask + 2] = R->nein;
    injob j = {A, solids, R->vmap, R->voff, task, R->buf, place};
    par_for(A->threads, ntask, in_task, &j);
    A3_TICK("in/tasks");
    if (a3_cancelled(A)) return util_seterr(err, el, ARR_ECANCELED, "cancelled");
    R->npc = R->npcyc = R->npcv = 0;
    for (size_t t = 0; t < ntask; t++) {
        if (R->buf[t].rc != ARR_OK) return util_seterr(err, el, R->buf[t].rc, "%s", R->buf[t].msg);
        R->npc += R->buf[t].npc, R->npcyc += R->buf[t].npcyc, R->npcv += R->buf[t].npcv;
    }
    return ARR_OK;
oom:
    return util_seterr(err, el, ARR_ENOMEM, "out of memory");
}

/* stage_input's last step: the runs' pieces joined in order into a3's arrays (join_task, on the
 * threads: in place only numbers to shift, else copied to new arrays), which solids take their
 * check's twins (twinned: given, and no face split), the faces left out mended into their
 * neighbours (mend_dropped), and the check's twins carried over (twin_chunk).  0, or -1 out of
 * memory. */
static int input_join(a3 *A, inrun *R)
{
    const intask *task = R->task;
    const pbuf *buf = R->buf;
    size_t ntask = R->ntask, ns = R->ns, *at, ndrop = 0, capdrop = 0;
    at = R->at = mem_malloc((3 * ntask + 3) * sizeof *R->at);
    if (!at) return -1;
    at[0] = at[1] = at[2] = 0;
    int inplace = 1;
    for (size_t t = 0; t < ntask; t++) {
        at[3 * t + 3] = at[3 * t] + buf[t].npc;
        at[3 * t + 4] = at[3 * t + 1] + buf[t].npcyc;
        at[3 * t + 5] = at[3 * t + 2] + buf[t].npcv;
        A->split_faces += buf[t].split_faces;
        if (!buf[t].direct || memcmp(at + 3 * t + 3, R->place + 3 * t + 3, 3 * sizeof *at))
            inplace = 0; /* every run wrote exactly its faces as they are */
    }
    if (!inplace) { /* the runs' pieces (in place or their own) to new arrays */
        R->old_pc = A->pc, R->old_off = A->pc_off, R->old_pcv = A->pcv;
        A->pc = NULL, A->pc_off = A->pcv = NULL;
        A->cappc = A->cappc_off = A->cappcv = 0;
    }
    if (mem_grow(&A->pc, &A->cappc, R->npc + 1, sizeof *A->pc) ||
        mem_grow(&A->pc_off, &A->cappc_off, R->npcyc + 2, sizeof *A->pc_off) ||
        mem_grow(&A->pcv, &A->cappcv, R->npcv + 1, sizeof *A->pcv) ||
        mem_grow(&A->pcvp, &A->cappcvp, R->npcv + 1, sizeof *A->pcvp) ||
        mem_grow(&A->ptwin, &A->capptwin, R->npcv + 1, sizeof *A->ptwin))
        return -1;
    /* by solid: the check's twins are taken (no split face), and its entries are its input's */
    R->ident = mem_calloc(ns + 1, 1);
    if (!R->ident) return -1;
    int need_map = 0;
    for (size_t s = 0, t = 0; s < ns; s++) {
        size_t split = 0;
        int asis = inplace;
        for (; t < ntask && task[t].s == s; t++) {
            split += buf[t].split_faces;
            /* in place, its counts are its input's: every entry went as it is? */
            if (buf[t].nin != R->place[3 * t + 5] - R->place[3 * t + 2] || buf[t].ndrop) asis = 0;
        }
        /* the check paired the input's edges; a face split into triangles has edges of its own
         * (and its input edges in other entries): such a solid's twins all come from its
         * pieces (stage_twins), so that its patches reach across the split faces */
        if (R->twins && R->twins[s] && !split) A->twinned[s] = 1;
        R->ident[s] = A->twinned[s] && asis;
        need_map |= A->twinned[s] && !asis;
    }
    if (need_map) {
        R->in2pcv = mem_malloc((R->nein + 1) * sizeof *R->in2pcv);
        if (!R->in2pcv) return -1;
        memset(R->in2pcv, 0xff, (R->nein + 1) * sizeof *R->in2pcv);
    }
    joinjob j = {A, R->buf, task, at, R->eoff, R->twins, R->in2pcv, inplace, R->ident};
    par_for(A->threads, ntask, join_task, &j);
    free(R->old_pc), free(R->old_off), free(R->old_pcv);
    R->old_pc = NULL, R->old_off = R->old_pcv = NULL;
    A->npc = R->npc, A->npcyc = R->npcyc, A->npcv = R->npcv;
    A->pc_off[A->npcyc] = (uint32_t)A->npcv;
    /* the faces left out, solid by solid: their vertices inside the solid's edges */
    for (size_t s = 0, t = 0; s < ns; s++) {
        size_t t0 = t;
        ndrop = 0;
        for (; t < ntask && task[t].s == s; t++)
            for (size_t i = 0; i < buf[t].ndrop; i++)
                if (A3_PUSH(R->drop, ndrop, capdrop, buf[t].drop[i])) return -1;
        if (ndrop && mend_dropped(A, at[3 * t0], at[3 * t], R->drop, ndrop)) return -1;
    }
    A3_TICK("in/join");
    if (R->in2pcv) { /* the twins the check found, between entries that went as they are */
        twinjob tj = {A, R->twins, R->in2pcv, R->eoff, ns, R->nein};
        par_for(A->threads, (R->nein + SNAP_CHUNK - 1) / SNAP_CHUNK, twin_chunk, &tj);
    }
    return 0;
}

/* The input: the solids' box and limits (input_count), the grid and its vertices (input_snap),
 * the faces into pieces on the threads (input_pieces), joined in order with the check's twins
 * (input_join).  ARR_OK or the error (err). */
A3_STAGE static int stage_input(a3 *A, const solid *solids, size_t ns, const uint32_t *const *twins,
                                char *err, size_t el)
{
    inrun R = {.solids = solids, .ns = ns, .twins = twins};
    int rc = input_count(A, &R, err, el);
    if (rc != ARR_OK || !R.nfaces) goto done;
    A3_TICK("in/bounds");
    if ((rc = input_snap(A, &R, err, el)) != ARR_OK) goto done;
    if ((rc = input_pieces(A, &R, err, el)) != ARR_OK) goto done;
    if (input_join(A, &R)) rc = util_seterr(err, el, ARR_ENOMEM, "out of memory");
done:
    inrun_free(&R);
    return rc;
}

/* Every entry's twin (a3.ptwin): the entries sorted by their edge's lower vertex (a counting
 * sort), then by (higher vertex, solid), stably; a run of exactly two entries of one solid
 * walking the edge opposite ways are each other's twins.  None in a soup.  -1 out of memory. */
A3_STAGE static int stage_twins(a3 *A)
{
    size_t n = A->npcv, nv = A->nv, left = 0;
    int rc = -1;
    uint32_t *pos = NULL, *lo = NULL, *nx = NULL, *sx = NULL;
    uint64_t *sk = NULL;
    if (A->soup || !n) return 0;
    for (size_t s = 0; s < A->nsolids; s++) left += !A->twinned[s];
    if (!left) return 0; /* every solid's twins came with its check */
    pos = mem_calloc(nv + 2, sizeof *pos);
    lo = mem_malloc(n * sizeof *lo);
    nx = mem_malloc(n * sizeof *nx);
    sk = mem_malloc(n * sizeof *sk);
    sx = mem_malloc(n * sizeof *sx);
    if (!pos || !lo || !nx || !sk || !sx) goto done;
    for (size_t pi = 0; pi < A->npc; pi++) {
        const piece *pc = &A->pc[pi];
        if (A->twinned[pc->solid]) continue;
        for (uint32_t cy = pc->c0; cy < pc->c0 + pc->nc; cy++) {
            uint32_t o = A->pc_off[cy], m = A->pc_off[cy + 1] - o;
            for (uint32_t t = 0; t < m; t++) {
                uint32_t a = A->pcv[o + t], b = A->pcv[t + 1 < m ? o + t + 1 : o];
                nx[o + t] = b;
                lo[o + t] = a < b ? a : b;
                pos[lo[o + t] + 2]++;
            }
        }
    }
    for (size_t v = 0; v < nv; v++) pos[v + 2] += pos[v + 1];
    for (size_t pi = 0; pi < A->npc; pi++) {
        const piece *pc = &A->pc[pi];
        if (A->twinned[pc->solid]) continue;
        uint32_t x0 = A->pc_off[pc->c0], x1 = A->pc_off[pc->c0 + pc->nc];
        for (uint32_t x = x0; x < x1; x++) {
            uint32_t a = A->pcv[x], b = nx[x], slot = pos[lo[x] + 1]++;
            sk[slot] = (uint64_t)(a ^ b ^ lo[x]) << 32 | pc->solid;
            sx[slot] = x;
        }
    }
    for (size_t v = 0; v < nv; v++) {
        uint32_t r0 = pos[v], r1 = pos[v + 1];
        for (uint32_t i = r0 + 1; i < r1; i++) {
            uint64_t k = sk[i];
            uint32_t x = sx[i], j = i;
            for (; j > r0 && sk[j - 1] > k; j--) sk[j] = sk[j - 1], sx[j] = sx[j - 1];
            sk[j] = k, sx[j] = x;
        }
        for (uint32_t i = r0; i < r1;) {
            uint32_t j = i + 1;
            while (j < r1 && sk[j] == sk[i]) j++;
            if (j - i == 2) {
                uint32_t x = sx[i], y = sx[i + 1];
                if (A->pcv[x] == nx[y] && A->pcv[y] == nx[x]) A->ptwin[x] = y, A->ptwin[y] = x;
            }
            i = j;
        }
    }
    rc = 0;
done:
    free(pos), free(lo), free(nx), free(sk), free(sx);
    return rc;
}

/* The canonical plane through piece pc's anchors into *P, and *flip: -1 when it turns the
 * other way than their raw plane, else 1.  -1 when they span none (not reached). */
static int piece_canon_plane(const a3 *A, const piece *pc, plane3 *P, int8_t *flip)
{
    if (plane_through(A->g + 3 * (size_t)pc->av[0], A->g + 3 * (size_t)pc->av[1],
                      A->g + 3 * (size_t)pc->av[2], P))
        return -1;
    *flip = (int8_t)plane_canon(P);
    return 0;
}

/* Piece pc takes canonical plane P (flip from piece_canon_plane): its id, and its sgn turned
 * to that plane's normal.  -1 out of memory. */
static int piece_take_plane(a3 *A, piece *pc, plane3 *P, int8_t flip)
{
    uint32_t id = plane_id(A, P);
    if (id == NONE) return -1;
    pc->plane = id;
    pc->sgn = (int8_t)(pc->sgn * flip);
    return 0;
}

/* Gives piece pi its canonical plane (once), turning its sgn to that plane's normal.  Returns
 * -1 out of memory. */
static int piece_plane_id(a3 *A, uint32_t pi)
{
    piece *pc = &A->pc[pi];
    if (pc->plane != NONE) return 0;
    plane3 P;
    int8_t flip;
    return piece_canon_plane(A, pc, &P, &flip) || piece_take_plane(A, pc, &P, flip) ? -1 : 0;
}

const plane3 *a3_piece_plane(const a3 *A, uint32_t pi, plane3 *tmp)
{
    const piece *pc = &A->pc[pi];
    if (pc->plane != NONE) return &A->pl[pc->plane];
    plane_through_raw(A->g + 3 * (size_t)pc->av[0], A->g + 3 * (size_t)pc->av[1],
                      A->g + 3 * (size_t)pc->av[2], tmp);
    return tmp;
}

void a3_face_normal(const a3 *A, uint32_t f, int64_t *n)
{
    if (A->f_plane[f] != NONE) {
        memcpy(n, A->pl[A->f_plane[f]].n, 3 * sizeof *n);
        return;
    }
    const piece *pc = &A->pc[A->cov[A->f_cov[f]]];
    if (pc->plane != NONE) {
        memcpy(n, A->pl[pc->plane].n, 3 * sizeof *n);
        return;
    }
    grid_normal(A->g + 3 * (size_t)pc->av[0], A->g + 3 * (size_t)pc->av[1],
                A->g + 3 * (size_t)pc->av[2], n);
}

const plane3 *a3_face_plane(const a3 *A, uint32_t f, plane3 *tmp)
{
    if (A->f_plane[f] != NONE) return &A->pl[A->f_plane[f]];
    return a3_piece_plane(A, A->cov[A->f_cov[f]], tmp);
}

int arr3_grid_step(double extent, double precision, double *step, char *err, size_t errlen)
{
    if (precision < 0 || !isfinite(precision))
        return util_seterr(err, errlen, ARR_EINVAL, "precision: expected a positive number");
    if (!(extent > 0) || !isfinite(extent)) {
        *step = precision > 0 ? precision : 1; /* nothing to snap: any step gives the same */
        return ARR_OK;
    }
    if (precision == 0) {
        double s = exp2(ceil(log2(extent * exp2(-ARR3_GRID_BITS))));
        *step = s < DBL_MIN ? DBL_MIN : s;
        return ARR_OK;
    }
    if (extent / precision > exp2(ARR3_GRID_BITS))
        return util_seterr(
            err, errlen, ARR_ELIMIT,
            "precision: %g is finer than the input allows: its extent %g divided by the "
            "precision must be at most 2^%d",
            precision, extent, ARR3_GRID_BITS);
    *step = precision;
    return ARR_OK;
}

int arr3_solids_step(const solid *s, size_t n, double precision, double *step, char *err,
                     size_t errlen)
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (size_t i = 0; i < n; i++)
        for (size_t v = 0; v < s[i].nv; v++)
            for (int a = 0; a < 3; a++) {
                double x = s[i].V[3 * v + a];
                if (!isfinite(x)) continue;
                if (x < lo[a]) lo[a] = x;
                if (x > hi[a]) hi[a] = x;
            }
    return bounds_step(lo, hi, precision, step, err, errlen);
}

/* ------------------------------------------------------------------ pairs */

/* ------------------------------------------------------------------ cuts */

/* The pairs run on par_for() in fixed chunks.  A chunk makes its LPIs as its own points (ids
 * with CUT_LOCAL set, once per (edge, plane) in the chunk) and writes its own cuts and contacts;
 * the chunks are then merged in order, each LPI that a cut or a contact uses becoming the global
 * point of its (edge, plane) (made once: a hash on the triple; the others are dropped), so the
 * result does not depend on the number of threads. */
#define CUT_CHUNK 8192
#define CUT_LOCAL 0x80000000u

/* A hash from (a, b, c) to point ids, NONE empty. */
typedef struct ltab {
    uint32_t *id;
    size_t cap, n;
} ltab;

/* An event of a polygon on the line: the closed stretch [lo, hi] of its boundary (one point for
 * a crossing, the vertices of a run along the line otherwise), and whether the inside changes
 * across it. */
typedef struct ev {
    uint32_t lo, hi;
    int toggle;
} ev;

/* A worker's scratch. */
typedef struct cutwork {
    ev *e[2];
    size_t ne[2], cap[2];
    uint32_t *iv[2]; /* closed intervals: pairs of points */
    size_t niv[2], capiv[2];
    int8_t *sd;
    size_t capsd;
    A3_PAD;
} cutwork;

/* A chunk's output. */
typedef struct cutout {
    xpt *pt; /* its LPIs */
    size_t npt, cappt;
    ltab lt; /* over pt: local indices */
    cseg *cs;
    size_t ncs, capcs;
    cpt *cp;
    size_t ncp, capcp;
    uint32_t *met; /* pieces of the pairs that meet */
    size_t nmet, capmet;
    size_t npairs;    /* pairs that meet */
    uint64_t *self;   /* the pairs of one solid that meet (cross, or overlap in a plane) */
    uint32_t *selfpt; /* by such pair: a point where they meet (NONE: overlapping in a plane) */
    size_t nself, capself, capselfpt;
    uint32_t *fold; /* planes where pieces of one solid overlap: arranged whole */
    size_t nfold, capfold;
    int rc; /* 0, -1 out of memory, -3 cancelled */
    A3_PAD;
} cutout;

typedef struct cutjob {
    const a3 *A;
    const uint64_t *pairs;
    size_t np;
    cutwork *w; /* by worker */
    cutout *o;  /* by chunk */
    atomic_size_t done;
} cutjob;

static uint64_t lkey(uint32_t a, uint32_t b, uint32_t c)
{
    return a3_mix64(((uint64_t)a << 32 | b) ^ a3_mix64(c + 0x9e3779b9ULL));
}

static int ltab_rehash(const xpt *pt, ltab *t, size_t ncap)
{
    uint32_t *id = mem_malloc(ncap * sizeof *id);
    if (!id) return -1;
    memset(id, 0xff, ncap * sizeof *id);
    for (size_t i = 0; i < t->cap; i++) {
        if (t->id[i] == NONE) continue;
        const xpt *p = &pt[t->id[i]];
        size_t h = lkey(p->a, p->b, p->c) & (ncap - 1);
        while (id[h] != NONE) h = (h + 1) & (ncap - 1);
        id[h] = t->id[i];
    }
    free(t->id);
    t->id = id;
    t->cap = ncap;
    return 0;
}

/* The slot of (a, b, c) in t over points pt: the one holding it, or the empty one where it
 * goes; SIZE_MAX when out of memory. */
static size_t ltab_slot(const xpt *pt, ltab *t, uint32_t a, uint32_t b, uint32_t c)
{
    if (2 * (t->n + 1) > t->cap && ltab_rehash(pt, t, t->cap ? 2 * t->cap : 1024)) return SIZE_MAX;
    size_t h = lkey(a, b, c) & (t->cap - 1);
    while (t->id[h] != NONE) {
        const xpt *p = &pt[t->id[h]];
        if (p->a == a && p->b == b && p->c == c) break;
        h = (h + 1) & (t->cap - 1);
    }
    return h;
}

static uint32_t add_point(a3 *A, xpt p)
{
    if (A->npt >= CUT_LOCAL - 1 || A3_PUSH(A->pt, A->npt, A->cappt, p)) return NONE;
    A->G.pl = A->pl;
    A->G.g = A->g;
    return (uint32_t)(A->npt - 1);
}

static const xpt *cut_pt(const a3 *A, const cutout *o, uint32_t p)
{
    return p & CUT_LOCAL ? &o->pt[p & ~CUT_LOCAL] : &A->pt[p];
}

/* The chunk's LPI of edge (a, b) and plane c. */
static uint32_t lpi_id(const a3 *A, cutout *o, uint32_t a, uint32_t b, uint32_t c)
{
    if (a > b) {
        uint32_t s = a;
        a = b, b = s;
    }
    size_t h = ltab_slot(o->pt, &o->lt, a, b, c);
    if (h == SIZE_MAX) return NONE;
    if (o->lt.id[h] != NONE) return o->lt.id[h] | CUT_LOCAL;
    if (o->npt >= CUT_LOCAL - 1 || A3_PUSH(o->pt, o->npt, o->cappt, xpt_lpi(&A->G, a, b, c)))
        return NONE;
    o->lt.id[h] = (uint32_t)(o->npt - 1);
    o->lt.n++;
    return (uint32_t)(o->npt - 1) | CUT_LOCAL;
}

static int cmp_on(const a3 *A, const cutout *o, uint32_t p, uint32_t q, int ax)
{
    return p == q ? 0 : cmp_coord(&A->G, cut_pt(A, o, p), cut_pt(A, o, q), ax);
}

/* Sorts events by lo (insertion sort: a handful per polygon). */
static void sort_events(const a3 *A, const cutout *o, ev *e, size_t n, int ax)
{
    for (size_t i = 1; i < n; i++) {
        ev x = e[i];
        size_t j = i;
        while (j > 0 && cmp_on(A, o, e[j - 1].lo, x.lo, ax) > 0) {
            e[j] = e[j - 1];
            j--;
        }
        e[j] = x;
    }
}

/* The closed intervals of piece `pi` on the line where its plane meets plane `q`, sorted along
 * axis ax.  Returns 0, -1 (out of memory) or -2 (the piece lies in q: no line). */
static int piece_on_line(const a3 *A, cutout *o, cutwork *w, int s, uint32_t pi, uint32_t q, int ax)
{
    const piece *P = &A->pc[pi];
    const plane3 *Q = &A->pl[q];
    w->ne[s] = 0;
    w->niv[s] = 0;
    for (uint32_t cy = P->c0; cy < P->c0 + P->nc; cy++) {
        uint32_t o0 = A->pc_off[cy], n = A->pc_off[cy + 1] - o0;
        const uint32_t *v = A->pcv + o0;
        if (mem_grow(&w->sd, &w->capsd, n, 1)) return -1;
        uint32_t nz = 0, first = NONE;
        for (uint32_t i = 0; i < n; i++) {
            const int64_t *g = A->g + 3 * (size_t)v[i];
            i128 x = (i128)Q->n[0] * g[0] + (i128)Q->n[1] * g[1] + (i128)Q->n[2] * g[2] + Q->d;
            w->sd[i] = (int8_t)((x > 0) - (x < 0));
            if (w->sd[i]) nz++, first = first == NONE ? i : first;
        }
        if (nz == 0) return -2;
        /* walk from a vertex off the line: crossings, and runs of vertices on it */
        for (uint32_t t = 0; t < n; t++) {
            uint32_t i = (first + t) % n, j = (i + 1) % n;
            if (w->sd[i] && w->sd[j] && w->sd[i] != w->sd[j]) {
                uint32_t x = lpi_id(A, o, v[i], v[j], q);
                if (x == NONE) return -1;
                ev e = {x, x, 1};
                if (A3_PUSH(w->e[s], w->ne[s], w->cap[s], e)) return -1;
            } else if (w->sd[i] && !w->sd[j]) {
                /* a run starts at j: follow it to its end */
                uint32_t r = j, lo = v[j], hi = v[j];
                while (!w->sd[(r + 1) % n]) {
                    r = (r + 1) % n;
                    if (cmp_on(A, o, v[r], lo, ax) < 0) lo = v[r];
                    if (cmp_on(A, o, v[r], hi, ax) > 0) hi = v[r];
                }
                int8_t after = w->sd[(r + 1) % n];
                ev e = {lo, hi, after != w->sd[i]};
                if (A3_PUSH(w->e[s], w->ne[s], w->cap[s], e)) return -1;
            }
        }
    }
    ev *E = w->e[s];
    size_t ne = w->ne[s];
    sort_events(A, o, E, ne, ax);
    /* sweep: inside between events when the parity is odd; events themselves are boundary */
    int par = 0;
    for (size_t i = 0; i < ne; i++) {
        size_t m = w->niv[s];
        uint32_t *iv = w->iv[s];
        if (m && (par || cmp_on(A, o, E[i].lo, iv[2 * m - 1], ax) <= 0)) {
            if (cmp_on(A, o, E[i].hi, iv[2 * m - 1], ax) > 0) iv[2 * m - 1] = E[i].hi;
        } else {
            if (mem_grow(&w->iv[s], &w->capiv[s], 2 * (m + 1), sizeof *w->iv[s])) return -1;
            w->iv[s][2 * m] = E[i].lo;
            w->iv[s][2 * m + 1] = E[i].hi;
            w->niv[s]++;
        }
        par ^= E[i].toggle;
    }
    return 0;
}

static int add_cut(cutout *o, uint32_t plane, uint32_t p0, uint32_t p1, uint32_t side)
{
    cseg c = {plane, p0, p1, side};
    return A3_PUSH(o->cs, o->ncs, o->capcs, c);
}

static int add_contact(a3 *A, uint32_t plane, uint32_t p)
{
    cpt c = {plane, p};
    return A3_PUSH(A->cp, A->ncp, A->capcp, c);
}

static int chunk_contact(cutout *o, uint32_t plane, uint32_t p)
{
    cpt c = {plane, p};
    return A3_PUSH(o->cp, o->ncp, o->capcp, c);
}

/* One pair of pieces: the stretches where both lie on the line of their planes are cuts of both
 * planes (a single point: a contact). */
/* Of a pair of one solid's pieces a, b, is the stretch from point p to point q (p == q: the
 * point) where they meet as neighbouring faces do: a vertex of both, or an edge of both? */
static int shared_part(const a3 *A, uint32_t a, uint32_t b, uint32_t p, uint32_t q)
{
    const piece *P = &A->pc[a], *Q = &A->pc[b];
    if ((p | q) & CUT_LOCAL || p >= A->nv || q >= A->nv) return 0; /* a made point */
    if (p == q) return a3_piece_vertex(A, P, p) && a3_piece_vertex(A, Q, p);
    return a3_piece_edge(A, P, p, q) && a3_piece_edge(A, Q, p, q);
}

/* A pair that meets: both pieces reached; a pair of one solid listed (its surface passes
 * through itself there). */
static int pair_met(const a3 *A, cutout *o, uint32_t a, uint32_t b, uint32_t at)
{
    o->npairs++;
    if (A->pc[a].solid == A->pc[b].solid) {
        size_t n = o->nself;
        if (A3_PUSH(o->self, o->nself, o->capself, (uint64_t)a << 32 | b) ||
            mem_grow(&o->selfpt, &o->capselfpt, n + 1, sizeof *o->selfpt))
            return -1;
        o->selfpt[n] = at;
    }
    return A3_PUSH(o->met, o->nmet, o->capmet, a) || A3_PUSH(o->met, o->nmet, o->capmet, b) ? -1
                                                                                            : 0;
}

static int cut_pair(const a3 *A, cutout *o, cutwork *w, uint32_t a, uint32_t b)
{
    uint32_t pa = A->pc[a].plane, pb = A->pc[b].plane;
    size_t ncs = o->ncs, ncp = o->ncp;
    int self = A->pc[a].solid == A->pc[b].solid;
    if (pa == pb) { /* coplanar, boxes meeting: both go through their plane's arrangement */
        if (!self) return pair_met(A, o, a, b, NONE);
        /* of one solid: only where they overlap or touch elsewhere than as neighbours, and
         * then the plane is arranged whole (its pieces are no longer apart) */
        int apart = a3_flat_apart(A, a, b);
        if (apart == 1) return 0;
        if (A3_PUSH(o->fold, o->nfold, o->capfold, pa)) return -1;
        if (apart == 2) { /* touching only: arranged, not a surface passing through itself */
            o->npairs++;
            return A3_PUSH(o->met, o->nmet, o->capmet, a) || A3_PUSH(o->met, o->nmet, o->capmet, b)
                       ? -1
                       : 0;
        }
        return pair_met(A, o, a, b, NONE);
    }
    i128 d[3];
    cross_ll(A->pl[pa].n, A->pl[pb].n, d);
    if (!d[0] && !d[1] && !d[2]) return 0; /* parallel planes */
    int ax = 0;
    for (int i = 1; i < 3; i++)
        if ((d[i] < 0 ? -d[i] : d[i]) > (d[ax] < 0 ? -d[ax] : d[ax])) ax = i;
    int r0 = piece_on_line(A, o, w, 0, a, pb, ax);
    if (r0 == -1) return -1;
    if (r0 == -2 || w->niv[0] == 0) return 0;
    int r1 = piece_on_line(A, o, w, 1, b, pa, ax);
    if (r1 == -1) return -1;
    if (r1 == -2 || w->niv[1] == 0) return 0;
    /* intersect the two sorted lists of closed intervals */
    size_t i = 0, j = 0;
    while (i < w->niv[0] && j < w->niv[1]) {
        uint32_t a0 = w->iv[0][2 * i], a1 = w->iv[0][2 * i + 1];
        uint32_t b0 = w->iv[1][2 * j], b1 = w->iv[1][2 * j + 1];
        uint32_t lo = cmp_on(A, o, a0, b0, ax) >= 0 ? a0 : b0;
        uint32_t hi = cmp_on(A, o, a1, b1, ax) <= 0 ? a1 : b1;
        int c = cmp_on(A, o, lo, hi, ax);
        if (self && c <= 0 && shared_part(A, a, b, lo, c ? hi : lo)) {
            /* where neighbours meet: nothing to cut */
        } else if (c < 0) {
            if (add_cut(o, pa, lo, hi, pb) || add_cut(o, pb, lo, hi, pa)) return -1;
        } else if (c == 0) {
            if (chunk_contact(o, pa, lo) || chunk_contact(o, pb, lo)) return -1;
        }
        if (cmp_on(A, o, a1, b1, ax) <= 0)
            i++;
        else
            j++;
    }
    if (o->ncs == ncs && o->ncp == ncp) return 0;
    if (self && o->ncs == ncs) { /* only touching at points: not passing through itself */
        o->npairs++;
        return A3_PUSH(o->met, o->nmet, o->capmet, a) || A3_PUSH(o->met, o->nmet, o->capmet, b) ? -1
                                                                                                : 0;
    }
    return pair_met(A, o, a, b, o->ncs > ncs ? o->cs[ncs].p0 : o->cp[ncp].p);
}

static void cut_chunk(void *ctx, size_t item, int worker)
{
    cutjob *j = ctx;
    cutout *o = &j->o[item];
    size_t k1 = (item + 1) * CUT_CHUNK < j->np ? (item + 1) * CUT_CHUNK : j->np;
    if (a3_cancelled(j->A)) {
        o->rc = -3;
        return;
    }
    for (size_t k = item * CUT_CHUNK; k < k1 && !o->rc; k++)
        o->rc =
            cut_pair(j->A, o, &j->w[worker], (uint32_t)(j->pairs[k] >> 32), (uint32_t)j->pairs[k]);
    size_t done = atomic_fetch_add(&j->done, 1) + 1;
    if (worker == 0) /* the calling thread */
        a3_progress(j->A, "cuts", (double)done / (double)((j->np + CUT_CHUNK - 1) / CUT_CHUNK));
}

static void cutout_free(cutout *o)
{
    free(o->self);
    free(o->selfpt);
    free(o->fold);
    free(o->met);
    free(o->pt);
    free(o->lt.id);
    free(o->cs);
    free(o->cp);
    memset(o, 0, sizeof *o);
}

static uint32_t merged_id(const uint32_t *map, uint32_t p)
{
    return p & CUT_LOCAL ? map[p & ~CUT_LOCAL] : p;
}

/* pair_planes' work: piece_canon_plane of pieces pcs[i], on the threads. */
typedef struct ppjob {
    const a3 *A;
    const uint32_t *pcs;
    plane3 *P;
    int8_t *flip;
    size_t n;
    int fail;
} ppjob;

#define PP_CHUNK 1024
static void pp_chunk(void *ctx, size_t item, int worker)
{
    (void)worker;
    ppjob *j = ctx;
    size_t i0 = item * PP_CHUNK, i1 = i0 + PP_CHUNK < j->n ? i0 + PP_CHUNK : j->n;
    for (size_t i = i0; i < i1; i++)
        if (piece_canon_plane(j->A, &j->A->pc[j->pcs[i]], &j->P[i], &j->flip[i]))
            j->fail = 1; /* the same value, whichever worker writes it */
}

/* Does every vertex of piece q lie strictly on one side of piece p's anchor plane (exact)?  Then
 * the two neither cross nor touch, whatever else holds. */
static int off_plane(const a3 *A, uint32_t p, uint32_t q)
{
    const piece *P = &A->pc[p], *Q = &A->pc[q];
    const int64_t *a = A->g + 3 * (size_t)P->av[0];
    int64_t n[3];
    if (grid_normal(a, A->g + 3 * (size_t)P->av[1], A->g + 3 * (size_t)P->av[2], n)) return 0;
    int side = 0;
    for (uint32_t x = A->pc_off[Q->c0]; x < A->pc_off[Q->c0 + Q->nc]; x++) {
        const int64_t *w = A->g + 3 * (size_t)A->pcv[x];
        i128 d =
            (i128)n[0] * (w[0] - a[0]) + (i128)n[1] * (w[1] - a[1]) + (i128)n[2] * (w[2] - a[2]);
        int sd = (d > 0) - (d < 0);
        if (sd == 0 || (side && sd != side)) return 0;
        side = sd;
    }
    return 1;
}

typedef struct apartjob {
    const a3 *A;
    const uint64_t *pairs;
    uint8_t *keep;
    size_t np;
} apartjob;

/* A triangle piece's vertices' grid points into t: 1, or 0 when the piece is no triangle. */
static int piece_tri(const a3 *A, uint32_t p, const int64_t **t)
{
    const uint32_t *v = a3_piece_tri(A, &A->pc[p]);
    for (int i = 0; v && i < 3; i++) t[i] = A->g + 3 * (size_t)v[i];
    return v != NULL;
}

static void apart_chunk(void *ctx, size_t item, int worker)
{
    (void)worker;
    const apartjob *j = ctx;
    size_t k0 = item * CUT_CHUNK, k1 = k0 + CUT_CHUNK < j->np ? k0 + CUT_CHUNK : j->np;
    for (size_t k = k0; k < k1; k++) {
        uint32_t p = (uint32_t)(j->pairs[k] >> 32), q = (uint32_t)j->pairs[k];
        const int64_t *tp[3], *tq[3];
        if (piece_tri(j->A, p, tp) && piece_tri(j->A, q, tq)) /* two triangles: their line too */
            j->keep[k] = !tri_tri_apart(tp, tq);
        else
            j->keep[k] = !off_plane(j->A, p, q) && !off_plane(j->A, q, p);
    }
}

/* The broad phase's pairs whose pieces are apart (most of them: boxes meet far more often than
 * faces): by either one's plane, and for two triangles also along the line of their planes
 * (tri_tri_apart), marked on the threads and dropped: no canonical plane and no cut work is
 * spent on them.  Returns how many are kept, in order. */
static size_t drop_apart(const a3 *A, uint64_t *pairs, size_t np)
{
    uint8_t *keep = mem_malloc(np + 1);
    if (!keep) return np; /* out of memory: every pair kept (the cuts decide alike) */
    apartjob j = {A, pairs, keep, np};
    par_for(A->threads, (np + CUT_CHUNK - 1) / CUT_CHUNK, apart_chunk, &j);
    size_t m = 0;
    for (size_t k = 0; k < np; k++)
        if (keep[k]) pairs[m++] = pairs[k];
    free(keep);
    return m;
}

/* piece_plane_id for both pieces of every pair, in pair order: the pieces without a plane
 * listed (marked PLANE_LISTED meanwhile), their planes made on the threads, then taken in the
 * list's order (so the ids are piece_plane_id's).  -1 out of memory (or a piece without a
 * plane). */
#define PLANE_LISTED (NONE - 1)
static int pair_planes(a3 *A, const uint64_t *pairs, size_t np)
{
    ppjob j = {A, NULL, NULL, NULL, 0, 0};
    uint32_t *pcs = NULL;
    size_t cap = 0;
    int rc = -1;
    /* the pairs of two solids first, then those of one (a surface that may cross itself): so
     * a clean surface's planes are numbered as they would be without the latter */
    for (int self = 0; self < 2; self++)
        for (size_t k = 0; k < 2 * np; k++) {
            uint64_t pr = pairs[k / 2];
            if ((A->pc[pr >> 32].solid == A->pc[(uint32_t)pr].solid) != self) continue;
            uint32_t pi = k & 1 ? (uint32_t)pr : (uint32_t)(pr >> 32);
            if (A->pc[pi].plane != NONE) continue;
            if (A3_PUSH(pcs, j.n, cap, pi)) goto done;
            A->pc[pi].plane = PLANE_LISTED;
        }
    j.pcs = pcs;
    j.P = mem_malloc((j.n + 1) * sizeof *j.P);
    j.flip = mem_malloc(j.n + 1);
    if (!j.P || !j.flip) goto done;
    par_for(A->threads, (j.n + PP_CHUNK - 1) / PP_CHUNK, pp_chunk, &j);
    if (j.fail) goto done;
    for (size_t i = 0; i < j.n; i++)
        if (piece_take_plane(A, &A->pc[pcs[i]], &j.P[i], j.flip[i])) goto done;
    rc = 0;
done:
    for (size_t i = 0; i < j.n; i++) /* on failure: none left marked */
        if (A->pc[pcs[i]].plane == PLANE_LISTED) A->pc[pcs[i]].plane = NONE;
    free(pcs), free(j.P), free(j.flip);
    return rc;
}

/* The reached pieces of a chunk of pieces, listed from the chunk's own place in list (its
 * count in cnt[2 chunk]), and the entries of the others (cnt[2 chunk + 1]). */
#define RCH_CHUNK 16384
typedef struct rchjob {
    const a3 *A;
    uint32_t *list;
    size_t *cnt;
} rchjob;

static void reached_chunk(void *ctx, size_t item, int worker)
{
    (void)worker;
    const rchjob *j = ctx;
    const a3 *A = j->A;
    size_t i0 = item * RCH_CHUNK, i1 = i0 + RCH_CHUNK < A->npc ? i0 + RCH_CHUNK : A->npc, m = 0,
           e = 0;
    for (size_t i = i0; i < i1; i++) {
        const piece *pc = &A->pc[i];
        if (!pc->reached)
            e += A->pc_off[pc->c0 + 1] - A->pc_off[pc->c0];
        else
            j->list[i0 + m++] = (uint32_t)i;
    }
    j->cnt[2 * item] = m, j->cnt[2 * item + 1] = e;
}

/* Every reached piece gets its canonical plane (in piece order) and goes into A->rl; the
 * others' entries are counted (merge_planes), so that no later stage scans every piece.  The
 * scan runs on the threads, the planes are made here in order.  -1 out of memory. */
static int list_reached(a3 *A)
{
    size_t nrch = (A->npc + RCH_CHUNK - 1) / RCH_CHUNK;
    rchjob rj = {A, malloc((A->npc + 1) * sizeof *rj.list),
                 malloc((2 * nrch + 1) * sizeof *rj.cnt)};
    int rc = -1;
    A->nrl = 0, A->unreached_ent = 0;
    if (!rj.list || !rj.cnt) goto done;
    par_for(A->threads, nrch, reached_chunk, &rj);
    for (size_t ch = 0; ch < nrch; ch++) {
        A->unreached_ent += rj.cnt[2 * ch + 1];
        for (size_t k = 0; k < rj.cnt[2 * ch]; k++) {
            uint32_t i = rj.list[ch * RCH_CHUNK + k];
            if (piece_plane_id(A, i) || A3_PUSH(A->rl, A->nrl, A->caprl, i)) goto done;
        }
    }
    A->st->faces_reached += A->nrl;
    rc = 0;
done:
    free(rj.list), free(rj.cnt);
    return rc;
}

A3_STAGE static int stage_cuts(a3 *A, const uint64_t *pairs, size_t np)
{
    size_t nch = (np + CUT_CHUNK - 1) / CUT_CHUNK;
    cutjob j = {A,
                pairs,
                np,
                mem_calloc((size_t)A->threads, sizeof(cutwork)),
                mem_calloc(nch + 1, sizeof(cutout)),
                0};
    ltab lt = {0};
    uint32_t *map = NULL;
    size_t capmap = 0;
    int rc = -1;
    if (!j.w || !j.o) goto done;
    /* the pairs' pieces need their canonical planes, numbered in pair order (the ids do not
     * depend on the threads): the planes made on the threads, then numbered */
    if (pair_planes(A, pairs, np)) goto done;
    A->G.pl = A->pl;
    par_for(A->threads, nch, cut_chunk, &j);
    for (size_t ch = 0; ch < nch; ch++)
        if (j.o[ch].rc) {
            rc = j.o[ch].rc;
            goto done;
        }
    /* merge in chunk order: each LPI the global point of its triple */
    for (size_t ch = 0; ch < nch; ch++) {
        cutout *o = &j.o[ch];
        if (mem_grow(&map, &capmap, o->npt + 1, sizeof *map)) goto done;
        /* only the LPIs the cuts and contacts use (most pairs make none) */
        for (size_t i = 0; i < o->npt; i++) map[i] = NONE;
        for (size_t i = 0; i < o->ncs; i++) {
            if (o->cs[i].p0 & CUT_LOCAL) map[o->cs[i].p0 & ~CUT_LOCAL] = 0;
            if (o->cs[i].p1 & CUT_LOCAL) map[o->cs[i].p1 & ~CUT_LOCAL] = 0;
        }
        for (size_t i = 0; i < o->ncp; i++)
            if (o->cp[i].p & CUT_LOCAL) map[o->cp[i].p & ~CUT_LOCAL] = 0;
        for (size_t i = 0; i < o->nself; i++)
            if (o->selfpt[i] != NONE && (o->selfpt[i] & CUT_LOCAL))
                map[o->selfpt[i] & ~CUT_LOCAL] = 0;
        for (size_t i = 0; i < o->npt; i++) {
            if (map[i] == NONE) continue;
            const xpt *p = &o->pt[i];
            size_t h = ltab_slot(A->pt, &lt, p->a, p->b, p->c);
            if (h == SIZE_MAX) goto done;
            if (lt.id[h] == NONE) {
                if ((lt.id[h] = add_point(A, *p)) == NONE) goto done;
                lt.n++;
            }
            map[i] = lt.id[h];
        }
        for (size_t i = 0; i < o->ncs; i++) {
            cseg c = o->cs[i];
            c.p0 = merged_id(map, c.p0), c.p1 = merged_id(map, c.p1);
            if (A3_PUSH(A->cs, A->ncs, A->capcs, c)) goto done;
        }
        for (size_t i = 0; i < o->ncp; i++)
            if (add_contact(A, o->cp[i].plane, merged_id(map, o->cp[i].p))) goto done;
        for (size_t i = 0; i < o->nmet; i++) A->pc[o->met[i]].reached = 1;
        for (size_t i = 0; i < o->nself; i++) {
            size_t k = A->nselfp;
            if (A3_PUSH(A->selfp, A->nselfp, A->capselfp, o->self[i]) ||
                mem_grow(&A->selfpt, &A->capselfpt, k + 1, sizeof *A->selfpt))
                goto done;
            A->selfpt[k] = o->selfpt[i] == NONE ? NONE : merged_id(map, o->selfpt[i]);
        }
        for (size_t i = 0; i < o->nfold; i++)
            if (A3_PUSH(A->fold, A->nfold, A->capfold, o->fold[i])) goto done;
        A->st->pairs_meeting += o->npairs;
        cutout_free(o);
    }
    /* the contacts of left-out faces: their pieces are reached */
    for (size_t i = 0; i < A->ndcp; i++) {
        uint32_t pi = A->dcp[i].plane;
        if (piece_plane_id(A, pi) || add_contact(A, A->pc[pi].plane, A->dcp[i].p)) goto done;
        A->pc[pi].reached = 1;
    }
    if (A->nfold) { /* ascending, each once */
        qsort(A->fold, A->nfold, sizeof *A->fold, u32_cmp);
        size_t m = 1;
        for (size_t i = 1; i < A->nfold; i++)
            if (A->fold[i] != A->fold[m - 1]) A->fold[m++] = A->fold[i];
        A->nfold = m;
    }
    if (list_reached(A)) goto done;
    A->G.pl = A->pl;
    rc = 0;
done:
    free(lt.id);
    free(map);
    for (size_t ch = 0; j.o && ch < nch; ch++) cutout_free(&j.o[ch]);
    for (int t = 0; j.w && t < A->threads; t++) {
        for (int s = 0; s < 2; s++) free(j.w[t].e[s]), free(j.w[t].iv[s]);
        free(j.w[t].sd);
    }
    free(j.w);
    free(j.o);
    return rc;
}

/* ------------------------------------------------------------------ points, planes' inputs */

static const xpt *get_global(const void *ctx, uint32_t id)
{
    const a3 *A = ctx;
    return &A->pt[id];
}

/* Merges equal points among those the cuts made; rewrites the cuts and contacts. */
A3_STAGE static int dedup_cut_points(a3 *A, pset *ps)
{
    uint32_t *alias = mem_malloc((A->npt + 1) * sizeof *alias);
    uint8_t *near = mem_calloc(A->nv + 1, 1);
    if (!alias || !near) {
        free(alias), free(near);
        return -1;
    }
    /* A made point (here, or later in a plane) lies on a reached piece, and an input vertex at
     * the same place is one of a reached piece's own: any other piece holding it meets that one
     * there (a pair, a contact), or, of the same solid, shares it as a vertex.  So only those
     * vertices go into the set, not all of them. */
    for (size_t r = 0; r < A->nrl; r++) { /* the reached pieces (stage_cuts's list) */
        const piece *pc = &A->pc[A->rl[r]];
        for (uint32_t x = A->pc_off[pc->c0]; x < A->pc_off[pc->c0 + pc->nc]; x++)
            near[A->pcv[x]] = 1;
    }
    pset_clear(ps, 0);
    for (size_t i = 0; i < A->npt; i++) {
        alias[i] = (uint32_t)i;
        if (i < A->nv && !near[i]) continue;
        if (A->pt[i].kind != PT_GRID) {
            uint32_t q = pset_find(ps, &A->G, &A->pt[i], get_global, A);
            if (q != NONE) {
                alias[i] = q;
                continue;
            }
        }
        if (pset_add(ps, &A->pt[i], (uint32_t)i)) {
            free(alias), free(near);
            return -1;
        }
    }
    free(near);
    size_t m = 0;
    for (size_t i = 0; i < A->ncs; i++) {
        cseg c = A->cs[i];
        c.p0 = alias[c.p0], c.p1 = alias[c.p1];
        if (c.p0 == c.p1) {
            if (add_contact(A, c.plane, c.p0)) {
                free(alias);
                return -1;
            }
            continue;
        }
        A->cs[m++] = c;
    }
    A->ncs = m;
    for (size_t i = 0; i < A->ncp; i++) A->cp[i].p = alias[A->cp[i].p];
    free(alias);
    return 0;
}

/* CSR of (plane, item) lists: off[npl + 1], and a permutation of the items by plane. */
static int csr_by_plane(size_t npl, size_t n, const void *items, size_t size, size_t plane_off,
                        uint32_t **off_out, void *sorted)
{
    uint32_t *off = mem_calloc(npl + 2, sizeof *off);
    if (!off) return -1;
    const char *it = items;
    for (size_t i = 0; i < n; i++) {
        uint32_t p;
        memcpy(&p, it + i * size + plane_off, sizeof p);
        off[p + 2]++;
    }
    for (size_t p = 0; p < npl; p++) off[p + 2] += off[p + 1];
    for (size_t i = 0; i < n; i++) {
        uint32_t p;
        memcpy(&p, it + i * size + plane_off, sizeof p);
        memcpy((char *)sorted + (size_t)off[p + 1]++ * size, it + i * size, size);
    }
    *off_out = off;
    return 0;
}

static int cmp_cpt(const void *pa, const void *pb)
{
    const cpt *a = pa, *b = pb;
    if (a->plane != b->plane) return a->plane < b->plane ? -1 : 1;
    return (a->p > b->p) - (a->p < b->p);
}

A3_STAGE static int plane_inputs(a3 *A)
{
    /* reached pieces by plane (the others are faces as they are: merge_planes) */
    A->pp_off = mem_calloc(A->npl + 2, sizeof *A->pp_off);
    A->pp = mem_malloc((A->nrl + 1) * sizeof *A->pp);
    if (!A->pp_off || !A->pp) return -1;
    for (size_t k = 0; k < A->nrl; k++) A->pp_off[A->pc[A->rl[k]].plane + 2]++;
    for (size_t p = 0; p < A->npl; p++) A->pp_off[p + 2] += A->pp_off[p + 1];
    for (size_t k = 0; k < A->nrl; k++) A->pp[A->pp_off[A->pc[A->rl[k]].plane + 1]++] = A->rl[k];
    /* the planes arranged, and those holding pieces of more than one input face */
    for (size_t p = 0; p < A->npl; p++) {
        uint32_t a = A->pp_off[p], b = A->pp_off[p + 1];
        if (a == b) continue;
        A->st->planes++;
        for (uint32_t k = a + 1; k < b; k++)
            if (A->pc[A->pp[k]].face != A->pc[A->pp[a]].face) {
                A->st->coplanar_groups++;
                break;
            }
    }
    /* cuts by plane (order kept: deterministic) */
    cseg *cs = mem_malloc((A->ncs + 1) * sizeof *cs);
    if (!cs ||
        csr_by_plane(A->npl, A->ncs, A->cs, sizeof *A->cs, offsetof(cseg, plane), &A->cs_off, cs)) {
        free(cs);
        return -1;
    }
    free(A->cs);
    A->cs = cs;
    /* contact points by plane, each once */
    if (A->ncp > 1) qsort(A->cp, A->ncp, sizeof *A->cp, cmp_cpt);
    size_t m = 0;
    for (size_t i = 0; i < A->ncp; i++)
        if (!m || cmp_cpt(&A->cp[i], &A->cp[m - 1])) A->cp[m++] = A->cp[i];
    A->ncp = m;
    cpt *cp = mem_malloc((A->ncp + 1) * sizeof *cp);
    if (!cp ||
        csr_by_plane(A->npl, A->ncp, A->cp, sizeof *A->cp, offsetof(cpt, plane), &A->cp_off, cp)) {
        free(cp);
        return -1;
    }
    free(A->cp);
    A->cp = cp;
    return 0;
}

int a3_plane_fold(const a3 *A, uint32_t P)
{
    return A->nfold && bsearch(&P, A->fold, A->nfold, sizeof *A->fold, u32_cmp) != NULL;
}

int a3_plane_simple(const a3 *A, uint32_t P)
{
    if (A->cs_off[P + 1] != A->cs_off[P] || A->cp_off[P + 1] != A->cp_off[P]) return 0;
    if (a3_plane_fold(A, P)) return 0;
    if (A->pp_off[P + 1] == A->pp_off[P]) return 1;
    const piece *p0 = &A->pc[A->pp[A->pp_off[P]]];
    for (uint32_t i = A->pp_off[P]; i < A->pp_off[P + 1]; i++) {
        const piece *pc = &A->pc[A->pp[i]];
        if (pc->nc != 1 || pc->solid != p0->solid || pc->sgn != p0->sgn) return 0;
    }
    return 1;
}

const plane3 *a3_side(const a3 *A, const plane3 *FP, uint32_t a, uint32_t b, uint32_t S,
                      plane3 *tmp)
{
    if (S == NONE) return NULL;
    if (S != SIDE_LAZY) return &A->pl[S];
    /* a and b are input vertices (points a, b are their grid points) */
    if (plane_vertical(A->g + 3 * (size_t)a, A->g + 3 * (size_t)b, plane_axis(FP), tmp))
        return NULL;
    return tmp;
}

/* The vertical planes of the edges of the pieces that go through a plane arrangement (where
 * they are the lines of the segments, shared by id).  Serial: it adds planes. */
A3_STAGE static int stage_sides(a3 *A)
{
    uint32_t npl0 = (uint32_t)A->npl;
    for (uint32_t P = 0; P < npl0; P++) {
        if (A->pp_off[P + 1] == A->pp_off[P] || a3_plane_simple(A, P)) continue;
        int k = plane_axis(&A->pl[P]);
        for (uint32_t i = A->pp_off[P]; i < A->pp_off[P + 1]; i++) {
            const piece *pc = &A->pc[A->pp[i]];
            for (uint32_t cy = pc->c0; cy < pc->c0 + pc->nc; cy++) {
                uint32_t o = A->pc_off[cy], n = A->pc_off[cy + 1] - o;
                for (uint32_t j = 0; j < n; j++) {
                    if (A->pcvp[o + j] != SIDE_LAZY) continue;
                    uint32_t vid = vertical_id(A, A->pcv[o + j], A->pcv[o + (j + 1) % n], k);
                    if (vid >= NONE - 1)
                        return -1; /* out of memory (or an edge along e_k,
                                      which add_piece has refused) */
                    A->pcvp[o + j] = vid;
                }
            }
        }
    }
    if (A->npl == npl0) return 0;
    /* the new planes hold no pieces, cuts or contact points: extend the offsets */
    uint32_t **off[3] = {&A->pp_off, &A->cs_off, &A->cp_off};
    for (int i = 0; i < 3; i++) {
        uint32_t *o = mem_realloc(*off[i], (A->npl + 2) * sizeof *o);
        if (!o) return -1;
        for (size_t P = npl0 + 1; P < A->npl + 2; P++) o[P] = o[npl0];
        *off[i] = o;
    }
    return 0;
}

/* ------------------------------------------------------------------ merge the planes */

typedef struct newctx {
    const a3 *A;
    const pfaces *F;
} newctx;

void pfaces_free(pfaces *f)
{
    free(f->f_cyc);
    free(f->cyc_off);
    free(f->ent);
    free(f->side);
    free(f->f_cov);
    free(f->cov);
    free(f->newp);
    free(f->direct);
    memset(f, 0, sizeof *f);
}

/* Piece pi written as a face of the complex as it is: its outer cycle counter-clockwise about
 * its plane's normal (its only cycle: a piece with holes is always reached). */
static void put_piece_face(a3 *A, uint32_t pi, size_t *ncov, uint32_t *pe2e)
{
    const piece *pc = &A->pc[pi];
    uint32_t o = A->pc_off[pc->c0], n = A->pc_off[pc->c0 + 1] - o;
    int rev = pc->sgn < 0;
    if (pe2e) /* where each of its entries goes: the edge from entry j runs backwards when
               * the cycle is reversed, from entry (n - 2 - j) mod n */
        for (uint32_t j = 0; j < n; j++)
            pe2e[o + j] = (uint32_t)A->nent + (rev ? (2 * n - 2 - j) % n : j);
    A->f_cyc[A->nf] = (uint32_t)A->ncyc;
    A->f_cov[A->nf] = (uint32_t)*ncov;
    A->f_plane[A->nf] = pc->plane;
    A->cov[(*ncov)++] = pi;
    A->cyc_off[A->ncyc] = (uint32_t)A->nent;
    uint32_t *ent = A->ent + A->nent, *side = A->side + A->nent;
    const uint32_t *v = A->pcv + o, *vp = A->pcvp + o;
    if (!rev) {
        memcpy(ent, v, n * sizeof *ent);
        memcpy(side, vp, n * sizeof *side);
    } else {
        for (uint32_t i = 0; i < n; i++) {
            ent[i] = v[n - 1 - i];
            side[i] = vp[(2 * n - 2 - i) % n];
        }
    }
    A->nent += n;
    A->ncyc++;
    A->nf++;
}

/* The patches: the pieces that nothing reached (nc == 1), linked across their twins (whose
 * pieces nothing reached either), numbered in order of their lowest piece; pieces of each patch
 * listed in ascending order (pp_patch[ppo[k] .. ppo[k+1])).  -1 out of memory. */
/* The patches of a run of whole solids (twins never leave a solid): stage_patches' tasks, each
 * on its own range of pieces, numbering its patches from 0 in order of their lowest piece. */
typedef struct patchjob {
    const a3 *A;
    const uint32_t *r_off;       /* ranges: pieces r_off[t] .. r_off[t + 1) */
    uint32_t *stack, *lab, *epc; /* by piece: the walks' stack, the piece's patch */
    uint8_t *rch;
    uint32_t *np; /* by range: its patches, then its first patch (np[nr]: all of them) */
    uint32_t *nu; /* by range: its pieces in patches, then where the first goes in pp */
    uint32_t *ppo, *pp, *cur; /* the result; cur: by patch, where its next piece goes */
} patchjob;

static void patch_range(void *ctx, size_t t, int worker)
{
    (void)worker;
    const patchjob *j = ctx;
    const a3 *A = j->A;
    uint32_t p0 = j->r_off[t], p1 = j->r_off[t + 1], np = 0, nu = 0;
    /* a range of triangles whose entries follow each other (the usual mesh): the piece of entry
     * x is p0 + (x - e0) / 3 and its entries e0 + 3 (i - p0) .., with no map written and no
     * piece read by the walk */
    uint32_t e0 = 0, e1 = 0;
    if (p1 > p0) e0 = A->pc_off[A->pc[p0].c0], e1 = A->pc_off[A->pc[p1 - 1].c0 + A->pc[p1 - 1].nc];
    int tri = p1 > p0 && (size_t)e1 - e0 == 3 * (size_t)(p1 - p0);
    const uint8_t *rch = j->rch;
    uint32_t *lab = j->lab, *stack = j->stack + p0;  /* each piece is pushed once: p1 - p0 room */
    memset(lab + p0, 0xff, (p1 - p0) * sizeof *lab); /* NONE */
    for (uint32_t i = p0; !tri && i < p1; i++) {
        const piece *pc = &A->pc[i];
        for (uint32_t x = A->pc_off[pc->c0]; x < A->pc_off[pc->c0 + pc->nc]; x++) j->epc[x] = i;
    }
    /* each patch walked across twins from its lowest piece (patches numbered in that order) */
    for (uint32_t i = p0; i < p1; i++) {
        if (rch[i] || lab[i] != NONE) continue;
        uint32_t top = 0;
        lab[i] = np, stack[top++] = i, nu++;
        while (top) {
            uint32_t u = stack[--top], x0, x1;
            if (tri)
                x0 = e0 + 3 * (u - p0), x1 = x0 + 3;
            else
                x0 = A->pc_off[A->pc[u].c0], x1 = A->pc_off[A->pc[u].c0 + 1];
            for (uint32_t x = x0; x < x1; x++) {
                uint32_t t2 = A->ptwin[x];
                if (t2 == NONE) continue;
                uint32_t q = tri ? p0 + (t2 - e0) / 3 : j->epc[t2];
                if (rch[q] || lab[q] != NONE) continue;
                lab[q] = np, stack[top++] = q, nu++;
            }
        }
        np++;
    }
    j->np[t] = np;
    j->nu[t] = nu;
}

/* A range's patches listed: ppo[k] for its patches k, their pieces in pp. */
static void patch_fill(void *ctx, size_t t, int worker)
{
    (void)worker;
    const patchjob *j = ctx;
    uint32_t p0 = j->r_off[t], p1 = j->r_off[t + 1], k0 = j->np[t], k1 = j->np[t + 1];
    for (uint32_t k = k0; k < k1; k++) j->cur[k] = 0;
    for (uint32_t i = p0; i < p1; i++)
        if (!j->rch[i]) j->cur[j->lab[i] += k0]++;
    uint32_t at = j->nu[t];
    for (uint32_t k = k0; k < k1; k++) {
        uint32_t c = j->cur[k];
        j->ppo[k] = j->cur[k] = at;
        at += c;
    }
    for (uint32_t i = p0; i < p1; i++)
        if (!j->rch[i]) j->pp[j->cur[j->lab[i]]++] = i;
}

/* The patches: the pieces that nothing reached (nc == 1), linked across their twins (whose
 * pieces nothing reached either), numbered in order of their lowest piece; pieces of each patch
 * listed in ascending order (pp_patch[ppo[k] .. ppo[k+1])).  Runs of whole solids on the
 * threads.  -1 out of memory. */
A3_STAGE static int stage_patches(a3 *A, uint32_t **ppo_out, uint32_t **pp_out)
{
    size_t npc = A->npc, nr = 0;
    uint32_t *stack = mem_malloc((npc + 1) * sizeof *stack);
    uint32_t *lab = mem_malloc((npc + 1) * sizeof *lab);
    uint32_t *epc = mem_malloc((A->npcv + 1) * sizeof *epc), *ppo = NULL, *pp = NULL;
    uint8_t *rch = mem_malloc(npc + 1); /* the pieces' reached flags, packed: looked up at random */
    uint32_t *r_off = mem_malloc((4 * (size_t)A->threads + 3) * sizeof *r_off);
    uint32_t *np = mem_calloc(4 * (size_t)A->threads + 3, sizeof *np);
    uint32_t *nu = mem_calloc(4 * (size_t)A->threads + 3, sizeof *nu), *cur = NULL;
    int rc = -1;
    if (!stack || !lab || !epc || !rch || !r_off || !np || !nu) goto done;
    /* ranges of about npc / (4 threads) pieces, cut where a solid starts */
    size_t want = npc / (4 * (size_t)A->threads) + 1;
    r_off[nr++] = 0;
    while (nr < 4 * (size_t)A->threads + 1 && r_off[nr - 1] + want < npc) {
        size_t at = a3_solid_end(A, r_off[nr - 1] + want - 1);
        if (at >= npc) break;
        r_off[nr++] = (uint32_t)at;
    }
    r_off[nr] = (uint32_t)npc;
    /* the reached flags from stage_cuts' list, not from the 64-byte pieces (a stream of all of
     * them: 80 MB at a million faces a solid) */
    memset(rch, 0, npc);
    for (size_t k = 0; k < A->nrl; k++) rch[A->rl[k]] = 1;
    patchjob j = {A, r_off, stack, lab, epc, rch, np, nu, NULL, NULL, NULL};
    par_for(A->threads, nr, patch_range, &j);
    uint32_t total = 0, inp = 0;
    for (size_t t = 0; t < nr; t++) {
        uint32_t n = np[t], m = nu[t];
        np[t] = total, nu[t] = inp; /* the range's first patch, and its first place in pp */
        total += n, inp += m;
    }
    np[nr] = total;
    ppo = mem_malloc(((size_t)total + 2) * sizeof *ppo);
    pp = mem_malloc((npc + 1) * sizeof *pp);
    cur = mem_malloc(((size_t)total + 1) * sizeof *cur);
    if (!ppo || !pp || !cur) goto done;
    j.ppo = ppo, j.pp = pp, j.cur = cur;
    par_for(A->threads, nr, patch_fill, &j);
    ppo[total] = inp;
    A->npatch = total;
    A->st->patches = total;
    *ppo_out = ppo, *pp_out = pp;
    ppo = pp = NULL;
    rc = 0;
done:
    free(stack), free(lab), free(epc), free(ppo), free(pp), free(rch), free(r_off), free(np);
    free(nu), free(cur);
    return rc;
}

/* The patches' faces, written on the threads: face i is piece pp[i] (faces come patch by patch),
 * its entries from eoff[i]; pe2e[x] where entry x of a patch's piece went. */
typedef struct putjob {
    a3 *A;
    const uint32_t *pp, *ppo, *eoff;
    uint32_t *pe2e;
    size_t n;
    int twins; /* 0: the faces; 1: their entries' twins (pe2e complete) */
} putjob;

#define PUT_CHUNK 8192
static void put_chunk(void *ctx, size_t item, int worker)
{
    (void)worker;
    const putjob *j = ctx;
    a3 *A = j->A;
    size_t i0 = item * PUT_CHUNK, i1 = i0 + PUT_CHUNK < j->n ? i0 + PUT_CHUNK : j->n;
    for (size_t i = i0; i < i1; i++) {
        const piece *pc = &A->pc[j->pp[i]];
        uint32_t o = A->pc_off[pc->c0], n = A->pc_off[pc->c0 + 1] - o, e0 = j->eoff[i];
        if (j->twins) {
            for (uint32_t x = o; x < o + n; x++) {
                uint32_t t = A->ptwin[x];
                A->etwin[j->pe2e[x]] = t == NONE ? NONE : j->pe2e[t];
            }
            continue;
        }
        int rev = pc->sgn < 0;
        A->f_cyc[i] = (uint32_t)i;
        A->f_cov[i] = (uint32_t)i;
        A->cov[i] = j->pp[i];
        A->f_plane[i] = pc->plane;
        A->f_out[i] = pc->sgn > 0;
        A->cyc_off[i] = e0;
        uint32_t *ent = A->ent + e0, *side = A->side + e0;
        const uint32_t *v = A->pcv + o, *vp = A->pcvp + o;
        for (uint32_t t = 0; t < n; t++) {
            /* entry t goes to k: reversed, (2n - 2 - t) mod n */
            uint32_t k = !rev ? t : t + 2 <= n ? n - 2 - t : n - 1;
            j->pe2e[o + t] = e0 + k;
        }
        if (n == 3 && !rev) { /* a triangle: no call for twelve bytes */
            ent[0] = v[0], ent[1] = v[1], ent[2] = v[2];
            side[0] = vp[0], side[1] = vp[1], side[2] = vp[2];
        } else if (!rev) {
            memcpy(ent, v, n * sizeof *ent);
            memcpy(side, vp, n * sizeof *side);
        } else {
            for (uint32_t t = 0; t < n; t++) {
                ent[t] = v[n - 1 - t];
                side[t] = vp[t + 2 <= n ? n - 2 - t : n - 1];
            }
        }
    }
}

/* Every plane's new points join the global ones (deduplicated), and the faces of the complex
 * are written with global point ids, unit by unit: first the patches (each one's pieces as they
 * are, in piece order), then each plane's: its pieces kept as they are, then the faces of its
 * arrangement, each a unit of its own.  The entries of a patch's faces get their twins. */
A3_STAGE static int merge_planes(a3 *A, pset *ps)
{
    uint32_t *map = NULL, *ppo = NULL, *pp = NULL, *pe2e = NULL;
    size_t capmap = 0, nf = 0, ncyc = 0, nent = 0, ncov = 0;
    int rc = -1;
    if (stage_patches(A, &ppo, &pp)) goto done;
    A3_TICK("m/patches");
    if (a3_cancelled(A)) {
        rc = -3;
        goto done;
    }
    /* sizes first: the pieces nothing reached (one cycle each), counted by stage_cuts */
    nf = ncyc = ncov = A->npc - A->nrl;
    nent = A->unreached_ent;
    for (size_t p = 0; p < A->npl; p++) {
        const pfaces *F = &A->pf[p];
        uint32_t nd = F->trivial ? A->pp_off[p + 1] - A->pp_off[p] : F->ndirect;
        for (uint32_t k = 0; k < nd; k++) {
            const piece *pc = &A->pc[F->trivial ? A->pp[A->pp_off[p] + k] : F->direct[k]];
            nf++, ncyc++, ncov++;
            nent += A->pc_off[pc->c0 + 1] - A->pc_off[pc->c0];
        }
        if (F->trivial) continue;
        nf += F->nf, ncyc += F->ncyc, ncov += F->ncov;
        nent += F->nent;
    }
    A->f_cyc = mem_malloc((nf + 1) * sizeof *A->f_cyc);
    A->f_plane = mem_malloc((nf + 1) * sizeof *A->f_plane);
    A->f_cov = mem_malloc((nf + 1) * sizeof *A->f_cov);
    A->cyc_off = mem_malloc((ncyc + 1) * sizeof *A->cyc_off);
    A->ent = mem_malloc((nent + 1) * sizeof *A->ent);
    A->side = mem_malloc((nent + 1) * sizeof *A->side);
    A->cov = mem_malloc((ncov + 1) * sizeof *A->cov);
    A->u_off = mem_malloc((nf + 2) * sizeof *A->u_off);
    A->f_unit = mem_malloc((nf + 1) * sizeof *A->f_unit);
    A->f_out = mem_calloc(nf + 1, 1);
    A->etwin = mem_malloc((nent + 1) * sizeof *A->etwin);
    pe2e = mem_malloc((A->npcv + 1) * sizeof *pe2e);
    if (!A->f_cyc || !A->f_plane || !A->f_cov || !A->cyc_off || !A->ent || !A->side || !A->cov ||
        !A->u_off || !A->f_unit || !A->f_out || !A->etwin || !pe2e)
        goto done;
    memset(pe2e, 0xff, (A->npcv + 1) * sizeof *pe2e); /* NONE: not in a patch */
    A3_TICK("m/alloc");
    /* the patches: their faces, then their entries' twins (a twin in no patch: NONE), on the
     * threads */
    {
        size_t npf = A->npatch ? ppo[A->npatch] : 0;
        uint32_t *eoff = mem_malloc((npf + 1) * sizeof *eoff);
        if (!eoff) goto done;
        uint32_t e = 0;
        for (size_t i = 0; i < npf; i++) {
            const piece *pc = &A->pc[pp[i]];
            eoff[i] = e;
            e += A->pc_off[pc->c0 + 1] - A->pc_off[pc->c0];
        }
        for (size_t k = 0; k < A->npatch; k++) {
            A->u_off[k] = ppo[k];
            for (uint32_t i = ppo[k]; i < ppo[k + 1]; i++) A->f_unit[i] = (uint32_t)k;
        }
        A3_TICK("m/offsets");
        putjob j = {A, pp, ppo, eoff, pe2e, npf, 0};
        par_for(A->threads, (npf + PUT_CHUNK - 1) / PUT_CHUNK, put_chunk, &j);
        A3_TICK("m/put");
        j.twins = 1;
        par_for(A->threads, (npf + PUT_CHUNK - 1) / PUT_CHUNK, put_chunk, &j);
        A3_TICK("m/twins");
        free(eoff);
        A->nf = A->ncyc = ncov = npf;
        A->nent = e;
        A->nunit = A->npatch;
    }
    for (size_t p = 0; p < A->npl; p++) {
        pfaces *F = &A->pf[p];
        uint32_t nd = F->trivial ? A->pp_off[p + 1] - A->pp_off[p] : F->ndirect;
        for (uint32_t k = 0; k < nd; k++) {
            A->u_off[A->nunit] = (uint32_t)A->nf;
            A->f_unit[A->nf] = (uint32_t)A->nunit++;
            put_piece_face(A, F->trivial ? A->pp[A->pp_off[p] + k] : F->direct[k], &ncov, NULL);
        }
        if (F->trivial) continue;
        if (!F->nf && !F->nnew) {
            pfaces_free(F);
            continue;
        }
        if (mem_grow(&map, &capmap, F->nnew + 1, sizeof *map)) goto done;
        for (uint32_t i = 0; i < F->nnew; i++) {
            uint32_t q = pset_find(ps, &A->G, &F->newp[i], get_global, A);
            if (q == NONE) {
                q = add_point(A, F->newp[i]);
                if (q == NONE || pset_add(ps, &F->newp[i], q)) goto done;
            }
            map[i] = q;
        }
        for (uint32_t f = 0; f < F->nf; f++) {
            A->u_off[A->nunit] = (uint32_t)A->nf;
            A->f_unit[A->nf] = (uint32_t)A->nunit++;
            A->f_cyc[A->nf] = (uint32_t)A->ncyc;
            A->f_cov[A->nf] = (uint32_t)ncov;
            A->f_plane[A->nf] = (uint32_t)p;
            for (uint32_t c = F->f_cyc[f]; c < F->f_cyc[f + 1]; c++) {
                A->cyc_off[A->ncyc] = (uint32_t)A->nent;
                for (uint32_t e = F->cyc_off[c]; e < F->cyc_off[c + 1]; e++) {
                    uint32_t v = F->ent[e];
                    A->ent[A->nent] = v >= F->base ? map[v - F->base] : v;
                    A->side[A->nent] = F->side[e];
                    A->nent++;
                }
                A->ncyc++;
            }
            for (uint32_t i = F->f_cov[f]; i < F->f_cov[f + 1]; i++) A->cov[ncov++] = F->cov[i];
            A->nf++;
        }
        pfaces_free(F);
    }
    A->f_cyc[A->nf] = (uint32_t)A->ncyc;
    A->f_cov[A->nf] = (uint32_t)ncov;
    A->cyc_off[A->ncyc] = (uint32_t)A->nent;
    A->u_off[A->nunit] = (uint32_t)A->nf;
    /* entries of faces in no patch: no twin */
    for (size_t x = A->u_off[A->npatch] < A->nf ? A->cyc_off[A->f_cyc[A->u_off[A->npatch]]]
                                                : A->nent;
         x < A->nent; x++)
        A->etwin[x] = NONE;
    rc = 0;
done:
    free(map), free(ppo), free(pp), free(pe2e);
    return rc;
}

/* ------------------------------------------------------------------ entry */

static void a3_free(a3 *A)
{
    free(A->g);
    free(A->pl);
    free(A->pltab);
    free(A->vpkey);
    free(A->vpval);
    free(A->pc);
    free(A->dcp);
    free(A->selfp);
    free(A->selfpt);
    free(A->fold);
    free(A->pc_off);
    free(A->pcv);
    free(A->pcvp);
    free(A->ptwin);
    free(A->rl);
    free(A->twinned);
    free(A->solid_face_off);
    free(A->pt);
    free(A->pp_off);
    free(A->pp);
    free(A->cs);
    free(A->cp);
    free(A->cs_off);
    free(A->cp_off);
    for (size_t p = 0; A->pf && p < A->npl; p++) pfaces_free(&A->pf[p]);
    free(A->pf);
    free(A->f_plane);
    free(A->f_cyc);
    free(A->cyc_off);
    free(A->ent);
    free(A->side);
    free(A->f_cov);
    free(A->cov);
    free(A->u_off);
    free(A->f_unit);
    free(A->f_out);
    free(A->etwin);
}

/* The solids whose surfaces pass through themselves, from the pairs of one solid that met
 * (their order is the pairs', so the first is the same on any number of threads).  -1 out of
 * memory. */
static int self_report(const a3 *A, lar3 *out)
{
    for (size_t i = 0; i < A->nselfp; i++) {
        uint32_t a = (uint32_t)(A->selfp[i] >> 32), b = (uint32_t)A->selfp[i];
        uint32_t s = A->pc[a].solid;
        size_t k = 0;
        while (k < out->nselfx && out->selfx[k].solid != s) k++;
        if (k < out->nselfx) {
            out->selfx[k].pairs++;
            continue;
        }
        arr3_selfx *x = realloc(out->selfx, (k + 1) * sizeof *x);
        if (!x) return -1;
        out->selfx = x;
        x += k;
        x->solid = s, x->pairs = 1;
        x->fa = A->pc[a].face - out->solid_face_off[s];
        x->fb = A->pc[b].face - out->solid_face_off[s];
        uint32_t p = A->selfpt[i];
        if (p == NONE) p = A->pcv[A->pc_off[A->pc[a].c0]]; /* overlapping: a vertex of one */
        for (int t = 0; t < 3; t++) x->at[t] = ((double)A->oi[t] + A->pt[p].x[t]) * A->step;
        out->nselfx = k + 1;
    }
    /* ascending by solid */
    for (size_t i = 1; i < out->nselfx; i++)
        for (size_t j = i; j > 0 && out->selfx[j - 1].solid > out->selfx[j].solid; j--) {
            arr3_selfx t = out->selfx[j];
            out->selfx[j] = out->selfx[j - 1], out->selfx[j - 1] = t;
        }
    return 0;
}

int arr3_build(const solid *solids, size_t ns, int soup, const arr3_opts *opts, lar3 *out,
               char *err, size_t errlen)
{
    return arr3_build_ex(solids, ns, soup, NULL, opts, out, err, errlen);
}

int arr3_build_ex(const solid *solids, size_t ns, int soup, const uint32_t *const *twins,
                  const arr3_opts *opts, lar3 *out, char *err, size_t errlen)
{
    static const arr3_opts defaults = {0};
    a3 A = {0};
    pset ps = {0};
    uint64_t *pairs = NULL;
    size_t np = 0;
    int rc = ARR_OK, r;
    double t0 = now_ms(), t;
    memset(out, 0, sizeof *out);
    if (err && errlen) err[0] = 0;
    A.o = opts ? opts : &defaults;
    A.threads = A.o->threads > 0 ? A.o->threads : par_ncpu();
    A.st = &out->stats;
    A.soup = soup;
    a3_progress(&A, "snap", 0);
    A3_TICK(NULL);
    if ((rc = stage_input(&A, solids, ns, soup ? NULL : twins, err, errlen))) goto fail;
    A3_TICK("input");
    if (a3_cancelled(&A)) goto cancel;
    a3_progress(&A, "snap", 1);
    out->nsolids = ns;
    out->solid_face_off = A.solid_face_off;
    A.solid_face_off = NULL;
    A.G.g = A.g;
    A.G.pl = A.pl;
    if (A.nv >= CUT_LOCAL - 1 || mem_grow(&A.pt, &A.cappt, A.nv + 1, sizeof *A.pt)) goto oom;
    par_for(A.threads, (A.nv + SNAP_CHUNK - 1) / SNAP_CHUNK, grid_points, &A);
    A.npt = A.nv;
    A3_TICK("points");
    if (stage_twins(&A)) goto oom;
    A3_TICK("twins");
    if (a3_cancelled(&A)) goto cancel;
    out->stats.split_faces = A.split_faces;
    out->stats.ms_snap = now_ms() - t0;
    t = now_ms();
    if ((r = a3_pairs(&A, &pairs, &np)) == -3) goto cancel;
    if (r) goto oom;
    A3_TICK("pairs");
    if (a3_cancelled(&A)) goto cancel;
    out->stats.pairs_tested = np;
    out->stats.ms_pairs = now_ms() - t;
    a3_progress(&A, "pairs", 1);
    t = now_ms();
    np = drop_apart(&A, pairs, np);
    r = stage_cuts(&A, pairs, np);
    if (r == -3) goto cancel;
    if (r) goto oom;
    free(pairs);
    pairs = NULL;
    if (A.nselfp && self_report(&A, out)) goto oom;
    out->stats.cuts = A.ncs / 2;
    A3_TICK("cuts");
    if (dedup_cut_points(&A, &ps) || plane_inputs(&A) || stage_sides(&A)) goto oom;
    A3_TICK("dedup+inputs");
    A.G.pl = A.pl; /* stage_sides may have moved the planes */
    out->stats.ms_cuts = now_ms() - t;
    if (a3_cancelled(&A)) goto cancel;
    t = now_ms();
    if ((rc = a3_planes(&A, err, errlen)) != ARR_OK) goto fail;
    A3_TICK("planes");
    if (a3_cancelled(&A)) goto cancel;
    size_t npt_before = A.npt;
    if ((r = merge_planes(&A, &ps)) == -3) goto cancel;
    if (r) goto oom;
    A3_TICK("merge");
    pset_free(&ps);
    out->stats.points = A.npt - A.nv;
    (void)npt_before;
    out->stats.ms_faces = now_ms() - t;
    a3_progress(&A, "planes", 1);
    if (a3_cancelled(&A)) goto cancel;
    t = now_ms();
    if ((rc = a3_cells(&A, out, err, errlen)) != ARR_OK) goto fail;
    out->stats.ms_cells = now_ms() - t;
    out->stats.ms_total = now_ms() - t0;
    a3_progress(&A, "cells", 1);
    a3_free(&A);
    return ARR_OK;
cancel:
    rc = util_seterr(err, errlen, ARR_ECANCELED, "cancelled");
    goto fail;
oom:
    rc = util_seterr(err, errlen, ARR_ENOMEM, "out of memory");
fail : {
    arr3_stats keep = out->stats;
    lar3_free(out);
    out->stats = keep;
}
    free(pairs);
    pset_free(&ps);
    a3_free(&A);
    return rc;
}

void lar3_free(lar3 *c)
{
    free(c->V);
    free(c->EV);
    free(c->FN);
    free(c->fc_off);
    free(c->fc);
    free(c->fe_off);
    free(c->fe);
    free(c->fsrc);
    free(c->cyc_off);
    free(c->cyc);
    free(c->cf_off);
    free(c->cf);
    free(c->cv_off);
    free(c->cv);
    free(c->cvol);
    free(c->ext);
    free(c->solid_face_off);
    free(c->fsol_off);
    free(c->fsol);
    free(c->fwind);
    free(c->selfx);
    free(c->u_off);
    free(c->ucell);
    free(c->frev);
    memset(c, 0, sizeof *c);
}

double lar3_face_cone(const lar3 *c, uint32_t f)
{
    double s = 0;
    for (uint32_t cy = c->fc_off[f]; cy < c->fc_off[f + 1]; cy++) {
        uint32_t c0 = c->cyc_off[c->fc[cy]], c1 = c->cyc_off[c->fc[cy] + 1];
        const double *p0 = c->V + 3 * (size_t)c->cyc[c0];
        for (uint32_t i = c0 + 1; i + 1 < c1; i++) {
            const double *p1 = c->V + 3 * (size_t)c->cyc[i], *p2 = c->V + 3 * (size_t)c->cyc[i + 1];
            s += p0[0] * (p1[1] * p2[2] - p1[2] * p2[1]) - p0[1] * (p1[0] * p2[2] - p1[2] * p2[0]) +
                 p0[2] * (p1[0] * p2[1] - p1[1] * p2[0]);
        }
    }
    return s / 6;
}
