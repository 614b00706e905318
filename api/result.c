/* result.c — the one reader of results (LAR JSON) for every renderer: api_result_read()
 * (api/api_int.h) serves the SVG and GeoJSON of 2D results (api/render.c) and the OBJ of 3D
 * results (api/render_obj.c).
 *
 * The result is read with jansson into a flat model, every index checked on the way, so the
 * writers never look at JSON again and never index out of bounds:
 *
 *     V:          dim coordinates per vertex, all finite
 *     face_ring:  f -> [face_ring[f], face_ring[f+1])   rings of face f: FV[f], then holes."f"
 *     ring_off:   r -> [ring_off[r], ring_off[r+1])     positions in idx
 *     idx:        vertex indices, every one < nv
 *     cell_off:   c -> [cell_off[c], cell_off[c+1])     positions in cf (3D: signed faces ±(f+1))
 *
 * What the two dimensions read differs where their results and their renderers do (api/render.h
 * says what each renderer requires, and the messages name the JSON path of what is wrong):
 *   2D: "EV" (optional); "holes" required; the faces are the bounded rows of FV (with
 *       exterior_last the exterior cycles after them are left out: bounded_rows()), each of 3 or
 *       more vertices; a Boolean's "result" ({"FV", "holes", "cells", "area"}: its polygons'
 *       rings follow the faces' in the ring table) and its "membership" (CSR, one row per face).
 *   3D: "CF" required; "holes" optional; every row of FV is a face; a Boolean's "result".faces
 *       (the signed faces of the result's boundary).  "EV" and "membership" are not read.
 * The reading runs in stages (read_members, read_vertices, read_edges, count_faces, count_holes,
 * count_cells, count_result_2d, then fill_tables): each checks one part, in the order the
 * messages have always come in, and the counting ones add up what the tables will hold, so that
 * fill_tables() allocates each table once and copies the checked rows without checking again.
 * The jansson tree costs about ten times the result's own size while it is read (api/larjson.c
 * says why results are not written that way); it is freed before api_result_read() returns.
 *
 * Threads: reentrant, no globals.  Ownership: the text is borrowed; the model's arrays are its
 * own, freed by api_result_free().
 */
#include "api/api_int.h"

#include <ctype.h>
#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void api_result_free(api_result *m)
{
    free(m->V);
    free(m->ev);
    free(m->face_ring);
    free(m->ring_off);
    free(m->idx);
    free(m->cell_off);
    free(m->cf);
    free(m->res_faces);
    free(m->poly_ring);
    free(m->selected);
    free(m->mem_off);
    free(m->mem);
    json_decref(m->root);
    *m = (api_result){0};
}

/* Checks that row is an array of at least minlen vertex indices < nv, named by what printf'd
 * with a (and b unless b == SIZE_MAX), and copies them to out (may be NULL). */
static int result_cycle(const json_t *row, size_t nv, size_t minlen, uint32_t *out, api_error *err,
                        const char *what, size_t a, size_t b)
{
    size_t n = json_array_size(row);
    char path[96];
    if (b == SIZE_MAX)
        snprintf(path, sizeof path, what, a);
    else
        snprintf(path, sizeof path, what, a, b);
    if (!json_is_array(row) || n < minlen) {
        if (minlen <= 1)
            return api_fail(err, API_EINVALID, "%s: expected an array of vertex indices", path);
        return api_fail(err, API_EINVALID, "%s: expected an array of at least %zu vertex indices",
                        path, minlen);
    }
    for (size_t i = 0; i < n; i++) {
        const json_t *v = json_array_get(row, i);
        json_int_t k = json_is_integer(v) ? json_integer_value(v) : -1;
        if (k < 0 || (uint64_t)k >= nv)
            return api_fail(err, API_EINVALID, "%s[%zu]: expected a vertex index < %zu", path, i,
                            nv);
        if (out) out[i] = (uint32_t)k;
    }
    return API_OK;
}

