/* larjson.c — LAR JSON out: a 2-complex (core/arr2.h) streamed into a growing buffer.
 *
 *   {"dim":2,"V":[[x,y],...],"EV":[[v0,v1],...],"FV":[[v,...],...],"FE":[[±(e+1),...],...],
 *    "holes":{"f":[[v,...],...]},"exterior":[[v,...],...],
 *    "operators":{"d1":{"shape":[V,E],"indptr":[...],"indices":[...],"data":[...]},"d2":{...}},
 *    "stats":{...}}
 *
 * Indices are 0-based.  Face f's FV row is its outer cycle, its FE row the core's signed edges
 * (outer cycle, then holes).  With exterior_last the exterior cycles follow as extra rows of FV
 * and FE (the seeds' convention); their FE rows are found by binary search in the sorted EV,
 * + when the walk goes from EV's v0 to v1, and an edge walked both ways (a dangling edge kept
 * with keep_dangling) cancels, as in the core's own FE rows.  The operators are compressed sparse
 * ROW matrices, loadable by scipy.sparse.csr_matrix((data, indices, indptr), shape):
 * d1 is V x E (column e: -1 at v0, +1 at v1), d2 is E x F with one column per FE row written
 * (so exterior rows too with exterior_last), holding the FE signs; d1·d2 = 0.
 *
 * Why not a jansson tree: a result can hold tens of millions of numbers, and a json_t per number
 * costs ten times the memory of the complex itself.  Numbers are formatted here directly, doubles
 * as the shortest of %.15g/%.16g/%.17g that reads back equal, so clients get the exact doubles.
 *
 * The writers both dimensions share are here: numbers and lists (api/api_int.h), the rows of V
 * and EV (api_buf_rows) and a holes entry's opening (api_buf_key_open, api/larjson.h);
 * api_lar2_write() writes each field by a function of its own (put_face_rows, put_holes,
 * put_exterior, put_operators, put_stats).
 *
 * Threads: reentrant, no globals.  Ownership: the complex is borrowed; the buffer is the
 * caller's (api_buf_free() frees it).
 */
#include "api/larjson.h"

#include "api/api_int.h"

#include <errno.h>

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *const api_field_names[API_NFIELDS] = {
    "V", "EV", "FV", "FE", "holes", "exterior", "stats", "operators", "membership", "result"};

int api_fields_refs(unsigned fl, const api_field_ref *rules, size_t n, const char *const *names,
                    api_error *err)
{
    for (size_t i = 0; i < n; i++) {
        const api_field_ref *r = &rules[i];
        if (!(fl & r->key) || (fl & r->any)) continue;
        unsigned k = (unsigned)__builtin_ctz(r->key), a = (unsigned)__builtin_ctz(r->any);
        unsigned rest = r->any & ~(1u << a);
        if (!rest)
            return api_fail(err, API_EINVALID,
                            "options.fields: \"%s\" refers to \"%s\", which is not named: "
                            "name it too, or leave \"%s\" out",
                            names[k], names[a], names[k]);
        return api_fail(err, API_EINVALID,
                        "options.fields: \"%s\" refers to %s, \"%s\" or \"%s\", neither of "
                        "which is named: name one, or leave \"%s\" out",
                        names[k], r->what, names[a], names[__builtin_ctz(rest)], names[k]);
    }
    return API_OK;
}

int api_lar2_fields_check(unsigned fl, api_error *err)
{
    static const api_field_ref rules[] = {{API_F_EV, API_F_V, NULL},
                                          {API_F_FV, API_F_V, NULL},
                                          {API_F_FE, API_F_EV, NULL},
                                          {API_F_HOLES, API_F_V, NULL},
                                          {API_F_HOLES, API_F_FV | API_F_FE, "the faces"},
                                          {API_F_EXTERIOR, API_F_V, NULL}};
    return api_fields_refs(fl, rules, sizeof rules / sizeof *rules, api_field_names, err);
}

/* ---- the buffer ---------------------------------------------------------------------------- */

void api_buf_section(api_buf *b)
{
    if (b->cancel && !b->canceled && atomic_load_explicit(b->cancel, memory_order_relaxed))
        b->canceled = b->failed = 1; /* as api_buf_tick: a section may have no long loop */
    if (!b->progress) return;
    unsigned n = b->nsections ? b->nsections : 1, k = b->sections < n ? b->sections : n;
    b->sections++;
    b->progress(b->udata, "output", (double)k / (double)(n + 1));
}

int api_buf_tick(api_buf *b, size_t i, size_t n)
{
    if ((i & 1023) == 0 && b->cancel && !b->canceled &&
        atomic_load_explicit(b->cancel, memory_order_relaxed))
        b->canceled = b->failed = 1; /* the writers stop: api_buf_finish says canceled */
    if (b->failed) return 1;
    if (!b->progress || (i & 8191) || !n) return 0;
    unsigned ns = b->nsections ? b->nsections : 1, k = b->sections ? b->sections - 1 : 0;
    if (k > ns) k = ns;
    b->progress(b->udata, "output", ((double)k + (double)i / (double)n) / (double)(ns + 1));
    return 0;
}

