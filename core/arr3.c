/* arr3.c — the arrangement of solids (the 3D pipeline of DESIGN.md; interface in arr3.h).
 *
 * Everything works on one integer grid (grid units below): a vertex is an int64 triple, equal
 * triples are one vertex (vtab).  Planes are per plane group: the faces lying in one plane
 * (within COPLANAR_TOL grid units) share the plane of their first face, with an integer Newell
 * normal (exact, for the angular sort) and a unit double normal and offset (for constructions).
 *
 * Shared segments ("seg3") are the only way a group learns about its neighbours: the input
 * faces' edges and the cut segments between faces of different groups.  A segment has its two
 * endpoints, the two planes it lies on, the groups that use it, and a set of split points.  Each
 * group is split by arr2 on the polylines of its segments; a vertex of that arrangement lying on
 * a piece (the exact hot-pixel rule of arr2) becomes a split point of the piece's segment for
 * every group using it.  The rounds stop when no group adds a split point: then every group's
 * arrangement has exactly the vertices its segments carry, and the faces on both sides of any
 * segment agree on its pieces.
 *
 * Constructions (a point where an edge crosses a plane, where three planes meet) are computed in
 * doubles from canonical inputs (the edge from its lower vertex id, the planes in group order),
 * so a point computed twice from the same inputs rounds to the same grid point.  Decisions that
 * make the complex (angular order of faces around an edge) are exact: integer normals and
 * 256-bit determinants.  The ray that places a nested part in a cell of another part uses a
 * generic direction in doubles and is shot again in another direction when it passes within
 * RAY_EPS of an edge.
 *
 * Threads: the plane groups of a round run on par_for(); each writes only its own group and its
 * own request lists; ids are assigned after the round, in group order, so the result does not
 * depend on the number of threads.
 */
#include "core/arr3.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/num.h"
#include "core/par.h"

#define NONE         UINT32_MAX
#define COPLANAR_TOL 2.0 /* grid units: faces this close to each other's plane share it */
#define PARALLEL_EPS 1e-12
#define RAY_EPS      1e-6 /* grid units */
#define RAY_TRIES    8
#define TINY_EDGE    4    /* grid units (per axis): see merge_tiny_edges() */
#define FAR_PX       1024 /* grid units: a point of three planes farther is not used */

/* ------------------------------------------------------------------ small tools */

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static int seterr(char *err, size_t errlen, int code, const char *fmt, ...)
{
    if (err && errlen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return code;
}

/* Grows *p (elements of size elem, capacity *cap) to hold need elements; 0 or -1. */
static int grow(void *pp, size_t *cap, size_t need, size_t elem)
{
    void **p = pp;
    if (need <= *cap) return 0;
    size_t nc = *cap ? *cap : 16;
    while (nc < need) nc *= 2;
    void *q = realloc(*p, nc * elem);
    if (!q) return -1;
    *p = q;
    *cap = nc;
    return 0;
}

#define PUSH(arr, n, cap, val)                                                                     \
    (grow(&(arr), &(cap), (n) + 1, sizeof *(arr)) ? -1 : ((arr)[(n)++] = (val), 0))

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 33;
    x *= 0xff51afd7ed558ccdULL;
    x ^= x >> 33;
    x *= 0xc4ceb9fe1a85ec53ULL;
    x ^= x >> 33;
    return x;
}

/* u64 -> u32 open-addressing map (key UINT64_MAX reserved). */
typedef struct umap {
    uint64_t *key;
    uint32_t *val;
    size_t cap, n; /* cap a power of two */
} umap;

static void umap_free(umap *m)
{
    free(m->key);
    free(m->val);
    memset(m, 0, sizeof *m);
}

static int umap_rehash(umap *m, size_t ncap)
{
    uint64_t *k = malloc(ncap * sizeof *k);
    uint32_t *v = malloc(ncap * sizeof *v);
    if (!k || !v) {
        free(k);
        free(v);
        return -1;
    }
    memset(k, 0xff, ncap * sizeof *k);
    for (size_t i = 0; i < m->cap; i++) {
        if (m->key[i] == UINT64_MAX) continue;
        size_t h = mix64(m->key[i]) & (ncap - 1);
        while (k[h] != UINT64_MAX) h = (h + 1) & (ncap - 1);
        k[h] = m->key[i];
        v[h] = m->val[i];
    }
    free(m->key);
    free(m->val);
    m->key = k;
    m->val = v;
    m->cap = ncap;
    return 0;
}

/* Returns the value of key, inserting val when absent (*found tells which); NONE on ENOMEM. */
static uint32_t umap_put(umap *m, uint64_t key, uint32_t val, int *found)
{
    if (2 * (m->n + 1) > m->cap && umap_rehash(m, m->cap ? 2 * m->cap : 64)) return NONE;
    size_t h = mix64(key) & (m->cap - 1);
    while (m->key[h] != UINT64_MAX) {
        if (m->key[h] == key) {
            if (found) *found = 1;
            return m->val[h];
        }
        h = (h + 1) & (m->cap - 1);
    }
    m->key[h] = key;
    m->val[h] = val;
    m->n++;
    if (found) *found = 0;
    return val;
}

static uint32_t umap_get(const umap *m, uint64_t key)
{
    if (!m->cap) return NONE;
    size_t h = mix64(key) & (m->cap - 1);
    while (m->key[h] != UINT64_MAX) {
        if (m->key[h] == key) return m->val[h];
        h = (h + 1) & (m->cap - 1);
    }
    return NONE;
}

static uint64_t key2(uint32_t a, uint32_t b)
{
    return (uint64_t)a << 32 | b;
}

static int cmpu64(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return (a > b) - (a < b);
}

static int cmpd(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

static int cmpu32(const void *pa, const void *pb)
{
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    return (a > b) - (a < b);
}

static int ekcmp(const void *pa, const void *pb, void *vk)
{
    const uint64_t *k = vk;
    uint64_t a = k[*(const uint32_t *)pa], b = k[*(const uint32_t *)pb];
    return (a > b) - (a < b);
}
/* ------------------------------------------------------------------ exact 256-bit sign */

/* Sign of a0*b0 + a1*b1 + a2*b2 for |a|, |b| < 2^126, exactly (five 64-bit limbs, two's
 * complement: the sum is below 2^255). */
static int sign_dot3(const i128 *a, const i128 *b)
{
    uint64_t acc[5] = {0};
    for (int i = 0; i < 3; i++) {
        int neg = (a[i] < 0) != (b[i] < 0);
        unsigned __int128 x = a[i] < 0 ? -(unsigned __int128)a[i] : (unsigned __int128)a[i];
        unsigned __int128 y = b[i] < 0 ? -(unsigned __int128)b[i] : (unsigned __int128)b[i];
        uint64_t x0 = (uint64_t)x, x1 = (uint64_t)(x >> 64);
        uint64_t y0 = (uint64_t)y, y1 = (uint64_t)(y >> 64);
        unsigned __int128 p00 = (unsigned __int128)x0 * y0, p01 = (unsigned __int128)x0 * y1;
        unsigned __int128 p10 = (unsigned __int128)x1 * y0, p11 = (unsigned __int128)x1 * y1;
        uint64_t p[5] = {0};
        unsigned __int128 t = (unsigned __int128)(uint64_t)p00;
        p[0] = (uint64_t)t;
        t = (p00 >> 64) + (uint64_t)p01 + (unsigned __int128)(uint64_t)p10;
        p[1] = (uint64_t)t;
        t = (t >> 64) + (p01 >> 64) + (p10 >> 64) + (uint64_t)p11;
        p[2] = (uint64_t)t;
        t = (t >> 64) + (p11 >> 64);
        p[3] = (uint64_t)t;
        if (neg) { /* two's complement of the 320-bit value */
            unsigned carry = 1;
            for (int k = 0; k < 5; k++) {
                unsigned __int128 s = (unsigned __int128)(uint64_t)~p[k] + carry;
                p[k] = (uint64_t)s;
                carry = (unsigned)(s >> 64);
            }
        }
        unsigned carry = 0;
        for (int k = 0; k < 5; k++) {
            unsigned __int128 s = (unsigned __int128)acc[k] + p[k] + carry;
            acc[k] = (uint64_t)s;
            carry = (unsigned)(s >> 64);
        }
    }
    if (acc[4] >> 63) return -1;
    for (int k = 0; k < 5; k++)
        if (acc[k]) return 1;
    return 0;
}

static void cross_i128(const i128 *a, const int64_t *e, i128 *out)
{
    out[0] = a[1] * e[2] - a[2] * e[1];
    out[1] = a[2] * e[0] - a[0] * e[2];
    out[2] = a[0] * e[1] - a[1] * e[0];
}

/* ------------------------------------------------------------------ the state */

typedef struct iface { /* an input face */
    uint32_t solid;    /* solid index; in a soup, the face's own index */
    uint32_t c0, nc;   /* its cycles: icyc_off[c0 .. c0 + nc) */
    int64_t box[6];    /* lo xyz, hi xyz (grid units) */
    uint32_t group;
} iface;

typedef struct group {
    uint32_t rep;    /* representative face: the plane's */
    int k;           /* dropped axis: the largest component of the normal */
    i128 n[3];       /* integer Newell normal of rep */
    double nd[3], d; /* unit normal and offset: nd . x = d (grid units) */
    lar2 res;        /* this group's arrangement (last round it ran) */
    uint32_t *rgid;  /* res.nv: global vertex of each arrangement vertex */
    uint32_t *rseg;  /* res.ne: a segment each arrangement edge is a whole piece of, or NONE */
    i128 ni[3];      /* the unit normal scaled by 2^40 and rounded: the fan order's planes */
    int dirty;
    int trivial;     /* one face that nothing cuts or splits: it is its own arrangement */
    uint32_t nfaces; /* input faces in the group */
} group;

typedef struct seg3 {
    uint32_t a, b;   /* endpoints (global vertex ids) */
    uint32_t p0, p1; /* the planes (groups) it lies on; p0 == p1 for a flat edge */
    uint32_t *sp;    /* split points */
    uint32_t nsp, capsp;
} seg3;

/* What one group's round asks for, applied after the round. */
typedef struct greq {
    int64_t *newp; /* 3 per new vertex proposed: grid coordinates */
    size_t nnew, capnew;
    uint64_t *split; /* (segment << 32 | vertex ref): ref < 2^31 a global id, else new index */
    size_t nsplit, capsplit;
    uint64_t *merge; /* pairs of global ids with one projection: to merge */
    size_t nmerge, capmerge;
    int rc; /* ARR_* of this group's run */
    char err[160];
} greq;

typedef struct ctx {
    const arr3_opts *o;
    int threads;
    size_t fins;   /* faces with one cell on both sides (stage_cells) */
    double step;   /* grid step */
    int64_t oi[3]; /* origin: world = (oi + g) * step */
    /* vertices */
    int64_t *P;
    size_t nv, capv;
    uint32_t *alias; /* union-find over merged vertices */
    size_t capalias;
    uint32_t *vtab; /* open addressing over P */
    size_t vcap;
    /* input faces */
    iface *F;
    size_t nf;
    uint32_t *icyc_off, *icyc;
    size_t nicyc, ncv, capicyc_off, capicyc;
    size_t nsolids;
    uint32_t *solid_face_off;
    /* groups */
    group *G;
    size_t ng;
    /* segments */
    seg3 *S;
    size_t ns, caps;
    umap edge_seg;    /* (lo, hi) -> E segment */
    uint32_t *sg_off; /* ns+1: groups of segment s: sg[sg_off[s] ..) */
    uint32_t *sg;
    uint32_t *gs_off; /* ng+1: segments of group g */
    uint32_t *gs;
    greq *req; /* ng */
    arr3_stats *st;
} ctx;

static int cancelled(const ctx *c)
{
    return c->o->cancel && atomic_load(c->o->cancel);
}

static void progress(const ctx *c, const char *stage, double f)
{
    if (c->o->progress) c->o->progress(c->o->udata, stage, f);
}

static uint32_t vfind(const ctx *c, uint32_t v)
{
    while (c->alias[v] != v) v = c->alias[v];
    return v;
}

static uint64_t hash_pt(const int64_t *x)
{
    return mix64((uint64_t)x[0] * 0x9e3779b97f4a7c15ULL ^ mix64((uint64_t)x[1] + 0x632be5ab) ^
                 ((uint64_t)x[2] << 21 | (uint64_t)x[2] >> 43));
}

static int vtab_rehash(ctx *c, size_t ncap)
{
    uint32_t *t = malloc(ncap * sizeof *t);
    if (!t) return -1;
    memset(t, 0xff, ncap * sizeof *t);
    for (size_t v = 0; v < c->nv; v++) {
        size_t h = hash_pt(c->P + 3 * v) & (ncap - 1);
        while (t[h] != NONE) h = (h + 1) & (ncap - 1);
        t[h] = (uint32_t)v;
    }
    free(c->vtab);
    c->vtab = t;
    c->vcap = ncap;
    return 0;
}

/* The vertex at grid point x, made when absent; NONE when out of memory. */
static uint32_t vertex_at(ctx *c, const int64_t *x)
{
    if (2 * (c->nv + 1) > c->vcap && vtab_rehash(c, c->vcap ? 2 * c->vcap : 1024)) return NONE;
    size_t h = hash_pt(x) & (c->vcap - 1);
    while (c->vtab[h] != NONE) {
        const int64_t *q = c->P + 3 * (size_t)c->vtab[h];
        if (q[0] == x[0] && q[1] == x[1] && q[2] == x[2]) return c->vtab[h];
        h = (h + 1) & (c->vcap - 1);
    }
    if (c->nv >= 0x7fffffffu) return NONE;
    if (grow(&c->P, &c->capv, 3 * (c->nv + 1), sizeof *c->P)) return NONE;
    if (grow(&c->alias, &c->capalias, c->nv + 1, sizeof *c->alias)) return NONE;
    uint32_t id = (uint32_t)c->nv++;
    memcpy(c->P + 3 * (size_t)id, x, 3 * sizeof *x);
    c->alias[id] = id;
    c->vtab[h] = id;
    return id;
}

static uint32_t vertex_round(ctx *c, const double *x)
{
    int64_t g[3] = {llround(x[0]), llround(x[1]), llround(x[2])};
    return vertex_at(c, g);
}

static void pt(const ctx *c, uint32_t v, double *x)
{
    const int64_t *p = c->P + 3 * (size_t)v;
    x[0] = (double)p[0], x[1] = (double)p[1], x[2] = (double)p[2];
}

/* The 2D coordinates of grid point p in a plane that drops axis k (right-handed: (k+1, k+2)). */
static ipt proj(const int64_t *p, int k)
{
    ipt q = {p[(k + 1) % 3], p[(k + 2) % 3]};
    return q;
}

static double plane_dist(const group *g, const double *x)
{
    return g->nd[0] * x[0] + g->nd[1] * x[1] + g->nd[2] * x[2] - g->d;
}

/* ------------------------------------------------------------------ stage 1: input */

static int stage_input(ctx *c, const solid *solids, size_t ns, int soup, char *err, size_t el)
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    size_t nfaces = 0;
    for (size_t s = 0; s < ns; s++) {
        for (size_t i = 0; i < solids[s].nv; i++)
            for (int a = 0; a < 3; a++) {
                double x = solids[s].V[3 * i + a];
                if (!isfinite(x))
                    return seterr(err, el, ARR_EINVAL, "solids[%zu]: vertex %zu is not finite", s,
                                  i);
                if (x < lo[a]) lo[a] = x;
                if (x > hi[a]) hi[a] = x;
            }
        nfaces += solids[s].nf;
    }
    c->st->input_solids = ns;
    c->st->input_faces = nfaces;
    if (nfaces > ARR3_MAX_FACES)
        return seterr(err, el, ARR_ELIMIT, "solids: %zu faces, more than the limit of %u", nfaces,
                      ARR3_MAX_FACES);
    c->solid_face_off = calloc(ns + 1, sizeof *c->solid_face_off);
    if (!c->solid_face_off) return seterr(err, el, ARR_ENOMEM, "out of memory");
    c->nsolids = ns;
    if (!nfaces) return ARR_OK;
    double ext = 0;
    for (int a = 0; a < 3; a++)
        if (hi[a] - lo[a] > ext) ext = hi[a] - lo[a];
    double step = c->o->precision;
    if (step < 0 || !isfinite(step))
        return seterr(err, el, ARR_EINVAL, "precision: expected a positive number");
    if (step == 0) {
        step = ext > 0 ? exp2(ceil(log2(ext * exp2(-ARR3_GRID_BITS)))) : 1;
        if (step < DBL_MIN) step = DBL_MIN;
    } else if (ext / step > exp2(ARR3_GRID_BITS)) {
        return seterr(err, el, ARR_ELIMIT,
                      "precision: %g is finer than extent / 2^%d = %g; use a coarser grid", step,
                      ARR3_GRID_BITS, ext * exp2(-ARR3_GRID_BITS));
    }
    c->step = step;
    c->st->precision = step;
    for (int a = 0; a < 3; a++) c->oi[a] = llround((lo[a] + hi[a]) / 2 / step);

    c->F = calloc(nfaces, sizeof *c->F);
    if (!c->F) return seterr(err, el, ARR_ENOMEM, "out of memory");
    uint32_t *map = NULL;
    size_t capmap = 0;
    for (size_t s = 0; s < ns; s++) {
        const solid *so = &solids[s];
        if (grow(&map, &capmap, so->nv + 1, sizeof *map)) goto oom;
        for (size_t i = 0; i < so->nv; i++) {
            int64_t g[3];
            for (int a = 0; a < 3; a++) g[a] = llround(so->V[3 * i + a] / step) - c->oi[a];
            if ((map[i] = vertex_at(c, g)) == NONE) goto oom;
        }
        c->solid_face_off[s] = (uint32_t)c->nf;
        for (size_t f = 0; f < so->nf; f++) {
            iface *F = &c->F[c->nf];
            F->solid = soup ? (uint32_t)c->nf : (uint32_t)s;
            F->c0 = (uint32_t)c->nicyc;
            F->nc = 0;
            for (int a = 0; a < 3; a++) F->box[a] = INT64_MAX, F->box[3 + a] = INT64_MIN;
            for (uint32_t cy = so->face_off[f]; cy < so->face_off[f + 1]; cy++) {
                size_t start = c->ncv;
                for (uint32_t i = so->cyc_off[cy]; i < so->cyc_off[cy + 1]; i++) {
                    uint32_t vi = so->cyc[i];
                    if (vi >= so->nv) {
                        free(map);
                        return seterr(err, el, ARR_EINVAL,
                                      "solids[%zu]: face %zu: vertex index %u out of range", s, f,
                                      vi);
                    }
                    uint32_t v = map[vi];
                    if (c->ncv > start && c->icyc[c->ncv - 1] == v) continue;
                    if (PUSH(c->icyc, c->ncv, c->capicyc, v)) goto oom;
                }
                while (c->ncv - start > 1 && c->icyc[c->ncv - 1] == c->icyc[start]) c->ncv--;
                if (c->ncv - start < 3) { /* collapsed on the grid */
                    c->ncv = start;
                    if (cy == so->face_off[f]) break; /* outer cycle gone: face gone */
                    continue;
                }
                if (grow(&c->icyc_off, &c->capicyc_off, c->nicyc + 2, sizeof *c->icyc_off))
                    goto oom;
                c->icyc_off[c->nicyc] = (uint32_t)start;
                c->icyc_off[++c->nicyc] = (uint32_t)c->ncv;
                F->nc++;
                for (size_t i = start; i < c->ncv; i++)
                    for (int a = 0; a < 3; a++) {
                        int64_t x = c->P[3 * (size_t)c->icyc[i] + a];
                        if (x < F->box[a]) F->box[a] = x;
                        if (x > F->box[3 + a]) F->box[3 + a] = x;
                    }
            }
            if (F->nc == 0) {
                c->nicyc = F->c0;
                c->ncv = c->nicyc ? c->icyc_off[c->nicyc] : 0;
                continue;
            }
            c->nf++;
        }
    }
    c->solid_face_off[ns] = (uint32_t)c->nf;
    free(map);
    return ARR_OK;
oom:
    free(map);
    return seterr(err, el, ARR_ENOMEM, "out of memory");
}

