/* arr3.h — the arrangement of solids given as face models (the 3D pipeline of DESIGN.md).
 *
 * arr3_build() takes validated solids (solid_check()'s fixed copies: closed, outward oriented)
 * or one face soup, and returns the 3-complex of the partition of space they induce:
 *   1. unification: every vertex is snapped to one integer grid of step `precision`, and equal
 *      grid points become one vertex;
 *   2. bucketing: a box-kd-tree of the faces' boxes gives the candidate pairs of faces;
 *   3. intersection: faces lying in one plane (within the precision) form one plane group; for
 *      each pair of faces of different groups the segment(s) where they cut each other are
 *      computed once, in 3D, and shared by both groups, as are the faces' own edges; each plane
 *      group is split by a 2D arrangement (arr2) in its plane, projected on the two coordinates
 *      that drop the largest normal component (so grid points stay exact).  A point where a
 *      group's arrangement splits a shared segment is added to that segment for every group
 *      that uses it, and the groups concerned run again, until no group splits anything new:
 *      neighbouring faces then agree exactly on every vertex and edge;
 *   4. reconstruction: the faces around each edge are sorted by exact angle (integer normals,
 *      256-bit determinants); the face sides around edges give the shells; the shell of negative
 *      volume of each connected part is its outside, and it is attached, by a ray, to the cell of
 *      another part that contains it (a cavity) or to the exterior.
 *
 * Threads: reentrant, no globals; plane groups run on opts->threads threads.
 * Ownership: inputs borrowed; the caller owns the lar3 it passes, lar3_free() frees it.
 */
#ifndef CELLAR_ARR3_H
#define CELLAR_ARR3_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "core/arr2.h" /* ARR_* codes */
#include "core/solid.h"

#define ARR3_GRID_BITS  30       /* extent / precision must be <= 2^ARR3_GRID_BITS */
#define ARR3_MAX_FACES  2000000u /* input faces, all solids together */
#define ARR3_MAX_ROUNDS 32       /* rounds of the plane-group arrangements before giving up */
#define ARR3_RETRIES    3        /* runs again on a grid twice as coarse (see arr3_build) */

typedef struct arr3_opts {
    double precision; /* grid step; 0: the power of two closest above extent * 2^-ARR3_GRID_BITS
                         (extent: the largest side of the input's box) */
    int threads;      /* <= 0: number of online CPUs */
    const atomic_int *cancel;
    void (*progress)(void *udata, const char *stage, double fraction);
    void *udata;
} arr3_opts;

typedef struct arr3_stats {
    size_t input_solids, input_faces;
    size_t planes;          /* plane groups */
    size_t coplanar_groups; /* plane groups holding faces of more than one input face */
    size_t pairs_tested;    /* candidate face pairs from the box-kd-tree */
    size_t cuts;            /* cut segments between faces */
    size_t rounds;          /* rounds of plane-group arrangements until stable */
    size_t nv, ne, nf, nc;  /* result counts (nc: bounded cells) */
    size_t shells, components;
    double precision;
    double ms_snap, ms_pairs, ms_cuts, ms_faces, ms_cells, ms_total;
} arr3_stats;

/* The 3-complex.  Face f's cycles are fc[fc_off[f] .. fc_off[f+1]), the first its outer cycle
 * (counter-clockwise seen from the tip of its normal), the others holes (clockwise); cycle c is
 * cyc[cyc_off[c] .. cyc_off[c+1]).  Signed indices are ±(i+1). */
typedef struct lar3 {
    size_t nv;
    double *V; /* 3*nv */
    size_t ne;
    uint32_t *EV; /* 2*ne, v0 < v1, sorted */
    size_t nf;
    double *FN;         /* 3*nf: unit normal of each face (its orientation) */
    uint32_t *fc_off;   /* nf+1 */
    uint32_t *fc;       /* cycle ids */
    uint32_t *fe_off;   /* nf+1 */
    int32_t *fe;        /* signed edges of each face (+: walked from EV[0] to EV[1]) */
    uint32_t *fsrc;     /* nf: the input face (index over all solids' faces) it lies on */
    uint32_t *fsol_off; /* nf+1: the solids whose surface holds face f (an odd number of their
                           faces do): fsol[fsol_off[f] .. fsol_off[f+1]), ascending; crossing f
                           goes into or out of exactly these solids */
    uint32_t *fsol;
    size_t ncyc;
    uint32_t *cyc_off; /* ncyc+1 */
    uint32_t *cyc;     /* vertex ids */
    size_t nc;         /* bounded cells */
    uint32_t *cf_off;  /* nc+1 */
    int32_t *cf;       /* signed faces: +(f+1) when f's normal points out of the cell */
    uint32_t *cv_off;  /* nc+1 */
    uint32_t *cv;      /* sorted vertex ids of each cell */
    double *cvol;      /* nc: volume of each bounded cell */
    size_t next;
    int32_t *ext;             /* signed faces of the exterior cell (same sign rule) */
    uint32_t *solid_face_off; /* nsolids+1: input faces of solid s are [off[s], off[s+1]) */
    size_t nsolids;
    arr3_stats stats;
} lar3;

/* Builds the arrangement of ns solids (borrowed; each closed and outward oriented, as
 * solid_check()'s fixed copy) or, with soup != 0, of the faces of all of them taken one by one
 * (no closedness assumed, any orientation).  Returns ARR_OK and fills *out, or an ARR_* code with
 * a message in err and *out zeroed. */
int arr3_build(const solid *solids, size_t ns, int soup, const arr3_opts *opts, lar3 *out,
               char *err, size_t errlen);

void lar3_free(lar3 *c);

/* Volume enclosed by face f's cycles as seen from its normal side's opposite (the signed
 * volume of the cone from the origin): sum over cells of ±face volume gives the cell volume. */
double lar3_face_cone(const lar3 *c, uint32_t f);

#endif
