/* test_svg.c — the SVG reader (core/svg.h) and the "svg" kind (api/svg.c).
 *
 * - every drawing of tests/data/svg is read without error or warning and gives a valid complex
 *   (tests/lar_check.h);
 * - the lar-cc floor plans give the faces GEOS gives on the same segments (count, sorted areas
 *   to 1e-9 relative plus what snapping can move, as in test_geos.c); pyinters-Emergency.svg
 *   prints our time and GEOS's;
 * - the drawings with transforms: where their elements land, computed by hand from the file
 *   (each expectation is the file's numbers through the file's matrix);
 * - each element, path command, transform, nested svg, use, unit and display rule;
 * - malformed and hostile input: each a clear error, fast, no crash.
 */
#include <dirent.h>
#include <sys/resource.h>
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "api/api.h"
#include "core/arr2.h"
#include "core/svg.h"
#include "tests/check.h"
#include "tests/lar_check.h"
#include "tests/ref/geos_ref.h"

#define NS        "xmlns=\"http://www.w3.org/2000/svg\""
#define DOC(body) "<svg " NS ">" body "</svg>"

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec / 1e6;
}

/* Reads text (NUL-terminated) with options o (may be NULL). */
static int rd(const char *text, const svg_opts *o, svg_result *r, char *err, size_t errlen)
{
    return svg_read(text, strlen(text), o, r, err, errlen);
}

/* Reads text, which must succeed; the segments then go through arr2_build and lar_check.
 * Returns the number of bounded faces, or -1 (a failure is recorded). */
static long rd_ok(const char *what, const char *text, const svg_opts *o, svg_result *r)
{
    char err[256], msg[256];
    lar2 c;
    long nf;
    int rc = rd(text, o, r, err, sizeof err);
    if (rc != ARR_OK) {
        test_fail(__FILE__, what, __LINE__, "svg_read: %d %s", rc, err);
        return -1;
    }
    rc = arr2_build(r->n ? r->seg : (const double[4]){0}, r->n, NULL, &c, err, sizeof err);
    if (rc != ARR_OK) {
        test_fail(__FILE__, what, __LINE__, "arr2_build: %s", err);
        return -1;
    }
    if (lar_check(&c, msg, sizeof msg)) test_fail(__FILE__, what, __LINE__, "invariant: %s", msg);
    nf = (long)c.nf;
    lar2_free(&c);
    return nf;
}

static int near(double a, double b, double tol)
{
    return fabs(a - b) <= tol;
}

/* Whether r has the segment (x1,y1)-(x2,y2), either way, to tol. */
static int has_seg(const svg_result *r, double x1, double y1, double x2, double y2, double tol)
{
    for (size_t i = 0; i < r->n; i++) {
        const double *s = r->seg + 4 * i;
        if (near(s[0], x1, tol) && near(s[1], y1, tol) && near(s[2], x2, tol) &&
            near(s[3], y2, tol))
            return 1;
        if (near(s[0], x2, tol) && near(s[1], y2, tol) && near(s[2], x1, tol) &&
            near(s[3], y1, tol))
            return 1;
    }
    return 0;
}

/* Whether some segment ends exactly at (x, y). */
static int has_end(const svg_result *r, double x, double y)
{
    for (size_t i = 0; i < 2 * r->n; i++)
        if (r->seg[2 * i] == x && r->seg[2 * i + 1] == y) return 1;
    return 0;
}

/* Distance from (x, y) to the nearest segment. */
static double dist(const svg_result *r, double x, double y)
{
    double best = INFINITY;
    for (size_t i = 0; i < r->n; i++) {
        const double *s = r->seg + 4 * i;
        double dx = s[2] - s[0], dy = s[3] - s[1], l2 = dx * dx + dy * dy, t = 0;
        if (l2 > 0) t = fmax(0, fmin(1, ((x - s[0]) * dx + (y - s[1]) * dy) / l2));
        double d = hypot(s[0] + t * dx - x, s[1] + t * dy - y);
        if (d < best) best = d;
    }
    return best;
}

/* Largest |distance from (cx, cy) - rad| over the segments' endpoints. */
static double off_circle(const svg_result *r, double cx, double cy, double rad)
{
    double worst = 0;
    for (size_t i = 0; i < 2 * r->n; i++)
        worst = fmax(worst, fabs(hypot(r->seg[2 * i] - cx, r->seg[2 * i + 1] - cy) - rad));
    return worst;
}

static int has_warning(const svg_result *r, const char *needle)
{
    for (size_t i = 0; i < r->nwarnings; i++)
        if (strstr(r->warning[i], needle)) return 1;
    return 0;
}

static char *data_file(const char *name, size_t *len)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/svg/%s", test_data_dir(), name);
    return test_read_file(path, len);
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* ---- the shared drawings ------------------------------------------------------------------ */

