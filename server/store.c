/* store.c — the backend-independent part of the store interface (server/store.h): the names
 * of job states and the release of a store_job's owned strings.  The backends live in their
 * own files (store_sqlite.c, store_pg.c); store_open() picks one by the --db value.
 *
 * Threads: reentrant, no globals.  Ownership: store_job_clear() frees the job's error and
 * request (malloc'd by a backend) and leaves the struct zeroed, so clearing twice is harmless.
 */
#include "server/store.h"

#include <stdlib.h>
#include <string.h>

const char *job_state_name(job_state s)
{
    switch (s) {
    case JOB_QUEUED:
        return "queued";
    case JOB_RUNNING:
        return "running";
    case JOB_DONE:
        return "done";
    case JOB_FAILED:
        return "failed";
    case JOB_CANCELED:
        return "canceled";
    }
    return "unknown";
}

store *store_open(const char *db, uint64_t budget_bytes, double touch_seconds, int flags, char *err,
                  size_t errlen)
{
    if (!strncmp(db, "postgresql://", 13) || !strncmp(db, "postgres://", 11))
        return store_pg_open(db, budget_bytes, touch_seconds, flags, err, errlen);
    return store_sqlite_open(db, budget_bytes, touch_seconds, flags, err, errlen);
}

void store_job_clear(store_job *j)
{
    if (!j) return;
    free(j->error);
    free(j->request);
    memset(j, 0, sizeof *j);
}
