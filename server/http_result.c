/* http_result.c — the answers about results and jobs (see http_int.h): content negotiation
 * (Accept and ?format= pick JSON or a rendering of it, with the drawing options), the ETag of
 * each representation, a stored result sent as it is read (a chunk at a time, gzipped as it
 * goes), a job's state as JSON with Retry-After, and Prefer: wait (the connection suspended
 * until the job ends or the wait runs out).
 *
 * Threads: MHD's threads, on a connection not suspended.
 */
#include "server/http_int.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#include "server/log.h"

/* The strong ETag of a result's representation: its hash, the rendering's suffix, and "-gz"
 * when it goes gzipped (every representation has its own). */
static void result_etag(const conn *c, const char *hash, char *etag, size_t n)
{
    snprintf(etag, n, "\"%s%s%s\"", hash, c->rep, c->gz ? "-gz" : "");
}

/* Sends r, a result's representation (gzipped already when c->gz), with its cache headers. */
static enum MHD_Result send_result(conn *c, const char *hash, struct MHD_Response *r,
                                   const char *ctype, const char *job_id, const char *cache)
{
    char etag[120], loc[CONFIG_PREFIX_MAX + 100] = "", applied[40];
    result_etag(c, hash, etag, sizeof etag);
    if (c->route != ROUTE_RESULT) http_link_to(c, loc, sizeof loc, "/v1/results/%s", hash);
    snprintf(applied, sizeof applied, "wait=%g", c->wait_applied);
    hdr hs[] = {{MHD_HTTP_HEADER_ETAG, etag},
                {MHD_HTTP_HEADER_CACHE_CONTROL, "public, max-age=31536000, immutable"},
                {MHD_HTTP_HEADER_VARY, "Accept, Accept-Encoding"},
                {c->gz ? MHD_HTTP_HEADER_CONTENT_ENCODING : NULL, "gzip"},
                {c->route == ROUTE_RESULT ? NULL : MHD_HTTP_HEADER_LOCATION, loc},
                {c->route == ROUTE_RESULT ? NULL : MHD_HTTP_HEADER_CONTENT_LOCATION, loc},
                {"X-Cellar-Job", job_id},
                {"X-Cellar-Cache", cache},
                {c->wait_applied > 0 ? MHD_HTTP_HEADER_PREFERENCE_APPLIED : NULL, applied}};
    return http_queue(c, 200, ctype, r, hs, sizeof hs / sizeof *hs);
}

/* Why a picture or map of a result of len bytes is not drawn here (a 422), into msg (200). */
static void too_large_msg(const conn *c, uint64_t len, char *msg)
{
    snprintf(msg, 200,
             "the result is %llu bytes: its %s form is made of results up to %lu bytes; "
             "ask for application/json",
             (unsigned long long)len, c->fmt->name, c->fmt->max);
}

static enum MHD_Result too_large_to_draw(conn *c, uint64_t len)
{
    char msg[200];
    too_large_msg(c, len, msg);
    return http_problem(c, 422, msg, NULL, NULL);
}

/* Pictures drawn lately, by the ETag of their representation (the result's hash, the format,
 * the options, gzip): a picture asked for again is sent as it was made, with no second draw.
 * A result is immutable, so a kept picture is never stale; it is sent only after the result
 * was found in the store (result_size), as a drawn one is.  Direct-mapped, as the memo. */
#define DRAWN_SLOTS     64
#define DRAWN_MAX_BYTES ((size_t)1 << 20) /* a larger picture is not kept */
typedef struct drawn_slot {
    char etag[120]; /* "" when empty */
    char *body;     /* malloc'd */
    size_t len;
} drawn_slot;

static size_t drawn_index(const char *etag)
{
    uint64_t h = 1469598103934665603ull; /* FNV-1a */
    for (const char *p = etag; *p; p++) h = (h ^ (unsigned char)*p) * 1099511628211ull;
    return (size_t)(h % DRAWN_SLOTS);
}

