/* bool3.c — see bool3.h. */
#include "core/bool3.h"

#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

/* The cells on each side of every face: minus (the normal points out of it) and plus; the
 * exterior is c->nc.  Faces with one cell on both sides are in no row and stay NONE. */
static int face_sides(const lar3 *c, uint32_t *minus, uint32_t *plus)
{
    for (size_t f = 0; f < c->nf; f++) minus[f] = plus[f] = NONE;
    for (size_t k = 0; k <= c->nc; k++) {
        const int32_t *row = k < c->nc ? c->cf + c->cf_off[k] : c->ext;
        size_t n = k < c->nc ? c->cf_off[k + 1] - c->cf_off[k] : c->next;
        for (size_t i = 0; i < n; i++) {
            int32_t s = row[i];
            uint32_t f = (uint32_t)(s > 0 ? s : -s) - 1;
            if (f >= c->nf) return -1;
            if (s > 0)
                minus[f] = (uint32_t)k;
            else
                plus[f] = (uint32_t)k;
        }
    }
    return 0;
}

long bool3_membership(const lar3 *c, uint8_t *mem)
{
    size_t ns = c->nsolids, nc = c->nc;
    uint32_t *minus = malloc((c->nf + 1) * sizeof *minus);
    uint32_t *plus = malloc((c->nf + 1) * sizeof *plus);
    uint32_t *queue = malloc((nc + 2) * sizeof *queue);
    uint8_t *seen = calloc(nc + 1, 1);
    uint8_t *ext = calloc(ns + 1, 1); /* the exterior's row: all 0 */
    uint8_t *row = malloc(ns + 1);
    long bad = -1;
    if (!minus || !plus || !queue || !seen || !ext || !row || face_sides(c, minus, plus)) goto done;
    bad = 0;
    memset(mem, 0, nc * ns);
    size_t qh = 0, qt = 0;
    queue[qt++] = (uint32_t)nc;
    seen[nc] = 1;
    while (qh < qt) {
        uint32_t k = queue[qh++];
        const uint8_t *mk = k == nc ? ext : mem + (size_t)k * ns;
        const int32_t *r = k < nc ? c->cf + c->cf_off[k] : c->ext;
        size_t n = k < nc ? c->cf_off[k + 1] - c->cf_off[k] : c->next;
        for (size_t i = 0; i < n; i++) {
            uint32_t f = (uint32_t)(r[i] > 0 ? r[i] : -r[i]) - 1;
            uint32_t o = minus[f] == k ? plus[f] : minus[f];
            if (o == NONE || o == k) continue;
            memcpy(row, mk, ns);
            for (uint32_t j = c->fsol_off[f]; j < c->fsol_off[f + 1]; j++)
                if (c->fsol[j] < ns) row[c->fsol[j]] ^= 1;
            if (o == nc) {
                bad += memcmp(row, ext, ns) != 0;
                continue;
            }
            uint8_t *mo = mem + (size_t)o * ns;
            if (seen[o]) {
                bad += memcmp(row, mo, ns) != 0;
                continue;
            }
            memcpy(mo, row, ns);
            seen[o] = 1;
            queue[qt++] = o;
        }
    }
done:
    free(minus);
    free(plus);
    free(queue);
    free(seen);
    free(ext);
    free(row);
    return bad;
}

int bool3_select(const lar3 *c, const uint8_t *mem, const bool_expr *e, bool3_result *r)
{
    size_t ns = c->nsolids, nc = c->nc;
    uint8_t *sel = calloc(nc + 1, 1), *stack = malloc(e->depth + 1);
    uint32_t *minus = malloc((c->nf + 1) * sizeof *minus);
    uint32_t *plus = malloc((c->nf + 1) * sizeof *plus);
    int rc = -1;
    memset(r, 0, sizeof *r);
    if (!sel || !stack || !minus || !plus || face_sides(c, minus, plus)) goto done;
    r->cells = malloc((nc + 1) * sizeof *r->cells);
    r->faces = malloc((c->nf + 1) * sizeof *r->faces);
    if (!r->cells || !r->faces) goto done;
    for (size_t k = 0; k < nc; k++) {
        sel[k] = (uint8_t)bool_expr_eval(e, mem + k * ns, stack);
        if (sel[k]) {
            r->cells[r->ncells++] = (uint32_t)k;
            r->volume += c->cvol[k];
        }
    }
    for (size_t f = 0; f < c->nf; f++) {
        if (minus[f] == NONE || plus[f] == NONE) continue;
        int a = sel[minus[f]], b = sel[plus[f]];
        if (a != b) r->faces[r->nfaces++] = a ? (int32_t)(f + 1) : -(int32_t)(f + 1);
    }
    rc = 0;
done:
    if (rc) bool3_result_free(r);
    free(sel);
    free(stack);
    free(minus);
    free(plus);
    return rc;
}

void bool3_result_free(bool3_result *r)
{
    free(r->cells);
    free(r->faces);
    memset(r, 0, sizeof *r);
}
