/* test_store.c — tests of the store (server/store.h) on its SQLite backend
 * (server/store_sqlite.c): jobs and their state machine, the result cache and its LRU budget,
 * persistence, schema versions, hostile files, the integrity check, and 8 threads at once.
 *
 * Every test works in its own directory made with mkdtemp and removes it at the end.  Where
 * the store's answer alone cannot show a property (user_version, last_used, the totals row),
 * the test looks into the file with SQLite directly, through a connection of its own.
 */
#include <dirent.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "server/store.h"
#include "tests/check.h"

/* ---- fixture: a temporary directory with a store in it ---- */

typedef struct fx {
    char dir[64];   /* the mkdtemp directory */
    char path[128]; /* dir/store.db */
    store *s;
    char err[512];
} fx;

static int fx_init(fx *f)
{
    memset(f, 0, sizeof *f);
    snprintf(f->dir, sizeof f->dir, "/tmp/cellar-test-store-XXXXXX");
    if (!mkdtemp(f->dir)) return -1;
    snprintf(f->path, sizeof f->path, "%s/store.db", f->dir);
    return 0;
}

static int fx_open(fx *f, uint64_t budget)
{
    f->err[0] = 0;
    f->s = store_sqlite_open(f->path, budget, 0, 0, f->err, sizeof f->err);
    return f->s ? 0 : -1;
}

static void fx_close(fx *f)
{
    if (f->s) f->s->ops->close(f->s);
    f->s = NULL;
}

/* Closes the store and removes the directory with everything in it (flat: db, -wal, -shm). */
static void fx_done(fx *f)
{
    DIR *d;
    struct dirent *e;
    char p[512];
    fx_close(f);
    if (!f->dir[0]) return;
    d = opendir(f->dir);
    if (d) {
        while ((e = readdir(d))) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
            snprintf(p, sizeof p, "%s/%s", f->dir, e->d_name);
            unlink(p);
        }
        closedir(d);
    }
    rmdir(f->dir);
}

/* ---- direct SQLite access, beside the store ---- */

/* The first column of the first row of sql as an integer; -999 on any error. */
static long long sql_int(const char *path, const char *sql)
{
    sqlite3 *db = NULL;
    sqlite3_stmt *st = NULL;
    long long v = -999;
    if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READWRITE, NULL) == SQLITE_OK &&
        sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
        v = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(db);
    return v;
}

static double sql_double(const char *path, const char *sql)
{
    sqlite3 *db = NULL;
    sqlite3_stmt *st = NULL;
    double v = -999;
    if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READWRITE, NULL) == SQLITE_OK &&
        sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
        v = sqlite3_column_double(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(db);
    return v;
}

/* The first column of the first row as text into out (empty on error). */
static void sql_text(const char *path, const char *sql, char *out, size_t cap)
{
    sqlite3 *db = NULL;
    sqlite3_stmt *st = NULL;
    out[0] = 0;
    if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READWRITE, NULL) == SQLITE_OK &&
        sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW &&
        sqlite3_column_text(st, 0))
        snprintf(out, cap, "%s", (const char *)sqlite3_column_text(st, 0));
    sqlite3_finalize(st);
    sqlite3_close(db);
}

static int sql_exec(const char *path, const char *sql)
{
    sqlite3 *db = NULL;
    int rc = sqlite3_open_v2(path, &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, NULL);
    if (rc == SQLITE_OK) rc = sqlite3_exec(db, sql, NULL, NULL, NULL);
    sqlite3_close(db);
    return rc;
}

/* ---- data ---- */

static void hash_of(char out[65], unsigned k)
{
    snprintf(out, 65, "%064x", k);
}

static void id_of(char out[33], unsigned k)
{
    snprintf(out, 33, "%032x", k);
}

static store_job job_make(unsigned k, const char *kind, job_state st, double created,
                          const char *req, size_t reqlen)
{
    store_job j;
    memset(&j, 0, sizeof j);
    id_of(j.id, k);
    hash_of(j.hash, 1000000 + k);
    snprintf(j.kind, sizeof j.kind, "%s", kind);
    j.state = st;
    j.created = created;
    j.request = (char *)req;
    j.request_len = reqlen;
    return j;
}

/* A body of n bytes that depends on k (and holds NUL bytes). */
static char *body_make(unsigned k, size_t n)
{
    char *b = malloc(n ? n : 1);
    for (size_t i = 0; b && i < n; i++) b[i] = (char)((i * 31 + k * 7) % 251);
    return b;
}

static int body_is(const char *b, size_t len, unsigned k, size_t n)
{
    if (!b || len != n || b[len] != 0) return 0;
    for (size_t i = 0; i < n; i++)
        if (b[i] != (char)((i * 31 + k * 7) % 251)) return 0;
    return 1;
}

static int put(store *s, unsigned k, size_t n)
{
    char h[65], err[256];
    char *b = body_make(k, n);
    int rc;
    hash_of(h, k);
    rc = s->ops->result_put(s, h, b, n, err, sizeof err);
    if (rc) printf("  put %u: %s\n", k, err);
    free(b);
    return rc;
}

static int exists(store *s, unsigned k)
{
    char h[65], err[256];
    hash_of(h, k);
    return s->ops->result_exists(s, h, err, sizeof err) == STORE_OK;
}

/* result_get of k: 1 when found with the body put(k, n) wrote, 0 when absent, -1 otherwise */
static int get_is(store *s, unsigned k, size_t n)
{
    char h[65], err[256], *b = NULL;
    size_t len = 0;
    int rc;
    hash_of(h, k);
    rc = s->ops->result_get(s, h, &b, &len, err, sizeof err);
    if (rc == STORE_NOTFOUND) return b == NULL ? 0 : -1;
    rc = rc == STORE_OK && body_is(b, len, k, n) ? 1 : -1;
    free(b);
    return rc;
}

/* ---- tests ---- */

TEST(store_job_state_names_and_clear)
{
    CHECK(!strcmp(job_state_name(JOB_QUEUED), "queued"), "%s", job_state_name(JOB_QUEUED));
    CHECK(!strcmp(job_state_name(JOB_RUNNING), "running"), "%s", job_state_name(JOB_RUNNING));
    CHECK(!strcmp(job_state_name(JOB_DONE), "done"), "%s", job_state_name(JOB_DONE));
    CHECK(!strcmp(job_state_name(JOB_FAILED), "failed"), "%s", job_state_name(JOB_FAILED));
    CHECK(!strcmp(job_state_name(JOB_CANCELED), "canceled"), "%s", job_state_name(JOB_CANCELED));
    CHECK(!strcmp(job_state_name((job_state)42), "unknown"), "%s", job_state_name((job_state)42));
    store_job j = job_make(1, "lines", JOB_FAILED, 5, NULL, 0);
    j.error = strdup("boom");
    j.request = strdup("{}");
    j.request_len = 2;
    store_job_clear(&j);
    CHECK(!j.error && !j.request && !j.request_len && !j.id[0] && j.created == 0,
          "store_job_clear left fields set");
    store_job_clear(&j); /* twice is harmless */
    store_job_clear(NULL);
}

