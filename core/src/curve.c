/*
 * curve.c: a special point of a family (a grazing, a period doubling)
 * followed as a second parameter moves.
 *
 * The unknowns are y = (tau_1..tau_n, [t*], q1, q2): the family's durations
 * over its period at the special point, for a margin's zero maximum inside
 * a phase its time there, and the two parameters, scaled.  The equations
 * are the duration equations of ss_orbit_equations() and one (two for an
 * interior maximum: the margin and its slope) that holds at the special
 * point; the curve they leave is followed by pseudo-arclength
 * (arclength.c), its Jacobian by central differences.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "arclength.h"
#include "continue.h"
#include "internal.h"
#include "params.h"

#define NMAX ARC_NMAX

#ifndef SIDE_OFFSET_TANGENCY
#define SIDE_OFFSET_TANGENCY 1e-5
#endif
#define SIDE_OFFSET_MAX 1e-3

typedef struct gcont {
  ss_params p;
  ss_special_kind kind; /* GRAZING or PERIOD_DOUBLING */
  ss_param_id id1, id2;
  int n, k; /* phases; a grazing is at the end of phase k */
  ss_mode modes[SS_MAX_PHASES];
  double lo1, S1, lo2, S2, T;
  double q1max, q2max; /* the ranges' ends in the scaled unknowns */
  int total_points;    /* max_points, as asked */
  /* an interior grazing: the margin (its index from
   * SS_MARGIN_SLIP_BELOW_V) has a zero maximum inside phase k, at local
   * time t* = T y[n], one more unknown */
  int interior, margin;
  /* a transversality grazing: phase k ends tangentially, the slope of its
   * switching function zero at its end */
  int transversal;
  arc_curve cv;
  arc_clock clock;
  const double *y0; /* the located special point on the curve */
  double step;      /* the first step */
} gcont;

/* The unknowns of a curve: durations, t* (interior grazing), q1, q2. */
static int gc_q1(const gcont *g) { return g->n + g->interior; }

static void gc_params(const gcont *g, const double *y, ss_params *p) {
  *p = g->p;
  *ss__param_ref(p, g->id1) = g->lo1 + g->S1 * y[gc_q1(g)];
  *ss__param_ref(p, g->id2) = g->lo2 + g->S2 * y[gc_q1(g) + 1];
}

/* The switching margin at the end of phase k from the start z0, by the
 * closed form of each phase: >= 0 when the switching rule holds there. */
static double switch_margin(const ss_model *m, const gcont *g,
                            const double *tau, const double z0[4]) {
  double x[4];
  ss_z_to_x(m, z0, x);
  for (int j = 0; j <= g->k; j++)
    ss_flow(m, g->modes[j], tau[j], x, x);
  double f = ss_stick_force(m, x), ur = m->p.ur;
  ss_mode mode = g->modes[g->k],
          want = g->k + 1 < g->n ? g->modes[g->k + 1] : SS_MODE_SLIP;
  if (mode == SS_MODE_SLIP)
    return want == SS_MODE_OVERSHOOT ? -ur - f : f + ur; /* (3.2) */
  return want == SS_MODE_STICK ? ur - f : f - ur;        /* (3.4) */
}

/* The margins that can have an interior zero maximum (by their index
 * from SS_MARGIN_SLIP_BELOW_V), and their value at the state x (>= 0 when
 * the constraint holds). */
static double interior_margin(const ss_model *m, int which, const double x[4]) {
  double f = ss_stick_force(m, x);
  switch (which) {
  case 0:
    return m->p.V - x[3];
  case 1:
    return x[3] - m->p.V;
  case 2:
    return m->p.ur - f;
  default:
    return m->p.ur + f;
  }
}

/* The duration equations and the grazing's equations at y: the margin (n
 * + 1 values), or an interior margin and its slope (n + 2). */
