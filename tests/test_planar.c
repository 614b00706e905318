/* test_planar.c — the planar half-edge kernel (core/planar.h) over a small grid model: sort
 * around vertices, successors, cycles and their order, placement of components by the slab
 * index (a small case, and many bars against a brute force on one and four threads, over
 * several chunks of the index and with its slabs halved), and the refusal of two half-edges
 * leaving a vertex in one direction. */
#include <stdlib.h>
#include <string.h>

#include "core/arr2.h"
#include "core/num.h"
#include "core/planar.h"
#include "tests/check.h"

/* The model: grid points and edges (EV[2e] < EV[2e + 1] lexicographically; half-edge 2e leaves
 * EV[2e]); the queries are points. */
typedef struct model {
    const ipt *P;
    const uint32_t *EV;
    const ipt *Q;
    const uint32_t *ecomp, *qcomp; /* each edge's and query's component */
} model;

static uint32_t tail(const model *m, uint32_t h)
{
    return m->EV[h];
}

static int around(void *vm, uint32_t a, uint32_t b)
{
    const model *m = vm;
    ipt pa = m->P[tail(m, a)], qa = m->P[tail(m, a ^ 1)];
    ipt pb = m->P[tail(m, b)], qb = m->P[tail(m, b ^ 1)];
    return dir_cmp(qa.x - pa.x, qa.y - pa.y, qb.x - pb.x, qb.y - pb.y);
}

/* e (not vertical) straddles x = q.x (left end strictly left) and q lies strictly above it */
static int below(const model *m, uint32_t e, uint32_t q)
{
    ipt a = m->P[m->EV[2 * e]], b = m->P[m->EV[2 * e + 1]], p = m->Q[q];
    if (a.x == b.x || !(a.x < p.x && p.x <= b.x)) return 0;
    return orient2(a, b, p) > 0;
}

/* The placement's keys: twice the grid x, each query's span one key wider on both sides (as a
 * model with conservative spans has them), so that a query may meet two slabs and its best is
 * carried from the first slab's scan to the second's. */
static void espan(void *vm, size_t e0, size_t e1, int64_t *lo, int64_t *hi)
{
    const model *m = vm;
    for (size_t i = 0; i < e1 - e0; i++) {
        const uint32_t *ev = m->EV + 2 * (e0 + i);
        lo[i] = 2 * m->P[ev[0]].x;
        hi[i] = 2 * m->P[ev[1]].x;
    }
}

static void qspan(void *vm, uint32_t q, int64_t *lo, int64_t *hi)
{
    int64_t k = 2 * ((const model *)vm)->Q[q].x;
    *lo = k - 1, *hi = k + 1;
}

/* the candidates are horizontal: of those below and of another component, the highest (the
 * first of equal ones) */
static uint32_t scan(void *vm, uint32_t q, const uint32_t *cand, size_t n, uint32_t best)
{
    const model *m = vm;
    uint32_t b = best;
    for (size_t i = 0; i < n; i++) {
        uint32_t e = cand[i];
        if (m->ecomp[e] == m->qcomp[q] || !below(m, e, q)) continue;
        if (b == PLANAR_NONE || m->P[m->EV[2 * e]].y > m->P[m->EV[2 * b]].y) b = e;
    }
    return b;
}

/* Outgoing lists of nv vertices from ne edges: off (nv + 1), out (2 ne). */
static void adjacency(const uint32_t *EV, size_t ne, size_t nv, uint32_t *off, uint32_t *out)
{
    memset(off, 0, (nv + 1) * sizeof *off);
    for (size_t h = 0; h < 2 * ne; h++) off[EV[h] + 1]++;
    for (size_t v = 0; v < nv; v++) off[v + 1] += off[v];
    uint32_t at[16];
    memcpy(at, off, nv * sizeof *at);
    for (size_t h = 0; h < 2 * ne; h++) out[at[EV[h]]++] = (uint32_t)h;
}

