/* daemon.h — driving a live cellard from a test: start it as a child process on a free port
 * of 127.0.0.1 (a SQLite file in a temporary directory, or a database given), talk to it
 * through libcurl and raw sockets, read its metrics and log, stop it with SIGTERM or SIGKILL;
 * and the request bodies and expected results (from the command-line tool) the tests post.
 * Shared by test_server.c (one daemon on SQLite) and test_cluster.c (several on PostgreSQL).
 * Every wait is a bounded poll whose bound is a multiple of slowdown() (tests/check.h): the
 * measured pace of this machine now, at least 3x under the sanitizers. */
#ifndef CELLAR_TESTS_DAEMON_H
#define CELLAR_TESTS_DAEMON_H

#include <curl/curl.h>
#include <jansson.h>
#include <pthread.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "tests/check.h"

typedef struct buf {
    char *p;
    size_t n, cap;
} buf;

#define MAXV 128
typedef struct srv {
    char dir[256], db[300], log[300], base[64];
    char flags[256];
    int port;
    pid_t pid; /* 0: not running */
    int nv;    /* documents to validate: schema name and file */
    const char *vschema[MAXV];
    char vfile[MAXV][320];
} srv;

typedef struct hreq {
    const char *method; /* default: GET, or POST with a body */
    const char *path;
    const char *body;
    size_t len;
    int has_body;
    int chunked;       /* send the body with Transfer-Encoding: chunked */
    const char *h[8];  /* extra header lines */
    double timeout;    /* seconds; default 60 (x3 under the sanitizers) */
    int no_expect_off; /* leave libcurl's Expect: 100-continue alone */
    int decode;        /* ask for gzip and let libcurl decode it (Content-Encoding stays) */
} hreq;

typedef struct hresp {
    long status;
    CURLcode cc;
    char err[CURL_ERROR_SIZE];
    buf body, hdr;
    double secs;
} hresp;

typedef struct jobv {
    char id[40], state[16], hash[72], result[128], daemon[64];
    int attempts;
} jobv;

typedef struct poster {
    srv *d;
    const char *body;
    size_t len;
    const char *prefer;
    pthread_barrier_t *bar;
    hresp r;
} poster;

/* Slow requests (see slow_body): sized once per process. */
struct slow_jobs {
    int ready, failed;
    size_t n;
    double secs; /* variant 0 with one core thread */
    char *base;  /* gen output without the final "}" and newline */
    size_t base_len;
    char *huge;
    size_t huge_len;
    char *variant[16];
    size_t variant_len[16];
};
extern struct slow_jobs slow;

#define NO_STATS    "{\"fields\":[\"V\",\"EV\",\"FV\",\"FE\",\"holes\",\"exterior\"]}"
#define srv_term(d) srv_term_(d, __func__, __LINE__)
#define SERVER_TEST(name, flags)                                                                   \
    static void name##_run(srv *d);                                                                \
    TEST(name)                                                                                     \
    {                                                                                              \
        srv d_;                                                                                    \
        if (srv_open(&d_, flags) == 0) name##_run(&d_);                                            \
        srv_finish(&d_);                                                                           \
    }                                                                                              \
    static void name##_run(srv *d)
#define submit(d, body, len, j) submit_(d, body, len, j, __func__, __LINE__)
#define ACCEPTED                "cellar_jobs_total{state=\"accepted\"}"
#define DONE                    "cellar_jobs_total{state=\"done\"}"
#define CANCELED                "cellar_jobs_total{state=\"canceled\"}"
#define HITS                    "cellar_cache_hits_total"
#define COALESCE                "cellar_jobs_coalesced_total"
#define check_problem(d, r, status, path, what)                                                    \
    check_problem_(d, r, status, path, what, __func__, __LINE__)
#define check_sane(d, after, k) check_sane_(d, after, k, __func__, __LINE__)

