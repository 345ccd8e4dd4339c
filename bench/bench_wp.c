/*
 * bench_wp.c: work-precision on the paper's orbit.
 *
 * From the stick -> slip state of the paper's overshoot orbit (found by
 * libstickslip and checked by simulation), run N = 1, 100, 1000 periods with
 *  (a) libstickslip's exact event-driven simulation,
 *  (b) GSL odeiv2 steppers on the physical equations with each switching
 *      event located on its step by bisection (tests/ref), and rk8pd with
 *      each event located inside its accepted step by Hermite interpolation
 *      (the strongest way to use a general-purpose stepper here),
 *  (c) regularized friction u = (us + (ur-us) exp(-(w/ws)^2)) tanh(w/eps),
 *      w = V - x2', with the stiff msbdf stepper and no events; and the plain
 *      u = us tanh(w/eps),
 * and report the error of the final state against the exact periodic state,
 * the largest switching-time error, whether the method took a wrong branch
 * (another sequence of modes), and the median CPU time.
 * Writes bench/results/work_precision.md and work_precision.svg.
 * Usage: bench_wp [results-dir] [--quick]
 */
#include "bench_common.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "refsim.h"
#include "stickslip.h"

typedef struct row {
  char method[48], setting[32];
  int N;
  double err_state, err_switch, cpu;
  int wrong_branch;
  char note[96];
} row;

static row rows[512];
static int nrows;

static ss_model M;
static ss_orbit ORB;
static double X0[4], T;

/* The exact event times of N periods: k T + partial sums of durations. */
static double exact_event_time(int i) {
  int k = i / 3, j = i % 3;
  double t = k * T;
  for (int q = 0; q <= j; q++)
    t += ORB.durations[q];
  return t;
}

static double state_err(const double *x) {
  double e = 0;
  for (int i = 0; i < 4; i++)
    e = fmax(e, fabs(x[i] - X0[i]));
  return e;
}

static int reps_for(double one) {
  if (one < 1e-4)
    return 201;
  if (one < 1e-2)
    return 21;
  if (one < 0.5)
    return 5;
  return 1;
}

/* (a) exact simulation */
static void run_exact(int N, double *drift_out) {
  ss_sim_opts o;
  ss_sim_result r;
  memset(&o, 0, sizeof o);
  o.t_end = N * T;
  o.record_events = 1;
  if (ss_simulate(&M, X0, &o, &r, NULL) != SS_OK) {
    fprintf(stderr, "exact simulation failed\n");
    exit(1);
  }
  row *w = &rows[nrows++];
  snprintf(w->method, sizeof w->method, "libstickslip exact");
  snprintf(w->setting, sizeof w->setting, "-");
  w->N = N;
  w->err_state = state_err(r.x);
  w->err_switch = 0;
  w->wrong_branch = 0;
  double drift = 0;
  for (size_t i = 0; i < r.n_events; i++) {
    ss_mode want_from = (ss_mode)(i % 3 == 0   ? SS_MODE_SLIP
                                  : i % 3 == 1 ? SS_MODE_OVERSHOOT
                                               : SS_MODE_STICK);
    if (r.events[i].from != want_from)
      w->wrong_branch = 1;
    if (i + 1 < (size_t)(3 * N))
      w->err_switch =
          fmax(w->err_switch, fabs(r.events[i].t - exact_event_time((int)i)));
    if (i % 3 == 2)
      drift = fmax(drift, state_err(r.events[i].x));
  }
  /* the last event falls at N T up to rounding: it may or may not be in */
  if (r.n_events < (size_t)(3 * N - 1) || r.n_events > (size_t)(3 * N))
    w->wrong_branch = 1;
  ss_sim_result_free(&r);
  /* timing: final state only, the way a client asking for it pays */
  o.record_events = 0;
  double t0 = cpu_now();
  ss_simulate(&M, X0, &o, &r, NULL);
  double one = cpu_now() - t0;
  int reps = reps_for(one);
  double *tv = malloc((size_t)reps * sizeof *tv);
  for (int k = 0; k < reps; k++) {
    t0 = cpu_now();
    ss_simulate(&M, X0, &o, &r, NULL);
    tv[k] = cpu_now() - t0;
  }
  w->cpu = median(tv, reps);
  free(tv);
  snprintf(w->note, sizeof w->note, "max drift at returns %.1e", drift);
  *drift_out = drift;
}

