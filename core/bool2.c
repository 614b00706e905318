/* bool2.c — Boolean operations on polygons with holes through one arrangement; see bool2.h.
 *
 * Stages, each a function below:
 *   segments    every ring edge becomes a segment tagged with its polygon;
 *   arrange     arr2_build() with the tags (each edge then lists the polygons lying on it an odd
 *               number of times: crossing it changes exactly their membership) and the input
 *               coordinates for the vertices that input points snapped to;
 *   sides       the face on each side of every edge: read from the arrangement, which keeps the
 *               planar kernel's half-edges for us (arr2_opts.half_edges: lar2.he_face, the face
 *               left of each half-edge; EXT, nf, stands for the unbounded face);
 *   membership  a walk over the faces from EXT, whose row is empty: crossing edge e toggles
 *               the polygons e lists (core/member.h: sparse rows, the few polygons a face lies
 *               in, never faces x polygons).  Every face is reached; a face reached again must
 *               get the same row, compared exactly (a 422 otherwise, never a wrong answer);
 *   select      the expression on each face's row (bool_tree: the ancestors of its members'
 *               leaves only);
 *   groups      selected faces joined across edges with a selected face on both sides: each
 *               group is one result polygon (polygons of the result meet at most at vertices);
 *   boundary    the edges with a selected face on one side only, directed with it on the
 *               left; at each vertex, an edge coming in is followed by the next edge of its
 *               group counter-clockwise around the vertex (the kernel's order there, lar2.he_out
 *               and he_pos: nothing is sorted again): the turn through the wedge outside
 *               the group.  So a ring never passes a vertex twice: where the outside touches
 *               the polygon (a hole touching the shell or another hole) the rings split there,
 *               as OGC asks;
 *   polygons    in each group one ring turns counter-clockwise (the shell: the boundary of the
 *               unbounded part of the group's outside) and the others clockwise (holes: the
 *               bounded parts).  No point-in-polygon test is needed: the group says which
 *               holes are whose.
 * Every decision is exact on the arrangement's grid coordinates (lar2.VG): angles as the kernel
 * sorted them (dir_cmp, the sign of 128-bit cross products), orientation by the exact signed
 * area.  The half-edges are freed once the rings are made (the result keeps the complex only).
 *
 * Threads: reentrant (arr2_build() starts and joins its own threads); no globals.
 * Ownership: see bool2.h.
 */
#include "core/bool2.h"
#include "core/member.h"
#include "core/stop.h"
#include "core/util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

typedef __int128 i128;

static void rings_free(bool2_rings *g)
{
    free(g->rc_off);
    free(g->rv);
    free(g->re);
    free(g->poly_outer);
    free(g->ph_off);
    free(g->ph_cyc);
    memset(g, 0, sizeof *g);
}

void bool2_free(bool2_result *r)
{
    lar2_free(&r->c);
    free(r->mem_off);
    free(r->mem);
    free(r->memw);
    free(r->cells);
    rings_free(&r->region);
    free(r->piece_face);
    rings_free(&r->pieces);
    free(r->poly_piece);
    memset(r, 0, sizeof *r);
}

/* ---- segments ----------------------------------------------------------------------------- */

/* Every ring edge as a segment (x1, y1, x2, y2) tagged with its polygon.  A ring's closing edge
 * is implicit; a last point equal to the first makes a zero-length segment, which arr2 drops. */
static int stage_segments(const bool2_input *in, double **seg, uint32_t **tag, size_t *n)
{
    size_t nr = in->poly_off[in->npoly], np = in->ring_off[nr];
    *seg = malloc((np ? np : 1) * 4 * sizeof **seg);
    *tag = malloc((np ? np : 1) * sizeof **tag);
    if (!*seg || !*tag) return -1;
    size_t k = 0;
    for (size_t p = 0; p < in->npoly; p++)
        for (uint32_t r = in->poly_off[p]; r < in->poly_off[p + 1]; r++) {
            uint32_t a = in->ring_off[r], m = in->ring_off[r + 1] - a;
            for (uint32_t i = 0; i < m; i++) {
                const double *u = in->xy + 2 * (a + i), *v = in->xy + 2 * (a + (i + 1) % m);
                double *s = *seg + 4 * k;
                s[0] = u[0], s[1] = u[1], s[2] = v[0], s[3] = v[1];
                (*tag)[k++] = (uint32_t)p;
            }
        }
    *n = k;
    return 0;
}

