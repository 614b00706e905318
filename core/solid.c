/* solid.c — solids given as face models (core/solid.h): checking them, and reading them from
 * Wavefront OBJ and OFF text.
 *
 * solid_check runs in stages, each a function below:
 *   shape     the offset arrays are well formed, every index is in range, every coordinate is
 *             finite and small enough for the grid.  A failure here stops the check: nothing
 *             after it could be trusted.
 *   merge     every vertex is snapped to the grid of step `precision` (llround of x / precision,
 *             halves away from zero: exactly core/arr3.c's rule), and vertices on the same grid
 *             point are one (a hash): the merged vertex is the smallest input index among them.  We
 * chose the grid over a sorted sweep with a distance test because the grid is what the 3D
 *             pipeline's unification does with the same solid, and because it never chains
 *             merges (a, b, c each within the precision of the next, a far from c).  The price,
 *             paid knowingly: two vertices closer than the precision on either side of a pixel
 *             border stay two — exactly as they will in the pipeline.  Merging is for the
 *             checks only: the fixed copy keeps the input's vertices and cycles.
 *   faces     per cycle, the steps between consecutive merged vertices that differ (a step
 *             between merged-equal vertices is no edge).  A cycle needs 3 distinct merged
 *             vertices.  The Newell normal of the outer cycle gives the plane and the area;
 *             a face is zero-area when its area is at most precision * (box diagonal) / 2 — a
 *             triangle whose height is one grid step — an error; and a face one of whose
 *             vertices (of any cycle) is farther than the precision from the plane through the
 *             mean of its vertices gets a warning, "not planar ...: split into triangles": the
 *             3D pipeline splits every face that is not exactly planar on the grid (see
 *             core/arr3.h), and says so here only where the input is not planar within the
 *             precision, which a user would want to know.
 *             Then each face as the 3D pipeline will take it (merged vertices, no step
 *             between equal ones) is checked exactly on the grid by face_check
 *             (core/facecheck.h): a polygon with holes in its plane, or in the projection a
 *             face that is not planar on the grid is triangulated in; a triangle is one.
 *   edges     the half-edges, keyed by their undirected merged vertex pair, are sorted (qsort,
 *             n log n): a key used once is an open edge, more than twice a non-manifold one.
 *   orient    faces paired across each manifold edge must walk it in opposite directions.  A
 *             breadth-first walk over that adjacency (a queue, no recursion) finds per
 *             connected surface the flips that make it consistent, or proves none exists.
 *             Each surface keeps the orientation most of its input faces have.
 *             Orientation and volume are only looked at on a closed manifold surface: after
 *             an open or non-manifold edge they would report noise.
 *   volume    divergence theorem: per cycle, the fan about its first vertex, triple products
 *             taken about the centre of the solid's box (exact for small dyadic coordinates:
 *             the unit cube gives 1, not 0.9999...), holes included with their own direction.
 *             A volume of at most precision * area / 2 (the solid is on average no thicker
 *             than one grid step) is an error; a negative one flips every face.
 * Messages name faces and vertices by their 0-based input indices, as the arrays hold them.
 *
 * Readers: one solid, each face one cycle (neither format has holes), 0-based indices.  OBJ:
 * "v" takes 3 to 7 numbers (x y z, then w or a colour, ignored); an "f" index counts from 1,
 * or back from the last vertex read when negative (no forward references); every other
 * statement is skipped.  OFF: extra numbers after a vertex (colour, normal) and up to 4 after
 * a face (its colour) are skipped; nothing but comments may follow the last face.
 * Limits (a reader refuses more): SOLID_MAX_VERTICES vertices, SOLID_MAX_FACES faces,
 * SOLID_MAX_FACE_LEN vertices in one face.  Arrays grow with the data actually read, never
 * with a count the text announces: OFF's counts are believed only after checking that the
 * bytes left could hold that many lines, so "OFF\n1000000 1000000 0" costs nothing.
 * Numbers are decimal (digits, sign, point, exponent: no "nan", "inf" or hex) and finite,
 * converted correctly rounded by core/fastfloat.h (strtod's double, whatever the process
 * locale).
 *
 * Threads: reentrant, no globals.  Ownership: inputs borrowed; outputs freed with solid_free().
 * Bounds: O(n log n) time (sorts), O(n) memory in the total length of the cycles; no recursion.
 */
#include "core/solid.h"

#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/facecheck.h"
#include "core/mem.h"
#include "core/num.h"
#include "core/fastfloat.h"

#define SOLID_MAX_VERTICES 64000000u /* a reader's limits, see above */
#define SOLID_MAX_FACES    64000000u
#define SOLID_MAX_FACE_LEN 1000000u
#define NUMBER_MAX         128 /* longest number token a reader takes */
#define NONE               UINT32_MAX

void solid_free(solid *s)
{
    if (!s) return;
    free(s->V);
    free(s->face_off);
    free(s->cyc_off);
    free(s->cyc);
    memset(s, 0, sizeof *s);
}

/* ---- check: messages ------------------------------------------------------------------ */

/* 16 bytes, since the check sorts one per entry of the cycles: its input end vertices are
 * read back from the cycles (half_a, half_b) where a message or a rare case needs them. */
typedef struct half {
    uint64_t key;       /* min << 32 | max of the merged end vertices */
    uint32_t ent;       /* its entry in the cycles (cyc[ent] is its start) */
    uint32_t face : 31; /* the face walking it (check_shape: fewer than 2^31 faces) */
    uint32_t fwd : 1;   /* 1 when the face walks it from the smaller merged vertex to the larger */
} half;

typedef struct ck {
    const solid *s;
    double p; /* precision */
    solid_report *rep;
    const char *label;
    int faces_only;   /* a face soup: no closedness, any orientation */
    int tri;          /* every face one cycle of 3 entries: face f's are 3 f .. 3 f + 2 */
    uint32_t *merged; /* nv: the merged vertex of each input vertex */
    int64_t *g;       /* 3 * nv: the grid point of each input vertex */
    double area;      /* the faces' outer cycles' areas, summed in face order */
    double ref[3];    /* the centre of the vertices' box (check_shape) */
    double vol6;      /* six times the volume about ref, every face as given (check_faces) */
    half *he;         /* half-edges, sorted by key */
    size_t nhe;
    uint32_t *pair; /* npair: index in he of the first of the two halves of a manifold edge */
    size_t npair;
    signed char *flip; /* nf: 1 when the fixed copy reverses the face */
    size_t flips;      /* how many (orient) */
    uint32_t *multi;   /* nmulti: the first half of each edge on more than 2 faces taken unpaired
                          (check_edges), its last in he: until the key changes */
    size_t nmulti, capmulti;
} ck;

/* Records a message: error or warning, about the whole solid (at SOLID_AT_SOLID), face `index`
 * or vertex `index`.  The text is "label: face 5: what" (or "vertex 5: ", or nothing); info
 * says the same as fields, so that callers never read the text to tell them apart. */
__attribute__((format(printf, 6, 7))) static void note_at(ck *c, int error, int at, size_t index,
                                                          size_t sub, const char *fmt, ...);
#define note(c, error, at, index, ...) note_at(c, error, at, index, 0, __VA_ARGS__)

__attribute__((format(printf, 6, 7))) static void note_at(ck *c, int error, int at, size_t index,
                                                          size_t sub, const char *fmt, ...)
{
    solid_report *r = c->rep;
    if (error)
        r->errors++;
    else
        r->warnings++;
    /* the last place is kept for the first error, so that warnings never hide it */
    if (r->nmsg + (!error && r->errors == 0) >= SOLID_MAX_MESSAGES) return;
    solid_msg_info *in = &r->info[r->nmsg];
    char *m = r->msg[r->nmsg++];
    size_t cap = sizeof r->msg[0];
    int k = snprintf(m, cap, "%s: ", c->label);
    in->warning = !error;
    in->at = (uint8_t)at;
    in->index = index;
    in->sub = sub;
    if (k >= 0 && (size_t)k < cap && at == SOLID_AT_HOLE)
        k += snprintf(m + k, cap - (size_t)k, "face %zu: hole %zu: ", index, sub + 1);
    else if (k >= 0 && (size_t)k < cap && at != SOLID_AT_SOLID)
        k += snprintf(m + k, cap - (size_t)k, "%s %zu: ", at == SOLID_AT_FACE ? "face" : "vertex",
                      index);
    if (k < 0 || (size_t)k >= cap) {
        in->what = (uint16_t)(cap - 1);
        return;
    }
    in->what = (uint16_t)k;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(m + k, cap - (size_t)k, fmt, ap);
    va_end(ap);
}

static const double *vert(const ck *c, uint32_t v)
{
    return c->s->V + 3 * (size_t)v;
}

/* The input vertices half h walks from (a) and to (b): its entry and the next in its cycle. */
static uint32_t half_a(const ck *c, const half *h)
{
    return c->s->cyc[h->ent];
}

static uint32_t half_b(const ck *c, const half *h)
{
    const solid *s = c->s;
    for (uint32_t k = s->face_off[h->face]; k < s->face_off[h->face + 1]; k++)
        if (h->ent >= s->cyc_off[k] && h->ent < s->cyc_off[k + 1])
            return s->cyc[h->ent + 1 < s->cyc_off[k + 1] ? h->ent + 1 : s->cyc_off[k]];
    return s->cyc[h->ent]; /* not reached: the entry is in one of its face's cycles */
}

/* ---- check: shape --------------------------------------------------------------------- */

