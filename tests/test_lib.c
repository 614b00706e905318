/* test_lib.c — the library's API (include/cellar.h): every entry point, every error, and the
 * arrays against the JSON the CLI and the daemon give for the same request.
 *
 * Each array of a result is compared, value by value, with the member of the result JSON its
 * name says (the .npz naming: "FV.indptr" / "FV.indices" are the rows of "FV", "holes.face" the
 * faces that key "holes", "operators.d1.data" a member of an object), and every member of the
 * JSON but dim and stats has its arrays: the two outputs are one complex. */
#include "tests/check.h"

#include <jansson.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "api/api.h"
#include "include/cellar.h"

static double elem(const cellar_array *a, size_t i)
{
    switch (a->dtype) {
    case CELLAR_F64:
        return ((const double *)a->data)[i];
    case CELLAR_I32:
        return ((const int32_t *)a->data)[i];
    case CELLAR_U32:
        return ((const uint32_t *)a->data)[i];
    case CELLAR_I8:
        return ((const int8_t *)a->data)[i];
    case CELLAR_U64:
        return (double)((const uint64_t *)a->data)[i];
    }
    return NAN;
}

/* The numbers the JSON value j holds for the array part `part` ("", "indptr", "indices",
 * "face"), flattened into *out (n of them); 0, or -1 when j has no such part. */
static int flatten(const json_t *j, const char *part, double **out, size_t *n)
{
    size_t cap = 64, k;
    json_t *row, *x;
    *n = 0;
    *out = malloc(cap * sizeof **out);
#define PUSH(v)                                                                                    \
    do {                                                                                           \
        if (*n == cap) *out = realloc(*out, (cap *= 2) * sizeof **out);                            \
        (*out)[(*n)++] = (v);                                                                      \
    } while (0)
    if (json_is_number(j) && !*part) {
        PUSH(json_number_value(j));
        return 0;
    }
    if (json_is_array(j)) {
        size_t at = 0;
        if (!strcmp(part, "indptr")) PUSH(0);
        json_array_foreach(j, k, row)
        {
            if (json_is_number(row)) {
                if (*part && strcmp(part, "")) return -1;
                PUSH(json_number_value(row));
                continue;
            }
            size_t i;
            json_array_foreach(row, i, x)
            {
                if (!strcmp(part, "indptr")) continue;
                PUSH(json_number_value(x));
            }
            at += json_array_size(row);
            if (!strcmp(part, "indptr")) PUSH((double)at);
        }
        return 0;
    }
    if (json_is_object(j)) { /* "holes": {"face": [cycles]} in increasing face order */
        const char *key;
        json_t *cycles;
        size_t at = 0;
        if (!strcmp(part, "indptr")) PUSH(0);
        json_object_foreach((json_t *)j, key, cycles)
        {
            json_array_foreach(cycles, k, row)
            {
                size_t i;
                if (!strcmp(part, "face")) PUSH(atof(key));
                if (!strcmp(part, "indices"))
                    json_array_foreach(row, i, x) PUSH(json_number_value(x));
                at += json_array_size(row);
                if (!strcmp(part, "indptr")) PUSH((double)at);
            }
        }
        return 0;
    }
#undef PUSH
    return -1;
}

/* Every array of r equals its member of the JSON text js, and every member of js (but dim and
 * stats) has an array; what differs is reported under label. */
