/* packed.h — the big arrays of a "solids", "lines" or "polygons" request read straight from its
 * text (issue 24, item 4, and 27, item 2: requests at disk speed).
 *
 * A solid's "V" ([[x, y, z], ...]) and "FV" ([[v, ...], ...]) are most of a request's bytes;
 * read by jansson they cost a node, an allocation and a free per number (a request of 17 MB,
 * two solids of 160 000 triangles: 0.85 s around a core of 0.36 s).  api_packed_scan() walks
 * the request's text once, finds solids[i].V, solids[i].FV, faces.V, faces.FV, lines and polygons
 * (native rings, or the "coordinates" of GeoJSON geometries and Features, in an array or a
 * FeatureCollection; WKT strings are left to jansson), reads each
 * into flat arrays (numbers by the correctly rounded reader of core/fastfloat.h, tokens checked
 * against JSON's grammar) and gives the rest of the text with each such array replaced by a
 * placeholder string, for jansson to read as usual.
 *
 * Nothing is decided here that the ordinary path would decide otherwise: any array the fast
 * reader is not sure of (a token that is not a plain JSON number or index, a row of V that is
 * not 3 numbers, an integer of more than 15 digits, an index of 2^32 or more, a number beyond
 * the doubles) ends the scan without a result, and the caller reads the whole text with jansson
 * as before, so that every error keeps its message and its JSON path.  A placeholder is
 * "\u0001#k" (k the array's number here); a valid request holds no free text, so the placeholders
 * are the only strings that start with U+0001 there.
 *
 * api_packed_canon() writes the canonical form of such a request (jansson's compact, sorted form,
 * numbers as jansson writes them: integers as written, reals by %.17g) from the rest's dump and
 * the arrays: byte for byte what json_dumps of the whole tree gives.
 */
#ifndef CELLAR_PACKED_H
#define CELLAR_PACKED_H

#include <stddef.h>
#include <stdint.h>

#define API_PACKED_FACES ((size_t)-1) /* api_packed.solid of the arrays of "faces" */

/* What an array is (api_packed.fv) */
#define API_PACKED_V        0 /* a solid's V: rows [x, y, z] */
#define API_PACKED_FV       1 /* a solid's FV: rows of indices */
#define API_PACKED_SEGMENTS 2 /* a "lines" request's lines: rows [[x1, y1], [x2, y2]] */
#define API_PACKED_RINGS    3 /* a "polygons" request's polygons, each native [[[x, y], ...]] */
#define API_PACKED_COORDS                                                                          \
    4 /* a GeoJSON geometry's "coordinates" among "polygons": solid 3, a                           \
         Polygon's rings; solid 4, a MultiPolygon's polygons */

typedef struct api_packed {
    size_t solid;  /* index in "solids", or API_PACKED_FACES (0 for segments and rings) */
    int fv;        /* API_PACKED_V, _FV, _SEGMENTS or _RINGS */
    size_t n;      /* rows */
    double *V;     /* V: 3 n numbers; segments: 4 n (x1, y1, x2, y2) */
    uint8_t *vint; /* V, segments: by row, bit k set when number k was written as an integer */
    uint32_t *off; /* FV: n + 1 offsets into idx; rings: nrings + 1 offsets into the points */
    uint32_t *idx; /* FV: the indices; rings: npoly + 1 offsets into the rings */
    size_t nrings, npoly; /* rings: n is the points (V: 2 n numbers, vint: 2 bits a point) */
    int taken;            /* the arrays were handed over (api_packed_take): not freed here */
} api_packed;

typedef struct api_packed_set {
    api_packed *a;
    size_t n, cap;
    char *rest; /* the text with each array replaced by its placeholder (NUL-terminated) */
    size_t restlen;
} api_packed_set;

/* Scans body (len bytes): 1 when at least one array was read (*set filled: free it with
 * api_packed_free), 0 when none or when the fast reader gave up (the caller reads body with
 * jansson), -1 out of memory. */
int api_packed_scan(const char *body, size_t len, api_packed_set *set);
void api_packed_free(api_packed_set *set);

/* The array of solid s (or API_PACKED_FACES; 0 for segments and rings) and kind fv
 * (API_PACKED_V, ...) whose placeholder is str (a JSON string's value), or NULL.  Its taker sets
 * its `taken`. */
api_packed *api_packed_find(api_packed_set *set, size_t s, int fv, const char *str);

/* The canonical form of the request: dump is json_dumps(JSON_COMPACT | JSON_SORT_KEYS |
 * JSON_REAL_PRECISION(17)) of the rest's tree; the result (malloc'd, NUL-terminated, *outlen
 * bytes) has each placeholder replaced by its array.  NULL out of memory. */
char *api_packed_canon(const api_packed_set *set, const char *dump, size_t *outlen);

/* x as printf's "%.17g" writes it, into buf (32 bytes), by exact 128-bit arithmetic for
 * 1e-6 <= |x| < 1e38 and zeros: its length, or 0 elsewhere (then printf is the way). */
size_t api_g17(double x, char *buf);

/* 0 or 1: whether api_packed_scan is used by the request readers (api/run.c); on by default,
 * off for the tests that compare both paths. */
void api_packed_enable(int on);
int api_packed_enabled(void);

#endif
