/* geos_ref.c — the GEOS reference for the 2D pipeline (see geos_ref.h).
 *
 * The segments become one MultiLineString; GEOSNode splits them at every crossing (and merges
 * identical pieces), GEOSPolygonize builds the polygons (with their holes) of the noded
 * linework.  Nodes and edges are counted here from the noded linework itself: every straight
 * piece between two consecutive coordinates is an edge, put in a canonical direction, sorted
 * and deduplicated, so the counts do not depend on how GEOS happens to group pieces into
 * linestrings.  Only the reentrant (_r) API is used, with one context per call.
 */
#if !defined(_GNU_SOURCE) && !defined(_POSIX_C_SOURCE)
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#endif
#define GEOS_USE_ONLY_R_API
#include <geos_c.h>

#include "tests/ref/geos_ref.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct ref_pt {
    double x, y;
} ref_pt;

typedef struct ref_seg {
    ref_pt a, b; /* a < b lexicographically (x, then y) */
} ref_seg;

void geos_ref_on_error(const char *message, void *udata)
{
    geos_ref_err *e = udata;
    if (e->set) return;
    snprintf(e->msg, sizeof e->msg, "%s", message ? message : "GEOS error");
    e->set = 1;
}

double geos_ref_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

GEOSGeometry *geos_ref_fold(GEOSContextHandle_t h, const char *op, GEOSGeometry *a, GEOSGeometry *b)
{
    GEOSGeometry *t;
    if (!strcmp(op, "union"))
        t = GEOSUnion_r(h, a, b);
    else if (!strcmp(op, "intersection"))
        t = GEOSIntersection_r(h, a, b);
    else
        t = GEOSSymDifference_r(h, a, b);
    GEOSGeom_destroy_r(h, a);
    GEOSGeom_destroy_r(h, b);
    return t;
}

static int ref_pt_cmp(ref_pt p, ref_pt q)
{
    if (p.x != q.x) return p.x < q.x ? -1 : 1;
    if (p.y != q.y) return p.y < q.y ? -1 : 1;
    return 0;
}

static int ref_pt_qcmp(const void *p, const void *q)
{
    return ref_pt_cmp(*(const ref_pt *)p, *(const ref_pt *)q);
}

static int ref_seg_qcmp(const void *p, const void *q)
{
    const ref_seg *s = p, *t = q;
    int c = ref_pt_cmp(s->a, t->a);
    return c ? c : ref_pt_cmp(s->b, t->b);
}

static int ref_double_qcmp(const void *p, const void *q)
{
    double a = *(const double *)p, b = *(const double *)q;
    return (a > b) - (a < b);
}

/* Appends the pieces of one noded linestring to segs (capacity *cap, grown as needed). */
static int ref_collect_pieces(GEOSContextHandle_t h, const GEOSGeometry *line, ref_seg **segs,
                              size_t *nseg, size_t *cap)
{
    const GEOSCoordSequence *cs = GEOSGeom_getCoordSeq_r(h, line);
    unsigned int npts = 0;
    if (!cs || !GEOSCoordSeq_getSize_r(h, cs, &npts)) return -1;
    ref_pt prev = {0, 0};
    for (unsigned int j = 0; j < npts; j++) {
        ref_pt p;
        if (!GEOSCoordSeq_getXY_r(h, cs, j, &p.x, &p.y)) return -1;
        if (j > 0 && ref_pt_cmp(prev, p) != 0) {
            if (*nseg == *cap) {
                size_t ncap = *cap ? 2 * *cap : 1024;
                ref_seg *grown = realloc(*segs, ncap * sizeof *grown);
                if (!grown) return -1;
                *segs = grown;
                *cap = ncap;
            }
            ref_seg s = ref_pt_cmp(prev, p) < 0 ? (ref_seg){prev, p} : (ref_seg){p, prev};
            (*segs)[(*nseg)++] = s;
        }
        prev = p;
    }
    return 0;
}

