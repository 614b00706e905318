/* arr2.c — the planar arrangement of segments (DESIGN.md, "The 2D pipeline").
 *
 * Stages, each a function below, all on integer grid coordinates (core/num.h):
 *   snap        map coordinates to the grid (step = precision), drop zero-length segments
 *   buckets     box-kd-tree of the segments' boxes (core/box.h)
 *   intersect   per bucket, in parallel: each pair tested once (in the bucket holding the
 *               corner (max x0, max y0) of the two boxes), exact orientation tests; a proper
 *               crossing is rounded to its pixel (a "hot pixel"); endpoints are hot too
 *   split       snap rounding: per bucket, each hot pixel against each segment whose box holds
 *               it (exact half-open pixel test); per segment, its hot pixels sorted along it
 *               become its edges.  A segment is split at every hot pixel it passes through,
 *               not only at its own crossings, so rounding never creates a crossing and no
 *               vertex ever lies inside an edge.  Collinear overlaps come out as identical
 *               edges, which the sort merges.
 *   graph       edges sorted and made unique; vertices in lexicographic order
 *   biconnected edges sorted around each vertex by exact angle, half-edge walks (each
 *               half-edge's successor, and the walks' areas, in parallel): an edge with one
 *               walk on both sides is a bridge, and blocks = components + the walks'
 *               repeated visits (block-cut tree); bridges (blocks of one edge: dangling trees)
 *               removed unless keep_dangling, with the vertices left without edges, and the
 *               walks made again
 *               (the half-edge topology is core/planar.c's kernel, arr2 one model of it: its
 *               traits order grid directions by dir_cmp; sorts and successors by chunks on
 *               the threads, the cycles by planar_cycles)
 *   faces       positive walks are bounded faces, the others the outer walks of components
 *               (union-find over the edges)
 *   holes       each component's outer walk is placed by a downward ray from its lowest
 *               vertex: the first edge of another component below it tells the face that
 *               contains it (a hole of that face) or the component it sits beside (same
 *               face as that one).  Chains only go down, so they end.  The first edge comes
 *               from the kernel's planar_place (its slab index over grid x; this model's
 *               scan: exact fractions, hit_below)
 *
 * Memory: flat arrays and per-worker buffers; nothing is allocated per element.
 * Thread use: par_for() in intersect, split, the sorts around vertices, the walks' successors
 * and areas, and the holes' rays; everything else on the calling thread.
 */
#include "core/arr2.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/box.h"
#include "core/num.h"
#include "core/par.h"
#include "core/planar.h"
#include "core/sort.h"
#include "core/stop.h"
#include "core/util.h"

#define MAXW      64 /* most workers */
#define LEAF_MAX  24 /* bucket size aimed at */
#define NONE      UINT32_MAX
#define SEG_CHUNK 512 /* segments per work item in the split stage */

typedef struct seg2 {
    ipt a, b;     /* a < b lexicographically */
    uint32_t id;  /* the input segment */
    uint32_t rev; /* 1 when the input ran from b to a */
} seg2;

typedef struct vbuf {
    void *p;
    size_t n, cap; /* in elements */
} vbuf;

typedef struct scratch {
    i128 *key;
    uint32_t *val;
    size_t cap;
} scratch;

typedef struct ctx {
    const arr2_opts *o;
    const double *in; /* the input segments (borrowed) */
    size_t n_in;      /* their number */
    int threads;
    atomic_int fail; /* set by workers: ARR_ENOMEM or ARR_ECANCELED */
    /* snap */
    double step;        /* grid step */
    double origin_d[2]; /* grid index of the origin per axis, as a double */
    int64_t origin[2];  /* same, when it fits in 2^52 (origin_int) */
    int origin_int[2];
    seg2 *seg;
    size_t m;
    int64_t *box; /* 4 per segment */
    box_tree tree;
    /* intersect: per worker */
    vbuf cross[MAXW]; /* ipt */
    size_t pairs[MAXW];
    /* hot pixels */
    ipt *pix;
    size_t npix;
    uint32_t *pl_off, *pl_pix; /* pixels grouped by leaf */
    vbuf inc[MAXW];            /* uint64: seg << 32 | pixel */
    uint32_t *sp_off, *sp_pix; /* pixels grouped by segment */
    vbuf edges[MAXW];          /* uint64: v0 << 32 | v1 */
    vbuf etags[MAXW];          /* uint32: with opts.tags, the tag of each edge in edges */
    /* with input_coords: pixels near a segment not routed through them, and those segments */
    vbuf nearp[MAXW], nears[MAXW]; /* uint32 */
    struct nbox *nbox;             /* by tree item: its segment's box, each leaf's by x0 */
    uint8_t *pinned;               /* npix: the vertex keeps its grid coordinates */
    uint32_t *ep; /* with input_coords, 2n: the pixel of input endpoint 2i + k (NONE: not known) */
    scratch scr[MAXW];
    stop_meter meter[MAXW]; /* each worker's cancel meter */
    stop_meter serial;      /* the calling thread's, in the serial stages */
} ctx;

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

/* Room for need elements of elem bytes in v (core/mem.h's growable array). */
static inline int vbuf_reserve(vbuf *v, size_t need, size_t elem)
{
    return mem_grow(&v->p, &v->cap, need, elem);
}

static int cancelled(const ctx *c)
{
    return c->o->cancel && atomic_load(c->o->cancel);
}

/* A part [lo, hi] of a stage, for par_for_ex's tick. */
typedef struct span {
    const ctx *c;
    const char *stage;
    double lo, hi;
} span;
static void span_tick(void *sp, double f);

static void progress(const ctx *c, const char *stage, double f)
{
    if (c->o->progress) c->o->progress(c->o->udata, stage, f);
}

static void span_tick(void *sp, double f)
{
    const span *p = sp;
    progress(p->c, p->stage, p->lo + (p->hi - p->lo) * f);
}

/* ---- snap ------------------------------------------------------------------------------ */

/* Grid coordinates are relative to an origin near the centre of the input's box, so they stay
 * below 2^(ARR2_GRID_BITS-1) + 1 in magnitude.  When the origin's grid index is small enough,
 * output coordinates are (origin + g) * step: a coordinate that was on the grid comes back
 * exactly (0.3 with precision 0.01 gives 0.3, not 0.2999...). */
/* llround's rule, inline (round_half_away): |v| / step <= 2^52 here, as stage_snap's step is
 * never finer than the doubles at the largest coordinate */
static int64_t snap_coord(const ctx *c, int axis, double v)
{
    if (c->origin_int[axis]) return round_half_away(v / c->step) - c->origin[axis];
    return round_half_away((v - c->origin_d[axis] * c->step) / c->step);
}

static double unsnap(const ctx *c, int axis, int64_t g)
{
    if (c->origin_int[axis]) return (double)(c->origin[axis] + g) * c->step;
    return c->origin_d[axis] * c->step + (double)g * c->step;
}

/* Interleaves the low 16 bits of x and y (a Morton code). */
static uint32_t morton16(uint32_t x, uint32_t y)
{
    uint64_t v = x | (uint64_t)y << 32;
    v = (v | v << 8) & 0x00ff00ff00ff00ffull;
    v = (v | v << 4) & 0x0f0f0f0f0f0f0f0full;
    v = (v | v << 2) & 0x3333333333333333ull;
    v = (v | v << 1) & 0x5555555555555555ull;
    return (uint32_t)(v | v >> 31);
}

/* Puts the segments in Morton order of their midpoints, so that a bucket's segments sit close
 * together in memory (every later stage walks the buckets).  The order of segments changes
 * nothing else: results are sorted by geometry. */
static int spatial_order(ctx *c)
{
    if (c->m < 2) return 0;
    uint64_t *key = malloc(c->m * sizeof *key);
    seg2 *tmp = malloc(c->m * sizeof *tmp);
    if (!key || !tmp) {
        free(key);
        free(tmp);
        return -1;
    }
    int64_t lo[2] = {INT64_MAX, INT64_MAX}, hi[2] = {INT64_MIN, INT64_MIN};
    for (size_t i = 0; i < c->m; i++) {
        int64_t mx = (c->seg[i].a.x + c->seg[i].b.x) / 2, my = (c->seg[i].a.y + c->seg[i].b.y) / 2;
        lo[0] = mx < lo[0] ? mx : lo[0];
        hi[0] = mx > hi[0] ? mx : hi[0];
        lo[1] = my < lo[1] ? my : lo[1];
        hi[1] = my > hi[1] ? my : hi[1];
    }
    int sh = 0;
    while (((hi[0] - lo[0]) >> sh) > 65535 || ((hi[1] - lo[1]) >> sh) > 65535) sh++;
    for (size_t i = 0; i < c->m; i++) {
        int64_t mx = (c->seg[i].a.x + c->seg[i].b.x) / 2, my = (c->seg[i].a.y + c->seg[i].b.y) / 2;
        uint32_t code = morton16((uint32_t)((mx - lo[0]) >> sh), (uint32_t)((my - lo[1]) >> sh));
        key[i] = (uint64_t)code << 32 | i;
    }
    if (sort_u64(key, c->m)) {
        free(key);
        free(tmp);
        return -1;
    }
    for (size_t i = 0; i < c->m; i++) tmp[i] = c->seg[(uint32_t)key[i]];
    free(c->seg);
    c->seg = tmp;
    free(key);
    return 0;
}