static void same_as_json(const cellar_result *r, const char *js, const char *label)
{
    json_error_t je;
    json_t *root = json_loads(js, 0, &je);
    REQUIRE(root, "%s: the JSON does not parse: %s", label, je.text);
    size_t n = cellar_result_count(r);
    for (size_t i = 0; i < n; i++) {
        const cellar_array *a = cellar_result_array(r, i);
        char name[128];
        snprintf(name, sizeof name, "%s", a->name);
        /* walk the objects as far as they go; the rest names the part */
        const json_t *j = root;
        char *p = name, *dot;
        const char *part = "";
        while (p) {
            dot = strchr(p, '.');
            if (dot) *dot = 0;
            const json_t *next = json_is_object(j) ? json_object_get(j, p) : NULL;
            if (!next) {
                part = p;
                break;
            }
            j = next;
            p = dot ? dot + 1 : NULL;
        }
        double *x;
        size_t nx;
        int rc = flatten(j, part, &x, &nx);
        CHECK(rc == 0, "%s: %s has no member in the JSON", label, a->name);
        CHECK(rc || nx == a->rows * a->cols, "%s: %s has %zu values, the JSON %zu", label, a->name,
              a->rows * a->cols, nx);
        for (size_t k = 0; rc == 0 && k < nx && k < a->rows * a->cols; k++)
            if (elem(a, k) != x[k]) {
                CHECK(0, "%s: %s[%zu] = %.17g, the JSON's %.17g", label, a->name, k, elem(a, k),
                      x[k]);
                break;
            }
        free(x);
    }
    const char *key;
    json_t *v;
    json_object_foreach(root, key, v)
    {
        if (!strcmp(key, "dim") || !strcmp(key, "stats")) continue;
        int found = 0;
        for (size_t i = 0; i < n && !found; i++) {
            const char *nm = cellar_result_array(r, i)->name;
            size_t k = strlen(key);
            found = !strncmp(nm, key, k) && (nm[k] == 0 || nm[k] == '.');
        }
        CHECK(found, "%s: the JSON's %s has no array", label, key);
    }
    json_t *stats = json_object_get(root, "stats");
    json_t *mine = json_loads(cellar_result_json(r), 0, &je);
    CHECK(mine && json_integer_value(json_object_get(mine, "dim")) ==
                      json_integer_value(json_object_get(root, "dim")),
          "%s: dim", label);
    CHECK(!stats || (mine && json_object_get(mine, "stats")), "%s: no stats in %s", label,
          cellar_result_json(r));
    json_decref(mine);
    json_decref(root);
}

static char *run_json(const char *req)
{
    char *out = NULL;
    size_t len;
    cellar_error e;
    int rc = cellar_run_json(req, strlen(req), NULL, &out, &len, &e);
    if (rc) {
        test_fail(__FILE__, __func__, __LINE__, "cellar_run_json: %d %s", rc, e.msg);
        return NULL;
    }
    return out;
}

static const cellar_array *get(const cellar_result *r, const char *name)
{
    const cellar_array *a = cellar_result_get(r, name);
    if (!a) test_fail(__FILE__, __func__, __LINE__, "no array %s", name);
    return a;
}

/* The segments of a square's sides and diagonals (5 vertices, 8 edges, 4 faces). */
static const double square_x[] = {0, 0, 2, 0, 2, 0, 2, 2, 2, 2, 0, 2,
                                  0, 2, 0, 0, 0, 0, 2, 2, 0, 2, 2, 0};

TEST(lines_arrays)
{
    cellar_result *r;
    cellar_error e;
    REQUIRE(cellar_arrangement2d(square_x, 6, NULL, &r, &e) == CELLAR_OK, "%s", e.msg);
    CHECK(cellar_result_dim(r) == 2, "dim %d", cellar_result_dim(r));
    const cellar_array *V = get(r, "V"), *EV = get(r, "EV"), *FV = get(r, "FV.indptr");
    REQUIRE(V && EV && FV, "arrays");
    CHECK(V->rows == 5 && V->cols == 2 && V->dtype == CELLAR_F64, "V %zu x %zu", V->rows, V->cols);
    CHECK(EV->rows == 8 && EV->cols == 2 && EV->dtype == CELLAR_U32, "EV %zu", EV->rows);
    CHECK(FV->rows == 5, "FV rows %zu", FV->rows - 1);
    CHECK(!cellar_result_get(r, "operators.d1.indptr"), "operators without asking");
    CHECK(!cellar_result_get(r, "no such") && !cellar_result_array(r, cellar_result_count(r)),
          "past the end");
    cellar_result_free(r);
    char *js = run_json("{\"kind\":\"lines\",\"lines\":[[[0,0],[2,0]],[[2,0],[2,2]],[[2,2],[0,2]],"
                        "[[0,2],[0,0]],[[0,0],[2,2]],[[0,2],[2,0]]]}");
    REQUIRE(cellar_arrangement2d(square_x, 6, NULL, &r, &e) == CELLAR_OK, "%s", e.msg);
    if (js) same_as_json(r, js, "square");
    cellar_result_free(r);
    cellar_free(js);
}

