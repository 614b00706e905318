/* test_bool3.c — Boolean chains of 3D arrangements (core/bool3.c): membership, the selected
 * cells, and their boundary, closed and outward (∂2 of the boundary is 0, its enclosed volume is
 * the cells' volume). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "api/api_int.h"
#include "core/arr3.h"
#include "core/bool3.h"
#include "core/boolexpr.h"
#include "core/solid.h"
#include "tests/check.h"
#include "tests/lar_check.h"
#include "tests/shapes.h"

static const uint32_t cube_faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                          {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

static solid box(double x0, double y0, double z0, double x1, double y1, double z1)
{
    solid s = {0};
    s.nv = 8;
    s.V = malloc(24 * sizeof *s.V);
    s.nf = s.ncyc = 6;
    s.face_off = malloc(7 * sizeof *s.face_off);
    s.cyc_off = malloc(7 * sizeof *s.cyc_off);
    s.cyc = malloc(24 * sizeof *s.cyc);
    for (int i = 0; i < 8; i++) {
        s.V[3 * i] = i & 1 ? x1 : x0;
        s.V[3 * i + 1] = i & 2 ? y1 : y0;
        s.V[3 * i + 2] = i & 4 ? z1 : z0;
    }
    for (int f = 0; f <= 6; f++) s.face_off[f] = (uint32_t)f, s.cyc_off[f] = (uint32_t)(4 * f);
    for (int f = 0; f < 6; f++) memcpy(s.cyc + 4 * f, cube_faces[f], 4 * sizeof(uint32_t));
    return s;
}

/* Checks the result's boundary: closed (every edge's signed count is 0) and enclosing the
 * volume of its cells; returns its area. */
static double check_boundary(const lar3 *c, const bool3_result *r)
{
    long *acc = calloc(c->ne + 1, sizeof *acc);
    double vol = 0, area = 0;
    for (size_t i = 0; i < r->nfaces; i++) {
        int32_t s = r->faces[i];
        uint32_t f = (uint32_t)abs(s) - 1;
        for (uint32_t j = c->fe_off[f]; j < c->fe_off[f + 1]; j++) {
            int32_t e = c->fe[j];
            acc[abs(e) - 1] += (s > 0 ? 1 : -1) * (e > 0 ? 1 : -1);
        }
        vol += (s > 0 ? 1 : -1) * lar3_face_cone(c, f);
        /* area: |sum of cross products| over the cycles, along the normal */
        for (uint32_t cy = c->fc_off[f]; cy < c->fc_off[f + 1]; cy++) {
            uint32_t c0 = c->cyc_off[c->fc[cy]], c1 = c->cyc_off[c->fc[cy] + 1];
            double n[3] = {0, 0, 0};
            for (uint32_t k = c0; k < c1; k++) {
                const double *p = c->V + 3 * c->cyc[k],
                             *q = c->V + 3 * c->cyc[k + 1 < c1 ? k + 1 : c0];
                n[0] += p[1] * q[2] - p[2] * q[1];
                n[1] += p[2] * q[0] - p[0] * q[2];
                n[2] += p[0] * q[1] - p[1] * q[0];
            }
            area += (n[0] * c->FN[3 * f] + n[1] * c->FN[3 * f + 1] + n[2] * c->FN[3 * f + 2]) / 2;
        }
    }
    size_t open = 0;
    for (size_t e = 0; e < c->ne; e++) open += acc[e] != 0;
    CHECK(open == 0, "the boundary is open at %zu edges", open);
    CHECK(fabs(vol - r->volume) < 1e-9 * (fabs(vol) + 1), "boundary encloses %.17g, cells %.17g",
          vol, r->volume);
    free(acc);
    return area;
}

typedef struct want {
    const char *op;
    size_t faces;
    double volume, area; /* area < 0: not checked */
} want;

