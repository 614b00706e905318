/* svg.c — SVG drawings to line segments (core/svg.h; DESIGN.md "SVG drawings").
 *
 * Stages:
 *   parse    libxml2 builds the tree: xmlCtxtReadMemory with XML_PARSE_NONET, without
 *            XML_PARSE_NOENT (entities are not substituted into the tree), DTDLOAD (no external
 *            subset, so no file or network access) or HUGE (libxml2's default limits stay: 256
 *            levels, 10 000 000 bytes per attribute value or text node).  Our SAX hooks count
 *            the elements and the depth as they are read and stop the parser at max_elements /
 *            max_depth, so memory is bounded by what was read and the message has the line and
 *            column.  Errors reach us through the context's structured error hook, so libxml2
 *            never prints.  What libxml2 2.9.14 does with hostile input (checked by
 *            tests/test_svg.c): billion laughs is refused while parsing (XML_ERR_ENTITY_LOOP,
 *            "Detected an entity reference loop", whether the entity is used in text or in an
 *            attribute); 100 000 nested elements stop at our max_depth (libxml2 alone would stop
 *            at 256, "Excessive depth in document"); a 20 MB attribute is "AttValue length too
 *            long".  We add: internal entities that refer to other entities are refused (no
 *            amplification by nesting), and the bytes that entity references in attribute
 *            values expand to are budgeted (SVG_MAX_BYTES for the whole document).
 *   walk     the tree, from the root, with the current transformation matrix (CTM): <g>, <a>,
 *            <switch> (its first child whose conditions hold), nested <svg> (x, y, width,
 *            height, viewBox, preserveAspectRatio), <use> (local #id, also through <symbol>;
 *            cycles refused, chains bounded by max_depth, expansions counted in max_elements),
 *            and the shapes.  Straight pieces become segments at once; curves (quadratic and
 *            cubic Béziers, elliptical arcs in centre form) are kept with their control points
 *            mapped to root user space.  Everything else (defs, symbol, clipPath, mask, marker,
 *            pattern, text, image, elements of other namespaces...) draws nothing.
 *   flatten  once the whole drawing is read its size is known, so the default tolerance (1e-3
 *            of the size) applies: each curve becomes n chords, n from the tolerance (Wang's
 *            bound for Béziers, the sagitta for arcs), at most SVG_CURVE_MAX_CHORDS.  A curve's
 *            first and last points are exactly the endpoints the neighbouring straight pieces
 *            have (the same local point through the same matrix), so paths stay connected.
 *   output   bbox in root user units, then the output map (normalize or y_up), reported.
 *
 * What is knowingly simple: no CSS beyond the style attribute's display (no <style> sheets,
 * no classes); no clipping (a nested <svg>'s overflow is drawn); lengths in %, em and ex are
 * refused on shapes (the element is skipped with a warning), % is resolved only for the x, y,
 * width and height of nested viewports; <rect> rounded corners (rx, ry) are drawn as arcs;
 * conditional attributes: only a non-empty requiredExtensions excludes an element.
 * Reading stops only at a limit, malformed XML or out of memory; an element that cannot be read
 * (a bad number, an odd coordinate count, a bad transform) is skipped and described in a
 * warning, and path data is drawn up to its first error as the SVG specification says
 * (path_draw: each command's numbers read by path_args, drawn from the pen by path_command).
 *
 * Counts: `elements` are the shapes drawn without error (once per drawing, so a shape used
 * twice counts twice), `skipped` the shapes and containers with an error (read in part or not
 * at all).  Zero-length pieces are not emitted.
 *
 * Threads: reentrant; the only global is the pthread_once that initialises libxml2.  Numbers
 * are converted with strtod_l in a "C" locale of our own, so the process locale does not matter.
 * Ownership: text is borrowed; out->seg is malloc'd and freed by svg_result_free().
 */
#include "core/svg.h"

#include <libxml/entities.h>
#include <libxml/hash.h>
#include <libxml/parser.h>
#include <libxml/SAX2.h>
#include <libxml/tree.h>
#include <locale.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/arr2.h"
#include "core/mem.h"

#define SVG_NS               "http://www.w3.org/2000/svg"
#define XLINK_NS             "http://www.w3.org/1999/xlink"
#define SVG_CURVE_MAX_CHORDS 4096u /* chords of one curve, whatever the tolerance */
#define SVG_DEPTH_CAP        1000u /* max_depth above this is taken as this (recursion) */
#define WMAX                 sizeof(((svg_result *)0)->warning[0])

static pthread_once_t xml_once = PTHREAD_ONCE_INIT;

static void xml_init(void)
{
    xmlInitParser();
}

/* ---- matrices -------------------------------------------------------------------------------- */

/* x' = a x + c y + e, y' = b x + d y + f (SVG's matrix(a,b,c,d,e,f)) */
typedef struct mat {
    double a, b, c, d, e, f;
} mat;

static const mat IDENTITY = {1, 0, 0, 1, 0, 0};

/* p ↦ A(B(p)) */
static mat mat_mul(const mat *A, const mat *B)
{
    mat r;
    r.a = A->a * B->a + A->c * B->b;
    r.b = A->b * B->a + A->d * B->b;
    r.c = A->a * B->c + A->c * B->d;
    r.d = A->b * B->c + A->d * B->d;
    r.e = A->a * B->e + A->c * B->f + A->e;
    r.f = A->b * B->e + A->d * B->f + A->f;
    return r;
}

static mat mat_translate(double tx, double ty)
{
    return (mat){1, 0, 0, 1, tx, ty};
}

static void mat_apply(const mat *m, double x, double y, double *ox, double *oy)
{
    *ox = m->a * x + m->c * y + m->e;
    *oy = m->b * x + m->d * y + m->f;
}

/* cos and sin of deg degrees, exact at multiples of 90 */
static void cos_sin_deg(double deg, double *c, double *s)
{
    double r = fmod(deg, 360.0);
    if (r < 0) r += 360.0;
    if (r == 0) {
        *c = 1, *s = 0;
    } else if (r == 90) {
        *c = 0, *s = 1;
    } else if (r == 180) {
        *c = -1, *s = 0;
    } else if (r == 270) {
        *c = 0, *s = -1;
    } else {
        *c = cos(r * (M_PI / 180));
        *s = sin(r * (M_PI / 180));
    }
}

/* ---- the reader -------------------------------------------------------------------------- */

enum { CURVE_QUAD, CURVE_CUBIC, CURVE_ARC };

/* A curve in root user space.  QUAD: p[0..5] = 3 points; CUBIC: p[0..7] = 4 points; ARC: p[0..1]
 * centre, p[2..3] u, p[4..5] v (point(t) = c + u cos t + v sin t), p[6] start angle, p[7] sweep,
 * p[8..11] the exact first and last points. */
typedef struct curve {
    int kind;
    double p[12];
} curve;

typedef struct id_entry {
    const char *id; /* borrowed from the tree */
    const xmlNode *node;
    size_t order; /* document order: the first of equal ids wins */
} id_entry;

/* The size of the nearest viewport, for percentages (NaN: unknown). */
typedef struct vpt {
    double w, h;
} vpt;

typedef struct reader {
    size_t max_elements, max_cmds, max_segs, max_depth;
    int rect_diagonal;
    xmlDocPtr doc;
    const xmlChar *root_ns; /* the root's namespace href (NULL: none) */
    locale_t cloc;
    double *seg; /* 4 per segment, root user space */
    size_t nseg, capseg;
    curve *cur;
    size_t ncur, capcur;
    size_t commands;    /* path commands read, all paths */
    size_t visited;     /* elements walked, <use> expansions included */
    size_t nelem, tick; /* elements of the document; visited at the next progress report */
    const svg_opts *o;
    size_t entity_budget; /* bytes entity references in attributes may still expand to */
    id_entry *ids;
    size_t nids;
    const xmlNode *use_stack[SVG_DEPTH_CAP + 1]; /* <use> elements being expanded */
    size_t nuse;
    int nonfinite; /* the current element produced a non-finite coordinate */
    svg_result *out;
    size_t warnings_total;
    char *err;
    size_t errlen;
} reader;

