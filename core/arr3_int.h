/* arr3_int.h — what the three files of the 3D arrangement share (not a public interface):
 *   arr3.c        the input (snapping, pieces, planes), candidate pairs, cuts, the driver;
 *   arr3_plane.c  the exact arrangement of one plane;
 *   arr3_cells.c  the 3-cells (fans about edges, shells, nesting) and the lar3 it returns.
 *
 * Vocabulary.
 *   vertex  an input vertex on the grid (int64 triple, centred on oi); equal triples are one.
 *   piece   a planar polygon of the input: an input face whose vertices lie exactly in one
 *           plane, or one triangle of a face that does not.  It has cycles of vertex ids (the
 *           first its outer one) and, for each cycle entry, the "vertical" plane through that
 *           edge parallel to the axis its plane's normal is largest on (the edge's line in the
 *           piece's plane is the two planes' intersection).
 *   plane   an exact integer plane, canonical (reduced, first non-zero normal component > 0),
 *           so that two pieces are coplanar exactly when their plane ids are equal.
 *   point   an xpt (core/pred.h); ids below nv are the vertices (GRID).
 *   cut     a segment where two pieces meet (of different solids, or of one solid that passes
 *           through itself there), on the line where their planes meet: it is given to both
 *           planes, each with the other as its side plane.  A point where they only touch is a
 *           contact point, given to both planes too.
 */
#ifndef CELLAR_ARR3_INT_H
#define CELLAR_ARR3_INT_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "core/arr3.h"
#include "core/mem.h"
#include "core/pred.h"
#include "core/util.h"

#define NONE UINT32_MAX
/* A stage of the pipeline: a function of its own in profiles (perf, callgrind), never inlined. */
#define A3_STAGE __attribute__((noinline))
/* A developer's build (make OPT='-O2 -DA3_PROF') prints each step's wall time on stderr. */
#ifdef A3_PROF
void a3_prof(const char *name);
#define A3_TICK(name) a3_prof(name)
#else
#define A3_TICK(name) ((void)0)
#endif

/* The last member of a struct kept in an array by worker or by task (a worker's scratch, a
 * task's output): 64 bytes of nothing, so that no cache line holds two neighbours' members.
 * Without it two workers writing their own counters write one line between them, which
 * ping-pongs between the cores on every write (the 3D volumes ran slower on two threads than
 * on one). */
#define A3_PAD char a3_pad_[64]

/* Is a worker's hash table, grown by one large plane, too large for the one just used (cap
 * slots, used of them)?  Then it is freed and made small again by its next insert, rather than
 * cleared whole before each small plane after it (fandisk: 10 % of a run).  pset_clear and
 * arr3_plane.c's lp_reset. */
static inline int a3_table_oversized(size_t cap, size_t used)
{
    return cap > 256 && 16 * used < cap;
}

/* The side plane of an edge between two input vertices whose plane needs no arrangement: not
 * made (nor added to the planes) unless asked for, by a3_side(). */
#define SIDE_LAZY (NONE - 2)

typedef struct piece {
    uint32_t solid;  /* solid index (in a soup: the input face, so that faces meet each other) */
    uint32_t face;   /* input face (index over all solids) */
    uint32_t plane;  /* canonical plane id, or NONE while the piece needs none (nothing reaches
                        it: its anchor plane serves) */
    uint32_t c0, nc; /* cycles pc_off[c0 .. c0 + nc) */
    uint32_t av[3];  /* three of its vertices spanning its plane: the anchor plane is the raw
                        plane through them (plane_through_raw) */
    int32_t box[6];  /* lo xyz, hi xyz (grid coordinates fit 32 bits) */
    int8_t sgn;      /* +1: the order of its outer cycle turns about the normal of its plane
                        (the canonical one once it has it, else the anchor plane's); for a solid
                        that normal then points out of it.  -1: the other way */
    uint8_t reached; /* goes through its plane's arrangement (a cut, a contact, a coplanar
                        piece of another solid, holes, or a surface touching itself there) */
    uint8_t cls;     /* its chart class (arr3_pairs.c): 2 k, plus 1 when it turns counter-
                        clockwise about axis k, the axis of its normal's largest component */
    uint8_t cmask;   /* bit 2 k + 1 (2 k) when it turns counter-clockwise (clockwise) about
                        axis k, for each axis its plane is not parallel to */
    uint8_t pad_[4]; /* to 64 bytes: an index times a power of two, a piece in one cache line
                        wherever the array starts on one */
} piece;
_Static_assert(sizeof(piece) == 64, "a piece is 64 bytes");

