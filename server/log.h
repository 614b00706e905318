/* log.h — structured logs: one JSON object a line on stderr, e.g.
 *   {"ts":"2026-11-22T06:00:00.123Z","level":"info","msg":"request","method":"GET",...}
 * Lines are written whole under a mutex, so threads never interleave.  No allocation on the
 * caller's side; strings are escaped by jansson. */
#ifndef CELLAR_LOG_H
#define CELLAR_LOG_H

enum { LOG_DEBUG = 0, LOG_INFO = 1, LOG_WARN = 2, LOG_ERROR = 3 };

/* Sets the least level written (default LOG_INFO). */
void log_set_level(int level);
/* Parses "debug", "info", "warn", "error"; returns -1 for anything else. */
int log_level_parse(const char *s);

/* Writes {"ts","level","msg", and the extra fields}: fields come in pairs (key, value) ended
 * by a NULL key; a NULL value leaves its field out; a value made by log_num() is written as a
 * number (an integer when it is one). */
void log_kv(int level, const char *msg, ...) __attribute__((sentinel));

/* A number for log_kv (3 decimals at most): formats v into buf (at least 32 bytes). */
const char *log_num(char *buf, double v);

#endif
