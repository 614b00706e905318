/* store_sqlite.c — the SQLite backend of the store (server/store.h): one database file in WAL
 * mode holding the jobs and the result cache.
 *
 * Schema (PRAGMA user_version is the number of migrations applied; sq_migrations below):
 *   jobs(id TEXT PRIMARY KEY, hash, kind, state, created, started, finished, error_status,
 *        error, request BLOB)                                   index jobs_state(state)
 *   results(hash TEXT PRIMARY KEY, bytes, created, last_used)   index results_last_used
 *   result_chunks(hash, off, body BLOB, PRIMARY KEY(hash, off)) a result's bytes from off on
 *   result_totals(id = 0, count, bytes)                         one row
 *   subs(id TEXT PRIMARY KEY, job, created, canceled)           index subs_job(job)
 * A job's submissions go with it (a trigger deletes them when it is pruned); the first has
 * the job's own id.
 * Times are Unix seconds as REAL, NULL for "not yet" (0 in a store_job); error_status and
 * error are NULL unless the job failed.
 *
 * Why the bodies have a table of their own: SQLite rewrites a whole record on any UPDATE, so
 * with the body in the results row every result_get rewrote the body to move last_used (a
 * 1 MiB result: 6.2 ms a get, against 0.4 ms to read it; 64 KiB: 226 us against 22 us), and
 * held the write lock meanwhile.  Apart, the mark is a ~20 us update of a small row, and the
 * body is read outside any write transaction.  A put costs one more upsert (1 KiB results:
 * ~110 us a put with its eviction, against ~70 us in one table).
 *
 * Why in chunks (schema version 2; version 1 had one body row per result, which the migration
 * turns into one chunk): a result of 500 MB (16 000 cubes with every field) was held whole by
 * the worker, by the put, and by every GET.  Now the worker spools it to a file, result_put_file
 * copies it a chunk at a time, and a GET sends it a chunk at a time (result_size,
 * result_chunk).  A large put writes its chunks in transactions of SQ_BATCH bytes, so that
 * the write lock is never held for the whole copy (other writers wait at most SQ_BUSY_MS);
 * the results row comes last, in the transaction that checks the chunks and evicts, so a
 * result is visible whole or not at all.  Chunks with no results row are those of a put under
 * way, or left by one that failed or crashed: a failed put deletes its own, and opening the
 * store deletes any (one daemon per file: see "Threads").
 *
 * Invariants:
 *   - result_totals equals COUNT(*), SUM(bytes) of results at every commit: three triggers
 *     (after insert, after delete, after update of bytes) keep it, in the same transaction as
 *     the change, whoever makes it.  result_put thus reads the total in ~2 us where SUM(bytes)
 *     costs ~400 us over 5000 results (and grows with them; with the bodies inline it walked
 *     their overflow pages: 2-37 ms).  Rows are written with upserts, never INSERT OR REPLACE,
 *     whose implicit delete fires no trigger.
 *   - The chunks of every results row tile [0, bytes): each starts where the one before ends
 *     (a trigger deletes them with their row).  check() verifies this and the totals, and
 *     result_get refuses a body that does not add up.
 *   - After a committed result_put with a budget, SUM(bytes) <= budget, or the new result is
 *     the only one left (a result larger than the budget is still stored, alone).
 *   - last_used stamps handed out by one store strictly increase (sq_stamp: the clock, or a
 *     microsecond past the last stamp when the clock has not moved or went back), so "least
 *     recently used" is a total order even within one clock tick.
 *   - Every write is one BEGIN IMMEDIATE ... COMMIT, rolled back on any error: a writer takes
 *     the write lock up front and waits for it under the busy timeout, instead of failing to
 *     upgrade a read lock half-way (SQLITE_BUSY_SNAPSHOT).  Readers never block in WAL mode.
 *
 * Threads: any thread may call any op.  Each thread gets its own connection (opened on its
 * first call, SQLITE_OPEN_NOMUTEX, with its own cache of prepared statements), found through a
 * pthread key whose destructor closes it when the thread exits.  The store keeps the list of
 * all its connections under mu, so that close() can finalize and close every one of them;
 * close() must therefore not run while another thread still uses the store or is exiting
 * after having used it (the daemon closes the store after joining its workers and stopping
 * the HTTP server).  The ops never hold mu while talking to SQLite.  A callback of
 * jobs_unfinished() runs with no statement active, so it may call any op of the same store.
 * One daemon uses a file at a time (opening deletes the chunks of puts under way elsewhere).
 *
 * Ownership: strings passed in are borrowed; error, request and body handed out are malloc'd
 * copies, NUL-terminated one byte past their length, which the caller frees.
 */
#include "server/store.h"

#include <openssl/evp.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <errno.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define SQ_BUSY_MS       5000 /* how long a connection waits for a lock before SQLITE_BUSY */
#define SQ_PROBE_BUSY_MS 1000 /* the same for the readiness probe (writable) */
#define SQ_BATCH         ((uint64_t)32 * STORE_CHUNK) /* bytes of chunks a put writes per transaction */
/* PRAGMA application_id of a cellar store: "cell" */
#define SQ_APP_ID      0x63656c6c
#define SQ_APP_ID_TEXT "1667591276"

/* The schema, one script per version: sq_migrations[v] takes a database from version v to
 * v + 1.  Append, never edit: a database in the field has run the scripts it has run. */
static const char *const sq_migrations[] = {
    /* 0 -> 1 */
    "CREATE TABLE jobs(id TEXT PRIMARY KEY, hash TEXT NOT NULL, kind TEXT NOT NULL,"
    " state INTEGER NOT NULL, created REAL, started REAL, finished REAL,"
    " error_status INTEGER, error TEXT, request BLOB NOT NULL);"
    "CREATE INDEX jobs_state ON jobs(state);"
    "CREATE TABLE results(hash TEXT PRIMARY KEY, bytes INTEGER NOT NULL, created REAL,"
    " last_used REAL);"
    "CREATE INDEX results_last_used ON results(last_used);"
    "CREATE TABLE result_bodies(hash TEXT PRIMARY KEY, body BLOB NOT NULL);"
    "CREATE TRIGGER results_body_delete AFTER DELETE ON results BEGIN"
    " DELETE FROM result_bodies WHERE hash = OLD.hash; END;"
    "CREATE TABLE result_totals(id INTEGER PRIMARY KEY CHECK (id = 0),"
    " count INTEGER NOT NULL, bytes INTEGER NOT NULL);"
    "INSERT INTO result_totals VALUES(0, 0, 0);"
    "CREATE TRIGGER results_total_insert AFTER INSERT ON results BEGIN"
    " UPDATE result_totals SET count = count + 1, bytes = bytes + NEW.bytes; END;"
    "CREATE TRIGGER results_total_delete AFTER DELETE ON results BEGIN"
    " UPDATE result_totals SET count = count - 1, bytes = bytes - OLD.bytes; END;"
    "CREATE TRIGGER results_total_update AFTER UPDATE OF bytes ON results BEGIN"
    " UPDATE result_totals SET bytes = bytes - OLD.bytes + NEW.bytes; END;",
    /* 1 -> 2: bodies in chunks */
    "CREATE TABLE result_chunks(hash TEXT NOT NULL, off INTEGER NOT NULL, body BLOB NOT NULL,"
    " sha BLOB, PRIMARY KEY(hash, off));"
    "INSERT INTO result_chunks(hash, off, body)" /* sha: filled in at open (sq_fill_digests) */
    " SELECT hash, 0, body FROM result_bodies WHERE length(body) > 0;"
    "DROP TRIGGER results_body_delete;"
    "DROP TABLE result_bodies;"
    "CREATE TRIGGER results_chunks_delete AFTER DELETE ON results BEGIN"
    " DELETE FROM result_chunks WHERE hash = OLD.hash; END;",
    /* 2 -> 3: finished jobs keep no request, and are pruned by count through this index */
    "UPDATE jobs SET request = zeroblob(0) WHERE state IN (2, 3, 4);"
    "CREATE INDEX jobs_finished ON jobs(finished) WHERE state IN (2, 3, 4);",
    /* 3 -> 4: submissions, each with its own id to poll and cancel with (every job so far
     * had one, its own id) */
    "CREATE TABLE subs(id TEXT PRIMARY KEY, job TEXT NOT NULL, created REAL, canceled REAL);"
    "CREATE INDEX subs_job ON subs(job);"
    "INSERT INTO subs SELECT id, id, created, CASE WHEN state = 4 THEN finished END FROM jobs;"
    "CREATE TRIGGER jobs_subs_delete AFTER DELETE ON jobs BEGIN"
    " DELETE FROM subs WHERE job = OLD.id; END;",
    /* 4 -> 5: the queue lives in the store: leases, attempts, the cancel flag, progress; at
     * most one queued or running job per request hash (older duplicates, which no cellard
     * made, are canceled) */
    "ALTER TABLE jobs ADD COLUMN owner TEXT;"
    "ALTER TABLE jobs ADD COLUMN lease_until REAL;"
    "ALTER TABLE jobs ADD COLUMN attempts INTEGER NOT NULL DEFAULT 0;"
    "ALTER TABLE jobs ADD COLUMN cancel INTEGER NOT NULL DEFAULT 0;"
    "ALTER TABLE jobs ADD COLUMN stage TEXT;"
    "ALTER TABLE jobs ADD COLUMN fraction REAL;"
    "UPDATE jobs SET state = 4, finished = coalesce(finished, created), request = zeroblob(0)"
    " WHERE state IN (0, 1) AND rowid NOT IN"
    " (SELECT min(rowid) FROM jobs WHERE state IN (0, 1) GROUP BY hash);"
    "CREATE UNIQUE INDEX jobs_active_hash ON jobs(hash) WHERE state IN (0, 1);"
    "CREATE INDEX jobs_queue ON jobs(created) WHERE state = 0;",
    /* 5 -> 6: the job that made each result (X-Cellar-Job of a cache hit) */
    "ALTER TABLE results ADD COLUMN job TEXT;",
    /* 6 -> 7: a job being canceled (running, its cancel flag set) is no longer the request's
     * job: a new submission of the request makes a new job beside it instead of joining one
     * that will end canceled */
    "DROP INDEX jobs_active_hash;"
    "CREATE UNIQUE INDEX jobs_active_hash ON jobs(hash) WHERE state IN (0, 1) AND cancel = 0;",
};
#define SQ_VERSION ((int)(sizeof sq_migrations / sizeof *sq_migrations))

/* The statements every connection prepares once (on first use) and keeps. */
enum sq_sql {
    SQ_BEGIN,
    SQ_COMMIT,
    SQ_ROLLBACK,
    SQ_JOB_INSERT,
    SQ_JOB_GET,
    SQ_JOB_ACTIVE,
    SQ_JOB_COUNTS,
    SQ_JOB_CLAIM,
    SQ_JOB_RENEW,
    SQ_JOB_FINISH,
    SQ_JOB_RELEASE,
    SQ_JOBS_REQUEUE,
    SQ_JOBS_PRUNE,
    SQ_SUB_INSERT,
    SQ_SUB_GET,
    SQ_SUB_CANCEL,
    SQ_SUB_ACTIVE,
    SQ_JOB_CANCEL_QUEUED,
    SQ_JOB_STOP_RUNNING,
    SQ_BEGIN_READ,
    SQ_RESULT_UPSERT,
    SQ_RESULT_DELETE,
    SQ_CHUNKS_DELETE,
    SQ_CHUNK_PUT,
    SQ_CHUNKS_SUM,
    SQ_RESULT_TOTALS,
    SQ_RESULT_EVICT_ONE,
    SQ_RESULT_HEAD,
    SQ_CHUNKS_ALL,
    SQ_CHUNK_AT,
    SQ_RESULT_TOUCH,
    SQ_RESULT_EXISTS,
    SQ_INTEGRITY,
    SQ_TOTALS_RECOUNT,
    SQ_PROBE,
    SQ_CHUNKS_EVERY,
    SQ_NSQL
};

