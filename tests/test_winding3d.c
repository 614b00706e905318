/* test_winding3d.c — solids whose surfaces pass through themselves, overlap themselves or turn
 * inside out (issue "every surface by winding number"): the complex's invariants (lar3_check:
 * every cell a real region of positive volume, the bounded cells adding up to what the exterior
 * encloses), each cell's winding numbers (bool3_membership), and the one-solid input against
 * the same surfaces given as separate solids: the same cells, each winding as many times as
 * solids hold it.  The end-to-end families (closed forms, CGAL) are tests/winding3d.py. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/arr3.h"
#include "core/bool3.h"
#include "core/solid.h"
#include "tests/check.h"
#include "tests/lar_check.h"
#include "tests/shapes.h"

/* The box [x0, x1] x [y0, y1] x [z0, z1] (shape_box), turned inward when inward is set (every
 * cycle reversed: shape_poly would turn it out again). */
static solid box(double x0, double y0, double z0, double x1, double y1, double z1, int inward)
{
    double lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
    solid s = shape_box(lo, hi);
    for (size_t c = 0; inward && c < s.ncyc; c++)
        for (uint32_t a = s.cyc_off[c], b = s.cyc_off[c + 1] - 1; a < b; a++, b--) {
            uint32_t t = s.cyc[a];
            s.cyc[a] = s.cyc[b], s.cyc[b] = t;
        }
    return s;
}

/* A cube of side s turned by angle a about unit axis u, moved by t. */
static solid cube_rt(double s, const double *u, double a, const double *t)
{
    double R[3][3];
    solid c = box(0, 0, 0, s, s, s, 0);
    shape_rotation(u, a, R);
    shape_transform(&c, R, t);
    return c;
}

/* The solids s[0 .. n) as one solid (their vertices and faces one after another). */
static solid merged(const solid *s, size_t n)
{
    solid m = {0};
    for (size_t i = 0; i < n; i++) m.nv += s[i].nv, m.nf += s[i].nf, m.ncyc += s[i].ncyc;
    size_t ni = 0;
    for (size_t i = 0; i < n; i++) ni += s[i].cyc_off[s[i].ncyc];
    m.V = malloc(3 * m.nv * sizeof *m.V + 1);
    m.face_off = malloc((m.nf + 1) * sizeof *m.face_off);
    m.cyc_off = malloc((m.ncyc + 1) * sizeof *m.cyc_off);
    m.cyc = malloc(ni * sizeof *m.cyc + 1);
    size_t v0 = 0, f0 = 0, c0 = 0, i0 = 0;
    for (size_t i = 0; i < n; i++) {
        memcpy(m.V + 3 * v0, s[i].V, 3 * s[i].nv * sizeof *m.V);
        for (size_t f = 0; f < s[i].nf; f++) m.face_off[f0 + f] = (uint32_t)c0 + s[i].face_off[f];
        for (size_t c = 0; c < s[i].ncyc; c++) m.cyc_off[c0 + c] = (uint32_t)i0 + s[i].cyc_off[c];
        for (uint32_t k = 0; k < s[i].cyc_off[s[i].ncyc]; k++)
            m.cyc[i0 + k] = (uint32_t)v0 + s[i].cyc[k];
        v0 += s[i].nv, f0 += s[i].nf, c0 += s[i].ncyc, i0 += s[i].cyc_off[s[i].ncyc];
    }
    m.face_off[m.nf] = (uint32_t)c0;
    m.cyc_off[m.ncyc] = (uint32_t)i0;
    return m;
}

/* The arrangement of s[0 .. n) and its invariants; 0 when both are fine. */
static int run3(const solid *s, size_t n, lar3 *out)
{
    arr3_opts o = {0};
    char err[256], msg[256];
    long eu;
    int rc = arr3_build(s, n, 0, &o, out, err, sizeof err);
    if (rc) {
        test_fail(__FILE__, __func__, __LINE__, "arr3_build: %d %s", rc, err);
        return -1;
    }
    if (lar3_check(out, 1e-6, &eu, msg, sizeof msg)) {
        test_fail(__FILE__, __func__, __LINE__, "lar3_check: %s", msg);
        return -1;
    }
    return 0;
}

