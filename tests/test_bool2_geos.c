/* test_bool2_geos.c — the 2D Booleans (kind "polygons": core/bool2.h, api/polygons.c) against
 * GEOS (libgeos_c, the _r API) on random inputs that are hard on purpose.
 *
 * Families (each a generator adding one OGC-valid polygon at a time, in a unit frame whose grid
 * step h is 2^-20; every polygon is checked with GEOSisValid_r after the move below and drawn
 * again when invalid; the redraws are counted and must stay a small fraction):
 *   spikes  star polygons with needle spikes (out) and slits (in) whose base is 0.1 to 5 grid
 *           steps wide, needle triangles (0.1 to 5 steps) and sharp wedges, some with their tip
 *           0.1 to 5 steps off an earlier polygon's edge or fanning out of an earlier vertex,
 *           and copies of earlier polygons moved by 0.1 to 3 steps and turned by a few steps;
 *   near    polygons with an edge 0.1 to 3 grid steps (a quarter: 2 to 6, around the distance
 *           where arr2 stops keeping input coordinates) from an earlier polygon's edge, each
 *           end offset on its own (so nearly parallel, and sometimes crossing), with the ends
 *           kept, moved along the edge or both;
 *   onedge  dyadic polygons with a vertex exactly at the midpoint of an earlier polygon's edge:
 *           triangles with an apex there, triangles sharing half the edge, stars pinned there;
 *   shared  lattice rectangles (some with a hole), L shapes and the triangles of a
 *           triangulated lattice: edges and vertices shared everywhere;
 *   holes   lattice rectangles whose holes touch the shell at one vertex (on an edge, at a
 *           corner) and each other at one vertex (chains and pairs of diamonds), with other
 *           such polygons, rectangles and stars over them.
 * Each family runs in three frames: "unit" (coordinates in about [0, 1]), "far" (moved by 1e6:
 * coordinates around 1e6) and "tiny" (scaled by 2^-20: coordinates around 1e-6, exact for the
 * dyadic families).  The precision is explicit (h times the frame's scale), except for one
 * case in eight that uses the automatic one (core/arr2.c: the power of two above extent *
 * 2^-38, no finer than the doubles there; the step used is read from the result's stats).
 *
 * For every case (2 to 5 polygons): union, intersection, difference (the first minus the union
 * of the rest) and xor (odd membership) of all; the same four of the first two, A and B, and
 * A and B alone (the union of one input); the identities |A| = |A & B| + |A - B|,
 * |A + B| = |A| + |B| - |A & B|, |A ^ B| = |A + B| - |A & B|; and the union of 8 to 30 polygons of
 * the same family against GEOSUnaryUnion_r.  Every area is compared with GEOS's:
 *
 *   |ours - GEOS| <= bound = 2 * P * (h + 8 ulp(M))
 *
 * P is the total perimeter of all input rings of the run, h the grid step used, M the largest
 * coordinate magnitude.  Why: snap rounding moves every point of every input edge by at most
 * half a pixel diagonal (h / sqrt 2): vertices go to their pixel's centre and edges are bent only
 * through the centres of pixels they cross, and vertices that input points snapped to even keep
 * the input's coordinates; the result's boundary lies on the input edges, so the region swept
 * between the exact and the snapped boundary has area at most P * h / sqrt 2.  The factor 2
 * covers that (0.71) with room for the identities, which add two or three such errors of
 * different runs (each at most 0.71 of its own inputs' perimeter, and the runs of A and B alone
 * have less of it); 8 ulp(M) stands for the rounding of GEOS's own crossings (and of ours when
 * the grid is finer than a double's resolution, as with the automatic precision at 1e6).  The
 * worst |error| / bound over all runs is printed.
 *
 * Every result must be OGC-valid: each polygon (shell = the vertices of poly_outer[q], holes =
 * the ph_cyc rings) and the MultiPolygon of all pass GEOSisValid_r (GEOSisValidReason_r printed
 * when not); shells are counter-clockwise and holes clockwise (signed areas from the
 * coordinates); the polygons' areas (from their coordinates) add up to r.area within the bound
 * above, and within 1e-9 of the larger of |r.area| and the rings' total |area| (the results
 * missing that are counted, the first few printed, and make one failure per family).
 *
 * No run may fail: bool2_build() must return ARR_OK; an error whose message says "labels
 * inconsistent after snapping" (a 422, not an internal error) is tolerated and counted, anything
 * else fails.  One case in eight also runs one of its four operations through api_run_json() as
 * a native JSON request, and another its union of many (status 200, the same area and polygon
 * count as directly).  When GEOS fails (NULL, or an invalid result) the run counts as "GEOS
 * failed" and is not compared.  When GEOS's answer is off by more than a quarter of the bound,
 * GEOS runs again on the inputs moved to about their centre (GEOS's rounding and its snapping
 * fallbacks far from the origin can cost more than the bound; the move costs at most an ulp per
 * coordinate), and the answer closer to ours is the reference (for the worst ratio too); when
 * only the moved one is within the bound, the run counts as "GEOS failed" (and "wrong"), printed
 * and dumped.  Any other disagreement beyond the bound is a failure.
 *
 * Environment: CELLAR_SANITIZED=1 (make check) runs a tenth of the cases; CELLAR_STRESS=N runs N
 * seeds of each family, a seed being a batch of the default number of cases (so N times as
 * many); CELLAR_DUMP=DIR writes every failing run into DIR as a request
 * (bool2-FAMILY-FRAME-CASE-WHAT.json) that `build/cellar run FILE` replays.
 */
#define GEOS_USE_ONLY_R_API
#include <geos_c.h>
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "api/api.h"
#include "core/bool2.h"
#include "tests/check.h"
#include "tests/ref/geos_ref.h"

#define CASES_PER_SEED 200 /* cases of each family and frame per seed (a tenth when sanitized) */
#define UNIT_STEP      (1.0 / 1048576) /* h: the grid step in the unit frame, 2^-20 */
#define TOLERATED_MSG  "labels inconsistent after snapping"

/* ---- building inputs ------------------------------------------------------------------------ */

#define PB_MAXP  64
#define PB_MAXR  512
#define PB_MAXPT 16384

typedef struct pb {
    uint32_t poly_off[PB_MAXP + 1], ring_off[PB_MAXR + 1];
    double xy[2 * PB_MAXPT];
    size_t np, nr, npt;
    int full; /* a ring or polygon did not fit */
} pb;

static void pb_ring(pb *b, const double *pts, size_t n)
{
    if (b->full || b->nr + 1 > PB_MAXR || b->npt + n > PB_MAXPT) {
        b->full = 1;
        return;
    }
    memcpy(b->xy + 2 * b->npt, pts, 2 * n * sizeof *pts);
    b->npt += n;
    b->ring_off[++b->nr] = (uint32_t)b->npt;
}

static void pb_end(pb *b)
{
    if (b->full || b->np + 1 > PB_MAXP) {
        b->full = 1;
        return;
    }
    b->poly_off[++b->np] = (uint32_t)b->nr;
}

/* Drops the polygons from np on (the last one, after a failed check). */
static void pb_truncate(pb *b, size_t np)
{
    b->np = np;
    b->nr = b->poly_off[np];
    b->npt = b->ring_off[b->nr];
    b->full = 0;
}

/* Appends polygon p of src to dst, each point mapped to (x * s + ox, y * s + oy). */
static void pb_copy_poly(pb *dst, const pb *src, size_t p, double s, double ox, double oy)
{
    for (uint32_t r = src->poly_off[p]; r < src->poly_off[p + 1]; r++) {
        uint32_t a = src->ring_off[r], n = src->ring_off[r + 1] - a;
        size_t at = dst->npt;
        pb_ring(dst, src->xy + 2 * a, n);
        if (dst->full) return;
        for (uint32_t i = 0; i < n; i++) {
            dst->xy[2 * (at + i)] = src->xy[2 * (a + i)] * s + ox;
            dst->xy[2 * (at + i) + 1] = src->xy[2 * (a + i) + 1] * s + oy;
        }
    }
    pb_end(dst);
}