/* (b) a GSL stepper with events by bisection */
static void run_ref(int N, const char *name, const gsl_odeiv2_step_type *type,
                    double tol, double h) {
  ref_params rp = {M.p.chi, M.p.eta, M.p.us, M.p.ur, M.p.V};
  ref_opts o = {type, tol, tol, h, h > 0 ? 1e-13 : fmax(tol * 1e-2, 1e-14)};
  size_t cap = (size_t)(3 * N + 16);
  ref_event *ev = malloc(cap * sizeof *ev);
  double xe[4];
  int me;
  double t0 = cpu_now();
  long n = ref_simulate(&rp, 0, X0, REF_SLIP, N * T, &o, ev, cap, xe, &me);
  double one = cpu_now() - t0;
  row *w = &rows[nrows++];
  snprintf(w->method, sizeof w->method, "GSL %s + bisection", name);
  if (h > 0)
    snprintf(w->setting, sizeof w->setting, "h = %.0e", h);
  else
    snprintf(w->setting, sizeof w->setting, "tol = %.0e", tol);
  w->N = N;
  if (n < 0) {
    w->err_state = w->err_switch = NAN;
    w->cpu = one;
    w->wrong_branch = 1;
    snprintf(w->note, sizeof w->note, "integration failed");
    free(ev);
    return;
  }
  w->err_state = state_err(xe);
  w->err_switch = 0;
  w->wrong_branch = n < 3 * N - 1 || n > 3 * N;
  long first_wrong = -1;
  for (long i = 0; i < n && i < (long)cap; i++) {
    int want = i % 3 == 0 ? REF_SLIP : i % 3 == 1 ? REF_OVERSHOOT : REF_STICK;
    if (ev[i].from != want) {
      w->wrong_branch = 1;
      if (first_wrong < 0)
        first_wrong = i;
    }
    if (!w->wrong_branch && i < 3 * N - 1)
      w->err_switch =
          fmax(w->err_switch, fabs(ev[i].t - exact_event_time((int)i)));
  }
  if (w->wrong_branch)
    snprintf(w->note, sizeof w->note, "%ld events (exact %d)%s", n, 3 * N,
             first_wrong >= 0 ? ", wrong mode sequence" : "");
  int reps = reps_for(one);
  double *tv = malloc((size_t)(reps + 1) * sizeof *tv);
  tv[0] = one;
  for (int k = 1; k < reps; k++) {
    t0 = cpu_now();
    ref_simulate(&rp, 0, X0, REF_SLIP, N * T, &o, ev, cap, xe, &me);
    tv[k] = cpu_now() - t0;
  }
  w->cpu = median(tv, reps);
  free(tv);
  free(ev);
}

/* (b') the strongest use of a general-purpose stepper: rk8pd with each
 * event located inside the accepted step, not by integrating again.  The
 * switching function is linear in the state, so on the cubic Hermite
 * interpolant of the step (from y and y' at both ends, no extra right-hand
 * side) it is a cubic, whose first sign change is found by bisection; the
 * state there is reached by one more rk8pd step from the step's start, and
 * the time corrected once by Newton on the switching function (a second
 * step).  After an event the step size carries on (clamped to the phase's
 * scale), instead of restarting small. */
typedef struct dense_ctx {
  double chi, eta, us, ur, V;
  int mode; /* REF_SLIP, REF_OVERSHOOT, REF_STICK */
} dense_ctx;

static int dense_rhs(double t, const double y[], double f[], void *vp) {
  const dense_ctx *c = vp;
  (void)t;
  f[0] = y[2];
  f[1] = y[3];
  f[2] = -y[0] + c->chi * y[1];
  f[3] = c->mode == REF_STICK
             ? 0
             : -c->chi * c->eta * (y[1] - y[0]) +
                   c->eta * (c->mode == REF_SLIP ? c->us : -c->us);
  return GSL_SUCCESS;
}

/* The switching function @a which of the mode (negative inside), and its
 * rate along the flow f. */
