/* test_npz.c — results as NumPy arrays (render_npz, api/npz.c).  Every .npz made here is read
 * back by a reader of its own: the zip's end record, central directory and local headers agree,
 * every member's CRC-32 is right, every member is a .npy of format 1.0 whose header names a dtype
 * of the documented ones and a shape that fits its data.  From the arrays and the "json" member
 * the result is then rebuilt (rows from indptr and indices, holes by face, float64 and integer
 * arrays as numbers) and compared, number by number, with jansson's reading of the result: so
 * nothing is lost or changed, for 2D and 3D results of every kind, with operators, membership,
 * "fields", holes.  Then results it must refuse (422 naming the path), and every prefix and
 * thousands of mutations of a result: a refusal or an npz that rebuilds what jansson reads,
 * never a crash.  tests/t_npz.sh reads the same files with numpy and scipy. */
#include "api/api.h"
#include "api/render.h"
#include "tests/check.h"

#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* ---- a reader of the zip and its .npy members ---------------------------------------------- */

typedef struct member {
    char name[128];  /* without ".npy" */
    char descr[8];   /* "<f8", "<i4", "<i8", "|u1" */
    int ndim;        /* 1 or 2 */
    size_t shape[2]; /* shape[1]: ndim 2 only */
    const unsigned char *data;
    size_t n; /* elements */
} member;

static unsigned rd16(const unsigned char *p)
{
    return p[0] | (unsigned)p[1] << 8;
}

static uint32_t rd32(const unsigned char *p)
{
    return rd16(p) | (uint32_t)rd16(p + 2) << 16;
}

/* The .npy at p[0..n) into m; NULL, or what is wrong. */
static const char *npy_read(const unsigned char *p, size_t n, member *m)
{
    if (n < 10 || memcmp(p, "\x93NUMPY\x01\x00", 8)) return "not a .npy of format 1.0";
    size_t hl = rd16(p + 8);
    if (10 + hl > n || (10 + hl) % 64 || p[10 + hl - 1] != '\n') return "header not padded to 64";
    char h[512];
    if (hl >= sizeof h) return "header too long";
    memcpy(h, p + 10, hl);
    h[hl] = 0;
    const char *d = strstr(h, "'descr': '"), *s = strstr(h, "'shape': (");
    if (!d || !s || !strstr(h, "'fortran_order': False")) return "header lacks a key";
    snprintf(m->descr, sizeof m->descr, "%.3s", d + 10);
    size_t w = !strcmp(m->descr, "<f8") || !strcmp(m->descr, "<i8") ? 8
               : !strcmp(m->descr, "<i4")                           ? 4
               : !strcmp(m->descr, "|u1")                           ? 1
                                                                    : 0;
    if (!w) return "a dtype of none of ours";
    char *e;
    m->shape[0] = strtoul(s + 10, &e, 10);
    if (*e == ',' && e[1] == ')') {
        m->ndim = 1;
        m->n = m->shape[0];
    } else if (*e == ',' && e[1] == ' ') {
        m->ndim = 2;
        m->shape[1] = strtoul(e + 2, &e, 10);
        if (*e != ')') return "a bad shape";
        m->n = m->shape[0] * m->shape[1];
    } else {
        return "a bad shape";
    }
    if (10 + hl + m->n * w != n) return "data of another size than the shape says";
    m->data = p + 10 + hl;
    return NULL;
}

