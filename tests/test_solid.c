/* test_solid.c — solids as face models (core/solid.h): solid_check and the OBJ and OFF readers.
 *
 * - closed-form solids: the unit cube (volume exactly 1, from both readers), inside out, with
 *   one face reversed, rotated (planar only up to rounding), an L-shaped prism (non-convex
 *   faces), a box with a square hole through it (faces with holes, a torus: V - E + F - holes
 *   = 0 on the merged skeleton);
 * - a face farther than the precision from planar: a warning at that face (the arrangement
 *   splits it into triangles), never an error;
 * - each error: open, non-manifold (a duplicated face; two cubes sharing an edge),
 *   fewer than 3 distinct vertices after merging, zero area, orientation no flip can fix,
 *   index out of range, non-finite coordinates, bad precision; the message cap;
 * - the readers' syntax (OBJ v/t/n forms, negative indices, comments, ignored statements; OFF
 *   headers, comments, colours) and their errors with line numbers, hostile counts included;
 * - the LAR.jl arrangement outputs of tests/data/mesh: read as one face soup (every triangle
 *   twice: non-manifold), then each 3-cell as a solid: the bounded cells' volumes add up to
 *   the exterior cell's.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "core/fastfloat.h"
#include "core/solid.h"
#include "tests/check.h"

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec / 1e6;
}

/* ---- helpers ------------------------------------------------------------------------------ */

/* A solid from nv vertices and a face list: each face is its cycles, the first the outer one,
 * a cycle ended by -1, a face by -2. */
static solid make(const double *V, size_t nv, const int *F, size_t nF)
{
    solid s = {0};
    s.nv = nv;
    s.V = malloc((3 * nv + 1) * sizeof *s.V);
    memcpy(s.V, V, 3 * nv * sizeof *s.V);
    s.face_off = malloc((nF + 1) * sizeof *s.face_off);
    s.cyc_off = malloc((nF + 1) * sizeof *s.cyc_off);
    s.cyc = malloc((nF + 1) * sizeof *s.cyc);
    s.face_off[0] = s.cyc_off[0] = 0;
    size_t ni = 0;
    for (size_t i = 0; i < nF; i++) {
        if (F[i] >= 0) {
            s.cyc[ni++] = (uint32_t)F[i];
            continue;
        }
        if (F[i] == -1 || i == 0 || F[i - 1] != -1) s.cyc_off[++s.ncyc] = (uint32_t)ni;
        if (F[i] == -2) s.face_off[++s.nf] = (uint32_t)s.ncyc;
    }
    return s;
}

#define MAKE(V, F) make(&(V)[0][0], sizeof(V) / sizeof((V)[0]), (F), sizeof(F) / sizeof((F)[0]))

static int has_msg(const solid_report *r, const char *needle)
{
    for (size_t i = 0; i < r->nmsg; i++)
        if (strstr(r->msg[i], needle)) return 1;
    return 0;
}

static void print_report(const char *what, const solid_report *r)
{
    printf("  %s: %zu errors, %zu warnings, volume %.17g, %zu flipped\n", what, r->errors,
           r->warnings, r->volume, r->flipped_faces);
    for (size_t i = 0; i < r->nmsg; i++) printf("    %s\n", r->msg[i]);
}

