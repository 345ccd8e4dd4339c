/*
 * continue.c: a family of periodic orbits followed in one parameter.
 *
 * The unknowns are y = (tau_1..tau_n, q): the phase durations and the
 * parameter, scaled (p = lo + S q).  The n duration equations of
 * ss_orbit_equations() (the start state eliminated through (5.1)) leave a
 * curve; it is followed by pseudo-arclength (arclength.c).  dF/dtau is the
 * analytic Jacobian; dF/dq is a central difference (h = 1e-6 in q, an error
 * of order 1e-12 that only slows Newton, never moves the root: F itself is
 * exact).  Durations are scaled by the start's period so that a unit of
 * arclength weighs the parameter and the durations alike.
 *
 * A point is accepted only when it is feasible (ss_orbit_check(): every
 * phase ends at its first crossing, into the next mode, without grazing).
 * A step that lands on an infeasible orbit is not taken: the boundary is
 * bisected along the chord between the last feasible point and it (each try
 * corrected onto the family, on the hyperplane normal to the chord), and
 * the family ends at a grazing.  The other special points are sign changes
 * between accepted points, located the same way with regula falsi.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "arclength.h"
#include "continue.h"
#include "internal.h"
#include "modal.h"
#include "orbit.h"
#include "params.h"

#define NMAX ARC_NMAX

static const char *const SPECIAL_NAMES[] = {
    "grazing", "fold", "saddle_node", "period_doubling", "neimark_sacker"};

const char *ss_special_name(ss_special_kind k) {
  return (unsigned)k < 5 ? SPECIAL_NAMES[k] : NULL;
}

void ss_branch_free(ss_branch *b) {
  if (!b)
    return;
  free(b->points);
  memset(b, 0, sizeof *b);
}

typedef struct cont {
  ss_params p; /* the others, as given */
  ss_param_id id;
  int phys; /* continuing the physical parameter pid of ph */
  ss_physical ph;
  ss_phys_id pid;
  int n;
  const ss_mode *modes;
  double lo, hi, S; /* p = lo + S q */
  double T;         /* durations are tau / T in y */
  arc_clock clock;
  arc_curve cv;     /* the duration equations in (tau, q) */
  int total_points; /* max_points, as asked */
  const double *y0; /* the start */
  double step;      /* the first step */
  ss_branch *b;     /* where the special points go */
} cont;

static double value_of(const cont *c, const double *y) {
  return c->lo + c->S * y[c->n];
}

static int model_at(const cont *c, double v, ss_model *m) {
  ss_params p = c->p;
  if (c->phys) {
    ss_physical ph = c->ph;
    *ss__phys_ref(&ph, c->pid) = v;
    if (ss_params_from_physical(&ph, &p, NULL, NULL) != SS_OK)
      return SS_EDOMAIN;
  } else {
    *ss__param_ref(&p, c->id) = v;
  }
  return ss_model_init(m, &p, NULL);
}

/* The name of the continued parameter. */
static const char *cont_name(const cont *c) {
  return c->phys ? ss_phys_name(c->pid) : ss_param_name(c->id);
}

/* F(y) (n values) and, when J is not NULL, dF/dy (n x (n+1), row-major). */
static int eval(const cont *c, const double *y, double *F, double *J,
                double z0[4]) {
  int n = c->n, np = n + 1;
  double tau[SS_MAX_PHASES], Jt[SS_MAX_PHASES * SS_MAX_PHASES];
  ss_model m;
  for (int k = 0; k < n; k++) {
    tau[k] = c->T * y[k];
    if (!(tau[k] > 0))
      return SS_EDOMAIN;
  }
  if (model_at(c, value_of(c, y), &m) != SS_OK)
    return SS_EDOMAIN;
  int rc = ss_orbit_equations(&m, n, c->modes, tau, z0, F, J ? Jt : NULL);
  if (rc != SS_OK || !J)
    return rc;
  for (int i = 0; i < n; i++)
    for (int k = 0; k < n; k++)
      J[np * i + k] = Jt[n * i + k] * c->T;
  double h = 1e-6, Fp[SS_MAX_PHASES], Fm[SS_MAX_PHASES], z[4];
  ss_model mp, mm;
  if (model_at(c, value_of(c, y) + c->S * h, &mp) != SS_OK ||
      model_at(c, value_of(c, y) - c->S * h, &mm) != SS_OK ||
      ss_orbit_equations(&mp, n, c->modes, tau, z, Fp, NULL) != SS_OK ||
      ss_orbit_equations(&mm, n, c->modes, tau, z, Fm, NULL) != SS_OK)
    return SS_EDOMAIN;
  for (int i = 0; i < n; i++)
    J[np * i + n] = (Fp[i] - Fm[i]) / (2 * h);
  return SS_OK;
}