TEST(svg_every_data_file_reads_and_gives_a_valid_complex)
{
    char dir[1024], *names[256];
    size_t nn = 0;
    DIR *d;
    struct dirent *e;
    snprintf(dir, sizeof dir, "%s/svg", test_data_dir());
    d = opendir(dir);
    REQUIRE(d, "cannot open %s", dir);
    while ((e = readdir(d)) && nn < 256) {
        size_t l = strlen(e->d_name);
        if (l > 4 && strcmp(e->d_name + l - 4, ".svg") == 0) names[nn++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(names, nn, sizeof *names, cmp_str);
    CHECK(nn >= 60, "only %zu drawings in %s", nn, dir);
    for (size_t i = 0; i < nn; i++) {
        size_t len;
        char *text = data_file(names[i], &len), err[256], msg[256];
        svg_result r;
        lar2 c;
        int rc;
        CHECK(text, "%s: unreadable", names[i]);
        if (!text) {
            free(names[i]);
            continue;
        }
        rc = svg_read(text, len, NULL, &r, err, sizeof err);
        CHECK(rc == ARR_OK, "%s: %d %s", names[i], rc, err);
        CHECK(r.skipped == 0 && r.nwarnings == 0, "%s: %zu skipped, first warning %s", names[i],
              r.skipped, r.nwarnings ? r.warning[0] : "");
        CHECK(r.n > 0 && r.elements > 0, "%s: %zu segments from %zu elements", names[i], r.n,
              r.elements);
        rc = arr2_build(r.seg, r.n, NULL, &c, err, sizeof err);
        CHECK(rc == ARR_OK, "%s: arr2_build: %s", names[i], err);
        if (rc == ARR_OK) {
            CHECK(lar_check(&c, msg, sizeof msg) == 0, "%s: invariant: %s", names[i], msg);
            lar2_free(&c);
        }
        svg_result_free(&r);
        /* normalized: into the unit square, the longer side exactly 1, y up */
        rc = svg_read(text, len, &(svg_opts){.normalize = 1}, &r, err, sizeof err);
        CHECK(rc == ARR_OK, "%s normalized: %s", names[i], err);
        double lo = INFINITY, hi = -INFINITY;
        for (size_t k = 0; k < 4 * r.n; k++) lo = fmin(lo, r.seg[k]), hi = fmax(hi, r.seg[k]);
        CHECK(lo == 0 && hi == 1, "%s normalized: coordinates in [%g, %g]", names[i], lo, hi);
        CHECK(r.transform[3] == -r.transform[0] && r.transform[0] > 0,
              "%s normalized: transform %g %g", names[i], r.transform[0], r.transform[3]);
        svg_result_free(&r);
        free(text);
        free(names[i]);
    }
}

/* Compares arr2_build with GEOS on the segments of a drawing.  GEOS nodes in floating point
 * without snapping, so where a drawing has sides meant to coincide but 1e-14 apart (a rect's
 * x + width computed in doubles beside a literal), it makes sliver faces of area < 1e-11 (16 of
 * them on building.svg).  GEOS therefore gets the segments rounded to our grid (the precision
 * arr2_build used), where such sides coincide exactly; arr2_build gives the same complex on
 * those, which is checked too. */
static void compare_geos(const char *name)
{
    size_t len, gf, gh, gv, ge, rf, rh;
    char *text = data_file(name, &len), err[256];
    svg_result r;
    lar2 c, c2;
    double *ga = NULL, *raw = NULL;
    REQUIRE(text, "%s: unreadable", name);
    REQUIRE(svg_read(text, len, NULL, &r, err, sizeof err) == ARR_OK, "%s: %s", name, err);
    free(text);
    REQUIRE(arr2_build(r.seg, r.n, NULL, &c, err, sizeof err) == ARR_OK, "%s: %s", name, err);
    REQUIRE(geos_ref_faces(r.seg, r.n, &raw, &rf, &rh, &gv, &ge) == 0, "%s: GEOS failed", name);
    free(raw);
    for (size_t i = 0; i < 4 * r.n; i++)
        r.seg[i] = round(r.seg[i] / c.stats.precision) * c.stats.precision;
    REQUIRE(arr2_build(r.seg, r.n, &(arr2_opts){.precision = c.stats.precision}, &c2, err,
                       sizeof err) == ARR_OK,
            "%s: %s", name, err);
    CHECK(c2.nf == c.nf && c2.nv == c.nv && c2.ne == c.ne, "%s: rounding to our grid changed us",
          name);
    lar2_free(&c2);
    REQUIRE(geos_ref_faces(r.seg, r.n, &ga, &gf, &gh, &gv, &ge) == 0, "%s: GEOS failed", name);
    if (rf != gf)
        printf("  %s: GEOS on the unrounded segments: %zu faces (%zu slivers)\n", name, rf,
               rf - gf);
    CHECK(c.nf == gf, "%s: %zu faces, GEOS %zu", name, c.nf, gf);
    CHECK(c.hole_off[c.nf] == gh, "%s: %u holes, GEOS %zu", name, c.hole_off[c.nf], gh);
    if (c.nf == gf) {
        double worst, extent = fmax(r.bbox[2] - r.bbox[0], r.bbox[3] - r.bbox[1]);
        size_t bad = lar_sorted_areas_differ(&c, ga, gf, 8 * extent * c.stats.precision, &worst);
        CHECK(bad == 0, "%s: %zu of %zu sorted areas differ from GEOS (worst relative %g)", name,
              bad, c.nf, worst);
    }
    free(ga);
    lar2_free(&c);
    svg_result_free(&r);
}

TEST(svg_floor_plans_match_geos)
{
    static const char *const plans[] = {
        "building.svg",   "pyinters-Emergency.svg",  "Administration.svg",
        "Delivery.svg",   "InputOutput.svg",         "Laboratories.svg",
        "OutPatient.svg", "PatientServices.svg",     "StaffServices.svg",
        "Surgery.svg",    "hospital2-Emergency.svg", "plan.svg"};
    for (size_t i = 0; i < sizeof plans / sizeof *plans; i++) compare_geos(plans[i]);
}

TEST(svg_emergency_time_vs_geos)
{
    size_t len, gf, gh, gv, ge;
    char *text = data_file("pyinters-Emergency.svg", &len), err[256];
    double best_read = INFINITY, best_arr = INFINITY, best_geos = INFINITY;
    size_t n = 0, nf = 0;
    REQUIRE(text, "pyinters-Emergency.svg unreadable");
    for (int rep = 0; rep < 5; rep++) {
        svg_result r;
        lar2 c;
        double *ga = NULL, gms = 0, t0 = now_ms(), t1, t2;
        REQUIRE(svg_read(text, len, NULL, &r, err, sizeof err) == ARR_OK, "%s", err);
        t1 = now_ms();
        REQUIRE(arr2_build(r.seg, r.n, NULL, &c, err, sizeof err) == ARR_OK, "%s", err);
        t2 = now_ms();
        REQUIRE(geos_ref_faces_timed(r.seg, r.n, &ga, &gf, &gh, &gv, &ge, &gms, err, sizeof err) ==
                    0,
                "GEOS: %s", err);
        best_read = fmin(best_read, t1 - t0);
        best_arr = fmin(best_arr, t2 - t1);
        best_geos = fmin(best_geos, gms);
        n = r.n, nf = c.nf;
        free(ga);
        lar2_free(&c);
        svg_result_free(&r);
    }
    free(text);
    CHECK(nf == gf, "faces %zu, GEOS %zu", nf, gf);
    printf("  pyinters-Emergency.svg: %zu segments, %zu faces; cellar %.2f ms (svg_read %.2f + "
           "arr2_build %.2f), GEOS %.2f ms (node + polygonize of the same segments); best of 5\n",
           n, nf, best_read + best_arr, best_read, best_arr, best_geos);
}

/* ---- drawings with transforms: expectations by hand from the files ------------------------ */

/* The 4 sides of rect (x, y, w, h) through matrix(a, 0, 0, d, e, f). */
static void check_rect(const char *what, const svg_result *r, double a, double d, double e,
                       double f, double x, double y, double w, double h)
{
    double x0 = a * x + e, y0 = d * y + f, x1 = a * (x + w) + e, y1 = d * (y + h) + f;
    double tol = 1e-9 * fmax(fabs(x1), fabs(y1));
    CHECK(has_seg(r, x0, y0, x1, y0, tol) && has_seg(r, x1, y0, x1, y1, tol) &&
              has_seg(r, x1, y1, x0, y1, tol) && has_seg(r, x0, y1, x0, y0, tol),
          "%s: rect (%g %g %g %g) should land at (%g, %g)-(%g, %g)", what, x, y, w, h, x0, y0, x1,
          y1);
}

TEST(svg_shells_rects_land_where_their_matrices_say)
{
    size_t len;
    char *text = data_file("shells.svg", &len);
    svg_result r;
    REQUIRE(text, "shells.svg");
    REQUIRE(rd_ok("shells", text, NULL, &r) == 8, "shells: 8 faces");
    CHECK(r.n == 32 && r.elements == 8, "%zu segments %zu elements", r.n, r.elements);
    check_rect("shells 1", &r, 1, 1, -330, 0, 666.222, 774.561, 860.381, 860.381);
    check_rect("shells 2", &r, 1, 1, 118.097, 425.136, 818.03, 928.596, 170.121, 170.121);
    check_rect("shells 3", &r, 1, 1, -388.69, 441.361, 818.03, 928.596, 170.121, 170.121);
    check_rect("shells 4", &r, 1.54986, 1.46307, -792.441, -370.083, 818.03, 928.596, 170.121,
               170.121);
    check_rect("shells 5", &r, 1, 1, 118.097, -76.56, 818.03, 928.596, 170.121, 170.121);
    check_rect("shells 6", &r, 1.2575, 1.17592, -525.075, -77.7556, 818.03, 928.596, 170.121,
               170.121);
    check_rect("shells 7", &r, 1, 1, 295.675, -82.5912, 245.142, 1131.8, 132.811, 127.522);
    check_rect("shells 8", &r, 0.801663, 0.784297, -607.854, 625.458, 1963.18, 972.318, 137.801,
               137.801);
    svg_result_free(&r);
    free(text);
}

TEST(svg_assembly_drawings_box_openings_wall)
{
    size_t len;
    char *text;
    svg_result r;
    /* box.svg: matrix(0.906472,0,0,0.984921,38.2562,15.1895) on rect 409.035 1007.31 1856.21
     * 1203.34 */
    text = data_file("box.svg", &len);
    REQUIRE(text, "box.svg");
    CHECK(rd_ok("box", text, NULL, &r) == 1, "box: 1 face");
    CHECK(r.n == 4, "box: %zu segments", r.n);
    check_rect("box", &r, 0.906472, 0.984921, 38.2562, 15.1895, 409.035, 1007.31, 1856.21, 1203.34);
    svg_result_free(&r);
    free(text);
    /* openings.svg: matrix(1,0,0,1,0,2): the path's points 2 lower */
    static const double op[6][2] = {{1246.02, 951.262}, {1246.02, 1493.96}, {2241.25, 1493.96},
                                    {2241.25, 1221.14}, {1551.97, 1221.14}, {1551.97, 950.481}};
    text = data_file("openings.svg", &len);
    REQUIRE(text, "openings.svg");
    CHECK(rd_ok("openings", text, NULL, &r) == 1, "openings: 1 face");
    CHECK(r.n == 6, "openings: %zu segments", r.n);
    for (int i = 0; i < 6; i++)
        CHECK(has_seg(&r, op[i][0], op[i][1] + 2, op[(i + 1) % 6][0], op[(i + 1) % 6][1] + 2, 1e-9),
              "openings: side %d", i);
    svg_result_free(&r);
    free(text);
    /* wall.svg: matrix(1.03926,0,0,1.03926,-89.9208,-80.611) on 10 points, closed */
    static const double wp[10][2] = {{540.313, 1109.81}, {540.313, 2129.59}, {2038.65, 2129.59},
                                     {2038.65, 1104.9},  {934.346, 1104.9},  {934.346, 1137.88},
                                     {1990.25, 1137.88}, {1990.25, 2064.15}, {583.951, 2064.15},
                                     {583.951, 1104.1}};
    text = data_file("wall.svg", &len);
    REQUIRE(text, "wall.svg");
    CHECK(rd_ok("wall", text, NULL, &r) == 1, "wall: 1 face");
    CHECK(r.n == 10, "wall: %zu segments", r.n);
    for (int i = 0; i < 10; i++) {
        const double *p = wp[i], *q = wp[(i + 1) % 10], s = 1.03926;
        CHECK(has_seg(&r, s * p[0] - 89.9208, s * p[1] - 80.611, s * q[0] - 89.9208,
                      s * q[1] - 80.611, 1e-9),
              "wall: side %d", i);
    }
    svg_result_free(&r);
    free(text);
}

TEST(svg_lar_curved_new_paths_with_matrices_and_curves)
{
    size_t len;
    char *text;
    svg_result r;
    /* Lar.svg: matrix(22.6,0,0,22.6,-25938.5,-41072.1) */
#define LAR(x, y) 22.6 * (x)-25938.5, 22.6 * (y)-41072.1
    text = data_file("Lar.svg", &len);
    REQUIRE(text, "Lar.svg");
    CHECK(rd_ok("Lar", text, NULL, &r) > 0, "Lar: faces");
    CHECK(r.elements == 5, "Lar: %zu elements", r.elements);
    CHECK(has_seg(&r, LAR(1166.22, 1857.95), LAR(1164.9, 1850.57), 1e-9), "Lar: first L");
    CHECK(has_seg(&r, LAR(1185.61, 1883), LAR(1185.61, 1844.22), 1e-9), "Lar: the L's stem");
    /* the "a": a cubic from (1233.67,1879.53) to (1228.58,1882.7), then the next */
    double x0, y0, x1, y1;
    x0 = 22.6 * 1233.67 - 25938.5, y0 = 22.6 * 1879.53 - 41072.1;
    x1 = 22.6 * 1228.58 - 25938.5, y1 = 22.6 * 1882.7 - 41072.1;
    CHECK(has_end(&r, x0, y0) && has_end(&r, x1, y1), "Lar: the a's first cubic's ends");
    /* its midpoint B(1/2) = (p0 + 3 p1 + 3 p2 + p3) / 8, within the default tolerance */
    double mx = (1233.67 + 3 * 1231.9 + 3 * 1230.21 + 1228.58) / 8;
    double my = (1879.53 + 3 * 1881.03 + 3 * 1882.09 + 1882.7) / 8;
    double tol = 1e-3 * fmax(r.bbox[2] - r.bbox[0], r.bbox[3] - r.bbox[1]);
    CHECK(dist(&r, LAR(mx, my)) <= tol * 1.0001, "Lar: cubic midpoint %g away (tolerance %g)",
          dist(&r, LAR(mx, my)), tol);
    CHECK(r.bbox[0] > 0 && r.bbox[2] < 3508 && r.bbox[1] > 0 && r.bbox[3] < 2481,
          "Lar: inside its viewBox");
    svg_result_free(&r);
    free(text);
#undef LAR
    /* curved.svg and new.svg: the first path in matrix(1,0,0,1,120.646,41.5716), the others
     * not transformed */
    const char *files[2] = {"curved.svg", "new.svg"};
    for (int k = 0; k < 2; k++) {
        text = data_file(files[k], &len);
        REQUIRE(text, "%s", files[k]);
        CHECK(rd_ok(files[k], text, NULL, &r) >= 0, "%s", files[k]);
        CHECK(r.elements == (k ? 5u : 3u), "%s: %zu elements", files[k], r.elements);
        CHECK(has_seg(&r, 919.761 + 120.646, 657.928 + 41.5716, 1111.6 + 120.646, 1299.26 + 41.5716,
                      1e-9),
              "%s: translated side", files[k]);
        CHECK(has_seg(&r, 1930.07, 1024.97, 1954.12, 1301.57, 0), "%s: untransformed side",
              files[k]);
        CHECK(has_end(&r, 1232.24, 1340.84) && has_end(&r, 2047.42, 365.394),
              "%s: the open curve's ends", files[k]);
        CHECK(has_seg(&r, 848.626, 1006.1, 416.549, 805.458, 0), "%s: L between curves", files[k]);
        if (k) CHECK(has_seg(&r, 2931.45, 536.383, 3039.01, 1117.46, 0), "new: last path");
        svg_result_free(&r);
        free(text);
    }
}

/* ---- elements ---------------------------------------------------------------------------- */

TEST(svg_line_rect_polyline_polygon)
{
    svg_result r;
    CHECK(rd_ok("line", DOC("<line x1='1' y1='2' x2='3' y2='4'/>"), NULL, &r) == 0, "line");
    CHECK(r.n == 1 && has_seg(&r, 1, 2, 3, 4, 0) && r.elements == 1, "line segment");
    svg_result_free(&r);
    CHECK(rd_ok("rect", DOC("<rect x='1' y='2' width='3' height='4'/>"), NULL, &r) == 1, "rect");
    CHECK(r.n == 4 && has_seg(&r, 1, 2, 4, 2, 0) && has_seg(&r, 4, 2, 4, 6, 0) &&
              has_seg(&r, 4, 6, 1, 6, 0) && has_seg(&r, 1, 6, 1, 2, 0),
          "rect sides");
    svg_result_free(&r);
    CHECK(rd_ok("diag", DOC("<rect x='1' y='2' width='3' height='4' rx='1'/>"),
                &(svg_opts){.rect_diagonal = 1}, &r) == 0,
          "diagonal");
    CHECK(r.n == 1 && has_seg(&r, 1, 2, 4, 6, 0), "rect diagonal");
    svg_result_free(&r);
    CHECK(rd_ok("zero rect", DOC("<rect width='0' height='4'/>"), NULL, &r) == 0, "zero rect");
    CHECK(r.n == 0 && r.elements == 1 && r.skipped == 0, "a zero-width rect draws nothing");
    svg_result_free(&r);
    CHECK(rd_ok("polyline", DOC("<polyline points='0,0 10,0 10,10'/>"), NULL, &r) == 0, "polyline");
    CHECK(r.n == 2 && has_seg(&r, 0, 0, 10, 0, 0) && has_seg(&r, 10, 0, 10, 10, 0), "polyline");
    svg_result_free(&r);
    CHECK(rd_ok("polygon", DOC("<polygon points='0 0,10 0 10 10'/>"), NULL, &r) == 1, "polygon");
    CHECK(r.n == 3 && has_seg(&r, 10, 10, 0, 0, 0), "polygon closes");
    svg_result_free(&r);
}

TEST(svg_rounded_rect_corners_are_arcs)
{
    svg_result r;
    CHECK(rd_ok("rounded", DOC("<rect x='0' y='0' width='10' height='6' rx='2'/>"),
                &(svg_opts){.flatten_tolerance = 1e-4}, &r) == 1,
          "rounded rect: one face");
    CHECK(r.n > 8 && r.elements == 1 && r.nwarnings == 0, "%zu segments", r.n);
    /* straight parts between the corners, exact */
    CHECK(has_seg(&r, 2, 0, 8, 0, 0) && has_seg(&r, 10, 2, 10, 4, 0) &&
              has_seg(&r, 8, 6, 2, 6, 0) && has_seg(&r, 0, 4, 0, 2, 0),
          "rounded rect sides");
    /* the corner arcs: ry = rx = 2 when only rx is given; the 45 degree point of each */
    double h = 2 - 2 / sqrt(2);
    CHECK(dist(&r, 8 + 2 - h, h) < 1.1e-4 && dist(&r, h, 6 - h) < 1.1e-4, "corner arcs");
    CHECK(dist(&r, 0, 0) > 0.5, "no sharp corner");
    svg_result_free(&r);
    /* rx beyond half the width is clamped: a stadium */
    CHECK(rd_ok("clamped", DOC("<rect width='10' height='4' rx='9' ry='2'/>"), NULL, &r) == 1,
          "clamped");
    CHECK(has_end(&r, 5, 0) && has_end(&r, 5, 4) && dist(&r, 0, 2) < 1e-3, "clamped to a stadium");
    svg_result_free(&r);
}

TEST(svg_circle_and_ellipse)
{
    svg_result r;
    CHECK(rd_ok("circle", DOC("<circle cx='5' cy='6' r='2'/>"),
                &(svg_opts){.flatten_tolerance = 1e-3}, &r) == 1,
          "circle: one face");
    CHECK(r.n >= 8 && r.n <= SVG_MAX_SEGMENTS, "circle: %zu chords", r.n);
    CHECK(off_circle(&r, 5, 6, 2) < 1e-12, "circle vertices on the circle (%g)",
          off_circle(&r, 5, 6, 2));
    /* chords within the tolerance: each chord's midpoint at least r - tol from the centre */
    double worst = 0;
    for (size_t i = 0; i < r.n; i++) {
        const double *s = r.seg + 4 * i;
        worst = fmax(worst, 2 - hypot((s[0] + s[2]) / 2 - 5, (s[1] + s[3]) / 2 - 6));
    }
    CHECK(worst <= 1e-3 && worst > 1e-4, "sagitta %g for tolerance 1e-3", worst);
    CHECK(has_end(&r, 7, 6), "starts at angle 0");
    svg_result_free(&r);
    CHECK(rd_ok("ellipse", DOC("<ellipse cx='1' cy='2' rx='4' ry='1'/>"), NULL, &r) == 1,
          "ellipse");
    double e = 0;
    for (size_t i = 0; i < 2 * r.n; i++) {
        double x = (r.seg[2 * i] - 1) / 4, y = r.seg[2 * i + 1] - 2;
        e = fmax(e, fabs(x * x + y * y - 1));
    }
    CHECK(e < 1e-12, "ellipse vertices on the ellipse (%g)", e);
    svg_result_free(&r);
    CHECK(rd_ok("r0", DOC("<circle r='0'/><ellipse rx='1' ry='0'/>"), NULL, &r) == 0, "r=0");
    CHECK(r.n == 0 && r.skipped == 0, "zero radius draws nothing");
    svg_result_free(&r);
    /* a tiny tolerance on a huge circle: the chord count is bounded */
    CHECK(rd_ok("huge", DOC("<circle r='1e6'/>"), &(svg_opts){.flatten_tolerance = 1e-12}, &r) == 1,
          "huge circle");
    CHECK(r.n == 4096, "huge circle: %zu chords, want the bound 4096", r.n);
    svg_result_free(&r);
}

/* ---- path commands ------------------------------------------------------------------------ */

TEST(svg_path_lines_absolute_relative_implicit)
{
    svg_result r;
    CHECK(rd_ok("MLHVZ", DOC("<path d='M 10 10 L 20 10 H 30 V 20 Z'/>"), NULL, &r) == 1, "MLHVZ");
    CHECK(r.n == 4 && has_seg(&r, 10, 10, 20, 10, 0) && has_seg(&r, 20, 10, 30, 10, 0) &&
              has_seg(&r, 30, 10, 30, 20, 0) && has_seg(&r, 30, 20, 10, 10, 0),
          "MLHVZ segments");
    svg_result_free(&r);
    CHECK(rd_ok("mlhvz", DOC("<path d='m 10 10 l 10 0 h 10 v 10 z'/>"), NULL, &r) == 1, "mlhvz");
    CHECK(r.n == 4 && has_seg(&r, 20, 10, 30, 10, 0) && has_seg(&r, 30, 20, 10, 10, 0),
          "relative segments");
    svg_result_free(&r);
    /* implicit repeats: after M pairs are L, after m pairs are l */
    rd_ok("M implicit", DOC("<path d='M 0 0 10 10 20 0'/>"), NULL, &r);
    CHECK(r.n == 2 && has_seg(&r, 0, 0, 10, 10, 0) && has_seg(&r, 10, 10, 20, 0, 0),
          "M 0 0 10 10 20 0");
    svg_result_free(&r);
    rd_ok("m implicit", DOC("<path d='m 1 1 2 2 3 0'/>"), NULL, &r);
    CHECK(r.n == 2 && has_seg(&r, 1, 1, 3, 3, 0) && has_seg(&r, 3, 3, 6, 3, 0), "m 1 1 2 2 3 0");
    svg_result_free(&r);
    rd_ok("L implicit", DOC("<path d='M0 0 L 1 1 2 0 h 1 1 v 1 -2'/>"), NULL, &r);
    CHECK(r.n == 6 && has_seg(&r, 2, 0, 3, 0, 0) && has_seg(&r, 3, 0, 4, 0, 0) &&
              has_seg(&r, 4, 0, 4, 1, 0) && has_seg(&r, 4, 1, 4, -1, 0),
          "implicit L, h, v");
    svg_result_free(&r);
    /* z returns to the subpath's start; a relative m after z starts from there */
    rd_ok("subpaths", DOC("<path d='M 0 0 L 10 0 L 10 10 z m 20 0 l 5 0 M 1 1 L 2 2 Z L 0 5'/>"),
          NULL, &r);
    CHECK(has_seg(&r, 10, 10, 0, 0, 0) && has_seg(&r, 20, 0, 25, 0, 0) &&
              has_seg(&r, 2, 2, 1, 1, 0) && has_seg(&r, 1, 1, 0, 5, 0) && r.n == 7,
          "subpaths: %zu segments", r.n);
    svg_result_free(&r);
    /* numbers: exponents, ".5.5", "-1-2", "1.5.5", signs; commas and whitespace anywhere */
    rd_ok("numbers", DOC("<path d='M1e-3,2L.5.5M-1-2L0 0M1.5.5L+3E+1,1e1'/>"), NULL, &r);
    CHECK(r.n == 3 && has_seg(&r, 1e-3, 2, 0.5, 0.5, 0) && has_seg(&r, -1, -2, 0, 0, 0) &&
              has_seg(&r, 1.5, 0.5, 30, 10, 0),
          "numbers: %zu segments", r.n);
    svg_result_free(&r);
    rd_ok("separators", DOC("<path d=' M,0,0,L\t1\n,\r1 ,, 2 0 '/>"), NULL, &r);
    CHECK(r.n == 2 && has_seg(&r, 0, 0, 1, 1, 0) && has_seg(&r, 1, 1, 2, 0, 0) && r.skipped == 0,
          "commas and whitespace anywhere");
    svg_result_free(&r);
}

TEST(svg_path_curves_and_smooth_reflection)
{
    svg_result r;
    svg_opts o = {.flatten_tolerance = 1e-5};
    /* C then S: S's first control point is C's second reflected about the current point */
    rd_ok("CS", DOC("<path d='M0 0 C 0 10 10 10 10 0 S 20 -10 20 0'/>"), &o, &r);
    CHECK(has_end(&r, 0, 0) && has_end(&r, 10, 0) && has_end(&r, 20, 0), "C S ends");
    CHECK(dist(&r, 5, 7.5) < 2e-5, "C midpoint (5, 7.5): %g", dist(&r, 5, 7.5));
    CHECK(dist(&r, 15, -7.5) < 2e-5, "S midpoint (15, -7.5) with the reflected control: %g",
          dist(&r, 15, -7.5));
    svg_result_free(&r);
    /* relative c and s */
    rd_ok("cs", DOC("<path d='m0 0 c 0 10 10 10 10 0 s 10 -10 10 0'/>"), &o, &r);
    CHECK(dist(&r, 5, 7.5) < 2e-5 && dist(&r, 15, -7.5) < 2e-5 && has_end(&r, 20, 0), "c s");
    svg_result_free(&r);
    /* S after a line: its first control point is the current point */
    rd_ok("LS", DOC("<path d='M0 0 L 10 0 S 20 10 20 0'/>"), &o, &r);
    /* B(1/2) with p0 = p1 = (10, 0), p2 = (20, 10), p3 = (20, 0): (10 + 30 + 60 + 20) / 8 */
    CHECK(dist(&r, 15, 3.75) < 2e-5, "S after L: %g", dist(&r, 15, 3.75));
    svg_result_free(&r);
    /* Q then T reflecting Q's control point; then relative q and t */
    rd_ok("QT", DOC("<path d='M0 0 Q 5 10 10 0 T 20 0'/>"), &o, &r);
    CHECK(dist(&r, 5, 5) < 2e-5 && dist(&r, 15, -5) < 2e-5 && has_end(&r, 20, 0), "Q T");
    svg_result_free(&r);
    rd_ok("qt", DOC("<path d='m0 0 q 5 10 10 0 t 10 0 t 10 0'/>"), &o, &r);
    CHECK(dist(&r, 15, -5) < 2e-5 && dist(&r, 25, 5) < 2e-5 && has_end(&r, 30, 0), "q t t");
    svg_result_free(&r);
    /* T after a line is a straight piece */
    rd_ok("LT", DOC("<path d='M0 0 L 10 0 T 20 0'/>"), &o, &r);
    CHECK(r.n == 2 && has_seg(&r, 10, 0, 20, 0, 0), "T after L: %zu segments", r.n);
    svg_result_free(&r);
    /* implicit repeated C */
    rd_ok("CC", DOC("<path d='M0 0 C 0 10 10 10 10 0 10 -10 20 -10 20 0'/>"), &o, &r);
    CHECK(has_end(&r, 10, 0) && has_end(&r, 20, 0) && dist(&r, 15, -7.5) < 2e-5, "C repeated");
    svg_result_free(&r);
}

/* One arc from (0,0) to (2,0) of radius 2 with the given flags: centre (1, cy) and the point
 * (1, my) the arc passes through (computed by hand: |fA - fS| picks the centre, the sweep the
 * side). */
static void check_arc(const char *d, double cy, double my)
{
    char doc[256];
    svg_result r;
    snprintf(doc, sizeof doc, DOC("<path d='%s'/>"), d);
    rd_ok(d, doc, &(svg_opts){.flatten_tolerance = 1e-6}, &r);
    CHECK(has_end(&r, 0, 0) && has_end(&r, 2, 0), "%s: endpoints exact", d);
    CHECK(off_circle(&r, 1, cy, 2) < 1e-12, "%s: vertices on the circle about (1, %g): %g", d, cy,
          off_circle(&r, 1, cy, 2));
    CHECK(dist(&r, 1, my) < 2e-6, "%s: passes through (1, %g): %g", d, my, dist(&r, 1, my));
    /* and not through the opposite point of the circle */
    CHECK(dist(&r, 1, 2 * cy - my) > 1, "%s: drew the wrong side", d);
    svg_result_free(&r);
}

TEST(svg_path_arcs_all_flags)
{
    double s3 = sqrt(3);
    check_arc("M0 0 A 2 2 0 0 1 2 0", s3, s3 - 2);  /* small, positive sweep: above */
    check_arc("M0 0 A 2 2 0 1 0 2 0", s3, s3 + 2);  /* large, negative sweep */
    check_arc("M0 0 A 2 2 0 0 0 2 0", -s3, 2 - s3); /* small, negative sweep: below */
    check_arc("M0 0 A 2 2 0 1 1 2 0", -s3, -s3 - 2);
    /* flags without separators, relative */
    check_arc("M0 0 a2,2 0 012,0", s3, s3 - 2);
    check_arc("M0 0a2 2 0 11 2 0", -s3, -s3 - 2);
    svg_result r;
    /* radii too small are scaled up: a half circle of radius 1 about (1, 0) */
    rd_ok("small", DOC("<path d='M0 0 A 0.5 0.5 0 0 1 2 0'/>"),
          &(svg_opts){.flatten_tolerance = 1e-6}, &r);
    CHECK(off_circle(&r, 1, 0, 1) < 1e-12 && dist(&r, 1, -1) < 2e-6 && has_end(&r, 2, 0),
          "radii scaled up");
    svg_result_free(&r);
    /* a zero radius is a line; equal endpoints draw nothing */
    rd_ok("zero", DOC("<path d='M0 0 A 0 5 0 0 1 2 0 A 3 3 0 0 1 2 0'/>"), NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 0, 0, 2, 0, 0), "zero radius: %zu segments", r.n);
    svg_result_free(&r);
    /* rotated ellipse: semi-axes 2 (along y after rotating 90) and 1, across its major axis */
    rd_ok("rotated", DOC("<path d='M0 0 A 2 1 90 0 1 0 4'/>"),
          &(svg_opts){.flatten_tolerance = 1e-6}, &r);
    double e = 0;
    for (size_t i = 0; i < 2 * r.n; i++) {
        double x = r.seg[2 * i], y = (r.seg[2 * i + 1] - 2) / 2;
        e = fmax(e, fabs(x * x + y * y - 1));
    }
    CHECK(e < 1e-12 && has_end(&r, 0, 4), "rotated ellipse arc: %g", e);
    /* sweep 1 turns clockwise on screen (y down): from the top, through the right */
    CHECK(dist(&r, 1, 2) < 2e-6, "sweep 1 goes through (1, 2): %g", dist(&r, 1, 2));
    svg_result_free(&r);
}

TEST(svg_path_errors_draw_up_to_the_error)
{
    svg_result r;
    rd_ok("bad number", DOC("<path d='M 0 0 L 10 0 L 10 x 20'/>"), NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 0, 0, 10, 0, 0), "drawn up to the error: %zu", r.n);
    CHECK(r.skipped == 1 && r.elements == 0 && has_warning(&r, "line 1: <path>: d:") &&
              has_warning(&r, "offset 13"),
          "warned: %s", r.nwarnings ? r.warning[0] : "(none)");
    svg_result_free(&r);
    rd_ok("no M", DOC("<path d='L 1 1'/>"), NULL, &r);
    CHECK(r.n == 0 && r.skipped == 1 && has_warning(&r, "must start with M"), "no M");
    svg_result_free(&r);
    rd_ok("after Z", DOC("<path d='M0 0 L1 0 L1 1 Z 5 5'/>"), NULL, &r);
    CHECK(r.n == 3 && r.skipped == 1 && has_warning(&r, "after Z"), "number after Z");
    svg_result_free(&r);
    rd_ok("bad flag", DOC("<path d='M0 0 L 1 0 A 1 1 0 2 1 2 0'/>"), NULL, &r);
    CHECK(r.n == 1 && has_warning(&r, "arc flag"), "arc flag 2");
    svg_result_free(&r);
    rd_ok("short", DOC("<path d='M0 0 L 1 0 C 1 1 2 2'/>"), NULL, &r);
    CHECK(r.n == 1 && r.skipped == 1, "missing coordinates");
    svg_result_free(&r);
    rd_ok("empty d", DOC("<path d=''/><path/>"), NULL, &r);
    CHECK(r.n == 0 && r.skipped == 0 && r.elements == 2, "empty path data is no error");
    svg_result_free(&r);
    rd_ok("huge", DOC("<path d='M0 0 L 1e999 0'/>"), NULL, &r);
    CHECK(r.n == 0 && has_warning(&r, "beyond the range"), "1e999");
    svg_result_free(&r);
}

