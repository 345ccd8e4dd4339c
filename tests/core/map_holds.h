/*
 * map_holds.h: a map's cell against the separate search at its parameters,
 * and a family's bifurcation between two cells (the map tests).
 */
#ifndef SS_TEST_MAP_HOLDS_H
#define SS_TEST_MAP_HOLDS_H

#include <math.h>
#include <string.h>

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

/* Which side of +1, of -1 and of the unit circle the multipliers of @a o
 * lie on: the parity of the real ones above 1, of those below -1, and
 * whether their product exceeds 1. */
static int sides(const ss_map_orbit *o) {
  int above = 0, below = 0;
  for (int k = 0; k < 2 && o->eig_im[0] == 0; k++) {
    above += o->eig_re[k] > 1;
    below += o->eig_re[k] < -1;
  }
  double det = o->eig_im[0] != 0
                   ? o->eig_re[0] * o->eig_re[0] + o->eig_im[0] * o->eig_im[0]
                   : o->eig_re[0] * o->eig_re[1];
  return (above & 1) | (below & 1) << 1 | (det > 1) << 2;
}

/* Does a family of cell @a c bifurcate on the way to cell @a nb: an orbit
 * of nb near one of c (its sequence, no phase's duration more than a tenth
 * of the period away) with its multipliers on other sides? */
static int bifurcates(const ss_map_cell *c, const ss_map_cell *nb) {
  for (int k = 0; k < nb->n_orbits; k++)
    for (int i = 0; i < c->n_orbits; i++) {
      const ss_map_orbit *o = &c->orbits[i], *q = &nb->orbits[k];
      int near =
          o->n_phases == q->n_phases &&
          !memcmp(o->modes, q->modes, (size_t)q->n_phases * sizeof *q->modes);
      for (int t = 0; near && t < q->n_phases; t++)
        near = fabs(o->durations[t] - q->durations[t]) < 0.1 * o->period;
      if (near && sides(o) != sides(q))
        return 1;
    }
  return 0;
}

#endif