/* A signed face +(f+1) or -(f+1) with f < nf, into *out; 0 when x is not one. */
static int signed_face(const json_t *x, size_t nf, int32_t *out)
{
    json_int_t k = json_is_integer(x) ? json_integer_value(x) : 0;
    if (k == 0 || k < -(json_int_t)nf || k > (json_int_t)nf) return 0;
    *out = (int32_t)k;
    return 1;
}

/* Twice the signed area of the cycle row (JSON, checked) of the 2D vertices xy. */
static double json_cycle_area2(const json_t *row, const double *xy)
{
    size_t n = json_array_size(row);
    double s = 0, ox, oy;
    if (n < 3) return 0;
    ox = xy[2 * json_integer_value(json_array_get(row, 0))];
    oy = xy[2 * json_integer_value(json_array_get(row, 0)) + 1];
    for (size_t i = 0; i < n; i++) {
        size_t a = (size_t)json_integer_value(json_array_get(row, i));
        size_t b = (size_t)json_integer_value(json_array_get(row, (i + 1) % n));
        s += (xy[2 * a] - ox) * (xy[2 * b + 1] - oy) - (xy[2 * b] - ox) * (xy[2 * a + 1] - oy);
    }
    return s;
}

/* How many rows of a 2D result's FV are bounded faces (see render.h): the rest are
 * exterior_last rows. */
static size_t bounded_rows(const json_t *root, const json_t *FV, const double *xy)
{
    size_t rows = json_array_size(FV), k;
    const json_t *F = json_object_get(json_object_get(root, "stats"), "F");
    const json_t *ext = json_object_get(root, "exterior");
    if (json_is_integer(F) && json_integer_value(F) >= 0 && (uint64_t)json_integer_value(F) <= rows)
        return (size_t)json_integer_value(F);
    k = json_array_size(ext);
    if (json_is_array(ext) && k > 0 && k <= rows) {
        size_t i = 0;
        while (i < k && json_equal(json_array_get(ext, i), json_array_get(FV, rows - k + i))) i++;
        if (i == k) return rows - k;
        return rows;
    }
    while (rows > 0 && json_cycle_area2(json_array_get(FV, rows - 1), xy) <= 0) rows--;
    return rows;
}

int api_face_key(const char *key, size_t nf, size_t *out)
{
    size_t v = 0, n = strlen(key);
    if (n == 0 || n > 19 || (n > 1 && key[0] == '0')) return 0;
    for (size_t i = 0; i < n; i++) {
        if (!isdigit((unsigned char)key[i])) return 0;
        v = v * 10 + (size_t)(key[i] - '0');
    }
    *out = v;
    return v < nf;
}

/* Parses text and checks that it is an object with "dim" equal to dim (why completes the
 * message "dim: expected D (why)"); *out is the caller's (json_decref). */
static int result_load(const char *text, size_t len, int dim, const char *why, json_t **out,
                       api_error *err)
{
    json_error_t je;
    json_t *root;
    const json_t *d;
    *out = NULL;
    if (!text || len == 0) return api_fail(err, API_EINVALID, "result: empty");
    root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        if (json_error_code(&je) == json_error_out_of_memory)
            return api_fail(err, API_ENOMEM, "out of memory reading the result");
        return api_fail(err, API_EINVALID, "result: malformed JSON at line %d, column %d: %s",
                        je.line, je.column, je.text);
    }
    int rc = API_OK;
    d = json_object_get(root, "dim");
    if (!json_is_object(root))
        rc = api_fail(err, API_EINVALID, "result: expected a JSON object (LAR JSON)");
    else if (!d)
        rc = api_fail(err, API_EINVALID, "dim: required (not a LAR JSON result)");
    else if (json_is_integer(d) && json_integer_value(d) != dim)
        rc = api_fail(err, API_EINVALID, "dim: expected %d (%s), got %lld", dim, why,
                      (long long)json_integer_value(d));
    else if (!json_is_integer(d))
        rc = api_fail(err, API_EINVALID, "dim: expected %d (%s)", dim, why);
    if (rc != API_OK) {
        json_decref(root);
        return rc;
    }
    *out = root;
    return API_OK;
}

