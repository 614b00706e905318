/* engine.c — see engine.h.
 *
 * One mutex (lock) guards the live list, the queue, every job's state/progress/refs and the
 * waiter list; the condition `work` wakes workers, `idle` wakes a drain waiting for running jobs
 * to end, `tick` wakes the timer thread.  Store I/O and the geometry run outside the lock.
 *
 * A job's references: one for the live list (dropped when it ends), one per holder
 * (submit/find callers, the worker running it).  It is freed when the count reaches 0.
 */
#include "server/engine.h"

#include <errno.h>
#include <malloc.h>
#include <openssl/evp.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>
#include <unistd.h>

#include "api/api.h"
#include "server/log.h"

typedef struct waiter {
    job *j;
    double deadline;
    void (*wake)(void *);
    void *ctx;
    struct waiter *next;
} waiter;

struct job {
    char id[33], hash[65], kind[16];
    job_state state; /* lock */
    double created, started, finished;
    char *request; /* canonical request; immutable */
    size_t request_len;
    atomic_int cancel; /* read by the core */
    char stage[32];    /* lock */
    double fraction;   /* lock */
    int error_status;  /* set once by the worker, under lock */
    char *error;
    char *result; /* DONE: the result JSON when at most ENGINE_KEEP bytes (else NULL: it is in
                     the store only); immutable once set */
    size_t result_len;
    int refs;   /* lock */
    int live;   /* lock: in e->live */
    int active; /* lock: submissions not canceled (the job is canceled when none is left) */
    job *next_live, *next_queue;
};

struct engine {
    engine_cfg cfg;
    pthread_mutex_t lock;
    pthread_cond_t work, idle, tick;
    job *live;          /* queued and running jobs */
    job *qhead, *qtail; /* FIFO of queued jobs */
    size_t nqueued, nrunning;
    waiter *waiters;
    int draining, stopping;
    pthread_t *threads; /* workers */
    int nthreads;
    pthread_t timer;
    int timer_started;
};

double engine_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

void engine_hash(const char *canon, size_t len, char *out)
{
    unsigned char md[32];
    unsigned int mdlen = 0;
    EVP_MD_CTX *ctx = EVP_MD_CTX_new();
    int ok = ctx && EVP_DigestInit_ex(ctx, EVP_sha256(), NULL) &&
             EVP_DigestUpdate(ctx, canon, len) && EVP_DigestUpdate(ctx, "\n", 1) &&
             EVP_DigestUpdate(ctx, CELLAR_ALGO_VERSION, strlen(CELLAR_ALGO_VERSION)) &&
             EVP_DigestFinal_ex(ctx, md, &mdlen);
    EVP_MD_CTX_free(ctx);
    if (!ok || mdlen != 32) memset(md, 0, sizeof md); /* cannot happen with OpenSSL's sha256 */
    for (int i = 0; i < 32; i++) snprintf(out + 2 * i, 3, "%02x", md[i]);
}

static int new_id(char *out)
{
    unsigned char r[16];
    if (getrandom(r, sizeof r, 0) != (ssize_t)sizeof r) return -1;
    for (int i = 0; i < 16; i++) snprintf(out + 2 * i, 3, "%02x", r[i]);
    return 0;
}

static void job_free(job *j)
{
    free(j->request);
    free(j->error);
    free(j->result);
    free(j);
}

/* lock held */
static void unref_locked(job *j)
{
    if (--j->refs == 0) job_free(j);
}

void engine_release(engine *e, job *j)
{
    if (!j) return;
    pthread_mutex_lock(&e->lock);
    unref_locked(j);
    pthread_mutex_unlock(&e->lock);
}

/* lock held: takes j off the live list.  The list's reference is the caller's to drop, and
 * every caller holds another one, so j stays valid (refs-- rather than a free). */
static void unlive_locked(engine *e, job *j)
{
    for (job **p = &e->live; *p; p = &(*p)->next_live)
        if (*p == j) {
            *p = j->next_live;
            j->live = 0;
            return;
        }
}

/* lock held: moves every waiter of j (or every waiter, when j is NULL; or those past `now`
 * when j is NULL and now > 0) to the returned list, to be woken outside the lock */