static int gc_values(const gcont *g, const double *y, double *F) {
  double tau[SS_MAX_PHASES], z0[4];
  ss_params p;
  ss_model m;
  for (int k = 0; k < g->n; k++)
    if (!((tau[k] = g->T * y[k]) > 0))
      return SS_EDOMAIN;
  gc_params(g, y, &p);
  if (ss_model_init(&m, &p, NULL) != SS_OK)
    return SS_EDOMAIN;
  int rc = ss_orbit_equations(&m, g->n, g->modes, tau, z0, F, NULL);
  if (rc != SS_OK)
    return rc;
  if (g->kind == SS_SPECIAL_GRAZING && g->interior) {
    /* the margin and its slope at t*, by the closed form of phase k (the
     * slope by central differences in t) */
    double ts = g->T * y[g->n], h = 1e-6 * g->T, x[4], v[3];
    if (!(ts > 0 && ts < tau[g->k]))
      return SS_EDOMAIN;
    ss_z_to_x(&m, z0, x);
    for (int j = 0; j < g->k; j++)
      ss_flow(&m, g->modes[j], tau[j], x, x);
    for (int s = 0; s < 3; s++) {
      double xt[4];
      ss_flow(&m, g->modes[g->k], ts + (s - 1) * h, x, xt);
      v[s] = interior_margin(&m, g->margin, xt);
    }
    F[g->n] = v[1];
    F[g->n + 1] = (v[2] - v[0]) / (2 * h) * g->T;
    return SS_OK;
  }
  if (g->kind == SS_SPECIAL_GRAZING && g->transversal) {
    F[g->n] = ss__end_slope(&m, g->n, g->modes, tau, z0, g->k) * g->T;
    return SS_OK;
  }
  if (g->kind == SS_SPECIAL_GRAZING) {
    F[g->n] = switch_margin(&m, g, tau, z0);
    return SS_OK;
  }
  /* a period doubling: det(I + J) = 0, J the map's analytic Jacobian */
  ss_stab st;
  if ((rc = ss_stability(&m, g->n, g->modes, tau, z0, NULL, &st)) != SS_OK)
    return rc;
  F[g->n] =
      (1 + st.jac[0][0]) * (1 + st.jac[1][1]) - st.jac[0][1] * st.jac[1][0];
  return SS_OK;
}

/* Whether the orbit at y is feasible (a period doubling curve's points
 * must be orbits). */
static int gc_feasible(const gcont *g, const double *y) {
  ss_params p;
  ss_model m;
  ss_orbit o;
  double F[SS_MAX_PHASES];
  memset(&o, 0, sizeof o);
  gc_params(g, y, &p);
  if (ss_model_init(&m, &p, NULL) != SS_OK)
    return 0;
  o.n_phases = g->n;
  for (int k = 0; k < g->n; k++) {
    o.modes[k] = g->modes[k];
    o.durations[k] = g->T * y[k];
  }
  return ss_orbit_equations(&m, g->n, g->modes, o.durations, o.z0, F, NULL) ==
             SS_OK &&
         ss_orbit_check(&m, &o, NULL) == SS_OK;
}

/* The curve's function, its Jacobian by central differences (the values
 * are exact; the Jacobian only steers Newton). */
static int gc_f(const void *ctx, const double *y, double *F, double *J) {
  const gcont *g = ctx;
  int ne = g->n + 1 + g->interior, nu = ne + 1;
  int rc = gc_values(g, y, F);
  if (rc != SS_OK || !J)
    return rc;
  for (int j = 0; j < nu; j++) {
    double yp[NMAX], ym[NMAX], Fp[NMAX], Fm[NMAX], h = 1e-7;
    memcpy(yp, y, sizeof yp[0] * (size_t)nu);
    memcpy(ym, y, sizeof ym[0] * (size_t)nu);
    yp[j] += h;
    ym[j] -= h;
    if ((rc = gc_values(g, yp, Fp)) != SS_OK ||
        (rc = gc_values(g, ym, Fm)) != SS_OK)
      return rc;
    for (int i = 0; i < ne; i++)
      J[nu * i + j] = (Fp[i] - Fm[i]) / (2 * h);
  }
  return SS_OK;
}

/* The side of p1 on which the orbit at y exists: the orbit solved at
 * p1 (1 +- 1e-7) from y's durations is feasible on one side only (+1 or
 * -1); 0 when both or neither are.  A transversality grazing is a
 * tangency: the end slope grows like the distance d to it, the function's
 * rise above zero like d^2, and below the event tolerance a crossing is a
 * touch (infeasible), so its side is taken at 1 +- SIDE_OFFSET_TANGENCY,
 * or ten or a hundred times that where neither side is feasible there. */
static int feasible_side(const gcont *g, const double *y) {
  ss_params p;
  gc_params(g, y, &p);
  double v1 = *ss__param_ref(&p, g->id1), tau[SS_MAX_PHASES];
  double off = g->transversal ? SIDE_OFFSET_TANGENCY : 1e-7;
  for (int k = 0; k < g->n; k++)
    tau[k] = g->T * y[k];
  for (;;) {
    int ok[2];
    for (int s = 0; s < 2; s++) {
      ss_params q = p;
      ss_model m;
      ss_orbit o;
      *ss__param_ref(&q, g->id1) = v1 * (1 + (s ? off : -off));
      ok[s] = ss_model_init(&m, &q, NULL) == SS_OK &&
              ss_orbit_solve(&m, g->n, g->modes, tau, NULL, &o, NULL) == SS_OK;
    }
    if (ok[0] != ok[1])
      return ok[1] ? 1 : -1;
    /* at a tangency neither side is feasible while the offset is inside
     * the band the check cannot decide (wider where the curvature at the
     * phase's end is small): ten times further, up to SIDE_OFFSET_MAX */
    if (!g->transversal || ok[0] || (off *= 10) > SIDE_OFFSET_MAX)
      return 0;
  }
}

