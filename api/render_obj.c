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
 * Triangulation: the face's rings are projected on the two coordinates that drop the largest
 * component of the normal (in cyclic order, mirrored when that component is negative, so the
 * outer ring is counter-clockwise in the plane); holes are turned clockwise; each hole is
 * bridged into the outer ring (holes by decreasing largest u: a ray from the hole's rightmost
 * vertex to +u, the nearest ring edge it hits, the visible vertex of smallest angle inside the
 * triangle so formed, the copy of that vertex whose wedge holds the hole — the method of
 * Eberly's "Triangulation by Ear Clipping" and of mapbox/earcut); then ears are clipped.  An
 * ear is a convex corner whose triangle holds no reflex or flat vertex (points coinciding with
 * the corner's own three, the copies a bridge makes, do not count).  Flat vertices (on a
 * straight run of the boundary, common where a neighbouring face split an edge) are kept, so
 * the mesh stays watertight where the complex is.  A pass without an ear (only on broken or
 * near-degenerate input) clips a flat corner, then any convex one, then any: triangulation
 * always ends, n - 2 + 2 * holes triangles for n ring vertices.  Knowingly simple: O(n * r) per
 * face for n vertices and r reflex ones, no spatial index (results are capped in size before
 * they are rendered by the daemon; faces of an arrangement are small).
 * Geometry here is floating point: for pictures and meshes, not for the complex.
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

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the cells written ---------------------------------------------------------------------- */

/* The result is read by api_result_read() (api/result.c, dim 3).  The cells written are its
 * cells (CF), or a Boolean's result's boundary ("result".faces) as the one cell. */
typedef struct ocells {
    size_t nc;
    const size_t *off; /* nc + 1: cell c's signed faces are cf[off[c] .. off[c+1]) */
    const int32_t *cf; /* ±(f+1), 1 <= f+1 <= nf */
    int result;        /* the one cell is a Boolean result's boundary */
} ocells;

/* ---- triangulation --------------------------------------------------------------------------- */

typedef struct pnode {
    double x, y;
    uint32_t v;          /* the vertex */
    uint32_t prev, next; /* nodes of the ring */
} pnode;

typedef struct tri_buf {
    uint32_t *t; /* 3 per triangle */
    size_t n, cap;
    int failed;
} tri_buf;

static void tri_add(tri_buf *b, uint32_t a, uint32_t c, uint32_t d)
{
    if (b->failed) return;
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 256;
        uint32_t *t = realloc(b->t, 3 * cap * sizeof *t);
        if (!t) {
            b->failed = 1;
            return;
        }
        b->t = t;
        b->cap = cap;
    }
    b->t[3 * b->n] = a;
    b->t[3 * b->n + 1] = c;
    b->t[3 * b->n + 2] = d;
    b->n++;
}

/* Twice the signed area of the triangle (a, b, c): > 0 counter-clockwise. */
static double cross(const pnode *a, const pnode *b, const pnode *c)
{
    return (b->x - a->x) * (c->y - a->y) - (b->y - a->y) * (c->x - a->x);
}

static int same_point(const pnode *a, const pnode *b)
{
    return a->x == b->x && a->y == b->y;
}

/* p in the closed triangle (a, b, c), whatever its orientation. */
static int in_triangle(const pnode *a, const pnode *b, const pnode *c, const pnode *p)
{
    double d1 = cross(a, b, p), d2 = cross(b, c, p), d3 = cross(c, a, p);
    int neg = d1 < 0 || d2 < 0 || d3<0, pos = d1> 0 || d2 > 0 || d3 > 0;
    return !(neg && pos);
}

/* p lies in the wedge of the ring at node a (the interior side of its two edges). */
static int locally_inside(const pnode *n, uint32_t a, const pnode *p)
{
    const pnode *pa = &n[n[a].prev], *na = &n[n[a].next], *A = &n[a];
    if (cross(pa, A, na) >= 0) return cross(A, na, p) >= 0 && cross(pa, A, p) >= 0;
    return cross(A, na, p) >= 0 || cross(pa, A, p) >= 0;
}