/* The arrays must describe what solid.h says; -1 (with one error) when they do not. */
static int check_shape(ck *c)
{
    const solid *s = c->s;
    if (s->nf == 0) {
        note(c, 1, SOLID_AT_SOLID, 0, "no faces");
        return -1;
    }
    if (s->nv > NONE || s->ncyc >= NONE || s->nf > s->ncyc || s->nf > 0x7fffffffu || !s->face_off ||
        !s->cyc_off || (s->nv && !s->V)) {
        note(c, 1, SOLID_AT_SOLID, 0,
             "malformed solid (counts %zu V, %zu faces, %zu cycles, or missing arrays)", s->nv,
             s->nf, s->ncyc);
        return -1;
    }
    if (s->face_off[0] != 0 || s->face_off[s->nf] != s->ncyc || s->cyc_off[0] != 0) {
        note(c, 1, SOLID_AT_SOLID, 0,
             "malformed solid (face_off or cyc_off do not start at 0 and end at ncyc)");
        return -1;
    }
    for (size_t f = 0; f < s->nf; f++)
        if (s->face_off[f + 1] <= s->face_off[f]) {
            note(c, 1, SOLID_AT_FACE, f, "malformed (no outer cycle)");
            return -1;
        }
    for (size_t k = 0; k < s->ncyc; k++)
        if (s->cyc_off[k + 1] < s->cyc_off[k]) {
            note(c, 1, SOLID_AT_SOLID, 0, "malformed solid (cyc_off decreases at cycle %zu)", k);
            return -1;
        }
    if (s->cyc_off[s->ncyc] && !s->cyc) {
        note(c, 1, SOLID_AT_SOLID, 0, "malformed solid (no cyc array)");
        return -1;
    }
    int bad = 0;
    c->tri = s->nf == s->ncyc;
    for (size_t k = 1; c->tri && k <= s->ncyc; k++) c->tri = s->cyc_off[k] == 3 * k;
    if (c->tri) { /* a mesh of triangles: one pass over the indices, the face found on a fault */
        uint32_t far = 0, nv = (uint32_t)s->nv;
        for (size_t i = 0; i < 3 * s->nf; i++) far |= s->cyc[i] >= nv;
        if (!far) goto vertices;
    }
    for (size_t f = 0; f < s->nf; f++)
        for (uint32_t i = s->cyc_off[s->face_off[f]]; i < s->cyc_off[s->face_off[f + 1]]; i++)
            if (s->cyc[i] >= s->nv) {
                note(c, 1, SOLID_AT_FACE, f, "vertex index %u out of range (%zu vertices)",
                     s->cyc[i], s->nv);
                bad = 1;
                break;
            }
vertices:;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < s->nv; v++) {
        const double *x = vert(c, (uint32_t)v);
        for (int a = 0; a < 3; a++) {
            lo[a] = x[a] < lo[a] ? x[a] : lo[a];
            hi[a] = x[a] > hi[a] ? x[a] : hi[a];
        }
        for (int a = 0; a < 3; a++)
            if (!isfinite(x[a])) {
                note(c, 1, SOLID_AT_VERTEX, v, "coordinate %d is not finite", a);
                bad = 1;
                break;
            } else if (!(fabs(x[a]) / c->p < SOLID_GRID_RANGE)) {
                note(c, 1, SOLID_AT_VERTEX, v, "coordinate %.17g is too large for precision %g",
                     x[a], c->p);
                bad = 1;
                break;
            }
    }
    for (int a = 0; a < 3; a++) c->ref[a] = (lo[a] + hi[a]) / 2;
    return bad ? -1 : 0;
}

/* ---- check: merge --------------------------------------------------------------------- */

/* Grid point -> the first vertex on it: open addressing over the vertices' grid points. */
static uint64_t gmix(const int64_t *g)
{
    uint64_t h = (uint64_t)g[0] * 0x9e3779b97f4a7c15ULL;
    h ^= (uint64_t)g[1] * 0xc2b2ae3d27d4eb4fULL + (h << 6) + (h >> 2);
    h ^= (uint64_t)g[2] * 0x165667b19e3779f9ULL + (h << 6) + (h >> 2);
    h ^= h >> 31;
    return h * 0xff51afd7ed558ccdULL;
}

/* The merged vertex of each vertex: the smallest index on its grid point (llround of x / p,
 * the rule of core/arr3.c, so that both see the same vertices). */
static int merge_vertices(ck *c)
{
    size_t nv = c->s->nv, cap = 16;
    while (cap < 2 * nv + 2) cap *= 2;
    int64_t *g = mem_malloc((nv ? 3 * nv : 1) * sizeof *g);
    uint32_t *tab = mem_malloc(cap * sizeof *tab);
    c->merged = mem_malloc((nv ? nv : 1) * sizeof *c->merged);
    c->g = g;
    if (!g || !tab || !c->merged) goto fail;
    memset(tab, 0xff, cap * sizeof *tab);
    for (size_t v = 0; v < nv; v++) {
        const double *x = vert(c, (uint32_t)v);
        int64_t *gv = g + 3 * v;
        for (int a = 0; a < 3; a++) gv[a] = round_half_away(x[a] / c->p);
        size_t h = gmix(gv) & (cap - 1);
        while (tab[h] != NONE && memcmp(g + 3 * (size_t)tab[h], gv, 3 * sizeof *gv))
            h = (h + 1) & (cap - 1);
        if (tab[h] == NONE) tab[h] = (uint32_t)v;
        c->merged[v] = tab[h];
    }
    free(tab);
    return 0;
fail:
    free(tab);
    return -1;
}

/* ---- check: faces --------------------------------------------------------------------- */

static void sub3(const double *a, const double *b, double *d)
{
    d[0] = a[0] - b[0];
    d[1] = a[1] - b[1];
    d[2] = a[2] - b[2];
}

static void cross3(const double *a, const double *b, double *d)
{
    d[0] = a[1] * b[2] - a[2] * b[1];
    d[1] = a[2] * b[0] - a[0] * b[2];
    d[2] = a[0] * b[1] - a[1] * b[0];
}

/* Number of distinct merged vertices of cycle k, counted up to 3. */
static int cycle_distinct(const ck *c, size_t k)
{
    const uint32_t *cy = c->s->cyc;
    uint32_t lo = c->s->cyc_off[k], hi = c->s->cyc_off[k + 1];
    if (lo == hi) return 0;
    uint32_t u0 = c->merged[cy[lo]], u1 = NONE;
    for (uint32_t i = lo + 1; i < hi; i++) {
        uint32_t u = c->merged[cy[i]];
        if (u == u0 || u == u1) continue;
        if (u1 != NONE) return 3;
        u1 = u;
    }
    return u1 == NONE ? 1 : 2;
}

/* Do the vertices of cycle k lie on one line on the grid (c->g: llround of x / p, exact)? */
static int collinear_on_grid(const ck *c, size_t k)
{
    const uint32_t *cy = c->s->cyc;
    uint32_t lo = c->s->cyc_off[k], hi = c->s->cyc_off[k + 1];
    const int64_t *g0 = c->g + 3 * (size_t)cy[lo];
    int64_t d[3] = {0, 0, 0};
    int have_d = 0;
    for (uint32_t i = lo + 1; i < hi; i++) {
        const int64_t *gi = c->g + 3 * (size_t)cy[i];
        int64_t e[3];
        for (int a = 0; a < 3; a++) {
            e[a] = gi[a] - g0[a];
            if (e[a] > ((int64_t)1 << 61) || e[a] < -((int64_t)1 << 61)) return 0; /* too far */
        }
        if (!e[0] && !e[1] && !e[2]) continue;
        if (!have_d) {
            memcpy(d, e, sizeof d);
            have_d = 1;
            continue;
        }
        /* cross(d, e) == 0, in 128 bits (|d|, |e| < 2^61: products below 2^122) */
        if ((__int128)d[1] * e[2] != (__int128)d[2] * e[1] ||
            (__int128)d[2] * e[0] != (__int128)d[0] * e[2] ||
            (__int128)d[0] * e[1] != (__int128)d[1] * e[0])
            return 0;
    }
    return 1;
}

/* collinear_on_grid for a triangle of three distinct grid points t. */
static int tri_collinear_on_grid(const ck *c, const uint32_t *t)
{
    const int64_t *g0 = c->g + 3 * (size_t)t[0], *g1 = c->g + 3 * (size_t)t[1],
                  *g2 = c->g + 3 * (size_t)t[2];
    int64_t d[3], e[3];
    for (int a = 0; a < 3; a++) {
        d[a] = g1[a] - g0[a];
        e[a] = g2[a] - g0[a];
        if (d[a] > ((int64_t)1 << 61) || d[a] < -((int64_t)1 << 61) || e[a] > ((int64_t)1 << 61) ||
            e[a] < -((int64_t)1 << 61))
            return 0; /* too far */
    }
    return (__int128)d[1] * e[2] == (__int128)d[2] * e[1] &&
           (__int128)d[2] * e[0] == (__int128)d[0] * e[2] &&
           (__int128)d[0] * e[1] == (__int128)d[1] * e[0];
}

/* ---- check: a face on the grid (core/facecheck.h) ----------------------------------------- */

/* The cycles of one face as the 3D pipeline sees them: merged vertices, without a step between
 * equal ones; inp keeps an input index of each entry for the messages. */
typedef struct gface {
    uint32_t *ids, *inp, **cyc;
    size_t *len;
    size_t capids, capinp, capcyc, caplen;
    face_work w;
} gface;

static void gface_free(gface *q)
{
    free(q->ids);
    free(q->inp);
    free(q->cyc);
    free(q->len);
    face_work_free(&q->w);
}

