/* npz.c — a result as NumPy arrays in one .npz (issue 27, item 5; render.h says what is written).
 *
 * The result JSON is read once by a reader of its own (not jansson: a 40 MB result would cost
 * a node per number): every array of numbers becomes a flat vector of doubles as it is read
 * (integers below 2^53 are exact there), and every value that is not turned into an array is
 * copied, as its text, into a JSON object of the rest (`json`).  Each array is then written as
 * a .npy (format 1.0: magic, a header dict padded to 64 bytes, the data little-endian) into a
 * zip with a central directory, stored as numpy.savez stores them (zlib's CRC-32): deflating
 * would cost three times the reading (80 MB/s at zlib's fastest level), and the daemon gzips an
 * answer for a client that takes gzip.  The zip's times are 1980-01-01 00:00, so the same
 * result always gives the same bytes (its ETag holds).
 *
 * Which arrays: by the last key of their path and the result's "dim"
 *   V                          float64, (n, dim)
 *   EV                         (m, 2)
 *   FV FE CF CV, exterior (2D) rows of different lengths: K.indptr, K.indices
 *   holes (an object)          holes.face (the face of each cycle), holes.indptr, holes.indices
 *   stats (an object)          kept whole in json
 *   other arrays               by their first element: numbers 1D, arrays rows (as FV);
 *                              anything else stays in json
 *   other objects              their members, named "key.member"
 * Integer arrays are int32, int64 when a value needs it; an array with a number that is not
 * an integer is float64.  Names join keys with ".": "operators.d1.indptr".
 *
 * A result this reader cannot take (not JSON, a row of V of another length than the first, a
 * bad number, more than NPZ_DEPTH levels) is API_EINVALID naming the JSON path; one too big
 * for a zip without its 64-bit extension (4 GiB a member) is API_EINVALID too.
 *
 * Threads: reentrant.  Ownership: as the other renderers (render.h). */
#include "api/render.h"

#include "api/api_int.h"
#include "core/fastfloat.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#define NPZ_DEPTH  32   /* nesting levels of the result read */
#define NPZ_NAME   120  /* bytes of an array's name, ".npy" and the NUL included */
#define NPZ_CHUNK  8192 /* numbers converted to their dtype at a time */
#define NPZ_MAXARR 4096 /* arrays in one file (the zip's 65535 entries, and names to compare) */

enum { NPZ_F8, NPZ_INT, NPZ_U1 };

typedef struct vec {
    double *x;
    size_t n, cap;
} vec;

typedef struct npz_arr {
    char name[NPZ_NAME];
    int ndim;       /* 1 or 2 */
    size_t cols;    /* ndim 2: the row length */
    int real;       /* a number is not an integer (or the array is V): float64 */
    vec v;          /* the numbers (ndim 1: all of them; 2: row by row) */
    const char *u1; /* NPZ_U1 (the rest's JSON): its bytes, not owned */
    size_t u1n;
} npz_arr;

typedef struct rd {
    const char *p, *end;
    api_error *err;
    int rc; /* API_OK until a failure (its message is in err) */
    char path[200];
    int dim;
    npz_arr *a;
    size_t na, cap;
    api_buf rest;
} rd;

/* ---- errors and paths ---------------------------------------------------------------------- */

static int bad(rd *r, const char *what)
{
    if (r->rc == API_OK)
        r->rc = api_fail(r->err, API_EINVALID, "%s: %s", r->path[0] ? r->path : "result", what);
    return -1;
}

static int nomem(rd *r)
{
    if (r->rc == API_OK) r->rc = api_fail(r->err, API_ENOMEM, "out of memory");
    return -1;
}

/* Appends ".key" (or "key" at the top) or "[i]" to the path; returns the old length. */
static size_t path_push(rd *r, const char *k, size_t kn, long idx)
{
    size_t old = strlen(r->path);
    size_t room = sizeof r->path - old;
    if (k)
        snprintf(r->path + old, room, "%s%.*s", old ? "." : "", (int)(kn < 60 ? kn : 60), k);
    else
        snprintf(r->path + old, room, "[%ld]", idx);
    return old;
}

static void path_pop(rd *r, size_t old)
{
    r->path[old] = 0;
}

/* ---- tokens -------------------------------------------------------------------------------- */

