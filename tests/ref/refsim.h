/*
 * refsim.h: an independent reference for the tests and the benchmark.
 *
 * It integrates the physical equations (1.1) with a GSL odeiv2 stepper, mode
 * by mode, and locates each switching event on the step where the switching
 * function changes sign by bisection, integrating again from the start of the
 * step.  It shares no code with libstickslip: only the equations and the
 * friction law of the paper.
 */
#ifndef SS_REFSIM_H
#define SS_REFSIM_H

#include <gsl/gsl_odeiv2.h>
#include <stddef.h>

typedef struct ref_params {
  double chi, eta, us, ur, V;
} ref_params;

/* Modes as in the paper: 0 slip (u = +us), 1 overshoot (u = -us), 2 stick. */
enum { REF_SLIP = 0, REF_OVERSHOOT = 1, REF_STICK = 2 };

typedef struct ref_event {
  double t;
  int from, to;
  double x[4];
} ref_event;

typedef struct ref_opts {
  const gsl_odeiv2_step_type *type; /* e.g. gsl_odeiv2_step_rk8pd */
  double rtol, atol;                /* adaptive steppers */
  double h_fixed;                   /* > 0: fixed step (rk4) */
  double loc_tol;                   /* event time tolerance of the bisection */
} ref_opts;

/* Integrate one mode for time t from x (in place), no events. */
int ref_flow(const ref_params *p, int mode, double t, double x[4],
             const ref_opts *o);

/* Simulate from (t0, x0, mode0) to t_end; events into ev (up to max_ev).
 * Returns the number of events, or -1 on a GSL failure; final state into
 * x_end and *mode_end. */
long ref_simulate(const ref_params *p, double t0, const double x0[4], int mode0,
                  double t_end, const ref_opts *o, ref_event *ev, size_t max_ev,
                  double x_end[4], int *mode_end);

#endif
