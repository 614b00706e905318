/* test_exact3d.c — the exact 3D arrangement on inputs that are hard on purpose.
 *
 * - contacts: every kind of contact between two solids (vertex on face, on edge, on vertex;
 *   edges crossing, edges overlapping along a line, an edge lying in a face, faces partly or
 *   wholly on each other), from outside and from inside a container, with boxes, tetrahedra,
 *   prisms and rotated cubes, on the grid's dyadic values and off them (everything scaled by
 *   0.3 and moved).  Expectations in closed form: touching from outside, the union is the sum
 *   of the volumes and the intersection empty; from inside, the union is the container and the
 *   intersection the inner solid.  On the grid, V/E/F/C are counted by hand and the complex must
 *   be one connected part.
 * - coplanar faces of two solids with different triangulations;
 * - near-coplanar faces: slabs whose faces are 0.5 to 20 grid steps apart at small angles;
 * - slivers: fan slabs whose faces have aspect ratios of 1e3 to 1e5, rotated, cut by a box.
 * Every result must pass lar3_check (d1 d2 = 0, d2 d3 = 0, every face on two cells, planarity,
 * volumes), the Booleans must agree with each other (|A u B| = |A| + |B| - |A n B|, |A - B| =
 * |A| - |A n B|) and with the closed forms within the snapping bound (grid step times the
 * solids' area), and nothing valid may be refused.  CELLAR_STRESS=N runs N seeds of each random
 * family (make stress); the suite runs a sample.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/arr3.h"
#include "core/bool3.h"
#include "core/boolexpr.h"
#include "core/solid.h"
#include "tests/check.h"
#include "tests/lar_check.h"
#include "tests/shapes.h"

static int stress(int dflt)
{
    const char *e = getenv("CELLAR_STRESS");
    int n = e ? atoi(e) : 0;
    return n > 0 ? n : dflt;
}

/* The volumes of the union, intersection and difference (first minus the rest) of the solids,
 * from one arrangement; checks its invariants and the Booleans' boundaries.  Returns 0. */
typedef struct run {
    lar3 c;
    double vol[3]; /* union, intersection, difference */
    double step;
} run;

/* CELLAR_DUMP=DIR: every input that fails is written there as a solids request. */
static void dump(const solid *in, size_t n, const char *what)
{
    const char *dir = getenv("CELLAR_DUMP");
    static int k;
    if (!dir) return;
    char path[512];
    snprintf(path, sizeof path, "%s/fail%03d.json", dir, k++);
    FILE *f = fopen(path, "w");
    if (!f) return;
    fprintf(f, "{\"kind\":\"solids\",\"what\":\"%s\",\"solids\":[", what);
    for (size_t i = 0; i < n; i++) {
        fprintf(f, "%s{\"V\":[", i ? "," : "");
        for (size_t v = 0; v < in[i].nv; v++)
            fprintf(f, "%s[%.17g,%.17g,%.17g]", v ? "," : "", in[i].V[3 * v], in[i].V[3 * v + 1],
                    in[i].V[3 * v + 2]);
        fprintf(f, "],\"FV\":[");
        for (size_t fc = 0; fc < in[i].nf; fc++) {
            uint32_t c = in[i].face_off[fc];
            fprintf(f, "%s[", fc ? "," : "");
            for (uint32_t j = in[i].cyc_off[c]; j < in[i].cyc_off[c + 1]; j++)
                fprintf(f, "%s%u", j > in[i].cyc_off[c] ? "," : "", in[i].cyc[j]);
            fprintf(f, "]");
        }
        fprintf(f, "]}");
    }
    fprintf(f, "]}\n");
    fclose(f);
}