static void run_ops(solid *s, size_t n, const want *w, size_t nw)
{
    arr3_opts o = {0};
    lar3 c;
    char err[256], msg[256];
    REQUIRE(!arr3_build(s, n, 0, &o, &c, err, sizeof err), "arr3_build: %s", err);
    CHECK(!lar3_check(&c, 1e-6, NULL, msg, sizeof msg), "lar3_check: %s", msg);
    member_rows rows = {0};
    uint8_t *mem = malloc(c.nc * n + 1);
    long bad = lar3_membership_dense(&c, mem, &rows);
    CHECK(bad == 0, "membership: %ld inconsistent cells", bad);
    /* every bounded cell lies in some solid, unless it is a void the solids enclose */
    for (size_t i = 0; i < nw; i++) {
        bool_expr e;
        REQUIRE(!bool_expr_named(w[i].op, n, &e), "%s", w[i].op);
        bool3_result r;
        REQUIRE(!bool3_select(&c, &rows, &e, &r), "select");
        CHECK(r.nfaces == w[i].faces, "%s: %zu boundary faces, want %zu", w[i].op, r.nfaces,
              w[i].faces);
        CHECK(fabs(r.volume - w[i].volume) < 1e-9, "%s: volume %.17g, want %.17g", w[i].op,
              r.volume, w[i].volume);
        double area = check_boundary(&c, &r);
        if (w[i].area >= 0)
            CHECK(fabs(area - w[i].area) < 1e-9, "%s: area %.17g, want %.17g", w[i].op, area,
                  w[i].area);
        bool3_result_free(&r);
        bool_expr_free(&e);
    }
    free(mem);
    member_rows_free(&rows);
    lar3_free(&c);
}

TEST(two_offset_cubes)
{
    solid s[2] = {box(0, 0, 0, 1, 1, 1), box(.5, .5, .5, 1.5, 1.5, 1.5)};
    want w[] = {{"union", 12, 1.875, 6 * 1 + 6 * 1 - 6 * .25},
                {"intersection", 6, 0.125, 6 * .25},
                {"difference", 9, 0.875, 6 - 3 * .25 + 3 * .25},
                {"xor", 18, 1.75, -1}};
    run_ops(s, 2, w, sizeof w / sizeof *w);
    solid_free(&s[0]), solid_free(&s[1]);
}

TEST(touching_and_coplanar)
{
    solid a[2] = {box(0, 0, 0, 1, 1, 1), box(1, 0, 0, 2, 1, 1)}; /* sharing a face */
    want wa[] = {{"union", 10, 2, 10}, {"intersection", 0, 0, 0}, {"difference", 6, 1, 6}};
    run_ops(a, 2, wa, 3);
    solid b[2] = {box(0, 0, 0, 1, 1, 1), box(0, 0, 0, 1, 1, 1)}; /* a cube minus itself */
    want wb[] = {
        {"difference", 0, 0, 0}, {"union", 6, 1, 6}, {"intersection", 6, 1, 6}, {"xor", 0, 0, 0}};
    run_ops(b, 2, wb, 4);
    solid d[2] = {box(0, 0, 0, 3, 3, 3), box(1, 1, 1, 2, 2, 2)}; /* a cavity */
    want wd[] = {{"difference", 12, 26, 54 + 6}, {"union", 6, 27, 54}, {"intersection", 6, 1, 6}};
    run_ops(d, 2, wd, 3);
    solid x[2] = {box(0, 0, 0, 1, 1, 1), box(.5, 0, 0, 1.5, 1, 1)}; /* xor, shifted by half */
    want wx[] = {
        {"xor", 12, 1, 2 * (2 + 4 * .5)}, {"union", 14, 1.5, 8}, {"intersection", 6, .5, 4}};
    run_ops(x, 2, wx, 3);
    for (int i = 0; i < 2; i++)
        solid_free(&a[i]), solid_free(&b[i]), solid_free(&d[i]), solid_free(&x[i]);
}

/* Many operands: the cubes (i, j, k) of a 6 x 6 x 6 grid with i + j + k even (108 unit cubes
 * meeting only along edges and at vertices): the union's volume is 108 exactly, every cell lies
 * in exactly one cube, intersection and difference as closed forms; the membership is sparse. */
