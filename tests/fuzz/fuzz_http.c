/* fuzz_http.c — libFuzzer target: the daemon's HTTP request path, whole.  LLVMFuzzerInitialize
 * starts the daemon's pieces in this process once, wired as server/main.c wires them: the
 * configuration (config_load, with small limits), a SQLite store in a temporary directory
 * (STORE_OPEN_INIT), the metrics, the engine (one worker, one core thread) and the HTTP server
 * on 127.0.0.1, port 0.  Each input is then sent as it is over a new TCP connection, the write
 * side shut, and the answer read until it is whole (by its Content-Length or chunks), the
 * daemon closes, or the wait runs out (FUZZ_HTTP_QUICK_MS for a first byte, unless the request
 * says Prefer; FUZZ_HTTP_WAIT_MS in all): a partial request never holds the fuzzer.  Then the
 * connection is reset.
 *
 * Checks beyond the sanitizers (which watch every thread: MHD's, the engine's, the reaper):
 * whatever arrives is an HTTP/1.x answer ("HTTP/1." at its start, or a prefix of it when cut
 * short), and no answer is a 500 (api/api.h: "a bug of ours").
 *
 * Seed inputs are real requests (tests/fuzz/corpus/http/): GET /healthz, POST /v1/jobs with a
 * small JSON, GET, DELETE of /v1/jobs/<id> and its result, bad requests.
 *
 * Leaks: LeakSanitizer stays on (no detect_leaks=0).  The daemon lives until the process
 * exits and frees a connection's memory on its own threads, possibly after the input that
 * opened it has returned, so libFuzzer's per-input malloc/free balance can be off; its leak
 * pass then finds that memory still reachable (the daemon holds it) and reports nothing (after
 * 1000 such passes libFuzzer would stop trying per input, and say so).  LeakSanitizer's
 * check at exit remains.
 */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* memmem, strnlen, strncasecmp (the Makefile defines it too) */
#endif
#include <arpa/inet.h>
#include <errno.h>
#include <ftw.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "server/config.h"
#include "server/engine.h"
#include "server/http.h"
#include "server/log.h"
#include "server/metrics.h"
#include "server/store.h"
#include "tests/fuzz/fuzz.h"

#define FUZZ_HTTP_MAX      4096 /* inputs larger than this are refused */
#define FUZZ_HTTP_WAIT_MS  200  /* the longest an input waits for its answer */
#define FUZZ_HTTP_QUICK_MS 50   /* ... for the answer's first byte, unless it asks to wait */

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The daemon: process-wide, started once, never stopped (the process's exit ends it). */
static config cfg;
static metrics *met;
static store *st;
static engine *eng;
static http_server *srv;
static struct sockaddr_in addr;
static char tmpdir[4096];
static int trace; /* CELLAR_FUZZ_HTTP_TRACE=1: each answer's first line (and time) on stderr */

static int rm_one(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)flag, (void)ftw;
    return remove(path) < 0 && errno != ENOENT ? -1 : 0;
}

static void remove_tmpdir(void)
{
    if (tmpdir[0]) nftw(tmpdir, rm_one, 16, FTW_DEPTH | FTW_PHYS);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    char err[512], db[4200], spool[4200];
    const char *t = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/cellar-fuzz-http-XXXXXX", t && *t ? t : "/tmp");
    if (!mkdtemp(tmpdir)) {
        fprintf(stderr, "fuzz_http: mkdtemp %s: %s\n", tmpdir, strerror(errno));
        exit(1);
    }
    atexit(remove_tmpdir);
    trace = getenv("CELLAR_FUZZ_HTTP_TRACE") != NULL;
    snprintf(db, sizeof db, "--db=%s/fuzz.db", tmpdir);
    snprintf(spool, sizeof spool, "--spool=%s", tmpdir);
    /* small limits: every input is cheap, and the queue and the cache stay small */
    char *args[] = {"fuzz_http",
                    "--listen=127.0.0.1:0",
                    db,
                    spool,
                    "--workers=1",
                    "--job-threads=1",
                    "--intake-threads=1",
                    "--queue=4",
                    "--max-body=4096",
                    "--max-inflight-bytes=65536",
                    "--max-connections=64",
                    "--max-per-ip=0",
                    "--header-timeout=2",
                    "--body-timeout=2",
                    "--idle-timeout=2",
                    "--max-wait=1",
                    "--cache-bytes=4194304",
                    "--job-ttl=60",
                    "--max-jobs=200",
                    "--log-level=error",
                    "--init",
                    NULL};
    int n = (int)(sizeof args / sizeof *args) - 1;
    if (config_load(&cfg, n, args, err, sizeof err) != 0) {
        fprintf(stderr, "fuzz_http: config: %s\n", err);
        exit(1);
    }
    log_set_level(cfg.log_level);
    signal(SIGPIPE, SIG_IGN);
    met = metrics_new();
    st = met ? store_sqlite_open(cfg.db, cfg.cache_bytes, 10, cfg.init ? STORE_OPEN_INIT : 0, err,
                                 sizeof err)
             : NULL;
    if (!st) {
        fprintf(stderr, "fuzz_http: store: %s\n", met ? err : "no memory");
        exit(1);
    }
    engine_cfg ec = {.st = st,
                     .m = met,
                     .workers = cfg.workers,
                     .job_threads = cfg.job_threads,
                     .queue_max = cfg.queue,
                     .spool_dir = cfg.spool,
                     .job_ttl = cfg.job_ttl,
                     .max_jobs = cfg.max_jobs,
                     .lease = cfg.lease,
                     .name = cfg.name};
    eng = engine_start(&ec, err, sizeof err);
    if (!eng) {
        fprintf(stderr, "fuzz_http: engine: %s\n", err);
        exit(1);
    }
    srv = http_start(&cfg, eng, st, met, err, sizeof err);
    if (!srv) {
        fprintf(stderr, "fuzz_http: http: %s\n", err);
        exit(1);
    }
    addr.sin_family = AF_INET;
    addr.sin_port = htons((uint16_t)http_port(srv));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    return 0;
}

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec / 1e6;
}

