/* geos_ref.h — GEOS as a reference for the 2D pipeline: node a set of segments, polygonize the
 * noded linework, and report counts and face areas to compare with arr2_build().
 *
 * Used by the differential tests (tests/) and by the benchmarks (bench/geos_polygonize.c,
 * bench/geos_bool2.c).
 * GEOS works in floating point without snap rounding, so on near-degenerate inputs it may
 * disagree with us or fail: callers compare on inputs where the reference is trustworthy.
 *
 * Threads: reentrant; every call makes and finishes its own GEOS context (the _r API only).
 * No globals.
 */
#ifndef CELLAR_GEOS_REF_H
#define CELLAR_GEOS_REF_H

#include <geos_c.h>
#include <stddef.h>
#include <stdint.h>

/* The arrangement of n segments seg[4i..4i+3] = x1, y1, x2, y2 (borrowed) according to GEOS.
 * Zero-length segments are skipped.  The segments are noded with GEOSNode and then
 * polygonized with GEOSPolygonize (which ignores dangles and cut edges, like arr2_build()
 * without keep_dangling).  On success returns 0 and sets
 *   *areas   the areas of the polygons (outer ring minus holes), sorted ascending; a malloc'd
 *            array of *nfaces doubles that the caller frees (NULL when *nfaces is 0);
 *   *nfaces  the number of polygons (bounded faces);
 *   *nholes  the total number of interior rings (holes) of the polygons;
 *   *nnodes  the distinct endpoints of the noded edges (dangles included);
 *   *nedges  the distinct noded edges: straight pieces between two nodes (dangles included).
 * Returns -1 on a GEOS error (or out of memory); then *areas is NULL and the counts are 0. */
int geos_ref_faces(const double *seg, size_t n, double **areas, size_t *nfaces, size_t *nholes,
                   size_t *nnodes, size_t *nedges);

/* The same, and also:
 *   *ms   (may be NULL) the wall time of GEOSNode plus GEOSPolygonize in milliseconds
 *         (CLOCK_MONOTONIC), without building the input or counting;
 *   err   (errlen bytes, may be NULL / 0) the GEOS message when -1 is returned. */
int geos_ref_faces_timed(const double *seg, size_t n, double **areas, size_t *nfaces,
                         size_t *nholes, size_t *nnodes, size_t *nedges, double *ms, char *err,
                         size_t errlen);

/* The first GEOS error message of a context: install with
 * GEOSContext_setErrorMessageHandler_r(h, geos_ref_on_error, &err). */
typedef struct geos_ref_err {
    char msg[400]; /* the first GEOS error message */
    int set;       /* non-zero once msg holds one */
} geos_ref_err;
void geos_ref_on_error(const char *message, void *udata);

/* Wall time in milliseconds (CLOCK_MONOTONIC). */
double geos_ref_now_ms(void);

/* a op b made in context h, for op "union" or "intersection" (any other: the symmetric
 * difference); a and b are taken (destroyed).  NULL on a GEOS error. */
GEOSGeometry *geos_ref_fold(GEOSContextHandle_t h, const char *op, GEOSGeometry *a,
                            GEOSGeometry *b);

/* Polygon p of a polygon set in the form of bool2_input (core/bool2.h: polygon p's rings are
 * ring_off[poly_off[p] .. poly_off[p+1]), ring r's points xy[2 ring_off[r] .. 2 ring_off[r+1]),
 * closed implicitly, the first the shell) as a GEOS polygon made in context h; the caller
 * destroys it.  Its rings are closed by repeating their first point. */
GEOSGeometry *geos_ref_polygon(GEOSContextHandle_t h, const uint32_t *poly_off,
                               const uint32_t *ring_off, const double *xy, size_t p);

#endif
