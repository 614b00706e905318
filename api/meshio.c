/* meshio.c — STL, PLY and 3MF read into solids, and the "solids" request of mesh files
 * (meshio.h says what each format gives and the limits).
 *
 * Every reader fills an mbuild: vertices and cycles (one cycle a face, no holes: none of these
 * formats has holes) grown as they come, never allocated from a count the file declares (a
 * count may lie), then handed over as a solid.  STL welds its vertices through an open
 * addressing table keyed by the three coordinates' bits; PLY and 3MF index theirs already.
 * Indices are checked against the vertex count before a solid leaves here, so a solid read is
 * well formed (every index < nv, every cycle of 3 or more entries).  The growable arrays are
 * mem_grow's (core/mem.h) and the messages util_seterr's (core/util.h); PLY is read in stages:
 * ply_header (a function per kind of line), then per element ply_columns and per item ply_item
 * (ply_list for a list property).
 *
 * Threads: reentrant, no globals (libxml2's reader with its errors sent to a handler of the
 * reader's own, so nothing is printed).  Ownership: meshio.h. */
#include "api/meshio.h"

#include "api/api_int.h"
#include "core/fastfloat.h"
#include "core/util.h"

#include <jansson.h>
#include <libxml/xmlreader.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <zip.h>

/* ---- formats by name and media type ---------------------------------------------------------- */

static const struct {
    const char *name, *ext;
    mesh_format f;
} formats[] = {{"obj", ".obj", MESH_OBJ},
               {"off", ".off", MESH_OFF},
               {"stl", ".stl", MESH_STL},
               {"ply", ".ply", MESH_PLY},
               {"3mf", ".3mf", MESH_3MF}};

static const struct {
    const char *media;
    mesh_format f;
} medias[] = {{"model/obj", MESH_OBJ},
              {"model/vnd.off", MESH_OFF},
              {"model/x-off", MESH_OFF},
              {"model/stl", MESH_STL},
              {"model/x.stl-binary", MESH_STL},
              {"model/x.stl-ascii", MESH_STL},
              {"application/sla", MESH_STL},
              {"application/vnd.ms-pki.stl", MESH_STL},
              {"model/vnd.ply", MESH_PLY},
              {"model/x-ply", MESH_PLY},
              {"application/ply", MESH_PLY},
              {"model/3mf", MESH_3MF},
              {"application/vnd.ms-3mfdocument", MESH_3MF}};

mesh_format mesh_format_of_name(const char *name)
{
    const char *dot = name ? strrchr(name, '.') : NULL;
    if (!dot || strchr(dot, '/')) return MESH_NONE;
    for (size_t i = 0; i < sizeof formats / sizeof *formats; i++)
        if (!strcasecmp(dot, formats[i].ext)) return formats[i].f;
    return MESH_NONE;
}

mesh_format mesh_format_of_media(const char *media)
{
    if (!media) return MESH_NONE;
    while (*media == ' ' || *media == '\t') media++;
    size_t n = strcspn(media, "; \t");
    for (size_t i = 0; i < sizeof medias / sizeof *medias; i++)
        if (strlen(medias[i].media) == n && !strncasecmp(media, medias[i].media, n))
            return medias[i].f;
    return MESH_NONE;
}

const char *mesh_format_name(mesh_format f)
{
    for (size_t i = 0; i < sizeof formats / sizeof *formats; i++)
        if (formats[i].f == f) return formats[i].name;
    return "?";
}

/* ---- the solid being built ------------------------------------------------------------------- */

typedef struct mbuild {
    double *V; /* 3 per vertex */
    size_t nv, vcap;
    uint32_t *cyc; /* indices, cycle after cycle */
    size_t ni, icap;
    uint32_t *cyc_off; /* starts of the cycles; ncyc + 1 once finished */
    size_t ncyc, ccap;
    /* welding (STL): slot -> vertex + 1, 0 empty; mask + 1 slots */
    uint32_t *slot;
    size_t mask;
} mbuild;

static void mb_free(mbuild *b)
{
    free(b->V);
    free(b->cyc);
    free(b->cyc_off);
    free(b->slot);
    *b = (mbuild){0};
}

static int mb_vertex(mbuild *b, const double x[3])
{
    if (b->nv >= MESH_MAX_VERTICES) return -2;
    if (mem_grow(&b->V, &b->vcap, b->nv + 1, 3 * sizeof(double))) return -1;
    memcpy(b->V + 3 * b->nv, x, 3 * sizeof(double));
    b->nv++;
    return 0;
}

/* A new cycle (one face); then mb_index() its entries. */
static int mb_face(mbuild *b)
{
    if (b->ncyc >= MESH_MAX_TRIANGLES) return -2;
    if (mem_grow(&b->cyc_off, &b->ccap, b->ncyc + 2, sizeof(uint32_t))) return -1;
    if (b->ni > UINT32_MAX - MESH_PLY_POLYGON) return -2;
    b->cyc_off[b->ncyc++] = (uint32_t)b->ni;
    return 0;
}

static int mb_index(mbuild *b, uint32_t v)
{
    if (mem_grow(&b->cyc, &b->icap, b->ni + 1, sizeof(uint32_t))) return -1;
    b->cyc[b->ni++] = v;
    return 0;
}

/* Hands the solid over (b then empty); every index must be < nv (the caller checked). */
static int mb_finish(mbuild *b, solid *out)
{
    uint32_t *fo = malloc((b->ncyc + 1) * sizeof *fo);
    if (!fo || mem_grow(&b->cyc_off, &b->ccap, b->ncyc + 1, sizeof(uint32_t))) {
        free(fo);
        return -1;
    }
    for (size_t f = 0; f <= b->ncyc; f++) fo[f] = (uint32_t)f;
    b->cyc_off[b->ncyc] = (uint32_t)b->ni;
    if (!b->cyc && !(b->cyc = malloc(sizeof *b->cyc))) {
        free(fo);
        return -1;
    }
    *out = (solid){b->nv, b->V, b->ncyc, fo, b->ncyc, b->cyc_off, b->cyc};
    free(b->slot);
    *b = (mbuild){0};
    return 0;
}

static uint64_t bits(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static uint64_t point_hash(const double x[3])
{
    uint64_t h = bits(x[0]) * 0x9E3779B97F4A7C15ull;
    h = (h ^ (h >> 29) ^ bits(x[1])) * 0xBF58476D1CE4E5B9ull;
    h = (h ^ (h >> 31) ^ bits(x[2])) * 0x94D049BB133111EBull;
    return h ^ (h >> 32);
}

/* The vertex at x (finite; -0 is 0), made when it is new: its index in *v. */
static int mb_weld(mbuild *b, const double x[3], uint32_t *v)
{
    double p[3] = {x[0] + 0.0, x[1] + 0.0, x[2] + 0.0};
    if (2 * (b->nv + 1) > b->mask) { /* load at most 1/2 */
        size_t n = b->mask ? 2 * (b->mask + 1) : 1024;
        uint32_t *s = calloc(n, sizeof *s);
        if (!s) return -1;
        for (size_t i = 0; i < b->nv; i++) {
            size_t k = point_hash(b->V + 3 * i) & (n - 1);
            while (s[k]) k = (k + 1) & (n - 1);
            s[k] = (uint32_t)i + 1;
        }
        free(b->slot);
        b->slot = s;
        b->mask = n - 1;
    }
    size_t k = point_hash(p) & b->mask;
    for (; b->slot[k]; k = (k + 1) & b->mask) {
        const double *q = b->V + 3 * (size_t)(b->slot[k] - 1);
        if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2]) {
            *v = b->slot[k] - 1;
            return 0;
        }
    }
    int rc = mb_vertex(b, p);
    if (rc) return rc;
    b->slot[k] = (uint32_t)b->nv;
    *v = (uint32_t)(b->nv - 1);
    return 0;
}

