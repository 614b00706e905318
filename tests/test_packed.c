/* test_packed.c — the fast reader of a solids or lines request's big arrays (api/packed.h): the
 * same request read with it and without it (api_packed_enable) gives the same canonical form byte
 * for byte, the same result, and the same error with the same status and message; it is taken for
 * the requests it should take, and gives way on everything it is not sure of. */
#include "api/api.h"
#include "api/api_int.h"
#include "api/packed.h"
#include "tests/check.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The canonical form (api_check_json) and the run's output (api_run_json) of body, with the
 * fast reader on or off. */
typedef struct both {
    int rc_check, rc_run;
    char *canon, *out;
    char msg_check[API_ERRMAX], msg_run[API_ERRMAX];
} both;

static void read_with(const char *body, int fast, both *b)
{
    api_error err;
    size_t n;
    memset(b, 0, sizeof *b);
    api_packed_enable(fast);
    b->rc_check = api_check_json(body, strlen(body), &b->canon, &n, &err);
    snprintf(b->msg_check, sizeof b->msg_check, "%s", b->rc_check ? err.msg : "");
    b->rc_run = api_run_json(body, strlen(body), 1, &b->out, &n, &err);
    snprintf(b->msg_run, sizeof b->msg_run, "%s", b->rc_run ? err.msg : "");
    api_packed_enable(1);
}

static void both_free(both *b)
{
    free(b->canon);
    free(b->out);
}

static int same_str(const char *a, const char *b)
{
    return (!a && !b) || (a && b && strcmp(a, b) == 0);
}

/* Does the fast reader take body (a scan that reads at least one array)? */
static int taken(const char *body)
{
    api_packed_set pk;
    int r = api_packed_scan(body, strlen(body), &pk);
    api_packed_free(&pk);
    return r;
}

/* body read both ways agrees; ok: whether it must be valid. */
static void agree_(const char *body, int ok, const char *func, int line)
{
    both f, s;
    read_with(body, 1, &f);
    read_with(body, 0, &s);
    if (f.rc_check != s.rc_check || strcmp(f.msg_check, s.msg_check) || !same_str(f.canon, s.canon))
        test_fail(__FILE__, func, line, "check differs: fast %d '%s' / %d '%s' on %.200s",
                  f.rc_check, f.msg_check, s.rc_check, s.msg_check, body);
    if (f.rc_run != s.rc_run || strcmp(f.msg_run, s.msg_run) || !same_str(f.out, s.out))
        test_fail(__FILE__, func, line, "run differs: fast %d '%s' / %d '%s' on %.200s", f.rc_run,
                  f.msg_run, s.rc_run, s.msg_run, body);
    if ((f.rc_check == API_OK) != ok || (f.rc_run == API_OK) != ok)
        test_fail(__FILE__, func, line, "expected %s: %d %d '%s' on %.200s",
                  ok ? "valid" : "an error", f.rc_check, f.rc_run, f.msg_check, body);
    both_free(&f);
    both_free(&s);
}
#define agree(body, ok) agree_(body, ok, __func__, __LINE__)

/* x written after sep in one of five forms (form 0..4): an integer, %.17g, %.6e, %.25f, %.3E;
 * returns the length. */
static size_t put_number(char *p, const char *sep, double x, int form)
{
    switch (form) {
    case 0:
        return (size_t)sprintf(p, "%s%lld", sep, (long long)llround(x));
    case 1:
        return (size_t)sprintf(p, "%s%.17g", sep, x);
    case 2:
        return (size_t)sprintf(p, "%s%.6e", sep, x);
    case 3:
        return (size_t)sprintf(p, "%s%.25f", sep, x);
    default:
        return (size_t)sprintf(p, "%s%.3E", sep, x);
    }
}

/* A random request: taken by the fast reader, and read both ways alike (canonical form, result,
 * status and messages).  0 (with a failed check) when not. */
static int random_agrees_(const char *body, const char *func, int line)
{
    if (taken(body) != 1) {
        test_fail(__FILE__, func, line, "not taken: %.300s", body);
        return 0;
    }
    both f, s;
    read_with(body, 1, &f);
    read_with(body, 0, &s);
    int same = f.rc_check == s.rc_check && same_str(f.canon, s.canon) &&
               !strcmp(f.msg_check, s.msg_check) && f.rc_run == s.rc_run &&
               same_str(f.out, s.out) && !strcmp(f.msg_run, s.msg_run);
    if (!same)
        test_fail(__FILE__, func, line, "differs (%d %d / %d %d '%s' '%s'): %.300s", f.rc_check,
                  f.rc_run, s.rc_check, s.rc_run, f.msg_check, s.msg_check, body);
    both_free(&f);
    both_free(&s);
    return same;
}

