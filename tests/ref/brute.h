/*
 * brute.h: an independent brute-force finder of the period-1 orbits
 *   (A) slip -> stick              and
 *   (B) slip -> overshoot -> stick
 * of the two-mass stick-slip oscillator (1.1)-(1.2).  It shares no code with
 * libstickslip (only refsim.h, for an optional cross-check).  See brute.c for
 * the method, the grid resolution and what it can miss.
 */
#ifndef SS_BRUTE_H
#define SS_BRUTE_H

typedef struct brute_orbit {
  int n_phases; /* 2 or 3 */
  int modes[3]; /* 0 slip, 1 overshoot, 2 stick (same numbering as refsim.h) */
  double dur[3];
  double period;
  double s[2];    /* x1, x1' at the stick -> slip point */
  double closure; /* |P(s) - s| by simulation */
  double margin;  /* smallest feasibility margin (>0 feasible) */
  double radius;  /* spectral radius of the Poincare map's Jacobian */
} brute_orbit;

typedef struct brute_params {
  double chi, eta, us, ur, V;
} brute_params;

/* All feasible orbits of sequences (A) and (B) with each duration in
 * (0, dmax]; returns how many (at most max_out written), or -1 on failure. */
int brute_orbits(const brute_params *p, double dmax, brute_orbit *out,
                 int max_out);

/* 1.5 * 2 pi / w_slow, w_slow the smaller modal frequency. */
double brute_dmax(const brute_params *p);

/* Extra: confirm an orbit with ref_simulate (GSL rk8pd, rtol = atol = 1e-12)
 * started at the orbit's section point in slip.  Returns the closure
 * |(x1, x1') at the first stick -> slip event - s|, or -1 if the simulation
 * failed or its event sequence differs from the orbit's; *dur_err (if not
 * NULL) receives the largest difference between the simulated and the
 * orbit's phase durations. */
double brute_refcheck(const brute_params *p, const brute_orbit *o,
                      double *dur_err);

#endif
