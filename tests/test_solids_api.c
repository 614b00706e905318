/* test_solids_api.c — the "solids" kind (api/solids.c), the dim-3 LAR JSON writer
 * (api/larjson3.c) and the OBJ export (api/render_obj.c):
 *   - every error path of a request with its status and JSON path, through api_run_json()
 *     and api_check_json() alike (the daemon's submit), and the face limit through
 *     api_solids_parse() on a tree of shared rows (a text that big would cost gigabytes);
 *   - the writer on a hand-built 3-complex, read back with jansson: shapes, values, holes,
 *     field subsets, the operators (d1·d2 = 0 and d2·d3 = 0 from the CSR arrays alone), and a
 *     broken complex refused with 500, not a crash;
 *   - render_obj on hand-written results: a cube (closed, outward, volume 1), non-convex faces
 *     and faces with holes in tilted planes (triangle areas add up to the polygon's area, every
 *     triangle faces like the face, or the other way for -(f+1)), random star-shaped faces
 *     with holes, explode, and bad input (a value, never a crash, also for every truncation).
 * The tests marked CORE below run the real 3D core (core/arr3.c) and assert its counts. */
#include "api/api.h"
#include "api/api_int.h"
#include "api/render.h"
#include "tests/check.h"

#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A unit cube, outward oriented, as a JSON solid; CUBE_AT(d) the same moved by (d, d, d). */
#define CUBE_V  "[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]"
#define CUBE_FV "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]"
#define CUBE    "{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}"
#define CUBE_HALF                                                                                  \
    "{\"V\":[[0.5,0.5,0.5],[1.5,0.5,0.5],[1.5,1.5,0.5],[0.5,1.5,0.5],[0.5,0.5,1.5],"               \
    "[1.5,0.5,1.5],[1.5,1.5,1.5],[0.5,1.5,1.5]],\"FV\":" CUBE_FV "}"
#define SOLIDS(s) "{\"kind\":\"solids\",\"solids\":[" s "]}"

/* ---- helpers ------------------------------------------------------------------------------- */

/* Runs body; on success returns the parsed result (caller decrefs), else NULL with a failure. */
static json_t *run_ok_(const char *body, const char *func, int line)
{
    char *out = NULL;
    size_t outlen = 0;
    api_error err;
    json_error_t je;
    json_t *r;
    int rc = api_run_json(body, strlen(body), 2, &out, &outlen, &err);
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
#define run_ok(body) run_ok_(body, __func__, __LINE__)

static long long ival(const json_t *v)
{
    return json_is_integer(v) ? (long long)json_integer_value(v) : -999999;
}

/* a equals b (taken) */
static int json_is(const json_t *a, json_t *b)
{
    int eq = json_equal(a, b);
    json_decref(b);
    return eq;
}

static long long stat_of(const json_t *r, const char *key)
{
    return ival(json_object_get(json_object_get(r, "stats"), key));
}

/* ---- request errors ------------------------------------------------------------------------ */

typedef struct err_case {
    const char *body;
    int status;
    const char *prefix;   /* the message starts with this */
    const char *contains; /* and holds this (may be NULL) */
} err_case;

/* a flat tetrahedron (all four vertices in z = 0) with face 1 walked the wrong way: the check
 * first warns about the orientation, then finds no volume; the 422 must name the error */
#define FLAT_TETRA                                                                                 \
    "{\"V\":[[0,0,0],[1,0,0],[0,1,0],[0.25,0.25,0]],\"FV\":[[0,2,1],[1,3,0],[0,3,2],[1,2,3]]}"

static const err_case err_cases[] = {
    /* the request's keys */
    {"{\"kind\":\"solids\"}", 422, "solids: required", NULL},
    {"{\"kind\":\"solids\",\"solids\":[" CUBE "],\"faces\":" CUBE "}", 422,
     "faces: give one of \"solids\" (closed surfaces), \"layers\"", NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"name\":\"x\"}", 422, "name: unknown key", NULL},
    {"{\"kind\":\"solids\",\"solids\":{}}", 422, "solids: expected an array of solids", NULL},
    {"{\"kind\":\"solids\",\"solids\":\"cube\"}", 422, "solids: expected an array", NULL},
    {"{\"kind\":\"solids\",\"solids\":[5]}", 422, "solids[0]: expected an object", NULL},
    {"{\"kind\":\"solids\",\"solids\":[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]}", 422,
     "solids[0]: expected an object", NULL},
    {SOLIDS(CUBE ",{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"colour\":1}"), 422,
     "solids[1].colour: unknown key (expected V, FV or holes)", NULL},
    /* V */
    {SOLIDS("{\"FV\":" CUBE_FV "}"), 422, "solids[0].V: required", NULL},
    {SOLIDS("{\"V\":{},\"FV\":" CUBE_FV "}"), 422, "solids[0].V: expected an array", NULL},
    {SOLIDS("{\"V\":[[0,0,0],[1,0]],\"FV\":[[0,1,1]]}"), 422,
     "solids[0].V[1]: expected 3 finite numbers", NULL},
    {SOLIDS("{\"V\":[[0,0,0],[1,0,\"1\"]],\"FV\":[[0,1,1]]}"), 422,
     "solids[0].V[1][2]: expected a finite number", NULL},
    {SOLIDS("{\"V\":[[0,0,0],[1,null,0]],\"FV\":[[0,1,1]]}"), 422,
     "solids[0].V[1][1]: expected a finite number", NULL},
    {SOLIDS(CUBE ",{\"V\":[[0,0,1e400]],\"FV\":[[0,0,0]]}"), 422, "solids[1].V[0][2]: ", NULL},
    {SOLIDS("{\"V\":[[0,0,0],5],\"FV\":[[0,1,1]]}"), 422, "solids[0].V[1]: expected 3", NULL},
    /* FV */
    {SOLIDS("{\"V\":" CUBE_V "}"), 422, "solids[0].FV: required", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":7}"), 422, "solids[0].FV: expected an array", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":[]}"), 422,
     "solids[0].FV: expected the faces of a closed surface, got none", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":[[0,3,2,1],[4,5],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}"),
     422, "solids[0].FV[1]: expected at least 3 vertex indices, got 2", NULL},
    {SOLIDS("{\"V\":" CUBE_V
            ",\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,8,7]]}"),
     422, "solids[0].FV[5][2]: expected a vertex index, an integer from 0 to 7 (V has 8 rows)",
     NULL},
    {SOLIDS("{\"V\":" CUBE_V
            ",\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,-4,7]]}"),
     422, "solids[0].FV[5][2]: expected a vertex index", NULL},
    {SOLIDS("{\"V\":" CUBE_V
            ",\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5.0,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}"),
     422, "solids[0].FV[2][2]: expected a vertex index", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":[[0,3,2,1],\"4 5 6 7\"]}"), 422,
     "solids[0].FV[1]: expected an array of vertex indices", NULL},
    {SOLIDS("{\"V\":[],\"FV\":[[0,1,2]]}"), 422,
     "solids[0].FV[0][0]: a vertex index, but V is empty", NULL},
    /* holes */
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":[]}"), 422,
     "solids[0].holes: expected an object", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{\"01\":[[0,1,2]]}}"), 422,
     "solids[0].holes.01: expected a face index in decimal, below 6", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{\"6\":[[0,1,2]]}}"), 422,
     "solids[0].holes.6: expected a face index", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{\"2\":[]}}"), 422,
     "solids[0].holes.2: expected a non-empty array of cycles", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{\"2\":[[0,1]]}}"), 422,
     "solids[0].holes.2[0]: expected at least 3 vertex indices, got 2", NULL},
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{\"2\":[[0,1,2],[0,1,9]]}}"), 422,
     "solids[0].holes.2[1][2]: expected a vertex index", NULL},
    /* geometry: solid_check's messages with JSON paths */
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6]]}"), 422,
     "solids[0].FV[", "open surface"},
    {SOLIDS("{\"V\":" CUBE_V
            ",\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,1],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}"),
     422, "solids[0].FV[", "non-manifold edge"}, /* FV[2] is left out with a warning */
    {SOLIDS("{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{\"0\":[[0,0,0]]}}"), 422,
     "solids[0].holes.0[0]: fewer than 3 distinct vertices", NULL},
    {SOLIDS(FLAT_TETRA), 422, "solids[0]: degenerate: volume", NULL},
    /* the soup */
    {"{\"kind\":\"solids\",\"faces\":[]}", 422, "faces: expected an object", NULL},
    {"{\"kind\":\"solids\",\"faces\":{\"V\":[[0,0,0]]}}", 422, "faces.FV: required", NULL},
    {"{\"kind\":\"solids\",\"faces\":{\"V\":[[0,0,0]],\"FV\":[]}}", 422,
     "faces.FV: expected at least one face, got none", NULL},
    {"{\"kind\":\"solids\",\"faces\":{\"V\":[[0,0,0],[4,0,0],[4,4,0],[0,4,0],[1,1,0],[2,2,0]],"
     "\"FV\":[[0,1,2,3]],\"holes\":{\"0\":[[4,5,4]]}}}",
     422, "faces.holes.0[0]: fewer than 3 distinct vertices", NULL},
    {"{\"kind\":\"solids\",\"faces\":{\"V\":[[0,0,0]],\"FV\":[[0,1,2]]}}", 422,
     "faces.FV[0][1]: expected a vertex index, an integer from 0 to 0", NULL},
    /* options */
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":{\"colour\":1}}", 422,
     "options.colour: unknown option (expected precision, operators, fields or fill)", NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":{\"keep_dangling\":true}}", 422,
     "options.keep_dangling: unknown option", NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":[]}", 422, "options: expected an object",
     NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":{\"precision\":0}}", 422,
     "options.precision: expected a number > 0", NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":{\"precision\":-1}}", 422,
     "options.precision: expected a number > 0", NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":{\"precision\":\"0.1\"}}", 422,
     "options.precision: expected a number > 0", NULL},
    {SOLIDS(CUBE) "x", 400, "malformed JSON", NULL},
    {"{\"kind\":\"solids\",\"solids\":[" CUBE "],\"options\":{\"precision\":1e-10}}", 422,
     "options.precision: 1e-10 is finer than the input allows", NULL},
    /* op (issue "Boolean chains") */
    {"{\"kind\":\"solids\",\"solids\":[" CUBE "],\"op\":\"merge\"}", 422, "op: expected \"union\"",
     NULL},
    {"{\"kind\":\"solids\",\"solids\":[" CUBE "],\"op\":[\"-\",0,1]}", 422,
     "op[2]: input 1 out of range (1 inputs)", NULL},
    {"{\"kind\":\"solids\",\"solids\":[" CUBE "," CUBE "],\"op\":[\"*\",0,1]}", 422,
     "op[0]: expected an operator", NULL},
    {"{\"kind\":\"solids\",\"solids\":[" CUBE "," CUBE "],\"op\":[\"+\",0]}", 422,
     "op: expected an input index or [operator, operand, operand, ...]", NULL},
    {"{\"kind\":\"solids\",\"solids\":[" CUBE "," CUBE "],\"op\":[\"+\",0,[\"&\",1,-1]]}", 422,
     "op[2][2]: input -1 out of range", NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"op\":\"union\"}", 422,
     "op: there are no inputs to combine", NULL},
    {"{\"kind\":\"solids\",\"faces\":" CUBE ",\"op\":\"union\"}", 422, "op: needs \"solids\"",
     NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":{\"operators\":1}}", 422,
     "options.operators: expected true or false", NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":{\"fields\":[\"V\",\"faces\"]}}", 422,
     "options.fields[1]: expected one of \"V\", \"EV\", \"FV\", \"FE\", \"holes\", \"CF\"", NULL},
    {"{\"kind\":\"solids\",\"solids\":[],\"options\":{\"fields\":\"CF\"}}", 422,
     "options.fields: expected an array", NULL},
};