/* Cell k's winding number about solid j (0 when not listed). */
static int32_t wind_of(const member_rows *m, size_t k, uint32_t j)
{
    for (uint32_t i = m->off[k]; i < m->off[k + 1]; i++)
        if (m->idx[i] == j) return m->wind ? m->wind[i] : 1;
    return 0;
}

/* Sum over cells of winding number times volume: the signed volume the surface encloses. */
static double wind_volume(const lar3 *c, const member_rows *m, uint32_t j)
{
    double v = 0;
    for (size_t k = 0; k < c->nc; k++) v += wind_of(m, k, j) * c->cvol[k];
    return v;
}

/* Runs one solid s, checks the invariants and the windings' volume; fills *c and *m. */
static int run_one(const solid *s, lar3 *c, member_rows *m)
{
    uint32_t bad;
    memset(m, 0, sizeof *m);
    if (run3(s, 1, c)) return -1;
    if (bool3_membership(c, m, &bad)) {
        test_fail(__FILE__, __func__, __LINE__, "membership failed at face %u", bad);
        return -1;
    }
    double w = wind_volume(c, m, 0), sv = shape_volume(s);
    if (fabs(w - sv) > 1e-6 * (1 + fabs(sv))) {
        test_fail(__FILE__, __func__, __LINE__, "sum of winding x volume %.12g, surface %.12g", w,
                  sv);
        return -1;
    }
    return 0;
}

/* The volume where solid 0 lies by the fill rule. */
static double filled(const lar3 *c, const member_rows *m, int fill)
{
    double v = 0;
    for (size_t k = 0; k < c->nc; k++)
        if (member_inside(wind_of(m, k, 0), fill)) v += c->cvol[k];
    return v;
}

TEST(two_overlapping_cubes_as_one_solid)
{
    solid p[2] = {box(0, 0, 0, 1, 1, 1, 0), box(.5, .5, .5, 1.5, 1.5, 1.5, 0)};
    solid s = merged(p, 2);
    lar3 c = {0};
    member_rows m;
    if (!run_one(&s, &c, &m)) {
        CHECK(c.nc == 3, "cells %zu", c.nc);
        int twos = 0;
        for (size_t k = 0; k < c.nc; k++) {
            int32_t w = wind_of(&m, k, 0);
            CHECK(w == 1 || w == 2, "winding %d", w);
            if (w == 2) {
                twos++;
                CHECK(fabs(c.cvol[k] - .125) < 1e-12, "overlap %g", c.cvol[k]);
            }
        }
        CHECK(twos == 1, "cells winding 2: %d", twos);
        CHECK(fabs(filled(&c, &m, BOOL3_FILL_POSITIVE) - 1.875) < 1e-12, "union");
        CHECK(fabs(filled(&c, &m, BOOL3_FILL_ODD) - 1.75) < 1e-12, "odd");
        CHECK(c.nselfx == 1 && c.selfx[0].pairs > 0, "self-crossing reported");
    }
    member_rows_free(&m);
    lar3_free(&c);
    solid_free(&s), solid_free(&p[0]), solid_free(&p[1]);
}

TEST(a_box_given_twice)
{
    solid p[2] = {box(0, 0, 0, 1, 2, 3, 0), box(0, 0, 0, 1, 2, 3, 0)};
    solid s = merged(p, 2);
    lar3 c = {0};
    member_rows m;
    if (!run_one(&s, &c, &m)) {
        CHECK(c.nc == 1 && wind_of(&m, 0, 0) == 2, "cells %zu, winding %d", c.nc,
              c.nc ? wind_of(&m, 0, 0) : 0);
        CHECK(fabs(filled(&c, &m, BOOL3_FILL_POSITIVE) - 6) < 1e-12, "positive");
        CHECK(filled(&c, &m, BOOL3_FILL_ODD) == 0, "odd");
    }
    member_rows_free(&m);
    lar3_free(&c);
    solid_free(&s), solid_free(&p[0]), solid_free(&p[1]);
}

