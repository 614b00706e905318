/* config.h — the daemon's settings: defaults, then CELLAR_* environment variables, then
 * command-line flags (each flag overrides its variable).
 *
 *   flag            variable            default         meaning
 *   --listen        CELLAR_LISTEN       127.0.0.1:8080  HOST:PORT to listen on (PORT 0: any)
 *   --db            CELLAR_DB           ./cellar.db     the SQLite file (jobs and results), or
 *                                                       a postgresql:// URI (shared)
 *   --name          CELLAR_NAME         HOSTNAME-PID    this daemon, as the jobs' owner
 *   --lease-seconds CELLAR_LEASE_SECONDS 30             a claim's lease (renewed every second)
 *   --spool         CELLAR_SPOOL        --db's dir/tmp  where results are written as they are
 *                                                       made, before they enter the store
 *   --workers       CELLAR_WORKERS      CPUs            jobs run at once
 *   --job-threads   CELLAR_JOB_THREADS  CPUs            core threads of one job
 *   --queue         CELLAR_QUEUE        64              jobs waiting at most (then 503)
 *   --intake-threads CELLAR_INTAKE_THREADS CPUs         threads that parse and validate POSTs
 *   --max-body      CELLAR_MAX_BODY     67108864        request body bytes at most (then 413)
 *   --max-inflight-bytes CELLAR_MAX_INFLIGHT_BYTES 268435456  request body bytes held at once
 *                                                       by all connections (then 503)
 *   --max-connections CELLAR_MAX_CONNECTIONS 1000       open connections at most
 *   --max-per-ip    CELLAR_MAX_PER_IP   64              open connections from one address (0: any)
 *   --header-timeout CELLAR_HEADER_TIMEOUT 10           seconds to send a request's headers
 *   --body-timeout  CELLAR_BODY_TIMEOUT 120             seconds to send a request's body
 *   --idle-timeout  CELLAR_IDLE_TIMEOUT 120             seconds a connection may stay silent
 *   --max-wait      CELLAR_MAX_WAIT     55              seconds a Prefer: wait may hold
 *   --cache-bytes   CELLAR_CACHE_BYTES  1073741824      result cache budget (0: unlimited)
 *   --drain-timeout CELLAR_DRAIN_TIMEOUT 30             seconds SIGTERM waits for running jobs
 *   --job-ttl       CELLAR_JOB_TTL      604800          seconds a finished job is kept
 *   --max-jobs      CELLAR_MAX_JOBS     100000          finished jobs kept at most
 *   --log-level     CELLAR_LOG_LEVEL    info            debug, info, warn, error
 *   --cors-origins  CELLAR_CORS_ORIGINS ""              origins allowed by CORS ("*": any)
 *   --base-path     CELLAR_BASE_PATH    ""              the path the service is mounted at
 *                                                       behind a proxy ("/geometry"): the
 *                                                       links it writes start with it, and a
 *                                                       request path under it is served with
 *                                                       it removed (config_path_prefix)
 *   --healthcheck   (flag only)                         GET /healthz of the daemon at --listen:
 *                                                       exit 0 on 200 (a container's check)
 *   --init          (flag only)                         make a store in an empty or foreign
 *                                                       --db file instead of refusing it
 */
#ifndef CELLAR_CONFIG_H
#define CELLAR_CONFIG_H

#include <stddef.h>
#include <stdint.h>

/* The longest path prefix (--base-path, X-Forwarded-Prefix) taken, in bytes. */
#define CONFIG_PREFIX_MAX 128

typedef struct config {
    char host[256];
    unsigned port;
    char db[4096];
    char spool[4096]; /* "": the system's temporary directory */
    char name[64];
    char cors_origins[1024]; /* --cors-origins: "" none, "*" any, or a comma-separated list */
    char base_path[CONFIG_PREFIX_MAX + 1]; /* --base-path: "" (the root) or "/a/b" */
    double lease;
    int workers, job_threads, intake_threads;
    size_t queue;
    uint64_t max_body;
    uint64_t max_inflight;
    double max_wait;
    unsigned max_connections, max_per_ip;
    double header_timeout, body_timeout;
    unsigned idle_timeout;
    uint64_t cache_bytes;
    double drain_timeout;
    double job_ttl;
    size_t max_jobs;
    int log_level;
    int init;        /* --init */
    int healthcheck; /* --healthcheck */
} config;

/* Fills *c from the environment and argv.  Returns 0; 1 after printing help (exit 0); -1 with
 * a message in err for a bad value or an unknown flag (exit 2). */
int config_load(config *c, int argc, char **argv, char *err, size_t errlen);

/* A path prefix (--base-path, or a request's X-Forwarded-Prefix) checked and copied to out:
 * "/" followed by segments of letters, digits and "-._~" separated by single "/", no segment
 * "." or "..", no "/" at the end, at most CONFIG_PREFIX_MAX bytes.  "/" alone is the root and
 * gives "".  Returns 0, or -1 (out is then "") with what is wrong in why (static). */
int config_path_prefix(const char *v, char out[CONFIG_PREFIX_MAX + 1], const char **why);

extern const char config_usage[];

#endif