TEST(store_open_creates_schema)
{
    fx f;
    char mode[32];
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    store *s = f.s;
    struct stat sb;
    CHECK(stat(f.path, &sb) == 0 && S_ISREG(sb.st_mode), "no database file at %s", f.path);
    CHECK(sql_int(f.path, "PRAGMA user_version") == 7, "user_version %lld, want 7",
          sql_int(f.path, "PRAGMA user_version"));
    sql_text(f.path, "PRAGMA journal_mode", mode, sizeof mode);
    CHECK(!strcmp(mode, "wal"), "journal_mode %s, want wal", mode);
    CHECK(sql_int(f.path, "SELECT count(*) FROM sqlite_master WHERE name IN ('jobs', 'results',"
                          " 'result_chunks', 'jobs_state', 'results_last_used', 'result_totals',"
                          " 'subs', 'subs_job')") == 8,
          "tables and indexes missing");
    size_t n = 99;
    uint64_t bytes = 99;
    CHECK(s->ops->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 0 &&
              bytes == 0,
          "empty stats %zu %llu", n, (unsigned long long)bytes);
    store_job j;
    CHECK(s->ops->job_get(s, "00000000000000000000000000000000", &j, f.err, sizeof f.err) ==
                  STORE_NOTFOUND &&
              !j.request && !j.error,
          "job_get on an empty store");
    char h[65], *b = (char *)1;
    size_t len = 7;
    hash_of(h, 1);
    CHECK(s->ops->result_get(s, h, &b, &len, f.err, sizeof f.err) == STORE_NOTFOUND && !b &&
              len == 0,
          "result_get on an empty store");
    CHECK(s->ops->result_exists(s, h, f.err, sizeof f.err) == STORE_NOTFOUND, "result_exists");
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);
    fx_done(&f);
    CHECK(access(f.dir, F_OK) != 0, "temp dir %s not removed", f.dir);
}

TEST(store_job_roundtrip)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    store *s = f.s;
    static const char req[] = "{\"kind\":\"lines\",\0\"x\":\0\0[1,2]}\0tail";
    size_t reqlen = sizeof req; /* with the embedded NULs and the final one */
    store_job in = job_make(7, "solids", JOB_FAILED, 1700000000.25, req, reqlen);
    in.started = 1700000001.5;
    in.finished = 1700000002.75;
    in.error_status = 422;
    in.error = "segment 3: NaN coordinate";
    REQUIRE(s->ops->job_insert(s, &in, f.err, sizeof f.err) == STORE_OK, "insert: %s", f.err);
    store_job out;
    REQUIRE(s->ops->job_get(s, in.id, &out, f.err, sizeof f.err) == STORE_OK, "get: %s", f.err);
    CHECK(!strcmp(out.id, in.id), "id %s", out.id);
    CHECK(!strcmp(out.hash, in.hash), "hash %s", out.hash);
    CHECK(!strcmp(out.kind, "solids"), "kind %s", out.kind);
    CHECK(out.state == JOB_FAILED, "state %d", (int)out.state);
    CHECK(out.created == in.created && out.started == in.started && out.finished == in.finished,
          "times %.17g %.17g %.17g", out.created, out.started, out.finished);
    CHECK(out.error_status == 422, "error_status %d", out.error_status);
    CHECK(out.error && !strcmp(out.error, in.error), "error %s", out.error ? out.error : "NULL");
    CHECK(out.request_len == reqlen, "request_len %zu, want %zu", out.request_len, reqlen);
    CHECK(out.request && !memcmp(out.request, req, reqlen) && out.request[reqlen] == 0,
          "request bytes differ");
    store_job_clear(&out);

    /* a queued job: no times but created, no error, an empty request */
    store_job q = job_make(8, "lines", JOB_QUEUED, 0, NULL, 0);
    REQUIRE(s->ops->job_insert(s, &q, f.err, sizeof f.err) == STORE_OK, "insert: %s", f.err);
    REQUIRE(s->ops->job_get(s, q.id, &out, f.err, sizeof f.err) == STORE_OK, "get: %s", f.err);
    CHECK(out.state == JOB_QUEUED && out.created == 0 && out.started == 0 && out.finished == 0,
          "queued job fields");
    CHECK(out.error_status == 0 && out.error == NULL, "queued job has an error");
    CHECK(out.request && out.request_len == 0 && out.request[0] == 0, "empty request");
    store_job_clear(&out);
    CHECK(sql_int(f.path, "SELECT count(*) FROM jobs WHERE created IS NULL AND started IS NULL"
                          " AND error IS NULL AND error_status IS NULL") == 1,
          "zero times and no error are not stored as NULL");

    /* the same id again is refused, the first row stays */
    store_job dup = job_make(7, "lines", JOB_QUEUED, 1, "x", 1);
    f.err[0] = 0;
    CHECK(s->ops->job_insert(s, &dup, f.err, sizeof f.err) == STORE_ERR && f.err[0],
          "duplicate id accepted");
    CHECK(strstr(f.err, "UNIQUE") != NULL, "duplicate message: %s", f.err);
    REQUIRE(s->ops->job_get(s, in.id, &out, f.err, sizeof f.err) == STORE_OK, "get: %s", f.err);
    CHECK(!strcmp(out.kind, "solids") && out.request_len == reqlen, "first row changed");
    store_job_clear(&out);

    /* fields that do not fit and states that do not exist are refused */
    store_job bad = job_make(9, "lines", JOB_QUEUED, 1, "x", 1);
    memset(bad.kind, 'k', sizeof bad.kind);
    CHECK(s->ops->job_insert(s, &bad, f.err, sizeof f.err) == STORE_ERR && strstr(f.err, "kind"),
          "unterminated kind: %s", f.err);
    bad = job_make(9, "lines", (job_state)9, 1, "x", 1);
    CHECK(s->ops->job_insert(s, &bad, f.err, sizeof f.err) == STORE_ERR && strstr(f.err, "state"),
          "state 9: %s", f.err);
    CHECK(sql_int(f.path, "SELECT count(*) FROM jobs") == 2, "jobs %lld, want 2",
          sql_int(f.path, "SELECT count(*) FROM jobs"));
    fx_done(&f);
}

