/* test_render.c — pictures and maps of results (api/render.h).  Real requests go through
 * api_run_json(); their results are rendered and read back: the SVG with libxml2 (well-formed,
 * one filled <path> per face holding 1 + holes subpaths, the cycles' own coordinates, a viewBox
 * around everything drawn, exploded faces translated so their centroids are k times as far
 * from the centre, a number per vertex and per face with each face's number inside the face),
 * the GeoJSON with jansson (one Feature per face, closed rings, the outer ring counter-clockwise
 * and the holes clockwise, areas equal to those computed here from V and the cycles).  Then
 * the error values and the query parameters. */
#include "api/api.h"
#include "api/render.h"
#include "tests/check.h"

#include <jansson.h>
#include <libxml/parser.h>
#include <libxml/tree.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ORTHOGONAL                                                                                 \
    "{\"kind\":\"lines\",\"lines\":[[[0,0],[6,0]],[[0,4],[10,4]],[[0,0],[0,4]],[[3,0],[3,4]],"     \
    "[[6,0],[6,8]],[[3,2],[6,2]],[[10,0],[10,8]],[[0,8],[10,8]]]"
#define CONCENTRIC                                                                                 \
    "{\"kind\":\"lines\",\"lines\":[[[0,0],[8,0]],[[8,0],[8,8]],[[8,8],[0,8]],[[0,8],[0,0]],"      \
    "[[1,1],[7,1]],[[7,1],[7,7]],[[7,7],[1,7]],[[1,7],[1,1]],[[2,2],[6,2]],[[6,2],[6,6]],"         \
    "[[6,6],[2,6]],[[2,6],[2,2]]]"
/* a square with a dangling edge from its side and a free edge inside */
#define DANGLING                                                                                   \
    "{\"kind\":\"lines\",\"lines\":[[[0,0],[4,0]],[[4,0],[4,4]],[[4,4],[0,4]],[[0,4],[0,0]],"      \
    "[[0,2],[2,2]],[[3,3],[3.5,3.5]]]"

/* ---- shapes: rings of points --------------------------------------------------------------- */

typedef struct shape {
    size_t nr;   /* rings */
    size_t *off; /* nr + 1 entries used: ring r is points off[r] .. off[r+1]-1 */
    size_t np, cap;
    double *pt; /* 2 per point */
} shape;

static void shape_free(shape *s)
{
    free(s->off);
    free(s->pt);
    *s = (shape){0};
}

static void shape_ring(shape *s)
{
    s->off = realloc(s->off, (s->nr + 2) * sizeof *s->off);
    s->off[s->nr++] = s->np;
    s->off[s->nr] = s->np;
}

static void shape_point(shape *s, double x, double y)
{
    if (s->np == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 16;
        s->pt = realloc(s->pt, 2 * s->cap * sizeof *s->pt);
    }
    s->pt[2 * s->np] = x;
    s->pt[2 * s->np + 1] = y;
    s->np++;
    s->off[s->nr] = s->np;
}

static size_t shape_len(const shape *s, size_t r)
{
    return s->off[r + 1] - s->off[r];
}

static const double *shape_pt(const shape *s, size_t r, size_t i)
{
    return s->pt + 2 * (s->off[r] + i);
}

/* Twice the signed area of ring r; with mx, my the first moments (times 6). */
static double ring_area2(const shape *s, size_t r, double *mx, double *my)
{
    size_t n = shape_len(s, r);
    double a = 0, sx = 0, sy = 0;
    const double *o = shape_pt(s, r, 0);
    for (size_t i = 0; i < n; i++) {
        const double *p = shape_pt(s, r, i), *q = shape_pt(s, r, (i + 1) % n);
        double px = p[0] - o[0], py = p[1] - o[1], qx = q[0] - o[0], qy = q[1] - o[1];
        double c = px * qy - qx * py;
        a += c;
        sx += (px + qx) * c;
        sy += (py + qy) * c;
    }
    if (mx) *mx = sx + 3 * a * o[0];
    if (my) *my = sy + 3 * a * o[1];
    return a;
}

static double shape_area(const shape *s)
{
    double a = 0;
    for (size_t r = 0; r < s->nr; r++) a += ring_area2(s, r, NULL, NULL);
    return a / 2;
}

static void shape_centroid(const shape *s, double *x, double *y)
{
    double a = 0, sx = 0, sy = 0;
    for (size_t r = 0; r < s->nr; r++) {
        double mx, my;
        a += ring_area2(s, r, &mx, &my);
        sx += mx;
        sy += my;
    }
    *x = sx / (3 * a);
    *y = sy / (3 * a);
}

/* Even-odd point in shape: holes and edges walked twice fall out of the parity. */
static int shape_contains(const shape *s, double x, double y)
{
    int in = 0;
    for (size_t r = 0; r < s->nr; r++) {
        size_t n = shape_len(s, r);
        for (size_t i = 0; i < n; i++) {
            const double *p = shape_pt(s, r, i), *q = shape_pt(s, r, (i + 1) % n);
            if ((p[1] > y) != (q[1] > y) && x < p[0] + (y - p[1]) * (q[0] - p[0]) / (q[1] - p[1]))
                in = !in;
        }
    }
    return in;
}

/* ---- results ------------------------------------------------------------------------------- */

typedef struct res {
    char *text; /* the result JSON */
    size_t len;
    json_t *root;
    size_t nv, nf;
    double cx, cy, extent; /* centre and larger side of V's bounding box */
    shape *face;           /* nf: the cycles of V (math coordinates), outer first */
    size_t *nholes;        /* nf */
} res;

static void res_free(res *r)
{
    for (size_t f = 0; r->face && f < r->nf; f++) shape_free(&r->face[f]);
    free(r->face);
    free(r->nholes);
    free(r->text);
    json_decref(r->root);
    *r = (res){0};
}

static void add_cycle(shape *s, const json_t *V, const json_t *cyc)
{
    shape_ring(s);
    for (size_t i = 0; i < json_array_size(cyc); i++) {
        const json_t *p = json_array_get(V, (size_t)json_integer_value(json_array_get(cyc, i)));
        shape_point(s, json_number_value(json_array_get(p, 0)),
                    json_number_value(json_array_get(p, 1)));
    }
}

/* Runs body; nf is stats.F, or nf_hint when the result has no stats. */
static int res_run_(const char *body, long nf_hint, res *r, const char *func, int line)
{
    api_error err;
    json_error_t je;
    const json_t *V, *FV, *holes, *F;
    *r = (res){0};
    if (api_run_json(body, strlen(body), 1, &r->text, &r->len, &err) != API_OK) {
        test_fail(__FILE__, func, line, "api_run_json: %s", err.msg);
        return 0;
    }
    r->root = json_loadb(r->text, r->len, 0, &je);
    V = json_object_get(r->root, "V");
    FV = json_object_get(r->root, "FV");
    holes = json_object_get(r->root, "holes");
    F = json_object_get(json_object_get(r->root, "stats"), "F");
    if (!V || !FV) {
        test_fail(__FILE__, func, line, "result without V or FV");
        return 0;
    }
    r->nv = json_array_size(V);
    r->nf = F ? (size_t)json_integer_value(F) : (size_t)nf_hint;
    r->face = calloc(r->nf + 1, sizeof *r->face);
    r->nholes = calloc(r->nf + 1, sizeof *r->nholes);
    for (size_t f = 0; f < r->nf; f++) {
        char k[24];
        const json_t *hs;
        snprintf(k, sizeof k, "%zu", f);
        hs = json_object_get(holes, k);
        add_cycle(&r->face[f], V, json_array_get(FV, f));
        for (size_t h = 0; h < json_array_size(hs); h++)
            add_cycle(&r->face[f], V, json_array_get(hs, h));
        r->nholes[f] = json_array_size(hs);
    }
    if (r->nv) {
        double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
        for (size_t i = 0; i < r->nv; i++) {
            double x = json_number_value(json_array_get(json_array_get(V, i), 0));
            double y = json_number_value(json_array_get(json_array_get(V, i), 1));
            x0 = fmin(x0, x), x1 = fmax(x1, x), y0 = fmin(y0, y), y1 = fmax(y1, y);
        }
        r->cx = (x0 + x1) / 2;
        r->cy = (y0 + y1) / 2;
        r->extent = fmax(x1 - x0, y1 - y0);
    }
    return 1;
}
#define res_run(body, hint, r) res_run_(body, hint, r, __func__, __LINE__)