static int cont_f(const void *ctx, const double *y, double *F, double *J) {
  double z0[4];
  return eval(ctx, y, F, J, z0);
}
/* The smallest margin of an orbit, the transversality slope among them,
 * and its name. */
static ss_margin smallest_margin(const ss_orbit *o, ss_margin_id *id) {
  static const ss_margin_id IDS[] = {
      SS_MARGIN_SLIP_BELOW_V,   SS_MARGIN_OVERSHOOT_ABOVE_V,
      SS_MARGIN_STICK_BELOW_UR, SS_MARGIN_STICK_ABOVE_MINUS_UR,
      SS_MARGIN_SWITCHING,      SS_MARGIN_TRANSVERSALITY};
  const ss_margin *all[] = {&o->slip_below,  &o->over_above, &o->stick_upper,
                            &o->stick_lower, &o->switching,  &o->transversal};
  int best = 0;
  for (int k = 1; k < 6; k++)
    if (all[k]->value < all[best]->value)
      best = k;
  if (id)
    *id = IDS[best];
  return *all[best];
}

/* The model and the orbit (modes, durations, start z0 from the duration
 * equations) at the family's point y, unchecked.  *no_model: the
 * parameter's value gives no model (then the rest is not filled). */
static int orbit_at(const cont *c, const double *y, ss_model *m, ss_orbit *o,
                    int *no_model) {
  double F[SS_MAX_PHASES];
  memset(o, 0, sizeof *o);
  *no_model = model_at(c, value_of(c, y), m) != SS_OK;
  if (*no_model)
    return SS_EDOMAIN;
  o->n_phases = c->n;
  o->kind = ss_orbit_kind_of(c->n, c->modes);
  for (int k = 0; k < c->n; k++) {
    o->modes[k] = c->modes[k];
    o->durations[k] = c->T * y[k];
  }
  return ss_orbit_equations(m, c->n, c->modes, o->durations, o->z0, F, NULL);
}

/* The point of the family for the orbit @a o at model @a m: feasibility
 * (ss_orbit_check) and stability.  SS_OK, SS_INFEASIBLE (reason in d), or
 * a failure. */
static int point_of(const cont *c, const ss_model *m, ss_orbit *o, double res,
                    ss_cont_point *pt, ss_diag *d) {
  int rc;
  if ((rc = ss_orbit_check(m, o, d)) != SS_OK)
    return rc;
  ss_stab_opts so = {o->n_turns, 0};
  ss_stab st;
  if ((rc = ss_stability(m, c->n, c->modes, o->durations, o->z0, &so, &st)) !=
      SS_OK)
    return rc == SS_ESINGULAR ? ss__fail(d, SS_INFEASIBLE, "phases", 0,
                                         "a phase ends tangentially (grazing)")
                              : rc;
  memcpy(pt->durations, o->durations, sizeof o->durations);
  pt->period = o->period;
  memcpy(pt->z0, o->z0, sizeof o->z0);
  pt->n_turns = o->n_turns;
  for (int k = 0; k < 2; k++) {
    pt->eig_re[k] = st.eig_re[k];
    pt->eig_im[k] = st.eig_im[k];
  }
  pt->spectral_radius = st.spectral_radius;
  pt->stable = st.stable;
  pt->residual = res;
  pt->min_margin = smallest_margin(o, NULL);
  return SS_OK;
}

/* The point of the family at y.  SS_OK, SS_INFEASIBLE (reason in d), or a
 * failure. */
static int point_at(const cont *c, const double *y, double res,
                    ss_cont_point *pt, ss_diag *d) {
  int no_model;
  ss_model m;
  ss_orbit o;
  memset(pt, 0, sizeof *pt);
  pt->value = value_of(c, y);
  int rc = orbit_at(c, y, &m, &o, &no_model);
  if (no_model)
    return ss__fail(d, SS_INFEASIBLE, cont_name(c), pt->value,
                    "the parameter left its domain");
  if (rc != SS_OK)
    return rc;
  return point_of(c, &m, &o, res, pt, d);
}