TEST(planar_square_hole_and_bar)
{
    /* an outer square (component 0), an inner square (1), a bar between their bottoms (2) */
    static const ipt P[] = {{0, 0}, {0, 10}, {10, 0}, {10, 10}, {3, 4},
                            {3, 6}, {6, 4},  {6, 6},  {2, 2},   {8, 2}};
    static const uint32_t EV[] = {0, 2, 0, 1, 1, 3, 2, 3, 4, 6, 4, 5, 5, 7, 6, 7, 8, 9};
    enum { NV = 10, NE = 9, NH = 18 };
    static const ipt Q[] = {{0, 0}, {3, 4}, {2, 2}}; /* each component's lowest (left) point */
    static const uint32_t ecomp[NE] = {0, 0, 0, 0, 1, 1, 1, 1, 2}, qcomp[3] = {0, 1, 2};
    model m = {P, EV, Q, ecomp, qcomp};
    planar_traits T = {&m, around, espan, qspan, scan, NULL};
    uint32_t off[NV + 1], out[NH], pos[NH], next[NH], cyc_of[NH], hes[NH], *hoff = NULL;
    size_t caphoff = 0;
    adjacency(EV, NE, NV, off, out);
    REQUIRE(planar_sort_around(&T, off, out, pos, 0, NV) == 0, "sort around refused");
    for (uint32_t v = 0; v < NV; v++)
        for (uint32_t i = 0; i + 1 < off[v + 1] - off[v]; i++)
            CHECK(around(&m, out[off[v] + i], out[off[v] + i + 1]) < 0,
                  "vertex %u: not counter-clockwise at %u", v, i);
    for (uint32_t h = 0; h < NH; h++) {
        CHECK(out[off[tail(&m, h)] + pos[h]] == h, "pos of %u", h);
        next[h] = planar_next(off, out, pos, tail(&m, h ^ 1), h);
        CHECK(tail(&m, next[h]) == tail(&m, h ^ 1), "next of %u does not leave its head", h);
    }
    size_t ncyc = 0;
    REQUIRE(planar_cycles(NH, next, cyc_of, hes, &hoff, &caphoff, &ncyc) == 0, "cycles refused");
    CHECK(ncyc == 5, "%zu cycles, expected 5 (two per square, one around the bar)", ncyc);
    int pos_area = 0, neg_area = 0;
    for (size_t c = 0; c < ncyc; c++) {
        CHECK(c == 0 || hes[hoff[c]] > hes[hoff[c - 1]], "cycles not by smallest half-edge");
        i128 a2 = 0;
        for (uint32_t i = hoff[c]; i < hoff[c + 1]; i++) {
            ipt p = P[tail(&m, hes[i])], q = P[tail(&m, hes[i] ^ 1)];
            a2 += cross2(p.x, p.y, q.x, q.y);
            CHECK(cyc_of[hes[i]] == c, "cyc_of of %u", hes[i]);
            CHECK(hes[i] >= hes[hoff[c]], "cycle %zu does not start at its smallest", c);
        }
        pos_area += a2 > 0, neg_area += a2 < 0;
    }
    CHECK(pos_area == 2 && neg_area == 2, "areas: %d positive, %d negative", pos_area, neg_area);
    CHECK(hoff[ncyc] == NH, "the cycles hold %u half-edges", hoff[ncyc]);
    free(hoff);
    /* placement */
    uint32_t best[3];
    planar_ws ws = {0};
    REQUIRE(planar_place(&T, 1, &ws, NE, 0, 20, 3, best) == 0, "place: no memory");
    planar_ws_free(&ws);
    CHECK(best[0] == PLANAR_NONE, "the outer square has %u below it", best[0]);
    CHECK(best[1] == 8, "the inner square sits on edge %u, expected the bar (8)", best[1]);
    CHECK(best[2] == 0, "the bar sits on edge %u, expected the outer bottom (0)", best[2]);
}

