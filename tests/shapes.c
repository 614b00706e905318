/* shapes.c — see shapes.h. */
#include "tests/shapes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double face_cone6(const solid *s, size_t f)
{
    double v = 0;
    for (uint32_t k = s->face_off[f]; k < s->face_off[f + 1]; k++) {
        uint32_t lo = s->cyc_off[k], hi = s->cyc_off[k + 1];
        const double *a = s->V + 3 * (size_t)s->cyc[lo];
        for (uint32_t i = lo + 1; i + 1 < hi; i++) {
            const double *b = s->V + 3 * (size_t)s->cyc[i], *c = s->V + 3 * (size_t)s->cyc[i + 1];
            v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                 a[2] * (b[0] * c[1] - b[1] * c[0]);
        }
    }
    return v;
}

double shape_volume(const solid *s)
{
    double v = 0;
    for (size_t f = 0; f < s->nf; f++) v += face_cone6(s, f);
    return v / 6;
}

double shape_area(const solid *s)
{
    double a = 0;
    for (size_t f = 0; f < s->nf; f++) {
        uint32_t k = s->face_off[f], lo = s->cyc_off[k], hi = s->cyc_off[k + 1];
        double n[3] = {0, 0, 0};
        const double *p0 = s->V + 3 * (size_t)s->cyc[lo];
        for (uint32_t i = lo + 1; i + 1 < hi; i++) {
            const double *p = s->V + 3 * (size_t)s->cyc[i], *q = s->V + 3 * (size_t)s->cyc[i + 1];
            double u[3] = {p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]};
            double w[3] = {q[0] - p0[0], q[1] - p0[1], q[2] - p0[2]};
            n[0] += u[1] * w[2] - u[2] * w[1];
            n[1] += u[2] * w[0] - u[0] * w[2];
            n[2] += u[0] * w[1] - u[1] * w[0];
        }
        a += sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 2;
    }
    return a;
}

solid shape_poly(const double *V, size_t nv, const int *F)
{
    solid s = {0};
    size_t nf = 0, ni = 0;
    for (const int *p = F; *p != -2; p++) {
        if (*p == -1)
            nf++;
        else
            ni++;
    }
    s.nv = nv;
    s.nf = s.ncyc = nf;
    s.V = malloc(3 * nv * sizeof *s.V);
    s.face_off = malloc((nf + 1) * sizeof *s.face_off);
    s.cyc_off = malloc((nf + 1) * sizeof *s.cyc_off);
    s.cyc = malloc((ni + 1) * sizeof *s.cyc);
    memcpy(s.V, V, 3 * nv * sizeof *s.V);
    size_t f = 0, k = 0;
    s.face_off[0] = s.cyc_off[0] = 0;
    for (const int *p = F; *p != -2; p++) {
        if (*p == -1) {
            f++;
            s.face_off[f] = (uint32_t)f;
            s.cyc_off[f] = (uint32_t)k;
        } else {
            s.cyc[k++] = (uint32_t)*p;
        }
    }
    if (shape_volume(&s) < 0)
        for (size_t c = 0; c < s.ncyc; c++)
            for (uint32_t i = s.cyc_off[c], j = s.cyc_off[c + 1] - 1; i < j; i++, j--) {
                uint32_t t = s.cyc[i];
                s.cyc[i] = s.cyc[j];
                s.cyc[j] = t;
            }
    return s;
}

solid shape_hexa(const double c[8][3])
{
    static const int F[] = {0, 4, 6, 2,  -1, 1, 3, 7, 5,  -1, 0, 1, 5, 4,  -1, 2,
                            6, 7, 3, -1, 0,  2, 3, 1, -1, 4,  5, 7, 6, -1, -2};
    return shape_poly(&c[0][0], 8, F);
}

solid shape_box(const double *lo, const double *hi)
{
    double c[8][3];
    for (int i = 0; i < 8; i++)
        for (int a = 0; a < 3; a++) c[i][a] = (i >> a) & 1 ? hi[a] : lo[a];
    return shape_hexa(c);
}

solid shape_tet(const double *a, const double *b, const double *c, const double *d)
{
    double V[12];
    memcpy(V, a, 3 * sizeof *V);
    memcpy(V + 3, b, 3 * sizeof *V);
    memcpy(V + 6, c, 3 * sizeof *V);
    memcpy(V + 9, d, 3 * sizeof *V);
    static const int F[] = {0, 2, 1, -1, 0, 1, 3, -1, 0, 3, 2, -1, 1, 2, 3, -1, -2};
    return shape_poly(V, 4, F);
}

