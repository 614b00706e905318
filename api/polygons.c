/* polygons.c — the "polygons" kind: 2D Booleans (issue "Boolean chains").
 *
 *   {"kind":"polygons","polygons":[[[[x,y],...], [[x,y],...], ...], ...],
 *    "op":"union"|"intersection"|"difference"|"xor"|["-", 0, ["+", 1, 2]], "options":{...}}
 *
 * Each polygon is a list of rings, the outer boundary first, then holes (>= 3 points each,
 * closed implicitly, any orientation: the even-odd rule over a polygon's rings decides), or a
 * GeoJSON Polygon, MultiPolygon or Feature object, or a WKT string (POLYGON, MULTIPOLYGON);
 * "polygons" may also be a GeoJSON FeatureCollection, one input per feature.  The
 * options are those of "lines" (api_lar2_option()) and "fill" (parse_options).  The answer is
 * the LAR JSON of the arrangement of all ring edges (api_lar2_write()) with two more members:
 *   "membership": the polygons each bounded face (FV's rows) lies in, as compressed sparse
 *                 rows {"format":"csr","shape":[F, N],"indptr":[...],"indices":[...]}; under
 *                 the fill rules "nonzero" and "positive" the polygons of non-zero winding
 *                 number, with "data": [their winding numbers] when one is not 1;
 *   "result": {"cells": [selected faces], "FV": [outer cycle of each result polygon, CCW],
 *              "FE": [signed edges of each result polygon, outer cycle then holes],
 *              "holes": {"q": [[hole cycle, CW], ...]}, "area": total area}.
 * options.fields may name "membership" and "result" (then only those named are written); a
 * result named without V carries its own "V" (put_bool2).  core/bool2.h does the work.
 *
 * Threads: reentrant, no globals.  Ownership: req is borrowed; *parsed belongs to the caller,
 * who frees it with api_polygons_free().
 */
#include "api/api_int.h"
#include "core/fastfloat.h"

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
    int fill; /* options.fill: BOOL2_FILL_* */
    /* "layers": layer k's name lname[k] (JSON text, quoted) and its polygons lfirst[k] ..
     * lfirst[k+1]); each polygon's "properties" (a Feature's, JSON text; "null" for none)
     * props[prop_off[p] .. prop_off[p+1]).  nlayers = 0: a plain "polygons" request. */
    size_t nlayers;
    char **lname;     /* owned, nlayers */
    uint32_t *lfirst; /* owned, nlayers + 1 */
    char *props;      /* owned */
    size_t *prop_off; /* owned, npoly + 1 */
    int named_and;    /* op "intersection" by name, over the single polygons */
} polygons_req;

void api_polygons_free(void *parsed)
{
    polygons_req *r = parsed;
    if (!r) return;
    free(r->poly_off);
    free(r->ring_off);
    free(r->xy);
    bool_expr_free(&r->op);
    for (size_t k = 0; k < r->nlayers; k++) free(r->lname[k]);
    free(r->lname);
    free(r->lfirst);
    free(r->props);
    free(r->prop_off);
    free(r);
}

/* options: those of "lines" (api_lar2_option) and "fill": "odd" (the default), "nonzero" or
 * "positive", the rule that says where a polygon's inside is by its rings' winding number. */
static int parse_options(const json_t *o, polygons_req *r, api_error *err)
{
    const char *key;
    json_t *v;
    r->opt = (api_lar2_opts){.fields = API_F_DEFAULT | API_F_MEMBERSHIP | API_F_RESULT};
    r->fill = BOOL2_FILL_ODD;
    if (!o) return API_OK;
    if (!json_is_object(o)) return api_fail(err, API_EINVALID, "options: expected an object");
    json_object_foreach((json_t *)o, key, v)
    {
        if (strcmp(key, "fill") == 0) {
            int rc = api_fill_parse(v, BOOL2_FILL_ODD, &r->fill, err);
            if (rc != API_OK) return rc;
            continue;
        }
        int rc = api_lar2_option(key, v, &r->opt, err);
        if (rc == API_NOT_MINE)
            return api_fail(err, API_EINVALID,
                            "options.%.64s: unknown option (expected precision, keep_dangling, "
                            "exterior_last, operators, fields or fill)",
                            key);
        if (rc != API_OK) return rc;
    }
    if (r->opt.operators) r->opt.fields |= API_F_OPERATORS;
    return API_OK;
}

/* ---- reading the polygons: native rings, GeoJSON geometries, WKT --------------------------- */

/* The rings read so far: growing arrays, checked against the limits as they grow. */
typedef struct pbuild {
    double *xy; /* 2 per point */
    size_t npts, cap;
    uint32_t *ring_off; /* nrings + 1 */
    size_t nrings, rcap;
    uint32_t *poly_off; /* npoly + 1 */
    size_t npoly, pcap;
    size_t ring_start; /* first point of the ring being read */
    api_buf *props;    /* NULL, or each polygon's properties, JSON text, ended by a NUL */
} pbuild;

static void pbuild_free(pbuild *b)
{
    free(b->xy);
    free(b->ring_off);
    free(b->poly_off);
}

static int add_point(pbuild *b, double x, double y, api_error *err)
{
    if (b->npts >= ARR2_MAX_SEGMENTS)
        return api_fail(err, API_EINVALID, "polygons: more than %u points in all, the limit",
                        (unsigned)ARR2_MAX_SEGMENTS);
    if (b->npts == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 256;
        double *xy = realloc(b->xy, cap * 2 * sizeof *xy);
        if (!xy) return api_fail(err, API_ENOMEM, "out of memory for %zu points", cap);
        b->xy = xy;
        b->cap = cap;
    }
    b->xy[2 * b->npts] = x;
    b->xy[2 * b->npts + 1] = y;
    b->npts++;
    return API_OK;
}

/* Ends the ring begun at b->ring_start: a last point equal to the first (GeoJSON and WKT close
 * their rings so) is dropped; fewer than 3 points left is an error at path. */
