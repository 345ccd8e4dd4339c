/*
 * shortest.h: a double in the fewest decimal digits that read back as the
 * same double (shortest.c).
 */
#ifndef SS_API_SHORTEST_H
#define SS_API_SHORTEST_H

#include <stdint.h>

/* @a v, finite, as few digits as read back as v, or one more, written as
 * printf's %g writes them, with ".0" added to a whole number, into @a out
 * (32 bytes); the length. */
int api__shortest(double v, char *out);
/* Entry @a i of the cached powers of ten: 10^k ~ f * 2^e, k returned
 * (0 when @a i is past the table). */
int api__pow10_cached(int i, uint64_t *f, int *e);
/* The shortest digits of the finite, nonzero |v| (v = digits * 10^k) by
 * Grisu3 alone: their count, or 0 when it cannot be sure. */
int api__grisu3(double v, char *digits, int *k);

#endif
