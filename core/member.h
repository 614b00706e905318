/* member.h — sparse membership by a walk (issue "Booleans of many operands").
 *
 * The 2D and 3D Booleans share one rule: the unbounded cell lies in no input, and crossing a
 * boundary element (an edge in 2D, a face in 3D) goes into or out of exactly the inputs that
 * element lists.  So a walk over the cells from the unbounded one gives every cell's
 * membership: the row of a cell is its neighbour's row with the element's inputs toggled (a
 * symmetric difference of sorted lists).  Rows are sorted lists of inputs, stored as
 * compressed sparse rows: the cost is the size of the arrangement times the few inputs a cell
 * lies in, never cells x inputs.  A cell reached twice must get the same row, compared exactly.
 *
 * Threads: reentrant, no globals.  Ownership: inputs borrowed; the rows are malloc'd and freed
 * with member_rows_free().
 */
#ifndef CELLAR_MEMBER_H
#define CELLAR_MEMBER_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

typedef struct member_rows {
    uint32_t *off; /* n + 1: the row of cell k is idx[off[k] .. off[k+1]), ascending */
    uint32_t *idx;
    int32_t *wind; /* NULL, or with member_walk_wind: the winding number of each idx entry
                      (never 0: an input the cell's winding number is 0 for is not listed) */
} member_rows;

/* The walk over n cells from cell root (its row empty).  Cell u's neighbours are
 * nb[aoff[u] .. aoff[u+1]) across the elements el[same range]; element x lists the inputs
 * tags[toff[x] .. toff[x+1]), ascending and each once.  Returns 0 and fills *rows; -1 out of
 * memory; 1 when a cell is reached with two different rows (*bad_el is then one element where
 * that happened) or some cell is out of reach (*bad_el is UINT32_MAX). */
int member_walk(size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                const uint32_t *el, const uint32_t *toff, const uint32_t *tags, member_rows *rows,
                uint32_t *bad_el);

/* The same, calling tick(udata, cells reached / n) every 65 536 cells when tick is not NULL,
 * and returning 2 (nothing in rows) once *cancel (read every 4096 cells; may be NULL) is set. */
int member_walk_ex(size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                   const uint32_t *el, const uint32_t *toff, const uint32_t *tags,
                   member_rows *rows, uint32_t *bad_el, void (*tick)(void *udata, double f),
                   void *udata, const atomic_int *cancel);

/* The walk with winding numbers (issue "every surface by winding number"): crossing element
 * x from the cell on its first side to the one on its second changes the winding number of
 * input tags[i] by dw[i] (toff[x] <= i < toff[x + 1], tags ascending, each once); dir[i]
 * (by neighbour entry, as nb and el) is +1 when cell u sees its neighbour across el[i] on that
 * element's second side, -1 on its first.  A cell's row lists the inputs of non-zero winding
 * number, ascending, with those numbers in rows->wind.  Returns as member_walk_ex. */
int member_walk_wind(size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                     const uint32_t *el, const int8_t *dir, const uint32_t *toff,
                     const uint32_t *tags, const int32_t *dw, member_rows *rows, uint32_t *bad_el,
                     void (*tick)(void *udata, double f), void *udata, const atomic_int *cancel);

/* The scratch of member_walk_ws, kept between walks (the 3D planes walk many small
 * arrangements, one after the other, on one thread): zero-initialise it, free it with
 * member_ws_free.  Not shared between threads. */
typedef struct member_ws {
    void *blk; /* by cell: start, len, queue, seen */
    uint32_t *buf, *ti, *off, *idx;
    int32_t *bw, *tw, *wind;
    size_t capblk, capbuf, capti, capoff, capidx, capbw, captw, capwind;
} member_ws;

/* member_walk over ws's scratch: the same rows, but borrowed from ws (valid until the next walk
 * on ws or member_ws_free; not freed with member_rows_free).  Returns as member_walk. */
int member_walk_ws(member_ws *ws, size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                   const uint32_t *el, const uint32_t *toff, const uint32_t *tags,
                   member_rows *rows, uint32_t *bad_el);
void member_ws_free(member_ws *ws);

void member_rows_free(member_rows *r);

/* out = a xor b of two ascending lists (each element once): ascending, each once; returns its
 * length (at most na + nb; out may not overlap a or b). */
size_t member_symdiff(const uint32_t *a, size_t na, const uint32_t *b, size_t nb, uint32_t *out);

/* The fill rules (2D and 3D alike): where a cell lies in an input, by the input's winding
 * number w about it. */
enum { MEMBER_FILL_POSITIVE = 0 /* w > 0 */, MEMBER_FILL_NONZERO /* w != 0 */, MEMBER_FILL_ODD };
int member_inside(int32_t w, int fill);
/* The longest of the first n rows (room for member_row_inside's buf). */
size_t member_row_most(const member_rows *r, size_t n);
/* The inputs cell k lies in by fill: with winding numbers (r->wind) those of its row the rule
 * takes, written to buf (room for the row) and *row = buf; without, *row is its row (the inputs
 * of odd crossings).  Returns how many. */
size_t member_row_inside(const member_rows *r, size_t k, int fill, uint32_t *buf,
                         const uint32_t **row);

#endif
