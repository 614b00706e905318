/* svg.c — the "svg" kind: {"kind":"svg","svg":"<svg ...>...</svg>","options":{...}}.
 *
 * Validates the request (every key known, every value of the right shape; messages name the
 * JSON path, status 422), copies the drawing's text, reads it with svg_read() (core/svg.h),
 * runs the 2D core on the segments and writes the complex with api_lar2_write(), adding
 * stats.svg = {"elements", "skipped", "warnings": [...], "segments", "transform": [a..f]}.
 * Malformed XML, a document that is not SVG, or one beyond a limit of the reader is a 422 whose
 * message starts "svg: " and names line and column ("svg: line 3, column 7: ..."): at submit
 * (api_svg_check, through api_check_request: the daemon refuses it before queueing, and hands
 * the segments read to the run), or when the job runs from its text.
 *
 * Options: those of "lines" (precision, keep_dangling, exterior_last, operators, fields; read by
 * api_lar2_option() in api/lines.c; precision is in output units, so after normalize a fraction
 * of the unit square) and
 *   normalize          bool (false): map into [0,1]^2 keeping the aspect ratio, y up (seeds)
 *   y_up               bool (false): without normalize, y' = -y (SVG's y points down)
 *   rect2lines         "sides" (default: a <rect> gives its 4 sides) or "diagonal" (seeds)
 *   flatten_tolerance  number > 0: most distance of a flattened curve from the curve, in the
 *                      drawing's root user units (default: 1e-3 of the drawing's size)
 *
 * Threads: reentrant, no globals.  Ownership: req is borrowed; a parsed request (*parsed)
 * belongs to the caller, who frees it with api_svg_free().
 */
#include "api/api_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/svg.h"

typedef struct svg_req {
    char *text; /* owned: the drawing, len bytes (and a NUL) */
    size_t len;
    svg_result *read; /* owned: the drawing as api_svg_check read it (NULL: not read yet) */
    api_lar2_opts opt;
    svg_opts so;
} svg_req;

static int parse_options(const json_t *o, svg_req *r, api_error *err)
{
    const char *key;
    json_t *v;
    r->opt = (api_lar2_opts){.fields = API_F_DEFAULT};
    if (!o) return API_OK;
    if (!json_is_object(o)) return api_fail(err, API_EINVALID, "options: expected an object");
    json_object_foreach((json_t *)o, key, v)
    {
        int rc = api_lar2_option(key, v, &r->opt, err);
        if (rc != API_NOT_MINE) {
            if (rc != API_OK) return rc;
            continue;
        }
        if (strcmp(key, "normalize") == 0 || strcmp(key, "y_up") == 0) {
            if (!json_is_boolean(v))
                return api_fail(err, API_EINVALID, "options.%s: expected true or false", key);
            *(key[0] == 'n' ? &r->so.normalize : &r->so.y_up) = json_is_true(v);
        } else if (strcmp(key, "rect2lines") == 0) {
            const char *s = json_string_value(v);
            if (!s || (strcmp(s, "sides") && strcmp(s, "diagonal")))
                return api_fail(err, API_EINVALID,
                                "options.rect2lines: expected \"sides\" or \"diagonal\"");
            r->so.rect_diagonal = strcmp(s, "diagonal") == 0;
        } else if (strcmp(key, "flatten_tolerance") == 0) {
            if (!json_is_number(v) || !(json_number_value(v) > 0) ||
                !isfinite(json_number_value(v)))
                return api_fail(err, API_EINVALID,
                                "options.flatten_tolerance: expected a number > 0");
            r->so.flatten_tolerance = json_number_value(v);
        } else {
            return api_fail(err, API_EINVALID,
                            "options.%.64s: unknown option (expected precision, keep_dangling, "
                            "exterior_last, operators, fields, normalize, y_up, rect2lines or "
                            "flatten_tolerance)",
                            key);
        }
    }
    if (r->opt.operators) r->opt.fields |= API_F_OPERATORS;
    return api_lar2_no_bool(&r->opt, err);
}

void api_svg_free(void *parsed)
{
    svg_req *r = parsed;
    if (!r) return;
    free(r->text);
    if (r->read) svg_result_free(r->read);
    free(r->read);
    free(r);
}

int api_svg_parse(const json_t *req, void **parsed, api_error *err)
{
    const json_t *text;
    svg_req *r;
    int rc;
    *parsed = NULL;
    if ((rc = api_only_keys(req, "svg", err)) != API_OK) return rc;
    text = json_object_get(req, "svg");
    if (!text) return api_fail(err, API_EINVALID, "svg: required, the drawing as a string");
    if (!json_is_string(text))
        return api_fail(err, API_EINVALID, "svg: expected a string (the SVG document)");
    if (json_string_length(text) > SVG_MAX_BYTES)
        return api_fail(err, API_EINVALID, "svg: %zu bytes, at most %u allowed",
                        json_string_length(text), (unsigned)SVG_MAX_BYTES);
    r = calloc(1, sizeof *r);
    if (!r) return api_fail(err, API_ENOMEM, "out of memory");
    rc = parse_options(json_object_get(req, "options"), r, err);
    if (rc != API_OK) goto fail;
    r->len = json_string_length(text);
    r->text = malloc(r->len + 1);
    if (!r->text) {
        rc = api_fail(err, API_ENOMEM, "out of memory for a drawing of %zu bytes", r->len);
        goto fail;
    }
    memcpy(r->text, json_string_value(text), r->len);
    r->text[r->len] = 0;
    *parsed = r;
    return API_OK;
fail:
    api_svg_free(r);
    return rc;
}