/* The outer-ring node to bridge hole node h to (outer: any node of the ring). */
static uint32_t hole_bridge(const pnode *n, uint32_t outer, uint32_t h)
{
    const pnode *H = &n[h];
    double best_x = INFINITY, tan_min = INFINITY, dist_min = INFINITY;
    uint32_t p = outer, m = UINT32_MAX, best;
    /* the nearest edge the ray from H to +x meets; m its end of larger x */
    do {
        const pnode *a = &n[p], *b = &n[n[p].next];
        if (a->y <= H->y && b->y >= H->y && b->y != a->y) {
            double x = a->x + (H->y - a->y) * (b->x - a->x) / (b->y - a->y);
            if (x >= H->x && x < best_x) {
                best_x = x;
                m = a->x > b->x ? p : n[p].next;
                if (x == a->x && a->y == H->y) m = p;
                if (x == b->x && b->y == H->y) m = n[p].next;
            }
        }
        p = n[p].next;
    } while (p != outer);
    if (m == UINT32_MAX) { /* no edge to the right (broken input): the nearest node */
        p = outer;
        do {
            double dx = n[p].x - H->x, dy = n[p].y - H->y, d = dx * dx + dy * dy;
            if (d < dist_min) dist_min = d, m = p;
            p = n[p].next;
        } while (p != outer);
        return m;
    }
    /* a node inside the triangle (H, hit point, m) would hide m: take the one of smallest
     * angle to the ray, then the nearest, among those whose wedge holds H */
    pnode I = {best_x, H->y, 0, 0, 0};
    best = locally_inside(n, m, H) ? m : UINT32_MAX;
    if (best != UINT32_MAX) {
        tan_min = fabs(n[m].y - H->y) / (n[m].x - H->x > 0 ? n[m].x - H->x : 1e-300);
        dist_min = (n[m].x - H->x) * (n[m].x - H->x) + (n[m].y - H->y) * (n[m].y - H->y);
    }
    p = outer;
    do {
        const pnode *P = &n[p];
        if (P->x >= H->x && in_triangle(H, &I, &n[m], P) && locally_inside(n, p, H)) {
            double dx = P->x - H->x, t = fabs(P->y - H->y) / (dx > 0 ? dx : 1e-300);
            double d = dx * dx + (P->y - H->y) * (P->y - H->y);
            if (t < tan_min || (t == tan_min && d < dist_min)) {
                best = p;
                tan_min = t;
                dist_min = d;
            }
        }
        p = n[p].next;
    } while (p != outer);
    return best != UINT32_MAX ? best : m;
}

/* Joins the ring of node b into the ring of node a by the bridge a-b and back, adding the two
 * copies at n[*nn], n[*nn + 1]. */
static void splice(pnode *n, size_t *nn, uint32_t a, uint32_t b)
{
    uint32_t a2 = (uint32_t)(*nn)++, b2 = (uint32_t)(*nn)++;
    uint32_t an = n[a].next, bp = n[b].prev;
    n[a2] = n[a];
    n[b2] = n[b];
    n[a].next = b;
    n[b].prev = a;
    n[a2].next = an;
    n[an].prev = a2;
    n[b2].next = a2;
    n[a2].prev = b2;
    n[bp].next = b2;
    n[b2].prev = bp;
}

/* Node ear can be clipped: convex, and its triangle holds no reflex or flat node. */
static int is_ear(const pnode *n, uint32_t ear)
{
    const pnode *a = &n[n[ear].prev], *b = &n[ear], *c = &n[n[ear].next];
    if (cross(a, b, c) <= 0) return 0;
    for (uint32_t p = n[n[ear].next].next; p != n[ear].prev; p = n[p].next) {
        const pnode *P = &n[p];
        if (same_point(P, a) || same_point(P, b) || same_point(P, c)) continue;
        if (cross(&n[P->prev], P, &n[P->next]) > 0) continue; /* convex: never alone inside */
        if (in_triangle(a, b, c, P)) return 0;
    }
    return 1;
}

/* Clips ears off the ring of node start (count nodes) into out. */
static void clip_ears(pnode *n, uint32_t start, size_t count, tri_buf *out)
{
    uint32_t ear = start, stop = start;
    while (count > 3 && !out->failed) {
        uint32_t pick = UINT32_MAX;
        if (is_ear(n, ear)) {
            pick = ear;
        } else {
            ear = n[ear].next;
            if (ear != stop) continue;
            /* a whole pass without an ear: a flat corner, else a convex one, else this one */
            uint32_t p = ear;
            do {
                double c = cross(&n[n[p].prev], &n[p], &n[n[p].next]);
                if (c == 0 && pick == UINT32_MAX) pick = p;
                p = n[p].next;
            } while (p != ear);
            if (pick == UINT32_MAX) {
                do {
                    if (cross(&n[n[p].prev], &n[p], &n[n[p].next]) > 0) {
                        pick = p;
                        break;
                    }
                    p = n[p].next;
                } while (p != ear);
            }
            if (pick == UINT32_MAX) pick = ear;
        }
        uint32_t a = n[pick].prev, c = n[pick].next;
        tri_add(out, n[a].v, n[pick].v, n[c].v);
        n[a].next = c;
        n[c].prev = a;
        count--;
        ear = stop = c;
    }
    if (count == 3) tri_add(out, n[n[ear].prev].v, n[ear].v, n[n[ear].next].v);
}

