/* geos_bool2.c — the GEOS peer of the 2D Boolean benchmark (bench/runbool2.sh).
 *
 * Usage: geos_bool2 REQUEST.json
 * Reads a cellar "polygons" request
 *   {"kind": "polygons", "polygons": [[ring, hole, ...], ...], "op": OP, "options": {...}}
 * (rings [[x, y], ...], closed implicitly: a last point equal to the first is dropped; options
 * are ignored; GeoJSON and WKT polygons are not read) and performs the same operation with
 * GEOS's reentrant C API:
 *   "union"         GEOSUnaryUnion_r of a collection of all polygons;
 *   "intersection"  GEOSIntersection_r chained over the polygons in order;
 *   "difference"    the first polygon minus the GEOSUnaryUnion_r of the others;
 *   "xor"           GEOSSymDifference_r chained over the polygons in order;
 *   an expression   ["+" | "&" | "-" | "^", operand, operand, ...], each operand an input
 *                   index or a nested expression: the same four rules on the operands' values
 *                   (cellar's own syntax, api/boolop.c; the cases of tests/data/bool2-cases use
 *                   it).
 * Prints one JSON line
 *   {"ms": GEOS time, "area": ..., "perimeter": ..., "polygons": P, "holes": H, "other": K}
 * where ms is CLOCK_MONOTONIC around the operation only (the request is read and the input
 * geometries are built before), perimeter is the length of the result's rings (shells and
 * holes), P and H count the result's polygons and their interior rings, and K the non-areal
 * parts of the result (points or lines from collapses; normally 0).
 * Exit status 0 on success, 1 on a bad request, 2 on a GEOS error (its message on stderr).
 */
#if !defined(_GNU_SOURCE) && !defined(_POSIX_C_SOURCE)
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#endif
#define GEOS_USE_ONLY_R_API
#include <geos_c.h>

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tests/ref/geos_ref.h"

#define MAX_DEPTH 64 /* expression nesting, as cellar's API_BOOL_MAX_DEPTH */

/* One node of the operation: a leaf (op 0) is input polygon `index`; an operator node combines
 * its n kids. */
typedef struct node {
    int op; /* 0, '+', '&', '-', '^' */
    size_t index;
    size_t n;
    struct node *kid;
    GEOSGeometry *g; /* a leaf's geometry, owned until eval() hands it on */
} node;

/* ---- the request ----------------------------------------------------------------------------- */

/* A ring [[x, y], ...] as a closed GEOS linear ring; NULL with why set on a bad ring. */
static GEOSGeometry *read_ring(GEOSContextHandle_t h, const json_t *ring, const char *path,
                               char *why, size_t whylen)
{
    size_t n = json_is_array(ring) ? json_array_size(ring) : 0;
    if (n < 3) {
        snprintf(why, whylen, "%s: expected a ring of at least 3 points [x, y]", path);
        return NULL;
    }
    double *xy = malloc((n + 1) * 2 * sizeof *xy);
    if (!xy) {
        snprintf(why, whylen, "out of memory");
        return NULL;
    }
    for (size_t i = 0; i < n; i++) {
        const json_t *p = json_array_get(ring, i);
        const json_t *x = json_array_get(p, 0), *y = json_array_get(p, 1);
        if (!json_is_array(p) || json_array_size(p) != 2 || !json_is_number(x) ||
            !json_is_number(y)) {
            snprintf(why, whylen, "%s[%zu]: expected [x, y]", path, i);
            free(xy);
            return NULL;
        }
        xy[2 * i] = json_number_value(x);
        xy[2 * i + 1] = json_number_value(y);
    }
    if (xy[0] == xy[2 * (n - 1)] && xy[1] == xy[2 * (n - 1) + 1]) n--; /* closed explicitly */
    if (n < 3) {
        snprintf(why, whylen, "%s: a ring needs at least 3 distinct points", path);
        free(xy);
        return NULL;
    }
    xy[2 * n] = xy[0];
    xy[2 * n + 1] = xy[1];
    GEOSCoordSequence *cs = GEOSCoordSeq_copyFromBuffer_r(h, xy, (unsigned)(n + 1), 0, 0);
    free(xy);
    GEOSGeometry *g = cs ? GEOSGeom_createLinearRing_r(h, cs) : NULL;
    if (!g) snprintf(why, whylen, "%s: GEOS refused the ring", path);
    return g;
}