void api_buf_flush(api_buf *b)
{
    if (!b->sink || b->failed || b->len == 0) return;
    if (fwrite(b->p, 1, b->len, b->sink) != b->len) {
        b->sink_errno = errno ? errno : EIO;
        b->failed = 1;
        return;
    }
    b->sunk += b->len;
    b->len = 0;
    b->p[0] = 0;
}

int api_buf_finish(api_buf *b, int rc, char **out, size_t *outlen, api_error *err)
{
    /* the writers saw a failed buffer; or the cancel came after their last look (a run canceled
     * before it returns is canceled, whatever part of the output was written) */
    if ((rc == API_OK || rc == API_ENOMEM) &&
        (b->canceled || (b->cancel && atomic_load_explicit(b->cancel, memory_order_relaxed))))
        rc = api_fail(err, API_ECANCELED, "canceled");
    if (rc == API_OK) {
        api_buf_putc(b, '\n');
        api_buf_flush(b);
        if (b->failed) rc = api_fail(err, API_ENOMEM, "out of memory while writing the result");
    }
    if (b->sink_errno)
        rc = api_fail(err, API_EINTERNAL, "writing the result: %s", strerror(b->sink_errno));
    if (rc == API_OK) {
        *outlen = b->sink ? b->sunk : b->len;
        if (!b->sink) {
            *out = b->p;
            b->p = NULL;
        }
    }
    api_buf_free(b);
    return rc;
}

char *api_buf_reserve(api_buf *b, size_t n)
{
    if (b->failed) return NULL;
    if (b->sink && b->len > 0 && b->len + n + 1 > API_BUF_SINK) {
        api_buf_flush(b);
        if (b->failed) return NULL;
    }
    if (n > SIZE_MAX / 2 - b->len) goto fail;
    if (b->len + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        char *p;
        while (cap < b->len + n + 1) cap *= 2;
        p = realloc(b->p, cap);
        if (!p) goto fail;
        b->p = p;
        b->cap = cap;
    }
    return b->p + b->len;
fail:
    b->failed = 1;
    return NULL;
}

void api_buf_put(api_buf *b, const char *s, size_t n)
{
    char *p = api_buf_reserve(b, n);
    if (!p) return;
    memcpy(p, s, n);
    b->len += n;
    b->p[b->len] = 0;
}

void api_buf_puts(api_buf *b, const char *s)
{
    api_buf_put(b, s, strlen(s));
}

/* Writes v in decimal at p (room for 20 digits); returns the length. */
static size_t fmt_u64(uint64_t v, char *p)
{
    char tmp[20];
    size_t n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    for (size_t i = 0; i < n; i++) p[i] = tmp[n - 1 - i];
    return n;
}

void api_buf_u64(api_buf *b, uint64_t v)
{
    char *p = api_buf_reserve(b, 20);
    if (!p) return;
    b->len += fmt_u64(v, p);
    b->p[b->len] = 0;
}

void api_buf_i64(api_buf *b, int64_t v)
{
    char *p = api_buf_reserve(b, 21);
    size_t n = 0;
    if (!p) return;
    if (v < 0) p[n++] = '-';
    n += fmt_u64(v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v, p + n);
    b->len += n;
    b->p[b->len] = 0;
}

/* ---- doubles: the shortest of %.15g, %.16g, %.17g that reads back ---------------------------
 *
 * printf and strtod cost a microsecond a number (50 MB/s of output).  For 1e-6 <= |x| < 1e15
 * (coordinates, areas, volumes) the digits come from one exact product instead: x = m 2^-k
 * (m < 2^53), so X = x 10^s = m 10^s / 2^k with s chosen to put X in [10^16, 10^17) is known
 * exactly as its integer part q and remainder r / 2^k (m 10^s < 2^53 10^22 < 2^127).  Rounding
 * X to 17, 16 or 15 digits is then exact and halves go to even, as printf's %.Ng; a rounding
 * D reads back as x when it lies within half a unit in the last place of x, |D - X| <
 * 10^s / 2^(k+1), compared in integers (at exactly that distance strtod would round to the even
 * m; the rule is kept, though in this range such a midpoint, an odd 54-bit number times a power
 * of 5 over a power of 10, has 19 digits or more and is never a rounding of 16).  A power of two
 * (whose lower neighbour is half as far) and anything outside the range take printf and strtod. */

typedef __int128 fmt_i128;

api_u128 api_pow10_u128(int k) /* 0 <= k <= 38 */
{
    api_u128 r = 1;
    for (; k >= 19; k -= 19) r *= (api_u128)10000000000000000000u;
    static const uint64_t small[19] = {1,
                                       10,
                                       100,
                                       1000,
                                       10000,
                                       100000,
                                       1000000,
                                       10000000,
                                       100000000,
                                       1000000000,
                                       10000000000,
                                       100000000000,
                                       1000000000000,
                                       10000000000000,
                                       100000000000000,
                                       1000000000000000,
                                       10000000000000000,
                                       100000000000000000,
                                       1000000000000000000};
    return r * small[k];
}

