/* larjson.h — the writers api/larjson.c shares with api/larjson3.c (the other writers of
 * api_buf are declared in api/api_int.h): a table of rows, checking api_buf_tick() every row
 * (so a large field stops as soon as the buffer failed or the run was canceled: the caller sees
 * b->failed), and the opening of a "holes" entry.
 *
 * Threads: as api_buf (one buffer, one thread).  Ownership: the arrays are borrowed. */
#ifndef CELLAR_LARJSON_H
#define CELLAR_LARJSON_H

#include <stddef.h>
#include <stdint.h>

#include "api/api_int.h"

/* n rows of k numbers each: with V the points of k coordinates at V ("V": [[x,y],...] or
 * [[x,y,z],...]), else the k vertex indices each at ix ("EV": [[v0,v1],...], k = 2). */
void api_buf_rows(api_buf *b, const double *V, const uint32_t *ix, size_t n, size_t k);

/* The opening of entry k of a "holes" object, "k":[ (after a ',' unless *first, which is
 * then cleared). */
void api_buf_key_open(api_buf *b, int *first, uint64_t k);

#endif
