/*
 * ep_stability.c: POST /stability, the Jacobian of the Poincare map of a
 * given orbit (as /orbit returns it, or its phases and start z0), its
 * eigenvalues, and whether the orbit as given is physically feasible.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "endpoints.h"

/* "phases": [{"mode", "duration"}, ...]. */
typedef struct stab_phases {
  api_modes modes;
  api_durations dur;
} stab_phases;

typedef struct stab_phase {
  int mode; /* ss_mode: the names below are in its order */
  double duration;
} stab_phase;

typedef struct stab_orbit {
  stab_phases phases;
  double z0[4];
} stab_orbit;

typedef struct stab_x {
  /* the request, in its own units */
  api_params ap;
  stab_phases phases;
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

static const char *const MODE_NAMES[] = {"slip", "overshoot", "stick", NULL};

static const api_field PHASE_FIELDS[] = {
    {"mode", API_T_ENUM, API_REQUIRED, 0, 0, NULL, offsetof(stab_phase, mode),
     0, 0, 0, MODE_NAMES},
    {"duration", API_T_NUMBER, API_REQUIRED, 0, 0, NULL,
     offsetof(stab_phase, duration)},
};
static const api_spec PHASE_SPEC = API_SPEC(PHASE_FIELDS);

static int decode_phases(const json_t *v, const char *ptr, void *dest,
                         const api_call *c) {
  stab_phases *s = dest;
  if (!json_is_array(v) || json_array_size(v) < 2 ||
      json_array_size(v) > SS_MAX_PHASES)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an array of 2 to %d phases", ptr,
                     SS_MAX_PHASES);
  int n = (int)json_array_size(v);
  for (int i = 0; i < n; i++) {
    const json_t *el = json_array_get(v, (size_t)i);
    stab_phase ph;
    char p[160];
    snprintf(p, sizeof p, "%s/%d", ptr, i);
    if (!json_is_object(el))
      return api__fail(c->e, API_P_INVALID_TYPE, p,
                       "%s must be a phase {mode, duration}", p);
    /* an unknown mode name is reported at the phase (as clients know it) */
    const json_t *mode = json_object_get(el, "mode");
    ss_mode m;
    if (json_is_string(mode) && api__mode_of(json_string_value(mode), &m))
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s must be \"slip\", \"overshoot\" or \"stick\"", p);
    if (api__decode(&PHASE_SPEC, el, p, &ph, c))
      return -1;
    if (!(ph.duration > 0))
      return api__fail(c->e, API_P_INVALID_VALUE, p, "%s/duration must be > 0",
                       p);
    s->modes.m[i] = (ss_mode)ph.mode;
    s->dur.v[i] = ph.duration;
  }
  s->modes.n = s->dur.n = n;
  return api__sequence(&s->modes, ptr, c);
}

static json_t *echo_phases(const void *dest) {
  const stab_phases *s = dest;
  json_t *a = json_array();
  for (int k = 0; k < s->modes.n; k++) {
    json_t *p = json_object();
    api__set(p, "mode", json_string(ss_mode_name(s->modes.m[k])));
    api__set(p, "duration", api__real(s->dur.v[k]));
    json_array_append_new(a, p);
  }
  return a;
}

static const api_custom PHASES = {decode_phases, echo_phases};

/* An orbit as /orbit returns it: its phases and start z0 are used. */
#define PHASES_FIELD                                                           \
  {                                                                            \
    "phases", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL,                          \
        offsetof(stab_orbit, phases), 0, 0, 0, &PHASES                         \
  }
#define Z0_FIELD                                                               \
  { "z0", API_T_VEC4, API_REQUIRED, 0, 0, NULL, offsetof(stab_orbit, z0) }
static const api_field ORBIT_FIELDS[] = {
    API_ORBIT_FIELDS(API_ANY("x0"), Z0_FIELD, PHASES_FIELD)};
static const api_spec ORBIT_SPEC = API_SPEC(ORBIT_FIELDS);

static const api_field FIELDS[] = {
    API_PARAMS_FIELDS(stab_x, ap),
    {"phases", API_T_CUSTOM, API_REQUIRED | API_DEFAULT, 0, 0, NULL,
     offsetof(stab_x, phases), 0, 2, 0, &PHASES},
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
  json_t *o = api__stability(&x->st, &x->ap);
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
