/* testlib.c — main() and bookkeeping for the test programs (see check.h). */
#include "tests/check.h"

#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#define MAX_TESTS 512

static struct {
    const char *name;
    test_fn fn;
} tests[MAX_TESTS];
static int ntests;
static int cur_failures;

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

int test_failed_now(void)
{
    return cur_failures != 0;
}

const char *test_data_dir(void)
{
    const char *d = getenv("CELLAR_DATA");
    return d && *d ? d : "../shared/data";
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

int main(int argc, char **argv)
{
    int passed = 0, failed = 0;
    for (int i = 0; i < ntests; i++) {
        if (argc > 1) {
            int want = 0;
            for (int a = 1; a < argc; a++) want |= strcmp(argv[a], tests[i].name) == 0;
            if (!want) continue;
        }
        cur_failures = 0;
        tests[i].fn();
        if (cur_failures) {
            printf("FAIL %s (%d failed checks)\n", tests[i].name, cur_failures);
            failed++;
        } else {
            printf("ok %s\n", tests[i].name);
            passed++;
        }
        fflush(stdout);
    }
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