typedef struct cseg {
    uint32_t plane, p0, p1, side;
} cseg;

typedef struct cpt {
    uint32_t plane, p;
} cpt;

/* The faces of one plane's arrangement (arr3_plane.c), in that plane's own point numbering:
 * ids below the plane's base are global points, from base on they are the plane's new points. */
typedef struct pfaces {
    uint32_t nf, ncyc, nent, ncov, nnew;
    uint32_t *f_cyc;   /* nf+1: face f has cycles f_cyc[f] .. f_cyc[f+1] (outer first) */
    uint32_t *cyc_off; /* ncyc+1 */
    uint32_t *ent;     /* point of each cycle entry */
    uint32_t *side;    /* side plane of the edge from each entry to the next (NONE: none) */
    uint32_t *f_cov;   /* nf+1 */
    uint32_t *cov;     /* pieces covering each face */
    xpt *newp;         /* nnew new points (crossings) */
    uint32_t base;     /* ent >= base: newp[ent - base] */
    int trivial;       /* simple pieces of one solid turning one way, nothing else: each piece is a
                          face as it is (no arrays) */
    uint32_t *direct;  /* else, pieces that nothing reaches: each a face as it is */
    uint32_t ndirect;
} pfaces;

void pfaces_free(pfaces *f);

/* The whole state of one arrangement. */
typedef struct a3 {
    const arr3_opts *o;
    int threads;
    arr3_stats *st;
    double step;   /* grid step */
    int64_t oi[3]; /* world = (oi + g) * step */
    int soup;
    /* vertices */
    int64_t *g;
    size_t nv, capv;
    /* planes (canonical, deduplicated by a hash) */
    plane3 *pl;
    size_t npl, cappl;
    uint32_t *pltab;
    size_t plcap;
    uint64_t *vpkey; /* the vertical plane of each (edge, axis) seen: key -> vpval */
    uint32_t *vpval;
    size_t vpcap, nvp;
    /* pieces and their cycles */
    piece *pc;
    size_t npc, cappc;
    uint32_t *pc_off; /* npcyc+1 */
    size_t npcyc, cappc_off;
    uint32_t *pcv;   /* vertex ids */
    uint32_t *pcvp;  /* vertical plane of each entry's edge */
    uint32_t *ptwin; /* by entry: the entry of another piece of the same solid walking its edge
                        the other way, the edge's only other one in that solid; NONE if none */
    size_t npcv, cappcv, cappcvp, capptwin;
    uint32_t *rl; /* the reached pieces, ascending (stage_cuts, once no piece is reached later) */
    size_t nrl, caprl, unreached_ent; /* and the entries of the others, one cycle each */
    uint8_t *twinned; /* by solid: its entries' twins came with the input (arr3_build_ex) */
    size_t nfaces;    /* input faces */
    uint32_t *solid_face_off;
    size_t nsolids;
    size_t split_faces; /* input faces split into triangles */
    uint64_t *selfp;    /* the pairs of one solid's pieces that meet (a surface passing through
                           itself), in pair order */
    uint32_t *selfpt;   /* by such pair: a point where they meet, or NONE (overlapping) */
    size_t nselfp, capselfp, capselfpt;
    uint32_t *fold; /* planes where pieces of one solid overlap (arranged whole), ascending */
    size_t nfold, capfold;
    cpt *dcp; /* contacts of left-out faces: (piece, point), given to the piece's
                 plane once it has one */
    size_t ndcp, capdcp;
    /* points */
    xpt *pt;
    size_t npt, cappt;
    geo G;
    /* per plane: pieces, cuts, contact points (CSR over plane ids) */
    uint32_t *pp_off, *pp;
    cseg *cs;
    size_t ncs, capcs;
    cpt *cp;
    size_t ncp, capcp;
    uint32_t *cs_off, *cp_off;
    /* the planes' arrangements */
    pfaces *pf;
    /* the faces of the complex, global point ids */
    size_t nf;
    uint32_t *f_plane;
    uint32_t *f_cyc;   /* nf+1 */
    uint32_t *cyc_off; /* ncyc+1 */
    size_t ncyc;
    uint32_t *ent, *side;
    size_t nent;
    uint32_t *f_cov, *cov;
    /* units of the faces: a patch (pieces that nothing reached, linked across their twins:
     * faces units[0 .. npatch) in order), then every other face a unit of its own */
    size_t npatch, nunit;
    uint32_t *u_off;  /* nunit + 1: unit u holds faces u_off[u] .. u_off[u + 1) */
    uint32_t *f_unit; /* by face */
    uint8_t *f_out;   /* by face of a patch: 1 when its normal points out of its solid */
    uint32_t *etwin;  /* by cycle entry of a patch's face: the entry walking the same edge in
                         the patch's other face (an edge inside the patch), else NONE */
} a3;