static void ws(rd *r)
{
    while (r->p < r->end && (*r->p == ' ' || *r->p == '\n' || *r->p == '\t' || *r->p == '\r'))
        r->p++;
}

static int peek(rd *r)
{
    ws(r);
    return r->p < r->end ? (unsigned char)*r->p : -1;
}

static int expect(rd *r, char c)
{
    if (peek(r) != c) {
        char m[40];
        snprintf(m, sizeof m, "expected '%c'", c);
        return bad(r, m);
    }
    r->p++;
    return 0;
}

/* A string at r->p: its contents [*k, *k + *kn) as written (escapes not decoded); *plain is 0
 * when it has an escape. */
static int string(rd *r, const char **k, size_t *kn, int *plain)
{
    if (peek(r) != '"') return bad(r, "expected a string");
    const char *s = ++r->p;
    *plain = 1;
    while (r->p < r->end && *r->p != '"') {
        unsigned char c = (unsigned char)*r->p;
        if (c < 0x20) return bad(r, "a control character in a string");
        if (c == '\\') {
            *plain = 0;
            if (++r->p >= r->end) break;
            if (*r->p == 'u') {
                for (int i = 1; i <= 4; i++)
                    if (r->p + i >= r->end || !strchr("0123456789abcdefABCDEF", r->p[i]) ||
                        !r->p[i])
                        return bad(r, "a bad escape in a string");
                r->p += 4;
            } else if (!*r->p || !strchr("\"\\/bfnrt", *r->p)) {
                return bad(r, "a bad escape in a string");
            }
        }
        r->p++;
    }
    if (r->p >= r->end) return bad(r, "a string is not closed");
    *k = s;
    *kn = (size_t)(r->p - s);
    r->p++;
    return 0;
}

/* A JSON number at r->p: *x, and *integer when it is written without fraction and exponent. */
static int number(rd *r, double *x, int *integer)
{
    size_t digits;
    int rc = ff_json_number(r->p, r->end, x, integer, &digits, &r->p);
    if (rc == -1) return bad(r, "expected a number");
    if (rc) return bad(r, "a number beyond the doubles");
    return 0;
}

/* Skips any JSON value (checked against the grammar), depth levels deep at most. */
static int skip_value(rd *r, int depth)
{
    int c = peek(r);
    if (depth > NPZ_DEPTH) return bad(r, "nested too deep");
    if (c == '"') {
        const char *k;
        size_t kn;
        int plain;
        return string(r, &k, &kn, &plain);
    }
    if (c == '{' || c == '[') {
        char close = c == '{' ? '}' : ']';
        r->p++;
        if (peek(r) == close) {
            r->p++;
            return 0;
        }
        for (;;) {
            if (c == '{') {
                const char *k;
                size_t kn;
                int plain;
                if (string(r, &k, &kn, &plain) || expect(r, ':')) return -1;
            }
            if (skip_value(r, depth + 1)) return -1;
            int n = peek(r);
            r->p++;
            if (n == close) return 0;
            if (n != ',') return bad(r, "expected ',' or the end of an array or object");
        }
    }
    static const char *const lit[] = {"true", "false", "null"};
    for (int i = 0; i < 3; i++) {
        size_t n = strlen(lit[i]);
        if ((size_t)(r->end - r->p) >= n && !memcmp(r->p, lit[i], n)) {
            r->p += n;
            return 0;
        }
    }
    double x;
    int integer;
    return number(r, &x, &integer);
}

/* ---- arrays -------------------------------------------------------------------------------- */

static int push(rd *r, vec *v, double x)
{
    if (v->n == v->cap) {
        size_t cap = v->cap ? 2 * v->cap : 256;
        double *p = realloc(v->x, cap * sizeof *p);
        if (!p) return nomem(r);
        v->x = p;
        v->cap = cap;
    }
    v->x[v->n++] = x;
    return 0;
}

/* A new array named prefix + key + suffix; NULL on failure (a name too long, a name twice, out of
 * memory: the message set). */
