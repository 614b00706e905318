/* log.c — see log.h. */
#include "server/log.h"

#include <jansson.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static atomic_int min_level = LOG_INFO;
static pthread_mutex_t out_lock = PTHREAD_MUTEX_INITIALIZER; /* guards writes to stderr */
static const char *names[] = {"debug", "info", "warn", "error"};

void log_set_level(int level)
{
    atomic_store(&min_level, level);
}

int log_level_parse(const char *s)
{
    for (int i = 0; i < 4; i++)
        if (strcmp(s, names[i]) == 0) return i;
    return -1;
}

const char *log_num(char *buf, double v)
{
    snprintf(buf, 32, "\x01%.3f", v);
    return buf;
}

void log_kv(int level, const char *msg, ...)
{
    if (level < atomic_load(&min_level)) return;
    struct timespec ts;
    struct tm tm;
    char when[40];
    clock_gettime(CLOCK_REALTIME, &ts);
    gmtime_r(&ts.tv_sec, &tm);
    size_t n = strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%S", &tm);
    snprintf(when + n, sizeof when - n, ".%03ldZ", ts.tv_nsec / 1000000);
    json_t *o = json_object();
    if (!o) return;
    json_object_set_new(o, "ts", json_string(when));
    json_object_set_new(o, "level", json_string(names[level & 3]));
    json_object_set_new(o, "msg", json_string(msg));
    va_list ap;
    va_start(ap, msg);
    for (;;) {
        const char *k = va_arg(ap, const char *);
        if (!k) break;
        const char *v = va_arg(ap, const char *);
        if (!v) continue; /* absent fields are left out */
        if (v[0] == '\x01') {
            double x = strtod(v + 1, NULL);
            json_object_set_new(
                o, k, x == (double)(long long)x ? json_integer((long long)x) : json_real(x));
        } else {
            json_t *sv = json_stringn(v, strlen(v)); /* NULL for invalid UTF-8 (a client's) */
            json_object_set_new(o, k, sv ? sv : json_string("(not UTF-8)"));
        }
    }
    va_end(ap);
    char *line = json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(9));
    json_decref(o);
    if (!line) return;
    pthread_mutex_lock(&out_lock);
    fputs(line, stderr);
    fputc('\n', stderr);
    fflush(stderr);
    pthread_mutex_unlock(&out_lock);
    free(line);
}