/* The smallest margin of the orbit at y (for a grazing). */
static ss_margin_id min_margin_id(const cont *c, const double *y) {
  ss_model m;
  ss_orbit o;
  double F[SS_MAX_PHASES];
  ss_margin_id id = SS_MARGIN_NONE;
  memset(&o, 0, sizeof o);
  if (model_at(c, value_of(c, y), &m) != SS_OK)
    return id;
  o.n_phases = c->n;
  for (int k = 0; k < c->n; k++) {
    o.modes[k] = c->modes[k];
    o.durations[k] = c->T * y[k];
  }
  if (ss_orbit_equations(&m, c->n, c->modes, o.durations, o.z0, F, NULL) ||
      ss_orbit_check(&m, &o, NULL))
    return id;
  smallest_margin(&o, &id);
  return id;
}

/* The point of the family at fraction th of the chord from ya to yb,
 * corrected onto the family on the hyperplane normal to the chord. */
static int on_chord(const cont *c, const double *ya, const double *yb,
                    double th, double *y, double *res) {
  int np = c->n + 1, it;
  double a[NMAX], base[NMAX];
  for (int k = 0; k < np; k++) {
    a[k] = yb[k] - ya[k];
    base[k] = ya[k] + th * a[k];
    y[k] = base[k];
  }
  return arc_correct(&c->cv, y, a, base, &it, res);
}

/* Test functions of the multiplier crossings at a point: det(I - J),
 * det(I + J), and det J - 1 when the multipliers are a complex pair (NAN
 * when they are real). */
static void crossings(const ss_cont_point *pt, double psi[3]) {
  double tr, det;
  if (pt->eig_im[0] != 0) {
    tr = 2 * pt->eig_re[0];
    det = pt->eig_re[0] * pt->eig_re[0] + pt->eig_im[0] * pt->eig_im[0];
  } else {
    tr = pt->eig_re[0] + pt->eig_re[1];
    det = pt->eig_re[0] * pt->eig_re[1];
  }
  psi[0] = 1 - tr + det;
  psi[1] = 1 + tr + det;
  psi[2] = pt->eig_im[0] != 0 ? det - 1 : NAN;
}

/* The value of test function @a which (0..2 crossings, 3 the tangent's
 * parameter component) at the corrected point y. */
static int test_value(const cont *c, const double *y, const double *dir,
                      int which, double res, double *v, ss_cont_point *pt) {
  if (which == 3) {
    double t[NMAX];
    int rc = arc_tangent(&c->cv, y, dir, t);
    if (rc != SS_OK)
      return rc;
    *v = t[c->n];
    return point_at(c, y, res, pt, NULL) == SS_OK ? SS_OK : SS_INFEASIBLE;
  }
  int rc = point_at(c, y, res, pt, NULL);
  if (rc != SS_OK)
    return rc;
  double psi[3];
  crossings(pt, psi);
  *v = psi[which];
  return isnan(*v) ? SS_ENOCONV : SS_OK;
}

static void add_special(ss_branch *b, const ss_special *s) {
  if (b->n_special < SS_MAX_SPECIAL)
    b->special[b->n_special++] = *s;
}

/* The orbit of the family at the parameter value of chord fraction th,
 * solved with its start as unknowns (ss__orbit_solve_full) from the chord's
 * durations and the start interpolated between the ends pa, pb.  Where a
 * real multiplier is +1 the elimination of the start through (5.1) is
 * singular and the duration equations have a pole on the family, so the
 * corrector on the chord fails within about 1e-5 of the crossing; this
 * system does not.  Used between points with no fold between them, where
 * the parameter is monotone along the family. */
static int at_chord_value(const cont *c, const double *ya, const double *yb,
                          const ss_cont_point *pa, const ss_cont_point *pb,
                          double th, double *y, ss_cont_point *pt) {
  int np = c->n + 1;
  double res;
  ss_model m;
  ss_orbit o;
  for (int k = 0; k < np; k++)
    y[k] = ya[k] + th * (yb[k] - ya[k]);
  memset(pt, 0, sizeof *pt);
  memset(&o, 0, sizeof o);
  pt->value = value_of(c, y);
  if (model_at(c, pt->value, &m) != SS_OK)
    return SS_EDOMAIN;
  o.n_phases = c->n;
  o.kind = ss_orbit_kind_of(c->n, c->modes);
  for (int k = 0; k < c->n; k++) {
    o.modes[k] = c->modes[k];
    o.durations[k] = c->T * y[k];
  }
  for (int i = 0; i < 4; i++)
    o.z0[i] = pa->z0[i] + th * (pb->z0[i] - pa->z0[i]);
  int rc = ss__orbit_solve_full(&m, c->n, c->modes, o.durations, o.z0, &res);
  if (rc != SS_OK)
    return rc;
  for (int k = 0; k < c->n; k++)
    y[k] = o.durations[k] / c->T;
  return point_of(c, &m, &o, res, pt, NULL);
}

