/*
 * handle.c: the computing endpoints.  Parse -> validate -> compute ->
 * encode; the core never sees JSON and this file never calls GSL.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "codec.h"

void api_limits_default(api_limits *l) {
  l->max_body = 1 << 20;
  l->max_samples = 100000;
  l->max_events = 2000000;
  l->max_event_list = 100000;
  l->max_horizon = 1e7;
  l->max_seconds = 10;
  l->max_orbits = 32;
  l->max_depth = 32;
}

const char *api_version(void) { return SS_VERSION; }

/* Nesting depth of a JSON text, outside strings; stops counting past max. */
static int too_deep(const char *s, size_t n, int max) {
  int depth = 0, in_str = 0;
  for (size_t i = 0; i < n; i++) {
    char c = s[i];
    if (in_str) {
      if (c == '\\')
        i++;
      else if (c == '"')
        in_str = 0;
    } else if (c == '"') {
      in_str = 1;
    } else if (c == '[' || c == '{') {
      if (++depth > max)
        return 1;
    } else if (c == ']' || c == '}') {
      depth--;
    }
  }
  return 0;
}

/* ------------------------------------------------------------------ */
/* /simulate                                                           */
/* ------------------------------------------------------------------ */

static const char *const SIM_KEYS[] = {
    "params", "physical", "initial",    "orbit",   "t0",
    "t_end",  "events",   "stop_after", "samples", NULL};
static const char *const SAMPLE_KEYS[] = {"n", "from", "to", "t", NULL};
/* An orbit object as /orbit returns it; only x0 is used. */
static const char *const ORBIT_KEYS[] = {
    "kind",    "phases",  "period",     "n_turns", "z0",
    "x0",      "margins", "residual",   "closure", "stability",
    "samples", "source",  "iterations", NULL};

static json_t *mode_json(ss_mode m) { return json_string(ss_mode_name(m)); }

/* The samples of a simulation as columns t, x1, x2, v1, v2, mode, in the
 * units of the request. */
static json_t *samples_json(const ss_sim_result *r, double omega) {
  json_t *s = json_object(), *col[6];
  static const char *const names[6] = {"t", "x1", "x2", "v1", "v2", "mode"};
  for (int c = 0; c < 6; c++)
    col[c] = json_array();
  for (size_t i = 0; i < r->n_samples; i++) {
    double t, x[4];
    ss_to_physical(omega, r->st[i], r->sx + 4 * i, &t, x);
    json_array_append_new(col[0], api__real(t));
    for (int c = 0; c < 4; c++)
      json_array_append_new(col[1 + c], api__real(x[c]));
    json_array_append_new(col[5], mode_json((ss_mode)r->smode[i]));
  }
  for (int c = 0; c < 6; c++)
    api__set(s, names[c], col[c]);
  return s;
}

