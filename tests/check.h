/* check.h — the test framework: small C programs, one file per area (tests/test_*.c).
 *
 * A test is a function registered with TEST(name); CHECK(cond, fmt, ...) records a failure
 * with file:function:line and a message, and lets the test go on; REQUIRE() also returns.
 * main() comes from testlib.c: it runs every test (or those named on the command line) and
 * prints one line per test ("ok NAME" / "FAIL NAME") and a last line "N passed, N failed"
 * that tests/run.sh adds up.
 */
#ifndef CELLAR_CHECK_H
#define CELLAR_CHECK_H

#include <stdint.h>
#include <stdio.h>

typedef void (*test_fn)(void);
void test_register(const char *name, test_fn fn);
void test_fail(const char *file, const char *func, int line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
int test_failed_now(void); /* non-zero once the running test has a failure */
/* Marks the running test skipped (counted apart, "N skipped"), when nothing failed in it; only
 * where a variable asks for the skip (CELLAR_SKIP_*), never silently. */
void test_skip(const char *why);

#define TEST(name)                                                                                 \
    static void name(void);                                                                        \
    __attribute__((constructor)) static void name##_register(void)                                 \
    {                                                                                              \
        test_register(#name, name);                                                                \
    }                                                                                              \
    static void name(void)

#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) test_fail(__FILE__, __func__, __LINE__, __VA_ARGS__);                         \
    } while (0)

#define REQUIRE(cond, ...)                                                                         \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            test_fail(__FILE__, __func__, __LINE__, __VA_ARGS__);                                  \
            return;                                                                                \
        }                                                                                          \
    } while (0)

/* How much longer than on a quiet machine things take here and now: a reference work measured
 * once per process (tests/daemon.c), at least 3 under the sanitizers.  Every time bound of the
 * suite is a multiple of it, never a fixed number of seconds. */
double slowdown(void);

/* The test data (tests/data, relative to the repository's top, where tests/run.sh runs). */
const char *test_data_dir(void);
/* Reads a whole file into a NUL-terminated buffer the caller frees; NULL on error. */
char *test_read_file(const char *path, size_t *len);

/* The tests' reproducible random numbers (splitmix64), in [0, 1). */
double test_rnd(uint64_t *state);
/* n cases, times CELLAR_STRESS when that is a positive number (make stress). */
size_t test_stress(size_t n);
/* n random segments made like the seeds' randomLines(n, scaling), without the final shift:
 * malloc'd, 4 doubles each, the caller frees. */
double *test_random_lines(size_t n, double scaling, uint64_t seed);

#endif