static const char AXIS[3] = {'x', 'y', 'z'};

/* The input indices of edge i of cycle k: "a-b". */
static void edge_name(const gface *q, size_t k, size_t i, char *buf, size_t cap)
{
    size_t off = (size_t)(q->cyc[k] - q->ids);
    snprintf(buf, cap, "%u-%u", q->inp[off + i], q->inp[off + (i + 1) % q->len[k]]);
}

static uint32_t entry_inp(const gface *q, size_t k, size_t i)
{
    return q->inp[(size_t)(q->cyc[k] - q->ids) + i];
}

/* Reports what face_check found wrong with face f: an error at the face, or at the hole the
 * problem is about (a hole crossing the outer cycle or another hole: the first such hole). */
static void face_problem(ck *c, size_t f, const gface *q, const face_verdict *v)
{
    char d[256], e1[24], e2[24], pre[64] = "";
    size_t c1 = v->c1, c2 = v->c2;
    uint32_t x1 = entry_inp(q, v->c1, v->i1), x2 = entry_inp(q, v->c2, v->i2);
    edge_name(q, v->c1, v->i1, e1, sizeof e1);
    edge_name(q, v->c2, v->i2, e2, sizeof e2);
    if (c2 < c1) { /* the outer cycle, or the first hole, first */
        size_t t = c1;
        c1 = c2, c2 = t;
    }
    /* the cycle the message is about: c1, or for two cycles the hole among them */
    size_t about = v->what == FACE_HOLE_IN ? v->c1 : c1 == c2 || c1 > 0 ? c1 : c2;
    const char *who = about ? "" : "its outer cycle "; /* the subject, unless the location */
    const char *other = c1 == 0 ? "the outer cycle" : "another hole";
    if (!v->planar) snprintf(pre, sizeof pre, "not planar, and seen along %c ", AXIS[v->axis]);
    switch (v->what) {
    case FACE_FLAT:
        snprintf(d, sizeof d, "zero area (a face with holes whose vertices lie on one line)");
        break;
    case FACE_PROJ_POINT:
        snprintf(d, sizeof d, "vertices %u and %u fall on one point", x1, x2);
        break;
    case FACE_CROSS:
        if (c1 == c2)
            snprintf(d, sizeof d, "%scrosses itself (edges %s and %s)", who, e1, e2);
        else
            snprintf(d, sizeof d, "crosses %s (edges %s and %s)", other, e1, e2);
        break;
    case FACE_OVERLAP:
        if (c1 == c2)
            snprintf(d, sizeof d, "%sruns back along itself (edges %s and %s overlap)", who, e1,
                     e2);
        else
            snprintf(d, sizeof d, "runs along %s (edges %s and %s overlap)", other, e1, e2);
        break;
    case FACE_PINCH:
        if (x1 == x2)
            snprintf(d, sizeof d, "%spasses twice through vertex %u (a pinch)", who, x1);
        else
            snprintf(d, sizeof d, "%spasses twice through one point (vertices %u and %u)", who, x1,
                     x2);
        break;
    case FACE_ON_EDGE:
        if (c1 == c2)
            snprintf(d, sizeof d, "%stouches itself: vertex %u lies inside its edge %s", who, x1,
                     e2);
        else
            snprintf(d, sizeof d,
                     "vertex %u of one cycle lies inside edge %s of another (a T-junction)", x1,
                     e2);
        break;
    case FACE_CROSS_AT:
        snprintf(d, sizeof d, "crosses %s at vertex %u", other, x1);
        break;
    case FACE_HOLE_OUT:
        snprintf(d, sizeof d, "lies outside the outer cycle");
        break;
    case FACE_HOLE_IN:
        snprintf(d, sizeof d, "lies inside another hole (the one through vertex %u)", x2);
        break;
    case FACE_HOLE_TURN:
        snprintf(d, sizeof d, "turns the same way as the outer cycle (holes turn the other way)");
        break;
    default:
        snprintf(d, sizeof d, "not a polygon");
    }
    note_at(c, 1, about ? SOLID_AT_HOLE : SOLID_AT_FACE, f, about ? about - 1 : 0,
            "%s%s on the grid of step %g", pre, d, c->p);
}

/* Face f on the grid: its cycles as the pipeline takes them, checked by face_check.  Returns -1
 * out of memory (else 0; a problem is reported). */
static int check_face_grid(ck *c, size_t f, gface *q)
{
    const solid *s = c->s;
    size_t k0 = s->face_off[f], k1 = s->face_off[f + 1];
    size_t total = s->cyc_off[k1] - s->cyc_off[k0], nc = k1 - k0;
    /* a triangle (not flat: checked before) is a polygon; so is any face of a single cycle of
     * three distinct points */
    if (nc == 1 && total == 3) return 0;
    if (mem_grow(&q->ids, &q->capids, total + 1, sizeof *q->ids) ||
        mem_grow(&q->inp, &q->capinp, total + 1, sizeof *q->inp) ||
        mem_grow(&q->cyc, &q->capcyc, nc, sizeof *q->cyc) ||
        mem_grow(&q->len, &q->caplen, nc, sizeof *q->len))
        return -1;
    size_t n = 0;
    for (size_t k = k0; k < k1; k++) {
        size_t st = n;
        for (uint32_t i = s->cyc_off[k]; i < s->cyc_off[k + 1]; i++) {
            uint32_t m = c->merged[s->cyc[i]];
            if (n > st && q->ids[n - 1] == m) continue;
            q->ids[n] = m;
            q->inp[n++] = s->cyc[i];
        }
        while (n - st > 1 && q->ids[n - 1] == q->ids[st]) n--;
        if (n - st < 3) return 0; /* reported (fewer than 3 distinct) */
        q->len[k - k0] = n - st;
    }
    for (size_t k = 0, off = 0; k < nc; off += q->len[k], k++) q->cyc[k] = q->ids + off;
    if (nc == 1 && q->len[0] == 3) return 0;
    face_cycles fcy = {c->g, nc, (const uint32_t *const *)q->cyc, q->len};
    face_verdict v;
    if (face_check(&fcy, c->faces_only ? 0 : FACE_SOLID, &q->w, &v)) return -1;
    if (v.what == FACE_OK || v.what == FACE_UNCHECKED) return 0;
    if (v.what == FACE_FLAT && nc == 1) return 0; /* left out (warned) */
    face_problem(c, f, q, &v);
    return 0;
}

static double face_volume6(const ck *c, size_t f, const double *ref)
{
    const solid *s = c->s;
    double sum = 0;
    for (size_t k = s->face_off[f]; k < s->face_off[f + 1]; k++) {
        uint32_t lo = s->cyc_off[k], hi = s->cyc_off[k + 1];
        double a[3], b[3], d[3], t[3];
        if (hi - lo < 3) continue; /* reported as degenerate; no volume */
        sub3(vert(c, s->cyc[lo]), ref, a);
        for (uint32_t i = lo + 1; i + 1 < hi; i++) {
            sub3(vert(c, s->cyc[i]), ref, b);
            sub3(vert(c, s->cyc[i + 1]), ref, d);
            cross3(b, d, t);
            sum += a[0] * t[0] + a[1] * t[1] + a[2] * t[2];
        }
    }
    return sum;
}

/* Degenerate cycles, zero area, planarity; sums c->area and c->vol6.  Appends nothing to the
 * topology: a bad face still has its edges, so what it does to its neighbours is reported too. */