static double vx(const res *r, size_t v)
{
    return json_number_value(json_array_get(json_array_get(json_object_get(r->root, "V"), v), 0));
}

static double vy(const res *r, size_t v)
{
    return json_number_value(json_array_get(json_array_get(json_object_get(r->root, "V"), v), 1));
}

/* ---- pictures read back -------------------------------------------------------------------- */

typedef struct pic {
    double vb[4]; /* viewBox */
    double width, height;
    int titled;       /* a <title> is the first element */
    size_t npaths;    /* filled <path> elements */
    shape *face;      /* by the N of id="face-N" (SVG coordinates), up to nf */
    size_t *moves;    /* M commands of each face path */
    char (*fill)[16]; /* fill of each face path */
    int *seen;        /* face path N found */
    int evenodd;      /* every face path has fill-rule="evenodd" */
    int has_edges;    /* a <path id="edges"> */
    shape edges;      /* its subpaths */
    int has_result;   /* a <path id="result"> (a Boolean's result region) */
    shape result;     /* its subpaths */
    size_t nvt, nft;  /* texts in vertex-numbers and face-numbers */
    double *vt, *ft;  /* 2 per text, indexed by its number, in SVG coordinates */
    int text_bad;     /* a text out of range or not a number */
    int path_bad;     /* a path's data did not parse */
    size_t nf, nv;
} pic;

static void pic_free(pic *p)
{
    for (size_t f = 0; p->face && f < p->nf; f++) shape_free(&p->face[f]);
    free(p->face);
    free(p->moves);
    free(p->fill);
    free(p->seen);
    shape_free(&p->edges);
    shape_free(&p->result);
    free(p->vt);
    free(p->ft);
    *p = (pic){0};
}

/* Reads path data of M, L, Z commands into s; returns the M count, or -1 (also when a subpath
 * of a face is not closed by Z, closed set). */
static long read_path(const char *d, shape *s, int closed)
{
    long moves = 0, closes = 0;
    char cmd = 0;
    while (*d) {
        char *end;
        double x, y;
        if (*d == ' ' || *d == ',' || *d == '\n') {
            d++;
            continue;
        }
        if (*d == 'M' || *d == 'L' || *d == 'Z') {
            cmd = *d++;
            if (cmd == 'M') {
                if (closed && closes != moves) return -1;
                moves++;
                shape_ring(s);
            }
            closes += cmd == 'Z';
            continue;
        }
        if (cmd != 'M' && cmd != 'L') return -1;
        x = strtod(d, &end);
        if (end == d) return -1;
        d = end;
        while (*d == ' ' || *d == ',') d++;
        y = strtod(d, &end);
        if (end == d) return -1;
        d = end;
        shape_point(s, x, y);
    }
    return closed && closes != moves ? -1 : moves;
}

static char *attr(xmlNodePtr n, const char *name)
{
    return (char *)xmlGetProp(n, (const xmlChar *)name);
}

static void walk(xmlNodePtr n, pic *p, const char *group, double scale)
{
    for (; n; n = n->next) {
        if (n->type != XML_ELEMENT_NODE) continue;
        const char *name = (const char *)n->name;
        if (!strcmp(name, "g")) {
            char *id = attr(n, "id"), *tr = attr(n, "transform");
            double sc = scale;
            if (tr && !strncmp(tr, "scale(", 6)) sc = scale * strtod(tr + 6, NULL);
            walk(n->children, p, id ? id : group, sc);
            xmlFree(id);
            xmlFree(tr);
        } else if (!strcmp(name, "path")) {
            char *fill = attr(n, "fill"), *id = attr(n, "id"), *d = attr(n, "d");
            char *rule = attr(n, "fill-rule");
            if (id && !strcmp(id, "result")) {
                p->has_result = 1;
                if (!d || read_path(d, &p->result, 1) < 0) p->path_bad = 1;
                if (!rule || strcmp(rule, "evenodd") != 0) p->evenodd = 0;
            } else if (fill && strcmp(fill, "none") != 0) {
                long moves;
                size_t f = SIZE_MAX;
                p->npaths++;
                if (id && !strncmp(id, "face-", 5)) f = strtoul(id + 5, NULL, 10);
                if (f < p->nf && !p->seen[f]) {
                    p->seen[f] = 1;
                    moves = d ? read_path(d, &p->face[f], 1) : -1;
                    if (moves < 0) p->path_bad = 1;
                    p->moves[f] = moves < 0 ? 0 : (size_t)moves;
                    snprintf(p->fill[f], sizeof p->fill[f], "%s", fill);
                } else {
                    p->path_bad = 1;
                }
                if (!rule || strcmp(rule, "evenodd") != 0) p->evenodd = 0;
            } else if (id && !strcmp(id, "edges")) {
                p->has_edges = 1;
                if (!d || read_path(d, &p->edges, 0) < 0) p->path_bad = 1;
            }
            xmlFree(fill);
            xmlFree(id);
            xmlFree(d);
            xmlFree(rule);
        } else if (!strcmp(name, "text")) {
            char *x = attr(n, "x"), *y = attr(n, "y");
            char *c = (char *)xmlNodeGetContent(n), *end = NULL;
            unsigned long k = c ? strtoul(c, &end, 10) : 0;
            int vert = group && !strcmp(group, "vertex-numbers");
            int face = group && !strcmp(group, "face-numbers");
            size_t lim = vert ? p->nv : p->nf;
            double *dst = vert ? p->vt : p->ft;
            if ((!vert && !face) || !x || !y || !c || end == c || *end || k >= lim) {
                p->text_bad = 1;
            } else {
                dst[2 * k] = strtod(x, NULL) * scale;
                dst[2 * k + 1] = strtod(y, NULL) * scale;
                if (vert)
                    p->nvt++;
                else
                    p->nft++;
            }
            xmlFree(x);
            xmlFree(y);
            xmlFree(c);
        } else if (!strcmp(name, "title")) {
            p->titled = n == xmlFirstElementChild(n->parent);
        }
    }
}

