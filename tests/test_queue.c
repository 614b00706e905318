/* test_queue.c — the store's contract (server/store.h), one suite run on both backends: every
 * test runs once on a SQLite file in a temporary directory (NAME_sqlite) and once on a new
 * database of a private PostgreSQL server (NAME_pg, tests/pg.h).  What is checked: jobs as
 * written and read back, submissions that join a job in flight (single-flight by the store's
 * unique index, also from 8 threads at once), the queue (claims in order, leases renewed,
 * lost, given back and run out, attempts, the cancel flag), cancels of submissions, the
 * prune, the result cache (chunks, the LRU budget, digests), and PostgreSQL's events.
 *
 * What only one backend has (SQLite's files, schema migrations, locks) is in test_store.c. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "server/store.h"
#include "tests/check.h"
#include "tests/pg.h"

typedef struct be {
    int pg;
    char dir[64], db[256]; /* the SQLite file, or the PostgreSQL URI */
    store *s;
    char err[512];
} be;

static int be_open(be *b, uint64_t budget)
{
    b->err[0] = 0;
    b->s = b->pg ? store_pg_open(b->db, budget, 0, 0, b->err, sizeof b->err)
                 : store_sqlite_open(b->db, budget, 0, 0, b->err, sizeof b->err);
    return b->s ? 0 : -1;
}

static void be_close(be *b)
{
    if (b->s) b->s->ops->close(b->s);
    b->s = NULL;
}

/* A fresh store of backend pg (0 SQLite, 1 PostgreSQL): 0; 1 skipped; -1 failed. */
static int be_init(be *b, int pg)
{
    memset(b, 0, sizeof *b);
    b->pg = pg;
    if (pg) {
        int a = pg_available();
        if (a == 0) {
            test_skip("CELLAR_SKIP_PG=1");
            return 1;
        }
        if (a < 0 || pg_new_db(b->db, sizeof b->db)) return -1;
    } else {
        snprintf(b->dir, sizeof b->dir, "/tmp/cellar-test-queue-XXXXXX");
        if (!mkdtemp(b->dir)) return -1;
        snprintf(b->db, sizeof b->db, "%s/store.db", b->dir);
    }
    return be_open(b, 0);
}

static void be_done(be *b)
{
    be_close(b);
    if (b->dir[0]) {
        char cmd[128];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", b->dir);
        if (system(cmd) != 0) printf("  could not remove %s\n", b->dir);
    }
}