/* Locate the sign change of test function @a which between the accepted
 * points ya (value fa) and yb (fb) by regula falsi (Illinois) on the chord
 * fraction, to a relative 1e-10 in the parameter. */
static void locate(cont *c, const double *ya, const double *yb,
                   const double *dir, int which, double fa, double fb,
                   const ss_cont_point *pa, const ss_cont_point *pb,
                   ss_special_kind kind, int saddle_node) {
  int np = c->n + 1;
  double lo = 0, hi = 1, flo = fa, fhi = fb, y[NMAX], best[NMAX];
  double res = 0;
  ss_cont_point pt = *pa, pbest = *pa;
  int side = 0, ok = 0;
  double vlo = pa->value, vhi = pb->value; /* the parameter at the ends */
  memcpy(best, ya, sizeof(double) * (size_t)np);
  for (int it = 0; it < 100; it++) {
    double chord = 0;
    for (int k = 0; k < np; k++)
      chord = fmax(chord, fabs(yb[k] - ya[k]) * (hi - lo));
    /* a fold is located on the chord (the parameter is stationary there),
     * the others in the parameter */
    if (kind == SS_SPECIAL_FOLD
            ? chord <= 1e-10
            : fabs(vhi - vlo) <= 1e-10 * fmax(fabs(vlo), DBL_MIN)) {
      ok = 1;
      break;
    }
    double th = lo + flo * (lo - hi) / (fhi - flo);
    if (!(th > lo && th < hi) || it % 4 == 3)
      th = 0.5 * (lo + hi); /* keep the bracket shrinking */
    double f, psi[3];
    if (which == 0 ? at_chord_value(c, ya, yb, pa, pb, th, y, &pt) != SS_OK ||
                         (crossings(&pt, psi), f = psi[0], 0)
                   : on_chord(c, ya, yb, th, y, &res) != SS_OK ||
                         test_value(c, y, dir, which, res, &f, &pt) != SS_OK)
      break;
    memcpy(best, y, sizeof y[0] * (size_t)np);
    pbest = pt;
    if (f == 0) { /* an exact zero: the bracket is the rounding */
      vlo = pt.value;
      vhi = nextafter(vlo, INFINITY);
      ok = 1;
      break;
    }
    if ((f < 0) == (flo < 0)) {
      lo = th;
      flo = f;
      vlo = pt.value;
      if (side == -1)
        fhi /= 2;
      side = -1;
    } else {
      hi = th;
      fhi = f;
      vhi = pt.value;
      if (side == 1)
        flo /= 2;
      side = 1;
    }
  }
  ss_special s;
  memset(&s, 0, sizeof s);
  s.kind = kind;
  s.at = pbest;
  s.value = pbest.value;
  s.precision = fabs(vhi - vlo) / fmax(fabs(s.value), DBL_MIN);
  /* the verdicts below and above the value (at a fold, along the family) */
  const ss_cont_point *below = pa->value <= pb->value ? pa : pb,
                      *above = below == pa ? pb : pa;
  s.stable_before = below->stable;
  s.stable_after = above->stable;
  static const char *const WHAT[] = {
      "", "the family turns back", "a real multiplier crosses +1",
      "a real multiplier crosses -1", "a complex pair crosses the unit circle"};
  /* located: where; not located: the bracket it is known to lie in, and
   * that the orbit given is only the last one tried, at one of its ends */
  char where[160];
  if (ok)
    snprintf(where, sizeof where, "at %.4s = %.15g", cont_name(c), s.value);
  else
    snprintf(where, sizeof where,
             "between %.4s = %.15g and %.15g (not located to 1e-10; the "
             "orbit given is at %.15g)",
             cont_name(c), fmin(vlo, vhi), fmax(vlo, vhi), s.value);
  snprintf(s.detail, sizeof s.detail, "%.40s %.159s%.60s%.40s", WHAT[kind],
           where,
           kind == SS_SPECIAL_FOLD && saddle_node
               ? ", a saddle-node (a real multiplier crosses +1)"
               : "",
           s.stable_before != s.stable_after
               ? (s.stable_before ? "; stable below, unstable above"
                                  : "; unstable below, stable above")
               : "");
  (void)best;
  add_special(c->b, &s);
}