/* d1 · d2 = 0 on the arrays of a result (2D) or d2 · d3 (3D): the boundary of a boundary. */
/* The array "operators.OP.PART" of r. */
static const cellar_array *op_part(const cellar_result *r, const char *op, const char *part)
{
    char n[64];
    snprintf(n, sizeof n, "operators.%s.%s", op, part);
    return get(r, n);
}

static void boundary_of_boundary(const cellar_result *r, const char *a, const char *b)
{
    const cellar_array *pa = op_part(r, a, "indptr"), *ia = op_part(r, a, "indices"),
                       *da = op_part(r, a, "data"), *sb = op_part(r, b, "shape"),
                       *pb = op_part(r, b, "indptr"), *ib = op_part(r, b, "indices"),
                       *db = op_part(r, b, "data");
    if (!pa || !ia || !da || !sb || !pb || !ib || !db) return;
    size_t rows = pa->rows - 1, cols = (size_t)elem(sb, 1), bad = 0;
    long *acc = calloc(cols + 1, sizeof *acc);
    for (size_t i = 0; i < rows && !bad; i++) {
        memset(acc, 0, (cols + 1) * sizeof *acc);
        for (size_t k = (size_t)elem(pa, i); k < (size_t)elem(pa, i + 1); k++) {
            size_t mid = (size_t)elem(ia, k);
            for (size_t m = (size_t)elem(pb, mid); m < (size_t)elem(pb, mid + 1); m++)
                acc[(size_t)elem(ib, m)] += (long)(elem(da, k) * elem(db, m));
        }
        for (size_t c = 0; c < cols; c++) bad += acc[c] != 0;
    }
    CHECK(!bad, "%s . %s is not 0", a, b);
    free(acc);
}

TEST(lines_options)
{
    cellar_result *r;
    cellar_error e;
    double *seg = test_random_lines(300, 1, 7);
    cellar_options o = {.operators = 1, .threads = 2};
    REQUIRE(cellar_arrangement2d(seg, 300, &o, &r, &e) == CELLAR_OK, "%s", e.msg);
    boundary_of_boundary(r, "d1", "d2");
    /* Euler for a planar graph: V - E + F = 1 + components with the unbounded face; F counts
     * the bounded ones */
    json_t *j = json_loads(cellar_result_json(r), 0, NULL);
    long comp =
        (long)json_integer_value(json_object_get(json_object_get(j, "stats"), "components"));
    json_decref(j);
    long nv = (long)get(r, "V")->rows, ne = (long)get(r, "EV")->rows,
         nf = (long)get(r, "FV.indptr")->rows - 1;
    CHECK(nv - ne + nf == comp, "V %ld - E %ld + F %ld != %ld components", nv, ne, nf, comp);
    /* the same as the JSON request, with its options */
    size_t cap = 300 * 120 + 200, at = 0;
    char *req = malloc(cap);
    at += (size_t)snprintf(req + at, cap - at, "{\"kind\":\"lines\",\"lines\":[");
    for (size_t i = 0; i < 300; i++)
        at += (size_t)snprintf(req + at, cap - at, "%s[[%.17g,%.17g],[%.17g,%.17g]]", i ? "," : "",
                               seg[4 * i], seg[4 * i + 1], seg[4 * i + 2], seg[4 * i + 3]);
    snprintf(req + at, cap - at, "],\"options\":{\"operators\":true}}");
    char *js = run_json(req);
    if (js) same_as_json(r, js, "random lines, operators");
    cellar_free(js);
    cellar_result_free(r);
    /* fields: only those named, and the others' absence */
    o = (cellar_options){.fields = "V, EV,stats", .keep_dangling = 1, .precision = 1.0 / 1024};
    REQUIRE(cellar_arrangement2d(seg, 300, &o, &r, &e) == CELLAR_OK, "%s", e.msg);
    CHECK(cellar_result_count(r) == 2 && get(r, "V") && get(r, "EV"), "fields V, EV: %zu arrays",
          cellar_result_count(r));
    CHECK(strstr(cellar_result_json(r), "\"stats\""), "stats asked: %s", cellar_result_json(r));
    cellar_result_free(r);
    o = (cellar_options){.fields = "V"};
    REQUIRE(cellar_arrangement2d(seg, 300, &o, &r, &e) == CELLAR_OK, "%s", e.msg);
    CHECK(!strstr(cellar_result_json(r), "stats"), "stats not asked: %s", cellar_result_json(r));
    cellar_result_free(r);
    free(req);
    free(seg);
}