/* n random requests, each written into a body by make (from the state st; t its number): taken
 * by the fast reader and read both ways alike, up to the first that is not. */
static void random_requests_(uint64_t st, size_t n, void (*make)(char *, uint64_t *, size_t),
                             const char *func, int line)
{
    char *body = malloc(1 << 16);
    if (!body) {
        test_fail(__FILE__, func, line, "out of memory");
        return;
    }
    for (size_t t = 0; t < n; t++) {
        make(body, &st, t);
        if (!random_agrees_(body, func, line)) break;
    }
    free(body);
}
#define random_requests(st, n, make) random_requests_(st, n, make, __func__, __LINE__)

#define CUBE_V     "[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]"
#define CUBE_FV    "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]"
#define OPTS       "\"options\":{\"fields\":[\"V\",\"FV\",\"CF\"]}"
#define REQ(V, FV) "{\"kind\":\"solids\",\"solids\":[{\"V\":" V ",\"FV\":" FV "}]," OPTS "}"

TEST(packed_same_as_jansson)
{
    static const char *good[] = {
        REQ(CUBE_V, CUBE_FV),
        /* reals, exponents, signs, zeros, blanks of every kind */
        "{\"kind\":\"solids\",\"solids\":[{\"V\":[[0.0,-0,0e0],[1.0E0,0,0],[1,1e+0,-0.0],"
        "[0,10e-1,0],[ 0 ,\t0\n,\r1],[1,0,1.00000000000000000001],[1,1,1],[0,1,1]],"
        "\"FV\":[[0, 3,2 ,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}]," OPTS "}",
        /* two solids, one moved by a tenth (reals that %.17g writes long), an op */
        "{\"op\":\"union\",\"kind\":\"solids\",\"solids\":[{\"FV\":" CUBE_FV ",\"V\":" CUBE_V
        "},{\"V\":[[0.1,0.1,0.1],[1.1,0.1,0.1],[1.1,1.1,0.1],[0.1,1.1,0.1],[0.1,0.1,1.1],"
        "[1.1,0.1,1.1],[1.1,1.1,1.1],[0.1,1.1,1.1]],\"FV\":" CUBE_FV "}]," OPTS "}",
        /* a box with a square hole through it: FV read fast, the holes by jansson, joined */
        "{\"kind\":\"solids\",\"solids\":[{\"V\":[[0,0,0],[4,0,0],[4,4,0],[0,4,0],[0,0,1],"
        "[4,0,1],[4,4,1],[0,4,1],[1,1,1],[3,1,1],[3,3,1],[1,3,1],[1,1,0],[3,1,0],[3,3,0],"
        "[1,3,0]],\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7],"
        "[8,12,13,9],[9,13,14,10],[10,14,15,11],[11,15,12,8]],"
        "\"holes\":{\"0\":[[12,13,14,15]],\"1\":[[8,11,10,9]]}}]," OPTS "}",
        /* a face soup */
        "{\"kind\":\"solids\",\"faces\":{\"V\":[[0,0,0],[1,0,0],[0,1,0],[0,0,1]],"
        "\"FV\":[[0,1,2],[0,1,3]]}," OPTS "}",
        /* numbers far apart, large and small */
        "{\"kind\":\"solids\",\"solids\":[{\"V\":[[1e6,2e6,3e6],[1000001,2000000,3000000],"
        "[1e6,2000001,3e6],[1e6,2e6,3000001]],\"FV\":[[0,2,1],[0,1,3],[0,3,2],[1,2,3]]}]," OPTS "}",
        "{\"kind\":\"solids\",\"solids\":[{\"V\":[[1.5e-3,0,0],[2.5e-3,0,0],[1.5e-3,1e-3,0],"
        "[1.5e-3,0,1e-3]],\"FV\":[[0,2,1],[0,1,3],[0,3,2],[1,2,3]]}],\"options\":{\"precision\":"
        "1e-7,\"fields\":[\"V\",\"FV\"]}}",
    };
    for (size_t i = 0; i < sizeof good / sizeof *good; i++) {
        CHECK(taken(good[i]) == 1, "case %zu not taken", i);
        agree(good[i], 1);
    }
}