/* A polygon [shell, hole, ...] as a GEOS polygon; NULL with why set. */
static GEOSGeometry *read_polygon(GEOSContextHandle_t h, const json_t *poly, size_t i, char *why,
                                  size_t whylen)
{
    char path[64];
    size_t nr = json_is_array(poly) ? json_array_size(poly) : 0;
    if (nr == 0) {
        snprintf(why, whylen, "polygons[%zu]: expected [ring, hole, ...] (rings of [x, y])", i);
        return NULL;
    }
    GEOSGeometry **rings = calloc(nr, sizeof *rings);
    if (!rings) {
        snprintf(why, whylen, "out of memory");
        return NULL;
    }
    size_t k = 0;
    for (; k < nr; k++) {
        snprintf(path, sizeof path, "polygons[%zu][%zu]", i, k);
        rings[k] = read_ring(h, json_array_get(poly, k), path, why, whylen);
        if (!rings[k]) break;
    }
    GEOSGeometry *g = NULL;
    if (k == nr) {
        g = GEOSGeom_createPolygon_r(h, rings[0], rings + 1, (unsigned)(nr - 1));
        if (!g) snprintf(why, whylen, "polygons[%zu]: GEOS refused the polygon", i);
    } else {
        while (k > 0) GEOSGeom_destroy_r(h, rings[--k]);
    }
    free(rings);
    return g;
}

static void node_free(node *t)
{
    for (size_t i = 0; i < t->n; i++) node_free(&t->kid[i]);
    free(t->kid);
    t->kid = NULL;
    t->n = 0;
}

/* The operation: a named one over all npoly inputs, or an expression; 0, or -1 with why. */
static int read_op(const json_t *op, size_t npoly, node *t, int depth, char *why, size_t whylen)
{
    memset(t, 0, sizeof *t);
    if (json_is_string(op) && depth == 0) {
        const char *s = json_string_value(op);
        t->op = !strcmp(s, "union")          ? '+'
                : !strcmp(s, "intersection") ? '&'
                : !strcmp(s, "difference")   ? '-'
                : !strcmp(s, "xor")          ? '^'
                                             : 0;
        if (!t->op) {
            snprintf(why, whylen, "op: \"%.40s\" is not union, intersection, difference or xor", s);
            return -1;
        }
        t->kid = calloc(npoly, sizeof *t->kid);
        if (!t->kid) {
            snprintf(why, whylen, "out of memory");
            return -1;
        }
        t->n = npoly;
        for (size_t i = 0; i < npoly; i++) t->kid[i].index = i;
        return 0;
    }
    if (json_is_integer(op)) {
        json_int_t i = json_integer_value(op);
        if (depth == 0 || i < 0 || (size_t)i >= npoly) {
            snprintf(why, whylen, "op: input %lld out of range (%zu inputs)", (long long)i, npoly);
            return -1;
        }
        t->index = (size_t)i;
        return 0;
    }
    const char *s = json_string_value(json_array_get(op, 0));
    size_t n = json_is_array(op) ? json_array_size(op) : 0;
    if (n < 3 || !s || strlen(s) != 1 || !strchr("+&-^", s[0]) || depth >= MAX_DEPTH) {
        snprintf(why, whylen,
                 "op: expected a name or [\"+\" | \"&\" | \"-\" | \"^\", operand, operand, ...] "
                 "(at most %d levels)",
                 MAX_DEPTH);
        return -1;
    }
    t->op = s[0];
    t->kid = calloc(n - 1, sizeof *t->kid);
    if (!t->kid) {
        snprintf(why, whylen, "out of memory");
        return -1;
    }
    t->n = n - 1;
    for (size_t i = 1; i < n; i++) {
        if (read_op(json_array_get(op, i), npoly, &t->kid[i - 1], depth + 1, why, whylen)) {
            node_free(t);
            return -1;
        }
    }
    return 0;
}