static int arrange(solid *in, size_t n, double precision, run *r, const char *what)
{
    char err[300], msg[300];
    arr3_opts o = {0};
    solid *fx = calloc(n, sizeof *fx);
    int rc = -1;
    memset(r, 0, sizeof *r);
    o.precision = precision;
    double step;
    if (arr3_solids_step(in, n, precision, &step, err, sizeof err)) {
        test_fail(__FILE__, __func__, __LINE__, "%s: grid: %s", what, err);
        goto out;
    }
    for (size_t i = 0; i < n; i++) {
        solid_report rep;
        if (solid_check(&in[i], step, "s", &rep, &fx[i])) {
            test_fail(__FILE__, __func__, __LINE__, "%s: solid %zu refused: %s", what, i,
                      rep.msg[0]);
            goto out;
        }
    }
    o.precision = step;
    if (arr3_build(fx, n, 0, &o, &r->c, err, sizeof err)) {
        test_fail(__FILE__, __func__, __LINE__, "%s: arr3_build: %s", what, err);
        dump(in, n, what);
        goto out;
    }
    r->step = r->c.stats.precision;
    if (lar3_check(&r->c, 4 * r->step, NULL, msg, sizeof msg)) {
        test_fail(__FILE__, __func__, __LINE__, "%s: lar3_check: %s", what, msg);
        dump(in, n, what);
        goto out;
    }
    member_rows rows = {0};
    uint8_t *mem = malloc(r->c.nc * n + 1);
    if (lar3_membership_dense(&r->c, mem, &rows) != 0) {
        test_fail(__FILE__, __func__, __LINE__, "%s: membership inconsistent", what);
        free(mem);
        member_rows_free(&rows);
        goto out;
    }
    static const char *ops[3] = {"union", "intersection", "difference"};
    for (int k = 0; k < 3; k++) {
        bool_expr e;
        bool3_result res;
        bool_expr_named(ops[k], n, &e);
        bool3_select(&r->c, &rows, &e, &res);
        r->vol[k] = res.volume;
        /* the result's boundary is closed: every edge's signed count is 0 */
        long *acc = calloc(r->c.ne + 1, sizeof *acc);
        for (size_t i = 0; i < res.nfaces; i++) {
            int32_t s = res.faces[i];
            uint32_t f = (uint32_t)(s > 0 ? s : -s) - 1;
            for (uint32_t j = r->c.fe_off[f]; j < r->c.fe_off[f + 1]; j++) {
                int32_t t = r->c.fe[j];
                acc[(t > 0 ? t : -t) - 1] += (s > 0 ? 1 : -1) * (t > 0 ? 1 : -1);
            }
        }
        for (size_t ed = 0; ed < r->c.ne; ed++)
            if (acc[ed]) {
                test_fail(__FILE__, __func__, __LINE__, "%s: %s: boundary open at edge %zu", what,
                          ops[k], ed);
                break;
            }
        free(acc);
        bool3_result_free(&res);
        bool_expr_free(&e);
    }
    free(mem);
    member_rows_free(&rows);
    rc = 0;
out:
    for (size_t i = 0; i < n; i++) solid_free(&fx[i]);
    free(fx);
    return rc;
}

static int near(double got, double want, double tol)
{
    return fabs(got - want) <= tol;
}

/* ---- contacts ------------------------------------------------------------------------------ */

typedef struct scene {
    const char *name;
    int inside;     /* 1: B inside A (touching its wall from inside) */
    int V, E, F, C; /* on the grid; -1: not counted */
    solid (*make_a)(void);
    solid (*make_b)(void);
} scene;

static const double O[3] = {0, 0, 0}, I1[3] = {1, 1, 1};

static solid unit_box(void)
{
    return shape_box(O, I1);
}

static solid big_box(void)
{
    const double lo[3] = {-1, -1, -1}, hi[3] = {3, 3, 1};
    return shape_box(lo, hi);
}

static solid tet_on_face(void) /* apex (0.25, 0.5, 1) on the top face */
{
    const double a[3] = {0.25, 0.5, 1}, b[3] = {0, 0, 2}, c[3] = {1, 0.25, 2}, d[3] = {0.5, 1, 2};
    return shape_tet(a, b, c, d);
}

static solid tet_on_edge(void) /* apex (0.5, 1, 1) on the top back edge */
{
    const double a[3] = {0.5, 1, 1}, b[3] = {0.25, 1.5, 1.5}, c[3] = {0.75, 1.75, 1.25},
                 d[3] = {0.5, 1.25, 2};
    return shape_tet(a, b, c, d);
}

static solid tet_on_vertex(void) /* apex at the corner (1, 1, 1) */
{
    const double a[3] = {1, 1, 1}, b[3] = {1.25, 1.5, 1.5}, c[3] = {1.75, 1.5, 1.25},
                 d[3] = {1.5, 1.25, 2};
    return shape_tet(a, b, c, d);
}

static solid tet_edge_crossing(void) /* its edge crosses the box's edge x=1, z=1 at y=1/2 */
{
    const double a[3] = {1.25, 0.5, 0.75}, b[3] = {0.75, 0.5, 1.25}, c[3] = {1.5, 0.25, 1.5},
                 d[3] = {1.5, 0.75, 1.5};
    return shape_tet(a, b, c, d);
}

static solid box_edge_overlap(void) /* shares the part y in [0.5, 1] of the edge x=1, z=1 */
{
    const double lo[3] = {1, 0.5, 1}, hi[3] = {2, 1.5, 2};
    return shape_box(lo, hi);
}