/* ---- transforms ---------------------------------------------------------------------------- */

/* The line (1,0)-(0,1) under transform t lands at (x1,y1)-(x2,y2). */
static void check_transform(const char *t, double x1, double y1, double x2, double y2)
{
    char doc[512];
    svg_result r;
    snprintf(doc, sizeof doc, DOC("<line x1='1' y1='0' x2='0' y2='1' transform='%s'/>"), t);
    rd_ok(t, doc, NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, x1, y1, x2, y2, 1e-12), "%s: got (%g,%g)-(%g,%g)", t,
          r.n ? r.seg[0] : NAN, r.n ? r.seg[1] : NAN, r.n ? r.seg[2] : NAN, r.n ? r.seg[3] : NAN);
    svg_result_free(&r);
}

TEST(svg_transforms_each_type_and_lists)
{
    check_transform("translate(5)", 6, 0, 5, 1);
    check_transform("translate(5,6)", 6, 6, 5, 7);
    check_transform("translate(5 -6)", 6, -6, 5, -5);
    check_transform("scale(2)", 2, 0, 0, 2);
    check_transform("scale(2,3)", 2, 0, 0, 3);
    check_transform("rotate(90)", 0, 1, -1, 0);
    check_transform("rotate(-90)", 0, -1, 1, 0);
    check_transform("rotate(180, 1, 1)", 1, 2, 2, 1);
    check_transform("rotate(30)", cos(M_PI / 6), sin(M_PI / 6), -sin(M_PI / 6), cos(M_PI / 6));
    check_transform("skewX(45)", 1, 0, 1, 1);
    check_transform("skewY(45)", 1, 1, 0, 1);
    check_transform("matrix(1,2,3,4,5,6)", 6, 8, 8, 10);
    check_transform("matrix(1 2 3 4 5 6)", 6, 8, 8, 10);
    /* lists apply right to left to the point */
    check_transform("translate(10,0) scale(2)", 12, 0, 10, 2);
    check_transform("scale(2) translate(10,0)", 22, 0, 20, 2);
    check_transform("translate(10 0),scale(2)", 12, 0, 10, 2);
    check_transform("  rotate(90)translate(1,0)  ", 0, 2, -1, 1);
    /* composed through nested groups */
    svg_result r;
    rd_ok("nested g",
          DOC("<g transform='translate(10,0)'><g transform='scale(2)'>"
              "<line x1='1' y1='0' x2='0' y2='1' transform='rotate(90)'/></g></g>"),
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 10, 2, 8, 0, 1e-12), "nested groups");
    svg_result_free(&r);
    /* bad transforms: the element is skipped with a warning naming the problem */
    rd_ok("bad",
          DOC("<line x2='1' transform='rotate(1,2)'/><line x2='1' transform='spin(3)'/>"
              "<g transform='scale()'><line x2='1'/></g><line x2='1' transform='skewX(90)'/>"),
          NULL, &r);
    CHECK(r.n == 0 && r.skipped == 4 && has_warning(&r, "rotate takes 1 or 3 arguments, not 2") &&
              has_warning(&r, "unknown transform") && has_warning(&r, "scale takes") &&
              has_warning(&r, "not finite"),
          "bad transforms: %zu segments, %zu skipped", r.n, r.skipped);
    svg_result_free(&r);
}

