/* lar_check.h — invariants every 2D result must satisfy, checked independently of the core's
 * own bookkeeping (from V, EV, the cycles and FE only). */
#ifndef CELLAR_LAR_CHECK_H
#define CELLAR_LAR_CHECK_H

#include <stddef.h>

#include "core/arr2.h"

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

#endif
