/* solids.c — the "solids" kind: the arrangement of 3D solids given as face models.
 *
 *   {"kind":"solids","solids":[{"V":[[x,y,z],...],"FV":[[v,...],...],"holes":{"f":[[v,...]]}},
 *                              ...],"options":{...}}
 *   {"kind":"solids","faces":{"V":...,"FV":...,"holes":...},"options":{...}}
 *
 * Exactly one of "solids" (closed surfaces, outward oriented: each face's outer cycle
 * counter-clockwise seen from outside, its hole cycles clockwise) and "faces" (one face soup:
 * no closedness, any orientation).  A face is a planar polygon: its outer cycle is a row of FV,
 * its holes (if any) are holes."f", f the face's index in decimal (the result format's rule).
 *
 * Three steps, as api_int.h's api_kind asks:
 *   parse   the shape of the request, with the JSON path of every problem (422): types, vertex
 *           indices in range, finite coordinates, cycles of at least 3 indices, the limits below;
 *           copies each solid into a `solid` (core/solid.h) so the JSON tree can be freed.
 *   check   (the daemon's submit, or at run when the request was not checked) the geometry:
 *           solid_check() of each solid, or solid_check_faces() of a soup (no closedness
 *           asked), at the grid step, keeping solid_check's fixed copies (orientation made
 *           consistent and outward), the edges' pairings and the warnings (told apart by info,
 *           never by their text) for the run.  The first error is the 422; its location
 *           (solid_report's info: a face or a vertex) becomes the JSON path,
 *           "solids[2].FV[5]: ...".
 *   run     arr3_build() the checked solids, write the complex (api/larjson3.c) with the
 *           warnings in stats.warnings.
 *
 * The grid step: arr3_solids_step() of the solids and options.precision, at parse; its refusal
 * (a precision finer than the input allows) is the 422 at options.precision.  The rule lives in
 * the core only; here it is called, never repeated.
 *
 * Limits (422 naming the key): the #defines below; at most api_solids_max_faces() faces in all
 * (ARR3_MAX_FACES unless set lower), and at run what memory allows (the core's estimate).
 *
 * Threads: reentrant, no globals.  Ownership: req is borrowed; a parsed request (*parsed)
 * belongs to the caller, who frees it with api_solids_free().
 */
#include "api/api_int.h"

#include <errno.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/arr3.h"
#include "core/par.h"
#include "core/solid.h"

#define SOLIDS_MAX_SOLIDS   100000u    /* entries of "solids" */
#define SOLIDS_MAX_VERTICES 64000000u  /* rows of V, all solids together */
#define SOLIDS_MAX_FACES    max_faces  /* rows of FV, all solids together (api_solids_max_faces) */
#define SOLIDS_MAX_CYCLE    1000000u   /* vertex indices in one cycle */
#define SOLIDS_MAX_INDICES  256000000u /* vertex indices in all cycles together */
#define SOLIDS_MAX_WARNINGS 64         /* stats.warnings: the last one counts those left out */
#define WARN_LEN            200

/* The faces a request may have in all: ARR3_MAX_FACES, or less when set (the process's
 * configuration: the daemon's --max-faces, the tests).  What memory allows is decided by the
 * core (arr3_opts.max_bytes), at run. */
static _Atomic unsigned max_faces = ARR3_MAX_FACES;

unsigned api_solids_max_faces(void)
{
    return max_faces;
}

void api_solids_set_max_faces(unsigned n)
{
    max_faces = n && n < ARR3_MAX_FACES ? n : ARR3_MAX_FACES;
}

typedef struct solids_req {
    solid *s; /* owned: ns solids; with soup, the face soup as s[0] (ns == 1) */
    size_t ns;
    int soup;         /* the request gave "faces" */
    double precision; /* options.precision; 0: the default */
    double step;      /* the grid step the core will use (arr3_solids_step) */
    unsigned fields;  /* API_F3_* */
    int has_op;       /* the request gave "op" */
    bool_expr op;     /* its program (api/boolop.c) */
    int fill;         /* options.fill: BOOL3_FILL_* */
    /* "layers": {"name": [solid, ...], ...}: layer k's solids are lfirst[k] .. lfirst[k+1]),
     * its name lname[k] (JSON text) and lkey[k] (as given); layers the result's "layers" */
    size_t nlayers;
    char **lname, **lkey;
    uint32_t *lfirst;
    char *layers;
    struct solids_checked *checked; /* owned: what api_solids_check made (NULL: not checked) */
} solids_req;

/* The name of solid i in messages: "solids[i]", "layers.NAME[j]" or "faces". */
static void solid_label(const solids_req *r, size_t i, char *out, size_t cap)
{
    if (r->soup) {
        snprintf(out, cap, "faces");
        return;
    }
    for (size_t k = 0; k < r->nlayers; k++)
        if (i < r->lfirst[k + 1]) {
            snprintf(out, cap, "layers.%.100s[%zu]", r->lkey[k], i - r->lfirst[k]);
            return;
        }
    snprintf(out, cap, "solids[%zu]", i);
}

typedef struct totals {
    size_t nv, nf, nidx; /* rows of V, rows of FV, vertex indices in cycles, so far */
} totals;

typedef struct warn_list {
    char msg[SOLIDS_MAX_WARNINGS][WARN_LEN];
    const char *ptr[SOLIDS_MAX_WARNINGS]; /* msg[i], for api_lar3_fmt */
    size_t n;                             /* kept */
    size_t total;                         /* seen */
} warn_list;

/* ---- options --------------------------------------------------------------------------------- */

static int parse_fields(const json_t *v, unsigned *out, api_error *err)
{
    size_t i;
    json_t *name;
    if (!json_is_array(v))
        return api_fail(
            err, API_EINVALID,
            "options.fields: expected an array of names among \"V\", \"EV\", \"FV\", "
            "\"FE\", \"holes\", \"CF\", \"CV\", \"exterior\", \"stats\", \"operators\", "
            "\"membership\", \"result\"");
    *out = 0;
    json_array_foreach(v, i, name)
    {
        unsigned bit = 0;
        for (unsigned k = 0; json_is_string(name) && k < API_NFIELDS3; k++)
            if (strcmp(json_string_value(name), api_field3_names[k]) == 0) bit = 1u << k;
        if (!bit)
            return api_fail(err, API_EINVALID,
                            "options.fields[%zu]: expected one of \"V\", \"EV\", \"FV\", \"FE\", "
                            "\"holes\", \"CF\", \"CV\", \"exterior\", \"stats\", \"operators\", "
                            "\"membership\", \"result\"",
                            i);
        *out |= bit;
    }
    return api_lar3_fields_check(*out, err);
}

