/* cellar.c — the command-line tool: runs requests offline and generates test inputs.
 *
 *   cellar run REQUEST.json|-        the result JSON the service returns for the request, same
 *                                    bytes (api_run_json()), on stdout
 *   cellar svg DRAWING.svg|- [--normalize] [--y-up] [--rect-diagonal] [--precision X]
 *              [--keep-dangling] [--flatten-tolerance X] [--options JSON]
 *                                    the same for the request {"kind":"svg","svg":<the file>,
 *                                    "options":{...}} (the flags set options; --options gives
 *                                    the others)
 *   cellar solids A.obj B.off ... [--faces] [--groups] [--precision X] [--options JSON]
 *                                    the same for the request {"kind":"solids","solids":[...]}
 *                                    of the solids read from the files (.obj, .off, .stl, .ply
 *                                    or .3mf by the extension, api/meshio.h; "-": standard
 *                                    input as OBJ; a solid per object "o" of an OBJ file, and
 *                                    with --groups per group "g"; per build item of a 3MF), or
 *                                    with --faces
 *                                    {"kind":"solids","faces":{...}}: all their faces as one
 *                                    soup; --format obj writes the cells as a Wavefront OBJ
 *   cellar gen lines N SCALING SEED  N random segments, as the seeds' randomLines(N, scaling)
 *   cellar gen grid K                K horizontal and K vertical segments: (K-1)^2 faces
 *
 * Exit status: 0 success, 1 the request failed (message "cellar: <where>: <what>" on stderr:
 * malformed or hostile SVG is "cellar: svg: line L, column C: ...") or an I/O error, 2 a usage
 * error.  Options (anywhere on the line): --threads N, --options JSON (gen, svg, solids: the
 * request's "options"), the svg and solids flags, --format, --quiet, --progress, --help,
 * --version.  A run draws a progress bar on stderr when stderr is a terminal.
 *
 * The random generator is our own (xoshiro256** seeded by splitmix64) and the arithmetic is
 * written one operation per statement (no contraction into fused multiply-adds), so that a seed
 * gives the same bytes on every machine and compiler.  Unlike the seeds, points are not rounded
 * to PRECISION decimal digits (vcode): that would put many endpoints on a coarse common grid,
 * a different (and easier) input; snapping is the request's "precision" option instead.
 *
 * Layout: main() parses the line (parse_option: number_option, value_option, render_option),
 * refuses a flag given to a command it is not for (misplaced_flag) and runs the command
 * (dispatch); every command that runs a request ends in run_request() (run, then write the
 * output), and reads --options with options_object(); solids reads its files (solids_read) and
 * writes its request (solids_request), polygons reads its layers (polygons_layers) and writes
 * GeoJSON with their reference system itself (polygons_own).
 *
 * Ownership: everything is freed before exit; the API's output buffer is the caller's to free.
 */
#include "api/api.h"
#include "api/meshio.h"
#include "api/render.h"
#include "core/arr2.h"
#include "core/solid.h"
#include "core/mem.h"

#include <errno.h>
#include <jansson.h>
#include <malloc.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define EXIT_USAGE 2

static const char usage_text[] =
    "usage: cellar [--threads N] [--quiet | --progress] COMMAND ...\n"
    "\n"
    "  cellar run REQUEST.json         run a request (\"-\": standard input) and print the\n"
    "                                  result JSON, exactly as the service returns it\n"
    "  cellar gen lines N SCALING SEED [--options JSON]\n"
    "                                  print a request of N random segments: two random points\n"
    "                                  of the unit square scaled by SCALING about their midpoint\n"
    "                                  and moved to a random point, then everything translated\n"
    "                                  to x, y >= 0 (the seeds' randomLines); the same SEED\n"
    "                                  gives the same bytes everywhere\n"
    "  cellar gen grid K [--options JSON]\n"
    "                                  print a request of K horizontal and K vertical segments\n"
    "                                  (0,i)-(K-1,i), (i,0)-(i,K-1): (K-1)^2 faces\n"
    "  cellar svg DRAWING.svg [--normalize] [--y-up] [--rect-diagonal] [--precision X]\n"
    "             [--keep-dangling] [--flatten-tolerance X] [--options JSON]\n"
    "                                  the complex of an SVG drawing (\"-\": standard input):\n"
    "                                  runs {\"kind\":\"svg\",\"svg\":...,\"options\":...}\n"
    "  cellar solids A.obj B.off ... [--faces] [--groups] [--precision X] [--op OP]\n"
    "               [--options JSON]   the arrangement of the solids in the files (Wavefront\n"
    "                                  OBJ, OFF, STL, PLY or 3MF by the extension, \"-\": OBJ\n"
    "                                  on standard input), each a closed surface (it may pass\n"
    "                                  through itself): a solid per OFF, STL or PLY file, per\n"
    "                                  object \"o\" of an OBJ file (--groups: per group \"g\"\n"
    "                                  too) and per mesh a 3MF file builds; runs {\"kind\":\n"
    "                                  \"solids\",\"solids\":[...]}; --faces: all their faces\n"
    "                                  as one soup\n"
    "  cellar polygons A.geojson B.shp ... --op OP [--format geojson|gpkg|json|svg|request]\n"
    "               [--output FILE] [--precision X] [--options JSON]\n"
    "                                  GIS layers overlaid: each file a layer named by its base\n"
    "                                  name (GeoJSON read as it is; Shapefile, GeoPackage,\n"
    "                                  FlatGeobuf and every vector format GDAL reads through\n"
    "                                  GDAL's ogr2ogr); OP over the layers: union,\n"
    "                                  intersection, difference, xor or an expression such as\n"
    "                                  '[\"&\", \"parcels\", \"zones\"]'; --format geojson: one\n"
    "                                  Feature per piece with its parents' attributes\n"
    "                                  (\"parcels.owner\"); gpkg: the same as a GeoPackage\n"
    "                                  (--output FILE.gpkg, by ogr2ogr)\n"
    "\n"
    "options:\n"
    "  --threads N       worker threads of the core (default 0: one per CPU)\n"
    "  --quiet           no progress bar (one is drawn on stderr when it is a terminal)\n"
    "  --progress        progress on stderr even when it is not a terminal: a line per\n"
    "                    stage and per tenth of the run (stage, percent, seconds)\n"
    "  --options JSON    gen, svg, solids: a JSON object used as the request's \"options\",\n"
    "                    e.g.\n"
    "                    '{\"precision\":1e-6,\"fields\":[\"V\",\"EV\",\"stats\"]}'\n"
    "  svg: --normalize (into the unit square, y up), --y-up (y' = -y), --rect-diagonal\n"
    "       (a rect is its diagonal), --precision X (grid step), --keep-dangling,\n"
    "       --flatten-tolerance X (curves, in drawing units): the options of the same names\n"
    "  solids: --precision X (grid step), --faces (one face soup: no closedness),\n"
    "       --op union|intersection|difference|xor|'[\"-\",0,[\"+\",1,2]]' (a Boolean\n"
    "       result; with --format obj the result solid is written)\n"
    "  svg, solids: --format request   print the request instead of running it (to post it\n"
    "       to the service: ... --format request | curl --data-binary @- ...)\n"
    "  run, svg, solids: --format json|svg|geojson|obj|npz|stl|off|3mf|glb   the result\n"
    "       JSON (default), a\n"
    "       picture of a 2D result (SVG: faces filled, edges, y up, a Boolean's result on top),\n"
    "       a map of it (GeoJSON FeatureCollection of the faces; of a Boolean, its result as\n"
    "       one MultiPolygon), the cells of a 3D result (Wavefront OBJ: a group per cell, faces\n"
    "       triangulated facing out) or its arrays for NumPy (npz: numpy.load reads it; see\n"
    "       the README); with svg: --explode K (faces moved apart, K >= 1),\n"
    "       --numbers (vertex and face numbers), --width PX; with geojson: --cells all (a\n"
    "       Boolean's faces too, with membership) or result; with obj: --explode K (cells\n"
    "       moved apart); stl (binary), off, 3mf: the cells of a 3D result, or a Boolean's\n"
    "       result solid only; glb (glTF 2.0 binary): a node per cell and one for a\n"
    "       Boolean's result (--explode K moves the cells' nodes)\n"
    "  --help            this text\n"
    "  --version         the version\n"
    "\n"
    "exit status: 0 success, 1 invalid request or I/O error, 2 usage error\n";

