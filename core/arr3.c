/* arr3.c — placeholder while the 3D core is written (see arr3.h); replaced by the real one. */
#include "core/arr3.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int arr3_build(const solid *solids, size_t ns, int soup, const arr3_opts *opts, lar3 *out,
               char *err, size_t errlen)
{
    (void)solids, (void)ns, (void)soup, (void)opts;
    memset(out, 0, sizeof *out);
    if (err && errlen) snprintf(err, errlen, "solids: the 3D core is not built yet");
    return ARR_EINTERNAL;
}

void lar3_free(lar3 *c)
{
    (void)c;
}

double lar3_face_cone(const lar3 *c, uint32_t f)
{
    (void)c, (void)f;
    return 0;
}