static int end_ring(pbuild *b, const char *path, api_error *err)
{
    size_t n = b->npts - b->ring_start;
    if (n >= 2 && b->xy[2 * b->ring_start] == b->xy[2 * (b->npts - 1)] &&
        b->xy[2 * b->ring_start + 1] == b->xy[2 * (b->npts - 1) + 1])
        b->npts--, n--;
    if (n < 3)
        return api_fail(err, API_EINVALID, "%s: a ring needs at least 3 distinct points (has %zu)",
                        path, n);
    if (b->nrings + 2 > b->rcap) {
        size_t cap = b->rcap ? 2 * b->rcap : 64;
        uint32_t *o = realloc(b->ring_off, cap * sizeof *o);
        if (!o) return api_fail(err, API_ENOMEM, "out of memory for %zu rings", cap);
        b->ring_off = o;
        b->rcap = cap;
    }
    b->ring_off[0] = 0;
    b->ring_off[++b->nrings] = (uint32_t)b->npts;
    b->ring_start = b->npts;
    return API_OK;
}

/* A position, point k of the ring at path: [x, y] (native: exactly 2 numbers; GeoJSON: 2 or
 * more, the rest ignored).  The path is written only into a message. */
static int json_position(const json_t *pt, int geojson, pbuild *b, const char *path, size_t k,
                         api_error *err)
{
    double c[2];
    if (!json_is_array(pt) || json_array_size(pt) < 2 || (!geojson && json_array_size(pt) != 2))
        return api_fail(err, API_EINVALID, "%s[%zu]: expected [x, y]%s", path, k,
                        geojson ? " (a GeoJSON position)" : "");
    for (size_t i = 0; i < json_array_size(pt); i++) {
        const json_t *x = json_array_get(pt, i);
        if (!json_is_number(x) || !isfinite(json_number_value(x)))
            return api_fail(err, API_EINVALID, "%s[%zu][%zu]: expected a finite number", path, k,
                            i);
        if (i < 2) c[i] = json_number_value(x);
    }
    return add_point(b, c[0], c[1], err);
}

/* A polygon's rings [[pos, ...], ...] at path: native (at least one ring, open rings allowed)
 * or GeoJSON (closed rings, none for an empty polygon). */
static int json_rings(const json_t *rings, int geojson, pbuild *b, const char *path, api_error *err)
{
    char sub[160];
    size_t j, k;
    json_t *ring, *pt;
    if (!json_is_array(rings) || (!geojson && json_array_size(rings) == 0))
        return api_fail(err, API_EINVALID,
                        "%s: expected a polygon: %sarray of rings [[x, y], ...], the outer "
                        "boundary first",
                        path, geojson ? "an " : "a non-empty ");
    json_array_foreach(rings, j, ring)
    {
        snprintf(sub, sizeof sub, "%s[%zu]", path, j);
        if (!json_is_array(ring) || json_array_size(ring) < 3)
            return api_fail(err, API_EINVALID, "%s: expected a ring of at least 3 points [x, y]",
                            sub);
        json_array_foreach(ring, k, pt)
        {
            int rc = json_position(pt, geojson, b, sub, k, err);
            if (rc != API_OK) return rc;
        }
        int rc = end_ring(b, sub, err);
        if (rc != API_OK) return rc;
    }
    return API_OK;
}

/* A GeoJSON object (RFC 7946) at path: a Polygon, a MultiPolygon (its parts' rings together:
 * the even-odd rule makes them the parts' union, as they do not overlap) or a Feature holding
 * one. */
static int packed_coords(const api_packed *a, pbuild *b, api_error *err);

static int geojson_polygon(const json_t *o, api_packed_set *pk, pbuild *b, const char *path,
                           api_error *err)
{
    const char *type = json_string_value(json_object_get(o, "type"));
    const json_t *c = json_object_get(o, "coordinates");
    char sub[160];
    if (!type)
        return api_fail(err, API_EINVALID,
                        "%s.type: required (a GeoJSON Polygon, MultiPolygon or Feature)", path);
    if (!strcmp(type, "Feature")) {
        const json_t *g = json_object_get(o, "geometry");
        snprintf(sub, sizeof sub, "%s.geometry", path);
        if (json_is_null(g) || !g) return API_OK; /* an unlocated feature: the empty set */
        if (!json_is_object(g) ||
            !strcmp(json_string_value(json_object_get(g, "type")) ?: "", "Feature"))
            return api_fail(err, API_EINVALID, "%s: expected a Polygon or MultiPolygon object",
                            sub);
        return geojson_polygon(g, pk, b, sub, err);
    }
    snprintf(sub, sizeof sub, "%s.coordinates", path);
    if (pk && json_is_string(c)) { /* read fast: a Polygon's rings or a MultiPolygon's */
        int multi = !strcmp(type, "MultiPolygon");
        const api_packed *a =
            multi || !strcmp(type, "Polygon")
                ? api_packed_find(pk, multi ? 4 : 3, API_PACKED_COORDS, json_string_value(c))
                : NULL;
        return a ? packed_coords(a, b, err) : API_EINVALID; /* jansson's path words it */
    }
    if (!strcmp(type, "Polygon")) return json_rings(c, 1, b, sub, err);
    if (!strcmp(type, "MultiPolygon")) {
        size_t i;
        json_t *poly;
        if (!json_is_array(c))
            return api_fail(err, API_EINVALID, "%s: expected an array of polygons", sub);
        json_array_foreach(c, i, poly)
        {
            char at[200];
            snprintf(at, sizeof at, "%s[%zu]", sub, i);
            int rc = json_rings(poly, 1, b, at, err);
            if (rc != API_OK) return rc;
        }
        return API_OK;
    }
    if (!strcmp(type, "FeatureCollection"))
        return api_fail(err, API_EINVALID,
                        "%s.type: a FeatureCollection is a layer, not one polygon: give two or "
                        "more collections as \"layers\": {\"name\": collection, ...} and "
                        "an op over the names, such as [\"&\", \"parcels\", \"zones\"]",
                        path);
    return api_fail(err, API_EINVALID,
                    "%s.type: \"%.40s\" is not an area (expected Polygon, MultiPolygon or "
                    "Feature)",
                    path, type);
}