static bool2_input pb_input(const pb *b)
{
    return (bool2_input){b->np, b->poly_off, b->ring_off, b->xy, BOOL2_FILL_ODD, 0};
}

/* The total perimeter of all rings and the largest coordinate magnitude. */
static double pb_perimeter(const pb *b, double *maxabs)
{
    double p = 0, m = 0;
    for (size_t r = 0; r < b->nr; r++) {
        uint32_t a = b->ring_off[r], n = b->ring_off[r + 1] - a;
        for (uint32_t i = 0; i < n; i++) {
            const double *u = b->xy + 2 * (a + i), *v = b->xy + 2 * (a + (i + 1) % n);
            p += hypot(v[0] - u[0], v[1] - u[1]);
            m = fmax(m, fmax(fabs(u[0]), fabs(u[1])));
        }
    }
    if (maxabs) *maxabs = m;
    return p;
}

/* The area bound of a run on b with grid step h (see the top of the file). */
static double area_bound(const pb *b, double h)
{
    double m, p = pb_perimeter(b, &m);
    double ulp = m > 0 ? ldexp(1.0, ilogb(m) - 52) : 0;
    return 2 * p * (h + 8 * ulp);
}

/* The request of op on b as native JSON (precision 0: none given); malloc'd. */
static char *case_json(const pb *b, const char *op, double precision)
{
    char *s = NULL;
    size_t len;
    FILE *f = open_memstream(&s, &len);
    if (!f) return NULL;
    fprintf(f, "{\"kind\":\"polygons\",\"polygons\":[");
    for (size_t p = 0; p < b->np; p++) {
        fprintf(f, "%s[", p ? "," : "");
        for (uint32_t r = b->poly_off[p]; r < b->poly_off[p + 1]; r++) {
            fprintf(f, "%s[", r > b->poly_off[p] ? "," : "");
            for (uint32_t i = b->ring_off[r]; i < b->ring_off[r + 1]; i++)
                fprintf(f, "%s[%.17g,%.17g]", i > b->ring_off[r] ? "," : "", b->xy[2 * i],
                        b->xy[2 * i + 1]);
            fprintf(f, "]");
        }
        fprintf(f, "]");
    }
    fprintf(f, "],\"op\":\"%s\"", op);
    if (precision > 0) fprintf(f, ",\"options\":{\"precision\":%.17g}", precision);
    fprintf(f, "}\n");
    fclose(f);
    return s;
}

/* ---- random shapes (unit frame) ------------------------------------------------------------- */

static double rr(uint64_t *st, double a, double b)
{
    return a + (b - a) * test_rnd(st);
}

static int ri(uint64_t *st, int n) /* 0 .. n-1 */
{
    int k = (int)(test_rnd(st) * n);
    return k < n ? k : n - 1;
}

static double rsign(uint64_t *st)
{
    return test_rnd(st) < 0.5 ? -1 : 1;
}

/* Per case: what the polygons of one case share. */
typedef struct gctx {
    double h;      /* grid step of the unit frame */
    int cells;     /* shared: lattice cells per side */
    uint64_t diag; /* shared: the diagonals of the triangulated lattice */
} gctx;

/* A star around (cx, cy), nv directions in increasing angle at radii [r0, r1]; with probability
 * pspike a direction becomes a needle: two base points w = 0.1..5 h apart and a tip far out, or
 * a slit in to 0.45..0.95 r0.  Star-shaped about the centre with strictly increasing angles, so
 * simple.  Returns the number of points. */
static size_t ring_star(double *pts, uint64_t *st, double cx, double cy, double r0, double r1,
                        int nv, double pspike, double h)
{
    size_t k = 0;
    double a0 = rr(st, 0, 2 * M_PI);
    for (int i = 0; i < nv; i++) {
        double ang = a0 + 2 * M_PI * (i + 0.15 + 0.7 * test_rnd(st)) / nv;
        double rad = rr(st, r0, r1);
        if (test_rnd(st) < pspike) {
            double w = h * rr(st, 0.1, 5), d = w / 2 / rad;
            double tip = test_rnd(st) < 0.7 ? rad + rr(st, 0.05, 0.35) : r0 * rr(st, 0.45, 0.95);
            pts[2 * k] = cx + rad * cos(ang - d), pts[2 * k + 1] = cy + rad * sin(ang - d), k++;
            pts[2 * k] = cx + tip * cos(ang), pts[2 * k + 1] = cy + tip * sin(ang), k++;
            pts[2 * k] = cx + rad * cos(ang + d), pts[2 * k + 1] = cy + rad * sin(ang + d), k++;
        } else {
            pts[2 * k] = cx + rad * cos(ang), pts[2 * k + 1] = cy + rad * sin(ang), k++;
        }
    }
    return k;
}

static void square_ring(double *pts, double cx, double cy, double s)
{
    double r[8] = {cx - s, cy - s, cx + s, cy - s, cx + s, cy + s, cx - s, cy + s};
    memcpy(pts, r, sizeof r);
}

static void rect_ring(double *pts, double x0, double y0, double x1, double y1)
{
    double r[8] = {x0, y0, x1, y0, x1, y1, x0, y1};
    memcpy(pts, r, sizeof r);
}

/* A random ring edge of polygon j: its end points. */
static void random_edge(const pb *u, uint64_t *st, size_t j, double *p, double *q)
{
    uint32_t r = u->poly_off[j] + (uint32_t)ri(st, (int)(u->poly_off[j + 1] - u->poly_off[j]));
    uint32_t a = u->ring_off[r], n = u->ring_off[r + 1] - a, i = (uint32_t)ri(st, (int)n);
    memcpy(p, u->xy + 2 * (a + i), 2 * sizeof *p);
    memcpy(q, u->xy + 2 * (a + (i + 1) % n), 2 * sizeof *q);
}

