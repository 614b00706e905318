/* store_sqlite.c — the SQLite backend of the store (server/store.h): one database file in WAL
 * mode holding the jobs and the result cache.  It gives the primitives of server/store_be.h
 * (one statement each, on the calling thread's connection); the policy over them (which
 * statements make an operation, reading results back against their digests, eviction, the
 * queue's rules) is store.c's.  What is SQLite's own stays here: the schema and its migrations,
 * opening and identifying the file, the lock of one daemon per file, the strictly increasing
 * stamps, and every write frame taking the write lock up front (BEGIN IMMEDIATE).
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
 *   - last_used stamps handed out by one store strictly increase (sq_be_stamp: the clock, or a
 *     microsecond past the last stamp when the clock has not moved or went back), so "least
 *     recently used" is a total order even within one clock tick.
 *   - Every write is one BEGIN IMMEDIATE ... COMMIT, rolled back on any error: a writer takes
 *     the write lock up front and waits for it under the busy timeout, instead of failing to
 *     upgrade a read lock half-way (SQLITE_BUSY_SNAPSHOT).  Readers never block in WAL mode.
 *
 * Threads: any thread may call any op.  Each thread gets its own connection (opened on its
 * first call, SQLITE_OPEN_NOMUTEX, with its own cache of prepared statements), kept by the
 * per-thread registry of server/store_conn.h: a pthread key whose destructor closes it when
 * the thread exits, and the list of all of them, so that close() can finalize and close every
 * one; close() must therefore not run while another thread still uses the store or is exiting
 * after having used it (the daemon closes the store after joining its workers and stopping
 * the HTTP server).  mu guards last_stamp only; no lock is held while talking to SQLite.  A
 * callback of jobs_unfinished() runs with no statement active, so it may call any op of the
 * same store.  One daemon uses a file at a time (opening deletes the chunks of puts under way
 * elsewhere).
 *
 * Ownership: strings passed in are borrowed; error, request and body handed out are malloc'd
 * copies, NUL-terminated one byte past their length, which the caller frees.
 */
#include "server/store.h"

#include "core/util.h"
#include "server/store_be.h"
#include "server/store_conn.h"

#include <openssl/evp.h>
#include <pthread.h>
#include <sqlite3.h>
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
    [SQ_INTEGRITY] = "PRAGMA integrity_check",
    /* the columns up to bad_off (no count of chunks of no result: a put under way has some) */
    [SQ_TOTALS_RECOUNT] = STORE_SQL_RECOUNT " FROM result_totals t WHERE t.id = 0",
};

typedef struct sq_store sq_store;

typedef struct store_conn sq_conn;

struct store_conn {
    store_conn_link link;        /* first member: in the store's registry (server/store_conn.h) */
    sqlite3 *db;                 /* used by one thread only (or by close) */
    sqlite3_stmt *stmt[SQ_NSQL]; /* prepared on first use, finalized when the conn closes */
};

struct sq_store {
    store base;         /* first member: a store * of this backend is a sq_store * */
    char *path;         /* the database file */
    store_conns conns;  /* every thread's sq_conn */
    pthread_mutex_t mu; /* guards last_stamp */
    double last_stamp;  /* the latest last_used handed out (or found at open) */
    int mu_made;        /* mu is valid (for the cleanup path of open) */
    int lock_fd;        /* path + "-lock", flock'd: one daemon per file (-1: none) */
};

/* "sqlite WHERE: SQLite's message of the connection's last error" */
static void sq_dberr(char *err, size_t errlen, const char *where, sqlite3 *db)
{
    util_seterr(err, errlen, STORE_ERR, "sqlite %s: %s", where,
                db ? sqlite3_errmsg(db) : "out of memory");
}

/* An error while opening path; the first read of a file that is no database says so. */
static void sq_open_err(char *err, size_t errlen, const char *path, sqlite3 *db, int rc)
{
    if ((rc & 0xff) == SQLITE_NOTADB)
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: not a SQLite database (%s)", path,
                    sqlite3_errmsg(db));
    else
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: %s", path, sqlite3_errmsg(db));
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
static void sq_be_rollback(sq_conn *c)
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