static int usage_error(const char *fmt, const char *arg) __attribute__((format(printf, 1, 0)));

static int usage_error(const char *fmt, const char *arg)
{
    fprintf(stderr, "cellar: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n(cellar --help for usage)\n");
    return EXIT_USAGE;
}

/* ---- random numbers: splitmix64 to seed xoshiro256** ---------------------------------------- */

typedef struct rng {
    uint64_t s[4];
} rng;

static uint64_t splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return z ^ (z >> 31);
}

static void rng_seed(rng *r, uint64_t seed)
{
    for (int i = 0; i < 4; i++) r->s[i] = splitmix64(&seed);
}

static uint64_t rotl(uint64_t x, int k)
{
    return (x << k) | (x >> (64 - k));
}

static uint64_t rng_next(rng *r)
{
    uint64_t *s = r->s;
    uint64_t result = rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

/* A uniform double in [0, 1): 53 random bits. */
static double rng_unit(rng *r)
{
    return (double)(rng_next(r) >> 11) * 0x1.0p-53;
}

/* One segment of randomLines: redge(scaling) without the seeds' rounding to PRECISION digits. */
static void random_segment(rng *r, double scaling, double s[4])
{
    double v1x = rng_unit(r), v1y = rng_unit(r);
    double v2x = rng_unit(r), v2y = rng_unit(r);
    double px = rng_unit(r), py = rng_unit(r);
    double cx = (v1x + v2x) / 2, cy = (v1y + v2y) / 2;
    const double v[4] = {v1x - cx, v1y - cy, v2x - cx, v2y - cy};
    for (int i = 0; i < 4; i++) {
        double d = v[i] * scaling; /* rounded here: an assignment is never fused with the + */
        s[i] = d + (i % 2 ? py : px);
    }
}

/* ---- output -------------------------------------------------------------------------------- */

static void put_double(FILE *f, double x)
{
    char buf[API_DOUBLE_MAX];
    fwrite(buf, 1, api_format_double(x, buf), f);
}

static void put_segment(FILE *f, size_t i, double x1, double y1, double x2, double y2)
{
    fputs(i ? ",[[" : "[[", f);
    put_double(f, x1);
    fputc(',', f);
    put_double(f, y1);
    fputs("],[", f);
    put_double(f, x2);
    fputc(',', f);
    put_double(f, y2);
    fputs("]]", f);
}

/* Writes v compactly to f, numbers in the format of our results (jansson's own dump prints 0.1
 * as 0.10000000000000001).  Depth is bounded by jansson's parser. */
static void put_json(FILE *f, const json_t *v)
{
    const char *key;
    json_t *x;
    size_t i;
    char *s;
    switch (json_typeof(v)) {
    case JSON_OBJECT:
        fputc('{', f);
        i = 0;
        json_object_foreach((json_t *)v, key, x)
        {
            json_t *k = json_string(key);
            if (i++) fputc(',', f);
            put_json(f, k);
            fputc(':', f);
            put_json(f, x);
            json_decref(k);
        }
        fputc('}', f);
        break;
    case JSON_ARRAY:
        fputc('[', f);
        json_array_foreach(v, i, x)
        {
            if (i) fputc(',', f);
            put_json(f, x);
        }
        fputc(']', f);
        break;
    case JSON_INTEGER:
        fprintf(f, "%" JSON_INTEGER_FORMAT, json_integer_value(v));
        break;
    case JSON_REAL:
        put_double(f, json_real_value(v));
        break;
    default: /* strings and literals: jansson escapes them */
        s = json_dumps(v, JSON_ENCODE_ANY | JSON_COMPACT);
        if (s) fputs(s, f);
        free(s);
        break;
    }
}

static int finish_output(const json_t *options)
{
    fputc(']', stdout);
    if (options) {
        fputs(",\"options\":", stdout);
        put_json(stdout, options);
    }
    fputs("}\n", stdout);
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "cellar: writing the output: %s\n", strerror(errno));
        return 1;
    }
    return 0;
}

/* ---- arguments ----------------------------------------------------------------------------- */

/* Parses a decimal unsigned integer (the whole string); returns 0 on success. */
static int parse_u64(const char *s, uint64_t *out)
{
    char *end;
    unsigned long long v;
    if (!*s || *s == '-' || *s == '+' || *s == ' ') return -1;
    errno = 0;
    v = strtoull(s, &end, 10);
    if (errno || *end) return -1;
    *out = v;
    return 0;
}

/* Parses the --options text: a JSON object that is valid as a "lines" request's options.
 * Returns it (caller json_decref()s) or NULL after printing why. */
static json_t *options_parse(const char *text)
{
    json_error_t je;
    json_t *o = json_loads(text, JSON_REJECT_DUPLICATES, &je), *req = NULL;
    char *body = NULL;
    api_error err;
    if (!o || !json_is_object(o)) {
        if (o)
            fprintf(stderr, "cellar: --options: expected a JSON object\n");
        else
            fprintf(stderr, "cellar: --options: line %d, column %d: %s\n", je.line, je.column,
                    je.text);
        goto fail;
    }
    req = json_pack("{s:s, s:[], s:O}", "kind", "lines", "lines", "options", o);
    body = req ? json_dumps(req, JSON_COMPACT) : NULL;
    if (!body) {
        fprintf(stderr, "cellar: out of memory\n");
        goto fail;
    }
    if (api_check_json(body, strlen(body), NULL, NULL, &err) != API_OK) {
        fprintf(stderr, "cellar: --options: %s\n", err.msg);
        goto fail;
    }
    free(body);
    json_decref(req);
    return o;
fail:
    free(body);
    json_decref(req);
    json_decref(o);
    return NULL;
}

static int gen_lines(char **pos, int npos, const char *options_text)
{
    uint64_t n, seed;
    double scaling, s[4], xmin = INFINITY, ymin = INFINITY;
    char *end;
    json_t *options = NULL;
    rng r;
    int rc;
    if (npos != 5) return usage_error("%s", "gen lines takes N SCALING SEED");
    if (parse_u64(pos[2], &n) || n > ARR2_MAX_SEGMENTS)
        return usage_error("gen lines: N must be an integer in 0..20000000, not \"%s\"", pos[2]);
    errno = 0;
    scaling = strtod(pos[3], &end);
    if (errno || *end || end == pos[3] || !isfinite(scaling) || scaling < 0)
        return usage_error("gen lines: SCALING must be a finite number >= 0, not \"%s\"", pos[3]);
    if (parse_u64(pos[4], &seed))
        return usage_error("gen lines: SEED must be an integer in 0..2^64-1, not \"%s\"", pos[4]);
    if (options_text && !(options = options_parse(options_text))) return EXIT_USAGE;
    /* Two passes over the same stream: the minimum first, then the translated segments, so the
     * generator needs no memory whatever N is. */
    rng_seed(&r, seed);
    for (uint64_t i = 0; i < n; i++) {
        random_segment(&r, scaling, s);
        xmin = fmin(xmin, fmin(s[0], s[2]));
        ymin = fmin(ymin, fmin(s[1], s[3]));
    }
    rng_seed(&r, seed);
    fputs("{\"kind\":\"lines\",\"lines\":[", stdout);
    for (uint64_t i = 0; i < n; i++) {
        random_segment(&r, scaling, s);
        put_segment(stdout, i, s[0] - xmin, s[1] - ymin, s[2] - xmin, s[3] - ymin);
    }
    rc = finish_output(options);
    json_decref(options);
    return rc;
}

