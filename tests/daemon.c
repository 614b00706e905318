/* daemon.c — see daemon.h. */
#include "tests/daemon.h"
#include "api/api.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <netinet/in.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* ---- small utilities --------------------------------------------------------------------- */

double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {
    }
}

/* The reference work the tests' time bounds are measured against: 400 random segments (about
 * 30 000 crossings) arranged in this process on one thread, the best of five runs, measured
 * once per process.  PACE_QUIET is what it takes on a quiet machine of ours (2 cores, no
 * sanitizer); a loaded machine, or the sanitizers, make it longer, and every bound with it. */
#define PACE_QUIET 0.020

double pace_s(void)
{
    static double pace = -1;
    if (pace >= 0) return pace;
    double *seg = test_random_lines(400, 1.0, 77), best = 1e9;
    buf b = {0};
    buf_printf(&b, "{\"kind\":\"lines\",\"lines\":[");
    for (size_t i = 0; seg && i < 400; i++)
        buf_printf(&b, "%s[[%.17g,%.17g],[%.17g,%.17g]]", i ? "," : "", seg[4 * i], seg[4 * i + 1],
                   seg[4 * i + 2], seg[4 * i + 3]);
    buf_printf(&b, "],\"options\":{\"fields\":[\"stats\"]}}");
    for (int r = 0; r < 5 && seg && b.p; r++) {
        char *out = NULL;
        size_t len = 0;
        double t0 = now_s();
        int rc = api_run_json(b.p, b.n, 1, &out, &len, NULL);
        double t = now_s() - t0;
        free(out);
        if (rc == 0 && t < best) best = t;
    }
    free(seg);
    free(b.p);
    pace = best < 1e9 ? best : PACE_QUIET;
    return pace;
}

/* How much longer than on a quiet machine things take here and now: the measured pace over
 * the quiet one, and at least 3 under the sanitizers (whose cost on I/O and threads the pace
 * does not see); never below 1.  Every time bound of the suite is a multiple of it. */
double slowdown(void)
{
    static double f = 0;
    if (f > 0) return f;
    const char *s = getenv("CELLAR_SANITIZED");
    double floor = s && *s && strcmp(s, "0") ? 3.0 : 1.0, p = pace_s() / PACE_QUIET;
    f = p > floor ? p : floor;
    if (f > 1.2 * floor) {
        printf("  (this machine runs the reference work in %.3f s, %.1f times a quiet one's: the "
               "time bounds grow alike)\n",
               pace_s(), p);
        fflush(stdout);
    }
    return f;
}

const char *build_dir(void)
{
    const char *b = getenv("CELLAR_BUILD");
    return b && *b ? b : "build";
}

const char *cli_bin(void)
{
    static char path[512];
    const char *b = getenv("CELLAR_BIN");
    if (b && *b) return b;
    snprintf(path, sizeof path, "%s/cellar", build_dir());
    return path;
}

int buf_add(buf *b, const void *data, size_t n)
{
    if (b->n + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->n + n + 1) cap *= 2;
        char *p = realloc(b->p, cap);
        if (!p) return -1;
        b->p = p;
        b->cap = cap;
    }
    memcpy(b->p + b->n, data, n);
    b->n += n;
    b->p[b->n] = 0;
    return 0;
}

void buf_printf(buf *b, const char *fmt, ...)
{
    char tmp[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n > 0) buf_add(b, tmp, (size_t)n < sizeof tmp ? (size_t)n : sizeof tmp - 1);
}

int write_file(const char *path, const char *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    size_t w = fwrite(data, 1, len, f);
    return fclose(f) == 0 && w == len ? 0 : -1;
}

static int rm_one(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    (void)ftw;
    remove(path);
    return 0;
}

void rm_rf(const char *dir)
{
    if (dir[0]) nftw(dir, rm_one, 16, FTW_DEPTH | FTW_PHYS);
}

/* The process's scratch directory (request files for the CLI), removed at exit. */
static char scratch[256];
static void scratch_cleanup(void);

const char *scratch_dir(void)
{
    if (!scratch[0]) {
        snprintf(scratch, sizeof scratch, "/tmp/cellar-test-server-XXXXXX");
        if (!mkdtemp(scratch)) {
            scratch[0] = 0;
            return "/tmp";
        }
        atexit(scratch_cleanup);
    }
    return scratch;
}

/* Runs a shell command and returns its standard output (malloc'd, NUL-terminated), or NULL
 * when it cannot start or exits non-zero. */
char *run_capture(const char *cmd, size_t *len)
{
    FILE *p = popen(cmd, "r");
    if (!p) return NULL;
    buf b = {0};
    char tmp[65536];
    size_t n;
    while ((n = fread(tmp, 1, sizeof tmp, p)) > 0)
        if (buf_add(&b, tmp, n)) break;
    int st = pclose(p);
    if (st != 0 || !b.p) {
        free(b.p);
        return NULL;
    }
    if (len) *len = b.n;
    return b.p;
}

/* ---- expected results from the CLI -------------------------------------------------------- */

static uint64_t fnv(const char *s, size_t n)
{
    uint64_t h = 1469598103934665603u;
    for (size_t i = 0; i < n; i++) h = (h ^ (unsigned char)s[i]) * 1099511628211u;
    return h;
}

static struct memo {
    uint64_t key;
    size_t body_len;
    char *out;
    size_t len;
} * memo;
static int memo_cap;
static int nmemo;
static int memo_seq;

static void memo_put(const char *body, size_t blen, char *out, size_t len)
{
    if (nmemo == memo_cap) { /* kept for the process: callers hold on to out */
        int cap = memo_cap ? 2 * memo_cap : 64;
        struct memo *m = realloc(memo, (size_t)cap * sizeof *m);
        if (!m) return; /* not remembered, still valid: computed again next time */
        memo = m;
        memo_cap = cap;
    }
    memo[nmemo++] = (struct memo){fnv(body, blen), blen, out, len};
}

