/* box.h — the box-kd-tree of the seeds ("Construction of independent buckets"): the bucket
 * index over boxes, in 2 or 3 dimensions.
 *
 * Boxes (closed, integer: lo[0..dim), hi[0..dim); in 2D x0, y0, x1, y1) are split at the mean
 * of their centres along one axis; a box goes below when its min <= t and above when its max >
 * t, so boxes straddling t go to both sides.  Where the seeds alternate y then x and stop when a
 * split removes fewer than 7 boxes, we try every axis, keep the one whose larger side is
 * smaller, and stop when none removes an eighth of the boxes (or the bucket is small): long thin
 * boxes (a grid of full-length lines) then still end in small buckets.
 *
 * Every leaf has a region, the half-open box (lo, hi] per axis (root: all of R^dim); the regions
 * partition the space, and a leaf holds every box that meets its region.  So a point lies in
 * exactly one leaf, and every box containing that point is in that leaf: this is what lets
 * a pair of boxes be tested in exactly one bucket (the one holding the corner (max x0, max y0)
 * of their intersection) and a point be located with box_tree_locate().  The thresholds are
 * doubles and the boxes integers below 2^53 (exact as doubles): a point given exactly as
 * doubles is located exactly.
 *
 * Users: arr2's split and facecheck (2D: pairs of boxes in one bucket, points located), the
 * probes of arr3_cells (2D, the pieces' boxes in a probe's projection: a point located).  The
 * 3D pair walk of arr3_pairs keeps its own BVH: a tree-against-tree walk of Morton-ordered
 * pieces, which must always split (pieces of one plane, a shell inside its mesh) and prunes
 * whole subtrees of two surfaces at once, where buckets that duplicate straddling boxes
 * compare every pair of a bucket that no split separates (see arr3_pairs.c).
 *
 * Ownership: box_tree_build*() fill a caller-provided box_tree; box_tree_free() frees it.
 * Threads: a built tree is read-only; the build uses two threads at most (box_tree_build_par).
 */
#ifndef CELLAR_BOX_H
#define CELLAR_BOX_H

#include <stddef.h>
#include <stdint.h>

#define BOX_DEPTH_MAX 60 /* levels of nodes at most below the root */
#define BOX_DIM_MAX   3

typedef struct box_node {
    double t;         /* threshold */
    int32_t axis;     /* 0: x, 1: y, 2: z */
    int32_t child[2]; /* below, above; >= 0 node index, < 0 leaf ~index */
} box_node;

typedef struct box_tree {
    int dim; /* 2 or 3 */
    size_t nleaves;
    uint32_t *leaf_off; /* nleaves+1: leaf l holds items[leaf_off[l] .. leaf_off[l+1]) */
    uint32_t *items;    /* box indices, ascending within a leaf */
    double *region;     /* 2 dim per leaf: lo[dim], hi[dim] of (lo, hi] (2D: xlo, ylo, xhi, yhi) */
    size_t nnodes;
    box_node *nodes; /* nodes[0] is the root when nnodes > 0 */
} box_tree;

/* Builds the tree of n boxes of dimension dim (2 or 3; box[2 dim i ..] = lo[dim], hi[dim],
 * borrowed) with buckets of about leaf_max boxes, the two sides of the root split built on two
 * threads when threads > 1 and there are enough boxes (the same tree, node for node).  Returns
 * 0, or -1 when out of memory (t is then zeroed). */
int box_tree_build_dim(box_tree *t, int dim, const int64_t *box, size_t n, size_t leaf_max,
                       int threads);

/* 2D: box[4i..4i+3] = x0, y0, x1, y1 (box_tree_build_dim with dim 2, on one thread). */
int box_tree_build(box_tree *t, const int64_t *box, size_t n, size_t leaf_max);

/* 2D, on threads threads (box_tree_build_dim with dim 2). */
int box_tree_build_par(box_tree *t, const int64_t *box, size_t n, size_t leaf_max, int threads);

/* The leaf whose region contains point (x, y) of a 2D tree. */
uint32_t box_tree_locate(const box_tree *t, double x, double y);
/* The leaf whose region contains point p[0..dim). */
uint32_t box_tree_locate_pt(const box_tree *t, const double *p);

void box_tree_free(box_tree *t);

#endif