double ss__end_slope(const ss_model *m, int n, const ss_mode *modes,
                     const double *tau, const double z0[4], int k) {
  double x[4], v[2];
  ss_trig ge;
  ss_z_to_x(m, z0, x);
  for (int j = 0; j < k; j++)
    ss_flow(m, modes[j], tau[j], x, x);
  ss__end_switching(m, modes[k], k + 1 < n ? modes[k + 1] : SS_MODE_SLIP, x,
                    &ge);
  ss_trig_eval(&ge, tau[k], 1, v);
  return v[1];
}

/* The end slope of phase k at the family's point y (NAN where the
 * parameter or the equations fail). */
static double slope_at(const cont *c, const double *y, int k) {
  ss_model m;
  ss_orbit o;
  int no_model;
  if (orbit_at(c, y, &m, &o, &no_model) != SS_OK)
    return NAN;
  return ss__end_slope(&m, c->n, c->modes, o.durations, o.z0, k);
}

/* Whether the orbit at the family's point y fails where a phase ends
 * tangentially: at phase k, by a touch (grazing), a maximum just short of
 * zero (phase_end), a crossing before its end (ends_early) or a falling end
 * (transversality), or with a stability that is singular there. */
static int tangential_failure(const cont *c, const double *y, int k) {
  ss_model m;
  ss_orbit o;
  int no_model;
  if (orbit_at(c, y, &m, &o, &no_model) != SS_OK)
    return 0;
  if (ss_orbit_check(&m, &o, NULL) == SS_OK) {
    ss_stab_opts so = {o.n_turns, 0};
    ss_stab st;
    return ss_stability(&m, c->n, c->modes, o.durations, o.z0, &so, &st) ==
           SS_ESINGULAR;
  }
  return o.violation.phase == k && (o.violation_id == SS_MARGIN_GRAZING ||
                                    o.violation_id == SS_MARGIN_PHASE_END ||
                                    o.violation_id == SS_MARGIN_ENDS_EARLY ||
                                    o.violation_id == SS_MARGIN_TRANSVERSALITY);
}

/* A phase that ends tangentially: the feasibility check cannot tell a
 * crossing whose slope is within about sqrt(tol |g''|) of zero from a touch
 * (its rise above zero is below the event tolerance), so the bisection
 * above stops that far from the tangency.  The tangency itself is where
 * the end slope, a smooth function along the family, is zero: Illinois
 * steps on the chord from the last feasible point (th_lo, slope > 0) to yb
 * (slope <= 0), every third a bisection, each try corrected onto the
 * family.  The corrector leaves the slope noisy near 1e-10, so the bracket
 * can stop shrinking before 1e-13: it ends when it is that narrow in the
 * parameter or a few ulps wide in th.  1, the value and the bracket's
 * relative width in *prec (one ulp for an exact zero); 0 when the slope
 * does not change sign on the chord or a try fails. */
static int tangency_on_chord(const cont *c, const double *ya, const double *yb,
                             double th_lo, int k, double *value, double *prec) {
  double y[NMAX], res, a = th_lo, b = 1, fa, fb;
  if (on_chord(c, ya, yb, a, y, &res) != SS_OK ||
      !((fa = slope_at(c, y, k)) > 0))
    return 0;
  double va = value_of(c, y);
  memcpy(y, yb, sizeof y[0] * (size_t)(c->n + 1));
  if (!((fb = slope_at(c, y, k)) <= 0))
    return 0;
  double vb = value_of(c, y);
  int side = 0;
  for (int it = 0; it < 200; it++) {
    double th = (a * fb - b * fa) / (fb - fa), f;
    if (it % 3 == 2 || !(th > a && th < b))
      th = 0.5 * (a + b);
    if (on_chord(c, ya, yb, th, y, &res) != SS_OK ||
        !isfinite(f = slope_at(c, y, k)))
      return 0;
    double v = value_of(c, y);
    if (f == 0) {
      *value = v;
      *prec = DBL_EPSILON;
      return 1;
    }
    if (f > 0) {
      a = th;
      fa = f;
      va = v;
      if (side == -1)
        fb /= 2;
      side = -1;
    } else {
      b = th;
      fb = f;
      vb = v;
      if (side == 1)
        fa /= 2;
      side = 1;
    }
    if (fabs(vb - va) <= 1e-13 * fabs(v) ||
        b - a <= 4 * DBL_EPSILON * fmax(fabs(a), fabs(b))) {
      *value = va - fa * (vb - va) / (fb - fa);
      if (!(*value >= fmin(va, vb) && *value <= fmax(va, vb)))
        *value = 0.5 * (va + vb);
      *prec = fabs(vb - va) / fmax(fabs(*value), DBL_MIN);
      return 1;
    }
  }
  return 0;
}

