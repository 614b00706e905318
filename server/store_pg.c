/* store_pg.c — the PostgreSQL backend of the store (server/store.h): one database that several
 * daemons share, holding the jobs (the queue itself), the submissions and the result cache.
 *
 * Schema (cellar_meta's 'schema' row is the number of migrations applied; pg_migrations below):
 *   jobs(id PRIMARY KEY, seq, hash, kind, state, created, started, finished, error_status,
 *        error, request bytea, owner, lease_until, attempts, cancel, stage, fraction)
 *        unique index jobs_active_hash(hash) WHERE state IN (0, 1) AND NOT cancel: one job
 *        per request in flight, which submissions join (a job being canceled is none: a new
 *        submission makes a new job); jobs_queue(created, seq) WHERE state = 0
 *   subs(id PRIMARY KEY, job REFERENCES jobs ON DELETE CASCADE, created, canceled)
 *   results(hash PRIMARY KEY, bytes, created, last_used)
 *   result_chunks(hash, off, body bytea, sha bytea, PRIMARY KEY(hash, off))
 *   result_totals(id = 0, count, bytes)   kept by triggers on results, as in SQLite
 * Times are Unix seconds (double precision), NULL for "not yet".
 *
 * How it differs from the SQLite backend, and why:
 *   - A result is written in one transaction, its chunks and then its row (PostgreSQL has no
 *     single write lock that a long put would hold against everyone): no chunk is ever left
 *     behind by a put that failed, so nothing needs deleting at open, when other daemons may be
 *     writing.  Two daemons putting the same result (a job run twice after a lease ran out)
 *     meet on the primary keys: the second waits for the first and keeps its rows.
 *   - Claims take the oldest queued job with FOR UPDATE SKIP LOCKED, so daemons never wait on
 *     each other's claims.  A join (job_submit) and the cancel of a job's last submission both
 *     lock the job's row first, so one of them sees what the other did.
 *   - Events: the writes that other daemons must hear of NOTIFY the channel "cellar" in their
 *     transaction (delivered at commit): "q" a job was queued, "e:ID" job ID ended, "c:ID" job
 *     ID is to stop.  wait_event LISTENs on a connection of its own; after that connection is
 *     made anew it reports STORE_EV_RESET, since events may have been lost meanwhile.
 *
 * Threads: any thread may call any op; each thread gets its own connection (made on its first
 * call, made anew after it is lost), found through a pthread key, as in store_sqlite.c.  A
 * connection that fails is given up; the next op on that thread connects again, at most twice a
 * second, so a database that is away costs each op one quick failure (STORE_ERR), the daemon
 * answers 503, and it recovers by itself when the database is back.
 */
#include "server/store.h"

#include <errno.h>
#include <libpq-fe.h>
#include <math.h>
#include <openssl/evp.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <time.h>

#define PG_RECONNECT_S 0.5        /* a thread tries to connect again at most this often */
#define PG_OPEN_WAIT_S 30         /* open waits this long for a database that cannot be reached */
#define PG_LOCK_ID     1667591276 /* advisory lock of the migrations ("cell") */

static const char *const pg_migrations[] = {
    /* 0 -> 1 */
    "CREATE TABLE jobs(id text PRIMARY KEY, seq bigserial, hash text NOT NULL, kind text NOT NULL,"
    " state smallint NOT NULL, created double precision, started double precision,"
    " finished double precision, error_status integer, error text, request bytea NOT NULL,"
    " owner text, lease_until double precision, attempts integer NOT NULL DEFAULT 0,"
    " cancel boolean NOT NULL DEFAULT false, stage text, fraction double precision);"
    "CREATE INDEX jobs_state ON jobs(state);"
    "CREATE UNIQUE INDEX jobs_active_hash ON jobs(hash) WHERE state IN (0, 1);"
    "CREATE INDEX jobs_queue ON jobs(created, seq) WHERE state = 0;"
    "CREATE INDEX jobs_finished ON jobs(finished) WHERE state IN (2, 3, 4);"
    "CREATE TABLE subs(id text PRIMARY KEY, job text NOT NULL REFERENCES jobs(id)"
    " ON DELETE CASCADE, created double precision, canceled double precision);"
    "CREATE INDEX subs_job ON subs(job);"
    "CREATE TABLE results(hash text PRIMARY KEY, bytes bigint NOT NULL,"
    " created double precision, last_used double precision);"
    "CREATE INDEX results_last_used ON results(last_used);"
    "CREATE TABLE result_chunks(hash text NOT NULL, off bigint NOT NULL, body bytea NOT NULL,"
    " sha bytea, PRIMARY KEY(hash, off));"
    "CREATE TABLE result_totals(id integer PRIMARY KEY CHECK (id = 0), count bigint NOT NULL,"
    " bytes bigint NOT NULL);"
    "INSERT INTO result_totals VALUES(0, 0, 0);"
    "CREATE FUNCTION cellar_results_changed() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN"
    " IF TG_OP = 'INSERT' THEN"
    "  UPDATE result_totals SET count = count + 1, bytes = bytes + NEW.bytes WHERE id = 0;"
    " ELSIF TG_OP = 'DELETE' THEN"
    "  UPDATE result_totals SET count = count - 1, bytes = bytes - OLD.bytes WHERE id = 0;"
    "  DELETE FROM result_chunks WHERE hash = OLD.hash;"
    " ELSIF NEW.bytes <> OLD.bytes THEN"
    "  UPDATE result_totals SET bytes = bytes - OLD.bytes + NEW.bytes WHERE id = 0;"
    " END IF; RETURN NULL; END $$;"
    "CREATE TRIGGER results_changed AFTER INSERT OR DELETE OR UPDATE OF bytes ON results"
    " FOR EACH ROW EXECUTE FUNCTION cellar_results_changed();",
    /* 1 -> 2: the job that made each result (X-Cellar-Job of a cache hit) */
    "ALTER TABLE results ADD COLUMN job text;",
    /* 2 -> 3: a job being canceled (running, its cancel flag set) is no longer the request's
     * job: a new submission of the request makes a new job beside it instead of joining one
     * that will end canceled */
    ("DROP INDEX jobs_active_hash;"
     "CREATE UNIQUE INDEX jobs_active_hash ON jobs(hash) WHERE state IN (0, 1) AND NOT cancel;"),
};
#define PG_VERSION ((int)(sizeof pg_migrations / sizeof *pg_migrations))

typedef struct pg_store pg_store;

typedef struct pg_conn {
    PGconn *db;
    double failed_at;            /* when a connect last failed (0: never) */
    pg_store *owner;             /* the store whose list holds this conn */
    struct pg_conn *prev, *next; /* in owner->conns; guarded by owner->mu */
} pg_conn;

struct pg_store {
    store base; /* first member */
    char *conninfo;
    uint64_t budget;
    double touch_seconds;
    pthread_key_t key;
    pthread_mutex_t mu; /* guards conns */
    pg_conn *conns;
    int key_made;
    PGconn *listen; /* wait_event's own connection (one thread calls wait_event) */
};

