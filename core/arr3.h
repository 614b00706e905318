/* arr3.h — the arrangement of solids given as face models (the 3D pipeline of DESIGN.md).
 *
 * arr3_build() takes validated solids (solid_check()'s fixed copies: closed, outward oriented)
 * or one face soup, and returns the 3-complex of the partition of space they induce.  The only
 * tolerance is the snapping grid: every vertex is snapped once to the grid of step `precision`
 * (equal grid points are one vertex), and from then on every decision is an exact predicate on
 * integer planes and implicit points (core/pred.h); coordinates are rounded to doubles only when
 * the result is written.
 *   1. pieces: a face whose snapped vertices lie exactly in one plane is one piece; a face that
 *      does not is split into triangles, each with its own exact plane (stats.split_faces);
 *   2. pairs: a bounding-volume hierarchy of the pieces' boxes gives the pairs of pieces of
 *      different solids, and of one solid where its surface may pass through itself;
 *   3. cuts: for each pair, where the two pieces meet on the line of their planes, exactly:
 *      segments (crossings, and contacts along an edge) and single points (a vertex on a face,
 *      edges crossing), given to both planes, so every contact becomes part of the complex;
 *   4. planes: each plane's pieces, cuts and contact points are arranged exactly in that plane
 *      (coplanar pieces of all solids together); its faces are the regions covered by pieces;
 *   5. cells: the faces around each edge are sorted exactly; the face sides give the shells;
 *      the outside shell of each connected part and the cell holding a part nested in another
 *      are found by exact rays (a line through a rational point of the part, symbolically
 *      perturbed, so that it never passes through an edge or a vertex).
 * See core/arr3.c, core/arr3_plane.c and core/arr3_cells.c.
 *
 * Threads: reentrant, no globals; planes run on opts->threads threads.
 * Ownership: inputs borrowed; the caller owns the lar3 it passes, lar3_free() frees it.
 */
#ifndef CELLAR_ARR3_H
#define CELLAR_ARR3_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "core/arr2.h" /* ARR_* codes */
#include "core/solid.h"

#define ARR3_GRID_BITS 30 /* extent / precision must be <= 2^ARR3_GRID_BITS */
/* Input faces, all solids together: the hard limit of the 32-bit numbering (a face's cycle
 * entries, its pieces, the complex's signed faces); below it, what memory allows: a run needs
 * about ARR3_BYTES_PER_FACE bytes an input face at its peak (triangle meshes, reading and
 * writing included: 1 million triangles a solid, 2 solids, peak at about 1 GB), and
 * arr3_build refuses an input whose estimate exceeds arr3_opts.max_bytes (0: the machine's
 * physical memory). */
#define ARR3_MAX_FACES      64000000u
#define ARR3_BYTES_PER_FACE 500u

typedef struct arr3_opts {
    double precision; /* grid step; 0: the power of two closest above extent * 2^-ARR3_GRID_BITS
                         (extent: the largest side of the input's box) */
    int threads;      /* <= 0: number of online CPUs */
    const atomic_int *cancel;
    /* may be NULL: told the stage running ("snap", "pairs", "cuts", "planes", "cells") and the
     * fraction of it done, 1 at its end */
    void (*progress)(void *udata, const char *stage, double fraction);
    void *udata;
    /* which optional parts of the lar3 to make: 0 for all of them, else ARR3_WANT_ONLY and
     * the ARR3_WANT_* bits of those wanted (the others are left NULL); the cells, faces, edges
     * and their numbering are always made */
    unsigned want;
    size_t max_bytes; /* the memory the run may take (0: the machine's physical memory) */
    /* 1: the caller has checked the solids (solid_check or solid_check_faces at this precision,
     * as api/solids.c does): every coordinate finite and less than 2^62 steps from the origin,
     * every vertex index in range.  The input stage then does not test these again.  0 (the
     * default): it does, and reports them as errors. */
    int checked;
} arr3_opts;

enum {
    ARR3_WANT_ONLY = 1u << 0,    /* the bits below say what is wanted */
    ARR3_WANT_COORDS = 1u << 1,  /* V (nv is always set) */
    ARR3_WANT_NORMALS = 1u << 2, /* FN and fsrc */
    ARR3_WANT_CV = 1u << 3,      /* cv_off and cv */
    ARR3_WANT_CF = 1u << 4,      /* cf_off, cf and ext */
    ARR3_WANT_FACES = 1u << 5    /* EV, the faces' cycles and edges (fc, cyc, fe): V and EV
                                    numbered (else nv and ne are only counted) */
};

