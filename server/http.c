/* http.c — see http.h; the files of the server and their private interface: http_int.h.
 *
 * This file wires libmicrohttpd and routes.  Every connection gets a `conn` (MHD's con_cls) on
 * the first call of the access handler (on_headers: early answers before any body is read);
 * the body arrives in later calls (http_body_piece: kept up to max_body, the rest refused
 * 413); the last call (no upload data) answers (on_request).  A POST is handed to the intake
 * pool (http_intake.c) and its connection suspended until its answer is decided; one that
 * asks to wait is suspended again until the engine's wake callback resumes it; MHD then calls
 * the handler once more and the job's state decides the answer.  The request-completed
 * callback logs the request, counts it in the metrics and frees the conn.
 *
 * Exactly one response per request: every path of handle() ends in http_respond() (which
 * queues it) or in a suspension whose resumption ends in http_respond().
 */
#include "server/http_int.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>

#include "server/log.h"

static enum MHD_Result status_json(conn *c, unsigned status, const char *value, const char *error)
{
    json_t *o = json_object();
    json_object_set_new(o, "status", json_string(value));
    if (error) json_object_set_new(o, "error", json_string(error));
    return http_respond_json(c, status, o, NULL, 0);
}

static enum MHD_Result route_metrics(conn *c)
{
    metrics_gauges g = {0};
    char err[256];
    engine_gauges(c->h->e, &g.queued, &g.running, &g.running_here, &g.queue_capacity, &g.draining);
    engine_checked_kept(c->h->e, &g.checked_kept, &g.checked_bytes);
    if (c->h->st->ops->result_stats(c->h->st, &g.cache_results, &g.cache_bytes, err, sizeof err))
        log_kv(LOG_WARN, "store: result_stats failed", "error", err, NULL);
    g.cache_budget = c->h->cfg->cache_bytes;
    size_t len;
    char *s = metrics_render(c->h->m, &g, &len);
    if (!s) return MHD_NO;
    return http_respond(c, 200, "text/plain; version=0.0.4; charset=utf-8", s, len, 0, NULL, 0);
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
    if (!a) return http_problem(c, 404, "no such resource", NULL, NULL);
    hdr hs[] = {{MHD_HTTP_HEADER_ALLOW, a},
                {c->origin[0] ? "Access-Control-Allow-Methods" : NULL, a},
                {c->origin[0] ? "Access-Control-Allow-Headers" : NULL,
                 "Content-Type, Accept, Prefer, If-None-Match"},
                {c->origin[0] ? "Access-Control-Max-Age" : NULL, "600"}};
    return http_respond(c, 204, NULL, NULL, 0, 1, hs, sizeof hs / sizeof *hs);
}

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

static enum MHD_Result dispatch(conn *c)
{
    const char *m = c->method;
    int get = !strcmp(m, "GET") || !strcmp(m, "HEAD");
    if (!strcmp(m, "OPTIONS")) return route_options(c);
    switch (c->route) {
    case ROUTE_INDEX:
        if (!get) break;
        return http_route_page(c);
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
        return http_route_openapi(c);
    case ROUTE_JOBS:
        if (strcmp(m, "POST")) return http_problem(c, 405, "use POST", NULL, "POST");
        return http_intake_push(c);
    case ROUTE_JOB:
        if (get) return http_route_job(c, 0);
        if (!strcmp(m, "DELETE")) return http_route_cancel(c);
        return http_problem(c, 405, "use GET or DELETE", NULL, "GET, HEAD, DELETE");
    case ROUTE_JOB_RESULT: {
        enum MHD_Result r;
        if (get && http_negotiate(c, &r)) return r;
        if (get) return http_route_job(c, 1);
        return http_problem(c, 405, "use GET", NULL, "GET, HEAD");
    }
    case ROUTE_RESULT: {
        enum MHD_Result r;
        if (get && http_negotiate(c, &r)) return r;
        if (get) return http_route_result(c);
        return http_problem(c, 405, "use GET", NULL, "GET, HEAD");
    }
    default:
        return http_problem(c, 404, "no such resource", NULL, NULL);
    }
    return http_problem(c, 405, "use GET", NULL, "GET, HEAD");
}

/* A refusal answered at once, whether a body follows or not (c->defer off): the body is
 * never read. */