static double ring_area2(const pnode *n, uint32_t start)
{
    double s = 0;
    uint32_t p = start;
    do {
        const pnode *a = &n[p], *b = &n[a->next];
        s += (a->x - n[start].x) * (b->y - n[start].y) - (b->x - n[start].x) * (a->y - n[start].y);
        p = a->next;
    } while (p != start);
    return s;
}

/* Newell normal of ring r (unnormalized). */
static void ring_normal(const api_result *m, size_t r, double nrm[3])
{
    const uint32_t *v = m->idx + m->ring_off[r];
    size_t k = m->ring_off[r + 1] - m->ring_off[r];
    const double *o = m->V + 3 * (size_t)v[0];
    nrm[0] = nrm[1] = nrm[2] = 0;
    for (size_t i = 0; i < k; i++) {
        const double *x = m->V + 3 * (size_t)v[i], *y = m->V + 3 * (size_t)v[(i + 1) % k];
        double dx[3] = {x[0] - o[0], x[1] - o[1], x[2] - o[2]};
        double dy[3] = {y[0] - o[0], y[1] - o[1], y[2] - o[2]};
        nrm[0] += dx[1] * dy[2] - dx[2] * dy[1];
        nrm[1] += dx[2] * dy[0] - dx[0] * dy[2];
        nrm[2] += dx[0] * dy[1] - dx[1] * dy[0];
    }
}

typedef struct hole_ref {
    uint32_t node; /* its rightmost node */
    double x;
} hole_ref;

static int cmp_hole(const void *pa, const void *pb)
{
    const hole_ref *a = pa, *b = pb;
    if (a->x != b->x) return a->x > b->x ? -1 : 1;
    return (a->node > b->node) - (a->node < b->node);
}

/* Triangulates face f into out, triangles oriented like the face (its outer ring's normal).
 * n and holes are scratch of room for the face's ring vertices + 2 per hole, and its holes. */
static void triangulate_face(const api_result *m, size_t f, pnode *n, hole_ref *holes, tri_buf *out)
{
    size_t r0 = m->face_ring[f], r1 = m->face_ring[f + 1], nn = 0, nh = 0, count = 0;
    double nrm[3];
    int k = 0, u, w, flip;
    uint32_t outer = 0;
    if (m->ring_off[r0 + 1] - m->ring_off[r0] < 3) return;
    ring_normal(m, r0, nrm);
    for (int a = 1; a < 3; a++)
        if (fabs(nrm[a]) > fabs(nrm[k])) k = a;
    if (!(fabs(nrm[k]) > 0)) return; /* no area: nothing to draw */
    u = (k + 1) % 3;
    w = (k + 2) % 3;
    flip = nrm[k] < 0;
    for (size_t r = r0; r < r1; r++) {
        const uint32_t *v = m->idx + m->ring_off[r];
        size_t len = m->ring_off[r + 1] - m->ring_off[r], first = nn;
        if (len < 3) continue; /* encloses nothing */
        for (size_t i = 0; i < len; i++) {
            const double *x = m->V + 3 * (size_t)v[i];
            n[nn] =
                (pnode){flip ? -x[u] : x[u], x[w], v[i], (uint32_t)(i ? nn - 1 : first + len - 1),
                        (uint32_t)(i + 1 < len ? nn + 1 : first)};
            nn++;
        }
        double a2 = ring_area2(n, (uint32_t)first);
        if (r == r0 ? a2 < 0 : a2 > 0) /* outer counter-clockwise, holes clockwise */
            for (size_t i = first; i < nn; i++) {
                uint32_t t = n[i].prev;
                n[i].prev = n[i].next;
                n[i].next = t;
            }
        if (r == r0) {
            outer = (uint32_t)first;
            count += len;
            continue;
        }
        uint32_t right = (uint32_t)first;
        for (size_t i = first; i < nn; i++)
            if (n[i].x > n[right].x || (n[i].x == n[right].x && n[i].y < n[right].y))
                right = (uint32_t)i;
        holes[nh++] = (hole_ref){right, n[right].x};
        count += len + 2;
    }
    qsort(holes, nh, sizeof *holes, cmp_hole);
    for (size_t h = 0; h < nh; h++) {
        uint32_t b = hole_bridge(n, outer, holes[h].node);
        splice(n, &nn, b, holes[h].node);
    }
    clip_ears(n, outer, count, out);
}