static int simulate(const json_t *root, const api_limits *lim, json_t **res,
                    api_err *e) {
  api_params ap;
  double x0[4], t0 = 0, t_end = 0, *times = NULL;
  int events = 1, rc;
  long long stop_after = 0;
  json_t *orb = NULL, *samp = NULL;
  ss_sim_opts o;
  ss_sim_result r;
  ss_model m;
  ss_diag d;
  memset(&o, 0, sizeof o);
  memset(&r, 0, sizeof r);
  if (api__keys(root, "", SIM_KEYS, e) || api__params(root, &ap, e))
    return -1;
  int hi = api__vec(root, "", "initial", 0, 4, x0, e);
  int ho = api__object(root, "", "orbit", 0, &orb, e);
  if (hi < 0 || ho < 0)
    return -1;
  if (hi == 0 && ho == 0)
    return api__fail(e, 422, "invalid-value", "/orbit",
                     "give either initial or orbit, not both");
  if (hi == 1 && ho == 1)
    return api__fail(e, 422, "missing-field", "/initial",
                     "the initial state is missing: give initial [x1, x2, "
                     "x1', x2'] or an orbit from /orbit");
  if (ho == 0 && (api__keys(orb, "/orbit", ORBIT_KEYS, e) ||
                  api__vec(orb, "/orbit", "x0", 1, 4, x0, e)))
    return -1;
  if (api__number(root, "", "t0", 0, &t0, e) < 0 ||
      api__number(root, "", "t_end", 1, &t_end, e) < 0 ||
      api__bool(root, "", "events", 0, &events, e) < 0 ||
      api__count(root, "", "stop_after", 0, 1, (long long)lim->max_events,
                 &stop_after, e) < 0)
    return -1;
  /* to dimensionless units */
  ss_from_physical(ap.omega, t0, x0, &t0, x0);
  ss_from_physical(ap.omega, t_end, NULL, &t_end, NULL);
  if (!(t_end >= t0))
    return api__fail(e, 422, "invalid-value", "/t_end",
                     "t_end must not be before t0");
  if (t_end - t0 > lim->max_horizon)
    return api__limit(e, "max_horizon", lim->max_horizon, "/t_end",
                      "the horizon t_end - t0 = %.6g (dimensionless) is over "
                      "the limit of %.6g",
                      t_end - t0, lim->max_horizon);
  rc = api__object(root, "", "samples", 0, &samp, e);
  if (rc < 0)
    return -1;
  if (rc == 0) {
    long long n = 0;
    json_t *tv = json_object_get(samp, "t");
    if (api__keys(samp, "/samples", SAMPLE_KEYS, e))
      return -1;
    if (tv) {
      if (json_object_get(samp, "n") || json_object_get(samp, "from") ||
          json_object_get(samp, "to"))
        return api__fail(e, 422, "invalid-value", "/samples/t",
                         "give either samples.t or samples.n (with from, to)");
      if (!json_is_array(tv) || json_array_size(tv) == 0)
        return api__fail(e, 422, "invalid-type", "/samples/t",
                         "/samples/t must be a non-empty array of times");
      size_t nt = json_array_size(tv);
      if (nt > lim->max_samples)
        return api__limit(e, "max_samples", (double)lim->max_samples,
                          "/samples/t", "%zu sample times, the limit is %zu",
                          nt, lim->max_samples);
      times = malloc(nt * sizeof *times);
      if (!times)
        return api__fail(e, 500, "internal", NULL, "out of memory");
      for (size_t i = 0; i < nt; i++) {
        json_t *x = json_array_get(tv, i);
        double t;
        if (!json_is_number(x)) {
          free(times);
          return api__fail(e, 422, "invalid-type", "/samples/t",
                           "/samples/t/%zu must be a number", i);
        }
        ss_from_physical(ap.omega, json_number_value(x), NULL, &t, NULL);
        if (t < t0 || t > t_end || (i > 0 && !(t >= times[i - 1]))) {
          free(times);
          return api__fail(e, 422, "invalid-value", "/samples/t",
                           "/samples/t/%zu: sample times must be ascending and "
                           "within [t0, t_end]",
                           i);
        }
        times[i] = t;
      }
      o.sample_times = times;
      o.n_sample_times = nt;
    } else {
      double from = t0, to = t_end;
      if (api__count(samp, "/samples", "n", 1, 1, 1000000000LL, &n, e) < 0)
        return -1;
      if ((size_t)n > lim->max_samples)
        return api__limit(e, "max_samples", (double)lim->max_samples,
                          "/samples/n",
                          "%lld samples asked for, the limit is "
                          "%zu",
                          n, lim->max_samples);
      int rf = api__number(samp, "/samples", "from", 0, &from, e);
      int rt = api__number(samp, "/samples", "to", 0, &to, e);
      if (rf < 0 || rt < 0)
        return -1;
      if (rf == 0)
        ss_from_physical(ap.omega, from, NULL, &from, NULL);
      if (rt == 0)
        ss_from_physical(ap.omega, to, NULL, &to, NULL);
      if (!(from >= t0 && to <= t_end && from <= to))
        return api__fail(e, 422, "invalid-value", "/samples",
                         "the sample window must satisfy t0 <= from <= to <= "
                         "t_end");
      o.n_samples = (size_t)n;
      o.sample_from = from;
      o.sample_to = to;
    }
  }
  ss_diag_clear(&d);
  if ((rc = ss_model_init(&m, &ap.p, &d))) {
    free(times);
    api__from_diag(e, rc, &d, "/params");
    return -1;
  }
  o.t0 = t0;
  o.t_end = t_end;
  o.stop_after = (size_t)stop_after;
  o.record_events = events;
  o.max_events = events && lim->max_event_list < lim->max_events
                     ? lim->max_event_list
                     : lim->max_events;
  o.max_samples = lim->max_samples;
  o.max_seconds = lim->max_seconds;
  rc = ss_simulate(&m, x0, &o, &r, &d);
  free(times);
  if (rc == SS_ELIMIT_EVENTS) {
    ss_sim_result_free(&r);
    if (events && o.max_events == lim->max_event_list)
      return api__limit(e, "max_event_list", (double)lim->max_event_list,
                        "/events",
                        "the run has more than %zu events to list; ask for "
                        "\"events\": false, a shorter t_end, or stop_after",
                        lim->max_event_list);
    return api__limit(e, "max_events", (double)lim->max_events, "/t_end",
                      "the run has more than %zu events before t_end; "
                      "shorten t_end or use stop_after",
                      lim->max_events);
  }
  if (rc == SS_ELIMIT_TIME) {
    ss_sim_result_free(&r);
    return api__limit(e, "max_seconds", lim->max_seconds, "/t_end",
                      "the computation needed more than %g s; shorten t_end",
                      lim->max_seconds);
  }
  if (rc) {
    ss_sim_result_free(&r);
    api__from_diag(e, rc, &d, "");
    return -1;
  }
  /* encode, in the units of the request */
  json_t *out = json_object(), *fin = json_object();
  double tt, xx[4];
  ss_to_physical(ap.omega, r.t, r.x, &tt, xx);
  api__set(fin, "t", api__real(tt));
  api__set(fin, "mode", mode_json(r.mode));
  api__set(fin, "x", api__vec4(xx));
  api__set(out, "final", fin);
  api__set(out, "n_events", json_integer((json_int_t)r.n_events));
  api__set(out, "n_grazing", json_integer((json_int_t)r.n_grazing));
  api__set(out, "perpetual_slip", json_boolean(r.perpetual));
  if (events) {
    json_t *ev = json_array();
    for (size_t i = 0; i < r.n_events; i++) {
      json_t *one = json_object();
      ss_to_physical(ap.omega, r.events[i].t, r.events[i].x, &tt, xx);
      api__set(one, "t", api__real(tt));
      api__set(one, "from", mode_json(r.events[i].from));
      api__set(one, "to", mode_json(r.events[i].to));
      api__set(one, "kind",
               json_string(r.events[i].kind == SS_EVENT_GRAZING
                               ? "grazing"
                               : "transition"));
      api__set(one, "x", api__vec4(xx));
      json_array_append_new(ev, one);
    }
    api__set(out, "events", ev);
  }
  if (r.n_samples || o.n_samples || o.n_sample_times) {
    api__set(out, "samples", samples_json(&r, ap.omega));
  }
  json_t *in = api__params_echo(&ap);
  double xin[4];
  ss_to_physical(ap.omega, t0, x0, &tt, xin);
  api__set(in, "initial", api__vec4(xin));
  api__set(in, "t0", api__real(tt));
  ss_to_physical(ap.omega, t_end, NULL, &tt, NULL);
  api__set(in, "t_end", api__real(tt));
  api__set(in, "events", json_boolean(events));
  if (stop_after)
    api__set(in, "stop_after", json_integer(stop_after));
  api__set(out, "input", in);
  api__set(out, "units",
           json_string(ap.physical ? "physical" : "dimensionless"));
  api__set(out, "version", json_string(SS_VERSION));
  ss_sim_result_free(&r);
  *res = out;
  return 0;
}

