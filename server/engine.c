/* engine.c — see engine.h.
 *
 * One mutex (lock) guards the list of jobs running here, the waiters, the workers' wake-up
 * count and the flags; the condition `work` wakes workers, `idle` wakes a drain waiting for
 * running jobs to end, `tick` wakes the timer thread.  Store I/O and the geometry run outside
 * the lock.
 *
 * A job running here is a `run`: the job as claimed (its request), the flag the core reads to
 * stop, its progress, and whether its lease was lost (then it is another daemon's: nothing it
 * makes is written as the job's end) or it is to be given back (a drain that stops it).  It
 * belongs to its worker; the list lets the timer renew its lease and a cancel reach it.
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
    char job[33];
    double deadline;
    void (*wake)(void *);
    void *ctx;
    struct waiter *next;
} waiter;

typedef struct run {
    store_job sj;      /* as claimed: id, hash, kind, request; immutable */
    atomic_int cancel; /* read by the core */
    char stage[32];    /* lock */
    double fraction;   /* lock */
    int lost;          /* lock: the lease is no longer ours */
    int give_back;     /* lock: a drain stops it: back to the queue, not canceled */
    struct run *next;  /* lock: e->running */
} run;

/* Checked requests kept for the workers here at most, and the bytes of their canonical texts. */
#define STASH_MAX   64
#define STASH_BYTES ((size_t)256 << 20)

struct engine {
    engine_cfg cfg;
    char owner[STORE_OWNER_MAX];
    pthread_mutex_t lock;
    pthread_cond_t work, idle, tick;
    run *running; /* the jobs running here */
    size_t nrunning;
    int pending; /* claims worth trying now (a job was queued, here or elsewhere) */
    int poll;    /* the timer should look at the waiters' jobs in the store */
    waiter *waiters;
    int draining, stopping;
    pthread_t *threads; /* workers */
    int nthreads;
    pthread_t timer, listener;
    int timer_started, listener_started;
    /* checked requests (lock): see stash_put */
    struct stash_ent {
        char hash[65];
        api_request *q;
        size_t bytes; /* its canonical text's, a proxy for its size */
    } stash[STASH_MAX];
    size_t nstash, stash_bytes;
};

/* How long an idle worker waits before it looks at the queue again (a job queued by another
 * daemon whose event was lost, a lease that ran out); a store no other daemon uses has no
 * jobs but those submitted here, which wake a worker themselves. */
#define POLL_SHARED 1.0
#define POLL_ALONE  5.0
/* A job's result or end that cannot be written (the store is away) is tried again every
 * second, this many times; then the job is left to its lease, and requeued when it runs out. */
#define STORE_TRIES 30