TEST(svg_nested_svg_viewbox_and_root_viewbox)
{
    svg_result r;
    /* meet: scale min(100/10, 50/10) = 5, centred in x: 10 + (100 - 50) / 2 */
    rd_ok("meet",
          DOC("<svg x='10' y='20' width='100' height='50' viewBox='0 0 10 10'>"
              "<line x1='0' y1='0' x2='10' y2='10'/></svg>"),
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 35, 20, 85, 70, 1e-12), "xMidYMid meet");
    svg_result_free(&r);
    rd_ok("none",
          DOC("<svg x='10' y='20' width='100' height='50' viewBox='0 0 10 10' "
              "preserveAspectRatio='none'><line x1='0' y1='0' x2='10' y2='10'/></svg>"),
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 10, 20, 110, 70, 1e-12), "none");
    svg_result_free(&r);
    rd_ok("slice",
          DOC("<svg x='10' y='20' width='100' height='50' viewBox='0 0 10 10' "
              "preserveAspectRatio='xMinYMax slice'><line x1='0' y1='0' x2='10' y2='10'/></svg>"),
          NULL, &r);
    /* slice: scale 10, the content 100 x 100 aligned at the bottom: ty = 20 + 50 - 100 */
    CHECK(r.n == 1 && has_seg(&r, 10, -30, 110, 70, 1e-12), "xMinYMax slice");
    svg_result_free(&r);
    rd_ok("viewBox origin",
          DOC("<svg width='20' height='20' viewBox='5 5 10 10'><line x1='5' y1='5' x2='15' "
              "y2='5'/></svg>"),
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 0, 0, 20, 0, 1e-12), "viewBox origin");
    svg_result_free(&r);
    rd_ok("no viewBox", DOC("<svg x='3' y='4'><line x1='0' y1='0' x2='1' y2='0'/></svg>"), NULL,
          &r);
    CHECK(r.n == 1 && has_seg(&r, 3, 4, 4, 4, 0), "nested svg without viewBox: translated");
    svg_result_free(&r);
    /* percentages of the nested viewport: of the root's viewBox */
    rd_ok("percent",
          "<svg " NS " viewBox='0 0 200 100'><svg width='50%' height='100%' viewBox='0 0 1 1'>"
          "<line x1='0' y1='0' x2='1' y2='1'/></svg></svg>",
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 0, 0, 100, 100, 1e-12), "percent width");
    svg_result_free(&r);
    /* the root's viewBox only defines the user space: coordinates are kept */
    rd_ok("root",
          "<svg " NS " width='500' height='500' viewBox='100 100 10 10'>"
          "<line x1='100' y1='101' x2='110' y2='101'/></svg>",
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 100, 101, 110, 101, 0), "root viewBox kept");
    svg_result_free(&r);
    rd_ok("zero", DOC("<svg width='0'><line x2='1'/></svg>"), NULL, &r);
    CHECK(r.n == 0 && r.skipped == 0, "zero-width nested svg draws nothing");
    svg_result_free(&r);
}

