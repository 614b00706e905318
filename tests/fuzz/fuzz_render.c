/* fuzz_render.c — libFuzzer target: the result readers of the renderers of api/render.h, the
 * input taken as a result JSON (LAR JSON): render_svg and render_geojson (2D), render_obj (3D),
 * render_npz (any), each with the default options and, when that draws, again with the other paths
 * on (numbers, an exploded picture, GeoJSON with every cell, an exploded OBJ).
 *
 * Checks beyond the sanitizers: "a bad result is a value, never a crash": every answer is
 * API_OK, API_EINVALID or API_ENOMEM and keeps the contract of api/render.h (fuzz.h); SVG and
 * GeoJSON end in "\n".  Inputs over FUZZ_RENDER_MAX bytes are refused.
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

#define FUZZ_RENDER_MAX 16384

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef int (*renderer)(const char *, size_t, const render_opts *, char **, size_t *, api_error *);

static int run(const char *what, renderer fn, const char *text, size_t len, const render_opts *o,
               int nl)
{
    char *out = NULL;
    size_t outlen = 0;
    api_error err = {0};
    int rc = fn(text, len, o, &out, &outlen, &err);
    FUZZ_CHECK(rc == API_OK || rc == API_EINVALID || rc == API_ENOMEM, "%s: status %d (%s)", what,
               rc, err.msg);
    fuzz_check_answer(what, rc, out, outlen, &err, nl);
    free(out);
    return rc;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *text = (const char *)data;
    render_opts o = RENDER_OPTS_INIT;
    if (size > FUZZ_RENDER_MAX) return -1;

    if (run("render_svg", render_svg, text, size, &o, 1) == API_OK) {
        render_opts p = o;
        p.numbers = 1;
        p.explode = 1.5;
        p.width = 300;
        p.stroke = 2;
        p.title = "fuzz <&> \"title\" \xff";
        run("render_svg exploded", render_svg, text, size, &p, 1);
    }
    if (run("render_geojson", render_geojson, text, size, &o, 1) == API_OK) {
        render_opts p = o;
        p.cells = 1;
        run("render_geojson cells", render_geojson, text, size, &p, 1);
    }
    { /* npz is binary: a zip whose end record closes it, or a refusal */
        char *out = NULL;
        size_t outlen = 0;
        api_error err = {0};
        int rc = render_npz(text, size, &o, &out, &outlen, &err);
        FUZZ_CHECK(rc == API_OK || rc == API_EINVALID || rc == API_ENOMEM, "render_npz: %d", rc);
        if (rc == API_OK)
            FUZZ_CHECK(out && outlen >= 22 && !memcmp(out, "PK", 2) &&
                           !memcmp(out + outlen - 22, "PK\x05\x06", 4),
                       "render_npz: not a zip");
        else
            fuzz_check_answer("render_npz", rc, out, outlen, &err, 0);
        free(out);
    }
    if (run("render_obj", render_obj, text, size, &o, 0) == API_OK) {
        render_opts p = o;
        p.explode = 2;
        run("render_obj exploded", render_obj, text, size, &p, 0);
    }
    return 0;
}