static uint32_t cyc_len(const ctx *c, uint32_t cy)
{
    return c->icyc_off[cy + 1] - c->icyc_off[cy];
}

static const uint32_t *cyc_v(const ctx *c, uint32_t cy)
{
    return c->icyc + c->icyc_off[cy];
}

/* Edge i of input cycle cy, as (lower id, higher id): how every face sharing it sees it. */
static void cyc_edge(const ctx *c, uint32_t cy, uint32_t i, uint32_t *lo, uint32_t *hi)
{
    const uint32_t *v = cyc_v(c, cy);
    uint32_t p = v[i], q = v[(i + 1) % cyc_len(c, cy)];
    *lo = p < q ? p : q;
    *hi = p ^ q ^ *lo;
}

/* ------------------------------------------------------------------ stage 2: pairs, groups */

static int box_overlap(const int64_t *a, const int64_t *b, int64_t slack)
{
    for (int k = 0; k < 3; k++)
        if (a[k] > b[3 + k] + slack || b[k] > a[3 + k] + slack) return 0;
    return 1;
}

/* The box-kd-tree of the seeds ("Construction of independent buckets"), in 3D: the faces'
 * boxes (grown by the coplanar slack) are split at the mean of their centres along the axis
 * where the centres spread most; a box meeting both sides goes to both.  A bucket stops
 * splitting when it is small, when a split would leave 7/8 of it on each side, or when it would
 * copy more than a third of its boxes to both sides.  Every pair of
 * boxes that meet shares at least one bucket; pairs found in two buckets are made unique at the
 * end. */
#define KD_LEAF 24

typedef struct kdwork {
    const iface *F;
    int64_t slack;
    uint64_t *pairs;
    size_t np, cap;
    int fail;
} kdwork;

static void kd_leaf(kdwork *w, const uint32_t *ids, size_t n)
{
    for (size_t i = 0; i < n && !w->fail; i++)
        for (size_t j = i + 1; j < n; j++) {
            if (!box_overlap(w->F[ids[i]].box, w->F[ids[j]].box, w->slack)) continue;
            uint32_t a = ids[i] < ids[j] ? ids[i] : ids[j], b = ids[i] ^ ids[j] ^ a;
            if (PUSH(w->pairs, w->np, w->cap, key2(a, b))) {
                w->fail = 1;
                return;
            }
        }
}

static void kd_split(kdwork *w, uint32_t *ids, size_t n, int depth)
{
    if (w->fail) return;
    if (n <= KD_LEAF || depth > 40) {
        kd_leaf(w, ids, n);
        return;
    }
    double mean[3] = {0, 0, 0}, lo[3], hi[3];
    for (int a = 0; a < 3; a++) lo[a] = DBL_MAX, hi[a] = -DBL_MAX;
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            const int64_t *b = w->F[ids[i]].box;
            double ctr = ((double)b[a] + (double)b[3 + a]) / 2;
            mean[a] += ctr;
            if (ctr < lo[a]) lo[a] = ctr;
            if (ctr > hi[a]) hi[a] = ctr;
        }
    int ax = 0;
    for (int a = 1; a < 3; a++)
        if (hi[a] - lo[a] > hi[ax] - lo[ax]) ax = a;
    double t = mean[ax] / (double)n;
    size_t nl = 0, nr = 0;
    for (size_t i = 0; i < n; i++) {
        const int64_t *b = w->F[ids[i]].box;
        nl += (double)(b[ax] - w->slack) <= t;
        nr += (double)(b[3 + ax] + w->slack) > t;
    }
    /* no split that leaves 7/8 on a side, nor one that copies more than a third of the boxes
     * to both sides (the boxes are then as large as the bucket: splitting only repeats them) */
    if ((nl * 8 >= n * 7 && nr * 8 >= n * 7) || (nl + nr - n) * 3 > n) {
        kd_leaf(w, ids, n);
        return;
    }
    uint32_t *l = malloc((nl + 1) * sizeof *l), *r = malloc((nr + 1) * sizeof *r);
    if (!l || !r) {
        free(l);
        free(r);
        w->fail = 1;
        return;
    }
    nl = nr = 0;
    for (size_t i = 0; i < n; i++) {
        const int64_t *b = w->F[ids[i]].box;
        if ((double)(b[ax] - w->slack) <= t) l[nl++] = ids[i];
        if ((double)(b[3 + ax] + w->slack) > t) r[nr++] = ids[i];
    }
    kd_split(w, l, nl, depth + 1);
    free(l);
    kd_split(w, r, nr, depth + 1);
    free(r);
}

/* Candidate pairs (a < b) of faces whose boxes meet (with slack for the coplanar tolerance),
 * sorted, each once. */
static int face_pairs(ctx *c, uint64_t **out, size_t *nout)
{
    uint32_t *ids = malloc((c->nf + 1) * sizeof *ids);
    kdwork w = {c->F, (int64_t)ceil(COPLANAR_TOL), NULL, 0, 0, 0};
    if (!ids) return -1;
    for (size_t i = 0; i < c->nf; i++) ids[i] = (uint32_t)i;
    kd_split(&w, ids, c->nf, 0);
    free(ids);
    if (w.fail) {
        free(w.pairs);
        return -1;
    }
    if (w.np > 1) qsort(w.pairs, w.np, sizeof *w.pairs, cmpu64);
    size_t m = 0;
    for (size_t i = 0; i < w.np; i++)
        if (!m || w.pairs[i] != w.pairs[m - 1]) w.pairs[m++] = w.pairs[i];
    *out = w.pairs;
    *nout = m;
    return 0;
}

static void newell(const ctx *c, uint32_t f, i128 *n)
{
    uint32_t cy = c->F[f].c0, len = cyc_len(c, cy);
    const uint32_t *v = cyc_v(c, cy);
    n[0] = n[1] = n[2] = 0;
    for (uint32_t i = 0; i < len; i++) {
        const int64_t *p = c->P + 3 * (size_t)v[i], *q = c->P + 3 * (size_t)v[(i + 1) % len];
        n[0] += (i128)(p[1] - q[1]) * (p[2] + q[2]);
        n[1] += (i128)(p[2] - q[2]) * (p[0] + q[0]);
        n[2] += (i128)(p[0] - q[0]) * (p[1] + q[1]);
    }
}

