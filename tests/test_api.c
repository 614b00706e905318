/* test_api.c — the JSON layer: every error path with its status and JSON path, results parsed
 * back with jansson and checked against hand-computed complexes, the CSR operators (d1·d2 = 0
 * from the CSR arrays alone), exterior_last, field subsets, number formatting. */
#include "api/api.h"
#include "api/render.h"
#include "api/api_int.h"
#include "tests/check.h"

#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define SQUARE           "[[[0,0],[1,0]],[[1,0],[1,1]],[[1,1],[0,1]],[[0,1],[0,0]]]"
#define SQUARE_REQ(opts) "{\"kind\":\"lines\",\"lines\":" SQUARE ",\"options\":" opts "}"

/* Runs body; on success returns the parsed result (caller decrefs), else NULL with a failure. */
static json_t *run_ok_(const char *body, int threads, const char *func, int line)
{
    char *out = NULL;
    size_t outlen = 0;
    api_error err;
    json_error_t je;
    json_t *r;
    int rc = api_run_json(body, strlen(body), threads, &out, &outlen, &err);
    if (rc != API_OK) {
        test_fail(__FILE__, func, line, "api_run_json: %d %s", rc, err.msg);
        return NULL;
    }
    if (!out || outlen != strlen(out) || outlen < 2 || out[outlen - 1] != '\n' ||
        memchr(out, '\n', outlen - 1)) {
        test_fail(__FILE__, func, line, "result is not one line ending with a newline");
        free(out);
        return NULL;
    }
    r = json_loadb(out, outlen, 0, &je);
    if (!json_is_object(r)) test_fail(__FILE__, func, line, "result is not JSON: %s", je.text);
    free(out);
    return r;
}
#define run_ok(body) run_ok_(body, 1, __func__, __LINE__)

/* json integer at a[i] (or a[i][j] with j >= 0), -999999 when absent */
static long long iat(const json_t *a, size_t i, long j)
{
    const json_t *v = json_array_get(a, i);
    if (j >= 0) v = json_array_get(v, (size_t)j);
    return json_is_integer(v) ? (long long)json_integer_value(v) : -999999;
}

/* ---- error paths ------------------------------------------------------------------------- */

typedef struct err_case {
    const char *body;
    int status;
    const char *prefix; /* the message starts with this */
} err_case;

static const err_case err_cases[] = {
    {"", 400, "malformed JSON: empty body"},
    {"  \n\t", 400, "malformed JSON: empty body"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1,0]]", 400, "malformed JSON at line 1, column 38"},
    {"{\"kind\":\"lines\",\n\"lines\":[[[0,0],[1,0]]]", 400, "malformed JSON at line 2, column"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[NaN,0]]]}", 400, "malformed JSON at line 1"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[Infinity,0]]]}", 400, "malformed JSON at line 1"},
    {"{\"kind\":\"lines\",\"lines\":[] } x", 400, "malformed JSON at line 1"},
    {"{\"kind\":\"l\xff\"}", 400, "malformed JSON"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1e400,0]]]}", 422, "lines[0][1][0]: "},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1,0]],[[0,0],[1,-1e400]]]}", 422, "lines[1][1][1]: "},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1,123456789012345678901234]]]}", 422,
     "lines[0][1][1]: "},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"precision\":1e999}}", 422,
     "options.precision: "},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"operators\":true,\"operators\":false}}", 422,
     "options: duplicate object key"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1,0,3]]]}", 422,
     "lines[0][1]: expected 2 finite numbers"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1,0]],[[0,0],[1]]]}", 422,
     "lines[1][1]: expected 2 finite numbers"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],5]]}", 422, "lines[0][1]: expected 2 finite numbers"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0]]]}", 422, "lines[0]: expected 2 points"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1],[2,2]]]}", 422, "lines[0]: expected 2 points"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]],7]}", 422, "lines[1]: expected 2 points"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[\"1\",0]]]}", 422,
     "lines[0][1][0]: expected a finite number"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,null],[1,0]]]}", 422,
     "lines[0][0][1]: expected a finite number"},
    {"{\"kind\":\"lines\",\"lines\":[[[0,0],[1,true]]]}", 422,
     "lines[0][1][1]: expected a finite number"},
    {"{\"kind\":\"lines\",\"lines\":{}}", 422, "lines: expected an array of segments"},
    {"{\"kind\":\"lines\",\"lines\":\"0 0 1 1\"}", 422, "lines: expected an array of segments"},
    {"{\"kind\":\"lines\"}", 422, "lines: required"},
    {"{\"lines\":[]}", 422, "kind: required, expected \"lines\""},
    {"{\"kind\":\"mesh\",\"lines\":[]}", 422,
     "kind: expected \"lines\", \"svg\", \"solids\" or \"polygons\""},
    {"{\"kind\":5,\"lines\":[]}", 422, "kind: expected \"lines\""},
    {"[1,2]", 422, "request: expected an object"},
    {"\"lines\"", 422, "request: expected an object"},
    {"{\"kind\":\"lines\",\"lines\":[],\"extra\":1}", 422, "extra: unknown key"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"foo\":1}}", 422,
     "options.foo: unknown option"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":[]}", 422, "options: expected an object"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":null}", 422, "options: expected an object"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"precision\":0}}", 422,
     "options.precision: expected a number > 0"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"precision\":-0.5}}", 422,
     "options.precision: expected a number > 0"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"precision\":\"1e-3\"}}", 422,
     "options.precision: expected a number > 0"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"keep_dangling\":1}}", 422,
     "options.keep_dangling: expected true or false"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"exterior_last\":\"yes\"}}", 422,
     "options.exterior_last: expected true or false"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"operators\":null}}", 422,
     "options.operators: expected true or false"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"fields\":[\"V\",\"X\"]}}", 422,
     "options.fields[1]: expected one of \"V\""},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"fields\":[\"V\",3]}}", 422,
     "options.fields[1]: expected one of"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"fields\":\"V\"}}", 422,
     "options.fields: expected an array"},
    {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"union\","
     "\"options\":{\"fill\":\"even\"}}",
     422, "options.fill: expected \"odd\", \"nonzero\" or \"positive\""},
    {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"union\","
     "\"options\":{\"fill\":1}}",
     422, "options.fill: expected"},
    {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"union\","
     "\"options\":{\"foo\":1}}",
     422,
     "options.foo: unknown option (expected precision, keep_dangling, exterior_last, "
     "operators, fields or fill)"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"fill\":\"odd\"}}", 422,
     "options.fill: unknown option"},
    {"{\"kind\":\"lines\",\"lines\":[],\"options\":{\"fields\":[\"result\"]}}", 422,
     "options.fields: \"membership\" and \"result\" are fields of a \"polygons\" request"},
    {"{\"kind\":\"svg\",\"svg\":\"<svg xmlns='http://www.w3.org/2000/svg'/>\","
     "\"options\":{\"fields\":[\"V\",\"membership\"]}}",
     422, "options.fields: \"membership\" and \"result\" are fields of a \"polygons\" request"},
    /* layers (issue 28) */
    {"{\"type\":\"FeatureCollection\",\"features\":[]}", 422,
     "kind: required: this is GeoJSON (a FeatureCollection), not a request"},
    {"{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"FeatureCollection\",\"features\":[]}],"
     "\"op\":\"union\"}",
     422, "polygons[0].type: a FeatureCollection is a layer, not one polygon"},
    {"{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"layers\":{\"a\":[]},"
     "\"op\":\"union\"}",
     422, "layers: give either \"polygons\" or \"layers\""},
    {"{\"kind\":\"polygons\",\"layers\":[],\"op\":\"union\"}", 422, "layers: expected an object"},
    {"{\"kind\":\"polygons\",\"layers\":{\"a\":[]},\"op\":\"union\"}", 422,
     "layers.a: expected a non-empty array of polygons"},
    {"{\"kind\":\"polygons\",\"layers\":{\"a\":[[[[0,0],[1,0],[0,1]]]],\"b\":[[[[0,0],[1,0]]]]},"
     "\"op\":\"union\"}",
     422, "layers.b[0][0]: expected a ring of at least 3 points"},
    {"{\"kind\":\"polygons\",\"layers\":{\"a\":[[[[0,0],[1,0],[0,1]]]]},\"op\":[\"+\",\"a\",\"z\"]"
     "}",
     422, "op[2]: \"z\" is not a layer (the layers: \"a\")"},
    {"{\"kind\":\"polygons\",\"layers\":{\"a\":[[[[0,0],[1,0],[0,1]]]]},\"op\":\"unite\"}", 422,
     "op: expected \"union\", \"intersection\", \"difference\", \"xor\" (over the layers)"},
    {"{\"kind\":\"polygons\",\"layers\":{\"\":[[[[0,0],[1,0],[0,1]]]]},\"op\":\"union\"}", 422,
     "layers: a layer's name must have 1 to 100 bytes"},
    {"{\"kind\":\"solids\",\"layers\":{\"a\":[]},\"op\":\"union\"}", 422,
     "layers.a: expected a solid or a non-empty array of solids"},
    {"{\"kind\":\"solids\",\"layers\":{\"a\":{\"V\":[[0,0,0]],\"FV\":[[0,1,2]]}},\"op\":\"union\"}",
     422, "layers.a.FV[0][1]: expected a vertex index"},
    {"{\"kind\":\"solids\",\"solids\":[],\"layers\":{}}", 422, "layers: give one of \"solids\""},
};

TEST(parse_errors_have_status_and_path)
{
    for (size_t i = 0; i < sizeof err_cases / sizeof err_cases[0]; i++) {
        const err_case *c = &err_cases[i];
        char *out = (char *)1, *canon = (char *)1;
        size_t outlen = 7;
        api_error err = {0};
        int rc = api_run_json(c->body, strlen(c->body), 1, &out, &outlen, &err);
        CHECK(rc == c->status && err.status == c->status, "case %zu %s: status %d, want %d (%s)", i,
              c->body, rc, c->status, err.msg);
        CHECK(strncmp(err.msg, c->prefix, strlen(c->prefix)) == 0,
              "case %zu %s: message \"%s\", want prefix \"%s\"", i, c->body, err.msg, c->prefix);
        CHECK(out == NULL && outlen == 0, "case %zu: output not cleared on failure", i);
        /* validation alone gives the same answer */
        memset(&err, 0, sizeof err);
        rc = api_check_json(c->body, strlen(c->body), &canon, NULL, &err);
        CHECK(rc == c->status && strncmp(err.msg, c->prefix, strlen(c->prefix)) == 0,
              "case %zu: api_check_json gives %d \"%s\"", i, rc, err.msg);
        CHECK(canon == NULL, "case %zu: canon not cleared", i);
        for (const char *p = err.msg; *p; p++)
            CHECK(*p >= 0x20 && *p < 0x7f, "case %zu: unprintable byte in message", i);
    }
}