/* What `cellar run` prints for body (borrowed, kept for the process), or NULL (then a failure
 * is recorded).  threads: the CLI's --threads (0: default). */
const char *expect_threads(const char *body, size_t blen, size_t *len, int threads, double *secs)
{
    uint64_t k = fnv(body, blen);
    for (int i = 0; i < nmemo; i++)
        if (memo[i].key == k && memo[i].body_len == blen) {
            *len = memo[i].len;
            return memo[i].out;
        }
    char path[320], cmd[1024];
    snprintf(path, sizeof path, "%s/req%d.json", scratch_dir(), memo_seq++);
    if (write_file(path, body, blen)) {
        test_fail(__FILE__, __func__, __LINE__, "cannot write %s", path);
        return NULL;
    }
    snprintf(cmd, sizeof cmd, "'%s' --threads %d run '%s'", cli_bin(), threads, path);
    double t0 = now_s();
    char *out = run_capture(cmd, len);
    if (secs) *secs = now_s() - t0;
    remove(path);
    if (!out) {
        test_fail(__FILE__, __func__, __LINE__, "`%s` failed", cmd);
        return NULL;
    }
    memo_put(body, blen, out, *len);
    return out;
}

const char *expect(const char *body, size_t blen, size_t *len)
{
    return expect_threads(body, blen, len, 0, NULL);
}

/* ---- request bodies ---------------------------------------------------------------------- */

/* A small hand-made request: a square of side k+1 with a diagonal and a crossing segment;
 * stats: the default fields (with the non-deterministic stats), else NO_STATS. */
char *small_body(int k, int stats, size_t *len)
{
    buf b = {0};
    int s = k + 1;
    buf_printf(&b,
               "{\"kind\":\"lines\",\"lines\":[[[0,0],[%d,0]],[[%d,0],[%d,%d]],[[%d,%d],[0,%d]],"
               "[[0,%d],[0,0]],[[0,0],[%d,%d]],[[0,%d],[%d,0]]]",
               s, s, s, s, s, s, s, s, s, s, s, s);
    buf_printf(&b, "%s}", stats ? "" : ",\"options\":" NO_STATS);
    *len = b.n;
    return b.p;
}

/* Medium requests (gen lines, 300..3900 segments, k = 20 and k >= 24: 8000, tens of ms; no
 * stats): cached for the process. */
#define MAX_MEDIUM 36
static struct {
    char *p;
    size_t n;
} medium_cache[MAX_MEDIUM];

const char *medium(int k, size_t *len)
{
    if (k < 0 || k >= MAX_MEDIUM) return NULL;
    if (!medium_cache[k].p) {
        char cmd[512];
        int n = k == 20 || k >= 24 ? 8000 : 300 + 400 * (k % 10);
        snprintf(cmd, sizeof cmd, "'%s' gen lines %d 0.1 %d --options '%s'", cli_bin(), n, 100 + k,
                 NO_STATS);
        medium_cache[k].p = run_capture(cmd, &medium_cache[k].n);
        if (!medium_cache[k].p) {
            test_fail(__FILE__, __func__, __LINE__, "`%s` failed", cmd);
            return NULL;
        }
    }
    *len = medium_cache[k].n;
    return medium_cache[k].p;
}

/* Slow requests: the lines of `gen lines N 0.4 1`, with options {"fields":["stats"]} and
 * (variant k > 0) "precision": k e-9 so that every variant is a distinct job of the same cost.
 * N is sized on the first call so that variant 0 takes 1-3 s in `cellar --threads 1 run`
 * (about 6000).  Long segments (0.4 rather than 0.02) give the same crossings with a body 20
 * times smaller: the daemon parses a body on its HTTP thread at about 5 MB/s (15 under the
 * sanitizers), which would dominate with 8 MB bodies.  The "huge" job is 2N lines of seed 2:
 * four times the crossings, 4-6 times as long. */
struct slow_jobs slow;

static void slow_cleanup(void)
{
    free(slow.base);
    free(slow.huge);
    for (int i = 0; i < 16; i++) free(slow.variant[i]);
    for (int i = 0; i < MAX_MEDIUM; i++) free(medium_cache[i].p);
    for (int i = 0; i < nmemo; i++) free(memo[i].out);
    free(memo);
    memo = NULL;
    memo_cap = 0;
    memset(&slow, 0, sizeof slow);
    nmemo = 0;
}

static void scratch_cleanup(void)
{
    rm_rf(scratch);
}

static char *slow_make(int k, size_t *len)
{
    buf b = {0};
    buf_add(&b, slow.base, slow.base_len);
    if (k == 0)
        buf_printf(&b, ",\"options\":{\"fields\":[\"stats\"]}}");
    else
        buf_printf(&b, ",\"options\":{\"fields\":[\"stats\"],\"precision\":%de-9}}", k);
    *len = b.n;
    return b.p;
}

