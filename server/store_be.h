/* store_be.h — the backend interface under the store's policy: what a backend (store_sqlite.c,
 * store_pg.c) gives store.c, which implements every operation of store.h once on top of it.
 *
 * A primitive is one statement (or one round trip) on the calling thread's connection: a job
 * row or a submission read or written, a chunk row, a results row, the totals.  Everything that
 * is decided from what the rows say lives in store.c: which statements make an operation and
 * in which transaction, reading a result's chunks back in order and checking each against its
 * digest, dropping a result that does not add up, the touch interval, eviction to the budget,
 * the join or make of job_submit, the last submission's cancel, the messages.  Where the two
 * databases genuinely differ, the primitive holds the difference and says so (row locks and
 * SKIP LOCKED against SQLite's single writer, NOTIFY, one statement against several).
 *
 * Errors: every primitive returns STORE_OK, STORE_NOTFOUND where it says so, or STORE_ERR
 * with a message "NAME WHERE: what the database said" in err (NAME the backend's, WHERE the
 * caller's).  A primitive never opens or ends a transaction unless it says so: the caller's
 * begin/commit frame it.
 *
 * Threads: conn() gives the calling thread's connection; a connection is used by its thread
 * only.  Ownership: strings passed in are borrowed; a store_job read is the caller's to clear.
 */
#ifndef CELLAR_STORE_BE_H
#define CELLAR_STORE_BE_H

#include "server/store.h"

/* A backend's connection of the calling thread (each backend defines the struct). */
typedef struct store_conn store_conn;

/* The frame of a transaction (begin):
 *   STORE_TX_READ   one snapshot for several reads (SQLite BEGIN; PostgreSQL REPEATABLE READ);
 *   STORE_TX_WRITE  several writes at once (SQLite BEGIN IMMEDIATE: the write lock up front;
 *                   PostgreSQL BEGIN, rows locked as they are written);
 *   STORE_TX_ONE    the one write statement that follows, atomic by itself: SQLite still takes
 *                   the write lock up front (BEGIN IMMEDIATE, never a failed upgrade of a read
 *                   lock), PostgreSQL runs it in autocommit (begin and commit cost no round
 *                   trip: the hot paths job_renew and the touch of a read stay one). */
typedef enum { STORE_TX_READ, STORE_TX_WRITE, STORE_TX_ONE } store_tx;

/* job_submit's job_write lost a race for the unique index jobs_active_hash against another
 * daemon's submit (PostgreSQL only; SQLite's single writer cannot): roll back and try again. */
#define STORE_RACE 100

/* A change of one running job's row (job_set), by its owner. */
typedef enum {
    STORE_SET_RENEW,   /* lease until `until`, stage and fraction; *cancel gets its flag */
    STORE_SET_FINISH,  /* state, finished = when, error_status and error (FAILED), no request */
    STORE_SET_RELEASE, /* back to the queue (canceled at `when` when asked to stop) */
} store_set_kind;

typedef struct store_set {
    store_set_kind kind;
    const char *id, *owner;
    double until, fraction, when; /* until: RENEW; when: FINISH, RELEASE */
    const char *stage;            /* RENEW; may be NULL */
    job_state state;              /* FINISH */
    int error_status;             /* FINISH, FAILED only */
    const char *error;            /* FINISH, FAILED only; may be NULL */
} store_set;

/* A chunk row as read: its offset, body and stored digest (NULL or not 32 bytes: none).  The
 * pointers are valid during the callback only.  A nonzero return stops the reading, and the
 * primitive returns it. */
typedef int (*store_chunk_fn)(void *ctx, uint64_t off, const void *body, size_t n, const void *sha,
                              size_t shalen);

/* What the consistency check counts (recount): the totals row, the table's count and sum, the
 * results whose chunks do not add up to their size, the chunks that do not start where the
 * one before ends, and (PostgreSQL, where no put leaves any) the chunks of no result; -1 for a
 * count a backend does not make. */
typedef struct store_recount {
    long long tot_count, tot_bytes, count, bytes, bad_size, bad_off, orphans;
} store_recount;

/* The recount's statement up to bad_off, the same SQL in both backends: the totals row (t),
 * the table's count and sum, the results whose chunks do not add up to their size, the chunks
 * that do not start where the one before ends.  A backend adds its further columns and
 * " FROM result_totals t WHERE t.id = 0". */
#define STORE_SQL_RECOUNT                                                                          \
    "SELECT t.count, t.bytes, (SELECT count(*) FROM results),"                                     \
    " (SELECT coalesce(sum(bytes), 0) FROM results),"                                              \
    " (SELECT count(*) FROM results r WHERE r.bytes <> (SELECT coalesce(sum(length(c.body)), 0)"   \
    "  FROM result_chunks c WHERE c.hash = r.hash)),"                                              \
    " (SELECT count(*) FROM (SELECT off, sum(length(body)) OVER (PARTITION BY hash ORDER BY off"   \
    "  ROWS UNBOUNDED PRECEDING) - length(body) AS start FROM result_chunks"                       \
    "  WHERE hash IN (SELECT hash FROM results)) x WHERE off <> start)"

