/* store_pg.c — the PostgreSQL backend of the store (server/store.h): one database that several
 * daemons share, holding the jobs (the queue itself), the submissions and the result cache.  It
 * gives the primitives of server/store_be.h (one statement, one round trip each); the policy
 * over them is store.c's, the same as SQLite's.  A frame of one statement (STORE_TX_ONE) runs
 * in autocommit, so job_renew, result_size's touch and job_claim stay one round trip each.
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
 * call, made anew after it is lost), kept by the per-thread registry of server/store_conn.h,
 * as in store_sqlite.c.  A
 * connection that fails is given up; the next op on that thread connects again, at most twice a
 * second, so a database that is away costs each op one quick failure (STORE_ERR), the daemon
 * answers 503, and it recovers by itself when the database is back.
 */
#include "server/store.h"

#include "core/util.h"
#include "server/store_be.h"
#include "server/store_conn.h"

#include <errno.h>
#include <libpq-fe.h>
#include <math.h>
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

typedef struct store_conn pg_conn;

struct store_conn {
    store_conn_link link; /* first member: in the store's registry (server/store_conn.h) */
    PGconn *db;
    int one;          /* in a STORE_TX_ONE frame: autocommit, nothing to end */
    double failed_at; /* when a connect last failed (0: never) */
};

struct pg_store {
    store base; /* first member */
    char *conninfo;
    store_conns conns; /* every thread's pg_conn */
    PGconn *listen;    /* wait_event's own connection (one thread calls wait_event) */
};

