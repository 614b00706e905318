/* lines.c — the "lines" kind: {"kind":"lines","lines":[[[x1,y1],[x2,y2]],...],"options":{...}}.
 *
 * Validates the request (every key known, every value of the right shape; messages name the JSON
 * path of the problem, status 422), copies the segments into the flat array arr2_build() takes,
 * runs the core and writes the complex with api_lar2_write().
 *
 * Two parsers fill the same lines_req.  The reference is the jansson tree (api_lines_parse), which
 * every error message comes from.  The fast one (api_lines_parse_fast) reads the body directly:
 * jansson needs ~2.5 s and ~800 MB for a request of a million segments (a node per number), this
 * ~0.4 s and the 32 MB of the segment array.  It is strict: it takes only an object with the keys
 * kind, lines and options, each once, "kind" spelled "lines" without escapes, lines exactly of
 * the shape [[[x,y],[x,y]],...] with JSON numbers that convert exactly as jansson converts them
 * (integers as int64 then double, reals by strtod in the C locale, overflow left to jansson),
 * and options handed to jansson (they are small) and to the same parse_options().  Anything
 * else returns "not handled" and the jansson path decides, so both paths agree by construction;
 * test_api.c checks it on generated and mutated bodies.
 *
 * Options:
 *   precision      number > 0: the snapping grid step (default: the core's, from the extent)
 *   keep_dangling  bool: keep bridges and dangling trees
 *   exterior_last  bool: the seeds' convention, exterior cycles as the last rows of FV and FE
 *   operators      bool: add the boundary operators d1, d2 as CSR
 *   fields         array of names among "V","EV","FV","FE","holes","exterior","stats",
 *                  "operators" (default: all but operators)
 *
 * Threads: reentrant, no globals.  Ownership: the body and req are borrowed; a parsed request
 * (*parsed) belongs to the caller, who frees it with api_lines_free().
 */
#include "api/api_int.h"

#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct lines_opts {
    double precision; /* 0: the core's default */
    int keep_dangling;
    int exterior_last;
    int operators;
    unsigned fields; /* API_F_* */
} lines_opts;

typedef struct lines_req {
    double *seg; /* owned: 4n doubles x1, y1, x2, y2 */
    size_t n;    /* segments */
    lines_opts opt;
} lines_req;

static int parse_bool(const json_t *v, const char *name, int *out, api_error *err)
{
    if (!json_is_boolean(v))
        return api_fail(err, API_EINVALID, "options.%s: expected true or false", name);
    *out = json_is_true(v);
    return API_OK;
}

static int parse_fields(const json_t *v, unsigned *out, api_error *err)
{
    size_t i;
    json_t *name;
    if (!json_is_array(v))
        return api_fail(err, API_EINVALID,
                        "options.fields: expected an array of names among \"V\", \"EV\", \"FV\", "
                        "\"FE\", \"holes\", \"exterior\", \"stats\", \"operators\"");
    *out = 0;
    json_array_foreach(v, i, name)
    {
        unsigned bit = 0;
        for (unsigned k = 0; json_is_string(name) && k < API_NFIELDS; k++)
            if (strcmp(json_string_value(name), api_field_names[k]) == 0) bit = 1u << k;
        if (!bit)
            return api_fail(err, API_EINVALID,
                            "options.fields[%zu]: expected one of \"V\", \"EV\", \"FV\", \"FE\", "
                            "\"holes\", \"exterior\", \"stats\", \"operators\"",
                            i);
        *out |= bit;
    }
    return API_OK;
}

static int parse_options(const json_t *o, lines_opts *opt, api_error *err)
{
    const char *key;
    json_t *v;
    int rc = API_OK;
    *opt = (lines_opts){.fields = API_F_DEFAULT};
    if (!o) return API_OK;
    if (!json_is_object(o)) return api_fail(err, API_EINVALID, "options: expected an object");
    json_object_foreach((json_t *)o, key, v)
    {
        if (strcmp(key, "precision") == 0) {
            if (!json_is_number(v) || !(json_number_value(v) > 0) ||
                !isfinite(json_number_value(v)))
                return api_fail(err, API_EINVALID, "options.precision: expected a number > 0");
            opt->precision = json_number_value(v);
        } else if (strcmp(key, "keep_dangling") == 0) {
            rc = parse_bool(v, key, &opt->keep_dangling, err);
        } else if (strcmp(key, "exterior_last") == 0) {
            rc = parse_bool(v, key, &opt->exterior_last, err);
        } else if (strcmp(key, "operators") == 0) {
            rc = parse_bool(v, key, &opt->operators, err);
        } else if (strcmp(key, "fields") == 0) {
            rc = parse_fields(v, &opt->fields, err);
        } else {
            return api_fail(err, API_EINVALID,
                            "options.%.64s: unknown option (expected precision, keep_dangling, "
                            "exterior_last, operators or fields)",
                            key);
        }
        if (rc != API_OK) return rc;
    }
    if (opt->operators) opt->fields |= API_F_OPERATORS;
    return API_OK;
}