/* Keeps a copy of the picture body[0..len) of etag (nothing when out of memory). */
static void drawn_put(http_server *h, const char *etag, const char *body, size_t len)
{
    char *copy = len <= DRAWN_MAX_BYTES ? malloc(len ? len : 1) : NULL;
    if (!copy) return;
    memcpy(copy, body, len);
    pthread_mutex_lock(&h->drawn_mu);
    if (!h->drawn) h->drawn = calloc(DRAWN_SLOTS, sizeof *h->drawn);
    drawn_slot *s = h->drawn ? &h->drawn[drawn_index(etag)] : NULL;
    if (s) {
        free(s->body);
        snprintf(s->etag, sizeof s->etag, "%s", etag);
        s->body = copy;
        s->len = len;
        copy = NULL;
    }
    pthread_mutex_unlock(&h->drawn_mu);
    free(copy);
}

/* A copy of the picture of etag when it is kept (malloc'd, *len its bytes), else NULL. */
static char *drawn_get(http_server *h, const char *etag, size_t *len)
{
    char *copy = NULL;
    pthread_mutex_lock(&h->drawn_mu);
    const drawn_slot *s = h->drawn ? &h->drawn[drawn_index(etag)] : NULL;
    if (s && s->body && !strcmp(s->etag, etag) && (copy = malloc(s->len ? s->len : 1))) {
        memcpy(copy, s->body, s->len);
        *len = s->len;
    }
    pthread_mutex_unlock(&h->drawn_mu);
    return copy;
}

void http_drawn_free(http_server *h)
{
    for (size_t i = 0; h->drawn && i < DRAWN_SLOTS; i++) free(h->drawn[i].body);
    free(h->drawn);
    h->drawn = NULL;
}

/* Whether c asks for a rendering of the result rather than its JSON. */
static int rendered(const conn *c)
{
    return c->fmt && c->fmt->render;
}

/* A result's JSON (taken) with its cache headers (a rendering is drawn by http_draw, on an
 * intake thread, and sent by http_send_drawn). */
static enum MHD_Result respond_result(conn *c, const char *hash, char *body, size_t len,
                                      const char *job_id, const char *cache)
{
    const char *ctype = "application/json";
    if (c->gz) { /* every result goes gzipped to such a client (its ETag says so) */
        size_t zl = 0;
        char *z = http_gzip_buf(body, len, 1, &zl);
        free(body);
        if (!z) return http_problem(c, 503, "out of memory", "5", NULL);
        body = z;
        len = zl;
    }
    struct MHD_Response *r = MHD_create_response_from_buffer(len, body, MHD_RESPMEM_MUST_FREE);
    if (!r) {
        free(body);
        return MHD_NO;
    }
    return send_result(c, hash, r, ctype, job_id, cache);
}

/* A stored result sent as it is read, a chunk at a time: its reader. */
typedef struct result_reader {
    store *st;
    char hash[65];
    uint64_t size;
    char *chunk; /* the chunk read last: bytes [start, start + len) of the result */
    size_t len;
    uint64_t start;
} result_reader;

static ssize_t result_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    result_reader *rr = cls;
    char err[256];
    if (pos >= rr->size) return MHD_CONTENT_READER_END_OF_STREAM;
    if (!rr->chunk || pos < rr->start || pos - rr->start >= rr->len) {
        free(rr->chunk);
        rr->chunk = NULL;
        int rc = rr->st->ops->result_chunk(rr->st, rr->hash, pos, &rr->chunk, &rr->len, &rr->start,
                                           err, sizeof err);
        if (rc == STORE_OK && rr->start + rr->len > rr->size) {
            rc = STORE_ERR;
            snprintf(err, sizeof err, "a chunk ends past the result's %llu bytes",
                     (unsigned long long)rr->size);
        }
        if (rc != STORE_OK) {
            char at[32];
            log_kv(rc == STORE_DAMAGED ? LOG_ERROR : LOG_WARN, "a result stopped while it was sent",
                   "hash", rr->hash, "byte", log_num(at, (double)pos), "error",
                   rc == STORE_NOTFOUND ? "evicted meanwhile" : err, NULL);
            return MHD_CONTENT_READER_END_WITH_ERROR;
        }
    }
    size_t n = rr->len - (size_t)(pos - rr->start);
    if (n > max) n = max;
    memcpy(buf, rr->chunk + (pos - rr->start), n);
    return (ssize_t)n;
}

static void result_reader_free(void *cls)
{
    result_reader *rr = cls;
    free(rr->chunk);
    free(rr);
}