static int parse_options(const json_t *o, solids_req *r, api_error *err)
{
    const char *key;
    json_t *v;
    int operators = 0;
    r->fields = API_F3_DEFAULT;
    if (!o) return API_OK;
    if (!json_is_object(o)) return api_fail(err, API_EINVALID, "options: expected an object");
    json_object_foreach((json_t *)o, key, v)
    {
        if (strcmp(key, "precision") == 0) {
            if (!json_is_number(v) || !(json_number_value(v) > 0) ||
                !isfinite(json_number_value(v)))
                return api_fail(err, API_EINVALID, "options.precision: expected a number > 0");
            r->precision = json_number_value(v);
        } else if (strcmp(key, "operators") == 0) {
            if (!json_is_boolean(v))
                return api_fail(err, API_EINVALID, "options.operators: expected true or false");
            operators = json_is_true(v);
        } else if (strcmp(key, "fields") == 0) {
            int rc = parse_fields(v, &r->fields, err);
            if (rc != API_OK) return rc;
        } else if (strcmp(key, "fill") == 0) {
            int rc = api_fill_parse(v, BOOL3_FILL_POSITIVE, &r->fill, err);
            if (rc != API_OK) return rc;
        } else {
            return api_fail(err, API_EINVALID,
                            "options.%.64s: unknown option (expected precision, operators, "
                            "fields or fill)",
                            key);
        }
    }
    if (operators) r->fields |= API_F3_OPERATORS;
    return API_OK;
}

/* ---- the geometry, copied ------------------------------------------------------------------- */

/* Writes the JSON path of cycle FV[f], or holes.key[h] when key is not NULL, of the solid at
 * path into where. */
static const char *cycle_path(char *where, size_t cap, const char *path, size_t f, const char *key,
                              size_t h)
{
    if (key)
        snprintf(where, cap, "%s.holes.%s[%zu]", path, key, h);
    else
        snprintf(where, cap, "%s.FV[%zu]", path, f);
    return where;
}

/* Checks one cycle (FV[f], or holes.key[h] when key is not NULL) of a solid with nv vertices;
 * copies its indices to out when out is not NULL. */
static int read_cycle(const json_t *row, size_t nv, uint32_t *out, const char *path, size_t f,
                      const char *key, size_t h, api_error *err)
{
    char w[160];
    size_t n = json_array_size(row);
    if (!json_is_array(row))
        return api_fail(err, API_EINVALID, "%s: expected an array of vertex indices",
                        cycle_path(w, sizeof w, path, f, key, h));
    if (n < 3)
        return api_fail(err, API_EINVALID, "%s: expected at least 3 vertex indices, got %zu",
                        cycle_path(w, sizeof w, path, f, key, h), n);
    if (n > SOLIDS_MAX_CYCLE)
        return api_fail(err, API_EINVALID, "%s: %zu vertex indices, at most %u in one cycle",
                        cycle_path(w, sizeof w, path, f, key, h), n, SOLIDS_MAX_CYCLE);
    for (size_t i = 0; i < n; i++) {
        const json_t *v = json_array_get(row, i);
        json_int_t k = json_is_integer(v) ? json_integer_value(v) : -1;
        if (nv == 0)
            return api_fail(err, API_EINVALID, "%s[%zu]: a vertex index, but V is empty",
                            cycle_path(w, sizeof w, path, f, key, h), i);
        if (k < 0 || (uint64_t)k >= nv)
            return api_fail(err, API_EINVALID,
                            "%s[%zu]: expected a vertex index, an integer from 0 to %zu "
                            "(V has %zu rows)",
                            cycle_path(w, sizeof w, path, f, key, h), i, nv - 1, nv);
        if (out) out[i] = (uint32_t)k;
    }
    return API_OK;
}

/* The holes of face f (a JSON array, checked) or NULL. */
static const json_t *holes_of(const json_t *holes, size_t f)
{
    char k[24];
    if (!holes) return NULL;
    snprintf(k, sizeof k, "%zu", f);
    return json_object_get(holes, k);
}

/* Row f of a packed FV: its indices, *n of them. */
static const uint32_t *packed_row(const api_packed *a, size_t f, size_t *n)
{
    *n = a->off[f + 1] - a->off[f];
    return a->idx + a->off[f];
}

/* parse_solid's cycles: the shape and size of every cycle of FV (or of the packed pf) and of
 * holes, checked before anything is allocated; *ncyc_out and *nidx_out get their counts. */
static int check_cycles(const json_t *FV, const json_t *holes, const api_packed *pf, size_t nv,
                        size_t nf, const char *path, const totals *tot, size_t *ncyc_out,
                        size_t *nidx_out, api_error *err)
{
    size_t ncyc = nf, nidx = 0;
    const char *key;
    const json_t *val;
    for (size_t f = 0; pf && f < nf; f++) { /* the checks of read_cycle */
        size_t n;
        const uint32_t *row = packed_row(pf, f, &n);
        if (n < 3 || n > SOLIDS_MAX_CYCLE)
            return api_fail(err, API_EINVALID, "%s.FV[%zu]: cycle length", path, f);
        for (size_t i = 0; i < n; i++)
            if (row[i] >= nv)
                return api_fail(err, API_EINVALID, "%s.FV[%zu][%zu]: index", path, f, i);
        nidx += n;
        if (nidx > SOLIDS_MAX_INDICES - tot->nidx) goto too_many;
    }
    for (size_t f = 0; !pf && f < nf; f++) {
        int rc = read_cycle(json_array_get(FV, f), nv, NULL, path, f, NULL, 0, err);
        if (rc != API_OK) return rc;
        nidx += json_array_size(json_array_get(FV, f));
        if (nidx > SOLIDS_MAX_INDICES - tot->nidx) goto too_many;
    }
    if (holes) {
        if (!json_is_object(holes))
            return api_fail(err, API_EINVALID,
                            "%s.holes: expected an object {\"f\": [[v, ...], ...]} keyed by face "
                            "index",
                            path);
        json_object_foreach((json_t *)holes, key, val)
        {
            size_t f;
            if (!api_face_key(key, nf, &f))
                return api_fail(err, API_EINVALID,
                                "%s.holes.%.40s: expected a face index in decimal, below %zu (the "
                                "rows of FV)",
                                path, key, nf);
            if (!json_is_array(val) || json_array_size(val) == 0)
                return api_fail(err, API_EINVALID,
                                "%s.holes.%s: expected a non-empty array of cycles", path, key);
            for (size_t h = 0; h < json_array_size(val); h++) {
                int rc = read_cycle(json_array_get(val, h), nv, NULL, path, f, key, h, err);
                if (rc != API_OK) return rc;
                nidx += json_array_size(json_array_get(val, h));
                if (nidx > SOLIDS_MAX_INDICES - tot->nidx) goto too_many;
                ncyc++;
            }
        }
    }
    *ncyc_out = ncyc;
    *nidx_out = nidx;
    return API_OK;
too_many:
    return api_fail(err, API_EINVALID, "%s: %zu vertex indices in the cycles in all, at most %u",
                    path, tot->nidx + nidx, SOLIDS_MAX_INDICES);
}