static const char *limit_msg(int rc)
{
    return rc == -2 ? "more than the vertices or faces a file may have (2^26)" : "out of memory";
}

/* ---- STL ------------------------------------------------------------------------------------- */

typedef struct tok {
    const char *p, *end;
    size_t line;
    const char *t; /* the token read */
    size_t n;
} tok;

/* The next whitespace-separated token (n 0 at the end). */
static void next_token(tok *k)
{
    while (k->p < k->end && (*k->p == ' ' || *k->p == '\t' || *k->p == '\r' || *k->p == '\n' ||
                             *k->p == '\f' || *k->p == '\v')) {
        if (*k->p == '\n') k->line++;
        k->p++;
    }
    k->t = k->p;
    while (k->p < k->end && !(*k->p == ' ' || *k->p == '\t' || *k->p == '\r' || *k->p == '\n' ||
                              *k->p == '\f' || *k->p == '\v'))
        k->p++;
    k->n = (size_t)(k->p - k->t);
}

static int token_is(const tok *k, const char *w)
{
    return k->n == strlen(w) && !strncasecmp(k->t, w, k->n);
}

static void skip_line(tok *k)
{
    while (k->p < k->end && *k->p != '\n') k->p++;
}

/* "got \"word\"" or "got the end of the file", for messages. */
static const char *got(const tok *k, char *buf, size_t n)
{
    if (!k->n) return "the end of the file";
    int m = k->n > 24 ? 24 : (int)k->n;
    int printable = 1;
    for (int i = 0; i < m; i++)
        if ((unsigned char)k->t[i] < 0x20 || (unsigned char)k->t[i] >= 0x7f) printable = 0;
    if (!printable) return "bytes that are not text";
    snprintf(buf, n, "\"%.*s%s\"", m, k->t, k->n > 24 ? "..." : "");
    return buf;
}

static int expect_word(tok *k, const char *w, char *err, size_t errlen)
{
    char g[40];
    next_token(k);
    if (token_is(k, w)) return 0;
    return util_seterr(err, errlen, -1, "line %zu: expected \"%s\", got %s", k->line, w,
                       got(k, g, sizeof g));
}

static int read_number(tok *k, double *x, char *err, size_t errlen)
{
    char g[40];
    next_token(k);
    if (k->n && ff_parse(k->t, k->t + k->n, x) == 0) return 0;
    return util_seterr(err, errlen, -1, "line %zu: expected a finite number, got %s", k->line,
                       got(k, g, sizeof g));
}

static int stl_ascii(const char *data, size_t len, mbuild *b, char *err, size_t errlen)
{
    tok k = {data, data + len, 1, NULL, 0};
    char g[40];
    size_t facet = 0;
    int rc;
    if (expect_word(&k, "solid", err, errlen)) return -1;
    skip_line(&k);
    for (;;) {
        next_token(&k);
        if (token_is(&k, "endsolid")) {
            skip_line(&k);
            next_token(&k);
            if (!k.n) return 0;
            if (!token_is(&k, "solid"))
                return util_seterr(err, errlen, -1,
                                   "line %zu: expected \"solid\" or the end, got %s", k.line,
                                   got(&k, g, sizeof g));
            skip_line(&k);
            continue;
        }
        if (!token_is(&k, "facet"))
            return util_seterr(err, errlen, -1,
                               "line %zu: expected \"facet\" or \"endsolid\", got %s", k.line,
                               got(&k, g, sizeof g));
        double x[3];
        if (expect_word(&k, "normal", err, errlen)) return -1;
        for (int a = 0; a < 3; a++)
            if (read_number(&k, &x[a], err, errlen)) return -1;
        if (expect_word(&k, "outer", err, errlen) || expect_word(&k, "loop", err, errlen))
            return -1;
        if ((rc = mb_face(b)))
            return util_seterr(err, errlen, -1, "line %zu: %s", k.line, limit_msg(rc));
        int nvert = 0;
        for (;;) {
            next_token(&k);
            if (token_is(&k, "endloop")) break;
            if (!token_is(&k, "vertex"))
                return util_seterr(err, errlen, -1,
                                   "line %zu: expected \"vertex\" or \"endloop\", got %s", k.line,
                                   got(&k, g, sizeof g));
            if (nvert >= MESH_PLY_POLYGON)
                return util_seterr(err, errlen, -1, "line %zu: facet %zu: more than %d vertices",
                                   k.line, facet, MESH_PLY_POLYGON);
            for (int a = 0; a < 3; a++)
                if (read_number(&k, &x[a], err, errlen)) return -1;
            uint32_t v;
            if ((rc = mb_weld(b, x, &v)) || (rc = mb_index(b, v)))
                return util_seterr(err, errlen, -1, "line %zu: %s", k.line, limit_msg(rc));
            nvert++;
        }
        if (nvert < 3)
            return util_seterr(err, errlen, -1, "line %zu: facet %zu: %d vertices (3 needed)",
                               k.line, facet, nvert);
        if (expect_word(&k, "endfacet", err, errlen)) return -1;
        facet++;
    }
}

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static int stl_binary(const char *data, size_t len, mbuild *b, char *err, size_t errlen)
{
    const unsigned char *p = (const unsigned char *)data;
    size_t n = le32(p + 80);
    int rc;
    if (n > MESH_MAX_TRIANGLES)
        return util_seterr(err, errlen, -1, "%zu triangles: more than %u", n, MESH_MAX_TRIANGLES);
    (void)len;
    for (size_t t = 0; t < n; t++) {
        const unsigned char *q = p + 84 + 50 * t + 12;
        if ((rc = mb_face(b)))
            return util_seterr(err, errlen, -1, "triangle %zu: %s", t, limit_msg(rc));
        for (int c = 0; c < 3; c++) {
            double x[3];
            for (int a = 0; a < 3; a++) {
                uint32_t u = le32(q + 12 * c + 4 * a);
                float f;
                memcpy(&f, &u, sizeof f);
                x[a] = f;
                if (!isfinite(x[a]))
                    return util_seterr(err, errlen, -1,
                                       "triangle %zu: vertex %d: coordinate not finite", t, c);
            }
            uint32_t v;
            if ((rc = mb_weld(b, x, &v)) || (rc = mb_index(b, v)))
                return util_seterr(err, errlen, -1, "triangle %zu: %s", t, limit_msg(rc));
        }
    }
    return 0;
}