static int gen_grid(char **pos, int npos, const char *options_text)
{
    uint64_t k;
    json_t *options = NULL;
    size_t at = 0;
    int rc;
    if (npos != 3) return usage_error("%s", "gen grid takes K");
    if (parse_u64(pos[2], &k) || k > ARR2_MAX_SEGMENTS / 2)
        return usage_error("gen grid: K must be an integer in 0..10000000, not \"%s\"", pos[2]);
    if (options_text && !(options = options_parse(options_text))) return EXIT_USAGE;
    fputs("{\"kind\":\"lines\",\"lines\":[", stdout);
    for (uint64_t i = 0; i < k; i++)
        put_segment(stdout, at++, 0, (double)i, (double)(k - 1), (double)i);
    for (uint64_t i = 0; i < k; i++)
        put_segment(stdout, at++, (double)i, 0, (double)i, (double)(k - 1));
    rc = finish_output(options);
    json_decref(options);
    return rc;
}

/* Reads a whole file ("-": stdin) into a malloc'd buffer; NULL after printing why. */
static char *read_all(const char *path, size_t *len)
{
    FILE *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "rb");
    char *buf = NULL, *p;
    size_t cap = 0, n = 0;
    if (!f) {
        fprintf(stderr, "cellar: %s: %s\n", path, strerror(errno));
        return NULL;
    }
    struct stat st; /* a regular file: one buffer of its size (and one byte to see the end) */
    if (f != stdin && fstat(fileno(f), &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0 &&
        (uint64_t)st.st_size < SIZE_MAX / 2) {
        cap = (size_t)st.st_size + 1;
        if (!(buf = mem_malloc(cap))) {
            fprintf(stderr, "cellar: %s: out of memory\n", path);
            goto fail;
        }
    }
    for (;;) {
        if (n == cap) {
            cap = cap ? 2 * cap : 1 << 16;
            p = mem_realloc(buf, cap);
            if (!p) {
                fprintf(stderr, "cellar: %s: out of memory\n", path);
                goto fail;
            }
            buf = p;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0) break;
    }
    if (ferror(f)) {
        fprintf(stderr, "cellar: %s: %s\n", path, strerror(errno));
        goto fail;
    }
    if (f != stdin) fclose(f);
    *len = n;
    return buf;
fail:
    if (f != stdin) fclose(f);
    free(buf);
    return NULL;
}

/* --format request: the request itself, not a row of render_formats (a format added there
 * takes the next index) */
#define OUT_REQUEST (-2)
/* --format gpkg (polygons): GeoJSON of the result written to a GeoPackage by ogr2ogr */
#define OUT_GPKG (-3)

/* What run, svg and solids print: the result JSON, or a picture, map or mesh of it
 * (api/render.h). */
typedef struct out_format {
    int kind; /* an index into render_formats (0 json, 1 svg, 2 geojson, 3 obj), or OUT_REQUEST */
    render_opts ro;
    const char *first;   /* the first SVG-only flag given, for "is for --format svg" errors */
    const char *explode; /* --explode when given: for --format svg or obj */
    const char *cells;   /* --cells when given: for --format geojson */
} out_format;

/* The last bytes of stdout out (after a result was streamed there, or written); returns the
 * exit status. */
static int write_streamed(void)
{
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "cellar: writing the output: %s\n", strerror(errno));
        return 1;
    }
    return 0;
}

/* Writes the result (or its rendering) to stdout; returns the exit status. */
static int write_result(const char *out, size_t outlen, const out_format *of)
{
    char *pic = NULL;
    size_t piclen = 0;
    api_error err;
    const render_format *f = &render_formats[of->kind];
    if (f->render && f->render(out, outlen, &of->ro, &pic, &piclen, &err) != API_OK) {
        fprintf(stderr, "cellar: --format %s: %s\n", f->name, err.msg);
        return 1;
    }
    fwrite(pic ? pic : out, 1, pic ? piclen : outlen, stdout);
    free(pic);
    return write_streamed();
}

/* --format request: the request a command would run, a line of JSON, for curl. */
static int write_request(const char *body, size_t len)
{
    fwrite(body, 1, len, stdout);
    fputc('\n', stdout);
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "cellar: writing the output: %s\n", strerror(errno));
        return 1;
    }
    return 0;
}

/* ---- progress on stderr ----------------------------------------------------------------- *
 * A bar redrawn in place when stderr is a terminal (at most ten times a second), or with
 * --progress a line per stage and per tenth of the run (for logs); --quiet: nothing. */
enum { PROGRESS_OFF, PROGRESS_BAR, PROGRESS_LINES };
static struct {
    int mode;
    double t0;
    double last_draw, last_f;
    char stage[32];
    int drawn; /* a bar is on the terminal's last line */
} bar;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void progress_cb(void *udata, const char *stage, double f)
{
    (void)udata;
    double t = now_s() - bar.t0;
    int new_stage = strcmp(stage, bar.stage) != 0;
    if (bar.mode == PROGRESS_LINES) {
        if (!new_stage && (int)(f * 10) == (int)(bar.last_f * 10)) return;
        fprintf(stderr, "cellar: %-11s %5.1f%% at %.2f s\n", stage, 100 * f, t);
    } else {
        if (!new_stage && t - bar.last_draw < 0.1) return;
        char cells[31];
        int k = (int)(f * 30);
        for (int i = 0; i < 30; i++) cells[i] = i < k ? '#' : '.';
        cells[30] = 0;
        fprintf(stderr, "\r\033[K[%s] %3d%% %-11s %.1f s", cells, (int)(100 * f), stage, t);
        bar.drawn = 1;
    }
    fflush(stderr);
    snprintf(bar.stage, sizeof bar.stage, "%s", stage);
    bar.last_draw = t;
    bar.last_f = f;
}

/* The end of a run: the bar is cleared (the result or the error follows on a clean line). */
static void progress_end(void)
{
    if (bar.mode == PROGRESS_LINES)
        fprintf(stderr, "cellar: %-11s %5.1f%% at %.2f s\n", "end", 100 * bar.last_f,
                now_s() - bar.t0);
    if (bar.drawn) fputs("\r\033[K", stderr);
    bar.drawn = 0;
}

static api_run_opts run_opts(int threads, const out_format *of)
{
    api_run_opts ro = {.threads = threads, .stream = of->kind == 0 ? stdout : NULL};
    if (bar.mode != PROGRESS_OFF) {
        ro.progress = progress_cb;
        bar.t0 = now_s();
        bar.stage[0] = 0;
        bar.last_f = 0;
    }
    return ro;
}

