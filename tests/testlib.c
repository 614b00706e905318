/* testlib.c — main() and bookkeeping for the test programs (see check.h). */
#include "tests/check.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_TESTS 512

static struct {
    const char *name;
    test_fn fn;
} tests[MAX_TESTS];
static int ntests;
static int cur_failures;
static const char *cur_skip; /* why the running test was skipped, or NULL */

void test_register(const char *name, test_fn fn)
{
    if (ntests < MAX_TESTS) {
        tests[ntests].name = name;
        tests[ntests].fn = fn;
        ntests++;
    }
}

void test_fail(const char *file, const char *func, int line, const char *fmt, ...)
{
    va_list ap;
    cur_failures++;
    if (cur_failures > 20) return; /* keep the log readable */
    fprintf(stdout, "  %s:%s:%d: ", file, func, line);
    va_start(ap, fmt);
    vfprintf(stdout, fmt, ap);
    va_end(ap);
    fputc('\n', stdout);
}

void test_skip(const char *why)
{
    cur_skip = why;
}

int test_failed_now(void)
{
    return cur_failures != 0;
}

const char *test_data_dir(void)
{
    return "tests/data"; /* tests/run.sh runs every test from the repository's top */
}

char *test_read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) != 0 || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) goto out;
    buf = malloc((size_t)n + 1);
    if (!buf) goto out;
    if (fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
        goto out;
    }
    buf[n] = 0;
    if (len) *len = (size_t)n;
out:
    fclose(f);
    return buf;
}

size_t test_stress(size_t n)
{
    const char *e = getenv("CELLAR_STRESS");
    return e && atoi(e) > 0 ? n * (size_t)atoi(e) : n;
}

double test_rnd(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    z ^= z >> 31;
    return (double)(z >> 11) / 9007199254740992.0;
}

double *test_random_lines(size_t n, double scaling, uint64_t seed)
{
    double *s = malloc((n ? n : 1) * 4 * sizeof *s);
    if (!s) return NULL;
    for (size_t i = 0; i < n; i++) {
        double x1 = test_rnd(&seed), y1 = test_rnd(&seed), x2 = test_rnd(&seed);
        double y2 = test_rnd(&seed), px = test_rnd(&seed), py = test_rnd(&seed);
        double cx = (x1 + x2) / 2, cy = (y1 + y2) / 2;
        s[4 * i] = (x1 - cx) * scaling + px;
        s[4 * i + 1] = (y1 - cy) * scaling + py;
        s[4 * i + 2] = (x2 - cx) * scaling + px;
        s[4 * i + 3] = (y2 - cy) * scaling + py;
    }
    return s;
}

int main(int argc, char **argv)
{
    int passed = 0, failed = 0, skipped = 0;
    for (int i = 0; i < ntests; i++) {
        if (argc > 1) {
            int want = 0;
            for (int a = 1; a < argc; a++) want |= strcmp(argv[a], tests[i].name) == 0;
            if (!want) continue;
        }
        cur_failures = 0;
        cur_skip = NULL;
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        tests[i].fn();
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double secs = (double)(t1.tv_sec - t0.tv_sec) + (double)(t1.tv_nsec - t0.tv_nsec) * 1e-9;
        if (cur_skip && !cur_failures) {
            printf("skip %s: %s\n", tests[i].name, cur_skip);
            skipped++;
        } else if (cur_failures) {
            printf("FAIL %s (%d failed checks, %.2f s)\n", tests[i].name, cur_failures, secs);
            failed++;
        } else {
            printf("ok %s (%.2f s)\n", tests[i].name, secs);
            passed++;
        }
        fflush(stdout);
    }
    if (skipped)
        printf("%d passed, %d failed, %d skipped\n", passed, failed, skipped);
    else
        printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
