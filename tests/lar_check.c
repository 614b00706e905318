/* lar_check.c — see lar_check.h. */
#include "tests/lar_check.h"

#include "core/bool3.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int bad(char *msg, size_t len, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, len, fmt, ap);
    va_end(ap);
    return -1;
}

/* Edge index of {u, v} by binary search in the sorted EV (ne edges), or -1. */
static long find_ev(const uint32_t *EV, size_t ne, uint32_t u, uint32_t v)
{
    uint32_t a = u < v ? u : v, b = u < v ? v : u;
    size_t lo = 0, hi = ne;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        uint32_t x = EV[2 * mid], y = EV[2 * mid + 1];
        if (x < a || (x == a && y < b))
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo < ne && EV[2 * lo] == a && EV[2 * lo + 1] == b) return (long)lo;
    return -1;
}

static long find_edge(const lar2 *c, uint32_t u, uint32_t v)
{
    return find_ev(c->EV, c->ne, u, v);
}

/* EV: every row v0 < v1 < nv, rows sorted and unique.  0, or -1 with a message. */
static int ev_check(const uint32_t *EV, size_t ne, size_t nv, char *msg, size_t len)
{
    for (size_t e = 0; e < ne; e++) {
        uint32_t a = EV[2 * e], b = EV[2 * e + 1];
        if (a >= b || b >= nv) return bad(msg, len, "EV[%zu] = [%u, %u] not v0 < v1 < nv", e, a, b);
        if (e && (EV[2 * e - 2] > a || (EV[2 * e - 2] == a && EV[2 * e - 1] >= b)))
            return bad(msg, len, "EV not sorted and unique at %zu", e);
    }
    return 0;
}

