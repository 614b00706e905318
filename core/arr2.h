/* arr2.h — the planar arrangement of line segments (the 2D pipeline of DESIGN.md).
 *
 * arr2_build() snaps the segments to an integer grid, finds every crossing with exact
 * predicates, snap-rounds (every segment is split at every hot pixel it passes through, so
 * rounding never creates a crossing), merges collinear overlaps and duplicates, removes
 * bridges and dangling trees (unless keep_dangling), and walks the faces.  Components lying
 * inside a face of another component become holes of that face.
 *
 * Threads: arr2_build() is reentrant; it starts opts->threads worker threads of its own and
 * joins them before returning.  No globals.
 * Ownership: the caller owns the lar2 it passes; arr2_build() fills it, lar2_free() frees it.
 */
#ifndef CELLAR_ARR2_H
#define CELLAR_ARR2_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

enum {
    ARR_OK = 0,
    ARR_EINVAL = 1,    /* bad input: non-finite number, bad option */
    ARR_ELIMIT = 2,    /* input beyond a documented limit (size, precision vs extent) */
    ARR_ENOMEM = 3,    /* out of memory */
    ARR_ECANCELED = 4, /* *opts->cancel became non-zero */
    ARR_EINTERNAL = 5  /* an invariant of ours failed: a bug, reported rather than crashing */
};

/* Limits, documented in README.md. */
#define ARR2_MAX_SEGMENTS 20000000u /* input segments */
#define ARR2_GRID_BITS    38        /* extent / precision must be <= 2^ARR2_GRID_BITS */

typedef struct arr2_opts {
    double precision;         /* grid step in input units; 0: default, the power of two
                                 closest above extent * 2^-ARR2_GRID_BITS */
    int keep_dangling;        /* keep bridges and dangling trees (and their vertices) */
    int threads;              /* worker threads; <= 0: number of online CPUs */
    const atomic_int *cancel; /* borrowed, may be NULL: non-zero asks to stop */
    /* may be NULL: told the stage running ("snap", "buckets", "intersect", "split",
     * "biconnected", "faces") and the fraction of it done, 1 at its end */
    void (*progress)(void *udata, const char *stage, double fraction);
    void *udata; /* passed to progress */
    /* Provenance (may be NULL): a tag per input segment (borrowed, n of them).  Then each edge
     * of the result lists the tags of the input segments lying on it an odd number of times
     * (lar2.etag_off / etag): through snapping, splitting and the merging of collinear overlaps,
     * so that crossing an edge changes exactly the inputs whose tags it lists (the 2D Booleans
     * need nothing else). */
    const uint32_t *tags;
    /* With tags, non-zero: each edge lists the tags whose segments lie on it with a non-zero
     * signed count, the segments running EV[2e] -> EV[2e+1] counted +1, the other way -1
     * (lar2.etagw), so that crossing an edge from its right to its left changes each listed
     * input's winding number by that count (the fill rules; tags below 2^31).  Its parity is
     * the even-odd rule's. */
    int signed_tags;
    /* Non-zero: a vertex that an input endpoint snapped to is written with that endpoint's
     * input coordinates (the first such endpoint in input order: segment i's start is 2i, its
     * end 2i+1); only the other vertices (crossings) are grid values.  Zero: all are grid
     * values.  Topology is the grid's either way (lar2.VG). */
    int input_coords;
    /* Non-zero: the lar2 keeps the planar kernel's half-edges (lar2.he_*), for a caller that
     * walks the complex by them (the 2D Booleans); zero: they are freed with the build. */
    int half_edges;
} arr2_opts;