/* Reads the drawing, for its errors only (the segments are read again when the job runs:
 * reading is a small part of a job, and a malformed drawing is then refused at once). */
static void reading_tick(void *udata, double f)
{
    const api_run_opts *ro = udata;
    ro->progress(ro->udata, "svg", f);
}

/* Reads the drawing (ro may be NULL: no progress). */
static int read_drawing(const svg_req *r, const api_run_opts *ro, svg_result *sr, api_error *err)
{
    char msg[API_ERRMAX] = "";
    svg_opts so = r->so;
    if (ro && ro->progress) so.progress = reading_tick, so.udata = (void *)ro;
    int rc = svg_read(r->text, r->len, &so, sr, msg, sizeof msg);
    if (rc == ARR_OK) return API_OK;
    if (rc == ARR_ENOMEM)
        return api_fail(err, API_ENOMEM, "out of memory while reading the drawing: %s", msg);
    return api_fail(err, rc == ARR_EINVAL || rc == ARR_ELIMIT ? API_EINVALID : API_EINTERNAL,
                    "svg: %s", *msg ? msg : "unreadable drawing");
}

int api_svg_check(void *parsed, api_error *err)
{
    svg_req *r = parsed;
    svg_result *sr = calloc(1, sizeof *sr);
    if (!sr) return api_fail(err, API_ENOMEM, "out of memory");
    int rc = read_drawing(r, NULL, sr, err);
    if (rc != API_OK) {
        svg_result_free(sr);
        free(sr);
        return rc;
    }
    r->read = sr; /* kept for the run */
    return API_OK;
}

/* Writes ,"svg":{...} into the stats object (api_lar2_fmt.stats_more). */
static void put_svg_stats(api_buf *b, const void *udata)
{
    const svg_result *s = udata;
    api_buf_puts(b, ",\"svg\":{\"elements\":");
    api_buf_u64(b, s->elements);
    api_buf_puts(b, ",\"skipped\":");
    api_buf_u64(b, s->skipped);
    api_buf_puts(b, ",\"warnings\":[");
    for (size_t i = 0; i < s->nwarnings; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_putc(b, '"');
        /* the reader's messages are printable ASCII: only quotes and backslashes to escape */
        for (const char *p = s->warning[i]; *p; p++) {
            if (*p == '"' || *p == '\\') api_buf_putc(b, '\\');
            api_buf_putc(b, (unsigned char)*p >= 0x20 && (unsigned char)*p < 0x7f ? *p : '?');
        }
        api_buf_putc(b, '"');
    }
    api_buf_puts(b, "],\"segments\":");
    api_buf_u64(b, s->n);
    api_buf_puts(b, ",\"transform\":[");
    for (int i = 0; i < 6; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_double(b, isfinite(s->transform[i]) ? s->transform[i] : 0);
    }
    api_buf_puts(b, "]}");
}

int api_svg_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err)
{
    static const double no_segment[4];
    const svg_req *r = parsed;
    arr2_opts ao = {.precision = r->opt.precision,
                    .input_coords = 1,
                    .keep_dangling = r->opt.keep_dangling,
                    .threads = ro->threads,
                    .cancel = ro->cancel,
                    .progress = ro->progress,
                    .udata = ro->udata};
    svg_result own = {0}, *sr = r->read ? r->read : &own;
    api_lar2_fmt fmt = {.fields = r->opt.fields,
                        .exterior_last = r->opt.exterior_last,
                        .stats_more = put_svg_stats,
                        .stats_udata = sr};
    lar2 c = {0};
    char msg[API_ERRMAX] = "";
    int rc;
    if (ro->progress) ro->progress(ro->udata, "svg", 0);
    rc = r->read ? API_OK : read_drawing(r, ro, sr, err); /* read once: at check, or here */
    if (rc != API_OK) goto out;
    if (ro->progress) ro->progress(ro->udata, "svg", 1);
    rc = arr2_build(sr->n ? sr->seg : no_segment, sr->n, &ao, &c, msg, sizeof msg);
    if (rc != ARR_OK) {
        rc = api_core_fail(err, rc, msg);
        goto out;
    }
    if (ro->progress) ro->progress(ro->udata, "output", 0);
    rc = api_lar2_write(out, &c, &fmt, err);
out:
    lar2_free(&c);
    svg_result_free(&own);
    return rc;
}
