/* run.c — the entry points of api/: load the JSON, dispatch on "kind", map errors to statuses.
 *
 * The table of kinds below is the one place that knows which kinds exist.  A kind parses and
 * validates its own keys and runs the core (api_int.h, api_kind); this file loads the body with
 * jansson, frees the tree as soon as the kind has parsed it
 * (before the core runs), and turns jansson's errors into error values:
 *   - syntax errors, bad UTF-8 and nesting deeper than jansson's limit (2048 levels in 2.14:
 *     "maximum parsing depth reached", an error value, not a recursion) are 400 with the
 *     parser's line and column;
 *   - a number out of range (1e400, an integer beyond 64 bits) or a duplicate key is valid JSON
 *     grammar with an invalid value, so it is 422; jansson only tells the byte position, and
 *     json_path_at() rescans the body up to there to name the JSON path of the offending value.
 *
 * Threads: reentrant, no globals (the tables are constant).
 * Ownership: the body is borrowed; *out and *canon are malloc'd for the caller.
 */
#include "api/api_int.h"

#include <errno.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The stages of each kind in the order they run, with the share of the run's time done at the
 * end of each, measured with `cellar --progress` on two threads: lines on 30 000 random
 * segments, svg on 30 000 lines and 3 000 circles, polygons on the union of 20 000 turned
 * squares, solids on 2 000 turned cubes with an op (the output, writing every double in its
 * shortest form, is a third of a 2D run).  Reading the request comes before the first stage
 * and is not counted.  openapi.json lists the same names. */
const api_stage api_stages_lines[] = {
    {"snap", 0.002},       {"buckets", 0.014}, {"intersect", 0.07}, {"split", 0.33},
    {"biconnected", 0.38}, {"faces", 0.64},    {"output", 1},       {NULL, 0}};
const api_stage api_stages_svg[] = {{"svg", 0.18},       {"snap", 0.182}, {"buckets", 0.19},
                                    {"intersect", 0.24}, {"split", 0.45}, {"biconnected", 0.50},
                                    {"faces", 0.68},     {"output", 1},   {NULL, 0}};
const api_stage api_stages_polygons[] = {{"snap", 0.002},
                                         {"buckets", 0.016},
                                         {"intersect", 0.057},
                                         {"split", 0.22},
                                         {"biconnected", 0.26},
                                         {"faces", 0.45},
                                         {"membership", 0.57},
                                         {"select", 0.58},
                                         {"polygons", 0.59},
                                         {"output", 1},
                                         {NULL, 0}};
const api_stage api_stages_solids[] = {{"check", 0.01},      {"snap", 0.02},   {"pairs", 0.065},
                                       {"cuts", 0.20},       {"planes", 0.44}, {"cells", 0.81},
                                       {"membership", 0.82}, {"output", 1},    {NULL, 0}};

static const api_kind kinds[] = {
    {"lines", api_lines_parse, api_lines_run, api_lines_free, NULL, api_stages_lines,
     api_lines_parse_packed},
    {"svg", api_svg_parse, api_svg_run, api_svg_free, api_svg_check, api_stages_svg, NULL},
    {"solids", api_solids_parse, api_solids_run, api_solids_free, api_solids_check,
     api_stages_solids, api_solids_parse_packed},
    {"polygons", api_polygons_parse, api_polygons_run, api_polygons_free, NULL, api_stages_polygons,
     api_polygons_parse_packed},
};
#define NKINDS (sizeof kinds / sizeof kinds[0])

size_t api_kind_count(void)
{
    return NKINDS;
}

const char *api_kind_name(size_t i)
{
    return i < NKINDS ? kinds[i].name : NULL;
}

const char *api_stage_name(const char *kind, size_t i)
{
    for (size_t k = 0; k < NKINDS; k++)
        if (!strcmp(kinds[k].name, kind)) {
            const api_stage *st = kinds[k].stages;
            for (size_t j = 0; st[j].name; j++)
                if (j == i) return st[j].name;
            return NULL;
        }
    return NULL;
}