TEST(planar_same_direction_refused)
{
    /* two edges from (0,0): to (2,2) and (1,1) — one direction */
    static const ipt P[] = {{0, 0}, {1, 1}, {2, 2}};
    static const uint32_t EV[] = {0, 2, 0, 1};
    model m = {P, EV, NULL, NULL, NULL};
    planar_traits T = {&m, around, NULL, NULL, NULL, NULL};
    uint32_t off[4], out[4], pos[4];
    adjacency(EV, 2, 3, off, out);
    CHECK(planar_sort_around(&T, off, out, pos, 0, 3) == -1, "same direction not refused");
}

TEST(planar_cycles_not_a_permutation)
{
    uint32_t next[4] = {1, 1, 3, 2}, cyc_of[4], hes[4], *hoff = NULL;
    size_t n, caphoff = 0;
    CHECK(planar_cycles(4, next, cyc_of, hes, &hoff, &caphoff, &n) == -2,
          "a broken successor map accepted");
    free(hoff);
}

/* Many horizontal bars (more than one chunk of the index: 65 536 edges), some spanning the
 * whole width (so the slabs are halved); each query's answer, on one thread and on four, is
 * the brute force's: the highest bar of another component strictly below, straddling it. */
TEST(planar_place_many_bars_against_brute_force)
{
    enum { NB = 70000, NLONG = 1500, NQ = 300, W = 1 << 20 };
    ipt *P = malloc(2 * NB * sizeof *P), Q[NQ];
    uint32_t *EV = malloc(2 * NB * sizeof *EV), *ecomp = malloc(NB * sizeof *ecomp);
    uint32_t qcomp[NQ], b1[NQ], b4[NQ], want[NQ];
    REQUIRE(P && EV && ecomp, "no memory");
    uint64_t r = 12345;
    for (uint32_t e = 0; e < NB; e++) {
        r = r * 6364136223846793005u + 1442695040888963407u;
        int64_t x0 = (int64_t)(r >> 33) % W, len = e < NLONG ? W : 1 + (int64_t)(r >> 20) % 64;
        if (e < NLONG) x0 = 0;
        P[2 * e] = (ipt){x0, (int64_t)e}, P[2 * e + 1] = (ipt){x0 + len, (int64_t)e};
        EV[2 * e] = 2 * e, EV[2 * e + 1] = 2 * e + 1;
        ecomp[e] = e % 7;
    }
    for (uint32_t q = 0; q < NQ; q++) {
        r = r * 6364136223846793005u + 1442695040888963407u;
        Q[q] = (ipt){(int64_t)(r >> 33) % W, (int64_t)(r >> 20) % NB};
        qcomp[q] = q % 7;
    }
    model m = {P, EV, Q, ecomp, qcomp};
    planar_traits T = {&m, NULL, espan, qspan, scan, NULL};
    planar_ws ws = {0};
    REQUIRE(planar_place(&T, 1, &ws, NB, 0, 2 * W + 128, NQ, b1) == 0, "place (1 thread) failed");
    REQUIRE(planar_place(&T, 4, &ws, NB, 0, 2 * W + 128, NQ, b4) == 0, "place (4 threads) failed");
    planar_ws_free(&ws);
    size_t found = 0;
    for (uint32_t q = 0; q < NQ; q++) {
        want[q] = PLANAR_NONE;
        for (uint32_t e = 0; e < NB; e++)
            if (ecomp[e] != qcomp[q] && below(&m, e, q) &&
                (want[q] == PLANAR_NONE || P[2 * e].y > P[2 * want[q]].y))
                want[q] = e;
        found += want[q] != PLANAR_NONE;
        CHECK(b1[q] == want[q], "query %u: %u on one thread, expected %u", q, b1[q], want[q]);
        CHECK(b4[q] == want[q], "query %u: %u on four threads, expected %u", q, b4[q], want[q]);
    }
    CHECK(found > NQ / 2, "only %zu of %d queries have a bar below: a weak test", found, NQ);
    free(P), free(EV), free(ecomp);
}

/* The half-edge u -> v of c (NONE: no such edge). */
static uint32_t half_edge(const lar2 *c, uint32_t u, uint32_t v)
{
    for (uint32_t e = 0; e < c->ne; e++) {
        if (c->EV[2 * e] == u && c->EV[2 * e + 1] == v) return 2 * e;
        if (c->EV[2 * e] == v && c->EV[2 * e + 1] == u) return 2 * e + 1;
    }
    return PLANAR_NONE;
}

