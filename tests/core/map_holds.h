/*
 * map_holds.h: whether a map's cell holds a given orbit (the map tests).
 */
#ifndef SS_TEST_MAP_HOLDS_H
#define SS_TEST_MAP_HOLDS_H

#include <math.h>

#include "stickslip.h"

/* Does the cell hold an orbit of the sequence and durations of @a o? */
static int holds(const ss_map_cell *c, int n, const ss_mode *modes,
                 const double *dur, double period) {
  for (int i = 0; i < c->n_orbits; i++) {
    const ss_map_orbit *q = &c->orbits[i];
    if (q->n_phases != n || fabs(q->period - period) > 1e-6 * (1 + period))
      continue;
    /* the same orbit may start at another of its stick -> slip points */
    for (int r = 0; r < n; r++) {
      int same = 1;
      for (int k = 0; k < n && same; k++)
        same = q->modes[k] == modes[(k + r) % n] &&
               fabs(q->durations[k] - dur[(k + r) % n]) < 1e-6 * (1 + period);
      if (same)
        return 1;
    }
  }
  return 0;
}

#endif