static void pg_errf(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void pg_errf(char *err, size_t errlen, const char *fmt, ...)
{
    if (!err || !errlen) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

/* libpq's message, on one line */
static void pg_dberr(char *err, size_t errlen, const char *where, const char *msg)
{
    char m[400];
    snprintf(m, sizeof m, "%s", msg && *msg ? msg : "unknown error");
    for (char *p = m; *p; p++)
        if (*p == '\n' || *p == '\r') *p = ' ';
    size_t n = strlen(m);
    while (n && m[n - 1] == ' ') m[--n] = 0;
    pg_errf(err, errlen, "postgresql %s: %s", where, m);
}

static double pg_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

/* ---- connections ---- */

static void pg_conn_close(pg_conn *c)
{
    if (!c) return;
    if (c->db) PQfinish(c->db);
    free(c);
}

static void pg_conn_release(void *p)
{
    pg_conn *c = p;
    pg_store *s = c->owner;
    pthread_mutex_lock(&s->mu);
    if (c->prev)
        c->prev->next = c->next;
    else if (s->conns == c)
        s->conns = c->next;
    if (c->next) c->next->prev = c->prev;
    pthread_mutex_unlock(&s->mu);
    pg_conn_close(c);
}

static void pg_notice(void *arg, const char *msg)
{
    (void)arg;
    (void)msg; /* NOTICEs (IF NOT EXISTS and the like) are not for the daemon's log */
}

/* A new connection to s, or NULL with a message. */
static PGconn *pg_connect(pg_store *s, char *err, size_t errlen)
{
    PGconn *db = PQconnectdb(s->conninfo);
    if (!db) {
        pg_errf(err, errlen, "postgresql: out of memory");
        return NULL;
    }
    if (PQstatus(db) != CONNECTION_OK) {
        pg_dberr(err, errlen, "connect", PQerrorMessage(db));
        PQfinish(db);
        return NULL;
    }
    PQsetNoticeProcessor(db, pg_notice, NULL);
    PGresult *r = PQexec(db, "SET synchronous_commit = on; SET client_min_messages = warning");
    PQclear(r);
    return db;
}

/* The calling thread's connection, made (again) when it has none; NULL with a message when the
 * database cannot be reached. */
static pg_conn *pg_conn_get(pg_store *s, char *err, size_t errlen)
{
    pg_conn *c = pthread_getspecific(s->key);
    if (!c) {
        c = calloc(1, sizeof *c);
        if (!c) {
            pg_errf(err, errlen, "postgresql: out of memory");
            return NULL;
        }
        c->owner = s;
        if (pthread_setspecific(s->key, c) != 0) {
            free(c);
            pg_errf(err, errlen, "postgresql: pthread_setspecific failed");
            return NULL;
        }
        pthread_mutex_lock(&s->mu);
        c->next = s->conns;
        if (s->conns) s->conns->prev = c;
        s->conns = c;
        pthread_mutex_unlock(&s->mu);
    }
    if (c->db && PQstatus(c->db) != CONNECTION_OK) { /* lost: made anew below */
        PQfinish(c->db);
        c->db = NULL;
    }
    if (!c->db) {
        double now = pg_now();
        if (c->failed_at && now - c->failed_at < PG_RECONNECT_S) {
            pg_errf(err, errlen, "postgresql: the database cannot be reached (trying again)");
            return NULL;
        }
        c->db = pg_connect(s, err, errlen);
        c->failed_at = c->db ? 0 : now;
        if (!c->db) return NULL;
    }
    return c;
}

/* ---- running statements ---- */

#define PG_MAXP 12

/* Parameters of one statement: text values, or binary ones (bytea). */
typedef struct pg_params {
    int n;
    const char *v[PG_MAXP];
    int len[PG_MAXP], fmt[PG_MAXP];
    char buf[PG_MAXP][40]; /* numbers as text */
} pg_params;

static void p_text(pg_params *p, const char *s)
{
    p->v[p->n] = s;
    p->len[p->n] = 0;
    p->fmt[p->n] = 0;
    p->n++;
}

static void p_num(pg_params *p, double x)
{
    snprintf(p->buf[p->n], sizeof p->buf[0], "%.17g", x);
    p_text(p, p->buf[p->n]);
}

static void p_int(pg_params *p, long long x)
{
    snprintf(p->buf[p->n], sizeof p->buf[0], "%lld", x);
    p_text(p, p->buf[p->n]);
}

/* a time: NULL for 0 */
static void p_time(pg_params *p, double t)
{
    if (t != 0)
        p_num(p, t);
    else
        p_text(p, NULL);
}

static void p_bin(pg_params *p, const void *data, size_t n)
{
    p->v[p->n] = data ? data : "";
    p->len[p->n] = (int)n;
    p->fmt[p->n] = 1;
    p->n++;
}

/* Runs sql with p on c; the result when its status is `want` (or PGRES_TUPLES_OK /
 * PGRES_COMMAND_OK as given), else NULL with the message (a lost connection is given up, so
 * that the next op connects again).  binary: the result's columns in binary (bytea as bytes). */
static PGresult *pg_run(pg_conn *c, const char *sql, const pg_params *p, int binary,
                        ExecStatusType want, const char *where, char *err, size_t errlen)
{
    PGresult *r = PQexecParams(c->db, sql, p ? p->n : 0, NULL, p ? p->v : NULL, p ? p->len : NULL,
                               p ? p->fmt : NULL, binary);
    if (r && PQresultStatus(r) == want) return r;
    pg_dberr(err, errlen, where, r ? PQresultErrorMessage(r) : PQerrorMessage(c->db));
    PQclear(r);
    if (PQstatus(c->db) != CONNECTION_OK) {
        PQfinish(c->db);
        c->db = NULL;
    }
    return NULL;
}

/* A statement whose result is not needed: 0, or -1 with a message. */
static int pg_cmd(pg_conn *c, const char *sql, const pg_params *p, const char *where, char *err,
                  size_t errlen)
{
    PGresult *r = pg_run(c, sql, p, 0, PGRES_COMMAND_OK, where, err, errlen);
    PQclear(r);
    return r ? 0 : -1;
}

/* A statement of one row or none: its result, or NULL (error: *rc STORE_ERR). */
static PGresult *pg_rows(pg_conn *c, const char *sql, const pg_params *p, int binary,
                         const char *where, char *err, size_t errlen)
{
    return pg_run(c, sql, p, binary, PGRES_TUPLES_OK, where, err, errlen);
}

static int pg_begin(pg_conn *c, const char *where, char *err, size_t errlen)
{
    return pg_cmd(c, "BEGIN", NULL, where, err, errlen);
}

static int pg_commit(pg_conn *c, const char *where, char *err, size_t errlen)
{
    return pg_cmd(c, "COMMIT", NULL, where, err, errlen);
}

static void pg_rollback(pg_conn *c)
{
    if (!c->db) return;
    PGresult *r = PQexec(c->db, "ROLLBACK");
    PQclear(r);
}

/* NOTIFY cellar, payload (in the caller's transaction: delivered at commit). */
static int pg_notify(pg_conn *c, const char *payload, char *err, size_t errlen)
{
    pg_params p = {0};
    p_text(&p, payload);
    PGresult *r = pg_rows(c, "SELECT pg_notify('cellar', $1)", &p, 0, "notify", err, errlen);
    PQclear(r);
    return r ? 0 : -1;
}

static int pg_notify_id(pg_conn *c, char kind, const char *id, char *err, size_t errlen)
{
    char payload[40];
    snprintf(payload, sizeof payload, "%c:%.32s", kind, id);
    return pg_notify(c, payload, err, errlen);
}

static double col_num(const PGresult *r, int row, int col)
{
    return PQgetisnull(r, row, col) ? 0 : strtod(PQgetvalue(r, row, col), NULL);
}

static int col_fixed(const PGresult *r, int row, int col, char *dst, size_t cap)
{
    const char *v = PQgetisnull(r, row, col) ? "" : PQgetvalue(r, row, col);
    size_t n = strlen(v);
    if (n >= cap) return -1;
    memcpy(dst, v, n + 1);
    return 0;
}

/* ---- jobs ---- */

static const char pg_job_cols[] =
    "id, hash, kind, state, created, started, finished, error_status, error, request,"
    " (SELECT count(*) FROM subs WHERE job = jobs.id AND canceled IS NULL), owner, lease_until,"
    " attempts, cancel::int, stage, fraction";

/* Row `row` of a result of pg_job_cols (text format; the request is bytea in hex) into out. */
static int pg_job_from(const PGresult *r, int row, store_job *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    if (col_fixed(r, row, 0, out->id, sizeof out->id) ||
        col_fixed(r, row, 1, out->hash, sizeof out->hash) ||
        col_fixed(r, row, 2, out->kind, sizeof out->kind) ||
        col_fixed(r, row, 11, out->owner, sizeof out->owner) ||
        col_fixed(r, row, 15, out->stage, sizeof out->stage)) {
        pg_errf(err, errlen, "postgresql job_get: a text field too long in the database");
        return STORE_ERR;
    }
    out->state = (job_state)atoi(PQgetvalue(r, row, 3));
    if (out->state < JOB_QUEUED || out->state > JOB_CANCELED) {
        pg_errf(err, errlen, "postgresql job_get %s: unknown state %d in the database", out->id,
                (int)out->state);
        return STORE_ERR;
    }
    out->created = col_num(r, row, 4);
    out->started = col_num(r, row, 5);
    out->finished = col_num(r, row, 6);
    out->error_status = PQgetisnull(r, row, 7) ? 0 : atoi(PQgetvalue(r, row, 7));
    if (!PQgetisnull(r, row, 8) && !(out->error = strdup(PQgetvalue(r, row, 8)))) goto nomem;
    size_t n = 0;
    unsigned char *req = PQunescapeBytea((const unsigned char *)PQgetvalue(r, row, 9), &n);
    if (!req) goto nomem;
    out->request = malloc(n + 1);
    if (!out->request) {
        PQfreemem(req);
        goto nomem;
    }
    memcpy(out->request, req, n);
    out->request[n] = 0;
    out->request_len = n;
    PQfreemem(req);
    out->active_subs = atoi(PQgetvalue(r, row, 10));
    out->lease_until = col_num(r, row, 12);
    out->attempts = atoi(PQgetvalue(r, row, 13));
    out->cancel = atoi(PQgetvalue(r, row, 14));
    out->fraction = col_num(r, row, 16);
    return STORE_OK;
nomem:
    store_job_clear(out);
    pg_errf(err, errlen, "postgresql job_get: out of memory");
    return STORE_ERR;
}

static int pg_job_read(pg_conn *c, const char *id, store_job *out, char *err, size_t errlen)
{
    char sql[400];
    pg_params p = {0};
    memset(out, 0, sizeof *out);
    p_text(&p, id);
    snprintf(sql, sizeof sql, "SELECT %s FROM jobs WHERE id = $1", pg_job_cols);
    PGresult *r = pg_rows(c, sql, &p, 0, "job_get", err, errlen);
    if (!r) return STORE_ERR;
    int rc = PQntuples(r) ? pg_job_from(r, 0, out, err, errlen) : STORE_NOTFOUND;
    PQclear(r);
    return rc;
}

static int pg_job_get(store *base, const char *id, store_job *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    return c ? pg_job_read(c, id, out, err, errlen) : STORE_ERR;
}

static int field_ok(const char *v, size_t cap, const char *what, char *err, size_t errlen)
{
    if (strnlen(v, cap) < cap) return 0;
    pg_errf(err, errlen, "postgresql job_insert: %s is not a string of at most %zu bytes", what,
            cap - 1);
    return -1;
}

/* Inserts job j and its first submission (in the caller's transaction). */
static int pg_job_write(pg_conn *c, const store_job *j, char *err, size_t errlen)
{
    if (j->state < JOB_QUEUED || j->state > JOB_CANCELED) {
        pg_errf(err, errlen, "postgresql job_insert: unknown state %d", (int)j->state);
        return STORE_ERR;
    }
    if ((!j->request && j->request_len) || j->request_len > (size_t)INT32_MAX) {
        pg_errf(err, errlen, "postgresql job_insert: a request of %zu bytes", j->request_len);
        return STORE_ERR;
    }
    if (field_ok(j->id, sizeof j->id, "id", err, errlen) ||
        field_ok(j->hash, sizeof j->hash, "hash", err, errlen) ||
        field_ok(j->kind, sizeof j->kind, "kind", err, errlen))
        return STORE_ERR;
    pg_params p = {0};
    p_text(&p, j->id);
    p_text(&p, j->hash);
    p_text(&p, j->kind);
    p_int(&p, (int)j->state);
    p_time(&p, j->created);
    p_time(&p, j->started);
    p_time(&p, j->finished);
    if (j->error_status)
        p_int(&p, j->error_status);
    else
        p_text(&p, NULL);
    p_text(&p, j->error);
    p_bin(&p, j->request, j->request_len);
    p_time(&p, j->state == JOB_CANCELED ? j->finished : 0);
    return pg_cmd(
               c,
               "WITH j AS (INSERT INTO jobs(id, hash, kind, state, created, started, finished,"
               " error_status, error, request) VALUES($1, $2, $3, $4, $5, $6, $7, $8, $9, $10)"
               " RETURNING id, created)"
               " INSERT INTO subs(id, job, created, canceled) SELECT id, id, created, $11 FROM j",
               &p, "job_insert", err, errlen)
               ? STORE_ERR
               : STORE_OK;
}

static int pg_job_insert(store *base, const store_job *j, char *err, size_t errlen)
{
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    if (pg_begin(c, "job_insert", err, errlen)) return STORE_ERR;
    if (pg_job_write(c, j, err, errlen) || pg_commit(c, "job_insert", err, errlen)) {
        pg_rollback(c);
        return STORE_ERR;
    }
    return STORE_OK;
}

/* One try of job_submit (see pg_job_submit): STORE_* or 2 + STORE_ERR when a concurrent submit
 * made the same job first (unique_violation): then the caller tries again, and joins it. */
#define PG_RACE 100
static int pg_submit_once(pg_conn *c, const store_job *j, size_t queue_max, int join_only,
                          char *job_id, int *joined, char *err, size_t errlen)
{
    pg_params p = {0};
    PGresult *r;
    int rc;
    *joined = 0;
    if (pg_begin(c, "job_submit", err, errlen)) return STORE_ERR;
    p_text(&p, j->hash);
    if (!(r = pg_rows(c, "SELECT 1 FROM results WHERE hash = $1", &p, 0, "job_submit", err,
                      errlen)))
        goto fail;
    int cached = PQntuples(r) > 0;
    PQclear(r);
    if (cached) {
        rc = STORE_CACHED;
        goto done;
    }
    /* the job in flight, locked: a cancel of its last submission waits for this join, or
     * this join sees the job canceled (or being canceled) and makes a new one */
    if (!(r = pg_rows(c,
                      "SELECT id FROM jobs WHERE hash = $1 AND state IN (0, 1) AND NOT cancel"
                      " FOR UPDATE",
                      &p, 0, "job_submit", err, errlen)))
        goto fail;
    int found = PQntuples(r) > 0 && !col_fixed(r, 0, 0, job_id, 33);
    PQclear(r);
    if (found) {
        pg_params q = {0};
        p_text(&q, j->id);
        p_text(&q, job_id);
        p_time(&q, j->created);
        if (pg_cmd(c, "INSERT INTO subs(id, job, created) VALUES($1, $2, $3)", &q, "job_submit",
                   err, errlen))
            goto fail;
        *joined = 1;
        rc = STORE_OK;
        goto done;
    }
    if (join_only) {
        rc = STORE_NOTFOUND;
        goto done;
    }
    if (queue_max) {
        if (!(r = pg_rows(c, "SELECT count(*) FROM jobs WHERE state = 0", NULL, 0, "job_submit",
                          err, errlen)))
            goto fail;
        unsigned long long queued = strtoull(PQgetvalue(r, 0, 0), NULL, 10);
        PQclear(r);
        if (queued >= queue_max) {
            rc = STORE_FULL;
            goto done;
        }
    }
    store_job q = *j;
    q.state = JOB_QUEUED;
    q.started = q.finished = 0;
    q.error_status = 0;
    q.error = NULL;
    if (pg_job_write(c, &q, err, errlen)) {
        if (strstr(err, "jobs_active_hash")) { /* made by another submit meanwhile */
            pg_rollback(c);
            return PG_RACE;
        }
        goto fail;
    }
    if (pg_notify(c, "q", err, errlen)) goto fail;
    memcpy(job_id, j->id, 33);
    rc = STORE_OK;
done:
    if (pg_commit(c, "job_submit", err, errlen)) goto fail;
    return rc;
fail:
    *joined = 0;
    pg_rollback(c);
    return STORE_ERR;
}

static int pg_job_submit(store *base, const store_job *j, size_t queue_max, int join_only,
                         char *job_id, int *joined, char *err, size_t errlen)
{
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    *joined = 0;
    if (!c) return STORE_ERR;
    for (int t = 0; t < 5; t++) {
        int rc = pg_submit_once(c, j, queue_max, join_only, job_id, joined, err, errlen);
        if (rc != PG_RACE) return rc;
    }
    pg_errf(err, errlen, "postgresql job_submit: the same request was made and canceled too often");
    return STORE_ERR;
}

static int pg_job_claim(store *base, const char *owner, double now, double lease, store_job *out,
                        char *err, size_t errlen)
{
    char sql[900];
    pg_params p = {0};
    memset(out, 0, sizeof *out);
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    p_text(&p, owner);
    p_num(&p, now);
    p_num(&p, now + lease);
    snprintf(sql, sizeof sql,
             "UPDATE jobs SET state = 1, owner = $1, started = $2, lease_until = $3,"
             " attempts = attempts + 1, cancel = false, stage = 'started', fraction = 0"
             " WHERE id = (SELECT id FROM jobs WHERE state = 0 ORDER BY created, seq LIMIT 1"
             " FOR UPDATE SKIP LOCKED) RETURNING %s",
             pg_job_cols);
    PGresult *r = pg_rows(c, sql, &p, 0, "job_claim", err, errlen);
    if (!r) return STORE_ERR;
    int rc = PQntuples(r) ? pg_job_from(r, 0, out, err, errlen) : STORE_NOTFOUND;
    PQclear(r);
    return rc;
}

static int pg_job_renew(store *base, const char *id, const char *owner, double now, double lease,
                        const char *stage, double fraction, int *cancel, char *err, size_t errlen)
{
    pg_params p = {0};
    *cancel = 0;
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    p_text(&p, id);
    p_text(&p, owner);
    p_num(&p, now + lease);
    p_text(&p, stage);
    p_num(&p, isfinite(fraction) ? fraction : 0);
    PGresult *r = pg_rows(c,
                          "UPDATE jobs SET lease_until = $3, stage = $4, fraction = $5"
                          " WHERE id = $1 AND owner = $2 AND state = 1 RETURNING cancel::int",
                          &p, 0, "job_renew", err, errlen);
    if (!r) return STORE_ERR;
    int rc = PQntuples(r) ? STORE_OK : STORE_NOTFOUND;
    if (rc == STORE_OK) *cancel = atoi(PQgetvalue(r, 0, 0));
    PQclear(r);
    return rc;
}

/* One write in a transaction of its own, with NOTIFY payload when it changed a row (payload
 * may be NULL): STORE_OK, STORE_NOTFOUND when it changed none. */
static int pg_write1(pg_store *s, const char *sql, const pg_params *p, char kind, const char *id,
                     const char *where, char *err, size_t errlen)
{
    pg_conn *c = pg_conn_get(s, err, errlen);
    if (!c) return STORE_ERR;
    if (pg_begin(c, where, err, errlen)) return STORE_ERR;
    PGresult *r = pg_run(c, sql, p, 0, PGRES_COMMAND_OK, where, err, errlen);
    if (!r) goto fail;
    int changed = atoi(PQcmdTuples(r)) > 0;
    PQclear(r);
    if (changed && kind == 'q' && pg_notify(c, "q", err, errlen)) goto fail;
    if (changed && kind && kind != 'q' && pg_notify_id(c, kind, id, err, errlen)) goto fail;
    if (pg_commit(c, where, err, errlen)) goto fail;
    return changed ? STORE_OK : STORE_NOTFOUND;
fail:
    pg_rollback(c);
    return STORE_ERR;
}

static int pg_job_finish(store *base, const char *id, const char *owner, job_state st, double when,
                         int error_status, const char *error, char *err, size_t errlen)
{
    if (st != JOB_DONE && st != JOB_FAILED && st != JOB_CANCELED) {
        pg_errf(err, errlen, "postgresql job_finish: %d is not an end state", (int)st);
        return STORE_ERR;
    }
    pg_params p = {0};
    p_text(&p, id);
    p_text(&p, owner);
    p_int(&p, (int)st);
    p_time(&p, when);
    if (st == JOB_FAILED && error_status)
        p_int(&p, error_status);
    else
        p_text(&p, NULL);
    p_text(&p, st == JOB_FAILED ? error : NULL);
    return pg_write1((pg_store *)base,
                     "UPDATE jobs SET state = $3, finished = $4, error_status = $5, error = $6,"
                     " request = ''::bytea, lease_until = NULL"
                     " WHERE id = $1 AND owner = $2 AND state = 1",
                     &p, 'e', id, "job_finish", err, errlen);
}

static int pg_job_release(store *base, const char *id, const char *owner, char *err, size_t errlen)
{
    pg_params p = {0};
    p_text(&p, id);
    p_text(&p, owner);
    p_num(&p, pg_now());
    return pg_write1(
        (pg_store *)base,
        "UPDATE jobs SET state = CASE WHEN cancel THEN 4 ELSE 0 END,"
        " finished = CASE WHEN cancel THEN $3::double precision END,"
        " request = CASE WHEN cancel THEN ''::bytea ELSE request END,"
        " started = CASE WHEN cancel THEN started END, stage = NULL,"
        " fraction = NULL, lease_until = NULL WHERE id = $1 AND owner = $2 AND state = 1",
        &p, 'q', id, "job_release", err, errlen);
}

static int pg_jobs_requeue(store *base, double now, int all, size_t *n, char *err, size_t errlen)
{
    char msg[200], attempts[16];
    pg_params p = {0};
    *n = 0;
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    snprintf(msg, sizeof msg,
             "the job was started %d times, and each time the daemon running it stopped before "
             "it ended",
             STORE_MAX_ATTEMPTS);
    snprintf(attempts, sizeof attempts, "%d", STORE_MAX_ATTEMPTS);
    p_num(&p, now);
    p_text(&p, all ? "true" : "false");
    p_text(&p, attempts);
    p_text(&p, msg);
    if (pg_begin(c, "jobs_requeue", err, errlen)) return STORE_ERR;
    PGresult *r = pg_rows(
        c,
        "UPDATE jobs SET state = CASE WHEN cancel THEN 4 WHEN attempts >= $3::int THEN 3"
        " ELSE 0 END,"
        " finished = CASE WHEN cancel OR attempts >= $3::int THEN $1::double precision END,"
        " error_status = CASE WHEN NOT cancel AND attempts >= $3::int THEN 500 END,"
        " error = CASE WHEN NOT cancel AND attempts >= $3::int THEN $4 END,"
        " request = CASE WHEN cancel OR attempts >= $3::int THEN ''::bytea ELSE request END,"
        " started = CASE WHEN cancel OR attempts >= $3::int THEN started END, stage = NULL,"
        " fraction = NULL, lease_until = NULL WHERE state = 1 AND ($2::boolean OR lease_until < $1)"
        " RETURNING id, state",
        &p, 0, "jobs_requeue", err, errlen);
    if (!r) goto fail;
    int queued = 0, bad = 0;
    for (int i = 0; i < PQntuples(r) && !bad; i++) {
        if (atoi(PQgetvalue(r, i, 1)) == JOB_QUEUED)
            queued = 1;
        else
            bad = pg_notify_id(c, 'e', PQgetvalue(r, i, 0), err, errlen);
    }
    *n = (size_t)PQntuples(r);
    PQclear(r);
    if (bad || (queued && pg_notify(c, "q", err, errlen))) goto fail;
    if (pg_commit(c, "jobs_requeue", err, errlen)) goto fail;
    return STORE_OK;
fail:
    *n = 0;
    pg_rollback(c);
    return STORE_ERR;
}

static int pg_job_counts(store *base, size_t *queued, size_t *running, char *err, size_t errlen)
{
    *queued = *running = 0;
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    PGresult *r = pg_rows(c,
                          "SELECT (SELECT count(*) FROM jobs WHERE state = 0),"
                          " (SELECT count(*) FROM jobs WHERE state = 1)",
                          NULL, 0, "job_counts", err, errlen);
    if (!r) return STORE_ERR;
    *queued = (size_t)strtoull(PQgetvalue(r, 0, 0), NULL, 10);
    *running = (size_t)strtoull(PQgetvalue(r, 0, 1), NULL, 10);
    PQclear(r);
    return STORE_OK;
}

static int pg_jobs_prune(store *base, double before, size_t keep, size_t *n, char *err,
                         size_t errlen)
{
    pg_params p = {0};
    if (n) *n = 0;
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    p_num(&p, before);
    if (keep && keep < (size_t)INT64_MAX)
        p_int(&p, (long long)keep);
    else
        p_text(&p, NULL); /* OFFSET NULL: no limit */
    PGresult *r = pg_run(c,
                         "DELETE FROM jobs WHERE state IN (2, 3, 4) AND (finished < $1 OR id IN"
                         " (SELECT id FROM jobs WHERE state IN (2, 3, 4) ORDER BY finished DESC"
                         " OFFSET coalesce($2::bigint, 9223372036854775807)))",
                         &p, 0, PGRES_COMMAND_OK, "jobs_prune", err, errlen);
    if (!r) return STORE_ERR;
    if (n) *n = (size_t)strtoull(PQcmdTuples(r), NULL, 10);
    PQclear(r);
    return STORE_OK;
}

/* ---- submissions ---- */

static int pg_sub_read(pg_conn *c, const char *id, int lock_job, store_sub *out, char *err,
                       size_t errlen)
{
    pg_params p = {0};
    memset(out, 0, sizeof *out);
    p_text(&p, id);
    PGresult *r = pg_rows(c, "SELECT id, job, created, canceled FROM subs WHERE id = $1", &p, 0,
                          "sub_get", err, errlen);
    if (!r) return STORE_ERR;
    int rc = STORE_NOTFOUND;
    if (PQntuples(r)) {
        rc = STORE_OK;
        if (col_fixed(r, 0, 0, out->id, sizeof out->id) ||
            col_fixed(r, 0, 1, out->job, sizeof out->job)) {
            pg_errf(err, errlen, "postgresql sub_get: an id too long in the database");
            rc = STORE_ERR;
        }
        out->created = col_num(r, 0, 2);
        out->canceled = col_num(r, 0, 3);
    }
    PQclear(r);
    if (rc != STORE_OK || !lock_job) return rc;
    pg_params q = {0};
    p_text(&q, out->job);
    r = pg_rows(c, "SELECT 1 FROM jobs WHERE id = $1 FOR UPDATE", &q, 0, "sub_cancel", err, errlen);
    PQclear(r);
    return r ? STORE_OK : STORE_ERR;
}

static int pg_sub_get(store *base, const char *id, store_sub *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    return c ? pg_sub_read(c, id, 0, out, err, errlen) : STORE_ERR;
}

static int pg_sub_cancel(store *base, const char *id, double when, int *changed, int *job,
                         char *err, size_t errlen)
{
    store_sub sub;
    pg_params p = {0};
    *changed = 0;
    *job = STORE_JOB_KEPT;
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    if (pg_begin(c, "sub_cancel", err, errlen)) return STORE_ERR;
    int rc = pg_sub_read(c, id, 1, &sub, err, errlen); /* its job's row locked: see job_submit */
    if (rc == STORE_NOTFOUND) goto done;
    if (rc != STORE_OK) goto fail;
    p_text(&p, id);
    p_num(&p, when);
    PGresult *r = pg_run(c, "UPDATE subs SET canceled = $2 WHERE id = $1 AND canceled IS NULL", &p,
                         0, PGRES_COMMAND_OK, "sub_cancel", err, errlen);
    if (!r) goto fail;
    *changed = atoi(PQcmdTuples(r)) > 0;
    PQclear(r);
    if (*changed) {
        pg_params q = {0};
        p_text(&q, sub.job);
        p_num(&q, when);
        r = pg_rows(c,
                    "WITH remaining AS (SELECT count(*) AS n FROM subs WHERE job = $1"
                    " AND canceled IS NULL),"
                    " q AS (UPDATE jobs SET state = 4, finished = $2, request = ''::bytea"
                    "  WHERE id = $1 AND state = 0 AND (SELECT n FROM remaining) = 0 RETURNING 1),"
                    " s AS (UPDATE jobs SET cancel = true WHERE id = $1 AND state = 1"
                    "  AND (SELECT n FROM remaining) = 0 RETURNING 1)"
                    " SELECT (SELECT count(*) FROM q), (SELECT count(*) FROM s)",
                    &q, 0, "sub_cancel", err, errlen);
        if (!r) goto fail;
        int canceled = atoi(PQgetvalue(r, 0, 0)), stopping = atoi(PQgetvalue(r, 0, 1));
        PQclear(r);
        if (canceled) {
            *job = STORE_JOB_CANCELED;
            if (pg_notify_id(c, 'e', sub.job, err, errlen)) goto fail;
        } else if (stopping) {
            *job = STORE_JOB_STOPPING;
            if (pg_notify_id(c, 'c', sub.job, err, errlen)) goto fail;
        }
    }
done:
    if (pg_commit(c, "sub_cancel", err, errlen)) goto fail;
    return rc;
fail:
    *changed = 0;
    *job = STORE_JOB_KEPT;
    pg_rollback(c);
    return STORE_ERR;
}

/* ---- events ---- */

static int pg_wait_event(store *base, double timeout, store_ev *ev, char *id, char *err,
                         size_t errlen)
{
    pg_store *s = (pg_store *)base;
    *ev = STORE_EV_NONE;
    id[0] = 0;
    if (s->listen && PQstatus(s->listen) != CONNECTION_OK) {
        PQfinish(s->listen);
        s->listen = NULL;
    }
    if (!s->listen) {
        s->listen = pg_connect(s, err, errlen);
        if (!s->listen) return STORE_ERR;
        PGresult *r = PQexec(s->listen, "LISTEN cellar");
        int ok = r && PQresultStatus(r) == PGRES_COMMAND_OK;
        if (!ok) pg_dberr(err, errlen, "listen", PQerrorMessage(s->listen));
        PQclear(r);
        if (!ok) {
            PQfinish(s->listen);
            s->listen = NULL;
            return STORE_ERR;
        }
        *ev = STORE_EV_RESET; /* events before now were not heard */
        return STORE_OK;
    }
    PGnotify *n = PQnotifies(s->listen);
    if (!n) {
        int fd = PQsocket(s->listen);
        fd_set rd;
        FD_ZERO(&rd);
        FD_SET(fd, &rd);
        struct timeval tv = {.tv_sec = (time_t)timeout,
                             .tv_usec = (suseconds_t)((timeout - (double)(time_t)timeout) * 1e6)};
        if (select(fd + 1, &rd, NULL, NULL, &tv) < 0 && errno != EINTR) {
            pg_errf(err, errlen, "postgresql wait_event: select: %s", strerror(errno));
            return STORE_ERR;
        }
        if (!PQconsumeInput(s->listen)) {
            pg_dberr(err, errlen, "wait_event", PQerrorMessage(s->listen));
            PQfinish(s->listen);
            s->listen = NULL;
            return STORE_ERR;
        }
        n = PQnotifies(s->listen);
    }
    if (!n) return STORE_OK;
    const char *pl = n->extra ? n->extra : "";
    if (!strcmp(pl, "q")) {
        *ev = STORE_EV_QUEUED;
    } else if ((pl[0] == 'e' || pl[0] == 'c') && pl[1] == ':' && strlen(pl + 2) == 32) {
        *ev = pl[0] == 'e' ? STORE_EV_ENDED : STORE_EV_CANCEL;
        memcpy(id, pl + 2, 33);
    }
    PQfreemem(n);
    return STORE_OK;
}

/* ---- results ---- */

static void pg_digest(const void *data, size_t n, unsigned char out[32])
{
    unsigned int len = 0;
    if (!EVP_Digest(data, n, out, &len, EVP_sha256(), NULL) || len != 32) memset(out, 0, 32);
}

/* Where a put's bytes come from: memory, or a file read a chunk at a time. */
typedef struct pg_source {
    const char *mem;
    FILE *f;
    char *buf; /* STORE_CHUNK bytes, for f */
} pg_source;

static const char *pg_take(pg_source *src, uint64_t pos, size_t n, uint64_t len, char *err,
                           size_t errlen)
{
    if (src->mem) return src->mem + pos;
    size_t got = fread(src->buf, 1, n, src->f);
    if (got == n) return src->buf;
    pg_errf(err, errlen, "postgresql result_put: %s after %llu of %llu bytes",
            ferror(src->f) ? "reading the result failed" : "the file ended",
            (unsigned long long)(pos + got), (unsigned long long)len);
    return NULL;
}

static int pg_evict(pg_conn *c, uint64_t budget, const char *keep, char *err, size_t errlen)
{
    pg_params p = {0};
    p_text(&p, keep);
    for (;;) {
        PGresult *r = pg_rows(c, "SELECT bytes FROM result_totals WHERE id = 0", NULL, 0,
                              "result_put: total", err, errlen);
        if (!r) return STORE_ERR;
        uint64_t total = PQntuples(r) ? strtoull(PQgetvalue(r, 0, 0), NULL, 10) : 0;
        PQclear(r);
        if (total <= budget) return STORE_OK;
        r = pg_run(c,
                   "DELETE FROM results WHERE hash = (SELECT hash FROM results WHERE hash <> $1"
                   " ORDER BY last_used LIMIT 1 FOR UPDATE SKIP LOCKED)",
                   &p, 0, PGRES_COMMAND_OK, "result_put: evict", err, errlen);
        if (!r) return STORE_ERR;
        int n = atoi(PQcmdTuples(r));
        PQclear(r);
        if (n == 0) return STORE_OK; /* keep alone exceeds the budget */
    }
}

static int pg_put(pg_store *s, const char *hash, const char *job, uint64_t len, pg_source *src,
                  char *err, size_t errlen)
{
    pg_conn *c = pg_conn_get(s, err, errlen);
    if (!c) return STORE_ERR;
    if (len > (uint64_t)INT64_MAX / 2) {
        pg_errf(err, errlen, "postgresql result_put: %llu bytes is too large",
                (unsigned long long)len);
        return STORE_ERR;
    }
    if (pg_begin(c, "result_put", err, errlen)) return STORE_ERR;
    pg_params p = {0};
    p_text(&p, hash);
    if (pg_cmd(c, "DELETE FROM results WHERE hash = $1", &p, "result_put: replace", err, errlen))
        goto fail;
    for (uint64_t pos = 0; pos < len;) {
        size_t n = len - pos < STORE_CHUNK ? (size_t)(len - pos) : STORE_CHUNK;
        const char *data = pg_take(src, pos, n, len, err, errlen);
        if (!data) goto fail;
        unsigned char md[32];
        pg_digest(data, n, md);
        pg_params q = {0};
        p_text(&q, hash);
        p_int(&q, (long long)pos);
        p_bin(&q, data, n);
        p_bin(&q, md, 32);
        if (pg_cmd(c,
                   "INSERT INTO result_chunks(hash, off, body, sha) VALUES($1, $2, $3, $4)"
                   " ON CONFLICT (hash, off) DO UPDATE SET body = excluded.body,"
                   " sha = excluded.sha",
                   &q, "result_put: chunk", err, errlen))
            goto fail;
        pos += n;
    }
    pg_params q = {0};
    p_text(&q, hash);
    p_int(&q, (long long)len);
    p_num(&q, pg_now());
    p_text(&q, job && *job ? job : NULL);
    if (pg_cmd(c,
               "INSERT INTO results(hash, bytes, created, last_used, job)"
               " VALUES($1, $2, $3, $3, $4) ON CONFLICT (hash) DO UPDATE SET"
               " bytes = excluded.bytes, created = excluded.created,"
               " last_used = excluded.last_used, job = excluded.job",
               &q, "result_put", err, errlen))
        goto fail;
    if (s->budget && pg_evict(c, s->budget, hash, err, errlen)) goto fail;
    if (pg_commit(c, "result_put", err, errlen)) goto fail;
    return STORE_OK;
fail:
    pg_rollback(c);
    return STORE_ERR;
}

static int pg_result_put(store *base, const char *hash, const char *body, size_t len, char *err,
                         size_t errlen)
{
    if (!body && len) {
        pg_errf(err, errlen, "postgresql result_put: %zu bytes with no body", len);
        return STORE_ERR;
    }
    pg_source src = {.mem = body ? body : ""};
    return pg_put((pg_store *)base, hash, NULL, len, &src, err, errlen);
}

static int pg_result_put_file(store *base, const char *hash, const char *job, FILE *f, uint64_t len,
                              char *err, size_t errlen)
{
    pg_source src = {.f = f, .buf = malloc(STORE_CHUNK)};
    if (!src.buf) {
        pg_errf(err, errlen, "postgresql result_put: out of memory");
        return STORE_ERR;
    }
    int rc = pg_put((pg_store *)base, hash, job, len, &src, err, errlen);
    free(src.buf);
    return rc;
}

/* Drops a damaged result (best effort). */
static void pg_drop(pg_conn *c, const char *hash)
{
    pg_params p = {0};
    p_text(&p, hash);
    char err[64];
    if (c->db) pg_cmd(c, "DELETE FROM results WHERE hash = $1", &p, "drop", err, sizeof err);
}

/* The result's size and last mark: STORE_OK, STORE_NOTFOUND. */
static int pg_head(pg_conn *c, const char *hash, uint64_t *bytes, double *used, char *job,
                   char *err, size_t errlen)
{
    pg_params p = {0};
    p_text(&p, hash);
    PGresult *r = pg_rows(c, "SELECT bytes, last_used, job FROM results WHERE hash = $1", &p, 0,
                          "result", err, errlen);
    if (!r) return STORE_ERR;
    int rc = PQntuples(r) ? STORE_OK : STORE_NOTFOUND;
    if (rc == STORE_OK) {
        *bytes = strtoull(PQgetvalue(r, 0, 0), NULL, 10);
        *used = col_num(r, 0, 1);
        if (job && col_fixed(r, 0, 2, job, 33)) job[0] = 0;
    }
    PQclear(r);
    return rc;
}

/* Marks a result used now, unless its mark is younger than touch_seconds. */
static int pg_touch(pg_store *s, pg_conn *c, const char *hash, double used, char *err,
                    size_t errlen)
{
    double now = pg_now();
    if (s->touch_seconds > 0 && now - used < s->touch_seconds) return STORE_OK;
    pg_params p = {0};
    p_text(&p, hash);
    p_num(&p, now);
    return pg_cmd(c, "UPDATE results SET last_used = $2 WHERE hash = $1", &p, "mark used", err,
                  errlen)
               ? STORE_ERR
               : STORE_OK;
}

/* A chunk's body and digest as returned in binary; 1 when the digest matches. */
static int pg_chunk_ok(const PGresult *r, int row, int body, int sha)
{
    unsigned char md[32];
    if (PQgetisnull(r, row, sha) || PQgetlength(r, row, sha) != 32) return 0;
    pg_digest(PQgetvalue(r, row, body), (size_t)PQgetlength(r, row, body), md);
    return memcmp(md, PQgetvalue(r, row, sha), 32) == 0;
}

/* int8 in network order, as a binary result gives it */
static uint64_t be64(const char *p)
{
    const unsigned char *u = (const unsigned char *)p;
    uint64_t x = 0;
    for (int i = 0; i < 8; i++) x = x << 8 | u[i];
    return x;
}

static int pg_result_get(store *base, const char *hash, char **body, size_t *len, char *err,
                         size_t errlen)
{
    pg_store *s = (pg_store *)base;
    uint64_t bytes = 0, pos = 0;
    double used = 0;
    char *copy = NULL;
    *body = NULL;
    if (len) *len = 0;
    pg_conn *c = pg_conn_get(s, err, errlen);
    if (!c) return STORE_ERR;
    if (pg_cmd(c, "BEGIN ISOLATION LEVEL REPEATABLE READ", NULL, "result_get", err, errlen))
        return STORE_ERR;
    int rc = pg_head(c, hash, &bytes, &used, NULL, err, errlen);
    PGresult *r = NULL;
    if (rc) goto out;
    rc = STORE_ERR;
    if (bytes >= SIZE_MAX || !(copy = malloc((size_t)bytes + 1))) {
        pg_errf(err, errlen, "postgresql result_get: out of memory for %llu bytes",
                (unsigned long long)bytes);
        goto out;
    }
    pg_params p = {0};
    p_text(&p, hash);
    r = pg_rows(c, "SELECT off, body, sha FROM result_chunks WHERE hash = $1 ORDER BY off", &p, 1,
                "result_get", err, errlen);
    if (!r) goto out;
    for (int i = 0; i < PQntuples(r); i++) {
        uint64_t off = be64(PQgetvalue(r, i, 0)), n = (uint64_t)PQgetlength(r, i, 1);
        if (off != pos || n > bytes - pos || !pg_chunk_ok(r, i, 1, 2)) {
            pg_errf(err, errlen,
                    "postgresql result_get: result %.16s... is damaged: its chunk at byte %llu "
                    "(%llu bytes, %llu of %llu read) does not fit or does not match its digest",
                    hash, (unsigned long long)off, (unsigned long long)n, (unsigned long long)pos,
                    (unsigned long long)bytes);
            rc = STORE_DAMAGED;
            goto out;
        }
        if (n) memcpy(copy + pos, PQgetvalue(r, i, 1), (size_t)n);
        pos += n;
    }
    if (pos != bytes) {
        pg_errf(err, errlen,
                "postgresql result_get: result %.16s... is damaged: its chunks hold %llu of its "
                "%llu bytes",
                hash, (unsigned long long)pos, (unsigned long long)bytes);
        rc = STORE_DAMAGED;
        goto out;
    }
    rc = STORE_OK;
out:
    PQclear(r);
    if (c->db) pg_commit(c, "result_get", NULL, 0);
    if (rc == STORE_DAMAGED) pg_drop(c, hash);
    if (rc == STORE_OK && c->db) rc = pg_touch(s, c, hash, used, err, errlen);
    if (rc != STORE_OK) {
        free(copy);
        return rc;
    }
    copy[bytes] = 0;
    *body = copy;
    if (len) *len = (size_t)bytes;
    return STORE_OK;
}

static int pg_result_size(store *base, const char *hash, uint64_t *bytes, char *job, char *err,
                          size_t errlen)
{
    pg_store *s = (pg_store *)base;
    double used = 0;
    *bytes = 0;
    pg_conn *c = pg_conn_get(s, err, errlen);
    if (!c) return STORE_ERR;
    if (job) job[0] = 0;
    int rc = pg_head(c, hash, bytes, &used, job, err, errlen);
    if (rc == STORE_OK) rc = pg_touch(s, c, hash, used, err, errlen);
    return rc;
}

static int pg_result_chunk(store *base, const char *hash, uint64_t pos, char **data, size_t *len,
                           uint64_t *start, char *err, size_t errlen)
{
    *data = NULL;
    *len = 0;
    *start = 0;
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    if (pos > (uint64_t)INT64_MAX) return STORE_NOTFOUND;
    pg_params p = {0};
    p_text(&p, hash);
    p_int(&p, (long long)pos);
    PGresult *r = pg_rows(c,
                          "SELECT off, body, sha FROM result_chunks WHERE hash = $1 AND off <= $2"
                          " ORDER BY off DESC LIMIT 1",
                          &p, 1, "result_chunk", err, errlen);
    if (!r) return STORE_ERR;
    int rc = STORE_NOTFOUND;
    if (PQntuples(r)) {
        uint64_t off = be64(PQgetvalue(r, 0, 0)), n = (uint64_t)PQgetlength(r, 0, 1);
        if (pos - off < n) {
            if (!pg_chunk_ok(r, 0, 1, 2)) {
                pg_errf(err, errlen,
                        "postgresql result_chunk: result %.16s... is damaged: its chunk at byte "
                        "%llu does not match its digest",
                        hash, (unsigned long long)off);
                rc = STORE_DAMAGED;
            } else if (!(*data = malloc((size_t)n + 1))) {
                pg_errf(err, errlen, "postgresql result_chunk: out of memory");
                rc = STORE_ERR;
            } else {
                memcpy(*data, PQgetvalue(r, 0, 1), (size_t)n);
                (*data)[n] = 0;
                *len = (size_t)n;
                *start = off;
                rc = STORE_OK;
            }
        }
    }
    PQclear(r);
    if (rc == STORE_DAMAGED) pg_drop(c, hash);
    return rc;
}

static int pg_result_exists(store *base, const char *hash, char *err, size_t errlen)
{
    uint64_t bytes;
    double used;
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    return c ? pg_head(c, hash, &bytes, &used, NULL, err, errlen) : STORE_ERR;
}

static int pg_result_stats(store *base, size_t *count, uint64_t *bytes, char *err, size_t errlen)
{
    *count = 0;
    *bytes = 0;
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    PGresult *r = pg_rows(c, "SELECT count, bytes FROM result_totals WHERE id = 0", NULL, 0,
                          "result_stats", err, errlen);
    if (!r) return STORE_ERR;
    if (PQntuples(r)) {
        *count = (size_t)strtoull(PQgetvalue(r, 0, 0), NULL, 10);
        *bytes = strtoull(PQgetvalue(r, 0, 1), NULL, 10);
    }
    PQclear(r);
    return STORE_OK;
}

static int pg_check(store *base, char *err, size_t errlen)
{
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    PGresult *r = pg_rows(
        c,
        "SELECT t.count, t.bytes, (SELECT count(*) FROM results),"
        " (SELECT coalesce(sum(bytes), 0) FROM results),"
        " (SELECT count(*) FROM results r WHERE r.bytes <> (SELECT coalesce(sum(length(c.body)), 0)"
        "  FROM result_chunks c WHERE c.hash = r.hash)),"
        " (SELECT count(*) FROM (SELECT off, sum(length(body)) OVER (PARTITION BY hash ORDER BY off"
        "  ROWS UNBOUNDED PRECEDING) - length(body) AS start FROM result_chunks"
        "  WHERE hash IN (SELECT hash FROM results)) x WHERE off <> start),"
        " (SELECT count(*) FROM result_chunks WHERE hash NOT IN (SELECT hash FROM results)),"
        " (SELECT count(*) FROM result_chunks WHERE sha IS NULL OR sha <> sha256(body))"
        " FROM result_totals t WHERE t.id = 0",
        NULL, 0, "check", err, errlen);
    if (!r) return STORE_ERR;
    int rc = STORE_OK;
    if (!PQntuples(r)) {
        pg_errf(err, errlen, "postgresql check: the result_totals row is missing");
        rc = STORE_ERR;
    } else {
        long long v[8];
        for (int i = 0; i < 8; i++) v[i] = strtoll(PQgetvalue(r, 0, i), NULL, 10);
        if (v[0] != v[2] || v[1] != v[3]) {
            pg_errf(err, errlen,
                    "postgresql check: result_totals says %lld results of %lld bytes, the table "
                    "holds %lld of %lld",
                    v[0], v[1], v[2], v[3]);
            rc = STORE_ERR;
        } else if (v[4] || v[5] || v[6] || v[7]) {
            pg_errf(err, errlen,
                    "postgresql check: %lld results whose chunks do not add up, %lld chunks out "
                    "of place, %lld chunks of no result, %lld chunks that do not match their "
                    "digest",
                    v[4], v[5], v[6], v[7]);
            rc = STORE_ERR;
        }
    }
    PQclear(r);
    return rc;
}

static int pg_writable(store *base, char *err, size_t errlen)
{
    pg_conn *c = pg_conn_get((pg_store *)base, err, errlen);
    if (!c) return STORE_ERR;
    if (pg_begin(c, "writable", err, errlen)) return STORE_ERR;
    int rc = pg_cmd(c, "SET LOCAL statement_timeout = 1000", NULL, "writable", err, errlen) ||
                     pg_cmd(c, "UPDATE result_totals SET count = count WHERE id = 0", NULL,
                            "writable", err, errlen)
                 ? STORE_ERR
                 : STORE_OK;
    pg_rollback(c);
    return rc;
}

static void pg_close(store *base)
{
    pg_store *s = (pg_store *)base;
    if (!s) return;
    if (s->key_made) pthread_key_delete(s->key);
    pthread_mutex_lock(&s->mu);
    pg_conn *c = s->conns;
    s->conns = NULL;
    pthread_mutex_unlock(&s->mu);
    while (c) {
        pg_conn *next = c->next;
        pg_conn_close(c);
        c = next;
    }
    if (s->listen) PQfinish(s->listen);
    pthread_mutex_destroy(&s->mu);
    free(s->conninfo);
    free(s);
}

static const store_ops pg_ops = {
    .job_submit = pg_job_submit,
    .job_claim = pg_job_claim,
    .job_renew = pg_job_renew,
    .job_finish = pg_job_finish,
    .job_release = pg_job_release,
    .jobs_requeue = pg_jobs_requeue,
    .job_insert = pg_job_insert,
    .job_get = pg_job_get,
    .job_counts = pg_job_counts,
    .jobs_prune = pg_jobs_prune,
    .sub_get = pg_sub_get,
    .sub_cancel = pg_sub_cancel,
    .wait_event = pg_wait_event,
    .result_put = pg_result_put,
    .result_put_file = pg_result_put_file,
    .result_get = pg_result_get,
    .result_size = pg_result_size,
    .result_chunk = pg_result_chunk,
    .result_exists = pg_result_exists,
    .result_stats = pg_result_stats,
    .check = pg_check,
    .writable = pg_writable,
    .close = pg_close,
};

/* ---- opening ---- */

/* Brings the schema to PG_VERSION under an advisory lock (daemons starting together migrate
 * once).  A database that has a jobs table but no cellar_meta is someone else's: refused
 * unless STORE_OPEN_INIT. */
static int pg_migrate(pg_conn *c, int flags, char *err, size_t errlen)
{
    char where[64];
    pg_params p = {0};
    p_int(&p, PG_LOCK_ID);
    if (pg_begin(c, "open", err, errlen)) return STORE_ERR;
    PGresult *r = pg_rows(c, "SELECT pg_advisory_xact_lock($1)", &p, 0, "open: lock", err, errlen);
    if (!r) goto fail;
    PQclear(r);
    r = pg_rows(c,
                "SELECT to_regclass('cellar_meta') IS NOT NULL, to_regclass('jobs') IS NOT NULL,"
                " (SELECT count(*) FROM pg_tables WHERE schemaname = current_schema())",
                NULL, 0, "open", err, errlen);
    if (!r) goto fail;
    int meta = !strcmp(PQgetvalue(r, 0, 0), "t"), jobs = !strcmp(PQgetvalue(r, 0, 1), "t");
    long long ntab = strtoll(PQgetvalue(r, 0, 2), NULL, 10);
    PQclear(r);
    if (!meta && jobs && !(flags & STORE_OPEN_INIT)) {
        pg_errf(err, errlen,
                "postgresql open: a database of something else (%lld tables, one named jobs, no "
                "cellar_meta), not a cellar store: check --db, or use a database of its own",
                ntab);
        goto fail;
    }
    if (!meta && (pg_cmd(c, "CREATE TABLE cellar_meta(key text PRIMARY KEY, value text NOT NULL)",
                         NULL, "open: cellar_meta", err, errlen) ||
                  pg_cmd(c, "INSERT INTO cellar_meta VALUES('schema', '0')", NULL,
                         "open: cellar_meta", err, errlen)))
        goto fail;
    r = pg_rows(c, "SELECT value::int FROM cellar_meta WHERE key = 'schema'", NULL, 0, "open", err,
                errlen);
    if (!r) goto fail;
    int v = PQntuples(r) ? atoi(PQgetvalue(r, 0, 0)) : -1;
    PQclear(r);
    if (v > PG_VERSION || v < 0) {
        pg_errf(err, errlen,
                "postgresql open: database schema version %d is %s this cellard (which knows "
                "versions up to %d)",
                v, v < 0 ? "unknown to" : "newer than", PG_VERSION);
        goto fail;
    }
    for (; v < PG_VERSION; v++) {
        snprintf(where, sizeof where, "open: migration to schema version %d", v + 1);
        r = PQexec(c->db, pg_migrations[v]);
        int ok = r && PQresultStatus(r) == PGRES_COMMAND_OK;
        if (!ok) pg_dberr(err, errlen, where, r ? PQresultErrorMessage(r) : PQerrorMessage(c->db));
        PQclear(r);
        if (!ok) goto fail;
    }
    pg_params q = {0};
    p_int(&q, PG_VERSION);
    if (pg_cmd(c, "UPDATE cellar_meta SET value = $1 WHERE key = 'schema'", &q, "open", err,
               errlen) ||
        pg_commit(c, "open", err, errlen))
        goto fail;
    return STORE_OK;
fail:
    pg_rollback(c);
    return STORE_ERR;
}

store *store_pg_open(const char *conninfo, uint64_t budget_bytes, double touch_seconds, int flags,
                     char *err, size_t errlen)
{
    pg_store *s = calloc(1, sizeof *s);
    int mu_made = 0;
    if (!s || !(s->conninfo = strdup(conninfo))) {
        pg_errf(err, errlen, "postgresql open: out of memory");
        goto fail;
    }
    s->base.ops = &pg_ops;
    s->base.shared = 1;
    s->budget = budget_bytes;
    s->touch_seconds = touch_seconds > 0 ? touch_seconds : 0;
    if (pthread_mutex_init(&s->mu, NULL) != 0) goto fail;
    mu_made = 1;
    if (pthread_key_create(&s->key, pg_conn_release) != 0) {
        pg_errf(err, errlen, "postgresql open: pthread_key_create failed");
        goto fail;
    }
    s->key_made = 1;
    /* a database that is still starting (a compose stack's) is waited for, PG_OPEN_WAIT_S */
    pg_conn *c = NULL;
    for (double t0 = pg_now();;) {
        c = pg_conn_get(s, err, errlen);
        int starting = !strstr(err, "FATAL") || strstr(err, "starting up") ||
                       strstr(err, "shutting down"); /* not a refusal: the server is not up */
        if (c || pg_now() - t0 > PG_OPEN_WAIT_S || !strstr(err, "connect") || !starting) break;
        nanosleep(&(struct timespec){1, 0}, NULL);
    }
    if (!c || pg_migrate(c, flags, err, errlen)) goto fail;
    return &s->base;
fail:
    if (s) {
        if (s->key_made) {
            pg_conn *c = pthread_getspecific(s->key);
            pthread_setspecific(s->key, NULL);
            pthread_key_delete(s->key);
            pg_conn_close(c);
        }
        if (mu_made) pthread_mutex_destroy(&s->mu);
        free(s->conninfo);
        free(s);
    }
    return NULL;
}
