/*
 * refsim.c: reference integration of (1.1) with event location by bisection.
 */
#include "refsim.h"

#include <math.h>
#include <string.h>

#include <gsl/gsl_errno.h>

typedef struct sys_ctx {
  const ref_params *p;
  int mode;
} sys_ctx;

static int rhs(double t, const double y[], double f[], void *vp) {
  const sys_ctx *c = vp;
  const ref_params *p = c->p;
  (void)t;
  f[0] = y[2];
  f[1] = y[3];
  f[2] = -y[0] + p->chi * y[1];
  if (c->mode == REF_STICK) {
    f[3] = 0;
  } else {
    double u = c->mode == REF_SLIP ? p->us : -p->us;
    f[3] = -p->chi * p->eta * (y[1] - y[0]) + p->eta * u;
  }
  return GSL_SUCCESS;
}

static int jac(double t, const double y[], double *dfdy, double dfdt[],
               void *vp) {
  const sys_ctx *c = vp;
  const ref_params *p = c->p;
  (void)t;
  (void)y;
  memset(dfdy, 0, 16 * sizeof *dfdy);
  dfdy[0 * 4 + 2] = 1;
  dfdy[1 * 4 + 3] = 1;
  dfdy[2 * 4 + 0] = -1;
  dfdy[2 * 4 + 1] = p->chi;
  if (c->mode != REF_STICK) {
    dfdy[3 * 4 + 0] = p->chi * p->eta;
    dfdy[3 * 4 + 1] = -p->chi * p->eta;
  }
  memset(dfdt, 0, 4 * sizeof *dfdt);
  return GSL_SUCCESS;
}

/* Switching functions, negative inside the mode. */
static double gfun(const ref_params *p, int mode, int which,
                   const double y[4]) {
  if (mode == REF_SLIP)
    return y[3] - p->V;
  if (mode == REF_OVERSHOOT)
    return p->V - y[3];
  double f = p->chi * (y[1] - y[0]);
  return which == 0 ? f - p->ur : -p->ur - f;
}

/* A driver owns the stepper, control and evolve objects; multistep
 * steppers (msbdf) need it to be attached to the stepper. */
static gsl_odeiv2_driver *new_driver(const gsl_odeiv2_system *sys,
                                     const ref_opts *o) {
  double h0 = o->h_fixed > 0 ? o->h_fixed : 1e-3;
  return gsl_odeiv2_driver_alloc_y_new(sys, o->type, h0,
                                       o->h_fixed > 0 ? 1 : o->atol,
                                       o->h_fixed > 0 ? 1 : o->rtol);
}

/* Integrate from (t, y) to t1 in mode with a fresh integrator. */
static int integrate(const ref_params *p, int mode, double t, double t1,
                     double y[4], const ref_opts *o) {
  sys_ctx c = {p, mode};
  gsl_odeiv2_system sys = {rhs, jac, 4, &c};
  int rc = GSL_SUCCESS;
  if (t1 <= t)
    return GSL_SUCCESS;
  gsl_odeiv2_driver *d = new_driver(&sys, o);
  if (!d)
    return GSL_ENOMEM;
  if (o->h_fixed > 0) {
    while (t < t1 && rc == GSL_SUCCESS) {
      double h = fmin(o->h_fixed, t1 - t);
      rc = gsl_odeiv2_evolve_apply_fixed_step(d->e, NULL, d->s, &sys, &t, h, y);
    }
  } else {
    double h = fmin(1e-3, t1 - t);
    while (t < t1 && rc == GSL_SUCCESS)
      rc = gsl_odeiv2_evolve_apply(d->e, d->c, d->s, &sys, &t, t1, &h, y);
  }
  gsl_odeiv2_driver_free(d);
  return rc;
}

int ref_flow(const ref_params *p, int mode, double t, double x[4],
             const ref_opts *o) {
  if (mode == REF_STICK)
    x[3] = p->V;
  return integrate(p, mode, 0, t, x, o);
}

