/* config.c — see config.h.  Every value is checked; nothing is silently clamped. */
#include "server/config.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "server/log.h"

const char config_usage[] =
    "usage: cellard [options]\n"
    "  --listen HOST:PORT    CELLAR_LISTEN        default 127.0.0.1:8080 (PORT 0: any free)\n"
    "  --db PATH|URI         CELLAR_DB            a SQLite file (one daemon), or a PostgreSQL\n"
    "                                             postgresql://... URI that several daemons\n"
    "                                             share (default ./cellar.db)\n"
    "  --spool DIR           CELLAR_SPOOL         results are written here as they are made\n"
    "                                             (default: the directory of a --db file, else\n"
    "                                             the system's temporary directory)\n"
    "  --name NAME           CELLAR_NAME          this daemon in the jobs it runs (default:\n"
    "                                             HOSTNAME-PID)\n"
    "  --lease-seconds SECS  CELLAR_LEASE_SECONDS a job's claim lasts this long unless renewed\n"
    "                                             (every second while it runs); a daemon's\n"
    "                                             jobs are requeued this long after it dies\n"
    "                                             (default 30)\n"
    "  --workers N           CELLAR_WORKERS       jobs run at once (default: CPUs; 0: this\n"
    "                                             daemon only answers, others sharing its\n"
    "                                             --db run the jobs)\n"
    "  --job-threads N       CELLAR_JOB_THREADS   core threads per job (default: CPUs)\n"
    "  --queue N             CELLAR_QUEUE         waiting jobs at most (default 64)\n"
    "  --intake-threads N    CELLAR_INTAKE_THREADS  threads that parse and validate POST bodies\n"
    "                                             (default: CPUs)\n"
    "  --max-body BYTES      CELLAR_MAX_BODY      request body limit (default 67108864)\n"
    "  --max-inflight-bytes BYTES  CELLAR_MAX_INFLIGHT_BYTES  request body bytes held by all\n"
    "                        connections at once, then 503 (default 268435456)\n"
    "  --max-connections N   CELLAR_MAX_CONNECTIONS  open connections at most (default 1000)\n"
    "  --max-per-ip N        CELLAR_MAX_PER_IP    from one address at most, 0 = any (default 64)\n"
    "  --header-timeout SECS CELLAR_HEADER_TIMEOUT  a request's headers must be in (default 10)\n"
    "  --body-timeout SECS   CELLAR_BODY_TIMEOUT  a request's body must be in (default 120)\n"
    "  --idle-timeout SECS   CELLAR_IDLE_TIMEOUT  a silent connection is closed (default 120)\n"
    "  --max-wait SECONDS    CELLAR_MAX_WAIT      longest Prefer: wait (default 55)\n"
    "  --cache-bytes BYTES   CELLAR_CACHE_BYTES   result cache budget, 0 = none (default 1 GiB)\n"
    "  --drain-timeout SECS  CELLAR_DRAIN_TIMEOUT SIGTERM waits this long for running jobs\n"
    "  --job-ttl SECONDS     CELLAR_JOB_TTL       a finished job is kept this long (default 7 "
    "days)\n"
    "  --max-jobs N          CELLAR_MAX_JOBS      finished jobs kept at most (default 100000)\n"
    "  --log-level LEVEL     CELLAR_LOG_LEVEL     debug, info, warn, error (default info)\n"
    "  --cors-origins LIST   CELLAR_CORS_ORIGINS  origins whose pages may call the API (CORS):\n"
    "                                             \"*\", or comma-separated origins such as\n"
    "                                             https://app.example (default none)\n"
    "  --base-path PATH      CELLAR_BASE_PATH     the path the service is mounted at behind a\n"
    "                                             proxy, such as /geometry: the links it writes\n"
    "                                             (Location, job \"result\") start with it, and\n"
    "                                             it is removed from request paths under it; a\n"
    "                                             request's X-Forwarded-Prefix overrides it\n"
    "                                             (default: none, the root)\n"
    "  --init                make a store in an empty --db file, or add its tables to another\n"
    "                        program's SQLite database (both are refused without it)\n"
    "  --healthcheck         ask the daemon at --listen for /healthz and exit 0 when it answers\n"
    "                        200 within 3 s, else 1 (a container's HEALTHCHECK: no curl needed)\n"
    "  --help\n";

