/* rmesh.h — the faces of a 3D result as triangles facing out of their cells: what every mesh
 * writer of a 3D result shares (render_obj.c, render_mesh.c).  See rmesh.c for the method.
 *
 * The result is read by api_result_read() (api/result.c, dim 3).  Every face is triangulated
 * once, in its own orientation (its outer cycle's Newell normal); a cell that lists the face as
 * -(f+1) takes its triangles reversed (rmesh_triangle), so every triangle of a cell faces out
 * of it.  The cells written (rmesh_cells) are the result's cells (CF), or a Boolean's result's
 * boundary ("result".faces) as one cell.
 *
 * Threads: reentrant.  Ownership: an rmesh borrows its api_result (which must outlive it) and
 * owns its arrays (rmesh_free()).
 */
#ifndef CELLAR_RMESH_H
#define CELLAR_RMESH_H

#include <stddef.h>
#include <stdint.h>

#include "api/api_int.h"

typedef struct rmesh_cells {
    size_t nc;
    const size_t *off; /* nc + 1: cell c's signed faces are cf[off[c] .. off[c+1]) */
    const int32_t *cf; /* ±(f+1), 1 <= f+1 <= nf */
    int result;        /* the one cell is a Boolean result's boundary */
} rmesh_cells;

typedef struct rmesh {
    const api_result *m; /* borrowed */
    uint32_t *t;         /* owned: 3 vertex ids per triangle, face after face */
    size_t nt;
    size_t *toff; /* owned, nf + 1: face f's triangles are toff[f] .. toff[f+1] */
} rmesh;

/* Triangulates every face of m.  API_OK, or API_ENOMEM (rm then empty). */
int rmesh_make(const api_result *m, rmesh *rm, api_error *err);
void rmesh_free(rmesh *rm);

/* The cells of m (one: room for the offsets of the one cell of a Boolean's result). */
rmesh_cells rmesh_cells_of(const api_result *m, size_t one[2]);

/* The cells' own cells, never the Boolean's result (for writers that give both). */
static inline rmesh_cells rmesh_all_cells(const api_result *m)
{
    return (rmesh_cells){m->nc, m->cell_off, m->cf, 0};
}

/* The centre of the box of V (0 with no vertex). */
void rmesh_centre(const api_result *m, double centre[3]);

/* Triangles of signed face s (±(f+1)); triangle j of it as it faces out: vertex ids in t. */
size_t rmesh_ntri(const rmesh *rm, int32_t s);
void rmesh_triangle(const rmesh *rm, int32_t s, size_t j, uint32_t t[3]);

/* Triangles of cell c. */
size_t rmesh_cell_ntri(const rmesh *rm, const rmesh_cells *cl, size_t c);

/* Translation of cell c by explode k: (k - 1) * (its centroid - centre). */
void rmesh_cell_shift(const rmesh *rm, const rmesh_cells *cl, size_t c, double k,
                      const double *centre, double *shift);

/* Numbers the vertices of cell c's triangles not numbered yet, in the order they first appear,
 * from nl on: local[v] (UINT32_MAX: not yet; the caller resets the entries it listed) and
 * list[nl..); returns the new count.  Called over several cells without a reset it numbers
 * the vertices they use together. */
size_t rmesh_cell_vertices(const rmesh *rm, const rmesh_cells *cl, size_t c, uint32_t *local,
                           uint32_t *list, size_t nl);

#endif
