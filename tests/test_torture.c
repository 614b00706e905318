/* test_torture.c — the 2D arrangement on random inputs that are degenerate on purpose, run
 * on several threads at once: segments through one point, collinear overlaps and duplicates,
 * axis-parallel grids full of T-junctions, near-parallel pencils, thin spikes, zero-length
 * segments, and all of them far from the origin or tiny.  Every case goes through
 * lar_check() (walks, every edge on two face sides, d1·d2 = 0, Euler, areas adding up), must
 * give the same complex on 1 and 3 core threads, the same faces and area with keep_dangling,
 * and distinct output vertices (distinct doubles, in grid order).
 *
 * The cases run on TORTURE_THREADS test threads at once (the core is reentrant: this is also
 * what the daemon's workers do), each case with its own seed, so a failure names a seed that
 * reproduces it alone.  CELLAR_STRESS=N runs N times as many cases (make stress).
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/arr2.h"
#include "tests/check.h"
#include "tests/lar_check.h"

#define TORTURE_THREADS 4
#define CASES_PER_SIZE  600 /* per family, at CELLAR_STRESS=1 */

typedef struct segs {
    double *s; /* 4 doubles a segment */
    size_t n, cap;
} segs;

static int seg_add(segs *g, double x1, double y1, double x2, double y2)
{
    if (g->n == g->cap) {
        size_t cap = g->cap ? 2 * g->cap : 64;
        double *p = realloc(g->s, cap * 4 * sizeof *p);
        if (!p) return -1;
        g->s = p;
        g->cap = cap;
    }
    double *q = g->s + 4 * g->n++;
    q[0] = x1;
    q[1] = y1;
    q[2] = x2;
    q[3] = y2;
    return 0;
}

static double rnd(uint64_t *st)
{
    return test_rnd(st);
}

static int irnd(uint64_t *st, int n)
{
    return (int)(rnd(st) * n);
}

/* ---- the families: each adds a scene in about the unit square (coordinates on a small
 * integer lattice where the degeneracy needs exact ties) ---- */

/* k segments through one point, both ends on the lattice, plus a few crossing them */
static void fam_star(segs *g, uint64_t *st)
{
    int k = 3 + irnd(st, 30), cx = irnd(st, 9), cy = irnd(st, 9);
    for (int i = 0; i < k; i++) {
        int dx = irnd(st, 9) - 4, dy = irnd(st, 9) - 4;
        if (!dx && !dy) dx = 1;
        seg_add(g, (cx - dx) / 8.0, (cy - dy) / 8.0, (cx + dx) / 8.0, (cy + dy) / 8.0);
    }
    for (int i = 0; i < 4; i++)
        seg_add(g, irnd(st, 9) / 8.0, irnd(st, 9) / 8.0, irnd(st, 9) / 8.0, irnd(st, 9) / 8.0);
}

/* segments on a few lines, overlapping, nested, repeated, reversed */
static void fam_collinear(segs *g, uint64_t *st)
{
    int lines = 1 + irnd(st, 4);
    for (int l = 0; l < lines; l++) {
        int ax = irnd(st, 5), ay = irnd(st, 5), dx = irnd(st, 3) - 1, dy = irnd(st, 3);
        if (!dx && !dy) dy = 1;
        int m = 2 + irnd(st, 12);
        for (int i = 0; i < m; i++) {
            int t0 = irnd(st, 8), t1 = irnd(st, 8);
            if (t0 == t1) t1 = t0 + 1;
            seg_add(g, (ax + t0 * dx) / 4.0, (ay + t0 * dy) / 4.0, (ax + t1 * dx) / 4.0,
                    (ay + t1 * dy) / 4.0);
            if (irnd(st, 4) == 0) /* the same again, reversed */
                seg_add(g, (ax + t1 * dx) / 4.0, (ay + t1 * dy) / 4.0, (ax + t0 * dx) / 4.0,
                        (ay + t0 * dy) / 4.0);
        }
    }
    for (int i = 0; i < 3; i++) /* something to close faces with */
        seg_add(g, irnd(st, 9) / 4.0, irnd(st, 9) / 4.0, irnd(st, 9) / 4.0, irnd(st, 9) / 4.0);
}

/* axis-parallel segments on a lattice: T-junctions, shared endpoints, overlaps */
static void fam_grid(segs *g, uint64_t *st)
{
    int m = 8 + irnd(st, 60);
    for (int i = 0; i < m; i++) {
        int a = irnd(st, 11), b = irnd(st, 11), c = irnd(st, 11);
        if (b == c) c = (c + 1) % 11;
        if (irnd(st, 2))
            seg_add(g, b / 10.0, a / 10.0, c / 10.0, a / 10.0);
        else
            seg_add(g, a / 10.0, b / 10.0, a / 10.0, c / 10.0);
    }
}