/* Corner i of the unit cube is (i & 1, i >> 1 & 1, i >> 2 & 1). */
static const double CUBE_V[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                    {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
/* outward: bottom, top, front (y=0), back (y=1), left (x=0), right (x=1) */
static const int CUBE_F[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

/* The face list of the cube's faces `which` (bit f), face `rev` (bits) reversed, plus the
 * faces in extra (-1 ended). */
static size_t cube_faces(int *F, unsigned which, unsigned rev)
{
    size_t n = 0;
    for (int f = 0; f < 6; f++) {
        if (!(which >> f & 1)) continue;
        for (int i = 0; i < 4; i++) F[n++] = CUBE_F[f][rev >> f & 1 ? 3 - i : i];
        F[n++] = -2;
    }
    return n;
}

static solid cube(unsigned which, unsigned rev)
{
    int F[64];
    size_t n = cube_faces(F, which, rev);
    return make(&CUBE_V[0][0], 8, F, n);
}

static const char CUBE_OBJ[] = "# the unit cube\n"
                               "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                               "v 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n"
                               "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

static const char CUBE_OFF[] = "OFF\n# the unit cube\n8 6 12\n"
                               "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                               "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n";

/* a (n entries) is b, or a rotation of b */
static int is_rotation(const uint32_t *a, const int *b, size_t n)
{
    for (size_t r = 0; r < n; r++) {
        size_t i = 0;
        while (i < n && a[i] == (uint32_t)b[(i + r) % n]) i++;
        if (i == n) return 1;
    }
    return 0;
}

/* s must check clean at precision p: no message, volume `vol` within tol. */
static void expect_clean(const char *what, const solid *s, double p, double vol, double tol)
{
    solid_report r;
    solid fx;
    int rc = solid_check(s, p, what, &r, &fx);
    CHECK(rc == 0 && r.errors == 0 && r.warnings == 0 && r.nmsg == 0,
          "%s: rc %d, %zu errors %zu warnings: %s", what, rc, r.errors, r.warnings,
          r.nmsg ? r.msg[0] : "");
    CHECK(fabs(r.volume - vol) <= tol, "%s: volume %.17g, want %.17g", what, r.volume, vol);
    CHECK(r.flipped_faces == 0, "%s: %zu flipped", what, r.flipped_faces);
    CHECK(rc != 0 || (fx.nf == s->nf && fx.nv == s->nv &&
                      !memcmp(fx.cyc, s->cyc, s->cyc_off[s->ncyc] * sizeof *s->cyc)),
          "%s: the fixed copy differs from a clean input", what);
    solid_free(&fx);
}

/* ---- the cube --------------------------------------------------------------------------- */

TEST(cube_from_obj_and_off)
{
    solid s;
    char err[200];
    REQUIRE(solid_read_obj(CUBE_OBJ, strlen(CUBE_OBJ), &s, err, sizeof err) == 0, "obj: %s", err);
    CHECK(s.nv == 8 && s.nf == 6 && s.ncyc == 6 && s.cyc_off[6] == 24, "obj: %zu V %zu F", s.nv,
          s.nf);
    solid_report r;
    CHECK(solid_check(&s, 1e-6, "obj", &r, NULL) == 0 && r.volume == 1.0 && r.nmsg == 0 &&
              r.warnings == 0,
          "obj cube: volume %.17g, %zu messages", r.volume, r.nmsg);
    expect_clean("obj", &s, 1e-6, 1, 0);
    solid o;
    REQUIRE(solid_read_off(CUBE_OFF, strlen(CUBE_OFF), &o, err, sizeof err) == 0, "off: %s", err);
    CHECK(o.nv == 8 && o.nf == 6 && o.ncyc == 6, "off: %zu V %zu F", o.nv, o.nf);
    CHECK(!memcmp(o.V, s.V, 24 * sizeof *o.V) && !memcmp(o.cyc, s.cyc, 24 * sizeof *o.cyc) &&
              !memcmp(o.face_off, s.face_off, 7 * sizeof *o.face_off) &&
              !memcmp(o.cyc_off, s.cyc_off, 7 * sizeof *o.cyc_off),
          "OBJ and OFF give different solids");
    expect_clean("off", &o, 1e-6, 1, 0);
    solid built = cube(63, 0);
    expect_clean("built", &built, 1e-3, 1, 0);
    solid_free(&built);
    solid_free(&s);
    solid_free(&o);
    solid_free(&o); /* twice is safe */
    CHECK(o.V == NULL && o.nv == 0 && o.nf == 0, "solid_free leaves a zeroed struct");
}

TEST(cube_inside_out_is_flipped)
{
    solid s = cube(63, 63);
    solid_report r;
    solid fx;
    REQUIRE(solid_check(&s, 1e-3, "inv", &r, &fx) == 0, "inside out: %s", r.msg[0]);
    print_report("inside out", &r);
    CHECK(r.errors == 0 && r.warnings == 1 && r.nmsg == 1, "%zu errors %zu warnings", r.errors,
          r.warnings);
    CHECK(has_msg(&r, "inv: inward oriented (volume -1): every face flipped"), "%s", r.msg[0]);
    CHECK(r.volume == 1.0 && r.flipped_faces == 6, "volume %.17g flipped %zu", r.volume,
          r.flipped_faces);
    /* the fixed copy is the outward cube, each cycle reversed keeping its first vertex */
    for (size_t f = 0; f < 6; f++) {
        const uint32_t *a = fx.cyc + fx.cyc_off[f], *b = s.cyc + s.cyc_off[f];
        CHECK(a[0] == b[0] && a[1] == b[3] && a[2] == b[2] && a[3] == b[1], "face %zu", f);
    }
    expect_clean("fixed", &fx, 1e-3, 1, 0);
    solid_free(&fx);
    solid_free(&s);
}

TEST(cube_one_face_reversed_is_fixed_by_bfs)
{
    for (unsigned f = 0; f < 6; f++) {
        solid s = cube(63, 1u << f);
        solid_report r;
        solid fx;
        REQUIRE(solid_check(&s, 1e-3, "one", &r, &fx) == 0, "face %u: %s", f, r.msg[0]);
        CHECK(r.errors == 0 && r.warnings == 1 && r.flipped_faces == 1 && r.volume == 1.0,
              "face %u reversed: %zu errors %zu warnings, %zu flipped, volume %g", f, r.errors,
              r.warnings, r.flipped_faces, r.volume);
        CHECK(has_msg(&r, "orientation inconsistent at 4 edges") &&
                  has_msg(&r, "flipped 1 of 6 faces"),
              "face %u: %s", f, r.msg[0]);
        if (f == 0) print_report("face 0 reversed", &r);
        expect_clean("one fixed", &fx, 1e-3, 1, 0);
        solid_free(&fx);
        solid_free(&s);
    }
    /* two reversed, and five (the majority then keeps the reversed orientation, and the
     * volume flips everything back): always the reversed faces and only them */
    unsigned revs[] = {3, 5, 31, 62};
    size_t want[] = {2, 2, 5, 5};
    for (size_t i = 0; i < 4; i++) {
        solid s = cube(63, revs[i]);
        solid_report r;
        solid fx;
        REQUIRE(solid_check(&s, 1e-3, "some", &r, &fx) == 0, "%s", r.msg[0]);
        CHECK(r.flipped_faces == want[i] && r.volume == 1.0, "rev %u: %zu flipped, volume %g",
              revs[i], r.flipped_faces, r.volume);
        for (size_t f = 0; f < 6; f++)
            CHECK(is_rotation(fx.cyc + 4 * f, CUBE_F[f], 4), "rev %u: face %zu not outward",
                  revs[i], f);
        expect_clean("some fixed", &fx, 1e-3, 1, 0);
        solid_free(&fx);
        solid_free(&s);
    }
}

/* The pairing the check hands to the arrangement (solid_check_nocopy's twins): every entry of
 * the usable solid (the input, or the fixed copy when faces were flipped) has its twin, which
 * walks the same edge the other way, and twins are mutual.  Cubes with 0 to 6 faces reversed
 * (6: inside out, every face flipped back), and an edge that four faces share (the surface
 * touching itself): no twins there. */
TEST(check_twins_are_the_usable_solids_pairs)
{
    for (unsigned rev = 0; rev < 64; rev += 7) {
        solid s = cube(63, rev), fx = {0};
        solid_report r;
        uint32_t tw[24];
        REQUIRE(solid_check_nocopy(&s, 1e-3, "tw", &r, &fx, tw) == 0, "rev %u: %s", rev, r.msg[0]);
        const solid *u = fx.nf ? &fx : &s;
        CHECK((fx.nf != 0) == (r.flipped_faces != 0), "rev %u: a copy iff faces flipped", rev);
        for (uint32_t i = 0; i < 24; i++) {
            uint32_t j = tw[i];
            REQUIRE(j < 24 && tw[j] == i, "rev %u: entry %u's twin %u", rev, i, j);
            uint32_t ni = i % 4 == 3 ? i - 3 : i + 1, nj = j % 4 == 3 ? j - 3 : j + 1;
            CHECK(u->cyc[i] == u->cyc[nj] && u->cyc[ni] == u->cyc[j],
                  "rev %u: entries %u and %u do not walk one edge both ways", rev, i, j);
        }
        solid_free(&fx);
        solid_free(&s);
    }
    /* cube A = [0,1]^3 and B = [1,2]x[1,2]x[0,1] touching along the edge x=y=1 (B's ends of it
     * merged with A's at the precision): that edge lies on four faces, and has no twins */
    double V[16][3];
    int F[2 * 6 * 5 + 1];
    size_t n = 0;
    for (int i = 0; i < 8; i++)
        for (int a = 0; a < 3; a++) {
            V[i][a] = CUBE_V[i][a];
            V[8 + i][a] = CUBE_V[i][a] + (a < 2 ? 1 : 0) + (a == 0 ? 1e-7 : 0);
        }
    for (int c = 0; c < 2; c++)
        for (int f = 0; f < 6; f++) {
            for (int i = 0; i < 4; i++) F[n++] = CUBE_F[f][i] + 8 * c;
            F[n++] = -2;
        }
    solid two = make(&V[0][0], 16, F, n), fx = {0};
    solid_report r;
    uint32_t tw[48];
    REQUIRE(solid_check_nocopy(&two, 1e-3, "two", &r, &fx, tw) == 0, "two: %s", r.msg[0]);
    size_t none = 0;
    for (uint32_t i = 0; i < 48; i++) {
        if (tw[i] == UINT32_MAX) {
            none++;
            continue;
        }
        CHECK(tw[i] < 48 && tw[tw[i]] == i, "two: entry %u's twin %u", i, tw[i]);
    }
    CHECK(none == 4, "two: %zu entries without a twin, want the 4 on the shared edge", none);
    solid_free(&fx);
    solid_free(&two);
}

/* ---- errors ------------------------------------------------------------------------------- */

TEST(cube_missing_face_is_open)
{
    solid s = cube(63 & ~2u, 0); /* no top */
    solid_report r;
    solid fx;
    CHECK(solid_check(&s, 1e-3, "open", &r, &fx) == -1, "open cube accepted");
    print_report("no top", &r);
    CHECK(r.errors == 4 && r.warnings == 0 && r.nmsg == 4, "%zu errors", r.errors);
    /* the top's edges 4-5, 5-7, 7-6, 6-4, each named by the side face that still has it
     * (faces renumbered without the top: front 1, back 2, left 3, right 4) */
    CHECK(has_msg(&r, "open: face 1: open surface (edge 5-4 has no other face)"), "%s", r.msg[0]);
    CHECK(has_msg(&r, "face 2: open surface (edge 6-7") &&
              has_msg(&r, "face 3: open surface (edge 4-6") &&
              has_msg(&r, "face 4: open surface (edge 7-5"),
          "%s", r.msg[0]);
    CHECK(fx.nf == 0 && fx.cyc == NULL, "a fixed copy of an unusable solid");
    solid_free(&s);
}

TEST(non_manifold_duplicated_face_and_shared_edge)
{
    int F[64];
    size_t n = cube_faces(F, 63, 0);
    for (int i = 0; i < 4; i++) F[n++] = CUBE_F[1][i];
    F[n++] = -2;
    solid s = make(&CUBE_V[0][0], 8, F, n);
    solid_report r;
    CHECK(solid_check(&s, 1e-3, "dup", &r, NULL) == -1, "duplicated face accepted");
    CHECK(r.errors == 4 && has_msg(&r, "non-manifold edge") && has_msg(&r, "(used 3 times,"),
          "%zu errors: %s", r.errors, r.msg[0]);
    print_report("duplicated top", &r);
    solid_free(&s);

    /* cube A = [0,1]^3 and B = [1,2]x[1,2]x[0,1] touch along the vertical edge x=y=1; B's
     * copies of that edge's ends are merged with A's at the precision */
    double V[16][3];
    for (int i = 0; i < 8; i++)
        for (int a = 0; a < 3; a++) {
            V[i][a] = CUBE_V[i][a];
            V[8 + i][a] = CUBE_V[i][a] + (a < 2 ? 1 : 0) + (a == 0 ? 1e-7 : 0);
        }
    n = 0;
    for (int c = 0; c < 2; c++)
        for (int f = 0; f < 6; f++) {
            for (int i = 0; i < 4; i++) F[n++] = CUBE_F[f][i] + 8 * c;
            F[n++] = -2;
        }
    s = make(&V[0][0], 16, F, n);
    /* an edge on 4 faces whose vertex indices pair them (A's two, B's two): one surface
     * touching itself, usable, with a warning at the face */
    CHECK(solid_check(&s, 1e-3, "two", &r, NULL) == 0 && r.errors == 0 && r.warnings == 1 &&
              has_msg(&r, "two: face 3: edge 7-3 lies on 4 faces: the surface touches itself") &&
              r.info[0].warning && r.info[0].at == SOLID_AT_FACE && r.info[0].index == 3 &&
              fabs(r.volume - 2) < 1e-6,
          "%zu errors: %s", r.errors, r.msg[0]);
    /* at a precision finer than the gap they are two cubes, 2 separate shells */
    expect_clean("two apart", &s, 1e-8, 2, 1e-12);
    solid_free(&s);
}

TEST(non_planar_beyond_and_within_the_precision)
{
    double V[8][3];
    memcpy(V, CUBE_V, sizeof V);
    V[7][2] = 1.01; /* lifts the top face's corner: the sides x=1 and y=1 stay planar */
    int F[64];
    size_t n = cube_faces(F, 63, 0);
    solid s = make(&V[0][0], 8, F, n);
    solid_report r;
    /* farther than the precision from planar: usable, with a warning (the arrangement splits
     * the face into triangles), located at the face */
    CHECK(solid_check(&s, 1e-3, "bent", &r, NULL) == 0, "bent top refused at 1e-3");
    print_report("bent top", &r);
    CHECK(r.errors == 0 && r.warnings == 1 && r.split_faces == 1 &&
              has_msg(&r, "bent: face 1: not planar (vertex ") &&
              has_msg(&r, "is 0.0025 from its plane, precision 0.001): split into triangles") &&
              r.info[0].warning == 1 && r.info[0].at == SOLID_AT_FACE && r.info[0].index == 1,
          "%zu errors %zu warnings: %s", r.errors, r.warnings, r.msg[0]);
    CHECK(fabs(r.volume - (1 + 0.01 / 3)) < 1e-15, "volume %.17g", r.volume);
    /* the volume: the cube plus the tetrahedron-like wedge under the lifted corner; the fan
     * from vertex 4 splits the top into (4,5,7) and (4,7,6): each adds 0.01/6 */
    expect_clean("bent at 1e-2", &s, 1e-2, 1 + 0.01 / 3, 1e-15);
    solid_free(&s);
}

/* The unit cube turned about an axis through its centre: its quads are planar only up to
 * rounding, which any sensible precision accepts. */
TEST(rotated_cube_is_planar_at_the_precision)
{
    uint64_t seed = 7;
    for (int t = 0; t < 20; t++) {
        double ax[3], len = 0;
        for (int a = 0; a < 3; a++) ax[a] = test_rnd(&seed) - 0.5, len += ax[a] * ax[a];
        len = sqrt(len);
        for (int a = 0; a < 3; a++) ax[a] /= len;
        double th = 6.283185307179586 * test_rnd(&seed), c = cos(th), s = sin(th), k = 1 - c;
        double R[3][3] = {
            {c + ax[0] * ax[0] * k, ax[0] * ax[1] * k - ax[2] * s, ax[0] * ax[2] * k + ax[1] * s},
            {ax[1] * ax[0] * k + ax[2] * s, c + ax[1] * ax[1] * k, ax[1] * ax[2] * k - ax[0] * s},
            {ax[2] * ax[0] * k - ax[1] * s, ax[2] * ax[1] * k + ax[0] * s, c + ax[2] * ax[2] * k}};
        double V[8][3];
        for (int i = 0; i < 8; i++)
            for (int a = 0; a < 3; a++) {
                V[i][a] = 10;
                for (int b = 0; b < 3; b++) V[i][a] += R[a][b] * (CUBE_V[i][b] - 0.5);
            }
        int F[64];
        size_t n = cube_faces(F, 63, 0);
        solid so = make(&V[0][0], 8, F, n);
        expect_clean("rotated", &so, 1e-9, 1, 1e-13);
        solid_free(&so);
    }
}

TEST(fewer_than_three_distinct_vertices_after_merging)
{
    /* the top face uses vertex 8, a copy of vertex 7 moved by 1e-5: one vertex at 1e-3 (the
     * cube), two at 1e-7 (the top's edges to 8 are then open) */
    double V[9][3];
    memcpy(V, CUBE_V, sizeof CUBE_V);
    V[8][0] = V[8][1] = 1;
    V[8][2] = 1 + 1e-5;
    int F[64];
    size_t n = cube_faces(F, 63, 0);
    F[7] = 8; /* top: 4 5 8 6 */
    solid s = make(&V[0][0], 9, F, n);
    expect_clean("merged", &s, 1e-3, 1, 1e-4);
    solid_report r;
    CHECK(solid_check(&s, 1e-7, "apart", &r, NULL) == -1 && r.errors == 4 && r.warnings == 1 &&
              has_msg(&r, "apart: face 1: open surface (edge 5-8 has no other face)") &&
              has_msg(&r, "apart: face 1: not planar (vertex 4 is 2.5e-06 from its plane"),
          "%zu errors: %s", r.errors, r.msg[0]);
    solid_free(&s);

    /* a triangle (0, 8, 1) where 8 is 1e-5 from 0: two distinct vertices at 1e-3 */
    V[8][0] = V[8][1] = V[8][2] = 1e-5;
    n = cube_faces(F, 63, 0);
    int tri[] = {0, 8, 1, -2};
    memcpy(F + n, tri, sizeof tri);
    s = make(&V[0][0], 9, F, n + 4);
    /* a warning (the face is left out), and another: the triangle's edge 8-1 is the cube's
     * edge 0-1 on the grid, and 1-0 its own too, so that edge is on 4 faces walked twice each
     * way (a surface touching itself), taken */
    CHECK(solid_check(&s, 1e-3, "thin", &r, NULL) == 0 &&
              has_msg(&r, "thin: face 6: degenerate on the grid of step 0.001 (fewer than 3 "
                          "distinct vertices): left out") &&
              has_msg(&r, "walking it each way"),
          "%zu errors: %s", r.errors, r.msg[0]);
    print_report("collapsed triangle", &r);
    solid_free(&s);
}

TEST(degenerate_holes)
{
    /* the bottom with an empty hole, then with a hole of 2 vertices (its two edges pair with
     * each other): reported, nothing else, and never read past the cycle */
    int F[64];
    size_t n = cube_faces(F, 63, 0);
    int empty[] = {0, 2, 3, 1, -1, -1, -2}, two[] = {0, 2, 3, 1, -1, 0, 3, -2};
    int *holes[] = {empty, two};
    size_t len[] = {7, 8};
    for (int h = 0; h < 2; h++) {
        int G[64];
        memcpy(G, holes[h], len[h] * sizeof *G);
        memcpy(G + len[h], F + 5, (n - 5) * sizeof *G);
        solid s = make(&CUBE_V[0][0], 8, G, len[h] + n - 5);
        REQUIRE(s.nf == 6 && s.ncyc == 7, "hole %d: %zu faces %zu cycles", h, s.nf, s.ncyc);
        solid_report r;
        CHECK(solid_check(&s, 1e-3, "hole", &r, NULL) == -1 && r.errors == 1 &&
                  has_msg(&r, "hole: face 0: hole 1: fewer than 3 distinct vertices"),
              "hole %d: %zu errors: %s", h, r.errors, r.msg[0]);
        solid_free(&s);
    }
}

TEST(zero_area_and_other_errors)
{
    const double V[4][3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}};
    const int F[] = {0, 1, 2, -2, 0, 3, 1, -2};
    solid s = MAKE(V, F);
    solid_report r;
    CHECK(solid_check(&s, 1e-6, "flat", &r, NULL) == -1 && r.degenerate_faces == 1 &&
              has_msg(&r, "flat: face 0: degenerate on the grid of step 1e-06 (its vertices on "
                          "one line): left out"),
          "%zu errors: %s", r.errors, r.msg[0]);
    s.cyc[3] = 9; /* out of range */
    CHECK(solid_check(&s, 1e-6, "idx", &r, NULL) == -1 && r.errors == 1 &&
              has_msg(&r, "idx: face 1: vertex index 9 out of range (4 vertices)"),
          "%zu errors: %s", r.errors, r.msg[0]);
    s.cyc[3] = 0;
    s.V[4] = NAN;
    CHECK(solid_check(&s, 1e-6, "nan", &r, NULL) == -1 && r.errors == 1 &&
              has_msg(&r, "nan: vertex 1: coordinate 1 is not finite"),
          "%zu errors: %s", r.errors, r.msg[0]);
    s.V[4] = 1e300;
    CHECK(solid_check(&s, 1e-6, "big", &r, NULL) == -1 && r.errors == 1 &&
              has_msg(&r, "too large for precision"),
          "%zu errors: %s", r.errors, r.msg[0]);
    s.V[4] = 0;
    CHECK(solid_check(&s, 0, NULL, &r, NULL) == -1 &&
              has_msg(&r, "solid: precision 0 is not a positive number"),
          "%s", r.msg[0]);
    CHECK(solid_check(&s, NAN, "p", NULL, NULL) == -1, "NaN precision accepted");
    solid_free(&s);
    solid empty = {0};
    uint32_t zero = 0;
    empty.face_off = empty.cyc_off = &zero;
    CHECK(solid_check(&empty, 1, "e", &r, NULL) == -1 && has_msg(&r, "e: no faces"), "%s",
          r.msg[0]);
    CHECK(solid_check(NULL, 1, "n", &r, NULL) == -1 && has_msg(&r, "n: no solid"), "%s", r.msg[0]);

    /* a flat "solid": a square and its reverse, closed and oriented, volume 0 */
    const int G[] = {0, 1, 3, -2, 3, 1, 0, -2};
    s = MAKE(V, G);
    CHECK(solid_check(&s, 1e-6, "sheet", &r, NULL) == -1 && r.errors == 1 &&
              has_msg(&r, "sheet: degenerate: volume 0 for area 1"),
          "%zu errors: %s", r.errors, r.msg[0]);
    solid_free(&s);
}

TEST(messages_are_capped_but_counted)
{
    /* 50 separate triangles: 150 open edges */
    double V[150][3];
    int F[200];
    for (int t = 0; t < 50; t++) {
        for (int i = 0; i < 3; i++) {
            V[3 * t + i][0] = t * 10 + (i == 1);
            V[3 * t + i][1] = i == 2;
            V[3 * t + i][2] = 0;
            F[4 * t + i] = 3 * t + i;
        }
        F[4 * t + 3] = -2;
    }
    solid s = MAKE(V, F);
    solid_report r;
    CHECK(solid_check(&s, 1e-3, "many", &r, NULL) == -1, "accepted");
    CHECK(r.errors == 150 && r.nmsg == SOLID_MAX_MESSAGES, "%zu errors, %zu kept", r.errors,
          r.nmsg);
    solid_free(&s);
}

/* ---- non-convex faces, faces with holes ------------------------------------------------- */

/* Distinct undirected edges of a solid whose vertices are all distinct (test meshes). */
static size_t count_edges(const solid *s)
{
    size_t n = s->cyc_off[s->ncyc], m = 0;
    uint64_t *e = malloc(n * sizeof *e);
    for (size_t k = 0; k < s->ncyc; k++)
        for (uint32_t i = s->cyc_off[k]; i < s->cyc_off[k + 1]; i++) {
            uint32_t a = s->cyc[i], b = s->cyc[i + 1 < s->cyc_off[k + 1] ? i + 1 : s->cyc_off[k]];
            e[m++] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        }
    size_t d = 0;
    for (size_t i = 0; i < m; i++) {
        int seen = 0;
        for (size_t j = 0; j < i && !seen; j++) seen = e[j] == e[i];
        d += !seen;
    }
    free(e);
    return d;
}

TEST(l_shaped_prism)
{
    /* L = (0,0) (2,0) (2,1) (1,1) (1,2) (0,2), area 3, extruded to height 1 */
    const double L[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
    double V[12][3];
    for (int i = 0; i < 12; i++) V[i][0] = L[i % 6][0], V[i][1] = L[i % 6][1], V[i][2] = i / 6;
    int F[64], n = 0;
    for (int i = 5; i >= 0; i--) F[n++] = i; /* bottom, seen from below */
    F[n++] = -2;
    for (int i = 6; i < 12; i++) F[n++] = i;
    F[n++] = -2;
    for (int i = 0; i < 6; i++) {
        int j = (i + 1) % 6, q[5] = {i, j, j + 6, i + 6, -2};
        memcpy(F + n, q, sizeof q);
        n += 5;
    }
    solid s = make(&V[0][0], 12, F, (size_t)n);
    expect_clean("L", &s, 1e-6, 3, 0);
    CHECK(12 - count_edges(&s) + 8 == 2, "L: Euler %zu edges", count_edges(&s));
    solid_free(&s);
}

/* [0,3]^2 x [0,1] with the square hole [1,2]^2 through it: a torus, volume 8.  top_hole_rev
 * walks the top's hole the wrong way (counter-clockwise, like the outer cycle). */
static solid holed_box(int top_hole_rev)
{
    const double sq[8][2] = {{0, 0}, {3, 0}, {3, 3}, {0, 3}, {1, 1}, {2, 1}, {2, 2}, {1, 2}};
    double V[16][3];
    for (int i = 0; i < 16; i++) V[i][0] = sq[i % 8][0], V[i][1] = sq[i % 8][1], V[i][2] = i / 8;
    int F[80], n = 0;
    int top[] = {8, 9, 10, 11, -1, 12, 15, 14, 13, -2};
    int top_rev[] = {8, 9, 10, 11, -1, 12, 13, 14, 15, -2};
    int bottom[] = {0, 3, 2, 1, -1, 4, 5, 6, 7, -2};
    memcpy(F + n, top_hole_rev ? top_rev : top, sizeof top);
    n += 10;
    memcpy(F + n, bottom, sizeof bottom);
    n += 10;
    for (int i = 0; i < 4; i++) {
        int j = (i + 1) % 4;
        int out[5] = {i, j, j + 8, i + 8, -2}, in[5] = {j + 4, i + 4, i + 12, j + 12, -2};
        memcpy(F + n, out, sizeof out);
        memcpy(F + n + 5, in, sizeof in);
        n += 10;
    }
    return make(&V[0][0], 16, F, (size_t)n);
}

TEST(box_with_a_hole_is_a_torus)
{
    solid s = holed_box(0);
    CHECK(s.nf == 10 && s.ncyc == 12, "%zu faces %zu cycles", s.nf, s.ncyc);
    expect_clean("torus", &s, 1e-6, 8, 0);
    size_t E = count_edges(&s), holes = s.ncyc - s.nf;
    CHECK(E == 24 && 16 - (long)E + (long)s.nf - (long)holes == 0, "V-E+F-holes: 16-%zu+%zu-%zu", E,
          s.nf, holes);
    /* a vertex of the top's hole lifted: the top is not planar (holes count), the inner sides
     * it belongs to stay planar (it moves within their planes) */
    solid_report r;
    s.V[3 * 13 + 2] += 0.01;
    CHECK(solid_check(&s, 1e-3, "lifted", &r, NULL) == 0 && r.warnings == 1 && r.split_faces == 1 &&
              has_msg(&r, "lifted: face 0: not planar (vertex "),
          "%zu errors: %s", r.errors, r.msg[0]);
    s.V[3 * 13 + 2] -= 0.01;
    /* all flipped: inward, every face (and hole) reversed in the fixed copy */
    for (size_t k = 0; k < s.ncyc; k++)
        for (uint32_t i = s.cyc_off[k], j = s.cyc_off[k + 1] - 1; i < j; i++, j--) {
            uint32_t t = s.cyc[i];
            s.cyc[i] = s.cyc[j];
            s.cyc[j] = t;
        }
    solid fx;
    CHECK(solid_check(&s, 1e-6, "inv torus", &r, &fx) == 0 && r.volume == 8 &&
              r.flipped_faces == 10 && r.warnings == 1,
          "inverted torus: volume %g, %zu flipped", r.volume, r.flipped_faces);
    expect_clean("torus fixed", &fx, 1e-6, 8, 0);
    solid_free(&fx);
    solid_free(&s);
}

/* The top's hole walked like its outer cycle: each inner side must flip to agree with the top
 * and stay to agree with the bottom.  No set of face flips fixes it. */
TEST(orientation_no_flip_can_fix)
{
    solid s = holed_box(1);
    solid_report r;
    solid fx;
    CHECK(solid_check(&s, 1e-6, "twisted", &r, &fx) == -1, "accepted");
    print_report("hole walked the wrong way", &r);
    /* the hole turns as its outer cycle does on the grid (exact), and so its walls cannot
     * agree with both faces */
    CHECK(r.errors == 2 &&
              has_msg(&r, "twisted: face 0: hole 1: turns the same way as the outer cycle") &&
              has_msg(&r, "cannot be oriented consistently"),
          "%zu errors: %s", r.errors, r.msg[0]);
    CHECK(fx.nf == 0 && fx.V == NULL, "fixed copy of an unusable solid");
    solid_free(&s);

    /* a projective plane: a cross-cap (a face walking edge 0-1 twice the same way) closed
     * by a disc along its boundary 1 2 0 3; every edge used exactly twice */
    const double V[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}};
    const int F[] = {0, 1, 2, 0, 1, 3, -2, 1, 2, 0, 3, -2};
    s = MAKE(V, F);
    solid_check(&s, 1e-6, "self", &r, NULL);
    print_report("projective plane", &r);
    CHECK(has_msg(&r, "self: face 0: walks edge 0-1 twice in the same direction") &&
              has_msg(&r, "cannot be oriented consistently") && !has_msg(&r, "open") &&
              !has_msg(&r, "non-manifold"),
          "%zu errors: %s", r.errors, r.msg[0]);
    solid_free(&s);
}

/* ---- size ---------------------------------------------------------------------------------- */

/* The box [0,k]^3 with every side a k x k grid of unit quads: 6k^2 + 2 vertices, 6k^2 faces,
 * volume k^3; every third face reversed when `shuffle`. */
static solid grid_box(int k, int shuffle)
{
    size_t side = (size_t)k + 1, nq = 6 * (size_t)k * (size_t)k, nv = 0;
    int32_t *id = malloc(side * side * side * sizeof *id);
    double *V = malloc(3 * (6 * side * side) * sizeof *V);
    int *F = malloc(5 * nq * sizeof *F);
    memset(id, 0xff, side * side * side * sizeof *id);
    size_t n = 0, q = 0;
    for (int a = 0; a < 3; a++)
        for (int sd = 0; sd <= k; sd += k) {
            int u = (a + 1) % 3, w = (a + 2) % 3;
            for (int i = 0; i < k; i++)
                for (int j = 0; j < k; j++) {
                    int corner[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}}, cyc[4];
                    for (int c = 0; c < 4; c++) {
                        int p[3];
                        p[a] = sd;
                        p[u] = i + corner[c][0];
                        p[w] = j + corner[c][1];
                        size_t key = ((size_t)p[0] * side + (size_t)p[1]) * side + (size_t)p[2];
                        if (id[key] < 0) {
                            for (int x = 0; x < 3; x++) V[3 * nv + (size_t)x] = p[x];
                            id[key] = (int32_t)nv++;
                        }
                        cyc[c] = id[key];
                    }
                    /* e_u x e_w = e_a: counter-clockwise seen from +a, outward on side k */
                    int rev = (sd == 0) ^ (shuffle && q % 3 == 1);
                    for (int c = 0; c < 4; c++) F[n++] = cyc[rev ? 3 - c : c];
                    F[n++] = -2;
                    q++;
                }
        }
    solid s = make(V, nv, F, n);
    free(id);
    free(V);
    free(F);
    return s;
}

TEST(large_box_is_checked_in_n_log_n)
{
    int k = 150;
    size_t nq = 6 * (size_t)k * (size_t)k;
    solid s = grid_box(k, 0);
    REQUIRE(s.nf == nq && s.nv == nq + 2, "%zu V %zu F", s.nv, s.nf);
    solid_report r;
    solid fx;
    double t0 = now_ms();
    int rc = solid_check(&s, 1e-6, "box", &r, &fx);
    double ms = now_ms() - t0;
    CHECK(rc == 0 && r.nmsg == 0 && r.volume == (double)k * k * k, "box: %zu errors, volume %.17g",
          r.errors, r.volume);
    solid_free(&fx);
    solid_free(&s);
    s = grid_box(k, 1);
    t0 = now_ms();
    rc = solid_check(&s, 1e-6, "shuffled", &r, &fx);
    double ms2 = now_ms() - t0;
    CHECK(rc == 0 && r.warnings == 1 && r.flipped_faces == nq / 3 && r.volume == (double)k * k * k,
          "shuffled: %zu warnings, %zu flipped, volume %.17g: %s", r.warnings, r.flipped_faces,
          r.volume, r.msg[0]);
    printf("  %zu faces: %.0f ms clean, %.0f ms with %zu faces to flip (one BFS, no recursion)\n",
           nq, ms, ms2, nq / 3);
    solid_free(&fx);
    solid_free(&s);
}

/* ---- faces on the grid: crossings, touches, holes (core/facecheck.c) ---------------------- */

#define END NAN /* ends a cycle in a face's points; two end the face */

/* The prism of height h over the face (x, y points, cycles ended by END, the last by two):
 * every cycle point gets its own bottom and top vertex (2i at z = 0, 2i + 1 at z = h, or
 * h + lift for the first point), so cycles that touch share positions, not indices.  Face 0 is
 * the top, its cycles as given (outer counter-clockwise seen from above, holes clockwise, unless
 * a case wants otherwise), face 1 the bottom, then a wall per edge. */
static solid prism(const double *pts, double h, double lift)
{
    size_t np = 0, ncyc = 0, k = 0;
    for (; !(isnan(pts[k]) && isnan(pts[k + 1])); k++)
        if (isnan(pts[k]))
            ncyc++;
        else
            np++, k++;
    ncyc++;
    np = np;
    double *V = malloc(6 * np * sizeof *V);
    size_t *start = malloc((ncyc + 1) * sizeof *start), c = 0, i = 0;
    start[0] = 0;
    for (k = 0; c < ncyc; k++) {
        if (isnan(pts[k])) {
            start[++c] = i;
            continue;
        }
        double z = h + (i == 0 ? lift : 0);
        double row[6] = {pts[k], pts[k + 1], 0, pts[k], pts[k + 1], z};
        memcpy(V + 6 * i, row, sizeof row);
        i++, k++;
    }
    int *F = malloc((2 * (np + ncyc) + 6 * np + 8) * sizeof *F);
    size_t n = 0;
    for (int top = 1; top >= 0; top--) {
        for (c = 0; c < ncyc; c++) {
            size_t len = start[c + 1] - start[c];
            for (size_t j = 0; j < len; j++)
                F[n++] = (int)(2 * (start[c] + (top ? j : len - 1 - j)) + (size_t)top);
            F[n++] = -1;
        }
        F[n - 1] = -2;
    }
    for (c = 0; c < ncyc; c++) {
        size_t len = start[c + 1] - start[c];
        for (size_t j = 0; j < len; j++) {
            int a = (int)(2 * (start[c] + j)), b = (int)(2 * (start[c] + (j + 1) % len));
            F[n++] = a, F[n++] = b, F[n++] = b + 1, F[n++] = a + 1, F[n++] = -2;
        }
    }
    solid s = make(V, 2 * np, F, n);
    free(V);
    free(start);
    free(F);
    return s;
}

typedef struct face_case {
    const char *name;
    double precision, h, lift;
    const double *pts;
    double volume;    /* > 0: usable, with this volume */
    const char *want; /* else: its first error holds this */
} face_case;

/* the face 0..8 square, counter-clockwise, and the same with more points on its sides */
#define SQ        0, 0, 8, 0, 8, 8, 0, 8, END
#define SQ_4      0, 0, 4, 0, 8, 0, 8, 8, 0, 8, END
#define SQ_46     0, 0, 4, 0, 6, 0, 8, 0, 8, 8, 0, 8, END
#define SQ_4_4    0, 0, 4, 0, 8, 0, 8, 8, 4, 8, 0, 8, END
#define FACE(...) ((const double[]){__VA_ARGS__, END, END})
#define P64       (1.0 / 64)

static const face_case face_cases[] = {
    /* usable: a hole; holes touching the outer cycle or each other at a point they share */
    {"hole", P64, 4, 0, FACE(SQ, 2, 2, 2, 4, 4, 4, 4, 2), 240, NULL},
    {"hole touching the outer cycle", P64, 4, 0, FACE(SQ_4, 4, 0, 3, 2, 5, 2), 248, NULL},
    {"holes touching each other", P64, 4, 0, FACE(SQ, 2, 2, 3, 4, 4, 2, END, 4, 2, 5, 4, 6, 2), 240,
     NULL},
    /* a chain outer - hole - hole - outer: the face's inside is in two parts */
    {"holes across the face", P64, 4, 0,
     FACE(SQ_4_4, 4, 0, 3, 2, 4, 4, 5, 2, END, 4, 4, 3, 6, 4, 8, 5, 6), 224, NULL},
    /* four holes at one point, each in its own quarter */
    {"four holes at one point", P64, 4, 0,
     FACE(SQ, 4, 4, 6, 5, 6, 3, END, 4, 4, 2, 3, 2, 5, END, 4, 4, 3, 6, 5, 6, END, 4, 4, 5, 2, 3,
          2),
     224, NULL},
    /* valid at a fine grid; at step 1 the tip (2, 2.25) snaps to (2, 2), below the snapped edge
     * (0, 2)-(4, 3): the outer cycle crosses itself there */
    {"fine grid", P64, 4, 0, FACE(0, 1.625, 4, 2.625, 4, 6, 2, 2.25, 0, 6), 32, NULL},
    {"coarse grid", 1, 4, 0, FACE(0, 1.625, 4, 2.625, 4, 6, 2, 2.25, 0, 6), 0,
     "prism: face 0: its outer cycle crosses itself (edges 1-3 and 5-7) on the grid of step 1"},
    /* a hole near the outer cycle: at step 1 its tip snaps onto the outer cycle's edge */
    {"hole, fine grid", P64, 4, 0, FACE(SQ, 3, 1, 5, 1, 4, 0.25), 253, NULL},
    {"hole, coarse grid", 1, 4, 0, FACE(SQ, 3, 1, 5, 1, 4, 0.25), 0,
     "prism: face 0: hole 1: vertex 13 of one cycle lies inside edge 1-3 of another (a "
     "T-junction)"},
    /* refused */
    {"bowtie", P64, 4, 0, FACE(0, 0, 8, 8, 8, 0, 0, 8), 0,
     "prism: face 0: its outer cycle crosses itself (edges 1-3 and 5-7) on the grid of step "
     "0.015625"},
    {"hole crossing the outer cycle", P64, 4, 0, FACE(SQ, 6, 2, 6, 4, 10, 4, 10, 2), 0,
     "prism: face 0: hole 1: crosses the outer cycle (edges 3-5 and 11-13)"},
    {"holes crossing", P64, 4, 0, FACE(SQ, 2, 2, 2, 5, 5, 5, 5, 2, END, 4, 4, 4, 6, 6, 6, 6, 4), 0,
     "prism: face 0: hole 1: crosses another hole (edges 11-13 and 17-19)"},
    {"hole crossing the outer cycle at two vertices", P64, 4, 0,
     FACE(SQ_46, 4, 0, 5, 1, 6, 0, 5, -1), 0,
     "prism: face 0: hole 1: crosses the outer cycle at vertex 3"},
    {"holes crossing at two vertices", P64, 4, 0,
     FACE(SQ, 2, 4, 4, 6, 6, 4, 4, 2, END, 4, 6, 7, 7, 6, 4, 4.5, 4.5), 0,
     "prism: face 0: hole 1: crosses another hole at vertex"},
    {"pinch", P64, 4, 0, FACE(0, 0, 8, 0, 4, 4, 8, 8, 0, 8, 4, 4), 0,
     "prism: face 0: its outer cycle passes twice through one point (vertices 5 and 11)"},
    {"hole outside", P64, 4, 0, FACE(SQ, 10, 2, 10, 4, 12, 4, 12, 2), 0,
     "prism: face 0: hole 1: lies outside the outer cycle"},
    {"hole inside a hole", P64, 4, 0, FACE(SQ, 1, 1, 1, 7, 7, 7, 7, 1, END, 3, 3, 3, 5, 5, 5, 5, 3),
     0, "prism: face 0: hole 2: lies inside another hole (the one through vertex 9)"},
    {"hole turning the same way", P64, 4, 0, FACE(SQ, 2, 2, 4, 2, 4, 4, 2, 4), 0,
     "prism: face 0: hole 1: turns the same way as the outer cycle"},
    {"T-junction", P64, 4, 0, FACE(SQ, 4, 0, 3, 2, 5, 2), 0,
     "prism: face 0: hole 1: vertex 9 of one cycle lies inside edge 1-3 of another (a "
     "T-junction)"},
    {"running back", P64, 4, 0, FACE(0, 0, 8, 0, 8, 8, 3, 8, 6, 8, 0, 8), 0,
     "prism: face 0: its outer cycle runs back along itself (edges 5-7 and 7-9 overlap)"},
    {"touching itself", P64, 4, 0, FACE(0, 0, 8, 0, 8, 8, 6, 8, 4, 0, 2, 8, 0, 8), 0,
     "prism: face 0: its outer cycle touches itself: vertex 9 lies inside its edge 1-3"},
    /* not planar (the first top vertex raised): split into triangles of its projection, which
     * must be a polygon */
    {"not planar", P64, 4, 1, FACE(SQ, 2, 2, 2, 4, 4, 4, 4, 2), -1, NULL},
    {"not planar, crossing", P64, 4, 1, FACE(0, 0, 8, 0, 8, 8, 0, 8, 4, -2), 0,
     "prism: face 0: not planar, and seen along z its outer cycle crosses itself (edges"},
};

TEST(faces_on_the_grid)
{
    for (size_t i = 0; i < sizeof face_cases / sizeof *face_cases; i++) {
        const face_case *fc = &face_cases[i];
        solid s = prism(fc->pts, fc->h, fc->lift), fx;
        solid_report r;
        int rc = solid_check(&s, fc->precision, "prism", &r, &fx);
        if (fc->volume != 0) {
            CHECK(rc == 0 && r.errors == 0, "%s: refused: %s", fc->name, r.msg[0]);
            CHECK(fc->volume < 0 || r.volume == fc->volume, "%s: volume %.17g, want %g", fc->name,
                  r.volume, fc->volume);
            solid_free(&fx);
        } else {
            size_t first = 0;
            while (first < r.nmsg && r.info[first].warning) first++;
            CHECK(rc == -1 && first < r.nmsg && strstr(r.msg[first], fc->want),
                  "%s: rc %d, first error \"%s\", want \"%s\"", fc->name, rc,
                  first < r.nmsg ? r.msg[first] : "(none)", fc->want);
        }
        solid_free(&s);
    }
}

/* The two inputs fuzzing found (tests/fuzz/corpus), at the grid step the API takes for them. */
TEST(fuzz_faces_refused)
{
    static const struct {
        const char *path, *want;
    } fz[] = {
        /* a pyramid whose base is a bowtie */
        {"tests/fuzz/corpus/obj/bowtie-face-refused.obj",
         "s: face 0: its outer cycle crosses itself (edges 3-2 and 1-0) on the grid of step "
         "5.96046e-08"},
        /* the grid of a coordinate near 1e13 (step 16384) collapses face 14 onto two lines */
        {"tests/fuzz/corpus/off/grid-collapses-face-refused.off",
         "s: face 14: its outer cycle runs back along itself (edges 15-16 and 6-5 overlap) on "
         "the grid of step 16384"},
    };
    for (size_t i = 0; i < sizeof fz / sizeof *fz; i++) {
        size_t len;
        char *text = test_read_file(fz[i].path, &len), err[200];
        REQUIRE(text, "%s: cannot read", fz[i].path);
        solid s;
        int off = strstr(fz[i].path, ".off") != NULL;
        int rc = off ? solid_read_off(text, len, &s, err, sizeof err)
                     : solid_read_obj(text, len, &s, err, sizeof err);
        free(text);
        REQUIRE(rc == 0, "%s: %s", fz[i].path, err);
        /* the API's step: the power of two just above extent * 2^-30 */
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t v = 0; v < s.nv; v++)
            for (int a = 0; a < 3; a++) {
                lo[a] = fmin(lo[a], s.V[3 * v + a]);
                hi[a] = fmax(hi[a], s.V[3 * v + a]);
            }
        double ext = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
        double step = exp2(ceil(log2(ext * 0x1p-30)));
        solid_report r;
        rc = solid_check(&s, step, "s", &r, NULL);
        size_t first = 0;
        while (first < r.nmsg && r.info[first].warning) first++;
        CHECK(rc == -1 && first < r.nmsg && strstr(r.msg[first], fz[i].want),
              "%s: rc %d, first error \"%s\"", fz[i].path, rc,
              first < r.nmsg ? r.msg[first] : "(none)");
        solid_free(&s);
    }
}

