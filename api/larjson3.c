/* larjson3.c — LAR JSON out: a 3-complex (core/arr3.h) streamed into a growing buffer.
 *
 *   {"dim":3,"V":[[x,y,z],...],"EV":[[v0,v1],...],"FV":[[v,...],...],"FE":[[±(e+1),...],...],
 *    "holes":{"f":[[v,...],...]},"CF":[[±(f+1),...],...],"CV":[[v,...],...],
 *    "exterior":[±(f+1),...],
 *    "operators":{"d1":{CSR V x E},"d2":{CSR E x F},"d3":{CSR F x C}},
 *    "stats":{counts, "precision", "ms":{...}, "volumes":[...], "warnings":[...]}}
 *
 * Indices are 0-based, signed ones ±(i+1).  Face f's FV row is its outer cycle
 * (counter-clockwise seen from the tip of its normal), its holes (clockwise) are holes."f", its FE
 * row the core's signed edges (+ when the face walks the edge from EV's v0 to v1).  CF row c
 * holds the faces of bounded cell c, +(f+1) when f's normal points out of the cell; CV row c
 * its sorted vertices; "exterior" the faces of the unbounded cell with the same sign rule
 * (so each face appears twice in CF and exterior together, once with each sign).
 * stats.volumes[c] is the volume of cell c; stats.warnings what the validation of the input
 * changed (flipped faces).  The operators are compressed sparse ROW matrices with one column
 * per edge (d1: -1 at v0, +1 at v1), per FE row (d2) and per CF row (d3), so d1·d2 = 0 and
 * d2·d3 = 0; scipy.sparse.csr_matrix((data, indices, indptr), shape) loads them.
 *
 * Why a stream and not a jansson tree, and the number format: see api/larjson.c.  The complex
 * is checked first (every index the writer follows, every number it prints), so a bug in the
 * core is a 500 with a message, never a crash.
 *
 * Threads: reentrant, no globals.  Ownership: the complex and the warnings are borrowed; the
 * buffer is the caller's (api_buf_free() frees it).
 */
#include "api/larjson.h"

#include "api/api_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const api_field3_names[API_NFIELDS3] = {"V",     "EV",        "FV",         "FE",
                                                    "holes", "CF",        "CV",         "exterior",
                                                    "stats", "operators", "membership", "result"};

int api_lar3_fields_check(unsigned fl, api_error *err)
{
    static const api_field_ref rules[] = {{API_F3_EV, API_F3_V, NULL},
                                          {API_F3_FV, API_F3_V, NULL},
                                          {API_F3_FE, API_F3_EV, NULL},
                                          {API_F3_HOLES, API_F3_V, NULL},
                                          {API_F3_HOLES, API_F3_FV | API_F3_FE, "the faces"},
                                          {API_F3_CF, API_F3_FV | API_F3_FE, "the faces"},
                                          {API_F3_CV, API_F3_V, NULL},
                                          {API_F3_EXTERIOR, API_F3_FV | API_F3_FE, "the faces"}};
    return api_fields_refs(fl, rules, sizeof rules / sizeof *rules, api_field3_names, err);
}

/* "membership": the solids each cell lies in (api_put_membership), or, when some cell winds
 * about a solid other than once (a surface that passes through itself, overlaps itself or
 * turns inward), each cell's winding numbers: "indices" the solids of a non-zero one, "data"
 * the numbers (a compressed sparse row matrix of cells x solids, as scipy reads it). */
static void put_membership3(api_buf *b, const lar3 *c, const member_rows *m)
{
    api_put_membership_w(b, c->nc, c->nsolids, m->off, m->idx, m->wind);
}

/* ---- checks ---------------------------------------------------------------------------------- */

/* off[0..n] is a non-decreasing offset array (NULL allowed when n == 0); its end in *end. */
static int offsets_ok(const uint32_t *off, size_t n, size_t *end)
{
    *end = 0;
    if (n == 0) return 1; /* off is not read */
    if (!off || off[0] != 0) return 0;
    for (size_t i = 0; i < n; i++)
        if (off[i + 1] < off[i]) return 0;
    *end = off[n];
    return 1;
}