#define CONTRACT(name)                                                                             \
    static void name##_on(be *b);                                                                  \
    static void name##_run(int pg)                                                                 \
    {                                                                                              \
        be b;                                                                                      \
        int rc = be_init(&b, pg);                                                                  \
        if (rc < 0) test_fail(__FILE__, #name, __LINE__, "no store: %s", b.err);                   \
        if (rc == 0) name##_on(&b);                                                                \
        be_done(&b);                                                                               \
    }                                                                                              \
    TEST(name##_sqlite)                                                                            \
    {                                                                                              \
        name##_run(0);                                                                             \
    }                                                                                              \
    TEST(name##_pg)                                                                                \
    {                                                                                              \
        name##_run(1);                                                                             \
    }                                                                                              \
    static void name##_on(be *b)

/* ---- data ---- */

static void id_of(char out[33], unsigned k)
{
    snprintf(out, 33, "%032x", k);
}

static void hash_of(char out[65], unsigned k)
{
    snprintf(out, 65, "%064x", k);
}

static store_job job_make(unsigned k, unsigned h, job_state st, double created, const char *req,
                          size_t reqlen)
{
    store_job j;
    memset(&j, 0, sizeof j);
    id_of(j.id, k);
    hash_of(j.hash, h);
    snprintf(j.kind, sizeof j.kind, "lines");
    j.state = st;
    j.created = created;
    j.request = (char *)req;
    j.request_len = reqlen;
    return j;
}

/* job_submit of submission k for request hash h: the job's id in job (33 bytes) */
static int submit(be *b, unsigned k, unsigned h, double created, size_t queue_max, int join_only,
                  char *job, int *joined)
{
    char req[32];
    int n = snprintf(req, sizeof req, "{\"k\":%u}", h);
    store_job j = job_make(k, h, JOB_QUEUED, created, req, (size_t)n);
    return b->s->ops->job_submit(b->s, &j, queue_max, join_only, job, joined, b->err,
                                 sizeof b->err);
}

static store_job get(be *b, const char *id)
{
    store_job j;
    if (b->s->ops->job_get(b->s, id, &j, b->err, sizeof b->err) != STORE_OK) {
        memset(&j, 0, sizeof j);
        j.state = (job_state)-1;
    }
    return j;
}

/* ---- jobs ---- */

CONTRACT(queue_job_roundtrip)
{
    store *s = b->s;
    static const char req[] = "{\"kind\":\"lines\",\0\"x\":\0\0[1,2]}\0tail";
    store_job in = job_make(7, 7, JOB_FAILED, 1700000000.25, req, sizeof req);
    snprintf(in.kind, sizeof in.kind, "solids");
    in.started = 1700000001.5;
    in.finished = 1700000002.75;
    in.error_status = 422;
    in.error = "segment 3: NaN coordinate";
    REQUIRE(s->ops->job_insert(s, &in, b->err, sizeof b->err) == STORE_OK, "insert: %s", b->err);
    store_job out = get(b, in.id);
    CHECK(!strcmp(out.id, in.id) && !strcmp(out.hash, in.hash) && !strcmp(out.kind, "solids"),
          "id %s hash %s kind %s", out.id, out.hash, out.kind);
    CHECK(out.state == JOB_FAILED && out.created == in.created && out.started == in.started &&
              out.finished == in.finished,
          "state %d times %.17g %.17g %.17g", (int)out.state, out.created, out.started,
          out.finished);
    CHECK(out.error_status == 422 && out.error && !strcmp(out.error, in.error), "error %d %s",
          out.error_status, out.error ? out.error : "NULL");
    CHECK(out.request_len == sizeof req && out.request && !memcmp(out.request, req, sizeof req) &&
              out.request[sizeof req] == 0,
          "request of %zu bytes, want %zu with its NULs", out.request_len, sizeof req);
    CHECK(out.attempts == 0 && out.owner[0] == 0 && out.lease_until == 0 && !out.cancel,
          "a job inserted as is: attempts %d owner '%s'", out.attempts, out.owner);
    CHECK(out.active_subs == 1, "its first submission: %d active", out.active_subs);
    store_job_clear(&out);
    store_job q = job_make(8, 8, JOB_QUEUED, 0, NULL, 0);
    REQUIRE(s->ops->job_insert(s, &q, b->err, sizeof b->err) == STORE_OK, "insert: %s", b->err);
    out = get(b, q.id);
    CHECK(out.state == JOB_QUEUED && out.created == 0 && out.started == 0 && out.finished == 0 &&
              out.error_status == 0 && !out.error && out.request && out.request_len == 0,
          "an empty queued job read back: state %d", (int)out.state);
    store_job_clear(&out);
    /* the same id again is refused, and the first stays; bad fields are refused */
    store_job dup = job_make(7, 9, JOB_DONE, 1, "x", 1);
    b->err[0] = 0;
    CHECK(s->ops->job_insert(s, &dup, b->err, sizeof b->err) == STORE_ERR && b->err[0],
          "a duplicate id was taken");
    out = get(b, in.id);
    CHECK(!strcmp(out.kind, "solids"), "the first row changed");
    store_job_clear(&out);
    store_job bad = job_make(9, 9, (job_state)9, 1, "x", 1);
    CHECK(s->ops->job_insert(s, &bad, b->err, sizeof b->err) == STORE_ERR, "state 9 was taken");
    bad = job_make(9, 9, JOB_QUEUED, 1, "x", 1);
    memset(bad.kind, 'k', sizeof bad.kind);
    CHECK(s->ops->job_insert(s, &bad, b->err, sizeof b->err) == STORE_ERR, "a long kind");
    out = get(b, "ffffffffffffffffffffffffffffffff");
    CHECK((int)out.state == -1, "a job that does not exist was read");
    size_t queued = 9, running = 9;
    CHECK(s->ops->job_counts(s, &queued, &running, b->err, sizeof b->err) == STORE_OK &&
              queued == 1 && running == 0,
          "counts %zu %zu", queued, running);
}

CONTRACT(queue_submit_joins_and_refuses)
{
    store *s = b->s;
    char job[33], job2[33];
    int joined = 9;
    REQUIRE(submit(b, 1, 100, 10, 2, 0, job, &joined) == STORE_OK && !joined, "submit: %s", b->err);
    char id1[33];
    id_of(id1, 1);
    CHECK(!strcmp(job, id1), "a new job has its first submission's id: %s", job);
    /* the same request: joins, a submission of its own */
    REQUIRE(submit(b, 2, 100, 11, 2, 0, job2, &joined) == STORE_OK && joined, "join: %s", b->err);
    CHECK(!strcmp(job2, id1), "joined %s, want %s", job2, id1);
    store_sub sub;
    char id2[33];
    id_of(id2, 2);
    CHECK(s->ops->sub_get(s, id2, &sub, b->err, sizeof b->err) == STORE_OK &&
              !strcmp(sub.job, id1) && sub.created == 11 && sub.canceled == 0,
          "the joined submission: %s", b->err);
    store_job j = get(b, id1);
    CHECK(j.active_subs == 2 && j.created == 10, "active %d created %g", j.active_subs, j.created);
    store_job_clear(&j);
    /* join only: not for a request in no job */
    CHECK(submit(b, 3, 101, 12, 2, 1, job, &joined) == STORE_NOTFOUND && !joined,
          "join_only made something");
    j = get(b, (id_of(id2, 3), id2));
    CHECK((int)j.state == -1, "join_only made a job");
    /* the queue holds 2: a second request fits, a third does not; joins still do */
    REQUIRE(submit(b, 4, 102, 13, 2, 0, job, &joined) == STORE_OK && !joined, "2nd: %s", b->err);
    CHECK(submit(b, 5, 103, 14, 2, 0, job, &joined) == STORE_FULL, "a full queue took a job");
    CHECK(submit(b, 6, 102, 15, 2, 0, job, &joined) == STORE_OK && joined,
          "a join with the queue full");
    CHECK(submit(b, 7, 103, 16, 0, 0, job, &joined) == STORE_OK && !joined,
          "no limit (queue_max 0)");
    /* a request whose result is stored makes nothing */
    char h[65];
    hash_of(h, 104);
    REQUIRE(s->ops->result_put(s, h, "{}", 2, b->err, sizeof b->err) == STORE_OK, "put: %s",
            b->err);
    CHECK(submit(b, 8, 104, 17, 0, 0, job, &joined) == STORE_CACHED, "a cached request made a job");
    size_t queued = 0, running = 0;
    CHECK(s->ops->job_counts(s, &queued, &running, b->err, sizeof b->err) == STORE_OK &&
              queued == 3 && running == 0,
          "queued %zu running %zu, want 3 and 0", queued, running);
}

CONTRACT(queue_claims_leases_attempts)
{
    store *s = b->s;
    char job[33], a[33], c[33];
    int joined;
    store_job w;
    for (unsigned k = 1; k <= 3; k++)
        REQUIRE(submit(b, k, 200 + k, 100 - k, 0, 0, job, &joined) == STORE_OK, "submit %u: %s", k,
                b->err);
    /* oldest first: created 97 (k 3), then 98, 99 */
    REQUIRE(s->ops->job_claim(s, "A", 1000, 10, &w, b->err, sizeof b->err) == STORE_OK, "claim: %s",
            b->err);
    id_of(a, 3);
    CHECK(!strcmp(w.id, a) && w.state == JOB_RUNNING && !strcmp(w.owner, "A") && w.attempts == 1 &&
              w.started == 1000 && w.lease_until == 1010 && w.request_len == 9 &&
              !memcmp(w.request, "{\"k\":203}", 9),
          "claimed %s state %d owner %s attempts %d lease %g", w.id, (int)w.state, w.owner,
          w.attempts, w.lease_until);
    store_job_clear(&w);
    /* renewals: the owner's, with progress; another's is refused */
    int cancel = 9;
    CHECK(s->ops->job_renew(s, a, "A", 1005, 10, "split", 0.5, &cancel, b->err, sizeof b->err) ==
                  STORE_OK &&
              cancel == 0,
          "renew: %s", b->err);
    w = get(b, a);
    CHECK(w.lease_until == 1015 && !strcmp(w.stage, "split") && w.fraction == 0.5,
          "renewed: lease %g stage %s fraction %g", w.lease_until, w.stage, w.fraction);
    store_job_clear(&w);
    CHECK(s->ops->job_renew(s, a, "B", 1005, 10, "x", 0, &cancel, b->err, sizeof b->err) ==
              STORE_NOTFOUND,
          "B renewed A's job");
    CHECK(s->ops->job_finish(s, a, "B", JOB_DONE, 1006, 0, NULL, b->err, sizeof b->err) ==
              STORE_NOTFOUND,
          "B finished A's job");
    /* a second claim takes the next one; none is taken twice */
    REQUIRE(s->ops->job_claim(s, "B", 1001, 10, &w, b->err, sizeof b->err) == STORE_OK, "claim");
    id_of(c, 2);
    CHECK(!strcmp(w.id, c), "B claimed %s, want %s", w.id, c);
    store_job_clear(&w);
    /* A ends its job: done, the request dropped; ending it again is refused */
    CHECK(s->ops->job_finish(s, a, "A", JOB_DONE, 1007, 0, NULL, b->err, sizeof b->err) == STORE_OK,
          "finish: %s", b->err);
    w = get(b, a);
    CHECK(w.state == JOB_DONE && w.finished == 1007 && w.request_len == 0 && w.lease_until == 0,
          "done: state %d finished %g request %zu", (int)w.state, w.finished, w.request_len);
    store_job_clear(&w);
    CHECK(s->ops->job_finish(s, a, "A", JOB_FAILED, 1008, 500, "x", b->err, sizeof b->err) ==
              STORE_NOTFOUND,
          "a done job was ended again");
    /* B gives its job back (a drain): queued again, claimed again with a second attempt */
    CHECK(s->ops->job_release(s, c, "B", b->err, sizeof b->err) == STORE_OK, "release: %s", b->err);
    w = get(b, c);
    CHECK(w.state == JOB_QUEUED && w.request_len == 9, "released: state %d", (int)w.state);
    store_job_clear(&w);
    REQUIRE(s->ops->job_claim(s, "A", 1010, 10, &w, b->err, sizeof b->err) == STORE_OK, "claim");
    CHECK(!strcmp(w.id, c) && w.attempts == 2 && !strcmp(w.owner, "A"),
          "reclaimed %s attempts %d owner %s", w.id, w.attempts, w.owner);
    store_job_clear(&w);
    /* a failed end keeps its status and message */
    CHECK(s->ops->job_finish(s, c, "A", JOB_FAILED, 1011, 422, "edge 4", b->err, sizeof b->err) ==
              STORE_OK,
          "fail: %s", b->err);
    w = get(b, c);
    CHECK(w.state == JOB_FAILED && w.error_status == 422 && w.error && !strcmp(w.error, "edge 4"),
          "failed: %d %s", w.error_status, w.error ? w.error : "NULL");
    store_job_clear(&w);
    CHECK(s->ops->job_finish(s, c, "A", JOB_QUEUED, 1, 0, NULL, b->err, sizeof b->err) == STORE_ERR,
          "queued is no end state");
    /* the last one, then none */
    REQUIRE(s->ops->job_claim(s, "A", 1012, 10, &w, b->err, sizeof b->err) == STORE_OK, "claim");
    store_job_clear(&w);
    CHECK(s->ops->job_claim(s, "A", 1013, 10, &w, b->err, sizeof b->err) == STORE_NOTFOUND,
          "a claim of an empty queue");
}

CONTRACT(queue_leases_run_out)
{
    store *s = b->s;
    char job[33], id[33];
    int joined, cancel;
    size_t n = 9;
    store_job w;
    REQUIRE(submit(b, 1, 300, 1, 0, 0, job, &joined) == STORE_OK, "submit: %s", b->err);
    id_of(id, 1);
    for (int attempt = 1; attempt <= STORE_MAX_ATTEMPTS; attempt++) {
        REQUIRE(s->ops->job_claim(s, "A", 100 * attempt, 5, &w, b->err, sizeof b->err) == STORE_OK,
                "claim %d: %s", attempt, b->err);
        CHECK(w.attempts == attempt, "attempt %d: %d", attempt, w.attempts);
        store_job_clear(&w);
        /* a live lease stays */
        CHECK(s->ops->jobs_requeue(s, 100 * attempt + 4, 0, &n, b->err, sizeof b->err) ==
                      STORE_OK &&
                  n == 0,
              "a live lease was requeued (%zu)", n);
        /* then it runs out: queued again, or failed after the last attempt */
        CHECK(s->ops->jobs_requeue(s, 100 * attempt + 6, 0, &n, b->err, sizeof b->err) ==
                      STORE_OK &&
                  n == 1,
              "attempt %d: requeued %zu", attempt, n);
        w = get(b, id);
        job_state want = attempt < STORE_MAX_ATTEMPTS ? JOB_QUEUED : JOB_FAILED;
        CHECK(w.state == want, "after attempt %d: state %d, want %d", attempt, (int)w.state,
              (int)want);
        if (want == JOB_FAILED)
            CHECK(w.error_status == 500 && w.error && strstr(w.error, "started 3 times"),
                  "the failed job's error: %d %s", w.error_status, w.error ? w.error : "NULL");
        store_job_clear(&w);
        /* the owner whose lease ran out cannot write the job any more */
        CHECK(s->ops->job_renew(s, id, "A", 100 * attempt + 7, 5, "x", 0, &cancel, b->err,
                                sizeof b->err) == STORE_NOTFOUND,
              "a lost lease was renewed");
    }
    /* all: every running job, whatever its lease (a store only this daemon uses, at start) */
    REQUIRE(submit(b, 2, 301, 2, 0, 0, job, &joined) == STORE_OK, "submit: %s", b->err);
    REQUIRE(s->ops->job_claim(s, "A", 1000, 3600, &w, b->err, sizeof b->err) == STORE_OK, "claim");
    store_job_clear(&w);
    CHECK(s->ops->jobs_requeue(s, 1001, 1, &n, b->err, sizeof b->err) == STORE_OK && n == 1,
          "requeue all: %zu", n);
    id_of(id, 2);
    w = get(b, id);
    CHECK(w.state == JOB_QUEUED, "after requeue all: %d", (int)w.state);
    store_job_clear(&w);
}

CONTRACT(queue_cancel_per_submission)
{
    store *s = b->s;
    char job[33], j1[33], s2[33], s3[33];
    int joined, changed, what, cancel;
    store_job w;
    REQUIRE(submit(b, 1, 400, 1, 0, 0, job, &joined) == STORE_OK, "submit: %s", b->err);
    REQUIRE(submit(b, 2, 400, 2, 0, 0, job, &joined) == STORE_OK && joined, "join: %s", b->err);
    id_of(j1, 1);
    id_of(s2, 2);
    /* one of two: the job stays */
    CHECK(s->ops->sub_cancel(s, j1, 5, &changed, &what, b->err, sizeof b->err) == STORE_OK &&
              changed && what == STORE_JOB_KEPT,
          "cancel 1: %s changed %d what %d", b->err, changed, what);
    CHECK(s->ops->sub_cancel(s, j1, 6, &changed, &what, b->err, sizeof b->err) == STORE_OK &&
              !changed && what == STORE_JOB_KEPT,
          "cancel 1 again: changed %d what %d", changed, what);
    store_sub sub;
    CHECK(s->ops->sub_get(s, j1, &sub, b->err, sizeof b->err) == STORE_OK && sub.canceled == 5,
          "the canceled submission keeps its first time: %g", sub.canceled);
    w = get(b, j1);
    CHECK(w.state == JOB_QUEUED && w.active_subs == 1, "state %d active %d", (int)w.state,
          w.active_subs);
    store_job_clear(&w);
    /* the last: a queued job is canceled at once */
    CHECK(s->ops->sub_cancel(s, s2, 7, &changed, &what, b->err, sizeof b->err) == STORE_OK &&
              changed && what == STORE_JOB_CANCELED,
          "cancel 2: changed %d what %d", changed, what);
    w = get(b, j1);
    CHECK(w.state == JOB_CANCELED && w.finished == 7 && w.request_len == 0,
          "canceled: state %d finished %g", (int)w.state, w.finished);
    store_job_clear(&w);
    /* the same request again makes a new job: the canceled one is no longer in flight */
    REQUIRE(submit(b, 3, 400, 8, 0, 0, job, &joined) == STORE_OK && !joined, "after: %s", b->err);
    id_of(s3, 3);
    CHECK(!strcmp(job, s3), "a new job %s", job);
    /* a running job asked to stop: its owner hears it at its next renewal */
    REQUIRE(s->ops->job_claim(s, "A", 10, 30, &w, b->err, sizeof b->err) == STORE_OK, "claim");
    store_job_clear(&w);
    CHECK(s->ops->sub_cancel(s, s3, 11, &changed, &what, b->err, sizeof b->err) == STORE_OK &&
              changed && what == STORE_JOB_STOPPING,
          "cancel running: changed %d what %d", changed, what);
    CHECK(s->ops->job_renew(s, s3, "A", 12, 30, "x", 0.1, &cancel, b->err, sizeof b->err) ==
                  STORE_OK &&
              cancel == 1,
          "renew after the cancel: cancel %d", cancel);
    /* while it stops, another client's same request makes a job of its own: it must not join
     * one that will end canceled (that client canceled nothing) */
    char s4[33], s5[33];
    REQUIRE(submit(b, 4, 400, 13, 0, 0, job, &joined) == STORE_OK, "while stopping: %s", b->err);
    id_of(s4, 4);
    CHECK(!joined && !strcmp(job, s4), "joined %d job %s: the request joined the stopping job",
          joined, job);
    w = get(b, s4);
    CHECK(w.state == JOB_QUEUED && w.active_subs == 1 && !w.cancel,
          "the new job: state %d active %d cancel %d", (int)w.state, w.active_subs, w.cancel);
    store_job_clear(&w);
    /* ... which later submissions join, as any job in flight */
    REQUIRE(submit(b, 5, 400, 14, 0, 0, job, &joined) == STORE_OK && joined && !strcmp(job, s4),
            "join the new job: joined %d job %s %s", joined, job, b->err);
    id_of(s5, 5);
    /* a stopped job given back is canceled, not queued */
    CHECK(s->ops->job_release(s, s3, "A", b->err, sizeof b->err) == STORE_OK, "release");
    w = get(b, s3);
    CHECK(w.state == JOB_CANCELED, "released with the cancel flag: %d", (int)w.state);
    store_job_clear(&w);
    w = get(b, s4);
    CHECK(w.state == JOB_QUEUED && w.active_subs == 2, "the new job after the release: %d %d",
          (int)w.state, w.active_subs);
    store_job_clear(&w);
    (void)s5;
    CHECK(s->ops->sub_cancel(s, "ffffffffffffffffffffffffffffffff", 1, &changed, &what, b->err,
                             sizeof b->err) == STORE_NOTFOUND,
          "cancel of no submission");
}

CONTRACT(queue_prune)
{
    store *s = b->s;
    static const struct {
        unsigned k;
        job_state st;
        double fin;
    } rows[] = {{1, JOB_DONE, 100}, {2, JOB_FAILED, 140}, {3, JOB_CANCELED, 149.5},
                {4, JOB_DONE, 150}, {5, JOB_DONE, 200},   {6, JOB_RUNNING, 0},
                {7, JOB_QUEUED, 0}};
    for (size_t i = 0; i < sizeof rows / sizeof *rows; i++) {
        store_job j = job_make(rows[i].k, rows[i].k, rows[i].st, 50, "{}", 2);
        j.finished = rows[i].fin;
        REQUIRE(s->ops->job_insert(s, &j, b->err, sizeof b->err) == STORE_OK, "insert: %s", b->err);
    }
    size_t n = 99;
    REQUIRE(s->ops->jobs_prune(s, 150, 0, &n, b->err, sizeof b->err) == STORE_OK, "prune: %s",
            b->err);
    CHECK(n == 3, "pruned %zu, want 3", n);
    for (size_t i = 0; i < sizeof rows / sizeof *rows; i++) {
        char id[33];
        id_of(id, rows[i].k);
        store_job w = get(b, id);
        store_sub sub;
        int sr = s->ops->sub_get(s, id, &sub, b->err, sizeof b->err);
        if (rows[i].k <= 3)
            CHECK((int)w.state == -1 && sr == STORE_NOTFOUND, "job %u and its submission kept",
                  rows[i].k);
        else
            CHECK(w.state == rows[i].st && sr == STORE_OK, "job %u: state %d", rows[i].k,
                  (int)w.state);
        store_job_clear(&w);
    }
    /* by count: the newest finished one stays (5), 4 goes; unfinished ones stay */
    REQUIRE(s->ops->jobs_prune(s, 0, 1, &n, b->err, sizeof b->err) == STORE_OK, "prune");
    CHECK(n == 1, "prune to 1 removed %zu", n);
    char id5[33];
    id_of(id5, 5);
    store_job w = get(b, id5);
    CHECK(w.state == JOB_DONE, "the newest finished job was pruned");
    store_job_clear(&w);
    REQUIRE(s->ops->jobs_prune(s, 1e12, 0, &n, b->err, sizeof b->err) == STORE_OK, "prune");
    CHECK(n == 1, "pruning all finished removed %zu, want 1", n);
    size_t q, r;
    CHECK(s->ops->job_counts(s, &q, &r, b->err, sizeof b->err) == STORE_OK && q == 1 && r == 1,
          "left queued %zu running %zu", q, r);
}

/* ---- many threads at once ---- */

typedef struct crowd {
    be *b;
    int k;
    atomic_int joined, made, claimed, errors;
    pthread_barrier_t bar;
} crowd;

static void *crowd_submit(void *arg)
{
    crowd *c = arg;
    static atomic_int next = 1000;
    int me = atomic_fetch_add(&next, 1);
    char job[33], err[256];
    int joined = 0;
    char req[] = "{}";
    store_job j = job_make((unsigned)me, 500, JOB_QUEUED, 1, req, 2);
    pthread_barrier_wait(&c->bar);
    for (int t = 0; t < 3; t++) { /* SQLite: a lock held past its busy timeout is an error */
        int rc = c->b->s->ops->job_submit(c->b->s, &j, 0, 0, job, &joined, err, sizeof err);
        if (rc == STORE_OK) {
            atomic_fetch_add(joined ? &c->joined : &c->made, 1);
            return NULL;
        }
    }
    atomic_fetch_add(&c->errors, 1);
    return NULL;
}

static void *crowd_claim(void *arg)
{
    crowd *c = arg;
    char err[256], owner[16];
    static atomic_int next = 0;
    snprintf(owner, sizeof owner, "T%d", atomic_fetch_add(&next, 1));
    pthread_barrier_wait(&c->bar);
    for (;;) {
        store_job w;
        int rc = c->b->s->ops->job_claim(c->b->s, owner, 10, 60, &w, err, sizeof err);
        if (rc == STORE_NOTFOUND) return NULL;
        if (rc != STORE_OK) {
            atomic_fetch_add(&c->errors, 1);
            continue;
        }
        atomic_fetch_add(&c->claimed, 1);
        if (c->b->s->ops->job_finish(c->b->s, w.id, owner, JOB_DONE, 11, 0, NULL, err,
                                     sizeof err) != STORE_OK)
            atomic_fetch_add(&c->errors, 1);
        store_job_clear(&w);
    }
}

CONTRACT(queue_eight_threads)
{
    enum { T = 8, JOBS = 40 };
    crowd c = {.b = b};
    pthread_t t[T];
    /* 8 threads submit the same request at once: one job, 8 submissions */
    pthread_barrier_init(&c.bar, NULL, T);
    for (int i = 0; i < T; i++) pthread_create(&t[i], NULL, crowd_submit, &c);
    for (int i = 0; i < T; i++) pthread_join(t[i], NULL);
    pthread_barrier_destroy(&c.bar);
    CHECK(c.made == 1 && c.joined == T - 1 && c.errors == 0, "made %d joined %d errors %d",
          (int)c.made, (int)c.joined, (int)c.errors);
    size_t q, r;
    CHECK(b->s->ops->job_counts(b->s, &q, &r, b->err, sizeof b->err) == STORE_OK && q == 1,
          "queued %zu", q);
    /* 40 more jobs, claimed and ended by 8 threads: each exactly once */
    char job[33];
    int joined;
    for (unsigned k = 0; k < JOBS - 1; k++)
        REQUIRE(submit(b, 2000 + k, 600 + k, 1 + k, 0, 0, job, &joined) == STORE_OK, "submit %u",
                k);
    c.errors = 0;
    pthread_barrier_init(&c.bar, NULL, T);
    for (int i = 0; i < T; i++) pthread_create(&t[i], NULL, crowd_claim, &c);
    for (int i = 0; i < T; i++) pthread_join(t[i], NULL);
    pthread_barrier_destroy(&c.bar);
    CHECK(c.claimed == JOBS && c.errors == 0, "claimed %d of %d, errors %d", (int)c.claimed, JOBS,
          (int)c.errors);
    CHECK(b->s->ops->job_counts(b->s, &q, &r, b->err, sizeof b->err) == STORE_OK && q == 0 &&
              r == 0,
          "left queued %zu running %zu", q, r);
}

/* ---- results ---- */

static char *body_make(unsigned k, size_t n)
{
    char *p = malloc(n ? n : 1);
    for (size_t i = 0; p && i < n; i++) p[i] = (char)((i * 31 + k * 7) % 251);
    return p;
}

static int body_is(const char *p, size_t len, unsigned k, size_t n)
{
    if (!p || len != n || p[len] != 0) return 0;
    for (size_t i = 0; i < n; i++)
        if (p[i] != (char)((i * 31 + k * 7) % 251)) return 0;
    return 1;
}

CONTRACT(queue_results)
{
    store *s = b->s;
    char h[65], *p = NULL;
    size_t len = 0, count = 0;
    uint64_t bytes = 0, size = 0, start = 0;
    /* small, in memory; large, from a file in chunks */
    hash_of(h, 1);
    char *small = body_make(1, 1000);
    REQUIRE(s->ops->result_put(s, h, small, 1000, b->err, sizeof b->err) == STORE_OK, "put: %s",
            b->err);
    CHECK(s->ops->result_get(s, h, &p, &len, b->err, sizeof b->err) == STORE_OK &&
              body_is(p, len, 1, 1000),
          "get: %s", b->err);
    free(p);
    free(small);
    size_t big = 3 * STORE_CHUNK + 12345;
    char *large = body_make(2, big);
    FILE *f = tmpfile();
    REQUIRE(f && fwrite(large, 1, big, f) == big && fseek(f, 0, SEEK_SET) == 0, "tmpfile");
    hash_of(h, 2);
    CHECK(s->ops->result_put_file(s, h, NULL, f, big, b->err, sizeof b->err) == STORE_OK,
          "put_file: %s", b->err);
    fclose(f);
    CHECK(s->ops->result_size(s, h, &size, NULL, b->err, sizeof b->err) == STORE_OK && size == big,
          "size %llu", (unsigned long long)size);
    int whole = 1;
    for (uint64_t pos = 0; pos < big && whole; pos += len) {
        p = NULL;
        whole =
            s->ops->result_chunk(s, h, pos, &p, &len, &start, b->err, sizeof b->err) == STORE_OK &&
            start == pos && len && !memcmp(p, large + pos, len) && p[len] == 0;
        free(p);
    }
    CHECK(whole, "reading the large result by chunks: %s", b->err);
    CHECK(s->ops->result_chunk(s, h, big, &p, &len, &start, b->err, sizeof b->err) ==
              STORE_NOTFOUND,
          "a chunk past the end");
    CHECK(s->ops->result_get(s, h, &p, &len, b->err, sizeof b->err) == STORE_OK && len == big &&
              !memcmp(p, large, big),
          "the large result whole: %s", b->err);
    free(p);
    free(large);
    /* a file shorter than said: nothing stored */
    hash_of(h, 3);
    f = tmpfile();
    REQUIRE(f && fwrite("abc", 1, 3, f) == 3 && fseek(f, 0, SEEK_SET) == 0, "tmpfile");
    CHECK(s->ops->result_put_file(s, h, NULL, f, 10, b->err, sizeof b->err) == STORE_ERR,
          "a short file was stored");
    fclose(f);
    CHECK(s->ops->result_exists(s, h, b->err, sizeof b->err) == STORE_NOTFOUND,
          "a failed put left a result");
    CHECK(s->ops->result_stats(s, &count, &bytes, b->err, sizeof b->err) == STORE_OK &&
              count == 2 && bytes == 1000 + big,
          "stats %zu %llu", count, (unsigned long long)bytes);
    CHECK(s->ops->check(s, b->err, sizeof b->err) == STORE_OK, "check: %s", b->err);
    hash_of(h, 9);
    CHECK(s->ops->result_get(s, h, &p, &len, b->err, sizeof b->err) == STORE_NOTFOUND && !p,
          "a result that is not there");
}

CONTRACT(queue_results_lru_budget)
{
    be_close(b);
    REQUIRE(be_open(b, 10000) == 0, "open with a budget: %s", b->err);
    store *s = b->s;
    char h[65], *p;
    size_t len, count;
    uint64_t bytes;
    /* five of 3000 bytes in a budget of 10000: the oldest go; a read makes one recent */
    for (unsigned k = 1; k <= 3; k++) {
        char *d = body_make(k, 3000);
        hash_of(h, k);
        REQUIRE(s->ops->result_put(s, h, d, 3000, b->err, sizeof b->err) == STORE_OK, "put %u", k);
        free(d);
        usleep(2000);
    }
    hash_of(h, 1); /* 1 used: 2 is now the least recently used */
    REQUIRE(s->ops->result_get(s, h, &p, &len, b->err, sizeof b->err) == STORE_OK, "get 1");
    free(p);
    usleep(2000);
    for (unsigned k = 4; k <= 5; k++) {
        char *d = body_make(k, 3000);
        hash_of(h, k);
        REQUIRE(s->ops->result_put(s, h, d, 3000, b->err, sizeof b->err) == STORE_OK, "put %u", k);
        free(d);
        usleep(2000);
    }
    static const int want[] = {0, 1, 0, 0, 1, 1}; /* kept: 1, 4, 5 */
    for (unsigned k = 1; k <= 5; k++) {
        hash_of(h, k);
        int there = s->ops->result_exists(s, h, b->err, sizeof b->err) == STORE_OK;
        CHECK(there == want[k], "result %u: there %d, want %d", k, there, want[k]);
    }
    CHECK(s->ops->result_stats(s, &count, &bytes, b->err, sizeof b->err) == STORE_OK &&
              count == 3 && bytes == 9000,
          "stats %zu %llu", count, (unsigned long long)bytes);
    /* one larger than the budget is stored alone */
    char *d = body_make(6, 12000);
    hash_of(h, 6);
    REQUIRE(s->ops->result_put(s, h, d, 12000, b->err, sizeof b->err) == STORE_OK, "put 6");
    free(d);
    CHECK(s->ops->result_stats(s, &count, &bytes, b->err, sizeof b->err) == STORE_OK &&
              count == 1 && bytes == 12000,
          "after a result above the budget: %zu %llu", count, (unsigned long long)bytes);
    CHECK(s->ops->check(s, b->err, sizeof b->err) == STORE_OK, "check: %s", b->err);
}

CONTRACT(queue_persists_across_reopen)
{
    char job[33], h[65], id[33], *p = NULL;
    int joined;
    size_t len;
    REQUIRE(submit(b, 1, 700, 5, 0, 0, job, &joined) == STORE_OK, "submit: %s", b->err);
    hash_of(h, 701);
    REQUIRE(b->s->ops->result_put(b->s, h, "{\"x\":1}", 7, b->err, sizeof b->err) == STORE_OK,
            "put");
    be_close(b);
    REQUIRE(be_open(b, 0) == 0, "reopen: %s", b->err);
    id_of(id, 1);
    store_job w = get(b, id);
    CHECK(w.state == JOB_QUEUED && w.created == 5 && w.request_len == 9, "the job after reopen");
    store_job_clear(&w);
    CHECK(b->s->ops->result_get(b->s, h, &p, &len, b->err, sizeof b->err) == STORE_OK && len == 7 &&
              !memcmp(p, "{\"x\":1}", 7),
          "the result after reopen: %s", b->err);
    free(p);
}

/* ---- PostgreSQL's events ---- */

/* The next event within secs that is not a reset: its kind, id in id. */
static store_ev next_event(store *s, double secs, char *id)
{
    char err[256];
    for (int i = 0; i < (int)(secs / 0.1) + 1; i++) {
        store_ev ev = STORE_EV_NONE;
        if (s->ops->wait_event(s, 0.1, &ev, id, err, sizeof err) != STORE_OK) continue;
        if (ev != STORE_EV_NONE && ev != STORE_EV_RESET) return ev;
    }
    return STORE_EV_NONE;
}

TEST(queue_events_pg)
{
    be b, other;
    int rc = be_init(&b, 1);
    if (rc) {
        if (rc < 0) CHECK(0, "no store: %s", b.err);
        be_done(&b);
        return;
    }
    /* a second store on the same database: the other daemon */
    other = b;
    other.s = NULL;
    REQUIRE(be_open(&other, 0) == 0, "second store: %s", other.err);
    char id[33], job[33], want[33];
    store_ev ev = STORE_EV_NONE;
    /* the first wait makes the listening connection: a reset, since nothing was heard before */
    REQUIRE(other.s->ops->wait_event(other.s, 0.1, &ev, id, other.err, sizeof other.err) ==
                    STORE_OK &&
                ev == STORE_EV_RESET,
            "the first wait: %d %s", (int)ev, other.err);
    int joined, cancel, changed, what;
    REQUIRE(submit(&b, 1, 800, 1, 0, 0, job, &joined) == STORE_OK, "submit: %s", b.err);
    CHECK(next_event(other.s, 3, id) == STORE_EV_QUEUED, "no 'queued' event after a submit");
    store_job w;
    REQUIRE(b.s->ops->job_claim(b.s, "A", 1, 30, &w, b.err, sizeof b.err) == STORE_OK, "claim");
    store_job_clear(&w);
    id_of(want, 1);
    REQUIRE(b.s->ops->sub_cancel(b.s, want, 2, &changed, &what, b.err, sizeof b.err) == STORE_OK,
            "cancel");
    CHECK(next_event(other.s, 3, id) == STORE_EV_CANCEL && !strcmp(id, want),
          "no 'cancel' event for %s (got %s)", want, id);
    CHECK(b.s->ops->job_renew(b.s, want, "A", 3, 30, "x", 0, &cancel, b.err, sizeof b.err) ==
                  STORE_OK &&
              cancel,
          "the cancel flag");
    REQUIRE(b.s->ops->job_finish(b.s, want, "A", JOB_CANCELED, 4, 0, NULL, b.err, sizeof b.err) ==
                STORE_OK,
            "finish");
    CHECK(next_event(other.s, 3, id) == STORE_EV_ENDED && !strcmp(id, want),
          "no 'ended' event for %s", want);
    be_close(&other);
    be_done(&b);
}