static void group_plane(ctx *c, group *g)
{
    newell(c, g->rep, g->n);
    double n[3] = {(double)g->n[0], (double)g->n[1], (double)g->n[2]};
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int a = 0; a < 3; a++) g->nd[a] = len > 0 ? n[a] / len : 0;
    for (int a = 0; a < 3; a++) g->ni[a] = (i128)llround(ldexp(g->nd[a], 40));
    g->k = 0;
    for (int a = 1; a < 3; a++)
        if (fabs(n[a]) > fabs(n[g->k])) g->k = a;
    uint32_t cy = c->F[g->rep].c0, len2 = cyc_len(c, cy);
    const uint32_t *v = cyc_v(c, cy);
    double d = 0;
    for (uint32_t i = 0; i < len2; i++) {
        double x[3];
        pt(c, v[i], x);
        d += g->nd[0] * x[0] + g->nd[1] * x[1] + g->nd[2] * x[2];
    }
    g->d = d / len2;
}

/* Are all vertices of face f within COPLANAR_TOL of plane g? */
static int face_on_plane(const ctx *c, uint32_t f, const group *g)
{
    const iface *F = &c->F[f];
    for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
        const uint32_t *v = cyc_v(c, cy);
        for (uint32_t i = 0; i < cyc_len(c, cy); i++) {
            double x[3];
            pt(c, v[i], x);
            if (fabs(plane_dist(g, x)) > COPLANAR_TOL) return 0;
        }
    }
    return 1;
}

static uint32_t uf_find(uint32_t *p, uint32_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

static void uf_union(uint32_t *p, uint32_t a, uint32_t b)
{
    a = uf_find(p, a), b = uf_find(p, b);
    if (a == b) return;
    if (a < b)
        p[b] = a;
    else
        p[a] = b;
}

/* Do faces a and b have an edge (two consecutive vertices, either way) in common? */
static int share_edge(const ctx *c, uint32_t a, uint32_t b)
{
    const iface *A = &c->F[a], *B = &c->F[b];
    for (uint32_t ca = A->c0; ca < A->c0 + A->nc; ca++) {
        const uint32_t *va = cyc_v(c, ca);
        uint32_t la = cyc_len(c, ca);
        for (uint32_t i = 0; i < la; i++) {
            uint32_t p = va[i], q = va[(i + 1) % la];
            for (uint32_t cb = B->c0; cb < B->c0 + B->nc; cb++) {
                const uint32_t *vb = cyc_v(c, cb);
                uint32_t lb = cyc_len(c, cb);
                for (uint32_t j = 0; j < lb; j++) {
                    uint32_t r = vb[j], s = vb[(j + 1) % lb];
                    if ((p == r && q == s) || (p == s && q == r)) return 1;
                }
            }
        }
    }
    return 0;
}

/* Plane groups: a face's own plane first, then faces lying on one another's planes are joined.
 * Returns 0 or -1 (ENOMEM).  pairs is left holding only the pairs of different groups. */
static int stage_groups(ctx *c, uint64_t *pairs, size_t *np)
{
    uint32_t *par = malloc((c->nf + 1) * sizeof *par);
    group *tmp = calloc(c->nf + 1, sizeof *tmp);
    if (!par || !tmp) goto oom;
    for (size_t f = 0; f < c->nf; f++) {
        par[f] = (uint32_t)f;
        tmp[f].rep = (uint32_t)f;
        group_plane(c, &tmp[f]);
    }
    for (size_t i = 0; i < *np; i++) {
        uint32_t a = (uint32_t)(pairs[i] >> 32), b = (uint32_t)pairs[i];
        double dot =
            tmp[a].nd[0] * tmp[b].nd[0] + tmp[a].nd[1] * tmp[b].nd[1] + tmp[a].nd[2] * tmp[b].nd[2];
        if (fabs(dot) < 0.99) continue;
        if (face_on_plane(c, b, &tmp[a]) && face_on_plane(c, a, &tmp[b])) uf_union(par, a, b);
    }
    /* groups numbered by their smallest face */
    size_t ng = 0;
    for (size_t f = 0; f < c->nf; f++) {
        uint32_t r = uf_find(par, (uint32_t)f);
        if (r == f)
            c->F[f].group = (uint32_t)ng++;
        else
            c->F[f].group = c->F[r].group;
    }
    c->G = calloc(ng + 1, sizeof *c->G);
    c->req = calloc(ng + 1, sizeof *c->req);
    if (!c->G || !c->req) goto oom;
    c->ng = ng;
    for (size_t f = 0; f < c->nf; f++) {
        group *g = &c->G[c->F[f].group];
        if (uf_find(par, (uint32_t)f) == f) *g = tmp[f];
    }
    for (size_t g = 0; g < ng; g++) c->G[g].dirty = 1;
    size_t m = 0, ncop = 0;
    for (size_t i = 0; i < *np; i++) {
        uint32_t a = (uint32_t)(pairs[i] >> 32), b = (uint32_t)pairs[i];
        if (c->F[a].group != c->F[b].group) pairs[m++] = pairs[i];
    }
    *np = m;
    uint32_t *cnt = calloc(ng + 1, sizeof *cnt);
    if (!cnt) goto oom;
    for (size_t f = 0; f < c->nf; f++) cnt[c->F[f].group]++;
    for (size_t g = 0; g < ng; g++) {
        ncop += cnt[g] > 1;
        c->G[g].nfaces = cnt[g];
    }
    free(cnt);
    c->st->planes = ng;
    c->st->coplanar_groups = ncop;
    free(par);
    free(tmp);
    return 0;
oom:
    free(par);
    free(tmp);
    return -1;
}

/* ------------------------------------------------------------------ stage 3: segments, cuts */

static uint32_t seg_new(ctx *c, uint32_t a, uint32_t b, uint32_t p0, uint32_t p1)
{
    seg3 s = {a, b, p0, p1, NULL, 0, 0};
    if (PUSH(c->S, c->ns, c->caps, s)) return NONE;
    return (uint32_t)(c->ns - 1);
}

/* The E segments: one per edge of the input faces, on the planes of the first two groups that
 * use it. */
static int stage_edges(ctx *c)
{
    for (size_t f = 0; f < c->nf; f++) {
        const iface *F = &c->F[f];
        for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
            for (uint32_t i = 0; i < cyc_len(c, cy); i++) {
                uint32_t a, b;
                cyc_edge(c, cy, i, &a, &b);
                int found;
                uint32_t s = umap_put(&c->edge_seg, key2(a, b), (uint32_t)c->ns, &found);
                if (s == NONE) return -1;
                if (!found) {
                    if (seg_new(c, a, b, F->group, F->group) == NONE) return -1;
                } else if (c->S[s].p1 == c->S[s].p0 && F->group != c->S[s].p0) {
                    c->S[s].p1 = F->group;
                }
            }
        }
    }
    return 0;
}

static int seg_add_split(seg3 *s, uint32_t v)
{
    if (v == s->a || v == s->b) return 0;
    for (uint32_t i = 0; i < s->nsp; i++)
        if (s->sp[i] == v) return 0;
    size_t n = s->nsp, cap = s->capsp;
    if (PUSH(s->sp, n, cap, v)) return -1;
    s->nsp = (uint32_t)n;
    s->capsp = (uint32_t)cap;
    return 1;
}

typedef struct xing {
    double lam;   /* position along the cut line */
    uint32_t v;   /* the vertex (rounded) */
    uint32_t seg; /* the E segment crossed */
} xing;

static int xing_cmp(const void *pa, const void *pb)
{
    const xing *a = pa, *b = pb;
    if (a->lam != b->lam) return a->lam < b->lam ? -1 : 1;
    return (a->v > b->v) - (a->v < b->v);
}

/* Where face f's boundary crosses plane g: the crossings along direction u, sorted.  A vertex on
 * the plane counts as above it (a symbolic perturbation of the plane), so the count is even and
 * consecutive pairs bound the stretches of the line inside the face.  The crossing point of an
 * edge is computed from the edge's lower vertex id and the plane only, so every face sharing
 * the edge gets the same point. */
static int clip_face(ctx *c, uint32_t f, const group *g, const double *u, xing **xs, size_t *nx,
                     size_t *cap)
{
    const iface *F = &c->F[f];
    *nx = 0;
    for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
        for (uint32_t i = 0; i < cyc_len(c, cy); i++) {
            uint32_t a, b;
            cyc_edge(c, cy, i, &a, &b);
            double pa[3], pb[3];
            pt(c, a, pa);
            pt(c, b, pb);
            double sa = plane_dist(g, pa), sb = plane_dist(g, pb);
            if ((sa >= 0) == (sb >= 0)) continue;
            double t = sa / (sa - sb), x[3];
            for (int k = 0; k < 3; k++) x[k] = pa[k] + t * (pb[k] - pa[k]);
            uint32_t vx = vertex_round(c, x);
            if (vx == NONE) return -1;
            xing xi = {u[0] * x[0] + u[1] * x[1] + u[2] * x[2], vx,
                       umap_get(&c->edge_seg, key2(a, b))};
            if (PUSH(*xs, *nx, *cap, xi)) return -1;
        }
    }
    if (*nx > 1) qsort(*xs, *nx, sizeof **xs, xing_cmp);
    return 0;
}

typedef struct cutbuf {
    xing *xa, *xb;
    size_t na, nb, capa, capb;
} cutbuf;

static int add_endpoint_split(ctx *c, const xing *x)
{
    if (x->seg == NONE) return 0;
    return seg_add_split(&c->S[x->seg], x->v) < 0 ? -1 : 0;
}

/* The segments where faces a and b (of different groups) cut each other. */
static int cut_pair(ctx *c, uint32_t a, uint32_t b, cutbuf *cb)
{
    const group *ga = &c->G[c->F[a].group], *gb = &c->G[c->F[b].group];
    double u[3] = {ga->nd[1] * gb->nd[2] - ga->nd[2] * gb->nd[1],
                   ga->nd[2] * gb->nd[0] - ga->nd[0] * gb->nd[2],
                   ga->nd[0] * gb->nd[1] - ga->nd[1] * gb->nd[0]};
    if (sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) < PARALLEL_EPS) return 0;
    if (clip_face(c, a, gb, u, &cb->xa, &cb->na, &cb->capa)) return -1;
    if (cb->na < 2) return 0;
    if (clip_face(c, b, ga, u, &cb->xb, &cb->nb, &cb->capb)) return -1;
    size_t i = 0, j = 0;
    while (i + 1 < cb->na && j + 1 < cb->nb) {
        const xing *a0 = &cb->xa[i], *a1 = &cb->xa[i + 1], *b0 = &cb->xb[j], *b1 = &cb->xb[j + 1];
        const xing *s = a0->lam >= b0->lam ? a0 : b0;
        const xing *e = a1->lam <= b1->lam ? a1 : b1;
        if (s->lam < e->lam && s->v != e->v) {
            uint32_t lo = c->F[a].group < c->F[b].group ? c->F[a].group : c->F[b].group;
            uint32_t hi = c->F[a].group ^ c->F[b].group ^ lo;
            if (seg_new(c, s->v, e->v, lo, hi) == NONE) return -1;
            c->st->cuts++;
            if (add_endpoint_split(c, s) || add_endpoint_split(c, e)) return -1;
        }
        if (a1->lam <= b1->lam)
            i += 2;
        else
            j += 2;
    }
    return 0;
}

static int stage_cuts(ctx *c, const uint64_t *pairs, size_t np)
{
    cutbuf cb = {0};
    int rc = 0;
    for (size_t i = 0; i < np && !rc; i++) {
        uint32_t a = (uint32_t)(pairs[i] >> 32), b = (uint32_t)pairs[i];
        if (c->F[a].solid == c->F[b].solid) continue; /* a solid does not cut itself */
        if (share_edge(c, a, b)) continue;            /* they meet along that edge only */
        rc = cut_pair(c, a, b, &cb);
        if ((i & 4095) == 0) progress(c, "cuts", (double)i / (double)np);
    }
    free(cb.xa);
    free(cb.xb);
    return rc;
}

/* The groups using each segment (CSR both ways). */
static int stage_incidence(ctx *c)
{
    uint64_t *pr = NULL; /* (group << 32 | seg) */
    size_t n = 0, cap = 0;
    for (size_t f = 0; f < c->nf; f++) {
        const iface *F = &c->F[f];
        for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
            for (uint32_t i = 0; i < cyc_len(c, cy); i++) {
                uint32_t a, b;
                cyc_edge(c, cy, i, &a, &b);
                uint32_t s = umap_get(&c->edge_seg, key2(a, b));
                if (PUSH(pr, n, cap, key2(F->group, s))) goto oom;
            }
        }
    }
    for (size_t s = 0; s < c->ns; s++) {
        if (umap_get(&c->edge_seg, key2(c->S[s].a, c->S[s].b)) == s) continue; /* an E seg */
        if (PUSH(pr, n, cap, key2(c->S[s].p0, (uint32_t)s))) goto oom;
        if (PUSH(pr, n, cap, key2(c->S[s].p1, (uint32_t)s))) goto oom;
    }
    /* sort and dedup */
    if (n > 1) qsort(pr, n, sizeof *pr, cmpu64);
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (!m || pr[i] != pr[m - 1]) pr[m++] = pr[i];
    n = m;
    c->gs_off = calloc(c->ng + 1, sizeof *c->gs_off);
    c->gs = malloc((n + 1) * sizeof *c->gs);
    c->sg_off = calloc(c->ns + 1, sizeof *c->sg_off);
    c->sg = malloc((n + 1) * sizeof *c->sg);
    if (!c->gs_off || !c->gs || !c->sg_off || !c->sg) goto oom;
    for (size_t i = 0; i < n; i++) {
        c->gs_off[(pr[i] >> 32) + 1]++;
        c->sg_off[(uint32_t)pr[i] + 1]++;
    }
    for (size_t g = 0; g < c->ng; g++) c->gs_off[g + 1] += c->gs_off[g];
    for (size_t s = 0; s < c->ns; s++) c->sg_off[s + 1] += c->sg_off[s];
    uint32_t *fill = calloc(c->ns + 1, sizeof *fill);
    if (!fill) goto oom;
    for (size_t i = 0; i < n; i++) {
        c->gs[i] = (uint32_t)pr[i]; /* sorted by group: CSR order already */
        uint32_t s = (uint32_t)pr[i];
        c->sg[c->sg_off[s] + fill[s]++] = (uint32_t)(pr[i] >> 32);
    }
    free(fill);
    free(pr);
    return 0;