static int signed_ok(const int32_t *a, size_t n, size_t bound)
{
    if (n && !a) return 0;
    for (size_t i = 0; i < n; i++)
        if (a[i] == 0 || (uint64_t)llabs((long long)a[i]) > bound) return 0;
    return 1;
}

static int index_ok(const uint32_t *a, size_t n, size_t bound)
{
    if (n && !a) return 0;
    for (size_t i = 0; i < n; i++)
        if (a[i] >= bound) return 0;
    return 1;
}

/* The parts of the lar3 the fields need (the core makes the others only when asked: api/solids.c
 * asks for these). */
static int need_faces(unsigned fl)
{
    return (fl & (API_F3_V | API_F3_EV | API_F3_FV | API_F3_FE | API_F3_HOLES | API_F3_CV |
                  API_F3_OPERATORS | API_F3_RESULT)) != 0;
}

static int need_cf(unsigned fl)
{
    return (fl & (API_F3_CF | API_F3_CV | API_F3_EXTERIOR | API_F3_OPERATORS)) != 0;
}

unsigned api_lar3_want(unsigned fl)
{
    /* a result's own V (without V named) is made of the coordinates */
    return ARR3_WANT_ONLY | (fl & (API_F3_V | API_F3_RESULT) ? ARR3_WANT_COORDS : 0) |
           (fl & API_F3_CV ? ARR3_WANT_CV : 0) | (need_faces(fl) ? ARR3_WANT_FACES : 0) |
           (need_cf(fl) ? ARR3_WANT_CF : 0);
}

/* Checks the indices the writer follows and the numbers it prints (of the parts the fields
 * print). */
static int check_complex(const lar3 *c, unsigned fl, api_error *err)
{
    const char *what = NULL;
    size_t ncycv, nfc, nfe, ncf, ncv;
    unsigned coords = fl & (API_F3_V | API_F3_RESULT); /* the result's own V: see put_result */
    if (coords && c->nv && !c->V) what = "V";
    for (size_t i = 0; !what && coords && i < 3 * c->nv; i++)
        if (!isfinite(c->V[i])) what = "V (not finite)";
    if (need_faces(fl)) {
        if (!what && !index_ok(c->EV, 2 * c->ne, c->nv)) what = "EV";
        if (!what && (!offsets_ok(c->cyc_off, c->ncyc, &ncycv) || !index_ok(c->cyc, ncycv, c->nv)))
            what = "cyc";
        if (!what && (!offsets_ok(c->fc_off, c->nf, &nfc) || !index_ok(c->fc, nfc, c->ncyc)))
            what = "fc";
        for (size_t f = 0; !what && f < c->nf; f++)
            if (c->fc_off[f + 1] == c->fc_off[f]) what = "fc_off (a face without a cycle)";
        if (!what && (!offsets_ok(c->fe_off, c->nf, &nfe) || !signed_ok(c->fe, nfe, c->ne)))
            what = "fe";
    }
    if (need_cf(fl)) {
        if (!what && (!offsets_ok(c->cf_off, c->nc, &ncf) || !signed_ok(c->cf, ncf, c->nf)))
            what = "cf";
        if (!what && !signed_ok(c->ext, c->next, c->nf)) what = "ext";
    }
    if (!what && (fl & API_F3_CV) &&
        (!offsets_ok(c->cv_off, c->nc, &ncv) || !index_ok(c->cv, ncv, c->nv)))
        what = "cv";
    if (!what && c->nc && !c->cvol) what = "cvol";
    for (size_t i = 0; !what && i < c->nc; i++)
        if (!isfinite(c->cvol[i])) what = "cvol (not finite)";
    if (what)
        return api_fail(err, API_EINTERNAL, "internal error: the 3-complex's %s is invalid", what);
    return API_OK;
}

/* ---- writers --------------------------------------------------------------------------------- */

static void put_key(api_buf *b, const char *key)
{
    api_buf_section(b);
    api_buf_puts(b, ",\"");
    api_buf_puts(b, key);
    api_buf_puts(b, "\":");
}

static void put_cycle(api_buf *b, const lar3 *c, uint32_t cy)
{
    api_buf_u32_list(b, c->cyc + c->cyc_off[cy], c->cyc_off[cy + 1] - c->cyc_off[cy]);
}

