/* test_bool2.c — 2D Booleans (core/bool2.h, kind "polygons"): hand-made cases with known areas
 * and boundaries, the seeds' bool2 test03 (two complexes combined through the arrangement of
 * their boundaries), expression trees, a differential test against GEOS (GEOSUnion,
 * GEOSIntersection, GEOSDifference, GEOSSymDifference areas to 1e-9 relative on random star
 * polygons with holes and random rectangles), and the request's error paths. */
#define GEOS_USE_ONLY_R_API
#include <geos_c.h>
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "api/api.h"
#include "core/bool2.h"
#include "core/boolexpr.h"
#include "tests/check.h"
#include "tests/ref/geos_ref.h"

/* ---- building inputs ------------------------------------------------------------------------ */

#define PB_MAXP  64
#define PB_MAXR  256
#define PB_MAXPT 8192

typedef struct pb {
    uint32_t poly_off[PB_MAXP + 1], ring_off[PB_MAXR + 1];
    double xy[2 * PB_MAXPT];
    size_t np, nr, npt;
} pb;

static void pb_ring(pb *b, const double *pts, size_t n)
{
    memcpy(b->xy + 2 * b->npt, pts, 2 * n * sizeof *pts);
    b->npt += n;
    b->ring_off[++b->nr] = (uint32_t)b->npt;
}

static void pb_end(pb *b)
{
    b->poly_off[++b->np] = (uint32_t)b->nr;
}

static void pb_rect(pb *b, double x0, double y0, double x1, double y1)
{
    double r[8] = {x0, y0, x1, y0, x1, y1, x0, y1};
    pb_ring(b, r, 4);
}

static bool2_input pb_input(const pb *b, int fill)
{
    return (bool2_input){b->np, b->poly_off, b->ring_off, b->xy, fill, 0};
}

/* Runs a named operation under a fill rule; returns the status, result in *r. */
static int run_fill(const pb *b, const char *name, int fill, bool2_result *r)
{
    bool_expr e;
    char err[256];
    bool2_input in = pb_input(b, fill);
    if (bool_expr_named(name, b->np, &e) || bool_expr_check(&e, b->np)) return -1;
    int rc = bool2_build(&in, &e, &(arr2_opts){.threads = 1}, r, err, sizeof err);
    if (rc) fprintf(stderr, "bool2_build: %s\n", err);
    bool_expr_free(&e);
    return rc;
}

static int run_named(const pb *b, const char *name, bool2_result *r)
{
    return run_fill(b, name, BOOL2_FILL_ODD, r);
}

/* The result's invariants: cycles closed and consistent with EV, outer cycles CCW and holes
 * CW, the sum of their signed areas is the area of the selected faces. */
static void check_result(const char *what, const bool2_result *r)
{
    double sum = 0;
    for (size_t k = 0; k < r->region.nrcyc; k++) {
        uint32_t a = r->region.rc_off[k], n = r->region.rc_off[k + 1] - a;
        double s = 0;
        for (uint32_t i = 0; i < n; i++) {
            uint32_t v = r->region.rv[a + i], w = r->region.rv[a + (i + 1) % n];
            int32_t se = r->region.re[a + i];
            uint32_t e = (uint32_t)abs(se) - 1;
            uint32_t v0 = r->c.EV[2 * e], v1 = r->c.EV[2 * e + 1];
            CHECK((se > 0 && v0 == v && v1 == w) || (se < 0 && v1 == v && v0 == w),
                  "%s: cycle %zu step %u: edge %d does not join %u-%u", what, k, i, se, v, w);
            const double *p = r->c.V + 2 * v, *q = r->c.V + 2 * w;
            s += p[0] * q[1] - p[1] * q[0];
        }
        sum += s / 2;
    }
    for (size_t q = 0; q < r->region.npoly; q++) {
        uint32_t k = r->region.poly_outer[q], a = r->region.rc_off[k],
                 n = r->region.rc_off[k + 1] - a;
        double s = 0;
        for (uint32_t i = 0; i < n; i++) {
            const double *p = r->c.V + 2 * r->region.rv[a + i],
                         *w = r->c.V + 2 * r->region.rv[a + (i + 1) % n];
            s += p[0] * w[1] - p[1] * w[0];
        }
        CHECK(s > 0, "%s: outer cycle %u is not counter-clockwise", what, k);
    }
    CHECK(fabs(sum - r->area) <= 1e-9 * fmax(1, fabs(r->area)),
          "%s: cycles bound %.17g, selected faces %.17g", what, sum, r->area);
    size_t nh = r->region.npoly ? r->region.ph_off[r->region.npoly] : 0;
    CHECK(r->region.npoly + nh == r->region.nrcyc, "%s: %zu polygons + %zu holes != %zu cycles",
          what, r->region.npoly, nh, r->region.nrcyc);
}

static size_t boundary_edges(const bool2_result *r)
{
    return r->region.nrcyc ? r->region.rc_off[r->region.nrcyc] : 0;
}

/* ---- hand-made cases ------------------------------------------------------------------------ */

TEST(bool2_two_squares)
{
    pb b = {0};
    pb_rect(&b, 0, 0, 2, 2);
    pb_end(&b);
    pb_rect(&b, 1, 1, 3, 3);
    pb_end(&b);
    struct {
        const char *op;
        double area;
        size_t edges, polys;
    } want[] = {
        {"union", 7, 8, 1}, {"intersection", 1, 4, 1}, {"difference", 3, 6, 1}, {"xor", 6, 12, 2}};
    for (size_t t = 0; t < 4; t++) {
        bool2_result r;
        REQUIRE(run_named(&b, want[t].op, &r) == ARR_OK, "%s failed", want[t].op);
        CHECK(r.c.nf == 3, "%s: %zu faces", want[t].op, r.c.nf);
        CHECK(fabs(r.area - want[t].area) < 1e-12, "%s: area %g, want %g", want[t].op, r.area,
              want[t].area);
        CHECK(boundary_edges(&r) == want[t].edges, "%s: %zu boundary edges, want %zu", want[t].op,
              boundary_edges(&r), want[t].edges);
        CHECK(r.region.npoly == want[t].polys, "%s: %zu polygons, want %zu", want[t].op,
              r.region.npoly, want[t].polys);
        check_result(want[t].op, &r);
        /* membership: every face in one or both inputs, one face in both, rows ascending */
        size_t both = 0;
        for (size_t f = 0; f < r.c.nf; f++) {
            uint32_t k = r.mem_off[f + 1] - r.mem_off[f];
            const uint32_t *row = r.mem + r.mem_off[f];
            CHECK(k == 1 || (k == 2 && row[0] == 0 && row[1] == 1), "%s: face %zu in %u inputs",
                  want[t].op, f, k);
            both += k == 2;
        }
        CHECK(both == 1, "%s: %zu faces in both inputs", want[t].op, both);
        CHECK(r.mem_off[r.c.nf + 1] == r.mem_off[r.c.nf], "%s: the unbounded face in an input",
              want[t].op);
        bool2_free(&r);
    }
}