/* ---- WKT: POLYGON and MULTIPOLYGON (OGC 06-103r4), with Z, M or ZM (extra ordinates ignored),
 * EMPTY, and PostGIS's "SRID=n;" prefix.  Keywords are case-insensitive.  Errors give the
 * character position (from 1). */
typedef struct wkt {
    const char *s, *p;
    const char *path;
    int dims; /* ordinates per position: 2..4, or 0 until the first position decides */
} wkt;

static void wkt_space(wkt *w)
{
    while (*w->p == ' ' || *w->p == '\t' || *w->p == '\n' || *w->p == '\r') w->p++;
}

static int wkt_fail(wkt *w, api_error *err, const char *what)
{
    char near[24];
    size_t n = 0;
    while (w->p[n] && n < 16) n++;
    snprintf(near, sizeof near, "%.*s", (int)n, w->p);
    for (char *c = near; *c; c++)
        if ((unsigned char)*c < 0x20 || (unsigned char)*c >= 0x7f) *c = '?';
    return api_fail(err, API_EINVALID, "%s: WKT at character %zu: expected %s%s%s%s", w->path,
                    (size_t)(w->p - w->s) + 1, what, *w->p ? ", found \"" : ", found the end",
                    *w->p ? near : "", *w->p ? "\"" : "");
}

/* The keyword kw (letters), case-insensitive, not followed by a letter. */
static int wkt_word(wkt *w, const char *kw)
{
    size_t n = strlen(kw);
    wkt_space(w);
    for (size_t i = 0; i < n; i++)
        if ((w->p[i] | 0x20) != (kw[i] | 0x20)) return 0;
    if ((w->p[n] | 0x20) >= 'a' && (w->p[n] | 0x20) <= 'z') return 0;
    w->p += n;
    return 1;
}

static int wkt_char(wkt *w, char c)
{
    wkt_space(w);
    if (*w->p != c) return 0;
    w->p++;
    return 1;
}

/* A number: [+-] digits [. digits] [e [+-] digits] (or . digits); no inf, nan or hex. */
static int wkt_number(wkt *w, double *x)
{
    const char *q;
    size_t digits = 0;
    wkt_space(w);
    q = w->p;
    if (*q == '+' || *q == '-') q++;
    while (*q >= '0' && *q <= '9') q++, digits++;
    if (*q == '.') {
        q++;
        while (*q >= '0' && *q <= '9') q++, digits++;
    }
    if (!digits) return 0;
    if (*q == 'e' || *q == 'E') {
        const char *e = q + 1;
        if (*e == '+' || *e == '-') e++;
        if (*e < '0' || *e > '9') return 0;
        while (*e >= '0' && *e <= '9') e++;
        q = e;
    }
    if (ff_parse(w->p, q, x) != 0 || !isfinite(*x)) return 0; /* strtod's double, faster */
    w->p = q;
    return 1;
}

/* '(' pos, pos, ... ')' */
static int wkt_ring(wkt *w, pbuild *b, api_error *err)
{
    const char *at;
    wkt_space(w);
    at = w->p;
    if (!wkt_char(w, '(')) return wkt_fail(w, err, "'(' opening a ring");
    do {
        double c[4];
        int n = 0;
        const char *pos;
        wkt_space(w);
        pos = w->p;
        while (n < 4) {
            wkt_space(w);
            if (!((*w->p >= '0' && *w->p <= '9') || *w->p == '-' || *w->p == '+' || *w->p == '.'))
                break;
            if (!wkt_number(w, &c[n])) return wkt_fail(w, err, "a finite number");
            n++;
        }
        if (n < 2 || (w->dims && n != w->dims)) {
            w->p = pos;
            return wkt_fail(w, err,
                            w->dims == 3   ? "3 ordinates (the dimension is Z or M)"
                            : w->dims == 4 ? "4 ordinates (the dimension is ZM)"
                            : w->dims == 2 ? "2 ordinates, x y"
                                           : "a position: x y");
        }
        w->dims = n;
        int rc = add_point(b, c[0], c[1], err);
        if (rc != API_OK) return rc;
    } while (wkt_char(w, ','));
    if (!wkt_char(w, ')')) return wkt_fail(w, err, "',' or ')' after a position");
    {
        char path[200];
        snprintf(path, sizeof path, "%s: WKT ring at character %zu", w->path,
                 (size_t)(at - w->s) + 1);
        return end_ring(b, path, err);
    }
}

/* EMPTY | '(' ring, ring, ... ')' */
static int wkt_polygon(wkt *w, pbuild *b, api_error *err)
{
    if (wkt_word(w, "EMPTY")) return API_OK;
    if (!wkt_char(w, '(')) return wkt_fail(w, err, "'(' or EMPTY");
    do {
        int rc = wkt_ring(w, b, err);
        if (rc != API_OK) return rc;
    } while (wkt_char(w, ','));
    if (!wkt_char(w, ')')) return wkt_fail(w, err, "',' or ')' after a ring");
    return API_OK;
}

static int wkt_read(const char *text, pbuild *b, const char *path, api_error *err)
{
    wkt w = {text, text, path, 0};
    int multi;
    if (wkt_word(&w, "SRID")) {
        double srid;
        if (!wkt_char(&w, '=') || !wkt_number(&w, &srid) || !wkt_char(&w, ';'))
            return wkt_fail(&w, err, "SRID=n; before the geometry");
    }
    if (wkt_word(&w, "POLYGON"))
        multi = 0;
    else if (wkt_word(&w, "MULTIPOLYGON"))
        multi = 1;
    else
        return wkt_fail(&w, err, "POLYGON or MULTIPOLYGON");
    if (wkt_word(&w, "ZM"))
        w.dims = 4;
    else if (wkt_word(&w, "Z") || wkt_word(&w, "M"))
        w.dims = 3;
    int rc;
    if (!multi) {
        rc = wkt_polygon(&w, b, err);
    } else if (wkt_word(&w, "EMPTY")) {
        rc = API_OK;
    } else if (!wkt_char(&w, '(')) {
        rc = wkt_fail(&w, err, "'(' or EMPTY");
    } else {
        do rc = wkt_polygon(&w, b, err);
        while (rc == API_OK && wkt_char(&w, ','));
        if (rc == API_OK && !wkt_char(&w, ')'))
            rc = wkt_fail(&w, err, "',' or ')' after a polygon");
    }
    if (rc != API_OK) return rc;
    wkt_space(&w);
    if (*w.p) return wkt_fail(&w, err, "the end of the geometry");
    return API_OK;
}