static int bad(char *err, size_t errlen, const char *what, const char *v)
{
    snprintf(err, errlen, "%s: invalid value \"%s\"", what, v);
    return -1;
}

int config_path_prefix(const char *v, char out[CONFIG_PREFIX_MAX + 1], const char **why)
{
    size_t n = strlen(v);
    out[0] = 0;
    *why = NULL;
    if (v[0] != '/')
        *why = "it must begin with \"/\"";
    else if (n > CONFIG_PREFIX_MAX)
        *why = "it is longer than 128 bytes";
    else if (n == 1)
        return 0; /* "/": the root */
    else if (v[n - 1] == '/')
        *why = "it must not end with \"/\"";
    for (const char *p = v; !*why && *p;) { /* a segment after each "/" */
        size_t k =
            strspn(++p, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-._~");
        if (p[k] && p[k] != '/')
            *why = "only letters, digits, \"-._~\" and \"/\" between segments are allowed";
        else if (k == 0)
            *why = "it has an empty segment (\"//\")";
        else if ((k == 1 && p[0] == '.') || (k == 2 && p[0] == '.' && p[1] == '.'))
            *why = "it has a \".\" or \"..\" segment";
        p += k;
    }
    if (*why) return -1;
    memcpy(out, v, n + 1);
    return 0;
}

static int parse_u64(const char *v, uint64_t lo, uint64_t hi, uint64_t *out)
{
    char *end;
    errno = 0;
    if (!*v || *v == '-') return -1;
    unsigned long long x = strtoull(v, &end, 10);
    if (errno || *end || x < lo || x > hi) return -1;
    *out = x;
    return 0;
}

static int parse_secs(const char *v, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double x = strtod(v, &end);
    if (errno || end == v || *end || !(x >= lo && x <= hi)) return -1;
    *out = x;
    return 0;
}

static int set(config *c, const char *name, const char *v, char *err, size_t errlen)
{
    uint64_t u;
    if (!strcmp(name, "listen")) {
        const char *colon = strrchr(v, ':');
        if (!colon || colon == v || (size_t)(colon - v) >= sizeof c->host ||
            parse_u64(colon + 1, 0, 65535, &u))
            return bad(err, errlen, "--listen (HOST:PORT)", v);
        memcpy(c->host, v, (size_t)(colon - v));
        c->host[colon - v] = 0;
        if (c->host[0] == '[' && c->host[strlen(c->host) - 1] == ']') { /* [::1] */
            memmove(c->host, c->host + 1, strlen(c->host));
            c->host[strlen(c->host) - 1] = 0;
        }
        c->port = (unsigned)u;
    } else if (!strcmp(name, "db")) {
        if (!*v || strlen(v) >= sizeof c->db) return bad(err, errlen, "--db", v);
        strcpy(c->db, v);
    } else if (!strcmp(name, "name")) {
        if (!*v || strlen(v) >= sizeof c->name) return bad(err, errlen, "--name (1..63 bytes)", v);
        strcpy(c->name, v);
    } else if (!strcmp(name, "lease-seconds")) {
        if (parse_secs(v, 2, 3600, &c->lease))
            return bad(err, errlen, "--lease-seconds (2..3600)", v);
    } else if (!strcmp(name, "cors-origins")) {
        if (strlen(v) >= sizeof c->cors_origins) return bad(err, errlen, "--cors-origins", v);
        strcpy(c->cors_origins, v);
    } else if (!strcmp(name, "base-path")) {
        const char *why;
        if (config_path_prefix(v, c->base_path, &why)) {
            snprintf(err, errlen, "--base-path: invalid value \"%.200s\": %s", v, why);
            return -1;
        }
        /* a request path under it has it removed: it cannot begin like a path of the
         * daemon's own (the page's assets, the API, the operations routes) */
        static const char *const own[] = {"v1",     "assets",  "healthz",
                                          "readyz", "metrics", "openapi.json"};
        for (size_t i = 0; i < sizeof own / sizeof *own; i++) {
            size_t k = strlen(own[i]);
            if (!strncmp(c->base_path + 1, own[i], k) &&
                (c->base_path[1 + k] == 0 || c->base_path[1 + k] == '/')) {
                snprintf(err, errlen,
                         "--base-path: invalid value \"%.200s\": it begins like a path of the "
                         "service's own (/%s)",
                         v, own[i]);
                c->base_path[0] = 0;
                return -1;
            }
        }
    } else if (!strcmp(name, "spool")) {
        if (!*v || strlen(v) >= sizeof c->spool) return bad(err, errlen, "--spool", v);
        strcpy(c->spool, v);
    } else if (!strcmp(name, "workers")) {
        if (parse_u64(v, 0, 256, &u)) return bad(err, errlen, "--workers (0..256)", v);
        c->workers = (int)u;
    } else if (!strcmp(name, "job-threads")) {
        if (parse_u64(v, 1, 64, &u)) return bad(err, errlen, "--job-threads (1..64)", v);
        c->job_threads = (int)u;
    } else if (!strcmp(name, "intake-threads")) {
        if (parse_u64(v, 1, 64, &u)) return bad(err, errlen, "--intake-threads (1..64)", v);
        c->intake_threads = (int)u;
    } else if (!strcmp(name, "queue")) {
        if (parse_u64(v, 1, 1000000, &u)) return bad(err, errlen, "--queue (1..1000000)", v);
        c->queue = (size_t)u;
    } else if (!strcmp(name, "max-body")) {
        if (parse_u64(v, 1024, (uint64_t)1 << 32, &u))
            return bad(err, errlen, "--max-body (1024..4294967296)", v);
        c->max_body = u;
    } else if (!strcmp(name, "max-inflight-bytes")) {
        if (parse_u64(v, 1024, (uint64_t)1 << 40, &u))
            return bad(err, errlen, "--max-inflight-bytes (1024..2^40)", v);
        c->max_inflight = u;
    } else if (!strcmp(name, "max-connections")) {
        if (parse_u64(v, 1, 100000, &u))
            return bad(err, errlen, "--max-connections (1..100000)", v);
        c->max_connections = (unsigned)u;
    } else if (!strcmp(name, "max-per-ip")) {
        if (parse_u64(v, 0, 100000, &u)) return bad(err, errlen, "--max-per-ip (0..100000)", v);
        c->max_per_ip = (unsigned)u;
    } else if (!strcmp(name, "header-timeout")) {
        if (parse_secs(v, 0.1, 3600, &c->header_timeout))
            return bad(err, errlen, "--header-timeout (0.1..3600)", v);
    } else if (!strcmp(name, "body-timeout")) {
        if (parse_secs(v, 0.1, 86400, &c->body_timeout))
            return bad(err, errlen, "--body-timeout (0.1..86400)", v);
    } else if (!strcmp(name, "idle-timeout")) {
        if (parse_u64(v, 1, 86400, &u)) return bad(err, errlen, "--idle-timeout (1..86400)", v);
        c->idle_timeout = (unsigned)u;
    } else if (!strcmp(name, "max-wait")) {
        if (parse_secs(v, 0, 3600, &c->max_wait))
            return bad(err, errlen, "--max-wait (0..3600)", v);
    } else if (!strcmp(name, "cache-bytes")) {
        if (parse_u64(v, 0, UINT64_MAX, &u)) return bad(err, errlen, "--cache-bytes", v);
        c->cache_bytes = u;
    } else if (!strcmp(name, "drain-timeout")) {
        if (parse_secs(v, 0, 86400, &c->drain_timeout))
            return bad(err, errlen, "--drain-timeout (0..86400)", v);
    } else if (!strcmp(name, "job-ttl")) {
        if (parse_secs(v, 1, 3.2e9, &c->job_ttl))
            return bad(err, errlen, "--job-ttl (1..3200000000)", v);
    } else if (!strcmp(name, "max-jobs")) {
        if (parse_u64(v, 1, 1000000000, &u))
            return bad(err, errlen, "--max-jobs (1..1000000000)", v);
        c->max_jobs = (size_t)u;
    } else if (!strcmp(name, "log-level")) {
        if ((c->log_level = log_level_parse(v)) < 0)
            return bad(err, errlen, "--log-level (debug, info, warn, error)", v);
    } else {
        snprintf(err, errlen, "unknown option --%s (cellard --help)", name);
        return -1;
    }
    return 0;
}

static const char *names[] = {"listen",
                              "db",
                              "spool",
                              "workers",
                              "job-threads",
                              "queue",
                              "max-body",
                              "max-wait",
                              "cache-bytes",
                              "drain-timeout",
                              "job-ttl",
                              "max-jobs",
                              "max-inflight-bytes",
                              "max-connections",
                              "max-per-ip",
                              "header-timeout",
                              "body-timeout",
                              "idle-timeout",
                              "log-level",
                              "name",
                              "lease-seconds",
                              "intake-threads",
                              "cors-origins",
                              "base-path"};

int config_load(config *c, int argc, char **argv, char *err, size_t errlen)
{
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    if (ncpu < 1) ncpu = 1;
    if (ncpu > 64) ncpu = 64;
    memset(c, 0, sizeof *c);
    strcpy(c->host, "127.0.0.1");
    c->port = 8080;
    strcpy(c->db, "./cellar.db");
    c->workers = (int)ncpu;
    c->job_threads = (int)ncpu;
    c->intake_threads = (int)ncpu;
    c->queue = 64;
    c->max_body = 64u << 20;
    c->max_inflight = 256u << 20;
    c->max_wait = 55;
    c->max_connections = 1000;
    c->max_per_ip = 64;
    c->header_timeout = 10;
    c->body_timeout = 120;
    c->idle_timeout = 120;
    c->cache_bytes = 1u << 30;
    c->drain_timeout = 30;
    c->job_ttl = 7 * 86400;
    c->max_jobs = 100000;
    c->log_level = LOG_INFO;
    c->lease = 30;
    char host[48] = "cellard";
    gethostname(host, sizeof host - 1);
    host[sizeof host - 1] = 0;
    snprintf(c->name, sizeof c->name, "%s-%ld", host, (long)getpid());
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        char var[64] = "CELLAR_";
        size_t k = 7;
        for (const char *p = names[i]; *p && k < sizeof var - 1; p++)
            var[k++] = *p == '-' ? '_' : (char)(*p - 'a' + 'A');
        var[k] = 0;
        const char *v = getenv(var);
        if (v && *v && set(c, names[i], v, err, errlen)) {
            char tmp[300];
            snprintf(tmp, sizeof tmp, "%s (from %s)", err, var);
            snprintf(err, errlen, "%s", tmp);
            return -1;
        }
    }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            fputs(config_usage, stdout);
            return 1;
        }
        if (!strcmp(a, "--init")) {
            c->init = 1;
            continue;
        }
        if (!strcmp(a, "--healthcheck")) {
            c->healthcheck = 1;
            continue;
        }
        if (strncmp(a, "--", 2) != 0) {
            snprintf(err, errlen, "unexpected argument \"%s\" (cellard --help)", a);
            return -1;
        }
        const char *eq = strchr(a, '=');
        char name[64];
        const char *v;
        if (eq) {
            snprintf(name, sizeof name, "%.*s", (int)(eq - a - 2), a + 2);
            v = eq + 1;
        } else {
            snprintf(name, sizeof name, "%s", a + 2);
            if (i + 1 >= argc) {
                snprintf(err, errlen, "--%s needs a value", name);
                return -1;
            }
            v = argv[++i];
        }
        if (set(c, name, v, err, errlen)) return -1;
    }
    if (c->max_inflight <= c->max_body) {
        snprintf(err, errlen,
                 "--max-inflight-bytes (%llu) must be more than --max-body (%llu): else a body "
                 "of the largest size could never be read",
                 (unsigned long long)c->max_inflight, (unsigned long long)c->max_body);
        return -1;
    }
    int uri = !strncmp(c->db, "postgresql://", 13) || !strncmp(c->db, "postgres://", 11);
    if (!c->spool[0] && !uri) { /* the directory of the database file */
        const char *slash = strrchr(c->db, '/');
        if (!slash)
            strcpy(c->spool, ".");
        else if (slash == c->db)
            strcpy(c->spool, "/");
        else
            snprintf(c->spool, sizeof c->spool, "%.*s", (int)(slash - c->db), c->db);
    }
    return 0;
}
