/* cellar.h — cellar as a library: arrangements and Booleans of 2D segments, 2D polygons and 3D
 * solids, arrays in and arrays out (README "The library").
 *
 *   #include <cellar.h>          cc prog.c $(pkg-config --cflags --libs cellar)
 *
 *   double seg[] = {0, 0, 2, 0,  2, 0, 1, 2,  1, 2, 0, 0};   a triangle's sides x1, y1, x2, y2
 *   cellar_result *r;
 *   cellar_error e;
 *   if (cellar_arrangement2d(seg, 3, NULL, &r, &e)) { fprintf(stderr, "%s\n", e.msg); ... }
 *   const cellar_array *V = cellar_result_get(r, "V");  V->data: V->rows x 2 doubles
 *   cellar_result_free(r);
 *
 * Every entry point runs the same core as the daemon and the CLI, with the same checks, limits
 * and messages, and gives the same complex: the arrays of a result are those of the result JSON
 * (README "Results"), named as the .npz output names them ("V", "EV", "FV.indptr",
 * "FV.indices", "operators.d1.data", "result.holes.face", ...), read where they lie: the
 * result owns them, and cellar_result_free() frees them all.  Nothing is written as JSON
 * except the few numbers of cellar_result_json() (dim, stats).
 *
 * Errors are values: a function returns CELLAR_OK (0) or a status (an HTTP code: 422 bad input,
 * 499 canceled, 503 out of memory, 500 a bug of ours) and fills the caller's cellar_error
 * (may be NULL) with a message naming the input element ("polygons[3] ring 1 point 4: expected
 * finite numbers", "solids[1].FV[7][2]: expected a vertex index below 8").  Nothing prints or
 * exits.
 *
 * Threads: every function is reentrant and may run on many threads at once (no global state
 * but the counters of the core's limits); each call starts its own worker threads
 * (cellar_options.threads) and joins them before it returns.  The callbacks are called from
 * those threads, one call at a time.
 *
 * Ownership: inputs are borrowed for the call only.  A result belongs to the caller until
 * cellar_result_free(); every pointer read from it (arrays, names, JSON text) lives as long as
 * it.  cellar_run_json()'s output is freed with cellar_free().
 *
 * Only names beginning with cellar_ / CELLAR_ are exported (README "The library"). */
#ifndef CELLAR_H
#define CELLAR_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(__GNUC__)
#define CELLAR_EXPORT __attribute__((visibility("default")))
#else
#define CELLAR_EXPORT
#endif

#define CELLAR_VERSION_MAJOR 0
#define CELLAR_VERSION_MINOR 3
#define CELLAR_VERSION_PATCH 0

enum {
    CELLAR_OK = 0,
    CELLAR_EJSON = 400,     /* cellar_run_json: the body is not JSON */
    CELLAR_EINVALID = 422,  /* the input, an option or a limit */
    CELLAR_ECANCELED = 499, /* cellar_options.cancel asked to stop */
    CELLAR_EINTERNAL = 500, /* a bug of ours: an invariant of the core failed */
    CELLAR_ENOMEM = 503     /* out of memory */
};

#define CELLAR_ERRMAX 256
typedef struct cellar_error {
    int status;              /* CELLAR_OK or one of CELLAR_E* */
    char msg[CELLAR_ERRMAX]; /* NUL-terminated, "" on success */
} cellar_error;

/* Options; a zeroed struct (or NULL) gives every default. */
typedef struct cellar_options {
    double precision;   /* > 0: the snapping grid step; 0: the default from the extent */
    int threads;        /* worker threads; <= 0: the number of online CPUs */
    const char *fields; /* NULL: the default; else the result's parts, names separated by
                           commas: "V,EV,FV,FE,holes,exterior,stats,operators,membership,result"
                           (3D adds CF, CV), as options.fields of the JSON request */
    const char *fill;   /* NULL: the default; "odd", "nonzero" or "positive": where a polygon's
                           or a solid's inside is, by its winding number */
    int keep_dangling;  /* 2D: keep bridges and dangling edges */
    int operators;      /* non-zero: the boundary operators too (as fields "operators") */
    /* may be NULL: asked, from the running threads, at each report of progress (whether or
     * not progress is given): each new stage, and every thousandth of the run, about a
     * thousand times a run at most; a non-zero answer stops the run, which then returns
     * CELLAR_ECANCELED */
    int (*cancel)(void *udata);
    /* may be NULL: told, at the same times, the stage running and the fraction of the whole run
     * done, 0 to 1, neither of which goes back (the stages: cellar_stage_name) */
    void (*progress)(void *udata, const char *stage, double fraction);
    void *udata; /* passed to cancel and progress */
} cellar_options;

