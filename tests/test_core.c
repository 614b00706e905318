/* test_core.c — unit tests of the 2D arrangement core (core/arr2.h): the seeds' examples,
 * counts known in closed form, holes, degenerate and hostile input, determinism.  Every
 * result also goes through lar_check() (tests/lar_check.h). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/arr2.h"
#include "core/box.h"
#include "core/num.h"
#include "core/pred.h"
#include "core/sort.h"
#include "tests/check.h"
#include "tests/lar_check.h"

/* Runs the arrangement and the invariant checks; returns ARR_* */
static int run(const double *s, size_t n, const arr2_opts *o, lar2 *out)
{
    char err[256], msg[256];
    int rc = arr2_build(s, n, o, out, err, sizeof err);
    if (rc == ARR_OK && lar_check(out, msg, sizeof msg))
        test_fail(__FILE__, "run", __LINE__, "invariant: %s", msg);
    return rc;
}

static size_t total_holes(const lar2 *c)
{
    return c->hole_off[c->nf];
}

static double sum_face_areas(const lar2 *c)
{
    double a = 0;
    for (size_t f = 0; f < c->nf; f++) a += lar_face_area(c, f);
    return a;
}

/* x0, y0 .. squares of side `side`, each as 4 segments */
static size_t add_square(double *s, size_t n, double x, double y, double side)
{
    double q[4][4] = {{x, y, x + side, y},
                      {x + side, y, x + side, y + side},
                      {x + side, y + side, x, y + side},
                      {x, y + side, x, y}};
    memcpy(s + 4 * n, q, sizeof q);
    return n + 4;
}

static const double ORTHO[8][4] = {{0, 0, 6, 0}, {0, 4, 10, 4}, {0, 0, 0, 4},   {3, 0, 3, 4},
                                   {6, 0, 6, 8}, {3, 2, 6, 2},  {10, 0, 10, 8}, {0, 8, 10, 8}};

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* sort_u64, sort_kv and sort_u64_hi32 at every size regime (insertion, merging, radix passes), keys
 * from a few values (ties: sort_kv must keep their order) to the full 64 bits, against qsort. */
TEST(sorts_against_qsort)
{
    static const size_t sizes[] = {0, 1, 2, 47, 48, 49, 95, 97, 500, 1023, 1024, 1025, 3000};
    uint64_t st = 77;
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; si++)
        for (int spread = 0; spread < 3; spread++) {
            size_t n = sizes[si];
            uint64_t *a = malloc((n + 1) * sizeof *a), *b = malloc((n + 1) * sizeof *b);
            kv *k = malloc((n + 1) * sizeof *k);
            REQUIRE(a && b && k, "memory");
            for (size_t i = 0; i < n; i++) {
                double r = test_rnd(&st);
                a[i] = spread == 0   ? (uint64_t)(r * 5)
                       : spread == 1 ? (uint64_t)(r * 1e9)
                                     : (uint64_t)(r * 18446744073709549568.0);
                b[i] = a[i];
                k[i] = (kv){a[i], (uint32_t)i};
            }
            qsort(b, n, sizeof *b, cmp_u64);
            CHECK(sort_u64(a, n) == 0 && sort_kv(k, n) == 0, "n %zu: out of memory", n);
            size_t bad = 0;
            for (size_t i = 0; i < n; i++) {
                bad += a[i] != b[i] || k[i].k != b[i];
                bad += i > 0 && k[i].k == k[i - 1].k && k[i].v < k[i - 1].v; /* stable */
            }
            CHECK(bad == 0, "n %zu spread %d: %zu misplaced", n, spread, bad);
            /* sort_u64_hi32: by the high half only, stable (the low half an index) */
            for (size_t i = 0; i < n; i++) a[i] = (uint64_t)(uint32_t)(k[i].k >> 7) << 32 | i;
            for (size_t i = n; i > 1; i--) { /* shuffled, the low halves still their places */
                size_t j = (size_t)(test_rnd(&st) * (double)i);
                uint64_t t = a[i - 1] >> 32;
                a[i - 1] = (a[j] >> 32) << 32 | (i - 1), a[j] = t << 32 | j;
            }
            CHECK(sort_u64_hi32(a, n) == 0, "n %zu: out of memory", n);
            bad = 0;
            for (size_t i = 1; i < n; i++)
                bad += a[i] >> 32 < a[i - 1] >> 32 ||
                       (a[i] >> 32 == a[i - 1] >> 32 && (uint32_t)a[i] < (uint32_t)a[i - 1]);
            CHECK(bad == 0, "hi32: n %zu spread %d: %zu out of order", n, spread, bad);
            free(a), free(b), free(k);
        }
}

TEST(orthogonal_example_seeds)
{
    lar2 c;
    arr2_opts o = {.keep_dangling = 1};
    REQUIRE(run(&ORTHO[0][0], 8, &o, &c) == ARR_OK, "keep_dangling run failed");
    CHECK(c.nv == 13 && c.ne == 16, "before pruning: %zu V %zu E, want 13, 16", c.nv, c.ne);
    CHECK(c.nf == 4, "faces %zu, want 4", c.nf);
    CHECK(c.stats.intersections == 1, "proper crossings %zu, want 1", c.stats.intersections);
    lar2_free(&c);
    REQUIRE(run(&ORTHO[0][0], 8, NULL, &c) == ARR_OK, "default run failed");
    CHECK(c.nv == 11 && c.ne == 14 && c.nf == 4, "%zu V %zu E %zu F, want 11 14 4", c.nv, c.ne,
          c.nf);
    CHECK(c.stats.blocks == 2, "blocks %zu, want 2", c.stats.blocks);
    CHECK(c.stats.dangling_removed == 2, "removed %zu, want 2", c.stats.dangling_removed);
    /* faces: 3x4 on the left, 3x2 twice (split by (3,2)-(6,2)), 4x4 upper right */
    double want[4] = {6, 6, 12, 16}, got[4];
    for (size_t f = 0; f < 4 && f < c.nf; f++) got[f] = lar_face_area(&c, f);
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            if (got[j] < got[i]) {
                double t = got[i];
                got[i] = got[j];
                got[j] = t;
            }
    for (int i = 0; i < 4; i++)
        CHECK(fabs(got[i] - want[i]) < 1e-9, "area %g want %g", got[i], want[i]);
    lar2_free(&c);
}