/* Piece P's three vertices when it is a triangle (one cycle of 3 entries), else NULL. */
static inline const uint32_t *a3_piece_tri(const a3 *A, const piece *P)
{
    uint32_t o = A->pc_off[P->c0];
    return P->nc == 1 && A->pc_off[P->c0 + 1] - o == 3 ? A->pcv + o : NULL;
}

/* ---- shared tools (arr3.c) ------------------------------------------------------------- */

/* Are items a and b equal? (a3_firsts) */
typedef int (*a3_eq_fn)(const void *ctx, uint32_t a, uint32_t b);
int a3_firsts(int threads, size_t n, const uint64_t *hash, a3_eq_fn eq, const void *ctx,
              uint32_t *first);
#define A3_PUSH(arr, n, cap, val)                                                                  \
    (mem_grow(&(arr), &(cap), (n) + 1, sizeof *(arr)) ? -1 : ((arr)[(n)++] = (val), 0))
uint64_t a3_mix64(uint64_t x);
/* The first piece after piece i of another solid (A->npc if none): the pieces come solid by
 * solid, so it is found by bisection. */
size_t a3_solid_end(const a3 *A, size_t i);
int a3_cancelled(const a3 *A);
void a3_progress(const a3 *A, const char *stage, double f);

/* A part [lo, hi] of a stage, for par_for_ex's tick: a3_span_tick(span, f) reports the stage at
 * lo + (hi - lo) * f. */
typedef struct a3_span {
    const a3 *A;
    const char *stage;
    double lo, hi;
} a3_span;
void a3_span_tick(void *span, double f);

/* Deduplication of points by position: a hash over cells of one grid unit, exact equality
 * inside.  Points are added with their id; pset_find returns the id of an equal point or NONE. */
typedef struct pset {
    uint64_t *key;  /* cell hash keys (0: empty) */
    uint32_t *head; /* first id of each slot's list */
    size_t cap, n;
    uint32_t *next; /* by id - base: next id in the same slot */
    size_t capnext;
    uint32_t base;
} pset;

void pset_clear(pset *s, uint32_t base);
void pset_free(pset *s);
/* pts(id) gives the point of an id. */
typedef const xpt *(*pset_get)(const void *ctx, uint32_t id);
uint32_t pset_find(const pset *s, const geo *G, const xpt *p, pset_get get, const void *ctx);
int pset_add(pset *s, const xpt *p, uint32_t id);

/* Triangulates the polygon with cycles cyc[0..nc) (vertex ids, lengths len[]; the first the
 * outer one) projected along axis k; appends 3 vertex ids per triangle to *tri.  Cycles may
 * touch at vertices they share (the inside then maybe in parts).  Returns 0, -1 (out of memory)
 * or -2 (not a polygon with holes in that projection). */
