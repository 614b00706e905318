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
        goto out;
    }
    uint8_t *mem = malloc(r->c.nc * n + 1);
    if (bool3_membership(&r->c, mem) != 0) {
        test_fail(__FILE__, __func__, __LINE__, "%s: membership inconsistent", what);
        free(mem);
        goto out;
    }
    static const char *ops[3] = {"union", "intersection", "difference"};
    for (int k = 0; k < 3; k++) {
        bool_expr e;
        bool3_result res;
        bool_expr_named(ops[k], n, &e);
        bool3_select(&r->c, mem, &e, &res);
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
