/* test_planar.c — the planar half-edge kernel (core/planar.h) over a small grid model: sort
 * around vertices, successors, cycles and their order, placement of components by the slab
 * index, and the refusal of two half-edges leaving a vertex in one direction. */
#include <stdlib.h>
#include <string.h>

#include "core/num.h"
#include "core/planar.h"
#include "tests/check.h"

/* The model: grid points and edges (EV[2e] < EV[2e + 1] lexicographically; half-edge 2e leaves
 * EV[2e]); the queries are points. */
typedef struct model {
    const ipt *P;
    const uint32_t *EV;
    const ipt *Q;
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
static int below(void *vm, uint32_t e, uint32_t q)
{
    const model *m = vm;
    ipt a = m->P[m->EV[2 * e]], b = m->P[m->EV[2 * e + 1]], p = m->Q[q];
    if (a.x == b.x || !(a.x < p.x && p.x <= b.x)) return 0;
    return orient2(a, b, p) > 0;
}

/* the test's candidates are horizontal: higher is the larger y */
static int higher(void *vm, uint32_t a, uint32_t b)
{
    const model *m = vm;
    return m->P[m->EV[2 * a]].y > m->P[m->EV[2 * b]].y;
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
    model m = {P, EV, Q};
    planar_traits T = {&m, around, below, higher};
    uint32_t off[NV + 1], out[NH], pos[NH], next[NH], cyc_of[NH], hes[NH], hoff[NH + 1];
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
    REQUIRE(planar_cycles(NH, next, cyc_of, hes, hoff, &ncyc) == 0, "cycles refused");
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
    /* placement: spans are the exact x ranges (a grid model needs no room) */
    double elo[NE], ehi[NE], qlo[3], qhi[3];
    uint32_t ecomp[NE], best[3];
    for (uint32_t e = 0; e < NE; e++) {
        elo[e] = (double)P[EV[2 * e]].x, ehi[e] = (double)P[EV[2 * e + 1]].x;
        ecomp[e] = e < 4 ? 0 : e < 8 ? 1 : 2;
    }
    for (int q = 0; q < 3; q++) qlo[q] = qhi[q] = (double)Q[q].x;
    REQUIRE(planar_place(&T, NE, elo, ehi, ecomp, 3, qlo, qhi, best) == 0, "place: no memory");
    CHECK(best[0] == PLANAR_NONE, "the outer square has %u below it", best[0]);
    CHECK(best[1] == 8, "the inner square sits on edge %u, expected the bar (8)", best[1]);
    CHECK(best[2] == 0, "the bar sits on edge %u, expected the outer bottom (0)", best[2]);
}

TEST(planar_same_direction_refused)
{
    /* two edges from (0,0): to (2,2) and (1,1) — one direction */
    static const ipt P[] = {{0, 0}, {1, 1}, {2, 2}};
    static const uint32_t EV[] = {0, 2, 0, 1};
    model m = {P, EV, NULL};
    planar_traits T = {&m, around, NULL, NULL};
    uint32_t off[4], out[4], pos[4];
    adjacency(EV, 2, 3, off, out);
    CHECK(planar_sort_around(&T, off, out, pos, 0, 3) == -1, "same direction not refused");
}

TEST(planar_cycles_not_a_permutation)
{
    uint32_t next[4] = {1, 1, 3, 2}, cyc_of[4], hes[4], hoff[5];
    size_t n;
    CHECK(planar_cycles(4, next, cyc_of, hes, hoff, &n) == -2, "a broken successor map accepted");
}
