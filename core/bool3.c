/* bool3.c — see bool3.h. */
#include "core/bool3.h"

#include "core/mem.h"
#include "core/util.h"

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

int bool3_membership(const lar3 *c, member_rows *rows, uint32_t *bad_face)
{
    return bool3_membership_ex(c, rows, bad_face, NULL, NULL);
}

/* The walk over the units (lar3.u_off): a unit's faces separate the same two cells and have the
 * same solids, so the walk crosses units, not faces.  With winding numbers (lar3.fwind), a
 * unit's first side is ucell[2u + 1], its second ucell[2u]; crossing from the first to the
 * second goes along its first face's normal unless that face is reversed (frev), and changes
 * each solid's winding number by -fwind along the normal.  Without, a unit's solids are
 * toggled. */
static int membership_units(const lar3 *c, member_rows *rows, uint32_t *bad_face,
                            void (*tick)(void *udata, double f), void *udata)
{
    int wind = c->fwind && c->frev;
    size_t ns = c->nsolids, nc = c->nc, nn = nc + 1, nu = c->nunit;
    uint32_t *toff = mem_malloc((nu + 2) * sizeof *toff);
    uint32_t *tags = mem_malloc((c->fsol_off[c->nf] + 1) * sizeof *tags);
    int32_t *dw = wind ? mem_malloc((c->fsol_off[c->nf] + 1) * sizeof *dw) : NULL;
    uint32_t *aoff = mem_calloc(nn + 2, sizeof *aoff);
    uint32_t *nb = mem_malloc((2 * nu + 1) * sizeof *nb),
             *el = mem_malloc((2 * nu + 1) * sizeof *el);
    int8_t *dir = mem_malloc(2 * nu + 1);
    int rc = -1;
    *bad_face = UINT32_MAX;
    memset(rows, 0, sizeof *rows);
    if (!toff || !tags || (wind && !dw) || !aoff || !nb || !el || !dir) goto done;
    /* each unit's solids (those of its first face): with their changes of winding number
     * (ascending, each once: arr3), or sorted and counted modulo 2 */
    toff[0] = 0;
    for (size_t u = 0; u < nu; u++) {
        uint32_t w = toff[u], n = 0, f = c->u_off[u];
        if (f < c->u_off[u + 1])
            for (uint32_t j = c->fsol_off[f]; j < c->fsol_off[f + 1]; j++)
                if (c->fsol[j] < ns) {
                    if (wind) dw[w + n] = c->frev[f] ? c->fwind[j] : -c->fwind[j];
                    tags[w + n++] = c->fsol[j];
                }
        if (wind) {
            toff[u + 1] = w + n;
            continue;
        }
        qsort(tags + w, n, sizeof *tags, u32_cmp);
        uint32_t k = 0;
        for (uint32_t i = 0; i < n;) {
            uint32_t j = i;
            while (j < n && tags[w + j] == tags[w + i]) j++;
            if ((j - i) & 1) tags[w + k++] = tags[w + i];
            i = j;
        }
        toff[u + 1] = w + k;
    }
    for (size_t u = 0; u < nu; u++) {
        uint32_t a = c->ucell[2 * u], b = c->ucell[2 * u + 1];
        if (a > nc || b > nc) goto done;
        if (a != b) aoff[a + 2]++, aoff[b + 2]++;
    }
    for (size_t k = 0; k < nn; k++) aoff[k + 2] += aoff[k + 1];
    for (size_t u = 0; u < nu; u++) {
        uint32_t second = c->ucell[2 * u], first = c->ucell[2 * u + 1];
        if (first == second) continue;
        nb[aoff[second + 1]] = first, el[aoff[second + 1]] = (uint32_t)u;
        dir[aoff[second + 1]++] = -1;
        nb[aoff[first + 1]] = second, el[aoff[first + 1]] = (uint32_t)u;
        dir[aoff[first + 1]++] = 1;
    }
    uint32_t bad = UINT32_MAX;
    rc = wind ? member_walk_wind(nn, (uint32_t)nc, aoff, nb, el, dir, toff, tags, dw, rows, &bad,
                                 tick, udata, NULL)
              : member_walk_ex(nn, (uint32_t)nc, aoff, nb, el, toff, tags, rows, &bad, tick, udata,
                               NULL);
    if (bad != UINT32_MAX) *bad_face = c->u_off[bad];
done:
    free(toff), free(tags), free(dw), free(aoff), free(nb), free(el), free(dir);
    return rc;
}

