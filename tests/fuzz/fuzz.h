/* fuzz.h — what the libFuzzer targets of tests/fuzz/ share: a check that aborts (libFuzzer then
 * keeps the input as a crash), and the checks every api/ answer must pass.
 *
 * The sanitizers (ASan, UBSan, LeakSanitizer) find the memory errors; these checks find answers
 * that break the contracts of api/api.h and api/render.h without touching bad memory: a status
 * that is not one of API_E*, an error without its message, an output whose length is not the
 * one returned or that does not end in "\n".
 */
#ifndef CELLAR_FUZZ_H
#define CELLAR_FUZZ_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api/api.h"

#define FUZZ_CHECK(cond, ...)                                                                      \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "fuzz: %s:%d: check failed: %s: ", __FILE__, __LINE__, #cond);         \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
            abort();                                                                               \
        }                                                                                          \
    } while (0)

/* Internal errors (500) of bugs found and reported but not fixed yet, told by their message:
 * tolerated, so that fuzzing goes on past them (a sanitizer's finding never is).  Add an entry
 * (a substring of the message) with a comment naming its reproducer in the corpus, and remove
 * it with its fix; the list ends with NULL.  Fixed so far, their reproducers kept in the corpus
 * (each now a 422 naming the face):
 *   - a face whose outer cycle crosses itself (a bowtie), which solid_check() took and the 3D
 *     pipeline failed on ("a part's own ray hits none of its faces"):
 *     tests/fuzz/corpus/obj/bowtie-face-refused.obj (as a request:
 *     tests/fuzz/corpus/json/bowtie-face-refused.json, over HTTP:
 *     tests/fuzz/corpus/http/post-bowtie-solid-wait.http);
 *   - a face that the grid of a far larger coordinate (1e12 among ones ~10) collapses onto two
 *     lines, its cycle running back along itself ("no point found inside input face 14"):
 *     tests/fuzz/corpus/off/grid-collapses-face-refused.off. */
static const char *const fuzz_known_bugs[] = {
    NULL,
};

/* Whether text[0..len) tells of a known bug (fuzz_known_bugs; said once on stderr). */
static inline int fuzz_known_bug(const char *text, size_t len)
{
    for (size_t i = 0; fuzz_known_bugs[i]; i++)
        if (memmem(text, len, fuzz_known_bugs[i], strlen(fuzz_known_bugs[i]))) {
            static int said;
            if (!said++)
                fprintf(stderr, "fuzz: a known bug, tolerated (fuzz.h): %s\n", fuzz_known_bugs[i]);
            return 1;
        }
    return 0;
}

/* A status api/ may return, besides API_OK.  API_EINTERNAL is "a bug of ours": a finding,
 * unless its message tells of a known bug. */
static inline int fuzz_status_ok_msg(int rc, const char *msg)
{
    if (rc == API_OK || rc == API_EJSON || rc == API_EINVALID || rc == API_ENOMEM) return 1;
    return rc == API_EINTERNAL && fuzz_known_bug(msg, strnlen(msg, API_ERRMAX));
}

/* The contract of a call that returned rc with output (out, outlen) and error err: on success
 * a malloc'd NUL-terminated output of outlen bytes (ending in "\n" when nl), on failure no
 * output and a printable message whose status is rc. */
static inline void fuzz_check_answer(const char *what, int rc, const char *out, size_t outlen,
                                     const api_error *err, int nl)
{
    FUZZ_CHECK(fuzz_status_ok_msg(rc, err->msg), "%s: status %d (%.*s)", what, rc, API_ERRMAX,
               err->msg);
    if (rc == API_OK) {
        FUZZ_CHECK(out != NULL, "%s: API_OK without output", what);
        FUZZ_CHECK(strlen(out) == outlen, "%s: output of %zu bytes, %zu said", what, strlen(out),
                   outlen);
        FUZZ_CHECK(!nl || (outlen > 0 && out[outlen - 1] == '\n'), "%s: output without a final \\n",
                   what);
        return;
    }
    FUZZ_CHECK(out == NULL && outlen == 0, "%s: status %d with an output", what, rc);
    FUZZ_CHECK(err->status == rc, "%s: status %d, err.status %d", what, rc, err->status);
    size_t n = strnlen(err->msg, API_ERRMAX);
    FUZZ_CHECK(n > 0 && n < API_ERRMAX, "%s: status %d with an empty or unterminated message", what,
               rc);
    for (size_t i = 0; i < n; i++)
        FUZZ_CHECK((unsigned char)err->msg[i] >= 0x20 && (unsigned char)err->msg[i] < 0x7f,
                   "%s: byte %zu of the message is not printable ASCII", what, i);
}

#endif