static const char *const sq_sql_text[SQ_NSQL] = {
    [SQ_BEGIN] = "BEGIN IMMEDIATE",
    [SQ_COMMIT] = "COMMIT",
    [SQ_ROLLBACK] = "ROLLBACK",
    [SQ_JOB_INSERT] =
        "INSERT INTO jobs(id, hash, kind, state, created, started, finished,"
        " error_status, error, request) VALUES(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
    [SQ_JOB_GET] = "SELECT id, hash, kind, state, created, started, finished, error_status, error,"
                   " request, (SELECT count(*) FROM subs WHERE job = ?1 AND canceled IS NULL),"
                   " owner, lease_until, attempts, cancel, stage, fraction FROM jobs WHERE id = ?1",
    /* the queued or running job of a request that is not being canceled (through the unique
     * index jobs_active_hash) */
    [SQ_JOB_ACTIVE] = "SELECT id FROM jobs WHERE hash = ?1 AND state IN (0, 1) AND cancel = 0",
    [SQ_JOB_COUNTS] = "SELECT (SELECT count(*) FROM jobs WHERE state = 0),"
                      " (SELECT count(*) FROM jobs WHERE state = 1)",
    /* the oldest queued job (through jobs_queue), for ?1 until ?3 */
    [SQ_JOB_CLAIM] = "UPDATE jobs SET state = 1, owner = ?1, started = ?2, lease_until = ?3,"
                     " attempts = attempts + 1, cancel = 0, stage = 'started', fraction = 0"
                     " WHERE rowid = (SELECT rowid FROM jobs WHERE state = 0"
                     " ORDER BY created, rowid LIMIT 1) RETURNING id",
    [SQ_JOB_RENEW] = "UPDATE jobs SET lease_until = ?3, stage = ?4, fraction = ?5"
                     " WHERE id = ?1 AND owner = ?2 AND state = 1 RETURNING cancel",
    /* a job that ends drops its request: only a queued or running job needs it, and bodies
     * are most of the table */
    [SQ_JOB_FINISH] = "UPDATE jobs SET state = ?3, finished = ?4, error_status = ?5, error = ?6,"
                      " request = zeroblob(0), lease_until = NULL"
                      " WHERE id = ?1 AND owner = ?2 AND state = 1",
    [SQ_JOB_RELEASE] = "UPDATE jobs SET state = CASE WHEN cancel THEN 4 ELSE 0 END,"
                       " finished = CASE WHEN cancel THEN ?3 END,"
                       " request = CASE WHEN cancel THEN zeroblob(0) ELSE request END,"
                       " started = CASE WHEN cancel THEN started END, stage = NULL,"
                       " fraction = NULL, lease_until = NULL"
                       " WHERE id = ?1 AND owner = ?2 AND state = 1",
    /* running jobs whose lease ended before ?1 (all of them when ?2): asked to stop, canceled;
     * started ?3 times already, failed; else queued again */
    [SQ_JOBS_REQUEUE] =
        "UPDATE jobs SET state = CASE WHEN cancel THEN 4 WHEN attempts >= ?3 THEN 3 ELSE 0 END,"
        " finished = CASE WHEN cancel OR attempts >= ?3 THEN ?1 END,"
        " error_status = CASE WHEN NOT cancel AND attempts >= ?3 THEN 500 END,"
        " error = CASE WHEN NOT cancel AND attempts >= ?3 THEN ?4 END,"
        " request = CASE WHEN cancel OR attempts >= ?3 THEN zeroblob(0) ELSE request END,"
        " started = CASE WHEN cancel OR attempts >= ?3 THEN started END, stage = NULL,"
        " fraction = NULL, lease_until = NULL WHERE state = 1 AND (?2 OR lease_until < ?1)",
    /* a submission of a job that exists */
    [SQ_SUB_INSERT] = "INSERT INTO subs(id, job, created, canceled) SELECT ?1, ?2, ?3, ?4"
                      " WHERE EXISTS (SELECT 1 FROM jobs WHERE id = ?2)",
    [SQ_SUB_GET] = "SELECT id, job, created, canceled FROM subs WHERE id = ?1",
    [SQ_SUB_CANCEL] = "UPDATE subs SET canceled = ?2 WHERE id = ?1 AND canceled IS NULL",
    [SQ_SUB_ACTIVE] = "SELECT count(*) FROM subs WHERE job = ?1 AND canceled IS NULL",
    [SQ_JOB_CANCEL_QUEUED] = "UPDATE jobs SET state = 4, finished = ?2, request = zeroblob(0)"
                             " WHERE id = ?1 AND state = 0",
    [SQ_JOB_STOP_RUNNING] = "UPDATE jobs SET cancel = 1 WHERE id = ?1 AND state = 1",
    /* finished jobs that ended before ?1, and those past the ?2 newest (?2 < 0: no limit),
     * both through the partial index jobs_finished (its states written out for it) */
    [SQ_JOBS_PRUNE] = "DELETE FROM jobs WHERE state IN (2, 3, 4) AND (finished < ?1 OR rowid IN"
                      " (SELECT rowid FROM jobs WHERE state IN (2, 3, 4) ORDER BY finished DESC"
                      " LIMIT -1 OFFSET ?2))",
    [SQ_RESULT_UPSERT] = "INSERT INTO results(hash, bytes, created, last_used, job)"
                         " VALUES(?1, ?2, ?3, ?3, ?4) ON CONFLICT(hash) DO UPDATE SET"
                         " bytes = excluded.bytes, created = excluded.created,"
                         " last_used = excluded.last_used, job = excluded.job",
    [SQ_BEGIN_READ] = "BEGIN",
    [SQ_RESULT_DELETE] = "DELETE FROM results WHERE hash = ?1",
    /* the chunks of a put that has no results row (yet, or any more) */
    [SQ_CHUNKS_DELETE] = "DELETE FROM result_chunks WHERE hash = ?1"
                         " AND NOT EXISTS (SELECT 1 FROM results WHERE hash = ?1)",
    [SQ_CHUNK_PUT] =
        "INSERT INTO result_chunks(hash, off, body, sha) VALUES(?1, ?2, ?3, ?4)"
        " ON CONFLICT(hash, off) DO UPDATE SET body = excluded.body, sha = excluded.sha",
    [SQ_CHUNKS_SUM] =
        "SELECT count(*), coalesce(sum(length(body)), 0) FROM result_chunks WHERE hash = ?1",
    [SQ_RESULT_TOTALS] = "SELECT count, bytes FROM result_totals WHERE id = 0",
    /* the least recently used result but ?1 (the one just stored), through the index */
    [SQ_RESULT_EVICT_ONE] = "DELETE FROM results WHERE rowid = (SELECT rowid FROM results"
                            " WHERE hash <> ?1 ORDER BY last_used LIMIT 1)",
    [SQ_RESULT_HEAD] = "SELECT bytes, last_used, job FROM results WHERE hash = ?1",
    [SQ_CHUNKS_ALL] = "SELECT off, body, sha FROM result_chunks WHERE hash = ?1 ORDER BY off",
    [SQ_CHUNK_AT] = "SELECT off, body, sha FROM result_chunks WHERE hash = ?1 AND off <= ?2"
                    " ORDER BY off DESC LIMIT 1",
    [SQ_PROBE] = "UPDATE result_totals SET count = count WHERE id = 0",
    [SQ_CHUNKS_EVERY] =
        "SELECT body, sha FROM result_chunks WHERE hash IN (SELECT hash FROM results)",
    [SQ_RESULT_TOUCH] = "UPDATE results SET last_used = ?2 WHERE hash = ?1",
    [SQ_RESULT_EXISTS] = "SELECT 1 FROM results WHERE hash = ?1",
    [SQ_INTEGRITY] = "PRAGMA integrity_check",
    /* the totals row, the table's count and sum, the results whose chunks do not add up to
     * their size, the chunks that do not start where the one before ends */
    [SQ_TOTALS_RECOUNT] =
        "SELECT t.count, t.bytes, (SELECT count(*) FROM results),"
        " (SELECT coalesce(sum(bytes), 0) FROM results),"
        " (SELECT count(*) FROM results r WHERE r.bytes <> (SELECT coalesce(sum(length(c.body)), 0)"
        "  FROM result_chunks c WHERE c.hash = r.hash)),"
        " (SELECT count(*) FROM (SELECT off, sum(length(body)) OVER (PARTITION BY hash ORDER BY off"
        "  ROWS UNBOUNDED PRECEDING) - length(body) AS start FROM result_chunks"
        "  WHERE hash IN (SELECT hash FROM results)) WHERE off <> start)"
        " FROM result_totals t WHERE t.id = 0",
};

typedef struct sq_store sq_store;

typedef struct sq_conn {
    sqlite3 *db;                 /* used by one thread only (or by close) */
    sqlite3_stmt *stmt[SQ_NSQL]; /* prepared on first use, finalized when the conn closes */
    sq_store *owner;             /* the store whose list holds this conn */
    struct sq_conn *prev, *next; /* in owner->conns; guarded by owner->mu */
} sq_conn;

struct sq_store {
    store base;           /* first member: a store * of this backend is a sq_store * */
    char *path;           /* the database file */
    uint64_t budget;      /* result bytes allowed; 0: unlimited */
    pthread_key_t key;    /* the calling thread's sq_conn */
    pthread_mutex_t mu;   /* guards conns and last_stamp */
    sq_conn *conns;       /* every open connection of this store */
    double last_stamp;    /* the latest last_used handed out (or found at open) */
    double touch_seconds; /* result_get leaves marks younger than this (immutable) */
    int key_made;         /* key is valid (for the cleanup path of open) */
    int lock_fd;          /* path + "-lock", flock'd: one daemon per file (-1: none) */
};