TEST(packed_errors_same_as_jansson)
{
    static const char *bad[] = {
        REQ("[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1]]", CUBE_FV),
        REQ("[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1,1]]", CUBE_FV),
        REQ("[[01,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]", CUBE_FV),
        REQ("[[1.,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]", CUBE_FV),
        REQ("[[.5,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]", CUBE_FV),
        REQ("[[+1,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]", CUBE_FV),
        REQ("[[1e,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]", CUBE_FV),
        REQ("[[1e400,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]", CUBE_FV),
        REQ("[[NaN,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]", CUBE_FV),
        REQ("[[\"0\",0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]", CUBE_FV),
        REQ("[[99999999999999999999,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],"
            "[0,1,1]]",
            CUBE_FV),
        REQ("[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1],]", CUBE_FV),
        REQ("[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]", CUBE_FV),
        REQ(CUBE_V, "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,8]]"),
        REQ(CUBE_V, "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,-7]]"),
        REQ(CUBE_V, "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7.0]]"),
        REQ(CUBE_V, "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,4294967296]]"),
        REQ(CUBE_V, "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0]]"),
        REQ(CUBE_V, "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[]]"),
        REQ(CUBE_V, "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,07]]"),
        REQ(CUBE_V, "[]"),
        REQ("[]", CUBE_FV),
        /* the surface is open: a geometry error after a good parse */
        REQ(CUBE_V, "[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6]]"),
        /* the same key twice, a key unknown, garbage after the end, an unclosed object */
        "{\"kind\":\"solids\",\"solids\":[{\"V\":" CUBE_V ",\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}]}",
        "{\"kind\":\"solids\",\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV ",\"W\":1}]}",
        "{\"kind\":\"solids\",\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}]} x",
        "{\"kind\":\"solids\",\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}]",
        "{\"kind\":\"solids\",\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}],\"kind\":1}",
        "{\"kind\":\"lines\",\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}]}",
        "{\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}]}",
        /* a placeholder given by the user is a string like any other */
        "{\"kind\":\"solids\",\"solids\":[{\"V\":\"\\u0001#0\",\"FV\":" CUBE_FV "}]}",
        "{\"kind\":\"solids\",\"solids\":[{\"V\":" CUBE_V ",\"FV\":\"\\u0001#0\"}]}",
        "{\"kind\":\"solids\",\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "},"
        "{\"V\":\"\\u0001#0\",\"FV\":\"\\u0001#1\"}]}",
        "{\"kind\":\"solids\",\"solids\":[1,{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}]}",
        "{\"kind\":\"solids\",\"faces\":{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "},\"solids\":[]}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) agree(bad[i], 0);
    /* another kind's request is left to jansson from its "kind" on: nothing more is scanned */
    CHECK(taken("{\"kind\":\"svg\",\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}]}") == 0,
          "an svg request taken");
    CHECK(taken("{\"solids\":[{\"V\":" CUBE_V ",\"FV\":" CUBE_FV "}],\"kind\":\"solids\"}") == 1,
          "a solids request with its kind last not taken");
}

/* A "lines" request's segments: read fast, the same canonical form, result and errors as
 * jansson's path. */
