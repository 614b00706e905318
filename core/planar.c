/* planar.c — the half-edge kernel; see planar.h for the numbering and the traits.
 *
 * Stages, each a function below: sort around vertices (insertion, the degrees are small),
 * cycles of the successor map (in the order of their smallest half-edge), placement of
 * components by a downward ray over a slab index.  Why slabs and not a tree: the edges of an
 * arrangement are short and spread across the plane, so about sqrt(n) slabs of equal width (a
 * power of two of the models' int64 keys) hold a few edges each; where long edges make the
 * lists too long (more than 8 entries per edge) the slabs are halved until they are not, so the
 * index stays linear in size.  The index is built by chunks of edges and asked by chunks of
 * queries, on par_for when the caller gives threads; the model's scan is its own tight loop
 * over a slab's edges (arr2's exact fractions, arr3_plane's filtered spans then exact tests).
 * Its scratch (planar_ws) grows to exact sizes (mem_fit): arr3_plane keeps it from plane to
 * plane, arr2 uses it once for up to millions of edges, where doubling would raise the peak.
 *
 * Threads: reentrant; nothing here is shared.  Ownership: see planar.h.
 */
#include "core/planar.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "core/par.h"
#include "core/util.h"

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

int planar_cycles(size_t nh, const uint32_t *next, uint32_t *cyc_of, uint32_t *hes, uint32_t **hoff,
                  size_t *caphoff, size_t *ncyc)
{
    size_t n = 0, k = 0;
    for (size_t h = 0; h < nh; h++) cyc_of[h] = PLANAR_NONE;
    if (mem_grow(hoff, caphoff, 1, sizeof **hoff)) return -1;
    (*hoff)[0] = 0;
    for (size_t h0 = 0; h0 < nh; h0++) {
        if (cyc_of[h0] != PLANAR_NONE) continue;
        uint32_t cy = (uint32_t)n++, h = (uint32_t)h0;
        if (mem_grow(hoff, caphoff, n + 1, sizeof **hoff)) return -1;
        do {
            if (cyc_of[h] != PLANAR_NONE || k >= nh) return -2;
            cyc_of[h] = cy;
            hes[k++] = h;
            h = next[h];
        } while (h != h0);
        (*hoff)[cy + 1] = (uint32_t)k;
    }
    *ncyc = n;
    return 0;
}

/* ---- placement: the slab index -------------------------------------------------------- */

#define ECHUNK 65536 /* edges per work item of the index */
#define QCHUNK 64    /* queries per work item */
#define EBATCH 256   /* edges per call of T->espan */

typedef struct place_job {
    const planar_traits *T;
    planar_ws *ws;
    size_t ne, nq, ns, nchunk;
    int64_t kmin;
    int shift; /* the slabs are 2^shift keys wide */
    uint32_t *best;
    atomic_int stopped;
} place_job;

/* Work items [0, n) of fn: on the calling thread when there is one thread or one item (no
 * thread started, the same worker number 0 as par_for would give), else par_for. */
static void run(int threads, size_t n, par_fn fn, void *job)
{
    if (threads <= 1 || n <= 1)
        for (size_t i = 0; i < n; i++) fn(job, i, 0);
    else
        par_for(threads, n, fn, job);
}

static int job_stop(place_job *j, int wk, size_t work)
{
    if (atomic_load_explicit(&j->stopped, memory_order_relaxed)) return 1;
    if (j->T->stop && j->T->stop(j->T->ctx, wk, work)) {
        atomic_store(&j->stopped, 1);
        return 1;
    }
    return 0;
}

/* The slab of key k (keys outside the edges' [kmin, kmax] go to the end slabs). */
static inline uint32_t slab_of(const place_job *j, int64_t k)
{
    if (k <= j->kmin) return 0;
    uint64_t s = ((uint64_t)k - (uint64_t)j->kmin) >> j->shift;
    return s >= j->ns ? (uint32_t)(j->ns - 1) : (uint32_t)s;
}

/* Chunk k of the edges: each one's first and last slab (es), and their entries (ctot[k]). */
static void range_chunk(void *vj, size_t k, int wk)
{
    place_job *j = vj;
    size_t e0 = k * ECHUNK, e1 = e0 + ECHUNK < j->ne ? e0 + ECHUNK : j->ne;
    if (job_stop(j, wk, e1 - e0)) return;
    uint32_t *es = j->ws->es;
    uint64_t t = 0;
    int64_t lo[EBATCH], hi[EBATCH];
    for (size_t b0 = e0; b0 < e1; b0 += EBATCH) {
        size_t b1 = b0 + EBATCH < e1 ? b0 + EBATCH : e1;
        j->T->espan(j->T->ctx, b0, b1, lo, hi);
        for (size_t e = b0; e < b1; e++) {
            uint32_t s0 = slab_of(j, lo[e - b0]), s1 = slab_of(j, hi[e - b0]);
            es[2 * e] = s0, es[2 * e + 1] = s1;
            t += s1 - s0 + 1;
        }
    }
    j->ws->ctot[k] = t;
}

/* Chunk k of the edges: its entries per slab (cnt, ns + 1 per chunk). */
static void count_chunk(void *vj, size_t k, int wk)
{
    place_job *j = vj;
    size_t e0 = k * ECHUNK, e1 = e0 + ECHUNK < j->ne ? e0 + ECHUNK : j->ne;
    const uint32_t *es = j->ws->es;
    uint32_t *cnt = j->ws->cnt + k * (j->ns + 1);
    (void)wk;
    for (size_t e = e0; e < e1; e++)
        for (uint32_t s = es[2 * e]; s <= es[2 * e + 1]; s++) cnt[s]++;
}