/* Opens a connection to s->path (creating the file if create), with this backend's per-connection
 * settings; not yet registered anywhere.  *out is the conn, or NULL on failure. */
static int sq_conn_open(sq_store *s, int create, sq_conn **out, char *err, size_t errlen)
{
    int rc, flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX | (create ? SQLITE_OPEN_CREATE : 0);
    sq_conn *c = calloc(1, sizeof *c);
    *out = NULL;
    if (!c) {
        util_seterr(err, errlen, STORE_ERR, "sqlite open: out of memory");
        return STORE_ERR;
    }
    if (sqlite3_open_v2(s->path, &c->db, flags, NULL) != SQLITE_OK) {
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: %s", s->path,
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

/* The registry's open: a connection of the calling thread to an existing file. */
static store_conn *sq_conn_new(void *s, char *err, size_t errlen)
{
    sq_conn *c;
    return sq_conn_open(s, 0, &c, err, errlen) ? NULL : c;
}

/* A last_used stamp: now, but strictly after every stamp this store handed out before. */
static double sq_be_stamp(store *base)
{
    sq_store *s = (sq_store *)base;
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

/* Steps a statement bound by the caller to its end: STORE_OK, or STORE_ERR with the message;
 * *changed (may be NULL) gets whether it changed a row. */
static int sq_step_done(sq_conn *c, sqlite3_stmt *st, int *changed, const char *where, char *err,
                        size_t errlen)
{
    int rc = sqlite3_step(st);
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, where, c->db);
    sq_done(st);
    if (changed) *changed = sqlite3_changes(c->db) > 0;
    return rc == SQLITE_DONE ? STORE_OK : STORE_ERR;
}

/* Runs a statement whose ?1 is a text key (a hash, an id) and that returns no row. */
static int sq_run_key(sq_conn *c, enum sq_sql id, const char *key, int *changed, const char *where,
                      char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, id, where, err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, key, -1, SQLITE_STATIC);
    return sq_step_done(c, st, changed, where, err, errlen);
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
            util_seterr(err, errlen, STORE_ERR, "sqlite %s: an id too long in the database", where);
            out_rc = STORE_ERR;
        }
    }
    sq_done(st);
    return out_rc;
}

/* ---- connections and transactions (store_be.h) ---- */

static store_conn *sq_be_conn(store *s, char *err, size_t errlen)
{
    return store_conns_get(&((sq_store *)s)->conns, err, errlen);
}

/* Every frame is a transaction: a write one takes the write lock up front (BEGIN IMMEDIATE),
 * STORE_TX_ONE included, so a writer waits for the lock under the busy timeout instead of
 * failing to upgrade a read lock half-way (SQLITE_BUSY_SNAPSHOT). */
static int sq_be_begin(sq_conn *c, store_tx tx, const char *where, char *err, size_t errlen)
{
    return sq_run(c, tx == STORE_TX_READ ? SQ_BEGIN_READ : SQ_BEGIN, where, err, errlen);
}

static int sq_be_commit(sq_conn *c, const char *where, char *err, size_t errlen)
{
    return sq_run(c, SQ_COMMIT, where, err, errlen);
}

/* ---- jobs and submissions ---- */

static int sq_be_sub_write(sq_conn *c, const store_sub *sub, const char *where, char *err,
                           size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_SUB_INSERT, where, err, errlen);
    int changed;
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, sub->id, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 2, sub->job, -1, SQLITE_STATIC);
    sq_bind_time(st, 3, sub->created);
    sq_bind_time(st, 4, sub->canceled);
    if (sq_step_done(c, st, &changed, where, err, errlen)) return STORE_ERR;
    if (changed) return STORE_OK;
    util_seterr(err, errlen, STORE_ERR, "sqlite %s: no job %s", where, sub->job);
    return STORE_NOTFOUND;
}