/* Parses svg into p; 0 when libxml2 refuses it. */
static int pic_read(const char *svg, size_t len, size_t nf, size_t nv, pic *p)
{
    xmlDocPtr doc = xmlReadMemory(svg, (int)len, "render.svg", NULL,
                                  XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    xmlNodePtr root;
    char *vb, *w, *h;
    *p = (pic){0};
    if (!doc) return 0;
    p->nf = nf;
    p->nv = nv;
    p->face = calloc(nf + 1, sizeof *p->face);
    p->moves = calloc(nf + 1, sizeof *p->moves);
    p->fill = calloc(nf + 1, sizeof *p->fill);
    p->seen = calloc(nf + 1, sizeof *p->seen);
    p->vt = calloc(2 * nv + 1, sizeof *p->vt);
    p->ft = calloc(2 * nf + 1, sizeof *p->ft);
    p->evenodd = 1;
    root = xmlDocGetRootElement(doc);
    vb = attr(root, "viewBox");
    w = attr(root, "width");
    h = attr(root, "height");
    if (vb) sscanf(vb, "%lf %lf %lf %lf", &p->vb[0], &p->vb[1], &p->vb[2], &p->vb[3]);
    p->width = w ? strtod(w, NULL) : 0;
    p->height = h ? strtod(h, NULL) : 0;
    if (!strcmp((const char *)root->name, "svg")) walk(root->children, p, NULL, 1);
    xmlFree(vb);
    xmlFree(w);
    xmlFree(h);
    xmlFreeDoc(doc);
    return 1;
}

static int in_box(const pic *p, double x, double y)
{
    return x > p->vb[0] && x < p->vb[0] + p->vb[2] && y > p->vb[1] && y < p->vb[1] + p->vb[3];
}

static int valid_colour(const char *c)
{
    if (strlen(c) != 7 || c[0] != '#') return 0;
    for (int i = 1; i < 7; i++)
        if (!strchr("0123456789abcdef", c[i])) return 0;
    return 1;
}

/* Renders r with o and checks the picture; fills *out (caller frees with pic_free) when not
 * NULL. */
static void check_svg_(const char *name, const res *r, const render_opts *o, pic *out,
                       const char *func, int line)
{
    char *svg = NULL;
    size_t len = 0, outside = 0, wrong_pts = 0, labels_out = 0;
    api_error err;
    pic p;
#define FAILF(...) test_fail(__FILE__, func, line, __VA_ARGS__)
    if (render_svg(r->text, r->len, o, &svg, &len, &err) != API_OK) {
        FAILF("%s: render_svg: %d %s", name, err.status, err.msg);
        return;
    }
    if (!svg || len != strlen(svg) || svg[len - 1] != '\n') FAILF("%s: bad output buffer", name);
    if (!pic_read(svg, len, r->nf, r->nv, &p)) {
        FAILF("%s: libxml2 cannot read the picture", name);
        free(svg);
        return;
    }
    free(svg);
    if (!p.titled) FAILF("%s: no <title> first", name);
    if (p.npaths != r->nf) FAILF("%s: %zu filled paths, %zu faces", name, p.npaths, r->nf);
    if (p.path_bad) FAILF("%s: a path is unreadable or not a face-N", name);
    if (!p.evenodd) FAILF("%s: a face path without fill-rule evenodd", name);
    if (!(p.vb[2] > 0 && p.vb[3] > 0)) FAILF("%s: viewBox %g %g", name, p.vb[2], p.vb[3]);
    if (p.width != o->width || fabs(p.height - o->width * p.vb[3] / p.vb[2]) > 1)
        FAILF("%s: size %g x %g for viewBox %g x %g", name, p.width, p.height, p.vb[2], p.vb[3]);
    for (size_t f = 0; f < r->nf; f++) {
        const shape *s = &p.face[f], *t = &r->face[f];
        if (!p.seen[f]) {
            FAILF("%s: no path for face %zu", name, f);
            continue;
        }
        if (p.moves[f] != 1 + r->nholes[f] || s->nr != t->nr)
            FAILF("%s: face %zu has %zu subpaths, %zu holes", name, f, p.moves[f], r->nholes[f]);
        if (!valid_colour(p.fill[f])) FAILF("%s: face %zu fill %s", name, f, p.fill[f]);
        if (f > 0 && !strcmp(p.fill[f], p.fill[f - 1]))
            FAILF("%s: faces %zu and %zu share a colour", name, f - 1, f);
        for (size_t i = 0; i < s->np; i++) outside += !in_box(&p, s->pt[2 * i], s->pt[2 * i + 1]);
        /* the cycles' own points, y negated, translated by one vector per face */
        if (s->nr == t->nr && s->np == t->np && s->np > 0) {
            double dx = s->pt[0] - t->pt[0], dy = s->pt[1] + t->pt[1];
            for (size_t i = 0; i < s->np; i++) {
                double ex = t->pt[2 * i] + dx, ey = -t->pt[2 * i + 1] + dy;
                double tol = 1e-9 * (r->extent + fabs(dx) + fabs(dy));
                if (o->explode == 1
                        ? (s->pt[2 * i] != t->pt[2 * i] || s->pt[2 * i + 1] != -t->pt[2 * i + 1])
                        : (fabs(s->pt[2 * i] - ex) > tol || fabs(s->pt[2 * i + 1] - ey) > tol))
                    wrong_pts++;
            }
        } else {
            FAILF("%s: face %zu has %zu points, the result %zu", name, f, s->np, t->np);
        }
    }
    if (wrong_pts) FAILF("%s: %zu face points are not the cycles' (moved as one)", name, wrong_pts);
    for (size_t i = 0; i < p.edges.np; i++)
        outside += !in_box(&p, p.edges.pt[2 * i], p.edges.pt[2 * i + 1]);
    if (o->edges != p.has_edges && r->nf > 0)
        FAILF("%s: edges %s", name, p.has_edges ? "drawn though off" : "missing");
    if (o->edges && o->explode == 1 && json_object_get(r->root, "EV")) {
        size_t ne = json_array_size(json_object_get(r->root, "EV"));
        if (p.edges.nr != ne) FAILF("%s: %zu edge subpaths, %zu edges", name, p.edges.nr, ne);
    }
    if (p.text_bad) FAILF("%s: a text outside the number groups or not an index", name);
    if (o->numbers) {
        if (p.nvt != r->nv || p.nft != r->nf)
            FAILF("%s: %zu vertex numbers, %zu face numbers for %zu, %zu", name, p.nvt, p.nft,
                  r->nv, r->nf);
        for (size_t v = 0; v < r->nv; v++) {
            outside += !in_box(&p, p.vt[2 * v], p.vt[2 * v + 1]);
            if (p.vt[2 * v] != vx(r, v) || p.vt[2 * v + 1] != -vy(r, v))
                FAILF("%s: vertex %zu numbered at %g %g", name, v, p.vt[2 * v], p.vt[2 * v + 1]);
        }
        for (size_t f = 0; f < r->nf; f++) {
            double x = p.ft[2 * f], y = p.ft[2 * f + 1];
            outside += !in_box(&p, x, y);
            /* inside the face as drawn, and (in place) inside the result's own cycles */
            if (!shape_contains(&p.face[f], x, y) ||
                (o->explode == 1 && !shape_contains(&r->face[f], x, -y))) {
                labels_out++;
                if (labels_out < 4)
                    FAILF("%s: the number of face %zu at %.17g %.17g is not inside it", name, f, x,
                          -y);
            }
        }
    } else if (p.nvt || p.nft) {
        FAILF("%s: numbers drawn though off", name);
    }
    if (labels_out) FAILF("%s: %zu face numbers outside their faces", name, labels_out);
    if (outside) FAILF("%s: %zu drawn coordinates outside the viewBox", name, outside);
    if (out)
        *out = p;
    else
        pic_free(&p);
#undef FAILF
}
#define check_svg(name, r, o, out) check_svg_(name, r, o, out, __func__, __LINE__)

/* Renders r exploded by k and checks each face moved as one, its centroid k times as far from
 * the centre of V's bounding box (in SVG coordinates: y negated). */
static void check_explode(const char *name, const res *r, double k)
{
    render_opts o1 = RENDER_OPTS_INIT, ok = RENDER_OPTS_INIT;
    pic a, b;
    size_t bad = 0;
    double cx = r->cx, cy = -r->cy;
    ok.explode = k;
    ok.numbers = 1;
    check_svg(name, r, &o1, &a);
    check_svg(name, r, &ok, &b);
    if (test_failed_now()) goto done;
    for (size_t f = 0; f < r->nf; f++) {
        double x1, y1, xk, yk, d1, dk, tol = 1e-9 * r->extent * k;
        shape_centroid(&a.face[f], &x1, &y1);
        shape_centroid(&b.face[f], &xk, &yk);
        d1 = hypot(x1 - cx, y1 - cy);
        dk = hypot(xk - cx, yk - cy);
        if (fabs((xk - cx) - k * (x1 - cx)) > tol || fabs((yk - cy) - k * (y1 - cy)) > tol ||
            fabs(dk - k * d1) > tol || (d1 > tol && !(dk > d1))) {
            if (bad++ < 3)
                CHECK(0, "%s: face %zu centroid %g from the centre, exploded %g (k %g)", name, f,
                      d1, dk, k);
        }
    }
    CHECK(bad == 0, "%s: %zu faces not exploded by %g", name, bad, k);
done:
    pic_free(&a);
    pic_free(&b);
}

/* ---- GeoJSON read back ------------------------------------------------------------------- */

static void check_geojson(const char *name, const res *r)
{
    char *text = NULL;
    size_t len = 0, bad_pos = 0;
    api_error err;
    json_error_t je;
    json_t *g, *feats;
    double total = 0;
    int rc = render_geojson(r->text, r->len, NULL, &text, &len, &err);
    REQUIRE(rc == API_OK, "%s: render_geojson: %d %s", name, rc, err.msg);
    g = json_loadb(text, len, 0, &je);
    free(text);
    REQUIRE(g, "%s: GeoJSON does not parse: %s", name, je.text);
    CHECK(!strcmp(json_string_value(json_object_get(g, "type")), "FeatureCollection"),
          "%s: not a FeatureCollection", name);
    feats = json_object_get(g, "features");
    /* one Polygon per face, then one LineString per edge on no ring (kept dangling) */
    size_t nfeat = json_array_size(feats), ndang = 0, nring_edges = 0, cap = 64;
    const json_t *EV = json_object_get(r->root, "EV"), *V = json_object_get(r->root, "V");
    double *ring_edges = malloc(cap * 4 * sizeof *ring_edges); /* x0 y0 x1 y1 of every ring edge */
    CHECK(nfeat >= r->nf, "%s: %zu features, %zu faces", name, nfeat, r->nf);
    /* Each face: its rings are simple cycles (no vertex twice), closed, the shell
     * counter-clockwise and the holes clockwise, made of the directed edges of the face's own
     * cycles, enclosing the face's area; every edge of its cycles that no ring has is walked
     * both ways (a tree edge: dangling). */
    for (size_t f = 0; f < nfeat && f < r->nf; f++) {
        const json_t *ft = json_array_get(feats, f), *geom = json_object_get(ft, "geometry");
        const json_t *props = json_object_get(ft, "properties");
        const json_t *rings = json_object_get(geom, "coordinates");
        const shape *s = &r->face[f];
        size_t nd = 0, used = 0;
        double area, a2 = 0;
        CHECK(!strcmp(json_string_value(json_object_get(ft, "type")), "Feature") &&
                  !strcmp(json_string_value(json_object_get(geom, "type")), "Polygon"),
              "%s: feature %zu is not a Feature with a Polygon", name, f);
        CHECK(json_integer_value(json_object_get(props, "face")) == (json_int_t)f,
              "%s: feature %zu names face %lld", name, f,
              (long long)json_integer_value(json_object_get(props, "face")));
        for (size_t rr = 0; rr < s->nr; rr++) nd += shape_len(s, rr);
        uint8_t *hit = calloc(nd + 1, 1);
        for (size_t ri = 0; ri < json_array_size(rings); ri++) {
            const json_t *ring = json_array_get(rings, ri);
            size_t m = json_array_size(ring), n = m ? m - 1 : 0;
            shape one = {0};
            double a;
            CHECK(m >= 4 && json_equal(json_array_get(ring, 0), json_array_get(ring, n)),
                  "%s: face %zu ring %zu: %zu positions, or not closed", name, f, ri, m);
            if (m < 4) continue;
            shape_ring(&one);
            for (size_t i = 0; i < n; i++) {
                const json_t *pos = json_array_get(ring, i), *nx = json_array_get(ring, i + 1);
                double x = json_number_value(json_array_get(pos, 0));
                double y = json_number_value(json_array_get(pos, 1));
                double x1 = json_number_value(json_array_get(nx, 0));
                double y1 = json_number_value(json_array_get(nx, 1));
                size_t k = 0, found = SIZE_MAX;
                if (json_array_size(pos) != 2) bad_pos++;
                for (size_t j = 0; j < i; j++)
                    if (json_equal(json_array_get(ring, j), pos)) bad_pos++; /* not simple */
                shape_point(&one, x, y);
                for (size_t rr = 0; rr < s->nr && found == SIZE_MAX; rr++) {
                    size_t ln = shape_len(s, rr);
                    for (size_t t = 0; t < ln; t++, k++) {
                        const double *p = shape_pt(s, rr, t), *q = shape_pt(s, rr, (t + 1) % ln);
                        if (!hit[k] && p[0] == x && p[1] == y && q[0] == x1 && q[1] == y1) {
                            found = k;
                            break;
                        }
                    }
                }
                if (found == SIZE_MAX) {
                    bad_pos++;
                } else {
                    hit[found] = 1;
                    used++;
                }
                if (nring_edges == cap) {
                    cap *= 2;
                    ring_edges = realloc(ring_edges, cap * 4 * sizeof *ring_edges);
                }
                ring_edges[4 * nring_edges] = x, ring_edges[4 * nring_edges + 1] = y;
                ring_edges[4 * nring_edges + 2] = x1, ring_edges[4 * nring_edges + 3] = y1;
                nring_edges++;
            }
            a = ring_area2(&one, 0, NULL, NULL);
            a2 += a;
            if (ri == 0)
                CHECK(a > 0, "%s: face %zu shell not counter-clockwise (%g)", name, f, a);
            else
                CHECK(a < 0, "%s: face %zu hole %zu not clockwise (%g)", name, f, ri, a);
            shape_free(&one);
        }
        /* the cycles' edges no ring has: each has its reverse in the cycles too */
        for (size_t rr = 0, k = 0; rr < s->nr; rr++) {
            size_t ln = shape_len(s, rr);
            for (size_t t = 0; t < ln; t++, k++) {
                const double *p = shape_pt(s, rr, t), *q = shape_pt(s, rr, (t + 1) % ln);
                int back = 0;
                if (hit[k]) continue;
                for (size_t r2 = 0; r2 < s->nr && !back; r2++) {
                    size_t l2 = shape_len(s, r2);
                    for (size_t u = 0; u < l2 && !back; u++) {
                        const double *p2 = shape_pt(s, r2, u), *q2 = shape_pt(s, r2, (u + 1) % l2);
                        back = p2[0] == q[0] && p2[1] == q[1] && q2[0] == p[0] && q2[1] == p[1];
                    }
                }
                CHECK(back || ln < 2,
                      "%s: face %zu: edge (%g %g)-(%g %g) of its cycles is on no ring", name, f,
                      p[0], p[1], q[0], q[1]);
            }
        }
        free(hit);
        area = shape_area(s); /* from V and the cycles of the result */
        CHECK(fabs(json_number_value(json_object_get(props, "area")) - area) <=
                  1e-9 * (fabs(area) + r->extent * r->extent * 1e-6),
              "%s: face %zu area %.17g, computed %.17g", name, f,
              json_number_value(json_object_get(props, "area")), area);
        CHECK(fabs(a2 / 2 - area) <= 1e-9 * (fabs(area) + r->extent * r->extent * 1e-6),
              "%s: face %zu rings enclose %.17g, not %.17g", name, f, a2 / 2, area);
        CHECK(area > 0, "%s: face %zu has area %g", name, f, area);
        total += area;
    }
    /* the dangling edges: LineStrings of EV's edges, exactly those on no ring */
    for (size_t i = r->nf; i < nfeat; i++) {
        const json_t *ft = json_array_get(feats, i), *geom = json_object_get(ft, "geometry");
        const json_t *props = json_object_get(ft, "properties"), *c, *ev;
        json_int_t e = json_integer_value(json_object_get(props, "edge"));
        ndang++;
        c = json_object_get(geom, "coordinates");
        ev = json_array_get(EV, (size_t)e);
        CHECK(!strcmp(json_string_value(json_object_get(geom, "type")), "LineString") &&
                  json_is_true(json_object_get(props, "dangling")) && ev &&
                  json_array_size(c) == 2 &&
                  json_equal(json_array_get(c, 0),
                             json_array_get(V, json_integer_value(json_array_get(ev, 0)))) &&
                  json_equal(json_array_get(c, 1),
                             json_array_get(V, json_integer_value(json_array_get(ev, 1)))),
              "%s: feature %zu is not a dangling edge of EV", name, i);
    }
    if (EV) {
        size_t on = 0;
        for (size_t e = 0; e < json_array_size(EV); e++) {
            const json_t *va =
                json_array_get(V, json_integer_value(json_array_get(json_array_get(EV, e), 0)));
            const json_t *vb =
                json_array_get(V, json_integer_value(json_array_get(json_array_get(EV, e), 1)));
            double ax = json_number_value(json_array_get(va, 0));
            double ay = json_number_value(json_array_get(va, 1));
            double bx = json_number_value(json_array_get(vb, 0));
            double by = json_number_value(json_array_get(vb, 1));
            int found = 0;
            for (size_t k = 0; k < nring_edges && !found; k++) {
                const double *q = ring_edges + 4 * k;
                found = (q[0] == ax && q[1] == ay && q[2] == bx && q[3] == by) ||
                        (q[0] == bx && q[1] == by && q[2] == ax && q[3] == ay);
            }
            on += found;
        }
        CHECK(ndang == json_array_size(EV) - on, "%s: %zu dangling features, %zu edges on no ring",
              name, ndang, json_array_size(EV) - on);
    }
    free(ring_edges);
    CHECK(bad_pos == 0, "%s: %zu positions are not the vertices of the cycles", name, bad_pos);
    /* the faces' areas add up to the area enclosed by the exterior cycles */
    {
        const json_t *ext = json_object_get(r->root, "exterior");
        if (json_is_array(ext) && json_object_get(r->root, "stats")) {
            shape e = {0};
            double ea;
            for (size_t i = 0; i < json_array_size(ext); i++)
                add_cycle(&e, json_object_get(r->root, "V"), json_array_get(ext, i));
            ea = -shape_area(&e);
            CHECK(fabs(ea - total) <= 1e-9 * (ea + 1e-300), "%s: faces %.17g, exterior %.17g", name,
                  total, ea);
            shape_free(&e);
        }
    }
    json_decref(g);
}

/* One request: the picture plain, with numbers, without edges, exploded; the GeoJSON. */
static void check_request(const char *name, const char *body, long nf_hint, double k)
{
    res r;
    render_opts o = RENDER_OPTS_INIT;
    if (!res_run(body, nf_hint, &r)) return;
    check_svg(name, &r, &o, NULL);
    o.numbers = 1;
    check_svg(name, &r, &o, NULL);
    o.edges = 0;
    o.width = 333;
    check_svg(name, &r, &o, NULL);
    check_explode(name, &r, k);
    check_geojson(name, &r);
    res_free(&r);
}

/* ---- the cases ----------------------------------------------------------------------------- */

TEST(render_orthogonal)
{
    res r;
    check_request("orthogonal", ORTHOGONAL "}", -1, 1.5);
    REQUIRE(res_run(ORTHOGONAL "}", -1, &r), "run");
    CHECK(r.nf == 4, "orthogonal: %zu faces", r.nf);
    /* all four colours distinct */
    {
        render_opts o = RENDER_OPTS_INIT;
        pic p;
        check_svg("orthogonal colours", &r, &o, &p);
        for (size_t i = 0; i < r.nf && p.fill; i++)
            for (size_t j = 0; j < i; j++)
                CHECK(strcmp(p.fill[i], p.fill[j]) != 0, "faces %zu, %zu: %s", i, j, p.fill[i]);
        pic_free(&p);
    }
    res_free(&r);
}

/* A U: its centroid lies in the notch, outside the face; the number must not go there. */
TEST(render_non_convex_face)
{
    res r;
    const char *u = "{\"kind\":\"lines\",\"lines\":[[[0,0],[6,0]],[[6,0],[6,6]],[[6,6],[4,6]],"
                    "[[4,6],[4,2]],[[4,2],[2,2]],[[2,2],[2,6]],[[2,6],[0,6]],[[0,6],[0,0]]]}";
    double x, y;
    check_request("U", u, -1, 1.5);
    REQUIRE(res_run(u, -1, &r), "run");
    REQUIRE(r.nf == 1, "U: %zu faces", r.nf);
    shape_centroid(&r.face[0], &x, &y);
    CHECK(!shape_contains(&r.face[0], x, y), "the U's centroid %g %g is inside it", x, y);
    res_free(&r);
}

TEST(render_concentric_squares_holes)
{
    res r;
    check_request("concentric", CONCENTRIC "}", -1, 2);
    REQUIRE(res_run(CONCENTRIC "}", -1, &r), "run");
    CHECK(r.nf == 3 && r.nholes[0] == 1 && r.nholes[1] == 1 && r.nholes[2] == 0,
          "concentric: %zu faces", r.nf);
    res_free(&r);
    /* with a square beside them the centroids are off the centre, and the holes move too */
    check_request("concentric and a square",
                  "{\"kind\":\"lines\",\"lines\":[[[0,0],[8,0]],[[8,0],[8,8]],[[8,8],[0,8]],"
                  "[[0,8],[0,0]],[[1,1],[7,1]],[[7,1],[7,7]],[[7,7],[1,7]],[[1,7],[1,1]],"
                  "[[2,2],[6,2]],[[6,2],[6,6]],[[6,6],[2,6]],[[2,6],[2,2]],[[10,0],[12,0]],"
                  "[[12,0],[12,2]],[[12,2],[10,2]],[[10,2],[10,0]]]}",
                  -1, 3);
}

static char *random_request(size_t n, double scaling, uint64_t seed, const char *options)
{
    double *s = test_random_lines(n, scaling, seed);
    size_t cap = n * 120 + 256, w = 0;
    char *b = malloc(cap);
    if (!s || !b) {
        free(s);
        free(b);
        return NULL;
    }
    w += (size_t)snprintf(b + w, cap - w, "{\"kind\":\"lines\",\"lines\":[");
    for (size_t i = 0; i < n; i++)
        w += (size_t)snprintf(b + w, cap - w, "%s[[%.17g,%.17g],[%.17g,%.17g]]", i ? "," : "",
                              s[4 * i], s[4 * i + 1], s[4 * i + 2], s[4 * i + 3]);
    snprintf(b + w, cap - w, "]%s%s}", options ? ",\"options\":" : "", options ? options : "");
    free(s);
    return b;
}

TEST(render_random_lines)
{
    static const struct {
        size_t n;
        double scaling;
        uint64_t seed;
    } cases[] = {{60, 0.3, 1}, {200, 0.3, 2}, {300, 0.2, 3}, {150, 0.6, 4}};
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char name[64], *body = random_request(cases[i].n, cases[i].scaling, cases[i].seed, NULL);
        res r;
        REQUIRE(body, "malloc");
        snprintf(name, sizeof name, "random %zu %g seed %llu", cases[i].n, cases[i].scaling,
                 (unsigned long long)cases[i].seed);
        check_request(name, body, -1, 1.25);
        if (res_run(body, -1, &r)) {
            CHECK(r.nf > 2, "%s: only %zu faces", name, r.nf);
            res_free(&r);
        }
        free(body);
    }
}

