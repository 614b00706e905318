/* store.h — where jobs and results live: one small interface of function pointers with two
 * backends, SQLite (server/store_sqlite.c: one file, one daemon) and PostgreSQL
 * (server/store_pg.c: one database shared by many daemons), so the rest of the daemon does not
 * know which it talks to.  The operations are implemented once, in server/store.c (the policy:
 * transactions, checks of what is read back, eviction, the queue's rules), over a narrow
 * interface of primitives that each backend implements (server/store_be.h).
 *
 * Jobs: one row per accepted job, written before the client hears of it, and the queue itself:
 * daemons claim jobs from the store with a lease (see "The queue" below), so that any daemon
 * sharing the store can run, poll, wait for or cancel any job, and a restart or the death of a
 * daemon loses none.  Submissions: one row per POST, each with the id its client polls and
 * cancels with.
 * Results: content-addressed by the request hash (64 hex digits of SHA-256), the result JSON
 * as bytes, with a total size budget enforced by least-recently-used eviction.  A result is
 * kept in chunks of at most STORE_CHUNK bytes, so that neither writing one (result_put_file,
 * from a spool file) nor reading one (result_size, then result_chunk) needs it whole in memory.
 *
 * Threads: every function may be called from any thread at any time; the backend takes care
 * of its own connections and locks (one connection per thread).
 * Errors: 0 on success, STORE_NOTFOUND when the row is absent, STORE_ERR on failure with a
 * message in err (errlen bytes), STORE_DAMAGED for a result that failed its check on reading.
 * Strings passed in are borrowed; strings and buffers returned are malloc'd and the caller frees
 * them (store_job_clear for a store_job).
 */
#ifndef CELLAR_STORE_H
#define CELLAR_STORE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* STORE_DAMAGED: a result read back does not match what was stored (a chunk's digest, or
 * chunks that do not add up to its size); the store has dropped it, so it can be made again.
 * STORE_FULL: job_submit made no job, the queue being full.  STORE_CACHED: job_submit made no
 * job, the result being in the cache already. */
enum {
    STORE_OK = 0,
    STORE_NOTFOUND = 1,
    STORE_FULL = 2,
    STORE_CACHED = 3,
    STORE_ERR = -1,
    STORE_DAMAGED = -2
};

/* The largest chunk a result is written in (the last may be shorter). */
#define STORE_CHUNK ((size_t)1 << 20)

typedef enum job_state {
    JOB_QUEUED = 0,
    JOB_RUNNING = 1,
    JOB_DONE = 2,
    JOB_FAILED = 3,
    JOB_CANCELED = 4
} job_state;

/* "queued", "running", "done", "failed", "canceled" */
const char *job_state_name(job_state s);

#define STORE_OWNER_MAX 64 /* a daemon's name, NUL included */

typedef struct store_job {
    char id[33];   /* 32 hex digits */
    char hash[65]; /* request hash, 64 hex digits */
    char kind[16]; /* "lines", "svg", "solids", ... */
    job_state state;
    double created, started, finished; /* Unix seconds; 0 when not yet */
    int error_status;                  /* HTTP status of a failed job (422, 500, ...), else 0 */
    char *error;                       /* message of a failed job, or NULL */
    char *request; /* the canonical request JSON (needed to run it; dropped when it ends) */
    size_t request_len;
    /* read back (job_insert ignores them): */
    int active_subs;             /* its submissions not canceled */
    char owner[STORE_OWNER_MAX]; /* the daemon running it, or that ran it last ("" never) */
    double lease_until;          /* running: the owner's lease ends then (renewed as it runs) */
    int attempts;                /* how often it was started */
    int cancel;                  /* running: every submission canceled, the owner must stop */
    char stage[32];              /* running: progress as its owner last wrote it */
    double fraction;
} store_job;

void store_job_clear(store_job *j); /* frees error and request, zeroes the struct */

/* A submission: one client's POST.  Identical requests share one job (the computation), but
 * each submission has its own id to poll and to cancel with; a job is canceled only when every
 * submission that joined it has been.  The first submission of a job has the job's id. */
typedef struct store_sub {
    char id[33], job[33];
    double created, canceled; /* Unix seconds; canceled 0 when not */
} store_sub;

/* What sub_cancel did to the submission's job. */
enum { STORE_JOB_KEPT = 0, STORE_JOB_CANCELED = 1, STORE_JOB_STOPPING = 2 };

/* An event from another daemon sharing the store (wait_event): a job was queued (id ""), a job
 * ended, or a running job is to stop; STORE_EV_RESET when events may have been lost (the
 * connection that listens was lost and made anew): look at everything again. */
typedef enum {
    STORE_EV_NONE,
    STORE_EV_QUEUED,
    STORE_EV_ENDED,
    STORE_EV_CANCEL,
    STORE_EV_RESET
} store_ev;