/* Fill rules: polygon 0 two squares overlapping in a unit square (winding 2 there), polygon 1 a
 * unit square turning clockwise (winding -1). */
TEST(bool2_fill_rules)
{
    pb b = {0};
    pb_rect(&b, 0, 0, 2, 2);
    pb_rect(&b, 1, 1, 3, 3);
    pb_end(&b);
    double cw[8] = {4, 0, 4, 1, 5, 1, 5, 0};
    pb_ring(&b, cw, 4);
    pb_end(&b);
    static const int fills[] = {BOOL2_FILL_ODD, BOOL2_FILL_NONZERO, BOOL2_FILL_POSITIVE};
    static const double area[] = {7, 8, 7};
    for (int t = 0; t < 3; t++) {
        bool2_result r;
        REQUIRE(run_fill(&b, "union", fills[t], &r) == ARR_OK, "fill %d failed", fills[t]);
        CHECK(fabs(r.area - area[t]) < 1e-12, "fill %d: area %g, want %g", fills[t], r.area,
              area[t]);
        CHECK((r.memw != NULL) == (t > 0), "fill %d: winding numbers %s", fills[t],
              r.memw ? "given" : "not given");
        int two = 0, minus = 0;
        for (size_t f = 0; f < r.c.nf; f++)
            for (uint32_t k = r.mem_off[f]; k < r.mem_off[f + 1]; k++) {
                int32_t w = r.memw ? r.memw[k] : 1;
                two += r.mem[k] == 0 && w == 2;
                minus += r.mem[k] == 1 && w == -1;
                CHECK(w != 0, "fill %d: face %zu lists polygon %u with winding 0", fills[t], f,
                      r.mem[k]);
            }
        CHECK(two == (t > 0) && minus == (t > 0), "fill %d: %d faces winding 2, %d winding -1",
              fills[t], two, minus);
        check_result("fill", &r);
        bool2_free(&r);
    }
}

TEST(bool2_square_with_hole_minus_square)
{
    pb b = {0};
    pb_rect(&b, 0, 0, 10, 10);
    pb_rect(&b, 3, 3, 7, 7); /* the hole; same orientation as the outer ring: free */
    pb_end(&b);
    pb_rect(&b, 5, -1, 11, 5);
    pb_end(&b);
    bool2_result r;
    REQUIRE(run_named(&b, "difference", &r) == ARR_OK, "difference failed");
    /* 100 - 16 = 84; minus the square [5,10]x[0,5] (25) plus its part in the hole [5,7]x[3,5]
     * (4): 84 - 21 = 63 */
    CHECK(fabs(r.area - 63) < 1e-12, "area %g, want 63", r.area);
    CHECK(r.region.npoly == 1 && r.region.ph_off[1] == 0, "%zu polygons, %u holes", r.region.npoly,
          r.region.npoly ? r.region.ph_off[1] : 0);
    check_result("hole minus square", &r);
    bool2_free(&r);
    REQUIRE(run_named(&b, "union", &r) == ARR_OK, "union failed");
    CHECK(fabs(r.area - (100 - 12 + 11)) < 1e-12, "union area %g, want 99", r.area);
    check_result("hole union square", &r);
    bool2_free(&r);
    /* the ring with a hole alone: one polygon with one hole */
    pb one = {0};
    pb_rect(&one, 0, 0, 10, 10);
    pb_rect(&one, 3, 3, 7, 7);
    pb_end(&one);
    REQUIRE(run_named(&one, "union", &r) == ARR_OK, "single failed");
    CHECK(r.region.npoly == 1 && r.region.ph_off[1] == 1 && fabs(r.area - 84) < 1e-12,
          "%zu polygons, %u holes, area %g", r.region.npoly,
          r.region.npoly ? r.region.ph_off[1] : 0, r.area);
    check_result("square with hole", &r);
    bool2_free(&r);
}

TEST(bool2_self_difference_is_empty)
{
    pb b = {0};
    double tri[6] = {0, 0, 4, 1, 1, 3};
    pb_ring(&b, tri, 3);
    pb_end(&b);
    pb_ring(&b, tri, 3);
    pb_end(&b);
    bool2_result r;
    REQUIRE(run_named(&b, "difference", &r) == ARR_OK, "difference failed");
    CHECK(r.ncells == 0 && r.area == 0 && r.region.nrcyc == 0 && r.region.npoly == 0,
          "%zu cells, area %g, %zu cycles", r.ncells, r.area, r.region.nrcyc);
    bool2_free(&r);
    REQUIRE(run_named(&b, "intersection", &r) == ARR_OK, "intersection failed");
    CHECK(r.ncells == 1 && fabs(r.area - 5.5) < 1e-12 && boundary_edges(&r) == 3,
          "%zu cells, area %g", r.ncells, r.area);
    bool2_free(&r);
}

TEST(bool2_touching_squares)
{
    /* sharing the edge x = 1: the union is one rectangle whose boundary has 6 edges (the
     * arrangement keeps the vertices (1,0) and (1,1)), the shared edge is not on it */
    pb b = {0};
    pb_rect(&b, 0, 0, 1, 1);
    pb_end(&b);
    double ccw[8] = {1, 1, 2, 1, 2, 0, 1, 0}; /* clockwise input: orientation is free */
    pb_ring(&b, ccw, 4);
    pb_end(&b);
    bool2_result r;
    REQUIRE(run_named(&b, "union", &r) == ARR_OK, "union failed");
    CHECK(r.ncells == 2 && r.region.npoly == 1 && boundary_edges(&r) == 6 &&
              fabs(r.area - 2) < 1e-12,
          "%zu cells, %zu polygons, %zu edges, area %g", r.ncells, r.region.npoly,
          boundary_edges(&r), r.area);
    check_result("touching union", &r);
    bool2_free(&r);
    REQUIRE(run_named(&b, "intersection", &r) == ARR_OK, "intersection failed");
    CHECK(r.ncells == 0 && r.area == 0, "touching intersection: %zu cells", r.ncells);
    bool2_free(&r);
    /* squares touching at a corner: two polygons, the walk splits at the shared vertex */
    pb c = {0};
    pb_rect(&c, 0, 0, 1, 1);
    pb_end(&c);
    pb_rect(&c, 1, 1, 2, 2);
    pb_end(&c);
    REQUIRE(run_named(&c, "union", &r) == ARR_OK, "corner union failed");
    CHECK(r.region.npoly == 2 && r.region.nrcyc == 2 && boundary_edges(&r) == 8,
          "%zu polygons, %zu cycles", r.region.npoly, r.region.nrcyc);
    check_result("corner union", &r);
    bool2_free(&r);
}

/* The seeds' test/py/bool2/test03.py: two 2-complexes (V1, FV1) and (V2, FV2); their boundary
 * rings (BE1, BE2 walked), and each face as an input of its own. */