/* ------------------------------------------------------------------ */
/* /orbit and /stability                                               */
/* ------------------------------------------------------------------ */

static int parse_mode(const char *s, ss_mode *m) {
  if (strcmp(s, "slip") == 0)
    *m = SS_MODE_SLIP;
  else if (strcmp(s, "overshoot") == 0)
    *m = SS_MODE_OVERSHOOT;
  else if (strcmp(s, "stick") == 0)
    *m = SS_MODE_STICK;
  else
    return -1;
  return 0;
}

static json_t *jac_json(const double J[2][2], double omega) {
  /* in physical units the map acts on (z1, z1'): J' = D J D^-1, D =
   * diag(1, omega) */
  json_t *a = json_array();
  for (int i = 0; i < 2; i++) {
    json_t *row = json_array();
    for (int j = 0; j < 2; j++) {
      double s = (i == 1 ? omega : 1) / (j == 1 ? omega : 1);
      json_array_append_new(row, api__real(J[i][j] * s));
    }
    json_array_append_new(a, row);
  }
  return a;
}

static const char *const STAB_NOTE =
    "Stability of the fixed point of the Poincare map on the section (4.2) "
    "in (z1, z1'): all eigenvalues inside the unit circle means small "
    "perturbations, except during stick, stay near the orbit. This is "
    "neither Lyapunov nor orbital stability (the paper, section 4).";

