/*
 * switch.c: branch switching, the families a family's special points start:
 * the period-2 family at a period doubling, and past a grazing the
 * attractor the motion settles on and the family of the adjacent sequence.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "continue.h"
#include "internal.h"
#include "params.h"

/* ---- the period-2 family at a period doubling ------------------------- */

int ss_continue_period2(const ss_params *p, const ss_branch *b,
                        const ss_special *pd, const ss_cont_opts *o,
                        ss_branch *out, ss_diag *d) {
  if (!out)
    return ss__fail(d, SS_EINVAL, "branch", 0, "no output");
  memset(out, 0, sizeof *out);
  if (!p || !b || !pd || !o || !ss_param_name(o->param) || o->physical ||
      b->physical)
    return ss__fail(d, SS_EINVAL, "opts", 0,
                    "a NULL argument, or a physical parameter");
  if (pd->kind != SS_SPECIAL_PERIOD_DOUBLING || 2 * b->n_phases > SS_MAX_PHASES)
    return ss__fail(d, SS_EINVAL, "special", 0,
                    "not a period doubling of a family short enough to "
                    "double");
  static const double STEPS[] = {5e-4, 1e-3, 2e-3, 4e-3, 8e-3};
  int n2 = 2 * b->n_phases;
  for (size_t i = 0; i < sizeof STEPS / sizeof STEPS[0]; i++)
    for (int side = -1; side <= 1; side += 2) {
      ss_params q = *p;
      double v = pd->value + side * STEPS[i] * (o->hi - o->lo);
      if (!(v >= o->lo && v <= o->hi))
        continue;
      *ss__param_ref(&q, o->param) = v;
      ss_model m;
      ss_orbit_opts oo;
      ss_orbit found[32];
      int nf = 0;
      memset(&oo, 0, sizeof oo);
      oo.kinds = SS_ORBIT_OTHER;
      oo.max_period = 2;
      oo.effort = 3;
      oo.max_seconds = o->max_seconds;
      oo.cancelled = o->cancelled;
      oo.cancel_cls = o->cancel_cls;
      if (ss_model_init(&m, &q, NULL) != SS_OK)
        continue;
      int rc = ss_orbit_find(&m, &oo, found, 32, &nf, NULL, NULL);
      /* out of time or cancelled: the search stops, it is not a side
       * without a period-2 orbit */
      if (rc == SS_ELIMIT_TIME || rc == SS_ECANCELED)
        return ss__fail(d, rc, "special", pd->value,
                        "the period-2 orbit's search near %.15g stopped",
                        pd->value);
      if (rc != SS_OK)
        continue;
      int best = -1;
      for (int k = 0; k < nf; k++) {
        const ss_orbit *f = &found[k];
        int match = f->n_turns == 2 && f->n_phases == n2;
        for (int j = 0; match && j < n2; j++)
          match = f->modes[j] == b->modes[j % b->n_phases];
        if (match &&
            (best < 0 || fabs(f->period - 2 * pd->at.period) <
                             fabs(found[best].period - 2 * pd->at.period)))
          best = k;
      }
      if (best >= 0)
        return ss_continue(&q, &found[best], o, out, d);
    }
  return ss__fail(d, SS_ENOCONV, "special", pd->value,
                  "no period-2 orbit found near the period doubling at "
                  "%.15g",
                  pd->value);
}

/* Whether the grazing @a g ends the family @a b (its point is the first or
 * the last of the family): then the parameter just past it, 1e-4
 * (relative) beyond the located value on the side where the family does
 * not exist, in *past.  The family's neighbour says which side that is (the
 * family's last point is g->at; g->value is past it by the location's
 * precision, or at a tangential end by the band the check cannot
 * decide). */
static int grazing_ends(const ss_branch *b, const ss_special *g, double *past) {
  int at = -1;
  for (int i = 0; i < b->n_points; i++)
    if (b->points[i].value == g->at.value)
      at = i;
  if (at < 0 || (at != 0 && at != b->n_points - 1))
    return 0;
  double toward = b->points[at == 0 ? 1 : at - 1].value - g->value;
  *past = g->value * (1 - (toward > 0 ? 1e-4 : -1e-4));
  return 1;
}

