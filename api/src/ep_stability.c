/*
 * ep_stability.c: POST /stability, the Jacobian of the Poincare map of a
 * given orbit (as /orbit returns it, or its phases and start z0), its
 * eigenvalues, and whether the orbit as given is physically feasible.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "endpoints.h"
#include "decode.h"
#include "encode.h"
#include "problem.h"
#include "values.h"

typedef struct stab_orbit {
  api_phases phases;
  double z0[4];
} stab_orbit;

typedef struct stab_x {
  /* the request, in its own units */
  api_params ap;
  api_phases phases;
  double z0[4];
  stab_orbit orbit;
  int has_orbit;
  int finite_difference;
  /* for the core, dimensionless */
  ss_model m;
  ss_orbit o;       /* the orbit as given: modes, durations, z0 */
  const char *base; /* "" or "/orbit": where phases and z0 came from */
  /* the answer */
  ss_stab st;
  int feasible;
  ss_diag why; /* why it is not feasible */
} stab_x;

/* An orbit as /orbit returns it: its phases and start z0 are used. */
#define PHASES_FIELD                                                           \
  {                                                                            \
    "phases", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL,                          \
        offsetof(stab_orbit, phases), 0, 0, 0, &API_PHASES                     \
  }
#define Z0_FIELD                                                               \
  { "z0", API_T_VEC4, API_REQUIRED, 0, 0, NULL, offsetof(stab_orbit, z0) }
static const api_field ORBIT_FIELDS[] = {
    API_ORBIT_FIELDS(API_ANY("x0"), Z0_FIELD, PHASES_FIELD)};
static const api_spec ORBIT_SPEC = API_SPEC(ORBIT_FIELDS);

static const api_field FIELDS[] = {
    API_PARAMS_FIELDS(stab_x, ap),
    {"phases", API_T_CUSTOM, API_REQUIRED | API_DEFAULT, 0, 0, NULL,
     offsetof(stab_x, phases), 0, 2, 0, &API_PHASES},
    {"z0", API_T_VEC4, API_REQUIRED | API_DEFAULT, 0, 0, NULL,
     offsetof(stab_x, z0), 0, 2, 0},
    {"orbit", API_T_OBJECT, API_REQUIRED | API_ECHO_NEVER, 0, 0, NULL,
     offsetof(stab_x, orbit), API_HAS(stab_x, has_orbit), 2, 1, &ORBIT_SPEC},
    {"finite_difference", API_T_BOOL, API_DEFAULT, 0, 0, NULL,
     offsetof(stab_x, finite_difference)},
};
static const api_spec SPEC = API_SPEC(FIELDS);

/* Every conversion of the request's units. */
static void to_core(stab_x *x) {
  ss_orbit *o = &x->o;
  o->n_phases = x->phases.modes.n;
  memcpy(o->modes, x->phases.modes.m, (size_t)o->n_phases * sizeof(ss_mode));
  for (int k = 0; k < o->n_phases; k++)
    o->durations[k] = api__time_in(&x->ap, x->phases.dur.v[k]);
  ss_from_physical(x->ap.omega, 0, x->z0, NULL, o->z0);
  o->kind = ss_orbit_kind_of(o->n_phases, o->modes);
}

int ep_stability_decode(const json_t *root, const api_call *c, void **xp) {
  stab_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->finite_difference = 1;
  x->base = "";
  if (api__decode_request(&SPEC, root, x, &x->ap, c))
    return -1;
  if (x->has_orbit) {
    x->phases = x->orbit.phases;
    memcpy(x->z0, x->orbit.z0, sizeof x->z0);
    x->base = "/orbit";
  }
  to_core(x);
  return api__model(&x->m, &x->ap, c);
}

int ep_stability_run(void *xp, const api_call *c) {
  stab_x *x = xp;
  ss_orbit *o = &x->o;
  ss_stab_opts so = {0, x->finite_difference};
  char pp[32];
  ss_diag_clear(&x->why);
  x->feasible = ss_orbit_check(&x->m, o, &x->why) == SS_OK;
  int rc = ss_stability(&x->m, o->n_phases, o->modes, o->durations, o->z0, &so,
                        &x->st);
  if (rc == SS_OK)
    return 0;
  snprintf(pp, sizeof pp, "%s/phases", x->base);
  if (rc == SS_ESINGULAR)
    return api__status(c->e, rc, pp,
                       "a phase ends tangentially (grazing): the Poincare "
                       "map is not differentiable there");
  return api__status(c->e, rc, x->base, "%s", ss_strerror(rc));
}

int ep_stability_encode(const void *xp, const api_call *c, api_response *out) {
  const stab_x *x = xp;
  const ss_params *p = &x->m.p;
  const double *z0 = x->o.z0;
  json_t *o = api__stability(c, &x->st, &x->ap);
  double sec = p->chi * (z0[1] - z0[0]) - (p->ur - p->us);
  double sec2 = z0[3] - p->V;
  api__set(o, "section_residual", api__real(fmax(fabs(sec), fabs(sec2))));
  api__set(o, "feasible", json_boolean(x->feasible));
  if (x->feasible)
    api__set(o, "closure", api__real(x->o.closure));
  else
    api__set(o, "reason", json_string(x->why.text));
  return api__answer(o, &SPEC, x, &x->ap, c, out);
}

void ep_stability_release(void *x) { free(x); }
