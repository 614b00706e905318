/* fuzz_obj.c — libFuzzer target: the Wavefront OBJ reader of core/solid.h (solid_read_obj),
 * then the checks and the run of a solid it reads (fuzz_mesh.h). */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* memmem, strnlen, strncasecmp (the Makefile defines it too) */
#endif
#include "tests/fuzz/fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_mesh_one(solid_read_obj, data, size);
}
