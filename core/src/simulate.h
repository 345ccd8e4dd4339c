/*
 * simulate.h: a simulation in progress, as the core's own loops keep it
 * (simulate.c); not installed.
 */
#ifndef SS_SIMULATE_H
#define SS_SIMULATE_H

#include "events.h"
#include "stickslip.h"

/* Records kept per switching function of a simulation: an orbit of up to
 * this many turns repeats each of its phases within them. */
#define SS__CERT_SLOTS 4

/* A simulation in progress (ss_sim of the header).  The core's own loops
 * keep one on the stack, started with ss__sim_init(_mode), so that no
 * allocation enters them. */
struct ss_sim {
  const ss_model *m;
  ss_mode mode;      /* current mode */
  double t_hi, t_lo; /* absolute time of the anchor, as a sum */
  double x[4];       /* state at the anchor */
  int perpetual;     /* the current slip can never end */
  double t_next;     /* local time of the next event (if have_next) */
  int next_status;   /* SS_OK, SS_GRAZING or SS_HORIZON for t_next */
  int next_sign;     /* stick: +1 next event at +ur, -1 at -ur */
  int have_next;
  double next_horizon; /* local horizon the search for t_next used */
  int full_search;     /* no certificates (ss_sim_opts.full_search) */
  /* stick anchored at a touch of +ur (+1) or -ur (-1): that side's
   * function is at its maximum there, on the surface */
  int touch;
  /* the last searches' certificates: slip, overshoot, stick at +ur, -ur */
  ss__root_cert cert[4][SS__CERT_SLOTS];
};

/* Start @a s at absolute time t0 from x0 in the mode of ss_mode_of_state(),
 * or in @a mode; SS_OK or SS_EINVAL (with the reason in d). */
int ss__sim_init(ss_sim *s, const ss_model *m, double t0, const double x0[4],
                 ss_diag *d);
int ss__sim_init_mode(ss_sim *s, const ss_model *m, double t0,
                      const double x0[4], ss_mode mode, ss_diag *d);

#endif