static int check_faces(ck *c)
{
    const solid *s = c->s;
    const uint32_t *cy = s->cyc;
    gface q = {0};
    int rc = 0;
    const double *ref = c->ref;
    c->area = c->vol6 = 0;
    for (size_t f = 0; f < s->nf && rc == 0; f++) {
        size_t k0 = s->face_off[f], k1 = s->face_off[f + 1];
        int degenerate = 0;
        if (k1 - k0 == 1 && s->cyc_off[k0 + 1] - s->cyc_off[k0] == 3) {
            /* a triangle: its volume as face_volume6 sums it; three points apart that are not
             * on one line of the grid (collinear_on_grid's test, unrolled) make it planar, and
             * its area is all there is to find */
            const uint32_t *t = cy + s->cyc_off[k0];
            const double *x0 = vert(c, t[0]), *x1 = vert(c, t[1]), *x2 = vert(c, t[2]);
            double a[3], b[3], d[3], n[3];
            sub3(x0, ref, a);
            sub3(x1, ref, b);
            sub3(x2, ref, d);
            cross3(b, d, n);
            c->vol6 += a[0] * n[0] + a[1] * n[1] + a[2] * n[2];
            uint32_t m0 = c->merged[t[0]], m1 = c->merged[t[1]], m2 = c->merged[t[2]];
            if (m0 != m1 && m1 != m2 && m0 != m2 && !tri_collinear_on_grid(c, t)) {
                sub3(x1, x0, a);
                sub3(x2, x0, b);
                cross3(a, b, n);
                c->area += sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 2;
                continue;
            }
        } else {
            c->vol6 += face_volume6(c, f, ref);
        }
        if (k1 - k0 == 1 && (cycle_distinct(c, k0) < 3 || collinear_on_grid(c, k0))) {
            /* a face without holes that the grid flattens onto a line (or a point): it bounds
             * nothing, and the arrangement leaves it out, splitting its neighbours' edges at
             * its vertices so that the surface stays closed */
            note(c, 0, SOLID_AT_FACE, f, "degenerate on the grid of step %g (%s): left out", c->p,
                 cycle_distinct(c, k0) < 3 ? "fewer than 3 distinct vertices"
                                           : "its vertices on one line");
            c->rep->degenerate_faces++;
            continue;
        }
        for (size_t k = k0; k < k1; k++)
            if (cycle_distinct(c, k) < 3) {
                if (k == k0)
                    note(c, 1, SOLID_AT_FACE, f, "fewer than 3 distinct vertices (at precision %g)",
                         c->p);
                else
                    note_at(c, 1, SOLID_AT_HOLE, f, k - k0 - 1, "fewer than 3 distinct vertices");
                degenerate = 1;
            }
        if (degenerate) continue;
        /* Newell normal of the outer cycle, about its first vertex */
        uint32_t lo = s->cyc_off[k0], hi = s->cyc_off[k0 + 1];
        const double *o = vert(c, cy[lo]);
        double n[3] = {0, 0, 0}, bmin[3], bmax[3];
        for (int a = 0; a < 3; a++) bmin[a] = bmax[a] = o[a];
        for (uint32_t i = lo; i < hi; i++) {
            const double *x = vert(c, cy[i]), *y = vert(c, cy[i + 1 < hi ? i + 1 : lo]);
            double dx[3], dy[3], t[3];
            sub3(x, o, dx);
            sub3(y, o, dy);
            cross3(dx, dy, t);
            for (int a = 0; a < 3; a++) {
                n[a] += t[a];
                bmin[a] = x[a] < bmin[a] ? x[a] : bmin[a];
                bmax[a] = x[a] > bmax[a] ? x[a] : bmax[a];
            }
        }
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        double diag = sqrt((bmax[0] - bmin[0]) * (bmax[0] - bmin[0]) +
                           (bmax[1] - bmin[1]) * (bmax[1] - bmin[1]) +
                           (bmax[2] - bmin[2]) * (bmax[2] - bmin[2]));
        c->area += len / 2;
        if (!(len > 0) && k1 - k0 > 1) {
            /* a face with holes whose outer cycle is flat in doubles (the grid test above
             * only takes faces without holes) */
            note(c, 1, SOLID_AT_FACE, f, "zero area (a face with holes, at precision %g)", c->p);
            continue;
        }
        (void)diag;
        /* plane through the mean of all the face's vertices */
        double m[3] = {0, 0, 0};
        size_t cnt = s->cyc_off[k1] - s->cyc_off[k0];
        for (uint32_t i = s->cyc_off[k0]; i < s->cyc_off[k1]; i++) {
            double d[3];
            sub3(vert(c, cy[i]), o, d);
            for (int a = 0; a < 3; a++) m[a] += d[a];
        }
        for (int a = 0; a < 3; a++) m[a] = o[a] + m[a] / (double)cnt;
        double worst = 0;
        uint32_t wv = 0;
        for (uint32_t i = s->cyc_off[k0]; i < s->cyc_off[k1]; i++) {
            double d[3];
            sub3(vert(c, cy[i]), m, d);
            double dist = fabs(d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / len;
            if (dist > worst) worst = dist, wv = cy[i];
        }
        if (worst > c->p) {
            note(c, 0, SOLID_AT_FACE, f,
                 "not planar (vertex %u is %.3g from its plane, precision %g): split into "
                 "triangles",
                 wv, worst, c->p);
            c->rep->split_faces++;
        }
        rc = check_face_grid(c, f, &q);
    }
    gface_free(&q);
    return rc;
}

/* ---- check: edges --------------------------------------------------------------------- */

/* The half-edges (every entry whose two merged ends differ), sorted by key, stably (so those of
 * one edge stay in face order): a counting sort by the lower merged vertex that writes each
 * half straight to its place (a first pass counts, a second places), then each vertex's few
 * halves by the higher one (insertion).  -1 out of memory. */
static int build_halves(ck *c)
{
    const solid *s = c->s;
    const uint32_t *cy = s->cyc;
    size_t nv = s->nv, n = 0;
    uint32_t *pos = mem_calloc(nv + 2, sizeof *pos);
    if (!pos) return -1;
    if (c->tri) { /* three merged vertices a face, read once a pass: no cycle bounds */
        const uint32_t *m = c->merged;
        for (size_t f = 0; f < s->nf; f++) {
            uint32_t u0 = m[cy[3 * f]], u1 = m[cy[3 * f + 1]], u2 = m[cy[3 * f + 2]];
            pos[(u0 < u1 ? u0 : u1) + 1] += u0 != u1;
            pos[(u1 < u2 ? u1 : u2) + 1] += u1 != u2;
            pos[(u2 < u0 ? u2 : u0) + 1] += u2 != u0;
            n += (u0 != u1) + (u1 != u2) + (u2 != u0);
        }
    }
    for (size_t k = 0; !c->tri && k < s->ncyc; k++) {
        uint32_t lo = s->cyc_off[k], hi = s->cyc_off[k + 1];
        for (uint32_t i = lo; i < hi; i++) {
            uint32_t u = c->merged[cy[i]], w = c->merged[cy[i + 1 < hi ? i + 1 : lo]];
            if (u == w) continue;
            pos[(u < w ? u : w) + 1]++;
            n++;
        }
    }
    for (size_t v = 0; v < nv; v++) pos[v + 1] += pos[v];
    c->he = mem_malloc((n ? n : 1) * sizeof *c->he);
    if (!c->he) {
        free(pos);
        return -1;
    }
    if (c->tri) {
        const uint32_t *m = c->merged;
        for (size_t f = 0; f < s->nf; f++) {
            uint32_t u[4] = {m[cy[3 * f]], m[cy[3 * f + 1]], m[cy[3 * f + 2]]};
            u[3] = u[0];
            for (uint32_t t = 0; t < 3; t++) {
                uint32_t a = u[t], b = u[t + 1];
                if (a == b) continue;
                c->he[pos[a < b ? a : b]++] =
                    (half){.key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a,
                           .ent = (uint32_t)(3 * f + t),
                           .face = (uint32_t)f & 0x7fffffffu,
                           .fwd = a < b};
            }
        }
    }
    for (size_t f = 0; !c->tri && f < s->nf; f++)
        for (size_t k = s->face_off[f]; k < s->face_off[f + 1]; k++) {
            uint32_t lo = s->cyc_off[k], hi = s->cyc_off[k + 1];
            for (uint32_t i = lo; i < hi; i++) {
                uint32_t u = c->merged[cy[i]], w = c->merged[cy[i + 1 < hi ? i + 1 : lo]];
                if (u == w) continue;
                c->he[pos[u < w ? u : w]++] =
                    (half){.key = u < w ? (uint64_t)u << 32 | w : (uint64_t)w << 32 | u,
                           .ent = i,
                           .face = (uint32_t)f & 0x7fffffffu,
                           .fwd = u < w};
            }
        }
    c->nhe = n;
    /* pos[v] is now where vertex v's run ends (the next one's start) */
    for (size_t v = 0; v < nv; v++) {
        uint32_t r0 = v ? pos[v - 1] : 0, r1 = pos[v];
        for (uint32_t i = r0 + 1; i < r1; i++) {
            half x = c->he[i];
            uint32_t j = i;
            for (; j > r0 && c->he[j - 1].key > x.key; j--) c->he[j] = c->he[j - 1];
            c->he[j] = x;
        }
    }
    free(pos);
    return 0;
}

/* A half with its input end vertices, lower first, for pair_by_index's sort. */
typedef struct half_ends {
    uint32_t lo, hi;
    half h;
} half_ends;

static int half_ends_cmp(const void *pa, const void *pb)
{
    const half_ends *a = pa, *b = pb;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return (a->h.face > b->h.face) - (a->h.face < b->h.face);
}

/* The halves he[i..j) share one edge in space (their merged ends).  When their input vertex
 * indices pair them two by two (a surface touching itself, like a mesh with two vertices at one
 * point), lists those pairs and returns 1; else returns 0 (a non-manifold edge); -1 out of
 * memory. */
static int pair_by_index(ck *c, size_t i, size_t j)
{
    half_ends *e = malloc((j - i) * sizeof *e);
    if (!e) return -1;
    for (size_t k = i; k < j; k++) {
        uint32_t a = half_a(c, &c->he[k]), b = half_b(c, &c->he[k]);
        e[k - i] = (half_ends){a < b ? a : b, a < b ? b : a, c->he[k]};
    }
    qsort(e, j - i, sizeof *e, half_ends_cmp);
    int paired = 1;
    for (size_t k = 0; k < j - i && paired; k += 2) {
        if (e[k].lo != e[k + 1].lo || e[k].hi != e[k + 1].hi) paired = 0;
        if (k + 2 < j - i && e[k + 2].lo == e[k].lo && e[k + 2].hi == e[k].hi)
            paired = 0; /* three on one */
    }
    if (paired) {
        for (size_t k = i; k < j; k++) c->he[k] = e[k - i].h;
        for (size_t k = i; k < j; k += 2) c->pair[c->npair++] = (uint32_t)k;
    }
    free(e);
    return paired;
}

/* Builds and sorts the half-edges, reports open and non-manifold edges, and lists the
 * manifold ones in c->pair.  Returns -1 out of memory; *bad is set on any error reported. */
static int check_edges(ck *c, int *bad)
{
    size_t total = c->s->cyc_off[c->s->ncyc];
    c->pair = mem_malloc((total / 2 + 1) * sizeof *c->pair);
    if (!c->pair || build_halves(c)) return -1;
    for (size_t i = 0, j; i < c->nhe; i = j) {
        for (j = i + 1; j < c->nhe && c->he[j].key == c->he[i].key; j++) continue;
        const half *h = &c->he[i];
        int paired = j - i > 2 && (j - i) % 2 == 0 ? pair_by_index(c, i, j) : 0;
        if (paired < 0) return -1;
        if (paired) {
            /* the surface meets itself along this edge in space, but every pair of faces
             * shares its own vertices: a closed surface touching itself, which the
             * arrangement takes as it is */
            note(c, 0, SOLID_AT_FACE, h->face,
                 "edge %u-%u lies on %zu faces: the surface touches itself there (its vertex "
                 "indices pair the faces two by two)",
                 half_a(c, h), half_b(c, h), j - i);
            continue;
        }
        size_t fwd = 0;
        for (size_t k = i; k < j; k++) fwd += c->he[k].fwd;
        if (j - i == 2) {
            c->pair[c->npair++] = (uint32_t)i;
        } else if (j - i > 2 && 2 * fwd == j - i) {
            /* as many faces walk it one way as the other: the surface is closed there in the
             * sense of winding numbers (parts touching along it, a surface given twice, one
             * passing through itself along it); its faces are not paired, the arrangement
             * orders them about the edge */
            note(c, 0, SOLID_AT_FACE, h->face,
                 "edge %u-%u lies on %zu faces, %zu walking it each way: the surface touches or "
                 "overlaps itself there",
                 half_a(c, h), half_b(c, h), j - i, fwd);
            if (mem_grow(&c->multi, &c->capmulti, c->nmulti + 1, sizeof *c->multi)) return -1;
            c->multi[c->nmulti++] = (uint32_t)i;
        } else if (j - i == 1) {
            note(c, 1, SOLID_AT_FACE, h->face, "open surface (edge %u-%u has no other face)",
                 half_a(c, h), half_b(c, h));
            *bad = 1;
        } else {
            note(c, 1, SOLID_AT_FACE, h->face,
                 "non-manifold edge %u-%u (used %zu times, %zu walking it one way and %zu the "
                 "other: the surface is not closed there)",
                 half_a(c, h), half_b(c, h), j - i, fwd, j - i - fwd);
            *bad = 1;
        }
    }
    return 0;
}

/* ---- check: orientation --------------------------------------------------------------- */

/* Fills c->flip with the flips that make every manifold edge walked in opposite directions.
 * Returns -1 out of memory; *bad set when no flips can do it (reported). */
static int orient(ck *c, int *bad)
{
    size_t nf = c->s->nf, inconsistent = 0, flips = 0, first = SIZE_MAX;
    size_t *adj_off = mem_calloc(nf + 1, sizeof *adj_off);
    uint32_t *adj = mem_malloc((2 * c->npair + 1) * sizeof *adj);
    uint32_t *queue = mem_malloc(nf * sizeof *queue);
    c->flip = mem_malloc(nf);
    if (!adj_off || !adj || !queue || !c->flip) goto fail;
    for (size_t e = 0; e < c->npair; e++) {
        const half *h = &c->he[c->pair[e]];
        if (h[0].fwd != h[1].fwd) continue;
        if (first == SIZE_MAX) first = e;
        inconsistent++;
        if (h[0].face == h[1].face) {
            note(c, 1, SOLID_AT_FACE, h->face,
                 "walks edge %u-%u twice in the same direction (no flip can fix it)", half_a(c, h),
                 half_b(c, h));
            *bad = 1;
        }
    }
    if (!inconsistent) { /* every edge walked both ways: nothing to flip, nothing to walk */
        memset(c->flip, 0, nf);
        free(adj_off), free(adj), free(queue);
        return 0;
    }
    for (size_t e = 0; e < c->npair; e++) {
        const half *h = &c->he[c->pair[e]];
        if (h[0].face == h[1].face) continue;
        adj_off[h[0].face + 1]++;
        adj_off[h[1].face + 1]++;
    }
    for (size_t f = 0; f < nf; f++) adj_off[f + 1] += adj_off[f];
    for (size_t e = 0; e < c->npair; e++) {
        const half *h = &c->he[c->pair[e]];
        if (h[0].face == h[1].face) continue;
        adj[adj_off[h[0].face]++] = (uint32_t)e;
        adj[adj_off[h[1].face]++] = (uint32_t)e;
    }
    for (size_t f = nf; f > 0; f--) adj_off[f] = adj_off[f - 1];
    adj_off[0] = 0;

    memset(c->flip, -1, nf);
    int conflict = 0;
    for (size_t root = 0; root < nf; root++) {
        if (c->flip[root] >= 0) continue;
        size_t head = 0, tail = 0, comp_flips = 0;
        c->flip[root] = 0;
        queue[tail++] = (uint32_t)root;
        while (head < tail) {
            uint32_t f = queue[head++];
            for (size_t i = adj_off[f]; i < adj_off[f + 1]; i++) {
                const half *h = &c->he[c->pair[adj[i]]];
                uint32_t g = h[0].face == f ? h[1].face : h[0].face;
                signed char want = (signed char)(c->flip[f] ^ (h[0].fwd == h[1].fwd));
                if (c->flip[g] < 0) {
                    c->flip[g] = want;
                    comp_flips += (size_t)want;
                    queue[tail++] = g;
                } else if (c->flip[g] != want && !conflict) {
                    note(c, 1, SOLID_AT_SOLID, 0,
                         "faces %u and %u: cannot be oriented consistently (edge %u-%u: "
                         "non-orientable, or a hole walked the wrong way)",
                         f, g, half_a(c, h), half_b(c, h));
                    conflict = 1;
                    *bad = 1;
                }
            }
        }
        /* the surface keeps the orientation of most of its input faces */
        if (2 * comp_flips > tail) {
            for (size_t i = 0; i < tail; i++) c->flip[queue[i]] ^= 1;
            comp_flips = tail - comp_flips;
        }
        flips += comp_flips;
    }
    c->flips = flips;
    if (!*bad && flips) {
        const half *h = &c->he[c->pair[first]];
        note(c, 0, SOLID_AT_SOLID, 0,
             "orientation inconsistent at %zu edges (first: %u-%u, faces %u and %u): flipped "
             "%zu of %zu faces",
             inconsistent, half_a(c, h), half_b(c, h), (uint32_t)h[0].face, (uint32_t)h[1].face,
             flips, nf);
    }
    free(adj_off);
    free(adj);
    free(queue);
    return 0;
fail:
    free(adj_off);
    free(adj);
    free(queue);
    return -1;
}

/* The edges on more than 2 faces, taken unpaired because as many faces walked them each way:
 * still so once orient has flipped faces?  Else the surface is not closed there (reported).
 * Returns 1 when one is not. */
static int multi_still_closed(ck *c)
{
    for (size_t m = 0; m < c->nmulti; m++) {
        size_t i = c->multi[m], j = i, fwd = 0;
        for (; j < c->nhe && c->he[j].key == c->he[i].key; j++)
            fwd += (size_t)(c->he[j].fwd ^ (c->flip[c->he[j].face] & 1));
        if (2 * fwd != j - i) {
            const half *h = &c->he[i];
            note(c, 1, SOLID_AT_FACE, h->face,
                 "edge %u-%u lies on %zu faces, %zu walking it one way once their orientation is "
                 "made consistent: the surface is not closed there",
                 half_a(c, h), half_b(c, h), j - i, fwd);
            return 1;
        }
    }
    return 0;
}

/* ---- check: volume -------------------------------------------------------------------- */

/* The area of face f's outer cycle (its Newell normal's length, halved). */
static double outer_area(const ck *c, size_t f)
{
    const solid *s = c->s;
    uint32_t lo = s->cyc_off[s->face_off[f]], hi = s->cyc_off[s->face_off[f] + 1];
    const double *o = vert(c, s->cyc[lo]);
    double n[3] = {0, 0, 0};
    for (uint32_t i = lo; i < hi; i++) {
        const double *x = vert(c, s->cyc[i]), *y = vert(c, s->cyc[i + 1 < hi ? i + 1 : lo]);
        double dx[3], dy[3], t[3];
        sub3(x, o, dx);
        sub3(y, o, dy);
        cross3(dx, dy, t);
        for (int a = 0; a < 3; a++) n[a] += t[a];
    }
    return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 2;
}

/* Is some part of the surface (faces joined across paired edges) thicker than the precision,
 * its own volume under c->flip against its area?  (A solid whose parts' volumes cancel, one
 * turned inside out beside another, is no flat solid: its winding numbers are -1 and 1.)
 * -1 out of memory. */
static int some_part_thick(const ck *c)
{
    const solid *s = c->s;
    size_t nf = s->nf;
    uint32_t *uf = mem_malloc((nf + 1) * sizeof *uf);
    double *vol = mem_calloc(nf + 1, sizeof *vol), *area = mem_calloc(nf + 1, sizeof *area);
    int rc = -1;
    if (!uf || !vol || !area) goto done;
    for (size_t f = 0; f < nf; f++) uf[f] = (uint32_t)f;
    for (size_t e = 0; e < c->npair; e++) {
        const half *h = &c->he[c->pair[e]];
        uint32_t a = h[0].face, b = h[1].face;
        while (uf[a] != a) a = uf[a] = uf[uf[a]];
        while (uf[b] != b) b = uf[b] = uf[uf[b]];
        if (a != b) uf[a > b ? a : b] = a < b ? a : b;
    }
    for (size_t f = 0; f < nf; f++) {
        uint32_t r = (uint32_t)f;
        while (uf[r] != r) r = uf[r];
        double v = face_volume6(c, f, c->ref) / 6;
        vol[r] += c->flip && c->flip[f] ? -v : v;
        area[r] += outer_area(c, f);
    }
    rc = 0;
    for (size_t f = 0; f < nf && !rc; f++)
        if (uf[f] == f && area[f] > 0 && fabs(vol[f]) > c->p * area[f] / 2) rc = 1;
done:
    free(uf), free(vol), free(area);
    return rc;
}

/* Signed volume under c->flip (check_faces's sum when orient flipped no face); flips
 * everything when negative.  -1 when degenerate. */
static int check_volume(ck *c)
{
    const solid *s = c->s;
    double vol6 = c->vol6, area = c->area;
    if (c->flips) {
        vol6 = 0;
        for (size_t f = 0; f < s->nf; f++) {
            double v = face_volume6(c, f, c->ref);
            vol6 += c->flip[f] ? -v : v;
        }
    }
    double vol = vol6 / 6;
    if (!(fabs(vol) > c->p * area / 2) && some_part_thick(c) != 1) {
        note(c, 1, SOLID_AT_SOLID, 0,
             "degenerate: volume %.3g for area %.3g (thinner than the precision %g)", vol, area,
             c->p);
        return -1;
    }
    if (vol < 0 && fabs(vol) > c->p * area / 2) { /* not when parts cancel (some_part_thick) */
        note(c, 0, SOLID_AT_SOLID, 0, "inward oriented (volume %.6g): every face flipped", vol);
        for (size_t f = 0; f < s->nf; f++) c->flip[f] ^= 1;
        vol = -vol;
    }
    c->rep->volume = vol;
    for (size_t f = 0; f < s->nf; f++) c->rep->flipped_faces += (size_t)c->flip[f];
    return 0;
}

/* ---- check: the fixed copy ------------------------------------------------------------ */

static int make_fixed(const ck *c, solid *out)
{
    const solid *s = c->s;
    size_t total = s->cyc_off[s->ncyc];
    out->V = mem_malloc((s->nv ? 3 * s->nv : 1) * sizeof *out->V);
    out->face_off = mem_malloc((s->nf + 1) * sizeof *out->face_off);
    out->cyc_off = mem_malloc((s->ncyc + 1) * sizeof *out->cyc_off);
    out->cyc = mem_malloc((total ? total : 1) * sizeof *out->cyc);
    if (!out->V || !out->face_off || !out->cyc_off || !out->cyc) goto fail;
    out->nv = s->nv;
    out->nf = s->nf;
    out->ncyc = s->ncyc;
    if (s->nv) memcpy(out->V, s->V, 3 * s->nv * sizeof *out->V);
    memcpy(out->face_off, s->face_off, (s->nf + 1) * sizeof *out->face_off);
    memcpy(out->cyc_off, s->cyc_off, (s->ncyc + 1) * sizeof *out->cyc_off);
    if (total) memcpy(out->cyc, s->cyc, total * sizeof *out->cyc);
    /* a flipped face reverses every cycle, keeping each cycle's first vertex */
    for (size_t f = 0; f < s->nf; f++) {
        if (!c->flip[f]) continue;
        for (size_t k = s->face_off[f]; k < s->face_off[f + 1]; k++)
            for (uint32_t i = s->cyc_off[k] + 1, j = s->cyc_off[k + 1]; j > 0 && i < j - 1;
                 i++, j--) {
                uint32_t t = out->cyc[i];
                out->cyc[i] = out->cyc[j - 1];
                out->cyc[j - 1] = t;
            }
    }
    return 0;
fail:
    solid_free(out);
    return -1;
}

/* The entry of the fixed copy that holds half h: its own, or in a face the copy reverses (every
 * cycle reversed keeping its first vertex) the entry walking the same edge there. */
static uint32_t fixed_entry(const ck *c, const half *h)
{
    const solid *s = c->s;
    if (!c->flip[h->face]) return h->ent;
    for (uint32_t k = s->face_off[h->face]; k < s->face_off[h->face + 1]; k++) {
        uint32_t lo = s->cyc_off[k], n = s->cyc_off[k + 1] - lo;
        if (h->ent < lo || h->ent >= lo + n) continue;
        return lo + (n - 1 - (h->ent - lo)) % n;
    }
    return h->ent;
}

/* twin[i] for every entry of the fixed copy: the entry walking the same edge the other way when
 * exactly two entries lie on that edge, else NONE. */
static void export_twins(const ck *c, uint32_t *twin)
{
    const solid *s = c->s;
    size_t total = s->cyc_off[s->ncyc];
    for (size_t i = 0; i < total; i++) twin[i] = NONE;
    int fl = c->rep->flipped_faces != 0; /* orient's flips, or every face (check_volume) */
    for (size_t e = 0; e < c->npair; e++) {
        size_t i = c->pair[e];
        const half *h = &c->he[i];
        if ((i > 0 && h[-1].key == h->key) || (i + 2 < c->nhe && h[2].key == h->key))
            continue; /* a pair of a surface touching itself: four faces on the edge */
        uint32_t x = fl ? fixed_entry(c, &h[0]) : h[0].ent,
                 y = fl ? fixed_entry(c, &h[1]) : h[1].ent;
        twin[x] = y, twin[y] = x;
    }
}

static int check(const solid *s, double precision, const char *label, solid_report *rep,
                 solid *fixed, int faces_only, int copy_unchanged, uint32_t *twin)
{
    solid_report local;
    ck c = {.s = s,
            .p = precision,
            .rep = rep ? rep : &local,
            .label = label ? label : "solid",
            .faces_only = faces_only};
    memset(c.rep, 0, sizeof *c.rep);
    if (fixed) memset(fixed, 0, sizeof *fixed);
    int bad = 0;
    if (!(precision > 0) || !isfinite(precision)) {
        note(&c, 1, SOLID_AT_SOLID, 0, "precision %g is not a positive number", precision);
        goto done;
    }
    if (!s) {
        note(&c, 1, SOLID_AT_SOLID, 0, "no solid");
        goto done;
    }
    if (check_shape(&c)) goto done;
    if (merge_vertices(&c) || check_faces(&c)) goto oom;
    if (faces_only) goto done;
    if (check_edges(&c, &bad)) goto oom;
    if (bad) goto done;
    if (orient(&c, &bad)) goto oom;
    if (bad || multi_still_closed(&c) || check_volume(&c)) goto done;
    if (c.rep->errors == 0 && fixed && (copy_unchanged || c.rep->flipped_faces) &&
        make_fixed(&c, fixed))
        goto oom;
    if (c.rep->errors == 0 && twin) export_twins(&c, twin);
    goto done;
oom:
    note(&c, 1, SOLID_AT_SOLID, 0, "out of memory");
done:
    free(c.merged);
    free(c.g);
    free(c.he);
    free(c.pair);
    free(c.flip);
    free(c.multi);
    if (c.rep->errors && fixed) solid_free(fixed);
    return c.rep->errors ? -1 : 0;
}

int solid_check(const solid *s, double precision, const char *label, solid_report *rep,
                solid *fixed)
{
    return check(s, precision, label, rep, fixed, 0, 1, NULL);
}

int solid_check_nocopy(const solid *s, double precision, const char *label, solid_report *rep,
                       solid *fixed, uint32_t *twin)
{
    return check(s, precision, label, rep, fixed, 0, 0, twin);
}

int solid_check_faces(const solid *s, double precision, const char *label, solid_report *rep)
{
    return check(s, precision, label, rep, NULL, 1, 0, NULL);
}

/* ---- readers: text ---------------------------------------------------------------------- */

typedef struct text {
    const char *p, *end; /* what is left */
    size_t line;         /* of the line last taken */
} text;

typedef struct span {
    const char *p, *end;
} span;

/* Takes the next line, without its comment and line end; 0 at the end of the text. */
static int next_line(text *t, span *l)
{
    if (t->p >= t->end) return 0;
    const char *nl = memchr(t->p, '\n', (size_t)(t->end - t->p));
    const char *e = nl ? nl : t->end;
    const char *hash = memchr(t->p, '#', (size_t)(e - t->p));
    l->p = t->p;
    l->end = hash ? hash : e;
    t->p = nl ? nl + 1 : t->end;
    t->line++;
    return 1;
}

static int is_space(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\f' || ch == '\v' || ch == '\0';
}

/* Skips the separators at the start of l; 0 when nothing is left. */
static inline int skip_space(span *l)
{
    while (l->p < l->end && is_space(*l->p)) l->p++;
    return l->p < l->end;
}

/* Takes the next whitespace-separated token of l; 0 when none is left. */
static int next_token(span *l, span *tok)
{
    if (!skip_space(l)) return 0;
    tok->p = l->p;
    while (l->p < l->end && !is_space(*l->p)) l->p++;
    tok->end = l->p;
    return 1;
}

static int tok_is(span tok, const char *word)
{
    size_t n = strlen(word);
    return (size_t)(tok.end - tok.p) == n && !memcmp(tok.p, word, n);
}

/* Prints a token for a message: at most 24 bytes, unprintable bytes as '?'. */
static const char *tok_show(span tok, char *buf, size_t cap)
{
    size_t n = (size_t)(tok.end - tok.p), k = 0;
    for (size_t i = 0; i < n && k + 4 < cap && i < 24; i++)
        buf[k++] = tok.p[i] >= 0x20 && tok.p[i] < 0x7f ? tok.p[i] : '?';
    if (n > 24 && k + 4 < cap) buf[k++] = '.', buf[k++] = '.', buf[k++] = '.';
    buf[k] = 0;
    return buf;
}

/* A finite decimal number (as strtod reads it in the "C" locale, correctly rounded): 0, or -1
 * (malformed or not finite). */
static int parse_number(span tok, double *out)
{
    if (tok.end - tok.p > NUMBER_MAX) return -1;
    return ff_parse(tok.p, tok.end, out);
}

/* The next token of l as a number, scanning its bytes once: 1 with *x, 0 when no token is
 * left, -1 when the token is no number (*tok is then the token, for the message). */
static int next_number(span *l, double *x, span *tok)
{
    if (!skip_space(l)) return 0;
    const char *stop;
    if (ff_parse_prefix(l->p, l->end, x, &stop) == 0 && (stop == l->end || is_space(*stop)) &&
        stop - l->p <= NUMBER_MAX) {
        l->p = stop;
        return 1;
    }
    next_token(l, tok);
    return -1;
}

/* The next token of l as an index (digits only, at most 18), scanning its bytes once: 1 with
 * *v, 0 when no token is left, -1 when the token is no index.  *tok is the token (for a
 * message) whenever there is one. */
static int next_index(span *l, int64_t *v, span *tok)
{
    if (!skip_space(l)) return 0;
    const char *p = l->p, *e = l->end;
    int64_t x = 0;
    while (p < e && *p >= '0' && *p <= '9' && p - l->p < 18) x = x * 10 + (*p++ - '0');
    if (p > l->p && (p == e || is_space(*p))) {
        *tok = (span){l->p, p};
        l->p = p;
        *v = x;
        return 1;
    }
    next_token(l, tok);
    return -1;
}

/* An optionally signed integer with at most 18 digits: 0, or -1. */
static int parse_int(const char *p, const char *end, int64_t *out)
{
    int neg = 0;
    if (p < end && (*p == '-' || *p == '+')) neg = *p++ == '-';
    if (p >= end || end - p > 18) return -1;
    int64_t v = 0;
    for (; p < end; p++) {
        if (*p < '0' || *p > '9') return -1;
        v = v * 10 + (*p - '0');
    }
    *out = neg ? -v : v;
    return 0;
}

/* ---- readers: building the solid -------------------------------------------------------- */

typedef struct build {
    double *V;
    size_t nv, capv; /* in vertices */
    uint32_t *idx;
    size_t ni, capi;
    uint32_t *off; /* nf + 1 */
    size_t nf, capf;
} build;

static inline int build_vertex(build *b, const double *x)
{
    if (mem_grow(&b->V, &b->capv, b->nv + 1, 3 * sizeof *b->V)) return -1;
    memcpy(b->V + 3 * b->nv++, x, 3 * sizeof *x);
    return 0;
}

static inline int build_index(build *b, uint32_t v)
{
    if (mem_grow(&b->idx, &b->capi, b->ni + 1, sizeof *b->idx)) return -1;
    b->idx[b->ni++] = v;
    return 0;
}

/* Closes the face whose indices were appended since the last one. */
static inline int build_face(build *b)
{
    if (mem_grow(&b->off, &b->capf, b->nf + 2, sizeof *b->off)) return -1;
    if (b->nf == 0) b->off[0] = 0;
    b->off[++b->nf] = (uint32_t)b->ni;
    return 0;
}

static void build_free(build *b)
{
    free(b->V);
    free(b->idx);
    free(b->off);
    memset(b, 0, sizeof *b);
}

/* Moves b into out (each face one cycle); b is left empty. */
static int build_finish(build *b, solid *out)
{
    uint32_t *fo = mem_malloc((b->nf + 1) * sizeof *fo);
    if (!fo) return -1;
    for (size_t f = 0; f <= b->nf; f++) fo[f] = (uint32_t)f;
    if (b->nf == 0) {
        free(b->off);
        b->off = mem_calloc(1, sizeof *b->off);
        if (!b->off) {
            free(fo);
            return -1;
        }
    }
    out->nv = b->nv;
    out->V = b->V;
    out->nf = out->ncyc = b->nf;
    out->face_off = fo;
    out->cyc_off = b->off;
    out->cyc = b->idx;
    memset(b, 0, sizeof *b);
    return 0;
}

__attribute__((format(printf, 4, 5))) static int read_error(char *err, size_t errlen, size_t line,
                                                            const char *fmt, ...)
{
    if (err && errlen) {
        int k = snprintf(err, errlen, "line %zu: ", line);
        if (k >= 0 && (size_t)k < errlen) {
            va_list ap;
            va_start(ap, fmt);
            vsnprintf(err + k, errlen - (size_t)k, fmt, ap);
            va_end(ap);
        }
    }
    return -1;
}

/* ---- readers: OBJ ----------------------------------------------------------------------- */

/* One "a", "a/t", "a//n" or "a/t/n" of an f line: the vertex index a, as written. */
static int obj_ref(span tok, int64_t *a)
{
    const char *s1 = memchr(tok.p, '/', (size_t)(tok.end - tok.p));
    if (parse_int(tok.p, s1 ? s1 : tok.end, a)) return -1;
    if (!s1) return 0;
    const char *s2 = memchr(s1 + 1, '/', (size_t)(tok.end - s1 - 1));
    int64_t ignored;
    if (s2) { /* a/t/n or a//n: t may be empty, n may not */
        if (s2 > s1 + 1 && parse_int(s1 + 1, s2, &ignored)) return -1;
        return parse_int(s2 + 1, tok.end, &ignored);
    }
    return parse_int(s1 + 1, tok.end, &ignored);
}

/* solid_read_obj's reader; with starts, the first face of every object ("o"), and of every
 * group ("g") when groups, goes into *starts (ascending, each once, 0 not listed). */
static int read_obj(const char *txt, size_t len, int groups, uint32_t **starts, size_t *nstarts,
                    solid *out, char *err, size_t errlen)
{
    text t = {txt, txt + len, 0};
    build b = {0};
    span l, tok;
    char show[32];
    size_t capst = 0;
    memset(out, 0, sizeof *out);
    if (err && errlen) err[0] = 0;
    if (!txt && len) return read_error(err, errlen, 0, "no text");
    while (next_line(&t, &l)) {
        if (!next_token(&l, &tok)) continue;
        if (tok_is(tok, "v")) {
            double x[3], w;
            int n = 0, r;
            for (; (r = next_number(&l, n < 3 ? &x[n] : &w, &tok)) != 0; n++) {
                if (r < 0) {
                    read_error(err, errlen, t.line, "malformed number '%s'",
                               tok_show(tok, show, sizeof show));
                    goto fail;
                }
            }
            /* x y z, with w, or the common x y z r g b [a] colour extension */
            if (n < 3 || n > 7) {
                read_error(err, errlen, t.line, "a vertex has 3 coordinates, this one %d", n);
                goto fail;
            }
            if (b.nv >= SOLID_MAX_VERTICES) {
                read_error(err, errlen, t.line, "more than %u vertices", SOLID_MAX_VERTICES);
                goto fail;
            }
            if (build_vertex(&b, x)) goto oom;
        } else if (tok_is(tok, "f")) {
            size_t n = 0;
            while (next_token(&l, &tok)) {
                int64_t a;
                if (obj_ref(tok, &a)) {
                    read_error(err, errlen, t.line, "malformed vertex reference '%s'",
                               tok_show(tok, show, sizeof show));
                    goto fail;
                }
                int64_t v = a > 0 ? a - 1 : (int64_t)b.nv + a;
                if (a == 0 || v < 0 || v >= (int64_t)b.nv) {
                    read_error(err, errlen, t.line,
                               "vertex index %lld out of range (%zu vertices so far; indices "
                               "start at 1)",
                               (long long)a, b.nv);
                    goto fail;
                }
                if (++n > SOLID_MAX_FACE_LEN) {
                    read_error(err, errlen, t.line, "a face of more than %u vertices",
                               SOLID_MAX_FACE_LEN);
                    goto fail;
                }
                if (b.ni >= UINT32_MAX - 1) {
                    read_error(err, errlen, t.line, "too many face vertices in all");
                    goto fail;
                }
                if (build_index(&b, (uint32_t)v)) goto oom;
            }
            if (n < 3) {
                read_error(err, errlen, t.line, "a face needs 3 vertices, this one has %zu", n);
                goto fail;
            }
            if (b.nf >= SOLID_MAX_FACES) {
                read_error(err, errlen, t.line, "more than %u faces", SOLID_MAX_FACES);
                goto fail;
            }
            if (build_face(&b)) goto oom;
        } else if (starts && (tok_is(tok, "o") || (groups && tok_is(tok, "g"))) && b.nf &&
                   (!*nstarts || (*starts)[*nstarts - 1] != b.nf)) {
            if (mem_grow(starts, &capst, *nstarts + 1, sizeof **starts)) goto oom;
            (*starts)[(*nstarts)++] = (uint32_t)b.nf;
        }
        /* anything else (vt, vn, vp, s, usemtl, mtllib, l, p, ...) is not geometry */
    }
    if (build_finish(&b, out)) goto oom;
    return 0;
oom:
    read_error(err, errlen, t.line, "out of memory");
fail:
    build_free(&b);
    return -1;
}

int solid_read_obj(const char *txt, size_t len, solid *out, char *err, size_t errlen)
{
    return read_obj(txt, len, 0, NULL, NULL, out, err, errlen);
}

/* Faces f0 .. f1 of s as a solid of their own, with the vertices they use (in order of first
 * use).  -1 out of memory. */
static int solid_part(const solid *s, uint32_t f0, uint32_t f1, uint32_t *map, solid *out)
{
    uint32_t c0 = s->face_off[f0], c1 = s->face_off[f1];
    uint32_t i0 = s->cyc_off[c0], i1 = s->cyc_off[c1];
    memset(out, 0, sizeof *out);
    out->nf = f1 - f0, out->ncyc = c1 - c0;
    out->face_off = malloc((out->nf + 1) * sizeof *out->face_off);
    out->cyc_off = malloc((out->ncyc + 1) * sizeof *out->cyc_off);
    out->cyc = malloc(((size_t)i1 - i0 + 1) * sizeof *out->cyc);
    out->V = malloc(3 * ((size_t)i1 - i0 + 1) * sizeof *out->V);
    if (!out->face_off || !out->cyc_off || !out->cyc || !out->V) {
        solid_free(out);
        return -1;
    }
    for (uint32_t f = f0; f <= f1; f++) out->face_off[f - f0] = s->face_off[f] - c0;
    for (uint32_t c = c0; c <= c1; c++) out->cyc_off[c - c0] = s->cyc_off[c] - i0;
    for (uint32_t i = i0; i < i1; i++) {
        uint32_t v = s->cyc[i];
        if (map[v] == UINT32_MAX) {
            map[v] = (uint32_t)out->nv;
            memcpy(out->V + 3 * out->nv++, s->V + 3 * (size_t)v, 3 * sizeof *out->V);
        }
        out->cyc[i - i0] = map[v];
    }
    for (uint32_t i = i0; i < i1; i++) map[s->cyc[i]] = UINT32_MAX; /* for the next part */
    return 0;
}

int solid_read_obj_parts(const char *txt, size_t len, int groups, solid **parts, size_t *nparts,
                         char *err, size_t errlen)
{
    solid whole;
    uint32_t *starts = NULL, *map = NULL;
    size_t ns = 0;
    *parts = NULL, *nparts = 0;
    int rc = read_obj(txt, len, groups, &starts, &ns, &whole, err, errlen);
    if (rc) {
        free(starts);
        return rc;
    }
    if (ns && starts[ns - 1] == whole.nf) ns--; /* an object with no face at the end */
    *parts = calloc(ns + 1, sizeof **parts);
    if (!*parts) goto oom;
    if (ns == 0) { /* one object: the solid as read */
        (*parts)[0] = whole;
        *nparts = 1;
        free(starts);
        return 0;
    }
    map = malloc((whole.nv + 1) * sizeof *map);
    if (!map) goto oom;
    memset(map, 0xff, (whole.nv + 1) * sizeof *map);
    for (size_t k = 0; k <= ns; k++) {
        uint32_t f0 = k ? starts[k - 1] : 0, f1 = k < ns ? starts[k] : (uint32_t)whole.nf;
        if (solid_part(&whole, f0, f1, map, &(*parts)[*nparts])) goto oom;
        (*nparts)++;
    }
    free(map), free(starts);
    solid_free(&whole);
    return 0;
oom:
    if (err && errlen) snprintf(err, errlen, "out of memory");
    for (size_t k = 0; *parts && k < *nparts; k++) solid_free(&(*parts)[k]);
    free(*parts);
    *parts = NULL, *nparts = 0;
    free(map), free(starts);
    solid_free(&whole);
    return -1;
}

/* ---- readers: OFF ----------------------------------------------------------------------- */

/* Takes the next line holding a token; 0 at the end of the text. */
static int next_data_line(text *t, span *l)
{
    while (next_line(t, l))
        if (skip_space(l)) return 1; /* the separators before the first token: nothing */
    return 0;
}

/* "OFF" with the optional prefixes of Geomview's [ST][C][N][4][n]OFF that only add per-vertex
 * values (texture, colour, normal): 1; "4OFF"/"nOFF" (other dimensions): 2; anything else 0. */
static int off_header(span tok)
{
    size_t n = (size_t)(tok.end - tok.p);
    if (n < 3 || memcmp(tok.end - 3, "OFF", 3)) return 0;
    const char *p = tok.p, *e = tok.end - 3;
    if (e - p >= 2 && p[0] == 'S' && p[1] == 'T') p += 2;
    if (p < e && *p == 'C') p++;
    if (p < e && *p == 'N') p++;
    if (p < e && (*p == '4' || *p == 'n')) return 2;
    return p == e ? 1 : 0;
}

int solid_read_off(const char *txt, size_t len, solid *out, char *err, size_t errlen)
{
    text t = {txt, txt + len, 0};
    build b = {0};
    span l, tok;
    char show[32];
    int64_t cnt[3] = {0, 0, 0};
    int ncnt = 0;
    memset(out, 0, sizeof *out);
    if (err && errlen) err[0] = 0;
    if (!txt && len) return read_error(err, errlen, 0, "no text");
    if (!next_data_line(&t, &l)) return read_error(err, errlen, t.line, "empty: no OFF header");
    span first = l;
    next_token(&first, &tok);
    int h = off_header(tok);
    if (h == 2)
        return read_error(err, errlen, t.line, "'%s': only 3D OFF is read",
                          tok_show(tok, show, sizeof show));
    if (h == 1) {
        l = first; /* counts may follow on the header line */
        span rest = l;
        if (!next_token(&rest, &tok) && !next_data_line(&t, &l))
            return read_error(err, errlen, t.line, "no counts after the OFF header");
    } else if (parse_int(tok.p, tok.end, &cnt[0])) {
        return read_error(err, errlen, t.line, "not an OFF file (it starts with '%s')",
                          tok_show(tok, show, sizeof show));
    }
    while (next_token(&l, &tok)) {
        if (ncnt == 3 || parse_int(tok.p, tok.end, &cnt[ncnt]) || cnt[ncnt] < 0)
            return read_error(err, errlen, t.line,
                              "counts are 'vertices faces edges', not '%s' at value %d",
                              tok_show(tok, show, sizeof show), ncnt + 1);
        ncnt++;
    }
    if (ncnt < 2) return read_error(err, errlen, t.line, "counts 'vertices faces edges' missing");
    if (cnt[0] > SOLID_MAX_VERTICES || cnt[1] > SOLID_MAX_FACES)
        return read_error(err, errlen, t.line, "%lld vertices and %lld faces: at most %u of each",
                          (long long)cnt[0], (long long)cnt[1], SOLID_MAX_VERTICES);
    size_t nv = (size_t)cnt[0], nf = (size_t)cnt[1];
    /* a vertex line is at least "0 0 0\n", a face line "3 0 1 2\n": believe the counts only
     * when what is left could hold them, so that no allocation follows a count alone */
    size_t left = (size_t)(t.end - t.p);
    if (nv * 6 + nf * 8 > left + 1)
        return read_error(err, errlen, t.line,
                          "%zu vertices and %zu faces announced, but only %zu bytes follow", nv, nf,
                          left);
    while (b.nv < nv) {
        if (!next_data_line(&t, &l)) {
            read_error(err, errlen, t.line, "the file ends after %zu of %zu vertices", b.nv, nv);
            goto fail;
        }
        double x[3], extra;
        int n = 0, r;
        for (; (r = next_number(&l, n < 3 ? &x[n] : &extra, &tok)) != 0; n++)
            if (r < 0) {
                read_error(err, errlen, t.line, "malformed number '%s'",
                           tok_show(tok, show, sizeof show));
                goto fail;
            }
        if (n < 3) {
            read_error(err, errlen, t.line, "a vertex has 3 coordinates, this one %d", n);
            goto fail;
        }
        if (build_vertex(&b, x)) goto oom;
    }
    while (b.nf < nf) {
        if (!next_data_line(&t, &l)) {
            read_error(err, errlen, t.line, "the file ends after %zu of %zu faces", b.nf, nf);
            goto fail;
        }
        int64_t k, v;
        next_token(&l, &tok);
        if (parse_int(tok.p, tok.end, &k) || k < 3 || k > SOLID_MAX_FACE_LEN) {
            read_error(err, errlen, t.line,
                       "a face starts with its vertex count (3 to %u), not '%s'",
                       SOLID_MAX_FACE_LEN, tok_show(tok, show, sizeof show));
            goto fail;
        }
        for (int64_t i = 0; i < k; i++) {
            int r = next_index(&l, &v, &tok);
            if (r == 0) {
                read_error(err, errlen, t.line, "the face announces %lld vertices, %lld given",
                           (long long)k, (long long)i);
                goto fail;
            }
            if (r < 0 && parse_int(tok.p, tok.end, &v)) /* "+1", "-0": an integer still */
                v = -1;
            if (v < 0 || v >= (int64_t)nv) {
                read_error(err, errlen, t.line, "vertex index '%s' out of range (%zu vertices)",
                           tok_show(tok, show, sizeof show), nv);
                goto fail;
            }
            if (b.ni >= UINT32_MAX - 1) {
                read_error(err, errlen, t.line, "too many face vertices in all");
                goto fail;
            }
            if (build_index(&b, (uint32_t)v)) goto oom;
        }
        /* a colour: an index into a colour map, or 3 or 4 components */
        int extra = 0;
        double c;
        for (; next_token(&l, &tok); extra++)
            if (parse_number(tok, &c) || extra == 4) {
                read_error(err, errlen, t.line,
                           "after the %lld indices of a face only a colour may follow, not '%s'",
                           (long long)k, tok_show(tok, show, sizeof show));
                goto fail;
            }
        if (build_face(&b)) goto oom;
    }
    if (next_data_line(&t, &l)) {
        read_error(err, errlen, t.line, "data after the last of the %zu faces", nf);
        goto fail;
    }
    if (build_finish(&b, out)) goto oom;
    return 0;
oom:
    read_error(err, errlen, t.line, "out of memory");
fail:
    build_free(&b);
    return -1;
}