/* Bisect the feasibility boundary between the feasible ya and the
 * infeasible yb; record the grazing and the last feasible point. */
static void locate_grazing(cont *c, const double *ya, const double *yb,
                           const ss_cont_point *pa, const char *why,
                           ss_cont_point *last) {
  int np = c->n + 1;
  double lo = 0, hi = 1, y[NMAX], ylo[NMAX], res;
  ss_cont_point pt, plo = *pa;
  int ok = 0;
  double vlo = pa->value, vhi = value_of(c, yb);
  memcpy(ylo, ya, sizeof y[0] * (size_t)np);
  for (int it = 0; it < 100; it++) {
    if (fabs(vhi - vlo) <= 1e-10 * fmax(fabs(vlo), DBL_MIN)) {
      ok = 1;
      break;
    }
    double th = 0.5 * (lo + hi);
    int rc = on_chord(c, ya, yb, th, y, &res);
    if (rc == SS_OK)
      rc = point_at(c, y, res, &pt, NULL);
    if (rc == SS_OK) {
      lo = th;
      plo = pt;
      vlo = pt.value;
      memcpy(ylo, y, sizeof y[0] * (size_t)np);
    } else {
      hi = th;
      vhi = value_of(c, y); /* corrected, or the chord's when it failed */
    }
  }
  ss_special s;
  memset(&s, 0, sizeof s);
  s.kind = SS_SPECIAL_GRAZING;
  s.at = plo;
  s.value = plo.value;
  s.precision = fabs(vhi - vlo) / fmax(fabs(s.value), DBL_MIN);
  s.margin = min_margin_id(c, ylo);
  if (s.margin == SS_MARGIN_TRANSVERSALITY) {
    /* a tangency only where the first infeasible point fails at the end of
     * the same phase; then at the zero of the end slope, or said not
     * located */
    double v, prec, yhi[NMAX];
    int k = plo.min_margin.phase;
    if (on_chord(c, ya, yb, hi, yhi, &res) == SS_OK &&
        tangential_failure(c, yhi, k) &&
        tangency_on_chord(c, ya, yb, lo, k, &v, &prec)) {
      s.value = v;
      s.precision = prec;
      ok = prec <= 1e-10;
    } else {
      ok = 0;
    }
  }
  s.stable_before = s.stable_after = plo.stable;
  snprintf(s.detail, sizeof s.detail,
           "the %.24s margin reaches zero in phase %d at %.4s = %.15g%.30s; "
           "beyond: %.200s",
           ss_margin_name(s.margin), plo.min_margin.phase, cont_name(c),
           s.value, ok ? "" : " (not located to 1e-10)", why);
  add_special(c->b, &s);
  *last = plo;
}

/* For a sequence that is a shorter one twice: the difference of the two
 * halves' first durations (0 for an orbit travelled twice); NAN for any
 * other sequence. */
static double asymmetry(int n, const ss_mode *modes, const double *tau) {
  if (n % 2)
    return NAN;
  for (int k = 0; k < n / 2; k++)
    if (modes[k] != modes[k + n / 2])
      return NAN;
  return tau[0] - tau[n / 2];
}

/* The walk's next candidate, held on the range's bound when the step
 * leaves the range (*at_bound).  1: a candidate; 0: try again with the
 * shorter step; -1: the family ends here (@a end says why). */
static int next_candidate(const cont *c, arc_walk *w, int *at_bound, char *end,
                          size_t end_n) {
  int rc = arc_walk_predict(w);
  *at_bound = 0;
  if (rc != SS_OK) {
    if (!arc_walk_shrink(w))
      return 0;
    snprintf(end, end_n,
             "the corrector failed at the smallest step (%s) at %s = %.15g",
             ss_strerror(rc), cont_name(c), value_of(c, w->y));
    return -1;
  }
  /* past the end of the range: the last point is on its bound */
  double vn = value_of(c, w->yn);
  if (!(vn > c->hi || vn < c->lo))
    return 1;
  double bound = vn > c->hi ? c->hi : c->lo;
  if (arc_walk_onto(w, c->n, (bound - c->lo) / c->S, 1) == SS_OK) {
    *at_bound = 1;
    return 1;
  }
  if (!arc_walk_shrink(w))
    return 0;
  snprintf(end, end_n, "no orbit on the bound %s = %.15g", cont_name(c), bound);
  return -1;
}

/* The special points between the accepted points prev (at w->y) and pt (at
 * the candidate w->yn): the multipliers' crossings and a fold. */