static int stage_snap(ctx *c, const double *s, size_t n, arr2_stats *st, char *err, size_t el)
{
    double minx = INFINITY, miny = INFINITY, maxx = -INFINITY, maxy = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        for (int k = 0; k < 4; k++)
            if (!isfinite(s[4 * i + k]))
                return util_seterr(err, el, ARR_EINVAL, "lines[%zu][%d]: expected 2 finite numbers",
                                   i, k / 2);
        for (int k = 0; k < 4; k += 2) {
            double x = s[4 * i + k], y = s[4 * i + k + 1];
            minx = x < minx ? x : minx;
            maxx = x > maxx ? x : maxx;
            miny = y < miny ? y : miny;
            maxy = y > maxy ? y : maxy;
        }
    }
    double w = n ? maxx - minx : 0, h = n ? maxy - miny : 0, ext = w > h ? w : h;
    if (n && !isfinite(ext))
        return util_seterr(err, el, ARR_ELIMIT,
                           "lines: the coordinates span more than a double holds");
    double p = c->o->precision;
    if (p != 0 && !(isfinite(p) && p > 0))
        return util_seterr(err, el, ARR_EINVAL, "options.precision: expected a number > 0");
    /* The finest grid the doubles where the drawing lies can write: twice their spacing at its
     * largest coordinate (mag < 2^em, where doubles are 2^(em-53) apart).  Grid points k * p
     * with p at least that are then distinct doubles, in the order of k, after rounding. */
    int em = 0;
    double mag = n ? fmax(fmax(fabs(minx), fabs(maxx)), fmax(fabs(miny), fabs(maxy))) : 0;
    frexp(mag, &em);
    double finest = ldexp(1.0, em - 52);
    if (p == 0) {
        if (n == 0 || ext == 0)
            p = 1;
        else {
            int e;
            frexp(ext, &e); /* ext <= 2^e */
            p = ldexp(1.0, e - ARR2_GRID_BITS);
            if (p < finest) p = finest;
        }
    } else if (n && ext > 0 && p < finest) {
        return util_seterr(err, el, ARR_ELIMIT,
                           "options.precision: %g is finer than the doubles near %g (the drawing's "
                           "largest coordinate) can write distinct points; use precision >= %g",
                           p, mag, finest);
    } else if (ext / p > ldexp(1.0, ARR2_GRID_BITS)) {
        return util_seterr(err, el, ARR_ELIMIT,
                           "options.precision: %g is too fine for a drawing %g wide (at most 2^%d "
                           "grid steps across; use precision >= %g)",
                           p, ext, ARR2_GRID_BITS, ext / ldexp(1.0, ARR2_GRID_BITS));
    }
    if (!isfinite(ext / p) || p < 1e-300)
        return util_seterr(err, el, ARR_ELIMIT, "options.precision: %g is out of range", p);
    c->step = p;
    st->precision = p;
    double centre[2] = {n ? minx / 2 + maxx / 2 : 0, n ? miny / 2 + maxy / 2 : 0};
    for (int a = 0; a < 2; a++) {
        c->origin_d[a] = nearbyint(centre[a] / p);
        c->origin_int[a] = fabs(c->origin_d[a]) < 4503599627370496.0; /* 2^52 */
        c->origin[a] = c->origin_int[a] ? (int64_t)c->origin_d[a] : 0;
    }

    c->seg = malloc((n ? n : 1) * sizeof *c->seg);
    if (!c->seg) return util_seterr(err, el, ARR_ENOMEM, "out of memory");
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        ipt a = {snap_coord(c, 0, s[4 * i]), snap_coord(c, 1, s[4 * i + 1])};
        ipt b = {snap_coord(c, 0, s[4 * i + 2]), snap_coord(c, 1, s[4 * i + 3])};
        int k = ipt_cmp(a, b);
        if (k == 0) continue;
        c->seg[m].a = k < 0 ? a : b;
        c->seg[m].b = k < 0 ? b : a;
        c->seg[m].id = (uint32_t)i;
        c->seg[m].rev = k > 0;
        m++;
    }
    c->m = m;
    st->zero_length = n - m;
    return spatial_order(c) ? util_seterr(err, el, ARR_ENOMEM, "out of memory") : ARR_OK;
}

/* The bound every predicate relies on (core/num.h); the snap stage guarantees it, this
 * checks it rather than assuming it. */
static int check_range(const ctx *c, char *err, size_t el)
{
    const int64_t lim = (int64_t)1 << (ARR2_GRID_BITS + 1);
    for (size_t i = 0; i < c->m; i++) {
        const seg2 *s = &c->seg[i];
        if (llabs(s->a.x) > lim || llabs(s->a.y) > lim || llabs(s->b.x) > lim ||
            llabs(s->b.y) > lim)
            return util_seterr(err, el, ARR_EINTERNAL,
                               "internal: a snapped coordinate is out of range");
    }
    return ARR_OK;
}

/* ---- intersect ------------------------------------------------------------------------- */

/* For worker w, after `work` units of work (stop.h): non-zero when the job failed or was
 * cancelled. */
static int worker_stop(ctx *c, int w, size_t work)
{
    if (atomic_load_explicit(&c->fail, memory_order_relaxed)) return 1;
    if (stop_poll(&c->meter[w], work)) {
        atomic_store(&c->fail, ARR_ECANCELED);
        return 1;
    }
    return 0;
}

static void intersect_leaf(void *vc, size_t l, int w)
{
    ctx *c = vc;
    const uint32_t *it = c->tree.items + c->tree.leaf_off[l];
    size_t k = c->tree.leaf_off[l + 1] - c->tree.leaf_off[l];
    const double *r = c->tree.region + 4 * l;
    vbuf *out = &c->cross[w];
    size_t pairs = 0;
    for (size_t i = 0; i < k; i++) {
        if (worker_stop(c, w, k - i)) return; /* the pairs of this row */
        const int64_t *bi = c->box + 4 * (size_t)it[i];
        const seg2 *si = &c->seg[it[i]];
        for (size_t j = i + 1; j < k; j++) {
            const int64_t *bj = c->box + 4 * (size_t)it[j];
            if (bi[2] < bj[0] || bj[2] < bi[0] || bi[3] < bj[1] || bj[3] < bi[1]) continue;
            double rx = (double)(bi[0] > bj[0] ? bi[0] : bj[0]);
            double ry = (double)(bi[1] > bj[1] ? bi[1] : bj[1]);
            if (!(rx > r[0] && rx <= r[2] && ry > r[1] && ry <= r[3])) continue;
            pairs++;
            const seg2 *sj = &c->seg[it[j]];
            i128 o1 = orient2(si->a, si->b, sj->a), o2 = orient2(si->a, si->b, sj->b);
            if (o1 == 0 || o2 == 0 || (o1 > 0) == (o2 > 0)) continue;
            i128 o3 = orient2(sj->a, sj->b, si->a), o4 = orient2(sj->a, sj->b, si->b);
            if (o3 == 0 || o4 == 0 || (o3 > 0) == (o4 > 0)) continue;
            /* proper crossing: a + (b - a) * tn / den, rounded to its pixel */
            int64_t dx = si->b.x - si->a.x, dy = si->b.y - si->a.y;
            int64_t ex = sj->b.x - sj->a.x, ey = sj->b.y - sj->a.y;
            i128 den = cross2(dx, dy, ex, ey);
            i128 tn = cross2(sj->a.x - si->a.x, sj->a.y - si->a.y, ex, ey);
            if (den < 0) {
                den = -den;
                tn = -tn;
            }
            ipt p = {si->a.x + rounddiv128((i128)dx * tn, den),
                     si->a.y + rounddiv128((i128)dy * tn, den)};
            if (vbuf_reserve(out, out->n + 1, sizeof(ipt))) {
                atomic_store(&c->fail, ARR_ENOMEM);
                return;
            }
            ((ipt *)out->p)[out->n++] = p;
        }
    }
    c->pairs[w] += pairs;
}

/* ---- split (snap rounding) ----------------------------------------------------------------- */

static void hotpixel_leaf(void *vc, size_t l, int w)
{
    ctx *c = vc;
    const uint32_t *it = c->tree.items + c->tree.leaf_off[l];
    size_t k = c->tree.leaf_off[l + 1] - c->tree.leaf_off[l];
    vbuf *out = &c->inc[w];
    if (worker_stop(c, w, 1)) return;
    for (uint32_t q = c->pl_off[l]; q < c->pl_off[l + 1]; q++) {
        if (worker_stop(c, w, k)) return; /* this pixel against the leaf's segments */
        uint32_t pid = c->pl_pix[q];
        ipt p = c->pix[pid];
        for (size_t i = 0; i < k; i++) {
            const int64_t *b = c->box + 4 * (size_t)it[i];
            if (p.x < b[0] || p.x > b[2] || p.y < b[1] || p.y > b[3]) continue;
            const seg2 *s = &c->seg[it[i]];
            if (!seg_hits_pixel(s->a, s->b, p)) continue;
            if (vbuf_reserve(out, out->n + 1, sizeof(uint64_t))) {
                atomic_store(&c->fail, ARR_ENOMEM);
                return;
            }
            ((uint64_t *)out->p)[out->n++] = (uint64_t)it[i] << 32 | pid;
        }
    }
}

/* Sorts key[0..n) ascending, carrying val; keys are distinct. */
static void sort_keyed(i128 *key, uint32_t *val, size_t n)
{
    while (n > 16) {
        i128 pv = key[n / 2];
        size_t i = 0, j = n - 1;
        for (;;) {
            while (key[i] < pv) i++;
            while (key[j] > pv) j--;
            if (i >= j) break;
            i128 tk = key[i];
            key[i] = key[j];
            key[j] = tk;
            uint32_t tv = val[i];
            val[i] = val[j];
            val[j] = tv;
            i++;
            j--;
        }
        /* recurse on the smaller side, loop on the larger */
        size_t left = j + 1;
        if (left < n - left) {
            sort_keyed(key, val, left);
            key += left;
            val += left;
            n -= left;
        } else {
            sort_keyed(key + left, val + left, n - left);
            n = left;
        }
    }
    for (size_t i = 1; i < n; i++) {
        i128 k = key[i];
        uint32_t v = val[i];
        size_t j = i;
        while (j > 0 && key[j - 1] > k) {
            key[j] = key[j - 1];
            val[j] = val[j - 1];
            j--;
        }
        key[j] = k;
        val[j] = v;
    }
}

static void split_segments(void *vc, size_t chunk, int w)
{
    ctx *c = vc;
    size_t s0 = chunk * SEG_CHUNK, s1 = s0 + SEG_CHUNK < c->m ? s0 + SEG_CHUNK : c->m;
    scratch *sc = &c->scr[w];
    vbuf *out = &c->edges[w];
    for (size_t s = s0; s < s1; s++) {
        size_t k = c->sp_off[s + 1] - c->sp_off[s];
        if (worker_stop(c, w, 4 * k + 1)) return; /* its pixels sorted along it */
        if (k > sc->cap) {
            size_t nc = k * 2;
            i128 *nk = realloc(sc->key, nc * sizeof *nk);
            if (nk) sc->key = nk;
            uint32_t *nv = realloc(sc->val, nc * sizeof *nv);
            if (nv) sc->val = nv;
            if (!nk || !nv) {
                atomic_store(&c->fail, ARR_ENOMEM);
                return;
            }
            sc->cap = nc;
        }
        const seg2 *sg = &c->seg[s];
        int64_t dx = sg->b.x - sg->a.x, dy = sg->b.y - sg->a.y;
        for (size_t i = 0; i < k; i++) {
            uint32_t pid = c->sp_pix[c->sp_off[s] + i];
            ipt p = c->pix[pid];
            sc->key[i] = (i128)(p.x - sg->a.x) * dx + (i128)(p.y - sg->a.y) * dy;
            sc->val[i] = pid;
        }
        sort_keyed(sc->key, sc->val, k);
        if (c->ep && k >= 2 && !ipt_cmp(c->pix[sc->val[0]], sg->a) &&
            !ipt_cmp(c->pix[sc->val[k - 1]], sg->b)) { /* the input's endpoints' pixels */
            c->ep[2 * (size_t)sg->id + sg->rev] = sc->val[0];
            c->ep[2 * (size_t)sg->id + !sg->rev] = sc->val[k - 1];
        }
        if (vbuf_reserve(out, out->n + k, sizeof(uint64_t))) {
            atomic_store(&c->fail, ARR_ENOMEM);
            return;
        }
        if (c->o->tags) {
            vbuf *tb = &c->etags[w];
            if (vbuf_reserve(tb, out->n + k, sizeof(uint32_t))) {
                atomic_store(&c->fail, ARR_ENOMEM);
                return;
            }
            uint32_t *t = tb->p, tag = c->o->tags[sg->id];
            if (c->o->signed_tags) /* the tag, and whether the input runs down the edge */
                for (size_t i = 0; i + 1 < k; i++)
                    t[tb->n++] = tag << 1 | ((sc->val[i] > sc->val[i + 1]) ^ sg->rev);
            else
                for (size_t i = 0; i + 1 < k; i++) t[tb->n++] = tag;
        }
        uint64_t *e = out->p;
        for (size_t i = 0; i + 1 < k; i++) {
            uint32_t u = sc->val[i], v = sc->val[i + 1];
            e[out->n++] = u < v ? (uint64_t)u << 32 | v : (uint64_t)v << 32 | u;
        }
    }
}