TEST(render_keep_dangling_and_exterior_last)
{
    res r;
    /* the seeds' convention: exterior cycles as the last rows of FV, found by stats.F */
    check_request("orthogonal exterior_last keep_dangling",
                  ORTHOGONAL ",\"options\":{\"exterior_last\":true,\"keep_dangling\":true}}", -1,
                  1.5);
    REQUIRE(
        res_run(ORTHOGONAL ",\"options\":{\"exterior_last\":true,\"keep_dangling\":true}}", -1, &r),
        "run");
    CHECK(r.nf == 4 && json_array_size(json_object_get(r.root, "FV")) == 5,
          "exterior_last: %zu faces", r.nf);
    res_free(&r);
    /* ... by the rows equal to "exterior" when there are no stats */
    check_request("exterior_last by exterior rows",
                  ORTHOGONAL ",\"options\":{\"exterior_last\":true,"
                             "\"fields\":[\"V\",\"EV\",\"FV\",\"holes\",\"exterior\"]}}",
                  4, 1.5);
    /* ... by their area (<= 0) when there is neither */
    check_request("exterior_last by area",
                  CONCENTRIC ",\"options\":{\"exterior_last\":true,"
                             "\"fields\":[\"V\",\"FV\",\"holes\"]}}",
                  3, 1.5);
    /* dangling edges kept: a spike in the outer cycle, a 2-vertex hole */
    check_request("square with dangling edges", DANGLING ",\"options\":{\"keep_dangling\":true}}",
                  -1, 1.5);
    check_request("square with dangling edges, exterior_last",
                  DANGLING ",\"options\":{\"keep_dangling\":true,\"exterior_last\":true}}", -1,
                  1.5);
    check_request("random keep_dangling",
                  "{\"kind\":\"lines\",\"lines\":[[[0,0],[3,3]],[[0,3],[3,0]],[[0,1],[3,1]],"
                  "[[1,-1],[1,4]],[[2,2],[5,2]]],\"options\":{\"keep_dangling\":true}}",
                  -1, 1.5);
}