/* The holes' places in a face of more edges than the all-pairs check takes (the rays then go
 * through the box tree): inside, touching the outer cycle, outside, inside another hole. */
TEST(holes_in_a_large_face)
{
    static const struct {
        double hole[2][8]; /* two square holes, clockwise; the second may be absent (NAN) */
        const char *want;  /* NULL: usable */
    } cases[] = {
        {{{-10, -10, -10, 10, 10, 10, 10, -10}, {100, 100, 100, 200, 200, 200, 200, 100}}, NULL},
        /* touching the outer cycle at its point (1000, 0) */
        {{{1000, 0, 900, -50, 900, 50, NAN}, {-10, -10, -10, 10, 10, 10, 10, -10}}, NULL},
        {{{-10, -10, -10, 10, 10, 10, 10, -10}, {2000, 0, 2000, 10, 2010, 10, 2010, 0}},
         "big: face 0: hole 2: lies outside the outer cycle"},
        {{{-100, -100, -100, 100, 100, 100, 100, -100}, {-10, -10, -10, 10, 10, 10, 10, -10}},
         "big: face 0: hole 2: lies inside another hole (the one through vertex 257)"},
        {{{-10, -10, -10, 10, 10, 10, 10, -10}, {-100, -100, -100, 100, 100, 100, 100, -100}},
         "big: face 0: hole 1: lies inside another hole (the one through vertex 265)"},
    };
    size_t n = 128;
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        double pts[2 * 128 + 2 * 10 + 8], area = 0;
        size_t m = 0;
        for (size_t i = 0; i < n; i++) { /* a regular polygon of radius 1000, (1000, 0) first */
            double a = 2 * M_PI * (double)i / (double)n;
            pts[m++] = i ? round(1000 * cos(a)) : 1000, pts[m++] = i ? round(1000 * sin(a)) : 0;
        }
        for (size_t i = 0; i < n; i++)
            area += (pts[2 * i] * pts[2 * ((i + 1) % n) + 1] -
                     pts[2 * ((i + 1) % n)] * pts[2 * i + 1]) /
                    2;
        for (int h = 0; h < 2; h++) {
            const double *q = cases[c].hole[h];
            size_t k = isnan(q[6]) ? 3 : 4;
            pts[m++] = END;
            for (size_t i = 0; i < 2 * k; i++) pts[m++] = q[i];
            for (size_t i = 0; i < k; i++) /* clockwise: subtracts */
                area +=
                    (q[2 * i] * q[2 * ((i + 1) % k) + 1] - q[2 * ((i + 1) % k)] * q[2 * i + 1]) / 2;
        }
        pts[m++] = END, pts[m++] = END;
        solid s = prism(pts, 100, 0), fx;
        solid_report r;
        int rc = solid_check(&s, 1, "big", &r, &fx);
        if (!cases[c].want) {
            CHECK(rc == 0 && r.volume == 100 * area, "case %zu: %s, volume %.17g, want %.17g", c,
                  r.msg[0], r.volume, 100 * area);
            solid_free(&fx);
        } else {
            CHECK(rc == -1 && has_msg(&r, cases[c].want), "case %zu: %d %s", c, rc, r.msg[0]);
        }
        solid_free(&s);
    }
}