/* Concatenates the per-worker buffers of elem-sized items into one malloc'd array. */
static void *gather(vbuf *v, int nw, size_t elem, size_t *n)
{
    size_t t = 0;
    for (int w = 0; w < nw; w++) t += v[w].n;
    char *out = malloc((t ? t : 1) * elem);
    if (!out) return NULL;
    size_t o = 0;
    for (int w = 0; w < nw; w++) {
        if (v[w].n) memcpy(out + o * elem, v[w].p, v[w].n * elem);
        o += v[w].n;
        free(v[w].p);
        v[w] = (vbuf){0};
    }
    *n = t;
    return out;
}

/* Groups items by a key in [0, nkeys): off gets nkeys+1 offsets, out the values, stably. */
static int group_by(const uint64_t *kv, size_t n, size_t nkeys, uint32_t **off, uint32_t **out)
{
    uint32_t *o = calloc(nkeys + 1, sizeof *o);
    uint32_t *v = malloc((n ? n : 1) * sizeof *v);
    if (!o || !v) {
        free(o);
        free(v);
        return -1;
    }
    for (size_t i = 0; i < n; i++) o[(kv[i] >> 32) + 1]++;
    for (size_t k = 0; k < nkeys; k++) o[k + 1] += o[k];
    for (size_t i = 0; i < n; i++) v[o[kv[i] >> 32]++] = (uint32_t)kv[i];
    for (size_t k = nkeys; k > 0; k--) o[k] = o[k - 1];
    o[0] = 0;
    *off = o;
    *out = v;
    return 0;
}

typedef struct locate_job {
    ctx *c;
    uint64_t *kv; /* leaf << 32 | pixel */
} locate_job;

static void locate_chunk(void *vj, size_t chunk, int w)
{
    locate_job *j = vj;
    size_t p0 = chunk * 4096, p1 = p0 + 4096 < j->c->npix ? p0 + 4096 : j->c->npix;
    for (size_t p = p0; p < p1; p++) {
        if (worker_stop(j->c, w, 16)) return; /* a walk down the tree */
        uint32_t l = box_tree_locate(&j->c->tree, (double)j->c->pix[p].x, (double)j->c->pix[p].y);
        j->kv[p] = (uint64_t)l << 32 | p;
    }
}

/* Sorts the n edges ev (v0 << 32 | v1) with their tags et by (edge, tag) (sort_u64_u32), then
 * makes the edges unique in place (*nu of them) and gives each the tags that lie on it an odd
 * number of times (*toff: nu+1 offsets into *tags).  Returns -1 out of memory. */
static int unique_tagged(uint64_t *ev, uint32_t *et, size_t n, size_t *nu, uint32_t **toff,
                         uint32_t **tags, int32_t **tw)
{
    uint32_t *off = NULL, *tg = NULL;
    if (sort_u64_u32(ev, et, n)) return -1;
    const uint64_t *ks = ev;
    const uint32_t *ts = et;
    off = malloc((n + 1) * sizeof *off);
    tg = malloc((n ? n : 1) * sizeof *tg);
    if (!off || !tg) goto fail;
    int32_t *w = NULL;
    if (tw && !(w = *tw = malloc((n ? n : 1) * sizeof *w))) goto fail;
    size_t u = 0, nt = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && ks[j] == ks[i]) j++;
        off[u] = (uint32_t)nt;
        for (size_t a = i; a < j;) { /* runs of one tag: kept when odd (signed: non-zero) */
            size_t b = a;
            if (w) { /* tag << 1 | down: the ups first, then the downs */
                int64_t sum = 0;
                while (b < j && ts[b] >> 1 == ts[a] >> 1) sum += ts[b] & 1 ? -1 : 1, b++;
                if (sum) w[nt] = (int32_t)sum, tg[nt++] = ts[a] >> 1;
                a = b;
                continue;
            }
            while (b < j && ts[b] == ts[a]) b++;
            if ((b - a) & 1) tg[nt++] = ts[a];
            a = b;
        }
        ev[u++] = ks[i]; /* u <= i: in place even when ks is ev */
        i = j;
    }
    off[u] = (uint32_t)nt;
    *nu = u;
    *toff = off;
    *tags = tg;
    return 0;
fail:
    free(off);
    free(tg);
    if (tw) free(*tw), *tw = NULL;
    return -1;
}

/* ---- which vertices may keep their input coordinates ------------------------------------------
 * With input_coords, a vertex that input points snapped to is written at the first such point,
 * up to half a grid step (0.71 steps) from its grid point; crossings stay at theirs.  Moving
 * vertices may not change the picture's topology (a thin spike's tip crossing the edge it
 * nearly touches, a ring made invalid), so vertices near other geometry stay on the grid:
 * every pixel within NEAR_R steps (a square) of a snapped segment that is not routed through
 * it keeps its grid point, and so does every pixel on that segment's route.  Why that is
 * enough: a snapped route lies within 0.71 steps of its segment, and every point of an edge
 * moves at most 0.71 steps as its ends do; two edges can only come to touch (the first event
 * of any change of topology) where an end of one comes within 1.42 steps of the other's grid
 * position, within 2.13 steps of that one's segment, inside the square of half-width 3: both
 * are then held on the grid. */
#define NEAR_R 3

/* A tree item for the near pass: its segment's box and id, the leaf's items sorted by x0 so
 * that a pixel's scan stops at the first one starting right of it. */
typedef struct nbox {
    int64_t x0, x1, y0, y1;
    uint32_t si;
} nbox;

/* Segment ab, its box nb, and a pixel p within NEAR_R of that box (the caller's filter): 0 when
 * the segment is not near p, 2 when it passes through p (seg_hits_pixel), 1 when it is only
 * near; the orientation taken once. */
static inline int seg_near_hit(ipt a, ipt b, const nbox *nb, ipt p)
{
    /* the line meets the square iff |orient(a, b, p)| <= R (|dx| + |dy|) (its corners spread
     * the orientation by that much); with the boxes meeting, so does the segment */
    int64_t L = llabs(b.x - a.x) + llabs(b.y - a.y);
    i128 o = orient2(a, b, p);
    if (o < 0) o = -o;
    if (o > (i128)NEAR_R * L) return 0;
    if (p.x < nb->x0 || p.x > nb->x1 || p.y < nb->y0 || p.y > nb->y1) return 1;
    /* in its box: through p when 2|O| < L (or at an end); at 2|O| == L the corner rule */
    if (2 * o < L || (a.x == p.x && a.y == p.y) || (b.x == p.x && b.y == p.y)) return 2;
    if (2 * o > L) return 1;
    return seg_hits_pixel(a, b, p) ? 2 : 1;
}

/* The leaves whose regions meet the closed box q, appended to *out (uint32): a walk down from
 * node that goes on alone while q lies on one side of each threshold (a pixel's box nearly
 * always does), with a stack of the other sides where it straddles one. */
static int leaves_meeting(const box_tree *t, const double *q, vbuf *out, int32_t node)
{
    int32_t stack[2 * BOX_DEPTH_MAX + 2];
    int top = 0;
    for (;;) {
        while (node >= 0) {
            const box_node *nd = &t->nodes[node];
            int below = q[nd->axis] <= nd->t, above = q[2 + nd->axis] > nd->t;
            if (below && above) stack[top++] = nd->child[1];
            node = below ? nd->child[0] : nd->child[1];
        }
        if (vbuf_reserve(out, out->n + 1, sizeof(uint32_t))) return -1;
        ((uint32_t *)out->p)[out->n++] = (uint32_t)~node;
        if (!top) return 0;
        node = stack[--top];
    }
}

static int nbox_cmp(const void *a, const void *b)
{
    const nbox *x = a, *y = b;
    return (x->x0 > y->x0) - (x->x0 < y->x0);
}

static void nbox_leaf(void *vc, size_t l, int w)
{
    (void)w;
    ctx *c = vc;
    uint32_t o = c->tree.leaf_off[l], n = c->tree.leaf_off[l + 1] - o;
    nbox *nb = c->nbox + o;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t si = c->tree.items[o + i];
        const int64_t *b = c->box + 4 * (size_t)si;
        nb[i] = (nbox){b[0], b[2], b[1], b[3], si};
    }
    if (n > 32) {
        qsort(nb, n, sizeof *nb, nbox_cmp);
        return;
    }
    for (uint32_t i = 1; i < n; i++) {
        nbox x = nb[i];
        uint32_t j = i;
        for (; j > 0 && nb[j - 1].x0 > x.x0; j--) nb[j] = nb[j - 1];
        nb[j] = x;
    }
}