static waiter *take_waiters_locked(engine *e, const job *j, double now)
{
    waiter *out = NULL;
    for (waiter **p = &e->waiters; *p;) {
        waiter *w = *p;
        int take = j ? w->j == j : (now <= 0 || w->deadline <= now);
        if (take) {
            *p = w->next;
            w->next = out;
            out = w;
        } else {
            p = &w->next;
        }
    }
    return out;
}

static void wake_all(waiter *w)
{
    while (w) {
        waiter *n = w->next;
        w->wake(w->ctx);
        free(w);
        w = n;
    }
}

typedef struct progress_ctx {
    engine *e;
    job *j;
} progress_ctx;

/* The cores report the end of each stage (and some stages their own fraction); these are the
 * shares of a job's time spent up to the end of each, so that `fraction` is of the whole job:
 * the 2D core's measured on random lines, the 3D core's on 16 000 turned cubes.  The API's own
 * stages (membership, select, polygons, output) report fractions of the whole job already. */
typedef struct stage_share {
    const char *stage;
    double done;
} stage_share;
static const stage_share shares2[] = {{"snap", 0.02},  {"buckets", 0.08},     {"intersect", 0.30},
                                      {"split", 0.65}, {"biconnected", 0.75}, {"faces", 0.95}};
static const stage_share shares3[] = {
    {"pairs", 0.06}, {"cuts", 0.20}, {"planes", 0.45}, {"cells", 0.95}};

static void progress_cb(void *udata, const char *stage, double fraction)
{
    progress_ctx *p = udata; /* a few calls per job: the engine lock is fine */
    int solids = !strcmp(p->j->kind, "solids");
    const stage_share *sh = solids ? shares3 : shares2;
    size_t n = solids ? sizeof shares3 / sizeof *shares3 : sizeof shares2 / sizeof *shares2;
    for (size_t i = 0; i < n; i++)
        if (!strcmp(stage, sh[i].stage)) {
            double before = i ? sh[i - 1].done : 0;
            fraction = before + (sh[i].done - before) * fraction;
            break;
        }
    pthread_mutex_lock(&p->e->lock);
    snprintf(p->j->stage, sizeof p->j->stage, "%s", stage);
    if (fraction > p->j->fraction) p->j->fraction = fraction;
    pthread_mutex_unlock(&p->e->lock);
}

/* A result of at most this many bytes stays in memory with its job for the clients that
 * wait for it; a larger one is read from the store, a chunk at a time. */
#define ENGINE_KEEP STORE_CHUNK

/* A new spool file, already unlinked (it goes when closed, or with the process): in dir, or
 * tmpfile() when dir is NULL.  NULL with a message in err. */
static FILE *spool_open(const char *dir, char *err, size_t errlen)
{
    FILE *f = NULL;
    if (!dir) {
        f = tmpfile();
        if (!f) snprintf(err, errlen, "cannot make a spool file: %s", strerror(errno));
        return f;
    }
    char path[4200];
    snprintf(path, sizeof path, "%s/cellar-spool-XXXXXX", dir);
    int fd = mkstemp(path);
    if (fd < 0) {
        snprintf(err, errlen, "cannot make a spool file in %.200s: %s", dir, strerror(errno));
        return NULL;
    }
    unlink(path);
    f = fdopen(fd, "w+");
    if (!f) {
        snprintf(err, errlen, "cannot open a spool file in %.200s: %s", dir, strerror(errno));
        close(fd);
    }
    return f;
}

/* Moves the spooled result (len bytes) into the store, and into *keep when it is small. */
static int spool_store(store *st, const char *hash, FILE *f, uint64_t len, char **keep, char *err,
                       size_t errlen)
{
    if (fflush(f) || fseek(f, 0, SEEK_SET)) {
        snprintf(err, errlen, "the spool file: %s", strerror(errno));
        return STORE_ERR;
    }
    if (st->ops->result_put_file(st, hash, f, len, err, errlen)) return STORE_ERR;
    *keep = NULL;
    if (len > ENGINE_KEEP || fseek(f, 0, SEEK_SET)) return STORE_OK;
    char *b = malloc((size_t)len + 1);
    if (b && fread(b, 1, (size_t)len, f) == (size_t)len) {
        b[len] = 0;
        *keep = b;
    } else {
        free(b); /* stored all the same: the clients read it from the store */
    }
    return STORE_OK;
}