static int slow_init(void)
{
    if (slow.ready) return 0;
    if (slow.failed) return -1;
    slow.failed = 1;
    atexit(slow_cleanup);
    size_t n = 6000;
    for (int attempt = 0; attempt < 4; attempt++) {
        char cmd[512];
        snprintf(cmd, sizeof cmd, "'%s' gen lines %zu 0.4 1", cli_bin(), n);
        free(slow.base);
        slow.base = run_capture(cmd, &slow.base_len);
        if (!slow.base) {
            test_fail(__FILE__, __func__, __LINE__, "`%s` failed", cmd);
            return -1;
        }
        while (slow.base_len &&
               (slow.base[slow.base_len - 1] == '\n' || slow.base[slow.base_len - 1] == '}'))
            if (slow.base[--slow.base_len] == '}') break;
        slow.base[slow.base_len] = 0;
        free(slow.variant[0]);
        slow.variant[0] = slow_make(0, &slow.variant_len[0]);
        size_t len;
        double secs = 0;
        if (!expect_threads(slow.variant[0], slow.variant_len[0], &len, 1, &secs)) return -1;
        slow.n = n;
        slow.secs = secs;
        if (secs < 1.0 && n < 20000)
            n = n * 6 / 5;
        else if (secs > 6.0 && n > 2000)
            n = n * 4 / 5;
        else
            break;
    }
    char cmd[512];
    snprintf(cmd, sizeof cmd, "'%s' gen lines %zu 0.4 2 --options '{\"fields\":[\"stats\"]}'",
             cli_bin(), slow.n * 2);
    slow.huge = run_capture(cmd, &slow.huge_len);
    if (!slow.huge) {
        test_fail(__FILE__, __func__, __LINE__, "`%s` failed", cmd);
        return -1;
    }
    printf("  (slow jobs: %zu segments, %.2f s with one thread; huge: %zu segments)\n", slow.n,
           slow.secs, slow.n * 2);
    fflush(stdout);
    slow.ready = 1;
    slow.failed = 0;
    return 0;
}

const char *slow_body(int k, size_t *len)
{
    *len = 0;
    if (slow_init() || k < 0 || k >= 16) return NULL;
    if (!slow.variant[k]) slow.variant[k] = slow_make(k, &slow.variant_len[k]);
    *len = slow.variant_len[k];
    return slow.variant[k];
}

const char *huge_body(size_t *len)
{
    *len = 0;
    if (slow_init()) return NULL;
    *len = slow.huge_len;
    return slow.huge;
}

char *huge_variant(int k, size_t *len)
{
    size_t hlen;
    const char *huge = huge_body(&hlen);
    *len = 0;
    if (!huge) return NULL;
    const char *end = huge + hlen;
    while (end > huge && (end[-1] == '\n' || end[-1] == '}')) end--; /* the options' "}}" */
    buf b = {0};
    buf_add(&b, huge, (size_t)(end - huge));
    buf_printf(&b, ",\"precision\":%de-9}}", 100 + k);
    *len = b.n;
    return b.p;
}

char *long_lines_body(int k, int n, size_t *len)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "'%s' gen lines %d 1.0 %d --options '{\"fields\":[\"stats\"]}'",
             cli_bin(), n, 40 + k);
    return run_capture(cmd, len);
}

/* 1: identical bytes; 2: equal as JSON once stats.ms is removed from both; 0: different. */
int same_result(const char *a, size_t alen, const char *b, size_t blen)
{
    if (a && b && alen == blen && memcmp(a, b, alen) == 0) return 1;
    if (!a || !b) return 0;
    json_t *x = json_loadb(a, alen, 0, NULL), *y = json_loadb(b, blen, 0, NULL);
    int eq = 0;
    if (x && y) {
        json_object_del(json_object_get(x, "stats"), "ms");
        json_object_del(json_object_get(y, "stats"), "ms");
        eq = json_equal(x, y) ? 2 : 0;
    }
    json_decref(x);
    json_decref(y);
    return eq;
}

/* ---- the daemon -------------------------------------------------------------------------- */

static int curl_ready;

static void global_init(void)
{
    if (curl_ready) return;
    signal(SIGPIPE, SIG_IGN);
    curl_global_init(CURL_GLOBAL_ALL);
    atexit(curl_global_cleanup);
    curl_ready = 1;
}

int free_port(void)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return -1;
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = 0};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t al = sizeof a;
    int port = -1;
    if (bind(fd, (struct sockaddr *)&a, sizeof a) == 0 &&
        getsockname(fd, (struct sockaddr *)&a, &al) == 0)
        port = ntohs(a.sin_port);
    close(fd);
    return port;
}

void log_tail(const srv *d, int lines)
{
    size_t n = 0;
    char *s = test_read_file(d->log, &n);
    if (!s) {
        printf("  (no daemon log at %s)\n", d->log);
        return;
    }
    size_t i = n;
    int seen = 0;
    while (i > 0) {
        if (s[i - 1] == '\n' && i != n && ++seen >= lines) break;
        i--;
    }
    printf("  --- tail of %s:\n", d->log);
    for (char *p = s + i; *p;) {
        char *e = strchr(p, '\n');
        size_t k = e ? (size_t)(e - p) : strlen(p);
        printf("  | %.*s\n", (int)(k > 400 ? 400 : k), p);
        p += k + (e ? 1 : 0);
    }
    fflush(stdout);
    free(s);
}

int log_contains(const srv *d, const char *what)
{
    char *s = test_read_file(d->log, NULL);
    int r = s && strstr(s, what);
    free(s);
    return r;
}

/* ---- HTTP through libcurl ---------------------------------------------------------------- */

void hresp_free(hresp *r)
{
    free(r->body.p);
    free(r->hdr.p);
    memset(r, 0, sizeof *r);
}

static size_t on_body(char *p, size_t size, size_t n, void *ud)
{
    return buf_add(ud, p, size * n) ? 0 : size * n;
}

static size_t on_header(char *p, size_t size, size_t n, void *ud)
{
    hresp *r = ud;
    if (size * n >= 5 && !strncmp(p, "HTTP/", 5)) r->hdr.n = 0; /* after a 100 Continue */
    return buf_add(&r->hdr, p, size * n) ? 0 : size * n;
}

typedef struct reader {
    const char *p;
    size_t n, off;
} reader;

static size_t on_read(char *dst, size_t size, size_t n, void *ud)
{
    reader *r = ud;
    size_t k = size * n, left = r->n - r->off;
    if (k > left) k = left;
    if (k > 1000) k = 1000; /* several chunks */
    memcpy(dst, r->p + r->off, k);
    r->off += k;
    return k;
}