static solid prism_edge_in_face(void) /* a prism lying on its edge inside the top face */
{
    const double base[3][3] = {{0.25, 0.5, 1}, {0.25, 0.25, 1.5}, {0.25, 0.75, 1.5}};
    const double dir[3] = {0.5, 0, 0};
    return shape_prism(base, 3, dir);
}

static solid prism_edge_across_face(void) /* lying on the top face from side to side */
{
    const double base[3][3] = {{0, 0.5, 1}, {0, 0, 2}, {0, 1, 2}};
    const double dir[3] = {1, 0, 0};
    return shape_prism(base, 3, dir);
}

static solid box_face_partial(void) /* its bottom overlaps the top face on [0.5, 1]^2 */
{
    const double lo[3] = {0.5, 0.5, 1}, hi[3] = {1.5, 1.5, 2};
    return shape_box(lo, hi);
}

static solid box_face_inside(void) /* its bottom face inside the top face */
{
    const double lo[3] = {0.25, 0.25, 1}, hi[3] = {0.75, 0.5, 1.5};
    return shape_box(lo, hi);
}

static solid cube_on_its_edge(void) /* a cube turned 45 degrees about x, its edge on the top */
{
    solid s = unit_box();
    const double u[3] = {1, 0, 0}, t0[3] = {0, 0, 0};
    double R[3][3];
    shape_rotation(u, M_PI / 4, R);
    shape_transform(&s, R, t0);
    /* the edge of corners 0 and 1 is at the origin: move it onto the top face, keep it exact */
    for (size_t v = 0; v < s.nv; v++) {
        s.V[3 * v] = s.V[3 * v] * 0.5 + 0.25;
        s.V[3 * v + 1] += 0.5;
        s.V[3 * v + 2] += 1;
    }
    for (size_t v = 0; v < s.nv; v++)
        if (fabs(s.V[3 * v + 2] - 1) < 1e-12) s.V[3 * v + 2] = 1, s.V[3 * v + 1] = 0.5;
    return s;
}

static solid cube_on_its_vertex(void) /* a cube turned to stand on a corner, on the top face */
{
    solid s = unit_box();
    const double u[3] = {1 / sqrt(2), -1 / sqrt(2), 0}, t0[3] = {0, 0, 0};
    double R[3][3];
    shape_rotation(u, acos(1 / sqrt(3)), R);
    shape_transform(&s, R, t0);
    for (size_t v = 0; v < s.nv; v++)
        for (int a = 0; a < 3; a++) s.V[3 * v + a] = s.V[3 * v + a] * 0.25 + (a == 2 ? 1 : 0.5);
    s.V[0] = 0.5, s.V[1] = 0.5, s.V[2] = 1; /* corner 0 exactly on the face */
    return s;
}

/* from inside the big box [-1,3]x[-1,3]x[-1,1]: touching its top face z = 1 */
static solid in_tet_on_face(void)
{
    const double a[3] = {0.25, 0.5, 1}, b[3] = {0, 0, 0}, c[3] = {1, 0.25, 0}, d[3] = {0.5, 1, 0};
    return shape_tet(a, b, c, d);
}

static solid in_box_on_face(void)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    return shape_box(lo, hi);
}

static solid in_box_in_corner(void) /* three faces on the container's walls */
{
    const double lo[3] = {2, 2, 0}, hi[3] = {3, 3, 1};
    return shape_box(lo, hi);
}

static solid in_prism_edge_on_face(void)
{
    const double base[3][3] = {{0, 0.5, 1}, {0, 0, 0}, {0, 1, 0}};
    const double dir[3] = {1, 0, 0};
    return shape_prism(base, 3, dir);
}

static solid in_cube_on_edge_of_wall(void) /* along the container's edge x = 3, z = 1 */
{
    const double lo[3] = {2.5, 0, 0.5}, hi[3] = {3, 1, 1};
    return shape_box(lo, hi);
}