/* spikes: needle stars (some with a hole), needle triangles and sharp wedges, near copies. */
static void gen_spikes(pb *u, uint64_t *st, const gctx *g)
{
    double pts[2 * 96];
    double x = test_rnd(st);
    if (u->np > 0 && x < 0.25) { /* a copy of an earlier polygon, moved 0.1..3 h, turned */
        size_t j = (size_t)ri(st, (int)u->np);
        double d = g->h * rr(st, 0.1, 3), a = rr(st, 0, 2 * M_PI);
        double th = test_rnd(st) < 0.5 ? g->h * rr(st, -3, 3) : 0; /* a few steps at 1 */
        double c = cos(th), s = sin(th);
        const double *o = u->xy + 2 * u->ring_off[u->poly_off[j]];
        for (uint32_t r = u->poly_off[j]; r < u->poly_off[j + 1]; r++) {
            uint32_t b = u->ring_off[r], n = u->ring_off[r + 1] - b;
            if (n > 96) return;
            for (uint32_t i = 0; i < n; i++) {
                double px = u->xy[2 * (b + i)] - o[0], py = u->xy[2 * (b + i) + 1] - o[1];
                pts[2 * i] = o[0] + c * px - s * py + d * cos(a);
                pts[2 * i + 1] = o[1] + s * px + c * py + d * sin(a);
            }
            pb_ring(u, pts, n);
        }
        pb_end(u);
    } else if (x < 0.65) { /* a needle star, maybe with a square hole inside its kernel */
        double cx = rr(st, 0.3, 0.7), cy = rr(st, 0.3, 0.7), r0 = rr(st, 0.12, 0.25);
        size_t n = ring_star(pts, st, cx, cy, r0, r0 + rr(st, 0, 0.15), 5 + ri(st, 12), 0.4, g->h);
        pb_ring(u, pts, n);
        if (test_rnd(st) < 0.25) {
            square_ring(pts, cx, cy, 0.25 * r0); /* corner at 0.35 r0 < the slits' 0.45 r0 */
            pb_ring(u, pts, 4);
        }
        pb_end(u);
    } else { /* a needle triangle (0.1..5 h wide) or a sharp wedge (5..300 h) */
        double px = rr(st, 0.2, 0.8), py = rr(st, 0.2, 0.8), a = rr(st, 0, 2 * M_PI);
        double y = test_rnd(st);
        if (u->np > 0 && y < 0.35) { /* its tip 0.1..5 h off an earlier polygon's edge */
            double p[2], q[2];
            random_edge(u, st, (size_t)ri(st, (int)u->np), p, q);
            double t = rr(st, 0.05, 0.95), dx = q[0] - p[0], dy = q[1] - p[1];
            double len = hypot(dx, dy), d = rsign(st) * g->h * rr(st, 0.1, 5);
            px = p[0] + t * dx - d * dy / len, py = p[1] + t * dy + d * dx / len;
        } else if (u->np > 0 && y < 0.5) { /* a fan: at or near an earlier polygon's vertex */
            const double *v = u->xy + 2 * u->ring_off[u->poly_off[u->np - 1]];
            double d = test_rnd(st) < 0.5 ? 0 : g->h * rr(st, 0, 2), b = rr(st, 0, 2 * M_PI);
            px = v[0] + d * cos(b), py = v[1] + d * sin(b);
        }
        double len = rr(st, 0.1, 0.6);
        double w = g->h * (test_rnd(st) < 0.6 ? rr(st, 0.1, 5) : rr(st, 5, 300));
        double ux = cos(a), uy = sin(a), nx = -uy, ny = ux;
        double t[6] = {px,
                       py,
                       px + len * ux + w / 2 * nx,
                       py + len * uy + w / 2 * ny,
                       px + len * ux - w / 2 * nx,
                       py + len * uy - w / 2 * ny};
        pb_ring(u, t, 3);
        pb_end(u);
    }
}

/* A plain star with maybe a hole: the first polygon of the near and onedge families. */
static void plain_star(pb *u, uint64_t *st, double lattice)
{
    double pts[2 * 32];
    double cx = rr(st, 0.3, 0.7), cy = rr(st, 0.3, 0.7), r0 = rr(st, 0.15, 0.25);
    size_t n = ring_star(pts, st, cx, cy, r0, r0 + rr(st, 0.02, 0.15), 4 + ri(st, 9), 0, 0);
    if (lattice > 0) {
        for (size_t i = 0; i < 2 * n; i++) pts[i] = round(pts[i] / lattice) * lattice;
        cx = round(cx / lattice) * lattice, cy = round(cy / lattice) * lattice;
    }
    pb_ring(u, pts, n);
    if (test_rnd(st) < 0.3) {
        double s = 0.3 * r0;
        if (lattice > 0) s = fmax(lattice, round(s / lattice) * lattice);
        square_ring(pts, cx, cy, s);
        pb_ring(u, pts, 4);
    }
    pb_end(u);
}

/* near: an edge 0.1..3 h off an earlier polygon's edge, each end on its own. */
static void gen_near(pb *u, uint64_t *st, const gctx *g)
{
    if (u->np == 0 || test_rnd(st) < 0.12) {
        plain_star(u, st, 0);
        return;
    }
    double p[2], q[2];
    random_edge(u, st, (size_t)ri(st, (int)u->np), p, q);
    double dx = q[0] - p[0], dy = q[1] - p[1], len = hypot(dx, dy);
    double ux = dx / len, uy = dy / len, nx = -uy, ny = ux;
    /* mostly 0.1..3 h; sometimes 2..6 h, about where arr2 stops keeping input coordinates */
    double lo = 0.1, hi = 3;
    if (test_rnd(st) < 0.25) lo = 2, hi = 6;
    double d1 = rsign(st) * g->h * rr(st, lo, hi), d2 = rsign(st) * g->h * rr(st, lo, hi);
    double e1 = 0, e2 = 0, y = test_rnd(st);
    if (y < 0.3) /* the ends moved along the edge: partial overlaps */
        e1 = rr(st, -0.4, 0.4) * len, e2 = rr(st, -0.4, 0.4) * len;
    else if (y < 0.45) /* one end kept exactly, the other off the edge */
        d1 = 0, e2 = rr(st, -0.3, 0.3) * len;
    double a[2] = {p[0] + e1 * ux + d1 * nx, p[1] + e1 * uy + d1 * ny};
    double b[2] = {q[0] + e2 * ux + d2 * nx, q[1] + e2 * uy + d2 * ny};
    if ((b[0] - a[0]) * ux + (b[1] - a[1]) * uy <= 0.02 * len) { /* kept the direction */
        b[0] = q[0] + d2 * nx, b[1] = q[1] + d2 * ny;
        a[0] = p[0] + d1 * nx, a[1] = p[1] + d1 * ny;
    }
    double s = rsign(st), t1 = rr(st, 0.02, 0.3), t2 = rr(st, 0.02, 0.3);
    if (test_rnd(st) < 0.35) { /* a triangle */
        double m = rr(st, 0.2, 0.8);
        double t[6] = {a[0],
                       a[1],
                       b[0],
                       b[1],
                       a[0] + m * (b[0] - a[0]) + s * t1 * nx,
                       a[1] + m * (b[1] - a[1]) + s * t1 * ny};
        pb_ring(u, t, 3);
    } else { /* a quadrilateral on one side */
        double j = rr(st, -0.1, 0.1) * t2;
        double t[8] = {a[0],
                       a[1],
                       b[0],
                       b[1],
                       b[0] + s * t2 * nx + j * ux,
                       b[1] + s * t2 * ny + j * uy,
                       a[0] + s * t1 * nx,
                       a[1] + s * t1 * ny};
        pb_ring(u, t, 4);
    }
    pb_end(u);
}

#define ONEDGE_LATTICE (1.0 / 256)

/* A random lattice vector of length about [lo, hi]. */
static void lattice_vec(uint64_t *st, double lo, double hi, double *v)
{
    double a = rr(st, 0, 2 * M_PI), l = rr(st, lo, hi);
    v[0] = round(l * cos(a) / ONEDGE_LATTICE) * ONEDGE_LATTICE;
    v[1] = round(l * sin(a) / ONEDGE_LATTICE) * ONEDGE_LATTICE;
}