/* Nesting far beyond jansson's limit (2048 in 2.14) is an error value, not a stack overflow. */
TEST(deep_nesting_is_an_error)
{
    size_t depth = 100000, n = 2 * depth + 64;
    char *body = malloc(n), *out = NULL;
    size_t outlen, len;
    api_error err;
    int rc;
    REQUIRE(body, "malloc");
    /* bare arrays */
    memset(body, '[', depth);
    memset(body + depth, ']', depth);
    rc = api_run_json(body, 2 * depth, 1, &out, &outlen, &err);
    CHECK(rc == 400 && strstr(err.msg, "maximum parsing depth"), "bare: %d %s", rc, err.msg);
    /* inside the lines of a real request, unterminated */
    len = (size_t)snprintf(body, n, "{\"kind\":\"lines\",\"lines\":");
    memset(body + len, '[', depth);
    len += depth;
    rc = api_run_json(body, len, 1, &out, &outlen, &err);
    CHECK(rc == 400 && strstr(err.msg, "maximum parsing depth") &&
              strstr(err.msg, "line 1, column"),
          "in lines: %d %s", rc, err.msg);
    /* nested objects */
    len = 0;
    for (size_t i = 0; i < 10000; i++) memcpy(body + len, "{\"a\":", 5), len += 5;
    rc = api_check_json(body, len, NULL, NULL, &err);
    CHECK(rc == 400 && strstr(err.msg, "maximum parsing depth"), "objects: %d %s", rc, err.msg);
    CHECK(out == NULL, "output set on failure");
    free(body);
}

/* The path named for an out-of-range number deep in a nested, multi-line body. */
TEST(overflow_path_in_nested_body)
{
    const char *body = "{\"kind\": \"lines\",\n \"lines\": [[[0, 0], [1, 1]],\n"
                       "  [[2, 2], [3, 3]], [[4, 4], [5, \"]\"]], [[6, 6], [7, 1e400]]]}";
    api_error err;
    int rc = api_check_json(body, strlen(body), NULL, NULL, &err);
    CHECK(rc == 422 && strncmp(err.msg, "lines[3][1][1]: ", 16) == 0 && strstr(err.msg, "line 3"),
          "%d %s", rc, err.msg);
    body = "{\"kind\":\"lines\",\"lines\":[],\"options\":{\"fields\":[\"V\"],\"na\\\"me\":-1e400}}";
    rc = api_check_json(body, strlen(body), NULL, NULL, &err);
    CHECK(rc == 422 && strncmp(err.msg, "options.na\\\"me: ", 16) == 0, "%d %s", rc, err.msg);
}

TEST(core_errors_map_to_statuses)
{
    api_error err;
    CHECK(api_core_fail(&err, ARR_EINVAL, "bad") == 422 && err.status == 422 &&
              strcmp(err.msg, "bad") == 0,
          "EINVAL: %d %s", err.status, err.msg);
    CHECK(api_core_fail(&err, ARR_ELIMIT, "too wide") == 422 && strcmp(err.msg, "too wide") == 0,
          "ELIMIT: %s", err.msg);
    CHECK(api_core_fail(&err, ARR_ENOMEM, "") == 503 && strcmp(err.msg, "out of memory") == 0,
          "ENOMEM: %s", err.msg);
    CHECK(api_core_fail(&err, ARR_ECANCELED, NULL) == API_ECANCELED, "ECANCELED");
    CHECK(api_core_fail(&err, ARR_EINTERNAL, "x") == 500 && strstr(err.msg, "internal error"),
          "EINTERNAL: %s", err.msg);
    CHECK(api_core_fail(&err, 77, "x") == 500, "unknown code");
    /* a real limit of the core: extent / precision beyond 2^ARR2_GRID_BITS */
    const char *body = "{\"kind\":\"lines\",\"lines\":[[[0,0],[1000,1000]]],"
                       "\"options\":{\"precision\":1e-12}}";
    char *out = NULL;
    size_t outlen;
    int rc = api_run_json(body, strlen(body), 1, &out, &outlen, &err);
    CHECK(rc == 422 && out == NULL && *err.msg, "precision too fine: %d %s", rc, err.msg);
}

TEST(cancel_before_start)
{
    atomic_int cancel = 1;
    api_run_opts ro = {.threads = 2, .cancel = &cancel};
    char body[1 << 16], *out = NULL;
    size_t len = 0, outlen;
    api_error err;
    int rc;
    len += (size_t)snprintf(body + len, sizeof body - len, "{\"kind\":\"lines\",\"lines\":[");
    for (int i = 0; i < 200; i++)
        len += (size_t)snprintf(body + len, sizeof body - len,
                                "%s[[0,%d],[199,%d]],[[%d,0],[%d,199]]", i ? "," : "", i, i, i, i);
    len += (size_t)snprintf(body + len, sizeof body - len, "]}");
    rc = api_run_json_ex(body, len, &ro, &out, &outlen, &err);
    CHECK(rc == API_ECANCELED && err.status == API_ECANCELED && out == NULL, "%d %s", rc, err.msg);
    cancel = 0;
    rc = api_run_json_ex(body, len, &ro, &out, &outlen, &err);
    CHECK(rc == API_OK && out && strstr(out, "\"F\":39601,"), "uncanceled: %d %s", rc, err.msg);
    free(out);
}

/* ---- results ----------------------------------------------------------------------------- */

/* Signed area of the cycle of vertex ids cyc (a JSON array) over V. */
static double cycle_area(const json_t *V, const json_t *cyc)
{
    double a = 0;
    size_t k = json_array_size(cyc);
    for (size_t i = 0; i < k; i++) {
        const json_t *p = json_array_get(V, (size_t)iat(cyc, i, -1));
        const json_t *q = json_array_get(V, (size_t)iat(cyc, (i + 1) % k, -1));
        a += json_number_value(json_array_get(p, 0)) * json_number_value(json_array_get(q, 1)) -
             json_number_value(json_array_get(q, 0)) * json_number_value(json_array_get(p, 1));
    }
    return a / 2;
}

/* Checks that the signed edges fe (JSON array) are exactly the walk of the cycle cyc over EV:
 * ±(e+1) with e = {a,b}, + when a < b (EV rows are [v0 < v1]). */
static int fe_matches_walk(const json_t *EV, const json_t *cyc, const json_t *fe)
{
    size_t k = json_array_size(cyc);
    if (json_array_size(fe) != k) return 0;
    for (size_t i = 0; i < k; i++) {
        long long a = iat(cyc, i, -1), b = iat(cyc, (i + 1) % k, -1), want = 0;
        for (size_t e = 0; e < json_array_size(EV); e++)
            if ((iat(EV, e, 0) == a && iat(EV, e, 1) == b) ||
                (iat(EV, e, 0) == b && iat(EV, e, 1) == a))
                want = a < b ? (long long)e + 1 : -(long long)e - 1;
        int found = 0;
        for (size_t j = 0; j < k; j++) found |= iat(fe, j, -1) == want;
        if (!want || !found) return 0;
    }
    return 1;
}

typedef struct csr {
    long long rows, cols;
    size_t nnz;
    long long *indptr, *indices, *data;
} csr;

/* Reads {"shape","indptr","indices","data"} checking the CSR structure; 0 on success. */
static int csr_read(const json_t *m, csr *c, char *why, size_t n)
{
    const json_t *shape = json_object_get(m, "shape"), *ip = json_object_get(m, "indptr"),
                 *ix = json_object_get(m, "indices"), *d = json_object_get(m, "data");
    memset(c, 0, sizeof *c);
    if (json_object_size(m) != 4 || json_array_size(shape) != 2 || !json_is_array(ip) ||
        !json_is_array(ix) || !json_is_array(d))
        return snprintf(why, n, "not a CSR object"), -1;
    c->rows = iat(shape, 0, -1), c->cols = iat(shape, 1, -1);
    c->nnz = json_array_size(ix);
    if ((long long)json_array_size(ip) != c->rows + 1 || json_array_size(d) != c->nnz)
        return snprintf(why, n, "bad lengths"), -1;
    c->indptr = calloc((size_t)c->rows + 1, sizeof *c->indptr);
    c->indices = calloc(c->nnz + 1, sizeof *c->indices);
    c->data = calloc(c->nnz + 1, sizeof *c->data);
    for (long long r = 0; r <= c->rows; r++) c->indptr[r] = iat(ip, (size_t)r, -1);
    for (size_t k = 0; k < c->nnz; k++) {
        c->indices[k] = iat(ix, k, -1);
        c->data[k] = iat(d, k, -1);
        if (c->indices[k] < 0 || c->indices[k] >= c->cols || (c->data[k] != 1 && c->data[k] != -1))
            return snprintf(why, n, "entry %zu out of range", k), -1;
    }
    if (c->indptr[0] != 0 || c->indptr[c->rows] != (long long)c->nnz)
        return snprintf(why, n, "indptr ends"), -1;
    for (long long r = 0; r < c->rows; r++) {
        if (c->indptr[r] > c->indptr[r + 1]) return snprintf(why, n, "indptr decreases"), -1;
        for (long long k = c->indptr[r] + 1; k < c->indptr[r + 1]; k++)
            if (c->indices[k - 1] >= c->indices[k])
                return snprintf(why, n, "row %lld indices unsorted", r), -1;
    }
    return 0;
}

static void csr_free(csr *c)
{
    free(c->indptr);
    free(c->indices);
    free(c->data);
}

/* Entry (r, col) of a CSR matrix. */
static long long csr_at(const csr *c, long long r, long long col)
{
    for (long long k = c->indptr[r]; k < c->indptr[r + 1]; k++)
        if (c->indices[k] == col) return c->data[k];
    return 0;
}

