/* render_mesh.c — a 3D result (LAR JSON, dim 3) written as binary STL, OFF, 3MF or glTF 2.0
 * binary (render.h says what each holds).  The triangles are api/rmesh.c's, the ones OBJ
 * writes; every mesh written holds only the vertices its triangles use.
 *
 * What a Boolean's result gives: STL, OFF and 3MF (for a slicer, a printer, a CAD tool) the
 * result solid only, its boundary ("result".faces); glb (for a viewer) every cell as its own
 * node and the result as one more node named "result".  Of any other 3D result: STL and OFF
 * every cell's triangles one after the other (adjacent cells' shared faces twice, once facing
 * out of each), 3MF one object per cell, glb one node per cell.
 *
 * Coordinates: STL and glb hold float32 (the doubles rounded to nearest); OFF and 3MF the
 * doubles printed exactly (api_format_double).  3MF says unit="millimeter" (a result has no
 * unit; 3MF's default is the millimetre).  The 3MF zip is made by libzip (deflated); its
 * entries' times are fixed.
 *
 * glb is written in stages: glb_nodes (the scene's nodes), glb_scene (their JSON), glb_meshes
 * (glb_mesh per node with triangles: its binary data, its mesh, accessors and views), glb_pack
 * (the container's chunks).
 *
 * Threads: reentrant, no globals.  Ownership: as the other renderers (render.h).
 */
#include "api/render.h"

#include "api/api_int.h"
#include "api/rmesh.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <zip.h>

typedef struct mctx {
    api_result m;
    rmesh rm;
    uint32_t *local; /* nv: a vertex's number in the part being written, UINT32_MAX none */
    uint32_t *list;  /* nv: the part's vertices */
} mctx;

static void mctx_free(mctx *x)
{
    rmesh_free(&x->rm);
    api_result_free(&x->m);
    free(x->local);
    free(x->list);
}

static int mctx_open(const char *json, size_t len, const char *why, mctx *x, api_error *err)
{
    memset(x, 0, sizeof *x);
    int rc = api_result_read(json, len, 3, why, &x->m, err);
    if (rc != API_OK) return rc;
    rc = rmesh_make(&x->m, &x->rm, err);
    if (rc != API_OK) {
        api_result_free(&x->m);
        return rc;
    }
    x->local = malloc((x->m.nv + 1) * sizeof *x->local);
    x->list = malloc((x->m.nv + 1) * sizeof *x->list);
    if (!x->local || !x->list) {
        mctx_free(x);
        return api_fail(err, API_ENOMEM, "out of memory");
    }
    for (size_t v = 0; v < x->m.nv; v++) x->local[v] = UINT32_MAX;
    return API_OK;
}

/* Numbers the vertices cells [c0, c1) of cl use (x->local, x->list); returns their count.
 * part_done() resets. */
static size_t part_vertices(mctx *x, const rmesh_cells *cl, size_t c0, size_t c1)
{
    size_t nl = 0;
    for (size_t c = c0; c < c1; c++) nl = rmesh_cell_vertices(&x->rm, cl, c, x->local, x->list, nl);
    return nl;
}

static void part_done(mctx *x, size_t nl)
{
    for (size_t i = 0; i < nl; i++) x->local[x->list[i]] = UINT32_MAX;
}

static int finish(api_buf *b, int rc, char **out, size_t *outlen, api_error *err)
{
    if (rc == API_OK && b->failed) rc = api_fail(err, API_ENOMEM, "out of memory");
    if (rc != API_OK) {
        api_buf_free(b);
        return rc;
    }
    *out = b->p;
    *outlen = b->len;
    if (!*out) { /* nothing written (cannot happen: every format has a header) */
        *out = calloc(1, 1);
        if (!*out) return api_fail(err, API_ENOMEM, "out of memory");
    }
    if (err) *err = (api_error){0};
    return API_OK;
}

static void put_le32(api_buf *b, uint32_t v)
{
    char c[4] = {(char)(v & 255), (char)(v >> 8 & 255), (char)(v >> 16 & 255), (char)(v >> 24)};
    api_buf_put(b, c, 4);
}

static void put_f32(api_buf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    put_le32(b, u);
}

/* ---- STL (binary) -----------------------------------------------------------------------------
 */

