/* test_geos.c — differential tests of the 2D core against GEOS (node + polygonize, through
 * tests/ref/geos_ref.h): on random inputs of several sizes and seeds, and on structured
 * ones, the same number of faces and holes, the same sorted face areas, and with
 * keep_dangling the same numbers of vertices and edges as GEOS's noding.
 *
 * Areas agree to 1e-9 relative, plus what snapping can move: a face's area changes by at
 * most its perimeter times half the grid step, and no face here has a perimeter above 8
 * units of the drawing's extent, hence the absolute term 8 * extent * step. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/arr2.h"
#include "tests/check.h"
#include "tests/lar_check.h"
#include "tests/ref/geos_ref.h"

/* Compares arr2_build with GEOS on n segments; extent = the drawing's size. */
static void compare(const char *what, const double *s, size_t n, double extent)
{
    lar2 c, k;
    char err[256], msg[256];
    double *ga = NULL;
    size_t gf, gh, gv, ge;
    int rc = arr2_build(s, n, NULL, &c, err, sizeof err);
    REQUIRE(rc == ARR_OK, "%s: arr2_build: %s", what, err);
    CHECK(lar_check(&c, msg, sizeof msg) == 0, "%s: invariant: %s", what, msg);
    rc = arr2_build(s, n, &(arr2_opts){.keep_dangling = 1}, &k, err, sizeof err);
    REQUIRE(rc == ARR_OK, "%s: arr2_build keep_dangling: %s", what, err);
    CHECK(lar_check(&k, msg, sizeof msg) == 0, "%s: invariant (keep_dangling): %s", what, msg);
    REQUIRE(geos_ref_faces(s, n, &ga, &gf, &gh, &gv, &ge) == 0, "%s: GEOS failed", what);
    CHECK(c.nf == gf, "%s: %zu faces, GEOS %zu", what, c.nf, gf);
    CHECK(c.hole_off[c.nf] == gh, "%s: %u holes, GEOS %zu", what, c.hole_off[c.nf], gh);
    CHECK(k.nv == gv && k.ne == ge, "%s: keep_dangling %zu V %zu E, GEOS noding %zu V %zu E", what,
          k.nv, k.ne, gv, ge);
    if (c.nf == gf) {
        double worst;
        size_t bad = lar_sorted_areas_differ(&c, ga, gf, 8 * extent * c.stats.precision, &worst);
        CHECK(bad == 0, "%s: %zu of %zu sorted areas differ from GEOS (worst relative %g)", what,
              bad, c.nf, worst);
    }
    free(ga);
    lar2_free(&c);
    lar2_free(&k);
}

TEST(geos_random_lines)
{
    size_t sizes[] = {30, 200, 800, 2000, 5000};
    double scal[] = {0.8, 0.3, 0.2, 0.1, 0.1};
    for (size_t t = 0; t < sizeof sizes / sizeof *sizes; t++)
        for (uint64_t seed = 1; seed <= 3; seed++) {
            size_t n = sizes[t];
            double *s = test_random_lines(n, scal[t], seed * 7919 + t);
            char what[64];
            snprintf(what, sizeof what, "random %zu/%.2f seed %d", n, scal[t], (int)seed);
            compare(what, s, n, 1 + scal[t]);
            free(s);
        }
}

TEST(geos_random_rectangles_with_holes)
{
    /* axis-aligned and rotated rectangles of many sizes: islands, holes, touching sides */
    for (uint64_t seed = 1; seed <= 4; seed++) {
        size_t nr = 150, n = 0;
        double *s = malloc(nr * 4 * 4 * sizeof *s);
        uint64_t st = seed;
        for (size_t r = 0; r < nr; r++) {
            double cx = test_rnd(&st) * 10, cy = test_rnd(&st) * 10;
            double w = test_rnd(&st) * (r % 5 ? 0.6 : 4), h = test_rnd(&st) * (r % 5 ? 0.6 : 4);
            double a = seed % 2 ? test_rnd(&st) * 3.14159 : 0;
            double ca = cos(a), sa = sin(a), px[4], py[4];
            double dx[4] = {-w, w, w, -w}, dy[4] = {-h, -h, h, h};
            for (int i = 0; i < 4; i++) {
                px[i] = cx + ca * dx[i] / 2 - sa * dy[i] / 2;
                py[i] = cy + sa * dx[i] / 2 + ca * dy[i] / 2;
            }
            for (int i = 0; i < 4; i++) {
                double q[4] = {px[i], py[i], px[(i + 1) % 4], py[(i + 1) % 4]};
                memcpy(s + 4 * n++, q, sizeof q);
            }
        }
        char what[64];
        snprintf(what, sizeof what, "rectangles seed %d", (int)seed);
        compare(what, s, n, 14);
        free(s);
    }
}

TEST(geos_grid_and_far_away)
{
    enum { K = 30 };
    double s[2 * K * 4];
    double offs[] = {0, 1e6};
    for (int t = 0; t < 2; t++) {
        for (int i = 0; i < K; i++) {
            double a[4] = {offs[t], offs[t] + i * 0.1, offs[t] + (K - 1) * 0.1, offs[t] + i * 0.1};
            double b[4] = {offs[t] + i * 0.1, offs[t], offs[t] + i * 0.1, offs[t] + (K - 1) * 0.1};
            memcpy(s + 8 * i, a, sizeof a);
            memcpy(s + 8 * i + 4, b, sizeof b);
        }
        compare(t ? "grid at 1e6" : "grid", s, 2 * K, (K - 1) * 0.1);
    }
}