int bool3_membership_ex(const lar3 *c, member_rows *rows, uint32_t *bad_face,
                        void (*tick)(void *udata, double f), void *udata)
{
    if (c->u_off && c->ucell) return membership_units(c, rows, bad_face, tick, udata);
    size_t ns = c->nsolids, nc = c->nc, nn = nc + 1;
    uint32_t *minus = mem_malloc((c->nf + 1) * sizeof *minus);
    uint32_t *plus = mem_malloc((c->nf + 1) * sizeof *plus);
    uint32_t *toff = mem_malloc((c->nf + 2) * sizeof *toff);
    uint32_t *tags = mem_malloc((c->fsol_off[c->nf] + 1) * sizeof *tags);
    uint32_t *aoff = mem_calloc(nn + 2, sizeof *aoff);
    uint32_t *nb = mem_malloc((2 * c->nf + 1) * sizeof *nb),
             *fc = mem_malloc((2 * c->nf + 1) * sizeof *fc);
    int rc = -1;
    *bad_face = UINT32_MAX;
    memset(rows, 0, sizeof *rows);
    if (!minus || !plus || !toff || !tags || !aoff || !nb || !fc || face_sides(c, minus, plus))
        goto done;
    /* each face's solids, sorted, counted modulo 2 */
    toff[0] = 0;
    for (size_t f = 0; f < c->nf; f++) {
        uint32_t w = toff[f], n = 0;
        for (uint32_t j = c->fsol_off[f]; j < c->fsol_off[f + 1]; j++)
            if (c->fsol[j] < ns) tags[w + n++] = c->fsol[j];
        qsort(tags + w, n, sizeof *tags, u32_cmp);
        uint32_t k = 0;
        for (uint32_t i = 0; i < n;) {
            uint32_t j = i;
            while (j < n && tags[w + j] == tags[w + i]) j++;
            if ((j - i) & 1) tags[w + k++] = tags[w + i];
            i = j;
        }
        toff[f + 1] = w + k;
    }
    /* the cells (the exterior is cell nc) through their faces */
    for (size_t f = 0; f < c->nf; f++)
        if (minus[f] != NONE && plus[f] != NONE && minus[f] != plus[f])
            aoff[minus[f] + 2]++, aoff[plus[f] + 2]++;
    for (size_t k = 0; k < nn; k++) aoff[k + 2] += aoff[k + 1];
    for (size_t f = 0; f < c->nf; f++)
        if (minus[f] != NONE && plus[f] != NONE && minus[f] != plus[f]) {
            nb[aoff[minus[f] + 1]] = plus[f], fc[aoff[minus[f] + 1]++] = (uint32_t)f;
            nb[aoff[plus[f] + 1]] = minus[f], fc[aoff[plus[f] + 1]++] = (uint32_t)f;
        }
    rc = member_walk_ex(nn, (uint32_t)nc, aoff, nb, fc, toff, tags, rows, bad_face, tick, udata,
                        NULL);
done:
    free(minus);
    free(plus);
    free(toff);
    free(tags);
    free(aoff);
    free(nb);
    free(fc);
    return rc;
}

int bool3_select(const lar3 *c, const member_rows *rows, const bool_expr *e, bool3_result *r)
{
    return bool3_select_fill(c, rows, e, BOOL3_FILL_POSITIVE, r);
}

int bool3_select_fill(const lar3 *c, const member_rows *rows, const bool_expr *e, int fill,
                      bool3_result *r)
{
    size_t nc = c->nc;
    uint8_t *sel = mem_calloc(nc + 1, 1);
    uint32_t *inside = mem_malloc((member_row_most(rows, nc) + 1) * sizeof *inside);
    uint32_t *minus = mem_malloc((c->nf + 1) * sizeof *minus);
    uint32_t *plus = mem_malloc((c->nf + 1) * sizeof *plus);
    bool_tree t = {0};
    int rc = -1, tree = 0;
    memset(r, 0, sizeof *r);
    if (!sel || !inside || !minus || !plus ||
        (!(c->u_off && c->ucell) && face_sides(c, minus, plus)))
        goto done;
    if (bool_tree_build(e, c->nsolids, &t)) goto done;
    tree = 1;
    r->cells = mem_malloc((nc + 1) * sizeof *r->cells);
    r->faces = mem_malloc((c->nf + 1) * sizeof *r->faces);
    if (!r->cells || !r->faces) goto done;
    for (size_t k = 0; k < nc; k++) {
        const uint32_t *in; /* the solids the cell is inside of, by the fill rule */
        size_t nin = member_row_inside(rows, k, fill, inside, &in);
        sel[k] = (uint8_t)bool_tree_eval(&t, in, nin);
        if (sel[k]) {
            r->cells[r->ncells++] = (uint32_t)k;
            r->volume += c->cvol[k];
        }
    }
    if (c->u_off && c->ucell) { /* unit by unit: its faces separate the same two cells */
        for (size_t u = 0; u < c->nunit; u++) {
            uint32_t into = c->ucell[2 * u], outof = c->ucell[2 * u + 1];
            if (into == outof || sel[into] == sel[outof]) continue;
            for (uint32_t f = c->u_off[u]; f < c->u_off[u + 1]; f++) {
                int a = sel[c->frev[f] ? into : outof]; /* the cell f's normal points out of */
                r->faces[r->nfaces++] = a ? (int32_t)(f + 1) : -(int32_t)(f + 1);
            }
        }
    } else {
        for (size_t f = 0; f < c->nf; f++) {
            if (minus[f] == NONE || plus[f] == NONE) continue;
            int a = sel[minus[f]], b = sel[plus[f]];
            if (a != b) r->faces[r->nfaces++] = a ? (int32_t)(f + 1) : -(int32_t)(f + 1);
        }
    }
    rc = 0;
done:
    if (rc) bool3_result_free(r);
    if (tree) bool_tree_free(&t);
    free(sel);
    free(inside);
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
