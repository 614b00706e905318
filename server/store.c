/* store.c — the store's policy (server/store.h), once for both backends: every operation of
 * store_ops made of the primitives of server/store_be.h, which store_sqlite.c and store_pg.c
 * implement.  Also the names of job states, store_job_clear and store_open (which picks a
 * backend by the --db value).
 *
 * What lives here: which primitives make an operation and in which transaction frame
 * (store_tx), the checks of a job before it is written, job_submit's cached / join / full /
 * make decision in one transaction (tried again when another daemon's submit made the same job
 * first), the cancel of a job's last submission, the events other daemons must hear of (when
 * the backend has them), the requeue message; for results, a put in batches with its row last
 * (a result appears whole or not at all), eviction of the least recently used to the budget,
 * reading a result back chunk by chunk with each chunk checked against its digest and the
 * chunks against the size, dropping a result that fails, the touch interval, and the
 * consistency check's messages.
 *
 * Invariants: a put's results row is written in the transaction that writes (or, after
 * batches, counts) its last chunks, then evicts; a read never returns bytes that did not match
 * their digest.  Messages are "BACKEND OP[: step]: ...", BACKEND the backend's name.
 *
 * Threads: reentrant, no globals; each call works on the calling thread's connection
 * (be->conn).  Ownership: store_job_clear() frees the job's error and request (malloc'd by a
 * backend) and leaves the struct zeroed, so clearing twice is harmless.
 */
#include "server/store.h"

#include "core/util.h"
#include "server/store_be.h"

#include <openssl/evp.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define STORE_SUBMIT_TRIES 5 /* job_submit's tries when it keeps losing the race (STORE_RACE) */

const char *job_state_name(job_state s)
{
    switch (s) {
    case JOB_QUEUED:
        return "queued";
    case JOB_RUNNING:
        return "running";
    case JOB_DONE:
        return "done";
    case JOB_FAILED:
        return "failed";
    case JOB_CANCELED:
        return "canceled";
    }
    return "unknown";
}

store *store_open(const char *db, uint64_t budget_bytes, double touch_seconds, int flags, char *err,
                  size_t errlen)
{
    if (!strncmp(db, "postgresql://", 13) || !strncmp(db, "postgres://", 11))
        return store_pg_open(db, budget_bytes, touch_seconds, flags, err, errlen);
    return store_sqlite_open(db, budget_bytes, touch_seconds, flags, err, errlen);
}

void store_job_clear(store_job *j)
{
    if (!j) return;
    free(j->error);
    free(j->request);
    memset(j, 0, sizeof *j);
}

void store_digest(const void *data, size_t n, unsigned char out[32])
{
    unsigned int len = 0;
    if (!EVP_Digest(data ? data : "", n, out, &len, EVP_sha256(), NULL) || len != 32)
        memset(out, 0, 32); /* cannot happen with OpenSSL's sha256; a wrong digest then shows */
}

/* ---- frames ---- */

static double st_clock(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* Ends the caller's transaction: commit, and on its failure (or when rc is STORE_ERR
 * already) a rollback.  Returns rc, or STORE_ERR when the commit failed. */
static int st_end(store *s, store_conn *c, int rc, const char *where, char *err, size_t errlen)
{
    if (rc != STORE_ERR && s->be->commit(c, where, err, errlen)) rc = STORE_ERR;
    if (rc == STORE_ERR) s->be->rollback(c);
    return rc;
}

/* Whether a chunk read back is the one written: its stored digest is the body's. */
int store_digest_ok(const void *body, size_t n, const void *sha, size_t shalen)
{
    unsigned char md[32];
    if (!sha || shalen != 32) return 0;
    store_digest(body, n, md);
    return memcmp(md, sha, 32) == 0;
}

/* Drops a damaged result (its row, and with it its chunks), best effort: it can be made again. */
static void st_drop(store *s, store_conn *c, const char *hash)
{
    if (s->be->begin(c, STORE_TX_ONE, "drop", NULL, 0)) return;
    st_end(s, c, s->be->result_delete(c, hash, "drop", NULL, 0), "drop", NULL, 0);
}

/* ---- jobs ---- */