TEST(lines_errors)
{
    cellar_result *r = (cellar_result *)1;
    cellar_error e;
    double bad[8] = {0, 0, 1, 1, 0, 1, NAN, 0};
    CHECK(cellar_arrangement2d(bad, 2, NULL, &r, &e) == CELLAR_EINVALID && !r, "NaN");
    CHECK(e.status == 422 && strstr(e.msg, "segments[1][1][0]"), "message: %s", e.msg);
    CHECK(cellar_arrangement2d(NULL, 2, NULL, &r, &e) == CELLAR_EINVALID, "NULL segments");
    CHECK(cellar_arrangement2d(bad, 1, NULL, NULL, &e) == CELLAR_EINVALID, "NULL out");
    cellar_options o = {.precision = -1};
    CHECK(cellar_arrangement2d(bad, 1, &o, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "options.precision"),
          "precision: %s", e.msg);
    o = (cellar_options){.fields = "V,nope"};
    CHECK(cellar_arrangement2d(bad, 1, &o, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "options.fields[1]"),
          "fields: %s", e.msg);
    o = (cellar_options){.fields = "FV"};
    CHECK(cellar_arrangement2d(bad, 1, &o, &r, &e) == CELLAR_EINVALID && strstr(e.msg, "\"V\""),
          "FV without V: %s", e.msg);
    o = (cellar_options){.fill = "odd"};
    CHECK(cellar_arrangement2d(bad, 1, &o, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "options.fill"),
          "fill of lines: %s", e.msg);
    o = (cellar_options){.fields = "membership"};
    CHECK(cellar_arrangement2d(bad, 1, &o, &r, &e) == CELLAR_EINVALID, "membership of lines");
    /* no segments: an empty complex */
    CHECK(cellar_arrangement2d(NULL, 0, NULL, &r, NULL) == CELLAR_OK && r && get(r, "V")->rows == 0,
          "empty");
    cellar_result_free(r);
    cellar_result_free(NULL);
}

/* Two squares [0,2]^2 and [1,3]^2, and a square with a square hole, as rings. */
static const double sq_xy[] = {0, 0, 2, 0, 2, 2, 0, 2, 1, 1, 3, 1, 3, 3, 1, 3,
                               4, 0, 8, 0, 8, 4, 4, 4, 5, 1, 5, 3, 7, 3, 7, 1};
static const uint32_t sq_poly[] = {0, 1, 2, 4}, sq_ring[] = {0, 4, 8, 12, 16};