double now_s(void);
void sleep_s(double s);
/* The seconds of the reference work slowdown() is measured with (see daemon.c). */
double pace_s(void);
const char *build_dir(void);
const char *cli_bin(void);
int buf_add(buf *b, const void *data, size_t n);
void buf_printf(buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
int write_file(const char *path, const char *data, size_t len);
void rm_rf(const char *dir);
const char *scratch_dir(void);
char *run_capture(const char *cmd, size_t *len);
const char *expect_threads(const char *body, size_t blen, size_t *len, int threads, double *secs);
const char *expect(const char *body, size_t blen, size_t *len);
char *small_body(int k, int stats, size_t *len);
/* k < 36: 300 + 400 (k % 10) segments, 8000 for k = 20 and k >= 24 (no stats). */
const char *medium(int k, size_t *len);
const char *slow_body(int k, size_t *len);
const char *huge_body(size_t *len);
/* The huge request with a precision of its own (k e-9 above 1e-7): a distinct job of the same
 * cost for each k; malloc'd, the caller frees. */
char *huge_variant(int k, size_t *len);
/* n random segments as long as the unit square (`gen lines n 1.0 40+k`): the buckets cannot
 * split them apart, so each holds thousands of segments and of crossings (the split stage runs
 * in a few buckets: issue 25's case; 2500 segments: 0.6 s, 3500: 1.7 s on one thread);
 * malloc'd, the caller frees. */
char *long_lines_body(int k, int n, size_t *len);
int same_result(const char *a, size_t alen, const char *b, size_t blen);
int free_port(void);
void log_tail(const srv *d, int lines);
int log_contains(const srv *d, const char *what);
void hresp_free(hresp *r);
void http_do(const srv *d, const hreq *q, hresp *r);
void http_get(const srv *d, const char *path, hresp *r);
void http_method(const srv *d, const char *method, const char *path, hresp *r);
void http_post(const srv *d, const char *body, size_t len, const char *prefer, hresp *r);
int hget(const hresp *r, const char *name, char *out, size_t n);
int has_header(const hresp *r, const char *name, const char *value);
json_t *jbody(const hresp *r);
const char *jstr(const json_t *o, const char *key);
int is_hex(const char *s, size_t n);
int srv_start(srv *d);
int srv_open(srv *d, const char *flags);
/* The same with the daemon's --db given (NULL: a SQLite file in its directory). */
int srv_open_db(srv *d, const char *db, const char *flags);
int srv_alive(srv *d);
int srv_wait_exit(srv *d, double timeout, int *status);
int srv_term_(srv *d, const char *func, int line);
void srv_kill(srv *d);
void vq_add(srv *d, const char *schema, const hresp *r);
const char *validator(void);
void vq_check(srv *d);
void srv_finish(srv *d);
int job_parse(const hresp *r, jobv *j);
int submit_(srv *d, const char *body, size_t len, jobv *j, const char *func, int line);
int wait_state(srv *d, const char *id, const char *want, double timeout, jobv *j);
long long db_ll(const char *path, const char *sql);
/* The daemon's CPU time so far (user + system, /proc/PID/stat), seconds; -1 when unreadable. */
double srv_cpu_s(const srv *d);
/* Watches the daemon's CPU use in samples of 50 ms until it has not been busy for `quiet` seconds
 * (or `timeout` passed) and returns the seconds from t0 to the end of its last busy sample
 * (one in which it used at least 40 % of a core: a worker computing), or to the first sample
 * when none was busy (a bound: it was idle by then); -1 when it never went quiet or its CPU
 * time cannot be read. */
double srv_idle_after(const srv *d, double t0, double quiet, double timeout);
/* The same for n daemons (at most 16) watched together: idle[i] for each; 0, or -1 as above. */
int srvs_idle_after(const srv *const *d, int n, double t0, double quiet, double timeout,
                    double *idle);
char *metrics_text(srv *d);
double mval(const char *text, const char *series);
double metric(srv *d, const char *series);
double metric_until(srv *d, const char *series, double want);
void check_no_500(srv *d);
void check_problem_(srv *d, const hresp *r, long status, const char *path, const char *what,
                    const char *func, int line);
void check_sane_(srv *d, const char *after, int k, const char *func, int line);
int raw_connect(const srv *d);
size_t raw_send(int fd, const void *data, size_t len);
size_t raw_read(int fd, char *out, size_t max, double timeout);
int raw_exchange(const srv *d, const void *data, size_t len, char *out, size_t max);
int raw_exchange_ex(const srv *d, const void *data, size_t len, char *out, size_t max,
                    int half_close);
void *post_thread(void *arg);

#endif
