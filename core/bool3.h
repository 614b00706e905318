/* bool3.h — Boolean chains of a 3D arrangement (issue "Boolean chains"): which input solids
 * each cell lies in, and the cells and boundary of any Boolean expression of the solids.
 *
 * Membership is exact and needs no ray: every solid's winding number is 0 in the exterior cell,
 * and crossing a face changes the winding numbers of the solids whose surface holds it by
 * their faces over it, counted with the way they turn (lar3.fsol, lar3.fwind).  A walk over
 * the cells through their faces, from the exterior, so gives every cell's winding numbers; a
 * cell reached twice with two different rows would be a broken complex, and is reported.  A
 * cell lies in a solid by a fill rule on its winding number (positive by default, as a solid
 * turned outward winds 1 inside; nonzero; odd).  Without fwind (a lar3 made by hand) the
 * faces' solids are toggled (the parity rule).
 * This is the parity test along a path of cells instead of along a ray: it never meets an edge
 * or a vertex, since it crosses faces only, each at a point of its interior.
 *
 * A result is the chain of the cells where the expression is 1; its boundary is the faces with
 * such a cell on exactly one side, each signed so that its normal points out of the result
 * (∂3 of the chain).
 *
 * Threads: reentrant, no globals.  Ownership: inputs borrowed; results freed with
 * bool3_result_free().
 */
#ifndef CELLAR_BOOL3_H
#define CELLAR_BOOL3_H

#include <stddef.h>
#include <stdint.h>

#include "core/arr3.h"
#include "core/boolexpr.h"
#include "core/member.h"

/* Each bounded cell's membership, as sparse rows (core/member.h; c->nc + 1 rows, the last the
 * exterior's, empty).  Returns 0, -1 when out of memory, or 1 when a cell is reached with two
 * memberships (*bad_face: a face where that happened; the complex is inconsistent). */
int bool3_membership(const lar3 *c, member_rows *rows, uint32_t *bad_face);
/* The same, calling tick(udata, cells reached / cells) during the walk (member_walk_ex). */
int bool3_membership_ex(const lar3 *c, member_rows *rows, uint32_t *bad_face,
                        void (*tick)(void *udata, double f), void *udata);

typedef struct bool3_result {
    size_t ncells;
    uint32_t *cells; /* the selected bounded cells, ascending */
    size_t nfaces;
    int32_t *faces; /* the boundary: ±(f+1), + when face f's normal points out of the result */
    double volume;  /* of the selected cells */
} bool3_result;

/* The fill rules: where a solid's inside is, by its winding number w (member.h's). */
enum {
    BOOL3_FILL_POSITIVE = MEMBER_FILL_POSITIVE,
    BOOL3_FILL_NONZERO = MEMBER_FILL_NONZERO,
    BOOL3_FILL_ODD = MEMBER_FILL_ODD
};

/* The cells where e (checked for c->nsolids inputs) is 1, and their boundary.  0 or -1
 * (out of memory; *r then empty).  With winding numbers in rows (rows->wind), a cell is in a
 * solid by the positive rule; bool3_select_fill takes the rule. */
int bool3_select(const lar3 *c, const member_rows *rows, const bool_expr *e, bool3_result *r);
int bool3_select_fill(const lar3 *c, const member_rows *rows, const bool_expr *e, int fill,
                      bool3_result *r);

void bool3_result_free(bool3_result *r);

#endif