TEST(polygons_arrays)
{
    static const struct {
        const char *op, *jop;
        double area;
    } ops[] = {{"union", "\"union\"", 7 + 12},
               {"intersection", "\"intersection\"", 0},
               {"[\"+\", 0, 1]", "[\"+\",0,1]", 7},
               {"[\"&\", 0, 1]", "[\"&\",0,1]", 1},
               {"[\"-\", 0, 1]", "[\"-\",0,1]", 3},
               {"xor", "\"xor\"", 6 + 12},
               {"2", "2", 12}};
    for (size_t k = 0; k < sizeof ops / sizeof *ops; k++) {
        cellar_result *r;
        cellar_error e;
        cellar_options o = {.operators = 1};
        REQUIRE(cellar_polygons(3, sq_poly, sq_ring, sq_xy, ops[k].op, &o, &r, &e) == CELLAR_OK,
                "%s: %s", ops[k].op, e.msg);
        const cellar_array *a = get(r, "result.area");
        CHECK(a && a->rows == 1 && elem(a, 0) == ops[k].area, "%s: area %g, expected %g", ops[k].op,
              a ? elem(a, 0) : NAN, ops[k].area);
        boundary_of_boundary(r, "d1", "d2");
        char req[1024];
        snprintf(req, sizeof req,
                 "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[2,0],[2,2],[0,2]]],"
                 "[[[1,1],[3,1],[3,3],[1,3]]],[[[4,0],[8,0],[8,4],[4,4]],[[5,1],[5,3],[7,3],"
                 "[7,1]]]],\"op\":%s,\"options\":{\"operators\":true}}",
                 ops[k].jop);
        char *js = run_json(req);
        if (js) same_as_json(r, js, ops[k].op);
        cellar_free(js);
        cellar_result_free(r);
    }
    /* fields without V: the result has its own V, and the fill rule */
    cellar_result *r;
    cellar_options o = {.fields = "result,membership", .fill = "nonzero"};
    REQUIRE(cellar_polygons(3, sq_poly, sq_ring, sq_xy, "union", &o, &r, NULL) == CELLAR_OK,
            "fields");
    CHECK(!cellar_result_get(r, "V") && get(r, "result.V") && get(r, "membership.indptr"), "own V");
    char *js = run_json("{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[2,0],[2,2],[0,2]]],"
                        "[[[1,1],[3,1],[3,3],[1,3]]],[[[4,0],[8,0],[8,4],[4,4]],[[5,1],[5,3],[7,"
                        "3],[7,1]]]],\"op\":\"union\",\"options\":{\"fields\":[\"result\","
                        "\"membership\"],\"fill\":\"nonzero\"}}");
    if (js) same_as_json(r, js, "fields result, membership");
    cellar_free(js);
    cellar_result_free(r);
}

TEST(polygons_errors)
{
    cellar_result *r;
    cellar_error e;
    double xy[] = {0, 0, 1, 0, 1, 1, 0, INFINITY};
    uint32_t po[] = {0, 1}, ro[] = {0, 4}, ro2[] = {0, 2};
    CHECK(cellar_polygons(1, po, ro, xy, "union", NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "polygons[0] ring 0 point 3"),
          "inf: %s", e.msg);
    xy[7] = 1;
    CHECK(cellar_polygons(1, po, ro2, xy, "union", NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "polygons[0] ring 0"),
          "2 points: %s", e.msg);
    uint32_t po0[] = {0, 0};
    CHECK(cellar_polygons(1, po0, ro, xy, "union", NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "polygons[0]"),
          "no ring: %s", e.msg);
    CHECK(cellar_polygons(1, po, ro, xy, "onion", NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "op"),
          "op: %s", e.msg);
    CHECK(cellar_polygons(1, po, ro, xy, "[\"-\", 0, 3]", NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "op"),
          "op index: %s", e.msg);
    CHECK(cellar_polygons(1, po, ro, xy, "[\"-\", 0,", NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "op"),
          "op JSON: %s", e.msg);
    CHECK(cellar_polygons(1, po, ro, xy, NULL, NULL, &r, &e) == CELLAR_EINVALID, "no op");
    cellar_options o = {.fill = "even"};
    CHECK(cellar_polygons(1, po, ro, xy, "union", &o, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "options.fill"),
          "fill: %s", e.msg);
    CHECK(cellar_polygons(1, NULL, ro, xy, "union", NULL, &r, &e) == CELLAR_EINVALID, "NULL");
    /* a closed ring (last point = first) is taken as open */
    double closed[] = {0, 0, 1, 0, 1, 1, 0, 1, 0, 0};
    uint32_t rc5[] = {0, 5};
    REQUIRE(cellar_polygons(1, po, rc5, closed, "union", NULL, &r, &e) == CELLAR_OK, "%s", e.msg);
    CHECK(elem(get(r, "result.area"), 0) == 1 && get(r, "V")->rows == 4, "closed ring");
    cellar_result_free(r);
}