static int sq_be_job_write(sq_conn *c, const store_job *j, const char *where, char *err,
                           size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_JOB_INSERT, where, err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, j->id, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 2, j->hash, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 3, j->kind, -1, SQLITE_STATIC);
    sqlite3_bind_int(st, 4, (int)j->state);
    sq_bind_time(st, 5, j->created);
    sq_bind_time(st, 6, j->started);
    sq_bind_time(st, 7, j->finished);
    if (j->error_status) sqlite3_bind_int(st, 8, j->error_status);
    if (j->error) sqlite3_bind_text(st, 9, j->error, -1, SQLITE_STATIC);
    /* a non-NULL pointer even for 0 bytes: a NULL one would bind SQL NULL */
    sqlite3_bind_blob64(st, 10, j->request ? j->request : "", j->request_len, SQLITE_STATIC);
    if (sq_step_done(c, st, NULL, where, err, errlen)) return STORE_ERR;
    store_sub first = {.created = j->created,
                       .canceled = j->state == JOB_CANCELED ? j->finished : 0};
    memcpy(first.id, j->id, sizeof first.id);
    memcpy(first.job, j->id, sizeof first.job);
    return sq_be_sub_write(c, &first, where, err, errlen) == STORE_OK ? STORE_OK : STORE_ERR;
}

/* Reads job id (one statement is one snapshot: no transaction of its own). */
static int sq_be_job_read(sq_conn *c, const char *id, store_job *out, char *err, size_t errlen)
{
    int rc;
    memset(out, 0, sizeof *out);
    sqlite3_stmt *st = sq_stmt(c, SQ_JOB_GET, "job_get", err, errlen);
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
        util_seterr(err, errlen, STORE_ERR,
                    "sqlite job_get %s: a text field too long in the database", id);
        goto fail;
    }
    out->state = (job_state)sqlite3_column_int(st, 3);
    out->created = sq_column_time(st, 4);
    out->started = sq_column_time(st, 5);
    out->finished = sq_column_time(st, 6);
    out->error_status = sqlite3_column_int(st, 7);
    if (sq_column_dup(st, 8, 1, &out->error, NULL) ||
        sq_column_dup(st, 9, 0, &out->request, &out->request_len)) {
        util_seterr(err, errlen, STORE_ERR, "sqlite job_get %s: out of memory", id);
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

/* The only writer needs no row lock: the write transaction is the lock. */
static int sq_be_job_active(sq_conn *c, const char *hash, char *id, char *err, size_t errlen)
{
    return sq_lookup(c, SQ_JOB_ACTIVE, hash, NULL, id, "job_submit", err, errlen);
}

/* An UPDATE ... RETURNING id, then the row read, in one write transaction of its own. */
static int sq_be_job_claim(sq_conn *c, const char *owner, double now, double until, store_job *out,
                           char *err, size_t errlen)
{
    char id[33];
    if (sq_run(c, SQ_BEGIN, "job_claim: begin", err, errlen)) return STORE_ERR;
    sqlite3_stmt *st = sq_stmt(c, SQ_JOB_CLAIM, "job_claim", err, errlen);
    if (!st) goto fail;
    sqlite3_bind_text(st, 1, owner, -1, SQLITE_STATIC);
    sqlite3_bind_double(st, 2, now);
    sqlite3_bind_double(st, 3, until);
    int rc = sqlite3_step(st), found = rc == SQLITE_ROW;
    if (found && sq_column_fixed(st, 0, id, sizeof id)) rc = SQLITE_MISMATCH;
    if (found && rc == SQLITE_ROW) rc = sqlite3_step(st); /* to its end: the update is done */
    if (rc != SQLITE_DONE) {
        if (rc == SQLITE_MISMATCH)
            util_seterr(err, errlen, STORE_ERR, "sqlite job_claim: an id too long in the database");
        else
            sq_dberr(err, errlen, "job_claim", c->db);
        sq_done(st);
        goto fail;
    }
    sq_done(st);
    if (found && sq_be_job_read(c, id, out, err, errlen) != STORE_OK) goto fail;
    if (sq_run(c, SQ_COMMIT, "job_claim: commit", err, errlen)) goto fail;
    return found ? STORE_OK : STORE_NOTFOUND;
fail:
    store_job_clear(out);
    sq_be_rollback(c);
    return STORE_ERR;
}

static int sq_be_job_set(sq_conn *c, const store_set *a, int *cancel, const char *where, char *err,
                         size_t errlen)
{
    static const enum sq_sql sql[] = {[STORE_SET_RENEW] = SQ_JOB_RENEW,
                                      [STORE_SET_FINISH] = SQ_JOB_FINISH,
                                      [STORE_SET_RELEASE] = SQ_JOB_RELEASE};
    sqlite3_stmt *st = sq_stmt(c, sql[a->kind], where, err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, a->id, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 2, a->owner, -1, SQLITE_STATIC);
    if (a->kind == STORE_SET_RENEW) {
        sqlite3_bind_double(st, 3, a->until);
        if (a->stage) sqlite3_bind_text(st, 4, a->stage, -1, SQLITE_STATIC);
        sqlite3_bind_double(st, 5, a->fraction);
    } else if (a->kind == STORE_SET_FINISH) {
        sqlite3_bind_int(st, 3, (int)a->state);
        sq_bind_time(st, 4, a->when);
        if (a->error_status) sqlite3_bind_int(st, 5, a->error_status);
        if (a->error) sqlite3_bind_text(st, 6, a->error, -1, SQLITE_STATIC);
    } else {
        sqlite3_bind_double(st, 3, a->when);
    }
    int rc = sqlite3_step(st), changed;
    if (rc == SQLITE_ROW) { /* RETURNING: the first column, then to the end */
        if (cancel) *cancel = sqlite3_column_int(st, 0);
        changed = 1;
        rc = sqlite3_step(st);
    } else {
        changed = sqlite3_changes(c->db) > 0;
    }
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, where, c->db);
    sq_done(st);
    return rc != SQLITE_DONE ? STORE_ERR : changed ? STORE_OK : STORE_NOTFOUND;
}