TEST(store_results_basic)
{
    fx f;
    char h[65], *b = NULL;
    size_t len = 0, n = 0;
    uint64_t bytes = 0;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    store *s = f.s;
    const store_ops *o = s->ops;
    REQUIRE(put(s, 1, 1000) == 0, "put 1");
    REQUIRE(put(s, 2, 3) == 0, "put 2");
    REQUIRE(put(s, 3, 0) == 0, "put 3 (empty)");
    CHECK(get_is(s, 1, 1000) == 1, "get 1");
    CHECK(get_is(s, 2, 3) == 1, "get 2");
    CHECK(get_is(s, 3, 0) == 1, "get 3 (empty)");
    CHECK(get_is(s, 4, 0) == 0, "get 4 (absent)");
    CHECK(exists(s, 1) && exists(s, 2) && exists(s, 3) && !exists(s, 4), "exists");
    CHECK(o->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 3 &&
              bytes == 1003,
          "stats %zu %llu, want 3 1003", n, (unsigned long long)bytes);

    /* a JSON body reads back as a C string too */
    hash_of(h, 5);
    REQUIRE(o->result_put(s, h, "{\"dim\":2}", 9, f.err, sizeof f.err) == STORE_OK, "put: %s",
            f.err);
    REQUIRE(o->result_get(s, h, &b, &len, f.err, sizeof f.err) == STORE_OK, "get: %s", f.err);
    CHECK(len == 9 && !strcmp(b, "{\"dim\":2}"), "body %s", b);
    free(b);

    /* replacing a hash: one row, the new body and size */
    REQUIRE(put(s, 1, 250) == 0, "put 1 again");
    CHECK(get_is(s, 1, 250) == 1, "get 1 after replace");
    CHECK(o->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 4 &&
              bytes == 250 + 3 + 0 + 9,
          "stats after replace %zu %llu", n, (unsigned long long)bytes);
    CHECK(sql_int(f.path, "SELECT count(*) FROM results") == 4, "rows after replace");

    /* result_get marks the result used, result_exists does not */
    const char *q = "SELECT last_used FROM results WHERE hash = "
                    "'0000000000000000000000000000000000000000000000000000000000000002'";
    double t0 = sql_double(f.path, q);
    CHECK(exists(s, 2), "exists 2");
    double t1 = sql_double(f.path, q);
    CHECK(t1 == t0, "result_exists moved last_used %.6f -> %.6f", t0, t1);
    CHECK(get_is(s, 2, 3) == 1, "get 2");
    double t2 = sql_double(f.path, q);
    CHECK(t2 > t1, "result_get did not move last_used %.6f -> %.6f", t1, t2);
    CHECK(sql_double(f.path, "SELECT max(last_used) FROM results") == t2,
          "the result just read is not the most recently used");
    CHECK(o->check(s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);
    fx_done(&f);
}

TEST(store_results_lru_budget)
{
    fx f;
    size_t n = 0;
    uint64_t bytes = 0;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 300) == 0, "open: %s", f.err);
    store *s = f.s;
    const store_ops *o = s->ops;
    REQUIRE(put(s, 1, 100) == 0 && put(s, 2, 100) == 0 && put(s, 3, 100) == 0, "puts");
    CHECK(exists(s, 1) && exists(s, 2) && exists(s, 3), "within budget, nothing evicted");
    /* 1 is read: 2 is now the least recently used, though 1 was inserted first */
    CHECK(get_is(s, 1, 100) == 1, "get 1");
    REQUIRE(put(s, 4, 100) == 0, "put 4");
    CHECK(exists(s, 1) && !exists(s, 2) && exists(s, 3) && exists(s, 4),
          "after put 4: want 1 3 4, have %d %d %d %d", exists(s, 1), exists(s, 2), exists(s, 3),
          exists(s, 4));
    CHECK(o->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 3 && bytes == 300,
          "stats %zu %llu, want 3 300", n, (unsigned long long)bytes);

    /* result_exists does not count as a use: 3 goes next */
    CHECK(exists(s, 3), "exists 3");
    REQUIRE(put(s, 5, 100) == 0, "put 5");
    CHECK(exists(s, 1) && !exists(s, 3) && exists(s, 4) && exists(s, 5), "after put 5");

    /* one put may evict several: 250 bytes need 1 and 4 gone (LRU first), 5 stays */
    REQUIRE(put(s, 6, 200) == 0, "put 6");
    CHECK(!exists(s, 1) && !exists(s, 4) && exists(s, 5) && exists(s, 6),
          "after put 6: have 1:%d 4:%d 5:%d 6:%d", exists(s, 1), exists(s, 4), exists(s, 5),
          exists(s, 6));
    CHECK(o->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 2 && bytes == 300,
          "stats %zu %llu, want 2 300", n, (unsigned long long)bytes);

    /* replacing a result with a bigger body evicts others, never itself */
    REQUIRE(put(s, 5, 250) == 0, "replace 5");
    CHECK(exists(s, 5) && !exists(s, 6) && get_is(s, 5, 250) == 1, "after replacing 5");

    /* larger than the whole budget: stored, alone */
    REQUIRE(put(s, 7, 1000) == 0, "put 7");
    CHECK(get_is(s, 7, 1000) == 1 && !exists(s, 5), "the oversized result");
    CHECK(o->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 1 &&
              bytes == 1000,
          "stats %zu %llu, want 1 1000", n, (unsigned long long)bytes);
    /* and the next put evicts it */
    REQUIRE(put(s, 8, 50) == 0, "put 8");
    CHECK(!exists(s, 7) && get_is(s, 8, 50) == 1, "after put 8");
    CHECK(o->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 1 && bytes == 50,
          "stats %zu %llu, want 1 50", n, (unsigned long long)bytes);
    CHECK(o->check(s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);
    fx_done(&f);
}

TEST(store_many_results_evicted_in_order)
{
    /* 10000 puts of 1000 bytes into a budget of 2500: the last 2500 stay, exactly */
    fx f;
    size_t n = 0;
    uint64_t bytes = 0;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 2500 * 1000) == 0, "open: %s", f.err);
    store *s = f.s;
    for (unsigned k = 0; k < 10000; k++) REQUIRE(put(s, k, 1000) == 0, "put %u", k);
    CHECK(s->ops->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 2500 &&
              bytes == 2500 * 1000,
          "stats %zu %llu", n, (unsigned long long)bytes);
    CHECK(!exists(s, 0) && !exists(s, 7499) && exists(s, 7500) && exists(s, 9999),
          "the wrong results were evicted");
    CHECK(sql_int(f.path,
                  "SELECT count(*) FROM results WHERE hash < "
                  "'0000000000000000000000000000000000000000000000000000000000001d4c'") == 0,
          "a result older than 7500 (0x1d4c) survived");
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);
    fx_done(&f);
}

TEST(store_persists_across_reopen)
{
    fx f;
    store_job out;
    size_t n = 0;
    uint64_t bytes = 0;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 300) == 0, "open: %s", f.err);
    store_job j = job_make(1, "lines", JOB_RUNNING, 10, "{\"a\":1}", 7);
    j.started = 11;
    REQUIRE(f.s->ops->job_insert(f.s, &j, f.err, sizeof f.err) == STORE_OK, "%s", f.err);
    REQUIRE(put(f.s, 1, 100) == 0 && put(f.s, 2, 100) == 0 && put(f.s, 3, 100) == 0, "puts");
    CHECK(get_is(f.s, 1, 100) == 1, "get 1"); /* 2 is the least recently used */
    fx_close(&f);
    CHECK(access(f.path, F_OK) == 0, "database file gone after close");

    REQUIRE(fx_open(&f, 300) == 0, "reopen: %s", f.err);
    REQUIRE(f.s->ops->job_get(f.s, j.id, &out, f.err, sizeof f.err) == STORE_OK, "%s", f.err);
    CHECK(out.state == JOB_RUNNING && out.created == 10 && out.started == 11 &&
              out.request_len == 7 && !memcmp(out.request, "{\"a\":1}", 7),
          "job after reopen");
    store_job_clear(&out);
    size_t queued = 9, running = 9;
    CHECK(f.s->ops->job_counts(f.s, &queued, &running, f.err, sizeof f.err) == STORE_OK &&
              queued == 0 && running == 1,
          "after reopen: %zu queued, %zu running", queued, running);
    CHECK(f.s->ops->result_stats(f.s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 3 &&
              bytes == 300,
          "stats after reopen %zu %llu", n, (unsigned long long)bytes);
    CHECK(get_is(f.s, 3, 100) == 1, "get 3 after reopen");
    /* the use order survived: 2 goes first */
    REQUIRE(put(f.s, 4, 100) == 0, "put 4");
    CHECK(exists(f.s, 1) && !exists(f.s, 2) && exists(f.s, 3) && exists(f.s, 4),
          "LRU order after reopen");
    fx_close(&f);

    /* a smaller budget at the next open applies at the next put */
    REQUIRE(fx_open(&f, 150) == 0, "reopen: %s", f.err);
    REQUIRE(put(f.s, 5, 100) == 0, "put 5");
    CHECK(f.s->ops->result_stats(f.s, &n, &bytes, f.err, sizeof f.err) == STORE_OK && n == 1 &&
              bytes == 100 && exists(f.s, 5),
          "stats under the smaller budget %zu %llu", n, (unsigned long long)bytes);
    fx_done(&f);
}

