/*
 * params.c: parameter validation and unit conversion (DESIGN.md section 1).
 */
#include <math.h>

#include "internal.h"

static int check_pos(ss_diag *d, const char *name, double v) {
  if (!isfinite(v))
    return ss__fail(d, SS_EDOMAIN, name, v, "%s must be a finite number", name);
  if (!(v > 0))
    return ss__fail(d, SS_EDOMAIN, name, v, "%s must be > 0 (got %.17g)", name,
                    v);
  return SS_OK;
}

int ss_params_check(const ss_params *p, ss_diag *d) {
  int rc;
  if (!p)
    return ss__fail(d, SS_EINVAL, "params", 0, "no parameters given");
  if ((rc = check_pos(d, "chi", p->chi)))
    return rc;
  if (!(p->chi < 1))
    return ss__fail(d, SS_EDOMAIN, "chi", p->chi,
                    "chi = k2/(k1+k2) must satisfy 0 < chi < 1 (got %.17g)",
                    p->chi);
  if ((rc = check_pos(d, "eta", p->eta)) || (rc = check_pos(d, "us", p->us)) ||
      (rc = check_pos(d, "ur", p->ur)) || (rc = check_pos(d, "V", p->V)))
    return rc;
  if (!(p->us < p->ur))
    return ss__fail(d, SS_EDOMAIN, "us", p->us,
                    "the dynamic friction us (%.17g) must be smaller than the "
                    "static friction ur (%.17g)",
                    p->us, p->ur);
  return SS_OK;
}

int ss_params_from_physical(const ss_physical *ph, ss_params *p, double *omega,
                            ss_diag *d) {
  int rc;
  double k, om;
  if (!ph || !p)
    return ss__fail(d, SS_EINVAL, "physical", 0, "no parameters given");
  if ((rc = check_pos(d, "m1", ph->m1)) || (rc = check_pos(d, "m2", ph->m2)) ||
      (rc = check_pos(d, "k1", ph->k1)) || (rc = check_pos(d, "k2", ph->k2)) ||
      (rc = check_pos(d, "Fs", ph->Fs)) || (rc = check_pos(d, "Fr", ph->Fr)) ||
      (rc = check_pos(d, "v0", ph->v0)))
    return rc;
  if (!(ph->Fs < ph->Fr))
    return ss__fail(d, SS_EDOMAIN, "Fs", ph->Fs,
                    "the dynamic friction force Fs (%.17g) must be smaller "
                    "than the static friction force Fr (%.17g)",
                    ph->Fs, ph->Fr);
  k = ph->k1 + ph->k2;
  om = sqrt(k / ph->m1);
  p->chi = ph->k2 / k;
  p->eta = ph->m1 / ph->m2;
  p->us = ph->Fs / k;
  p->ur = ph->Fr / k;
  p->V = ph->v0 / om;
  if (omega)
    *omega = om;
  rc = ss_params_check(p, d);
  return rc;
}

void ss_to_physical(double omega, double t, const double x[4], double *t_out,
                    double x_out[4]) {
  if (t_out)
    *t_out = t / omega;
  if (x && x_out) {
    x_out[0] = x[0];
    x_out[1] = x[1];
    x_out[2] = x[2] * omega;
    x_out[3] = x[3] * omega;
  }
}

void ss_from_physical(double omega, double t_phys, const double x_phys[4],
                      double *t_out, double x_out[4]) {
  if (t_out)
    *t_out = t_phys * omega;
  if (x_phys && x_out) {
    x_out[0] = x_phys[0];
    x_out[1] = x_phys[1];
    x_out[2] = x_phys[2] / omega;
    x_out[3] = x_phys[3] / omega;
  }
}
