/* render_obj.c — a 3D result (LAR JSON, dim 3) written as Wavefront OBJ (api/render.h).
 *
 * The result is read by api_result_read() (api/result.c, dim 3) into a flat model, every index
 * checked on the way (so the writer never indexes out of bounds):
 *
 *     face_ring:  f -> [face_ring[f], face_ring[f+1])   rings of face f: FV[f], then holes."f"
 *     ring_off:   r -> [ring_off[r], ring_off[r+1])     positions in idx (vertex indices)
 *     cell_off:   c -> [cell_off[c], cell_off[c+1])     positions in cf (signed faces ±(f+1))
 *
 * Then every face is triangulated once, in its own orientation (the outer cycle's Newell
 * normal), and each cell writes the triangles of its faces, reversed for a face it lists as
 * -(f+1), so every triangle of a cell faces out of it.  Of a Boolean's result the one cell
 * written is the result's boundary ("result".faces) in place of the cells.
 *
 * The triangles come from api/rmesh.c (the triangulation every mesh writer shares).  Only the
 * vertices the written triangles use are written, numbered in the order they are first used (a
 * Boolean's result writes its boundary's, not every vertex of the arrangement).
 *
 * Exploding: with explode = k > 1 each cell moves by (k - 1) * (c - C), c the cell's centroid
 * (of its volume, from the outward triangles; the mean of its vertices when the volume is not
 * positive), C the centre of the box of V; every cell then writes its own vertices.
 *
 * Threads: reentrant, no globals.  Ownership: inputs are borrowed; *out is malloc'd, the caller
 * frees it with free().
 */
#include "api/render.h"

#include "api/api_int.h"
#include "api/rmesh.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void put_vertex(api_buf *b, const double *x, const double *t)
{
    api_buf_puts(b, "v ");
    api_buf_double(b, x[0] + t[0]);
    api_buf_putc(b, ' ');
    api_buf_double(b, x[1] + t[1]);
    api_buf_putc(b, ' ');
    api_buf_double(b, x[2] + t[2]);
    api_buf_putc(b, '\n');
}

static void put_face(api_buf *b, uint64_t a, uint64_t c, uint64_t d)
{
    api_buf_puts(b, "f ");
    api_buf_u64(b, a);
    api_buf_putc(b, ' ');
    api_buf_u64(b, c);
    api_buf_putc(b, ' ');
    api_buf_u64(b, d);
    api_buf_putc(b, '\n');
}

static void put_cell_faces(api_buf *b, const rmesh *rm, const rmesh_cells *cl, size_t c,
                           const uint32_t *local, uint64_t base)
{
    for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++)
        for (size_t j = 0, nj = rmesh_ntri(rm, cl->cf[i]); j < nj; j++) {
            uint32_t t[3];
            rmesh_triangle(rm, cl->cf[i], j, t);
            put_face(b, base + local[t[0]] + 1, base + local[t[1]] + 1, base + local[t[2]] + 1);
        }
}

static int obj_write(const api_result *m, const rmesh_cells *cl, const render_opts *o, api_buf *b,
                     api_error *err)
{
    rmesh rm;
    uint32_t *local = NULL, *list = NULL;
    double centre[3], zero[3] = {0, 0, 0};
    size_t nl = 0;
    int rc = rmesh_make(m, &rm, err);
    if (rc != API_OK) return rc;
    local = malloc((m->nv + 1) * sizeof *local);
    list = malloc((m->nv + 1) * sizeof *list);
    if (!local || !list) goto nomem;
    for (size_t v = 0; v < m->nv; v++) local[v] = UINT32_MAX;
    for (size_t c = 0; c < cl->nc; c++) nl = rmesh_cell_vertices(&rm, cl, c, local, list, nl);
    for (size_t i = 0; i < nl; i++) local[list[i]] = UINT32_MAX;

    api_buf_puts(b, "# cellar: ");
    api_buf_u64(b, cl->nc);
    api_buf_puts(b, cl->result ? " result, " : " cells, ");
    api_buf_u64(b, rm.nt);
    api_buf_puts(b, " triangles of ");
    api_buf_u64(b, m->nf);
    api_buf_puts(b, " faces, ");
    api_buf_u64(b, nl);
    api_buf_puts(b, " of ");
    api_buf_u64(b, m->nv);
    api_buf_puts(b, " vertices\n");
    if (!(o->explode > 1)) { /* the vertices the cells use, once each, then the groups */
        nl = 0;
        for (size_t c = 0; c < cl->nc; c++) nl = rmesh_cell_vertices(&rm, cl, c, local, list, nl);
        for (size_t i = 0; i < nl; i++) put_vertex(b, m->V + 3 * (size_t)list[i], zero);
        for (size_t c = 0; c < cl->nc; c++) {
            api_buf_puts(b, cl->result ? "g result" : "g cell");
            if (!cl->result) api_buf_u64(b, c);
            api_buf_putc(b, '\n');
            put_cell_faces(b, &rm, cl, c, local, 0);
        }
        goto out;
    }
    /* exploded: each cell its own vertices (in the order its triangles first use them), all
     * the vertices first, then the groups */
    rmesh_centre(m, centre);
    for (size_t c = 0; c < cl->nc; c++) {
        double shift[3];
        nl = rmesh_cell_vertices(&rm, cl, c, local, list, 0);
        rmesh_cell_shift(&rm, cl, c, o->explode, centre, shift);
        for (size_t i = 0; i < nl; i++) {
            put_vertex(b, m->V + 3 * (size_t)list[i], shift);
            local[list[i]] = UINT32_MAX;
        }
    }
    uint64_t base = 0;
    for (size_t c = 0; c < cl->nc; c++) {
        nl = rmesh_cell_vertices(&rm, cl, c, local, list, 0);
        api_buf_puts(b, "g cell");
        api_buf_u64(b, c);
        api_buf_putc(b, '\n');
        put_cell_faces(b, &rm, cl, c, local, base);
        for (size_t i = 0; i < nl; i++) local[list[i]] = UINT32_MAX;
        base += nl;
    }
    goto out;
nomem:
    rc = api_fail(err, API_ENOMEM, "out of memory writing the OBJ");
out:
    rmesh_free(&rm);
    free(local);
    free(list);
    return rc;
}

int render_obj(const char *result_json, size_t len, const render_opts *o, char **out,
               size_t *outlen, api_error *err)
{
    render_opts def = RENDER_OPTS_INIT;
    api_result m;
    rmesh_cells cl;
    size_t one[2];
    api_buf b = {0};
    int rc;
    *out = NULL;
    *outlen = 0;
    if (!o) o = &def;
    if (!(o->explode >= 1 && o->explode <= RENDER_EXPLODE_MAX))
        return api_fail(err, API_EINVALID, "explode: expected a number in [1, %g]",
                        RENDER_EXPLODE_MAX);
    rc = api_result_read(result_json, len, 3, "OBJ is written of 3D results", &m, err);
    if (rc != API_OK) return rc;
    cl = rmesh_cells_of(&m, one); /* of a Boolean: its result's boundary, one solid */
    rc = obj_write(&m, &cl, o, &b, err);
    api_result_free(&m);
    if (rc == API_OK && b.failed) rc = api_fail(err, API_ENOMEM, "out of memory");
    if (rc != API_OK) {
        api_buf_free(&b);
        return rc;
    }
    *out = b.p;
    *outlen = b.len;
    if (err) *err = (api_error){0};
    return API_OK;
}