/* Appends the exchange to DIR/responses.jsonl (one line, written at once: threads may record
 * together), for srv_finish's check against schemas/openapi.json (tests/openapi_check.py).
 * Bodies over 256 KiB, or not JSON, or gzipped, are not kept. */
static void record(const srv *d, const char *method, const char *path, const hresp *r)
{
    if (!d->dir[0] || r->status <= 0) return;
    json_t *o = json_object(), *h = json_object();
    const char *block = r->hdr.p ? r->hdr.p : "";
    for (const char *p = strstr(block, "HTTP/"); p; p = strstr(p + 5, "\r\nHTTP/"))
        block = p; /* the last header block (after any 100 Continue) */
    for (const char *l = block; l && *l;) {
        const char *e = strstr(l, "\r\n");
        size_t n = e ? (size_t)(e - l) : strlen(l);
        const char *colon = memchr(l, ':', n);
        if (colon) {
            char name[64], value[1024];
            size_t k = (size_t)(colon - l);
            if (k < sizeof name) {
                for (size_t i = 0; i < k; i++) name[i] = (char)tolower((unsigned char)l[i]);
                name[k] = 0;
                const char *v = colon + 1;
                while (v < l + n && *v == ' ') v++;
                snprintf(value, sizeof value, "%.*s", (int)(l + n - v), v);
                json_object_set_new(h, name, json_string(value));
            }
        }
        l = e ? e + 2 : NULL;
    }
    const char *ct = json_string_value(json_object_get(h, "content-type"));
    int keep = r->body.n <= (256u << 10) && !json_object_get(h, "content-encoding") && ct &&
               strstr(ct, "json");
    json_object_set_new(o, "method", json_string(method));
    json_object_set_new(o, "path", json_string(path));
    json_object_set_new(o, "status", json_integer(r->status));
    json_object_set_new(o, "headers", h);
    json_object_set_new(o, "body", keep ? json_stringn(r->body.p, r->body.n) : json_null());
    char *line = json_dumps(o, JSON_COMPACT);
    json_decref(o);
    if (!line) return;
    char file[320];
    snprintf(file, sizeof file, "%s/responses.jsonl", d->dir);
    int fd = open(file, O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
        size_t n = strlen(line);
        line[n] = '\n';
        if (write(fd, line, n + 1) != (ssize_t)(n + 1)) fprintf(stderr, "record: short write\n");
        close(fd);
    }
    free(line);
}

void http_do(const srv *d, const hreq *q, hresp *r)
{
    char url[512];
    memset(r, 0, sizeof *r);
    snprintf(url, sizeof url, "%s%s", d->base, q->path);
    CURL *c = curl_easy_init();
    if (!c) {
        r->cc = CURLE_FAILED_INIT;
        return;
    }
    struct curl_slist *hl = NULL;
    reader rd = {q->body, q->len, 0};
    long tmo = (long)((q->timeout > 0 ? q->timeout : 60 * slowdown()) * 1000);
    curl_easy_setopt(c, CURLOPT_URL, url);
    curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
    curl_easy_setopt(c, CURLOPT_NOPROXY, "*");
    curl_easy_setopt(c, CURLOPT_CONNECTTIMEOUT_MS, 5000L);
    curl_easy_setopt(c, CURLOPT_TIMEOUT_MS, tmo);
    curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, on_body);
    curl_easy_setopt(c, CURLOPT_WRITEDATA, &r->body);
    curl_easy_setopt(c, CURLOPT_HEADERFUNCTION, on_header);
    curl_easy_setopt(c, CURLOPT_HEADERDATA, r);
    curl_easy_setopt(c, CURLOPT_ERRORBUFFER, r->err);
    const char *m = q->method ? q->method : q->has_body ? "POST" : "GET";
    if (q->has_body) {
        curl_easy_setopt(c, CURLOPT_POST, 1L);
        if (q->chunked) {
            curl_easy_setopt(c, CURLOPT_READFUNCTION, on_read);
            curl_easy_setopt(c, CURLOPT_READDATA, &rd);
            hl = curl_slist_append(hl, "Transfer-Encoding: chunked");
        } else {
            curl_easy_setopt(c, CURLOPT_POSTFIELDSIZE_LARGE, (curl_off_t)q->len);
            curl_easy_setopt(c, CURLOPT_POSTFIELDS, q->body ? q->body : "");
        }
        if (strcmp(m, "POST")) curl_easy_setopt(c, CURLOPT_CUSTOMREQUEST, m);
    } else if (!strcmp(m, "HEAD")) {
        curl_easy_setopt(c, CURLOPT_NOBODY, 1L);
    } else if (strcmp(m, "GET")) {
        curl_easy_setopt(c, CURLOPT_CUSTOMREQUEST, m);
    }
    if (q->decode) curl_easy_setopt(c, CURLOPT_ACCEPT_ENCODING, "gzip");
    for (int i = 0; i < 8 && q->h[i]; i++) hl = curl_slist_append(hl, q->h[i]);
    if (!q->no_expect_off) hl = curl_slist_append(hl, "Expect:");
    curl_easy_setopt(c, CURLOPT_HTTPHEADER, hl);
    double t0 = now_s();
    r->cc = curl_easy_perform(c);
    r->secs = now_s() - t0;
    curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, &r->status);
    curl_slist_free_all(hl);
    curl_easy_cleanup(c);
    if (!r->body.p) buf_add(&r->body, "", 0);
    if (!r->hdr.p) buf_add(&r->hdr, "", 0);
    record(d, m, q->path, r);
}

void http_get(const srv *d, const char *path, hresp *r)
{
    hreq q = {.path = path};
    http_do(d, &q, r);
}

void http_method(const srv *d, const char *method, const char *path, hresp *r)
{
    hreq q = {.method = method, .path = path};
    http_do(d, &q, r);
}