double lar_face_area(const lar2 *c, size_t f)
{
    double a = lar2_cycle_area(c, c->face_cycle[f]);
    for (uint32_t h = c->hole_off[f]; h < c->hole_off[f + 1]; h++)
        a += lar2_cycle_area(c, c->hole_cyc[h]);
    return a;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

size_t lar_sorted_areas_differ(const lar2 *c, const double *ref, size_t nref, double tol_abs,
                               double *worst)
{
    *worst = 0;
    if (c->nf != nref) return nref + 1;
    double *a = malloc((c->nf + 1) * sizeof *a);
    if (!a) return nref + 1;
    for (size_t f = 0; f < c->nf; f++) a[f] = lar_face_area(c, f);
    qsort(a, c->nf, sizeof *a, cmp_double);
    size_t bad = 0;
    for (size_t f = 0; f < c->nf; f++) {
        double d = fabs(a[f] - ref[f]);
        if (d > 1e-9 * fabs(ref[f]) + tol_abs) bad++;
        *worst = fmax(*worst, d / fmax(fabs(ref[f]), 1e-300));
    }
    free(a);
    return bad;
}

static uint32_t uf(uint32_t *p, uint32_t x)
{
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
}

int lar_check(const lar2 *c, char *msg, size_t len)
{
    int rc = -1;
    int *use = calloc(2 * c->ne + 1, sizeof *use);
    int *net = calloc(c->ne + 1, sizeof *net);
    long *vsum = calloc(c->nv + 1, sizeof *vsum);
    uint32_t *par = malloc((c->nv + 1) * sizeof *par);
    if (!use || !net || !vsum || !par) {
        bad(msg, len, "out of memory");
        goto out;
    }
    if (ev_check(c->EV, c->ne, c->nv, msg, len)) goto out;
    /* every cycle a closed walk; every directed edge used once */
    for (size_t cy = 0; cy < c->ncyc; cy++) {
        uint32_t s = c->cyc_off[cy], t = c->cyc_off[cy + 1];
        if (t - s < 2) {
            bad(msg, len, "cycle %zu has %u vertices", cy, t - s);
            goto out;
        }
        for (uint32_t i = s; i < t; i++) {
            uint32_t u = c->cyc[i], v = c->cyc[i + 1 < t ? i + 1 : s];
            long e = find_edge(c, u, v);
            if (e < 0) {
                bad(msg, len, "cycle %zu steps %u -> %u along no edge", cy, u, v);
                goto out;
            }
            use[2 * e + (u > v)]++;
        }
    }
    for (size_t h = 0; h < 2 * c->ne; h++)
        if (use[h] != 1) {
            bad(msg, len, "edge %zu walked %d times in direction %zu", h / 2, use[h], h % 2);
            goto out;
        }
    /* FE = net signed edges of the face's cycles; d1 d2 = 0 */
    for (size_t f = 0; f < c->nf; f++) {
        memset(net, 0, c->ne * sizeof *net);
        for (uint32_t j = 0; j <= c->hole_off[f + 1] - c->hole_off[f]; j++) {
            uint32_t cy = j == 0 ? c->face_cycle[f] : c->hole_cyc[c->hole_off[f] + j - 1];
            uint32_t s = c->cyc_off[cy], t = c->cyc_off[cy + 1];
            for (uint32_t i = s; i < t; i++) {
                uint32_t u = c->cyc[i], v = c->cyc[i + 1 < t ? i + 1 : s];
                net[find_edge(c, u, v)] += u < v ? 1 : -1;
            }
        }
        for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
            int32_t s = c->fe[i];
            long e = labs((long)s) - 1;
            if (e < 0 || (size_t)e >= c->ne) {
                bad(msg, len, "FE[%zu] has edge %ld out of range", f, e);
                goto out;
            }
            net[e] -= s > 0 ? 1 : -1;
            vsum[c->EV[2 * e]] -= s > 0 ? 1 : -1;
            vsum[c->EV[2 * e + 1]] += s > 0 ? 1 : -1;
        }
        for (size_t e = 0; e < c->ne; e++)
            if (net[e]) {
                bad(msg, len, "FE row %zu disagrees with its cycles at edge %zu", f, e);
                goto out;
            }
        for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
            long e = labs((long)c->fe[i]) - 1;
            if (vsum[c->EV[2 * e]] || vsum[c->EV[2 * e + 1]]) {
                bad(msg, len, "d1 d2 != 0 in column %zu", f);
                goto out;
            }
        }
    }
    /* orientation and areas */
    /* a flat walk (a tree kept with keep_dangling) has area 0 exactly on the grid, and
     * about scale^2 * 1e-16 per vertex in doubles: anything below flat is treated as 0 */
    double fsum = 0, esum = 0, scale = 0;
    for (size_t v = 0; v < 2 * c->nv; v++) scale = fmax(scale, fabs(c->V[v]));
    double flat = 1e-13 * scale * scale * (double)(c->ne + 1);
    for (size_t f = 0; f < c->nf; f++) {
        if (!(lar2_cycle_area(c, c->face_cycle[f]) > 0)) {
            bad(msg, len, "face %zu outer cycle not counter-clockwise", f);
            goto out;
        }
        for (uint32_t h = c->hole_off[f]; h < c->hole_off[f + 1]; h++)
            if (lar2_cycle_area(c, c->hole_cyc[h]) > flat) {
                bad(msg, len, "face %zu has a counter-clockwise hole", f);
                goto out;
            }
        fsum += lar_face_area(c, f);
    }
    for (size_t x = 0; x < c->next; x++) {
        double a = lar2_cycle_area(c, c->ext_cyc[x]);
        if (a > flat) {
            bad(msg, len, "exterior cycle %zu counter-clockwise (area %g)", x, a);
            goto out;
        }
        esum -= a;
    }
    if (fabs(fsum - esum) > 1e-9 * fmax(esum, 1e-300) + 1e-12 * scale * scale) {
        bad(msg, len, "face areas add up to %.17g, exterior encloses %.17g", fsum, esum);
        goto out;
    }
    /* Euler: V - E + F = components */
    for (size_t v = 0; v < c->nv; v++) par[v] = (uint32_t)v;
    size_t comps = c->nv;
    for (size_t e = 0; e < c->ne; e++) {
        uint32_t a = uf(par, c->EV[2 * e]), b = uf(par, c->EV[2 * e + 1]);
        if (a != b) {
            par[a] = b;
            comps--;
        }
    }
    if ((long)c->nv - (long)c->ne + (long)c->nf != (long)comps) {
        bad(msg, len, "V - E + F = %ld, components = %zu", (long)c->nv - (long)c->ne + (long)c->nf,
            comps);
        goto out;
    }
    if (c->stats.components != comps) {
        bad(msg, len, "stats.components = %zu, found %zu", c->stats.components, comps);
        goto out;
    }
    rc = 0;