static void sq_errf(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void sq_errf(char *err, size_t errlen, const char *fmt, ...)
{
    va_list ap;
    if (!err || !errlen) return;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

/* "sqlite WHERE: SQLite's message of the connection's last error" */
static void sq_dberr(char *err, size_t errlen, const char *where, sqlite3 *db)
{
    sq_errf(err, errlen, "sqlite %s: %s", where, db ? sqlite3_errmsg(db) : "out of memory");
}

/* An error while opening path; the first read of a file that is no database says so. */
static void sq_open_err(char *err, size_t errlen, const char *path, sqlite3 *db, int rc)
{
    if ((rc & 0xff) == SQLITE_NOTADB)
        sq_errf(err, errlen, "sqlite open %s: not a SQLite database (%s)", path,
                sqlite3_errmsg(db));
    else
        sq_errf(err, errlen, "sqlite open %s: %s", path, sqlite3_errmsg(db));
}

/* Resets a statement after use and drops its bindings (borrowed buffers bound SQLITE_STATIC
 * must not outlive the call that bound them). */
static void sq_done(sqlite3_stmt *st)
{
    if (!st) return;
    sqlite3_reset(st);
    sqlite3_clear_bindings(st);
}

static sqlite3_stmt *sq_stmt(sq_conn *c, enum sq_sql id, const char *where, char *err,
                             size_t errlen)
{
    if (!c->stmt[id] && sqlite3_prepare_v3(c->db, sq_sql_text[id], -1, SQLITE_PREPARE_PERSISTENT,
                                           &c->stmt[id], NULL) != SQLITE_OK) {
        sq_dberr(err, errlen, where, c->db);
        c->stmt[id] = NULL;
        return NULL;
    }
    return c->stmt[id];
}

/* Runs a statement that returns no row (BEGIN, COMMIT, ...). */
static int sq_run(sq_conn *c, enum sq_sql id, const char *where, char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, id, where, err, errlen);
    int rc;
    if (!st) return STORE_ERR;
    rc = sqlite3_step(st);
    if (rc != SQLITE_DONE && rc != SQLITE_ROW) sq_dberr(err, errlen, where, c->db);
    sq_done(st);
    return rc == SQLITE_DONE || rc == SQLITE_ROW ? STORE_OK : STORE_ERR;
}

/* Rolls back the open transaction, if any (SQLite ends some on its own, e.g. on SQLITE_FULL). */
static void sq_rollback(sq_conn *c)
{
    if (!sqlite3_get_autocommit(c->db)) sq_run(c, SQ_ROLLBACK, "rollback", NULL, 0);
}

static void sq_conn_close(sq_conn *c)
{
    if (!c) return;
    for (int i = 0; i < SQ_NSQL; i++) sqlite3_finalize(c->stmt[i]);
    sqlite3_close_v2(c->db);
    free(c);
}

/* The pthread key's destructor: a thread that used the store is exiting. */
static void sq_conn_release(void *p)
{
    sq_conn *c = p;
    sq_store *s = c->owner;
    pthread_mutex_lock(&s->mu);
    if (c->prev)
        c->prev->next = c->next;
    else
        s->conns = c->next;
    if (c->next) c->next->prev = c->prev;
    pthread_mutex_unlock(&s->mu);
    sq_conn_close(c);
}

/* Opens a connection to s->path (creating the file if create), with this backend's per-connection
 * settings; not yet registered anywhere.  *out is the conn, or NULL on failure. */
static int sq_conn_open(sq_store *s, int create, sq_conn **out, char *err, size_t errlen)
{
    int rc, flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX | (create ? SQLITE_OPEN_CREATE : 0);
    sq_conn *c = calloc(1, sizeof *c);
    *out = NULL;
    if (!c) {
        sq_errf(err, errlen, "sqlite open: out of memory");
        return STORE_ERR;
    }
    c->owner = s;
    if (sqlite3_open_v2(s->path, &c->db, flags, NULL) != SQLITE_OK) {
        sq_errf(err, errlen, "sqlite open %s: %s", s->path,
                c->db ? sqlite3_errmsg(c->db) : "out of memory");
        goto fail;
    }
    sqlite3_extended_result_codes(c->db, 1);
    sqlite3_busy_timeout(c->db, SQ_BUSY_MS);
    /* synchronous=NORMAL: in WAL mode a commit survives a crash of the process, and the last
     * ones may be lost only with the machine (fsync at checkpoints, not at every commit). */
    rc = sqlite3_exec(c->db, "PRAGMA synchronous=NORMAL; PRAGMA journal_size_limit=67108864", NULL,
                      NULL, NULL);
    if (rc != SQLITE_OK) {
        sq_open_err(err, errlen, s->path, c->db, rc);
        goto fail;
    }
    *out = c;
    return STORE_OK;
fail:
    sq_conn_close(c);
    return STORE_ERR;
}

/* The calling thread's connection, opened and registered on its first call. */
static sq_conn *sq_conn_get(sq_store *s, char *err, size_t errlen)
{
    sq_conn *c = pthread_getspecific(s->key);
    if (c) return c;
    if (sq_conn_open(s, 0, &c, err, errlen)) return NULL;
    if (pthread_setspecific(s->key, c) != 0) {
        sq_errf(err, errlen, "sqlite open: pthread_setspecific failed");
        sq_conn_close(c);
        return NULL;
    }
    pthread_mutex_lock(&s->mu);
    c->next = s->conns;
    if (s->conns) s->conns->prev = c;
    s->conns = c;
    pthread_mutex_unlock(&s->mu);
    return c;
}

/* A last_used stamp: now, but strictly after every stamp this store handed out before. */
static double sq_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static double sq_stamp(sq_store *s)
{
    struct timespec ts;
    double t;
    clock_gettime(CLOCK_REALTIME, &ts);
    t = (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
    pthread_mutex_lock(&s->mu);
    if (t <= s->last_stamp) t = s->last_stamp + 1e-6; /* > 4 ulps at today's Unix times */
    s->last_stamp = t;
    pthread_mutex_unlock(&s->mu);
    return t;
}

static void sq_bind_time(sqlite3_stmt *st, int i, double t)
{
    if (t != 0)
        sqlite3_bind_double(st, i, t);
    else
        sqlite3_bind_null(st, i);
}

static double sq_column_time(sqlite3_stmt *st, int col)
{
    return sqlite3_column_type(st, col) == SQLITE_NULL ? 0 : sqlite3_column_double(st, col);
}

/* Copies a text column into dst[cap]; -1 when it does not fit (NULL reads as ""). */
static int sq_column_fixed(sqlite3_stmt *st, int col, char *dst, size_t cap)
{
    const unsigned char *t = sqlite3_column_text(st, col);
    size_t n = (size_t)sqlite3_column_bytes(st, col);
    if (!t) n = 0;
    if (n >= cap) return -1;
    if (n) memcpy(dst, t, n);
    dst[n] = 0;
    return 0;
}

/* A malloc'd copy of a blob or text column, NUL-terminated past its length; NULL in *out for
 * an SQL NULL when null_ok.  -1 on out of memory. */
static int sq_column_dup(sqlite3_stmt *st, int col, int null_ok, char **out, size_t *len)
{
    const void *p;
    size_t n;
    *out = NULL;
    if (len) *len = 0;
    if (null_ok && sqlite3_column_type(st, col) == SQLITE_NULL) return 0;
    p = sqlite3_column_blob(st, col);
    n = (size_t)sqlite3_column_bytes(st, col);
    if (!p && n) return -1;
    *out = malloc(n + 1);
    if (!*out) return -1;
    if (n) memcpy(*out, p, n);
    (*out)[n] = 0;
    if (len) *len = n;
    return 0;
}

/* Binds a NUL-terminated string that must fit a store_job field of cap bytes. */
static int sq_bind_field(sqlite3_stmt *st, int i, const char *v, size_t cap, const char *what,
                         char *err, size_t errlen)
{
    size_t n = strnlen(v, cap);
    if (n == cap) {
        sq_errf(err, errlen, "sqlite job_insert: %s is not a string of at most %zu bytes", what,
                cap - 1);
        return STORE_ERR;
    }
    sqlite3_bind_text(st, i, v, (int)n, SQLITE_STATIC);
    return STORE_OK;
}

static int sq_state_valid(int st)
{
    return st >= JOB_QUEUED && st <= JOB_CANCELED;
}

/* ---- jobs ---- */

/* Inserts sub (inside the caller's transaction): STORE_NOTFOUND when its job is not there. */
static int sq_sub_write(sq_conn *c, const store_sub *sub, const char *where, char *err,
                        size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_SUB_INSERT, where, err, errlen);
    if (!st) return STORE_ERR;
    if (sq_bind_field(st, 1, sub->id, sizeof sub->id, "id", err, errlen) ||
        sq_bind_field(st, 2, sub->job, sizeof sub->job, "job", err, errlen)) {
        sq_done(st);
        return STORE_ERR;
    }
    sq_bind_time(st, 3, sub->created);
    sq_bind_time(st, 4, sub->canceled);
    if (sqlite3_step(st) != SQLITE_DONE) {
        sq_dberr(err, errlen, where, c->db);
        sq_done(st);
        return STORE_ERR;
    }
    int rc = sqlite3_changes(c->db) ? STORE_OK : STORE_NOTFOUND;
    sq_done(st);
    if (rc == STORE_NOTFOUND) sq_errf(err, errlen, "sqlite %s: no job %s", where, sub->job);
    return rc;
}

/* Inserts job j and its first submission (inside the caller's transaction). */
static int sq_job_write(sq_conn *c, const store_job *j, const char *where, char *err, size_t errlen)
{
    if (!sq_state_valid((int)j->state)) {
        sq_errf(err, errlen, "sqlite %s: unknown state %d", where, (int)j->state);
        return STORE_ERR;
    }
    if (!j->request && j->request_len) {
        sq_errf(err, errlen, "sqlite %s: request_len %zu with no request", where, j->request_len);
        return STORE_ERR;
    }
    sqlite3_stmt *st = sq_stmt(c, SQ_JOB_INSERT, where, err, errlen);
    if (!st) return STORE_ERR;
    if (sq_bind_field(st, 1, j->id, sizeof j->id, "id", err, errlen) ||
        sq_bind_field(st, 2, j->hash, sizeof j->hash, "hash", err, errlen) ||
        sq_bind_field(st, 3, j->kind, sizeof j->kind, "kind", err, errlen)) {
        sq_done(st);
        return STORE_ERR;
    }
    sqlite3_bind_int(st, 4, (int)j->state);
    sq_bind_time(st, 5, j->created);
    sq_bind_time(st, 6, j->started);
    sq_bind_time(st, 7, j->finished);
    if (j->error_status) sqlite3_bind_int(st, 8, j->error_status);
    if (j->error) sqlite3_bind_text(st, 9, j->error, -1, SQLITE_STATIC);
    /* a non-NULL pointer even for 0 bytes: a NULL one would bind SQL NULL */
    sqlite3_bind_blob64(st, 10, j->request ? j->request : "", j->request_len, SQLITE_STATIC);
    int rc = sqlite3_step(st);
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, where, c->db);
    sq_done(st);
    if (rc != SQLITE_DONE) return STORE_ERR;
    store_sub first = {.created = j->created,
                       .canceled = j->state == JOB_CANCELED ? j->finished : 0};
    memcpy(first.id, j->id, sizeof first.id);
    memcpy(first.job, j->id, sizeof first.job);
    return sq_sub_write(c, &first, where, err, errlen) == STORE_OK ? STORE_OK : STORE_ERR;
}

/* Runs statement `id` with the text `key` bound to ?1 and reads the first column of its one
 * row as an integer (*out) or as an id (idout, 33 bytes); STORE_NOTFOUND when it gives no row. */
static int sq_lookup(sq_conn *c, enum sq_sql id, const char *key, long long *out, char *idout,
                     const char *where, char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, id, where, err, errlen);
    if (!st) return STORE_ERR;
    if (key) sqlite3_bind_text(st, 1, key, -1, SQLITE_STATIC);
    int rc = sqlite3_step(st), out_rc = STORE_OK;
    if (rc == SQLITE_DONE) {
        out_rc = STORE_NOTFOUND;
    } else if (rc != SQLITE_ROW) {
        sq_dberr(err, errlen, where, c->db);
        out_rc = STORE_ERR;
    } else {
        if (out) *out = sqlite3_column_int64(st, 0);
        if (idout && sq_column_fixed(st, 0, idout, 33)) {
            sq_errf(err, errlen, "sqlite %s: an id too long in the database", where);
            out_rc = STORE_ERR;
        }
    }
    sq_done(st);
    return out_rc;
}