/* parse_solid's copy: the checked solid (nv vertices, nf faces, ncyc cycles of nidx indices in
 * all) into *out; a packed V, and a packed FV without holes, are taken as they are. */
static int copy_solid(const json_t *V, const json_t *FV, const json_t *holes, api_packed *pv,
                      api_packed *pf, size_t nv, size_t nf, size_t ncyc, size_t nidx,
                      const char *path, solid *out, api_error *err)
{
    size_t c, w;
    /* copy (a packed V, and a packed FV without holes, are taken as they are) */
    if (pv && pv->V) {
        out->V = pv->V;
        pv->taken = 1;
    } else {
        out->V = malloc((nv ? 3 * nv : 1) * sizeof *out->V);
    }
    out->face_off = malloc((nf + 1) * sizeof *out->face_off);
    if (pf && ncyc == nf) {
        out->cyc_off = pf->off;
        out->cyc = pf->idx;
        pf->taken = 1;
    } else {
        out->cyc_off = malloc((ncyc + 1) * sizeof *out->cyc_off);
        out->cyc = malloc((nidx ? nidx : 1) * sizeof *out->cyc);
    }
    if (!out->V || !out->face_off || !out->cyc_off || !out->cyc) {
        solid_free(out);
        return api_fail(err, API_ENOMEM, "out of memory for %s", path);
    }
    out->nv = nv;
    out->nf = nf;
    out->ncyc = ncyc;
    if (pf && ncyc == nf) {
        for (size_t f = 0; f <= nf; f++) out->face_off[f] = (uint32_t)f;
        return API_OK;
    }
    for (size_t v = 0; !pv && v < nv; v++)
        for (size_t a = 0; a < 3; a++)
            out->V[3 * v + a] = json_number_value(json_array_get(json_array_get(V, v), a));
    c = w = 0;
    for (size_t f = 0; f < nf; f++) {
        const json_t *row = pf ? NULL : json_array_get(FV, f), *hs = holes_of(holes, f);
        out->face_off[f] = (uint32_t)c;
        out->cyc_off[c++] = (uint32_t)w;
        if (pf) {
            size_t n;
            const uint32_t *r = packed_row(pf, f, &n);
            memcpy(out->cyc + w, r, n * sizeof *r);
            w += n;
        } else {
            read_cycle(row, nv, out->cyc + w, path, f, NULL, 0, NULL);
            w += json_array_size(row);
        }
        for (size_t h = 0; h < json_array_size(hs); h++) {
            row = json_array_get(hs, h);
            out->cyc_off[c++] = (uint32_t)w;
            read_cycle(row, nv, out->cyc + w, path, f, "", h, NULL);
            w += json_array_size(row);
        }
    }
    out->face_off[nf] = (uint32_t)c;
    out->cyc_off[c] = (uint32_t)w;
    if (c != ncyc || w != nidx) { /* cannot happen: the keys were checked canonical and < nf */
        solid_free(out);
        return api_fail(err, API_EINTERNAL, "internal error: %s: holes counted differently", path);
    }
    return API_OK;
}

/* Reads o, the solid at path ("solids[2]", or "faces" for a soup), into *out.  With pk, its V
 * and FV may be placeholders of arrays read beforehand (solid si's, api/packed.h): those are
 * taken as they are (checked here as the JSON ones are, but the messages are not kept: the
 * caller reads the whole text again on any failure). */
static int parse_solid(const json_t *o, const char *path, int soup, totals *tot, solid *out,
                       api_packed_set *pk, size_t si, api_error *err)
{
    const json_t *V, *FV, *holes, *val;
    const char *key;
    size_t nv, nf, ncyc = 0, nidx = 0;
    api_packed *pv = NULL, *pf = NULL;
    if (!json_is_object(o))
        return api_fail(err, API_EINVALID,
                        "%s: expected an object {\"V\": [[x, y, z], ...], \"FV\": [[v, ...], "
                        "...]}",
                        path);
    json_object_foreach((json_t *)o, key, val)
    {
        if (strcmp(key, "V") && strcmp(key, "FV") && strcmp(key, "holes"))
            return api_fail(err, API_EINVALID, "%s.%.64s: unknown key (expected V, FV or holes)",
                            path, key);
    }
    V = json_object_get(o, "V");
    FV = json_object_get(o, "FV");
    holes = json_object_get(o, "holes");
    if (pk && json_is_string(V)) pv = api_packed_find(pk, si, API_PACKED_V, json_string_value(V));
    if (pk && json_is_string(FV))
        pf = api_packed_find(pk, si, API_PACKED_FV, json_string_value(FV));
    if (!V) return api_fail(err, API_EINVALID, "%s.V: required, an array of [x, y, z]", path);
    if (!json_is_array(V) && !pv)
        return api_fail(err, API_EINVALID, "%s.V: expected an array of [x, y, z]", path);
    nv = pv ? pv->n : json_array_size(V);
    if (nv > SOLIDS_MAX_VERTICES - tot->nv)
        return api_fail(err, API_EINVALID, "%s.V: %zu vertices in all, at most %u allowed", path,
                        tot->nv + nv, SOLIDS_MAX_VERTICES);
    if (!FV)
        return api_fail(err, API_EINVALID,
                        "%s.FV: required, an array of faces (cycles of vertex indices)", path);
    if (!json_is_array(FV) && !pf)
        return api_fail(err, API_EINVALID,
                        "%s.FV: expected an array of faces (cycles of vertex indices)", path);
    nf = pf ? pf->n : json_array_size(FV);
    if (nf > SOLIDS_MAX_FACES - tot->nf)
        return api_fail(err, API_EINVALID, "%s.FV: %zu faces in all, at most %u allowed", path,
                        tot->nf + nf, (unsigned)max_faces);
    if (nf == 0)
        return api_fail(err, API_EINVALID, "%s.FV: expected %s, got none", path,
                        soup ? "at least one face" : "the faces of a closed surface");
    for (size_t v = 0; !pv && v < nv; v++) { /* a packed V holds 3 finite numbers a row */
        const json_t *p = json_array_get(V, v);
        if (!json_is_array(p) || json_array_size(p) != 3)
            return api_fail(err, API_EINVALID, "%s.V[%zu]: expected 3 finite numbers [x, y, z]",
                            path, v);
        for (size_t a = 0; a < 3; a++) {
            const json_t *x = json_array_get(p, a);
            if (!json_is_number(x) || !isfinite(json_number_value(x)))
                return api_fail(err, API_EINVALID, "%s.V[%zu][%zu]: expected a finite number", path,
                                v, a);
        }
    }
    int rc = check_cycles(FV, holes, pf, nv, nf, path, tot, &ncyc, &nidx, err);
    if (rc == API_OK) rc = copy_solid(V, FV, holes, pv, pf, nv, nf, ncyc, nidx, path, out, err);
    if (rc != API_OK) return rc;
    tot->nv += nv;
    tot->nf += nf;
    tot->nidx += nidx;
    return API_OK;
}

