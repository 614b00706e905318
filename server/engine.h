/* engine.h — the job engine: worker threads that claim jobs from the store's queue and run them
 * through api/ (the geometry never runs on an HTTP thread), submissions that join identical
 * jobs, waiters woken when a job ends or their deadline passes, cancellation, progress, and
 * the leases that let several daemons share one store.
 *
 * The queue is the store's (server/store.h, "The queue"), never this process's memory: a
 * worker claims the oldest queued job with a lease, a timer renews the leases of the jobs
 * running here every second (writing their progress, and reading whether they are to stop),
 * and requeues the jobs of daemons whose leases ran out.  So any daemon sharing the store can
 * take, poll, wait for or cancel any job, and none is lost when a daemon stops or dies.
 * Wake-ups: a job submitted here wakes a worker here; with a shared store, the store's events
 * (PostgreSQL LISTEN/NOTIFY) wake workers, waiters and cancels across daemons, and a poll every
 * second covers an event lost with a connection.
 *
 * Threads: every function is thread-safe.  engine_wait's wake callback runs on a worker, the
 * timer or the listener thread, never under the engine's lock, exactly once per registered
 * wait.
 */
#ifndef CELLAR_ENGINE_H
#define CELLAR_ENGINE_H

#include <stddef.h>

#include "server/metrics.h"
#include "server/store.h"

/* Part of every request hash: bump it when an algorithm's output changes, so that an upgrade
 * never serves a stale complex from the cache. */
#define CELLAR_ALGO_VERSION "cellar-algo-2"

typedef struct engine engine;
struct api_request;

typedef struct engine_cfg {
    store *st;       /* borrowed; outlives the engine */
    metrics *m;      /* borrowed */
    int workers;     /* worker threads */
    int job_threads; /* core threads per job */
    size_t queue_max;
    const char *spool_dir; /* borrowed: where results are written as they are made (NULL: the
                              system's temporary directory) */
    double job_ttl;        /* seconds a finished job is kept */
    size_t max_jobs;       /* finished jobs kept at most (0: no limit); pruned every 5 s */
    double lease;          /* seconds a claim holds without renewal (renewed every second) */
    const char *name;      /* borrowed: this daemon's name, the owner of the jobs it runs */
} engine_cfg;

enum {
    ENG_OK = 0,
    ENG_FULL = 1,
    ENG_DRAINING = 2,
    ENG_CACHED = 3,
    ENG_NOTFOUND = 4,
    ENG_ENDED = 5,
    ENG_ERR = -1
};

/* A job as one submission sees it, for responses. */
typedef struct job_info {
    char id[33], job[33], hash[65], kind[16];
    job_state state;
    double created, started, finished;
    char stage[32];
    double fraction;
    int error_status;
    char error[300];
    int attempts;                /* how often the job was started */
    char owner[STORE_OWNER_MAX]; /* the daemon that runs it or ran it last ("" never) */
} job_info;

/* SHA-256 of canon + "\n" + CELLAR_ALGO_VERSION as 64 lowercase hex digits (out: 65 bytes). */
void engine_hash(const char *canon, size_t len, char *out);

/* Starts the threads, after requeueing the running jobs that no live daemon holds (all of
 * them in a store only this daemon uses).  NULL with err on failure. */
engine *engine_start(const engine_cfg *cfg, char *err, size_t errlen);

/* Accepts a request (canon: its canonical JSON, borrowed; kind: its kind; hash: engine_hash of
 * canon; checked: the request as the intake parsed and checked it, taken, may be NULL): a new
 * job, or a new submission of the identical job queued or running (*coalesced = 1).  A worker
 * here that claims the job runs the checked request (engine.c, "checked requests"); any other
 * runs it from canon.  ENG_OK: sub (33 bytes) gets the submission's id, the client's to poll and
 * cancel with, and job (33 bytes) the job's; ENG_CACHED: the result is in the store (nothing was
 * made); ENG_FULL / ENG_DRAINING: refused; ENG_ERR: the store failed (err). */
int engine_submit(engine *e, const char *canon, size_t len, const char *kind, const char *hash,
                  struct api_request *checked, char *sub, char *job, int *coalesced, char *err,
                  size_t errlen);

/* Joins the queued or running job with this request hash, as engine_submit does for an
 * identical request (a new submission, its id in sub, the job's in job): ENG_OK, or
 * ENG_NOTFOUND when none is in flight (or the engine drains); ENG_ERR (err). */
int engine_join(engine *e, const char *hash, char *sub, char *job, char *err, size_t errlen);

/* Whether a new job would be refused now: ENG_FULL (the queue is full), ENG_DRAINING, or
 * ENG_OK (or ENG_ERR when the store cannot say: err). */
int engine_full(engine *e, char *err, size_t errlen);

/* The submission with this id: *out is its job as the submission sees it (the submission's id
 * and creation time; canceled when the submission was, whatever its job does).  ENG_OK,
 * ENG_NOTFOUND (no such submission), or ENG_ERR (the store failed: err). */
int engine_lookup(engine *e, const char *id, job_info *out, char *err, size_t errlen);

/* Cancels a submission; its job is canceled when no other submission of it is left (it stops
 * within about a second if running, on whichever daemon).  ENG_OK with *out the submission's
 * new state (canceled); ENG_ENDED when the job has ended or the submission was canceled
 * already (*out as it is); ENG_NOTFOUND; ENG_ERR (err). */
int engine_cancel(engine *e, const char *id, job_info *out, char *err, size_t errlen);

/* Calls wake(ctx) once, when job `job` ends or at `deadline` (Unix seconds), whichever is
 * first.  Returns 0 when registered, 1 when the job has ended already or the engine drains
 * (wake is then not called). */
int engine_wait(engine *e, const char *job, double deadline, void (*wake)(void *), void *ctx);

/* Stops taking jobs, waits up to timeout seconds for the running ones, then stops those still
 * running and gives them back to the queue (another daemon, or the next start, runs them),
 * and wakes every waiter. */
void engine_drain(engine *e, double timeout);
/* Joins the threads and frees the engine (after engine_drain). */
void engine_stop(engine *e);

/* The store's queued and running jobs (every daemon's), this engine's running ones, the
 * queue's capacity, whether it drains. */
void engine_gauges(engine *e, size_t *queued, size_t *running, size_t *running_here,
                   size_t *queue_max, int *draining);

/* The checked requests kept for jobs not yet claimed here, and their requests' bytes. */
void engine_checked_kept(engine *e, size_t *n, uint64_t *bytes);

/* Unix time now, in seconds. */
double engine_now(void);

#endif
