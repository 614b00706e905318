/* fuzz_3mf.c — libFuzzer target: the 3MF reader of api/meshio.h (mesh_read_3mf: libzip, then
 * libxml2's reader) on the input as a zip; a refusal is -1 with a message and no solids, a
 * reading well-formed solids (fuzz_mesh.h's fuzz_check_solid), each checked by solid_check().
 * The seeds (tests/fuzz/corpus/3mf/) are small zips; most mutations break the zip's structure
 * or its CRC, which is the point: the zip layer is the first thing an attacker reaches. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif
#include "api/meshio.h"
#include "tests/fuzz/fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    solid *parts = NULL;
    size_t np = 99;
    char err[256];
    if (size > FUZZ_MESH_MAX) return -1;
    memset(err, 'x', sizeof err);
    int rc = mesh_read_3mf((const char *)data, size, &parts, &np, err, sizeof err);
    FUZZ_CHECK(memchr(err, 0, sizeof err) != NULL, "unterminated message");
    if (rc != 0) {
        FUZZ_CHECK(rc == -1 && err[0] && !parts && np == 0, "refusal %d \"%s\"", rc, err);
        return 0;
    }
    FUZZ_CHECK(np <= MESH_3MF_SOLIDS, "%zu solids", np);
    for (size_t i = 0; i < np; i++) {
        solid_report rep;
        fuzz_check_solid(&parts[i]);
        memset(&rep, 0, sizeof rep);
        int bad = solid_check(&parts[i], 1.0 / 1024, "solid", &rep, NULL);
        FUZZ_CHECK((bad == 0) == (rep.errors == 0), "solid_check %d with %zu errors", bad,
                   rep.errors);
        solid_free(&parts[i]);
    }
    free(parts);
    return 0;
}