static enum MHD_Result refuse_now(conn *c, unsigned status, const char *detail, const char *retry)
{
    c->defer = 0;
    return http_problem(c, status, detail, retry, NULL);
}

/* The request's framing (RFC 9112 6.1): a body is framed by Content-Length or by chunks, never
 * both (a request with both is an attack on whoever reads it next), and chunked is the only
 * coding understood: past such a request the stream cannot be trusted, so it is closed.
 * 0, or 1 with the 400 queued in *r (at once: past bad framing the body cannot be found). */
static int bad_framing(conn *c, enum MHD_Result *r)
{
    struct MHD_Connection *mc = c->mc;
    const char *te =
        MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_TRANSFER_ENCODING);
    if (!te) return 0;
    const char *why = NULL;
    if (MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH)) {
        why = "Content-Length and Transfer-Encoding together";
    } else {
        while (*te == ' ' || *te == '\t') te++;
        size_t n = strlen(te);
        while (n && (te[n - 1] == ' ' || te[n - 1] == '\t')) n--;
        if (n != 7 || strncasecmp(te, "chunked", 7))
            why = "Transfer-Encoding: only chunked is understood";
    }
    if (!why) return 0;
    c->close = 1;
    *r = refuse_now(c, 400, why, NULL);
    return 1;
}

/* The headers of a POST /v1/jobs: what they refuse, and its bytes reserved against the
 * in-flight budget.  Draining and over the budget are answered at once with Connection:
 * close, the body never read; too large, a type not read or a representation not made
 * once the body is read and dropped when it is small (c->defer, see body_follows), else
 * at once. */
static enum MHD_Result post_headers(conn *c)
{
    http_server *h = c->h;
    struct MHD_Connection *mc = c->mc;
    if (atomic_load(&h->draining)) return refuse_now(c, 503, "the service is shutting down", "5");
    const char *cl =
        MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    c->close = 1; /* an early answer: the body that follows is not read (but see c->defer) */
    unsigned long long clv = cl ? strtoull(cl, NULL, 10) : 0;
    if (cl && clv > h->cfg->max_body) {
        char msg[128];
        http_too_large_msg(h, msg, sizeof msg);
        return http_problem(c, 413, msg, NULL, NULL);
    }
    if (http_body_type(c))
        return http_problem(c, 415,
                            "the body must be application/json, one mesh (model/stl, "
                            "model/obj, model/3mf, model/vnd.ply, model/vnd.off) or "
                            "multipart/form-data of mesh files",
                            NULL, NULL);
    if (c->body_type == BODY_MULTIPART &&
        !(c->pp = MHD_create_post_processor(mc, 65536, http_part_data, c)))
        return http_problem(c, 415, "multipart/form-data without a boundary", NULL, NULL);
    /* the representation of a result answered to this POST (Accept, ?format= and the
     * drawing options), decided before the body is read: 406 or 422 at once */
    enum MHD_Result nr;
    if (http_negotiate(c, &nr)) return nr;
    /* the body's bytes are reserved before any is read (all of them when the length
     * is known, else as they come), against one budget for every connection */
    if (cl && (http_body_reserve(c, clv + 1) || !(c->body = malloc(clv + 1)))) {
        char msg[200]; /* the budget is spent: no time is spent reading a body refused */
        http_inflight_msg(h, msg, sizeof msg);
        return refuse_now(c, 503, msg, "1");
    }
    if (cl) c->cap = clv + 1;
    c->close = 0;
    return MHD_YES;
}

/* Whether a refusal made from the headers waits for the body (conn.later): one follows, it
 * is not larger than http_drain_limit, and the client is not waiting for a 100 Continue (which
 * it then never gets: the answer comes at once and the body is never sent). */
static int body_follows(const conn *c)
{
    struct MHD_Connection *mc = c->mc;
    const char *cl =
        MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    const char *te =
        MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_TRANSFER_ENCODING);
    const char *ex = MHD_lookup_connection_value(mc, MHD_HEADER_KIND, MHD_HTTP_HEADER_EXPECT);
    if (ex && strcasestr(ex, "100-continue")) return 0;
    if (te) return 1; /* chunked: its bytes are counted as they are dropped */
    if (!cl) return 0;
    unsigned long long n = strtoull(cl, NULL, 10);
    return n > 0 && n <= http_drain_limit(c->h);
}

