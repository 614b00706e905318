/* fuzz_mesh.h — the body of the OBJ and OFF targets (fuzz_obj.c, fuzz_off.c): one reader of
 * core/solid.h on the input, then what the CLI does with what it read, at a small scale.
 *
 * Also the STL and PLY targets (fuzz_stl.c, fuzz_ply.c: any message but an empty one).
 * Checks beyond the sanitizers: a refusal is -1 with a "line N: ..." message and an empty
 * solid; a reading is a well-formed solid (offsets from 0, non-decreasing, ending at the counts;
 * every index < nv).  A reading then goes through solid_check() and solid_check_faces() at the
 * grid step arr3_solids_step() gives it (the validation of a "solids" request), and, when it is
 * usable and small (FUZZ_MESH_RUN_FACES faces at most), through api_solids_run_direct(), one
 * thread: the arrangement `cellar solids FILE` computes.
 *
 * Inputs over FUZZ_MESH_MAX bytes are refused, so each run stays small.
 */
#ifndef CELLAR_FUZZ_MESH_H
#define CELLAR_FUZZ_MESH_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "api/api.h"
#include "core/arr3.h"
#include "core/solid.h"
#include "tests/fuzz/fuzz.h"

#define FUZZ_MESH_MAX       16384
#define FUZZ_MESH_RUN_FACES 64

typedef int (*fuzz_mesh_reader)(const char *text, size_t len, solid *out, char *err, size_t errlen);

static void fuzz_check_solid(const solid *s)
{
    FUZZ_CHECK(s->nv == 0 || s->V != NULL, "vertices without V");
    FUZZ_CHECK(s->face_off && s->cyc_off, "no offsets");
    FUZZ_CHECK(s->face_off[0] == 0 && s->face_off[s->nf] == s->ncyc, "face_off: %u .. %u of %zu",
               s->face_off[0], s->face_off[s->nf], s->ncyc);
    for (size_t f = 0; f < s->nf; f++)
        FUZZ_CHECK(s->face_off[f] < s->face_off[f + 1], "face %zu without a cycle", f);
    FUZZ_CHECK(s->cyc_off[0] == 0, "cyc_off[0] = %u", s->cyc_off[0]);
    for (size_t c = 0; c < s->ncyc; c++) {
        FUZZ_CHECK(s->cyc_off[c] + 3 <= s->cyc_off[c + 1], "cycle %zu of %u indices", c,
                   s->cyc_off[c + 1] - s->cyc_off[c]);
        for (uint32_t i = s->cyc_off[c]; i < s->cyc_off[c + 1]; i++)
            FUZZ_CHECK(s->cyc[i] < s->nv, "cycle %zu: index %u of %zu vertices", c, s->cyc[i],
                       s->nv);
    }
}

/* One input through reader; a refusal's message must start with prefix (NULL: any text). */
static int fuzz_mesh_one_msg(fuzz_mesh_reader reader, const uint8_t *data, size_t size,
                             const char *prefix)
{
    solid s, fixed = {0};
    solid_report rep;
    char err[256];
    double step = 0;
    if (size > FUZZ_MESH_MAX) return -1;
    memset(err, 'x', sizeof err);
    int rc = reader((const char *)data, size, &s, err, sizeof err);
    FUZZ_CHECK(memchr(err, 0, sizeof err) != NULL, "unterminated message");
    if (rc != 0) {
        FUZZ_CHECK(rc == -1, "reader returned %d", rc);
        FUZZ_CHECK(prefix ? strncmp(err, prefix, strlen(prefix)) == 0 : err[0] != 0,
                   "message \"%s\"", err);
        FUZZ_CHECK(s.nv == 0 && s.nf == 0 && !s.V && !s.cyc, "refused with a solid");
        return 0;
    }
    fuzz_check_solid(&s);
    if (arr3_solids_step(&s, 1, 0, &step, err, sizeof err) != ARR_OK) {
        solid_free(&s);
        return 0;
    }
    memset(&rep, 0, sizeof rep);
    solid_check_faces(&s, step, "faces", &rep);
    FUZZ_CHECK(rep.nmsg <= SOLID_MAX_MESSAGES, "%zu messages", rep.nmsg);
    memset(&rep, 0, sizeof rep);
    int bad = solid_check(&s, step, "solid", &rep, &fixed);
    FUZZ_CHECK(rep.nmsg <= SOLID_MAX_MESSAGES, "%zu messages", rep.nmsg);
    FUZZ_CHECK((bad == 0) == (rep.errors == 0), "solid_check %d with %zu errors", bad, rep.errors);
    if (bad == 0) fuzz_check_solid(&fixed);
    solid_free(&fixed);
    if (bad != 0 || s.nf > FUZZ_MESH_RUN_FACES) {
        solid_free(&s);
        return 0;
    }
    /* `cellar solids FILE`: the solid is handed over */
    solid *sv = malloc(sizeof *sv);
    if (!sv) {
        solid_free(&s);
        return 0;
    }
    *sv = s;
    api_run_opts ro = {.threads = 1};
    api_error e = {0};
    char *out = NULL;
    size_t outlen = 0;
    rc = api_solids_run_direct(sv, 1, 0, NULL, NULL, &ro, &out, &outlen, &e);
    fuzz_check_answer("api_solids_run_direct", rc, out, outlen, &e, 1);
    free(out);
    return 0;
}

/* OBJ and OFF: "line N: ..." */
static inline int fuzz_mesh_one(fuzz_mesh_reader reader, const uint8_t *data, size_t size)
{
    return fuzz_mesh_one_msg(reader, data, size, "line ");
}

#endif
