/* solid.h — solids given as face models (issue "3D: the arrangement of solids"): the input of
 * the 3D pipeline, and its validation.
 *
 * A solid is a closed polyhedral surface: vertices V (x, y, z) and faces, each a planar polygon
 * given as an outer cycle of vertex indices and zero or more hole cycles, outward oriented
 * (counter-clockwise seen from outside, holes clockwise).  solid_check() validates one solid
 * against a precision (the snapping grid step of the 3D pipeline) and reports every problem by
 * solid and face:
 *   - an index out of range; a hole with fewer than 3 distinct vertices (after merging vertices
 *     on one grid point), a face with holes of zero area;
 *   - a face without holes whose vertices lie on one line on the grid (or on fewer than 3
 *     points): a warning, since the 3D pipeline leaves it out and splits its neighbours' edges
 *     at its vertices (counted in degenerate_faces);
 *   - a face farther than the precision from planar (a vertex that far from the plane through
 *     the mean of its vertices): a warning, since the 3D pipeline splits such a face into
 *     triangles, each exactly planar (counted in split_faces);
 *   - a face that is not a polygon with holes on the grid, in its plane or (not planar on the
 *     grid) in the projection the pipeline triangulates it in, decided exactly on the grid
 *     points (core/facecheck.h): a cycle crossing itself, running back along itself, passing a
 *     point twice or touching its own edge; a hole crossing the outer cycle or another hole,
 *     outside the outer cycle, inside another hole, or (solids) turning the same way as the
 *     outer cycle; (solids) a vertex of one cycle inside an edge of another.  Cycles touching
 *     at a shared vertex are taken;
 *   - an open surface (an edge used once), a non-manifold one (an edge used more than twice);
 *   - inconsistent orientation (an edge walked twice in the same direction): reported; when the
 *     faces can be made consistent by flipping some of them (the surface is orientable), they are
 *     flipped in the fixed copy and a warning says so;
 *   - an inward-oriented solid (negative signed volume): flipped in the fixed copy, warning.
 * Errors make the solid unusable; warnings describe what the fixed copy changed.  Messages are
 * kept up to SOLID_MAX_MESSAGES, the last place for the first error (warnings never hide it).
 *
 * Threads: reentrant, no globals.  Ownership: inputs are borrowed; a solid made by the readers
 * or by solid_check's fixed copy is freed with solid_free().
 */
#ifndef CELLAR_SOLID_H
#define CELLAR_SOLID_H

#include <stddef.h>
#include <stdint.h>

typedef struct solid {
    size_t nv;
    double *V; /* 3 * nv */
    size_t nf;
    uint32_t *face_off; /* nf + 1: face f owns cycles face_off[f] .. face_off[f+1] (first: outer) */
    size_t ncyc;
    uint32_t *cyc_off; /* ncyc + 1: cycle c is cyc[cyc_off[c] .. cyc_off[c+1]) */
    uint32_t *cyc;     /* vertex indices */
} solid;

void solid_free(solid *s); /* frees the arrays, zeroes the struct; safe twice */

#define SOLID_MAX_MESSAGES 32

/* The grid's range: a coordinate x is taken at precision p only when |x / p| < 2^62 (the check
 * reports it otherwise, and so does the arrangement's input stage).  Its grid point, x / p
 * rounded, is then an integer of magnitude at most 2^62 - 2^9 (the largest double below 2^62),
 * so it and the difference of two of them (at most 2^63 - 2^10) are int64 values without
 * overflow. */
#define SOLID_GRID_RANGE 0x1p62

enum { SOLID_AT_SOLID = 0, SOLID_AT_FACE = 1, SOLID_AT_VERTEX = 2, SOLID_AT_HOLE = 3 };

/* What a message is, as fields: callers never need to read the text to tell them apart. */
typedef struct solid_msg_info {
    uint8_t warning; /* 1: a warning (the solid is usable); 0: an error */
    uint8_t at;      /* SOLID_AT_*: the whole solid, face `index`, vertex `index`, or hole `sub`
                        (0-based) of face `index` */
    uint16_t what;   /* offset in the text where the description starts (after the location) */
    size_t index, sub;
} solid_msg_info;

typedef struct solid_report {
    size_t errors, warnings; /* counts (the messages kept are capped) */
    size_t nmsg;
    char msg[SOLID_MAX_MESSAGES][160]; /* "label: face 12: open surface (edge 3-4 ...)" */
    solid_msg_info info[SOLID_MAX_MESSAGES];
    double volume;           /* signed volume of the (fixed) solid */
    size_t flipped_faces;    /* faces the fixed copy reverses */
    size_t split_faces;      /* faces farther than the precision from planar (warned) */
    size_t degenerate_faces; /* faces the grid flattens onto a line or a point (warned, left
                                out) */
} solid_report;

/* Checks s (borrowed) at `precision` (> 0).  Returns 0 when it is usable (rep->errors == 0),
 * with *fixed (may be NULL) set to a copy with consistent outward orientation; -1 when it is
 * not (rep says why).  `label` prefixes the messages ("solids[2]"). */
int solid_check(const solid *s, double precision, const char *label, solid_report *rep,
                solid *fixed);

/* The same, but *fixed is made only when the fixed copy differs from s (rep->flipped_faces > 0);
 * otherwise it is left empty (nf == 0) and s itself is the usable solid: no copy of a large
 * input that needs none.  twin (may be NULL; one entry per cycle entry of s) gets, when s is
 * usable, the pairing the check found, in the usable solid's entries: twin[i] is the entry
 * that walks the edge from entry i to the next the other way when exactly those two walk it,
 * else UINT32_MAX (what arr3_build_ex takes, so that the arrangement does not pair them again). */
int solid_check_nocopy(const solid *s, double precision, const char *label, solid_report *rep,
                       solid *fixed, uint32_t *twin);

/* The per-face checks of solid_check only (shape, indices, distinct vertices, zero area,
 * planarity), for a face soup: no closedness, no orientation, no volume. */
int solid_check_faces(const solid *s, double precision, const char *label, solid_report *rep);

/* Readers, one solid per file: Wavefront OBJ (v and f lines; f with v, v/t, v//n, v/t/n and
 * negative indices; other lines ignored) and OFF ("OFF" header, counts, comments).  Return 0,
 * or -1 with "line N: ..." in err (out then empty). */
int solid_read_obj(const char *text, size_t len, solid *out, char *err, size_t errlen);
int solid_read_off(const char *text, size_t len, solid *out, char *err, size_t errlen);

/* An OBJ file's objects as solids: each "o" (and, with groups, each "g") that has faces is a
 * solid with the vertices its faces use (in order of first use); a file of one object is one
 * solid, as solid_read_obj reads it.  *parts (malloc'd, *nparts >= 1 solids) is the caller's to
 * free (solid_free each, then free).  Returns 0, or -1 with a message in err. */
int solid_read_obj_parts(const char *text, size_t len, int groups, solid **parts, size_t *nparts,
                         char *err, size_t errlen);

#endif
