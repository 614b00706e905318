/* api_int.h — what the files of api/ share with one another; nothing outside api/ includes it.
 *
 * api_buf: the growing output buffer every result is streamed into.  A failed allocation makes
 * the buffer sticky-failed: later appends do nothing, and the writer checks b->failed once at the
 * end, so the serializers need no error path per number.
 *
 * api_kind: one entry of the table of request kinds (api/run.c).  Adding a kind ("svg",
 * "solids") is one handler in its own file and one line in that table.
 */
#ifndef CELLAR_API_INT_H
#define CELLAR_API_INT_H

#include <jansson.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdint.h>

#include "api/api.h"
#include "api/packed.h"
#include "core/arr2.h"
#include "core/bool3.h"
#include "core/member.h"
#include "core/boolexpr.h"
#include "core/arr3.h"

typedef struct api_buf {
    char *p;    /* owned; NUL-terminated whenever len > 0 and !failed */
    size_t len; /* bytes used */
    size_t cap; /* bytes allocated */
    int failed; /* an allocation failed: contents are incomplete */
    /* streaming (api_run_opts.stream): when set, the bytes are written to sink whenever the
     * buffer would grow beyond API_BUF_SINK, so a large result never sits whole in memory;
     * sunk counts what was written.  Writers only append: nothing reads back what it wrote. */
    FILE *sink;
    size_t sunk;
    int sink_errno; /* the errno of a failed write to sink (then failed is set too) */
    /* progress of the output (api_run_opts.progress): the writers call api_buf_section() as
     * they start each top-level key, of about nsections */
    void (*progress)(void *udata, const char *stage, double fraction);
    void *udata;
    unsigned nsections, sections;
    /* the run's cancel (api_run_opts.cancel, may be NULL): read by api_buf_tick every 1024 rows;
     * once set the buffer fails (the writers stop writing) and api_buf_finish says canceled */
    const atomic_int *cancel;
    int canceled;
} api_buf;

/* A top-level key of the result begins: "output" progress by the share of the keys written. */
void api_buf_section(api_buf *b);
/* Row i of the n of the section being written (cheap: reports every 8192nd, and reads the
 * cancel every 1024th); non-zero once the buffer failed (out of memory, or canceled): the
 * writer may stop its loop, nothing more is written. */
int api_buf_tick(api_buf *b, size_t i, size_t n);
#define API_BUF_SINK (1u << 20)

/* Writes what the buffer holds to its sink (no-op without one); failed on a write error. */
void api_buf_flush(api_buf *b);

/* The end of a run that wrote its result into b, rc its status: on API_OK the final "\n" is
 * added and the rest flushed, and *out / *outlen get the result (with a sink: NULL and the bytes
 * written); a failed buffer becomes API_ENOMEM, or an error naming the stream's write error
 * (the writers see only "failed").  b is freed or taken over either way; returns the status. */
int api_buf_finish(api_buf *b, int rc, char **out, size_t *outlen, api_error *err);

/* Makes room for n more bytes (and a NUL); returns where they go, or NULL once failed. */
char *api_buf_reserve(api_buf *b, size_t n);
void api_buf_put(api_buf *b, const char *s, size_t n);
void api_buf_puts(api_buf *b, const char *s);
void api_buf_u64(api_buf *b, uint64_t v);
void api_buf_i64(api_buf *b, int64_t v);
void api_buf_double(api_buf *b, double x); /* x finite (asserted) */
/* [x0,x1,...] of the dim coordinates at x, each by api_buf_double. */
void api_buf_point(api_buf *b, const double *x, int dim);
/* A Boolean result's own "V" (fields without V): writes "V":[...] of the vertices v < nv whose
 * map[v] is non-zero (V holds dim coordinates each), in order, and renumbers map[v] to their
 * place in it, which the result's cycles then write. */
void api_buf_own_vertices(api_buf *b, const double *V, size_t nv, int dim, uint32_t *map);
void api_buf_free(api_buf *b);
void api_buf_u32_list(api_buf *b, const uint32_t *a, size_t n); /* [a0,a1,...] */
/* The numbers' writers (larjson.c): 10^k in 128 bits (0 <= k <= 38); x > 0 written as
 * %.{prec}g would (prec <= 17) from its prec-digit rounding d (10^(prec-1) <= d < 10^prec) and
 * the decimal exponent E of its first digit.  Returns the length (a 0 is written after). */