/* The same, gzipped as it is read (its compressed size unknown: sent chunked). */
typedef struct gz_reader {
    result_reader *rr;
    z_stream z;
    uint64_t in_pos; /* bytes of the result read */
    int eof, finished;
    char in[64 * 1024];
} gz_reader;

static ssize_t gz_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    gz_reader *g = cls;
    (void)pos;
    if (g->finished) return MHD_CONTENT_READER_END_OF_STREAM;
    g->z.next_out = (Bytef *)buf;
    g->z.avail_out = (uInt)(max > (1u << 30) ? (1u << 30) : max);
    while (g->z.avail_out > 0 && !g->finished) {
        if (g->z.avail_in == 0 && !g->eof) {
            ssize_t n = result_read(g->rr, g->in_pos, g->in, sizeof g->in);
            if (n == MHD_CONTENT_READER_END_WITH_ERROR) return n;
            if (n == MHD_CONTENT_READER_END_OF_STREAM || n == 0) {
                g->eof = 1;
            } else {
                g->z.next_in = (Bytef *)g->in;
                g->z.avail_in = (uInt)n;
                g->in_pos += (uint64_t)n;
            }
        }
        int rc = deflate(&g->z, g->eof ? Z_FINISH : Z_NO_FLUSH);
        if (rc == Z_STREAM_END)
            g->finished = 1;
        else if (rc != Z_OK && rc != Z_BUF_ERROR)
            return MHD_CONTENT_READER_END_WITH_ERROR;
    }
    size_t made = (size_t)((char *)g->z.next_out - buf);
    if (!made && g->finished) return MHD_CONTENT_READER_END_OF_STREAM;
    return (ssize_t)made;
}

static void gz_reader_free(void *cls)
{
    gz_reader *g = cls;
    deflateEnd(&g->z);
    result_reader_free(g->rr);
    free(g);
}

/* The answer to a store error rc (not STORE_OK, err its message) about result `hash`, into
 * *pl (PLAN_PROBLEM).  post: the answer to a POST (a result evicted since it was found or made
 * is then "try again", not "not found"). */
static void store_plan(plan *pl, int rc, const char *err, const char *hash, const char *job_id,
                       int post)
{
    if (rc == STORE_DAMAGED) {
        log_kv(LOG_ERROR, "a stored result was damaged: dropped", "hash", hash, "error", err, NULL);
        return http_plan_problem(pl, 500,
                                 "the stored result was damaged (it no longer matches its "
                                 "digest) and has been dropped: post the request again",
                                 NULL);
    }
    if (rc == STORE_NOTFOUND && post)
        return http_plan_problem(pl, 503, "the result was evicted as it was read: try again", "1");
    if (rc == STORE_NOTFOUND)
        return http_plan_problem(pl, 404,
                                 job_id ? "the result was evicted from the cache: post the "
                                          "request again"
                                        : "no result with this hash",
                                 NULL);
    http_plan_problem(pl, 503, err, "5");
}

static enum MHD_Result store_problem(conn *c, int rc, const char *err, const char *hash,
                                     const char *job_id, int post)
{
    plan pl;
    store_plan(&pl, rc, err, hash, job_id, post);
    return http_problem(c, pl.status, pl.msg, pl.retry, NULL);
}

/* Draws the stored result c->plan names (PLAN_DRAW), on an intake thread (no MHD call): reads
 * it, parses and draws it (c->fmt, c->ro), gzips the picture for a client that takes gzip.
 * c->plan becomes PLAN_DRAWN (the bytes to send) or PLAN_PROBLEM. */
void http_draw(conn *c)
{
    plan *pl = &c->plan;
    store *st = c->h->st;
    char err[256], msg[200], *body = NULL, *pic = NULL;
    size_t len = 0, piclen = 0;
    api_error ae;
    int rc = st->ops->result_get(st, pl->hash, &body, &len, err, sizeof err);
    if (rc != STORE_OK)
        return store_plan(pl, rc, err, pl->hash, pl->job_id[0] ? pl->job_id : NULL, pl->post);
    if (len > c->fmt->max) {
        free(body);
        too_large_msg(c, len, msg);
        return http_plan_problem(pl, 422, msg, NULL);
    }
    rc = c->fmt->render(body, len, &c->ro, &pic, &piclen, &ae);
    free(body);
    if (rc != API_OK) return http_plan_problem(pl, (unsigned)rc, ae.msg, NULL);
    if (c->gz) { /* every result goes gzipped to such a client (its ETag says so) */
        size_t zl = 0;
        char *z = http_gzip_buf(pic, piclen, 1, &zl);
        free(pic);
        if (!z) return http_plan_problem(pl, 503, "out of memory", "5");
        pic = z;
        piclen = zl;
    }
    char etag[120];
    result_etag(c, pl->hash, etag, sizeof etag);
    drawn_put(c->h, etag, pic, piclen);
    pl->kind = PLAN_DRAWN;
    pl->body = pic;
    pl->len = piclen;
}