/* Rows of signed lists (FE, CF): row r is a[off[r] .. off[r+1]). */
static void put_signed_rows(api_buf *b, const uint32_t *off, const int32_t *a, size_t n)
{
    api_buf_putc(b, '[');
    for (size_t r = 0; r < n; r++) {
        if (r) api_buf_putc(b, ',');
        api_buf_i32_list(b, a + off[r], off[r + 1] - off[r]);
    }
    api_buf_putc(b, ']');
}

/* A JSON string of printable ASCII: quotes and backslashes escaped, other bytes '?'. */
static void put_string(api_buf *b, const char *s)
{
    api_buf_putc(b, '"');
    for (const char *p = s; *p; p++) {
        if (*p == '"' || *p == '\\') api_buf_putc(b, '\\');
        api_buf_putc(b, (unsigned char)*p >= 0x20 && (unsigned char)*p < 0x7f ? *p : '?');
    }
    api_buf_putc(b, '"');
}

/* The matrix whose column j holds, for each entry s of ent[col_off[j] .. col_off[j+1]),
 * sign(s) at row |s|-1, into *m (the caller frees it with api_csr_free, success or not).
 * Columns are visited in order, so every row's indices come out sorted. */
static int csr_from_columns(size_t nrows, size_t ncols, const uint32_t *col_off, const int32_t *ent,
                            api_csr *m, api_error *err)
{
    size_t nnz = ncols ? col_off[ncols] : 0;
    size_t *fill = malloc((nrows + 1) * sizeof *fill);
    *m = (api_csr){nrows, ncols, calloc(nrows + 2, sizeof *m->ptr),
                   malloc((nnz ? nnz : 1) * sizeof *m->idx), malloc(nnz ? nnz : 1)};
    if (!fill || !m->ptr || !m->idx || !m->val) {
        free(fill);
        return api_fail(err, API_ENOMEM, "out of memory while writing the operators");
    }
    size_t *ptr = m->ptr;
    for (size_t i = 0; i < nnz; i++) ptr[(size_t)llabs((long long)ent[i])]++;
    for (size_t r = 0; r < nrows; r++) ptr[r + 1] += ptr[r];
    memcpy(fill, ptr, (nrows + 1) * sizeof *fill);
    for (size_t j = 0; j < ncols; j++)
        for (size_t i = col_off[j]; i < col_off[j + 1]; i++) {
            size_t at = fill[(size_t)llabs((long long)ent[i]) - 1]++;
            m->idx[at] = (uint32_t)j;
            m->val[at] = ent[i] > 0 ? 1 : -1;
        }
    free(fill);
    return API_OK;
}

/* d1 (V x E), d2 (E x F), d3 (F x C) into m[0..2] (the caller frees them, success or not). */
static int lar3_operators(const lar3 *c, api_csr m[3], api_error *err)
{
    static const uint32_t zero = 0;
    if (c->nv >= INT32_MAX || c->ne >= UINT32_MAX / 2)
        return api_fail(err, API_EINVALID, "operators: the complex is too large to write them");
    uint32_t *off = malloc((c->ne + 1) * sizeof *off);
    int32_t *ent = malloc((2 * c->ne + 1) * sizeof *ent);
    if (!off || !ent) {
        free(off), free(ent);
        return api_fail(err, API_ENOMEM, "out of memory while writing the operators");
    }
    for (size_t e = 0; e <= c->ne; e++) off[e] = (uint32_t)(2 * e);
    for (size_t e = 0; e < c->ne; e++) {
        ent[2 * e] = -(int32_t)(c->EV[2 * e] + 1);
        ent[2 * e + 1] = (int32_t)(c->EV[2 * e + 1] + 1);
    }
    int rc = csr_from_columns(c->nv, c->ne, off, ent, &m[0], err);
    free(off), free(ent);
    if (rc == API_OK)
        rc = csr_from_columns(c->ne, c->nf, c->nf ? c->fe_off : &zero, c->fe, &m[1], err);
    if (rc == API_OK)
        rc = csr_from_columns(c->nf, c->nc, c->nc ? c->cf_off : &zero, c->cf, &m[2], err);
    return rc;
}