/* onedge: a vertex exactly at the midpoint of an earlier polygon's edge (dyadic: exact). */
static void gen_onedge(pb *u, uint64_t *st, const gctx *g)
{
    (void)g;
    if (u->np == 0 || test_rnd(st) < 0.12) {
        plain_star(u, st, ONEDGE_LATTICE);
        return;
    }
    size_t j = (size_t)ri(st, (int)u->np);
    double p[2], q[2];
    random_edge(u, st, j, p, q);
    double m[2] = {(p[0] + q[0]) / 2, (p[1] + q[1]) / 2};
    double x = test_rnd(st), a[2], c[2];
    if (x < 0.3) { /* a triangle with its apex at m, on either side or across */
        lattice_vec(st, 0.03, 0.3, a);
        lattice_vec(st, 0.03, 0.3, c);
        double t[6] = {m[0], m[1], m[0] + a[0], m[1] + a[1], m[0] + c[0], m[1] + c[1]};
        pb_ring(u, t, 3);
    } else if (x < 0.55) { /* a triangle on half the edge: m, an end, an apex off the line */
        const double *e = test_rnd(st) < 0.5 ? p : q;
        lattice_vec(st, 0.03, 0.3, a);
        double t[6] = {m[0], m[1], e[0], e[1], m[0] + a[0], m[1] + a[1]};
        pb_ring(u, t, 3);
    } else if (x < 0.75) { /* a quadrilateral from m to the midpoint of another edge */
        double p2[2], q2[2];
        random_edge(u, st, j, p2, q2);
        double m2[2] = {(p2[0] + q2[0]) / 2, (p2[1] + q2[1]) / 2};
        lattice_vec(st, 0.03, 0.2, a);
        double t[8] = {m[0],         m[1],         m2[0],       m2[1],
                       m2[0] + a[0], m2[1] + a[1], m[0] + a[0], m[1] + a[1]};
        pb_ring(u, t, 4);
    } else { /* a lattice star moved so that one of its vertices is m */
        double pts[2 * 32];
        size_t n = ring_star(pts, st, 0.5, 0.5, rr(st, 0.08, 0.15), 0.2, 4 + ri(st, 7), 0, 0);
        for (size_t i = 0; i < 2 * n; i++) pts[i] = round(pts[i] / ONEDGE_LATTICE) * ONEDGE_LATTICE;
        size_t k = (size_t)ri(st, (int)n);
        c[0] = m[0] - pts[2 * k], c[1] = m[1] - pts[2 * k + 1];
        for (size_t i = 0; i < n; i++) pts[2 * i] += c[0], pts[2 * i + 1] += c[1];
        pb_ring(u, pts, n);
    }
    pb_end(u);
}

/* shared: lattice rectangles (with holes), L shapes and triangles of a triangulated lattice. */
static void gen_shared(pb *u, uint64_t *st, const gctx *g)
{
    int k = g->cells;
    double c = 1.0 / 8, pts[16];
    double x = test_rnd(st);
    if (x < 0.45) { /* a triangle of cell (i, j), split along its diagonal */
        int i = ri(st, k), j = ri(st, k);
        double x0 = i * c, y0 = j * c, x1 = x0 + c, y1 = y0 + c;
        int d = (int)(g->diag >> ((i * 8 + j) % 64) & 1), up = test_rnd(st) < 0.5;
        double t[6];
        if (d) { /* diagonal (x0, y0) - (x1, y1) */
            double lo[6] = {x0, y0, x1, y0, x1, y1}, hi[6] = {x0, y0, x1, y1, x0, y1};
            memcpy(t, up ? hi : lo, sizeof t);
        } else { /* diagonal (x1, y0) - (x0, y1) */
            double lo[6] = {x0, y0, x1, y0, x0, y1}, hi[6] = {x1, y0, x1, y1, x0, y1};
            memcpy(t, up ? hi : lo, sizeof t);
        }
        pb_ring(u, t, 3);
    } else if (x < 0.75) { /* a lattice rectangle */
        int i = ri(st, k), j = ri(st, k), w = 1 + ri(st, 4), h = 1 + ri(st, 4);
        rect_ring(pts, i * c, j * c, (i + w) * c, (j + h) * c);
        pb_ring(u, pts, 4);
    } else if (x < 0.9) { /* a rectangle of 3..5 cells with a hole on the half lattice */
        int i = ri(st, k), j = ri(st, k), w = 3 + ri(st, 3), h = 3 + ri(st, 3);
        rect_ring(pts, i * c, j * c, (i + w) * c, (j + h) * c);
        pb_ring(u, pts, 4);
        int a = 1 + ri(st, 2 * w - 3), b = 1 + ri(st, 2 * h - 3);
        int aw = 1 + ri(st, 2 * w - 1 - a), bh = 1 + ri(st, 2 * h - 1 - b);
        rect_ring(pts, i * c + a * c / 2, j * c + b * c / 2, i * c + (a + aw) * c / 2,
                  j * c + (b + bh) * c / 2);
        pb_ring(u, pts, 4);
    } else { /* an L shape */
        int i = ri(st, k), j = ri(st, k), w = 2 + ri(st, 3), h = 2 + ri(st, 3);
        int a = 1 + ri(st, w - 1), b = 1 + ri(st, h - 1);
        double l[12] = {i * c,       j * c,       (i + w) * c, j * c,
                        (i + w) * c, (j + b) * c, (i + a) * c, (j + b) * c,
                        (i + a) * c, (j + h) * c, i * c,       (j + h) * c};
        pb_ring(u, l, 6);
    }
    pb_end(u);
}

#define HOLES_LATTICE (1.0 / 64)

static void diamond(double *pts, double cx, double cy, double d)
{
    double r[8] = {cx, cy - d, cx + d, cy, cx, cy + d, cx - d, cy};
    memcpy(pts, r, sizeof r);
}

/* holes: a lattice rectangle with structures of holes in vertical strips: a chain of diamonds
 * from the bottom or top edge (the first touches the shell, each the next), a triangle in a
 * corner of the shell, a floating pair of diamonds touching each other, a diamond touching a
 * side edge.  Or another shape over such polygons. */
static void gen_holes(pb *u, uint64_t *st, const gctx *g)
{
    const double q = HOLES_LATTICE;
    double pts[16];
    double x = test_rnd(st);
    if (u->np > 0 && x < 0.3) { /* a lattice rectangle or a star over them */
        if (test_rnd(st) < 0.6) {
            int i = ri(st, 48), j = ri(st, 48), w = 4 + ri(st, 20), h = 4 + ri(st, 20);
            rect_ring(pts, i * q, j * q, (i + w) * q, (j + h) * q);
            pb_ring(u, pts, 4);
            pb_end(u);
        } else {
            plain_star(u, st, 0);
        }
        return;
    }
    (void)g;
    int W = 24 + ri(st, 25), H = 24 + ri(st, 25), X = ri(st, 64 - W + 8), Y = ri(st, 64 - H + 8);
    rect_ring(pts, X * q, Y * q, (X + W) * q, (Y + H) * q);
    pb_ring(u, pts, 4);
    int m = 1 + ri(st, 3), sw = W / m;
    for (int s = 0; s < m; s++) {
        int s0 = X + s * sw, s1 = s0 + sw; /* the strip [s0, s1] x [Y, Y + H] */
        int kind = ri(st, 4);
        if (kind == 1 && s != 0 && s != m - 1) kind = 0;
        if (kind == 0) { /* a chain of diamonds from the bottom or the top edge */
            int d = 1 + ri(st, 3), top = test_rnd(st) < 0.5;
            if (s1 - s0 < 2 * d + 2) continue;
            int cx = s0 + d + 1 + ri(st, s1 - s0 - 2 * d - 1);
            int n = 1 + ri(st, 4);
            while (n > 1 && 2 * d * n > H - 3) n--;
            if (2 * d * n > H - 3) continue;
            for (int i = 0; i < n; i++) {
                double cy = top ? Y + H - d * (2 * i + 1) : Y + d * (2 * i + 1);
                diamond(pts, cx * q, cy * q, d * q);
                pb_ring(u, pts, 4);
            }
        } else if (kind == 1) { /* a triangle in a corner of the shell */
            int d = 1 + ri(st, 3), left = s == 0, bottom = test_rnd(st) < 0.5;
            double cx = left ? X : X + W, cy = bottom ? Y : Y + H, sx = left ? 1 : -1,
                   sy = bottom ? 1 : -1;
            double t[6] = {cx * q,
                           cy * q,
                           (cx + sx * 2 * d) * q,
                           (cy + sy * d) * q,
                           (cx + sx * d) * q,
                           (cy + sy * 2 * d) * q};
            pb_ring(u, t, 3);
        } else if (kind == 2) { /* a floating pair of diamonds touching at a vertex */
            int d = 1 + ri(st, 2);
            if (s1 - s0 < 4 * d + 2 || H < 2 * d + 4) continue;
            int cx = s0 + d + 1 + ri(st, s1 - s0 - 4 * d - 1);
            int cy = Y + d + 2 + ri(st, H - 2 * d - 3);
            diamond(pts, cx * q, cy * q, d * q);
            pb_ring(u, pts, 4);
            diamond(pts, (cx + 2 * d) * q, cy * q, d * q);
            pb_ring(u, pts, 4);
        } else { /* a diamond touching the left or right edge of the shell, or the top */
            int d = 1 + ri(st, 3), cy = Y + d + 2 + ri(st, H - 2 * d - 3 > 0 ? H - 2 * d - 3 : 1);
            if (s == 0)
                diamond(pts, (X + d) * q, cy * q, d * q);
            else if (s == m - 1)
                diamond(pts, (X + W - d) * q, cy * q, d * q);
            else if (s1 - s0 >= 2 * d + 2)
                diamond(pts, (s0 + d + 1) * q, (Y + H - d) * q, d * q);
            else
                continue;
            pb_ring(u, pts, 4);
        }
    }
    pb_end(u);
}