static void checked_free(struct solids_checked *ck, size_t ns);

void api_solids_free(void *parsed)
{
    solids_req *r = parsed;
    if (!r) return;
    checked_free(r->checked, r->ns);
    free(r->checked);
    bool_expr_free(&r->op);
    for (size_t i = 0; i < r->ns; i++) solid_free(&r->s[i]);
    free(r->s);
    for (size_t k = 0; k < r->nlayers; k++) free(r->lname[k]), free(r->lkey[k]);
    free(r->lname);
    free(r->lkey);
    free(r->lfirst);
    free(r->layers);
    free(r);
}

/* Reads "layers": {"name": [solid, ...] or one solid, ...} into r->s, layer after layer. */
static int parse_layers(const json_t *ls, solids_req *r, totals *tot, api_packed_set *pk,
                        api_error *err)
{
    const char *key;
    json_t *v;
    size_t n = 0, nl = json_object_size(ls);
    if (!json_is_object(ls) || nl == 0)
        return api_fail(err, API_EINVALID,
                        "layers: expected an object {\"name\": [solid, ...], ...}");
    json_object_foreach((json_t *)ls, key, v) n += json_is_array(v) ? json_array_size(v) : 1;
    if (n > SOLIDS_MAX_SOLIDS)
        return api_fail(err, API_EINVALID, "layers: %zu solids, at most %u allowed", n,
                        SOLIDS_MAX_SOLIDS);
    r->s = calloc(n ? n : 1, sizeof *r->s);
    r->lname = calloc(nl, sizeof *r->lname);
    r->lkey = calloc(nl, sizeof *r->lkey);
    r->lfirst = calloc(nl + 1, sizeof *r->lfirst);
    if (!r->s || !r->lname || !r->lkey || !r->lfirst)
        return api_fail(err, API_ENOMEM, "out of memory");
    api_buf lb = {0};
    api_buf_putc(&lb, '[');
    json_object_foreach((json_t *)ls, key, v)
    {
        size_t k = r->nlayers;
        if (!*key || strlen(key) > API_LAYER_NAME_MAX) {
            api_buf_free(&lb);
            return api_fail(err, API_EINVALID, "layers: a layer's name must have 1 to %d bytes",
                            API_LAYER_NAME_MAX);
        }
        json_t *js = json_string(key);
        r->lname[k] = js ? json_dumps(js, JSON_ENCODE_ANY | JSON_COMPACT) : NULL;
        r->lkey[k] = strdup(key);
        json_decref(js);
        r->nlayers++;
        if (!r->lname[k] || !r->lkey[k]) {
            api_buf_free(&lb);
            return api_fail(err, API_ENOMEM, "out of memory");
        }
        r->lfirst[k] = (uint32_t)r->ns;
        size_t m = json_is_array(v) ? json_array_size(v) : 1;
        if (json_is_array(v) && m == 0) {
            api_buf_free(&lb);
            return api_fail(err, API_EINVALID,
                            "layers.%.100s: expected a solid or a non-empty "
                            "array of solids",
                            key);
        }
        for (size_t j = 0; j < m; j++) {
            char path[160];
            snprintf(path, sizeof path, json_is_array(v) ? "layers.%.100s[%zu]" : "layers.%.100s",
                     key, j);
            /* the fast reader knows "solids" only: a layer's solids are read by jansson */
            int rc = parse_solid(json_is_array(v) ? json_array_get(v, j) : v, path, 0, tot,
                                 &r->s[r->ns], NULL, r->ns, err);
            r->ns++;
            if (rc != API_OK) {
                api_buf_free(&lb);
                return rc;
            }
        }
        if (k) api_buf_putc(&lb, ',');
        api_buf_puts(&lb, "{\"name\":");
        api_buf_puts(&lb, r->lname[k]);
        api_buf_puts(&lb, ",\"first\":");
        api_buf_u64(&lb, r->lfirst[k]);
        api_buf_puts(&lb, ",\"count\":");
        api_buf_u64(&lb, r->ns - r->lfirst[k]);
        api_buf_putc(&lb, '}');
    }
    (void)pk;
    r->lfirst[r->nlayers] = (uint32_t)r->ns;
    api_buf_putc(&lb, ']');
    if (lb.failed) {
        api_buf_free(&lb);
        return api_fail(err, API_ENOMEM, "out of memory");
    }
    r->layers = lb.p;
    return API_OK;
}

int api_solids_parse(const json_t *req, void **parsed, api_error *err)
{
    return api_solids_parse_packed(req, NULL, parsed, err);
}