static size_t grid_segments(double *s, int k, double x0, double y0, double step)
{
    size_t n = 0;
    for (int i = 0; i < k; i++) {
        double a[4] = {x0, y0 + i * step, x0 + (k - 1) * step, y0 + i * step};
        double b[4] = {x0 + i * step, y0, x0 + i * step, y0 + (k - 1) * step};
        memcpy(s + 4 * n++, a, sizeof a);
        memcpy(s + 4 * n++, b, sizeof b);
    }
    return n;
}

TEST(grid_closed_form)
{
    int ks[] = {2, 3, 4, 10, 50};
    for (size_t t = 0; t < sizeof ks / sizeof *ks; t++) {
        int k = ks[t];
        double *s = malloc(2 * (size_t)k * 4 * sizeof *s);
        size_t n = grid_segments(s, k, 0, 0, 1);
        lar2 c;
        REQUIRE(run(s, n, NULL, &c) == ARR_OK, "grid %d failed", k);
        size_t f = (size_t)(k - 1) * (size_t)(k - 1);
        CHECK(c.nf == f, "grid %d: %zu faces, want %zu", k, c.nf, f);
        CHECK(c.nv == (size_t)k * k, "grid %d: %zu V", k, c.nv);
        CHECK(c.ne == 2 * (size_t)k * (k - 1), "grid %d: %zu E", k, c.ne);
        for (size_t i = 0; i < c.nf; i++)
            CHECK(fabs(lar_face_area(&c, i) - 1) < 1e-12, "grid %d face %zu area %g", k, i,
                  lar_face_area(&c, i));
        lar2_free(&c);
        free(s);
    }
}

TEST(grid_4x4_chaincomplex_oracle)
{
    /* LinearAlgebraicRepresentation.jl "chaincomplex 2D": 16 V, 24 unit edges, 9 faces,
     * copFE with 36 non-zeros; here given as 24 unit segments */
    double s[24 * 4];
    size_t n = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 3; j++) {
            double a[4] = {j, i, j + 1, i}, b[4] = {i, j, i, j + 1};
            memcpy(s + 4 * n++, a, sizeof a);
            memcpy(s + 4 * n++, b, sizeof b);
        }
    lar2 c;
    REQUIRE(run(s, n, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nv == 16 && c.ne == 24 && c.nf == 9, "%zu %zu %zu", c.nv, c.ne, c.nf);
    CHECK(c.fe_off[c.nf] == 36, "FE non-zeros %u, want 36", c.fe_off[c.nf]);
    lar2_free(&c);
}

