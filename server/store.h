/* store.h — where jobs and results live: one small interface of function pointers, so the
 * backend can change (SQLite today, in server/store_sqlite.c; PostgreSQL for scale-out later)
 * without the rest of the daemon knowing.
 *
 * Jobs: one row per accepted job, written when it is accepted, updated when it starts and
 * when it ends, so that a restart can resume every job that was queued or running.
 * Results: content-addressed by the request hash (64 hex digits of SHA-256), the result JSON
 * as bytes, with a total size budget enforced by least-recently-used eviction.  A result is
 * kept in chunks of at most STORE_CHUNK bytes, so that neither writing one (result_put_file,
 * from a spool file) nor reading one (result_size, then result_chunk) needs it whole in memory.
 *
 * Threads: every function may be called from any thread at any time; the backend takes care
 * of its own connections and locks (SQLite: one connection per thread).
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
 * chunks that do not add up to its size); the store has dropped it, so it can be made again. */
enum { STORE_OK = 0, STORE_NOTFOUND = 1, STORE_ERR = -1, STORE_DAMAGED = -2 };

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

typedef struct store_job {
    char id[33];   /* 32 hex digits */
    char hash[65]; /* request hash, 64 hex digits */
    char kind[16]; /* "lines", "svg", "solids", ... */
    job_state state;
    double created, started, finished; /* Unix seconds; 0 when not yet */
    int error_status;                  /* HTTP status of a failed job (422, 500, ...), else 0 */
    char *error;                       /* message of a failed job, or NULL */
    char *request; /* the canonical request JSON (needed to resume after a restart) */
    size_t request_len;
    int active_subs; /* read back: its submissions not canceled (job_insert ignores it) */
} store_job;

/* A submission: one client's POST.  Identical requests share one job (the computation), but
 * each submission has its own id to poll and to cancel with; a job is canceled only when every
 * submission that joined it has been.  The first submission of a job has the job's id (and
 * job_insert makes it); a request that joins a job in flight adds one with sub_insert. */
typedef struct store_sub {
    char id[33], job[33];
    double created, canceled; /* Unix seconds; canceled 0 when not */
} store_sub;

void store_job_clear(store_job *j); /* frees error and request, zeroes the struct */

typedef struct store store;

typedef struct store_ops {
    /* Inserts a new job (state, times and request as given) and its first submission (the
     * job's id, created when the job is, canceled when the job is inserted canceled). */
    int (*job_insert)(store *s, const store_job *j, char *err, size_t errlen);
    /* Sets state and the matching time (started for RUNNING, finished for the end states);
     * error_status/error only for JOB_FAILED (error may be NULL otherwise).  A job set to an
     * end state (DONE, FAILED, CANCELED) loses its request: it is never run again. */
    int (*job_set_state)(store *s, const char *id, job_state st, double when, int error_status,
                         const char *error, char *err, size_t errlen);
    /* Reads one job (request included, and active_subs). */
    int (*job_get)(store *s, const char *id, store_job *out, char *err, size_t errlen);
    /* Calls fn for every job in state QUEUED or RUNNING, oldest first (request included;
     * the job is cleared after fn returns).  fn returns non-zero to stop early. */
    int (*jobs_unfinished)(store *s, int (*fn)(void *ctx, store_job *j), void *ctx, char *err,
                           size_t errlen);
    /* Deletes finished jobs (DONE, FAILED, CANCELED) that ended before `before`, and those
     * past the `keep` most recently finished (0: no limit), with their submissions; returns
     * how many jobs in *n.  (A job
     * that ends keeps no request: job_set_state drops it, so the jobs on disk are bounded by
     * the queued and running ones' bodies plus `keep` small rows.) */
    int (*jobs_prune)(store *s, double before, size_t keep, size_t *n, char *err, size_t errlen);
    /* Adds a submission to job sub->job, which must exist (else STORE_NOTFOUND). */
    int (*sub_insert)(store *s, const store_sub *sub, char *err, size_t errlen);
    /* Reads one submission. */
    int (*sub_get)(store *s, const char *id, store_sub *out, char *err, size_t errlen);
    /* Marks a submission canceled at `when`: *changed = 1 when this call canceled it, 0 when
     * it was canceled already (its time stays); STORE_NOTFOUND when there is no such one. */
    int (*sub_cancel)(store *s, const char *id, double when, int *changed, char *err,
                      size_t errlen);
    /* Stores a result (replacing one with the same hash), then evicts least recently used
     * results until the total is within the budget (the new one is never evicted). */
    int (*result_put)(store *s, const char *hash, const char *body, size_t len, char *err,
                      size_t errlen);
    /* The same with the body read from f: its next len bytes (a shorter file is an error,
     * and nothing is stored).  The result appears whole or not at all: readers do not see
     * it until every chunk is written, yet the writer does not hold the database's write
     * lock for the whole copy. */
    int (*result_put_file)(store *s, const char *hash, FILE *f, uint64_t len, char *err,
                           size_t errlen);
    /* Reads a result whole and marks it used now.  Every chunk is checked against the digest
     * stored with it: a result that does not match, or whose chunks do not add up to its size,
     * is dropped and reported STORE_DAMAGED, never returned. */
    int (*result_get)(store *s, const char *hash, char **body, size_t *len, char *err,
                      size_t errlen);
    /* A result's size in bytes, marking it used now (as result_get); its body is then read
     * with result_chunk from position 0 to the size. */
    int (*result_size)(store *s, const char *hash, uint64_t *bytes, char *err, size_t errlen);
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
    /* A consistency check of the backend (SQLite: PRAGMA integrity_check, the totals, the
     * chunks' tiling and digests).  Reads everything: for tests and tools, not for serving. */
    int (*check)(store *s, char *err, size_t errlen);
    /* Whether the store takes writes now (a small write, rolled into the database): the
     * readiness probe's question. */
    int (*writable)(store *s, char *err, size_t errlen);
    /* Closes every connection and frees s. */
    void (*close)(store *s);
} store_ops;

struct store {
    const store_ops *ops;
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

#endif