static const double t03_ring1[] = {3, 0,  11, 0,  13, 10, 10, 3,  10, 11, 8, 4,
                                   8, 11, 6,  11, 6,  4,  4,  11, 4,  3,  1, 10};
static const double t03_ring2[] = {0, 3, 0, 8, 14, 11, 3, 7, 14, 7, 14, 5, 3, 5, 14, 2};
static const double t03_faces[][13] = {{6, 3, 0, 11, 0, 10, 3, 8, 4, 6, 4, 4, 3},
                                       {3, 11, 0, 13, 10, 10, 3},
                                       {3, 10, 11, 8, 4, 10, 3},
                                       {4, 8, 11, 6, 11, 6, 4, 8, 4},
                                       {3, 4, 11, 4, 3, 6, 4},
                                       {3, 3, 0, 1, 10, 4, 3},
                                       {4, 0, 3, 0, 8, 3, 7, 3, 5},
                                       {3, 0, 3, 14, 2, 3, 5},
                                       {3, 14, 11, 0, 8, 3, 7},
                                       {4, 14, 5, 14, 7, 3, 7, 3, 5}};

TEST(bool2_seeds_test03)
{
    pb b = {0};
    pb_ring(&b, t03_ring1, 12);
    pb_end(&b);
    pb_ring(&b, t03_ring2, 8);
    pb_end(&b);
    bool2_result u, x;
    REQUIRE(run_named(&b, "union", &u) == ARR_OK, "union failed");
    REQUIRE(run_named(&b, "intersection", &x) == ARR_OK, "intersection failed");
    /* |A| = 71, |B| = 59.5 (the faces' areas) */
    CHECK(fabs(u.area + x.area - (71 + 59.5)) < 1e-9, "union %g + intersection %g != 130.5", u.area,
          x.area);
    check_result("test03 union", &u);
    check_result("test03 intersection", &x);
    /* the same through the faces: (f0 + ... + f5) & (f6 + ... + f9) */
    pb fb = {0};
    for (size_t i = 0; i < 10; i++) {
        pb_ring(&fb, t03_faces[i] + 1, (size_t)t03_faces[i][0]);
        pb_end(&fb);
    }
    /* compile it the way the API does, through a request */
    char body[4096];
    int n = snprintf(body, sizeof body, "{\"kind\":\"polygons\",\"op\":%s,\"polygons\":[",
                     "[\"&\", [\"+\",0,1,2,3,4,5], [\"+\",6,7,8,9]]");
    for (size_t i = 0; i < 10; i++) {
        n += snprintf(body + n, sizeof body - n, "%s[[", i ? "," : "");
        for (int k = 0; k < (int)t03_faces[i][0]; k++)
            n += snprintf(body + n, sizeof body - n, "%s[%g,%g]", k ? "," : "",
                          t03_faces[i][1 + 2 * k], t03_faces[i][2 + 2 * k]);
        n += snprintf(body + n, sizeof body - n, "]]");
    }
    snprintf(body + n, sizeof body - n, "]}");
    char *out = NULL;
    size_t outlen;
    api_error err = {0};
    int rc = api_run_json(body, strlen(body), 1, &out, &outlen, &err);
    REQUIRE(rc == API_OK, "api: %d %s", rc, err.msg);
    json_t *res = json_loads(out, 0, NULL);
    REQUIRE(res, "result is not JSON");
    double area = json_number_value(json_object_get(json_object_get(res, "result"), "area"));
    CHECK(fabs(area - x.area) < 1e-9, "faces' expression area %.17g, rings' intersection %.17g",
          area, x.area);
    json_t *mem = json_object_get(res, "membership");
    json_t *shape = json_object_get(mem, "shape");
    CHECK(json_integer_value(json_array_get(shape, 0)) ==
                  (json_int_t)json_array_size(json_object_get(res, "FV")) &&
              json_array_size(json_object_get(mem, "indptr")) ==
                  json_array_size(json_object_get(res, "FV")) + 1,
          "membership rows");
    CHECK(json_integer_value(json_array_get(shape, 1)) == 10, "membership columns");
    json_decref(res);
    free(out);
    bool2_free(&u);
    bool2_free(&x);
}

/* ---- GEOS ------------------------------------------------------------------------------------ */

static GEOSGeometry *geos_poly(GEOSContextHandle_t h, const pb *b, size_t p)
{
    return geos_ref_polygon(h, b->poly_off, b->ring_off, b->xy, p);
}

/* The area of the named operation over b's polygons by GEOS (difference: the first minus the
 * union of the others). */
static double geos_area(const pb *b, const char *op, size_t *npoly, size_t *nholes)
{
    GEOSContextHandle_t h = GEOS_init_r();
    GEOSGeometry *acc = geos_poly(h, b, 0), *rest = NULL;
    for (size_t p = 1; p < b->np; p++) {
        GEOSGeometry *g = geos_poly(h, b, p);
        if (!strcmp(op, "difference")) {
            if (!rest) {
                rest = g;
                continue;
            }
            rest = geos_ref_fold(h, "union", rest, g);
            continue;
        }
        acc = geos_ref_fold(h, op, acc, g);
    }
    if (rest) {
        GEOSGeometry *t = GEOSDifference_r(h, acc, rest);
        GEOSGeom_destroy_r(h, acc);
        GEOSGeom_destroy_r(h, rest);
        acc = t;
    }
    double a = -1;
    *npoly = *nholes = 0;
    if (acc) {
        GEOSArea_r(h, acc, &a);
        int ng = GEOSisEmpty_r(h, acc) ? 0 : GEOSGetNumGeometries_r(h, acc);
        for (int i = 0; i < ng; i++) {
            const GEOSGeometry *p = GEOSGetGeometryN_r(h, acc, i);
            if (GEOSGeomTypeId_r(h, p) != GEOS_POLYGON || GEOSisEmpty_r(h, p)) continue;
            (*npoly)++;
            *nholes += (size_t)GEOSGetNumInteriorRings_r(h, p);
        }
    }
    GEOSGeom_destroy_r(h, acc);
    GEOS_finish_r(h);
    return a;
}

/* A star-shaped polygon around (cx, cy) with n vertices, with a small square hole at the
 * centre when hole != 0. */
static void random_star(pb *b, uint64_t *st, double cx, double cy, int hole)
{
    double pts[2 * 64];
    size_t n = 5 + (size_t)(test_rnd(st) * 20);
    for (size_t i = 0; i < n; i++) {
        double ang = 2 * M_PI * (i + 0.2 + 0.6 * test_rnd(st)) / n;
        double rad = 0.4 + 0.6 * test_rnd(st);
        pts[2 * i] = cx + rad * cos(ang);
        pts[2 * i + 1] = cy + rad * sin(ang);
    }
    pb_ring(b, pts, n);
    if (hole) { /* inside the kernel: the star's radii are all >= 0.4 */
        double s = 0.1 + 0.1 * test_rnd(st);
        double hr[8] = {cx - s, cy - s, cx - s, cy + s, cx + s, cy + s, cx + s, cy - s};
        pb_ring(b, hr, 4);
    }
    pb_end(b);
}

