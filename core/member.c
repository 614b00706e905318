/* member.c — see member.h. */
#include "core/member.h"

#include <stdlib.h>
#include <string.h>

#include "core/mem.h"

void member_rows_free(member_rows *r)
{
    free(r->off);
    free(r->idx);
    free(r->wind);
    memset(r, 0, sizeof *r);
}

int member_inside(int32_t w, int fill)
{
    return fill == MEMBER_FILL_NONZERO ? w != 0 : fill == MEMBER_FILL_ODD ? (w & 1) != 0 : w > 0;
}

size_t member_row_most(const member_rows *r, size_t n)
{
    size_t most = 0;
    for (size_t k = 0; k < n; k++)
        if (r->off[k + 1] - r->off[k] > most) most = r->off[k + 1] - r->off[k];
    return most;
}

size_t member_row_inside(const member_rows *r, size_t k, int fill, uint32_t *buf,
                         const uint32_t **row)
{
    const uint32_t *in = r->idx + r->off[k];
    size_t n = r->off[k + 1] - r->off[k], m = 0;
    *row = in;
    if (!r->wind) return n;
    for (size_t i = 0; i < n; i++)
        if (member_inside(r->wind[r->off[k] + i], fill)) buf[m++] = in[i];
    *row = buf;
    return m;
}

size_t member_symdiff(const uint32_t *a, size_t na, const uint32_t *b, size_t nb, uint32_t *out)
{
    size_t i = 0, j = 0, k = 0;
    while (i < na && j < nb) {
        if (a[i] < b[j])
            out[k++] = a[i++];
        else if (b[j] < a[i])
            out[k++] = b[j++];
        else
            i++, j++;
    }
    while (i < na) out[k++] = a[i++];
    while (j < nb) out[k++] = b[j++];
    return k;
}

int member_walk(size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                const uint32_t *el, const uint32_t *toff, const uint32_t *tags, member_rows *rows,
                uint32_t *bad_el)
{
    return member_walk_ex(n, root, aoff, nb, el, toff, tags, rows, bad_el, NULL, NULL, NULL);
}

/* out = a + sign * b over sorted (input, winding) lists, zeros left out; returns its length. */
static size_t wsum(const uint32_t *ai, const int32_t *aw, size_t na, const uint32_t *bi,
                   const int32_t *bw, size_t nb, int sign, uint32_t *oi, int32_t *ow)
{
    size_t i = 0, j = 0, k = 0;
    while (i < na || j < nb) {
        uint32_t t;
        int64_t w;
        if (j == nb || (i < na && ai[i] < bi[j]))
            t = ai[i], w = aw[i++];
        else if (i == na || bi[j] < ai[i])
            t = bi[j], w = (int64_t)sign * bw[j++];
        else
            t = ai[i], w = aw[i++] + (int64_t)sign * bw[j++];
        if (w == 0) continue;
        if (w > INT32_MAX || w < -INT32_MAX) w = w > 0 ? INT32_MAX : -INT32_MAX; /* never met */
        oi[k] = t, ow[k] = (int32_t)w, k++;
    }
    return k;
}

/* The scratch block of n cells in ws: start, len, queue and seen (one block: the 3D planes walk
 * many small arrangements).  Returns 0, or -1 out of memory. */
static int ws_cells(member_ws *ws, size_t n, size_t **start, uint32_t **len, uint32_t **queue,
                    uint8_t **seen)
{
    if (mem_grow(&ws->blk, &ws->capblk, n + 1, sizeof(size_t) + 2 * sizeof(uint32_t) + 1))
        return -1;
    size_t cap = ws->capblk;
    *start = ws->blk;
    *len = (uint32_t *)(*start + cap);
    *queue = *len + cap;
    *seen = (uint8_t *)(*queue + cap);
    memset(*seen, 0, n + 1);
    return 0;
}