/* No events to make (one daemon per file): ended and *queued are left alone. */
static int sq_be_jobs_requeue(sq_conn *c, double now, int all, int max_attempts, const char *msg,
                              int (*ended)(void *ctx, const char *id), void *ctx, size_t *n,
                              int *queued, char *err, size_t errlen)
{
    (void)ended;
    (void)ctx;
    (void)queued;
    sqlite3_stmt *st = sq_stmt(c, SQ_JOBS_REQUEUE, "jobs_requeue", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_double(st, 1, now);
    sqlite3_bind_int(st, 2, all != 0);
    sqlite3_bind_int(st, 3, max_attempts);
    sqlite3_bind_text(st, 4, msg, -1, SQLITE_STATIC);
    if (sq_step_done(c, st, NULL, "jobs_requeue", err, errlen)) return STORE_ERR;
    *n = (size_t)sqlite3_changes64(c->db);
    return STORE_OK;
}

static int sq_be_job_counts(sq_conn *c, size_t *queued, size_t *running, const char *where,
                            char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_JOB_COUNTS, where, err, errlen);
    if (!st) return STORE_ERR;
    int rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        *queued = (size_t)sqlite3_column_int64(st, 0);
        if (running) *running = (size_t)sqlite3_column_int64(st, 1);
    } else {
        sq_dberr(err, errlen, where, c->db);
    }
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : STORE_ERR;
}

static int sq_be_jobs_prune(sq_conn *c, double before, size_t keep, size_t *n, char *err,
                            size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_JOBS_PRUNE, "jobs_prune", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_double(st, 1, before);
    if (keep && keep < (size_t)INT64_MAX)
        sqlite3_bind_int64(st, 2, (sqlite3_int64)keep);
    else
        sqlite3_bind_int64(st, 2, INT64_MAX); /* past every row: no limit */
    if (sq_step_done(c, st, NULL, "jobs_prune", err, errlen)) return STORE_ERR;
    *n = (size_t)sqlite3_changes64(c->db);
    return STORE_OK;
}