TEST(an_inside_out_box_overlapping_a_box)
{
    solid p[2] = {box(0, 0, 0, 2, 2, 2, 0), box(1, 1, 1, 3, 3, 3, 1)};
    solid s = merged(p, 2);
    lar3 c = {0};
    member_rows m;
    if (!run_one(&s, &c, &m)) {
        CHECK(c.nc == 3, "cells %zu", c.nc);
        for (size_t k = 0; k < c.nc; k++) {
            int32_t w = wind_of(&m, k, 0);
            double want = w == 1 ? 7 : w == 0 ? 1 : w == -1 ? 7 : -1;
            CHECK(fabs(c.cvol[k] - want) < 1e-12, "cell of winding %d: volume %g", w, c.cvol[k]);
        }
        CHECK(fabs(filled(&c, &m, BOOL3_FILL_POSITIVE) - 7) < 1e-12, "positive");
        CHECK(fabs(filled(&c, &m, BOOL3_FILL_NONZERO) - 14) < 1e-12, "nonzero");
    }
    member_rows_free(&m);
    lar3_free(&c);
    solid_free(&s), solid_free(&p[0]), solid_free(&p[1]);
}

/* The pentagram prism: side quads along the five star edges, each cap a fan of five triangles
 * from the centre, so the inner pentagon is covered twice. */
TEST(pentagram_prism)
{
    const double pi = acos(-1.0);
    solid s = {0};
    s.nv = 12, s.nf = 15, s.ncyc = 15;
    s.V = malloc(36 * sizeof *s.V);
    s.face_off = malloc(16 * sizeof *s.face_off);
    s.cyc_off = malloc(16 * sizeof *s.cyc_off);
    s.cyc = malloc(50 * sizeof *s.cyc);
    double P[5][2];
    for (int i = 0; i < 5; i++)
        P[i][0] = cos(pi / 2 + 2 * pi * i / 5), P[i][1] = sin(pi / 2 + 2 * pi * i / 5);
    const int order[5] = {0, 2, 4, 1, 3};
    double *V = s.V;
    V[0] = V[1] = V[2] = 0, V[3] = V[4] = 0, V[5] = 1;
    for (int k = 0; k < 5; k++)
        for (int z = 0; z < 2; z++) {
            double *x = V + 3 * (2 + 5 * z + k);
            x[0] = P[order[k]][0], x[1] = P[order[k]][1], x[2] = z;
        }
    uint32_t f = 0, at = 0;
    for (int k = 0; k < 5; k++) {
        uint32_t a = (uint32_t)(2 + k), b = (uint32_t)(2 + (k + 1) % 5);
        uint32_t bot[3] = {0, b, a}, top[3] = {1, a + 5, b + 5}, side[4] = {a, b, b + 5, a + 5};
        s.face_off[f] = f, s.cyc_off[f++] = at;
        memcpy(s.cyc + at, bot, sizeof bot), at += 3;
        s.face_off[f] = f, s.cyc_off[f++] = at;
        memcpy(s.cyc + at, top, sizeof top), at += 3;
        s.face_off[f] = f, s.cyc_off[f++] = at;
        memcpy(s.cyc + at, side, sizeof side), at += 4;
    }
    s.face_off[f] = f, s.cyc_off[f] = at;
    lar3 c = {0};
    member_rows m;
    if (!run_one(&s, &c, &m)) {
        /* the outline: the five points' triangles around the inner pentagon */
        double r = cos(2 * pi / 5) / cos(pi / 5); /* the inner vertices' radius */
        double pent = 5 * r * r * sin(2 * pi / 5) / 2;
        double tri = 5 * r * sin(pi / 5) * (1 - r * cos(pi / 5)); /* five point triangles */
        CHECK(c.nc == 6, "cells %zu", c.nc);
        CHECK(fabs(filled(&c, &m, BOOL3_FILL_POSITIVE) - (pent + tri)) < 1e-9, "positive %.12g",
              filled(&c, &m, BOOL3_FILL_POSITIVE));
        CHECK(fabs(filled(&c, &m, BOOL3_FILL_ODD) - tri) < 1e-9, "odd %.12g",
              filled(&c, &m, BOOL3_FILL_ODD));
    }
    member_rows_free(&m);
    lar3_free(&c);
    solid_free(&s);
}

/* A box without its top, given twice: every edge but the open rim is on 4 faces, 2 walking it
 * each way, and the rim's two copies walk it the same way, so making the orientation consistent
 * turns one copy over, and the 4 faces no longer balance: refused as not closed (a fuzz find:
 * the arrangement used to meet an edge whose winding did not come back). */