static int put_operators(api_buf *b, const lar3 *c, api_error *err)
{
    static const char *const key[3] = {"{\"d1\":", ",\"d2\":", ",\"d3\":"};
    api_csr m[3] = {0};
    int rc = lar3_operators(c, m, err);
    for (int i = 0; i < 3; i++) {
        if (rc == API_OK) {
            api_buf_puts(b, key[i]);
            api_buf_csr(b, m[i].nrows, m[i].ncols, m[i].ptr, m[i].idx, m[i].val);
        }
        api_csr_free(&m[i]);
    }
    if (rc == API_OK) api_buf_putc(b, '}');
    return rc;
}

static void put_stats(api_buf *b, const lar3 *c, const api_lar3_fmt *fmt)
{
    const arr3_stats *s = &c->stats;
    static const char *const names[] = {"input_solids",
                                        "input_faces",
                                        "planes",
                                        "coplanar_groups",
                                        "pairs_tested",
                                        "pairs_meeting",
                                        "faces_reached",
                                        "patches",
                                        "split_faces",
                                        "cuts",
                                        "points",
                                        "V",
                                        "E",
                                        "F",
                                        "C",
                                        "shells",
                                        "components"};
    const size_t counts[] = {s->input_solids,
                             s->input_faces,
                             s->planes,
                             s->coplanar_groups,
                             s->pairs_tested,
                             s->pairs_meeting,
                             s->faces_reached,
                             s->patches,
                             s->split_faces,
                             s->cuts,
                             s->points,
                             c->nv,
                             c->ne,
                             c->nf,
                             c->nc,
                             s->shells,
                             s->components};
    static const char *const ms_names[] = {"check", "snap",  "pairs",   "cuts",
                                           "faces", "cells", "boolean", "total"};
    const double ms[] = {s->ms_check, s->ms_snap,  s->ms_pairs,   s->ms_cuts,
                         s->ms_faces, s->ms_cells, s->ms_boolean, s->ms_total};
    api_buf_putc(b, '{');
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_putc(b, '"');
        api_buf_puts(b, names[i]);
        api_buf_puts(b, "\":");
        api_buf_u64(b, counts[i]);
    }
    put_key(b, "precision");
    api_buf_double(b, isfinite(s->precision) && s->precision > 0 ? s->precision : 0);
    api_buf_puts(b, ",\"ms\":{");
    for (size_t i = 0; i < sizeof ms / sizeof ms[0]; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_putc(b, '"');
        api_buf_puts(b, ms_names[i]);
        api_buf_puts(b, "\":");
        api_buf_double(b, isfinite(ms[i]) && ms[i] > 0 ? ms[i] : 0);
    }
    api_buf_putc(b, '}');
    put_key(b, "volumes");
    api_buf_putc(b, '[');
    for (size_t i = 0; i < c->nc; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_double(b, c->cvol[i]);
    }
    api_buf_putc(b, ']');
    put_key(b, "warnings");
    api_buf_putc(b, '[');
    for (size_t i = 0; i < fmt->nwarnings; i++) {
        if (i) api_buf_putc(b, ',');
        put_string(b, fmt->warnings[i] ? fmt->warnings[i] : "");
    }
    api_buf_puts(b, "]}");
}

/* A cycle walked backwards when reversed (the face turned to point out of the result), its
 * vertices through map (NULL: as they are). */
static void put_cycle_dir(api_buf *b, const lar3 *c, uint32_t cy, int reversed, const uint32_t *map)
{
    uint32_t c0 = c->cyc_off[cy], c1 = c->cyc_off[cy + 1], n = c1 - c0;
    api_buf_putc(b, '[');
    for (uint32_t i = 0; i < n; i++) {
        if (i) api_buf_putc(b, ',');
        uint32_t v = c->cyc[reversed ? c0 + (n - i) % n : c0 + i];
        api_buf_u64(b, map ? map[v] : v);
    }
    api_buf_putc(b, ']');
}