/* lock_job: nothing to do, the write transaction is the lock. */
static int sq_be_sub_read(sq_conn *c, const char *id, int lock_job, store_sub *out, char *err,
                          size_t errlen)
{
    (void)lock_job;
    memset(out, 0, sizeof *out);
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
        util_seterr(err, errlen, STORE_ERR, "sqlite sub_get %s: an id too long in the database",
                    id);
        out_rc = STORE_ERR;
    } else {
        out->created = sq_column_time(st, 2);
        out->canceled = sq_column_time(st, 3);
    }
    sq_done(st);
    return out_rc;
}

/* Runs statement `id` on job `job` at `when` (?1, ?2): *changed whether it changed a row. */
static int sq_job_step(sq_conn *c, enum sq_sql id, const char *job, double when, int *changed,
                       char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, id, "sub_cancel", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, job, -1, SQLITE_STATIC);
    if (sqlite3_bind_parameter_count(st) >= 2) sqlite3_bind_double(st, 2, when);
    return sq_step_done(c, st, changed, "sub_cancel", err, errlen);
}

static int sq_be_sub_cancel(sq_conn *c, const char *id, double when, int *changed, char *err,
                            size_t errlen)
{
    return sq_job_step(c, SQ_SUB_CANCEL, id, when, changed, err, errlen);
}

/* A count, then the cancel of a queued job, or else the stop of a running one. */
static int sq_be_job_last_sub(sq_conn *c, const char *job, double when, int *effect, char *err,
                              size_t errlen)
{
    long long active = 0;
    int q = 0, r = 0;
    *effect = STORE_JOB_KEPT;
    if (sq_lookup(c, SQ_SUB_ACTIVE, job, &active, NULL, "sub_cancel", err, errlen))
        return STORE_ERR;
    if (active) return STORE_OK;
    if (sq_job_step(c, SQ_JOB_CANCEL_QUEUED, job, when, &q, err, errlen) ||
        (!q && sq_job_step(c, SQ_JOB_STOP_RUNNING, job, when, &r, err, errlen)))
        return STORE_ERR;
    *effect = q ? STORE_JOB_CANCELED : r ? STORE_JOB_STOPPING : STORE_JOB_KEPT;
    return STORE_OK;
}

/* ---- results ---- */