static const scene scenes[] = {
    {"vertex on face", 0, 12, 18, 10, 2, unit_box, tet_on_face},
    {"vertex on edge", 0, 12, 19, 10, 2, unit_box, tet_on_edge},
    {"vertex on vertex", 0, 11, 18, 10, 2, unit_box, tet_on_vertex},
    {"edges crossing", 0, 13, 20, 10, 2, unit_box, tet_edge_crossing},
    {"edges overlapping", 0, 16, 25, 12, 2, unit_box, box_edge_overlap},
    {"edge in face", 0, 14, 21, 11, 2, unit_box, prism_edge_in_face},
    {"edge across face", 0, 14, 23, 12, 2, unit_box, prism_edge_across_face},
    {"faces partly on each other", 0, 18, 28, 13, 2, unit_box, box_face_partial},
    {"face inside face", 0, 16, 24, 12, 2, unit_box, box_face_inside},
    {"rotated cube on its edge", 0, 16, 24, 12, 2, unit_box, cube_on_its_edge},
    {"rotated cube on its vertex", 0, 16, 24, 12, 2, unit_box, cube_on_its_vertex},
    {"inside: vertex on face", 1, 12, 18, 10, 2, big_box, in_tet_on_face},
    {"inside: face on face", 1, 16, 24, 12, 2, big_box, in_box_on_face},
    {"inside: in a corner", 1, 15, 24, 12, 2, big_box, in_box_in_corner},
    {"inside: edge on face", 1, 14, 21, 11, 2, big_box, in_prism_edge_on_face},
    {"inside: along a wall's edge", 1, 16, 25, 12, 2, big_box, in_cube_on_edge_of_wall},
};

static void contact_case(const scene *sc, int off_grid, const double *R, const double *t)
{
    solid s[2] = {sc->make_a(), sc->make_b()};
    char what[160];
    snprintf(what, sizeof what, "%s%s", sc->name, off_grid ? " (off the grid)" : "");
    if (off_grid) { /* scale by 0.3, turn, move: contacts stay exact in doubles only in part */
        for (int i = 0; i < 2; i++) {
            for (size_t v = 0; v < 3 * s[i].nv; v++) s[i].V[v] *= 0.3;
            shape_transform(&s[i], (const double(*)[3])R, t);
        }
    }
    double va = shape_volume(&s[0]), vb = shape_volume(&s[1]);
    double area = shape_area(&s[0]) + shape_area(&s[1]);
    run r;
    if (arrange(s, 2, 0, &r, what) == 0) {
        double tol = 2 * r.step * area + 1e-12 * (va + vb);
        double want[3] = {sc->inside ? va : va + vb, sc->inside ? vb : 0,
                          sc->inside ? va - vb : va};
        static const char *ops[3] = {"union", "intersection", "difference"};
        for (int k = 0; k < 3; k++)
            CHECK(near(r.vol[k], want[k], tol), "%s: %s %.17g, want %.17g (tol %.3g)", what, ops[k],
                  r.vol[k], want[k], tol);
        if (!off_grid) {
            CHECK(r.c.nc == 2, "%s: %zu cells", what, r.c.nc);
            CHECK(r.c.stats.components == 1, "%s: %zu parts, the solids touch", what,
                  r.c.stats.components);
            /* a rotated quad not exactly planar on the grid is two triangles: one more edge
             * and one more face each */
            long sp = (long)r.c.stats.split_faces;
            CHECK((long)r.c.nv == sc->V && (long)r.c.ne == sc->E + sp &&
                      (long)r.c.nf == sc->F + sp && (long)r.c.nc == sc->C,
                  "%s: V %zu E %zu F %zu C %zu, want %d %ld %ld %d", what, r.c.nv, r.c.ne, r.c.nf,
                  r.c.nc, sc->V, sc->E + sp, sc->F + sp, sc->C);
        }
    }
    lar3_free(&r.c);
    solid_free(&s[0]);
    solid_free(&s[1]);
}

TEST(contacts_on_the_grid)
{
    for (size_t i = 0; i < sizeof scenes / sizeof *scenes; i++)
        contact_case(&scenes[i], 0, NULL, NULL);
}

TEST(contacts_off_the_grid)
{
    uint64_t seed = 12345;
    int n = stress(2);
    for (int t = 0; t < n; t++)
        for (size_t i = 0; i < sizeof scenes / sizeof *scenes; i++) {
            double u[3], len = 0, R[3][3], tr[3];
            for (int a = 0; a < 3; a++) u[a] = test_rnd(&seed) - 0.5, len += u[a] * u[a];
            for (int a = 0; a < 3; a++) u[a] /= sqrt(len), tr[a] = 100 * test_rnd(&seed) - 50;
            shape_rotation(u, 2 * M_PI * test_rnd(&seed), R);
            contact_case(&scenes[i], 1, &R[0][0], tr);
        }
}

/* ---- the volumes of each solid, from the cells ---------------------------------------------- */

/* Checks that the cells inside each solid add up to its volume (within tol) and that the
 * Booleans' boundaries are closed (done by arrange). */