/* The members of the zip z[0..n) into *ms (*count of them, malloc'd); NULL or what is wrong. */
static const char *zip_read(const unsigned char *z, size_t n, member **ms, size_t *count)
{
    *ms = NULL;
    *count = 0;
    if (n < 22 || rd32(z + n - 22) != 0x06054b50) return "no end record";
    const unsigned char *e = z + n - 22;
    size_t k = rd16(e + 10), cdsize = rd32(e + 12), cd = rd32(e + 16);
    if (rd16(e + 8) != k || cd + cdsize != n - 22) return "a bad end record";
    member *m = calloc(k ? k : 1, sizeof *m);
    if (!m) return "calloc";
    const unsigned char *c = z + cd;
    for (size_t i = 0; i < k; i++) {
        if (c + 46 > e || rd32(c) != 0x02014b50) return free(m), "a bad central entry";
        size_t nl = rd16(c + 28), off = rd32(c + 42), size = rd32(c + 20);
        if (rd16(c + 10) != 0 || rd32(c + 24) != size) return free(m), "a member not stored";
        if (nl < 5 || nl > 120 || memcmp(c + 46 + nl - 4, ".npy", 4))
            return free(m), "a member not named .npy";
        const unsigned char *l = z + off;
        if (off + 30 + nl + size > cd || rd32(l) != 0x04034b50 || rd16(l + 26) != nl ||
            memcmp(l + 30, c + 46, nl) || rd32(l + 14) != rd32(c + 16) || rd32(l + 18) != size)
            return free(m), "a local header that disagrees";
        const unsigned char *data = l + 30 + nl;
        if (crc32(0, data, (uInt)size) != rd32(c + 16)) return free(m), "a wrong CRC-32";
        memcpy(m[i].name, c + 46, nl - 4);
        const char *why = npy_read(data, size, &m[i]);
        if (why) return free(m), why;
        c += 46 + nl;
    }
    *ms = m;
    *count = k;
    return NULL;
}

static double elem(const member *m, size_t i)
{
    const unsigned char *p = m->data;
    if (!strcmp(m->descr, "<f8")) {
        uint64_t u = 0;
        for (int b = 7; b >= 0; b--) u = u << 8 | p[8 * i + (size_t)b];
        double x;
        memcpy(&x, &u, 8);
        return x;
    }
    if (!strcmp(m->descr, "<i8")) {
        uint64_t u = 0;
        for (int b = 7; b >= 0; b--) u = u << 8 | p[8 * i + (size_t)b];
        return (double)(int64_t)u;
    }
    if (!strcmp(m->descr, "<i4")) return (double)(int32_t)rd32(p + 4 * i);
    return p[i];
}

static const member *find(const member *ms, size_t n, const char *name)
{
    for (size_t i = 0; i < n; i++)
        if (!strcmp(ms[i].name, name)) return &ms[i];
    return NULL;
}

/* ---- the result rebuilt from the arrays ---------------------------------------------------- */

/* [elem from, ..., elem to) of m as a JSON array of numbers */
static json_t *run(const member *m, size_t from, size_t to)
{
    json_t *a = json_array();
    for (size_t i = from; i < to; i++) json_array_append_new(a, json_real(elem(m, i)));
    return a;
}

/* The object at path p (the name's components but the last) in root, made when missing; the
 * last component in *last. */
static json_t *parent(json_t *root, const char *name, char *last)
{
    char buf[128];
    snprintf(buf, sizeof buf, "%s", name);
    json_t *o = root;
    char *s = buf, *dot;
    while ((dot = strchr(s, '.'))) {
        *dot = 0;
        json_t *c = json_object_get(o, s);
        if (!c) json_object_set_new(o, s, c = json_object());
        o = c;
        s = dot + 1;
    }
    strcpy(last, s);
    return o;
}

/* The value at a dotted path of objects in root, or NULL. */
static json_t *at(json_t *root, const char *path)
{
    char buf[128];
    snprintf(buf, sizeof buf, "%s", path);
    json_t *o = root;
    for (char *s = strtok(buf, "."); s && o; s = strtok(NULL, ".")) o = json_object_get(o, s);
    return o;
}