static double dense_g(const dense_ctx *c, int which, const double y[4]) {
  if (c->mode == REF_SLIP)
    return y[3] - c->V;
  if (c->mode == REF_OVERSHOOT)
    return c->V - y[3];
  double f = c->chi * (y[1] - y[0]);
  return which == 0 ? f - c->ur : -c->ur - f;
}

static double dense_gdot(const dense_ctx *c, int which, const double f[4]) {
  if (c->mode == REF_SLIP)
    return f[3];
  if (c->mode == REF_OVERSHOOT)
    return -f[3];
  double d = c->chi * (f[1] - f[0]);
  return which == 0 ? d : -d;
}

static long dense_simulate(const dense_ctx *c0, double t_end, double tol,
                           ref_event *ev, size_t cap, double y[4]) {
  dense_ctx c = *c0;
  gsl_odeiv2_system sys = {dense_rhs, NULL, 4, &c};
  gsl_odeiv2_step *s = gsl_odeiv2_step_alloc(gsl_odeiv2_step_rk8pd, 4);
  gsl_odeiv2_control *ctl = gsl_odeiv2_control_y_new(tol, tol);
  gsl_odeiv2_evolve *e = gsl_odeiv2_evolve_alloc(4);
  double t = 0, h = 1e-2;
  long n = 0;
  int rc = GSL_SUCCESS;
  while (t < t_end && rc == GSL_SUCCESS) {
    double yp[4], fp[4], tp = t;
    memcpy(yp, y, sizeof yp);
    if (c.mode == REF_STICK)
      y[3] = yp[3] = c.V;
    rc = gsl_odeiv2_evolve_apply(e, ctl, s, &sys, &t, t_end, &h, y);
    if (rc != GSL_SUCCESS)
      break;
    int which = -1;
    for (int k = (c.mode == REF_STICK ? 1 : 0); k >= 0; k--)
      if (dense_g(&c, k, y) >= 0)
        which = k;
    if (which < 0)
      continue;
    /* the cubic g(tp + th dt) on the Hermite interpolant */
    double f1[4], dt = t - tp;
    dense_rhs(tp, yp, fp, &c);
    dense_rhs(t, y, f1, &c);
    double g0 = dense_g(&c, which, yp), g1 = dense_g(&c, which, y);
    double d0 = dt * dense_gdot(&c, which, fp),
           d1 = dt * dense_gdot(&c, which, f1);
    double lo = 0, hi = 1;
    for (int it = 0; it < 60; it++) {
      double th = 0.5 * (lo + hi), a = th * th * (3 - 2 * th);
      double gv = (1 - a) * g0 + a * g1 + th * (1 - th) * (1 - th) * d0 -
                  th * th * (1 - th) * d1;
      if (gv >= 0)
        hi = th;
      else
        lo = th;
    }
    double te = tp + hi * dt, ye[4], yerr[4];
    for (int pass = 0; pass < 2; pass++) {
      memcpy(ye, yp, sizeof ye);
      gsl_odeiv2_step_apply(s, tp, te - tp, ye, yerr, fp, NULL, &sys);
      if (pass == 0) {
        double fe[4];
        dense_rhs(te, ye, fe, &c);
        double gd = dense_gdot(&c, which, fe);
        if (gd != 0)
          te -= dense_g(&c, which, ye) / gd;
      }
    }
    memcpy(y, ye, sizeof ye);
    t = te;
    double f = c.chi * (y[1] - y[0]);
    int to = c.mode == REF_SLIP        ? (f < -c.ur ? REF_OVERSHOOT : REF_STICK)
             : c.mode == REF_OVERSHOOT ? (f > c.ur ? REF_SLIP : REF_STICK)
             : which == 0              ? REF_SLIP
                                       : REF_OVERSHOOT;
    if (c.mode != REF_STICK || to == REF_STICK)
      y[3] = c.V;
    if ((size_t)n < cap) {
      ev[n].t = t;
      ev[n].from = c.mode;
      ev[n].to = to;
      memcpy(ev[n].x, y, sizeof ev[n].x);
    }
    n++;
    c.mode = to;
    gsl_odeiv2_evolve_reset(e);
    gsl_odeiv2_step_reset(s);
    h = fmin(h, 0.5);
  }
  gsl_odeiv2_evolve_free(e);
  gsl_odeiv2_control_free(ctl);
  gsl_odeiv2_step_free(s);
  return rc == GSL_SUCCESS ? n : -1;
}