/* Runs the request body[0..len) as `cellar run` runs it (JSON streamed to stdout, any other
 * format rendered from the whole result) and writes the output: the exit status, or -1 when the
 * request failed (*err says why; nothing printed). */
static int run_request(const char *body, size_t len, int threads, const out_format *of,
                       api_error *err)
{
    char *out = NULL;
    size_t outlen = 0;
    api_run_opts ro = run_opts(threads, of);
    int r = api_run_json_ex(body, len, &ro, &out, &outlen, err) == API_OK ? 0 : -1;
    progress_end();
    if (r == 0) r = ro.stream ? write_streamed() : write_result(out, outlen, of);
    free(out);
    return r;
}

/* The request's "options" of --options (an object; none given: an empty one), or NULL after
 * the message is printed (the caller exits EXIT_USAGE); where: say where the text is not
 * JSON. */
static json_t *options_object(const char *options_text, int where)
{
    json_error_t je;
    json_t *opts =
        options_text ? json_loads(options_text, JSON_REJECT_DUPLICATES, &je) : json_object();
    if (json_is_object(opts)) return opts;
    if (opts || !options_text || !where)
        fprintf(stderr, "cellar: --options: expected a JSON object\n");
    else
        fprintf(stderr, "cellar: --options: line %d, column %d: %s\n", je.line, je.column, je.text);
    json_decref(opts);
    return NULL;
}

static int run(char **pos, int npos, int threads, const out_format *of)
{
    size_t len;
    char *body;
    api_error err;
    int rc;
    if (npos != 2) return usage_error("%s", "run takes one REQUEST.json (or - for stdin)");
    body = read_all(pos[1], &len);
    if (!body) return 1;
    /* JSON goes out as it is made (a large result never sits whole in memory); pictures and
     * maps need the whole result */
    rc = run_request(body, len, threads, of, &err);
    free(body);
    if (rc < 0) {
        fprintf(stderr, "cellar: %s\n", err.msg);
        return 1;
    }
    return rc;
}

/* The svg and solids commands' flags: each sets the request option of the same name, but
 * --faces, which makes the solids one face soup. */
typedef struct svg_flags {
    int normalize, y_up, rect_diagonal, keep_dangling;
    double precision, tolerance; /* 0: not given */
    const char *first;           /* the first svg-only flag given (for "is for svg" errors) */
    int faces;                   /* solids --faces */
    int groups;                  /* solids --groups: each "g" of an OBJ file a solid too */
    const char *op;              /* solids --op: a name, or a JSON expression tree */
} svg_flags;

/* Parses a number > 0 for flag; returns 0 on success. */
static int parse_positive(const char *flag, const char *val, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(val, &end);
    if (errno || *end || end == val || !isfinite(*out) || !(*out > 0)) {
        char msg[160];
        snprintf(msg, sizeof msg, "%s: expected a number > 0, not \"%.64s\"", flag, val);
        usage_error("%s", msg);
        return -1;
    }
    return 0;
}

/* The request req as one line of compact JSON into *body (malloc'd; req NULL: out of memory
 * already): 0, or 1 with the message printed. */
static int dump_request(const json_t *req, char **body)
{
    *body = req ? json_dumps(req, JSON_COMPACT) : NULL;
    if (*body) return 0;
    fprintf(stderr, "cellar: out of memory\n");
    return 1;
}

static int svg_command(char **pos, int npos, const char *options_text, const svg_flags *fl,
                       int threads, const out_format *of)
{
    size_t len;
    char *text = NULL, *body = NULL;
    json_t *opts = NULL, *req = NULL, *str = NULL;
    api_error err;
    int rc = 1;
    if (npos != 2) return usage_error("%s", "svg takes one DRAWING.svg (or - for stdin)");
    opts = options_object(options_text, 1);
    if (!opts) return EXIT_USAGE;
    if ((fl->normalize && json_object_set_new(opts, "normalize", json_true())) ||
        (fl->y_up && json_object_set_new(opts, "y_up", json_true())) ||
        (fl->rect_diagonal && json_object_set_new(opts, "rect2lines", json_string("diagonal"))) ||
        (fl->keep_dangling && json_object_set_new(opts, "keep_dangling", json_true())) ||
        (fl->precision > 0 && json_object_set_new(opts, "precision", json_real(fl->precision))) ||
        (fl->tolerance > 0 &&
         json_object_set_new(opts, "flatten_tolerance", json_real(fl->tolerance)))) {
        fprintf(stderr, "cellar: out of memory\n");
        goto out;
    }
    text = read_all(pos[1], &len);
    if (!text) goto out;
    str = json_stringn(text, len);
    if (!str) {
        fprintf(stderr,
                "cellar: %s: not UTF-8 text (the request carries the drawing as a JSON "
                "string)\n",
                pos[1]);
        goto out;
    }
    req = json_pack("{s:s, s:o, s:O}", "kind", "svg", "svg", str, "options", opts);
    str = NULL; /* the "o" format took it, also on failure */
    if (dump_request(req, &body)) goto out;
    if (of->kind == OUT_REQUEST) {
        rc = write_request(body, strlen(body));
        goto out;
    }
    rc = run_request(body, strlen(body), threads, of, &err);
    if (rc < 0) {
        fprintf(stderr, "cellar: %s\n", err.msg);
        rc = 1;
    }
out:
    free(body);
    free(text);
    json_decref(str);
    json_decref(req);
    json_decref(opts);
    return rc;
}

/* ---- solids ----------------------------------------------------------------------------- */

/* Writes the cycle c of s (indices shifted by off) as a JSON array. */
static void put_cycle(FILE *f, const solid *s, size_t c, size_t off)
{
    fputc('[', f);
    for (uint32_t i = s->cyc_off[c]; i < s->cyc_off[c + 1]; i++)
        fprintf(f, i > s->cyc_off[c] ? ",%zu" : "%zu", (size_t)s->cyc[i] + off);
    fputc(']', f);
}

/* Writes {"V":[...],"FV":[...],"holes":{...}} of the n solids s as one (their vertices one
 * after the other): one solid, or with n > 1 the face soup of them all. */
static void put_solid_json(FILE *f, const solid *s, size_t n)
{
    size_t off = 0, face = 0;
    int first = 1;
    fputs("{\"V\":[", f);
    for (size_t k = 0; k < n; k++)
        for (size_t v = 0; v < s[k].nv; v++) {
            fputs(first ? "[" : ",[", f);
            first = 0;
            for (int a = 0; a < 3; a++) {
                if (a) fputc(',', f);
                put_double(f, s[k].V[3 * v + a]);
            }
            fputc(']', f);
        }
    fputs("],\"FV\":[", f);
    first = 1;
    for (size_t k = 0; k < n; off += s[k].nv, k++)
        for (size_t g = 0; g < s[k].nf; g++) {
            if (!first) fputc(',', f);
            first = 0;
            put_cycle(f, &s[k], s[k].face_off[g], off);
        }
    fputs("],\"holes\":{", f);
    first = 1;
    off = 0;
    for (size_t k = 0; k < n; off += s[k].nv, k++)
        for (size_t g = 0; g < s[k].nf; g++, face++) {
            if (s[k].face_off[g + 1] - s[k].face_off[g] < 2) continue;
            fprintf(f, first ? "\"%zu\":[" : ",\"%zu\":[", face);
            first = 0;
            for (size_t c = s[k].face_off[g] + 1; c < s[k].face_off[g + 1]; c++) {
                if (c > s[k].face_off[g] + 1) fputc(',', f);
                put_cycle(f, &s[k], c, off);
            }
            fputc(']', f);
        }
    fputs("}}", f);
}

