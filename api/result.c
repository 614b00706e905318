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

/* A 2D Boolean's "result" after the faces' rings (r, w: the next ring and position): its
 * polygons' rings, the faces it selects ("cells"), its area, and the root's "membership". */
static int read_result_2d(const json_t *root, const json_t *res, api_result *m, size_t *r,
                          size_t *w, api_error *err)
{
    const json_t *rFV = json_object_get(res, "FV"), *rholes = json_object_get(res, "holes");
    m->has_result = 1;
    m->poly_ring = malloc((m->npoly + 1) * sizeof *m->poly_ring);
    m->selected = calloc(m->nf + 1, 1);
    if (!m->poly_ring || !m->selected) return API_ENOMEM;
    for (size_t q = 0; q < m->npoly; q++) {
        const json_t *row = json_array_get(rFV, q), *hs;
        char k[24];
        m->poly_ring[q] = *r;
        m->ring_off[(*r)++] = *w;
        result_cycle(row, m->nv, 3, m->idx + *w, NULL, "result.FV[%zu]", q, SIZE_MAX);
        *w += json_array_size(row);
        snprintf(k, sizeof k, "%zu", q);
        hs = json_object_get(rholes, k);
        for (size_t h = 0; h < json_array_size(hs); h++) {
            row = json_array_get(hs, h);
            m->ring_off[(*r)++] = *w;
            result_cycle(row, m->nv, 3, m->idx + *w, NULL, "result.holes.%zu[%zu]", q, h);
            *w += json_array_size(row);
        }
    }
    m->poly_ring[m->npoly] = *r;
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
    /* the membership, compressed sparse rows: one row per face */
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

int api_result_read(const char *text, size_t len, int dim, const char *why, api_result *m,
                    api_error *err)
{
    json_t *root = NULL;
    const json_t *V, *FV, *EV = NULL, *holes, *CF = NULL, *res, *val;
    const char *key;
    size_t rows, nidx = 0, nres = 0, ncf = 0, r, w;
    size_t minlen = dim == 2 ? 3 : 1; /* of a face's outer cycle: a bounded face has 3 or more */
    int rc;
    *m = (api_result){0};
    m->dim = dim;
    rc = result_load(text, len, dim, why, &root, err);
    if (rc != API_OK) return rc;
    V = json_object_get(root, "V");
    FV = json_object_get(root, "FV");
    if (dim == 2) EV = json_object_get(root, "EV");
    if (dim == 3) CF = json_object_get(root, "CF");
    holes = json_object_get(root, "holes");
    if (!V || !FV || (dim == 3 && !CF)) {
        rc = api_fail(err, API_EINVALID,
                      "%s: required (the result was made with \"fields\" leaving it out: ask for "
                      "%s)",
                      !V    ? "V"
                      : !FV ? "FV"
                            : "CF",
                      dim == 2 ? "\"V\", \"FV\" and \"holes\""
                               : "\"V\", \"FV\", \"holes\" and \"CF\"");
        goto fail;
    }
    if (!json_is_array(V)) {
        rc = api_fail(err, API_EINVALID, "V: expected an array of %s",
                      dim == 2 ? "[x, y]" : "[x, y, z]");
        goto fail;
    }
    m->nv = json_array_size(V);
    if (m->nv > UINT32_MAX) {
        rc = api_fail(err, API_EINVALID, "V: more than 2^32 vertices");
        goto fail;
    }
    m->V = malloc((size_t)dim * m->nv * sizeof *m->V + 1);
    if (!m->V) goto nomem;
    for (size_t i = 0; i < m->nv; i++) {
        const json_t *p = json_array_get(V, i);
        int ok = json_array_size(p) == (size_t)dim;
        for (int a = 0; ok && a < dim; a++) {
            const json_t *x = json_array_get(p, (size_t)a);
            ok = json_is_number(x) && isfinite(json_number_value(x));
            if (ok) m->V[(size_t)dim * i + (size_t)a] = json_number_value(x);
        }
        if (!ok) {
            rc = api_fail(err, API_EINVALID, "V[%zu]: expected %d finite numbers", i, dim);
            goto fail;
        }
    }

    if (EV && !json_is_null(EV)) {
        if (!json_is_array(EV)) {
            rc = api_fail(err, API_EINVALID, "EV: expected an array of [v0, v1]");
            goto fail;
        }
        m->ne = json_array_size(EV);
        m->ev = malloc(2 * m->ne * sizeof *m->ev + 1);
        if (!m->ev) goto nomem;
        for (size_t e = 0; e < m->ne; e++) {
            const json_t *row = json_array_get(EV, e);
            if (json_array_size(row) != 2) {
                rc = api_fail(err, API_EINVALID, "EV[%zu]: expected 2 vertex indices", e);
                goto fail;
            }
            rc = result_cycle(row, m->nv, 2, m->ev + 2 * e, err, "EV[%zu]", e, SIZE_MAX);
            if (rc != API_OK) goto fail;
        }
    }

    if (!json_is_array(FV)) {
        rc = api_fail(err, API_EINVALID, "FV: expected an array of cycles");
        goto fail;
    }
    rows = json_array_size(FV);
    for (size_t f = 0; f < rows; f++) {
        rc = result_cycle(json_array_get(FV, f), m->nv, 1, NULL, err, "FV[%zu]", f, SIZE_MAX);
        if (rc != API_OK) goto fail;
    }
    m->nf = dim == 2 ? bounded_rows(root, FV, m->V) : rows;
    m->nrings = m->nf;
    for (size_t f = 0; f < m->nf; f++) {
        const json_t *row = json_array_get(FV, f);
        if (minlen > 1) {
            rc = result_cycle(row, m->nv, minlen, NULL, err, "FV[%zu]", f, SIZE_MAX);
            if (rc != API_OK) goto fail;
        }
        nidx += json_array_size(row);
    }
    if (holes && !json_is_null(holes)) {
        if (!json_is_object(holes)) {
            rc = api_fail(err, API_EINVALID, "holes: expected an object {\"f\": [[v, ...], ...]}");
            goto fail;
        }
        json_object_foreach((json_t *)holes, key, val)
        {
            size_t f;
            if (!api_face_key(key, m->nf, &f)) {
                rc = api_fail(err, API_EINVALID, "holes.%.40s: not %s (there are %zu)", key,
                              dim == 2 ? "a bounded face" : "a face", m->nf);
                goto fail;
            }
            if (!json_is_array(val)) {
                rc = api_fail(err, API_EINVALID, "holes.%zu: expected an array of cycles", f);
                goto fail;
            }
            for (size_t h = 0; h < json_array_size(val); h++) {
                const json_t *row = json_array_get(val, h);
                rc = result_cycle(row, m->nv, 1, NULL, err, "holes.%zu[%zu]", f, h);
                if (rc != API_OK) goto fail;
                nidx += json_array_size(row);
                m->nrings++;
            }
        }
    }

    /* every key is well formed; without "holes" the faces would be drawn without their holes */
    if (dim == 2 && !holes) {
        rc = api_fail(err, API_EINVALID,
                      "holes: required (the result was made with \"fields\" leaving it out: ask "
                      "for \"V\", \"FV\" and \"holes\"; the faces cannot be drawn without their "
                      "holes)");
        goto fail;
    }

    if (dim == 3) {
        if (!json_is_array(CF)) {
            rc = api_fail(err, API_EINVALID, "CF: expected an array of rows of signed faces");
            goto fail;
        }
        m->nc = json_array_size(CF);
        for (size_t c = 0; c < m->nc; c++) {
            const json_t *row = json_array_get(CF, c);
            int32_t s;
            if (!json_is_array(row)) {
                rc = api_fail(err, API_EINVALID, "CF[%zu]: expected an array of signed faces", c);
                goto fail;
            }
            for (size_t i = 0; i < json_array_size(row); i++) {
                if (!signed_face(json_array_get(row, i), m->nf, &s)) {
                    rc = api_fail(err, API_EINVALID,
                                  "CF[%zu][%zu]: expected a signed face +(f+1) or -(f+1), "
                                  "0 <= f < %zu",
                                  c, i, m->nf);
                    goto fail;
                }
            }
            ncf += json_array_size(row);
        }
    }

    /* a 2D Boolean's result: its polygons' rings after the faces' */
    res = json_object_get(root, "result");
    if (dim == 2 && res) {
        const json_t *rFV = json_object_get(res, "FV"), *rholes = json_object_get(res, "holes");
        if (!json_is_object(res) || !json_is_array(rFV) || !json_is_object(rholes)) {
            rc = api_fail(err, API_EINVALID,
                          "result: expected an object with \"FV\" (the result polygons' shells) "
                          "and \"holes\"");
            goto fail;
        }
        m->npoly = json_array_size(rFV);
        for (size_t q = 0; q < m->npoly; q++) {
            const json_t *row = json_array_get(rFV, q);
            rc = result_cycle(row, m->nv, 3, NULL, err, "result.FV[%zu]", q, SIZE_MAX);
            if (rc != API_OK) goto fail;
            nidx += json_array_size(row);
            nres++;
        }
        json_object_foreach((json_t *)rholes, key, val)
        {
            size_t q;
            if (!api_face_key(key, m->npoly, &q) || !json_is_array(val)) {
                rc = api_fail(err, API_EINVALID,
                              "result.holes.%.40s: expected an array of rings of a result polygon "
                              "(there are %zu)",
                              key, m->npoly);
                goto fail;
            }
            for (size_t h = 0; h < json_array_size(val); h++) {
                const json_t *row = json_array_get(val, h);
                rc = result_cycle(row, m->nv, 3, NULL, err, "result.holes.%zu[%zu]", q, h);
                if (rc != API_OK) goto fail;
                nidx += json_array_size(row);
                nres++;
            }
        }
    }

    /* everything is checked and counted: the tables, filled */
    m->nface_rings = m->nrings;
    m->nrings += nres;
    m->face_ring = malloc((m->nf + 1) * sizeof *m->face_ring);
    m->ring_off = malloc((m->nrings + 1) * sizeof *m->ring_off);
    m->idx = malloc(nidx * sizeof *m->idx + 1);
    if (!m->face_ring || !m->ring_off || !m->idx) goto nomem;
    if (dim == 3) {
        m->cell_off = malloc((m->nc + 1) * sizeof *m->cell_off);
        m->cf = malloc(ncf * sizeof *m->cf + 1);
        if (!m->cell_off || !m->cf) goto nomem;
    }
    r = w = 0;
    for (size_t f = 0; f < m->nf; f++) {
        const json_t *row = json_array_get(FV, f), *hs = NULL;
        char k[24];
        m->face_ring[f] = r;
        m->ring_off[r++] = w;
        result_cycle(row, m->nv, minlen, m->idx + w, NULL, "FV[%zu]", f, SIZE_MAX);
        w += json_array_size(row);
        snprintf(k, sizeof k, "%zu", f);
        if (json_is_object(holes)) hs = json_object_get(holes, k);
        for (size_t h = 0; h < json_array_size(hs); h++) {
            row = json_array_get(hs, h);
            m->ring_off[r++] = w;
            result_cycle(row, m->nv, 1, m->idx + w, NULL, "holes.%zu[%zu]", f, h);
            w += json_array_size(row);
        }
    }
    m->face_ring[m->nf] = r;
    if (dim == 2 && res) {
        rc = read_result_2d(root, res, m, &r, &w, err);
        if (rc == API_ENOMEM) goto nomem;
        if (rc != API_OK) goto fail;
    }
    m->ring_off[r] = w;
    if (r != m->nrings || w != nidx) { /* cannot happen: keys were checked canonical and < nf */
        rc = api_fail(err, API_EINTERNAL, "render: holes counted twice differently");
        goto fail;
    }
    if (dim == 3) {
        rc = read_cells_3d(CF, res, m, err);
        if (rc == API_ENOMEM) goto nomem;
        if (rc != API_OK) goto fail;
    }
    if (dim == 2 && json_object_get(root, "layers"))
        m->root = root;
    else
        json_decref(root);
    return API_OK;
nomem:
    rc = api_fail(err, API_ENOMEM, "out of memory reading the result");
fail:
    json_decref(root);
    api_result_free(m);
    return rc;
}
