/* main.c — cellard: the daemon.  Loads the configuration, opens the store, starts the engine
 * (which resumes the jobs a previous run left queued or running) and the HTTP server, then
 * waits for SIGTERM or SIGINT and drains: /readyz answers 503 and new jobs are refused, the
 * running jobs finish (up to --drain-timeout), waiting clients get their answer, and the
 * process exits 0.  Queued jobs stay in the store for the next start.
 *
 * Signals are blocked in every thread (the mask is set before any thread starts) and taken
 * here with sigwait(), so no handler runs inside the daemon's threads.
 */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <netdb.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include "api/meshio.h"
#include "api/api.h"
#include "server/config.h"
#include "server/engine.h"
#include "server/http.h"
#include "server/log.h"
#include "server/metrics.h"
#include "server/store.h"

/* --db for the log: a URI's password is not written (postgresql://user:***@host/db). */
static const char *log_db(const char *db)
{
    static char out[4200];
    const char *scheme = strstr(db, "://"), *at = strchr(db, '@');
    const char *colon = scheme ? strchr(scheme + 3, ':') : NULL;
    if (!scheme || !at || !colon || colon > at) return db;
    snprintf(out, sizeof out, "%.*s:***%s", (int)(colon - db), db, at);
    return out;
}

/* --healthcheck: GET /healthz from the daemon at cfg's --listen (0.0.0.0 and :: asked at the
 * loopback), 3 s at most; 0 when it answers 200. */
static int healthcheck(const config *cfg)
{
    char port[8];
    const char *host = cfg->host;
    if (!strcmp(host, "0.0.0.0") || !*host) host = "127.0.0.1";
    if (!strcmp(host, "::")) host = "::1";
    snprintf(port, sizeof port, "%u", cfg->port);
    struct addrinfo hints = {.ai_socktype = SOCK_STREAM}, *ai = NULL;
    if (getaddrinfo(host, port, &hints, &ai) != 0) return 1;
    int fd = socket(ai->ai_family, SOCK_STREAM | SOCK_CLOEXEC, 0), ok = 0;
    struct timeval tv = {3, 0};
    if (fd >= 0) {
        setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    }
    if (fd >= 0 && connect(fd, ai->ai_addr, ai->ai_addrlen) == 0) {
        static const char req[] = "GET /healthz HTTP/1.1\r\nHost: localhost\r\n"
                                  "Connection: close\r\n\r\n";
        char buf[64] = "";
        if (write(fd, req, sizeof req - 1) == (ssize_t)(sizeof req - 1)) {
            ssize_t n = read(fd, buf, sizeof buf - 1);
            ok = n > 12 && !strncmp(buf, "HTTP/1.1 200", 12);
        }
    }
    if (fd >= 0) close(fd);
    freeaddrinfo(ai);
    fprintf(stderr, "cellard: %s:%s /healthz: %s\n", host, port, ok ? "ok" : "not healthy");
    return ok ? 0 : 1;
}

int main(int argc, char **argv)
{
    config cfg;
    char err[512];
    int rc = config_load(&cfg, argc, argv, err, sizeof err);
    if (rc == 1) return 0;
    if (rc < 0) {
        fprintf(stderr, "cellard: %s\n", err);
        return 2;
    }
    if (cfg.healthcheck) return healthcheck(&cfg);
    log_set_level(cfg.log_level);
    mesh_set_max_part(cfg.max_body); /* a 3MF body inflates to no more than a JSON body holds */

    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    signal(SIGPIPE, SIG_IGN);
    /* --max-connections sockets, the database's files and the spool: raise the soft limit on
     * open files to the hard one (often 1024 by default, below what 1000 connections need) */
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < rl.rlim_max) {
        rl.rlim_cur = rl.rlim_max;
        setrlimit(RLIMIT_NOFILE, &rl);
    }

    metrics *m = metrics_new();
    store *st =
        m ? store_open(cfg.db, cfg.cache_bytes, 10, cfg.init ? STORE_OPEN_INIT : 0, err, sizeof err)
          : NULL;
    if (!st) {
        log_kv(LOG_ERROR, "cannot open the store", "db", log_db(cfg.db), "error",
               m ? err : "no memory", NULL);
        metrics_free(m);
        return 1;
    }
    engine_cfg ec = {.st = st,
                     .m = m,
                     .workers = cfg.workers,
                     .job_threads = cfg.job_threads,
                     .queue_max = cfg.queue,
                     .spool_dir = cfg.spool[0] ? cfg.spool : NULL,
                     .lease = cfg.lease,
                     .name = cfg.name,
                     .job_ttl = cfg.job_ttl,
                     .max_jobs = cfg.max_jobs};
    engine *e = engine_start(&ec, err, sizeof err);
    if (!e) {
        log_kv(LOG_ERROR, "cannot start the engine", "error", err, NULL);
        st->ops->close(st);
        metrics_free(m);
        return 1;
    }
    http_server *h = http_start(&cfg, e, st, m, err, sizeof err);
    if (!h) {
        log_kv(LOG_ERROR, "cannot start the HTTP server", "error", err, NULL);
        engine_drain(e, 0);
        engine_stop(e);
        st->ops->close(st);
        metrics_free(m);
        return 1;
    }
    char port[32], workers[32];
    log_num(port, http_port(h));
    log_num(workers, cfg.workers);
    log_kv(LOG_INFO, "listening", "host", cfg.host, "port", port, "db", log_db(cfg.db), "name",
           cfg.name, "workers", workers, "version", API_VERSION, "algorithm", CELLAR_ALGO_VERSION,
           NULL);

    int sig = 0;
    sigwait(&set, &sig);
    log_kv(LOG_INFO, "draining", "signal", sig == SIGTERM ? "SIGTERM" : "SIGINT", NULL);
    http_set_draining(h);
    engine_drain(e, cfg.drain_timeout);
    http_stop(h);
    engine_stop(e);
    st->ops->close(st);
    metrics_free(m);
    log_kv(LOG_INFO, "stopped", NULL);
    return 0;
}
