/* api.h — the JSON layer: requests in, LAR JSON out (DESIGN.md, "LAR JSON" and "The service").
 *
 * A request is a JSON object {"kind": K, ...}.  api_run_json() parses it, dispatches on K to the
 * kind's handler (api/run.c holds the table of kinds; "lines" is in api/lines.c), calls the core
 * and serializes the result (api/larjson.c) into one line of compact JSON followed by "\n".
 * Both the daemon and the command-line tool call it, so the bytes they return are the same.
 *
 * Errors are values: every failure returns its status (an HTTP status code, see API_E*) and fills
 * the caller's api_error with a message that names where the problem is, as a JSON path
 * ("lines[17][1]: expected 2 finite numbers", "options.precision: expected a number > 0") or,
 * for malformed JSON, the line and column of the parser.  Nothing here prints or exits.
 *
 * Threads: every function is reentrant; there are no globals.  The core starts its own worker
 * threads (api_run_opts.threads) and joins them before api_run_json() returns.
 */
#ifndef CELLAR_API_H
#define CELLAR_API_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdio.h>

#define API_VERSION "0.3.0"

/* Statuses: HTTP status codes, so the daemon can send them as they are. */
enum {
    API_OK = 0,
    API_EJSON = 400,     /* the body is not JSON (or nests deeper than the parser allows) */
    API_EINVALID = 422,  /* valid JSON, invalid request: bad shape, value, option, or a limit */
    API_ECANCELED = 499, /* the run was canceled through api_run_opts.cancel; the daemon records
                            the job as canceled rather than sending this status to anyone */
    API_EINTERNAL = 500, /* a bug of ours (an invariant of the core failed) */
    API_ENOMEM = 503     /* out of memory: may succeed later or on a smaller input */
};

#define API_ERRMAX 256

typedef struct api_error {
    int status;           /* API_OK or one of API_E* */
    char msg[API_ERRMAX]; /* NUL-terminated; "" when status is API_OK */
} api_error;

typedef struct api_run_opts {
    int threads;              /* core worker threads; <= 0: number of online CPUs */
    const atomic_int *cancel; /* borrowed, may be NULL: non-zero asks the core to stop */
    /* may be NULL: told, from the running thread, the stage running now (one of
     * api_stage_name's for the kind) and the fraction of the whole run done, 0 to 1, neither of
     * which goes back; a few hundred times per run at most */
    void (*progress)(void *udata, const char *stage, double fraction);
    void *udata; /* passed to progress */
    /* may be NULL: the result is written to this stream as it is made (a megabyte at a time)
     * instead of being returned: then *out is NULL and *outlen the bytes written.  A failure
     * after some bytes were written leaves them written (the output is then incomplete). */
    FILE *stream;
} api_run_opts;

/* Runs the request body[0..len) (borrowed; need not be NUL-terminated) with `threads` worker
 * threads.  On success returns API_OK and sets *out to a malloc'd, NUL-terminated buffer of
 * *outlen bytes (the result JSON and a final "\n") that the caller frees with free().
 * On failure returns the status, fills *err (may be NULL) and sets *out = NULL, *outlen = 0. */
int api_run_json(const char *body, size_t len, int threads, char **out, size_t *outlen,
                 api_error *err);

/* The stages a request of this kind reports to api_run_opts.progress, in the order they run:
 * the i-th name, NULL past the last (or for an unknown kind). */
const char *api_stage_name(const char *kind, size_t i);

/* The same with cancellation and progress (ro may be NULL: all CPUs, no cancel, no progress). */
int api_run_json_ex(const char *body, size_t len, const api_run_opts *ro, char **out,
                    size_t *outlen, api_error *err);

/* The most faces a solids request may have in all (ARR3_MAX_FACES unless set lower: process-wide
 * configuration, as the daemon's or a test's; 0 restores the default).  Beyond the count, the
 * core refuses at run an input whose memory estimate exceeds the machine's memory. */
unsigned api_solids_max_faces(void);
void api_solids_set_max_faces(unsigned n);

/* A solids request whose solids are already read (the CLI's OBJ / OFF files): the same result
 * bytes as api_run_json() on {"kind": "solids", "solids" (or "faces" when soup): s, "op": op,
 * "options": options}, without writing and parsing that JSON.  s (a malloc'd array of n
 * struct solid of core/solid.h) is taken over, array and solids: freed here, success or not; op and
 * options (jansson values, may be NULL) are borrowed.  The same limits and checks as the JSON
 * request, with its messages. */
struct solid;
struct json_t;
int api_solids_run_direct(struct solid *s, size_t n, int soup, const struct json_t *op,
                          const struct json_t *options, const api_run_opts *ro, char **out,
                          size_t *outlen, api_error *err);

/* Validates body[0..len) as api_run_json() would, without running the core: the daemon rejects
 * a bad request at once instead of queueing it.  When canon is not NULL, sets *canon to the
 * canonical form of the request (compact, keys sorted, one line, no final newline: what the
 * result cache hashes), malloc'd, caller frees with free(); *canonlen gets its length (canonlen
 * may be NULL).  On failure *canon is NULL. */
int api_check_json(const char *body, size_t len, char **canon, size_t *canonlen, api_error *err);

/* The same, and *kind_name (may be NULL) gets the request's kind ("lines", ...), a static
 * string, or NULL on failure. */
int api_check_request(const char *body, size_t len, char **canon, size_t *canonlen,
                      const char **kind_name, api_error *err);

/* A request parsed and checked by api_check_request_ex, ready to run without being read or
 * checked again (the daemon's intake hands it to the worker that runs the job). */
typedef struct api_request api_request;

/* api_check_request, and, when checked is not NULL and the request is valid, *checked gets
 * the request as parsed and checked (caller runs it with api_request_run or frees it with
 * api_request_free) -- or NULL when the canonical form would not parse to the same request
 * (a "layers" object or a feature's "properties" whose keys are not in sorted order: the
 * canonical form sorts them, and their order shows in the result).  The job then runs from
 * its canonical form, parsed and checked there, as a job from the store does. */
int api_check_request_ex(const char *body, size_t len, char **canon, size_t *canonlen,
                         const char **kind_name, api_request **checked, api_error *err);

/* Runs a checked request (taken: freed here, success or not) as api_run_json_ex runs its
 * body, with the same result bytes, without parsing or checking it again. */
int api_request_run(api_request *q, const api_run_opts *ro, char **out, size_t *outlen,
                    api_error *err);

/* Frees a checked request that will not run; safe on NULL. */
void api_request_free(api_request *q);

/* Writes the shortest of %.15g, %.16g, %.17g that reads back as x (x finite) into buf, which
 * must hold API_DOUBLE_MAX bytes; returns the length.  The format of every number we print. */
#define API_DOUBLE_MAX 32
size_t api_format_double(double x, char *buf);

/* The kinds of request this build understands ("lines", ...), for --help and the OpenAPI text:
 * api_kind_name(i) for i < api_kind_count() is a static string. */
size_t api_kind_count(void);
const char *api_kind_name(size_t i);

#endif
