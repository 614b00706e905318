/* engine.h — the job engine: a bounded queue, a pool of worker threads that run jobs through
 * api/ (the geometry never runs on an HTTP thread), identical requests coalesced, waiters that
 * are woken when a job ends or their deadline passes, and recovery of unfinished jobs from the
 * store at start.
 *
 * Jobs are "live" (in memory) while queued or running, and a little after, while someone holds
 * a reference; the store has every job.  A job is written to the store before it is queued, so
 * an accepted job is never lost: after a crash, engine_start() queues again every job the store
 * has as queued or running.
 *
 * Threads: every function is thread-safe.  engine_wait's wake callback runs on a worker or the
 * timer thread, never under the engine's lock, exactly once per registered wait.
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
typedef struct job job;

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

/* A snapshot of a job, for responses. */
typedef struct job_info {
    char id[33], hash[65], kind[16];
    job_state state;
    double created, started, finished;
    char stage[32];
    double fraction;
    int error_status;
    char error[300];
} job_info;

/* SHA-256 of canon + "\n" + CELLAR_ALGO_VERSION as 64 lowercase hex digits (out: 65 bytes). */
void engine_hash(const char *canon, size_t len, char *out);

/* Starts the threads and queues the store's unfinished jobs.  NULL with err on failure. */
engine *engine_start(const engine_cfg *cfg, char *err, size_t errlen);

/* Accepts a request (canon: its canonical JSON, borrowed; kind: its kind; hash: engine_hash of
 * canon).  ENG_OK: *out is a referenced job (new, or an identical one in flight: *coalesced
 * = 1), and sub (33 bytes) the id of this submission, the client's to poll and cancel with
 * (a new job's own id; a new one for a submission that joins a job); ENG_CACHED: an identical job
 * ended while we looked, its result is in the store; ENG_FULL / ENG_DRAINING: refused; ENG_ERR: the
 * store failed (err).  Identical requests run once: the caller looks in the cache first, this looks
 * for a job in flight, then in the cache again (a worker stores its result before its job leaves
 * the live list). */
int engine_submit(engine *e, const char *canon, size_t len, const char *kind, const char *hash,
                  job **out, char *sub, int *coalesced, char *err, size_t errlen);

/* Joins the queued or running job with this request hash, as engine_submit does for an
 * identical request (a new submission, its id in sub): ENG_OK with *out referenced, or
 * ENG_NOTFOUND when none is in flight (or the engine drains); ENG_ERR (err). */
int engine_join(engine *e, const char *hash, job **out, char *sub, char *err, size_t errlen);

/* Whether a new job would be refused now: ENG_FULL (the queue is full), ENG_DRAINING, or
 * ENG_OK. */
int engine_full(engine *e);

/* The live job with this job id, referenced, or NULL (then look in the store). */
job *engine_find(engine *e, const char *id);
/* Drops a reference taken by engine_submit or engine_find. */
void engine_release(engine *e, job *j);
void engine_info(engine *e, job *j, job_info *out);
/* The result of a job that ended DONE (borrowed while the reference is held), else NULL; NULL
 * too when the result was larger than a store chunk (then read it from the store). */
const char *engine_result(engine *e, job *j, size_t *len);

/* The submission with this id: *out is its job as the submission sees it (the submission's
 * id and creation time; canceled when the submission was, whatever its job does), and *live
 * the job, referenced, when it is live (else NULL).  ENG_OK, ENG_NOTFOUND (no such
 * submission), or ENG_ERR (the store failed: err). */
int engine_lookup(engine *e, const char *id, job_info *out, job **live, char *err, size_t errlen);

/* Cancels a submission; its job is canceled when no other submission of it is left (it stops
 * within about a second if running).  ENG_OK with *out the submission's new state (canceled);
 * ENG_ENDED when the job has ended or the submission was canceled already (*out as it is);
 * ENG_NOTFOUND; ENG_ERR (err). */
int engine_cancel(engine *e, const char *id, job_info *out, char *err, size_t errlen);

/* Calls wake(ctx) once, when j ends or at `deadline` (Unix seconds), whichever is first.
 * Returns 0 when registered, 1 when j has already ended (wake is then not called). */
int engine_wait(engine *e, job *j, double deadline, void (*wake)(void *), void *ctx);

/* Stops taking and starting jobs, waits up to timeout seconds for the running ones (those
 * still running then stay "running" in the store and are resumed by the next start), and
 * wakes every waiter.  Queued jobs stay queued in the store. */
void engine_drain(engine *e, double timeout);
/* Joins the threads and frees the engine (after engine_drain). */
void engine_stop(engine *e);

void engine_gauges(engine *e, size_t *queued, size_t *running, size_t *queue_max, int *draining);

/* Unix time now, in seconds. */
double engine_now(void);

#endif