/* ---- membership --------------------------------------------------------------------------- */

/* The rows of the nf + 1 faces (the last is EXT, empty) by member_walk() over the faces
 * through the edges with two different faces beside them, each listing its polygons (etag). */
/* Progress inside the walk (a fraction of the membership stage). */
static void membership_tick(void *udata, double f)
{
    const arr2_opts *po = udata;
    po->progress(po->udata, "membership", f);
}

static int stage_membership(bool2_result *out, const uint32_t *side, const arr2_opts *po, char *err,
                            size_t el)
{
    const lar2 *c = &out->c;
    size_t nf = c->nf, nn = nf + 1;
    uint32_t *aoff = calloc(nn + 2, sizeof *aoff), *nb = malloc((2 * c->ne + 1) * sizeof *nb);
    uint32_t *ed = malloc((2 * c->ne + 1) * sizeof *ed), bad = UINT32_MAX;
    int8_t *dir = c->etagw ? malloc(2 * c->ne + 1) : NULL;
    member_rows rows;
    int rc = ARR_ENOMEM;
    if (!aoff || !nb || !ed || (c->etagw && !dir)) goto done;
    for (size_t e = 0; e < c->ne; e++)
        if (side[2 * e] != side[2 * e + 1]) aoff[side[2 * e] + 2]++, aoff[side[2 * e + 1] + 2]++;
    for (size_t f = 0; f < nn; f++) aoff[f + 2] += aoff[f + 1];
    /* with winding numbers an edge's first side is its right (side[2e + 1]): crossing from
     * there to its left adds its signed counts (a ring turning counter-clockwise holds what
     * lies on its left) */
    for (size_t e = 0; e < c->ne; e++)
        if (side[2 * e] != side[2 * e + 1]) {
            uint32_t a = side[2 * e], b = side[2 * e + 1];
            if (dir) dir[aoff[a + 1]] = -1, dir[aoff[b + 1]] = 1;
            nb[aoff[a + 1]] = b, ed[aoff[a + 1]++] = (uint32_t)e;
            nb[aoff[b + 1]] = a, ed[aoff[b + 1]++] = (uint32_t)e;
        }
    void (*tick)(void *, double) = po && po->progress ? membership_tick : NULL;
    const atomic_int *cancel = po ? po->cancel : NULL;
    int w = dir ? member_walk_wind(nn, (uint32_t)nf, aoff, nb, ed, dir, c->etag_off, c->etag,
                                   c->etagw, &rows, &bad, tick, (void *)po, cancel)
                : member_walk_ex(nn, (uint32_t)nf, aoff, nb, ed, c->etag_off, c->etag, &rows, &bad,
                                 tick, (void *)po, cancel);
    if (w < 0) goto done;
    if (w == 2) {
        rc = util_seterr(err, el, ARR_ECANCELED, "cancelled");
        goto done;
    }
    if (w > 0) {
        if (bad == UINT32_MAX) {
            rc = util_seterr(err, el, ARR_EINTERNAL, "internal: faces out of reach of the walk");
        } else {
            const double *a = c->V + 2 * c->EV[2 * bad], *b = c->V + 2 * c->EV[2 * bad + 1];
            rc = util_seterr(
                err, el, ARR_EINVAL,
                "polygons: the labels are inconsistent after snapping: the faces beside "
                "the edge (%.17g, %.17g)-(%.17g, %.17g) get two memberships",
                a[0], a[1], b[0], b[1]);
        }
        goto done;
    }
    out->mem_off = rows.off;
    out->mem = rows.idx;
    out->memw = rows.wind;
    rc = ARR_OK;
done:
    if (rc == ARR_ENOMEM) util_seterr(err, el, rc, "out of memory");
    free(aoff);
    free(nb);
    free(ed);
    free(dir);
    return rc;
}

