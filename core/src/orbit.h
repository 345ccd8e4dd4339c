/*
 * orbit.h: what the orbit solver (orbit.c) gives the other files; not
 * installed.
 */
#ifndef SS_ORBIT_H
#define SS_ORBIT_H

#include "stickslip.h"

/* Whether the sequence (n phases, durations tau) is a shorter one repeated
 * two or more times, durations equal within @a tol: the same orbit
 * travelled again, not an orbit of longer period.  The length of the
 * shortest such block, or 0. */
int ss__is_repetition(int n, const ss_mode *modes, const double *tau,
                      double tol);

#endif
