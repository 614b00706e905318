/* lib.c — the library's entry points (include/cellar.h): arrays in, arrays out.
 *
 * A call makes the kind's own request struct from the caller's arrays (api_*_make: the same
 * checks, limits and messages as a JSON request; the options and the op, a few values, go
 * through small jansson values so that the kinds read them as they read a request's), runs it
 * with the kind's *_arrays function (the same core calls as *_run) and hands out the result as
 * named arrays: the core's own arrays where they have the result's layout (V, EV, FE, ...),
 * gathered copies where they do not (FV, holes, operators).
 *
 * Cancel and progress: the caller's cancel is asked at every progress report told to the
 * caller (lib_progress: each new stage, and every thousandth of the run) and, once it says stop,
 * sets the flag the core polls; both callbacks are called under a mutex, one at a time, from
 * whichever thread reports.
 *
 * Threads: reentrant; a result is the caller's and is never shared.  Ownership: see cellar.h.
 */
#include "api/api_int.h"
#include "include/cellar.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "core/solid.h"

_Static_assert((int)CELLAR_F64 == API_A_F64 && (int)CELLAR_I32 == API_A_I32 &&
                   (int)CELLAR_U32 == API_A_U32 && (int)CELLAR_I8 == API_A_I8 &&
                   (int)CELLAR_U64 == API_A_U64,
               "the dtypes of api_int.h are cellar.h's");
_Static_assert(sizeof(cellar_error) == sizeof(api_error) && CELLAR_ERRMAX == API_ERRMAX,
               "cellar_error is api_error");

typedef struct kept {
    void *p;
    void (*fr)(void *);
} kept;

struct cellar_result {
    int dim;
    cellar_array *a; /* n, names owned */
    size_t n, cap;
    kept *keep; /* nkeep: blocks freed with the result (owned arrays too) */
    size_t nkeep, kcap;
    char *json; /* owned */
};

int api_arrays_keep(api_arrays *r, void *p, void (*fr)(void *))
{
    if (r->nkeep == r->kcap) {
        size_t cap = r->kcap ? 2 * r->kcap : 32;
        kept *k = realloc(r->keep, cap * sizeof *k);
        if (!k) {
            fr(p);
            return -1;
        }
        r->keep = k;
        r->kcap = cap;
    }
    r->keep[r->nkeep++] = (kept){p, fr};
    return 0;
}

int api_arrays_add(api_arrays *r, const char *name, int dt, size_t rows, size_t cols,
                   const void *data, int own)
{
    if (own && api_arrays_keep(r, (void *)data, free)) return -1;
    char *nm = strdup(name);
    if (!nm || api_arrays_keep(r, nm, free)) return -1;
    if (r->n == r->cap) {
        size_t cap = r->cap ? 2 * r->cap : 32;
        cellar_array *a = realloc(r->a, cap * sizeof *a);
        if (!a) return -1;
        r->a = a;
        r->cap = cap;
    }
    r->a[r->n++] = (cellar_array){nm, (cellar_dtype)dt, rows, cols, data};
    return 0;
}

void api_arrays_put(api_arrays *r, int *bad, const char *name, int dt, size_t rows, size_t cols,
                    const void *data, int own)
{
    if (*bad) {
        if (own) free((void *)data);
        return;
    }
    if (api_arrays_add(r, name, dt, rows, cols, data, own)) *bad = 1;
}

void api_arrays_json(api_arrays *r, int dim, char *json)
{
    free(r->json);
    r->json = json;
    r->dim = dim;
}