/* A face's membership (a list of inputs) against row f of the result's sparse rows. */
static int row_equal(const json_t *list, const json_t *mem, size_t f)
{
    const json_t *ip = json_object_get(mem, "indptr"), *ix = json_object_get(mem, "indices");
    size_t a = (size_t)json_integer_value(json_array_get(ip, f));
    size_t b = (size_t)json_integer_value(json_array_get(ip, f + 1));
    if (!json_is_array(list) || json_array_size(list) != b - a) return 0;
    for (size_t k = a; k < b; k++)
        if (json_integer_value(json_array_get(list, k - a)) !=
            json_integer_value(json_array_get(ix, k)))
            return 0;
    return 1;
}

/* A Boolean's result: the SVG draws its region on top (one subpath per ring, in the result
 * polygons' coordinates, y negated), the GeoJSON's first feature is the region as a MultiPolygon
 * with the result's area, and cells=all adds every face with "selected" and "membership" equal
 * to the result's own. */
TEST(render_boolean_result)
{
    static const char *const ops[] = {"union", "intersection", "difference", "xor"};
    for (size_t k = 0; k < 4; k++) {
        char body[600];
        res r;
        render_opts o = RENDER_OPTS_INIT;
        pic p = {0};
        char *text = NULL;
        size_t len = 0, nrings = 0, npos = 0;
        api_error err;
        const json_t *result, *rFV, *rholes, *val;
        const char *key;
        json_t *g = NULL;
        /* two squares with holes; the second's hole touches the first's at a vertex */
        snprintf(body, sizeof body,
                 "{\"kind\":\"polygons\",\"polygons\":["
                 "[[[0,0],[6,0],[6,6],[0,6]],[[1,1],[3,1],[3,3],[1,3]]],"
                 "[[[2,2],[9,2],[9,9],[2,9]],[[3,3],[5,3],[5,5],[3,5]]]],\"op\":\"%s\"}",
                 ops[k]);
        if (!res_run(body, -1, &r)) continue;
        result = json_object_get(r.root, "result");
        rFV = json_object_get(result, "FV");
        rholes = json_object_get(result, "holes");
        REQUIRE(json_is_array(rFV) && json_is_object(rholes), "%s: no result polygons", ops[k]);
        nrings = json_array_size(rFV);
        json_object_foreach((json_t *)rholes, key, val) nrings += json_array_size(val);
        check_svg(ops[k], &r, &o, &p);
        CHECK(p.has_result && p.result.nr == nrings, "%s: result path has %zu subpaths, %zu rings",
              ops[k], p.result.nr, nrings);
        /* the subpaths are the rings' vertices, y negated */
        for (size_t q = 0, ri = 0; q < json_array_size(rFV) && p.has_result; q++) {
            char kq[24];
            const json_t *hs;
            snprintf(kq, sizeof kq, "%zu", q);
            hs = json_object_get(rholes, kq);
            for (size_t h = 0; h <= json_array_size(hs) && ri < p.result.nr; h++, ri++) {
                const json_t *ring = h == 0 ? json_array_get(rFV, q) : json_array_get(hs, h - 1);
                CHECK(shape_len(&p.result, ri) == json_array_size(ring),
                      "%s: result subpath %zu has %zu points, ring %zu", ops[k], ri,
                      shape_len(&p.result, ri), json_array_size(ring));
                for (size_t i = 0; i < json_array_size(ring) && i < shape_len(&p.result, ri); i++) {
                    size_t v = (size_t)json_integer_value(json_array_get(ring, i));
                    if (shape_pt(&p.result, ri, i)[0] != vx(&r, v) ||
                        shape_pt(&p.result, ri, i)[1] != -vy(&r, v))
                        npos++;
                }
            }
        }
        CHECK(npos == 0, "%s: %zu result points are not the rings' vertices", ops[k], npos);
        pic_free(&p);
        /* exploded: no result layer */
        o.explode = 2;
        check_svg(ops[k], &r, &o, &p);
        CHECK(!p.has_result, "%s: exploded drawing has a result layer", ops[k]);
        pic_free(&p);

        /* GeoJSON: the region, then (cells=all) the faces */
        for (int cells = 0; cells < 2; cells++) {
            const json_t *feats, *f0, *coords;
            size_t want = 1 + (cells ? r.nf : 0);
            o = (render_opts)RENDER_OPTS_INIT;
            o.cells = cells;
            REQUIRE(render_geojson(r.text, r.len, &o, &text, &len, &err) == API_OK, "%s: %s",
                    ops[k], err.msg);
            g = json_loadb(text, len, 0, NULL);
            free(text);
            feats = json_object_get(g, "features");
            CHECK(json_array_size(feats) == want, "%s cells=%d: %zu features, want %zu", ops[k],
                  cells, json_array_size(feats), want);
            f0 = json_array_get(feats, 0);
            coords = json_object_get(json_object_get(f0, "geometry"), "coordinates");
            CHECK(
                !strcmp(json_string_value(json_object_get(json_object_get(f0, "geometry"), "type")),
                        "MultiPolygon") &&
                    json_is_true(json_object_get(json_object_get(f0, "properties"), "result")),
                "%s: first feature is not the result MultiPolygon", ops[k]);
            CHECK(json_array_size(coords) == json_array_size(rFV), "%s: %zu polygons, want %zu",
                  ops[k], json_array_size(coords), json_array_size(rFV));
            CHECK(json_number_value(json_object_get(json_object_get(f0, "properties"), "area")) ==
                      json_number_value(json_object_get(result, "area")),
                  "%s: result area differs", ops[k]);
            /* its rings enclose the result's area: shells counter-clockwise, holes clockwise */
            {
                double a = 0;
                int bad_orient = 0;
                for (size_t q = 0; q < json_array_size(coords); q++) {
                    const json_t *poly = json_array_get(coords, q);
                    for (size_t h = 0; h < json_array_size(poly); h++) {
                        const json_t *ring = json_array_get(poly, h);
                        double ra = 0;
                        for (size_t i = 0; i + 1 < json_array_size(ring); i++) {
                            const json_t *u = json_array_get(ring, i);
                            const json_t *w = json_array_get(ring, i + 1);
                            ra += json_number_value(json_array_get(u, 0)) *
                                      json_number_value(json_array_get(w, 1)) -
                                  json_number_value(json_array_get(w, 0)) *
                                      json_number_value(json_array_get(u, 1));
                        }
                        if ((h == 0) != (ra > 0)) bad_orient++;
                        a += ra / 2;
                    }
                }
                CHECK(bad_orient == 0 &&
                          fabs(a - json_number_value(json_object_get(result, "area"))) < 1e-9,
                      "%s: rings enclose %g (%d misoriented), result area %g", ops[k], a,
                      bad_orient, json_number_value(json_object_get(result, "area")));
            }
            if (cells) {
                const json_t *cellsv = json_object_get(result, "cells");
                const json_t *mem = json_object_get(r.root, "membership");
                size_t bad = 0;
                for (size_t f = 0; f < r.nf; f++) {
                    const json_t *pr = json_object_get(json_array_get(feats, f + 1), "properties");
                    int sel = 0;
                    for (size_t i = 0; i < json_array_size(cellsv); i++)
                        sel |= json_integer_value(json_array_get(cellsv, i)) == (json_int_t)f;
                    if (json_integer_value(json_object_get(pr, "face")) != (json_int_t)f ||
                        json_is_true(json_object_get(pr, "selected")) != sel ||
                        !row_equal(json_object_get(pr, "membership"), mem, f))
                        bad++;
                }
                CHECK(bad == 0, "%s: %zu faces with wrong face, selected or membership", ops[k],
                      bad);
            }
            json_decref(g);
        }
        res_free(&r);
    }
    /* cells=all needs the membership (a result edited to leave it out) */
    {
        res r;
        render_opts o = RENDER_OPTS_INIT;
        char *text = NULL, *cut;
        size_t len = 0;
        api_error err;
        o.cells = 1;
        if (res_run("{\"kind\":\"polygons\",\"polygons\":[[[[0,0],[1,0],[0,1]]]],\"op\":\"union\"}",
                    1, &r)) {
            json_object_del(r.root, "membership");
            cut = json_dumps(r.root, 0);
            CHECK(render_geojson(cut, strlen(cut), &o, &text, &len, &err) == 422 &&
                      strstr(err.msg, "membership"),
                  "cells=all without membership: %s", text ? text : err.msg);
            free(text);
            free(cut);
            res_free(&r);
        }
    }
    /* a face whose area overflows a double (an edited result): refused, not written as inf */
    {
        static const char huge[] = "{\"dim\":2,\"V\":[[1e308,0],[-1e308,0],[0,1]],"
                                   "\"EV\":[[0,1],[1,2],[0,2]],\"FV\":[[0,2,1]],\"holes\":{}}";
        char *text = NULL;
        size_t len = 0;
        api_error err;
        CHECK(render_geojson(huge, sizeof huge - 1, NULL, &text, &len, &err) == 422 &&
                  strstr(err.msg, "FV[0]"),
              "a face of infinite area: %s", text ? text : err.msg);
        free(text);
    }
}