TEST(store_schema_versions)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    /* an older database (version 0: made by someone else, with a table of its own) is
     * migrated, its content kept */
    REQUIRE(sql_exec(f.path, "CREATE TABLE notes(t TEXT); INSERT INTO notes VALUES('kept');") ==
                SQLITE_OK,
            "making a version-0 database");
    CHECK(sql_int(f.path, "PRAGMA user_version") == 0, "not version 0");
    /* refused as it is: someone else's database is no store unless --init says so */
    CHECK(fx_open(&f, 0) != 0 && strstr(f.err, "a SQLite database of something else") &&
              strstr(f.err, "--init"),
          "a foreign database was opened: %s", f.err);
    CHECK(sql_int(f.path, "SELECT count(*) FROM sqlite_master") == 1, "the refusal changed it");
    f.s = store_sqlite_open(f.path, 0, 0, STORE_OPEN_INIT, f.err, sizeof f.err);
    REQUIRE(f.s, "open of a version-0 database with --init: %s", f.err);
    CHECK(sql_int(f.path, "PRAGMA application_id") == 0x63656c6c, "application_id %lld",
          sql_int(f.path, "PRAGMA application_id"));
    CHECK(sql_int(f.path, "PRAGMA user_version") == 7, "user_version %lld after migration",
          sql_int(f.path, "PRAGMA user_version"));
    char t[16];
    sql_text(f.path, "SELECT t FROM notes", t, sizeof t);
    CHECK(!strcmp(t, "kept"), "the database's own table lost: '%s'", t);
    REQUIRE(put(f.s, 1, 10) == 0, "put after migration");
    fx_close(&f);

    /* opening again does not migrate again */
    REQUIRE(fx_open(&f, 0) == 0, "reopen: %s", f.err);
    CHECK(get_is(f.s, 1, 10) == 1, "result after reopen");
    fx_close(&f);

    /* a newer version is refused, and left as it is */
    REQUIRE(sql_exec(f.path, "PRAGMA user_version = 99") == SQLITE_OK, "setting user_version");
    CHECK(fx_open(&f, 0) != 0, "a version-99 database was opened");
    CHECK(strstr(f.err, "database schema version 99 is newer than this cellard") != NULL,
          "message: %s", f.err);
    CHECK(strstr(f.err, f.path) != NULL, "message does not name the file: %s", f.err);
    CHECK(sql_int(f.path, "PRAGMA user_version") == 99, "user_version changed");
    CHECK(sql_int(f.path, "SELECT count(*) FROM results") == 1, "results changed");
    /* so is a negative one, which no cellard ever wrote */
    REQUIRE(sql_exec(f.path, "PRAGMA user_version = -3") == SQLITE_OK, "setting user_version");
    CHECK(fx_open(&f, 0) != 0 && strstr(f.err, "version -3"), "version -3: %s", f.err);
    fx_done(&f);
}

TEST(store_open_refuses_garbage)
{
    fx f;
    char bad[160], dirpath[160];
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    static const char text[] = "this is a text file, not a database; "
                               "it is long enough to fill a header and then some more.\n"
                               "second line of plain text to be sure it spans 100 bytes.\n";
    FILE *fp = fopen(f.path, "wb");
    REQUIRE(fp, "cannot write %s", f.path);
    fwrite(text, 1, sizeof text - 1, fp);
    fclose(fp);
    CHECK(fx_open(&f, 0) != 0, "a text file was opened as a store");
    CHECK(strstr(f.err, "not a SQLite database") && strstr(f.err, f.path), "message: %s", f.err);
    size_t len = 0;
    char *after = test_read_file(f.path, &len);
    CHECK(after && len == sizeof text - 1 && !memcmp(after, text, len),
          "the text file was changed");
    free(after);
    snprintf(bad, sizeof bad, "%s-wal", f.path);
    CHECK(access(bad, F_OK) != 0, "a WAL file was made next to the text file");

    /* a file in a directory that does not exist */
    snprintf(dirpath, sizeof dirpath, "%s/no/such/dir/store.db", f.dir);
    f.err[0] = 0;
    store *s = store_sqlite_open(dirpath, 0, 0, 0, f.err, sizeof f.err);
    CHECK(!s && (strstr(f.err, "unable to open") || strstr(f.err, "cannot open")) &&
              strstr(f.err, dirpath),
          "message: %s", f.err);
    if (s) s->ops->close(s);
    f.err[0] = 0;
    CHECK(!store_sqlite_open("", 0, 0, 0, f.err, sizeof f.err) && f.err[0], "empty path");
    fx_done(&f);
}

/* One daemon per SQLite file: a second store on the same file is refused while the first is
 * open, and taken once it is closed. */
TEST(store_one_daemon_per_file)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    char err[512] = "";
    store *second = store_sqlite_open(f.path, 0, 0, 0, err, sizeof err);
    CHECK(!second && strstr(err, "another cellard is using this database") &&
              strstr(err, "postgresql://") && strstr(err, f.path),
          "a second store on the same file: %s", second ? "opened" : err);
    if (second) second->ops->close(second);
    fx_close(&f);
    second = store_sqlite_open(f.path, 0, 0, 0, err, sizeof err);
    CHECK(second != NULL, "the file once the first store closed: %s", err);
    if (second) second->ops->close(second);
    fx_done(&f);
}

TEST(store_check_reports_problems)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    REQUIRE(put(f.s, 1, 100) == 0 && put(f.s, 2, 50) == 0, "puts");
    strcpy(f.err, "untouched");
    CHECK(f.s->ops->check(f.s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);
    CHECK(!strcmp(f.err, "untouched"), "check wrote a message on success: %s", f.err);
    /* someone edits the file behind the store's back: the totals no longer add up */
    REQUIRE(sql_exec(f.path, "UPDATE result_totals SET bytes = bytes + 1") == SQLITE_OK, "update");
    CHECK(f.s->ops->check(f.s, f.err, sizeof f.err) == STORE_ERR, "check passed a bad total");
    CHECK(strstr(f.err, "result_totals") && strstr(f.err, "151") && strstr(f.err, "150"),
          "message: %s", f.err);
    /* an index that no longer matches its table */
    REQUIRE(sql_exec(f.path, "UPDATE result_totals SET bytes = bytes - 1;"
                             "PRAGMA writable_schema = ON;"
                             "UPDATE sqlite_schema SET sql = replace(sql, 'last_used)', 'bytes)')"
                             " WHERE name = 'results_last_used';") == SQLITE_OK,
            "breaking the index");
    fx_close(&f);
    REQUIRE(fx_open(&f, 0) == 0, "reopen: %s", f.err);
    CHECK(f.s->ops->check(f.s, f.err, sizeof f.err) == STORE_ERR, "check passed a bad index");
    CHECK(strstr(f.err, "results_last_used") != NULL, "message: %s", f.err);
    fx_done(&f);
}