typedef struct store_be_ops {
    const char *name; /* "sqlite", "postgresql": the first word of every message */

    /* ---- connections, transactions, events ---- */
    store_conn *(*conn)(store *s, char *err, size_t errlen);
    int (*begin)(store_conn *c, store_tx tx, const char *where, char *err, size_t errlen);
    int (*commit)(store_conn *c, const char *where, char *err, size_t errlen);
    void (*rollback)(store_conn *c); /* of the open transaction, if any (best effort) */
    /* A last_used stamp (SQLite: strictly after every stamp this store handed out). */
    double (*stamp)(store *s);
    /* Tells the other daemons of ev about job id ("" for STORE_EV_QUEUED), delivered at the
     * commit of the caller's transaction (PostgreSQL's NOTIFY).  NULL: one daemon per store. */
    int (*notify)(store_conn *c, store_ev ev, const char *id, char *err, size_t errlen);
    int (*wait_event)(store *s, double timeout, store_ev *ev, char *id, char *err, size_t errlen);

    /* ---- jobs and submissions ---- */
    /* Inserts j (fields checked by the caller) and its first submission, canceled at
     * j->finished when j is CANCELED.  STORE_RACE: see above. */
    int (*job_write)(store_conn *c, const store_job *j, const char *where, char *err,
                     size_t errlen);
    /* Reads job id (text fields checked to fit; state as stored: the caller checks it). */
    int (*job_read)(store_conn *c, const char *id, store_job *out, char *err, size_t errlen);
    /* The id (33 bytes) of the queued or running job of hash not being canceled, its row
     * locked to the transaction's end where rows lock (PostgreSQL FOR UPDATE): a cancel of its
     * last submission waits for the join.  STORE_NOTFOUND when none. */
    int (*job_active)(store_conn *c, const char *hash, char *id, char *err, size_t errlen);
    /* Claims the oldest queued job for owner (RUNNING, started, lease until, attempts + 1)
     * and reads it into *out, as one atomic step of its own (not in a caller's transaction):
     * PostgreSQL one UPDATE ... FOR UPDATE SKIP LOCKED RETURNING the row (one round trip,
     * claims of other daemons skipped, not waited for); SQLite its own write transaction.
     * STORE_NOTFOUND when none is queued. */
    int (*job_claim)(store_conn *c, const char *owner, double now, double until, store_job *out,
                     char *err, size_t errlen);
    /* One change of owner's running job id (see store_set): STORE_NOTFOUND when it is no
     * longer owner's. */
    int (*job_set)(store_conn *c, const store_set *a, int *cancel, const char *where, char *err,
                   size_t errlen);
    /* Moves the running jobs whose lease ended before now (every one when all): canceled when
     * asked to stop, failed with error msg when started max_attempts times, else queued.  *n
     * gets how many; with notify set, ended(ctx, id) is called for each one that ended and
     * *queued gets whether any was queued (else neither is made). */
    int (*jobs_requeue)(store_conn *c, double now, int all, int max_attempts, const char *msg,
                        int (*ended)(void *ctx, const char *id), void *ctx, size_t *n, int *queued,
                        char *err, size_t errlen);
    /* The counts of queued and running jobs (running may be NULL: the queued alone). */
    int (*job_counts)(store_conn *c, size_t *queued, size_t *running, const char *where, char *err,
                      size_t errlen);
    /* Deletes the finished jobs that ended before `before` or past the `keep` newest (0: no
     * limit), with their submissions; *n gets how many. */
    int (*jobs_prune)(store_conn *c, double before, size_t keep, size_t *n, char *err,
                      size_t errlen);
    /* Inserts a submission of job sub->job (STORE_NOTFOUND, or STORE_ERR, when no such job). */
    int (*sub_write)(store_conn *c, const store_sub *sub, const char *where, char *err,
                     size_t errlen);
    /* Reads submission id; with lock_job, its job's row locked too (PostgreSQL FOR UPDATE:
     * see job_active). */
    int (*sub_read)(store_conn *c, const char *id, int lock_job, store_sub *out, char *err,
                    size_t errlen);
    /* Marks submission id canceled at when: *changed whether it was not already. */
    int (*sub_cancel)(store_conn *c, const char *id, double when, int *changed, char *err,
                      size_t errlen);
    /* When job has no submission left that is not canceled: cancels it at when if queued
     * (*effect STORE_JOB_CANCELED), asks it to stop if running (STORE_JOB_STOPPING); else
     * *effect STORE_JOB_KEPT.  PostgreSQL: one statement; SQLite: a count and two updates. */
    int (*job_last_sub)(store_conn *c, const char *job, double when, int *effect, char *err,
                        size_t errlen);

    /* ---- results ---- */
    /* A result's size, last mark and job (33 bytes; may be NULL): STORE_NOTFOUND when none. */
    int (*result_head)(store_conn *c, const char *hash, uint64_t *bytes, double *used, char *job,
                       const char *where, char *err, size_t errlen);
    /* Upserts the results row (never a delete and insert: the totals' triggers see it). */
    int (*result_row)(store_conn *c, const char *hash, uint64_t bytes, double stamp,
                      const char *job, char *err, size_t errlen);
    int (*result_delete)(store_conn *c, const char *hash, const char *where, char *err,
                         size_t errlen);
    int (*result_touch)(store_conn *c, const char *hash, double stamp, const char *where, char *err,
                        size_t errlen);
    /* Deletes the chunks of hash that have no results row (a put's that failed part-way);
     * NULL where a put is one transaction and leaves none (PostgreSQL). */
    int (*chunks_forget)(store_conn *c, const char *hash, const char *where, char *err,
                         size_t errlen);
    /* Upserts a chunk with its SHA-256. */
    int (*chunk_put)(store_conn *c, const char *hash, uint64_t off, const void *data, size_t n,
                     const unsigned char sha[32], char *err, size_t errlen);
    /* How many chunks hash has and their total bytes. */
    int (*chunks_sum)(store_conn *c, const char *hash, uint64_t *count, uint64_t *bytes, char *err,
                      size_t errlen);
    /* Calls fn on the chunks of hash in order of offset (at < 0), or on the one chunk that
     * starts at or before byte at (STORE_NOTFOUND when none). */
    int (*chunks_read)(store_conn *c, const char *hash, long long at, store_chunk_fn fn, void *ctx,
                       const char *where, char *err, size_t errlen);
    /* The totals row. */
    int (*totals)(store_conn *c, size_t *count, uint64_t *bytes, const char *where, char *err,
                  size_t errlen);
    /* Deletes the least recently used result but keep: *gone 0 when keep is alone. */
    int (*evict_one)(store_conn *c, const char *keep, int *gone, char *err, size_t errlen);

    /* ---- the check, the probe, the end ---- */
    /* The database's own check (SQLite integrity_check), NULL when none. */
    int (*integrity)(store_conn *c, char *err, size_t errlen);
    int (*recount)(store_conn *c, store_recount *out, char *err, size_t errlen);
    /* Counts the chunks of the results (*all) and those that do not match their digest
     * (*bad).  PostgreSQL hashes in the server (sha256(), no body crosses the wire); SQLite,
     * which has no SHA-256, in C (store_digest_ok). */
    int (*chunks_digests)(store_conn *c, long long *all, long long *bad, char *err, size_t errlen);
    /* A small write, rolled back or rewritten as it was, that waits at most about a second
     * for a lock (the readiness probe). */
    int (*probe)(store_conn *c, char *err, size_t errlen);
    void (*close)(store *s);
} store_be_ops;