/* Gives every leaf its own geometry: the input itself at its first use, a copy after. */
static int bind_leaves(GEOSContextHandle_t h, node *t, GEOSGeometry **poly, unsigned char *used)
{
    if (t->op) {
        for (size_t i = 0; i < t->n; i++)
            if (bind_leaves(h, &t->kid[i], poly, used)) return -1;
        return 0;
    }
    t->g = used[t->index] ? GEOSGeom_clone_r(h, poly[t->index]) : poly[t->index];
    used[t->index] = 1;
    return t->g ? 0 : -1;
}

static void unbind_leaves(GEOSContextHandle_t h, node *t)
{
    for (size_t i = 0; i < t->n; i++) unbind_leaves(h, &t->kid[i]);
    if (t->g) GEOSGeom_destroy_r(h, t->g);
    t->g = NULL;
}

/* ---- the operation -----------------------------------------------------------------------------
 */

static GEOSGeometry *eval(GEOSContextHandle_t h, node *t);

/* GEOSUnaryUnion_r of the values of kids[0..n) (one value: itself). */
static GEOSGeometry *union_of(GEOSContextHandle_t h, node *kids, size_t n)
{
    if (n == 1) return eval(h, &kids[0]);
    GEOSGeometry **g = calloc(n, sizeof *g);
    if (!g) return NULL;
    size_t k = 0;
    for (; k < n; k++)
        if (!(g[k] = eval(h, &kids[k]))) break;
    GEOSGeometry *c = NULL, *r = NULL;
    if (k == n) c = GEOSGeom_createCollection_r(h, GEOS_GEOMETRYCOLLECTION, g, (unsigned)n);
    if (c) {
        r = GEOSUnaryUnion_r(h, c);
        GEOSGeom_destroy_r(h, c); /* and the parts it took */
    } else {
        while (k > 0) GEOSGeom_destroy_r(h, g[--k]);
    }
    free(g);
    return r;
}

/* The value of t as a new geometry (leaves hand their own on); NULL on a GEOS error. */
static GEOSGeometry *eval(GEOSContextHandle_t h, node *t)
{
    if (!t->op) {
        GEOSGeometry *g = t->g;
        t->g = NULL;
        return g;
    }
    if (t->op == '+') return union_of(h, t->kid, t->n);
    GEOSGeometry *r = eval(h, &t->kid[0]);
    if (!r || t->n == 1) return r;
    if (t->op == '-') {
        GEOSGeometry *rest = union_of(h, t->kid + 1, t->n - 1), *d = NULL;
        if (rest) d = GEOSDifference_r(h, r, rest);
        GEOSGeom_destroy_r(h, r);
        if (rest) GEOSGeom_destroy_r(h, rest);
        return d;
    }
    for (size_t i = 1; i < t->n && r; i++) {
        GEOSGeometry *b = eval(h, &t->kid[i]), *c = NULL;
        if (b) {
            c = t->op == '&' ? GEOSIntersection_r(h, r, b) : GEOSSymDifference_r(h, r, b);
            GEOSGeom_destroy_r(h, b);
        }
        GEOSGeom_destroy_r(h, r);
        r = c;
    }
    return r;
}

