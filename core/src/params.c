/*
 * params.c: parameter validation, unit conversion (DESIGN.md section 1) and
 * the parameters' names.
 */
#include <math.h>
#include <string.h>

#include "internal.h"
#include "params.h"

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
                    "chi must satisfy 0 < chi < 1 (got %.17g)", p->chi);
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

/* Each dimensionless parameter as the physical ones make it (DESIGN.md
 * section 1), and the physical value it is made from, in the order of
 * SS_PARAM_NAMES. */
static const struct {
  const char *formula, *from;
} FROM_PHYSICAL[] = {
    {"k2/(k1+k2)", "k2"},
    {"m1/m2", "m1"},
    {"Fs/(k1+k2)", "Fs"},
    {"Fr/(k1+k2)", "Fr"},
    {"v0/omega, omega = sqrt((k1+k2)/m1)", "v0"},
};
_Static_assert(sizeof FROM_PHYSICAL / sizeof FROM_PHYSICAL[0] == SS_PARAM_V + 1,
               "one row per parameter of SS_PARAM_NAMES");

/* The parameters converted from valid physical values can still leave their
 * domain when the values differ by many orders of magnitude (k1 negligible
 * beside k2 gives chi = 1; a quotient overflows).  The problem is then told
 * in the units the caller used: the formula that made the parameter, and
 * the physical value it was made from. */
static int physical_check(const ss_params *p, ss_diag *d) {
  ss_diag own;
  ss_param_id id;
  ss_diag_clear(&own);
  int rc = ss_params_check(p, &own);
  if (rc == SS_OK || ss_param_by_name(own.where, &id) != SS_OK)
    return rc ? ss__fail(d, rc, own.where, own.value, "%s", own.text) : rc;
  return ss__fail(d, rc, FROM_PHYSICAL[id].from, own.value,
                  "%s = %s, made from these physical values, is out of "
                  "range: %s",
                  own.where, FROM_PHYSICAL[id].formula, own.text);
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
  return physical_check(p, d);
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

#define NAME_STRING(name) #name,
static const char *const PARAM_NAMES[] = {SS_PARAM_NAMES(NAME_STRING)};
static const char *const PHYS_NAMES[] = {SS_PHYS_NAMES(NAME_STRING)};
#undef NAME_STRING
enum {
  N_PARAMS = sizeof PARAM_NAMES / sizeof PARAM_NAMES[0],
  N_PHYS = sizeof PHYS_NAMES / sizeof PHYS_NAMES[0]
};

const char *ss_param_name(ss_param_id id) {
  return (unsigned)id < N_PARAMS ? PARAM_NAMES[id] : NULL;
}

int ss_param_by_name(const char *name, ss_param_id *id) {
  for (int i = 0; name && id && i < N_PARAMS; i++)
    if (!strcmp(name, PARAM_NAMES[i])) {
      *id = (ss_param_id)i;
      return SS_OK;
    }
  return SS_EINVAL;
}

const char *ss_phys_name(ss_phys_id id) {
  return (unsigned)id < N_PHYS ? PHYS_NAMES[id] : NULL;
}

int ss_phys_by_name(const char *name, ss_phys_id *id) {
  for (int i = 0; name && id && i < N_PHYS; i++)
    if (!strcmp(name, PHYS_NAMES[i])) {
      *id = (ss_phys_id)i;
      return SS_OK;
    }
  return SS_EINVAL;
}

double *ss__phys_ref(ss_physical *ph, ss_phys_id id) {
  double *v[] = {&ph->m1, &ph->m2, &ph->k1, &ph->k2, &ph->Fs, &ph->Fr, &ph->v0};
  return (unsigned)id < N_PHYS ? v[id] : NULL;
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