/* The checks of a job before it is written (job_insert, job_submit). */
static int st_job_fields(store *s, const store_job *j, const char *where, char *err, size_t errlen)
{
    const char *name = s->be->name;
    if (j->state < JOB_QUEUED || j->state > JOB_CANCELED)
        return util_seterr(err, errlen, STORE_ERR, "%s %s: unknown state %d", name, where,
                           (int)j->state);
    if (!j->request && j->request_len)
        return util_seterr(err, errlen, STORE_ERR, "%s %s: request_len %zu with no request", name,
                           where, j->request_len);
    struct {
        const char *v, *what;
        size_t cap;
    } f[3] = {{j->id, "id", sizeof j->id},
              {j->hash, "hash", sizeof j->hash},
              {j->kind, "kind", sizeof j->kind}};
    for (int i = 0; i < 3; i++)
        if (strnlen(f[i].v, f[i].cap) == f[i].cap)
            return util_seterr(err, errlen, STORE_ERR,
                               "%s job_insert: %s is not a string of at most %zu bytes", name,
                               f[i].what, f[i].cap - 1);
    return STORE_OK;
}

/* A job read back (rc the read's) whose state is none of ours is an error. */
static int st_job_read_ok(store *s, int rc, const char *id, store_job *out, char *err,
                          size_t errlen)
{
    if (rc != STORE_OK) {
        store_job_clear(out);
        return rc;
    }
    if (out->state >= JOB_QUEUED && out->state <= JOB_CANCELED) return STORE_OK;
    util_seterr(err, errlen, STORE_ERR, "%s job_get %s: unknown state %d in the database",
                s->be->name, id ? id : out->id, (int)out->state);
    store_job_clear(out);
    return STORE_ERR;
}

static int st_job_insert(store *s, const store_job *j, char *err, size_t errlen)
{
    if (st_job_fields(s, j, "job_insert", err, errlen)) return STORE_ERR;
    store_conn *c = s->be->conn(s, err, errlen);
    if (!c || s->be->begin(c, STORE_TX_WRITE, "job_insert: begin", err, errlen)) return STORE_ERR;
    int rc = s->be->job_write(c, j, "job_insert", err, errlen) ? STORE_ERR : STORE_OK;
    return st_end(s, c, rc, "job_insert: commit", err, errlen);
}

/* One try of job_submit, in one write transaction: STORE_* as job_submit, or STORE_RACE (rolled
 * back) when another daemon's submit made the job first. */
static int st_submit_once(store *s, store_conn *c, const store_job *j, size_t queue_max,
                          int join_only, char *job_id, int *joined, char *err, size_t errlen)
{
    const store_be_ops *be = s->be;
    uint64_t bytes;
    double used;
    *joined = 0;
    if (be->begin(c, STORE_TX_WRITE, "job_submit: begin", err, errlen)) return STORE_ERR;
    int rc = be->result_head(c, j->hash, &bytes, &used, NULL, "job_submit", err, errlen);
    if (rc != STORE_NOTFOUND)
        return st_end(s, c, rc == STORE_OK ? STORE_CACHED : STORE_ERR, "job_submit: commit", err,
                      errlen);
    rc = be->job_active(c, j->hash, job_id, err, errlen);
    if (rc == STORE_OK) { /* joined: a submission of its own */
        store_sub sub = {.created = j->created};
        memcpy(sub.id, j->id, sizeof sub.id);
        memcpy(sub.job, job_id, sizeof sub.job);
        rc = be->sub_write(c, &sub, "job_submit: join", err, errlen) ? STORE_ERR : STORE_OK;
        *joined = rc == STORE_OK;
        return st_end(s, c, rc, "job_submit: commit", err, errlen);
    }
    if (rc != STORE_NOTFOUND || join_only)
        return st_end(s, c, rc, "job_submit: commit", err, errlen);
    if (queue_max) {
        size_t queued = 0;
        if (be->job_counts(c, &queued, NULL, "job_submit", err, errlen))
            return st_end(s, c, STORE_ERR, "job_submit", err, errlen);
        if (queued >= queue_max) return st_end(s, c, STORE_FULL, "job_submit: commit", err, errlen);
    }
    store_job q = *j;
    q.state = JOB_QUEUED;
    q.started = q.finished = 0;
    q.error_status = 0;
    q.error = NULL;
    rc = be->job_write(c, &q, "job_submit", err, errlen);
    if (rc == STORE_RACE) {
        be->rollback(c);
        return STORE_RACE;
    }
    if (rc == STORE_OK && be->notify) rc = be->notify(c, STORE_EV_QUEUED, "", err, errlen);
    if (rc == STORE_OK) memcpy(job_id, j->id, 33);
    return st_end(s, c, rc ? STORE_ERR : STORE_OK, "job_submit: commit", err, errlen);
}