typedef struct family {
    const char *name;
    void (*gen)(pb *u, uint64_t *st, const gctx *g);
} family;

typedef struct frame {
    const char *name;
    double scale, off; /* unit frame -> test frame: x * scale + off */
} frame;

static const family fam_spikes = {"spikes", gen_spikes}, fam_near = {"near", gen_near},
                    fam_onedge = {"onedge", gen_onedge}, fam_shared = {"shared", gen_shared},
                    fam_holes = {"holes", gen_holes};
static const frame frm_unit = {"unit", 1, 0}, frm_far = {"far", 1, 1e6},
                   frm_tiny = {"tiny", 1.0 / 1048576, 0};

/* ---- the bookkeeping ---------------------------------------------------------------------- */

typedef struct stats {
    size_t cases, runs, geos_runs, tolerated, json_runs;
    size_t geos_failed; /* GEOS returned NULL or an invalid result, or was wrong (below) */
    size_t geos_wrong;  /* GEOS disagreed beyond the bound, and agreed once moved to the centre */
    size_t polys, redrawn, dropped; /* generated polygons, redrawn as invalid, cases cut short */
    double worst;                   /* |error| / bound against GEOS */
    char worst_what[160];
    double worst_id; /* the identities' */
    char worst_id_what[160];
    size_t results;        /* results checked */
    size_t area_sum_off;   /* results whose polygons' areas miss r.area by more than 1e-9 */
    double area_sum_worst; /* relative */
    char area_sum_what[96];
} stats;

static stats total; /* over all the families run */

/* One case being run. */
typedef struct tcase {
    const family *fam;
    const frame *frm;
    uint64_t seed;
    double precision; /* given to the core; 0: automatic */
    GEOSContextHandle_t h;
    stats *s;
    int dumped;
} tcase;

static void note_worst(double ratio, double *worst, char *what, size_t len, const tcase *c,
                       const char *op)
{
    if (!(ratio > *worst)) return;
    *worst = ratio;
    snprintf(what, len, "%s/%s, case %llu, %s", c->fam->name, c->frm->name,
             (unsigned long long)c->seed, op);
}

static void record(const tcase *c, double err, double bound, const char *op, int identity)
{
    double ratio = bound > 0 ? fabs(err) / bound : (err != 0) * INFINITY;
    if (identity) {
        note_worst(ratio, &c->s->worst_id, c->s->worst_id_what, sizeof c->s->worst_id_what, c, op);
        note_worst(ratio, &total.worst_id, total.worst_id_what, sizeof total.worst_id_what, c, op);
    } else {
        note_worst(ratio, &c->s->worst, c->s->worst_what, sizeof c->s->worst_what, c, op);
        note_worst(ratio, &total.worst, total.worst_what, sizeof total.worst_what, c, op);
    }
}

/* CELLAR_DUMP=DIR: the failing run as a request, DIR/bool2-FAMILY-FRAME-CASE-WHAT.json. */
static void dump(tcase *c, const pb *b, const char *op, const char *what)
{
    const char *dir = getenv("CELLAR_DUMP");
    if (!dir || c->dumped > 8) return;
    c->dumped++;
    char path[600];
    snprintf(path, sizeof path, "%s/bool2-%s-%s-%llu-%s.json", dir, c->fam->name, c->frm->name,
             (unsigned long long)c->seed, what);
    char *s = case_json(b, op, c->precision);
    FILE *f = s ? fopen(path, "w") : NULL;
    if (f) {
        fputs(s, f);
        fclose(f);
        printf("  dumped %s\n", path);
    }
    free(s);
}

/* ---- ours ----------------------------------------------------------------------------------- */

/* Runs op on b; 1 with *r filled, 0 when the run failed (a test failure, or a tolerated "labels
 * inconsistent" refusal, counted). */
static int ours(tcase *c, const pb *b, const char *op, const char *what, bool2_result *r)
{
    bool_expr e;
    char err[256] = "";
    bool2_input in = pb_input(b);
    memset(r, 0, sizeof *r);
    if (bool_expr_named(op, b->np, &e) || bool_expr_check(&e, b->np)) {
        test_fail(__FILE__, __func__, __LINE__, "%s: no expression", op);
        return 0;
    }
    arr2_opts o = {.threads = 1, .precision = c->precision};
    int rc = bool2_build(&in, &e, &o, r, err, sizeof err);
    bool_expr_free(&e);
    c->s->runs++;
    if (rc == ARR_OK) return 1;
    if ((rc == ARR_EINVAL || rc == ARR_ELIMIT) && strstr(err, TOLERATED_MSG)) {
        c->s->tolerated++;
        printf("  tolerated: %s/%s case %llu %s: %s\n", c->fam->name, c->frm->name,
               (unsigned long long)c->seed, what, err);
        return 0;
    }
    test_fail(__FILE__, __func__, __LINE__, "%s/%s case %llu %s (%s, %zu polygons): code %d: %s",
              c->fam->name, c->frm->name, (unsigned long long)c->seed, what, op, b->np, rc, err);
    dump(c, b, op, what);
    return 0;
}

/* Signed area of result cycle k from its coordinates (about its first vertex). */
static double cycle_area(const bool2_result *r, uint32_t k)
{
    uint32_t a = r->region.rc_off[k], n = r->region.rc_off[k + 1] - a;
    const double *o = r->c.V + 2 * r->region.rv[a];
    double s = 0;
    for (uint32_t i = 1; i + 1 < n; i++) {
        const double *p = r->c.V + 2 * r->region.rv[a + i],
                     *q = r->c.V + 2 * r->region.rv[a + i + 1];
        s += (p[0] - o[0]) * (q[1] - o[1]) - (q[0] - o[0]) * (p[1] - o[1]);
    }
    return s / 2;
}

static GEOSGeometry *geos_cycle(GEOSContextHandle_t h, const bool2_result *r, uint32_t k)
{
    uint32_t a = r->region.rc_off[k], n = r->region.rc_off[k + 1] - a;
    GEOSCoordSequence *cs = GEOSCoordSeq_create_r(h, n + 1, 2);
    for (uint32_t i = 0; i <= n; i++) {
        const double *p = r->c.V + 2 * r->region.rv[a + i % n];
        GEOSCoordSeq_setXY_r(h, cs, i, p[0], p[1]);
    }
    return GEOSGeom_createLinearRing_r(h, cs);
}

/* The result's polygons must be valid alone and together, shells CCW and holes CW, and their
 * areas must add up to r->area. */