/* long segments whose slopes differ by a few ulps, and a few crossing them */
static void fam_pencil(segs *g, uint64_t *st)
{
    int k = 2 + irnd(st, 12);
    double y = rnd(st), slope = rnd(st) - 0.5;
    for (int i = 0; i < k; i++) {
        double s = slope + (irnd(st, 7) - 3) * 1e-15, yy = y + (irnd(st, 5) - 2) * 1e-13;
        seg_add(g, 0, yy, 1, yy + s);
    }
    for (int i = 0; i < 3; i++) {
        double x = rnd(st);
        seg_add(g, x, -1, x + (rnd(st) - 0.5) * 1e-9, 2);
    }
}

/* polygons with thin spikes: a tip within a few grid steps of an edge, or of another tip */
static void fam_spikes(segs *g, uint64_t *st)
{
    int m = 1 + irnd(st, 5);
    for (int p = 0; p < m; p++) {
        double x0 = rnd(st), y0 = rnd(st), w = 0.1 + 0.4 * rnd(st), h = 0.1 + 0.4 * rnd(st);
        double eps = ldexp(1.0, -30 - irnd(st, 14)); /* about the default grid step */
        double tx = x0 + w * rnd(st), ty = y0 + h + h * rnd(st);
        /* a rectangle whose top edge carries a spike of width eps */
        seg_add(g, x0, y0, x0 + w, y0);
        seg_add(g, x0 + w, y0, x0 + w, y0 + h);
        seg_add(g, x0 + w, y0 + h, tx + eps, y0 + h);
        seg_add(g, tx + eps, y0 + h, tx, ty);
        seg_add(g, tx, ty, tx - eps, y0 + h);
        seg_add(g, tx - eps, y0 + h, x0, y0 + h);
        seg_add(g, x0, y0 + h, x0, y0);
        if (irnd(st, 2)) /* a segment passing just below the tip */
            seg_add(g, tx - w, ty - eps * irnd(st, 4), tx + w, ty - eps * irnd(st, 4));
    }
}

/* random segments with zero-length ones and exact duplicates mixed in */
static void fam_dups(segs *g, uint64_t *st)
{
    int m = 5 + irnd(st, 40);
    for (int i = 0; i < m; i++) {
        double x1 = irnd(st, 17) / 16.0, y1 = irnd(st, 17) / 16.0;
        double x2 = irnd(st, 17) / 16.0, y2 = irnd(st, 17) / 16.0;
        switch (irnd(st, 5)) {
        case 0:
            seg_add(g, x1, y1, x1, y1);
            break;
        case 1:
            seg_add(g, x1, y1, x2, y2);
            seg_add(g, x1, y1, x2, y2);
            break;
        case 2:
            seg_add(g, x1, y1, x2, y2);
            seg_add(g, x2, y2, x1, y1);
            break;
        default:
            seg_add(g, x1, y1, x2, y2);
        }
    }
}

typedef void (*family_fn)(segs *, uint64_t *);
static const struct {
    const char *name;
    family_fn fn;
} families[] = {{"star", fam_star},     {"collinear", fam_collinear}, {"grid", fam_grid},
                {"pencil", fam_pencil}, {"spikes", fam_spikes},       {"dups", fam_dups}};
#define NFAM (sizeof families / sizeof *families)

/* Where the scene goes: 0 as made, 1 far from the origin (1e6 .. 1e13), 2 tiny (1e-9), 3
 * far and large (x 1e5 at 1e9). */
static void place(segs *g, int where, uint64_t *st)
{
    double scale = 1, off = 0;
    if (where == 1) off = ldexp(1.0, 20 + irnd(st, 24)) * (1 + rnd(st));
    if (where == 2) scale = 1e-9;
    if (where == 3) {
        scale = 1e5;
        off = 1e9;
    }
    for (size_t i = 0; i < 4 * g->n; i++) g->s[i] = g->s[i] * scale + off;
}

/* ---- the checks of one case ---- */

typedef struct outcome {
    char msg[512]; /* the first failure, or "" */
    size_t faces, skipped;
} outcome;

static int same_complex(const lar2 *a, const lar2 *b)
{
    return a->nv == b->nv && a->ne == b->ne && a->nf == b->nf && a->ncyc == b->ncyc &&
           !memcmp(a->V, b->V, 2 * a->nv * sizeof *a->V) &&
           !memcmp(a->EV, b->EV, 2 * a->ne * sizeof *a->EV) &&
           !memcmp(a->cyc_off, b->cyc_off, (a->ncyc + 1) * sizeof *a->cyc_off) &&
           !memcmp(a->cyc, b->cyc, a->cyc_off[a->ncyc] * sizeof *a->cyc);
}

static double area_sum(const lar2 *c)
{
    double a = 0;
    for (size_t f = 0; f < c->nf; f++) a += lar_face_area(c, f);
    return a;
}

/* Output vertices are distinct doubles (V is in grid order, x then y, and distinct points
 * there must stay distinct once written). */
static int distinct_vertices(const lar2 *c, size_t *at)
{
    for (size_t v = 1; v < c->nv; v++)
        if (c->V[2 * v] == c->V[2 * v - 2] && c->V[2 * v + 1] == c->V[2 * v - 1]) {
            *at = v;
            return 0;
        }
    return 1;
}

