/*
 * shortest.h: a double in the fewest decimal digits that read back as the
 * same double (shortest.c).
 */
#ifndef SS_API_SHORTEST_H
#define SS_API_SHORTEST_H

#include <stdint.h>

/* @a v, finite, in as few digits as read back as v (the closest to v of
 * that many), written as printf's %g writes them, with ".0" added to a
 * whole number, into @a out, NUL-terminated; the length.  All 32 bytes of
 * @a out are written (the digits are copied in whole words). */
int api__shortest(double v, char *out);
/* The power of ten the digits of a double are scaled by:
 * hi 2^64 + lo = floor(10^k 2^(127 - e)) + 1, e = floor(log2 10^k); 0 when
 * @a k is past the table (-292 .. 326). */
int api__pow10_g(int k, uint64_t *hi, uint64_t *lo, int *e);

#endif