int api_arrays_cycles(api_arrays *r, const char *name, const uint32_t *cyc_off, const uint32_t *cyc,
                      const uint32_t *which, const uint8_t *reversed, size_t n, const uint32_t *map)
{
    size_t total = 0;
    for (size_t i = 0; i < n; i++) total += cyc_off[which[i] + 1] - cyc_off[which[i]];
    uint32_t *ptr = malloc((n + 1) * sizeof *ptr), *idx = malloc((total + 1) * sizeof *idx);
    char nm[96];
    if (!ptr || !idx) {
        free(ptr);
        free(idx);
        return -1;
    }
    size_t w = 0;
    for (size_t i = 0; i < n; i++) {
        uint32_t c0 = cyc_off[which[i]], k = cyc_off[which[i] + 1] - c0;
        ptr[i] = (uint32_t)w;
        for (uint32_t j = 0; j < k; j++) {
            uint32_t v = cyc[reversed && reversed[i] ? c0 + (k - j) % k : c0 + j];
            idx[w++] = map ? map[v] : v;
        }
    }
    ptr[n] = (uint32_t)w;
    snprintf(nm, sizeof nm, "%s.indptr", name);
    if (api_arrays_add(r, nm, API_A_U32, n + 1, 1, ptr, 1)) {
        free(idx);
        return -1;
    }
    snprintf(nm, sizeof nm, "%s.indices", name);
    return api_arrays_add(r, nm, API_A_U32, w, 1, idx, 1);
}

int api_arrays_own_vertices(api_arrays *out, const char *name, const double *V, size_t nv, int dim,
                            uint32_t *map)
{
    size_t n = 0;
    for (size_t v = 0; v < nv; v++) n += map[v] != 0;
    double *W = malloc((n * (size_t)dim + 1) * sizeof *W);
    if (!W) return -1;
    n = 0;
    for (size_t v = 0; v < nv; v++) {
        if (!map[v]) continue;
        memcpy(W + n * (size_t)dim, V + (size_t)dim * v, (size_t)dim * sizeof *W);
        map[v] = (uint32_t)n++;
    }
    return api_arrays_add(out, name, API_A_F64, n, (size_t)dim, W, 1);
}

void api_arrays_holes(api_arrays *r, int *bad, const char *name, size_t n, const uint32_t *off,
                      const uint32_t *ids, const uint32_t *cyc_off, const uint32_t *cyc,
                      const uint32_t *map)
{
    size_t nh = n ? off[n] : 0;
    char nm[96];
    uint32_t *face = *bad ? NULL : malloc((nh + 1) * sizeof *face);
    for (size_t q = 0; face && q < n; q++)
        for (uint32_t h = off[q]; h < off[q + 1]; h++) face[h] = (uint32_t)q;
    *bad = *bad || !face;
    snprintf(nm, sizeof nm, "%s.face", name);
    api_arrays_put(r, bad, nm, API_A_U32, nh, 1, face, 1);
    *bad = *bad || api_arrays_cycles(r, name, cyc_off, cyc, ids, NULL, nh, map);
}

void api_arrays_f64(api_arrays *r, int *bad, const char *name, double x)
{
    double *p = *bad ? NULL : malloc(sizeof *p);
    if (p) *p = x;
    *bad = *bad || !p;
    api_arrays_put(r, bad, name, API_A_F64, 1, 1, p, 1);
}

int api_arrays_membership(api_arrays *out, size_t nrows, size_t ninputs, const uint32_t *off,
                          const uint32_t *idx, const int32_t *wind)
{
    int plain = api_membership_plain(nrows, off, wind);
    uint64_t *shape = malloc(2 * sizeof *shape);
    if (!shape) return -1;
    shape[0] = nrows;
    shape[1] = ninputs;
    if (api_arrays_add(out, "membership.shape", API_A_U64, 2, 1, shape, 1) ||
        api_arrays_add(out, "membership.indptr", API_A_U32, nrows + 1, 1, off, 0) ||
        api_arrays_add(out, "membership.indices", API_A_U32, off[nrows], 1, idx, 0))
        return -1;
    if (!plain && api_arrays_add(out, "membership.data", API_A_I32, off[nrows], 1, wind, 0))
        return -1;
    return 0;
}

/* ---- the public functions -------------------------------------------------------------------- */

size_t cellar_result_count(const cellar_result *r)
{
    return r ? r->n : 0;
}

const cellar_array *cellar_result_array(const cellar_result *r, size_t i)
{
    return r && i < r->n ? &r->a[i] : NULL;
}

const cellar_array *cellar_result_get(const cellar_result *r, const char *name)
{
    for (size_t i = 0; r && name && i < r->n; i++)
        if (strcmp(r->a[i].name, name) == 0) return &r->a[i];
    return NULL;
}

int cellar_result_dim(const cellar_result *r)
{
    return r ? r->dim : 0;
}