static void differential(const char *what, const pb *b)
{
    const char *ops[] = {"union", "intersection", "difference", "xor"};
    for (size_t t = 0; t < 4; t++) {
        bool2_result r;
        REQUIRE(run_named(b, ops[t], &r) == ARR_OK, "%s %s failed", what, ops[t]);
        size_t gp, gh;
        double g = geos_area(b, ops[t], &gp, &gh);
        CHECK(g >= 0, "%s %s: GEOS failed", what, ops[t]);
        CHECK(fabs(r.area - g) <= 1e-9 * fmax(1, g), "%s %s: area %.17g, GEOS %.17g", what, ops[t],
              r.area, g);
        size_t holes = r.region.npoly ? r.region.ph_off[r.region.npoly] : 0;
        CHECK(r.region.npoly == gp && holes == gh,
              "%s %s: %zu polygons and %zu holes, GEOS %zu and %zu", what, ops[t], r.region.npoly,
              holes, gp, gh);
        check_result(what, &r);
        bool2_free(&r);
    }
}

TEST(bool2_geos_random_stars)
{
    for (uint64_t seed = 1; seed <= 12; seed++) {
        uint64_t st = seed * 0x9e3779b97f4a7c15ull;
        pb b = {0};
        size_t np = 2 + (size_t)(test_rnd(&st) * 4);
        for (size_t p = 0; p < np; p++)
            random_star(&b, &st, test_rnd(&st), test_rnd(&st), test_rnd(&st) < 0.5);
        char what[64];
        snprintf(what, sizeof what, "stars seed %d (%zu polygons)", (int)seed, np);
        differential(what, &b);
    }
}

TEST(bool2_geos_random_rectangles)
{
    /* on a coarse lattice: shared edges, collinear overlaps, vertices on edges */
    for (uint64_t seed = 1; seed <= 12; seed++) {
        uint64_t st = seed * 0x2545f4914f6cdd1dull;
        pb b = {0};
        size_t np = 2 + (size_t)(test_rnd(&st) * 5);
        for (size_t p = 0; p < np; p++) {
            double x0 = floor(test_rnd(&st) * 8), y0 = floor(test_rnd(&st) * 8);
            double x1 = x0 + 1 + floor(test_rnd(&st) * 5), y1 = y0 + 1 + floor(test_rnd(&st) * 5);
            pb_rect(&b, x0, y0, x1, y1);
            pb_end(&b);
        }
        char what[64];
        snprintf(what, sizeof what, "rectangles seed %d (%zu)", (int)seed, np);
        differential(what, &b);
    }
}

/* ---- overlay cases from real GIS polygons (tests/data/bool2-cases) ----------------------------
 */

/* The area of ring cyc (vertex indices into V), signed; about its first vertex, so that large
 * coordinates do not cancel. */
static double json_ring_area(const json_t *V, const json_t *cyc)
{
    double a = 0, x0, y0;
    size_t n = json_array_size(cyc);
    const json_t *o = json_array_get(V, (size_t)json_integer_value(json_array_get(cyc, 0)));
    x0 = json_number_value(json_array_get(o, 0));
    y0 = json_number_value(json_array_get(o, 1));
    for (size_t i = 0; i < n; i++) {
        const json_t *p = json_array_get(V, (size_t)json_integer_value(json_array_get(cyc, i)));
        const json_t *q =
            json_array_get(V, (size_t)json_integer_value(json_array_get(cyc, (i + 1) % n)));
        a += (json_number_value(json_array_get(p, 0)) - x0) *
                 (json_number_value(json_array_get(q, 1)) - y0) -
             (json_number_value(json_array_get(q, 0)) - x0) *
                 (json_number_value(json_array_get(p, 1)) - y0);
    }
    return a / 2;
}