static npz_arr *new_arr(rd *r, const char *prefix, const char *key, size_t kn, const char *suffix)
{
    char name[NPZ_NAME];
    int n = snprintf(name, sizeof name, "%s%.*s%s", prefix, (int)kn, key, suffix);
    if (n < 0 || (size_t)n + 5 > sizeof name) return bad(r, "a name too long for npz"), NULL;
    for (size_t i = 0; i < r->na; i++)
        if (!strcmp(r->a[i].name, name)) return bad(r, "a key given twice"), NULL;
    if (r->na == NPZ_MAXARR) return bad(r, "too many arrays for one npz"), NULL;
    if (r->na == r->cap) {
        size_t cap = r->cap ? 2 * r->cap : 16;
        npz_arr *p = realloc(r->a, cap * sizeof *p);
        if (!p) return nomem(r), NULL;
        r->a = p;
        r->cap = cap;
    }
    npz_arr *a = &r->a[r->na++];
    memset(a, 0, sizeof *a);
    memcpy(a->name, name, (size_t)n + 1);
    a->ndim = 1;
    return a;
}

/* [x, ...] into a (its numbers appended); *count gets how many. */
static int numbers(rd *r, npz_arr *a, size_t *count)
{
    if (expect(r, '[')) return -1;
    *count = 0;
    if (peek(r) == ']') {
        r->p++;
        return 0;
    }
    for (;;) {
        double x;
        int integer;
        ws(r);
        if (number(r, &x, &integer) || push(r, &a->v, x)) return -1;
        if (!integer || x >= 9007199254740992.0 || x <= -9007199254740992.0)
            a->real = 1; /* not an exact integer below 2^53: float64 */
        ++*count;
        int c = peek(r);
        r->p++;
        if (c == ']') return 0;
        if (c != ',') return bad(r, "expected ',' or ']'");
    }
}

/* [[x, ...], ...]: rows into a (2D, every row as long as the first) or into ptr and a (rows of
 * any length: ptr the offsets, starting at 0); face >= 0: each row's face into fa too. */
static int rows(rd *r, npz_arr *a, npz_arr *ptr, npz_arr *fa, double face)
{
    if (expect(r, '[')) return -1;
    if (ptr && !ptr->v.n && push(r, &ptr->v, 0)) return -1;
    if (peek(r) == ']') {
        r->p++;
        return 0;
    }
    for (long i = 0;; i++) {
        size_t old = path_push(r, NULL, 0, i), n;
        if (numbers(r, a, &n)) return -1;
        if (ptr && push(r, &ptr->v, (double)a->v.n)) return -1;
        if (fa && push(r, &fa->v, face)) return -1;
        if (!ptr) {
            if (i == 0 && !a->cols) a->cols = n;
            if (!n || n != a->cols) return bad(r, "a row of another length than the others");
        }
        path_pop(r, old);
        int c = peek(r);
        r->p++;
        if (c == ']') return 0;
        if (c != ',') return bad(r, "expected ',' or ']'");
    }
}

/* The array at r->p (key k of the object named prefix) as arrays: 1 when taken, 0 when it is
 * left to the rest (an array of strings or objects), -1 on failure. */
static int take_array(rd *r, const char *prefix, const char *k, size_t kn)
{
    const char *save = r->p;
    r->p++;
    int first = peek(r);
    r->p = save;
#define IS(s) (kn == sizeof(s) - 1 && !memcmp(k, s, kn))
    int v = IS("V"), ev = IS("EV");
    int ragged = IS("FV") || IS("FE") || IS("CF") || IS("CV") || (IS("exterior") && r->dim == 2);
#undef IS
    if (!v && !ev && !ragged) {
        if (first == '[')
            ragged = 1;
        else if (first != ']' && first != '-' && !(first >= '0' && first <= '9'))
            return 0;
    }
    if (v || ev) {
        npz_arr *a = new_arr(r, prefix, k, kn, "");
        if (!a) return -1;
        a->ndim = 2;
        a->real = v;
        a->cols = v ? (size_t)r->dim : 2;
        return rows(r, a, NULL, NULL, -1) ? -1 : 1;
    }
    if (ragged) {
        npz_arr *ptr = new_arr(r, prefix, k, kn, ".indptr");
        if (!ptr) return -1;
        npz_arr *idx = new_arr(r, prefix, k, kn, ".indices");
        if (!idx) return -1;
        /* new_arr may move r->a: find both again by position */
        ptr = &r->a[r->na - 2];
        return rows(r, idx, ptr, NULL, -1) ? -1 : 1;
    }
    npz_arr *a = new_arr(r, prefix, k, kn, "");
    size_t n;
    return !a || numbers(r, a, &n) ? -1 : 1;
}

