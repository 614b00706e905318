/* render.c — a 2D result (LAR JSON) drawn as SVG or written as GeoJSON (api/render.h).
 *
 * The result is read by api_result_read() (api/result.c, dim 2) into a flat model: V as
 * doubles, and for each bounded face its rings (the outer cycle, then its holes) as runs of
 * vertex indices:
 *
 *     face_ring:  f -> [face_ring[f], face_ring[f+1])      rings of face f, outer first
 *     ring_off:   r -> [ring_off[r], ring_off[r+1])        positions in idx
 *     idx:        vertex indices, every one < nv (checked while reading)
 *
 * so the writers never look at JSON again and never index out of bounds; a Boolean's result
 * polygons are rings of the same table, after the faces'.  The JSON tree is freed before
 * anything is drawn.  Output is streamed into api_bufs (api/api_int.h), numbers formatted by
 * api_format_double.  The faces and the edges are written into buffers of their own, and the
 * label points kept, before the SVG's header: the viewBox (and with it the stroke width and the
 * font size in user units) must fit every coordinate drawn, exploded faces and labels included,
 * which is known only at the end: svg_write() runs svg_place, svg_faces, svg_edges, svg_labels,
 * then svg_frame_of, and writes svg_head, svg_body and svg_numbers around the parts.  A layers
 * result's GeoJSON is read (lay_read, lp_read) and written a piece at a time (layer_geometry once,
 * layer_features per choice of parents).
 *
 * Geometry here is for pictures, not for the complex: floating point, no exact predicates.
 * The face label point is the one place that must be right: the midpoint of the widest
 * horizontal chord through the face, taken at heights strictly between two consecutive distinct
 * vertex heights of the face, so the line meets no vertex and the crossings' parity (decided by
 * comparisons only, hence exact) says which chords are inside; holes and edges walked twice
 * (kept dangling) fall out of the parity.  Faces with many distinct heights try 64 of them
 * spread over the range plus the largest gap, so the cost stays linear in the face's size.
 *
 * Threads: reentrant, no globals.  Ownership: inputs are borrowed; the output buffer goes to the
 * caller (free()).
 */
#include "api/render.h"

#include "api/api_int.h"
#include "core/sort.h"

#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- options ------------------------------------------------------------------------------- */

const render_format render_formats[] = {
    {"json", "application/json", "application/*", 0, NULL, 0},
    {"svg", "image/svg+xml", "image/*", 2, render_svg, RENDER_MAX_BYTES},
    {"geojson", "application/geo+json", NULL, 2, render_geojson, RENDER_MAX_BYTES},
    {"obj", "model/obj", "model/*", 3, render_obj, RENDER_MAX_BYTES},
    {"npz", "application/x-npz", NULL, 0, render_npz, RENDER_NPZ_MAX_BYTES},
    {"stl", "model/stl", NULL, 3, render_stl, RENDER_MAX_BYTES},
    {"off", "model/vnd.off", NULL, 3, render_off, RENDER_MAX_BYTES},
    {"3mf", "model/3mf", NULL, 3, render_3mf, RENDER_MAX_BYTES},
    {"glb", "model/gltf-binary", NULL, 3, render_glb, RENDER_MAX_BYTES},
};
const size_t render_nformats = sizeof render_formats / sizeof *render_formats;

const render_format *render_format_named(const char *name)
{
    for (size_t i = 0; name && i < render_nformats; i++)
        if (!strcmp(render_formats[i].name, name)) return &render_formats[i];
    return NULL;
}

void render_opts_init(render_opts *o)
{
    *o = (render_opts)RENDER_OPTS_INIT;
}

static int check_opts(const render_opts *o, api_error *err)
{
    if (!(o->explode >= 1 && o->explode <= RENDER_EXPLODE_MAX))
        return api_fail(err, API_EINVALID, "explode: expected a number in [1, %g]",
                        RENDER_EXPLODE_MAX);
    if (o->width < RENDER_WIDTH_MIN || o->width > RENDER_WIDTH_MAX)
        return api_fail(err, API_EINVALID, "width: expected an integer in [%d, %d]",
                        RENDER_WIDTH_MIN, RENDER_WIDTH_MAX);
    if (!(o->stroke >= 0 && o->stroke <= RENDER_STROKE_MAX))
        return api_fail(err, API_EINVALID, "stroke: expected a number in [0, %g] (0: auto)",
                        RENDER_STROKE_MAX);
    return API_OK;
}

/* A decimal number, nothing else (no spaces, no hex, no inf or nan). */
static int parse_number(const char *s, double *out)
{
    char *end;
    if (!s || !*s) return 0;
    for (const char *p = s; *p; p++)
        if (!isdigit((unsigned char)*p) && !strchr("+-.eE", *p)) return 0;
    *out = strtod(s, &end);
    return *end == 0 && isfinite(*out);
}

/* 1 0 true false yes no on off (any case); no value at all is true ("?numbers"). */
static int parse_bool(const char *s, int *out)
{
    static const char *const words[] = {"1", "true", "yes", "on", "0", "false", "no", "off"};
    if (!s || !*s) {
        *out = 1;
        return 1;
    }
    for (size_t i = 0; i < sizeof words / sizeof *words; i++) {
        if (!strcasecmp(s, words[i])) {
            *out = i < 4;
            return 1;
        }
    }
    return 0;
}

int render_opts_is_query_key(const char *key)
{
    static const char *const keys[] = {"explode", "numbers", "edges", "width", "stroke", "cells"};
    for (size_t i = 0; key && i < sizeof keys / sizeof *keys; i++)
        if (!strcmp(key, keys[i])) return 1;
    return 0;
}

int render_opts_parse_query(const char *query_key, const char *value, render_opts *o,
                            api_error *err)
{
    const char *k = query_key ? query_key : "";
    const char *v = value ? value : "";
    double d;
    int b;
    if (!strcmp(k, "explode")) {
        if (!parse_number(value, &d) || !(d >= 1 && d <= RENDER_EXPLODE_MAX))
            return api_fail(err, API_EINVALID,
                            "explode: expected a number in [1, %g], got \"%.40s\"",
                            RENDER_EXPLODE_MAX, v);
        o->explode = d;
    } else if (!strcmp(k, "stroke")) {
        if (!parse_number(value, &d) || !(d >= 0 && d <= RENDER_STROKE_MAX))
            return api_fail(err, API_EINVALID,
                            "stroke: expected a number in [0, %g] (0: auto), got \"%.40s\"",
                            RENDER_STROKE_MAX, v);
        o->stroke = d;
    } else if (!strcmp(k, "width")) {
        char *end;
        long w = 0;
        int digits = *v != 0;
        for (const char *p = v; *p; p++) digits &= isdigit((unsigned char)*p) != 0;
        if (digits && strlen(v) <= 6) w = strtol(v, &end, 10);
        if (!digits || w < RENDER_WIDTH_MIN || w > RENDER_WIDTH_MAX)
            return api_fail(err, API_EINVALID,
                            "width: expected an integer in [%d, %d] (pixels), got \"%.40s\"",
                            RENDER_WIDTH_MIN, RENDER_WIDTH_MAX, v);
        o->width = (int)w;
    } else if (!strcmp(k, "cells")) {
        if (strcmp(v, "all") && strcmp(v, "result"))
            return api_fail(err, API_EINVALID, "cells: expected all or result, got \"%.40s\"", v);
        o->cells = !strcmp(v, "all");
    } else if (!strcmp(k, "numbers") || !strcmp(k, "edges")) {
        if (!parse_bool(value, &b))
            return api_fail(err, API_EINVALID,
                            "%s: expected 1, 0, true, false, yes, no, on or off, got \"%.40s\"", k,
                            v);
        if (k[0] == 'n')
            o->numbers = b;
        else
            o->edges = b;
    } else {
        return api_fail(err, API_EINVALID,
                        "%.40s: unknown parameter (expected explode, numbers, edges, width, "
                        "stroke or cells)",
                        k);
    }
    return API_OK;
}