oom:
    free(pr);
    return -1;
}

/* ------------------------------------------------------------------ stage 4: group rounds */

typedef struct piece {
    uint32_t seg, u, v; /* segment, global endpoints */
} piece;

typedef struct sortkey {
    double t;
    uint32_t v;
} sortkey;

static int sortkey_cmp(const void *pa, const void *pb)
{
    const sortkey *a = pa, *b = pb;
    if (a->t != b->t) return a->t < b->t ? -1 : 1;
    return (a->v > b->v) - (a->v < b->v);
}

/* The intersection of three planes (groups, in increasing order), in grid units; 0 or -1 when
 * they do not meet in one well-defined point. */
static int three_planes(const ctx *c, uint32_t g0, uint32_t g1, uint32_t g2, double *x)
{
    uint32_t g[3] = {g0, g1, g2};
    for (int i = 0; i < 3; i++) /* sort */
        for (int j = i + 1; j < 3; j++)
            if (g[j] < g[i]) {
                uint32_t t = g[i];
                g[i] = g[j], g[j] = t;
            }
    const double *a = c->G[g[0]].nd, *b = c->G[g[1]].nd, *e = c->G[g[2]].nd;
    double da = c->G[g[0]].d, db = c->G[g[1]].d, de = c->G[g[2]].d;
    double bc[3] = {b[1] * e[2] - b[2] * e[1], b[2] * e[0] - b[0] * e[2],
                    b[0] * e[1] - b[1] * e[0]};
    double ca[3] = {e[1] * a[2] - e[2] * a[1], e[2] * a[0] - e[0] * a[2],
                    e[0] * a[1] - e[1] * a[0]};
    double ab[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0]};
    double det = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2];
    if (fabs(det) < 1e-6) return -1;
    for (int k = 0; k < 3; k++) x[k] = (da * bc[k] + db * ca[k] + de * ab[k]) / det;
    return 0;
}

typedef struct gwork { /* scratch of one worker */
    piece *pc;
    size_t npc, cappc;
    double *sg;
    size_t capsg;
    sortkey *sk;
    size_t capsk;
    umap at;       /* projected point -> global id */
    umap oedge;    /* output edges */
    uint32_t *hit; /* (piece, out vertex) pairs of the scan */
    size_t nhit, caphit;
} gwork;

/* Grid coordinates stay below 2^(ARR3_GRID_BITS - 1) + 2^4 in magnitude (the origin is the
 * box's centre), so both fit in 32 bits. */
_Static_assert(ARR3_GRID_BITS <= 31, "ipt_key packs two coordinates in 64 bits");
static uint64_t ipt_key(ipt p)
{
    return (uint64_t)(p.x + (1LL << 31)) << 32 | (uint64_t)(p.y + (1LL << 31));
}

static int greq_split(greq *r, uint32_t seg, uint32_t ref)
{
    return PUSH(r->split, r->nsplit, r->capsplit, key2(seg, ref));
}

/* The vertex of L at grid point p (V is sorted by x then y), or NONE. */
static uint32_t out_vertex(const lar2 *L, ipt p)
{
    size_t lo = 0, hi = L->nv;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        double x = L->V[2 * mid], y = L->V[2 * mid + 1];
        if (x < (double)p.x || (x == (double)p.x && y < (double)p.y))
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo < L->nv && L->V[2 * lo] == (double)p.x && L->V[2 * lo + 1] == (double)p.y)
        return (uint32_t)lo;
    return NONE;
}

/* Runs group gi's arrangement and records what it asks of the segments. */
/* Is group gi one face whose segments are its own edges, none split?  Then its arrangement is
 * the face itself (most faces of a large mesh), and arr2 is not run for it. */
static int group_trivial(const ctx *c, uint32_t gi)
{
    if (c->G[gi].nfaces != 1) return 0;
    for (uint32_t i = c->gs_off[gi]; i < c->gs_off[gi + 1]; i++) {
        const seg3 *S = &c->S[c->gs[i]];
        if (S->nsp || umap_get(&c->edge_seg, key2(S->a, S->b)) != c->gs[i]) return 0;
    }
    return 1;
}

static int group_run(ctx *c, uint32_t gi, gwork *w)
{
    group *g = &c->G[gi];
    greq *r = &c->req[gi];
    r->nnew = r->nsplit = r->nmerge = 0;
    /* the worker's maps are cleared for every group: keep them near this group's size */
    size_t want = 4 * (size_t)(c->gs_off[gi + 1] - c->gs_off[gi]) + 64;
    if (w->at.cap > 16 * want) umap_free(&w->at);
    if (w->oedge.cap > 16 * want) umap_free(&w->oedge);
    g->trivial = group_trivial(c, gi);
    if (g->trivial) {
        lar2_free(&g->res);
        free(g->rgid);
        free(g->rseg);
        g->rgid = g->rseg = NULL;
        return ARR_OK;
    }
    w->npc = 0;
    w->at.n = 0;
    if (w->at.cap) memset(w->at.key, 0xff, w->at.cap * sizeof *w->at.key);
    /* pieces of the polylines */
    for (uint32_t i = c->gs_off[gi]; i < c->gs_off[gi + 1]; i++) {
        uint32_t s = c->gs[i];
        const seg3 *S = &c->S[s];
        uint32_t a = vfind(c, S->a), b = vfind(c, S->b);
        double pa[3], pb[3], d[3];
        pt(c, a, pa);
        pt(c, b, pb);
        for (int k = 0; k < 3; k++) d[k] = pb[k] - pa[k];
        if (grow(&w->sk, &w->capsk, S->nsp + 2, sizeof *w->sk)) return ARR_ENOMEM;
        size_t m = 0;
        w->sk[m++] = (sortkey){0, a};
        for (uint32_t j = 0; j < S->nsp; j++) {
            uint32_t v = vfind(c, S->sp[j]);
            double p[3];
            pt(c, v, p);
            double t = (p[0] - pa[0]) * d[0] + (p[1] - pa[1]) * d[1] + (p[2] - pa[2]) * d[2];
            w->sk[m++] = (sortkey){t, v};
        }
        if (m - 1 > 1) qsort(w->sk + 1, m - 1, sizeof *w->sk, sortkey_cmp);
        w->sk[m++] = (sortkey){DBL_MAX, b};
        uint32_t prev = NONE;
        for (size_t j = 0; j < m; j++) {
            uint32_t v = w->sk[j].v;
            if (v == prev) continue;
            if (prev != NONE) {
                piece p = {s, prev, v};
                if (PUSH(w->pc, w->npc, w->cappc, p)) return ARR_ENOMEM;
            }
            prev = v;
        }
    }
    /* projected ends; two vertices with one projection are merged */
    for (size_t i = 0; i < w->npc; i++) {
        uint32_t e2[2] = {w->pc[i].u, w->pc[i].v};
        for (int j = 0; j < 2; j++) {
            ipt q = proj(c->P + 3 * (size_t)e2[j], g->k);
            int found;
            uint32_t had = umap_put(&w->at, ipt_key(q), e2[j], &found);
            if (had == NONE) return ARR_ENOMEM;
            if (found && had != e2[j]) {
                if (PUSH(r->merge, r->nmerge, r->capmerge, key2(had, e2[j]))) return ARR_ENOMEM;
            }
        }
    }
    if (r->nmerge) return ARR_OK; /* merged first, run again next round */
    if (grow(&w->sg, &w->capsg, 4 * w->npc + 4, sizeof *w->sg)) return ARR_ENOMEM;
    size_t nseg = 0;
    for (size_t i = 0; i < w->npc; i++) {
        ipt p = proj(c->P + 3 * (size_t)w->pc[i].u, g->k),
            q = proj(c->P + 3 * (size_t)w->pc[i].v, g->k);
        if (p.x == q.x && p.y == q.y) continue;
        w->sg[4 * nseg] = (double)p.x, w->sg[4 * nseg + 1] = (double)p.y;
        w->sg[4 * nseg + 2] = (double)q.x, w->sg[4 * nseg + 3] = (double)q.y;
        nseg++;
    }
    lar2_free(&g->res);
    free(g->rgid);
    g->rgid = NULL;
    free(g->rseg);
    g->rseg = NULL;
    arr2_opts ao = {0};
    ao.precision = 1;
    ao.threads = 1;
    ao.cancel = c->o->cancel;
    int rc = arr2_build(w->sg, nseg, &ao, &g->res, r->err, sizeof r->err);
    if (rc) return rc;
    const lar2 *L = &g->res;
    g->rgid = malloc((L->nv + 1) * sizeof *g->rgid);
    if (!g->rgid) return ARR_ENOMEM;
    for (size_t i = 0; i < L->nv; i++) {
        ipt q = {llround(L->V[2 * i]), llround(L->V[2 * i + 1])};
        g->rgid[i] = umap_get(&w->at, ipt_key(q));
    }
    /* output edges, to find the pieces that came out whole */
    w->oedge.n = 0;
    if (w->oedge.cap) memset(w->oedge.key, 0xff, w->oedge.cap * sizeof *w->oedge.key);
    g->rseg = malloc((L->ne + 1) * sizeof *g->rseg);
    if (!g->rseg) return ARR_ENOMEM;
    for (size_t e = 0; e < L->ne; e++) {
        g->rseg[e] = NONE;
        if (umap_put(&w->oedge, key2(L->EV[2 * e], L->EV[2 * e + 1]), (uint32_t)e, NULL) == NONE)
            return ARR_ENOMEM;
    }
    /* the out vertex at a projected point: V is sorted by x then y */
    w->nhit = 0;
    for (size_t i = 0; i < w->npc; i++) {
        ipt p = proj(c->P + 3 * (size_t)w->pc[i].u, g->k),
            q = proj(c->P + 3 * (size_t)w->pc[i].v, g->k);
        if (p.x == q.x && p.y == q.y) continue;
        int64_t x0 = p.x < q.x ? p.x : q.x, x1 = p.x ^ q.x ^ x0;
        int64_t y0 = p.y < q.y ? p.y : q.y, y1 = p.y ^ q.y ^ y0;
        /* first vertex with x >= x0 */
        size_t lo = 0, hi = L->nv;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (L->V[2 * mid] < (double)x0)
                lo = mid + 1;
            else
                hi = mid;
        }
        size_t start = lo;
        uint32_t iu = out_vertex(L, p), iv = out_vertex(L, q);
        if (iu != NONE && iv != NONE) {
            uint32_t e = umap_get(&w->oedge, iu < iv ? key2(iu, iv) : key2(iv, iu));
            if (e != NONE) { /* whole */
                if (g->rseg[e] == NONE) g->rseg[e] = w->pc[i].seg;
                continue;
            }
        }
        for (size_t j = start; j < L->nv && L->V[2 * j] <= (double)x1; j++) {
            ipt o = {llround(L->V[2 * j]), llround(L->V[2 * j + 1])};
            if (o.y < y0 || o.y > y1) continue;
            if ((o.x == p.x && o.y == p.y) || (o.x == q.x && o.y == q.y)) continue;
            if (!seg_hits_pixel(p, q, o)) continue;
            if (grow(&w->hit, &w->caphit, 2 * w->nhit + 2, sizeof *w->hit)) return ARR_ENOMEM;
            w->hit[2 * w->nhit] = (uint32_t)i;
            w->hit[2 * w->nhit + 1] = (uint32_t)j;
            w->nhit++;
        }
    }
    /* new vertices: a point on the planes of the segments through it */
    for (size_t h = 0; h < w->nhit; h++) {
        uint32_t j = w->hit[2 * h + 1];
        if (g->rgid[j] != NONE) continue;
        uint32_t pl[2] = {NONE, NONE};
        for (size_t h2 = 0; h2 < w->nhit; h2++) {
            if (w->hit[2 * h2 + 1] != j) continue;
            const seg3 *S = &c->S[w->pc[w->hit[2 * h2]].seg];
            uint32_t cand[2] = {S->p0, S->p1};
            for (int k = 0; k < 2; k++) {
                if (cand[k] == gi || cand[k] == pl[0] || cand[k] == pl[1]) continue;
                if (pl[0] == NONE)
                    pl[0] = cand[k];
                else if (pl[1] == NONE)
                    pl[1] = cand[k];
            }
        }
        double x[3];
        int ok = pl[1] != NONE && !three_planes(c, gi, pl[0], pl[1], x);
        if (ok) {
            /* The point of the three planes is the same whichever group asks, so it is used
             * however far (crossings of rounded cut segments at a shallow angle move along
             * them), unless the planes are so near dependent that it lands far off. */
            ipt q = {llround(L->V[2 * j]), llround(L->V[2 * j + 1])};
            int64_t gx[3] = {llround(x[0]), llround(x[1]), llround(x[2])};
            ipt pq = proj(gx, g->k);
            if (llabs(pq.x - q.x) > FAR_PX || llabs(pq.y - q.y) > FAR_PX) ok = 0;
        }
        if (!ok) { /* lift into the group's plane */
            int k = g->k, i1 = (k + 1) % 3, i2 = (k + 2) % 3;
            x[i1] = L->V[2 * j];
            x[i2] = L->V[2 * j + 1];
            x[k] = (g->d - g->nd[i1] * x[i1] - g->nd[i2] * x[i2]) / g->nd[k];
        }
        if (grow(&r->newp, &r->capnew, 3 * (r->nnew + 1), sizeof *r->newp)) return ARR_ENOMEM;
        for (int k = 0; k < 3; k++) r->newp[3 * r->nnew + k] = llround(x[k]);
        g->rgid[j] = 0x80000000u | (uint32_t)r->nnew; /* resolved after the round */
        r->nnew++;
    }
    for (size_t h = 0; h < w->nhit; h++) {
        uint32_t i = w->hit[2 * h], j = w->hit[2 * h + 1];
        if (greq_split(r, w->pc[i].seg, g->rgid[j])) return ARR_ENOMEM;
    }
    return ARR_OK;
}