static json_t *stab_json(const ss_stab *st, double omega) {
  json_t *s = json_object(), *ev = json_array();
  for (int i = 0; i < 2; i++) {
    json_t *p = json_array();
    json_array_append_new(p, api__real(st->eig_re[i]));
    json_array_append_new(p, api__real(st->eig_im[i]));
    json_array_append_new(ev, p);
  }
  api__set(s, "eigenvalues", ev);
  api__set(s, "spectral_radius", api__real(st->spectral_radius));
  api__set(s, "stable", json_boolean(st->stable));
  api__set(s, "jacobian", jac_json(st->jac, omega));
  if (!isnan(st->jac_diff)) {
    api__set(s, "jacobian_fd", jac_json(st->jac_fd, omega));
    api__set(s, "jacobian_difference", api__real(st->jac_diff));
  }
  api__set(s, "note", json_string(STAB_NOTE));
  return s;
}

/* A margin: its value stays dimensionless (velocities in units of V's,
 * forces as chi (x2 - x1), in units of k1 + k2), its place t in the time unit
 * of the request. */
static json_t *margin_json(const ss_margin *mg, double omega) {
  json_t *o = json_object();
  api__set(o, "value", api__real(mg->value));
  if (mg->phase >= 0) {
    api__set(o, "phase", json_integer(mg->phase));
    api__set(o, "t", api__real(mg->t / omega));
  }
  return o;
}

static json_t *orbit_json(const ss_model *m, const ss_orbit *o, double omega,
                          long long n_samples, const api_limits *lim) {
  json_t *j = json_object(), *ph = json_array(), *mg = json_object();
  double x[4], z[4], t;
  api__set(j, "kind", json_string(ss_orbit_kind_name(o->kind)));
  for (int k = 0; k < o->n_phases; k++) {
    json_t *p = json_object();
    api__set(p, "mode", mode_json(o->modes[k]));
    api__set(p, "duration", api__real(o->durations[k] / omega));
    json_array_append_new(ph, p);
  }
  api__set(j, "phases", ph);
  api__set(j, "period", api__real(o->period / omega));
  api__set(j, "n_turns", json_integer(o->n_turns));
  ss_to_physical(omega, 0, o->z0, &t, z);
  ss_to_physical(omega, 0, o->x0, &t, x);
  api__set(j, "z0", api__vec4(z));
  api__set(j, "x0", api__vec4(x));
  api__set(mg, "slip_below_V", margin_json(&o->slip_below, omega));
  api__set(mg, "overshoot_above_V", margin_json(&o->over_above, omega));
  api__set(mg, "stick_below_ur", margin_json(&o->stick_upper, omega));
  api__set(mg, "stick_above_minus_ur", margin_json(&o->stick_lower, omega));
  api__set(mg, "switching", margin_json(&o->switching, omega));
  api__set(mg, "transversality", margin_json(&o->transversal, omega));
  api__set(mg, "min", margin_json(&o->min_margin, omega));
  api__set(
      mg, "units",
      json_string(
          omega == 1
              ? "dimensionless"
              : "values dimensionless; t in the time unit of the request"));
  api__set(j, "margins", mg);
  api__set(j, "residual", api__real(o->residual));
  api__set(j, "closure", api__real(o->closure));
  api__set(j, "stability", stab_json(&o->stab, omega));
  api__set(j, "iterations", json_integer(o->iterations));
  static const char *const src[] = {"guess", "simulation", "duration-grid",
                                    "poincare-newton"};
  api__set(j, "source", json_string(src[o->source & 3]));
  if (n_samples > 0) {
    ss_sim_opts so;
    ss_sim_result r;
    memset(&so, 0, sizeof so);
    so.t_end = o->period;
    so.n_samples = (size_t)n_samples;
    so.sample_from = 0;
    so.sample_to = o->period;
    so.max_events = 64 * (size_t)o->n_phases;
    so.max_seconds = lim->max_seconds;
    if (ss_simulate(m, o->x0, &so, &r, NULL) == SS_OK)
      api__set(j, "samples", samples_json(&r, omega));
    ss_sim_result_free(&r);
  }
  return j;
}

