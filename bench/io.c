/* io.c — how fast requests are read and results written (issue 27: "requests and results that
 * move at disk speed"), beside jansson on the same bytes.
 *
 * Usage: io REQUEST.json ...   (bench/io.sh makes the requests and runs it)
 *
 * For each request, the best of REPEAT runs of:
 *   read    api_run_json_ex from its call to the first progress report of the core: the request
 *           parsed and checked (the fast reader of api/packed.c for the big arrays, jansson for
 *           the rest), MB of request per second;
 *   intake  api_check_request with the canonical form: what the daemon does to a POST before it
 *           queues the job, MB/s;
 *   write   from the first report of the stage "output" to the return, the result streamed to
 *           /dev/null (as the CLI and the daemon's spool stream it): MB of result per second;
 *   jansson json_loadb of the request (read) and json_dumps of the result's tree (write, its
 *           compact form, MB of its own text per second): the library a C program would
 *           otherwise use.
 * Each measure's REPEAT runs follow one another (the daemon's intake is a loop over requests).
 * One line per request: sizes, and each figure in MB/s (1 MB = 10^6 bytes); the read figures
 * only for requests of 1 MB or more (a smaller one is read in fixed costs). */
#include "api/api.h"

#include <jansson.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define REPEAT   3
#define MIN_READ 1000000 /* bytes of request below which read figures are not printed */

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct marks {
    double first;  /* the first progress report */
    double output; /* the first report of "output" */
} marks;

static void progress(void *udata, const char *stage, double fraction)
{
    (void)fraction;
    marks *m = udata;
    double t = now();
    if (!m->first) m->first = t;
    if (!m->output && !strcmp(stage, "output")) m->output = t;
}

static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    rewind(f);
    char *p = n >= 0 ? malloc((size_t)n + 1) : NULL;
    if (p && fread(p, 1, (size_t)n, f) != (size_t)n) {
        free(p);
        p = NULL;
    }
    fclose(f);
    if (p) {
        p[n] = 0;
        *len = (size_t)n;
    }
    return p;
}

static double mbs(size_t bytes, double s)
{
    return s > 0 ? (double)bytes / s / 1e6 : 0;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: io REQUEST.json ...\n");
        return 2;
    }
    int status = 0;
    printf("%-26s %9s %9s %9s %9s %9s %9s %9s\n", "request", "req MB", "res MB", "read", "intake",
           "write", "jansson r", "jansson w");
    for (int a = 1; a < argc; a++) {
        size_t len = 0, outlen = 0;
        char *body = slurp(argv[a], &len);
        const char *name = strrchr(argv[a], '/') ? strrchr(argv[a], '/') + 1 : argv[a];
        if (!body) {
            fprintf(stderr, "io: cannot read %s\n", argv[a]);
            status = 1;
            continue;
        }
        double read = 1e9, write = 1e9, intake = 1e9, jr = 1e9, jw = 1e9;
        size_t reslen = 0, jwlen = 0;
        int ok = 1;
        for (int r = 0; r < REPEAT && ok; r++) {
            FILE *null = fopen("/dev/null", "wb");
            marks m = {0, 0};
            api_run_opts ro = {.threads = 0, .progress = progress, .udata = &m, .stream = null};
            char *out = NULL;
            api_error err;
            double t0 = now();
            int rc = api_run_json_ex(body, len, &ro, &out, &outlen, &err);
            double t1 = now();
            fclose(null);
            if (rc != API_OK || !m.first || !m.output) {
                fprintf(stderr, "io: %s: %d %s\n", name, rc, err.msg);
                ok = 0;
                break;
            }
            reslen = outlen;
            if (m.first - t0 < read) read = m.first - t0;
            if (t1 - m.output < write) write = t1 - m.output;
        }
        for (int r = 0; r < REPEAT && ok; r++) { /* each measure's runs together: warm */
            char *canon = NULL;
            size_t cl = 0;
            api_error err;
            double t0 = now();
            int rc = api_check_request(body, len, &canon, &cl, NULL, &err);
            double t1 = now();
            free(canon);
            if (rc != API_OK) ok = 0;
            if (t1 - t0 < intake) intake = t1 - t0;
        }
        for (int r = 0; r < REPEAT && ok; r++) {
            json_error_t je;
            double t0 = now();
            json_t *req = json_loadb(body, len, 0, &je);
            double t1 = now();
            json_decref(req);
            if (t1 - t0 < jr) jr = t1 - t0;
        }
        if (ok) { /* jansson writing the result's tree */
            char *out = NULL;
            api_error err;
            if (api_run_json(body, len, 0, &out, &outlen, &err) == API_OK) {
                json_error_t je;
                json_t *res = json_loadb(out, outlen, 0, &je);
                for (int r = 0; res && r < REPEAT; r++) {
                    double t0 = now();
                    char *d = json_dumps(res, JSON_COMPACT);
                    double t1 = now();
                    if (d && t1 - t0 < jw) {
                        jw = t1 - t0;
                        jwlen = strlen(d);
                    }
                    free(d);
                }
                json_decref(res);
            }
            free(out);
        }
        if (!ok) {
            printf("%-26s failed\n", name);
            status = 1;
        } else {
            char rd[16] = "-", in[16] = "-", jrs[16] = "-";
            if (len >= MIN_READ) { /* a smaller request is read in fixed costs, not bytes */
                snprintf(rd, sizeof rd, "%.0f", mbs(len, read));
                snprintf(in, sizeof in, "%.0f", mbs(len, intake));
                snprintf(jrs, sizeof jrs, "%.0f", mbs(len, jr));
            }
            printf("%-26s %9.1f %9.1f %9s %9s %9.0f %9s %9.0f\n", name, (double)len / 1e6,
                   (double)reslen / 1e6, rd, in, mbs(reslen, write), jrs, mbs(jwlen, jw));
        }
        free(body);
    }
    return status;
}