/* ---- select, groups ----------------------------------------------------------------------- */

/* sel[f] (1: selected) for the nf + 1 faces (EXT never selected); out->cells.  The expression is
 * evaluated on each face's sparse row (bool_tree). */
static int stage_select(bool2_result *out, const bool_expr *op, int fill, uint32_t *sel)
{
    size_t nf = out->c.nf;
    member_rows m = {out->mem_off, out->mem, out->memw}; /* a view: owned by out */
    bool_tree t;
    uint32_t *buf = out->memw ? malloc((member_row_most(&m, nf) + 1) * sizeof *buf) : NULL;
    if ((out->memw && !buf) || bool_tree_build(op, out->ninputs, &t)) {
        free(buf);
        return -1;
    }
    out->cells = malloc((nf + 1) * sizeof *out->cells);
    if (!out->cells) {
        bool_tree_free(&t);
        free(buf);
        return -1;
    }
    out->ncells = 0;
    for (size_t f = 0; f < nf; f++) {
        const uint32_t *row; /* the polygons the face lies in, by the fill rule */
        size_t n = member_row_inside(&m, f, fill, buf, &row);
        sel[f] = (uint32_t)bool_tree_eval(&t, row, n);
        if (sel[f]) out->cells[out->ncells++] = (uint32_t)f;
    }
    sel[nf] = 0;
    bool_tree_free(&t);
    free(buf);
    return 0;
}

/* grp[f]: the group (a representative face) of each labelled face (lab[f] != 0), joined across
 * edges with one label on both sides. */
static void stage_groups(const lar2 *c, const uint32_t *side, const uint32_t *lab, uint32_t *grp)
{
    for (size_t f = 0; f <= c->nf; f++) grp[f] = (uint32_t)f;
    for (size_t e = 0; e < c->ne; e++) {
        uint32_t a = side[2 * e], b = side[2 * e + 1];
        if (a != b && lab[a] && lab[a] == lab[b]) {
            uf_union(grp, a, b); /* the smaller face leads */
        }
    }
    for (size_t f = 0; f <= c->nf; f++) grp[f] = uf_find(grp, (uint32_t)f);
}

/* The pieces: sel[f] becomes 1 + the piece of each selected face (0 stays 0), a piece the
 * selected faces of one membership row (by the fill rule), numbered in the order of their first
 * faces; out->npieces, piece_face.  The rows are sorted (length, then inputs) to find the equal
 * ones.  0, or -1 out of memory. */
typedef struct prow {
    const uint32_t *in; /* the row's inputs */
    uint32_t n, f;      /* their count, the face */
} prow;

static int prow_cmp(const void *pa, const void *pb)
{
    const prow *a = pa, *b = pb;
    if (a->n != b->n) return a->n < b->n ? -1 : 1;
    int c = a->n ? memcmp(a->in, b->in, a->n * sizeof *a->in) : 0;
    if (c) return c;
    return a->f < b->f ? -1 : a->f > b->f;
}

