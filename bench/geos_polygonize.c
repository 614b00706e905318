/* geos_polygonize.c — the GEOS peer of the 2D benchmark.
 *
 * Usage: geos_polygonize REQUEST.json
 * Reads a cellar request {"kind": "lines", "lines": [[[x1, y1], [x2, y2]], ...], ...} (options
 * are ignored), nodes and polygonizes the segments with GEOS (tests/ref/geos_ref.c) and prints
 * one JSON line {"V": nodes, "E": noded edges, "F": polygons, "holes": interior rings,
 * "ms": wall time of node + polygonize}.  V and E count dangling edges too; F does not.
 * Exit status 0 on success, 1 on a bad request, 2 on a GEOS error.
 */
#include "tests/ref/geos_ref.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>

/* One point [x, y] into xy[0..1]; 0 on success. */
static int read_point(const json_t *p, double *xy)
{
    if (!json_is_array(p) || json_array_size(p) != 2) return -1;
    for (size_t k = 0; k < 2; k++) {
        const json_t *c = json_array_get(p, k);
        if (!json_is_number(c)) return -1;
        xy[k] = json_number_value(c);
    }
    return 0;
}

/* The segments of a request as a malloc'd array of 4n doubles; NULL on a bad request. */
static double *read_segments(const json_t *req, size_t *n, char *why, size_t whylen)
{
    const json_t *lines = json_object_get(req, "lines");
    if (!json_is_array(lines)) {
        snprintf(why, whylen, "request has no \"lines\" array");
        return NULL;
    }
    *n = json_array_size(lines);
    double *seg = malloc((*n ? *n : 1) * 4 * sizeof *seg);
    if (!seg) {
        snprintf(why, whylen, "out of memory");
        return NULL;
    }
    for (size_t i = 0; i < *n; i++) {
        const json_t *l = json_array_get(lines, i);
        if (!json_is_array(l) || json_array_size(l) != 2 ||
            read_point(json_array_get(l, 0), seg + 4 * i) ||
            read_point(json_array_get(l, 1), seg + 4 * i + 2)) {
            snprintf(why, whylen, "lines[%zu] is not [[x1, y1], [x2, y2]]", i);
            free(seg);
            return NULL;
        }
    }
    return seg;
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
    char why[256];
    size_t n = 0;
    double *seg = read_segments(req, &n, why, sizeof why);
    json_decref(req);
    if (!seg) {
        fprintf(stderr, "%s: %s\n", argv[1], why);
        return 1;
    }

    double *areas = NULL, ms = 0;
    size_t nf = 0, nholes = 0, nv = 0, ne = 0;
    char err[256];
    int rc = geos_ref_faces_timed(seg, n, &areas, &nf, &nholes, &nv, &ne, &ms, err, sizeof err);
    free(seg);
    free(areas);
    if (rc != 0) {
        fprintf(stderr, "%s: GEOS: %s\n", argv[1], err);
        return 2;
    }
    printf("{\"V\":%zu,\"E\":%zu,\"F\":%zu,\"holes\":%zu,\"ms\":%.3f}\n", nv, ne, nf, nholes, ms);
    return 0;
}