size_t api_fmt_g(uint64_t d, int prec, int E, char *p)
{
    static const char two[201] =
        "00010203040506070809101112131415161718192021222324252627282930313233"
        "34353637383940414243444546474849505152535455565758596061626364656667"
        "6869707172737475767778798081828384858687888990919293949596979899";
    char dig[18], *p0 = p;
    int i = prec;
    for (; i >= 2; i -= 2, d /= 100) memcpy(dig + i - 2, two + 2 * (d % 100), 2);
    if (i) dig[0] = (char)('0' + d);
    int nd = prec;
    while (nd > 1 && dig[nd - 1] == '0') nd--; /* %g drops trailing zeros */
    if (E < -4 || E >= prec) {
        *p++ = dig[0];
        if (nd > 1) {
            *p++ = '.';
            memcpy(p, dig + 1, (size_t)nd - 1);
            p += nd - 1;
        }
        *p++ = 'e';
        *p++ = E < 0 ? '-' : '+';
        int a = E < 0 ? -E : E;
        if (a >= 100) *p++ = (char)('0' + a / 100);
        *p++ = (char)('0' + a / 10 % 10);
        *p++ = (char)('0' + a % 10);
    } else if (E >= 0) {
        for (int i = 0; i <= E; i++) *p++ = i < nd ? dig[i] : '0';
        if (nd > E + 1) {
            *p++ = '.';
            memcpy(p, dig + E + 1, (size_t)(nd - E - 1));
            p += nd - E - 1;
        }
    } else {
        *p++ = '0', *p++ = '.';
        for (int i = 0; i < -E - 1; i++) *p++ = '0';
        memcpy(p, dig, (size_t)nd);
        p += nd;
    }
    *p = 0;
    return (size_t)(p - p0);
}

/* X = q + r / 2^k rounded to prec digits (unit = 10^(17 - prec)), halves to even: when the
 * rounding reads back as x (or prec is 17), x written, else 0. */
static inline size_t fmt_try(uint64_t q, api_u128 r, int k, uint64_t m, api_u128 ten_s, int E,
                             int prec, uint64_t unit, char *p)
{
    uint64_t qd = q / unit, rem = q % unit;
    api_u128 num2 = (((api_u128)rem << k) + r) << 1, half2 = (api_u128)unit << k;
    uint64_t d = qd + (num2 > half2 || (num2 == half2 && (qd & 1)));
    if (prec < 17) { /* |d unit - X| against half the unit in the last place of x */
        fmt_i128 a = (fmt_i128)(d * unit) - (fmt_i128)q;
        fmt_i128 diff2 = ((a * ((fmt_i128)1 << k)) - (fmt_i128)r) * 2;
        api_u128 ad = (api_u128)(diff2 < 0 ? -diff2 : diff2);
        if (ad > ten_s || (ad == ten_s && (m & 1))) return 0;
    }
    if (d == 100000000000000000u / unit) d /= 10, E++; /* 99..9.5 rounds up a digit */
    return api_fmt_g(d, prec, E, p);
}

/* The fast path for x > 0; 0 when x is not in its range. */
static size_t fmt_short(double x, char *p)
{
    if (!(x >= 1e-6 && x < 1e15)) return 0;
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    uint64_t m = (bits & (((uint64_t)1 << 52) - 1)) | (uint64_t)1 << 52;
    int e2 = (int)(bits >> 52 & 0x7ff) - 1022; /* x = m 2^(e2 - 53), 2^(e2-1) <= x < 2^e2 */
    int k = 53 - e2;                           /* x = m / 2^k, 0 < k <= 73 in this range */
    if (m == (uint64_t)1 << 52) return 0;
    int E = (int)floor((e2 - 1) * 0.30102999566398120), s; /* log10 x, or one below */
    api_u128 q, r, ten_s;
    for (int tries = 0;; tries++) { /* E: 10^16 <= x 10^(16 - E) < 10^17 */
        s = 16 - E;
        if (tries == 3 || s < 0 || s > 22) return 0;
        api_u128 n = (api_u128)m * (ten_s = api_pow10_u128(s));
        q = n >> k, r = n & (((api_u128)1 << k) - 1);
        if (q >= (api_u128)100000000000000000u)
            E++;
        else if (q < (api_u128)10000000000000000u)
            E--;
        else
            break;
    }
    size_t n;
    if ((n = fmt_try((uint64_t)q, r, k, m, ten_s, E, 15, 100, p))) return n;
    if ((n = fmt_try((uint64_t)q, r, k, m, ten_s, E, 16, 10, p))) return n;
    return fmt_try((uint64_t)q, r, k, m, ten_s, E, 17, 1, p);
}

size_t api_format_double(double x, char *buf)
{
    size_t n;
    assert(isfinite(x));
    /* Integers below 1e15 print the same under %.15g: skip snprintf and strtod for them (grids,
     * counts, integer drawings). -0 prints as 0. */
    if (fabs(x) < 1e15 && x == (double)(int64_t)x) {
        int64_t i = (int64_t)x;
        n = 0;
        if (i < 0) buf[n++] = '-';
        n += fmt_u64(i < 0 ? (uint64_t)0 - (uint64_t)i : (uint64_t)i, buf + n);
        buf[n] = 0;
        return n;
    }
    n = x < 0 ? (buf[0] = '-', 1) : 0;
    size_t f = fmt_short(fabs(x), buf + n);
    if (f) return n + f;
    /* the shortest of %.15g, %.16g, %.17g that reads back as x */
    for (int prec = 15;; prec++) {
        int w = snprintf(buf, API_DOUBLE_MAX, "%.*g", prec, x);
        assert(w > 0 && w < API_DOUBLE_MAX);
        if (prec == 17 || strtod(buf, NULL) == x) return (size_t)w;
    }
}