/* Walks that pass a vertex twice: a triangle touching the square's side at a vertex, two
 * triangles meeting at a vertex inside, a dangling tree inside and one hanging from the side.
 * The GeoJSON rings must still be simple (check_geojson): the face is a shell with holes that
 * touch it or each other at a point, and the tree edges are LineStrings. */
TEST(render_rings_through_a_vertex_twice)
{
    check_request("cut vertices",
                  "{\"kind\":\"lines\",\"lines\":[[[0,0],[8,0]],[[8,0],[8,8]],[[8,8],[0,8]],"
                  "[[0,8],[0,0]],[[4,0],[6,4]],[[6,4],[2,4]],[[2,4],[4,0]],[[1,5],[2,7]],"
                  "[[2,7],[3,5]],[[3,5],[1,5]],[[3,5],[4,7]],[[4,7],[5,5]],[[5,5],[3,5]],"
                  "[[6,6],[7,6]],[[7,6],[7,7]],[[7,6],[7.5,5.5]],[[0,2],[1,2]],[[1,2],[1,3]]],"
                  "\"options\":{\"keep_dangling\":true}}",
                  -1, 1.5);
    check_request("cut vertices without dangling edges",
                  "{\"kind\":\"lines\",\"lines\":[[[0,0],[8,0]],[[8,0],[8,8]],[[8,8],[0,8]],"
                  "[[0,8],[0,0]],[[4,0],[6,4]],[[6,4],[2,4]],[[2,4],[4,0]],[[1,5],[2,7]],"
                  "[[2,7],[3,5]],[[3,5],[1,5]],[[3,5],[4,7]],[[4,7],[5,5]],[[5,5],[3,5]]]}",
                  -1, 2);
}