static int st_job_submit(store *s, const store_job *j, size_t queue_max, int join_only,
                         char *job_id, int *joined, char *err, size_t errlen)
{
    *joined = 0;
    if (st_job_fields(s, j, "job_submit", err, errlen)) return STORE_ERR;
    store_conn *c = s->be->conn(s, err, errlen);
    if (!c) return STORE_ERR;
    for (int t = 0; t < STORE_SUBMIT_TRIES; t++) {
        int rc = st_submit_once(s, c, j, queue_max, join_only, job_id, joined, err, errlen);
        if (rc == STORE_ERR) *joined = 0;
        if (rc != STORE_RACE) return rc;
    }
    return util_seterr(err, errlen, STORE_ERR,
                       "%s job_submit: the same request was made and canceled too often",
                       s->be->name);
}

static int st_job_get(store *s, const char *id, store_job *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    store_conn *c = s->be->conn(s, err, errlen);
    if (!c) return STORE_ERR;
    return st_job_read_ok(s, s->be->job_read(c, id, out, err, errlen), id, out, err, errlen);
}

static int st_job_claim(store *s, const char *owner, double now, double lease, store_job *out,
                        char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    store_conn *c = s->be->conn(s, err, errlen);
    if (!c) return STORE_ERR;
    int rc = s->be->job_claim(c, owner, now, now + lease, out, err, errlen);
    return st_job_read_ok(s, rc, NULL, out, err, errlen);
}

/* One change of a running job in a transaction of its own; ev (with its id) told to the other
 * daemons when it changed the row (STORE_EV_NONE: nothing to tell). */
static int st_job_set(store *s, const store_set *a, int *cancel, store_ev ev, const char *where,
                      char *err, size_t errlen)
{
    const store_be_ops *be = s->be;
    store_conn *c = be->conn(s, err, errlen);
    int tell = ev != STORE_EV_NONE && be->notify;
    if (!c || be->begin(c, tell ? STORE_TX_WRITE : STORE_TX_ONE, where, err, errlen))
        return STORE_ERR;
    int rc = be->job_set(c, a, cancel, where, err, errlen);
    if (rc == STORE_OK && tell &&
        be->notify(c, ev, ev == STORE_EV_QUEUED ? "" : a->id, err, errlen))
        rc = STORE_ERR;
    return st_end(s, c, rc, where, err, errlen);
}

static int st_job_renew(store *s, const char *id, const char *owner, double now, double lease,
                        const char *stage, double fraction, int *cancel, char *err, size_t errlen)
{
    store_set a = {.kind = STORE_SET_RENEW,
                   .id = id,
                   .owner = owner,
                   .until = now + lease,
                   .stage = stage,
                   .fraction = fraction};
    *cancel = 0;
    return st_job_set(s, &a, cancel, STORE_EV_NONE, "job_renew", err, errlen);
}

static int st_job_finish(store *s, const char *id, const char *owner, job_state state, double when,
                         int error_status, const char *error, char *err, size_t errlen)
{
    if (state != JOB_DONE && state != JOB_FAILED && state != JOB_CANCELED)
        return util_seterr(err, errlen, STORE_ERR, "%s job_finish: %d is not an end state",
                           s->be->name, (int)state);
    store_set a = {.kind = STORE_SET_FINISH,
                   .id = id,
                   .owner = owner,
                   .when = when,
                   .state = state,
                   .error_status = state == JOB_FAILED ? error_status : 0,
                   .error = state == JOB_FAILED ? error : NULL};
    return st_job_set(s, &a, NULL, STORE_EV_ENDED, "job_finish", err, errlen);
}

static int st_job_release(store *s, const char *id, const char *owner, char *err, size_t errlen)
{
    store_set a = {.kind = STORE_SET_RELEASE, .id = id, .owner = owner, .when = st_clock()};
    return st_job_set(s, &a, NULL, STORE_EV_QUEUED, "job_release", err, errlen);
}