#define LOPTS "\"options\":{\"fields\":[\"V\",\"EV\",\"FV\"]}" /* no stats: no times */
TEST(packed_lines_same_as_jansson)
{
    static const char *good[] = {
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[4,0]],[[4,0],[4,4]],[[4,4],[0,4]],[[0,4],[0,0]],"
        "[[0,0],[4,4]]]," LOPTS "}",
        /* reals, exponents, signs, zeros, blanks; the kind last */
        "{\"lines\":[ [ [0.5,-0] , [1e1,0.0]],\n[[10E0,-0.0],[1.00000000000000000001,7.25e-1]],"
        "[[0,0],[3.3333333333333335,9.999999999999999e22]]]," LOPTS ",\"kind\":\"lines\"}",
        "{\"kind\":\"lines\",\"lines\":[]," LOPTS "}",
        "{\"kind\":\"lines\",\"lines\":[[[123456789012345,-123456789012345],[1e-300,5e-324]]]"
        "," LOPTS "}",
    };
    for (size_t i = 0; i < sizeof good / sizeof *good; i++) {
        CHECK(taken(good[i]) == 1, "case %zu not taken", i);
        agree(good[i], 1);
    }
    static const char *bad[] = {
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1,1]]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0]]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1],[2,2]]]}",
        "{\"kind\":\"lines\",\"lines\":[[0,0,1,1]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[1e400,1]]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[\"1\",1]]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[01,1]]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]],]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[99999999999999999999,1]]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]]],\"lines\":[]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]]],\"solids\":[]}",
        "{\"kind\":\"lines\",\"lines\":\"\\u0001#0\"}",
        "{\"kind\":\"solids\",\"lines\":[[[0,0],[1,1]]]}",
        "{\"kind\":\"svg\",\"lines\":[[[0,0],[1,1]]]}",
        "{\"lines\":[[[0,0],[1,1]]]}",
        "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]]],\"options\":{\"fields\":[\"result\"]}}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) agree(bad[i], 0);
    CHECK(taken("{\"kind\":\"svg\",\"lines\":[[[0,0],[1,1]]]}") == 0, "an svg request taken");
}

/* A "polygons" request's native rings: read fast, the same canonical form, result and errors as
 * jansson's path; GeoJSON objects and WKT strings among them send the whole text there. */
