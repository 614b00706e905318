/* metrics.c — see metrics.h.  Counters are plain atomics in fixed tables: a status is counted
 * in the slot of its code (100..599), so a scrape walks ROUTE_COUNT * 500 slots. */
#include "server/metrics.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double buckets[] = {0.001, 0.005, 0.01, 0.05, 0.1, 0.5, 1, 5, 10, 30, 60, 300};
#define NBUCKETS (sizeof buckets / sizeof *buckets)
static const char *end_states[] = {"done", "failed", "canceled"};
#define NSTATES 3

struct metrics {
    atomic_uint_fast64_t http[ROUTE_COUNT][500]; /* [route][status - 100] */
    atomic_uint_fast64_t job_bucket[NBUCKETS + 1];
    atomic_uint_fast64_t job_count;
    atomic_uint_fast64_t job_sum_us; /* microseconds */
    atomic_uint_fast64_t jobs_end[NSTATES];
    atomic_uint_fast64_t accepted, started, coalesced, hits, misses;
};

static const char *route_names[ROUTE_COUNT] = {"other",      "index",   "healthz", "readyz",
                                               "metrics",    "openapi", "jobs",    "job",
                                               "job_result", "result"};

const char *metrics_route_name(metrics_route r)
{
    return r < ROUTE_COUNT ? route_names[r] : "other";
}

metrics *metrics_new(void)
{
    return calloc(1, sizeof(metrics));
}

void metrics_free(metrics *m)
{
    free(m);
}

void metrics_request(metrics *m, metrics_route r, unsigned status)
{
    if (r >= ROUTE_COUNT) r = ROUTE_OTHER;
    if (status < 100 || status > 599) return;
    atomic_fetch_add(&m->http[r][status - 100], 1);
}

void metrics_job_end(metrics *m, const char *state, double seconds)
{
    for (int s = 0; s < NSTATES; s++)
        if (strcmp(state, end_states[s]) == 0) atomic_fetch_add(&m->jobs_end[s], 1);
    size_t b = 0;
    while (b < NBUCKETS && seconds > buckets[b]) b++;
    atomic_fetch_add(&m->job_bucket[b], 1);
    atomic_fetch_add(&m->job_count, 1);
    atomic_fetch_add(&m->job_sum_us, (uint64_t)(seconds * 1e6));
}

void metrics_job_accepted(metrics *m)
{
    atomic_fetch_add(&m->accepted, 1);
}
void metrics_job_started(metrics *m)
{
    atomic_fetch_add(&m->started, 1);
}
void metrics_coalesced(metrics *m)
{
    atomic_fetch_add(&m->coalesced, 1);
}
void metrics_cache(metrics *m, int hit)
{
    atomic_fetch_add(hit ? &m->hits : &m->misses, 1);
}

