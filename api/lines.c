/* lines.c — the "lines" kind: {"kind":"lines","lines":[[[x1,y1],[x2,y2]],...],"options":{...}}.
 *
 * Validates the request (every key known, every value of the right shape; messages name the JSON
 * path of the problem, status 422), copies the segments into the flat array arr2_build() takes,
 * runs the core and writes the complex with api_lar2_write().
 *
 * The request is parsed with jansson; its tree is freed before the core runs.  A request of
 * a million segments costs jansson about 800 MB and 2.5 s (a node per number): the daemon's
 * body-size limit bounds that.
 *
 * Options:
 *   precision      number > 0: the snapping grid step (default: the core's, from the extent)
 *   keep_dangling  bool: keep bridges and dangling trees
 *   exterior_last  bool: the seeds' convention, exterior cycles as the last rows of FV and FE
 *   operators      bool: add the boundary operators d1, d2 as CSR
 *   fields         array of names among "V","EV","FV","FE","holes","exterior","stats",
 *                  "operators" (default: all but operators); "membership" and "result" are
 *                  names of "polygons" only (api_lar2_no_bool refuses them elsewhere)
 * api_lar2_option() reads them, for "svg" (api/svg.c) too.
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

typedef struct lines_req {
    double *seg; /* owned: 4n doubles x1, y1, x2, y2 */
    size_t n;    /* segments */
    api_lar2_opts opt;
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
                        "\"FE\", \"holes\", \"exterior\", \"stats\", \"operators\" (and "
                        "\"membership\", \"result\" for polygons)");
    *out = 0;
    json_array_foreach(v, i, name)
    {
        unsigned bit = 0;
        for (unsigned k = 0; json_is_string(name) && k < API_NFIELDS; k++)
            if (strcmp(json_string_value(name), api_field_names[k]) == 0) bit = 1u << k;
        if (!bit)
            return api_fail(err, API_EINVALID,
                            "options.fields[%zu]: expected one of \"V\", \"EV\", \"FV\", \"FE\", "
                            "\"holes\", \"exterior\", \"stats\", \"operators\" (and "
                            "\"membership\", \"result\" for polygons)",
                            i);
        *out |= bit;
    }
    return api_lar2_fields_check(*out, err);
}

int api_lar2_option(const char *key, const json_t *v, api_lar2_opts *o, api_error *err)
{
    if (strcmp(key, "precision") == 0) {
        if (!json_is_number(v) || !(json_number_value(v) > 0) || !isfinite(json_number_value(v)))
            return api_fail(err, API_EINVALID, "options.precision: expected a number > 0");
        o->precision = json_number_value(v);
        return API_OK;
    }
    if (strcmp(key, "keep_dangling") == 0) return parse_bool(v, key, &o->keep_dangling, err);
    if (strcmp(key, "exterior_last") == 0) return parse_bool(v, key, &o->exterior_last, err);
    if (strcmp(key, "operators") == 0) return parse_bool(v, key, &o->operators, err);
    if (strcmp(key, "fields") == 0) return parse_fields(v, &o->fields, err);
    return API_NOT_MINE;
}

int api_lar2_options(const json_t *o, api_lar2_opts *opt, api_error *err)
{
    const char *key;
    json_t *v;
    *opt = (api_lar2_opts){.fields = API_F_DEFAULT};
    if (!o) return API_OK;
    if (!json_is_object(o)) return api_fail(err, API_EINVALID, "options: expected an object");
    json_object_foreach((json_t *)o, key, v)
    {
        int rc = api_lar2_option(key, v, opt, err);
        if (rc == API_NOT_MINE)
            return api_fail(err, API_EINVALID,
                            "options.%.64s: unknown option (expected precision, keep_dangling, "
                            "exterior_last, operators or fields)",
                            key);
        if (rc != API_OK) return rc;
    }
    if (opt->operators) opt->fields |= API_F_OPERATORS;
    return api_lar2_no_bool(opt, err);
}

