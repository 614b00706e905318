/* test_arr3.c — the 3D arrangement (core/arr3.c): closed-form counts and volumes, the seeds'
 * examples, coplanar and nested cases, and invariants (lar3_check) on every result. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "core/arr3.h"
#include "core/solid.h"
#include "tests/check.h"
#include "tests/lar_check.h"
#include "tests/shapes.h"

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

/* Runs the arrangement (with the check's pairing of each solid's edges when twins is given, as
 * the API runs it) and its invariants; returns 0 when both are fine.  *out can be freed
 * either way. */
static int run3_ex(solid *s, size_t n, int soup, const uint32_t *const *twins, double precision,
                   lar3 *out, long *euler)
{
    arr3_opts o = {0};
    o.precision = precision;
    char err[256];
    int rc = arr3_build_ex(s, n, soup, twins, &o, out, err, sizeof err);
    if (rc) {
        test_fail(__FILE__, __func__, __LINE__, "arr3_build_ex: %d %s", rc, err);
        return -1;
    }
    char msg[256];
    if (lar3_check(out, precision > 0 ? 3 * precision : 1e-6, euler, msg, sizeof msg)) {
        test_fail(__FILE__, __func__, __LINE__, "lar3_check: %s", msg);
        return -1;
    }
    return 0;
}

static int run3(solid *s, size_t n, int soup, double precision, lar3 *out, long *euler)
{
    return run3_ex(s, n, soup, NULL, precision, out, euler);
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
        CHECK(c.nv == 22 && c.ne == 36 && c.nf == 18 && c.nc == 3, "V %zu E %zu F %zu C %zu", c.nv,
              c.ne, c.nf, c.nc);
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
        CHECK(c.nv == 20 && c.ne == 34 && c.nf == 18 && c.nc == 3, "V %zu E %zu F %zu C %zu", c.nv,
              c.ne, c.nf, c.nc);
        CHECK(eu == 0, "euler %ld", eu);
        double tot = 0;
        for (size_t k = 0; k < c.nc; k++) tot += c.cvol[k];
        /* union = 2 - the intersection, a prism of height 0.5 over the square ∩ rotated square */
        CHECK(tot > 1.5 && tot < 2, "total %g", tot);
    }
    lar3_free(&c);
    free_all(s, 2);
}

/* K x K x K unit cubes at (i, j, k) / 2: the union [0, (K+1)/2]^3 cut by every plane x, y,
 * z = m / 2 into (K+1)^3 cells of volume 1/8. */
TEST(grid_of_overlapping_cubes)
{
    for (int K = 1; K <= 5; K++) {
        size_t n = (size_t)K * K * K;
        solid *s = calloc(n, sizeof *s);
        size_t m = 0;
        for (int i = 0; i < K; i++)
            for (int j = 0; j < K; j++)
                for (int k = 0; k < K; k++)
                    s[m++] = box(i / 2.0, j / 2.0, k / 2.0, i / 2.0 + 1, j / 2.0 + 1, k / 2.0 + 1);
        lar3 c;
        long eu;
        if (!run3(s, n, 0, 0, &c, &eu)) {
            size_t a = (size_t)K + 1, b = (size_t)K + 2;
            if (K == 1) a = 1, b = 2; /* a single cube */
            CHECK(c.nv == b * b * b && c.ne == 3 * a * b * b && c.nf == 3 * a * a * b &&
                      c.nc == a * a * a,
                  "K=%d: V %zu E %zu F %zu C %zu", K, c.nv, c.ne, c.nf, c.nc);
            double bad = 0, want = K == 1 ? 1 : 0.125;
            for (size_t q = 0; q < c.nc; q++)
                if (fabs(c.cvol[q] - want) > bad) bad = fabs(c.cvol[q] - want);
            CHECK(bad < 1e-12, "K=%d: a cell's volume is off by %g", K, bad);
            CHECK(eu == 0, "K=%d: euler %ld", K, eu);
        }
        lar3_free(&c);
        free_all(s, n);
        free(s);
    }
}