/* Whether data[0..n) holds "prefer:" in any case (a request that may wait for its job). */
static int asks_to_wait(const uint8_t *data, size_t n)
{
    static const char w[] = "prefer:";
    for (size_t i = 0; i + sizeof w - 1 <= n; i++)
        if (strncasecmp((const char *)data + i, w, sizeof w - 1) == 0) return 1;
    return 0;
}

/* The end of the HTTP response that starts at a[pos] when a[0..n) holds it whole, else 0.
 * head: the request was a HEAD (no body follows the headers).  *close (may be NULL) is set
 * when the response says "Connection: close". */
static size_t response_end(const char *a, size_t n, size_t pos, int head, int *close)
{
    const char *h = memmem(a + pos, n - pos, "\r\n\r\n", 4);
    if (!h) return 0;
    size_t body = (size_t)(h - a) + 4, len = 0;
    int status = 0, chunked = 0, has_len = 0;
    if (n - pos >= 12 && memcmp(a + pos, "HTTP/1.", 7) == 0)
        status = (a[pos + 9] - '0') * 100 + (a[pos + 10] - '0') * 10 + (a[pos + 11] - '0');
    for (const char *l = a + pos; l < h;) {
        const char *e = memmem(l, (size_t)(h - l), "\r\n", 2);
        if (!e) e = h;
        if (strncasecmp(l, "Content-Length:", 15) == 0) {
            has_len = 1;
            len = strtoul(l + 15, NULL, 10);
        } else if (strncasecmp(l, "Transfer-Encoding:", 18) == 0 &&
                   memmem(l, (size_t)(e - l), "chunked", 7)) {
            chunked = 1;
        } else if (close && strncasecmp(l, "Connection:", 11) == 0 &&
                   memmem(l, (size_t)(e - l), "close", 5)) {
            *close = 1;
        }
        l = e + 2;
    }
    /* head: the input began with HEAD, but pipelined requests after it may not be HEADs (the
     * requests are not parsed here): a response whose declared body is there, where the next
     * status line would be, has one */
    if (head && has_len && n - body >= len && len > 0 && n > body &&
        memcmp(a + body, "HTTP/1.", n - body < 7 ? n - body : 7) != 0)
        head = 0;
    if ((status >= 100 && status < 200) || status == 204 || status == 304 || head) return body;
    if (has_len) return n - body >= len ? body + len : 0;
    if (!chunked) return 0;   /* the body runs to the end of the connection */
    for (size_t p = body;;) { /* chunks: SIZE CRLF DATA CRLF ..., 0 CRLF, trailers, CRLF */
        const char *e = memmem(a + p, n - p, "\r\n", 2);
        if (!e) return 0;
        size_t sz = strtoul(a + p, NULL, 16);
        p = (size_t)(e - a) + 2;
        if (sz == 0) {
            const char *t = memmem(a + p - 2, n - p + 2, "\r\n\r\n", 4);
            return t ? (size_t)(t - a) + 4 : 0;
        }
        if (n - p < sz + 2) return 0;
        p += sz + 2;
    }
}