/* Checks d1 against EV, d2 against FE, and d1·d2 = 0, from the CSR arrays alone. */
static void check_operators(const json_t *r, const char *what)
{
    const json_t *ops = json_object_get(r, "operators"), *EV = json_object_get(r, "EV"),
                 *FE = json_object_get(r, "FE"), *V = json_object_get(r, "V");
    csr d1, d2;
    char why[128];
    long long nv = (long long)json_array_size(V), ne = (long long)json_array_size(EV),
              nf = (long long)json_array_size(FE);
    if (!json_is_object(ops)) {
        test_fail(__FILE__, __func__, __LINE__, "%s: no operators", what);
        return;
    }
    if (csr_read(json_object_get(ops, "d1"), &d1, why, sizeof why) != 0 ||
        csr_read(json_object_get(ops, "d2"), &d2, why, sizeof why) != 0) {
        test_fail(__FILE__, __func__, __LINE__, "%s: %s", what, why);
        goto out;
    }
    CHECK(d1.rows == nv && d1.cols == ne && d2.rows == ne && d2.cols == nf,
          "%s: shapes %lldx%lld %lldx%lld for V=%lld E=%lld F=%lld", what, d1.rows, d1.cols,
          d2.rows, d2.cols, nv, ne, nf);
    if (test_failed_now()) goto out;
    CHECK(d1.nnz == 2 * (size_t)ne, "%s: d1 has %zu entries", what, d1.nnz);
    for (long long e = 0; e < ne; e++) {
        long long v0 = iat(EV, (size_t)e, 0), v1 = iat(EV, (size_t)e, 1);
        CHECK(csr_at(&d1, v0, e) == -1 && csr_at(&d1, v1, e) == 1, "%s: d1 column %lld", what, e);
    }
    size_t fe_total = 0;
    for (long long f = 0; f < nf; f++) {
        const json_t *row = json_array_get(FE, (size_t)f);
        fe_total += json_array_size(row);
        for (size_t k = 0; k < json_array_size(row); k++) {
            long long s = iat(row, k, -1), e = llabs(s) - 1;
            CHECK(csr_at(&d2, e, f) == (s > 0 ? 1 : -1), "%s: d2[%lld][%lld]", what, e, f);
        }
    }
    CHECK(d2.nnz == fe_total, "%s: d2 has %zu entries, FE %zu", what, d2.nnz, fe_total);
    /* (d1·d2)[v][f] = sum over e of d1[v][e] d2[e][f], from the rows of d1 and of d2 */
    long long *acc = calloc((size_t)nf + 1, sizeof *acc);
    for (long long v = 0; acc && v < nv; v++) {
        memset(acc, 0, ((size_t)nf + 1) * sizeof *acc);
        for (long long k = d1.indptr[v]; k < d1.indptr[v + 1]; k++) {
            long long e = d1.indices[k];
            for (long long j = d2.indptr[e]; j < d2.indptr[e + 1]; j++)
                acc[d2.indices[j]] += d1.data[k] * d2.data[j];
        }
        for (long long f = 0; f < nf; f++)
            CHECK(acc[f] == 0, "%s: (d1 d2)[%lld][%lld] = %lld", what, v, f, acc[f]);
    }
    free(acc);
out:
    csr_free(&d1);
    csr_free(&d2);
}

static const char *const keys_all[] = {"dim", "V", "EV", "FV", "FE", "holes", "exterior", "stats"};

TEST(unit_square_round_trip)
{
    json_t *r = run_ok(SQUARE_REQ("{}"));
    REQUIRE(r, "no result");
    const json_t *V = json_object_get(r, "V"), *EV = json_object_get(r, "EV"),
                 *FV = json_object_get(r, "FV"), *FE = json_object_get(r, "FE"),
                 *ext = json_object_get(r, "exterior"), *st = json_object_get(r, "stats");
    CHECK(json_object_size(r) == 8, "%zu keys", json_object_size(r));
    for (size_t i = 0; i < 8; i++) CHECK(json_object_get(r, keys_all[i]), "no %s", keys_all[i]);
    CHECK(json_is_integer(json_object_get(r, "dim")) &&
              json_integer_value(json_object_get(r, "dim")) == 2,
          "dim");
    /* V sorted by x then y */
    static const double wantV[4][2] = {{0, 0}, {0, 1}, {1, 0}, {1, 1}};
    REQUIRE(json_array_size(V) == 4, "%zu vertices", json_array_size(V));
    for (size_t v = 0; v < 4; v++)
        for (size_t k = 0; k < 2; k++)
            CHECK(json_number_value(json_array_get(json_array_get(V, v), k)) == wantV[v][k],
                  "V[%zu][%zu]", v, k);
    static const long long wantEV[4][2] = {{0, 1}, {0, 2}, {1, 3}, {2, 3}};
    REQUIRE(json_array_size(EV) == 4, "%zu edges", json_array_size(EV));
    for (size_t e = 0; e < 4; e++)
        CHECK(iat(EV, e, 0) == wantEV[e][0] && iat(EV, e, 1) == wantEV[e][1], "EV[%zu]", e);
    /* one face: a counter-clockwise rotation of 0 -> 2 -> 3 -> 1 */
    REQUIRE(json_array_size(FV) == 1 && json_array_size(FE) == 1, "%zu faces", json_array_size(FV));
    const json_t *f0 = json_array_get(FV, 0);
    static const long long ccw[4] = {0, 2, 3, 1};
    size_t start = 0;
    while (start < 4 && ccw[start] != iat(f0, 0, -1)) start++;
    REQUIRE(json_array_size(f0) == 4 && start < 4, "FV[0] has %zu vertices", json_array_size(f0));
    for (size_t i = 0; i < 4; i++)
        CHECK(iat(f0, i, -1) == ccw[(start + i) % 4], "FV[0][%zu] = %lld", i, iat(f0, i, -1));
    CHECK(cycle_area(V, f0) == 1, "face area %g", cycle_area(V, f0));
    /* FE: walking 0->2 is +(1+1), 2->3 +(3+1), 3->1 -(2+1), 1->0 -(0+1) */
    const json_t *fe0 = json_array_get(FE, 0);
    CHECK(fe_matches_walk(EV, f0, fe0), "FE[0] does not match the walk of FV[0]");
    long long sum = 0, prod = 1;
    for (size_t i = 0; i < json_array_size(fe0); i++)
        sum += iat(fe0, i, -1), prod *= iat(fe0, i, -1);
    CHECK(sum == 2 + 4 - 3 - 1 && prod == 2 * 4 * 3 * 1, "FE[0] sum %lld prod %lld", sum, prod);
    /* exterior: the same square, clockwise; no holes */
    REQUIRE(json_array_size(ext) == 1, "%zu exterior cycles", json_array_size(ext));
    CHECK(cycle_area(V, json_array_get(ext, 0)) == -1, "exterior area");
    CHECK(json_is_object(json_object_get(r, "holes")) &&
              json_object_size(json_object_get(r, "holes")) == 0,
          "holes");
    /* stats */
    static const char *const ones[] = {"F", "components", "blocks"};
    for (size_t i = 0; i < 3; i++)
        CHECK(json_integer_value(json_object_get(st, ones[i])) == 1, "stats.%s", ones[i]);
    CHECK(json_integer_value(json_object_get(st, "V")) == 4 &&
              json_integer_value(json_object_get(st, "E")) == 4 &&
              json_integer_value(json_object_get(st, "input_segments")) == 4 &&
              json_integer_value(json_object_get(st, "zero_length_dropped")) == 0 &&
              json_number_value(json_object_get(st, "precision")) > 0,
          "stats counts");
    const json_t *ms = json_object_get(st, "ms");
    CHECK(json_object_size(st) == 14 && json_object_size(ms) == 9 &&
              json_is_number(json_object_get(ms, "total")),
          "stats keys %zu ms keys %zu", json_object_size(st), json_object_size(ms));
    json_decref(r);
}

TEST(operators_csr)
{
    json_t *r = run_ok(SQUARE_REQ("{\"operators\":true}"));
    REQUIRE(r, "no result");
    CHECK(json_object_size(r) == 9, "%zu keys", json_object_size(r));
    check_operators(r, "square");
    /* exact arrays for the square: d1 rows are vertices */
    json_t *d1 = json_object_get(json_object_get(r, "operators"), "d1");
    char *s = json_dumps(json_object_get(d1, "indptr"), JSON_COMPACT);
    CHECK(s && strcmp(s, "[0,2,4,6,8]") == 0, "d1.indptr %s", s);
    free(s);
    s = json_dumps(json_object_get(d1, "data"), JSON_COMPACT);
    CHECK(s && strcmp(s, "[-1,-1,1,-1,1,-1,1,1]") == 0, "d1.data %s", s);
    free(s);
    json_decref(r);

    /* a grid with a hole-free interior and a square with a hole */
    r = run_ok("{\"kind\":\"lines\",\"lines\":[[[0,0],[3,0]],[[0,1],[3,1]],[[0,2],[3,2]],"
               "[[0,3],[3,3]],[[0,0],[0,3]],[[1,0],[1,3]],[[2,0],[2,3]],[[3,0],[3,3]]],"
               "\"options\":{\"operators\":true}}");
    REQUIRE(r, "no grid result");
    CHECK(json_array_size(json_object_get(r, "FE")) == 9, "grid faces");
    check_operators(r, "grid");
    json_decref(r);
}

TEST(exterior_last_appends_exterior_rows)
{
    json_t *plain = run_ok(SQUARE_REQ("{}"));
    json_t *r = run_ok(SQUARE_REQ("{\"exterior_last\":true,\"operators\":true}"));
    REQUIRE(r && plain, "no result");
    const json_t *V = json_object_get(r, "V"), *EV = json_object_get(r, "EV"),
                 *FV = json_object_get(r, "FV"), *FE = json_object_get(r, "FE"),
                 *ext = json_object_get(r, "exterior");
    REQUIRE(json_array_size(FV) == 2 && json_array_size(FE) == 2, "rows: FV %zu FE %zu",
            json_array_size(FV), json_array_size(FE));
    CHECK(json_equal(json_array_get(FV, 0), json_array_get(json_object_get(plain, "FV"), 0)) &&
              json_equal(json_array_get(FE, 0), json_array_get(json_object_get(plain, "FE"), 0)),
          "first rows changed");
    CHECK(json_equal(json_array_get(FV, 1), json_array_get(ext, 0)), "FV's last row");
    CHECK(cycle_area(V, json_array_get(FV, 1)) == -1, "exterior row not clockwise");
    CHECK(fe_matches_walk(EV, json_array_get(FV, 1), json_array_get(FE, 1)),
          "exterior FE row does not match its walk");
    /* each edge once with each sign over the two rows */
    for (long long e = 1; e <= 4; e++) {
        int plus = 0, minus = 0;
        for (size_t f = 0; f < 2; f++)
            for (size_t k = 0; k < json_array_size(json_array_get(FE, f)); k++) {
                long long s = iat(json_array_get(FE, f), k, -1);
                plus += s == e, minus += s == -e;
            }
        CHECK(plus == 1 && minus == 1, "edge %lld: %d +, %d -", e, plus, minus);
    }
    check_operators(r, "exterior_last");
    json_decref(r);
    json_decref(plain);

    /* a dangling edge kept with keep_dangling is walked both ways by the exterior: it cancels */
    r = run_ok("{\"kind\":\"lines\",\"lines\":[[[0,0],[1,0]],[[1,0],[1,1]],[[1,1],[0,1]],"
               "[[0,1],[0,0]],[[1,1],[2,2]]],\"options\":{\"keep_dangling\":true,"
               "\"exterior_last\":true,\"operators\":true}}");
    REQUIRE(r, "no dangling result");
    FE = json_object_get(r, "FE");
    CHECK(json_array_size(json_object_get(r, "EV")) == 5 && json_array_size(FE) == 2,
          "dangling: E %zu rows %zu", json_array_size(json_object_get(r, "EV")),
          json_array_size(FE));
    CHECK(json_array_size(json_array_get(FE, 1)) == 4, "exterior FE row has %zu edges",
          json_array_size(json_array_get(FE, 1)));
    check_operators(r, "dangling");
    json_decref(r);
}