/* "result": {"V": [...], "cells": [...], "faces": [±(f+1), ...], "FV": [...], "FE": [...],
 * "holes": {...}, "volume": v}: row i of FV, FE and holes is result face i (faces[i]), oriented
 * out of the result (a face listed -(f+1) has its cycles reversed and its edges' signs
 * flipped).  Nothing in it refers to a key the fields leave out: "cells" (the complex's cells)
 * come with CF or CV, "faces" (the complex's faces) with FV or FE, "FE" with EV; without V
 * named, a "V" of its own (the vertices its cycles use, in the complex's order) is what its
 * "FV" and "holes" index. */
static void put_result(api_buf *b, const lar3 *c, const bool3_result *r, unsigned fl)
{
    uint32_t *map = NULL;
    const char *sep = "";
    put_key(b, "result");
    api_buf_putc(b, '{');
    if (!(fl & API_F3_V)) { /* its own V */
        map = calloc(c->nv + 1, sizeof *map);
        if (!map) {
            b->failed = 1; /* out of memory: api_lar3_write says so */
            return;
        }
        for (size_t i = 0; i < r->nfaces; i++) {
            uint32_t f = (uint32_t)(r->faces[i] > 0 ? r->faces[i] : -r->faces[i]) - 1;
            for (uint32_t k = c->fc_off[f]; k < c->fc_off[f + 1]; k++)
                for (uint32_t j = c->cyc_off[c->fc[k]]; j < c->cyc_off[c->fc[k] + 1]; j++)
                    map[c->cyc[j]] = 1;
        }
        api_buf_own_vertices(b, c->V, c->nv, 3, map);
        sep = ",";
    }
    if (fl & (API_F3_CF | API_F3_CV)) {
        api_buf_puts(b, sep);
        api_buf_puts(b, "\"cells\":");
        api_buf_u32_list(b, r->cells, r->ncells);
        sep = ",";
    }
    if (fl & (API_F3_FV | API_F3_FE)) {
        api_buf_puts(b, sep);
        api_buf_puts(b, "\"faces\":");
        api_buf_i32_list(b, r->faces, r->nfaces);
        sep = ",";
    }
    api_buf_puts(b, sep);
    api_buf_puts(b, "\"FV\":[");
    for (size_t i = 0; i < r->nfaces; i++) {
        uint32_t f = (uint32_t)(r->faces[i] > 0 ? r->faces[i] : -r->faces[i]) - 1;
        if (i) api_buf_putc(b, ',');
        put_cycle_dir(b, c, c->fc[c->fc_off[f]], r->faces[i] < 0, map);
    }
    api_buf_putc(b, ']');
    if (fl & API_F3_EV) {
        api_buf_puts(b, ",\"FE\":[");
        for (size_t i = 0; i < r->nfaces; i++) {
            uint32_t f = (uint32_t)(r->faces[i] > 0 ? r->faces[i] : -r->faces[i]) - 1;
            api_buf_puts(b, i ? ",[" : "[");
            for (uint32_t j = c->fe_off[f]; j < c->fe_off[f + 1]; j++) {
                if (j > c->fe_off[f]) api_buf_putc(b, ',');
                api_buf_i64(b, r->faces[i] > 0 ? c->fe[j] : -(int64_t)c->fe[j]);
            }
            api_buf_putc(b, ']');
        }
        api_buf_putc(b, ']');
    }
    api_buf_puts(b, ",\"holes\":{");
    int first = 1;
    for (size_t i = 0; i < r->nfaces; i++) {
        uint32_t f = (uint32_t)(r->faces[i] > 0 ? r->faces[i] : -r->faces[i]) - 1;
        if (c->fc_off[f + 1] - c->fc_off[f] < 2) continue;
        api_buf_key_open(b, &first, i);
        for (uint32_t k = c->fc_off[f] + 1; k < c->fc_off[f + 1]; k++) {
            if (k > c->fc_off[f] + 1) api_buf_putc(b, ',');
            put_cycle_dir(b, c, c->fc[k], r->faces[i] < 0, map);
        }
        api_buf_putc(b, ']');
    }
    api_buf_puts(b, "},\"volume\":");
    api_buf_double(b, r->volume);
    api_buf_putc(b, '}');
    free(map);
}