typedef struct arr2_stats {
    size_t input_segments;   /* segments given */
    size_t zero_length;      /* dropped: zero length after snapping */
    size_t intersections;    /* proper crossings found between pairs of segments */
    size_t hot_pixels;       /* distinct snapped points (endpoints and crossings) */
    size_t pairs_tested;     /* candidate pairs given to the exact test */
    size_t buckets;          /* leaves of the box-kd-tree */
    size_t dangling_removed; /* edges removed as bridges or dangling trees */
    size_t nv, ne, nf;       /* result counts (nf: bounded faces) */
    size_t components;       /* connected components of the result */
    size_t blocks;           /* biconnected components of the result */
    double precision;        /* grid step used */
    double ms_snap, ms_buckets, ms_intersect, ms_split, ms_graph, ms_biconnected, ms_faces,
        ms_holes, ms_total;
} arr2_stats;

/* The 2-complex.  All arrays are owned by the struct.  Cycles (vertex lists) live in one CSR
 * table: cycle c is cyc[cyc_off[c] .. cyc_off[c+1]).  A cycle may repeat a vertex (a walk
 * through a cut vertex). */
typedef struct lar2 {
    size_t nv;
    double *V; /* 2*nv: x, y; in the order of their grid points VG (x, then y); distinct */
    size_t ne;
    uint32_t *EV;         /* 2*ne: v0 < v1; sorted */
    size_t nf;            /* bounded faces */
    uint32_t *face_cycle; /* nf: the face's outer cycle (counter-clockwise) */
    uint32_t *hole_off;   /* nf+1: holes of face f are hole_cyc[hole_off[f]..hole_off[f+1]) */
    uint32_t *hole_cyc;   /* cycle ids of holes (clockwise) */
    uint32_t *fe_off;     /* nf+1 */
    int32_t *fe;          /* signed edges ±(e+1) of each face, outer cycle then holes;
                             an edge walked both ways (dangling) cancels and is left out */
    size_t ncyc;
    uint32_t *cyc_off; /* ncyc+1 */
    uint32_t *cyc;     /* vertex ids */
    size_t next;
    uint32_t *ext_cyc;  /* cycles bounding the unbounded face (clockwise) */
    int64_t *VG;        /* 2*nv: the vertices' grid coordinates (V = (origin + VG) * step, or the
                           input's coordinates with input_coords); exact predicates use these */
    uint32_t *etag_off; /* with opts.tags: ne+1, edge e's tags are etag[etag_off[e]..] */
    uint32_t *etag;     /* ascending, each an input tag lying on e an odd number of times
                           (with signed_tags: with a non-zero signed count) */
    int32_t *etagw;     /* with signed_tags: the signed count of each etag entry */
    /* With opts.half_edges, the kernel's half-edges as the build made them (else NULL):
     * half-edge h is edge h/2 leaving EV[h] (2e runs EV[2e] -> EV[2e+1], 2e+1 back). */
    uint32_t *he_face; /* 2*ne: the face on h's left: a bounded face f < nf, or nf (unbounded) */
    uint32_t *he_off;  /* nv+1: the half-edges leaving v are he_out[he_off[v] .. he_off[v+1]), */
    uint32_t *he_out;  /*       counter-clockwise from the direction +x (exact, on VG) */
    uint32_t *he_pos;  /* 2*ne: h's place in its tail's he_out list */
    arr2_stats stats;
} lar2;

/* Builds the arrangement of n segments seg[4i..4i+3] = x1, y1, x2, y2 (borrowed).
 * Returns ARR_OK and fills *out, or an error code with a message in err (errlen bytes, may
 * be 0) and *out zeroed.  An input with no non-degenerate segment gives an empty complex. */
int arr2_build(const double *seg, size_t n, const arr2_opts *opts, lar2 *out, char *err,
               size_t errlen);

/* Frees what arr2_build() allocated; safe on a zeroed or already freed lar2. */
void lar2_free(lar2 *c);

/* Frees the half-edges only (lar2.he_*: NULL after), once the caller has walked them. */
void lar2_free_half_edges(lar2 *c);

/* Signed area of a cycle (shoelace), in input units. */
double lar2_cycle_area(const lar2 *c, uint32_t cycle);

#endif