static int sq_be_result_head(sq_conn *c, const char *hash, uint64_t *bytes, double *used, char *job,
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

static int sq_be_result_row(sq_conn *c, const char *hash, uint64_t bytes, double stamp,
                            const char *job, char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_RESULT_UPSERT, "result_put", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    sqlite3_bind_int64(st, 2, (sqlite3_int64)bytes);
    sqlite3_bind_double(st, 3, stamp);
    if (job) sqlite3_bind_text(st, 4, job, -1, SQLITE_STATIC);
    return sq_step_done(c, st, NULL, "result_put", err, errlen);
}

static int sq_be_result_delete(sq_conn *c, const char *hash, const char *where, char *err,
                               size_t errlen)
{
    return sq_run_key(c, SQ_RESULT_DELETE, hash, NULL, where, err, errlen);
}

static int sq_be_chunks_forget(sq_conn *c, const char *hash, const char *where, char *err,
                               size_t errlen)
{
    return sq_run_key(c, SQ_CHUNKS_DELETE, hash, NULL, where, err, errlen);
}

static int sq_be_result_touch(sq_conn *c, const char *hash, double stamp, const char *where,
                              char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_RESULT_TOUCH, where, err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    sqlite3_bind_double(st, 2, stamp);
    return sq_step_done(c, st, NULL, where, err, errlen);
}

static int sq_be_chunk_put(sq_conn *c, const char *hash, uint64_t off, const void *data, size_t n,
                           const unsigned char sha[32], char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_CHUNK_PUT, "result_put: chunk", err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    sqlite3_bind_int64(st, 2, (sqlite3_int64)off);
    sqlite3_bind_blob64(st, 3, data, n, SQLITE_STATIC);
    sqlite3_bind_blob(st, 4, sha, 32, SQLITE_STATIC);
    return sq_step_done(c, st, NULL, "result_put: chunk", err, errlen);
}

static int sq_be_chunks_sum(sq_conn *c, const char *hash, uint64_t *count, uint64_t *bytes,
                            char *err, size_t errlen)
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

/* Steps st (columns off, body, sha) to its end, calling fn on each row. */
static int sq_chunks_each(sq_conn *c, sqlite3_stmt *st, int one, store_chunk_fn fn, void *ctx,
                          const char *where, char *err, size_t errlen)
{
    int step, rc = STORE_OK, rows = 0;
    while (rc == STORE_OK && (step = sqlite3_step(st)) == SQLITE_ROW) {
        const void *p = sqlite3_column_blob(st, 1);
        size_t n = (size_t)sqlite3_column_bytes(st, 1);
        rows++;
        if (!p && n) {
            util_seterr(err, errlen, STORE_ERR, "sqlite %s: out of memory", where);
            rc = STORE_ERR;
            break;
        }
        const void *sha =
            sqlite3_column_type(st, 2) == SQLITE_BLOB ? sqlite3_column_blob(st, 2) : NULL;
        rc = fn(ctx, (uint64_t)sqlite3_column_int64(st, 0), p, n, sha,
                sha ? (size_t)sqlite3_column_bytes(st, 2) : 0);
    }
    if (rc == STORE_OK && step != SQLITE_DONE) {
        sq_dberr(err, errlen, where, c->db);
        rc = STORE_ERR;
    }
    sq_done(st);
    return rc == STORE_OK && one && !rows ? STORE_NOTFOUND : rc;
}

static int sq_be_chunks_read(sq_conn *c, const char *hash, long long at, store_chunk_fn fn,
                             void *ctx, const char *where, char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, at < 0 ? SQ_CHUNKS_ALL : SQ_CHUNK_AT, where, err, errlen);
    if (!st) return STORE_ERR;
    sqlite3_bind_text(st, 1, hash, -1, SQLITE_STATIC);
    if (at >= 0) sqlite3_bind_int64(st, 2, (sqlite3_int64)at);
    return sq_chunks_each(c, st, at >= 0, fn, ctx, where, err, errlen);
}

/* Reads result_totals (inside the caller's transaction, or as one snapshot). */
static int sq_be_totals(sq_conn *c, size_t *count, uint64_t *bytes, const char *where, char *err,
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
        util_seterr(err, errlen, STORE_ERR, "sqlite %s: the result_totals row is missing", where);
    } else {
        sq_dberr(err, errlen, where, c->db);
    }
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : STORE_ERR;
}

static int sq_be_evict_one(sq_conn *c, const char *keep, int *gone, char *err, size_t errlen)
{
    return sq_run_key(c, SQ_RESULT_EVICT_ONE, keep, gone, "result_put: evict", err, errlen);
}

/* PRAGMA integrity_check: every line it reports but "ok", joined with "; ". */
static int sq_be_integrity(sq_conn *c, char *err, size_t errlen)
{
    int rc, bad = 0;
    size_t used = 0;
    sqlite3_stmt *st = sq_stmt(c, SQ_INTEGRITY, "check", err, errlen);
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
    return rc != SQLITE_DONE || bad ? STORE_ERR : STORE_OK;
}

/* One snapshot of one statement; the chunks of no result are those of a put under way here. */
static int sq_be_recount(sq_conn *c, store_recount *v, char *err, size_t errlen)
{
    sqlite3_stmt *st = sq_stmt(c, SQ_TOTALS_RECOUNT, "check: totals", err, errlen);
    if (!st) return STORE_ERR;
    int rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        long long *f[6] = {&v->tot_count, &v->tot_bytes, &v->count,
                           &v->bytes,     &v->bad_size,  &v->bad_off};
        for (int i = 0; i < 6; i++) *f[i] = sqlite3_column_int64(st, i);
        v->orphans = -1;
    } else if (rc != SQLITE_DONE) {
        sq_dberr(err, errlen, "check: totals", c->db);
    }
    sq_done(st);
    return rc == SQLITE_ROW ? STORE_OK : rc == SQLITE_DONE ? STORE_NOTFOUND : STORE_ERR;
}