void api_buf_double(api_buf *b, double x)
{
    char *p = api_buf_reserve(b, API_DOUBLE_MAX);
    if (!p) return;
    b->len += api_format_double(x, p);
}

/* api_buf_point's body, inline where rows of points are written (api_buf_rows). */
static inline void point_inline(api_buf *b, const double *x, int dim)
{
    api_buf_putc(b, '[');
    for (int k = 0; k < dim; k++) {
        if (k) api_buf_putc(b, ',');
        api_buf_double(b, x[k]);
    }
    api_buf_putc(b, ']');
}

void api_buf_point(api_buf *b, const double *x, int dim)
{
    point_inline(b, x, dim);
}

void api_buf_own_vertices(api_buf *b, const double *V, size_t nv, int dim, uint32_t *map)
{
    uint32_t n = 0;
    api_buf_puts(b, "\"V\":[");
    for (size_t v = 0; v < nv; v++) {
        if (!map[v]) continue;
        if (n) api_buf_putc(b, ',');
        api_buf_point(b, V + (size_t)dim * v, dim);
        map[v] = n++;
    }
    api_buf_putc(b, ']');
}

void api_buf_key_open(api_buf *b, int *first, uint64_t k)
{
    if (!*first) api_buf_putc(b, ',');
    *first = 0;
    api_buf_putc(b, '"');
    api_buf_u64(b, k);
    api_buf_puts(b, "\":[");
}

void api_buf_rows(api_buf *b, const double *V, const uint32_t *ix, size_t n, size_t k)
{
    api_buf_putc(b, '[');
    for (size_t i = 0; i < n; i++) {
        if (api_buf_tick(b, i, n)) break; /* failed, or canceled */
        if (i) api_buf_putc(b, ',');
        if (V)
            point_inline(b, V + k * i, (int)k);
        else
            api_buf_u32_list(b, ix + k * i, k);
    }
    api_buf_putc(b, ']');
}

void api_buf_free(api_buf *b)
{
    free(b->p);
    *b = (api_buf){0};
}

/* ---- rows of the complex ------------------------------------------------------------------- */

/* The FV and FE rows written: the bounded faces, then (exterior_last) the exterior cycles. */
typedef struct rows {
    const lar2 *c;
    size_t nrows; /* c->nf, plus c->next with exterior_last */
    size_t *xoff; /* owned, next+1 or NULL: exterior FE row r is xfe[xoff[r]..xoff[r+1]) */
    int32_t *xfe; /* owned */
} rows;

static size_t cycle_of(const lar2 *c, uint32_t cy, const uint32_t **v)
{
    *v = c->cyc + c->cyc_off[cy];
    return c->cyc_off[cy + 1] - c->cyc_off[cy];
}

static size_t fv_row(const rows *r, size_t f, const uint32_t **v)
{
    const lar2 *c = r->c;
    return cycle_of(c, f < c->nf ? c->face_cycle[f] : c->ext_cyc[f - c->nf], v);
}

static size_t fe_row(const rows *r, size_t f, const int32_t **e)
{
    const lar2 *c = r->c;
    if (f < c->nf) {
        *e = c->fe + c->fe_off[f];
        return c->fe_off[f + 1] - c->fe_off[f];
    }
    f -= c->nf;
    *e = r->xfe + r->xoff[f];
    return r->xoff[f + 1] - r->xoff[f];
}

/* The index of edge {a, b} in the sorted EV, or -1. */
static int64_t edge_find(const lar2 *c, uint32_t a, uint32_t b)
{
    uint32_t lo_v = a < b ? a : b, hi_v = a < b ? b : a;
    size_t lo = 0, hi = c->ne;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        const uint32_t *e = c->EV + 2 * mid;
        if (e[0] < lo_v || (e[0] == lo_v && e[1] < hi_v))
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo < c->ne && c->EV[2 * lo] == lo_v && c->EV[2 * lo + 1] == hi_v) return (int64_t)lo;
    return -1;
}

static int cmp_i32(const void *a, const void *b)
{
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return (x > y) - (x < y);
}