TEST(svg_use_symbol_cycles_and_limits)
{
    svg_result r;
    char err[256];
    rd_ok("use",
          DOC("<defs><rect id='r' width='2' height='1'/></defs><use href='#r' x='10' y='20'/>"),
          NULL, &r);
    CHECK(r.n == 4 && has_seg(&r, 10, 20, 12, 20, 0) && has_seg(&r, 12, 20, 12, 21, 0),
          "use of a rect in defs: %zu", r.n);
    svg_result_free(&r);
    rd_ok("xlink",
          "<svg " NS " xmlns:xlink='http://www.w3.org/1999/xlink'><line id='l' x2='1'/>"
          "<use xlink:href='#l' transform='scale(2)' x='1'/></svg>",
          NULL, &r);
    /* the use's x, y come after its transform: (0,0) -> scale(2) translate(1,0) -> (2, 0) */
    CHECK(r.n == 2 && has_seg(&r, 0, 0, 1, 0, 0) && has_seg(&r, 2, 0, 4, 0, 0) && r.elements == 2,
          "xlink:href, transform then x: %zu", r.n);
    svg_result_free(&r);
    rd_ok("symbol",
          DOC("<symbol id='s' viewBox='0 0 1 1'><line x2='1' y2='1'/></symbol>"
              "<use href='#s' x='5' y='5' width='10' height='10'/>"),
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 5, 5, 15, 15, 1e-12), "symbol sized by the use");
    svg_result_free(&r);
    rd_ok("group",
          DOC("<g id='g' transform='translate(1,0)'><line x2='1'/><line y2='1'/></g>"
              "<use href='#g' y='10'/>"),
          NULL, &r);
    CHECK(r.n == 4 && has_seg(&r, 1, 10, 2, 10, 0) && has_seg(&r, 1, 10, 1, 11, 0),
          "use of a group keeps its transform");
    svg_result_free(&r);
    /* cycles: a use inside what it refers to, and two uses referring to each other */
    rd_ok("self", DOC("<g id='a'><line x2='1'/><use href='#a'/></g>"), NULL, &r);
    CHECK(r.n == 1 && r.skipped == 1 && has_warning(&r, "cycle"), "self reference");
    svg_result_free(&r);
    rd_ok("mutual", DOC("<use id='a' href='#b'/><use id='b' href='#a'/><line x2='1'/>"), NULL, &r);
    CHECK(r.n == 1 && r.skipped >= 1 && has_warning(&r, "cycle"), "mutual reference");
    svg_result_free(&r);
    rd_ok("missing", DOC("<use href='#nope'/><use href='other.svg#x'/>"), NULL, &r);
    CHECK(r.skipped == 2 && has_warning(&r, "no element has this id") &&
              has_warning(&r, "only local references"),
          "missing and external references");
    svg_result_free(&r);
    /* exponential expansion: 2^30 lines through 30 levels of two uses: refused by the limit */
    {
        char *doc = malloc(8192);
        size_t w = (size_t)sprintf(doc, "<svg %s><defs><line id='g0' x2='1'/>", NS);
        for (int i = 1; i <= 30; i++)
            w += (size_t)sprintf(doc + w,
                                 "<g id='g%d'><use href='#g%d'/><use href='#g%d' "
                                 "y='%d'/></g>",
                                 i, i - 1, i - 1, i);
        sprintf(doc + w, "</defs><use href='#g30'/></svg>");
        double t0 = now_ms();
        int rc = rd(doc, NULL, &r, err, sizeof err);
        CHECK(rc == ARR_ELIMIT && strstr(err, "max_elements") && strstr(err, "<use>"),
              "use bomb: %d %s", rc, err);
        CHECK(now_ms() - t0 < 10000, "use bomb took %.0f ms", now_ms() - t0);
        free(doc);
    }
    /* a chain of uses deeper than max_depth */
    {
        char doc[4096];
        size_t w = (size_t)sprintf(doc, "<svg %s><line id='u0' x2='1'/>", NS);
        for (int i = 1; i <= 20; i++)
            w += (size_t)sprintf(doc + w, "<use id='u%d' href='#u%d'/>", i, i - 1);
        sprintf(doc + w, "</svg>");
        int rc = rd(doc, &(svg_opts){.max_depth = 10}, &r, err, sizeof err);
        CHECK(rc == ARR_ELIMIT && strstr(err, "max_depth"), "use chain: %d %s", rc, err);
        rc = rd(doc, NULL, &r, err, sizeof err);
        /* the line, and once more through each of the 20 uses */
        CHECK(rc == ARR_OK && r.n == 21 && r.elements == 21, "use chain within the limit: %d %s",
              rc, err);
        svg_result_free(&r);
    }
}