TEST(holes_keyed_by_face)
{
    json_t *r = run_ok("{\"kind\":\"lines\",\"lines\":[[[0,0],[10,0]],[[10,0],[10,10]],"
                       "[[10,10],[0,10]],[[0,10],[0,0]],[[3,3],[7,3]],[[7,3],[7,7]],[[7,7],"
                       "[3,7]],[[3,7],[3,3]]],\"options\":{\"operators\":true}}");
    REQUIRE(r, "no result");
    const json_t *V = json_object_get(r, "V"), *FV = json_object_get(r, "FV"),
                 *holes = json_object_get(r, "holes");
    REQUIRE(json_array_size(FV) == 2, "%zu faces", json_array_size(FV));
    size_t outer = cycle_area(V, json_array_get(FV, 0)) == 100 ? 0 : 1;
    char key[8];
    snprintf(key, sizeof key, "%zu", outer);
    CHECK(cycle_area(V, json_array_get(FV, outer)) == 100 &&
              cycle_area(V, json_array_get(FV, 1 - outer)) == 16,
          "face areas");
    REQUIRE(json_object_size(holes) == 1 && json_object_get(holes, key), "holes keyed %s", key);
    const json_t *h = json_object_get(holes, key);
    CHECK(json_array_size(h) == 1 && cycle_area(V, json_array_get(h, 0)) == -16,
          "hole cycle clockwise of area 16");
    CHECK(json_array_size(json_array_get(json_object_get(r, "FE"), outer)) == 8,
          "FE of the face with a hole has outer and hole edges");
    CHECK(json_array_size(json_object_get(r, "exterior")) == 1, "one exterior cycle");
    check_operators(r, "hole");
    json_decref(r);
}

TEST(fields_subset)
{
    static const struct {
        const char *opts;
        const char *keys[6];
    } cases[] = {
        {"{\"fields\":[\"V\",\"stats\"]}", {"dim", "V", "stats"}},
        {"{\"fields\":[]}", {"dim"}},
        {"{\"fields\":[\"operators\"]}", {"dim", "operators"}},
        {"{\"fields\":[\"FE\",\"EV\",\"V\"],\"operators\":true}",
         {"dim", "V", "EV", "FE", "operators"}},
        {"{\"fields\":[\"holes\",\"exterior\",\"holes\",\"V\",\"FV\"]}",
         {"dim", "V", "FV", "holes", "exterior"}},
        {"{\"fields\":[\"holes\",\"V\",\"FE\",\"EV\"]}", {"dim", "V", "EV", "FE", "holes"}},
        {"{\"fields\":[\"V\",\"EV\",\"FV\"],\"exterior_last\":true}", {"dim", "V", "EV", "FV"}},
    };
    char body[512];
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        size_t n = 0;
        snprintf(body, sizeof body, "{\"kind\":\"lines\",\"lines\":" SQUARE ",\"options\":%s}",
                 cases[i].opts);
        json_t *r = run_ok(body);
        if (!r) continue;
        while (n < 6 && cases[i].keys[n]) {
            CHECK(json_object_get(r, cases[i].keys[n]), "%s: no %s", cases[i].opts,
                  cases[i].keys[n]);
            n++;
        }
        CHECK(json_object_size(r) == n, "%s: %zu keys, want %zu", cases[i].opts,
              json_object_size(r), n);
        json_decref(r);
    }
    /* exterior_last without FE still adds the exterior row to FV */
    json_t *r = run_ok(SQUARE_REQ("{\"fields\":[\"FV\",\"V\"],\"exterior_last\":true}"));
    CHECK(r && json_array_size(json_object_get(r, "FV")) == 2, "FV rows with exterior_last");
    json_decref(r);
}

TEST(empty_and_degenerate_inputs)
{
    json_t *r = run_ok("{\"kind\":\"lines\",\"lines\":[],\"options\":{\"operators\":true}}");
    REQUIRE(r, "empty request failed");
    static const char *const empty_arrays[] = {"V", "EV", "FV", "FE", "exterior"};
    for (size_t i = 0; i < 5; i++)
        CHECK(json_is_array(json_object_get(r, empty_arrays[i])) &&
                  json_array_size(json_object_get(r, empty_arrays[i])) == 0,
              "%s not empty", empty_arrays[i]);
    CHECK(json_integer_value(json_object_get(json_object_get(r, "stats"), "F")) == 0, "F");
    const json_t *d1 = json_object_get(json_object_get(r, "operators"), "d1");
    char *s = json_dumps(d1, JSON_COMPACT | JSON_SORT_KEYS);
    CHECK(s && strcmp(s, "{\"data\":[],\"indices\":[],\"indptr\":[0],\"shape\":[0,0]}") == 0,
          "empty d1 %s", s);
    free(s);
    json_decref(r);
    /* only zero-length segments, integers and reals mixed */
    r = run_ok("{\"kind\":\"lines\",\"lines\":[[[1,1],[1.0,1]],[[2.5,-3],[2.5,-3e0]]]}");
    REQUIRE(r, "degenerate request failed");
    const json_t *st = json_object_get(r, "stats");
    CHECK(json_integer_value(json_object_get(st, "input_segments")) == 2 &&
              json_integer_value(json_object_get(st, "zero_length_dropped")) == 2 &&
              json_array_size(json_object_get(r, "EV")) == 0,
          "zero-length segments");
    json_decref(r);
}

/* Threads change timings only: the complex is the same bytes. */
TEST(threads_give_identical_results)
{
    char *body = malloc(1 << 20), *a = NULL, *b = NULL;
    size_t len = 0, alen, blen;
    api_error err;
    uint64_t x = 12345;
    REQUIRE(body, "malloc");
    len += (size_t)snprintf(body, 1 << 20,
                            "{\"kind\":\"lines\",\"options\":{\"fields\":"
                            "[\"V\",\"EV\",\"FV\",\"FE\",\"holes\",\"exterior\","
                            "\"operators\"]},\"lines\":[");
    for (int i = 0; i < 400; i++) {
        double c[4];
        for (int k = 0; k < 4; k++) {
            x = x * 6364136223846793005u + 1442695040888963407u;
            c[k] = (double)(x >> 11) * 0x1.0p-53;
        }
        len += (size_t)snprintf(body + len, (1 << 20) - len, "%s[[%.17g,%.17g],[%.17g,%.17g]]",
                                i ? "," : "", c[0], c[1], c[0] + (c[2] - .5) / 3,
                                c[1] + (c[3] - .5) / 3);
    }
    len += (size_t)snprintf(body + len, (1 << 20) - len, "]}");
    int ra = api_run_json(body, len, 1, &a, &alen, &err);
    int rb = api_run_json(body, len, 4, &b, &blen, &err);
    CHECK(ra == API_OK && rb == API_OK, "%d %d %s", ra, rb, err.msg);
    CHECK(a && b && alen == blen && memcmp(a, b, alen) == 0, "1 and 4 threads differ");
    if (a) {
        json_t *r = json_loadb(a, alen, 0, NULL);
        CHECK(r && json_array_size(json_object_get(r, "FV")) > 10, "too few faces");
        if (r) check_operators(r, "random");
        json_decref(r);
    }
    free(a);
    free(b);
    free(body);
}

TEST(check_json_canonical)
{
    const char *body = "{ \"options\": {\"keep_dangling\": true, \"fields\": [\"V\"]},\n"
                       "  \"lines\": [[[0, 0.5], [1, 2]]], \"kind\": \"lines\" }";
    char *canon = NULL;
    size_t n = 0;
    api_error err;
    int rc = api_check_json(body, strlen(body), &canon, &n, &err);
    CHECK(rc == API_OK && canon &&
              strcmp(canon, "{\"kind\":\"lines\",\"lines\":[[[0,0.5],[1,2]]],\"options\":"
                            "{\"fields\":[\"V\"],\"keep_dangling\":true}}") == 0 &&
              n == strlen(canon),
          "%d %s", rc, canon ? canon : err.msg);
    free(canon);
    CHECK(api_kind_count() == 4 && strcmp(api_kind_name(0), "lines") == 0 &&
              strcmp(api_kind_name(1), "svg") == 0 && strcmp(api_kind_name(2), "solids") == 0 &&
              strcmp(api_kind_name(3), "polygons") == 0 && api_kind_name(4) == NULL,
          "kinds");
}

/* A polygons request's fields may name "result" alone: the answer is {"dim", "result"}, the
 * result with a V of its own (the vertices its cycles use) that its FV and holes index; its
 * polygons, coordinate for coordinate, and its area are those of the full answer.  Named with
 * V, it indexes the complex's V; "membership" alone gives the membership alone. */
