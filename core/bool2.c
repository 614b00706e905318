/* bool2.c — Boolean operations on polygons with holes through one arrangement; see bool2.h.
 *
 * Steps: rings -> segments -> arr2_build(); per bounded face an interior point (face_point) and
 * its membership in every input (parity test, exact orientation on doubles); bool_expr per
 * face; boundary half-edges (selected face on the left); cycles walked with the tightest turn;
 * cycles grouped by the edge-connected region of selected faces they bound; holes go to the
 * outer cycle of their region (by an exact point-in-cycle test when a region has several).
 *
 * Exactness: orient() filters a double evaluation with Shewchuk's error bound and otherwise sums
 * the 16 exact products of the two-term differences as an expansion, so the sign is exact for
 * any finite doubles (barring underflow, far below the snapping grid).  The interior point
 * itself is computed in floating point, then checked exactly against the face's edges; when the
 * check fails (a sliver) the next widest gap between vertex heights is tried.
 *
 * Cost: membership is faces x input edges (with a bounding-box test per polygon first); known
 * to be simple rather than fast for thousands of faces against thousands of ring edges.
 *
 * Threads: reentrant, no globals.  Ownership: see bool2.h.
 */
#include "core/bool2.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- exact orientation on doubles ----------------------------------------------------------- */

static void two_sum(double a, double b, double *x, double *y)
{
    double s = a + b, bv = s - a, av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

static void two_diff(double a, double b, double *x, double *y)
{
    double s = a - b, bv = a - s, av = s + bv;
    *x = s;
    *y = (a - av) + (bv - b);
}

/* Adds one double to an expansion of n components (increasing magnitude); returns new n. */
static int grow(double *e, int n, double b)
{
    double q = b;
    for (int i = 0; i < n; i++) {
        double s, t;
        two_sum(q, e[i], &s, &t);
        e[i] = t;
        q = s;
    }
    e[n] = q;
    return n + 1;
}

/* Sign of (b - a) x (c - a): > 0 when a, b, c turn counter-clockwise.  Exact. */
static int orient(double ax, double ay, double bx, double by, double cx, double cy)
{
    double l = (bx - ax) * (cy - ay), r = (by - ay) * (cx - ax), det = l - r;
    double bound = 3.3306690738754716e-16 * (fabs(l) + fabs(r));
    if (det > bound) return 1;
    if (-det > bound) return -1;
    double u[2], v[2], w[2], z[2], e[17];
    two_diff(bx, ax, &u[1], &u[0]);
    two_diff(cy, ay, &v[1], &v[0]);
    two_diff(by, ay, &w[1], &w[0]);
    two_diff(cx, ax, &z[1], &z[0]);
    int n = 0;
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) {
            double p = u[i] * v[j], q = w[i] * z[j];
            n = grow(e, n, p);
            n = grow(e, n, fma(u[i], v[j], -p));
            n = grow(e, n, -q);
            n = grow(e, n, -fma(w[i], z[j], -q));
        }
    for (int i = n - 1; i >= 0; i--)
        if (e[i] != 0) return e[i] > 0 ? 1 : -1;
    return 0;
}

/* Does the rightward ray from p cross segment ab (half-open in y: an endpoint at p's height
 * counts as above)?  A point on the segment does not cross it. */
static int ray_crosses(double px, double py, double ax, double ay, double bx, double by)
{
    if ((ay > py) == (by > py)) return 0;
    int o = orient(ax, ay, bx, by, px, py);
    return by > ay ? o > 0 : o < 0;
}

int bool2_point_in(double px, double py, const uint32_t *ring_off, size_t nring, const double *xy)
{
    int in = 0;
    for (size_t r = 0; r < nring; r++) {
        uint32_t a = ring_off[r], n = ring_off[r + 1] - a;
        for (uint32_t i = 0; i < n; i++) {
            const double *p = xy + 2 * (a + i), *q = xy + 2 * (a + (i + 1) % n);
            in ^= ray_crosses(px, py, p[0], p[1], q[0], q[1]);
        }
    }
    return in;
}

/* ---- interior points ------------------------------------------------------------------------- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

typedef struct gap {
    double lo, hi;
} gap;

static int cmp_gap_wide(const void *a, const void *b)
{
    const gap *g = a, *h = b;
    double x = g->hi - g->lo, y = h->hi - h->lo;
    return (x < y) - (x > y);
}

/* Even-odd over the face's edges (its outer cycle and holes). */
static int face_contains(const lar2 *c, size_t f, double px, double py)
{
    int in = 0;
    for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
        uint32_t e = (uint32_t)abs(c->fe[i]) - 1;
        const double *a = c->V + 2 * c->EV[2 * e], *b = c->V + 2 * c->EV[2 * e + 1];
        in ^= ray_crosses(px, py, a[0], a[1], b[0], b[1]);
    }
    return in;
}

