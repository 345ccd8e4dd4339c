/*
 * continue.c: a family of periodic orbits followed in one parameter.
 *
 * The unknowns are y = (tau_1..tau_n, q): the phase durations and the
 * parameter, scaled (p = lo + S q).  The n duration equations of
 * ss_orbit_equations() (the start state eliminated through (5.1)) leave a
 * curve; it is followed by pseudo-arclength: a step of ds along the unit
 * tangent t, then Newton on [F(y); t.(y - y_pred)] = 0.  dF/dtau is the
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

#include "internal.h"
#include "linalg.h"

#define NMAX (SS_MAX_PHASES + 3)

/* A curve F(y) = 0 with F from R^(ne + 1) to R^ne: f fills F and, when J
 * is not NULL, dF/dy (ne x (ne + 1), row-major). */
typedef int curve_fn(const void *ctx, const double *y, double *F, double *J);
typedef struct curve {
  curve_fn *f;
  const void *ctx;
  int ne;
} curve;

static const char *const PARAM_NAMES[] = {"chi", "eta", "us", "ur", "V"};

const char *ss_param_name(ss_param_id id) {
  return (unsigned)id < 5 ? PARAM_NAMES[id] : NULL;
}

int ss_param_by_name(const char *name, ss_param_id *id) {
  for (int i = 0; name && id && i < 5; i++)
    if (!strcmp(name, PARAM_NAMES[i])) {
      *id = (ss_param_id)i;
      return SS_OK;
    }
  return SS_EINVAL;
}

static const char *const PHYS_NAMES[] = {"m1", "m2", "k1", "k2",
                                         "Fs", "Fr", "v0"};

const char *ss_phys_name(ss_phys_id id) {
  return (unsigned)id < 7 ? PHYS_NAMES[id] : NULL;
}

int ss_phys_by_name(const char *name, ss_phys_id *id) {
  for (int i = 0; name && id && i < 7; i++)
    if (!strcmp(name, PHYS_NAMES[i])) {
      *id = (ss_phys_id)i;
      return SS_OK;
    }
  return SS_EINVAL;
}

double *ss__phys_ref(ss_physical *ph, ss_phys_id id) {
  double *v[] = {&ph->m1, &ph->m2, &ph->k1, &ph->k2, &ph->Fs, &ph->Fr, &ph->v0};
  return (unsigned)id < 7 ? v[id] : NULL;
}

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