int mesh_read_stl(const char *data, size_t len, solid *out, char *err, size_t errlen)
{
    if (errlen) err[0] = 0;
    mbuild b = {0};
    size_t i = 0;
    char aerr[160] = "";
    *out = (solid){0};
    while (i < len && (data[i] == ' ' || data[i] == '\t' || data[i] == '\r' || data[i] == '\n'))
        i++;
    int ascii = len - i >= 5 && !strncasecmp(data + i, "solid", 5);
    int sized = len >= 84 && (uint64_t)le32((const unsigned char *)data + 80) * 50 + 84 == len;
    if (ascii) {
        if (stl_ascii(data, len, &b, aerr, sizeof aerr) == 0) goto done;
        mb_free(&b);
        if (!sized) return util_seterr(err, errlen, -1, "%s", aerr);
    }
    if (!sized) {
        if (len < 84)
            return util_seterr(
                err, errlen, -1,
                "not an STL file: %zu bytes, neither ASCII (\"solid\" ...) nor binary (84 "
                "bytes of header and count at least)",
                len);
        return util_seterr(
            err, errlen, -1,
            "not an STL file: binary STL of %lu triangles is %llu bytes, this is %zu "
            "(and it does not start with \"solid\")",
            (unsigned long)le32((const unsigned char *)data + 80),
            (unsigned long long)le32((const unsigned char *)data + 80) * 50 + 84, len);
    }
    if (stl_binary(data, len, &b, err, errlen)) {
        mb_free(&b);
        return -1;
    }
done:
    if (mb_finish(&b, out)) {
        mb_free(&b);
        return util_seterr(err, errlen, -1, "out of memory");
    }
    return 0;
}

/* ---- PLY ------------------------------------------------------------------------------------- */

enum { PLY_I8, PLY_U8, PLY_I16, PLY_U16, PLY_I32, PLY_U32, PLY_F32, PLY_F64 };
static const struct {
    const char *a, *b;
    int size;
} ply_types[] = {{"char", "int8", 1},     {"uchar", "uint8", 1},   {"short", "int16", 2},
                 {"ushort", "uint16", 2}, {"int", "int32", 4},     {"uint", "uint32", 4},
                 {"float", "float32", 4}, {"double", "float64", 8}};

typedef struct ply_prop {
    int type;  /* PLY_*: the value, or the list's items */
    int count; /* -1: a scalar; else the list's count type */
    char name[32];
} ply_prop;

typedef struct ply_elem {
    char name[32];
    uint64_t count;
    size_t np;
    ply_prop p[MESH_PLY_ELEMENTS];
} ply_elem;

typedef struct ply {
    int fmt; /* 0 ascii, 1 little-endian, 2 big-endian */
    size_t ne;
    ply_elem e[MESH_PLY_ELEMENTS];
    const unsigned char *p, *end; /* the data */
    tok k;                        /* ascii */
    size_t hlines;                /* lines of the header */
} ply;

static int ply_type(const char *w, size_t n)
{
    for (int t = 0; t < 8; t++)
        if ((strlen(ply_types[t].a) == n && !strncmp(w, ply_types[t].a, n)) ||
            (strlen(ply_types[t].b) == n && !strncmp(w, ply_types[t].b, n)))
            return t;
    return -1;
}

/* The next word of the header line [*p, end) (n 0: none). */
static const char *word(const char **p, const char *end, size_t *n)
{
    while (*p < end && (**p == ' ' || **p == '\t' || **p == '\r')) (*p)++;
    const char *w = *p;
    while (*p < end && !(**p == ' ' || **p == '\t' || **p == '\r')) (*p)++;
    *n = (size_t)(*p - w);
    return w;
}

/* The rest [*p, nl) of header line `line` after "format": ascii, binary_little_endian or
 * binary_big_endian, then 1.0, into h->fmt; 0 or -1 with the message. */
static int ply_format_line(ply *h, const char **p, const char *nl, size_t line, char *err,
                           size_t errlen)
{
    size_t n;
    const char *f = word(p, nl, &n);
    if (n == 5 && !strncmp(f, "ascii", 5))
        h->fmt = 0;
    else if (n == 20 && !strncmp(f, "binary_little_endian", 20))
        h->fmt = 1;
    else if (n == 17 && !strncmp(f, "binary_big_endian", 17))
        h->fmt = 2;
    else
        return util_seterr(err, errlen, -1,
                           "line %zu: format: expected ascii, binary_little_endian or "
                           "binary_big_endian",
                           line);
    f = word(p, nl, &n);
    if (n != 3 || strncmp(f, "1.0", 3))
        return util_seterr(err, errlen, -1, "line %zu: format: version 1.0 expected", line);
    return 0;
}

/* The rest of an "element" line: a name and a decimal count, as a new element of h. */
static int ply_element_line(ply *h, const char **p, const char *nl, size_t line, char *err,
                            size_t errlen)
{
    size_t n;
    uint64_t v = 0;
    if (h->ne >= MESH_PLY_ELEMENTS)
        return util_seterr(err, errlen, -1, "line %zu: more than %d elements", line,
                           MESH_PLY_ELEMENTS);
    ply_elem *e = &h->e[h->ne++];
    const char *nm = word(p, nl, &n);
    if (!n || n >= sizeof e->name)
        return util_seterr(err, errlen, -1,
                           "line %zu: element: expected a name (of at most %zu "
                           "bytes) and a count",
                           line, sizeof e->name - 1);
    memcpy(e->name, nm, n);
    e->name[n] = 0;
    const char *c = word(p, nl, &n);
    if (!n)
        return util_seterr(err, errlen, -1, "line %zu: element %s: expected a count", line,
                           e->name);
    for (size_t i = 0; i < n; i++) {
        if (c[i] < '0' || c[i] > '9' || v > UINT64_MAX / 20)
            return util_seterr(err, errlen, -1, "line %zu: element %s: expected a count", line,
                               e->name);
        v = 10 * v + (uint64_t)(c[i] - '0');
    }
    e->count = v;
    return 0;
}

/* The rest of a "property" line: a type (or "list", a count type and an item type) and a name,
 * as a new property of the last element. */
static int ply_property_line(ply *h, const char **p, const char *nl, size_t line, char *err,
                             size_t errlen)
{
    size_t n;
    if (!h->ne)
        return util_seterr(err, errlen, -1, "line %zu: a property before any element", line);
    ply_elem *e = &h->e[h->ne - 1];
    if (e->np >= MESH_PLY_ELEMENTS)
        return util_seterr(err, errlen, -1, "line %zu: element %s: more than %d properties", line,
                           e->name, MESH_PLY_ELEMENTS);
    ply_prop *q = &e->p[e->np++];
    const char *t = word(p, nl, &n);
    q->count = -1;
    if (n == 4 && !strncmp(t, "list", 4)) {
        t = word(p, nl, &n);
        if ((q->count = ply_type(t, n)) < 0 || q->count >= PLY_F32)
            return util_seterr(err, errlen, -1,
                               "line %zu: property list: expected an integer count "
                               "type",
                               line);
        t = word(p, nl, &n);
    }
    if ((q->type = ply_type(t, n)) < 0)
        return util_seterr(err, errlen, -1, "line %zu: property: unknown type \"%.*s\"", line,
                           (int)(n > 16 ? 16 : n), t);
    const char *nm = word(p, nl, &n);
    if (!n || n >= sizeof q->name)
        return util_seterr(err, errlen, -1, "line %zu: property: expected a name", line);
    memcpy(q->name, nm, n);
    q->name[n] = 0;
    return 0;
}

/* The header of data[0..len) (at most MESH_PLY_HEADER bytes, up to its end_header line) into
 * *h, h->p at the data after it; 0 or -1 with the message naming the line. */