/* The reader of a file by its extension (api/meshio.h); "-" is OBJ on standard input. */
static mesh_format solid_format(const char *path)
{
    if (strcmp(path, "-") == 0) return MESH_OBJ;
    return mesh_format_of_name(path);
}

/* The solids the files pos[1 .. nfiles] hold, into *sv (*n of them; (*from)[i]: the file of
 * solid i, an index into pos from 0): a solid per OFF, STL or PLY file, per object of an OBJ
 * file ("o"; with groups "g" too), per mesh object a 3MF file's build places.  0, or 1 with the
 * message printed (*sv then holds the solids read so far). */
static int solids_read(char **pos, size_t nfiles, int groups, solid **sv, size_t **from, size_t *n)
{
    size_t cap = 0;
    char rerr[256];
    *n = 0;
    for (size_t i = 0; i < nfiles; i++) {
        const char *path = pos[i + 1];
        size_t len, np = 0;
        char *text = read_all(path, &len);
        solid *parts = NULL;
        int r;
        if (!text) return 1;
        r = mesh_read(solid_format(path), text, len, groups, &parts, &np, rerr, sizeof rerr);
        free(text);
        if (r != 0) {
            fprintf(stderr, "cellar: %s: %s\n", strcmp(path, "-") ? path : "standard input", rerr);
            return 1;
        }
        if (*n + np > cap) {
            size_t c = 2 * (*n + np) + 4;
            solid *x = realloc(*sv, c * sizeof *x);
            size_t *y = x ? realloc(*from, c * sizeof *y) : NULL;
            if (x) *sv = x;
            if (y) *from = y;
            if (!x || !y) {
                for (size_t k = 0; k < np; k++) solid_free(&parts[k]);
                free(parts);
                fprintf(stderr, "cellar: out of memory\n");
                return 1;
            }
            cap = c;
        }
        for (size_t k = 0; k < np; k++) (*sv)[*n] = parts[k], (*from)[(*n)++] = i;
        free(parts);
    }
    return 0;
}

/* The request {"kind":"solids", "solids":[...] (with faces: "faces":{...}, one soup), "op",
 * "options"} of the n solids sv, written into *body (*blen bytes, malloc'd); 0, or 1 with the
 * message printed. */
static int solids_request(const solid *sv, size_t n, int faces, const json_t *op,
                          const json_t *opts, char **body, size_t *blen)
{
    FILE *m = open_memstream(body, blen);
    if (!m) {
        fprintf(stderr, "cellar: out of memory\n");
        return 1;
    }
    fputs("{\"kind\":\"solids\",", m);
    if (faces) {
        fputs("\"faces\":", m);
        put_solid_json(m, sv, n);
    } else {
        fputs("\"solids\":[", m);
        for (size_t i = 0; i < n; i++) {
            if (i) fputc(',', m);
            put_solid_json(m, &sv[i], 1);
        }
        fputc(']', m);
    }
    if (op) {
        fputs(",\"op\":", m);
        put_json(m, op);
    }
    if (json_object_size(opts)) {
        fputs(",\"options\":", m);
        put_json(m, opts);
    }
    fputc('}', m);
    if (fclose(m) != 0 || !*body) {
        fprintf(stderr, "cellar: out of memory\n");
        return 1;
    }
    return 0;
}

/* The message of a failed solids request, naming the file of "solids[i]..." too. */
static void solids_failed(const api_error *err, char **pos, const size_t *from, size_t n)
{
    size_t i;
    int k = -1;
    if (sscanf(err->msg, "solids[%zu]%n", &i, &k) == 1 && k > 0 && i < n)
        fprintf(stderr, "cellar: %s (solids[%zu] is %s)\n", err->msg, i,
                strcmp(pos[from[i] + 1], "-") ? pos[from[i] + 1] : "standard input");
    else
        fprintf(stderr, "cellar: %s\n", err->msg);
}

/* cellar solids FILE...: the request {"kind":"solids",...} of the solids the files hold, run as
 * `cellar run` runs it. */
static int solids_command(char **pos, int npos, const char *options_text, const svg_flags *fl,
                          int threads, const out_format *of)
{
    size_t nfiles = npos > 1 ? (size_t)npos - 1 : 0, n = 0, blen = 0, outlen;
    solid *sv = NULL;
    size_t *from = NULL; /* by solid: the file it comes from */
    char *body = NULL, *out = NULL;
    json_t *opts = NULL, *op = NULL;
    api_error err;
    int rc = 1;
    if (nfiles == 0)
        return usage_error("%s", "solids takes one or more files (.obj, .off, .stl, .ply, .3mf, "
                                 "- for OBJ on stdin)");
    for (size_t i = 0; i < nfiles; i++)
        if (!solid_format(pos[i + 1]))
            return usage_error("solids: \"%s\": expected a .obj, .off, .stl, .ply or .3mf file "
                               "(or - for OBJ on standard input)",
                               pos[i + 1]);
    opts = options_object(options_text, 1);
    if (!opts) return EXIT_USAGE;
    if (fl->precision > 0 && json_object_set_new(opts, "precision", json_real(fl->precision))) {
        fprintf(stderr, "cellar: out of memory\n");
        goto out;
    }
    if (solids_read(pos, nfiles, fl->groups, &sv, &from, &n)) goto out;
    if (fl->op) { /* a name ("union") or an expression tree (["-", 0, ["+", 1, 2]]) */
        op = fl->op[0] == '[' ? json_loads(fl->op, JSON_DECODE_ANY, NULL) : json_string(fl->op);
        if (!op) {
            fprintf(stderr, "cellar: --op: expected union, intersection, difference, xor or a "
                            "JSON expression such as '[\"-\", 0, [\"+\", 1, 2]]'\n");
            rc = EXIT_USAGE;
            goto out;
        }
    }
    if (!fl->faces && of->kind != OUT_REQUEST) {
        /* the solids as read, straight to the run: the bytes of `cellar run` on the request
         * that --format request prints, without writing and parsing it */
        api_run_opts ro = run_opts(threads, of);
        int r = api_solids_run_direct(sv, n, 0, op, json_object_size(opts) ? opts : NULL, &ro, &out,
                                      &outlen, &err);
        progress_end();
        sv = NULL; /* taken over, array and all */
        if (r == API_OK)
            rc = ro.stream ? write_streamed() : write_result(out, outlen, of);
        else
            solids_failed(&err, pos, from, n);
        goto out;
    }
    if (solids_request(sv, n, fl->faces, op, opts, &body, &blen)) goto out;
    if (of->kind == OUT_REQUEST) {
        rc = write_request(body, blen);
        goto out;
    }
    rc = run_request(body, blen, threads, of, &err);
    if (rc < 0) {
        solids_failed(&err, pos, from, n);
        rc = 1;
    }
out:
    free(body);
    free(out);
    for (size_t i = 0; sv && i < n; i++) solid_free(&sv[i]);
    free(sv);
    free(from);
    json_decref(op);
    json_decref(opts);
    return rc;
}

/* ---- polygons: GIS files as layers ---------------------------------------------------------
 * Each file is a layer named by its base name (a second "a" becomes "a_2").  GeoJSON (.geojson,
 * .json) is read as it is; every other vector format through GDAL's ogr2ogr (gdal-bin: GDAL
 * reads Shapefile, GeoPackage, FlatGeobuf, KML, GML, ... and writes GeoJSON for us), run as
 * a program without a shell.  The request is {"kind": "polygons", "layers": {...}, "op": ...};
 * --format gpkg writes the GeoJSON of the result to a GeoPackage with ogr2ogr again.  The
 * coordinates are taken as they are (no reprojection): layers in different reference systems
 * are refused. */