/* holes: {"f": [[v, ...], ...], ...} as holes.face, holes.indptr, holes.indices. */
static int take_holes(rd *r, const char *prefix, const char *k, size_t kn)
{
    if (!new_arr(r, prefix, k, kn, ".face") || !new_arr(r, prefix, k, kn, ".indptr") ||
        !new_arr(r, prefix, k, kn, ".indices"))
        return -1;
    size_t base = r->na - 3;
    if (expect(r, '{')) return -1;
    if (peek(r) == '}') {
        r->p++;
        return push(r, &r->a[base + 1].v, 0);
    }
    for (;;) {
        const char *f;
        size_t fn;
        int plain;
        if (string(r, &f, &fn, &plain) || expect(r, ':')) return -1;
        size_t old = path_push(r, f, fn, 0);
        double face = 0;
        if (!fn || fn > 10 || (fn > 1 && *f == '0')) return bad(r, "expected a face number");
        for (size_t i = 0; i < fn; i++) {
            if (f[i] < '0' || f[i] > '9') return bad(r, "expected a face number");
            face = face * 10 + (f[i] - '0');
        }
        npz_arr *a = r->a + base;
        size_t before = a[0].v.n;
        if (rows(r, &a[2], &a[1], &a[0], face)) return -1;
        if (a[0].v.n == before) return bad(r, "expected at least one cycle");
        path_pop(r, old);
        int c = peek(r);
        r->p++;
        if (c == '}') return 0;
        if (c != ',') return bad(r, "expected ',' or '}'");
    }
}

/* The object at r->p, named prefix (ends in '.' or is ""): its arrays taken, the rest of it
 * written to r->rest as an object.  *kept: the members written there. */
static int object(rd *r, const char *prefix, int depth, size_t *kept, size_t *members)
{
    if (depth > NPZ_DEPTH) return bad(r, "nested too deep");
    if (expect(r, '{')) return -1;
    api_buf_putc(&r->rest, '{');
    *kept = *members = 0;
    if (peek(r) != '}') {
        for (;;) {
            const char *k;
            size_t kn;
            int plain;
            if (string(r, &k, &kn, &plain) || expect(r, ':')) return -1;
            size_t old = path_push(r, k, kn, 0), mark = r->rest.len;
            ++*members;
            if (*kept) api_buf_putc(&r->rest, ',');
            api_buf_putc(&r->rest, '"');
            api_buf_put(&r->rest, k, kn);
            api_buf_put(&r->rest, "\":", 2);
            int c = peek(r), taken = 0;
            int named = plain && kn && !memchr(k, '.', kn) && !memchr(k, '/', kn);
            if (named && c == '[') {
                taken = take_array(r, prefix, k, kn);
            } else if (named && c == '{' && kn == 5 && !memcmp(k, "holes", 5)) {
                taken = take_holes(r, prefix, k, kn) ? -1 : 1;
            } else if (named && c == '{' && !(kn == 5 && !memcmp(k, "stats", 5))) {
                char sub[NPZ_NAME];
                int n = snprintf(sub, sizeof sub, "%s%.*s.", prefix, (int)kn, k);
                size_t inner, had;
                if (n > 0 && (size_t)n < sizeof sub) {
                    if (object(r, sub, depth + 1, &inner, &had)) return -1;
                    /* an object whose every member became an array leaves nothing behind */
                    taken = inner == 0 && had > 0 ? 1 : 2;
                    if (taken == 2) ++*kept;
                }
            }
            if (taken < 0) return -1;
            if (taken == 1) {
                r->rest.len = mark;
                if (r->rest.p) r->rest.p[mark] = 0;
            } else if (taken == 0) {
                const char *s = r->p;
                if (kn == 3 && !memcmp(k, "dim", 3) && !*prefix && (c == '2' || c == '3'))
                    r->dim = c - '0';
                if (skip_value(r, depth + 1)) return -1;
                api_buf_put(&r->rest, s, (size_t)(r->p - s));
                ++*kept;
            }
            path_pop(r, old);
            int n = peek(r);
            r->p++;
            if (n == '}') break;
            if (n != ',') return bad(r, "expected ',' or '}'");
        }
    } else {
        r->p++;
    }
    api_buf_putc(&r->rest, '}');
    return 0;
}

