/* fastfloat.h — decimal numbers read at the speed of the text: a correctly rounded (to nearest,
 * ties to even: the same double as strtod) parser after Eisel and Lemire ("Number Parsing at a
 * Gigabyte per Second", 2021): a 64-bit significand times a 128-bit power of five, strtod only
 * where that cannot decide (a tie within one unit, a subnormal result, more than 19 significant
 * digits).  See fastfloat.c.
 *
 * Threads: reentrant (the "C" locale of the strtod fallback is made once, atomically). */
#ifndef CELLAR_FASTFLOAT_H
#define CELLAR_FASTFLOAT_H

#include <stddef.h>

/* The decimal number that is exactly the bytes [p, end): an optional sign, digits with an
 * optional point (at least one digit), an optional exponent (e or E, optional sign, digits).
 * Returns 0 with the nearest double in *out, or -1 when the bytes are not such a number or it
 * is not finite. */
int ff_parse(const char *p, const char *end, double *out);

/* The same for the longest prefix of [p, end) that has the form above; *stop gets its end.
 * Returns -1 when no prefix is a number (or it is not finite).  A reader that takes a token
 * when the byte at *stop separates tokens scans each byte once. */
int ff_parse_prefix(const char *p, const char *end, double *out, const char **stop);

/* A JSON number token (RFC 8259: -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)?) at the start of
 * [p, end): its end in *stop, *integer when it has neither fraction nor exponent, *digits the
 * digits of its integer part, and its value in *out (an integer of up to 15 digits from its
 * digits, exactly, "-0" as -0.0; anything else by ff_parse).  Returns 0, -1 when no such token
 * starts at p, or -2 when its value is not finite.  The byte after it is the caller's to check. */
int ff_json_number(const char *p, const char *end, double *out, int *integer, size_t *digits,
                   const char **stop);

#endif