TEST(checkerboard_of_cubes)
{
    solid s[108];
    size_t n = 0;
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++)
            for (int k = 0; k < 6; k++)
                if ((i + j + k) % 2 == 0) s[n++] = box(i, j, k, i + 1, j + 1, k + 1);
    arr3_opts o = {0};
    lar3 c;
    char err[256];
    REQUIRE(n == 108, "%zu cubes", n);
    REQUIRE(!arr3_build(s, n, 0, &o, &c, err, sizeof err), "arr3_build: %s", err);
    member_rows rows;
    uint32_t bad;
    REQUIRE(bool3_membership(&c, &rows, &bad) == 0, "membership");
    /* the 32 odd cubes inside are voids the even ones enclose: bounded cells in no cube */
    CHECK(c.nc == 140 && rows.off[c.nc] == 108, "%zu cells, %u memberships", c.nc, rows.off[c.nc]);
    static const char *const ops[] = {"union", "xor", "intersection", "difference"};
    static const double want[] = {108, 108, 0, 1};
    for (int t = 0; t < 4; t++) {
        bool_expr e;
        bool3_result r;
        REQUIRE(!bool_expr_named(ops[t], n, &e), "%s", ops[t]);
        REQUIRE(!bool3_select(&c, &rows, &e, &r), "select");
        CHECK(fabs(r.volume - want[t]) < 1e-12, "%s: volume %.17g, want %g", ops[t], r.volume,
              want[t]);
        check_boundary(&c, &r);
        bool3_result_free(&r);
        bool_expr_free(&e);
    }
    member_rows_free(&rows);
    lar3_free(&c);
    for (size_t i = 0; i < n; i++) solid_free(&s[i]);
}

/* Threads change timings only: 400 turned cubes overlapping at random (pairs, edges and cells
 * in several of the core's parallel chunks) give the same complex, in the same order, on 1 and
 * on 3 threads. */
TEST(threads_give_identical_complex)
{
    enum { N = 400 };
    solid s[N];
    uint64_t x = 99;
    for (int i = 0; i < N; i++) {
        double r[6], R[3][3];
        for (int k = 0; k < 6; k++) {
            x = x * 6364136223846793005u + 1442695040888963407u;
            r[k] = (double)(x >> 11) * 0x1.0p-53;
        }
        double len = sqrt(r[3] * r[3] + r[4] * r[4] + 0.01),
               u[3] = {r[3] / len, r[4] / len, 0.1 / len};
        s[i] = box(-0.5, -0.5, -0.5, 0.5, 0.5, 0.5);
        shape_rotation(u, 6.28 * r[5], R);
        double t[3] = {6 * r[0], 6 * r[1], 6 * r[2]};
        shape_transform(&s[i], R, t);
    }
    lar3 c[2];
    char err[256];
    for (int t = 0; t < 2; t++) {
        arr3_opts o = {.threads = t ? 3 : 1};
        REQUIRE(!arr3_build(s, N, 0, &o, &c[t], err, sizeof err), "arr3_build: %s", err);
    }
    CHECK(c[0].stats.pairs_tested > 2 * 8192 && c[0].ne > 2 * 8192 && c[0].nc > 2 * 4096,
          "too small to span chunks: %zu pairs, %zu edges, %zu cells", c[0].stats.pairs_tested,
          c[0].ne, c[0].nc);
    int same = c[0].nv == c[1].nv && c[0].ne == c[1].ne && c[0].nf == c[1].nf &&
               c[0].nc == c[1].nc && c[0].ncyc == c[1].ncyc;
    if (same)
        same = !memcmp(c[0].V, c[1].V, 3 * c[0].nv * sizeof *c[0].V) &&
               !memcmp(c[0].EV, c[1].EV, 2 * c[0].ne * sizeof *c[0].EV) &&
               !memcmp(c[0].fe_off, c[1].fe_off, (c[0].nf + 1) * sizeof *c[0].fe_off) &&
               !memcmp(c[0].fe, c[1].fe, c[0].fe_off[c[0].nf] * sizeof *c[0].fe) &&
               !memcmp(c[0].cf_off, c[1].cf_off, (c[0].nc + 1) * sizeof *c[0].cf_off) &&
               !memcmp(c[0].cf, c[1].cf, c[0].cf_off[c[0].nc] * sizeof *c[0].cf) &&
               !memcmp(c[0].cvol, c[1].cvol, c[0].nc * sizeof *c[0].cvol);
    CHECK(same, "1 and 3 threads differ: %zu/%zu vertices, %zu/%zu edges, %zu/%zu cells", c[0].nv,
          c[1].nv, c[0].ne, c[1].ne, c[0].nc, c[1].nc);
    for (int t = 0; t < 2; t++) lar3_free(&c[t]);
    for (int i = 0; i < N; i++) solid_free(&s[i]);
}

