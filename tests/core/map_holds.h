/*
 * map_holds.h: a map's cell against the separate search at its parameters
 * (the map tests).
 */
#ifndef SS_TEST_MAP_HOLDS_H
#define SS_TEST_MAP_HOLDS_H

#include <math.h>

#include "stickslip.h"
#include "test.h"

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

/* The separate search at cell @a c of @a map (what /orbit with @a oo finds
 * at its parameters) into @a out, at most @a max; the orbits of @a out
 * the cell lacks to the front of @a out, and how many into *lacking; how
 * many orbits.  *m: the cell's model. */
static int search_cell(const ss_params *base, const ss_map_opts *mo,
                       const ss_map *map, int c, const ss_orbit_opts *oo,
                       ss_model *m, ss_orbit *out, int max, int *lacking) {
  ss_params p;
  int n = 0;
  ASSERT_EQ_INT(ss_map_params(base, mo, map, c, &p, NULL, NULL), SS_OK);
  ASSERT_EQ_INT(ss_model_init(m, &p, NULL), SS_OK);
  ASSERT_EQ_INT(ss_orbit_find(m, oo, out, max, &n, NULL, NULL), SS_OK);
  *lacking = 0;
  for (int k = 0; k < n; k++)
    if (!holds(&map->cells[c], out[k].n_phases, out[k].modes, out[k].durations,
               out[k].period)) {
      ss_orbit o = out[*lacking];
      out[*lacking] = out[k];
      out[k] = o;
      ++*lacking;
    }
  return n;
}

#endif