/* An axis-aligned box [a, b] as 8 vertices and 12 triangles, counter-clockwise seen from
 * outside. */
static void box(double *V, uint32_t *F, const double a[3], const double b[3])
{
    static const uint32_t t[36] = {0, 3, 2, 0, 1, 3, 4, 7, 5, 4, 6, 7, 0, 5, 1, 0, 4, 5,
                                   2, 7, 6, 2, 3, 7, 0, 6, 4, 0, 2, 6, 1, 7, 3, 1, 5, 7};
    for (int i = 0; i < 8; i++) {
        V[3 * i] = i & 4 ? b[0] : a[0];
        V[3 * i + 1] = i & 2 ? b[1] : a[1];
        V[3 * i + 2] = i & 1 ? b[2] : a[2];
    }
    memcpy(F, t, sizeof t);
}

static void put_box_json(char *s, size_t cap, const double *V, const uint32_t *F)
{
    size_t at = (size_t)snprintf(s, cap, "{\"V\":[");
    for (int i = 0; i < 8; i++)
        at += (size_t)snprintf(s + at, cap - at, "%s[%.17g,%.17g,%.17g]", i ? "," : "", V[3 * i],
                               V[3 * i + 1], V[3 * i + 2]);
    at += (size_t)snprintf(s + at, cap - at, "],\"FV\":[");
    for (int f = 0; f < 12; f++)
        at += (size_t)snprintf(s + at, cap - at, "%s[%u,%u,%u]", f ? "," : "", F[3 * f],
                               F[3 * f + 1], F[3 * f + 2]);
    snprintf(s + at, cap - at, "]}");
}

TEST(solids_arrays)
{
    double V[3][24];
    uint32_t F[3][36];
    box(V[0], F[0], (double[]){0, 0, 0}, (double[]){1, 1, 1});
    box(V[1], F[1], (double[]){0.5, 0.5, 0.5}, (double[]){1.5, 1.5, 1.5});
    box(V[2], F[2], (double[]){0.25, 0.25, 1}, (double[]){0.75, 0.75, 2}); /* touching a face */
    cellar_solid s[3];
    for (int i = 0; i < 3; i++) s[i] = (cellar_solid){V[i], 8, F[i], NULL, 12};
    static const struct {
        const char *op, *jop;
        double vol;
    } ops[] = {{"union", "\"union\"", 1 + 1 - 0.125 + 0.25 - 0.03125},
               {"[\"&\", 0, 1]", "[\"&\",0,1]", 0.125},
               {"[\"-\", 0, 1]", "[\"-\",0,1]", 0.875},
               {"[\"-\", 1, [\"+\", 0, 2]]", "[\"-\",1,[\"+\",0,2]]", 0.875 - 0.03125},
               {NULL, NULL, 0}};
    for (size_t k = 0; k < sizeof ops / sizeof *ops; k++) {
        cellar_result *r;
        cellar_error e;
        cellar_options o = {.operators = 1, .threads = 2};
        REQUIRE(cellar_solids(s, 3, ops[k].op, &o, &r, &e) == CELLAR_OK, "%s: %s",
                ops[k].op ? ops[k].op : "no op", e.msg);
        CHECK(cellar_result_dim(r) == 3, "dim");
        if (ops[k].op) {
            const cellar_array *a = get(r, "result.volume");
            CHECK(a && fabs(elem(a, 0) - ops[k].vol) < 1e-12, "%s: volume %.17g, expected %g",
                  ops[k].op, a ? elem(a, 0) : NAN, ops[k].vol);
        } else {
            CHECK(!cellar_result_get(r, "result.volume"), "no op, no result");
        }
        boundary_of_boundary(r, "d1", "d2");
        boundary_of_boundary(r, "d2", "d3");
        char req[8192], b[3][1400];
        for (int i = 0; i < 3; i++) put_box_json(b[i], sizeof b[i], V[i], F[i]);
        snprintf(req, sizeof req,
                 "{\"kind\":\"solids\",\"solids\":[%s,%s,%s]%s%s,\"options\":{\"operators\":"
                 "true}}",
                 b[0], b[1], b[2], ops[k].jop ? ",\"op\":" : "", ops[k].jop ? ops[k].jop : "");
        char *js = run_json(req);
        if (js) same_as_json(r, js, ops[k].op ? ops[k].op : "no op");
        cellar_free(js);
        cellar_result_free(r);
    }
    /* polygon faces through face_off (the two triangles of each side as one quad), a solid
     * turned inside out (warned, turned back), and fields without V */
    uint32_t quads[24], qoff[7];
    for (int f = 0; f < 6; f++) {
        const uint32_t *t = F[0] + 6 * f;
        uint32_t q[4] = {t[0], t[4], t[1], t[2]};
        memcpy(quads + 4 * f, q, sizeof q);
        qoff[f] = (uint32_t)(4 * f);
    }
    qoff[6] = 24;
    uint32_t inv[36];
    for (int f = 0; f < 12; f++)
        inv[3 * f] = F[1][3 * f], inv[3 * f + 1] = F[1][3 * f + 2],
                inv[3 * f + 2] = F[1][3 * f + 1];
    cellar_solid s2[2] = {{V[0], 8, quads, qoff, 6}, {V[1], 8, inv, NULL, 12}};
    cellar_result *r;
    cellar_error e;
    cellar_options o = {.fields = "result,stats"};
    REQUIRE(cellar_solids(s2, 2, "union", &o, &r, &e) == CELLAR_OK, "quads: %s", e.msg);
    CHECK(fabs(elem(get(r, "result.volume"), 0) - 1.875) < 1e-12, "quads: volume");
    CHECK(get(r, "result.V") && !cellar_result_get(r, "V"), "own V");
    CHECK(strstr(cellar_result_json(r), "solids[1]"), "the inside-out solid is warned: %s",
          cellar_result_json(r));
    cellar_result_free(r);
}