out:
    free(use);
    free(net);
    free(vsum);
    free(par);
    return rc;
}

/* ------------------------------------------------------------------ 3D */

/* Six times the signed volume of the cone from o over face f's cycles (fans); *abs (may be NULL)
 * gets the sum of the terms' magnitudes, which bounds the rounding error of the sum. */
static double cone6a(const lar3 *c, uint32_t f, const double *o, double *abs)
{
    double s = 0;
    for (uint32_t cy = c->fc_off[f]; cy < c->fc_off[f + 1]; cy++) {
        uint32_t c0 = c->cyc_off[c->fc[cy]], c1 = c->cyc_off[c->fc[cy] + 1];
        const double *q0 = c->V + 3 * (size_t)c->cyc[c0];
        double a[3] = {q0[0] - o[0], q0[1] - o[1], q0[2] - o[2]};
        for (uint32_t i = c0 + 1; i + 1 < c1; i++) {
            const double *q1 = c->V + 3 * (size_t)c->cyc[i], *q2 = c->V + 3 * (size_t)c->cyc[i + 1];
            double b[3] = {q1[0] - o[0], q1[1] - o[1], q1[2] - o[2]};
            double d[3] = {q2[0] - o[0], q2[1] - o[1], q2[2] - o[2]};
            double t = a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
                       a[2] * (b[0] * d[1] - b[1] * d[0]);
            s += t;
            if (abs) { /* rounding of the sum, and of the coordinates themselves (eps each) */
                double na = fabs(a[0]) + fabs(a[1]) + fabs(a[2]);
                double nb = fabs(b[0]) + fabs(b[1]) + fabs(b[2]);
                double nd = fabs(d[0]) + fabs(d[1]) + fabs(d[2]);
                abs[0] += fabs(a[0]) * (fabs(b[1] * d[2]) + fabs(b[2] * d[1])) +
                          fabs(a[1]) * (fabs(b[0] * d[2]) + fabs(b[2] * d[0])) +
                          fabs(a[2]) * (fabs(b[0] * d[1]) + fabs(b[1] * d[0]));
                abs[1] += 2 * (nb * nd + na * nd + na * nb);
            }
        }
    }
    return s;
}

/* The cones are taken from a vertex of the cell, so that a small cell far from the origin does
 * not lose its volume to cancellation.  *err (may be NULL): a bound of the rounding of the sum
 * (the coordinates are themselves rounded: a cell thinner than that has no reliable sign). */
static double cell_volume(const lar3 *c, size_t k, double *err)
{
    double v = 0, abs[2] = {0, 0}, big = 0;
    if (c->cf_off[k] == c->cf_off[k + 1]) return 0;
    int32_t s0 = c->cf[c->cf_off[k]];
    uint32_t f0 = (uint32_t)(s0 > 0 ? s0 : -s0) - 1;
    const double *o = c->V + 3 * (size_t)c->cyc[c->cyc_off[c->fc[c->fc_off[f0]]]];
    for (uint32_t i = c->cf_off[k]; i < c->cf_off[k + 1]; i++) {
        int32_t s = c->cf[i];
        uint32_t f = (uint32_t)(s > 0 ? s : -s) - 1;
        v += (s > 0 ? 1 : -1) * cone6a(c, f, o, abs);
    }
    for (size_t i = 0; err && i < 3 * c->nv; i++)
        if (fabs(c->V[i]) > big) big = fabs(c->V[i]);
    /* each written coordinate is within half an ulp of its point: eps of its largest */
    if (err) *err = (abs[0] * 0x1p-48 + abs[1] * big * 0x1p-52) / 6;
    return v / 6;
}