TEST(cubes_sharing_a_face)
{
    solid s[2] = {box(0, 0, 0, 1, 1, 1), box(1, 0, 0, 2, 1, 1)};
    lar3 c;
    long eu;
    if (!run3(s, 2, 0, 0, &c, &eu)) {
        CHECK(c.nv == 12 && c.ne == 20 && c.nf == 11 && c.nc == 2, "V %zu E %zu F %zu C %zu", c.nv,
              c.ne, c.nf, c.nc);
        double want[2] = {1, 1};
        CHECK(volumes_are(&c, want, 2, 1e-12), "volumes");
        CHECK(eu == 0, "euler %ld", eu);
    }
    lar3_free(&c);
    free_all(s, 2);
}

/* A small box standing on a big one: the big box's top becomes a ring (a face with a hole)
 * around the square they share. */
TEST(cube_on_top_of_another)
{
    solid s[2] = {box(0, 0, 0, 2, 2, 1), box(.5, .5, 1, 1.5, 1.5, 2)};
    lar3 c;
    long eu;
    if (!run3(s, 2, 0, 0, &c, &eu)) {
        CHECK(c.nv == 16 && c.ne == 24 && c.nf == 12 && c.nc == 2, "V %zu E %zu F %zu C %zu", c.nv,
              c.ne, c.nf, c.nc);
        size_t holes = 0;
        for (size_t f = 0; f < c.nf; f++) holes += c.fc_off[f + 1] - c.fc_off[f] - 1;
        CHECK(holes == 1, "%zu holes", holes);
        double want[2] = {1, 4};
        CHECK(volumes_are(&c, want, 2, 1e-12), "volumes");
        CHECK(eu == 1, "euler %ld (one annular face)", eu);
    }
    lar3_free(&c);
    free_all(s, 2);
}

TEST(identical_cubes)
{
    solid s[3] = {box(0, 0, 0, 1, 1, 1), box(0, 0, 0, 1, 1, 1), box(0, 0, 0, 1, 1, 1)};
    lar3 c;
    long eu;
    if (!run3(s, 3, 0, 0, &c, &eu)) {
        CHECK(c.nv == 8 && c.ne == 12 && c.nf == 6 && c.nc == 1, "V %zu E %zu F %zu C %zu", c.nv,
              c.ne, c.nf, c.nc);
        CHECK(c.nc == 1 && fabs(c.cvol[0] - 1) < 1e-12, "volume");
    }
    lar3_free(&c);
    free_all(s, 3);
}

/* A cube floating inside another: the outer cell has a cavity (12 faces, volume 26). */
TEST(cube_inside_cube_is_a_cavity)
{
    solid s[2] = {box(0, 0, 0, 3, 3, 3), box(1, 1, 1, 2, 2, 2)};
    lar3 c;
    long eu;
    if (!run3(s, 2, 0, 0, &c, &eu)) {
        CHECK(c.nv == 16 && c.ne == 24 && c.nf == 12 && c.nc == 2, "V %zu E %zu F %zu C %zu", c.nv,
              c.ne, c.nf, c.nc);
        double want[2] = {1, 26};
        CHECK(volumes_are(&c, want, 2, 1e-12), "volumes");
        size_t big = c.cvol[0] > c.cvol[1] ? 0 : 1;
        CHECK(c.cf_off[big + 1] - c.cf_off[big] == 12, "the outer cell has %u faces",
              c.cf_off[big + 1] - c.cf_off[big]);
        CHECK(c.next == 6, "exterior %zu faces", c.next);
    }
    lar3_free(&c);
    /* nested twice, and a rotated cube inside: still cavities */
    double ax[3] = {0.6, 0.8, 0}, t[3] = {4.2, 4.2, 4.2};
    solid s2[3] = {box(0, 0, 0, 10, 10, 10), box(2, 2, 2, 8, 8, 8), cube_rt(1, ax, 0.7, t)};
    if (!run3(s2, 3, 0, 0, &c, &eu)) {
        double want[3] = {1, 216 - 1, 1000 - 216};
        CHECK(volumes_are(&c, want, 3, 1e-6), "nested volumes (the rotated cube is snapped)");
    }
    lar3_free(&c);
    free_all(s2, 3);
    free_all(s, 2);
}

