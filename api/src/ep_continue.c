/*
 * ep_continue.c: POST /continue, a family of periodic orbits followed in
 * one parameter from a starting orbit (as /orbit returns it) or a guess,
 * with its grazing, folds and multiplier crossings located, and what they
 * lead to (ss_continue_study).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "endpoints.h"
#include "decode.h"
#include "encode.h"
#include "problem.h"
#include "values.h"

static const char *const DIRECTIONS[] = {"both", "up", "down", NULL};
static const int DIRECTION_OF[] = {0, 1, -1};

typedef struct cont_range {
  double lo, hi;
} cont_range;

typedef struct cont_orbit {
  api_phases phases;
} cont_orbit;

/* follow: {"special": "grazing", "parameter": name, "range": [lo, hi]} */
static const char *const SPECIALS[] = {"grazing", "period_doubling", NULL};

typedef struct cont_follow {
  int special;
  int parameter;
  cont_range range;
} cont_follow;

typedef struct cont_fields {
  unsigned mask; /* bit k: POINT_FIELDS[k] */
} cont_fields;

typedef struct cont_x {
  /* the request */
  api_params ap;
  cont_orbit orbit;
  int has_orbit;
  api_guess guess;
  int has_guess;
  int parameter;
  cont_range range;
  long long max_points;
  double step;
  int direction;
  cont_follow follow;
  int has_follow;
  int branch_switching;
  cont_fields fields;
  /* for the core */
  ss_orbit start;
  ss_study_opts opts;
  /* the answer */
  ss_study s;
  int rc;
} cont_x;

static int decode_range(const json_t *v, const char *ptr, void *dest,
                        const api_call *c) {
  cont_range *r = dest;
  double two[2];
  if (!json_is_array(v) || json_array_size(v) != 2)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be [lo, hi], two numbers", ptr);
  if (api__numbers(v, ptr, two, c->e))
    return -1;
  if (!(two[0] < two[1]))
    return api__fail(c->e, API_P_INVALID_VALUE, ptr,
                     "%s must be [lo, hi] with lo < hi", ptr);
  r->lo = two[0];
  r->hi = two[1];
  return 0;
}

static json_t *echo_range(const void *dest) {
  const cont_range *r = dest;
  json_t *a = json_array();
  json_array_append_new(a, api__real(r->lo));
  json_array_append_new(a, api__real(r->hi));
  return a;
}

static const api_custom RANGE = {decode_range, echo_range};

/* "fields": the per-point fields to return ("value" always is). */
static const char *const POINT_FIELDS[] = {
    "value",           "period",      "durations", "z0",         "n_turns",
    "spectral_radius", "multipliers", "stable",    "min_margin", "residual"};
enum { N_POINT_FIELDS = 10 };

static int decode_fields(const json_t *v, const char *ptr, void *dest,
                         const api_call *c) {
  cont_fields *f = dest;
  if (!json_is_array(v))
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an array of field names", ptr);
  f->mask = 1; /* value */
  for (size_t i = 0; i < json_array_size(v); i++) {
    const json_t *e = json_array_get(v, i);
    char p[160];
    int k = 0;
    snprintf(p, sizeof p, "%s/%zu", ptr, i);
    if (!json_is_string(e))
      return api__fail(c->e, API_P_INVALID_TYPE, p, "%s must be a string", p);
    while (k < N_POINT_FIELDS && strcmp(json_string_value(e), POINT_FIELDS[k]))
      k++;
    if (k == N_POINT_FIELDS)
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s: no point field \"%.40s\" (value, period, "
                       "durations, z0, n_turns, spectral_radius, multipliers, "
                       "stable, min_margin, residual)",
                       p, json_string_value(e));
    f->mask |= 1u << k;
  }
  return 0;
}

static json_t *echo_fields(const void *dest) {
  const cont_fields *f = dest;
  json_t *a = json_array();
  for (int k = 0; k < N_POINT_FIELDS; k++)
    if (f->mask & (1u << k))
      json_array_append_new(a, json_string(POINT_FIELDS[k]));
  return a;
}

static const api_custom FIELDS_OF_POINTS = {decode_fields, echo_fields};

#define PHASES_FIELD                                                           \
  {                                                                            \
    "phases", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL,                          \
        offsetof(cont_orbit, phases), 0, 0, 0, &API_PHASES                     \
  }
static const api_field ORBIT_FIELDS[] = {
    API_ORBIT_FIELDS(API_ANY("x0"), API_ANY("z0"), PHASES_FIELD)};