/* ---- OBJ ------------------------------------------------------------------------------------- */

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

/* The triangle j of signed face s as it faces out of the cell: vertex ids in t[0..3). */
static void cell_triangle(const tri_buf *tb, const size_t *toff, int32_t s, size_t j, uint32_t t[3])
{
    const uint32_t *x = tb->t + 3 * (toff[(size_t)llabs(s) - 1] + j);
    t[0] = x[0];
    t[1] = s > 0 ? x[1] : x[2];
    t[2] = s > 0 ? x[2] : x[1];
}

/* Translation of cell c by explode k: (k - 1) * (centroid - centre). */
static void cell_shift(const api_result *m, const ocells *cl, const tri_buf *tb, const size_t *toff,
                       size_t c, double k, const double *centre, double *shift)
{
    double vol6 = 0, acc[3] = {0, 0, 0}, mean[3] = {0, 0, 0}, cnt = 0, cen[3];
    for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++) {
        int32_t s = cl->cf[i];
        size_t f = (size_t)llabs(s) - 1;
        for (size_t j = 0; j < toff[f + 1] - toff[f]; j++) {
            uint32_t t[3];
            double p[3][3];
            cell_triangle(tb, toff, s, j, t);
            for (int q = 0; q < 3; q++)
                for (int a = 0; a < 3; a++) {
                    p[q][a] = m->V[3 * (size_t)t[q] + a] - centre[a];
                    mean[a] += p[q][a];
                }
            cnt += 3;
            double v = p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) -
                       p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
                       p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
            vol6 += v;
            for (int a = 0; a < 3; a++) acc[a] += v * (p[0][a] + p[1][a] + p[2][a]) / 4;
        }
    }
    for (int a = 0; a < 3; a++) {
        if (vol6 > 0 && isfinite(vol6))
            cen[a] = acc[a] / vol6;
        else
            cen[a] = cnt > 0 ? mean[a] / cnt : 0;
        shift[a] = (k - 1) * cen[a];
        if (!isfinite(shift[a])) shift[a] = 0;
    }
}

/* Numbers the vertices of cell c's triangles in the order they first appear: local[v] (all
 * UINT32_MAX on entry; the caller resets those in list) and list[0..n); returns n. */
static size_t cell_vertices(const ocells *cl, const tri_buf *tb, const size_t *toff, size_t c,
                            uint32_t *local, uint32_t *list)
{
    size_t nl = 0;
    for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++) {
        size_t f = (size_t)llabs(cl->cf[i]) - 1;
        for (size_t j = 0; j < toff[f + 1] - toff[f]; j++) {
            uint32_t t[3];
            cell_triangle(tb, toff, cl->cf[i], j, t);
            for (int q = 0; q < 3; q++)
                if (local[t[q]] == UINT32_MAX) {
                    local[t[q]] = (uint32_t)nl;
                    list[nl++] = t[q];
                }
        }
    }
    return nl;
}