/* An L-shaped prism (non-convex top and bottom) crossing a box. */
TEST(l_prism_crossing_a_box)
{
    static const double L[6][2] = {{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}};
    solid p = {0};
    p.nv = 12;
    p.V = malloc(36 * sizeof *p.V);
    for (int i = 0; i < 6; i++)
        for (int z = 0; z < 2; z++) {
            p.V[3 * (i + 6 * z)] = L[i][0];
            p.V[3 * (i + 6 * z) + 1] = L[i][1];
            p.V[3 * (i + 6 * z) + 2] = z;
        }
    p.nf = p.ncyc = 8;
    p.face_off = malloc(9 * sizeof *p.face_off);
    p.cyc_off = malloc(9 * sizeof *p.cyc_off);
    p.cyc = malloc(36 * sizeof *p.cyc);
    uint32_t n = 0;
    p.cyc_off[0] = 0;
    for (int i = 5; i >= 0; i--) p.cyc[n++] = (uint32_t)i; /* bottom, seen from below */
    p.cyc_off[1] = n;
    for (int i = 0; i < 6; i++) p.cyc[n++] = (uint32_t)(6 + i);
    p.cyc_off[2] = n;
    for (int i = 0; i < 6; i++) {
        uint32_t a = (uint32_t)i, b = (uint32_t)((i + 1) % 6);
        p.cyc[n++] = a, p.cyc[n++] = b, p.cyc[n++] = b + 6, p.cyc[n++] = a + 6;
        p.cyc_off[3 + i] = n;
    }
    for (int f = 0; f <= 8; f++) p.face_off[f] = (uint32_t)f;
    solid s[2] = {p, box(.5, .5, -1, 2.5, 2.5, .5)};
    lar3 c;
    long eu;
    if (!run3(s, 2, 0, 0, &c, &eu)) {
        double want[3] = {0.875, 4.125, 5.125};
        CHECK(volumes_are(&c, want, 3, 1e-12), "volumes");
        CHECK(eu == 0, "euler %ld", eu);
    }
    lar3_free(&c);
    free_all(s, 2);
}

/* The seeds' five random cubes (tests/data/mesh/fivecubes-input.json; quads in LAR cuboid
 * order a, b, d, c), oriented by solid_check. */
static int load_fivecubes(solid *s)
{
    char path[512];
    snprintf(path, sizeof path, "%s/mesh/fivecubes-input.json", test_data_dir());
    json_error_t je;
    json_t *j = json_load_file(path, 0, &je);
    if (!j) return -1;
    json_t *V = json_object_get(j, "V"), *FV = json_object_get(j, "FV");
    for (int k = 0; k < 5; k++) {
        double c[8][3];
        for (int i = 0; i < 8; i++)
            for (int a = 0; a < 3; a++)
                c[i][a] = json_number_value(json_array_get(json_array_get(V, 8 * k + i), a));
        solid raw = hexa(c);
        /* the file's own faces, in their order and orientation */
        for (int f = 0; f < 6; f++) {
            json_t *q = json_array_get(FV, 6 * k + f);
            uint32_t a = (uint32_t)json_integer_value(json_array_get(q, 0)) - 1 - 8 * k;
            uint32_t b = (uint32_t)json_integer_value(json_array_get(q, 1)) - 1 - 8 * k;
            uint32_t cc = (uint32_t)json_integer_value(json_array_get(q, 2)) - 1 - 8 * k;
            uint32_t d = (uint32_t)json_integer_value(json_array_get(q, 3)) - 1 - 8 * k;
            raw.cyc[4 * f] = a, raw.cyc[4 * f + 1] = b, raw.cyc[4 * f + 2] = d;
            raw.cyc[4 * f + 3] = cc;
        }
        solid_report rep;
        /* the file's corners are planar to 2e-6 only (printed digits) */
        int rc = solid_check(&raw, 1e-5, "fivecubes", &rep, &s[k]);
        solid_free(&raw);
        if (rc) {
            json_decref(j);
            return -1;
        }
    }
    json_decref(j);
    return 0;
}

/* The volumes of the bounded cells of LAR.jl's own arrangement of the five cubes
 * (tests/data/mesh/fivecubes.obj: "g cellN" groups of triangles, cell1 the exterior), each cell
 * read as a solid and oriented by solid_check; sorted into vol[26]. */