static void check_polygons(tcase *c, const pb *b, const char *op, const char *what,
                           const bool2_result *r)
{
    GEOSContextHandle_t h = c->h;
    size_t nh = r->region.npoly ? r->region.ph_off[r->region.npoly] : 0;
    int bad = 0;
    c->s->results++;
    if (r->region.npoly + nh != r->region.nrcyc) {
        test_fail(__FILE__, __func__, __LINE__,
                  "%s/%s case %llu %s: %zu polygons + %zu holes != %zu cycles", c->fam->name,
                  c->frm->name, (unsigned long long)c->seed, what, r->region.npoly, nh,
                  r->region.nrcyc);
        bad = 1;
    }
    GEOSGeometry **polys = malloc((r->region.npoly + 1) * sizeof *polys);
    GEOSGeometry **holes = malloc((nh + 1) * sizeof *holes);
    double sum = 0, scale = fabs(r->area);
    for (size_t q = 0; q < r->region.npoly; q++) {
        uint32_t k = r->region.poly_outer[q];
        double a = cycle_area(r, k);
        sum += a, scale += fabs(a);
        if (!(a > 0) && !bad) {
            test_fail(__FILE__, __func__, __LINE__,
                      "%s/%s case %llu %s: shell of polygon %zu not counter-clockwise (%.17g)",
                      c->fam->name, c->frm->name, (unsigned long long)c->seed, what, q, a);
            bad = 1;
        }
        uint32_t h0 = r->region.ph_off[q], h1 = r->region.ph_off[q + 1];
        for (uint32_t i = h0; i < h1; i++) {
            double ha = cycle_area(r, r->region.ph_cyc[i]);
            sum += ha, scale += fabs(ha);
            if (!(ha < 0) && !bad) {
                test_fail(__FILE__, __func__, __LINE__,
                          "%s/%s case %llu %s: hole %u of polygon %zu not clockwise (%.17g)",
                          c->fam->name, c->frm->name, (unsigned long long)c->seed, what, i - h0, q,
                          ha);
                bad = 1;
            }
            holes[i - h0] = geos_cycle(h, r, r->region.ph_cyc[i]);
        }
        polys[q] = GEOSGeom_createPolygon_r(h, geos_cycle(h, r, k), holes, h1 - h0);
        if (!bad && GEOSisValid_r(h, polys[q]) != 1) {
            char *why = GEOSisValidReason_r(h, polys[q]);
            test_fail(__FILE__, __func__, __LINE__,
                      "%s/%s case %llu %s: result polygon %zu (of %zu, %u holes) is invalid: %s",
                      c->fam->name, c->frm->name, (unsigned long long)c->seed, what, q,
                      r->region.npoly, h1 - h0, why ? why : "?");
            GEOSFree_r(h, why);
            bad = 1;
        }
    }
    /* the areas: within the snapping bound always (the coordinates of vertices that input
     * points snapped to are the input's, r.area is the grid's), within 1e-9 as asked */
    double apart = fabs(sum - r->area), bound = area_bound(b, r->c.stats.precision);
    if (!bad && !(apart <= bound)) {
        test_fail(__FILE__, __func__, __LINE__,
                  "%s/%s case %llu %s: the polygons' areas add up to %.17g, r.area %.17g: %.3g "
                  "apart, beyond the bound %.3g",
                  c->fam->name, c->frm->name, (unsigned long long)c->seed, what, sum, r->area,
                  apart, bound);
        bad = 1;
    }
    if (!(apart <= 1e-9 * scale)) {
        stats *st = c->s;
        if (st->area_sum_off++ < 3)
            printf("  %s/%s case %llu %s: the polygons' areas add up to %.17g, r.area %.17g "
                   "(%.3g relative)\n",
                   c->fam->name, c->frm->name, (unsigned long long)c->seed, what, sum, r->area,
                   apart / scale);
        if (apart / scale > st->area_sum_worst) {
            st->area_sum_worst = apart / scale;
            snprintf(st->area_sum_what, sizeof st->area_sum_what, "case %llu %s",
                     (unsigned long long)c->seed, what);
            char tag[64];
            snprintf(tag, sizeof tag, "areasum-%s", what);
            dump(c, b, op, tag);
        }
    }
    GEOSGeometry *mp =
        GEOSGeom_createCollection_r(h, GEOS_MULTIPOLYGON, polys, (unsigned)r->region.npoly);
    if (!bad && GEOSisValid_r(h, mp) != 1) {
        char *why = GEOSisValidReason_r(h, mp);
        test_fail(__FILE__, __func__, __LINE__,
                  "%s/%s case %llu %s: the MultiPolygon of the %zu result polygons is invalid: %s",
                  c->fam->name, c->frm->name, (unsigned long long)c->seed, what, r->region.npoly,
                  why ? why : "?");
        GEOSFree_r(h, why);
        bad = 1;
    }
    GEOSGeom_destroy_r(h, mp);
    free(polys);
    free(holes);
    if (bad) dump(c, b, op, what);
}

/* ---- GEOS ----------------------------------------------------------------------------------- */

/* GEOS's errors and notices: silent (a NULL result is what counts). */
static void geos_message(const char *msg, void *udata)
{
    (void)msg;
    (void)udata;
}

static GEOSGeometry *geos_poly(GEOSContextHandle_t h, const pb *b, size_t p)
{
    return geos_ref_polygon(h, b->poly_off, b->ring_off, b->xy, p);
}

/* The union of polygons [p0, p1) of b by GEOSUnaryUnion_r; NULL when GEOS fails. */
static GEOSGeometry *geos_unary_union(GEOSContextHandle_t h, const pb *b, size_t p0, size_t p1)
{
    GEOSGeometry *g[PB_MAXP];
    for (size_t p = p0; p < p1; p++) g[p - p0] = geos_poly(h, b, p);
    GEOSGeometry *col = GEOSGeom_createCollection_r(h, GEOS_MULTIPOLYGON, g, (unsigned)(p1 - p0));
    GEOSGeometry *u = col ? GEOSUnaryUnion_r(h, col) : NULL;
    GEOSGeom_destroy_r(h, col);
    return u;
}

/* GEOS's area of op over b's polygons ("union": pairwise, "unary": GEOSUnaryUnion_r of all,
 * "difference": the first minus the unary union of the rest), or -1 when GEOS fails: NULL, an
 * invalid result. */
static double geos_area(GEOSContextHandle_t h, const pb *b, const char *op)
{
    GEOSGeometry *acc = NULL;
    if (!strcmp(op, "unary")) {
        acc = geos_unary_union(h, b, 0, b->np);
    } else if (!strcmp(op, "difference")) {
        GEOSGeometry *first = geos_poly(h, b, 0);
        GEOSGeometry *rest = b->np > 1 ? geos_unary_union(h, b, 1, b->np) : NULL;
        acc = b->np == 1 ? first : rest ? GEOSDifference_r(h, first, rest) : NULL;
        if (b->np > 1) GEOSGeom_destroy_r(h, first);
        if (rest) GEOSGeom_destroy_r(h, rest);
    } else {
        acc = geos_poly(h, b, 0);
        for (size_t p = 1; p < b->np && acc; p++) {
            acc = geos_ref_fold(h, op, acc, geos_poly(h, b, p));
        }
    }
    double a = -1;
    if (acc && GEOSisValid_r(h, acc) == 1 && GEOSArea_r(h, acc, &a) != 1) a = -1;
    if (acc) GEOSGeom_destroy_r(h, acc);
    return a;
}

/* The same with b moved by about minus the centre of its box (a multiple of a power of two near
 * its extent, so that the move rounds little); -1 when GEOS fails. */
static double geos_area_centred(GEOSContextHandle_t h, const pb *b, const char *op)
{
    static pb moved;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t i = 0; i < b->npt; i++)
        for (int k = 0; k < 2; k++) {
            lo[k] = fmin(lo[k], b->xy[2 * i + k]);
            hi[k] = fmax(hi[k], b->xy[2 * i + k]);
        }
    double ext = fmax(hi[0] - lo[0], hi[1] - lo[1]), q = ext > 0 ? ldexp(1.0, ilogb(ext)) : 1;
    double tx = nearbyint((lo[0] + hi[0]) / 2 / q) * q, ty = nearbyint((lo[1] + hi[1]) / 2 / q) * q;
    pb_truncate(&moved, 0);
    for (size_t p = 0; p < b->np; p++) pb_copy_poly(&moved, b, p, 1, -tx, -ty);
    return geos_area(h, &moved, op);
}