TEST(polygons_fields_result_alone)
{
    const char *base = "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[10,0],[10,10],[0,10]],"
                       "[[4,4],[7,4],[7,7],[4,7]]],[[[1,1],[3,1],[3,3],[1,3]]],"
                       "[[[8,-1],[12,-1],[12,12],[8,12]]]],\"op\":[\"-\",0,[\"+\",1,2]]";
    char body[1024];
    snprintf(body, sizeof body, "%s}", base);
    json_t *full = run_ok(body);
    snprintf(body, sizeof body, "%s,\"options\":{\"fields\":[\"result\"]}}", base);
    json_t *alone = run_ok(body);
    snprintf(body, sizeof body, "%s,\"options\":{\"fields\":[\"membership\"]}}", base);
    json_t *mem = run_ok(body);
    REQUIRE(full && alone && mem, "runs");
    CHECK(json_object_size(alone) == 2 && json_object_get(alone, "dim") &&
              json_object_get(alone, "result"),
          "fields [result]: keys other than dim and result");
    CHECK(json_object_size(mem) == 2 && json_object_get(mem, "membership"),
          "fields [membership]: keys other than dim and membership");
    json_t *fr = json_object_get(full, "result"), *ar = json_object_get(alone, "result");
    json_t *fv = json_object_get(full, "V"), *av = json_object_get(ar, "V");
    REQUIRE(json_is_array(av) && json_is_array(fv), "V missing");
    CHECK(!json_object_get(ar, "cells") && !json_object_get(ar, "FE"),
          "cells or FE without the complex's FV and EV");
    CHECK(json_number_value(json_object_get(ar, "area")) ==
                  json_number_value(json_object_get(fr, "area")) &&
              json_number_value(json_object_get(ar, "area")) == 100 - 9 - 4 - 20,
          "area %g", json_number_value(json_object_get(ar, "area")));
    /* every cycle, coordinate for coordinate; each vertex of the own V used */
    size_t nav = json_array_size(av), used = 0;
    char *seen = calloc(nav + 1, 1);
    for (int part = 0; part < 2; part++) {
        json_t *fa = part ? json_object_get(fr, "holes") : json_object_get(fr, "FV");
        json_t *aa = part ? json_object_get(ar, "holes") : json_object_get(ar, "FV");
        REQUIRE(fa && aa, "part %d missing", part);
        json_t *frows = json_array(), *arows = json_array();
        if (part) {
            const char *key;
            json_t *v;
            json_object_foreach(fa, key, v) json_array_extend(frows, v);
            json_object_foreach(aa, key, v) json_array_extend(arows, v);
            CHECK(json_object_size(fa) == json_object_size(aa), "holes keys differ");
        } else {
            json_array_extend(frows, fa);
            json_array_extend(arows, aa);
        }
        CHECK(json_array_size(frows) == json_array_size(arows), "part %d: cycles differ", part);
        for (size_t c = 0; c < json_array_size(frows) && c < json_array_size(arows); c++) {
            json_t *x = json_array_get(frows, c), *y = json_array_get(arows, c);
            CHECK(json_array_size(x) == json_array_size(y), "cycle %zu length", c);
            for (size_t k = 0; k < json_array_size(x) && k < json_array_size(y); k++) {
                size_t i = (size_t)json_integer_value(json_array_get(x, k));
                size_t j = (size_t)json_integer_value(json_array_get(y, k));
                REQUIRE(j < nav, "own index %zu of %zu", j, nav);
                used += !seen[j], seen[j] = 1;
                CHECK(json_equal(json_array_get(fv, i), json_array_get(av, j)),
                      "cycle %zu vertex %zu: another point", c, k);
            }
        }
        json_decref(frows);
        json_decref(arows);
    }
    CHECK(used == nav, "own V has %zu vertices, the cycles use %zu", nav, used);
    CHECK(json_array_size(json_object_get(json_object_get(ar, "holes"), "0")) == 2,
          "the square's hole and the small square's are not its two holes");
    free(seen);
    json_decref(full);
    json_decref(alone);
    json_decref(mem);
}

/* Layers (issue 28): an op over layer names is the op over the layers' unions; the result
 * carries the layers with their features' properties and the pieces (the result cut where the
 * inputs change), whose rows are the inputs each piece lies in; with fields ["result"] the
 * pieces index the result's own V. */
TEST(polygons_layers_pieces)
{
    const char *base =
        "{\"kind\":\"polygons\",\"layers\":{\"p\":{\"type\":\"FeatureCollection\","
        "\"features\":[{\"type\":\"Feature\",\"properties\":{\"n\":\"west\"},"
        "\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[2,0],[2,2],[0,2],[0,0]]]}},"
        "{\"type\":\"Feature\",\"properties\":null,\"geometry\":{\"type\":\"Polygon\","
        "\"coordinates\":[[[2,0],[4,0],[4,2],[2,2],[2,0]]]}}]},"
        "\"z\":[[[[1,1],[3,1],[3,3],[1,3]]],[[[1,-1],[5,-1],[5,0.5],[1,0.5]]]]},\"op\":";
    char body[2048];
    snprintf(body, sizeof body, "%s[\"&\",\"p\",\"z\"]}", base);
    json_t *r = run_ok(body);
    snprintf(body, sizeof body, "%s\"intersection\"}", base);
    json_t *named = run_ok(body);
    snprintf(body, sizeof body, "%s\"difference\",\"options\":{\"fields\":[\"result\"]}}", base);
    json_t *diff = run_ok(body);
    REQUIRE(r && named && diff, "runs");
    json_t *res = json_object_get(r, "result");
    CHECK(json_number_value(json_object_get(res, "area")) == 2 + 1.5, "p & z: area %g, want 3.5",
          json_number_value(json_object_get(res, "area")));
    CHECK(json_equal(json_object_get(r, "result"), json_object_get(named, "result")),
          "\"intersection\" over the layers differs from [\"&\", \"p\", \"z\"]");
    json_t *ly = json_object_get(r, "layers");
    CHECK(json_array_size(ly) == 2 &&
              !strcmp(json_string_value(json_object_get(json_array_get(ly, 1), "name")), "z") &&
              json_integer_value(json_object_get(json_array_get(ly, 1), "first")) == 2 &&
              json_integer_value(json_object_get(json_array_get(ly, 1), "count")) == 2,
          "layers: %s", json_dumps(ly, JSON_COMPACT));
    json_t *pp = json_object_get(json_array_get(ly, 0), "properties");
    CHECK(json_array_size(pp) == 2 &&
              !strcmp(json_string_value(json_object_get(json_array_get(pp, 0), "n")), "west") &&
              json_is_null(json_array_get(pp, 1)),
          "the properties of layer p");
    /* pieces: p0 & z0 (1), p1 & z0 (1), p0 & z1 (0.5), p1 & z1 (1): four rows */
    json_t *pc = json_object_get(res, "pieces"), *in = json_object_get(pc, "inputs");
    json_t *ip = json_object_get(in, "indptr"), *ix = json_object_get(in, "indices");
    CHECK(json_array_size(ip) == 5 && json_array_size(ix) == 8, "pieces: %zu rows, %zu inputs",
          json_array_size(ip) - 1, json_array_size(ix));
    int seen[4] = {0};
    for (size_t k = 0; k + 1 < json_array_size(ip); k++) {
        json_int_t a = json_integer_value(json_array_get(ip, k));
        json_int_t p = json_integer_value(json_array_get(ix, (size_t)a));
        json_int_t z = json_integer_value(json_array_get(ix, (size_t)a + 1));
        CHECK(p < 2 && z >= 2 && z < 4, "piece %zu lies in %lld and %lld", k, (long long)p,
              (long long)z);
        if (p < 2 && z >= 2 && z < 4) seen[p * 2 + (z - 2)]++;
    }
    CHECK(seen[0] == 1 && seen[1] == 1 && seen[2] == 1 && seen[3] == 1,
          "each pair of parents once: %d %d %d %d", seen[0], seen[1], seen[2], seen[3]);
    CHECK(json_array_size(json_object_get(pc, "FV")) == 4 &&
              json_array_size(json_object_get(pc, "piece")) == 4,
          "four piece polygons");
    /* difference with fields [result]: the pieces index the own V */
    json_t *dr = json_object_get(diff, "result"), *dv = json_object_get(dr, "V");
    json_t *dfv = json_object_get(json_object_get(dr, "pieces"), "FV");
    REQUIRE(json_is_array(dv) && json_is_array(dfv), "own V and pieces");
    double area = 0;
    for (size_t q = 0; q < json_array_size(dfv); q++) {
        json_t *row = json_array_get(dfv, q);
        for (size_t i = 0; i < json_array_size(row); i++) {
            size_t a = (size_t)json_integer_value(json_array_get(row, i));
            size_t b =
                (size_t)json_integer_value(json_array_get(row, (i + 1) % json_array_size(row)));
            REQUIRE(a < json_array_size(dv) && b < json_array_size(dv), "an index beyond V");
            json_t *pa = json_array_get(dv, a), *pb = json_array_get(dv, b);
            area +=
                json_number_value(json_array_get(pa, 0)) *
                    json_number_value(json_array_get(pb, 1)) -
                json_number_value(json_array_get(pb, 0)) * json_number_value(json_array_get(pa, 1));
        }
    }
    CHECK(area / 2 == 8 - 3.5, "p - z: pieces of area %g, want 4.5", area / 2);
    json_decref(r);
    json_decref(named);
    json_decref(diff);
}

/* The GeoJSON of a layers result read defensively: a result whose pieces or layers do not
 * agree with it is a 422 naming the key, never a crash; the good one gives a Feature per piece
 * with its parents' properties. */