static int cmp_dbl(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* GEOS's answers printed to `digits` significant digits: half a unit in the last digit. */
static double printed(double v, double digits)
{
    return v == 0 ? 0 : 0.5 * pow(10, floor(log10(fabs(v))) - digits + 1);
}

TEST(bool2_overlay_cases)
{
    char path[512];
    size_t len;
    snprintf(path, sizeof path, "%s/bool2-cases/expected.json", test_data_dir());
    char *text = test_read_file(path, &len);
    REQUIRE(text, "cannot read %s", path);
    json_t *exp = json_loads(text, 0, NULL);
    free(text);
    REQUIRE(exp, "%s does not parse", path);
    const char *name;
    json_t *want;
    size_t ncases = 0;
    json_object_foreach(json_object_get(exp, "cases"), name, want)
    {
        snprintf(path, sizeof path, "%s/bool2-cases/%s", test_data_dir(), name);
        text = test_read_file(path, &len);
        CHECK(text, "cannot read %s", path);
        if (!text) continue;
        ncases++;
        /* every field (the files ask for V only): the stats give the grid step */
        json_t *req = json_loads(text, 0, NULL);
        free(text);
        json_object_del(json_object_get(req, "options"), "fields");
        char *body = json_dumps(req, 0), *out = NULL;
        api_error err = {0};
        int rc = api_run_json(body, strlen(body), 1, &out, &len, &err);
        free(body);
        CHECK(rc == API_OK, "%s: status %d: %s", name, rc, err.msg);
        if (rc != API_OK) {
            json_decref(req);
            continue;
        }
        json_t *res = json_loads(out, 0, NULL), *result = json_object_get(res, "result");
        free(out);
        const json_t *V = json_object_get(res, "V"), *FV = json_object_get(result, "FV");
        const json_t *holes = json_object_get(result, "holes");
        double step =
            json_number_value(json_object_get(json_object_get(res, "stats"), "precision"));
        /* the snapping bound: every input ring's perimeter times the grid step */
        double perim = 0;
        size_t i, j, k;
        json_t *poly, *ring;
        json_array_foreach(json_object_get(req, "polygons"), i, poly)
            json_array_foreach(poly, j, ring)
        {
            size_t n = json_array_size(ring);
            for (k = 0; k < n; k++) {
                const json_t *p = json_array_get(ring, k), *q = json_array_get(ring, (k + 1) % n);
                perim += hypot(json_number_value(json_array_get(q, 0)) -
                                   json_number_value(json_array_get(p, 0)),
                               json_number_value(json_array_get(q, 1)) -
                                   json_number_value(json_array_get(p, 1)));
            }
        }
        double bound = perim * step;
        double area = json_number_value(json_object_get(result, "area"));
        double garea = json_number_value(json_object_get(want, "area"));
        double tol =
            bound + printed(garea, json_number_value(json_object_get(want, "area_digits")));
        CHECK(fabs(area - garea) <= tol, "%s: area %.17g, GEOS %.10g (bound %.3g)", name, area,
              garea, tol);
        CHECK(json_array_size(FV) == (size_t)json_integer_value(json_object_get(want, "polygons")),
              "%s: %zu polygons, GEOS %lld", name, json_array_size(FV),
              (long long)json_integer_value(json_object_get(want, "polygons")));
        /* the holes: their areas, sorted, against GEOS's; the rings add up to the area */
        {
            const json_t *wh = json_object_get(want, "holes");
            double got[16], sum = 0;
            size_t nh = 0;
            const char *key;
            json_t *hs;
            for (size_t q = 0; q < json_array_size(FV); q++) {
                double a = json_ring_area(V, json_array_get(FV, q));
                CHECK(a > 0, "%s: polygon %zu shell not counter-clockwise (%g)", name, q, a);
                sum += a;
            }
            json_object_foreach((json_t *)holes, key, hs) json_array_foreach(hs, k, ring)
            {
                double a = json_ring_area(V, ring);
                CHECK(a < 0, "%s: hole of polygon %s not clockwise (%g)", name, key, a);
                sum += a;
                if (nh < 16) got[nh++] = -a;
            }
            /* V holds the input's own coordinates where input points snapped, the area is the
             * grid's: they differ within the bound */
            CHECK(fabs(sum - area) <= bound + 1e-12 * fmax(1, area),
                  "%s: rings enclose %.17g, area %.17g (bound %.3g)", name, sum, area, bound);
            CHECK(nh == json_array_size(wh), "%s: %zu holes, GEOS %zu", name, nh,
                  json_array_size(wh));
            qsort(got, nh, sizeof *got, cmp_dbl);
            for (k = 0; k < nh && k < json_array_size(wh); k++) {
                double g = json_number_value(json_array_get(wh, k));
                double t =
                    bound + printed(g, json_number_value(json_object_get(want, "hole_digits")));
                CHECK(fabs(got[k] - g) <= t, "%s: hole %zu area %.17g, GEOS %.10g", name, k, got[k],
                      g);
            }
        }
        json_decref(res);
        json_decref(req);
    }
    CHECK(ncases == 4, "%zu cases of 4", ncases);
    json_decref(exp);
    /* the near-collinear lines: a valid arrangement, no error (README.md there) */
    snprintf(path, sizeof path, "%s/bool2-cases/near-collinear-overlap.json", test_data_dir());
    text = test_read_file(path, &len);
    REQUIRE(text, "cannot read %s", path);
    {
        char *out = NULL;
        size_t outlen;
        api_error err = {0};
        CHECK(api_run_json(text, len, 1, &out, &outlen, &err) == API_OK, "near-collinear: %s",
              err.msg);
        free(out);
    }
    free(text);
}

/* The sparse evaluator (bool_tree) against the dense one (bool_expr_eval) on random programs
 * (operators mixed, inputs repeated, chains of one operator) and the named operations, on
 * random membership lists, empty and full ones included. */
TEST(bool2_sparse_expressions_equal_dense)
{
    uint64_t st = 77;
    size_t bad = 0, runs = 0;
    for (int round = 0; round < 400; round++) {
        bool_expr e = {0};
        size_t ni = 1 + (size_t)(test_rnd(&st) * 12);
        if (round % 4 == 0) {
            static const char *const names[] = {"union", "intersection", "difference", "xor"};
            REQUIRE(bool_expr_named(names[(round / 4) % 4], ni, &e) == 0, "named");
        } else {
            /* a random postfix program: push while the stack is low, else combine */
            size_t d = 0, len = 2 + (size_t)(test_rnd(&st) * 30);
            for (size_t i = 0; i < len || d != 1; i++) {
                if (d < 2 || (i < len && test_rnd(&st) < 0.5)) {
                    bool_expr_push(&e, (int32_t)(test_rnd(&st) * ni));
                    d++;
                } else {
                    int32_t op = -1 - (int32_t)(test_rnd(&st) * 4);
                    if (test_rnd(&st) < 0.4) op = BOOL_OR; /* chains */
                    bool_expr_push(&e, op);
                    d--;
                }
            }
            REQUIRE(bool_expr_check(&e, ni) == 0, "random program not well formed");
        }
        bool_tree t;
        REQUIRE(bool_tree_build(&e, ni, &t) == 0, "bool_tree_build");
        uint8_t row[16], stack[64];
        uint32_t in[16];
        for (int k = 0; k < 64; k++) {
            size_t m = 0;
            for (size_t i = 0; i < ni; i++) {
                double p = k == 0 ? 0 : k == 1 ? 1 : test_rnd(&st);
                row[i] = p > 0.5 || k == 1;
                if (row[i]) in[m++] = (uint32_t)i;
            }
            /* any order */
            for (size_t i = m; i > 1; i--) {
                size_t j = (size_t)(test_rnd(&st) * i);
                uint32_t tmp = in[i - 1];
                in[i - 1] = in[j];
                in[j] = tmp;
            }
            uint8_t *sk = e.depth <= sizeof stack ? stack : malloc(e.depth);
            int want = bool_expr_eval(&e, row, sk) != 0;
            if (sk != stack) free(sk);
            int got = bool_tree_eval(&t, in, m);
            runs++;
            if (got != want && bad++ < 5)
                CHECK(0, "round %d row %d: sparse %d, dense %d (%zu inputs, %zu code)", round, k,
                      got, want, ni, e.n);
        }
        bool_tree_free(&t);
        bool_expr_free(&e);
    }
    CHECK(bad == 0, "%zu of %zu evaluations differ", bad, runs);
}

/* Many operands (issue "Booleans of many operands"): a 40 x 40 tiling of unit squares (every
 * edge shared) — union area 1600 in one polygon, xor the same, intersection empty, every face in
 * exactly one square — and the union of 2000 turned squares against GEOS's unary union within
 * the snapping bound.  Membership is sparse: its size is the faces' few inputs, not faces x
 * inputs. */
TEST(bool2_many_operands)
{
    const size_t k = 40, n = k * k, most = 2000; /* the tiling, then 2000 squares */
    uint32_t *poly_off = malloc((most + 1) * sizeof *poly_off);
    uint32_t *ring_off = malloc((most + 1) * sizeof *ring_off);
    double *xy = malloc(8 * most * sizeof *xy);
    REQUIRE(poly_off && ring_off && xy, "memory");
    poly_off[0] = ring_off[0] = 0;
    for (size_t i = 0; i < k; i++)
        for (size_t j = 0; j < k; j++) {
            size_t q = i * k + j;
            double r[8] = {(double)i,     (double)j,     (double)i + 1, (double)j,
                           (double)i + 1, (double)j + 1, (double)i,     (double)j + 1};
            memcpy(xy + 8 * q, r, sizeof r);
            poly_off[q + 1] = (uint32_t)(q + 1);
            ring_off[q + 1] = (uint32_t)(4 * (q + 1));
        }
    bool2_input in = {n, poly_off, ring_off, xy, BOOL2_FILL_ODD, 0};
    static const char *const ops[] = {"union", "xor", "intersection"};
    static const double want[] = {1600, 1600, 0};
    for (int t = 0; t < 3; t++) {
        bool_expr e;
        bool2_result r;
        char err[256];
        REQUIRE(bool_expr_named(ops[t], n, &e) == 0, "expr");
        int rc = bool2_build(&in, &e, &(arr2_opts){.threads = 2}, &r, err, sizeof err);
        CHECK(rc == ARR_OK, "tiling %s: %s", ops[t], err);
        if (rc == ARR_OK) {
            CHECK(r.area == want[t], "tiling %s: area %.17g, want %g", ops[t], r.area, want[t]);
            CHECK(r.region.npoly == (t < 2 ? 1u : 0u) &&
                      (r.region.npoly == 0 || r.region.ph_off[r.region.npoly] == 0),
                  "tiling %s: %zu polygons", ops[t], r.region.npoly);
            CHECK(r.c.nf == n && r.mem_off[r.c.nf] == n, "tiling %s: %zu faces, %u memberships",
                  ops[t], r.c.nf, r.mem_off[r.c.nf]);
            check_result(ops[t], &r);
            bool2_free(&r);
        }
        bool_expr_free(&e);
    }
    /* 2000 turned unit squares, centres uniform in a square of area 1000: union against GEOS */
    {
        const size_t m = 2000;
        uint64_t st = 4242;
        double side = sqrt(m / 2.0), perim = 0;
        GEOSContextHandle_t h = GEOS_init_r();
        GEOSGeometry **g = malloc(m * sizeof *g);
        for (size_t q = 0; q < m; q++) {
            double cx = test_rnd(&st) * side, cy = test_rnd(&st) * side;
            poly_off[q + 1] = (uint32_t)(q + 1);
            ring_off[q + 1] = (uint32_t)(4 * (q + 1));
            double a = test_rnd(&st) * M_PI / 2, c = cos(a) / 2, s = sin(a) / 2;
            double d[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
            for (int v = 0; v < 4; v++) {
                xy[8 * q + 2 * v] = cx + d[v][0] * c - d[v][1] * s;
                xy[8 * q + 2 * v + 1] = cy + d[v][0] * s + d[v][1] * c;
            }
            g[q] = geos_ref_polygon(h, poly_off, ring_off, xy, q);
            perim += 4;
        }
        GEOSGeometry *coll =
            GEOSGeom_createCollection_r(h, GEOS_GEOMETRYCOLLECTION, g, (unsigned)m);
        GEOSGeometry *u = GEOSUnaryUnion_r(h, coll);
        double ga = -1;
        if (u) GEOSArea_r(h, u, &ga);
        bool2_input in2 = {m, poly_off, ring_off, xy, BOOL2_FILL_ODD, 0};
        bool_expr e;
        bool2_result r;
        char err[256];
        REQUIRE(bool_expr_named("union", m, &e) == 0, "expr");
        int rc = bool2_build(&in2, &e, &(arr2_opts){.threads = 2}, &r, err, sizeof err);
        CHECK(rc == ARR_OK, "2000 squares: %s", err);
        if (rc == ARR_OK) {
            double bound = perim * r.c.stats.precision;
            CHECK(ga > 0 && fabs(r.area - ga) <= bound, "2000 squares: area %.17g, GEOS %.17g",
                  r.area, ga);
            /* sparse: about two inputs per face at this density, nowhere near faces x inputs */
            CHECK(r.mem_off[r.c.nf] < 8 * r.c.nf, "2000 squares: %u memberships for %zu faces",
                  r.mem_off[r.c.nf], r.c.nf);
            check_result("2000 squares", &r);
            bool2_free(&r);
        }
        bool_expr_free(&e);
        GEOSGeom_destroy_r(h, u);
        GEOSGeom_destroy_r(h, coll);
        free(g);
        GEOS_finish_r(h);
    }
    free(poly_off);
    free(ring_off);
    free(xy);
}

/* Progress of a large Boolean (fractions of the whole job): the arrangement's stages, then
 * membership (also inside the walk: 67 600 faces pass a tick), select, polygons and output
 * (moving as the result's keys are written), never going back, ending at 1. */
typedef struct prog_log {
    int n, back, membership_inside, select, polygons, output;
    double last, membership_from;
} prog_log;

static void prog_cb(void *udata, const char *stage, double f)
{
    prog_log *l = udata;
    l->n++;
    if (f < l->last || f > 1) l->back++;
    l->last = f;
    if (!strcmp(stage, "membership")) {
        if (!l->membership_from) l->membership_from = f;
        l->membership_inside += f > l->membership_from;
    }
    l->select += !strcmp(stage, "select");
    l->polygons += !strcmp(stage, "polygons");
    l->output += !strcmp(stage, "output");
}

TEST(bool2_progress)
{
    const size_t k = 260;
    size_t cap = 64 + k * k * 64, len = 0;
    char *body = malloc(cap);
    REQUIRE(body, "memory");
    len += (size_t)snprintf(body + len, cap - len,
                            "{\"kind\":\"polygons\",\"op\":\"union\","
                            "\"options\":{\"fields\":[\"stats\"]},"
                            "\"polygons\":[");
    for (size_t i = 0; i < k; i++)
        for (size_t j = 0; j < k; j++)
            len += (size_t)snprintf(body + len, cap - len, "%s[[[%zu,%zu],[%zu,%zu],[%zu,%zu]]]",
                                    i || j ? "," : "", i, j, i + 1, j, i, j + 1);
    len += (size_t)snprintf(body + len, cap - len, "]}");
    prog_log l = {0};
    api_run_opts ro = {.threads = 2, .progress = prog_cb, .udata = &l};
    char *out = NULL;
    size_t outlen;
    api_error err = {0};
    int rc = api_run_json_ex(body, len, &ro, &out, &outlen, &err);
    CHECK(rc == API_OK, "%d %s", rc, err.msg);
    CHECK(l.membership_inside >= 1 && l.select >= 1 && l.polygons >= 1 && l.output >= 3 &&
              l.back == 0 && l.last == 1,
          "progress: %d calls, %d inside membership, select %d, polygons %d, output %d, %d back",
          l.n, l.membership_inside, l.select, l.polygons, l.output, l.back);
    free(out);
    free(body);
}

/* ---- the request ----------------------------------------------------------------------------- */

/* Request body must be refused with 422 and a message starting with msg (its JSON path). */
static void check_refused(const char *body, const char *msg, size_t i)
{
    char *out = NULL;
    size_t outlen;
    api_error err = {0};
    int rc = api_run_json(body, strlen(body), 1, &out, &outlen, &err);
    CHECK(rc == API_EINVALID, "case %zu: status %d, want 422", i, rc);
    CHECK(strncmp(err.msg, msg, strlen(msg)) == 0, "case %zu: message \"%s\", want \"%s...\"", i,
          err.msg, msg);
    free(out);
}

TEST(bool2_api_errors)
{
    struct {
        const char *body, *msg; /* msg: the start of the error message (its JSON path) */
    } cases[] = {
        {"{\"kind\":\"polygons\",\"op\":\"union\"}", "polygons: required"},
        {"{\"kind\":\"polygons\",\"polygons\":[],\"op\":\"union\"}", "polygons: expected"},
        {"{\"kind\":\"polygons\",\"polygons\":{},\"op\":\"union\"}", "polygons: expected"},
        {"{\"kind\":\"polygons\",\"polygons\":[[]],\"op\":\"union\"}", "polygons[0]: expected"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]],[[[0,0],[1,0]]]],\"op\":"
         "\"union\"}",
         "polygons[1][0]: expected a ring of at least 3 points"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]],[[[0,0],[1,0],[0,1]],[[0,0],"
         "[1,0],7]]],\"op\":\"union\"}",
         "polygons[1][1][2]: expected [x, y]"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1,2]]]],\"op\":\"union\"}",
         "polygons[0][0][2]: expected [x, y]"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,\"a\"],[0,1]]]],\"op\":\"union\"}",
         "polygons[0][0][1][1]: expected a finite number"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]]}", "op: required"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"merge\"}",
         "op: expected"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":[\"-\",0,[\"+\",0,"
         "3]]}",
         "op[2][2]: input 3 out of range (1 inputs)"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":[\"*\",0,0]}",
         "op[0]: expected an operator"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":[\"+\",0]}",
         "op: expected an input index"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"union\","
         "\"options\":{\"precision\":-1}}",
         "options.precision: expected"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"union\","
         "\"options\":{\"nope\":1}}",
         "options.nope: unknown option"},
        {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"union\","
         "\"lines\":[]}",
         "lines: unknown key"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++)
        check_refused(cases[i].body, cases[i].msg, i);
}