static void near_chunk(void *vc, size_t chunk, int w)
{
    ctx *c = vc;
    size_t p0 = chunk * 1024, p1 = p0 + 1024 < c->npix ? p0 + 1024 : c->npix;
    vbuf leaves = {0};
    for (size_t pid = p0; pid < p1; pid++) {
        if (worker_stop(c, w, 64)) break; /* a few leaves' segments */
        ipt p = c->pix[pid];
        double q[4] = {(double)(p.x - NEAR_R), (double)(p.y - NEAR_R), (double)(p.x + NEAR_R),
                       (double)(p.y + NEAR_R)};
        leaves.n = 0;
        if (c->tree.nnodes == 0) {
            if (vbuf_reserve(&leaves, 1, sizeof(uint32_t))) goto nomem;
            ((uint32_t *)leaves.p)[leaves.n++] = 0;
        } else if (leaves_meeting(&c->tree, q, &leaves, 0)) {
            goto nomem;
        }
        double px = (double)p.x, py = (double)p.y;
        for (size_t k = 0; k < leaves.n; k++) {
            uint32_t l = ((uint32_t *)leaves.p)[k];
            /* the one leaf whose region holds p holds every segment through p: the
             * incidences come from it alone, each once */
            const double *rg = c->tree.region ? c->tree.region + 4 * (size_t)l : NULL;
            int home = !rg || (px > rg[0] && px <= rg[2] && py > rg[1] && py <= rg[3]);
            for (uint32_t i = c->tree.leaf_off[l]; i < c->tree.leaf_off[l + 1]; i++) {
                const nbox *nb = &c->nbox[i];
                if (nb->x0 - NEAR_R > p.x) break; /* and every item after it */
                if (nb->x1 + NEAR_R < p.x || nb->y0 - NEAR_R > p.y || nb->y1 + NEAR_R < p.y)
                    continue;
                uint32_t si = nb->si;
                const seg2 *sg = &c->seg[si];
                int nh = seg_near_hit(sg->a, sg->b, nb, p);
                if (!nh) continue;
                if (nh == 2) { /* routed through p */
                    if (!home) continue;
                    if (vbuf_reserve(&c->inc[w], c->inc[w].n + 1, sizeof(uint64_t))) goto nomem;
                    ((uint64_t *)c->inc[w].p)[c->inc[w].n++] = (uint64_t)si << 32 | pid;
                    continue;
                }
                if (vbuf_reserve(&c->nearp[w], c->nearp[w].n + 1, sizeof(uint32_t)) ||
                    vbuf_reserve(&c->nears[w], c->nears[w].n + 1, sizeof(uint32_t)))
                    goto nomem;
                ((uint32_t *)c->nearp[w].p)[c->nearp[w].n++] = (uint32_t)pid;
                ((uint32_t *)c->nears[w].p)[c->nears[w].n++] = si;
            }
        }
    }
    free(leaves.p);
    return;
nomem:
    free(leaves.p);
    atomic_store(&c->fail, ARR_ENOMEM);
}

/* c->pinned: the pixels that keep their grid coordinates (see above), from the near pairs
 * near_chunk listed and the pixels of each segment (sp_off, sp_pix).  -1 out of memory. */
static int pin_crowded(ctx *c)
{
    c->pinned = calloc(c->npix + 1, 1);
    if (!c->pinned) return -1;
    for (int w = 0; w < c->threads; w++) {
        const uint32_t *pp = c->nearp[w].p, *ss = c->nears[w].p;
        for (size_t k = 0; k < c->nearp[w].n; k++) {
            c->pinned[pp[k]] = 1;
            for (uint32_t j = c->sp_off[ss[k]]; j < c->sp_off[ss[k] + 1]; j++)
                c->pinned[c->sp_pix[j]] = 1;
        }
    }
    return 0;
}

/* From the snapped segments to a sorted, duplicate-free edge list over the hot pixels. */
static int stage_split(ctx *c, arr2_stats *st, uint64_t **edges_out, size_t *ne_out,
                       uint32_t **toff_out, uint32_t **tags_out, int32_t **tw_out, char *err,
                       size_t el)
{
    int rc = ARR_ENOMEM;
    uint64_t *kv = NULL, *inc = NULL, *ev = NULL;
    uint32_t *et = NULL;
    size_t ncross = 0, ninc = 0, nev = 0;
    double t0 = now_ms();

    /* buckets */
    c->box = malloc((c->m ? c->m : 1) * 4 * sizeof *c->box);
    if (!c->box) goto fail;
    for (size_t i = 0; i < c->m; i++) {
        const seg2 *s = &c->seg[i];
        int64_t *b = c->box + 4 * i;
        b[0] = s->a.x; /* a < b lexicographically */
        b[2] = s->b.x;
        b[1] = s->a.y < s->b.y ? s->a.y : s->b.y;
        b[3] = s->a.y < s->b.y ? s->b.y : s->a.y;
    }
    if (box_tree_build_par(&c->tree, c->box, c->m, LEAF_MAX, c->threads)) goto fail;
    st->buckets = c->tree.nleaves;
    double t1 = now_ms();
    st->ms_buckets = t1 - t0;
    progress(c, "buckets", 1);

    /* intersect */
    span si = {c, "intersect", 0, 0.9};
    par_for_ex(c->threads, c->tree.nleaves, intersect_leaf, c, span_tick, &si);
    if ((rc = atomic_load(&c->fail))) goto fail;
    rc = ARR_ENOMEM;
    for (int w = 0; w < c->threads; w++) st->pairs_tested += c->pairs[w];
    ipt *cr = gather(c->cross, c->threads, sizeof(ipt), &ncross);
    if (!cr) goto fail;
    st->intersections = ncross;
    c->pix = realloc(cr, (ncross + 2 * c->m + 1) * sizeof *c->pix);
    if (!c->pix) {
        free(cr);
        goto fail;
    }
    size_t np = ncross;
    for (size_t i = 0; i < c->m; i++) {
        c->pix[np++] = c->seg[i].a;
        c->pix[np++] = c->seg[i].b;
    }
    int sr = sort_ipt_stop(c->pix, np, c->o->cancel);
    if (sr == -2) rc = ARR_ECANCELED;
    if (sr) goto fail;
    size_t u = 0;
    for (size_t i = 0; i < np; i++)
        if (u == 0 || ipt_cmp(c->pix[u - 1], c->pix[i]) != 0) c->pix[u++] = c->pix[i];
    c->npix = u;
    st->hot_pixels = u;
    if (u >= NONE) {
        rc = util_seterr(err, el, ARR_ELIMIT, "lines: more than 2^32 vertices");
        goto fail;
    }
    double t2 = now_ms();
    st->ms_intersect = t2 - t1;
    progress(c, "intersect", 1);

    span sh = {c, "split", 0.05, 0.45};
    if (c->o->input_coords) {
        /* one pass over each pixel's neighbourhood (the leaves within NEAR_R of it): the
         * segments through it (its incidences) and those near it (to pin) together */
        c->nbox = malloc(((size_t)c->tree.leaf_off[c->tree.nleaves] + 1) * sizeof *c->nbox);
        if (!c->nbox) goto fail;
        par_for(c->threads, c->tree.nleaves, nbox_leaf, c);
        par_for_ex(c->threads, (c->npix + 1023) / 1024, near_chunk, c, span_tick, &sh);
        free(c->nbox);
        c->nbox = NULL;
    } else {
        /* hot pixels into their buckets, then each bucket's pixels against its segments */
        kv = malloc((c->npix ? c->npix : 1) * sizeof *kv);
        if (!kv) goto fail;
        locate_job lj = {c, kv};
        par_for(c->threads, (c->npix + 4095) / 4096, locate_chunk, &lj);
        if ((rc = atomic_load(&c->fail))) goto fail;
        rc = ARR_ENOMEM;
        if (group_by(kv, c->npix, c->tree.nleaves, &c->pl_off, &c->pl_pix)) goto fail;
        free(kv);
        kv = NULL;
        par_for_ex(c->threads, c->tree.nleaves, hotpixel_leaf, c, span_tick, &sh);
    }
    if ((rc = atomic_load(&c->fail))) goto fail;
    rc = ARR_ENOMEM;
    inc = gather(c->inc, c->threads, sizeof(uint64_t), &ninc);
    if (!inc) goto fail;
    if (group_by(inc, ninc, c->m, &c->sp_off, &c->sp_pix)) goto fail;
    if (c->o->input_coords && pin_crowded(c)) goto fail;
    free(inc);
    inc = NULL;
    span ss = {c, "split", 0.5, 0.9};
    if (c->o->input_coords) {
        c->ep = malloc((2 * c->n_in + 1) * sizeof *c->ep);
        if (!c->ep) goto fail;
        for (size_t i = 0; i < 2 * c->n_in; i++) c->ep[i] = NONE;
    }
    par_for_ex(c->threads, (c->m + SEG_CHUNK - 1) / SEG_CHUNK, split_segments, c, span_tick, &ss);
    if ((rc = atomic_load(&c->fail))) goto fail;
    rc = ARR_ENOMEM;
    ev = gather(c->edges, c->threads, sizeof(uint64_t), &nev);
    if (!ev) goto fail;
    size_t k = 0;
    if (c->o->tags) {
        size_t nt;
        et = gather(c->etags, c->threads, sizeof(uint32_t), &nt);
        if (!et || nt != nev ||
            unique_tagged(ev, et, nev, &k, toff_out, tags_out, c->o->signed_tags ? tw_out : NULL))
            goto fail;
        free(et);
        et = NULL;
    } else {
        if (sort_u64(ev, nev)) goto fail;
        for (size_t i = 0; i < nev; i++)
            if (k == 0 || ev[k - 1] != ev[i]) ev[k++] = ev[i];
    }
    *edges_out = ev;
    *ne_out = k;
    st->ms_split = now_ms() - t2;
    progress(c, "split", 1);
    return ARR_OK;
fail:
    free(kv);
    free(inc);
    free(ev);
    free(et);
    if (rc == ARR_ENOMEM) util_seterr(err, el, rc, "out of memory");
    return rc;
}

/* ---- graph, blocks ------------------------------------------------------------------------ */

typedef struct graph {
    size_t nv, ne;
    ipt *P;           /* nv */
    uint32_t *src;    /* nv, with input_coords: the first input endpoint on the vertex, or NONE */
    uint32_t *toff;   /* with tags: ne+1 */
    uint32_t *tag;    /* with tags: each edge's odd tags (signed_tags: non-zero) */
    int32_t *tw;      /* with signed_tags: each tag's signed count */
    uint32_t *EV;     /* 2*ne */
    uint32_t *off;    /* nv+1: outgoing half-edges of v are out[off[v]..off[v+1]) */
    uint32_t *out;    /* half-edge ids: 2e leaves EV[2e], 2e+1 leaves EV[2e+1] */
    stop_meter *stop; /* the cancel, polled by the long loops (may be NULL) */
} graph;

/* After `work` units of a serial stage: non-zero when the job is cancelled. */
static int g_stop(const graph *g, size_t work)
{
    return g->stop && stop_poll(g->stop, work);
}

static inline uint32_t he_tail(const graph *g, uint32_t h)
{
    return g->EV[h];
}
static inline uint32_t he_head(const graph *g, uint32_t h)
{
    return g->EV[h ^ 1];
}

static void graph_free(graph *g)
{
    free(g->P);
    free(g->src);
    free(g->toff);
    free(g->tag);
    free(g->tw);
    free(g->EV);
    free(g->off);
    free(g->out);
    memset(g, 0, sizeof *g);
}