#define ST_STR_(x) #x
#define ST_STR(x)  ST_STR_(x)
#define ST_REQUEUE_MSG                                                                             \
    "the job was started " ST_STR(STORE_MAX_ATTEMPTS) " times, and each time the daemon running "  \
                                                      "it stopped before it ended"

typedef struct st_tell {
    store *s;
    store_conn *c;
    char *err;
    size_t errlen;
} st_tell;

static int st_tell_ended(void *ctx, const char *id)
{
    st_tell *t = ctx;
    return t->s->be->notify(t->c, STORE_EV_ENDED, id, t->err, t->errlen);
}

static int st_jobs_requeue(store *s, double now, int all, size_t *n, char *err, size_t errlen)
{
    const store_be_ops *be = s->be;
    int queued = 0;
    *n = 0;
    store_conn *c = be->conn(s, err, errlen);
    if (!c || be->begin(c, STORE_TX_WRITE, "jobs_requeue: begin", err, errlen)) return STORE_ERR;
    st_tell t = {s, c, err, errlen};
    int rc = be->jobs_requeue(c, now, all, STORE_MAX_ATTEMPTS, ST_REQUEUE_MSG,
                              be->notify ? st_tell_ended : NULL, &t, n, &queued, err, errlen);
    if (rc == STORE_OK && queued && be->notify && be->notify(c, STORE_EV_QUEUED, "", err, errlen))
        rc = STORE_ERR;
    rc = st_end(s, c, rc ? STORE_ERR : STORE_OK, "jobs_requeue: commit", err, errlen);
    if (rc) *n = 0;
    return rc;
}

static int st_job_counts(store *s, size_t *queued, size_t *running, char *err, size_t errlen)
{
    *queued = *running = 0;
    store_conn *c = s->be->conn(s, err, errlen);
    return c ? s->be->job_counts(c, queued, running, "job_counts", err, errlen) : STORE_ERR;
}

static int st_jobs_prune(store *s, double before, size_t keep, size_t *n, char *err, size_t errlen)
{
    size_t got = 0;
    if (n) *n = 0;
    store_conn *c = s->be->conn(s, err, errlen);
    if (!c || s->be->begin(c, STORE_TX_ONE, "jobs_prune: begin", err, errlen)) return STORE_ERR;
    int rc = s->be->jobs_prune(c, before, keep, &got, err, errlen);
    rc = st_end(s, c, rc, "jobs_prune: commit", err, errlen);
    if (rc == STORE_OK && n) *n = got;
    return rc;
}

/* ---- submissions ---- */

static int st_sub_get(store *s, const char *id, store_sub *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    store_conn *c = s->be->conn(s, err, errlen);
    return c ? s->be->sub_read(c, id, 0, out, err, errlen) : STORE_ERR;
}

/* The submission is canceled; when it was its job's last, in the same transaction, the job is
 * canceled or asked to stop (its row locked first where rows lock: see job_active). */
static int st_sub_cancel(store *s, const char *id, double when, int *changed, int *job, char *err,
                         size_t errlen)
{
    const store_be_ops *be = s->be;
    store_sub sub;
    *changed = 0;
    *job = STORE_JOB_KEPT;
    store_conn *c = be->conn(s, err, errlen);
    if (!c || be->begin(c, STORE_TX_WRITE, "sub_cancel: begin", err, errlen)) return STORE_ERR;
    int rc = be->sub_read(c, id, 1, &sub, err, errlen);
    if (rc == STORE_OK) rc = be->sub_cancel(c, id, when, changed, err, errlen);
    if (rc == STORE_OK && *changed) rc = be->job_last_sub(c, sub.job, when, job, err, errlen);
    if (rc == STORE_OK && be->notify && *job != STORE_JOB_KEPT)
        rc = be->notify(c, *job == STORE_JOB_CANCELED ? STORE_EV_ENDED : STORE_EV_CANCEL, sub.job,
                        err, errlen);
    rc = st_end(s, c, rc, "sub_cancel: commit", err, errlen);
    if (rc == STORE_ERR) {
        *changed = 0;
        *job = STORE_JOB_KEPT;
    }
    return rc;
}

static int st_wait_event(store *s, double timeout, store_ev *ev, char *id, char *err, size_t errlen)
{
    return s->be->wait_event(s, timeout, ev, id, err, errlen);
}

/* ---- results: writing ---- */