static int hexval(int c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* Decodes s[0..n) (%XX, '+') into out (room for n + 1); returns 0 on a bad or %00 escape. */
static int url_decode(const char *s, size_t n, char *out)
{
    size_t w = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '+') {
            out[w++] = ' ';
        } else if (s[i] == '%') {
            int hi, lo;
            if (i + 2 >= n) return 0;
            hi = hexval((unsigned char)s[i + 1]);
            lo = hexval((unsigned char)s[i + 2]);
            if (hi < 0 || lo < 0 || (hi == 0 && lo == 0)) return 0;
            out[w++] = (char)(hi * 16 + lo);
            i += 2;
        } else {
            out[w++] = s[i];
        }
    }
    out[w] = 0;
    return 1;
}

int render_opts_parse_query_string(const char *query, size_t len, render_opts *o, api_error *err)
{
    char *buf = NULL;
    int rc = API_OK;
    size_t i = 0;
    if (!query) return API_OK;
    buf = malloc(2 * len + 2);
    if (!buf) return api_fail(err, API_ENOMEM, "out of memory reading the query");
    while (i < len) {
        size_t start = i, eq = SIZE_MAX;
        char *key = buf, *value;
        while (i < len && query[i] != '&' && query[i] != ';') {
            if (query[i] == '=' && eq == SIZE_MAX) eq = i;
            i++;
        }
        if (i > start) {
            size_t kend = eq == SIZE_MAX ? i : eq;
            value = buf + (kend - start) + 1;
            if (!url_decode(query + start, kend - start, key) ||
                (eq != SIZE_MAX && !url_decode(query + eq + 1, i - eq - 1, value))) {
                rc = api_fail(err, API_EINVALID,
                              "query: bad percent-escape in the parameter at byte %zu", start);
                goto fail;
            }
            rc = render_opts_parse_query(key, eq == SIZE_MAX ? NULL : value, o, err);
            if (rc != API_OK) goto fail;
        }
        i++; /* past the separator */
    }
fail:
    free(buf);
    return rc;
}

/* ---- the result's rings (read by api_result_read, api/result.c) ---------------------------- */

static size_t ring_len(const api_result *m, size_t r)
{
    return m->ring_off[r + 1] - m->ring_off[r];
}

static const uint32_t *ring_idx(const api_result *m, size_t r)
{
    return m->idx + m->ring_off[r];
}

/* Every vertex's coordinates formatted once, "x<sep>y" (y negated for SVG): a vertex is written
 * by each ring through it, and finding the shortest round-tripping form of a double is most of
 * the time spent on a large result. */
typedef struct vtext {
    api_buf pool; /* the texts, back to back */
    size_t *off;  /* owned, nv + 1: vertex v's text is pool.p[off[v] .. off[v+1]) */
} vtext;

static void vtext_free(vtext *t)
{
    api_buf_free(&t->pool);
    free(t->off);
    t->off = NULL;
}

static int vtext_make(const api_result *m, int negate_y, char sep, vtext *t)
{
    t->pool = (api_buf){0};
    t->off = malloc((m->nv + 1) * sizeof *t->off);
    if (!t->off) return API_ENOMEM;
    for (size_t v = 0; v < m->nv; v++) {
        t->off[v] = t->pool.len;
        api_buf_double(&t->pool, m->V[2 * v]);
        api_buf_putc(&t->pool, sep);
        api_buf_double(&t->pool, negate_y ? -m->V[2 * v + 1] : m->V[2 * v + 1]);
    }
    t->off[m->nv] = t->pool.len;
    if (!t->pool.failed) return API_OK;
    vtext_free(t);
    return API_ENOMEM;
}

static void vtext_put(api_buf *b, const vtext *t, uint32_t v)
{
    api_buf_put(b, t->pool.p + t->off[v], t->off[v + 1] - t->off[v]);
}

/* ---- geometry ------------------------------------------------------------------------------ */

/* Twice the signed area of ring r, and (when cx is not NULL) the first moments about (ox, oy)
 * times 6: the ring's share of the centroid sums. */
static double ring_area2(const api_result *m, size_t r, double ox, double oy, double *mx,
                         double *my)
{
    const uint32_t *v = ring_idx(m, r);
    size_t n = ring_len(m, r);
    double s = 0, sx = 0, sy = 0;
    for (size_t i = 0; i < n; i++) {
        const double *a = m->V + 2 * (size_t)v[i], *b = m->V + 2 * (size_t)v[(i + 1) % n];
        double ax = a[0] - ox, ay = a[1] - oy, bx = b[0] - ox, by = b[1] - oy;
        double c = ax * by - bx * ay;
        s += c;
        sx += (ax + bx) * c;
        sy += (ay + by) * c;
    }
    if (mx) *mx = sx;
    if (my) *my = sy;
    return s;
}

/* The face's area with its holes subtracted (holes are clockwise: their signed areas are <= 0). */
static double face_area(const api_result *m, size_t f)
{
    const double *o = m->V + 2 * (size_t)ring_idx(m, m->face_ring[f])[0];
    double s = 0;
    for (size_t r = m->face_ring[f]; r < m->face_ring[f + 1]; r++)
        s += ring_area2(m, r, o[0], o[1], NULL, NULL);
    return s / 2;
}