/* Runs one job on this worker thread; returns with the job ended and off the live list.  The
 * result is written to a spool file as it is made, then copied into the store a chunk at a
 * time: a large result never sits whole in memory. */
static void run_job(engine *e, job *j)
{
    char err[256] = "";
    api_error ae = {0};
    char *out = NULL;
    size_t outlen = 0;
    double t0 = engine_now();
    store *st = e->cfg.st;

    if (st->ops->job_set_state(st, j->id, JOB_RUNNING, j->started, 0, NULL, err, sizeof err))
        log_kv(LOG_WARN, "store: job_set_state failed", "job", j->id, "error", err, NULL);
    progress_ctx pc = {e, j};
    api_run_opts ro = {
        .threads = e->cfg.job_threads, .cancel = &j->cancel, .progress = progress_cb, .udata = &pc};
    int rc;
    ro.stream = spool_open(e->cfg.spool_dir, err, sizeof err);
    if (!ro.stream) {
        log_kv(LOG_ERROR, "spool failed", "job", j->id, "error", err, NULL);
        rc = API_ENOMEM;
        snprintf(ae.msg, sizeof ae.msg, "the result could not be spooled: %.200s", err);
    } else {
        rc = api_run_json_ex(j->request, j->request_len, &ro, &out, &outlen, &ae);
    }
    double t1 = engine_now();
    job_state final = rc == API_OK ? JOB_DONE : rc == API_ECANCELED ? JOB_CANCELED : JOB_FAILED;
    if (rc == API_OK && spool_store(st, j->hash, ro.stream, outlen, &out, err, sizeof err)) {
        log_kv(LOG_ERROR, "store: result_put failed", "job", j->id, "error", err, NULL);
        final = JOB_FAILED;
        rc = 503;
        snprintf(ae.msg, sizeof ae.msg, "the result could not be stored: %.200s", err);
    }
    if (ro.stream) fclose(ro.stream);
    pthread_mutex_lock(&e->lock);
    int canceled_meanwhile = j->state == JOB_CANCELED;
    pthread_mutex_unlock(&e->lock);
    if (!canceled_meanwhile &&
        st->ops->job_set_state(st, j->id, final, t1, final == JOB_FAILED ? rc : 0,
                               final == JOB_FAILED ? ae.msg : NULL, err, sizeof err))
        log_kv(LOG_ERROR, "store: job_set_state failed", "job", j->id, "error", err, NULL);

    pthread_mutex_lock(&e->lock);
    if (!canceled_meanwhile) {
        j->state = final;
        j->finished = t1;
        if (final == JOB_FAILED) {
            j->error_status = rc;
            j->error = strdup(ae.msg);
        }
    }
    if (final == JOB_DONE) {
        j->result = out;
        j->result_len = outlen;
        out = NULL;
    }
    e->nrunning--;
    unlive_locked(e, j);
    j->refs--; /* the list's; the worker still holds its own */
    waiter *w = take_waiters_locked(e, j, 0);
    pthread_cond_broadcast(&e->idle);
    pthread_mutex_unlock(&e->lock);
    wake_all(w);
    free(out);
    char ms[32];
    metrics_job_end(e->cfg.m, job_state_name(canceled_meanwhile ? JOB_CANCELED : final), t1 - t0);
    log_kv(LOG_INFO, "job ended", "job", j->id, "kind", j->kind, "state",
           job_state_name(canceled_meanwhile ? JOB_CANCELED : final), "ms",
           log_num(ms, (t1 - t0) * 1e3), NULL);
}

static void *worker_main(void *arg)
{
    engine *e = arg;
    for (;;) {
        pthread_mutex_lock(&e->lock);
        while (!e->stopping && !e->draining && !e->qhead) pthread_cond_wait(&e->work, &e->lock);
        if (e->stopping || e->draining) {
            pthread_mutex_unlock(&e->lock);
            return NULL;
        }
        job *j = e->qhead;
        e->qhead = j->next_queue;
        if (!e->qhead) e->qtail = NULL;
        e->nqueued--;
        e->nrunning++;
        j->state = JOB_RUNNING;
        j->started = engine_now();
        snprintf(j->stage, sizeof j->stage, "started");
        j->refs++; /* the worker's */
        pthread_mutex_unlock(&e->lock);
        run_job(e, j);
        engine_release(e, j);
        /* a large job leaves most of its peak free but kept by the allocator (16 000 cubes:
         * 0.7 GB resident after a 1.7 GB peak): hand it back to the system */
        malloc_trim(0);
    }
}