/* The same polygons posted as native rings, GeoJSON geometries (Polygon, MultiPolygon,
 * Feature), a FeatureCollection and WKT (with Z, SRID, EMPTY) give the same answer, byte for
 * byte (rings closed by repeating their first point lose that point). */
TEST(bool2_gis_inputs)
{
#define NATIVE_A "[[[0,0],[4,0],[4,4],[0,4]],[[1,1],[2,1],[2,2],[1,2]]]"
#define NATIVE_B "[[[2,2],[6,2],[6,6],[2,6]]],"
    static const char *const forms[][3] = {
        {NATIVE_A, "[[[2,2],[6,2],[6,6],[2,6]]]", "[[[10,10],[11,10],[11,11]]]"},
        {"{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[4,0],[4,4],[0,4],[0,0]],"
         "[[1,1],[2,1],[2,2],[1,2],[1,1]]]}",
         "{\"type\":\"Feature\",\"properties\":{\"name\":\"b\"},\"geometry\":{\"type\":"
         "\"MultiPolygon\",\"coordinates\":[[[[2,2,9],[6,2,9],[6,6,9],[2,6,9],[2,2,9]]]]}}",
         "{\"type\":\"Polygon\",\"coordinates\":[[[10,10],[11,10],[11,11],[10,10]]]}"},
        {"\"POLYGON ((0 0, 4 0, 4 4, 0 4, 0 0), (1 1, 2 1, 2 2, 1 2, 1 1))\"",
         "\"SRID=4326;multipolygon z (((2 2 1, 6 2 1, 6 6 1, 2 6 1, 2 2 1)), EMPTY)\"",
         "\"POLYGON((10 10,11 10,11 11,10 10))\""},
    };
    static const char *const ops[] = {"\"union\"", "\"intersection\"", "[\"-\",0,1]", "\"xor\""};
    for (size_t o = 0; o < 4; o++) {
        json_t *want = NULL;
        for (size_t f = 0; f < 4; f++) {
            char body[1200];
            char *out = NULL;
            size_t len;
            api_error err = {0};
            if (f < 3)
                snprintf(body, sizeof body,
                         "{\"kind\":\"polygons\",\"polygons\":[%s,%s,%s],\"op\":%s}", forms[f][0],
                         forms[f][1], forms[f][2], ops[o]);
            else /* a FeatureCollection: one input per Feature */
                snprintf(body, sizeof body,
                         "{\"kind\":\"polygons\",\"polygons\":{\"type\":\"FeatureCollection\","
                         "\"features\":[{\"type\":\"Feature\",\"geometry\":%s},"
                         "{\"type\":\"Feature\",\"geometry\":{\"type\":\"Polygon\","
                         "\"coordinates\":[[[2,2],[6,2],[6,6],[2,6],[2,2]]]}},"
                         "{\"type\":\"Feature\",\"properties\":null,\"geometry\":%s}]},\"op\":%s}",
                         forms[1][0], forms[1][2], ops[o]);
            int rc = api_run_json(body, strlen(body), 1, &out, &len, &err);
            CHECK(rc == API_OK, "op %s form %zu: %d %s", ops[o], f, rc, err.msg);
            if (rc == API_OK) { /* all but the timings */
                json_t *res = json_loads(out, 0, NULL);
                json_object_del(res, "stats");
                if (!want)
                    want = res;
                else
                    CHECK(json_equal(res, want), "op %s: form %zu differs from the native form",
                          ops[o], f);
                if (res != want) json_decref(res);
            }
            free(out);
        }
        json_decref(want);
    }
    /* EMPTY and an unlocated feature are the empty set */
    {
        const char *body = "{\"kind\":\"polygons\",\"polygons\":[\"POLYGON EMPTY\","
                           "{\"type\":\"Feature\",\"geometry\":null,\"properties\":{}},"
                           "[[[0,0],[1,0],[1,1],[0,1]]]],\"op\":[\"+\",0,1]}";
        char *out = NULL;
        size_t len;
        api_error err = {0};
        REQUIRE(api_run_json(body, strlen(body), 1, &out, &len, &err) == API_OK, "%s", err.msg);
        json_t *res = json_loads(out, 0, NULL);
        CHECK(json_number_value(json_object_get(json_object_get(res, "result"), "area")) == 0,
              "empty inputs: area %g",
              json_number_value(json_object_get(json_object_get(res, "result"), "area")));
        json_decref(res);
        free(out);
    }
#undef NATIVE_A
#undef NATIVE_B
}