static void solid_volumes(const run *r, solid *s, size_t n, double tol, const char *what)
{
    member_rows rows = {0};
    uint8_t *mem = malloc(r->c.nc * n + 1);
    if (lar3_membership_dense(&r->c, mem, &rows) != 0) {
        test_fail(__FILE__, __func__, __LINE__, "%s: membership", what);
        free(mem);
        member_rows_free(&rows);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        double v = 0, want = shape_volume(&s[i]);
        for (size_t k = 0; k < r->c.nc; k++)
            if (mem[k * n + i]) v += r->c.cvol[k];
        CHECK(near(v, want, tol), "%s: solid %zu: its cells add up to %.17g, its volume %.17g",
              what, i, v, want);
    }
    free(mem);
    member_rows_free(&rows);
}

/* Two boxes whose faces z = 0 overlap on [1,2]^2, triangulated along crossing diagonals: one
 * exact arrangement of the plane z = 0 splits them together. */
TEST(coplanar_faces_with_different_triangulations)
{
    /* A = [0,2]^2 x [-1,0], its top split along (0,0)-(2,2); B = [1,3]^2 x [-1,0] or x [0,1],
     * its top or bottom split along (3,1)-(1,3) */
    for (int below = 0; below < 2; below++) {
        const double VA[8][3] = {{0, 0, -1}, {2, 0, -1}, {2, 2, -1}, {0, 2, -1},
                                 {0, 0, 0},  {2, 0, 0},  {2, 2, 0},  {0, 2, 0}};
        static const int FA[] = {0,  3, 2, 1, -1, 4,  5, 6, -1, 4, 6,  7, -1, 0, 1, 5,  4,
                                 -1, 1, 2, 6, 5,  -1, 2, 3, 7,  6, -1, 3, 0,  4, 7, -1, -2};
        double z0 = below ? -1 : 0, z1 = below ? 0 : 1;
        const double VB[8][3] = {{1, 1, z0}, {3, 1, z0}, {3, 3, z0}, {1, 3, z0},
                                 {1, 1, z1}, {3, 1, z1}, {3, 3, z1}, {1, 3, z1}};
        /* B's face at z = 0 as two triangles along (3,1)-(1,3) */
        static const int FB_top[] = {0,  3, 2, 1, -1, 4,  5, 7, -1, 5, 6,  7, -1, 0, 1, 5,  4,
                                     -1, 1, 2, 6, 5,  -1, 2, 3, 7,  6, -1, 3, 0,  4, 7, -1, -2};
        static const int FB_bottom[] = {0,  3, 1, -1, 1, 3,  2, -1, 4, 5, 6,  7, -1, 0, 1, 5,  4,
                                        -1, 1, 2, 6,  5, -1, 2, 3,  7, 6, -1, 3, 0,  4, 7, -1, -2};
        solid s[2] = {shape_poly(&VA[0][0], 8, FA),
                      shape_poly(&VB[0][0], 8, below ? FB_top : FB_bottom)};
        run r;
        const char *what = below ? "overlapping boxes, coplanar tops" : "box on box, face on face";
        if (arrange(s, 2, 0, &r, what) == 0) {
            double want[3] = {below ? 7 : 8, below ? 1 : 0, below ? 3 : 4};
            for (int k = 0; k < 3; k++)
                CHECK(near(r.vol[k], want[k], 1e-12), "%s: op %d: %.17g, want %g", what, k,
                      r.vol[k], want[k]);
            CHECK(r.c.stats.coplanar_groups >= 1, "%s: no plane holds both", what);
            solid_volumes(&r, s, 2, 1e-12, what);
        }
        lar3_free(&r.c);
        solid_free(&s[0]);
        solid_free(&s[1]);
    }
}

/* A solid with a face that is flat on the grid: a "roof box" whose top is two planes meeting
 * along AC, where the faces of one plane have a vertex E on AC that the other's do not (a
 * T-junction), closed by the triangle A C E of zero area (E exactly on AC, or off it by far
 * less than the grid step).  The flat face is left out with a warning and the other plane's
 * edge AC is split at E: the volume is the roof box's, alone and cut by a box. */
