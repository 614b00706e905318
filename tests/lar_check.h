/* lar_check.h — invariants every 2D result must satisfy, checked independently of the core's
 * own bookkeeping (from V, EV, the cycles and FE only). */
#ifndef CELLAR_LAR_CHECK_H
#define CELLAR_LAR_CHECK_H

#include <stddef.h>
#include <stdint.h>

#include "core/arr2.h"
#include "core/arr3.h"

/* Checks: EV sorted, unique, v0 < v1, in range; every cycle is a closed walk along edges;
 * every edge is walked exactly once in each direction over all cycles (faces' outer cycles,
 * holes, exterior); FE of each face equals the signed sum of its cycles' edges (net), and
 * d1·d2 = 0; outer cycles counter-clockwise, holes and exterior cycles clockwise (or flat);
 * V - E + F = number of connected components; the faces' areas (holes subtracted) add up to
 * the area enclosed by the exterior cycles.  Returns 0, or -1 with a message in msg. */
int lar_check(const lar2 *c, char *msg, size_t len);

/* Area of face f with its holes subtracted. */
double lar_face_area(const lar2 *c, size_t f);

/* Compares c's face areas, sorted ascending, with ref[0..nref) (sorted ascending, e.g. GEOS's
 * polygon areas): returns how many differ by more than 1e-9 relative plus tol_abs (nref + 1
 * when the counts differ); *worst gets the largest relative difference. */
size_t lar_sorted_areas_differ(const lar2 *c, const double *ref, size_t nref, double tol_abs,
                               double *worst);

/* Checks a 3-complex from V, EV, the cycles, FE and CF only: EV sorted, unique, v0 < v1, in
 * range; each face's cycles are closed walks along edges and FE is their signed sum (so
 * d1·d2 = 0); each face lies in the plane of its normal FN (within tol, in input units);
 * every face is on exactly two cells counting the exterior, with opposite signs; each bounded
 * cell's boundary and the exterior's have d2·d3 = 0; every bounded cell has positive volume
 * (recomputed from its faces) equal to cvol, and the bounded volumes add up to the volume
 * the exterior encloses.  Returns 0, or -1 with a message in msg.  *euler (may be NULL) gets
 * V - E + F - (C + 1). */
int lar3_check(const lar3 *c, double tol, long *euler, char *msg, size_t len);

/* Volume of bounded cell k recomputed from its faces. */
double lar3_cell_volume(const lar3 *c, size_t k);

/* The sparse membership rows of c (bool3_membership) and the same as a dense table (c->nc rows
 * of c->nsolids bytes, mem) for the checks; 0, or non-zero when the walk failed. */
struct member_rows;
long lar3_membership_dense(const lar3 *c, uint8_t *mem, struct member_rows *rows);

#endif
