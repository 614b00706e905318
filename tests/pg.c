/* pg.c — see pg.h. */
#include "tests/pg.h"

#include <arpa/inet.h>
#include <glob.h>
#include <libpq-fe.h>
#include <netinet/in.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

static struct {
    int state; /* 0 not tried, 1 running, -1 failed, 2 skipped */
    char dir[128], bin[256], as[64];
    int port, ndb;
} pg;

static int pg_free_port(void)
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

/* Runs a command line as the server's user; its exit status. */
static int as_user(const char *cmd)
{
    char line[2048];
    snprintf(line, sizeof line, "%s%s >>'%s/pg.log' 2>&1", pg.as, cmd, pg.dir);
    return system(line);
}

int pg_start(void)
{
    char cmd[1024];
    snprintf(cmd, sizeof cmd,
             "'%s/pg_ctl' -D '%s/data' -l '%s/server.log' -w -t 60 -o \"-k '%s' -p %d "
             "-h 127.0.0.1 -c fsync=off -c synchronous_commit=off -c full_page_writes=off "
             "-c max_connections=400\" start",
             pg.bin, pg.dir, pg.dir, pg.dir, pg.port);
    return as_user(cmd) == 0 ? 0 : -1;
}

int pg_stop(void)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "'%s/pg_ctl' -D '%s/data' -m fast -w -t 60 stop", pg.bin, pg.dir);
    return as_user(cmd) == 0 ? 0 : -1;
}

int pg_port(void)
{
    return pg.port;
}

static void pg_cleanup(void)
{
    if (pg.state != 1) return;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "'%s/pg_ctl' -D '%s/data' -m immediate -w stop", pg.bin, pg.dir);
    as_user(cmd);
    if (!getenv("CELLAR_TEST_KEEP") || !*getenv("CELLAR_TEST_KEEP")) {
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", pg.dir);
        if (system(cmd) != 0) fprintf(stderr, "pg: could not remove %s\n", pg.dir);
    }
    pg.state = 0;
}

static int fail(const char *why)
{
    printf("  PostgreSQL for the tests: %s\n", why);
    if (pg.dir[0]) {
        char cmd[400];
        snprintf(cmd, sizeof cmd, "tail -n 20 '%s/pg.log' '%s/server.log' 2>/dev/null", pg.dir,
                 pg.dir);
        if (system(cmd) != 0) printf("  (no log)\n");
    }
    fflush(stdout);
    pg.state = -1;
    return -1;
}

int pg_available(void)
{
    if (pg.state) return pg.state == 2 ? 0 : pg.state;
    const char *skip = getenv("CELLAR_SKIP_PG");
    if (skip && !strcmp(skip, "1")) {
        pg.state = 2;
        return 0;
    }
    glob_t g;
    if (glob("/usr/lib/postgresql/*/bin/initdb", 0, NULL, &g) != 0 || g.gl_pathc == 0)
        return fail("no initdb under /usr/lib/postgresql/*/bin (apt-get install postgresql; "
                    "make deps does; CELLAR_SKIP_PG=1 skips these tests)");
    snprintf(pg.bin, sizeof pg.bin, "%s", g.gl_pathv[g.gl_pathc - 1]);
    globfree(&g);
    *strrchr(pg.bin, '/') = 0;
    snprintf(pg.dir, sizeof pg.dir, "/tmp/cellar-test-pg-XXXXXX");
    if (!mkdtemp(pg.dir)) {
        pg.dir[0] = 0;
        return fail("mkdtemp failed");
    }
    pg.as[0] = 0;
    if (geteuid() == 0) { /* initdb refuses root: the package's postgres user runs it */
        struct passwd *pw = getpwnam("postgres");
        if (!pw) return fail("running as root, and there is no postgres user to run it as");
        if (chown(pg.dir, pw->pw_uid, pw->pw_gid) != 0) return fail("chown of its directory");
        snprintf(pg.as, sizeof pg.as, "runuser -u postgres -- ");
    }
    chmod(pg.dir, 0700);
    char cmd[1024];
    snprintf(cmd, sizeof cmd,
             "'%s/initdb' -D '%s/data' --auth=trust -U postgres -E UTF8 --no-sync --no-locale",
             pg.bin, pg.dir);
    if (as_user(cmd) != 0) return fail("initdb failed");
    atexit(pg_cleanup);
    pg.state = 1; /* for the cleanup */
    for (int attempt = 0; attempt < 3; attempt++) {
        pg.port = pg_free_port();
        if (pg.port > 0 && pg_start() == 0) return 1;
    }
    return fail("pg_ctl start failed");
}

int pg_new_db(char *uri, size_t cap)
{
    if (pg_available() != 1) return -1;
    char conn[200], sql[100], name[64];
    snprintf(name, sizeof name, "cellar_%ld_%d", (long)getpid(), ++pg.ndb);
    snprintf(conn, sizeof conn, "host=127.0.0.1 port=%d user=postgres dbname=postgres", pg.port);
    PGconn *c = PQconnectdb(conn);
    int ok = c && PQstatus(c) == CONNECTION_OK;
    if (ok) {
        snprintf(sql, sizeof sql, "CREATE DATABASE %s", name);
        PGresult *r = PQexec(c, sql);
        ok = r && PQresultStatus(r) == PGRES_COMMAND_OK;
        if (!ok) printf("  pg: %s: %s", sql, PQerrorMessage(c));
        PQclear(r);
    } else {
        printf("  pg: connect: %s", c ? PQerrorMessage(c) : "out of memory\n");
    }
    PQfinish(c);
    if (!ok) return -1;
    snprintf(uri, cap, "postgresql://postgres@127.0.0.1:%d/%s", pg.port, name);
    return 0;
}