static int sq_job_insert(store *base, const store_job *j, char *err, size_t errlen)
{
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    if (sq_run(c, SQ_BEGIN, "job_insert: begin", err, errlen)) return STORE_ERR;
    if (sq_job_write(c, j, "job_insert", err, errlen) ||
        sq_run(c, SQ_COMMIT, "job_insert: commit", err, errlen)) {
        sq_rollback(c);
        return STORE_ERR;
    }
    return STORE_OK;
}

static int sq_job_submit(store *base, const store_job *j, size_t queue_max, int join_only,
                         char *job_id, int *joined, char *err, size_t errlen)
{
    long long queued = 0;
    *joined = 0;
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    if (sq_run(c, SQ_BEGIN, "job_submit: begin", err, errlen)) return STORE_ERR;
    int rc = sq_lookup(c, SQ_RESULT_EXISTS, j->hash, NULL, NULL, "job_submit", err, errlen);
    if (rc == STORE_OK) {
        rc = STORE_CACHED;
        goto done;
    }
    if (rc != STORE_NOTFOUND) goto fail;
    rc = sq_lookup(c, SQ_JOB_ACTIVE, j->hash, NULL, job_id, "job_submit", err, errlen);
    if (rc == STORE_OK) { /* joined: a submission of its own */
        store_sub sub = {.created = j->created};
        memcpy(sub.id, j->id, sizeof sub.id);
        memcpy(sub.job, job_id, sizeof sub.job);
        if (sq_sub_write(c, &sub, "job_submit: join", err, errlen)) goto fail;
        *joined = 1;
        goto done;
    }
    if (rc != STORE_NOTFOUND) goto fail;
    if (join_only) goto done; /* STORE_NOTFOUND */
    if (queue_max) {
        if (sq_lookup(c, SQ_JOB_COUNTS, NULL, &queued, NULL, "job_submit", err, errlen) != STORE_OK)
            goto fail;
        if ((unsigned long long)queued >= queue_max) {
            rc = STORE_FULL;
            goto done;
        }
    }
    store_job q = *j;
    q.state = JOB_QUEUED;
    q.started = q.finished = 0;
    q.error_status = 0;
    q.error = NULL;
    if (sq_job_write(c, &q, "job_submit", err, errlen)) goto fail;
    memcpy(job_id, j->id, 33);
    rc = STORE_OK;
done:
    if (sq_run(c, SQ_COMMIT, "job_submit: commit", err, errlen)) goto fail;
    return rc;
fail:
    *joined = 0;
    sq_rollback(c);
    return STORE_ERR;
}

/* Reads job id into *out on connection c (no transaction: one statement is one snapshot). */
static int sq_job_read(sq_conn *c, const char *id, store_job *out, char *err, size_t errlen)
{
    sqlite3_stmt *st;
    int rc;
    memset(out, 0, sizeof *out);
    st = sq_stmt(c, SQ_JOB_GET, "job_get", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
    rc = sqlite3_step(st);
    if (rc == SQLITE_DONE) {
        sq_done(st);
        return STORE_NOTFOUND;
    }
    if (rc != SQLITE_ROW) {
        sq_dberr(err, errlen, "job_get", c->db);
        goto fail;
    }
    if (sq_column_fixed(st, 0, out->id, sizeof out->id) ||
        sq_column_fixed(st, 1, out->hash, sizeof out->hash) ||
        sq_column_fixed(st, 2, out->kind, sizeof out->kind) ||
        sq_column_fixed(st, 11, out->owner, sizeof out->owner) ||
        sq_column_fixed(st, 15, out->stage, sizeof out->stage)) {
        sq_errf(err, errlen, "sqlite job_get %s: a text field too long in the database", id);
        goto fail;
    }
    out->state = (job_state)sqlite3_column_int(st, 3);
    if (!sq_state_valid((int)out->state)) {
        sq_errf(err, errlen, "sqlite job_get %s: unknown state %d in the database", id,
                (int)out->state);
        goto fail;
    }
    out->created = sq_column_time(st, 4);
    out->started = sq_column_time(st, 5);
    out->finished = sq_column_time(st, 6);
    out->error_status = sqlite3_column_int(st, 7);
    if (sq_column_dup(st, 8, 1, &out->error, NULL) ||
        sq_column_dup(st, 9, 0, &out->request, &out->request_len)) {
        sq_errf(err, errlen, "sqlite job_get %s: out of memory", id);
        goto fail;
    }
    out->active_subs = sqlite3_column_int(st, 10);
    out->lease_until = sq_column_time(st, 12);
    out->attempts = sqlite3_column_int(st, 13);
    out->cancel = sqlite3_column_int(st, 14);
    out->fraction = sqlite3_column_double(st, 16);
    sq_done(st);
    return STORE_OK;
fail:
    sq_done(st);
    store_job_clear(out);
    return STORE_ERR;
}

static int sq_job_get(store *base, const char *id, store_job *out, char *err, size_t errlen)
{
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) {
        memset(out, 0, sizeof *out);
        return STORE_ERR;
    }
    return sq_job_read(c, id, out, err, errlen);
}

static int sq_job_claim(store *base, const char *owner, double now, double lease, store_job *out,
                        char *err, size_t errlen)
{
    char id[33];
    memset(out, 0, sizeof *out);
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    if (sq_run(c, SQ_BEGIN, "job_claim: begin", err, errlen)) return STORE_ERR;
    sqlite3_stmt *st = sq_stmt(c, SQ_JOB_CLAIM, "job_claim", err, errlen);
    if (!st) goto fail;
    sqlite3_bind_text(st, 1, owner, -1, SQLITE_STATIC);
    sqlite3_bind_double(st, 2, now);
    sqlite3_bind_double(st, 3, now + lease);
    int rc = sqlite3_step(st), found = rc == SQLITE_ROW;
    if (found && sq_column_fixed(st, 0, id, sizeof id)) rc = SQLITE_MISMATCH;
    if (found && rc == SQLITE_ROW) rc = sqlite3_step(st); /* to its end: the update is done */
    if (rc != SQLITE_DONE) {
        if (rc == SQLITE_MISMATCH)
            sq_errf(err, errlen, "sqlite job_claim: an id too long in the database");
        else
            sq_dberr(err, errlen, "job_claim", c->db);
        sq_done(st);
        goto fail;
    }
    sq_done(st);
    if (found && sq_job_read(c, id, out, err, errlen) != STORE_OK) goto fail;
    if (sq_run(c, SQ_COMMIT, "job_claim: commit", err, errlen)) goto fail;
    return found ? STORE_OK : STORE_NOTFOUND;
fail:
    store_job_clear(out);
    sq_rollback(c);
    return STORE_ERR;
}

/* One write in a transaction of its own: statement `id`, its parameters bound by bind(st,
 * args); with RETURNING, *col0 (may be NULL) gets the first column of its row.  STORE_NOTFOUND
 * when it changed no row. */
typedef void (*sq_binder)(sqlite3_stmt *st, const void *args);

static int sq_write1(sq_store *s, enum sq_sql id, sq_binder bind, const void *args, int *col0,
                     const char *where, char *err, size_t errlen)
{
    sq_conn *c = sq_conn_get(s, err, errlen);
    if (!c) return STORE_ERR;
    if (sq_run(c, SQ_BEGIN, where, err, errlen)) return STORE_ERR;
    sqlite3_stmt *st = sq_stmt(c, id, where, err, errlen);
    if (!st) goto fail;
    bind(st, args);
    int rc = sqlite3_step(st), changed;
    if (rc == SQLITE_ROW) { /* RETURNING: the first column, then to the end */
        if (col0) *col0 = sqlite3_column_int(st, 0);
        changed = 1;
        rc = sqlite3_step(st);
    } else {
        changed = sqlite3_changes(c->db) > 0;
    }
    if (rc != SQLITE_DONE) {
        sq_dberr(err, errlen, where, c->db);
        sq_done(st);
        goto fail;
    }
    sq_done(st);
    if (sq_run(c, SQ_COMMIT, where, err, errlen)) goto fail;
    return changed ? STORE_OK : STORE_NOTFOUND;
fail:
    sq_rollback(c);
    return STORE_ERR;
}

typedef struct sq_renew_args {
    const char *id, *owner, *stage;
    double until, fraction;
} sq_renew_args;

static void sq_bind_renew(sqlite3_stmt *st, const void *p)
{
    const sq_renew_args *a = p;
    sqlite3_bind_text(st, 1, a->id, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 2, a->owner, -1, SQLITE_STATIC);
    sqlite3_bind_double(st, 3, a->until);
    if (a->stage) sqlite3_bind_text(st, 4, a->stage, -1, SQLITE_STATIC);
    sqlite3_bind_double(st, 5, a->fraction);
}

static int sq_job_renew(store *base, const char *id, const char *owner, double now, double lease,
                        const char *stage, double fraction, int *cancel, char *err, size_t errlen)
{
    sq_renew_args a = {id, owner, stage, now + lease, fraction};
    *cancel = 0;
    return sq_write1((sq_store *)base, SQ_JOB_RENEW, sq_bind_renew, &a, cancel, "job_renew", err,
                     errlen);
}

typedef struct sq_finish_args {
    const char *id, *owner, *error;
    int state, error_status;
    double when;
} sq_finish_args;

static void sq_bind_finish(sqlite3_stmt *st, const void *p)
{
    const sq_finish_args *a = p;
    sqlite3_bind_text(st, 1, a->id, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 2, a->owner, -1, SQLITE_STATIC);
    sqlite3_bind_int(st, 3, a->state);
    sq_bind_time(st, 4, a->when);
    if (a->state == JOB_FAILED && a->error_status) sqlite3_bind_int(st, 5, a->error_status);
    if (a->state == JOB_FAILED && a->error) sqlite3_bind_text(st, 6, a->error, -1, SQLITE_STATIC);
}

static int sq_job_finish(store *base, const char *id, const char *owner, job_state state,
                         double when, int error_status, const char *error, char *err, size_t errlen)
{
    if (state != JOB_DONE && state != JOB_FAILED && state != JOB_CANCELED) {
        sq_errf(err, errlen, "sqlite job_finish: %d is not an end state", (int)state);
        return STORE_ERR;
    }
    sq_finish_args a = {id, owner, error, (int)state, error_status, when};
    return sq_write1((sq_store *)base, SQ_JOB_FINISH, sq_bind_finish, &a, NULL, "job_finish", err,
                     errlen);
}

static void sq_bind_release(sqlite3_stmt *st, const void *p)
{
    const char *const *a = p;
    sqlite3_bind_text(st, 1, a[0], -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 2, a[1], -1, SQLITE_STATIC);
    sqlite3_bind_double(st, 3, sq_now());
}

static int sq_job_release(store *base, const char *id, const char *owner, char *err, size_t errlen)
{
    const char *a[2] = {id, owner};
    return sq_write1((sq_store *)base, SQ_JOB_RELEASE, sq_bind_release, a, NULL, "job_release", err,
                     errlen);
}

#define SQ_REQUEUE_MSG                                                                             \
    "the job was started " SQ_STR(STORE_MAX_ATTEMPTS) " times, and each time the daemon running "  \
                                                      "it stopped before it ended"
#define SQ_STR_(x) #x
#define SQ_STR(x)  SQ_STR_(x)