/* A 2D Boolean's "membership" (optional), compressed sparse rows: one row per face, the
 * inputs each face lies in, into m->mem_off and m->mem. */
static int read_membership(const json_t *root, api_result *m, api_error *err)
{
    const json_t *mem = json_object_get(root, "membership");
    if (!mem) return API_OK;
    const json_t *shape = json_object_get(mem, "shape");
    const json_t *ip = json_object_get(mem, "indptr"), *ix = json_object_get(mem, "indices");
    size_t nnz = json_array_size(ix);
    if (!json_is_object(mem) || !json_is_array(ip) || !json_is_array(ix) ||
        json_array_size(shape) != 2 ||
        (size_t)json_integer_value(json_array_get(shape, 0)) != m->nf ||
        json_integer_value(json_array_get(shape, 1)) < 0 || json_array_size(ip) != m->nf + 1)
        return api_fail(err, API_EINVALID,
                        "membership: expected {\"shape\": [%zu, inputs], \"indptr\": [%zu "
                        "offsets], \"indices\": [...]}",
                        m->nf, m->nf + 1);
    m->ninputs = (size_t)json_integer_value(json_array_get(shape, 1));
    m->mem_off = malloc((m->nf + 1) * sizeof *m->mem_off);
    m->mem = malloc((nnz + 1) * sizeof *m->mem);
    if (!m->mem_off || !m->mem) return API_ENOMEM;
    for (size_t f = 0; f <= m->nf; f++) {
        const json_t *x = json_array_get(ip, f);
        json_int_t v = json_integer_value(x);
        if (!json_is_integer(x) || v < 0 || (size_t)v > nnz ||
            (f > 0 && (size_t)v < m->mem_off[f - 1]) || (f == 0 && v != 0) ||
            (f == m->nf && (size_t)v != nnz))
            return api_fail(err, API_EINVALID,
                            "membership.indptr[%zu]: expected offsets from 0 to %zu, "
                            "non-decreasing",
                            f, nnz);
        m->mem_off[f] = (size_t)v;
    }
    for (size_t k = 0; k < nnz; k++) {
        const json_t *x = json_array_get(ix, k);
        json_int_t v = json_integer_value(x);
        if (!json_is_integer(x) || v < 0 || (size_t)v >= m->ninputs)
            return api_fail(err, API_EINVALID,
                            "membership.indices[%zu]: expected an input index < %zu", k,
                            m->ninputs);
        m->mem[k] = (uint32_t)v;
    }
    return API_OK;
}

/* The cycle row (checked) as the next ring of m: ring *nr from position *w of idx; both
 * advanced. */
static void put_ring(api_result *m, const json_t *row, size_t *nr, size_t *w)
{
    size_t n = json_array_size(row);
    m->ring_off[(*nr)++] = *w;
    for (size_t i = 0; i < n; i++)
        m->idx[*w + i] = (uint32_t)json_integer_value(json_array_get(row, i));
    *w += n;
}

/* The array of holes (an object of face keys to arrays of cycles) of face f, or NULL. */
static const json_t *face_holes(const json_t *holes, size_t f)
{
    char k[24];
    snprintf(k, sizeof k, "%zu", f);
    return json_object_get(holes, k);
}

/* A 2D Boolean's "result" (checked) after the faces' rings (nr, w: the next ring and
 * position): its polygons' rings, the faces it selects ("cells"), its area; then the root's
 * "membership" (read_membership()). */