int render_stl(const char *result_json, size_t len, const render_opts *o, char **out,
               size_t *outlen, api_error *err)
{
    mctx x;
    api_buf b = {0};
    size_t one[2], nt = 0;
    char head[80];
    (void)o;
    *out = NULL;
    *outlen = 0;
    int rc = mctx_open(result_json, len, "STL is written of 3D results", &x, err);
    if (rc != API_OK) return rc;
    rmesh_cells cl = rmesh_cells_of(&x.m, one);
    for (size_t c = 0; c < cl.nc; c++) nt += rmesh_cell_ntri(&x.rm, &cl, c);
    if (nt > UINT32_MAX) {
        rc = api_fail(err, API_EINVALID, "STL: more than 2^32 triangles");
        goto out;
    }
    /* the header must not start with "solid" (readers would take it for ASCII) */
    memset(head, ' ', sizeof head);
    int hn = snprintf(head, sizeof head, "cellar binary STL: %s, %zu triangles",
                      cl.result ? "Boolean result" : "cells", nt);
    if (hn > 0 && hn < (int)sizeof head) head[hn] = ' ';
    api_buf_put(&b, head, sizeof head);
    put_le32(&b, (uint32_t)nt);
    for (size_t c = 0; c < cl.nc && !b.failed; c++)
        for (size_t i = cl.off[c]; i < cl.off[c + 1]; i++)
            for (size_t j = 0, nj = rmesh_ntri(&x.rm, cl.cf[i]); j < nj; j++) {
                uint32_t t[3];
                float p[3][3], n[3], e1[3], e2[3];
                rmesh_triangle(&x.rm, cl.cf[i], j, t);
                for (int q = 0; q < 3; q++)
                    for (int a = 0; a < 3; a++) p[q][a] = (float)x.m.V[3 * (size_t)t[q] + a];
                for (int a = 0; a < 3; a++) {
                    e1[a] = p[1][a] - p[0][a];
                    e2[a] = p[2][a] - p[0][a];
                }
                n[0] = e1[1] * e2[2] - e1[2] * e2[1];
                n[1] = e1[2] * e2[0] - e1[0] * e2[2];
                n[2] = e1[0] * e2[1] - e1[1] * e2[0];
                double l = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
                for (int a = 0; a < 3; a++)
                    put_f32(&b, l > 0 && isfinite(l) ? (float)(n[a] / l) : 0.0f);
                for (int q = 0; q < 3; q++)
                    for (int a = 0; a < 3; a++) put_f32(&b, p[q][a]);
                api_buf_put(&b, "\0\0", 2);
            }
out:
    mctx_free(&x);
    return finish(&b, rc, out, outlen, err);
}

/* ---- OFF --------------------------------------------------------------------------------------
 */

int render_off(const char *result_json, size_t len, const render_opts *o, char **out,
               size_t *outlen, api_error *err)
{
    mctx x;
    api_buf b = {0};
    size_t one[2], nt = 0;
    (void)o;
    *out = NULL;
    *outlen = 0;
    int rc = mctx_open(result_json, len, "OFF is written of 3D results", &x, err);
    if (rc != API_OK) return rc;
    rmesh_cells cl = rmesh_cells_of(&x.m, one);
    for (size_t c = 0; c < cl.nc; c++) nt += rmesh_cell_ntri(&x.rm, &cl, c);
    size_t nl = part_vertices(&x, &cl, 0, cl.nc);
    api_buf_puts(&b, "OFF\n# cellar: ");
    api_buf_puts(&b, cl.result ? "the Boolean's result" : "every cell");
    api_buf_puts(&b, ", triangles facing out\n");
    api_buf_u64(&b, nl);
    api_buf_putc(&b, ' ');
    api_buf_u64(&b, nt);
    api_buf_puts(&b, " 0\n");
    for (size_t i = 0; i < nl; i++) {
        const double *p = x.m.V + 3 * (size_t)x.list[i];
        api_buf_double(&b, p[0]);
        api_buf_putc(&b, ' ');
        api_buf_double(&b, p[1]);
        api_buf_putc(&b, ' ');
        api_buf_double(&b, p[2]);
        api_buf_putc(&b, '\n');
    }
    for (size_t c = 0; c < cl.nc && !b.failed; c++)
        for (size_t i = cl.off[c]; i < cl.off[c + 1]; i++)
            for (size_t j = 0, nj = rmesh_ntri(&x.rm, cl.cf[i]); j < nj; j++) {
                uint32_t t[3];
                rmesh_triangle(&x.rm, cl.cf[i], j, t);
                api_buf_puts(&b, "3");
                for (int q = 0; q < 3; q++) {
                    api_buf_putc(&b, ' ');
                    api_buf_u64(&b, x.local[t[q]]);
                }
                api_buf_putc(&b, '\n');
            }
    part_done(&x, nl);
    mctx_free(&x);
    return finish(&b, rc, out, outlen, err);
}

