/* render.h — pictures and maps of a 2D result (issue "pictures out"): LAR JSON in, SVG or
 * GeoJSON out; and meshes of a 3D result: Wavefront OBJ (render_obj, see below).
 *
 * Both renderers read a result as api_run_json() writes it (DESIGN.md "LAR JSON"): "dim" must be
 * 2; "V", "FV" and "holes" are required (a result made with "fields" leaving one out is
 * refused, 422 naming the key, never drawn without its holes); "EV" is optional.  The bounded faces
 * are the rows of FV; with exterior_last the exterior cycles that follow them are recognised and
 * left out (by "stats".F when present, else by the rows equal to those of "exterior", else as the
 * trailing rows of area <= 0: a bounded face's outer cycle is counter-clockwise, so of area > 0).
 * A bad result is a value, never a crash: status API_EINVALID (422) and a message that names the
 * JSON path ("FV[3][2]: expected a vertex index < 11", "V: required ...", "dim: expected 2 ...",
 * "result: malformed JSON at line 1, column 7: ...").  Out of memory is API_ENOMEM (503).
 *
 * SVG (render_svg): each bounded face is ONE <path> filled with fill-rule="evenodd" holding its
 * outer cycle and its holes as subpaths ("M ... Z" each), inside <g id="faces">, coloured by a
 * deterministic palette (golden-ratio hue steps by face index, lightness varied too).  Edges
 * are one <path id="edges"> with fill="none" on top.  Coordinates are the result's with y
 * negated (SVG's y points down; results are in math coordinates, y up), so the picture shows
 * y up and text stays upright.  The viewBox fits every drawn coordinate plus a margin; width is
 * the option, height follows the aspect ratio.  Vertex numbers go in <g id="vertex-numbers">,
 * face numbers in <g id="face-numbers">, one <text> each.  A face's number sits at a point
 * strictly inside the face, holes excluded (the midpoint of the widest horizontal chord at a
 * height that passes through no vertex), not at the centroid, which may lie outside.
 *
 * Exploding (the seeds' EXPLODE figures): with explode = k > 1 every face is translated by
 * (k - 1) * (c_f - C), c_f the face's area centroid (holes subtracted), C the centre of the
 * bounding box of V, so each centroid's distance from C grows k times.  Edges then follow the
 * faces: each face's cycles are drawn with it (an edge between two faces is drawn twice, once
 * with each), and an edge on no bounded face (kept dangling, bridges outside) moves by
 * (k - 1) * (its midpoint - C).  Vertex numbers stay at the vertices' own positions.
 *
 * A Boolean's result (kind polygons: the result has "result") is drawn with the result region
 * on top of the faces and edges: one <path id="result"> holding its polygons' rings, filled
 * translucent with fill-rule="evenodd" and outlined; exploded drawings leave it out (the
 * region is not a face and does not move as one).
 *
 * GeoJSON (render_geojson, RFC 7946).  Of a Boolean's result: a FeatureCollection whose first
 * Feature is the result region, one MultiPolygon (one polygon per result polygon: its shell
 * counter-clockwise, then its holes clockwise; no polygon: "coordinates": []), properties
 * {"result": true, "area": a}; with o->cells, then one Feature per bounded face of the
 * arrangement (geometry a Polygon, properties {"face": f, "area": a, "selected": s,
 * "membership": [the inputs it lies in, ascending]}).  Of any other 2D result: one Feature per
 * bounded face, in face order, geometry a Polygon, properties {"face": f, "area": a}.  Of a layers
 * request's result ("layers" and "result".pieces): the overlay a GIS tool gives, one Feature per
 * piece and choice of one parent per layer, geometry a MultiPolygon, properties {"area": a,
 * "L": the parent's index in layer L or null, "L.key": each of the parent's properties}, then
 * the faces with o->cells (api/render.c, geojson_layers).  Rings are
 * OGC rings: closed by repeating their first position, simple.  A face's boundary walk that passes
 * a vertex twice (a block hanging from a cut vertex: a triangle touching the outer boundary at one
 * vertex, two triangles meeting at a vertex inside; a dangling tree kept inside the face) is cut
 * there into simple cycles: the outer walk's counter-clockwise piece is the shell, every other
 * piece of 3 or more vertices a clockwise hole (touching the shell or another hole at a point, as
 * OGC allows), and pieces of 2 (tree edges) enclose nothing.  Edges on no ring (kept with
 * keep_dangling, also those inside a face) come last, each a LineString Feature with properties
 * {"edge": e, "dangling": true}: never part of a ring.  The coordinates are the result's own plane
 * coordinates, not longitude and latitude: RFC 7946 allows that "by prior arrangement".  Numbers
 * are printed with api_format_double (exact doubles).
 *
 * Threads: reentrant, no globals.  Ownership: the result text and the options (and o->title)
 * are borrowed; *out is malloc'd and NUL-terminated, the caller frees it with free().  On
 * failure *out = NULL, *outlen = 0 and *err (may be NULL) holds the status and message.
 */