/* Computes the FE rows of the exterior cycles into r->xoff, r->xfe. */
static int exterior_rows(rows *r, api_error *err)
{
    const lar2 *c = r->c;
    size_t total = 0, maxlen = 0, w = 0;
    int32_t *sorted = NULL;
    int rc;
    for (size_t x = 0; x < c->next; x++) {
        const uint32_t *v;
        size_t k = cycle_of(c, c->ext_cyc[x], &v);
        total += k;
        if (k > maxlen) maxlen = k;
    }
    r->xoff = malloc((c->next + 1) * sizeof *r->xoff);
    r->xfe = malloc((total ? total : 1) * sizeof *r->xfe);
    sorted = malloc((maxlen ? maxlen : 1) * sizeof *sorted);
    if (!r->xoff || !r->xfe || !sorted) {
        rc = api_fail(err, API_ENOMEM, "out of memory while writing the result");
        goto fail;
    }
    for (size_t x = 0; x < c->next; x++) {
        const uint32_t *v;
        size_t k = cycle_of(c, c->ext_cyc[x], &v);
        r->xoff[x] = w;
        for (size_t i = 0; i < k; i++) {
            uint32_t a = v[i], b = v[(i + 1) % k];
            int64_t e = edge_find(c, a, b);
            if (e < 0) {
                rc = api_fail(err, API_EINTERNAL,
                              "internal error: exterior cycle %zu walks %u-%u, not an edge", x,
                              (unsigned)a, (unsigned)b);
                goto fail;
            }
            sorted[i] = a < b ? (int32_t)(e + 1) : -(int32_t)(e + 1);
        }
        memcpy(r->xfe + w, sorted, k * sizeof *sorted);
        qsort(sorted, k, sizeof *sorted, cmp_i32);
        for (size_t i = 0; i < k; i++) { /* keep the walk's order, drop edges walked both ways */
            int32_t s = r->xfe[r->xoff[x] + i], neg = -s;
            if (!bsearch(&neg, sorted, k, sizeof *sorted, cmp_i32)) r->xfe[w++] = s;
        }
    }
    r->xoff[c->next] = w;
    free(sorted);
    return API_OK;
fail:
    free(sorted);
    free(r->xoff);
    free(r->xfe);
    r->xoff = NULL;
    r->xfe = NULL;
    return rc;
}

/* Checks the indices the writer follows, so that a bug in the core is a 500, not a crash. */
static int check_complex(const lar2 *c, api_error *err)
{
    const char *what = NULL;
    if (c->nv && !c->V) what = "V";
    for (size_t i = 0; !what && i < 2 * c->ne; i++)
        if (c->EV[i] >= c->nv) what = "EV";
    for (size_t i = 0; !what && i + 1 < c->ncyc + 1; i++)
        if (c->cyc_off[i] > c->cyc_off[i + 1]) what = "cyc_off";
    for (size_t i = 0; !what && c->ncyc && i < c->cyc_off[c->ncyc]; i++)
        if (c->cyc[i] >= c->nv) what = "cyc";
    for (size_t f = 0; !what && f < c->nf; f++) {
        if (c->face_cycle[f] >= c->ncyc) what = "face_cycle";
        if (c->hole_off[f] > c->hole_off[f + 1] || c->fe_off[f] > c->fe_off[f + 1])
            what = "hole_off/fe_off";
    }
    for (size_t i = 0; !what && c->nf && i < c->hole_off[c->nf]; i++)
        if (c->hole_cyc[i] >= c->ncyc) what = "hole_cyc";
    for (size_t i = 0; !what && c->nf && i < c->fe_off[c->nf]; i++)
        if (c->fe[i] == 0 || (size_t)llabs(c->fe[i]) > c->ne) what = "fe";
    for (size_t i = 0; !what && i < c->next; i++)
        if (c->ext_cyc[i] >= c->ncyc) what = "ext_cyc";
    if (what)
        return api_fail(err, API_EINTERNAL, "internal error: the complex's %s is invalid", what);
    return API_OK;
}

/* ---- writers ------------------------------------------------------------------------------- */

void api_buf_u32_list(api_buf *b, const uint32_t *a, size_t n)
{
    api_buf_putc(b, '[');
    for (size_t i = 0; i < n; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_u64(b, a[i]);
    }
    api_buf_putc(b, ']');
}

void api_put_membership(api_buf *b, size_t nrows, size_t ninputs, const uint32_t *off,
                        const uint32_t *idx)
{
    api_put_membership_w(b, nrows, ninputs, off, idx, NULL);
}

int api_membership_plain(size_t nrows, const uint32_t *off, const int32_t *wind)
{
    for (size_t i = 0; wind && i < off[nrows]; i++)
        if (wind[i] != 1) return 0;
    return 1;
}

void api_put_membership_w(api_buf *b, size_t nrows, size_t ninputs, const uint32_t *off,
                          const uint32_t *idx, const int32_t *wind)
{
    int plain = api_membership_plain(nrows, off, wind);
    api_buf_section(b);
    api_buf_puts(b, ",\"membership\":{\"format\":\"csr\",\"shape\":[");
    api_buf_u64(b, nrows);
    api_buf_putc(b, ',');
    api_buf_u64(b, ninputs);
    api_buf_puts(b, "],\"indptr\":");
    api_buf_u32_list(b, off, nrows + 1);
    api_buf_puts(b, ",\"indices\":");
    api_buf_u32_list(b, idx, off[nrows]);
    if (!plain) {
        api_buf_puts(b, ",\"data\":");
        api_buf_i32_list(b, wind, off[nrows]);
    }
    api_buf_putc(b, '}');
}

/* api_buf_i32_list's body, inline where rows of them are written (put_face_rows). */
static inline void i32_list_inline(api_buf *b, const int32_t *a, size_t n)
{
    api_buf_putc(b, '[');
    for (size_t i = 0; i < n; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_i64(b, a[i]);
    }
    api_buf_putc(b, ']');
}