TEST(face_flat_on_the_grid)
{
    for (int off = 0; off < 2; off++) {
        /* 0-3 bottom, A B C D top (D raised), E the middle of AC */
        double V[9][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0},   {0, 1, 0},    {0, 0, 1},
                          {1, 0, 1}, {1, 1, 1}, {0, 1, 1.5}, {0.5, 0.5, 1}};
        if (off) V[8][2] += 1e-13; /* off the line by 1e-13: on it on the grid */
        enum { A = 4, B = 5, C = 6, D = 7, E = 8 };
        const int F[] = {0, 3, 2, 1,  -1, 0, 1, B,  A, -1, 1, 2,  C, B, -1, 2,  3, D, C, -1, 3,
                         0, A, D, -1, A,  B, C, -1, A, C,  E, -1, C, D, E,  -1, E, D, A, -1, -2};
        const int G[] = {0, 3, 2,  1, -1, 0, 1, B,  A, -1, 1, 2,  C, B, -1, 2,  3,
                         D, C, -1, 3, 0,  A, D, -1, A, B,  C, -1, A, C, D,  -1, -2}; /* without E */
        solid roof = shape_poly(&V[0][0], 9, F), plain = shape_poly(&V[0][0], 8, G);
        double want = shape_volume(&plain);
        const char *what = off ? "a face flat on the grid" : "a flat face";
        solid_report rep;
        solid fx = {0};
        double step;
        char err[300];
        CHECK(arr3_solids_step(&roof, 1, 0, &step, err, sizeof err) == 0, "%s: step", what);
        CHECK(solid_check(&roof, step, "s", &rep, &fx) == 0 && rep.degenerate_faces == 1 &&
                  rep.warnings >= 1 && rep.info[0].warning,
              "%s: taken with a warning: %zu errors, %zu degenerate, '%s'", what, rep.errors,
              rep.degenerate_faces, rep.nmsg ? rep.msg[0] : "");
        solid_free(&fx);
        run r;
        if (arrange(&roof, 1, 0, &r, what) == 0) {
            CHECK(r.c.nc == 1 && near(r.c.cvol[0], want, 1e-12),
                  "%s: one cell of %.17g: %zu, %.17g", what, want, r.c.nc,
                  r.c.nc ? r.c.cvol[0] : 0);
            CHECK(r.c.nv == 9, "%s: E is a vertex of the complex: %zu vertices", what, r.c.nv);
        }
        lar3_free(&r.c);
        const double lo[3] = {0.25, -0.5, 0.5}, hi[3] = {0.75, 1.5, 2};
        solid s[2] = {roof, shape_box(lo, hi)}, t[2] = {plain, shape_box(lo, hi)};
        run r1, r2;
        if (arrange(s, 2, 0, &r1, what) == 0 && arrange(t, 2, 0, &r2, "the same without E") == 0)
            for (int k = 0; k < 3; k++)
                CHECK(near(r1.vol[k], r2.vol[k], 1e-12), "%s and a box: op %d: %.17g, want %.17g",
                      what, k, r1.vol[k], r2.vol[k]);
        lar3_free(&r1.c);
        lar3_free(&r2.c);
        solid_free(&s[0]), solid_free(&s[1]), solid_free(&t[0]), solid_free(&t[1]);
    }
}

/* One solid made of two boxes stacked on a common face (each with its own vertices): its
 * surface touches itself face to face, an inner wall with the solid on both sides.  Two cells;
 * with a box crossing the wall the Booleans are the closed forms, in either order. */