/* One input polygon at path: native rings, a GeoJSON object or a WKT string. */
static int read_polygon(const json_t *p, api_packed_set *pk, pbuild *b, const char *path,
                        api_error *err)
{
    if (json_is_string(p)) return wkt_read(json_string_value(p), b, path, err);
    if (json_is_object(p)) return geojson_polygon(p, pk, b, path, err);
    return json_rings(p, 0, b, path, err);
}

static int end_polygon(pbuild *b, size_t total, api_error *err)
{
    if (b->npoly + 2 > b->pcap) {
        size_t cap = b->npoly + 1 + total;
        uint32_t *o = realloc(b->poly_off, cap * sizeof *o);
        if (!o) return api_fail(err, API_ENOMEM, "out of memory");
        b->poly_off = o;
        b->pcap = cap;
        b->poly_off[0] = 0;
    }
    b->poly_off[++b->npoly] = (uint32_t)b->nrings;
    return API_OK;
}

/* Keeps polygon p's "properties" (a Feature's; null for anything else) as JSON text. */
static int keep_properties(pbuild *b, const json_t *p, api_error *err)
{
    if (!b->props) return API_OK;
    const json_t *pr = json_is_object(p) ? json_object_get(p, "properties") : NULL;
    if (pr && !json_is_null(pr)) {
        char *t = json_dumps(pr, JSON_COMPACT | JSON_ENCODE_ANY);
        if (!t) return api_fail(err, API_ENOMEM, "out of memory");
        api_buf_puts(b->props, t);
        free(t);
    } else {
        api_buf_puts(b->props, "null");
    }
    api_buf_putc(b->props, 0);
    return b->props->failed ? api_fail(err, API_ENOMEM, "out of memory") : API_OK;
}

/* "polygons" as api_packed_scan read it (native rings, a: API_PACKED_RINGS): the same build as
 * json_rings', without the messages (a failure sends the request to the ordinary path, which
 * words it; end_ring refuses a ring of fewer than 3 points). */
static int packed_polygons(const api_packed *a, pbuild *b, api_error *err)
{
    if (a->npoly == 0 || a->npoly > BOOL2_MAX_INPUTS) return API_EINVALID;
    for (size_t q = 0; q < a->npoly; q++) {
        for (uint32_t k = a->idx[q]; k < a->idx[q + 1]; k++) {
            for (uint32_t v = a->off[k]; v < a->off[k + 1]; v++) {
                int rc = add_point(b, a->V[2 * (size_t)v], a->V[2 * (size_t)v + 1], err);
                if (rc != API_OK) return rc;
            }
            int rc = end_ring(b, "polygons", err);
            if (rc != API_OK) return rc;
        }
        int rc = end_polygon(b, a->npoly, err);
        if (rc != API_OK) return rc;
    }
    return API_OK;
}

/* A GeoJSON geometry's coordinates as api_packed_scan read them (a: API_PACKED_COORDS): every
 * ring's points, as json_rings takes them (a closing point dropped by end_ring); a failure
 * sends the request to the ordinary path, which words it. */
static int packed_coords(const api_packed *a, pbuild *b, api_error *err)
{
    for (size_t q = 0; q < a->npoly; q++)
        for (uint32_t k = a->idx[q]; k < a->idx[q + 1]; k++) {
            if (a->off[k + 1] - a->off[k] < 3) return API_EINVALID;
            for (uint32_t v = a->off[k]; v < a->off[k + 1]; v++) {
                int rc = add_point(b, a->V[2 * (size_t)v], a->V[2 * (size_t)v + 1], err);
                if (rc != API_OK) return rc;
            }
            int rc = end_ring(b, "polygons", err);
            if (rc != API_OK) return rc;
        }
    return API_OK;
}

/* Appends the polygons of ps, at name ("polygons" or "layers.NAME"): an array of polygons
 * (each native, GeoJSON or WKT), or a GeoJSON FeatureCollection (one polygon per feature); with
 * one_ok, also one polygon alone (a layer of one); or, with pk, what api_packed_scan read of
 * it. */
static int read_list(const json_t *ps, const char *name, int one_ok, api_packed_set *pk, pbuild *b,
                     api_error *err)
{
    const json_t *list = ps;
    char lname[200], path[300];
    int rc = API_OK;
    snprintf(lname, sizeof lname, "%s", name);
    api_packed *a = pk && json_is_string(ps)
                        ? api_packed_find(pk, 0, API_PACKED_RINGS, json_string_value(ps))
                        : NULL;
    if (pk && json_is_string(ps) && !a) return API_EINVALID; /* not ours: jansson's path */
    if (a) {
        if ((rc = packed_polygons(a, b, err)) != API_OK) return rc;
        for (size_t q = 0; q < a->npoly && rc == API_OK; q++) rc = keep_properties(b, NULL, err);
        return rc;
    }
    if (one_ok &&
        (json_is_string(ps) ||
         (json_is_object(ps) &&
          strcmp(json_string_value(json_object_get(ps, "type")) ?: "", "FeatureCollection")))) {
        rc = read_polygon(ps, pk, b, name, err);
        if (rc == API_OK) rc = end_polygon(b, 1, err);
        if (rc == API_OK) rc = keep_properties(b, ps, err);
        return rc;
    }
    if (json_is_object(ps)) {
        const char *type = json_string_value(json_object_get(ps, "type"));
        if (!type || strcmp(type, "FeatureCollection"))
            return api_fail(err, API_EINVALID,
                            "%s: expected an array of polygons or a GeoJSON "
                            "FeatureCollection (an object with \"type\": \"FeatureCollection\")",
                            name);
        list = json_object_get(ps, "features");
        snprintf(lname, sizeof lname, "%s.features", name);
        if (!json_is_array(list))
            return api_fail(err, API_EINVALID, "%s: expected an array of Features", lname);
    }
    if (!json_is_array(list) || json_array_size(list) == 0)
        return api_fail(err, API_EINVALID,
                        "%s: expected a non-empty array of polygons [ring, hole, ...]", lname);
    if (b->npoly + json_array_size(list) > BOOL2_MAX_INPUTS)
        return api_fail(err, API_EINVALID, "%s: %zu polygons in all, at most %u allowed", lname,
                        b->npoly + json_array_size(list), (unsigned)BOOL2_MAX_INPUTS);
    for (size_t i = 0; i < json_array_size(list) && rc == API_OK; i++) {
        const json_t *p = json_array_get(list, i);
        snprintf(path, sizeof path, "%s[%zu]", lname, i);
        if (list != ps &&
            !(json_is_object(p) &&
              !strcmp(json_string_value(json_object_get(p, "type")) ?: "", "Feature")))
            rc = api_fail(err, API_EINVALID, "%s: expected a GeoJSON Feature", path);
        else
            rc = read_polygon(p, pk, b, path, err);
        if (rc == API_OK) rc = end_polygon(b, json_array_size(list) - i, err);
        if (rc == API_OK) rc = keep_properties(b, p, err);
    }
    return rc;
}