typedef unsigned __int128 api_u128;
api_u128 api_pow10_u128(int k);
size_t api_fmt_g(uint64_t d, int prec, int E, char *p);
void api_buf_i32_list(api_buf *b, const int32_t *a, size_t n);
/* {"shape":[nrows,ncols],"indptr":[...],"indices":[...],"data":[±1,...]}: a CSR matrix whose
 * row r holds indices/data[indptr[r] .. indptr[r+1]). */
void api_buf_csr(api_buf *b, size_t nrows, size_t ncols, const size_t *indptr,
                 const uint32_t *indices, const int8_t *data);

/* ,"membership":{"format":"csr","shape":[nrows,ninputs],"indptr":[...],"indices":[...]}: row r
 * (a face or cell) lies in the inputs indices[indptr[r] .. indptr[r+1]), ascending; scipy:
 * csr_matrix((ones, indices, indptr), shape). */
void api_put_membership(api_buf *b, size_t nrows, size_t ninputs, const uint32_t *off,
                        const uint32_t *idx);
/* The same with winding numbers (wind may be NULL: as above): wind[i] is the winding number of
 * entry i; when one is not 1 they are written as "data" (scipy: csr_matrix((data, indices,
 * indptr), shape)). */
void api_put_membership_w(api_buf *b, size_t nrows, size_t ninputs, const uint32_t *off,
                          const uint32_t *idx, const int32_t *wind);

static inline void api_buf_putc(api_buf *b, char c)
{
    if (b->len + 2 <= b->cap) {
        b->p[b->len++] = c;
        b->p[b->len] = 0;
    } else {
        api_buf_put(b, &c, 1);
    }
}

/* Fills err (may be NULL) with status and a printf-style message, bytes outside printable ASCII
 * replaced by '?' (messages quote user input and end up in JSON and on terminals); returns
 * status. */
int api_fail(api_error *err, int status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* A request of a kind holds the keys "kind", `own` (the kind's data: "lines", "svg", ...) and
 * "options" only: API_OK, or API_EINVALID naming the first other key. */
int api_only_keys(const json_t *req, const char *own, api_error *err);

/* Maps an ARR_* code of the core and its message to an api status and *err. */
int api_core_fail(api_error *err, int arr_code, const char *core_msg);

/* ---- progress ---------------------------------------------------------------------------- *
 * The cores and the kinds report (stage, fraction of that stage done); a kind's table of stages
 * (api_stage: its name and the share of the whole run done at its end, in the order they run)
 * turns that into (the stage running now, fraction of the whole run) for api_run_opts.progress:
 * a stage's end (fraction 1) names the next one, a stage that does not run (a solids request
 * without op has no membership) is passed over, and a report of an earlier stage than the one
 * running (or of a name not in the table) is dropped, so both stay monotonic. */
typedef struct api_stage {
    const char *name;
    double end;
} api_stage;

typedef struct api_progress {
    const api_stage *st; /* the kind's table, {NULL, 0}-terminated */
    size_t cur;          /* the stage running */
    double last;         /* the fraction last reported */
    void (*up)(void *udata, const char *stage, double fraction);
    void *udata;
} api_progress;

/* Fills *wrapped as a copy of ro whose progress goes through p and the table st; ro unchanged
 * (and p unused) when it has no progress callback. */
void api_progress_wrap(api_progress *p, const api_stage *st, const api_run_opts *ro,
                       api_run_opts *wrapped);
/* The stages of each kind (api/run.c). */
extern const api_stage api_stages_lines[], api_stages_svg[], api_stages_polygons[],
    api_stages_solids[];

/* One kind of request, in three steps so that the parsed JSON tree (jansson keeps a node per
 * number: ten times the size of the body) is freed before the core runs:
 *   parse       req (borrowed, its "kind" already matched) -> *parsed, the kind's own request
 *               struct; validates every other key.  On failure *parsed is NULL.
 *   run         runs *parsed (borrowed) with ro and appends the result JSON (no final "\n").
 *   free        frees what parse made; safe on NULL. */
typedef struct api_kind {
    const char *name; /* the value of "kind" */
    int (*parse)(const json_t *req, void **parsed, api_error *err);
    int (*run)(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err);
    void (*free)(void *parsed);
    /* optional, run by api_check_request() only (the daemon's submit, before queueing): the
     * checks that parse leaves to run but a client should hear about at once (svg: the XML,
     * solids: the surfaces).  What they make that run needs (svg: the segments; solids: the
     * fixed copies, pairings and warnings) is kept in *parsed, so that run, handed a checked
     * request (api_request_run), does not check it again. */
    int (*check)(void *parsed, api_error *err);
    const api_stage *stages; /* its stages, for progress */
    /* optional: parse with the big arrays read beforehand (api/packed.h); req is the rest's
     * tree.  Any failure sends the caller back to parse() on the whole text, whose message
     * counts: this one is not shown. */
    int (*parse_packed)(const json_t *req, api_packed_set *pk, void **parsed, api_error *err);
} api_kind;

/* The "lines" kind (api/lines.c). */
int api_lines_parse(const json_t *req, void **parsed, api_error *err);
/* The same, its "lines" possibly read by api_packed_scan (pk: then taken from there). */
int api_lines_parse_packed(const json_t *req, api_packed_set *pk, void **parsed, api_error *err);
int api_lines_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err);
void api_lines_free(void *parsed);

/* The "svg" kind (api/svg.c). */
int api_svg_parse(const json_t *req, void **parsed, api_error *err);
int api_svg_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err);
void api_svg_free(void *parsed);
int api_svg_check(void *parsed, api_error *err);