/* Progress of a 3D Boolean through the API: the arrangement's stages, then membership, then
 * output moving as the result's keys are written; never back, never past 1. */
typedef struct prog3 {
    int membership, output, back;
    double last;
} prog3;

static void prog3_cb(void *udata, const char *stage, double f)
{
    prog3 *l = udata;
    l->membership += !strcmp(stage, "membership");
    l->output += !strcmp(stage, "output");
    if (f < l->last || f > 1) l->back++;
    l->last = f;
}

TEST(progress_through_membership_and_output)
{
    static const char body[] =
        "{\"kind\":\"solids\",\"op\":\"union\",\"solids\":["
        "{\"V\":[[0,0,0],[1,0,0],[0,1,0],[1,1,0],[0,0,1],[1,0,1],[0,1,1],[1,1,1]],"
        "\"FV\":[[0,4,6,2],[1,3,7,5],[0,1,5,4],[2,6,7,3],[0,2,3,1],[4,5,7,6]]},"
        "{\"V\":[[0.5,0.5,0.5],[1.5,0.5,0.5],[0.5,1.5,0.5],[1.5,1.5,0.5],[0.5,0.5,1.5],"
        "[1.5,0.5,1.5],[0.5,1.5,1.5],[1.5,1.5,1.5]],"
        "\"FV\":[[0,4,6,2],[1,3,7,5],[0,1,5,4],[2,6,7,3],[0,2,3,1],[4,5,7,6]]}]}";
    prog3 l = {0};
    api_run_opts ro = {.threads = 2, .progress = prog3_cb, .udata = &l};
    char *out = NULL;
    size_t outlen;
    api_error err = {0};
    int rc = api_run_json_ex(body, sizeof body - 1, &ro, &out, &outlen, &err);
    CHECK(rc == API_OK, "%d %s", rc, err.msg);
    CHECK(l.membership >= 1 && l.output >= 4 && l.back == 0,
          "progress: membership %d, output %d, %d back or past 1", l.membership, l.output, l.back);
    free(out);
}

/* Three cubes and an expression tree: 0 - (1 + 2). */
TEST(expression_tree)
{
    solid s[3] = {box(0, 0, 0, 2, 2, 2), box(1, 0, 0, 3, 1, 1), box(0, 1, 1, 1, 3, 3)};
    arr3_opts o = {0};
    lar3 c;
    char err[256];
    REQUIRE(!arr3_build(s, 3, 0, &o, &c, err, sizeof err), "%s", err);
    member_rows rows = {0};
    uint8_t *mem = malloc(c.nc * 3 + 1);
    CHECK(lar3_membership_dense(&c, mem, &rows) == 0, "membership");
    bool_expr e = {0};
    int32_t prog[] = {0, 1, 2, BOOL_OR, BOOL_SUB};
    for (size_t i = 0; i < 5; i++) bool_expr_push(&e, prog[i]);
    REQUIRE(!bool_expr_check(&e, 3), "check");
    bool3_result r;
    REQUIRE(!bool3_select(&c, &rows, &e, &r), "select");
    /* 8 - (1*1*1 inside of cube 1) - (1*1*1 inside of cube 2) */
    CHECK(fabs(r.volume - 6) < 1e-12, "volume %.17g", r.volume);
    check_boundary(&c, &r);
    bool3_result_free(&r);
    bool_expr_free(&e);
    free(mem);
    member_rows_free(&rows);
    lar3_free(&c);
    for (int i = 0; i < 3; i++) solid_free(&s[i]);
}