/* arr2 keeps the kernel's half-edges when asked (the 2D Booleans walk them): each half-edge's
 * place in its tail's counter-clockwise list, the lists in angle order, and the face on each
 * one's left agreeing with the complex's cycles (every cycle has its face on its left: a
 * bounded face's outer cycle and holes, the unbounded face's cycles as nf). */
TEST(arr2_keeps_the_kernels_half_edges)
{
    /* a square with a square hole, a square beside it sharing a corner, a free bar inside */
    static const double seg[] = {0,  0,  10, 0,  10, 0,  10, 10, 10, 10, 0,  10, 0,
                                 10, 0,  0,  3,  3,  6,  3,  6,  3,  6,  6,  6,  6,
                                 3,  6,  3,  6,  3,  3,  10, 10, 14, 10, 14, 10, 14,
                                 14, 14, 14, 10, 14, 10, 14, 10, 10, 1,  8,  2,  9};
    arr2_opts o = {.threads = 2, .keep_dangling = 1, .half_edges = 1};
    lar2 c;
    char err[256];
    REQUIRE(arr2_build(seg, sizeof seg / sizeof *seg / 4, &o, &c, err, sizeof err) == ARR_OK, "%s",
            err);
    REQUIRE(c.he_face && c.he_off && c.he_out && c.he_pos, "the half-edges are not kept");
    for (uint32_t h = 0; h < 2 * c.ne; h++) {
        uint32_t t = c.EV[h];
        CHECK(c.he_out[c.he_off[t] + c.he_pos[h]] == h, "he_pos of %u", h);
    }
    for (uint32_t v = 0; v < c.nv; v++)
        for (uint32_t i = c.he_off[v]; i + 1 < c.he_off[v + 1]; i++) {
            uint32_t a = c.he_out[i], b = c.he_out[i + 1];
            const int64_t *G = c.VG;
            CHECK(dir_cmp(G[2 * c.EV[a ^ 1]] - G[2 * v], G[2 * c.EV[a ^ 1] + 1] - G[2 * v + 1],
                          G[2 * c.EV[b ^ 1]] - G[2 * v], G[2 * c.EV[b ^ 1] + 1] - G[2 * v + 1]) < 0,
                  "vertex %u: not counter-clockwise at %u", v, i);
        }
    size_t seen = 0;
    for (size_t f = 0; f <= c.nf; f++) {
        size_t ncy = f < c.nf ? 1 + c.hole_off[f + 1] - c.hole_off[f] : c.next;
        for (size_t j = 0; j < ncy; j++) {
            uint32_t cy = f == c.nf ? c.ext_cyc[j]
                          : j == 0  ? c.face_cycle[f]
                                    : c.hole_cyc[c.hole_off[f] + j - 1];
            uint32_t b = c.cyc_off[cy], n = c.cyc_off[cy + 1] - b;
            for (uint32_t i = 0; i < n; i++) {
                uint32_t h = half_edge(&c, c.cyc[b + i], c.cyc[b + (i + 1) % n]);
                CHECK(h != PLANAR_NONE && c.he_face[h] == f, "face %zu, cycle %u: half-edge %u", f,
                      cy, h);
                seen++;
            }
        }
    }
    CHECK(seen == 2 * c.ne, "the cycles walk %zu half-edges of %zu", seen, 2 * c.ne);
    CHECK(c.nf == 3, "%zu bounded faces, expected 3", c.nf);
    lar2_free_half_edges(&c);
    CHECK(!c.he_face && !c.he_out, "freed half-edges left");
    lar2_free(&c);
    o.half_edges = 0;
    REQUIRE(arr2_build(seg, sizeof seg / sizeof *seg / 4, &o, &c, err, sizeof err) == ARR_OK, "%s",
            err);
    CHECK(!c.he_face && !c.he_off && !c.he_out && !c.he_pos, "half-edges kept unasked");
    lar2_free(&c);
}