#define GIS_MAX_BYTES (4ul << 30) /* of one layer's GeoJSON from ogr2ogr */

/* Runs argv (argv[0] looked up in PATH) with its standard output into *out (malloc'd, *len
 * bytes, NUL-ended) when out is not NULL; its standard error passes through.  0, or -1 with
 * a message printed. */
static int run_program(char *const *argv, const char *what, char **out, size_t *len)
{
    int fd[2] = {-1, -1};
    posix_spawn_file_actions_t fa;
    pid_t pid;
    if (out && pipe(fd) != 0) {
        fprintf(stderr, "cellar: %s: %s\n", what, strerror(errno));
        return -1;
    }
    posix_spawn_file_actions_init(&fa);
    if (out) {
        posix_spawn_file_actions_adddup2(&fa, fd[1], STDOUT_FILENO);
        posix_spawn_file_actions_addclose(&fa, fd[0]);
        posix_spawn_file_actions_addclose(&fa, fd[1]);
    }
    extern char **environ;
    int e = posix_spawnp(&pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (out) close(fd[1]);
    if (e != 0) {
        if (out) close(fd[0]);
        fprintf(stderr,
                "cellar: %s needs GDAL's %s (%s); on Debian: apt-get install gdal-bin, or give "
                "GeoJSON files\n",
                what, argv[0], strerror(e));
        return -1;
    }
    int bad = 0;
    if (out) {
        size_t cap = 1 << 16, n = 0;
        char *buf = malloc(cap);
        for (ssize_t got = 1; buf && got > 0;) {
            if (n + 1 == cap) {
                char *p = cap < GIS_MAX_BYTES ? realloc(buf, 2 * cap) : NULL;
                if (!p) {
                    free(buf);
                    buf = NULL;
                    break;
                }
                buf = p, cap *= 2;
            }
            got = read(fd[0], buf + n, cap - 1 - n);
            if (got > 0) n += (size_t)got;
            if (got < 0 && errno == EINTR) got = 1;
        }
        close(fd[0]);
        if (!buf) {
            fprintf(stderr, "cellar: %s: out of memory (or more than %lu bytes)\n", what,
                    GIS_MAX_BYTES);
            bad = 1;
        } else {
            buf[n] = 0;
            *out = buf, *len = n;
        }
    }
    int st;
    while (waitpid(pid, &st, 0) < 0 && errno == EINTR) continue;
    if (!WIFEXITED(st) || WEXITSTATUS(st) != 0) {
        fprintf(stderr, "cellar: %s: %s failed (%s %d)\n", what, argv[0],
                WIFEXITED(st) ? "exit status" : "signal",
                WIFEXITED(st) ? WEXITSTATUS(st) : WTERMSIG(st));
        bad = 1;
    }
    if (bad && out && *out) free(*out), *out = NULL;
    return bad ? -1 : 0;
}

/* A layer's name: the file's base name without its extension; "layer" when nothing is left. */
static void layer_name(const char *path, char *out, size_t cap)
{
    const char *b = strrchr(path, '/');
    b = b ? b + 1 : path;
    const char *dot = strrchr(b, '.');
    size_t n = dot && dot != b ? (size_t)(dot - b) : strlen(b);
    if (n == 0) b = "layer", n = 5;
    if (n > 90) n = 90;
    snprintf(out, cap, "%.*s", (int)n, b);
}

static int is_geojson_path(const char *path)
{
    const char *dot = strrchr(path, '.');
    return !strcmp(path, "-") ||
           (dot && (!strcasecmp(dot, ".geojson") || !strcasecmp(dot, ".json")));
}

/* The layers of the files pos[1 .. npos) into the object layers (a FeatureCollection each,
 * named by layer_name(), a second "a" as "a_2"), their common reference system into *crs (a
 * reference, NULL: GeoJSON's own); 0, or 1 with the message printed. */
static int polygons_layers(char **pos, int npos, json_t *layers, json_t **crs)
{
    json_error_t je;
    for (int i = 1; i < npos; i++) {
        const char *path = pos[i];
        char name[128], uniq[140];
        size_t len;
        char *text = NULL;
        if (is_geojson_path(path)) {
            text = read_all(path, &len);
        } else {
            char *argv[] = {"ogr2ogr", "-q", "-f", "GeoJSON", "/vsistdout/", (char *)path, NULL};
            char what[300];
            snprintf(what, sizeof what, "reading %.250s", path);
            text = run_program(argv, what, &text, &len) == 0 ? text : NULL;
        }
        if (!text) return 1;
        json_t *fc = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
        free(text);
        if (!fc) {
            fprintf(stderr, "cellar: %s: line %d, column %d: %s\n", path, je.line, je.column,
                    je.text);
            return 1;
        }
        /* the reference system: the same for every layer, carried to the result (none is
         * GeoJSON's own, CRS84, as ogr2ogr names it) */
        json_t *c = json_object_get(fc, "crs");
        const char *cn =
            json_string_value(json_object_get(json_object_get(c, "properties"), "name"));
        if (cn && (!strcmp(cn, "urn:ogc:def:crs:OGC:1.3:CRS84") ||
                   !strcmp(cn, "urn:ogc:def:crs:EPSG::4326") || !strcmp(cn, "EPSG:4326")))
            c = NULL;
        if (i == 1) {
            *crs = c ? json_incref(c) : NULL;
        } else if (!json_equal(*crs ? *crs : json_null(), c ? c : json_null())) {
            fprintf(stderr,
                    "cellar: %s: its coordinate reference system differs from %s's; reproject "
                    "one (ogr2ogr -t_srs) so that the coordinates agree\n",
                    path, pos[1]);
            json_decref(fc);
            return 1;
        }
        json_object_del(fc, "crs");
        json_object_del(fc, "name");
        layer_name(path, name, sizeof name);
        snprintf(uniq, sizeof uniq, "%s", name);
        for (int k = 2; json_object_get(layers, uniq); k++)
            snprintf(uniq, sizeof uniq, "%s_%d", name, k);
        json_object_set_new(layers, uniq, fc);
    }
    return 0;
}

/* The GeoJSON of the result out[0..outlen) with the layers' reference system crs (may be
 * NULL), ogr2ogr reading its "crs" member: on stdout, or with --format gpkg through a temporary
 * file (*tmp, the caller's to unlink and free) into the GeoPackage output.  The exit status. */
static int polygons_own(const char *out, size_t outlen, const out_format *of, const json_t *crs,
                        const char *output, char **tmp)
{
    const render_format *geo = render_format_named("geojson");
    char *map = NULL, *crs_text = NULL;
    size_t maplen = 0;
    api_error err;
    FILE *f = stdout;
    if (geo->render(out, outlen, &of->ro, &map, &maplen, &err) != API_OK) {
        fprintf(stderr, "cellar: --format %s: %s\n", of->kind == OUT_GPKG ? "gpkg" : "geojson",
                err.msg);
        return 1;
    }
    crs_text = crs ? json_dumps(crs, JSON_COMPACT) : NULL;
    if (of->kind == OUT_GPKG) {
        const char *dir = getenv("TMPDIR");
        *tmp = malloc(strlen(dir ? dir : "/tmp") + 32);
        if (*tmp) sprintf(*tmp, "%s/cellar-XXXXXX.geojson", dir ? dir : "/tmp");
        int fd = *tmp ? mkstemps(*tmp, 8) : -1;
        f = fd >= 0 ? fdopen(fd, "w") : NULL;
        if (!f) {
            fprintf(stderr, "cellar: a temporary file: %s\n", strerror(errno));
            if (fd >= 0) close(fd);
            free(map);
            free(crs_text);
            return 1;
        }
    }
    if (crs_text && maplen > 1) { /* {"type":"FeatureCollection","crs":...,"features":... */
        fputc('{', f);
        fprintf(f, "\"crs\":%s,", crs_text);
        fwrite(map + 1, 1, maplen - 1, f);
    } else {
        fwrite(map, 1, maplen, f);
    }
    free(map);
    free(crs_text);
    if (of->kind != OUT_GPKG) return write_streamed();
    if (fclose(f) != 0) {
        fprintf(stderr, "cellar: %s: %s\n", *tmp, strerror(errno));
        return 1;
    }
    char nln[140];
    layer_name(output, nln, sizeof nln);
    char *argv[] = {"ogr2ogr", "-q",   "-overwrite", "-f",   "GPKG",         (char *)output,
                    *tmp,      "-nln", nln,          "-nlt", "MULTIPOLYGON", NULL};
    char what[300];
    snprintf(what, sizeof what, "writing %.250s", output);
    return run_program(argv, what, NULL, NULL) == 0 ? 0 : 1;
}

static int polygons_command(char **pos, int npos, const char *options_text, const svg_flags *fl,
                            int threads, const out_format *of, const char *output)
{
    json_t *req = NULL, *layers = NULL, *opts = NULL, *op = NULL, *crs = NULL;
    char *body = NULL, *out = NULL, *tmp = NULL;
    size_t outlen = 0;
    api_error err;
    int rc = 1;
    if (npos < 2)
        return usage_error("%s", "polygons takes one or more GIS files (GeoJSON, Shapefile, "
                                 "GeoPackage, ... : a layer each)");
    if (!fl->op)
        return usage_error("%s", "polygons: --op is required: union, intersection, difference, "
                                 "xor (over the layers) or an expression over their names such "
                                 "as '[\"&\", \"parcels\", \"zones\"]'");
    if (of->kind == OUT_GPKG && !output)
        return usage_error("%s", "--format gpkg needs --output FILE.gpkg");
    opts = options_object(options_text, 0);
    if (!opts) return EXIT_USAGE;
    if (fl->precision > 0) json_object_set_new(opts, "precision", json_real(fl->precision));
    op = fl->op[0] == '[' ? json_loads(fl->op, JSON_DECODE_ANY, NULL) : json_string(fl->op);
    layers = json_object();
    req = json_object();
    if (!op || !layers || !req) {
        fprintf(stderr, "cellar: --op: expected union, intersection, difference, xor or a JSON "
                        "expression over the layers' names\n");
        rc = EXIT_USAGE;
        goto out;
    }
    if (polygons_layers(pos, npos, layers, &crs)) goto out;
    json_object_set_new(req, "kind", json_string("polygons"));
    json_object_set(req, "layers", layers);
    json_object_set(req, "op", op);
    if (json_object_size(opts)) json_object_set(req, "options", opts);
    if (dump_request(req, &body)) goto out;
    if (of->kind == OUT_REQUEST) {
        rc = write_request(body, strlen(body));
        goto out;
    }
    /* GeoJSON (and the GeoPackage made of it) carries the layers' reference system: written
     * here, every other format as the other commands write it */
    int kgeo = (int)(render_format_named("geojson") - render_formats);
    if (of->kind != OUT_GPKG && !(of->kind == kgeo && crs)) {
        rc = run_request(body, strlen(body), threads, of, &err);
    } else {
        api_run_opts ro = run_opts(threads, &(out_format){.kind = kgeo});
        rc = api_run_json_ex(body, strlen(body), &ro, &out, &outlen, &err) == API_OK ? 0 : -1;
        progress_end();
        if (rc == 0) rc = polygons_own(out, outlen, of, crs, output, &tmp);
    }
    if (rc < 0) {
        fprintf(stderr, "cellar: %s\n", err.msg);
        rc = 1;
    }
out:
    if (tmp) unlink(tmp);
    free(tmp);
    free(out);
    free(body);
    json_decref(req);
    json_decref(layers);
    json_decref(opts);
    json_decref(op);
    json_decref(crs);
    return rc;
}

/* The command line as parsed: the positional words (the command first) and the options. */
typedef struct cli_args {
    char **pos;
    int npos;
    const char *options_text; /* --options */
    svg_flags fl;
    out_format of;
    const char *output; /* --output */
    int threads;
    int progress_flag; /* 'q' --quiet, 'p' --progress, 0 neither */
} cli_args;

/* --precision X, --flatten-tolerance X (or =X) at argv[*i]: the svg flags' numbers. */
static int number_option(cli_args *a, int argc, char **argv, int *i)
{
    const char *arg = argv[*i], *eq = strchr(arg, '=');
    int tol = arg[2] == 'f';
    char flag[24];
    snprintf(flag, sizeof flag, "%.*s", eq ? (int)(eq - arg) : (int)strlen(arg), arg);
    if (!eq && *i + 1 == argc) return usage_error("%s needs a value", arg);
    if (parse_positive(flag, eq ? eq + 1 : argv[++*i], tol ? &a->fl.tolerance : &a->fl.precision))
        return EXIT_USAGE;
    if (tol && !a->fl.first) a->fl.first = "--flatten-tolerance";
    return -1;
}

/* --format, --explode, --width, --cells with its value val: the output's kind and options. */
static int render_option(cli_args *a, const char *arg, const char *val)
{
    out_format *of = &a->of;
    if (arg[2] == 'f') {
        const render_format *f = render_format_named(val);
        of->kind = f                         ? (int)(f - render_formats)
                   : !strcmp(val, "request") ? OUT_REQUEST
                   : !strcmp(val, "gpkg")    ? OUT_GPKG
                                             : -1;
        if (of->kind == -1)
            return usage_error("--format: expected json, svg, geojson, obj, npz, stl, off, 3mf, "
                               "glb or request, not \"%s\"",
                               val);
        return -1;
    }
    api_error re;
    if (render_opts_parse_query(arg + 2, val, &of->ro, &re) != API_OK)
        return usage_error("--%s", re.msg);
    if (arg[2] == 'e')
        of->explode = arg;
    else if (arg[2] == 'c')
        of->cells = arg;
    else if (!of->first)
        of->first = arg;
    return -1;
}

/* An option that takes a value (--format, --explode, --width, --cells, --output, -o,
 * --threads, --options; the last two also as --name=value) at argv[*i]; 0 when arg is none of
 * them. */
static int value_option(cli_args *a, int argc, char **argv, int *i)
{
    const char *arg = argv[*i], *val;
    int known = !strcmp(arg, "--format") || !strcmp(arg, "--explode") || !strcmp(arg, "--width") ||
                !strcmp(arg, "--cells") || !strcmp(arg, "--output") || !strcmp(arg, "-o") ||
                !strcmp(arg, "--threads") || !strcmp(arg, "--options");
    if (known && *i + 1 == argc) return usage_error("%s needs a value", arg);
    if (known) {
        val = argv[++*i];
    } else if (!strncmp(arg, "--threads=", 10) || !strncmp(arg, "--options=", 10)) {
        val = arg + 10;
    } else {
        return 0;
    }
    if (!strcmp(arg, "--output") || !strcmp(arg, "-o")) {
        a->output = val;
    } else if (!strncmp(arg, "--threads", 9)) {
        uint64_t t;
        if (parse_u64(val, &t) || t > 4096)
            return usage_error("--threads: expected an integer in 0..4096, not \"%s\"", val);
        a->threads = (int)t;
    } else if (!strncmp(arg, "--options", 9)) {
        a->options_text = val;
    } else {
        return render_option(a, arg, val);
    }
    return -1;
}

/* The option argv[*i] (a word starting "--", or -h, -o) into *a: -1 to go on, or the exit
 * status (0 after --help or --version, EXIT_USAGE with the message printed). */
static int parse_option(cli_args *a, int argc, char **argv, int *i)
{
    const char *arg = argv[*i];
    if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
        fputs(usage_text, stdout);
        return 0;
    }
    if (!strcmp(arg, "--version")) {
        printf("cellar %s (jansson %s)\n", API_VERSION, JANSSON_VERSION);
        return 0;
    }
    if (!strcmp(arg, "--normalize") || !strcmp(arg, "--y-up") || !strcmp(arg, "--rect-diagonal") ||
        !strcmp(arg, "--keep-dangling")) {
        *(arg[2] == 'n'   ? &a->fl.normalize
          : arg[2] == 'y' ? &a->fl.y_up
          : arg[2] == 'r' ? &a->fl.rect_diagonal
                          : &a->fl.keep_dangling) = 1;
        if (!a->fl.first) a->fl.first = arg;
        return -1;
    }
    if (!strcmp(arg, "--precision") || !strcmp(arg, "--flatten-tolerance") ||
        !strncmp(arg, "--precision=", 12) || !strncmp(arg, "--flatten-tolerance=", 20))
        return number_option(a, argc, argv, i);
    if (!strcmp(arg, "--faces") || !strcmp(arg, "--groups")) {
        *(arg[2] == 'f' ? &a->fl.faces : &a->fl.groups) = 1;
        return -1;
    }
    if (!strcmp(arg, "--quiet") || !strcmp(arg, "--progress")) {
        a->progress_flag = arg[2];
        return -1;
    }
    if (!strcmp(arg, "--op") || !strncmp(arg, "--op=", 5)) {
        if (!arg[4] && *i + 1 == argc) return usage_error("%s", "--op needs a value");
        a->fl.op = arg[4] ? arg + 5 : argv[++*i];
        return -1;
    }
    if (!strcmp(arg, "--numbers")) {
        a->of.ro.numbers = 1;
        if (!a->of.first) a->of.first = arg;
        return -1;
    }
    int rc = value_option(a, argc, argv, i);
    return rc == 0 ? usage_error("unknown option %s", arg) : rc;
}