static int fivecubes_reference(double *vol)
{
    char path[512], err[200];
    snprintf(path, sizeof path, "%s/mesh/fivecubes.obj", test_data_dir());
    size_t len;
    char *text = test_read_file(path, &len);
    if (!text) return -1;
    int n = 0, cur = 0;
    for (int g = 2; g <= 27; g++) {
        /* keep the v lines and the f lines of group g */
        char *t = malloc(len + 1);
        size_t k = 0;
        cur = 0;
        for (const char *p = text; *p;) {
            const char *e = strchr(p, '\n');
            e = e ? e + 1 : p + strlen(p);
            if (p[0] == 'g' && p[1] == ' ') cur++;
            if (!(p[0] == 'f' && p[1] == ' ') || cur == g) {
                memcpy(t + k, p, (size_t)(e - p));
                k += (size_t)(e - p);
            }
            p = e;
        }
        t[k] = 0;
        solid s;
        solid_report r;
        if (solid_read_obj(t, k, &s, err, sizeof err) == 0) {
            if (solid_check(&s, 1e-7, "cell", &r, NULL) == 0) vol[n++] = fabs(r.volume);
            solid_free(&s);
        }
        free(t);
    }
    free(text);
    qsort(vol, (size_t)n, sizeof *vol, cmp_double);
    return n == 26 ? 0 : -1;
}

/* A closed mesh of k x k quads on each side of a cube, pushed out to a lumpy sphere (radius
 * 1 + 0.08 sin(3x) cos(2y) sin(z) at each corner, coordinates on the grid of 2^-20): its quads
 * are not planar.  With tri, each quad is given as the two triangles the arrangement would make
 * of it: the diagonal whose triangles' normals agree best. */
static solid lumpy_quads(int k, int tri)
{
    int n1 = k + 1;
    size_t nv = 6 * (size_t)n1 * (size_t)n1;
    double *V = malloc(3 * nv * sizeof *V);
    int *F = malloc((6 * (size_t)k * (size_t)k * 8 + 1) * sizeof *F);
    size_t nf = 0;
    for (int side = 0; side < 6; side++) {
        int ax = side / 2, sg = side % 2 ? 1 : -1;
        for (int i = 0; i <= k; i++)
            for (int j = 0; j <= k; j++) {
                double c[3];
                c[ax] = sg;
                c[(ax + 1) % 3] = -1 + 2.0 * i / k;
                c[(ax + 2) % 3] = -1 + 2.0 * j / k;
                double r = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                double rr = 1 + 0.08 * sin(3 * c[0]) * cos(2 * c[1]) * sin(c[2]);
                double *v = V + 3 * ((size_t)(side * n1 + i) * n1 + j);
                for (int a = 0; a < 3; a++) v[a] = ldexp(round(ldexp(c[a] / r * rr, 20)), -20);
            }
        for (int i = 0; i < k; i++)
            for (int j = 0; j < k; j++) {
                int q[4] = {(side * n1 + i) * n1 + j, (side * n1 + i + 1) * n1 + j,
                            (side * n1 + i + 1) * n1 + j + 1, (side * n1 + i) * n1 + j + 1};
                if (sg < 0) {
                    int t = q[1];
                    q[1] = q[3], q[3] = t;
                }
                if (!tri) {
                    for (int t = 0; t < 4; t++) F[nf++] = q[t];
                    F[nf++] = -1;
                    continue;
                }
                double dot[2];
                for (int a = 0; a < 2; a++) {
                    double nrm[2][3];
                    for (int h = 0; h < 2; h++) {
                        const double *p0 = V + 3 * q[(a + 2 * h) % 4],
                                     *p1 = V + 3 * q[(a + 2 * h + 1) % 4],
                                     *p2 = V + 3 * q[(a + 2 * h + 2) % 4];
                        double u[3], w[3];
                        for (int d = 0; d < 3; d++) u[d] = p1[d] - p0[d], w[d] = p2[d] - p0[d];
                        nrm[h][0] = u[1] * w[2] - u[2] * w[1];
                        nrm[h][1] = u[2] * w[0] - u[0] * w[2];
                        nrm[h][2] = u[0] * w[1] - u[1] * w[0];
                    }
                    dot[a] = nrm[0][0] * nrm[1][0] + nrm[0][1] * nrm[1][1] + nrm[0][2] * nrm[1][2];
                }
                int a = dot[0] > dot[1] ? 0 : 1;
                int t6[6] = {q[a], q[a + 1], q[a + 2], q[a + 2], q[(a + 3) % 4], q[a]};
                for (int t = 0; t < 6; t++) {
                    F[nf++] = t6[t];
                    if (t % 3 == 2) F[nf++] = -1;
                }
            }
    }
    F[nf] = -2;
    solid s = shape_poly(V, nv, F);
    free(V), free(F);
    return s;
}

