/* box.h — the box-kd-tree of the seeds ("Construction of independent buckets").
 *
 * Boxes (closed, integer: x0, y0, x1, y1) are split at the mean of their centres along one
 * axis; a box goes below when its min <= t and above when its max > t, so boxes straddling t
 * go to both sides.  Where the seeds alternate y then x and stop when a split removes fewer
 * than 7 boxes, we try both axes, keep the one whose larger side is smaller, and stop when
 * neither removes an eighth of the boxes (or the bucket is small): long thin boxes (a grid of
 * full-length lines) then still end in small buckets.
 *
 * Every leaf has a region, the half-open box (lo, hi] per axis (root: all of R^2); the regions
 * partition the plane, and a leaf holds every box that meets its region.  So a point lies in
 * exactly one leaf, and every box containing that point is in that leaf: this is what lets
 * a pair of boxes be tested in exactly one bucket (the one holding the corner
 * (max x0, max y0) of their intersection) and a point be located with box_tree_locate().
 *
 * Ownership: box_tree_build() fills a caller-provided box_tree; box_tree_free() frees it.
 */
#ifndef CELLAR_BOX_H
#define CELLAR_BOX_H

#include <stddef.h>
#include <stdint.h>

#define BOX_DEPTH_MAX 60 /* levels of nodes at most below the root */

typedef struct box_node {
    double t;         /* threshold */
    int32_t axis;     /* 0: x, 1: y */
    int32_t child[2]; /* below, above; >= 0 node index, < 0 leaf ~index */
} box_node;

typedef struct box_tree {
    size_t nleaves;
    uint32_t *leaf_off; /* nleaves+1: leaf l holds items[leaf_off[l] .. leaf_off[l+1]) */
    uint32_t *items;    /* box indices, ascending within a leaf */
    double *region;     /* 4 per leaf: xlo, ylo, xhi, yhi of (lo, hi] */
    size_t nnodes;
    box_node *nodes; /* nodes[0] is the root when nnodes > 0 */
} box_tree;

/* Builds the tree of n boxes (box[4i..4i+3] = x0, y0, x1, y1, borrowed) with buckets of about
 * leaf_max boxes.  Returns 0, or -1 when out of memory (t is then zeroed). */
int box_tree_build(box_tree *t, const int64_t *box, size_t n, size_t leaf_max);

/* The same tree, node for node, with the two sides of the root split built on two threads
 * when threads > 1 and there are enough boxes. */
int box_tree_build_par(box_tree *t, const int64_t *box, size_t n, size_t leaf_max, int threads);

/* The leaf whose region contains point (x, y). */
uint32_t box_tree_locate(const box_tree *t, double x, double y);

void box_tree_free(box_tree *t);

#endif