TEST(solid_touching_itself_face_to_face)
{
    double V[16][3];
    int F[2 * 6 * 5 + 1];
    static const int box[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    size_t nfv = 0;
    for (int b = 0; b < 2; b++) {
        for (int i = 0; i < 8; i++) {
            V[8 * b + i][0] = i & 1 ? 1.5 : 0.25;
            V[8 * b + i][1] = i & 2 ? 1.25 : 0;
            V[8 * b + i][2] = b + (i & 4 ? 1 : 0);
        }
        for (int f = 0; f < 6; f++) {
            for (int k = 0; k < 4; k++) F[nfv++] = 8 * b + box[f][k];
            F[nfv++] = -1;
        }
    }
    F[nfv] = -2;
    const double lo[3] = {1, 0.5, 0.5}, hi[3] = {2, 1, 1.75};
    for (int order = 0; order < 2; order++) {
        solid two = shape_poly(&V[0][0], 16, F), b = shape_box(lo, hi);
        double vtwo = shape_volume(&two), vb = shape_volume(&b);
        double common = (1.5 - 1) * (1 - 0.5) * (1.75 - 0.5);
        solid s[2] = {order ? b : two, order ? two : b};
        run r;
        const char *what =
            order ? "box and a solid with an inner wall" : "a solid with an inner wall and a box";
        CHECK(near(vtwo, 2 * 1.25 * 1.25, 1e-15), "volume of the stacked boxes: %g", vtwo);
        if (arrange(s, 2, 0, &r, what) == 0) {
            double want[3] = {vtwo + vb - common, common, (order ? vb : vtwo) - common};
            for (int k = 0; k < 3; k++)
                CHECK(near(r.vol[k], want[k], 1e-12), "%s: op %d: %.17g, want %.17g", what, k,
                      r.vol[k], want[k]);
            solid_volumes(&r, s, 2, 1e-12, what);
        }
        lar3_free(&r.c);
        solid_free(&two);
        solid_free(&b);
    }
    /* alone: two cells of the stacked boxes' volumes, and the wall between them */
    solid one = shape_poly(&V[0][0], 16, F);
    run r;
    if (arrange(&one, 1, 0, &r, "a solid with an inner wall") == 0) {
        CHECK(r.c.nc == 2 && near(r.c.cvol[0], 1.25 * 1.25, 1e-15) &&
                  near(r.c.cvol[1], 1.25 * 1.25, 1e-15),
              "two cells of 1.5625: %zu cells", r.c.nc);
        CHECK(r.c.nv == 12 && r.c.ne == 20 && r.c.nf == 11, "V/E/F %zu/%zu/%zu, want 12/20/11",
              r.c.nv, r.c.ne, r.c.nf);
    }
    lar3_free(&r.c);
    solid_free(&one);
}

/* B's bottom face lies 0.5 to 20 grid steps from A's top face and turns away from it by a
 * small angle: the two planes meet along a line where they are nearly parallel. */
TEST(near_coplanar_faces)
{
    static const double steps[] = {0.5, 1, 2, 5, 20, -0.5, -3};
    static const double angles[] = {1e-9, 1e-7, 1e-5, 1e-3, 0};
    uint64_t seed = 99;
    int rounds = stress(1);
    for (int t = 0; t < rounds; t++)
        for (size_t i = 0; i < sizeof steps / sizeof *steps; i++)
            for (size_t j = 0; j < sizeof angles / sizeof *angles; j++) {
                const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
                const double blo[3] = {0.2, 0.2, 1}, bhi[3] = {1.2, 0.8, 2};
                solid s[2] = {shape_box(lo, hi), shape_box(blo, bhi)};
                double u[3] = {0, 1, 0}, R[3][3], c[3] = {0.7, 0.5, 1}, tr[3];
                if (t) { /* random axes in the plane, random pivots */
                    double a = 2 * M_PI * test_rnd(&seed);
                    u[0] = cos(a), u[1] = sin(a);
                    c[0] = 0.2 + test_rnd(&seed), c[1] = 0.2 + 0.6 * test_rnd(&seed);
                }
                shape_rotation(u, angles[j], R);
                double step;
                char err[200], what[160];
                arr3_solids_step(s, 2, 0, &step, err, sizeof err);
                for (int a = 0; a < 3; a++)
                    tr[a] = c[a] - (R[a][0] * c[0] + R[a][1] * c[1] + R[a][2] * c[2]) +
                            (a == 2 ? steps[i] * step : 0);
                shape_transform(&s[1], R, tr);
                snprintf(what, sizeof what, "near-coplanar: %g steps apart, angle %g", steps[i],
                         angles[j]);
                run r;
                double area = shape_area(&s[0]) + shape_area(&s[1]);
                if (arrange(s, 2, 0, &r, what) == 0) {
                    double va = shape_volume(&s[0]), vb = shape_volume(&s[1]);
                    double tol = 2 * r.step * area;
                    solid_volumes(&r, s, 2, tol, what);
                    CHECK(near(r.vol[0], va + vb - r.vol[1], tol) &&
                              near(r.vol[2], va - r.vol[1], tol),
                          "%s: union %.17g, intersection %.17g, difference %.17g", what, r.vol[0],
                          r.vol[1], r.vol[2]);
                }
                lar3_free(&r.c);
                solid_free(&s[0]);
                solid_free(&s[1]);
            }
}

/* Slabs whose top and bottom are fans of slivers (aspect 1e3 to 1e5), turned at random, cut by
 * a small box far from the thin ends of the slivers. */
TEST(sliver_fans)
{
    uint64_t seed = 7;
    int rounds = stress(3);
    for (int t = 0; t < rounds; t++) {
        double spread = t % 3 == 0 ? 8 : t % 3 == 1 ? 30 : 100;
        solid s[2];
        s[0] = shape_fan_slab(24, 60, 1, 0.05, spread, 0.5);
        const double lo[3] = {2 + 50 * test_rnd(&seed), 0.2, 0.1};
        const double hi[3] = {lo[0] + 0.5 + test_rnd(&seed), 0.7, 0.8};
        s[1] = shape_box(lo, hi);
        double u[3], len = 0, R[3][3], tr[3] = {100, -50, 25};
        for (int a = 0; a < 3; a++) u[a] = test_rnd(&seed) - 0.5, len += u[a] * u[a];
        for (int a = 0; a < 3; a++) u[a] /= sqrt(len);
        shape_rotation(u, 2 * M_PI * test_rnd(&seed), R);
        for (int i = 0; i < 2; i++) shape_transform(&s[i], R, tr);
        char what[120];
        snprintf(what, sizeof what, "sliver fan %d (spread %g)", t, spread);
        run r;
        double area = shape_area(&s[0]) + shape_area(&s[1]);
        if (arrange(s, 2, 0, &r, what) == 0) {
            solid_volumes(&r, s, 2, 2 * r.step * area, what);
            /* the box is inside the slab's thickness only partly: it pokes out of the top */
            CHECK(r.vol[1] > 0 && r.vol[1] < shape_volume(&s[1]), "%s: intersection %.17g", what,
                  r.vol[1]);
        }
        lar3_free(&r.c);
        solid_free(&s[0]);
        solid_free(&s[1]);
    }
}

/* Random scenes on a lattice of step 1/4: boxes, tetrahedra, prisms placed so that they share
 * planes, edges and vertices all the time.  The coordinates are on the grid, so nothing is
 * rounded: each solid's cells must add up to its volume exactly (to double rounding). */
static solid random_lattice_solid(uint64_t *st)
{
    double o[3];
    for (int a = 0; a < 3; a++) o[a] = (double)(int)(8 * test_rnd(st)) / 4;
    int kind = (int)(3 * test_rnd(st));
    if (kind == 0) {
        double hi[3];
        for (int a = 0; a < 3; a++) hi[a] = o[a] + (double)(1 + (int)(4 * test_rnd(st))) / 4;
        return shape_box(o, hi);
    }
    if (kind == 1) {
        double p[4][3];
        double vol;
        do {
            for (int i = 0; i < 4; i++)
                for (int a = 0; a < 3; a++) p[i][a] = o[a] + (double)(int)(5 * test_rnd(st)) / 4;
            double u[3], v[3], w[3];
            for (int a = 0; a < 3; a++)
                u[a] = p[1][a] - p[0][a], v[a] = p[2][a] - p[0][a], w[a] = p[3][a] - p[0][a];
            vol = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                  u[2] * (v[0] * w[1] - v[1] * w[0]);
        } while (vol == 0);
        return shape_tet(p[0], p[1], p[2], p[3]);
    }
    /* a prism over a lattice triangle, along an axis */
    double b[3][3], dir[3] = {0, 0, 0};
    int ax = (int)(3 * test_rnd(st));
    double area;
    do {
        for (int i = 0; i < 3; i++)
            for (int a = 0; a < 3; a++)
                b[i][a] = a == ax ? o[a] : o[a] + (double)(int)(5 * test_rnd(st)) / 4;
        int u = (ax + 1) % 3, v = (ax + 2) % 3;
        area =
            (b[1][u] - b[0][u]) * (b[2][v] - b[0][v]) - (b[1][v] - b[0][v]) * (b[2][u] - b[0][u]);
    } while (area == 0);
    dir[ax] = (double)(1 + (int)(4 * test_rnd(st))) / 4;
    return shape_prism((const double(*)[3])b, 3, dir);
}

TEST(random_lattice_scenes)
{
    uint64_t seed = 2024;
    int rounds = stress(20);
    for (int t = 0; t < rounds; t++) {
        size_t n = 2 + (size_t)(7 * test_rnd(&seed));
        solid s[8];
        for (size_t i = 0; i < n; i++) s[i] = random_lattice_solid(&seed);
        char what[80];
        snprintf(what, sizeof what, "lattice scene %d (%zu solids)", t, n);
        run r;
        if (arrange(s, n, 0x1p-20, &r, what) == 0) solid_volumes(&r, s, n, 1e-12, what);
        lar3_free(&r.c);
        /* the same scene turned and moved: off the grid, contacts become near-contacts or
         * small overlaps, and every volume moves by at most the snapping */
        double u[3], len = 0, R[3][3], tr[3], area = 0;
        for (int a = 0; a < 3; a++) u[a] = test_rnd(&seed) - 0.5, len += u[a] * u[a];
        for (int a = 0; a < 3; a++) u[a] /= sqrt(len), tr[a] = 10 * test_rnd(&seed);
        shape_rotation(u, 2 * M_PI * test_rnd(&seed), R);
        for (size_t i = 0; i < n; i++) shape_transform(&s[i], R, tr), area += shape_area(&s[i]);
        snprintf(what, sizeof what, "lattice scene %d turned", t);
        if (arrange(s, n, 0, &r, what) == 0) solid_volumes(&r, s, n, 2 * r.step * area, what);
        lar3_free(&r.c);
        for (size_t i = 0; i < n; i++) solid_free(&s[i]);
    }
}