/* Chunk k of the edges, written at the chunk's own places of each slab (cnt). */
static void fill_chunk(void *vj, size_t k, int wk)
{
    place_job *j = vj;
    size_t e0 = k * ECHUNK, e1 = e0 + ECHUNK < j->ne ? e0 + ECHUNK : j->ne;
    const uint32_t *es = j->ws->es;
    uint32_t *at = j->ws->cnt + k * (j->ns + 1), *item = j->ws->item;
    (void)wk;
    for (size_t e = e0; e < e1; e++)
        for (uint32_t s = es[2 * e]; s <= es[2 * e + 1]; s++) item[at[s]++] = (uint32_t)e;
}

/* Queries [chunk * QCHUNK, ...): each one's slabs scanned by the model. */
static void query_chunk(void *vj, size_t chunk, int wk)
{
    place_job *j = vj;
    const planar_traits *T = j->T;
    const uint32_t *off = j->ws->off, *item = j->ws->item;
    size_t q0 = chunk * QCHUNK, q1 = q0 + QCHUNK < j->nq ? q0 + QCHUNK : j->nq;
    for (size_t q = q0; q < q1; q++) {
        int64_t lo, hi;
        T->qspan(T->ctx, (uint32_t)q, &lo, &hi);
        uint32_t b = PLANAR_NONE;
        for (uint32_t s = slab_of(j, lo), s1 = slab_of(j, hi); s <= s1; s++) {
            if (job_stop(j, wk, off[s + 1] - off[s] + 1)) return;
            b = T->scan(T->ctx, (uint32_t)q, item + off[s], off[s + 1] - off[s], b);
        }
        j->best[q] = b;
    }
}

/* The slabs: ns = the least power of two with ns^2 >= ne, halved while the lists would hold
 * more than 8 entries per edge; each edge listed in every slab its span meets, in edge order
 * (a bucket sort by chunks of edges: each chunk counts its edges per slab, then writes them at
 * its own offsets).  Returns 0, -1 out of memory, 1 stopped. */
static int index_build(place_job *j, int threads, int64_t kmax)
{
    planar_ws *ws = j->ws;
    size_t ne = j->ne, ns = 1, nchunk = (ne + ECHUNK - 1) / ECHUNK;
    uint64_t range = kmax > j->kmin ? (uint64_t)kmax - (uint64_t)j->kmin : 0, total;
    while (ns * ns < ne) ns *= 2;
    j->nchunk = nchunk;
    if (mem_fit(&ws->es, &ws->capes, 2 * ne + 1, sizeof *ws->es) ||
        mem_fit(&ws->ctot, &ws->capctot, nchunk + 1, sizeof *ws->ctot))
        return -1;
    for (;;) {
        j->shift = 0;
        while (j->shift < 63 && (range >> j->shift) >= ns) j->shift++;
        j->ns = ns;
        run(threads, nchunk, range_chunk, j);
        if (atomic_load(&j->stopped)) return 1;
        total = 0;
        for (size_t k = 0; k < nchunk; k++) total += ws->ctot[k];
        if (total <= 8 * (uint64_t)ne + ns || ns == 1) break;
        ns /= 2;
    }
    if (total > UINT32_MAX || mem_fit(&ws->off, &ws->capoff, ns + 2, sizeof *ws->off) ||
        mem_fit(&ws->item, &ws->capitem, total + 1, sizeof *ws->item) ||
        mem_fit(&ws->cnt, &ws->capcnt, nchunk * (ns + 1) + 1, sizeof *ws->cnt))
        return -1;
    memset(ws->cnt, 0, (nchunk * (ns + 1) + 1) * sizeof *ws->cnt);
    run(threads, nchunk, count_chunk, j);
    uint32_t at = 0; /* chunk k's entries of slab s go after those of the chunks before it */
    for (size_t s = 0; s < ns; s++) {
        ws->off[s] = at;
        for (size_t k = 0; k < nchunk; k++) {
            uint32_t n = ws->cnt[k * (ns + 1) + s];
            ws->cnt[k * (ns + 1) + s] = at;
            at += n;
        }
    }
    ws->off[ns] = ws->off[ns + 1] = at;
    run(threads, nchunk, fill_chunk, j);
    return 0;
}

int planar_place(const planar_traits *T, int threads, planar_ws *ws, size_t ne, int64_t kmin,
                 int64_t kmax, size_t nq, uint32_t *best)
{
    place_job j = {.T = T, .ws = ws, .ne = ne, .nq = nq, .kmin = kmin, .best = best};
    atomic_init(&j.stopped, 0);
    if (ne == 0) {
        for (size_t q = 0; q < nq; q++) best[q] = PLANAR_NONE;
        return 0;
    }
    int rc = index_build(&j, threads, kmax);
    if (rc) return rc;
    run(threads, (nq + QCHUNK - 1) / QCHUNK, query_chunk, &j);
    return atomic_load(&j.stopped) ? 1 : 0;
}

void planar_ws_free(planar_ws *ws)
{
    free(ws->es), free(ws->off), free(ws->item), free(ws->cnt), free(ws->ctot);
    memset(ws, 0, sizeof *ws);
}