typedef struct roundctx {
    ctx *c;
    uint32_t *todo;
    gwork *w; /* per worker */
} roundctx;

static void round_item(void *vr, size_t item, int worker)
{
    roundctx *rc = vr;
    uint32_t gi = rc->todo[item];
    greq *r = &rc->c->req[gi];
    if (cancelled(rc->c)) {
        r->rc = ARR_ECANCELED;
        return;
    }
    r->rc = group_run(rc->c, gi, &rc->w[worker]);
}

static void gwork_free(gwork *w)
{
    free(w->pc);
    free(w->sg);
    free(w->sk);
    umap_free(&w->at);
    umap_free(&w->oedge);
    free(w->hit);
}

/* An edge on the planes of three groups or more is where rounding split a point at which
 * several planes (nearly) meet; when it is shorter than TINY_EDGE its ends are one point at
 * this precision, and two rounded copies of one point give a fan of faces about a direction
 * that is only noise.  Merges the ends of such edges; returns how many, or -1. */
static int merge_tiny_edges(ctx *c)
{
    umap first = {0}; /* edge -> first group */
    uint64_t *cand = NULL;
    size_t nc = 0, cap = 0;
    int merged = 0;
    for (size_t gi = 0; gi < c->ng; gi++) {
        const group *g = &c->G[gi];
        for (size_t e = 0; g->rgid && e < g->res.ne; e++) {
            uint32_t a = vfind(c, g->rgid[g->res.EV[2 * e]]);
            uint32_t b = vfind(c, g->rgid[g->res.EV[2 * e + 1]]);
            const int64_t *p = c->P + 3 * (size_t)a, *q = c->P + 3 * (size_t)b;
            if (llabs(p[0] - q[0]) > TINY_EDGE || llabs(p[1] - q[1]) > TINY_EDGE ||
                llabs(p[2] - q[2]) > TINY_EDGE)
                continue;
            uint64_t k = a < b ? key2(a, b) : key2(b, a);
            int found;
            uint32_t g0 = umap_put(&first, k, (uint32_t)gi, &found);
            if (g0 == NONE) goto oom;
            if (found && g0 != gi && PUSH(cand, nc, cap, k)) goto oom;
        }
    }
    /* a candidate seen from two groups; a third makes it degenerate */
    if (nc > 1) qsort(cand, nc, sizeof *cand, cmpu64);
    for (size_t i = 0; i < nc;) {
        size_t j = i;
        while (j < nc && cand[j] == cand[i]) j++;
        if (j - i >= 2) { /* three groups or more (first + two more) */
            uint32_t a = vfind(c, (uint32_t)(cand[i] >> 32)), b = vfind(c, (uint32_t)cand[i]);
            if (a != b) {
                if (a < b)
                    c->alias[b] = a;
                else
                    c->alias[a] = b;
                merged++;
            }
        }
        i = j;
    }
    free(cand);
    umap_free(&first);
    return merged;
oom:
    free(cand);
    umap_free(&first);
    return -1;
}

static int stage_rounds(ctx *c, char *err, size_t el)
{
    uint32_t *todo = malloc((c->ng + 1) * sizeof *todo);
    gwork *w = calloc((size_t)c->threads, sizeof *w);
    int rc = ARR_OK;
    if (!todo || !w) {
        rc = seterr(err, el, ARR_ENOMEM, "out of memory");
        goto done;
    }
    for (int round = 0;; round++) {
        size_t nt = 0;
        for (size_t g = 0; g < c->ng; g++)
            if (c->G[g].dirty) todo[nt++] = (uint32_t)g;
        if (!nt) {
            int m = merge_tiny_edges(c);
            if (m < 0) {
                rc = seterr(err, el, ARR_ENOMEM, "out of memory");
                goto done;
            }
            if (!m) break;
            for (size_t g = 0; g < c->ng; g++) c->G[g].dirty = 1;
            continue;
        }
        if (round >= ARR3_MAX_ROUNDS) {
            rc = seterr(err, el, ARR_EINTERNAL,
                        "solids: the faces' arrangements did not settle in %d rounds (%zu plane "
                        "groups still changing); a coarser precision may help",
                        ARR3_MAX_ROUNDS, nt);
            goto done;
        }
        c->st->rounds = (size_t)round + 1;
        roundctx r = {c, todo, w};
        par_for(c->threads, nt, round_item, &r);
        for (size_t i = 0; i < nt; i++) c->G[todo[i]].dirty = 0;
        int merged = 0;
        for (size_t i = 0; i < nt; i++) { /* in group order: ids do not depend on threads */
            uint32_t gi = todo[i];
            greq *q = &c->req[gi];
            if (q->rc) {
                if (q->rc == ARR_ECANCELED)
                    rc = seterr(err, el, ARR_ECANCELED, "cancelled");
                else
                    rc = seterr(err, el, q->rc, "solids: plane %u: %s", gi, q->err);
                goto done;
            }
            uint32_t *ids = NULL;
            if (q->nnew) {
                ids = malloc(q->nnew * sizeof *ids);
                if (!ids) {
                    rc = seterr(err, el, ARR_ENOMEM, "out of memory");
                    goto done;
                }
                for (size_t k = 0; k < q->nnew; k++)
                    if ((ids[k] = vertex_at(c, q->newp + 3 * k)) == NONE) {
                        free(ids);
                        rc = seterr(err, el, ARR_ENOMEM, "out of memory");
                        goto done;
                    }
            }
            group *g = &c->G[gi];
            for (size_t k = 0; g->rgid && k < g->res.nv; k++)
                if (g->rgid[k] != NONE && (g->rgid[k] & 0x80000000u))
                    g->rgid[k] = ids[g->rgid[k] & 0x7fffffffu];
            for (size_t k = 0; k < q->nsplit; k++) {
                uint32_t s = (uint32_t)(q->split[k] >> 32), ref = (uint32_t)q->split[k];
                uint32_t v = vfind(c, (ref & 0x80000000u) ? ids[ref & 0x7fffffffu] : ref);
                seg3 *S = &c->S[s];
                if (v == vfind(c, S->a) || v == vfind(c, S->b)) continue;
                int added = seg_add_split(S, v);
                if (added < 0) {
                    free(ids);
                    rc = seterr(err, el, ARR_ENOMEM, "out of memory");
                    goto done;
                }
                if (added)
                    for (uint32_t t = c->sg_off[s]; t < c->sg_off[s + 1]; t++)
                        c->G[c->sg[t]].dirty = 1;
            }
            free(ids);
            for (size_t k = 0; k < q->nmerge; k++) {
                uint32_t a = vfind(c, (uint32_t)(q->merge[k] >> 32));
                uint32_t b = vfind(c, (uint32_t)q->merge[k]);
                if (a == b) continue;
                if (a < b)
                    c->alias[b] = a;
                else
                    c->alias[a] = b;
                merged = 1;
            }
        }
        if (merged)
            for (size_t g = 0; g < c->ng; g++) c->G[g].dirty = 1;
        progress(c, "faces", 1.0 - 1.0 / (round + 2));
    }
done:
    for (int i = 0; w && i < c->threads; i++) gwork_free(&w[i]);
    free(w);
    free(todo);
    return rc;
}

/* ------------------------------------------------------------------ stage 5: faces */

/* A point strictly inside face f of arrangement L (holes excluded): the middle of the widest
 * stretch of the horizontal line through the middle of the largest gap between the face's
 * vertex heights. */
static void face_inner_point(const lar2 *L, uint32_t f, double *out)
{
    uint32_t cycs[1 + 64];
    size_t nc = 0;
    cycs[nc++] = L->face_cycle[f];
    for (uint32_t h = L->hole_off[f]; h < L->hole_off[f + 1] && nc < 65; h++)
        cycs[nc++] = L->hole_cyc[h];
    /* heights of the outer cycle */
    double best_gap = -1, yl = 0;
    {
        uint32_t c0 = L->cyc_off[cycs[0]], c1 = L->cyc_off[cycs[0] + 1];
        size_t n = c1 - c0;
        double *ys = malloc(n * sizeof *ys);
        if (ys) {
            for (size_t i = 0; i < n; i++) ys[i] = L->V[2 * L->cyc[c0 + i] + 1];
            if (n > 1) qsort(ys, n, sizeof *ys, cmpd);
            for (size_t i = 0; i + 1 < n; i++)
                if (ys[i + 1] - ys[i] > best_gap) best_gap = ys[i + 1] - ys[i], yl = ys[i];
            free(ys);
        }
    }
    double y = yl + best_gap / 2;
    double xs[512];
    size_t nx = 0;
    for (size_t k = 0; k < nc; k++) {
        uint32_t c0 = L->cyc_off[cycs[k]], c1 = L->cyc_off[cycs[k] + 1];
        for (uint32_t i = c0; i < c1; i++) {
            const double *p = L->V + 2 * L->cyc[i], *q = L->V + 2 * L->cyc[i + 1 < c1 ? i + 1 : c0];
            if ((p[1] > y) == (q[1] > y)) continue;
            if (nx < 512) xs[nx++] = p[0] + (y - p[1]) * (q[0] - p[0]) / (q[1] - p[1]);
        }
    }
    if (nx > 1) qsort(xs, nx, sizeof *xs, cmpd);
    double bw = -1, bx = 0;
    for (size_t i = 0; i + 1 < nx; i += 2)
        if (xs[i + 1] - xs[i] > bw) bw = xs[i + 1] - xs[i], bx = (xs[i] + xs[i + 1]) / 2;
    out[0] = bx;
    out[1] = y;
}

/* Is 2D point x inside input face f (projected dropping axis k), even-odd over its cycles? */
static int inside_input_face(const ctx *c, uint32_t f, int k, const double *x)
{
    const iface *F = &c->F[f];
    int in = 0;
    for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
        const uint32_t *v = cyc_v(c, cy);
        uint32_t len = cyc_len(c, cy);
        for (uint32_t i = 0; i < len; i++) {
            ipt p = proj(c->P + 3 * (size_t)vfind(c, v[i]), k);
            ipt q = proj(c->P + 3 * (size_t)vfind(c, v[(i + 1) % len]), k);
            if (((double)p.y > x[1]) == ((double)q.y > x[1])) continue;
            double xc = p.x + (x[1] - p.y) * (double)(q.x - p.x) / (double)(q.y - p.y);
            if (xc > x[0]) in ^= 1;
        }
    }
    return in;
}

typedef struct outface {
    uint32_t group, src;
    uint32_t c0, nc; /* cycles in ocyc_off */
    uint32_t s0, ns; /* the solids whose surface holds it: fsol[s0 .. s0 + ns) */
} outface;

typedef struct asm3 {
    umap eplane;    /* (lo, hi) global edge -> a segment it is a piece of: its two planes */
    uint32_t *fsol; /* solids of the faces (outface.s0, ns) */
    size_t nfsol, capfsol;
    outface *of;
    size_t nof, capof;
    uint32_t *ocyc_off, *ocyc;
    size_t nocyc, nocv, capoff, capocv;
} asm3;

/* Adds solid s to the list that starts at fsol[s0] (the face's, the last list), or removes it
 * when there: a face on two faces of one solid is inside that solid on both sides. */
static int fsol_toggle(asm3 *A, size_t s0, uint32_t s)
{
    for (size_t i = s0; i < A->nfsol; i++)
        if (A->fsol[i] == s) {
            A->fsol[i] = A->fsol[--A->nfsol];
            return 0;
        }
    return PUSH(A->fsol, A->nfsol, A->capfsol, s);
}

static int asm_cycle(const ctx *c, asm3 *A, const group *g, const lar2 *L, uint32_t cy, int rev)
{
    uint32_t c0 = L->cyc_off[cy], c1 = L->cyc_off[cy + 1], n = c1 - c0;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t j = rev ? c0 + (n - i) % n : c0 + i;
        uint32_t v = vfind(c, g->rgid[L->cyc[j]]);
        if (PUSH(A->ocyc, A->nocv, A->capocv, v)) return -1;
    }
    if (grow(&A->ocyc_off, &A->capoff, A->nocyc + 2, sizeof *A->ocyc_off)) return -1;
    A->ocyc_off[A->nocyc + 1] = (uint32_t)A->nocv;
    A->nocyc++;
    return 0;
}