/* ---- 8 threads at once ---- */

#define NTHREADS 8
#define NITER    300

typedef struct worker {
    store *s;
    unsigned t;
    int errors, bad;
    char first[320]; /* room for what and a whole err */
} worker;

static void worker_err(worker *w, const char *what, const char *err)
{
    if (!w->errors++) snprintf(w->first, sizeof w->first, "%s: %s", what, err);
}

static size_t worker_size(unsigned k)
{
    return 200 + (k * 37) % 700;
}

static void *worker_run(void *arg)
{
    worker *w = arg;
    store *s = w->s;
    const store_ops *o = s->ops;
    char err[256], req[64];
    for (unsigned i = 0; i < NITER; i++) {
        unsigned k = w->t * 100000 + i;
        store_job j;
        int n = snprintf(req, sizeof req, "{\"t\":%u,\"i\":%u}", w->t, i);
        switch (i % 4) {
        case 0: { /* a job's short life: queued, then its submission canceled */
            int changed = 0, what = 0;
            j = job_make(k, "lines", JOB_QUEUED, 1000 + i, req, (size_t)n);
            if (o->job_insert(s, &j, err, sizeof err)) worker_err(w, "job_insert", err);
            if (o->sub_cancel(s, j.id, 3000 + i, &changed, &what, err, sizeof err))
                worker_err(w, "sub_cancel", err);
            else if (!changed || what != STORE_JOB_CANCELED)
                w->bad++;
            break;
        }
        case 1: /* a result, sometimes a replacement of an earlier one */
            if (put(s, w->t * 100000 + i % 50, worker_size(w->t * 100000 + i % 50)))
                worker_err(w, "result_put", "see above");
            break;
        case 2: { /* read back a recent result (it may have been evicted) and a job */
            unsigned r = w->t * 100000 + (i - 1) % 50;
            if (get_is(s, r, worker_size(r)) < 0) worker_err(w, "result_get", "wrong body");
            store_job out;
            id_of(j.id, w->t * 100000 + i - 2);
            if (o->job_get(s, j.id, &out, err, sizeof err) != STORE_OK)
                worker_err(w, "job_get", err);
            else {
                if (out.state != JOB_CANCELED || out.finished != 3000 + i - 2) w->bad++;
                store_job_clear(&out);
            }
            break;
        }
        case 3: {
            size_t cnt;
            uint64_t bytes;
            exists(s, w->t * 100000 + i % 50);
            if (o->result_stats(s, &cnt, &bytes, err, sizeof err))
                worker_err(w, "result_stats", err);
            else if (bytes > 64 * 1024)
                w->bad++;
            break;
        }
        }
    }
    return NULL;
}

TEST(store_concurrent_threads)
{
    fx f;
    pthread_t th[NTHREADS];
    worker w[NTHREADS];
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 64 * 1024) == 0, "open: %s", f.err);
    for (unsigned t = 0; t < NTHREADS; t++) {
        memset(&w[t], 0, sizeof w[t]);
        w[t].s = f.s;
        w[t].t = t + 1;
        REQUIRE(pthread_create(&th[t], NULL, worker_run, &w[t]) == 0, "pthread_create");
    }
    for (unsigned t = 0; t < NTHREADS; t++) pthread_join(th[t], NULL);
    for (unsigned t = 0; t < NTHREADS; t++) {
        CHECK(w[t].errors == 0, "thread %u: %d errors, first %s", t, w[t].errors, w[t].first);
        CHECK(w[t].bad == 0, "thread %u: %d wrong values", t, w[t].bad);
    }
    store *s = f.s;
    size_t n = 0;
    uint64_t bytes = 0;
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);
    CHECK(s->ops->result_stats(s, &n, &bytes, f.err, sizeof f.err) == STORE_OK, "%s", f.err);
    CHECK(bytes <= 64 * 1024 && n > 0, "total %llu over the budget, %zu results",
          (unsigned long long)bytes, n);
    CHECK((long long)bytes == sql_int(f.path, "SELECT sum(bytes) FROM results") &&
              (long long)n == sql_int(f.path, "SELECT count(*) FROM results"),
          "stats %zu %llu disagree with the table", n, (unsigned long long)bytes);
    CHECK(sql_int(f.path,
                  "SELECT count(*) FROM results r WHERE r.bytes <>"
                  " (SELECT sum(length(body)) FROM result_chunks c WHERE c.hash = r.hash)") == 0,
          "a row's bytes is not its chunks' length");
    CHECK(sql_int(
              f.path,
              "SELECT count(*) FROM result_chunks WHERE hash NOT IN (SELECT hash FROM results)") ==
              0,
          "chunks left with no result");
    long long jobs = sql_int(f.path, "SELECT count(*) FROM jobs WHERE state = 4");
    CHECK(jobs == NTHREADS * NITER / 4, "%lld canceled jobs, want %d", jobs, NTHREADS * NITER / 4);
    size_t queued = 9, running = 9;
    CHECK(s->ops->job_counts(s, &queued, &running, f.err, sizeof f.err) == STORE_OK &&
              queued == 0 && running == 0,
          "%zu queued, %zu running", queued, running);
    /* the threads' connections are closed; the store still works from this one */
    REQUIRE(put(s, 1, 10) == 0 && get_is(s, 1, 10) == 1, "put/get after the threads");
    fx_done(&f);
}

/* A thread that uses the store and is still alive when the store closes: close() closes its
 * connection, and the thread's exit later must not touch the freed store. */
typedef struct idler {
    store *s;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int stage; /* 1: used the store, 2: the store is closed */
    int rc;
} idler;

static void *idler_run(void *arg)
{
    idler *d = arg;
    d->rc = put(d->s, 42, 10);
    pthread_mutex_lock(&d->mu);
    d->stage = 1;
    pthread_cond_broadcast(&d->cv);
    while (d->stage != 2) pthread_cond_wait(&d->cv, &d->mu);
    pthread_mutex_unlock(&d->mu);
    return NULL;
}

TEST(store_close_with_live_threads)
{
    fx f;
    pthread_t th;
    idler d = {.mu = PTHREAD_MUTEX_INITIALIZER, .cv = PTHREAD_COND_INITIALIZER};
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    d.s = f.s;
    REQUIRE(pthread_create(&th, NULL, idler_run, &d) == 0, "pthread_create");
    pthread_mutex_lock(&d.mu);
    while (d.stage != 1) pthread_cond_wait(&d.cv, &d.mu);
    pthread_mutex_unlock(&d.mu);
    fx_close(&f);
    pthread_mutex_lock(&d.mu);
    d.stage = 2;
    pthread_cond_broadcast(&d.cv);
    pthread_mutex_unlock(&d.mu);
    pthread_join(th, NULL);
    CHECK(d.rc == 0, "the thread's put failed");
    REQUIRE(fx_open(&f, 0) == 0, "reopen: %s", f.err);
    CHECK(get_is(f.s, 42, 10) == 1, "the thread's result is not in the file");
    fx_done(&f);
}

/* With a touch interval, reading a result whose mark is fresh does not move it (no write):
 * eviction then takes the result put first even though it was read last.  With 0 the read
 * moves it, and the other one goes. */