/* The "solids" kind (api/solids.c). */
int api_solids_parse(const json_t *req, void **parsed, api_error *err);
int api_solids_parse_packed(const json_t *req, api_packed_set *pk, void **parsed, api_error *err);
int api_solids_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err);
void api_solids_free(void *parsed);
int api_solids_check(void *parsed, api_error *err);

/* The "polygons" kind (api/polygons.c): 2D Booleans. */
int api_polygons_parse(const json_t *req, void **parsed, api_error *err);
/* The same, its native "polygons" possibly read by api_packed_scan (pk). */
int api_polygons_parse_packed(const json_t *req, api_packed_set *pk, void **parsed, api_error *err);
int api_polygons_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err);
void api_polygons_free(void *parsed);

/* The result fields a request may ask for (options.fields), as bits. */
enum {
    API_F_V = 1u << 0,
    API_F_EV = 1u << 1,
    API_F_FV = 1u << 2,
    API_F_FE = 1u << 3,
    API_F_HOLES = 1u << 4,
    API_F_EXTERIOR = 1u << 5,
    API_F_STATS = 1u << 6,
    API_F_OPERATORS = 1u << 7,
    API_F_DEFAULT = (1u << 7) - 1, /* all but operators (and the two below) */
    /* "polygons" only (written when named, or when no fields are given); a result without V
     * named carries its own V, its "cells" only with FV or FE named, its "FE" only with EV */
    API_F_MEMBERSHIP = 1u << 8,
    API_F_RESULT = 1u << 9
};
#define API_NFIELDS 10
extern const char *const api_field_names[API_NFIELDS]; /* "V", "EV", ... in bit order */

/* A rule of the fields: the key `key` (a bit) refers to one of the keys `any` (bits), so that
 * naming key without one of them is refused. */
typedef struct api_field_ref {
    unsigned key, any;
    const char *what; /* what the keys of any are, for a message when they are two: "the faces" */
} api_field_ref;
/* 422 naming the first rule that fl breaks (names: the keys' names in bit order), else API_OK. */
int api_fields_refs(unsigned fl, const api_field_ref *rules, size_t n, const char *const *names,
                    api_error *err);