static int ply_header(ply *h, const char *data, size_t len, char *err, size_t errlen)
{
    const char *p = data, *end = data + (len < MESH_PLY_HEADER ? len : MESH_PLY_HEADER);
    size_t line = 0;
    int have_fmt = 0, rc = 0;
    for (;;) {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        line++;
        if (!nl)
            return util_seterr(err, errlen, -1,
                               len > MESH_PLY_HEADER ? "header: longer than %d bytes"
                                                     : "header: no end_header line",
                               MESH_PLY_HEADER);
        size_t n;
        const char *w = word(&p, nl, &n);
        if (line == 1) {
            size_t more;
            if (n != 3 || strncmp(w, "ply", 3) || (word(&p, nl, &more), more))
                return util_seterr(err, errlen, -1, "line 1: expected \"ply\"");
        } else if (n == 6 && !strncmp(w, "format", 6)) {
            rc = ply_format_line(h, &p, nl, line, err, errlen);
            have_fmt = 1;
        } else if ((n == 7 && !strncmp(w, "comment", 7)) ||
                   (n == 8 && !strncmp(w, "obj_info", 8)) || n == 0) {
            /* nothing */
        } else if (n == 7 && !strncmp(w, "element", 7)) {
            rc = ply_element_line(h, &p, nl, line, err, errlen);
        } else if (n == 8 && !strncmp(w, "property", 8)) {
            rc = ply_property_line(h, &p, nl, line, err, errlen);
        } else if (n == 10 && !strncmp(w, "end_header", 10)) {
            if (!have_fmt) return util_seterr(err, errlen, -1, "header: no format line");
            h->p = (const unsigned char *)nl + 1;
            h->hlines = line;
            h->end = (const unsigned char *)data + len;
            return 0;
        } else {
            return util_seterr(err, errlen, -1, "line %zu: unknown header line \"%.*s\"", line,
                               (int)(n > 16 ? 16 : n), w);
        }
        if (rc) return rc;
        p = nl + 1;
    }
}

/* One value of type t, as a double (exact for every integer type). */
static int ply_value(ply *h, int t, double *x)
{
    if (h->fmt == 0) {
        next_token(&h->k);
        if (!h->k.n) return -2;
        if (ff_parse(h->k.t, h->k.t + h->k.n, x)) return -1;
        if (t < PLY_F32 && *x != floor(*x)) return -1;
        return 0;
    }
    int size = ply_types[t].size;
    unsigned char b[8];
    if (h->end - h->p < size) return -2;
    for (int i = 0; i < size; i++) b[i] = h->p[h->fmt == 1 ? i : size - 1 - i];
    h->p += size;
    uint64_t u = 0;
    for (int i = size - 1; i >= 0; i--) u = u << 8 | b[i];
    switch (t) {
    case PLY_I8:
        *x = (int8_t)u;
        break;
    case PLY_U8:
        *x = (uint8_t)u;
        break;
    case PLY_I16:
        *x = (int16_t)u;
        break;
    case PLY_U16:
        *x = (uint16_t)u;
        break;
    case PLY_I32:
        *x = (int32_t)u;
        break;
    case PLY_U32:
        *x = (uint32_t)u;
        break;
    case PLY_F32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, sizeof f);
        *x = f;
        break;
    }
    default:
        memcpy(x, &u, sizeof *x);
    }
    return isfinite(*x) ? 0 : -1;
}

/* The columns of an element the solid is made of: "vertex"'s scalar x, y, z, "face"'s list
 * vertex_indices (or vertex_index); -1 where there is none. */
typedef struct ply_cols {
    int vert, face;
    int ix, iy, iz, il;
} ply_cols;

/* The columns of element e, checked: a vertex element has x, y and z, a face element its list,
 * and neither more items than a solid may have; 0 or -1 with the message. */
static int ply_columns(const ply_elem *e, ply_cols *c, char *err, size_t errlen)
{
    *c = (ply_cols){!strcmp(e->name, "vertex"), !strcmp(e->name, "face"), -1, -1, -1, -1};
    for (size_t q = 0; q < e->np; q++) {
        const char *nm = e->p[q].name;
        if (c->vert && e->p[q].count < 0 && !strcmp(nm, "x")) c->ix = (int)q;
        if (c->vert && e->p[q].count < 0 && !strcmp(nm, "y")) c->iy = (int)q;
        if (c->vert && e->p[q].count < 0 && !strcmp(nm, "z")) c->iz = (int)q;
        if (c->face && e->p[q].count >= 0 &&
            (!strcmp(nm, "vertex_indices") || !strcmp(nm, "vertex_index")))
            c->il = (int)q;
    }
    if (c->vert && (c->ix < 0 || c->iy < 0 || c->iz < 0))
        return util_seterr(err, errlen, -1, "element vertex: no scalar property x, y and z");
    if (c->face && c->il < 0)
        return util_seterr(err, errlen, -1, "element face: no list property vertex_indices");
    if (c->vert && e->count > MESH_MAX_VERTICES)
        return util_seterr(err, errlen, -1, "element vertex: %llu vertices: more than %u",
                           (unsigned long long)e->count, MESH_MAX_VERTICES);
    if (c->face && e->count > MESH_MAX_TRIANGLES)
        return util_seterr(err, errlen, -1, "element face: %llu faces: more than %u",
                           (unsigned long long)e->count, MESH_MAX_TRIANGLES);
    return 0;
}

/* Where item i of element e is, for messages: "vertex 12". */
static const char *ply_where(char where[96], const ply_elem *e, uint64_t i)
{
    snprintf(where, 96, "%s %llu", e->name, (unsigned long long)i);
    return where;
}

/* The message of a value of property pp of item i of e that ply_value() refused (got: -2 the
 * file ends, -1 not a number of its type); -1. */
static int ply_bad_value(const ply *h, const ply_elem *e, uint64_t i, const ply_prop *pp, int got,
                         char *err, size_t errlen)
{
    char where[96];
    ply_where(where, e, i);
    if (got == -2) return util_seterr(err, errlen, -1, "%s: %s: the file ends", where, pp->name);
    if (h->fmt == 0)
        return util_seterr(err, errlen, -1, "%s: %s: line %zu: expected %s number", where, pp->name,
                           h->k.line, pp->type < PLY_F32 ? "an integer" : "a finite");
    return util_seterr(err, errlen, -1, "%s: %s: not a finite number", where, pp->name);
}

/* The list property q of item i of e: its count and items read; of the face's index list
 * (q == c->il), the indices into b.  0 or -1 with the message. */
static int ply_list(ply *h, const ply_elem *e, const ply_cols *c, uint64_t i, size_t q, mbuild *b,
                    char *err, size_t errlen)
{
    const ply_prop *pp = &e->p[q];
    char where[96];
    double n, v;
    int got, rc;
    if ((got = ply_value(h, pp->count, &n))) return ply_bad_value(h, e, i, pp, got, err, errlen);
    if (n < 0 || n > MESH_PLY_POLYGON)
        return util_seterr(err, errlen, -1, "%s: %s: a list of %g items (0 to %d)",
                           ply_where(where, e, i), pp->name, n, MESH_PLY_POLYGON);
    if ((int)q == c->il && n < 3)
        return util_seterr(err, errlen, -1, "%s: %g vertices (3 or more needed)",
                           ply_where(where, e, i), n);
    for (int j = 0; j < (int)n; j++) {
        if ((got = ply_value(h, pp->type, &v))) return ply_bad_value(h, e, i, pp, got, err, errlen);
        if ((int)q != c->il) continue;
        if (!(v >= 0 && v < 4294967295.0) || v != floor(v))
            return util_seterr(err, errlen, -1, "%s: vertex_indices[%d]: %g is not a vertex index",
                               ply_where(where, e, i), j, v);
        if ((rc = mb_index(b, (uint32_t)v)))
            return util_seterr(err, errlen, -1, "%s: %s", ply_where(where, e, i), limit_msg(rc));
    }
    return 0;
}