/* Copies the segments of lines into *seg (malloc'd, 4 doubles a segment, caller frees). */
static int parse_lines(const json_t *lines, double **seg, size_t *n, api_error *err)
{
    size_t i, count;
    json_t *s;
    *seg = NULL;
    *n = 0;
    if (!lines) return api_fail(err, API_EINVALID, "lines: required, an array of segments");
    if (!json_is_array(lines))
        return api_fail(err, API_EINVALID,
                        "lines: expected an array of segments [[x1,y1],[x2,y2]]");
    count = json_array_size(lines);
    if (count > ARR2_MAX_SEGMENTS)
        return api_fail(err, API_EINVALID, "lines: %zu segments, at most %u allowed", count,
                        (unsigned)ARR2_MAX_SEGMENTS);
    *seg = malloc((count ? count : 1) * 4 * sizeof **seg);
    if (!*seg) return api_fail(err, API_ENOMEM, "out of memory for %zu segments", count);
    json_array_foreach(lines, i, s)
    {
        if (!json_is_array(s) || json_array_size(s) != 2) {
            api_fail(err, API_EINVALID, "lines[%zu]: expected 2 points [[x1,y1],[x2,y2]]", i);
            goto fail;
        }
        for (size_t j = 0; j < 2; j++) {
            const json_t *p = json_array_get(s, j);
            if (!json_is_array(p) || json_array_size(p) != 2) {
                api_fail(err, API_EINVALID, "lines[%zu][%zu]: expected 2 finite numbers", i, j);
                goto fail;
            }
            for (size_t k = 0; k < 2; k++) {
                const json_t *x = json_array_get(p, k);
                if (!json_is_number(x) || !isfinite(json_number_value(x))) {
                    api_fail(err, API_EINVALID, "lines[%zu][%zu][%zu]: expected a finite number", i,
                             j, k);
                    goto fail;
                }
                (*seg)[4 * i + 2 * j + k] = json_number_value(x);
            }
        }
    }
    *n = count;
    return API_OK;
fail:
    free(*seg);
    *seg = NULL;
    return err ? err->status : API_EINVALID;
}

void api_lines_free(void *parsed)
{
    lines_req *r = parsed;
    if (!r) return;
    free(r->seg);
    free(r);
}

const double *api_lines_segments(const void *parsed, size_t *n)
{
    const lines_req *r = parsed;
    *n = r->n;
    return r->seg;
}

int api_lines_same(const void *a, const void *b)
{
    const lines_req *x = a, *y = b;
    return x->n == y->n && memcmp(&x->opt, &y->opt, sizeof x->opt) == 0 &&
           (x->n == 0 || memcmp(x->seg, y->seg, 4 * x->n * sizeof *x->seg) == 0);
}

int api_lines_parse(const json_t *req, void **parsed, api_error *err)
{
    const char *key;
    json_t *v;
    lines_req *r;
    int rc;
    *parsed = NULL;
    json_object_foreach((json_t *)req, key, v)
    {
        if (strcmp(key, "kind") && strcmp(key, "lines") && strcmp(key, "options"))
            return api_fail(err, API_EINVALID,
                            "%.64s: unknown key (expected kind, lines or options)", key);
    }
    r = calloc(1, sizeof *r);
    if (!r) return api_fail(err, API_ENOMEM, "out of memory");
    rc = parse_options(json_object_get(req, "options"), &r->opt, err);
    if (rc != API_OK) goto fail;
    rc = parse_lines(json_object_get(req, "lines"), &r->seg, &r->n, err);
    if (rc != API_OK) goto fail;
    *parsed = r;
    return API_OK;
fail:
    api_lines_free(r);
    return rc;
}

/* ---- the fast parser ----------------------------------------------------------------------- */

typedef struct cursor {
    const char *p;     /* next byte */
    const char *end;   /* end of the body */
    locale_t c_locale; /* for strtod_l; (locale_t)0 until first needed */
} cursor;

static void skip_ws(cursor *c)
{
    while (c->p < c->end && (*c->p == ' ' || *c->p == '\n' || *c->p == '\r' || *c->p == '\t'))
        c->p++;
}