int api_solids_parse_packed(const json_t *req, api_packed_set *pk, void **parsed, api_error *err)
{
    const json_t *solids, *faces;
    const char *key;
    json_t *val;
    solids_req *r;
    totals tot = {0};
    int rc;
    *parsed = NULL;
    json_object_foreach((json_t *)req, key, val)
    {
        if (strcmp(key, "kind") && strcmp(key, "solids") && strcmp(key, "faces") &&
            strcmp(key, "layers") && strcmp(key, "options") && strcmp(key, "op"))
            return api_fail(err, API_EINVALID,
                            "%.64s: unknown key (expected kind, solids, layers or faces, op and "
                            "options)",
                            key);
    }
    solids = json_object_get(req, "solids");
    faces = json_object_get(req, "faces");
    const json_t *layers = json_object_get(req, "layers");
    if (!!solids + !!faces + !!layers > 1)
        return api_fail(err, API_EINVALID,
                        "%s: give one of \"solids\" (closed surfaces), \"layers\" (named groups "
                        "of them) and \"faces\" (one face soup)",
                        faces ? "faces" : "layers");
    if (!solids && !faces && !layers)
        return api_fail(err, API_EINVALID,
                        "solids: required, an array of solids (or \"layers\": named groups of "
                        "solids, or \"faces\": one face soup)");
    r = calloc(1, sizeof *r);
    if (!r) return api_fail(err, API_ENOMEM, "out of memory");
    rc = parse_options(json_object_get(req, "options"), r, err);
    if (rc != API_OK) goto fail;
    if (layers) {
        rc = parse_layers(layers, r, &tot, pk, err);
        if (rc != API_OK) goto fail;
    } else if (solids) {
        size_t n = json_array_size(solids);
        if (!json_is_array(solids)) {
            rc = api_fail(err, API_EINVALID,
                          "solids: expected an array of solids {\"V\": ..., \"FV\": ...}");
            goto fail;
        }
        if (n > SOLIDS_MAX_SOLIDS) {
            rc = api_fail(err, API_EINVALID, "solids: %zu solids, at most %u allowed", n,
                          SOLIDS_MAX_SOLIDS);
            goto fail;
        }
        r->s = calloc(n ? n : 1, sizeof *r->s);
        if (!r->s) {
            rc = api_fail(err, API_ENOMEM, "out of memory for %zu solids", n);
            goto fail;
        }
        r->ns = n;
        for (size_t i = 0; i < n; i++) {
            char path[32];
            snprintf(path, sizeof path, "solids[%zu]", i);
            rc = parse_solid(json_array_get(solids, i), path, 0, &tot, &r->s[i], pk, i, err);
            if (rc != API_OK) goto fail;
        }
    } else {
        r->soup = 1;
        r->s = calloc(1, sizeof *r->s);
        if (!r->s) {
            rc = api_fail(err, API_ENOMEM, "out of memory");
            goto fail;
        }
        r->ns = 1;
        rc = parse_solid(faces, "faces", 1, &tot, &r->s[0], pk, API_PACKED_FACES, err);
        if (rc != API_OK) goto fail;
    }
    if (json_object_get(req, "op")) {
        if (r->soup) {
            rc = api_fail(err, API_EINVALID,
                          "op: needs \"solids\" (a face soup has no inside to combine)");
            goto fail;
        }
        if (r->nlayers) {
            api_layers ly = {r->nlayers, r->lname, r->lfirst};
            rc = api_bool_parse_layers(json_object_get(req, "op"), r->ns, &ly, &r->op, err);
        } else {
            rc = api_bool_parse(json_object_get(req, "op"), r->ns, &r->op, err);
        }
        if (rc != API_OK) goto fail;
        r->has_op = 1;
    }
    {
        char msg[API_ERRMAX];
        if (arr3_solids_step(r->s, r->ns, r->precision, &r->step, msg, sizeof msg) != ARR_OK) {
            rc = api_fail(err, API_EINVALID, "options.%s", msg); /* "precision: ..." */
            goto fail;
        }
    }
    *parsed = r;
    return API_OK;
fail:
    api_solids_free(r);
    return rc;
}

/* ---- the geometry, checked ------------------------------------------------------------------ */

/* A solid_check message as a JSON path message: about face f of solids[i] it reads
 * "solids[i].FV[f]: what", about vertex v "solids[i].V[v]: what", about hole h of face f
 * "solids[i].holes.f[h]: what", else "solids[i]: what" (label is "solids[i]" or "faces"). */
static void json_path_message(const solid_report *rep, size_t m, const char *label, char *out,
                              size_t cap)
{
    const solid_msg_info *in = &rep->info[m];
    const char *what = rep->msg[m] + in->what;
    if (in->at == SOLID_AT_FACE)
        snprintf(out, cap, "%s.FV[%zu]: %s", label, in->index, what);
    else if (in->at == SOLID_AT_VERTEX)
        snprintf(out, cap, "%s.V[%zu]: %s", label, in->index, what);
    else if (in->at == SOLID_AT_HOLE)
        snprintf(out, cap, "%s.holes.%zu[%zu]: %s", label, in->index, in->sub, what);
    else
        snprintf(out, cap, "%s: %s", label, what);
}

static void warn_add(warn_list *w, const solid_report *rep, size_t m, const char *label)
{
    w->total++;
    if (w->n < SOLIDS_MAX_WARNINGS - 1) {
        json_path_message(rep, m, label, w->msg[w->n], WARN_LEN);
        w->ptr[w->n] = w->msg[w->n];
        w->n++;
    }
}

/* Closes the list: when some were left out, the last entry counts them. */
static void warn_finish(warn_list *w)
{
    if (w->total > w->n) {
        snprintf(w->msg[w->n], WARN_LEN, "%zu more warnings left out", w->total - w->n);
        w->ptr[w->n] = w->msg[w->n];
        w->n++;
    }
}

/* What check_solid found for solids[i] (rep), turned into the request's answer: its warnings
 * into w (may be NULL), or the 422 of its first error. */
static int report_solid(const solids_req *r, const solid_report *rep, size_t i, warn_list *w,
                        api_error *err)
{
    char label[160], where[API_ERRMAX];
    solid_label(r, i, label, sizeof label);
    if (rep->errors == 0) {
        for (size_t m = 0; w && m < rep->nmsg; m++) warn_add(w, rep, m, label);
        if (w) w->total += rep->warnings > rep->nmsg ? rep->warnings - rep->nmsg : 0;
        return API_OK;
    }
    size_t first = rep->nmsg;
    for (size_t m = 0; m < rep->nmsg && first == rep->nmsg; m++)
        if (!rep->info[m].warning) first = m;
    if (first == rep->nmsg) return api_fail(err, API_EINVALID, "%s: invalid solid", label);
    if (strcmp(rep->msg[first] + rep->info[first].what, "out of memory") == 0)
        return api_fail(err, API_ENOMEM, "out of memory while checking %s", label);
    json_path_message(rep, first, label, where, sizeof where);
    if (rep->errors > 1)
        return api_fail(err, API_EINVALID, "%s (and %zu more errors in %s)", where, rep->errors - 1,
                        label);
    return api_fail(err, API_EINVALID, "%s", where);
}