static int read_result_2d(const json_t *root, const json_t *res, api_result *m, size_t *nr,
                          size_t *w, api_error *err)
{
    const json_t *rFV = json_object_get(res, "FV"), *rholes = json_object_get(res, "holes");
    m->has_result = 1;
    m->poly_ring = malloc((m->npoly + 1) * sizeof *m->poly_ring);
    m->selected = calloc(m->nf + 1, 1);
    if (!m->poly_ring || !m->selected) return API_ENOMEM;
    for (size_t q = 0; q < m->npoly; q++) {
        const json_t *hs = face_holes(rholes, q);
        m->poly_ring[q] = *nr;
        put_ring(m, json_array_get(rFV, q), nr, w);
        for (size_t h = 0; h < json_array_size(hs); h++) put_ring(m, json_array_get(hs, h), nr, w);
    }
    m->poly_ring[m->npoly] = *nr;
    const json_t *cells = json_object_get(res, "cells"), *area = json_object_get(res, "area");
    m->res_area = json_is_number(area) ? json_number_value(area) : 0;
    for (size_t i = 0; i < json_array_size(cells); i++) {
        const json_t *x = json_array_get(cells, i);
        if (!json_is_integer(x) || json_integer_value(x) < 0 ||
            (uint64_t)json_integer_value(x) >= m->nf)
            return api_fail(err, API_EINVALID, "result.cells[%zu]: expected a face index < %zu", i,
                            m->nf);
        m->selected[json_integer_value(x)] = 1;
    }
    return read_membership(root, m, err);
}

/* A 3D result's cells (CF, checked) and a Boolean's "result".faces. */
static int read_cells_3d(const json_t *CF, const json_t *res, api_result *m, api_error *err)
{
    size_t w = 0;
    for (size_t c = 0; c < m->nc; c++) {
        const json_t *row = json_array_get(CF, c);
        m->cell_off[c] = w;
        for (size_t i = 0; i < json_array_size(row); i++)
            signed_face(json_array_get(row, i), m->nf, m->cf + w++);
    }
    m->cell_off[m->nc] = w;
    if (!res) return API_OK;
    const json_t *rf = json_object_get(res, "faces");
    if (!json_is_array(rf))
        return api_fail(err, API_EINVALID, "result.faces: expected an array of signed faces");
    m->has_result = 1;
    m->nres_faces = json_array_size(rf);
    m->res_faces = malloc(m->nres_faces * sizeof *m->res_faces + 1);
    if (!m->res_faces) return API_ENOMEM;
    for (size_t i = 0; i < m->nres_faces; i++)
        if (!signed_face(json_array_get(rf, i), m->nf, m->res_faces + i))
            return api_fail(err, API_EINVALID,
                            "result.faces[%zu]: expected a signed face +(f+1) or -(f+1), "
                            "0 <= f < %zu",
                            i, m->nf);
    return API_OK;
}

/* ---- the reader, in stages ------------------------------------------------------------------
 * api_result_read() runs them in order; each checks one part of the result (in the order the
 * messages have always come in, so the first thing wrong is the one named), and the counting
 * stages add up what the tables will hold, so fill_tables() allocates each table once and
 * copies without checking again.  A stage returns API_OK, API_EINVALID with the message set, or
 * API_ENOMEM bare (api_result_read() says "out of memory reading the result"). */

typedef struct rread {
    json_t *root; /* the parsed result (api_result_read() keeps or frees it) */
    const json_t *V, *FV, *EV, *holes, *CF, *res;
    int dim;
    size_t minlen; /* of a face's outer cycle: a bounded 2D face has 3 or more, a 3D face 1 */
    size_t nidx;   /* counted: the entries of every ring (faces', holes', result polygons') */
    size_t nres;   /* counted: the result polygons' rings (2D) */
    size_t ncf;    /* counted: the entries of CF (3D) */
    api_result *m;
    api_error *err;
} rread;

/* The members read; V, FV and (3D) CF are required. */
static int read_members(rread *r)
{
    r->V = json_object_get(r->root, "V");
    r->FV = json_object_get(r->root, "FV");
    if (r->dim == 2) r->EV = json_object_get(r->root, "EV");
    if (r->dim == 3) r->CF = json_object_get(r->root, "CF");
    r->holes = json_object_get(r->root, "holes");
    r->res = json_object_get(r->root, "result");
    if (r->V && r->FV && (r->dim != 3 || r->CF)) return API_OK;
    return api_fail(r->err, API_EINVALID,
                    "%s: required (the result was made with \"fields\" leaving it out: ask for "
                    "%s)",
                    !r->V    ? "V"
                    : !r->FV ? "FV"
                             : "CF",
                    r->dim == 2 ? "\"V\", \"FV\" and \"holes\""
                                : "\"V\", \"FV\", \"holes\" and \"CF\"");
}