static void run_dense(int N, double tol) {
  dense_ctx c = {M.p.chi, M.p.eta, M.p.us, M.p.ur, M.p.V, REF_SLIP};
  size_t cap = (size_t)(3 * N + 16);
  ref_event *ev = malloc(cap * sizeof *ev);
  double y[4];
  memcpy(y, X0, sizeof y);
  double t0 = cpu_now();
  long n = dense_simulate(&c, N * T, tol, ev, cap, y);
  double one = cpu_now() - t0;
  row *w = &rows[nrows++];
  snprintf(w->method, sizeof w->method, "GSL rk8pd + Hermite events");
  snprintf(w->setting, sizeof w->setting, "tol = %.0e", tol);
  w->N = N;
  w->err_state = n < 0 ? NAN : state_err(y);
  w->err_switch = 0;
  w->wrong_branch = n < 3 * N - 1 || n > 3 * N;
  for (long i = 0; i < n && i < (long)cap; i++) {
    int want = i % 3 == 0 ? REF_SLIP : i % 3 == 1 ? REF_OVERSHOOT : REF_STICK;
    if (ev[i].from != want)
      w->wrong_branch = 1;
    if (!w->wrong_branch && i < 3 * N - 1)
      w->err_switch =
          fmax(w->err_switch, fabs(ev[i].t - exact_event_time((int)i)));
  }
  int reps = reps_for(one);
  double *tv = malloc((size_t)(reps + 1) * sizeof *tv);
  tv[0] = one;
  for (int k = 1; k < reps; k++) {
    memcpy(y, X0, sizeof y);
    t0 = cpu_now();
    dense_simulate(&c, N * T, tol, ev, cap, y);
    tv[k] = cpu_now() - t0;
  }
  w->cpu = median(tv, reps);
  free(tv);
  free(ev);
}

/* (c) regularized friction, no events */
typedef struct reg {
  double chi, eta, us, ur, V, eps, ws;
  int plain;
} reg;

static double fric(const reg *p, double w, double *dudw) {
  double th = tanh(w / p->eps), sech2 = 1 - th * th;
  if (p->plain) {
    *dudw = p->us * sech2 / p->eps;
    return p->us * th;
  }
  double e = exp(-(w / p->ws) * (w / p->ws));
  double a = p->us + (p->ur - p->us) * e;
  double da = (p->ur - p->us) * e * (-2 * w / (p->ws * p->ws));
  *dudw = da * th + a * sech2 / p->eps;
  return a * th;
}

static int reg_rhs(double t, const double y[], double f[], void *vp) {
  const reg *p = vp;
  double d;
  (void)t;
  f[0] = y[2];
  f[1] = y[3];
  f[2] = -y[0] + p->chi * y[1];
  f[3] = -p->chi * p->eta * (y[1] - y[0]) + p->eta * fric(p, p->V - y[3], &d);
  return GSL_SUCCESS;
}

static int reg_jac(double t, const double y[], double *J, double dfdt[],
                   void *vp) {
  const reg *p = vp;
  double d;
  (void)t;
  fric(p, p->V - y[3], &d);
  memset(J, 0, 16 * sizeof *J);
  J[2] = 1;
  J[7] = 1;
  J[8] = -1;
  J[9] = p->chi;
  J[12] = p->chi * p->eta;
  J[13] = -p->chi * p->eta;
  J[15] = -p->eta * d;
  memset(dfdt, 0, 4 * sizeof *dfdt);
  return GSL_SUCCESS;
}