/* Builds the outgoing half-edge lists (unsorted). */
static int graph_adjacency(graph *g)
{
    free(g->off);
    free(g->out);
    g->off = calloc(g->nv + 1, sizeof *g->off);
    g->out = malloc((2 * g->ne + 1) * sizeof *g->out);
    if (!g->off || !g->out) return -1;
    for (size_t h = 0; h < 2 * g->ne; h++) g->off[g->EV[h] + 1]++;
    for (size_t v = 0; v < g->nv; v++) g->off[v + 1] += g->off[v];
    for (size_t h = 0; h < 2 * g->ne; h++) g->out[g->off[g->EV[h]]++] = (uint32_t)h;
    for (size_t v = g->nv; v > 0; v--) g->off[v] = g->off[v - 1];
    g->off[0] = 0;
    return 0;
}

/* Removes the edges with drop[e] set and the vertices left without edges; keeps the order
 * of what remains (so EV stays sorted and V lexicographic). */
static int graph_prune(graph *g, const uint8_t *drop)
{
    uint32_t *vmap = malloc((g->nv + 1) * sizeof *vmap);
    if (!vmap) return -1;
    for (size_t v = 0; v < g->nv; v++) vmap[v] = NONE;
    size_t ne = 0, nt = 0;
    for (size_t e = 0; e < g->ne; e++) {
        if (drop[e]) continue;
        vmap[g->EV[2 * e]] = vmap[g->EV[2 * e + 1]] = 0;
        g->EV[2 * ne] = g->EV[2 * e];
        g->EV[2 * ne + 1] = g->EV[2 * e + 1];
        if (g->toff) { /* a dropped edge is a bridge: its tags are even (rings are closed) */
            uint32_t t0 = g->toff[e], t1 = g->toff[e + 1];
            g->toff[ne] = (uint32_t)nt;
            for (uint32_t t = t0; t < t1; t++) {
                if (g->tw) g->tw[nt] = g->tw[t];
                g->tag[nt++] = g->tag[t];
            }
        }
        ne++;
    }
    if (g->toff) g->toff[ne] = (uint32_t)nt;
    size_t nv = 0;
    for (size_t v = 0; v < g->nv; v++)
        if (vmap[v] != NONE) {
            g->P[nv] = g->P[v];
            if (g->src) g->src[nv] = g->src[v];
            vmap[v] = (uint32_t)nv++;
        }
    for (size_t i = 0; i < 2 * ne; i++) g->EV[i] = vmap[g->EV[i]];
    g->nv = nv;
    g->ne = ne;
    free(vmap);
    return graph_adjacency(g);
}

/* ---- faces and holes ------------------------------------------------------------------------ */

static inline void he_dir(const graph *g, uint32_t h, int64_t *dx, int64_t *dy)
{
    ipt a = g->P[he_tail(g, h)], b = g->P[he_head(g, h)];
    *dx = b.x - a.x;
    *dy = b.y - a.y;
}

#define VERT_CHUNK 4096 /* vertices per work item of the face stage */

typedef struct sort_job {
    ctx *c;
    const graph *g;
    uint32_t *pos;
    atomic_int same; /* two edges leave a vertex in the same direction */
} sort_job;

/* The model's "around" (planar_traits): two half-edges leaving one vertex by the exact angle of
 * their grid directions (dir_cmp, from +x counter-clockwise). */
static int model_around(void *vg, uint32_t a, uint32_t b)
{
    const graph *g = vg;
    int64_t ax, ay, bx, by;
    he_dir(g, a, &ax, &ay);
    he_dir(g, b, &bx, &by);
    return dir_cmp(ax, ay, bx, by);
}

static void sort_chunk(void *vj, size_t chunk, int wk)
{
    sort_job *j = vj;
    const graph *g = j->g;
    size_t v0 = chunk * VERT_CHUNK, v1 = v0 + VERT_CHUNK < g->nv ? v0 + VERT_CHUNK : g->nv;
    size_t work = 0;
    for (size_t v = v0; v < v1; v++) {
        size_t d = g->off[v + 1] - g->off[v];
        work += d * d + 1;
    }
    if (worker_stop(j->c, wk, work)) return;
    planar_traits T = {(void *)g, model_around, NULL, NULL, NULL, NULL};
    if (planar_sort_around(&T, g->off, g->out, j->pos, v0, v1)) atomic_store(&j->same, 1);
}

/* Sorts each vertex's outgoing half-edges counter-clockwise, in parallel; pos[h] = index of h
 * in its list.  Returns -1 if two edges leave a vertex in the same direction (cannot happen
 * after snap rounding; checked rather than assumed), -2 when cancelled. */
static int sort_around_vertices(ctx *c, const graph *g, uint32_t *pos)
{
    sort_job j = {.c = c, .g = g, .pos = pos};
    atomic_init(&j.same, 0);
    par_for(c->threads, (g->nv + VERT_CHUNK - 1) / VERT_CHUNK, sort_chunk, &j);
    if (atomic_load(&j.same)) return -1;
    return atomic_load(&c->fail) ? -2 : 0;
}

static inline uint32_t he_next(const graph *g, const uint32_t *pos, uint32_t h)
{
    return planar_next(g->off, g->out, pos, he_head(g, h), h);
}

/* The connected components: comp[v] for every vertex, numbered in the order of their smallest
 * vertex, by union-find over the edges (par: nv entries of scratch); returns their number. */
static size_t components(const graph *g, uint32_t *comp, uint32_t *par)
{
    for (size_t v = 0; v < g->nv; v++) par[v] = (uint32_t)v;
    for (size_t e = 0; e < g->ne; e++) {
        uf_union(par, g->EV[2 * e], g->EV[2 * e + 1]); /* the smaller vertex is the root */
    }
    size_t n = 0;
    for (size_t v = 0; v < g->nv; v++) { /* a root is the smallest vertex of its component */
        uint32_t r = uf_find(par, (uint32_t)v);
        comp[v] = r == v ? (uint32_t)n++ : comp[r];
    }
    return n;
}

typedef struct walks {
    size_t ncyc;
    uint32_t *cyc_of; /* 2*ne: cycle of each half-edge */
    uint32_t *hoff;   /* ncyc+1 */
    uint32_t *hes;    /* half-edges of each cycle in walk order */
    i128 *area2;      /* twice the signed area of each cycle */
} walks;

static void walks_free(walks *w)
{
    free(w->cyc_of);
    free(w->hoff);
    free(w->hes);
    free(w->area2);
    memset(w, 0, sizeof *w);
}

#define HE_CHUNK 16384 /* half-edges (or cycles) per work item of the walks */

typedef struct walk_job {
    ctx *c;
    const graph *g;
    const uint32_t *pos;
    uint32_t *next; /* the half-edge after each one around its face */
    walks *w;
} walk_job;

static void next_chunk(void *vj, size_t chunk, int wk)
{
    walk_job *j = vj;
    size_t nh = 2 * j->g->ne, h0 = chunk * HE_CHUNK, h1 = h0 + HE_CHUNK < nh ? h0 + HE_CHUNK : nh;
    if (worker_stop(j->c, wk, h1 - h0)) return;
    for (size_t h = h0; h < h1; h++) j->next[h] = he_next(j->g, j->pos, (uint32_t)h);
}

static void area_chunk(void *vj, size_t chunk, int wk)
{
    walk_job *j = vj;
    const walks *w = j->w;
    const graph *g = j->g;
    size_t c0 = chunk * HE_CHUNK, c1 = c0 + HE_CHUNK < w->ncyc ? c0 + HE_CHUNK : w->ncyc;
    if (worker_stop(j->c, wk, w->hoff[c1] - w->hoff[c0] + 1)) return;
    for (size_t cy = c0; cy < c1; cy++) {
        i128 a2 = 0;
        for (uint32_t i = w->hoff[cy]; i < w->hoff[cy + 1]; i++) {
            uint32_t h = w->hes[i];
            ipt p = g->P[he_tail(g, h)], q = g->P[he_head(g, h)];
            a2 += cross2(p.x, p.y, q.x, q.y);
        }
        w->area2[cy] = a2;
    }
}

/* The boundary walks: each half-edge's successor around its face (in parallel), the cycles
 * they make (in half-edge order), and each cycle's twice signed area (in parallel). */
static int walk_faces(ctx *c, const graph *g, const uint32_t *pos, walks *w)
{
    size_t nh = 2 * g->ne;
    uint32_t *next = malloc((nh + 1) * sizeof *next);
    w->cyc_of = malloc((nh + 1) * sizeof *w->cyc_of);
    w->hes = malloc((nh + 1) * sizeof *w->hes);
    if (!next || !w->cyc_of || !w->hes) {
        free(next);
        return ARR_ENOMEM;
    }
    walk_job j = {c, g, pos, next, w};
    par_for(c->threads, (nh + HE_CHUNK - 1) / HE_CHUNK, next_chunk, &j);
    if (atomic_load(&c->fail)) {
        free(next);
        return ARR_ECANCELED;
    }
    size_t caphoff = 0;
    int rc = planar_cycles(nh, next, w->cyc_of, w->hes, &w->hoff, &caphoff, &w->ncyc);
    free(next);
    if (rc) return rc == -1 ? ARR_ENOMEM : ARR_EINTERNAL;
    if (g_stop(g, nh)) return ARR_ECANCELED;
    w->area2 = malloc((w->ncyc + 1) * sizeof *w->area2);
    if (!w->area2) return ARR_ENOMEM;
    par_for(c->threads, (w->ncyc + HE_CHUNK - 1) / HE_CHUNK, area_chunk, &j);
    return atomic_load(&c->fail) ? ARR_ECANCELED : ARR_OK;
}

/* Highest point strictly below p where edge e meets the vertical line through p, as the
 * fraction num/den (den > 0); *at gets the vertex hit, or NONE for an edge interior.
 * Returns 0 when e does not meet the line below p. */
static int hit_below(const graph *g, uint32_t e, ipt p, i128 *num, i128 *den, uint32_t *at)
{
    uint32_t u = g->EV[2 * e], v = g->EV[2 * e + 1]; /* P[u] < P[v] lexicographically */
    ipt a = g->P[u], b = g->P[v];
    if (p.x < a.x || p.x > b.x) return 0;
    if (a.x == b.x) { /* vertical, on the line: its top is hit */
        if (b.y >= p.y) return 0;
        *num = b.y;
        *den = 1;
        *at = v;
        return 1;
    }
    i128 d = b.x - a.x;
    i128 n = (i128)a.y * d + (i128)(b.y - a.y) * (p.x - a.x);
    if (n >= (i128)p.y * d) return 0;
    *num = n;
    *den = d;
    *at = p.x == a.x ? u : (p.x == b.x ? v : NONE);
    return 1;
}

/* The placement model (planar_traits) of arr2: keys are grid x, exact; a query is a
 * component's lowest vertex. */
typedef struct place_model {
    ctx *c;
    const graph *g;
    const uint32_t *comp, *low; /* see place_components */
} place_model;