typedef struct store store;

/* The queue.  A job is QUEUED when made, RUNNING once a daemon claims it with a lease (owner,
 * lease_until), which that daemon renews while it runs the job; it ends DONE, FAILED or
 * CANCELED by its owner (job_finish), or CANCELED when every submission of a queued job is
 * canceled.  A daemon that dies leaves its jobs' leases to expire: jobs_requeue puts them back
 * in the queue (or fails them after STORE_MAX_ATTEMPTS starts), so no accepted job is lost and
 * none runs twice while its lease is live.  Identical requests share a job: at most one job per
 * request hash is queued or running (a unique index), and job_submit joins it. */
#define STORE_MAX_ATTEMPTS 3

typedef struct store_ops {
    /* Makes a job and its first submission from j (id, hash, kind, created, request; the
     * submission's id is j->id), or joins the queued or running job with j->hash by adding
     * the submission j->id to it (*joined = 1), in one transaction: job_id (33 bytes) gets
     * the job's id.  STORE_CACHED when a result with j->hash is stored (nothing is made);
     * STORE_FULL when no job could be joined and queue_max jobs are queued already (0: no
     * limit); with join_only, STORE_NOTFOUND instead of making a job. */
    int (*job_submit)(store *s, const store_job *j, size_t queue_max, int join_only, char *job_id,
                      int *joined, char *err, size_t errlen);
    /* Claims the oldest queued job for owner: RUNNING, started now, attempts + 1, leased
     * until now + lease (*out, request included).  STORE_NOTFOUND when none is queued. */
    int (*job_claim)(store *s, const char *owner, double now, double lease, store_job *out,
                     char *err, size_t errlen);
    /* Renews owner's lease of running job id to now + lease and writes its progress; *cancel
     * gets whether it is to stop.  STORE_NOTFOUND when the job is no longer owner's (its
     * lease ran out and another took it, or it ended). */
    int (*job_renew)(store *s, const char *id, const char *owner, double now, double lease,
                     const char *stage, double fraction, int *cancel, char *err, size_t errlen);
    /* Ends owner's running job id: DONE, FAILED (error_status, error) or CANCELED at `when`;
     * it drops its request.  STORE_NOTFOUND when the job is no longer owner's. */
    int (*job_finish)(store *s, const char *id, const char *owner, job_state st, double when,
                      int error_status, const char *error, char *err, size_t errlen);
    /* Gives owner's running job id back to the queue (a drain that stops it unfinished). */
    int (*job_release)(store *s, const char *id, const char *owner, char *err, size_t errlen);
    /* Requeues the running jobs whose lease ended before now (all running jobs when `all`: a
     * store no other daemon can use, at start), canceling those asked to stop and failing
     * those started STORE_MAX_ATTEMPTS times; *n gets how many it moved. */
    int (*jobs_requeue)(store *s, double now, int all, size_t *n, char *err, size_t errlen);
    /* Inserts a job as given, in any state, with its first submission (canceled when the job
     * is inserted canceled): for tools and tests; the daemon uses job_submit. */
    int (*job_insert)(store *s, const store_job *j, char *err, size_t errlen);
    /* Reads one job (request, active_subs and the queue's fields included). */
    int (*job_get)(store *s, const char *id, store_job *out, char *err, size_t errlen);
    /* How many jobs are queued and running, in the whole store. */
    int (*job_counts)(store *s, size_t *queued, size_t *running, char *err, size_t errlen);
    /* Deletes finished jobs (DONE, FAILED, CANCELED) that ended before `before`, and those
     * past the `keep` most recently finished (0: no limit), with their submissions; returns
     * how many jobs in *n. */
    int (*jobs_prune)(store *s, double before, size_t keep, size_t *n, char *err, size_t errlen);
    /* Reads one submission. */
    int (*sub_get)(store *s, const char *id, store_sub *out, char *err, size_t errlen);
    /* Marks a submission canceled at `when`: *changed = 1 when this call canceled it, 0 when
     * it was canceled already (its time stays); STORE_NOTFOUND when there is no such one.
     * When it was its job's last submission not canceled, in the same transaction, a queued
     * job is canceled (*job = STORE_JOB_CANCELED) and a running one asked to stop
     * (STORE_JOB_STOPPING); else *job = STORE_JOB_KEPT. */
    int (*sub_cancel)(store *s, const char *id, double when, int *changed, int *job, char *err,
                      size_t errlen);
    /* Waits up to timeout seconds for an event of another daemon: *ev (STORE_EV_NONE when
     * none came), id the job's (33 bytes).  NULL in a backend that only one daemon uses. */
    int (*wait_event)(store *s, double timeout, store_ev *ev, char *id, char *err, size_t errlen);
    /* Stores a result (replacing one with the same hash), then evicts least recently used
     * results until the total is within the budget (the new one is never evicted). */
    int (*result_put)(store *s, const char *hash, const char *body, size_t len, char *err,
                      size_t errlen);
    /* The same with the body read from f: its next len bytes, made by job `job` (its id, kept
     * with the result; may be NULL) (a shorter file is an error,
     * and nothing is stored).  The result appears whole or not at all: readers do not see
     * it until every chunk is written. */
    int (*result_put_file)(store *s, const char *hash, const char *job, FILE *f, uint64_t len,
                           char *err, size_t errlen);
    /* Reads a result whole and marks it used now.  Every chunk is checked against the digest
     * stored with it: a result that does not match, or whose chunks do not add up to its size,
     * is dropped and reported STORE_DAMAGED, never returned. */
    int (*result_get)(store *s, const char *hash, char **body, size_t *len, char *err,
                      size_t errlen);
    /* A result's size in bytes, marking it used now (as result_get); its body is then read
     * with result_chunk from position 0 to the size.  job (33 bytes, may be NULL) gets the id
     * of the job that made it ("" when not known). */
    int (*result_size)(store *s, const char *hash, uint64_t *bytes, char *job, char *err,
                       size_t errlen);
    /* The chunk of a result that holds byte pos: *data (malloc'd, NUL-terminated past its
     * length) of *len bytes starting at byte *start <= pos.  STORE_NOTFOUND when the result
     * or that chunk is gone (evicted since result_size: a reader then stops with an error;
     * the bytes it had were right, since a hash fixes its content).  The chunk is checked
     * against its digest: STORE_DAMAGED (and the result dropped) when it does not match. */
    int (*result_chunk)(store *s, const char *hash, uint64_t pos, char **data, size_t *len,
                        uint64_t *start, char *err, size_t errlen);
    /* Whether a result exists, without reading it or marking it. */
    int (*result_exists)(store *s, const char *hash, char *err, size_t errlen);
    /* Number of results and their total bytes. */
    int (*result_stats)(store *s, size_t *count, uint64_t *bytes, char *err, size_t errlen);
    /* A consistency check of the backend (the totals, the chunks' tiling and digests, and the
     * backend's own check).  Reads everything: for tests and tools, not for serving. */
    int (*check)(store *s, char *err, size_t errlen);
    /* Whether the store takes writes now (a small write, rolled back): the readiness
     * probe's question. */
    int (*writable)(store *s, char *err, size_t errlen);
    /* Closes every connection and frees s. */
    void (*close)(store *s);
} store_ops;