/* The checks of the solids, one a task on the threads (each writes only its own report, fixed
 * copy and twins; the reports are read in order after). */
typedef struct checkjob {
    const solids_req *r;
    solid *fixed;      /* may be NULL */
    uint32_t **twin;   /* may be NULL */
    solid_report *rep; /* by solid */
    const api_run_opts *ro;
} checkjob;

static void check_one(void *ctx, size_t i, int worker)
{
    (void)worker;
    const checkjob *j = ctx;
    const solids_req *r = j->r;
    solid_report *rep = &j->rep[i];
    char label[160];
    if (j->ro && j->ro->cancel && atomic_load(j->ro->cancel)) {
        rep->errors = 0, rep->nmsg = 0;
        return;
    }
    solid_label(r, i, label, sizeof label);
    if (r->soup)
        solid_check_faces(&r->s[i], r->step, label, rep);
    else
        solid_check_nocopy(&r->s[i], r->step, label, rep, j->fixed ? &j->fixed[i] : NULL,
                           j->twin ? j->twin[i] : NULL);
}

static void check_tick(void *ctx, double f)
{
    const api_run_opts *ro = ctx;
    ro->progress(ro->udata, "check", f);
}

/* Checks the geometry at the grid step (the solids on ro->threads threads); fixed (ns entries,
 * may be NULL) gets solid_check's fixed copies, twin (ns arrays, may be NULL) the pairings it
 * found, w (may be NULL) the warnings.  The first error (by solid) is the answer. */
static int validate(const solids_req *r, solid *fixed, uint32_t **twin, warn_list *w,
                    const api_run_opts *ro, api_error *err)
{
    solid_report *rep = calloc(r->ns ? r->ns : 1, sizeof *rep);
    int rc = API_OK;
    if (!rep) return api_fail(err, API_ENOMEM, "out of memory");
    checkjob j = {r, fixed, twin, rep, ro};
    int threads = ro && ro->threads > 0 ? ro->threads : 1;
    if (ro && ro->progress)
        par_for_ex(threads, r->ns, check_one, &j, check_tick, (void *)ro);
    else
        par_for(threads, r->ns, check_one, &j);
    if (ro && ro->cancel && atomic_load(ro->cancel)) {
        rc = api_fail(err, API_ECANCELED, "canceled");
        goto out;
    }
    for (size_t i = 0; i < r->ns && rc == API_OK; i++) rc = report_solid(r, &rep[i], i, w, err);
out:
    free(rep);
    return rc;
}

static double ms_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

/* What the check of a request makes for its run: the fixed copies (NULL for a soup; an entry
 * with no faces: the solid needed no change), the edges' pairings (NULL for a soup), the
 * warnings, and how long the check took. */
typedef struct solids_checked {
    solid *fixed;
    uint32_t **twin;
    warn_list *w;
    double ms;
} solids_checked;

static void checked_free(solids_checked *ck, size_t ns)
{
    if (!ck) return;
    for (size_t i = 0; ck->twin && i < ns; i++) free(ck->twin[i]);
    free(ck->twin);
    for (size_t i = 0; ck->fixed && i < ns; i++) solid_free(&ck->fixed[i]);
    free(ck->fixed);
    free(ck->w);
    memset(ck, 0, sizeof *ck);
}

/* The check stage: the geometry of r's solids checked (validate) into *ck (which the caller
 * frees with checked_free, success or not); ro may be NULL (one thread, no progress). */
static int check_stage(const solids_req *r, const api_run_opts *ro, solids_checked *ck,
                       api_error *err)
{
    double t = ms_now();
    if (!(ck->w = calloc(1, sizeof *ck->w))) return api_fail(err, API_ENOMEM, "out of memory");
    if (ro && ro->progress) ro->progress(ro->udata, "check", 0);
    if (!r->soup && (!(ck->fixed = calloc(r->ns ? r->ns : 1, sizeof *ck->fixed)) ||
                     !(ck->twin = calloc(r->ns ? r->ns : 1, sizeof *ck->twin))))
        return api_fail(err, API_ENOMEM, "out of memory for %zu solids", r->ns);
    /* the checks' pairings of the edges, handed to the arrangement (arr3_build_ex) */
    for (size_t i = 0; ck->twin && i < r->ns; i++)
        if (!(ck->twin[i] = malloc((r->s[i].cyc_off[r->s[i].ncyc] + 1) * sizeof *ck->twin[i])))
            return api_fail(err, API_ENOMEM, "out of memory for %zu solids", r->ns);
    int rc = validate(r, r->soup ? NULL : ck->fixed, ck->twin, ck->w, ro, err);
    ck->ms = ms_now() - t;
    return rc;
}

int api_solids_check(void *parsed, api_error *err)
{
    solids_req *r = parsed;
    solids_checked *ck = calloc(1, sizeof *ck);
    if (!ck) return api_fail(err, API_ENOMEM, "out of memory");
    int rc = check_stage(r, NULL, ck, err);
    if (rc != API_OK) {
        checked_free(ck, r->ns);
        free(ck);
        return rc;
    }
    r->checked = ck; /* kept for the run */
    return API_OK;
}

/* Progress inside the membership walk. */
static void membership_tick(void *udata, double f)
{
    const api_run_opts *ro = udata;
    ro->progress(ro->udata, "membership", f);
}

/* What a run computes, before it is written (api_solids_run) or handed out as arrays
 * (api_solids_arrays). */
typedef struct solids_out {
    lar3 c;
    bool3_result res;
    member_rows mem;
    warn_list *w;
    api_lar3_fmt fmt;
} solids_out;

static void solids_out_free(solids_out *o)
{
    bool3_result_free(&o->res);
    member_rows_free(&o->mem);
    lar3_free(&o->c);
    free(o->w);
}

/* Checks the solids, builds the arrangement and, with an op, the membership and the Boolean,
 * into *o (which the caller frees with solids_out_free, success or not). */