/* The cells selected by an expression tree given as JSON text (compiled by the API's parser). */
static uint8_t *select_json(const lar3 *c, const uint8_t *mem, const char *tree)
{
    json_t *j = json_loads(tree, JSON_DECODE_ANY, NULL);
    bool_expr e;
    api_error err;
    uint8_t *sel = calloc(c->nc + 1, 1);
    if (!j || api_bool_parse(j, c->nsolids, &e, &err) != API_OK) {
        test_fail(__FILE__, __func__, __LINE__, "%s: %s", tree, j ? err.msg : "bad JSON");
        json_decref(j);
        return sel;
    }
    uint8_t stack[64];
    for (size_t k = 0; k < c->nc; k++)
        sel[k] = (uint8_t)bool_expr_eval(&e, mem + k * c->nsolids, stack);
    bool_expr_free(&e);
    json_decref(j);
    return sel;
}

/* Associativity, distributivity and De Morgan's laws, as sets of cells, on random boxes. */
TEST(expression_identities)
{
    static const char *const same[][2] = {
        {"[\"-\",0,[\"+\",1,2]]", "[\"&\",[\"-\",0,1],[\"-\",0,2]]"},
        {"[\"-\",0,1,2]", "[\"-\",0,[\"+\",1,2]]"},
        {"[\"-\",0,[\"&\",1,2]]", "[\"+\",[\"-\",0,1],[\"-\",0,2]]"},
        {"[\"+\",[\"+\",0,1],2]", "[\"+\",0,[\"+\",1,2]]"},
        {"[\"&\",[\"&\",0,1],2]", "[\"&\",0,1,2]"},
        {"[\"^\",[\"^\",0,1],2]", "[\"^\",0,[\"^\",1,2]]"},
        {"[\"&\",0,[\"+\",1,2]]", "[\"+\",[\"&\",0,1],[\"&\",0,2]]"},
        {"[\"^\",0,1]", "[\"-\",[\"+\",0,1],[\"&\",0,1]]"},
    };
    for (uint64_t seed = 1; seed <= 6; seed++) {
        uint64_t st = seed * 7777;
        solid s[3];
        for (int i = 0; i < 3; i++) {
            double p[3], q[3];
            for (int a = 0; a < 3; a++) {
                p[a] = test_rnd(&st);
                q[a] = p[a] + 0.3 + test_rnd(&st);
            }
            s[i] = box(p[0], p[1], p[2], q[0], q[1], q[2]);
        }
        arr3_opts o = {0};
        lar3 c;
        char err[256];
        REQUIRE(!arr3_build(s, 3, 0, &o, &c, err, sizeof err), "%s", err);
        member_rows rows = {0};
        uint8_t *mem = malloc(c.nc * 3 + 1);
        CHECK(lar3_membership_dense(&c, mem, &rows) == 0, "membership");
        for (size_t i = 0; i < sizeof same / sizeof *same; i++) {
            uint8_t *a = select_json(&c, mem, same[i][0]), *b = select_json(&c, mem, same[i][1]);
            CHECK(!memcmp(a, b, c.nc), "seed %llu: %s and %s select different cells",
                  (unsigned long long)seed, same[i][0], same[i][1]);
            free(a);
            free(b);
        }
        free(mem);
        member_rows_free(&rows);
        lar3_free(&c);
        for (int i = 0; i < 3; i++) solid_free(&s[i]);
    }
}