char *metrics_render(metrics *m, const metrics_gauges *g, size_t *len)
{
    char *buf = NULL;
    size_t n = 0;
    FILE *f = open_memstream(&buf, &n);
    if (!f) return NULL;
    fprintf(f, "# HELP cellar_http_requests_total HTTP requests answered, by route and status.\n"
               "# TYPE cellar_http_requests_total counter\n");
    for (int r = 0; r < ROUTE_COUNT; r++)
        for (int s = 0; s < 500; s++) {
            uint64_t v = atomic_load(&m->http[r][s]);
            if (v)
                fprintf(f, "cellar_http_requests_total{route=\"%s\",status=\"%d\"} %llu\n",
                        route_names[r], s + 100, (unsigned long long)v);
        }
    fprintf(f, "# HELP cellar_job_duration_seconds Time jobs spent running.\n"
               "# TYPE cellar_job_duration_seconds histogram\n");
    uint64_t cum = 0;
    for (size_t b = 0; b <= NBUCKETS; b++) {
        cum += atomic_load(&m->job_bucket[b]);
        if (b < NBUCKETS)
            fprintf(f, "cellar_job_duration_seconds_bucket{le=\"%g\"} %llu\n", buckets[b],
                    (unsigned long long)cum);
        else
            fprintf(f, "cellar_job_duration_seconds_bucket{le=\"+Inf\"} %llu\n",
                    (unsigned long long)cum);
    }
    fprintf(f, "cellar_job_duration_seconds_sum %.6f\n", (double)atomic_load(&m->job_sum_us) / 1e6);
    fprintf(f, "cellar_job_duration_seconds_count %llu\n",
            (unsigned long long)atomic_load(&m->job_count));
    fprintf(f, "# HELP cellar_jobs_total Jobs accepted here, jobs started here (claimed from the "
               "queue, which every daemon sharing the store takes from), and jobs ended here by "
               "final state.\n"
               "# TYPE cellar_jobs_total counter\n");
    fprintf(f, "cellar_jobs_total{state=\"accepted\"} %llu\n",
            (unsigned long long)atomic_load(&m->accepted));
    fprintf(f, "cellar_jobs_total{state=\"started\"} %llu\n",
            (unsigned long long)atomic_load(&m->started));
    for (int s = 0; s < NSTATES; s++)
        fprintf(f, "cellar_jobs_total{state=\"%s\"} %llu\n", end_states[s],
                (unsigned long long)atomic_load(&m->jobs_end[s]));
    fprintf(f,
            "# HELP cellar_jobs_coalesced_total Requests that joined an identical job in "
            "flight.\n# TYPE cellar_jobs_coalesced_total counter\n"
            "cellar_jobs_coalesced_total %llu\n",
            (unsigned long long)atomic_load(&m->coalesced));
    fprintf(f,
            "# HELP cellar_cache_hits_total Job requests answered from the result cache.\n"
            "# TYPE cellar_cache_hits_total counter\ncellar_cache_hits_total %llu\n",
            (unsigned long long)atomic_load(&m->hits));
    fprintf(f,
            "# HELP cellar_cache_misses_total Job requests not in the result cache.\n"
            "# TYPE cellar_cache_misses_total counter\ncellar_cache_misses_total %llu\n",
            (unsigned long long)atomic_load(&m->misses));
    if (g) {
        fprintf(f,
                "# HELP cellar_jobs Jobs in the store by state (every daemon's).\n"
                "# TYPE cellar_jobs gauge\n"
                "cellar_jobs{state=\"queued\"} %zu\ncellar_jobs{state=\"running\"} %zu\n"
                "# HELP cellar_jobs_running_here Jobs this daemon runs now.\n"
                "# TYPE cellar_jobs_running_here gauge\ncellar_jobs_running_here %zu\n",
                g->queued, g->running, g->running_here);
        fprintf(f,
                "# HELP cellar_queue_depth Jobs waiting for a worker.\n"
                "# TYPE cellar_queue_depth gauge\ncellar_queue_depth %zu\n"
                "# HELP cellar_queue_capacity Jobs the queue accepts.\n"
                "# TYPE cellar_queue_capacity gauge\ncellar_queue_capacity %zu\n",
                g->queued, g->queue_capacity);
        fprintf(f,
                "# HELP cellar_cache_results Results in the cache.\n"
                "# TYPE cellar_cache_results gauge\ncellar_cache_results %zu\n"
                "# HELP cellar_cache_bytes Bytes of results in the cache.\n"
                "# TYPE cellar_cache_bytes gauge\ncellar_cache_bytes %llu\n"
                "# HELP cellar_cache_budget_bytes The cache's size budget (0: none).\n"
                "# TYPE cellar_cache_budget_bytes gauge\ncellar_cache_budget_bytes %llu\n",
                g->cache_results, (unsigned long long)g->cache_bytes,
                (unsigned long long)g->cache_budget);
        fprintf(f,
                "# HELP cellar_draining 1 while the daemon drains before exit.\n"
                "# TYPE cellar_draining gauge\ncellar_draining %d\n",
                g->draining);
        fprintf(f,
                "# HELP cellar_checked_requests_kept Requests kept in their checked form for "
                "jobs queued here and not yet claimed (at most 64).\n"
                "# TYPE cellar_checked_requests_kept gauge\ncellar_checked_requests_kept %zu\n"
                "# HELP cellar_checked_request_bytes_kept Their requests' bytes (at most 256 "
                "MiB).\n"
                "# TYPE cellar_checked_request_bytes_kept gauge\n"
                "cellar_checked_request_bytes_kept %llu\n",
                g->checked_kept, (unsigned long long)g->checked_bytes);
    }
    if (fclose(f) != 0) {
        free(buf);
        return NULL;
    }
    if (len) *len = n;
    return buf;
}