static int stage_pieces(bool2_result *out, int fill, uint32_t *sel)
{
    size_t ns = out->ncells, nf = out->c.nf;
    member_rows m = {out->mem_off, out->mem, out->memw};
    size_t total = 0;
    for (size_t i = 0; i < ns; i++) {
        uint32_t f = out->cells[i];
        total += out->mem_off[f + 1] - out->mem_off[f];
    }
    uint32_t *flat = malloc((total + 1) * sizeof *flat), *lead = malloc((nf + 1) * sizeof *lead);
    prow *rows = malloc((ns + 1) * sizeof *rows);
    out->piece_face = malloc((ns + 1) * sizeof *out->piece_face);
    int rc = -1;
    if (!flat || !lead || !rows || !out->piece_face) goto done;
    size_t k = 0;
    for (size_t i = 0; i < ns; i++) {
        uint32_t f = out->cells[i];
        const uint32_t *row;
        size_t n = member_row_inside(&m, f, fill, flat + k, &row);
        if (row != flat + k) memcpy(flat + k, row, n * sizeof *row);
        rows[i] = (prow){flat + k, (uint32_t)n, f};
        k += n;
    }
    qsort(rows, ns, sizeof *rows, prow_cmp);
    /* each run of equal rows is led by its first face (the run is sorted by face) */
    for (size_t i = 0; i < ns; i++)
        lead[rows[i].f] =
            i && rows[i].n == rows[i - 1].n &&
                    !memcmp(rows[i].in, rows[i - 1].in, rows[i].n * sizeof *rows[i].in)
                ? lead[rows[i - 1].f]
                : rows[i].f;
    /* cells are ascending: a piece's number is given at its first face, its lead */
    out->npieces = 0;
    for (size_t i = 0; i < ns; i++) {
        uint32_t f = out->cells[i];
        if (lead[f] == f) {
            out->piece_face[out->npieces] = f;
            sel[f] = (uint32_t)++out->npieces;
        }
    }
    for (size_t i = 0; i < ns; i++) sel[out->cells[i]] = sel[lead[out->cells[i]]];
    rc = 0;
done:
    free(flat);
    free(lead);
    free(rows);
    return rc;
}

/* ---- boundary rings ----------------------------------------------------------------------- */

static uint32_t he_tail(const lar2 *c, uint32_t h)
{
    return c->EV[h];
}

/* Is half-edge x on the boundary of group gr: a labelled face of gr on its left, another label
 * on its right? */
static inline int bound_of(const uint32_t *side, const uint32_t *lab, const uint32_t *grp,
                           uint32_t x, uint32_t gr)
{
    uint32_t f = side[x];
    return lab[f] && lab[f] != lab[side[x ^ 1]] && grp[f] == gr;
}

/* next[h] for every boundary half-edge h (NONE for the others): at h's head v, the first
 * half-edge of h's group counter-clockwise after h's twin in the kernel's order around v
 * (lar2.he_out), which must leave v on the boundary (the rays of one group alternate in and out
 * around a vertex).  Returns ARR_OK, or an error with its message. */
static int ring_next(const lar2 *c, const uint32_t *side, const uint32_t *lab, const uint32_t *grp,
                     uint32_t *next, stop_meter *stop, char *err, size_t el)
{
    for (size_t h = 0; h < 2 * c->ne; h++) {
        next[h] = NONE;
        uint32_t f = side[h];
        if (!lab[f] || lab[f] == lab[side[h ^ 1]]) continue;
        uint32_t gr = grp[f], t = (uint32_t)h ^ 1, v = he_tail(c, t);
        const uint32_t *o = c->he_out + c->he_off[v];
        uint32_t d = c->he_off[v + 1] - c->he_off[v], j = c->he_pos[t];
        if (stop_poll(stop, d)) return util_seterr(err, el, ARR_ECANCELED, "cancelled");
        for (uint32_t k = 0; k < d && next[h] == NONE; k++) {
            j = j + 1 == d ? 0 : j + 1;
            if (bound_of(side, lab, grp, o[j], gr))
                next[h] = o[j];
            else if (bound_of(side, lab, grp, o[j] ^ 1, gr))
                return util_seterr(
                    err, el, ARR_EINTERNAL,
                    "internal: the result's boundary does not alternate at a vertex");
        }
    }
    return ARR_OK;
}

/* The rings of the labelled faces: g->rc_off, rv, re (every ring with its faces on its left),
 * and ring_grp (the group of each ring).  An edge between two labels is on a ring of each
 * (once each way), an edge between a label and none on one.  At each vertex a boundary
 * half-edge coming in is followed by the next one of its group counter-clockwise (ring_next). */