/* The type of an array's elements. */
typedef enum cellar_dtype {
    CELLAR_F64 = 1, /* double */
    CELLAR_I32 = 2, /* int32_t: signed indices ±(i+1), winding numbers */
    CELLAR_U32 = 3, /* uint32_t: indices, offsets */
    CELLAR_I8 = 4,  /* int8_t: the operators' ±1 */
    CELLAR_U64 = 5  /* uint64_t: large offsets, shapes */
} cellar_dtype;

/* One array of a result: rows x cols elements of type dtype, row-major (cols 1: a vector). */
typedef struct cellar_array {
    const char *name; /* "V", "FV.indptr", ... */
    cellar_dtype dtype;
    size_t rows, cols;
    const void *data; /* rows * cols elements; may be NULL when rows is 0 */
} cellar_array;

typedef struct cellar_result cellar_result;

/* A 2D arrangement of n segments seg[4i .. 4i+3] = x1, y1, x2, y2 (the JSON kind "lines"). */
CELLAR_EXPORT int cellar_arrangement2d(const double *seg, size_t n, const cellar_options *o,
                                       cellar_result **out, cellar_error *err);

/* Polygons with holes and a Boolean over them (the JSON kind "polygons"): polygon p has the
 * rings poly_off[p] .. poly_off[p+1] (its outer ring first, then its holes; any orientation),
 * ring r the points ring_off[r] .. ring_off[r+1] (closed or not: a last point equal to the
 * first is dropped; at least 3 points), point i at xy[2i], xy[2i+1].  poly_off has npoly + 1
 * entries, ring_off poly_off[npoly] + 1.  op: "union", "intersection", "difference", "xor", or an
 * expression over the polygons' indices as JSON text, such as "[\"-\", 0, [\"+\", 1, 2]]". */
CELLAR_EXPORT int cellar_polygons(size_t npoly, const uint32_t *poly_off, const uint32_t *ring_off,
                                  const double *xy, const char *op, const cellar_options *o,
                                  cellar_result **out, cellar_error *err);

/* One solid: nv vertices V[3i .. 3i+2] and nf faces.  With face_off NULL every face is a
 * triangle F[3f .. 3f+2]; else face f is the polygon F[face_off[f] .. face_off[f+1])
 * (face_off: nf + 1 entries).  Faces are counter-clockwise seen from outside (a solid turned
 * inside out is turned back, and said so in stats.warnings). */
typedef struct cellar_solid {
    const double *V;
    size_t nv;
    const uint32_t *F;
    const uint32_t *face_off;
    size_t nf;
} cellar_solid;

/* The 3D arrangement of n closed solids and, with op (may be NULL), a Boolean over them (the JSON
 * kind "solids"); op as cellar_polygons'. */
CELLAR_EXPORT int cellar_solids(const cellar_solid *s, size_t n, const char *op,
                                const cellar_options *o, cellar_result **out, cellar_error *err);

/* The result's arrays: cellar_result_array(r, i) for i < cellar_result_count(r), in the order
 * of the result JSON's keys; cellar_result_get(r, name) the one of that name, or NULL. */
CELLAR_EXPORT size_t cellar_result_count(const cellar_result *r);
CELLAR_EXPORT const cellar_array *cellar_result_array(const cellar_result *r, size_t i);
CELLAR_EXPORT const cellar_array *cellar_result_get(const cellar_result *r, const char *name);
/* 2 or 3 */
CELLAR_EXPORT int cellar_result_dim(const cellar_result *r);
/* The result's members that are no arrays, as a JSON object: {"dim": d, "stats": {...}} (stats
 * when the fields have it), NUL-terminated. */
CELLAR_EXPORT const char *cellar_result_json(const cellar_result *r);
/* Frees the result and everything read from it; safe on NULL. */
CELLAR_EXPORT void cellar_result_free(cellar_result *r);

/* The JSON entry point of the CLI and the daemon: a request {"kind": ...} (README "Requests")
 * in body[0 .. len), its result JSON (one line and "\n") in *out (*outlen bytes, freed with
 * cellar_free()).  o: threads, cancel and progress are used; the rest is the request's. */
CELLAR_EXPORT int cellar_run_json(const char *body, size_t len, const cellar_options *o, char **out,
                                  size_t *outlen, cellar_error *err);
CELLAR_EXPORT void cellar_free(void *p);

/* The stages a run of kind ("lines", "polygons", "solids", ...) tells progress, in order: the
 * i-th name, NULL past the last. */
CELLAR_EXPORT const char *cellar_stage_name(const char *kind, size_t i);

/* "0.3.0" */
CELLAR_EXPORT const char *cellar_version(void);

#ifdef __cplusplus
}
#endif

#endif
