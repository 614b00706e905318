/* packed.c — see packed.h. */
#include "api/packed.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api/api_int.h"
#include "core/fastfloat.h"
#include "core/mem.h"

static atomic_int enabled = 1;

void api_packed_enable(int on)
{
    atomic_store(&enabled, on != 0);
}

int api_packed_enabled(void)
{
    return atomic_load(&enabled);
}

/* ---- the scan ----------------------------------------------------------------------------- */

typedef struct scan {
    const char *p, *end;
    api_packed_set *set;
} scan;

typedef struct span {
    size_t at, len; /* in the body */
} span;

static int is_ws(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

static void ws(scan *s)
{
    while (s->p < s->end && is_ws(*s->p)) s->p++;
}

/* Skips a string (s->p at its opening quote); its raw bytes (without quotes) in *k, *kn.  0, or
 * -1 when it does not end. */
static int skip_string(scan *s, const char **k, size_t *kn)
{
    const char *q = s->p + 1;
    while (q < s->end && *q != '"') q += *q == '\\' ? 2 : 1;
    if (q >= s->end) return -1;
    if (k) *k = s->p + 1, *kn = (size_t)(q - s->p - 1);
    s->p = q + 1;
    return 0;
}

/* Skips any value, counting brackets (jansson checks what is skipped).  0, or -1 at the end. */
static int skip_value(scan *s)
{
    int depth = 0;
    do {
        ws(s);
        if (s->p >= s->end) return -1;
        char c = *s->p;
        if (c == '"') {
            if (skip_string(s, NULL, NULL)) return -1;
        } else if (c == '[' || c == '{') {
            depth++, s->p++;
        } else if (c == ']' || c == '}') {
            if (--depth < 0) return -1;
            s->p++;
        } else if (c == ',' || c == ':') {
            if (depth == 0) return -1;
            s->p++;
        } else {
            while (s->p < s->end && !is_ws(*s->p) && *s->p != ',' && *s->p != ']' && *s->p != '}' &&
                   *s->p != ':' && *s->p != '"' && *s->p != '[' && *s->p != '{')
                s->p++;
        }
    } while (depth > 0);
    return 0;
}

/* Expects c (after blanks): 0, or -1. */
static int expect(scan *s, char c)
{
    ws(s);
    if (s->p >= s->end || *s->p != c) return -1;
    s->p++;
    return 0;
}

/* After an element: 1 at ',' (taken), 0 at ']' (taken), -1 else. */
static int next_elem(scan *s)
{
    ws(s);
    if (s->p < s->end && *s->p == ',') return s->p++, 1;
    if (s->p < s->end && *s->p == ']') return s->p++, 0;
    return -1;
}

/* One number at s->p (after blanks) into *x; *integer when written as one.  0, or -1 when it is
 * not one the fast reader takes. */
static int read_number(scan *s, double *x, int *integer)
{
    const char *e;
    size_t digits;
    ws(s);
    /* not finite: jansson's overflow error, or another message; an integer of more than 15
     * digits: jansson's int64, exactly a double only below 10^15 */
    if (ff_json_number(s->p, s->end, x, integer, &digits, &e) || (*integer && digits > 15))
        return -1;
    if (e < s->end && !is_ws(*e) && *e != ',' && *e != ']') return -1; /* not a separator */
    if (*integer) *x += 0.0; /* jansson reads "-0" as the integer 0 */
    s->p = e;
    return 0;
}

/* The rows of a (API_PACKED_V: [[x, y, z], ...]; API_PACKED_SEGMENTS: [[[x1, y1], [x2, y2]],
 * ...]) at s->p: 0, -1 (not taken), -2 out of memory. */
static int read_rows(scan *s, api_packed *a)
{
    size_t capv = 0, capi = 0; /* doubles, rows */
    int seg = a->fv == API_PACKED_SEGMENTS, per = seg ? 4 : 3;
    if (expect(s, '[')) return -1;
    ws(s);
    if (s->p < s->end && *s->p == ']') return s->p++, 0;
    for (;;) {
        if (expect(s, '[')) return -1;
        if (mem_grow(&a->V, &capv, (size_t)per * (a->n + 1), sizeof *a->V) ||
            mem_grow(&a->vint, &capi, a->n + 1, 1))
            return -2;
        uint8_t flags = 0;
        for (int k = 0; k < per; k++) {
            int integer;
            if (seg && k % 2 == 0 && ((k && expect(s, ',')) || expect(s, '['))) return -1;
            if ((seg ? k % 2 : k) && expect(s, ',')) return -1;
            if (read_number(s, &a->V[(size_t)per * a->n + (size_t)k], &integer)) return -1;
            flags |= (uint8_t)((unsigned)integer << k);
            if (seg && k % 2 == 1 && expect(s, ']')) return -1;
        }
        if (expect(s, ']')) return -1;
        a->vint[a->n++] = flags;
        int r = next_elem(s);
        if (r < 0) return -1;
        if (r == 0) return 0;
    }
}

/* [[v, ...], ...] at s->p into a: 0, -1 (not taken), -2 out of memory. */
static int read_FV(scan *s, api_packed *a)
{
    size_t capo = 0, capi = 0, ni = 0;
    if (mem_grow(&a->off, &capo, 1, sizeof *a->off)) return -2;
    a->off[0] = 0;
    if (expect(s, '[')) return -1;
    ws(s);
    if (s->p < s->end && *s->p == ']') return s->p++, 0;
    for (;;) {
        if (expect(s, '[')) return -1;
        ws(s);
        if (s->p < s->end && *s->p == ']') return -1; /* an empty cycle: the message is jansson's */
        for (;;) {
            ws(s);
            const char *q = s->p;
            uint64_t v = 0;
            if (q >= s->end || *q < '0' || *q > '9' ||
                (*q == '0' && q + 1 < s->end && q[1] >= '0' && q[1] <= '9'))
                return -1;
            while (q < s->end && *q >= '0' && *q <= '9' && v < ((uint64_t)1 << 32))
                v = v * 10 + (uint64_t)(*q++ - '0');
            if (v >= ((uint64_t)1 << 32) || (q < s->end && !is_ws(*q) && *q != ',' && *q != ']'))
                return -1;
            if (ni >= UINT32_MAX) return -1;
            if (mem_grow(&a->idx, &capi, ni + 1, sizeof *a->idx)) return -2;
            a->idx[ni++] = (uint32_t)v;
            s->p = q;
            int r = next_elem(s);
            if (r < 0) return -1;
            if (r == 0) break;
        }
        if (mem_grow(&a->off, &capo, a->n + 2, sizeof *a->off)) return -2;
        a->off[++a->n] = (uint32_t)ni;
        int r = next_elem(s);
        if (r < 0) return -1;
        if (r == 0) return 0;
    }
}

/* [[[[x, y], ...], ...], ...] at s->p (polygons of rings of points, the native form only: an
 * element that is not an array, a GeoJSON object or a WKT string, gives up) into a: 0, -1 (not
 * taken), -2 out of memory.  a->V the points, a->off the rings' offsets into them, a->idx the
 * polygons' offsets into the rings.  single: the array at s->p is one polygon's rings
 * [[[x, y], ...], ...] (a GeoJSON Polygon's coordinates). */
static int read_rings(scan *s, api_packed *a, int single)
{
    size_t capv = 0, capi = 0, capo = 0, capp = 0, nr = 0, np = 0;
    if (mem_grow(&a->off, &capo, 1, sizeof *a->off) || mem_grow(&a->idx, &capp, 1, sizeof *a->idx))
        return -2;
    a->off[0] = a->idx[0] = 0;
    if (!single) {
        if (expect(s, '[')) return -1;
        ws(s);
        if (s->p < s->end && *s->p == ']') return s->p++, 0;
    }
    for (;;) { /* a polygon (single: the only one, the array at s->p) */
        if (expect(s, '[')) return -1;
        ws(s);
        if (s->p < s->end && *s->p == ']') return -1; /* no ring: jansson's message */
        for (;;) {                                    /* a ring */
            if (expect(s, '[')) return -1;
            for (;;) { /* a point */
                if (expect(s, '[')) return -1;
                if (mem_grow(&a->V, &capv, 2 * (a->n + 1), sizeof *a->V) ||
                    mem_grow(&a->vint, &capi, a->n + 1, 1))
                    return -2;
                int i0, i1;
                if (read_number(s, &a->V[2 * a->n], &i0) || expect(s, ',') ||
                    read_number(s, &a->V[2 * a->n + 1], &i1) || expect(s, ']'))
                    return -1;
                a->vint[a->n++] = (uint8_t)(i0 | i1 << 1);
                if (a->n >= UINT32_MAX) return -1;
                int r = next_elem(s);
                if (r < 0) return -1;
                if (r == 0) break;
            }
            if (mem_grow(&a->off, &capo, nr + 2, sizeof *a->off)) return -2;
            a->off[++nr] = (uint32_t)a->n;
            int r = next_elem(s);
            if (r < 0) return -1;
            if (r == 0) break;
        }
        if (mem_grow(&a->idx, &capp, np + 2, sizeof *a->idx)) return -2;
        a->idx[++np] = (uint32_t)nr;
        if (single) break;
        int r = next_elem(s);
        if (r < 0) return -1;
        if (r == 0) break;
    }
    a->nrings = nr, a->npoly = np;
    return 0;
}

/* A GeoJSON geometry's "coordinates" at s->p: a Polygon's rings (a->solid = 3) or a
 * MultiPolygon's polygons (a->solid = 4), told by how deep the first position lies; positions
 * of 2 numbers only (others, and empty arrays, give up: jansson reads them). */
static int read_coords(scan *s, api_packed *a)
{
    const char *q = s->p;
    int depth = 0;
    for (;;) {
        while (q < s->end && is_ws(*q)) q++;
        if (q >= s->end || *q != '[') break;
        depth++, q++;
    }
    if (depth != 3 && depth != 4) return -1;
    a->solid = (size_t)depth;
    return read_rings(s, a, depth == 3);
}

static void packed_release(api_packed *a)
{
    if (!a->taken) {
        free(a->V);
        free(a->off);
        free(a->idx);
    }
    free(a->vint);
    memset(a, 0, sizeof *a);
}

typedef struct spans {
    span *v;
    size_t n, cap;
} spans;

/* The array at s->p, of solid `sol` (0 for a request's lines or polygons) and of the kind of
 * api_packed.fv: read into a new entry of the set, its place in the body listed in out.  0, -1
 * (give up), -2 out of memory. */
static int take_array(scan *s, const char *body, size_t sol, int kind, spans *out)
{
    api_packed_set *set = s->set;
    if (mem_grow(&set->a, &set->cap, set->n + 1, sizeof *set->a) ||
        mem_grow(&out->v, &out->cap, out->n + 1, sizeof *out->v))
        return -2;
    api_packed *a = &set->a[set->n];
    memset(a, 0, sizeof *a);
    a->solid = sol, a->fv = kind;
    const char *at = s->p;
    int r = kind == API_PACKED_FV       ? read_FV(s, a)
            : kind == API_PACKED_RINGS  ? read_rings(s, a, 0)
            : kind == API_PACKED_COORDS ? read_coords(s, a)
                                        : read_rows(s, a);
    if (r) {
        packed_release(a);
        return r;
    }
    set->n++;
    out->v[out->n++] = (span){(size_t)(at - body), (size_t)(s->p - at)};
    return 0;
}

/* Where the members' readers put what they take: the body, the solid's index, the spans. */
typedef struct walk {
    const char *body;
    size_t sol;
    spans *out;
    int depth; /* of a GeoJSON object (a Feature's geometry is 1) */
} walk;

/* The object at s->p (after blanks): member(s, key, its length, w) for each member, with s->p at
 * its value (after blanks), which it reads or skips.  0; -1 when it is not an object or is
 * malformed; or member's non-zero answer (-1, -2). */
static int members(scan *s, int (*member)(scan *, const char *, size_t, walk *), walk *w)
{
    if (expect(s, '{')) return -1;
    ws(s);
    if (s->p < s->end && *s->p == '}') return s->p++, 0;
    for (;;) {
        ws(s);
        const char *k;
        size_t kn;
        if (s->p >= s->end || *s->p != '"' || skip_string(s, &k, &kn) || expect(s, ':')) return -1;
        ws(s);
        int r = member(s, k, kn, w);
        if (r) return r;
        ws(s);
        if (s->p < s->end && *s->p == ',') {
            s->p++;
            continue;
        }
        return expect(s, '}');
    }
}

static int at(const scan *s, char c)
{
    return s->p < s->end && *s->p == c;
}

/* A solid's member: V and FV read, the rest skipped. */
static int solid_member(scan *s, const char *k, size_t kn, walk *w)
{
    int kind = kn == 2 && !memcmp(k, "FV", 2) ? API_PACKED_FV
               : kn == 1 && *k == 'V'         ? API_PACKED_V
                                              : -1;
    return kind >= 0 && at(s, '[') ? take_array(s, w->body, w->sol, kind, w->out) : skip_value(s);
}

/* The object at s->p as a solid (index sol): its V and FV read (other keys skipped; a value
 * that is not an object skipped too).  0, -1, -2. */
static int solid_obj(scan *s, const char *body, size_t sol, spans *out)
{
    walk w = {body, sol, out, 0};
    ws(s);
    return at(s, '{') ? members(s, solid_member, &w) : skip_value(s);
}

static int geo_obj(scan *s, const char *body, spans *out, int depth);

/* A GeoJSON object's member: "coordinates" read, a Feature's "geometry" walked, the rest
 * skipped. */
static int geo_member(scan *s, const char *k, size_t kn, walk *w)
{
    if (kn == 11 && !memcmp(k, "coordinates", 11) && at(s, '['))
        return take_array(s, w->body, 0, API_PACKED_COORDS, w->out);
    if (kn == 8 && !memcmp(k, "geometry", 8) && at(s, '{'))
        return geo_obj(s, w->body, w->out, w->depth + 1);
    return skip_value(s);
}

/* A GeoJSON object among "polygons" (a geometry, or a Feature and its "geometry"): each
 * "coordinates" array read (other keys skipped).  0, -1, -2. */
static int geo_obj(scan *s, const char *body, spans *out, int depth)
{
    walk w = {body, 0, out, depth};
    return depth > 2 ? -1 : members(s, geo_member, &w);
}

static int geo_polygons(scan *s, const char *body, spans *out);

/* A FeatureCollection's member: its "features" walked, the rest skipped. */
static int collection_member(scan *s, const char *k, size_t kn, walk *w)
{
    return kn == 8 && !memcmp(k, "features", 8) && at(s, '[') ? geo_polygons(s, w->body, w->out)
                                                              : skip_value(s);
}

/* "polygons" that are GeoJSON: an array of geometries or Features (WKT strings among them
 * skipped: jansson reads them), or a FeatureCollection object.  0, -1, -2. */
static int geo_polygons(scan *s, const char *body, spans *out)
{
    walk w = {body, 0, out, 0};
    ws(s);
    if (at(s, '{')) return members(s, collection_member, &w); /* a FeatureCollection */
    if (expect(s, '[')) return -1;
    ws(s);
    if (at(s, ']')) return s->p++, 0;
    for (;;) {
        ws(s);
        int r = at(s, '"') ? skip_value(s) : geo_obj(s, body, out, 0);
        if (r) return r;
        int e = next_elem(s);
        if (e < 0) return -1;
        if (e == 0) return 0;
    }
}

static void set_free_arrays(api_packed_set *set)
{
    for (size_t i = 0; i < set->n; i++) packed_release(&set->a[i]);
    free(set->a);
    free(set->rest);
    memset(set, 0, sizeof *set);
}

void api_packed_free(api_packed_set *set)
{
    if (set) set_free_arrays(set);
}

/* The placeholder of array k: "\u0001#k" as JSON text (in *buf, its length returned). */
static size_t placeholder(size_t k, char *buf, size_t cap)
{
    int n = snprintf(buf, cap, "\"\\u0001#%zu\"", k);
    return n > 0 ? (size_t)n : 0;
}

int api_packed_scan(const char *body, size_t len, api_packed_set *set)
{
    memset(set, 0, sizeof *set);
    scan s = {body, body + len, set};
    spans sp = {0};
    int rc = 0;
    if (expect(&s, '{')) goto give_up;
    ws(&s);
    if (s.p < s.end && *s.p == '}') goto give_up;
    for (;;) {
        const char *k;
        size_t kn;
        ws(&s);
        if (s.p >= s.end || *s.p != '"' || skip_string(&s, &k, &kn) || expect(&s, ':'))
            goto give_up;
        ws(&s);
        int r = 0;
        if (kn == 6 && !memcmp(k, "solids", 6) && s.p < s.end && *s.p == '[') {
            s.p++;
            ws(&s);
            if (s.p < s.end && *s.p == ']') {
                s.p++;
            } else {
                for (size_t i = 0;; i++) {
                    r = solid_obj(&s, body, i, &sp);
                    if (r) break;
                    int e = next_elem(&s);
                    if (e < 0) r = -1;
                    if (e <= 0) break;
                }
            }
        } else if (kn == 5 && !memcmp(k, "faces", 5)) {
            r = solid_obj(&s, body, API_PACKED_FACES, &sp);
        } else if (kn == 5 && !memcmp(k, "lines", 5) && s.p < s.end && *s.p == '[') {
            r = take_array(&s, body, 0, API_PACKED_SEGMENTS, &sp);
        } else if (kn == 8 && !memcmp(k, "polygons", 8) && s.p < s.end && *s.p == '[') {
            const char *q = s.p + 1; /* native rings, or GeoJSON objects (and WKT strings) */
            while (q < s.end && is_ws(*q)) q++;
            r = q < s.end && (*q == '{' || *q == '"')
                    ? geo_polygons(&s, body, &sp)
                    : take_array(&s, body, 0, API_PACKED_RINGS, &sp);
        } else if (kn == 8 && !memcmp(k, "polygons", 8) && s.p < s.end && *s.p == '{') {
            r = geo_polygons(&s, body, &sp);
        } else if (kn == 4 && !memcmp(k, "kind", 4) && s.p < s.end && *s.p == '"') {
            const char *v;
            size_t vn;
            r = skip_string(&s, &v, &vn);
            if (!r && !(vn == 6 && !memcmp(v, "solids", 6)) &&
                !(vn == 5 && !memcmp(v, "lines", 5)) && !(vn == 8 && !memcmp(v, "polygons", 8)))
                goto give_up; /* another kind's */
        } else {
            r = skip_value(&s);
        }
        if (r == -2) goto oom;
        if (r) goto give_up;
        ws(&s);
        if (s.p < s.end && *s.p == ',') {
            s.p++;
            continue;
        }
        break;
    }
    if (sp.n == 0) goto give_up; /* nothing read: the ordinary path (jansson checks the end) */
    /* the rest: the body with each array's span replaced by its placeholder (spans ascend) */
    size_t restcap = len + 24 * sp.n + 1, w = 0, from = 0;
    set->rest = malloc(restcap);
    if (!set->rest) goto oom;
    for (size_t i = 0; i < sp.n; i++) {
        memcpy(set->rest + w, body + from, sp.v[i].at - from);
        w += sp.v[i].at - from;
        w += placeholder(i, set->rest + w, restcap - w);
        from = sp.v[i].at + sp.v[i].len;
    }
    memcpy(set->rest + w, body + from, len - from);
    w += len - from;
    set->rest[w] = 0;
    set->restlen = w;
    free(sp.v);
    return 1;
oom:
    rc = -1;
give_up:
    free(sp.v);
    set_free_arrays(set);
    return rc;
}

api_packed *api_packed_find(api_packed_set *set, size_t s, int fv, const char *str)
{
    if (!set || !str || str[0] != '\x01' || str[1] != '#') return NULL;
    char *e;
    unsigned long long k = strtoull(str + 2, &e, 10);
    if (*e || e == str + 2 || k >= set->n) return NULL;
    api_packed *a = &set->a[k];
    return a->solid == s && a->fv == fv ? a : NULL;
}

/* ---- the canonical form ------------------------------------------------------------------- */

typedef api_u128 u128;

/* round(x 10^s) for x = m 2^e, ties to even (printf's rule), into *d and floor(x 10^s) into *f,
 * when 128 bits hold the work: 1, else 0. */
static int scaled(uint64_t m, int e, int s, u128 *d, u128 *f)
{
    if (s >= 0) {
        if (s > 22) return 0; /* m 10^s below 2^128 */
        u128 n = (u128)m * api_pow10_u128(s);
        if (e >= 0) {
            if (e > 10 || n >> (127 - e)) return 0;
            *d = *f = n << e;
            return 1;
        }
        if (-e >= 127) return 0;
        u128 q = n >> -e, r = n & (((u128)1 << -e) - 1), half = (u128)1 << (-e - 1);
        *f = q;
        *d = q + (r > half || (r == half && (q & 1)));
        return 1;
    }
    if (e < 0 || e > 74 || -s > 38) return 0;
    u128 x = (u128)m << e, div = api_pow10_u128(-s), q = x / div, r = x % div;
    *f = q;
    *d = q + (2 * r > div || (2 * r == div && (q & 1)));
    return 1;
}

size_t api_g17(double x, char *buf)
{
    char *p = buf;
    if (!isfinite(x)) return 0;
    if (signbit(x)) *p++ = '-', x = -x;
    if (x == 0) {
        *p++ = '0';
        *p = 0;
        return (size_t)(p - buf);
    }
    if (!(x >= 1e-6 && x < 1e38)) return 0;
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits); /* x is normal here: x = m 2^e exactly */
    uint64_t m = (bits & (((uint64_t)1 << 52) - 1)) | (uint64_t)1 << 52;
    int e2 = (int)(bits >> 52 & 0x7ff) - 1022;                       /* 2^(e2 - 1) <= x < 2^e2 */
    int e = e2 - 53, E = (int)floor((e2 - 1) * 0.30102999566398120); /* log10 x, or one below */
    u128 d = 0, f = 0, lo = api_pow10_u128(16), hi = api_pow10_u128(17);
    for (int tries = 0;; tries++) { /* E: 10^16 <= x 10^(16 - E) < 10^17, before rounding */
        if (tries == 4 || !scaled(m, e, 16 - E, &d, &f)) return 0;
        if (f >= hi)
            E++;
        else if (f < lo)
            E--;
        else
            break;
    }
    if (d == hi) d = lo, E++; /* 99...9.5 rounds up to a digit more: printf's next exponent */
    return (size_t)(p - buf) + api_fmt_g((uint64_t)d, 17, E, p);
}