/* Hands b's arrays to r (empty ones allocated), or frees them on failure. */
static int take_build(pbuild *b, int rc, polygons_req *r, api_error *err)
{
    /* an input without polygons (or points) still has its first offsets, 0 */
    if (rc == API_OK && !b->poly_off) b->poly_off = calloc(1, sizeof *b->poly_off);
    if (rc == API_OK && !b->ring_off) b->ring_off = calloc(1, sizeof *b->ring_off);
    if (rc == API_OK && !b->xy) b->xy = calloc(2, sizeof *b->xy);
    if (rc == API_OK && (!b->poly_off || !b->ring_off || !b->xy))
        rc = api_fail(err, API_ENOMEM, "out of memory");
    if (rc != API_OK) {
        pbuild_free(b);
        return rc;
    }
    r->npoly = b->npoly;
    r->poly_off = b->poly_off;
    r->ring_off = b->ring_off;
    r->xy = b->xy;
    return API_OK;
}

/* Reads "polygons" (read_list). */
static int parse_polygons(const json_t *ps, api_packed_set *pk, polygons_req *r, api_error *err)
{
    pbuild b = {0};
    if (!ps)
        return api_fail(err, API_EINVALID,
                        "polygons: required, an array of polygons or a GeoJSON "
                        "FeatureCollection (or \"layers\": {\"name\": polygons, ...})");
    return take_build(&b, read_list(ps, "polygons", 0, pk, &b, err), r, err);
}

/* Reads "layers": {"name": polygons, ...} (each read_list's, or one polygon), in order: the
 * layers' names, where each begins, and every polygon's properties. */
static int parse_layers(const json_t *ls, api_packed_set *pk, polygons_req *r, api_error *err)
{
    pbuild b = {0};
    api_buf props = {0};
    const char *key;
    json_t *v;
    int rc = API_OK;
    if (!json_is_object(ls) || json_object_size(ls) == 0)
        return api_fail(err, API_EINVALID,
                        "layers: expected an object {\"name\": FeatureCollection or array of "
                        "polygons, ...}");
    size_t nl = json_object_size(ls);
    r->lname = calloc(nl, sizeof *r->lname);
    r->lfirst = calloc(nl + 1, sizeof *r->lfirst);
    if (!r->lname || !r->lfirst) return api_fail(err, API_ENOMEM, "out of memory");
    b.props = &props;
    json_object_foreach((json_t *)ls, key, v)
    {
        char name[200];
        size_t k = r->nlayers;
        if (!*key || strlen(key) > API_LAYER_NAME_MAX) {
            rc = api_fail(err, API_EINVALID, "layers: a layer's name must have 1 to %d bytes",
                          API_LAYER_NAME_MAX);
            break;
        }
        json_t *js = json_string(key);
        r->lname[k] = js ? json_dumps(js, JSON_ENCODE_ANY | JSON_COMPACT) : NULL;
        json_decref(js);
        if (!r->lname[k]) {
            rc = api_fail(err, API_ENOMEM, "out of memory");
            break;
        }
        r->nlayers++;
        r->lfirst[k] = (uint32_t)b.npoly;
        snprintf(name, sizeof name, "layers.%.100s", key);
        if ((rc = read_list(v, name, 1, pk, &b, err)) != API_OK) break;
    }
    r->lfirst[r->nlayers] = (uint32_t)b.npoly;
    if (rc == API_OK && props.failed) rc = api_fail(err, API_ENOMEM, "out of memory");
    if (rc == API_OK) {
        r->prop_off = malloc((b.npoly + 1) * sizeof *r->prop_off);
        if (!r->prop_off) rc = api_fail(err, API_ENOMEM, "out of memory");
    }
    if (rc == API_OK) { /* the NUL-ended texts, one per polygon, in order */
        size_t at = 0;
        for (size_t p = 0; p < b.npoly; p++) {
            r->prop_off[p] = at;
            at += strlen(props.p + at) + 1;
        }
        r->prop_off[b.npoly] = at;
        r->props = props.p;
        props.p = NULL;
    }
    api_buf_free(&props);
    return take_build(&b, rc, r, err);
}

int api_polygons_parse(const json_t *req, void **parsed, api_error *err)
{
    return api_polygons_parse_packed(req, NULL, parsed, err);
}