static int stage_rings(const lar2 *c, bool2_rings *g, const uint32_t *side, const uint32_t *lab,
                       const uint32_t *grp, uint32_t **ring_grp, stop_meter *stop, char *err,
                       size_t el)
{
    size_t nb = 0;
    for (size_t e = 0; e < c->ne; e++) {
        uint32_t l = lab[side[2 * e]], r = lab[side[2 * e + 1]];
        if (l != r) nb += (l != 0) + (r != 0);
    }
    uint32_t *next = malloc((2 * c->ne + 1) * sizeof *next);
    uint8_t *done = calloc(2 * c->ne + 1, 1);
    g->rc_off = malloc((nb + 1) * sizeof *g->rc_off);
    g->rv = malloc((nb + 1) * sizeof *g->rv);
    g->re = malloc((nb + 1) * sizeof *g->re);
    *ring_grp = malloc((nb + 1) * sizeof **ring_grp);
    int rc = ARR_ENOMEM;
    if (!next || !done || !g->rc_off || !g->rv || !g->re || !*ring_grp) goto fail;
    if ((rc = ring_next(c, side, lab, grp, next, stop, err, el)) != ARR_OK) goto fail;
    size_t nring = 0, k = 0;
    g->rc_off[0] = 0;
    for (size_t e = 0; e < c->ne; e++)
        for (uint32_t h = (uint32_t)(2 * e); h <= 2 * e + 1; h++) {
            if (next[h] == NONE || done[h]) continue;
            if (stop_poll(stop, 1)) {
                rc = util_seterr(err, el, ARR_ECANCELED, "cancelled");
                goto fail;
            }
            uint32_t x = h;
            do {
                if (done[x] || next[x] == NONE || k >= nb) {
                    rc = util_seterr(err, el, ARR_EINTERNAL,
                                     "internal: a boundary ring is not closed");
                    goto fail;
                }
                done[x] = 1;
                g->rv[k] = he_tail(c, x);
                g->re[k] = (x & 1) ? -(int32_t)((x >> 1) + 1) : (int32_t)((x >> 1) + 1);
                k++;
                x = next[x];
            } while (x != h);
            uint32_t s = side[h]; /* the labelled face */
            (*ring_grp)[nring] = grp[s];
            g->rc_off[++nring] = (uint32_t)k;
        }
    g->nrcyc = nring;
    rc = ARR_OK;
fail:
    if (rc == ARR_ENOMEM) util_seterr(err, el, rc, "out of memory");
    free(next);
    free(done);
    return rc;
}

/* Twice ring k's signed area in grid units, exactly. */
static i128 ring_area2(const lar2 *c, const bool2_rings *r, size_t k)
{
    const int64_t *G = c->VG;
    i128 a = 0;
    uint32_t b = r->rc_off[k], n = r->rc_off[k + 1] - b;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t u = r->rv[b + i], v = r->rv[b + (i + 1) % n];
        a += (i128)G[2 * u] * G[2 * v + 1] - (i128)G[2 * v] * G[2 * u + 1];
    }
    return a;
}

/* Per group, its one counter-clockwise ring (the shell) and its clockwise ones (the holes), in
 * the order of the groups' leading faces; the area of the result. */