/* The result the npz holds: "json" and the arrays put back where their names say. */
static json_t *rebuild(const member *ms, size_t n)
{
    const member *js = find(ms, n, "json");
    if (!js || strcmp(js->descr, "|u1")) return NULL;
    json_t *root = json_loadb((const char *)js->data, js->n, JSON_DECODE_INT_AS_REAL, NULL);
    if (!root) return NULL;
    for (size_t i = 0; i < n; i++) {
        const member *m = &ms[i];
        char last[128], base[128];
        if (m == js) continue;
        size_t bl = strlen(m->name) - strlen(strrchr(m->name, '.') ? strrchr(m->name, '.') : "");
        snprintf(base, sizeof base, "%.*s", (int)bl, m->name);
        /* rows (K.indptr and K.indices, and K.face for holes) are the only members named
         * K.something, and K is not an object of the rest (a CSR object has its shape) */
        const member *ptr = NULL, *idx = NULL, *face = NULL;
        int rows = bl < strlen(m->name), others = 0;
        for (size_t j = 0; rows && j < n; j++) {
            if (strncmp(ms[j].name, base, bl) || ms[j].name[bl] != '.') continue;
            const char *suf = ms[j].name + bl + 1;
            if (!strcmp(suf, "indptr"))
                ptr = &ms[j];
            else if (!strcmp(suf, "indices"))
                idx = &ms[j];
            else if (!strcmp(suf, "face"))
                face = &ms[j];
            else
                others = 1;
        }
        if (others || !ptr || !idx || at(root, base)) rows = 0;
        if (rows) {
            if (m != idx) continue; /* the rows are made once, at their indices */
            json_t *rows = json_array(), *holes = face ? json_object() : NULL;
            for (size_t r = 0; r + 1 < ptr->n; r++) {
                size_t a = (size_t)elem(ptr, r), b = (size_t)elem(ptr, r + 1);
                if (a > b || b > idx->n) {
                    json_decref(rows);
                    json_decref(holes);
                    json_decref(root);
                    return NULL;
                }
                json_t *row = run(idx, a, b);
                if (holes) {
                    char k[32];
                    snprintf(k, sizeof k, "%.0f", elem(face, r));
                    json_t *l = json_object_get(holes, k);
                    if (!l) json_object_set_new(holes, k, l = json_array());
                    json_array_append_new(l, row);
                } else {
                    json_array_append_new(rows, row);
                }
            }
            json_t *o = parent(root, base, last);
            json_object_set_new(o, last, holes ? holes : rows);
            if (holes) json_decref(rows);
            continue;
        }
        json_t *v;
        if (m->ndim == 2) {
            v = json_array();
            for (size_t r = 0; r < m->shape[0]; r++)
                json_array_append_new(v, run(m, r * m->shape[1], (r + 1) * m->shape[1]));
        } else {
            v = run(m, 0, m->n);
        }
        json_t *o = parent(root, m->name, last);
        json_object_set_new(o, last, v);
    }
    return root;
}

/* Equal as values: numbers by value (integer or real alike), objects by keys. */
static int same(const json_t *a, const json_t *b, char *where, size_t cap)
{
    if (json_is_number(a) && json_is_number(b)) {
        if (json_number_value(a) == json_number_value(b)) return 1;
        snprintf(where, cap, "%.17g != %.17g", json_number_value(a), json_number_value(b));
        return 0;
    }
    if (json_typeof(a) != json_typeof(b)) return snprintf(where, cap, "types differ"), 0;
    if (json_is_array(a)) {
        if (json_array_size(a) != json_array_size(b))
            return snprintf(where, cap, "lengths %zu, %zu", json_array_size(a), json_array_size(b)),
                   0;
        for (size_t i = 0; i < json_array_size(a); i++) {
            if (!same(json_array_get(a, i), json_array_get(b, i), where, cap)) {
                char t[200];
                snprintf(t, sizeof t, "[%zu]%s", i, where);
                snprintf(where, cap, "%s", t);
                return 0;
            }
        }
        return 1;
    }
    if (json_is_object(a)) {
        const char *k;
        const json_t *v;
        if (json_object_size(a) != json_object_size(b))
            return snprintf(where, cap, "objects of %zu and %zu keys", json_object_size(a),
                            json_object_size(b)),
                   0;
        json_object_foreach((json_t *)a, k, v)
        {
            const json_t *w = json_object_get(b, k);
            if (!w) return snprintf(where, cap, ".%s missing", k), 0;
            if (!same(v, w, where, cap)) {
                char t[200];
                snprintf(t, sizeof t, ".%s%s", k, where);
                snprintf(where, cap, "%s", t);
                return 0;
            }
        }
        return 1;
    }
    if (json_equal((json_t *)a, (json_t *)b)) return 1;
    return snprintf(where, cap, "values differ"), 0;
}

