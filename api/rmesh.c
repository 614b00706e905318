/* rmesh.c — the faces of a 3D result (LAR JSON, dim 3) as triangles, for the mesh writers
 * (render_obj.c: OBJ; render_mesh.c: STL, OFF, 3MF, glTF binary).  See rmesh.h.
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
 *
 * Geometry here is floating point: for pictures and meshes, not for the complex.  It is not a
 * copy of the exact clipper of the 3D input (core/arr3.c's a3_triangulate): that one decides on
 * the integer grid, bridges to the nearest visible vertex, splits pinched loops and fails when
 * no ear is left; this one reads a written result's doubles and must always end.  The two give
 * different triangles, and every written mesh's bytes depend on these.
 *
 * Threads: reentrant, no globals.  Ownership: rmesh.h.
 */
#include "api/rmesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/mem.h"

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
    if (mem_grow(&b->t, &b->cap, b->n + 1, 3 * sizeof *b->t)) {
        b->failed = 1;
        return;
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

int rmesh_make(const api_result *m, rmesh *rm, api_error *err)
{
    tri_buf tb = {0};
    size_t maxn = 0, maxh = 0;
    pnode *scratch = NULL;
    hole_ref *holes = NULL;
    *rm = (rmesh){0};
    rm->m = m;
    rm->toff = malloc((m->nf + 1) * sizeof *rm->toff);
    if (!rm->toff) goto nomem;
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
        rm->toff[f] = tb.n;
        triangulate_face(m, f, scratch, holes, &tb);
    }
    rm->toff[m->nf] = tb.n;
    if (tb.failed) goto nomem;
    free(scratch);
    free(holes);
    rm->t = tb.t;
    rm->nt = tb.n;
    return API_OK;
nomem:
    free(scratch);
    free(holes);
    free(tb.t);
    rmesh_free(rm);
    return api_fail(err, API_ENOMEM, "out of memory triangulating the faces");
}

void rmesh_free(rmesh *rm)
{
    free(rm->t);
    free(rm->toff);
    *rm = (rmesh){0};
}

rmesh_cells rmesh_cells_of(const api_result *m, size_t one[2])
{
    if (!m->has_result) return (rmesh_cells){m->nc, m->cell_off, m->cf, 0};
    one[0] = 0;
    one[1] = m->nres_faces;
    return (rmesh_cells){1, one, m->res_faces, 1};
}

void rmesh_centre(const api_result *m, double centre[3])
{
    double lo[3], hi[3];
    centre[0] = centre[1] = centre[2] = 0;
    if (!m->nv) return;
    for (int a = 0; a < 3; a++) lo[a] = hi[a] = m->V[a];
    for (size_t v = 1; v < m->nv; v++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], m->V[3 * v + a]);
            hi[a] = fmax(hi[a], m->V[3 * v + a]);
        }
    for (int a = 0; a < 3; a++) centre[a] = lo[a] / 2 + hi[a] / 2;
}

void rmesh_triangle(const rmesh *rm, int32_t s, size_t j, uint32_t t[3])
{
    const uint32_t *x = rm->t + 3 * (rm->toff[(size_t)llabs(s) - 1] + j);
    t[0] = x[0];
    t[1] = s > 0 ? x[1] : x[2];
    t[2] = s > 0 ? x[2] : x[1];
}

size_t rmesh_ntri(const rmesh *rm, int32_t s)
{
    size_t f = (size_t)llabs(s) - 1;
    return rm->toff[f + 1] - rm->toff[f];
}

void rmesh_cell_shift(const rmesh *rm, const rmesh_cells *cl, size_t c, double k,
                      const double *centre, double *shift)
{
    const api_result *m = rm->m;
    double vol6 = 0, acc[3] = {0, 0, 0}, mean[3] = {0, 0, 0}, cnt = 0, cen[3];
    for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++) {
        int32_t s = cl->cf[i];
        for (size_t j = 0, nj = rmesh_ntri(rm, s); j < nj; j++) {
            uint32_t t[3];
            double p[3][3];
            rmesh_triangle(rm, s, j, t);
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

size_t rmesh_cell_vertices(const rmesh *rm, const rmesh_cells *cl, size_t c, uint32_t *local,
                           uint32_t *list, size_t nl)
{
    for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++)
        for (size_t j = 0, nj = rmesh_ntri(rm, cl->cf[i]); j < nj; j++) {
            uint32_t t[3];
            rmesh_triangle(rm, cl->cf[i], j, t);
            for (int q = 0; q < 3; q++)
                if (local[t[q]] == UINT32_MAX) {
                    local[t[q]] = (uint32_t)nl;
                    list[nl++] = t[q];
                }
        }
    return nl;
}

size_t rmesh_cell_ntri(const rmesh *rm, const rmesh_cells *cl, size_t c)
{
    size_t n = 0;
    for (size_t i = cl->off[c]; i < cl->off[c + 1]; i++) n += rmesh_ntri(rm, cl->cf[i]);
    return n;
}
