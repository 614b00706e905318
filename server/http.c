/* http.c — see http.h.
 *
 * Every connection gets a `conn` (MHD's con_cls) on the first call of the access handler; the
 * body arrives in later calls (kept up to max_body, the rest discarded and answered 413); the
 * last call (no upload data) answers.  A POST that asks to wait suspends its connection, and the
 * engine's wake callback resumes it; MHD then calls the handler once more and the job's state
 * decides the answer.  The request-completed callback logs the request, counts it in the
 * metrics and frees the conn.
 *
 * Exactly one response per request: every path of handle() ends in respond() (which queues
 * it) or in a suspension whose resumption ends in respond().
 */
#include "server/http.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <jansson.h>
#include <microhttpd.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/evp.h>
#include <zlib.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <time.h>

#include "api/api.h"
#include "api/meshio.h"
#include "api/render.h"
#include "server/log.h"
#include "server/webassets.h"

extern const unsigned char cellar_openapi[];
extern const size_t cellar_openapi_len;

struct http_server {
    const config *cfg;
    engine *e;
    store *st;
    metrics *m;
    struct MHD_Daemon *d;
    atomic_int draining;
    atomic_int parked;         /* connections suspended for a wait and not yet answered */
    _Atomic uint64_t inflight; /* bytes reserved by request bodies being read (max_inflight) */
    pthread_mutex_t ready_mu;  /* guards the readiness probe's last answer */
    pthread_mutex_t conns_mu;  /* guards conns and every sock_ctx's deadline */
    struct sock_ctx *conns;    /* every open connection */
    pthread_t reaper;          /* shuts connections past their deadline */
    pthread_cond_t reaper_cv;
    int reaper_started, reaper_stop;
    double ready_at; /* when the store was last probed for writes (0: never) */
    int ready_ok;
    char ready_err[256];
    pthread_mutex_t memo_mu; /* guards memo */
    struct memo_slot *memo;  /* MEMO_SLOTS: request bodies seen lately */
    /* the intake pool: POST bodies parsed, validated and submitted off the HTTP threads */
    pthread_mutex_t in_mu;
    pthread_cond_t in_cv;
    struct conn *in_head, *in_tail; /* FIFO, guarded by in_mu */
    size_t in_n;
    int in_stop;
    pthread_t *in_threads;
    int in_nthreads;
};

/* POSTs waiting for an intake thread at most (then 503 at once). */
#define INTAKE_MAX 1024

/* Request bodies seen lately, by the SHA-256 of their bytes, with the hash of their canonical
 * form.  While no new job can be taken (the queue is full, or the daemon drains), a POST is
 * answered without parsing its body: a refusal costs a digest, not a parse and a validation
 * (an SVG body is read and flattened to validate it).  A body seen before still finds its
 * cached result, or joins its job in flight. */
#define MEMO_SLOTS 4096
typedef struct memo_slot {
    unsigned char raw[32];
    char hash[65]; /* "" when the slot is empty */
} memo_slot;

static size_t memo_index(const unsigned char raw[32])
{
    return ((size_t)raw[0] | (size_t)raw[1] << 8) % MEMO_SLOTS;
}

static void memo_put(http_server *h, const unsigned char raw[32], const char *hash)
{
    if (!h->memo) return;
    pthread_mutex_lock(&h->memo_mu);
    memo_slot *m = &h->memo[memo_index(raw)];
    memcpy(m->raw, raw, 32);
    snprintf(m->hash, sizeof m->hash, "%s", hash);
    pthread_mutex_unlock(&h->memo_mu);
}

/* The canonical hash of the body whose digest is raw, when it was seen lately (1), else 0. */
static int memo_get(http_server *h, const unsigned char raw[32], char *hash)
{
    if (!h->memo) return 0;
    pthread_mutex_lock(&h->memo_mu);
    const memo_slot *m = &h->memo[memo_index(raw)];
    int found = m->hash[0] && !memcmp(m->raw, raw, 32);
    if (found) memcpy(hash, m->hash, sizeof m->hash);
    pthread_mutex_unlock(&h->memo_mu);
    return found;
}

/* What a POST's intake decided (intake_work), answered once its connection is resumed. */
typedef enum { PLAN_PROBLEM = 0, PLAN_STORED, PLAN_RESULT, PLAN_SUBMITTED } plan_kind;
typedef struct plan {
    plan_kind kind;
    unsigned status;   /* PLAN_PROBLEM */
    char msg[320];     /* PLAN_PROBLEM */
    const char *retry; /* PLAN_PROBLEM: Retry-After, static */
    char hash[65];     /* PLAN_STORED, PLAN_RESULT */
    uint64_t size;     /* PLAN_STORED */
} plan;

/* The body of a POST /v1/jobs, by its Content-Type. */
enum { BODY_JSON = 0, BODY_MESH, BODY_MULTIPART };

/* Parts of a multipart/form-data body at most, and the bytes of their names kept. */
#define HTTP_MAX_PARTS 256

/* A part of a multipart/form-data body: its data is c->body[start .. start + len). */
typedef struct http_part {
    char name[64];      /* the form field's name ("request", "file", ...) */
    char filename[128]; /* "" when none */
    char ctype[96];     /* its Content-Type, "" when none */
    size_t start, len;
} http_part;

typedef struct conn {
    http_server *h;
    struct MHD_Connection *mc;
    metrics_route route;
    char method[8];
    char path[160]; /* for the log: as the request named it */
    size_t off;     /* the length of --base-path at the start of path (then removed) */
    char prefix[CONFIG_PREFIX_MAX + 1]; /* the links' prefix: X-Forwarded-Prefix, --base-path */
    int linked;  /* a link with the prefix was written: Vary: X-Forwarded-Prefix */
    char id[65]; /* the job id or hash in the path */
    double t0;
    char *body;
    size_t len, cap;
    char job[33]; /* the job a POST waits on */
    int waiting;  /* suspended, waiting for job */
    int intake;   /* suspended, its body with the intake pool (2: done, plan made) */
    plan plan;
    struct conn *next_intake; /* h->in's queue */
    int parked;               /* counted in h->parked until completed */
    double wait_applied;
    unsigned status;          /* the status sent, for the log */
    const render_format *fmt; /* result routes: the representation (Accept, ?format=); NULL
                                 or render_formats[0]: the JSON itself */
    render_opts ro;           /* the picture's options (query parameters) */
    char rep[48];             /* the ETag suffix of the representation: "" for JSON */
    int gz;           /* the client takes gzip (Accept-Encoding): compressible answers are */
    char origin[256]; /* the request's Origin when CORS allows it ("": no CORS headers) */
    char job_id[33];  /* for the log */
    int close;        /* answer with Connection: close (the rest of the stream cannot be trusted) */
    uint64_t reserved; /* bytes of h->inflight this request's body holds */
    /* a POST's body type (BODY_*): JSON as it is; one mesh file (mesh its format); or
     * multipart/form-data, split by MHD's post processor as it arrives: the parts' data one
     * after the other in body (len of them; raw counts the body's own bytes, which bound
     * them), described in parts */
    int body_type;
    mesh_format mesh;
    struct MHD_PostProcessor *pp;
    uint64_t raw;
    http_part *parts;
    size_t nparts;
    char mp_err[160]; /* the multipart body is bad: why ("" when it is not) */
} conn;

/* The path that routes: the request's, without --base-path when it begins with it. */
static const char *route_path(const conn *c)
{
    return c->path + c->off;
}

/* A link back to this service as the client sees it, into out: c->prefix (X-Forwarded-Prefix,
 * else --base-path, else "") then the printf of fmt (a path from "/").  Every URL the daemon
 * writes (Location, Content-Location, job "result", problem "instance", OpenAPI "servers") is
 * made here, and the answer then varies with X-Forwarded-Prefix (queue() says so). */