/* The rows in cell order as compressed sparse rows (buf, bw: in reach order at start[c], len[c];
 * used entries): in ws's own arrays when own is 0 (borrowed by the caller), else malloc'd to
 * the size (the caller's, freed with member_rows_free).  Returns 0, or -1 out of memory. */
static int rows_make(member_ws *ws, int own, size_t n, size_t used, const size_t *start,
                     const uint32_t *len, int with_wind, member_rows *rows)
{
    if (own) {
        rows->off = malloc((n + 1) * sizeof *rows->off);
        rows->idx = malloc((used + 1) * sizeof *rows->idx);
        if (with_wind) rows->wind = malloc((used + 1) * sizeof *rows->wind);
    } else {
        if (mem_grow(&ws->off, &ws->capoff, n + 1, sizeof *ws->off) ||
            mem_grow(&ws->idx, &ws->capidx, used + 1, sizeof *ws->idx) ||
            (with_wind && mem_grow(&ws->wind, &ws->capwind, used + 1, sizeof *ws->wind)))
            return -1;
        rows->off = ws->off, rows->idx = ws->idx, rows->wind = with_wind ? ws->wind : NULL;
    }
    if (!rows->off || !rows->idx || (with_wind && !rows->wind)) return -1;
    rows->off[0] = 0;
    for (size_t c = 0; c < n; c++) {
        memcpy(rows->idx + rows->off[c], ws->buf + start[c], len[c] * sizeof *ws->buf);
        if (with_wind)
            memcpy(rows->wind + rows->off[c], ws->bw + start[c], len[c] * sizeof *ws->bw);
        rows->off[c + 1] = rows->off[c] + len[c];
    }
    return 0;
}

/* The walk of member_walk_ex (dw NULL: each element's inputs toggled) and member_walk_wind
 * (dw: their winding numbers changed by dw, with the sign dir gives), over ws's scratch; the
 * rows are the caller's (own) or borrowed from ws (!own). */
static int walk(member_ws *ws, int own, size_t n, uint32_t root, const uint32_t *aoff,
                const uint32_t *nb, const uint32_t *el, const int8_t *dir, const uint32_t *toff,
                const uint32_t *tags, const int32_t *dw, member_rows *rows, uint32_t *bad_el,
                void (*tick)(void *udata, double f), void *udata, const atomic_int *cancel)
{
    /* rows in the order cells are reached, in one growing buffer ws->buf (ws->bw: their winding
     * numbers, with dw); a neighbour's row is made in ws->ti (ws->tw) */
    size_t *start;
    uint32_t *len, *queue;
    uint8_t *seen;
    size_t used = 0;
    int rc = -1;
    memset(rows, 0, sizeof *rows);
    *bad_el = UINT32_MAX;
    if (ws_cells(ws, n, &start, &len, &queue, &seen) ||
        mem_grow(&ws->buf, &ws->capbuf, 1024, sizeof *ws->buf) ||
        mem_grow(&ws->ti, &ws->capti, 64, sizeof *ws->ti) ||
        (dw && (mem_grow(&ws->bw, &ws->capbw, 1024, sizeof *ws->bw) ||
                mem_grow(&ws->tw, &ws->captw, 64, sizeof *ws->tw))))
        goto done;
    size_t qh = 0, qt = 0;
    queue[qt++] = root;
    seen[root] = 1;
    start[root] = 0;
    len[root] = 0;
    while (qh < qt) {
        uint32_t u = queue[qh++];
        if (tick && (qh & 0xffff) == 0) tick(udata, (double)qh / (double)n);
        if (cancel && (qh & 4095) == 0 && atomic_load_explicit(cancel, memory_order_relaxed)) {
            rc = 2;
            goto done;
        }
        for (uint32_t i = aoff[u]; i < aoff[u + 1]; i++) {
            uint32_t v = nb[i], x = el[i];
            size_t nt = toff[x + 1] - toff[x], most = len[u] + nt;
            if (mem_grow(&ws->ti, &ws->capti, most, sizeof *ws->ti) ||
                (dw && mem_grow(&ws->tw, &ws->captw, most, sizeof *ws->tw)))
                goto done;
            uint32_t *buf = ws->buf, *ti = ws->ti;
            int32_t *bw = ws->bw, *tw = ws->tw;
            size_t k = dw ? wsum(buf + start[u], bw + start[u], len[u], tags + toff[x],
                                 dw + toff[x], nt, dir[i], ti, tw)
                          : member_symdiff(buf + start[u], len[u], tags + toff[x], nt, ti);
            if (seen[v]) {
                if (k != len[v] || memcmp(ti, buf + start[v], k * sizeof *ti) ||
                    (dw && memcmp(tw, bw + start[v], k * sizeof *tw))) {
                    *bad_el = x;
                    rc = 1;
                    goto done;
                }
                continue;
            }
            if (used + k > UINT32_MAX) goto done; /* the rows' offsets are 32 bits */
            if (mem_grow(&ws->buf, &ws->capbuf, used + k, sizeof *ws->buf) ||
                (dw && mem_grow(&ws->bw, &ws->capbw, used + k, sizeof *ws->bw)))
                goto done;
            memcpy(ws->buf + used, ti, k * sizeof *ti);
            if (dw) memcpy(ws->bw + used, tw, k * sizeof *tw);
            start[v] = used;
            len[v] = (uint32_t)k;
            used += k;
            seen[v] = 1;
            queue[qt++] = v;
        }
    }
    if (qt != n) {
        rc = 1;
        goto done;
    }
    rc = rows_make(ws, own, n, used, start, len, dw != NULL, rows);
done:
    if (rc) {
        if (own) member_rows_free(rows);
        memset(rows, 0, sizeof *rows);
    }
    return rc;
}