static const api_spec ORBIT_SPEC = API_SPEC(ORBIT_FIELDS);

static const api_field FOLLOW_FIELDS[] = {
    {"special", API_T_ENUM, API_REQUIRED, 0, 0, NULL,
     offsetof(cont_follow, special), 0, 0, 0, SPECIALS},
    {"parameter", API_T_ENUM, API_REQUIRED, 0, 0, NULL,
     offsetof(cont_follow, parameter), 0, 0, 0, API_PARAMETER_NAMES},
    {"range", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL,
     offsetof(cont_follow, range), 0, 0, 0, &RANGE},
};
static const api_spec FOLLOW_SPEC = API_SPEC(FOLLOW_FIELDS);

static const api_field FIELDS[] = {
    API_PARAMS_FIELDS(cont_x, ap),
    {"orbit", API_T_OBJECT, API_REQUIRED | API_ECHO_NEVER, 0, 0, NULL,
     offsetof(cont_x, orbit), API_HAS(cont_x, has_orbit), 2, 0, &ORBIT_SPEC},
    {"guess", API_T_OBJECT, API_REQUIRED, 0, 0, NULL, offsetof(cont_x, guess),
     API_HAS(cont_x, has_guess), 2, 1, &API_GUESS_SPEC},
    {"parameter", API_T_ENUM, API_REQUIRED, 0, 0, NULL,
     offsetof(cont_x, parameter), 0, 0, 0, API_PARAMETER_NAMES},
    {"range", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL, offsetof(cont_x, range),
     0, 0, 0, &RANGE},
    {"max_points", API_T_COUNT, API_DEFAULT, 2, 1e9, "max_points",
     offsetof(cont_x, max_points)},
    {"step", API_T_NUMBER, API_DEFAULT, 1e-6, 0.2, NULL,
     offsetof(cont_x, step)},
    {"direction", API_T_ENUM, API_DEFAULT, 0, 0, NULL,
     offsetof(cont_x, direction), 0, 0, 0, DIRECTIONS},
    {"follow", API_T_OBJECT, 0, 0, 0, NULL, offsetof(cont_x, follow),
     API_HAS(cont_x, has_follow), 0, 0, &FOLLOW_SPEC},
    {"branch_switching", API_T_BOOL, API_DEFAULT, 0, 0, NULL,
     offsetof(cont_x, branch_switching)},
    {"fields", API_T_CUSTOM, API_DEFAULT, 0, 0, NULL, offsetof(cont_x, fields),
     0, 0, 0, &FIELDS_OF_POINTS},
};
static const api_spec SPEC = API_SPEC(FIELDS);