double engine_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static struct timespec abs_time(double t)
{
    struct timespec ts = {.tv_sec = (time_t)t, .tv_nsec = (long)((t - (double)(time_t)t) * 1e9)};
    return ts;
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

/* ---- waiters ---- */

/* lock held: moves the waiters of job (every waiter when job is NULL and now <= 0; those past
 * `now` when job is NULL and now > 0) to the returned list, to be woken outside the lock */
static waiter *take_waiters_locked(engine *e, const char *job, double now)
{
    waiter *out = NULL;
    for (waiter **p = &e->waiters; *p;) {
        waiter *w = *p;
        int take = job ? !strcmp(w->job, job) : (now <= 0 || w->deadline <= now);
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

static void wake_job(engine *e, const char *job)
{
    pthread_mutex_lock(&e->lock);
    waiter *w = take_waiters_locked(e, job, 0);
    pthread_mutex_unlock(&e->lock);
    wake_all(w);
}

/* Wakes n workers (a job was queued): they try a claim at once. */
static void hint_workers(engine *e, int n)
{
    pthread_mutex_lock(&e->lock);
    e->pending += n;
    if (e->pending > e->nthreads) e->pending = e->nthreads;
    if (n > 1)
        pthread_cond_broadcast(&e->work);
    else
        pthread_cond_signal(&e->work);
    pthread_mutex_unlock(&e->lock);
}

/* ---- running a job ---- */

typedef struct progress_ctx {
    engine *e;
    run *r;
} progress_ctx;

/* api/ reports the stage running and the fraction of the whole job (api_run_opts.progress),
 * a few hundred times per job at most: the engine lock is fine. */
static void progress_cb(void *udata, const char *stage, double fraction)
{
    progress_ctx *p = udata;
    pthread_mutex_lock(&p->e->lock);
    snprintf(p->r->stage, sizeof p->r->stage, "%s", stage);
    if (fraction > p->r->fraction) p->r->fraction = fraction;
    pthread_mutex_unlock(&p->e->lock);
}

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

static int run_lost(engine *e, run *r)
{
    pthread_mutex_lock(&e->lock);
    int lost = r->lost;
    pthread_mutex_unlock(&e->lock);
    return lost;
}

static void pause_s(double s)
{
    struct timespec ts = {.tv_sec = (time_t)s, .tv_nsec = (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

/* Moves the spooled result (len bytes) into the store, tried again while the store is away
 * (STORE_TRIES) and the job is still ours. */
static int spool_store(engine *e, run *r, FILE *f, uint64_t len, char *err, size_t errlen)
{
    store *st = e->cfg.st;
    for (int t = 0;; t++) {
        if (fflush(f) || fseek(f, 0, SEEK_SET)) {
            snprintf(err, errlen, "the spool file: %s", strerror(errno));
            return STORE_ERR;
        }
        if (st->ops->result_put_file(st, r->sj.hash, r->sj.id, f, len, err, errlen) == STORE_OK)
            return STORE_OK;
        if (t + 1 >= STORE_TRIES || run_lost(e, r)) return STORE_ERR;
        log_kv(LOG_WARN, "store: result_put failed, trying again", "job", r->sj.id, "error", err,
               NULL);
        pause_s(1);
    }
}

/* Writes the end of job r, tried again while the store is away.  0 written; 1 the job is no
 * longer ours; -1 not written (the lease will run out, and the job be requeued). */
static int finish(engine *e, run *r, job_state st, double when, int status, const char *msg)
{
    char err[256];
    store *s = e->cfg.st;
    for (int t = 0;; t++) {
        int rc = s->ops->job_finish(s, r->sj.id, e->owner, st, when, status, msg, err, sizeof err);
        if (rc == STORE_OK) return 0;
        if (rc == STORE_NOTFOUND) return 1;
        if (t + 1 >= STORE_TRIES || run_lost(e, r)) {
            log_kv(LOG_ERROR, "store: job_finish failed: the job is left to its lease", "job",
                   r->sj.id, "error", err, NULL);
            return -1;
        }
        pause_s(1);
    }
}

/* ---- checked requests ----
 * The intake parses and checks a request once (api_check_request_ex) and hands the checked
 * form to engine_submit, which keeps it here by request hash for the worker of this daemon
 * that claims the job: that worker runs it without reading or checking it again.  A job run
 * from the store (claimed by another daemon, requeued, resumed after a restart) or whose
 * checked form was dropped runs from its stored canonical text, parsed and checked then,
 * once.  The oldest are dropped past STASH_MAX or STASH_BYTES (a job queued long, or taken by
 * another daemon, never holds memory for long). */

/* Keeps q (taken) for the job with this hash. */
static void stash_put(engine *e, const char *hash, api_request *q, size_t bytes)
{
    pthread_mutex_lock(&e->lock);
    while (e->nstash && (e->nstash == STASH_MAX || e->stash_bytes + bytes > STASH_BYTES)) {
        api_request_free(e->stash[0].q); /* the oldest */
        e->stash_bytes -= e->stash[0].bytes;
        memmove(e->stash, e->stash + 1, --e->nstash * sizeof *e->stash);
    }
    struct stash_ent *s = &e->stash[e->nstash++];
    snprintf(s->hash, sizeof s->hash, "%s", hash);
    s->q = q;
    s->bytes = bytes;
    e->stash_bytes += bytes;
    pthread_mutex_unlock(&e->lock);
}

/* Takes the checked request kept for hash (only: that one), or NULL. */
static api_request *stash_take(engine *e, const char *hash, const api_request *only)
{
    api_request *q = NULL;
    pthread_mutex_lock(&e->lock);
    for (size_t i = 0; i < e->nstash; i++) {
        struct stash_ent *s = &e->stash[i];
        if (strcmp(s->hash, hash) || (only && s->q != only)) continue;
        q = s->q;
        e->stash_bytes -= s->bytes;
        memmove(s, s + 1, (--e->nstash - i) * sizeof *s);
        break;
    }
    pthread_mutex_unlock(&e->lock);
    return q;
}

/* Runs the claimed job r on this worker thread.  The result is written to a spool file as it
 * is made, then copied into the store a chunk at a time: a large result never sits whole in
 * memory. */
/* Returns whether the job was large (it ran half a second or more, or its request or result
 * was large): then most of its peak is worth handing back to the system. */
static int run_job(engine *e, run *r)
{
    char err[256] = "";
    api_error ae = {0};
    char *out = NULL;
    size_t outlen = 0;
    double t0 = engine_now();
    progress_ctx pc = {e, r};
    api_run_opts ro = {
        .threads = e->cfg.job_threads, .cancel = &r->cancel, .progress = progress_cb, .udata = &pc};
    int rc;
    api_request *q = stash_take(e, r->sj.hash, NULL); /* checked at the intake here */
    ro.stream = spool_open(e->cfg.spool_dir, err, sizeof err);
    if (!ro.stream) {
        log_kv(LOG_ERROR, "spool failed", "job", r->sj.id, "error", err, NULL);
        api_request_free(q);
        rc = API_ENOMEM;
        snprintf(ae.msg, sizeof ae.msg, "the result could not be spooled: %.200s", err);
    } else if (q) {
        rc = api_request_run(q, &ro, &out, &outlen, &ae);
    } else {
        rc = api_run_json_ex(r->sj.request, r->sj.request_len, &ro, &out, &outlen, &ae);
    }
    free(out); /* streamed: nothing is returned */
    job_state final = rc == API_OK ? JOB_DONE : rc == API_ECANCELED ? JOB_CANCELED : JOB_FAILED;
    if (rc == API_OK && spool_store(e, r, ro.stream, outlen, err, sizeof err)) {
        log_kv(LOG_ERROR, "store: result_put failed", "job", r->sj.id, "error", err, NULL);
        final = JOB_FAILED;
        rc = 503;
        snprintf(ae.msg, sizeof ae.msg, "the result could not be stored: %.200s", err);
    }
    if (ro.stream) fclose(ro.stream);
    double t1 = engine_now();

    pthread_mutex_lock(&e->lock);
    int lost = r->lost, give_back = r->give_back && final == JOB_CANCELED;
    pthread_mutex_unlock(&e->lock);
    const char *what = job_state_name(final);
    if (lost) {
        what = "lost"; /* another daemon has it now: its end is theirs to write */
    } else if (give_back) {
        if (e->cfg.st->ops->job_release(e->cfg.st, r->sj.id, e->owner, err, sizeof err) ==
            STORE_ERR)
            log_kv(LOG_ERROR, "store: job_release failed: the job is left to its lease", "job",
                   r->sj.id, "error", err, NULL);
        what = "given back";
    } else if (finish(e, r, final, t1, final == JOB_FAILED ? rc : 0,
                      final == JOB_FAILED ? ae.msg : NULL) == 1) {
        what = "lost";
    }
    pthread_mutex_lock(&e->lock);
    for (run **p = &e->running; *p; p = &(*p)->next)
        if (*p == r) {
            *p = r->next;
            break;
        }
    e->nrunning--;
    waiter *w = take_waiters_locked(e, r->sj.id, 0);
    pthread_cond_broadcast(&e->idle);
    pthread_mutex_unlock(&e->lock);
    wake_all(w);
    if (!lost && !give_back) metrics_job_end(e->cfg.m, job_state_name(final), t1 - t0);
    char ms[32];
    log_kv(LOG_INFO, "job ended", "job", r->sj.id, "kind", r->sj.kind, "state", what, "ms",
           log_num(ms, (t1 - t0) * 1e3), NULL);
    return t1 - t0 >= 0.5 || outlen > (8u << 20) || r->sj.request_len > (1u << 20);
}

static void *worker_main(void *arg)
{
    engine *e = arg;
    int try_now = 1; /* at start: jobs may be queued already */
    double poll = e->cfg.st->shared ? POLL_SHARED : POLL_ALONE;
    for (;;) {
        pthread_mutex_lock(&e->lock);
        if (!try_now && !e->pending && !e->stopping && !e->draining) {
            struct timespec ts = abs_time(engine_now() + poll);
            pthread_cond_timedwait(&e->work, &e->lock, &ts);
        }
        if (e->stopping || e->draining) {
            pthread_mutex_unlock(&e->lock);
            return NULL;
        }
        if (e->pending > 0) e->pending--;
        pthread_mutex_unlock(&e->lock);

        char err[256];
        run *r = calloc(1, sizeof *r);
        if (!r) {
            pause_s(1);
            continue;
        }
        int rc = e->cfg.st->ops->job_claim(e->cfg.st, e->owner, engine_now(), e->cfg.lease, &r->sj,
                                           err, sizeof err);
        if (rc != STORE_OK) {
            if (rc == STORE_ERR) log_kv(LOG_WARN, "store: job_claim failed", "error", err, NULL);
            free(r);
            try_now = 0;
            continue;
        }
        atomic_init(&r->cancel, 0);
        snprintf(r->stage, sizeof r->stage, "started");
        if (r->sj.active_subs == 0) { /* every submission canceled (a store written by hand) */
            if (finish(e, r, JOB_CANCELED, engine_now(), 0, NULL) == 0)
                metrics_job_end(e->cfg.m, "canceled", 0);
            wake_job(e, r->sj.id);
            store_job_clear(&r->sj);
            free(r);
            continue; /* try_now stays set: the queue may hold more */
        }
        pthread_mutex_lock(&e->lock);
        r->next = e->running;
        e->running = r;
        e->nrunning++;
        pthread_mutex_unlock(&e->lock);
        metrics_job_started(e->cfg.m);
        if (r->sj.attempts > 1) {
            char a[32];
            log_kv(LOG_INFO, "job resumed", "job", r->sj.id, "kind", r->sj.kind, "attempt",
                   log_num(a, r->sj.attempts), NULL);
        }
        int large = run_job(e, r);
        store_job_clear(&r->sj);
        free(r);
        try_now = 1; /* the queue may hold more */
        /* a large job leaves most of its peak free but kept by the allocator (16 000 cubes:
         * 0.7 GB resident after a 1.7 GB peak): hand it back to the system (not after every
         * small one: a trim costs about 2 ms, more than a small job) */
        if (large) malloc_trim(0);
    }
}

/* ---- the timer: deadlines, leases, requeues, the prune ---- */

typedef struct renewal {
    char id[33], stage[32];
    double fraction;
    run *r;
} renewal;

/* After a renewal found no job running here under id: is it running elsewhere, or queued
 * again (the lease was lost)?  Not when it ended meanwhile (its worker finished it between the
 * list of running jobs and the renewal): that is no loss, and says nothing.  A store error
 * counts as lost, as the renewal said. */
static int lease_taken(engine *e, const char *id)
{
    char err[256];
    store_job j = {0};
    int rc = e->cfg.st->ops->job_get(e->cfg.st, id, &j, err, sizeof err);
    int taken = rc != STORE_OK || j.state == JOB_QUEUED ||
                (j.state == JOB_RUNNING && strcmp(j.owner, e->owner) != 0);
    store_job_clear(&j);
    return taken;
}

/* Renews the lease of every job running here and writes its progress; a job asked to stop is
 * told, one no longer ours is marked lost and stopped. */
static void renew_all(engine *e)
{
    char err[256];
    pthread_mutex_lock(&e->lock);
    size_t n = e->nrunning, k = 0;
    renewal *rs = n ? calloc(n, sizeof *rs) : NULL;
    for (run *r = e->running; r && k < n && rs; r = r->next, k++) {
        memcpy(rs[k].id, r->sj.id, sizeof rs[k].id);
        memcpy(rs[k].stage, r->stage, sizeof rs[k].stage);
        rs[k].fraction = r->fraction;
        rs[k].r = r;
    }
    pthread_mutex_unlock(&e->lock);
    for (size_t i = 0; i < k; i++) {
        int cancel = 0;
        int rc =
            e->cfg.st->ops->job_renew(e->cfg.st, rs[i].id, e->owner, engine_now(), e->cfg.lease,
                                      rs[i].stage, rs[i].fraction, &cancel, err, sizeof err);
        if (rc == STORE_ERR) {
            log_kv(LOG_WARN, "store: job_renew failed", "job", rs[i].id, "error", err, NULL);
            continue;
        }
        if (rc == STORE_NOTFOUND && !lease_taken(e, rs[i].id)) continue; /* it just ended */
        pthread_mutex_lock(&e->lock);
        for (run *r = e->running; r; r = r->next) /* still running (rs[i].r may be gone) */
            if (r == rs[i].r && !strcmp(r->sj.id, rs[i].id)) {
                if (rc == STORE_NOTFOUND) r->lost = 1;
                if (rc == STORE_NOTFOUND || cancel) atomic_store(&r->cancel, 1);
                break;
            }
        pthread_mutex_unlock(&e->lock);
        if (rc == STORE_NOTFOUND)
            log_kv(LOG_WARN, "lease lost: the job runs elsewhere now", "job", rs[i].id, NULL);
    }
    free(rs);
}

/* With a shared store: wakes the waiters whose job ended elsewhere (an event may have been
 * lost; this runs every second). */
static void poll_waiters(engine *e)
{
    char err[256];
    pthread_mutex_lock(&e->lock);
    size_t n = 0;
    for (waiter *w = e->waiters; w; w = w->next) n++;
    char(*ids)[33] = n ? malloc(n * sizeof *ids) : NULL;
    size_t k = 0;
    for (waiter *w = e->waiters; w && ids; w = w->next) {
        size_t i = 0;
        while (i < k && strcmp(ids[i], w->job)) i++;
        if (i == k) memcpy(ids[k++], w->job, 33);
    }
    pthread_mutex_unlock(&e->lock);
    for (size_t i = 0; i < k; i++) {
        store_job sj;
        if (e->cfg.st->ops->job_get(e->cfg.st, ids[i], &sj, err, sizeof err) != STORE_OK) continue;
        int ended = sj.state != JOB_QUEUED && sj.state != JOB_RUNNING;
        store_job_clear(&sj);
        if (ended) wake_job(e, ids[i]);
    }
    free(ids);
}

static void *timer_main(void *arg)
{
    engine *e = arg;
    double now = engine_now(), next_prune = now + 5, next_tick = now + 1,
           next_requeue = now + (e->cfg.lease / 3 < 5 ? e->cfg.lease / 3 : 5);
    pthread_mutex_lock(&e->lock);
    while (!e->stopping) {
        now = engine_now();
        double soonest = next_tick;
        for (waiter *w = e->waiters; w; w = w->next)
            if (w->deadline < soonest) soonest = w->deadline;
        if (soonest > now) {
            struct timespec ts = abs_time(soonest);
            pthread_cond_timedwait(&e->tick, &e->lock, &ts);
            continue;
        }
        waiter *w = take_waiters_locked(e, NULL, now);
        int poll = e->poll || e->cfg.st->shared;
        e->poll = 0;
        pthread_mutex_unlock(&e->lock);
        wake_all(w);
        /* renewals also read the cancel flag (set by a DELETE in the instant between a claim
         * and the job's entry in the running list, or by another daemon) */
        if (now >= next_tick) {
            next_tick = now + 1;
            renew_all(e);
            if (poll) poll_waiters(e);
        }
        char err[256];
        /* others' jobs whose leases ran out (a store only this daemon uses has none: its jobs
         * are requeued at its next start) */
        if (now >= next_requeue && e->cfg.st->shared) {
            size_t n = 0;
            next_requeue = now + (e->cfg.lease / 3 < 5 ? e->cfg.lease / 3 : 5);
            if (e->cfg.st->ops->jobs_requeue(e->cfg.st, now, 0, &n, err, sizeof err))
                log_kv(LOG_WARN, "store: jobs_requeue failed", "error", err, NULL);
            if (n) {
                char c[32];
                log_kv(LOG_INFO, "leases ran out: jobs requeued", "jobs", log_num(c, (double)n),
                       NULL);
                hint_workers(e, (int)n);
            }
        }
        if (now >= next_prune) { /* finished jobs: kept job_ttl seconds, max_jobs at most */
            size_t n = 0;
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

/* ---- the listener: other daemons' events (a shared store only) ---- */

static void *listener_main(void *arg)
{
    engine *e = arg;
    char err[256], id[33];
    for (;;) {
        pthread_mutex_lock(&e->lock);
        int stop = e->stopping;
        pthread_mutex_unlock(&e->lock);
        if (stop) return NULL;
        store_ev ev = STORE_EV_NONE;
        if (e->cfg.st->ops->wait_event(e->cfg.st, 0.5, &ev, id, err, sizeof err)) {
            log_kv(LOG_WARN, "store: wait_event failed", "error", err, NULL);
            pause_s(0.5);
            ev = STORE_EV_RESET;
        }
        switch (ev) {
        case STORE_EV_QUEUED:
            hint_workers(e, e->nthreads);
            break;
        case STORE_EV_ENDED:
            wake_job(e, id);
            break;
        case STORE_EV_CANCEL:
            pthread_mutex_lock(&e->lock);
            for (run *r = e->running; r; r = r->next)
                if (!strcmp(r->sj.id, id)) atomic_store(&r->cancel, 1);
            pthread_mutex_unlock(&e->lock);
            break;
        case STORE_EV_RESET: /* events may have been lost: look again */
            hint_workers(e, e->nthreads);
            pthread_mutex_lock(&e->lock);
            e->poll = 1;
            pthread_mutex_unlock(&e->lock);
            break;
        case STORE_EV_NONE:
            break;
        }
    }
}

/* ---- start and stop ---- */

engine *engine_start(const engine_cfg *cfg, char *err, size_t errlen)
{
    engine *e = calloc(1, sizeof *e);
    if (!e) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    e->cfg = *cfg;
    if (e->cfg.lease <= 0) e->cfg.lease = 30;
    snprintf(e->owner, sizeof e->owner, "%s", cfg->name && *cfg->name ? cfg->name : "cellard");
    pthread_mutex_init(&e->lock, NULL);
    pthread_cond_init(&e->work, NULL);
    pthread_cond_init(&e->idle, NULL);
    pthread_cond_init(&e->tick, NULL);
    FILE *probe = spool_open(cfg->spool_dir, err, errlen); /* refuse to start without a spool */
    if (!probe) goto fail;
    fclose(probe);
    /* jobs left running: in a store only this daemon uses, all of them (their daemon was this
     * one, before a restart); in a shared one, those whose lease ran out */
    size_t n = 0;
    if (cfg->st->ops->jobs_requeue(cfg->st, engine_now(), !cfg->st->shared, &n, err, errlen))
        goto fail;
    if (n) {
        char c[32];
        log_kv(LOG_INFO, "jobs requeued at start", "jobs", log_num(c, (double)n), NULL);
    }
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
    if (cfg->st->ops->wait_event) {
        if (pthread_create(&e->listener, NULL, listener_main, e) != 0) {
            snprintf(err, errlen, "cannot start the listener thread");
            goto fail;
        }
        e->listener_started = 1;
    }
    return e;
fail:
    engine_drain(e, 0);
    engine_stop(e);
    return NULL;
}

void engine_drain(engine *e, double timeout)
{
    pthread_mutex_lock(&e->lock);
    e->draining = 1;
    pthread_cond_broadcast(&e->work);
    double until = engine_now() + timeout;
    while (e->nrunning > 0 && engine_now() < until) {
        struct timespec ts = abs_time(until);
        pthread_cond_timedwait(&e->idle, &e->lock, &ts);
    }
    if (e->nrunning > 0) {
        /* stop them and give them back to the queue: another daemon, or the next start,
         * runs them; the core stops within about a second */
        log_kv(LOG_WARN, "drain timeout: the jobs still running go back to the queue", NULL);
        for (run *r = e->running; r; r = r->next) {
            r->give_back = 1;
            atomic_store(&r->cancel, 1);
        }
        until = engine_now() + 5;
        while (e->nrunning > 0 && engine_now() < until) {
            struct timespec ts = abs_time(until);
            pthread_cond_timedwait(&e->idle, &e->lock, &ts);
        }
    }
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
    if (e->listener_started) pthread_join(e->listener, NULL);
    if (busy) {
        /* a worker is still inside a job after the drain: it must not touch a freed engine;
         * the process is about to exit, so the engine is left allocated (the job's lease runs
         * out, and it is requeued) */
        for (int i = 0; i < e->nthreads; i++) pthread_detach(e->threads[i]);
        return;
    }
    for (int i = 0; i < e->nthreads; i++) pthread_join(e->threads[i], NULL);
    for (size_t i = 0; i < e->nstash; i++) api_request_free(e->stash[i].q);
    free(e->threads);
    pthread_mutex_destroy(&e->lock);
    pthread_cond_destroy(&e->work);
    pthread_cond_destroy(&e->idle);
    pthread_cond_destroy(&e->tick);
    free(e);
}

/* ---- submissions ---- */

static int draining(engine *e)
{
    pthread_mutex_lock(&e->lock);
    int d = e->draining;
    pthread_mutex_unlock(&e->lock);
    return d;
}

int engine_submit(engine *e, const char *canon, size_t len, const char *kind, const char *hash,
                  api_request *checked, char *sub, char *job, int *coalesced, char *err,
                  size_t errlen)
{
    *coalesced = 0;
    if (draining(e)) {
        api_request_free(checked);
        return ENG_DRAINING;
    }
    store_job j = {.created = engine_now(), .request = (char *)canon, .request_len = len};
    if (new_id(j.id)) {
        api_request_free(checked);
        snprintf(err, errlen, "no random bytes for an id");
        return ENG_ERR;
    }
    snprintf(j.hash, sizeof j.hash, "%s", hash);
    snprintf(j.kind, sizeof j.kind, "%s", kind);
    /* kept before the job is queued, so that the worker that claims it finds it */
    if (checked) stash_put(e, hash, checked, len);
    int rc =
        e->cfg.st->ops->job_submit(e->cfg.st, &j, e->cfg.queue_max, 0, job, coalesced, err, errlen);
    if (checked && (rc != STORE_OK || *coalesced)) /* no new job: not needed */
        api_request_free(stash_take(e, hash, checked));
    if (rc == STORE_CACHED) return ENG_CACHED;
    if (rc == STORE_FULL) return ENG_FULL;
    if (rc != STORE_OK) return ENG_ERR;
    memcpy(sub, j.id, sizeof j.id);
    if (*coalesced) {
        metrics_coalesced(e->cfg.m);
    } else {
        metrics_job_accepted(e->cfg.m);
        hint_workers(e, 1);
    }
    return ENG_OK;
}

int engine_join(engine *e, const char *hash, char *sub, char *job, char *err, size_t errlen)
{
    int joined = 0;
    if (draining(e)) return ENG_NOTFOUND;
    store_job j = {.created = engine_now(), .request = ""};
    if (new_id(j.id)) {
        snprintf(err, errlen, "no random bytes for an id");
        return ENG_ERR;
    }
    snprintf(j.hash, sizeof j.hash, "%s", hash);
    int rc = e->cfg.st->ops->job_submit(e->cfg.st, &j, 0, 1, job, &joined, err, errlen);
    if (rc == STORE_OK && joined) {
        memcpy(sub, j.id, sizeof j.id);
        metrics_coalesced(e->cfg.m);
        return ENG_OK;
    }
    return rc == STORE_ERR ? ENG_ERR : ENG_NOTFOUND;
}

int engine_full(engine *e, char *err, size_t errlen)
{
    size_t queued = 0, running = 0;
    if (draining(e)) return ENG_DRAINING;
    if (e->cfg.st->ops->job_counts(e->cfg.st, &queued, &running, err, errlen)) return ENG_ERR;
    return e->cfg.queue_max && queued >= e->cfg.queue_max ? ENG_FULL : ENG_OK;
}

/* The job as one submission sees it (s: the submission), with the progress of a job running
 * here taken from memory (the store's is at most a second old). */
static void info_fill(engine *e, const store_job *sj, const store_sub *s, job_info *out)
{
    memset(out, 0, sizeof *out);
    snprintf(out->id, sizeof out->id, "%s", s->id);
    snprintf(out->job, sizeof out->job, "%s", sj->id);
    snprintf(out->hash, sizeof out->hash, "%s", sj->hash);
    snprintf(out->kind, sizeof out->kind, "%s", sj->kind);
    snprintf(out->owner, sizeof out->owner, "%s", sj->owner);
    out->attempts = sj->attempts;
    out->state = sj->state;
    out->created = s->created;
    out->started = sj->started;
    out->finished = sj->finished;
    out->error_status = sj->error_status;
    if (sj->error) snprintf(out->error, sizeof out->error, "%s", sj->error);
    if (sj->state == JOB_RUNNING) {
        snprintf(out->stage, sizeof out->stage, "%s", sj->stage[0] ? sj->stage : "started");
        out->fraction = sj->fraction;
        pthread_mutex_lock(&e->lock);
        for (run *r = e->running; r; r = r->next)
            if (!strcmp(r->sj.id, sj->id)) {
                snprintf(out->stage, sizeof out->stage, "%s", r->stage);
                out->fraction = r->fraction;
            }
        pthread_mutex_unlock(&e->lock);
    } else {
        static const char *const names[] = {[JOB_QUEUED] = "queued",
                                            [JOB_DONE] = "done",
                                            [JOB_FAILED] = "failed",
                                            [JOB_CANCELED] = "canceled"};
        snprintf(out->stage, sizeof out->stage, "%s", names[sj->state] ? names[sj->state] : "");
        out->fraction = sj->state == JOB_DONE ? 1 : 0;
    }
    if (s->canceled > 0 && sj->state != JOB_CANCELED) { /* the submission's own cancel */
        out->state = JOB_CANCELED;
        out->finished = s->canceled;
        snprintf(out->stage, sizeof out->stage, "canceled");
        out->fraction = 0;
        out->error_status = 0;
        out->error[0] = 0;
    }
}

/* The submission id and its job from the store. */
static int lookup(engine *e, const char *id, store_sub *s, store_job *sj, char *err, size_t errlen)
{
    store *st = e->cfg.st;
    memset(sj, 0, sizeof *sj);
    int rc = st->ops->sub_get(st, id, s, err, errlen);
    if (rc == STORE_NOTFOUND) return ENG_NOTFOUND;
    if (rc != STORE_OK) return ENG_ERR;
    rc = st->ops->job_get(st, s->job, sj, err, errlen);
    if (rc == STORE_NOTFOUND) return ENG_NOTFOUND; /* pruned since */
    return rc == STORE_OK ? ENG_OK : ENG_ERR;
}

int engine_lookup(engine *e, const char *id, job_info *out, char *err, size_t errlen)
{
    store_sub s;
    store_job sj;
    int rc = lookup(e, id, &s, &sj, err, errlen);
    if (rc == ENG_OK) info_fill(e, &sj, &s, out);
    store_job_clear(&sj);
    return rc;
}

int engine_cancel(engine *e, const char *id, job_info *out, char *err, size_t errlen)
{
    store_sub s;
    store_job sj;
    int rc = lookup(e, id, &s, &sj, err, errlen);
    if (rc == ENG_OK) info_fill(e, &sj, &s, out);
    store_job_clear(&sj);
    if (rc != ENG_OK) return rc;
    if (out->state != JOB_QUEUED && out->state != JOB_RUNNING) return ENG_ENDED;
    double now = engine_now();
    int changed = 0, what = STORE_JOB_KEPT;
    rc = e->cfg.st->ops->sub_cancel(e->cfg.st, id, now, &changed, &what, err, errlen);
    if (rc != STORE_OK) return rc == STORE_NOTFOUND ? ENG_NOTFOUND : ENG_ERR;
    if (!changed) return ENG_ENDED;   /* canceled by another DELETE meanwhile */
    if (what == STORE_JOB_CANCELED) { /* it was queued: ended now, its checked form dropped */
        metrics_job_end(e->cfg.m, "canceled", 0);
        api_request_free(stash_take(e, out->hash, NULL));
        wake_job(e, s.job);
    } else if (what == STORE_JOB_STOPPING) { /* running: here, stopped now; elsewhere, told */
        pthread_mutex_lock(&e->lock);
        for (run *r = e->running; r; r = r->next)
            if (!strcmp(r->sj.id, s.job)) atomic_store(&r->cancel, 1);
        pthread_mutex_unlock(&e->lock);
    }
    s.canceled = now;
    if (lookup(e, id, &s, &sj, err, errlen) == ENG_OK) info_fill(e, &sj, &s, out);
    store_job_clear(&sj);
    out->state = JOB_CANCELED;
    out->finished = now;
    return ENG_OK;
}

int engine_wait(engine *e, const char *job, double deadline, void (*wake)(void *), void *ctx)
{
    char err[256];
    waiter *w = malloc(sizeof *w);
    if (!w) { /* no memory for a waiter: answer at once, as if the deadline had passed */
        wake(ctx);
        return 0;
    }
    *w = (waiter){.deadline = deadline, .wake = wake, .ctx = ctx};
    snprintf(w->job, sizeof w->job, "%s", job);
    pthread_mutex_lock(&e->lock);
    if (e->draining) { /* the drain has woken every waiter already: answer now */
        pthread_mutex_unlock(&e->lock);
        free(w);
        return 1;
    }
    w->next = e->waiters;
    e->waiters = w;
    pthread_cond_signal(&e->tick);
    pthread_mutex_unlock(&e->lock);
    /* registered first, then looked at: a job that ends meanwhile either finds the waiter (and
     * wakes it) or is seen ended here */
    store_job sj;
    int ended = 0;
    if (e->cfg.st->ops->job_get(e->cfg.st, job, &sj, err, sizeof err) == STORE_OK) {
        ended = sj.state != JOB_QUEUED && sj.state != JOB_RUNNING;
        store_job_clear(&sj);
    }
    if (!ended) return 0;
    pthread_mutex_lock(&e->lock);
    for (waiter **p = &e->waiters; *p; p = &(*p)->next)
        if (*p == w) { /* still ours to take: answer now */
            *p = w->next;
            pthread_mutex_unlock(&e->lock);
            free(w);
            return 1;
        }
    pthread_mutex_unlock(&e->lock); /* taken by a waker, which calls wake */
    return 0;
}

void engine_checked_kept(engine *e, size_t *n, uint64_t *bytes)
{
    pthread_mutex_lock(&e->lock);
    *n = e->nstash;
    *bytes = e->stash_bytes;
    pthread_mutex_unlock(&e->lock);
}

void engine_gauges(engine *e, size_t *queued, size_t *running, size_t *running_here,
                   size_t *queue_max, int *draining_out)
{
    char err[256];
    *queued = *running = 0;
    if (e->cfg.st->ops->job_counts(e->cfg.st, queued, running, err, sizeof err))
        log_kv(LOG_WARN, "store: job_counts failed", "error", err, NULL);
    pthread_mutex_lock(&e->lock);
    *running_here = e->nrunning;
    *queue_max = e->cfg.queue_max;
    *draining_out = e->draining;
    pthread_mutex_unlock(&e->lock);
}