/* walk() over a scratch of its own, the rows the caller's. */
static int walk_own(size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                    const uint32_t *el, const int8_t *dir, const uint32_t *toff,
                    const uint32_t *tags, const int32_t *dw, member_rows *rows, uint32_t *bad_el,
                    void (*tick)(void *udata, double f), void *udata, const atomic_int *cancel)
{
    member_ws ws = {0};
    int rc =
        walk(&ws, 1, n, root, aoff, nb, el, dir, toff, tags, dw, rows, bad_el, tick, udata, cancel);
    member_ws_free(&ws);
    return rc;
}

int member_walk_ws(member_ws *ws, size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                   const uint32_t *el, const uint32_t *toff, const uint32_t *tags,
                   member_rows *rows, uint32_t *bad_el)
{
    return walk(ws, 0, n, root, aoff, nb, el, NULL, toff, tags, NULL, rows, bad_el, NULL, NULL,
                NULL);
}

void member_ws_free(member_ws *ws)
{
    free(ws->blk), free(ws->buf), free(ws->bw), free(ws->ti), free(ws->tw);
    free(ws->off), free(ws->idx), free(ws->wind);
    memset(ws, 0, sizeof *ws);
}

int member_walk_ex(size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                   const uint32_t *el, const uint32_t *toff, const uint32_t *tags,
                   member_rows *rows, uint32_t *bad_el, void (*tick)(void *udata, double f),
                   void *udata, const atomic_int *cancel)
{
    return walk_own(n, root, aoff, nb, el, NULL, toff, tags, NULL, rows, bad_el, tick, udata,
                    cancel);
}

int member_walk_wind(size_t n, uint32_t root, const uint32_t *aoff, const uint32_t *nb,
                     const uint32_t *el, const int8_t *dir, const uint32_t *toff,
                     const uint32_t *tags, const int32_t *dw, member_rows *rows, uint32_t *bad_el,
                     void (*tick)(void *udata, double f), void *udata, const atomic_int *cancel)
{
    return walk_own(n, root, aoff, nb, el, dir, toff, tags, dw, rows, bad_el, tick, udata, cancel);
}