int ep_continue_decode(const json_t *root, const api_call *c, void **xp) {
  cont_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->max_points = 200;
  x->step = 0.02;
  x->fields.mask = (1u << N_POINT_FIELDS) - 1;
  if (api__decode_request(&SPEC, root, x, &x->ap, c) ||
      (x->has_guess && api__guess_modes(&x->guess, "/guess", c)))
    return -1;
  int physical = x->parameter >= API_N_DIMENSIONLESS;
  if (x->ap.has_physical != physical)
    return api__fail(c->e, API_P_INVALID_VALUE, "/parameter",
                     x->ap.has_physical
                         ? "/parameter must be a physical parameter (m1, m2, "
                           "k1, k2, Fs, Fr, v0) for a request in physical "
                           "units"
                         : "/parameter must be a dimensionless parameter "
                           "(chi, eta, us, ur, V); send \"physical\" to "
                           "continue a physical one");
  if (physical && (x->has_follow || x->branch_switching))
    return api__fail(c->e, API_P_INVALID_VALUE,
                     x->has_follow ? "/follow" : "/branch_switching",
                     "follow and branch_switching work in the dimensionless "
                     "parameters only; send \"params\"");
  const api_modes *modes =
      x->has_orbit ? &x->orbit.phases.modes : &x->guess.modes;
  const api_durations *dur =
      x->has_orbit ? &x->orbit.phases.dur : &x->guess.durations;
  x->start.n_phases = modes->n;
  memcpy(x->start.modes, modes->m, (size_t)modes->n * sizeof(ss_mode));
  for (int k = 0; k < dur->n; k++)
    x->start.durations[k] = api__time_in(&x->ap, dur->v[k]);
  ss_cont_opts *o = &x->opts.family;
  if (physical) {
    o->physical = &x->ap.ph;
    o->phys = (ss_phys_id)(x->parameter - API_N_DIMENSIONLESS);
  } else {
    o->param = (ss_param_id)x->parameter;
  }
  o->lo = x->range.lo;
  o->hi = x->range.hi;
  o->max_points = (int)x->max_points;
  o->step = x->step;
  o->direction = DIRECTION_OF[x->direction];
  o->max_seconds = c->lim->max_seconds;
  if (c->srv && c->srv->cancelled) {
    o->cancelled = c->srv->cancelled;
    o->cancel_cls = c->srv->cancel_cls;
  }
  const ss_params *p = &x->ap.p;
  const ss_physical *ph = &x->ap.ph;
  const double values[] = {p->chi, p->eta, p->us,  p->ur,  p->V,   ph->m1,
                           ph->m2, ph->k1, ph->k2, ph->Fs, ph->Fr, ph->v0};
  double v0 = values[x->parameter];
  if (x->has_follow) {
    double v2 = values[x->follow.parameter];
    if (x->follow.parameter >= API_N_DIMENSIONLESS)
      return api__fail(c->e, API_P_INVALID_VALUE, "/follow/parameter",
                       "/follow/parameter must be a dimensionless parameter "
                       "(chi, eta, us, ur, V)");
    if (x->follow.parameter == x->parameter)
      return api__fail(c->e, API_P_INVALID_VALUE, "/follow/parameter",
                       "/follow/parameter must differ from /parameter");
    if (!(v2 >= x->follow.range.lo && v2 <= x->follow.range.hi))
      return api__fail(c->e, API_P_INVALID_VALUE, "/follow/range",
                       "/follow/range [%.15g, %.15g] must contain %s = %.15g",
                       x->follow.range.lo, x->follow.range.hi,
                       API_PARAMETER_NAMES[x->follow.parameter], v2);
  }
  if (!(v0 >= o->lo && v0 <= o->hi))
    return api__fail(c->e, API_P_INVALID_VALUE, "/range",
                     "/range [%.15g, %.15g] must contain the start's %s = "
                     "%.15g",
                     o->lo, o->hi, API_PARAMETER_NAMES[x->parameter], v0);
  x->opts.follow = x->has_follow;
  x->opts.follow_kind =
      x->follow.special == 1 ? SS_SPECIAL_PERIOD_DOUBLING : SS_SPECIAL_GRAZING;
  x->opts.follow_param = (ss_param_id)x->follow.parameter;
  x->opts.follow_lo = x->follow.range.lo;
  x->opts.follow_hi = x->follow.range.hi;
  x->opts.branch_switching = x->branch_switching;
  return 0;
}

int ep_continue_run(void *xp, const api_call *c) {
  cont_x *x = xp;
  ss_diag d;
  ss_diag_clear(&d);
  x->rc = ss_continue_study(&x->ap.p, &x->start, &x->opts, &x->s, &d);
  if (x->rc == SS_OK)
    return 0;
  if (x->rc == SS_ELIMIT_TIME)
    return api__status_limit(c->e, x->rc, "max_seconds", c->lim->max_seconds,
                             "",
                             "the continuation needed more than %g s; narrow "
                             "the range or lower max_points",
                             c->lim->max_seconds);
  if (x->rc == SS_INFEASIBLE || x->rc == SS_ENOCONV || x->rc == SS_ESINGULAR)
    return api__fail(c->e, API_P_INVALID_VALUE,
                     x->has_orbit ? "/orbit" : "/guess",
                     "the starting orbit is not a feasible orbit of these "
                     "parameters: %s",
                     d.text[0] ? d.text : ss_strerror(x->rc));
  return api__from_diag(c->e, x->rc, &d, "");
}

static json_t *multipliers(const double re[2], const double im[2]) {
  json_t *a = json_array();
  for (int k = 0; k < 2; k++) {
    json_t *m = json_array();
    json_array_append_new(m, api__real(re[k]));
    json_array_append_new(m, api__real(im[k]));
    json_array_append_new(a, m);
  }
  return a;
}

/* The time scale at a point: 1 for a dimensionless request; for a
 * physical one, omega of the physical parameters with the continued one at
 * @a value. */
static double omega_at(const cont_x *x, double value) {
  if (!x->opts.family.physical)
    return 1;
  ss_physical ph = x->ap.ph;
  double *f[] = {&ph.m1, &ph.m2, &ph.k1, &ph.k2, &ph.Fs, &ph.Fr, &ph.v0};
  ss_params p;
  double omega = 1;
  *f[x->opts.family.phys] = value;
  ss_params_from_physical(&ph, &p, &omega, NULL);
  return omega;
}

