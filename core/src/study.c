/*
 * study.c: a family and what its special points lead to, in one call
 * (ss_continue_study): the curves of its special points in a second
 * parameter, the families its period doublings and grazings start, and the
 * attractor past each grazing.  A special point that leads nowhere says why
 * in the study; only time, a cancel or memory stop it.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"

/* Whether a step's status stops the study. */
static int stops(int rc) {
  return rc == SS_ELIMIT_TIME || rc == SS_ECANCELED || rc == SS_ENOMEM;
}

/* Whether a family that returned @a rc is the study's to keep: a whole
 * one, or one the time budget or a cancel cut short with points found
 * (the caller is promised what was found). */
static int kept(int rc, const ss_branch *b) {
  return rc == SS_OK ||
         ((rc == SS_ELIMIT_TIME || rc == SS_ECANCELED) && b->n_points > 0);
}

/* Each special point of the kind asked, followed in the second parameter;
 * one that cannot be followed is listed with no points and the reason. */
static int study_curves(const ss_params *p, const ss_study_opts *o,
                        ss_study *s) {
  const ss_branch *b = &s->family;
  ss_cont_opts o2 = o->family;
  o2.param = o->follow_param;
  o2.lo = o->follow_lo;
  o2.hi = o->follow_hi;
  o2.direction = 0;
  for (int i = 0; i < b->n_special; i++) {
    const ss_special *g = &b->special[i];
    if (g->kind != o->follow_kind)
      continue;
    ss_curve *cv = &s->curves[s->n_curves++];
    ss_diag d;
    ss_diag_clear(&d);
    int rc = o->follow_kind == SS_SPECIAL_PERIOD_DOUBLING
                 ? ss_continue_period_doubling(p, b, g, &o2, cv, &d)
                 : ss_continue_grazing(p, b, g, &o2, cv, &d);
    if (stops(rc))
      return rc;
    if (rc != SS_OK) {
      ss_curve_free(cv);
      cv->kind = o->follow_kind;
      cv->p1 = b->param;
      cv->p2 = o2.param;
      cv->start = -1;
      snprintf(cv->end[0], sizeof cv->end[0], "%s",
               d.text[0] ? d.text : ss_strerror(rc));
    }
  }
  return SS_OK;
}

/* The period-2 family at each period doubling, or why there is none. */
static int study_period2(const ss_params *p, const ss_study_opts *o,
                         ss_study *s) {
  for (int i = 0; i < s->family.n_special; i++) {
    const ss_special *pd = &s->family.special[i];
    if (pd->kind != SS_SPECIAL_PERIOD_DOUBLING)
      continue;
    ss_diag d;
    ss_diag_clear(&d);
    ss_branch *b2 = &s->branches[s->n_branches];
    int rc = ss_continue_period2(p, &s->family, pd, &o->family, b2, &d);
    if (kept(rc, b2)) {
      s->of_special[s->n_branches++] = i;
      if (rc == SS_OK)
        continue;
      return rc;
    }
    ss_branch_free(b2);
    if (stops(rc))
      return rc;
    snprintf(s->why_none[i], sizeof s->why_none[i], "%s", d.text);
  }
  return SS_OK;
}

/* Past each grazing: the attractor, and the adjacent sequence's family
 * (kept with branch switching). */
static int study_beyond(const ss_params *p, const ss_study_opts *o,
                        ss_study *s) {
  for (int i = 0; i < s->family.n_special; i++) {
    const ss_special *g = &s->family.special[i];
    ss_beyond *by = &s->beyond[i];
    if (g->kind != SS_SPECIAL_GRAZING)
      continue;
    ss_diag d;
    ss_diag_clear(&d);
    by->done = ss_beyond_grazing(p, &s->family, g, &by->value,
                                 &by->attractor) == SS_OK;
    ss_branch adj;
    int rc = ss_continue_adjacent(p, &s->family, g, &o->family, &adj, &d);
    by->adjacent_rc = rc;
    by->adjacent_n_phases = adj.n_phases;
    memcpy(by->adjacent_modes, adj.modes, sizeof adj.modes);
    snprintf(by->adjacent_why, sizeof by->adjacent_why, "%s", d.text);
    if (kept(rc, &adj) && o->branch_switching &&
        s->n_branches < SS_MAX_SPECIAL) {
      s->branches[s->n_branches] = adj;
      s->of_special[s->n_branches++] = i;
    } else {
      ss_branch_free(&adj);
    }
    if (stops(rc))
      return rc;
  }
  return SS_OK;
}

int ss_continue_study(const ss_params *p, const ss_orbit *start,
                      const ss_study_opts *opts, ss_study *s, ss_diag *d) {
  if (!s)
    return ss__fail(d, SS_EINVAL, "study", 0, "no output");
  memset(s, 0, sizeof *s);
  if (!opts)
    return ss__fail(d, SS_EINVAL, "opts", 0, "a NULL argument");
  if (opts->follow && opts->follow_kind != SS_SPECIAL_GRAZING &&
      opts->follow_kind != SS_SPECIAL_PERIOD_DOUBLING)
    return ss__fail(d, SS_EINVAL, "follow", (double)opts->follow_kind,
                    "only a grazing or a period doubling can be followed");
  int rc = ss_continue(p, start, &opts->family, &s->family, d);
  if (rc == SS_OK && opts->follow)
    rc = study_curves(p, opts, s);
  if (rc == SS_OK && opts->branch_switching &&
      !(s->branches = calloc(SS_MAX_SPECIAL, sizeof *s->branches)))
    rc = SS_ENOMEM;
  if (rc == SS_OK && opts->branch_switching)
    rc = study_period2(p, opts, s);
  if (rc == SS_OK && !s->family.physical)
    rc = study_beyond(p, opts, s);
  return rc;
}

void ss_study_free(ss_study *s) {
  if (!s)
    return;
  ss_branch_free(&s->family);
  for (int i = 0; i < s->n_curves; i++)
    ss_curve_free(&s->curves[i]);
  for (int i = 0; i < s->n_branches; i++)
    ss_branch_free(&s->branches[i]);
  free(s->branches);
  memset(s, 0, sizeof *s);
}
