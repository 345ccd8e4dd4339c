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

/* Newton on the duration equations with the start z0 one more unknown
 * (not eliminated through (5.1)): tau and z0 are the guess, updated in
 * place on success, *resid the largest residual.  It stays regular where
 * a real multiplier of the return map is +1, where the elimination is
 * singular and ss_orbit_equations() has a pole on the family.  SS_OK,
 * SS_ENOCONV, SS_ESINGULAR or SS_EINVAL. */
int ss__orbit_solve_full(const ss_model *m, int n, const ss_mode *modes,
                         double *tau, double z0[4], double *resid);

#endif