static void *timer_main(void *arg)
{
    engine *e = arg;
    double next_prune = engine_now() + 5;
    pthread_mutex_lock(&e->lock);
    while (!e->stopping) {
        double now = engine_now(), soonest = next_prune < now + 1 ? next_prune : now + 1;
        for (waiter *w = e->waiters; w; w = w->next)
            if (w->deadline < soonest) soonest = w->deadline;
        if (soonest > now) {
            struct timespec ts = {.tv_sec = (time_t)soonest,
                                  .tv_nsec = (long)((soonest - (double)(time_t)soonest) * 1e9)};
            pthread_cond_timedwait(&e->tick, &e->lock, &ts);
            continue;
        }
        waiter *w = take_waiters_locked(e, NULL, now);
        pthread_mutex_unlock(&e->lock);
        wake_all(w);
        if (now >= next_prune) { /* finished jobs: kept job_ttl seconds, max_jobs at most */
            size_t n = 0;
            char err[256];
            if (e->cfg.st->ops->jobs_prune(e->cfg.st, now - e->cfg.job_ttl, e->cfg.max_jobs, &n,
                                           err, sizeof err))
                log_kv(LOG_WARN, "store: jobs_prune failed", "error", err, NULL);
            next_prune = now + 5;
        }
        pthread_mutex_lock(&e->lock);
    }
    pthread_mutex_unlock(&e->lock);
    return NULL;
}

static job *job_new(const char *id, const char *hash, const char *kind, const char *req, size_t len)
{
    job *j = calloc(1, sizeof *j);
    if (!j) return NULL;
    j->request = malloc(len + 1);
    if (!j->request) {
        free(j);
        return NULL;
    }
    memcpy(j->request, req, len);
    j->request[len] = 0;
    j->request_len = len;
    snprintf(j->id, sizeof j->id, "%s", id);
    snprintf(j->hash, sizeof j->hash, "%s", hash);
    snprintf(j->kind, sizeof j->kind, "%s", kind);
    snprintf(j->stage, sizeof j->stage, "queued");
    atomic_init(&j->cancel, 0);
    return j;
}

/* lock held */
static void enqueue_locked(engine *e, job *j)
{
    j->next_queue = NULL;
    if (e->qtail)
        e->qtail->next_queue = j;
    else
        e->qhead = j;
    e->qtail = j;
    pthread_cond_signal(&e->work);
}

static int recover_one(void *ctx, store_job *sj)
{
    engine *e = ctx;
    char err[256];
    job *j = job_new(sj->id, sj->hash, sj->kind, sj->request, sj->request_len);
    if (!j) return 1;
    j->created = sj->created;
    j->state = JOB_QUEUED;
    j->refs = 1;
    j->live = 1;
    j->active = sj->active_subs;
    if (j->active == 0) { /* every submission was canceled before the job could be */
        if (e->cfg.st->ops->job_set_state(e->cfg.st, sj->id, JOB_CANCELED, engine_now(), 0, NULL,
                                          err, sizeof err))
            log_kv(LOG_WARN, "store: cancel failed", "job", sj->id, "error", err, NULL);
        job_free(j);
        return 0;
    }
    if (sj->state == JOB_RUNNING &&
        e->cfg.st->ops->job_set_state(e->cfg.st, sj->id, JOB_QUEUED, 0, 0, NULL, err, sizeof err))
        log_kv(LOG_WARN, "store: requeue failed", "job", sj->id, "error", err, NULL);
    pthread_mutex_lock(&e->lock);
    j->next_live = e->live;
    e->live = j;
    e->nqueued++;
    enqueue_locked(e, j);
    pthread_mutex_unlock(&e->lock);
    log_kv(LOG_INFO, "job resumed", "job", j->id, "kind", j->kind, NULL);
    return 0;
}

