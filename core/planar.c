/* planar.c — the half-edge kernel; see planar.h for the numbering and the traits.
 *
 * Stages, each a function below: sort around vertices (insertion, the degrees are small),
 * cycles of the successor map (in the order of their smallest half-edge), placement of
 * components by a downward ray over a slab index.  Why slabs and not a tree: the edges of an
 * arrangement are short and spread across the plane, so about sqrt(n) slabs of equal width hold
 * a few edges each; where long edges make the lists too long (more than 8 entries per edge) the
 * slabs are halved until they are not, so the index stays linear in size.
 *
 * Threads: reentrant; nothing here is shared.  Ownership: see planar.h.
 */
#include "core/planar.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int planar_sort_around(const planar_traits *T, const uint32_t *off, uint32_t *out, uint32_t *pos,
                       size_t v0, size_t v1)
{
    for (size_t v = v0; v < v1; v++) {
        uint32_t *o = out + off[v];
        size_t d = off[v + 1] - off[v];
        for (size_t i = 1; i < d; i++) {
            uint32_t h = o[i];
            size_t k = i;
            while (k > 0) {
                int c = T->around(T->ctx, o[k - 1], h);
                if (c == 0) return -1;
                if (c < 0) break;
                o[k] = o[k - 1];
                k--;
            }
            o[k] = h;
        }
        for (size_t i = 0; i < d; i++) pos[o[i]] = (uint32_t)i;
    }
    return 0;
}

int planar_cycles(size_t nh, const uint32_t *next, uint32_t *cyc_of, uint32_t *hes, uint32_t *hoff,
                  size_t *ncyc)
{
    size_t n = 0, k = 0;
    for (size_t h = 0; h < nh; h++) cyc_of[h] = PLANAR_NONE;
    hoff[0] = 0;
    for (size_t h0 = 0; h0 < nh; h0++) {
        if (cyc_of[h0] != PLANAR_NONE) continue;
        uint32_t cy = (uint32_t)n++, h = (uint32_t)h0;
        do {
            if (cyc_of[h] != PLANAR_NONE || k >= nh) return -2;
            cyc_of[h] = cy;
            hes[k++] = h;
            h = next[h];
        } while (h != h0);
        hoff[cy + 1] = (uint32_t)k;
    }
    *ncyc = n;
    return 0;
}

/* ---- the slab index ------------------------------------------------------------------------ */

static size_t slab_of(const planar_slabs *S, double x)
{
    double q = (x - S->x0) / S->w; /* monotone in x: so is the slab */
    if (!(q > 0)) return 0;
    if (q >= (double)S->ns) return S->ns - 1;
    return (size_t)q;
}

/* The slabs of n items with closed spans [lo[i], hi[i]]: about sqrt(n) of them, fewer when the
 * lists would hold more than 8 entries per item.  Returns 0, or -1 out of memory. */
static int slabs_build(planar_slabs *S, size_t n, const double *lo, const double *hi)
{
    double x0 = INFINITY, x1 = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        x0 = lo[i] < x0 ? lo[i] : x0;
        x1 = hi[i] > x1 ? hi[i] : x1;
    }
    size_t ns = 1, total;
    while (ns * ns < n) ns *= 2;
    S->x0 = x0;
    for (;;) {
        S->ns = ns;
        S->w = (x1 - x0) / (double)ns;
        if (!(S->w > 0) || !isfinite(S->w)) S->ns = ns = 1, S->w = 1;
        total = 0;
        for (size_t i = 0; i < n; i++) total += slab_of(S, hi[i]) - slab_of(S, lo[i]) + 1;
        if (total <= 8 * n + ns || ns == 1) break;
        ns /= 2;
    }
    S->off = calloc(ns + 1, sizeof *S->off);
    S->item = malloc((total + 1) * sizeof *S->item);
    if (!S->off || !S->item || total > UINT32_MAX) return -1;
    for (size_t i = 0; i < n; i++)
        for (size_t s = slab_of(S, lo[i]), e = slab_of(S, hi[i]); s <= e; s++) S->off[s + 1]++;
    for (size_t s = 0; s < ns; s++) S->off[s + 1] += S->off[s];
    for (size_t i = 0; i < n; i++) /* in item order within each slab */
        for (size_t s = slab_of(S, lo[i]), e = slab_of(S, hi[i]); s <= e; s++)
            S->item[S->off[s]++] = (uint32_t)i;
    for (size_t s = ns; s > 0; s--) S->off[s] = S->off[s - 1];
    S->off[0] = 0;
    return 0;
}

int planar_place(const planar_traits *T, size_t ne, const double *elo, const double *ehi,
                 const uint32_t *ecomp, size_t nq, const double *qlo, const double *qhi,
                 uint32_t *best)
{
    planar_slabs S = {0};
    if (slabs_build(&S, ne, elo, ehi)) {
        free(S.off);
        free(S.item);
        return -1;
    }
    for (size_t k = 0; k < nq; k++) {
        uint32_t b = PLANAR_NONE;
        for (size_t s = slab_of(&S, qlo[k]), s1 = slab_of(&S, qhi[k]); s <= s1; s++)
            for (uint32_t i = S.off[s]; i < S.off[s + 1]; i++) {
                uint32_t e = S.item[i];
                if (ecomp[e] == k || ehi[e] < qlo[k] || elo[e] > qhi[k]) continue;
                if (e == b || !T->below(T->ctx, e, (uint32_t)k)) continue;
                if (b == PLANAR_NONE || T->higher(T->ctx, e, b)) b = e;
            }
        best[k] = b;
    }
    free(S.off);
    free(S.item);
    return 0;
}