/* A real as jansson writes it with JSON_REAL_PRECISION(17): %.17g, ".0" when it has neither a
 * point nor an exponent, the exponent without '+' and leading zeros. */
static size_t real_text(double x, char *buf)
{
    size_t len = api_g17(x, buf);
    if (!len) {
        int n = snprintf(buf, 40, "%.17g", x);
        len = n > 0 ? (size_t)n : 0;
    }
    char *e = NULL;
    int point = 0;
    for (size_t i = 0; i < len; i++) {
        point |= buf[i] == '.';
        if (buf[i] == 'e') e = buf + i;
    }
    if (!point && !e) {
        memcpy(buf + len, ".0", 3);
        len += 2;
    }
    if (e) {
        char *start = e + 1, *end = e + 2;
        if (*start == '-') start++;
        while (*end == '0') end++;
        if (end != start) {
            memmove(start, end, len - (size_t)(end - buf) + 1);
            len -= (size_t)(end - start);
        }
    }
    return len;
}

/* A number as jansson wrote it: an integer as such (below 10^15 in magnitude: exact), a real by
 * real_text. */
static void put_number(api_buf *b, double x, int integer)
{
    char num[48];
    if (integer)
        api_buf_i64(b, (int64_t)x);
    else
        api_buf_put(b, num, real_text(x, num));
}