const char *cellar_result_json(const cellar_result *r)
{
    return r && r->json ? r->json : "{}";
}

void cellar_result_free(cellar_result *r)
{
    if (!r) return;
    for (size_t i = r->nkeep; i-- > 0;) r->keep[i].fr(r->keep[i].p);
    free(r->keep);
    free(r->a);
    free(r->json);
    free(r);
}

void cellar_free(void *p)
{
    free(p);
}

const char *cellar_version(void)
{
    return API_VERSION;
}

const char *cellar_stage_name(const char *kind, size_t i)
{
    return kind ? api_stage_name(kind, i) : NULL;
}

/* A run's callbacks: the caller's, one at a time, and the flag the core reads.  The core may
 * report tens of thousands of times on a large input; the caller hears a new stage at once and
 * otherwise every thousandth of the run (and its end), so about a thousand times at most. */
typedef struct lib_run {
    const cellar_options *o;
    atomic_int stop;
    pthread_mutex_t mu;
    char stage[32]; /* the last told */
    double told;    /* the fraction last told */
} lib_run;

static void lib_progress(void *udata, const char *stage, double fraction)
{
    lib_run *L = udata;
    pthread_mutex_lock(&L->mu);
    int tell = fraction >= 1 || fraction >= L->told + 1e-3 || strncmp(stage, L->stage, 31) != 0;
    if (tell) {
        snprintf(L->stage, sizeof L->stage, "%s", stage);
        L->told = fraction;
        if (L->o->cancel && !atomic_load(&L->stop) && L->o->cancel(L->o->udata))
            atomic_store(&L->stop, 1);
        if (L->o->progress) L->o->progress(L->o->udata, stage, fraction);
    }
    pthread_mutex_unlock(&L->mu);
}

static void run_opts(lib_run *L, const cellar_options *o, api_run_opts *ro)
{
    *ro = (api_run_opts){.threads = o ? o->threads : 0};
    L->o = o;
    L->stage[0] = 0;
    L->told = -1;
    atomic_init(&L->stop, 0);
    pthread_mutex_init(&L->mu, NULL);
    if (o && (o->cancel || o->progress)) {
        ro->cancel = &L->stop;
        ro->progress = lib_progress;
        ro->udata = L;
    }
}

int cellar_run_json(const char *body, size_t len, const cellar_options *o, char **out,
                    size_t *outlen, cellar_error *err)
{
    lib_run L;
    api_run_opts ro;
    size_t dummy;
    if (!outlen) outlen = &dummy;
    if (!out) return api_fail((api_error *)err, API_EINVALID, "out: required");
    if (!body) {
        *out = NULL;
        *outlen = 0;
        return api_fail((api_error *)err, API_EJSON, "the body is empty");
    }
    run_opts(&L, o, &ro);
    int rc = api_run_json_ex(body, len, &ro, out, outlen, (api_error *)err);
    pthread_mutex_destroy(&L.mu);
    return rc;
}

/* options as the JSON request's "options" (NULL: none given); fill only for kinds that have it. */
static int options_json(const cellar_options *o, int fill_ok, json_t **out, api_error *err)
{
    *out = NULL;
    if (!o) return API_OK;
    json_t *j = json_object();
    if (!j) return api_fail(err, API_ENOMEM, "out of memory");
    int bad = 0;
    if (o->precision != 0) bad |= json_object_set_new(j, "precision", json_real(o->precision));
    if (o->keep_dangling) bad |= json_object_set_new(j, "keep_dangling", json_true());
    if (o->operators) bad |= json_object_set_new(j, "operators", json_true());
    if (o->fill) {
        if (!fill_ok) {
            json_decref(j);
            return api_fail(err, API_EINVALID,
                            "options.fill: a fill rule is an option of polygons and solids");
        }
        bad |= json_object_set_new(j, "fill", json_string(o->fill));
    }
    if (o->fields) {
        json_t *f = json_array();
        bad |= !f || json_object_set_new(j, "fields", f);
        const char *p = o->fields;
        while (f && !bad && *p) {
            size_t k = strcspn(p, ",");
            const char *s = p;
            size_t n = k;
            while (n && *s == ' ') s++, n--;
            while (n && s[n - 1] == ' ') n--;
            bad |= json_array_append_new(f, json_stringn(s, n));
            p += k + (p[k] == ',');
        }
    }
    if (bad) {
        json_decref(j);
        return api_fail(err, API_EINVALID,
                        "options: a value that is not one (a precision that is not finite, a "
                        "fields or fill name that is not UTF-8)");
    }
    *out = j;
    return API_OK;
}