/* 422 naming the first key among fl (API_F_*) that refers to one fl leaves out ("FV" without
 * "V": options.fields: "FV" refers to "V", which is not named), else API_OK.  EV, FV, holes and
 * exterior index V; FE indexes EV; holes are keyed by faces (FV or FE).  operators, stats,
 * membership and result stand alone (the result is made self-contained by its writer). */
int api_lar2_fields_check(unsigned fl, api_error *err);

/* The options of every kind that returns a 2-complex ("lines", "svg"): api/lines.c reads them. */
typedef struct api_lar2_opts {
    double precision; /* 0: the core's default */
    int keep_dangling;
    int exterior_last;
    int operators;
    unsigned fields; /* API_F_*; API_F_DEFAULT unless given */
} api_lar2_opts;

#define API_NOT_MINE (-1) /* api_lar2_option(): the key is not one of these options */

/* Reads options.key = v into *o when key is precision, keep_dangling, exterior_last, operators or
 * fields.  Returns API_OK, an error status (message in *err) or API_NOT_MINE.  Start from
 * {.fields = API_F_DEFAULT}; after the last key, operators adds API_F_OPERATORS to fields. */
int api_lar2_option(const char *key, const json_t *v, api_lar2_opts *o, api_error *err);

/* Reads the whole "options" object o (may be NULL) of a kind whose options are exactly those of
 * api_lar2_option ("lines", "polygons"): API_OK, or an error naming options.KEY. */
int api_lar2_options(const json_t *o, api_lar2_opts *opt, api_error *err);
/* 422 when o's fields name "membership" or "result" (a kind without a Boolean), else API_OK. */
int api_lar2_no_bool(const api_lar2_opts *o, api_error *err);

/* How api_lar2_write() presents a 2-complex. */
typedef struct api_lar2_fmt {
    unsigned fields;   /* API_F_* bits */
    int exterior_last; /* append the exterior cycles as the last rows of FV and FE */
    /* may be NULL: appends more members to the "stats" object, each as ,"key":value */
    void (*stats_more)(api_buf *b, const void *udata);
    const void *stats_udata; /* passed to stats_more */
    /* may be NULL: appends more top-level members after the others, each as ,"key":value */
    void (*more)(api_buf *b, const void *udata);
    const void *more_udata; /* passed to more */
} api_lar2_fmt;

/* Appends the LAR JSON object of c (borrowed) to b.  Returns API_OK, API_ENOMEM (b failed or a
 * scratch allocation failed) or API_EINTERNAL (c breaks an invariant, e.g. an exterior cycle
 * walks a pair of vertices that is not an edge). */
int api_lar2_write(api_buf *b, const lar2 *c, const api_lar2_fmt *fmt, api_error *err);

/* The fields of a 3-complex (options.fields of "solids"), as bits. */
enum {
    API_F3_V = 1u << 0,
    API_F3_EV = 1u << 1,
    API_F3_FV = 1u << 2,
    API_F3_FE = 1u << 3,
    API_F3_HOLES = 1u << 4,
    API_F3_CF = 1u << 5,
    API_F3_CV = 1u << 6,
    API_F3_EXTERIOR = 1u << 7,
    API_F3_STATS = 1u << 8,
    API_F3_OPERATORS = 1u << 9,
    /* with an "op": written when named, or when no fields are given (a result without V named
     * carries its own V; its "cells" come only with CF or CV, "faces" with FV or FE, "FE"
     * with EV) */
    API_F3_MEMBERSHIP = 1u << 10,
    API_F3_RESULT = 1u << 11,
    API_F3_DEFAULT = ((1u << 9) - 1) | API_F3_MEMBERSHIP | API_F3_RESULT /* all but operators */
};
#define API_NFIELDS3 12
extern const char *const api_field3_names[API_NFIELDS3]; /* "V", "EV", ... in bit order */

/* How api_lar3_write() presents a 3-complex (api/larjson3.c). */
typedef struct api_lar3_fmt {
    unsigned fields;             /* API_F3_* bits */
    const char *const *warnings; /* borrowed, nwarnings strings for stats.warnings (may be NULL) */
    size_t nwarnings;
    /* a Boolean operation (may be NULL): "membership" (the solids each bounded cell lies in,
     * sparse rows, c->nc of them) and "result" (the cells, the outward boundary faces, their
     * cycles and signed edges, the volume), each written when its field is in fields */
    const member_rows *membership;
    const bool3_result *result;
    const char *layers; /* borrowed, may be NULL: the JSON array written as "layers" */
} api_lar3_fmt;