/* A flag given to a command (or format) it is not for: the usage error's exit status, or -1
 * when every flag fits the command cmd. */
static int misplaced_flag(const cli_args *a, const char *cmd)
{
    const out_format *of = &a->of;
    int svg = !strcmp(cmd, "svg"), solids = !strcmp(cmd, "solids");
    int polygons = !strcmp(cmd, "polygons");
    if (a->fl.first && !svg) return usage_error("%s is for the svg command", a->fl.first);
    if (a->fl.precision > 0 && !svg && !solids && !polygons)
        return usage_error("%s is for the svg, solids and polygons commands", "--precision");
    if (of->kind == OUT_GPKG && !polygons)
        return usage_error("%s", "--format gpkg is for the polygons command");
    if (a->output && !polygons)
        return usage_error("%s", "--output is for the polygons command (others write to standard "
                                 "output)");
    if (a->fl.faces && !solids) return usage_error("%s is for the solids command", "--faces");
    if (a->fl.groups && !solids) return usage_error("%s is for the solids command", "--groups");
    if (of->first && of->kind != 1) return usage_error("%s is for --format svg", of->first);
    if (of->cells && of->kind != 2) return usage_error("%s is for --format geojson", of->cells);
    if (of->explode && of->kind != 1 && of->kind != 3 &&
        !(of->kind >= 0 && !strcmp(render_formats[of->kind].name, "glb")))
        return usage_error("%s is for --format svg, obj or glb", of->explode);
    if (of->kind == OUT_REQUEST && !svg && !solids && !polygons)
        return usage_error("%s", "--format request is for the svg, solids and polygons commands");
    return -1;
}