/* V: at most 2^32 vertices of dim finite numbers each, into m->V. */
static int read_vertices(rread *r)
{
    api_result *m = r->m;
    size_t dim = (size_t)r->dim;
    if (!json_is_array(r->V))
        return api_fail(r->err, API_EINVALID, "V: expected an array of %s",
                        dim == 2 ? "[x, y]" : "[x, y, z]");
    m->nv = json_array_size(r->V);
    if (m->nv > UINT32_MAX) return api_fail(r->err, API_EINVALID, "V: more than 2^32 vertices");
    m->V = malloc(dim * m->nv * sizeof *m->V + 1);
    if (!m->V) return API_ENOMEM;
    for (size_t i = 0; i < m->nv; i++) {
        const json_t *p = json_array_get(r->V, i);
        int ok = json_array_size(p) == dim;
        for (size_t a = 0; ok && a < dim; a++) {
            const json_t *x = json_array_get(p, a);
            ok = json_is_number(x) && isfinite(json_number_value(x));
            if (ok) m->V[dim * i + a] = json_number_value(x);
        }
        if (!ok)
            return api_fail(r->err, API_EINVALID, "V[%zu]: expected %d finite numbers", i, r->dim);
    }
    return API_OK;
}

/* EV (2D, optional; null is absent): pairs of vertex indices, into m->ev. */
static int read_edges(rread *r)
{
    api_result *m = r->m;
    if (!r->EV || json_is_null(r->EV)) return API_OK;
    if (!json_is_array(r->EV))
        return api_fail(r->err, API_EINVALID, "EV: expected an array of [v0, v1]");
    m->ne = json_array_size(r->EV);
    m->ev = malloc(2 * m->ne * sizeof *m->ev + 1);
    if (!m->ev) return API_ENOMEM;
    for (size_t e = 0; e < m->ne; e++) {
        const json_t *row = json_array_get(r->EV, e);
        if (json_array_size(row) != 2)
            return api_fail(r->err, API_EINVALID, "EV[%zu]: expected 2 vertex indices", e);
        int rc = result_cycle(row, m->nv, 2, m->ev + 2 * e, r->err, "EV[%zu]", e, SIZE_MAX);
        if (rc != API_OK) return rc;
    }
    return API_OK;
}

/* FV: every row a cycle of vertex indices; the faces (2D: the bounded rows, bounded_rows())
 * of minlen or more, counted into m->nf, m->nrings and r->nidx. */
static int count_faces(rread *r)
{
    api_result *m = r->m;
    size_t rows;
    int rc;
    if (!json_is_array(r->FV))
        return api_fail(r->err, API_EINVALID, "FV: expected an array of cycles");
    rows = json_array_size(r->FV);
    for (size_t f = 0; f < rows; f++) {
        rc = result_cycle(json_array_get(r->FV, f), m->nv, 1, NULL, r->err, "FV[%zu]", f, SIZE_MAX);
        if (rc != API_OK) return rc;
    }
    m->nf = r->dim == 2 ? bounded_rows(r->root, r->FV, m->V) : rows;
    m->nrings = m->nf;
    for (size_t f = 0; f < m->nf; f++) {
        const json_t *row = json_array_get(r->FV, f);
        if (r->minlen > 1) {
            rc = result_cycle(row, m->nv, r->minlen, NULL, r->err, "FV[%zu]", f, SIZE_MAX);
            if (rc != API_OK) return rc;
        }
        r->nidx += json_array_size(row);
    }
    return API_OK;
}

