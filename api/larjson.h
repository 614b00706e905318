/* larjson.h — the row writers api/larjson.c shares with api/larjson3.c (the other writers of
 * api_buf are declared in api/api_int.h).  Each writes one JSON array of rows, checking
 * api_buf_tick() every row, so a large field stops as soon as the buffer failed or the run was
 * canceled (the caller sees b->failed).
 *
 * Threads: as api_buf (one buffer, one thread).  Ownership: the arrays are borrowed. */
#ifndef CELLAR_LARJSON_H
#define CELLAR_LARJSON_H

#include <stddef.h>
#include <stdint.h>

#include "api/api_int.h"

/* [[x,y],...] or [[x,y,z],...]: the n points of dim coordinates at V ("V"). */
void api_buf_point_rows(api_buf *b, const double *V, size_t n, int dim);

/* [[a0,a1],...]: n rows of k vertex indices each at a ("EV": k = 2). */
void api_buf_u32_rows(api_buf *b, const uint32_t *a, size_t n, size_t k);

#endif
