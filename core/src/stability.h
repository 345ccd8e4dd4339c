/*
 * stability.h: the returns to Sigma0 one at a time, and the poll that stops
 * them (stability.c); not installed.
 */
#ifndef SS_STABILITY_H
#define SS_STABILITY_H

#include <stddef.h>

#include "simulate.h"
#include "stickslip.h"

/* A caller's wish to stop a long computation (its time budget spent, its
 * client gone), asked at one tick in SS__POLL_EVERY of the loops it is
 * handed to (a tick is an event): an event costs about a microsecond, so a
 * stop is seen within a millisecond, and the question (a clock read, a
 * flag) costs nothing measurable.  The count of ticks is the poll's own,
 * carried across every simulation it is handed to, so that many short ones
 * ask as often as one long one; once the answer is stop, every tick says
 * so. */
#define SS__POLL_EVERY 256
typedef struct ss__poll {
  int (*stop)(void *cls); /* non-zero: stop now; NULL: never */
  void *cls;
  unsigned ticks;
  int stopped; /* stop has said so */
} ss__poll;

/* One tick of @a p (NULL: never stops): whether to stop now. */
static inline int ss__poll_tick(ss__poll *p) {
  if (p && p->stop && !p->stopped && ++p->ticks % SS__POLL_EVERY == 0)
    p->stopped = p->stop(p->cls) != 0;
  return p && p->stopped;
}

/* The returns to Sigma0 of one motion, one at a time, by one simulation (its
 * event certificates carried from return to return): ss_poincare() for one
 * turn after another without restarting. */
typedef struct ss__returns {
  ss_sim sim;
  double t_last;  /* the last phase's end */
  int np;         /* phases so far */
  ss__poll *poll; /* ticked at each event; NULL after ss__returns_start */
} ss__returns;

/* Start at s = (z1, z1') on Sigma0; SS_OK or SS_EINVAL. */
int ss__returns_start(ss__returns *r, const ss_model *m, const double s[2]);

/* On to the next return, into out = (z1, z1'), spending at most
 * *events_left events (decremented); the phases travelled are appended to
 * modes and durations (room for SS_MAX_PHASES in all) when both are given.
 * SS_OK, SS_ELIMIT_EVENTS, SS_HORIZON, SS_ECANCELED (r->poll said stop), or
 * the simulation's failure. */
int ss__returns_next(ss__returns *r, size_t *events_left, double out[2],
                     ss_mode *modes, double *durations);

/* ss_poincare() polling @a poll (NULL: never) at each event: SS_ECANCELED
 * when it says stop. */
int ss__poincare(const ss_model *m, const double s[2], int turns,
                 size_t max_events, double out[2], ss_mode *modes,
                 double *durations, int *n_phases, ss__poll *poll);

#endif