TEST(solids_errors)
{
    double V[24];
    uint32_t F[36];
    box(V, F, (double[]){0, 0, 0}, (double[]){1, 1, 1});
    cellar_result *r;
    cellar_error e;
    cellar_solid s = {V, 8, F, NULL, 12};
    F[7] = 8;
    CHECK(cellar_solids(&s, 1, NULL, NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "solids[0].FV[2][1]"),
          "index: %s", e.msg);
    F[7] = 5;
    V[4] = NAN;
    CHECK(cellar_solids(&s, 1, NULL, NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "solids[0].V[1][1]"),
          "NaN: %s", e.msg);
    V[4] = 0;
    cellar_solid open = {V, 8, F, NULL, 11};
    CHECK(cellar_solids(&open, 1, NULL, NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "solids[0]"),
          "open surface: %s", e.msg);
    CHECK(cellar_solids(&s, 1, "[\"-\", 0, 1]", NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "op"),
          "op: %s", e.msg);
    uint32_t off[] = {0, 3, 2};
    cellar_solid back = {V, 8, F, off, 2};
    CHECK(cellar_solids(&back, 1, NULL, NULL, &r, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "face_off"),
          "offsets: %s", e.msg);
    cellar_solid none = {NULL, 8, F, NULL, 12};
    CHECK(cellar_solids(&none, 1, NULL, NULL, &r, &e) == CELLAR_EINVALID, "NULL V");
    cellar_options o = {.fields = "CF"};
    CHECK(cellar_solids(&s, 1, NULL, &o, &r, &e) == CELLAR_EINVALID && strstr(e.msg, "fields"),
          "CF alone: %s", e.msg);
}

/* progress: increasing, ending at 1, named stages; cancel: 499 */
typedef struct watch {
    int calls, backwards, stop_after, asked;
    double last;
    char stage[32];
} watch;

static void on_progress(void *u, const char *stage, double f)
{
    watch *w = u;
    w->calls++;
    if (f < w->last) w->backwards++;
    w->last = f;
    snprintf(w->stage, sizeof w->stage, "%s", stage);
}

static int on_cancel(void *u)
{
    watch *w = u;
    w->asked++;
    return w->stop_after && w->calls >= w->stop_after;
}