static const char *const ORBIT_REQ_KEYS[] = {
    "params",     "physical",          "kind", "guess", "samples", "effort",
    "max_period", "finite_difference", NULL};
static const char *const GUESS_KEYS[] = {"durations", "modes", NULL};

/* phases: an array of modes (strings) or of {mode, duration} objects. */
static int parse_modes(const json_t *arr, const char *ptr, int n_expect,
                       ss_mode *modes, double *dur, api_err *e) {
  if (!json_is_array(arr) || json_array_size(arr) < 2 ||
      json_array_size(arr) > SS_MAX_PHASES ||
      (n_expect > 0 && (int)json_array_size(arr) != n_expect))
    return api__fail(e, 422, "invalid-type", ptr,
                     n_expect > 0 ? "%s must have one entry per duration"
                                  : "%s must be an array of 2 to 16 phases",
                     ptr);
  for (size_t i = 0; i < json_array_size(arr); i++) {
    json_t *v = json_array_get(arr, i);
    const char *s = NULL;
    char p[160];
    snprintf(p, sizeof p, "%s/%zu", ptr, i);
    if (json_is_string(v) && !dur) {
      s = json_string_value(v);
    } else if (json_is_object(v) && dur) {
      static const char *const PK[] = {"mode", "duration", NULL};
      if (api__keys(v, p, PK, e) || api__string(v, p, "mode", 1, &s, e) ||
          api__number(v, p, "duration", 1, &dur[i], e))
        return -1;
      if (!(dur[i] > 0))
        return api__fail(e, 422, "invalid-value", p, "%s/duration must be > 0",
                         p);
    } else {
      return api__fail(e, 422, "invalid-type", p,
                       dur ? "%s must be a phase {mode, duration}"
                           : "%s must be a mode name",
                       p);
    }
    if (parse_mode(s, &modes[i]))
      return api__fail(e, 422, "invalid-value", p,
                       "%s must be \"slip\", \"overshoot\" or \"stick\"", p);
  }
  size_t n = json_array_size(arr);
  if (modes[0] != SS_MODE_SLIP || modes[n - 1] != SS_MODE_STICK)
    return api__fail(e, 422, "invalid-value", ptr,
                     "%s must start with slip (at the stick -> slip point) "
                     "and end with stick",
                     ptr);
  for (size_t i = 1; i < n; i++)
    if (modes[i] == modes[i - 1])
      return api__fail(e, 422, "invalid-value", ptr,
                       "%s repeats a mode in two consecutive phases", ptr);
  return (int)n;
}