/* Where a put's bytes come from: a buffer, or a file read a chunk at a time into buf. */
typedef struct st_source {
    const char *mem;
    FILE *f;
    char *buf; /* STORE_CHUNK bytes, for f */
} st_source;

/* The next n bytes of the source (pos: how many were taken before). */
static const char *st_take(store *s, st_source *src, uint64_t pos, size_t n, uint64_t len,
                           char *err, size_t errlen)
{
    if (src->mem) return src->mem + pos;
    size_t got = fread(src->buf, 1, n, src->f);
    if (got == n) return src->buf;
    if (ferror(src->f))
        util_seterr(err, errlen, STORE_ERR, "%s result_put: reading the result at byte %llu failed",
                    s->be->name, (unsigned long long)(pos + got));
    else
        util_seterr(err, errlen, STORE_ERR,
                    "%s result_put: the file ended after %llu of %llu bytes", s->be->name,
                    (unsigned long long)(pos + got), (unsigned long long)len);
    return NULL;
}

/* Deletes the least recently used results but keep until the total is within the budget or
 * keep is alone (inside the caller's transaction): each round one read of the totals row and
 * one indexed delete. */
static int st_evict(store *s, store_conn *c, const char *keep, char *err, size_t errlen)
{
    for (;;) {
        uint64_t total;
        int gone;
        if (s->be->totals(c, NULL, &total, "result_put: total", err, errlen)) return STORE_ERR;
        if (total <= s->budget) return STORE_OK;
        if (s->be->evict_one(c, keep, &gone, err, errlen)) return STORE_ERR;
        if (!gone) return STORE_OK; /* keep alone exceeds the budget */
    }
}

/* After a put in several transactions: the chunks are all there (another put of the same
 * hash, or an eviction of it, could have touched them in between). */
static int st_put_complete(store *s, store_conn *c, const char *hash, uint64_t nchunks,
                           uint64_t len, char *err, size_t errlen)
{
    uint64_t have_n, have_bytes;
    if (s->be->chunks_sum(c, hash, &have_n, &have_bytes, err, errlen)) return STORE_ERR;
    if (have_n == nchunks && have_bytes == len) return STORE_OK;
    return util_seterr(err, errlen, STORE_ERR,
                       "%s result_put: %llu chunks of %llu bytes written, %llu of %llu found "
                       "(another put of the same result meanwhile?)",
                       s->be->name, (unsigned long long)nchunks, (unsigned long long)len,
                       (unsigned long long)have_n, (unsigned long long)have_bytes);
}

/* Writes chunks from *pos on until len or the end of this transaction's batch. */
static int st_put_batch(store *s, store_conn *c, const char *hash, uint64_t len, st_source *src,
                        uint64_t *pos, uint64_t *nchunks, char *err, size_t errlen)
{
    uint64_t end = s->put_batch && len - *pos > s->put_batch ? *pos + s->put_batch : len;
    while (*pos < end) {
        size_t n = len - *pos < STORE_CHUNK ? (size_t)(len - *pos) : STORE_CHUNK;
        const char *data = st_take(s, src, *pos, n, len, err, errlen);
        unsigned char md[32];
        if (!data) return STORE_ERR;
        store_digest(data, n, md);
        if (s->be->chunk_put(c, hash, *pos, data, n, md, err, errlen)) return STORE_ERR;
        *pos += n;
        ++*nchunks;
    }
    return STORE_OK;
}

/* A put: the old result of this hash goes, the chunks are written put_batch bytes per
 * transaction (all in one when 0), and the last transaction checks that they are all there
 * (when there were several), writes the results row and evicts.  A put that fails deletes the
 * chunks its earlier transactions committed (best effort; opening a SQLite store again deletes
 * any left). */