/* POST /v1/jobs with Content-Type: application/json and, when prefer is set, Prefer. */
void http_post(const srv *d, const char *body, size_t len, const char *prefer, hresp *r)
{
    char pf[128];
    hreq q = {.path = "/v1/jobs", .body = body, .len = len, .has_body = 1};
    q.h[0] = "Content-Type: application/json";
    if (prefer) {
        snprintf(pf, sizeof pf, "Prefer: %s", prefer);
        q.h[1] = pf;
    }
    http_do(d, &q, r);
}

/* The value of a response header (case-insensitive name) into out; 0 when absent. */
int hget(const hresp *r, const char *name, char *out, size_t n)
{
    size_t nl = strlen(name);
    const char *p = r->hdr.p;
    out[0] = 0;
    while (p && *p) {
        const char *e = strchr(p, '\n');
        size_t k = e ? (size_t)(e - p) : strlen(p);
        if (k > nl && !strncasecmp(p, name, nl) && p[nl] == ':') {
            const char *v = p + nl + 1;
            while (*v == ' ' || *v == '\t') v++;
            size_t vl = k - (size_t)(v - p);
            while (vl && (v[vl - 1] == '\r' || v[vl - 1] == ' ')) vl--;
            if (vl >= n) vl = n - 1;
            memcpy(out, v, vl);
            out[vl] = 0;
            return 1;
        }
        p = e ? e + 1 : NULL;
    }
    return 0;
}

int has_header(const hresp *r, const char *name, const char *value)
{
    char v[512];
    return hget(r, name, v, sizeof v) && !strcmp(v, value);
}

json_t *jbody(const hresp *r)
{
    return json_loadb(r->body.p ? r->body.p : "", r->body.n, 0, NULL);
}

const char *jstr(const json_t *o, const char *key)
{
    const char *s = json_string_value(json_object_get(o, key));
    return s ? s : "";
}

int is_hex(const char *s, size_t n)
{
    if (strlen(s) != n) return 0;
    for (size_t i = 0; i < n; i++)
        if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f'))) return 0;
    return 1;
}

/* ---- starting and stopping the daemon ---------------------------------------------------- */

int srv_start(srv *d)
{
    char cellard[512], listen[64];
    snprintf(cellard, sizeof cellard, "%s/cellard", build_dir());
    if (access(cellard, X_OK) != 0) {
        test_fail(__FILE__, __func__, __LINE__, "%s is not built", cellard);
        return -1;
    }
    for (int attempt = 0; attempt < 3; attempt++) {
        d->port = free_port();
        if (d->port <= 0) continue;
        snprintf(listen, sizeof listen, "127.0.0.1:%d", d->port);
        snprintf(d->base, sizeof d->base, "http://127.0.0.1:%d", d->port);
        char flags[256], *argv[40], *save = NULL;
        int argc = 0;
        snprintf(flags, sizeof flags, "%s", d->flags);
        argv[argc++] = cellard;
        argv[argc++] = "--listen";
        argv[argc++] = listen;
        argv[argc++] = "--db";
        argv[argc++] = d->db;
        for (char *t = strtok_r(flags, " ", &save); t && argc < 38; t = strtok_r(NULL, " ", &save))
            argv[argc++] = t;
        argv[argc] = NULL;
        fflush(stdout);
        pid_t pid = fork();
        if (pid < 0) {
            test_fail(__FILE__, __func__, __LINE__, "fork: %s", strerror(errno));
            return -1;
        }
        if (pid == 0) {
            int fd = open(d->log, O_WRONLY | O_CREAT | O_APPEND, 0644);
            int nul = open("/dev/null", O_RDONLY);
            if (fd >= 0) {
                dup2(fd, 1);
                dup2(fd, 2);
            }
            if (nul >= 0) dup2(nul, 0);
            execv(cellard, argv);
            _exit(127);
        }
        d->pid = pid;
        double deadline = now_s() + 10 * slowdown();
        int exited = 0, st = 0;
        while (now_s() < deadline) {
            if (waitpid(pid, &st, WNOHANG) == pid) {
                exited = 1;
                d->pid = 0;
                break;
            }
            hresp r;
            hreq q = {.path = "/healthz", .timeout = 1};
            http_do(d, &q, &r);
            long s = r.status;
            hresp_free(&r);
            if (s == 200) return 0;
            sleep_s(0.02);
        }
        if (exited && log_contains(d, "cannot listen")) continue; /* the port was taken */
        if (!exited) {
            kill(pid, SIGKILL);
            waitpid(pid, &st, 0);
            d->pid = 0;
            test_fail(__FILE__, __func__, __LINE__, "cellard did not answer /healthz in %.0f s",
                      10 * slowdown());
        } else {
            test_fail(__FILE__, __func__, __LINE__, "cellard exited at start (status 0x%x)", st);
        }
        log_tail(d, 20);
        return -1;
    }
    test_fail(__FILE__, __func__, __LINE__, "no free port for cellard");
    return -1;
}

int srv_open(srv *d, const char *flags)
{
    return srv_open_db(d, NULL, flags);
}

int srv_open_db(srv *d, const char *db, const char *flags)
{
    global_init();
    memset(d, 0, sizeof *d);
    snprintf(d->dir, sizeof d->dir, "/tmp/cellar-test-server-d-XXXXXX");
    if (!mkdtemp(d->dir)) {
        test_fail(__FILE__, __func__, __LINE__, "mkdtemp: %s", strerror(errno));
        d->dir[0] = 0;
        return -1;
    }
    if (db)
        snprintf(d->db, sizeof d->db, "%s", db);
    else
        snprintf(d->db, sizeof d->db, "%s/cellar.db", d->dir);
    snprintf(d->log, sizeof d->log, "%s/cellard.log", d->dir);
    snprintf(d->flags, sizeof d->flags, "%s", flags);
    return srv_start(d);
}

