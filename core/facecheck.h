/* facecheck.h — is one face, as the 3D pipeline sees it on the grid, a polygon it can take?
 *
 * A face is an outer cycle and zero or more holes of vertex ids with integer grid coordinates
 * (core/solid.c's merged vertices; core/arr3.c's snapped ones).  The 3D pipeline takes a face
 * whose vertices lie exactly in one plane as one piece with those cycles, and splits one that
 * does not into triangles: a quad along a diagonal, anything else by ear clipping of its
 * projection along the largest axis of its exact Newell normal (face_newell_axis).  Either
 * way it relies on the face being a polygon with holes in that plane or projection:
 *   - every cycle simple: no two of its edges cross or run along each other, no vertex on
 *     another of its edges, no point passed twice (a pinch);
 *   - cycles that meet only touch, at single points, without crossing there (decided from the
 *     order of their edges about the point);
 *   - every hole inside the outer cycle and outside every other hole.
 * face_check decides exactly that, by exact integer predicates on the grid coordinates (no
 * tolerance), and says what is wrong and where.  With FACE_SOLID (a face of a closed solid) it
 * also asks every hole to turn against the outer cycle, and cycles to touch only at a shared
 * vertex: a vertex of one cycle inside an edge of another is a T-junction with the face across
 * that edge, which does not have that vertex.  A face that is not planar may touch itself only
 * at shared vertices (two vertices above one another would meet in its projection).
 *
 * Cost: all pairs of edges for small faces; beyond that the edges' boxes go into a box-kd-tree
 * (core/box.h) that gives the pairs of edges whose boxes meet, each once, and the edges a ray
 * from each hole meets (to tell whether the hole lies inside the outer cycle); the points where
 * cycles meet are found by one sort.  So O(n log n) plus the pairs of edges whose boxes meet,
 * as for the 2D arrangement's buckets (core/arr2.c).
 *
 * Threads: reentrant; a face_work is used by one thread at a time.  Ownership: inputs borrowed;
 * face_work (zero-initialised by the caller) grows as needed and is freed by face_work_free().
 */
#ifndef CELLAR_FACECHECK_H
#define CELLAR_FACECHECK_H

#include <stddef.h>
#include <stdint.h>

#include "core/box.h"

/* A face whose grid box has a side this long or longer is not checked (FACE_UNCHECKED): the
 * exact predicates below are sized for less.  The 3D pipeline refuses such grids anyway
 * (extent / precision <= 2^ARR3_GRID_BITS). */
#define FACE_CHECK_LIMIT ((int64_t)1 << 40)

#define FACE_SOLID 1 /* a face of a closed solid (see above) */

enum {
    FACE_OK = 0,
    FACE_UNCHECKED,  /* too large to check (FACE_CHECK_LIMIT): taken as it is */
    FACE_FLAT,       /* every vertex on one line */
    FACE_PROJ_POINT, /* not planar: entries (c1, i1) and (c2, i2), different vertices, project to
                        one point */
    FACE_CROSS,      /* edges (c1, i1) and (c2, i2) cross */
    FACE_OVERLAP,    /* edges (c1, i1) and (c2, i2) run along each other */
    FACE_PINCH,      /* cycle c1 passes twice through one point: entries i1 and i2 (c2 == c1) */
    FACE_ON_EDGE,    /* entry (c1, i1) lies inside edge (c2, i2): of its own cycle (c1 == c2),
                        or (FACE_SOLID, or not planar) of another */
    FACE_CROSS_AT,   /* cycles c1 and c2 cross at the point of entry (c1, i1) */
    FACE_HOLE_OUT,   /* hole c1 lies outside the outer cycle */
    FACE_HOLE_IN,    /* hole c1 lies inside hole c2 */
    FACE_HOLE_TURN   /* hole c1 turns the same way as the outer cycle (FACE_SOLID) */
};

/* The edge (c, i) runs from entry i of cycle c to entry (i + 1) % len[c]. */
typedef struct face_verdict {
    int what;   /* FACE_* */
    int planar; /* 1: every vertex in one plane; 0: not (split into triangles) */
    int axis;   /* the plane or the projection is looked at along this axis (0, 1, 2) */
    size_t c1, i1, c2, i2;
} face_verdict;

typedef struct face_cycles {
    const int64_t *g;           /* 3 per vertex id: grid coordinates (any common origin) */
    size_t ncyc;                /* cycles, the first the outer one */
    const uint32_t *const *cyc; /* cycle c: vertex ids cyc[c][0 .. len[c]); consecutive ids
                                   differ (the last and the first too), at least 3 ids */
    const size_t *len;
} face_cycles;

/* Scratch arrays, kept from face to face (zero-initialise; face_work_free). */
typedef struct face_work {
    int64_t *P; /* 2 per entry */
    uint32_t *cyc, *start;
    uint8_t *touched;
    uint32_t *stamp;
    void *rec, *inc;
    int64_t *box;
    size_t capP, capcyc, capstart, captouched, capstamp, caprec, capinc, capbox;
    box_tree tree;
} face_work;

void face_work_free(face_work *w);

/* Checks face f; flags FACE_SOLID or 0 (a face of a soup).  Returns 0 with *out filled
 * (out->what FACE_OK, FACE_UNCHECKED or what is wrong), or -1 when out of memory. */
int face_check(const face_cycles *f, int flags, face_work *w, face_verdict *out);

/* The axis (0, 1, 2) of the largest component of the exact Newell normal of cycle v[0..n) (the
 * first of equals): the projection along which the 3D pipeline splits a face that is not
 * planar into triangles.  Exact (128-bit sums about v[0]) for coordinate differences below
 * FACE_CHECK_LIMIT and cycles of fewer than 2^40 entries, so that every caller gets the same
 * axis for the same face whatever the origin of its grid. */
int face_newell_axis(const int64_t *g, const uint32_t *v, size_t n);

#endif
