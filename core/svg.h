/* svg.h — SVG drawings to line segments (DESIGN.md "SVG drawings"; issue "SVG drawings in").
 *
 * svg_read() parses the drawing with libxml2 (no network, no external entities, no DTD
 * loading, libxml2's own limits on entity expansion and depth) and turns every geometric
 * element into segments in one coordinate system:
 *   <line>, <rect> (its four sides, or its diagonal with rect_diagonal), <polyline>,
 *   <polygon>, <path> (M L H V C S Q T A Z, absolute and relative, implicit repeats),
 *   <circle>, <ellipse> (curves and arcs flattened to flatten_tolerance), nested <g> and
 *   <svg> with transform (matrix, translate, scale, rotate, skewX, skewY, lists of them),
 *   viewBox, <use> of local references (#id), units on lengths, and elements hidden with
 *   display="none" / style="display:none" (or inside <defs>, <clipPath>, <mask>, ...) skipped.
 * Elements without geometry are ignored; elements that cannot be read are skipped, counted and
 * described in warnings.  Coordinates are those of the root's user space (after every
 * transform), then mapped by the output transform (normalize / y_up), which is reported.
 *
 * Threads: reentrant (libxml2 is initialised once, thread-safely).  Ownership: the caller owns
 * the svg_result; svg_result_free() frees what svg_read() put in it.
 */
#ifndef CELLAR_SVG_H
#define CELLAR_SVG_H

#include <stddef.h>

/* Defaults of the limits (0 in svg_opts means these). */
#define SVG_MAX_BYTES         (64u << 20) /* the document */
#define SVG_MAX_ELEMENTS      1000000u    /* elements of the document */
#define SVG_MAX_PATH_COMMANDS 2000000u    /* path commands, all paths together */
#define SVG_MAX_SEGMENTS      5000000u    /* segments produced, after flattening */
#define SVG_MAX_DEPTH         200u        /* nesting of elements (and of <use> chains) */
#define SVG_MAX_WARNINGS      16          /* messages kept; the count goes on */

typedef struct svg_opts {
    int rect_diagonal; /* the seeds' rect2lines: 0 a rect gives its 4 sides, 1 its diagonal */
    int normalize;     /* map the drawing into the unit square, aspect kept, y up */
    int y_up;          /* without normalize: y' = -y (SVG's y points down) */
    double flatten_tolerance; /* most distance of a curve from its chords, in root user units;
                                 0: 1e-3 of the drawing's size */
    size_t max_elements, max_path_commands, max_segments, max_depth; /* 0: defaults above */
    /* may be NULL: told the fraction of the reading done (parsing the XML, walking the
     * elements, flattening the curves), up to 1 at the end */
    void (*progress)(void *udata, double fraction);
    void *udata;
} svg_opts;

typedef struct svg_result {
    double *seg; /* 4 per segment: x1, y1, x2, y2 (output coordinates) */
    size_t n;
    size_t elements;  /* geometric elements read */
    size_t skipped;   /* elements skipped (unreadable, unsupported): see warnings */
    size_t nwarnings; /* messages in warning[] (at most SVG_MAX_WARNINGS) */
    char warning[SVG_MAX_WARNINGS][160];
    double transform[6]; /* output = (a c e; b d f) * root user coordinates: a,b,c,d,e,f
                            as in SVG's matrix(); the identity unless normalize/y_up */
    double bbox[4];      /* of the segments in root user coordinates: x0, y0, x1, y1 */
} svg_result;

/* Reads the drawing text[0..len) (borrowed, need not be NUL-terminated).  Returns ARR_OK (0)
 * and fills *out, or ARR_EINVAL for malformed XML or a document that is not SVG (the message
 * names line and column: "line 3, column 7: ..."), ARR_ELIMIT for a drawing beyond a limit
 * (the message names it), ARR_ENOMEM; *out is then empty. */
int svg_read(const char *text, size_t len, const svg_opts *o, svg_result *out, char *err,
             size_t errlen);

void svg_result_free(svg_result *r);

#endif