TEST(store_touch_interval)
{
    double intervals[2] = {3600, 0};
    const char *evicted[2] = {"a", "b"};
    char body[100];
    memset(body, 'x', sizeof body);
    for (int t = 0; t < 2; t++) {
        fx f;
        REQUIRE(fx_init(&f) == 0, "mkdtemp");
        f.s = store_sqlite_open(f.path, 250, intervals[t], 0, f.err, sizeof f.err);
        REQUIRE(f.s, "open: %s", f.err);
        char ha[65], hb[65], hc[65];
        memset(ha, 'a', 64);
        memset(hb, 'b', 64);
        memset(hc, 'c', 64);
        ha[64] = hb[64] = hc[64] = 0;
        CHECK(f.s->ops->result_put(f.s, ha, body, sizeof body, f.err, sizeof f.err) == 0, "put a");
        CHECK(f.s->ops->result_put(f.s, hb, body, sizeof body, f.err, sizeof f.err) == 0, "put b");
        char *got = NULL;
        size_t n = 0;
        CHECK(f.s->ops->result_get(f.s, ha, &got, &n, f.err, sizeof f.err) == 0 && n == 100,
              "get a");
        free(got);
        CHECK(f.s->ops->result_put(f.s, hc, body, sizeof body, f.err, sizeof f.err) == 0, "put c");
        const char *gone =
            f.s->ops->result_exists(f.s, ha, f.err, sizeof f.err) == STORE_NOTFOUND   ? "a"
            : f.s->ops->result_exists(f.s, hb, f.err, sizeof f.err) == STORE_NOTFOUND ? "b"
                                                                                      : "none";
        CHECK(!strcmp(gone, evicted[t]), "interval %g: %s evicted, want %s", intervals[t], gone,
              evicted[t]);
        fx_done(&f);
    }
}

/* ---- results in chunks ---- */

/* A file holding `skip` bytes of something else, then body_make(k, n); positioned at the body. */
static FILE *file_with_body(unsigned k, size_t n, size_t skip)
{
    FILE *f = tmpfile();
    char *b = body_make(k, n);
    if (f && b) {
        for (size_t i = 0; i < skip; i++) fputc('#', f);
        fwrite(b, 1, n, f);
        fflush(f);
        fseek(f, (long)skip, SEEK_SET);
    }
    free(b);
    return f;
}

/* Reads result k back through result_size and result_chunk, as a GET does: 1 when every
 * byte is body_make(k, n) and the chunks are as the store says they are. */
static int chunks_are(store *s, unsigned k, size_t n)
{
    char h[65], err[256];
    uint64_t size = 0, pos = 0;
    hash_of(h, k);
    if (s->ops->result_size(s, h, &size, NULL, err, sizeof err) != STORE_OK || size != n) return 0;
    char *want = body_make(k, n);
    int ok = want != NULL;
    while (ok && pos < size) {
        char *d = NULL;
        size_t len = 0;
        uint64_t start = 99;
        /* ask from the middle of a chunk too: the chunk holding pos comes back */
        uint64_t ask = pos + (pos / STORE_CHUNK) % 3;
        if (ask >= size) ask = pos;
        if (s->ops->result_chunk(s, h, ask, &d, &len, &start, err, sizeof err) != STORE_OK ||
            start != pos || len == 0 || len > STORE_CHUNK || start + len > size || d[len] != 0 ||
            memcmp(d, want + start, len))
            ok = 0;
        pos += len;
        free(d);
    }
    char *d = (char *)1;
    size_t len = 5;
    uint64_t start = 5;
    if (s->ops->result_chunk(s, h, size, &d, &len, &start, err, sizeof err) != STORE_NOTFOUND ||
        d || len)
        ok = 0; /* past the end */
    free(want);
    return ok;
}

TEST(store_large_results_in_chunks)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    store *s = f.s;
    char h[65];
    /* from a file, read from where it stands: 3 chunks and a piece */
    size_t n1 = 3 * STORE_CHUNK + 17;
    FILE *in = file_with_body(1, n1, 1000);
    REQUIRE(in, "tmpfile");
    hash_of(h, 1);
    CHECK(s->ops->result_put_file(s, h, NULL, in, n1, f.err, sizeof f.err) == STORE_OK, "put: %s",
          f.err);
    fclose(in);
    CHECK(sql_int(f.path, "SELECT count(*) FROM result_chunks") == 4, "%lld chunks, want 5",
          sql_int(f.path, "SELECT count(*) FROM result_chunks"));
    CHECK(chunks_are(s, 1, n1) == 1, "chunks of result 1 wrong");
    CHECK(get_is(s, 1, n1) == 1, "result_get of result 1 wrong");
    /* one past a chunk boundary, and exactly one chunk */
    CHECK(put(s, 2, STORE_CHUNK + 1) == 0 && chunks_are(s, 2, STORE_CHUNK + 1) == 1, "result 2");
    CHECK(put(s, 3, STORE_CHUNK) == 0 && chunks_are(s, 3, STORE_CHUNK) == 1, "result 3");
    /* more than one transaction's worth (SQ_BATCH: 32 chunks) */
    size_t n4 = 33 * STORE_CHUNK + 5;
    in = file_with_body(4, n4, 0);
    hash_of(h, 4);
    CHECK(s->ops->result_put_file(s, h, NULL, in, n4, f.err, sizeof f.err) == STORE_OK, "put: %s",
          f.err);
    fclose(in);
    CHECK(chunks_are(s, 4, n4) == 1 && get_is(s, 4, n4) == 1, "result 4 wrong");
    /* a replacement by a smaller body leaves no chunk of the old one */
    CHECK(put(s, 4, 100) == 0 && get_is(s, 4, 100) == 1, "replacement");
    hash_of(h, 4);
    CHECK(sql_int(f.path, "SELECT count(*) FROM result_chunks WHERE hash = '"
                          "0000000000000000000000000000000000000000000000000000000000000004'") == 1,
          "old chunks left after a replacement");
    /* a file shorter than announced, past the first transaction: nothing stored, nothing left */
    in = file_with_body(5, 34 * STORE_CHUNK, 0);
    hash_of(h, 5);
    CHECK(s->ops->result_put_file(s, h, NULL, in, 40 * STORE_CHUNK, f.err, sizeof f.err) ==
              STORE_ERR,
          "a short file was stored");
    CHECK(strstr(f.err, "ended after 35651584 of 41943040 bytes") != NULL, "message: %s", f.err);
    fclose(in);
    CHECK(!exists(s, 5), "the short result exists");
    CHECK(sql_int(f.path, "SELECT count(*) FROM result_chunks WHERE hash NOT IN"
                          " (SELECT hash FROM results)") == 0,
          "chunks of the failed put left");
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);
    size_t cnt = 0;
    uint64_t bytes = 0;
    CHECK(s->ops->result_stats(s, &cnt, &bytes, f.err, sizeof f.err) == STORE_OK && cnt == 4 &&
              bytes == n1 + 2 * STORE_CHUNK + 1 + 100,
          "stats %zu %llu", cnt, (unsigned long long)bytes);
    fx_done(&f);
}

/* The hash of result k in SQL quotes, for tests that edit the file. */
static const char *qhash(unsigned k)
{
    static char q[80];
    snprintf(q, sizeof q, "'%064x'", k);
    return q;
}