int api_polygons_parse_packed(const json_t *req, api_packed_set *pk, void **parsed, api_error *err)
{
    const char *key;
    json_t *v;
    polygons_req *r;
    int rc;
    *parsed = NULL;
    json_object_foreach((json_t *)req, key, v)
    {
        if (strcmp(key, "kind") && strcmp(key, "polygons") && strcmp(key, "layers") &&
            strcmp(key, "op") && strcmp(key, "options"))
            return api_fail(err, API_EINVALID,
                            "%.64s: unknown key (expected kind, polygons or layers, op, options)",
                            key);
    }
    if (json_object_get(req, "polygons") && json_object_get(req, "layers"))
        return api_fail(err, API_EINVALID,
                        "layers: give either \"polygons\" or \"layers\", not both");
    r = calloc(1, sizeof *r);
    if (!r) return api_fail(err, API_ENOMEM, "out of memory");
    rc = parse_options(json_object_get(req, "options"), r, err);
    if (rc != API_OK) goto fail;
    const json_t *layers = json_object_get(req, "layers");
    rc = layers ? parse_layers(layers, pk, r, err)
                : parse_polygons(json_object_get(req, "polygons"), pk, r, err);
    if (rc != API_OK) goto fail;
    if (!json_object_get(req, "op")) {
        rc = api_fail(err, API_EINVALID,
                      "op: required, \"union\", \"intersection\", \"difference\", \"xor\" or an "
                      "expression such as [\"-\", 0, [\"+\", 1, 2]]");
        goto fail;
    }
    if (layers) {
        api_layers ly = {r->nlayers, r->lname, r->lfirst};
        rc = api_bool_parse_layers(json_object_get(req, "op"), r->npoly, &ly, &r->op, err);
    } else {
        rc = api_bool_parse(json_object_get(req, "op"), r->npoly, &r->op, err);
        r->named_and = !strcmp(json_string_value(json_object_get(req, "op")) ?: "", "intersection");
    }
    if (rc != API_OK) goto fail;
    *parsed = r;
    return API_OK;
fail:
    api_polygons_free(r);
    return rc;
}

/* What put_bool2 writes: the result, and the request's fields. */
typedef struct bool2_out {
    const bool2_result *r;
    unsigned fields;
    const polygons_req *req; /* its layers */
} bool2_out;

/* One cycle, its vertices through map (NULL: as they are). */
static void put_ring(api_buf *b, const uint32_t *rc_off, const uint32_t *rv, uint32_t k,
                     const uint32_t *map)
{
    if (!map) {
        api_buf_u32_list(b, rv + rc_off[k], rc_off[k + 1] - rc_off[k]);
        return;
    }
    api_buf_putc(b, '[');
    for (uint32_t i = rc_off[k]; i < rc_off[k + 1]; i++) {
        if (i > rc_off[k]) api_buf_putc(b, ',');
        api_buf_u64(b, map[rv[i]]);
    }
    api_buf_putc(b, ']');
}

/* "holes": {"q": [cycle, ...], ...} of the polygons of g that have holes. */
static void put_holes(api_buf *b, const bool2_rings *g, const uint32_t *map)
{
    api_buf_puts(b, "\"holes\":{");
    int hfirst = 1;
    for (size_t q = 0; q < g->npoly; q++) {
        if (g->ph_off[q] == g->ph_off[q + 1]) continue;
        if (!hfirst) api_buf_putc(b, ',');
        hfirst = 0;
        api_buf_putc(b, '"');
        api_buf_u64(b, q);
        api_buf_puts(b, "\":[");
        for (uint32_t h = g->ph_off[q]; h < g->ph_off[q + 1]; h++) {
            if (h > g->ph_off[q]) api_buf_putc(b, ',');
            put_ring(b, g->rc_off, g->rv, g->ph_cyc[h], map);
        }
        api_buf_putc(b, ']');
    }
    api_buf_putc(b, '}');
}

/* "pieces" of a layers request's result: {"FV": [outer cycle of each polygon], "holes": {...},
 * "piece": [the piece of each polygon], "inputs": {"indptr", "indices"} (piece k lies in the
 * inputs indices[indptr[k] .. indptr[k+1]))}. */
static void put_pieces(api_buf *b, const bool2_result *r, int fill, const uint32_t *map)
{
    const bool2_rings *g = &r->pieces;
    api_buf_puts(b, ",\"pieces\":{\"FV\":[");
    for (size_t q = 0; q < g->npoly; q++) {
        if (q) api_buf_putc(b, ',');
        put_ring(b, g->rc_off, g->rv, g->poly_outer[q], map);
    }
    api_buf_puts(b, "],");
    put_holes(b, g, map);
    api_buf_puts(b, ",\"piece\":");
    api_buf_u32_list(b, r->poly_piece, g->npoly);
    member_rows m = {r->mem_off, r->mem, r->memw};
    uint32_t *buf = malloc((member_row_most(&m, r->c.nf) + 1) * sizeof *buf);
    if (!buf) {
        b->failed = 1;
        return;
    }
    api_buf_puts(b, ",\"inputs\":{\"indptr\":[0");
    size_t at = 0;
    for (size_t k = 0; k < r->npieces; k++) {
        const uint32_t *row;
        at += member_row_inside(&m, r->piece_face[k], fill, buf, &row);
        api_buf_putc(b, ',');
        api_buf_u64(b, at);
    }
    api_buf_puts(b, "],\"indices\":[");
    at = 0;
    for (size_t k = 0; k < r->npieces; k++) {
        const uint32_t *row;
        size_t n = member_row_inside(&m, r->piece_face[k], fill, buf, &row);
        for (size_t i = 0; i < n; i++) {
            if (at++) api_buf_putc(b, ',');
            api_buf_u64(b, row[i]);
        }
    }
    api_buf_puts(b, "]}}");
    free(buf);
}

/* "layers": [{"name", "first", "count", "properties": [each input's, or null]}, ...]. */
static void put_layers(api_buf *b, const polygons_req *q)
{
    api_buf_puts(b, ",\"layers\":[");
    for (size_t k = 0; k < q->nlayers; k++) {
        api_buf_puts(b, k ? ",{\"name\":" : "{\"name\":");
        api_buf_puts(b, q->lname[k]);
        api_buf_puts(b, ",\"first\":");
        api_buf_u64(b, q->lfirst[k]);
        api_buf_puts(b, ",\"count\":");
        api_buf_u64(b, q->lfirst[k + 1] - q->lfirst[k]);
        api_buf_puts(b, ",\"properties\":[");
        for (uint32_t p = q->lfirst[k]; p < q->lfirst[k + 1]; p++) {
            if (p > q->lfirst[k]) api_buf_putc(b, ',');
            api_buf_put(b, q->props + q->prop_off[p], q->prop_off[p + 1] - q->prop_off[p] - 1);
        }
        api_buf_puts(b, "]}");
    }
    api_buf_putc(b, ']');
}