static int orbit(const json_t *root, const api_limits *lim, json_t **res,
                 api_err *e) {
  api_params ap;
  ss_orbit_opts opts;
  ss_model m;
  ss_diag d;
  const char *kind = NULL;
  json_t *guess = NULL;
  long long samples = 0, effort = 2, max_period = 4;
  int fd = 1, rc;
  memset(&opts, 0, sizeof opts);
  if (api__keys(root, "", ORBIT_REQ_KEYS, e) || api__params(root, &ap, e))
    return -1;
  if (api__string(root, "", "kind", 0, &kind, e) < 0 ||
      api__object(root, "", "guess", 0, &guess, e) < 0 ||
      api__count(root, "", "effort", 0, 1, 3, &effort, e) < 0 ||
      api__count(root, "", "max_period", 0, 1, 8, &max_period, e) < 0 ||
      api__bool(root, "", "finite_difference", 0, &fd, e) < 0 ||
      api__count(root, "", "samples", 0, 0, (long long)lim->max_samples,
                 &samples, e) < 0)
    return -1;
  if (kind) {
    if (strcmp(kind, "overshoot") == 0)
      opts.kinds = SS_ORBIT_OVERSHOOT;
    else if (strcmp(kind, "stick-slip") == 0)
      opts.kinds = SS_ORBIT_STICKSLIP;
    else if (strcmp(kind, "other") == 0)
      opts.kinds = SS_ORBIT_OTHER;
    else if (strcmp(kind, "all") == 0)
      opts.kinds = SS_ORBIT_ALL;
    else
      return api__fail(e, 422, "invalid-value", "/kind",
                       "/kind must be \"overshoot\", \"stick-slip\", "
                       "\"other\" or \"all\"");
  }
  if (guess) {
    json_t *du;
    if (api__keys(guess, "/guess", GUESS_KEYS, e))
      return -1;
    du = json_object_get(guess, "durations");
    if (!json_is_array(du) || json_array_size(du) < 2 ||
        json_array_size(du) > SS_MAX_PHASES)
      return api__fail(e, 422, "invalid-type", "/guess/durations",
                       "/guess/durations must be an array of 2 to 16 "
                       "durations");
    opts.n_guess = (int)json_array_size(du);
    for (int i = 0; i < opts.n_guess; i++) {
      json_t *v = json_array_get(du, (size_t)i);
      if (!json_is_number(v) || !(json_number_value(v) > 0))
        return api__fail(e, 422, "invalid-value", "/guess/durations",
                         "/guess/durations/%d must be a number > 0", i);
      opts.guess[i] = json_number_value(v) * ap.omega;
    }
    json_t *mo = json_object_get(guess, "modes");
    if (mo) {
      if (parse_modes(mo, "/guess/modes", opts.n_guess, opts.guess_modes, NULL,
                      e) < 0)
        return -1;
    } else if (opts.n_guess > 3) {
      return api__fail(e, 422, "missing-field", "/guess/modes",
                       "a guess with more than 3 durations needs its modes");
    } else {
      /* by length: 3 overshoot, 2 stick-slip */
      ss_mode ov[3] = {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK};
      ss_mode ss[2] = {SS_MODE_SLIP, SS_MODE_STICK};
      memcpy(opts.guess_modes, opts.n_guess == 3 ? ov : ss,
             (size_t)opts.n_guess * sizeof(ss_mode));
    }
  }
  opts.effort = (int)effort;
  opts.max_period = (int)max_period;
  opts.no_fd = !fd;
  opts.max_seconds = lim->max_seconds;
  ss_diag_clear(&d);
  if ((rc = ss_model_init(&m, &ap.p, &d))) {
    api__from_diag(e, rc, &d, "/params");
    return -1;
  }
  int max_out = lim->max_orbits > 0 ? lim->max_orbits : 1, n = 0;
  ss_orbit *out = calloc((size_t)max_out, sizeof *out);
  ss_orbit_report rep;
  if (!out)
    return api__fail(e, 500, "internal", NULL, "out of memory");
  rc = ss_orbit_find(&m, &opts, out, max_out, &n, &rep, &d);
  if (rc == SS_ELIMIT_TIME) {
    free(out);
    return api__limit(e, "max_seconds", lim->max_seconds, "",
                      "the orbit search needed more than %g s; lower effort "
                      "or max_period, or give a guess",
                      lim->max_seconds);
  }
  if (rc) {
    free(out);
    api__from_diag(e, rc, &d, "");
    return -1;
  }
  json_t *res_o = json_object(), *arr = json_array();
  if ((size_t)samples * (size_t)(n ? n : 1) > lim->max_samples) {
    free(out);
    json_decref(res_o);
    json_decref(arr);
    return api__limit(e, "max_samples", (double)lim->max_samples, "/samples",
                      "%lld samples for each of %d orbits is over the limit "
                      "of %zu",
                      samples, n, lim->max_samples);
  }
  for (int i = 0; i < n; i++)
    json_array_append_new(arr, orbit_json(&m, &out[i], ap.omega, samples, lim));
  api__set(res_o, "orbits", arr);
  if (rep.reason[0])
    api__set(res_o, "reason", json_string(rep.reason));
  json_t *se = json_object();
  api__set(se, "method", json_string(opts.n_guess ? "guess" : "search"));
  api__set(se, "simulations", json_integer(rep.simulations));
  api__set(se, "newton_starts", json_integer(rep.newton_starts));
  api__set(se, "roots", json_integer(rep.roots));
  api__set(se, "infeasible", json_integer(rep.infeasible));
  api__set(se, "duplicates", json_integer(rep.duplicates));
  api__set(se, "truncated", json_integer(rep.truncated));
  api__set(res_o, "search", se);
  json_t *in = api__params_echo(&ap);
  api__set(in, "kind", json_string(kind ? kind : "all"));
  api__set(in, "effort", json_integer(effort));
  api__set(in, "max_period", json_integer(max_period));
  api__set(in, "finite_difference", json_boolean(fd));
  api__set(in, "samples", json_integer(samples));
  if (opts.n_guess) {
    json_t *g = json_object(), *du = json_array(), *mo = json_array();
    for (int i = 0; i < opts.n_guess; i++) {
      json_array_append_new(du, api__real(opts.guess[i] / ap.omega));
      json_array_append_new(mo, mode_json(opts.guess_modes[i]));
    }
    api__set(g, "durations", du);
    api__set(g, "modes", mo);
    api__set(in, "guess", g);
  }
  api__set(res_o, "input", in);
  api__set(res_o, "units",
           json_string(ap.physical ? "physical" : "dimensionless"));
  api__set(res_o, "version", json_string(SS_VERSION));
  free(out);
  *res = res_o;
  return 0;
}