static int sq_jobs_requeue(store *base, double now, int all, size_t *n, char *err, size_t errlen)
{
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    *n = 0;
    if (!c) return STORE_ERR;
    if (sq_run(c, SQ_BEGIN, "jobs_requeue: begin", err, errlen)) return STORE_ERR;
    sqlite3_stmt *st = sq_stmt(c, SQ_JOBS_REQUEUE, "jobs_requeue", err, errlen);
    if (!st) goto fail;
    sqlite3_bind_double(st, 1, now);
    sqlite3_bind_int(st, 2, all != 0);
    sqlite3_bind_int(st, 3, STORE_MAX_ATTEMPTS);
    sqlite3_bind_text(st, 4, SQ_REQUEUE_MSG, -1, SQLITE_STATIC);
    if (sqlite3_step(st) != SQLITE_DONE) {
        sq_dberr(err, errlen, "jobs_requeue", c->db);
        sq_done(st);
        goto fail;
    }
    *n = (size_t)sqlite3_changes64(c->db);
    sq_done(st);
    if (sq_run(c, SQ_COMMIT, "jobs_requeue: commit", err, errlen)) goto fail;
    return STORE_OK;
fail:
    *n = 0;
    sq_rollback(c);
    return STORE_ERR;
}

static int sq_job_counts(store *base, size_t *queued, size_t *running, char *err, size_t errlen)
{
    *queued = *running = 0;
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    sqlite3_stmt *st = sq_stmt(c, SQ_JOB_COUNTS, "job_counts", err, errlen);
    if (!st) return STORE_ERR;
    int rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        *queued = (size_t)sqlite3_column_int64(st, 0);
        *running = (size_t)sqlite3_column_int64(st, 1);
    } else {
        sq_dberr(err, errlen, "job_counts", c->db);
    }
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : STORE_ERR;
}

static int sq_jobs_prune(store *base, double before, size_t keep, size_t *n, char *err,
                         size_t errlen)
{
    sq_store *s = (sq_store *)base;
    sqlite3_stmt *st = NULL;
    sqlite3_int64 changed;
    sq_conn *c = sq_conn_get(s, err, errlen);
    if (n) *n = 0;
    if (!c) return STORE_ERR;
    if (sq_run(c, SQ_BEGIN, "jobs_prune: begin", err, errlen)) return STORE_ERR;
    st = sq_stmt(c, SQ_JOBS_PRUNE, "jobs_prune", err, errlen);
    if (!st) goto fail;
    sqlite3_bind_double(st, 1, before);
    if (keep && keep < (size_t)INT64_MAX)
        sqlite3_bind_int64(st, 2, (sqlite3_int64)keep);
    else
        sqlite3_bind_int64(st, 2, INT64_MAX); /* past every row: no limit */
    if (sqlite3_step(st) != SQLITE_DONE) {
        sq_dberr(err, errlen, "jobs_prune", c->db);
        goto fail;
    }
    changed = sqlite3_changes64(c->db);
    sq_done(st);
    st = NULL;
    if (sq_run(c, SQ_COMMIT, "jobs_prune: commit", err, errlen)) goto fail;
    if (n) *n = (size_t)changed;
    return STORE_OK;
fail:
    sq_done(st);
    sq_rollback(c);
    return STORE_ERR;
}

/* ---- submissions ---- */

static int sq_sub_get(store *base, const char *id, store_sub *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    sqlite3_stmt *st = sq_stmt(c, SQ_SUB_GET, "sub_get", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, id, -1, SQLITE_STATIC);
    int rc = sqlite3_step(st), out_rc = STORE_OK;
    if (rc == SQLITE_DONE) {
        out_rc = STORE_NOTFOUND;
    } else if (rc != SQLITE_ROW) {
        sq_dberr(err, errlen, "sub_get", c->db);
        out_rc = STORE_ERR;
    } else if (sq_column_fixed(st, 0, out->id, sizeof out->id) ||
               sq_column_fixed(st, 1, out->job, sizeof out->job)) {
        sq_errf(err, errlen, "sqlite sub_get %s: an id too long in the database", id);
        out_rc = STORE_ERR;
    } else {
        out->created = sq_column_time(st, 2);
        out->canceled = sq_column_time(st, 3);
    }
    sq_done(st);
    return out_rc;
}

/* Runs statement `id` on job `job` at `when` (?1, ?2): whether it changed a row (-1: error). */
static int sq_job_step(sq_conn *c, enum sq_sql id, const char *job, double when, const char *where,
                       char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, id, where, err, errlen);
    if (!st) return -1;
    sqlite3_bind_text(st, 1, job, -1, SQLITE_STATIC);
    if (sqlite3_bind_parameter_count(st) >= 2) sqlite3_bind_double(st, 2, when);
    int rc = sqlite3_step(st);
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, where, c->db);
    sq_done(st);
    return rc != SQLITE_DONE ? -1 : sqlite3_changes(c->db) > 0;
}

static int sq_sub_cancel(store *base, const char *id, double when, int *changed, int *job,
                         char *err, size_t errlen)
{
    store_sub sub;
    long long active = 0;
    *changed = 0;
    *job = STORE_JOB_KEPT;
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    if (sq_run(c, SQ_BEGIN, "sub_cancel: begin", err, errlen)) return STORE_ERR;
    int rc = sq_sub_get(base, id, &sub, err, errlen);
    if (rc == STORE_NOTFOUND) goto done;
    if (rc != STORE_OK) goto fail;
    int ch = sq_job_step(c, SQ_SUB_CANCEL, id, when, "sub_cancel", err, errlen);
    if (ch < 0) goto fail;
    *changed = ch;
    if (ch) { /* the last one of its job? */
        if (sq_lookup(c, SQ_SUB_ACTIVE, sub.job, &active, NULL, "sub_cancel", err, errlen))
            goto fail;
        if (active == 0) {
            int q = sq_job_step(c, SQ_JOB_CANCEL_QUEUED, sub.job, when, "sub_cancel", err, errlen);
            int r =
                q ? q
                  : sq_job_step(c, SQ_JOB_STOP_RUNNING, sub.job, when, "sub_cancel", err, errlen);
            if (q < 0 || r < 0) goto fail;
            *job = q ? STORE_JOB_CANCELED : r ? STORE_JOB_STOPPING : STORE_JOB_KEPT;
        }
    }
done:
    if (sq_run(c, SQ_COMMIT, "sub_cancel: commit", err, errlen)) goto fail;
    return rc;
fail:
    *changed = 0;
    *job = STORE_JOB_KEPT;
    sq_rollback(c);
    return STORE_ERR;
}

/* ---- results ---- */

/* Reads result_totals (inside the caller's transaction, or as one snapshot). */
static int sq_totals(sq_conn *c, const char *where, size_t *count, uint64_t *bytes, char *err,
                     size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_RESULT_TOTALS, where, err, errlen);
    int rc;
    if (!st) return STORE_ERR;
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        if (count) *count = (size_t)sqlite3_column_int64(st, 0);
        if (bytes) *bytes = (uint64_t)sqlite3_column_int64(st, 1);
    } else if (rc == SQLITE_DONE) {
        sq_errf(err, errlen, "sqlite %s: the result_totals row is missing", where);
    } else {
        sq_dberr(err, errlen, where, c->db);
    }
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : STORE_ERR;
}

/* Deletes the least recently used results but `keep` until the total is within budget or
 * `keep` is alone; inside the caller's transaction.  Each round is an O(1) read of the total
 * and one indexed delete. */
static int sq_evict(sq_conn *c, uint64_t budget, const char *keep, char *err, size_t errlen)
{
    for (;;) {
        uint64_t total;
        sqlite3_stmt *st;
        int rc;
        if (sq_totals(c, "result_put: total", NULL, &total, err, errlen)) return STORE_ERR;
        if (total <= budget) return STORE_OK;
        st = sq_stmt(c, SQ_RESULT_EVICT_ONE, "result_put: evict", err, errlen);
        if (!st) return STORE_ERR;
        sqlite3_bind_text(st, 1, keep, -1, SQLITE_STATIC);
        rc = sqlite3_step(st);
        if (rc != SQLITE_DONE) sq_dberr(err, errlen, "result_put: evict", c->db);
        sq_done(st);
        if (rc != SQLITE_DONE) return STORE_ERR;
        if (sqlite3_changes(c->db) == 0) return STORE_OK; /* keep alone exceeds the budget */
    }
}

/* Runs a statement whose ?1 is a hash and that returns no row. */
static int sq_run_hash(sq_conn *c, enum sq_sql id, const char *hash, const char *where, char *err,
                       size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, id, where, err, errlen);
    int rc;
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    rc = sqlite3_step(st);
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, where, c->db);
    sq_done(st);
    return rc == SQLITE_DONE ? STORE_OK : STORE_ERR;
}

/* The SHA-256 of a chunk, stored beside it and checked whenever the chunk is read. */
static void sq_digest(const void *data, size_t n, unsigned char out[32])
{
    unsigned int len = 0;
    if (!EVP_Digest(data, n, out, &len, EVP_sha256(), NULL) || len != 32)
        memset(out, 0, 32); /* cannot happen with OpenSSL's sha256; a wrong digest then shows */
}

/* Whether column col of st is the digest of data[0..n). */
static int sq_digest_ok(sqlite3_stmt *st, int col, const void *data, size_t n)
{
    unsigned char md[32];
    if (sqlite3_column_type(st, col) != SQLITE_BLOB || sqlite3_column_bytes(st, col) != 32)
        return 0;
    sq_digest(data ? data : "", n, md);
    return memcmp(md, sqlite3_column_blob(st, col), 32) == 0;
}

/* Drops a damaged result (its row, and with it its chunks), best effort: it can be made again. */
static void sq_drop(sq_conn *c, const char *hash)
{
    if (sq_run(c, SQ_BEGIN, "drop", NULL, 0)) return;
    if (sq_run_hash(c, SQ_RESULT_DELETE, hash, "drop", NULL, 0) ||
        sq_run(c, SQ_COMMIT, "drop", NULL, 0))
        sq_rollback(c);
}

/* Where a put's bytes come from: a buffer, or a file read a chunk at a time into buf. */
typedef struct sq_source {
    const char *mem;
    FILE *f;
    char *buf; /* STORE_CHUNK bytes, for f */
} sq_source;

/* The next n bytes of the source (pos: how many were taken before). */
static const char *sq_source_take(sq_source *src, uint64_t pos, size_t n, uint64_t len, char *err,
                                  size_t errlen)
{
    if (src->mem) return src->mem + pos;
    size_t got = fread(src->buf, 1, n, src->f);
    if (got == n) return src->buf;
    if (ferror(src->f))
        sq_errf(err, errlen, "sqlite result_put: reading the result at byte %llu failed",
                (unsigned long long)(pos + got));
    else
        sq_errf(err, errlen, "sqlite result_put: the file ended after %llu of %llu bytes",
                (unsigned long long)(pos + got), (unsigned long long)len);
    return NULL;
}

static int sq_chunk_put(sq_conn *c, const char *hash, uint64_t off, const char *data, size_t n,
                        char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_CHUNK_PUT, "result_put: chunk", err, errlen);
    unsigned char md[32];
    int rc;
    if (!st) return STORE_ERR;
    sq_digest(data, n, md);
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    sqlite3_bind_int64(st, 2, (sqlite3_int64)off);
    sqlite3_bind_blob64(st, 3, data, n, SQLITE_STATIC);
    sqlite3_bind_blob(st, 4, md, 32, SQLITE_STATIC);
    rc = sqlite3_step(st);
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, "result_put: chunk", c->db);
    sq_done(st);
    return rc == SQLITE_DONE ? STORE_OK : STORE_ERR;
}

/* The chunks now stored under hash: how many and their total bytes. */
static int sq_chunks_sum(sq_conn *c, const char *hash, uint64_t *count, uint64_t *bytes, char *err,
                         size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_CHUNKS_SUM, "result_put: sum", err, errlen);
    int rc;
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        *count = (uint64_t)sqlite3_column_int64(st, 0);
        *bytes = (uint64_t)sqlite3_column_int64(st, 1);
    } else {
        sq_dberr(err, errlen, "result_put: sum", c->db);
    }
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : STORE_ERR;
}