int srv_alive(srv *d)
{
    int st;
    if (!d->pid) return 0;
    if (waitpid(d->pid, &st, WNOHANG) == d->pid) {
        d->pid = 0;
        test_fail(__FILE__, __func__, __LINE__, "cellard died (status 0x%x)", st);
        return 0;
    }
    return 1;
}

/* Waits up to timeout seconds for the daemon to exit: 1 with *status, or 0. */
int srv_wait_exit(srv *d, double timeout, int *status)
{
    double deadline = now_s() + timeout;
    while (d->pid) {
        if (waitpid(d->pid, status, WNOHANG) == d->pid) {
            d->pid = 0;
            return 1;
        }
        if (now_s() > deadline) return 0;
        sleep_s(0.01);
    }
    return 0;
}

/* SIGTERM and expect exit status 0 within the drain time. */
int srv_term_(srv *d, const char *func, int line)
{
    int st = 0;
    if (!d->pid) {
        test_fail(__FILE__, func, line, "cellard is not running");
        return -1;
    }
    kill(d->pid, SIGTERM);
    if (!srv_wait_exit(d, 60 * slowdown(), &st)) {
        test_fail(__FILE__, func, line, "cellard did not exit within %.0f s of SIGTERM",
                  60 * slowdown());
        kill(d->pid, SIGKILL);
        waitpid(d->pid, &st, 0);
        d->pid = 0;
        return -1;
    }
    if (!WIFEXITED(st) || WEXITSTATUS(st) != 0) {
        if (WIFSIGNALED(st))
            test_fail(__FILE__, func, line, "cellard was killed by signal %d", WTERMSIG(st));
        else
            test_fail(__FILE__, func, line, "cellard exited with status %d", WEXITSTATUS(st));
        return -1;
    }
    return 0;
}

void srv_kill(srv *d)
{
    int st;
    if (!d->pid) return;
    kill(d->pid, SIGKILL);
    waitpid(d->pid, &st, 0);
    d->pid = 0;
}

/* Queues a document for validation against schemas/NAME.schema.json (checked at the end).
 * Documents over 512 KB are skipped: the Python validator takes about 5 s per MB. */
void vq_add(srv *d, const char *schema, const hresp *r)
{
    char f[sizeof d->vfile[0]];
    if (d->nv >= MAXV || !d->dir[0] || r->body.n > (512u << 10)) return;
    snprintf(f, sizeof f, "%s/doc%03d-%s.json", d->dir, d->nv, schema);
    if (write_file(f, r->body.p ? r->body.p : "", r->body.n)) return;
    memcpy(d->vfile[d->nv], f, sizeof f);
    d->vschema[d->nv++] = schema;
}

const char *validator(void)
{
    static char path[512];
    const char *src = getenv("CELLAR_SRC");
    snprintf(path, sizeof path, "%s/tests/validate.py", src && *src ? src : ".");
    return path;
}

void vq_check(srv *d)
{
    static const char *schemas[] = {"job", "result", "problem", "request"};
    if (!d->nv) return;
    if (access(validator(), R_OK) != 0) {
        test_fail(__FILE__, __func__, __LINE__, "%s is missing", validator());
        return;
    }
    const char *py = getenv("PYTHON");
    for (size_t s = 0; s < sizeof schemas / sizeof *schemas; s++) {
        buf cmd = {0};
        int n = 0;
        buf_printf(&cmd, "'%s' '%s' %s", py && *py ? py : "python3", validator(), schemas[s]);
        for (int i = 0; i < d->nv; i++)
            if (!strcmp(d->vschema[i], schemas[s])) {
                buf_printf(&cmd, " '%s'", d->vfile[i]);
                n++;
            }
        buf_printf(&cmd, " 2>&1");
        if (n) {
            FILE *p = popen(cmd.p, "r");
            buf out = {0};
            char tmp[4096];
            size_t k;
            while (p && (k = fread(tmp, 1, sizeof tmp, p)) > 0) buf_add(&out, tmp, k);
            int st = p ? pclose(p) : -1;
            int oks = 0;
            for (const char *q = out.p; q && (q = strstr(q, "ok ")); q += 3)
                if (q == out.p || q[-1] == '\n') oks++;
            CHECK(st == 0 && oks == n, "%d %s documents against the schema: %s", n, schemas[s],
                  out.p ? out.p : "(no output)");
            free(out.p);
        }
        free(cmd.p);
    }
    d->nv = 0;
}

/* Every response the test recorded, against schemas/openapi.json. */
static void openapi_check(srv *d)
{
    char file[320], cmd[1024];
    snprintf(file, sizeof file, "%s/responses.jsonl", d->dir);
    if (access(file, R_OK) != 0) return;
    const char *py = getenv("PYTHON");
    const char *src = getenv("CELLAR_SRC");
    snprintf(cmd, sizeof cmd, "'%s' '%s/tests/openapi_check.py' '%s' 2>&1",
             py && *py ? py : "python3", src && *src ? src : ".", file);
    size_t n = 0;
    FILE *p = popen(cmd, "r");
    buf out = {0};
    char tmp[4096];
    while (p && (n = fread(tmp, 1, sizeof tmp, p)) > 0) buf_add(&out, tmp, n);
    int st = p ? pclose(p) : -1;
    CHECK(st == 0 && out.p && !strncmp(out.p, "ok ", 3), "responses against openapi.json:\n%s",
          out.p ? out.p : "(no output)");
    free(out.p);
}

void srv_finish(srv *d)
{
    if (!d->dir[0]) return;
    vq_check(d);
    openapi_check(d);
    if (d->pid) srv_kill(d);
    const char *keep = getenv("CELLAR_TEST_KEEP");
    if (test_failed_now() || (keep && *keep)) {
        log_tail(d, 40);
        printf("  (daemon directory kept: %s)\n", d->dir);
    } else {
        rm_rf(d->dir);
    }
    d->dir[0] = 0;
}