/* The "membership" and "result" members (api_lar2_fmt.more), each when the fields have it
 * (without fields given: both).  Nothing in the result refers to a key left out: it has
 * "cells" with the complex's faces (FV or FE), "FE" with its EV, and, without its V, a "V" of
 * its own: the vertices its cycles use, in the complex's order, which its "FV" and "holes"
 * then index. */
static void put_bool2(api_buf *b, const void *udata)
{
    const bool2_out *o = udata;
    const bool2_result *r = o->r;
    const bool2_rings *g = &r->region;
    unsigned fl = o->fields;
    int membership = (fl & API_F_MEMBERSHIP) != 0, result = (fl & API_F_RESULT) != 0;
    int cells = (fl & (API_F_FV | API_F_FE)) != 0, fe = (fl & API_F_EV) != 0;
    uint32_t *map = NULL;
    if (o->req->nlayers) put_layers(b, o->req);
    if (membership) {
        api_put_membership_w(b, r->c.nf, r->ninputs, r->mem_off, r->mem, r->memw);
        api_buf_section(b);
    }
    if (!result) return;
    api_buf_puts(b, ",\"result\":{");
    const char *sep = "";
    if (!(fl & API_F_V)) { /* its own V */
        map = calloc(r->c.nv + 1, sizeof *map);
        if (!map) {
            b->failed = 1; /* out of memory: the result is incomplete, the run says so */
            return;
        }
        for (size_t i = 0; i < g->rc_off[g->nrcyc]; i++) map[g->rv[i]] = 1;
        for (size_t i = 0; r->npieces && i < r->pieces.rc_off[r->pieces.nrcyc]; i++)
            map[r->pieces.rv[i]] = 1;
        api_buf_own_vertices(b, r->c.V, r->c.nv, 2, map);
        sep = ",";
    }
    if (cells) {
        api_buf_puts(b, sep);
        api_buf_puts(b, "\"cells\":");
        api_buf_u32_list(b, r->cells, r->ncells);
        sep = ",";
    }
    api_buf_puts(b, sep);
    api_buf_puts(b, "\"FV\":[");
    for (size_t q = 0; q < g->npoly; q++) {
        if (q) api_buf_putc(b, ',');
        put_ring(b, g->rc_off, g->rv, g->poly_outer[q], map);
    }
    api_buf_putc(b, ']');
    if (fe) {
        api_buf_puts(b, ",\"FE\":[");
        for (size_t q = 0; q < g->npoly; q++) {
            int first = 1;
            api_buf_puts(b, q ? ",[" : "[");
            for (uint32_t h = g->ph_off[q]; h <= g->ph_off[q + 1]; h++) {
                uint32_t k = h == g->ph_off[q] ? g->poly_outer[q] : g->ph_cyc[h - 1];
                for (uint32_t i = g->rc_off[k]; i < g->rc_off[k + 1]; i++) {
                    if (!first) api_buf_putc(b, ',');
                    first = 0;
                    api_buf_i64(b, g->re[i]);
                }
            }
            api_buf_putc(b, ']');
        }
        api_buf_putc(b, ']');
    }
    api_buf_putc(b, ',');
    put_holes(b, g, map);
    if (o->req->nlayers) put_pieces(b, r, o->req->fill, map);
    api_buf_puts(b, ",\"area\":");
    api_buf_double(b, r->area);
    api_buf_putc(b, '}');
    free(map);
}

/* stats.warnings, when there is something to say: the one trap so far is a named
 * "intersection" over many single polygons (two layers merged into one collection) that is
 * empty, where "layers" was meant. */
static void put_warnings(api_buf *b, const void *udata)
{
    const bool2_out *o = udata;
    if (!(o->req->named_and && o->r->ninputs > 2 && o->r->region.npoly == 0)) return;
    char msg[300];
    snprintf(msg, sizeof msg,
             ",\"warnings\":[\"op: the intersection of all %zu polygons is empty; to intersect "
             "collections, give them as \\\"layers\\\" and an op over their names, such as "
             "[\\\"&\\\", \\\"parcels\\\", \\\"zones\\\"]\"]",
             o->r->ninputs);
    api_buf_puts(b, msg);
}

/* Builds r's arrangement and Boolean into *res (the caller frees it with bool2_free). */
static int polygons_compute(const polygons_req *r, const api_run_opts *ro, bool2_result *res,
                            api_error *err)
{
    arr2_opts ao = {.precision = r->opt.precision,
                    .keep_dangling = r->opt.keep_dangling,
                    .threads = ro->threads,
                    .cancel = ro->cancel,
                    .progress = ro->progress,
                    .udata = ro->udata};
    bool2_input in = {r->npoly, r->poly_off, r->ring_off, r->xy, r->fill, r->nlayers > 0};
    char core_msg[API_ERRMAX] = "";
    int rc = bool2_build(&in, &r->op, &ao, res, core_msg, sizeof core_msg);
    if (rc != ARR_OK) return api_core_fail(err, rc, core_msg);
    if (ro->progress) ro->progress(ro->udata, "output", 0);
    return API_OK;
}

int api_polygons_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err)
{
    const polygons_req *r = parsed;
    bool2_result res = {0};
    int rc = polygons_compute(r, ro, &res, err);
    if (rc == API_OK) {
        bool2_out bo = {&res, r->opt.fields, r};
        api_lar2_fmt fmt = {.fields = r->opt.fields,
                            .exterior_last = r->opt.exterior_last,
                            .stats_more = put_warnings,
                            .stats_udata = &bo,
                            .more = put_bool2,
                            .more_udata = &bo};
        rc = api_lar2_write(out, &res.c, &fmt, err);
    }
    bool2_free(&res);
    return rc;
}

/* ---- arrays out (the library) ---------------------------------------------------------------- */

static void bool2_drop(void *p)
{
    bool2_free(p);
    free(p);
}