static void link_to(conn *c, char *out, size_t n, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void link_to(conn *c, char *out, size_t n, const char *fmt, ...)
{
    va_list ap;
    int k = snprintf(out, n, "%s", c->prefix);
    c->linked = 1;
    if (k < 0 || (size_t)k >= n) return;
    va_start(ap, fmt);
    vsnprintf(out + k, n - (size_t)k, fmt, ap);
    va_end(ap);
}

/* Reserves n more bytes of the in-flight budget for c's body: 0, or -1 when over it. */
static int body_reserve(conn *c, uint64_t n)
{
    http_server *h = c->h;
    uint64_t old = atomic_fetch_add(&h->inflight, n);
    if (old + n > h->cfg->max_inflight) {
        atomic_fetch_sub(&h->inflight, n);
        return -1;
    }
    c->reserved += n;
    return 0;
}

static void inflight_msg(const http_server *h, char *msg, size_t n)
{
    snprintf(msg, n,
             "the service is reading its limit of request bodies (%llu bytes, "
             "--max-inflight-bytes): try again shortly",
             (unsigned long long)h->cfg->max_inflight);
}

static void too_large_msg(const http_server *h, char *msg, size_t n)
{
    snprintf(msg, n, "the body is larger than %llu bytes", (unsigned long long)h->cfg->max_body);
}

/* c is suspended and not yet answered (h->parked counts those: http_stop waits for them). */
static void park(conn *c)
{
    if (!c->parked) {
        c->parked = 1;
        atomic_fetch_add(&c->h->parked, 1);
    }
}

static void unpark(conn *c)
{
    if (c->parked) {
        c->parked = 0;
        atomic_fetch_sub(&c->h->parked, 1);
    }
}

/* What a CORS answer lets a page elsewhere read. */
#define CORS_EXPOSE                                                                                \
    "Location, Content-Location, Retry-After, ETag, X-Cellar-Job, X-Cellar-Cache, "                \
    "Preference-Applied"

/* c->origin from the request's Origin and --cors-origins ("*": any origin; else a comma-separated
 * list of origins, compared exactly); "" when CORS does not apply. */
static void cors_origin(conn *c)
{
    const char *list = c->h->cfg->cors_origins;
    c->origin[0] = 0;
    if (!list[0]) return;
    const char *o = MHD_lookup_connection_value(c->mc, MHD_HEADER_KIND, "Origin");
    if (!o || !*o) return;
    if (!strcmp(list, "*")) {
        snprintf(c->origin, sizeof c->origin, "*");
        return;
    }
    size_t n = strlen(o);
    for (const char *p = list; *p;) {
        while (*p == ' ' || *p == ',') p++;
        size_t k = strcspn(p, ", ");
        if (k == n && !strncmp(p, o, n) && n < sizeof c->origin) {
            memcpy(c->origin, o, n + 1);
            return;
        }
        p += k;
    }
}

/* Frees c's body and gives its bytes back to the budget. */
static void body_release(conn *c)
{
    free(c->body);
    free(c->parts);
    c->parts = NULL;
    c->nparts = 0;
    c->body = NULL;
    c->len = c->cap = 0;
    if (c->reserved) atomic_fetch_sub(&c->h->inflight, c->reserved);
    c->reserved = 0;
}

/* Per TCP connection (MHD's socket context): what the URL unescaper saw in the request line
 * being read (requests on one connection are read one after the other, so the handler's
 * first call for a request reads and clears it), and the connection's deadline.
 *
 * Deadlines: MHD's own timeout is for idleness only, so a client that sends its headers a
 * byte at a time, each in time, holds a connection for ever.  Each connection here has a
 * deadline for what it is reading: its headers (--header-timeout, from the connection's start
 * or the end of its previous request plus the idle timeout), then its body
 * (--body-timeout).  While its request is handled or answered it has none (a wait is bounded
 * by --max-wait, an answer by MHD's idle timeout).  The reaper thread shuts down the socket
 * of a connection past its deadline; MHD then sees it closed and cleans it up.  MHD calls the
 * CLOSED notification, which unlinks the context under h->conns_mu, before it closes the
 * socket, so the reaper never shuts a socket number that has been reused. */
typedef struct sock_ctx {
    int bad_escape;               /* a %00, or a % not followed by two hex digits */
    int fd;                       /* the connection's socket */
    double deadline;              /* guarded by h->conns_mu; 0: none */
    const char *reading;          /* what the deadline is for: "headers" or "body" */
    struct sock_ctx *prev, *next; /* h->conns, guarded by h->conns_mu */
} sock_ctx;

/* mc's socket context, or NULL (none could be made for it) */
static sock_ctx *sock_of(struct MHD_Connection *mc)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(mc, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return ci ? ci->socket_context : NULL;
}

/* Sets the deadline of mc's connection: `secs` from now for `reading`, or none (secs 0). */
static void set_deadline(http_server *h, struct MHD_Connection *mc, double secs,
                         const char *reading)
{
    sock_ctx *sc = sock_of(mc);
    if (!sc) return;
    pthread_mutex_lock(&h->conns_mu);
    sc->deadline = secs > 0 ? engine_now() + secs : 0;
    sc->reading = reading;
    pthread_mutex_unlock(&h->conns_mu);
}

static const char *status_title(unsigned s)
{
    switch (s) {
    case 400:
        return "Bad Request";
    case 404:
        return "Not Found";
    case 405:
        return "Method Not Allowed";
    case 406:
        return "Not Acceptable";
    case 409:
        return "Conflict";
    case 413:
        return "Content Too Large";
    case 415:
        return "Unsupported Media Type";
    case 422:
        return "Unprocessable Content";
    case 500:
        return "Internal Server Error";
    case 503:
        return "Service Unavailable";
    default:
        return "Error";
    }
}

/* ---- responses ------------------------------------------------------------------------ */

typedef struct hdr {
    const char *name, *value;
} hdr;

/* Queues r (destroyed here, NULL: out of memory) with its headers. */
static enum MHD_Result queue(conn *c, unsigned status, const char *ctype, struct MHD_Response *r,
                             const hdr *hs, size_t nh)
{
    if (!r) return MHD_NO;
    if (ctype) MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    for (size_t i = 0; i < nh; i++)
        if (hs[i].name && hs[i].value) MHD_add_response_header(r, hs[i].name, hs[i].value);
    if (c->origin[0]) { /* CORS (--cors-origins): a page elsewhere may read this answer */
        MHD_add_response_header(r, "Access-Control-Allow-Origin", c->origin);
        MHD_add_response_header(r, "Access-Control-Expose-Headers", CORS_EXPOSE);
    }
    const char *cors = c->h->cfg->cors_origins;
    if (cors[0] && strcmp(cors, "*")) /* the answer depends on Origin: caches must know */
        MHD_add_response_header(r, MHD_HTTP_HEADER_VARY, "Origin");
    if (c->linked) /* its links carry the client's prefix: a cache keeps one per prefix */
        MHD_add_response_header(r, MHD_HTTP_HEADER_VARY, "X-Forwarded-Prefix");
    c->status = status;
    enum MHD_Result ok = MHD_queue_response(c->mc, status, r);
    MHD_destroy_response(r);
    return ok;
}

/* ---- gzip (Accept-Encoding) ---- */

/* Whether the Accept-Encoding header takes gzip (or any coding, "*") with q > 0. */
static int accepts_gzip(struct MHD_Connection *mc)
{
    const char *p = MHD_lookup_connection_value(mc, MHD_HEADER_KIND, "Accept-Encoding");
    while (p && *p) {
        while (*p == ' ' || *p == ',' || *p == '\t') p++;
        size_t n = strcspn(p, ",");
        size_t tl = strcspn(p, ";, \t");
        if (tl > n) tl = n;
        int match = (tl == 4 && !strncasecmp(p, "gzip", 4)) || (tl == 1 && *p == '*');
        const char *q = memmem(p, n, "q=", 2);
        if (match && !(q && strtod(q + 2, NULL) <= 0)) return 1;
        p += n;
    }
    return 0;
}

/* Media types worth compressing: every text we send. */
static int compressible(const char *ctype)
{
    return ctype &&
           (!strncmp(ctype, "application/json", 16) ||
            !strncmp(ctype, "application/problem+json", 24) ||
            !strncmp(ctype, "application/geo+json", 20) || !strncmp(ctype, "image/svg+xml", 13) ||
            !strncmp(ctype, "model/obj", 9) || !strncmp(ctype, "application/x-npz", 17) ||
            !strncmp(ctype, "text/", 5) || !strncmp(ctype, "application/javascript", 22));
}

/* Whether an answer of this type and size goes gzipped to a client that takes gzip. */
static int worth_gzip(const char *ctype, size_t len)
{
    return compressible(ctype) && len >= 1024;
}

/* Starts a gzip stream (deflate with a gzip header) at `level`; 0 on failure. */
static int gzip_init(z_stream *z, int level)
{
    return deflateInit2(z, level, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) == Z_OK;
}

/* gzip of data[0..len) at `level` (1 for answers: results are big, and the CPU is the jobs'),
 * malloc'd; NULL when out of memory. */
static char *gzip_buf(const char *data, size_t len, int level, size_t *outlen)
{
    z_stream z = {0};
    if (!gzip_init(&z, level)) return NULL;
    size_t cap = deflateBound(&z, (uLong)len) + 32;
    char *out = malloc(cap);
    if (!out) {
        deflateEnd(&z);
        return NULL;
    }
    z.next_in = (Bytef *)data;
    z.avail_in = (uInt)len;
    z.next_out = (Bytef *)out;
    z.avail_out = (uInt)cap;
    int rc = deflate(&z, Z_FINISH);
    *outlen = z.total_out;
    deflateEnd(&z);
    if (rc != Z_STREAM_END) {
        free(out);
        return NULL;
    }
    return out;
}

/* Queues the response: body is malloc'd and taken (or, with `persistent`, static); a body worth
 * it goes gzipped to a client that takes gzip. */
static enum MHD_Result respond(conn *c, unsigned status, const char *ctype, char *body, size_t len,
                               int persistent, const hdr *hs, size_t nh)
{
    hdr all[16];
    size_t na = 0;
    for (size_t i = 0; i < nh && na < 14; i++) all[na++] = hs[i];
    if (worth_gzip(ctype, len)) {
        all[na++] = (hdr){MHD_HTTP_HEADER_VARY, "Accept-Encoding"};
        size_t zl = 0;
        char *z = c->gz ? gzip_buf(body, len, 1, &zl) : NULL;
        if (z) {
            if (!persistent) free(body);
            body = z;
            len = zl;
            persistent = 0;
            all[na++] = (hdr){MHD_HTTP_HEADER_CONTENT_ENCODING, "gzip"};
        }
    }
    struct MHD_Response *r = MHD_create_response_from_buffer(
        len, body, persistent ? MHD_RESPMEM_PERSISTENT : MHD_RESPMEM_MUST_FREE);
    if (!r && !persistent) free(body);
    return queue(c, status, ctype, r, all, na);
}

static enum MHD_Result respond_json(conn *c, unsigned status, json_t *o, const hdr *hs, size_t nh)
{
    char *s = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    if (!s) return MHD_NO;
    size_t n = strlen(s);
    char *b = realloc(s, n + 2);
    if (!b) {
        free(s);
        return MHD_NO;
    }
    b[n] = '\n';
    b[n + 1] = 0;
    return respond(c, status, "application/json", b, n + 1, 0, hs, nh);
}

/* The JSON path at the start of an error message ("lines[3][1]: ..."), or "" */
static void message_path(const char *msg, char *path, size_t n)
{
    const char *p = msg;
    path[0] = 0;
    if (!isalpha((unsigned char)*p) && *p != '_') return;
    while (*p && (isalnum((unsigned char)*p) || strchr("_.[]", *p))) p++;
    if (p[0] != ':' || p[1] != ' ' || (size_t)(p - msg) >= n) return;
    memcpy(path, msg, (size_t)(p - msg));
    path[p - msg] = 0;
}

static json_t *problem_json(unsigned status, const char *detail, const char *instance)
{
    char path[200];
    json_t *o = json_object();
    if (!o) return NULL;
    json_object_set_new(o, "type", json_string("about:blank"));
    json_object_set_new(o, "title", json_string(status_title(status)));
    json_object_set_new(o, "status", json_integer(status));
    json_t *d = json_string(detail);
    json_object_set_new(o, "detail", d ? d : json_string("(message not UTF-8)"));
    json_t *in = json_string(instance); /* a client's path: may not be UTF-8 */
    json_object_set_new(o, "instance", in ? in : json_string("(path not UTF-8)"));
    message_path(detail, path, sizeof path);
    if (path[0]) json_object_set_new(o, "path", json_string(path));
    return o;
}

static enum MHD_Result problem(conn *c, unsigned status, const char *detail, const char *retry,
                               const char *allow)
{
    char instance[CONFIG_PREFIX_MAX + sizeof c->path];
    link_to(c, instance, sizeof instance, "%s", route_path(c));
    json_t *o = problem_json(status, detail, instance);
    char *s = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    if (!s) return MHD_NO;
    hdr hs[] = {{MHD_HTTP_HEADER_RETRY_AFTER, retry},
                {MHD_HTTP_HEADER_ALLOW, allow},
                {c->close ? MHD_HTTP_HEADER_CONNECTION : NULL, "close"}};
    return respond(c, status, "application/problem+json", s, strlen(s), 0, hs, 3);
}

static void iso_time(double t, char *out, size_t n)
{
    time_t s = (time_t)t;
    struct tm tm;
    gmtime_r(&s, &tm);
    size_t k = strftime(out, n, "%Y-%m-%dT%H:%M:%S", &tm);
    snprintf(out + k, n - k, ".%03dZ", (int)((t - (double)s) * 1000));
}

static json_t *time_or_null(double t)
{
    char b[40];
    if (t <= 0) return json_null();
    iso_time(t, b, sizeof b);
    return json_string(b);
}

/* A job as JSON, its links made for c's client. */
static json_t *job_json(conn *c, const job_info *ji)
{
    char url[CONFIG_PREFIX_MAX + 100];
    json_t *o = json_object();
    if (!o) return NULL;
    json_object_set_new(o, "id", json_string(ji->id));
    json_object_set_new(o, "kind", json_string(ji->kind));
    json_object_set_new(o, "state", json_string(job_state_name(ji->state)));
    json_object_set_new(o, "hash", json_string(ji->hash));
    json_object_set_new(o, "created", time_or_null(ji->created));
    json_object_set_new(o, "started", time_or_null(ji->started));
    json_object_set_new(o, "finished", time_or_null(ji->finished));
    json_t *p = json_object();
    json_object_set_new(p, "stage", json_string(ji->stage));
    json_object_set_new(p, "fraction", json_real(ji->fraction));
    json_object_set_new(o, "progress", p);
    json_object_set_new(o, "attempts", json_integer(ji->attempts));
    json_object_set_new(o, "daemon", ji->owner[0] ? json_string(ji->owner) : json_null());
    if (ji->state == JOB_FAILED) {
        link_to(c, url, sizeof url, "/v1/jobs/%s", ji->id);
        json_object_set_new(o, "error", problem_json((unsigned)ji->error_status, ji->error, url));
    }
    if (ji->state == JOB_DONE) {
        link_to(c, url, sizeof url, "/v1/results/%s", ji->hash);
        json_object_set_new(o, "result", json_string(url));
    }
    return o;
}

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
    if (c->route != ROUTE_RESULT) link_to(c, loc, sizeof loc, "/v1/results/%s", hash);
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
    return queue(c, 200, ctype, r, hs, sizeof hs / sizeof *hs);
}