/* libpq's message, on one line */
static void pg_dberr(char *err, size_t errlen, const char *where, const char *msg)
{
    char m[400];
    snprintf(m, sizeof m, "%s", msg && *msg ? msg : "unknown error");
    for (char *p = m; *p; p++)
        if (*p == '\n' || *p == '\r') *p = ' ';
    size_t n = strlen(m);
    while (n && m[n - 1] == ' ') m[--n] = 0;
    util_seterr(err, errlen, STORE_ERR, "postgresql %s: %s", where, m);
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

/* The registry's open: a thread's conn, not yet connected (pg_conn_get connects it). */
static store_conn *pg_conn_new(void *ctx, char *err, size_t errlen)
{
    (void)ctx;
    pg_conn *c = calloc(1, sizeof *c);
    if (!c) util_seterr(err, errlen, STORE_ERR, "postgresql: out of memory");
    return c;
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
        util_seterr(err, errlen, STORE_ERR, "postgresql: out of memory");
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
    pg_conn *c = store_conns_get(&s->conns, err, errlen);
    if (!c) return NULL;
    if (c->db && PQstatus(c->db) != CONNECTION_OK) { /* lost: made anew below */
        PQfinish(c->db);
        c->db = NULL;
    }
    if (!c->db) {
        double now = pg_now();
        if (c->failed_at && now - c->failed_at < PG_RECONNECT_S) {
            util_seterr(err, errlen, STORE_ERR,
                        "postgresql: the database cannot be reached (trying again)");
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

/* an HTTP status: NULL for 0 */
static void p_status(pg_params *p, int status)
{
    if (status)
        p_int(p, status);
    else
        p_text(p, NULL);
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

static void pg_be_rollback(pg_conn *c)
{
    if (c->one) { /* autocommit: nothing open */
        c->one = 0;
        return;
    }
    if (!c->db) return;
    PGresult *r = PQexec(c->db, "ROLLBACK");
    PQclear(r);
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

/* The number of rows a command changed. */
static int pg_changed(pg_conn *c, const char *sql, const pg_params *p, long long *n,
                      const char *where, char *err, size_t errlen)
{
    PGresult *r = pg_run(c, sql, p, 0, PGRES_COMMAND_OK, where, err, errlen);
    if (!r) return STORE_ERR;
    *n = strtoll(PQcmdTuples(r), NULL, 10);
    PQclear(r);
    return STORE_OK;
}

/* A query whose one parameter is key (text): its result, or NULL with the message. */
static PGresult *pg_by_key(pg_conn *c, const char *sql, const char *key, int binary,
                           const char *where, char *err, size_t errlen)
{
    pg_params p = {0};
    p_text(&p, key);
    return pg_rows(c, sql, &p, binary, where, err, errlen);
}

/* ---- connections, transactions, events (store_be.h) ---- */

static store_conn *pg_be_conn(store *s, char *err, size_t errlen)
{
    return pg_conn_get((pg_store *)s, err, errlen);
}

/* STORE_TX_ONE costs no round trip: the one statement that follows runs in autocommit, atomic
 * by itself (c->one remembers that commit and rollback have nothing to end).  A read snapshot
 * is REPEATABLE READ (the chunks seen are those of the row seen). */
static int pg_be_begin(pg_conn *c, store_tx tx, const char *where, char *err, size_t errlen)
{
    c->one = tx == STORE_TX_ONE;
    if (c->one) return STORE_OK;
    return pg_cmd(c, tx == STORE_TX_READ ? "BEGIN ISOLATION LEVEL REPEATABLE READ" : "BEGIN", NULL,
                  where, err, errlen)
               ? STORE_ERR
               : STORE_OK;
}

static int pg_be_commit(pg_conn *c, const char *where, char *err, size_t errlen)
{
    if (c->one) {
        c->one = 0;
        return STORE_OK;
    }
    if (!c->db) return util_seterr(err, errlen, STORE_ERR, "postgresql %s: connection lost", where);
    return pg_commit(c, where, err, errlen) ? STORE_ERR : STORE_OK;
}

static double pg_be_stamp(store *s)
{
    (void)s;
    return pg_now();
}

/* NOTIFY cellar in the caller's transaction (delivered at commit): "q" a job was queued,
 * "e:ID" job ID ended, "c:ID" job ID is to stop. */
static int pg_be_notify(pg_conn *c, store_ev ev, const char *id, char *err, size_t errlen)
{
    char payload[40] = "q";
    if (ev != STORE_EV_QUEUED)
        snprintf(payload, sizeof payload, "%c:%.32s", ev == STORE_EV_ENDED ? 'e' : 'c', id);
    pg_params p = {0};
    p_text(&p, payload);
    PGresult *r = pg_rows(c, "SELECT pg_notify('cellar', $1)", &p, 0, "notify", err, errlen);
    PQclear(r);
    return r ? STORE_OK : STORE_ERR;
}

static int pg_be_wait_event(store *base, double timeout, store_ev *ev, char *id, char *err,
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
        if (select(fd + 1, &rd, NULL, NULL, &tv) < 0 && errno != EINTR)
            return util_seterr(err, errlen, STORE_ERR, "postgresql wait_event: select: %s",
                               strerror(errno));
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

/* ---- jobs and submissions ---- */

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
        col_fixed(r, row, 15, out->stage, sizeof out->stage))
        return util_seterr(err, errlen, STORE_ERR,
                           "postgresql job_get: a text field too long in the database");
    out->state = (job_state)atoi(PQgetvalue(r, row, 3));
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
    return util_seterr(err, errlen, STORE_ERR, "postgresql job_get: out of memory");
}

/* sql (its row pg_job_cols) into out: STORE_NOTFOUND when it gives none. */
static int pg_job_query(pg_conn *c, const char *sql, const pg_params *p, store_job *out,
                        const char *where, char *err, size_t errlen)
{
    PGresult *r = pg_rows(c, sql, p, 0, where, err, errlen);
    if (!r) return STORE_ERR;
    int rc = PQntuples(r) ? pg_job_from(r, 0, out, err, errlen) : STORE_NOTFOUND;
    PQclear(r);
    return rc;
}

static int pg_be_job_read(pg_conn *c, const char *id, store_job *out, char *err, size_t errlen)
{
    char sql[400];
    pg_params p = {0};
    p_text(&p, id);
    snprintf(sql, sizeof sql, "SELECT %s FROM jobs WHERE id = $1", pg_job_cols);
    return pg_job_query(c, sql, &p, out, "job_get", err, errlen);
}

/* The job and its first submission in one statement; a unique violation of jobs_active_hash is
 * another daemon's submit of the same request, made first: STORE_RACE. */
static int pg_be_job_write(pg_conn *c, const store_job *j, const char *where, char *err,
                           size_t errlen)
{
    (void)where;
    if (j->request_len > (size_t)INT32_MAX)
        return util_seterr(err, errlen, STORE_ERR, "postgresql job_insert: a request of %zu bytes",
                           j->request_len);
    pg_params p = {0};
    p_text(&p, j->id);
    p_text(&p, j->hash);
    p_text(&p, j->kind);
    p_int(&p, (int)j->state);
    p_time(&p, j->created);
    p_time(&p, j->started);
    p_time(&p, j->finished);
    p_status(&p, j->error_status);
    p_text(&p, j->error);
    p_bin(&p, j->request, j->request_len);
    p_time(&p, j->state == JOB_CANCELED ? j->finished : 0);
    if (!pg_cmd(c,
                "WITH j AS (INSERT INTO jobs(id, hash, kind, state, created, started, finished,"
                " error_status, error, request) VALUES($1, $2, $3, $4, $5, $6, $7, $8, $9, $10)"
                " RETURNING id, created)"
                " INSERT INTO subs(id, job, created, canceled) SELECT id, id, created, $11 FROM j",
                &p, "job_insert", err, errlen))
        return STORE_OK;
    return err && strstr(err, "jobs_active_hash") ? STORE_RACE : STORE_ERR;
}

/* FOR UPDATE: a cancel of its last submission waits for this join, or this join sees the job
 * canceled (or being canceled) and makes a new one. */
static int pg_be_job_active(pg_conn *c, const char *hash, char *id, char *err, size_t errlen)
{
    PGresult *r = pg_by_key(c,
                            "SELECT id FROM jobs WHERE hash = $1 AND state IN (0, 1) AND NOT cancel"
                            " FOR UPDATE",
                            hash, 0, "job_submit", err, errlen);
    if (!r) return STORE_ERR;
    int found = PQntuples(r) > 0 && !col_fixed(r, 0, 0, id, 33);
    PQclear(r);
    return found ? STORE_OK : STORE_NOTFOUND;
}

/* One statement: the oldest queued job that no other daemon is claiming (SKIP LOCKED). */
static int pg_be_job_claim(pg_conn *c, const char *owner, double now, double until, store_job *out,
                           char *err, size_t errlen)
{
    char sql[900];
    pg_params p = {0};
    p_text(&p, owner);
    p_num(&p, now);
    p_num(&p, until);
    snprintf(sql, sizeof sql,
             "UPDATE jobs SET state = 1, owner = $1, started = $2, lease_until = $3,"
             " attempts = attempts + 1, cancel = false, stage = 'started', fraction = 0"
             " WHERE id = (SELECT id FROM jobs WHERE state = 0 ORDER BY created, seq LIMIT 1"
             " FOR UPDATE SKIP LOCKED) RETURNING %s",
             pg_job_cols);
    return pg_job_query(c, sql, &p, out, "job_claim", err, errlen);
}

static int pg_be_job_set(pg_conn *c, const store_set *a, int *cancel, const char *where, char *err,
                         size_t errlen)
{
    pg_params p = {0};
    long long n = 0;
    p_text(&p, a->id);
    p_text(&p, a->owner);
    if (a->kind == STORE_SET_RENEW) {
        p_num(&p, a->until);
        p_text(&p, a->stage);
        p_num(&p, isfinite(a->fraction) ? a->fraction : 0);
        PGresult *r = pg_rows(c,
                              "UPDATE jobs SET lease_until = $3, stage = $4, fraction = $5"
                              " WHERE id = $1 AND owner = $2 AND state = 1 RETURNING cancel::int",
                              &p, 0, where, err, errlen);
        if (!r) return STORE_ERR;
        int rc = PQntuples(r) ? STORE_OK : STORE_NOTFOUND;
        if (rc == STORE_OK && cancel) *cancel = atoi(PQgetvalue(r, 0, 0));
        PQclear(r);
        return rc;
    }
    const char *sql;
    if (a->kind == STORE_SET_FINISH) {
        p_int(&p, (int)a->state);
        p_time(&p, a->when);
        p_status(&p, a->error_status);
        p_text(&p, a->error);
        sql = "UPDATE jobs SET state = $3, finished = $4, error_status = $5, error = $6,"
              " request = ''::bytea, lease_until = NULL WHERE id = $1 AND owner = $2 AND state = 1";
    } else {
        p_num(&p, a->when);
        sql = "UPDATE jobs SET state = CASE WHEN cancel THEN 4 ELSE 0 END,"
              " finished = CASE WHEN cancel THEN $3::double precision END,"
              " request = CASE WHEN cancel THEN ''::bytea ELSE request END,"
              " started = CASE WHEN cancel THEN started END, stage = NULL,"
              " fraction = NULL, lease_until = NULL WHERE id = $1 AND owner = $2 AND state = 1";
    }
    if (pg_changed(c, sql, &p, &n, where, err, errlen)) return STORE_ERR;
    return n > 0 ? STORE_OK : STORE_NOTFOUND;
}

/* RETURNING the moved jobs, so that each one that ended is told of (ended). */
static int pg_be_jobs_requeue(pg_conn *c, double now, int all, int max_attempts, const char *msg,
                              int (*ended)(void *ctx, const char *id), void *ctx, size_t *n,
                              int *queued, char *err, size_t errlen)
{
    pg_params p = {0};
    p_num(&p, now);
    p_text(&p, all ? "true" : "false");
    p_int(&p, max_attempts);
    p_text(&p, msg);
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
    if (!r) return STORE_ERR;
    int bad = 0;
    for (int i = 0; i < PQntuples(r) && !bad; i++) {
        if (atoi(PQgetvalue(r, i, 1)) == JOB_QUEUED)
            *queued = 1;
        else if (ended)
            bad = ended(ctx, PQgetvalue(r, i, 0)) != STORE_OK;
    }
    *n = (size_t)PQntuples(r);
    PQclear(r);
    return bad ? STORE_ERR : STORE_OK;
}

static int pg_be_job_counts(pg_conn *c, size_t *queued, size_t *running, const char *where,
                            char *err, size_t errlen)
{
    PGresult *r = pg_rows(c,
                          running ? "SELECT (SELECT count(*) FROM jobs WHERE state = 0),"
                                    " (SELECT count(*) FROM jobs WHERE state = 1)"
                                  : "SELECT count(*) FROM jobs WHERE state = 0",
                          NULL, 0, where, err, errlen);
    if (!r) return STORE_ERR;
    *queued = (size_t)strtoull(PQgetvalue(r, 0, 0), NULL, 10);
    if (running) *running = (size_t)strtoull(PQgetvalue(r, 0, 1), NULL, 10);
    PQclear(r);
    return STORE_OK;
}

static int pg_be_jobs_prune(pg_conn *c, double before, size_t keep, size_t *n, char *err,
                            size_t errlen)
{
    pg_params p = {0};
    long long k = 0;
    p_num(&p, before);
    if (keep && keep < (size_t)INT64_MAX)
        p_int(&p, (long long)keep);
    else
        p_text(&p, NULL); /* OFFSET NULL: no limit */
    if (pg_changed(c,
                   "DELETE FROM jobs WHERE state IN (2, 3, 4) AND (finished < $1 OR id IN"
                   " (SELECT id FROM jobs WHERE state IN (2, 3, 4) ORDER BY finished DESC"
                   " OFFSET coalesce($2::bigint, 9223372036854775807)))",
                   &p, &k, "jobs_prune", err, errlen))
        return STORE_ERR;
    *n = (size_t)k;
    return STORE_OK;
}

/* A foreign key, not a check, refuses a submission of no job (an error, not STORE_NOTFOUND). */
static int pg_be_sub_write(pg_conn *c, const store_sub *sub, const char *where, char *err,
                           size_t errlen)
{
    pg_params p = {0};
    p_text(&p, sub->id);
    p_text(&p, sub->job);
    p_time(&p, sub->created);
    p_time(&p, sub->canceled);
    return pg_cmd(c, "INSERT INTO subs(id, job, created, canceled) VALUES($1, $2, $3, $4)", &p,
                  where, err, errlen)
               ? STORE_ERR
               : STORE_OK;
}

/* lock_job: the job's row FOR UPDATE (see pg_be_job_active). */
static int pg_be_sub_read(pg_conn *c, const char *id, int lock_job, store_sub *out, char *err,
                          size_t errlen)
{
    memset(out, 0, sizeof *out);
    PGresult *r = pg_by_key(c, "SELECT id, job, created, canceled FROM subs WHERE id = $1", id, 0,
                            "sub_get", err, errlen);
    if (!r) return STORE_ERR;
    int rc = STORE_NOTFOUND;
    if (PQntuples(r)) {
        rc = STORE_OK;
        if (col_fixed(r, 0, 0, out->id, sizeof out->id) ||
            col_fixed(r, 0, 1, out->job, sizeof out->job))
            rc = util_seterr(err, errlen, STORE_ERR,
                             "postgresql sub_get: an id too long in the database");
        out->created = col_num(r, 0, 2);
        out->canceled = col_num(r, 0, 3);
    }
    PQclear(r);
    if (rc != STORE_OK || !lock_job) return rc;
    r = pg_by_key(c, "SELECT 1 FROM jobs WHERE id = $1 FOR UPDATE", out->job, 0, "sub_cancel", err,
                  errlen);
    PQclear(r);
    return r ? STORE_OK : STORE_ERR;
}

static int pg_be_sub_cancel(pg_conn *c, const char *id, double when, int *changed, char *err,
                            size_t errlen)
{
    pg_params p = {0};
    long long n = 0;
    p_text(&p, id);
    p_num(&p, when);
    if (pg_changed(c, "UPDATE subs SET canceled = $2 WHERE id = $1 AND canceled IS NULL", &p, &n,
                   "sub_cancel", err, errlen))
        return STORE_ERR;
    *changed = n > 0;
    return STORE_OK;
}

/* One statement: the count and both updates. */
static int pg_be_job_last_sub(pg_conn *c, const char *job, double when, int *effect, char *err,
                              size_t errlen)
{
    pg_params p = {0};
    p_text(&p, job);
    p_num(&p, when);
    PGresult *r = pg_rows(c,
                          "WITH remaining AS (SELECT count(*) AS n FROM subs WHERE job = $1"
                          " AND canceled IS NULL),"
                          " q AS (UPDATE jobs SET state = 4, finished = $2, request = ''::bytea"
                          "  WHERE id = $1 AND state = 0 AND (SELECT n FROM remaining) = 0"
                          "  RETURNING 1),"
                          " s AS (UPDATE jobs SET cancel = true WHERE id = $1 AND state = 1"
                          "  AND (SELECT n FROM remaining) = 0 RETURNING 1)"
                          " SELECT (SELECT count(*) FROM q), (SELECT count(*) FROM s)",
                          &p, 0, "sub_cancel", err, errlen);
    if (!r) return STORE_ERR;
    int canceled = atoi(PQgetvalue(r, 0, 0)), stopping = atoi(PQgetvalue(r, 0, 1));
    PQclear(r);
    *effect = canceled ? STORE_JOB_CANCELED : stopping ? STORE_JOB_STOPPING : STORE_JOB_KEPT;
    return STORE_OK;
}

/* ---- results ---- */

/* int8 in network order, as a binary result gives it */
static uint64_t be64(const char *p)
{
    const unsigned char *u = (const unsigned char *)p;
    uint64_t x = 0;
    for (int i = 0; i < 8; i++) x = x << 8 | u[i];
    return x;
}

/* A statement whose one parameter is a hash and whose result is not needed. */
static int pg_cmd_hash(pg_conn *c, const char *sql, const char *hash, const char *where, char *err,
                       size_t errlen)
{
    pg_params p = {0};
    p_text(&p, hash);
    return pg_cmd(c, sql, &p, where, err, errlen) ? STORE_ERR : STORE_OK;
}

static int pg_be_result_head(pg_conn *c, const char *hash, uint64_t *bytes, double *used, char *job,
                             const char *where, char *err, size_t errlen)
{
    PGresult *r = pg_by_key(c, "SELECT bytes, last_used, job FROM results WHERE hash = $1", hash, 0,
                            where, err, errlen);
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

static int pg_be_result_row(pg_conn *c, const char *hash, uint64_t bytes, double stamp,
                            const char *job, char *err, size_t errlen)
{
    pg_params p = {0};
    p_text(&p, hash);
    p_int(&p, (long long)bytes);
    p_num(&p, stamp);
    p_text(&p, job);
    return pg_cmd(c,
                  "INSERT INTO results(hash, bytes, created, last_used, job)"
                  " VALUES($1, $2, $3, $3, $4) ON CONFLICT (hash) DO UPDATE SET"
                  " bytes = excluded.bytes, created = excluded.created,"
                  " last_used = excluded.last_used, job = excluded.job",
                  &p, "result_put", err, errlen)
               ? STORE_ERR
               : STORE_OK;
}

/* The trigger deletes its chunks with the row. */
static int pg_be_result_delete(pg_conn *c, const char *hash, const char *where, char *err,
                               size_t errlen)
{
    return pg_cmd_hash(c, "DELETE FROM results WHERE hash = $1", hash, where, err, errlen);
}

/* A connection lost since the read leaves the mark (the read was whole: best effort). */
static int pg_be_result_touch(pg_conn *c, const char *hash, double stamp, const char *where,
                              char *err, size_t errlen)
{
    if (!c->db) return STORE_OK;
    pg_params p = {0};
    p_text(&p, hash);
    p_num(&p, stamp);
    return pg_cmd(c, "UPDATE results SET last_used = $2 WHERE hash = $1", &p, where, err, errlen)
               ? STORE_ERR
               : STORE_OK;
}

static int pg_be_chunk_put(pg_conn *c, const char *hash, uint64_t off, const void *data, size_t n,
                           const unsigned char sha[32], char *err, size_t errlen)
{
    pg_params p = {0};
    p_text(&p, hash);
    p_int(&p, (long long)off);
    p_bin(&p, data, n);
    p_bin(&p, sha, 32);
    return pg_cmd(c,
                  "INSERT INTO result_chunks(hash, off, body, sha) VALUES($1, $2, $3, $4)"
                  " ON CONFLICT (hash, off) DO UPDATE SET body = excluded.body,"
                  " sha = excluded.sha",
                  &p, "result_put: chunk", err, errlen)
               ? STORE_ERR
               : STORE_OK;
}

/* The two numbers of the one row of sql (key its $1, or NULL for none). */
static int pg_two(pg_conn *c, const char *sql, const char *key, long long *x, long long *y,
                  const char *where, char *err, size_t errlen)
{
    PGresult *r = key ? pg_by_key(c, sql, key, 0, where, err, errlen)
                      : pg_rows(c, sql, NULL, 0, where, err, errlen);
    if (!r) return STORE_ERR;
    *x = strtoll(PQgetvalue(r, 0, 0), NULL, 10);
    *y = strtoll(PQgetvalue(r, 0, 1), NULL, 10);
    PQclear(r);
    return STORE_OK;
}

static int pg_be_chunks_sum(pg_conn *c, const char *hash, uint64_t *count, uint64_t *bytes,
                            char *err, size_t errlen)
{
    long long n = 0, b = 0;
    int rc = pg_two(c,
                    "SELECT count(*), coalesce(sum(length(body)), 0) FROM result_chunks"
                    " WHERE hash = $1",
                    hash, &n, &b, "result_put: sum", err, errlen);
    *count = (uint64_t)n;
    *bytes = (uint64_t)b;
    return rc;
}

/* One query, its rows in binary (bytea as bytes, off as int8). */
static int pg_be_chunks_read(pg_conn *c, const char *hash, long long at, store_chunk_fn fn,
                             void *ctx, const char *where, char *err, size_t errlen)
{
    pg_params p = {0};
    p_text(&p, hash);
    if (at >= 0) p_int(&p, at);
    PGresult *r = pg_rows(c,
                          at < 0 ? "SELECT off, body, sha FROM result_chunks WHERE hash = $1"
                                   " ORDER BY off"
                                 : "SELECT off, body, sha FROM result_chunks WHERE hash = $1"
                                   " AND off <= $2 ORDER BY off DESC LIMIT 1",
                          &p, 1, where, err, errlen);
    if (!r) return STORE_ERR;
    int rc = at >= 0 && !PQntuples(r) ? STORE_NOTFOUND : STORE_OK;
    for (int i = 0; rc == STORE_OK && i < PQntuples(r); i++) {
        int nosha = PQgetisnull(r, i, 2);
        rc = fn(ctx, be64(PQgetvalue(r, i, 0)), PQgetvalue(r, i, 1), (size_t)PQgetlength(r, i, 1),
                nosha ? NULL : PQgetvalue(r, i, 2), nosha ? 0 : (size_t)PQgetlength(r, i, 2));
    }
    PQclear(r);
    return rc;
}

static int pg_be_totals(pg_conn *c, size_t *count, uint64_t *bytes, const char *where, char *err,
                        size_t errlen)
{
    PGresult *r = pg_rows(c, "SELECT count, bytes FROM result_totals WHERE id = 0", NULL, 0, where,
                          err, errlen);
    if (!r) return STORE_ERR;
    int rc = PQntuples(r) ? STORE_OK : STORE_ERR;
    if (rc == STORE_OK) {
        if (count) *count = (size_t)strtoull(PQgetvalue(r, 0, 0), NULL, 10);
        if (bytes) *bytes = strtoull(PQgetvalue(r, 0, 1), NULL, 10);
    } else {
        util_seterr(err, errlen, STORE_ERR, "postgresql %s: the result_totals row is missing",
                    where);
    }
    PQclear(r);
    return rc;
}

/* SKIP LOCKED: a result another daemon is reading or writing is not waited for. */
static int pg_be_evict_one(pg_conn *c, const char *keep, int *gone, char *err, size_t errlen)
{
    pg_params p = {0};
    long long n = 0;
    p_text(&p, keep);
    if (pg_changed(c,
                   "DELETE FROM results WHERE hash = (SELECT hash FROM results WHERE hash <> $1"
                   " ORDER BY last_used LIMIT 1 FOR UPDATE SKIP LOCKED)",
                   &p, &n, "result_put: evict", err, errlen))
        return STORE_ERR;
    *gone = n > 0;
    return STORE_OK;
}

/* One statement; chunks of no result are an error here (no put leaves any). */
static int pg_be_recount(pg_conn *c, store_recount *v, char *err, size_t errlen)
{
    PGresult *r = pg_rows(
        c,
        STORE_SQL_RECOUNT
        ", (SELECT count(*) FROM result_chunks WHERE hash NOT IN (SELECT hash FROM results))"
        " FROM result_totals t WHERE t.id = 0",
        NULL, 0, "check", err, errlen);
    if (!r) return STORE_ERR;
    int rc = PQntuples(r) ? STORE_OK : STORE_NOTFOUND;
    long long *f[7] = {&v->tot_count, &v->tot_bytes, &v->count,  &v->bytes,
                       &v->bad_size,  &v->bad_off,   &v->orphans};
    for (int i = 0; rc == STORE_OK && i < 7; i++) *f[i] = strtoll(PQgetvalue(r, 0, i), NULL, 10);
    PQclear(r);
    return rc;
}

static int pg_be_chunks_digests(pg_conn *c, long long *all, long long *bad, char *err,
                                size_t errlen)
{
    return pg_two(c,
                  "SELECT count(*), count(*) FILTER (WHERE sha IS NULL OR sha <> sha256(body))"
                  " FROM result_chunks",
                  NULL, all, bad, "check", err, errlen);
}

/* The totals row rewritten as it is, under a statement timeout of a second, rolled back. */
static int pg_be_probe(pg_conn *c, char *err, size_t errlen)
{
    if (pg_begin(c, "writable", err, errlen)) return STORE_ERR;
    int rc = pg_cmd(c, "SET LOCAL statement_timeout = 1000", NULL, "writable", err, errlen) ||
                     pg_cmd(c, "UPDATE result_totals SET count = count WHERE id = 0", NULL,
                            "writable", err, errlen)
                 ? STORE_ERR
                 : STORE_OK;
    pg_be_rollback(c);
    return rc;
}

static void pg_be_close(store *base)
{
    pg_store *s = (pg_store *)base;
    if (!s) return;
    store_conns_free(&s->conns);
    if (s->listen) PQfinish(s->listen);
    free(s->conninfo);
    free(s);
}

/* events by NOTIFY; a put is one transaction and leaves no chunk behind (no chunks_forget);
 * no check of the database's own */
static const store_be_ops pg_be = {STORE_BE_PRIMITIVES(pg_be), .name = "postgresql",
                                   .notify = pg_be_notify,     .wait_event = pg_be_wait_event,
                                   .chunks_forget = NULL,      .integrity = NULL};

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
        util_seterr(
            err, errlen, STORE_ERR,
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
        util_seterr(err, errlen, STORE_ERR,
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
    pg_be_rollback(c);
    return STORE_ERR;
}

store *store_pg_open(const char *conninfo, uint64_t budget_bytes, double touch_seconds, int flags,
                     char *err, size_t errlen)
{
    pg_store *s = calloc(1, sizeof *s);
    const char *what;
    if (!s || !(s->conninfo = strdup(conninfo))) {
        util_seterr(err, errlen, STORE_ERR, "postgresql open: out of memory");
        goto fail;
    }
    s->base.ops = &store_ops_shared;
    s->base.be = &pg_be;
    s->base.shared = 1;
    s->base.budget = budget_bytes;
    s->base.touch_seconds = touch_seconds > 0 ? touch_seconds : 0;
    s->base.put_batch = 0; /* a put is one transaction (see the file comment) */
    if ((what = store_conns_init(&s->conns, pg_conn_new, pg_conn_close, s, "postgresql"))) {
        util_seterr(err, errlen, STORE_ERR, "postgresql open: %s failed", what);
        goto fail;
    }
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
        store_conns_free(&s->conns);
        free(s->conninfo);
        free(s);
    }
    return NULL;
}