static void progress_tick(void *udata, const char *stage, double f)
{
    api_progress *p = udata;
    size_t i = p->cur;
    while (p->st[i].name && strcmp(p->st[i].name, stage)) i++;
    if (!p->st[i].name) return; /* an earlier stage, or one this kind does not list */
    if (!(f >= 0)) f = 0;       /* NaN too */
    if (f > 1) f = 1;
    double lo = i ? p->st[i - 1].end : 0, whole = lo + (p->st[i].end - lo) * f;
    if (f == 1 && p->st[i + 1].name) i++; /* this stage is over: the next one runs */
    if (whole < p->last) whole = p->last;
    if (i == p->cur && whole == p->last && f > 0) return; /* nothing new */
    p->cur = i;
    p->last = whole;
    p->up(p->udata, p->st[i].name, whole);
}

void api_progress_wrap(api_progress *p, const api_stage *st, const api_run_opts *ro,
                       api_run_opts *wrapped)
{
    *wrapped = *ro;
    if (!ro->progress) return;
    *p = (api_progress){.st = st, .up = ro->progress, .udata = ro->udata};
    wrapped->progress = progress_tick;
    wrapped->udata = p;
}

int api_fail(api_error *err, int status, const char *fmt, ...)
{
    va_list ap;
    if (!err) return status;
    err->status = status;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    for (char *p = err->msg; *p; p++)
        if ((unsigned char)*p < 0x20 || (unsigned char)*p > 0x7e) *p = '?';
    return status;
}

int api_only_keys(const json_t *req, const char *own, api_error *err)
{
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)req, key, v)
    {
        if (strcmp(key, "kind") && strcmp(key, own) && strcmp(key, "options"))
            return api_fail(err, API_EINVALID, "%.64s: unknown key (expected kind, %s or options)",
                            key, own);
    }
    return API_OK;
}

int api_core_fail(api_error *err, int arr_code, const char *core_msg)
{
    const char *m = core_msg && *core_msg ? core_msg : NULL;
    switch (arr_code) {
    case ARR_EINVAL:
        return api_fail(err, API_EINVALID, "%s", m ? m : "invalid input");
    case ARR_ELIMIT:
        return api_fail(err, API_EINVALID, "%s", m ? m : "input beyond a limit");
    case ARR_ENOMEM:
        return api_fail(err, API_ENOMEM, "out of memory%s%s", m ? ": " : "", m ? m : "");
    case ARR_ECANCELED:
        return api_fail(err, API_ECANCELED, "canceled");
    default:
        return api_fail(err, API_EINTERNAL, "internal error (core code %d)%s%s", arr_code,
                        m ? ": " : "", m ? m : "");
    }
}

/* One open container while rescanning a body. */
typedef struct scan_frame {
    char type;      /* '[' or '{' */
    int expect_key; /* object: the next string is a key */
    size_t index;   /* array: index of the current element */
    size_t koff;    /* object: the current key's raw bytes body[koff .. koff+klen) */
    size_t klen;
} scan_frame;

#define SCAN_MAX_DEPTH 4096 /* above jansson's 2048: a body it parsed that far fits */
#define SCAN_KEY_MAX   64   /* longer keys are cut in messages */

/* Writes into path[0..n) the JSON path ("lines[3][1][0]", "options", "" for the root) of the
 * value (or object key) that contains byte stop-1 of body, by following the structure of
 * body[0..stop).  The body is known to be well-formed up to there: jansson read it. */
static void json_path_at(const char *body, size_t len, size_t stop, char *path, size_t n)
{
    scan_frame *st = NULL;
    size_t depth = 0, i = 0, w = 0;
    path[0] = 0;
    if (stop > len) stop = len;
    if (stop > 0) stop--; /* jansson's position is just past the offending token */
    st = malloc(SCAN_MAX_DEPTH * sizeof *st);
    if (!st) return;
    while (i < stop) {
        char ch = body[i];
        scan_frame *top = depth ? &st[depth - 1] : NULL;
        if (ch == '"') {
            size_t j = i + 1;
            while (j < len && body[j] != '"') j += body[j] == '\\' ? 2 : 1;
            if (j >= stop) break; /* the offending token is this string (a duplicate key) */
            if (top && top->type == '{' && top->expect_key) {
                top->koff = i + 1;
                top->klen = j - i - 1;
            }
            i = j + 1;
            continue;
        }
        if (ch == '[' || ch == '{') {
            if (depth == SCAN_MAX_DEPTH) goto out;
            st[depth++] = (scan_frame){.type = ch, .expect_key = ch == '{'};
        } else if ((ch == ']' || ch == '}') && depth) {
            depth--;
        } else if (ch == ',' && top) {
            if (top->type == '[')
                top->index++;
            else
                top->expect_key = 1;
        } else if (ch == ':' && top) {
            top->expect_key = 0;
        }
        i++;
    }
    for (size_t d = 0; d < depth && w + 1 < n; d++) {
        const scan_frame *f = &st[d];
        int k;
        if (f->type == '[') {
            k = snprintf(path + w, n - w, "[%zu]", f->index);
        } else {
            if (f->expect_key) break; /* inside a key: the path ends at its object */
            k = snprintf(path + w, n - w, "%s%.*s", w ? "." : "",
                         (int)(f->klen < SCAN_KEY_MAX ? f->klen : SCAN_KEY_MAX), body + f->koff);
        }
        if (k < 0 || (size_t)k >= n - w) break;
        w += (size_t)k;
    }
out:
    free(st);
}