/* A put: the old result of this hash goes, the chunks are written SQ_BATCH bytes per
 * transaction, and the last transaction checks that they are all there (another put of the
 * same hash, or an eviction of it, could have touched them in between), writes the results
 * row and evicts.  A small result is one transaction, as before chunks. */
static int sq_put(sq_store *s, const char *hash, const char *job, uint64_t len, sq_source *src,
                  char *err, size_t errlen)
{
    sq_conn *c = sq_conn_get(s, err, errlen);
    uint64_t pos = 0, nchunks = 0;
    int first = 1;
    if (!c) return STORE_ERR;
    if (len > (uint64_t)INT64_MAX / 2) {
        sq_errf(err, errlen, "sqlite result_put: %llu bytes is too large", (unsigned long long)len);
        return STORE_ERR;
    }
    for (;;) {
        if (sq_run(c, SQ_BEGIN, "result_put: begin", err, errlen)) goto fail_nolock;
        if (first && (sq_run_hash(c, SQ_RESULT_DELETE, hash, "result_put: replace", err, errlen) ||
                      sq_run_hash(c, SQ_CHUNKS_DELETE, hash, "result_put: replace", err, errlen)))
            goto fail;
        first = 0;
        uint64_t batch_end = pos + SQ_BATCH;
        while (pos < len && pos < batch_end) {
            size_t n = len - pos < STORE_CHUNK ? (size_t)(len - pos) : STORE_CHUNK;
            const char *data = sq_source_take(src, pos, n, len, err, errlen);
            if (!data || sq_chunk_put(c, hash, pos, data, n, err, errlen)) goto fail;
            pos += n;
            nchunks++;
        }
        if (pos == len) break;
        if (sq_run(c, SQ_COMMIT, "result_put: commit", err, errlen)) goto fail;
    }
    uint64_t have_n, have_bytes;
    if (sq_chunks_sum(c, hash, &have_n, &have_bytes, err, errlen)) goto fail;
    if (have_n != nchunks || have_bytes != len) {
        sq_errf(err, errlen,
                "sqlite result_put: %llu chunks of %llu bytes written, %llu of %llu found "
                "(another put of the same result meanwhile?)",
                (unsigned long long)nchunks, (unsigned long long)len, (unsigned long long)have_n,
                (unsigned long long)have_bytes);
        goto fail;
    }
    /* the stamp is taken under the write lock: stamps of puts follow the commit order */
    sqlite3_stmt *st = sq_stmt(c, SQ_RESULT_UPSERT, "result_put", err, errlen);
    if (!st) goto fail;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    sqlite3_bind_int64(st, 2, (sqlite3_int64)len);
    sqlite3_bind_double(st, 3, sq_stamp(s));
    if (job && *job) sqlite3_bind_text(st, 4, job, -1, SQLITE_STATIC);
    int rc = sqlite3_step(st);
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, "result_put", c->db);
    sq_done(st);
    if (rc != SQLITE_DONE) goto fail;
    if (s->budget && sq_evict(c, s->budget, hash, err, errlen)) goto fail;
    if (sq_run(c, SQ_COMMIT, "result_put: commit", err, errlen)) goto fail;
    return STORE_OK;
fail:
    sq_rollback(c);
fail_nolock:
    /* chunks committed by earlier batches: gone with the put (best effort; opening the store
     * again deletes any left) */
    if (pos > 0 && !sq_run(c, SQ_BEGIN, "result_put: clean up", NULL, 0)) {
        if (sq_run_hash(c, SQ_CHUNKS_DELETE, hash, "result_put: clean up", NULL, 0) ||
            sq_run(c, SQ_COMMIT, "result_put: clean up", NULL, 0))
            sq_rollback(c);
    }
    return STORE_ERR;
}

static int sq_result_put(store *base, const char *hash, const char *body, size_t len, char *err,
                         size_t errlen)
{
    if (!body && len) {
        sq_errf(err, errlen, "sqlite result_put: %zu bytes with no body", len);
        return STORE_ERR;
    }
    sq_source src = {.mem = body ? body : ""};
    return sq_put((sq_store *)base, hash, NULL, len, &src, err, errlen);
}

static int sq_result_put_file(store *base, const char *hash, const char *job, FILE *f, uint64_t len,
                              char *err, size_t errlen)
{
    if (!f) {
        sq_errf(err, errlen, "sqlite result_put: no file");
        return STORE_ERR;
    }
    sq_source src = {.f = f, .buf = malloc(STORE_CHUNK)};
    if (!src.buf) {
        sq_errf(err, errlen, "sqlite result_put: out of memory");
        return STORE_ERR;
    }
    int rc = sq_put((sq_store *)base, hash, job, len, &src, err, errlen);
    free(src.buf);
    return rc;
}

/* A result's size and mark (no transaction of its own: the caller's, or one snapshot). */
static int sq_head(sq_conn *c, const char *hash, uint64_t *bytes, double *used, char *job,
                   const char *where, char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_RESULT_HEAD, where, err, errlen);
    int rc;
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        *bytes = (uint64_t)sqlite3_column_int64(st, 0);
        *used = sq_column_time(st, 1);
        if (job && sq_column_fixed(st, 2, job, 33)) job[0] = 0;
    } else if (rc != SQLITE_DONE) {
        sq_dberr(err, errlen, where, c->db);
    }
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : rc == SQLITE_DONE ? STORE_NOTFOUND : STORE_ERR;
}

/* Marks a result used now, unless its mark is younger than touch_seconds: a hot result then
 * costs one write per interval instead of one per read (every write takes the database's
 * write lock, and readers queued behind it showed up as a tail of hundreds of ms under load).
 * The LRU order is exact to that resolution.  A result evicted since it was read is left. */
static int sq_touch(sq_store *s, sq_conn *c, const char *hash, double used, const char *where,
                    char *err, size_t errlen)
{
    sqlite3_stmt *st = NULL;
    if (sq_now() - used < s->touch_seconds) return STORE_OK;
    if (sq_run(c, SQ_BEGIN, where, err, errlen)) return STORE_ERR;
    st = sq_stmt(c, SQ_RESULT_TOUCH, where, err, errlen);
    if (!st) goto fail;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    sqlite3_bind_double(st, 2, sq_stamp(s));
    if (sqlite3_step(st) != SQLITE_DONE) {
        sq_dberr(err, errlen, where, c->db);
        goto fail;
    }
    sq_done(st);
    st = NULL;
    if (sq_run(c, SQ_COMMIT, where, err, errlen)) goto fail;
    return STORE_OK;
fail:
    sq_done(st);
    sq_rollback(c);
    return STORE_ERR;
}

/* The body is read in one read transaction (readers run in parallel under WAL), then the
 * small results row is marked in a write transaction of its own.  A result evicted in between
 * is still returned: it was there when read, and its content is fixed by its hash. */
static int sq_result_get(store *base, const char *hash, char **body, size_t *len, char *err,
                         size_t errlen)
{
    sq_store *s = (sq_store *)base;
    sqlite3_stmt *st = NULL;
    char *copy = NULL;
    uint64_t bytes = 0, pos = 0;
    double used = 0;
    int rc;
    sq_conn *c = sq_conn_get(s, err, errlen);
    *body = NULL;
    if (len) *len = 0;
    if (!c) return STORE_ERR;
    if (sq_run(c, SQ_BEGIN_READ, "result_get: begin", err, errlen)) return STORE_ERR;
    rc = sq_head(c, hash, &bytes, &used, NULL, "result_get", err, errlen);
    if (rc) goto out;
    rc = STORE_ERR;
    if (bytes >= SIZE_MAX || !(copy = malloc((size_t)bytes + 1))) {
        sq_errf(err, errlen, "sqlite result_get: out of memory for %llu bytes",
                (unsigned long long)bytes);
        goto out;
    }
    if (!(st = sq_stmt(c, SQ_CHUNKS_ALL, "result_get", err, errlen))) goto out;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    int step;
    while ((step = sqlite3_step(st)) == SQLITE_ROW) {
        uint64_t off = (uint64_t)sqlite3_column_int64(st, 0);
        const void *p = sqlite3_column_blob(st, 1);
        uint64_t n = (uint64_t)sqlite3_column_bytes(st, 1);
        if (!p && n) {
            sq_errf(err, errlen, "sqlite result_get: out of memory");
            goto out;
        }
        if (off != pos || n > bytes - pos) {
            sq_errf(err, errlen,
                    "sqlite result_get: result %.16s... is damaged: a chunk of %llu bytes at "
                    "byte %llu, where %llu of %llu bytes were read",
                    hash, (unsigned long long)n, (unsigned long long)off, (unsigned long long)pos,
                    (unsigned long long)bytes);
            rc = STORE_DAMAGED;
            goto out;
        }
        if (!sq_digest_ok(st, 2, p, (size_t)n)) {
            sq_errf(err, errlen,
                    "sqlite result_get: result %.16s... is damaged: its chunk at byte %llu does "
                    "not match its digest",
                    hash, (unsigned long long)off);
            rc = STORE_DAMAGED;
            goto out;
        }
        if (n) memcpy(copy + pos, p, (size_t)n);
        pos += n;
    }
    if (step != SQLITE_DONE) {
        sq_dberr(err, errlen, "result_get", c->db);
        goto out;
    }
    if (pos != bytes) {
        sq_errf(err, errlen,
                "sqlite result_get: result %.16s... is damaged: its chunks hold %llu of its "
                "%llu bytes",
                hash, (unsigned long long)pos, (unsigned long long)bytes);
        rc = STORE_DAMAGED;
        goto out;
    }
    rc = STORE_OK;
out:
    sq_done(st);
    sq_run(c, SQ_COMMIT, "result_get: end", NULL, 0);
    if (rc == STORE_DAMAGED) sq_drop(c, hash);
    if (rc == STORE_OK) rc = sq_touch(s, c, hash, used, "result_get: mark used", err, errlen);
    if (rc != STORE_OK) {
        free(copy);
        return rc;
    }
    copy[bytes] = 0;
    *body = copy;
    if (len) *len = (size_t)bytes;
    return STORE_OK;
}

static int sq_result_size(store *base, const char *hash, uint64_t *bytes, char *job, char *err,
                          size_t errlen)
{
    sq_store *s = (sq_store *)base;
    double used = 0;
    sq_conn *c = sq_conn_get(s, err, errlen);
    *bytes = 0;
    if (!c) return STORE_ERR;
    if (job) job[0] = 0;
    int rc = sq_head(c, hash, bytes, &used, job, "result_size", err, errlen);
    if (rc == STORE_OK) rc = sq_touch(s, c, hash, used, "result_size: mark used", err, errlen);
    return rc;
}