static int st_put(store *s, const char *hash, const char *job, uint64_t len, st_source *src,
                  char *err, size_t errlen)
{
    const store_be_ops *be = s->be;
    uint64_t pos = 0, nchunks = 0;
    int committed = 0;
    store_conn *c = be->conn(s, err, errlen);
    if (!c) return STORE_ERR;
    if (len > (uint64_t)INT64_MAX / 2)
        return util_seterr(err, errlen, STORE_ERR, "%s result_put: %llu bytes is too large",
                           be->name, (unsigned long long)len);
    for (;;) {
        if (be->begin(c, STORE_TX_WRITE, "result_put: begin", err, errlen)) goto fail_nolock;
        if (!committed &&
            (be->result_delete(c, hash, "result_put: replace", err, errlen) ||
             (be->chunks_forget && be->chunks_forget(c, hash, "result_put: replace", err, errlen))))
            goto fail;
        if (st_put_batch(s, c, hash, len, src, &pos, &nchunks, err, errlen)) goto fail;
        if (pos == len) break;
        if (be->commit(c, "result_put: commit", err, errlen)) goto fail;
        committed = 1;
    }
    if (committed && st_put_complete(s, c, hash, nchunks, len, err, errlen)) goto fail;
    /* the stamp is taken under the write lock: stamps of puts follow the commit order */
    if (be->result_row(c, hash, len, be->stamp(s), job && *job ? job : NULL, err, errlen) ||
        (s->budget && st_evict(s, c, hash, err, errlen)) ||
        be->commit(c, "result_put: commit", err, errlen))
        goto fail;
    return STORE_OK;
fail:
    be->rollback(c);
fail_nolock:
    if (committed && be->chunks_forget &&
        !be->begin(c, STORE_TX_WRITE, "result_put: clean up", NULL, 0))
        st_end(s, c, be->chunks_forget(c, hash, "result_put: clean up", NULL, 0),
               "result_put: clean up", NULL, 0);
    return STORE_ERR;
}

static int st_result_put(store *s, const char *hash, const char *body, size_t len, char *err,
                         size_t errlen)
{
    if (!body && len)
        return util_seterr(err, errlen, STORE_ERR, "%s result_put: %zu bytes with no body",
                           s->be->name, len);
    st_source src = {.mem = body ? body : ""};
    return st_put(s, hash, NULL, len, &src, err, errlen);
}

static int st_result_put_file(store *s, const char *hash, const char *job, FILE *f, uint64_t len,
                              char *err, size_t errlen)
{
    if (!f) return util_seterr(err, errlen, STORE_ERR, "%s result_put: no file", s->be->name);
    st_source src = {.f = f, .buf = malloc(STORE_CHUNK)};
    if (!src.buf)
        return util_seterr(err, errlen, STORE_ERR, "%s result_put: out of memory", s->be->name);
    int rc = st_put(s, hash, job, len, &src, err, errlen);
    free(src.buf);
    return rc;
}

/* ---- results: reading ---- */

/* Marks a result used now, unless its mark is younger than touch_seconds: a hot result then
 * costs one write per interval instead of one per read (every write takes SQLite's write
 * lock, and readers queued behind it showed up as a tail of hundreds of ms under load).  The
 * LRU order is exact to that resolution.  A result evicted since it was read is left. */
static int st_touch(store *s, store_conn *c, const char *hash, double used, const char *where,
                    char *err, size_t errlen)
{
    if (s->touch_seconds > 0 && st_clock() - used < s->touch_seconds) return STORE_OK;
    if (s->be->begin(c, STORE_TX_ONE, where, err, errlen)) return STORE_ERR;
    int rc = s->be->result_touch(c, hash, s->be->stamp(s), where, err, errlen);
    return st_end(s, c, rc, where, err, errlen);
}

/* A reading of a result's chunks (result_get: all of them into copy; result_chunk: the one
 * that holds pos into data), each checked against its digest as it comes. */
typedef struct st_read {
    store *s;
    const char *hash;
    uint64_t bytes, pos, start; /* result_get: its size, the bytes read; result_chunk: pos */
    char *copy, *data;
    size_t len;
    char *err;
    size_t errlen;
} st_read;

/* result_get's: each chunk must start where the last ended and fit the size. */
static int st_whole_chunk(void *ctx, uint64_t off, const void *p, size_t n, const void *sha,
                          size_t shalen)
{
    st_read *w = ctx;
    const char *name = w->s->be->name;
    if (off != w->pos || n > w->bytes - w->pos)
        return util_seterr(w->err, w->errlen, STORE_DAMAGED,
                           "%s result_get: result %.16s... is damaged: a chunk of %llu bytes at "
                           "byte %llu, where %llu of %llu bytes were read",
                           name, w->hash, (unsigned long long)n, (unsigned long long)off,
                           (unsigned long long)w->pos, (unsigned long long)w->bytes);
    if (!store_digest_ok(p, n, sha, shalen))
        return util_seterr(w->err, w->errlen, STORE_DAMAGED,
                           "%s result_get: result %.16s... is damaged: its chunk at byte %llu "
                           "does not match its digest",
                           name, w->hash, (unsigned long long)off);
    if (n) memcpy(w->copy + w->pos, p, n);
    w->pos += n;
    return 0;
}