static int obj_write(const api_result *m, const ocells *cl, const render_opts *o, api_buf *b,
                     api_error *err)
{
    tri_buf tb = {0};
    size_t *toff = malloc((m->nf + 1) * sizeof *toff), maxn = 0, maxh = 0;
    pnode *scratch = NULL;
    hole_ref *holes = NULL;
    uint32_t *local = NULL, *list = NULL;
    double centre[3] = {0, 0, 0}, zero[3] = {0, 0, 0};
    int explode = o->explode > 1, rc = API_OK;
    if (!toff) goto nomem;
    for (size_t f = 0; f < m->nf; f++) {
        size_t r0 = m->face_ring[f], r1 = m->face_ring[f + 1];
        size_t n = m->ring_off[r1] - m->ring_off[r0] + 2 * (r1 - r0);
        if (n > maxn) maxn = n;
        if (r1 - r0 > maxh) maxh = r1 - r0;
    }
    scratch = malloc((maxn + 1) * sizeof *scratch);
    holes = malloc((maxh + 1) * sizeof *holes);
    if (!scratch || !holes) goto nomem;
    for (size_t f = 0; f < m->nf; f++) {
        toff[f] = tb.n;
        triangulate_face(m, f, scratch, holes, &tb);
    }
    toff[m->nf] = tb.n;
    if (tb.failed) goto nomem;

    api_buf_puts(b, "# cellar: ");
    api_buf_u64(b, cl->nc);
    api_buf_puts(b, " cells, ");
    api_buf_u64(b, m->nf);
    api_buf_puts(b, " faces, ");
    api_buf_u64(b, m->nv);
    api_buf_puts(b, " vertices\n");
    if (!explode) {
        for (size_t v = 0; v < m->nv; v++) put_vertex(b, m->V + 3 * v, zero);
        for (size_t c = 0; c < cl->nc; c++) {
            api_buf_puts(b, cl->result ? "g result" : "g cell");
            if (!cl->result) api_buf_u64(b, c);
            api_buf_putc(b, '\n');
            for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++) {
                size_t f = (size_t)llabs(cl->cf[i]) - 1;
                for (size_t j = 0; j < toff[f + 1] - toff[f]; j++) {
                    uint32_t t[3];
                    cell_triangle(&tb, toff, cl->cf[i], j, t);
                    put_face(b, (uint64_t)t[0] + 1, (uint64_t)t[1] + 1, (uint64_t)t[2] + 1);
                }
            }
        }
        goto out;
    }
    /* exploded: each cell its own vertices (in the order its triangles first use them), all
     * the vertices first, then the groups */
    local = malloc((m->nv + 1) * sizeof *local);
    list = malloc((m->nv + 1) * sizeof *list);
    if (!local || !list) goto nomem;
    for (size_t v = 0; v < m->nv; v++) local[v] = UINT32_MAX;
    if (m->nv) {
        double lo[3], hi[3];
        for (int a = 0; a < 3; a++) lo[a] = hi[a] = m->V[a];
        for (size_t v = 1; v < m->nv; v++)
            for (int a = 0; a < 3; a++) {
                lo[a] = fmin(lo[a], m->V[3 * v + a]);
                hi[a] = fmax(hi[a], m->V[3 * v + a]);
            }
        for (int a = 0; a < 3; a++) centre[a] = lo[a] / 2 + hi[a] / 2;
    }
    for (size_t c = 0; c < cl->nc; c++) {
        double shift[3];
        size_t nl = cell_vertices(cl, &tb, toff, c, local, list);
        cell_shift(m, cl, &tb, toff, c, o->explode, centre, shift);
        for (size_t i = 0; i < nl; i++) {
            put_vertex(b, m->V + 3 * (size_t)list[i], shift);
            local[list[i]] = UINT32_MAX;
        }
    }
    uint64_t base = 0;
    for (size_t c = 0; c < cl->nc; c++) {
        size_t nl = cell_vertices(cl, &tb, toff, c, local, list);
        api_buf_puts(b, "g cell");
        api_buf_u64(b, c);
        api_buf_putc(b, '\n');
        for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++) {
            size_t f = (size_t)llabs(cl->cf[i]) - 1;
            for (size_t j = 0; j < toff[f + 1] - toff[f]; j++) {
                uint32_t t[3];
                cell_triangle(&tb, toff, cl->cf[i], j, t);
                put_face(b, base + local[t[0]] + 1, base + local[t[1]] + 1, base + local[t[2]] + 1);
            }
        }
        for (size_t i = 0; i < nl; i++) local[list[i]] = UINT32_MAX;
        base += nl;
    }
    goto out;
nomem:
    rc = api_fail(err, API_ENOMEM, "out of memory writing the OBJ");
out:
    free(toff);
    free(tb.t);
    free(scratch);
    free(holes);
    free(local);
    free(list);
    return rc;
}

int render_obj(const char *result_json, size_t len, const render_opts *o, char **out,
               size_t *outlen, api_error *err)
{
    render_opts def = RENDER_OPTS_INIT;
    api_result m;
    ocells cl;
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
    cl = (ocells){m.nc, m.cell_off, m.cf, 0};
    if (m.has_result) { /* a Boolean result: its boundary is the one solid written */
        one[0] = 0;
        one[1] = m.nres_faces;
        cl = (ocells){1, one, m.res_faces, 1};
    }
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