static int sq_result_chunk(store *base, const char *hash, uint64_t pos, char **data, size_t *len,
                           uint64_t *start, char *err, size_t errlen)
{
    sqlite3_stmt *st;
    int rc;
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    *data = NULL;
    *len = 0;
    *start = 0;
    if (!c) return STORE_ERR;
    if (pos > (uint64_t)INT64_MAX) return STORE_NOTFOUND;
    st = sq_stmt(c, SQ_CHUNK_AT, "result_chunk", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    sqlite3_bind_int64(st, 2, (sqlite3_int64)pos);
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        uint64_t off = (uint64_t)sqlite3_column_int64(st, 0);
        uint64_t n = (uint64_t)sqlite3_column_bytes(st, 1);
        if (pos - off >= n) { /* the chunk that held pos is gone */
            sq_done(st);
            return STORE_NOTFOUND;
        }
        if (sq_column_dup(st, 1, 0, data, len)) {
            sq_errf(err, errlen, "sqlite result_chunk: out of memory");
            sq_done(st);
            return STORE_ERR;
        }
        if (!sq_digest_ok(st, 2, *data, *len)) {
            sq_errf(err, errlen,
                    "sqlite result_chunk: result %.16s... is damaged: its chunk at byte %llu does "
                    "not match its digest",
                    hash, (unsigned long long)off);
            sq_done(st);
            free(*data);
            *data = NULL;
            *len = 0;
            sq_drop(c, hash);
            return STORE_DAMAGED;
        }
        *start = off;
    } else if (rc != SQLITE_DONE) {
        sq_dberr(err, errlen, "result_chunk", c->db);
    }
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : rc == SQLITE_DONE ? STORE_NOTFOUND : STORE_ERR;
}

static int sq_result_exists(store *base, const char *hash, char *err, size_t errlen)
{
    sqlite3_stmt *st;
    int rc;
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    st = sq_stmt(c, SQ_RESULT_EXISTS, "result_exists", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    rc = sqlite3_step(st);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) sq_dberr(err, errlen, "result_exists", c->db);
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : rc == SQLITE_DONE ? STORE_NOTFOUND : STORE_ERR;
}

static int sq_result_stats(store *base, size_t *count, uint64_t *bytes, char *err, size_t errlen)
{
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (count) *count = 0;
    if (bytes) *bytes = 0;
    if (!c) return STORE_ERR;
    return sq_totals(c, "result_stats", count, bytes, err, errlen);
}

/* PRAGMA integrity_check (every line it reports but "ok", joined with "; "), then the
 * result_totals row against a recount of the table, in one snapshot. */
static int sq_check(store *base, char *err, size_t errlen)
{
    sqlite3_stmt *st;
    int rc, bad = 0;
    size_t used = 0;
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    st = sq_stmt(c, SQ_INTEGRITY, "check", err, errlen);
    if (!st) return STORE_ERR;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        const char *line = (const char *)sqlite3_column_text(st, 0);
        if (line && strcmp(line, "ok") == 0) continue;
        if (err && errlen && used + 1 < errlen) {
            int k = snprintf(err + used, errlen - used, "%s%s",
                             bad ? "; " : "sqlite check: ", line ? line : "(null)");
            used += k > 0 ? (size_t)k : 0;
            if (used >= errlen) used = errlen - 1;
        }
        bad = 1;
    }
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, "check", c->db);
    sq_done(st);
    if (rc != SQLITE_DONE || bad) return STORE_ERR;
    st = sq_stmt(c, SQ_TOTALS_RECOUNT, "check: totals", err, errlen);
    if (!st) return STORE_ERR;
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        sqlite3_int64 n0 = sqlite3_column_int64(st, 0), b0 = sqlite3_column_int64(st, 1);
        sqlite3_int64 n1 = sqlite3_column_int64(st, 2), b1 = sqlite3_column_int64(st, 3);
        sqlite3_int64 nsize = sqlite3_column_int64(st, 4), noff = sqlite3_column_int64(st, 5);
        if (n0 != n1 || b0 != b1) {
            sq_errf(err, errlen,
                    "sqlite check: result_totals says %lld results of %lld bytes, the table "
                    "holds %lld of %lld",
                    (long long)n0, (long long)b0, (long long)n1, (long long)b1);
            bad = 1;
        } else if (nsize || noff) {
            sq_errf(err, errlen,
                    "sqlite check: of %lld results, %lld have chunks that do not add up to their "
                    "size; %lld chunks do not start where the one before ends",
                    (long long)n1, (long long)nsize, (long long)noff);
            bad = 1;
        }
    } else if (rc == SQLITE_DONE) {
        sq_errf(err, errlen, "sqlite check: the result_totals row is missing");
        bad = 1;
    } else {
        sq_dberr(err, errlen, "check: totals", c->db);
    }
    sq_done(st);
    if (rc != SQLITE_ROW || bad) return STORE_ERR;
    /* every chunk of every result against its digest */
    long long nbad = 0, nall = 0;
    st = sq_stmt(c, SQ_CHUNKS_EVERY, "check: digests", err, errlen);
    if (!st) return STORE_ERR;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        nall++;
        nbad +=
            !sq_digest_ok(st, 1, sqlite3_column_blob(st, 0), (size_t)sqlite3_column_bytes(st, 0));
    }
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, "check: digests", c->db);
    sq_done(st);
    if (rc == SQLITE_DONE && nbad)
        sq_errf(err, errlen, "sqlite check: %lld of %lld chunks do not match their digest", nbad,
                nall);
    return rc != SQLITE_DONE || nbad ? STORE_ERR : STORE_OK;
}

/* A small write (the totals row rewritten as it is), rolled into the database like any other:
 * it fails when the file is read-only, the disk refuses, or the lock cannot be had. */
static int sq_writable(store *base, char *err, size_t errlen)
{
    sq_conn *c = sq_conn_get((sq_store *)base, err, errlen);
    int rc = STORE_ERR;
    if (!c) return STORE_ERR;
    /* a probe waits a second for the lock, not the writers' five: a lock held that long
     * (a put holds it for a batch of chunks: ~0.1 s) means the store is stuck for writers */
    sqlite3_busy_timeout(c->db, SQ_PROBE_BUSY_MS);
    if (!sq_run(c, SQ_BEGIN, "writable: begin", err, errlen)) {
        if (sq_run(c, SQ_PROBE, "writable", err, errlen) ||
            sq_run(c, SQ_COMMIT, "writable: commit", err, errlen))
            sq_rollback(c);
        else
            rc = STORE_OK;
    }
    sqlite3_busy_timeout(c->db, SQ_BUSY_MS);
    return rc;
}

/* Finalizes and closes every connection of the store, on whichever thread opened it (see the
 * file comment: no other thread may be using the store). */
static void sq_close(store *base)
{
    sq_store *s = (sq_store *)base;
    sq_conn *c;
    if (!s) return;
    /* first, so that no thread exiting from now on runs the destructor on a conn freed here */
    if (s->key_made) pthread_key_delete(s->key);
    pthread_mutex_lock(&s->mu);
    c = s->conns;
    s->conns = NULL;
    pthread_mutex_unlock(&s->mu);
    while (c) {
        sq_conn *next = c->next;
        sq_conn_close(c);
        c = next;
    }
    pthread_mutex_destroy(&s->mu);
    if (s->lock_fd >= 0) close(s->lock_fd);
    free(s->path);
    free(s);
}

static const store_ops sq_ops = {
    .job_submit = sq_job_submit,
    .job_claim = sq_job_claim,
    .job_renew = sq_job_renew,
    .job_finish = sq_job_finish,
    .job_release = sq_job_release,
    .jobs_requeue = sq_jobs_requeue,
    .job_insert = sq_job_insert,
    .job_get = sq_job_get,
    .job_counts = sq_job_counts,
    .jobs_prune = sq_jobs_prune,
    .sub_get = sq_sub_get,
    .sub_cancel = sq_sub_cancel,
    .wait_event = NULL, /* one daemon per file: nobody else makes events */
    .result_put = sq_result_put,
    .result_put_file = sq_result_put_file,
    .result_get = sq_result_get,
    .result_size = sq_result_size,
    .result_chunk = sq_result_chunk,
    .result_exists = sq_result_exists,
    .result_stats = sq_result_stats,
    .check = sq_check,
    .writable = sq_writable,
    .close = sq_close,
};

/* ---- opening ---- */

/* PRAGMA user_version into *v (the first read of the file: a file that is no database fails
 * here); a version this cellard does not know is an error too. */
static int sq_user_version(sq_conn *c, const char *path, int *v, char *err, size_t errlen)
{
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(c->db, "PRAGMA user_version", -1, &st, NULL);
    if (rc == SQLITE_OK) rc = sqlite3_step(st);
    if (rc == SQLITE_ROW)
        *v = sqlite3_column_int(st, 0);
    else
        sq_open_err(err, errlen, path, c->db, rc);
    sqlite3_finalize(st);
    if (rc != SQLITE_ROW) return STORE_ERR;
    if (*v > SQ_VERSION) {
        sq_errf(err, errlen,
                "sqlite open %s: database schema version %d is newer than this cellard "
                "(which knows versions up to %d)",
                path, *v, SQ_VERSION);
        return STORE_ERR;
    }
    if (*v < 0) {
        sq_errf(err, errlen, "sqlite open %s: database schema version %d is not ours", path, *v);
        return STORE_ERR;
    }
    return STORE_OK;
}

static int sq_exec(sq_conn *c, const char *sql, const char *where, char *err, size_t errlen)
{
    char *msg = NULL;
    if (sqlite3_exec(c->db, sql, NULL, NULL, &msg) == SQLITE_OK) return STORE_OK;
    sq_errf(err, errlen, "sqlite %s: %s", where, msg ? msg : sqlite3_errmsg(c->db));
    sqlite3_free(msg);
    return STORE_ERR;
}

/* The first column of the one row of sql, an integer. */
static int sq_int(sq_conn *c, const char *sql, long long *out, const char *path, char *err,
                  size_t errlen)
{
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(c->db, sql, -1, &st, NULL);
    if (rc == SQLITE_OK) rc = sqlite3_step(st);
    if (rc == SQLITE_ROW)
        *out = sqlite3_column_int64(st, 0);
    else
        sq_open_err(err, errlen, path, c->db, rc);
    sqlite3_finalize(st);
    return rc == SQLITE_ROW ? STORE_OK : STORE_ERR;
}

/* Whether the file is a store of ours (or, flags STORE_OPEN_INIT, may become one): made by
 * cellard (its application_id), or by a cellard from before the id (schema version 1 or more
 * and our tables), or new (existed: 0).  An empty file that was there, or a database of
 * something else, is refused: a truncated file or a wrong --db must not quietly become an
 * empty cache, losing the queued jobs. */
static int sq_identify(sq_conn *c, const char *path, int v, int existed, off_t size, int flags,
                       char *err, size_t errlen)
{
    long long app = 0, ntab = 0, ours = 0;
    if (!existed || (flags & STORE_OPEN_INIT)) return STORE_OK;
    if (size == 0) {
        sq_errf(err, errlen,
                "sqlite open %s: the file is empty, not a cellar store (truncated?): restore it, "
                "or start with --init to make a new store in it",
                path);
        return STORE_ERR;
    }
    if (sq_int(c, "PRAGMA application_id", &app, path, err, errlen) ||
        sq_int(c, "SELECT count(*) FROM sqlite_master WHERE type = 'table'", &ntab, path, err,
               errlen) ||
        sq_int(c,
               "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name IN ('jobs',"
               " 'results', 'result_totals')",
               &ours, path, err, errlen))
        return STORE_ERR;
    if (app == SQ_APP_ID || (app == 0 && v >= 1 && ours == 3)) return STORE_OK;
    sq_errf(err, errlen,
            "sqlite open %s: a SQLite database of something else (application_id %lld, schema "
            "version %d, %lld tables), not a cellar store: check --db, or start with --init to "
            "add cellar's tables to it",
            path, app, v, ntab);
    return STORE_ERR;
}