/* Every chunk of every result against its digest, in C: SQLite has no SHA-256 of its own. */
static int sq_be_chunks_digests(sq_conn *c, long long *all, long long *bad, char *err,
                                size_t errlen)
{
    int rc;
    *all = *bad = 0;
    sqlite3_stmt *st = sq_stmt(c, SQ_CHUNKS_EVERY, "check: digests", err, errlen);
    if (!st) return STORE_ERR;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        ++*all;
        *bad += !store_digest_ok(
            sqlite3_column_blob(st, 0), (size_t)sqlite3_column_bytes(st, 0),
            sqlite3_column_type(st, 1) == SQLITE_BLOB ? sqlite3_column_blob(st, 1) : NULL,
            (size_t)sqlite3_column_bytes(st, 1));
    }
    if (rc != SQLITE_DONE) sq_dberr(err, errlen, "check: digests", c->db);
    sq_done(st);
    return rc == SQLITE_DONE ? STORE_OK : STORE_ERR;
}

/* A small write (the totals row rewritten as it is), committed like any other: it fails when
 * the file is read-only, the disk refuses, or the lock cannot be had.  A probe waits a second
 * for the lock, not the writers' five: a lock held that long (a put holds it for a batch of
 * chunks: ~0.1 s) means the store is stuck for writers. */
static int sq_be_probe(sq_conn *c, char *err, size_t errlen)
{
    int rc = STORE_ERR;
    sqlite3_busy_timeout(c->db, SQ_PROBE_BUSY_MS);
    if (!sq_run(c, SQ_BEGIN, "writable: begin", err, errlen)) {
        if (sq_run(c, SQ_PROBE, "writable", err, errlen) ||
            sq_run(c, SQ_COMMIT, "writable: commit", err, errlen))
            sq_be_rollback(c);
        else
            rc = STORE_OK;
    }
    sqlite3_busy_timeout(c->db, SQ_BUSY_MS);
    return rc;
}

/* Finalizes and closes every connection of the store, on whichever thread opened it (see the
 * file comment: no other thread may be using the store). */
static void sq_be_close(store *base)
{
    sq_store *s = (sq_store *)base;
    if (!s) return;
    store_conns_free(&s->conns);
    if (s->mu_made) pthread_mutex_destroy(&s->mu);
    if (s->lock_fd >= 0) close(s->lock_fd);
    free(s->path);
    free(s);
}

/* one daemon per file: nobody else hears events (no NOTIFY); a put in batches may leave chunks
 * behind, which chunks_forget deletes; the file has a check of its own (integrity_check) */
static const store_be_ops sq_be = {STORE_BE_PRIMITIVES(sq_be),
                                   .name = "sqlite",
                                   .notify = NULL,
                                   .wait_event = NULL,
                                   .chunks_forget = sq_be_chunks_forget,
                                   .integrity = sq_be_integrity};
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
        util_seterr(err, errlen, STORE_ERR,
                    "sqlite open %s: database schema version %d is newer than this cellard "
                    "(which knows versions up to %d)",
                    path, *v, SQ_VERSION);
        return STORE_ERR;
    }
    if (*v < 0) {
        util_seterr(err, errlen, STORE_ERR,
                    "sqlite open %s: database schema version %d is not ours", path, *v);
        return STORE_ERR;
    }
    return STORE_OK;
}