/* A point strictly inside face f, into *px, *py; scratch: ys and xs of 2 * (edges of f) doubles
 * each, gaps as many.  Returns 0, or -1 when no candidate checks out. */
static int face_point(const lar2 *c, size_t f, double *ys, double *xs, gap *gaps, double *px,
                      double *py)
{
    size_t ny = 0, ng = 0;
    for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
        uint32_t e = (uint32_t)abs(c->fe[i]) - 1;
        ys[ny++] = c->V[2 * c->EV[2 * e] + 1];
        ys[ny++] = c->V[2 * c->EV[2 * e + 1] + 1];
    }
    qsort(ys, ny, sizeof *ys, cmp_double);
    for (size_t i = 1; i < ny; i++)
        if (ys[i] > ys[i - 1]) gaps[ng++] = (gap){ys[i - 1], ys[i]};
    qsort(gaps, ng, sizeof *gaps, cmp_gap_wide);
    for (size_t g = 0; g < ng; g++) {
        double y = gaps[g].lo + (gaps[g].hi - gaps[g].lo) / 2, best = 0, bx = 0;
        size_t nx = 0;
        if (!(y > gaps[g].lo && y < gaps[g].hi)) continue;
        for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
            uint32_t e = (uint32_t)abs(c->fe[i]) - 1;
            const double *a = c->V + 2 * c->EV[2 * e], *b = c->V + 2 * c->EV[2 * e + 1];
            if ((a[1] > y) == (b[1] > y)) continue;
            xs[nx++] = a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
        }
        qsort(xs, nx, sizeof *xs, cmp_double);
        for (size_t i = 0; i + 1 < nx; i += 2)
            if (xs[i + 1] - xs[i] > best) {
                best = xs[i + 1] - xs[i];
                bx = xs[i] + best / 2;
            }
        if (best > 0 && face_contains(c, f, bx, y)) {
            *px = bx;
            *py = y;
            return 0;
        }
    }
    return -1;
}

/* ---- the result's boundary ----------------------------------------------------------------- */

static uint32_t uf_find(uint32_t *p, uint32_t x)
{
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
}

/* Is the CCW angle from d = u - v to w1 - v larger than to w2 - v (both half-edges out of v)? */
static int angle_larger(const double *V, uint32_t v, uint32_t u, uint32_t w1, uint32_t w2)
{
    const double *o = V + 2 * v, *d = V + 2 * u, *a = V + 2 * w1, *b = V + 2 * w2;
    int h[2];
    const double *w[2] = {a, b};
    for (int k = 0; k < 2; k++) {
        int s = orient(o[0], o[1], d[0], d[1], w[k][0], w[k][1]);
        if (s > 0)
            h[k] = 0;
        else if (s < 0)
            h[k] = 1;
        else { /* collinear with d: same direction is angle 0 (taken last), opposite is pi */
            int same = ((w[k][0] > o[0]) == (d[0] > o[0])) && ((w[k][0] < o[0]) == (d[0] < o[0])) &&
                       ((w[k][1] > o[1]) == (d[1] > o[1])) && ((w[k][1] < o[1]) == (d[1] < o[1]));
            h[k] = same ? 2 : 1;
        }
    }
    if (h[0] != h[1]) return h[0] > h[1];
    return orient(o[0], o[1], a[0], a[1], b[0], b[1]) < 0; /* b before a counter-clockwise */
}

static int seterr(char *err, size_t el, int code, const char *msg)
{
    if (el) snprintf(err, el, "%s", msg);
    return code;
}

void bool2_free(bool2_result *r)
{
    lar2_free(&r->c);
    free(r->member);
    free(r->cells);
    free(r->rc_off);
    free(r->rv);
    free(r->re);
    free(r->poly_outer);
    free(r->ph_off);
    free(r->ph_cyc);
    memset(r, 0, sizeof *r);
}

/* Cycle k's signed area, shoelace. */
static double cycle_area(const bool2_result *r, size_t k)
{
    double s = 0;
    uint32_t a = r->rc_off[k], n = r->rc_off[k + 1] - a;
    for (uint32_t i = 0; i < n; i++) {
        const double *p = r->c.V + 2 * r->rv[a + i], *q = r->c.V + 2 * r->rv[a + (i + 1) % n];
        s += p[0] * q[1] - p[1] * q[0];
    }
    return s / 2;
}

