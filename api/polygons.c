/* polygons.c — the "polygons" kind: 2D Booleans (issue "Boolean chains").
 *
 *   {"kind":"polygons","polygons":[[[[x,y],...], [[x,y],...], ...], ...],
 *    "op":"union"|"intersection"|"difference"|"xor"|["-", 0, ["+", 1, 2]], "options":{...}}
 *
 * Each polygon is a list of rings, the outer boundary first, then holes (>= 3 points each,
 * closed implicitly, any orientation: the even-odd rule over a polygon's rings decides).  The
 * options are those of "lines" (api_lar2_option()).  The answer is the LAR JSON of the
 * arrangement of all ring edges (api_lar2_write()) with two more members:
 *   "membership": one row per bounded face (FV's rows), one 0/1 per input polygon;
 *   "result": {"cells": [selected faces], "FV": [outer cycle of each result polygon, CCW],
 *              "FE": [signed edges of each result polygon, outer cycle then holes],
 *              "holes": {"q": [[hole cycle, CW], ...]}, "area": total area}.
 * core/bool2.h does the work.
 *
 * Threads: reentrant, no globals.  Ownership: req is borrowed; *parsed belongs to the caller,
 * who frees it with api_polygons_free().
 */
#include "api/api_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/bool2.h"

typedef struct polygons_req {
    size_t npoly;
    uint32_t *poly_off; /* owned, npoly+1 */
    uint32_t *ring_off; /* owned, nrings+1 */
    double *xy;         /* owned, 2 per point */
    bool_expr op;       /* owned, checked for npoly inputs */
    api_lar2_opts opt;
} polygons_req;

void api_polygons_free(void *parsed)
{
    polygons_req *r = parsed;
    if (!r) return;
    free(r->poly_off);
    free(r->ring_off);
    free(r->xy);
    bool_expr_free(&r->op);
    free(r);
}

/* Counts the rings and points of "polygons" and checks every shape and number. */
static int parse_polygons(const json_t *ps, polygons_req *r, api_error *err)
{
    size_t i, nrings = 0, npts = 0;
    json_t *p;
    if (!ps) return api_fail(err, API_EINVALID, "polygons: required, an array of polygons");
    if (!json_is_array(ps) || json_array_size(ps) == 0)
        return api_fail(err, API_EINVALID,
                        "polygons: expected a non-empty array of polygons [ring, hole, ...]");
    if (json_array_size(ps) > BOOL2_MAX_INPUTS)
        return api_fail(err, API_EINVALID, "polygons: %zu polygons, at most %u allowed",
                        json_array_size(ps), (unsigned)BOOL2_MAX_INPUTS);
    json_array_foreach(ps, i, p)
    {
        size_t j;
        json_t *ring;
        if (!json_is_array(p) || json_array_size(p) == 0)
            return api_fail(err, API_EINVALID,
                            "polygons[%zu]: expected a polygon: a non-empty array of rings "
                            "[[x, y], ...], the outer boundary first",
                            i);
        json_array_foreach(p, j, ring)
        {
            size_t k;
            json_t *pt;
            if (!json_is_array(ring) || json_array_size(ring) < 3)
                return api_fail(err, API_EINVALID,
                                "polygons[%zu][%zu]: expected a ring of at least 3 points [x, y]",
                                i, j);
            json_array_foreach(ring, k, pt)
            {
                if (!json_is_array(pt) || json_array_size(pt) != 2)
                    return api_fail(err, API_EINVALID, "polygons[%zu][%zu][%zu]: expected [x, y]",
                                    i, j, k);
                for (size_t c = 0; c < 2; c++) {
                    const json_t *x = json_array_get(pt, c);
                    if (!json_is_number(x) || !isfinite(json_number_value(x)))
                        return api_fail(err, API_EINVALID,
                                        "polygons[%zu][%zu][%zu][%zu]: expected a finite number", i,
                                        j, k, c);
                }
            }
            nrings++;
            npts += json_array_size(ring);
            if (npts > ARR2_MAX_SEGMENTS)
                return api_fail(err, API_EINVALID,
                                "polygons[%zu][%zu]: more than %u points in all, the limit", i, j,
                                (unsigned)ARR2_MAX_SEGMENTS);
        }
    }
    r->npoly = json_array_size(ps);
    r->poly_off = malloc((r->npoly + 1) * sizeof *r->poly_off);
    r->ring_off = malloc((nrings + 1) * sizeof *r->ring_off);
    r->xy = malloc((npts ? npts : 1) * 2 * sizeof *r->xy);
    if (!r->poly_off || !r->ring_off || !r->xy)
        return api_fail(err, API_ENOMEM, "out of memory for %zu points", npts);
    nrings = npts = 0;
    r->poly_off[0] = r->ring_off[0] = 0;
    json_array_foreach(ps, i, p)
    {
        size_t j;
        json_t *ring;
        json_array_foreach(p, j, ring)
        {
            size_t k;
            json_t *pt;
            json_array_foreach(ring, k, pt)
            {
                r->xy[2 * npts] = json_number_value(json_array_get(pt, 0));
                r->xy[2 * npts + 1] = json_number_value(json_array_get(pt, 1));
                npts++;
            }
            r->ring_off[++nrings] = (uint32_t)npts;
        }
        r->poly_off[i + 1] = (uint32_t)nrings;
    }
    return API_OK;
}