int a3_triangulate(const a3 *A, int k, uint32_t **cyc, const size_t *len, size_t nc, uint32_t **tri,
                   size_t *ntri, size_t *captri);

/* Does plane P keep its pieces as they are (nothing from another solid reaches it; simple
 * pieces of one solid turning one way)?  Such a plane's pieces skip the plane arrangement and
 * their edges' side planes are made only when asked for (SIDE_LAZY). */
int a3_plane_simple(const a3 *A, uint32_t P);
/* Do pieces of one solid overlap in plane P (A->fold)?  Then all its pieces are arranged. */
int a3_plane_fold(const a3 *A, uint32_t P);

/* The side plane of the edge from point a to point b of a face on plane FP with side entry S:
 * A->pl[S], or, for S == SIDE_LAZY (a and b input vertices), that vertical plane made in *tmp.
 * NULL when S is NONE (an edge with no side: a contact hole). */
const plane3 *a3_side(const a3 *A, const plane3 *FP, uint32_t a, uint32_t b, uint32_t S,
                      plane3 *tmp);

/* The plane of piece pi: its canonical plane, or its anchor plane made in *tmp. */
const plane3 *a3_piece_plane(const a3 *A, uint32_t pi, plane3 *tmp);

/* The plane of face f of the complex (A->f_plane[f], or for a face that is a piece kept whole
 * without a canonical plane, that piece's anchor plane, made in *tmp): f's cycles turn
 * counter-clockwise about its normal. */
const plane3 *a3_face_plane(const a3 *A, uint32_t f, plane3 *tmp);
/* Its normal only (as a3_face_plane's), into n[3]: no offset, no doubles. */
void a3_face_normal(const a3 *A, uint32_t f, int64_t *n);

/* The candidate pairs: pieces of different solids whose closed boxes meet, and pieces of one
 * solid whose boxes meet and that self_apart could not tell apart, each pair once as (lower id
 * << 32 | higher id), sorted (arr3_pairs.c: a bounding-volume hierarchy per solid).  Returns
 * 0, -1 out of memory, or -3 cancelled. */
int a3_pairs(const a3 *A, uint64_t **out, size_t *nout);

/* The chart class of a piece whose outer cycle turns sgn about normal n (piece.cls), and in
 * *mask its piece.cmask. */
static inline uint8_t a3_chart_class(const int64_t *n, int sgn, uint8_t *mask)
{
    int k = 0;
    *mask = 0;
    for (int t = 0; t < 3; t++) {
        int64_t a = n[t] < 0 ? -n[t] : n[t], b = n[k] < 0 ? -n[k] : n[k];
        if (a > b) k = t;
        if (n[t]) *mask |= (uint8_t)(1u << (2 * t + ((n[t] > 0) == (sgn > 0))));
    }
    return (uint8_t)(2 * k + ((n[k] > 0) == (sgn > 0)));
}

/* Pairs of pieces of one solid (arr3_pairs.c).  Is vertex v on the outer cycle of piece P?  Is
 * {a, b} an edge of it? */
int a3_piece_vertex(const a3 *A, const piece *P, uint32_t v);
int a3_piece_edge(const a3 *A, const piece *P, uint32_t a, uint32_t b);
/* Pieces p and q of one solid in one plane: 1 when they meet only in the vertices and edges
 * they share, lying on the two sides of each shared edge (as neighbouring faces of one flat
 * stretch of a surface do); 2 when they also touch elsewhere on their boundaries (a vertex of
 * one inside an edge of the other, edges along one line), 0 when they overlap (or have holes
 * or many edges).  Exact.  Their plane is arranged whole unless 1. */
int a3_flat_apart(const a3 *A, uint32_t p, uint32_t q);

/* ---- the stages ------------------------------------------------------------------------ */

/* Arranges every plane (in parallel); fills A->pf.  Returns ARR_OK or an ARR_* code. */
int a3_planes(a3 *A, char *err, size_t errlen);

/* From A's faces: the edges, the fans, the shells, the cells, and the lar3. */
int a3_cells(a3 *A, lar3 *out, char *err, size_t errlen);

#endif
