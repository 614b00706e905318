/* fuzz_stl.c — libFuzzer target: the STL reader of api/meshio.h (mesh_read_stl), then the checks
 * and the run of a solid it reads (fuzz_mesh.h). */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* memmem, strnlen, strncasecmp (the Makefile defines it too) */
#endif
#include "api/meshio.h"
#include "tests/fuzz/fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_mesh_one_msg(mesh_read_stl, data, size, NULL);
}