/* The first call for a request: its headers are in.  Makes its conn (*con_cls) and answers
 * what needs no body (a bad prefix, escape or framing; a POST refused early): at once, or
 * when a body follows, once it is read (body_follows; bad framing, a body over http_drain_limit,
 * the in-flight budget spent and a service shutting down are answered at once, the
 * connection closed). */
static enum MHD_Result head_checks(conn *c, const char *url, const char *method);

static enum MHD_Result on_headers(http_server *h, struct MHD_Connection *mc, const char *url,
                                  const char *method, void **con_cls)
{
    conn *c = calloc(1, sizeof *c);
    if (!c) return MHD_NO;
    *con_cls = c;
    c->h = h;
    c->mc = mc;
    c->defer = body_follows(c);
    enum MHD_Result r = head_checks(c, url, method);
    c->defer = 0;
    return r;
}

static enum MHD_Result head_checks(conn *c, const char *url, const char *method)
{
    http_server *h = c->h;
    struct MHD_Connection *mc = c->mc;
    /* the headers are in: the body (if any) has --body-timeout from now */
    http_set_deadline(h, mc, h->cfg->body_timeout, "body");
    c->t0 = engine_now();
    snprintf(c->method, sizeof c->method, "%s", method);
    snprintf(c->path, sizeof c->path, "%s", url);
    /* --base-path: a path under it is served without it (a proxy that passes the path
     * whole); one that is the base path itself goes to the page (http_route_page) */
    const char *bp = h->cfg->base_path;
    size_t bl = strlen(bp);
    if (bl && !strncmp(url, bp, bl) && (url[bl] == '/' || !url[bl]) && bl < sizeof c->path)
        c->off = bl;
    c->route = c->off && !url[bl] ? ROUTE_INDEX : classify(url + c->off, c->id);
    c->gz = http_accepts_gzip(mc);
    http_cors_origin(c);
    /* the links' prefix: the proxy's X-Forwarded-Prefix (any client may send one: it only
     * changes the links of its own answer, which then vary with it), else --base-path */
    const char *xfp = MHD_lookup_connection_value(mc, MHD_HEADER_KIND, "X-Forwarded-Prefix");
    if (xfp && *xfp) {
        const char *why;
        if (config_path_prefix(xfp, c->prefix, &why)) {
            char msg[300];
            snprintf(msg, sizeof msg, "X-Forwarded-Prefix: invalid value \"%.100s\": %s", xfp, why);
            c->close = 1; /* a body that follows is not read */
            return http_problem(c, 400, msg, NULL, NULL);
        }
    } else {
        memcpy(c->prefix, bp, bl + 1);
    }
    sock_ctx *sc = http_sock_of(mc);
    int bad_escape = sc && sc->bad_escape;
    if (sc) sc->bad_escape = 0;
    if (bad_escape)
        return http_problem(c, 400,
                            "the URL has a bad percent-escape (%00, or % not followed by two hex "
                            "digits)",
                            NULL, NULL);
    enum MHD_Result r;
    if (bad_framing(c, &r)) return r;
    if (c->route == ROUTE_JOBS && !strcmp(method, "POST")) return post_headers(c);
    return MHD_YES;
}

/* The last call for a request (its body, if any, is in), and the call after each resumption:
 * the answer. */
static enum MHD_Result on_request(conn *c)
{
    if (c->pp) { /* the body is in: the parts are all found */
        if (MHD_destroy_post_processor(c->pp) != MHD_YES && !c->mp_err[0])
            snprintf(c->mp_err, sizeof c->mp_err, "the body ends inside a part");
        c->pp = NULL;
    }
    http_set_deadline(c->h, c->mc, 0, NULL); /* the request is in: no deadline */
    if (c->status) return MHD_YES;           /* answered before the body (413, 503) */
    if (c->later.status)                     /* refused from the headers: the body is dropped */
        return http_problem(c, c->later.status, c->later.detail, c->later.retry, c->later.allow);
    if (c->intake == 2) { /* resumed: the intake has decided */
        c->intake = 0;
        http_unpark(c);
        return http_answer_plan(c);
    }
    if (c->waiting) { /* resumed: the job ended or the wait is over */
        c->waiting = 0;
        return http_answer_job(c);
    }
    return dispatch(c);
}