static void specials_between(cont *c, const arc_walk *w, int at_bound,
                             const ss_cont_point *prev,
                             const ss_cont_point *pt) {
  static const ss_special_kind KIND[3] = {SS_SPECIAL_SADDLE_NODE,
                                          SS_SPECIAL_PERIOD_DOUBLING,
                                          SS_SPECIAL_NEIMARK_SACKER};
  int n = c->n;
  double pa[3], pb[3];
  crossings(prev, pa);
  crossings(pt, pb);
  /* a fold of the family is a multiplier through +1 of its map: one
   * special point, a fold that says it is a saddle-node */
  int fold = (w->t[n] < 0) != (w->tn[n] < 0) && !at_bound, sn = 0;
  for (int k = 0; k < 3; k++)
    if (!isnan(pa[k]) && !isnan(pb[k]) && (pa[k] < 0) != (pb[k] < 0)) {
      if (k == 0 && fold)
        sn = 1;
      else
        locate(c, w->y, w->yn, w->t, k, pa[k], pb[k], prev, pt, KIND[k], 0);
    }
  if (fold)
    locate(c, w->y, w->yn, w->t, 3, w->t[n], w->tn[n], prev, pt,
           SS_SPECIAL_FOLD, sn);
}

/* Take the candidate after the accepted point *prev: a point of the family
 * (then *prev), or where it ends (*done, with @a end saying why): a
 * grazing, a period-2 family back at its period doubling, the range's
 * bound.  SS_OK or SS_ENOMEM. */
static int take(cont *c, arc_walk *w, int at_bound, ss_cont_point *prev,
                arc_list *pts, int *done, char *end, size_t end_n) {
  int n = c->n, rc;
  ss_cont_point pt;
  ss_diag why;
  ss_diag_clear(&why);
  *done = 1;
  if (point_at(c, w->yn, w->res, &pt, &why) != SS_OK) {
    ss_cont_point last;
    locate_grazing(c, w->y, w->yn, prev, why.text[0] ? why.text : "infeasible",
                   &last);
    if ((rc = arc_push(pts, &last)) != SS_OK)
      return rc;
    snprintf(end, end_n, "grazing at %s = %.15g: %.200s", cont_name(c),
             last.value, why.text);
    return SS_OK;
  }
  /* a period-2 family that meets the orbit it was born from: its halves
   * become equal (and then swap, the same orbit shifted by a period) */
  double a0 = asymmetry(n, c->modes, prev->durations),
         a1 = asymmetry(n, c->modes, pt.durations);
  if ((a0 < 0 && a1 >= 0) || (a0 > 0 && a1 <= 0)) {
    snprintf(end, end_n,
             "returns to the orbit of half its period, at its period "
             "doubling, after %s = %.15g (its halves swap)",
             cont_name(c), prev->value);
    return SS_OK;
  }
  specials_between(c, w, at_bound, prev, &pt);
  if ((rc = arc_push(pts, &pt)) != SS_OK)
    return rc;
  arc_walk_accept(w);
  *prev = pt;
  if (at_bound) {
    snprintf(end, end_n, "the end of the range, %s = %.15g", cont_name(c),
             pt.value);
    return SS_OK;
  }
  *done = 0;
  return SS_OK;
}

/* Follow the family from its start in direction @a dir (+1 up in the
 * parameter at the start, -1 down), at most @a max_points points; the
 * points go to @a pts, the special points to c->b (an arc_leg_fn). */
static int follow(void *ctx, int dir, int max_points, arc_list *pts, char *end,
                  size_t end_n) {
  cont *c = ctx;
  arc_walk w;
  ss_cont_point prev;
  int rc = arc_walk_start(&w, &c->cv, c->y0, c->n, dir, c->step, 0.2);
  if (rc != SS_OK) {
    snprintf(end, end_n, "no tangent at the start (%s)", ss_strerror(rc));
    return SS_OK;
  }
  if (point_at(c, w.y, 0, &prev, NULL) != SS_OK) {
    snprintf(end, end_n, "the start is not feasible");
    return SS_OK;
  }
  while (pts->n < max_points) {
    if (arc_should_stop(&c->clock)) {
      snprintf(end, end_n, "%s", ss_strerror(c->clock.stop));
      return c->clock.stop;
    }
    int at_bound, done, got = next_candidate(c, &w, &at_bound, end, end_n);
    if (got < 0)
      return SS_OK;
    if (got == 0)
      continue;
    if ((rc = take(c, &w, at_bound, &prev, pts, &done, end, end_n)) != SS_OK ||
        done)
      return rc;
  }
  snprintf(end, end_n, "max_points (%d) reached", c->total_points);
  return SS_OK;
}