static json_t *margin(const ss_margin *mg, double omega) {
  json_t *o = json_object();
  api__set(o, "value", api__real(mg->value));
  if (mg->phase >= 0) {
    api__set(o, "phase", json_integer(mg->phase));
    api__set(o, "t", api__real(mg->t / omega));
  }
  return o;
}

/* A point in the request's units: times over omega, the start state as
 * ss_to_physical gives it. */
static json_t *point(const cont_x *x, const ss_cont_point *p, int n,
                     unsigned mask) {
  double omega = omega_at(x, p->value), dur[SS_MAX_PHASES], z0[4];
  for (int k = 0; k < n; k++)
    dur[k] = p->durations[k] / omega;
  ss_to_physical(omega, 0, p->z0, NULL, z0);
  json_t *v[N_POINT_FIELDS] = {api__real(p->value),
                               api__real(p->period / omega),
                               api__vec(dur, n),
                               api__vec4(z0),
                               json_integer(p->n_turns),
                               api__real(p->spectral_radius),
                               multipliers(p->eig_re, p->eig_im),
                               json_boolean(p->stable),
                               margin(&p->min_margin, omega),
                               api__real(p->residual)};
  json_t *o = json_object();
  for (int k = 0; k < N_POINT_FIELDS; k++) {
    if (mask & (1u << k))
      api__set(o, POINT_FIELDS[k], v[k]);
    else
      json_decref(v[k]);
  }
  return o;
}

/* What the motion does just past the grazing b.special[i] that ends the
 * family: the attractor simulation reaches, and whether the adjacent
 * sequence has a family there. */
static json_t *beyond_json(const cont_x *x, int i) {
  const ss_beyond *by = &x->s.beyond[i];
  if (!by->done)
    return json_null();
  const ss_attractor *a = &by->attractor;
  json_t *o = json_object();
  api__set(o, "value", api__real(by->value));
  api__set(o, "found", json_boolean(a->found));
  api__set(o, "perpetual_slip", json_boolean(a->perpetual_slip));
  api__set(o, "turns_simulated", json_integer(a->turns_run));
  if (a->found) {
    json_t *modes = json_array();
    for (int k = 0; k < a->n_phases && k < SS_MAX_PHASES; k++)
      json_array_append_new(modes, json_string(ss_mode_name(a->modes[k])));
    api__set(o, "n_turns", json_integer(a->n_turns));
    api__set(o, "period", api__real(a->period));
    api__set(o, "n_phases", json_integer(a->n_phases));
    api__set(o, "n_overshoot", json_integer(a->n_overshoot));
    api__set(o, "modes", modes);
    api__set(o, "s", api__vec(a->s, 2));
  }
  json_t *ad = json_object(), *am = json_array();
  for (int k = 0; k < by->adjacent_n_phases; k++)
    json_array_append_new(am, json_string(ss_mode_name(by->adjacent_modes[k])));
  api__set(ad, "modes", am);
  api__set(ad, "exists", json_boolean(by->adjacent_rc == SS_OK));
  for (int k = 0; k < x->s.n_branches; k++)
    if (x->s.of_special[k] == i)
      api__set(ad, "branch", json_integer(k + 1));
  if (by->adjacent_rc != SS_OK)
    api__set(ad, "reason", json_string(by->adjacent_why));
  api__set(o, "adjacent", ad);
  return o;
}