/* The model's "espan": an edge's x range (its ends are in lexicographic order). */
static void model_espan(void *vm, size_t e0, size_t e1, int64_t *lo, int64_t *hi)
{
    const place_model *m = vm;
    const graph *g = m->g;
    for (size_t e = e0; e < e1; e++)
        lo[e - e0] = g->P[g->EV[2 * e]].x, hi[e - e0] = g->P[g->EV[2 * e + 1]].x;
}

static void model_qspan(void *vm, uint32_t q, int64_t *lo, int64_t *hi)
{
    const place_model *m = vm;
    *lo = *hi = m->g->P[m->low[q]].x;
}

/* The model's "scan": of best and the candidates, the edge of another component whose hit
 * below component q's lowest vertex is highest (exact fractions; the first of equal ones). */
static uint32_t model_scan(void *vm, uint32_t q, const uint32_t *cand, size_t n, uint32_t best)
{
    const place_model *m = vm;
    const graph *g = m->g;
    ipt p = g->P[m->low[q]];
    i128 bn = 0, bd = 0;
    uint32_t be = NONE, at;
    for (size_t i = best == NONE; i <= n; i++) { /* best first, then the candidates */
        uint32_t e = i ? cand[i - 1] : best;
        if (m->comp[g->EV[2 * e]] == q) continue;
        i128 num, den;
        if (!hit_below(g, e, p, &num, &den, &at)) continue;
        if (be == NONE || num * bd > bn * den) bn = num, bd = den, be = e;
    }
    return be;
}

static int model_stop(void *vm, int wk, size_t work)
{
    return worker_stop(((place_model *)vm)->c, wk, work);
}

/* The half-edge whose face lies just above p, from e, the first edge below p: at the vertex
 * the ray hits, the wedge there that holds "up"; inside e, its half-edge leaving its left end
 * (the face above on its left). */
static uint32_t face_above(const graph *g, uint32_t e, ipt p)
{
    uint32_t u = g->EV[2 * e], v = g->EV[2 * e + 1]; /* as hit_below: a vertical edge's top */
    uint32_t at = g->P[u].x == g->P[v].x ? v : p.x == g->P[u].x ? u : p.x == g->P[v].x ? v : NONE;
    if (at == NONE) return 2 * e;
    const uint32_t *o = g->out + g->off[at];
    size_t d = g->off[at + 1] - g->off[at], jj = d - 1;
    for (size_t i = 0; i < d; i++) {
        int64_t dx, dy;
        he_dir(g, o[i], &dx, &dy);
        if (dir_cmp(dx, dy, 0, 1) < 0) jj = i;
    }
    return o[jj];
}

/* Places every component's outer walk: hole of a bounded face or exterior.  face_of[c] gets,
 * for every outer-walk cycle c, the face cycle it is a hole of, or NONE.  The first edge below
 * each component's lowest vertex comes from the kernel's planar_place (its slab index and
 * queries on the threads). */
static int place_components(ctx *c, const graph *g, const walks *w, const uint32_t *comp,
                            size_t ncomp, const uint32_t *comp_outer, uint32_t *face_of)
{
    int rc = ARR_ENOMEM;
    uint32_t *low = malloc(ncomp * sizeof *low), *par = malloc(ncomp * sizeof *par);
    uint32_t *found = malloc(ncomp * sizeof *found);
    planar_ws ws = {0};
    if (!low || !par || !found) goto out;
    for (size_t k = 0; k < ncomp; k++) {
        low[k] = NONE;
        par[k] = (uint32_t)k;
        found[k] = NONE;
    }
    int64_t minx = INT64_MAX, maxx = INT64_MIN;
    for (size_t v = 0; v < g->nv; v++) {
        uint32_t k = comp[v];
        ipt p = g->P[v];
        if (low[k] == NONE || p.y < g->P[low[k]].y) low[k] = (uint32_t)v;
        minx = p.x < minx ? p.x : minx;
        maxx = p.x > maxx ? p.x : maxx;
    }
    /* each component's first edge below its lowest vertex, then the half-edge with the face
     * above on its left; then, in order, the face it is a hole of, or the component whose
     * outer walk holds it */
    place_model m = {c, g, comp, low};
    planar_traits T = {&m, NULL, model_espan, model_qspan, model_scan, model_stop};
    int pr = planar_place(&T, c->threads, &ws, g->ne, minx, maxx, ncomp, found);
    if ((rc = atomic_load(&c->fail)))
        goto out; /* stopped (pr 1): the job failed or was cancelled */
    rc = ARR_ENOMEM;
    if (pr) goto out;
    for (size_t k = 0; k < ncomp; k++) {
        uint32_t e = found[k];
        found[k] = NONE;
        if (e == NONE) continue; /* nothing below: in the unbounded face */
        uint32_t h = face_above(g, e, g->P[low[k]]);
        uint32_t cyc = w->cyc_of[h];
        if (w->area2[cyc] > 0)
            found[k] = cyc;
        else
            par[uf_find(par, (uint32_t)k)] = uf_find(par, comp[he_tail(g, h)]);
    }
    for (size_t k = 0; k < ncomp; k++) {
        if (found[k] == NONE) continue;
        uint32_t r = uf_find(par, (uint32_t)k);
        if (found[r] != NONE && found[r] != found[k] && r != k) {
            rc = ARR_EINTERNAL;
            goto out;
        }
        if (r != k) found[r] = found[k];
    }
    for (size_t k = 0; k < ncomp; k++) face_of[comp_outer[k]] = found[uf_find(par, (uint32_t)k)];
    rc = ARR_OK;
out:
    free(low);
    free(par);
    free(found);
    planar_ws_free(&ws);
    return rc;
}

/* ---- the whole pipeline ----------------------------------------------------------------- */

/* Splits a closed walk of vertices at its repeated vertices into simple cycles, in walk
 * order; appends them to the cycle table (*k vertices, *np cycles so far), with the half-edge
 * leaving each vertex to ecyc (whe[i] leaves walk[i]), and their signs (1: counter-clockwise)
 * to pos.  The top of the stack is always the last vertex walked, so the half-edge that arrives
 * at each step leaves the top (estack).  instack has nv entries, all NONE, and is left so. */
static void split_walk(const graph *g, const uint32_t *walk, const uint32_t *whe, size_t len,
                       uint32_t *stack, uint32_t *estack, uint32_t *instack, uint32_t *cyc,
                       uint32_t *ecyc, uint32_t *off, uint8_t *pos, size_t *k, size_t *np)
{
    size_t sp = 0;
    for (size_t i = 0; i <= len; i++) {
        uint32_t v = i < len ? walk[i] : NONE;
        size_t from;
        if (i > 0) estack[sp - 1] = whe[i - 1];
        if (i < len && instack[v] == NONE) {
            instack[v] = (uint32_t)sp;
            stack[sp++] = v;
            continue;
        }
        from = i < len ? instack[v] : 0; /* a loop closes at v (or the walk ends) */
        i128 a2 = 0;
        for (size_t j = from; j < sp; j++) {
            ipt p = g->P[stack[j]], q = g->P[stack[j + 1 < sp ? j + 1 : from]];
            a2 += cross2(p.x, p.y, q.x, q.y);
            ecyc[*k] = estack[j];
            cyc[(*k)++] = stack[j];
            if (j > from || i == len) instack[stack[j]] = NONE;
        }
        pos[*np] = a2 > 0;
        off[++*np] = (uint32_t)*k;
        sp = from + (i < len);
    }
}

/* Fills the lar2 from the graph and its walks.  Each walk is split at repeated vertices
 * into simple cycles (unless keep_dangling, where walks along dangling edges are kept
 * whole): a bounded face's walk gives one counter-clockwise cycle, its outer cycle, and
 * clockwise cycles where something touches it from inside at a single vertex, which become
 * holes (as GEOS and the OGC model have it: holes may touch the shell at a point). */
typedef struct emit_job {
    ctx *c;
    const graph *g;
    const walks *w;
    lar2 *out;
    atomic_size_t bad; /* the first vertex not written on its grid point, + 1 (0: none) */
} emit_job;

/* Vertices [chunk * VERT_CHUNK, ...): their coordinates as written (the input's own where an
 * input point snapped to them), their grid points, and the check that each written point
 * snaps back to its grid point. */
static void emit_vertices(void *vj, size_t chunk, int wk)
{
    emit_job *j = vj;
    const ctx *c = j->c;
    const graph *g = j->g;
    lar2 *out = j->out;
    size_t v0 = chunk * VERT_CHUNK, v1 = v0 + VERT_CHUNK < g->nv ? v0 + VERT_CHUNK : g->nv;
    if (worker_stop(j->c, wk, v1 - v0)) return;
    for (size_t v = v0; v < v1; v++) {
        uint32_t s = g->src ? g->src[v] : NONE;
        if (s != NONE) { /* segment s / 2's start (even) or end (odd), as given */
            out->V[2 * v] = c->in[4 * (size_t)(s / 2) + 2 * (s & 1)];
            out->V[2 * v + 1] = c->in[4 * (size_t)(s / 2) + 2 * (s & 1) + 1];
        } else {
            out->V[2 * v] = unsnap(c, 0, g->P[v].x);
            out->V[2 * v + 1] = unsnap(c, 1, g->P[v].y);
        }
        out->VG[2 * v] = g->P[v].x;
        out->VG[2 * v + 1] = g->P[v].y;
        if (snap_coord(c, 0, out->V[2 * v]) != g->P[v].x ||
            snap_coord(c, 1, out->V[2 * v + 1]) != g->P[v].y) {
            size_t want = v + 1, cur = atomic_load(&j->bad);
            while ((cur == 0 || want < cur) && !atomic_compare_exchange_weak(&j->bad, &cur, want))
                ;
            return;
        }
    }
}

/* With keep_dangling every walk is a cycle: its vertices, from half-edges [chunk * HE_CHUNK,
 * ...). */
static void emit_walk_cycles(void *vj, size_t chunk, int wk)
{
    emit_job *j = vj;
    size_t nh = 2 * j->g->ne, h0 = chunk * HE_CHUNK, h1 = h0 + HE_CHUNK < nh ? h0 + HE_CHUNK : nh;
    if (worker_stop(j->c, wk, h1 - h0)) return;
    for (size_t i = h0; i < h1; i++) j->out->cyc[i] = he_tail(j->g, j->w->hes[i]);
}