/* render_npz of result text[0..len): NULL and the npz's members (*ms, *nm), or what is wrong;
 * *rc the status. */
static const char *npz_of(const char *text, size_t len, int *rc, api_error *err, char **z,
                          size_t *zl, member **ms, size_t *nm)
{
    *rc = render_npz(text, len, NULL, z, zl, err);
    *ms = NULL;
    *nm = 0;
    if (*rc != API_OK) return "refused";
    return zip_read((const unsigned char *)*z, *zl, ms, nm);
}

/* The npz of text rebuilds what jansson reads of text: 1, or 0 with why; typed: V, EV and the
 * rows have the dtypes of the README (a result of ours; a damaged one may have a fraction in
 * FV, and then FV.indices is float64, as the numbers are). */
static int round_trip(const char *text, size_t len, int typed, char *why, size_t cap)
{
    char *z = NULL;
    size_t zl, nm;
    member *ms;
    int rc;
    api_error err;
    const char *bad = npz_of(text, len, &rc, &err, &z, &zl, &ms, &nm);
    if (bad) {
        snprintf(why, cap, "%s %s", bad, rc == API_OK ? "" : err.msg);
        free(z);
        free(ms);
        return 0;
    }
    int ok = 1;
    json_t *orig = json_loadb(text, len, JSON_DECODE_INT_AS_REAL, NULL);
    json_t *back = rebuild(ms, nm);
    if (!orig || !back) {
        snprintf(why, cap, "%s", !orig ? "jansson refuses what npz took" : "cannot rebuild");
        ok = 0;
    } else if (!same(orig, back, why, cap)) {
        ok = 0;
    }
    /* the dtypes: V float64 of dim columns, EV integers of 2, indptr and indices integers */
    const member *V = find(ms, nm, "V"), *EV = find(ms, nm, "EV");
    const json_t *dim = json_object_get(orig, "dim");
    if (!typed) V = EV = NULL;
    if (ok && V &&
        (strcmp(V->descr, "<f8") || V->ndim != 2 ||
         (dim && V->shape[1] != (size_t)json_number_value(dim)))) {
        snprintf(why, cap, "V is %s of %d dimensions", V->descr, V->ndim);
        ok = 0;
    }
    if (ok && EV && (EV->descr[1] != 'i' || EV->ndim != 2 || EV->shape[1] != 2)) {
        snprintf(why, cap, "EV is %s", EV->descr);
        ok = 0;
    }
    for (size_t i = 0; ok && typed && i < nm; i++) {
        const char *dot = strrchr(ms[i].name, '.');
        if (dot && (!strcmp(dot, ".indptr") || !strcmp(dot, ".indices")) && ms[i].descr[1] != 'i') {
            snprintf(why, cap, "%s is %s", ms[i].name, ms[i].descr);
            ok = 0;
        }
    }
    json_decref(orig);
    json_decref(back);
    free(ms);
    free(z);
    return ok;
}

static char *result_of(const char *req, size_t *len)
{
    char *out = NULL;
    api_error err;
    if (api_run_json(req, strlen(req), 1, &out, len, &err) != API_OK) {
        fprintf(stderr, "request refused: %s\n", err.msg);
        return NULL;
    }
    return out;
}

#define SQUARES                                                                                    \
    "{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[2,0],[2,2],[0,2]]],"                            \
    "[[[1,1],[3,1],[3,3],[1,3]],[[1.5,1.5],[2.5,1.5],[2.5,2.5]]]],\"op\":[\"-\",0,1]"