static int fail(reader *r, int code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* Records the error of the whole read (the first one wins); returns code. */
static int fail(reader *r, int code, const char *fmt, ...)
{
    va_list ap;
    if (!r->err || !r->errlen || r->err[0]) return code;
    va_start(ap, fmt);
    vsnprintf(r->err, r->errlen, fmt, ap);
    va_end(ap);
    for (char *p = r->err; *p; p++)
        if ((unsigned char)*p < 0x20 || (unsigned char)*p > 0x7e) *p = '?';
    return code;
}

static void warn(reader *r, const xmlNode *n, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Adds a warning about element n ("line 12: <path>: ..."); past the last slot, counts. */
static void warn(reader *r, const xmlNode *n, const char *fmt, ...)
{
    svg_result *o = r->out;
    char *w;
    int k;
    va_list ap;
    r->warnings_total++;
    if (o->nwarnings >= SVG_MAX_WARNINGS) return;
    w = o->warning[o->nwarnings++];
    k = n ? snprintf(w, WMAX, "line %ld: <%s>: ", xmlGetLineNo(n), (const char *)n->name) : 0;
    if (k < 0) k = 0;
    if ((size_t)k < WMAX) {
        va_start(ap, fmt);
        vsnprintf(w + k, WMAX - (size_t)k, fmt, ap);
        va_end(ap);
    }
    for (char *p = w; *p; p++)
        if ((unsigned char)*p < 0x20 || (unsigned char)*p > 0x7e) *p = '?';
}

/* An element that could not be read (or only in part): warned and counted. */
#define SKIP(r, n, ...)                                                                            \
    do {                                                                                           \
        (r)->out->skipped++;                                                                       \
        warn((r), (n), __VA_ARGS__);                                                               \
    } while (0)

/* Quotes at most 24 bytes of s for a message. */
static const char *snippet(const char *s, char buf[32])
{
    size_t n = strlen(s);
    if (n <= 24) return s;
    memcpy(buf, s, 21);
    memcpy(buf + 21, "...", 4);
    return buf;
}

/* ---- output of pieces ---------------------------------------------------------------------- */

static int push_seg(reader *r, double x1, double y1, double x2, double y2)
{
    if (x1 == x2 && y1 == y2) return ARR_OK;
    if (!isfinite(x1) || !isfinite(y1) || !isfinite(x2) || !isfinite(y2)) {
        r->nonfinite = 1;
        return ARR_OK;
    }
    if (r->nseg >= r->max_segs)
        return fail(r, ARR_ELIMIT, "more than %zu segments (limit max_segments)", r->max_segs);
    if (mem_grow(&r->seg, &r->capseg, r->nseg + 1, 4 * sizeof *r->seg))
        return fail(r, ARR_ENOMEM, "out of memory for %zu segments", r->nseg + 1);
    double *s = r->seg + 4 * r->nseg++;
    s[0] = x1, s[1] = y1, s[2] = x2, s[3] = y2;
    return ARR_OK;
}

/* A straight piece between two local points. */
static int line_local(reader *r, const mat *m, double x1, double y1, double x2, double y2)
{
    double a, b, c, d;
    mat_apply(m, x1, y1, &a, &b);
    mat_apply(m, x2, y2, &c, &d);
    return push_seg(r, a, b, c, d);
}

static int push_curve(reader *r, const curve *c, int npts)
{
    for (int i = 0; i < npts; i++)
        if (!isfinite(c->p[i])) {
            r->nonfinite = 1;
            return ARR_OK;
        }
    if (mem_grow(&r->cur, &r->capcur, r->ncur + 1, sizeof *r->cur))
        return fail(r, ARR_ENOMEM, "out of memory for %zu curves", r->ncur + 1);
    r->cur[r->ncur++] = *c;
    return ARR_OK;
}

/* Whether the control points x[0..2n) lie exactly on the segment from the first to the last:
 * then the curve's image is that segment (a smooth command after a line, a degenerate curve). */
static int bezier_is_straight(const double *x, int n)
{
    double dx = x[2 * n - 2] - x[0], dy = x[2 * n - 1] - x[1], l2 = dx * dx + dy * dy;
    for (int i = 1; i < n - 1; i++) {
        double px = x[2 * i] - x[0], py = x[2 * i + 1] - x[1], t = px * dx + py * dy;
        if (px * dy - py * dx != 0 || t < 0 || t > l2) return 0;
    }
    return 1;
}

/* Quadratic (n = 3) or cubic (n = 4) Bézier with local control points x[0..2n). */
static int bezier_local(reader *r, const mat *m, const double *x, int n)
{
    curve c = {.kind = n == 3 ? CURVE_QUAD : CURVE_CUBIC};
    if (bezier_is_straight(x, n)) return line_local(r, m, x[0], x[1], x[2 * n - 2], x[2 * n - 1]);
    for (int i = 0; i < n; i++) mat_apply(m, x[2 * i], x[2 * i + 1], &c.p[2 * i], &c.p[2 * i + 1]);
    return push_curve(r, &c, 2 * n);
}

/* Elliptical arc c + u cos t + v sin t for t from t0 over dt (local), from local point p0 to p1. */
static int arc_local(reader *r, const mat *m, double cx, double cy, double ux, double uy, double vx,
                     double vy, double t0, double dt, double x0, double y0, double x1, double y1)
{
    curve c = {.kind = CURVE_ARC};
    mat_apply(m, cx, cy, &c.p[0], &c.p[1]);
    c.p[2] = m->a * ux + m->c * uy, c.p[3] = m->b * ux + m->d * uy;
    c.p[4] = m->a * vx + m->c * vy, c.p[5] = m->b * vx + m->d * vy;
    c.p[6] = t0, c.p[7] = dt;
    mat_apply(m, x0, y0, &c.p[8], &c.p[9]);
    mat_apply(m, x1, y1, &c.p[10], &c.p[11]);
    return push_curve(r, &c, 12);
}

/* ---- lexical helpers -------------------------------------------------------------------- */

static int is_wsp(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f';
}

static void skip_wsp(const char **s)
{
    while (is_wsp(**s)) (*s)++;
}

/* whitespace and commas, anywhere */
static void skip_sep(const char **s)
{
    while (is_wsp(**s) || **s == ',') (*s)++;
}

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

/* Reads an SVG number at *s: [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?, the
 * exponent only when digits follow.  Returns 1 and advances *s, 0 when no number starts there,
 * -1 when it does not fit in a double (*s then points at it). */
static int scan_number(reader *r, const char **s, double *v)
{
    const char *p = *s, *start = *s;
    char buf[64], *big = NULL, *dst = buf;
    size_t n;
    int digits = 0;
    if (*p == '+' || *p == '-') p++;
    while (is_digit(*p)) p++, digits++;
    if (*p == '.') {
        const char *q = p + 1;
        int frac = 0;
        while (is_digit(*q)) q++, frac++;
        if (digits || frac) p = q, digits += frac;
    }
    if (!digits) return 0;
    if (*p == 'e' || *p == 'E') {
        const char *q = p + 1;
        if (*q == '+' || *q == '-') q++;
        if (is_digit(*q)) {
            while (is_digit(*q)) q++;
            p = q;
        }
    }
    n = (size_t)(p - start);
    if (n >= sizeof buf) {
        big = malloc(n + 1);
        if (!big) return -1;
        dst = big;
    }
    memcpy(dst, start, n);
    dst[n] = 0;
    *v = strtod_l(dst, NULL, r->cloc);
    free(big);
    if (!isfinite(*v)) return -1;
    *s = p;
    return 1;
}

enum { LEN_OK, LEN_PERCENT, LEN_FONT, LEN_BAD };

/* A length: a number and an optional unit (px, mm, cm, in, pt, pc at 96 dpi; % and em/ex
 * reported as such).  *v is in user units (for %, the percentage). */
static int parse_length(reader *r, const char *s, double *v)
{
    static const struct {
        const char *unit;
        double scale;
    } units[] = {{"px", 1},  {"mm", 96 / 25.4}, {"cm", 96 / 2.54},
                 {"in", 96}, {"pt", 96 / 72.0}, {"pc", 16}};
    int kind = LEN_OK;
    skip_wsp(&s);
    if (scan_number(r, &s, v) != 1) return LEN_BAD;
    if (*s == '%') {
        kind = LEN_PERCENT;
        s++;
    } else if ((s[0] == 'e' && (s[1] == 'm' || s[1] == 'x'))) {
        kind = LEN_FONT;
        s += 2;
    } else {
        for (size_t i = 0; i < sizeof units / sizeof units[0]; i++)
            if (strncmp(s, units[i].unit, 2) == 0) {
                *v *= units[i].scale;
                s += 2;
                break;
            }
    }
    skip_wsp(&s);
    if (*s || !isfinite(*v)) return LEN_BAD;
    return kind;
}

/* ---- attributes ------------------------------------------------------------------------------ */

/* An attribute's value: s borrowed from the tree, or owned when entities were expanded. */
typedef struct aval {
    const char *s; /* NULL: absent */
    xmlChar *owned;
} aval;

static void aval_free(aval *v)
{
    if (v->owned) xmlFree(v->owned);
    v->owned = NULL;
    v->s = NULL;
}

/* The attribute `name` of n in namespace ns (NULL: none). */
static const xmlAttr *attr_find(const xmlNode *n, const char *name, const char *ns)
{
    for (const xmlAttr *a = n->properties; a; a = a->next) {
        if (strcmp((const char *)a->name, name) != 0) continue;
        if (!ns && !a->ns) return a;
        if (ns && a->ns && a->ns->href && strcmp((const char *)a->ns->href, ns) == 0) return a;
    }
    return NULL;
}

/* The value of attribute a.  Entity references (only flat ones exist: see check_entities) are
 * expanded within the document's budget. */
static int attr_value(reader *r, const xmlAttr *a, aval *v)
{
    const xmlNode *c;
    size_t need = 0;
    v->s = NULL;
    v->owned = NULL;
    if (!a) return ARR_OK;
    c = a->children;
    if (!c) {
        v->s = "";
        return ARR_OK;
    }
    if (c->type == XML_TEXT_NODE && !c->next) {
        v->s = c->content ? (const char *)c->content : "";
        return ARR_OK;
    }
    for (; c; c = c->next) {
        if (c->type == XML_TEXT_NODE && c->content) {
            need += strlen((const char *)c->content);
        } else if (c->type == XML_ENTITY_REF_NODE) {
            xmlEntityPtr e = xmlGetDocEntity(r->doc, c->name);
            if (e && e->content) need += strlen((const char *)e->content);
        }
    }
    if (need > r->entity_budget)
        return fail(r, ARR_ELIMIT,
                    "entity references in attribute values expand to more than %u bytes "
                    "(limit SVG_MAX_BYTES)",
                    SVG_MAX_BYTES);
    r->entity_budget -= need;
    v->owned = xmlNodeListGetString(r->doc, a->children, 1);
    if (!v->owned) return fail(r, ARR_ENOMEM, "out of memory for an attribute value");
    v->s = (const char *)v->owned;
    return ARR_OK;
}

static int attr_get(reader *r, const xmlNode *n, const char *name, aval *v)
{
    return attr_value(r, attr_find(n, name, NULL), v);
}

/* One length attribute of a shape.  Returns 1 present and read, 0 absent (*v = dflt), or
 * ATTR_BAD: not readable (warned and counted as skipped) or *fatal set (an ARR_* code). */
enum { ATTR_BAD = -1 };
static int length_attr(reader *r, const xmlNode *n, const char *name, double dflt, double *v,
                       int *fatal)
{
    aval a;
    int k;
    char b[32];
    *fatal = attr_get(r, n, name, &a);
    if (*fatal) return ATTR_BAD;
    if (!a.s) {
        *v = dflt;
        return 0;
    }
    k = parse_length(r, a.s, v);
    if (k == LEN_OK) {
        aval_free(&a);
        return 1;
    }
    if (k == LEN_BAD)
        SKIP(r, n, "%s=\"%s\" is not a finite number or length; skipped", name, snippet(a.s, b));
    else
        SKIP(r, n, "%s=\"%s\": lengths in %s are not supported; skipped", name, snippet(a.s, b),
             k == LEN_PERCENT ? "%" : "em/ex");
    aval_free(&a);
    return ATTR_BAD;
}

/* ---- namespaces, visibility ------------------------------------------------------------------ */

/* A namespace href that is SVG's, also as "&name;" of an internal entity holding it (Illustrator
 * writes xmlns="&ns_svg;", which libxml2 keeps unexpanded). */
static int href_is_svg(xmlDocPtr doc, const xmlChar *href)
{
    const char *h = (const char *)href;
    size_t n;
    if (strcmp(h, SVG_NS) == 0) return 1;
    n = strlen(h);
    if (n > 2 && h[0] == '&' && h[n - 1] == ';' && n < 128) {
        char name[128];
        xmlEntityPtr e;
        memcpy(name, h + 1, n - 2);
        name[n - 2] = 0;
        e = xmlGetDocEntity(doc, (const xmlChar *)name);
        return e && e->content && strcmp((const char *)e->content, SVG_NS) == 0;
    }
    return 0;
}

/* An element of the drawing: no namespace, SVG's, or the root's. */
static int is_svg_element(const reader *r, const xmlNode *n)
{
    if (n->type != XML_ELEMENT_NODE) return 0;
    if (!n->ns || !n->ns->href) return 1;
    if (r->root_ns && strcmp((const char *)n->ns->href, (const char *)r->root_ns) == 0) return 1;
    return strcmp((const char *)n->ns->href, SVG_NS) == 0;
}

/* The value of CSS property prop in a style attribute (the last declaration wins), trimmed,
 * into buf; 0 when absent. */
static int style_prop(const char *style, const char *prop, char *buf, size_t len)
{
    size_t plen = strlen(prop);
    int found = 0;
    const char *s = style;
    while (*s) {
        const char *decl = s, *end = strchr(s, ';'), *colon;
        if (!end) end = s + strlen(s);
        s = *end ? end + 1 : end;
        while (decl < end && is_wsp(*decl)) decl++;
        colon = memchr(decl, ':', (size_t)(end - decl));
        if (!colon) continue;
        const char *ne = colon;
        while (ne > decl && is_wsp(ne[-1])) ne--;
        if ((size_t)(ne - decl) != plen || strncasecmp(decl, prop, plen) != 0) continue;
        const char *v = colon + 1, *ve = end;
        while (v < ve && is_wsp(*v)) v++;
        while (ve > v && is_wsp(ve[-1])) ve--;
        size_t k = (size_t)(ve - v) < len - 1 ? (size_t)(ve - v) : len - 1;
        memcpy(buf, v, k);
        buf[k] = 0;
        found = 1;
    }
    return found;
}

/* Whether n is hidden by display="none" or style="display:none" (style wins), or excluded by a
 * non-empty requiredExtensions (we support none).  Returns 1 hidden, 0 drawn; on a fatal error
 * sets *fatal (an ARR_* code) and returns 1. */
static int hidden(reader *r, const xmlNode *n, int *fatal)
{
    aval a;
    char v[32] = "";
    int none = 0;
    *fatal = attr_get(r, n, "display", &a);
    if (*fatal) return 1;
    if (a.s) {
        const char *s = a.s;
        skip_wsp(&s);
        if (strncmp(s, "none", 4) == 0) {
            s += 4;
            skip_wsp(&s);
            none = *s == 0;
        }
    }
    aval_free(&a);
    *fatal = attr_get(r, n, "style", &a);
    if (*fatal) return 1;
    if (a.s && style_prop(a.s, "display", v, sizeof v)) {
        char *imp = strstr(v, "!important");
        if (imp) {
            *imp = 0;
            while (imp > v && is_wsp(imp[-1])) *--imp = 0;
        }
        none = strcasecmp(v, "none") == 0;
    }
    aval_free(&a);
    *fatal = attr_get(r, n, "requiredExtensions", &a);
    if (*fatal) return 1;
    if (a.s) {
        const char *s = a.s;
        skip_wsp(&s);
        if (*s) none = 1;
    }
    aval_free(&a);
    return none;
}

/* ---- transform lists ------------------------------------------------------------------------ */

/* Parses a transform list into *m (identity when empty).  Returns 0, or -1 with why. */
static int parse_transform(reader *r, const char *s, mat *m, char *why, size_t wl)
{
    static const struct {
        const char *name;
        int n1, n2; /* accepted argument counts */
    } kinds[] = {{"matrix", 6, 6}, {"translate", 1, 2}, {"scale", 1, 2},
                 {"rotate", 1, 3}, {"skewX", 1, 1},     {"skewY", 1, 1}};
    *m = IDENTITY;
    skip_sep(&s);
    while (*s) {
        size_t len = 0, k;
        double a[6];
        int na = 0;
        mat t;
        while ((s[len] >= 'a' && s[len] <= 'z') || (s[len] >= 'A' && s[len] <= 'Z')) len++;
        for (k = 0; k < sizeof kinds / sizeof kinds[0]; k++)
            if (strlen(kinds[k].name) == len && strncmp(s, kinds[k].name, len) == 0) break;
        if (k == sizeof kinds / sizeof kinds[0]) {
            char b[32];
            snprintf(why, wl, "unknown transform at \"%s\"", snippet(s, b));
            return -1;
        }
        s += len;
        skip_wsp(&s);
        if (*s != '(') {
            snprintf(why, wl, "%s: expected (", kinds[k].name);
            return -1;
        }
        s++;
        for (;;) {
            double v;
            int got;
            skip_sep(&s);
            if (*s == ')') break;
            got = scan_number(r, &s, &v);
            if (got != 1 || na == 6) {
                snprintf(why, wl, "%s: %s", kinds[k].name,
                         got < 0 ? "a number beyond the range of doubles"
                                 : "expected numbers and )");
                return -1;
            }
            a[na++] = v;
        }
        s++;
        if (na != kinds[k].n1 && na != kinds[k].n2) {
            snprintf(why, wl, "%s takes %d%s%s arguments, not %d", kinds[k].name, kinds[k].n1,
                     kinds[k].n2 != kinds[k].n1 ? " or " : "",
                     kinds[k].n2 != kinds[k].n1 ? (kinds[k].n2 == 2 ? "2" : "3") : "", na);
            return -1;
        }
        switch (k) {
        case 0:
            t = (mat){a[0], a[1], a[2], a[3], a[4], a[5]};
            break;
        case 1:
            t = mat_translate(a[0], na == 2 ? a[1] : 0);
            break;
        case 2:
            t = (mat){a[0], 0, 0, na == 2 ? a[1] : a[0], 0, 0};
            break;
        case 3: {
            double c, sn;
            cos_sin_deg(a[0], &c, &sn);
            t = (mat){c, sn, -sn, c, 0, 0};
            if (na == 3) {
                mat to = mat_translate(a[1], a[2]), back = mat_translate(-a[1], -a[2]);
                t = mat_mul(&to, &t);
                t = mat_mul(&t, &back);
            }
            break;
        }
        case 4:
        case 5: {
            double c, sn;
            cos_sin_deg(a[0], &c, &sn);
            double tn = sn / c;
            t = k == 4 ? (mat){1, 0, tn, 1, 0, 0} : (mat){1, tn, 0, 1, 0, 0};
            break;
        }
        default:
            t = IDENTITY;
        }
        *m = mat_mul(m, &t);
        skip_sep(&s);
    }
    if (!isfinite(m->a) || !isfinite(m->b) || !isfinite(m->c) || !isfinite(m->d) ||
        !isfinite(m->e) || !isfinite(m->f)) {
        snprintf(why, wl, "the matrix is not finite");
        return -1;
    }
    return 0;
}

/* ctm · n's transform attribute into *out.  Returns 1 ok, 0 bad (warned, counted) or *fatal
 * set (an ARR_* code). */
static int element_transform(reader *r, const xmlNode *n, const mat *ctm, mat *out, int *fatal)
{
    aval a;
    mat t;
    char why[96], b[32];
    *out = *ctm;
    *fatal = attr_get(r, n, "transform", &a);
    if (*fatal) return 0;
    if (!a.s) return 1;
    if (parse_transform(r, a.s, &t, why, sizeof why) != 0) {
        SKIP(r, n, "transform=\"%s\": %s; skipped", snippet(a.s, b), why);
        aval_free(&a);
        return 0;
    }
    aval_free(&a);
    *out = mat_mul(ctm, &t);
    return 1;
}

/* ---- path data ----------------------------------------------------------------------------- */

/* Endpoint to centre parameterization of an SVG arc (SVG 1.1 appendix F.6.5, F.6.6), then the
 * arc in local coordinates.  Radii too small are scaled up; a zero radius is a line. */
static int path_arc(reader *r, const mat *m, double x1, double y1, double rx, double ry,
                    double phi_deg, int large, int sweep, double x2, double y2)
{
    double cphi, sphi, dx2, dy2, x1p, y1p, lambda, num, den, coef, cxp, cyp, cx, cy;
    double ux, uy, vx, vy, t1, dt;
    if (x1 == x2 && y1 == y2) return ARR_OK; /* omitted, as the specification says */
    rx = fabs(rx);
    ry = fabs(ry);
    if (rx == 0 || ry == 0) return line_local(r, m, x1, y1, x2, y2);
    cos_sin_deg(phi_deg, &cphi, &sphi);
    dx2 = (x1 - x2) / 2;
    dy2 = (y1 - y2) / 2;
    x1p = cphi * dx2 + sphi * dy2;
    y1p = -sphi * dx2 + cphi * dy2;
    lambda = (x1p * x1p) / (rx * rx) + (y1p * y1p) / (ry * ry);
    if (lambda > 1) {
        double sl = sqrt(lambda);
        rx *= sl;
        ry *= sl;
    }
    num = rx * rx * ry * ry - rx * rx * y1p * y1p - ry * ry * x1p * x1p;
    den = rx * rx * y1p * y1p + ry * ry * x1p * x1p;
    coef = num > 0 && den > 0 ? sqrt(num / den) : 0;
    if (large == sweep) coef = -coef;
    cxp = coef * rx * y1p / ry;
    cyp = -coef * ry * x1p / rx;
    cx = cphi * cxp - sphi * cyp + (x1 + x2) / 2;
    cy = sphi * cxp + cphi * cyp + (y1 + y2) / 2;
    /* angles of the start and end vectors in the unit-circle frame */
    t1 = atan2((y1p - cyp) / ry, (x1p - cxp) / rx);
    dt = atan2((-y1p - cyp) / ry, (-x1p - cxp) / rx) - t1;
    if (sweep && dt < 0) dt += 2 * M_PI;
    if (!sweep && dt > 0) dt -= 2 * M_PI;
    ux = rx * cphi, uy = rx * sphi;
    vx = -ry * sphi, vy = ry * cphi;
    return arc_local(r, m, cx, cy, ux, uy, vx, vy, t1, dt, x1, y1, x2, y2);
}

static int is_command(char c)
{
    return c && strchr("MmZzLlHhVvCcSsQqTtAa", c) != NULL;
}

/* How many numbers path command up (upper case) takes. */
static int path_nargs(char up)
{
    switch (up) {
    case 'Z':
        return 0;
    case 'H':
    case 'V':
        return 1;
    case 'M':
    case 'L':
    case 'T':
        return 2;
    case 'S':
    case 'Q':
        return 4;
    case 'C':
        return 6;
    default: /* 'A' */
        return 7;
    }
}

/* Reads the na arguments of command up at *s into a (an arc's flags one character each).
 * 0, or -1 with *why (and *bad_number when a number was beyond the range of doubles). */
static int path_args(reader *r, const char **s, char up, int na, double *a, const char **why,
                     int *bad_number)
{
    for (int i = 0; i < na; i++) {
        int got;
        skip_sep(s);
        if (up == 'A' && (i == 3 || i == 4)) { /* flags: one character each */
            if (**s != '0' && **s != '1') {
                *why = "expected an arc flag 0 or 1";
                return -1;
            }
            a[i] = *(*s)++ - '0';
            continue;
        }
        got = scan_number(r, s, &a[i]);
        if (got != 1) {
            *why = "expected a number";
            *bad_number = got < 0;
            return -1;
        }
    }
    return 0;
}

/* Where a path's drawing stands: the current point, its subpath's start, the last control
 * point (for S and T) and the last command (upper case). */
typedef struct pen {
    double x, y, sx, sy, qx, qy;
    char prev;
} pen;

/* Draws command up (relative when rel) with its arguments a from the pen p, which it moves.
 * ARR_OK or a fatal code. */
static int path_command(reader *r, const mat *m, pen *p, char up, int rel, const double *a)
{
    double x = p->x, y = p->y;
    int rc = ARR_OK;
    switch (up) {
    case 'Z':
        rc = line_local(r, m, x, y, p->sx, p->sy);
        p->x = p->sx, p->y = p->sy;
        break;
    case 'M':
        p->x = rel ? x + a[0] : a[0];
        p->y = rel ? y + a[1] : a[1];
        p->sx = p->x, p->sy = p->y;
        break;
    case 'L':
    case 'H':
    case 'V': {
        double nx = x, ny = y;
        if (up == 'L') nx = rel ? x + a[0] : a[0], ny = rel ? y + a[1] : a[1];
        if (up == 'H') nx = rel ? x + a[0] : a[0];
        if (up == 'V') ny = rel ? y + a[0] : a[0];
        rc = line_local(r, m, x, y, nx, ny);
        p->x = nx, p->y = ny;
        break;
    }
    case 'C':
    case 'S': {
        double c[8] = {x, y};
        int k = 0;
        if (up == 'C') {
            c[2] = a[0], c[3] = a[1];
            k = 2;
        } else if (p->prev == 'C' || p->prev == 'S') {
            c[2] = 2 * x - p->qx, c[3] = 2 * y - p->qy;
        } else {
            c[2] = x, c[3] = y;
        }
        c[4] = a[k], c[5] = a[k + 1], c[6] = a[k + 2], c[7] = a[k + 3];
        if (rel) {
            if (up == 'C') c[2] += x, c[3] += y;
            c[4] += x, c[5] += y, c[6] += x, c[7] += y;
        }
        rc = bezier_local(r, m, c, 4);
        p->qx = c[4], p->qy = c[5];
        p->x = c[6], p->y = c[7];
        break;
    }
    case 'Q':
    case 'T': {
        double c[6] = {x, y};
        if (up == 'Q') {
            c[2] = rel ? x + a[0] : a[0], c[3] = rel ? y + a[1] : a[1];
            c[4] = rel ? x + a[2] : a[2], c[5] = rel ? y + a[3] : a[3];
        } else {
            if (p->prev == 'Q' || p->prev == 'T')
                c[2] = 2 * x - p->qx, c[3] = 2 * y - p->qy;
            else
                c[2] = x, c[3] = y;
            c[4] = rel ? x + a[0] : a[0], c[5] = rel ? y + a[1] : a[1];
        }
        rc = bezier_local(r, m, c, 3);
        p->qx = c[2], p->qy = c[3];
        p->x = c[4], p->y = c[5];
        break;
    }
    default: { /* 'A' */
        double nx = rel ? x + a[5] : a[5], ny = rel ? y + a[6] : a[6];
        rc = path_arc(r, m, x, y, a[0], a[1], a[2], a[3] != 0, a[4] != 0, nx, ny);
        p->x = nx, p->y = ny;
        break;
    }
    }
    p->prev = up;
    return rc;
}

/* Reads the path data d of element n and draws it with m: command by command, each with its
 * arguments (path_args) from the pen (path_command).  Drawn up to the first error (then warned
 * and counted as skipped).  Returns ARR_OK or a fatal code. */
static int path_draw(reader *r, const xmlNode *n, const char *d, const mat *m)
{
    const char *s = d, *cmd_at = d;
    pen p = {0};
    char cmd = 0;
    const char *why = NULL;
    int rc = ARR_OK, bad_number = 0;
    skip_sep(&s);
    if (!*s) return ARR_OK;
    if (*s != 'M' && *s != 'm') {
        why = "path data must start with M or m";
        goto bad;
    }
    for (;;) {
        double a[7];
        skip_sep(&s);
        if (!*s) break;
        cmd_at = s;
        if (is_command(*s)) {
            cmd = *s++;
        } else if (!cmd || cmd == 'Z' || cmd == 'z') {
            why = cmd ? "expected a command after Z" : "expected a command";
            goto bad;
        }
        if (++r->commands > r->max_cmds)
            return fail(r, ARR_ELIMIT,
                        "line %ld: more than %zu path commands (limit "
                        "max_path_commands)",
                        xmlGetLineNo(n), r->max_cmds);
        int rel = cmd >= 'a';
        char up = rel ? (char)(cmd - 32) : cmd;
        if (path_args(r, &s, up, path_nargs(up), a, &why, &bad_number)) goto bad;
        if (up == 'M') cmd = rel ? 'l' : 'L'; /* pairs that follow are implicit lineto */
        if ((rc = path_command(r, m, &p, up, rel, a)) != ARR_OK) return rc;
    }
    return ARR_OK;
bad : {
    char b[32];
    SKIP(r, n, "d: %s at offset %zu (\"%s\"); drawn up to there",
         bad_number ? "a number beyond the range of doubles" : why, (size_t)(cmd_at - d),
         snippet(cmd_at, b));
    return ARR_OK;
}
}

/* ---- shapes --------------------------------------------------------------------------------- */

/* Reads the named length attributes of n into v (defaults dflt).  Returns 1 all read, 0 one is
 * bad (warned, counted), or sets *fatal. */
static int lengths(reader *r, const xmlNode *n, const char *const *names, const double *dflt,
                   double *v, int count, int *present, int *fatal)
{
    for (int i = 0; i < count; i++) {
        int k = length_attr(r, n, names[i], dflt[i], &v[i], fatal);
        if (*fatal || k == ATTR_BAD) return 0;
        if (present) present[i] = k == 1;
    }
    return 1;
}

static int draw_line(reader *r, const xmlNode *n, const mat *m)
{
    static const char *const names[] = {"x1", "y1", "x2", "y2"};
    static const double dflt[4] = {0};
    double v[4];
    int fatal = 0;
    if (!lengths(r, n, names, dflt, v, 4, NULL, &fatal)) return fatal;
    r->out->elements++;
    return line_local(r, m, v[0], v[1], v[2], v[3]);
}

static int draw_rect(reader *r, const xmlNode *n, const mat *m)
{
    static const char *const names[] = {"x", "y", "width", "height", "rx", "ry"};
    static const double dflt[6] = {0, 0, 0, 0, 0, 0};
    double v[6];
    int has[6], fatal = 0, rc = ARR_OK;
    if (!lengths(r, n, names, dflt, v, 6, has, &fatal)) return fatal;
    double x = v[0], y = v[1], w = v[2], h = v[3], rx = v[4], ry = v[5];
    if (w < 0 || h < 0 || rx < 0 || ry < 0) {
        SKIP(r, n, "negative %s; skipped", w < 0 || h < 0 ? "width or height" : "rx or ry");
        return ARR_OK;
    }
    r->out->elements++;
    if (w == 0 || h == 0) return ARR_OK; /* not rendered */
    if (r->rect_diagonal) return line_local(r, m, x, y, x + w, y + h);
    if (has[4] && !has[5]) ry = rx;
    if (has[5] && !has[4]) rx = ry;
    if (rx > w / 2) rx = w / 2;
    if (ry > h / 2) ry = h / 2;
    if (rx == 0 || ry == 0) {
        if (!rc) rc = line_local(r, m, x, y, x + w, y);
        if (!rc) rc = line_local(r, m, x + w, y, x + w, y + h);
        if (!rc) rc = line_local(r, m, x + w, y + h, x, y + h);
        if (!rc) rc = line_local(r, m, x, y + h, x, y);
        return rc;
    }
    /* rounded: sides between the corner arcs, clockwise on screen from the top left */
    const double h2 = M_PI / 2;
    if (!rc) rc = line_local(r, m, x + rx, y, x + w - rx, y);
    if (!rc)
        rc = arc_local(r, m, x + w - rx, y + ry, rx, 0, 0, ry, -h2, h2, x + w - rx, y, x + w,
                       y + ry);
    if (!rc) rc = line_local(r, m, x + w, y + ry, x + w, y + h - ry);
    if (!rc)
        rc = arc_local(r, m, x + w - rx, y + h - ry, rx, 0, 0, ry, 0, h2, x + w, y + h - ry,
                       x + w - rx, y + h);
    if (!rc) rc = line_local(r, m, x + w - rx, y + h, x + rx, y + h);
    if (!rc)
        rc =
            arc_local(r, m, x + rx, y + h - ry, rx, 0, 0, ry, h2, h2, x + rx, y + h, x, y + h - ry);
    if (!rc) rc = line_local(r, m, x, y + h - ry, x, y + ry);
    if (!rc) rc = arc_local(r, m, x + rx, y + ry, rx, 0, 0, ry, M_PI, h2, x, y + ry, x + rx, y);
    return rc;
}

/* circle (is_circle) or ellipse: a closed arc from angle 0 */
static int draw_ellipse(reader *r, const xmlNode *n, const mat *m, int is_circle)
{
    static const char *const cnames[] = {"cx", "cy", "r"};
    static const char *const enames[] = {"cx", "cy", "rx", "ry"};
    static const double dflt[4] = {0, 0, 0, 0};
    double v[4];
    int has[4] = {0}, fatal = 0;
    if (!lengths(r, n, is_circle ? cnames : enames, dflt, v, is_circle ? 3 : 4, has, &fatal))
        return fatal;
    double cx = v[0], cy = v[1], rx = v[2], ry = is_circle ? v[2] : v[3];
    if (!is_circle && has[2] && !has[3]) ry = rx; /* SVG 2: a missing radius is "auto" */
    if (!is_circle && has[3] && !has[2]) rx = ry;
    if (rx < 0 || ry < 0) {
        SKIP(r, n, "negative radius; skipped");
        return ARR_OK;
    }
    r->out->elements++;
    if (rx == 0 || ry == 0) return ARR_OK; /* not rendered */
    return arc_local(r, m, cx, cy, rx, 0, 0, ry, 0, 2 * M_PI, cx + rx, cy, cx + rx, cy);
}

static int draw_poly(reader *r, const xmlNode *n, const mat *m, int closed)
{
    aval a;
    const char *s;
    double x0 = 0, y0 = 0, px = 0, py = 0, c[2];
    size_t npts = 0, ncoord = 0;
    int rc, bad = 0;
    rc = attr_get(r, n, "points", &a);
    if (rc) return rc;
    s = a.s ? a.s : "";
    for (;;) {
        int got;
        skip_sep(&s);
        if (!*s) break;
        got = scan_number(r, &s, &c[ncoord % 2]);
        if (got != 1) {
            bad = got < 0 ? 2 : 1;
            break;
        }
        if (++ncoord % 2) continue;
        if (npts == 0) {
            x0 = c[0], y0 = c[1];
        } else {
            rc = line_local(r, m, px, py, c[0], c[1]);
            if (rc) goto out;
        }
        px = c[0], py = c[1];
        npts++;
    }
    if (closed && npts > 2) rc = line_local(r, m, px, py, x0, y0);
    if (bad || ncoord % 2) {
        char b[32];
        SKIP(r, n, "points: %s after %zu numbers (\"%s\"); drawn up to there",
             bad == 2 ? "a number beyond the range of doubles"
             : bad    ? "not a number"
                      : "an odd number of coordinates",
             ncoord, snippet(s, b));
    } else {
        r->out->elements++;
    }
out:
    aval_free(&a);
    return rc;
}

static int draw_path(reader *r, const xmlNode *n, const mat *m)
{
    aval a;
    size_t skipped = r->out->skipped;
    int rc = attr_get(r, n, "d", &a);
    if (rc) return rc;
    if (a.s) rc = path_draw(r, n, a.s, m);
    if (!rc && r->out->skipped == skipped) r->out->elements++;
    aval_free(&a);
    return rc;
}

/* ---- containers ---------------------------------------------------------------------------- */

static int walk(reader *r, const xmlNode *n, const mat *ctm, vpt vp, size_t depth);

static int walk_children(reader *r, const xmlNode *n, const mat *ctm, vpt vp, size_t depth)
{
    for (const xmlNode *c = n->children; c; c = c->next) {
        if (c->type == XML_ENTITY_REF_NODE) {
            warn(r, n, "entity reference &%s; in element content is not expanded",
                 (const char *)c->name);
            continue;
        }
        if (!is_svg_element(r, c)) continue;
        int rc = walk(r, c, ctm, vp, depth + 1);
        if (rc) return rc;
    }
    return ARR_OK;
}

/* Parses viewBox="x y w h".  Returns 1 read, 0 absent, -1 bad. */
static int parse_viewbox(reader *r, const char *s, double vb[4])
{
    if (!s) return 0;
    for (int i = 0; i < 4; i++) {
        skip_sep(&s);
        if (scan_number(r, &s, &vb[i]) != 1) return -1;
    }
    skip_sep(&s);
    return *s ? -1 : 1;
}

/* preserveAspectRatio: align (0..2 per axis: min, mid, max; -1: none) and slice. */
static int parse_par(const char *s, int *ax, int *ay, int *slice)
{
    static const char *const al[3] = {"Min", "Mid", "Max"};
    *ax = *ay = 1;
    *slice = 0;
    if (!s) return 0;
    skip_wsp(&s);
    if (strncmp(s, "defer", 5) == 0) {
        s += 5;
        skip_wsp(&s);
    }
    if (strncmp(s, "none", 4) == 0) {
        *ax = *ay = -1;
        s += 4;
    } else {
        int i, j;
        if (s[0] != 'x') return -1;
        for (i = 0; i < 3 && strncmp(s + 1, al[i], 3) != 0; i++) {
        }
        if (i == 3 || s[4] != 'Y') return -1;
        for (j = 0; j < 3 && strncmp(s + 5, al[j], 3) != 0; j++) {
        }
        if (j == 3) return -1;
        *ax = i, *ay = j;
        s += 8;
    }
    skip_wsp(&s);
    if (strncmp(s, "meet", 4) == 0) {
        s += 4;
    } else if (strncmp(s, "slice", 5) == 0) {
        *slice = 1;
        s += 5;
    }
    skip_wsp(&s);
    return *s ? -1 : 0;
}

/* A viewport length attribute (x, y, width, height) of n, or of `over` when it has it (a <use>
 * sizing a symbol or svg); dflt_pct % when absent; % of the parent viewport's size `of`, which
 * may be unknown (NaN): then *v is NaN.  Returns 1 read, 0 bad (warned) or *fatal set. */
static int vp_length(reader *r, const xmlNode *n, const xmlNode *over, const char *name,
                     double dflt_pct, double of, double *v, int *fatal)
{
    aval a = {0};
    int k;
    char b[32];
    const xmlNode *src = n;
    *fatal = 0;
    if (over) {
        *fatal = attr_get(r, over, name, &a);
        if (*fatal) return 0;
        if (a.s) src = over;
    }
    if (!a.s) *fatal = attr_get(r, n, name, &a);
    if (*fatal) return 0;
    if (!a.s) {
        *v = dflt_pct == 0 ? 0 : dflt_pct * of / 100;
        return 1;
    }
    k = parse_length(r, a.s, v);
    if (k == LEN_PERCENT) {
        *v = *v * of / 100;
        k = LEN_OK;
    }
    if (k != LEN_OK)
        SKIP(r, src, "%s=\"%s\": %s; skipped", name, snippet(a.s, b),
             k == LEN_BAD ? "not a finite number or length" : "lengths in em/ex are not supported");
    aval_free(&a);
    return k == LEN_OK;
}

/* The map of a viewport-establishing element n (nested <svg>, or <svg>/<symbol> through the
 * <use> `over`, whose width and height win) into its parent, and its inner viewport.  Width and
 * height default to 100% of the parent's; they matter only with a viewBox (no clipping), so an
 * unknown parent size is an error only then.  Returns 1 drawn, 0 not (zero size, or an error:
 * warned), or sets *fatal. */
static int viewport_map(reader *r, const xmlNode *n, const xmlNode *over, vpt parent, mat *m,
                        vpt *inner, int *fatal)
{
    double x = 0, y = 0, w, h, vb[4];
    int ax, ay, slice, k;
    aval a;
    char b[32];
    int is_symbol = strcmp((const char *)n->name, "symbol") == 0;
    if (!is_symbol) {
        if (!vp_length(r, n, NULL, "x", 0, parent.w, &x, fatal)) return 0;
        if (!vp_length(r, n, NULL, "y", 0, parent.h, &y, fatal)) return 0;
        if (isnan(x) || isnan(y)) {
            SKIP(r, n, "x, y: a percentage of a viewport of unknown size; skipped");
            return 0;
        }
    }
    if (!vp_length(r, n, over, "width", 100, parent.w, &w, fatal)) return 0;
    if (!vp_length(r, n, over, "height", 100, parent.h, &h, fatal)) return 0;
    if (w < 0 || h < 0) {
        SKIP(r, n, "negative width or height; skipped");
        return 0;
    }
    if (w == 0 || h == 0) return 0; /* not rendered */
    *fatal = attr_get(r, n, "viewBox", &a);
    if (*fatal) return 0;
    k = parse_viewbox(r, a.s, vb);
    if (k < 0 || (k > 0 && (vb[2] < 0 || vb[3] < 0))) {
        SKIP(r, n, "viewBox=\"%s\" is not 4 numbers with width, height >= 0; skipped",
             snippet(a.s, b));
        aval_free(&a);
        return 0;
    }
    aval_free(&a);
    if (k == 0) {
        *m = mat_translate(x, y);
        *inner = (vpt){w, h};
        return 1;
    }
    if (vb[2] == 0 || vb[3] == 0) return 0;
    if (isnan(w) || isnan(h)) {
        SKIP(r, n,
             "width, height: a percentage of a viewport of unknown size (the root has no "
             "viewBox, width or height); skipped");
        return 0;
    }
    *fatal = attr_get(r, n, "preserveAspectRatio", &a);
    if (*fatal) return 0;
    if (parse_par(a.s, &ax, &ay, &slice) != 0) {
        warn(r, n, "preserveAspectRatio=\"%s\" not understood; xMidYMid meet used",
             snippet(a.s, b));
        ax = ay = 1;
        slice = 0;
    }
    aval_free(&a);
    double sx = w / vb[2], sy = h / vb[3], tx, ty;
    if (ax >= 0) sx = sy = slice ? fmax(sx, sy) : fmin(sx, sy);
    tx = x - vb[0] * sx;
    ty = y - vb[1] * sy;
    if (ax > 0) tx += (w - vb[2] * sx) / (ax == 1 ? 2 : 1);
    if (ay > 0) ty += (h - vb[3] * sy) / (ay == 1 ? 2 : 1);
    *m = (mat){sx, 0, 0, sy, tx, ty};
    *inner = (vpt){vb[2], vb[3]};
    return 1;
}

static int cmp_id(const void *pa, const void *pb)
{
    const id_entry *a = pa, *b = pb;
    int c = strcmp(a->id, b->id);
    return c ? c : (a->order > b->order) - (a->order < b->order);
}

/* Indexes the elements' id attributes (plain text values only). */
static int index_ids(reader *r, const xmlNode *root)
{
    size_t cap = 0, order = 0;
    const xmlNode *n = root;
    while (n) {
        if (n->type == XML_ELEMENT_NODE) {
            const xmlAttr *a = attr_find(n, "id", NULL);
            if (!a) a = attr_find(n, "id", (const char *)XML_XML_NAMESPACE);
            if (a && a->children && a->children->type == XML_TEXT_NODE && !a->children->next &&
                a->children->content) {
                if (mem_grow(&r->ids, &cap, r->nids + 1, sizeof *r->ids))
                    return fail(r, ARR_ENOMEM, "out of memory for the id index");
                r->ids[r->nids++] = (id_entry){(const char *)a->children->content, n, order};
            }
            order++;
        }
        r->nelem = order;
        if (n->type == XML_ELEMENT_NODE && n->children) {
            n = n->children;
            continue;
        }
        while (n && n != root && !n->next) n = n->parent;
        if (!n || n == root) break;
        n = n->next;
    }
    if (r->nids) qsort(r->ids, r->nids, sizeof *r->ids, cmp_id);
    return ARR_OK;
}

static const xmlNode *find_id(const reader *r, const char *id)
{
    size_t lo = 0, hi = r->nids;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (strcmp(r->ids[mid].id, id) < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < r->nids && strcmp(r->ids[lo].id, id) == 0 ? r->ids[lo].node : NULL;
}

static int is_ancestor_or_self(const xmlNode *a, const xmlNode *n)
{
    for (; n; n = n->parent)
        if (n == a) return 1;
    return 0;
}

static int draw_use(reader *r, const xmlNode *n, const mat *ctm, vpt vp, size_t depth)
{
    aval h = {0};
    const xmlAttr *ha = attr_find(n, "href", XLINK_NS);
    const xmlNode *t;
    double x, y;
    mat m, inner_m;
    vpt inner = vp;
    int fatal = 0, rc = ARR_OK;
    char b[32];
    if (!ha) ha = attr_find(n, "href", NULL);
    if (!ha) ha = attr_find(n, "xlink:href", NULL); /* prefix used without declaring it */
    rc = attr_value(r, ha, &h);
    if (rc) return rc;
    if (!h.s) goto out; /* nothing to draw */
    if (h.s[0] != '#') {
        SKIP(r, n, "href=\"%s\": only local references (#id) are supported; skipped",
             snippet(h.s, b));
        goto out;
    }
    t = find_id(r, h.s + 1);
    if (!t) {
        SKIP(r, n, "href=\"%s\": no element has this id; skipped", snippet(h.s, b));
        goto out;
    }
    if (is_ancestor_or_self(t, n)) goto cycle;
    for (size_t i = 0; i < r->nuse; i++)
        if (is_ancestor_or_self(t, r->use_stack[i])) goto cycle;
    if (!is_svg_element(r, t)) goto out;
    if (length_attr(r, n, "x", 0, &x, &fatal) == ATTR_BAD ||
        length_attr(r, n, "y", 0, &y, &fatal) == ATTR_BAD) {
        rc = fatal;
        goto out;
    }
    if (!element_transform(r, n, ctm, &m, &fatal)) {
        rc = fatal;
        goto out;
    }
    inner_m = mat_translate(x, y);
    m = mat_mul(&m, &inner_m);
    if (r->nuse >= r->max_depth || depth >= r->max_depth) {
        rc = fail(r, ARR_ELIMIT, "line %ld: <use> chain nested deeper than %zu (limit max_depth)",
                  xmlGetLineNo(n), r->max_depth);
        goto out;
    }
    r->use_stack[r->nuse++] = n;
    if (strcmp((const char *)t->name, "symbol") == 0 || strcmp((const char *)t->name, "svg") == 0) {
        /* a viewport sized by the use's width and height */
        int hid = hidden(r, t, &fatal);
        if (fatal) {
            rc = fatal;
        } else if (!hid) {
            if (++r->visited > r->max_elements)
                rc = fail(r, ARR_ELIMIT,
                          "more than %zu elements to draw, <use> expansions included (limit "
                          "max_elements)",
                          r->max_elements);
            else if (element_transform(r, t, &m, &m, &fatal) &&
                     viewport_map(r, t, n, vp, &inner_m, &inner, &fatal))
                m = mat_mul(&m, &inner_m), rc = walk_children(r, t, &m, inner, depth + 1);
            if (!rc) rc = fatal;
        }
    } else {
        rc = walk(r, t, &m, vp, depth + 1);
    }
    r->nuse--;
out:
    aval_free(&h);
    return rc;
cycle:
    SKIP(r, n, "href=\"%s\" refers to an element that contains this <use>: a cycle; skipped",
         snippet(h.s, b));
    aval_free(&h);
    return ARR_OK;
}

/* <switch>: the first direct child whose conditions hold (requiredExtensions empty). */
static int draw_switch(reader *r, const xmlNode *n, const mat *ctm, vpt vp, size_t depth)
{
    for (const xmlNode *c = n->children; c; c = c->next) {
        aval a;
        int rc, excluded = 0;
        if (!is_svg_element(r, c)) continue;
        rc = attr_get(r, c, "requiredExtensions", &a);
        if (rc) return rc;
        if (a.s) {
            const char *s = a.s;
            skip_wsp(&s);
            excluded = *s != 0;
        }
        aval_free(&a);
        if (!excluded) return walk(r, c, ctm, vp, depth + 1);
    }
    return ARR_OK;
}

/* Draws element n (an SVG element) under ctm. */
static int walk(reader *r, const xmlNode *n, const mat *ctm, vpt vp, size_t depth)
{
    const char *name = (const char *)n->name;
    size_t nseg = r->nseg, ncur = r->ncur, elements = r->out->elements;
    mat m;
    int fatal = 0, rc = ARR_OK;
    if (++r->visited > r->max_elements)
        return fail(r, ARR_ELIMIT,
                    "more than %zu elements to draw, <use> expansions included (limit "
                    "max_elements)",
                    r->max_elements);
    if (depth > r->max_depth)
        return fail(r, ARR_ELIMIT, "line %ld: elements nested deeper than %zu (limit max_depth)",
                    xmlGetLineNo(n), r->max_depth);
    if (r->o->progress && r->visited >= r->tick) { /* parsing was 0.3, walking is to 0.8 */
        r->tick = r->visited + r->nelem / 100 + 1;
        double f = (double)r->visited / (double)(r->nelem + 1);
        r->o->progress(r->o->udata, 0.3 + 0.5 * (f < 1 ? f : 1));
    }
    if (hidden(r, n, &fatal) || fatal) return fatal;
    if (strcmp(name, "g") == 0 || strcmp(name, "a") == 0) {
        if (element_transform(r, n, ctm, &m, &fatal)) rc = walk_children(r, n, &m, vp, depth);
        return rc ? rc : fatal;
    }
    if (strcmp(name, "switch") == 0) {
        if (element_transform(r, n, ctm, &m, &fatal)) rc = draw_switch(r, n, &m, vp, depth);
        return rc ? rc : fatal;
    }
    if (strcmp(name, "svg") == 0) { /* nested: a new viewport */
        mat vm;
        vpt inner;
        if (element_transform(r, n, ctm, &m, &fatal) &&
            viewport_map(r, n, NULL, vp, &vm, &inner, &fatal)) {
            m = mat_mul(&m, &vm);
            rc = walk_children(r, n, &m, inner, depth);
        }
        return rc ? rc : fatal;
    }
    if (strcmp(name, "use") == 0) return draw_use(r, n, ctm, vp, depth);
    int shape = strcmp(name, "line") == 0       ? 1
                : strcmp(name, "rect") == 0     ? 2
                : strcmp(name, "polyline") == 0 ? 3
                : strcmp(name, "polygon") == 0  ? 4
                : strcmp(name, "path") == 0     ? 5
                : strcmp(name, "circle") == 0   ? 6
                : strcmp(name, "ellipse") == 0  ? 7
                                                : 0;
    if (!shape) return ARR_OK; /* draws nothing: defs, symbol, text, image, ... */
    if (!element_transform(r, n, ctm, &m, &fatal)) return fatal;
    r->nonfinite = 0;
    switch (shape) {
    case 1:
        rc = draw_line(r, n, &m);
        break;
    case 2:
        rc = draw_rect(r, n, &m);
        break;
    case 3:
    case 4:
        rc = draw_poly(r, n, &m, shape == 4);
        break;
    case 5:
        rc = draw_path(r, n, &m);
        break;
    default:
        rc = draw_ellipse(r, n, &m, shape == 6);
        break;
    }
    if (!rc && r->nonfinite) { /* coordinates beyond doubles: drop the whole element */
        r->nseg = nseg;
        r->ncur = ncur;
        if (r->out->elements > elements) r->out->elements = elements;
        SKIP(r, n, "coordinates beyond the range of doubles after transforms; skipped");
    }
    return rc;
}

/* ---- flattening ---------------------------------------------------------------------------- */

static double hyp(double x, double y)
{
    return sqrt(x * x + y * y);
}

/* chords for curve c at tolerance tol */
static size_t chords(const curve *c, double tol)
{
    const double *p = c->p;
    double n;
    if (c->kind == CURVE_QUAD) {
        double l = hyp(p[0] - 2 * p[2] + p[4], p[1] - 2 * p[3] + p[5]);
        n = ceil(sqrt(l / (4 * tol)));
    } else if (c->kind == CURVE_CUBIC) {
        double l1 = hyp(p[0] - 2 * p[2] + p[4], p[1] - 2 * p[3] + p[5]);
        double l2 = hyp(p[2] - 2 * p[4] + p[6], p[3] - 2 * p[5] + p[7]);
        n = ceil(sqrt(0.75 * fmax(l1, l2) / tol));
    } else {
        /* the largest radius of c + u cos t + v sin t is the largest singular value of [u v];
         * a chord over dt is within R (1 - cos(dt/2)) of the arc */
        double s = p[2] * p[2] + p[3] * p[3] + p[4] * p[4] + p[5] * p[5];
        double det = p[2] * p[5] - p[3] * p[4];
        double R = sqrt((s + sqrt(fmax(0, s * s - 4 * det * det))) / 2), step;
        step = tol < R ? 2 * acos(1 - tol / R) : M_PI;
        if (step > M_PI / 4) step = M_PI / 4;
        n = ceil(fabs(p[7]) / step);
    }
    if (!(n >= 1)) n = isnan(n) ? 1 : SVG_CURVE_MAX_CHORDS;
    if (n > SVG_CURVE_MAX_CHORDS) n = SVG_CURVE_MAX_CHORDS;
    return (size_t)n;
}

static void curve_point(const curve *c, size_t i, size_t n, double *x, double *y)
{
    const double *p = c->p;
    double t = (double)i / (double)n, s = 1 - t;
    if (c->kind == CURVE_QUAD) {
        *x = s * s * p[0] + 2 * s * t * p[2] + t * t * p[4];
        *y = s * s * p[1] + 2 * s * t * p[3] + t * t * p[5];
    } else if (c->kind == CURVE_CUBIC) {
        double b0 = s * s * s, b1 = 3 * s * s * t, b2 = 3 * s * t * t, b3 = t * t * t;
        *x = b0 * p[0] + b1 * p[2] + b2 * p[4] + b3 * p[6];
        *y = b0 * p[1] + b1 * p[3] + b2 * p[5] + b3 * p[7];
    } else {
        double a = p[6] + p[7] * t, ca = cos(a), sa = sin(a);
        *x = p[0] + p[2] * ca + p[4] * sa;
        *y = p[1] + p[3] * ca + p[5] * sa;
    }
}

static void curve_ends(const curve *c, double e[4])
{
    const double *p = c->p;
    if (c->kind == CURVE_QUAD)
        e[0] = p[0], e[1] = p[1], e[2] = p[4], e[3] = p[5];
    else if (c->kind == CURVE_CUBIC)
        e[0] = p[0], e[1] = p[1], e[2] = p[6], e[3] = p[7];
    else
        e[0] = p[8], e[1] = p[9], e[2] = p[10], e[3] = p[11];
}

static void bbox_add(double bb[4], double x, double y)
{
    if (x < bb[0]) bb[0] = x;
    if (y < bb[1]) bb[1] = y;
    if (x > bb[2]) bb[2] = x;
    if (y > bb[3]) bb[3] = y;
}

static int flatten(reader *r, double tol_opt)
{
    double bb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY}, tol;
    size_t total = r->nseg;
    size_t *nch = NULL;
    if (!r->ncur) return ARR_OK;
    for (size_t i = 0; i < r->nseg; i++) {
        bbox_add(bb, r->seg[4 * i], r->seg[4 * i + 1]);
        bbox_add(bb, r->seg[4 * i + 2], r->seg[4 * i + 3]);
    }
    for (size_t i = 0; i < r->ncur; i++) {
        const curve *c = &r->cur[i];
        if (c->kind == CURVE_ARC) {
            double ex = hyp(c->p[2], c->p[4]), ey = hyp(c->p[3], c->p[5]);
            bbox_add(bb, c->p[0] - ex, c->p[1] - ey);
            bbox_add(bb, c->p[0] + ex, c->p[1] + ey);
        } else {
            for (int k = 0; k < (c->kind == CURVE_QUAD ? 3 : 4); k++)
                bbox_add(bb, c->p[2 * k], c->p[2 * k + 1]);
        }
    }
    tol = tol_opt > 0 ? tol_opt : 1e-3 * fmax(bb[2] - bb[0], bb[3] - bb[1]);
    if (!(tol > 0) || !isfinite(tol)) tol = 1;
    nch = malloc(r->ncur * sizeof *nch);
    if (!nch) return fail(r, ARR_ENOMEM, "out of memory for %zu curves", r->ncur);
    for (size_t i = 0; i < r->ncur; i++) {
        nch[i] = chords(&r->cur[i], tol);
        total += nch[i];
    }
    if (total > r->max_segs) {
        free(nch);
        return fail(r, ARR_ELIMIT,
                    "more than %zu segments once curves are flattened to tolerance %g (limit "
                    "max_segments)",
                    r->max_segs, tol);
    }
    for (size_t i = 0; i < r->ncur; i++) {
        const curve *c = &r->cur[i];
        double e[4], px, py;
        curve_ends(c, e);
        px = e[0], py = e[1];
        for (size_t k = 1; k <= nch[i]; k++) {
            double x, y;
            int rc;
            if (k == nch[i])
                x = e[2], y = e[3];
            else
                curve_point(c, k, nch[i], &x, &y);
            rc = push_seg(r, px, py, x, y);
            if (rc) {
                free(nch);
                return rc;
            }
            px = x, py = y;
        }
    }
    free(nch);
    return ARR_OK;
}

/* ---- parsing ------------------------------------------------------------------------------- */

typedef struct parse_state {
    size_t elements, depth, max_elements, max_depth;
    int limit;                  /* ARR_ELIMIT once a limit stopped the parser */
    int have_fatal, have_error; /* first errors seen, by level */
    int fatal_code, fatal_line, fatal_col;
    char fatal_msg[160];
    int error_line, error_col;
    char error_msg[160];
    int root_line, root_col; /* where the root element's start tag ends */
    char limit_msg[160];
} parse_state;

static void copy_msg(char *dst, size_t len, const char *src)
{
    size_t n = src ? strlen(src) : 0;
    while (n && (src[n - 1] == '\n' || src[n - 1] == ' ')) n--;
    if (n >= len) n = len - 1;
    if (n) memcpy(dst, src, n);
    dst[n] = 0;
}

static void on_error(void *data, xmlErrorPtr e)
{
    xmlParserCtxtPtr ctxt = data;
    parse_state *st = ctxt ? ctxt->_private : NULL;
    if (!st || !e || e->level < XML_ERR_ERROR) return;
    if (e->level == XML_ERR_FATAL) {
        if (!st->have_fatal) {
            st->have_fatal = 1;
            st->fatal_code = e->code;
            copy_msg(st->fatal_msg, sizeof st->fatal_msg, e->message);
            st->fatal_line = e->line;
            st->fatal_col = e->int2;
        } else if (e->code == st->fatal_code) {
            /* the same error reported again on the way out of nested entity inputs: the last
             * report has the position in the document */
            char m[160];
            copy_msg(m, sizeof m, e->message);
            if (strcmp(m, st->fatal_msg) == 0) st->fatal_line = e->line, st->fatal_col = e->int2;
        }
    } else if (!st->have_error) {
        st->have_error = 1;
        copy_msg(st->error_msg, sizeof st->error_msg, e->message);
        st->error_line = e->line;
        st->error_col = e->int2;
    }
}

static void on_start(void *ctx, const xmlChar *localname, const xmlChar *prefix, const xmlChar *URI,
                     int nb_namespaces, const xmlChar **namespaces, int nb_attributes,
                     int nb_defaulted, const xmlChar **attributes)
{
    xmlParserCtxtPtr ctxt = ctx;
    parse_state *st = ctxt->_private;
    xmlSAX2StartElementNs(ctx, localname, prefix, URI, nb_namespaces, namespaces, nb_attributes,
                          nb_defaulted, attributes);
    if (!st) return; /* a context libxml2 made without our state: cannot happen in 2.9.14 */
    st->elements++;
    st->depth++;
    if (st->elements == 1) {
        st->root_line = xmlSAX2GetLineNumber(ctx);
        st->root_col = xmlSAX2GetColumnNumber(ctx);
    }
    if (st->limit) return;
    if (st->elements > st->max_elements) {
        snprintf(st->limit_msg, sizeof st->limit_msg,
                 "line %d, column %d: more than %zu elements (limit max_elements)",
                 xmlSAX2GetLineNumber(ctx), xmlSAX2GetColumnNumber(ctx), st->max_elements);
        st->limit = ARR_ELIMIT;
        xmlStopParser(ctxt);
    } else if (st->depth > st->max_depth) {
        snprintf(st->limit_msg, sizeof st->limit_msg,
                 "line %d, column %d: elements nested deeper than %zu (limit max_depth)",
                 xmlSAX2GetLineNumber(ctx), xmlSAX2GetColumnNumber(ctx), st->max_depth);
        st->limit = ARR_ELIMIT;
        xmlStopParser(ctxt);
    }
}

static void on_end(void *ctx, const xmlChar *localname, const xmlChar *prefix, const xmlChar *URI)
{
    xmlParserCtxtPtr ctxt = ctx;
    parse_state *st = ctxt->_private;
    if (st && st->depth) st->depth--;
    xmlSAX2EndElementNs(ctx, localname, prefix, URI);
}

/* libxml2's own limits (without XML_PARSE_HUGE), from its messages: NULL when m is none. */
static const char *libxml2_limit(const char *m)
{
    if (strstr(m, "Excessive depth")) return "libxml2's limit: 256 levels of elements";
    if (strstr(m, "Huge input lookup"))
        return "libxml2's limit: 10000000 bytes of lookahead, reached within very long lines";
    if (strstr(m, "too long") || strstr(m, "too big") || strstr(m, "too large"))
        return "libxml2's limit: 10000000 bytes per attribute value, text or name";
    return NULL;
}

typedef struct entity_scan {
    const char *nested; /* the entity (first by name) whose value refers to another, or NULL */
} entity_scan;

static void scan_entity(void *payload, void *data, const xmlChar *name)
{
    xmlEntityPtr e = payload;
    entity_scan *es = data;
    (void)name;
    if (!e || e->etype != XML_INTERNAL_GENERAL_ENTITY || !e->content || !e->name) return;
    if (es->nested && strcmp((const char *)e->name, es->nested) >= 0) return;
    for (const char *p = (const char *)e->content; (p = strchr(p, '&')); p++)
        if (p[1] != '#') {
            es->nested = (const char *)e->name;
            return;
        }
}

/* Parses text into *doc.  Returns ARR_OK or an error with the message in r. */
static int parse(reader *r, const char *text, size_t len, xmlDocPtr *doc)
{
    parse_state st = {.max_elements = r->max_elements, .max_depth = r->max_depth};
    xmlParserCtxtPtr ctxt;
    int opts = XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING | XML_PARSE_BIG_LINES |
               XML_PARSE_NOBLANKS | XML_PARSE_COMPACT,
        rc = ARR_OK;
    *doc = NULL;
    if (len > SVG_MAX_BYTES)
        return fail(r, ARR_ELIMIT, "the document has %zu bytes, more than %u (limit SVG_MAX_BYTES)",
                    len, SVG_MAX_BYTES);
    ctxt = xmlNewParserCtxt();
    if (!ctxt) return fail(r, ARR_ENOMEM, "out of memory for the XML parser");
    ctxt->_private = &st;
    ctxt->sax->serror = on_error;
    ctxt->sax->startElementNs = on_start;
    ctxt->sax->endElementNs = on_end;
    *doc = xmlCtxtReadMemory(ctxt, text, (int)len, NULL, NULL, opts);
    if (st.limit) {
        rc = fail(r, ARR_ELIMIT, "%s", st.limit_msg);
    } else if (!*doc || !ctxt->wellFormed) {
        const char *m = st.have_fatal ? st.fatal_msg : st.have_error ? st.error_msg : "";
        int line = st.have_fatal ? st.fatal_line : st.error_line;
        int col = st.have_fatal ? st.fatal_col : st.error_col;
        char lm[160];
        if (!*m && ctxt->lastError.message) {
            copy_msg(lm, sizeof lm, ctxt->lastError.message);
            m = lm;
            line = ctxt->lastError.line;
            col = ctxt->lastError.int2;
        }
        if (st.have_fatal && st.fatal_code == XML_ERR_NO_MEMORY)
            rc = fail(r, ARR_ENOMEM, "out of memory while parsing the XML");
        else if (st.have_fatal && st.fatal_code == XML_ERR_ENTITY_LOOP)
            rc = fail(r, ARR_EINVAL,
                      "line %d, column %d: %s (entity expansion refused: billion laughs guard)",
                      line, col, m);
        else if (libxml2_limit(m))
            rc = fail(r, ARR_ELIMIT, "line %d, column %d: %s (%s)", line, col, m, libxml2_limit(m));
        else
            rc = fail(r, ARR_EINVAL, "line %d, column %d: %s", line > 0 ? line : 1,
                      col > 0 ? col : 1, *m ? m : "malformed XML");
    } else {
        xmlNodePtr root = xmlDocGetRootElement(*doc);
        if (!root) {
            rc = fail(r, ARR_EINVAL, "line 1, column 1: no root element");
        } else if (strcmp((const char *)root->name, "svg") != 0) {
            rc = fail(r, ARR_EINVAL, "line %d, column %d: the root element is <%.40s>, not <svg>",
                      st.root_line, st.root_col, (const char *)root->name);
        } else if (root->ns && root->ns->href && !href_is_svg(*doc, root->ns->href)) {
            rc = fail(r, ARR_EINVAL,
                      "line %d, column %d: the root <svg> is in namespace \"%.60s\", not SVG's "
                      "(" SVG_NS ")",
                      st.root_line, st.root_col, (const char *)root->ns->href);
        } else if ((*doc)->intSubset && (*doc)->intSubset->entities) {
            entity_scan es = {0};
            xmlHashScan((*doc)->intSubset->entities, scan_entity, &es);
            if (es.nested)
                rc = fail(r, ARR_EINVAL,
                          "entity \"%.40s\" refers to other entities: nested entities are refused "
                          "(billion laughs guard)",
                          es.nested);
        }
    }
    if (rc && *doc) {
        xmlFreeDoc(*doc);
        *doc = NULL;
    }
    xmlFreeParserCtxt(ctxt);
    return rc;
}

/* ---- entry points -------------------------------------------------------------------------- */

static size_t or_default(size_t v, size_t dflt)
{
    return v ? v : dflt;
}

int svg_read(const char *text, size_t len, const svg_opts *o, svg_result *out, char *err,
             size_t errlen)
{
    static const svg_opts no_opts;
    reader r = {0};
    xmlDocPtr doc = NULL;
    xmlNodePtr root;
    int rc;
    vpt vp = {NAN, NAN};
    if (!o) o = &no_opts;
    memset(out, 0, sizeof *out);
    out->transform[0] = out->transform[3] = 1;
    if (err && errlen) err[0] = 0;
    r.err = err;
    r.errlen = errlen;
    r.out = out;
    r.o = o;
    r.max_elements = or_default(o->max_elements, SVG_MAX_ELEMENTS);
    r.max_cmds = or_default(o->max_path_commands, SVG_MAX_PATH_COMMANDS);
    r.max_segs = or_default(o->max_segments, SVG_MAX_SEGMENTS);
    r.max_depth = or_default(o->max_depth, SVG_MAX_DEPTH);
    if (r.max_depth > SVG_DEPTH_CAP) r.max_depth = SVG_DEPTH_CAP;
    r.rect_diagonal = o->rect_diagonal;
    r.entity_budget = SVG_MAX_BYTES;
    if (!(o->flatten_tolerance >= 0) || !isfinite(o->flatten_tolerance))
        return fail(&r, ARR_EINVAL, "flatten_tolerance: expected a finite number >= 0");
    if (!text && len) return fail(&r, ARR_EINVAL, "no text");
    pthread_once(&xml_once, xml_init);
    r.cloc = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    if (!r.cloc) return fail(&r, ARR_ENOMEM, "out of memory for a locale");
    rc = parse(&r, text ? text : "", len, &doc);
    if (rc) goto fail;
    if (o->progress) o->progress(o->udata, 0.3);
    r.doc = doc;
    root = xmlDocGetRootElement(doc);
    r.root_ns = root->ns ? root->ns->href : NULL;
    rc = index_ids(&r, root);
    if (rc) goto fail;
    {
        /* the root: its viewBox (or absolute width/height) sizes percentages; its own
         * coordinates are kept, so no viewport map */
        aval a;
        double vb[4], w, h;
        int fatal = 0;
        mat m;
        rc = attr_get(&r, root, "viewBox", &a);
        if (rc) goto fail;
        if (parse_viewbox(&r, a.s, vb) > 0 && vb[2] > 0 && vb[3] > 0) {
            vp = (vpt){vb[2], vb[3]};
        } else {
            aval b;
            rc = attr_get(&r, root, "width", &b);
            if (!rc && b.s && parse_length(&r, b.s, &w) == LEN_OK) vp.w = w;
            aval_free(&b);
            if (!rc) rc = attr_get(&r, root, "height", &b);
            if (!rc && b.s && parse_length(&r, b.s, &h) == LEN_OK) vp.h = h;
            aval_free(&b);
        }
        aval_free(&a);
        if (rc) goto fail;
        r.visited = 1;
        if (hidden(&r, root, &fatal)) {
            rc = fatal;
        } else if (element_transform(&r, root, &IDENTITY, &m, &fatal)) {
            rc = walk_children(&r, root, &m, vp, 1);
        }
        if (!rc) rc = fatal;
        if (rc) goto fail;
    }
    if (o->progress) o->progress(o->udata, 0.8);
    rc = flatten(&r, o->flatten_tolerance);
    if (rc) goto fail;
    /* bbox in root user space, then the output map */
    if (r.nseg) {
        double bb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < r.nseg; i++) {
            bbox_add(bb, r.seg[4 * i], r.seg[4 * i + 1]);
            bbox_add(bb, r.seg[4 * i + 2], r.seg[4 * i + 3]);
        }
        memcpy(out->bbox, bb, sizeof bb);
    }
    if (o->normalize) {
        double x0 = out->bbox[0], y1 = out->bbox[3];
        double s = fmax(out->bbox[2] - out->bbox[0], out->bbox[3] - out->bbox[1]);
        if (!(s > 0) || !isfinite(s)) s = 1;
        for (size_t i = 0; i < r.nseg; i++) {
            double *p = r.seg + 4 * i;
            p[0] = (p[0] - x0) / s, p[1] = (y1 - p[1]) / s;
            p[2] = (p[2] - x0) / s, p[3] = (y1 - p[3]) / s;
        }
        out->transform[0] = 1 / s, out->transform[1] = 0, out->transform[2] = 0;
        out->transform[3] = -1 / s, out->transform[4] = -x0 / s, out->transform[5] = y1 / s;
    } else if (o->y_up) {
        for (size_t i = 0; i < r.nseg; i++) r.seg[4 * i + 1] *= -1, r.seg[4 * i + 3] *= -1;
        out->transform[3] = -1;
    }
    if (r.warnings_total > SVG_MAX_WARNINGS)
        snprintf(out->warning[SVG_MAX_WARNINGS - 1], WMAX, "... and %zu more warnings (%zu in all)",
                 r.warnings_total - (SVG_MAX_WARNINGS - 1), r.warnings_total);
    out->seg = r.seg;
    out->n = r.nseg;
    r.seg = NULL;
    rc = ARR_OK;
fail:
    if (rc) {
        memset(out, 0, sizeof *out);
        free(r.seg);
    }
    free(r.cur);
    free(r.ids);
    if (doc) xmlFreeDoc(doc);
    freelocale(r.cloc);
    return rc;
}

void svg_result_free(svg_result *r)
{
    if (!r) return;
    free(r->seg);
    memset(r, 0, sizeof *r);
}
