/* metrics.h — the daemon's counters, exported in the Prometheus text format (GET /metrics):
 *   cellar_http_requests_total{route,status}   requests answered
 *   cellar_job_duration_seconds                histogram of job run times (by kind)
 *   cellar_jobs_total{state}                   jobs ended here, by final state; accepted and
 *                                              started here
 *   cellar_jobs_coalesced_total                requests that joined an identical job in flight
 *   cellar_cache_hits_total / _misses_total    result cache lookups on POST
 * plus gauges the caller supplies at scrape time (queue depth, jobs by state, cache bytes).
 * Every function is thread-safe (atomics; no lock on the request path). */
#ifndef CELLAR_METRICS_H
#define CELLAR_METRICS_H

#include <stddef.h>
#include <stdint.h>

typedef enum metrics_route {
    ROUTE_OTHER = 0,
    ROUTE_INDEX,
    ROUTE_HEALTHZ,
    ROUTE_READYZ,
    ROUTE_METRICS,
    ROUTE_OPENAPI,
    ROUTE_JOBS,       /* POST /v1/jobs */
    ROUTE_JOB,        /* /v1/jobs/{id} */
    ROUTE_JOB_RESULT, /* /v1/jobs/{id}/result */
    ROUTE_RESULT,     /* /v1/results/{hash} */
    ROUTE_COUNT
} metrics_route;

const char *metrics_route_name(metrics_route r);

typedef struct metrics metrics;

metrics *metrics_new(void); /* NULL when out of memory */
void metrics_free(metrics *m);

void metrics_request(metrics *m, metrics_route r, unsigned status);
void metrics_job_end(metrics *m, const char *state, double seconds); /* done/failed/canceled */
void metrics_job_accepted(metrics *m);
void metrics_job_started(metrics *m); /* claimed from the queue and run here */
void metrics_coalesced(metrics *m);
void metrics_cache(metrics *m, int hit);

typedef struct metrics_gauges {
    size_t queued, running; /* in the store (every daemon's) */
    size_t running_here;
    size_t queue_capacity;
    size_t cache_results;
    uint64_t cache_bytes, cache_budget;
    int draining;
    size_t checked_kept; /* requests kept checked for jobs not yet claimed here */
    uint64_t checked_bytes;
} metrics_gauges;

/* The whole exposition as a malloc'd NUL-terminated string (caller frees), or NULL. */
char *metrics_render(metrics *m, const metrics_gauges *g, size_t *len);

#endif