TEST(layers_geojson_checked)
{
    const char *req = "{\"kind\":\"polygons\",\"layers\":{\"a\":[{\"type\":\"Feature\","
                      "\"properties\":{\"k\":\"x\"},\"geometry\":{\"type\":\"Polygon\","
                      "\"coordinates\":[[[0,0],[2,0],[2,2],[0,2],[0,0]]]}}],\"b\":[[[[1,1],[3,1],"
                      "[3,3],[1,3]]]]},\"op\":\"union\"}";
    char *out = NULL, *map = NULL;
    size_t outlen = 0, maplen = 0;
    api_error err = {0};
    REQUIRE(api_run_json(req, strlen(req), 1, &out, &outlen, &err) == API_OK, "%s", err.msg);
    REQUIRE(render_geojson(out, outlen, NULL, &map, &maplen, &err) == API_OK, "%s", err.msg);
    json_t *m = json_loadb(map, maplen, 0, NULL);
    json_t *fs = json_object_get(m, "features");
    /* a alone, a & b, b alone */
    CHECK(json_array_size(fs) == 3, "%zu features", json_array_size(fs));
    int both = 0;
    for (size_t i = 0; i < json_array_size(fs); i++) {
        json_t *p = json_object_get(json_array_get(fs, i), "properties");
        if (json_is_integer(json_object_get(p, "a")) && json_is_integer(json_object_get(p, "b"))) {
            both++;
            CHECK(!strcmp(json_string_value(json_object_get(p, "a.k")) ?: "", "x") &&
                      json_number_value(json_object_get(p, "area")) == 1,
                  "the piece in both: %s", json_dumps(p, JSON_COMPACT));
        }
    }
    CHECK(both == 1, "%d pieces in both", both);
    json_decref(m);
    free(map);
    static const struct {
        const char *after, *from, *to, *msg;
    } bad[] = {
        {"\"pieces\"", "\"piece\":[0", "\"piece\":[9", "result.pieces.piece[0]: expected a piece"},
        {"\"layers\"", "\"first\":1", "\"first\":2", "layers[1]: expected {\"name\", \"first\": 1"},
        {"\"pieces\"", "\"indices\":[0", "\"indices\":[5",
         "result.pieces.inputs.indices[0]: expected an input"},
        {"\"result\"", "\"pieces\":{\"FV\"", "\"pieces\":{\"GV\"", "result.pieces: required with"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        const char *from = strstr(out, bad[k].after);
        const char *at = from ? strstr(from, bad[k].from) : NULL;
        REQUIRE(at, "case %zu: %s not in the result", k, bad[k].from);
        size_t n = outlen + strlen(bad[k].to) + 1, a = (size_t)(at - out);
        char *t = malloc(n);
        snprintf(t, n, "%.*s%s%s", (int)a, out, bad[k].to, at + strlen(bad[k].from));
        err = (api_error){0};
        int rc = render_geojson(t, strlen(t), NULL, &map, &maplen, &err);
        CHECK(rc == API_EINVALID && strstr(err.msg, bad[k].msg) && !map,
              "case %zu: %d \"%s\", want 422 \"%s\"", k, rc, err.msg, bad[k].msg);
        free(t);
    }
    free(out);
}

/* Solids in named groups: the op over names, the result's "layers". */
TEST(solids_layers)
{
    const char *cube = "{\"V\":[[%d,0,0],[%d,0,0],[%d,2,0],[%d,2,0],[%d,0,2],[%d,0,2],[%d,2,2],"
                       "[%d,2,2]],\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],"
                       "[3,0,4,7]]}";
    char c0[512], c1[512], c2[512], body[2048];
    snprintf(c0, sizeof c0, cube, 0, 2, 2, 0, 0, 2, 2, 0);
    snprintf(c1, sizeof c1, cube, 3, 5, 5, 3, 3, 5, 5, 3);
    snprintf(c2, sizeof c2, cube, 1, 4, 4, 1, 1, 4, 4, 1);
    snprintf(body, sizeof body,
             "{\"kind\":\"solids\",\"layers\":{\"ab\":[%s,%s],\"c\":%s},\"op\":[\"-\",\"c\","
             "\"ab\"],\"options\":{\"fields\":[\"stats\",\"result\"]}}",
             c0, c1, c2);
    json_t *r = run_ok(body);
    REQUIRE(r, "runs");
    double v = json_number_value(json_object_get(json_object_get(r, "result"), "volume"));
    CHECK(fabs(v - (12 - 4 - 4)) < 1e-9, "c - ab: volume %g, want 4", v);
    json_t *ly = json_object_get(r, "layers");
    CHECK(json_array_size(ly) == 2 &&
              json_integer_value(json_object_get(json_array_get(ly, 1), "first")) == 2 &&
              json_integer_value(json_object_get(json_array_get(ly, 0), "count")) == 2,
          "layers");
    json_decref(r);
}

/* ---- numbers ----------------------------------------------------------------------------- */

TEST(double_format_known_values)
{
    static const struct {
        double x;
        const char *s;
    } cases[] = {
        {0, "0"},
        {-0.0, "0"},
        {1, "1"},
        {-42, "-42"},
        {0.1, "0.1"},
        {0.3, "0.3"},
        {1.0 / 3, "0.3333333333333333"},
        {2.0 / 3, "0.6666666666666666"},
        {0.1 + 0.2, "0.30000000000000004"},
        {1e-7, "1e-07"},
        {1.5e-5, "1.5e-05"},
        {123456789012345.5, "123456789012345.5"},
        {999999999999999.9, "999999999999999.9"},
        {1e15, "1e+15"},
        {1e300, "1e+300"},
        {5e-324, "4.94065645841247e-324"},
        {0x1p-20, "9.5367431640625e-07"},
        {0.5, "0.5"},
        {-1.25, "-1.25"},
        {1.7976931348623157e308, "1.7976931348623157e+308"},
    };
    char buf[API_DOUBLE_MAX];
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        size_t n = api_format_double(cases[i].x, buf);
        CHECK(n == strlen(buf) && strcmp(buf, cases[i].s) == 0, "%.17g: \"%s\", want \"%s\"",
              cases[i].x, buf, cases[i].s);
        CHECK(strtod(buf, NULL) == cases[i].x, "%s does not read back", buf);
    }
}

/* The shortest of %.15g, %.16g, %.17g that reads back as x (integers below 1e15 as such): what
 * api_format_double must print, byte for byte, fast path or not. */
static size_t double_ref(double x, char *buf)
{
    if (fabs(x) < 1e15 && x == (double)(int64_t)x)
        return (size_t)snprintf(buf, 64, "%lld", (long long)(int64_t)x);
    for (int prec = 15;; prec++) {
        int n = snprintf(buf, 64, "%.*g", prec, x);
        if (prec == 17 || strtod(buf, NULL) == x) return (size_t)n;
    }
}

/* api_format_double against that reference: random bit patterns, numbers of the fast path's
 * range (1e-6 .. 1e15) with random mantissas, short decimals and their neighbours, decimals of
 * 16 and 17 digits ending in 5 (ties at the 15th and 16th digit), powers of two (the path left
 * to printf) and their neighbours, the range's ends; each also negated. */
TEST(double_format_is_the_shortest_printf)
{
    uint64_t st = 1129;
    size_t n = test_stress(300000), bad = 0;
    char a[64], b[64];
    for (size_t i = 0; i < n && bad < 5; i++) {
        double x;
        uint64_t r = (uint64_t)(test_rnd(&st) * 18446744073709551616.0);
        switch (i % 7) {
        case 0:
            memcpy(&x, &r, sizeof x);
            if (!isfinite(x)) x = 0.75;
            break;
        case 1:
            x = ldexp(1 + test_rnd(&st), (int)(test_rnd(&st) * 72) - 21);
            break;
        case 2:
            x = floor(test_rnd(&st) * 1e6) * pow(10, (int)(test_rnd(&st) * 22) - 13);
            break;
        case 3:
            x = floor(test_rnd(&st) * 1e5) * pow(10, (int)(test_rnd(&st) * 18) - 11);
            x = nextafter(x, test_rnd(&st) < 0.5 ? INFINITY : 0);
            break;
        case 4: {
            char s[64];
            snprintf(s, sizeof s, "%llu5e%d", (unsigned long long)(r % 10000000000000000u),
                     (int)(test_rnd(&st) * 30) - 26);
            x = strtod(s, NULL);
            break;
        }
        case 5:
            x = ldexp(1, (int)(test_rnd(&st) * 90) - 40);
            if (test_rnd(&st) < 0.7) x = nextafter(x, test_rnd(&st) < 0.5 ? INFINITY : 0);
            break;
        default: {
            static const double ends[] = {1e-6,       1e15, 999999999999999.9,  1e-7, 9.999999e-7,
                                          1e14 + 0.5, 0.1,  0.30000000000000004};
            x = ends[r % (sizeof ends / sizeof ends[0])];
            if (r >> 32 & 1) x = nextafter(x, r >> 33 & 1 ? INFINITY : 0);
        }
        }
        if (r >> 63) x = -x;
        size_t la = api_format_double(x, a), lb = double_ref(x, b);
        if (la != lb || strcmp(a, b) != 0 || strlen(a) != la) {
            bad++;
            CHECK(0, "%a: \"%s\", want \"%s\"", x, a, b);
        }
    }
}

/* The submit-time check (api_check_json, what the daemon runs before queueing) reads an SVG
 * drawing, so a malformed one is refused at once with its line and column. */
TEST(check_reads_svg_drawings)
{
    api_error err;
    char *canon = NULL;
    const char *bad = "{\"kind\":\"svg\",\"svg\":\"<svg xmlns='http://www.w3.org/2000/svg'>\\n"
                      "<line x1='0' y1='0' x2='1' y2='1'>\\n</svg>\"}";
    int rc = api_check_json(bad, strlen(bad), &canon, NULL, &err);
    CHECK(rc == 422, "malformed drawing: status %d, want 422", rc);
    CHECK(strstr(err.msg, "svg: line") != NULL, "message '%s' names no line", err.msg);
    CHECK(canon == NULL, "canonical form given for a refused request");
    const char *good = "{\"kind\":\"svg\",\"svg\":\"<svg xmlns='http://www.w3.org/2000/svg'>"
                       "<rect x='0' y='0' width='2' height='1'/></svg>\"}";
    rc = api_check_json(good, strlen(good), &canon, NULL, &err);
    CHECK(rc == 0 && canon != NULL, "good drawing refused: %d %s", rc, err.msg);
    free(canon);
    const char *notsvg = "{\"kind\":\"svg\",\"svg\":\"<html></html>\"}";
    CHECK(api_check_json(notsvg, strlen(notsvg), NULL, NULL, &err) == 422, "html accepted");
}

/* ---- progress ------------------------------------------------------------------------------ */

/* What a run told its progress callback: the stages in the order first told, the fractions. */
typedef struct prog_rec {
    const char *kind;
    char seen[16][16];
    int nseen, calls, back, unknown, out_of_order, inside[16];
    double last, first_f[16];
    char last_stage[16];
} prog_rec;

static int stage_index(const char *kind, const char *stage)
{
    for (size_t i = 0; api_stage_name(kind, i); i++)
        if (!strcmp(api_stage_name(kind, i), stage)) return (int)i;
    return -1;
}

static void prog_rec_cb(void *udata, const char *stage, double f)
{
    prog_rec *p = udata;
    int i = stage_index(p->kind, stage);
    p->calls++;
    if (i < 0) {
        p->unknown++;
        return;
    }
    if (!(f >= p->last) || f > 1) p->back++;
    if (p->nseen && strcmp(p->seen[p->nseen - 1], stage)) {
        if (i < stage_index(p->kind, p->seen[p->nseen - 1])) p->out_of_order++;
    }
    if (!p->nseen || strcmp(p->seen[p->nseen - 1], stage)) {
        if (p->nseen < 16) {
            snprintf(p->seen[p->nseen], sizeof p->seen[0], "%s", stage);
            p->first_f[i] = f;
            p->nseen++;
        }
    } else if (f > p->first_f[i]) {
        p->inside[i]++; /* a report within the stage, past its start */
    }
    p->last = f;
    snprintf(p->last_stage, sizeof p->last_stage, "%s", stage);
}

/* xorshift for the generated requests */
static double prog_rand(uint64_t *s)
{
    *s ^= *s << 13, *s ^= *s >> 7, *s ^= *s << 17;
    return (double)(*s >> 11) / 9007199254740992.0;
}