/* Appends the LAR JSON object of the 3-complex c (borrowed; core/arr3.h) to b.  Returns API_OK,
 * API_ENOMEM (b failed or a scratch allocation failed) or API_EINTERNAL (c breaks an invariant
 * the writer relies on: an index out of range, offsets that decrease). */
int api_lar3_write(api_buf *b, const lar3 *c, const api_lar3_fmt *fmt, api_error *err);
/* As api_lar2_fields_check for a 3-complex's fields (API_F3_*): EV, FV, holes and CV index V;
 * FE indexes EV; holes, CF and exterior index the faces (FV or FE). */
int api_lar3_fields_check(unsigned fl, api_error *err);
/* The arr3_opts.want for a request of these fields (API_F3_*): the parts the writer prints. */
unsigned api_lar3_want(unsigned fields);

/* Compiles a request's "op" (api/boolop.c): a named operation ("union", "intersection",
 * "difference", "xor") over all ninputs inputs, or an expression tree such as
 * ["-", 0, ["+", 1, 2]] with operators + & - ^ and input indices.  Returns API_OK with *out
 * checked (bool_expr_free it), or API_EINVALID naming the JSON path under "op". */
int api_bool_parse(const json_t *op, size_t ninputs, bool_expr *out, api_error *err);

/* The layers of a request ("layers": {"name": inputs, ...}): layer k is named name[k] (JSON
 * text of a string, quotes included) and holds the inputs first[k] .. first[k+1]). */
#define API_LAYER_NAME_MAX 100
typedef struct api_layers {
    size_t n;
    char *const *name;
    const uint32_t *first; /* n + 1 */
} api_layers;

/* api_bool_parse() over layers: an operand may also be a layer's name (the union of its
 * inputs), and "union", "intersection", "difference", "xor" combine the layers' unions (the
 * first layer minus the others, ...).  Errors as api_bool_parse's, and an unknown name is
 * named with the layers there are. */
int api_bool_parse_layers(const json_t *op, size_t ninputs, const api_layers *ly, bool_expr *out,
                          api_error *err);

/* Reads options.fill (api/boolop.c): "positive", "nonzero" or "odd" into *fill (MEMBER_FILL_*).
 * Returns API_OK, or API_EINVALID listing the names with the kind's default, dflt, first. */
int api_fill_parse(const json_t *v, int dflt, int *fill, api_error *err);

/* A result (LAR JSON) as the renderers read it (api/result.c): one reader for every renderer,
 * the dimension a parameter.  Every index is checked while reading, so writers index without
 * checks.  Faces' rings: face f's are rings face_ring[f] .. face_ring[f+1] (its outer cycle
 * first, then its holes), ring r's vertices idx[ring_off[r] .. ring_off[r+1]). */