typedef struct dedupctx {
    const asm3 *A;
    const uint32_t *off, *sv; /* each face's sorted vertices */
} dedupctx;

static int face_vs_cmp(const void *pa, const void *pb, void *vx)
{
    const dedupctx *x = vx;
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    uint32_t la = x->off[a + 1] - x->off[a], lb = x->off[b + 1] - x->off[b];
    if (la != lb) return la < lb ? -1 : 1;
    int r = memcmp(x->sv + x->off[a], x->sv + x->off[b], la * sizeof *x->sv);
    if (r) {
        for (uint32_t i = 0; i < la; i++)
            if (x->sv[x->off[a] + i] != x->sv[x->off[b] + i])
                return x->sv[x->off[a] + i] < x->sv[x->off[b] + i] ? -1 : 1;
    }
    return (a > b) - (a < b);
}

/* Faces of different planes with the same vertices (rounding can give two nearly coincident
 * planes one small polygon) are one face: the first is kept. */
static int faces_dedup(asm3 *A)
{
    size_t nf = A->nof;
    uint32_t *off = malloc((nf + 1) * sizeof *off), *sv = malloc((A->nocv + 1) * sizeof *sv);
    uint32_t *ord = malloc((nf + 1) * sizeof *ord);
    uint8_t *drop = calloc(nf + 1, 1);
    uint32_t *drop_to = malloc((nf + 1) * sizeof *drop_to);
    uint32_t *noff = NULL, *ncyc = NULL;
    int rc = -1;
    if (!off || !sv || !ord || !drop || !drop_to) goto done;
    off[0] = 0;
    for (size_t f = 0; f < nf; f++) {
        const outface *F = &A->of[f];
        uint32_t a = A->ocyc_off[F->c0], b = A->ocyc_off[F->c0 + F->nc];
        memcpy(sv + off[f], A->ocyc + a, (b - a) * sizeof *sv);
        if (b - a > 1) qsort(sv + off[f], b - a, sizeof *sv, cmpu32);
        off[f + 1] = off[f] + (b - a);
        ord[f] = (uint32_t)f;
    }
    dedupctx x = {A, off, sv};
    qsort_r(ord, nf, sizeof *ord, face_vs_cmp, &x);
    size_t ndrop = 0;
    for (size_t i = 1; i < nf; i++) {
        uint32_t a = ord[i - 1], b = ord[i];
        if (off[a + 1] - off[a] == off[b + 1] - off[b] &&
            !memcmp(sv + off[a], sv + off[b], (off[a + 1] - off[a]) * sizeof *sv)) {
            uint32_t keep = a;
            while (drop[keep]) keep = drop_to[keep]; /* the first of a run of equals */
            drop[b] = 1; /* ord is by index among equals: a < b, a kept */
            drop_to[b] = keep;
            ndrop++;
            /* the kept face lies on the solids of both: a new list, their symmetric difference */
            outface *K = &A->of[keep];
            const outface *D = &A->of[b];
            size_t s0 = A->nfsol;
            for (uint32_t j = 0; j < K->ns; j++)
                if (fsol_toggle(A, s0, A->fsol[K->s0 + j])) goto done;
            for (uint32_t j = 0; j < D->ns; j++)
                if (fsol_toggle(A, s0, A->fsol[D->s0 + j])) goto done;
            K->s0 = (uint32_t)s0;
            K->ns = (uint32_t)(A->nfsol - s0);
        }
    }
    if (ndrop) { /* compact faces and their cycles */
        noff = malloc((A->nocyc + 1) * sizeof *noff);
        ncyc = malloc((A->nocv + 1) * sizeof *ncyc);
        if (!noff || !ncyc) goto done;
        size_t nof = 0, nc = 0, nv = 0;
        noff[0] = 0;
        for (size_t f = 0; f < nf; f++) {
            if (drop[f]) continue;
            outface F = A->of[f];
            uint32_t c0 = (uint32_t)nc;
            for (uint32_t cy = F.c0; cy < F.c0 + F.nc; cy++) {
                for (uint32_t i = A->ocyc_off[cy]; i < A->ocyc_off[cy + 1]; i++)
                    ncyc[nv++] = A->ocyc[i];
                noff[++nc] = (uint32_t)nv;
            }
            F.c0 = c0;
            A->of[nof++] = F;
        }
        free(A->ocyc_off);
        free(A->ocyc);
        A->ocyc_off = noff, A->ocyc = ncyc;
        noff = ncyc = NULL;
        A->nof = nof, A->nocyc = nc, A->nocv = nv;
        A->capoff = nc + 1, A->capocv = nv + 1;
    }
    rc = 0;
done:
    free(off);
    free(sv);
    free(ord);
    free(drop);
    free(drop_to);
    free(noff);
    free(ncyc);
    return rc;
}

static int stage_faces(ctx *c, asm3 *A)
{
    uint32_t *gf_off = calloc(c->ng + 1, sizeof *gf_off), *gf = malloc((c->nf + 1) * sizeof *gf);
    if (!gf_off || !gf) goto oom;
    for (size_t f = 0; f < c->nf; f++) gf_off[c->F[f].group + 1]++;
    for (size_t g = 0; g < c->ng; g++) gf_off[g + 1] += gf_off[g];
    {
        uint32_t *fill = calloc(c->ng + 1, sizeof *fill);
        if (!fill) goto oom;
        for (size_t f = 0; f < c->nf; f++) {
            uint32_t g = c->F[f].group;
            gf[gf_off[g] + fill[g]++] = (uint32_t)f;
        }
        free(fill);
    }
    if (grow(&A->ocyc_off, &A->capoff, 1, sizeof *A->ocyc_off)) goto oom;
    A->ocyc_off[0] = 0;
    for (size_t gi = 0; gi < c->ng; gi++) {
        const group *g = &c->G[gi];
        const lar2 *L = &g->res;
        int single = gf_off[gi + 1] - gf_off[gi] == 1 && c->F[gf[gf_off[gi]]].nc == 1;
        int rev = g->n[g->k] < 0;
        if (g->trivial) { /* the input face as it is: its outer cycle is CCW about n (Newell) */
            uint32_t src = gf[gf_off[gi]];
            const iface *F = &c->F[src];
            size_t s0 = A->nfsol;
            if (fsol_toggle(A, s0, F->solid)) goto oom;
            outface o = {(uint32_t)gi, src, (uint32_t)A->nocyc, F->nc, (uint32_t)s0, 1};
            for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
                const uint32_t *v = cyc_v(c, cy);
                for (uint32_t i = 0; i < cyc_len(c, cy); i++)
                    if (PUSH(A->ocyc, A->nocv, A->capocv, vfind(c, v[i]))) goto oom;
                if (grow(&A->ocyc_off, &A->capoff, A->nocyc + 2, sizeof *A->ocyc_off)) goto oom;
                A->ocyc_off[++A->nocyc] = (uint32_t)A->nocv;
            }
            if (PUSH(A->of, A->nof, A->capof, o)) goto oom;
            for (uint32_t i = c->gs_off[gi]; i < c->gs_off[gi + 1]; i++) {
                const seg3 *S = &c->S[c->gs[i]];
                uint32_t a = vfind(c, S->a), b = vfind(c, S->b);
                if (umap_put(&A->eplane, a < b ? key2(a, b) : key2(b, a), c->gs[i], NULL) == NONE)
                    goto oom;
            }
            continue;
        }
        for (uint32_t f = 0; f < L->nf; f++) {
            uint32_t src = gf[gf_off[gi]];
            size_t s0 = A->nfsol;
            if (!single) {
                double x[2];
                face_inner_point(L, f, x);
                src = NONE;
                for (uint32_t i = gf_off[gi]; i < gf_off[gi + 1]; i++) {
                    if (!inside_input_face(c, gf[i], g->k, x)) continue;
                    if (src == NONE) src = gf[i];
                    if (fsol_toggle(A, s0, c->F[gf[i]].solid)) goto oom;
                }
                if (src == NONE) continue;
            } else if (fsol_toggle(A, s0, c->F[src].solid)) {
                goto oom;
            }
            outface o = {
                (uint32_t)gi, src, (uint32_t)A->nocyc, 0, (uint32_t)s0, (uint32_t)(A->nfsol - s0)};
            if (asm_cycle(c, A, g, L, L->face_cycle[f], rev)) goto oom;
            o.nc++;
            for (uint32_t h = L->hole_off[f]; h < L->hole_off[f + 1]; h++) {
                if (asm_cycle(c, A, g, L, L->hole_cyc[h], rev)) goto oom;
                o.nc++;
            }
            if (PUSH(A->of, A->nof, A->capof, o)) goto oom;
        }
    }
    for (size_t gi = 0; gi < c->ng; gi++) {
        const group *g = &c->G[gi];
        for (size_t e = 0; g->rseg && e < g->res.ne; e++) {
            if (g->rseg[e] == NONE) continue;
            uint32_t a = vfind(c, g->rgid[g->res.EV[2 * e]]);
            uint32_t b = vfind(c, g->rgid[g->res.EV[2 * e + 1]]);
            if (umap_put(&A->eplane, a < b ? key2(a, b) : key2(b, a), g->rseg[e], NULL) == NONE)
                goto oom;
        }
    }
    free(gf_off);
    free(gf);
    return faces_dedup(A);
oom:
    free(gf_off);
    free(gf);
    return -1;
}

/* ------------------------------------------------------------------ stage 6: cells */

typedef struct inc { /* a face at an edge */
    uint32_t e, f;
    int s; /* +1: the face walks the edge from EV[0] to EV[1] */
} inc;

static int inc_cmp(const void *pa, const void *pb)
{
    const inc *a = pa, *b = pb;
    if (a->e != b->e) return a->e < b->e ? -1 : 1;
    return (a->f > b->f) - (a->f < b->f);
}

typedef struct fanctx {
    const ctx *c;
    const outface *of;
    int planes;          /* 1: the edge's direction is sigma (nP x nQ), exactly; 0: e */
    const i128 *nP, *nQ; /* the planes of the segment the edge is a piece of */
    int sigma;
    int64_t e[3];     /* the rounded direction */
    const i128 *nref; /* the reference face's normal and sign */
    int sref;
} fanctx;

static const i128 *face_n(const fanctx *x, uint32_t f)
{
    return x->c->G[x->of[f].group].ni;
}

static i128 dot_i128(const i128 *a, const i128 *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Sign of det(na, nb, E), E the edge's direction: with E = sigma (nP x nQ) this is
 * sigma ((na.nP)(nb.nQ) - (na.nQ)(nb.nP)), exact (normals < 2^41, dots < 2^83). */
static int fan_det(const fanctx *x, const i128 *na, const i128 *nb)
{
    if (x->planes) {
        i128 u[3] = {dot_i128(na, x->nP), -dot_i128(na, x->nQ), 0};
        i128 v[3] = {dot_i128(nb, x->nQ), dot_i128(nb, x->nP), 0};
        return x->sigma * sign_dot3(u, v);
    }
    i128 nbe[3];
    cross_i128(nb, x->e, nbe);
    return sign_dot3(na, nbe);
}

/* w_f = s_f (n_f x E) points from the edge into face f; e . (w_a x w_b) has the sign of
 * s_a s_b det(n_a, n_b, E). */
static int fan_half(const fanctx *x, const inc *a)
{
    const i128 *na = face_n(x, a->f);
    int cr = x->sref * a->s * fan_det(x, x->nref, na);
    if (cr > 0) return 0;
    if (cr < 0) return 1;
    /* parallel to the reference: the same way or the opposite */
    int same = na[0] == x->nref[0] && na[1] == x->nref[1] && na[2] == x->nref[2];
    int opp = na[0] == -x->nref[0] && na[1] == -x->nref[1] && na[2] == -x->nref[2];
    if (same) return a->s == x->sref ? 0 : 1;
    if (opp) return a->s != x->sref ? 0 : 1;
    return 0;
}

/* Angular order about the edge, exact for the planes' normals; faces in one direction are
 * ordered as if each face were moved by (f+1) epsilon along its normal, which turns it by
 * s_f (f+1) epsilon: the same perturbation at every edge, so the cells stay consistent. */
static int fan_cmp(const void *pa, const void *pb, void *vx)
{
    const fanctx *x = vx;
    const inc *a = pa, *b = pb;
    int ha = fan_half(x, a), hb = fan_half(x, b);
    if (ha != hb) return ha - hb;
    int cr = a->s * b->s * fan_det(x, face_n(x, a->f), face_n(x, b->f));
    if (cr) return -cr;
    int64_t ka = a->s * ((int64_t)a->f + 1), kb = b->s * ((int64_t)b->f + 1);
    return (ka > kb) - (ka < kb);
}

static double face_cone6(const ctx *c, const asm3 *A, uint32_t f, const double *o)
{
    double s = 0;
    const outface *F = &A->of[f];
    for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
        uint32_t c0 = A->ocyc_off[cy], c1 = A->ocyc_off[cy + 1];
        double p0[3];
        pt(c, A->ocyc[c0], p0);
        for (int k = 0; k < 3; k++) p0[k] -= o[k];
        for (uint32_t i = c0 + 1; i + 1 < c1; i++) {
            double p1[3], p2[3];
            pt(c, A->ocyc[i], p1);
            pt(c, A->ocyc[i + 1], p2);
            for (int k = 0; k < 3; k++) p1[k] -= o[k], p2[k] -= o[k];
            s += p0[0] * (p1[1] * p2[2] - p1[2] * p2[1]) - p0[1] * (p1[0] * p2[2] - p1[2] * p2[0]) +
                 p0[2] * (p1[0] * p2[1] - p1[1] * p2[0]);
        }
    }
    return s;
}