/* op as the request's "op": a name ("union") or an expression as JSON text ("[\"-\",0,1]"). */
static int op_json(const char *op, json_t **out, api_error *err)
{
    *out = NULL;
    if (!op) return API_OK;
    json_error_t je;
    const char *s = op;
    while (*s == ' ') s++;
    if (*s == '[' || *s == '"' || (*s >= '0' && *s <= '9') || *s == '-') {
        *out = json_loads(op, JSON_DECODE_ANY, &je);
        if (!*out)
            return api_fail(err, API_EINVALID, "op: not an expression in JSON (%s, column %d)",
                            je.text, je.column);
        return API_OK;
    }
    *out = json_string(op);
    if (!*out) return api_fail(err, API_EINVALID, "op: expected a name in UTF-8");
    return API_OK;
}

typedef int (*arrays_fn)(const void *parsed, const api_run_opts *ro, api_arrays *out,
                         api_error *err);

/* Runs parsed (freed here with fr) into a new result. */
static int run_arrays(void *parsed, void (*fr)(void *), arrays_fn fn, const api_stage *stages,
                      const cellar_options *o, cellar_result **out, api_error *err)
{
    lib_run L;
    api_run_opts ro, wr;
    api_progress pr;
    cellar_result *r = calloc(1, sizeof *r);
    int rc;
    if (!r) {
        fr(parsed);
        return api_fail(err, API_ENOMEM, "out of memory");
    }
    run_opts(&L, o, &ro);
    api_progress_wrap(&pr, stages, &ro, &wr);
    rc = fn(parsed, &wr, r, err);
    if (rc == API_OK && atomic_load(&L.stop)) rc = api_fail(err, API_ECANCELED, "canceled");
    if (rc == API_OK && wr.progress) wr.progress(wr.udata, "output", 1);
    pthread_mutex_destroy(&L.mu);
    fr(parsed);
    if (rc != API_OK) {
        cellar_result_free(r);
        return rc;
    }
    *out = r;
    return API_OK;
}

static void clear(cellar_result **out, cellar_error *err)
{
    if (out) *out = NULL;
    if (err) err->status = CELLAR_OK, err->msg[0] = 0;
}

int cellar_arrangement2d(const double *seg, size_t n, const cellar_options *o, cellar_result **out,
                         cellar_error *err)
{
    api_error *e = (api_error *)err;
    json_t *opt;
    void *parsed;
    clear(out, err);
    if (!out) return api_fail(e, API_EINVALID, "out: required");
    if (!seg && n) return api_fail(e, API_EINVALID, "segments: NULL with %zu segments", n);
    int rc = options_json(o, 0, &opt, e);
    if (rc != API_OK) return rc;
    rc = api_lines_make(seg, n, opt, &parsed, e);
    json_decref(opt);
    if (rc != API_OK) return rc;
    return run_arrays(parsed, api_lines_free, api_lines_arrays, api_stages_lines, o, out, e);
}

int cellar_polygons(size_t npoly, const uint32_t *poly_off, const uint32_t *ring_off,
                    const double *xy, const char *op, const cellar_options *o, cellar_result **out,
                    cellar_error *err)
{
    api_error *e = (api_error *)err;
    json_t *opt = NULL, *jop = NULL;
    void *parsed;
    clear(out, err);
    if (!out) return api_fail(e, API_EINVALID, "out: required");
    if (!poly_off || (poly_off[npoly] && (!ring_off || !xy)))
        return api_fail(e, API_EINVALID, "polygons: poly_off, ring_off and xy are required");
    if (!op)
        return api_fail(e, API_EINVALID,
                        "op: required, \"union\", \"intersection\", \"difference\", \"xor\" or an "
                        "expression such as [\"-\", 0, [\"+\", 1, 2]]");
    int rc = options_json(o, 1, &opt, e);
    if (rc == API_OK) rc = op_json(op, &jop, e);
    if (rc == API_OK) rc = api_polygons_make(npoly, poly_off, ring_off, xy, jop, opt, &parsed, e);
    json_decref(opt);
    json_decref(jop);
    if (rc != API_OK) return rc;
    return run_arrays(parsed, api_polygons_free, api_polygons_arrays, api_stages_polygons, o, out,
                      e);
}