/* The picture http_draw made (c->plan PLAN_DRAWN), with its cache headers. */
enum MHD_Result http_send_drawn(conn *c)
{
    plan *pl = &c->plan;
    char *body = pl->body;
    pl->body = NULL;
    struct MHD_Response *r = MHD_create_response_from_buffer(pl->len, body, MHD_RESPMEM_MUST_FREE);
    if (!r) {
        free(body);
        return MHD_NO;
    }
    return send_result(c, pl->hash, r, c->fmt->media, pl->job_id[0] ? pl->job_id : NULL, pl->cache);
}

/* A stored result of `size` bytes (from result_size), as JSON (streamed when larger than a
 * chunk) or rendered; post as for store_problem. */
enum MHD_Result http_serve_stored(conn *c, const char *hash, uint64_t size, const char *job_id,
                                  const char *cache, int post)
{
    char err[256];
    char *body = NULL;
    size_t len = 0;
    store *st = c->h->st;
    if (rendered(c) && size > c->fmt->max) return too_large_to_draw(c, size);
    if (rendered(c)) { /* drawn on an intake thread: parsing never runs on an HTTP thread */
        char etag[120];
        size_t dlen = 0;
        result_etag(c, hash, etag, sizeof etag);
        char *d = drawn_get(c->h, etag, &dlen);
        if (d) { /* drawn lately: sent as it was made */
            struct MHD_Response *r =
                MHD_create_response_from_buffer(dlen, d, MHD_RESPMEM_MUST_FREE);
            if (!r) {
                free(d);
                return MHD_NO;
            }
            return send_result(c, hash, r, c->fmt->media, job_id, cache);
        }
        plan *pl = &c->plan;
        char h[65];
        snprintf(h, sizeof h, "%s", hash); /* hash may be pl->hash */
        memcpy(pl->hash, h, sizeof h);
        snprintf(pl->job_id, sizeof pl->job_id, "%s", job_id ? job_id : "");
        pl->cache = cache;
        pl->post = post;
        pl->kind = PLAN_DRAW;
        return http_intake_push(c);
    }
    if (!rendered(c) && size > STORE_CHUNK) {
        result_reader *rr = calloc(1, sizeof *rr);
        if (!rr) return http_problem(c, 503, "out of memory", "5", NULL);
        rr->st = st;
        snprintf(rr->hash, sizeof rr->hash, "%s", hash);
        rr->size = size;
        struct MHD_Response *r = NULL;
        gz_reader *g = c->gz ? calloc(1, sizeof *g) : NULL;
        if (c->gz && (!g || !http_gzip_init(&g->z, 1))) {
            free(g);
            free(rr);
            return http_problem(c, 503, "out of memory", "5", NULL);
        }
        if (g) {
            g->rr = rr;
            r = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 256 * 1024, gz_read, g,
                                                  gz_reader_free);
            if (!r) gz_reader_free(g);
        } else {
            r = MHD_create_response_from_callback(size, 256 * 1024, result_read, rr,
                                                  result_reader_free);
            if (!r) free(rr);
        }
        if (!r) return MHD_NO;
        return send_result(c, hash, r, "application/json", job_id, cache);
    }
    int rc = st->ops->result_get(st, hash, &body, &len, err, sizeof err);
    if (rc != STORE_OK) return store_problem(c, rc, err, hash, job_id, post);
    return respond_result(c, hash, body, len, job_id, cache);
}