int api_lar2_no_bool(const api_lar2_opts *o, api_error *err)
{
    if (o->fields & (API_F_MEMBERSHIP | API_F_RESULT))
        return api_fail(err, API_EINVALID,
                        "options.fields: \"membership\" and \"result\" are fields of a "
                        "\"polygons\" request (its Boolean)");
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

int api_lines_parse(const json_t *req, void **parsed, api_error *err)
{
    return api_lines_parse_packed(req, NULL, parsed, err);
}

int api_lines_parse_packed(const json_t *req, api_packed_set *pk, void **parsed, api_error *err)
{
    lines_req *r;
    int rc;
    *parsed = NULL;
    if ((rc = api_only_keys(req, "lines", err)) != API_OK) return rc;
    r = calloc(1, sizeof *r);
    if (!r) return api_fail(err, API_ENOMEM, "out of memory");
    rc = api_lar2_options(json_object_get(req, "options"), &r->opt, err);
    if (rc != API_OK) goto fail;
    const json_t *lines = json_object_get(req, "lines");
    api_packed *a = pk && json_is_string(lines)
                        ? api_packed_find(pk, 0, API_PACKED_SEGMENTS, json_string_value(lines))
                        : NULL;
    if (a) { /* read by api_packed_scan: finite numbers, four a segment; taken as they are */
        if (a->n > ARR2_MAX_SEGMENTS) {
            rc = api_fail(err, API_EINVALID, "lines: %zu segments, at most %u allowed", a->n,
                          (unsigned)ARR2_MAX_SEGMENTS);
            goto fail;
        }
        r->seg = a->V, r->n = a->n;
        a->taken = 1;
    } else {
        rc = parse_lines(lines, &r->seg, &r->n, err);
    }
    if (rc != API_OK) goto fail;
    *parsed = r;
    return API_OK;
fail:
    api_lines_free(r);
    return rc;
}

/* Runs r's arrangement into *c (the caller frees it with lar2_free, success or not). */
static int lines_compute(const lines_req *r, const api_run_opts *ro, lar2 *c, api_error *err)
{
    static const double no_segment[4];
    arr2_opts ao = {.precision = r->opt.precision,
                    .input_coords = 1,
                    .keep_dangling = r->opt.keep_dangling,
                    .threads = ro->threads,
                    .cancel = ro->cancel,
                    .progress = ro->progress,
                    .udata = ro->udata};
    char core_msg[API_ERRMAX] = "";
    int rc = arr2_build(r->n ? r->seg : no_segment, r->n, &ao, c, core_msg, sizeof core_msg);
    if (rc != ARR_OK) return api_core_fail(err, rc, core_msg);
    if (ro->progress) ro->progress(ro->udata, "output", 0);
    return API_OK;
}

int api_lines_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err)
{
    const lines_req *r = parsed;
    api_lar2_fmt fmt = {.fields = r->opt.fields, .exterior_last = r->opt.exterior_last};
    lar2 c = {0};
    int rc = lines_compute(r, ro, &c, err);
    if (rc == API_OK) rc = api_lar2_write(out, &c, &fmt, err);
    lar2_free(&c);
    return rc;
}

static void lar2_drop(void *p)
{
    lar2_free(p);
    free(p);
}

int api_lines_arrays(const void *parsed, const api_run_opts *ro, api_arrays *out, api_error *err)
{
    const lines_req *r = parsed;
    api_lar2_fmt fmt = {.fields = r->opt.fields};
    lar2 *c = calloc(1, sizeof *c); /* kept by the result, which frees it, success or not */
    if (!c || api_arrays_keep(out, c, lar2_drop)) return api_fail(err, API_ENOMEM, "out of memory");
    int rc = lines_compute(r, ro, c, err);
    return rc == API_OK ? api_lar2_arrays(out, c, &fmt, err) : rc;
}

int api_lines_make(const double *seg, size_t n, const json_t *options, void **parsed,
                   api_error *err)
{
    *parsed = NULL;
    if (n > ARR2_MAX_SEGMENTS)
        return api_fail(err, API_EINVALID, "segments: %zu segments, at most %u allowed", n,
                        (unsigned)ARR2_MAX_SEGMENTS);
    for (size_t i = 0; i < 4 * n; i++)
        if (!isfinite(seg[i]))
            return api_fail(err, API_EINVALID, "segments[%zu][%zu][%zu]: expected a finite number",
                            i / 4, i / 2 % 2, i % 2);
    lines_req *r = calloc(1, sizeof *r);
    if (!r) return api_fail(err, API_ENOMEM, "out of memory");
    int rc = api_lar2_options(options, &r->opt, err);
    if (rc == API_OK && !(r->seg = malloc((4 * n + 1) * sizeof *r->seg)))
        rc = api_fail(err, API_ENOMEM, "out of memory for %zu segments", n);
    if (rc != API_OK) {
        api_lines_free(r);
        return rc;
    }
    if (n) memcpy(r->seg, seg, 4 * n * sizeof *seg);
    r->n = n;
    *parsed = r;
    return API_OK;
}