static void run_reg(int N, double eps, double ws, int plain, double tol) {
  reg p = {M.p.chi, M.p.eta, M.p.us, M.p.ur, M.p.V, eps, ws, plain};
  gsl_odeiv2_system sys = {reg_rhs, reg_jac, 4, &p};
  row *w = &rows[nrows++];
  double tv[5];
  int reps = 0;
  double stuck_time = 0, over_time = 0;
  double y[4];
  for (int k = 0; k < 5; k++) {
    gsl_odeiv2_driver *d = gsl_odeiv2_driver_alloc_y_new(
        &sys, gsl_odeiv2_step_msbdf, 1e-6, tol, tol);
    double t = 0;
    memcpy(y, X0, sizeof y);
    if (k == 0)
      stuck_time = over_time = 0;
    double t0 = cpu_now();
    int rc = GSL_SUCCESS;
    /* record how long the belt mass moves with the belt and faster than it,
     * sampling on a fine grid (only in the first, untimed-alike pass) */
    double dt = k == 0 ? 1e-2 : N * T;
    while (t < N * T && rc == GSL_SUCCESS) {
      double tn = fmin(t + dt, N * T);
      rc = gsl_odeiv2_driver_apply(d, &t, tn, y);
      if (k == 0) {
        double wv = p.V - y[3];
        if (fabs(wv) < 1e-3 * p.V)
          stuck_time += dt;
        else if (wv < 0)
          over_time += dt;
      }
    }
    tv[reps++] = cpu_now() - t0;
    gsl_odeiv2_driver_free(d);
    if (rc != GSL_SUCCESS) {
      snprintf(w->note, sizeof w->note, "msbdf failed (%d)", rc);
      break;
    }
    if (k == 0)
      continue;
    if (tv[reps - 1] > 2)
      break;
  }
  /* the first pass sampled every 1e-3; time only the others if any */
  w->cpu = reps > 1 ? median(tv + 1, reps - 1) : tv[0];
  snprintf(w->method, sizeof w->method,
           plain ? "plain us tanh(w/eps), msbdf" : "regularized, msbdf");
  if (plain)
    snprintf(w->setting, sizeof w->setting, "eps=%.0e tol=%.0e", eps, tol);
  else
    snprintf(w->setting, sizeof w->setting, "eps=%.0e ws=%.0e", eps, ws);
  w->N = N;
  w->err_state = state_err(y);
  w->err_switch = NAN;
  /* exact: per period stick 3.0513, overshoot 2.7227 */
  double want_stick = N * ORB.durations[2], want_over = N * ORB.durations[1];
  w->wrong_branch = fabs(stuck_time - want_stick) > 0.2 * want_stick ||
                    fabs(over_time - want_over) > 0.2 * want_over;
  if (!w->note[0])
    snprintf(
        w->note, sizeof w->note,
        "abs(w) < 1e-3 V for %.3g (exact %.3g), w < 0 for %.3g (exact %.3g)",
        stuck_time, want_stick, over_time, want_over);
}

static void write_md(const char *dir, int quick) {
  char path[512];
  snprintf(path, sizeof path, "%s/work_precision.md", dir);
  FILE *f = fopen(path, "w");
  if (!f) {
    perror(path);
    return;
  }
  fprintf(f, "# Work-precision on the paper's orbit\n\n");
  fprintf(
      f,
      "Generated by `bench_wp`%s. Paper's data set, start at the stick -> slip "
      "state of the overshoot orbit (period T = %.13f), N periods. "
      "*state error*: max |x(NT) - x0|; *switch error*: largest |t_event - "
      "t_exact| over the 3N - 1 events before the last (which falls on t = NT "
      "up to rounding); *wrong branch*: the sequence of modes "
      "differs from slip, overshoot, stick repeated; *CPU*: median CPU time "
      "of repeated runs (final state only for libstickslip).\n\n",
      quick ? " --quick" : "", T);
  fprintf(f, "| method | setting | N | state error | switch error | wrong "
             "branch | CPU (s) | note |\n");
  fprintf(f, "| --- | --- | ---: | ---: | ---: | --- | ---: | --- |\n");
  for (int i = 0; i < nrows; i++) {
    row *w = &rows[i];
    char es[32], ew[32];
    snprintf(es, sizeof es, isnan(w->err_state) ? "-" : "%.2e", w->err_state);
    snprintf(ew, sizeof ew,
             isnan(w->err_switch) || w->wrong_branch ? "-" : "%.2e",
             w->err_switch);
    fprintf(f, "| %s | %s | %d | %s | %s | %s | %.3e | %s |\n", w->method,
            w->setting, w->N, es, ew, w->wrong_branch ? "**yes**" : "no",
            w->cpu, w->note);
  }
  fclose(f);
  printf("wrote %s\n", path);
}