/* run3 with each solid checked first and the check's pairing of its edges handed on. */
static int run3_checked(solid *s, size_t n, double precision, lar3 *out, long *euler)
{
    uint32_t *tw[8] = {0};
    int rc = -1;
    memset(out, 0, sizeof *out);
    for (size_t i = 0; i < n && i < 8; i++) {
        solid_report r;
        tw[i] = malloc((s[i].cyc_off[s[i].ncyc] + 1) * sizeof *tw[i]);
        if (!tw[i] || solid_check_nocopy(&s[i], precision, "s", &r, NULL, tw[i])) {
            test_fail(__FILE__, __func__, __LINE__, "solid %zu: the check failed", i);
            goto done;
        }
    }
    rc = run3_ex(s, n, 0, (const uint32_t *const *)tw, precision, out, euler);
done:
    for (size_t i = 0; i < n && i < 8; i++) free(tw[i]);
    return rc;
}

/* Faces split into triangles keep their patches: the untouched part of a mesh of quads that are
 * not planar is walked as one patch (not one patch a triangle), and the complex is the one of
 * the same mesh given as those triangles. */
TEST(split_quads_stay_in_patches)
{
    lar3 c[2];
    long eu[2];
    int ok[2];
    for (int tri = 0; tri < 2; tri++) {
        solid s[2] = {lumpy_quads(12, tri), box(0.3, 0.3, 0.3, 2, 2, 2)};
        ok[tri] = !run3_checked(s, 2, 0x1p-20, &c[tri], &eu[tri]);
        free_all(s, 2);
    }
    if (ok[0] && ok[1]) {
        printf("# lumpy quads: V %zu E %zu F %zu C %zu, %zu split, %zu patches\n", c[0].nv, c[0].ne,
               c[0].nf, c[0].nc, c[0].stats.split_faces, c[0].stats.patches);
        CHECK(c[0].stats.split_faces == 6 * 12 * 12, "%zu quads split", c[0].stats.split_faces);
        CHECK(c[0].stats.faces_reached > 0 && c[0].stats.faces_reached < 200, "%zu reached",
              c[0].stats.faces_reached);
        CHECK(c[0].stats.patches >= 1 && c[0].stats.patches <= 4,
              "%zu patches (one a triangle: %zu)", c[0].stats.patches,
              2 * c[0].stats.split_faces - c[0].stats.faces_reached);
        CHECK(c[0].stats.patches == c[1].stats.patches, "patches %zu, as triangles %zu",
              c[0].stats.patches, c[1].stats.patches);
        CHECK(c[0].nv == c[1].nv && c[0].ne == c[1].ne && c[0].nf == c[1].nf && c[0].nc == c[1].nc,
              "V %zu E %zu F %zu C %zu, as triangles V %zu E %zu F %zu C %zu", c[0].nv, c[0].ne,
              c[0].nf, c[0].nc, c[1].nv, c[1].ne, c[1].nf, c[1].nc);
        CHECK(c[0].nc == 3 && eu[0] == eu[1], "C %zu, euler %ld / %ld", c[0].nc, eu[0], eu[1]);
        for (size_t k = 0; k < c[0].nc && k < c[1].nc; k++)
            CHECK(fabs(c[0].cvol[k] - c[1].cvol[k]) <= 1e-12 * fabs(c[1].cvol[k]),
                  "cell %zu: volume %.17g, as triangles %.17g", k, c[0].cvol[k], c[1].cvol[k]);
    }
    for (int tri = 0; tri < 2; tri++) lar3_free(&c[tri]);
}