/* ---- 3MF --------------------------------------------------------------------------------------
 */

static const char content_types[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">"
    "<Default Extension=\"rels\" "
    "ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>"
    "<Default Extension=\"model\" "
    "ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/></Types>\n";

static const char rels[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">"
    "<Relationship Target=\"/3D/3dmodel.model\" Id=\"rel0\" "
    "Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/></Relationships>\n";

static void put_attr_double(api_buf *b, const char *name, double v)
{
    api_buf_puts(b, name);
    api_buf_puts(b, "=\"");
    api_buf_double(b, v);
    api_buf_putc(b, '"');
}

static void put_attr_u64(api_buf *b, const char *name, uint64_t v)
{
    api_buf_puts(b, name);
    api_buf_puts(b, "=\"");
    api_buf_u64(b, v);
    api_buf_putc(b, '"');
}

/* The model part: one object per cell (or the result), each its own vertices. */
static void model_xml(mctx *x, const rmesh_cells *cl, api_buf *b)
{
    size_t id = 0;
    api_buf_puts(b, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" "
                    "xml:lang=\"en-US\" "
                    "xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n"
                    "<metadata name=\"Application\">cellar</metadata>\n<resources>\n");
    for (size_t c = 0; c < cl->nc && !b->failed; c++) {
        if (!rmesh_cell_ntri(&x->rm, cl, c)) continue;
        size_t nl = part_vertices(x, cl, c, c + 1);
        put_attr_u64(b, "<object id", ++id);
        api_buf_puts(b, " type=\"model\" name=\"");
        if (cl->result) {
            api_buf_puts(b, "result");
        } else {
            api_buf_puts(b, "cell");
            api_buf_u64(b, c);
        }
        api_buf_puts(b, "\"><mesh><vertices>\n");
        for (size_t i = 0; i < nl; i++) {
            const double *p = x->m.V + 3 * (size_t)x->list[i];
            put_attr_double(b, "<vertex x", p[0]);
            put_attr_double(b, " y", p[1]);
            put_attr_double(b, " z", p[2]);
            api_buf_puts(b, "/>\n");
        }
        api_buf_puts(b, "</vertices><triangles>\n");
        for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++)
            for (size_t j = 0, nj = rmesh_ntri(&x->rm, cl->cf[i]); j < nj; j++) {
                uint32_t t[3];
                rmesh_triangle(&x->rm, cl->cf[i], j, t);
                put_attr_u64(b, "<triangle v1", x->local[t[0]]);
                put_attr_u64(b, " v2", x->local[t[1]]);
                put_attr_u64(b, " v3", x->local[t[2]]);
                api_buf_puts(b, "/>\n");
            }
        api_buf_puts(b, "</triangles></mesh></object>\n");
        part_done(x, nl);
    }
    api_buf_puts(b, "</resources>\n<build>");
    for (size_t k = 1; k <= id; k++) {
        put_attr_u64(b, "<item objectid", k);
        api_buf_puts(b, "/>");
    }
    api_buf_puts(b, "</build>\n</model>\n");
}

/* A zip of the three parts, deflated, into *out (malloc'd).  0, or -1. */
static int zip_parts(const char *model, size_t mlen, char **out, size_t *outlen, char *msg,
                     size_t msglen)
{
    const struct {
        const char *name, *data;
        size_t len;
    } parts[] = {{"[Content_Types].xml", content_types, sizeof content_types - 1},
                 {"_rels/.rels", rels, sizeof rels - 1},
                 {"3D/3dmodel.model", model, mlen}};
    zip_error_t ze;
    zip_t *za = NULL;
    int rc = -1;
    zip_error_init(&ze);
    zip_source_t *src = zip_source_buffer_create(NULL, 0, 0, &ze);
    if (!src) goto fail;
    zip_source_keep(src);
    if (!(za = zip_open_from_source(src, ZIP_TRUNCATE, &ze))) goto fail;
    /* the entries' time, 1980-01-01 12:00 as the zip's DOS time holds it: libzip turns a time_t
     * into DOS time through the local time zone, so the time_t is the one local time gives for
     * that date, and the bytes are the same in every time zone (a strong ETag) */
    struct tm noon = {.tm_year = 80, .tm_mon = 0, .tm_mday = 1, .tm_hour = 12, .tm_isdst = -1};
    time_t when = mktime(&noon);
    for (size_t i = 0; i < 3; i++) {
        zip_source_t *s = zip_source_buffer(za, parts[i].data, parts[i].len, 0);
        zip_int64_t k = s ? zip_file_add(za, parts[i].name, s, ZIP_FL_ENC_UTF_8) : -1;
        if (k < 0) {
            if (s) zip_source_free(s);
            snprintf(msg, msglen, "%s", zip_strerror(za));
            goto fail_za;
        }
        zip_set_file_compression(za, (zip_uint64_t)k, ZIP_CM_DEFLATE, 6);
        zip_file_set_mtime(za, (zip_uint64_t)k, when, 0);
    }
    if (zip_close(za) < 0) {
        snprintf(msg, msglen, "%s", zip_strerror(za));
        goto fail_za;
    }
    za = NULL;
    if (zip_source_open(src) < 0) goto fail;
    zip_source_seek(src, 0, SEEK_END);
    zip_int64_t n = zip_source_tell(src);
    zip_source_seek(src, 0, SEEK_SET);
    char *p = n > 0 ? malloc((size_t)n) : NULL;
    if (p && zip_source_read(src, p, (zip_uint64_t)n) == n) {
        *out = p;
        *outlen = (size_t)n;
        rc = 0;
    } else {
        free(p);
        snprintf(msg, msglen, "cannot read the zip back");
    }
    zip_source_close(src);
    zip_source_free(src);
    zip_error_fini(&ze);
    return rc;
fail_za:
    zip_discard(za);
fail:
    if (src) zip_source_free(src);
    if (rc && !msg[0]) snprintf(msg, msglen, "%s", zip_error_strerror(&ze));
    zip_error_fini(&ze);
    return -1;
}

int render_3mf(const char *result_json, size_t len, const render_opts *o, char **out,
               size_t *outlen, api_error *err)
{
    mctx x;
    api_buf b = {0};
    size_t one[2];
    char msg[160] = "";
    (void)o;
    *out = NULL;
    *outlen = 0;
    int rc = mctx_open(result_json, len, "3MF is written of 3D results", &x, err);
    if (rc != API_OK) return rc;
    rmesh_cells cl = rmesh_cells_of(&x.m, one);
    model_xml(&x, &cl, &b);
    mctx_free(&x);
    if (b.failed) {
        api_buf_free(&b);
        return api_fail(err, API_ENOMEM, "out of memory writing the 3MF");
    }
    if (zip_parts(b.p, b.len, out, outlen, msg, sizeof msg)) {
        api_buf_free(&b);
        return api_fail(err, API_ENOMEM, "3MF: cannot make the zip: %s", msg);
    }
    api_buf_free(&b);
    if (err) *err = (api_error){0};
    return API_OK;
}

/* ---- glTF 2.0 binary --------------------------------------------------------------------------
 */

/* One node of the scene: a cell (or the result) of cl. */
typedef struct gnode {
    const rmesh_cells *cl;
    size_t c;
    int result;
    size_t nv, nt; /* 0 triangles: a node without a mesh */
    double shift[3];
} gnode;

/* The scene's nodes (room for nc + 2): a node per cell of cells, moved by explode as render_obj
 * moves it, then the result (res) of a Boolean; returns how many. */
static size_t glb_nodes(mctx *x, const render_opts *o, const rmesh_cells *cells,
                        const rmesh_cells *res, gnode *nodes)
{
    double centre[3];
    size_t nn = 0;
    rmesh_centre(&x->m, centre);
    for (size_t c = 0; c < x->m.nc; c++) {
        nodes[nn] = (gnode){cells, c, 0, 0, rmesh_cell_ntri(&x->rm, cells, c), {0, 0, 0}};
        if (o->explode > 1) rmesh_cell_shift(&x->rm, cells, c, o->explode, centre, nodes[nn].shift);
        nn++;
    }
    if (x->m.has_result) nodes[nn++] = (gnode){res, 0, 1, 0, rmesh_cell_ntri(&x->rm, res, 0), {0}};
    return nn;
}

/* The JSON's "scene", "scenes" and "nodes" (a node with triangles names its mesh, in order). */
static void glb_scene(api_buf *js, const gnode *nodes, size_t nn)
{
    size_t nmesh = 0;
    api_buf_puts(js, "{\"asset\":{\"version\":\"2.0\",\"generator\":\"cellar\"},\"scene\":0,"
                     "\"scenes\":[{\"nodes\":[");
    for (size_t i = 0; i < nn; i++) {
        if (i) api_buf_putc(js, ',');
        api_buf_u64(js, i);
    }
    api_buf_puts(js, "]}],\"nodes\":[");
    for (size_t i = 0; i < nn; i++) {
        const gnode *g = &nodes[i];
        api_buf_puts(js, i ? ",{\"name\":\"" : "{\"name\":\"");
        api_buf_puts(js, g->result ? "result" : "cell");
        if (!g->result) api_buf_u64(js, g->c);
        api_buf_putc(js, '"');
        if (g->nt) {
            api_buf_puts(js, ",\"mesh\":");
            api_buf_u64(js, nmesh++);
        }
        if (g->shift[0] != 0 || g->shift[1] != 0 || g->shift[2] != 0) {
            api_buf_puts(js, ",\"translation\":");
            api_buf_point(js, g->shift, 3);
        }
        api_buf_putc(js, '}');
    }
}

/* The k-th mesh, of node g (with triangles): into bin its positions (float32 VEC3, their box
 * kept for the accessor), then its indices (uint32), both 4-byte aligned by construction; its
 * entry of "meshes" into js, its two accessors into acc and its two views into views. */
static void glb_mesh(mctx *x, const gnode *g, size_t k, api_buf *js, api_buf *acc, api_buf *views,
                     api_buf *bin)
{
    size_t nl = part_vertices(x, g->cl, g->c, g->c + 1);
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t pos_off = bin->len;
    for (size_t v = 0; v < nl; v++)
        for (int a = 0; a < 3; a++) {
            float f = (float)x->m.V[3 * (size_t)x->list[v] + a];
            lo[a] = fminf(lo[a], f);
            hi[a] = fmaxf(hi[a], f);
            put_f32(bin, f);
        }
    size_t idx_off = bin->len;
    const rmesh_cells *cl = g->cl;
    for (size_t f = cl->off[g->c]; f < cl->off[g->c + 1]; f++)
        for (size_t j = 0, nj = rmesh_ntri(&x->rm, cl->cf[f]); j < nj; j++) {
            uint32_t t[3];
            rmesh_triangle(&x->rm, cl->cf[f], j, t);
            for (int q = 0; q < 3; q++) put_le32(bin, x->local[t[q]]);
        }
    part_done(x, nl);
    if (k) api_buf_putc(js, ',');
    api_buf_puts(js, "{\"name\":\"");
    api_buf_puts(js, g->result ? "result" : "cell");
    if (!g->result) api_buf_u64(js, g->c);
    api_buf_puts(js, "\",\"primitives\":[{\"attributes\":{\"POSITION\":");
    api_buf_u64(js, 2 * k);
    api_buf_puts(js, "},\"indices\":");
    api_buf_u64(js, 2 * k + 1);
    api_buf_puts(js, ",\"mode\":4}]}");
    /* accessors and views, in step */
    double dlo[3] = {lo[0], lo[1], lo[2]}, dhi[3] = {hi[0], hi[1], hi[2]};
    api_buf_puts(acc, k ? ",{\"bufferView\":" : "{\"bufferView\":");
    api_buf_u64(acc, 2 * k);
    api_buf_puts(acc, ",\"componentType\":5126,\"count\":");
    api_buf_u64(acc, nl);
    api_buf_puts(acc, ",\"type\":\"VEC3\",\"min\":");
    api_buf_point(acc, dlo, 3);
    api_buf_puts(acc, ",\"max\":");
    api_buf_point(acc, dhi, 3);
    api_buf_puts(acc, "},{\"bufferView\":");
    api_buf_u64(acc, 2 * k + 1);
    api_buf_puts(acc, ",\"componentType\":5125,\"count\":");
    api_buf_u64(acc, 3 * g->nt);
    api_buf_puts(acc, ",\"type\":\"SCALAR\"}");
    api_buf_puts(views, k ? ",{\"buffer\":0,\"byteOffset\":" : "{\"buffer\":0,\"byteOffset\":");
    api_buf_u64(views, pos_off);
    api_buf_puts(views, ",\"byteLength\":");
    api_buf_u64(views, idx_off - pos_off);
    api_buf_puts(views, ",\"target\":34962},{\"buffer\":0,\"byteOffset\":");
    api_buf_u64(views, idx_off);
    api_buf_puts(views, ",\"byteLength\":");
    api_buf_u64(views, bin->len - idx_off);
    api_buf_puts(views, ",\"target\":34963}");
}

/* The JSON's "meshes" (and with any, "accessors", "bufferViews" and "buffers") of the nodes'
 * meshes, their data into bin; API_ENOMEM. */
static int glb_meshes(mctx *x, const gnode *nodes, size_t nn, api_buf *js, api_buf *bin)
{
    api_buf acc = {0}, views = {0};
    size_t k = 0;
    api_buf_puts(js, "],\"meshes\":[");
    for (size_t i = 0; i < nn; i++)
        if (nodes[i].nt) glb_mesh(x, &nodes[i], k++, js, &acc, &views, bin);
    api_buf_puts(js, "]");
    if (k) {
        api_buf_puts(js, ",\"accessors\":[");
        api_buf_put(js, acc.p ? acc.p : "", acc.len);
        api_buf_puts(js, "],\"bufferViews\":[");
        api_buf_put(js, views.p ? views.p : "", views.len);
        api_buf_puts(js, "],\"buffers\":[{\"byteLength\":");
        api_buf_u64(js, bin->len);
        api_buf_puts(js, "}]");
    }
    api_buf_putc(js, '}');
    int failed = acc.failed || views.failed;
    api_buf_free(&acc);
    api_buf_free(&views);
    return failed ? API_ENOMEM : API_OK;
}

/* The GLB container into b: the 12-byte header, the JSON chunk (js, padded with spaces to 4
 * bytes), the binary chunk (bin, when not empty); API_EINVALID past 4 GiB. */
static int glb_pack(api_buf *b, api_buf *js, const api_buf *bin, api_error *err)
{
    while (js->len % 4) api_buf_putc(js, ' ');
    if (bin->len > UINT32_MAX - 64 - js->len)
        return api_fail(err, API_EINVALID, "glTF: more than 4 GiB");
    size_t total = 12 + 8 + js->len + (bin->len ? 8 + bin->len : 0);
    put_le32(b, 0x46546C67u); /* "glTF" */
    put_le32(b, 2);
    put_le32(b, (uint32_t)total);
    put_le32(b, (uint32_t)js->len);
    put_le32(b, 0x4E4F534Au); /* "JSON" */
    api_buf_put(b, js->p, js->len);
    if (bin->len) {
        put_le32(b, (uint32_t)bin->len);
        put_le32(b, 0x004E4942u); /* "BIN\0" */
        api_buf_put(b, bin->p, bin->len);
    }
    return API_OK;
}

int render_glb(const char *result_json, size_t len, const render_opts *o, char **out,
               size_t *outlen, api_error *err)
{
    render_opts def = RENDER_OPTS_INIT;
    mctx x;
    api_buf js = {0}, bin = {0}, b = {0};
    size_t one[2], nn;
    gnode *nodes = NULL;
    *out = NULL;
    *outlen = 0;
    if (!o) o = &def;
    if (!(o->explode >= 1 && o->explode <= RENDER_EXPLODE_MAX))
        return api_fail(err, API_EINVALID, "explode: expected a number in [1, %g]",
                        RENDER_EXPLODE_MAX);
    int rc = mctx_open(result_json, len, "glTF is written of 3D results", &x, err);
    if (rc != API_OK) return rc;
    rmesh_cells cells = rmesh_all_cells(&x.m), res = rmesh_cells_of(&x.m, one);
    nodes = calloc(x.m.nc + 2, sizeof *nodes);
    if (!nodes) goto nomem;
    nn = glb_nodes(&x, o, &cells, &res, nodes);
    glb_scene(&js, nodes, nn);
    if (glb_meshes(&x, nodes, nn, &js, &bin) != API_OK || js.failed || bin.failed) goto nomem;
    rc = glb_pack(&b, &js, &bin, err);
    goto out;
nomem:
    rc = api_fail(err, API_ENOMEM, "out of memory writing the glTF");
out:
    free(nodes);
    api_buf_free(&js);
    api_buf_free(&bin);
    mctx_free(&x);
    return finish(&b, rc, out, outlen, err);
}