/* A request of each kind, large enough for reports inside its long stages. */
static char *progress_request(const char *kind)
{
    size_t cap = 4 << 20, w = 0;
    char *b = malloc(cap);
    uint64_t s = 88172645463325252ull;
    if (!b) return NULL;
#define P(...) (w += (size_t)snprintf(b + w, cap - w, __VA_ARGS__))
    if (!strcmp(kind, "lines")) {
        P("{\"kind\":\"lines\",\"options\":{\"fields\":[\"V\",\"FV\",\"stats\"]},\"lines\":[");
        for (int i = 0; i < 6000; i++) {
            double x = prog_rand(&s) * 100, y = prog_rand(&s) * 100;
            P("%s[[%.6f,%.6f],[%.6f,%.6f]]", i ? "," : "", x, y, x + prog_rand(&s) * 8 - 4,
              y + prog_rand(&s) * 8 - 4);
        }
        P("]}");
    } else if (!strcmp(kind, "svg")) {
        P("{\"kind\":\"svg\",\"svg\":\"<svg xmlns='http://www.w3.org/2000/svg'>");
        for (int i = 0; i < 4000; i++) {
            double x = prog_rand(&s) * 100, y = prog_rand(&s) * 100;
            if (i % 10)
                P("<line x1='%.4f' y1='%.4f' x2='%.4f' y2='%.4f'/>", x, y,
                  x + prog_rand(&s) * 8 - 4, y + prog_rand(&s) * 8 - 4);
            else
                P("<circle cx='%.3f' cy='%.3f' r='%.3f'/>", x, y, 0.5 + prog_rand(&s) * 2);
        }
        P("</svg>\"}");
    } else if (!strcmp(kind, "polygons")) {
        P("{\"kind\":\"polygons\",\"op\":\"union\",\"polygons\":[");
        for (int i = 0; i < 3000; i++) {
            double x = prog_rand(&s) * 40, y = prog_rand(&s) * 40, t = prog_rand(&s) * 1.5;
            double c = cos(t) / 2, n = sin(t) / 2;
            P("%s[[[%.6f,%.6f],[%.6f,%.6f],[%.6f,%.6f],[%.6f,%.6f]]]", i ? "," : "", x - c + n,
              y - n - c, x + c + n, y + n - c, x + c - n, y + n + c, x - c - n, y - n + c);
        }
        P("]}");
    } else { /* solids: 60 overlapping boxes, their union */
        P("{\"kind\":\"solids\",\"op\":\"union\",\"solids\":[");
        for (int i = 0; i < 60; i++) {
            double x0 = prog_rand(&s) * 4, y0 = prog_rand(&s) * 4, z0 = prog_rand(&s) * 4;
            double x1 = x0 + 0.5 + prog_rand(&s), y1 = y0 + 0.5 + prog_rand(&s),
                   z1 = z0 + 0.5 + prog_rand(&s);
            P("%s{\"V\":[[%.5f,%.5f,%.5f],[%.5f,%.5f,%.5f],[%.5f,%.5f,%.5f],[%.5f,%.5f,%.5f],"
              "[%.5f,%.5f,%.5f],[%.5f,%.5f,%.5f],[%.5f,%.5f,%.5f],[%.5f,%.5f,%.5f]],"
              "\"FV\":[[0,4,6,2],[1,3,7,5],[0,1,5,4],[2,6,7,3],[0,2,3,1],[4,5,7,6]]}",
              i ? "," : "", x0, y0, z0, x1, y0, z0, x0, y1, z0, x1, y1, z0, x0, y0, z1, x1, y0, z1,
              x0, y1, z1, x1, y1, z1);
        }
        P("]}");
    }
#undef P
    return b;
}

/* Every kind reports each of its documented stages (api_stage_name) in order, fractions of
 * the whole run that never go back and end at 1 in "output", and reports inside its long
 * stages, not only at their ends. */
TEST(progress_every_kind)
{
    static const struct {
        const char *kind;
        const char *long_stages[3];
    } kinds[] = {{"lines", {"split", "faces", "output"}},
                 {"svg", {"svg", "split", "faces"}},
                 {"polygons", {"split", "faces", "output"}},
                 {"solids", {"planes", "cells", "output"}}};
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
        const char *kind = kinds[k].kind;
        char *body = progress_request(kind);
        REQUIRE(body, "memory");
        prog_rec p = {.kind = kind, .last = 0};
        api_run_opts ro = {.threads = 2, .progress = prog_rec_cb, .udata = &p};
        char *out = NULL;
        size_t outlen;
        api_error err = {0};
        int rc = api_run_json_ex(body, strlen(body), &ro, &out, &outlen, &err);
        CHECK(rc == API_OK, "%s: %d %s", kind, rc, err.msg);
        CHECK(p.back == 0 && p.unknown == 0 && p.out_of_order == 0,
              "%s: %d reports back, %d of unknown stages, %d out of order", kind, p.back, p.unknown,
              p.out_of_order);
        CHECK(p.last == 1 && !strcmp(p.last_stage, "output"), "%s: ends at %g in %s", kind, p.last,
              p.last_stage);
        size_t nst = 0;
        while (api_stage_name(kind, nst)) nst++;
        CHECK(nst >= 5 && (size_t)p.nseen == nst, "%s: %d stages seen of %zu", kind, p.nseen, nst);
        for (size_t i = 0; i < nst && i < (size_t)p.nseen; i++)
            CHECK(!strcmp(p.seen[i], api_stage_name(kind, i)), "%s: stage %zu is %s, want %s", kind,
                  i, p.seen[i], api_stage_name(kind, i));
        for (int j = 0; j < 3; j++) {
            int i = stage_index(kind, kinds[k].long_stages[j]);
            CHECK(i >= 0 && p.inside[i] >= 2, "%s: %d reports inside %s", kind,
                  i >= 0 ? p.inside[i] : -1, kinds[k].long_stages[j]);
        }
        free(out);
        free(body);
    }
    CHECK(api_stage_name("nonsense", 0) == NULL, "stages of an unknown kind");
}

/* ---- fields never send a key that refers to one left out (issue 28) ----------------------- */

/* The largest index in a (nested arrays of integers; a signed index ±(i+1) counts as i), or
 * -1 when there is none. */
static long long max_index(const json_t *a, int is_signed)
{
    long long m = -1;
    if (json_is_integer(a)) {
        long long v = json_integer_value(a);
        return is_signed ? (v < 0 ? -v : v) - 1 : v;
    }
    size_t i;
    const json_t *x;
    if (json_is_array(a)) json_array_foreach(a, i, x)
        {
            long long k = max_index(x, is_signed);
            if (k > m) m = k;
        }
    if (json_is_object(a)) {
        const char *key;
        json_object_foreach((json_t *)a, key, x)
        {
            long long k = max_index(x, is_signed);
            if (k > m) m = k;
        }
    }
    return m;
}

/* The rows of r's key, or -1 when r has no such key. */
static long long rows(const json_t *r, const char *key)
{
    const json_t *a = json_object_get(r, key);
    return a ? (long long)json_array_size(a) : -1;
}

/* Why result r (of dimension dim) has a key that refers to one it lacks or indexes past it
 * ("" when nothing does): every index points into a key that is there. */
static void dangling(const json_t *r, int dim, char *why, size_t n)
{
    long long nv = rows(r, "V"), ne = rows(r, "EV");
    long long nf = rows(r, "FV") >= 0 ? rows(r, "FV") : rows(r, "FE");
    long long nc = rows(r, "CF") >= 0 ? rows(r, "CF") : rows(r, "CV");
    const json_t *res = json_object_get(r, "result"), *h = json_object_get(r, "holes");
    struct {
        const json_t *a;
        int is_signed;
        long long bound;
        const char *what;
    } refs[] = {{json_object_get(r, "EV"), 0, nv, "EV into V"},
                {json_object_get(r, "FV"), 0, nv, "FV into V"},
                {json_object_get(r, "FE"), 1, ne, "FE into EV"},
                {h, 0, nv, "holes into V"},
                {json_object_get(r, "exterior"), dim == 3, dim == 3 ? nf : nv,
                 dim == 3 ? "exterior into the faces" : "exterior into V"},
                {json_object_get(r, "CF"), 1, nf, "CF into the faces"},
                {json_object_get(r, "CV"), 0, nv, "CV into V"},
                {json_object_get(res, "FV"), 0, json_object_get(res, "V") ? rows(res, "V") : nv,
                 "result.FV into a V"},
                {json_object_get(res, "holes"), 0, json_object_get(res, "V") ? rows(res, "V") : nv,
                 "result.holes into a V"},
                {json_object_get(res, "FE"), 1, ne, "result.FE into EV"},
                {json_object_get(res, "cells"), 0, dim == 3 ? nc : nf,
                 dim == 3 ? "result.cells into the cells" : "result.cells into the faces"},
                {json_object_get(res, "faces"), 1, nf, "result.faces into the faces"}};
    why[0] = 0;
    for (size_t i = 0; i < sizeof refs / sizeof *refs; i++) {
        if (!refs[i].a) continue;
        long long m = max_index(refs[i].a, refs[i].is_signed);
        if (refs[i].bound < 0 || m >= refs[i].bound) {
            snprintf(why, n, "%s: index %lld, %lld rows there", refs[i].what, m, refs[i].bound);
            return;
        }
    }
    const char *key;
    const json_t *x;
    if (h) json_object_foreach((json_t *)h, key, x)
        {
            if (nf < 0 || atoll(key) >= nf) {
                snprintf(why, n, "holes.%s: a face not sent (%lld rows)", key, nf);
                return;
            }
        }
}

/* The test's own statement of the rule, apart from the code's: bit k of names refers to the
 * keys of any[k] (bits, one of which must be named; 0: refers to none). */
typedef struct fields_rule {
    const char *key;
    const char *any[2];
} fields_rule;

static int named(unsigned set, const char *const *names, size_t nn, const char *key)
{
    for (size_t k = 0; k < nn; k++)
        if ((set >> k & 1) && !strcmp(names[k], key)) return 1;
    return 0;
}

/* Whether `set` of names breaks a rule with key `key` (any key when NULL). */
static int breaks(unsigned set, const char *const *names, size_t nn, const fields_rule *rules,
                  size_t nr, const char *key)
{
    for (size_t i = 0; i < nr; i++) {
        const fields_rule *r = &rules[i];
        if (key && strcmp(key, r->key)) continue;
        if (named(set, names, nn, r->key) && !named(set, names, nn, r->any[0]) &&
            !(r->any[1] && named(set, names, nn, r->any[1])))
            return 1;
    }
    return 0;
}

/* Every subset of the names as a request's fields (body: the request up to its options,
 * without the closing brace): a subset that names a key without one it refers to is refused
 * 422 naming such a key; any other gives exactly its keys (and "dim"), none of which refers to
 * one left out.  Returns the number of subsets refused. */