int ss_beyond_grazing(const ss_params *p, const ss_branch *b,
                      const ss_special *g, double *value, ss_attractor *a) {
  if (!p || !b || !g || !value || !a || g->kind != SS_SPECIAL_GRAZING ||
      b->physical || !ss_param_name(b->param) || b->n_points < 2 ||
      !grazing_ends(b, g, value))
    return SS_EINVAL;
  ss_params q = *p;
  *ss__param_ref(&q, b->param) = *value;
  ss_model m;
  if (ss_model_init(&m, &q, NULL) != SS_OK)
    return SS_EINVAL;
  double s0[2] = {g->at.z0[0], g->at.z0[2]};
  return ss_attractor_from(&m, s0, 5000, 64, a);
}

/* The adjacent sequence past the grazing @a g at the end of phase k of the
 * family @a b: a short stick after the phase that ends on its switching
 * surface; or, for a maximum inside phase k, that phase split there by a
 * short phase of the mode the margin's zero would start.  The durations
 * are the grazing orbit's, the new phase 1e-3 of its period. */
static void adjacent_guess(const ss_branch *b, const ss_special *g,
                           ss_orbit *guess) {
  static const ss_mode SPLIT[4] = {SS_MODE_STICK, SS_MODE_STICK, SS_MODE_SLIP,
                                   SS_MODE_OVERSHOOT};
  int k = g->at.min_margin.phase, interior = ss__interior_index(g->margin);
  int q = 0;
  memset(guess, 0, sizeof *guess);
  for (int j = 0; j < b->n_phases; j++) {
    double tj = g->at.durations[j];
    if (j == k && interior >= 0) {
      guess->modes[q] = b->modes[j];
      guess->durations[q++] = g->at.min_margin.t;
      guess->modes[q] = SPLIT[interior];
      guess->durations[q++] = 1e-3 * g->at.period;
      guess->modes[q] = b->modes[j];
      guess->durations[q++] = tj - g->at.min_margin.t;
      continue;
    }
    guess->modes[q] = b->modes[j];
    guess->durations[q++] = tj;
    if (j == k) {
      guess->modes[q] = SS_MODE_STICK;
      guess->durations[q++] = 1e-3 * g->at.period;
    }
  }
  guess->n_phases = q;
}

int ss_continue_adjacent(const ss_params *p, const ss_branch *b,
                         const ss_special *g, const ss_cont_opts *o,
                         ss_branch *out, ss_diag *d) {
  if (!out)
    return ss__fail(d, SS_EINVAL, "branch", 0, "no output");
  memset(out, 0, sizeof *out);
  if (!p || !b || !g || !o || !ss_param_name(o->param) || o->physical)
    return ss__fail(d, SS_EINVAL, "opts", 0,
                    "a NULL argument, or a physical parameter");
  int k = g->at.min_margin.phase, n = b->n_phases;
  int interior = ss__interior_index(g->margin);
  if (g->kind != SS_SPECIAL_GRAZING || k < 0 || k >= n || b->n_points < 2 ||
      n + (interior >= 0 ? 2 : 1) > SS_MAX_PHASES ||
      (interior < 0 &&
       (g->margin != SS_MARGIN_SWITCHING || b->modes[k] == SS_MODE_STICK)) ||
      (interior >= 0 &&
       !(g->at.min_margin.t > 0 && g->at.min_margin.t < g->at.durations[k])))
    return ss__fail(d, SS_EINVAL, "special", 0,
                    "not a grazing of the switching condition at the end of "
                    "a slip or overshoot, or of a margin's maximum inside a "
                    "phase");
  ss_params past = *p;
  double v;
  if (!grazing_ends(b, g, &v))
    return ss__fail(d, SS_EINVAL, "special", g->value,
                    "the grazing does not end the family");
  *ss__param_ref(&past, o->param) = v;
  ss_orbit guess, start;
  adjacent_guess(b, g, &guess);
  out->n_phases = guess.n_phases;
  memcpy(out->modes, guess.modes, sizeof guess.modes);
  ss_model m;
  int rc = ss_model_init(&m, &past, d);
  if (rc != SS_OK)
    return rc;
  rc = ss_orbit_solve(&m, guess.n_phases, guess.modes, guess.durations, NULL,
                      &start, d);
  if (rc == SS_ENOCONV || rc == SS_ESINGULAR) {
    /* the solver's words kept, under the status returned */
    char why[sizeof d->text] = "";
    if (d)
      snprintf(why, sizeof why, "%s", d->text);
    ss_diag_clear(d);
    return ss__fail(d, SS_INFEASIBLE, "special", g->value,
                    "the adjacent sequence has no orbit past the grazing "
                    "(%s)",
                    why);
  }
  if (rc != SS_OK)
    return rc;
  return ss_continue(&past, &start, o, out, d);
}