static const char *const STAB_REQ_KEYS[] = {
    "params", "physical", "orbit", "phases", "z0", "finite_difference", NULL};

static int stability(const json_t *root, const api_limits *lim, json_t **res,
                     api_err *e) {
  api_params ap;
  ss_model m;
  ss_diag d;
  json_t *orb = NULL, *src;
  const char *base;
  ss_mode modes[SS_MAX_PHASES];
  double dur[SS_MAX_PHASES], z0[4];
  int fd = 1, n, rc;
  (void)lim;
  if (api__keys(root, "", STAB_REQ_KEYS, e) || api__params(root, &ap, e) ||
      api__bool(root, "", "finite_difference", 0, &fd, e) < 0)
    return -1;
  rc = api__object(root, "", "orbit", 0, &orb, e);
  if (rc < 0)
    return -1;
  if (rc == 0) {
    if (json_object_get(root, "phases") || json_object_get(root, "z0"))
      return api__fail(e, 422, "invalid-value", "/orbit",
                       "give either orbit or phases and z0, not both");
    if (api__keys(orb, "/orbit", ORBIT_KEYS, e))
      return -1;
    src = orb;
    base = "/orbit";
  } else {
    src = (json_t *)root;
    base = "";
  }
  char pp[64], pz[64];
  snprintf(pp, sizeof pp, "%s/phases", base);
  snprintf(pz, sizeof pz, "%s/z0", base);
  json_t *ph = json_object_get(src, "phases");
  if (!ph)
    return api__fail(e, 422, "missing-field", pp,
                     "the required field %s is missing", pp);
  if ((n = parse_modes(ph, pp, 0, modes, dur, e)) < 0)
    return -1;
  if (api__vec(src, base, "z0", 1, 4, z0, e))
    return -1;
  for (int k = 0; k < n; k++)
    dur[k] *= ap.omega;
  ss_from_physical(ap.omega, 0, z0, NULL, z0);
  ss_diag_clear(&d);
  if ((rc = ss_model_init(&m, &ap.p, &d))) {
    api__from_diag(e, rc, &d, "/params");
    return -1;
  }
  /* the orbit as given: is it one? */
  ss_orbit o;
  memset(&o, 0, sizeof o);
  o.n_phases = n;
  memcpy(o.modes, modes, (size_t)n * sizeof *modes);
  memcpy(o.durations, dur, (size_t)n * sizeof *dur);
  memcpy(o.z0, z0, sizeof z0);
  o.kind = ss_orbit_kind_of(n, modes);
  ss_diag dc;
  ss_diag_clear(&dc);
  int feas = ss_orbit_check(&m, &o, &dc);
  int turns = 0;
  for (int k = 0; k < n; k++)
    turns += modes[k] == SS_MODE_STICK &&
             (k + 1 == n || modes[k + 1] == SS_MODE_SLIP);
  ss_stab st;
  rc = ss_stability(&m, n, modes, dur, z0, turns, !fd, &st);
  if (rc == SS_ESINGULAR)
    return api__fail(e, 422, "invalid-value", pp,
                     "a phase ends tangentially (grazing): the Poincare map "
                     "is not differentiable there");
  if (rc) {
    api__from_diag(e, rc, &d, base);
    return -1;
  }
  json_t *out = stab_json(&st, ap.omega);
  const ss_params *p = &m.p;
  double sec = p->chi * (z0[1] - z0[0]) - (p->ur - p->us);
  double sec2 = z0[3] - p->V;
  api__set(out, "section_residual", api__real(fmax(fabs(sec), fabs(sec2))));
  api__set(out, "feasible", json_boolean(feas == SS_OK));
  if (feas == SS_OK)
    api__set(out, "closure", api__real(o.closure));
  else
    api__set(out, "reason", json_string(dc.text));
  json_t *in = api__params_echo(&ap);
  json_t *pa = json_array();
  for (int k = 0; k < n; k++) {
    json_t *one = json_object();
    api__set(one, "mode", mode_json(modes[k]));
    api__set(one, "duration", api__real(dur[k] / ap.omega));
    json_array_append_new(pa, one);
  }
  double zz[4];
  ss_to_physical(ap.omega, 0, z0, NULL, zz);
  api__set(in, "phases", pa);
  api__set(in, "z0", api__vec4(zz));
  api__set(in, "finite_difference", json_boolean(fd));
  api__set(out, "input", in);
  api__set(out, "units",
           json_string(ap.physical ? "physical" : "dimensionless"));
  api__set(out, "version", json_string(SS_VERSION));
  *res = out;
  return 0;
}