/* Whether a[0..n) ends with a final (not 1xx) response, whole. */
static int answer_whole(const char *a, size_t n, int head)
{
    size_t pos = 0;
    int final = 0;
    while (pos < n) {
        size_t end = response_end(a, n, pos, head, NULL);
        if (!end) return 0;
        final = !(n - pos >= 12 && a[pos + 9] == '1');
        pos = end;
    }
    return final;
}

/* Every response of the answer (several when requests were pipelined) is HTTP/1.x (or a prefix
 * of it, cut short) and none is a 500.  Bytes after a response that closes the connection are
 * not looked at: libmicrohttpd 0.9.75 (Debian 12) sends the headers of its own 400 for an
 * HTTP/1.1 request without Host twice, the second copy counted in the body's Content-Length,
 * so the end of its body follows the response (not a bug of ours). */
static void check_answer(const char *a, size_t n, int head)
{
    static const char proto[] = "HTTP/1.";
    size_t pos = 0;
    int close = 0;
    while (pos < n && !close) {
        size_t k = n - pos < sizeof proto - 1 ? n - pos : sizeof proto - 1;
        FUZZ_CHECK(memcmp(a + pos, proto, k) == 0, "an answer that is not HTTP/1.x: \"%.*s\"",
                   (int)(n - pos < 40 ? n - pos : 40), a + pos);
        size_t end = response_end(a, n, pos, head, &close);
        /* a 500 is a finding, unless its problem's detail tells of a known bug (fuzz.h) */
        FUZZ_CHECK(n - pos < 12 || memcmp(a + pos + 9, "500", 3) != 0 ||
                       fuzz_known_bug(a + pos, (end ? end : n) - pos),
                   "a 500 answer: \"%.*s\"", (int)(n - pos < 400 ? n - pos : 400), a + pos);
        if (!end) break;
        pos = end;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char answer[1 << 16];
    size_t got = 0;
    if (size > FUZZ_HTTP_MAX) return -1;
    int head = size >= 5 && memcmp(data, "HEAD ", 5) == 0;
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    FUZZ_CHECK(fd >= 0, "socket: %s", strerror(errno));
    /* closed with a reset, not a FIN: no TIME_WAIT left behind, so hundreds of connections a
     * second for hours never run out of local ports (connect would fail) */
    struct linger lg = {.l_onoff = 1, .l_linger = 0};
    setsockopt(fd, SOL_SOCKET, SO_LINGER, &lg, sizeof lg);
    int rc = connect(fd, (struct sockaddr *)&addr, sizeof addr);
    if (rc < 0 && errno == EINTR) {
        /* a signal (libFuzzer's timer) cut the call short: the connection goes on being made;
         * wait for it and take its outcome */
        struct pollfd p = {.fd = fd, .events = POLLOUT};
        while (poll(&p, 1, 5000) < 0 && errno == EINTR) {
        }
        int err = ETIMEDOUT;
        socklen_t len = sizeof err;
        if (p.revents && getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) < 0) err = errno;
        rc = err ? -1 : 0;
        errno = err;
    }
    if (rc < 0) {
        /* the daemon is gone or refuses connections: a finding, not a bad input */
        FUZZ_CHECK(0, "connect to 127.0.0.1:%u: %s", ntohs(addr.sin_port), strerror(errno));
    }
    for (size_t off = 0; off < size;) {
        ssize_t w = send(fd, data + off, size - off, MSG_NOSIGNAL);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) break; /* the daemon closed early (a bad request): read its answer */
        off += (size_t)w;
    }
    shutdown(fd, SHUT_WR);
    /* the daemon answers at once, but for a wait on a job; it does not close a half-closed
     * connection, so an incomplete request is given up on after the first wait */
    double t0 = now_ms(), deadline = t0 + FUZZ_HTTP_WAIT_MS;
    double first = asks_to_wait(data, size) ? deadline : t0 + FUZZ_HTTP_QUICK_MS;
    for (;;) {
        double left = (got ? deadline : first) - now_ms();
        if (left <= 0) break;
        struct pollfd p = {.fd = fd, .events = POLLIN};
        int r = poll(&p, 1, (int)left + 1);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) break;
        ssize_t k = recv(fd, answer + got, sizeof answer - 1 - got, 0);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) break; /* closed (or reset) by the daemon */
        got += (size_t)k;
        answer[got] = 0; /* strtoul and strncasecmp stop here */
        if (got == sizeof answer - 1 || answer_whole(answer, got, head)) break;
    }
    close(fd);
    if (trace) {
        size_t eol = 0;
        while (eol < got && answer[eol] != '\r' && answer[eol] != '\n') eol++;
        fprintf(stderr, "fuzz_http: %zu bytes in, %zu out in %.1f ms: %.*s\n", size, got,
                now_ms() - t0, (int)eol, answer);
    }
    if (got) check_answer(answer, got, head);
    return 0;
}