/* The body is read in one read transaction (a snapshot: SQLite's readers run in parallel under
 * WAL), then the small results row is marked in a write of its own.  A result evicted in
 * between is still returned: it was there when read, and its content is fixed by its hash. */
static int st_result_get(store *s, const char *hash, char **body, size_t *len, char *err,
                         size_t errlen)
{
    const store_be_ops *be = s->be;
    st_read w = {.s = s, .hash = hash, .err = err, .errlen = errlen};
    double used = 0;
    *body = NULL;
    if (len) *len = 0;
    store_conn *c = be->conn(s, err, errlen);
    if (!c || be->begin(c, STORE_TX_READ, "result_get: begin", err, errlen)) return STORE_ERR;
    int rc = be->result_head(c, hash, &w.bytes, &used, NULL, "result_get", err, errlen);
    if (rc == STORE_OK && (w.bytes >= SIZE_MAX || !(w.copy = malloc((size_t)w.bytes + 1))))
        rc = util_seterr(err, errlen, STORE_ERR, "%s result_get: out of memory for %llu bytes",
                         be->name, (unsigned long long)w.bytes);
    if (rc == STORE_OK)
        rc = be->chunks_read(c, hash, -1, st_whole_chunk, &w, "result_get", err, errlen);
    if (rc == STORE_OK && w.pos != w.bytes)
        rc = util_seterr(err, errlen, STORE_DAMAGED,
                         "%s result_get: result %.16s... is damaged: its chunks hold %llu of its "
                         "%llu bytes",
                         be->name, hash, (unsigned long long)w.pos, (unsigned long long)w.bytes);
    be->commit(c, "result_get: end", NULL, 0);
    if (rc == STORE_DAMAGED) st_drop(s, c, hash);
    if (rc == STORE_OK) rc = st_touch(s, c, hash, used, "result_get: mark used", err, errlen);
    if (rc != STORE_OK) {
        free(w.copy);
        return rc;
    }
    w.copy[w.bytes] = 0;
    *body = w.copy;
    if (len) *len = (size_t)w.bytes;
    return STORE_OK;
}

static int st_result_size(store *s, const char *hash, uint64_t *bytes, char *job, char *err,
                          size_t errlen)
{
    double used = 0;
    *bytes = 0;
    store_conn *c = s->be->conn(s, err, errlen);
    if (!c) return STORE_ERR;
    if (job) job[0] = 0;
    int rc = s->be->result_head(c, hash, bytes, &used, job, "result_size", err, errlen);
    if (rc == STORE_OK) rc = st_touch(s, c, hash, used, "result_size: mark used", err, errlen);
    return rc;
}

/* result_chunk's: the chunk that holds pos. */
static int st_piece_chunk(void *ctx, uint64_t off, const void *p, size_t n, const void *sha,
                          size_t shalen)
{
    st_read *q = ctx;
    if (q->pos - off >= n) return STORE_NOTFOUND; /* the chunk that held pos is gone */
    if (!store_digest_ok(p, n, sha, shalen))
        return util_seterr(q->err, q->errlen, STORE_DAMAGED,
                           "%s result_chunk: result %.16s... is damaged: its chunk at byte %llu "
                           "does not match its digest",
                           q->s->be->name, q->hash, (unsigned long long)off);
    if (!(q->data = malloc(n + 1)))
        return util_seterr(q->err, q->errlen, STORE_ERR, "%s result_chunk: out of memory",
                           q->s->be->name);
    if (n) memcpy(q->data, p, n);
    q->data[n] = 0;
    q->len = n;
    q->start = off;
    return 0;
}

