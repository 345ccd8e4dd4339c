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

/* Newton on P^k(s) = s from @a s, with the analytic Jacobian of the
 * sequence travelled (the search's third source, and how a cell of a basin
 * map that does not settle is resolved): 0 with @a s the fixed point and
 * @a modes, @a dur, @a np the sequence of its k turns; -1 when it does not
 * converge to 1e-12 of the scale max(V, (ur - us)/chi) in 30 steps. */
int ss__map_newton(const ss_model *m, double s[2], int k, ss_mode *modes,
                   double *dur, int *np);

/* Whether the fixed point @a s of P^k is one of no P^j, j | k, j < k. */
int ss__minimal_period(const ss_model *m, const double s[2], int k);

#endif
