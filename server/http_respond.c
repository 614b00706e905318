/* http_respond.c — the HTTP server's responses (see http_int.h): every answer is queued by
 * http_queue, which adds the headers every answer carries (CORS, Vary), so that a handler's
 * paths differ only in what they say.  Errors are problem+json (RFC 9457) naming the JSON path
 * of the message when it starts with one; links (Location, "result", "instance") carry the
 * client's prefix (X-Forwarded-Prefix or --base-path).
 *
 * Threads: MHD's threads, on a connection not suspended (http_problem_json and http_job_json
 * are pure and run anywhere).
 */
#include "server/http_int.h"

#include <ctype.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <time.h>

/* A link back to this service as the client sees it, into out: c->prefix (X-Forwarded-Prefix,
 * else --base-path, else "") then the printf of fmt (a path from "/").  Every URL the daemon
 * writes (Location, Content-Location, job "result", problem "instance", OpenAPI "servers") is
 * made here, and the answer then varies with X-Forwarded-Prefix (http_queue() says so). */
void http_link_to(conn *c, char *out, size_t n, const char *fmt, ...)
{
    va_list ap;
    int k = snprintf(out, n, "%s", c->prefix);
    c->linked = 1;
    if (k < 0 || (size_t)k >= n) return;
    va_start(ap, fmt);
    vsnprintf(out + k, n - (size_t)k, fmt, ap);
    va_end(ap);
}

/* What a CORS answer lets a page elsewhere read. */
#define CORS_EXPOSE                                                                                \
    "Location, Content-Location, Retry-After, ETag, X-Cellar-Job, X-Cellar-Cache, "                \
    "Preference-Applied"

/* c->origin from the request's Origin and --cors-origins ("*": any origin; else a comma-separated
 * list of origins, compared exactly); "" when CORS does not apply. */
void http_cors_origin(conn *c)
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

const char *http_status_title(unsigned s)
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

/* Queues r (destroyed here, NULL: out of memory) with its headers. */
enum MHD_Result http_queue(conn *c, unsigned status, const char *ctype, struct MHD_Response *r,
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

/* Queues the response: body is malloc'd and taken (or, with `persistent`, static); a body worth
 * it goes gzipped to a client that takes gzip. */
enum MHD_Result http_respond(conn *c, unsigned status, const char *ctype, char *body, size_t len,
                             int persistent, const hdr *hs, size_t nh)
{
    hdr all[16];
    size_t na = 0;
    for (size_t i = 0; i < nh && na < 14; i++) all[na++] = hs[i];
    if (http_worth_gzip(ctype, len)) {
        all[na++] = (hdr){MHD_HTTP_HEADER_VARY, "Accept-Encoding"};
        size_t zl = 0;
        char *z = c->gz ? http_gzip_buf(body, len, 1, &zl) : NULL;
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
    return http_queue(c, status, ctype, r, all, na);
}

enum MHD_Result http_respond_json(conn *c, unsigned status, json_t *o, const hdr *hs, size_t nh)
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
    return http_respond(c, status, "application/json", b, n + 1, 0, hs, nh);
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

json_t *http_problem_json(unsigned status, const char *detail, const char *instance)
{
    char path[200];
    json_t *o = json_object();
    if (!o) return NULL;
    json_object_set_new(o, "type", json_string("about:blank"));
    json_object_set_new(o, "title", json_string(http_status_title(status)));
    json_object_set_new(o, "status", json_integer(status));
    json_t *d = json_string(detail);
    json_object_set_new(o, "detail", d ? d : json_string("(message not UTF-8)"));
    json_t *in = json_string(instance); /* a client's path: may not be UTF-8 */
    json_object_set_new(o, "instance", in ? in : json_string("(path not UTF-8)"));
    message_path(detail, path, sizeof path);
    if (path[0]) json_object_set_new(o, "path", json_string(path));
    return o;
}

/* Keeps a refusal, answered once the body is read and dropped (conn.later): the body held
 * so far is let go, and the connection, read to the body's end, stays in step. */
enum MHD_Result http_refuse_later(conn *c, unsigned status, const char *detail, const char *retry,
                                  const char *allow)
{
    c->later.status = status;
    c->later.retry = retry;
    c->later.allow = allow;
    snprintf(c->later.detail, sizeof c->later.detail, "%s", detail);
    c->close = 0;
    http_body_release(c);
    return MHD_YES;
}

enum MHD_Result http_problem(conn *c, unsigned status, const char *detail, const char *retry,
                             const char *allow)
{
    /* decided from the headers while a body follows: answered after it */
    if (c->defer) return http_refuse_later(c, status, detail, retry, allow);
    char instance[CONFIG_PREFIX_MAX + sizeof c->path];
    http_link_to(c, instance, sizeof instance, "%s", route_path(c));
    json_t *o = http_problem_json(status, detail, instance);
    char *s = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    if (!s) return MHD_NO;
    hdr hs[] = {{MHD_HTTP_HEADER_RETRY_AFTER, retry},
                {MHD_HTTP_HEADER_ALLOW, allow},
                {c->close ? MHD_HTTP_HEADER_CONNECTION : NULL, "close"}};
    return http_respond(c, status, "application/problem+json", s, strlen(s), 0, hs, 3);
}

/* An answer in the middle of a body, where MHD cannot queue one (it would read the body to
 * its end first: 1 GB of chunks before a 413): the problem is written to the socket here,
 * its sending side shut, and MHD told to close the connection.  A client that stops sending
 * to read gets the answer; one that keeps sending gets a reset. */
enum MHD_Result http_refuse_mid_body(conn *c, unsigned status, const char *detail)
{
    c->status = status;
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c->mc, MHD_CONNECTION_INFO_CONNECTION_FD);
    char instance[CONFIG_PREFIX_MAX + sizeof c->path];
    http_link_to(c, instance, sizeof instance, "%s", route_path(c));
    json_t *o = http_problem_json(status, detail, instance);
    char *body = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    if (ci && body) {
        char head[256];
        size_t blen = strlen(body);
        int n = snprintf(head, sizeof head,
                         "HTTP/1.1 %u %s\r\nContent-Type: application/problem+json\r\n"
                         "Content-Length: %zu\r\nConnection: close\r\n\r\n",
                         status, http_status_title(status), blen + 1);
        struct iovec iov[3] = {{head, (size_t)n}, {body, blen}, {"\n", 1}};
        struct msghdr mh = {.msg_iov = iov, .msg_iovlen = 3};
        (void)sendmsg(ci->connect_fd, &mh, MSG_NOSIGNAL | MSG_DONTWAIT);
        shutdown(ci->connect_fd, SHUT_WR);
    }
    free(body);
    return MHD_NO;
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
json_t *http_job_json(conn *c, const job_info *ji)
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
        http_link_to(c, url, sizeof url, "/v1/jobs/%s", ji->id);
        json_object_set_new(o, "error",
                            http_problem_json((unsigned)ji->error_status, ji->error, url));
    }
    if (ji->state == JOB_DONE) {
        http_link_to(c, url, sizeof url, "/v1/results/%s", ji->hash);
        json_object_set_new(o, "result", json_string(url));
    }
    return o;
}