static int sq_exec(sq_conn *c, const char *sql, const char *where, char *err, size_t errlen)
{
    char *msg = NULL;
    if (sqlite3_exec(c->db, sql, NULL, NULL, &msg) == SQLITE_OK) return STORE_OK;
    util_seterr(err, errlen, STORE_ERR, "sqlite %s: %s", where, msg ? msg : sqlite3_errmsg(c->db));
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
        util_seterr(
            err, errlen, STORE_ERR,
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
    util_seterr(err, errlen, STORE_ERR,
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
    util_seterr(err, errlen, STORE_ERR,
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
        store_digest(sqlite3_column_blob(one, 0), (size_t)sqlite3_column_bytes(one, 0), md);
        sqlite3_reset(one);
        sqlite3_bind_int64(upd, 1, ids[i]);
        sqlite3_bind_blob(upd, 2, md, 32, SQLITE_TRANSIENT);
        if (sqlite3_step(upd) != SQLITE_DONE) rc = SQLITE_ERROR;
        sqlite3_reset(upd);
    }
    if (rc == SQLITE_OK) rc = sqlite3_exec(c->db, "COMMIT", NULL, NULL, NULL);
    if (rc != SQLITE_OK) {
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: digests of the moved results: %s",
                    path, ids ? sqlite3_errmsg(c->db) : "out of memory");
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
            util_seterr(err, errlen, STORE_ERR,
                        "sqlite open %s: journal_mode=WAL refused (mode is %s)", path,
                        mode ? mode : "unknown");
    } else {
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: journal_mode=WAL: %s", path,
                    sqlite3_errmsg(c->db));
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
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: %s", s->path, sqlite3_errmsg(c->db));
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
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: cannot open its lock file %s: %s",
                    s->path, lp, strerror(errno));
        return STORE_ERR;
    }
    if (flock(s->lock_fd, LOCK_EX | LOCK_NB) == 0) return STORE_OK;
    if (errno == EWOULDBLOCK)
        util_seterr(err, errlen, STORE_ERR,
                    "sqlite open %s: another cellard is using this database (one daemon per SQLite "
                    "file; to run several daemons, give them one PostgreSQL database: --db "
                    "postgresql://...)",
                    s->path);
    else
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: cannot lock %s: %s", s->path, lp,
                    strerror(errno));
    return STORE_ERR;
}

store *store_sqlite_open(const char *path, uint64_t budget_bytes, double touch_seconds, int flags,
                         char *err, size_t errlen)
{
    sq_store *s = NULL;
    sq_conn *c = NULL;
    int v;
    const char *what;
    struct stat sb;
    if (!path || !*path) {
        util_seterr(err, errlen, STORE_ERR, "sqlite open: no path");
        return NULL;
    }
    if (!sqlite3_threadsafe()) {
        util_seterr(err, errlen, STORE_ERR,
                    "sqlite open: this libsqlite3 was built without thread support");
        return NULL;
    }
    s = calloc(1, sizeof *s);
    if (!s || !(s->path = strdup(path))) {
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: out of memory", path);
        goto fail;
    }
    s->base.ops = &store_ops_local;
    s->base.be = &sq_be;
    s->base.put_batch = SQ_BATCH;
    s->lock_fd = -1;
    s->base.budget = budget_bytes;
    s->base.touch_seconds = touch_seconds > 0 ? touch_seconds : 0;
    if (pthread_mutex_init(&s->mu, NULL) != 0) {
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: pthread_mutex_init failed", path);
        goto fail;
    }
    s->mu_made = 1;
    if ((what = store_conns_init(&s->conns, sq_conn_new, sq_conn_close, s, "sqlite open"))) {
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: %s failed", path, what);
        goto fail;
    }
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
    if (store_conns_add(&s->conns, c) != 0) { /* this thread's connection from now on */
        util_seterr(err, errlen, STORE_ERR, "sqlite open %s: pthread_setspecific failed", path);
        goto fail;
    }
    return &s->base;
fail:
    sq_conn_close(c);
    if (s) {
        store_conns_free(&s->conns);
        if (s->mu_made) pthread_mutex_destroy(&s->mu);
        if (s->lock_fd >= 0) close(s->lock_fd);
        free(s->path);
        free(s);
    }
    return NULL;
}
