/* http_intake.c — request bodies and their intake (see http_int.h).
 *
 * A POST's body is read on the HTTP threads into c->body against one in-flight budget for
 * every connection (--max-inflight-bytes): reserved whole when its length is known, else as
 * it comes; a multipart body is split into its parts by MHD's post processor as it arrives.
 * Once it is in, the connection is suspended and handed to the intake pool: a few threads
 * that hash, parse, validate and submit it (a body can cost seconds: an SVG's curves
 * flattened, a solid's surface checked) and decide the answer (c->plan), then resume the
 * connection; the HTTP thread makes the plan a response.  No MHD call but resume on an intake
 * thread, and no parsing on an HTTP thread.
 *
 * The memo cache: the SHA-256 of bodies seen lately with the hash of their canonical form, so
 * that a POST is refused or served without parsing while no new job can be taken.
 *
 * Threads: the body functions run on MHD's threads; intake_work on an intake thread while the
 * connection is suspended; the queue is guarded by h->in_mu, the memo by h->memo_mu.
 */
#include "server/http_int.h"

#include <openssl/evp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

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

/* Reserves n more bytes of the in-flight budget for c's body: 0, or -1 when over it. */
int http_body_reserve(conn *c, uint64_t n)
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

void http_inflight_msg(const http_server *h, char *msg, size_t n)
{
    snprintf(msg, n,
             "the service is reading its limit of request bodies (%llu bytes, "
             "--max-inflight-bytes): try again shortly",
             (unsigned long long)h->cfg->max_inflight);
}

void http_too_large_msg(const http_server *h, char *msg, size_t n)
{
    snprintf(msg, n, "the body is larger than %llu bytes", (unsigned long long)h->cfg->max_body);
}

/* The most bytes of a refused body that are read and dropped before its answer (so that the
 * answer is not lost to a reset, see conn.later): --max-body, and at least 1 MiB (so that a
 * body a little over a small --max-body gets its 413 too).  Past it the body is cut. */
uint64_t http_drain_limit(const http_server *h)
{
    return h->cfg->max_body > (1u << 20) ? h->cfg->max_body : 1u << 20;
}