/* The first face hit by the ray from p in direction d among faces whose component is not
 * `skip`; returns the face-side node facing p, NONE when nothing is hit, or NONE - 1 when the
 * ray passes too near an edge (try another direction). */
static uint32_t ray_hit(const ctx *c, const asm3 *A, const uint32_t *fcomp, uint32_t skip,
                        const double *p, const double *d)
{
    double best = DBL_MAX;
    uint32_t bestf = NONE;
    int bests = 0, tie = 0;
    double degen = DBL_MAX;
    for (size_t f = 0; f < A->nof; f++) {
        if (fcomp[f] == skip) continue;
        const group *g = &c->G[A->of[f].group];
        double nd = g->nd[0] * d[0] + g->nd[1] * d[1] + g->nd[2] * d[2];
        if (fabs(nd) < 1e-12) continue;
        double t = -plane_dist(g, p) / nd;
        if (t <= 1e-9 || t > best + 1e-9) continue;
        double x[3] = {p[0] + t * d[0], p[1] + t * d[1], p[2] + t * d[2]};
        int k = g->k, i1 = (k + 1) % 3, i2 = (k + 2) % 3;
        double X = x[i1], Y = x[i2], mind = DBL_MAX;
        int in = 0;
        const outface *F = &A->of[f];
        for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
            uint32_t c0 = A->ocyc_off[cy], c1 = A->ocyc_off[cy + 1];
            for (uint32_t i = c0; i < c1; i++) {
                const int64_t *P = c->P + 3 * (size_t)A->ocyc[i];
                const int64_t *Q = c->P + 3 * (size_t)A->ocyc[i + 1 < c1 ? i + 1 : c0];
                double px = (double)P[i1], py = (double)P[i2], qx = (double)Q[i1],
                       qy = (double)Q[i2];
                double ex = qx - px, ey = qy - py, l2 = ex * ex + ey * ey;
                double tt = l2 > 0 ? ((X - px) * ex + (Y - py) * ey) / l2 : 0;
                if (tt < 0) tt = 0;
                if (tt > 1) tt = 1;
                double dx = px + tt * ex - X, dy = py + tt * ey - Y, dd = sqrt(dx * dx + dy * dy);
                if (dd < mind) mind = dd;
                if ((py > Y) != (qy > Y) && px + (Y - py) * ex / ey > X) in ^= 1;
            }
        }
        if (mind < RAY_EPS) { /* through an edge or a vertex: no clear answer here */
            if (t < degen) degen = t;
            continue;
        }
        if (!in) continue;
        if (fabs(t - best) <= 1e-9) tie = 1;
        if (t < best) {
            if (best - t > 1e-9) tie = 0;
            best = t;
            bestf = (uint32_t)f;
            bests = nd < 0 ? 0 : 1; /* ray enters through the + side: p is on it */
        }
    }
    if (tie || degen <= best + 1e-9) return NONE - 1;
    if (bestf == NONE) return NONE;
    return 2 * bestf + (uint32_t)bests;
}

static int stage_cells(ctx *c, asm3 *A, lar3 *out)
{
    int rc = -1;
    size_t nf = A->nof;
    umap em = {0};
    inc *I = NULL;
    size_t ni = 0, capi = 0;
    uint32_t *evv = NULL; /* edges: 2 per edge, global ids */
    size_t ne = 0, cape = 0;
    uint32_t *sp = NULL, *shell_id = NULL, *fcomp = NULL, *cell = NULL;
    double *cone = NULL, *svol = NULL;
    /* edges and incidences */
    for (size_t f = 0; f < nf; f++) {
        const outface *F = &A->of[f];
        for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
            uint32_t c0 = A->ocyc_off[cy], c1 = A->ocyc_off[cy + 1];
            for (uint32_t i = c0; i < c1; i++) {
                uint32_t a = A->ocyc[i], b = A->ocyc[i + 1 < c1 ? i + 1 : c0];
                uint32_t lo = a < b ? a : b, hi = a ^ b ^ lo;
                int found;
                uint32_t e = umap_put(&em, key2(lo, hi), (uint32_t)ne, &found);
                if (e == NONE) goto done;
                if (!found) {
                    if (grow(&evv, &cape, 2 * ne + 2, sizeof *evv)) goto done;
                    evv[2 * ne] = lo, evv[2 * ne + 1] = hi;
                    ne++;
                }
                inc x = {e, (uint32_t)f, a == lo ? 1 : -1};
                if (PUSH(I, ni, capi, x)) goto done;
            }
        }
    }
    if (ni > 1) qsort(I, ni, sizeof *I, inc_cmp);
    /* face sides around edges: node 2f (+ side), 2f+1 (- side) */
    sp = malloc((2 * nf + 1) * sizeof *sp);
    fcomp = malloc((nf + 1) * sizeof *fcomp);
    if (!sp || !fcomp) goto done;
    for (size_t i = 0; i < 2 * nf; i++) sp[i] = (uint32_t)i;
    for (size_t i = 0; i < nf; i++) fcomp[i] = (uint32_t)i;
    for (size_t i = 0; i < ni;) {
        size_t j = i;
        while (j < ni && I[j].e == I[i].e) j++;
        /* drop pairs of the same face walking the edge both ways (inside a face) */
        uint32_t e = I[i].e;
        const int64_t *pa = c->P + 3 * (size_t)evv[2 * e], *pb = c->P + 3 * (size_t)evv[2 * e + 1];
        fanctx x = {c,    A->of, 0, NULL, NULL, 0, {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]},
                    NULL, 0};
        uint32_t sg = umap_get(&A->eplane, key2(evv[2 * e], evv[2 * e + 1]));
        if (sg != NONE && c->S[sg].p0 != c->S[sg].p1) {
            x.nP = c->G[c->S[sg].p0].ni;
            x.nQ = c->G[c->S[sg].p1].ni;
            i128 E[3] = {x.nP[1] * x.nQ[2] - x.nP[2] * x.nQ[1],
                         x.nP[2] * x.nQ[0] - x.nP[0] * x.nQ[2],
                         x.nP[0] * x.nQ[1] - x.nP[1] * x.nQ[0]};
            i128 d = E[0] * x.e[0] + E[1] * x.e[1] + E[2] * x.e[2];
            x.sigma = (d > 0) - (d < 0);
            x.planes = x.sigma != 0;
        }
        x.nref = face_n(&x, I[i].f);
        x.sref = I[i].s;
        qsort_r(I + i, j - i, sizeof *I, fan_cmp, &x);
        for (size_t k = i; k < j; k++) {
            const inc *f0 = &I[k], *f1 = &I[k + 1 < j ? k + 1 : i];
            uint32_t n0 = 2 * f0->f + (f0->s > 0 ? 0 : 1);
            uint32_t n1 = 2 * f1->f + (f1->s > 0 ? 1 : 0);
            uf_union(sp, n0, n1);
            uf_union(fcomp, f0->f, f1->f);
        }
        i = j;
    }
    /* shells and their volumes */
    double o[3] = {0, 0, 0};
    cone = malloc((nf + 1) * sizeof *cone);
    shell_id = malloc((2 * nf + 1) * sizeof *shell_id);
    if (!cone || !shell_id) goto done;
    for (size_t f = 0; f < nf; f++) cone[f] = face_cone6(c, A, (uint32_t)f, o);
    size_t nsh = 0;
    for (size_t i = 0; i < 2 * nf; i++) shell_id[i] = NONE;
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t r = uf_find(sp, (uint32_t)i);
        if (shell_id[r] == NONE) shell_id[r] = (uint32_t)nsh++;
        shell_id[i] = shell_id[r];
    }
    svol = calloc(nsh + 1, sizeof *svol);
    uint32_t *scomp = malloc((nsh + 1) * sizeof *scomp);
    if (!svol || !scomp) {
        free(scomp);
        goto done;
    }
    for (size_t i = 0; i < 2 * nf; i++) {
        svol[shell_id[i]] += (i & 1) ? cone[i / 2] : -cone[i / 2];
        scomp[shell_id[i]] = uf_find(fcomp, (uint32_t)(i / 2));
    }
    for (size_t f = 0; f < nf; f++) fcomp[f] = uf_find(fcomp, (uint32_t)f);
    /* the outer shell of each component: the most negative */
    size_t ncomp = 0;
    uint32_t *outer = malloc((nf + 1) * sizeof *outer); /* by component root */
    uint32_t *cu = malloc((nsh + 2) * sizeof *cu);      /* union-find over shells + exterior */
    if (!outer || !cu) {
        free(outer), free(cu), free(scomp);
        goto done;
    }
    for (size_t f = 0; f < nf; f++) outer[f] = NONE;
    for (size_t s = 0; s < nsh; s++) {
        uint32_t k = scomp[s];
        if (outer[k] == NONE) ncomp++;
        if (outer[k] == NONE || svol[s] < svol[outer[k]]) outer[k] = (uint32_t)s;
    }
    for (size_t s = 0; s <= nsh; s++) cu[s] = (uint32_t)s;
    uint32_t EXT = (uint32_t)nsh;
    c->st->shells = nsh;
    c->st->components = ncomp;
    for (size_t k = 0; k < nf; k++) {
        if (outer[k] == NONE) continue;
        if (ncomp == 1) {
            uf_union(cu, outer[k], EXT);
            continue;
        }
        /* lowest vertex of component k */
        uint32_t best = NONE;
        for (size_t f = 0; f < nf; f++) {
            if (fcomp[f] != k) continue;
            const outface *F = &A->of[f];
            for (uint32_t i = A->ocyc_off[F->c0]; i < A->ocyc_off[F->c0 + 1]; i++) {
                uint32_t v = A->ocyc[i];
                if (best == NONE) best = v;
                const int64_t *p = c->P + 3 * (size_t)v, *q = c->P + 3 * (size_t)best;
                if (p[2] < q[2] || (p[2] == q[2] && (p[1] < q[1] || (p[1] == q[1] && p[0] < q[0]))))
                    best = v;
            }
        }
        double p[3];
        pt(c, best, p);
        static const double dirs[RAY_TRIES][3] = {
            {0.1234567, 0.0765432, -1}, {-0.21, 0.137, -1},   {0.0571, -0.3117, -1},
            {-0.0917, -0.1553, -1},     {0.3311, 0.2718, -1}, {0.01, 0.7, -1},
            {-0.6, 0.05, -1},           {0.45, -0.45, -1}};
        uint32_t hit = NONE - 1;
        for (int t = 0; t < RAY_TRIES && hit == NONE - 1; t++)
            hit = ray_hit(c, A, fcomp, (uint32_t)k, p, dirs[t]);
        if (hit == NONE || hit == NONE - 1)
            uf_union(cu, outer[k], EXT);
        else
            uf_union(cu, outer[k], shell_id[hit]);
    }
    /* cells: classes of shells; the one holding EXT is the exterior */
    cell = malloc((nsh + 2) * sizeof *cell);
    if (!cell) {
        free(outer), free(cu), free(scomp);
        goto done;
    }
    size_t nc = 0;
    for (size_t s = 0; s <= nsh; s++) cell[s] = NONE;
    uint32_t ext_root = uf_find(cu, EXT);
    /* number bounded cells by their smallest face side, which is deterministic */
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t r = uf_find(cu, shell_id[i]);
        if (r == ext_root || cell[r] != NONE) continue;
        cell[r] = (uint32_t)nc++;
    }
    free(outer);
    free(scomp);
    /* CF rows */
    out->nc = nc;
    out->cf_off = calloc(nc + 1, sizeof *out->cf_off);
    out->cvol = calloc(nc + 1, sizeof *out->cvol);
    if (!out->cf_off || !out->cvol) {
        free(cu);
        goto done;
    }
    size_t next = 0;
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t r = uf_find(cu, shell_id[i]);
        uint32_t other = uf_find(cu, shell_id[i ^ 1]);
        if (r == other) { /* both sides in one cell: not on its boundary */
            c->fins += (i & 1) == 0;
            continue;
        }
        if (r == ext_root)
            next++;
        else
            out->cf_off[cell[r] + 1]++;
    }
    for (size_t k = 0; k < nc; k++) out->cf_off[k + 1] += out->cf_off[k];
    out->cf = malloc((out->cf_off[nc] + 1) * sizeof *out->cf);
    out->ext = malloc((next + 1) * sizeof *out->ext);
    uint32_t *fill = calloc(nc + 1, sizeof *fill);
    if (!out->cf || !out->ext || !fill) {
        free(fill);
        free(cu);
        goto done;
    }
    out->next = 0;
    double h3 = c->step * c->step * c->step / 6;
    for (size_t i = 0; i < 2 * nf; i++) {
        uint32_t r = uf_find(cu, shell_id[i]);
        if (r == uf_find(cu, shell_id[i ^ 1])) continue;
        /* - side: the normal points out of this cell: +(f+1) */
        int32_t sf = (i & 1) ? (int32_t)(i / 2 + 1) : -(int32_t)(i / 2 + 1);
        if (r == ext_root) {
            out->ext[out->next++] = sf;
        } else {
            uint32_t k = cell[r];
            out->cf[out->cf_off[k] + fill[k]++] = sf;
            out->cvol[k] += ((i & 1) ? cone[i / 2] : -cone[i / 2]) * h3;
        }
    }
    /* a bounded cell of less than half a grid cube is a fold of rounding, not a region */
    for (size_t k = 0; k < nc; k++)
        if (!(out->cvol[k] / (h3 * 6) >= 0.5)) c->fins++;
    free(fill);
    free(cu);
    out->ne = ne;
    out->EV = evv;
    evv = NULL;
    rc = 0;