TEST(an_open_surface_given_twice_is_refused)
{
    solid b = box(0, 0, 0, 1, 1, 1, 0), s = b;
    /* faces 0 .. 4 (shape_hexa's: the top is the last) twice, on the same vertices */
    s.nf = s.ncyc = 10;
    s.face_off = malloc(11 * sizeof *s.face_off);
    s.cyc_off = malloc(11 * sizeof *s.cyc_off);
    s.cyc = malloc(40 * sizeof *s.cyc);
    s.V = malloc(24 * sizeof *s.V);
    memcpy(s.V, b.V, 24 * sizeof *s.V);
    for (uint32_t f = 0; f <= 10; f++) s.face_off[f] = f, s.cyc_off[f] = 4 * f;
    for (uint32_t f = 0; f < 10; f++) memcpy(s.cyc + 4 * f, b.cyc + 4 * (f % 5), 4 * sizeof *s.cyc);
    solid_report rep;
    memset(&rep, 0, sizeof rep);
    solid fixed = {0};
    int bad = solid_check(&s, 1e-6, "s", &rep, &fixed);
    int named = 0;
    for (size_t i = 0; i < rep.nmsg; i++) named |= strstr(rep.msg[i], "not closed") != NULL;
    CHECK(bad != 0 && named, "check %d, %zu messages", bad, rep.nmsg);
    solid_free(&fixed);
    solid_free(&s), solid_free(&b);
}

static uint64_t rng;
static double rnd(void)
{
    rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng >> 11) * 0x1p-53;
}

static int cmp_dd(const void *a, const void *b)
{
    const double *x = a, *y = b;
    if (x[0] != y[0]) return (x[0] > y[0]) - (x[0] < y[0]);
    return (x[1] > y[1]) - (x[1] < y[1]);
}

/* Random turned cubes as one solid and as separate solids: the same cells (by volume), each
 * winding about the one solid as many times as separate solids hold it (24 seeds; with
 * CELLAR_STRESS=N, 100 N). */
TEST(merged_cubes_wind_as_many_times_as_cubes_hold_them)
{
    const char *st = getenv("CELLAR_STRESS"); /* make stress: that many seeds times 100 */
    uint64_t seeds = st && atoi(st) > 0 ? 100 * (uint64_t)atoi(st) : 24;
    for (uint64_t seed = 1; seed <= seeds; seed++) {
        rng = seed * 0x9e3779b97f4a7c15ULL;
        size_t n = 2 + (size_t)(rnd() * 4);
        solid *p = calloc(n, sizeof *p);
        for (size_t i = 0; i < n; i++) {
            double u[3] = {rnd() - .5, rnd() - .5, rnd() - .5};
            double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
            for (int k = 0; k < 3; k++) u[k] /= l;
            double t[3] = {rnd(), rnd(), rnd()};
            p[i] = cube_rt(.6 + rnd(), u, rnd() * 3, t);
        }
        solid s = merged(p, n);
        lar3 a = {0}, b = {0};
        member_rows ma = {0}, mb = {0};
        uint32_t bad;
        if (!run_one(&s, &a, &ma) && !run3(p, n, &b) && !bool3_membership(&b, &mb, &bad)) {
            double *x = malloc(2 * (a.nc + b.nc + 1) * sizeof *x), *y = x + 2 * a.nc;
            for (size_t k = 0; k < a.nc; k++)
                x[2 * k] = a.cvol[k], x[2 * k + 1] = wind_of(&ma, k, 0);
            for (size_t k = 0; k < b.nc; k++)
                y[2 * k] = b.cvol[k], y[2 * k + 1] = mb.off[k + 1] - mb.off[k];
            qsort(x, a.nc, 2 * sizeof *x, cmp_dd);
            qsort(y, b.nc, 2 * sizeof *y, cmp_dd);
            int same = a.nc == b.nc;
            for (size_t k = 0; same && k < a.nc; k++)
                same = fabs(x[2 * k] - y[2 * k]) < 1e-9 && x[2 * k + 1] == y[2 * k + 1];
            CHECK(same, "seed %llu: %zu cubes: %zu cells as one solid, %zu as %zu solids",
                  (unsigned long long)seed, n, a.nc, b.nc, n);
            free(x);
        } else {
            test_fail(__FILE__, __func__, __LINE__, "seed %llu", (unsigned long long)seed);
        }
        member_rows_free(&ma), member_rows_free(&mb);
        lar3_free(&a), lar3_free(&b);
        solid_free(&s);
        for (size_t i = 0; i < n; i++) solid_free(&p[i]);
        free(p);
    }
}