/* Item i of element e: its values read in order; a vertex's x, y, z or a face's indices into
 * b, the other properties skipped.  0 or -1 with the message. */
static int ply_item(ply *h, const ply_elem *e, const ply_cols *c, uint64_t i, mbuild *b, char *err,
                    size_t errlen)
{
    double x[3] = {0, 0, 0};
    char where[96];
    int rc, got;
    if (c->face && (rc = mb_face(b)))
        return util_seterr(err, errlen, -1, "%s: %s", ply_where(where, e, i), limit_msg(rc));
    for (size_t q = 0; q < e->np; q++) {
        const ply_prop *pp = &e->p[q];
        double v;
        if (pp->count >= 0) {
            if (ply_list(h, e, c, i, q, b, err, errlen)) return -1;
            continue;
        }
        if ((got = ply_value(h, pp->type, &v))) return ply_bad_value(h, e, i, pp, got, err, errlen);
        if ((int)q == c->ix) x[0] = v;
        if ((int)q == c->iy) x[1] = v;
        if ((int)q == c->iz) x[2] = v;
    }
    if (c->vert && (rc = mb_vertex(b, x)))
        return util_seterr(err, errlen, -1, "%s: %s", ply_where(where, e, i), limit_msg(rc));
    return 0;
}

int mesh_read_ply(const char *data, size_t len, solid *out, char *err, size_t errlen)
{
    if (errlen) err[0] = 0;
    ply *h = calloc(1, sizeof *h);
    mbuild b = {0};
    *out = (solid){0};
    if (!h) return util_seterr(err, errlen, -1, "out of memory");
    if (ply_header(h, data, len, err, errlen)) goto fail;
    h->k = (tok){(const char *)h->p, data + len, h->hlines + 1, NULL, 0};
    for (size_t ei = 0; ei < h->ne; ei++) {
        const ply_elem *e = &h->e[ei];
        ply_cols c;
        if (ply_columns(e, &c, err, errlen)) goto fail;
        if (!e->np) continue;
        for (uint64_t i = 0; i < e->count; i++)
            if (ply_item(h, e, &c, i, &b, err, errlen)) goto fail;
    }
    for (size_t f = 0; f < b.ncyc; f++) {
        size_t end = f + 1 < b.ncyc ? b.cyc_off[f + 1] : b.ni;
        for (size_t i = b.cyc_off[f]; i < end; i++)
            if (b.cyc[i] >= b.nv) {
                util_seterr(err, errlen, -1, "face %zu: vertex index %u not below the %zu vertices",
                            f, b.cyc[i], b.nv);
                goto fail;
            }
    }
    if (mb_finish(&b, out)) {
        util_seterr(err, errlen, -1, "out of memory");
        goto fail;
    }
    free(h);
    return 0;
fail:
    mb_free(&b);
    free(h);
    return -1;
}

/* ---- 3MF ------------------------------------------------------------------------------------- */

typedef struct comp3 {
    uint32_t id;
    double t[12];
} comp3;

typedef struct obj3 {
    uint32_t id;
    int has_mesh;
    double *V;
    size_t nv, vcap;
    uint32_t *T; /* 3 per triangle */
    size_t nt, tcap;
    comp3 *c;
    size_t nc, ccap;
} obj3;

typedef struct model3 {
    obj3 *o;
    size_t no, ocap;
    comp3 *items;
    size_t ni, icap;
    const char *part; /* for messages */
    char xerr[160];   /* libxml2's first error */
    int xline;
} model3;

static const double IDENTITY[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};

static void model_free(model3 *m)
{
    for (size_t i = 0; i < m->no; i++) {
        free(m->o[i].V);
        free(m->o[i].T);
        free(m->o[i].c);
    }
    free(m->o);
    free(m->items);
}

static void xml_error(void *arg, xmlErrorPtr e)
{
    model3 *m = arg;
    if (m->xerr[0] || !e) return;
    snprintf(m->xerr, sizeof m->xerr, "%s", e->message ? e->message : "malformed XML");
    size_t n = strlen(m->xerr);
    while (n && (m->xerr[n - 1] == '\n' || m->xerr[n - 1] == ' ')) m->xerr[--n] = 0;
    m->xline = e->line;
}