typedef struct arr3_stats {
    size_t input_solids, input_faces;
    size_t planes;          /* exact planes arranged (holding pieces that meet others) */
    size_t coplanar_groups; /* of those, planes holding pieces of more than one input face */
    size_t split_faces;     /* input faces not planar on the grid, split into triangles */
    size_t pairs_tested;    /* candidate piece pairs (of different solids, boxes meeting) */
    size_t pairs_meeting;   /* of those, pairs whose pieces meet (cut, contact, coplanar overlap) */
    size_t faces_reached;   /* pieces that go through a plane arrangement (the rest kept whole) */
    size_t patches;         /* edge-connected runs of the pieces kept whole, each decided once */
    size_t cuts;            /* segments where pieces of different solids meet */
    size_t points;          /* vertices made by the arrangement (implicit, exact) */
    size_t nv, ne, nf, nc;  /* result counts (nc: bounded cells) */
    size_t shells, components;
    double precision;
    double ms_check; /* set by the caller that checked the solids (0 if none) */
    double ms_snap, ms_pairs, ms_cuts, ms_faces, ms_cells;
    double ms_boolean; /* set by the caller that ran a Boolean (0 if none) */
    double ms_total;   /* the arrangement; callers add their check and Boolean */
} arr3_stats;

/* A solid whose surface passes through itself (or overlaps itself): how many pairs of its
 * pieces cross or overlap, the first pair's input faces (indices within the solid) and a point
 * where they meet (of two overlapping in one plane: a vertex of the first). */
typedef struct arr3_selfx {
    uint32_t solid, fa, fb;
    size_t pairs;
    double at[3];
} arr3_selfx;

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
    uint32_t *fsol_off; /* nf+1: the solids whose surface holds face f, counted with the way
                           their faces turn: fsol[fsol_off[f] .. fsol_off[f+1]), ascending;
                           crossing f changes the winding numbers of exactly these solids */
    uint32_t *fsol;
    int32_t *fwind; /* by fsol entry: the solid's faces over f, each +1 when its outward normal
                       is f's normal, -1 when it is the opposite, summed (never 0); crossing f
                       the way its normal points changes that solid's winding number by
                       -fwind (a clean solid's faces: +1 each, leaving it) */
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
    /* The faces come in units: the faces of a patch (input faces that nothing reached, joined
     * edge to edge: one cell on each side of all of them), or one face.  Unit u holds faces
     * u_off[u] .. u_off[u + 1); ucell[2u] is the cell its faces' normals point into and
     * ucell[2u + 1] the cell they point out of, for a face whose frev is 0 (the other way round
     * for one whose frev is 1); nc for the exterior.  The faces of a unit have the same solids
     * (fsol). */
    size_t nunit;
    uint32_t *u_off;   /* nunit + 1 */
    uint32_t *ucell;   /* 2 nunit */
    uint8_t *frev;     /* nf */
    arr3_selfx *selfx; /* the solids that pass through themselves, ascending */
    size_t nselfx;
    arr3_stats stats;
} lar3;

/* The grid step for an input whose bounding box's largest side is `extent`: `precision` when
 * it is > 0 (ARR_ELIMIT, with a message, when extent / precision > 2^ARR3_GRID_BITS), else the
 * default, the power of two closest above extent * 2^-ARR3_GRID_BITS.  The only place the rule
 * lives: the API checks solids at the step this returns. */
int arr3_grid_step(double extent, double precision, double *step, char *err, size_t errlen);

/* The same for solids s[0..n) (borrowed): extent is the largest side of the box of every vertex
 * of every solid (a non-finite coordinate is left to the checks: it is skipped here). */
int arr3_solids_step(const solid *s, size_t n, double precision, double *step, char *err,
                     size_t errlen);

/* Builds the arrangement of ns solids (borrowed; each closed and outward oriented, as
 * solid_check()'s fixed copy) or, with soup != 0, of the faces of all of them taken one by one
 * (no closedness assumed, any orientation).  Returns ARR_OK and fills *out, or an ARR_* code with
 * a message in err and *out zeroed. */
int arr3_build(const solid *solids, size_t ns, int soup, const arr3_opts *opts, lar3 *out,
               char *err, size_t errlen);

/* The same, given for each solid (twins may be NULL, and so may each twins[s]) the pairing its
 * check found (solid_check_nocopy's twin: for each entry of its cycles, the entry walking the
 * same edge the other way), so that the arrangement does not pair the edges again. */
int arr3_build_ex(const solid *solids, size_t ns, int soup, const uint32_t *const *twins,
                  const arr3_opts *opts, lar3 *out, char *err, size_t errlen);

void lar3_free(lar3 *c);

/* Volume enclosed by face f's cycles as seen from its normal side's opposite (the signed
 * volume of the cone from the origin): sum over cells of ±face volume gives the cell volume. */
double lar3_face_cone(const lar3 *c, uint32_t f);

#endif