TEST(render_empty_result)
{
    res r;
    char *out = NULL;
    size_t len;
    api_error err;
    json_t *g;
    REQUIRE(res_run("{\"kind\":\"lines\",\"lines\":[]}", -1, &r), "run");
    check_request("empty", "{\"kind\":\"lines\",\"lines\":[]}", -1, 2);
    CHECK(render_geojson(r.text, r.len, NULL, &out, &len, &err) == API_OK, "%s", err.msg);
    g = json_loads(out ? out : "", 0, NULL);
    CHECK(json_array_size(json_object_get(g, "features")) == 0 &&
              json_is_array(json_object_get(g, "features")),
          "empty: %s", out);
    json_decref(g);
    free(out);
    res_free(&r);
}

/* The title is text from the caller: escaped, and bytes XML cannot hold replaced. */
TEST(render_title_is_escaped)
{
    res r;
    render_opts o = RENDER_OPTS_INIT;
    char *svg = NULL;
    size_t len;
    api_error err;
    xmlDocPtr doc;
    REQUIRE(res_run(ORTHOGONAL "}", -1, &r), "run");
    o.title = "<a & 'b'> \"c\" \x01\xff caf\xc3\xa9 ]]>";
    REQUIRE(render_svg(r.text, r.len, &o, &svg, &len, &err) == API_OK, "%s", err.msg);
    doc = xmlReadMemory(svg, (int)len, "t.svg", NULL,
                        XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    CHECK(doc != NULL, "title makes the SVG unreadable");
    if (doc) {
        xmlNodePtr t = xmlFirstElementChild(xmlDocGetRootElement(doc));
        char *c = (char *)xmlNodeGetContent(t);
        CHECK(t && !strcmp((const char *)t->name, "title") && c &&
                  !strcmp(c, "<a & 'b'> \"c\" ?? caf\xc3\xa9 ]]>"),
              "title read back as \"%s\"", c ? c : "(null)");
        xmlFree(c);
        xmlFreeDoc(doc);
    }
    free(svg);
    res_free(&r);
}

/* ---- errors -------------------------------------------------------------------------------- */

typedef struct bad_case {
    const char *result;
    const char *needle; /* the message names this */
} bad_case;

TEST(render_errors_are_422_with_a_message)
{
    static const bad_case cases[] = {
        {"this is not JSON", "malformed JSON"},
        {"", "empty"},
        {"[1,2]", "object"},
        {"{\"dim\":3,\"V\":[[0,0,0]],\"FV\":[]}", "dim"},
        {"{\"dim\":\"2\",\"V\":[],\"FV\":[]}", "dim"},
        {"{\"V\":[],\"FV\":[]}", "dim"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]]}", "FV"},
        {"{\"dim\":2,\"FV\":[[0,1,2]]}", "V"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]],\"FV\":[[0,1,3]]}", "FV[0][2]"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]],\"FV\":[[0,1,-1]]}", "FV[0][2]"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]],\"FV\":[[0,1]],\"stats\":{\"F\":1}}", "FV[0]"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0]],\"FV\":[[0,1,2]]}", "V[2]"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]],\"FV\":[[0,1,2]],\"holes\":{\"1\":[[0,1,2]]}}",
         "holes.1"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]],\"FV\":[[0,1,2]],\"holes\":{\"00\":[[0,1,2]]}}",
         "holes.00"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]],\"FV\":[[0,1,2]],\"holes\":{\"0\":[[0,7]]}}",
         "holes.0[0][1]"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]],\"FV\":[[0,1,2]],\"EV\":[[0,1,2]]}", "EV[0]"},
        {"{\"dim\":2,\"V\":[[0,0],[1,0],[0,1]],\"FV\":[[0,1,2]],\"EV\":[[0,9]]}", "EV[0][1]"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        for (int g = 0; g < 2; g++) {
            char *out = (char *)1;
            size_t len = 7;
            api_error err = {0};
            int rc =
                g ? render_geojson(cases[i].result, strlen(cases[i].result), NULL, &out, &len, &err)
                  : render_svg(cases[i].result, strlen(cases[i].result), NULL, &out, &len, &err);
            CHECK(rc == 422 && err.status == 422, "case %zu (%s): %d %s", i, g ? "geojson" : "svg",
                  rc, err.msg);
            CHECK(err.msg[0] && strstr(err.msg, cases[i].needle), "case %zu: \"%s\" lacks %s", i,
                  err.msg, cases[i].needle);
            CHECK(out == NULL && len == 0, "case %zu: output not cleared", i);
        }
    }
}

/* Every prefix of a result, and the result with bytes changed: a picture or an error value,
 * never a crash (the sanitizer build runs this too). */
