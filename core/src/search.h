/*
 * search.h: what the orbit search (search.c) gives the other files; not
 * installed.
 */
#ifndef SS_SEARCH_H
#define SS_SEARCH_H

#include "stickslip.h"

/* Whether orbit b passes through a's start with a's sequence rotated (the
 * same orbit started at another of its stick -> slip points), states within
 * @a tol. */
int ss__same_orbit(const ss_model *m, const ss_orbit *a, const ss_orbit *b,
                   double tol);

#endif