TEST(svg_units_display_defs_switch)
{
    svg_result r;
    rd_ok("units", DOC("<line x1='10mm' x2='4px' y2=' 2 '/>"), NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 10 * 96 / 25.4, 0, 4, 2, 1e-12), "mm and px");
    svg_result_free(&r);
    rd_ok("units2", DOC("<line x1='1in' y1='72pt' x2='2.54cm' y2='7pc'/>"), NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 96, 96, 96, 112, 1e-12), "in pt cm pc");
    svg_result_free(&r);
    rd_ok("percent", DOC("<line x1='10%' x2='1'/><circle r='2em'/><rect width='3ex' height='1'/>"),
          NULL, &r);
    CHECK(r.n == 0 && r.skipped == 3 && has_warning(&r, "lengths in % are not supported") &&
              has_warning(&r, "em/ex"),
          "%% and em/ex skipped with warnings");
    svg_result_free(&r);
    rd_ok("display",
          DOC("<line x2='1' display='none'/><line x2='2' style='stroke:red; display : none'/>"
              "<g style='display:none !important'><line x2='3'/></g>"
              "<line x2='4' display='none' style='display:inline'/><line x2='5' display=' inline "
              "'/>"),
          NULL, &r);
    CHECK(r.n == 2 && has_seg(&r, 0, 0, 4, 0, 0) && has_seg(&r, 0, 0, 5, 0, 0) && r.skipped == 0,
          "display: %zu", r.n);
    svg_result_free(&r);
    rd_ok("not drawn",
          DOC("<defs><line x2='1'/></defs><symbol><line x2='2'/></symbol>"
              "<clipPath><rect width='1' height='1'/></clipPath><mask><line x2='3'/></mask>"
              "<marker><line x2='4'/></marker><pattern><line x2='5'/></pattern>"
              "<text x='1'>hi</text><line x2='6'/>"),
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 0, 0, 6, 0, 0) && r.elements == 1, "defs & co not drawn");
    svg_result_free(&r);
    rd_ok("switch",
          DOC("<switch><foreignObject "
              "requiredExtensions='http://ns.adobe.com/AdobeIllustrator/10.0/'>"
              "<line x2='1'/></foreignObject><g><line x2='2'/></g><g><line x2='3'/></g></switch>"),
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 0, 0, 2, 0, 0), "switch: the first child that applies");
    svg_result_free(&r);
    /* foreign namespaces draw nothing; a no-namespace root is fine */
    rd_ok("foreign",
          "<svg xmlns:i='urn:x'><i:line x2='1'/><line x2='2'/><a><line x2='3'/></a></svg>", NULL,
          &r);
    CHECK(r.n == 2 && has_seg(&r, 0, 0, 2, 0, 0) && has_seg(&r, 0, 0, 3, 0, 0), "foreign: %zu",
          r.n);
    svg_result_free(&r);
}

TEST(svg_unreadable_elements_are_skipped_and_warned)
{
    svg_result r;
    rd_ok("nan",
          DOC("<line x1='NaN' x2='1'/><line x2='inf'/><rect width='1e999' height='1'/>"
              "<circle r='-1'/><rect width='-2' height='1'/><line x1='1 2' x2='3'/><line x2='7'/>"),
          NULL, &r);
    CHECK(r.n == 1 && r.elements == 1 && r.skipped == 6, "%zu segments, %zu skipped", r.n,
          r.skipped);
    CHECK(has_warning(&r, "line 1: <line>: x1=\"NaN\" is not a finite number") &&
              has_warning(&r, "x2=\"inf\"") && has_warning(&r, "1e999") &&
              has_warning(&r, "negative radius") && has_warning(&r, "negative width"),
          "warnings name the attribute: %s", r.nwarnings ? r.warning[0] : "");
    svg_result_free(&r);
    rd_ok("odd", DOC("<polygon points='0 0 10 0 10 10 0'/><polyline points='0 0 5 NaN'/>"), NULL,
          &r);
    CHECK(r.skipped == 2 && has_warning(&r, "odd number of coordinates") &&
              has_warning(&r, "not a number"),
          "odd coordinates");
    CHECK(r.n == 3 && has_seg(&r, 10, 10, 0, 0, 0), "polygon drawn up to the error, closed");
    svg_result_free(&r);
    /* more warnings than slots: the last says how many more */
    {
        char doc[4096];
        size_t w = (size_t)sprintf(doc, "<svg %s>", NS);
        for (int i = 0; i < 20; i++) w += (size_t)sprintf(doc + w, "<line x1='bad%d'/>", i);
        sprintf(doc + w, "</svg>");
        rd_ok("many", doc, NULL, &r);
        CHECK(r.skipped == 20 && r.nwarnings == SVG_MAX_WARNINGS &&
                  strstr(r.warning[SVG_MAX_WARNINGS - 1], "5 more warnings (20 in all)"),
              "overflow: %zu %s", r.nwarnings, r.warning[SVG_MAX_WARNINGS - 1]);
        svg_result_free(&r);
    }
}