static int solids_compute(const solids_req *r, const api_run_opts *ro, solids_out *o,
                          api_error *err)
{
    static const solid no_solid;
    arr3_opts ao = {.precision = r->step,
                    .threads = ro->threads,
                    .cancel = ro->cancel,
                    .progress = ro->progress,
                    .udata = ro->udata,
                    /* only the parts of the complex the fields print */
                    .want = api_lar3_want(r->fields),
                    /* check_stage (here or at intake) checked every solid at r->step */
                    .checked = 1};
    char msg[API_ERRMAX] = "";
    int rc = API_OK;
    /* checked once: by api_solids_check (taken from the request: a second run checks again),
     * or here */
    solids_checked ck = {0};
    if (r->checked) {
        ck = *r->checked;
        memset(r->checked, 0, sizeof *r->checked);
        if (ro->progress) ro->progress(ro->udata, "check", 0);
    } else {
        rc = check_stage(r, ro, &ck, err);
    }
    solid *fixed = ck.fixed;
    uint32_t **twin = ck.twin;
    warn_list *w = o->w = ck.w;
    if (rc != API_OK) goto out;
    if (ro->progress) ro->progress(ro->udata, "check", 1);
    double ms_check = ck.ms;
    if (r->soup)
        rc = arr3_build(r->s, 1, 1, &ao, &o->c, msg, sizeof msg);
    else {
        /* a solid that needed no change is used as it is (no fixed copy was made) */
        for (size_t i = 0; i < r->ns; i++)
            if (fixed[i].nf == 0) fixed[i] = r->s[i];
        rc = arr3_build_ex(r->ns ? fixed : &no_solid, r->ns, 0, (const uint32_t *const *)twin, &ao,
                           &o->c, msg, sizeof msg);
        for (size_t i = 0; i < r->ns; i++) free(twin[i]);
        free(twin);
        twin = NULL;
        for (size_t i = 0; i < r->ns; i++)
            if (fixed[i].V == r->s[i].V) memset(&fixed[i], 0, sizeof fixed[i]);
    }
    if (rc != ARR_OK) {
        rc = api_core_fail(err, rc, msg);
        goto out;
    }
    for (size_t k = 0; k < o->c.nselfx; k++) { /* the surfaces that pass through themselves */
        const arr3_selfx *x = &o->c.selfx[k];
        w->total++;
        if (w->n < SOLIDS_MAX_WARNINGS - 1) {
            snprintf(w->msg[w->n], WARN_LEN,
                     "solids[%u]: the surface passes through itself: %zu pair%s of its faces "
                     "cross or overlap, the first faces %u and %u near (%.9g, %.9g, %.9g)",
                     x->solid, x->pairs, x->pairs == 1 ? "" : "s", x->fa, x->fb, x->at[0], x->at[1],
                     x->at[2]);
            w->ptr[w->n] = w->msg[w->n];
            w->n++;
        }
    }
    warn_finish(w);
    if (!(o->c.stats.precision > 0)) o->c.stats.precision = r->step; /* no faces: nothing snapped */
    o->c.stats.ms_check = ms_check;
    o->c.stats.ms_total += ms_check;
    o->fmt = (api_lar3_fmt){
        .fields = r->fields, .warnings = w->ptr, .nwarnings = w->n, .layers = r->layers};
    if (r->has_op) { /* membership of every cell, then the chain of the expression */
        uint32_t bad_face;
        double t_bool = ms_now();
        if (ro->progress) ro->progress(ro->udata, "membership", 0);
        int m = bool3_membership_ex(&o->c, &o->mem, &bad_face,
                                    ro->progress ? membership_tick : NULL, (void *)ro);
        if (!m && ro->progress) ro->progress(ro->udata, "membership", 1);
        if (m) {
            rc = m < 0 ? api_fail(err, API_ENOMEM, "out of memory")
                       : api_fail(err, API_EINTERNAL,
                                  "op: cells reached with two memberships across face %u (a "
                                  "broken complex)",
                                  bad_face);
            goto out;
        }
        if (bool3_select_fill(&o->c, &o->mem, &r->op, r->fill, &o->res)) {
            rc = api_fail(err, API_ENOMEM, "out of memory");
            goto out;
        }
        o->fmt.membership = &o->mem;
        o->fmt.result = &o->res;
        o->c.stats.ms_boolean = ms_now() - t_bool;
        o->c.stats.ms_total += o->c.stats.ms_boolean;
    }
    if (ro->cancel && atomic_load(ro->cancel)) {
        rc = api_fail(err, API_ECANCELED, "canceled");
        goto out;
    }
    if (ro->progress) ro->progress(ro->udata, "output", 0);
out:
    for (size_t i = 0; twin && i < r->ns; i++) free(twin[i]);
    free(twin);
    for (size_t i = 0; fixed && i < r->ns; i++) solid_free(&fixed[i]);
    free(fixed);
    return rc;
}

int api_solids_run(const void *parsed, const api_run_opts *ro, api_buf *out, api_error *err)
{
    solids_out o = {0};
    int rc = solids_compute(parsed, ro, &o, err);
    if (rc == API_OK) rc = api_lar3_write(out, &o.c, &o.fmt, err);
    solids_out_free(&o);
    return rc;
}

static void solids_out_drop(void *p)
{
    solids_out_free(p);
    free(p);
}

int api_solids_arrays(const void *parsed, const api_run_opts *ro, api_arrays *out, api_error *err)
{
    solids_out *o = calloc(1, sizeof *o); /* kept by the result, which frees it, success or not */
    if (!o || api_arrays_keep(out, o, solids_out_drop))
        return api_fail(err, API_ENOMEM, "out of memory");
    int rc = solids_compute(parsed, ro, o, err);
    return rc == API_OK ? api_lar3_arrays(out, &o->c, &o->fmt, err) : rc;
}

/* ---- solids already read -------------------------------------------------------------------- */

/* parse_solid's checks on a solid read from a file (the reader has checked the indices and the
 * numbers; the limits and the shapes of the cycles are checked here, with the same messages). */