/* A stored result by its hash (see serve_stored). */
enum MHD_Result http_get_result(conn *c, const char *hash, const char *job_id, const char *cache,
                                int post)
{
    char err[256], made_by[33] = "";
    uint64_t size = 0;
    int rc = c->h->st->ops->result_size(c->h->st, hash, &size, made_by, err, sizeof err);
    if (rc != STORE_OK) return store_problem(c, rc, err, hash, job_id, post);
    return http_serve_stored(c, hash, size,
                             job_id       ? job_id
                             : made_by[0] ? made_by
                                          : NULL,
                             cache, post);
}

/* Which representation the Accept header asks for (a row of render_formats), or NULL when it
 * names none we have.  The highest q wins; at equal q an exact type beats a wildcard, then the
 * table's order (JSON first).  Whether the result can be drawn that way (SVG and GeoJSON of 2D
 * results, OBJ of 3D ones) is the renderer's to say: 422 naming "dim". */
static const render_format *accept_format(const char *accept)
{
    const render_format *best = NULL;
    int best_exact = 0;
    double best_q = 0;
    if (!accept || !*accept) return &render_formats[0];
    const char *p = accept;
    while (*p) {
        while (*p == ' ' || *p == ',' || *p == '\t') p++;
        if (!*p) break;
        const char *end = strchr(p, ',');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        size_t tl = strcspn(p, ";, \t");
        if (tl > n) tl = n;
        double q = 1;
        const char *qp = memmem(p, n, ";q=", 3);
        if (!qp) qp = memmem(p, n, "; q=", 4);
        if (qp) q = strtod(strchr(qp, '=') + 1, NULL);
        for (size_t i = 0; i < render_nformats && q > 0; i++) {
            const render_format *f = &render_formats[i];
            int exact = tl == strlen(f->media) && !strncasecmp(p, f->media, tl);
            int wild =
                !exact && ((f->wild && tl == strlen(f->wild) && !strncasecmp(p, f->wild, tl)) ||
                           (i == 0 && tl == 3 && !strncmp(p, "*/*", 3)));
            if ((exact || wild) && (q > best_q || (q == best_q && exact > best_exact) ||
                                    (q == best_q && exact == best_exact && (!best || f < best)))) {
                best = f;
                best_q = q;
                best_exact = exact;
            }
        }
        p += n;
    }
    return best;
}

typedef struct query_ctx {
    conn *c;
    int failed;
    api_error err;
} query_ctx;

static enum MHD_Result query_arg(void *cls, enum MHD_ValueKind kind, const char *key,
                                 const char *value)
{
    (void)kind;
    query_ctx *q = cls;
    if (q->failed) return MHD_YES;
    if (!strcmp(key, "format")) { /* for links, which cannot set Accept */
        const render_format *f = render_format_named(value);
        if (!f) {
            q->failed = 1;
            q->err.status = API_EINVALID;
            snprintf(q->err.msg, sizeof q->err.msg,
                     "format: expected json, svg, geojson, obj or npz, got \"%.40s\"",
                     value ? value : "");
        }
        q->c->fmt = f;
        return MHD_YES;
    }
    if (!render_opts_is_query_key(key)) return MHD_YES;
    if (render_opts_parse_query(key, value, &q->c->ro, &q->err) != API_OK) q->failed = 1;
    return MHD_YES;
}

/* Decides the representation of a result route from Accept and the query; answers 406 or
 * 422 itself (returning 1) when it cannot. */