double lar3_cell_volume(const lar3 *c, size_t k)
{
    return cell_volume(c, k, NULL);
}

/* Adds sign * FE(f) into acc (per edge). */
static void add_face(const lar3 *c, uint32_t f, int sign, long *acc)
{
    for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
        int32_t s = c->fe[i];
        acc[(s > 0 ? s : -s) - 1] += sign * (s > 0 ? 1 : -1);
    }
}

int lar3_check(const lar3 *c, double tol, long *euler, char *msg, size_t len)
{
    int rc = -1;
    long *acc = calloc(c->ne + 1, sizeof *acc);
    long *vacc = calloc(c->nv + 1, sizeof *vacc);
    int *seen = calloc(c->nf + 1, sizeof *seen);
    if (!acc || !vacc || !seen) {
        bad(msg, len, "out of memory");
        goto done;
    }
    if (ev_check(c->EV, c->ne, c->nv, msg, len)) goto done;
    for (size_t f = 0; f < c->nf; f++) {
        /* FE equals the signed sum of the cycles' edges */
        memset(acc, 0, c->ne * sizeof *acc);
        const double *n = c->FN + 3 * f;
        double d = 0;
        int first = 1;
        for (uint32_t cy = c->fc_off[f]; cy < c->fc_off[f + 1]; cy++) {
            uint32_t c0 = c->cyc_off[c->fc[cy]], c1 = c->cyc_off[c->fc[cy] + 1];
            /* a hole may be a contact: one vertex (nothing walked) or an edge walked both ways */
            if (c1 - c0 < (cy == c->fc_off[f] ? 3u : 1u)) {
                bad(msg, len, "face %zu: a cycle of %u vertices", f, c1 - c0);
                goto done;
            }
            if (c1 - c0 == 2 && c->cyc[c0] == c->cyc[c0 + 1]) {
                bad(msg, len, "face %zu: a hole walks one vertex twice", f);
                goto done;
            }
            for (uint32_t i = c0; i < c1 && c1 - c0 > 1; i++) {
                uint32_t u = c->cyc[i], v = c->cyc[i + 1 < c1 ? i + 1 : c0];
                long e = find_ev(c->EV, c->ne, u, v);
                if (e < 0) {
                    bad(msg, len, "face %zu walks (%u, %u), not an edge", f, u, v);
                    goto done;
                }
                acc[e] += u < v ? 1 : -1;
                const double *p = c->V + 3 * (size_t)u;
                double pd = n[0] * p[0] + n[1] * p[1] + n[2] * p[2];
                if (first) d = pd, first = 0;
                if (fabs(pd - d) > tol) {
                    bad(msg, len, "face %zu: vertex %u is %g off its plane", f, u, fabs(pd - d));
                    goto done;
                }
            }
        }
        for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
            int32_t s = c->fe[i];
            long e = (s > 0 ? s : -s) - 1;
            if (e >= (long)c->ne) {
                bad(msg, len, "FE[%zu]: edge out of range", f);
                goto done;
            }
            acc[e] -= s > 0 ? 1 : -1;
        }
        for (size_t e = 0; e < c->ne; e++)
            if (acc[e]) {
                bad(msg, len, "face %zu: FE is not the signed sum of its cycles (edge %zu)", f, e);
                goto done;
            }
        /* d1 . d2 = 0 */
        memset(vacc, 0, c->nv * sizeof *vacc);
        for (uint32_t i = c->fe_off[f]; i < c->fe_off[f + 1]; i++) {
            int32_t s = c->fe[i];
            uint32_t e = (uint32_t)(s > 0 ? s : -s) - 1;
            vacc[c->EV[2 * e]] -= s > 0 ? 1 : -1;
            vacc[c->EV[2 * e + 1]] += s > 0 ? 1 : -1;
        }
        for (size_t v = 0; v < c->nv; v++)
            if (vacc[v]) {
                bad(msg, len, "face %zu: d1.d2 != 0 at vertex %zu", f, v);
                goto done;
            }
    }
    /* cells: every face twice with opposite signs; d2 . d3 = 0 */
    for (size_t k = 0; k <= c->nc; k++) {
        const int32_t *row = k < c->nc ? c->cf + c->cf_off[k] : c->ext;
        size_t nrow = k < c->nc ? c->cf_off[k + 1] - c->cf_off[k] : c->next;
        memset(acc, 0, c->ne * sizeof *acc);
        for (size_t i = 0; i < nrow; i++) {
            int32_t s = row[i];
            uint32_t f = (uint32_t)(s > 0 ? s : -s) - 1;
            if (f >= c->nf) {
                bad(msg, len, "cell %zu: face out of range", k);
                goto done;
            }
            seen[f] += s > 0 ? 1 : 16;
            add_face(c, f, s > 0 ? 1 : -1, acc);
        }
        for (size_t e = 0; e < c->ne; e++)
            if (acc[e]) {
                bad(msg, len, "%s %zu: d2.d3 != 0 at edge %zu", k < c->nc ? "cell" : "exterior", k,
                    e);
                goto done;
            }
    }
    for (size_t f = 0; f < c->nf; f++)
        if (seen[f] != 17) {
            bad(msg, len, "face %zu is on %d + and %d - cell sides (want 1 and 1)", f, seen[f] % 16,
                seen[f] / 16);
            goto done;
        }
    double total = 0, ext = 0, total_scale = 0;
    for (size_t k = 0; k < c->nc; k++) total_scale += fabs(c->cvol[k]);
    total_scale = total_scale / (c->nc + 1) + 1e-300;
    for (size_t k = 0; k < c->nc; k++) {
        /* the core's volume (from exact points) must be positive; the one from the written
         * doubles must agree with it within its rounding */
        double err, v = cell_volume(c, k, &err);
        if (!(c->cvol[k] > 0) || !(v > -err) ||
            fabs(v - c->cvol[k]) > 1e-9 * (fabs(v) + total_scale) + err) {
            bad(msg, len, "cell %zu: volume %.17g (cvol %.17g)", k, v, c->cvol[k]);
            goto done;
        }
        total += v;
    }
    for (size_t i = 0; i < c->next; i++) {
        int32_t s = c->ext[i];
        ext += (s > 0 ? 1 : -1) * lar3_face_cone(c, (uint32_t)(s > 0 ? s : -s) - 1);
    }
    if (fabs(total + ext) > 1e-9 * (fabs(total) + 1)) {
        bad(msg, len, "bounded volumes add up to %.17g, the exterior encloses %.17g", total, -ext);
        goto done;
    }
    if (euler) *euler = (long)c->nv - (long)c->ne + (long)c->nf - (long)c->nc - 1;
    rc = 0;
done:
    free(acc);
    free(vacc);
    free(seen);
    return rc;
}

long lar3_membership_dense(const lar3 *c, uint8_t *mem, member_rows *rows)
{
    uint32_t bad;
    int rc = bool3_membership(c, rows, &bad);
    if (rc) return rc;
    memset(mem, 0, c->nc * c->nsolids);
    for (size_t k = 0; k < c->nc; k++)
        for (uint32_t j = rows->off[k]; j < rows->off[k + 1]; j++)
            mem[k * c->nsolids + rows->idx[j]] = 1;
    return 0;
}