TEST(render_damaged_results)
{
    res r;
    uint64_t seed = 42;
    size_t ok = 0, bad = 0;
    REQUIRE(res_run(CONCENTRIC ",\"options\":{\"exterior_last\":true}}", -1, &r), "run");
    for (size_t cut = 0; cut + 1 < r.len; cut++) { /* r.len - 1: all but the final newline */
        char *out = NULL;
        size_t len;
        api_error err;
        int rc = render_svg(r.text, cut, NULL, &out, &len, &err);
        CHECK(rc == 422 && !out, "prefix %zu: %d", cut, rc);
        free(out);
    }
    for (int t = 0; t < 2000; t++) {
        char *copy = malloc(r.len), *out = NULL;
        size_t len;
        api_error err;
        int rc;
        REQUIRE(copy, "malloc");
        memcpy(copy, r.text, r.len);
        for (int k = 0; k < 3; k++)
            copy[(size_t)(test_rnd(&seed) * (double)r.len)] = "0123456789-,[]{}\"e."[t % 17];
        rc = t % 2 ? render_geojson(copy, r.len, NULL, &out, &len, &err)
                   : render_svg(copy, r.len, NULL, &out, &len, &err);
        CHECK(rc == API_OK || (rc == 422 && err.msg[0] && !out), "mutation %d: %d", t, rc);
        if (rc == API_OK) {
            ok++;
            CHECK(out && len == strlen(out), "mutation %d: output", t);
        } else {
            bad++;
        }
        free(out);
        free(copy);
    }
    CHECK(ok > 0 && bad > 0, "mutations: %zu drawn, %zu refused", ok, bad);
    res_free(&r);
}

/* A real result asked for without V, FV or holes. */
TEST(render_missing_fields_of_real_results)
{
    static const struct {
        const char *fields;
        const char *key;
    } cases[] = {{"[\"V\",\"EV\"]", "FV:"},
                 {"[\"operators\"]", "V:"},
                 {"[\"stats\"]", "V:"},
                 {"[\"V\",\"EV\",\"FV\"]", "holes:"}};
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char body[512], *out = NULL;
        size_t len;
        api_error err;
        res r = {0};
        snprintf(body, sizeof body, "%s,\"options\":{\"fields\":%s}}", ORTHOGONAL, cases[i].fields);
        REQUIRE(api_run_json(body, strlen(body), 1, &r.text, &r.len, &err) == API_OK, "%s",
                err.msg);
        CHECK(render_svg(r.text, r.len, NULL, &out, &len, &err) == 422 &&
                  strncmp(err.msg, cases[i].key, strlen(cases[i].key)) == 0,
              "fields %s: %d %s", cases[i].fields, err.status, err.msg);
        CHECK(render_geojson(r.text, r.len, NULL, &out, &len, &err) == 422 &&
                  strncmp(err.msg, cases[i].key, strlen(cases[i].key)) == 0,
              "fields %s (geojson): %d %s", cases[i].fields, err.status, err.msg);
        res_free(&r);
    }
}

TEST(render_bad_options)
{
    res r;
    char *out = (char *)1;
    size_t len = 1;
    api_error err;
    render_opts o = RENDER_OPTS_INIT;
    REQUIRE(res_run(ORTHOGONAL "}", -1, &r), "run");
    o.explode = 0.5;
    CHECK(render_svg(r.text, r.len, &o, &out, &len, &err) == 422 && strstr(err.msg, "explode"),
          "explode 0.5: %s", err.msg);
    CHECK(out == NULL && len == 0, "output not cleared");
    o.explode = NAN;
    CHECK(render_svg(r.text, r.len, &o, &out, &len, &err) == 422, "explode NaN");
    o = (render_opts)RENDER_OPTS_INIT;
    o.width = 3;
    CHECK(render_svg(r.text, r.len, &o, &out, &len, &err) == 422 && strstr(err.msg, "width"),
          "width 3: %s", err.msg);
    o = (render_opts)RENDER_OPTS_INIT;
    o.stroke = -1;
    CHECK(render_svg(r.text, r.len, &o, &out, &len, &err) == 422 && strstr(err.msg, "stroke"),
          "stroke -1: %s", err.msg);
    /* huge coordinates exploded beyond doubles: an error, not inf in the picture */
    {
        const char *big = "{\"dim\":2,\"V\":[[-1e308,0],[1e308,0],[1e308,1e308],[-1e308,1e308],"
                          "[1e308,-1e308],[-1e308,-1e308]],"
                          "\"FV\":[[0,1,2,3],[5,4,1,0]]}";
        o = (render_opts)RENDER_OPTS_INIT;
        o.explode = 100;
        CHECK(render_svg(big, strlen(big), &o, &out, &len, &err) == 422, "huge explode: %d %s",
              err.status, err.msg);
    }
    res_free(&r);
}

/* ---- query parameters ---------------------------------------------------------------------- */

TEST(render_query_parameters)
{
    render_opts o;
    api_error err;
    static const char *const bad[][2] = {
        {"explode", "0.99"}, {"explode", "abc"},  {"explode", ""},   {"explode", "nan"},
        {"explode", "1e9"},  {"explode", " 1.2"}, {"width", "15"},   {"width", "16385"},
        {"width", "600px"},  {"width", "-800"},   {"width", "6e2"},  {"numbers", "2"},
        {"edges", "maybe"},  {"stroke", "-1"},    {"stroke", "101"}, {"explod", "1.2"},
        {"", "1"},           {"explode", NULL},   {"width", NULL},
    };
    const char *q = "explode=1.2&numbers=1&width=600";
    render_opts_init(&o);
    CHECK(o.explode == 1 && !o.numbers && o.edges && o.width == 800 && o.stroke == 0 && !o.title,
          "defaults");
    CHECK(render_opts_parse_query_string(q, strlen(q), &o, &err) == API_OK, "%s", err.msg);
    CHECK(o.explode == 1.2 && o.numbers == 1 && o.width == 600 && o.edges == 1, "parsed %g %d %d",
          o.explode, o.numbers, o.width);
    q = "numbers&edges=off;stroke=2.5&explode=1%2E5&width=+640";
    CHECK(render_opts_parse_query_string(q, strlen(q), &o, &err) == 422 && strstr(err.msg, "width"),
          "\"+640\" decodes to \" 640\": %s", err.msg);
    render_opts_init(&o);
    q = "numbers&edges=off;stroke=2.5&explode=1%2E5&&width=640";
    CHECK(render_opts_parse_query_string(q, strlen(q), &o, &err) == API_OK, "%s", err.msg);
    CHECK(o.numbers == 1 && o.edges == 0 && o.stroke == 2.5 && o.explode == 1.5 && o.width == 640,
          "parsed %d %d %g %g %d", o.numbers, o.edges, o.stroke, o.explode, o.width);
    CHECK(render_opts_parse_query("numbers", "FALSE", &o, &err) == API_OK && o.numbers == 0,
          "numbers=FALSE");
    CHECK(render_opts_parse_query("edges", "yes", &o, &err) == API_OK && o.edges == 1, "edges=yes");
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        render_opts before;
        render_opts_init(&o);
        before = o;
        err = (api_error){0};
        CHECK(render_opts_parse_query(bad[i][0], bad[i][1], &o, &err) == 422 && err.status == 422 &&
                  strstr(err.msg, bad[i][0]),
              "%s=%s: %d %s", bad[i][0], bad[i][1] ? bad[i][1] : "(none)", err.status, err.msg);
        CHECK(!memcmp(&o, &before, sizeof o), "%s=%s changed the options", bad[i][0],
              bad[i][1] ? bad[i][1] : "(none)");
    }
    for (size_t i = 0; i < 3; i++) {
        static const char *const qs[] = {"explode=1%2", "explode=%zz", "numbers=%00"};
        CHECK(render_opts_parse_query_string(qs[i], strlen(qs[i]), &o, &err) == 422 &&
                  strstr(err.msg, "percent"),
              "%s: %s", qs[i], err.msg);
    }
    CHECK(render_opts_is_query_key("explode") && render_opts_is_query_key("width") &&
              !render_opts_is_query_key("wait") && !render_opts_is_query_key(NULL),
          "is_query_key");
    /* the parsed options draw */
    {
        res r;
        q = "explode=1.3&numbers=1&width=600";
        render_opts_init(&o);
        REQUIRE(render_opts_parse_query_string(q, strlen(q), &o, &err) == API_OK, "%s", err.msg);
        REQUIRE(res_run(ORTHOGONAL "}", -1, &r), "run");
        check_svg("from a query", &r, &o, NULL);
        res_free(&r);
    }
}