/* Loads body as JSON; on failure fills *err and returns NULL. */
static json_t *load(const char *body, size_t len, api_error *err)
{
    json_error_t je;
    json_t *root;
    size_t i = 0;
    while (i < len && (body[i] == ' ' || body[i] == '\t' || body[i] == '\n' || body[i] == '\r'))
        i++;
    if (i == len) {
        api_fail(err, API_EJSON, "malformed JSON: empty body");
        return NULL;
    }
    root = json_loadb(body, len, JSON_DECODE_ANY | JSON_REJECT_DUPLICATES, &je);
    if (root) return root;
    switch (json_error_code(&je)) {
    case json_error_out_of_memory:
        api_fail(err, API_ENOMEM, "out of memory while parsing the request");
        break;
    case json_error_numeric_overflow:
    case json_error_duplicate_key: {
        char path[256];
        json_path_at(body, len, je.position > 0 ? (size_t)je.position : 0, path, sizeof path);
        api_fail(err, API_EINVALID, "%s: %s (line %d, column %d)", *path ? path : "request",
                 je.text, je.line, je.column);
        break;
    }
    default:
        api_fail(err, API_EJSON, "malformed JSON at line %d, column %d: %s", je.line, je.column,
                 je.text);
        break;
    }
    return NULL;
}

/* Finds the handler of root's "kind". */
static const api_kind *kind_of(const json_t *root, api_error *err)
{
    const json_t *k;
    char expected[128];
    size_t w = 0;
    if (!json_is_object(root)) {
        api_fail(err, API_EINVALID, "request: expected an object {\"kind\": ...}");
        return NULL;
    }
    k = json_object_get(root, "kind");
    if (json_is_string(k))
        for (size_t i = 0; i < NKINDS; i++)
            if (strcmp(json_string_value(k), kinds[i].name) == 0) return &kinds[i];
    for (size_t i = 0; i < NKINDS && w < sizeof expected; i++) {
        const char *sep = i == 0 ? "" : i + 1 == NKINDS ? " or " : ", ";
        int n = snprintf(expected + w, sizeof expected - w, "%s\"%s\"", sep, kinds[i].name);
        if (n < 0) break;
        w += (size_t)n;
    }
    const char *type = json_string_value(json_object_get(root, "type"));
    static const char *const geo[] = {"FeatureCollection",  "Feature", "Polygon",    "MultiPolygon",
                                      "GeometryCollection", "Point",   "LineString", "MultiPoint",
                                      "MultiLineString"};
    int geojson = 0;
    for (size_t i = 0; type && i < sizeof geo / sizeof *geo; i++) geojson |= !strcmp(type, geo[i]);
    if (!k && geojson)
        api_fail(err, API_EINVALID,
                 "kind: required: this is GeoJSON (a %.20s), not a request; overlay files "
                 "with cellar polygons A.geojson B.geojson --op OP, or post {\"kind\": "
                 "\"polygons\", \"layers\": {\"a\": ..., \"b\": ...}, \"op\": ...}",
                 type);
    else if (!k)
        api_fail(err, API_EINVALID, "kind: required, expected %s", expected);
    else
        api_fail(err, API_EINVALID, "kind: expected %s", expected);
    return NULL;
}

/* The fast path of parse(): the big arrays read by api_packed_scan, jansson on the rest.  1 when
 * it parsed the request (*pk then holds the arrays, some handed to *parsed), 0 when the caller
 * must read the whole text as before (*pk empty), -1 out of memory. */