/* Solid i of the caller's as core/solid.h's (copied: the core's solid owns its arrays). */
static int copy_solid(const cellar_solid *c, size_t i, solid *s, api_error *err)
{
    memset(s, 0, sizeof *s);
    if ((!c->V && c->nv) || (!c->F && c->nf))
        return api_fail(err, API_EINVALID, "solids[%zu]: V or F is NULL", i);
    size_t nidx = c->face_off ? (c->nf ? c->face_off[c->nf] : 0) : 3 * c->nf;
    if (c->face_off)
        for (size_t f = 0; f < c->nf; f++)
            if (c->face_off[f + 1] < c->face_off[f])
                return api_fail(err, API_EINVALID,
                                "solids[%zu].face_off[%zu]: the offsets go back (%u after %u)", i,
                                f + 1, c->face_off[f + 1], c->face_off[f]);
    if (c->nv > SIZE_MAX / 24 || c->nf >= UINT32_MAX || nidx >= UINT32_MAX)
        return api_fail(err, API_EINVALID, "solids[%zu]: too large", i);
    s->nv = c->nv;
    s->nf = c->nf;
    s->ncyc = c->nf;
    s->V = malloc((3 * c->nv + 1) * sizeof *s->V);
    s->face_off = malloc((c->nf + 1) * sizeof *s->face_off);
    s->cyc_off = malloc((c->nf + 1) * sizeof *s->cyc_off);
    s->cyc = malloc((nidx + 1) * sizeof *s->cyc);
    if (!s->V || !s->face_off || !s->cyc_off || !s->cyc) {
        solid_free(s);
        return api_fail(err, API_ENOMEM, "out of memory for solids[%zu]", i);
    }
    if (c->nv) memcpy(s->V, c->V, 3 * c->nv * sizeof *s->V);
    if (nidx) memcpy(s->cyc, c->F + (c->face_off ? c->face_off[0] : 0), nidx * sizeof *s->cyc);
    for (size_t f = 0; f <= c->nf; f++) {
        s->face_off[f] = (uint32_t)f; /* one cycle a face: no holes */
        s->cyc_off[f] = (uint32_t)(c->face_off ? c->face_off[f] - c->face_off[0] : 3 * f);
    }
    return API_OK;
}

int cellar_solids(const cellar_solid *s, size_t n, const char *op, const cellar_options *o,
                  cellar_result **out, cellar_error *err)
{
    api_error *e = (api_error *)err;
    json_t *opt = NULL, *jop = NULL;
    void *parsed;
    clear(out, err);
    if (!out) return api_fail(e, API_EINVALID, "out: required");
    if (!s && n) return api_fail(e, API_EINVALID, "solids: NULL with %zu solids", n);
    solid *cp = calloc(n ? n : 1, sizeof *cp);
    if (!cp) return api_fail(e, API_ENOMEM, "out of memory for %zu solids", n);
    int rc = API_OK;
    for (size_t i = 0; i < n && rc == API_OK; i++) rc = copy_solid(&s[i], i, &cp[i], e);
    if (rc == API_OK) rc = options_json(o, 1, &opt, e);
    if (rc == API_OK) rc = op_json(op, &jop, e);
    if (rc != API_OK) {
        for (size_t i = 0; i < n; i++) solid_free(&cp[i]);
        free(cp);
        json_decref(opt);
        return rc;
    }
    rc = api_solids_make(cp, n, jop, opt, &parsed, e); /* takes cp over */
    json_decref(opt);
    json_decref(jop);
    if (rc != API_OK) return rc;
    return run_arrays(parsed, api_solids_free, api_solids_arrays, api_stages_solids, o, out, e);
}