static int st_result_chunk(store *s, const char *hash, uint64_t pos, char **data, size_t *len,
                           uint64_t *start, char *err, size_t errlen)
{
    st_read q = {.s = s, .hash = hash, .pos = pos, .err = err, .errlen = errlen};
    *data = NULL;
    *len = 0;
    *start = 0;
    store_conn *c = s->be->conn(s, err, errlen);
    if (!c) return STORE_ERR;
    if (pos > (uint64_t)INT64_MAX) return STORE_NOTFOUND;
    int rc = s->be->chunks_read(c, hash, (long long)pos, st_piece_chunk, &q, "result_chunk", err,
                                errlen);
    if (rc == STORE_DAMAGED) st_drop(s, c, hash);
    if (rc != STORE_OK) {
        free(q.data);
        return rc;
    }
    *data = q.data;
    *len = q.len;
    *start = q.start;
    return STORE_OK;
}

static int st_result_exists(store *s, const char *hash, char *err, size_t errlen)
{
    uint64_t bytes;
    double used;
    store_conn *c = s->be->conn(s, err, errlen);
    return c ? s->be->result_head(c, hash, &bytes, &used, NULL, "result_exists", err, errlen)
             : STORE_ERR;
}

static int st_result_stats(store *s, size_t *count, uint64_t *bytes, char *err, size_t errlen)
{
    if (count) *count = 0;
    if (bytes) *bytes = 0;
    store_conn *c = s->be->conn(s, err, errlen);
    return c ? s->be->totals(c, count, bytes, "result_stats", err, errlen) : STORE_ERR;
}

/* ---- the check, the probe ---- */

/* The database's own check, then the totals row against a recount and the chunks' tiling,
 * then every chunk of every result against its digest. */
static int st_check(store *s, char *err, size_t errlen)
{
    const store_be_ops *be = s->be;
    store_recount v;
    long long all = 0, bad = 0;
    store_conn *c = be->conn(s, err, errlen);
    if (!c || (be->integrity && be->integrity(c, err, errlen))) return STORE_ERR;
    int rc = be->recount(c, &v, err, errlen);
    if (rc == STORE_NOTFOUND)
        return util_seterr(err, errlen, STORE_ERR, "%s check: the result_totals row is missing",
                           be->name);
    if (rc) return STORE_ERR;
    if (v.tot_count != v.count || v.tot_bytes != v.bytes)
        return util_seterr(err, errlen, STORE_ERR,
                           "%s check: result_totals says %lld results of %lld bytes, the table "
                           "holds %lld of %lld",
                           be->name, v.tot_count, v.tot_bytes, v.count, v.bytes);
    if (v.bad_size || v.bad_off)
        return util_seterr(err, errlen, STORE_ERR,
                           "%s check: of %lld results, %lld have chunks that do not add up to "
                           "their size; %lld chunks do not start where the one before ends",
                           be->name, v.count, v.bad_size, v.bad_off);
    if (v.orphans > 0)
        return util_seterr(err, errlen, STORE_ERR, "%s check: %lld chunks of no result", be->name,
                           v.orphans);
    if (be->chunks_digests(c, &all, &bad, err, errlen)) return STORE_ERR;
    if (bad)
        return util_seterr(err, errlen, STORE_ERR,
                           "%s check: %lld of %lld chunks do not match their digest", be->name, bad,
                           all);
    return STORE_OK;
}

static int st_writable(store *s, char *err, size_t errlen)
{
    store_conn *c = s->be->conn(s, err, errlen);
    return c ? s->be->probe(c, err, errlen) : STORE_ERR;
}

static void st_close(store *s)
{
    if (s) s->be->close(s);
}

#define ST_OPS(wait)                                                                               \
    {                                                                                              \
        .job_submit = st_job_submit, .job_claim = st_job_claim, .job_renew = st_job_renew,         \
        .job_finish = st_job_finish, .job_release = st_job_release,                                \
        .jobs_requeue = st_jobs_requeue, .job_insert = st_job_insert, .job_get = st_job_get,       \
        .job_counts = st_job_counts, .jobs_prune = st_jobs_prune, .sub_get = st_sub_get,           \
        .sub_cancel = st_sub_cancel, .wait_event = wait, .result_put = st_result_put,              \
        .result_put_file = st_result_put_file, .result_get = st_result_get,                        \
        .result_size = st_result_size, .result_chunk = st_result_chunk,                            \
        .result_exists = st_result_exists, .result_stats = st_result_stats, .check = st_check,     \
        .writable = st_writable, .close = st_close,                                                \
    }

/* one daemon per store (SQLite): nobody else makes events */
const store_ops store_ops_local = ST_OPS(NULL);
const store_ops store_ops_shared = ST_OPS(st_wait_event);