engine *engine_start(const engine_cfg *cfg, char *err, size_t errlen)
{
    engine *e = calloc(1, sizeof *e);
    if (!e) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    e->cfg = *cfg;
    pthread_mutex_init(&e->lock, NULL);
    pthread_cond_init(&e->work, NULL);
    pthread_cond_init(&e->idle, NULL);
    pthread_cond_init(&e->tick, NULL);
    FILE *probe = spool_open(cfg->spool_dir, err, errlen); /* refuse to start without a spool */
    if (!probe) goto fail;
    fclose(probe);
    if (cfg->st->ops->jobs_unfinished(cfg->st, recover_one, e, err, errlen)) goto fail;
    e->threads = calloc((size_t)cfg->workers, sizeof *e->threads);
    if (!e->threads) {
        snprintf(err, errlen, "out of memory");
        goto fail;
    }
    for (int i = 0; i < cfg->workers; i++) {
        if (pthread_create(&e->threads[i], NULL, worker_main, e) != 0) {
            snprintf(err, errlen, "cannot start worker threads");
            goto fail;
        }
        e->nthreads++;
    }
    if (pthread_create(&e->timer, NULL, timer_main, e) != 0) {
        snprintf(err, errlen, "cannot start the timer thread");
        goto fail;
    }
    e->timer_started = 1;
    return e;
fail:
    engine_drain(e, 0);
    engine_stop(e);
    return NULL;
}

static int job_active(const job *j)
{
    return j->state == JOB_QUEUED || j->state == JOB_RUNNING;
}

/* lock held: the queued or running job with this hash, referenced and with one more active
 * submission (the caller's), or NULL */
static job *join_locked(engine *e, const char *hash)
{
    for (job *j = e->live; j; j = j->next_live)
        if (job_active(j) && strcmp(j->hash, hash) == 0) {
            j->refs++;
            j->active++;
            return j;
        }
    return NULL;
}

/* Cancels j, queued or running, whose last submission has just been canceled: takes it off
 * the queue or tells it to stop, wakes its waiters and tells the store.  Called with the lock
 * held and a reference of the caller's; returns with the lock released. */
static void cancel_job_unlock(engine *e, job *j)
{
    char err[256];
    double now = engine_now();
    int was_queued = j->state == JOB_QUEUED;
    if (was_queued) { /* off the queue and the live list */
        for (job **p = &e->qhead; *p; p = &(*p)->next_queue)
            if (*p == j) {
                *p = j->next_queue;
                break;
            }
        e->qtail = NULL;
        for (job *q = e->qhead; q; q = q->next_queue) e->qtail = q;
        e->nqueued--;
        unlive_locked(e, j);
        j->refs--; /* the list's; the caller's is still held */
    } else {
        atomic_store(&j->cancel, 1); /* the worker takes it off the live list */
    }
    j->state = JOB_CANCELED;
    j->finished = now;
    waiter *w = take_waiters_locked(e, j, 0);
    pthread_mutex_unlock(&e->lock);
    wake_all(w);
    if (e->cfg.st->ops->job_set_state(e->cfg.st, j->id, JOB_CANCELED, now, 0, NULL, err,
                                      sizeof err))
        log_kv(LOG_ERROR, "store: cancel failed", "job", j->id, "error", err, NULL);
    if (was_queued) metrics_job_end(e->cfg.m, "canceled", 0); /* else the worker counts it */
}

/* j was joined (join_locked) by a submission that could not be recorded: takes it back, and
 * cancels j when that leaves it no submission. */
static void unjoin(engine *e, job *j)
{
    pthread_mutex_lock(&e->lock);
    if (--j->active == 0 && job_active(j))
        cancel_job_unlock(e, j);
    else
        pthread_mutex_unlock(&e->lock);
    engine_release(e, j);
}

/* Records a new submission of j (joined) under a new id, written to sub. */
static int add_sub(engine *e, job *j, char *sub, char *err, size_t errlen)
{
    store_sub s = {.created = engine_now()};
    memcpy(s.job, j->id, sizeof s.job);
    if (new_id(s.id)) {
        snprintf(err, errlen, "no random bytes for an id");
        return ENG_ERR;
    }
    if (e->cfg.st->ops->sub_insert(e->cfg.st, &s, err, errlen)) return ENG_ERR;
    memcpy(sub, s.id, sizeof s.id);
    return ENG_OK;
}