TEST(request_errors_have_status_and_path)
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
              "case %zu: message \"%s\", want prefix \"%s\"", i, err.msg, c->prefix);
        CHECK(!c->contains || strstr(err.msg, c->contains), "case %zu: message \"%s\" lacks \"%s\"",
              i, err.msg, c->contains);
        CHECK(out == NULL && outlen == 0, "case %zu: output not cleared on failure", i);
        /* the daemon's submit (parse and check, no core) gives the same answer */
        memset(&err, 0, sizeof err);
        rc = api_check_json(c->body, strlen(c->body), &canon, NULL, &err);
        CHECK(rc == c->status && strncmp(err.msg, c->prefix, strlen(c->prefix)) == 0,
              "case %zu: api_check_json gives %d \"%s\"", i, rc, err.msg);
        CHECK(canon == NULL, "case %zu: canonical form on failure", i);
    }
}

TEST(check_accepts_valid_requests)
{
    static const char *const ok[] = {
        SOLIDS(CUBE),
        SOLIDS(CUBE "," CUBE_HALF),
        "{\"kind\":\"solids\",\"solids\":[]}",
        "{\"options\":{\"precision\":0.001,\"operators\":true,\"fields\":[\"CF\",\"FE\",\"EV\","
        "\"V\",\"stats\"]},"
        "\"kind\":\"solids\",\"solids\":[" CUBE "]}",
        /* a face with a hole: a unit cube whose top carries a hole, the hole's walls and floor */
        "{\"kind\":\"solids\",\"faces\":{\"V\":[[0,0,0],[4,0,0],[4,4,0],[0,4,0],[1,1,0],[1,3,0],"
        "[3,3,0],[3,1,0]],\"FV\":[[0,1,2,3]],\"holes\":{\"0\":[[4,5,6,7]]}}}",
        /* an inward cube and one with a flipped face: usable, with a warning */
        SOLIDS("{\"V\":" CUBE_V
               ",\"FV\":[[0,1,2,3],[4,7,6,5],[0,4,5,1],[1,5,6,2],[2,6,7,3],[3,7,4,0]]}"),
        SOLIDS("{\"V\":" CUBE_V
               ",\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,7,4,0]]}"),
    };
    for (size_t i = 0; i < sizeof ok / sizeof *ok; i++) {
        char *canon = NULL;
        const char *kind = NULL;
        api_error err;
        int rc = api_check_request(ok[i], strlen(ok[i]), &canon, NULL, &kind, &err);
        CHECK(rc == API_OK && kind && strcmp(kind, "solids") == 0, "case %zu: %d %s", i, rc,
              err.msg);
        CHECK(canon && strncmp(canon, "{\"", 2) == 0 && strstr(canon, "\"kind\":\"solids\""),
              "case %zu: canonical %s", i, canon ? canon : "(null)");
        free(canon);
    }
}

/* FV of as many rows as the limit in solids[0] (one shared row) and one more in solids[1]: the
 * limit counts the faces of all solids together (set to 1000 here: the default is tens of
 * millions, ARR3_MAX_FACES). */