/* The cycles of the array val (holes of face, or of result polygon, f: what names them) of
 * minlen or more vertex indices, counted into *rings and r->nidx. */
static int count_rings(rread *r, const json_t *val, size_t minlen, const char *what, size_t f,
                       size_t *rings)
{
    for (size_t h = 0; h < json_array_size(val); h++) {
        const json_t *row = json_array_get(val, h);
        int rc = result_cycle(row, r->m->nv, minlen, NULL, r->err, what, f, h);
        if (rc != API_OK) return rc;
        r->nidx += json_array_size(row);
        (*rings)++;
    }
    return API_OK;
}

/* "holes": an object (or null, 3D) of face keys (api_face_key(), < nf) to arrays of cycles,
 * counted into m->nrings and r->nidx; required in 2D. */
static int count_holes(rread *r)
{
    api_result *m = r->m;
    const char *key;
    const json_t *val;
    if (r->holes && !json_is_null(r->holes)) {
        if (!json_is_object(r->holes))
            return api_fail(r->err, API_EINVALID,
                            "holes: expected an object {\"f\": [[v, ...], ...]}");
        json_object_foreach((json_t *)r->holes, key, val)
        {
            size_t f;
            if (!api_face_key(key, m->nf, &f))
                return api_fail(r->err, API_EINVALID, "holes.%.40s: not %s (there are %zu)", key,
                                r->dim == 2 ? "a bounded face" : "a face", m->nf);
            if (!json_is_array(val))
                return api_fail(r->err, API_EINVALID, "holes.%zu: expected an array of cycles", f);
            int rc = count_rings(r, val, 1, "holes.%zu[%zu]", f, &m->nrings);
            if (rc != API_OK) return rc;
        }
    }
    /* every key is well formed; without "holes" the faces would be drawn without their holes */
    if (r->dim == 2 && !r->holes)
        return api_fail(r->err, API_EINVALID,
                        "holes: required (the result was made with \"fields\" leaving it out: "
                        "ask for \"V\", \"FV\" and \"holes\"; the faces cannot be drawn without "
                        "their holes)");
    return API_OK;
}

/* CF (3D): rows of signed faces ±(f+1), f < nf, counted into m->nc and r->ncf. */
static int count_cells(rread *r)
{
    api_result *m = r->m;
    if (!json_is_array(r->CF))
        return api_fail(r->err, API_EINVALID, "CF: expected an array of rows of signed faces");
    m->nc = json_array_size(r->CF);
    for (size_t c = 0; c < m->nc; c++) {
        const json_t *row = json_array_get(r->CF, c);
        int32_t s;
        if (!json_is_array(row))
            return api_fail(r->err, API_EINVALID, "CF[%zu]: expected an array of signed faces", c);
        for (size_t i = 0; i < json_array_size(row); i++)
            if (!signed_face(json_array_get(row, i), m->nf, &s))
                return api_fail(r->err, API_EINVALID,
                                "CF[%zu][%zu]: expected a signed face +(f+1) or -(f+1), "
                                "0 <= f < %zu",
                                c, i, m->nf);
        r->ncf += json_array_size(row);
    }
    return API_OK;
}

/* A 2D Boolean's "result": its polygons' shells ("FV", 3 or more vertices each) and holes
 * (keys < npoly), counted into m->npoly, r->nres and r->nidx. */
static int count_result_2d(rread *r)
{
    api_result *m = r->m;
    const json_t *rFV = json_object_get(r->res, "FV"), *rholes = json_object_get(r->res, "holes");
    const char *key;
    const json_t *val;
    if (!json_is_object(r->res) || !json_is_array(rFV) || !json_is_object(rholes))
        return api_fail(r->err, API_EINVALID,
                        "result: expected an object with \"FV\" (the result polygons' shells) "
                        "and \"holes\"");
    m->npoly = json_array_size(rFV);
    for (size_t q = 0; q < m->npoly; q++) {
        const json_t *row = json_array_get(rFV, q);
        int rc = result_cycle(row, m->nv, 3, NULL, r->err, "result.FV[%zu]", q, SIZE_MAX);
        if (rc != API_OK) return rc;
        r->nidx += json_array_size(row);
        r->nres++;
    }
    json_object_foreach((json_t *)rholes, key, val)
    {
        size_t q;
        if (!api_face_key(key, m->npoly, &q) || !json_is_array(val))
            return api_fail(r->err, API_EINVALID,
                            "result.holes.%.40s: expected an array of rings of a result polygon "
                            "(there are %zu)",
                            key, m->npoly);
        int rc = count_rings(r, val, 3, "result.holes.%zu[%zu]", q, &r->nres);
        if (rc != API_OK) return rc;
    }
    return API_OK;
}