/* An identical job in flight joined by this submission: counted, then recorded. */
static int joined(engine *e, job *j, job **out, char *sub, int *coalesced, char *err, size_t errlen)
{
    if (add_sub(e, j, sub, err, errlen) != ENG_OK) {
        unjoin(e, j);
        return ENG_ERR;
    }
    *out = j;
    *coalesced = 1;
    metrics_coalesced(e->cfg.m);
    return ENG_OK;
}

int engine_submit(engine *e, const char *canon, size_t len, const char *kind, const char *hash,
                  job **out, char *sub, int *coalesced, char *err, size_t errlen)
{
    char id[33];
    job *jn;
    *out = NULL;
    *coalesced = 0;
    pthread_mutex_lock(&e->lock);
    if (e->draining) {
        pthread_mutex_unlock(&e->lock);
        return ENG_DRAINING;
    }
    if ((jn = join_locked(e, hash))) {
        pthread_mutex_unlock(&e->lock);
        return joined(e, jn, out, sub, coalesced, err, errlen);
    }
    /* No identical job in flight.  One may have just ended: a worker stores its result before
     * it leaves the live list, so the cache now has it (the caller looked before the scan). */
    pthread_mutex_unlock(&e->lock);
    int cached = e->cfg.st->ops->result_exists(e->cfg.st, hash, err, errlen) == STORE_OK;
    pthread_mutex_lock(&e->lock);
    if (cached) {
        pthread_mutex_unlock(&e->lock);
        return ENG_CACHED;
    }
    if ((jn = join_locked(e, hash))) { /* created by another request meanwhile */
        pthread_mutex_unlock(&e->lock);
        return joined(e, jn, out, sub, coalesced, err, errlen);
    }
    if (e->nqueued >= e->cfg.queue_max) {
        pthread_mutex_unlock(&e->lock);
        return ENG_FULL;
    }
    job *j = NULL;
    if (new_id(id) == 0) j = job_new(id, hash, kind, canon, len);
    if (!j) {
        pthread_mutex_unlock(&e->lock);
        snprintf(err, errlen, "out of memory");
        return ENG_ERR;
    }
    j->created = engine_now();
    j->state = JOB_QUEUED;
    j->refs = 2; /* the live list's and the caller's */
    j->live = 1;
    j->active = 1;
    j->next_live = e->live;
    e->live = j;
    e->nqueued++; /* counted now so that the queue limit holds while the store writes */
    pthread_mutex_unlock(&e->lock);

    store_job sj = {
        .state = JOB_QUEUED, .created = j->created, .request = j->request, .request_len = len};
    memcpy(sj.id, j->id, sizeof sj.id);
    memcpy(sj.hash, j->hash, sizeof sj.hash);
    memcpy(sj.kind, j->kind, sizeof sj.kind);
    int rc = e->cfg.st->ops->job_insert(e->cfg.st, &sj, err, errlen);
    pthread_mutex_lock(&e->lock);
    if (rc) {
        /* an identical request may have joined it meanwhile: fail it for them too */
        e->nqueued--;
        unlive_locked(e, j);
        j->state = JOB_FAILED;
        j->finished = engine_now();
        j->error_status = 503;
        j->error = strdup(err);
        waiter *w = take_waiters_locked(e, j, 0);
        j->refs -= 2; /* the list's and ours */
        int dead = j->refs == 0;
        pthread_mutex_unlock(&e->lock);
        wake_all(w);
        if (dead) job_free(j);
        return ENG_ERR;
    }
    enqueue_locked(e, j);
    pthread_mutex_unlock(&e->lock);
    metrics_job_accepted(e->cfg.m);
    memcpy(sub, j->id, sizeof j->id); /* the first submission has the job's id */
    *out = j;
    return ENG_OK;
}

int engine_join(engine *e, const char *hash, job **out, char *sub, char *err, size_t errlen)
{
    int coalesced = 0;
    *out = NULL;
    pthread_mutex_lock(&e->lock);
    job *j = e->draining ? NULL : join_locked(e, hash);
    pthread_mutex_unlock(&e->lock);
    if (!j) return ENG_NOTFOUND;
    return joined(e, j, out, sub, &coalesced, err, errlen);
}