int api_lar3_write(api_buf *b, const lar3 *c, const api_lar3_fmt *fmt, api_error *err)
{
    unsigned fl = fmt->fields;
    int rc = check_complex(c, fl, err);
    if (rc != API_OK) return rc;
    b->nsections = (unsigned)__builtin_popcount(fl) + 2;
    api_buf_puts(b, "{\"dim\":3");
    if (fl & API_F3_V) {
        put_key(b, "V");
        api_buf_rows(b, c->V, NULL, c->nv, 3);
    }
    if (fl & API_F3_EV) {
        put_key(b, "EV");
        api_buf_rows(b, NULL, c->EV, c->ne, 2);
    }
    if (fl & API_F3_FV) {
        put_key(b, "FV");
        api_buf_putc(b, '[');
        for (size_t f = 0; f < c->nf; f++) {
            if (api_buf_tick(b, f, c->nf)) break; /* failed, or canceled */
            if (f) api_buf_putc(b, ',');
            put_cycle(b, c, c->fc[c->fc_off[f]]);
        }
        api_buf_putc(b, ']');
    }
    if (fl & API_F3_FE) {
        put_key(b, "FE");
        put_signed_rows(b, c->fe_off, c->fe, c->nf);
    }
    if (fl & API_F3_HOLES) {
        int first = 1;
        put_key(b, "holes");
        api_buf_putc(b, '{');
        for (size_t f = 0; f < c->nf; f++) {
            if (c->fc_off[f + 1] - c->fc_off[f] < 2) continue;
            api_buf_key_open(b, &first, f);
            for (size_t k = c->fc_off[f] + 1; k < c->fc_off[f + 1]; k++) {
                if (k > c->fc_off[f] + 1) api_buf_putc(b, ',');
                put_cycle(b, c, c->fc[k]);
            }
            api_buf_putc(b, ']');
        }
        api_buf_putc(b, '}');
    }
    if (fl & API_F3_CF) {
        put_key(b, "CF");
        put_signed_rows(b, c->cf_off, c->cf, c->nc);
    }
    if (fl & API_F3_CV) {
        put_key(b, "CV");
        api_buf_putc(b, '[');
        for (size_t k = 0; k < c->nc; k++) {
            if (k) api_buf_putc(b, ',');
            api_buf_u32_list(b, c->cv + c->cv_off[k], c->cv_off[k + 1] - c->cv_off[k]);
        }
        api_buf_putc(b, ']');
    }
    if (fl & API_F3_EXTERIOR) {
        put_key(b, "exterior");
        api_buf_i32_list(b, c->ext, c->next);
    }
    if (fl & API_F3_OPERATORS) {
        put_key(b, "operators");
        rc = put_operators(b, c, err);
        if (rc != API_OK) return rc;
    }
    if (fmt->layers) {
        put_key(b, "layers");
        api_buf_puts(b, fmt->layers);
    }
    if (fmt->membership && (fl & API_F3_MEMBERSHIP)) put_membership3(b, c, fmt->membership);
    if (fmt->result && (fl & API_F3_RESULT)) put_result(b, c, fmt->result, fl);
    if (fl & API_F3_STATS) {
        put_key(b, "stats");
        put_stats(b, c, fmt);
    }
    api_buf_putc(b, '}');
    if (b->failed) return api_fail(err, API_ENOMEM, "out of memory while writing the result");
    return API_OK;
}

/* ---- arrays out (the library) ---------------------------------------------------------------- */

/* The absolute face of result face i. */
static uint32_t res_face(const bool3_result *r, size_t i)
{
    return (uint32_t)(r->faces[i] > 0 ? r->faces[i] : -r->faces[i]) - 1;
}

/* Rows of signed lists (FE, CF) with their offsets as they lie. */
static void signed_rows(api_arrays *out, int *bad, const char *name, const uint32_t *off,
                        const int32_t *a, size_t n)
{
    static const uint32_t zero = 0;
    char nm[64];
    snprintf(nm, sizeof nm, "%s.indptr", name);
    api_arrays_put(out, bad, nm, API_A_U32, n + 1, 1, n ? off : &zero, 0);
    snprintf(nm, sizeof nm, "%s.indices", name);
    api_arrays_put(out, bad, nm, API_A_I32, n ? off[n] : 0, 1, a, 0);
}