double *ss__param_ref(ss_params *p, ss_param_id id) {
  switch (id) {
  case SS_PARAM_CHI:
    return &p->chi;
  case SS_PARAM_ETA:
    return &p->eta;
  case SS_PARAM_US:
    return &p->us;
  case SS_PARAM_UR:
    return &p->ur;
  case SS_PARAM_V:
    return &p->V;
  }
  return NULL;
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
  double t0, budget;
  int (*cancelled)(void *);
  void *cancel_cls;
  int stop;         /* SS_ELIMIT_TIME or SS_ECANCELED once asked to stop */
  curve cv;         /* the duration equations in (tau, q) */
  int total_points; /* max_points, as asked */
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

/* The scale of a parameter's unknown: its range's width, but no more than
 * ten times its value, so that a very wide range does not make the first
 * step or the difference step leave the parameter's domain. */
static double scale_of(double lo, double hi, double v) {
  double w = hi - lo;
  return v != 0 && w > 10 * fabs(v) ? 10 * fabs(v) : w;
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

/* The unit tangent at y, oriented along @a prev: [J; prev^T] t = e_ne. */
static int tangent(const curve *cv, const double *y, const double *prev,
                   double *t) {
  int n = cv->ne, np = n + 1, piv[NMAX];
  double A[NMAX * NMAX], F[NMAX];
  int rc = cv->f(cv->ctx, y, F, A);
  if (rc != SS_OK)
    return rc;
  for (int k = 0; k < np; k++) {
    A[np * n + k] = prev[k];
    t[k] = 0;
  }
  t[n] = 1;
  if (lu_factor(A, np, piv, 1e-14))
    return SS_ESINGULAR;
  lu_solve(A, np, piv, t);
  double s = 0;
  for (int k = 0; k < np; k++)
    s += t[k] * t[k];
  s = sqrt(s);
  if (!(s > 0) || !isfinite(s))
    return SS_ESINGULAR;
  for (int k = 0; k < np; k++)
    t[k] /= s;
  return SS_OK;
}

/* Newton from @a y (updated in place) on F = 0 and a.(y - base) = 0.
 * Returns SS_OK with the iterations in *iters, or a failure. */
static int correct(const curve *cv, double *y, const double *a,
                   const double *base, int *iters, double *res) {
  int n = cv->ne, np = n + 1, piv[NMAX];
  double A[NMAX * NMAX], F[NMAX], dy_prev = INFINITY;
  for (int it = 1; it <= 12; it++) {
    int rc = cv->f(cv->ctx, y, F, A);
    if (rc != SS_OK)
      return rc;
    double g = 0;
    for (int k = 0; k < np; k++) {
      A[np * n + k] = a[k];
      g += a[k] * (y[k] - base[k]);
    }
    F[n] = g;
    for (int k = 0; k < np; k++)
      F[k] = -F[k];
    if (lu_factor(A, np, piv, 1e-15))
      return SS_ESINGULAR;
    lu_solve(A, np, piv, F);
    double dy = 0, ymax = 1;
    for (int k = 0; k < np; k++) {
      y[k] += F[k];
      dy = fmax(dy, fabs(F[k]));
      ymax = fmax(ymax, fabs(y[k]));
    }
    if (!isfinite(dy) || dy > 1)
      return SS_ENOCONV;
    /* converged, or (an ill-conditioned system) the steps stopped
     * shrinking at the level of rounding */
    int stalled = it >= 4 && dy <= 1e-9 * ymax && dy > 0.5 * dy_prev;
    dy_prev = dy;
    if (dy <= 1e-13 * ymax || stalled) {
      /* the residual at the final iterate */
      if ((rc = cv->f(cv->ctx, y, F, NULL)) != SS_OK)
        return rc;
      double r = 0;
      for (int k = 0; k < n; k++)
        r = fmax(r, fabs(F[k]));
      *iters = it;
      *res = r;
      return r < 1e-9 ? SS_OK : SS_ENOCONV;
    }
  }
  return SS_ENOCONV;
}

/* The smallest margin of an orbit, the transversality slope among them,
 * and its name. */
static ss_margin smallest_margin(const ss_orbit *o, const char **name) {
  static const char *const NAMES[] = {"slip_below_V",   "overshoot_above_V",
                                      "stick_below_ur", "stick_above_minus_ur",
                                      "switching",      "transversality"};
  const ss_margin *all[] = {&o->slip_below,  &o->over_above, &o->stick_upper,
                            &o->stick_lower, &o->switching,  &o->transversal};
  int best = 0;
  for (int k = 1; k < 6; k++)
    if (all[k]->value < all[best]->value)
      best = k;
  if (name)
    *name = NAMES[best];
  return *all[best];
}

/* The orbit at y: feasibility (ss_orbit_check) and stability.  SS_OK,
 * SS_INFEASIBLE (reason in d), or a failure. */
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

static int point_at(const cont *c, const double *y, double res,
                    ss_cont_point *pt, ss_diag *d) {
  int n = c->n, no_model;
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
  if ((rc = ss_orbit_check(&m, &o, d)) != SS_OK)
    return rc;
  ss_stab_opts so = {o.n_turns, 0};
  ss_stab st;
  if ((rc = ss_stability(&m, n, c->modes, o.durations, o.z0, &so, &st)) !=
      SS_OK)
    return rc == SS_ESINGULAR ? ss__fail(d, SS_INFEASIBLE, "phases", 0,
                                         "a phase ends tangentially (grazing)")
                              : rc;
  memcpy(pt->durations, o.durations, sizeof o.durations);
  pt->period = o.period;
  memcpy(pt->z0, o.z0, sizeof o.z0);
  pt->n_turns = o.n_turns;
  for (int k = 0; k < 2; k++) {
    pt->eig_re[k] = st.eig_re[k];
    pt->eig_im[k] = st.eig_im[k];
  }
  pt->spectral_radius = st.spectral_radius;
  pt->stable = st.stable;
  pt->residual = res;
  pt->min_margin = smallest_margin(&o, NULL);
  return SS_OK;
}

/* The name of the smallest margin of the orbit at y (for a grazing). */
static const char *min_margin_name(const cont *c, const double *y) {
  ss_model m;
  ss_orbit o;
  double F[SS_MAX_PHASES];
  const char *name = "unknown";
  memset(&o, 0, sizeof o);
  if (model_at(c, value_of(c, y), &m) != SS_OK)
    return name;
  o.n_phases = c->n;
  for (int k = 0; k < c->n; k++) {
    o.modes[k] = c->modes[k];
    o.durations[k] = c->T * y[k];
  }
  if (ss_orbit_equations(&m, c->n, c->modes, o.durations, o.z0, F, NULL) ||
      ss_orbit_check(&m, &o, NULL))
    return name;
  smallest_margin(&o, &name);
  return name;
}

static int should_stop(cont *c) {
  if (c->stop)
    return 1;
  if (c->cancelled && c->cancelled(c->cancel_cls))
    c->stop = SS_ECANCELED;
  else if (c->budget > 0 && ss__now() - c->t0 > c->budget)
    c->stop = SS_ELIMIT_TIME;
  return c->stop != 0;
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
  return correct(&c->cv, y, a, base, &it, res);
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
    int rc = tangent(&c->cv, y, dir, t);
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

/* Locate the sign change of test function @a which between the accepted
 * points ya (value fa) and yb (fb) by regula falsi (Illinois) on the chord
 * fraction, to a relative 1e-10 in the parameter. */
static void locate(cont *c, const double *ya, const double *yb,
                   const double *dir, int which, double fa, double fb,
                   const ss_cont_point *pa, const ss_cont_point *pb,
                   ss_special_kind kind, int saddle_node, ss_branch *b) {
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
    double f;
    if (on_chord(c, ya, yb, th, y, &res) != SS_OK ||
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
  snprintf(s.detail, sizeof s.detail, "%.40s at %.4s = %.15g%.60s%.40s%.30s",
           WHAT[kind], cont_name(c), s.value,
           kind == SS_SPECIAL_FOLD && saddle_node
               ? ", a saddle-node (a real multiplier crosses +1)"
               : "",
           s.stable_before != s.stable_after
               ? (s.stable_before ? "; stable below, unstable above"
                                  : "; unstable below, stable above")
               : "",
           ok ? "" : " (not located to 1e-10)");
  (void)best;
  add_special(b, &s);
}

/* The slope at the end of phase k of the function that ends it, as
 * ss_orbit_check() takes it (its transversality margin there), by the
 * closed form of the phases from z0. */
static double end_slope(const ss_model *m, int n, const ss_mode *modes,
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
  return end_slope(&m, c->n, c->modes, o.durations, o.z0, k);
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
  return o.violation.phase == k &&
         (!strcmp(o.violation_name, "grazing") ||
          !strcmp(o.violation_name, "phase_end") ||
          !strcmp(o.violation_name, "ends_early") ||
          !strcmp(o.violation_name, "transversality"));
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
                           ss_branch *b, ss_cont_point *last) {
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
  snprintf(s.margin, sizeof s.margin, "%s", min_margin_name(c, ylo));
  if (!strcmp(s.margin, "transversality")) {
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
           s.margin, plo.min_margin.phase, cont_name(c), s.value,
           ok ? "" : " (not located to 1e-10)", why);
  add_special(b, &s);
  *last = plo;
}

static int push(ss_cont_point **v, int *n, int *cap, const ss_cont_point *p) {
  if (*n == *cap) {
    int nc = *cap ? 2 * *cap : 64;
    ss_cont_point *w = realloc(*v, (size_t)nc * sizeof *w);
    if (!w)
      return SS_ENOMEM;
    *v = w;
    *cap = nc;
  }
  (*v)[(*n)++] = *p;
  return SS_OK;
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

/* Follow the family from y0 in direction @a dir (+1 up in the parameter at
 * the start, -1 down); the points go to *v, the specials to b. */
static int follow(cont *c, const double *y0, int dir, double step0,
                  int max_points, ss_cont_point **v, int *nv, int *cap,
                  ss_branch *b, char *end, size_t end_n) {
  int n = c->n, np = n + 1;
  double y[NMAX], t[NMAX], e[NMAX] = {0};
  memcpy(y, y0, sizeof y[0] * (size_t)np);
  e[n] = dir;
  int rc = tangent(&c->cv, y, e, t);
  if (rc != SS_OK) {
    snprintf(end, end_n, "no tangent at the start (%s)", ss_strerror(rc));
    return SS_OK;
  }
  double ds = step0, ds_min = 1e-9, ds_max = 0.2;
  ss_cont_point prev;
  double res0 = 0;
  if ((rc = point_at(c, y, res0, &prev, NULL)) != SS_OK) {
    snprintf(end, end_n, "the start is not feasible");
    return SS_OK;
  }
  while (*nv < max_points) {
    if (should_stop(c)) {
      snprintf(end, end_n, "%s", ss_strerror(c->stop));
      return c->stop;
    }
    double yn[NMAX], tn[NMAX], res;
    int iters;
    for (int k = 0; k < np; k++)
      yn[k] = y[k] + ds * t[k];
    rc = correct(&c->cv, yn, t, yn, &iters, &res);
    if (rc == SS_OK)
      rc = tangent(&c->cv, yn, t, tn);
    double dot = 0;
    for (int k = 0; rc == SS_OK && k < np; k++)
      dot += t[k] * tn[k];
    if (rc != SS_OK || dot < 0.95) {
      if ((ds *= 0.5) < ds_min) {
        snprintf(end, end_n,
                 "the corrector failed at the smallest step (%s) at %s = "
                 "%.15g",
                 ss_strerror(rc != SS_OK ? rc : SS_ENOCONV), cont_name(c),
                 value_of(c, y));
        return SS_OK;
      }
      continue;
    }
    /* past the end of the range: the last point is on its bound */
    double vn = value_of(c, yn);
    int at_bound = 0;
    if (vn > c->hi || vn < c->lo) {
      double bound = vn > c->hi ? c->hi : c->lo;
      double a[NMAX] = {0}, base[NMAX];
      memcpy(base, yn, sizeof base);
      a[n] = 1;
      base[n] = (bound - c->lo) / c->S;
      memcpy(yn, y, sizeof yn);
      yn[n] = base[n];
      if (correct(&c->cv, yn, a, base, &iters, &res) != SS_OK ||
          tangent(&c->cv, yn, t, tn) != SS_OK) {
        if ((ds *= 0.5) < ds_min) {
          snprintf(end, end_n, "no orbit on the bound %s = %.15g", cont_name(c),
                   bound);
          return SS_OK;
        }
        continue;
      }
      yn[n] = base[n];
      at_bound = 1;
    }
    ss_cont_point pt;
    ss_diag why;
    ss_diag_clear(&why);
    rc = point_at(c, yn, res, &pt, &why);
    if (rc != SS_OK) {
      ss_cont_point last;
      locate_grazing(c, y, yn, &prev, why.text[0] ? why.text : "infeasible", b,
                     &last);
      if ((rc = push(v, nv, cap, &last)) != SS_OK)
        return rc;
      snprintf(end, end_n, "grazing at %s = %.15g: %.200s", cont_name(c),
               last.value, why.text);
      return SS_OK;
    }
    /* a period-2 family that meets the orbit it was born from: its halves
     * become equal (and then swap, the same orbit shifted by a period) */
    double a0 = asymmetry(n, c->modes, prev.durations),
           a1 = asymmetry(n, c->modes, pt.durations);
    if ((a0 < 0 && a1 >= 0) || (a0 > 0 && a1 <= 0)) {
      snprintf(end, end_n,
               "returns to the orbit of half its period, at its period "
               "doubling, after %s = %.15g (its halves swap)",
               cont_name(c), prev.value);
      return SS_OK;
    }
    /* sign changes between prev and pt */
    double pa[3], pb[3];
    crossings(&prev, pa);
    crossings(&pt, pb);
    static const ss_special_kind KIND[3] = {SS_SPECIAL_SADDLE_NODE,
                                            SS_SPECIAL_PERIOD_DOUBLING,
                                            SS_SPECIAL_NEIMARK_SACKER};
    /* a fold of the family is a multiplier through +1 of its map: one
     * special point, a fold that says it is a saddle-node */
    int fold = (t[n] < 0) != (tn[n] < 0) && !at_bound, sn = 0;
    for (int k = 0; k < 3; k++)
      if (!isnan(pa[k]) && !isnan(pb[k]) && (pa[k] < 0) != (pb[k] < 0)) {
        if (k == 0 && fold)
          sn = 1;
        else
          locate(c, y, yn, t, k, pa[k], pb[k], &prev, &pt, KIND[k], 0, b);
      }
    if (fold)
      locate(c, y, yn, t, 3, t[n], tn[n], &prev, &pt, SS_SPECIAL_FOLD, sn, b);
    if ((rc = push(v, nv, cap, &pt)) != SS_OK)
      return rc;
    memcpy(y, yn, sizeof y);
    memcpy(t, tn, sizeof t);
    prev = pt;
    if (at_bound) {
      snprintf(end, end_n, "the end of the range, %s = %.15g", cont_name(c),
               pt.value);
      return SS_OK;
    }
    if (iters <= 3)
      ds = fmin(ds * 1.5, ds_max);
    else if (iters >= 6)
      ds *= 0.6;
  }
  snprintf(end, end_n, "max_points (%d) reached", c->total_points);
  return SS_OK;
}

int ss_continue(const ss_params *p, const ss_orbit *start,
                const ss_cont_opts *opts, ss_branch *b, ss_diag *d) {
  if (!b)
    return ss__fail(d, SS_EINVAL, "branch", 0, "no output");
  memset(b, 0, sizeof *b);
  if (!p || !start || !opts)
    return ss__fail(d, SS_EINVAL, "opts", 0, "a NULL argument");
  if (opts->physical ? !ss_phys_name(opts->phys) : !ss_param_name(opts->param))
    return ss__fail(d, SS_EINVAL, "parameter", (double)opts->param,
                    "unknown parameter");
  if (!(opts->lo < opts->hi) || !isfinite(opts->lo) || !isfinite(opts->hi))
    return ss__fail(d, SS_EINVAL, "range", opts->lo,
                    "the range must be [lo, hi] with lo < hi, both finite");
  if (opts->direction < -1 || opts->direction > 1 || opts->max_points < 0 ||
      !(opts->step >= 0) || !(opts->max_seconds >= 0))
    return ss__fail(d, SS_EINVAL, "opts", 0, "bad options");
  cont c;
  memset(&c, 0, sizeof c);
  c.p = *p;
  c.id = opts->param;
  double v0;
  if (opts->physical) {
    c.phys = 1;
    c.ph = *opts->physical;
    c.pid = opts->phys;
    v0 = *ss__phys_ref(&c.ph, c.pid);
    if (ss_params_from_physical(&c.ph, &c.p, NULL, d) != SS_OK)
      return ss__fail(d, SS_EINVAL, "physical", 0, "bad physical parameters");
  } else {
    v0 = *ss__param_ref(&c.p, c.id);
  }
  if (!(v0 >= opts->lo && v0 <= opts->hi))
    return ss__fail(d, SS_EINVAL, "range", v0,
                    "the start's %s = %.15g is outside the range [%.15g, "
                    "%.15g]",
                    cont_name(&c), v0, opts->lo, opts->hi);
  c.n = start->n_phases;
  c.modes = start->modes;
  c.lo = opts->lo;
  c.hi = opts->hi;
  c.S = scale_of(opts->lo, opts->hi, v0);
  c.t0 = ss__now();
  c.budget = opts->max_seconds;
  c.cancelled = opts->cancelled;
  c.cancel_cls = opts->cancel_cls;
  c.cv = (curve){cont_f, &c, c.n};
  /* the start, solved again at p */
  ss_model m;
  ss_orbit o;
  int rc = ss_model_init(&m, &c.p, d);
  if (rc != SS_OK)
    return rc;
  if ((rc = ss_orbit_solve(&m, start->n_phases, start->modes, start->durations,
                           NULL, &o, d)) != SS_OK)
    return rc;
  c.T = o.period;
  b->n_phases = o.n_phases;
  memcpy(b->modes, o.modes, sizeof o.modes);
  double y0[NMAX];
  for (int k = 0; k < c.n; k++)
    y0[k] = o.durations[k] / c.T;
  y0[c.n] = (v0 - c.lo) / c.S;
  int max_points = opts->max_points ? opts->max_points : 200;
  double step = opts->step > 0 ? opts->step : 0.02;
  ss_cont_point *down = NULL, *up = NULL, first;
  int nd = 0, cd = 0, nu = 0, cu = 0;
  if ((rc = point_at(&c, y0, o.residual, &first, d)) != SS_OK)
    return rc;
  int budget_down = opts->direction == 0 ? (max_points - 1) / 2 : 0;
  int budget_up = max_points - 1 - budget_down;
  if (opts->direction == -1) {
    budget_down = max_points - 1;
    budget_up = 0;
  }
  int rc_down = SS_OK, rc_up = SS_OK;
  c.total_points = max_points;
  if (budget_down > 0)
    rc_down = follow(&c, y0, -1, step, budget_down, &down, &nd, &cd, b,
                     b->end[0], sizeof b->end[0]);
  else if (opts->direction == 0)
    snprintf(b->end[0], sizeof b->end[0], "max_points (%d) reached",
             max_points);
  /* going up gets what going down left of the budget */
  if (opts->direction == 0)
    budget_up = max_points - 1 - nd;
  if (budget_up > 0 && rc_down != SS_ENOMEM)
    rc_up = follow(&c, y0, +1, step, budget_up, &up, &nu, &cu, b, b->end[1],
                   sizeof b->end[1]);
  else if (opts->direction != -1)
    snprintf(b->end[1], sizeof b->end[1], "max_points (%d) reached",
             max_points);
  b->points = malloc((size_t)(nd + nu + 1) * sizeof *b->points);
  if (!b->points) {
    free(down);
    free(up);
    return ss__fail(d, SS_ENOMEM, "points", 0, "out of memory");
  }
  for (int k = 0; k < nd; k++)
    b->points[k] = down[nd - 1 - k];
  b->points[nd] = first;
  for (int k = 0; k < nu; k++)
    b->points[nd + 1 + k] = up[k];
  b->n_points = nd + nu + 1;
  b->start = nd;
  free(down);
  free(up);
  rc = rc_down != SS_OK ? rc_down : rc_up;
  if (rc != SS_OK)
    return ss__fail(d, rc, "max_seconds", c.budget, "%s",
                    rc == SS_ECANCELED ? "the continuation was cancelled"
                                       : "the time budget ran out");
  return SS_OK;
}

/* ---- a grazing followed in two parameters ------------------------------ */

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
  /* an interior grazing: the margin (its index in INTERIOR) has a zero
   * maximum inside phase k, at local time t* = T y[n], one more unknown */
  int interior, margin;
  /* a transversality grazing: phase k ends tangentially, the slope of its
   * switching function zero at its end */
  int transversal;
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

/* The margins that can have an interior zero maximum, by name, and their
 * value at the state x (>= 0 when the constraint holds). */
static const char *const INTERIOR[] = {"slip_below_V", "overshoot_above_V",
                                       "stick_below_ur",
                                       "stick_above_minus_ur"};

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
    F[g->n] = end_slope(&m, g->n, g->modes, tau, z0, g->k) * g->T;
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

static int gc_push(ss_curve_point **v, int *n, int *cap,
                   const ss_curve_point *p) {
  if (*n == *cap) {
    int nc = *cap ? 2 * *cap : 64;
    ss_curve_point *w = realloc(*v, (size_t)nc * sizeof *w);
    if (!w)
      return SS_ENOMEM;
    *v = w;
    *cap = nc;
  }
  (*v)[(*n)++] = *p;
  return SS_OK;
}

/* Follow the curve from y0 with p2 going @a dir at the start. */
static int gc_follow(const gcont *g, cont *stop, const double *y0, int dir,
                     double step, int max_points, ss_curve_point **v, int *nv,
                     int *cap, char *end, size_t end_n) {
  int nu = g->n + 2 + g->interior, iq1 = gc_q1(g), iq2 = iq1 + 1, iters;
  curve cv = {gc_f, g, g->n + 1 + g->interior};
  double y[NMAX], t[NMAX], e[NMAX] = {0}, res;
  memcpy(y, y0, sizeof y[0] * (size_t)nu);
  e[iq2] = dir;
  if (tangent(&cv, y, e, t) != SS_OK) {
    snprintf(end, end_n, "no tangent to the curve at its start");
    return SS_OK;
  }
  double ds = step, ds_min = 1e-9, ds_max = 0.1;
  while (*nv < max_points) {
    if (should_stop(stop)) {
      snprintf(end, end_n, "%s", ss_strerror(stop->stop));
      return stop->stop;
    }
    double yn[NMAX], tn[NMAX];
    for (int k = 0; k < nu; k++)
      yn[k] = y[k] + ds * t[k];
    int rc = correct(&cv, yn, t, yn, &iters, &res);
    if (rc == SS_OK)
      rc = tangent(&cv, yn, t, tn);
    double dot = 0;
    for (int k = 0; rc == SS_OK && k < nu; k++)
      dot += t[k] * tn[k];
    if (rc != SS_OK || dot < 0.95) {
      if ((ds *= 0.5) < ds_min) {
        snprintf(end, end_n, "the corrector failed at the smallest step");
        return SS_OK;
      }
      continue;
    }
    /* the ranges: the last point on the bound of the second parameter; the
     * first parameter leaving its range ends the curve where it left */
    int at_bound = 0;
    if (yn[iq2] > g->q2max || yn[iq2] < 0) {
      double a[NMAX] = {0}, base[NMAX];
      memcpy(base, yn, sizeof base);
      a[iq2] = 1;
      base[iq2] = yn[iq2] > g->q2max ? g->q2max : 0;
      memcpy(yn, y, sizeof yn);
      yn[iq2] = base[iq2];
      if (correct(&cv, yn, a, base, &iters, &res) != SS_OK ||
          tangent(&cv, yn, t, tn) != SS_OK) {
        if ((ds *= 0.5) < ds_min) {
          snprintf(end, end_n, "no grazing orbit on the range's bound");
          return SS_OK;
        }
        continue;
      }
      yn[iq2] = base[iq2];
      at_bound = 1;
    }
    if (yn[iq1] > g->q1max || yn[iq1] < 0) {
      /* the first parameter leaves its range: the last point on its
       * bound, and the curve ends there */
      double a[NMAX] = {0}, base[NMAX];
      memcpy(base, yn, sizeof base);
      a[iq1] = 1;
      base[iq1] = yn[iq1] > g->q1max ? g->q1max : 0;
      memcpy(yn, y, sizeof yn);
      yn[iq1] = base[iq1];
      if (correct(&cv, yn, a, base, &iters, &res) != SS_OK) {
        if ((ds *= 0.5) < ds_min) {
          snprintf(end, end_n, "no point of the curve on %s's bound",
                   ss_param_name(g->id1));
          return SS_OK;
        }
        continue;
      }
      yn[iq1] = base[iq1];
      at_bound = 2;
    }
    int side = g->kind == SS_SPECIAL_GRAZING ? feasible_side(g, yn)
                                             : gc_feasible(g, yn);
    if (side == 0 && g->kind != SS_SPECIAL_GRAZING) {
      if ((ds *= 0.5) < ds_min) {
        snprintf(end, end_n,
                 "the orbit stops being feasible (a grazing) near %s = %.15g",
                 ss_param_name(g->id2), g->lo2 + g->S2 * yn[iq2]);
        return SS_OK;
      }
      continue;
    }
    if (g->kind != SS_SPECIAL_GRAZING)
      side = 0;
    else if (side == 0) {
      if ((ds *= 0.5) < ds_min) {
        snprintf(end, end_n,
                 "the grazing stops being the family's boundary (another "
                 "constraint binds) near %s = %.15g",
                 ss_param_name(g->id2), g->lo2 + g->S2 * yn[iq2]);
        return SS_OK;
      }
      continue;
    }
    ss_curve_point pt;
    gc_point(g, yn, side, &pt);
    if ((rc = gc_push(v, nv, cap, &pt)) != SS_OK)
      return rc;
    memcpy(y, yn, sizeof y);
    memcpy(t, tn, sizeof t);
    if (at_bound) {
      snprintf(end, end_n, "the end of the range, %s = %.15g",
               ss_param_name(at_bound == 2 ? g->id1 : g->id2),
               at_bound == 2 ? pt.v1 : pt.v2);
      return SS_OK;
    }
    if (iters <= 3)
      ds = fmin(ds * 1.5, ds_max);
    else if (iters >= 6)
      ds *= 0.6;
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

/* A special point of kind @a kind followed in a second parameter. */
static int continue_special(const ss_params *p, const ss_branch *b,
                            const ss_special *g, ss_special_kind kind,
                            ss_param_id p1, double lo1, double hi1,
                            const ss_cont_opts *o2, ss_curve *cv, ss_diag *d) {
  if (!cv)
    return ss__fail(d, SS_EINVAL, "curve", 0, "no output");
  memset(cv, 0, sizeof *cv);
  if (!p || !b || !g || !o2)
    return ss__fail(d, SS_EINVAL, "opts", 0, "a NULL argument");
  int interior = -1;
  for (int i = 0; i < 4; i++)
    if (!strcmp(g->margin, INTERIOR[i]))
      interior = i;
  int transversal = !strcmp(g->margin, "transversality");
  if (kind == SS_SPECIAL_GRAZING &&
      (g->kind != SS_SPECIAL_GRAZING || g->at.min_margin.phase < 0 ||
       g->at.min_margin.phase >= b->n_phases ||
       (interior < 0 && !transversal &&
        (strcmp(g->margin, "switching") ||
         b->modes[g->at.min_margin.phase] == SS_MODE_STICK)) ||
       (interior >= 0 && !(g->at.min_margin.t > 0))))
    return ss__fail(d, SS_EINVAL, "special", 0,
                    "only a grazing of the switching condition at the end of "
                    "a slip or overshoot, of a phase's end (transversality), "
                    "or of a margin's maximum inside a phase, can be "
                    "followed");
  if (kind == SS_SPECIAL_PERIOD_DOUBLING &&
      g->kind != SS_SPECIAL_PERIOD_DOUBLING)
    return ss__fail(d, SS_EINVAL, "special", 0, "not a period doubling");
  if (!ss_param_name(p1) || !ss_param_name(o2->param) || o2->param == p1)
    return ss__fail(d, SS_EINVAL, "parameter", (double)o2->param,
                    "the second parameter must be another one");
  if (!(lo1 < hi1) || !(o2->lo < o2->hi) || !isfinite(o2->lo) ||
      !isfinite(o2->hi))
    return ss__fail(d, SS_EINVAL, "range", o2->lo,
                    "a range must be [lo, hi] with lo < hi");
  gcont gc;
  memset(&gc, 0, sizeof gc);
  gc.p = *p;
  gc.kind = kind;
  *ss__param_ref(&gc.p, p1) = g->value;
  gc.id1 = p1;
  gc.id2 = o2->param;
  gc.n = b->n_phases;
  gc.k = kind == SS_SPECIAL_GRAZING ? g->at.min_margin.phase : 0;
  gc.interior = kind == SS_SPECIAL_GRAZING && interior >= 0;
  gc.margin = interior;
  gc.transversal = kind == SS_SPECIAL_GRAZING && transversal;
  memcpy(gc.modes, b->modes, sizeof gc.modes);
  gc.lo1 = lo1;
  gc.S1 = scale_of(lo1, hi1, g->value);
  gc.q1max = (hi1 - lo1) / gc.S1;
  gc.lo2 = o2->lo;
  gc.S2 = scale_of(o2->lo, o2->hi, *ss__param_ref(&gc.p, o2->param));
  gc.q2max = (o2->hi - o2->lo) / gc.S2;
  gc.T = g->at.period;
  double v2 = *ss__param_ref(&gc.p, gc.id2);
  if (!(v2 >= o2->lo && v2 <= o2->hi))
    return ss__fail(d, SS_EINVAL, "range", v2,
                    "the range of %s must contain its value %.15g",
                    ss_param_name(gc.id2), v2);
  double y0[NMAX];
  for (int k = 0; k < gc.n; k++)
    y0[k] = g->at.durations[k] / gc.T;
  int iq1 = gc_q1(&gc);
  if (gc.interior)
    y0[gc.n] = g->at.min_margin.t / gc.T;
  y0[iq1] = (g->value - lo1) / gc.S1;
  y0[iq1 + 1] = (v2 - gc.lo2) / gc.S2;
  /* onto the curve exactly (the located grazing is within 1e-10) */
  curve c = {gc_f, &gc, gc.n + 1 + gc.interior};
  double a[NMAX] = {0}, base[NMAX];
  int iters;
  double res;
  memcpy(base, y0, sizeof base);
  a[iq1 + 1] = 1;
  int rc = correct(&c, y0, a, base, &iters, &res);
  if (rc != SS_OK)
    return ss__fail(d, SS_ENOCONV, "special", g->value,
                    "no curve through the located point");
  /* a tangency's curve passes through its located value; one that does not
   * was no tangency (the family ended otherwise, its smallest margin a
   * slope) */
  double v1 = gc.lo1 + gc.S1 * y0[iq1];
  if (gc.transversal &&
      !(fabs(v1 - g->value) <= fmax(1e-8, 10 * g->precision) * fabs(g->value)))
    return ss__fail(d, SS_ENOCONV, "special", g->value,
                    "the family does not end at a tangency of phase %d's end "
                    "here (the curve of a zero end slope passes %s = %.9g)",
                    gc.k, ss_param_name(gc.id1), v1);
  int side = kind == SS_SPECIAL_GRAZING ? feasible_side(&gc, y0) : 0;
  cont stop;
  memset(&stop, 0, sizeof stop);
  stop.t0 = ss__now();
  stop.budget = o2->max_seconds;
  stop.cancelled = o2->cancelled;
  stop.cancel_cls = o2->cancel_cls;
  int max_points = o2->max_points ? o2->max_points : 200;
  double step = o2->step > 0 ? o2->step : 0.02;
  ss_curve_point *down = NULL, *up = NULL, first;
  int nd = 0, cd = 0, nu = 0, cu = 0;
  gc_point(&gc, y0, side, &first);
  int bd = (max_points - 1) / 2, bu;
  gc.total_points = max_points;
  int rc_d = bd > 0 ? gc_follow(&gc, &stop, y0, -1, step, bd, &down, &nd, &cd,
                                cv->end[0], sizeof cv->end[0])
                    : SS_OK;
  bu = max_points - 1 - nd; /* what going down left of the budget */
  int rc_u = bu > 0 && rc_d != SS_ENOMEM
                 ? gc_follow(&gc, &stop, y0, +1, step, bu, &up, &nu, &cu,
                             cv->end[1], sizeof cv->end[1])
                 : SS_OK;
  cv->points = malloc((size_t)(nd + nu + 1) * sizeof *cv->points);
  if (!cv->points) {
    free(down);
    free(up);
    return ss__fail(d, SS_ENOMEM, "points", 0, "out of memory");
  }
  for (int k = 0; k < nd; k++)
    cv->points[k] = down[nd - 1 - k];
  cv->points[nd] = first;
  for (int k = 0; k < nu; k++)
    cv->points[nd + 1 + k] = up[k];
  cv->n_points = nd + nu + 1;
  cv->start = nd;
  cv->kind = kind;
  snprintf(cv->margin, sizeof cv->margin, "%s",
           kind == SS_SPECIAL_GRAZING ? g->margin : "");
  cv->phase = gc.k;
  cv->p1 = p1;
  cv->p2 = gc.id2;
  free(down);
  free(up);
  rc = rc_d != SS_OK ? rc_d : rc_u;
  if (rc != SS_OK)
    return ss__fail(d, rc, "max_seconds", stop.budget, "%s",
                    rc == SS_ECANCELED ? "cancelled"
                                       : "the time budget ran out");
  return SS_OK;
}

int ss_continue_grazing(const ss_params *p, const ss_branch *b,
                        const ss_special *g, ss_param_id p1, double lo1,
                        double hi1, const ss_cont_opts *o2, ss_curve *cv,
                        ss_diag *d) {
  return continue_special(p, b, g, SS_SPECIAL_GRAZING, p1, lo1, hi1, o2, cv, d);
}

int ss_continue_period_doubling(const ss_params *p, const ss_branch *b,
                                const ss_special *pd, ss_param_id p1,
                                double lo1, double hi1, const ss_cont_opts *o2,
                                ss_curve *cv, ss_diag *d) {
  return continue_special(p, b, pd, SS_SPECIAL_PERIOD_DOUBLING, p1, lo1, hi1,
                          o2, cv, d);
}

/* ---- the period-2 family at a period doubling ------------------------- */

int ss_continue_period2(const ss_params *p, const ss_branch *b,
                        const ss_special *pd, const ss_cont_opts *o,
                        ss_branch *out, ss_diag *d) {
  if (!out)
    return ss__fail(d, SS_EINVAL, "branch", 0, "no output");
  memset(out, 0, sizeof *out);
  if (!p || !b || !pd || !o || !ss_param_name(o->param))
    return ss__fail(d, SS_EINVAL, "opts", 0, "a NULL argument");
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
      if (ss_model_init(&m, &q, NULL) != SS_OK ||
          ss_orbit_find(&m, &oo, found, 32, &nf, NULL, NULL) != SS_OK)
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

/* ---- beyond a grazing: the attractor simulation reaches ---------------- */

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

int ss_beyond_grazing(const ss_params *p, const ss_branch *b,
                      const ss_special *g, ss_param_id param, double *value,
                      ss_attractor *a) {
  if (!p || !b || !g || !value || !a || g->kind != SS_SPECIAL_GRAZING ||
      !ss_param_name(param) || b->n_points < 2)
    return SS_EINVAL;
  /* the family lies on one side of the grazing: its neighbour says which
   * (the family's last point is g->at; g->value is past it by the location's
   * precision, or at a tangential end by the band the check cannot decide) */
  int at = -1;
  for (int i = 0; i < b->n_points; i++)
    if (b->points[i].value == g->at.value)
      at = i;
  if (at < 0 || (at != 0 && at != b->n_points - 1))
    return SS_EINVAL;
  double toward = b->points[at == 0 ? 1 : at - 1].value - g->value;
  ss_params q = *p;
  *value = g->value * (1 - (toward > 0 ? 1e-4 : -1e-4));
  *ss__param_ref(&q, param) = *value;
  ss_model m;
  if (ss_model_init(&m, &q, NULL) != SS_OK)
    return SS_EINVAL;
  double s0[2] = {g->at.z0[0], g->at.z0[2]};
  return ss_attractor_from(&m, s0, 5000, 64, a);
}

/* ---- the adjacent sequence past a grazing ------------------------------ */

int ss_continue_adjacent(const ss_params *p, const ss_branch *b,
                         const ss_special *g, const ss_cont_opts *o,
                         ss_branch *out, ss_diag *d) {
  if (!out)
    return ss__fail(d, SS_EINVAL, "branch", 0, "no output");
  memset(out, 0, sizeof *out);
  if (!p || !b || !g || !o || !ss_param_name(o->param) || o->physical)
    return ss__fail(d, SS_EINVAL, "opts", 0,
                    "a NULL argument, or a physical parameter");
  int k = g->at.min_margin.phase, n = b->n_phases, interior = -1;
  for (int i = 0; i < 4; i++)
    if (!strcmp(g->margin, INTERIOR[i]))
      interior = i;
  if (g->kind != SS_SPECIAL_GRAZING || k < 0 || k >= n || b->n_points < 2 ||
      n + (interior >= 0 ? 2 : 1) > SS_MAX_PHASES ||
      (interior < 0 &&
       (strcmp(g->margin, "switching") || b->modes[k] == SS_MODE_STICK)) ||
      (interior >= 0 &&
       !(g->at.min_margin.t > 0 && g->at.min_margin.t < g->at.durations[k])))
    return ss__fail(d, SS_EINVAL, "special", 0,
                    "not a grazing of the switching condition at the end of "
                    "a slip or overshoot, or of a margin's maximum inside a "
                    "phase");
  /* the side past the grazing: away from the family */
  int at = -1;
  for (int i = 0; i < b->n_points; i++)
    if (b->points[i].value == g->at.value)
      at = i;
  if (at < 0 || (at != 0 && at != b->n_points - 1))
    return ss__fail(d, SS_EINVAL, "special", g->value,
                    "the grazing does not end the family");
  double toward = b->points[at == 0 ? 1 : at - 1].value - g->value;
  /* the adjacent sequence: a short stick after the phase that ends on its
   * switching surface; or, for a maximum inside phase k, that phase split
   * there by a short phase of the mode the margin's zero would start */
  static const ss_mode SPLIT[4] = {SS_MODE_STICK, SS_MODE_STICK, SS_MODE_SLIP,
                                   SS_MODE_OVERSHOOT};
  ss_orbit guess;
  memset(&guess, 0, sizeof guess);
  int q = 0;
  for (int j = 0; j < n; j++) {
    double tj = g->at.durations[j];
    if (j == k && interior >= 0) {
      guess.modes[q] = b->modes[j];
      guess.durations[q++] = g->at.min_margin.t;
      guess.modes[q] = SPLIT[interior];
      guess.durations[q++] = 1e-3 * g->at.period;
      guess.modes[q] = b->modes[j];
      guess.durations[q++] = tj - g->at.min_margin.t;
      continue;
    }
    guess.modes[q] = b->modes[j];
    guess.durations[q++] = tj;
    if (j == k) {
      guess.modes[q] = SS_MODE_STICK;
      guess.durations[q++] = 1e-3 * g->at.period;
    }
  }
  guess.n_phases = q;
  out->n_phases = guess.n_phases;
  memcpy(out->modes, guess.modes, sizeof guess.modes);
  ss_params past = *p;
  *ss__param_ref(&past, o->param) =
      g->value * (1 - (toward > 0 ? 1e-4 : -1e-4));
  ss_model m;
  ss_orbit start;
  int rc = ss_model_init(&m, &past, d);
  if (rc != SS_OK)
    return rc;
  rc = ss_orbit_solve(&m, guess.n_phases, guess.modes, guess.durations, NULL,
                      &start, d);
  if (rc != SS_OK)
    return rc == SS_ENOCONV || rc == SS_ESINGULAR
               ? ss__fail(d, SS_INFEASIBLE, "special", g->value,
                          "the adjacent sequence has no orbit past the "
                          "grazing")
               : rc;
  rc = ss_continue(&past, &start, o, out, d);
  return rc;
}