/* Runs the command a->pos[0]; its exit status. */
static int dispatch(const cli_args *a)
{
    char **pos = a->pos;
    int npos = a->npos;
    if (npos == 0) return usage_error("%s", "no command (run, gen, svg, solids, polygons)");
    if (!strcmp(pos[0], "svg"))
        return svg_command(pos, npos, a->options_text, &a->fl, a->threads, &a->of);
    if (!strcmp(pos[0], "solids"))
        return solids_command(pos, npos, a->options_text, &a->fl, a->threads, &a->of);
    if (!strcmp(pos[0], "polygons"))
        return polygons_command(pos, npos, a->options_text, &a->fl, a->threads, &a->of, a->output);
    if (!strcmp(pos[0], "run"))
        return a->options_text ? usage_error("%s", "--options is for gen; put options in the "
                                                   "request")
                               : run(pos, npos, a->threads, &a->of);
    if (!strcmp(pos[0], "gen")) {
        if (npos < 2) return usage_error("%s", "gen needs lines or grid");
        if (!strcmp(pos[1], "lines")) return gen_lines(pos, npos, a->options_text);
        if (!strcmp(pos[1], "grid")) return gen_grid(pos, npos, a->options_text);
        return usage_error("gen: unknown generator \"%s\" (lines, grid)", pos[1]);
    }
    return usage_error("unknown command \"%s\" (run, gen, svg, solids, polygons)", pos[0]);
}

int main(int argc, char **argv)
{
    static char outbuf[1 << 16];
    cli_args a = {.pos = calloc((size_t)argc + 1, sizeof *a.pos),
                  .of = {.kind = 0, .ro = RENDER_OPTS_INIT}};
    int rc = -1;
    if (!a.pos) return 1;
    /* One run a process: the arrays a stage frees stay in the heap for the next stage to reuse
     * (glibc would give blocks of 128 KiB and more back to the kernel, and the next stage would
     * fault and zero its pages again: 5-10 % of a 3D run).  Freed memory is reused, so the peak
     * stays what the run needs; the process ends with the run. */
    (void)mallopt(M_MMAP_THRESHOLD, 32 << 20);
    (void)mallopt(M_TRIM_THRESHOLD, 1 << 30);
    setvbuf(stdout, outbuf, _IOFBF, sizeof outbuf);
    for (int i = 1; i < argc && rc < 0; i++) {
        if (strncmp(argv[i], "--", 2) != 0 && strcmp(argv[i], "-h") != 0 &&
            strcmp(argv[i], "-o") != 0)
            a.pos[a.npos++] = argv[i];
        else
            rc = parse_option(&a, argc, argv, &i);
    }
    if (rc < 0) {
        bar.mode = a.progress_flag == 'q'   ? PROGRESS_OFF
                   : isatty(STDERR_FILENO)  ? PROGRESS_BAR
                   : a.progress_flag == 'p' ? PROGRESS_LINES
                                            : PROGRESS_OFF;
        rc = misplaced_flag(&a, a.npos ? a.pos[0] : "");
        if (rc < 0) rc = dispatch(&a);
    }
    free(a.pos);
    if (fflush(stdout) != 0) rc = rc ? rc : 1;
    return rc;
}