/* "holes": the faces i < n with more than one cycle (face fof[i]; fof NULL: face i), each
 * cycle after the first (reversed with rev[i], through map) as a row, and "name.face" the row
 * i of each. */
static void holes_rows(api_arrays *out, int *bad, const char *name, const lar3 *c,
                       const uint32_t *fof, const uint8_t *rev, size_t n, const uint32_t *map)
{
#define FOF(i) (fof ? fof[i] : (uint32_t)(i))
    size_t nh = 0;
    char nm[64];
    for (size_t i = 0; i < n; i++) nh += c->fc_off[FOF(i) + 1] - c->fc_off[FOF(i)] - 1;
    uint32_t *face = *bad ? NULL : malloc((nh + 1) * sizeof *face);
    uint32_t *cyc = face ? malloc((nh + 1) * sizeof *cyc) : NULL;
    uint8_t *r = cyc && rev ? malloc(nh + 1) : NULL;
    *bad = *bad || !face || !cyc || (rev && !r);
    size_t w = 0;
    for (size_t i = 0; !*bad && i < n; i++)
        for (uint32_t k = c->fc_off[FOF(i)] + 1; k < c->fc_off[FOF(i) + 1]; k++) {
            face[w] = (uint32_t)i;
            if (r) r[w] = rev[i];
            cyc[w++] = c->fc[k];
        }
    snprintf(nm, sizeof nm, "%s.face", name);
    if (*bad) free(cyc), cyc = NULL;
    api_arrays_put(out, bad, nm, API_A_U32, nh, 1, face, 1);
    *bad = *bad || api_arrays_cycles(out, name, c->cyc_off, c->cyc, cyc, r, nh, map);
    free(cyc);
    free(r);
#undef FOF
}

/* "result", as put_result writes it. */
static void result_arrays(api_arrays *out, int *bad, const lar3 *c, const bool3_result *r,
                          unsigned fl)
{
    uint32_t *map = NULL, *fof = malloc((r->nfaces + 1) * sizeof *fof), *outer = NULL;
    uint8_t *rev = malloc(r->nfaces + 1);
    outer = malloc((r->nfaces + 1) * sizeof *outer);
    *bad = *bad || !fof || !rev || !outer;
    for (size_t i = 0; !*bad && i < r->nfaces; i++) {
        fof[i] = res_face(r, i);
        rev[i] = r->faces[i] < 0;
        outer[i] = c->fc[c->fc_off[fof[i]]];
    }
    if (!*bad && !(fl & API_F3_V)) { /* its own V */
        map = calloc(c->nv + 1, sizeof *map);
        *bad = !map;
        for (size_t i = 0; !*bad && i < r->nfaces; i++)
            for (uint32_t k = c->fc_off[fof[i]]; k < c->fc_off[fof[i] + 1]; k++)
                for (uint32_t j = c->cyc_off[c->fc[k]]; j < c->cyc_off[c->fc[k] + 1]; j++)
                    map[c->cyc[j]] = 1;
        *bad = *bad || api_arrays_own_vertices(out, "result.V", c->V, c->nv, 3, map);
    }
    if (fl & (API_F3_CF | API_F3_CV))
        api_arrays_put(out, bad, "result.cells", API_A_U32, r->ncells, 1, r->cells, 0);
    if (fl & (API_F3_FV | API_F3_FE))
        api_arrays_put(out, bad, "result.faces", API_A_I32, r->nfaces, 1, r->faces, 0);
    *bad =
        *bad || api_arrays_cycles(out, "result.FV", c->cyc_off, c->cyc, outer, rev, r->nfaces, map);
    if (!*bad && (fl & API_F3_EV)) {
        size_t total = 0, w = 0;
        for (size_t i = 0; i < r->nfaces; i++) total += c->fe_off[fof[i] + 1] - c->fe_off[fof[i]];
        uint32_t *ptr = malloc((r->nfaces + 1) * sizeof *ptr);
        int32_t *idx = malloc((total + 1) * sizeof *idx);
        for (size_t i = 0; ptr && idx && i < r->nfaces; i++) {
            ptr[i] = (uint32_t)w;
            for (uint32_t j = c->fe_off[fof[i]]; j < c->fe_off[fof[i] + 1]; j++)
                idx[w++] = r->faces[i] > 0 ? c->fe[j] : -c->fe[j];
        }
        if (ptr) ptr[r->nfaces] = (uint32_t)w;
        *bad = !ptr || !idx;
        api_arrays_put(out, bad, "result.FE.indptr", API_A_U32, r->nfaces + 1, 1, ptr, 1);
        api_arrays_put(out, bad, "result.FE.indices", API_A_I32, w, 1, idx, 1);
    }
    holes_rows(out, bad, "result.holes", c, fof, rev, r->nfaces, map);
    api_arrays_f64(out, bad, "result.volume", r->volume);
    free(map);
    free(fof);
    free(rev);
    free(outer);
}