void api_buf_i32_list(api_buf *b, const int32_t *a, size_t n)
{
    i32_list_inline(b, a, n);
}

static void put_key(api_buf *b, int *first, const char *key)
{
    if (!*first) api_buf_putc(b, ',');
    *first = 0;
    api_buf_putc(b, '"');
    api_buf_puts(b, key);
    api_buf_puts(b, "\":");
}

/* A top-level key: a section of the output's progress. */
static void put_field(api_buf *b, int *first, const char *key)
{
    api_buf_section(b);
    put_key(b, first, key);
}

static void put_stats(api_buf *b, const arr2_stats *s, const api_lar2_fmt *fmt)
{
    static const char *const names[] = {"input_segments",
                                        "zero_length_dropped",
                                        "intersections",
                                        "hot_pixels",
                                        "pairs_tested",
                                        "buckets",
                                        "dangling_removed",
                                        "V",
                                        "E",
                                        "F",
                                        "components",
                                        "blocks"};
    const size_t counts[] = {s->input_segments,
                             s->zero_length,
                             s->intersections,
                             s->hot_pixels,
                             s->pairs_tested,
                             s->buckets,
                             s->dangling_removed,
                             s->nv,
                             s->ne,
                             s->nf,
                             s->components,
                             s->blocks};
    static const char *const ms_names[] = {"snap",        "buckets", "intersect", "split", "graph",
                                           "biconnected", "faces",   "holes",     "total"};
    const double ms[] = {s->ms_snap,  s->ms_buckets, s->ms_intersect,
                         s->ms_split, s->ms_graph,   s->ms_biconnected,
                         s->ms_faces, s->ms_holes,   s->ms_total};
    int first = 1;
    api_buf_putc(b, '{');
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; i++) {
        put_key(b, &first, names[i]);
        api_buf_u64(b, counts[i]);
    }
    put_key(b, &first, "precision");
    api_buf_double(b, isfinite(s->precision) ? s->precision : 0);
    put_key(b, &first, "ms");
    first = 1;
    api_buf_putc(b, '{');
    for (size_t i = 0; i < sizeof ms / sizeof ms[0]; i++) {
        put_key(b, &first, ms_names[i]);
        api_buf_double(b, isfinite(ms[i]) ? ms[i] : 0);
    }
    api_buf_putc(b, '}');
    if (fmt->stats_more) fmt->stats_more(b, fmt->stats_udata);
    api_buf_putc(b, '}');
}

void api_buf_csr(api_buf *b, size_t nrows, size_t ncols, const size_t *indptr,
                 const uint32_t *indices, const int8_t *data)
{
    api_buf_puts(b, "{\"shape\":[");
    api_buf_u64(b, nrows);
    api_buf_putc(b, ',');
    api_buf_u64(b, ncols);
    api_buf_puts(b, "],\"indptr\":[");
    for (size_t i = 0; i <= nrows; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_u64(b, indptr[i]);
    }
    api_buf_puts(b, "],\"indices\":");
    api_buf_u32_list(b, indices, indptr[nrows]);
    api_buf_puts(b, ",\"data\":[");
    for (size_t i = 0; i < indptr[nrows]; i++) {
        if (i) api_buf_putc(b, ',');
        api_buf_puts(b, data[i] > 0 ? "1" : "-1");
    }
    api_buf_puts(b, "]}");
}

void api_csr_free(api_csr *m)
{
    free(m->ptr);
    free(m->idx);
    free(m->val);
    *m = (api_csr){0};
}

/* The operators d1 (V x E) and d2 (E x rows) as CSR into m[0], m[1] (the caller frees them
 * with api_csr_free, success or not). */
static int lar2_operators(const rows *r, api_csr m[2], api_error *err)
{
    const lar2 *c = r->c;
    size_t nnz2 = 0;
    for (size_t f = 0; f < r->nrows; f++) {
        const int32_t *e;
        nnz2 += fe_row(r, f, &e);
    }
    m[0] = (api_csr){c->nv, c->ne, calloc(c->nv + 1, sizeof *m[0].ptr),
                     malloc((2 * c->ne + 1) * sizeof *m[0].idx), malloc(2 * c->ne + 1)};
    m[1] = (api_csr){c->ne, r->nrows, calloc(c->ne + 1, sizeof *m[1].ptr),
                     malloc((nnz2 + 1) * sizeof *m[1].idx), malloc(nnz2 + 1)};
    size_t *fill = malloc(((c->nv > c->ne ? c->nv : c->ne) + 1) * sizeof *fill);
    if (!fill || !m[0].ptr || !m[0].idx || !m[0].val || !m[1].ptr || !m[1].idx || !m[1].val) {
        free(fill);
        return api_fail(err, API_ENOMEM, "out of memory while writing the operators");
    }
    /* d1: row v holds edge e with -1 when v is EV's v0, +1 when it is v1; edges are visited in
     * order, so every row's indices come out sorted. */
    size_t *ptr = m[0].ptr;
    for (size_t e = 0; e < c->ne; e++) ptr[c->EV[2 * e] + 1]++, ptr[c->EV[2 * e + 1] + 1]++;
    for (size_t v = 0; v < c->nv; v++) ptr[v + 1] += ptr[v];
    memcpy(fill, ptr, (c->nv + 1) * sizeof *fill);
    for (size_t e = 0; e < c->ne; e++) {
        size_t k0 = fill[c->EV[2 * e]]++, k1 = fill[c->EV[2 * e + 1]]++;
        m[0].idx[k0] = (uint32_t)e, m[0].val[k0] = -1;
        m[0].idx[k1] = (uint32_t)e, m[0].val[k1] = 1;
    }
    /* d2: row e holds the FE rows (faces) that contain ±(e+1), with that sign. */
    ptr = m[1].ptr;
    for (size_t f = 0; f < r->nrows; f++) {
        const int32_t *e;
        size_t k = fe_row(r, f, &e);
        for (size_t i = 0; i < k; i++) ptr[(size_t)llabs(e[i])]++;
    }
    for (size_t e = 0; e < c->ne; e++) ptr[e + 1] += ptr[e];
    memcpy(fill, ptr, (c->ne + 1) * sizeof *fill);
    for (size_t f = 0; f < r->nrows; f++) {
        const int32_t *e;
        size_t k = fe_row(r, f, &e);
        for (size_t i = 0; i < k; i++) {
            size_t at = fill[(size_t)llabs(e[i]) - 1]++;
            m[1].idx[at] = (uint32_t)f;
            m[1].val[at] = e[i] > 0 ? 1 : -1;
        }
    }
    free(fill);
    return API_OK;
}