/* PRAGMA quick_check: a damaged file is refused rather than served from. */
static int sq_quick_check(sq_conn *c, const char *path, char *err, size_t errlen)
{
    sqlite3_stmt *st = NULL;
    char first[200] = "";
    int rc = sqlite3_prepare_v2(c->db, "PRAGMA quick_check", -1, &st, NULL), bad = 0;
    while (rc == SQLITE_OK && (rc = sqlite3_step(st)) == SQLITE_ROW) {
        const char *line = (const char *)sqlite3_column_text(st, 0);
        if (line && !strcmp(line, "ok")) continue;
        if (!bad++) snprintf(first, sizeof first, "%s", line ? line : "(null)");
    }
    if (rc == SQLITE_ROW) rc = SQLITE_DONE;
    if (rc != SQLITE_DONE && rc != SQLITE_OK && !bad)
        snprintf(first, sizeof first, "%s", sqlite3_errmsg(c->db));
    sqlite3_finalize(st);
    if (!bad && (rc == SQLITE_DONE || rc == SQLITE_OK)) return STORE_OK;
    sq_errf(err, errlen,
            "sqlite open %s: the database is damaged (quick_check: %s%s): restore it from a "
            "backup, or move it away to start with an empty store (the cached results and the "
            "queued jobs in it would be lost)",
            path, first, bad > 1 ? "; and more" : "");
    return STORE_ERR;
}

/* Chunks without a digest (moved from schema version 1) get theirs, once. */
static int sq_fill_digests(sq_conn *c, const char *path, char *err, size_t errlen)
{
    long long n = 0;
    if (sq_int(c, "SELECT count(*) FROM result_chunks WHERE sha IS NULL", &n, path, err, errlen))
        return STORE_ERR;
    if (n == 0) return STORE_OK;
    sqlite3_int64 *ids = malloc((size_t)n * sizeof *ids);
    sqlite3_stmt *sel = NULL, *one = NULL, *upd = NULL;
    long long k = 0;
    int rc = ids ? SQLITE_OK : SQLITE_NOMEM;
    if (rc == SQLITE_OK)
        rc = sqlite3_prepare_v2(c->db, "SELECT rowid FROM result_chunks WHERE sha IS NULL", -1,
                                &sel, NULL);
    while (rc == SQLITE_OK && k < n && sqlite3_step(sel) == SQLITE_ROW)
        ids[k++] = sqlite3_column_int64(sel, 0);
    if (rc == SQLITE_OK)
        rc = sqlite3_prepare_v2(c->db, "SELECT body FROM result_chunks WHERE rowid = ?1", -1, &one,
                                NULL);
    if (rc == SQLITE_OK)
        rc = sqlite3_prepare_v2(c->db, "UPDATE result_chunks SET sha = ?2 WHERE rowid = ?1", -1,
                                &upd, NULL);
    if (rc == SQLITE_OK) rc = sqlite3_exec(c->db, "BEGIN IMMEDIATE", NULL, NULL, NULL);
    for (long long i = 0; rc == SQLITE_OK && i < k; i++) {
        unsigned char md[32];
        sqlite3_bind_int64(one, 1, ids[i]);
        if (sqlite3_step(one) != SQLITE_ROW) {
            rc = SQLITE_ERROR;
            break;
        }
        sq_digest(sqlite3_column_blob(one, 0), (size_t)sqlite3_column_bytes(one, 0), md);
        sqlite3_reset(one);
        sqlite3_bind_int64(upd, 1, ids[i]);
        sqlite3_bind_blob(upd, 2, md, 32, SQLITE_TRANSIENT);
        if (sqlite3_step(upd) != SQLITE_DONE) rc = SQLITE_ERROR;
        sqlite3_reset(upd);
    }
    if (rc == SQLITE_OK) rc = sqlite3_exec(c->db, "COMMIT", NULL, NULL, NULL);
    if (rc != SQLITE_OK) {
        sq_errf(err, errlen, "sqlite open %s: digests of the moved results: %s", path,
                ids ? sqlite3_errmsg(c->db) : "out of memory");
        if (!sqlite3_get_autocommit(c->db)) sqlite3_exec(c->db, "ROLLBACK", NULL, NULL, NULL);
    }
    sqlite3_finalize(sel);
    sqlite3_finalize(one);
    sqlite3_finalize(upd);
    free(ids);
    return rc == SQLITE_OK ? STORE_OK : STORE_ERR;
}

/* Brings the schema to SQ_VERSION, all migrations in one transaction.  The version is read
 * again under the write lock: another process may have migrated in between. */
static int sq_migrate(sq_conn *c, const char *path, char *err, size_t errlen)
{
    char sql[64], where[64];
    int v;
    long long app = 0;
    if (sq_user_version(c, path, &v, err, errlen) ||
        sq_int(c, "PRAGMA application_id", &app, path, err, errlen))
        return STORE_ERR;
    if (v == SQ_VERSION && app == SQ_APP_ID) return STORE_OK;
    if (sq_exec(c, "BEGIN IMMEDIATE", "open: begin", err, errlen)) return STORE_ERR;
    if (sq_user_version(c, path, &v, err, errlen)) goto fail;
    for (; v < SQ_VERSION; v++) {
        snprintf(where, sizeof where, "open: migration to schema version %d", v + 1);
        if (sq_exec(c, sq_migrations[v], where, err, errlen)) goto fail;
    }
    snprintf(sql, sizeof sql, "PRAGMA user_version = %d", SQ_VERSION);
    if (sq_exec(c, sql, "open: user_version", err, errlen) ||
        sq_exec(c, "PRAGMA application_id = " SQ_APP_ID_TEXT, "open: application_id", err,
                errlen) ||
        sq_exec(c, "COMMIT", "open: commit", err, errlen))
        goto fail;
    return STORE_OK;
fail:
    if (!sqlite3_get_autocommit(c->db)) sqlite3_exec(c->db, "ROLLBACK", NULL, NULL, NULL);
    return STORE_ERR;
}

/* Switches the file to WAL (a property of the file, kept across opens). */
static int sq_wal(sq_conn *c, const char *path, char *err, size_t errlen)
{
    sqlite3_stmt *st = NULL;
    int ok = 0, rc = sqlite3_prepare_v2(c->db, "PRAGMA journal_mode=WAL", -1, &st, NULL);
    if (rc == SQLITE_OK) rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        const char *mode = (const char *)sqlite3_column_text(st, 0);
        ok = mode && strcmp(mode, "wal") == 0;
        if (!ok)
            sq_errf(err, errlen, "sqlite open %s: journal_mode=WAL refused (mode is %s)", path,
                    mode ? mode : "unknown");
    } else {
        sq_errf(err, errlen, "sqlite open %s: journal_mode=WAL: %s", path, sqlite3_errmsg(c->db));
    }
    sqlite3_finalize(st);
    return ok ? STORE_OK : STORE_ERR;
}

/* The largest last_used in the file, so stamps keep increasing across a restart even if the
 * clock went back. */
static int sq_load_stamp(sq_conn *c, sq_store *s, char *err, size_t errlen)
{
    sqlite3_stmt *st = NULL;
    int rc = sqlite3_prepare_v2(c->db, "SELECT max(last_used) FROM results", -1, &st, NULL);
    if (rc == SQLITE_OK) rc = sqlite3_step(st);
    if (rc == SQLITE_ROW)
        s->last_stamp = sq_column_time(st, 0);
    else
        sq_errf(err, errlen, "sqlite open %s: %s", s->path, sqlite3_errmsg(c->db));
    sqlite3_finalize(st);
    return rc == SQLITE_ROW ? STORE_OK : STORE_ERR;
}

/* One daemon per file: the queue's leases need every daemon to see the others, and a store
 * that opens deletes the chunks of puts under way and requeues every running job.  An
 * exclusive flock on path + "-lock" (kept while the store is open; the kernel drops it with
 * the process, however it ends) makes a second daemon on the same file stop with a message. */
static int sq_lock(sq_store *s, char *err, size_t errlen)
{
    char lp[4200];
    snprintf(lp, sizeof lp, "%s-lock", s->path);
    s->lock_fd = open(lp, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (s->lock_fd < 0) {
        sq_errf(err, errlen, "sqlite open %s: cannot open its lock file %s: %s", s->path, lp,
                strerror(errno));
        return STORE_ERR;
    }
    if (flock(s->lock_fd, LOCK_EX | LOCK_NB) == 0) return STORE_OK;
    if (errno == EWOULDBLOCK)
        sq_errf(err, errlen,
                "sqlite open %s: another cellard is using this database (one daemon per SQLite "
                "file; to run several daemons, give them one PostgreSQL database: --db "
                "postgresql://...)",
                s->path);
    else
        sq_errf(err, errlen, "sqlite open %s: cannot lock %s: %s", s->path, lp, strerror(errno));
    return STORE_ERR;
}

store *store_sqlite_open(const char *path, uint64_t budget_bytes, double touch_seconds, int flags,
                         char *err, size_t errlen)
{
    sq_store *s = NULL;
    sq_conn *c = NULL;
    int mu_made = 0, v;
    struct stat sb;
    if (!path || !*path) {
        sq_errf(err, errlen, "sqlite open: no path");
        return NULL;
    }
    if (!sqlite3_threadsafe()) {
        sq_errf(err, errlen, "sqlite open: this libsqlite3 was built without thread support");
        return NULL;
    }
    s = calloc(1, sizeof *s);
    if (!s || !(s->path = strdup(path))) {
        sq_errf(err, errlen, "sqlite open %s: out of memory", path);
        goto fail;
    }
    s->base.ops = &sq_ops;
    s->lock_fd = -1;
    s->budget = budget_bytes;
    s->touch_seconds = touch_seconds > 0 ? touch_seconds : 0;
    if (pthread_mutex_init(&s->mu, NULL) != 0) {
        sq_errf(err, errlen, "sqlite open %s: pthread_mutex_init failed", path);
        goto fail;
    }
    mu_made = 1;
    if (pthread_key_create(&s->key, sq_conn_release) != 0) {
        sq_errf(err, errlen, "sqlite open %s: pthread_key_create failed", path);
        goto fail;
    }
    s->key_made = 1;
    if (sq_lock(s, err, errlen)) goto fail;
    int existed = stat(path, &sb) == 0;
    if (sq_conn_open(s, 1, &c, err, errlen)) goto fail;
    /* the version, what the file is and whether it is sound first: refuse a newer database,
     * a file that is no database, someone else's or a damaged one before changing anything */
    if (sq_user_version(c, path, &v, err, errlen) ||
        sq_identify(c, path, v, existed, existed ? sb.st_size : 0, flags, err, errlen) ||
        sq_quick_check(c, path, err, errlen) || sq_wal(c, path, err, errlen) ||
        sq_migrate(c, path, err, errlen) || sq_fill_digests(c, path, err, errlen) ||
        sq_load_stamp(c, s, err, errlen) ||
        sq_exec(c, "DELETE FROM result_chunks WHERE hash NOT IN (SELECT hash FROM results)",
                "open: deleting the chunks of unfinished puts", err, errlen))
        goto fail;
    if (pthread_setspecific(s->key, c) != 0) {
        sq_errf(err, errlen, "sqlite open %s: pthread_setspecific failed", path);
        goto fail;
    }
    s->conns = c; /* this thread's connection from now on */
    return &s->base;
fail:
    sq_conn_close(c);
    if (s) {
        if (s->key_made) pthread_key_delete(s->key);
        if (mu_made) pthread_mutex_destroy(&s->mu);
        if (s->lock_fd >= 0) close(s->lock_fd);
        free(s->path);
        free(s);
    }
    return NULL;
}