int api_polygons_parse(const json_t *req, void **parsed, api_error *err)
{
    const char *key;
    json_t *v;
    polygons_req *r;
    int rc;
    *parsed = NULL;
    json_object_foreach((json_t *)req, key, v)
    {
        if (strcmp(key, "kind") && strcmp(key, "polygons") && strcmp(key, "op") &&
            strcmp(key, "options"))
            return api_fail(err, API_EINVALID,
                            "%.64s: unknown key (expected kind, polygons, op or options)", key);
    }
    r = calloc(1, sizeof *r);
    if (!r) return api_fail(err, API_ENOMEM, "out of memory");
    rc = api_lar2_options(json_object_get(req, "options"), &r->opt, err);
    if (rc != API_OK) goto fail;
    rc = parse_polygons(json_object_get(req, "polygons"), r, err);
    if (rc != API_OK) goto fail;
    if (!json_object_get(req, "op")) {
        rc = api_fail(err, API_EINVALID,
                      "op: required, \"union\", \"intersection\", \"difference\", \"xor\" or an "
                      "expression such as [\"-\", 0, [\"+\", 1, 2]]");
        goto fail;
    }
    rc = api_bool_parse(json_object_get(req, "op"), r->npoly, &r->op, err);
    if (rc != API_OK) goto fail;
    *parsed = r;
    return API_OK;
fail:
    api_polygons_free(r);
    return rc;
}

/* The "membership" and "result" members (api_lar2_fmt.more). */
static void put_bool2(api_buf *b, const void *udata)
{
    const bool2_result *r = udata;
    api_buf_puts(b, ",\"membership\":[");
    for (size_t f = 0; f < r->c.nf; f++) {
        api_buf_puts(b, f ? ",[" : "[");
        for (size_t p = 0; p < r->ninputs; p++) {
            if (p) api_buf_putc(b, ',');
            api_buf_putc(b, r->member[f * r->ninputs + p] ? '1' : '0');
        }
        api_buf_putc(b, ']');
    }
    api_buf_puts(b, "],\"result\":{\"cells\":");
    api_buf_u32_list(b, r->cells, r->ncells);
    api_buf_puts(b, ",\"FV\":[");
    for (size_t q = 0; q < r->npoly; q++) {
        uint32_t k = r->poly_outer[q];
        if (q) api_buf_putc(b, ',');
        api_buf_u32_list(b, r->rv + r->rc_off[k], r->rc_off[k + 1] - r->rc_off[k]);
    }
    api_buf_puts(b, "],\"FE\":[");
    for (size_t q = 0; q < r->npoly; q++) {
        int first = 1;
        api_buf_puts(b, q ? ",[" : "[");
        for (uint32_t h = r->ph_off[q]; h <= r->ph_off[q + 1]; h++) {
            uint32_t k = h == r->ph_off[q] ? r->poly_outer[q] : r->ph_cyc[h - 1];
            for (uint32_t i = r->rc_off[k]; i < r->rc_off[k + 1]; i++) {
                if (!first) api_buf_putc(b, ',');
                first = 0;
                api_buf_i64(b, r->re[i]);
            }
        }
        api_buf_putc(b, ']');
    }
    api_buf_puts(b, "],\"holes\":{");
    int hfirst = 1;
    for (size_t q = 0; q < r->npoly; q++) {
        if (r->ph_off[q] == r->ph_off[q + 1]) continue;
        if (!hfirst) api_buf_putc(b, ',');
        hfirst = 0;
        api_buf_putc(b, '"');
        api_buf_u64(b, q);
        api_buf_puts(b, "\":[");
        for (uint32_t h = r->ph_off[q]; h < r->ph_off[q + 1]; h++) {
            uint32_t k = r->ph_cyc[h];
            if (h > r->ph_off[q]) api_buf_putc(b, ',');
            api_buf_u32_list(b, r->rv + r->rc_off[k], r->rc_off[k + 1] - r->rc_off[k]);
        }
        api_buf_putc(b, ']');
    }
    api_buf_puts(b, "},\"area\":");
    api_buf_double(b, r->area);
    api_buf_putc(b, '}');
}

int api_polygons_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err)
{
    const polygons_req *r = parsed;
    arr2_opts ao = {.precision = r->opt.precision,
                    .keep_dangling = r->opt.keep_dangling,
                    .threads = ro->threads,
                    .cancel = ro->cancel,
                    .progress = ro->progress,
                    .udata = ro->udata};
    bool2_input in = {r->npoly, r->poly_off, r->ring_off, r->xy};
    bool2_result res = {0};
    char core_msg[API_ERRMAX] = "";
    int rc = bool2_build(&in, &r->op, &ao, &res, core_msg, sizeof core_msg);
    if (rc != ARR_OK) {
        rc = api_core_fail(err, rc, core_msg);
        goto out;
    }
    api_lar2_fmt fmt = {.fields = r->opt.fields,
                        .exterior_last = r->opt.exterior_last,
                        .more = put_bool2,
                        .more_udata = &res};
    rc = api_lar2_write(out, &res.c, &fmt, err);
out:
    bool2_free(&res);
    return rc;
}