/* Faces of 200 000 points and of 20 000 holes touching each other at their corners (a
 * checkerboard), checked in about n log n; and the big one with two points swapped (a crossing
 * among 200 000 edges) refused. */
TEST(large_faces_are_checked_near_linearly)
{
    size_t n = 200000;
    double *pts = malloc((2 * n + 4) * sizeof *pts);
    for (size_t i = 0; i < n; i++) {
        double a = 2 * M_PI * (double)i / (double)n;
        pts[2 * i] = round(1e7 * cos(a)), pts[2 * i + 1] = round(1e7 * sin(a));
    }
    pts[2 * n] = pts[2 * n + 1] = END;
    for (int swap = 0; swap < 2; swap++) {
        if (swap) { /* points 1000 and 1001 swapped */
            double t[2] = {pts[2000], pts[2001]};
            pts[2000] = pts[2002], pts[2001] = pts[2003], pts[2002] = t[0], pts[2003] = t[1];
        }
        solid s = prism(pts, 1e6, 0);
        solid_report r;
        double t0 = now_ms();
        int rc = solid_check(&s, 1, "circle", &r, NULL);
        double ms = now_ms() - t0;
        if (!swap)
            CHECK(rc == 0 && fabs(r.volume - M_PI * 1e20) < 1e-6 * M_PI * 1e20,
                  "circle: %d %s, volume %g", rc, r.msg[0], r.volume);
        else
            CHECK(rc == -1 && has_msg(&r, "circle: face 0: its outer cycle "), "swapped: %d %s", rc,
                  r.msg[0]);
        CHECK(ms < 20000 * slowdown(), "%.0f ms", ms);
        printf("  a face of %zu points%s: %.0f ms (the solid: %zu faces)\n", n,
               swap ? ", two swapped" : "", ms, s.nf);
        solid_free(&s);
    }
    free(pts);
    /* a 200 x 200 checkerboard of unit holes in a square of side 202 */
    int N = 200;
    size_t m = 0;
    pts = malloc((10 + 10 * (size_t)N * (size_t)N / 2 + 10) * sizeof *pts);
    double sq[] = {-1, -1, N + 1, -1, N + 1, N + 1, -1, N + 1};
    memcpy(pts, sq, sizeof sq);
    m = 8;
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++) {
            if ((i + j) % 2) continue;
            double h[] = {END, i, j, i, j + 1, i + 1, j + 1, i + 1, j}; /* clockwise */
            memcpy(pts + m, h, sizeof h);
            m += 9;
        }
    pts[m++] = END, pts[m++] = END;
    solid s = prism(pts, 4, 0);
    solid_report r;
    double t0 = now_ms();
    int rc = solid_check(&s, 0.125, "board", &r, NULL);
    double ms = now_ms() - t0;
    double area = (double)(N + 2) * (N + 2) - (double)N * N / 2;
    CHECK(rc == 0 && r.volume == 4 * area, "board: %d, volume %g", rc, r.volume);
    CHECK(ms < 20000 * slowdown(), "%.0f ms", ms);
    printf("  a face of %d holes touching at %d points: %.0f ms\n", N * N / 2,
           (N - 1) * (N - 1) / 2 * 2, ms);
    /* at step 1 it is thinner than the grid: the error comes after 39 601 warnings (an edge on
     * four faces at each point where holes touch), and is kept */
    rc = solid_check(&s, 1, "board", &r, NULL);
    CHECK(rc == -1 && r.errors == 1 && r.nmsg == SOLID_MAX_MESSAGES &&
              strstr(r.msg[SOLID_MAX_MESSAGES - 1], "board: degenerate: volume"),
          "board at step 1: %d, %zu errors, %zu warnings, last kept: %s", rc, r.errors, r.warnings,
          r.msg[r.nmsg - 1]);
    solid_free(&s);
    free(pts);
}

