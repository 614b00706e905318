/* pg.h — a private PostgreSQL server for the tests: Debian's postgresql (initdb, pg_ctl from
 * /usr/lib/postgresql/N/bin), started once per test process in a temporary directory, on a port
 * of its own and a socket in that directory, as a user that is not root (the postgres user of
 * the Debian package when the tests run as root), with trust authentication on 127.0.0.1 only.
 * It is stopped and its directory removed at exit.
 *
 * CELLAR_SKIP_PG=1 makes pg_available() say no (the tests that need it then report skips);
 * without it, a missing PostgreSQL is a failure with a message saying what to install. */
#ifndef CELLAR_TESTS_PG_H
#define CELLAR_TESTS_PG_H

#include <stddef.h>

/* 1 when the server runs (started on the first call), 0 when CELLAR_SKIP_PG=1 asks to skip,
 * -1 when it could not be started (why: printed). */
int pg_available(void);

/* A new empty database on the server: its postgresql:// URI in uri (cap bytes); 0, or -1. */
int pg_new_db(char *uri, size_t cap);

/* The server's port (for tests that stop and start it). */
int pg_port(void);

/* Stops the server (fast shutdown: connections are cut) / starts it again on the same port and
 * directory.  0, or -1. */
int pg_stop(void);
int pg_start(void);

#endif
