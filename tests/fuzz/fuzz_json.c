/* fuzz_json.c — libFuzzer target: a request body through api/ (every kind: lines, svg,
 * polygons, solids), as the daemon takes it: api_check_request() first (parse, validate,
 * canonicalise), then, for a valid request, api_run_json() with one thread, and the picture
 * and map renderers on the result.
 *
 * Checks beyond the sanitizers: every answer keeps the contract of api/api.h (fuzz.h); the
 * canonical form of a valid request is valid too and canonical again (the result cache hashes
 * it: two forms of one request must not become two keys); a valid request does not fail
 * with 400 (malformed JSON) when run; a result is renderable or refused, never 500.
 *
 * Work is bounded by the input: bodies over FUZZ_JSON_MAX bytes are refused (a few hundred
 * segments or faces at most), so each run stays in milliseconds.
 */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* memmem, strnlen, strncasecmp (the Makefile defines it too) */
#endif
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "api/api.h"
#include "api/render.h"
#include "tests/fuzz/fuzz.h"

#define FUZZ_JSON_MAX 4096

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A result through the renderers: any status but 500, the contract kept. */
static void render_result(const char *res, size_t len)
{
    render_opts o = RENDER_OPTS_INIT;
    char *out = NULL;
    size_t outlen = 0;
    api_error err = {0};
    int rc;
    if (strncmp(res, "{\"dim\":3", 8) == 0) {
        rc = render_obj(res, len, &o, &out, &outlen, &err);
        fuzz_check_answer("render_obj", rc, out, outlen, &err, 0);
        free(out);
        return;
    }
    rc = render_svg(res, len, &o, &out, &outlen, &err);
    fuzz_check_answer("render_svg", rc, out, outlen, &err, 1);
    free(out);
    out = NULL;
    err = (api_error){0};
    o.cells = 1;
    rc = render_geojson(res, len, &o, &out, &outlen, &err);
    fuzz_check_answer("render_geojson", rc, out, outlen, &err, 1);
    free(out);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *body = (const char *)data;
    char *canon = NULL, *canon2 = NULL, *out = NULL;
    size_t canonlen = 0, canonlen2 = 0, outlen = 0;
    const char *kind = NULL;
    api_error err = {0};
    int rc;
    if (size > FUZZ_JSON_MAX) return -1; /* not added to the corpus */

    rc = api_check_request(body, size, &canon, &canonlen, &kind, &err);
    fuzz_check_answer("api_check_request", rc, canon, canonlen, &err, 0);
    if (rc != API_OK) {
        FUZZ_CHECK(kind == NULL, "a kind for a refused request");
        return 0;
    }
    FUZZ_CHECK(kind != NULL, "no kind for a valid request");
    FUZZ_CHECK(memchr(canon, '\n', canonlen) == NULL, "a canonical request on two lines");

    /* the canonical form is a valid request of the same kind, and its own canonical form */
    const char *kind2 = NULL;
    err = (api_error){0};
    rc = api_check_request(canon, canonlen, &canon2, &canonlen2, &kind2, &err);
    FUZZ_CHECK(rc == API_OK, "the canonical form is refused: %d %s\n%s", rc, err.msg, canon);
    FUZZ_CHECK(strcmp(kind, kind2) == 0, "kind %s, canonical form's %s", kind, kind2);
    FUZZ_CHECK(canonlen == canonlen2 && memcmp(canon, canon2, canonlen) == 0,
               "canonical form not canonical:\n%s\n%s", canon, canon2);
    free(canon);
    free(canon2);

    err = (api_error){0};
    rc = api_run_json(body, size, 1, &out, &outlen, &err);
    fuzz_check_answer("api_run_json", rc, out, outlen, &err, 1);
    FUZZ_CHECK(rc != API_EJSON, "a valid request fails to parse when run: %s", err.msg);
    if (rc == API_OK) render_result(out, outlen);
    free(out);
    return 0;
}