/* A test with a daemon started with flags, available as `d` in the body; the daemon is killed
 * (if the body did not stop it) and its directory removed afterwards. */

/* ---- API helpers ------------------------------------------------------------------------- */

int job_parse(const hresp *r, jobv *j)
{
    memset(j, 0, sizeof *j);
    json_t *o = jbody(r);
    if (!json_is_object(o)) {
        json_decref(o);
        return -1;
    }
    snprintf(j->id, sizeof j->id, "%s", jstr(o, "id"));
    snprintf(j->state, sizeof j->state, "%s", jstr(o, "state"));
    snprintf(j->hash, sizeof j->hash, "%s", jstr(o, "hash"));
    snprintf(j->result, sizeof j->result, "%s", jstr(o, "result"));
    snprintf(j->daemon, sizeof j->daemon, "%s", jstr(o, "daemon"));
    j->attempts = (int)json_integer_value(json_object_get(o, "attempts"));
    json_decref(o);
    return is_hex(j->id, 32) && is_hex(j->hash, 64) ? 0 : -1;
}

/* POSTs body without Prefer and expects 202 with a job: fills j; 0 on success. */
int submit_(srv *d, const char *body, size_t len, jobv *j, const char *func, int line)
{
    hresp r;
    char loc[256], want[128];
    http_post(d, body, len, NULL, &r);
    int ok = r.status == 202 && job_parse(&r, j) == 0;
    if (ok) {
        snprintf(want, sizeof want, "/v1/jobs/%.32s", j->id);
        ok = hget(&r, "Location", loc, sizeof loc) && !strcmp(loc, want);
    }
    if (!ok)
        test_fail(__FILE__, func, line, "POST: want 202 with a job and its Location, got %ld %s %s",
                  r.status, r.err, r.body.p ? r.body.p : "");
    hresp_free(&r);
    return ok ? 0 : -1;
}

/* Polls GET /v1/jobs/{id} until its state is `want` (1), or it ends otherwise or timeout
 * seconds pass (0); the last job seen is in *j (when not NULL). */
int wait_state(srv *d, const char *id, const char *want, double timeout, jobv *j)
{
    char path[128];
    jobv tmp;
    if (!j) j = &tmp;
    snprintf(path, sizeof path, "/v1/jobs/%.32s", id);
    double deadline = now_s() + timeout, pause = 0.01;
    for (int i = 0; i < 100000; i++) {
        hresp r;
        http_get(d, path, &r);
        int parsed = r.status == 200 && job_parse(&r, j) == 0;
        hresp_free(&r);
        if (parsed && !strcmp(j->state, want)) return 1;
        if (parsed && strcmp(want, "running") &&
            (!strcmp(j->state, "done") || !strcmp(j->state, "failed") ||
             !strcmp(j->state, "canceled")))
            return 0; /* ended otherwise */
        if (parsed && !strcmp(want, "running") && strcmp(j->state, "queued")) return 0;
        if (now_s() > deadline || (d->pid && !srv_alive(d))) return 0;
        sleep_s(pause);
        if (pause < 0.05) pause *= 1.5;
    }
    return 0;
}

/* The first column of the first row of sql on the database at path, read-only (-1 on error). */
long long db_ll(const char *path, const char *sql)
{
    sqlite3 *db = NULL;
    sqlite3_stmt *st = NULL;
    long long v = -1;
    if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
        sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
        v = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(db);
    return v;
}

double srv_cpu_s(const srv *d)
{
    char path[64], line[1024];
    snprintf(path, sizeof path, "/proc/%d/stat", (int)d->pid);
    FILE *f = d->pid > 0 ? fopen(path, "r") : NULL;
    if (!f) return -1;
    size_t n = fread(line, 1, sizeof line - 1, f);
    fclose(f);
    line[n] = 0;
    /* after the command's closing parenthesis: state is field 3, utime 14, stime 15 */
    const char *p = strrchr(line, ')');
    unsigned long long ut = 0, st = 0;
    if (!p ||
        sscanf(p + 1, " %*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %llu %llu", &ut, &st) != 2)
        return -1;
    return (double)(ut + st) / (double)sysconf(_SC_CLK_TCK);
}

double srv_idle_after(const srv *d, double t0, double quiet, double timeout)
{
    double idle;
    return srvs_idle_after(&d, 1, t0, quiet, timeout, &idle) ? -1 : idle;
}

int srvs_idle_after(const srv *const *d, int n, double t0, double quiet, double timeout,
                    double *idle)
{
    double prev[16], last_busy[16], tp = now_s(), quiet_since = tp;
    if (n > 16) return -1;
    for (int i = 0; i < n; i++) {
        if ((prev[i] = srv_cpu_s(d[i])) < 0) return -1;
        last_busy[i] = tp; /* not busy from the first sample on: idle by then (a bound) */
    }
    while (now_s() < t0 + timeout) {
        sleep_s(0.05);
        double t = now_s();
        for (int i = 0; i < n; i++) {
            double c = srv_cpu_s(d[i]);
            if (c < 0) return -1;
            if (c - prev[i] >= 0.4 * (t - tp)) { /* a little now and then (the daemon's own
                                                     threads, the clock's ticks of 10 ms) is
                                                     not busy */
                last_busy[i] = t;
                quiet_since = t;
            }
            prev[i] = c;
        }
        tp = t;
        if (t - quiet_since >= quiet) {
            for (int i = 0; i < n; i++) idle[i] = last_busy[i] - t0;
            return 0;
        }
    }
    return -1;
}