int engine_full(engine *e)
{
    pthread_mutex_lock(&e->lock);
    int full = e->draining ? ENG_DRAINING : e->nqueued >= e->cfg.queue_max ? ENG_FULL : ENG_OK;
    pthread_mutex_unlock(&e->lock);
    return full;
}

job *engine_find(engine *e, const char *id)
{
    pthread_mutex_lock(&e->lock);
    job *j = e->live;
    while (j && strcmp(j->id, id) != 0) j = j->next_live;
    if (j) j->refs++;
    pthread_mutex_unlock(&e->lock);
    return j;
}

/* Fills a job_info; `running_stage` is what a running job shows as its stage. */
static void info_fill(job_info *out, const char *id, const char *hash, const char *kind,
                      job_state st, double created, double started, double finished,
                      const char *running_stage, double running_fraction, int error_status,
                      const char *error)
{
    memset(out, 0, sizeof *out);
    snprintf(out->id, sizeof out->id, "%s", id);
    snprintf(out->hash, sizeof out->hash, "%s", hash);
    snprintf(out->kind, sizeof out->kind, "%s", kind);
    out->state = st;
    out->created = created;
    out->started = started;
    out->finished = finished;
    snprintf(out->stage, sizeof out->stage, "%s",
             st == JOB_QUEUED    ? "queued"
             : st == JOB_RUNNING ? running_stage
                                 : "done");
    out->fraction = st == JOB_DONE ? 1 : st == JOB_RUNNING ? running_fraction : 0;
    out->error_status = error_status;
    if (error) snprintf(out->error, sizeof out->error, "%s", error);
}

static void info_locked(const job *j, job_info *out)
{
    info_fill(out, j->id, j->hash, j->kind, j->state, j->created, j->started, j->finished, j->stage,
              j->fraction, j->error_status, j->error);
}

/* The same for a job read from the store (not live). */
static void engine_info_from_store(const store_job *sj, job_info *out)
{
    info_fill(out, sj->id, sj->hash, sj->kind, sj->state, sj->created, sj->started, sj->finished,
              "running", 0, sj->error_status, sj->error);
}

void engine_info(engine *e, job *j, job_info *out)
{
    pthread_mutex_lock(&e->lock);
    info_locked(j, out);
    pthread_mutex_unlock(&e->lock);
}

const char *engine_result(engine *e, job *j, size_t *len)
{
    pthread_mutex_lock(&e->lock);
    const char *r = j->state == JOB_DONE ? j->result : NULL;
    if (r) *len = j->result_len;
    pthread_mutex_unlock(&e->lock);
    return r;
}

/* What a submission sees of its job: its own id and creation, and canceled when it was. */
static void sub_overlay(job_info *out, const store_sub *s)
{
    snprintf(out->id, sizeof out->id, "%s", s->id);
    out->created = s->created;
    if (s->canceled > 0 && out->state != JOB_CANCELED) {
        out->state = JOB_CANCELED;
        out->finished = s->canceled;
        snprintf(out->stage, sizeof out->stage, "done");
        out->fraction = 0;
        out->error_status = 0;
        out->error[0] = 0;
    }
}

int engine_lookup(engine *e, const char *id, job_info *out, job **live, char *err, size_t errlen)
{
    store_sub s;
    store *st = e->cfg.st;
    *live = NULL;
    int rc = st->ops->sub_get(st, id, &s, err, errlen);
    if (rc == STORE_NOTFOUND) return ENG_NOTFOUND;
    if (rc != STORE_OK) return ENG_ERR;
    job *j = engine_find(e, s.job);
    if (j) {
        engine_info(e, j, out);
        *live = j;
    } else { /* not live: it has ended (or it is queued after a restart of this engine) */
        store_job sj;
        rc = st->ops->job_get(st, s.job, &sj, err, errlen);
        if (rc == STORE_NOTFOUND) return ENG_NOTFOUND; /* pruned since */
        if (rc != STORE_OK) return ENG_ERR;
        engine_info_from_store(&sj, out);
        store_job_clear(&sj);
    }
    sub_overlay(out, &s);
    return ENG_OK;
}