static json_t *branch_json(const cont_x *x, const ss_branch *b, int first) {
  json_t *br = json_object();
  api__set(
      br, "kind",
      json_string(ss_orbit_kind_name(ss_orbit_kind_of(b->n_phases, b->modes))));
  json_t *modes = json_array();
  for (int k = 0; k < b->n_phases; k++)
    json_array_append_new(modes, json_string(ss_mode_name(b->modes[k])));
  api__set(br, "modes", modes);
  api__set(br, "period_multiple",
           json_integer(b->n_points ? b->points[0].n_turns : 1));
  json_t *pts = json_array();
  for (int i = 0; i < b->n_points; i++)
    json_array_append_new(pts,
                          point(x, &b->points[i], b->n_phases, x->fields.mask));
  api__set(br, "points", pts);
  api__set(br, "start", json_integer(b->start));
  json_t *sp = json_array();
  for (int i = 0; i < b->n_special; i++) {
    const ss_special *s = &b->special[i];
    json_t *o = json_object();
    api__set(o, "type", json_string(ss_special_name(s->kind)));
    api__set(o, "value", api__real(s->value));
    api__set(o, "precision", api__real(s->precision));
    if (s->kind == SS_SPECIAL_GRAZING) {
      api__set(o, "margin", json_string(ss_margin_name(s->margin)));
      api__set(o, "phase", json_integer(s->at.min_margin.phase));
      api__set(o, "t",
               api__real(s->at.min_margin.t / omega_at(x, s->at.value)));
      api__set(o, "margin_value", api__real(s->at.min_margin.value));
      if (first)
        api__set(o, "beyond", beyond_json(x, i));
    }
    api__set(o, "multipliers", multipliers(s->at.eig_re, s->at.eig_im));
    api__set(o, "stable_before", json_boolean(s->stable_before));
    api__set(o, "stable_after", json_boolean(s->stable_after));
    api__set(o, "detail", json_string(s->detail));
    if (first && x->branch_switching && s->kind == SS_SPECIAL_PERIOD_DOUBLING) {
      int at = -1;
      for (int k = 0; k < x->s.n_branches; k++)
        if (x->s.of_special[k] == i)
          at = k + 1;
      if (at > 0)
        api__set(o, "branch", json_integer(at));
      else
        api__set(o, "no_branch", json_string(x->s.why_none[i]));
    }
    api__set(o, "orbit",
             point(x, &s->at, b->n_phases, (1u << N_POINT_FIELDS) - 1));
    json_array_append_new(sp, o);
  }
  api__set(br, "special", sp);
  json_t *ends = json_object();
  if (b->end[0][0])
    api__set(ends, "down", json_string(b->end[0]));
  if (b->end[1][0])
    api__set(ends, "up", json_string(b->end[1]));
  char end[2 * sizeof b->end[0] + 4];
  snprintf(end, sizeof end, "%s%s%s", b->end[0][0] ? b->end[0] : "",
           b->end[0][0] && b->end[1][0] ? "; " : "",
           b->end[1][0] ? b->end[1] : "");
  api__set(br, "end", json_string(end));
  api__set(br, "ends", ends);
  return br;
}

int ep_continue_encode(const void *xp, const api_call *c, api_response *out) {
  const cont_x *x = xp;
  json_t *o = json_object();
  json_t *branches = json_array();
  json_array_append_new(branches, branch_json(x, &x->s.family, 1));
  for (int i = 0; i < x->s.n_branches; i++)
    json_array_append_new(branches, branch_json(x, &x->s.branches[i], 0));
  api__set(o, "branches", branches);
  json_t *curves = json_array();
  for (int i = 0; i < x->s.n_curves; i++) {
    const ss_curve *cv = &x->s.curves[i];
    const char *n1 = API_PARAMETER_NAMES[cv->p1],
               *n2 = API_PARAMETER_NAMES[cv->p2];
    json_t *co = json_object(), *names = json_array(), *cp = json_array();
    api__set(co, "type", json_string(ss_special_name(cv->kind)));
    if (cv->kind == SS_SPECIAL_GRAZING) {
      api__set(co, "margin", json_string(ss_margin_name(cv->margin)));
      api__set(co, "phase", json_integer(cv->phase));
    }
    json_array_append_new(names, json_string(n1));
    json_array_append_new(names, json_string(n2));
    api__set(co, "parameters", names);
    for (int k = 0; k < cv->n_points; k++) {
      json_t *q = json_object();
      api__set(q, n1, api__real(cv->points[k].v1));
      api__set(q, n2, api__real(cv->points[k].v2));
      api__set(
          q, "feasible_side",
          json_string(cv->points[k].feasible_side > 0 ? "above" : "below"));
      json_array_append_new(cp, q);
    }
    api__set(co, "points", cp);
    if (cv->n_points == 0) { /* no curve through this special point */
      api__set(co, "error", json_string(cv->end[0]));
      json_array_append_new(curves, co);
      continue;
    }
    api__set(co, "start", json_integer(cv->start));
    json_t *ce = json_object();
    if (cv->end[0][0])
      api__set(ce, "down", json_string(cv->end[0]));
    if (cv->end[1][0])
      api__set(ce, "up", json_string(cv->end[1]));
    api__set(co, "ends", ce);
    json_array_append_new(curves, co);
  }
  api__set(o, "curves", curves);
  api__set(o, "parameter", json_string(API_PARAMETER_NAMES[x->parameter]));
  return api__answer(o, &SPEC, x, &x->ap, c, out);
}

void ep_continue_release(void *xp) {
  cont_x *x = xp;
  if (!x)
    return;
  ss_study_free(&x->s);
  free(x);
}
