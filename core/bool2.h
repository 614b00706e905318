/* bool2.h — Boolean operations on polygons with holes, through one planar arrangement (issue
 * "Boolean chains", 2D).
 *
 * Every ring edge of every input polygon goes into ONE arr2_build() arrangement, so the result
 * shares the arrangement's snapped vertices and edges.  Each bounded face gets an interior point
 * (not a fixed offset from an edge: the middle of the widest inside stretch of a horizontal line
 * halfway across the largest gap between the face's vertex heights, checked exactly against the
 * face's cycles) that is classified against every input polygon by an exact even-odd test over
 * all its rings (half-open rule for the ray through vertices).  That is the membership table,
 * faces x inputs; the bool_expr selects faces; the result's boundary is the set of edges with a
 * selected face on exactly one side (the exterior counts as unselected), walked into cycles with
 * the selected region on the left: outer cycles counter-clockwise, holes clockwise.  At a vertex
 * of several boundary edges the walk takes the tightest turn: where the region touches itself
 * (two squares sharing a corner) the cycles split; where the outside touches itself (a hole
 * touching the outer boundary at a vertex) one cycle passes the vertex twice and there is no
 * hole, the region being simply connected.
 *
 * The classification is exact against the INPUT coordinates; the faces are those of the SNAPPED
 * arrangement.  A face narrower than the grid step (a sliver that snapping created or nearly
 * closed) may be classified on the wrong side: the grid step is the one tolerance (DESIGN.md).
 *
 * Threads: reentrant (arr2_build() starts and joins its own threads); no globals.
 * Ownership: inputs are borrowed; the caller owns *out and frees it with bool2_free().
 */
#ifndef CELLAR_BOOL2_H
#define CELLAR_BOOL2_H

#include <stddef.h>
#include <stdint.h>

#include "core/arr2.h"
#include "core/boolexpr.h"

#define BOOL2_MAX_INPUTS 100000u /* input polygons */

/* The input polygons, in CSR form (all borrowed):
 *   polygon p has rings poly_off[p] .. poly_off[p+1]) (first the outer boundary, then holes;
 *   an even-odd rule over all rings is what counts, so ring roles and orientations are free);
 *   ring r has points xy[2*ring_off[r] .. 2*ring_off[r+1]) (x, y), closed implicitly (a last
 *   point equal to the first is allowed and adds nothing). */
typedef struct bool2_input {
    size_t npoly;
    const uint32_t *poly_off; /* npoly+1 */
    const uint32_t *ring_off; /* nrings+1, nrings = poly_off[npoly] */
    const double *xy;         /* 2 * ring_off[nrings] */
} bool2_input;

/* The arrangement, its membership table and the selected region. */
typedef struct bool2_result {
    lar2 c;          /* the arrangement of all ring edges */
    size_t ninputs;  /* polygons */
    uint8_t *member; /* c.nf * ninputs: member[f*ninputs + p] = 1 when face f lies in p */
    size_t ncells;
    uint32_t *cells; /* ncells selected faces, ascending */
    double area;     /* total area of the selected faces (input units) */
    /* The region's boundary cycles, CSR: cycle k has vertices rv[rc_off[k]..rc_off[k+1]) and
     * signed edges re[same range], re[i] = ±(e+1) the edge from rv[i] to the next vertex
     * (+ when that is EV's v0 -> v1).  The selected region is on the left of every cycle. */
    size_t nrcyc;
    uint32_t *rc_off; /* nrcyc+1 */
    uint32_t *rv;
    int32_t *re;
    /* The result polygons: polygon q has outer cycle poly_outer[q] (counter-clockwise) and
     * holes ph_cyc[ph_off[q]..ph_off[q+1]) (clockwise), cycle ids as above. */
    size_t npoly;
    uint32_t *poly_outer; /* npoly */
    uint32_t *ph_off;     /* npoly+1 */
    uint32_t *ph_cyc;
} bool2_result;

/* Builds the arrangement of in's rings with opts (may be NULL: defaults), classifies its faces
 * and selects them with op (checked for in->npoly inputs, bool_expr_check()).  Returns ARR_OK
 * and fills *out, or an ARR_* code with a message in err (errlen bytes) and *out zeroed. */
int bool2_build(const bool2_input *in, const bool_expr *op, const arr2_opts *opts,
                bool2_result *out, char *err, size_t errlen);

/* Frees what bool2_build() allocated; safe on a zeroed or already freed result. */
void bool2_free(bool2_result *r);

/* Is (px, py) inside the polygon of nring rings (ring_off/xy as in bool2_input, ring_off
 * borrowed from index 0) by the even-odd rule?  Exact for double inputs; a point exactly on
 * an edge falls on one side by the half-open rule (consistent across shared edges). */
int bool2_point_in(double px, double py, const uint32_t *ring_off, size_t nring, const double *xy);

#endif