done:
    umap_free(&em);
    free(I);
    free(evv);
    free(sp);
    free(shell_id);
    free(fcomp);
    free(cell);
    free(cone);
    free(svol);
    return rc;
}

/* ------------------------------------------------------------------ output */

static int vcmp(const void *pa, const void *pb, void *vx)
{
    const int64_t *P = vx;
    uint32_t a = *(const uint32_t *)pa, b = *(const uint32_t *)pb;
    for (int k = 0; k < 3; k++)
        if (P[3 * (size_t)a + k] != P[3 * (size_t)b + k])
            return P[3 * (size_t)a + k] < P[3 * (size_t)b + k] ? -1 : 1;
    return 0;
}

static int cmpi32(const void *pa, const void *pb)
{
    int32_t a = *(const int32_t *)pa, b = *(const int32_t *)pb;
    return (a > b) - (a < b);
}

/* Renumbers vertices (by coordinates) and edges (by vertex pair) and fills the rest of out. */
static int stage_output(ctx *c, asm3 *A, lar3 *out)
{
    size_t nf = A->nof;
    uint32_t *used = NULL, *newid = NULL, *eord = NULL, *enew = NULL;
    int rc = -1;
    newid = malloc((c->nv + 1) * sizeof *newid);
    used = malloc((c->nv + 1) * sizeof *used);
    if (!newid || !used) goto done;
    for (size_t v = 0; v < c->nv; v++) newid[v] = NONE;
    size_t nu = 0;
    for (size_t i = 0; i < A->nocv; i++)
        if (newid[A->ocyc[i]] == NONE) newid[A->ocyc[i]] = 0, used[nu++] = A->ocyc[i];
    qsort_r(used, nu, sizeof *used, vcmp, c->P);
    for (size_t i = 0; i < nu; i++) newid[used[i]] = (uint32_t)i;
    out->nv = nu;
    out->V = malloc((3 * nu + 1) * sizeof *out->V);
    if (!out->V) goto done;
    for (size_t i = 0; i < nu; i++)
        for (int k = 0; k < 3; k++)
            out->V[3 * i + k] = (double)(c->oi[k] + c->P[3 * (size_t)used[i] + k]) * c->step;
    /* edges: renumber endpoints, orient, sort */
    size_t ne = out->ne;
    eord = malloc((ne + 1) * sizeof *eord);
    enew = malloc((ne + 1) * sizeof *enew);
    if (!eord || !enew) goto done;
    uint64_t *ek = malloc((ne + 1) * sizeof *ek);
    if (!ek) goto done;
    for (size_t e = 0; e < ne; e++) {
        uint32_t a = newid[out->EV[2 * e]], b = newid[out->EV[2 * e + 1]];
        if (a > b) {
            uint32_t t = a;
            a = b, b = t;
        }
        ek[e] = key2(a, b);
        eord[e] = (uint32_t)e;
    }
    qsort_r(eord, ne, sizeof *eord, ekcmp, ek);
    for (size_t i = 0; i < ne; i++) {
        enew[eord[i]] = (uint32_t)i;
        out->EV[2 * i] = (uint32_t)(ek[eord[i]] >> 32);
        out->EV[2 * i + 1] = (uint32_t)ek[eord[i]];
    }
    /* faces: cycles, signed edges */
    umap em = {0};
    for (size_t e = 0; e < ne; e++)
        if (umap_put(&em, ek[e], enew[e], NULL) == NONE) {
            free(ek);
            umap_free(&em);
            goto done;
        }
    free(ek);
    out->nf = nf;
    out->FN = malloc((3 * nf + 1) * sizeof *out->FN);
    out->fc_off = malloc((nf + 1) * sizeof *out->fc_off);
    out->fc = malloc((A->nocyc + 1) * sizeof *out->fc);
    out->fe_off = malloc((nf + 1) * sizeof *out->fe_off);
    out->fe = malloc((A->nocv + 1) * sizeof *out->fe);
    out->fsrc = malloc((nf + 1) * sizeof *out->fsrc);
    out->ncyc = A->nocyc;
    out->cyc_off = malloc((A->nocyc + 1) * sizeof *out->cyc_off);
    out->cyc = malloc((A->nocv + 1) * sizeof *out->cyc);
    if (!out->FN || !out->fc_off || !out->fc || !out->fe_off || !out->fe || !out->fsrc ||
        !out->cyc_off || !out->cyc) {
        umap_free(&em);
        goto done;
    }
    out->fc_off[0] = out->fe_off[0] = 0;
    size_t nfe = 0;
    for (size_t f = 0; f < nf; f++) {
        const outface *F = &A->of[f];
        const group *g = &c->G[F->group];
        for (int k = 0; k < 3; k++) out->FN[3 * f + k] = g->nd[k];
        out->fsrc[f] = F->src;
        for (uint32_t cy = F->c0; cy < F->c0 + F->nc; cy++) {
            out->fc[cy] = cy;
            uint32_t c0 = A->ocyc_off[cy], c1 = A->ocyc_off[cy + 1];
            for (uint32_t i = c0; i < c1; i++) {
                uint32_t a = newid[A->ocyc[i]], b = newid[A->ocyc[i + 1 < c1 ? i + 1 : c0]];
                uint32_t e = umap_get(&em, a < b ? key2(a, b) : key2(b, a));
                out->fe[nfe++] = a < b ? (int32_t)(e + 1) : -(int32_t)(e + 1);
            }
        }
        out->fc_off[f + 1] = F->c0 + F->nc;
        out->fe_off[f + 1] = (uint32_t)nfe;
    }
    umap_free(&em);
    out->fsol_off = malloc((nf + 1) * sizeof *out->fsol_off);
    out->fsol = malloc((A->nfsol + 1) * sizeof *out->fsol);
    if (!out->fsol_off || !out->fsol) goto done;
    out->fsol_off[0] = 0;
    for (size_t f = 0, n = 0; f < nf; f++) {
        const outface *F = &A->of[f];
        memcpy(out->fsol + n, A->fsol + F->s0, F->ns * sizeof *out->fsol);
        if (F->ns > 1) qsort(out->fsol + n, F->ns, sizeof *out->fsol, cmpu32);
        n += F->ns;
        out->fsol_off[f + 1] = (uint32_t)n;
    }
    for (size_t cy = 0; cy <= A->nocyc; cy++) out->cyc_off[cy] = A->ocyc_off[cy];
    for (size_t i = 0; i < A->nocv; i++) out->cyc[i] = newid[A->ocyc[i]];
    /* CV: sorted vertices of each cell's faces */
    out->cv_off = calloc(out->nc + 1, sizeof *out->cv_off);
    if (!out->cv_off) goto done;
    {
        uint32_t *buf = NULL, *cv = NULL;
        size_t nb = 0, capb = 0, ncv = 0, capcv = 0;
        for (size_t k = 0; k < out->nc; k++) {
            nb = 0;
            for (uint32_t i = out->cf_off[k]; i < out->cf_off[k + 1]; i++) {
                uint32_t f = (uint32_t)abs(out->cf[i]) - 1;
                for (uint32_t cy = out->fc_off[f]; cy < out->fc_off[f + 1]; cy++)
                    for (uint32_t j = out->cyc_off[cy]; j < out->cyc_off[cy + 1]; j++)
                        if (PUSH(buf, nb, capb, out->cyc[j])) {
                            free(buf), free(cv);
                            goto done;
                        }
            }
            if (nb > 1) qsort(buf, nb, sizeof *buf, cmpu32);
            for (size_t i = 0; i < nb; i++)
                if (i == 0 || buf[i] != buf[i - 1])
                    if (PUSH(cv, ncv, capcv, buf[i])) {
                        free(buf), free(cv);
                        goto done;
                    }
            out->cv_off[k + 1] = (uint32_t)ncv;
            if (out->cf_off[k + 1] - out->cf_off[k] > 1)
                qsort(out->cf + out->cf_off[k], out->cf_off[k + 1] - out->cf_off[k],
                      sizeof *out->cf, cmpi32);
        }
        free(buf);
        out->cv = cv ? cv : malloc(sizeof *out->cv);
        if (!out->cv) goto done;
    }
    if (out->next > 1) qsort(out->ext, out->next, sizeof *out->ext, cmpi32);
    out->stats.nv = out->nv;
    out->stats.ne = out->ne;
    out->stats.nf = out->nf;
    out->stats.nc = out->nc;
    rc = 0;
done:
    free(used);
    free(newid);
    free(eord);
    free(enew);
    return rc;
}

/* ------------------------------------------------------------------ entry */

static void ctx_free(ctx *c)
{
    free(c->P);
    free(c->alias);
    free(c->vtab);
    free(c->F);
    free(c->icyc_off);
    free(c->icyc);
    free(c->solid_face_off);
    for (size_t g = 0; c->G && g < c->ng; g++) {
        lar2_free(&c->G[g].res);
        free(c->G[g].rgid);
        free(c->G[g].rseg);
    }
    free(c->G);
    for (size_t s = 0; s < c->ns; s++) free(c->S[s].sp);
    free(c->S);
    umap_free(&c->edge_seg);
    free(c->sg_off);
    free(c->sg);
    free(c->gs_off);
    free(c->gs);
    for (size_t g = 0; c->req && g < c->ng; g++) {
        free(c->req[g].newp);
        free(c->req[g].split);
        free(c->req[g].merge);
    }
    free(c->req);
}

static int build_once(const solid *solids, size_t ns, int soup, const arr3_opts *opts, lar3 *out,
                      char *err, size_t errlen, size_t *fins)
{
    ctx c = {0};
    asm3 A = {0};
    uint64_t *pairs = NULL;
    size_t np = 0;
    int rc = ARR_OK;
    double t0 = now_ms(), t;
    memset(out, 0, sizeof *out);
    if (err && errlen) err[0] = 0;
    c.o = opts;
    c.threads = c.o->threads > 0 ? c.o->threads : par_ncpu();
    c.st = &out->stats;
    if ((rc = stage_input(&c, solids, ns, soup, err, errlen))) goto fail;
    out->nsolids = ns;
    out->solid_face_off = c.solid_face_off;
    c.solid_face_off = NULL;
    out->stats.ms_snap = now_ms() - t0;
    t = now_ms();
    if (face_pairs(&c, &pairs, &np) || stage_groups(&c, pairs, &np)) goto oom;
    out->stats.pairs_tested = np;
    out->stats.ms_pairs = now_ms() - t;
    t = now_ms();
    if (stage_edges(&c) || stage_cuts(&c, pairs, np) || stage_incidence(&c)) goto oom;
    free(pairs);
    pairs = NULL;
    out->stats.ms_cuts = now_ms() - t;
    if (cancelled(&c)) {
        rc = seterr(err, errlen, ARR_ECANCELED, "cancelled");
        goto fail;
    }
    t = now_ms();
    if ((rc = stage_rounds(&c, err, errlen))) goto fail;
    if (stage_faces(&c, &A)) goto oom;
    out->stats.ms_faces = now_ms() - t;
    t = now_ms();
    if (stage_cells(&c, &A, out) || stage_output(&c, &A, out)) goto oom;
    *fins = c.fins;
    out->stats.ms_cells = now_ms() - t;
    out->stats.ms_total = now_ms() - t0;
    progress(&c, "cells", 1);
    free(A.of);
    free(A.ocyc_off);
    free(A.ocyc);
    free(A.fsol);
    umap_free(&A.eplane);
    ctx_free(&c);
    return ARR_OK;
oom:
    rc = seterr(err, errlen, ARR_ENOMEM, "out of memory");
fail : {
    arr3_stats keep = out->stats;
    lar3_free(out);
    out->stats = keep;
}
    free(pairs);
    free(A.of);
    free(A.ocyc_off);
    free(A.ocyc);
    free(A.fsol);
    umap_free(&A.eplane);
    ctx_free(&c);
    return rc;
}

/* A closed surface has no face with one cell on both sides, and no cell without volume; rounding
 * can still make them where planes nearly coincide along a line (the faces' order about such an
 * edge is then only noise).
 * The arrangement is then made again on a grid twice as coarse, up to ARR3_RETRIES times, and
 * stats.precision says which grid was used. */
int arr3_build(const solid *solids, size_t ns, int soup, const arr3_opts *opts, lar3 *out,
               char *err, size_t errlen)
{
    static const arr3_opts defaults = {0};
    arr3_opts o = opts ? *opts : defaults;
    for (int attempt = 0;; attempt++) {
        size_t fins = 0;
        int rc = build_once(solids, ns, soup, &o, out, err, errlen, &fins);
        if (rc || soup || fins == 0) return rc;
        if (attempt == ARR3_RETRIES) {
            lar3_free(out);
            return seterr(err, errlen, ARR_EINTERNAL,
                          "solids: %zu faces have one cell on both sides or cells have no volume "
                          "at precision %g (planes too nearly coincident for this grid); try a "
                          "coarser precision",
                          fins, o.precision);
        }
        o.precision = 2 * out->stats.precision;
        lar3_free(out);
    }
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
