/*
 * attractor.c: where the motion settles, found by following its returns to
 * the section Sigma0 (ss_poincare(), one return at a time) until they
 * repeat.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "attractor.h"
#include "stability.h"

int ss_attractor_from(const ss_model *m, const double s0[2], int max_turns,
                      int max_period, ss_attractor *a) {
  return ss__attractor_from(m, s0, max_turns, max_period, NULL, a);
}

int ss__attractor_from(const ss_model *m, const double s0[2], int max_turns,
                       int max_period, ss__poll *poll, ss_attractor *a) {
  if (!m || !s0 || !a || max_turns < 1 || max_period < 1 || max_period > 256)
    return SS_EINVAL;
  memset(a, 0, sizeof *a);
  /* the last max_period + 1 returns: the point reached and the phases of
   * the turn that led there */
  typedef struct turn {
    double s[2];
    int n;
    ss_mode modes[SS_MAX_PHASES];
    double dur[SS_MAX_PHASES];
  } turn;
  int cap = max_period + 2;
  turn *h = calloc((size_t)cap, sizeof *h);
  if (!h)
    return SS_ENOMEM;
  double s[2] = {s0[0], s0[1]};
  int rc = SS_OK;
  for (int t = 0; t < max_turns; t++) {
    turn *cur = &h[t % cap];
    rc = ss__poincare(m, s, 1, 100000, cur->s, cur->modes, cur->dur, &cur->n,
                      poll);
    if (rc == SS_HORIZON) {
      a->perpetual_slip = 1;
      a->turns_run = t + 1;
      rc = SS_OK;
      break;
    }
    if (rc != SS_OK)
      break;
    s[0] = cur->s[0];
    s[1] = cur->s[1];
    a->turns_run = t + 1;
    if (t < 20)
      continue;
    double tol = 1e-9 * (1 + fabs(s[0]) + fabs(s[1]));
    for (int k = 1; k <= max_period && k + 1 <= t; k++) {
      const turn *b = &h[(t - k) % cap], *c1 = &h[(t - 1) % cap],
                 *b1 = &h[(t - 1 - k) % cap];
      if (fabs(cur->s[0] - b->s[0]) > tol || fabs(cur->s[1] - b->s[1]) > tol ||
          fabs(c1->s[0] - b1->s[0]) > tol || fabs(c1->s[1] - b1->s[1]) > tol)
        continue;
      /* the period: the last k turns */
      a->found = 1;
      a->n_turns = k;
      a->s[0] = cur->s[0];
      a->s[1] = cur->s[1];
      for (int j = k - 1; j >= 0; j--) {
        const turn *u = &h[(t - j) % cap];
        for (int q = 0; q < u->n; q++) {
          if (a->n_phases < SS_MAX_PHASES) {
            a->modes[a->n_phases] = u->modes[q];
            a->durations[a->n_phases] = u->dur[q];
          }
          a->n_phases++;
          a->n_overshoot += u->modes[q] == SS_MODE_OVERSHOOT;
          a->period += u->dur[q];
        }
      }
      free(h);
      return SS_OK;
    }
  }
  free(h);
  return rc;
}