static int parse_fast(const char *body, size_t len, const api_kind **kind, void **parsed,
                      json_t **tree, api_packed_set *pk)
{
    int r = api_packed_enabled() ? api_packed_scan(body, len, pk) : 0;
    if (r <= 0) return r;
    json_error_t je;
    json_t *root = json_loadb(pk->rest, pk->restlen, JSON_DECODE_ANY | JSON_REJECT_DUPLICATES, &je);
    const json_t *k = json_is_object(root) ? json_object_get(root, "kind") : NULL;
    for (size_t i = 0; json_is_string(k) && i < NKINDS; i++) {
        api_error quiet = {0};
        if (strcmp(json_string_value(k), kinds[i].name) || !kinds[i].parse_packed) continue;
        if (kinds[i].parse_packed(root, pk, parsed, &quiet) != API_OK) break;
        *kind = &kinds[i];
        if (tree)
            *tree = root;
        else
            json_decref(root);
        return 1;
    }
    json_decref(root);
    api_packed_free(pk);
    return 0;
}

/* Parses body into the request of its kind: *kind and *parsed (free with (*kind)->free); with
 * tree, a valid request's JSON tree is handed over too (the caller decrefs it), else freed.
 * With pk, a request whose big arrays the fast reader took comes that way: *pk holds them and
 * *tree is the rest's (api_packed_canon writes the whole); the caller frees *pk after *parsed. */
static int parse(const char *body, size_t len, const api_kind **kind, void **parsed, json_t **tree,
                 api_packed_set *pk, api_error *err)
{
    json_t *root;
    int rc;
    *kind = NULL;
    *parsed = NULL;
    if (tree) *tree = NULL;
    if (pk) {
        int r = parse_fast(body, len, kind, parsed, tree, pk);
        if (r < 0) return api_fail(err, API_ENOMEM, "out of memory while reading the request");
        if (r > 0) return API_OK;
    }
    root = load(body, len, err);
    if (!root) return err ? err->status : API_EJSON;
    *kind = kind_of(root, err);
    rc = *kind ? (*kind)->parse(root, parsed, err) : API_EINVALID;
    if (tree && rc == API_OK)
        *tree = root; /* the caller's now */
    else
        json_decref(root);
    return rc;
}

/* A request parsed (and, from api_check_request_ex, checked): its kind, its parsed form and
 * the arrays the fast reader took (which the parsed form may point into). */
struct api_request {
    const api_kind *kind;
    void *req;
    api_packed_set pk;
};

/* Runs a parsed request (rc: API_OK, or the status its parse failed with, err filled) and
 * frees it: the one run path of api_run_json_ex and api_request_run. */
static int run_parsed(int rc, const api_kind *kind, void *req, api_packed_set *pk,
                      const api_run_opts *ro, char **out, size_t *outlen, api_error *err)
{
    api_run_opts dflt = {0};
    api_buf b = {0};
    api_progress pr;
    api_run_opts wr;
    if (!ro) ro = &dflt;
    if (rc != API_OK) goto fail;
    api_progress_wrap(&pr, kind->stages, ro, &wr);
    b.sink = wr.stream;
    b.progress = wr.progress;
    b.udata = wr.udata;
    b.cancel = ro->cancel;
    rc = kind->run(req, &wr, &b, err);
fail:
    if (kind) kind->free(req);
    api_packed_free(pk);
    void (*up)(void *, const char *, double) = b.progress; /* b goes in api_buf_finish */
    void *uu = b.udata;
    rc = api_buf_finish(&b, rc, out, outlen, err);
    if (rc == API_OK && up) up(uu, "output", 1);
    return rc;
}

int api_run_json_ex(const char *body, size_t len, const api_run_opts *ro, char **out,
                    size_t *outlen, api_error *err)
{
    const api_kind *kind = NULL;
    void *req = NULL;
    api_packed_set pk = {0};
    *out = NULL;
    *outlen = 0;
    if (err) err->status = API_OK, err->msg[0] = 0;
    int rc = parse(body, len, &kind, &req, NULL, &pk, err);
    return run_parsed(rc, kind, req, &pk, ro, out, outlen, err);
}