static int stage_polygons(const lar2 *c, bool2_rings *out, const uint32_t *ring_grp,
                          double *area_out, char *err, size_t el)
{
    size_t nr = out->nrcyc, nf = c->nf;
    uint32_t *gi = malloc((nf + 2) * sizeof *gi); /* group (leading face) -> polygon */
    int8_t *ccw = malloc(nr + 1);
    out->poly_outer = malloc((nr + 1) * sizeof *out->poly_outer);
    out->ph_off = calloc(nr + 2, sizeof *out->ph_off);
    out->ph_cyc = malloc((nr + 1) * sizeof *out->ph_cyc);
    int rc = ARR_ENOMEM;
    if (!gi || !ccw || !out->poly_outer || !out->ph_off || !out->ph_cyc) goto done;
    for (size_t f = 0; f <= nf; f++) gi[f] = NONE;
    for (size_t k = 0; k < nr; k++) {
        i128 a = ring_area2(c, out, k);
        ccw[k] = a > 0;
        if (a == 0) {
            rc = util_seterr(err, el, ARR_EINTERNAL, "internal: a boundary ring of zero area");
            goto done;
        }
    }
    /* one shell per group; polygons numbered in the order of their groups' leading faces */
    size_t np = 0;
    for (size_t k = 0; k < nr; k++)
        if (ccw[k]) {
            if (gi[ring_grp[k]] != NONE) {
                rc = util_seterr(err, el, ARR_EINTERNAL,
                                 "internal: a result polygon with two shells");
                goto done;
            }
            gi[ring_grp[k]] = 0;
        }
    for (size_t f = 0; f < nf; f++)
        if (gi[f] != NONE) out->poly_outer[np] = NONE, gi[f] = (uint32_t)np++;
    for (size_t k = 0; k < nr; k++) {
        uint32_t q = gi[ring_grp[k]];
        if (q == NONE) {
            rc = util_seterr(err, el, ARR_EINTERNAL, "internal: a result polygon without a shell");
            goto done;
        }
        if (ccw[k])
            out->poly_outer[q] = (uint32_t)k;
        else
            out->ph_off[q + 2]++;
    }
    for (size_t q = 0; q < np; q++) out->ph_off[q + 2] += out->ph_off[q + 1];
    for (size_t k = 0; k < nr; k++)
        if (!ccw[k]) out->ph_cyc[out->ph_off[gi[ring_grp[k]] + 1]++] = (uint32_t)k;
    out->npoly = np;
    /* the area of the polygons as written: input points keep their coordinates (arr2's
     * input_coords), so this is the input's own area where snapping changed nothing (a needle
     * five grid steps high keeps its area) and within the snapping bound of the grid's, total,
     * everywhere; each ring about its first vertex, so that far coordinates do not cancel */
    long double area = 0;
    for (size_t k = 0; k < nr; k++) {
        const double *V = c->V;
        uint32_t b = out->rc_off[k], n = out->rc_off[k + 1] - b;
        double x0 = V[2 * out->rv[b]], y0 = V[2 * out->rv[b] + 1];
        for (uint32_t i = 0; i < n; i++) {
            uint32_t u = out->rv[b + i], v = out->rv[b + (i + 1) % n];
            area += ((long double)V[2 * u] - x0) * ((long double)V[2 * v + 1] - y0) -
                    ((long double)V[2 * v] - x0) * ((long double)V[2 * u + 1] - y0);
        }
    }
    *area_out = area > 0 ? (double)(area / 2) : 0;
    rc = ARR_OK;
done:
    if (rc == ARR_ENOMEM) util_seterr(err, el, rc, "out of memory");
    free(gi);
    free(ccw);
    return rc;
}

/* ---- the pipeline ------------------------------------------------------------------------- */