TEST(five_cubes_of_the_seeds)
{
    solid s[5] = {0};
    double ref[26], got[26];
    REQUIRE(!load_fivecubes(s), "cannot load fivecubes-input.json");
    REQUIRE(!fivecubes_reference(ref), "cannot read the 26 cells of fivecubes.obj");
    lar3 c;
    long eu;
    if (!run3(s, 5, 0, 1e-5, &c, &eu)) {
        /* LAR.jl's arrangement (fivecubes-arrangement.json) has 137 V, 268 E, 157 F and 26
         * bounded cells: it takes each quad as planar.  The file's corners are planar only to
         * 2e-6, so on the grid of 1e-5 the quads are not exactly planar and each becomes two
         * triangles (more vertices, edges and faces); the cells are the same 26, with the same
         * volumes up to the snapping (1e-5 times a cell's area) and the file's 6 digits (some
         * quads happen to be exactly planar on the grid and stay whole). */
        printf("# fivecubes: V %zu E %zu F %zu C %zu (+1), %zu split faces\n", c.nv, c.ne, c.nf,
               c.nc, c.stats.split_faces);
        CHECK(c.nc == 26, "%zu bounded cells, LAR.jl has 26", c.nc);
        CHECK(c.stats.split_faces > 0 && c.stats.split_faces <= 30, "%zu quads split",
              c.stats.split_faces);
        if (c.nc == 26) {
            double worst = 0;
            for (int i = 0; i < 26; i++) got[i] = c.cvol[i];
            qsort(got, 26, sizeof *got, cmp_double);
            for (int i = 0; i < 26; i++)
                if (fabs(got[i] - ref[i]) > worst) worst = fabs(got[i] - ref[i]);
            printf("# fivecubes: cell volumes within %.3g of LAR.jl's\n", worst);
            CHECK(worst < 6e-5, "a cell volume differs by %.3g from LAR.jl's", worst);
        }
    }
    lar3_free(&c);
    free_all(s, 5);
}

/* n cubes of edge 0.5 * (0.5 + rand) randomly rotated, in the unit box (like the seeds'
 * randomcubes.jl).  Returns the solids (malloc'd). */
static solid *random_cubes(size_t n, uint64_t seed)
{
    solid *s = calloc(n, sizeof *s);
    uint64_t st = seed;
    for (size_t i = 0; i < n; i++) {
        double u[3], len;
        do {
            for (int k = 0; k < 3; k++) u[k] = 2 * test_rnd(&st) - 1;
            len = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        } while (len < 0.1 || len > 1);
        for (int k = 0; k < 3; k++) u[k] /= len;
        double a = 2 * M_PI * test_rnd(&st), e = 0.5 * (0.5 + test_rnd(&st));
        double t[3] = {test_rnd(&st), test_rnd(&st), test_rnd(&st)};
        s[i] = cube_rt(e, u, a, t);
    }
    return s;
}

TEST(random_rotated_cubes)
{
    static const size_t sizes[] = {2, 3, 5, 8, 12, 20};
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; si++)
        for (uint64_t seed = 1; seed <= 6; seed++) {
            size_t n = sizes[si];
            solid *s = random_cubes(n, seed * 7919 + n);
            lar3 c;
            long eu;
            if (run3(s, n, 0, 0, &c, &eu))
                test_fail(__FILE__, __func__, __LINE__, "n=%zu seed=%llu", n,
                          (unsigned long long)seed);
            lar3_free(&c);
            free_all(s, n);
            free(s);
        }
}

/* Volume of the union of n boxes (6 numbers each) with its voids filled, by coordinate
 * compression: the compressed cells not covered by any box and not reachable from outside
 * through faces of other such cells are voids, and a void the boxes enclose is a bounded cell of
 * the arrangement too. */