/* ---- OBJ ---------------------------------------------------------------------------------- */

static void obj_fails(const char *text, const char *want)
{
    solid s;
    char err[200] = "";
    int rc = solid_read_obj(text, strlen(text), &s, err, sizeof err);
    CHECK(rc == -1 && strstr(err, want), "OBJ %s: rc %d, \"%s\", want \"%s\"", text, rc, err, want);
    CHECK(s.nv == 0 && s.nf == 0 && s.V == NULL && s.cyc == NULL, "OBJ %s: out not empty", text);
}

TEST(obj_syntax)
{
    const char *t = "# cube, every index form\r\n"
                    "mtllib cube.mtl\no cube\n"
                    "v 0 0 0 1.0\nv 1 0 0\nv 0 1 0\nv 1 1 0   # a comment after a vertex\n"
                    "vt 0 0\nvt 1 0\nvn 0 0 1\nvp 0.5\n"
                    "v 0 0 1 0.1 0.2 0.3\nv 1.0e0 0 1\nv 0 +1 1.\nv 1 1 1\n"
                    "g side\ns off\nusemtl red\n"
                    "f 1/1 3/2 4/1 2/2\n"
                    "f -4 -3 -1 -2\n"
                    "f 1//1 2//1 6//1 5//1\n"
                    "f 3/1/1 7/2/1 8/1/1 4/2/1\n"
                    "l 1 2\np 3\n"
                    "\tf\t1 5 7 3\n"
                    "f 2 4 8 -3 # comment\n";
    solid s;
    char err[200];
    REQUIRE(solid_read_obj(t, strlen(t), &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 8 && s.nf == 6, "%zu V %zu F", s.nv, s.nf);
    solid c;
    REQUIRE(solid_read_obj(CUBE_OBJ, strlen(CUBE_OBJ), &c, err, sizeof err) == 0, "%s", err);
    CHECK(!memcmp(s.V, c.V, sizeof(double[24])) && !memcmp(s.cyc, c.cyc, sizeof(uint32_t[24])),
          "the forms do not give the cube");
    expect_clean("obj forms", &s, 1e-9, 1, 0);
    solid_free(&s);
    solid_free(&c);
    /* no newline at the end; no faces at all */
    REQUIRE(solid_read_obj("v 0 0 0", 7, &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 1 && s.nf == 0 && s.face_off && s.cyc_off && s.cyc_off[0] == 0, "one vertex");
    solid_free(&s);
    REQUIRE(solid_read_obj("", 0, &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 0 && s.nf == 0, "empty");
    solid_free(&s);
}

TEST(obj_errors_name_the_line)
{
    const char *tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    char t[256];
#define OBJ_FAILS(line, want) (snprintf(t, sizeof t, "%s%s", tri, line), obj_fails(t, want))
    OBJ_FAILS("f 0 1 2\n", "line 4: vertex index 0 out of range");
    OBJ_FAILS("f 1 2 4\n", "line 4: vertex index 4 out of range (3 vertices so far");
    OBJ_FAILS("f 1 2 -4\n", "line 4: vertex index -4 out of range");
    OBJ_FAILS("\n# x\nf 1 2\n", "line 6: a face needs 3 vertices, this one has 2");
    OBJ_FAILS("f\n", "line 4: a face needs 3 vertices, this one has 0");
    OBJ_FAILS("f 1 2 x\n", "line 4: malformed vertex reference 'x'");
    OBJ_FAILS("f 1 2 3/4/5/6\n", "line 4: malformed vertex reference '3/4/5/6'");
    OBJ_FAILS("f 1 2 3/\n", "line 4: malformed vertex reference");
    OBJ_FAILS("f 1 2 3.0\n", "line 4: malformed vertex reference '3.0'");
    OBJ_FAILS("f 1 2 99999999999999999999\n", "line 4: malformed vertex reference");
    OBJ_FAILS("v 1 2 x\n", "line 4: malformed number 'x'");
    OBJ_FAILS("v 1 2\n", "line 4: a vertex has 3 coordinates, this one 2");
    OBJ_FAILS("v 1 2 3 4 5 6 7 8\n", "line 4: a vertex has 3 coordinates, this one 8");
    OBJ_FAILS("v 1 2 1e999\n", "line 4: malformed number '1e999'");
    OBJ_FAILS("v nan 0 0\n", "line 4: malformed number 'nan'");
    OBJ_FAILS("v 0x1p3 0 0\n", "line 4: malformed number '0x1p3'");
    OBJ_FAILS("v 1..2 0 0\n", "line 4: malformed number '1..2'");
#undef OBJ_FAILS
    obj_fails("f 1 2 3\nv 0 0 0\n", "line 1: vertex index 1 out of range (0 vertices so far");
    /* a NUL byte is a separator, not the end of the text */
    solid s;
    char err[200];
    const char nul[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\0003\n";
    CHECK(solid_read_obj(nul, sizeof nul - 1, &s, err, sizeof err) == 0 && s.nf == 1 &&
              s.cyc_off[1] == 3,
          "NUL: %s", err);
    solid_free(&s);
}

/* ---- OFF ---------------------------------------------------------------------------------- */

static void off_fails(const char *text, const char *want)
{
    solid s;
    char err[200] = "";
    int rc = solid_read_off(text, strlen(text), &s, err, sizeof err);
    CHECK(rc == -1 && strstr(err, want), "OFF %s: rc %d, \"%s\", want \"%s\"", text, rc, err, want);
    CHECK(s.nv == 0 && s.nf == 0 && s.V == NULL && s.cyc == NULL, "OFF %s: out not empty", text);
}

TEST(off_syntax)
{
    const char *forms[] = {
        /* counts on the header line, comments everywhere, colours on faces */
        "# made by hand\nOFF 8 6 12 # counts\n\n"
        "0 0 0\n1 0 0\n0 1 0\n1 1 0 # corner 3\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
        "# faces\n4 0 2 3 1 255 0 0\n4 4 5 7 6 0.5 0.5 0.5 1\n4 0 1 5 4 3\n"
        "4  2 6 7 3\r\n\t4 0 4 6 2\n4 1 3 7 5\n# the end\n",
        /* no header; two counts */
        "8 6\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
        "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5",
        /* CNOFF: colour and normal after each vertex */
        "CNOFF\n8 6 0\n0 0 0 1 0 0 1 0 0 -1\n1 0 0 1 0 0 1 0 0 -1\n0 1 0 1 0 0 1 0 0 -1\n"
        "1 1 0 1 0 0 1 0 0 -1\n0 0 1 1 0 0 1 0 0 1\n1 0 1 1 0 0 1 0 0 1\n"
        "0 1 1 1 0 0 1 0 0 1\n1 1 1 1 0 0 1 0 0 1\n"
        "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n",
        /* numbers with signs, exponents and long fractions; signed indices; NUL as a
         * separator */
        "OFF\n8 6 0\n+0 0 0e5\n1.000000000000000000 0 0\n0 10000000000e-10 0\n1 1 0\n"
        "0 0 .1e1\n1. 0 1\n0 1 1\n1 1 1\n"
        "4 +0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 -0 4 6 2\n4 1 3 7 +5\0",
    };
    solid c;
    char err[200];
    REQUIRE(solid_read_off(CUBE_OFF, strlen(CUBE_OFF), &c, err, sizeof err) == 0, "%s", err);
    for (size_t i = 0; i < sizeof forms / sizeof *forms; i++) {
        solid s;
        size_t len = strlen(forms[i]) + (i == 3); /* the last form ends with a NUL */
        REQUIRE(solid_read_off(forms[i], len, &s, err, sizeof err) == 0, "form %zu: %s", i, err);
        CHECK(s.nv == 8 && s.nf == 6 && !memcmp(s.V, c.V, sizeof(double[24])) &&
                  !memcmp(s.cyc, c.cyc, sizeof(uint32_t[24])),
              "form %zu is not the cube", i);
        expect_clean("off form", &s, 1e-9, 1, 0);
        solid_free(&s);
    }
    solid_free(&c);
    solid s;
    REQUIRE(solid_read_off("OFF\n0 0 0\n", 10, &s, err, sizeof err) == 0, "%s", err);
    CHECK(s.nv == 0 && s.nf == 0, "empty OFF");
    solid_free(&s);
}

/* The process's peak resident size so far, in MB. */
static double peak_mb(void)
{
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return (double)u.ru_maxrss / 1024;
}

TEST(off_errors_name_the_line)
{
    off_fails("", "line 0: empty: no OFF header");
    off_fails("# only a comment\n", "line 1: empty: no OFF header");
    off_fails("ply\nformat ascii 1.0\n", "line 1: not an OFF file (it starts with 'ply')");
    off_fails("4OFF\n1 0 0\n0 0 0 1\n", "line 1: '4OFF': only 3D OFF is read");
    off_fails("nOFF\n", "only 3D OFF");
    off_fails("OFF\n", "line 1: no counts after the OFF header");
    off_fails("OFF\n3\n", "line 2: counts 'vertices faces edges' missing");
    off_fails("OFF\n3 1 0 4\n", "line 2: counts are 'vertices faces edges', not '4' at value 4");
    off_fails("OFF\n3 -1 0\n", "line 2: counts are");
    off_fails("OFF\n3 x 0\n", "line 2: counts are 'vertices faces edges', not 'x' at value 2");
    off_fails("OFF\n0 0 0\n3 0 1 2\n", "line 3: data after the last of the 0 faces");
    const char *tri = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n";
    char t[256];
#define OFF_FAILS(line, want) (snprintf(t, sizeof t, "%s%s", tri, line), off_fails(t, want))
    OFF_FAILS("3 0 1 3\n", "line 6: vertex index '3' out of range (3 vertices)");
    OFF_FAILS("3 0 1 -1\n", "line 6: vertex index '-1' out of range");
    /* the index itself is named, not the token before it (the face's count was) */
    OFF_FAILS("3 0 1 7\n", "line 6: vertex index '7' out of range (3 vertices)");
    OFF_FAILS("2 0 1 # short\n",
              "line 6: a face starts with its vertex count (3 to 1000000), not '2'");
    OFF_FAILS("4 0 1 2\n", "line 6: the face announces 4 vertices, 3 given");
    OFF_FAILS("3 0 1 2 1 1 1 1 1\n", "line 6: after the 3 indices of a face only a colour may "
                                     "follow, not '1'");
    OFF_FAILS("3 0 1 2 red\n", "only a colour may follow, not 'red'");
    /* an index is read in one pass: a token that only begins with digits is named whole */
    OFF_FAILS("3 0 1 2x\n", "line 6: vertex index '2x' out of range (3 vertices)");
    OFF_FAILS("3 0 1 1234567890123456789\n", "vertex index '1234567890123456789' out of range");
    OFF_FAILS("3 0 1 2\n3 0 1 2\n", "line 7: data after the last of the 1 faces");
    OFF_FAILS("# a comment long enough to pass the size test\n",
              "line 6: the file ends after 0 of 1 faces");
    OFF_FAILS("", "line 2: 3 vertices and 1 faces announced, but only 18 bytes follow");
#undef OFF_FAILS
    off_fails("OFF\n3 1 0\n0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n", "line 4: malformed number 'x'");
    off_fails("OFF\n3 1 0\n0 0 0\n1 0 1.25e3q\n0 1 0\n3 0 1 2\n",
              "line 4: malformed number '1.25e3q'");
    off_fails("OFF\n3 1 0\n0 0 0\n1 0 0.123456789012x\n0 1 0\n3 0 1 2\n",
              "line 4: malformed number '0.123456789012x'");
    off_fails("OFF\n3 1 0\n0 0 0\n1 0 # a comment to pass the size test\n0 1 0\n3 0 1 2\n",
              "line 4: a vertex has 3 coordinates, this one 2");
    off_fails("OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0 # a comment long enough to pass the size test\n",
              "line 5: the file ends after 3 of 4 vertices");

    /* hostile counts: over the limit, or within it but without the data */
    off_fails("OFF\n1000000000000 1 0\n0 0 0\n",
              "line 2: 1000000000000 vertices and 1 faces: at most 64000000");
    off_fails("OFF\n3 1000000000000 0\n", "at most 64000000");
    off_fails("OFF 99999999999999999999 1 0\n", "line 1: counts are");
    /* 10^7 vertices would be 240 MB of doubles: refused before anything is allocated, checked
     * with an address-space limit (not under the sanitizers, which reserve terabytes) */
    struct rlimit old;
    int limited = 0;
    FILE *st = fopen("/proc/self/statm", "r");
    unsigned long pages = 0;
    if (!getenv("CELLAR_SANITIZED") && st && fscanf(st, "%lu", &pages) == 1 &&
        getrlimit(RLIMIT_AS, &old) == 0) {
        struct rlimit lim = old;
        lim.rlim_cur = (rlim_t)pages * (rlim_t)sysconf(_SC_PAGESIZE) + (64u << 20);
        if (old.rlim_cur == RLIM_INFINITY || lim.rlim_cur < old.rlim_cur)
            limited = setrlimit(RLIMIT_AS, &lim) == 0;
    }
    if (st) fclose(st);
    double m0 = peak_mb();
    off_fails("OFF\n10000000 10000000 0\n0 0 0\n1 0 0\n",
              "line 2: 10000000 vertices and 10000000 faces announced, but only 12 bytes follow");
    /* counts believable for the size, data malformed far before the end */
    size_t n = 3 << 20;
    char *big = malloc(n + 64);
    int k = snprintf(big, 64, "OFF\n%zu 0 0\n0 0 0\n1 0 x\n", n / 8);
    memset(big + k, ' ', n - (size_t)k);
    big[n] = 0;
    off_fails(big, "line 4: malformed number 'x'");
    if (limited) setrlimit(RLIMIT_AS, &old);
    double grew = peak_mb() - m0;
    CHECK(grew < 64, "peak memory grew by %.0f MB", grew);
    printf("  hostile counts: address space %s, peak +%.0f MB\n",
           limited ? "limited to +64 MB" : "not limited", grew);
    free(big);
}

/* ---- the arrangement outputs of tests/data/mesh ------------------------------------------- */

/* The text of an OBJ file with only the faces of group `g` (1-based "g" statements in file
 * order), every other line kept; the caller frees. */
static char *obj_group(const char *text, int g)
{
    size_t len = strlen(text), k = 0;
    char *out = malloc(len + 1);
    int cur = 0;
    for (const char *p = text; *p;) {
        const char *e = strchr(p, '\n');
        e = e ? e + 1 : p + strlen(p);
        if (p[0] == 'g' && p[1] == ' ') cur++;
        if (!(p[0] == 'f' && p[1] == ' ') || cur == g) {
            memcpy(out + k, p, (size_t)(e - p));
            k += (size_t)(e - p);
        }
        p = e;
    }
    out[k] = 0;
    return out;
}

/* Reads an arrangement's OBJ: as one solid, where every triangle comes twice (once for each
 * cell beside it), so each edge of the triangulated complex lies on 4 or more faces: taken when
 * as many walk it each way (cells turned alike: nedges 0), else one error an edge whose faces
 * do not balance (nedges of them, cells turned inward); then cell by cell; returns the bounded
 * cells' total volume and sets *exterior. */
static double arrangement_cells(const char *name, size_t nv, size_t nf, size_t nedges, int ncells,
                                double precision, double *exterior)
{
    char path[512], err[200];
    snprintf(path, sizeof path, "%s/mesh/%s", test_data_dir(), name);
    size_t len;
    char *text = test_read_file(path, &len);
    *exterior = 0;
    if (!text) {
        test_fail(__FILE__, __func__, __LINE__, "cannot read %s", path);
        return 0;
    }
    solid s;
    if (solid_read_obj(text, len, &s, err, sizeof err)) {
        test_fail(__FILE__, __func__, __LINE__, "%s: %s", name, err);
        free(text);
        return 0;
    }
    CHECK(s.nv == nv && s.nf == nf && s.ncyc == nf && s.cyc_off[nf] == 3 * nf,
          "%s: %zu V %zu F, want %zu %zu", name, s.nv, s.nf, nv, nf);
    solid_report r;
    int rc1 = solid_check(&s, precision, name, &r, NULL);
    if (nedges)
        CHECK(rc1 == -1 && r.errors == nedges && has_msg(&r, "non-manifold edge") &&
                  !has_msg(&r, "open surface"),
              "%s as one solid: %zu errors: %s", name, r.errors, r.msg[0]);
    else
        CHECK(rc1 == 0 && r.errors == 0 && has_msg(&r, "walking it each way"),
              "%s as one solid: %zu errors: %s", name, r.errors, r.msg[0]);
    printf("  %s as one solid: %zu V, %zu faces, %zu errors (first message: %s)\n", name, s.nv,
           s.nf, r.errors, r.msg[0]);
    solid_free(&s);
    double sum = 0;
    size_t faces = 0, flipped = 0, inward = 0;
    for (int g = 1; g <= ncells; g++) {
        char *t = obj_group(text, g), label[64];
        snprintf(label, sizeof label, "%s cell%d", name, g);
        if (solid_read_obj(t, strlen(t), &s, err, sizeof err)) {
            test_fail(__FILE__, __func__, __LINE__, "%s: %s", label, err);
            free(t);
            continue;
        }
        solid fx;
        int rc = solid_check(&s, precision, label, &r, &fx);
        CHECK(rc == 0 && r.errors == 0 && r.volume > 0, "%s: %zu errors: %s", label, r.errors,
              r.msg[0]);
        if (rc == 0) {
            solid_report r2;
            CHECK(solid_check(&fx, precision, label, &r2, NULL) == 0 && r2.warnings == 0 &&
                      r2.volume == r.volume,
                  "%s: the fixed copy is not clean: %s", label, r2.msg[0]);
        }
        faces += s.nf;
        flipped += r.flipped_faces;
        inward += has_msg(&r, "inward oriented");
        if (g == 1)
            *exterior = r.volume;
        else
            sum += r.volume;
        solid_free(&fx);
        solid_free(&s);
        free(t);
    }
    CHECK(faces == nf, "%s: the cells hold %zu faces, want %zu", name, faces, nf);
    printf("  %s: %d cells, %zu faces flipped to agree, %zu cells inward; bounded volumes %.9g, "
           "exterior %.9g\n",
           name, ncells, flipped, inward, sum, *exterior);
    free(text);
    return sum;
}

TEST(two_cubes_arrangement_cells)
{
    /* every cell turned outward: each edge's faces balance */
    double ext, sum = arrangement_cells("two_cubes.obj", 20, 88, 0, 4, 1e-7, &ext);
    /* two unit cubes, the second turned pi/3 about z and moved up by 1/2: the union is 2 minus
     * the overlap, a prism of height 1/2 over the square and turned square's intersection,
     * whose area is tan(pi/12) = 2 - sqrt(3); the file's coordinates have 6 decimals */
    CHECK(fabs(sum - ext) < 1e-12 && fabs(sum - (1 + sqrt(3) / 2)) < 1e-5,
          "bounded %.17g exterior %.17g, want 1 + sqrt(3)/2", sum, ext);
}

TEST(fivecubes_arrangement_cells)
{
    /* 10 cells turned inward: the 150 edges where their faces meet others' do not balance */
    double ext, sum = arrangement_cells("fivecubes.obj", 137, 952, 150, 27, 1e-7, &ext);
    CHECK(fabs(sum - ext) < 1e-12 && sum > 0, "bounded %.17g exterior %.17g", sum, ext);
}

/* ---- the readers' numbers: core/fastfloat.h against strtod ------------------------------- */

static uint64_t ff_next(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* One string: both parsers accept it or refuse it, and agree bit for bit. */
static int ff_agree(const char *str, size_t *bad)
{
    double a = 0, b;
    char *end;
    int ra = ff_parse(str, str + strlen(str), &a);
    b = strtod(str, &end);
    int rb = (*end == 0 && end != str && isfinite(b)) ? 0 : -1;
    uint64_t ba, bb;
    memcpy(&ba, &a, 8);
    memcpy(&bb, &b, 8);
    if (ra != rb || (ra == 0 && ba != bb)) {
        if ((*bad)++ < 5)
            fprintf(stderr, "fastfloat: '%s': %d %.17g, strtod %d %.17g\n", str, ra, a, rb, b);
        return 0;
    }
    return 1;
}

/* Random doubles printed every way a file may hold them, random digit strings with random
 * exponents (short, long, beyond 19 digits, subnormal, overflowing), the integers about 2^53
 * and 2^64 where every other one is a tie, and the classic hard cases: each read as strtod
 * reads it.  Malformed strings are refused by both. */
TEST(fastfloat_is_strtod)
{
    static const char *hard[] = {
        "9007199254740993",
        "9007199254740995",
        "1e23",
        "8.98846567431158e307",
        "1.7976931348623157e308",
        "1.7976931348623158e308",
        "1.7976931348623159e308",
        "2.2250738585072011e-308",
        "2.2250738585072014e-308",
        "4.9406564584124654e-324",
        "2.4703282292062327e-324",
        "2.4703282292062328e-324",
        "1e-400",
        "1e400",
        "-0",
        "0e999",
        "0.000000000000000000000000000000000000001",
        "123456789012345678901234567890",
        "7.038531e-26",
        "9223372036854775807",
        "9223372036854775808",
        "18446744073709551615",
        "18446744073709551616",
        "1.00000000000000011102230246251565404236316680908203125",
        "1.00000000000000011102230246251565404236316680908203124",
        "0.1",
        "0.2",
        "0.3",
        "3.14159265358979323846264338327950288",
        ".5",
        "5.",
        "+1",
        "-1e-5",
        "1E+5",
        "1e",
        "e5",
        ".",
        "+",
        "-",
        "1.2.3",
        "1e5.5",
        "--1",
        "1-1",
        "",
        "00000000000000000000001",
        "1.000000000000000000000000000000000000000000000000000000000000000000000001"};
    /* eight digits at a time: every position of a byte that is no digit, runs that end inside
     * a word, a word after leading zeros */
    static const char *octets[] = {"12345678.87654321",
                                   "1.2345678x",
                                   "1.23456/89",
                                   "1.234567:9",
                                   "1.2345678901234567",
                                   "91.234567890123456",
                                   "912345678901.2345678",
                                   "0.000000012345678901234567",
                                   "00000000123456789.99999999",
                                   "9.99999999999999999999",
                                   "1.2345678e-7",
                                   "19999999.99999999e3",
                                   "1 2345678"};
    size_t bad = 0, n = 0;
    for (size_t i = 0; i < sizeof hard / sizeof *hard; i++, n++) ff_agree(hard[i], &bad);
    for (size_t i = 0; i < sizeof octets / sizeof *octets; i++, n++) ff_agree(octets[i], &bad);
    uint64_t s = 24;
    char buf[96];
    for (int i = 0; i < 200000; i++, n++) {
        uint64_t r = ff_next(&s), bits = ff_next(&s);
        double d;
        memcpy(&d, &bits, 8);
        if (!isfinite(d)) continue;
        switch (r % 8) {
        case 0:
            snprintf(buf, sizeof buf, "%.17g", d);
            break;
        case 1:
            snprintf(buf, sizeof buf, "%.16g", d);
            break;
        case 2:
            snprintf(buf, sizeof buf, "%.15g", d);
            break;
        case 3:
            snprintf(buf, sizeof buf, "%.6e", d);
            break;
        case 4: /* a coordinate of a mesh: a few units, 17 digits */
            snprintf(buf, sizeof buf, "%.17g", (double)(int64_t)(bits >> 11) * 0x1p-50);
            break;
        case 5: { /* random digits, a point somewhere, an exponent */
            int nd = 1 + (int)((r >> 8) % 24), pt = (int)((r >> 16) % (uint64_t)(nd + 1)), k = 0;
            if (r & 0x100000) buf[k++] = '-';
            for (int j = 0; j < nd; j++) {
                if (j == pt) buf[k++] = '.';
                buf[k++] = (char)('0' + ff_next(&s) % 10);
            }
            snprintf(buf + k, sizeof buf - (size_t)k, "e%d", (int)(ff_next(&s) % 700) - 350);
            break;
        }
        case 6: /* integers about 2^53 and 2^64: every other one a tie */
            snprintf(buf, sizeof buf, "%llu",
                     (unsigned long long)(((r & 1) ? (1ULL << 53) : (UINT64_MAX - (1ULL << 40))) +
                                          (bits % (1ULL << 30))));
            break;
        default:
            snprintf(buf, sizeof buf, "%.20e", d);
            break;
        }
        ff_agree(buf, &bad);
    }
    CHECK(bad == 0, "%zu of %zu strings read otherwise than strtod reads them", bad, n);
}