#define TETRAS                                                                                     \
    "{\"kind\":\"solids\",\"solids\":[{\"V\":[[0,0,0],[1,0,0],[0,1,0],[0,0,1]],"                   \
    "\"FV\":[[0,2,1],[0,1,3],[0,3,2],[1,2,3]]},{\"V\":[[0.25,0.25,0.25],[1.25,0.25,0.25],"         \
    "[0.25,1.25,0.25],[0.25,0.25,1.25]],\"FV\":[[0,2,1],[0,1,3],[0,3,2],[1,2,3]]}]"

static const char *const requests[] = {
    /* lines: nested squares (holes), a crossing, kept dangling edges, exterior last */
    "{\"kind\":\"lines\",\"lines\":[[[0,0],[8,0]],[[8,0],[8,8]],[[8,8],[0,8]],[[0,8],[0,0]],"
    "[[2,2],[6,2]],[[6,2],[6,6]],[[6,6],[2,6]],[[2,6],[2,2]],[[9,0],[10,1]],[[9,1],[10,0]],"
    "[[3,3],[4,4.5]]],\"options\":{\"operators\":true,\"keep_dangling\":true,"
    "\"exterior_last\":true}}",
    "{\"kind\":\"lines\",\"lines\":[[[0,0],[1e-3,0]]]}",
    "{\"kind\":\"lines\",\"lines\":[[[0,0],[1,1]],[[0,1],[1,0]]],\"options\":"
    "{\"fields\":[\"V\",\"EV\"]}}",
    SQUARES ",\"options\":{\"operators\":true,\"fill\":\"nonzero\"}}",
    SQUARES ",\"options\":{\"fields\":[\"result\"]}}",
    SQUARES ",\"options\":{\"fields\":[\"membership\",\"stats\"]}}",
    "{\"kind\":\"svg\",\"svg\":\"<svg xmlns='http://www.w3.org/2000/svg' viewBox='0 0 10 6'>"
    "<rect width='10' height='6'/><circle cx='5' cy='3' r='2'/><path d='M4 0V6M4 3H10'/></svg>\","
    "\"options\":{\"y_up\":true}}",
    TETRAS ",\"op\":\"intersection\",\"options\":{\"operators\":true}}",
    TETRAS ",\"op\":\"union\",\"options\":{\"fields\":[\"stats\",\"FV\",\"V\",\"result\"]}}",
    TETRAS ",\"op\":\"union\",\"options\":{\"fields\":[\"result\"]}}",
    /* a box with a square hole through its top face's plane: a face with a hole */
    "{\"kind\":\"solids\",\"solids\":[{\"V\":[[0,0,0],[4,0,0],[4,4,0],[0,4,0],[0,0,1],[4,0,1],"
    "[4,4,1],[0,4,1]],\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]},"
    "{\"V\":[[1,1,1],[3,1,1],[3,3,1],[1,3,1],[1,1,2],[3,1,2],[3,3,2],[1,3,2]],"
    "\"FV\":[[0,3,2,1],[4,5,6,7],[0,1,5,4],[1,2,6,5],[2,3,7,6],[3,0,4,7]]}],"
    "\"options\":{\"operators\":true}}",
};

TEST(npz_round_trips_every_kind)
{
    for (size_t i = 0; i < sizeof requests / sizeof *requests; i++) {
        size_t len;
        char *text = result_of(requests[i], &len), why[300] = "";
        REQUIRE(text, "request %zu", i);
        CHECK(round_trip(text, len, 1, why, sizeof why), "request %zu: %s", i, why);
        free(text);
    }
}