char *metrics_text(srv *d)
{
    hresp r;
    http_get(d, "/metrics", &r);
    char *s = NULL;
    if (r.status == 200) {
        s = r.body.p;
        r.body.p = NULL;
    } else {
        test_fail(__FILE__, __func__, __LINE__, "GET /metrics: %ld %s", r.status, r.err);
    }
    hresp_free(&r);
    return s;
}

/* The value of a series (name with its labels exactly as exposed), or -1 when absent. */
double mval(const char *text, const char *series)
{
    size_t n = strlen(series);
    for (const char *p = text; p && *p;) {
        if (!strncmp(p, series, n) && p[n] == ' ') return strtod(p + n + 1, NULL);
        p = strchr(p, '\n');
        if (p) p++;
    }
    return -1;
}

double metric(srv *d, const char *series)
{
    char *t = metrics_text(d);
    double v = t ? mval(t, series) : -1;
    free(t);
    return v;
}

/* The value of a series once it equals want (polled for 5 s at most), else the last value:
 * the daemon counts a request when it completes and a job after it wakes its waiters, so a
 * client may hear its answer a moment before the counter moves. */
double metric_until(srv *d, const char *series, double want)
{
    double v = -1, deadline = now_s() + 5 * slowdown();
    for (int i = 0; i < 1000; i++) {
        if ((v = metric(d, series)) == want || now_s() > deadline) break;
        sleep_s(0.01);
    }
    return v;
}

/* Every 5xx counted in /metrics other than 503 (none expected). */
void check_no_500(srv *d)
{
    char *t = metrics_text(d);
    for (const char *p = t; p && (p = strstr(p, "status=\"5")); p++)
        CHECK(!strncmp(p, "status=\"503\"", 12), "a 5xx other than 503 was answered: %.60s", p);
    free(t);
}

/* The problem document checks shared by every error response. */
void check_problem_(srv *d, const hresp *r, long status, const char *path, const char *what,
                    const char *func, int line)
{
    char ct[128];
    if (r->status != status) {
        test_fail(__FILE__, func, line, "%s: want %ld, got %ld (%s) %s", what, status, r->status,
                  r->err, r->body.p ? r->body.p : "");
        return;
    }
    if (!hget(r, "Content-Type", ct, sizeof ct) || strcmp(ct, "application/problem+json"))
        test_fail(__FILE__, func, line, "%s: Content-Type %s", what, ct);
    json_t *o = jbody(r);
    if (!json_is_object(o) || json_integer_value(json_object_get(o, "status")) != status ||
        !*jstr(o, "title") || !*jstr(o, "detail") || (path && strcmp(jstr(o, "instance"), path)))
        test_fail(__FILE__, func, line, "%s: not the problem expected: %s", what, r->body.p);
    json_decref(o);
    vq_add(d, "problem", r);
}

/* /healthz answers and a small request still works (after some abuse). */
void check_sane_(srv *d, const char *after, int k, const char *func, int line)
{
    hresp r;
    size_t len, elen;
    if (!srv_alive(d)) {
        test_fail(__FILE__, func, line, "after %s: cellard is gone", after);
        return;
    }
    http_get(d, "/healthz", &r);
    if (r.status != 200)
        test_fail(__FILE__, func, line, "after %s: /healthz %ld %s", after, r.status, r.err);
    hresp_free(&r);
    char *body = small_body(k, 0, &len);
    const char *exp = expect(body, len, &elen);
    http_post(d, body, len, "wait=20", &r);
    if (r.status != 200 || same_result(r.body.p, r.body.n, exp, elen) != 1)
        test_fail(__FILE__, func, line, "after %s: a small request: %ld %s", after, r.status,
                  r.err);
    hresp_free(&r);
    free(body);
}

/* ---- raw sockets ------------------------------------------------------------------------ */

int raw_connect(const srv *d)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return -1;
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)d->port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    struct timeval tv = {5, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

/* Sends everything it can (the server may close first); returns the bytes sent. */
size_t raw_send(int fd, const void *data, size_t len)
{
    size_t off = 0;
    while (off < len) {
        ssize_t k = send(fd, (const char *)data + off, len - off, MSG_NOSIGNAL);
        if (k <= 0) break;
        off += (size_t)k;
    }
    return off;
}

/* Reads until the server closes, the timeout passes or max bytes; NUL-terminated. */
size_t raw_read(int fd, char *out, size_t max, double timeout)
{
    size_t n = 0;
    double deadline = now_s() + timeout;
    while (n + 1 < max && now_s() < deadline) {
        ssize_t k = recv(fd, out + n, max - 1 - n, 0);
        if (k <= 0) break;
        n += (size_t)k;
    }
    out[n] = 0;
    return n;
}

/* One raw exchange: the status of the answer (0: none).  The write side is shut after the
 * request, as a client that sends garbage might. */
int raw_exchange(const srv *d, const void *data, size_t len, char *out, size_t max)
{
    return raw_exchange_ex(d, data, len, out, max, 1);
}

/* The same; half_close 0 leaves the write side open, as HTTP clients do (one that shuts it
 * while its request is suspended, in the intake or in a wait, loses the answer: libmicrohttpd
 * takes the end of its input for the end of the connection when it resumes it). */
int raw_exchange_ex(const srv *d, const void *data, size_t len, char *out, size_t max,
                    int half_close)
{
    int fd = raw_connect(d);
    if (fd < 0) return -1;
    raw_send(fd, data, len);
    if (half_close) shutdown(fd, SHUT_WR);
    size_t n = raw_read(fd, out, max, 10 * slowdown());
    close(fd);
    int status = 0;
    if (n > 12 && !strncmp(out, "HTTP/1.", 7)) status = atoi(out + 9);
    return status;
}

void *post_thread(void *arg)
{
    poster *p = arg;
    if (p->bar) pthread_barrier_wait(p->bar);
    http_post(p->d, p->body, p->len, p->prefer, &p->r);
    return NULL;
}