int http_negotiate(conn *c, enum MHD_Result *r)
{
    render_opts def = RENDER_OPTS_INIT;
    c->ro = def;
    c->fmt = NULL;
    query_ctx q = {.c = c};
    MHD_get_connection_values(c->mc, MHD_GET_ARGUMENT_KIND, query_arg, &q);
    if (q.failed) {
        *r = http_problem(c, 422, q.err.msg, NULL, NULL);
        return 1;
    }
    if (!c->fmt) { /* no ?format=: the Accept header says */
        const char *acc =
            MHD_lookup_connection_value(c->mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
        c->fmt = accept_format(acc);
    }
    if (!c->fmt) {
        *r = http_problem(c, 406,
                          "results are application/json, image/svg+xml (a picture of a 2D result), "
                          "application/geo+json (a map of a 2D result), model/obj (the cells of a "
                          "3D result) or application/x-npz (its arrays for NumPy); a link can ask "
                          "with ?format=json|svg|geojson|obj|npz",
                          NULL, NULL);
        return 1;
    }
    /* the ETag of a rendering: the hash, the format's name and a digest of the options that
     * made it ("HASH-svg-0123456789abcdef"), so that every representation has its own */
    c->rep[0] = 0;
    if (rendered(c)) {
        char opts[160];
        int n = snprintf(opts, sizeof opts, "%.17g;%d;%d;%d;%.17g;%d", c->ro.explode, c->ro.numbers,
                         c->ro.edges, c->ro.width, c->ro.stroke, c->ro.cells);
        uint64_t h = 1469598103934665603ull; /* FNV-1a */
        for (int i = 0; i < n && i < (int)sizeof opts; i++) {
            h ^= (unsigned char)opts[i];
            h *= 1099511628211ull;
        }
        snprintf(c->rep, sizeof c->rep, "-%s-%016llx", c->fmt->name, (unsigned long long)h);
    }
    return 0;
}

/* Retry-After for a job not finished (buf: 16 bytes): the seconds until a poll is worth making.
 * A running job's rest is estimated from its progress rate, elapsed * (1 - f) / f, and kept
 * within 1 to RETRY_AFTER_MAX seconds so that a progress bar polling by it keeps moving; 1 for a
 * queued job and for one too young for an estimate (under 1% done). */
#define RETRY_AFTER_MAX 5
static const char *retry_after(const job_info *ji, char *buf)
{
    long s = 1;
    if (ji->state == JOB_RUNNING && ji->started > 0 && ji->fraction >= 0.01) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        double el = (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9 - ji->started;
        double rest = el * (1 - ji->fraction) / ji->fraction;
        s = rest > RETRY_AFTER_MAX ? RETRY_AFTER_MAX : rest > 1 ? (long)(rest + 0.999) : 1;
    }
    snprintf(buf, 16, "%ld", s);
    return buf;
}

static enum MHD_Result respond_accepted(conn *c, const job_info *ji)
{
    char loc[CONFIG_PREFIX_MAX + 100], applied[40], retry[16];
    http_link_to(c, loc, sizeof loc, "/v1/jobs/%s", ji->id);
    snprintf(applied, sizeof applied, "wait=%g", c->wait_applied);
    hdr hs[] = {{MHD_HTTP_HEADER_LOCATION, loc},
                {MHD_HTTP_HEADER_RETRY_AFTER, retry_after(ji, retry)},
                {"X-Cellar-Job", ji->id},
                {c->wait_applied > 0 ? MHD_HTTP_HEADER_PREFERENCE_APPLIED : NULL, applied}};
    return http_respond_json(c, 202, http_job_json(c, ji), hs, sizeof hs / sizeof *hs);
}

/* The answer to a POST about its submission c->job_id, once its wait is over. */
enum MHD_Result http_answer_job(conn *c)
{
    char err[256];
    job_info ji;
    int rc = engine_lookup(c->h->e, c->job_id, &ji, err, sizeof err);
    if (rc == ENG_NOTFOUND) return http_problem(c, 503, "the job is gone: try again", "1", NULL);
    if (rc != ENG_OK) return http_problem(c, 503, err, "5", NULL);
    if (ji.state == JOB_DONE) return http_get_result(c, ji.hash, ji.id, "miss", 1);
    if (ji.state == JOB_FAILED)
        return http_problem(c, (unsigned)ji.error_status, ji.error, NULL, NULL);
    if (ji.state == JOB_CANCELED) return http_problem(c, 409, "the job was canceled", NULL, NULL);
    return respond_accepted(c, &ji);
}

enum MHD_Result http_route_result(conn *c)
{
    char etag[120];
    const char *inm = MHD_lookup_connection_value(c->mc, MHD_HEADER_KIND, "If-None-Match");
    result_etag(c, c->id, etag, sizeof etag);
    if (inm && (strstr(inm, etag) || !strcmp(inm, "*"))) {
        char err[256];
        int rc = c->h->st->ops->result_exists(c->h->st, c->id, err, sizeof err);
        if (rc == STORE_OK) {
            hdr hs[] = {{MHD_HTTP_HEADER_ETAG, etag},
                        {MHD_HTTP_HEADER_CACHE_CONTROL, "public, max-age=31536000, immutable"},
                        {MHD_HTTP_HEADER_VARY, "Accept, Accept-Encoding"}};
            return http_respond(c, 304, NULL, NULL, 0, 1, hs, 3);
        }
    }
    return http_get_result(c, c->id, NULL, "hit", 0);
}

enum MHD_Result http_route_job(conn *c, int want_result)
{
    char err[256];
    job_info ji;
    snprintf(c->job_id, sizeof c->job_id, "%.32s", c->id);
    int rc = engine_lookup(c->h->e, c->id, &ji, err, sizeof err);
    if (rc == ENG_NOTFOUND) return http_problem(c, 404, "no job with this id", NULL, NULL);
    if (rc != ENG_OK) return http_problem(c, 503, err, "5", NULL);
    char retry[16];
    int busy = ji.state == JOB_QUEUED || ji.state == JOB_RUNNING;
    if (!want_result) {
        hdr hs[] = {{busy ? MHD_HTTP_HEADER_RETRY_AFTER : NULL, retry_after(&ji, retry)}};
        return http_respond_json(c, 200, http_job_json(c, &ji), hs, 1);
    }
    switch (ji.state) {
    case JOB_DONE:
        return http_get_result(c, ji.hash, ji.id, "hit", 0);
    case JOB_FAILED:
        return http_problem(c, (unsigned)ji.error_status, ji.error, NULL, NULL);
    case JOB_CANCELED:
        return http_problem(c, 409, "the job was canceled", NULL, NULL);
    default:
        return http_problem(c, 409, "the job has not finished yet", retry_after(&ji, retry), NULL);
    }
}

enum MHD_Result http_route_cancel(conn *c)
{
    char err[256];
    job_info ji;
    snprintf(c->job_id, sizeof c->job_id, "%.32s", c->id);
    int rc = engine_cancel(c->h->e, c->id, &ji, err, sizeof err);
    if (rc == ENG_OK) return http_respond_json(c, 200, http_job_json(c, &ji), NULL, 0);
    if (rc == ENG_ENDED)
        return http_problem(c, 409,
                            ji.state == JOB_CANCELED ? "the job was canceled already"
                                                     : "the job has already ended",
                            NULL, NULL);
    if (rc == ENG_NOTFOUND) return http_problem(c, 404, "no job with this id", NULL, NULL);
    return http_problem(c, 503, err, "5", NULL);
}

/* Prefer: wait=N (RFC 7240): the seconds asked for, or -1. */
static double prefer_wait(struct MHD_Connection *mc)
{
    const char *p = MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_PREFER);
    while (p && *p) {
        while (*p == ' ' || *p == ',' || *p == '\t') p++;
        if (!strncasecmp(p, "wait", 4)) {
            const char *q = p + 4;
            while (*q == ' ') q++;
            if (*q == '=') {
                q++;
                while (*q == ' ') q++;
                if (*q == '"') q++;
                /* decimal only (RFC 7240's delta-seconds, a fraction allowed): no sign, no
                 * hex, no exponent, no inf or nan, as strtod would take */
                const char *e = q;
                while (isdigit((unsigned char)*e)) e++;
                if (e > q && *e == '.' && isdigit((unsigned char)e[1])) {
                    e++;
                    while (isdigit((unsigned char)*e)) e++;
                }
                int end_ok = !*e || *e == '"' || *e == ',' || *e == ';' || *e == ' ' || *e == '\t';
                if (e > q && end_ok && e - q < 16) {
                    double w = strtod(q, NULL);
                    if (w < 1e9) return w;
                }
            }
        }
        p = strchr(p, ',');
    }
    return -1;
}

static void wake_conn(void *ctx)
{
    conn *c = ctx;
    MHD_resume_connection(c->mc);
}

/* A POST whose submission (c->job_id, of job c->job) is made: answered now, or suspended until
 * the job ends or the client's wait runs out. */
enum MHD_Result http_submitted(conn *c)
{
    http_server *h = c->h;
    double wait = prefer_wait(c->mc);
    if (wait > h->cfg->max_wait) wait = h->cfg->max_wait;
    if (wait <= 0) return http_answer_job(c);
    c->wait_applied = wait;
    c->waiting = 1;
    http_park(c);
    MHD_suspend_connection(c->mc);
    if (engine_wait(h->e, c->job, engine_now() + wait, wake_conn, c) == 1)
        MHD_resume_connection(c->mc); /* ended meanwhile: answer at once */
    return MHD_YES;
}