/* MHD's access handler: the headers, each piece of the body, then the answer. */
static enum MHD_Result handle(void *cls, struct MHD_Connection *mc, const char *url,
                              const char *method, const char *version, const char *upload,
                              size_t *upload_size, void **con_cls)
{
    (void)version;
    conn *c = *con_cls;
    if (!c) return on_headers(cls, mc, url, method, con_cls);
    if (*upload_size) { /* a piece of the body */
        size_t n = *upload_size;
        *upload_size = 0;
        if (c->status) return MHD_YES; /* answered already */
        if (c->later.status) {         /* refused from the headers: dropped, up to the limit */
            c->later.dropped += n;
            if (c->later.dropped > http_drain_limit(c->h))
                return http_refuse_mid_body(c, c->later.status, c->later.detail);
            return MHD_YES;
        }
        if (c->route != ROUTE_JOBS) return MHD_YES; /* bodies of other routes are ignored */
        return http_body_piece(c, upload, n);
    }
    return on_request(c);
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
    http_unpark(c);
    if (c->pp) MHD_destroy_post_processor(c->pp);
    /* kept alive: the next request's headers are due within the idle time and the header time */
    http_set_deadline(h, mc, h->cfg->idle_timeout + h->cfg->header_timeout, "headers");
    http_body_release(c);
    free(c->plan.body);
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
    pthread_mutex_destroy(&h->drawn_mu);
    http_drawn_free(h);
    pthread_mutex_destroy(&h->in_mu);
    pthread_cond_destroy(&h->in_cv);
    pthread_cond_destroy(&h->in_idle);
    pthread_cond_destroy(&h->reaper_cv);
    free(h->in_threads);
    free(h->memo);
    free(h);
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
    pthread_mutex_init(&h->drawn_mu, NULL);
    pthread_mutex_init(&h->in_mu, NULL);
    pthread_cond_init(&h->in_cv, NULL);
    pthread_cond_init(&h->in_idle, NULL);
    pthread_cond_init(&h->reaper_cv, NULL);
    unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_EPOLL | MHD_ALLOW_SUSPEND_RESUME |
                     MHD_USE_ERROR_LOG | (ai->ai_family == AF_INET6 ? MHD_USE_IPv6 : 0);
    h->d = MHD_start_daemon(
        flags, (uint16_t)cfg->port, NULL, NULL, handle, h, MHD_OPTION_SOCK_ADDR, ai->ai_addr,
        MHD_OPTION_THREAD_POOL_SIZE, (unsigned)4, MHD_OPTION_CONNECTION_TIMEOUT,
        (unsigned)cfg->idle_timeout, MHD_OPTION_CONNECTION_LIMIT, (unsigned)cfg->max_connections,
        MHD_OPTION_PER_IP_CONNECTION_LIMIT, (unsigned)cfg->max_per_ip, MHD_OPTION_NOTIFY_COMPLETED,
        completed, h, MHD_OPTION_NOTIFY_CONNECTION, http_notify_connection, h,
        MHD_OPTION_UNESCAPE_CALLBACK, http_unescape, NULL, MHD_OPTION_STRICT_FOR_CLIENT, (int)1,
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
    if (http_reaper_start(h)) {
        snprintf(err, errlen, "cannot start the connection reaper thread");
        MHD_stop_daemon(h->d);
        http_free(h);
        return NULL;
    }
    if (http_intake_start(h, cfg->intake_threads > 0 ? cfg->intake_threads : 1)) {
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
    /* the intake finishes the bodies it holds (the engine drains: new jobs are refused), then
     * the waits that the drain woke are answered (their pictures drawn) before every
     * connection is closed (for 5 s at most: a client that does not read its answer cannot
     * hold the exit) */
    http_intake_close(h);
    for (int i = 0; i < 500 && atomic_load(&h->parked) > 0; i++)
        nanosleep(&(struct timespec){0, 10000000}, NULL);
    http_intake_stop(h);
    http_reaper_stop(h);
    MHD_stop_daemon(h->d);
    http_free(h);
}