TEST(store_damaged_result_refused)
{
    fx f;
    char h[65], *b = NULL, sql[300];
    size_t len = 0;
    uint64_t start;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    store *s = f.s;
    REQUIRE(put(s, 1, 3 * STORE_CHUNK) == 0 && put(s, 2, 10) == 0 &&
                put(s, 3, 2 * STORE_CHUNK) == 0 && put(s, 4, STORE_CHUNK + 3000) == 0,
            "puts");
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);

    /* a chunk lost behind the store's back: check() sees it, a read drops the result */
    snprintf(sql, sizeof sql, "DELETE FROM result_chunks WHERE hash = %s AND off = 1048576",
             qhash(1));
    REQUIRE(sql_exec(f.path, sql) == SQLITE_OK, "delete");
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_ERR, "check passed a lost chunk");
    CHECK(strstr(f.err, "1 have chunks that do not add up"), "message: %s", f.err);
    hash_of(h, 1);
    CHECK(s->ops->result_get(s, h, &b, &len, f.err, sizeof f.err) == STORE_DAMAGED && !b,
          "a result with a lost chunk was returned");
    CHECK(strstr(f.err, "is damaged") && strstr(f.err, "at byte 2097152, where 1048576"),
          "message: %s", f.err);
    CHECK(!exists(s, 1), "the damaged result was kept");
    CHECK(sql_int(f.path,
                  "SELECT count(*) FROM result_chunks WHERE hash = "
                  "'0000000000000000000000000000000000000000000000000000000000000001'") == 0,
          "its chunks were kept");

    /* one byte changed in a chunk: its digest says so, whole or chunk by chunk */
    snprintf(sql, sizeof sql,
             "UPDATE result_chunks SET body = CAST(substr(body, 1, 4) || X'00' || substr(body, 6)"
             " AS BLOB)"
             " WHERE hash = %s",
             qhash(2));
    REQUIRE(sql_exec(f.path, sql) == SQLITE_OK, "update");
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_ERR &&
              strstr(f.err, "1 of 5 chunks do not match their digest"),
          "check: %s", f.err);
    hash_of(h, 2);
    CHECK(s->ops->result_get(s, h, &b, &len, f.err, sizeof f.err) == STORE_DAMAGED && !b,
          "changed bytes were returned");
    CHECK(strstr(f.err, "chunk at byte 0 does not match its digest"), "message: %s", f.err);
    CHECK(!exists(s, 2), "the changed result was kept");
    snprintf(sql, sizeof sql,
             "UPDATE result_chunks SET body = zeroblob(1048576) WHERE hash = %s AND off = 1048576",
             qhash(3));
    REQUIRE(sql_exec(f.path, sql) == SQLITE_OK, "update");
    hash_of(h, 3);
    CHECK(s->ops->result_chunk(s, h, 0, &b, &len, &start, f.err, sizeof f.err) == STORE_OK &&
              len == STORE_CHUNK,
          "the sound first chunk: %s", f.err);
    free(b);
    b = NULL;
    CHECK(s->ops->result_chunk(s, h, STORE_CHUNK + 7, &b, &len, &start, f.err, sizeof f.err) ==
                  STORE_DAMAGED &&
              !b,
          "a changed chunk was returned");
    CHECK(!exists(s, 3), "the result with a changed chunk was kept");

    /* the last chunk lost: sizes no longer add up */
    snprintf(sql, sizeof sql, "DELETE FROM result_chunks WHERE hash = %s AND off = 1048576",
             qhash(4));
    REQUIRE(sql_exec(f.path, sql) == SQLITE_OK, "truncate");
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_ERR, "check passed a short chunk");
    hash_of(h, 4);
    CHECK(s->ops->result_get(s, h, &b, &len, f.err, sizeof f.err) == STORE_DAMAGED && !b,
          "a short result was returned");
    CHECK(strstr(f.err, "hold 1048576 of its 1051576 bytes"), "message: %s", f.err);
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_OK, "check after the drops: %s", f.err);

    /* a chunk that does not start where the one before ends (and sizes that add up) */
    REQUIRE(put(s, 5, 10) == 0, "put");
    snprintf(sql, sizeof sql, "UPDATE result_chunks SET off = 3 WHERE hash = %s", qhash(5));
    REQUIRE(sql_exec(f.path, sql) == SQLITE_OK, "move");
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_ERR, "check passed a moved chunk");
    CHECK(strstr(f.err, "1 chunks do not start where"), "message: %s", f.err);
    fx_done(&f);
}

TEST(store_migrates_version_1)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    /* a database as the first cellard left it: bodies whole, one row each */
    REQUIRE(sql_exec(f.path,
                     "PRAGMA journal_mode=WAL;"
                     "CREATE TABLE jobs(id TEXT PRIMARY KEY, hash TEXT NOT NULL, kind TEXT NOT "
                     "NULL, state INTEGER NOT NULL, created REAL, started REAL, finished REAL,"
                     " error_status INTEGER, error TEXT, request BLOB NOT NULL);"
                     "CREATE INDEX jobs_state ON jobs(state);"
                     "CREATE TABLE results(hash TEXT PRIMARY KEY, bytes INTEGER NOT NULL, "
                     "created REAL, last_used REAL);"
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
                     " UPDATE result_totals SET bytes = bytes - OLD.bytes + NEW.bytes; END;"
                     "INSERT INTO results VALUES('" /* */
                     "0000000000000000000000000000000000000000000000000000000000000001', 10, 1, "
                     "1);"
                     "INSERT INTO result_bodies VALUES('"
                     "0000000000000000000000000000000000000000000000000000000000000001',"
                     " CAST('0123456789' AS BLOB));"
                     "INSERT INTO results VALUES('"
                     "0000000000000000000000000000000000000000000000000000000000000002', 2097152,"
                     " 2, 2);"
                     "INSERT INTO result_bodies VALUES('"
                     "0000000000000000000000000000000000000000000000000000000000000002',"
                     " zeroblob(2097152));"
                     "INSERT INTO jobs VALUES('00000000000000000000000000000001', 'h', 'lines',"
                     " 0, 3, NULL, NULL, NULL, NULL, CAST('{}' AS BLOB));"
                     "INSERT INTO jobs VALUES('00000000000000000000000000000002', 'h', 'lines',"
                     " 4, 4, NULL, 5, NULL, NULL, CAST('{}' AS BLOB));"
                     "PRAGMA user_version = 1;") == SQLITE_OK,
            "making a version-1 database");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    store *s = f.s;
    CHECK(sql_int(f.path, "PRAGMA user_version") == 7, "user_version %lld",
          sql_int(f.path, "PRAGMA user_version"));
    /* version 7: a job being canceled leaves the request's one-job-in-flight index */
    CHECK(sql_int(f.path, "SELECT count(*) FROM sqlite_master WHERE name = 'jobs_active_hash'"
                          " AND sql LIKE '%cancel = 0%'") == 1,
          "jobs_active_hash still counts jobs being canceled");
    CHECK(sql_int(f.path, "SELECT count(*) FROM sqlite_master WHERE name = 'result_bodies'") == 0,
          "result_bodies left");
    /* every job became its own first submission, canceled with it */
    store_sub sub;
    char jid[33];
    id_of(jid, 1);
    CHECK(s->ops->sub_get(s, jid, &sub, f.err, sizeof f.err) == STORE_OK && !strcmp(sub.job, jid) &&
              sub.created == 3 && sub.canceled == 0,
          "the queued job's submission after migration: %s", f.err);
    id_of(jid, 2);
    CHECK(s->ops->sub_get(s, jid, &sub, f.err, sizeof f.err) == STORE_OK && !strcmp(sub.job, jid) &&
              sub.canceled == 5,
          "the canceled job's submission after migration: %s", f.err);
    store_job mj;
    id_of(jid, 1);
    CHECK(s->ops->job_get(s, jid, &mj, f.err, sizeof f.err) == STORE_OK && mj.active_subs == 1,
          "active submissions of the migrated queued job: %d", mj.active_subs);
    store_job_clear(&mj);
    char h[65], *b = NULL;
    size_t len = 0;
    hash_of(h, 1);
    CHECK(s->ops->result_get(s, h, &b, &len, f.err, sizeof f.err) == STORE_OK && len == 10 &&
              !memcmp(b, "0123456789", 11),
          "result 1 after migration: %s", f.err);
    free(b);
    b = NULL;
    /* a body of two chunks' size became one chunk: read whole, and through result_chunk */
    hash_of(h, 2);
    CHECK(s->ops->result_get(s, h, &b, &len, f.err, sizeof f.err) == STORE_OK &&
              len == 2 * STORE_CHUNK,
          "result 2 after migration: %s", f.err);
    free(b);
    uint64_t start = 9;
    CHECK(s->ops->result_chunk(s, h, STORE_CHUNK + 3, &b, &len, &start, f.err, sizeof f.err) ==
                  STORE_OK &&
              start == 0 && len == 2 * STORE_CHUNK,
          "result_chunk of a migrated body");
    free(b);
    CHECK(s->ops->check(s, f.err, sizeof f.err) == STORE_OK, "check: %s", f.err);
    /* deleting a result deletes its chunks */
    REQUIRE(put(s, 3, 2000) == 0, "put");
    fx_close(&f);
    REQUIRE(sql_exec(f.path, "DELETE FROM results") == SQLITE_OK, "delete");
    CHECK(sql_int(f.path, "SELECT count(*) FROM result_chunks") == 0, "chunks left");
    fx_done(&f);
}