int api_lar3_arrays(api_arrays *out, const lar3 *c, const api_lar3_fmt *fmt, api_error *err)
{
    unsigned fl = fmt->fields;
    int rc = check_complex(c, fl, err), bad = 0;
    if (rc != API_OK) return rc;
    uint32_t *outer = malloc((c->nf + 1) * sizeof *outer); /* each face's first cycle */
    bad = !outer;
    for (size_t f = 0; !bad && f < c->nf; f++) outer[f] = c->fc[c->fc_off[f]];
    if (fl & API_F3_V) api_arrays_put(out, &bad, "V", API_A_F64, c->nv, 3, c->V, 0);
    if (fl & API_F3_EV) api_arrays_put(out, &bad, "EV", API_A_U32, c->ne, 2, c->EV, 0);
    if (!bad && (fl & API_F3_FV))
        bad = api_arrays_cycles(out, "FV", c->cyc_off, c->cyc, outer, NULL, c->nf, NULL);
    if (fl & API_F3_FE) signed_rows(out, &bad, "FE", c->fe_off, c->fe, c->nf);
    if (fl & API_F3_HOLES) holes_rows(out, &bad, "holes", c, NULL, NULL, c->nf, NULL);
    if (fl & API_F3_CF) signed_rows(out, &bad, "CF", c->cf_off, c->cf, c->nc);
    if (fl & API_F3_CV) {
        static const uint32_t zero = 0;
        api_arrays_put(out, &bad, "CV.indptr", API_A_U32, c->nc + 1, 1, c->nc ? c->cv_off : &zero,
                       0);
        api_arrays_put(out, &bad, "CV.indices", API_A_U32, c->nc ? c->cv_off[c->nc] : 0, 1, c->cv,
                       0);
    }
    if (fl & API_F3_EXTERIOR)
        api_arrays_put(out, &bad, "exterior", API_A_I32, c->next, 1, c->ext, 0);
    free(outer);
    if (!bad && (fl & API_F3_OPERATORS)) {
        static const char *const name[3] = {"operators.d1", "operators.d2", "operators.d3"};
        api_csr m[3] = {0};
        rc = lar3_operators(c, m, err);
        for (int i = 0; i < 3; i++)
            if (rc == API_OK && !bad)
                bad = api_arrays_csr(out, name[i], &m[i]);
            else
                api_csr_free(&m[i]);
        if (rc != API_OK) return rc;
    }
    if (!bad && fmt->membership && (fl & API_F3_MEMBERSHIP))
        bad = api_arrays_membership(out, c->nc, c->nsolids, fmt->membership->off,
                                    fmt->membership->idx, fmt->membership->wind);
    if (fmt->result && (fl & API_F3_RESULT)) result_arrays(out, &bad, c, fmt->result, fl);
    if (bad) return api_fail(err, API_ENOMEM, "out of memory");
    /* the JSON of what is not an array: dim and the stats */
    api_buf b = {0};
    api_buf_puts(&b, "{\"dim\":3");
    if (fl & API_F3_STATS) {
        put_key(&b, "stats");
        put_stats(&b, c, fmt);
    }
    api_buf_putc(&b, '}');
    if (b.failed) {
        api_buf_free(&b);
        return api_fail(err, API_ENOMEM, "out of memory");
    }
    api_arrays_json(out, 3, b.p);
    return API_OK;
}