/* The arrays are where the README says, with the dtypes it says. */
TEST(npz_names_and_dtypes)
{
    size_t len, zl, nm;
    char *text =
        result_of(TETRAS ",\"op\":\"intersection\",\"options\":{\"operators\":true}}", &len);
    REQUIRE(text, "run");
    char *z = NULL;
    member *ms;
    int rc;
    api_error err;
    const char *bad = npz_of(text, len, &rc, &err, &z, &zl, &ms, &nm);
    REQUIRE(!bad, "%s %s", bad, err.msg);
    static const char *const want[][2] = {
        {"V", "<f8"},
        {"EV", "<i4"},
        {"FV.indptr", "<i4"},
        {"FV.indices", "<i4"},
        {"FE.indices", "<i4"},
        {"CF.indptr", "<i4"},
        {"exterior", "<i4"},
        {"operators.d1.shape", "<i4"},
        {"operators.d2.data", "<i4"},
        {"operators.d3.indptr", "<i4"},
        {"membership.indices", "<i4"},
        {"result.cells", "<i4"},
        {"result.FV.indices", "<i4"},
        {"json", "|u1"},
    };
    for (size_t i = 0; i < sizeof want / sizeof *want; i++) {
        const member *m = find(ms, nm, want[i][0]);
        CHECK(m && !strcmp(m->descr, want[i][1]), "%s: %s", want[i][0], m ? m->descr : "missing");
    }
    const member *V = find(ms, nm, "V"), *sh = find(ms, nm, "operators.d1.shape");
    CHECK(V && V->ndim == 2 && V->shape[1] == 3, "V's shape");
    CHECK(V && sh && elem(sh, 0) == (double)V->shape[0], "d1 has a row per vertex");
    json_t *rest =
        json_loadb((const char *)find(ms, nm, "json")->data, find(ms, nm, "json")->n, 0, NULL);
    CHECK(rest && json_integer_value(json_object_get(rest, "dim")) == 3 &&
              json_object_get(json_object_get(rest, "result"), "volume") &&
              json_object_get(rest, "stats") && !json_object_get(rest, "V") &&
              !json_object_get(rest, "operators"),
          "json holds dim, stats, result.volume, and no array");
    json_decref(rest);
    /* the same result gives the same bytes */
    char *z2 = NULL;
    size_t zl2;
    REQUIRE(render_npz(text, len, NULL, &z2, &zl2, &err) == API_OK, "%s", err.msg);
    CHECK(zl2 == zl && !memcmp(z, z2, zl), "two renderings differ");
    free(z2);
    free(ms);
    free(z);
    free(text);
}

/* Big integers take int64; a number with a fraction makes a float64 array. */
TEST(npz_integer_widths)
{
    const char *t = "{\"dim\":2,\"a\":[1,2147483648],\"b\":[1,-2147483648],\"c\":[1,0.5],"
                    "\"d\":[1,2147483647],\"V\":[[0,0]],\"e\":[1e300]}";
    size_t zl, nm;
    char *z = NULL, why[200];
    member *ms;
    int rc;
    api_error err;
    const char *bad = npz_of(t, strlen(t), &rc, &err, &z, &zl, &ms, &nm);
    REQUIRE(!bad, "%s %s", bad, err.msg);
    static const char *const want[][2] = {{"a", "<i8"}, {"b", "<i4"}, {"c", "<f8"},
                                          {"d", "<i4"}, {"V", "<f8"}, {"e", "<f8"}};
    for (size_t i = 0; i < sizeof want / sizeof *want; i++) {
        const member *m = find(ms, nm, want[i][0]);
        CHECK(m && !strcmp(m->descr, want[i][1]), "%s: %s", want[i][0], m ? m->descr : "missing");
    }
    CHECK(round_trip(t, strlen(t), 1, why, sizeof why), "%s", why);
    free(ms);
    free(z);
}