TEST(store_open_deletes_unfinished_puts)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    REQUIRE(put(f.s, 1, 3000) == 0, "put");
    fx_close(&f);
    /* chunks of a put that never wrote its results row (the process died) */
    REQUIRE(sql_exec(f.path, "INSERT INTO result_chunks VALUES('"
                             "0000000000000000000000000000000000000000000000000000000000000009',"
                             " 0, zeroblob(100), NULL)") == SQLITE_OK,
            "insert");
    REQUIRE(fx_open(&f, 0) == 0, "reopen: %s", f.err);
    CHECK(sql_int(f.path, "SELECT count(*) FROM result_chunks") == 1, "%lld chunks, want 1",
          sql_int(f.path, "SELECT count(*) FROM result_chunks"));
    CHECK(get_is(f.s, 1, 3000) == 1, "the finished result is gone");
    fx_done(&f);
}

TEST(store_refuses_empty_and_damaged_files)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    /* a file truncated to nothing is no empty store, unless asked for */
    FILE *fp = fopen(f.path, "wb");
    REQUIRE(fp, "create");
    fclose(fp);
    CHECK(fx_open(&f, 0) != 0 && strstr(f.err, "the file is empty") && strstr(f.err, "--init"),
          "an empty file was opened: %s", f.err);
    struct stat sb;
    CHECK(stat(f.path, &sb) == 0 && sb.st_size == 0, "the refusal wrote to the file");
    f.s = store_sqlite_open(f.path, 0, 0, STORE_OPEN_INIT, f.err, sizeof f.err);
    REQUIRE(f.s, "--init on an empty file: %s", f.err);
    for (unsigned k = 1; k <= 40; k++) REQUIRE(put(f.s, k, 60000 + k) == 0, "put %u", k);
    fx_close(&f);
    /* reopened without --init: it is ours now */
    REQUIRE(fx_open(&f, 0) == 0, "reopen: %s", f.err);
    CHECK(get_is(f.s, 7, 60007) == 1, "result 7");
    fx_close(&f);

    /* 4 KiB of garbage over the second page (a b-tree page): refused at open, not served */
    char junk[4096];
    uint64_t seed = 5;
    for (size_t i = 0; i < sizeof junk; i++) junk[i] = (char)(test_rnd(&seed) * 256);
    fp = fopen(f.path, "r+b");
    REQUIRE(fp, "open for writing");
    fseek(fp, 4096, SEEK_SET);
    fwrite(junk, 1, sizeof junk, fp);
    fclose(fp);
    CHECK(fx_open(&f, 0) != 0 && strstr(f.err, "the database is damaged") &&
              strstr(f.err, "quick_check") && strstr(f.err, "restore it from a backup"),
          "a damaged file was opened: %s", f.err);
    fx_done(&f);

    /* 4 KiB of garbage in the middle, where the results' bytes lie: whatever it hits, no
     * changed byte is served */
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    for (unsigned k = 1; k <= 40; k++) REQUIRE(put(f.s, k, 60000 + k) == 0, "put %u", k);
    fx_close(&f);
    REQUIRE(stat(f.path, &sb) == 0, "stat");
    fp = fopen(f.path, "r+b");
    REQUIRE(fp, "open for writing");
    fseek(fp, (long)(sb.st_size / 2 / 4096 * 4096 + 1000), SEEK_SET);
    fwrite(junk, 1, sizeof junk, fp);
    fclose(fp);
    if (fx_open(&f, 0) == 0) {
        int good = 0, damaged = 0, other = 0;
        for (unsigned k = 1; k <= 40; k++) {
            char h[65], *b = NULL;
            size_t len = 0;
            hash_of(h, k);
            int rc = f.s->ops->result_get(f.s, h, &b, &len, f.err, sizeof f.err);
            if (rc == STORE_OK && body_is(b, len, k, 60000 + k))
                good++;
            else if (rc == STORE_DAMAGED || rc == STORE_ERR)
                damaged++;
            else
                other++;
            free(b);
        }
        CHECK(other == 0 && damaged >= 1 && good + damaged == 40,
              "%d good, %d damaged, %d served wrong or lost", good, damaged, other);
    } else {
        CHECK(strstr(f.err, "damaged") != NULL, "refused, but: %s", f.err);
    }
    fx_done(&f);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

TEST(store_writable_probe)
{
    fx f;
    REQUIRE(fx_init(&f) == 0, "mkdtemp failed");
    REQUIRE(fx_open(&f, 0) == 0, "open: %s", f.err);
    CHECK(f.s->ops->writable(f.s, f.err, sizeof f.err) == STORE_OK, "writable: %s", f.err);
    /* another process holds the write lock: the probe gives up after a second */
    sqlite3 *db = NULL;
    REQUIRE(sqlite3_open(f.path, &db) == SQLITE_OK &&
                sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL) == SQLITE_OK,
            "lock");
    double t0 = now_s();
    CHECK(f.s->ops->writable(f.s, f.err, sizeof f.err) == STORE_ERR && strstr(f.err, "locked"),
          "writable under another's lock: %s", f.err);
    double dt = now_s() - t0;
    CHECK(dt > 0.5 && dt < 4, "the probe waited %.2f s", dt);
    sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL);
    sqlite3_close(db);
    CHECK(f.s->ops->writable(f.s, f.err, sizeof f.err) == STORE_OK, "writable again: %s", f.err);
    fx_done(&f);
}