TEST(svg_normalize_y_up_tolerance_and_limits)
{
    svg_result r;
    char err[256];
    const char *doc = DOC("<rect x='10' y='20' width='20' height='40'/>");
    rd_ok("normalize", doc, &(svg_opts){.normalize = 1}, &r);
    /* bbox (10,20)-(30,60), s = 40: x' = (x - 10) / 40, y' = (60 - y) / 40 */
    CHECK(has_seg(&r, 0, 1, 0.5, 1, 0) && has_seg(&r, 0.5, 1, 0.5, 0, 0) &&
              has_seg(&r, 0, 0, 0, 1, 0),
          "normalized rect");
    CHECK(r.transform[0] == 1.0 / 40 && r.transform[1] == 0 && r.transform[2] == 0 &&
              r.transform[3] == -1.0 / 40 && r.transform[4] == -10.0 / 40 &&
              r.transform[5] == 60.0 / 40,
          "transform %g %g %g %g %g %g", r.transform[0], r.transform[1], r.transform[2],
          r.transform[3], r.transform[4], r.transform[5]);
    CHECK(r.bbox[0] == 10 && r.bbox[1] == 20 && r.bbox[2] == 30 && r.bbox[3] == 60, "bbox");
    svg_result_free(&r);
    rd_ok("y_up", doc, &(svg_opts){.y_up = 1}, &r);
    CHECK(has_seg(&r, 10, -20, 30, -20, 0) && r.transform[0] == 1 && r.transform[3] == -1 &&
              r.transform[4] == 0 && r.transform[5] == 0,
          "y_up");
    svg_result_free(&r);
    rd_ok("identity", doc, NULL, &r);
    CHECK(r.transform[0] == 1 && r.transform[3] == 1 && r.transform[1] == 0 &&
              r.transform[2] == 0 && r.transform[4] == 0 && r.transform[5] == 0,
          "identity");
    svg_result_free(&r);
    /* default tolerance: 1e-3 of the drawing's size */
    rd_ok("default tol", DOC("<circle r='100'/><line x1='-100' x2='900'/>"), NULL, &r);
    double worst = 0;
    for (size_t i = 0; i < r.n; i++) {
        const double *s = r.seg + 4 * i;
        if (s[1] == 0 && s[3] == 0) continue;
        worst = fmax(worst, 100 - hypot((s[0] + s[2]) / 2, (s[1] + s[3]) / 2));
    }
    CHECK(worst <= 1.0 && worst > 0.1, "sagitta %g for the default tolerance 1", worst);
    svg_result_free(&r);
    /* limits, each named */
    int rc = rd(DOC("<line x2='1'/><line x2='2'/><line x2='3'/>"), &(svg_opts){.max_segments = 2},
                &r, err, sizeof err);
    CHECK(rc == ARR_ELIMIT && strstr(err, "max_segments"), "segments: %d %s", rc, err);
    CHECK(r.n == 0 && r.seg == NULL, "empty on error");
    rc = rd(DOC("<circle r='1'/>"), &(svg_opts){.max_segments = 5}, &r, err, sizeof err);
    CHECK(rc == ARR_ELIMIT && strstr(err, "max_segments") && strstr(err, "flattened"),
          "flattened segments: %d %s", rc, err);
    rc = rd(DOC("<g><g><line/></g></g><line/>"), &(svg_opts){.max_elements = 3}, &r, err,
            sizeof err);
    CHECK(rc == ARR_ELIMIT && strstr(err, "max_elements") && strstr(err, "line 1, column"),
          "elements: %d %s", rc, err);
    rc = rd(DOC("<g><g><g><line/></g></g></g>"), &(svg_opts){.max_depth = 3}, &r, err, sizeof err);
    CHECK(rc == ARR_ELIMIT && strstr(err, "max_depth") && strstr(err, "line 1, column"),
          "depth: %d %s", rc, err);
    rc = rd(DOC("<path d='M0 0 h1 1 1 1'/><path d='M0 0 1 1'/>"),
            &(svg_opts){.max_path_commands = 5}, &r, err, sizeof err);
    CHECK(rc == ARR_ELIMIT && strstr(err, "max_path_commands"), "commands: %d %s", rc, err);
    rc = rd(DOC("<line/>"), &(svg_opts){.flatten_tolerance = -1}, &r, err, sizeof err);
    CHECK(rc == ARR_EINVAL && strstr(err, "flatten_tolerance"), "bad tolerance: %d %s", rc, err);
}

/* ---- malformed and hostile input ---------------------------------------------------------- */

/* The process's peak resident size so far, in MB. */
static double peak_mb(void)
{
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return (double)u.ru_maxrss / 1024;
}

/* text must be refused with code and a message containing each of the needles; prints the time
 * and how much the peak resident size grew (an upper bound of what the read used). */
static void refused(const char *what, const char *text, size_t len, int code, const char *n1,
                    const char *n2)
{
    svg_result r;
    char err[256] = "";
    double t0 = now_ms(), m0 = peak_mb();
    int rc = svg_read(text, len, NULL, &r, err, sizeof err);
    double ms = now_ms() - t0, grew = peak_mb() - m0;
    CHECK(rc == code, "%s: code %d, want %d (%s)", what, rc, code, err);
    CHECK(strstr(err, n1) && (!n2 || strstr(err, n2)), "%s: message \"%s\" lacks \"%s\"/\"%s\"",
          what, err, n1, n2 ? n2 : "");
    CHECK(r.n == 0 && r.seg == NULL && r.nwarnings == 0, "%s: result not empty", what);
    for (const char *p = err; *p; p++) CHECK(*p >= 0x20 && *p < 0x7f, "%s: unprintable", what);
    /* bounded: libxml2's tree and our arrays, far below what the input could expand to */
    CHECK(getenv("CELLAR_SANITIZED") || grew < 400, "%s: peak memory grew by %.0f MB", what, grew);
    printf("  %s: %.1f ms, peak +%.0f MB: %s\n", what, ms, grew, err);
}

#define REFUSED(what, text, code, n1, n2) refused(what, text, strlen(text), code, n1, n2)

TEST(svg_malformed_xml_names_line_and_column)
{
    REFUSED("unclosed tag", "<svg " NS ">\n<g>\n  <line x1=\"0\"/>\n</svg>\n", ARR_EINVAL,
            "line 4, column 7", "mismatch");
    REFUSED("truncated", "<svg " NS "><line x1='0'", ARR_EINVAL, "line 1, column", NULL);
    REFUSED("bad attribute", "<svg " NS ">\n<line x1=0/></svg>", ARR_EINVAL, "line 2, column",
            "AttValue");
    REFUSED("empty", "", ARR_EINVAL, "line 1, column 1", "empty");
    REFUSED("blank", "  \n\t ", ARR_EINVAL, "line 2, column", "Start tag expected");
    REFUSED("not SVG", "<?xml version='1.0'?>\n<html><body/></html>", ARR_EINVAL, "line 2, column",
            "root element is <html>, not <svg>");
    REFUSED("other namespace", "<svg xmlns='http://example.com/'/>", ARR_EINVAL,
            "namespace \"http://example.com/\"", NULL);
    REFUSED("two roots", "<svg " NS "/><svg " NS "/>", ARR_EINVAL, "line 1, column", "Extra");
    refused("NUL byte", "<svg " NS ">\0</svg>", sizeof("<svg " NS ">\0</svg>") - 1, ARR_EINVAL,
            "line 1, column", NULL);
}

TEST(svg_hostile_entities_are_refused)
{
    static const char decl[] =
        "<?xml version='1.0'?>\n<!DOCTYPE svg [\n <!ENTITY lol 'lol'>\n"
        " <!ENTITY lol1 '&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;'>\n"
        " <!ENTITY lol2 '&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;'>\n"
        " <!ENTITY lol3 '&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;'>\n"
        " <!ENTITY lol4 '&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;'>\n"
        " <!ENTITY lol5 '&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;'>\n"
        " <!ENTITY lol6 '&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;'>\n"
        " <!ENTITY lol7 '&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;'>\n"
        " <!ENTITY lol8 '&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;'>\n"
        " <!ENTITY lol9 '&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;'>\n]>\n";
    char doc[2048];
    /* billion laughs in text, in a path's d, in an attribute of the root, and declared only */
    snprintf(doc, sizeof doc, "%s<svg %s><text>&lol9;</text></svg>", decl, NS);
    REFUSED("billion laughs in text", doc, ARR_EINVAL, "line 14, column", "entity");
    snprintf(doc, sizeof doc, "%s<svg %s><path d='&lol9;'/></svg>", decl, NS);
    REFUSED("billion laughs in d", doc, ARR_EINVAL, "line 14, column", "entity");
    snprintf(doc, sizeof doc, "%s<svg %s id='&lol9;'/>", decl, NS);
    REFUSED("billion laughs in the root", doc, ARR_EINVAL, "entity", "billion laughs");
    snprintf(doc, sizeof doc, "%s<svg %s/>", decl, NS);
    REFUSED("billion laughs declared", doc, ARR_EINVAL, "nested entities are refused", NULL);
    /* an external entity is neither fetched nor substituted */
    REFUSED("external entity",
            "<!DOCTYPE svg [<!ENTITY x SYSTEM 'file:///etc/passwd'>]><svg " NS " id='&x;'/>",
            ARR_EINVAL, "line 1, column", NULL);
    /* flat entities are fine: Illustrator's namespace entity, a number in an attribute */
    svg_result r;
    rd_ok("flat entities",
          "<!DOCTYPE svg [<!ENTITY ns_svg 'http://www.w3.org/2000/svg'><!ENTITY w '10'>]>"
          "<svg xmlns='&ns_svg;'><line x2='&w;' y2='&#49;'/></svg>",
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 0, 0, 10, 1, 0), "flat entities: %zu", r.n);
    svg_result_free(&r);
    /* elements inside an entity's text are not drawn (a warning says so) */
    rd_ok("elements in an entity",
          "<!DOCTYPE svg [<!ENTITY e \"<line x2='1'/><g><line x2='2'/></g>\">]>"
          "<svg " NS ">&e;&e;<line x2='3'/></svg>",
          NULL, &r);
    CHECK(r.n == 1 && has_seg(&r, 0, 0, 3, 0, 0) && has_warning(&r, "&e; in element content"),
          "entity in content: %zu", r.n);
    svg_result_free(&r);
}