static void gc_point(const gcont *g, const double *y, int side,
                     ss_curve_point *pt) {
  ss_params p;
  ss_model m;
  double F[SS_MAX_PHASES];
  memset(pt, 0, sizeof *pt);
  gc_params(g, y, &p);
  pt->v1 = *ss__param_ref(&p, g->id1);
  pt->v2 = *ss__param_ref(&p, g->id2);
  for (int k = 0; k < g->n; k++)
    pt->durations[k] = g->T * y[k];
  if (ss_model_init(&m, &p, NULL) == SS_OK)
    ss_orbit_equations(&m, g->n, g->modes, pt->durations, pt->z0, F, NULL);
  pt->feasible_side = side;
}

/* The walk's next candidate: the second parameter held on its range's bound
 * when the step leaves it (*at_bound 1); the first parameter, leaving its
 * range, held on its bound, and the curve ends there (*at_bound 2).  1: a
 * candidate; 0: try again with the shorter step; -1: the curve ends here
 * (@a end says why). */
static int gc_candidate(const gcont *g, arc_walk *w, int *at_bound, char *end,
                        size_t end_n) {
  int iq1 = gc_q1(g), iq2 = iq1 + 1;
  *at_bound = 0;
  if (arc_walk_predict(w) != SS_OK) {
    if (!arc_walk_shrink(w))
      return 0;
    snprintf(end, end_n, "the corrector failed at the smallest step");
    return -1;
  }
  if (w->yn[iq2] > g->q2max || w->yn[iq2] < 0) {
    if (arc_walk_onto(w, iq2, w->yn[iq2] > g->q2max ? g->q2max : 0, 1) !=
        SS_OK) {
      if (!arc_walk_shrink(w))
        return 0;
      snprintf(end, end_n, "no grazing orbit on the range's bound");
      return -1;
    }
    *at_bound = 1;
  }
  if (w->yn[iq1] > g->q1max || w->yn[iq1] < 0) {
    if (arc_walk_onto(w, iq1, w->yn[iq1] > g->q1max ? g->q1max : 0, 0) !=
        SS_OK) {
      if (!arc_walk_shrink(w))
        return 0;
      snprintf(end, end_n, "no point of the curve on %s's bound",
               ss_param_name(g->id1));
      return -1;
    }
    *at_bound = 2;
  }
  return 1;
}

/* The candidate's side: a grazing's, the side of p1 on which its orbit
 * exists (which must be one); a period doubling's 0, once its orbit is
 * feasible.  1, 0 and -1 as gc_candidate(). */
static int gc_side(const gcont *g, arc_walk *w, int *side, char *end,
                   size_t end_n) {
  int grazing = g->kind == SS_SPECIAL_GRAZING;
  *side = grazing ? feasible_side(g, w->yn) : gc_feasible(g, w->yn);
  if (*side != 0) {
    if (!grazing)
      *side = 0;
    return 1;
  }
  if (!arc_walk_shrink(w))
    return 0;
  snprintf(end, end_n,
           grazing ? "the grazing stops being the family's boundary (another "
                     "constraint binds) near %s = %.15g"
                   : "the orbit stops being feasible (a grazing) near %s = "
                     "%.15g",
           ss_param_name(g->id2), g->lo2 + g->S2 * w->yn[gc_q1(g) + 1]);
  return -1;
}

/* Follow the curve from its start with p2 going @a dir at the start, at
 * most @a max_points points (an arc_leg_fn). */