/* Writes the operators d1 (V x E) and d2 (E x rows) as CSR. */
static int put_operators(api_buf *b, const rows *r, api_error *err)
{
    api_csr m[2] = {0};
    int rc = lar2_operators(r, m, err);
    if (rc == API_OK) {
        api_buf_puts(b, "{\"d1\":");
        api_buf_csr(b, m[0].nrows, m[0].ncols, m[0].ptr, m[0].idx, m[0].val);
        api_buf_puts(b, ",\"d2\":");
        api_buf_csr(b, m[1].nrows, m[1].ncols, m[1].ptr, m[1].idx, m[1].val);
        api_buf_putc(b, '}');
    }
    api_csr_free(&m[0]);
    api_csr_free(&m[1]);
    return rc;
}

/* FV's rows, or with fe FE's (with exterior_last the exterior cycles after the faces'). */
static void put_face_rows(api_buf *b, const rows *r, int fe)
{
    api_buf_putc(b, '[');
    for (size_t f = 0; f < r->nrows; f++) {
        const uint32_t *v;
        const int32_t *e;
        if (api_buf_tick(b, f, r->nrows)) break; /* failed, or canceled */
        if (f) api_buf_putc(b, ',');
        if (fe) {
            size_t n = fe_row(r, f, &e); /* before e is read: arguments have no order */
            i32_list_inline(b, e, n);
        } else {
            size_t n = fv_row(r, f, &v);
            api_buf_u32_list(b, v, n);
        }
    }
    api_buf_putc(b, ']');
}

/* "holes": {"f": [cycle, ...]} of the faces with holes. */
static void put_holes(api_buf *b, const lar2 *c)
{
    int first = 1;
    api_buf_putc(b, '{');
    for (size_t f = 0; f < c->nf; f++) {
        if (c->hole_off[f] == c->hole_off[f + 1]) continue;
        api_buf_key_open(b, &first, f);
        for (size_t h = c->hole_off[f]; h < c->hole_off[f + 1]; h++) {
            const uint32_t *v;
            size_t k = cycle_of(c, c->hole_cyc[h], &v);
            if (h > c->hole_off[f]) api_buf_putc(b, ',');
            api_buf_u32_list(b, v, k);
        }
        api_buf_putc(b, ']');
    }
    api_buf_putc(b, '}');
}

/* "exterior": the exterior cycles. */
static void put_exterior(api_buf *b, const lar2 *c)
{
    api_buf_putc(b, '[');
    for (size_t x = 0; x < c->next; x++) {
        const uint32_t *v;
        size_t k = cycle_of(c, c->ext_cyc[x], &v);
        if (x) api_buf_putc(b, ',');
        api_buf_u32_list(b, v, k);
    }
    api_buf_putc(b, ']');
}