/* The sides of a prism over n base vertices (bottom 0 .. n-1, top n .. 2n-1): quad i runs
 * i, i+1, n+i+1, n+i (faces out for a counter-clockwise base); then the end of the face list.
 * Appends to F from k; returns the new length. */
static size_t side_quads(int *F, size_t k, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        F[k++] = (int)i;
        F[k++] = (int)((i + 1) % n);
        F[k++] = (int)(n + (i + 1) % n);
        F[k++] = (int)(n + i);
        F[k++] = -1;
    }
    F[k++] = -2;
    return k;
}

solid shape_prism(const double (*base)[3], size_t n, const double *dir)
{
    double *V = malloc(6 * n * sizeof *V);
    int *F = malloc((6 * n + 8) * sizeof *F);
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            V[3 * i + a] = base[i][a];
            V[3 * (n + i) + a] = base[i][a] + dir[a];
        }
    for (size_t i = 0; i < n; i++) F[k++] = (int)(n - 1 - i); /* bottom, reversed */
    F[k++] = -1;
    for (size_t i = 0; i < n; i++) F[k++] = (int)(n + i);
    F[k++] = -1;
    k = side_quads(F, k, n);
    solid s = shape_poly(V, 2 * n, F);
    free(V);
    free(F);
    return s;
}

solid shape_fan_slab(size_t n, double len, double w, double bulge, double spread, double h)
{
    double(*b)[3] = malloc(n * sizeof *b);
    b[0][0] = 0, b[0][1] = 0, b[0][2] = 0;
    b[1][0] = len, b[1][1] = 0, b[1][2] = 0;
    for (size_t i = 2; i < n; i++) {
        /* t from 0 (at (len, w)) to 1 (at (0, w)), crowded at its start by spread */
        double t = pow((double)(i - 2) / (double)(n - 3), 1 / spread);
        b[i][0] = len * (1 - t);
        b[i][1] = w + bulge * 4 * t * (1 - t);
        b[i][2] = 0;
    }
    /* top and bottom as fans from vertex 0; the sides as quads */
    double *V = malloc(6 * n * sizeof *V);
    int *F = malloc((16 * n + 8) * sizeof *F);
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            V[3 * i + a] = b[i][a];
            V[3 * (n + i) + a] = b[i][a] + (a == 2 ? h : 0);
        }
    for (size_t i = 1; i + 1 < n; i++) {
        F[k++] = 0, F[k++] = (int)(i + 1), F[k++] = (int)i, F[k++] = -1;
        F[k++] = (int)n, F[k++] = (int)(n + i), F[k++] = (int)(n + i + 1), F[k++] = -1;
    }
    k = side_quads(F, k, n);
    solid s = shape_poly(V, 2 * n, F);
    free(b);
    free(V);
    free(F);
    return s;
}

void shape_transform(solid *s, const double R[3][3], const double *t)
{
    for (size_t v = 0; v < s->nv; v++) {
        double *p = s->V + 3 * v, q[3];
        for (int a = 0; a < 3; a++) q[a] = R[a][0] * p[0] + R[a][1] * p[1] + R[a][2] * p[2] + t[a];
        memcpy(p, q, sizeof q);
    }
}

void shape_translate(solid *s, const double *t)
{
    for (size_t v = 0; v < s->nv; v++)
        for (int a = 0; a < 3; a++) s->V[3 * v + a] += t[a];
}

void shape_rotation(const double *u, double a, double R[3][3])
{
    double c = cos(a), sn = sin(a), C = 1 - c;
    R[0][0] = c + u[0] * u[0] * C, R[0][1] = u[0] * u[1] * C - u[2] * sn;
    R[0][2] = u[0] * u[2] * C + u[1] * sn;
    R[1][0] = u[1] * u[0] * C + u[2] * sn, R[1][1] = c + u[1] * u[1] * C;
    R[1][2] = u[1] * u[2] * C - u[0] * sn;
    R[2][0] = u[2] * u[0] * C - u[1] * sn, R[2][1] = u[2] * u[1] * C + u[0] * sn;
    R[2][2] = c + u[2] * u[2] * C;
}