static size_t every_subset(const char *body, int dim, const char *const *names, size_t nn,
                           const fields_rule *rules, size_t nr, const char *label)
{
    size_t refused = 0, failed = 0;
    for (unsigned set = 0; set < 1u << nn && failed < 5; set++) {
        char req[8192], fl[256] = "[";
        size_t w = 1;
        for (size_t k = 0; k < nn; k++)
            if (set >> k & 1)
                w +=
                    (size_t)snprintf(fl + w, sizeof fl - w, "%s\"%s\"", w > 1 ? "," : "", names[k]);
        snprintf(fl + w, sizeof fl - w, "]");
        snprintf(req, sizeof req, "%s,\"options\":{\"fields\":%s}}", body, fl);
        char *out = NULL;
        size_t outlen = 0;
        api_error err = {0};
        int rc = api_run_json(req, strlen(req), 1, &out, &outlen, &err);
        int broken = breaks(set, names, nn, rules, nr, NULL);
        if (broken) {
            refused++;
            char key[32] = "";
            if (rc == API_EINVALID) sscanf(err.msg, "options.fields: \"%31[^\"]\" refers to", key);
            int ok = rc == API_EINVALID && key[0] && breaks(set, names, nn, rules, nr, key) &&
                     (strstr(err.msg, "which is not named") || strstr(err.msg, "neither of which"));
            if (!ok) failed++;
            CHECK(ok, "%s fields %s: %d \"%s\", want 422 naming a key that refers to one left out",
                  label, fl, rc, err.msg);
            free(out);
            continue;
        }
        json_t *r = rc == API_OK ? json_loadb(out, outlen, 0, NULL) : NULL;
        free(out);
        if (!r) {
            failed++;
            CHECK(0, "%s fields %s: %d %s", label, fl, rc, err.msg);
            continue;
        }
        size_t want = 1;
        for (size_t k = 0; k < nn; k++)
            if (set >> k & 1) {
                want++;
                if (!json_object_get(r, names[k])) {
                    failed++;
                    CHECK(0, "%s fields %s: no \"%s\"", label, fl, names[k]);
                }
            }
        char why[200];
        dangling(r, dim, why, sizeof why);
        if (json_object_size(r) != want || why[0]) failed++;
        CHECK(json_object_size(r) == want, "%s fields %s: %zu keys, want %zu", label, fl,
              json_object_size(r), want);
        CHECK(!why[0], "%s fields %s: %s", label, fl, why);
        json_decref(r);
    }
    return refused;
}

static const fields_rule rules2[] = {{"EV", {"V"}},           {"FV", {"V"}},
                                     {"FE", {"EV"}},          {"holes", {"V"}},
                                     {"holes", {"FV", "FE"}}, {"exterior", {"V"}}};
static const fields_rule rules3[] = {
    {"EV", {"V"}},           {"FV", {"V"}},        {"FE", {"EV"}}, {"holes", {"V"}},
    {"holes", {"FV", "FE"}}, {"CF", {"FV", "FE"}}, {"CV", {"V"}},  {"exterior", {"FV", "FE"}}};

/* Every kind, every subset of its fields: lines, svg and polygons (2D, with holes), solids
 * (with an op: membership and result). */
TEST(fields_never_refer_to_left_out_keys)
{
    static const char *const n2[] = {"V",        "EV",    "FV",        "FE",         "holes",
                                     "exterior", "stats", "operators", "membership", "result"};
    static const char *const n3[] = {"V",     "EV",        "FV",         "FE",
                                     "holes", "CF",        "CV",         "exterior",
                                     "stats", "operators", "membership", "result"};
    /* a square with a square hole (a face with a hole) */
    const char *lines = "{\"kind\":\"lines\",\"lines\":[[[0,0],[4,0]],[[4,0],[4,4]],[[4,4],[0,4]],"
                        "[[0,4],[0,0]],[[1,1],[2,1]],[[2,1],[2,2]],[[2,2],[1,2]],[[1,2],[1,1]]]";
    const char *svg =
        "{\"kind\":\"svg\",\"svg\":\"<svg xmlns='http://www.w3.org/2000/svg'>"
        "<rect width='4' height='4'/><rect x='1' y='1' width='1' height='1'/></svg>\"";
    /* a square with a hole, minus a square across its corner: a result polygon with a hole */
    const char *poly = "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[10,0],[10,10],[0,10]],"
                       "[[4,4],[6,4],[6,6],[4,6]]],[[[8,8],[12,8],[12,12],[8,12]]]],"
                       "\"op\":\"difference\"";
    /* a box with a box through its top: result faces with holes */
    const char *solids =
        "{\"kind\":\"solids\",\"solids\":[{\"V\":[[0,0,0],[4,0,0],[4,4,0],[0,4,0],[0,0,1],[4,0,1],"
        "[4,4,1],[0,4,1]],\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]},"
        "{\"V\":[[1,1,1],[3,1,1],[3,3,1],[1,3,1],[1,1,2],[3,1,2],[3,3,2],[1,3,2]],"
        "\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}],\"op\":\"union\"";
    size_t r;
    r = every_subset(lines, 2, n2, 8, rules2, 6, "lines");
    CHECK(r > 0 && r < 256, "lines: %zu of 256 subsets refused", r);
    r = every_subset(svg, 2, n2, 8, rules2, 6, "svg");
    CHECK(r > 0 && r < 256, "svg: %zu of 256 subsets refused", r);
    r = every_subset(poly, 2, n2, 10, rules2, 6, "polygons");
    CHECK(r > 0 && r < 1024, "polygons: %zu of 1024 subsets refused", r);
    r = every_subset(solids, 3, n3, 12, rules3, 8, "solids");
    CHECK(r > 0 && r < 4096, "solids: %zu of 4096 subsets refused", r);
}

/* The cases a user meets, spelled out: ["stats"] is only stats (no membership, no result);
 * ["result"] alone is the result with a V of its own that its cycles index (2D and 3D), the
 * same points as the complex's; a key without the one it refers to is a 422 naming both. */
TEST(fields_result_alone_and_stats_alone)
{
    const char *poly = "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[10,0],[10,10],[0,10]],"
                       "[[4,4],[6,4],[6,6],[4,6]]],[[[8,8],[12,8],[12,12],[8,12]]]],"
                       "\"op\":\"difference\"";
    const char *solids =
        "{\"kind\":\"solids\",\"solids\":[{\"V\":[[0,0,0],[2,0,0],[2,2,0],[0,2,0],[0,0,2],[2,0,2],"
        "[2,2,2],[0,2,2]],\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]},"
        "{\"V\":[[1,1,1],[3,1,1],[3,3,1],[1,3,1],[1,1,3],[3,1,3],[3,3,3],[1,3,3]],"
        "\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}],\"op\":"
        "\"difference\"";
    const char *bodies[] = {poly, solids};
    for (int k = 0; k < 2; k++) {
        char req[4096];
        snprintf(req, sizeof req, "%s,\"options\":{\"fields\":[\"stats\"]}}", bodies[k]);
        json_t *r = run_ok(req);
        CHECK(r && json_object_size(r) == 2 && json_object_get(r, "stats"),
              "%s [\"stats\"]: only dim and stats", k ? "solids" : "polygons");
        json_decref(r);
        /* the result alone, against the whole result: the same points, face by face */
        snprintf(req, sizeof req, "%s,\"options\":{\"fields\":[\"result\"]}}", bodies[k]);
        json_t *alone = run_ok(req);
        snprintf(req, sizeof req, "%s}", bodies[k]);
        json_t *all = run_ok(req);
        REQUIRE(alone && all, "no results");
        const json_t *ra = json_object_get(alone, "result"), *rw = json_object_get(all, "result");
        const json_t *va = json_object_get(ra, "V"), *vw = json_object_get(all, "V");
        CHECK(json_object_size(alone) == 2 && json_is_array(va) && json_array_size(va) > 0 &&
                  json_array_size(va) < json_array_size(vw) && !json_object_get(ra, "cells") &&
                  !json_object_get(ra, "faces") && !json_object_get(ra, "FE"),
              "%s [\"result\"]: {dim, result: {V, FV, holes, %s}}", k ? "solids" : "polygons",
              k ? "volume" : "area");
        for (int part = 0; part < 2; part++) { /* FV, then holes */
            const char *key = part ? "holes" : "FV";
            char *a = json_dumps(json_object_get(ra, key), JSON_COMPACT | JSON_SORT_KEYS);
            char *w = json_dumps(json_object_get(rw, key), JSON_COMPACT | JSON_SORT_KEYS);
            /* map each index to its point: the same text when the points agree */
            json_t *pa = json_loads(a ? a : "null", JSON_DECODE_ANY, NULL);
            json_t *pw = json_loads(w ? w : "null", JSON_DECODE_ANY, NULL);
            size_t same = 0, total = 0;
            const json_t *cyc_a, *cyc_w;
            json_t *ea, *ew;
            const char *hk;
            json_t *la = part ? json_array() : json_incref(pa),
                   *lw = part ? json_array() : json_incref(pw);
            if (part) {
                json_object_foreach(pa, hk, ea) json_array_extend(la, ea);
                json_object_foreach(pw, hk, ew) json_array_extend(lw, ew);
            }
            size_t i;
            json_array_foreach(la, i, cyc_a)
            {
                cyc_w = json_array_get(lw, i);
                for (size_t j = 0; j < json_array_size(cyc_a); j++) {
                    total++;
                    json_t *p =
                        json_array_get(va, (size_t)json_integer_value(json_array_get(cyc_a, j)));
                    json_t *q =
                        json_array_get(vw, (size_t)json_integer_value(json_array_get(cyc_w, j)));
                    same += p && q && json_equal(p, q);
                }
            }
            CHECK((total > 0 || part) && same == total &&
                      json_array_size(la) == json_array_size(lw),
                  "%s [\"result\"]: %s: %zu of %zu points as in the whole result",
                  k ? "solids" : "polygons", key, same, total);
            json_decref(la);
            json_decref(lw);
            json_decref(pa);
            json_decref(pw);
            free(a);
            free(w);
        }
        json_decref(alone);
        json_decref(all);
    }
    /* the messages */
    static const struct {
        const char *fields, *msg;
    } bad[] = {{"[\"FV\"]", "options.fields: \"FV\" refers to \"V\", which is not named"},
               {"[\"V\",\"FE\"]", "options.fields: \"FE\" refers to \"EV\", which is not named"},
               {"[\"V\",\"CF\"]",
                "options.fields: \"CF\" refers to the faces, \"FV\" or \"FE\", neither of which "
                "is named"}};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        char req[4096], *out = NULL;
        size_t outlen;
        api_error err = {0};
        snprintf(req, sizeof req, "%s,\"options\":{\"fields\":%s}}", solids, bad[i].fields);
        int rc = api_run_json(req, strlen(req), 1, &out, &outlen, &err);
        CHECK(rc == 422 && !strncmp(err.msg, bad[i].msg, strlen(bad[i].msg)),
              "fields %s: %d \"%s\"", bad[i].fields, rc, err.msg);
        free(out);
        /* the daemon's intake says the same, before any geometry */
        char *canon = NULL;
        memset(&err, 0, sizeof err);
        rc = api_check_json(req, strlen(req), &canon, NULL, &err);
        CHECK(rc == 422 && !strncmp(err.msg, bad[i].msg, strlen(bad[i].msg)) && !canon,
              "api_check_json fields %s: %d \"%s\"", bad[i].fields, rc, err.msg);
        free(canon);
    }
}