/* Consumes ch after optional whitespace. */
static int eat(cursor *c, char ch)
{
    skip_ws(c);
    if (c->p < c->end && *c->p == ch) {
        c->p++;
        return 1;
    }
    return 0;
}

static int is_digit(const cursor *c)
{
    return c->p < c->end && *c->p >= '0' && *c->p <= '9';
}

/* Reads one JSON number into *out, converted as jansson converts it; 0 when the token is not a
 * JSON number or is one we leave to jansson (long integers, out of range). */
static int read_number(cursor *c, double *out)
{
    static const double p10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                   1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                   1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    const char *start;
    int neg = 0, real = 0, ndig = 0, frac = 0, exp = 0, eneg = 0;
    uint64_t w = 0;
    skip_ws(c);
    start = c->p;
    if (c->p < c->end && *c->p == '-') neg = 1, c->p++;
    if (!is_digit(c)) return 0;
    if (*c->p == '0') {
        c->p++;
    } else {
        while (is_digit(c)) {
            if (ndig < 19) w = w * 10 + (uint64_t)(*c->p - '0');
            ndig += ndig || *c->p != '0';
            c->p++;
        }
    }
    if (c->p < c->end && *c->p == '.') {
        real = 1;
        c->p++;
        if (!is_digit(c)) return 0;
        while (is_digit(c)) {
            if (ndig < 19) w = w * 10 + (uint64_t)(*c->p - '0'), frac++;
            ndig += ndig || *c->p != '0';
            c->p++;
        }
    }
    if (c->p < c->end && (*c->p == 'e' || *c->p == 'E')) {
        real = 1;
        c->p++;
        if (c->p < c->end && (*c->p == '+' || *c->p == '-')) eneg = *c->p == '-', c->p++;
        if (!is_digit(c)) return 0;
        while (is_digit(c)) {
            if (exp < 100000) exp = exp * 10 + (*c->p - '0');
            c->p++;
        }
    }
    if (!real) {
        /* jansson: an integer token is a json_integer (int64; longer ones are its error), and
         * json_number_value() converts it: "-0" is +0. */
        if (ndig > 18) return 0;
        *out = (double)(neg ? -(int64_t)w : (int64_t)w);
        return 1;
    }
    /* jansson: strtod.  When the significand is exact in a double and the power of ten too,
     * one IEEE operation is the correctly rounded result, as strtod's (Clinger's fast path). */
    int e10 = (eneg ? -exp : exp) - frac;
    if (FLT_EVAL_METHOD == 0 && ndig <= 19 && w <= ((uint64_t)1 << 53) && e10 >= -22 && e10 <= 22) {
        double v = (double)w;
        v = e10 < 0 ? v / p10[-e10] : v * p10[e10];
        *out = neg ? -v : v;
        return 1;
    }
    char tmp[64], *end;
    size_t n = (size_t)(c->p - start);
    if (n >= sizeof tmp) return 0;
    memcpy(tmp, start, n);
    tmp[n] = 0;
    if (!c->c_locale) c->c_locale = newlocale(LC_ALL_MASK, "C", (locale_t)0);
    if (!c->c_locale) return 0;
    *out = strtod_l(tmp, &end, c->c_locale);
    return end == tmp + n && isfinite(*out);
}

/* Reads "[x,y]". */
static int read_point(cursor *c, double *xy)
{
    return eat(c, '[') && read_number(c, &xy[0]) && eat(c, ',') && read_number(c, &xy[1]) &&
           eat(c, ']');
}

/* Reads the lines array; *seg grows as needed.  Past ARR2_MAX_SEGMENTS it only counts. */
static int read_lines(cursor *c, double **seg, size_t *n, size_t *cap)
{
    double s[4];
    if (!eat(c, '[')) return 0;
    if (eat(c, ']')) return 1;
    do {
        if (!(eat(c, '[') && read_point(c, s) && eat(c, ',') && read_point(c, s + 2) &&
              eat(c, ']')))
            return 0;
        if (*n < ARR2_MAX_SEGMENTS) {
            if (*n == *cap) {
                size_t nc = *cap ? 2 * *cap : 1024;
                double *p = realloc(*seg, nc * 4 * sizeof *p);
                if (!p) return 0; /* the jansson path will report it */
                *seg = p;
                *cap = nc;
            }
            memcpy(*seg + 4 * *n, s, sizeof s);
        }
        (*n)++;
    } while (eat(c, ','));
    return eat(c, ']');
}

/* Reads a key without escapes or control characters into key[0..n); 0 if it has any. */
static int read_key(cursor *c, char *key, size_t n)
{
    size_t k = 0;
    if (!eat(c, '"')) return 0;
    while (c->p < c->end && *c->p != '"') {
        unsigned char ch = (unsigned char)*c->p++;
        if (ch == '\\' || ch < 0x20 || k + 1 >= n) return 0;
        key[k++] = (char)ch;
    }
    key[k] = 0;
    return c->p < c->end && *c->p++ == '"' && eat(c, ':');
}