/* ---- the zip ------------------------------------------------------------------------------- */

typedef struct zmember {
    uint32_t crc, size, off;
    char name[NPZ_NAME + 8];
} zmember;

static void le16(unsigned char *p, unsigned v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
}

static void le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}

/* The .npy header of a (10 + its dict, padded with spaces and a newline to 64 bytes). */
static size_t npy_header(const npz_arr *a, const char *descr, size_t count, char *h, size_t cap)
{
    char shape[64];
    if (a->ndim == 2)
        snprintf(shape, sizeof shape, "(%zu, %zu)", a->cols ? count / a->cols : 0, a->cols);
    else
        snprintf(shape, sizeof shape, "(%zu,)", count);
    char dict[160];
    int n = snprintf(dict, sizeof dict, "{'descr': '%s', 'fortran_order': False, 'shape': %s, }",
                     descr, shape);
    size_t total = (10 + (size_t)n + 1 + 63) / 64 * 64;
    if (total > cap) return 0;
    memcpy(h, "\x93NUMPY\x01\x00", 8);
    le16((unsigned char *)h + 8, (unsigned)(total - 10));
    memcpy(h + 10, dict, (size_t)n);
    memset(h + 10 + n, ' ', total - 10 - (size_t)n - 1);
    h[total - 1] = '\n';
    return total;
}

/* Appends data[0..n) to the member being written. */
static void put(api_buf *out, uLong *crc, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t left = n; left;) {
        uInt step = left > (1u << 30) ? (1u << 30) : (uInt)left;
        *crc = crc32(*crc, p, step);
        p += step;
        left -= step;
    }
    api_buf_put(out, data, n);
}

/* Writes array a as member name.npy (stored: the daemon gzips what it sends when the client
 * takes gzip); 0, or -1 (out of memory, or too big for the zip). */
static int put_member(rd *r, api_buf *out, const npz_arr *a, zmember *m)
{
    const char *descr = "|u1";
    int wide = 0;
    size_t count = a->u1 ? a->u1n : a->v.n;
    if (!a->u1 && a->real) {
        descr = "<f8";
    } else if (!a->u1) {
        descr = "<i4";
        for (size_t i = 0; i < a->v.n; i++)
            if (a->v.x[i] < INT32_MIN || a->v.x[i] > INT32_MAX) wide = 1;
        if (wide) descr = "<i8";
    }
    char h[256];
    size_t hn = npy_header(a, descr, count, h, sizeof h);
    snprintf(m->name, sizeof m->name, "%s.npy", a->name);
    size_t nl = strlen(m->name);
    m->off = (uint32_t)out->len;
    char *lh = api_buf_reserve(out, 30 + nl);
    if (!lh || !hn) return nomem(r);
    out->len += 30 + nl;
    memcpy(lh + 30, m->name, nl);
    size_t start = out->len;
    uLong crc = crc32(0, NULL, 0);
    put(out, &crc, h, hn);
    if (a->u1) {
        put(out, &crc, a->u1, a->u1n);
    } else {
        unsigned char buf[NPZ_CHUNK * 8];
        for (size_t i = 0; i < count; i += NPZ_CHUNK) {
            size_t k = count - i < NPZ_CHUNK ? count - i : NPZ_CHUNK, nb;
            const double *x = a->v.x + i;
            if (a->real || wide) {
                for (size_t j = 0; j < k; j++) {
                    uint64_t u;
                    if (a->real)
                        memcpy(&u, &x[j], 8);
                    else
                        u = (uint64_t)(int64_t)x[j];
                    for (int b = 0; b < 8; b++) buf[8 * j + b] = (unsigned char)(u >> (8 * b));
                }
                nb = 8 * k;
            } else {
                for (size_t j = 0; j < k; j++) le32(buf + 4 * j, (uint32_t)(int32_t)x[j]);
                nb = 4 * k;
            }
            put(out, &crc, buf, nb);
        }
    }
    if (out->failed) return nomem(r);
    uint64_t size = out->len - start;
    if (size > UINT32_MAX || out->len > UINT32_MAX)
        return bad(r, "the result is too big for npz (4 GiB)");
    m->crc = (uint32_t)crc;
    m->size = (uint32_t)size;
    unsigned char *p = (unsigned char *)out->p + m->off;
    le32(p, 0x04034b50);
    le16(p + 4, 10);  /* version needed: 1.0 (stored) */
    le16(p + 6, 0);   /* flags */
    le16(p + 8, 0);   /* stored */
    le16(p + 10, 0);  /* 00:00 */
    le16(p + 12, 33); /* 1980-01-01 */
    le32(p + 14, m->crc);
    le32(p + 18, m->size);
    le32(p + 22, m->size);
    le16(p + 26, (unsigned)nl);
    le16(p + 28, 0);
    return 0;
}