int engine_cancel(engine *e, const char *id, job_info *out, char *err, size_t errlen)
{
    job *j = NULL;
    int rc = engine_lookup(e, id, out, &j, err, errlen);
    if (rc != ENG_OK) return rc;
    if (!j || (out->state != JOB_QUEUED && out->state != JOB_RUNNING)) {
        engine_release(e, j);
        return ENG_ENDED;
    }
    double now = engine_now();
    int changed = 0;
    rc = e->cfg.st->ops->sub_cancel(e->cfg.st, id, now, &changed, err, errlen);
    if (rc != STORE_OK || !changed) { /* failed, or canceled by another DELETE meanwhile */
        engine_release(e, j);
        return rc == STORE_OK ? ENG_ENDED : rc == STORE_NOTFOUND ? ENG_NOTFOUND : ENG_ERR;
    }
    pthread_mutex_lock(&e->lock);
    if (--j->active == 0 && job_active(j))
        cancel_job_unlock(e, j);
    else
        pthread_mutex_unlock(&e->lock);
    store_sub s = {.created = out->created, .canceled = now};
    memcpy(s.id, out->id, sizeof s.id);
    engine_info(e, j, out);
    sub_overlay(out, &s);
    engine_release(e, j);
    return ENG_OK;
}

int engine_wait(engine *e, job *j, double deadline, void (*wake)(void *), void *ctx)
{
    waiter *w = malloc(sizeof *w);
    pthread_mutex_lock(&e->lock);
    if ((j->state != JOB_QUEUED && j->state != JOB_RUNNING) || e->draining) {
        /* ended, or the drain has already woken every waiter: answer now */
        pthread_mutex_unlock(&e->lock);
        free(w);
        return 1;
    }
    if (!w) { /* no memory for a waiter: answer at once, as if the deadline had passed */
        pthread_mutex_unlock(&e->lock);
        wake(ctx);
        return 0;
    }
    *w = (waiter){.j = j, .deadline = deadline, .wake = wake, .ctx = ctx, .next = e->waiters};
    e->waiters = w;
    pthread_cond_signal(&e->tick);
    pthread_mutex_unlock(&e->lock);
    return 0;
}

void engine_drain(engine *e, double timeout)
{
    pthread_mutex_lock(&e->lock);
    e->draining = 1;
    pthread_cond_broadcast(&e->work);
    double until = engine_now() + timeout;
    while (e->nrunning > 0 && engine_now() < until) {
        struct timespec ts = {.tv_sec = (time_t)until,
                              .tv_nsec = (long)((until - (double)(time_t)until) * 1e9)};
        pthread_cond_timedwait(&e->idle, &e->lock, &ts);
    }
    if (e->nrunning > 0)
        log_kv(LOG_WARN, "drain timeout: jobs still running are resumed at the next start", NULL);
    waiter *w = take_waiters_locked(e, NULL, 0);
    pthread_mutex_unlock(&e->lock);
    wake_all(w);
}

void engine_stop(engine *e)
{
    pthread_mutex_lock(&e->lock);
    int busy = e->nrunning > 0;
    e->stopping = 1;
    pthread_cond_broadcast(&e->work);
    pthread_cond_broadcast(&e->tick);
    pthread_mutex_unlock(&e->lock);
    if (e->timer_started) pthread_join(e->timer, NULL);
    if (busy) {
        /* a worker is still inside a job after the drain timeout: it must not touch a freed
         * engine; the process is about to exit, so the engine is left allocated */
        for (int i = 0; i < e->nthreads; i++) pthread_detach(e->threads[i]);
        return;
    }
    for (int i = 0; i < e->nthreads; i++) pthread_join(e->threads[i], NULL);
    free(e->threads);
    while (e->live) { /* queued jobs: they stay queued in the store */
        job *j = e->live;
        e->live = j->next_live;
        unref_locked(j);
    }
    pthread_mutex_destroy(&e->lock);
    pthread_cond_destroy(&e->work);
    pthread_cond_destroy(&e->idle);
    pthread_cond_destroy(&e->tick);
    free(e);
}

void engine_gauges(engine *e, size_t *queued, size_t *running, size_t *queue_max, int *draining)
{
    pthread_mutex_lock(&e->lock);
    *queued = e->nqueued;
    *running = e->nrunning;
    *queue_max = e->cfg.queue_max;
    *draining = e->draining;
    pthread_mutex_unlock(&e->lock);
}