/* error against CPU time, log-log, one colour per method, N = 100 */
static void write_svg(const char *dir) {
  char path[512];
  snprintf(path, sizeof path, "%s/work_precision.svg", dir);
  FILE *f = fopen(path, "w");
  if (!f)
    return;
  const double W = 760, H = 480, L = 80, R = 250, Tp = 30, B = 60;
  double xmin = -7, xmax = 2, ymin = -16, ymax = 2;
  fprintf(f,
          "<svg xmlns='http://www.w3.org/2000/svg' width='%g' height='%g' "
          "font-family='sans-serif' font-size='12'>\n<rect width='100%%' "
          "height='100%%' fill='white'/>\n",
          W, H);
  fprintf(f,
          "<text x='%g' y='18' font-size='14'>Final-state error against CPU "
          "time, paper's orbit, N = 100 periods</text>\n",
          L);
  for (int e = (int)xmin; e <= (int)xmax; e++) {
    double x = L + (e - xmin) / (xmax - xmin) * (W - L - R);
    fprintf(f,
            "<line x1='%g' y1='%g' x2='%g' y2='%g' stroke='#ddd'/>"
            "<text x='%g' y='%g' text-anchor='middle'>1e%d</text>\n",
            x, Tp, x, H - B, x, H - B + 16, e);
  }
  for (int e = (int)ymin; e <= (int)ymax; e += 2) {
    double y = Tp + (ymax - e) / (ymax - ymin) * (H - Tp - B);
    fprintf(f,
            "<line x1='%g' y1='%g' x2='%g' y2='%g' stroke='#ddd'/>"
            "<text x='%g' y='%g' text-anchor='end'>1e%d</text>\n",
            L, y, W - R, y, L - 4, y + 4, e);
  }
  fprintf(f, "<text x='%g' y='%g' text-anchor='middle'>CPU time (s)</text>\n",
          L + (W - L - R) / 2, H - 20);
  fprintf(f,
          "<text x='16' y='%g' transform='rotate(-90 16 %g)' "
          "text-anchor='middle'>max |x(NT) - x0|</text>\n",
          Tp + (H - Tp - B) / 2, Tp + (H - Tp - B) / 2);
  const char *colors[] = {"#d62728", "#1f77b4", "#2ca02c", "#ff7f0e",
                          "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"};
  char seen[8][48];
  int ns = 0;
  for (int i = 0; i < nrows; i++) {
    row *w = &rows[i];
    if (w->N != 100 || !(w->err_state > 0) || !(w->cpu > 0))
      continue;
    int c = -1;
    for (int s = 0; s < ns; s++)
      if (!strcmp(seen[s], w->method))
        c = s;
    if (c < 0 && ns < 8) {
      c = ns;
      snprintf(seen[ns++], sizeof seen[0], "%s", w->method);
    }
    if (c < 0)
      continue;
    double lx = log10(w->cpu), ly = log10(fmax(w->err_state, 1e-16));
    double x = L + (lx - xmin) / (xmax - xmin) * (W - L - R);
    double y = Tp + (ymax - ly) / (ymax - ymin) * (H - Tp - B);
    if (w->wrong_branch)
      fprintf(f,
              "<rect x='%g' y='%g' width='8' height='8' fill='none' "
              "stroke='%s' stroke-width='2'/>\n",
              x - 4, y - 4, colors[c]);
    else
      fprintf(f, "<circle cx='%g' cy='%g' r='4' fill='%s'/>\n", x, y,
              colors[c]);
  }
  for (int s = 0; s < ns; s++)
    fprintf(f,
            "<circle cx='%g' cy='%g' r='4' fill='%s'/><text x='%g' "
            "y='%g'>%s</text>\n",
            W - R + 14, Tp + 20 + 18 * s, colors[s], W - R + 24,
            Tp + 24 + 18 * s, seen[s]);
  fprintf(
      f,
      "<rect x='%g' y='%g' width='8' height='8' fill='none' stroke='black'/>"
      "<text x='%g' y='%g'>wrong branch</text>\n",
      W - R + 10, Tp + 20 + 18 * ns - 4, W - R + 24, Tp + 24 + 18 * ns);
  fprintf(f, "</svg>\n");
  fclose(f);
  printf("wrote %s\n", path);
}