/* Polygons of rings of points (API_PACKED_RINGS) as jansson writes them compact. */
static void put_rings(api_buf *b, const api_packed *a, int single)
{
    if (!single) api_buf_putc(b, '[');
    for (size_t q = 0; q < a->npoly; q++) {
        api_buf_puts(b, q ? ",[" : "[");
        for (uint32_t k = a->idx[q]; k < a->idx[q + 1]; k++) {
            api_buf_puts(b, k > a->idx[q] ? ",[" : "[");
            for (uint32_t v = a->off[k]; v < a->off[k + 1]; v++) {
                api_buf_puts(b, v > a->off[k] ? ",[" : "[");
                put_number(b, a->V[2 * (size_t)v], a->vint[v] & 1);
                api_buf_putc(b, ',');
                put_number(b, a->V[2 * (size_t)v + 1], a->vint[v] >> 1 & 1);
                api_buf_putc(b, ']');
            }
            api_buf_putc(b, ']');
        }
        api_buf_putc(b, ']');
    }
    if (!single) api_buf_putc(b, ']');
}

/* Array a as jansson writes it compact: rows of V and segments with each number as it was
 * written, rows of FV as lists of indices, polygons by put_rings. */
static void put_array(api_buf *b, const api_packed *a)
{
    if (a->fv == API_PACKED_RINGS || a->fv == API_PACKED_COORDS) {
        put_rings(b, a, a->fv == API_PACKED_COORDS && a->solid == 3);
        return;
    }
    int seg = a->fv == API_PACKED_SEGMENTS, per = seg ? 4 : 3;
    api_buf_putc(b, '[');
    for (size_t r = 0; r < a->n; r++) {
        if (r) api_buf_putc(b, ',');
        if (a->fv == API_PACKED_FV) {
            api_buf_u32_list(b, a->idx + a->off[r], a->off[r + 1] - a->off[r]);
            continue;
        }
        api_buf_puts(b, seg ? "[[" : "[");
        for (int k = 0; k < per; k++) {
            if (k) api_buf_puts(b, seg && k == 2 ? "],[" : ",");
            put_number(b, a->V[(size_t)per * r + (size_t)k], a->vint[r] >> k & 1);
        }
        api_buf_puts(b, seg ? "]]" : "]");
    }
    api_buf_putc(b, ']');
}

char *api_packed_canon(const api_packed_set *set, const char *dump, size_t *outlen)
{
    api_buf b = {0};
    static const char mark[] = "\"\\u0001#";
    const char *p = dump;
    for (;;) {
        const char *q = strstr(p, mark);
        if (!q) break;
        const char *d = q + sizeof mark - 1;
        size_t k = 0;
        while (*d >= '0' && *d <= '9') k = k * 10 + (size_t)(*d++ - '0');
        if (*d != '"' || k >= set->n) { /* not one of ours: kept as it is */
            api_buf_put(&b, p, (size_t)(d - p));
            p = d;
            continue;
        }
        api_buf_put(&b, p, (size_t)(q - p));
        put_array(&b, &set->a[k]);
        p = d + 1;
    }
    api_buf_puts(&b, p);
    if (b.failed || !api_buf_reserve(&b, 0)) {
        api_buf_free(&b);
        return NULL;
    }
    b.p[b.len] = 0;
    if (outlen) *outlen = b.len;
    return b.p;
}