TEST(progress_and_cancel)
{
    double *seg = test_random_lines(3000, 1, 11);
    watch w = {0};
    cellar_options o = {.progress = on_progress, .cancel = on_cancel, .udata = &w};
    cellar_result *r;
    cellar_error e;
    REQUIRE(cellar_arrangement2d(seg, 3000, &o, &r, &e) == CELLAR_OK, "%s", e.msg);
    CHECK(w.calls > 3 && !w.backwards && w.last == 1 && !strcmp(w.stage, "output"),
          "progress: %d calls, %d backwards, last %g at %s", w.calls, w.backwards, w.last, w.stage);
    CHECK(w.asked == w.calls, "cancel asked %d times of %d", w.asked, w.calls);
    CHECK(w.calls <= 1000 + 20, "progress told %d times: about a thousand at most", w.calls);
    cellar_result_free(r);
    for (size_t i = 0; cellar_stage_name("lines", i); i++)
        CHECK(i < 20, "stages of lines never end");
    CHECK(!strcmp(cellar_stage_name("solids", 0), "check") && !cellar_stage_name("nope", 0) &&
              !cellar_stage_name(NULL, 0),
          "stage names");
    w = (watch){.stop_after = 2};
    CHECK(cellar_arrangement2d(seg, 3000, &o, &r, &e) == CELLAR_ECANCELED && !r && e.status == 499,
          "canceled: %d %s", e.status, e.msg);
    free(seg);
    /* the same on solids */
    double V[24];
    uint32_t F[36];
    box(V, F, (double[]){0, 0, 0}, (double[]){1, 1, 1});
    cellar_solid s = {V, 8, F, NULL, 12};
    w = (watch){.stop_after = 1};
    CHECK(cellar_solids(&s, 1, "union", &o, &r, &e) == CELLAR_ECANCELED, "solids canceled: %s",
          e.msg);
}

TEST(run_json_entry)
{
    char *out;
    size_t len;
    cellar_error e;
    const char *req = "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]],[[0,1],[1,0]]]}";
    REQUIRE(cellar_run_json(req, strlen(req), NULL, &out, &len, &e) == CELLAR_OK, "%s", e.msg);
    CHECK(len == strlen(out) && out[len - 1] == '\n' && !strncmp(out, "{\"dim\":2", 8), "%s", out);
    cellar_free(out);
    CHECK(cellar_run_json("{", 1, NULL, &out, &len, &e) == CELLAR_EJSON && !out, "bad JSON");
    CHECK(cellar_run_json("{\"kind\":\"x\"}", 12, NULL, &out, &len, &e) == CELLAR_EINVALID &&
              strstr(e.msg, "kind"),
          "kind: %s", e.msg);
    CHECK(cellar_run_json(NULL, 0, NULL, &out, &len, &e) == CELLAR_EJSON, "NULL body");
    char v[32];
    snprintf(v, sizeof v, "%d.%d.%d", CELLAR_VERSION_MAJOR, CELLAR_VERSION_MINOR,
             CELLAR_VERSION_PATCH);
    CHECK(!strcmp(cellar_version(), API_VERSION) && !strcmp(v, API_VERSION),
          "version %s, the header's %s, the service's %s", cellar_version(), v, API_VERSION);
}

/* Many calls at once on threads of the caller's: each gets its own, equal, result. */
static void *one_call(void *arg)
{
    double *area = arg;
    cellar_result *r;
    if (cellar_polygons(3, sq_poly, sq_ring, sq_xy, "union", NULL, &r, NULL) != CELLAR_OK)
        return NULL;
    *area = elem(cellar_result_get(r, "result.area"), 0);
    cellar_result_free(r);
    return NULL;
}

TEST(threads)
{
    pthread_t t[8];
    double area[8] = {0};
    for (int i = 0; i < 8; i++) pthread_create(&t[i], NULL, one_call, &area[i]);
    for (int i = 0; i < 8; i++) pthread_join(t[i], NULL);
    for (int i = 0; i < 8; i++) CHECK(area[i] == 19, "thread %d: area %g", i, area[i]);
}