static int emit_complex(ctx *c, const graph *g, const walks *w, const uint32_t *face_idx,
                        const uint32_t *face_of, size_t nf, lar2 *out, char *err, size_t el)
{
    int rc = ARR_ENOMEM;
    size_t nh = 2 * g->ne, np = 0, k = 0;
    uint32_t *pwalk = malloc((nh + 1) * sizeof *pwalk);
    uint8_t *ppos = malloc(nh + 1);
    uint32_t *stack = malloc((nh + 1) * sizeof *stack), *instack = malloc((g->nv + 1) * 4);
    uint32_t *walkv = malloc((nh + 1) * sizeof *walkv);
    uint32_t *estack = malloc((nh + 1) * sizeof *estack), *ecyc = malloc((nh + 1) * sizeof *ecyc);
    out->nv = g->nv;
    out->ne = g->ne;
    out->nf = nf;
    out->V = malloc((2 * g->nv + 1) * sizeof *out->V);
    out->EV = malloc((2 * g->ne + 1) * sizeof *out->EV);
    out->face_cycle = malloc((nf + 1) * sizeof *out->face_cycle);
    out->hole_off = calloc(nf + 2, sizeof *out->hole_off);
    out->hole_cyc = malloc((nh + 1) * sizeof *out->hole_cyc);
    out->fe_off = malloc((nf + 1) * sizeof *out->fe_off);
    out->fe = malloc((nh + 1) * sizeof *out->fe);
    out->cyc_off = malloc((nh + 2) * sizeof *out->cyc_off);
    out->cyc = malloc((nh + 1) * sizeof *out->cyc);
    out->ext_cyc = malloc((nh + 1) * sizeof *out->ext_cyc);
    if (!pwalk || !ppos || !stack || !instack || !walkv || !estack || !ecyc || !out->V ||
        !out->EV || !out->face_cycle || !out->hole_off || !out->hole_cyc || !out->fe_off ||
        !out->fe || !out->cyc_off || !out->cyc || !out->ext_cyc)
        goto out;
    out->VG = malloc((2 * g->nv + 1) * sizeof *out->VG);
    if (!out->VG) goto out;
    /* Distinct vertices must be written as distinct doubles.  Each written point snaps back to
     * its vertex's grid point, and snapping is a function, so two vertices could share a
     * double point only by sharing a grid point.  That holds because the grid is never finer
     * than twice the doubles' spacing (stage_snap); checked, as a bug would break it. */
    emit_job ej = {.c = c, .g = g, .w = w, .out = out};
    atomic_init(&ej.bad, 0);
    par_for(c->threads, (g->nv + VERT_CHUNK - 1) / VERT_CHUNK, emit_vertices, &ej);
    if (atomic_load(&c->fail)) {
        rc = ARR_ECANCELED;
        goto out;
    }
    size_t badv = atomic_load(&ej.bad);
    if (badv) {
        size_t v = badv - 1;
        rc = util_seterr(err, el, ARR_EINTERNAL,
                         "internal: vertex %zu is written (%.17g, %.17g), which is not on its grid "
                         "point",
                         v, out->V[2 * v], out->V[2 * v + 1]);
        goto out;
    }
    for (size_t v = 0; v < g->nv; v++) instack[v] = NONE;
    memcpy(out->EV, g->EV, 2 * g->ne * sizeof *g->EV);
    if (g->toff) {
        out->etag_off = g->toff;
        out->etag = g->tag;
        out->etagw = g->tw;
        ((graph *)g)->toff = ((graph *)g)->tag = NULL; /* handed over */
        ((graph *)g)->tw = NULL;
    }
    out->cyc_off[0] = 0;
    if (c->o->keep_dangling) { /* the walks as they are, in parallel */
        par_for(c->threads, (nh + HE_CHUNK - 1) / HE_CHUNK, emit_walk_cycles, &ej);
        if (atomic_load(&c->fail)) {
            rc = ARR_ECANCELED;
            goto out;
        }
        memcpy(ecyc, w->hes, nh * sizeof *ecyc);
        for (size_t cy = 0; cy < w->ncyc; cy++) {
            out->cyc_off[cy + 1] = w->hoff[cy + 1];
            ppos[cy] = w->area2[cy] > 0; /* so face_idx[cy] != NONE: one outer cycle */
            pwalk[cy] = (uint32_t)cy;
        }
        np = w->ncyc;
    }
    for (size_t cy = 0; !c->o->keep_dangling && cy < w->ncyc; cy++) {
        size_t len = w->hoff[cy + 1] - w->hoff[cy], p0 = np;
        if (g_stop(g, 4 * len + 1)) {
            rc = ARR_ECANCELED;
            goto out;
        }
        for (size_t i = 0; i < len; i++) walkv[i] = he_tail(g, w->hes[w->hoff[cy] + i]);
        split_walk(g, walkv, w->hes + w->hoff[cy], len, stack, estack, instack, out->cyc, ecyc,
                   out->cyc_off, ppos, &k, &np);
        size_t npos = 0;
        for (size_t p = p0; p < np; p++) {
            pwalk[p] = (uint32_t)cy;
            npos += ppos[p];
        }
        if (npos != (face_idx[cy] != NONE)) {
            rc = util_seterr(err, el, ARR_EINTERNAL,
                             "internal: walk %zu splits into %zu outer cycles", cy, npos);
            goto out;
        }
    }
    out->ncyc = np;
    /* holes: the clockwise pieces of each face's walk and every piece of the outer walks
     * placed in it; counted per face, then filled in cycle order */
    for (size_t p = 0; p < np; p++) {
        uint32_t fw = face_of[pwalk[p]];
        if (!ppos[p] && fw != NONE) out->hole_off[face_idx[fw] + 1]++;
    }
    for (size_t f = 0; f < nf; f++) out->hole_off[f + 1] += out->hole_off[f];
    out->next = 0;
    for (size_t p = 0; p < np; p++) {
        uint32_t fw = face_of[pwalk[p]];
        if (ppos[p])
            out->face_cycle[face_idx[pwalk[p]]] = (uint32_t)p;
        else if (fw == NONE)
            out->ext_cyc[out->next++] = (uint32_t)p;
        else
            out->hole_cyc[out->hole_off[face_idx[fw]]++] = (uint32_t)p;
    }
    for (size_t f = nf; f > 0; f--) out->hole_off[f] = out->hole_off[f - 1];
    out->hole_off[0] = 0;
    /* FE: the signed edges of the face's cycles; an edge with this face on both sides (a
     * dangling edge kept on request) cancels */
    size_t fe = 0;
    for (size_t f = 0; f < nf; f++) {
        out->fe_off[f] = (uint32_t)fe;
        uint32_t nhol = out->hole_off[f + 1] - out->hole_off[f];
        if (g_stop(g, 8 * (nhol + 1))) {
            rc = ARR_ECANCELED;
            goto out;
        }
        uint32_t fw = pwalk[out->face_cycle[f]];
        for (uint32_t j = 0; j <= nhol; j++) {
            uint32_t p = j == 0 ? out->face_cycle[f] : out->hole_cyc[out->hole_off[f] + j - 1];
            for (uint32_t i = out->cyc_off[p]; i < out->cyc_off[p + 1]; i++) {
                uint32_t h = ecyc[i]; /* from cyc[i] to the next vertex of the cycle */
                if (face_of[w->cyc_of[h ^ 1]] == fw) continue;
                int32_t e = (int32_t)(h >> 1) + 1;
                out->fe[fe++] = (h & 1) ? -e : e;
            }
        }
    }
    out->fe_off[nf] = (uint32_t)fe;
    rc = ARR_OK;
out:
    free(pwalk);
    free(ppos);
    free(stack);
    free(instack);
    free(walkv);
    free(estack);
    free(ecyc);
    return rc;
}

/* With opts.half_edges: the kernel's half-edges handed to out (graph's sorted lists, *pos; both
 * then owned by out) and the face on each one's left: its walk's face (a bounded face's own,
 * the face an outer walk is a hole of, or nf).  Returns 0, or -1 out of memory. */
static int keep_half_edges(graph *g, const walks *w, const uint32_t *face_of,
                           const uint32_t *face_idx, size_t nf, uint32_t **pos, lar2 *out)
{
    size_t nh = 2 * g->ne;
    out->he_face = malloc((nh + 1) * sizeof *out->he_face);
    if (!out->he_face) return -1;
    for (size_t h = 0; h < nh; h++) {
        uint32_t fw = face_of[w->cyc_of[h]];
        out->he_face[h] = fw == NONE ? (uint32_t)nf : face_idx[fw];
    }
    out->he_off = g->off, out->he_out = g->out, out->he_pos = *pos;
    g->off = g->out = *pos = NULL;
    return 0;
}

