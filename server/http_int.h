/* http_int.h — the private interface between the files of the HTTP server (server/http*.c);
 * nothing outside server/http*.c includes it.
 *
 *   http.c         the libmicrohttpd wiring: start and stop, the access handler (a request's
 *                  headers, its body, its answer), routing, the small routes (healthz, readyz,
 *                  metrics, OPTIONS)
 *   http_respond.c responses: queueing with the common headers (CORS, Vary), problem+json,
 *                  links with the client's prefix, a job as JSON
 *   http_assets.c  gzip, the page's assets (gzipped once) and the OpenAPI document
 *   http_result.c  results and jobs' answers: content negotiation, ETags, stored results sent
 *                  as they are read (gzipped as they go), Prefer: wait
 *   http_intake.c  request bodies (the in-flight budget, multipart, mesh files) and the intake
 *                  pool: the threads that decide a POST's answer (parse, validate, submit) and
 *                  draw the pictures of results, never on an HTTP thread; the memo cache of
 *                  bodies seen lately
 *   http_conn.c    connections: the deadlines and their reaper, the first byte's check, the
 *                  URL unescaper, parked (suspended) connections
 *
 * Threads: MHD's threads call the handler (http.c), which calls into the others; an intake
 * thread works on a conn only while its connection is suspended (c->intake == 1), so no two
 * threads touch a conn at once.
 */
#ifndef CELLAR_HTTP_INT_H
#define CELLAR_HTTP_INT_H

#include <jansson.h>
#include <microhttpd.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <zlib.h>

#include "api/api.h"
#include "api/meshio.h"
#include "api/render.h"
#include "server/http.h"

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
    pthread_mutex_t drawn_mu; /* guards drawn */
    struct drawn_slot *drawn; /* DRAWN_SLOTS: pictures drawn lately (http_result.c) */
    pthread_mutex_t memo_mu;  /* guards memo */
    struct memo_slot *memo;   /* MEMO_SLOTS: request bodies seen lately (http_intake.c) */
    /* the intake pool: POST bodies parsed, validated and submitted off the HTTP threads */
    pthread_mutex_t in_mu;
    pthread_cond_t in_cv;           /* a connection was queued, or the threads are to end */
    pthread_cond_t in_idle;         /* in_bodies came down to 0 */
    struct conn *in_head, *in_tail; /* FIFO, guarded by in_mu */
    size_t in_n;
    size_t in_bodies; /* POST bodies queued or being worked on, guarded by in_mu */
    int in_stop;      /* no more POST bodies (results are still drawn) */
    int in_quit;      /* the threads end once the queue is empty */
    pthread_t *in_threads;
    int in_nthreads;
};

/* What the intake pool is to do for a suspended connection, and what it decided, answered once
 * the connection is resumed (http_answer_plan).  A POST's body comes with a zeroed plan and
 * leaves as PLAN_PROBLEM, _STORED, _RESULT or _SUBMITTED (intake_work); a result to draw comes
 * as PLAN_DRAW and leaves as PLAN_DRAWN or PLAN_PROBLEM (http_draw). */
typedef enum {
    PLAN_PROBLEM = 0,
    PLAN_STORED,
    PLAN_RESULT,
    PLAN_SUBMITTED,
    PLAN_DRAW,
    PLAN_DRAWN
} plan_kind;
typedef struct plan {
    plan_kind kind;
    unsigned status;   /* PLAN_PROBLEM */
    char msg[320];     /* PLAN_PROBLEM */
    const char *retry; /* PLAN_PROBLEM: Retry-After, static */
    char hash[65];     /* PLAN_STORED, PLAN_RESULT, PLAN_DRAW, PLAN_DRAWN */
    uint64_t size;     /* PLAN_STORED */
    /* PLAN_DRAW, PLAN_DRAWN: the answer's X-Cellar-Job ("": none), X-Cellar-Cache (static),
     * whether it answers a POST (see store_problem) */
    char job_id[33];
    const char *cache;
    int post;
    char *body; /* PLAN_DRAWN: the picture (gzipped for c->gz), malloc'd; NULL once sent */
    size_t len;
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
    int intake;   /* suspended, with the intake pool (its body, or a result to draw; 2: done,
                     plan made) */
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
    /* A refusal the headers decided while a body follows: answered once the body is read
     * and dropped (closing on unread bytes makes the client's kernel reset the connection,
     * which can destroy the answer before the client reads it).  defer: http_problem keeps
     * its problem here instead of answering. */
    int defer;
    struct {
        unsigned status;
        const char *retry, *allow; /* string constants */
        char detail[512];
        uint64_t dropped; /* the body's bytes read and dropped */
    } later;
} conn;