typedef struct api_result {
    int dim;           /* 2 or 3 */
    size_t nv;         /* vertices */
    double *V;         /* owned: dim coordinates per vertex, all finite */
    size_t ne;         /* 2D: edges in ev (0 when the result has no EV); 3D: 0, EV is not read */
    uint32_t *ev;      /* owned, may be NULL: 2 per edge */
    size_t nf;         /* faces: 2D the bounded rows of FV (exterior_last rows left out), 3D all */
    size_t *face_ring; /* owned, nf + 1 */
    size_t nrings;     /* the faces' rings (nface_rings), then a 2D Boolean's result's */
    size_t nface_rings;
    size_t *ring_off; /* owned, nrings + 1 */
    uint32_t *idx;    /* owned, ring_off[nrings] */
    /* 3D: the cells, CF: cell c's signed faces ±(f+1) are cf[cell_off[c] .. cell_off[c+1]) */
    size_t nc;
    size_t *cell_off; /* owned, nc + 1 (NULL in 2D) */
    int32_t *cf;      /* owned */
    /* a Boolean's result ("result" of a polygons or solids result), else has_result = 0 */
    int has_result;
    /* 2D: polygon q's rings (shell, then holes) are rings poly_ring[q] .. poly_ring[q+1], after
     * the faces' (rings nface_rings .. nrings); res_area its "area"; selected[f]: face f is one
     * of its "cells" */
    size_t npoly;
    size_t *poly_ring; /* owned, npoly + 1 */
    double res_area;
    uint8_t *selected; /* owned, nf */
    size_t ninputs;    /* 2D: inputs of "membership" (0: none) */
    size_t *mem_off;   /* owned, nf + 1 (NULL: no "membership"): face f lies in the inputs */
    uint32_t *mem;     /* mem[mem_off[f] .. mem_off[f+1]) */
    /* 3D: the signed faces of the result's boundary ("result".faces) */
    size_t nres_faces;
    int32_t *res_faces; /* owned */
    /* 2D: the whole result as read, kept only when it has "layers" (a layers request's: the
     * GeoJSON writer reads its "layers" and "result".pieces there); else NULL */
    json_t *root; /* owned reference */
} api_result;

/* Reads the result text[0..len) of dimension dim (2 or 3) into *m: "dim" must equal dim (why
 * completes the message "dim: expected D (why)").  2D: V, FV and holes required, EV optional,
 * a Boolean's result and membership; 3D: V, FV and CF required, holes optional, a Boolean's
 * result.faces (api/result.c says more).  Returns API_OK, API_EINVALID with a message naming
 * the JSON path, or API_ENOMEM; on failure *m is empty.  api_result_free() frees *m either way
 * (and leaves it empty). */
int api_result_read(const char *text, size_t len, int dim, const char *why, api_result *m,
                    api_error *err);
void api_result_free(api_result *m);

/* A key of "holes", canonical decimal ("0", "17": no sign, no leading zero) below nf, into
 * *out; 0 when it is not one (api/result.c). */
int api_face_key(const char *key, size_t nf, size_t *out);

/* ---- arrays out (the library, include/cellar.h) ------------------------------------------- *
 * A result as named arrays (struct cellar_result, api/lib.c): the kinds' *_arrays functions
 * compute as *_run does and add each array of the result JSON, under the name the .npz output
 * gives it, instead of writing it.  An array is added either owned (malloc'd, freed with the
 * result) or borrowed from a block the result keeps (api_arrays_keep: the core's complex, freed
 * with the result by its function), so the core's own arrays are handed out without a copy. */
typedef struct cellar_result api_arrays;
enum { API_A_F64 = 1, API_A_I32, API_A_U32, API_A_I8, API_A_U64 }; /* cellar_dtype's values */
/* Adds name (copied) as rows x cols elements of type dt at data; own: data is malloc'd and
 * the result takes it (freed here on failure too).  0, or -1 out of memory. */
int api_arrays_add(api_arrays *r, const char *name, int dt, size_t rows, size_t cols,
                   const void *data, int own);
/* The same, with a sticky failure: nothing is added once *bad is set (an owned data is freed),
 * and a failure sets it. */
void api_arrays_put(api_arrays *r, int *bad, const char *name, int dt, size_t rows, size_t cols,
                    const void *data, int own);
/* The result keeps p until it is freed, then calls fr(p); on failure fr(p) is called now.  0 or
 * -1 (out of memory). */
int api_arrays_keep(api_arrays *r, void *p, void (*fr)(void *));
/* Sets the result's JSON member text (taken over, malloc'd) and its dim. */
void api_arrays_json(api_arrays *r, int dim, char *json);
/* CSR rows gathered from pieces: adds "name.indptr" (U32, n + 1) and "name.indices" (U32) where
 * row i is the cycle cyc[cyc_off[k] .. cyc_off[k+1]) of k = which[i]; reversed[i] (may be NULL)
 * walks it backwards from its first vertex, and map (may be NULL) renumbers the vertices.
 * 0 or -1 (out of memory). */