/* Counts the distinct edges and nodes of the noded linework. */
static int ref_count_graph(GEOSContextHandle_t h, const GEOSGeometry *noded, size_t *nnodes,
                           size_t *nedges)
{
    ref_seg *segs = NULL;
    ref_pt *pts = NULL;
    size_t nseg = 0, cap = 0;
    int rc = -1;

    int type = GEOSGeomTypeId_r(h, noded);
    if (type == GEOS_LINESTRING) {
        if (ref_collect_pieces(h, noded, &segs, &nseg, &cap)) goto fail;
    } else {
        int ng = GEOSGetNumGeometries_r(h, noded);
        if (ng < 0) goto fail;
        for (int i = 0; i < ng; i++) {
            const GEOSGeometry *g = GEOSGetGeometryN_r(h, noded, i);
            if (!g) goto fail;
            if (GEOSGeomTypeId_r(h, g) != GEOS_LINESTRING) continue;
            if (ref_collect_pieces(h, g, &segs, &nseg, &cap)) goto fail;
        }
    }

    size_t ne = 0;
    if (nseg) qsort(segs, nseg, sizeof *segs, ref_seg_qcmp);
    for (size_t i = 0; i < nseg; i++)
        if (i == 0 || ref_seg_qcmp(&segs[i - 1], &segs[i]) != 0) segs[ne++] = segs[i];

    pts = malloc((2 * ne + 1) * sizeof *pts);
    if (!pts) goto fail;
    for (size_t i = 0; i < ne; i++) {
        pts[2 * i] = segs[i].a;
        pts[2 * i + 1] = segs[i].b;
    }
    size_t nv = 0;
    if (ne) qsort(pts, 2 * ne, sizeof *pts, ref_pt_qcmp);
    for (size_t i = 0; i < 2 * ne; i++)
        if (i == 0 || ref_pt_cmp(pts[i - 1], pts[i]) != 0) nv++;

    *nnodes = nv;
    *nedges = ne;
    rc = 0;
fail:
    free(segs);
    free(pts);
    return rc;
}