static void run_case(size_t k, outcome *o)
{
    uint64_t st = 0x70727475726555u + k * 0x9e3779b97f4a7c15u;
    size_t fam = k % NFAM;
    int where = (int)(k / NFAM % 4);
    segs g = {0};
    families[fam].fn(&g, &st);
    place(&g, where, &st);
    char err[256], msg[256];
    lar2 a = {0}, b = {0}, d = {0};
    arr2_opts o1 = {.threads = 1, .input_coords = 1}, o3 = {.threads = 3, .input_coords = 1},
              od = {.threads = 2, .keep_dangling = 1, .input_coords = 1};
    int ra = arr2_build(g.s, g.n, &o1, &a, err, sizeof err);
    if (ra == ARR_ELIMIT) { /* a scene the grid cannot hold at this place: said, not wrong */
        o->skipped++;
        goto out;
    }
    if (ra != ARR_OK) {
        snprintf(o->msg, sizeof o->msg, "arr2_build failed (%d): %s", ra, err);
        goto out;
    }
    if (lar_check(&a, msg, sizeof msg)) {
        snprintf(o->msg, sizeof o->msg, "invariant: %s", msg);
        goto out;
    }
    size_t at = 0;
    if (!distinct_vertices(&a, &at)) {
        snprintf(o->msg, sizeof o->msg, "vertices %zu and %zu are the same double (%.17g, %.17g)",
                 at - 1, at, a.V[2 * at], a.V[2 * at + 1]);
        goto out;
    }
    int rb = arr2_build(g.s, g.n, &o3, &b, err, sizeof err);
    if (rb != ARR_OK || !same_complex(&a, &b)) {
        snprintf(o->msg, sizeof o->msg, "1 and 3 threads differ (rc %d: %s)", rb, rb ? err : "");
        goto out;
    }
    int rd = arr2_build(g.s, g.n, &od, &d, err, sizeof err);
    if (rd != ARR_OK || lar_check(&d, msg, sizeof msg)) {
        snprintf(o->msg, sizeof o->msg, "keep_dangling: rc %d: %s", rd, rd ? err : msg);
        goto out;
    }
    double aa = area_sum(&a), ad = area_sum(&d);
    if (d.nf != a.nf || fabs(aa - ad) > 1e-9 * (fabs(aa) + 1e-300)) {
        snprintf(o->msg, sizeof o->msg,
                 "keep_dangling changes the faces: %zu (area %.17g) vs %zu"
                 " (area %.17g)",
                 d.nf, ad, a.nf, aa);
        goto out;
    }
    o->faces += a.nf;
out:
    lar2_free(&a);
    lar2_free(&b);
    lar2_free(&d);
    free(g.s);
}

/* ---- the pool ---- */

typedef struct pool {
    size_t ncases;
    atomic_size_t next;
    pthread_mutex_t mu;
    size_t failed, faces, skipped, done[NFAM];
    char first[8][600]; /* the first failures, to print */
} pool;

static void *worker(void *arg)
{
    pool *p = arg;
    for (;;) {
        size_t k = atomic_fetch_add(&p->next, 1);
        if (k >= p->ncases) return NULL;
        outcome o = {{0}, 0, 0};
        run_case(k, &o);
        pthread_mutex_lock(&p->mu);
        p->faces += o.faces;
        p->skipped += o.skipped;
        p->done[k % NFAM]++;
        if (o.msg[0]) {
            if (p->failed < 8)
                snprintf(p->first[p->failed], sizeof p->first[0], "case %zu (%s, place %d): %s", k,
                         families[k % NFAM].name, (int)(k / NFAM % 4), o.msg);
            p->failed++;
        }
        pthread_mutex_unlock(&p->mu);
    }
}

TEST(torture_2d_degenerate_families)
{
    const char *env = getenv("CELLAR_STRESS");
    size_t mult = env && atoi(env) > 0 ? (size_t)atoi(env) : 1;
    pool p = {.ncases = mult * CASES_PER_SIZE * NFAM};
    atomic_init(&p.next, 0);
    pthread_mutex_init(&p.mu, NULL);
    pthread_t t[TORTURE_THREADS];
    int started = 0;
    for (int i = 0; i < TORTURE_THREADS; i++)
        if (pthread_create(&t[i], NULL, worker, &p) == 0) started++;
    REQUIRE(started > 0, "no test thread could start");
    for (int i = 0; i < TORTURE_THREADS; i++)
        if (i < started) pthread_join(t[i], NULL);
    pthread_mutex_destroy(&p.mu);
    for (size_t i = 0; i < p.failed && i < 8; i++) CHECK(0, "%s", p.first[i]);
    CHECK(p.failed == 0, "%zu of %zu cases failed", p.failed, p.ncases);
    /* the families must do what they are for: faces in most cases, few refused */
    CHECK(p.faces > p.ncases, "only %zu faces in %zu cases", p.faces, p.ncases);
    CHECK(p.skipped * 20 < p.ncases, "%zu of %zu cases refused by the grid limit", p.skipped,
          p.ncases);
    printf("  (torture: %zu cases on %d threads, %zu faces, %zu refused as beyond the grid)\n",
           p.ncases, started, p.faces, p.skipped);
}