static double filled_union_volume(const double *bx, size_t n)
{
    double *c[3];
    size_t m[3];
    for (int a = 0; a < 3; a++) {
        c[a] = malloc((2 * n + 2) * sizeof(double));
        for (size_t i = 0; i < n; i++)
            c[a][2 * i] = bx[6 * i + a], c[a][2 * i + 1] = bx[6 * i + 3 + a];
        qsort(c[a], 2 * n, sizeof(double), cmp_double);
        m[a] = 0;
        for (size_t i = 0; i < 2 * n; i++)
            if (!m[a] || c[a][i] != c[a][m[a] - 1]) c[a][m[a]++] = c[a][i];
    }
    /* cells (i, j, k) of the compressed grid, with a layer of outside around: index + 1 */
    size_t X = m[0] + 1, Y = m[1] + 1, Z = m[2] + 1, N = X * Y * Z;
    char *st = calloc(N, 1); /* 0 empty, 1 covered, 2 reached from outside */
    size_t *stack = malloc(N * sizeof *stack), sp = 0;
    for (size_t i = 1; i + 1 < X; i++)
        for (size_t j = 1; j + 1 < Y; j++)
            for (size_t k = 1; k + 1 < Z; k++) {
                double p[3] = {(c[0][i - 1] + c[0][i]) / 2, (c[1][j - 1] + c[1][j]) / 2,
                               (c[2][k - 1] + c[2][k]) / 2};
                for (size_t b = 0; b < n; b++)
                    if (p[0] > bx[6 * b] && p[0] < bx[6 * b + 3] && p[1] > bx[6 * b + 1] &&
                        p[1] < bx[6 * b + 4] && p[2] > bx[6 * b + 2] && p[2] < bx[6 * b + 5]) {
                        st[(i * Y + j) * Z + k] = 1;
                        break;
                    }
            }
    st[0] = 2;
    stack[sp++] = 0;
    while (sp) {
        size_t q = stack[--sp], i = q / (Y * Z), j = q / Z % Y, k = q % Z;
        long d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (int t = 0; t < 6; t++) {
            long a = (long)i + d[t][0], b = (long)j + d[t][1], e = (long)k + d[t][2];
            if (a < 0 || b < 0 || e < 0 || a >= (long)X || b >= (long)Y || e >= (long)Z) continue;
            size_t r = ((size_t)a * Y + (size_t)b) * Z + (size_t)e;
            if (st[r]) continue;
            st[r] = 2;
            stack[sp++] = r;
        }
    }
    double v = 0;
    for (size_t i = 1; i + 1 < X; i++)
        for (size_t j = 1; j + 1 < Y; j++)
            for (size_t k = 1; k + 1 < Z; k++)
                if (st[(i * Y + j) * Z + k] != 2)
                    v +=
                        (c[0][i] - c[0][i - 1]) * (c[1][j] - c[1][j - 1]) * (c[2][k] - c[2][k - 1]);
    free(st);
    free(stack);
    for (int a = 0; a < 3; a++) free(c[a]);
    return v;
}

/* Random boxes on a lattice of step 1/4: faces share planes, edges and corners everywhere (the
 * coplanar cases), and the cells must fill the union (voids filled) exactly. */
TEST(random_boxes_on_a_lattice)
{
    for (uint64_t seed = 1; seed <= 60; seed++) {
        size_t n = 4 + seed % 27;
        uint64_t st = seed * 1000 + 7;
        double *bx = malloc(6 * n * sizeof *bx);
        solid *s = calloc(n, sizeof *s);
        for (size_t i = 0; i < n; i++) {
            for (int a = 0; a < 3; a++) {
                double lo = floor(test_rnd(&st) * 8) / 4, len = (1 + floor(test_rnd(&st) * 6)) / 4;
                bx[6 * i + a] = lo, bx[6 * i + 3 + a] = lo + len;
            }
            s[i] = box(bx[6 * i], bx[6 * i + 1], bx[6 * i + 2], bx[6 * i + 3], bx[6 * i + 4],
                       bx[6 * i + 5]);
        }
        lar3 c;
        long eu;
        if (!run3(s, n, 0, 0, &c, &eu)) {
            double sum = 0, want = filled_union_volume(bx, n);
            for (size_t k = 0; k < c.nc; k++) sum += c.cvol[k];
            CHECK(fabs(sum - want) < 1e-12, "seed %llu: cells %.17g, union %.17g",
                  (unsigned long long)seed, sum, want);
        }
        lar3_free(&c);
        free_all(s, n);
        free(s);
        free(bx);
    }
}