/* The options checked, and the family's parameter, range and scale set up
 * in @a c and recorded in @a b; the start's value in *v0. */
static int cont_setup(cont *c, const ss_params *p, const ss_cont_opts *opts,
                      ss_branch *b, double *v0, ss_diag *d) {
  if (opts->physical ? !ss_phys_name(opts->phys) : !ss_param_name(opts->param))
    return ss__fail(d, SS_EINVAL, "parameter", (double)opts->param,
                    "unknown parameter");
  if (!(opts->lo < opts->hi) || !isfinite(opts->lo) || !isfinite(opts->hi))
    return ss__fail(d, SS_EINVAL, "range", opts->lo,
                    "the range must be [lo, hi] with lo < hi, both finite");
  if (opts->direction < -1 || opts->direction > 1 || opts->max_points < 0 ||
      !(opts->step >= 0) || !(opts->max_seconds >= 0))
    return ss__fail(d, SS_EINVAL, "opts", 0, "bad options");
  memset(c, 0, sizeof *c);
  c->p = *p;
  c->id = opts->param;
  if (opts->physical) {
    c->phys = 1;
    c->ph = *opts->physical;
    c->pid = opts->phys;
    *v0 = *ss__phys_ref(&c->ph, c->pid);
    if (ss_params_from_physical(&c->ph, &c->p, NULL, d) != SS_OK) {
      /* d says which value and why; the status is the options' */
      if (d)
        d->status = SS_EINVAL;
      return SS_EINVAL;
    }
  } else {
    *v0 = *ss__param_ref(&c->p, c->id);
  }
  if (!(*v0 >= opts->lo && *v0 <= opts->hi))
    return ss__fail(d, SS_EINVAL, "range", *v0,
                    "the start's %s = %.15g is outside the range [%.15g, "
                    "%.15g]",
                    cont_name(c), *v0, opts->lo, opts->hi);
  c->lo = opts->lo;
  c->hi = opts->hi;
  c->S = arc_scale(opts->lo, opts->hi, *v0);
  arc_clock_start(&c->clock, opts);
  c->cv = (arc_curve){cont_f, c, 0};
  c->b = b;
  b->param = opts->param;
  b->physical = opts->physical != NULL;
  b->phys = opts->phys;
  b->lo = opts->lo;
  b->hi = opts->hi;
  return SS_OK;
}

int ss_continue(const ss_params *p, const ss_orbit *start,
                const ss_cont_opts *opts, ss_branch *b, ss_diag *d) {
  if (!b)
    return ss__fail(d, SS_EINVAL, "branch", 0, "no output");
  memset(b, 0, sizeof *b);
  if (!p || !start || !opts)
    return ss__fail(d, SS_EINVAL, "opts", 0, "a NULL argument");
  cont c;
  double v0 = 0;
  int rc = cont_setup(&c, p, opts, b, &v0, d);
  if (rc != SS_OK)
    return rc;
  c.n = start->n_phases;
  c.modes = start->modes;
  c.cv.ne = c.n;
  /* the start, solved again at p */
  ss_model m;
  ss_orbit o;
  if ((rc = ss_model_init(&m, &c.p, d)) != SS_OK ||
      (rc = ss_orbit_solve(&m, start->n_phases, start->modes, start->durations,
                           NULL, &o, d)) != SS_OK)
    return rc;
  c.T = o.period;
  b->n_phases = o.n_phases;
  memcpy(b->modes, o.modes, sizeof o.modes);
  double y0[NMAX];
  for (int k = 0; k < c.n; k++)
    y0[k] = o.durations[k] / c.T;
  y0[c.n] = (v0 - c.lo) / c.S;
  c.y0 = y0;
  c.total_points = opts->max_points ? opts->max_points : 200;
  c.step = opts->step > 0 ? opts->step : 0.02;
  ss_cont_point first;
  if ((rc = point_at(&c, y0, o.residual, &first, d)) != SS_OK)
    return rc;
  void *points;
  int leg_rc;
  if (arc_both_ways(follow, &c, &first, sizeof first, c.total_points,
                    opts->direction, 1, &points, &b->n_points, &b->start,
                    b->end, &leg_rc) != SS_OK)
    return ss__fail(d, SS_ENOMEM, "points", 0, "out of memory");
  b->points = points;
  return arc_leg_status(d, leg_rc, c.clock.budget,
                        "the continuation was cancelled");
}