/* GeoJSON and WKT errors name the JSON path, and for WKT the character position. */
TEST(bool2_gis_errors)
{
    struct {
        const char *polygons, *msg;
    } cases[] = {
        {"[{\"coordinates\":[]}]", "polygons[0].type: required"},
        {"[{\"type\":\"LineString\",\"coordinates\":[[0,0],[1,1]]}]",
         "polygons[0].type: \"LineString\" is not an area"},
        {"[{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1],[0,0]]]},"
         "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[\"x\",1],[0,0]]]}]",
         "polygons[1].coordinates[0][2][0]: expected a finite number"},
        {"[{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[0,0]]]}]",
         "polygons[0].coordinates[0]: a ring needs at least 3 distinct points"},
        {"[{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1],[1,1],[0,0]]]}]",
         "polygons[0].coordinates[0][1]: expected [x, y]"},
        {"[{\"type\":\"MultiPolygon\",\"coordinates\":[[[[0,0],[1,0],[1,1]]],7]}]",
         "polygons[0].coordinates[1]: expected a polygon"},
        {"[{\"type\":\"Feature\",\"geometry\":{\"type\":\"Feature\"}}]",
         "polygons[0].geometry: expected a Polygon or MultiPolygon"},
        {"[{\"type\":\"Feature\",\"geometry\":{\"type\":\"Point\",\"coordinates\":[0,0]}}]",
         "polygons[0].geometry.type: \"Point\" is not an area"},
        {"{\"type\":\"GeometryCollection\"}", "polygons: expected an array of polygons or"},
        {"{\"type\":\"FeatureCollection\",\"features\":7}", "polygons.features: expected"},
        {"{\"type\":\"FeatureCollection\",\"features\":[]}", "polygons.features: expected a non"},
        {"{\"type\":\"FeatureCollection\",\"features\":[\"POLYGON EMPTY\"]}",
         "polygons.features[0]: expected a GeoJSON Feature"},
        {"[\"LINESTRING (0 0, 1 1)\"]",
         "polygons[0]: WKT at character 1: expected POLYGON or MULTIPOLYGON"},
        {"[\"POLYGON ((0 0, 1 0, 1 1, 0 0)\"]",
         "polygons[0]: WKT at character 30: expected ',' or ')' after a ring, found the end"},
        {"[\"POLYGON ((0 0, 1 0, 1 1, 0 0)) x\"]",
         "polygons[0]: WKT at character 32: expected the end of the geometry"},
        {"[\"POLYGON ((0 0, 1 0, 1 nan, 0 0))\"]",
         "polygons[0]: WKT at character 21: expected 2 ordinates"},
        {"[\"POLYGON ((0 0, 1 0, 1 1e999, 0 0))\"]",
         "polygons[0]: WKT at character 23: expected a finite number"},
        {"[\"POLYGON Z ((0 0 0, 1 0, 1 1 0, 0 0 0))\"]",
         "polygons[0]: WKT at character 20: expected 3 ordinates"},
        {"[\"POLYGON ((0 0, 1 0 0, 1 1, 0 0))\"]",
         "polygons[0]: WKT at character 16: expected 2 ordinates"},
        {"[\"POLYGON ((0 0, 1 0, 0 0))\"]",
         "polygons[0]: WKT ring at character 10: a ring needs at least 3 distinct points"},
        {"[\"MULTIPOLYGON (((0 0, 1 0, 1 1, 0 0)) ((2 2, 3 2, 3 3)))\"]",
         "polygons[0]: WKT at character 38: expected ',' or ')' after a polygon"},
        {"[\"SRID=x;POLYGON EMPTY\"]", "polygons[0]: WKT at character 6: expected SRID=n;"},
        {"[\"\"]",
         "polygons[0]: WKT at character 1: expected POLYGON or MULTIPOLYGON, found the end"},
        {"[\"POLYGON ((0 0, 1 0, 1 1, 0 0), ())\"]", "polygons[0]: WKT at character 33:"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char body[600];
        snprintf(body, sizeof body, "{\"kind\":\"polygons\",\"polygons\":%s,\"op\":\"union\"}",
                 cases[i].polygons);
        check_refused(body, cases[i].msg, i);
    }
}

TEST(bool2_api_result)
{
    const char *body = "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[2,0],[2,2],[0,2]]],"
                       "[[[1,1],[3,1],[3,3],[1,3]]]],\"op\":[\"^\",0,1],"
                       "\"options\":{\"fields\":[\"V\",\"FV\",\"membership\",\"result\"]}}";
    char *out = NULL;
    size_t outlen;
    api_error err = {0};
    int rc = api_run_json(body, strlen(body), 1, &out, &outlen, &err);
    REQUIRE(rc == API_OK, "status %d: %s", rc, err.msg);
    json_t *res = json_loads(out, 0, NULL);
    REQUIRE(res, "not JSON: %s", out);
    json_t *result = json_object_get(res, "result");
    /* membership as compressed sparse rows: the three faces lie in {0}, {0, 1}, {1} */
    {
        json_t *mem = json_object_get(res, "membership");
        json_t *want = json_loads("{\"format\":\"csr\",\"shape\":[3,2],\"indptr\":[0,1,3,4],"
                                  "\"indices\":[0,0,1,1]}",
                                  0, NULL);
        CHECK(json_equal(mem, want), "membership %s", json_dumps(mem, JSON_COMPACT));
        json_decref(want);
    }
    CHECK(json_array_size(json_object_get(result, "cells")) == 2, "xor: 2 cells");
    CHECK(json_array_size(json_object_get(result, "FV")) == 2, "xor: 2 polygons");
    CHECK(!json_object_get(result, "FE"), "xor: no FE without EV named");
    CHECK(!json_object_get(result, "V"), "xor: no V of its own with V named");
    CHECK(json_object_size(json_object_get(result, "holes")) == 0, "xor: no holes");
    CHECK(json_number_value(json_object_get(result, "area")) == 6, "xor: area 6");
    CHECK(!json_object_get(res, "EV"), "fields: no EV");
    json_decref(res);
    free(out);
}

TEST(bool2_hole_touching_outer_at_a_vertex)
{
    /* [0,10]^2 with the hole [3,7]^2, minus [0,2]^2 and [1,3]^2: the second square touches
     * the hole at (3,3), so the outside touches itself there.  As OGC asks, no ring passes a
     * vertex twice: the shell (the notched square) and the hole touch at (3,3); area
     * 100 - 16 - 7 = 77 */
    pb b = {0};
    pb_rect(&b, 0, 0, 10, 10);
    pb_rect(&b, 3, 3, 7, 7);
    pb_end(&b);
    pb_rect(&b, 0, 0, 2, 2);
    pb_end(&b);
    pb_rect(&b, 1, 1, 3, 3);
    pb_end(&b);
    bool2_result r;
    REQUIRE(run_named(&b, "difference", &r) == ARR_OK, "difference failed");
    CHECK(fabs(r.area - 77) < 1e-12, "area %g, want 77", r.area);
    CHECK(r.region.npoly == 1 && r.region.nrcyc == 2 && boundary_edges(&r) == 14 &&
              r.region.ph_off[1] - r.region.ph_off[0] == 1,
          "%zu polygons, %zu cycles, %zu edges", r.region.npoly, r.region.nrcyc,
          boundary_edges(&r));
    check_result("hole touching outer", &r);
    bool2_free(&r);
}