TEST(face_limit_counts_all_solids)
{
    CHECK(api_solids_max_faces() == ARR3_MAX_FACES, "default limit %u", api_solids_max_faces());
    api_solids_set_max_faces(1000);
    json_t *row = json_pack("[i,i,i]", 0, 1, 2);
    json_t *big = json_array(), *small = json_array();
    json_t *V = json_pack("[[f,f,f],[f,f,f],[f,f,f]]", 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    void *parsed = (void *)1;
    api_error err = {0};
    REQUIRE(row && big && small && V, "out of memory");
    for (size_t i = 0; i < 1000; i++) json_array_append(big, row);
    json_array_append(small, row);
    json_t *req = json_pack("{s:s, s:[{s:O, s:o}, {s:O, s:o}]}", "kind", "solids", "solids", "V", V,
                            "FV", big, "V", V, "FV", small);
    REQUIRE(req, "json_pack");
    int rc = api_solids_parse(req, &parsed, &err);
    CHECK(rc == API_EINVALID && parsed == NULL, "rc %d", rc);
    CHECK(strcmp(err.msg, "solids[1].FV: 1001 faces in all, at most 1000 allowed") == 0,
          "message %s", err.msg);
    /* one face fewer passes the parse */
    json_array_remove(big, 0); /* req holds it */
    rc = api_solids_parse(req, &parsed, &err);
    CHECK(rc == API_OK && parsed, "rc %d %s", rc, err.msg);
    api_solids_free(parsed);
    json_decref(req);
    json_decref(V);
    json_decref(row);
    api_solids_set_max_faces(0);
    CHECK(api_solids_max_faces() == ARR3_MAX_FACES, "restored limit %u", api_solids_max_faces());
}

/* The core's memory estimate: an input needing more than the run may take is refused at run,
 * naming the bytes a face costs (max_bytes set to 1 MB for 6 000 faces). */
TEST(memory_limit_refuses_at_run)
{
    size_t n = 1000;
    solid s[1] = {{0}};
    s[0].nv = 8 * n;
    s[0].V = malloc(3 * s[0].nv * sizeof *s[0].V);
    s[0].nf = s[0].ncyc = 6 * n;
    s[0].face_off = malloc((s[0].nf + 1) * sizeof *s[0].face_off);
    s[0].cyc_off = malloc((s[0].ncyc + 1) * sizeof *s[0].cyc_off);
    s[0].cyc = malloc(24 * n * sizeof *s[0].cyc);
    REQUIRE(s[0].V && s[0].face_off && s[0].cyc_off && s[0].cyc, "out of memory");
    static const int box[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (size_t c = 0; c < n; c++) {
        for (int i = 0; i < 8; i++) {
            s[0].V[3 * (8 * c + i) + 0] = 3.0 * (double)c + (i & 1);
            s[0].V[3 * (8 * c + i) + 1] = i & 2 ? 1 : 0;
            s[0].V[3 * (8 * c + i) + 2] = i & 4 ? 1 : 0;
        }
        for (int f = 0; f < 6; f++)
            for (int k = 0; k < 4; k++)
                s[0].cyc[24 * c + 4 * f + k] = (uint32_t)(8 * c + box[f][k]);
    }
    for (size_t f = 0; f <= s[0].nf; f++)
        s[0].face_off[f] = (uint32_t)f, s[0].cyc_off[f] = (uint32_t)(4 * f);
    arr3_opts o = {.threads = 1, .max_bytes = 1000000};
    lar3 c = {0};
    char msg[256];
    int rc = arr3_build(s, 1, 0, &o, &c, msg, sizeof msg);
    CHECK(rc == ARR_ELIMIT && strstr(msg, "6000 faces need about") && strstr(msg, "bytes a face"),
          "rc %d: %s", rc, msg);
    lar3_free(&c);
    o.max_bytes = 0; /* the machine's memory: enough */
    rc = arr3_build(s, 1, 0, &o, &c, msg, sizeof msg);
    CHECK(rc == ARR_OK && c.nc == n, "rc %d, %zu cells: %s", rc, c.nc, msg);
    lar3_free(&c);
    solid_free(&s[0]);
}

/* ---- the writer on a hand-built complex ------------------------------------------------------ */

/* A tetrahedron (cell 0) and, apart, a square face with a square hole in z = 5 (on no cell). */
static const double HV[] = {0,  0,  0, 1,  0,  0, 0,  1,  0, 0,  0,  1, 10, 10, 5, 14, 10, 5,
                            14, 14, 5, 10, 14, 5, 11, 11, 5, 11, 13, 5, 13, 13, 5, 13, 11, 5};
static const uint32_t HCYC[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
static const uint32_t HCYC_OFF[] = {0, 3, 6, 9, 12, 16, 20};

typedef struct hand3 {
    lar3 c;
    uint32_t EV[64], fc_off[6], fc[6], fe_off[6], cf_off[2], cv_off[2], cv[4];
    int32_t fe[64], cf[4], ext[4];
    double cvol[1], FN[15];
} hand3;

static size_t edge_of(const hand3 *h, uint32_t a, uint32_t b)
{
    uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
    for (size_t e = 0; e < h->c.ne; e++)
        if (h->EV[2 * e] == lo && h->EV[2 * e + 1] == hi) return e;
    return SIZE_MAX;
}

static int cmp_edge(const void *pa, const void *pb)
{
    const uint32_t *a = pa, *b = pb;
    if (a[0] != b[0]) return a[0] < b[0] ? -1 : 1;
    return (a[1] > b[1]) - (a[1] < b[1]);
}

static void hand_build(hand3 *h)
{
    memset(h, 0, sizeof *h);
    lar3 *c = &h->c;
    c->nv = 12;
    c->V = (double *)HV;
    c->ncyc = 6;
    c->cyc_off = (uint32_t *)HCYC_OFF;
    c->cyc = (uint32_t *)HCYC;
    /* faces 0..3 the tetrahedron's triangles, face 4 the square (cycle 4) with hole cycle 5 */
    c->nf = 5;
    for (uint32_t f = 0; f <= 4; f++) h->fc_off[f] = f, h->fc[f] = f;
    h->fc[5] = 5;
    h->fc_off[5] = 6;
    c->fc_off = h->fc_off;
    c->fc = h->fc;
    /* EV: every cycle edge, sorted, unique */
    for (size_t k = 0; k < 6; k++)
        for (uint32_t i = HCYC_OFF[k]; i < HCYC_OFF[k + 1]; i++) {
            uint32_t a = HCYC[i], b = HCYC[i + 1 < HCYC_OFF[k + 1] ? i + 1 : HCYC_OFF[k]];
            h->EV[2 * c->ne] = a < b ? a : b;
            h->EV[2 * c->ne + 1] = a < b ? b : a;
            c->ne++;
        }
    qsort(h->EV, c->ne, 2 * sizeof *h->EV, cmp_edge);
    size_t w = 0;
    for (size_t e = 0; e < c->ne; e++)
        if (w == 0 || cmp_edge(h->EV + 2 * e, h->EV + 2 * (w - 1))) {
            h->EV[2 * w] = h->EV[2 * e], h->EV[2 * w + 1] = h->EV[2 * e + 1];
            w++;
        }
    c->ne = w;
    c->EV = h->EV;
    /* FE: the signed sum of each face's cycles */
    size_t n = 0;
    for (size_t f = 0; f < 5; f++) {
        h->fe_off[f] = (uint32_t)n;
        for (uint32_t k = h->fc_off[f]; k < h->fc_off[f + 1]; k++)
            for (uint32_t i = HCYC_OFF[h->fc[k]]; i < HCYC_OFF[h->fc[k] + 1]; i++) {
                uint32_t a = HCYC[i],
                         b = HCYC[i + 1 < HCYC_OFF[h->fc[k] + 1] ? i + 1 : HCYC_OFF[h->fc[k]]];
                int32_t e = (int32_t)edge_of(h, a, b) + 1;
                h->fe[n++] = a < b ? e : -e;
            }
    }
    h->fe_off[5] = (uint32_t)n;
    c->fe_off = h->fe_off;
    c->fe = h->fe;
    c->FN = h->FN;
    c->nc = 1;
    h->cf_off[1] = 4;
    for (int i = 0; i < 4; i++) h->cf[i] = i + 1, h->ext[i] = -(i + 1), h->cv[i] = (uint32_t)i;
    c->cf_off = h->cf_off;
    c->cf = h->cf;
    h->cv_off[1] = 4;
    c->cv_off = h->cv_off;
    c->cv = h->cv;
    h->cvol[0] = 1.0 / 6;
    c->cvol = h->cvol;
    c->next = 4;
    c->ext = h->ext;
    c->stats.input_solids = 1;
    c->stats.input_faces = 4;
    c->stats.precision = 0.125;
    c->stats.ms_total = 1.5;
}

static json_t *write_hand(const hand3 *h, unsigned fields, const char *const *warn, size_t nwarn)
{
    api_buf b = {0};
    api_error err;
    api_lar3_fmt fmt = {.fields = fields, .warnings = warn, .nwarnings = nwarn};
    json_error_t je;
    int rc = api_lar3_write(&b, &h->c, &fmt, &err);
    json_t *r = NULL;
    if (rc == API_OK) r = json_loadb(b.p, b.len, JSON_REJECT_DUPLICATES, &je);
    if (rc != API_OK || !r) test_fail(__FILE__, __func__, __LINE__, "write: %d %s", rc, err.msg);
    api_buf_free(&b);
    return r;
}

/* Dense copy of a CSR matrix from JSON ({"shape","indptr","indices","data"}); NULL when
 * malformed. *rows, *cols get the shape. */
static int *csr_dense(const json_t *m, size_t *rows, size_t *cols)
{
    const json_t *shape = json_object_get(m, "shape"), *ptr = json_object_get(m, "indptr");
    const json_t *ind = json_object_get(m, "indices"), *dat = json_object_get(m, "data");
    *rows = (size_t)ival(json_array_get(shape, 0));
    *cols = (size_t)ival(json_array_get(shape, 1));
    if (json_array_size(ptr) != *rows + 1 || *rows > 1000 || *cols > 1000) return NULL;
    int *d = calloc(*rows * *cols + 1, sizeof *d);
    for (size_t r = 0; d && r < *rows; r++)
        for (long long i = ival(json_array_get(ptr, r)); i < ival(json_array_get(ptr, r + 1));
             i++) {
            long long col = ival(json_array_get(ind, (size_t)i));
            if (col < 0 || (size_t)col >= *cols) {
                free(d);
                return NULL;
            }
            d[r * *cols + (size_t)col] += (int)ival(json_array_get(dat, (size_t)i));
        }
    return d;
}

/* Non-zero when a (n x k) times b (k x m) is zero. */
static int product_zero(const int *a, const int *b, size_t n, size_t k, size_t m)
{
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < m; j++) {
            long s = 0;
            for (size_t t = 0; t < k; t++) s += (long)a[i * k + t] * b[t * m + j];
            if (s) return 0;
        }
    return 1;
}

TEST(writer_hand_built_complex)
{
    hand3 h;
    static const char *const warn[] = {"solids[0]: a \"quoted\" warning\\", "second"};
    hand_build(&h);
    json_t *r = write_hand(&h, API_F3_DEFAULT, warn, 2);
    REQUIRE(r, "no result");
    CHECK(ival(json_object_get(r, "dim")) == 3, "dim");
    const json_t *V = json_object_get(r, "V"), *FV = json_object_get(r, "FV");
    CHECK(json_array_size(V) == 12, "V rows %zu", json_array_size(V));
    for (size_t v = 0; v < json_array_size(V); v++) {
        const json_t *p = json_array_get(V, v);
        CHECK(json_array_size(p) == 3, "V[%zu] has %zu numbers", v, json_array_size(p));
        for (size_t a = 0; a < 3; a++)
            CHECK(json_number_value(json_array_get(p, a)) == HV[3 * v + a], "V[%zu][%zu]", v, a);
    }
    CHECK(json_array_size(json_object_get(r, "EV")) == h.c.ne, "EV rows");
    for (size_t e = 0; e < h.c.ne; e++)
        CHECK(ival(json_array_get(json_array_get(json_object_get(r, "EV"), e), 0)) == h.EV[2 * e] &&
                  ival(json_array_get(json_array_get(json_object_get(r, "EV"), e), 1)) ==
                      h.EV[2 * e + 1],
              "EV[%zu]", e);
    CHECK(json_array_size(FV) == 5, "FV rows");
    for (size_t f = 0; f < 5; f++) {
        const json_t *row = json_array_get(FV, f);
        size_t k = h.fc[h.fc_off[f]];
        CHECK(json_array_size(row) == HCYC_OFF[k + 1] - HCYC_OFF[k], "FV[%zu] length", f);
        for (size_t i = 0; i < json_array_size(row); i++)
            CHECK(ival(json_array_get(row, i)) == HCYC[HCYC_OFF[k] + i], "FV[%zu][%zu]", f, i);
    }
    const json_t *holes = json_object_get(r, "holes");
    CHECK(json_object_size(holes) == 1 && json_array_size(json_object_get(holes, "4")) == 1,
          "holes: only face 4, one hole");
    const json_t *hole = json_array_get(json_object_get(holes, "4"), 0);
    CHECK(json_array_size(hole) == 4 && ival(json_array_get(hole, 0)) == 8 &&
              ival(json_array_get(hole, 3)) == 11,
          "holes.4[0]");
    const json_t *FE = json_object_get(r, "FE");
    CHECK(json_array_size(FE) == 5 && json_array_size(json_array_get(FE, 4)) == 8, "FE rows");
    CHECK(json_is(json_object_get(r, "CF"), json_pack("[[i,i,i,i]]", 1, 2, 3, 4)), "CF");
    CHECK(json_is(json_object_get(r, "CV"), json_pack("[[i,i,i,i]]", 0, 1, 2, 3)), "CV");
    CHECK(json_is(json_object_get(r, "exterior"), json_pack("[i,i,i,i]", -1, -2, -3, -4)),
          "exterior");
    CHECK(!json_object_get(r, "operators"), "operators without asking");
    const json_t *st = json_object_get(r, "stats");
    CHECK(stat_of(r, "V") == 12 && stat_of(r, "E") == (long long)h.c.ne && stat_of(r, "F") == 5 &&
              stat_of(r, "C") == 1 && stat_of(r, "input_solids") == 1,
          "stats counts");
    CHECK(json_real_value(json_object_get(st, "precision")) == 0.125, "stats.precision");
    CHECK(json_number_value(json_object_get(json_object_get(st, "ms"), "total")) == 1.5,
          "stats.ms.total");
    CHECK(json_array_size(json_object_get(st, "volumes")) == 1 &&
              json_real_value(json_array_get(json_object_get(st, "volumes"), 0)) == 1.0 / 6,
          "stats.volumes exact");
    const json_t *w = json_object_get(st, "warnings");
    CHECK(json_array_size(w) == 2 &&
              strcmp(json_string_value(json_array_get(w, 0)), warn[0]) == 0 &&
              strcmp(json_string_value(json_array_get(w, 1)), "second") == 0,
          "warnings escaped and read back");
    json_decref(r);

    /* a subset, and the operators */
    r = write_hand(&h, API_F3_CF | API_F3_OPERATORS, NULL, 0);
    REQUIRE(r, "no result");
    CHECK(json_object_size(r) == 3 && json_object_get(r, "CF") && json_object_get(r, "operators"),
          "only dim, CF and operators");
    const json_t *ops = json_object_get(r, "operators");
    size_t r1, c1, r2, c2, r3, c3;
    int *d1 = csr_dense(json_object_get(ops, "d1"), &r1, &c1);
    int *d2 = csr_dense(json_object_get(ops, "d2"), &r2, &c2);
    int *d3 = csr_dense(json_object_get(ops, "d3"), &r3, &c3);
    CHECK(d1 && d2 && d3, "operators malformed");
    CHECK(r1 == 12 && c1 == h.c.ne && r2 == h.c.ne && c2 == 5 && r3 == 5 && c3 == 1,
          "shapes %zux%zu %zux%zu %zux%zu", r1, c1, r2, c2, r3, c3);
    if (d1 && d2 && d3 && c1 == r2 && c2 == r3) {
        CHECK(product_zero(d1, d2, r1, c1, c2), "d1 d2 != 0");
        CHECK(product_zero(d2, d3, r2, c2, c3), "d2 d3 != 0");
        CHECK(d1[0 * c1 + 0] == -1, "d1: -1 at EV[0][0]");
    }
    free(d1), free(d2), free(d3);
    json_decref(r);

    r = write_hand(&h, 0, NULL, 0);
    CHECK(r && json_object_size(r) == 1, "fields [] gives {\"dim\":3}");
    json_decref(r);
}

TEST(writer_refuses_a_broken_complex)
{
    hand3 h;
    api_buf b = {0};
    api_error err;
    api_lar3_fmt fmt = {.fields = API_F3_DEFAULT | API_F3_OPERATORS};
    hand_build(&h);
    h.cf[2] = 99;
    CHECK(api_lar3_write(&b, &h.c, &fmt, &err) == API_EINTERNAL &&
              strstr(err.msg, "internal error: the 3-complex's cf is invalid"),
          "%s", err.msg);
    hand_build(&h);
    h.fc_off[3] = 7; /* beyond fc */
    CHECK(api_lar3_write(&b, &h.c, &fmt, &err) == API_EINTERNAL, "fc_off: %s", err.msg);
    hand_build(&h);
    double V[36];
    memcpy(V, HV, sizeof V);
    V[5] = NAN;
    h.c.V = V;
    CHECK(api_lar3_write(&b, &h.c, &fmt, &err) == API_EINTERNAL && strstr(err.msg, "V"), "%s",
          err.msg);
    hand_build(&h);
    h.fe[0] = 0;
    CHECK(api_lar3_write(&b, &h.c, &fmt, &err) == API_EINTERNAL, "fe 0: %s", err.msg);
    api_buf_free(&b);
    /* an empty complex is fine */
    lar3 empty = {0};
    api_buf e = {0};
    CHECK(api_lar3_write(&e, &empty, &fmt, &err) == API_OK, "empty: %s", err.msg);
    const char *want = "{\"dim\":3,\"V\":[],\"EV\":[],\"FV\":[],\"FE\":[],\"holes\":{},\"CF\":[],"
                       "\"CV\":[],\"exterior\":[],\"operators\":{\"d1\":{\"shape\":[0,0],";
    CHECK(e.p && strncmp(e.p, want, strlen(want)) == 0, "empty: %s", e.p ? e.p : "(null)");
    api_buf_free(&e);
}

/* ---- OBJ ------------------------------------------------------------------------------------- */

typedef struct objmesh {
    size_t nv, nt;
    double *v;     /* 3 per vertex */
    size_t *t;     /* 3 per triangle, 0-based */
    size_t *group; /* per triangle: the index of its "g" */
    size_t ngroups;
    int ok;
} objmesh;

static void obj_free(objmesh *m)
{
    free(m->v);
    free(m->t);
    free(m->group);
    memset(m, 0, sizeof *m);
}

/* Parses what render_obj writes: comments, v, g, f lines; ok = 0 on anything else. */
static objmesh obj_parse(const char *text)
{
    objmesh m = {0};
    size_t capv = 0, capt = 0;
    m.ok = 1;
    for (const char *p = text; *p;) {
        const char *e = strchr(p, '\n');
        char line[256];
        size_t n = e ? (size_t)(e - p) : strlen(p);
        if (n >= sizeof line) n = sizeof line - 1;
        memcpy(line, p, n);
        line[n] = 0;
        p += e ? (size_t)(e - p) + 1 : strlen(p);
        double x, y, z;
        size_t a, b, c;
        char tail;
        if (line[0] == '#') continue;
        if (sscanf(line, "v %lf %lf %lf %c", &x, &y, &z, &tail) == 3) {
            if (m.nv == capv) m.v = realloc(m.v, 3 * (capv = capv ? 2 * capv : 64) * sizeof *m.v);
            m.v[3 * m.nv] = x, m.v[3 * m.nv + 1] = y, m.v[3 * m.nv + 2] = z;
            m.nv++;
        } else if (sscanf(line, "f %zu %zu %zu %c", &a, &b, &c, &tail) == 3) {
            if (m.nt == capt) {
                capt = capt ? 2 * capt : 64;
                m.t = realloc(m.t, 3 * capt * sizeof *m.t);
                m.group = realloc(m.group, capt * sizeof *m.group);
            }
            if (a < 1 || b < 1 || c < 1 || m.ngroups == 0) m.ok = 0;
            m.t[3 * m.nt] = a - 1, m.t[3 * m.nt + 1] = b - 1, m.t[3 * m.nt + 2] = c - 1;
            m.group[m.nt++] = m.ngroups - 1;
        } else if (strncmp(line, "g cell", 6) == 0) {
            if ((size_t)atol(line + 6) != m.ngroups) m.ok = 0;
            m.ngroups++;
        } else {
            m.ok = 0;
        }
    }
    for (size_t i = 0; i < 3 * m.nt; i++)
        if (m.t[i] >= m.nv) m.ok = 0;
    return m;
}

static void tri_normal(const objmesh *m, size_t t, double n[3])
{
    const double *a = m->v + 3 * m->t[3 * t], *b = m->v + 3 * m->t[3 * t + 1],
                 *c = m->v + 3 * m->t[3 * t + 2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

static double tri_area(const objmesh *m, size_t t)
{
    double n[3];
    tri_normal(m, t, n);
    return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 2;
}

/* Signed volume enclosed by the triangles of group g (divergence theorem). */
static double group_volume(const objmesh *m, size_t g)
{
    double s = 0;
    for (size_t t = 0; t < m->nt; t++) {
        if (m->group[t] != g) continue;
        const double *a = m->v + 3 * m->t[3 * t], *b = m->v + 3 * m->t[3 * t + 1],
                     *c = m->v + 3 * m->t[3 * t + 2];
        s += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
             a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
    return s / 6;
}

/* Every directed edge of group g's triangles (by vertex position) has its reverse exactly
 * once: closed and consistently oriented.  Returns the number of edges without a partner. */
static size_t group_open_edges(const objmesh *m, size_t g)
{
    size_t bad = 0;
    for (size_t t = 0; t < m->nt; t++) {
        if (m->group[t] != g) continue;
        for (int i = 0; i < 3; i++) {
            const double *a = m->v + 3 * m->t[3 * t + i], *b = m->v + 3 * m->t[3 * t + (i + 1) % 3];
            size_t fwd = 0, rev = 0;
            for (size_t u = 0; u < m->nt; u++) {
                if (m->group[u] != g) continue;
                for (int j = 0; j < 3; j++) {
                    const double *p = m->v + 3 * m->t[3 * u + j],
                                 *q = m->v + 3 * m->t[3 * u + (j + 1) % 3];
                    if (!memcmp(p, a, 3 * sizeof *p) && !memcmp(q, b, 3 * sizeof *q)) fwd++;
                    if (!memcmp(p, b, 3 * sizeof *p) && !memcmp(q, a, 3 * sizeof *q)) rev++;
                }
            }
            if (fwd != 1 || rev != 1) bad++;
        }
    }
    return bad;
}

static objmesh obj_of(const char *json, double explode, int *rc, api_error *err)
{
    render_opts o = RENDER_OPTS_INIT;
    char *out = NULL;
    size_t len = 0;
    objmesh m = {0};
    o.explode = explode;
    *rc = render_obj(json, strlen(json), &o, &out, &len, err);
    if (*rc == API_OK) {
        m = obj_parse(out);
        if (len != strlen(out) || len == 0 || out[len - 1] != '\n') m.ok = 0;
    }
    free(out);
    return m;
}

#define CUBE_RESULT                                                                                \
    "{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{},\"CF\":[[1,2,3,4,5,6]],"          \
    "\"exterior\":[-1,-2,-3,-4,-5,-6]}"

TEST(obj_cube_is_closed_and_outward)
{
    api_error err;
    int rc;
    objmesh m = obj_of(CUBE_RESULT, 1, &rc, &err);
    REQUIRE(rc == API_OK, "render_obj: %d %s", rc, err.msg);
    CHECK(m.ok, "unparseable OBJ");
    CHECK(m.nv == 8 && m.nt == 12 && m.ngroups == 1, "%zu v, %zu f, %zu g", m.nv, m.nt, m.ngroups);
    CHECK(group_open_edges(&m, 0) == 0, "cube not closed and consistent");
    CHECK(fabs(group_volume(&m, 0) - 1) < 1e-12, "volume %g", group_volume(&m, 0));
    double area = 0;
    for (size_t t = 0; t < m.nt; t++) {
        double n[3], c[3] = {0, 0, 0};
        tri_normal(&m, t, n);
        for (int i = 0; i < 3; i++)
            for (int a = 0; a < 3; a++) c[a] += m.v[3 * m.t[3 * t + i] + a] / 3;
        CHECK(n[0] * (c[0] - 0.5) + n[1] * (c[1] - 0.5) + n[2] * (c[2] - 0.5) > 0,
              "triangle %zu faces in", t);
        area += tri_area(&m, t);
    }
    CHECK(fabs(area - 6) < 1e-12, "area %g", area);
    obj_free(&m);
    /* the same cell listed with every face reversed in the JSON and -(f+1) in CF: same mesh */
    m = obj_of("{\"dim\":3,\"V\":" CUBE_V
               ",\"FV\":[[1,2,3,0],[7,6,5,4],[4,5,1,0],[5,6,2,1],[6,7,3,2],[7,4,0,3]],"
               "\"CF\":[[-1,-2,-3,-4,-5,-6]]}",
               1, &rc, &err);
    CHECK(rc == API_OK && m.ok && m.nt == 12 && group_open_edges(&m, 0) == 0 &&
              fabs(group_volume(&m, 0) - 1) < 1e-12,
          "reversed faces, -(f+1): %d %s", rc, err.msg);
    obj_free(&m);
}

/* ---- faces: polygons with holes in tilted planes --------------------------------------------- */

typedef struct poly {
    const char *name;
    size_t nring;
    size_t len[4];    /* ring lengths: outer, holes */
    double pt[40][2]; /* the rings' points one after the other */
    double area;      /* outer minus holes */
} poly;

static const poly polys[] = {
    {"L", 1, {6}, {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}, 3},
    {"L with flat vertices",
     1,
     {8},
     {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}, {0, 1}},
     3},
    {"square with a hole",
     2,
     {4, 4},
     {{0, 0}, {4, 0}, {4, 4}, {0, 4}, {1, 1}, {1, 3}, {3, 3}, {3, 1}},
     12},
    {"square with a hole given counter-clockwise",
     2,
     {4, 4},
     {{0, 0}, {4, 0}, {4, 4}, {0, 4}, {1, 1}, {3, 1}, {3, 3}, {1, 3}},
     12},
    {"U with three holes",
     4,
     {8, 4, 4, 4},
     {{0, 0},     {6, 0},     {6, 4},     {4, 4},     {4, 2},     {2, 2},     {2, 4},
      {0, 4},     {0.5, 0.5}, {0.5, 1.5}, {1.5, 1.5}, {1.5, 0.5}, {4.5, 0.5}, {4.5, 1.5},
      {5.5, 1.5}, {5.5, 0.5}, {0.5, 2.5}, {0.5, 3.5}, {1.5, 3.5}, {1.5, 2.5}},
     17},
    {"comb",
     1,
     {12},
     {{0, 0},
      {5, 0},
      {5, 3},
      {4, 3},
      {4, 1},
      {3, 1},
      {3, 3},
      {2, 3},
      {2, 1},
      {1, 1},
      {1, 3},
      {0, 3}},
     11},
    {"holes sharing the rightmost x",
     3,
     {4, 4, 4},
     {{0, 0},
      {6, 0},
      {6, 6},
      {0, 6},
      {1, 1},
      {1, 2},
      {4, 2},
      {4, 1},
      {2, 3},
      {2, 4},
      {4, 4},
      {4, 3}},
     36 - 3 - 2},
};

/* The plane p = O + x U + y W (U, W orthonormal): its normal U x W. */
typedef struct plane {
    double O[3], U[3], W[3];
} plane;

static const plane planes[] = {
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}},      /* z = 0, normal +z */
    {{1, 2, 3}, {1, 0, 0}, {0, 0.6, 0.8}},  /* normal (0, -0.8, 0.6): -y dominates */
    {{-5, 0, 2}, {0.6, 0.8, 0}, {0, 0, 1}}, /* normal (0.8, -0.6, 0): +x */
    {{0, 0, 7}, {0, 1, 0}, {1, 0, 0}},      /* normal -z */
};

/* The result JSON of polygon p in plane q as one face on one cell (sign ±1). */
static char *poly_result(const poly *p, const plane *q, int sign)
{
    size_t np = 0, cap = 8192, w = 0;
    char *s = malloc(cap);
    for (size_t r = 0; r < p->nring; r++) np += p->len[r];
    w += (size_t)snprintf(s + w, cap - w, "{\"dim\":3,\"V\":[");
    for (size_t i = 0; i < np; i++) {
        double x = p->pt[i][0], y = p->pt[i][1];
        w += (size_t)snprintf(s + w, cap - w, "%s[%.17g,%.17g,%.17g]", i ? "," : "",
                              q->O[0] + x * q->U[0] + y * q->W[0],
                              q->O[1] + x * q->U[1] + y * q->W[1],
                              q->O[2] + x * q->U[2] + y * q->W[2]);
    }
    size_t at = 0;
    for (size_t r = 0; r < p->nring; r++) {
        w += (size_t)snprintf(s + w, cap - w,
                              r == 0   ? "],\"FV\":[["
                              : r == 1 ? "]],\"holes\":{\"0\":[["
                                       : "],[");
        for (size_t i = 0; i < p->len[r]; i++)
            w += (size_t)snprintf(s + w, cap - w, "%s%zu", i ? "," : "", at++);
    }
    snprintf(s + w, cap - w, "]]%s,\"CF\":[[%d]]}", p->nring > 1 ? "}" : "", sign);
    return s;
}

TEST(obj_faces_nonconvex_and_holed)
{
    for (size_t i = 0; i < sizeof polys / sizeof *polys; i++)
        for (size_t j = 0; j < sizeof planes / sizeof *planes; j++)
            for (int sign = -1; sign <= 1; sign += 2) {
                const poly *p = &polys[i];
                const plane *q = &planes[j];
                char *json = poly_result(p, q, sign);
                api_error err;
                int rc;
                objmesh m = obj_of(json, 1, &rc, &err);
                size_t n = 0;
                double nrm[3] = {q->U[1] * q->W[2] - q->U[2] * q->W[1],
                                 q->U[2] * q->W[0] - q->U[0] * q->W[2],
                                 q->U[0] * q->W[1] - q->U[1] * q->W[0]},
                       area = 0;
                for (size_t r = 0; r < p->nring; r++) n += p->len[r];
                CHECK(rc == API_OK && m.ok, "%s, plane %zu: %d %s", p->name, j, rc, err.msg);
                CHECK(m.nt == n + 2 * (p->nring - 1) - 2, "%s, plane %zu: %zu triangles, want %zu",
                      p->name, j, m.nt, n + 2 * (p->nring - 1) - 2);
                for (size_t t = 0; t < m.nt; t++) {
                    double tn[3];
                    tri_normal(&m, t, tn);
                    double d = sign * (tn[0] * nrm[0] + tn[1] * nrm[1] + tn[2] * nrm[2]);
                    CHECK(d > 1e-12, "%s, plane %zu, sign %d: triangle %zu faces wrong (%g)",
                          p->name, j, sign, t, d);
                    area += tri_area(&m, t);
                }
                CHECK(fabs(area - p->area) < 1e-9 * p->area, "%s, plane %zu: area %.17g, want %g",
                      p->name, j, area, p->area);
                obj_free(&m);
                free(json);
            }
}

/* Random star-shaped faces (simple by construction) with a square hole about the centre. */
TEST(obj_random_star_faces)
{
    uint64_t seed = 12345;
    for (int iter = 0; iter < 300; iter++) {
        poly p = {.name = "star"};
        size_t n = 5 + (size_t)(test_rnd(&seed) * 30);
        double rmin = INFINITY, area = 0;
        if (n > 30) n = 30;
        for (size_t i = 0; i < n; i++) {
            double a = 2 * M_PI * (i + 0.2 + 0.6 * test_rnd(&seed)) / (double)n;
            double r = 1 + 3 * test_rnd(&seed);
            /* on a coarse grid now and then, so that flat and repeated directions happen */
            if (iter % 3 == 0) r = floor(r * 4) / 4;
            p.pt[i][0] = r * cos(a);
            p.pt[i][1] = r * sin(a);
            rmin = fmin(rmin, r);
        }
        p.len[0] = n;
        p.nring = 1;
        for (size_t i = 0; i < n; i++)
            area += p.pt[i][0] * p.pt[(i + 1) % n][1] - p.pt[(i + 1) % n][0] * p.pt[i][1];
        area /= 2;
        int hole = n >= 8 && iter % 2; /* max gap < pi/2: the hole's corners are inside */
        if (hole) {
            double h = 0.25 * rmin;
            const double sq[4][2] = {{-h, -h}, {-h, h}, {h, h}, {h, -h}}; /* clockwise */
            for (int k = 0; k < 4; k++) p.pt[n + k][0] = sq[k][0], p.pt[n + k][1] = sq[k][1];
            p.len[1] = 4;
            p.nring = 2;
            area -= 4 * h * h;
        }
        p.area = area;
        const plane *q = &planes[iter % 4];
        char *json = poly_result(&p, q, 1);
        api_error err;
        int rc;
        objmesh m = obj_of(json, 1, &rc, &err);
        double sum = 0, nrm[3] = {q->U[1] * q->W[2] - q->U[2] * q->W[1],
                                  q->U[2] * q->W[0] - q->U[0] * q->W[2],
                                  q->U[0] * q->W[1] - q->U[1] * q->W[0]};
        int wrong = 0;
        REQUIRE(rc == API_OK && m.ok, "iter %d: %d %s", iter, rc, err.msg);
        for (size_t t = 0; t < m.nt; t++) {
            double tn[3];
            tri_normal(&m, t, tn);
            if (tn[0] * nrm[0] + tn[1] * nrm[1] + tn[2] * nrm[2] < -1e-12) wrong++;
            sum += tri_area(&m, t);
        }
        CHECK(m.nt == n + 4 * (size_t)hole + 2 * (size_t)hole - 2, "iter %d: %zu triangles", iter,
              m.nt);
        CHECK(wrong == 0, "iter %d: %d triangles face the wrong way", iter, wrong);
        CHECK(fabs(sum - area) < 1e-9 * area, "iter %d: area %.17g, want %.17g", iter, sum, area);
        obj_free(&m);
        free(json);
    }
}

/* Two unit cubes side by side, [0,1]^3 and [1,2]x[0,1]^2, sharing face 5 (x = 1). */
#define TWO_CELLS                                                                                  \
    "{\"dim\":3,\"V\":[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1],"           \
    "[2,0,0],[2,1,0],[2,1,1],[2,0,1]],"                                                            \
    "\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[2,3,7,6],[3,0,4,7],[1,2,6,5],"                         \
    "[1,2,9,8],[5,11,10,6],[1,8,11,5],[2,6,10,9],[8,9,10,11]],"                                    \
    "\"CF\":[[1,2,3,4,5,6],[-6,7,8,9,10,11]]}"

TEST(obj_explode_moves_cells_apart)
{
    api_error err;
    int rc;
    objmesh m = obj_of(TWO_CELLS, 1, &rc, &err);
    REQUIRE(rc == API_OK && m.ok, "%d %s", rc, err.msg);
    CHECK(m.nv == 12 && m.ngroups == 2 && m.nt == 24, "%zu v %zu g %zu f", m.nv, m.ngroups, m.nt);
    for (size_t g = 0; g < 2; g++) {
        CHECK(group_open_edges(&m, g) == 0, "cell %zu not closed", g);
        CHECK(fabs(group_volume(&m, g) - 1) < 1e-12, "cell %zu volume %g", g, group_volume(&m, g));
    }
    obj_free(&m);
    /* k = 3: box centre (1, .5, .5), centroids (.5, .5, .5) and (1.5, .5, .5): each cell moves
     * by 2 * (-.5, 0, 0) and 2 * (.5, 0, 0), and writes its own 8 vertices */
    m = obj_of(TWO_CELLS, 3, &rc, &err);
    REQUIRE(rc == API_OK && m.ok, "%d %s", rc, err.msg);
    CHECK(m.nv == 16 && m.ngroups == 2 && m.nt == 24, "%zu v %zu g %zu f", m.nv, m.ngroups, m.nt);
    for (size_t t = 0; t < m.nt; t++)
        for (int i = 0; i < 3; i++) {
            size_t v = m.t[3 * t + i];
            CHECK(m.group[t] == 0 ? v < 8 : v >= 8, "triangle %zu uses vertex %zu of another cell",
                  t, v);
            double x = m.v[3 * v];
            CHECK(m.group[t] == 0 ? x >= -1 && x <= 0 : x >= 2 && x <= 3,
                  "cell %zu vertex at x = %g", m.group[t], x);
        }
    for (size_t g = 0; g < 2; g++) {
        CHECK(group_open_edges(&m, g) == 0, "exploded cell %zu not closed", g);
        CHECK(fabs(group_volume(&m, g) - 1) < 1e-12, "exploded cell %zu volume", g);
    }
    obj_free(&m);
}

TEST(obj_bad_input_is_a_value)
{
    static const struct {
        const char *json;
        double explode;
        const char *prefix;
    } cases[] = {
        {"", 1, "result: empty"},
        {"{\"dim\":3,", 1, "result: malformed JSON at line 1"},
        {"[3]", 1, "result: expected a JSON object"},
        {"{\"V\":[]}", 1, "dim: required"},
        {"{\"dim\":2,\"V\":[[0,0]],\"FV\":[]}", 1,
         "dim: expected 3 (OBJ is written of 3D results), got 2"},
        {"{\"dim\":\"3\"}", 1, "dim: expected 3"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}", 1, "CF: required"},
        {"{\"dim\":3,\"FV\":" CUBE_FV ",\"CF\":[]}", 1, "V: required"},
        {"{\"dim\":3,\"V\":{},\"FV\":[],\"CF\":[]}", 1, "V: expected an array"},
        {"{\"dim\":3,\"V\":[[0,0]],\"FV\":[],\"CF\":[]}", 1, "V[0]: expected 3 finite numbers"},
        {"{\"dim\":3,\"V\":[[0,0,\"0\"]],\"FV\":[],\"CF\":[]}", 1, "V[0]: expected 3 finite"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":[[0,1,8]],\"CF\":[]}", 1,
         "FV[0][2]: expected a vertex index < 8"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":[[0,1,2],5],\"CF\":[]}", 1,
         "FV[1]: expected an array of vertex indices"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"CF\":[[1,2,7]]}", 1,
         "CF[0][2]: expected a signed face +(f+1) or -(f+1), 0 <= f < 6"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"CF\":[[1],[0]]}", 1,
         "CF[1][0]: expected"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"CF\":[[-7]]}", 1, "CF[0][0]: expected"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"CF\":[1]}", 1,
         "CF[0]: expected an array"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"CF\":{}}", 1, "CF: expected an array"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{\"6\":[[0,1,2]]},\"CF\":[]}", 1,
         "holes.6: not a face"},
        {"{\"dim\":3,\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"holes\":{\"0\":[[0,1,20]]},\"CF\":[]}",
         1, "holes.0[0][2]: expected a vertex index < 8"},
        {CUBE_RESULT, 0.5, "explode: expected a number in [1, 100]"},
        {CUBE_RESULT, 101, "explode: expected a number in [1, 100]"},
        {CUBE_RESULT, NAN, "explode: expected a number in [1, 100]"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        render_opts o = RENDER_OPTS_INIT;
        char *out = (char *)1;
        size_t len = 9;
        api_error err = {0};
        o.explode = cases[i].explode;
        int rc = render_obj(cases[i].json, strlen(cases[i].json), &o, &out, &len, &err);
        CHECK(rc == API_EINVALID && out == NULL && len == 0, "case %zu: rc %d", i, rc);
        CHECK(strncmp(err.msg, cases[i].prefix, strlen(cases[i].prefix)) == 0,
              "case %zu: \"%s\", want \"%s\"", i, err.msg, cases[i].prefix);
    }
    /* every truncation and every byte changed of a valid result: a value, never a crash */
    const char *good = TWO_CELLS;
    size_t n = strlen(good);
    char *buf = malloc(n + 1);
    for (size_t k = 0; k <= n; k++) {
        char *out = NULL;
        size_t len = 0;
        api_error err;
        int rc = render_obj(good, k, NULL, &out, &len, &err);
        CHECK(k == n ? rc == API_OK : rc == API_EINVALID, "prefix %zu: rc %d", k, rc);
        free(out);
        if (k == n) break;
        memcpy(buf, good, n + 1);
        buf[k] = buf[k] == '1' ? '9' : buf[k] == '-' ? '5' : '1';
        rc = render_obj(buf, n, NULL, &out, &len, &err);
        CHECK(rc == API_OK || rc == API_EINVALID, "byte %zu changed: rc %d", k, rc);
        free(out);
    }
    free(buf);
}

/* ---- CORE: these run the 3D core (core/arr3.c) and assert its counts ------------------------ */

/* CORE: two unit cubes, the second moved by (0.5, 0.5, 0.5). */
TEST(core_two_cubes)
{
    json_t *r = run_ok("{\"kind\":\"solids\",\"solids\":[" CUBE "," CUBE_HALF
                       "],\"options\":{\"operators\":true}}");
    REQUIRE(r, "no result");
    CHECK(stat_of(r, "V") == 22 && stat_of(r, "E") == 36 && stat_of(r, "F") == 18 &&
              stat_of(r, "C") == 3,
          "V %lld E %lld F %lld C %lld, want 22 36 18 3", stat_of(r, "V"), stat_of(r, "E"),
          stat_of(r, "F"), stat_of(r, "C"));
    CHECK(json_array_size(json_object_get(r, "V")) == 22 &&
              json_array_size(json_object_get(r, "EV")) == 36 &&
              json_array_size(json_object_get(r, "FV")) == 18 &&
              json_array_size(json_object_get(r, "FE")) == 18 &&
              json_array_size(json_object_get(r, "CF")) == 3 &&
              json_array_size(json_object_get(r, "CV")) == 3,
          "row counts");
    CHECK(stat_of(r, "input_solids") == 2 && stat_of(r, "input_faces") == 12, "input counts");
    const json_t *vols = json_object_get(json_object_get(r, "stats"), "volumes");
    double sum = 0;
    for (size_t i = 0; i < json_array_size(vols); i++)
        sum += json_number_value(json_array_get(vols, i));
    CHECK(json_array_size(vols) == 3 && fabs(sum - 1.875) < 1e-12, "volumes add up to %g", sum);
    CHECK(json_array_size(json_object_get(json_object_get(r, "stats"), "warnings")) == 0,
          "warnings");
    /* every face on two cells (exterior included), once with each sign */
    int seen[18][2] = {{0}};
    const json_t *CF = json_object_get(r, "CF"), *ext = json_object_get(r, "exterior");
    for (size_t c = 0; c <= json_array_size(CF); c++) {
        const json_t *row = c < json_array_size(CF) ? json_array_get(CF, c) : ext;
        for (size_t i = 0; i < json_array_size(row); i++) {
            long long s = ival(json_array_get(row, i));
            if (s != 0 && llabs(s) <= 18) seen[llabs(s) - 1][s > 0]++;
        }
    }
    for (int f = 0; f < 18; f++)
        CHECK(seen[f][0] == 1 && seen[f][1] == 1, "face %d: %d -, %d +", f, seen[f][0], seen[f][1]);
    const json_t *ops = json_object_get(r, "operators");
    size_t r1, c1, r2, c2, r3, c3;
    int *d1 = csr_dense(json_object_get(ops, "d1"), &r1, &c1);
    int *d2 = csr_dense(json_object_get(ops, "d2"), &r2, &c2);
    int *d3 = csr_dense(json_object_get(ops, "d3"), &r3, &c3);
    CHECK(d1 && d2 && d3 && r1 == 22 && c1 == 36 && r2 == 36 && c2 == 18 && r3 == 18 && c3 == 3,
          "operator shapes");
    if (d1 && d2 && d3 && c1 == r2 && c2 == r3) {
        CHECK(product_zero(d1, d2, r1, c1, c2), "d1 d2 != 0");
        CHECK(product_zero(d2, d3, r2, c2, c3), "d2 d3 != 0");
    }
    free(d1), free(d2), free(d3);

    /* CORE: the OBJ of this result: every cell closed, outward, of its volume */
    char *txt = json_dumps(r, JSON_COMPACT | JSON_REAL_PRECISION(17));
    api_error err;
    int rc;
    objmesh m = obj_of(txt, 1, &rc, &err);
    CHECK(rc == API_OK && m.ok && m.ngroups == 3, "obj: %d %s", rc, err.msg);
    for (size_t g = 0; rc == API_OK && g < m.ngroups && g < 3; g++) {
        CHECK(group_open_edges(&m, g) == 0, "cell %zu not closed in the OBJ", g);
        CHECK(fabs(group_volume(&m, g) - json_number_value(json_array_get(vols, g))) < 1e-9,
              "cell %zu: OBJ volume %g, stats %g", g, group_volume(&m, g),
              json_number_value(json_array_get(vols, g)));
    }
    obj_free(&m);
    free(txt);
    json_decref(r);
}

/* CORE: a cube with one face walked the wrong way, and one turned inside out: the fixed copy
 * runs, stats.warnings says what changed. */
TEST(core_orientation_fixed_with_warning)
{
    json_t *r = run_ok(SOLIDS("{\"V\":" CUBE_V ",\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],"
                              "[2,3,7,6],[3,7,4,0]]}"));
    REQUIRE(r, "no result");
    const json_t *w = json_object_get(json_object_get(r, "stats"), "warnings");
    CHECK(json_array_size(w) == 1 &&
              strncmp(json_string_value(json_array_get(w, 0)),
                      "solids[0]: orientation inconsistent at 4 edges", 46) == 0,
          "warning %s", json_string_value(json_array_get(w, 0)));
    CHECK(stat_of(r, "C") == 1 && stat_of(r, "F") == 6, "C %lld F %lld", stat_of(r, "C"),
          stat_of(r, "F"));
    json_decref(r);
    r = run_ok(SOLIDS("{\"V\":" CUBE_V ",\"FV\":[[0,1,2,3],[4,7,6,5],[0,4,5,1],[1,5,6,2],"
                      "[2,6,7,3],[3,7,4,0]]}"));
    REQUIRE(r, "no result");
    w = json_object_get(json_object_get(r, "stats"), "warnings");
    CHECK(json_array_size(w) == 1 && strncmp(json_string_value(json_array_get(w, 0)),
                                             "solids[0]: inward oriented", 26) == 0,
          "warning %s", json_string_value(json_array_get(w, 0)));
    CHECK(stat_of(r, "C") == 1, "C %lld", stat_of(r, "C"));
    const json_t *vols = json_object_get(json_object_get(r, "stats"), "volumes");
    CHECK(fabs(json_number_value(json_array_get(vols, 0)) - 1) < 1e-12, "volume");
    json_decref(r);
}

/* The unit cube whose top has the flat triangle 4 6 8 (8 = [0.5,0.5,1]) among the faces fv,
 * that one at index flat: one warning for it, one cell of volume 1; *fe its F and E. */
static void flat_top_cube(const char *fv, int flat, long long *fe)
{
    char body[512], want[64];
    snprintf(body, sizeof body,
             SOLIDS("{\"V\":[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1],"
                    "[0.5,0.5,1]],\"FV\":[%s]}"),
             fv);
    snprintf(want, sizeof want, "solids[0].FV[%d]: degenerate on the grid", flat);
    fe[0] = fe[1] = -1;
    json_t *r = run_ok(body);
    REQUIRE(r, "no result");
    const json_t *w = json_object_get(json_object_get(r, "stats"), "warnings");
    CHECK(json_array_size(w) == 1 &&
              strncmp(json_string_value(json_array_get(w, 0)), want, strlen(want)) == 0,
          "warning %s", json_string_value(json_array_get(w, 0)));
    const json_t *vols = json_object_get(json_object_get(r, "stats"), "volumes");
    CHECK(stat_of(r, "C") == 1 && fabs(json_number_value(json_array_get(vols, 0)) - 1) < 1e-15,
          "C %lld volume %g", stat_of(r, "C"), json_number_value(json_array_get(vols, 0)));
    fe[0] = stat_of(r, "F"), fe[1] = stat_of(r, "E");
    json_decref(r);
}

/* CORE: faces that the grid flattens are left out with a warning, in a soup and in a solid (a
 * cube whose top has a flat triangle along its diagonal: the same cube). */
TEST(core_flat_faces_left_out)
{
    json_t *r = run_ok("{\"kind\":\"solids\",\"faces\":{\"V\":[[0,0,0],[1,0,0],[1,1,0],[2,0,0]],"
                       "\"FV\":[[0,1,2],[0,1,3],[0,2,2,0]]}}");
    REQUIRE(r, "no result");
    const json_t *w = json_object_get(json_object_get(r, "stats"), "warnings");
    CHECK(json_array_size(w) == 2 &&
              strncmp(json_string_value(json_array_get(w, 0)),
                      "faces.FV[1]: degenerate on the grid of step", 43) == 0 &&
              strstr(json_string_value(json_array_get(w, 1)), "fewer than 3 distinct"),
          "warnings %s", json_string_value(json_array_get(w, 0)));
    CHECK(stat_of(r, "F") == 1 && stat_of(r, "V") == 3, "F %lld V %lld", stat_of(r, "F"),
          stat_of(r, "V"));
    json_decref(r);
    /* the top 4 5 6 7 as triangles 4 5 6 and 4 6 7 with the flat 4 6 8 between (8 = middle
     * of 4-6, a vertex of 4 6 7 only: 4 8 6 7) */
    long long fe_mid[2];
    flat_top_cube("[0,3,2,1],[4,5,6],[4,6,8],[8,6,7,4],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]", 2,
                  fe_mid);
    /* the flat face last, after every face that went as it is: the input's pairs of the run are
     * still implicit when the check's edge pairing is mapped onto the pieces (the same cube) */
    long long fe_last[2];
    flat_top_cube("[0,3,2,1],[4,5,6],[8,6,7,4],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7],[4,6,8]", 7,
                  fe_last);
    CHECK(fe_last[0] == fe_mid[0] && fe_last[1] == fe_mid[1],
          "F %lld E %lld with the flat face last, %lld %lld in the middle", fe_last[0], fe_last[1],
          fe_mid[0], fe_mid[1]);
}

/* CORE: a face soup of one square: one face, no cell; and the fields option. */
TEST(core_soup_and_fields)
{
    json_t *r = run_ok("{\"kind\":\"solids\",\"faces\":{\"V\":[[0,0,0],[1,0,0],[1,1,0],[0,1,0]],"
                       "\"FV\":[[0,1,2,3]]}}");
    REQUIRE(r, "no result");
    CHECK(stat_of(r, "V") == 4 && stat_of(r, "E") == 4 && stat_of(r, "F") == 1 &&
              stat_of(r, "C") == 0,
          "V %lld E %lld F %lld C %lld", stat_of(r, "V"), stat_of(r, "E"), stat_of(r, "F"),
          stat_of(r, "C"));
    json_decref(r);
    r = run_ok("{\"kind\":\"solids\",\"solids\":[" CUBE "],\"options\":{\"fields\":[\"CF\","
               "\"V\",\"FV\",\"stats\"],\"precision\":0.001}}");
    REQUIRE(r, "no result");
    CHECK(json_object_size(r) == 5 && json_object_get(r, "CF") && json_object_get(r, "stats") &&
              json_object_get(r, "V") && json_object_get(r, "FV"),
          "fields CF, V, FV and stats only");
    CHECK(json_number_value(json_object_get(json_object_get(r, "stats"), "precision")) == 0.001,
          "precision");
    json_decref(r);
    /* the default precision: the power of two above extent * 2^-30 (a cube of side 3: 2^-28) */
    r = run_ok("{\"kind\":\"solids\",\"solids\":[{\"V\":[[0,0,0],[3,0,0],[3,3,0],[0,3,0],[0,0,3],"
               "[3,0,3],[3,3,3],[0,3,3]],\"FV\":" CUBE_FV
               "}],\"options\":{\"fields\":[\"stats\"]}}");
    REQUIRE(r, "no result");
    CHECK(json_number_value(json_object_get(json_object_get(r, "stats"), "precision")) ==
              ldexp(1, -28),
          "default precision %.17g",
          json_number_value(json_object_get(json_object_get(r, "stats"), "precision")));
    json_decref(r);
}

/* CORE: no solids: an empty complex, with the precision it would have used. */
TEST(core_no_solids)
{
    json_t *r = run_ok("{\"kind\":\"solids\",\"solids\":[]}");
    REQUIRE(r, "no result");
    CHECK(stat_of(r, "V") == 0 && stat_of(r, "C") == 0 &&
              json_array_size(json_object_get(r, "CF")) == 0 &&
              json_number_value(json_object_get(json_object_get(r, "stats"), "precision")) == 1,
          "empty complex");
    json_decref(r);
}

/* ---- faces on the grid: touching, crossing, snapped (core/facecheck.c) ---------------------- */

#define END NAN /* ends a cycle of a face's points; two end the face */

/* A request for the prism of height 4 over the face (x, y points, cycles ended by END, the
 * last by two; the outer cycle counter-clockwise, holes clockwise): every cycle point its own
 * bottom and top vertex (2i, 2i + 1), so touching cycles share positions, not indices; face 0
 * the top, face 1 the bottom, then the walls.  soup: the top face alone, as "faces".  The
 * caller frees. */
static char *prism_json(const double *pts, double precision, int soup)
{
    size_t cap = 1 << 16, n = 0, np = 0, ncyc = 1, k;
    char *s = malloc(cap);
    for (k = 0; !(isnan(pts[k]) && isnan(pts[k + 1])); k++)
        if (isnan(pts[k]))
            ncyc++;
        else
            np++, k++;
    size_t *start = malloc((ncyc + 1) * sizeof *start), c = 0, i = 0;
    start[0] = 0;
#define OUT(...) (n += (size_t)snprintf(s + n, cap - n, __VA_ARGS__))
    OUT("{\"kind\":\"solids\",\"%s\":%s{\"V\":[", soup ? "faces" : "solids", soup ? "" : "[");
    for (k = 0; c < ncyc; k++) {
        if (isnan(pts[k])) {
            start[++c] = i;
            continue;
        }
        OUT("%s[%.17g,%.17g,0],[%.17g,%.17g,4]", i ? "," : "", pts[k], pts[k + 1], pts[k],
            pts[k + 1]);
        i++, k++;
    }
    OUT("],\"FV\":[");
    for (int top = 1; top >= (soup ? 1 : 0); top--) {
        OUT("%s[", top ? "" : ",");
        for (size_t j = 0; j < start[1]; j++)
            OUT("%s%zu", j ? "," : "", 2 * (top ? j : start[1] - 1 - j) + (size_t)top);
        OUT("]");
    }
    for (c = 0; c < ncyc && !soup; c++)
        for (size_t j = start[c]; j < start[c + 1]; j++) {
            size_t a = 2 * j, b = 2 * (j + 1 < start[c + 1] ? j + 1 : start[c]);
            OUT(",[%zu,%zu,%zu,%zu]", a, b, b + 1, a + 1);
        }
    OUT("]");
    if (ncyc > 1) {
        OUT(",\"holes\":{");
        for (int top = 1; top >= (soup ? 1 : 0); top--) {
            OUT("%s\"%d\":[", top ? "" : ",", 1 - top);
            for (c = 1; c < ncyc; c++) {
                OUT("%s[", c > 1 ? "," : "");
                size_t len = start[c + 1] - start[c];
                for (size_t j = 0; j < len; j++)
                    OUT("%s%zu", j ? "," : "",
                        2 * (start[c] + (top ? j : len - 1 - j)) + (size_t)top);
                OUT("]");
            }
            OUT("]");
        }
        OUT("}");
    }
    OUT("}%s,\"options\":{\"precision\":%.17g}}", soup ? "" : "]", precision);
#undef OUT
    free(start);
    if (n >= cap) s[0] = 0; /* too long for the buffer: an empty body, refused */
    return s;
}

#define SQ        0, 0, 8, 0, 8, 8, 0, 8, END
#define SQ_4      0, 0, 4, 0, 8, 0, 8, 8, 0, 8, END
#define SQ_4_4    0, 0, 4, 0, 8, 0, 8, 8, 4, 8, 0, 8, END
#define FACE(...) ((const double[]){__VA_ARGS__, END, END})
#define P64       (1.0 / 64)

typedef struct grid_case {
    const char *name;
    double precision;
    const double *pts;
    double volume;    /* > 0: the arrangement's cells add up to this */
    const char *want; /* else: the 422's message */
} grid_case;

static const grid_case grid_cases[] = {
    {"hole", P64, FACE(SQ, 2, 2, 2, 4, 4, 4, 4, 2), 240, NULL},
    {"hole touching the outer cycle", P64, FACE(SQ_4, 4, 0, 3, 2, 5, 2), 248, NULL},
    {"holes touching each other", P64, FACE(SQ, 2, 2, 3, 4, 4, 2, END, 4, 2, 5, 4, 6, 2), 240,
     NULL},
    /* the face's inside in two parts; a3_triangulate splits its loop there */
    {"holes across the face", P64,
     FACE(SQ_4_4, 4, 0, 3, 2, 4, 4, 5, 2, END, 4, 4, 3, 6, 4, 8, 5, 6), 224, NULL},
    /* a triangle hole on three vertices of the outer cycle: the inside in three parts */
    {"hole on three vertices", P64,
     FACE(0, 0, 4, 0, 8, 0, 8, 4, 8, 8, 0, 8, 0, 4, END, 4, 0, 0, 4, 8, 4), 48 * 4, NULL},
    {"four holes at one point", P64,
     FACE(SQ, 4, 4, 6, 5, 6, 3, END, 4, 4, 2, 3, 2, 5, END, 4, 4, 3, 6, 5, 6, END, 4, 4, 5, 2, 3,
          2),
     224, NULL},
    {"fine grid", P64, FACE(0, 1.625, 4, 2.625, 4, 6, 2, 2.25, 0, 6), 32, NULL},
    {"hole, fine grid", P64, FACE(SQ, 3, 1, 5, 1, 4, 0.25), 253, NULL},
    {"coarse grid", 1, FACE(0, 1.625, 4, 2.625, 4, 6, 2, 2.25, 0, 6), 0,
     "solids[0].FV[0]: its outer cycle crosses itself (edges 1-3 and 5-7) on the grid of step 1"},
    {"hole, coarse grid", 1, FACE(SQ, 3, 1, 5, 1, 4, 0.25), 0,
     "solids[0].holes.0[0]: vertex 13 of one cycle lies inside edge 1-3 of another (a "
     "T-junction) on the grid of step 1"},
    {"bowtie", P64, FACE(0, 0, 8, 8, 8, 0, 0, 8), 0,
     "solids[0].FV[0]: its outer cycle crosses itself (edges 1-3 and 5-7)"},
    {"hole crossing the outer cycle", P64, FACE(SQ, 6, 2, 6, 4, 10, 4, 10, 2), 0,
     "solids[0].holes.0[0]: crosses the outer cycle (edges 3-5 and 11-13)"},
    {"holes crossing", P64, FACE(SQ, 2, 2, 2, 5, 5, 5, 5, 2, END, 4, 4, 4, 6, 6, 6, 6, 4), 0,
     "solids[0].holes.0[0]: crosses another hole (edges 11-13 and 17-19)"},
    {"pinch", P64, FACE(0, 0, 8, 0, 4, 4, 8, 8, 0, 8, 4, 4), 0,
     "solids[0].FV[0]: its outer cycle passes twice through one point (vertices 5 and 11)"},
    {"hole inside a hole", P64, FACE(SQ, 1, 1, 1, 7, 7, 7, 7, 1, END, 3, 3, 3, 5, 5, 5, 5, 3), 0,
     "solids[0].holes.0[1]: lies inside another hole (the one through vertex 9)"},
};

/* The arrangement of each case through the API (422s also at the daemon's submit), and for the
 * usable ones the complex of the core, checked (lar3_check). */
TEST(core_faces_on_the_grid)
{
    for (size_t i = 0; i < sizeof grid_cases / sizeof *grid_cases; i++) {
        const grid_case *gc = &grid_cases[i];
        char *body = prism_json(gc->pts, gc->precision, 0), *out = NULL, *canon = NULL;
        size_t outlen = 0;
        api_error err = {0};
        int rc = api_run_json(body, strlen(body), 2, &out, &outlen, &err);
        if (gc->volume > 0) {
            json_error_t je;
            json_t *r = rc == API_OK ? json_loadb(out, outlen, 0, &je) : NULL;
            CHECK(r, "%s: %d %s", gc->name, rc, err.msg);
            const json_t *vols = json_object_get(json_object_get(r, "stats"), "volumes");
            double sum = 0;
            for (size_t v = 0; v < json_array_size(vols); v++)
                sum += json_number_value(json_array_get(vols, v));
            CHECK(!r || fabs(sum - gc->volume) < 1e-9, "%s: volumes add up to %.17g, want %g",
                  gc->name, sum, gc->volume);
            json_decref(r);
        } else {
            CHECK(rc == API_EINVALID && strncmp(err.msg, gc->want, strlen(gc->want)) == 0,
                  "%s: %d \"%s\", want \"%s\"", gc->name, rc, err.msg, gc->want);
            memset(&err, 0, sizeof err);
            rc = api_check_json(body, strlen(body), &canon, NULL, &err);
            CHECK(rc == API_EINVALID && strncmp(err.msg, gc->want, strlen(gc->want)) == 0,
                  "%s: at submit %d \"%s\"", gc->name, rc, err.msg);
            free(canon);
        }
        free(out);
        free(body);
    }
}

/* A face alone in a soup whose holes cut its inside in two (each part its own piece of the
 * complex: the probe of each part must be a point of that part), and one with a hole touching
 * its outer cycle inside an edge (no neighbour there in a soup: taken). */
TEST(core_soup_faces_touching)
{
    const struct {
        const double *pts;
        long long faces;
    } soups[] = {
        {FACE(SQ_4_4, 4, 0, 3, 2, 4, 4, 5, 2, END, 4, 4, 3, 6, 4, 8, 5, 6), 2},
        {FACE(0, 0, 4, 0, 8, 0, 8, 4, 8, 8, 0, 8, 0, 4, END, 4, 0, 0, 4, 8, 4), 3},
        {FACE(SQ, 4, 0, 3, 2, 5, 2), 1},
    };
    for (size_t i = 0; i < sizeof soups / sizeof *soups; i++) {
        char *body = prism_json(soups[i].pts, P64, 1);
        json_t *r = run_ok(body);
        CHECK(r && stat_of(r, "F") == soups[i].faces && stat_of(r, "C") == 0,
              "soup %zu: F %lld, want %lld", i, r ? stat_of(r, "F") : -1, soups[i].faces);
        json_decref(r);
        free(body);
    }
}

/* The inputs fuzzing found, a 422 naming the face (were a 500). */
TEST(core_fuzz_faces_refused)
{
    size_t len;
    char *text = test_read_file("tests/fuzz/corpus/json/bowtie-face-refused.json", &len);
    REQUIRE(text, "no tests/fuzz/corpus/json/bowtie-face-refused.json");
    api_error err = {0};
    char *out = NULL;
    size_t outlen;
    int rc = api_run_json(text, len, 2, &out, &outlen, &err);
    CHECK(rc == API_EINVALID &&
              strstr(err.msg, "solids[0].FV[0]: its outer cycle crosses itself (edges 3-2 and "
                              "1-0) on the grid of step 5.96046e-08"),
          "bowtie: %d %s", rc, err.msg);
    free(text);
    /* tests/fuzz/corpus/off/grid-collapses-face-refused.off as a request (cellar solids
     * --format request): the grid step is 16384, and face 14 runs from (0, 5, 0) to the origin,
     * up to (0, 0, 603352776) and back, to (0, 2, 0) and back */
    static const char off[] =
        "{\"kind\":\"solids\",\"solids\":[{\"V\":[[2,1,2.2],[3,3,7],[72,18,6],[4,38,0],[724,3,-3],"
        "[7,32642,-1],[54,4,-3],[7,331,9885331884650],[6,1,0],[12,15,6],[0,6,7],[3,0,7],[3,0,9],"
        "[3,0,910],[3,0,0],[0,89885,0],[14,71,42],[3,26,1]],\"FV\":[[0,1,2],[0,2,3],[0,3,4],[0,"
        "4,5],[0,5,6],[0,6,7],[0,7,8],[0,8,9],[0,9,10],[0,0,1],[0,11,12],[0,12,13],[14,1,16,15],"
        "[14,15,1,0],[15,16,10,9,8,7,6,5,4,3,2,1],[16,1,13,12,11,1],[17,14,0,1]],\"holes\":{}}]}";
    memset(&err, 0, sizeof err);
    rc = api_run_json(off, strlen(off), 2, &out, &outlen, &err);
    CHECK(rc == API_EINVALID &&
              strstr(err.msg, "solids[0].FV[14]: its outer cycle runs back along itself (edges "
                              "15-16 and 6-5 overlap) on the grid of step 16384"),
          "collapsed face: %d %s", rc, err.msg);
}

/* A pyramid over a quad that is not planar and whose projection along its Newell normal's axis
 * is a dart, split along the diagonal outside the dart (q0-q2, whose triangles' normals agree
 * best): both triangles keep the quad's order (they were made counter-clockwise in the
 * projection, which turned one over: "passes through itself").  The volume is that of the two
 * tetrahedra on that diagonal, on either side of the base. */
TEST(core_nonplanar_quad_keeps_its_order)
{
    const double q[4][3] = {{3, 0, -3}, {1, 5, -2}, {-1, 1, 3}, {-5, -3, -5}};
    const double N[3] = {45, -48, 38}; /* Newell normal: along x (45 < 48: y is the axis) */
    for (int side = -1; side <= 1; side += 2) {
        double P[3], vol = 0;
        for (int a = 0; a < 3; a++)
            P[a] = (q[0][a] + q[1][a] + q[2][a] + q[3][a]) / 4 - side * N[a] / 8;
        for (int t = 0; t < 2; t++) { /* tetrahedra P q0 q1 q2 and P q0 q2 q3 */
            const double *a = q[0], *b = q[1 + t], *c = q[2 + t];
            double u[3], v[3], w[3];
            for (int k = 0; k < 3; k++) u[k] = b[k] - a[k], v[k] = c[k] - a[k], w[k] = P[k] - a[k];
            vol += (u[1] * v[2] - u[2] * v[1]) * w[0] + (u[2] * v[0] - u[0] * v[2]) * w[1] +
                   (u[0] * v[1] - u[1] * v[0]) * w[2];
        }
        vol = fabs(vol) / 6;
        char body[512];
        snprintf(body, sizeof body,
                 "{\"kind\":\"solids\",\"solids\":[{\"V\":[[3,0,-3],[1,5,-2],[-1,1,3],[-5,-3,-5],"
                 "[%.17g,%.17g,%.17g]],\"FV\":[[0,1,2,3],[1,0,4],[2,1,4],[3,2,4],[0,3,4]]}]}",
                 P[0], P[1], P[2]);
        json_t *r = run_ok(body);
        REQUIRE(r, "side %d: no result", side);
        const json_t *vols = json_object_get(json_object_get(r, "stats"), "volumes");
        double got = json_number_value(json_array_get(vols, 0));
        CHECK(json_array_size(vols) == 1 && fabs(got - vol) < 1e-9 * vol,
              "side %d: %zu cells, volume %.17g, want %.17g", side, json_array_size(vols), got,
              vol);
        CHECK(stat_of(r, "split_faces") == 1, "side %d: split faces %lld", side,
              stat_of(r, "split_faces"));
        json_decref(r);
    }
}