int api_request_run(api_request *q, const api_run_opts *ro, char **out, size_t *outlen,
                    api_error *err)
{
    *out = NULL;
    *outlen = 0;
    if (err) err->status = API_OK, err->msg[0] = 0;
    int rc = run_parsed(API_OK, q->kind, q->req, &q->pk, ro, out, outlen, err);
    free(q);
    return rc;
}

void api_request_free(api_request *q)
{
    if (!q) return;
    q->kind->free(q->req);
    api_packed_free(&q->pk);
    free(q);
}

/* Whether every object under v has its keys in sorted (strcmp) order, as the canonical form
 * writes them: all of them when all, else only those under a "properties" member (a feature's
 * properties are written back in their order, the rest of the request is read by key). */
static int keys_sorted(const json_t *v, int all)
{
    if (json_is_array(v)) {
        for (size_t i = 0; i < json_array_size(v); i++)
            if (!keys_sorted(json_array_get(v, i), all)) return 0;
        return 1;
    }
    if (!json_is_object(v)) return 1;
    const char *key, *prev = NULL;
    json_t *m;
    json_object_foreach((json_t *)v, key, m)
    {
        if (all && prev && strcmp(prev, key) > 0) return 0;
        if (!keys_sorted(m, all || !strcmp(key, "properties"))) return 0;
        prev = key;
    }
    return 1;
}

/* Whether the canonical form of root parses to the request root parsed to: a parse reads
 * objects by key, except "layers" (in order: the result's layers) and the features'
 * "properties" (written back as they are); numbers and strings read back the same. */
static int canon_same_request(const json_t *root)
{
    const json_t *ls = json_object_get(root, "layers");
    const char *key, *prev = NULL;
    json_t *m;
    if (json_is_object(ls)) json_object_foreach((json_t *)ls, key, m)
        {
            if (prev && strcmp(prev, key) > 0) return 0;
            prev = key;
        }
    return keys_sorted(root, 0);
}

int api_run_json(const char *body, size_t len, int threads, char **out, size_t *outlen,
                 api_error *err)
{
    api_run_opts ro = {.threads = threads};
    return api_run_json_ex(body, len, &ro, out, outlen, err);
}

int api_check_request_ex(const char *body, size_t len, char **canon, size_t *canonlen,
                         const char **kind_name, api_request **checked, api_error *err)
{
    const api_kind *kind = NULL;
    void *req = NULL;
    json_t *root = NULL;
    int rc;
    if (canon) *canon = NULL;
    if (canonlen) *canonlen = 0;
    if (err) err->status = API_OK, err->msg[0] = 0;
    if (kind_name) *kind_name = NULL;
    if (checked) *checked = NULL;
    api_packed_set pk = {0};
    rc = parse(body, len, &kind, &req, canon || checked ? &root : NULL, &pk, err);
    if (rc == API_OK && kind->check) rc = kind->check(req, err);
    if (rc == API_OK && kind_name) *kind_name = kind->name;
    if (rc == API_OK && canon) {
        /* valid: the canonical form comes from the tree parse kept (and the arrays the fast
         * reader took, still held by req) */
        char *dump = json_dumps(root, JSON_COMPACT | JSON_SORT_KEYS | JSON_REAL_PRECISION(17));
        size_t n = dump ? strlen(dump) : 0;
        if (dump && pk.n) {
            char *whole = api_packed_canon(&pk, dump, &n);
            free(dump);
            dump = whole;
        }
        *canon = dump;
        if (canonlen) *canonlen = n;
        if (!dump)
            rc = api_fail(err, API_ENOMEM, "out of memory while writing the canonical request");
    }
    if (rc == API_OK && checked && canon_same_request(root) &&
        (*checked = malloc(sizeof **checked))) { /* handed over: kept for its run */
        **checked = (api_request){kind, req, pk};
        kind = NULL;
        pk = (api_packed_set){0};
    }
    if (kind) kind->free(req);
    api_packed_free(&pk);
    json_decref(root);
    return rc;
}

int api_check_request(const char *body, size_t len, char **canon, size_t *canonlen,
                      const char **kind_name, api_error *err)
{
    return api_check_request_ex(body, len, canon, canonlen, kind_name, NULL, err);
}

int api_check_json(const char *body, size_t len, char **canon, size_t *canonlen, api_error *err)
{
    return api_check_request(body, len, canon, canonlen, NULL, err);
}