/* ---- one run: ours, its checks, GEOS -------------------------------------------------------- */

typedef struct outcome {
    int ok;      /* ours ran */
    double area; /* ours */
    double step; /* the grid step used */
    double bound;
    size_t npoly;
} outcome;

/* Runs op ("unary": union) on b, checks the result, compares with GEOS. */
static outcome run_op(tcase *c, const pb *b, const char *op, const char *what)
{
    outcome o = {0};
    bool2_result r;
    const char *cop = strcmp(op, "unary") ? op : "union";
    if (!ours(c, b, cop, what, &r)) return o;
    o.ok = 1;
    o.area = r.area;
    o.step = r.c.stats.precision;
    o.bound = area_bound(b, o.step);
    o.npoly = r.region.npoly;
    check_polygons(c, b, cop, what, &r);
    bool2_free(&r);
    c->s->geos_runs++;
    double g = geos_area(c->h, b, op);
    if (g < 0) {
        c->s->geos_failed++;
        return o;
    }
    /* GEOS again, about the inputs' centre, when the first answer is off by more than a quarter
     * of the bound: far from the origin GEOS's own rounding (and its snapping fallbacks) can
     * cost more than our grid does, while moving the inputs costs at most an ulp per coordinate
     * (the 8 ulp of the bound).  The answer closer to ours is the reference; when only the moved
     * one is within the bound, it was GEOS that was wrong: counted as a GEOS failure, printed
     * and dumped.  Beyond the bound of both, the disagreement is ours. */
    double ref = g;
    if (!(fabs(o.area - g) <= o.bound / 4)) {
        double g2 = geos_area_centred(c->h, b, op);
        if (g2 >= 0 && fabs(o.area - g2) < fabs(o.area - g)) {
            ref = g2;
            if (!(fabs(o.area - g) <= o.bound) && fabs(o.area - g2) <= o.bound) {
                c->s->geos_failed++, c->s->geos_wrong++;
                printf("  GEOS wrong: %s/%s case %llu %s (%s, %zu polygons): GEOS %.17g, about "
                       "the centre %.17g, ours %.17g, bound %.3g\n",
                       c->fam->name, c->frm->name, (unsigned long long)c->seed, what, op, b->np, g,
                       g2, o.area, o.bound);
                char tag[64];
                snprintf(tag, sizeof tag, "geoswrong-%s", what);
                dump(c, b, cop, tag);
            }
        }
    }
    double err = o.area - ref;
    record(c, err, o.bound, what, 0);
    if (!(fabs(err) <= o.bound)) {
        test_fail(__FILE__, __func__, __LINE__,
                  "%s/%s case %llu %s (%s, %zu polygons): area %.17g, GEOS %.17g (%.17g about the "
                  "centre): |error| %.3g > bound %.3g (%.3g times)",
                  c->fam->name, c->frm->name, (unsigned long long)c->seed, what, op, b->np, o.area,
                  g, ref, fabs(err), o.bound, fabs(err) / o.bound);
        dump(c, b, cop, what);
    }
    return o;
}

/* The same run through the request path: status 200, the same area and polygon count. */
static void run_json(tcase *c, const pb *b, const char *op, const outcome *direct)
{
    char *body = case_json(b, op, c->precision), *out = NULL;
    size_t outlen;
    api_error err = {0};
    if (!body) {
        test_fail(__FILE__, __func__, __LINE__, "out of memory for a request");
        return;
    }
    c->s->json_runs++;
    int rc = api_run_json(body, strlen(body), 1, &out, &outlen, &err);
    if (rc == API_EINVALID && strstr(err.msg, TOLERATED_MSG)) {
        c->s->tolerated++;
        printf("  tolerated (JSON): %s/%s case %llu %s: %s\n", c->fam->name, c->frm->name,
               (unsigned long long)c->seed, op, err.msg);
    } else if (rc != API_OK) {
        test_fail(__FILE__, __func__, __LINE__, "%s/%s case %llu %s through JSON: status %d: %s",
                  c->fam->name, c->frm->name, (unsigned long long)c->seed, op, rc, err.msg);
        dump(c, b, op, "json");
    } else if (direct->ok) {
        json_t *res = json_loads(out, 0, NULL);
        json_t *result = json_object_get(res, "result");
        double a = json_number_value(json_object_get(result, "area"));
        size_t np = json_array_size(json_object_get(result, "FV"));
        if (a != direct->area || np != direct->npoly) {
            test_fail(__FILE__, __func__, __LINE__,
                      "%s/%s case %llu %s through JSON: area %.17g and %zu polygons, directly "
                      "%.17g and %zu",
                      c->fam->name, c->frm->name, (unsigned long long)c->seed, op, a, np,
                      direct->area, direct->npoly);
            dump(c, b, op, "json");
        }
        json_decref(res);
    }
    free(out);
    free(body);
}

/* ---- cases ---------------------------------------------------------------------------------- */

/* Adds n polygons of the family to b (test frame; u holds them in the unit frame), each valid
 * by GEOS (drawn again when not, up to 30 times).  Returns the number added. */
static size_t generate(tcase *c, pb *u, pb *b, uint64_t *st, const gctx *g, size_t n)
{
    double s = c->frm->scale, off = c->frm->off;
    for (size_t k = 0; k < n; k++) {
        int ok = 0;
        for (int t = 0; t < 30 && !ok; t++) {
            size_t np = u->np;
            c->s->polys++;
            c->fam->gen(u, st, g);
            if (u->np == np + 1 && !u->full) {
                pb_copy_poly(b, u, np, s, off, off);
                if (b->np == np + 1 && !b->full) {
                    GEOSGeometry *p = geos_poly(c->h, b, np);
                    ok = p && GEOSisValid_r(c->h, p) == 1;
                    if (p) GEOSGeom_destroy_r(c->h, p);
                }
            }
            if (!ok) {
                c->s->redrawn++;
                pb_truncate(u, np);
                pb_truncate(b, np);
            }
        }
        if (!ok) break;
    }
    return b->np;
}

/* The polygons [p0, p1) of src as a new input. */
static void pb_sub(pb *dst, const pb *src, size_t p0, size_t p1)
{
    pb_truncate(dst, 0);
    for (size_t p = p0; p < p1; p++) pb_copy_poly(dst, src, p, 1, 0, 0);
}

/* An identity between areas of A and B (pair: the two polygons, dumped as their union). */
static void identity(tcase *c, const pb *pair, const char *name, double lhs, double rhs,
                     double bound)
{
    record(c, lhs - rhs, bound, name, 1);
    if (!(fabs(lhs - rhs) <= bound)) {
        test_fail(__FILE__, __func__, __LINE__,
                  "%s/%s case %llu: %s: %.17g vs %.17g: |difference| %.3g > bound %.3g",
                  c->fam->name, c->frm->name, (unsigned long long)c->seed, name, lhs, rhs,
                  fabs(lhs - rhs), bound);
        dump(c, pair, "union", "identity");
    }
}

typedef struct bufs {
    pb u, b, pair, one, um, bm;
} bufs;