TEST(svg_hostile_sizes_are_refused_fast)
{
    size_t depth = 100000, n = 2 * 4 * depth + 256, w;
    char *doc = malloc(24u << 20);
    REQUIRE(doc, "malloc");
    /* 100 000 nested groups */
    w = (size_t)sprintf(doc, "<svg %s>", NS);
    for (size_t i = 0; i < depth; i++) memcpy(doc + w, "<g>", 3), w += 3;
    for (size_t i = 0; i < depth; i++) memcpy(doc + w, "</g>", 4), w += 4;
    w += (size_t)sprintf(doc + w, "</svg>");
    CHECK(w < n, "size");
    refused("100000 nested groups", doc, w, ARR_ELIMIT, "deeper than 200", "max_depth");
    /* 10^7 path commands in one d: 20 MB, beyond libxml2's 10 MB per attribute */
    w = (size_t)sprintf(doc, "<svg %s><path d='M0 0", NS);
    for (size_t i = 0; i < 10000000; i++) memcpy(doc + w, "h1", 2), w += 2;
    w += (size_t)sprintf(doc + w, "'/></svg>");
    refused("10^7 commands in one path", doc, w, ARR_ELIMIT, "AttValue length too long", "limit");
    /* 10^7 commands in 10 paths of 2 MB: libxml2 2.9.14 stops at its 10 MB lookup limit
     * ("Huge input lookup": it does not shrink its input buffer within such long lines) */
    w = (size_t)sprintf(doc, "<svg %s>", NS);
    for (int p = 0; p < 10; p++) {
        w += (size_t)sprintf(doc + w, "<path d='M0 0");
        for (size_t i = 0; i < 1000000; i++) memcpy(doc + w, "h1", 2), w += 2;
        w += (size_t)sprintf(doc + w, "'/>\n");
    }
    w += (size_t)sprintf(doc + w, "</svg>");
    refused("10^7 commands in 10 paths", doc, w, ARR_ELIMIT, "limit", NULL);
    /* 2 250 000 commands in 3 paths (4.5 MB): our limit of path commands, all paths together */
    w = (size_t)sprintf(doc, "<svg %s>", NS);
    for (int p = 0; p < 3; p++) {
        w += (size_t)sprintf(doc + w, "<path d='M0 0");
        for (size_t i = 0; i < 750000; i++) memcpy(doc + w, "h1", 2), w += 2;
        w += (size_t)sprintf(doc + w, "'/>\n");
    }
    w += (size_t)sprintf(doc + w, "</svg>");
    refused("2.25 million commands in 3 paths", doc, w, ARR_ELIMIT, "max_path_commands", "2000000");
    /* more than 1 000 000 elements */
    w = (size_t)sprintf(doc, "<svg %s>", NS);
    for (size_t i = 0; i < 1100000; i++) memcpy(doc + w, "<g/>", 4), w += 4;
    w += (size_t)sprintf(doc + w, "</svg>");
    refused("1.1 million elements", doc, w, ARR_ELIMIT, "max_elements", "line 1, column");
    free(doc);
    /* beyond SVG_MAX_BYTES: refused before parsing */
    refused("70 MB", "<svg/>", (size_t)70 << 20, ARR_ELIMIT, "SVG_MAX_BYTES", NULL);
}

/* ---- the "svg" kind --------------------------------------------------------------------- */

/* Runs body; returns the status, *out the result (caller json_decref()s) when 0. */
static int run_api(const char *body, json_t **out, api_error *err)
{
    char *res = NULL;
    size_t len;
    int rc = api_run_json(body, strlen(body), 1, &res, &len, err);
    *out = NULL;
    if (rc == API_OK) {
        *out = json_loadb(res, len, 0, NULL);
        free(res);
    }
    return rc;
}

TEST(svg_kind_result_and_stats)
{
    json_t *o, *s;
    api_error err;
    int rc = run_api("{\"kind\":\"svg\",\"svg\":\"<svg xmlns='http://www.w3.org/2000/svg'>"
                     "<rect width='2' height='1'/><line x1='NaN'/><path d='M0 0 l1 1'/></svg>\","
                     "\"options\":{\"normalize\":true,\"fields\":[\"V\",\"stats\"]}}",
                     &o, &err);
    REQUIRE(rc == API_OK && o, "%d %s", rc, err.msg);
    s = json_object_get(json_object_get(o, "stats"), "svg");
    CHECK(json_is_object(s) && json_integer_value(json_object_get(s, "elements")) == 2 &&
              json_integer_value(json_object_get(s, "skipped")) == 1 &&
              json_integer_value(json_object_get(s, "segments")) == 5 &&
              json_array_size(json_object_get(s, "warnings")) == 1 &&
              json_array_size(json_object_get(s, "transform")) == 6,
          "stats.svg");
    CHECK(json_real_value(json_array_get(json_object_get(s, "transform"), 0)) == 0.5 &&
              json_real_value(json_array_get(json_object_get(s, "transform"), 3)) == -0.5,
          "transform");
    CHECK(strstr(json_string_value(json_array_get(json_object_get(s, "warnings"), 0)),
                 "x1=\\\"NaN\\\"") == NULL &&
              strstr(json_string_value(json_array_get(json_object_get(s, "warnings"), 0)),
                     "x1=\"NaN\""),
          "warning text survives JSON");
    CHECK(json_integer_value(json_object_get(json_object_get(o, "stats"), "input_segments")) == 5,
          "input_segments");
    json_decref(o);
    /* rect2lines diagonal, y_up, flatten_tolerance, keep_dangling */
    rc = run_api(
        "{\"kind\":\"svg\",\"svg\":\"<svg><rect x='-2' y='-1' width='4' height='2'/><circle r='1'/>"
        "</svg>\",\"options\":{\"rect2lines\":\"diagonal\",\"y_up\":true,"
        "\"flatten_tolerance\":0.5,\"keep_dangling\":true,\"fields\":[\"stats\"]}}",
        &o, &err);
    REQUIRE(rc == API_OK && o, "%d %s", rc, err.msg);
    s = json_object_get(json_object_get(o, "stats"), "svg");
    CHECK(json_integer_value(json_object_get(s, "segments")) == 9, "diagonal + 8 chords: %d",
          (int)json_integer_value(json_object_get(s, "segments")));
    CHECK(json_integer_value(json_object_get(json_object_get(o, "stats"), "F")) == 2,
          "faces of the octagon split by the diagonal");
    json_decref(o);
    /* a lines result has no stats.svg */
    rc = run_api("{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]]]}", &o, &err);
    CHECK(rc == API_OK && !json_object_get(json_object_get(o, "stats"), "svg"), "lines: no svg");
    json_decref(o);
}

TEST(svg_kind_errors)
{
    static const struct {
        const char *body;
        int status;
        const char *prefix;
    } cases[] = {
        {"{\"kind\":\"svg\",\"svg\":\"<svg>\\n<g>\\n</svg>\"}", 422,
         "svg: line 3, column 7: Opening and ending tag mismatch"},
        {"{\"kind\":\"svg\",\"svg\":\"\"}", 422, "svg: line 1, column 1: Document is empty"},
        {"{\"kind\":\"svg\",\"svg\":\"<html/>\"}", 422,
         "svg: line 1, column 6: the root element is <html>, not <svg>"},
        {"{\"kind\":\"svg\"}", 422, "svg: required"},
        {"{\"kind\":\"svg\",\"svg\":7}", 422, "svg: expected a string"},
        {"{\"kind\":\"svg\",\"svg\":\"<svg/>\",\"lines\":[]}", 422, "lines: unknown key"},
        {"{\"kind\":\"svg\",\"svg\":\"<svg/>\",\"options\":{\"normalize\":1}}", 422,
         "options.normalize: expected true or false"},
        {"{\"kind\":\"svg\",\"svg\":\"<svg/>\",\"options\":{\"y_up\":\"yes\"}}", 422,
         "options.y_up: expected true or false"},
        {"{\"kind\":\"svg\",\"svg\":\"<svg/>\",\"options\":{\"rect2lines\":\"both\"}}", 422,
         "options.rect2lines: expected \"sides\" or \"diagonal\""},
        {"{\"kind\":\"svg\",\"svg\":\"<svg/>\",\"options\":{\"flatten_tolerance\":0}}", 422,
         "options.flatten_tolerance: expected a number > 0"},
        {"{\"kind\":\"svg\",\"svg\":\"<svg/>\",\"options\":{\"precision\":-1}}", 422,
         "options.precision: expected a number > 0"},
        {"{\"kind\":\"svg\",\"svg\":\"<svg/>\",\"options\":{\"colour\":1}}", 422,
         "options.colour: unknown option"},
        {"{\"kind\":\"svg\",\"svg\":\"<svg/>\",\"options\":{\"fields\":[\"X\"]}}", 422,
         "options.fields[0]: expected one of"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        json_t *o;
        api_error err = {0};
        int rc = run_api(cases[i].body, &o, &err);
        CHECK(rc == cases[i].status &&
                  strncmp(err.msg, cases[i].prefix, strlen(cases[i].prefix)) == 0,
              "case %zu: %d \"%s\", want %d \"%s\"", i, rc, err.msg, cases[i].status,
              cases[i].prefix);
        json_decref(o);
    }
    /* the check step (the daemon's submit) reads the drawing too: malformed XML is refused
     * there, with line and column, and a good drawing passes with its kind */
    api_error err;
    const char *body = "{\"kind\":\"svg\",\"svg\":\"<svg>\",\"options\":{\"normalize\":true}}";
    const char *kind = NULL;
    CHECK(api_check_request(body, strlen(body), NULL, NULL, &kind, &err) == API_EINVALID && !kind &&
              strstr(err.msg, "svg: line 1, column") != NULL,
          "check: %s", err.msg);
    body = "{\"kind\":\"svg\",\"svg\":\"<svg xmlns='http://www.w3.org/2000/svg'/>\"}";
    CHECK(api_check_request(body, strlen(body), NULL, NULL, &kind, &err) == API_OK && kind &&
              strcmp(kind, "svg") == 0,
          "check of a good drawing: %s", err.msg);
}