/* The initializers of a backend's store_be_ops for every primitive but name and the optional
 * ones (notify, wait_event, chunks_forget, integrity), from its functions named P_conn,
 * P_begin, ... (P the prefix given). */
#define STORE_BE_PRIMITIVES(P)                                                                     \
    .conn = P##_conn, .begin = P##_begin, .commit = P##_commit, .rollback = P##_rollback,          \
    .stamp = P##_stamp, .job_write = P##_job_write, .job_read = P##_job_read,                      \
    .job_active = P##_job_active, .job_claim = P##_job_claim, .job_set = P##_job_set,              \
    .jobs_requeue = P##_jobs_requeue, .job_counts = P##_job_counts, .jobs_prune = P##_jobs_prune,  \
    .sub_write = P##_sub_write, .sub_read = P##_sub_read, .sub_cancel = P##_sub_cancel,            \
    .job_last_sub = P##_job_last_sub, .result_head = P##_result_head,                              \
    .result_row = P##_result_row, .result_delete = P##_result_delete,                              \
    .result_touch = P##_result_touch, .chunk_put = P##_chunk_put, .chunks_sum = P##_chunks_sum,    \
    .chunks_read = P##_chunks_read, .totals = P##_totals, .evict_one = P##_evict_one,              \
    .recount = P##_recount, .chunks_digests = P##_chunks_digests, .probe = P##_probe,              \
    .close = P##_close

/* The operations of store.h over s->be: what a backend's open sets s->ops to (the second
 * with wait_event, for a store other daemons share). */
extern const store_ops store_ops_local, store_ops_shared;

/* The SHA-256 of a chunk (all zero in the impossible case OpenSSL fails). */
void store_digest(const void *data, size_t n, unsigned char out[32]);

/* Whether sha (shalen bytes; NULL: none) is the digest of body[0..n). */
int store_digest_ok(const void *body, size_t n, const void *sha, size_t shalen);

#endif