static int central(rd *r, api_buf *out, const zmember *m, size_t n)
{
    size_t cd = out->len;
    for (size_t i = 0; i < n; i++) {
        size_t nl = strlen(m[i].name);
        unsigned char *p = (unsigned char *)api_buf_reserve(out, 46 + nl);
        if (!p) return nomem(r);
        memset(p, 0, 46);
        le32(p, 0x02014b50);
        le16(p + 4, 10);
        le16(p + 6, 10);
        le16(p + 14, 33);
        le32(p + 16, m[i].crc);
        le32(p + 20, m[i].size);
        le32(p + 24, m[i].size);
        le16(p + 28, (unsigned)nl);
        le32(p + 42, m[i].off);
        memcpy(p + 46, m[i].name, nl);
        out->len += 46 + nl;
    }
    size_t cdn = out->len - cd;
    unsigned char *e = (unsigned char *)api_buf_reserve(out, 22);
    if (!e) return nomem(r);
    if (out->len > UINT32_MAX) return bad(r, "the result is too big for npz (4 GiB)");
    memset(e, 0, 22);
    le32(e, 0x06054b50);
    le16(e + 8, (unsigned)n);
    le16(e + 10, (unsigned)n);
    le32(e + 12, (uint32_t)cdn);
    le32(e + 16, (uint32_t)cd);
    out->len += 22;
    return 0;
}

int render_npz(const char *json, size_t len, const render_opts *o, char **out, size_t *outlen,
               api_error *err)
{
    (void)o;
    *out = NULL;
    *outlen = 0;
    api_error spare;
    if (!err) err = &spare;
    err->status = API_OK;
    err->msg[0] = 0;
    rd r = {.p = json, .end = json + len, .err = err, .rc = API_OK};
    size_t kept, members;
    /* "dim" comes first in our results; look for it anyway, so V's width is known */
    const char *dp = memmem(json, len < 64 ? len : 64, "\"dim\":", 6);
    if (dp && dp + 6 < json + len && (dp[6] == '2' || dp[6] == '3')) r.dim = dp[6] - '0';
    if (peek(&r) != '{') {
        bad(&r, "expected a JSON object");
    } else if (!object(&r, "", 0, &kept, &members)) {
        if (peek(&r) != -1) bad(&r, "text after the result's object");
    }
    api_buf zo = {0};
    zmember *m = NULL;
    npz_arr *rest = NULL;
    if (r.rc == API_OK && r.rest.failed) nomem(&r);
    if (r.rc == API_OK && (rest = new_arr(&r, "", "json", 4, ""))) {
        rest->u1 = r.rest.p;
        rest->u1n = r.rest.len;
    }
    if (r.rc == API_OK && !(m = calloc(r.na, sizeof *m))) nomem(&r);
    for (size_t i = 0; r.rc == API_OK && i < r.na; i++) put_member(&r, &zo, &r.a[i], &m[i]);
    if (r.rc == API_OK) central(&r, &zo, m, r.na);
    free(m);
    for (size_t i = 0; i < r.na; i++) free(r.a[i].v.x);
    free(r.a);
    api_buf_free(&r.rest);
    if (r.rc == API_OK && zo.failed) nomem(&r);
    if (r.rc != API_OK) {
        api_buf_free(&zo);
        return r.rc;
    }
    *out = zo.p;
    *outlen = zo.len;
    return API_OK;
}