int api_handle(api_endpoint ep, const char *body, size_t len,
               const api_limits *lim, api_response *out) {
  api_err e;
  json_error_t jerr;
  json_t *root, *res = NULL;
  int rc;
  memset(&e, 0, sizeof e);
  memset(out, 0, sizeof *out);
  if (len == 0) {
    api__fail(&e, 400, "invalid-json", NULL,
              "the request body is empty; send a JSON object");
    api__problem_response(&e, out);
    return out->status;
  }
  if (too_deep(body, len, lim->max_depth)) {
    api__fail(&e, 400, "invalid-json", NULL,
              "the JSON nesting is deeper than %d levels", lim->max_depth);
    api__problem_response(&e, out);
    return out->status;
  }
  root = json_loadb(body, len, JSON_REJECT_DUPLICATES, &jerr);
  if (!root) {
    api__fail(&e, 400, "invalid-json", NULL,
              "the body is not valid JSON: %s (line %d, column %d)", jerr.text,
              jerr.line, jerr.column);
    api__problem_response(&e, out);
    return out->status;
  }
  if (!json_is_object(root)) {
    api__fail(&e, 422, "invalid-type", "",
              "the request body must be a JSON object");
  } else {
    switch (ep) {
    case API_ORBIT:
      rc = orbit(root, lim, &res, &e);
      break;
    case API_SIMULATE:
      rc = simulate(root, lim, &res, &e);
      break;
    case API_STABILITY:
      rc = stability(root, lim, &res, &e);
      break;
    default:
      rc = api__fail(&e, 404, "not-found", NULL, "unknown endpoint");
    }
    (void)rc;
  }
  json_decref(root);
  if (e.status) {
    json_decref(res);
    api__problem_response(&e, out);
    return out->status;
  }
  out->body = api__dump(res, &out->len);
  json_decref(res);
  if (!out->body) {
    api__fail(&e, 500, "internal", NULL, "could not encode the response");
    api__problem_response(&e, out);
    return out->status;
  }
  out->status = 200;
  out->content_type = "application/json";
  return 200;
}