static int check_read_solid(const solid *s, const char *path, int soup, totals *tot, api_error *err)
{
    char w[160];
    if (s->nv > SOLIDS_MAX_VERTICES - tot->nv)
        return api_fail(err, API_EINVALID, "%s.V: %zu vertices in all, at most %u allowed", path,
                        tot->nv + s->nv, SOLIDS_MAX_VERTICES);
    if (s->nf > SOLIDS_MAX_FACES - tot->nf)
        return api_fail(err, API_EINVALID, "%s.FV: %zu faces in all, at most %u allowed", path,
                        tot->nf + s->nf, (unsigned)SOLIDS_MAX_FACES);
    if (s->nf == 0)
        return api_fail(err, API_EINVALID, "%s.FV: expected %s, got none", path,
                        soup ? "at least one face" : "the faces of a closed surface");
    for (size_t v = 0; v < 3 * s->nv; v++)
        if (!isfinite(s->V[v]))
            return api_fail(err, API_EINVALID, "%s.V[%zu][%zu]: expected a finite number", path,
                            v / 3, v % 3);
    size_t nidx = s->cyc_off[s->ncyc];
    if (nidx > SOLIDS_MAX_INDICES - tot->nidx)
        return api_fail(err, API_EINVALID,
                        "%s: %zu vertex indices in the cycles in all, at most %u", path,
                        tot->nidx + nidx, SOLIDS_MAX_INDICES);
    for (size_t f = 0; f < s->nf; f++)
        for (uint32_t c = s->face_off[f]; c < s->face_off[f + 1]; c++) {
            size_t n = s->cyc_off[c + 1] - s->cyc_off[c], h = c - s->face_off[f] - 1;
            int ok = n >= 3 && n <= SOLIDS_MAX_CYCLE;
            for (uint32_t i = s->cyc_off[c]; ok && i < s->cyc_off[c + 1]; i++)
                ok = s->cyc[i] < s->nv;
            if (ok) continue;
            /* the error: where it is */
            char key[24];
            snprintf(key, sizeof key, "%zu", f);
            const char *k = c == s->face_off[f] ? NULL : key;
            if (n < 3)
                return api_fail(err, API_EINVALID,
                                "%s: expected at least 3 vertex indices, got %zu",
                                cycle_path(w, sizeof w, path, f, k, h), n);
            if (n > SOLIDS_MAX_CYCLE)
                return api_fail(err, API_EINVALID,
                                "%s: %zu vertex indices, at most %u in one cycle",
                                cycle_path(w, sizeof w, path, f, k, h), n, SOLIDS_MAX_CYCLE);
            for (uint32_t i = s->cyc_off[c]; i < s->cyc_off[c + 1]; i++)
                if (s->cyc[i] >= s->nv)
                    return api_fail(err, API_EINVALID,
                                    "%s[%u]: expected a vertex index below %zu (V has %zu rows)",
                                    cycle_path(w, sizeof w, path, f, k, h), i - s->cyc_off[c],
                                    s->nv, s->nv);
        }
    tot->nv += s->nv;
    tot->nf += s->nf;
    tot->nidx += nidx;
    return API_OK;
}

/* A request of the solids s (taken over), made as api_solids_run_direct and api_solids_make
 * need it: the checks of a request's solids, options and op. */
static int solids_make(solid *s, size_t n, int soup, const json_t *op, const json_t *options,
                       solids_req **parsed, api_error *err)
{
    totals tot = {0};
    int rc;
    *parsed = NULL;
    solids_req *r = calloc(1, sizeof *r);
    if (!r) {
        for (size_t i = 0; i < n; i++) solid_free(&s[i]);
        free(s);
        return api_fail(err, API_ENOMEM, "out of memory");
    }
    r->s = s; /* taken over: api_solids_free frees them */
    r->ns = n;
    r->soup = soup;
    if (soup && n != 1) {
        rc = api_fail(err, API_EINTERNAL, "internal error: a face soup is one solid");
        goto fail;
    }
    if (!soup && n > SOLIDS_MAX_SOLIDS) {
        rc = api_fail(err, API_EINVALID, "solids: %zu solids, at most %u allowed", n,
                      SOLIDS_MAX_SOLIDS);
        goto fail;
    }
    rc = parse_options(options, r, err);
    if (rc != API_OK) goto fail;
    for (size_t i = 0; i < n; i++) {
        char path[32];
        if (soup)
            snprintf(path, sizeof path, "faces");
        else
            snprintf(path, sizeof path, "solids[%zu]", i);
        rc = check_read_solid(&s[i], path, soup, &tot, err);
        if (rc != API_OK) goto fail;
    }
    if (op) {
        if (soup) {
            rc = api_fail(err, API_EINVALID,
                          "op: needs \"solids\" (a face soup has no inside to combine)");
            goto fail;
        }
        rc = api_bool_parse(op, n, &r->op, err);
        if (rc != API_OK) goto fail;
        r->has_op = 1;
    }
    {
        char msg[API_ERRMAX];
        if (arr3_solids_step(r->s, r->ns, r->precision, &r->step, msg, sizeof msg) != ARR_OK) {
            rc = api_fail(err, API_EINVALID, "options.%s", msg);
            goto fail;
        }
    }
    *parsed = r;
    return API_OK;
fail:
    api_solids_free(r);
    return rc;
}

int api_solids_make(solid *s, size_t n, const json_t *op, const json_t *options, void **parsed,
                    api_error *err)
{
    solids_req *r;
    int rc = solids_make(s, n, 0, op, options, &r, err);
    *parsed = r;
    return rc;
}

int api_solids_run_direct(solid *s, size_t n, int soup, const json_t *op, const json_t *options,
                          const api_run_opts *ro, char **out, size_t *outlen, api_error *err)
{
    api_run_opts dflt = {0};
    api_buf b = {0};
    solids_req *r;
    *out = NULL;
    *outlen = 0;
    if (err) err->status = API_OK, err->msg[0] = 0;
    if (!ro) ro = &dflt;
    int rc = solids_make(s, n, soup, op, options, &r, err);
    if (rc != API_OK) return api_buf_finish(&b, rc, out, outlen, err);
    api_progress pr;
    api_run_opts wr;
    api_progress_wrap(&pr, api_stages_solids, ro, &wr);
    b.sink = wr.stream;
    b.progress = wr.progress;
    b.udata = wr.udata;
    b.cancel = ro->cancel;
    rc = api_solids_run(r, &wr, &b, err);
    void (*up)(void *, const char *, double) = b.progress; /* b goes in api_buf_finish */
    void *uu = b.udata;
    rc = api_buf_finish(&b, rc, out, outlen, err);
    if (rc == API_OK && up) up(uu, "output", 1);
    api_solids_free(r);
    return rc;
}