#ifndef CELLAR_RENDER_H
#define CELLAR_RENDER_H

#include <stddef.h>

#include "api/api.h"

#define RENDER_EXPLODE_MAX 100.0 /* explode is in [1, RENDER_EXPLODE_MAX] */
#define RENDER_WIDTH_MIN   16    /* width in pixels is in [RENDER_WIDTH_MIN, RENDER_WIDTH_MAX] */
#define RENDER_WIDTH_MAX   16384
#define RENDER_STROKE_MAX  100.0 /* stroke in pixels is 0 (auto) or in (0, RENDER_STROKE_MAX] */

typedef struct render_opts {
    double explode;    /* k >= 1: faces moved away from the centre (1, the default: in place) */
    int numbers;       /* non-zero: vertex numbers and face numbers (default 0) */
    int edges;         /* non-zero: draw the edges (default 1) */
    int width;         /* of the picture in pixels (default 800); height from the aspect ratio */
    double stroke;     /* edge width in pixels; 0 (the default): auto, width / 800 in [0.5, 4] */
    const char *title; /* borrowed, may be NULL: the <title> text (escaped; bytes that are not
                          UTF-8 become '?'); NULL: "cellar: F faces, E edges, V vertices" */
    int cells;         /* GeoJSON of a Boolean's result: 0 (the default) the result region
                          only; 1 every face of the arrangement too, with its membership */
} render_opts;

/* The defaults above. */
#define RENDER_OPTS_INIT                                                                           \
    {                                                                                              \
        1.0, 0, 1, 800, 0.0, NULL, 0                                                               \
    }
void render_opts_init(render_opts *o);

/* A renderer: the result result_json[0..len) (need not be NUL-terminated) written in its format
 * into *out (*outlen bytes) with the options o (may be NULL: the defaults); the ones below. */
typedef int render_func(const char *result_json, size_t len, const render_opts *o, char **out,
                        size_t *outlen, api_error *err);

/* Draws the 2D result result_json[0..len) (need not be NUL-terminated) as an SVG document
 * (o may be NULL: the defaults).  Returns API_OK and sets *out (*outlen bytes, ending in "\n"),
 * or API_EINVALID for a result it cannot draw or options out of range (the message names the
 * key or option), API_ENOMEM. */
render_func render_svg;

/* Writes the 2D result result_json[0..len) as a GeoJSON FeatureCollection (one line, ending in
 * "\n"; o may be NULL: the defaults, only o->cells is read).  Returns API_OK, API_EINVALID or
 * API_ENOMEM as render_svg(). */
render_func render_geojson;

/* Writes the bounded cells of the 3D result result_json[0..len) (dim 3; "V", "FV" and "CF"
 * required, "holes" optional) as Wavefront OBJ (api/render_obj.c): a comment line, every
 * vertex its triangles use as "v x y z" (in the order first used), then per cell "g cellN" and its
 * faces triangulated ("f a b c", 1-based), each triangle facing out of the cell (a face listed
 * -(f+1) in CF is reversed).  Faces may be non-convex and have holes.  With o->explode = k > 1 each
 * cell is moved by (k - 1) * (its centroid - the centre of the box of V) and writes its own
 * vertices (all of them first, cell by cell, then the groups).  Only o->explode is read (o may be
 * NULL: the defaults).  Returns API_OK, API_EINVALID (a result it cannot read: the message names
 * the JSON path, "CF[2][0]:
 * ...", "dim: expected 3 ..."; explode out of range) or API_ENOMEM. */
render_func render_obj;

/* Meshes of a 3D result for other tools (api/render_mesh.c), of the triangles render_obj
 * writes (api/rmesh.c), each holding only the vertices its triangles use:
 *   render_stl  binary STL (float32; the 80-byte header never starts with "solid")
 *   render_off  OFF: "OFF", a comment, counts, the vertices (exact doubles), "3 a b c" faces
 *   render_3mf  a 3MF package ([Content_Types].xml, _rels/.rels, 3D/3dmodel.model; deflated
 *               zip): one object per cell (its own vertices), each a build item
 *   render_glb  glTF 2.0 binary: one mesh per cell, each its own node ("cellN"), float32
 *               positions and uint32 indices; with explode = k > 1 each cell's node is
 *               translated as render_obj moves it
 * Of a Boolean's result STL, OFF and 3MF hold the result solid only (its boundary,
 * "result".faces, as render_obj writes it); glb holds every cell and one more node "result"
 * (not moved by explode).  Of any other result STL and OFF hold every cell's triangles (a face
 * two cells share twice, facing out of each).  Only o->explode is read, by glb (o may be
 * NULL).  Returns API_OK, API_EINVALID (as render_obj) or API_ENOMEM. */