int bool2_build(const bool2_input *in, const bool_expr *op, const arr2_opts *opts,
                bool2_result *out, char *err, size_t errlen)
{
    static const arr2_opts defaults = {0};
    double *seg = NULL;
    uint32_t *tag = NULL, *grp = NULL, *ring_grp = NULL, *sel = NULL;
    size_t n = 0;
    int rc = ARR_ENOMEM;
    memset(out, 0, sizeof *out);
    if (err && errlen) err[0] = 0;
    if (in->npoly > BOOL2_MAX_INPUTS)
        return util_seterr(err, errlen, ARR_ELIMIT, "polygons: %zu, more than the limit of %u",
                           in->npoly, BOOL2_MAX_INPUTS);
    if (stage_segments(in, &seg, &tag, &n)) goto fail;
    arr2_opts ao = opts ? *opts : defaults;
    ao.tags = tag;
    ao.signed_tags = in->fill != BOOL2_FILL_ODD;
    ao.input_coords = 1;
    ao.half_edges = 1; /* the sides of the edges and the order around the vertices, kept */
    if ((rc = arr2_build(seg, n, &ao, &out->c, err, errlen)) != ARR_OK) goto fail;
    free(seg);
    free(tag);
    seg = NULL, tag = NULL;
    lar2 *c = &out->c;
    size_t ni = in->npoly, nf = c->nf;
    out->ninputs = ni;
    rc = ARR_ENOMEM;
    const uint32_t *side = c->he_face; /* side[h]: the face left of half-edge h */
    sel = malloc((nf + 1) * sizeof *sel);
    grp = malloc((nf + 1) * sizeof *grp);
    if (!sel || !grp) goto fail;
        /* the stages after the arrangement's, a cancel read between them and each stage's end
         * reported */
#define BOOL2_CANCEL_POINT                                                                         \
    do {                                                                                           \
        if (ao.cancel && atomic_load(ao.cancel)) {                                                 \
            rc = util_seterr(err, errlen, ARR_ECANCELED, "cancelled");                             \
            goto fail;                                                                             \
        }                                                                                          \
    } while (0)
#define BOOL2_PROGRESS(stage, f)                                                                   \
    do {                                                                                           \
        if (ao.progress) ao.progress(ao.udata, stage, f);                                          \
        BOOL2_CANCEL_POINT;                                                                        \
    } while (0)
    stop_meter stop = {.flag = ao.cancel};
    BOOL2_CANCEL_POINT;
    if ((rc = stage_membership(out, side, &ao, err, errlen)) != ARR_OK) goto fail;
    BOOL2_PROGRESS("membership", 1);
    rc = ARR_ENOMEM;
    if (stage_select(out, op, in->fill, sel)) goto fail;
    stage_groups(c, side, sel, grp);
    BOOL2_PROGRESS("select", 1);
    if ((rc = stage_rings(c, &out->region, side, sel, grp, &ring_grp, &stop, err, errlen)) !=
        ARR_OK)
        goto fail;
    BOOL2_PROGRESS("polygons", 0.5);
    if ((rc = stage_polygons(c, &out->region, ring_grp, &out->area, err, errlen)) != ARR_OK)
        goto fail;
    if (in->pieces) {
        free(ring_grp);
        ring_grp = NULL;
        rc = ARR_ENOMEM;
        if (stage_pieces(out, in->fill, sel)) goto fail;
        stage_groups(c, side, sel, grp);
        BOOL2_PROGRESS("polygons", 0.75);
        if ((rc = stage_rings(c, &out->pieces, side, sel, grp, &ring_grp, &stop, err, errlen)) !=
            ARR_OK)
            goto fail;
        double unused;
        rc = stage_polygons(c, &out->pieces, ring_grp, &unused, err, errlen);
        if (rc != ARR_OK) goto fail;
        rc = ARR_ENOMEM;
        out->poly_piece = malloc((out->pieces.npoly + 1) * sizeof *out->poly_piece);
        if (!out->poly_piece) goto fail;
        for (size_t q = 0; q < out->pieces.npoly; q++)
            out->poly_piece[q] = sel[ring_grp[out->pieces.poly_outer[q]]] - 1;
    }
    BOOL2_PROGRESS("polygons", 1);
#undef BOOL2_PROGRESS
#undef BOOL2_CANCEL_POINT
    lar2_free_half_edges(c); /* walked: the result keeps the complex only */
    free(sel);
    free(grp);
    free(ring_grp);
    return ARR_OK;
fail:
    if (rc == ARR_ENOMEM) util_seterr(err, errlen, rc, "out of memory");
    free(seg);
    free(tag);
    free(sel);
    free(grp);
    free(ring_grp);
    bool2_free(out);
    return rc;
}