static int parse_num(const xmlChar *s, double *x)
{
    const char *p = (const char *)s, *e;
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') p++;
    e = p + strlen(p);
    while (e > p && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\n' || e[-1] == '\r')) e--;
    return e > p && ff_parse(p, e, x) == 0 ? 0 : -1;
}

static int parse_index(const xmlChar *s, uint32_t *v)
{
    double x;
    if (parse_num(s, &x) || x < 0 || x >= 4294967295.0 || x != floor(x)) return -1;
    *v = (uint32_t)x;
    return 0;
}

static int parse_transform(const xmlChar *s, double t[12])
{
    const char *p = (const char *)s;
    for (int i = 0; i < 12; i++) {
        const char *stop;
        while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') p++;
        if (ff_parse_prefix(p, p + strlen(p), &t[i], &stop)) return -1;
        p = stop;
    }
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') p++;
    return *p ? -1 : 0;
}

/* The element the reader is on, read into m.  cur: the object being read (or -1). */
static int model_element(xmlTextReaderPtr r, model3 *m, long *cur, int in_build, char *err,
                         size_t errlen)
{
    const char *name = (const char *)xmlTextReaderConstLocalName(r);
    int line = xmlTextReaderGetParserLineNumber(r);
    int is_obj = !strcmp(name, "object"), is_v = !strcmp(name, "vertex"),
        is_t = !strcmp(name, "triangle"), is_c = !strcmp(name, "component"),
        is_i = in_build && !strcmp(name, "item"), is_mesh = !strcmp(name, "mesh");
    if (!(is_obj || is_v || is_t || is_c || is_i || is_mesh)) return 0;
    obj3 *o = *cur >= 0 ? &m->o[*cur] : NULL;
    if ((is_v || is_t || is_c || is_mesh) && !o)
        return util_seterr(err, errlen, -1, "%s: line %d: <%s> outside an <object>", m->part, line,
                           name);
    if (is_mesh) {
        o->has_mesh = 1;
        return 0;
    }
    if (is_obj) {
        if (m->no >= MESH_3MF_OBJECTS)
            return util_seterr(err, errlen, -1, "%s: line %d: more than %d objects", m->part, line,
                               MESH_3MF_OBJECTS);
        if (mem_grow(&m->o, &m->ocap, m->no + 1, sizeof *m->o)) goto nomem;
        o = &m->o[m->no];
        *o = (obj3){0};
        o->id = UINT32_MAX;
        *cur = (long)m->no++;
    }
    double x[3] = {NAN, NAN, NAN}, t[12];
    uint32_t v[3] = {UINT32_MAX, UINT32_MAX, UINT32_MAX}, id = UINT32_MAX;
    memcpy(t, IDENTITY, sizeof t);
    while (xmlTextReaderMoveToNextAttribute(r) == 1) {
        const char *a = (const char *)xmlTextReaderConstLocalName(r);
        const xmlChar *val = xmlTextReaderConstValue(r);
        if (!val) continue;
        int bad = 0;
        if (is_v && a[0] >= 'x' && a[0] <= 'z' && !a[1])
            bad = parse_num(val, &x[a[0] - 'x']);
        else if (is_t && a[0] == 'v' && a[1] >= '1' && a[1] <= '3' && !a[2])
            bad = parse_index(val, &v[a[1] - '1']);
        else if ((is_obj && !strcmp(a, "id")) || ((is_c || is_i) && !strcmp(a, "objectid")))
            bad = parse_index(val, &id);
        else if ((is_c || is_i) && !strcmp(a, "transform"))
            bad = parse_transform(val, t);
        else
            continue;
        if (bad) {
            xmlTextReaderMoveToElement(r);
            return util_seterr(err, errlen, -1, "%s: line %d: <%s> %s: expected %s", m->part, line,
                               name, a,
                               !strcmp(a, "transform") ? "12 numbers"
                               : is_v                  ? "a finite number"
                                                       : "an index");
        }
    }
    xmlTextReaderMoveToElement(r);
    if (is_obj) {
        if (id == UINT32_MAX)
            return util_seterr(err, errlen, -1, "%s: line %d: <object> without an id", m->part,
                               line);
        o->id = id;
    } else if (is_v) {
        for (int a = 0; a < 3; a++)
            if (isnan(x[a]))
                return util_seterr(err, errlen, -1, "%s: line %d: vertex %zu: no %c", m->part, line,
                                   o->nv, 'x' + a);
        if (o->nv >= MESH_MAX_VERTICES)
            return util_seterr(err, errlen, -1, "%s: line %d: more than %u vertices", m->part, line,
                               MESH_MAX_VERTICES);
        if (mem_grow(&o->V, &o->vcap, o->nv + 1, 3 * sizeof(double))) goto nomem;
        memcpy(o->V + 3 * o->nv++, x, sizeof x);
    } else if (is_t) {
        for (int a = 0; a < 3; a++)
            if (v[a] == UINT32_MAX)
                return util_seterr(err, errlen, -1, "%s: line %d: triangle %zu: no v%d", m->part,
                                   line, o->nt, a + 1);
        if (o->nt >= MESH_MAX_TRIANGLES)
            return util_seterr(err, errlen, -1, "%s: line %d: more than %u triangles", m->part,
                               line, MESH_MAX_TRIANGLES);
        if (mem_grow(&o->T, &o->tcap, o->nt + 1, 3 * sizeof(uint32_t))) goto nomem;
        memcpy(o->T + 3 * o->nt++, v, sizeof v);
    } else {
        if (id == UINT32_MAX)
            return util_seterr(err, errlen, -1, "%s: line %d: <%s> without an objectid", m->part,
                               line, name);
        comp3 **arr = is_c ? &o->c : &m->items;
        size_t *n = is_c ? &o->nc : &m->ni, *cap = is_c ? &o->ccap : &m->icap;
        if (*n >= MESH_3MF_SOLIDS)
            return util_seterr(err, errlen, -1, "%s: line %d: more than %d <%s>s", m->part, line,
                               MESH_3MF_SOLIDS, name);
        if (mem_grow(arr, cap, *n + 1, sizeof **arr)) goto nomem;
        (*arr)[*n].id = id;
        memcpy((*arr)[(*n)++].t, t, sizeof t);
    }
    return 0;
nomem:
    return util_seterr(err, errlen, -1, "out of memory");
}

static int model_parse(const char *xml, size_t len, model3 *m, char *err, size_t errlen)
{
    xmlTextReaderPtr r = xmlReaderForMemory(xml, (int)len, NULL, NULL,
                                            XML_PARSE_NONET | XML_PARSE_NOERROR |
                                                XML_PARSE_NOWARNING | XML_PARSE_BIG_LINES);
    long cur = -1;
    int in_build = 0, rc = 0, ret;
    if (!r) return util_seterr(err, errlen, -1, "out of memory");
    xmlTextReaderSetStructuredErrorHandler(r, xml_error, m);
    while ((ret = xmlTextReaderRead(r)) == 1) {
        int type = xmlTextReaderNodeType(r);
        if (type == XML_READER_TYPE_DOCUMENT_TYPE) {
            rc = util_seterr(err, errlen, -1, "%s: a DTD (<!DOCTYPE>) is not allowed", m->part);
            goto out;
        }
        if (xmlTextReaderDepth(r) > MESH_3MF_DEPTH) {
            rc = util_seterr(err, errlen, -1, "%s: line %d: nested deeper than %d", m->part,
                             xmlTextReaderGetParserLineNumber(r), MESH_3MF_DEPTH);
            goto out;
        }
        const char *name = (const char *)xmlTextReaderConstLocalName(r);
        if (type == XML_READER_TYPE_ELEMENT) {
            if (!strcmp(name, "build")) in_build = !xmlTextReaderIsEmptyElement(r);
            if ((rc = model_element(r, m, &cur, in_build, err, errlen))) goto out;
            if (!strcmp(name, "object") && xmlTextReaderIsEmptyElement(r)) cur = -1;
        } else if (type == XML_READER_TYPE_END_ELEMENT) {
            if (!strcmp(name, "object")) cur = -1;
            if (!strcmp(name, "build")) in_build = 0;
        }
    }
    if (ret < 0)
        rc = util_seterr(err, errlen, -1, "%s: line %d: malformed XML: %s", m->part, m->xline,
                         m->xerr[0] ? m->xerr : "cannot parse");
out:
    xmlFreeTextReader(r);
    return rc;
}

/* Reads the member name of za (at most max bytes inflated) into *buf (NUL after). */
static _Atomic size_t max_part = MESH_3MF_MAX_PART;

void mesh_set_max_part(size_t bytes)
{
    max_part = bytes && bytes < MESH_3MF_MAX_PART ? bytes : MESH_3MF_MAX_PART;
}

size_t mesh_max_part(void)
{
    return max_part;
}

static int zip_member(zip_t *za, const char *name, size_t max, char **buf, size_t *n, char *err,
                      size_t errlen)
{
    zip_int64_t i = zip_name_locate(za, name, ZIP_FL_NOCASE);
    *buf = NULL;
    *n = 0;
    if (i < 0) return 1;
    /* a size the directory declares beyond the limit is refused before anything is inflated;
     * a directory that lies is caught by the count below, at the limit */
    zip_stat_t st;
    if (zip_stat_index(za, (zip_uint64_t)i, 0, &st) == 0 && (st.valid & ZIP_STAT_SIZE) &&
        st.size > max)
        return util_seterr(err, errlen, -1,
                           "%s: inflates to more than %zu bytes (%llu, its directory says)", name,
                           max, (unsigned long long)st.size);
    zip_file_t *zf = zip_fopen_index(za, (zip_uint64_t)i, 0);
    if (!zf) return util_seterr(err, errlen, -1, "%s: cannot open: %s", name, zip_strerror(za));
    size_t cap = 0, len = 0;
    char *b = NULL;
    for (;;) {
        /* room doubled with plain realloc, not mem_grow: its huge-page hint has the kernel back
         * the whole doubled block, twice the bytes read (t_meshio bounds a lying zip's memory) */
        char *q = len + 65537 > cap ? realloc(b, cap = cap ? 2 * cap : 1 << 17) : b;
        if (!q) {
            zip_fclose(zf);
            free(b);
            return util_seterr(err, errlen, -1, "out of memory");
        }
        b = q;
        zip_int64_t got = zip_fread(zf, b + len, 65536);
        if (got < 0) {
            util_seterr(err, errlen, -1, "%s: cannot inflate: %s", name, zip_file_strerror(zf));
            zip_fclose(zf);
            free(b);
            return -1;
        }
        if (got == 0) break;
        len += (size_t)got;
        if (len > max) {
            zip_fclose(zf);
            free(b);
            return util_seterr(err, errlen, -1, "%s: inflates to more than %zu bytes", name, max);
        }
    }
    zip_fclose(zf);
    b[len] = 0;
    *buf = b;
    *n = len;
    return 0;
}

/* The root model part's name from _rels/.rels (into name), or 3D/3dmodel.model. */
static int find_model(zip_t *za, char *name, size_t cap, char *err, size_t errlen)
{
    char *rels;
    size_t n;
    snprintf(name, cap, "3D/3dmodel.model");
    int rc = zip_member(za, "_rels/.rels", MESH_3MF_MAX_RELS, &rels, &n, err, errlen);
    if (rc) return rc < 0 ? -1 : 0;
    xmlTextReaderPtr r = xmlReaderForMemory(
        rels, (int)n, NULL, NULL, XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    if (!r) {
        free(rels);
        return util_seterr(err, errlen, -1, "out of memory");
    }
    while (xmlTextReaderRead(r) == 1) {
        if (xmlTextReaderNodeType(r) == XML_READER_TYPE_DOCUMENT_TYPE ||
            xmlTextReaderDepth(r) > MESH_3MF_DEPTH)
            break;
        if (xmlTextReaderNodeType(r) != XML_READER_TYPE_ELEMENT ||
            strcmp((const char *)xmlTextReaderConstLocalName(r), "Relationship"))
            continue;
        xmlChar *type = xmlTextReaderGetAttribute(r, BAD_CAST "Type");
        xmlChar *target = xmlTextReaderGetAttribute(r, BAD_CAST "Target");
        size_t tl = type ? strlen((const char *)type) : 0;
        if (target && tl >= 8 && !strcmp((const char *)type + tl - 8, "/3dmodel")) {
            const char *t = (const char *)target;
            while (*t == '/') t++;
            if (*t && strlen(t) < cap) snprintf(name, cap, "%s", t);
            xmlFree(type);
            xmlFree(target);
            break;
        }
        xmlFree(type);
        xmlFree(target);
    }
    xmlFreeTextReader(r);
    free(rels);
    return 0;
}

static int cmp_obj(const void *a, const void *b)
{
    const obj3 *x = a, *y = b;
    return (x->id > y->id) - (x->id < y->id);
}

static obj3 *find_obj(model3 *m, uint32_t id)
{
    obj3 key = {.id = id};
    return m->no ? bsearch(&key, m->o, m->no, sizeof *m->o, cmp_obj) : NULL;
}

/* c = a then b (row vectors: p a b). */
static void compose(const double a[12], const double b[12], double c[12])
{
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 3; j++) {
            double s = i == 3 ? b[9 + j] : 0;
            for (int k = 0; k < 3; k++) s += a[3 * i + k] * b[3 * k + j];
            c[3 * i + j] = s;
        }
}

typedef struct out3 {
    solid *s;
    size_t n, cap;
    size_t verts, tris; /* made so far */
} out3;

static int instance(model3 *m, uint32_t id, const double t[12], int depth, out3 *o,
                    const char *where, char *err, size_t errlen)
{
    obj3 *ob = find_obj(m, id);
    if (!ob) return util_seterr(err, errlen, -1, "%s: object %u: no such object", where, id);
    if (depth > MESH_3MF_NESTING)
        return util_seterr(err, errlen, -1, "%s: components nested deeper than %d (a cycle?)",
                           where, MESH_3MF_NESTING);
    if (ob->has_mesh && ob->nt) {
        mbuild b = {0};
        if (o->n >= MESH_3MF_SOLIDS)
            return util_seterr(err, errlen, -1, "%s: more than %d solids", where, MESH_3MF_SOLIDS);
        if (o->verts + ob->nv > MESH_MAX_VERTICES || o->tris + ob->nt > MESH_MAX_TRIANGLES)
            return util_seterr(err, errlen, -1, "%s: more than %u vertices or triangles in all",
                               where, MESH_MAX_VERTICES);
        double det = t[0] * (t[4] * t[8] - t[5] * t[7]) - t[1] * (t[3] * t[8] - t[5] * t[6]) +
                     t[2] * (t[3] * t[7] - t[4] * t[6]);
        for (size_t v = 0; v < ob->nv; v++) {
            const double *p = ob->V + 3 * v;
            double q[3];
            for (int j = 0; j < 3; j++) {
                q[j] = p[0] * t[j] + p[1] * t[3 + j] + p[2] * t[6 + j] + t[9 + j];
                if (!isfinite(q[j])) {
                    mb_free(&b);
                    return util_seterr(err, errlen, -1,
                                       "object %u: vertex %zu: not finite once transformed", id, v);
                }
            }
            if (mb_vertex(&b, q)) goto nomem;
        }
        for (size_t k = 0; k < ob->nt; k++) {
            const uint32_t *tr = ob->T + 3 * k;
            if (mb_face(&b)) goto nomem;
            for (int j = 0; j < 3; j++) {
                uint32_t v = tr[det < 0 ? (3 - j) % 3 : j];
                if (v >= ob->nv) {
                    mb_free(&b);
                    return util_seterr(err, errlen, -1,
                                       "object %u: triangle %zu: v%d = %u not below the %zu "
                                       "vertices",
                                       id, k, (det < 0 ? (3 - j) % 3 : j) + 1, v, ob->nv);
                }
                if (mb_index(&b, v)) goto nomem;
            }
        }
        if (mem_grow(&o->s, &o->cap, o->n + 1, sizeof *o->s) || mb_finish(&b, &o->s[o->n]))
            goto nomem;
        o->n++;
        o->verts += ob->nv;
        o->tris += ob->nt;
        goto comps;
    nomem:
        mb_free(&b);
        return util_seterr(err, errlen, -1, "out of memory");
    }
comps:
    for (size_t i = 0; i < ob->nc; i++) {
        double c[12];
        compose(ob->c[i].t, t, c);
        if (instance(m, ob->c[i].id, c, depth + 1, o, where, err, errlen)) return -1;
    }
    return 0;
}

int mesh_read_3mf(const char *data, size_t len, solid **parts, size_t *nparts, char *err,
                  size_t errlen)
{
    if (errlen) err[0] = 0;
    zip_error_t ze;
    zip_source_t *src;
    zip_t *za = NULL;
    model3 m = {0};
    out3 o = {0};
    char name[256], *xml = NULL;
    size_t n;
    int rc = -1;
    *parts = NULL;
    *nparts = 0;
    zip_error_init(&ze);
    if (!(src = zip_source_buffer_create(data, len, 0, &ze))) {
        util_seterr(err, errlen, -1, "out of memory");
        goto out;
    }
    if (!(za = zip_open_from_source(src, ZIP_RDONLY, &ze))) {
        util_seterr(err, errlen, -1, "not a 3MF file: not a zip (%s)", zip_error_strerror(&ze));
        zip_source_free(src);
        goto out;
    }
    if (find_model(za, name, sizeof name, err, errlen)) goto out;
    int r = zip_member(za, name, mesh_max_part(), &xml, &n, err, errlen);
    if (r > 0) util_seterr(err, errlen, -1, "not a 3MF file: no model part %s", name);
    if (r) goto out;
    if (n > INT32_MAX) {
        util_seterr(err, errlen, -1, "%s: too large", name);
        goto out;
    }
    m.part = name;
    if (model_parse(xml, n, &m, err, errlen)) goto out;
    if (m.no > 1) qsort(m.o, m.no, sizeof *m.o, cmp_obj);
    for (size_t i = 1; i < m.no; i++)
        if (m.o[i].id == m.o[i - 1].id) {
            util_seterr(err, errlen, -1, "%s: object id %u twice", name, m.o[i].id);
            goto out;
        }
    if (m.ni) {
        for (size_t i = 0; i < m.ni; i++) {
            char where[48];
            snprintf(where, sizeof where, "build item %zu", i);
            if (instance(&m, m.items[i].id, m.items[i].t, 0, &o, where, err, errlen)) goto out;
        }
    } else {
        for (size_t i = 0; i < m.no; i++)
            if (m.o[i].has_mesh &&
                instance(&m, m.o[i].id, IDENTITY, MESH_3MF_NESTING, &o, "object", err, errlen))
                goto out;
    }
    *parts = o.s;
    *nparts = o.n;
    o.s = NULL;
    o.n = 0;
    rc = 0;
out:
    for (size_t i = 0; i < o.n; i++) solid_free(&o.s[i]);
    free(o.s);
    model_free(&m);
    free(xml);
    if (za) zip_discard(za);
    zip_error_fini(&ze);
    return rc;
}

/* ---- any format, and the request --------------------------------------------------------------
 */

int mesh_read(mesh_format f, const char *data, size_t len, int groups, solid **parts,
              size_t *nparts, char *err, size_t errlen)
{
    solid one;
    int rc;
    *parts = NULL;
    *nparts = 0;
    switch (f) {
    case MESH_OBJ:
        return solid_read_obj_parts(data, len, groups, parts, nparts, err, errlen);
    case MESH_3MF:
        return mesh_read_3mf(data, len, parts, nparts, err, errlen);
    case MESH_OFF:
        rc = solid_read_off(data, len, &one, err, errlen);
        break;
    case MESH_STL:
        rc = mesh_read_stl(data, len, &one, err, errlen);
        break;
    case MESH_PLY:
        rc = mesh_read_ply(data, len, &one, err, errlen);
        break;
    default:
        return util_seterr(err, errlen, -1, "not a mesh format this reads");
    }
    if (rc) return -1;
    if (!(*parts = malloc(sizeof **parts))) {
        solid_free(&one);
        return util_seterr(err, errlen, -1, "out of memory");
    }
    **parts = one;
    *nparts = 1;
    return 0;
}

static void put_cycle(api_buf *b, const solid *s, size_t c)
{
    api_buf_u32_list(b, s->cyc + s->cyc_off[c], s->cyc_off[c + 1] - s->cyc_off[c]);
}

static void put_solid(api_buf *b, const solid *s)
{
    api_buf_puts(b, "{\"V\":[");
    for (size_t v = 0; v < s->nv; v++) {
        if (v) api_buf_putc(b, ',');
        api_buf_point(b, s->V + 3 * v, 3);
    }
    api_buf_puts(b, "],\"FV\":[");
    for (size_t f = 0; f < s->nf; f++) {
        if (f) api_buf_putc(b, ',');
        put_cycle(b, s, s->face_off[f]);
    }
    api_buf_puts(b, "]");
    int first = 1;
    for (size_t f = 0; f < s->nf; f++) {
        if (s->face_off[f + 1] - s->face_off[f] < 2) continue;
        api_buf_puts(b, first ? ",\"holes\":{\"" : ",\"");
        first = 0;
        api_buf_u64(b, f);
        api_buf_puts(b, "\":[");
        for (size_t c = s->face_off[f] + 1; c < s->face_off[f + 1]; c++) {
            if (c > s->face_off[f] + 1) api_buf_putc(b, ',');
            put_cycle(b, s, c);
        }
        api_buf_putc(b, ']');
    }
    if (!first) api_buf_putc(b, '}');
    api_buf_putc(b, '}');
}

int mesh_request_json(const mesh_file *files, size_t n, const char *request, size_t rlen,
                      char **out, size_t *outlen, api_error *err)
{
    json_t *req = NULL;
    json_error_t je;
    api_buf b = {0};
    char msg[200];
    size_t count = 0;
    int rc = API_OK;
    *out = NULL;
    *outlen = 0;
    if (request) {
        req = json_loadb(request, rlen, JSON_REJECT_DUPLICATES, &je);
        if (!req)
            return api_fail(err, API_EINVALID, "request: not JSON: line %d, column %d: %s", je.line,
                            je.column, je.text);
        if (!json_is_object(req)) {
            rc = api_fail(err, API_EINVALID, "request: expected a JSON object");
            goto out;
        }
        json_t *k = json_object_get(req, "kind");
        if (k && !(json_is_string(k) && !strcmp(json_string_value(k), "solids"))) {
            rc = api_fail(err, API_EINVALID,
                          "request.kind: the files make a \"solids\" request (or leave it out)");
            goto out;
        }
        if (json_object_get(req, "solids") || json_object_get(req, "faces")) {
            rc = api_fail(err, API_EINVALID,
                          "request: the solids are the files: no \"solids\" or \"faces\" here");
            goto out;
        }
    }
    api_buf_puts(&b, "{\"kind\":\"solids\",\"solids\":[");
    for (size_t i = 0; i < n; i++) {
        solid *parts = NULL;
        size_t np = 0;
        if (mesh_read(files[i].format, files[i].data, files[i].len, 0, &parts, &np, msg,
                      sizeof msg)) {
            rc = api_fail(err, API_EINVALID, "%s: %s", files[i].name, msg);
            goto out;
        }
        for (size_t k = 0; k < np; k++) {
            if (count++) api_buf_putc(&b, ',');
            put_solid(&b, &parts[k]);
            solid_free(&parts[k]);
        }
        free(parts);
        if (b.failed) break;
    }
    if (!b.failed && count == 0) {
        rc = api_fail(err, API_EINVALID, "no solid in the files");
        goto out;
    }
    api_buf_putc(&b, ']');
    const char *key;
    json_t *val;
    json_object_foreach(req, key, val)
    {
        if (!strcmp(key, "kind")) continue;
        char *s = json_dumps(val, JSON_COMPACT | JSON_ENCODE_ANY | JSON_PRESERVE_ORDER);
        json_t *kj = json_string(key);
        char *kd = kj ? json_dumps(kj, JSON_ENCODE_ANY) : NULL;
        json_decref(kj);
        if (!s || !kd) {
            free(s);
            free(kd);
            b.failed = 1;
            break;
        }
        api_buf_putc(&b, ',');
        api_buf_puts(&b, kd);
        api_buf_putc(&b, ':');
        api_buf_puts(&b, s);
        free(s);
        free(kd);
    }
    api_buf_putc(&b, '}');
    if (b.failed) {
        rc = api_fail(err, API_ENOMEM, "out of memory making the request of the mesh files");
        goto out;
    }
    *out = b.p;
    *outlen = b.len;
    b.p = NULL;
    if (err) *err = (api_error){0};
out:
    api_buf_free(&b);
    json_decref(req);
    return rc;
}