static int build_complex(ctx *c, graph *g, lar2 *out, char *err, size_t el)
{
    arr2_stats *st = &out->stats;
    int rc = ARR_ENOMEM;
    uint32_t *pos = NULL, *comp = NULL, *stack = NULL;
    uint32_t *comp_outer = NULL, *face_of = NULL, *face_idx = NULL;
    uint8_t *drop = NULL;
    walks w = {0};
    double t0 = now_ms();

    /* blocks, from the face walks of the plane graph: an edge is a bridge exactly when its two
     * sides are on one walk, and a vertex lies in 1 + sum over the walks through it of (its
     * visits - 1) blocks, so (block-cut tree) blocks = components + sum over the walks of
     * (length - distinct vertices), the components counted by their outer walks (one each: the
     * faces below check it).  Bridges are removed (unless keep_dangling) and the walks made
     * again. */
    if (graph_adjacency(g)) goto fail;
    comp = malloc((g->nv + 1) * sizeof *comp); /* nv only shrinks from here */
    stack = malloc((g->nv + 1) * sizeof *stack);
    if (!comp || !stack) goto fail;
    for (int pass = 0; pass < 2; pass++) {
        free(pos);
        pos = malloc((2 * g->ne + 1) * sizeof *pos);
        if (!pos) goto fail;
        int sr = sort_around_vertices(c, g, pos);
        if (sr == -2) {
            rc = ARR_ECANCELED;
            goto fail;
        }
        if (sr) {
            rc = util_seterr(err, el, ARR_EINTERNAL, "internal: two edges leave a vertex together");
            goto fail;
        }
        walks_free(&w);
        if ((rc = walk_faces(c, g, pos, &w))) goto fail;
        rc = ARR_ENOMEM;
        if (pass == 1) break;
        drop = calloc(g->ne + 1, 1);
        if (!drop) goto fail;
        size_t nbridge = 0, outer = 0, repeats = 0;
        for (size_t e = 0; e < g->ne; e++) {
            drop[e] = w.cyc_of[2 * e] == w.cyc_of[2 * e + 1];
            nbridge += drop[e];
        }
        for (size_t v = 0; v < g->nv; v++) stack[v] = 0; /* the last walk seen there, + 1 */
        for (size_t cy = 0; cy < w.ncyc; cy++) {
            outer += w.area2[cy] <= 0;
            for (uint32_t i = w.hoff[cy]; i < w.hoff[cy + 1]; i++) {
                uint32_t v = he_tail(g, w.hes[i]);
                if (stack[v] == cy + 1) repeats++;
                stack[v] = (uint32_t)cy + 1;
            }
        }
        if (g_stop(g, 2 * g->ne + 1)) {
            rc = ARR_ECANCELED;
            goto fail;
        }
        st->blocks = outer + repeats - (c->o->keep_dangling ? 0 : nbridge);
        if (c->o->keep_dangling || !nbridge) break;
        st->dangling_removed = nbridge;
        if (graph_prune(g, drop)) goto fail;
    }
    size_t ncomp = components(g, comp, stack);
    double t1 = now_ms();
    st->ms_biconnected = t1 - t0;
    progress(c, "biconnected", 1);
    progress(c, "faces", 0.55);
    comp_outer = malloc((ncomp + 1) * sizeof *comp_outer);
    face_of = malloc((w.ncyc + 1) * sizeof *face_of);
    face_idx = malloc((w.ncyc + 1) * sizeof *face_idx);
    if (!comp_outer || !face_of || !face_idx) goto fail;
    for (size_t k = 0; k < ncomp; k++) comp_outer[k] = NONE;
    size_t nf = 0, nouter = 0;
    for (size_t cy = 0; cy < w.ncyc; cy++) {
        face_of[cy] = NONE;
        face_idx[cy] = NONE;
        if (w.area2[cy] > 0) {
            face_idx[cy] = (uint32_t)nf++;
            face_of[cy] = (uint32_t)cy;
            continue;
        }
        uint32_t k = comp[he_tail(g, w.hes[w.hoff[cy]])];
        if (comp_outer[k] != NONE) {
            rc = util_seterr(err, el, ARR_EINTERNAL, "internal: a component with two outer walks");
            goto fail;
        }
        comp_outer[k] = (uint32_t)cy;
        nouter++;
    }
    if (nouter != ncomp ||
        (long long)g->nv - (long long)g->ne + (long long)w.ncyc != 2 * (long long)ncomp) {
        rc = util_seterr(err, el, ARR_EINTERNAL, "internal: the face walks are not planar");
        goto fail;
    }
    double t2 = now_ms();
    st->ms_faces = t2 - t1;
    progress(c, "faces", 0.7);

    /* holes */
    if (ncomp > 1) {
        rc = place_components(c, g, &w, comp, ncomp, comp_outer, face_of);
        if (rc) {
            if (rc == ARR_EINTERNAL)
                util_seterr(err, el, rc, "internal: inconsistent hole placement");
            goto fail;
        }
        rc = ARR_ENOMEM;
    }
    st->ms_holes = now_ms() - t2;
    progress(c, "faces", 0.85);

    /* output */
    if ((rc = emit_complex(c, g, &w, face_idx, face_of, nf, out, err, el))) goto fail;
    rc = ARR_ENOMEM;
    if (c->o->half_edges && keep_half_edges(g, &w, face_of, face_idx, nf, &pos, out)) goto fail;
    progress(c, "faces", 1);
    st->nv = g->nv;
    st->ne = g->ne;
    st->nf = nf;
    st->components = ncomp;
    rc = ARR_OK;
fail:
    if (rc == ARR_ENOMEM) util_seterr(err, el, rc, "out of memory");
    free(drop);
    free(pos);
    free(comp);
    free(stack);
    free(comp_outer);
    free(face_of);
    free(face_idx);
    walks_free(&w);
    return rc;
}

/* Frees the intermediate buffers and leaves them NULL, so it can run twice. */
static void ctx_free(ctx *c)
{
    free(c->seg);
    free(c->box);
    box_tree_free(&c->tree);
    free(c->pix);
    free(c->pl_off);
    free(c->pl_pix);
    free(c->sp_off);
    free(c->sp_pix);
    c->seg = NULL;
    c->pix = NULL;
    c->box = NULL;
    c->pl_off = c->pl_pix = c->sp_off = c->sp_pix = NULL;
    free(c->nbox);
    free(c->pinned);
    c->pinned = NULL;
    free(c->ep);
    c->ep = NULL;
    for (int w = 0; w < MAXW; w++) {
        free(c->nearp[w].p);
        free(c->nears[w].p);
        c->nearp[w] = c->nears[w] = (vbuf){0};
        free(c->cross[w].p);
        free(c->inc[w].p);
        free(c->edges[w].p);
        free(c->etags[w].p);
        free(c->scr[w].key);
        free(c->scr[w].val);
        c->cross[w] = c->inc[w] = c->edges[w] = c->etags[w] = (vbuf){0};
        c->scr[w] = (scratch){0};
    }
}

/* With input_coords: for every vertex (hot pixel, g->P sorted), the first input endpoint that
 * snapped to it (2i for segment i's start, 2i+1 for its end), or NONE for a crossing.  The split
 * stage noted the pixel of each endpoint of a segment of non-zero length (c->ep); the others are
 * looked up. */
static int vertex_sources(const ctx *c, const double *seg, size_t n, graph *g)
{
    g->src = malloc((g->nv + 1) * sizeof *g->src);
    if (!g->src) return -1;
    for (size_t v = 0; v < g->nv; v++) g->src[v] = NONE;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 2; k++) {
            uint32_t q = c->ep ? c->ep[2 * i + (size_t)k] : NONE;
            if (q != NONE) {
                if (g->src[q] == NONE && !(c->pinned && c->pinned[q]))
                    g->src[q] = (uint32_t)(2 * i + (size_t)k);
                continue;
            }
            ipt p = {snap_coord(c, 0, seg[4 * i + 2 * k]),
                     snap_coord(c, 1, seg[4 * i + 2 * k + 1])};
            size_t lo = 0, hi = g->nv;
            while (lo < hi) {
                size_t mid = lo + (hi - lo) / 2;
                if (ipt_cmp(g->P[mid], p) < 0)
                    lo = mid + 1;
                else
                    hi = mid;
            }
            if (lo < g->nv && ipt_cmp(g->P[lo], p) == 0 && g->src[lo] == NONE &&
                !(c->pinned && c->pinned[lo]))
                g->src[lo] = (uint32_t)(2 * i + (size_t)k);
        }
    return 0;
}

int arr2_build(const double *seg, size_t n, const arr2_opts *opts, lar2 *out, char *err,
               size_t errlen)
{
    static const arr2_opts defaults = {0};
    ctx *c = calloc(1, sizeof *c);
    graph g = {0};
    uint64_t *ev = NULL;
    size_t nev = 0;
    int rc;
    double t0 = now_ms();

    memset(out, 0, sizeof *out);
    if (err && errlen) err[0] = 0;
    if (!c) return util_seterr(err, errlen, ARR_ENOMEM, "out of memory");
    c->o = opts ? opts : &defaults;
    c->in = seg;
    c->n_in = n;
    c->threads = c->o->threads > 0 ? c->o->threads : par_ncpu();
    if (c->threads > MAXW) c->threads = MAXW;
    atomic_init(&c->fail, 0);
    for (int w = 0; w < MAXW; w++) c->meter[w].flag = c->o->cancel;
    c->serial.flag = c->o->cancel;
    g.stop = &c->serial;
    out->stats.input_segments = n;
    if (n > ARR2_MAX_SEGMENTS) {
        rc = util_seterr(err, errlen, ARR_ELIMIT, "lines: %zu segments, more than the limit of %u",
                         n, ARR2_MAX_SEGMENTS);
        goto fail;
    }
    progress(c, "snap", 0);
    if ((rc = stage_snap(c, seg, n, &out->stats, err, errlen))) goto fail;
    if ((rc = check_range(c, err, errlen))) goto fail;
    out->stats.ms_snap = now_ms() - t0;
    progress(c, "snap", 1);
    uint32_t *toff = NULL, *tags = NULL;
    int32_t *tw = NULL;
    if ((rc = stage_split(c, &out->stats, &ev, &nev, &toff, &tags, &tw, err, errlen))) goto fail;
    g.toff = toff;
    g.tag = tags;
    g.tw = tw;
    if (cancelled(c)) {
        rc = ARR_ECANCELED;
        goto fail;
    }

    /* graph: the hot pixels as vertices, the unique edges; unused pixels cannot occur
     * (each is an endpoint or a crossing, so on a segment) */
    double tg = now_ms();
    g.nv = c->npix;
    g.ne = nev;
    g.P = c->pix;
    c->pix = NULL;
    if (c->o->input_coords && vertex_sources(c, seg, n, &g)) {
        rc = util_seterr(err, errlen, ARR_ENOMEM, "out of memory");
        goto fail;
    }
    g.EV = malloc((2 * nev + 1) * sizeof *g.EV);
    if (!g.EV) {
        rc = util_seterr(err, errlen, ARR_ENOMEM, "out of memory");
        goto fail;
    }
    for (size_t e = 0; e < nev; e++) {
        g.EV[2 * e] = (uint32_t)(ev[e] >> 32);
        g.EV[2 * e + 1] = (uint32_t)ev[e];
    }
    free(ev);
    ev = NULL;
    ctx_free(c); /* the big intermediate buffers are done with */
    out->stats.ms_graph = now_ms() - tg;
    if ((rc = build_complex(c, &g, out, err, errlen))) goto fail;
    out->stats.ms_total = now_ms() - t0;
    graph_free(&g);
    free(c);
    return ARR_OK;
fail : {
    arr2_stats keep = out->stats;
    lar2_free(out);
    out->stats = keep;
}
    if (rc == ARR_ECANCELED) util_seterr(err, errlen, rc, "cancelled");
    free(ev);
    graph_free(&g);
    ctx_free(c);
    free(c);
    return rc;
}

void lar2_free_half_edges(lar2 *c)
{
    free(c->he_face), free(c->he_off), free(c->he_out), free(c->he_pos);
    c->he_face = c->he_off = c->he_out = c->he_pos = NULL;
}

void lar2_free(lar2 *c)
{
    lar2_free_half_edges(c);
    free(c->V);
    free(c->VG);
    free(c->etag_off);
    free(c->etag);
    free(c->etagw);
    free(c->EV);
    free(c->face_cycle);
    free(c->hole_off);
    free(c->hole_cyc);
    free(c->fe_off);
    free(c->fe);
    free(c->cyc_off);
    free(c->cyc);
    free(c->ext_cyc);
    memset(c, 0, sizeof *c);
}

double lar2_cycle_area(const lar2 *c, uint32_t cy)
{
    double a = 0;
    uint32_t b = c->cyc_off[cy], e = c->cyc_off[cy + 1];
    if (e - b < 3) return 0;
    double x0 = c->V[2 * c->cyc[b]], y0 = c->V[2 * c->cyc[b] + 1];
    for (uint32_t i = b + 1; i + 1 < e; i++) {
        double x1 = c->V[2 * c->cyc[i]] - x0, y1 = c->V[2 * c->cyc[i] + 1] - y0;
        double x2 = c->V[2 * c->cyc[i + 1]] - x0, y2 = c->V[2 * c->cyc[i + 1] + 1] - y0;
        a += x1 * y2 - x2 * y1;
    }
    return a / 2;
}