#define POPTS "\"options\":{\"fields\":[\"V\",\"FV\",\"result\"]}"
TEST(packed_polygons_same_as_jansson)
{
    static const char *good[] = {
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[4,0],[4,4],[0,4]],[[1,1],[2,1],[2,2],"
        "[1,2]]],[[[2,2],[6,2],[6,6],[2,6],[2,2]]]],\"op\":\"union\"," POPTS "}",
        /* reals, exponents, signs, blanks; the kind last, an expression */
        "{\"polygons\":[ [ [ [0.5,-0] , [1e1,0.0],[10E0,7.25e-1],\n[1.00000000000000000001,5]]],"
        "[[[0,0],[3.3333333333333335,0],[3.3333333333333335,2.5e0]]],[[[1,-1],[2,-1],[2,9]]]],"
        "\"op\":[\"-\",0,[\"+\",1,2]]," POPTS ",\"kind\":\"polygons\"}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"xor\"," POPTS "}",
    };
    for (size_t i = 0; i < sizeof good / sizeof *good; i++) {
        CHECK(taken(good[i]) == 1, "case %zu not taken", i);
        agree(good[i], 1);
    }
    static const char *bad[] = {
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0]]]],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,0]]]],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[[]],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1,2]]]],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,\"1\"]]]],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1e999]]]],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":[\"+\",0,1]}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]]}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]],[]],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"union\","
        "\"options\":{\"fields\":[\"X\"]}}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) agree(bad[i], 0);
    /* native rings mixed with GeoJSON or WKT, positions of 3 numbers, empty geometries, no
     * coordinates at all: not read fast, the same answers */
    static const char *mixed[] = {
        "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[4,0],[4,4]]],\"POLYGON ((1 1, 5 1, 5 5, 1 "
        "1))\"],"
        "\"op\":\"union\"," POPTS "}",
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],"
        "[1,1],[0,0]]]},[[[0,0],[2,0],[0,2]]]],\"op\":\"intersection\"," POPTS "}",
        "{\"kind\":\"polygons\",\"polygons\":{\"type\":\"FeatureCollection\",\"features\":[]},"
        "\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"Polygon\",\"coordinates\":[[[0,0,9],"
        "[1,0,9],[1,1,9],[0,0,9]]]}],\"op\":\"union\"," POPTS "}",
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"Polygon\",\"coordinates\":[]},"
        "{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[1,0],[1,1]]]}],\"op\":\"union\"," POPTS "}",
        "{\"kind\":\"polygons\",\"polygons\":[\"POLYGON ((1 1, 5 1, 5 5, 1 1))\"],\"op\":"
        "\"union\"," POPTS "}",
    };
    for (size_t i = 0; i < sizeof mixed / sizeof *mixed; i++) {
        CHECK(taken(mixed[i]) == 0, "mixed case %zu taken", i);
        agree(mixed[i], i != 2);
    }
    /* GeoJSON geometries, Features and FeatureCollections (WKT strings among them): their
     * coordinates read fast, the same answers */
    static const char *geo[] = {
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"Polygon\",\"coordinates\":[[[0,0],"
        "[4,0],[4,4],[0,4],[0,0]],[[1,1],[2,1],[2,2],[1,1]]]},{\"coordinates\":[[[[2,2],[6,2],[6,6]"
        ","
        "[2,2]]],[[[7,7],[8,7],[8,8]]]],\"type\":\"MultiPolygon\"}],\"op\":\"union\"," POPTS "}",
        "{\"kind\":\"polygons\",\"polygons\":{\"type\":\"FeatureCollection\",\"bbox\":[0,0,9,9],"
        "\"features\":[{\"type\":\"Feature\",\"properties\":{\"coordinates\":[1,2],\"name\":"
        "\"a\"},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[3,0],[3,3],[0,0]]]}},"
        "{\"type\":\"Feature\",\"geometry\":null,\"properties\":null},{\"geometry\":{\"type\":"
        "\"MultiPolygon\",\"coordinates\":[[[[1,1],[5,1],[5,5],[1,1]]]]},\"type\":\"Feature\"}]},"
        "\"op\":\"intersection\"," POPTS "}",
        "{\"kind\":\"polygons\",\"polygons\":[\"POLYGON ((1 1, 5 1, 5 5, 1 1))\",{\"type\":"
        "\"Polygon\",\"coordinates\":[[[0,0],[2.5e0,0],[2,2.25],[0,0]]]}],\"op\":\"xor\"," POPTS
        "}",
    };
    for (size_t i = 0; i < sizeof geo / sizeof *geo; i++) {
        CHECK(taken(geo[i]) == 1, "GeoJSON case %zu not taken", i);
        agree(geo[i], 1);
    }
    /* GeoJSON the fast reader takes but the request is wrong: jansson's messages */
    static const char *geobad[] = {
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"Polygon\",\"coordinates\":[[[[0,0],"
        "[4,0],[4,4],[0,0]]]]}],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"MultiPolygon\",\"coordinates\":[[[0,0],"
        "[4,0],[4,4],[0,0]]]}],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"Polygon\",\"coordinates\":[[[0,0],"
        "[4,0],[0,0]]]}],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"Polygon\",\"coordinates\":[[[0,0],"
        "[4,0]]]}],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[{\"type\":\"LineString\",\"coordinates\":[[[0,0],"
        "[4,0],[4,4]]]}],\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":[{\"coordinates\":[[[0,0],[4,0],[4,4]]]}],\"op\":"
        "\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":{\"type\":\"FeatureCollection\",\"features\":[{"
        "\"type\":\"Polygon\",\"coordinates\":[[[0,0],[4,0],[4,4]]]}]},\"op\":\"union\"}",
        "{\"kind\":\"polygons\",\"polygons\":{\"type\":\"GeometryCollection\",\"features\":[{"
        "\"type\":\"Feature\",\"geometry\":{\"type\":\"Polygon\",\"coordinates\":[[[0,0],[4,0],"
        "[4,4]]]}}]},\"op\":\"union\"}",
    };
    for (size_t i = 0; i < sizeof geobad / sizeof *geobad; i++) {
        CHECK(taken(geobad[i]) == 1, "bad GeoJSON case %zu not taken", i);
        agree(geobad[i], 0);
    }
}

/* Random GeoJSON: Polygons, MultiPolygons and Features in an array or a FeatureCollection,
 * closed or open rings, properties in the way, numbers in assorted forms. */
static void random_geojson(char *body, uint64_t *st, size_t t)
{
    static const char *ops[] = {"\"union\"", "\"intersection\"", "\"difference\"", "\"xor\""};
    int fc = t % 3 == 0;
    size_t w = (size_t)sprintf(body, "{\"kind\":\"polygons\",\"polygons\":%s",
                               fc ? "{\"type\":\"FeatureCollection\",\"features\":[" : "[");
    int np = 1 + (int)(test_rnd(st) * 5);
    double sc = pow(10, (int)(test_rnd(st) * 7) - 3);
    for (int q = 0; q < np; q++) {
        int feature = fc || test_rnd(st) < 0.3, multi = test_rnd(st) < 0.4;
        int parts = multi ? 1 + (int)(test_rnd(st) * 2) : 1;
        w += (size_t)sprintf(body + w, "%s", q ? "," : "");
        if (feature)
            w += (size_t)sprintf(body + w,
                                 "{\"type\":\"Feature\",\"properties\":{\"id\":%d,"
                                 "\"tags\":[[1,2],{\"coordinates\":[3]}]},"
                                 "\"geometry\":",
                                 q);
        w += (size_t)sprintf(body + w, "{\"type\":\"%s\",\"coordinates\":%s",
                             multi ? "MultiPolygon" : "Polygon", multi ? "[" : "");
        for (int part = 0; part < parts; part++) {
            double cx = test_rnd(st) * 4 + 6 * part, cy = test_rnd(st) * 4,
                   h = 0.5 + test_rnd(st) * 2;
            int holes = test_rnd(st) < 0.3, closed = test_rnd(st) < 0.7;
            w += (size_t)sprintf(body + w, "%s[", part ? "," : "");
            for (int ring = 0; ring <= holes; ring++) {
                double r = ring ? h / 3 : h;
                double pts[5][2] = {
                    {cx - r, cy - r}, {cx + r, cy - r}, {cx + r, cy + r}, {cx - r, cy + r}, {0, 0}};
                for (int k = 0; k < 4; k++)
                    for (int c = 0; c < 2; c++)
                        pts[k][c] = (pts[k][c] + (test_rnd(st) - 0.5) * 0.1) * sc;
                pts[4][0] = pts[0][0], pts[4][1] = pts[0][1];
                w += (size_t)sprintf(body + w, "%s[", ring ? "," : "");
                for (int k = 0; k < 4 + closed; k++)
                    for (int c = 0; c < 2; c++) {
                        const char *sep = c ? "," : k ? "],[" : "[";
                        w += put_number(body + w, sep, pts[k][c],
                                        k == 4 ? 1 : (int)(test_rnd(st) * 5));
                    }
                w += (size_t)sprintf(body + w, "]]");
            }
            w += (size_t)sprintf(body + w, "]");
        }
        w += (size_t)sprintf(body + w, "%s}%s", multi ? "]" : "", feature ? "}" : "");
    }
    w += (size_t)sprintf(body + w, "]%s,\"op\":%s," POPTS "}", fc ? "}" : "", ops[t % 4]);
}

TEST(packed_geojson_random)
{
    random_requests(4111, test_stress(60), random_geojson);
}

/* Random native polygons (jittered squares with square holes), numbers in assorted forms and
 * operations, read both ways. */
static void random_polygons(char *body, uint64_t *st, size_t t)
{
    static const char *ops[] = {"\"union\"", "\"intersection\"", "\"difference\"", "\"xor\""};
    size_t w = (size_t)sprintf(body, "{\"kind\":\"polygons\",\"polygons\":[");
    int np = 1 + (int)(test_rnd(st) * 6);
    double sc = pow(10, (int)(test_rnd(st) * 7) - 3);
    for (int q = 0; q < np; q++) {
        double cx = test_rnd(st) * 4, cy = test_rnd(st) * 4, h = 0.5 + test_rnd(st) * 2;
        int holes = test_rnd(st) < 0.3;
        w += (size_t)sprintf(body + w, "%s[", q ? "," : "");
        for (int ring = 0; ring <= holes; ring++) {
            double r = ring ? h / 3 : h;
            double pts[4][2] = {
                {cx - r, cy - r}, {cx + r, cy - r}, {cx + r, cy + r}, {cx - r, cy + r}};
            w += (size_t)sprintf(body + w, "%s[", ring ? "," : "");
            for (int k = 0; k < 4; k++)
                for (int c = 0; c < 2; c++) {
                    double x = (pts[k][c] + (test_rnd(st) - 0.5) * 0.1) * sc;
                    const char *sep = c ? "," : k ? "],[" : "[";
                    w += put_number(body + w, sep, x, (int)(test_rnd(st) * 5));
                }
            w += (size_t)sprintf(body + w, "]]");
        }
        w += (size_t)sprintf(body + w, "]");
    }
    w += (size_t)sprintf(body + w, "],\"op\":%s," POPTS "}", ops[t % 4]);
}

TEST(packed_polygons_random)
{
    random_requests(1127, test_stress(60), random_polygons);
}

/* Random segments, their numbers in assorted forms, read both ways. */
static void random_lines(char *body, uint64_t *st, size_t t)
{
    (void)t;
    size_t w = (size_t)sprintf(body, "{\"kind\":\"lines\",\"lines\":[");
    int ns = 1 + (int)(test_rnd(st) * 30);
    double sc = pow(10, (int)(test_rnd(st) * 9) - 4), off = (test_rnd(st) - 0.5) * 100;
    for (int k = 0; k < 4 * ns; k++) {
        double x = (test_rnd(st) + off) * sc;
        const char *sep = k % 4 == 0 ? (k ? "]],[[" : "[[") : k % 2 == 0 ? "],[" : ",";
        w += put_number(body + w, sep, x, (int)(test_rnd(st) * 5));
    }
    w += (size_t)sprintf(body + w, "]]]," LOPTS "}");
}

TEST(packed_lines_random_numbers)
{
    random_requests(1128, test_stress(100), random_lines);
}

/* Random solids (a tetrahedron moved and scaled, its numbers written in assorted forms: integers,
 * reals with and without exponents, long digit strings) read both ways. */
static void random_solids(char *body, uint64_t *st, size_t t)
{
    (void)t;
    size_t w = 0;
    w += (size_t)sprintf(body + w, "{\"kind\":\"solids\",\"solids\":[");
    int ns = 1 + (int)(test_rnd(st) * 2);
    for (int k = 0; k < ns; k++) {
        static const double T[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        double sc = pow(10, (int)(test_rnd(st) * 9) - 4), off = (test_rnd(st) - 0.5) * 100;
        w += (size_t)sprintf(body + w, "%s{\"V\":[", k ? "," : "");
        for (int v = 0; v < 4; v++)
            for (int a = 0; a < 3; a++) {
                double x = (T[v][a] + 0.3 * test_rnd(st)) * sc + off * sc;
                const char *sep = a ? "," : v ? "],[" : "[";
                w += put_number(body + w, sep, x, (int)(test_rnd(st) * 5));
            }
        w += (size_t)sprintf(body + w, "]],\"FV\":[[0,2,1],[0,1,3],[0,3,2],[1,2,3]]}");
    }
    w += (size_t)sprintf(body + w, "],\"options\":{\"fields\":[\"V\",\"FV\",\"CF\"]}}");
}

TEST(packed_random_numbers)
{
    random_requests(20261129, test_stress(200), random_solids);
}

/* api_g17 against printf's %.17g: random bit patterns, decimal numbers, integers, dyadic
 * fractions (ties at the 17th digit), powers of ten and their neighbours, the range's ends. */
TEST(packed_g17_is_printf)
{
    uint64_t st = 17;
    size_t n = test_stress(300000), bad = 0, fast = 0;
    char a[64], b[64];
    for (size_t i = 0; i < n && bad < 5; i++) {
        double x;
        uint64_t r = (uint64_t)(test_rnd(&st) * 18446744073709551616.0);
        switch (i % 8) {
        case 0:
            memcpy(&x, &r, sizeof x);
            break;
        case 1:
            x = (test_rnd(&st) - 0.5) * pow(10, (int)(test_rnd(&st) * 50) - 10);
            break;
        case 2:
            x = (double)(int64_t)(r >> (int)(test_rnd(&st) * 40));
            break;
        case 3:
            x = ldexp((double)(r >> 11), -(int)(test_rnd(&st) * 120));
            break;
        case 4:
            x = ldexp((double)(r >> 40 | 1), (int)(test_rnd(&st) * 80) - 60);
            break;
        case 5: {
            double p = pow(10, (int)(test_rnd(&st) * 48) - 8);
            x = r & 1 ? nextafter(p, 0) : r & 2 ? nextafter(p, INFINITY) : p;
            break;
        }
        case 6:
            x = (double)(r % 100000000) / pow(10, (int)(test_rnd(&st) * 12));
            break;
        default: {
            static const double ends[] = {1e-6, 1e38, 5e-7, 2e38, 0.0, -0.0, 0.5, 1.5, 2.5};
            x = ends[r % 9];
            if (r & 16) x = nextafter(x, r & 32 ? INFINITY : -INFINITY);
            break;
        }
        }
        if (!isfinite(x)) continue;
        size_t k = api_g17(x, a);
        if (!k) continue;
        fast++;
        snprintf(b, sizeof b, "%.17g", x);
        if (strcmp(a, b) || k != strlen(b)) {
            CHECK(0, "%a: '%s', printf '%s'", x, a, b);
            bad++;
        }
    }
    CHECK(fast > n / 2, "only %zu of %zu in the fast range", fast, n);
}