/* Everything checked and counted: the tables allocated and filled, the faces' rings (the outer
 * cycle, then the holes), a 2D Boolean's result polygons' rings after them, a 3D result's
 * cells. */
static int fill_tables(rread *r)
{
    api_result *m = r->m;
    size_t nr = 0, w = 0;
    m->nface_rings = m->nrings;
    m->nrings += r->nres;
    m->face_ring = malloc((m->nf + 1) * sizeof *m->face_ring);
    m->ring_off = malloc((m->nrings + 1) * sizeof *m->ring_off);
    m->idx = malloc(r->nidx * sizeof *m->idx + 1);
    if (!m->face_ring || !m->ring_off || !m->idx) return API_ENOMEM;
    if (r->dim == 3) {
        m->cell_off = malloc((m->nc + 1) * sizeof *m->cell_off);
        m->cf = malloc(r->ncf * sizeof *m->cf + 1);
        if (!m->cell_off || !m->cf) return API_ENOMEM;
    }
    for (size_t f = 0; f < m->nf; f++) {
        const json_t *hs = NULL;
        m->face_ring[f] = nr;
        put_ring(m, json_array_get(r->FV, f), &nr, &w);
        if (json_is_object(r->holes)) hs = face_holes(r->holes, f);
        for (size_t h = 0; h < json_array_size(hs); h++)
            put_ring(m, json_array_get(hs, h), &nr, &w);
    }
    m->face_ring[m->nf] = nr;
    if (r->dim == 2 && r->res) {
        int rc = read_result_2d(r->root, r->res, m, &nr, &w, r->err);
        if (rc != API_OK) return rc;
    }
    m->ring_off[nr] = w;
    if (nr != m->nrings || w != r->nidx) /* cannot happen: keys were checked canonical, < nf */
        return api_fail(r->err, API_EINTERNAL, "render: holes counted twice differently");
    if (r->dim == 3) return read_cells_3d(r->CF, r->res, m, r->err);
    return API_OK;
}

int api_result_read(const char *text, size_t len, int dim, const char *why, api_result *m,
                    api_error *err)
{
    rread r = {.dim = dim, .minlen = dim == 2 ? 3 : 1, .m = m, .err = err};
    int rc;
    *m = (api_result){0};
    m->dim = dim;
    rc = result_load(text, len, dim, why, &r.root, err);
    if (rc != API_OK) return rc;
    rc = read_members(&r);
    if (rc == API_OK) rc = read_vertices(&r);
    if (rc == API_OK) rc = read_edges(&r);
    if (rc == API_OK) rc = count_faces(&r);
    if (rc == API_OK) rc = count_holes(&r);
    if (rc == API_OK && dim == 3) rc = count_cells(&r);
    if (rc == API_OK && dim == 2 && r.res) rc = count_result_2d(&r);
    if (rc == API_OK) rc = fill_tables(&r);
    if (rc == API_OK) {
        if (dim == 2 && json_object_get(r.root, "layers"))
            m->root = r.root; /* the GeoJSON writer reads "layers" and "result".pieces there */
        else
            json_decref(r.root);
        return API_OK;
    }
    if (rc == API_ENOMEM) rc = api_fail(err, API_ENOMEM, "out of memory reading the result");
    json_decref(r.root);
    api_result_free(m);
    return rc;
}