static int next_mode(const ref_params *p, int mode, int which,
                     const double y[4]) {
  double f = p->chi * (y[1] - y[0]);
  if (mode == REF_SLIP)
    return f < -p->ur ? REF_OVERSHOOT : REF_STICK;
  if (mode == REF_OVERSHOOT)
    return f > p->ur ? REF_SLIP : REF_STICK;
  return which == 0 ? REF_SLIP : REF_OVERSHOOT;
}

long ref_simulate(const ref_params *p, double t0, const double x0[4], int mode0,
                  double t_end, const ref_opts *o, ref_event *ev, size_t max_ev,
                  double x_end[4], int *mode_end) {
  sys_ctx c = {p, mode0};
  gsl_odeiv2_system sys = {rhs, jac, 4, &c};
  double y[4], t = t0, h = 1e-3;
  long n = 0;
  int mode = mode0, rc = GSL_SUCCESS;
  memcpy(y, x0, sizeof y);
  gsl_odeiv2_driver *drv = new_driver(&sys, o);
  if (!drv)
    return -1;
  gsl_odeiv2_step *s = drv->s;
  gsl_odeiv2_control *ctl = o->h_fixed > 0 ? NULL : drv->c;
  gsl_odeiv2_evolve *e = drv->e;
  while (t < t_end && rc == GSL_SUCCESS) {
    double yp[4], tp = t;
    memcpy(yp, y, sizeof y);
    c.mode = mode;
    if (mode == REF_STICK)
      y[3] = p->V;
    if (o->h_fixed > 0)
      rc = gsl_odeiv2_evolve_apply_fixed_step(e, NULL, s, &sys, &t,
                                              fmin(o->h_fixed, t_end - t), y);
    else
      rc = gsl_odeiv2_evolve_apply(e, ctl, s, &sys, &t, t_end, &h, y);
    if (rc != GSL_SUCCESS)
      break;
    /* a sign change on this step?  (the step start counts as inside) */
    int which = -1;
    for (int k = 0; k < (mode == REF_STICK ? 2 : 1); k++)
      if (gfun(p, mode, k, y) >= 0)
        which = k;
    if (mode == REF_STICK && gfun(p, mode, 0, y) >= 0 &&
        gfun(p, mode, 1, y) >= 0)
      which = 0;
    if (which < 0)
      continue;
    /* bisection on [tp, t] integrating again from the step start */
    double lo = tp, hi = t, ylo[4];
    memcpy(ylo, yp, sizeof ylo);
    while (hi - lo > o->loc_tol) {
      double mid = 0.5 * (lo + hi), ym[4];
      if (mid <= lo || mid >= hi)
        break; /* the bracket is down to adjacent doubles */
      memcpy(ym, yp, sizeof ym);
      if (integrate(p, mode, tp, mid, ym, o) != GSL_SUCCESS) {
        gsl_odeiv2_driver_free(drv);
        return -1;
      }
      if (gfun(p, mode, which, ym) >= 0) {
        hi = mid;
      } else {
        lo = mid;
        memcpy(ylo, ym, sizeof ylo);
      }
    }
    memcpy(y, yp, sizeof y);
    if (integrate(p, mode, tp, hi, y, o) != GSL_SUCCESS) {
      gsl_odeiv2_driver_free(drv);
      return -1;
    }
    t = hi;
    int to = next_mode(p, mode, which, y);
    if (mode != REF_STICK || to == REF_STICK)
      y[3] = p->V;
    if ((size_t)n < max_ev) {
      ev[n].t = t;
      ev[n].from = mode;
      ev[n].to = to;
      memcpy(ev[n].x, y, sizeof y);
    }
    n++;
    mode = to;
    gsl_odeiv2_driver_reset(drv);
    h = o->h_fixed > 0 ? o->h_fixed : 1e-3;
  }
  gsl_odeiv2_driver_free(drv);
  if (rc != GSL_SUCCESS)
    return -1;
  if (x_end)
    memcpy(x_end, y, sizeof y);
  if (mode_end)
    *mode_end = mode;
  return n;
}
