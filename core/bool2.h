/* bool2.h — Boolean operations on polygons with holes, through one planar arrangement (issue
 * "Boolean chains", 2D).
 *
 * Every ring edge of every input polygon goes into ONE arr2_build() arrangement, tagged with its
 * polygon, so the result shares the arrangement's snapped vertices and edges, and every edge
 * knows the polygons whose rings lie on it an odd number of times.  Membership follows from the
 * arrangement alone: the unbounded face lies in no polygon, and crossing an edge changes the
 * membership of exactly the polygons it lists (no sample point, no ray).  The expression selects
 * faces; selected faces joined across edges make the result's polygons; each one's boundary
 * rings are walked turning through the outside at every vertex, so rings never pass a vertex
 * twice: one shell (counter-clockwise) and holes (clockwise) per polygon, holes touching the
 * shell or each other at a vertex as separate rings, as OGC asks.  Exact throughout on the grid
 * (the precision is the one tolerance).
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
#include "core/member.h"

#define BOOL2_MAX_INPUTS 500000u /* input polygons (the expression holds at most 10^6 codes) */

/* Where a polygon's inside is, by the winding number w of its rings about a point (member.h's
 * rules): odd w (the even-odd rule, the API's default: ring roles and orientations are free),
 * w != 0, or w > 0 (rings counter-clockwise around what they hold, holes clockwise, as
 * GeoJSON's right-hand rule and SVG's nonzero fill mean them). */
enum {
    BOOL2_FILL_ODD = MEMBER_FILL_ODD,
    BOOL2_FILL_NONZERO = MEMBER_FILL_NONZERO,
    BOOL2_FILL_POSITIVE = MEMBER_FILL_POSITIVE
};

/* The input polygons, in CSR form (all borrowed):
 *   polygon p has rings poly_off[p] .. poly_off[p+1]) (first the outer boundary, then holes;
 *   the fill rule over all rings is what counts);
 *   ring r has points xy[2*ring_off[r] .. 2*ring_off[r+1]) (x, y), closed implicitly (a last
 *   point equal to the first is allowed and adds nothing). */
typedef struct bool2_input {
    size_t npoly;
    const uint32_t *poly_off; /* npoly+1 */
    const uint32_t *ring_off; /* nrings+1, nrings = poly_off[npoly] */
    const double *xy;         /* 2 * ring_off[nrings] */
    int fill;                 /* BOOL2_FILL_* (named: 0 is not the even-odd rule) */
    int pieces;               /* non-zero: the result's pieces too (bool2_result.pieces) */
} bool2_input;

/* Polygons made of the boundary of labelled faces, CSR: cycle k has vertices
 * rv[rc_off[k]..rc_off[k+1]) and signed edges re[same range], re[i] = ±(e+1) the edge from rv[i]
 * to the next vertex (+ when that is EV's v0 -> v1), its faces on the left; polygon q has outer
 * cycle poly_outer[q] (counter-clockwise) and holes ph_cyc[ph_off[q]..ph_off[q+1]) (clockwise). */
typedef struct bool2_rings {
    size_t nrcyc;
    uint32_t *rc_off; /* nrcyc+1 */
    uint32_t *rv;
    int32_t *re;
    size_t npoly;
    uint32_t *poly_outer; /* npoly */
    uint32_t *ph_off;     /* npoly+1 */
    uint32_t *ph_cyc;
} bool2_rings;

/* The arrangement, its membership table and the selected region. */
typedef struct bool2_result {
    lar2 c;         /* the arrangement of all ring edges */
    size_t ninputs; /* polygons */
    /* face f lies in the polygons mem[mem_off[f] .. mem_off[f+1]), ascending (c.nf + 1 rows:
     * the last, empty, is the unbounded face); compressed sparse rows, never faces x inputs.
     * Under the even-odd rule a row lists the polygons of odd winding number; under the others
     * those of non-zero winding number, memw then holding the numbers. */
    uint32_t *mem_off, *mem;
    int32_t *memw; /* NULL under the even-odd rule */
    size_t ncells;
    uint32_t *cells; /* ncells selected faces, ascending */
    double area;     /* the area the result polygons enclose, from their written coordinates */
    /* The result polygons (bool2_rings): the region's boundary cycles, the selected region on
     * the left of every one, and the polygons, outer cycles counter-clockwise, holes
     * clockwise. */
    bool2_rings region;
    /* With in->pieces, the result cut where the membership changes, as a GIS overlay gives it:
     * the selected faces of one membership row (the inputs a face lies in by the fill rule) are
     * one piece, npieces of them, numbered in the order of their first face; piece k's row is
     * that of face piece_face[k].  pieces holds their polygons (a piece may have several, and
     * pieces meet along edges), polygon q of piece poly_piece[q].  Else all zero. */
    size_t npieces;
    uint32_t *piece_face; /* npieces */
    bool2_rings pieces;
    uint32_t *poly_piece; /* pieces.npoly */
} bool2_result;

/* Builds the arrangement of in's rings with opts (may be NULL: defaults; tags and input_coords
 * are set here), labels its faces and selects them with op (checked for in->npoly inputs,
 * bool_expr_check()).  Returns ARR_OK
 * and fills *out, or an ARR_* code with a message in err (errlen bytes) and *out zeroed. */
int bool2_build(const bool2_input *in, const bool_expr *op, const arr2_opts *opts,
                bool2_result *out, char *err, size_t errlen);

/* Frees what bool2_build() allocated; safe on a zeroed or already freed result. */
void bool2_free(bool2_result *r);

#endif