/* Per TCP connection (MHD's socket context): what the URL unescaper saw in the request line
 * being read (requests on one connection are read one after the other, so the handler's
 * first call for a request reads and clears it), and the connection's deadline (see
 * http_conn.c). */
typedef struct sock_ctx {
    int bad_escape;               /* a %00, or a % not followed by two hex digits */
    int fd;                       /* the connection's socket */
    double deadline;              /* guarded by h->conns_mu; 0: none */
    const char *reading;          /* what the deadline is for: "headers" or "body" */
    struct sock_ctx *prev, *next; /* h->conns, guarded by h->conns_mu */
} sock_ctx;

/* A response header; a NULL name or value is left out. */
typedef struct hdr {
    const char *name, *value;
} hdr;

/* The path that routes: the request's, without --base-path when it begins with it. */
static inline const char *route_path(const conn *c)
{
    return c->path + c->off;
}

/* ---- http_respond.c ---- */
void http_link_to(conn *c, char *out, size_t n, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
void http_cors_origin(conn *c);
const char *http_status_title(unsigned s);
enum MHD_Result http_queue(conn *c, unsigned status, const char *ctype, struct MHD_Response *r,
                           const hdr *hs, size_t nh);
enum MHD_Result http_respond(conn *c, unsigned status, const char *ctype, char *body, size_t len,
                             int persistent, const hdr *hs, size_t nh);
enum MHD_Result http_respond_json(conn *c, unsigned status, json_t *o, const hdr *hs, size_t nh);
json_t *http_problem_json(unsigned status, const char *detail, const char *instance);
enum MHD_Result http_problem(conn *c, unsigned status, const char *detail, const char *retry,
                             const char *allow);
enum MHD_Result http_refuse_mid_body(conn *c, unsigned status, const char *detail);
enum MHD_Result http_refuse_later(conn *c, unsigned status, const char *detail, const char *retry,
                                  const char *allow);
json_t *http_job_json(conn *c, const job_info *ji);

/* ---- http_assets.c ---- */
int http_accepts_gzip(struct MHD_Connection *mc);
int http_worth_gzip(const char *ctype, size_t len);
int http_gzip_init(z_stream *z, int level);
char *http_gzip_buf(const char *data, size_t len, int level, size_t *outlen);
enum MHD_Result http_route_page(conn *c);
enum MHD_Result http_route_openapi(conn *c);

/* ---- http_result.c ---- */
int http_negotiate(conn *c, enum MHD_Result *r);
enum MHD_Result http_serve_stored(conn *c, const char *hash, uint64_t size, const char *job_id,
                                  const char *cache, int post);
enum MHD_Result http_get_result(conn *c, const char *hash, const char *job_id, const char *cache,
                                int post);
enum MHD_Result http_answer_job(conn *c);
enum MHD_Result http_submitted(conn *c);
enum MHD_Result http_route_result(conn *c);
enum MHD_Result http_route_job(conn *c, int want_result);
enum MHD_Result http_route_cancel(conn *c);
void http_draw(conn *c);
void http_drawn_free(http_server *h);
enum MHD_Result http_send_drawn(conn *c);

/* ---- http_intake.c ---- */
int http_body_reserve(conn *c, uint64_t n);
void http_body_release(conn *c);
void http_inflight_msg(const http_server *h, char *msg, size_t n);
void http_too_large_msg(const http_server *h, char *msg, size_t n);
uint64_t http_drain_limit(const http_server *h);
int http_body_type(conn *c);
enum MHD_Result http_part_data(void *cls, enum MHD_ValueKind kind, const char *key,
                               const char *filename, const char *content_type,
                               const char *transfer_encoding, const char *data, uint64_t off,
                               size_t size);
enum MHD_Result http_body_piece(conn *c, const char *upload, size_t n);
enum MHD_Result http_intake_push(conn *c);
enum MHD_Result http_answer_plan(conn *c);
void http_plan_problem(plan *pl, unsigned status, const char *msg, const char *retry);
int http_intake_start(http_server *h, int n);
void http_intake_close(http_server *h);
void http_intake_stop(http_server *h);

/* ---- http_conn.c ---- */
void http_park(conn *c);
void http_unpark(conn *c);
sock_ctx *http_sock_of(struct MHD_Connection *mc);
void http_set_deadline(http_server *h, struct MHD_Connection *mc, double secs, const char *reading);
void http_notify_connection(void *cls, struct MHD_Connection *mc, void **socket_context,
                            enum MHD_ConnectionNotificationCode toe);
size_t http_unescape(void *cls, struct MHD_Connection *mc, char *s);
int http_reaper_start(http_server *h);
void http_reaper_stop(http_server *h);

#endif