/* Counts the polygons, their holes and the other non-empty parts of g. */
static void count_parts(GEOSContextHandle_t h, const GEOSGeometry *g, size_t *np, size_t *nh,
                        size_t *nother)
{
    int type = GEOSGeomTypeId_r(h, g);
    if (type == GEOS_MULTIPOLYGON || type == GEOS_GEOMETRYCOLLECTION ||
        type == GEOS_MULTILINESTRING || type == GEOS_MULTIPOINT) {
        int n = GEOSGetNumGeometries_r(h, g);
        for (int i = 0; i < n; i++) count_parts(h, GEOSGetGeometryN_r(h, g, i), np, nh, nother);
    } else if (GEOSisEmpty_r(h, g) == 1) {
        return;
    } else if (type == GEOS_POLYGON) {
        int k = GEOSGetNumInteriorRings_r(h, g);
        (*np)++;
        *nh += k > 0 ? (size_t)k : 0;
    } else {
        (*nother)++;
    }
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s REQUEST.json\n", argv[0]);
        return 1;
    }
    json_error_t jerr;
    json_t *req = json_load_file(argv[1], 0, &jerr);
    if (!req) {
        fprintf(stderr, "%s:%d:%d: %s\n", argv[1], jerr.line, jerr.column, jerr.text);
        return 1;
    }
    geos_ref_err ge = {.set = 0};
    GEOSContextHandle_t h = GEOS_init_r();
    GEOSContext_setErrorMessageHandler_r(h, geos_ref_on_error, &ge);

    char why[512] = "";
    int status = 1;
    const json_t *polys = json_object_get(req, "polygons");
    size_t npoly = json_is_array(polys) ? json_array_size(polys) : 0;
    GEOSGeometry **poly = calloc(npoly ? npoly : 1, sizeof *poly);
    unsigned char *used = calloc(npoly ? npoly : 1, 1);
    node op = {0};
    int have_op = 0;
    if (!poly || !used) {
        snprintf(why, sizeof why, "out of memory");
        goto done;
    }
    if (npoly == 0) {
        snprintf(why, sizeof why, "polygons: expected a non-empty array of polygons");
        goto done;
    }
    for (size_t i = 0; i < npoly; i++)
        if (!(poly[i] = read_polygon(h, json_array_get(polys, i), i, why, sizeof why))) goto done;
    if (read_op(json_object_get(req, "op"), npoly, &op, 0, why, sizeof why)) goto done;
    have_op = 1;
    if (bind_leaves(h, &op, poly, used)) {
        snprintf(why, sizeof why, "GEOS could not copy an input polygon");
        goto done;
    }
    json_decref(req);
    req = NULL;

    double t0 = geos_ref_now_ms();
    GEOSGeometry *r = eval(h, &op);
    double ms = geos_ref_now_ms() - t0;
    if (!r) {
        snprintf(why, sizeof why, "GEOS: %s", ge.set ? ge.msg : "the operation failed");
        status = 2;
        goto done;
    }
    double area = 0, perimeter = 0;
    size_t np = 0, nh = 0, nother = 0;
    if (!GEOSArea_r(h, r, &area) || !GEOSLength_r(h, r, &perimeter)) {
        snprintf(why, sizeof why, "GEOS: %s", ge.set ? ge.msg : "no area or length");
        GEOSGeom_destroy_r(h, r);
        status = 2;
        goto done;
    }
    count_parts(h, r, &np, &nh, &nother);
    GEOSGeom_destroy_r(h, r);
    printf("{\"ms\":%.3f,\"area\":%.17g,\"perimeter\":%.17g,\"polygons\":%zu,\"holes\":%zu,"
           "\"other\":%zu}\n",
           ms, area, perimeter, np, nh, nother);
    status = 0;
done:
    if (status) fprintf(stderr, "%s: %s\n", argv[1], why);
    if (have_op) {
        unbind_leaves(h, &op);
        node_free(&op);
    }
    for (size_t i = 0; poly && i < npoly; i++)
        if (poly[i] && !used[i]) GEOSGeom_destroy_r(h, poly[i]);
    free(poly);
    free(used);
    if (req) json_decref(req);
    GEOS_finish_r(h);
    return status;
}
