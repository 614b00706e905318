/* shapes.h — closed solids for the 3D tests (core/solid.h's struct solid), built from exact
 * corners so that contacts stay contacts: a box, a tetrahedron, a prism over any convex polygon,
 * a hexahedron from 8 corners, a slab whose top and bottom are fans of slivers; transforms; the
 * volume and area of a solid (doubles, for expectations and the snapping bound).
 *
 * Every builder returns a solid oriented outward (counter-clockwise seen from outside); the
 * caller frees it with solid_free().  Deterministic, no globals.
 */
#ifndef CELLAR_TESTS_SHAPES_H
#define CELLAR_TESTS_SHAPES_H

#include <stddef.h>
#include <stdint.h>

#include "core/solid.h"

/* A solid from nv corners (3 doubles each) and faces: vertex indices, each face ended by -1,
 * the list ended by -2 (one cycle a face).  Turned outward when its volume is negative. */
solid shape_poly(const double *V, size_t nv, const int *F);

solid shape_box(const double *lo, const double *hi);
solid shape_tet(const double *a, const double *b, const double *c, const double *d);
/* The prism over the convex polygon base[0..n) (in any order around it), extruded by dir. */
solid shape_prism(const double (*base)[3], size_t n, const double *dir);
/* A hexahedron from 8 corners (bit 0: x side, bit 1: y, bit 2: z of a box). */
solid shape_hexa(const double c[8][3]);
/* A slab over a convex polygon of n >= 4 vertices, height h, whose top and bottom are fans
 * from vertex 0: with points crowded near one corner (aspect up to about 1/spread), the fans are
 * slivers.  The polygon: a long side from (0,0) to (len,0), then n-2 points on the arc from
 * (len, w) to (0, w) bulging out by `bulge` (spread controls how they crowd at its start). */
solid shape_fan_slab(size_t n, double len, double w, double bulge, double spread, double h);

/* x' = R x + t for every vertex (R row-major). */
void shape_transform(solid *s, const double R[3][3], const double *t);
/* The rotation about unit axis u by angle a. */
void shape_rotation(const double *u, double a, double R[3][3]);
void shape_translate(solid *s, const double *t);

double shape_volume(const solid *s);
double shape_area(const solid *s);

#endif