/* The face's area centroid (holes subtracted); its outer cycle's first vertex if the area is 0. */
static void face_centroid(const api_result *m, size_t f, double *x, double *y)
{
    const double *o = m->V + 2 * (size_t)ring_idx(m, m->face_ring[f])[0];
    double s = 0, sx = 0, sy = 0;
    for (size_t r = m->face_ring[f]; r < m->face_ring[f + 1]; r++) {
        double mx, my;
        s += ring_area2(m, r, o[0], o[1], &mx, &my);
        sx += mx;
        sy += my;
    }
    *x = o[0];
    *y = o[1];
    if (s > 0) {
        *x += sx / (3 * s);
        *y += sy / (3 * s);
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

#define LABEL_HEIGHTS 64 /* heights tried for a face label when the face has more */

/* Width of the widest inside chord of face f at height y (no vertex at y), its midpoint in *mid;
 * xs has room for the face's vertex count. */
static double widest_chord(const api_result *m, size_t f, double y, double *xs, double *mid)
{
    size_t k = 0;
    double best = -1;
    for (size_t r = m->face_ring[f]; r < m->face_ring[f + 1]; r++) {
        const uint32_t *v = ring_idx(m, r);
        size_t n = ring_len(m, r);
        for (size_t i = 0; i < n; i++) {
            const double *a = m->V + 2 * (size_t)v[i], *b = m->V + 2 * (size_t)v[(i + 1) % n];
            if ((a[1] > y) != (b[1] > y))
                xs[k++] = a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
        }
    }
    qsort(xs, k, sizeof *xs, cmp_double);
    for (size_t i = 0; i + 1 < k; i += 2) {
        if (xs[i + 1] - xs[i] > best) {
            best = xs[i + 1] - xs[i];
            *mid = xs[i] / 2 + xs[i + 1] / 2;
        }
    }
    return best;
}

/* A point strictly inside face f (holes excluded), for its number; ys and xs have room for the
 * face's vertex count. */
static void face_label_point(const api_result *m, size_t f, double *ys, double *xs, double *px,
                             double *py)
{
    size_t n = 0, u = 0, gaps, big = 0, tries;
    double best = -1;
    for (size_t r = m->face_ring[f]; r < m->face_ring[f + 1]; r++)
        for (size_t i = 0; i < ring_len(m, r); i++)
            ys[n++] = m->V[2 * (size_t)ring_idx(m, r)[i] + 1];
    qsort(ys, n, sizeof *ys, cmp_double);
    for (size_t i = 0; i < n; i++)
        if (u == 0 || ys[i] != ys[u - 1]) ys[u++] = ys[i];
    face_centroid(m, f, px, py); /* the fallback: a face with no room between heights */
    gaps = u > 0 ? u - 1 : 0;
    for (size_t j = 1; j < gaps; j++)
        if (ys[j + 1] - ys[j] > ys[big + 1] - ys[big]) big = j;
    tries = gaps > LABEL_HEIGHTS ? LABEL_HEIGHTS + 1 : gaps;
    for (size_t t = 0; t < tries; t++) {
        size_t j = gaps <= LABEL_HEIGHTS ? t
                   : t == LABEL_HEIGHTS  ? big
                                         : t * (gaps - 1) / (LABEL_HEIGHTS - 1);
        double y, x = 0, wid;
        y = ys[j] / 2 + ys[j + 1] / 2;
        if (!(y > ys[j] && y < ys[j + 1])) continue; /* adjacent doubles: no height between */
        wid = widest_chord(m, f, y, xs, &x);
        if (wid > best) {
            best = wid;
            *px = x;
            *py = y;
        }
    }
}

/* ---- SVG ----------------------------------------------------------------------------------- */

typedef struct svg_ctx {
    double x0, y0, x1, y1; /* bounding box of the SVG coordinates written */
    int any;               /* the box holds a point */
    int overflow;          /* a coordinate was not finite (an explode too large for doubles) */
} svg_ctx;

/* Maps (x, y) to SVG coordinates (*sx, *sy) (y negated) and grows the box. */
static void svg_track(svg_ctx *c, double x, double y, double *sx, double *sy)
{
    *sx = x;
    *sy = -y;
    if (!isfinite(*sx) || !isfinite(*sy)) {
        c->overflow = 1;
        *sx = *sy = 0;
    }
    if (!c->any) {
        c->x0 = c->x1 = *sx;
        c->y0 = c->y1 = *sy;
        c->any = 1;
    } else {
        c->x0 = fmin(c->x0, *sx), c->x1 = fmax(c->x1, *sx);
        c->y0 = fmin(c->y0, *sy), c->y1 = fmax(c->y1, *sy);
    }
}

/* Writes "x y" of the point (x, y) for path data. */
static void svg_point(svg_ctx *c, api_buf *b, double x, double y)
{
    double sx, sy;
    svg_track(c, x, y, &sx, &sy);
    api_buf_double(b, sx);
    api_buf_putc(b, ' ');
    api_buf_double(b, sy);
}

static void svg_number_attr(api_buf *b, const char *name, double x)
{
    api_buf_putc(b, ' ');
    api_buf_puts(b, name);
    api_buf_puts(b, "=\"");
    api_buf_double(b, x);
    api_buf_putc(b, '"');
}

/* x to 4 significant digits, for sizes (stroke, font) where exactness is noise. */
static double round4(double x)
{
    char tmp[32];
    snprintf(tmp, sizeof tmp, "%.4g", x);
    return strtod(tmp, NULL);
}

/* Writes <text x=".." y="..">n</text> at the SVG point (sx, sy), in a group scaled by scale. */
static void svg_label(api_buf *b, double sx, double sy, double scale, size_t n)
{
    api_buf_puts(b, "<text");
    svg_number_attr(b, "x", sx / scale);
    svg_number_attr(b, "y", sy / scale);
    api_buf_putc(b, '>');
    api_buf_u64(b, n);
    api_buf_puts(b, "</text>\n");
}

/* Writes "x y" of vertex v translated by (dx, dy); in place, its text from vt. */
static void svg_vertex(svg_ctx *c, api_buf *b, const api_result *m, const vtext *vt, uint32_t v,
                       double dx, double dy)
{
    const double *p = m->V + 2 * (size_t)v;
    double sx, sy;
    if (dx == 0 && dy == 0) {
        svg_track(c, p[0], p[1], &sx, &sy);
        vtext_put(b, vt, v);
    } else {
        svg_point(c, b, p[0] + dx, p[1] + dy);
    }
}

/* Writes ring r of the model as "M x y L x y ... Z", translated by (dx, dy). */
static void svg_ring(svg_ctx *c, api_buf *b, const api_result *m, const vtext *vt, size_t r,
                     double dx, double dy)
{
    const uint32_t *v = ring_idx(m, r);
    for (size_t i = 0; i < ring_len(m, r); i++) {
        api_buf_puts(b, i == 0 ? (b->len && b->p[b->len - 1] != '"' ? " M" : "M") : " L");
        svg_vertex(c, b, m, vt, v[i], dx, dy);
    }
    api_buf_puts(b, " Z");
}

/* The fill of face f: golden-ratio hue steps, lightness in a second low-discrepancy sequence, so
 * neighbours by index differ and colours stay distinct for many faces. */
static void face_colour(size_t f, char out[8])
{
    static const char hex[] = "0123456789abcdef";
    double h = fmod((double)f * 0.6180339887498949, 1.0) * 6;
    double l = 0.56 + 0.18 * fmod((double)f * 0.7548776662466927 + 0.5, 1.0), s = 0.65;
    double ch = (1 - fabs(2 * l - 1)) * s, x = ch * (1 - fabs(fmod(h, 2) - 1)), lo = l - ch / 2;
    double rgb[3];
    int sector = (int)h;
    switch (sector) {
    case 0:
        rgb[0] = ch, rgb[1] = x, rgb[2] = 0;
        break;
    case 1:
        rgb[0] = x, rgb[1] = ch, rgb[2] = 0;
        break;
    case 2:
        rgb[0] = 0, rgb[1] = ch, rgb[2] = x;
        break;
    case 3:
        rgb[0] = 0, rgb[1] = x, rgb[2] = ch;
        break;
    case 4:
        rgb[0] = x, rgb[1] = 0, rgb[2] = ch;
        break;
    default:
        rgb[0] = ch, rgb[1] = 0, rgb[2] = x;
        break;
    }
    out[0] = '#';
    for (int i = 0; i < 3; i++) {
        long v = lround((rgb[i] + lo) * 255);
        v = v < 0 ? 0 : v > 255 ? 255 : v;
        out[1 + 2 * i] = hex[v >> 4];
        out[2 + 2 * i] = hex[v & 15];
    }
    out[7] = 0;
}

/* Length of the UTF-8 character at s[0..n) if it is one XML allows, else 0. */
static size_t xml_char_len(const unsigned char *s, size_t n)
{
    uint32_t cp;
    size_t len;
    if (s[0] < 0x80) return s[0] >= 0x20 || s[0] == '\t' || s[0] == '\n' || s[0] == '\r';
    if ((s[0] & 0xe0) == 0xc0)
        len = 2, cp = s[0] & 0x1f;
    else if ((s[0] & 0xf0) == 0xe0)
        len = 3, cp = s[0] & 0x0f;
    else if ((s[0] & 0xf8) == 0xf0)
        len = 4, cp = s[0] & 0x07;
    else
        return 0;
    if (len > n) return 0;
    for (size_t i = 1; i < len; i++) {
        if ((s[i] & 0xc0) != 0x80) return 0;
        cp = cp << 6 | (s[i] & 0x3f);
    }
    if ((len == 2 && cp < 0x80) || (len == 3 && cp < 0x800) || (len == 4 && cp < 0x10000) ||
        cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff) || cp == 0xfffe || cp == 0xffff)
        return 0;
    return len;
}

/* Appends text escaped for XML character data and attribute values; what XML cannot hold
 * (control characters, bytes that are not UTF-8) becomes '?'. */
static void xml_escape(api_buf *b, const char *text)
{
    const unsigned char *s = (const unsigned char *)text;
    size_t n = strlen(text);
    for (size_t i = 0; i < n;) {
        size_t k = xml_char_len(s + i, n - i);
        if (k == 0) {
            api_buf_putc(b, '?');
            i++;
            continue;
        }
        switch (s[i]) {
        case '<':
            api_buf_puts(b, "&lt;");
            break;
        case '>':
            api_buf_puts(b, "&gt;");
            break;
        case '&':
            api_buf_puts(b, "&amp;");
            break;
        case '"':
            api_buf_puts(b, "&quot;");
            break;
        case '\'':
            api_buf_puts(b, "&apos;");
            break;
        default:
            api_buf_put(b, (const char *)s + i, k);
        }
        i += k;
    }
}

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

/* The sorted keys of the edges walked by the faces' rings; NULL when out of memory. */
static uint64_t *face_edge_keys(const api_result *m, size_t *n)
{
    uint64_t *k = malloc(m->ring_off[m->nrings] * sizeof *k + 1);
    size_t w = 0;
    if (!k) return NULL;
    for (size_t r = 0; r < m->nrings; r++) {
        const uint32_t *v = ring_idx(m, r);
        size_t len = ring_len(m, r);
        for (size_t i = 0; i < len; i++) k[w++] = edge_key(v[i], v[(i + 1) % len]);
    }
    if (sort_u64(k, w)) {
        free(k);
        return NULL;
    }
    *n = w;
    return k;
}

static int has_key(const uint64_t *k, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (k[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && k[lo] == key;
}

/* The parts of a picture, each in its own buffer: the header, which needs the frame, is the
 * last thing known. */
typedef struct svg_parts {
    api_buf faces;   /* the <path> elements of the faces */
    api_buf edges;   /* the edges' path data */
    api_buf result;  /* a Boolean's result region's path data */
    double *label;   /* 2 per face: where its number goes, in SVG coordinates */
    double *off;     /* 2 per face: its translation */
    double *ys, *xs; /* scratch of the label points */
    uint64_t *keys;  /* sorted edges of the faces' rings (exploded drawings with EV) */
    vtext vt;        /* the vertices' SVG coordinates */
    double cx, cy;   /* centre of the bounding box of V (0, 0 when V is empty) */
} svg_parts;

static void svg_parts_free(svg_parts *p)
{
    api_buf_free(&p->faces);
    api_buf_free(&p->edges);
    api_buf_free(&p->result);
    free(p->label);
    free(p->off);
    free(p->ys);
    free(p->xs);
    free(p->keys);
    vtext_free(&p->vt);
}

/* The edges' path data: in place, EV (or, without EV, the faces' rings); exploded, each face's
 * rings with the face and the edges on no face moved by their midpoints. */
static int svg_edges(const api_result *m, const render_opts *o, svg_ctx *c, svg_parts *p)
{
    double k1 = o->explode - 1;
    size_t nkeys = 0;
    if (k1 > 0 || !m->ev)
        for (size_t f = 0; f < m->nf; f++)
            for (size_t r = m->face_ring[f]; r < m->face_ring[f + 1]; r++)
                svg_ring(c, &p->edges, m, &p->vt, r, p->off[2 * f], p->off[2 * f + 1]);
    if (!m->ev) return API_OK;
    if (k1 > 0) {
        p->keys = face_edge_keys(m, &nkeys);
        if (!p->keys) return API_ENOMEM;
    }
    for (size_t e = 0; e < m->ne; e++) {
        double dx = 0, dy = 0;
        if (k1 > 0) {
            const double *a = m->V + 2 * (size_t)m->ev[2 * e];
            const double *b = m->V + 2 * (size_t)m->ev[2 * e + 1];
            if (has_key(p->keys, nkeys, edge_key(m->ev[2 * e], m->ev[2 * e + 1]))) continue;
            dx = k1 * ((a[0] / 2 + b[0] / 2) - p->cx);
            dy = k1 * ((a[1] / 2 + b[1] / 2) - p->cy);
        }
        api_buf_puts(&p->edges, p->edges.len ? " M" : "M");
        svg_vertex(c, &p->edges, m, &p->vt, m->ev[2 * e], dx, dy);
        api_buf_puts(&p->edges, " L");
        svg_vertex(c, &p->edges, m, &p->vt, m->ev[2 * e + 1], dx, dy);
    }
    return API_OK;
}

/* The centre of the box of V (p->cx, p->cy), the vertices' text and each face's translation
 * (p->off: (explode - 1) times its centroid's offset from the centre; 0 in place); API_ENOMEM. */
static int svg_place(const api_result *m, const render_opts *o, svg_parts *p)
{
    double k1 = o->explode - 1;
    if (m->nv > 0) {
        double x0 = m->V[0], x1 = m->V[0], y0 = m->V[1], y1 = m->V[1];
        for (size_t i = 1; i < m->nv; i++) {
            x0 = fmin(x0, m->V[2 * i]), x1 = fmax(x1, m->V[2 * i]);
            y0 = fmin(y0, m->V[2 * i + 1]), y1 = fmax(y1, m->V[2 * i + 1]);
        }
        p->cx = x0 / 2 + x1 / 2;
        p->cy = y0 / 2 + y1 / 2;
    }
    p->off = calloc(2 * m->nf + 1, sizeof *p->off);
    if (!p->off || vtext_make(m, 1, ' ', &p->vt) != API_OK) return API_ENOMEM;
    for (size_t f = 0; k1 > 0 && f < m->nf; f++) {
        double x, y;
        face_centroid(m, f, &x, &y);
        p->off[2 * f] = k1 * (x - p->cx);
        p->off[2 * f + 1] = k1 * (y - p->cy);
    }
    return API_OK;
}

/* The faces' <path> elements (each its own fill, its rings moved by its translation). */
static void svg_faces(const api_result *m, svg_ctx *c, svg_parts *p)
{
    for (size_t f = 0; f < m->nf; f++) {
        char fill[8];
        face_colour(f, fill);
        api_buf_puts(&p->faces, "<path id=\"face-");
        api_buf_u64(&p->faces, f);
        api_buf_puts(&p->faces, "\" fill=\"");
        api_buf_puts(&p->faces, fill);
        api_buf_puts(&p->faces, "\" fill-rule=\"evenodd\" d=\"");
        for (size_t r = m->face_ring[f]; r < m->face_ring[f + 1]; r++)
            svg_ring(c, &p->faces, m, &p->vt, r, p->off[2 * f], p->off[2 * f + 1]);
        api_buf_puts(&p->faces, "\"/>\n");
    }
}

/* With numbers: every vertex tracked into the frame, and each face's label point
 * (face_label_point(), moved with the face) into p->label, tracked too; API_ENOMEM. */
static int svg_labels(const api_result *m, svg_ctx *c, svg_parts *p)
{
    size_t maxv = 0;
    double sx, sy;
    for (size_t v = 0; v < m->nv; v++) svg_track(c, m->V[2 * v], m->V[2 * v + 1], &sx, &sy);
    for (size_t f = 0; f < m->nf; f++) {
        size_t n = m->ring_off[m->face_ring[f + 1]] - m->ring_off[m->face_ring[f]];
        if (n > maxv) maxv = n;
    }
    p->ys = malloc(maxv * sizeof *p->ys + 1);
    p->xs = malloc(maxv * sizeof *p->xs + 1);
    p->label = malloc(2 * m->nf * sizeof *p->label + 1);
    if (!p->ys || !p->xs || !p->label) return API_ENOMEM;
    for (size_t f = 0; f < m->nf; f++) {
        double x, y;
        face_label_point(m, f, p->ys, p->xs, &x, &y);
        svg_track(c, x + p->off[2 * f], y + p->off[2 * f + 1], p->label + 2 * f,
                  p->label + 2 * f + 1);
    }
    return API_OK;
}

/* The picture's frame in user units and its sizes in pixels. */
typedef struct svg_frame {
    double vx, vy, vw, vh; /* the viewBox */
    double unit;           /* user units per pixel */
    double stroke_px, font_px;
    long height; /* in pixels */
} svg_frame;

/* The frame of everything tracked in c (the centre of V when nothing was), with a margin of
 * 5% of the larger side; API_EINVALID when it does not fit in doubles. */
static int svg_frame_of(svg_ctx *c, const svg_parts *p, const render_opts *o, svg_frame *fr,
                        api_error *err)
{
    double s, margin;
    if (!c->any) {
        c->x0 = c->x1 = p->cx;
        c->y0 = c->y1 = -p->cy;
    }
    s = fmax(c->x1 - c->x0, c->y1 - c->y0);
    margin = s > 0 ? 0.05 * s : fmax(1.0, 1e-3 * fmax(fabs(c->x0), fabs(c->y0)));
    fr->vx = c->x0 - margin;
    fr->vy = c->y0 - margin;
    fr->vw = (c->x1 - c->x0) + 2 * margin;
    fr->vh = (c->y1 - c->y0) + 2 * margin;
    if (!isfinite(fr->vx) || !isfinite(fr->vy) || !isfinite(fr->vw) || !isfinite(fr->vh) ||
        !(fr->vw > 0) || !(fr->vh > 0))
        return api_fail(err, API_EINVALID, "V: the drawing's extent does not fit in doubles");
    fr->unit = fr->vw / o->width;
    fr->height = lround(o->width * (fr->vh / fr->vw));
    if (fr->height < 1) fr->height = 1;
    fr->stroke_px = o->stroke > 0 ? o->stroke : fmin(4, fmax(0.5, o->width / 800.0));
    fr->font_px = fmin(24, fmax(6, 11 * o->width / 800.0));
    return API_OK;
}

/* The document's head: the XML declaration, <svg> with its size and viewBox, the <title>. */
static void svg_head(api_buf *out, const api_result *m, const render_opts *o, const svg_frame *fr)
{
    api_buf_puts(out, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\"");
    svg_number_attr(out, "width", o->width);
    svg_number_attr(out, "height", (double)fr->height);
    api_buf_puts(out, " viewBox=\"");
    api_buf_double(out, fr->vx);
    api_buf_putc(out, ' ');
    api_buf_double(out, fr->vy);
    api_buf_putc(out, ' ');
    api_buf_double(out, fr->vw);
    api_buf_putc(out, ' ');
    api_buf_double(out, fr->vh);
    api_buf_puts(out, "\">\n<title>");
    if (o->title) {
        xml_escape(out, o->title);
    } else {
        api_buf_puts(out, "cellar: ");
        api_buf_u64(out, m->nf);
        api_buf_puts(out, m->nf == 1 ? " face, " : " faces, ");
        api_buf_u64(out, m->ne);
        api_buf_puts(out, m->ne == 1 ? " edge, " : " edges, ");
        api_buf_u64(out, m->nv);
        api_buf_puts(out, m->nv == 1 ? " vertex" : " vertices");
    }
    api_buf_puts(out, "</title>\n");
}

/* The parts, in drawing order: the faces' group, the edges' path, a Boolean's result region. */
static void svg_body(api_buf *out, const svg_parts *p, const svg_frame *fr)
{
    api_buf_puts(out, "<g id=\"faces\" stroke=\"none\">\n");
    api_buf_put(out, p->faces.p ? p->faces.p : "", p->faces.len);
    api_buf_puts(out, "</g>\n");
    if (p->edges.len > 0) {
        api_buf_puts(out, "<path id=\"edges\" fill=\"none\" stroke=\"#1a1a1a\"");
        svg_number_attr(out, "stroke-width", round4(fr->stroke_px * fr->unit));
        api_buf_puts(out, " stroke-linecap=\"round\" stroke-linejoin=\"round\" d=\"");
        api_buf_put(out, p->edges.p, p->edges.len);
        api_buf_puts(out, "\"/>\n");
    }
    if (p->result.len > 0) {
        api_buf_puts(out, "<path id=\"result\" fill=\"#d62728\" fill-opacity=\"0.35\" "
                          "fill-rule=\"evenodd\" stroke=\"#d62728\"");
        svg_number_attr(out, "stroke-width", round4(2 * fr->stroke_px * fr->unit));
        api_buf_puts(out, " stroke-linejoin=\"round\" d=\"");
        api_buf_put(out, p->result.p, p->result.len);
        api_buf_puts(out, "\"/>\n");
    }
}

/* The vertex numbers' and the face numbers' groups (p->label: svg_labels()). */
static void svg_numbers(api_buf *out, const api_result *m, const svg_parts *p, const svg_frame *fr)
{
    /* Text lives in a group scaled to about a pixel per unit (a power of two, so positions
     * divide exactly): renderers that size glyphs in whole units, or apply a minimum font
     * size, draw a font of 0.005 user units badly or not at all. */
    double scale = ldexp(1.0, (int)lround(log2(fr->unit)));
    for (int i = 0; i < 2; i++) {
        api_buf_puts(out, i == 0 ? "<g id=\"vertex-numbers\" fill=\"#8b0000\""
                                 : "<g id=\"face-numbers\" fill=\"#000000\" "
                                   "font-weight=\"bold\"");
        api_buf_puts(out, " transform=\"scale(");
        api_buf_double(out, scale);
        api_buf_puts(out, ")\" font-family=\"sans-serif\"");
        svg_number_attr(out, "font-size", round4(fr->font_px * fr->unit / scale));
        api_buf_puts(out, " text-anchor=\"middle\" dominant-baseline=\"central\">\n");
        if (i == 0)
            for (size_t v = 0; v < m->nv; v++)
                svg_label(out, m->V[2 * v], -m->V[2 * v + 1], scale, v);
        else
            for (size_t f = 0; f < m->nf; f++)
                svg_label(out, p->label[2 * f], p->label[2 * f + 1], scale, f);
        api_buf_puts(out, "</g>\n");
    }
}

/* The picture of m: the parts drawn into their buffers first (tracking the frame), then the
 * document written into out around them. */
static int svg_write(const api_result *m, const render_opts *o, api_buf *out, api_error *err)
{
    svg_parts p = {0};
    svg_ctx c = {0};
    svg_frame fr = {0};
    int rc = API_OK;
    if (svg_place(m, o, &p) != API_OK) goto nomem;
    svg_faces(m, &c, &p);
    if (o->edges && svg_edges(m, o, &c, &p) != API_OK) goto nomem;
    /* a Boolean's result region, on top, where the faces are (not exploded) */
    if (m->has_result && !(o->explode - 1 > 0))
        for (size_t r = m->nface_rings; r < m->nrings; r++)
            svg_ring(&c, &p.result, m, &p.vt, r, 0, 0);
    if (o->numbers && svg_labels(m, &c, &p) != API_OK) goto nomem;
    if (p.faces.failed || p.edges.failed || p.result.failed) goto nomem;
    if (c.overflow) {
        rc = api_fail(err, API_EINVALID,
                      "explode: the exploded drawing does not fit in doubles (coordinates too "
                      "large)");
        goto fail;
    }
    rc = svg_frame_of(&c, &p, o, &fr, err);
    if (rc != API_OK) goto fail;
    svg_head(out, m, o, &fr);
    svg_body(out, &p, &fr);
    if (o->numbers) svg_numbers(out, m, &p, &fr);
    api_buf_puts(out, "</svg>\n");
    if (out->failed) goto nomem;
    goto fail; /* the common exit: rc is API_OK */
nomem:
    rc = api_fail(err, API_ENOMEM, "out of memory drawing the result");
fail:
    svg_parts_free(&p);
    return rc;
}

static int finish(api_buf *b, int rc, char **out, size_t *outlen, api_error *err)
{
    if (rc == API_OK && b->failed) rc = api_fail(err, API_ENOMEM, "out of memory");
    if (rc != API_OK) {
        api_buf_free(b);
        return rc;
    }
    *out = b->p;
    *outlen = b->len;
    if (err) *err = (api_error){0};
    return API_OK;
}

int render_svg(const char *result_json, size_t len, const render_opts *o, char **out,
               size_t *outlen, api_error *err)
{
    render_opts def = RENDER_OPTS_INIT;
    api_result m;
    api_buf b = {0};
    int rc;
    *out = NULL;
    *outlen = 0;
    if (!o) o = &def;
    rc = check_opts(o, err);
    if (rc != API_OK) return rc;
    rc = api_result_read(result_json, len, 2, "only 2D results are drawn", &m, err);
    if (rc != API_OK) return rc;
    rc = svg_write(&m, o, &b, err);
    api_result_free(&m);
    return finish(&b, rc, out, outlen, err);
}

/* ---- GeoJSON ------------------------------------------------------------------------------- */

/* Ring r as GeoJSON positions, closed: [[x,y],...,[x,y]]. */
static void geojson_cycle(api_buf *b, const vtext *vt, const uint32_t *v, size_t n)
{
    api_buf_putc(b, '[');
    for (size_t i = 0; i <= n; i++) {
        api_buf_puts(b, i ? ",[" : "[");
        vtext_put(b, vt, v[i % n]);
        api_buf_putc(b, ']');
    }
    api_buf_putc(b, ']');
}

static void geojson_ring(api_buf *b, const api_result *m, const vtext *vt, size_t r)
{
    geojson_cycle(b, vt, ring_idx(m, r), ring_len(m, r));
}

/* A face's cycles as OGC rings.  A boundary walk may pass a vertex twice: where a dangling tree
 * hangs from it (kept with keep_dangling), where a block of the graph hangs from a cut vertex
 * (a triangle touching the outer boundary at one vertex, two triangles meeting at one vertex
 * inside a face).  A Polygon ring may not, so each walk is cut at its repeated vertices into
 * simple cycles: those of fewer than 3 vertices are tree edges and enclose nothing (they become
 * dangling LineStrings); of the outer walk's pieces the counter-clockwise one is the shell and
 * the others (clockwise) are holes touching it; every piece of a hole walk is a hole. */
typedef struct pieces {
    int32_t *pos; /* nv: a vertex's place on the stack, -1 when not on it */
    uint32_t *stack;
    uint32_t *idx;  /* the pieces' vertices, back to back */
    size_t *off;    /* piece k is idx[off[k] .. off[k+1]) */
    uint8_t *outer; /* piece k comes from the outer walk */
    size_t n, nidx;
} pieces;

static void pieces_free(pieces *p)
{
    free(p->pos);
    free(p->stack);
    free(p->idx);
    free(p->off);
    free(p->outer);
}

/* Room for any one face's pieces; API_ENOMEM. */
static int pieces_init(pieces *p, const api_result *m)
{
    size_t most = 0;
    for (size_t f = 0; f < m->nf; f++) {
        size_t n = m->ring_off[m->face_ring[f + 1]] - m->ring_off[m->face_ring[f]];
        if (n > most) most = n;
    }
    *p = (pieces){0};
    p->pos = malloc((m->nv + 1) * sizeof *p->pos);
    p->stack = malloc((most + 1) * sizeof *p->stack);
    p->idx = malloc((most + 1) * sizeof *p->idx);
    p->off = malloc((most + 2) * sizeof *p->off);
    p->outer = malloc(most + 1);
    if (!p->pos || !p->stack || !p->idx || !p->off || !p->outer) return API_ENOMEM;
    for (size_t v = 0; v < m->nv; v++) p->pos[v] = -1;
    return API_OK;
}

/* Face f's walks cut into simple cycles (pieces of 3 or more vertices). */
static void pieces_of_face(pieces *p, const api_result *m, size_t f)
{
    p->n = p->nidx = 0;
    p->off[0] = 0;
    for (size_t r = m->face_ring[f]; r < m->face_ring[f + 1]; r++) {
        const uint32_t *v = ring_idx(m, r);
        size_t n = ring_len(m, r), sp = 0;
        for (size_t i = 0; i <= n && n > 0; i++) {
            uint32_t x = v[i % n];
            if (p->pos[x] >= 0) { /* a loop closes at x: stack[pos[x]] .. top */
                size_t from = (size_t)p->pos[x];
                if (sp - from >= 3) {
                    memcpy(p->idx + p->nidx, p->stack + from, (sp - from) * sizeof *p->idx);
                    p->nidx += sp - from;
                    p->outer[p->n] = r == m->face_ring[f];
                    p->off[++p->n] = p->nidx;
                }
                for (size_t k = from; k < sp; k++) p->pos[p->stack[k]] = -1;
                sp = from;
            }
            if (i < n) {
                p->pos[x] = (int32_t)sp;
                p->stack[sp++] = x;
            }
        }
        for (size_t k = 0; k < sp; k++) p->pos[p->stack[k]] = -1;
    }
}

static double cycle_area2(const api_result *m, const uint32_t *v, size_t n)
{
    const double *o = m->V + 2 * (size_t)v[0];
    long double s = 0;
    for (size_t i = 0; i < n; i++) {
        const double *a = m->V + 2 * (size_t)v[i], *c = m->V + 2 * (size_t)v[(i + 1) % n];
        s += ((long double)a[0] - o[0]) * ((long double)c[1] - o[1]) -
             ((long double)c[0] - o[0]) * ((long double)a[1] - o[1]);
    }
    return (double)s;
}

/* Face f as a Polygon Feature (pieces: pieces_of_face(f) done). */
static void geojson_face(api_buf *b, const api_result *m, const vtext *vt, size_t f,
                         const pieces *p)
{
    size_t shell = SIZE_MAX;
    double best = 0;
    for (size_t k = 0; k < p->n; k++) { /* the outer walk's largest counter-clockwise piece */
        double a = p->outer[k] ? cycle_area2(m, p->idx + p->off[k], p->off[k + 1] - p->off[k]) : 0;
        if (a > best) best = a, shell = k;
    }
    api_buf_puts(b, "{\"type\":\"Feature\",\"geometry\":{\"type\":\"Polygon\","
                    "\"coordinates\":[");
    for (size_t t = 0; t <= p->n && shell != SIZE_MAX; t++) {
        size_t k = t == 0 ? shell : t - 1;
        if (t > 0 && k == shell) continue;
        if (t > 0) api_buf_putc(b, ',');
        geojson_cycle(b, vt, p->idx + p->off[k], p->off[k + 1] - p->off[k]);
    }
    api_buf_puts(b, "]},\"properties\":{\"face\":");
    api_buf_u64(b, f);
    api_buf_puts(b, ",\"area\":");
    api_buf_double(b, face_area(m, f));
    if (m->has_result) {
        api_buf_puts(b, m->selected[f] ? ",\"selected\":true" : ",\"selected\":false");
        if (m->mem_off) {
            api_buf_puts(b, ",\"membership\":");
            api_buf_u32_list(b, m->mem + m->mem_off[f], m->mem_off[f + 1] - m->mem_off[f]);
        }
    }
    api_buf_puts(b, "}}");
}

/* ---- a layers request's result: the pieces with their parents' properties ------------------
 *
 * As a GIS overlay gives it: one Feature per piece of the result (the result cut where the
 * inputs it lies in change: "result".pieces) and per choice of one parent in each layer the
 * piece lies in (a piece in two overlapping features of one layer is written once with each, as
 * GIS tools do; in none of a layer: that layer's properties are absent).  Properties: "area",
 * then per layer L its parent's index in L ("L": k, or null) and the parent's own properties
 * as "L.key".  The pieces' rings index V; every index and the layers' table are checked. */

#define RENDER_MAX_FEATURES 2000000 /* pieces times parent choices */

typedef struct lay {
    size_t n;
    const char **name;
    size_t *first; /* n + 1 */
    const json_t **props;
} lay;

static int lay_read(const json_t *root, size_t ninputs, lay *L, api_error *err)
{
    const json_t *ls = json_object_get(root, "layers");
    size_t n = json_array_size(ls);
    *L = (lay){0};
    if (!json_is_array(ls) || n == 0)
        return api_fail(err, API_EINVALID, "layers: expected an array of {name, first, count}");
    L->name = calloc(n, sizeof *L->name);
    L->first = calloc(n + 1, sizeof *L->first);
    L->props = calloc(n, sizeof *L->props);
    if (!L->name || !L->first || !L->props) return API_ENOMEM;
    L->n = n;
    for (size_t k = 0; k < n; k++) {
        const json_t *x = json_array_get(ls, k);
        const json_t *f = json_object_get(x, "first"), *c = json_object_get(x, "count");
        const json_t *pr = json_object_get(x, "properties");
        L->name[k] = json_string_value(json_object_get(x, "name"));
        if (!L->name[k] || !json_is_integer(f) || !json_is_integer(c) ||
            (size_t)json_integer_value(f) != L->first[k] || json_integer_value(c) < 0 ||
            (pr && (!json_is_array(pr) || json_array_size(pr) != (size_t)json_integer_value(c))))
            return api_fail(err, API_EINVALID,
                            "layers[%zu]: expected {\"name\", \"first\": %zu, \"count\", "
                            "\"properties\": [count values]}",
                            k, L->first[k]);
        L->first[k + 1] = L->first[k] + (size_t)json_integer_value(c);
        L->props[k] = pr;
    }
    if (L->first[n] != ninputs)
        return api_fail(err, API_EINVALID, "layers: they hold %zu inputs, membership %zu",
                        L->first[n], ninputs);
    return API_OK;
}

static void lay_free(lay *L)
{
    free(L->name);
    free(L->first);
    free(L->props);
}

/* The cycle row (indices < nv, 3 or more) into idx; 0, or -1 when it is not one. */
static int piece_cycle(const json_t *row, size_t nv, uint32_t *idx, size_t *n)
{
    *n = json_array_size(row);
    if (!json_is_array(row) || *n < 3) return -1;
    for (size_t i = 0; i < *n; i++) {
        const json_t *x = json_array_get(row, i);
        if (!json_is_integer(x) || json_integer_value(x) < 0 ||
            (uint64_t)json_integer_value(x) >= nv)
            return -1;
        idx[i] = (uint32_t)json_integer_value(x);
    }
    return 0;
}

/* The properties of one Feature: its area, and per layer the chosen parent (choice[k], or
 * SIZE_MAX: none) with its properties. */
static int piece_props(api_buf *b, const lay *L, const size_t *choice, double area)
{
    json_t *o = json_object();
    int bad = !o || json_object_set_new(o, "area", json_real(area));
    for (size_t k = 0; k < L->n && !bad; k++) {
        size_t p = choice[k];
        bad = json_object_set_new(o, L->name[k],
                                  p == SIZE_MAX ? json_null() : json_integer((json_int_t)p));
        const json_t *pr = p == SIZE_MAX ? NULL : json_array_get(L->props[k], p);
        const char *key;
        json_t *v;
        json_object_foreach((json_t *)pr, key, v)
        {
            char name[512];
            snprintf(name, sizeof name, "%s.%s", L->name[k], key);
            if (json_object_set(o, name, v)) bad = 1;
        }
    }
    char *t = bad ? NULL : json_dumps(o, JSON_COMPACT | JSON_REAL_PRECISION(17));
    json_decref(o);
    if (!t) return API_ENOMEM;
    api_buf_puts(b, t);
    free(t);
    return API_OK;
}

/* A layers result's "result".pieces: the polygons (FV, holes) and the piece of each (piece),
 * the inputs each piece lies in (inputs, CSR); np polygons, nk pieces. */
typedef struct lpieces {
    const json_t *FV, *holes, *piece, *ip, *ix;
    size_t np, nk;
    size_t most; /* the longest ring */
} lpieces;

/* The polygon q's rings: its shell (h 0), then its holes (h 1 ..). */
static const json_t *lp_holes(const lpieces *lp, size_t q)
{
    char key[24];
    snprintf(key, sizeof key, "%zu", q);
    return json_object_get(lp->holes, key);
}

/* "result".pieces of m read into *lp and checked: its members there, the inputs' offsets
 * non-decreasing from 0 to their end, every input < m->ninputs, every polygon's piece < nk
 * (the rings are checked as they are written: layer_geometry()). */
static int lp_read(lpieces *lp, const api_result *m, api_error *err)
{
    const json_t *pc = json_object_get(json_object_get(m->root, "result"), "pieces");
    const json_t *in = json_object_get(pc, "inputs");
    *lp = (lpieces){.FV = json_object_get(pc, "FV"),
                    .holes = json_object_get(pc, "holes"),
                    .piece = json_object_get(pc, "piece"),
                    .ip = json_object_get(in, "indptr"),
                    .ix = json_object_get(in, "indices")};
    lp->np = json_array_size(lp->FV);
    lp->nk = json_array_size(lp->ip) ? json_array_size(lp->ip) - 1 : 0;
    if (!json_is_array(lp->FV) || !json_is_object(lp->holes) ||
        json_array_size(lp->piece) != lp->np || !json_is_array(lp->ip) || !json_is_array(lp->ix))
        return api_fail(err, API_EINVALID,
                        "result.pieces: required with \"layers\": {\"FV\", \"holes\", "
                        "\"piece\", \"inputs\"}");
    size_t nix = json_array_size(lp->ix);
    for (size_t k = 0; k <= lp->nk; k++) { /* the pieces' rows: offsets, inputs ascending */
        const json_t *x = json_array_get(lp->ip, k);
        json_int_t v = json_integer_value(x);
        if (!json_is_integer(x) || v < 0 || (size_t)v > nix || (k == 0 && v != 0) ||
            (k == lp->nk && (size_t)v != nix) ||
            (k > 0 && v < json_integer_value(json_array_get(lp->ip, k - 1))))
            return api_fail(err, API_EINVALID, "result.pieces.inputs.indptr[%zu]: bad offset", k);
    }
    for (size_t i = 0; i < nix; i++) {
        const json_t *x = json_array_get(lp->ix, i);
        if (!json_is_integer(x) || json_integer_value(x) < 0 ||
            (size_t)json_integer_value(x) >= m->ninputs)
            return api_fail(err, API_EINVALID,
                            "result.pieces.inputs.indices[%zu]: expected an input < %zu", i,
                            m->ninputs);
    }
    for (size_t q = 0; q < lp->np; q++) {
        const json_t *x = json_array_get(lp->piece, q), *hs;
        if (!json_is_integer(x) || json_integer_value(x) < 0 ||
            (size_t)json_integer_value(x) >= lp->nk)
            return api_fail(err, API_EINVALID, "result.pieces.piece[%zu]: expected a piece < %zu",
                            q, lp->nk);
        size_t n = json_array_size(json_array_get(lp->FV, q));
        if (n > lp->most) lp->most = n;
        hs = lp_holes(lp, q);
        for (size_t h = 0; h < json_array_size(hs); h++)
            if (json_array_size(json_array_get(hs, h)) > lp->most)
                lp->most = json_array_size(json_array_get(hs, h));
    }
    return API_OK;
}

/* The geometry of piece k, its polygons plist[poff[k] .. poff[k+1]), as a MultiPolygon into
 * g, twice its area into *area2 (idx: room for the longest ring); API_EINVALID for a ring that
 * is not a cycle of 3 or more vertex indices. */
static int layer_geometry(api_buf *g, const lpieces *lp, const api_result *m, const vtext *vt,
                          const size_t *poff, const size_t *plist, size_t k, uint32_t *idx,
                          double *area2, api_error *err)
{
    *area2 = 0;
    api_buf_puts(g, "{\"type\":\"MultiPolygon\",\"coordinates\":[");
    for (size_t i = poff[k]; i < poff[k + 1]; i++) {
        size_t q = plist[i], n;
        const json_t *hs = lp_holes(lp, q);
        api_buf_puts(g, i > poff[k] ? ",[" : "[");
        for (size_t h = 0; h <= json_array_size(hs); h++) {
            const json_t *row = h ? json_array_get(hs, h - 1) : json_array_get(lp->FV, q);
            if (piece_cycle(row, m->nv, idx, &n))
                return api_fail(err, API_EINVALID,
                                "result.pieces.%s[%zu]: expected a cycle of vertex indices < "
                                "%zu",
                                h ? "holes" : "FV", q, m->nv);
            if (h) api_buf_putc(g, ',');
            geojson_cycle(g, vt, idx, n);
            *area2 += cycle_area2(m, idx, n);
        }
        api_buf_putc(g, ']');
    }
    api_buf_puts(g, "]}");
    return API_OK;
}

/* The Features of piece k (its geometry g, its area): one per choice of one parent in each
 * layer its inputs fall in (none where they fall in none), the choices counted in *nfeat
 * (at most RENDER_MAX_FEATURES); lo, hi, choice: room for L->n.  API_ENOMEM bare. */
static int layer_features(api_buf *b, const lpieces *lp, const lay *L, size_t k, const api_buf *g,
                          double area, size_t *lo, size_t *hi, size_t *choice, size_t *nfeat,
                          int *any, api_error *err)
{
    /* its parents per layer: the inputs of its row within each layer's range */
    size_t a = (size_t)json_integer_value(json_array_get(lp->ip, k));
    size_t z = (size_t)json_integer_value(json_array_get(lp->ip, k + 1));
    size_t at[64] = {0};
    for (size_t l = 0; l < L->n; l++) {
        lo[l] = a;
        while (lo[l] < z && (size_t)json_integer_value(json_array_get(lp->ix, lo[l])) < L->first[l])
            lo[l]++;
        hi[l] = lo[l];
        while (hi[l] < z &&
               (size_t)json_integer_value(json_array_get(lp->ix, hi[l])) < L->first[l + 1])
            hi[l]++;
    }
    if (L->n > 64) return api_fail(err, API_EINVALID, "layers: more than 64");
    for (;;) { /* every choice of one parent per layer, as an odometer */
        for (size_t l = 0; l < L->n; l++)
            choice[l] = lo[l] == hi[l]
                            ? SIZE_MAX
                            : (size_t)json_integer_value(json_array_get(lp->ix, lo[l] + at[l])) -
                                  L->first[l];
        if (++*nfeat > RENDER_MAX_FEATURES)
            return api_fail(err, API_EINVALID, "result: more than %d pieces and parents to write",
                            RENDER_MAX_FEATURES);
        if (*any) api_buf_putc(b, ',');
        *any = 1;
        api_buf_puts(b, "{\"type\":\"Feature\",\"geometry\":");
        api_buf_put(b, g->p, g->len);
        api_buf_puts(b, ",\"properties\":");
        if (piece_props(b, L, choice, area) != API_OK) return API_ENOMEM;
        api_buf_putc(b, '}');
        size_t l = 0;
        for (; l < L->n; l++) {
            if (lo[l] + at[l] + 1 < hi[l]) {
                at[l]++;
                break;
            }
            at[l] = 0;
        }
        if (l == L->n) return API_OK;
    }
}

/* A layers result's Features (the section's comment above): per piece its geometry once, then
 * a Feature per choice of parents. */
static int geojson_layers(api_buf *b, const api_result *m, const vtext *vt, int *any,
                          api_error *err)
{
    lpieces lp;
    lay L;
    size_t *poff = NULL, *plist = NULL, *choice = NULL, *lo = NULL, *hi = NULL, nfeat = 0;
    uint32_t *idx = NULL;
    int rc = lay_read(m->root, m->ninputs, &L, err);
    if (rc == API_OK) rc = lp_read(&lp, m, err);
    if (rc != API_OK) goto done;
    /* the polygons of each piece, in order (CSR) */
    poff = calloc(lp.nk + 2, sizeof *poff);
    plist = malloc((lp.np + 1) * sizeof *plist);
    idx = malloc((lp.most + 1) * sizeof *idx);
    choice = malloc((L.n + 1) * sizeof *choice);
    lo = malloc((L.n + 1) * sizeof *lo);
    hi = malloc((L.n + 1) * sizeof *hi);
    if (!poff || !plist || !idx || !choice || !lo || !hi) {
        rc = API_ENOMEM;
        goto done;
    }
    for (size_t q = 0; q < lp.np; q++) poff[json_integer_value(json_array_get(lp.piece, q)) + 2]++;
    for (size_t k = 0; k < lp.nk; k++) poff[k + 2] += poff[k + 1];
    for (size_t q = 0; q < lp.np; q++)
        plist[poff[json_integer_value(json_array_get(lp.piece, q)) + 1]++] = q;
    for (size_t k = 0; k < lp.nk && rc == API_OK; k++) {
        api_buf g = {0};
        double area2;
        rc = layer_geometry(&g, &lp, m, vt, poff, plist, k, idx, &area2, err);
        if (rc == API_OK && g.failed) rc = API_ENOMEM;
        if (rc == API_OK)
            rc = layer_features(b, &lp, &L, k, &g, area2 / 2, lo, hi, choice, &nfeat, any, err);
        api_buf_free(&g);
    }
done:
    free(poff);
    free(plist);
    free(idx);
    free(choice);
    free(lo);
    free(hi);
    lay_free(&L);
    if (rc == API_ENOMEM) rc = api_fail(err, API_ENOMEM, "out of memory writing the GeoJSON");
    return rc;
}

/* A Boolean's result region as one MultiPolygon Feature (its rings' edges added to keys). */
static void geojson_result(api_buf *b, const api_result *m, const vtext *vt, uint64_t *keys,
                           size_t *nkeys)
{
    api_buf_puts(b, "{\"type\":\"Feature\",\"geometry\":{\"type\":\"MultiPolygon\","
                    "\"coordinates\":[");
    for (size_t q = 0; q < m->npoly; q++) {
        api_buf_puts(b, q ? ",[" : "[");
        for (size_t r = m->poly_ring[q]; r < m->poly_ring[q + 1]; r++) {
            const uint32_t *v = ring_idx(m, r);
            size_t n = ring_len(m, r);
            if (r > m->poly_ring[q]) api_buf_putc(b, ',');
            geojson_ring(b, m, vt, r);
            for (size_t i = 0; i < n; i++) keys[(*nkeys)++] = edge_key(v[i], v[(i + 1) % n]);
        }
        api_buf_putc(b, ']');
    }
    api_buf_puts(b, "]},\"properties\":{\"result\":true,\"area\":");
    api_buf_double(b, m->res_area);
    api_buf_puts(b, "}}");
}

/* The edges on no ring (keys: the rings' edges, nkeys of them, sorted here) as LineString
 * Features: dangling edges (kept on request), also those inside a face; API_ENOMEM. */
static int geojson_dangling(api_buf *b, const api_result *m, const vtext *vt, uint64_t *keys,
                            size_t nkeys, int *any)
{
    if (sort_u64(keys, nkeys)) return API_ENOMEM;
    for (size_t e = 0; e < m->ne; e++) {
        if (has_key(keys, nkeys, edge_key(m->ev[2 * e], m->ev[2 * e + 1]))) continue;
        if (*any) api_buf_putc(b, ',');
        *any = 1;
        api_buf_puts(b, "{\"type\":\"Feature\",\"geometry\":{\"type\":\"LineString\","
                        "\"coordinates\":[[");
        vtext_put(b, vt, m->ev[2 * e]);
        api_buf_puts(b, "],[");
        vtext_put(b, vt, m->ev[2 * e + 1]);
        api_buf_puts(b, "]]},\"properties\":{\"edge\":");
        api_buf_u64(b, e);
        api_buf_puts(b, ",\"dangling\":true}}");
    }
    return API_OK;
}

int render_geojson(const char *result_json, size_t len, const render_opts *o, char **out,
                   size_t *outlen, api_error *err)
{
    render_opts def = RENDER_OPTS_INIT;
    api_result m;
    api_buf b = {0};
    vtext vt;
    pieces pc;
    uint64_t *keys = NULL;
    size_t nkeys = 0;
    int rc, any = 0;
    *out = NULL;
    *outlen = 0;
    if (!o) o = &def;
    rc = api_result_read(result_json, len, 2, "only 2D results are drawn", &m, err);
    if (rc != API_OK) return rc;
    if (vtext_make(&m, 0, ',', &vt) != API_OK) {
        api_result_free(&m);
        return api_fail(err, API_ENOMEM, "out of memory writing the GeoJSON");
    }
    keys = malloc((m.ring_off[m.nrings] + 1) * sizeof *keys);
    if (pieces_init(&pc, &m) != API_OK || !keys) {
        rc = api_fail(err, API_ENOMEM, "out of memory writing the GeoJSON");
        goto done;
    }
    if (m.has_result && o->cells && !m.mem_off) {
        rc = api_fail(err, API_EINVALID,
                      "membership: required for cells=all (the result has no \"membership\")");
        goto done;
    }
    for (size_t f = 0; f < m.nf; f++) /* each face's area is written: it must be a number */
        if (!isfinite(face_area(&m, f))) {
            rc = api_fail(err, API_EINVALID,
                          "FV[%zu]: the face's area is beyond a double (coordinates too large)", f);
            goto done;
        }
    api_buf_puts(&b, "{\"type\":\"FeatureCollection\",\"features\":[");
    if (m.has_result && m.root) { /* a layers request's: the pieces with their parents */
        if (!m.mem_off) {
            rc = api_fail(err, API_EINVALID,
                          "membership: required with \"layers\" (the result was made with "
                          "\"fields\" leaving it out)");
            goto done;
        }
        rc = geojson_layers(&b, &m, &vt, &any, err);
        if (rc != API_OK) goto done;
    } else if (m.has_result) {
        geojson_result(&b, &m, &vt, keys, &nkeys);
        any = 1;
    }
    for (size_t f = 0; f < m.nf; f++) {
        pieces_of_face(&pc, &m, f);
        for (size_t k = 0; k < pc.n; k++) {
            const uint32_t *v = pc.idx + pc.off[k];
            size_t n = pc.off[k + 1] - pc.off[k];
            for (size_t i = 0; i < n; i++) keys[nkeys++] = edge_key(v[i], v[(i + 1) % n]);
        }
        if (m.has_result && !o->cells) continue;
        if (any) api_buf_putc(&b, ',');
        any = 1;
        geojson_face(&b, &m, &vt, f, &pc);
    }
    if (geojson_dangling(&b, &m, &vt, keys, nkeys, &any) != API_OK) {
        rc = api_fail(err, API_ENOMEM, "out of memory writing the GeoJSON");
        goto done;
    }
    api_buf_puts(&b, "]}\n");
done:
    free(keys);
    pieces_free(&pc);
    vtext_free(&vt);
    api_result_free(&m);
    return finish(&b, rc, out, outlen, err);
}