/* 422 for a picture or map of a result too large to draw here. */
static enum MHD_Result too_large_to_draw(conn *c, uint64_t len)
{
    char msg[200];
    snprintf(msg, sizeof msg,
             "the result is %llu bytes: its %s form is made of results up to %lu bytes; "
             "ask for application/json",
             (unsigned long long)len, c->fmt->name, c->fmt->max);
    return problem(c, 422, msg, NULL, NULL);
}

/* Whether c asks for a rendering of the result rather than its JSON. */
static int rendered(const conn *c)
{
    return c->fmt && c->fmt->render;
}

/* A result body (taken) with its cache headers, as JSON or rendered (c->fmt). */
static enum MHD_Result respond_result(conn *c, const char *hash, char *body, size_t len,
                                      const char *job_id, const char *cache)
{
    const char *ctype = "application/json";
    if (rendered(c)) {
        char *pic = NULL;
        size_t piclen = 0;
        api_error ae;
        if (len > c->fmt->max) {
            free(body);
            return too_large_to_draw(c, len);
        }
        int rc = c->fmt->render(body, len, &c->ro, &pic, &piclen, &ae);
        free(body);
        if (rc != API_OK) return problem(c, (unsigned)rc, ae.msg, NULL, NULL);
        body = pic;
        len = piclen;
        ctype = c->fmt->media;
    }
    if (c->gz) { /* every result goes gzipped to such a client (its ETag says so) */
        size_t zl = 0;
        char *z = gzip_buf(body, len, 1, &zl);
        free(body);
        if (!z) return problem(c, 503, "out of memory", "5", NULL);
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

/* The answer to a store error rc (not STORE_OK, err its message) about result `hash`.  post:
 * the answer to a POST (a result evicted since it was found or made is then "try again", not
 * "not found"). */
static enum MHD_Result store_problem(conn *c, int rc, const char *err, const char *hash,
                                     const char *job_id, int post)
{
    if (rc == STORE_DAMAGED) {
        log_kv(LOG_ERROR, "a stored result was damaged: dropped", "hash", hash, "error", err, NULL);
        return problem(c, 500,
                       "the stored result was damaged (it no longer matches its digest) and has "
                       "been dropped: post the request again",
                       NULL, NULL);
    }
    if (rc == STORE_NOTFOUND && post)
        return problem(c, 503, "the result was evicted as it was read: try again", "1", NULL);
    if (rc == STORE_NOTFOUND)
        return problem(c, 404,
                       job_id ? "the result was evicted from the cache: post the request again"
                              : "no result with this hash",
                       NULL, NULL);
    return problem(c, 503, err, "5", NULL);
}

/* A stored result of `size` bytes (from result_size), as JSON (streamed when larger than a
 * chunk) or rendered; post as for store_problem. */
static enum MHD_Result serve_stored(conn *c, const char *hash, uint64_t size, const char *job_id,
                                    const char *cache, int post)
{
    char err[256];
    char *body = NULL;
    size_t len = 0;
    store *st = c->h->st;
    if (rendered(c) && size > c->fmt->max) return too_large_to_draw(c, size);
    if (!rendered(c) && size > STORE_CHUNK) {
        result_reader *rr = calloc(1, sizeof *rr);
        if (!rr) return problem(c, 503, "out of memory", "5", NULL);
        rr->st = st;
        snprintf(rr->hash, sizeof rr->hash, "%s", hash);
        rr->size = size;
        struct MHD_Response *r = NULL;
        gz_reader *g = c->gz ? calloc(1, sizeof *g) : NULL;
        if (c->gz && (!g || !gzip_init(&g->z, 1))) {
            free(g);
            free(rr);
            return problem(c, 503, "out of memory", "5", NULL);
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
static enum MHD_Result get_result(conn *c, const char *hash, const char *job_id, const char *cache,
                                  int post)
{
    char err[256], made_by[33] = "";
    uint64_t size = 0;
    int rc = c->h->st->ops->result_size(c->h->st, hash, &size, made_by, err, sizeof err);
    if (rc != STORE_OK) return store_problem(c, rc, err, hash, job_id, post);
    return serve_stored(c, hash, size, job_id ? job_id : made_by[0] ? made_by : NULL, cache, post);
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
static int negotiate(conn *c, enum MHD_Result *r)
{
    render_opts def = RENDER_OPTS_INIT;
    c->ro = def;
    c->fmt = NULL;
    query_ctx q = {.c = c};
    MHD_get_connection_values(c->mc, MHD_GET_ARGUMENT_KIND, query_arg, &q);
    if (q.failed) {
        *r = problem(c, 422, q.err.msg, NULL, NULL);
        return 1;
    }
    if (!c->fmt) { /* no ?format=: the Accept header says */
        const char *acc =
            MHD_lookup_connection_value(c->mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT);
        c->fmt = accept_format(acc);
    }
    if (!c->fmt) {
        *r = problem(c, 406,
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
    link_to(c, loc, sizeof loc, "/v1/jobs/%s", ji->id);
    snprintf(applied, sizeof applied, "wait=%g", c->wait_applied);
    hdr hs[] = {{MHD_HTTP_HEADER_LOCATION, loc},
                {MHD_HTTP_HEADER_RETRY_AFTER, retry_after(ji, retry)},
                {"X-Cellar-Job", ji->id},
                {c->wait_applied > 0 ? MHD_HTTP_HEADER_PREFERENCE_APPLIED : NULL, applied}};
    return respond_json(c, 202, job_json(c, ji), hs, sizeof hs / sizeof *hs);
}

/* The answer to a POST about its submission c->job_id, once its wait is over. */
static enum MHD_Result answer_job(conn *c)
{
    char err[256];
    job_info ji;
    int rc = engine_lookup(c->h->e, c->job_id, &ji, err, sizeof err);
    if (rc == ENG_NOTFOUND) return problem(c, 503, "the job is gone: try again", "1", NULL);
    if (rc != ENG_OK) return problem(c, 503, err, "5", NULL);
    if (ji.state == JOB_DONE) return get_result(c, ji.hash, ji.id, "miss", 1);
    if (ji.state == JOB_FAILED) return problem(c, (unsigned)ji.error_status, ji.error, NULL, NULL);
    if (ji.state == JOB_CANCELED) return problem(c, 409, "the job was canceled", NULL, NULL);
    return respond_accepted(c, &ji);
}

/* ---- routes ------------------------------------------------------------------------------ */

static int is_hex(const char *s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isdigit((unsigned char)s[i]) && !(s[i] >= 'a' && s[i] <= 'f')) return 0;
    return s[n] == 0 || s[n] == '/';
}

/* The route of a path, with the id or hash it names copied into id. */
static metrics_route classify(const char *url, char *id)
{
    id[0] = 0;
    if (!strcmp(url, "/") || !strncmp(url, "/assets/", 8)) return ROUTE_INDEX; /* the page */
    if (!strcmp(url, "/healthz")) return ROUTE_HEALTHZ;
    if (!strcmp(url, "/readyz")) return ROUTE_READYZ;
    if (!strcmp(url, "/metrics")) return ROUTE_METRICS;
    if (!strcmp(url, "/openapi.json")) return ROUTE_OPENAPI;
    if (!strcmp(url, "/v1/jobs")) return ROUTE_JOBS;
    if (!strncmp(url, "/v1/jobs/", 9) && strlen(url) >= 41 && is_hex(url + 9, 32)) {
        memcpy(id, url + 9, 32);
        id[32] = 0;
        if (url[41] == 0) return ROUTE_JOB;
        if (!strcmp(url + 41, "/result")) return ROUTE_JOB_RESULT;
        return ROUTE_OTHER;
    }
    if (!strncmp(url, "/v1/results/", 12) && strlen(url) == 76 && is_hex(url + 12, 64)) {
        memcpy(id, url + 12, 65);
        return ROUTE_RESULT;
    }
    return ROUTE_OTHER;
}

/* The assets gzipped once (level 9), at the first request that takes gzip: each with its own
 * ETag (the asset's with "-gz"), as a different representation must have. */
typedef struct page_gz {
    char *data; /* NULL: not worth it (small or not text), or out of memory */
    size_t len;
    char etag[48];
} page_gz;
static page_gz *page_gzs;
static pthread_once_t page_gz_once = PTHREAD_ONCE_INIT;

static void page_gz_init(void)
{
    page_gzs = calloc(cellar_web_assets_n ? cellar_web_assets_n : 1, sizeof *page_gzs);
    for (size_t i = 0; page_gzs && i < cellar_web_assets_n; i++) {
        const web_asset *a = &cellar_web_assets[i];
        size_t n = strlen(a->etag);
        if (!worth_gzip(a->type, a->len) || n < 2 || n + 3 >= sizeof page_gzs->etag) continue;
        page_gz *g = &page_gzs[i];
        g->data = gzip_buf((const char *)a->data, a->len, 9, &g->len);
        if (g->data && g->len >= a->len) { /* no gain */
            free(g->data);
            g->data = NULL;
        }
        snprintf(g->etag, sizeof g->etag, "%.*s-gz\"", (int)(n - 1), a->etag);
    }
}

/* The page (web/, bundled at build time and embedded as build/gen/web.c): "/" and its assets
 * under /assets/ (their names carry a hash of their bytes: immutable), each with a strong ETag
 * (If-None-Match answers 304); an unknown asset is a 404 problem. */
static enum MHD_Result route_page(conn *c)
{
    size_t i = 0;
    if (c->off && !route_path(c)[0]) { /* the base path without its "/": to the page */
        char loc[CONFIG_PREFIX_MAX + 2];
        link_to(c, loc, sizeof loc, "/");
        hdr hs[] = {{MHD_HTTP_HEADER_LOCATION, loc}};
        return respond(c, 301, NULL, NULL, 0, 1, hs, 1);
    }
    while (i < cellar_web_assets_n && strcmp(cellar_web_assets[i].path, route_path(c))) i++;
    if (i == cellar_web_assets_n) return problem(c, 404, "no such asset", NULL, NULL);
    const web_asset *a = &cellar_web_assets[i];
    const page_gz *g = NULL;
    int gzippable = worth_gzip(a->type, a->len);
    if (gzippable) {
        pthread_once(&page_gz_once, page_gz_init);
        if (c->gz && page_gzs && page_gzs[i].data) g = &page_gzs[i];
    }
    int html = !strncmp(a->type, "text/html", 9);
    hdr hs[] = {{MHD_HTTP_HEADER_ETAG, g ? g->etag : a->etag},
                {MHD_HTTP_HEADER_CACHE_CONTROL, a->cache},
                {"X-Content-Type-Options", "nosniff"},
                {g ? MHD_HTTP_HEADER_CONTENT_ENCODING : NULL, "gzip"},
                {gzippable ? MHD_HTTP_HEADER_VARY : NULL, "Accept-Encoding"},
                {html ? "Content-Security-Policy" : NULL,
                 "default-src 'self'; img-src 'self' data: blob:; object-src 'none'; "
                 "base-uri 'none'; form-action 'none'; frame-ancestors 'none'"}};
    size_t nh = sizeof hs / sizeof *hs;
    /* If-None-Match: either representation's tag names the same bytes once decoded */
    const char *inm = MHD_lookup_connection_value(c->mc, MHD_HEADER_KIND, "If-None-Match");
    if (inm && (strstr(inm, a->etag) || !strcmp(inm, "*") ||
                (gzippable && page_gzs && page_gzs[i].etag[0] && strstr(inm, page_gzs[i].etag)))) {
        struct MHD_Response *r = MHD_create_response_from_buffer(0, NULL, MHD_RESPMEM_PERSISTENT);
        return queue(c, 304, NULL, r, hs, nh);
    }
    const char *data = g ? g->data : (const char *)a->data;
    size_t len = g ? g->len : a->len;
    struct MHD_Response *r =
        MHD_create_response_from_buffer(len, (void *)data, MHD_RESPMEM_PERSISTENT);
    return queue(c, 200, a->type, r, hs, nh);
}

static enum MHD_Result route_result(conn *c)
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
            return respond(c, 304, NULL, NULL, 0, 1, hs, 3);
        }
    }
    return get_result(c, c->id, NULL, "hit", 0);
}

static enum MHD_Result route_job(conn *c, int want_result)
{
    char err[256];
    job_info ji;
    snprintf(c->job_id, sizeof c->job_id, "%.32s", c->id);
    int rc = engine_lookup(c->h->e, c->id, &ji, err, sizeof err);
    if (rc == ENG_NOTFOUND) return problem(c, 404, "no job with this id", NULL, NULL);
    if (rc != ENG_OK) return problem(c, 503, err, "5", NULL);
    char retry[16];
    int busy = ji.state == JOB_QUEUED || ji.state == JOB_RUNNING;
    if (!want_result) {
        hdr hs[] = {{busy ? MHD_HTTP_HEADER_RETRY_AFTER : NULL, retry_after(&ji, retry)}};
        return respond_json(c, 200, job_json(c, &ji), hs, 1);
    }
    switch (ji.state) {
    case JOB_DONE:
        return get_result(c, ji.hash, ji.id, "hit", 0);
    case JOB_FAILED:
        return problem(c, (unsigned)ji.error_status, ji.error, NULL, NULL);
    case JOB_CANCELED:
        return problem(c, 409, "the job was canceled", NULL, NULL);
    default:
        return problem(c, 409, "the job has not finished yet", retry_after(&ji, retry), NULL);
    }
}

static enum MHD_Result route_cancel(conn *c)
{
    char err[256];
    job_info ji;
    snprintf(c->job_id, sizeof c->job_id, "%.32s", c->id);
    int rc = engine_cancel(c->h->e, c->id, &ji, err, sizeof err);
    if (rc == ENG_OK) return respond_json(c, 200, job_json(c, &ji), NULL, 0);
    if (rc == ENG_ENDED)
        return problem(c, 409,
                       ji.state == JOB_CANCELED ? "the job was canceled already"
                                                : "the job has already ended",
                       NULL, NULL);
    if (rc == ENG_NOTFOUND) return problem(c, 404, "no job with this id", NULL, NULL);
    return problem(c, 503, err, "5", NULL);
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

/* The media type t (spaces before it skipped) is name (then the end, ';' or a space). */
static int media_is(const char *t, const char *name)
{
    size_t n = strlen(name);
    if (!t) return 0;
    while (*t == ' ') t++;
    if (strncasecmp(t, name, n) != 0) return 0;
    return t[n] == 0 || t[n] == ';' || t[n] == ' ';
}

/* The body type of a POST /v1/jobs by its Content-Type (c->body_type, c->mesh): 0, or -1 when
 * it is none the service reads (415). */
static int body_content_type(conn *c)
{
    const char *t =
        MHD_lookup_connection_value(c->mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    if (media_is(t, "application/json")) {
        c->body_type = BODY_JSON;
        return 0;
    }
    if ((c->mesh = mesh_format_of_media(t)) != MESH_NONE) {
        c->body_type = BODY_MESH;
        return 0;
    }
    if (media_is(t, "multipart/form-data")) {
        c->body_type = BODY_MULTIPART;
        return 0;
    }
    return -1;
}

/* MHD's post processor hands the data of a multipart body's parts here as it reads them:
 * appended to c->body (whose room the caller made: the data is never more than the body),
 * a part starting where off is 0. */
static enum MHD_Result part_data(void *cls, enum MHD_ValueKind kind, const char *key,
                                 const char *filename, const char *content_type,
                                 const char *transfer_encoding, const char *data, uint64_t off,
                                 size_t size)
{
    conn *c = cls;
    (void)kind;
    (void)transfer_encoding;
    http_part *p = c->nparts ? &c->parts[c->nparts - 1] : NULL;
    int same = p && p->len == 0 && !strcmp(p->name, key ? key : "") &&
               !strcmp(p->filename, filename ? filename : "");
    if (off == 0 && !same) {
        if (c->nparts >= HTTP_MAX_PARTS) {
            snprintf(c->mp_err, sizeof c->mp_err, "more than %d parts", HTTP_MAX_PARTS);
            return MHD_NO;
        }
        if (!c->parts && !(c->parts = calloc(HTTP_MAX_PARTS, sizeof *c->parts))) {
            snprintf(c->mp_err, sizeof c->mp_err, "out of memory");
            return MHD_NO;
        }
        p = &c->parts[c->nparts++];
        snprintf(p->name, sizeof p->name, "%s", key ? key : "");
        snprintf(p->filename, sizeof p->filename, "%s", filename ? filename : "");
        snprintf(p->ctype, sizeof p->ctype, "%s", content_type ? content_type : "");
        p->start = c->len;
        p->len = 0;
    }
    if (!p || c->len + size + 1 > c->cap) {
        snprintf(c->mp_err, sizeof c->mp_err, "malformed multipart body");
        return MHD_NO;
    }
    memcpy(c->body + c->len, data, size);
    c->len += size;
    p->len += size;
    return MHD_YES;
}

/* Fills *ae with status and message; returns status. */
static int body_fail(api_error *ae, int status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int body_fail(api_error *ae, int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ae->status = status;
    vsnprintf(ae->msg, sizeof ae->msg, fmt, ap);
    va_end(ap);
    return status;
}

/* The request of a mesh or multipart body (c->body_type not BODY_JSON) as JSON text, into
 * *json: API_OK, or a status with ae filled. */
static int mesh_body_request(conn *c, char **json, size_t *jlen, api_error *ae)
{
    const char *body = c->body ? c->body : "";
    if (c->body_type == BODY_MESH) {
        mesh_file f = {"body", c->mesh, body, c->len};
        char name[32];
        snprintf(name, sizeof name, "body (%s)", mesh_format_name(c->mesh));
        f.name = name;
        return mesh_request_json(&f, 1, NULL, 0, json, jlen, ae);
    }
    if (c->mp_err[0]) return body_fail(ae, API_EJSON, "multipart/form-data: %s", c->mp_err);
    mesh_file *files = calloc(c->nparts + 1, sizeof *files);
    char(*names)[200] = calloc(c->nparts + 1, sizeof *names);
    const char *req = NULL;
    size_t rlen = 0, n = 0;
    int rc = API_OK;
    if (!files || !names) {
        rc = body_fail(ae, API_ENOMEM, "out of memory");
        goto out;
    }
    for (size_t i = 0; i < c->nparts; i++) {
        const http_part *p = &c->parts[i];
        if (!strcmp(p->name, "request") && !p->filename[0]) {
            if (req) {
                rc = body_fail(ae, API_EINVALID, "multipart/form-data: two parts \"request\"");
                goto out;
            }
            req = body + p->start;
            rlen = p->len;
            continue;
        }
        mesh_format f = mesh_format_of_media(p->ctype);
        if (f == MESH_NONE) f = mesh_format_of_name(p->filename);
        if (p->filename[0])
            snprintf(names[n], sizeof names[n], "part %zu (%s)", i, p->filename);
        else
            snprintf(names[n], sizeof names[n], "part %zu (\"%s\")", i, p->name);
        if (f == MESH_NONE) {
            rc = body_fail(ae, API_EINVALID,
                           "%s: not a mesh: expected a Content-Type such as model/stl or a file "
                           "name ending in .stl, .obj, .off, .ply or .3mf (or the part "
                           "\"request\")",
                           names[n]);
            goto out;
        }
        files[n] = (mesh_file){names[n], f, body + p->start, p->len};
        n++;
    }
    if (!n) {
        rc = body_fail(ae, API_EINVALID, "multipart/form-data: no mesh file among the parts");
        goto out;
    }
    rc = mesh_request_json(files, n, req, rlen, json, jlen, ae);
out:
    free(files);
    free(names);
    return rc;
}

static void plan_problem(plan *pl, unsigned status, const char *msg, const char *retry)
{
    pl->kind = PLAN_PROBLEM;
    pl->status = status;
    snprintf(pl->msg, sizeof pl->msg, "%s", msg);
    pl->retry = retry;
}

/* A POST that no new job can be made for: ENG_FULL or ENG_DRAINING. */
static void plan_refused(plan *pl, int why)
{
    plan_problem(pl, 503,
                 why == ENG_DRAINING ? "the service is shutting down"
                                     : "the job queue is full: try again later",
                 "5");
}

static void plan_result(plan *pl, plan_kind kind, const char *hash, uint64_t size)
{
    pl->kind = kind;
    snprintf(pl->hash, sizeof pl->hash, "%s", hash);
    pl->size = size;
}

static enum MHD_Result submitted(conn *c);

/* The intake of a POST (on an intake thread, never on an HTTP thread: parsing and validating a
 * body can cost seconds, an SVG's curves flattened, a solid's surface checked): what the
 * answer will be, in c->plan, made into a response by answer_plan() once the connection is
 * resumed.  No MHD call here. */
static void intake_work(conn *c)
{
    char err[256], hash[65];
    api_error ae = {0};
    char *canon = NULL;
    size_t clen = 0;
    const char *kind = NULL;
    http_server *h = c->h;
    unsigned char raw[32];
    uint64_t size = 0;
    int rc, hit;
    plan *pl = &c->plan;

    if (!EVP_Digest(c->body ? c->body : "", c->len, raw, NULL, EVP_sha256(), NULL))
        memset(raw, 0, sizeof raw);  /* cannot happen with OpenSSL's sha256: never found */
    if (c->body_type != BODY_JSON) { /* a mesh's bytes mean what their type says: in the key */
        unsigned char k[32 + 2 + HTTP_MAX_PARTS * sizeof(http_part)];
        size_t kn = 0;
        memcpy(k, raw, 32);
        kn = 32;
        k[kn++] = (unsigned char)c->body_type;
        k[kn++] = (unsigned char)c->mesh;
        if (c->nparts) {
            memcpy(k + kn, c->parts, c->nparts * sizeof *c->parts);
            kn += c->nparts * sizeof *c->parts;
        }
        if (!EVP_Digest(k, kn, raw, NULL, EVP_sha256(), NULL)) memset(raw, 0, sizeof raw);
    }
    int full = engine_full(h->e, err, sizeof err);
    if (full == ENG_ERR) {
        body_release(c);
        return plan_problem(pl, 503, err, "5");
    }
    if (full != ENG_OK) { /* no new job: answer without parsing (see memo_slot) */
        body_release(c);
        if (!memo_get(h, raw, hash)) return plan_refused(pl, full);
        hit = h->st->ops->result_size(h->st, hash, &size, c->job_id, err, sizeof err);
        metrics_cache(h->m, hit == STORE_OK);
        if (hit == STORE_OK) return plan_result(pl, PLAN_STORED, hash, size);
        rc = engine_join(h->e, hash, c->job_id, c->job, err, sizeof err);
        if (rc == ENG_NOTFOUND) return plan_refused(pl, full);
        if (rc != ENG_OK) return plan_problem(pl, 503, err, "5");
        pl->kind = PLAN_SUBMITTED;
        return;
    }

    if (c->body_type != BODY_JSON) { /* a mesh, or mesh files: their "solids" request */
        char *json = NULL;
        size_t jlen = 0;
        rc = mesh_body_request(c, &json, &jlen, &ae);
        body_release(c);
        if (rc != API_OK)
            return plan_problem(pl, (unsigned)rc, ae.msg, rc == API_ENOMEM ? "5" : NULL);
        if (jlen > h->cfg->max_body) { /* the request the files make, as a JSON body is held */
            char msg[200];
            snprintf(msg, sizeof msg,
                     "the solids request these mesh files make is %zu bytes, more than the %llu "
                     "a request may hold (--max-body)",
                     jlen, (unsigned long long)h->cfg->max_body);
            free(json);
            return plan_problem(pl, 413, msg, NULL);
        }
        c->body = json;
        c->len = jlen;
    }
    rc = api_check_request(c->body ? c->body : "", c->len, &canon, &clen, &kind, &ae);
    body_release(c);
    if (rc != API_OK) return plan_problem(pl, (unsigned)rc, ae.msg, rc == API_ENOMEM ? "5" : NULL);
    engine_hash(canon, clen, hash);
    memo_put(h, raw, hash);

    /* a cached result costs one lookup (its size and the job that made it, then it is served) */
    hit = h->st->ops->result_size(h->st, hash, &size, c->job_id, err, sizeof err);
    metrics_cache(h->m, hit == STORE_OK);
    if (hit == STORE_OK) {
        free(canon);
        return plan_result(pl, PLAN_STORED, hash, size);
    }
    int coalesced = 0;
    rc = engine_submit(h->e, canon, clen, kind, hash, c->job_id, c->job, &coalesced, err,
                       sizeof err);
    free(canon);
    if (rc == ENG_CACHED) /* an identical job ended between our two looks */
        return plan_result(pl, PLAN_RESULT, hash, 0);
    if (rc == ENG_FULL || rc == ENG_DRAINING) return plan_refused(pl, rc);
    if (rc != ENG_OK) return plan_problem(pl, 503, err, "5");
    pl->kind = PLAN_SUBMITTED;
}

/* The answer to a POST whose intake is done (on the HTTP thread). */
static enum MHD_Result answer_plan(conn *c)
{
    plan *pl = &c->plan;
    switch (pl->kind) {
    case PLAN_STORED:
        return serve_stored(c, pl->hash, pl->size, c->job_id[0] ? c->job_id : NULL, "hit", 1);
    case PLAN_RESULT:
        return get_result(c, pl->hash, NULL, "hit", 1);
    case PLAN_SUBMITTED:
        return submitted(c);
    default:
        return problem(c, pl->status, pl->msg, pl->retry, NULL);
    }
}

/* A POST whose submission (c->job_id, of job c->job) is made: answered now, or suspended until
 * the job ends or the client's wait runs out. */
static enum MHD_Result submitted(conn *c)
{
    http_server *h = c->h;
    double wait = prefer_wait(c->mc);
    if (wait > h->cfg->max_wait) wait = h->cfg->max_wait;
    if (wait <= 0) return answer_job(c);
    c->wait_applied = wait;
    c->waiting = 1;
    park(c);
    MHD_suspend_connection(c->mc);
    if (engine_wait(h->e, c->job, engine_now() + wait, wake_conn, c) == 1)
        MHD_resume_connection(c->mc); /* ended meanwhile: answer at once */
    return MHD_YES;
}

static enum MHD_Result route_metrics(conn *c)
{
    metrics_gauges g = {0};
    char err[256];
    engine_gauges(c->h->e, &g.queued, &g.running, &g.running_here, &g.queue_capacity, &g.draining);
    if (c->h->st->ops->result_stats(c->h->st, &g.cache_results, &g.cache_bytes, err, sizeof err))
        log_kv(LOG_WARN, "store: result_stats failed", "error", err, NULL);
    g.cache_budget = c->h->cfg->cache_bytes;
    size_t len;
    char *s = metrics_render(c->h->m, &g, &len);
    if (!s) return MHD_NO;
    return respond(c, 200, "text/plain; version=0.0.4; charset=utf-8", s, len, 0, NULL, 0);
}

static enum MHD_Result status_json(conn *c, unsigned status, const char *value, const char *error)
{
    json_t *o = json_object();
    json_object_set_new(o, "status", json_string(value));
    if (error) json_object_set_new(o, "error", json_string(error));
    return respond_json(c, status, o, NULL, 0);
}

/* Ready: not draining, and the store takes writes (every POST writes its job first).  The
 * store is probed with a small write at most once a second. */
static enum MHD_Result route_readyz(conn *c)
{
    http_server *h = c->h;
    char err[256] = "";
    if (atomic_load(&h->draining)) return status_json(c, 503, "draining", NULL);
    double now = engine_now();
    pthread_mutex_lock(&h->ready_mu);
    int fresh = h->ready_at > 0 && now - h->ready_at < 1.0, ok = h->ready_ok;
    snprintf(err, sizeof err, "%s", h->ready_err);
    pthread_mutex_unlock(&h->ready_mu);
    if (!fresh) {
        err[0] = 0;
        ok = h->st->ops->writable(h->st, err, sizeof err) == STORE_OK;
        if (!ok) log_kv(LOG_WARN, "the store cannot be written", "error", err, NULL);
        pthread_mutex_lock(&h->ready_mu);
        h->ready_at = now;
        h->ready_ok = ok;
        snprintf(h->ready_err, sizeof h->ready_err, "%s", ok ? "" : err);
        pthread_mutex_unlock(&h->ready_mu);
    }
    return ok ? status_json(c, 200, "ready", NULL) : status_json(c, 503, "store not writable", err);
}

/* Hands a POST to the intake pool: the connection is suspended until an intake thread has
 * decided its answer (c->plan) and resumes it.  Suspended before it is queued, so that no
 * thread can resume it before it is suspended. */
static enum MHD_Result intake_push(conn *c)
{
    http_server *h = c->h;
    pthread_mutex_lock(&h->in_mu);
    if (h->in_n >= INTAKE_MAX || h->in_stop) {
        pthread_mutex_unlock(&h->in_mu);
        body_release(c);
        return problem(c, 503, "too many requests are being read: try again", "1", NULL);
    }
    c->intake = 1;
    park(c);
    MHD_suspend_connection(c->mc);
    c->next_intake = NULL;
    if (h->in_tail)
        h->in_tail->next_intake = c;
    else
        h->in_head = c;
    h->in_tail = c;
    h->in_n++;
    pthread_cond_signal(&h->in_cv);
    pthread_mutex_unlock(&h->in_mu);
    return MHD_YES;
}

static void *intake_main(void *arg)
{
    http_server *h = arg;
    pthread_mutex_lock(&h->in_mu);
    for (;;) {
        while (!h->in_head && !h->in_stop) pthread_cond_wait(&h->in_cv, &h->in_mu);
        conn *c = h->in_head;
        if (!c) break; /* stopping, and nothing left */
        h->in_head = c->next_intake;
        if (!h->in_head) h->in_tail = NULL;
        h->in_n--;
        pthread_mutex_unlock(&h->in_mu);
        intake_work(c);
        c->intake = 2;
        MHD_resume_connection(c->mc);
        pthread_mutex_lock(&h->in_mu);
    }
    pthread_mutex_unlock(&h->in_mu);
    return NULL;
}

/* OPTIONS: a CORS preflight from an allowed origin gets what it may send; any other the
 * methods of the path. */
static enum MHD_Result route_options(conn *c)
{
    static const char *const allow[ROUTE_COUNT] = {
        [ROUTE_INDEX] = "GET, HEAD, OPTIONS",       [ROUTE_HEALTHZ] = "GET, HEAD, OPTIONS",
        [ROUTE_READYZ] = "GET, HEAD, OPTIONS",      [ROUTE_METRICS] = "GET, HEAD, OPTIONS",
        [ROUTE_OPENAPI] = "GET, HEAD, OPTIONS",     [ROUTE_JOBS] = "POST, OPTIONS",
        [ROUTE_JOB] = "GET, HEAD, DELETE, OPTIONS", [ROUTE_JOB_RESULT] = "GET, HEAD, OPTIONS",
        [ROUTE_RESULT] = "GET, HEAD, OPTIONS"};
    const char *a = allow[c->route];
    if (!a) return problem(c, 404, "no such resource", NULL, NULL);
    hdr hs[] = {{MHD_HTTP_HEADER_ALLOW, a},
                {c->origin[0] ? "Access-Control-Allow-Methods" : NULL, a},
                {c->origin[0] ? "Access-Control-Allow-Headers" : NULL,
                 "Content-Type, Accept, Prefer, If-None-Match"},
                {c->origin[0] ? "Access-Control-Max-Age" : NULL, "600"}};
    return respond(c, 204, NULL, NULL, 0, 1, hs, sizeof hs / sizeof *hs);
}

/* The OpenAPI document, its "servers" URL the client's prefix ("/" without one). */
static enum MHD_Result route_openapi(conn *c)
{
    static const char root[] = "\"servers\": [{\"url\": \"/\"";
    char url[CONFIG_PREFIX_MAX + 2];
    link_to(c, url, sizeof url, "%s", "");
    const char *doc = (const char *)cellar_openapi;
    const char *at = memmem(doc, cellar_openapi_len, root, sizeof root - 1);
    if (!url[0] || !at) /* the root (or no such line: the document as it is) */
        return respond(c, 200, "application/json", (char *)doc, cellar_openapi_len, 1, NULL, 0);
    size_t head = (size_t)(at - doc) + sizeof root - 3; /* at its "/" */
    size_t ul = strlen(url), len = cellar_openapi_len - 1 + ul;
    char *b = malloc(len);
    if (!b) return problem(c, 503, "out of memory", "5", NULL);
    memcpy(b, doc, head);
    memcpy(b + head, url, ul);
    memcpy(b + head + ul, doc + head + 1, cellar_openapi_len - head - 1);
    return respond(c, 200, "application/json", b, len, 0, NULL, 0);
}

static enum MHD_Result dispatch(conn *c)
{
    const char *m = c->method;
    int get = !strcmp(m, "GET") || !strcmp(m, "HEAD");
    if (!strcmp(m, "OPTIONS")) return route_options(c);
    switch (c->route) {
    case ROUTE_INDEX:
        if (!get) break;
        return route_page(c);
    case ROUTE_HEALTHZ:
        if (!get) break;
        return status_json(c, 200, "ok", NULL);
    case ROUTE_READYZ:
        if (!get) break;
        return route_readyz(c);
    case ROUTE_METRICS:
        if (!get) break;
        return route_metrics(c);
    case ROUTE_OPENAPI:
        if (!get) break;
        return route_openapi(c);
    case ROUTE_JOBS:
        if (strcmp(m, "POST")) return problem(c, 405, "use POST", NULL, "POST");
        return intake_push(c);
    case ROUTE_JOB:
        if (get) return route_job(c, 0);
        if (!strcmp(m, "DELETE")) return route_cancel(c);
        return problem(c, 405, "use GET or DELETE", NULL, "GET, HEAD, DELETE");
    case ROUTE_JOB_RESULT: {
        enum MHD_Result r;
        if (get && negotiate(c, &r)) return r;
        if (get) return route_job(c, 1);
        return problem(c, 405, "use GET", NULL, "GET, HEAD");
    }
    case ROUTE_RESULT: {
        enum MHD_Result r;
        if (get && negotiate(c, &r)) return r;
        if (get) return route_result(c);
        return problem(c, 405, "use GET", NULL, "GET, HEAD");
    }
    default:
        return problem(c, 404, "no such resource", NULL, NULL);
    }
    return problem(c, 405, "use GET", NULL, "GET, HEAD");
}

/* An answer in the middle of a body, where MHD cannot queue one (it would read the body to
 * its end first: 1 GB of chunks before a 413): the problem is written to the socket here,
 * its sending side shut, and MHD told to close the connection.  A client that stops sending
 * to read gets the answer; one that keeps sending gets a reset. */
static enum MHD_Result refuse_mid_body(conn *c, unsigned status, const char *detail)
{
    c->status = status;
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c->mc, MHD_CONNECTION_INFO_CONNECTION_FD);
    char instance[CONFIG_PREFIX_MAX + sizeof c->path];
    link_to(c, instance, sizeof instance, "%s", route_path(c));
    json_t *o = problem_json(status, detail, instance);
    char *body = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    if (ci && body) {
        char head[256];
        size_t blen = strlen(body);
        int n = snprintf(head, sizeof head,
                         "HTTP/1.1 %u %s\r\nContent-Type: application/problem+json\r\n"
                         "Content-Length: %zu\r\nConnection: close\r\n\r\n",
                         status, status_title(status), blen + 1);
        struct iovec iov[3] = {{head, (size_t)n}, {body, blen}, {"\n", 1}};
        struct msghdr mh = {.msg_iov = iov, .msg_iovlen = 3};
        (void)sendmsg(ci->connect_fd, &mh, MSG_NOSIGNAL | MSG_DONTWAIT);
        shutdown(ci->connect_fd, SHUT_WR);
    }
    free(body);
    return MHD_NO;
}

static enum MHD_Result handle(void *cls, struct MHD_Connection *mc, const char *url,
                              const char *method, const char *version, const char *upload,
                              size_t *upload_size, void **con_cls)
{
    (void)version;
    http_server *h = cls;
    conn *c = *con_cls;
    if (!c) { /* headers are in: early answers before any body is read */
        c = calloc(1, sizeof *c);
        if (!c) return MHD_NO;
        *con_cls = c;
        /* the headers are in: the body (if any) has --body-timeout from now */
        set_deadline(h, mc, h->cfg->body_timeout, "body");
        c->h = h;
        c->mc = mc;
        c->t0 = engine_now();
        snprintf(c->method, sizeof c->method, "%s", method);
        snprintf(c->path, sizeof c->path, "%s", url);
        /* --base-path: a path under it is served without it (a proxy that passes the path
         * whole); one that is the base path itself goes to the page (route_page) */
        const char *bp = h->cfg->base_path;
        size_t bl = strlen(bp);
        if (bl && !strncmp(url, bp, bl) && (url[bl] == '/' || !url[bl]) && bl < sizeof c->path)
            c->off = bl;
        c->route = c->off && !url[bl] ? ROUTE_INDEX : classify(url + c->off, c->id);
        c->gz = accepts_gzip(mc);
        cors_origin(c);
        /* the links' prefix: the proxy's X-Forwarded-Prefix (any client may send one: it only
         * changes the links of its own answer, which then vary with it), else --base-path */
        const char *xfp = MHD_lookup_connection_value(mc, MHD_HEADER_KIND, "X-Forwarded-Prefix");
        if (xfp && *xfp) {
            const char *why;
            if (config_path_prefix(xfp, c->prefix, &why)) {
                char msg[300];
                snprintf(msg, sizeof msg, "X-Forwarded-Prefix: invalid value \"%.100s\": %s", xfp,
                         why);
                c->close = 1; /* a body that follows is not read */
                return problem(c, 400, msg, NULL, NULL);
            }
        } else {
            memcpy(c->prefix, bp, bl + 1);
        }
        sock_ctx *sc = sock_of(mc);
        int bad_escape = sc && sc->bad_escape;
        if (sc) sc->bad_escape = 0;
        if (bad_escape)
            return problem(c, 400,
                           "the URL has a bad percent-escape (%00, or % not followed by two hex "
                           "digits)",
                           NULL, NULL);
        /* a body is framed by Content-Length or by chunks, never both (RFC 9112 6.1: a request
         * with both is an attack on whoever reads it next), and chunked is the only coding
         * understood: past such a request the stream cannot be trusted, so it is closed */
        const char *te =
            MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_TRANSFER_ENCODING);
        if (te) {
            c->close = 1;
            if (MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH))
                return problem(c, 400, "Content-Length and Transfer-Encoding together", NULL, NULL);
            while (*te == ' ' || *te == '\t') te++;
            size_t n = strlen(te);
            while (n && (te[n - 1] == ' ' || te[n - 1] == '\t')) n--;
            if (n != 7 || strncasecmp(te, "chunked", 7))
                return problem(c, 400, "Transfer-Encoding: only chunked is understood", NULL, NULL);
            c->close = 0;
        }
        if (c->route == ROUTE_JOBS && !strcmp(method, "POST")) {
            if (atomic_load(&h->draining))
                return problem(c, 503, "the service is shutting down", "5", NULL);
            const char *cl =
                MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
            c->close = 1; /* an early answer: the body that follows is not read */
            unsigned long long clv = cl ? strtoull(cl, NULL, 10) : 0;
            if (cl && clv > h->cfg->max_body) {
                char msg[128];
                too_large_msg(h, msg, sizeof msg);
                return problem(c, 413, msg, NULL, NULL);
            }
            if (body_content_type(c))
                return problem(c, 415,
                               "the body must be application/json, one mesh (model/stl, "
                               "model/obj, model/3mf, model/vnd.ply, model/vnd.off) or "
                               "multipart/form-data of mesh files",
                               NULL, NULL);
            if (c->body_type == BODY_MULTIPART &&
                !(c->pp = MHD_create_post_processor(mc, 65536, part_data, c)))
                return problem(c, 415, "multipart/form-data without a boundary", NULL, NULL);
            /* the representation of a result answered to this POST (Accept, ?format= and the
             * drawing options), decided before the body is read: 406 or 422 at once */
            enum MHD_Result nr;
            if (negotiate(c, &nr)) return nr;
            /* the body's bytes are reserved before any is read (all of them when the length
             * is known, else as they come), against one budget for every connection */
            if (cl && (body_reserve(c, clv + 1) || !(c->body = malloc(clv + 1)))) {
                char msg[200];
                inflight_msg(h, msg, sizeof msg);
                return problem(c, 503, msg, "1", NULL);
            }
            if (cl) c->cap = clv + 1;
            c->close = 0;
        }
        return MHD_YES;
    }
    if (*upload_size) { /* a piece of the body */
        size_t n = *upload_size;
        *upload_size = 0;
        if (c->status) return MHD_YES;              /* answered already */
        if (c->route != ROUTE_JOBS) return MHD_YES; /* bodies of other routes are ignored */
        uint64_t seen = c->pp ? c->raw : c->len;    /* multipart: len counts the parts' data */
        if (seen + n > h->cfg->max_body) {
            /* no Content-Length said so (chunked): the rest is never read */
            char msg[128];
            body_release(c);
            too_large_msg(h, msg, sizeof msg);
            return refuse_mid_body(c, 413, msg);
        }
        if (seen + n + 1 > c->cap) { /* chunked: no length was reserved */
            size_t cap = c->cap ? c->cap : 4096;
            while (cap < seen + n + 1) cap *= 2;
            if (cap > h->cfg->max_body + 1) cap = h->cfg->max_body + 1;
            if (body_reserve(c, cap - c->cap)) {
                char msg[200];
                inflight_msg(h, msg, sizeof msg);
                body_release(c);
                return refuse_mid_body(c, 503, msg);
            }
            char *b = realloc(c->body, cap);
            if (!b) return MHD_NO;
            c->body = b;
            c->cap = cap;
        }
        if (c->pp) { /* the parts' data go to body as the post processor finds them */
            c->raw += n;
            if (!c->mp_err[0] && MHD_post_process(c->pp, upload, n) != MHD_YES && !c->mp_err[0])
                snprintf(c->mp_err, sizeof c->mp_err, "malformed multipart body");
            return MHD_YES;
        }
        memcpy(c->body + c->len, upload, n);
        c->len += n;
        return MHD_YES;
    }
    if (c->pp) { /* the body is in: the parts are all found */
        if (MHD_destroy_post_processor(c->pp) != MHD_YES && !c->mp_err[0])
            snprintf(c->mp_err, sizeof c->mp_err, "the body ends inside a part");
        c->pp = NULL;
    }
    set_deadline(h, mc, 0, NULL);  /* the request is in: handled and answered, no deadline */
    if (c->status) return MHD_YES; /* answered before the body (413, 415, 503) */
    if (c->intake == 2) {          /* resumed: the intake has decided */
        c->intake = 0;
        unpark(c);
        return answer_plan(c);
    }
    if (c->waiting) { /* resumed: the job ended or the wait is over */
        c->waiting = 0;
        return answer_job(c);
    }
    return dispatch(c);
}

static void completed(void *cls, struct MHD_Connection *mc, void **con_cls,
                      enum MHD_RequestTerminationCode toe)
{
    http_server *h = cls;
    conn *c = *con_cls;
    if (!c) return;
    char ms[32], st[32];
    metrics_request(h->m, c->route, c->status);
    log_kv(c->status >= 500 ? LOG_WARN : LOG_INFO, "request", "method", c->method, "path", c->path,
           "status", log_num(st, c->status), "ms", log_num(ms, (engine_now() - c->t0) * 1e3), "job",
           c->job_id[0] ? c->job_id : NULL, "closed",
           toe == MHD_REQUEST_TERMINATED_COMPLETED_OK ? NULL : "early", NULL);
    unpark(c);
    if (c->pp) MHD_destroy_post_processor(c->pp);
    /* kept alive: the next request's headers are due within the idle time and the header time */
    set_deadline(h, mc, h->cfg->idle_timeout + h->cfg->header_timeout, "headers");
    body_release(c);
    free(c);
    *con_cls = NULL;
}

static void mhd_log(void *cls, const char *fmt, va_list ap)
{
    (void)cls;
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, ap);
    size_t n = strlen(msg);
    while (n && (msg[n - 1] == '\n' || msg[n - 1] == '\r')) msg[--n] = 0;
    log_kv(LOG_DEBUG, "libmicrohttpd", "detail", msg, NULL);
}

static void http_free(http_server *h)
{
    pthread_mutex_destroy(&h->ready_mu);
    pthread_mutex_destroy(&h->conns_mu);
    pthread_mutex_destroy(&h->memo_mu);
    pthread_mutex_destroy(&h->in_mu);
    pthread_cond_destroy(&h->in_cv);
    pthread_cond_destroy(&h->reaper_cv);
    free(h->in_threads);
    free(h->memo);
    free(h);
}

/* Can a request begin with byte c?  A request line begins with its method, a token (letters,
 * digits and !#$%&'*+-.^_`|~), and may follow a few empty lines (CR, LF). */
static int request_first_byte(unsigned char c)
{
    return isalnum(c) || (c && strchr("!#$%&'*+-.^_`|~\r\n", c));
}

/* MHD (0.9.75) takes a line whose first byte is NUL for an empty line before the request line,
 * skips it and waits for a request line until the header deadline (10 s).  A connection whose
 * first byte can begin no request is answered 400 here, as MHD accepts it, and shut at once;
 * MHD then finds it closed.  The listening socket defers each accept until the connection's
 * first bytes are in (TCP_DEFER_ACCEPT, up to the header timeout), so they are there to see. */
static void refuse_bad_start(int fd)
{
    unsigned char b;
    if (recv(fd, &b, 1, MSG_PEEK | MSG_DONTWAIT) != 1 || request_first_byte(b)) return;
    static const char body[] =
        "{\"type\":\"about:blank\",\"title\":\"Bad Request\",\"status\":400,\"detail\":"
        "\"the request begins with a byte no request line can hold\"}";
    char msg[512];
    int n = snprintf(msg, sizeof msg,
                     "HTTP/1.1 400 Bad Request\r\nConnection: close\r\n"
                     "Content-Type: application/problem+json\r\nContent-Length: %zu\r\n\r\n%s",
                     sizeof body - 1, body);
    if (n > 0 && (size_t)n < sizeof msg)
        (void)send(fd, msg, (size_t)n, MSG_NOSIGNAL | MSG_DONTWAIT);
    shutdown(fd, SHUT_RDWR);
    log_kv(LOG_INFO, "request refused: a first byte no request line can begin with", NULL);
}

/* MHD_OPTION_NOTIFY_CONNECTION: a sock_ctx for each TCP connection. */
static void notify_connection(void *cls, struct MHD_Connection *mc, void **socket_context,
                              enum MHD_ConnectionNotificationCode toe)
{
    http_server *h = cls;
    if (toe == MHD_CONNECTION_NOTIFY_STARTED) {
        const union MHD_ConnectionInfo *fi =
            MHD_get_connection_info(mc, MHD_CONNECTION_INFO_CONNECTION_FD);
        if (fi) refuse_bad_start(fi->connect_fd);
        /* NULL (out of memory): no escape check and no deadline for this one */
        sock_ctx *sc = calloc(1, sizeof *sc);
        const union MHD_ConnectionInfo *ci =
            MHD_get_connection_info(mc, MHD_CONNECTION_INFO_CONNECTION_FD);
        if (sc && ci) {
            sc->fd = ci->connect_fd;
            sc->reading = "headers";
            pthread_mutex_lock(&h->conns_mu);
            sc->deadline = engine_now() + h->cfg->header_timeout;
            sc->next = h->conns;
            if (h->conns) h->conns->prev = sc;
            h->conns = sc;
            pthread_mutex_unlock(&h->conns_mu);
        }
        *socket_context = sc && ci ? sc : NULL;
        if (sc && !ci) free(sc);
    } else if (toe == MHD_CONNECTION_NOTIFY_CLOSED) {
        sock_ctx *sc = *socket_context;
        if (sc) {
            pthread_mutex_lock(&h->conns_mu);
            if (sc->prev)
                sc->prev->next = sc->next;
            else
                h->conns = sc->next;
            if (sc->next) sc->next->prev = sc->prev;
            pthread_mutex_unlock(&h->conns_mu);
            free(sc);
        }
        *socket_context = NULL;
    }
}

/* Shuts the sockets of connections past their deadline, four times a second. */
static void *reaper_main(void *arg)
{
    http_server *h = arg;
    pthread_mutex_lock(&h->conns_mu);
    while (!h->reaper_stop) {
        double now = engine_now(), t = now + 0.25;
        struct timespec ts = {.tv_sec = (time_t)t,
                              .tv_nsec = (long)((t - (double)(time_t)t) * 1e9)};
        pthread_cond_timedwait(&h->reaper_cv, &h->conns_mu, &ts);
        now = engine_now();
        for (sock_ctx *sc = h->conns; sc; sc = sc->next)
            if (sc->deadline > 0 && now > sc->deadline) {
                sc->deadline = 0;
                shutdown(sc->fd, SHUT_RDWR);
                log_kv(LOG_INFO, "connection closed: too slow", "reading", sc->reading, NULL);
            }
    }
    pthread_mutex_unlock(&h->conns_mu);
    return NULL;
}

static int hexval(char ch)
{
    return ch >= '0' && ch <= '9'   ? ch - '0'
           : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10
           : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10
                                    : -1;
}

/* MHD_OPTION_UNESCAPE_CALLBACK: decodes %XX in place (the path and the query's keys and
 * values), as MHD's own does, but notes what MHD lets through: %00, which would cut the
 * string short (/healthz%00x was /healthz), and a % without two hex digits.  The handler
 * then answers 400. */
static size_t unescape(void *cls, struct MHD_Connection *mc, char *s)
{
    (void)cls;
    char *w = s;
    int bad = 0;
    for (const char *r = s; *r;) {
        int hi, lo;
        if (*r != '%') {
            *w++ = *r++;
        } else if ((hi = hexval(r[1])) >= 0 && (lo = hexval(r[2])) >= 0 && (hi || lo)) {
            *w++ = (char)(hi * 16 + lo);
            r += 3;
        } else {
            bad = 1;
            *w++ = *r++; /* left as it is */
        }
    }
    *w = 0;
    sock_ctx *sc = bad ? sock_of(mc) : NULL;
    if (sc) sc->bad_escape = 1;
    return (size_t)(w - s);
}

http_server *http_start(const config *cfg, engine *e, store *st, metrics *m, char *err,
                        size_t errlen)
{
    struct addrinfo hints = {.ai_family = AF_UNSPEC,
                             .ai_socktype = SOCK_STREAM,
                             .ai_flags = AI_NUMERICSERV | AI_PASSIVE};
    struct addrinfo *ai = NULL;
    char port[8];
    snprintf(port, sizeof port, "%u", cfg->port);
    int gai = getaddrinfo(cfg->host[0] ? cfg->host : NULL, port, &hints, &ai);
    if (gai) {
        snprintf(err, errlen, "cannot resolve %s: %s", cfg->host, gai_strerror(gai));
        return NULL;
    }
    http_server *h = calloc(1, sizeof *h);
    if (!h) {
        freeaddrinfo(ai);
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    h->cfg = cfg;
    h->e = e;
    h->st = st;
    h->m = m;
    atomic_init(&h->draining, 0);
    atomic_init(&h->parked, 0);
    atomic_init(&h->inflight, 0);
    pthread_mutex_init(&h->ready_mu, NULL);
    pthread_mutex_init(&h->conns_mu, NULL);
    pthread_mutex_init(&h->memo_mu, NULL);
    h->memo = calloc(MEMO_SLOTS, sizeof *h->memo); /* NULL: a full queue refuses every POST */
    pthread_mutex_init(&h->in_mu, NULL);
    pthread_cond_init(&h->in_cv, NULL);
    pthread_cond_init(&h->reaper_cv, NULL);
    unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_EPOLL | MHD_ALLOW_SUSPEND_RESUME |
                     MHD_USE_ERROR_LOG | (ai->ai_family == AF_INET6 ? MHD_USE_IPv6 : 0);
    h->d = MHD_start_daemon(
        flags, (uint16_t)cfg->port, NULL, NULL, handle, h, MHD_OPTION_SOCK_ADDR, ai->ai_addr,
        MHD_OPTION_THREAD_POOL_SIZE, (unsigned)4, MHD_OPTION_CONNECTION_TIMEOUT,
        (unsigned)cfg->idle_timeout, MHD_OPTION_CONNECTION_LIMIT, (unsigned)cfg->max_connections,
        MHD_OPTION_PER_IP_CONNECTION_LIMIT, (unsigned)cfg->max_per_ip, MHD_OPTION_NOTIFY_COMPLETED,
        completed, h, MHD_OPTION_NOTIFY_CONNECTION, notify_connection, h,
        MHD_OPTION_UNESCAPE_CALLBACK, unescape, NULL, MHD_OPTION_STRICT_FOR_CLIENT, (int)1,
        MHD_OPTION_EXTERNAL_LOGGER, mhd_log, NULL, MHD_OPTION_END);
    freeaddrinfo(ai);
    if (!h->d) {
        snprintf(err, errlen, "cannot listen on %s:%u (in use, or not an address of this host)",
                 cfg->host, cfg->port);
        http_free(h);
        return NULL;
    }
    /* a connection is accepted once its first bytes are in (up to the header timeout), so that
     * refuse_bad_start sees them as MHD accepts it */
    const union MHD_DaemonInfo *li = MHD_get_daemon_info(h->d, MHD_DAEMON_INFO_LISTEN_FD);
    int defer = (int)(cfg->header_timeout > 1 ? cfg->header_timeout : 1);
    if (li && setsockopt(li->listen_fd, IPPROTO_TCP, TCP_DEFER_ACCEPT, &defer, sizeof defer))
        log_kv(LOG_WARN,
               "TCP_DEFER_ACCEPT refused: a bad first byte is seen only when it comes "
               "with the connection",
               NULL);
    if (pthread_create(&h->reaper, NULL, reaper_main, h) != 0) {
        snprintf(err, errlen, "cannot start the connection reaper thread");
        MHD_stop_daemon(h->d);
        http_free(h);
        return NULL;
    }
    h->reaper_started = 1;
    int nin = cfg->intake_threads > 0 ? cfg->intake_threads : 1;
    h->in_threads = calloc((size_t)nin, sizeof *h->in_threads);
    for (int i = 0; h->in_threads && i < nin; i++) {
        if (pthread_create(&h->in_threads[i], NULL, intake_main, h) != 0) break;
        h->in_nthreads++;
    }
    if (h->in_nthreads == 0) {
        snprintf(err, errlen, "cannot start the intake threads");
        http_stop(h);
        return NULL;
    }
    return h;
}

unsigned http_port(http_server *h)
{
    const union MHD_DaemonInfo *i = MHD_get_daemon_info(h->d, MHD_DAEMON_INFO_BIND_PORT);
    return i ? i->port : 0;
}

void http_set_draining(http_server *h)
{
    atomic_store(&h->draining, 1);
}

void http_stop(http_server *h)
{
    if (!h) return;
    /* the waits that the drain woke are answered before every connection is closed (for 5 s
     * at most: a client that does not read its answer cannot hold the exit) */
    /* the intake finishes what it holds (the engine drains: new jobs are refused) */
    pthread_mutex_lock(&h->in_mu);
    h->in_stop = 1;
    pthread_cond_broadcast(&h->in_cv);
    pthread_mutex_unlock(&h->in_mu);
    for (int i = 0; i < h->in_nthreads; i++) pthread_join(h->in_threads[i], NULL);
    h->in_nthreads = 0;
    for (int i = 0; i < 500 && atomic_load(&h->parked) > 0; i++)
        nanosleep(&(struct timespec){0, 10000000}, NULL);
    if (h->reaper_started) {
        pthread_mutex_lock(&h->conns_mu);
        h->reaper_stop = 1;
        pthread_cond_signal(&h->reaper_cv);
        pthread_mutex_unlock(&h->conns_mu);
        pthread_join(h->reaper, NULL);
    }
    MHD_stop_daemon(h->d);
    http_free(h);
}