TEST(refactoring_jl_oracles)
{
    /* test/refactoring.jl: square plus a diagonal to (2,1) that cuts the right side at (1,.5):
     * fragmentlines gives 6 V, 7 E; the arrangement 5 V, 6 E, 2 faces */
    double s[5][4] = {{0, 0, 1, 0}, {1, 0, 1, 1}, {1, 1, 0, 1}, {0, 1, 0, 0}, {0, 0, 2, 1}};
    lar2 c;
    arr2_opts keep = {.keep_dangling = 1};
    REQUIRE(run(&s[0][0], 5, &keep, &c) == ARR_OK, "failed");
    CHECK(c.nv == 6 && c.ne == 7, "fragments: %zu V %zu E, want 6, 7", c.nv, c.ne);
    lar2_free(&c);
    REQUIRE(run(&s[0][0], 5, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nv == 5 && c.ne == 6 && c.nf == 2, "%zu V %zu E %zu F, want 5 6 2", c.nv, c.ne, c.nf);
    lar2_free(&c);
    /* refactor_planar_arrangement.jl: a collinear overlap and a crossing: 7 V, 8 E */
    double t[5][4] = {{0, 1, 4, 1}, {1, 1, 3, 1}, {2, 2, 2, 0}, {1, 1, 2, 2}, {3, 1, 2, 0}};
    REQUIRE(run(&t[0][0], 5, &keep, &c) == ARR_OK, "failed");
    CHECK(c.nv == 7 && c.ne == 8 && c.nf == 2, "%zu V %zu E %zu F, want 7 8 2", c.nv, c.ne, c.nf);
    lar2_free(&c);
    REQUIRE(run(&t[0][0], 5, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nv == 5 && c.ne == 6 && c.nf == 2 && c.stats.blocks == 2, "%zu V %zu E %zu F %zu B",
          c.nv, c.ne, c.nf, c.stats.blocks);
    lar2_free(&c);
    /* intersection([[0,0],[1,2]],[[2,0],[0,3]]) = (0.857142857142857, 0.571428571428571):
     * the parameters on the two segments, 6/7 and 4/7, so the point is (6/7, 12/7) */
    double x[2][4] = {{0, 0, 1, 2}, {2, 0, 0, 3}};
    REQUIRE(run(&x[0][0], 2, &keep, &c) == ARR_OK, "failed");
    int found = 0;
    for (size_t v = 0; v < c.nv; v++)
        found |= fabs(c.V[2 * v] - 6.0 / 7) < 1e-10 && fabs(c.V[2 * v + 1] - 12.0 / 7) < 1e-10;
    CHECK(c.nv == 5 && found, "crossing point not found (%zu V)", c.nv);
    lar2_free(&c);
}

TEST(concentric_squares_are_holes)
{
    double s[4 * 4 * 4];
    size_t n = 0;
    for (int i = 0; i < 4; i++) n = add_square(s, n, i, i, 8 - 2 * i);
    lar2 c;
    REQUIRE(run(s, n, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 4 && c.stats.components == 4, "%zu faces %zu comps", c.nf, c.stats.components);
    CHECK(total_holes(&c) == 3 && c.next == 1, "%zu holes, %zu exterior", total_holes(&c), c.next);
    /* rings of area 64-36, 36-16, 16-4, and the core 4 */
    double want[] = {28, 20, 12, 4};
    for (size_t f = 0; f < c.nf; f++) {
        double a = lar_face_area(&c, f);
        int ok = 0;
        for (int i = 0; i < 4; i++) ok |= fabs(a - want[i]) < 1e-9;
        CHECK(ok, "face %zu area %g", f, a);
    }
    lar2_free(&c);
}

TEST(disjoint_and_nested_components)
{
    double s[16 * 4];
    size_t n = 0;
    n = add_square(s, n, 0, 0, 1);
    n = add_square(s, n, 5, 0, 1);   /* beside */
    n = add_square(s, n, 10, 0, 10); /* a big one ... */
    n = add_square(s, n, 12, 2, 2);  /* ... with one inside */
    lar2 c;
    REQUIRE(run(s, n, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 4, "faces %zu", c.nf);
    CHECK(c.next == 3, "exterior cycles %zu, want 3", c.next);
    CHECK(total_holes(&c) == 1, "holes %zu, want 1", total_holes(&c));
    for (size_t f = 0; f < c.nf; f++)
        if (c.hole_off[f + 1] > c.hole_off[f])
            CHECK(fabs(lar_face_area(&c, f) - 96) < 1e-9, "holed face area %g",
                  lar_face_area(&c, f));
    CHECK(fabs(sum_face_areas(&c) - 102) < 1e-9, "total %g", sum_face_areas(&c));
    lar2_free(&c);
}

TEST(hole_in_nonconvex_face_goes_to_the_right_face)
{
    /* a U-shaped face whose bounding box holds a square that lies in the notch, outside the
     * U: the square must not become a hole of the U (the seeds' bbox rule gets this wrong) */
    double u[8][4] = {{0, 0, 9, 0}, {9, 0, 9, 9}, {9, 9, 6, 9}, {6, 9, 6, 3},
                      {6, 3, 3, 3}, {3, 3, 3, 9}, {3, 9, 0, 9}, {0, 9, 0, 0}};
    double s[12 * 4];
    memcpy(s, u, sizeof u);
    size_t n = add_square(s, 8, 4, 5, 1);
    lar2 c;
    REQUIRE(run(s, n, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 2 && total_holes(&c) == 0 && c.next == 2, "%zu faces %zu holes %zu ext", c.nf,
          total_holes(&c), c.next);
    lar2_free(&c);
    /* and in the U's arm it is a hole */
    n = add_square(s, 8, 1, 5, 1);
    REQUIRE(run(s, n, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 2 && total_holes(&c) == 1 && c.next == 1, "%zu faces %zu holes %zu ext", c.nf,
          total_holes(&c), c.next);
    lar2_free(&c);
}

TEST(hole_below_a_vertex_and_stacked_islands)
{
    /* islands whose lowest vertex lies straight above a vertex or a vertical edge of
     * another: the downward ray hits vertices, not only edge interiors */
    double s[32 * 4];
    size_t n = 0;
    n = add_square(s, n, 0, 0, 20);
    n = add_square(s, n, 5, 2, 4); /* island A: lowest vertex (5,2) */
    n = add_square(s, n, 5, 8, 2); /* island B: straight above A's vertex (5,6) */
    double d[4][4] = {{14, 2, 16, 4}, {16, 4, 14, 6}, {14, 6, 12, 4}, {12, 4, 14, 2}};
    memcpy(s + 4 * n, d, sizeof d); /* a diamond; its bottom (14,2) above nothing */
    n += 4;
    n = add_square(s, n, 13, 9, 2); /* above the diamond's top vertex (14,6) */
    lar2 c;
    REQUIRE(run(s, n, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 5 && total_holes(&c) == 4 && c.next == 1, "%zu faces %zu holes %zu ext", c.nf,
          total_holes(&c), c.next);
    lar2_free(&c);
}

TEST(collinear_overlaps_merge)
{
    /* the same square drawn three times with overlapping pieces of each side */
    double s[][4] = {{0, 0, 4, 0}, {1, 0, 3, 0}, {2, 0, 6, 0}, {6, 0, 6, 4}, {6, 2, 6, 4},
                     {6, 4, 0, 4}, {0, 4, 0, 0}, {0, 1, 0, 3}, {0, 4, 0, 2}, {4, 0, 0, 0}};
    lar2 c;
    REQUIRE(run(&s[0][0], sizeof s / sizeof *s, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 1, "faces %zu", c.nf);
    CHECK(fabs(lar_face_area(&c, 0) - 24) < 1e-12, "area %g", lar_face_area(&c, 0));
    lar2_free(&c);
}

TEST(many_segments_through_one_point)
{
    /* n chords through the centre of a regular 2n-gon: 2n triangles */
    enum { N = 64 };
    double s[(N + 2 * N) * 4];
    size_t n = 0;
    for (int i = 0; i < N; i++) {
        double a = M_PI * i / N;
        double q[4] = {cos(a), sin(a), -cos(a), -sin(a)};
        memcpy(s + 4 * n++, q, sizeof q);
    }
    for (int i = 0; i < 2 * N; i++) {
        double a = M_PI * i / N, b = M_PI * (i + 1) / N;
        double q[4] = {cos(a), sin(a), cos(b), sin(b)};
        memcpy(s + 4 * n++, q, sizeof q);
    }
    lar2 c;
    REQUIRE(run(s, n, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 2 * N, "faces %zu want %d", c.nf, 2 * N);
    CHECK(c.nv == 2 * N + 1, "V %zu want %d", c.nv, 2 * N + 1);
    double want = N * sin(M_PI / N); /* area of the 2N-gon */
    CHECK(fabs(sum_face_areas(&c) - want) < 1e-9, "area %.15g want %.15g", sum_face_areas(&c),
          want);
    lar2_free(&c);
}

TEST(far_from_origin_same_complex)
{
    double base[8][4];
    /* at 1e9 a double holds the input to about 1e-7: the area can only be that good */
    double off[][2] = {{0, 0}, {1e6, 1e6}, {-3e7, 2e5}, {1e9, -1e9}};
    size_t nv0 = 0, ne0 = 0, nf0 = 0;
    for (size_t t = 0; t < sizeof off / sizeof *off; t++) {
        for (int i = 0; i < 8; i++)
            for (int k = 0; k < 4; k++) base[i][k] = ORTHO[i][k] * 0.37 + off[t][k % 2];
        lar2 c;
        REQUIRE(run(&base[0][0], 8, NULL, &c) == ARR_OK, "offset %zu failed", t);
        if (t == 0) {
            nv0 = c.nv;
            ne0 = c.ne;
            nf0 = c.nf;
        }
        CHECK(c.nv == nv0 && c.ne == ne0 && c.nf == nf0 && nf0 == 4, "offset %zu: %zu %zu %zu", t,
              c.nv, c.ne, c.nf);
        double a = sum_face_areas(&c), want = 40 * 0.37 * 0.37;
        CHECK(fabs(a - want) < 1e-9 * want + 1e-13 * fabs(off[t][0]) * 40,
              "offset %zu: area %.12g want %.12g", t, a, want);
        lar2_free(&c);
    }
}

TEST(bad_and_degenerate_input)
{
    lar2 c;
    char err[256];
    double nanseg[2][4] = {{0, 0, 1, 1}, {0, NAN, 1, 0}};
    CHECK(arr2_build(&nanseg[0][0], 2, NULL, &c, err, sizeof err) == ARR_EINVAL, "NaN accepted");
    CHECK(strstr(err, "lines[1][0]") != NULL, "message '%s' does not name lines[1][0]", err);
    double infseg[1][4] = {{0, 0, INFINITY, 1}};
    CHECK(arr2_build(&infseg[0][0], 1, NULL, &c, err, sizeof err) == ARR_EINVAL, "inf accepted");
    CHECK(strstr(err, "lines[0][1]") != NULL, "message '%s'", err);
    /* empty, all degenerate, one segment: empty complexes */
    CHECK(run(NULL, 0, NULL, &c) == ARR_OK && c.nv == 0 && c.nf == 0, "empty");
    lar2_free(&c);
    double deg[3][4] = {{1, 1, 1, 1}, {2, 2, 2, 2}, {1, 1, 1, 1}};
    CHECK(run(&deg[0][0], 3, NULL, &c) == ARR_OK && c.nv == 0 && c.stats.zero_length == 3,
          "degenerate: %zu V, %zu dropped", c.nv, c.stats.zero_length);
    lar2_free(&c);
    double one[1][4] = {{0, 0, 1, 1}};
    CHECK(run(&one[0][0], 1, NULL, &c) == ARR_OK && c.nv == 0 && c.ne == 0, "one segment pruned");
    lar2_free(&c);
    arr2_opts keep = {.keep_dangling = 1};
    CHECK(run(&one[0][0], 1, &keep, &c) == ARR_OK && c.nv == 2 && c.ne == 1 && c.nf == 0 &&
              c.next == 1,
          "one segment kept: %zu V %zu E %zu ext", c.nv, c.ne, c.next);
    lar2_free(&c);
    /* huge coordinates: fine as long as the span fits a double */
    double huge[4][4] = {{-1e300, -1e300, 1e300, 1e300},
                         {-1e300, 1e300, 1e300, -1e300},
                         {-1e300, -1e300, 1e300, -1e300},
                         {1e300, -1e300, 1e300, 1e300}};
    CHECK(run(&huge[0][0], 4, NULL, &c) == ARR_OK && c.nf == 2, "huge: %zu faces", c.nf);
    lar2_free(&c);
    double span[1][4] = {{-1.7e308, 0, 1.7e308, 1}};
    CHECK(arr2_build(&span[0][0], 1, NULL, &c, err, sizeof err) == ARR_ELIMIT, "span accepted");
    /* a precision finer than the grid allows is refused with the bound in the message */
    arr2_opts fine = {.precision = 1e-15};
    CHECK(arr2_build(&ORTHO[0][0], 8, &fine, &c, err, sizeof err) == ARR_ELIMIT,
          "precision too fine accepted");
    CHECK(strstr(err, "precision") != NULL, "message '%s'", err);
    arr2_opts negp = {.precision = -1};
    CHECK(arr2_build(&ORTHO[0][0], 8, &negp, &c, err, sizeof err) == ARR_EINVAL, "negative");
    CHECK(c.V == NULL && c.nv == 0, "failed build left data behind");
}

TEST(precision_merges_close_vertices)
{
    /* a square whose corners miss each other by 1e-4: open at a fine grid, closed at 1e-3 */
    double s[4][4] = {{0, 0, 1, 0}, {1.0001, 0, 1, 1}, {1, 1.0001, 0, 1}, {0, 1, 0, 0.0001}};
    lar2 c;
    REQUIRE(run(&s[0][0], 4, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 0, "fine grid: %zu faces, want 0", c.nf);
    lar2_free(&c);
    arr2_opts o = {.precision = 1e-3};
    REQUIRE(run(&s[0][0], 4, &o, &c) == ARR_OK, "failed");
    CHECK(c.nf == 1 && c.nv == 4, "coarse grid: %zu faces %zu V, want 1, 4", c.nf, c.nv);
    CHECK(c.stats.precision == 1e-3, "precision %g", c.stats.precision);
    lar2_free(&c);
}

TEST(snap_rounding_near_misses)
{
    /* many nearly concurrent lines at a coarse grid: rounding must not create crossings
     * (lar_check verifies planarity through Euler and the walks) */
    enum { N = 40 };
    double s[N * 4];
    for (int i = 0; i < N; i++) {
        double a = 0.3 + i * 1e-3;
        double q[4] = {-cos(a) + i * 1e-4, -sin(a), cos(a), sin(a) + i * 2e-4};
        memcpy(s + 4 * i, q, sizeof q);
    }
    arr2_opts o = {.precision = 1e-3, .keep_dangling = 1};
    lar2 c;
    REQUIRE(run(s, N, &o, &c) == ARR_OK, "failed");
    CHECK(c.nv > 0, "no vertices");
    lar2_free(&c);
}

static double *random_lines(size_t n, double scaling, uint64_t seed)
{
    return test_random_lines(n, scaling, seed);
}

TEST(random_invariants_and_thread_determinism)
{
    size_t sizes[] = {10, 200, 1000, 5000};
    double scal[] = {0.8, 0.3, 0.2, 0.1};
    for (size_t t = 0; t < 4; t++)
        for (uint64_t seed = 1; seed <= 3; seed++) {
            double *s = random_lines(sizes[t], scal[t], seed);
            lar2 a, b, k;
            arr2_opts o1 = {.threads = 1}, o2 = {.threads = 2}, ok = {.keep_dangling = 1};
            REQUIRE(run(s, sizes[t], &o1, &a) == ARR_OK, "n=%zu seed=%d", sizes[t], (int)seed);
            REQUIRE(run(s, sizes[t], &o2, &b) == ARR_OK, "n=%zu seed=%d", sizes[t], (int)seed);
            REQUIRE(run(s, sizes[t], &ok, &k) == ARR_OK, "n=%zu seed=%d", sizes[t], (int)seed);
            CHECK(a.nv == b.nv && a.ne == b.ne && a.nf == b.nf &&
                      !memcmp(a.V, b.V, 2 * a.nv * sizeof *a.V) &&
                      !memcmp(a.EV, b.EV, 2 * a.ne * sizeof *a.EV) &&
                      !memcmp(a.cyc, b.cyc, a.cyc_off[a.ncyc] * sizeof *a.cyc),
                  "1 and 2 threads differ at n=%zu seed=%d", sizes[t], (int)seed);
            CHECK(k.nf == a.nf, "keep_dangling changes the faces: %zu vs %zu", k.nf, a.nf);
            CHECK(fabs(sum_face_areas(&k) - sum_face_areas(&a)) <= 1e-9 * sum_face_areas(&a),
                  "keep_dangling changes the area");
            lar2_free(&a);
            lar2_free(&b);
            lar2_free(&k);
            free(s);
        }
}

static void count_progress(void *u, const char *stage, double f)
{
    (void)stage;
    (void)f;
    (*(int *)u)++;
}

TEST(cancel_and_progress)
{
    double *s = random_lines(2000, 0.2, 7);
    atomic_int stop;
    atomic_init(&stop, 1);
    int calls = 0;
    arr2_opts o = {.cancel = &stop};
    lar2 c;
    char err[128];
    CHECK(arr2_build(s, 2000, &o, &c, err, sizeof err) == ARR_ECANCELED, "not cancelled");
    CHECK(c.V == NULL, "cancelled build left data");
    atomic_store(&stop, 0);
    o.progress = count_progress;
    o.udata = &calls;
    CHECK(arr2_build(s, 2000, &o, &c, err, sizeof err) == ARR_OK, "failed: %s", err);
    CHECK(calls >= 5, "progress called %d times", calls);
    lar2_free(&c);
    free(s);
}

TEST(exact_predicates)
{
    ipt a = {0, 0}, b = {(int64_t)1 << 38, 1}, c = {(int64_t)1 << 37, 0};
    CHECK(orient2(a, b, c) < 0, "orient sign");
    ipt d = {((int64_t)1 << 38) - 1, 1};
    CHECK(orient2(a, b, d) == 1, "orient exact: %lld", (long long)orient2(a, b, d));
    CHECK(rounddiv128(5, 2) == 3 && rounddiv128(-5, 2) == -2 && rounddiv128(-7, 2) == -3,
          "rounding");
    CHECK(dir_cmp(1, 0, 0, 1) < 0 && dir_cmp(0, -1, 1, 1) > 0 && dir_cmp(-1, 0, 0, -1) < 0 &&
              dir_cmp(2, 2, 1, 1) == 0,
          "angular order");
}

TEST(touching_hole_is_a_simple_cycle)
{
    /* a triangle inside a square, touching it at the square's corner (0,0): the square's
     * face gets the triangle as a hole touching its outer cycle at one point; every cycle
     * is simple */
    double s[7][4] = {{0, 0, 4, 0}, {4, 0, 4, 4}, {4, 4, 0, 4}, {0, 4, 0, 0},
                      {0, 0, 2, 1}, {2, 1, 1, 2}, {1, 2, 0, 0}};
    lar2 c;
    REQUIRE(run(&s[0][0], 7, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nf == 2 && total_holes(&c) == 1 && c.next == 1, "%zu faces %zu holes %zu ext", c.nf,
          total_holes(&c), c.next);
    for (size_t cy = 0; cy < c.ncyc; cy++)
        for (uint32_t i = c.cyc_off[cy]; i < c.cyc_off[cy + 1]; i++)
            for (uint32_t j = i + 1; j < c.cyc_off[cy + 1]; j++)
                CHECK(c.cyc[i] != c.cyc[j], "cycle %zu repeats vertex %u", cy, c.cyc[i]);
    CHECK(fabs(sum_face_areas(&c) - 16) < 1e-12, "area %g", sum_face_areas(&c));
    lar2_free(&c);
}

TEST(coarse_grid_snap_rounding_stress)
{
    /* on a coarse grid most segments pass through other segments' hot pixels: snap rounding
     * must still give a planar complex (lar_check: walks, Euler, areas) */
    double precs[] = {1.0 / 64, 0.013, 0.05};
    for (size_t t = 0; t < 3; t++)
        for (uint64_t seed = 1; seed <= 4; seed++) {
            double *s = random_lines(400, 0.3, seed * 31 + t);
            lar2 c;
            arr2_opts o = {.precision = precs[t], .keep_dangling = (int)(seed & 1)};
            REQUIRE(run(s, 400, &o, &c) == ARR_OK, "precision %g seed %d", precs[t], (int)seed);
            CHECK(c.nf > 0, "no faces");
            for (size_t v = 0; v < c.nv; v++) {
                double gx = c.V[2 * v] / precs[t], gy = c.V[2 * v + 1] / precs[t];
                CHECK(fabs(gx - nearbyint(gx)) < 1e-6 && fabs(gy - nearbyint(gy)) < 1e-6,
                      "vertex %zu (%g, %g) off the grid", v, c.V[2 * v], c.V[2 * v + 1]);
                if (test_failed_now()) break;
            }
            lar2_free(&c);
            free(s);
        }
}

TEST(planar_arrangement_jl_oracles)
{
    /* test/planar_arrangement.jl intersect_edges: V = (2,2),(4,2),(3,3.5),(1,3),(5,3),(1,2),
     * (5,2); edges (1,2),(2,3),(1,3),(4,5),(6,7).  Edge 5 overlaps edge 1 (the points (2,2)
     * at 1/4 and (4,2) at 3/4 of it), edge 4 misses edge 1, edges 1 and 2 meet at (4,2). */
    double s[5][4] = {{2, 2, 4, 2}, {4, 2, 3, 3.5}, {2, 2, 3, 3.5}, {1, 3, 5, 3}, {1, 2, 5, 2}};
    lar2 c;
    arr2_opts keep = {.keep_dangling = 1};
    REQUIRE(run(&s[0][0], 5, &keep, &c) == ARR_OK, "failed");
    /* vertices: the 7 given plus where (1,3)-(5,3) crosses the triangle's two slanted sides */
    CHECK(c.nv == 9, "V %zu, want 9", c.nv);
    /* edges: (1,2)-(2,2)-(4,2)-(5,2) 3, the slanted sides 2 pieces each, (1,3)-(5,3) 3 */
    CHECK(c.ne == 10, "E %zu, want 10", c.ne);
    CHECK(c.nf == 2, "F %zu, want 2 (the triangle cut in two)", c.nf);
    CHECK(fabs(sum_face_areas(&c) - 1.5) < 8 * c.stats.precision, "area %.17g, want 1.5",
          sum_face_areas(&c));
    lar2_free(&c);
    /* merge_vertices!: 16 points within 1e-12 of the unit square's corners, 16 edges ->
     * 4 vertices, 4 edges */
    double q[16][4];
    double cx[4] = {0, 1, 1, 0}, cy[4] = {0, 0, 1, 1};
    for (int i = 0; i < 16; i++) {
        int a = i % 4, b = (i + 1) % 4;
        double e1 = ((i * 7) % 5 - 2) * 0.5e-12, e2 = ((i * 3) % 5 - 2) * 0.5e-12;
        double r[4] = {cx[a] + e1, cy[a] - e2, cx[b] - e2, cy[b] + e1};
        memcpy(q[i], r, sizeof r);
    }
    REQUIRE(run(&q[0][0], 16, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nv == 4 && c.ne == 4 && c.nf == 1, "%zu V %zu E %zu F, want 4 4 1", c.nv, c.ne, c.nf);
    lar2_free(&c);
    /* a 3-edge star: no biconnected component, nothing left */
    double star[3][4] = {{0, 0, 1, 0}, {0, 0, 0, 1}, {0, 0, -1, -1}};
    REQUIRE(run(&star[0][0], 3, NULL, &c) == ARR_OK, "failed");
    CHECK(c.nv == 0 && c.ne == 0 && c.stats.blocks == 0, "%zu V %zu E", c.nv, c.ne);
    lar2_free(&c);
}

static int cmp_pt(const void *a, const void *b)
{
    const double *p = a, *q = b;
    return p[0] < q[0] ? -1 : p[0] > q[0] ? 1 : p[1] < q[1] ? -1 : p[1] > q[1];
}

/* Twice the signed area of a cycle, in differences from its first vertex (exact there by
 * Sterbenz: the drawing is small beside its coordinates). */
static double cycle_area2(const lar2 *c, uint32_t cy)
{
    const uint32_t *v = c->cyc + c->cyc_off[cy];
    size_t n = c->cyc_off[cy + 1] - c->cyc_off[cy];
    double x0 = c->V[2 * v[0]], y0 = c->V[2 * v[0] + 1], a = 0;
    for (size_t i = 0; i < n; i++) {
        uint32_t p = v[i], q = v[(i + 1) % n];
        a += (c->V[2 * p] - x0) * (c->V[2 * q + 1] - y0) -
             (c->V[2 * q] - x0) * (c->V[2 * p + 1] - y0);
    }
    return a;
}

TEST(far_from_origin_small_drawings)
{
    /* small random drawings at 1e6 .. 3e15: the automatic grid follows the doubles there, so
     * vertices stay distinct doubles, in grid order, and every face keeps a positive area */
    const double offs[] = {1e6, -1e9, 1e12, 7.3e13, -1e15, 3e15};
    uint64_t seed = 17;
    for (size_t t = 0; t < sizeof offs / sizeof *offs; t++)
        for (int rep = 0; rep < 5; rep++) {
            double s[60][4];
            for (int i = 0; i < 60; i++)
                for (int k = 0; k < 4; k++) s[i][k] = offs[t] + 20 * test_rnd(&seed);
            lar2 c;
            REQUIRE(run(&s[0][0], 60, NULL, &c) == ARR_OK, "offset %g failed", offs[t]);
            CHECK(c.nf > 10, "offset %g: only %zu faces", offs[t], c.nf);
            double *pts = malloc((2 * c.nv + 1) * sizeof *pts);
            REQUIRE(pts, "no memory");
            memcpy(pts, c.V, 2 * c.nv * sizeof *pts);
            qsort(pts, c.nv, 2 * sizeof *pts, cmp_pt);
            size_t same = 0, order = 0, flat = 0;
            for (size_t v = 1; v < c.nv; v++) {
                same += pts[2 * v] == pts[2 * v - 2] && pts[2 * v + 1] == pts[2 * v - 1];
                order += !(c.VG[2 * v - 2] < c.VG[2 * v] ||
                           (c.VG[2 * v - 2] == c.VG[2 * v] && c.VG[2 * v - 1] < c.VG[2 * v + 1]));
            }
            for (size_t f = 0; f < c.nf; f++) flat += !(cycle_area2(&c, c.face_cycle[f]) > 0);
            CHECK(same == 0 && order == 0 && flat == 0,
                  "offset %g: %zu vertices written as another's point, %zu out of grid order, "
                  "%zu faces without a positive area (of %zu V, %zu F; grid step %g)",
                  offs[t], same, order, flat, c.nv, c.nf, c.stats.precision);
            free(pts);
            lar2_free(&c);
        }
    /* a precision finer than the doubles there is refused, with the bound */
    double sq[4][4] = {{1e15, 1e15, 1e15 + 5, 1e15},
                       {1e15 + 5, 1e15, 1e15 + 5, 1e15 + 5},
                       {1e15 + 5, 1e15 + 5, 1e15, 1e15 + 5},
                       {1e15, 1e15 + 5, 1e15, 1e15}};
    arr2_opts o = {.precision = 0.01};
    lar2 c;
    char err[256];
    CHECK(arr2_build(&sq[0][0], 4, &o, &c, err, sizeof err) == ARR_ELIMIT, "0.01 at 1e15 accepted");
    CHECK(strstr(err, "options.precision: 0.01 is finer than the doubles near 1e+15") &&
              strstr(err, "use precision >= 0.25"),
          "message '%s'", err);
    o.precision = 0.25;
    CHECK(run(&sq[0][0], 4, &o, &c) == ARR_OK && c.nf == 1, "0.25 at 1e15: %zu faces", c.nf);
    lar2_free(&c);
}

/* ---- tri_tri_apart against edges through triangles --------------------------------------- */

/* Does segment ab pass through triangle pqr?  -1 when a test on the way is 0 (not generic). */
static int seg_tri(const int64_t *a, const int64_t *b, const int64_t *const t[3])
{
    int sa = orient3_grid(t[0], t[1], t[2], a), sb = orient3_grid(t[0], t[1], t[2], b);
    if (!sa || !sb) return -1;
    if (sa == sb) return 0;
    int s0 = orient3_grid(a, b, t[0], t[1]), s1 = orient3_grid(a, b, t[1], t[2]),
        s2 = orient3_grid(a, b, t[2], t[0]);
    if (!s0 || !s1 || !s2) return -1;
    return s0 == s1 && s1 == s2;
}

/* Do two triangles in general position meet (an edge of one through the other)?  -1 when the
 * position is not general. */
static int tri_tri_meet_ref(const int64_t *const p[3], const int64_t *const q[3])
{
    int any = 0;
    for (int k = 0; k < 3; k++) {
        int r1 = seg_tri(p[k], p[(k + 1) % 3], q), r2 = seg_tri(q[k], q[(k + 1) % 3], p);
        if (r1 < 0 || r2 < 0) return -1;
        any |= r1 | r2;
    }
    return any;
}

/* Do the three grid points span a plane (not on one line)? */
static int spans_plane(const int64_t *const t[3])
{
    int64_t u[3], v[3];
    for (int a = 0; a < 3; a++) u[a] = t[1][a] - t[0][a], v[a] = t[2][a] - t[0][a];
    return u[1] * v[2] != u[2] * v[1] || u[2] * v[0] != u[0] * v[2] || u[0] * v[1] != u[1] * v[0];
}

TEST(tri_tri_apart_matches_edges)
{
    uint64_t st = 99;
    size_t n = 200000, generic = 0, meet = 0, bad = 0;
    const char *e = getenv("CELLAR_STRESS");
    if (e && atoi(e) > 0) n *= (size_t)atoi(e);
    for (size_t it = 0; it < n && bad < 5; it++) {
        int64_t P[3][3], Q[3][3];
        /* small ranges make touching and crossing common; large ones test the arithmetic's
         * bounds (coordinates below 2^30) */
        int64_t R = it % 4 == 3 ? ((int64_t)1 << 29) : it % 4 == 2 ? 1000 : 6;
        for (int i = 0; i < 3; i++)
            for (int a = 0; a < 3; a++) {
                P[i][a] = (int64_t)(test_rnd(&st) * (double)(2 * R + 1)) - R;
                Q[i][a] = (int64_t)(test_rnd(&st) * (double)(2 * R + 1)) - R;
            }
        const int64_t *p[3] = {P[0], P[1], P[2]}, *q[3] = {Q[0], Q[1], Q[2]};
        if (!spans_plane(p) || !spans_plane(q)) continue;
        int apart = tri_tri_apart(p, q), ref = tri_tri_meet_ref(p, q);
        if (apart != tri_tri_apart(q, p)) {
            CHECK(0, "not symmetric at case %zu", it);
            bad++;
        }
        if (ref < 0) continue;
        generic++;
        meet += (size_t)ref;
        if (apart == ref) {
            CHECK(0, "case %zu: apart %d, edges say they %s", it, apart, ref ? "meet" : "do not");
            bad++;
        }
    }
    CHECK(generic > n / 4 && meet > generic / 20 && meet < generic, "%zu generic, %zu meeting",
          generic, meet);
}

/* The box-kd-tree built with the root's two sides on two threads is the tree one thread
 * builds, node for node and leaf for leaf; and it keeps the invariant the 2D pipeline relies
 * on: the leaf that a point locates to holds every box containing the point. */
TEST(box_tree_parallel_build_is_the_serial_one)
{
    uint64_t seed = 11;
    for (int family = 0; family < 4; family++) {
        size_t n = 20000 + (size_t)(test_rnd(&seed) * 30000);
        int64_t *box = malloc(4 * n * sizeof *box);
        REQUIRE(box, "malloc");
        for (size_t i = 0; i < n; i++) {
            int64_t x = (int64_t)(test_rnd(&seed) * 1e6), y = (int64_t)(test_rnd(&seed) * 1e6);
            int64_t w = (int64_t)(test_rnd(&seed) * 2e3), h = (int64_t)(test_rnd(&seed) * 2e3);
            if (family == 1) /* long thin boxes, horizontal and vertical */
                i % 2 ? (w *= 50, h = 0) : (h *= 50, w = 0);
            if (family == 2) x = x / 50, y = y / 50; /* crowded: every box meets many */
            if (family == 3 && i % 3) x = y;         /* along a diagonal */
            box[4 * i] = x, box[4 * i + 1] = y, box[4 * i + 2] = x + w, box[4 * i + 3] = y + h;
        }
        box_tree a, b;
        REQUIRE(box_tree_build(&a, box, n, 24) == 0, "serial build");
        REQUIRE(box_tree_build_par(&b, box, n, 24, 2) == 0, "parallel build");
        CHECK(a.nleaves == b.nleaves && a.nnodes == b.nnodes && a.nnodes > 1,
              "family %d: %zu/%zu leaves, %zu/%zu nodes", family, a.nleaves, b.nleaves, a.nnodes,
              b.nnodes);
        if (a.nleaves == b.nleaves && a.nnodes == b.nnodes) {
            size_t diff = 0;
            for (size_t k = 0; k < a.nnodes; k++)
                diff += a.nodes[k].t != b.nodes[k].t || a.nodes[k].axis != b.nodes[k].axis ||
                        a.nodes[k].child[0] != b.nodes[k].child[0] ||
                        a.nodes[k].child[1] != b.nodes[k].child[1];
            CHECK(diff == 0, "family %d: %zu nodes differ", family, diff);
            CHECK(!memcmp(a.leaf_off, b.leaf_off, (a.nleaves + 1) * sizeof *a.leaf_off) &&
                      !memcmp(a.items, b.items, a.leaf_off[a.nleaves] * sizeof *a.items) &&
                      !memcmp(a.region, b.region, 4 * a.nleaves * sizeof *a.region),
                  "family %d: leaves", family);
        }
        size_t bad = 0;
        for (int q = 0; q < 2000; q++) {
            size_t i = (size_t)(test_rnd(&seed) * (double)n);
            const int64_t *bx = box + 4 * i; /* a point of box i, a corner or inside */
            double x = (double)bx[0] + floor(test_rnd(&seed) * (double)(bx[2] - bx[0] + 1));
            double y = (double)bx[1] + floor(test_rnd(&seed) * (double)(bx[3] - bx[1] + 1));
            uint32_t l = box_tree_locate(&b, x, y), found = 0;
            for (uint32_t k = b.leaf_off[l]; k < b.leaf_off[l + 1]; k++) found |= b.items[k] == i;
            bad += !found;
        }
        CHECK(bad == 0, "family %d: %zu points whose box is not in their leaf", family, bad);
        box_tree_free(&a);
        box_tree_free(&b);
        free(box);
    }
}

/* The same index in 3D (box_tree_build_dim, dim 3): serial and parallel builds agree, it
 * splits along z too, every leaf holds exactly the boxes that meet its region, and the leaf a
 * point locates to holds every box containing it (checked against every box). */
TEST(box_tree_3d_locates_every_box_holding_a_point)
{
    uint64_t seed = 23;
    size_t n = 30000;
    int64_t *box = malloc(6 * n * sizeof *box);
    REQUIRE(box, "malloc");
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            int64_t lo = (int64_t)(test_rnd(&seed) * 1e5), w = (int64_t)(test_rnd(&seed) * 3e3);
            if (i % 7 == 0 && a == 2) w *= 30; /* tall boxes */
            box[6 * i + a] = lo, box[6 * i + 3 + a] = lo + w;
        }
    box_tree a, b;
    REQUIRE(box_tree_build_dim(&a, 3, box, n, 16, 1) == 0, "serial build");
    REQUIRE(box_tree_build_dim(&b, 3, box, n, 16, 2) == 0, "parallel build");
    CHECK(a.dim == 3 && a.nleaves == b.nleaves && a.nnodes == b.nnodes && a.nnodes > 100,
          "%zu/%zu leaves, %zu/%zu nodes", a.nleaves, b.nleaves, a.nnodes, b.nnodes);
    size_t zsplits = 0, diff = 0;
    for (size_t k = 0; k < a.nnodes && a.nnodes == b.nnodes; k++) {
        zsplits += a.nodes[k].axis == 2;
        diff += a.nodes[k].t != b.nodes[k].t || a.nodes[k].axis != b.nodes[k].axis;
    }
    CHECK(zsplits > 0 && diff == 0, "%zu splits along z, %zu nodes differ", zsplits, diff);
    size_t wrong = 0;
    for (size_t l = 0; l < a.nleaves && l < 40; l++) { /* the leaf holds what meets its region */
        const double *r = a.region + 6 * l;
        size_t meet = 0;
        for (size_t i = 0; i < n; i++) {
            int m = 1;
            for (int d = 0; d < 3; d++)
                m &= (double)box[6 * i + d] <= r[3 + d] && (double)box[6 * i + 3 + d] > r[d];
            meet += (size_t)m;
        }
        wrong += meet != a.leaf_off[l + 1] - a.leaf_off[l];
    }
    CHECK(wrong == 0, "%zu leaves whose items are not the boxes meeting their region", wrong);
    size_t bad = 0;
    for (int q = 0; q < 300; q++) {
        double p[3];
        for (int d = 0; d < 3; d++) p[d] = floor(test_rnd(&seed) * 1.1e5);
        uint32_t l = box_tree_locate_pt(&a, p);
        for (size_t i = 0; i < n; i++) {
            int in = 1;
            for (int d = 0; d < 3; d++)
                in &= (double)box[6 * i + d] <= p[d] && p[d] <= (double)box[6 * i + 3 + d];
            if (!in) continue;
            uint32_t found = 0;
            for (uint32_t k = a.leaf_off[l]; k < a.leaf_off[l + 1]; k++) found |= a.items[k] == i;
            bad += !found;
        }
    }
    CHECK(bad == 0, "%zu boxes holding a point but not in its leaf", bad);
    box_tree_free(&a);
    box_tree_free(&b);
    free(box);
}