int api_lar2_write(api_buf *b, const lar2 *c, const api_lar2_fmt *fmt, api_error *err)
{
    rows r = {.c = c, .nrows = c->nf};
    unsigned fl = fmt->fields;
    int first = 0, rc;
    rc = check_complex(c, err);
    if (rc != API_OK) return rc;
    if (fmt->exterior_last && (fl & (API_F_FV | API_F_FE | API_F_OPERATORS))) {
        rc = exterior_rows(&r, err);
        if (rc != API_OK) return rc;
        r.nrows += c->next;
    }
    b->nsections = (unsigned)__builtin_popcount(fl) + 2;
    api_buf_puts(b, "{\"dim\":2");
    if (fl & API_F_V) {
        put_field(b, &first, "V");
        api_buf_rows(b, c->V, NULL, c->nv, 2);
    }
    if (fl & API_F_EV) {
        put_field(b, &first, "EV");
        api_buf_rows(b, NULL, c->EV, c->ne, 2);
    }
    if (fl & API_F_FV) {
        put_field(b, &first, "FV");
        put_face_rows(b, &r, 0);
    }
    if (fl & API_F_FE) {
        put_field(b, &first, "FE");
        put_face_rows(b, &r, 1);
    }
    if (fl & API_F_HOLES) {
        put_field(b, &first, "holes");
        put_holes(b, c);
    }
    if (fl & API_F_EXTERIOR) {
        put_field(b, &first, "exterior");
        put_exterior(b, c);
    }
    if (fl & API_F_OPERATORS) {
        put_field(b, &first, "operators");
        rc = put_operators(b, &r, err);
        if (rc != API_OK) goto out;
    }
    if (fl & API_F_STATS) {
        put_field(b, &first, "stats");
        put_stats(b, &c->stats, fmt);
    }
    if (fmt->more) fmt->more(b, fmt->more_udata);
    api_buf_putc(b, '}');
    if (b->failed) rc = api_fail(err, API_ENOMEM, "out of memory while writing the result");
out:
    free(r.xoff);
    free(r.xfe);
    return rc;
}

/* ---- arrays out (the library) ---------------------------------------------------------------- */

_Static_assert(sizeof(size_t) == sizeof(uint64_t), "CSR offsets are handed out as uint64");

int api_arrays_csr(api_arrays *out, const char *name, api_csr *m)
{
    char nm[96];
    uint64_t *shape = malloc(2 * sizeof *shape);
    int bad = !shape;
    size_t nnz = m->ptr ? m->ptr[m->nrows] : 0;
    if (shape) shape[0] = m->nrows, shape[1] = m->ncols;
    snprintf(nm, sizeof nm, "%s.shape", name);
    api_arrays_put(out, &bad, nm, API_A_U64, 2, 1, shape, 1);
    snprintf(nm, sizeof nm, "%s.indptr", name);
    api_arrays_put(out, &bad, nm, API_A_U64, m->nrows + 1, 1, m->ptr, 1);
    snprintf(nm, sizeof nm, "%s.indices", name);
    api_arrays_put(out, &bad, nm, API_A_U32, nnz, 1, m->idx, 1);
    snprintf(nm, sizeof nm, "%s.data", name);
    api_arrays_put(out, &bad, nm, API_A_I8, nnz, 1, m->val, 1);
    *m = (api_csr){0};
    return bad ? -1 : 0;
}

/* The JSON of what is not an array: dim and, with the fields' stats, the stats. */
static int stats_json(api_arrays *out, const lar2 *c, const api_lar2_fmt *fmt, api_error *err)
{
    api_buf b = {0};
    int first = 0;
    api_buf_puts(&b, "{\"dim\":2");
    if (fmt->fields & API_F_STATS) {
        put_key(&b, &first, "stats");
        put_stats(&b, &c->stats, fmt);
    }
    api_buf_putc(&b, '}');
    if (b.failed) {
        api_buf_free(&b);
        return api_fail(err, API_ENOMEM, "out of memory");
    }
    api_arrays_json(out, 2, b.p);
    return API_OK;
}

int api_lar2_arrays(api_arrays *out, const lar2 *c, const api_lar2_fmt *fmt, api_error *err)
{
    static const uint32_t zero = 0;
    rows r = {.c = c, .nrows = c->nf};
    unsigned fl = fmt->fields;
    int rc = check_complex(c, err), bad = 0;
    if (rc != API_OK) return rc;
    if (fl & API_F_V) api_arrays_put(out, &bad, "V", API_A_F64, c->nv, 2, c->V, 0);
    if (fl & API_F_EV) api_arrays_put(out, &bad, "EV", API_A_U32, c->ne, 2, c->EV, 0);
    if (fl & API_F_FV)
        bad = bad ||
              api_arrays_cycles(out, "FV", c->cyc_off, c->cyc, c->face_cycle, NULL, c->nf, NULL);
    if (fl & API_F_FE) {
        api_arrays_put(out, &bad, "FE.indptr", API_A_U32, c->nf + 1, 1, c->nf ? c->fe_off : &zero,
                       0);
        api_arrays_put(out, &bad, "FE.indices", API_A_I32, c->nf ? c->fe_off[c->nf] : 0, 1, c->fe,
                       0);
    }
    if (fl & API_F_HOLES)
        api_arrays_holes(out, &bad, "holes", c->nf, c->hole_off, c->hole_cyc, c->cyc_off, c->cyc,
                         NULL);
    if (fl & API_F_EXTERIOR)
        bad = bad || api_arrays_cycles(out, "exterior", c->cyc_off, c->cyc, c->ext_cyc, NULL,
                                       c->next, NULL);
    if (!bad && (fl & API_F_OPERATORS)) {
        api_csr m[2] = {0};
        rc = lar2_operators(&r, m, err);
        if (rc != API_OK) {
            api_csr_free(&m[0]);
            api_csr_free(&m[1]);
            return rc;
        }
        bad = api_arrays_csr(out, "operators.d1", &m[0]);
        bad = api_arrays_csr(out, "operators.d2", &m[1]) || bad;
    }
    if (bad) return api_fail(err, API_ENOMEM, "out of memory");
    return stats_json(out, c, fmt, err);
}
