/* planar.h — the half-edge kernel of a planar arrangement (issue 30, item 1).
 *
 * One topology for the two planar arrangements of the house: arr2's grid points (int64
 * coordinates, core/arr2.c) and the points of one plane of the 3D pipeline (implicit points
 * projected, core/arr3_plane.c).  The kernel knows half-edges and vertices by number only; every
 * geometric question goes to the model's traits, exact predicates:
 *   around    the order of two half-edges leaving one vertex (counter-clockwise);
 *   below     whether an edge meets the downward vertical ray from a component's lowest point;
 *   higher    which of two such edges the ray meets first.
 * Numbering (both models): edge e has half-edges 2e and 2e + 1; a vertex's outgoing half-edges
 * are out[off[v] .. off[v + 1]).  After planar_sort_around they run counter-clockwise and
 * pos[h] is h's place in its vertex's list; next(h) is, at h's head, the half-edge just
 * clockwise of h's twin (planar_next), so every cycle has its face on its left.  Cycles are
 * numbered in the order of their smallest half-edge (planar_cycles), the walk order of both
 * models before the kernel, so their output is unchanged.
 *
 * Placement (planar_place) answers, for each component's query point, the first edge of
 * another component a downward ray meets, from a slab index over the edges' conservative
 * horizontal spans: each query tests the edges of its slab only, not every edge.
 *
 * Threads: reentrant, no globals; the traits' context is only read.  Ownership: inputs are
 * borrowed; outputs are the caller's arrays, or malloc'd where said (free()).
 */
#ifndef CELLAR_PLANAR_H
#define CELLAR_PLANAR_H

#include <stddef.h>
#include <stdint.h>

#define PLANAR_NONE UINT32_MAX

/* A model's exact predicates (ctx is passed back to each). */
typedef struct planar_traits {
    void *ctx;
    /* < 0 when half-edge a comes before b counter-clockwise around their common tail (from the
     * model's reference direction), > 0 after; 0 only when they leave in the same direction. */
    int (*around)(void *ctx, uint32_t a, uint32_t b);
    /* 1 when edge e meets the downward vertical ray from query q's point (strictly below it,
     * e straddling the vertical line as the model defines it), else 0. */
    int (*below)(void *ctx, uint32_t e, uint32_t q);
    /* 1 when edge a lies above edge b on the vertical line both meet (they do not cross). */
    int (*higher)(void *ctx, uint32_t a, uint32_t b);
} planar_traits;

/* The successor of half-edge h around its face: at v = h's head, the half-edge just clockwise
 * of h's twin in v's counter-clockwise list. */
static inline uint32_t planar_next(const uint32_t *off, const uint32_t *out, const uint32_t *pos,
                                   uint32_t v, uint32_t h)
{
    uint32_t t = h ^ 1, d = off[v + 1] - off[v], i = pos[t];
    return out[off[v] + (i == 0 ? d - 1 : i - 1)];
}

/* Sorts out[off[v] .. off[v + 1]) of vertices [v0, v1) counter-clockwise by T->around and sets
 * pos[h].  Returns 0, or -1 when two half-edges of a vertex leave in the same direction. */
int planar_sort_around(const planar_traits *T, const uint32_t *off, uint32_t *out, uint32_t *pos,
                       size_t v0, size_t v1);

/* The cycles of the successor map next over nh half-edges, numbered in the order of their
 * smallest half-edge: cyc_of[h] (nh), hes (nh: each cycle's half-edges in walk order, from its
 * smallest), hoff (room for nh + 1: *ncyc + 1 offsets into hes).  Returns 0, or -2 when next
 * is not a permutation (a bug of the caller). */
int planar_cycles(size_t nh, const uint32_t *next, uint32_t *cyc_of, uint32_t *hes, uint32_t *hoff,
                  size_t *ncyc);

/* The slab index of planar_place: ns vertical slabs of equal width over [x0, x0 + ns w); each
 * lists the items whose closed span meets it (off: ns + 1 offsets into item). */
typedef struct planar_slabs {
    double x0, w;
    size_t ns;
    uint32_t *off, *item;
} planar_slabs;

/* For each query k < nq: best[k] = the edge e (ecomp[e] != k) with T->below(e, k) that is
 * highest by T->higher, or PLANAR_NONE.  elo/ehi: each edge's conservative horizontal span
 * (the exact edge lies within it); qlo/qhi: each query point's.  Edges whose span misses the
 * query's are not asked.  Returns 0, or -1 out of memory. */
int planar_place(const planar_traits *T, size_t ne, const double *elo, const double *ehi,
                 const uint32_t *ecomp, size_t nq, const double *qlo, const double *qhi,
                 uint32_t *best);

#endif