/* The arrays of "result", as put_bool2 writes it. */
static int bool2_arrays(api_arrays *out, const bool2_result *r, unsigned fl)
{
    const bool2_rings *g = &r->region;
    int bad = 0;
    uint32_t *map = NULL;
    if (!(fl & API_F_V)) { /* its own V */
        map = calloc(r->c.nv + 1, sizeof *map);
        if (!map) return -1;
        for (size_t i = 0; i < g->rc_off[g->nrcyc]; i++) map[g->rv[i]] = 1;
        bad = api_arrays_own_vertices(out, "result.V", r->c.V, r->c.nv, 2, map);
    }
    if (fl & (API_F_FV | API_F_FE))
        api_arrays_put(out, &bad, "result.cells", API_A_U32, r->ncells, 1, r->cells, 0);
    bad = bad ||
          api_arrays_cycles(out, "result.FV", g->rc_off, g->rv, g->poly_outer, NULL, g->npoly, map);
    if (!bad && (fl & API_F_EV)) {
        size_t total = g->rc_off[g->nrcyc];
        uint32_t *ptr = malloc((g->npoly + 1) * sizeof *ptr);
        int32_t *idx = malloc((total + 1) * sizeof *idx);
        size_t w = 0;
        for (size_t q = 0; ptr && idx && q < g->npoly; q++) {
            ptr[q] = (uint32_t)w;
            for (uint32_t h = g->ph_off[q]; h <= g->ph_off[q + 1]; h++) {
                uint32_t k = h == g->ph_off[q] ? g->poly_outer[q] : g->ph_cyc[h - 1];
                for (uint32_t i = g->rc_off[k]; i < g->rc_off[k + 1]; i++) idx[w++] = g->re[i];
            }
        }
        if (ptr) ptr[g->npoly] = (uint32_t)w;
        bad = !ptr || !idx;
        api_arrays_put(out, &bad, "result.FE.indptr", API_A_U32, g->npoly + 1, 1, ptr, 1);
        api_arrays_put(out, &bad, "result.FE.indices", API_A_I32, w, 1, idx, 1);
    }
    api_arrays_holes(out, &bad, "result.holes", g->npoly, g->ph_off, g->ph_cyc, g->rc_off, g->rv,
                     map);
    api_arrays_f64(out, &bad, "result.area", r->area);
    free(map);
    return bad ? -1 : 0;
}

int api_polygons_arrays(const void *parsed, const api_run_opts *ro, api_arrays *out, api_error *err)
{
    const polygons_req *r = parsed;
    bool2_result *res = calloc(1, sizeof *res); /* kept by the result, which frees it */
    if (!res || api_arrays_keep(out, res, bool2_drop))
        return api_fail(err, API_ENOMEM, "out of memory");
    int rc = polygons_compute(r, ro, res, err);
    if (rc != API_OK) return rc;
    bool2_out bo = {res, r->opt.fields, r};
    api_lar2_fmt fmt = {.fields = r->opt.fields, .stats_more = put_warnings, .stats_udata = &bo};
    rc = api_lar2_arrays(out, &res->c, &fmt, err);
    if (rc != API_OK) return rc;
    if ((r->opt.fields & API_F_MEMBERSHIP) &&
        api_arrays_membership(out, res->c.nf, res->ninputs, res->mem_off, res->mem, res->memw))
        return api_fail(err, API_ENOMEM, "out of memory");
    if ((r->opt.fields & API_F_RESULT) && bool2_arrays(out, res, r->opt.fields))
        return api_fail(err, API_ENOMEM, "out of memory");
    return API_OK;
}

int api_polygons_make(size_t npoly, const uint32_t *poly_off, const uint32_t *ring_off,
                      const double *xy, const json_t *op, const json_t *options, void **parsed,
                      api_error *err)
{
    pbuild b = {0};
    char path[96];
    int rc = API_OK;
    *parsed = NULL;
    if (npoly > BOOL2_MAX_INPUTS)
        return api_fail(err, API_EINVALID, "polygons: %zu polygons, at most %u allowed", npoly,
                        (unsigned)BOOL2_MAX_INPUTS);
    polygons_req *r = calloc(1, sizeof *r);
    if (!r) return api_fail(err, API_ENOMEM, "out of memory");
    rc = parse_options(options, r, err);
    for (size_t p = 0; rc == API_OK && p < npoly; p++) {
        if (poly_off[p + 1] <= poly_off[p]) {
            rc = api_fail(err, API_EINVALID,
                          "polygons[%zu]: expected at least one ring (poly_off[%zu] = %u, "
                          "poly_off[%zu] = %u)",
                          p, p, poly_off[p], p + 1, poly_off[p + 1]);
            break;
        }
        for (uint32_t k = poly_off[p]; rc == API_OK && k < poly_off[p + 1]; k++) {
            snprintf(path, sizeof path, "polygons[%zu] ring %u", p, k - poly_off[p]);
            if (ring_off[k + 1] < ring_off[k] + 3) {
                rc = api_fail(err, API_EINVALID, "%s: expected a ring of at least 3 points", path);
                break;
            }
            for (uint32_t i = ring_off[k]; rc == API_OK && i < ring_off[k + 1]; i++) {
                if (!isfinite(xy[2 * (size_t)i]) || !isfinite(xy[2 * (size_t)i + 1]))
                    rc = api_fail(err, API_EINVALID, "%s point %u: expected finite numbers", path,
                                  i - ring_off[k]);
                else
                    rc = add_point(&b, xy[2 * (size_t)i], xy[2 * (size_t)i + 1], err);
            }
            if (rc == API_OK) rc = end_ring(&b, path, err);
        }
        if (rc == API_OK) rc = end_polygon(&b, npoly, err);
    }
    rc = take_build(&b, rc, r, err);
    if (rc == API_OK) rc = api_bool_parse(op, r->npoly, &r->op, err);
    if (rc == API_OK && json_is_string(op))
        r->named_and = !strcmp(json_string_value(op), "intersection");
    if (rc != API_OK) {
        api_polygons_free(r);
        return rc;
    }
    *parsed = r;
    return API_OK;
}