struct store {
    const store_ops *ops;
    int shared; /* other daemons may use the same store (PostgreSQL): wait_event is set */
    /* the rest is the store's own (store.c and its backends, server/store_be.h): */
    const struct store_be_ops *be; /* the backend's primitives, under the policy of store.c */
    uint64_t budget;               /* result bytes allowed; 0: unlimited */
    double touch_seconds;          /* result_get leaves marks younger than this */
    uint64_t put_batch;            /* bytes of chunks a put writes per transaction; 0: all in one */
};

/* store_sqlite_open flags: STORE_OPEN_INIT makes a store in an empty file or adds the store's
 * tables to a SQLite database of something else (without it both are refused: a file
 * truncated to nothing, or the wrong --db, must not quietly become an empty store). */
#define STORE_OPEN_INIT 1

/* Opens (creating or migrating) the SQLite store at path with a result budget in bytes
 * (0: unlimited).  A file that does not exist is made; the file is checked at open (SQLite's
 * quick_check), and a damaged one is refused with a message saying what to do.
 * touch_seconds: result_get marks a result used only when its mark is older than this (0: on
 * every read; the daemon uses 10, so a hot result does not take the write lock on every
 * read).  flags: STORE_OPEN_INIT or 0.  Returns NULL with a message in err on failure. */
store *store_sqlite_open(const char *path, uint64_t budget_bytes, double touch_seconds, int flags,
                         char *err, size_t errlen);

/* Opens (creating or migrating) the PostgreSQL store at conninfo (a postgresql:// or
 * postgres:// URI, or libpq's key=value form), as store_sqlite_open; several daemons may
 * share it.  A database that cannot be reached is waited for, 30 s at most, then an error
 * (later losses are retried: an op fails while the database is away, and the next one
 * connects again). */
store *store_pg_open(const char *conninfo, uint64_t budget_bytes, double touch_seconds, int flags,
                     char *err, size_t errlen);

/* store_pg_open for a PostgreSQL URI (postgresql:// or postgres://), else store_sqlite_open. */
store *store_open(const char *db, uint64_t budget_bytes, double touch_seconds, int flags, char *err,
                  size_t errlen);

#endif