/* Skips one JSON value, without validating it (jansson does, later); returns its extent. */
static int skip_value(cursor *c, const char **start, size_t *len)
{
    int depth = 0;
    skip_ws(c);
    *start = c->p;
    while (c->p < c->end) {
        char ch = *c->p;
        if (ch == '"') {
            c->p++;
            while (c->p < c->end && *c->p != '"') {
                if (*c->p == '\\' && c->end - c->p < 2) return 0;
                c->p += *c->p == '\\' ? 2 : 1;
            }
            if (c->p >= c->end) return 0;
        } else if (ch == '[' || ch == '{') {
            depth++;
        } else if (ch == ']' || ch == '}') {
            if (depth == 0) break;
            depth--;
        } else if (depth == 0 &&
                   (ch == ',' || ch == ' ' || ch == '\n' || ch == '\r' || ch == '\t')) {
            break;
        }
        c->p++;
        if (depth == 0 && (ch == '"' || ch == ']' || ch == '}')) break;
    }
    *len = (size_t)(c->p - *start);
    return *len > 0;
}

int api_lines_parse_fast(const char *body, size_t len, void **parsed, api_error *err)
{
    cursor c = {.p = body, .end = body + len};
    lines_req *r = NULL;
    json_t *opts = NULL;
    size_t cap = 0;
    int seen_kind = 0, seen_lines = 0, seen_opts = 0, rc = API_OK;
    char key[16];
    *parsed = NULL;
    r = calloc(1, sizeof *r);
    if (!r) goto fallback;
    r->opt = (lines_opts){.fields = API_F_DEFAULT};
    if (!eat(&c, '{')) goto fallback;
    do {
        if (!read_key(&c, key, sizeof key)) goto fallback;
        if (strcmp(key, "kind") == 0 && !seen_kind) {
            seen_kind = 1;
            if (!(eat(&c, '"') && c.end - c.p >= 6 && memcmp(c.p, "lines\"", 6) == 0))
                goto fallback;
            c.p += 6;
        } else if (strcmp(key, "lines") == 0 && !seen_lines) {
            seen_lines = 1;
            if (!read_lines(&c, &r->seg, &r->n, &cap)) goto fallback;
        } else if (strcmp(key, "options") == 0 && !seen_opts) {
            const char *o;
            size_t olen;
            seen_opts = 1;
            if (!skip_value(&c, &o, &olen)) goto fallback;
            opts = json_loadb(o, olen, JSON_DECODE_ANY | JSON_REJECT_DUPLICATES, NULL);
            if (!opts || parse_options(opts, &r->opt, NULL) != API_OK) goto fallback;
            json_decref(opts);
            opts = NULL;
        } else {
            goto fallback;
        }
    } while (eat(&c, ','));
    if (!eat(&c, '}') || !seen_kind || !seen_lines) goto fallback;
    skip_ws(&c);
    if (c.p != c.end) goto fallback;
    if (r->n > ARR2_MAX_SEGMENTS) {
        rc = api_fail(err, API_EINVALID, "lines: %zu segments, at most %u allowed", r->n,
                      (unsigned)ARR2_MAX_SEGMENTS);
        goto fallback;
    }
    if (c.c_locale) freelocale(c.c_locale);
    *parsed = r;
    return API_OK;
fallback:
    if (c.c_locale) freelocale(c.c_locale);
    json_decref(opts);
    api_lines_free(r);
    return rc;
}

/* ---- running ------------------------------------------------------------------------------- */

int api_lines_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err)
{
    static const double no_segment[4];
    const lines_req *r = parsed;
    arr2_opts ao = {.precision = r->opt.precision,
                    .keep_dangling = r->opt.keep_dangling,
                    .threads = ro->threads,
                    .cancel = ro->cancel,
                    .progress = ro->progress,
                    .udata = ro->udata};
    api_lar2_fmt fmt = {.fields = r->opt.fields, .exterior_last = r->opt.exterior_last};
    lar2 c = {0};
    char core_msg[API_ERRMAX] = "";
    int rc = arr2_build(r->n ? r->seg : no_segment, r->n, &ao, &c, core_msg, sizeof core_msg);
    if (rc != ARR_OK) {
        rc = api_core_fail(err, rc, core_msg);
        goto out;
    }
    rc = api_lar2_write(out, &c, &fmt, err);
out:
    lar2_free(&c);
    return rc;
}