render_func render_stl;
render_func render_off;
render_func render_3mf;
render_func render_glb;

/* Writes the result result_json[0..len) (2D or 3D, any kind, any fields) as NumPy arrays in one
 * .npz: a zip of .npy files (format 1.0, little-endian), stored as numpy.savez writes it, so
 * numpy.load reads it (no pickle).  The arrays:
 *   V                        float64 (n, dim)
 *   EV                       (m, 2)
 *   FV, FE, CF, CV, exterior (2D: cycles), result.FV, result.FE: rows of different lengths, as
 *                            K.indptr and K.indices (row i: K.indices[K.indptr[i]:K.indptr[i+1]])
 *   holes, result.holes      K.face (the face, or result polygon, of each cycle), K.indptr,
 *                            K.indices (the cycles)
 *   operators.d1 (d2, d3), membership: their shape, indptr, indices, data as they are in JSON,
 *                            so scipy.sparse.csr_matrix((data, indices, indptr), shape) loads one
 *   every other array of numbers (result.cells, exterior in 3D, ...): as it is, 1D
 * and "json": uint8, the JSON text of an object of everything else (dim, stats, result.area or
 * volume, membership.format), so nothing of the result is lost.  Integer arrays are int32, or
 * int64 when a value needs it.  Names join keys with ".".  The bytes are a function of the
 * result only (the zip's times are 1980-01-01).  o is not read (may be NULL).  Returns API_OK,
 * API_EINVALID (a result it cannot read: the message names the JSON path; more than 4 GiB) or
 * API_ENOMEM.  See api/npz.c. */
render_func render_npz;

/* Results of more than this many bytes of JSON are not rendered by the daemon (on an HTTP thread,
 * rendering costs about ten times the result's size in memory and ~0.2 s per MB); npz costs
 * about three times and is made at ~200 MB/s, and exists for big results. */
#define RENDER_MAX_BYTES     (16ul << 20)
#define RENDER_NPZ_MAX_BYTES (256ul << 20)

/* The representations of a result, in one table: what the daemon serves (Accept and ?format=)
 * and what the command-line tool writes (--format).  A new one is a row here. */
typedef render_func *render_fn;
typedef struct render_format {
    const char *name;  /* "json", "svg", "geojson", "obj", "npz", "stl", "off", "3mf", "glb":
                          ?format= and --format */
    const char *media; /* its media type (Content-Type, and what Accept names) */
    const char *wild;  /* a wildcard media type that picks it (image/ and a star), or NULL */
    int dim;           /* the results it is made of: 2, 3, or 0 (any) */
    render_fn render;  /* NULL: the result JSON itself */
    unsigned long max; /* the largest result (bytes of JSON) the daemon renders this way */
} render_format;

/* json, svg, geojson, obj, npz, stl, off, 3mf, glb, in that order (the order Accept's ties are
 * broken in). */
extern const render_format render_formats[];
extern const size_t render_nformats;

/* The row named name, or NULL. */
const render_format *render_format_named(const char *name);

/* Options from a URL's query, one parameter at a time (already percent-decoded, as
 * libmicrohttpd's MHD_get_connection_values gives them):
 *   explode=K   a number in [1, 100]
 *   numbers=B   B one of 1 0 true false yes no on off, or no value at all ("?numbers"): true
 *   edges=B
 *   width=N     an integer in [16, 16384]
 *   stroke=S    a number in [0, 100] (0: auto)
 *   cells=C     C "result" (the default) or "all" (GeoJSON of a Boolean: every face too)
 * value may be NULL (no "=").  Sets the field of *o and returns API_OK, or returns
 * API_EINVALID with a message naming the parameter ("explode: expected a number in [1, 100],
 * got \"x\"", "foo: unknown parameter ...") and leaves *o as it was.  The title is not a query
 * parameter.  A caller that has query parameters of its own asks render_opts_is_query_key()
 * first. */
int render_opts_parse_query(const char *query_key, const char *value, render_opts *o,
                            api_error *err);

/* Non-zero when key is one of the parameters render_opts_parse_query() reads. */
int render_opts_is_query_key(const char *key);

/* The same for a whole raw query string query[0..len) ("explode=1.2&numbers=1&width=600",
 * without the '?'): splits it at '&' (and ';'), decodes %XX and '+', and applies every
 * parameter in order with render_opts_parse_query(); an unknown parameter or a bad %-escape is
 * an error.  On failure *o may hold the parameters before the bad one. */
int render_opts_parse_query_string(const char *query, size_t len, render_opts *o, api_error *err);

#endif