/* Is (px, py) inside cycle k (even-odd)? */
static int cycle_contains(const bool2_result *r, size_t k, double px, double py)
{
    int in = 0;
    uint32_t a = r->rc_off[k], n = r->rc_off[k + 1] - a;
    for (uint32_t i = 0; i < n; i++) {
        const double *p = r->c.V + 2 * r->rv[a + i], *q = r->c.V + 2 * r->rv[a + (i + 1) % n];
        in ^= ray_crosses(px, py, p[0], p[1], q[0], q[1]);
    }
    return in;
}

int bool2_build(const bool2_input *in, const bool_expr *op, const arr2_opts *opts,
                bool2_result *out, char *err, size_t errlen)
{
    bool2_result r = {0};
    double *seg = NULL, *ys = NULL, *xs = NULL, *bbox = NULL;
    gap *gaps = NULL;
    uint8_t *sel = NULL, *stack = NULL, *used = NULL, *ccw = NULL;
    int32_t *left = NULL, *right = NULL;
    uint32_t *hoff = NULL, *hto = NULL, *hedge = NULL, *uf = NULL, *region = NULL, *owner = NULL;
    size_t nseg = 0, nring, npts, maxfe = 0, nh = 0;
    int rc = ARR_ENOMEM;
    memset(out, 0, sizeof *out);
    if (!in || !op || in->npoly == 0 || in->npoly > BOOL2_MAX_INPUTS)
        return seterr(err, errlen, ARR_EINVAL, "bool2: between 1 and 100000 input polygons");
    nring = in->poly_off[in->npoly];
    npts = in->ring_off[nring];
    r.ninputs = in->npoly;

    /* rings -> segments, and each polygon's bounding box */
    seg = malloc((npts ? npts : 1) * 4 * sizeof *seg);
    bbox = malloc(in->npoly * 4 * sizeof *bbox);
    if (!seg || !bbox) goto fail;
    for (size_t p = 0; p < in->npoly; p++) {
        double *bb = bbox + 4 * p;
        bb[0] = bb[1] = INFINITY;
        bb[2] = bb[3] = -INFINITY;
        for (uint32_t k = in->poly_off[p]; k < in->poly_off[p + 1]; k++) {
            uint32_t a = in->ring_off[k], n = in->ring_off[k + 1] - a;
            for (uint32_t i = 0; i < n; i++) {
                const double *s = in->xy + 2 * (a + i), *t = in->xy + 2 * (a + (i + 1) % n);
                if (!isfinite(s[0]) || !isfinite(s[1])) {
                    rc = seterr(err, errlen, ARR_EINVAL, "bool2: non-finite coordinate");
                    goto out;
                }
                bb[0] = fmin(bb[0], s[0]);
                bb[1] = fmin(bb[1], s[1]);
                bb[2] = fmax(bb[2], s[0]);
                bb[3] = fmax(bb[3], s[1]);
                if (s[0] == t[0] && s[1] == t[1]) continue;
                memcpy(seg + 4 * nseg, s, 2 * sizeof *s);
                memcpy(seg + 4 * nseg + 2, t, 2 * sizeof *t);
                nseg++;
            }
        }
    }
    rc = arr2_build(seg, nseg, opts, &r.c, err, errlen);
    if (rc != ARR_OK) goto out;
    rc = ARR_ENOMEM;
    free(seg);
    seg = NULL;

    /* membership and selection */
    const lar2 *c = &r.c;
    for (size_t f = 0; f < c->nf; f++)
        if (c->fe_off[f + 1] - c->fe_off[f] > maxfe) maxfe = c->fe_off[f + 1] - c->fe_off[f];
    r.member = calloc(c->nf ? c->nf * r.ninputs : 1, 1);
    sel = calloc(c->nf + 1, 1);
    stack = malloc(op->depth + 1);
    ys = malloc((2 * maxfe + 1) * sizeof *ys);
    xs = malloc((2 * maxfe + 1) * sizeof *xs);
    gaps = malloc((2 * maxfe + 1) * sizeof *gaps);
    if (!r.member || !sel || !stack || !ys || !xs || !gaps) goto fail;
    for (size_t f = 0; f < c->nf; f++) {
        double px, py;
        uint8_t *row = r.member + f * r.ninputs;
        if (opts && opts->cancel && atomic_load(opts->cancel)) {
            rc = seterr(err, errlen, ARR_ECANCELED, "canceled");
            goto out;
        }
        if (face_point(c, f, ys, xs, gaps, &px, &py)) {
            char m[96];
            snprintf(m, sizeof m, "bool2: no interior point found for face %zu", f);
            rc = seterr(err, errlen, ARR_EINTERNAL, m);
            goto out;
        }
        for (size_t p = 0; p < r.ninputs; p++) {
            const double *bb = bbox + 4 * p;
            if (px < bb[0] || px > bb[2] || py < bb[1] || py > bb[3]) continue;
            row[p] = (uint8_t)bool2_point_in(px, py, in->ring_off + in->poly_off[p],
                                             in->poly_off[p + 1] - in->poly_off[p], in->xy);
        }
        sel[f] = (uint8_t)bool_expr_eval(op, row, stack);
        if (sel[f]) {
            double a = lar2_cycle_area(c, c->face_cycle[f]);
            for (uint32_t h = c->hole_off[f]; h < c->hole_off[f + 1]; h++)
                a += lar2_cycle_area(c, c->hole_cyc[h]);
            r.area += a;
            r.ncells++;
        }
    }
    r.cells = malloc((r.ncells ? r.ncells : 1) * sizeof *r.cells);
    if (!r.cells) goto fail;
    for (size_t f = 0, k = 0; f < c->nf; f++)
        if (sel[f]) r.cells[k++] = (uint32_t)f;

    /* the faces on either side of each edge (-1: the exterior) */
    left = malloc((c->ne + 1) * sizeof *left);
    right = malloc((c->ne + 1) * sizeof *right);
    uf = malloc((c->nf + 1) * sizeof *uf);
    if (!left || !right || !uf) goto fail;
    for (size_t e = 0; e < c->ne; e++) left[e] = right[e] = -1;
    for (size_t f = 0; f < c->nf; f++) {
        uf[f] = (uint32_t)f;
        for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
            int32_t s = c->fe[i];
            if (s > 0)
                left[s - 1] = (int32_t)f;
            else
                right[-s - 1] = (int32_t)f;
        }
    }
    /* boundary half-edges, grouped by origin (counting sort); regions by union-find */
    hoff = calloc(c->nv + 1, sizeof *hoff);
    if (!hoff) goto fail;
    for (size_t e = 0; e < c->ne; e++) {
        int sl = left[e] >= 0 && sel[left[e]], sr = right[e] >= 0 && sel[right[e]];
        if (sl && sr) {
            uint32_t a = uf_find(uf, (uint32_t)left[e]), b = uf_find(uf, (uint32_t)right[e]);
            uf[a] = b;
        }
        if (sl == sr) continue;
        hoff[c->EV[2 * e + (sl ? 0 : 1)] + 1]++;
        nh++;
    }
    for (size_t v = 0; v < c->nv; v++) hoff[v + 1] += hoff[v];
    hto = malloc((nh + 1) * sizeof *hto);
    hedge = malloc((nh + 1) * sizeof *hedge);
    used = calloc(nh + 1, 1);
    r.rc_off = malloc((nh + 1) * sizeof *r.rc_off);
    r.rv = malloc((nh + 1) * sizeof *r.rv);
    r.re = malloc((nh + 1) * sizeof *r.re);
    if (!hto || !hedge || !used || !r.rc_off || !r.rv || !r.re) goto fail;
    {
        uint32_t *fill = malloc((c->nv + 1) * sizeof *fill);
        if (!fill) goto fail;
        memcpy(fill, hoff, (c->nv + 1) * sizeof *fill);
        for (size_t e = 0; e < c->ne; e++) {
            int sl = left[e] >= 0 && sel[left[e]], sr = right[e] >= 0 && sel[right[e]];
            if (sl == sr) continue;
            uint32_t from = c->EV[2 * e + (sl ? 0 : 1)], to = c->EV[2 * e + (sl ? 1 : 0)];
            hto[fill[from]] = to;
            hedge[fill[from]++] = (uint32_t)e;
        }
        free(fill);
    }

    /* walk the cycles: from each unused half-edge, at every vertex take the outgoing half-edge
     * of largest counter-clockwise angle from the way back (the tightest turn) */
    r.rc_off[0] = 0;
    size_t len = 0;
    for (size_t v = 0; v < c->nv; v++)
        for (uint32_t h0 = hoff[v]; h0 < hoff[v + 1]; h0++) {
            if (used[h0]) continue;
            uint32_t h = h0, from = (uint32_t)v;
            while (!used[h]) {
                uint32_t e = hedge[h], to = hto[h], best = UINT32_MAX;
                used[h] = 1;
                r.rv[len] = from;
                r.re[len++] = c->EV[2 * e] == from ? (int32_t)e + 1 : -(int32_t)e - 1;
                for (uint32_t k = hoff[to]; k < hoff[to + 1]; k++)
                    if (best == UINT32_MAX || angle_larger(c->V, to, from, hto[k], hto[best]))
                        best = k;
                if (best == UINT32_MAX) {
                    rc = seterr(err, errlen, ARR_EINTERNAL, "bool2: open boundary walk");
                    goto out;
                }
                from = to;
                h = best;
            }
            if (h != h0) {
                rc = seterr(err, errlen, ARR_EINTERNAL, "bool2: boundary walk closes elsewhere");
                goto out;
            }
            r.rc_off[++r.nrcyc] = (uint32_t)len;
        }

    /* orientation (exact, at the cycle's smallest vertex: V is sorted) and region of each */
    ccw = malloc(r.nrcyc + 1);
    region = malloc((r.nrcyc + 1) * sizeof *region);
    owner = malloc((r.nrcyc + 1) * sizeof *owner);
    r.poly_outer = malloc((r.nrcyc + 1) * sizeof *r.poly_outer);
    r.ph_off = calloc(r.nrcyc + 2, sizeof *r.ph_off);
    r.ph_cyc = malloc((r.nrcyc + 1) * sizeof *r.ph_cyc);
    if (!ccw || !region || !owner || !r.poly_outer || !r.ph_off || !r.ph_cyc) goto fail;
    for (size_t k = 0; k < r.nrcyc; k++) {
        uint32_t a = r.rc_off[k], n = r.rc_off[k + 1] - a, m = 0;
        for (uint32_t i = 1; i < n; i++)
            if (r.rv[a + i] < r.rv[a + m]) m = i;
        const double *p = c->V + 2 * r.rv[a + (m + n - 1) % n], *o = c->V + 2 * r.rv[a + m],
                     *q = c->V + 2 * r.rv[a + (m + 1) % n];
        ccw[k] = orient(p[0], p[1], o[0], o[1], q[0], q[1]) > 0;
        int32_t s = r.re[a];
        region[k] = uf_find(uf, (uint32_t)(s > 0 ? left[s - 1] : right[-s - 1]));
    }
    /* outer cycles become polygons; a hole goes to the only outer cycle of its region, or to
     * the smallest one of its region around the middle of its first edge */
    for (size_t k = 0; k < r.nrcyc; k++)
        if (ccw[k]) {
            owner[k] = (uint32_t)r.npoly;
            r.poly_outer[r.npoly++] = (uint32_t)k;
        }
    for (size_t k = 0; k < r.nrcyc; k++) {
        if (ccw[k]) continue;
        uint32_t a = r.rc_off[k], n = r.rc_off[k + 1] - a, best = UINT32_MAX;
        const double *p = c->V + 2 * r.rv[a], *q = c->V + 2 * r.rv[a + (n > 1)];
        double mx = p[0] + (q[0] - p[0]) / 2, my = p[1] + (q[1] - p[1]) / 2, barea = 0;
        size_t cand = 0;
        for (size_t j = 0; j < r.nrcyc; j++)
            if (ccw[j] && region[j] == region[k]) cand++;
        for (size_t j = 0; j < r.nrcyc; j++) {
            if (!ccw[j] || region[j] != region[k]) continue;
            if (cand > 1 && !cycle_contains(&r, j, mx, my)) continue;
            double ar = cycle_area(&r, j);
            if (best == UINT32_MAX || ar < barea) {
                best = (uint32_t)j;
                barea = ar;
            }
        }
        if (best == UINT32_MAX) {
            rc = seterr(err, errlen, ARR_EINTERNAL, "bool2: a hole of the result has no outer");
            goto out;
        }
        owner[k] = owner[best];
        r.ph_off[owner[k] + 1]++;
    }
    for (size_t q = 0; q < r.npoly; q++) r.ph_off[q + 1] += r.ph_off[q];
    {
        uint32_t *fill = malloc((r.npoly + 1) * sizeof *fill);
        if (!fill) goto fail;
        memcpy(fill, r.ph_off, (r.npoly + 1) * sizeof *fill);
        for (size_t k = 0; k < r.nrcyc; k++)
            if (!ccw[k]) r.ph_cyc[fill[owner[k]]++] = (uint32_t)k;
        free(fill);
    }
    rc = ARR_OK;
    *out = r;
    goto done;
fail:
    rc = seterr(err, errlen, ARR_ENOMEM, "bool2: out of memory");
out:
    bool2_free(&r);
done:
    free(seg);
    free(bbox);
    free(ys);
    free(xs);
    free(gaps);
    free(sel);
    free(stack);
    free(used);
    free(ccw);
    free(left);
    free(right);
    free(hoff);
    free(hto);
    free(hedge);
    free(uf);
    free(region);
    free(owner);
    return rc;
}