static int gc_follow(void *ctx, int dir, int max_points, arc_list *pts,
                     char *end, size_t end_n) {
  gcont *g = ctx;
  arc_walk w;
  int rc;
  if (arc_walk_start(&w, &g->cv, g->y0, gc_q1(g) + 1, dir, g->step, 0.1) !=
      SS_OK) {
    snprintf(end, end_n, "no tangent to the curve at its start");
    return SS_OK;
  }
  while (pts->n < max_points) {
    if (arc_should_stop(&g->clock)) {
      snprintf(end, end_n, "%s", ss_strerror(g->clock.stop));
      return g->clock.stop;
    }
    int at_bound, side, got = gc_candidate(g, &w, &at_bound, end, end_n);
    if (got > 0)
      got = gc_side(g, &w, &side, end, end_n);
    if (got < 0)
      return SS_OK;
    if (got == 0)
      continue;
    ss_curve_point pt;
    gc_point(g, w.yn, side, &pt);
    if ((rc = arc_push(pts, &pt)) != SS_OK)
      return rc;
    arc_walk_accept(&w);
    if (at_bound) {
      snprintf(end, end_n, "the end of the range, %s = %.15g",
               ss_param_name(at_bound == 2 ? g->id1 : g->id2),
               at_bound == 2 ? pt.v1 : pt.v2);
      return SS_OK;
    }
  }
  snprintf(end, end_n, "max_points (%d) reached", g->total_points);
  return SS_OK;
}

void ss_curve_free(ss_curve *c) {
  if (!c)
    return;
  free(c->points);
  memset(c, 0, sizeof *c);
}

/* Whether the special point @a g of kind @a kind of the family @a b can be
 * followed in o2->param: SS_OK or SS_EINVAL with the reason in @a d. */
static int followable(const ss_branch *b, const ss_special *g,
                      ss_special_kind kind, const ss_cont_opts *o2,
                      ss_diag *d) {
  int interior = ss__interior_index(g->margin), k = g->at.min_margin.phase;
  if (kind == SS_SPECIAL_GRAZING &&
      (g->kind != SS_SPECIAL_GRAZING || k < 0 || k >= b->n_phases ||
       (interior < 0 && g->margin != SS_MARGIN_TRANSVERSALITY &&
        (g->margin != SS_MARGIN_SWITCHING || b->modes[k] == SS_MODE_STICK)) ||
       (interior >= 0 && !(g->at.min_margin.t > 0))))
    return ss__fail(d, SS_EINVAL, "special", 0,
                    "only a grazing of the switching condition at the end of "
                    "a slip or overshoot, of a phase's end (transversality), "
                    "or of a margin's maximum inside a phase, can be "
                    "followed");
  if (kind == SS_SPECIAL_PERIOD_DOUBLING &&
      g->kind != SS_SPECIAL_PERIOD_DOUBLING)
    return ss__fail(d, SS_EINVAL, "special", 0, "not a period doubling");
  if (!ss_param_name(b->param) || !ss_param_name(o2->param) ||
      o2->param == b->param)
    return ss__fail(d, SS_EINVAL, "parameter", (double)o2->param,
                    "the second parameter must be another one");
  if (b->physical)
    return ss__fail(d, SS_EINVAL, "parameter", 0,
                    "a family in a physical parameter cannot be followed in "
                    "a second one");
  if (!(b->lo < b->hi) || !(o2->lo < o2->hi) || !isfinite(o2->lo) ||
      !isfinite(o2->hi))
    return ss__fail(d, SS_EINVAL, "range", o2->lo,
                    "a range must be [lo, hi] with lo < hi");
  return SS_OK;
}

/* The curve's problem: the family's parameters with p1 at the special
 * point's value, its phases, unknowns and ranges. */
static void gc_setup(gcont *gc, const ss_params *p, const ss_branch *b,
                     const ss_special *g, ss_special_kind kind,
                     const ss_cont_opts *o2) {
  int interior = ss__interior_index(g->margin);
  memset(gc, 0, sizeof *gc);
  gc->p = *p;
  gc->kind = kind;
  *ss__param_ref(&gc->p, b->param) = g->value;
  gc->id1 = b->param;
  gc->id2 = o2->param;
  gc->n = b->n_phases;
  gc->k = kind == SS_SPECIAL_GRAZING ? g->at.min_margin.phase : 0;
  gc->interior = kind == SS_SPECIAL_GRAZING && interior >= 0;
  gc->margin = interior;
  gc->transversal =
      kind == SS_SPECIAL_GRAZING && g->margin == SS_MARGIN_TRANSVERSALITY;
  memcpy(gc->modes, b->modes, sizeof gc->modes);
  gc->lo1 = b->lo;
  gc->S1 = arc_scale(b->lo, b->hi, g->value);
  gc->q1max = (b->hi - b->lo) / gc->S1;
  gc->lo2 = o2->lo;
  gc->S2 = arc_scale(o2->lo, o2->hi, *ss__param_ref(&gc->p, o2->param));
  gc->q2max = (o2->hi - o2->lo) / gc->S2;
  gc->T = g->at.period;
  gc->cv = (arc_curve){gc_f, gc, gc->n + 1 + gc->interior};
}