TEST(npz_refusals_name_the_path)
{
    static const struct {
        const char *result, *needle;
    } cases[] = {
        {"", "expected a JSON object"},
        {"[1,2]", "expected a JSON object"},
        {"{\"dim\":2,\"V\":[[0,0],[1]]}", "V[1]"},
        {"{\"dim\":2,\"V\":[[0,0,0]]}", "V[0]"},
        {"{\"dim\":2,\"EV\":[[0,1],[2]]}", "EV[1]"},
        {"{\"dim\":2,\"FV\":[[0,1,2],[0,x]]}", "FV[1]"},
        {"{\"dim\":2,\"FV\":[0,1]}", "FV"},
        {"{\"dim\":2,\"holes\":{\"a\":[[0,1,2]]}}", "holes.a"},
        {"{\"dim\":2,\"holes\":{\"3\":[]}}", "holes.3"},
        {"{\"dim\":2,\"holes\":{\"3\":[[0,1,2]],\"01\":[[1]]}}", "holes.01"},
        {"{\"dim\":2,\"x\":[1,01]}", "x"},
        {"{\"dim\":2,\"x\":[1,2.]}", "x"},
        {"{\"dim\":2,\"x\":[1,1e999]}", "x"},
        {"{\"dim\":2,\"x\":[1,2],\"x\":[3]}", "twice"},
        {"{\"dim\":2,\"s\":\"a\\qb\"}", "escape"},
        {"{\"dim\":2,\"s\":\"a\\u12\"}", "escape"},
        {"{\"dim\":2} x", "after"},
        {"{\"dim\":2", "expected"},
        {"{\"a\":[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]}",
         "a"},
        {"{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{"
         "\"a\":"
         "{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{"
         "\"a\":"
         "{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":{\"a\":1}}}}}}}}}}}}}}}}}}}}}}}}}}}}}}}}"
         "}}",
         "deep"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char *out = (char *)1;
        size_t len = 7;
        api_error err = {0};
        int rc = render_npz(cases[i].result, strlen(cases[i].result), NULL, &out, &len, &err);
        CHECK(rc == 422 && err.status == 422, "case %zu: %d %s", i, rc, err.msg);
        CHECK(strstr(err.msg, cases[i].needle), "case %zu: \"%s\" lacks %s", i, err.msg,
              cases[i].needle);
        CHECK(out == NULL && len == 0, "case %zu: output not cleared", i);
    }
}

/* Every prefix, and results with bytes changed: refused, or an npz that rebuilds what jansson
 * reads of the same bytes. */
TEST(npz_damaged_results)
{
    size_t len;
    char *text = result_of(SQUARES ",\"options\":{\"operators\":true}}", &len);
    REQUIRE(text, "run");
    len--; /* the final newline: whitespace after the object is fine, and it is tested below */
    for (size_t cut = 0; cut < len; cut++) {
        char *out = NULL;
        size_t ol;
        api_error err;
        int rc = render_npz(text, cut, NULL, &out, &ol, &err);
        CHECK(rc == 422 && !out && err.msg[0], "prefix %zu: %d", cut, rc);
        free(out);
    }
    uint64_t seed = 7;
    size_t ok = 0, refused = 0, n = test_stress(3000);
    for (size_t t = 0; t < n; t++) {
        char *copy = malloc(len + 1), why[300] = "";
        REQUIRE(copy, "malloc");
        memcpy(copy, text, len + 1);
        for (int k = 0; k < 2; k++)
            copy[(size_t)(test_rnd(&seed) * (double)len)] = "0123456789-,[]{}\"e. :\\"[t % 21];
        char *out = NULL;
        size_t ol;
        api_error err;
        int rc = render_npz(copy, len + 1, NULL, &out, &ol, &err);
        free(out);
        if (rc == API_OK) {
            ok++;
            CHECK(round_trip(copy, len + 1, 0, why, sizeof why), "mutation %zu: %s\n%s", t, why,
                  copy);
        } else {
            refused++;
            CHECK(rc == 422 && err.msg[0], "mutation %zu: %d", t, rc);
        }
        free(copy);
    }
    CHECK(ok > 0 && refused > 0, "mutations: %zu written, %zu refused", ok, refused);
    free(text);
}