/* Frees c's body and gives its bytes back to the budget. */
void http_body_release(conn *c)
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
int http_body_type(conn *c)
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
enum MHD_Result http_part_data(void *cls, enum MHD_ValueKind kind, const char *key,
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

void http_plan_problem(plan *pl, unsigned status, const char *msg, const char *retry)
{
    pl->kind = PLAN_PROBLEM;
    pl->status = status;
    snprintf(pl->msg, sizeof pl->msg, "%s", msg);
    pl->retry = retry;
}

/* A POST that no new job can be made for: ENG_FULL or ENG_DRAINING. */
static void plan_refused(plan *pl, int why)
{
    http_plan_problem(pl, 503,
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

/* The intake of a POST (on an intake thread, never on an HTTP thread: parsing and validating a
 * body can cost seconds, an SVG's curves flattened, a solid's surface checked): what the
 * answer will be, in c->plan, made into a response by http_answer_plan() once the connection is
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
        http_body_release(c);
        return http_plan_problem(pl, 503, err, "5");
    }
    if (full != ENG_OK) { /* no new job: answer without parsing (see memo_slot) */
        http_body_release(c);
        if (!memo_get(h, raw, hash)) return plan_refused(pl, full);
        hit = h->st->ops->result_size(h->st, hash, &size, c->job_id, err, sizeof err);
        metrics_cache(h->m, hit == STORE_OK);
        if (hit == STORE_OK) return plan_result(pl, PLAN_STORED, hash, size);
        rc = engine_join(h->e, hash, c->job_id, c->job, err, sizeof err);
        if (rc == ENG_NOTFOUND) return plan_refused(pl, full);
        if (rc != ENG_OK) return http_plan_problem(pl, 503, err, "5");
        pl->kind = PLAN_SUBMITTED;
        return;
    }

    if (c->body_type != BODY_JSON) { /* a mesh, or mesh files: their "solids" request */
        char *json = NULL;
        size_t jlen = 0;
        rc = mesh_body_request(c, &json, &jlen, &ae);
        http_body_release(c);
        if (rc != API_OK)
            return http_plan_problem(pl, (unsigned)rc, ae.msg, rc == API_ENOMEM ? "5" : NULL);
        if (jlen > h->cfg->max_body) { /* the request the files make, as a JSON body is held */
            char msg[200];
            snprintf(msg, sizeof msg,
                     "the solids request these mesh files make is %zu bytes, more than the %llu "
                     "a request may hold (--max-body)",
                     jlen, (unsigned long long)h->cfg->max_body);
            free(json);
            return http_plan_problem(pl, 413, msg, NULL);
        }
        c->body = json;
        c->len = jlen;
    }
    api_request *checked = NULL; /* parsed and checked once: handed to the worker */
    rc = api_check_request_ex(c->body ? c->body : "", c->len, &canon, &clen, &kind, &checked, &ae);
    http_body_release(c);
    if (rc != API_OK)
        return http_plan_problem(pl, (unsigned)rc, ae.msg, rc == API_ENOMEM ? "5" : NULL);
    engine_hash(canon, clen, hash);
    memo_put(h, raw, hash);

    /* a cached result costs one lookup (its size and the job that made it, then it is served) */
    hit = h->st->ops->result_size(h->st, hash, &size, c->job_id, err, sizeof err);
    metrics_cache(h->m, hit == STORE_OK);
    if (hit == STORE_OK) {
        free(canon);
        api_request_free(checked);
        return plan_result(pl, PLAN_STORED, hash, size);
    }
    int coalesced = 0;
    rc = engine_submit(h->e, canon, clen, kind, hash, checked, c->job_id, c->job, &coalesced, err,
                       sizeof err);
    free(canon);
    if (rc == ENG_CACHED) /* an identical job ended between our two looks */
        return plan_result(pl, PLAN_RESULT, hash, 0);
    if (rc == ENG_FULL || rc == ENG_DRAINING) return plan_refused(pl, rc);
    if (rc != ENG_OK) return http_plan_problem(pl, 503, err, "5");
    pl->kind = PLAN_SUBMITTED;
}

/* The answer to a POST whose intake is done (on the HTTP thread). */
enum MHD_Result http_answer_plan(conn *c)
{
    plan *pl = &c->plan;
    switch (pl->kind) {
    case PLAN_STORED:
        return http_serve_stored(c, pl->hash, pl->size, c->job_id[0] ? c->job_id : NULL, "hit", 1);
    case PLAN_RESULT:
        return http_get_result(c, pl->hash, NULL, "hit", 1);
    case PLAN_SUBMITTED:
        return http_submitted(c);
    case PLAN_DRAWN:
        return http_send_drawn(c);
    default:
        return http_problem(c, pl->status, pl->msg, pl->retry, NULL);
    }
}

/* Hands a POST (or, c->plan PLAN_DRAW, a result to draw) to the intake pool: the connection is
 * suspended until an intake thread has decided its answer (c->plan) and resumes it.
 * Suspended before it is queued, so that no thread can resume it before it is suspended. */
enum MHD_Result http_intake_push(conn *c)
{
    http_server *h = c->h;
    int draw = c->plan.kind == PLAN_DRAW;
    pthread_mutex_lock(&h->in_mu);
    if (h->in_n >= INTAKE_MAX || (h->in_stop && !draw) || h->in_quit) {
        pthread_mutex_unlock(&h->in_mu);
        http_body_release(c);
        return http_problem(c, 503, "too many requests are being read: try again", "1", NULL);
    }
    c->intake = 1;
    http_park(c);
    MHD_suspend_connection(c->mc);
    c->next_intake = NULL;
    if (h->in_tail)
        h->in_tail->next_intake = c;
    else
        h->in_head = c;
    h->in_tail = c;
    h->in_n++;
    h->in_bodies += !draw;
    pthread_cond_signal(&h->in_cv);
    pthread_mutex_unlock(&h->in_mu);
    return MHD_YES;
}

static void *intake_main(void *arg)
{
    http_server *h = arg;
    pthread_mutex_lock(&h->in_mu);
    for (;;) {
        while (!h->in_head && !h->in_quit) pthread_cond_wait(&h->in_cv, &h->in_mu);
        conn *c = h->in_head;
        if (!c) break; /* stopping, and nothing left */
        h->in_head = c->next_intake;
        if (!h->in_head) h->in_tail = NULL;
        h->in_n--;
        pthread_mutex_unlock(&h->in_mu);
        int draw = c->plan.kind == PLAN_DRAW;
        if (draw)
            http_draw(c);
        else
            intake_work(c);
        c->intake = 2;
        MHD_resume_connection(c->mc);
        pthread_mutex_lock(&h->in_mu);
        if (!draw && --h->in_bodies == 0) pthread_cond_broadcast(&h->in_idle);
    }
    pthread_mutex_unlock(&h->in_mu);
    return NULL;
}

/* A piece of a POST's body (n bytes at upload): kept (multipart: through the post processor),
 * or, past --max-body or the in-flight budget, refused mid-body (http_refuse_mid_body). */
enum MHD_Result http_body_piece(conn *c, const char *upload, size_t n)
{
    http_server *h = c->h;
    uint64_t seen = c->pp ? c->raw : c->len; /* multipart: len counts the parts' data */
    if (seen + n > h->cfg->max_body) {
        /* no Content-Length said so (chunked): the rest is read and dropped up to
         * http_drain_limit, then the 413 (conn.later); past it, never read */
        char msg[128];
        http_body_release(c);
        http_too_large_msg(h, msg, sizeof msg);
        if (seen + n > http_drain_limit(h)) return http_refuse_mid_body(c, 413, msg);
        c->later.dropped = seen + n;
        return http_refuse_later(c, 413, msg, NULL, NULL);
    }
    if (seen + n + 1 > c->cap) { /* chunked: no length was reserved */
        size_t cap = c->cap ? c->cap : 4096;
        while (cap < seen + n + 1) cap *= 2;
        if (cap > h->cfg->max_body + 1) cap = h->cfg->max_body + 1;
        if (http_body_reserve(c, cap - c->cap)) {
            char msg[200];
            http_inflight_msg(h, msg, sizeof msg);
            http_body_release(c);
            return http_refuse_mid_body(c, 503, msg);
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

/* Starts n intake threads (at least one) and the memo cache: 0, or -1 when no thread could be
 * started. */
int http_intake_start(http_server *h, int n)
{
    h->memo = calloc(MEMO_SLOTS, sizeof *h->memo); /* NULL: a full queue refuses every POST */
    h->in_threads = calloc((size_t)n, sizeof *h->in_threads);
    for (int i = 0; h->in_threads && i < n; i++) {
        if (pthread_create(&h->in_threads[i], NULL, intake_main, h) != 0) break;
        h->in_nthreads++;
    }
    return h->in_nthreads ? 0 : -1;
}

/* Closes the intake to POST bodies (one pushed from now on is answered 503) and returns once
 * those it holds are answered (the engine drains: new jobs are refused).  Results are still
 * drawn, for the waits the drain wakes. */
void http_intake_close(http_server *h)
{
    pthread_mutex_lock(&h->in_mu);
    h->in_stop = 1;
    while (h->in_bodies > 0 && h->in_nthreads > 0) pthread_cond_wait(&h->in_idle, &h->in_mu);
    pthread_mutex_unlock(&h->in_mu);
}

/* Stops the intake: what it holds is finished, then its threads are joined. */
void http_intake_stop(http_server *h)
{
    pthread_mutex_lock(&h->in_mu);
    h->in_stop = h->in_quit = 1;
    pthread_cond_broadcast(&h->in_cv);
    pthread_mutex_unlock(&h->in_mu);
    for (int i = 0; i < h->in_nthreads; i++) pthread_join(h->in_threads[i], NULL);
    h->in_nthreads = 0;
}