static void run_case(tcase *c, bufs *w)
{
    static const char *const ops[4] = {"union", "intersection", "difference", "xor"};
    uint64_t st = 1469598103934665603ull; /* FNV-1a of "family/frame", then the case */
    for (const char *n = c->fam->name; *n; n++) st = (st ^ (unsigned char)*n) * 1099511628211ull;
    for (const char *n = c->frm->name; *n; n++) st = (st ^ (unsigned char)*n) * 1099511628211ull;
    st ^= (c->seed + 1) * 0x9e3779b97f4a7c15ull;
    gctx g = {.h = UNIT_STEP, .cells = 4 + ri(&st, 5), .diag = (uint64_t)(test_rnd(&st) * 0x1p53)};
    c->precision = ri(&st, 8) == 0 ? 0 : UNIT_STEP * c->frm->scale;
    c->s->cases++;

    /* all the polygons: the four operations */
    pb_truncate(&w->u, 0);
    pb_truncate(&w->b, 0);
    size_t want = 2 + (size_t)ri(&st, 4);
    if (generate(c, &w->u, &w->b, &st, &g, want) < want) {
        c->s->dropped++;
        if (w->b.np < 2) return;
    }
    outcome all[4];
    for (int k = 0; k < 4; k++) {
        char what[32];
        snprintf(what, sizeof what, "%s-all", ops[k]);
        all[k] = run_op(c, &w->b, ops[k], what);
    }
    int json_op = ri(&st, 4);
    if (c->seed % 8 == 3) run_json(c, &w->b, ops[json_op], &all[json_op]);

    /* A and B: the four operations, each alone, the identities */
    outcome pair[4], a, b;
    if (w->b.np == 2) {
        memcpy(pair, all, sizeof pair);
    } else {
        pb_sub(&w->pair, &w->b, 0, 2);
        for (int k = 0; k < 4; k++) {
            char what[32];
            snprintf(what, sizeof what, "%s-AB", ops[k]);
            pair[k] = run_op(c, &w->pair, ops[k], what);
        }
    }
    pb_sub(&w->one, &w->b, 0, 1);
    a = run_op(c, &w->one, "union", "A");
    double bound_a = a.bound;
    pb_sub(&w->one, &w->b, 1, 2);
    b = run_op(c, &w->one, "union", "B");
    if (a.ok && b.ok && pair[0].ok && pair[1].ok && pair[2].ok && pair[3].ok) {
        double step = fmax(fmax(a.step, b.step), pair[0].step);
        pb_sub(&w->pair, &w->b, 0, 2);
        double bound = fmax(area_bound(&w->pair, step), bound_a);
        identity(c, &w->pair, "|A| = |A & B| + |A - B|", a.area, pair[1].area + pair[2].area,
                 bound);
        identity(c, &w->pair, "|A + B| = |A| + |B| - |A & B|", pair[0].area,
                 a.area + b.area - pair[1].area, bound);
        identity(c, &w->pair, "|A ^ B| = |A + B| - |A & B|", pair[3].area,
                 pair[0].area - pair[1].area, bound);
    }

    /* the union of many */
    pb_truncate(&w->um, 0);
    pb_truncate(&w->bm, 0);
    size_t many = 8 + (size_t)ri(&st, 23);
    if (generate(c, &w->um, &w->bm, &st, &g, many) < many) c->s->dropped++;
    if (w->bm.np >= 2) {
        outcome m = run_op(c, &w->bm, "unary", "unary-union");
        if (c->seed % 8 == 5) run_json(c, &w->bm, "union", &m);
    }
}

static int env_int(const char *name)
{
    const char *e = getenv(name);
    return e ? atoi(e) : 0;
}

static void run_family(const family *f, const frame *fr)
{
    static bufs w; /* big: not on the stack */
    stats s = {0};
    int per_seed = getenv("CELLAR_SANITIZED") ? CASES_PER_SEED / 10 : CASES_PER_SEED;
    int seeds = env_int("CELLAR_STRESS") > 0 ? env_int("CELLAR_STRESS") : 1;
    GEOSContextHandle_t h = GEOS_init_r();
    GEOSContext_setErrorMessageHandler_r(h, geos_message, NULL);
    GEOSContext_setNoticeMessageHandler_r(h, geos_message, NULL);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (uint64_t seed = 0; seed < (uint64_t)seeds * (uint64_t)per_seed; seed++) {
        tcase c = {.fam = f, .frm = fr, .seed = seed, .h = h, .s = &s};
        run_case(&c, &w);
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    GEOS_finish_r(h);
    double secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    printf("  %s/%s: %zu cases, %zu runs (%zu through JSON), %.1f s; GEOS failed %zu (wrong %zu) "
           "of %zu; "
           "tolerated %zu; inputs redrawn %zu of %zu, cases short %zu\n",
           f->name, fr->name, s.cases, s.runs, s.json_runs, secs, s.geos_failed, s.geos_wrong,
           s.geos_runs, s.tolerated, s.redrawn, s.polys, s.dropped);
    printf("  %s/%s: worst area error / bound: %.4g (%s); identities: %.4g (%s)\n", f->name,
           fr->name, s.worst, s.worst_what[0] ? s.worst_what : "-", s.worst_id,
           s.worst_id_what[0] ? s.worst_id_what : "-");
    CHECK(s.area_sum_off == 0,
          "%s/%s: %zu of %zu results: the polygons' areas (from their coordinates) miss r.area by "
          "more than 1e-9 relative, at worst %.3g (%s)",
          f->name, fr->name, s.area_sum_off, s.results, s.area_sum_worst, s.area_sum_what);
    CHECK(s.redrawn <= s.polys / 10, "%s/%s: %zu of %zu generated polygons invalid", f->name,
          fr->name, s.redrawn, s.polys);
    CHECK(s.dropped <= s.cases / 50 + 1, "%s/%s: %zu of %zu cases cut short", f->name, fr->name,
          s.dropped, s.cases);
    CHECK(s.geos_failed <= s.geos_runs / 5, "%s/%s: GEOS failed on %zu of %zu runs", f->name,
          fr->name, s.geos_failed, s.geos_runs);
    total.cases += s.cases, total.runs += s.runs, total.geos_runs += s.geos_runs;
    total.geos_failed += s.geos_failed, total.geos_wrong += s.geos_wrong;
    total.tolerated += s.tolerated;
    total.json_runs += s.json_runs, total.polys += s.polys, total.redrawn += s.redrawn;
    total.results += s.results, total.area_sum_off += s.area_sum_off;
}

#define FAMILY_TEST(f, fr)                                                                         \
    TEST(bool2_geos_##f##_##fr)                                                                    \
    {                                                                                              \
        run_family(&fam_##f, &frm_##fr);                                                           \
    }

FAMILY_TEST(spikes, unit)
FAMILY_TEST(spikes, far)
FAMILY_TEST(spikes, tiny)
FAMILY_TEST(near, unit)
FAMILY_TEST(near, far)
FAMILY_TEST(near, tiny)
FAMILY_TEST(onedge, unit)
FAMILY_TEST(onedge, far)
FAMILY_TEST(onedge, tiny)
FAMILY_TEST(shared, unit)
FAMILY_TEST(shared, far)
FAMILY_TEST(shared, tiny)
FAMILY_TEST(holes, unit)
FAMILY_TEST(holes, far)
FAMILY_TEST(holes, tiny)

/* Last: the totals over the families run. */
TEST(bool2_geos_summary)
{
    printf("  all: %zu cases, %zu runs (%zu through JSON); GEOS failed %zu (wrong %zu) of %zu; "
           "tolerated %zu; inputs redrawn %zu of %zu\n",
           total.cases, total.runs, total.json_runs, total.geos_failed, total.geos_wrong,
           total.geos_runs, total.tolerated, total.redrawn, total.polys);
    printf("  results whose polygons' areas miss r.area by more than 1e-9 relative: %zu of %zu\n",
           total.area_sum_off, total.results);
    printf("worst area error / bound: %.4g (%s)\n", total.worst,
           total.worst_what[0] ? total.worst_what : "-");
    printf("worst identity error / bound: %.4g (%s)\n", total.worst_id,
           total.worst_id_what[0] ? total.worst_id_what : "-");
}