/* The curve's first point y0: the located special point @a g, corrected
 * onto the curve with p2 held at its value @a v2.  SS_OK, or SS_ENOCONV
 * when no curve passes there. */
static int gc_start(const gcont *gc, const ss_special *g, double v2, double *y0,
                    ss_diag *d) {
  int iq1 = gc_q1(gc), iters;
  double a[NMAX] = {0}, base[NMAX], res;
  for (int k = 0; k < gc->n; k++)
    y0[k] = g->at.durations[k] / gc->T;
  if (gc->interior)
    y0[gc->n] = g->at.min_margin.t / gc->T;
  y0[iq1] = (g->value - gc->lo1) / gc->S1;
  y0[iq1 + 1] = (v2 - gc->lo2) / gc->S2;
  /* onto the curve exactly (the located grazing is within 1e-10) */
  memcpy(base, y0, sizeof base);
  a[iq1 + 1] = 1;
  if (arc_correct(&gc->cv, y0, a, base, &iters, &res) != SS_OK)
    return ss__fail(d, SS_ENOCONV, "special", g->value,
                    "no curve through the located point");
  /* a tangency's curve passes through its located value; one that does not
   * was no tangency (the family ended otherwise, its smallest margin a
   * slope) */
  double v1 = gc->lo1 + gc->S1 * y0[iq1];
  if (gc->transversal &&
      !(fabs(v1 - g->value) <= fmax(1e-8, 10 * g->precision) * fabs(g->value)))
    return ss__fail(d, SS_ENOCONV, "special", g->value,
                    "the family does not end at a tangency of phase %d's end "
                    "here (the curve of a zero end slope passes %s = %.9g)",
                    gc->k, ss_param_name(gc->id1), v1);
  return SS_OK;
}

/* A special point of kind @a kind of the family @a b followed in a second
 * parameter. */
static int continue_special(const ss_params *p, const ss_branch *b,
                            const ss_special *g, ss_special_kind kind,
                            const ss_cont_opts *o2, ss_curve *cv, ss_diag *d) {
  if (!cv)
    return ss__fail(d, SS_EINVAL, "curve", 0, "no output");
  memset(cv, 0, sizeof *cv);
  if (!p || !b || !g || !o2)
    return ss__fail(d, SS_EINVAL, "opts", 0, "a NULL argument");
  int rc = followable(b, g, kind, o2, d);
  if (rc != SS_OK)
    return rc;
  gcont gc;
  gc_setup(&gc, p, b, g, kind, o2);
  double v2 = *ss__param_ref(&gc.p, gc.id2), y0[NMAX];
  if (!(v2 >= o2->lo && v2 <= o2->hi))
    return ss__fail(d, SS_EINVAL, "range", v2,
                    "the range of %s must contain its value %.15g",
                    ss_param_name(gc.id2), v2);
  if ((rc = gc_start(&gc, g, v2, y0, d)) != SS_OK)
    return rc;
  ss_curve_point first;
  gc_point(&gc, y0, kind == SS_SPECIAL_GRAZING ? feasible_side(&gc, y0) : 0,
           &first);
  arc_clock_start(&gc.clock, o2);
  gc.y0 = y0;
  gc.total_points = o2->max_points ? o2->max_points : 200;
  gc.step = o2->step > 0 ? o2->step : 0.02;
  void *points;
  int leg_rc;
  if (arc_both_ways(gc_follow, &gc, &first, sizeof first, gc.total_points, 0, 0,
                    &points, &cv->n_points, &cv->start, cv->end,
                    &leg_rc) != SS_OK)
    return ss__fail(d, SS_ENOMEM, "points", 0, "out of memory");
  cv->points = points;
  cv->kind = kind;
  cv->margin = kind == SS_SPECIAL_GRAZING ? g->margin : SS_MARGIN_NONE;
  cv->phase = gc.k;
  cv->p1 = gc.id1;
  cv->p2 = gc.id2;
  return arc_leg_status(d, leg_rc, gc.clock.budget, "cancelled");
}

int ss_continue_grazing(const ss_params *p, const ss_branch *b,
                        const ss_special *g, const ss_cont_opts *o2,
                        ss_curve *cv, ss_diag *d) {
  return continue_special(p, b, g, SS_SPECIAL_GRAZING, o2, cv, d);
}

int ss_continue_period_doubling(const ss_params *p, const ss_branch *b,
                                const ss_special *pd, const ss_cont_opts *o2,
                                ss_curve *cv, ss_diag *d) {
  return continue_special(p, b, pd, SS_SPECIAL_PERIOD_DOUBLING, o2, cv, d);
}
