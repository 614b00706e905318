/* planar.h — the half-edge kernel of a planar arrangement (issue 30, item 1).
 *
 * One topology for the two planar arrangements of the house: arr2's grid points (int64
 * coordinates, core/arr2.c) and the points of one plane of the 3D pipeline (implicit points
 * projected, core/arr3_plane.c).  The kernel knows half-edges and vertices by number only; every
 * geometric question goes to the model's traits, exact predicates:
 *   around    the order of two half-edges leaving one vertex (counter-clockwise);
 *   espan,    the horizontal key spans of edges and of query points (for the placement's
 *   qspan     slab index: conservative, the exact geometry lies within them);
 *   scan      of some candidate edges, the first a downward vertical ray from a component's
 *             lowest point meets (the model's exact tests, in its own tight loop).
 * Numbering (both models): edge e has half-edges 2e and 2e + 1; a vertex's outgoing half-edges
 * are out[off[v] .. off[v + 1]).  After planar_sort_around they run counter-clockwise and
 * pos[h] is h's place in its vertex's list; next(h) is, at h's head, the half-edge just
 * clockwise of h's twin (planar_next), so every cycle has its face on its left.  Cycles are
 * numbered in the order of their smallest half-edge (planar_cycles), the walk order of both
 * models before the kernel, so their output is unchanged.
 *
 * Placement (planar_place) answers, for each component's query point, the first edge of
 * another component a downward ray meets, from a slab index: the edges are listed in the
 * vertical slabs their horizontal key span meets (keys: int64, monotone in the model's x), and
 * each query scans the edges of its slab(s) only, not every edge.  Both the index and the queries
 * run by chunks on par_for (core/par.h) when given threads.
 *
 * Threads: reentrant, no globals; the traits' context is only read, but for what the model's
 * scan writes by query (each query is one worker's).  Ownership: inputs are borrowed; outputs
 * are the caller's arrays; planar_ws is the caller's scratch (planar_ws_free).
 */
#ifndef CELLAR_PLANAR_H
#define CELLAR_PLANAR_H

#include <stddef.h>
#include <stdint.h>

#define PLANAR_NONE UINT32_MAX

/* A model's exact predicates (ctx is passed back to each); the placement's are needed only by
 * planar_place, around only by planar_sort_around. */
typedef struct planar_traits {
    void *ctx;
    /* < 0 when half-edge a comes before b counter-clockwise around their common tail (from the
     * model's reference direction), > 0 after; 0 only when they leave in the same direction. */
    int (*around)(void *ctx, uint32_t a, uint32_t b);
    /* The key spans of edges [e0, e1): lo[i] <= hi[i] for edge e0 + i.  Keys are monotone
     * (non-decreasing) in the model's x and an edge's span holds the keys of all its points. */
    void (*espan)(void *ctx, size_t e0, size_t e1, int64_t *lo, int64_t *hi);
    /* The key span of query q's point. */
    void (*qspan)(void *ctx, uint32_t q, int64_t *lo, int64_t *hi);
    /* Of best (PLANAR_NONE, or what an earlier scan for q returned) and the edges cand[0 .. n)
     * (ascending), the edge of another component than q that the downward vertical ray from
     * q's point meets first (strictly below the point); best when none comes first. */
    uint32_t (*scan)(void *ctx, uint32_t q, const uint32_t *cand, size_t n, uint32_t best);
    /* May be NULL.  Polled by worker wk after `work` units (edges, candidates): non-zero stops
     * the placement (planar_place returns 1; the model knows why). */
    int (*stop)(void *ctx, int wk, size_t work);
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
 * smallest), *hoff (*ncyc + 1 offsets into hes: a growable array of *caphoff, core/mem.h's
 * mem_grow, so that it holds what the cycles need, not nh + 1).  Returns 0, -1 out of memory,
 * or -2 when next is not a permutation (a bug of the caller). */
int planar_cycles(size_t nh, const uint32_t *next, uint32_t *cyc_of, uint32_t *hes, uint32_t **hoff,
                  size_t *caphoff, size_t *ncyc);

/* planar_place's scratch, kept between calls (zero-initialise; planar_ws_free). */
typedef struct planar_ws {
    uint32_t *es, *off, *item, *cnt;
    uint64_t *ctot;
    size_t capes, capoff, capitem, capcnt, capctot;
} planar_ws;

/* For each query q < nq: best[q] = T->scan's answer over the edges whose key span meets q's
 * (PLANAR_NONE: nothing below).  kmin, kmax: the least and greatest key of the edges.
 * threads: par_for's (1: all on the calling thread).  Returns 0, -1 out of memory, or 1
 * stopped by T->stop (best then unspecified). */
int planar_place(const planar_traits *T, int threads, planar_ws *ws, size_t ne, int64_t kmin,
                 int64_t kmax, size_t nq, uint32_t *best);
void planar_ws_free(planar_ws *ws);

#endif
