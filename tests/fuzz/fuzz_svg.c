/* fuzz_svg.c — libFuzzer target: the SVG reader of core/svg.h (svg_read) on the input as a
 * drawing, with the default options and, when that reads, again normalized with rect diagonals.
 *
 * Checks beyond the sanitizers: a refusal is one of the documented codes with a message and an
 * empty result; a reading has finite segments (4 numbers each) within max_segments, at most
 * SVG_MAX_WARNINGS terminated warnings, and the same elements however it is mapped.
 *
 * Inputs over FUZZ_SVG_MAX bytes are refused, so each run stays small.
 */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* memmem, strnlen, strncasecmp (the Makefile defines it too) */
#endif
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/arr2.h"
#include "core/svg.h"
#include "tests/fuzz/fuzz.h"

#define FUZZ_SVG_MAX 16384

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Reads the input with o; checks the contract; returns the code (*out filled on ARR_OK). */
static int read_with(const char *text, size_t len, const svg_opts *o, svg_result *out)
{
    char err[256];
    memset(err, 'x', sizeof err);
    int rc = svg_read(text, len, o, out, err, sizeof err);
    FUZZ_CHECK(rc == ARR_OK || rc == ARR_EINVAL || rc == ARR_ELIMIT || rc == ARR_ENOMEM,
               "svg_read returned %d", rc);
    FUZZ_CHECK(memchr(err, 0, sizeof err) != NULL, "unterminated message");
    if (rc != ARR_OK) {
        FUZZ_CHECK(err[0] != 0, "refused (%d) without a message", rc);
        FUZZ_CHECK(out->seg == NULL && out->n == 0, "refused (%d) with segments", rc);
        return rc;
    }
    FUZZ_CHECK(out->n <= SVG_MAX_SEGMENTS, "%zu segments", out->n);
    FUZZ_CHECK(out->n == 0 || out->seg != NULL, "segments without an array");
    FUZZ_CHECK(out->nwarnings <= SVG_MAX_WARNINGS, "%zu warnings", out->nwarnings);
    for (size_t i = 0; i < out->nwarnings; i++)
        FUZZ_CHECK(memchr(out->warning[i], 0, sizeof out->warning[i]) != NULL,
                   "warning %zu unterminated", i);
    for (size_t i = 0; i < 4 * out->n; i++)
        FUZZ_CHECK(isfinite(out->seg[i]), "segment %zu: a coordinate %g", i / 4, out->seg[i]);
    for (int i = 0; i < 6; i++) FUZZ_CHECK(!isnan(out->transform[i]), "transform[%d] is NaN", i);
    return rc;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *text = (const char *)data;
    svg_opts o = {0};
    svg_result a = {0}, b = {0};
    if (size > FUZZ_SVG_MAX) return -1;
    if (read_with(text, size, &o, &a) != ARR_OK) return 0;
    o.normalize = 1;
    o.rect_diagonal = 1;
    if (read_with(text, size, &o, &b) == ARR_OK && !a.skipped && !b.skipped)
        FUZZ_CHECK(b.elements == a.elements, "%zu elements read, %zu normalized", a.elements,
                   b.elements);
    svg_result_free(&a);
    svg_result_free(&b);
    return 0;
}