int main(int argc, char **argv) {
  setvbuf(stdout, NULL, _IOLBF, 0);
  const char *dir = argc > 1 && argv[1][0] != '-' ? argv[1] : "bench/results";
  int quick = argc > 2 && !strcmp(argv[2], "--quick");
  ss_params p = {0.2, 4.0, 0.0724, 0.6178, 1.0};
  ss_mode modes[3] = {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK};
  double guess[3] = {4.5, 2.717, 3.0536};
  gsl_set_error_handler_off();
  ss_model_init(&M, &p, NULL);
  if (ss_orbit_solve(&M, 3, modes, guess, NULL, &ORB, NULL) != SS_OK) {
    fprintf(stderr, "cannot solve the paper's orbit\n");
    return 1;
  }
  memcpy(X0, ORB.x0, sizeof X0);
  T = ORB.period;
  const int Ns[] = {1, 100, 1000};
  for (int ni = 0; ni < 3; ni++) {
    int N = Ns[ni];
    double drift;
    run_exact(N, &drift);
    printf("exact N=%d: err %.2e, cpu %.3e s\n", N, rows[nrows - 1].err_state,
           rows[nrows - 1].cpu);
    if (quick && N > 100)
      continue;
    struct {
      const char *name;
      const gsl_odeiv2_step_type *t;
    } st[] = {{"rkf45", gsl_odeiv2_step_rkf45},
              {"rk8pd", gsl_odeiv2_step_rk8pd},
              {"msbdf", gsl_odeiv2_step_msbdf}};
    const double tols[] = {1e-6, 1e-8, 1e-10, 1e-12};
    for (int s = 0; s < 3; s++)
      for (int k = 0; k < 4; k++) {
        if (N == 1000 && (s != 1 || k < 2))
          continue; /* N = 1000 only for rk8pd at 1e-10 and 1e-12 */
        if (st[s].t == gsl_odeiv2_step_msbdf && tols[k] < 1e-10)
          continue;
        run_ref(N, st[s].name, st[s].t, tols[k], 0);
        printf("%s tol %.0e N=%d: err %.2e cpu %.3e\n", st[s].name, tols[k], N,
               rows[nrows - 1].err_state, rows[nrows - 1].cpu);
      }
    for (int k = 0; k < 3; k++) {
      const double dtol[] = {1e-8, 1e-10, 1e-12};
      run_dense(N, dtol[k]);
      printf("rk8pd + Hermite tol %.0e N=%d: err %.2e switch %.2e cpu %.3e\n",
             dtol[k], N, rows[nrows - 1].err_state, rows[nrows - 1].err_switch,
             rows[nrows - 1].cpu);
    }
    const double hs[] = {1e-2, 1e-3};
    for (int k = 0; k < 2 && N <= 100; k++) {
      run_ref(N, "rk4", gsl_odeiv2_step_rk4, 0, hs[k]);
      printf("rk4 h %.0e N=%d: err %.2e cpu %.3e\n", hs[k], N,
             rows[nrows - 1].err_state, rows[nrows - 1].cpu);
    }
    if (N <= 100) {
      const double eps[] = {1e-2, 1e-3, 1e-4};
      for (int k = 0; k < 3; k++)
        for (int j = 0; j < 2; j++) {
          run_reg(N, eps[k], j ? 1e-2 : 1e-1, 0, 1e-8);
          printf("regularized eps %.0e N=%d: err %.2e cpu %.3e %s\n", eps[k], N,
                 rows[nrows - 1].err_state, rows[nrows - 1].cpu,
                 rows[nrows - 1].note);
        }
      run_reg(N, 1e-3, 0, 1, 1e-8);
      printf("plain tanh N=%d: err %.2e %s\n", N, rows[nrows - 1].err_state,
             rows[nrows - 1].note);
    }
  }
  write_md(dir, quick);
  write_svg(dir);
  return 0;
}