int geos_ref_faces_timed(const double *seg, size_t n, double **areas, size_t *nfaces,
                         size_t *nholes, size_t *nnodes, size_t *nedges, double *ms, char *err,
                         size_t errlen)
{
    GEOSContextHandle_t h = NULL;
    GEOSGeometry **lines = NULL, *mls = NULL, *noded = NULL, *polys = NULL;
    double *area = NULL;
    size_t nl = 0, nlines = 0, np = 0, holes = 0, nv = 0, ne = 0;
    double t0, t1;
    int ng;
    geos_ref_err e = {{0}, 0};
    int rc = -1;

    *areas = NULL;
    *nfaces = *nholes = *nnodes = *nedges = 0;
    if (ms) *ms = 0;
    if (err && errlen) err[0] = '\0';
    if (n > UINT_MAX) {
        snprintf(e.msg, sizeof e.msg, "too many segments for GEOS (%zu)", n);
        e.set = 1;
        goto fail;
    }

    h = GEOS_init_r();
    if (!h) goto fail;
    GEOSContext_setErrorMessageHandler_r(h, geos_ref_on_error, &e);

    lines = malloc((n ? n : 1) * sizeof *lines);
    if (!lines) goto fail;
    for (size_t i = 0; i < n; i++) {
        const double *s = seg + 4 * i;
        if (s[0] == s[2] && s[1] == s[3]) continue;
        GEOSCoordSequence *cs = GEOSCoordSeq_create_r(h, 2, 2);
        if (!cs) goto fail;
        if (!GEOSCoordSeq_setXY_r(h, cs, 0, s[0], s[1]) ||
            !GEOSCoordSeq_setXY_r(h, cs, 1, s[2], s[3])) {
            GEOSCoordSeq_destroy_r(h, cs);
            goto fail;
        }
        GEOSGeometry *ls = GEOSGeom_createLineString_r(h, cs); /* takes cs, even on failure */
        if (!ls) goto fail;
        lines[nl++] = ls;
    }
    if (nl == 0) {
        rc = 0; /* nothing to node: an empty arrangement */
        goto fail;
    }
    /* The collection takes the geometries (not the array), on failure too. */
    nlines = nl;
    nl = 0;
    mls = GEOSGeom_createCollection_r(h, GEOS_MULTILINESTRING, lines, (unsigned)nlines);
    if (!mls) goto fail;

    t0 = geos_ref_now_ms();
    noded = GEOSNode_r(h, mls);
    if (!noded) goto fail;
    polys = GEOSPolygonize_r(h, (const GEOSGeometry *const[]){noded}, 1);
    if (!polys) goto fail;
    t1 = geos_ref_now_ms();

    if (ref_count_graph(h, noded, &nv, &ne)) goto fail;

    ng = GEOSGetNumGeometries_r(h, polys);
    if (ng < 0) goto fail;
    area = malloc(((size_t)ng + 1) * sizeof *area);
    if (!area) goto fail;
    for (int i = 0; i < ng; i++) {
        const GEOSGeometry *p = GEOSGetGeometryN_r(h, polys, i);
        if (!p || GEOSGeomTypeId_r(h, p) != GEOS_POLYGON) continue;
        int nr = GEOSGetNumInteriorRings_r(h, p);
        if (nr < 0 || !GEOSArea_r(h, p, &area[np])) goto fail;
        holes += (size_t)nr;
        np++;
    }
    if (np) qsort(area, np, sizeof *area, ref_double_qcmp);

    if (ms) *ms = t1 - t0;
    *nfaces = np;
    *nholes = holes;
    *nnodes = nv;
    *nedges = ne;
    if (np) {
        *areas = area;
        area = NULL;
    }
    rc = 0;
fail:
    if (rc != 0 && err && errlen)
        snprintf(err, errlen, "%s", e.set ? e.msg : "GEOS failed (out of memory?)");
    free(area);
    if (h) {
        for (size_t i = 0; i < nl; i++) GEOSGeom_destroy_r(h, lines[i]);
        if (polys) GEOSGeom_destroy_r(h, polys);
        if (noded) GEOSGeom_destroy_r(h, noded);
        if (mls) GEOSGeom_destroy_r(h, mls);
        GEOS_finish_r(h);
    }
    free(lines);
    return rc;
}

int geos_ref_faces(const double *seg, size_t n, double **areas, size_t *nfaces, size_t *nholes,
                   size_t *nnodes, size_t *nedges)
{
    return geos_ref_faces_timed(seg, n, areas, nfaces, nholes, nnodes, nedges, NULL, NULL, 0);
}

/* Ring xy[0 .. 2n) closed by repeating its first point. */
static GEOSGeometry *ring(GEOSContextHandle_t h, const double *xy, size_t n)
{
    GEOSCoordSequence *cs = GEOSCoordSeq_create_r(h, (unsigned)n + 1, 2);
    for (size_t i = 0; i <= n; i++)
        GEOSCoordSeq_setXY_r(h, cs, (unsigned)i, xy[2 * (i % n)], xy[2 * (i % n) + 1]);
    return GEOSGeom_createLinearRing_r(h, cs);
}

GEOSGeometry *geos_ref_polygon(GEOSContextHandle_t h, const uint32_t *poly_off,
                               const uint32_t *ring_off, const double *xy, size_t p)
{
    uint32_t r0 = poly_off[p], nr = poly_off[p + 1] - r0;
    GEOSGeometry **holes = malloc((nr ? nr : 1) * sizeof *holes);
    if (!holes) return NULL;
    for (uint32_t k = 1; k < nr; k++)
        holes[k - 1] = ring(h, xy + 2 * ring_off[r0 + k], ring_off[r0 + k + 1] - ring_off[r0 + k]);
    GEOSGeometry *shell = ring(h, xy + 2 * ring_off[r0], ring_off[r0 + 1] - ring_off[r0]);
    GEOSGeometry *g = GEOSGeom_createPolygon_r(h, shell, holes, nr - 1);
    free(holes);
    return g;
}
