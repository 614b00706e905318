/* test_arr3.c — the 3D arrangement (core/arr3.c): closed-form counts and volumes, the seeds'
 * examples, coplanar and nested cases, and invariants (lar3_check) on every result. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/arr3.h"
#include "core/solid.h"
#include "tests/check.h"
#include "tests/lar_check.h"

static const uint32_t cube_faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                          {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

/* A hexahedron from 8 corners (bit 0: x side, bit 1: y, bit 2: z), outward oriented. */
static solid hexa(const double c[8][3])
{
    solid s = {0};
    s.nv = 8;
    s.V = malloc(24 * sizeof *s.V);
    s.nf = 6;
    s.ncyc = 6;
    s.face_off = malloc(7 * sizeof *s.face_off);
    s.cyc_off = malloc(7 * sizeof *s.cyc_off);
    s.cyc = malloc(24 * sizeof *s.cyc);
    for (int i = 0; i < 8; i++) memcpy(s.V + 3 * i, c[i], 3 * sizeof(double));
    for (int f = 0; f <= 6; f++) s.face_off[f] = (uint32_t)f, s.cyc_off[f] = (uint32_t)(4 * f);
    for (int f = 0; f < 6; f++) memcpy(s.cyc + 4 * f, cube_faces[f], 4 * sizeof(uint32_t));
    return s;
}

static solid box(double x0, double y0, double z0, double x1, double y1, double z1)
{
    double c[8][3];
    for (int i = 0; i < 8; i++) {
        c[i][0] = i & 1 ? x1 : x0;
        c[i][1] = i & 2 ? y1 : y0;
        c[i][2] = i & 4 ? z1 : z0;
    }
    return hexa(c);
}

/* The unit cube scaled by s, rotated by angle a about unit axis u, then moved by t. */
static solid cube_rt(double s, const double *u, double a, const double *t)
{
    double c[8][3], R[3][3];
    double cs = cos(a), sn = sin(a), C = 1 - cs;
    R[0][0] = cs + u[0] * u[0] * C, R[0][1] = u[0] * u[1] * C - u[2] * sn;
    R[0][2] = u[0] * u[2] * C + u[1] * sn;
    R[1][0] = u[1] * u[0] * C + u[2] * sn, R[1][1] = cs + u[1] * u[1] * C;
    R[1][2] = u[1] * u[2] * C - u[0] * sn;
    R[2][0] = u[2] * u[0] * C - u[1] * sn, R[2][1] = u[2] * u[1] * C + u[0] * sn;
    R[2][2] = cs + u[2] * u[2] * C;
    for (int i = 0; i < 8; i++) {
        double p[3] = {i & 1 ? s : 0, i & 2 ? s : 0, i & 4 ? s : 0};
        for (int k = 0; k < 3; k++)
            c[i][k] = R[k][0] * p[0] + R[k][1] * p[1] + R[k][2] * p[2] + t[k];
    }
    return hexa(c);
}

static void free_all(solid *s, size_t n)
{
    for (size_t i = 0; i < n; i++) solid_free(&s[i]);
}

/* Runs the arrangement and its invariants; returns 0 when both are fine. */
static int run3(solid *s, size_t n, int soup, double precision, lar3 *out, long *euler)
{
    arr3_opts o = {0};
    o.precision = precision;
    char err[256];
    int rc = arr3_build(s, n, soup, &o, out, err, sizeof err);
    if (rc) {
        test_fail(__FILE__, __func__, __LINE__, "arr3_build: %d %s", rc, err);
        return -1;
    }
    char msg[256];
    if (lar3_check(out, 1e-6, euler, msg, sizeof msg)) {
        test_fail(__FILE__, __func__, __LINE__, "lar3_check: %s", msg);
        return -1;
    }
    return 0;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Are the sorted cell volumes of c equal to want (sorted) within tol? */
static int volumes_are(const lar3 *c, const double *want, size_t n, double tol)
{
    if (c->nc != n) return 0;
    double *v = malloc(n * sizeof *v + 1);
    for (size_t k = 0; k < n; k++) v[k] = c->cvol[k];
    qsort(v, n, sizeof *v, cmp_double);
    int ok = 1;
    for (size_t k = 0; k < n; k++)
        if (fabs(v[k] - want[k]) > tol) ok = 0;
    free(v);
    return ok;
}

TEST(two_offset_cubes)
{
    solid s[2] = {box(0, 0, 0, 1, 1, 1), box(.5, .5, .5, 1.5, 1.5, 1.5)};
    lar3 c;
    long eu;
    if (!run3(s, 2, 0, 0, &c, &eu)) {
        CHECK(c.nv == 22 && c.ne == 36 && c.nf == 18 && c.nc == 3, "V %zu E %zu F %zu C %zu",
              c.nv, c.ne, c.nf, c.nc);
        double want[3] = {.125, .875, .875};
        CHECK(volumes_are(&c, want, 3, 1e-12), "volumes");
        CHECK(eu == 0, "euler %ld", eu);
    }
    lar3_free(&c);
    free_all(s, 2);
}

TEST(cube_and_rotated_cube)
{
    double z[3] = {0, 0, 1}, t[3] = {0, 0, .5};
    solid s[2] = {box(0, 0, 0, 1, 1, 1), cube_rt(1, z, M_PI / 3, t)};
    lar3 c;
    long eu;
    if (!run3(s, 2, 0, 0, &c, &eu)) {
        CHECK(c.nv == 20 && c.ne == 34 && c.nf == 18 && c.nc == 3, "V %zu E %zu F %zu C %zu",
              c.nv, c.ne, c.nf, c.nc);
        CHECK(eu == 0, "euler %ld", eu);
        double tot = 0;
        for (size_t k = 0; k < c.nc; k++) tot += c.cvol[k];
        /* union = 2 - the intersection, a prism of height 0.5 over the square ∩ rotated square */
        CHECK(tot > 1.5 && tot < 2, "total %g", tot);
    }
    lar3_free(&c);
    free_all(s, 2);
}