int api_arrays_cycles(api_arrays *r, const char *name, const uint32_t *cyc_off, const uint32_t *cyc,
                      const uint32_t *which, const uint8_t *reversed, size_t n,
                      const uint32_t *map);
/* A compressed sparse row matrix: row i holds idx/val[ptr[i] .. ptr[i+1]); owned arrays. */
typedef struct api_csr {
    size_t nrows, ncols;
    size_t *ptr; /* nrows + 1 */
    uint32_t *idx;
    int8_t *val;
} api_csr;
void api_csr_free(api_csr *m);
/* Adds "name.shape", ".indptr", ".indices", ".data" of m, taking its arrays over (m is left
 * empty, success or not).  0 or -1 (out of memory). */
int api_arrays_csr(api_arrays *out, const char *name, api_csr *m);
/* A Boolean result's own V (fields without V), as api_buf_own_vertices writes it: "name" (F64,
 * rows of dim) holds the vertices v < nv whose map[v] is non-zero, in order, and map[v] becomes
 * their place in it.  0 or -1 (out of memory). */
int api_arrays_own_vertices(api_arrays *out, const char *name, const double *V, size_t nv, int dim,
                            uint32_t *map);
/* "name.face" (the row q of each), "name.indptr" and "name.indices" of the holes of n rows:
 * row q's holes are the cycles ids[off[q] .. off[q+1]) (off may be NULL when n is 0) of the
 * cycle table cyc_off / cyc, their vertices through map (may be NULL), as the writers'
 * "holes": {"q": [cycle, ...]} lists them.  Sticky failure as api_arrays_put. */
void api_arrays_holes(api_arrays *r, int *bad, const char *name, size_t n, const uint32_t *off,
                      const uint32_t *ids, const uint32_t *cyc_off, const uint32_t *cyc,
                      const uint32_t *map);
/* "name" as one double (a result's area or volume).  Sticky failure as api_arrays_put. */
void api_arrays_f64(api_arrays *r, int *bad, const char *name, double x);
/* 1 when every winding number of a membership (wind may be NULL: none) is 1, so that the
 * membership is written without "data". */
int api_membership_plain(size_t nrows, const uint32_t *off, const int32_t *wind);
/* The kinds' array runs: as *_run, the result's arrays added to out instead of written. */
int api_lines_arrays(const void *parsed, const api_run_opts *ro, api_arrays *out, api_error *err);
int api_polygons_arrays(const void *parsed, const api_run_opts *ro, api_arrays *out,
                        api_error *err);
int api_solids_arrays(const void *parsed, const api_run_opts *ro, api_arrays *out, api_error *err);
/* The arrays of a 2-complex (the fields of fmt: V, EV, FV, FE, holes, exterior, operators) and
 * the JSON of its stats (with fmt's stats_more), as api_lar2_write writes them; c must outlive
 * out (api_arrays_keep). */
int api_lar2_arrays(api_arrays *out, const lar2 *c, const api_lar2_fmt *fmt, api_error *err);
/* The same of a 3-complex (the fields of fmt, its membership and result). */
int api_lar3_arrays(api_arrays *out, const lar3 *c, const api_lar3_fmt *fmt, api_error *err);
/* membership as api_put_membership_w writes it: "membership.shape" (U64, 2), ".indptr",
 * ".indices", and ".data" when a winding number is not 1; the arrays are borrowed. */
int api_arrays_membership(api_arrays *out, size_t nrows, size_t ninputs, const uint32_t *off,
                          const uint32_t *idx, const int32_t *wind);
/* The library's requests, made from arrays (api/lib.c builds options and op as small JSON values
 * and the kinds check them as in a JSON request): *parsed as the kind's parse gives it. */
int api_lines_make(const double *seg, size_t n, const json_t *options, void **parsed,
                   api_error *err);
int api_polygons_make(size_t npoly, const uint32_t *poly_off, const uint32_t *ring_off,
                      const double *xy, const json_t *op, const json_t *options, void **parsed,
                      api_error *err);
/* s (n solids) taken over as api_solids_run_direct takes them. */
int api_solids_make(struct solid *s, size_t n, const json_t *op, const json_t *options,
                    void **parsed, api_error *err);

#endif
