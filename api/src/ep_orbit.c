/*
 * ep_orbit.c: POST /orbit, the periodic orbits for given parameters, with
 * no guess (the core's search) or from a guess of the phase durations.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "endpoints.h"
#include "decode.h"
#include "encode.h"
#include "problem.h"
#include "samples.h"
#include "values.h"

static const char *const KINDS[] = {"overshoot", "stick-slip", "other", "all",
                                    NULL};
static const unsigned KIND_MASK[] = {SS_ORBIT_OVERSHOOT, SS_ORBIT_STICKSLIP,
                                     SS_ORBIT_OTHER, SS_ORBIT_ALL};

typedef struct orbit_x {
  /* the request, in its own units */
  api_params ap;
  int kind;
  api_guess guess;
  int has_guess;
  api_samples_req samples; /* an integer n, or the object */
  int samples_object;      /* given as the object */
  long long effort, max_period;
  int finite_difference;
  int certify;
  double certify_seconds;
  /* for the core, dimensionless */
  ss_model m;
  ss_orbit_opts opts;
  /* the answer */
  ss_orbit *orbits; /* room for max_orbits */
  int n;
  ss_orbit_report rep;
  ss_sim_result *paths; /* n sampled periods when samples > 0 */
} orbit_x;

/* "samples": n (evenly over each period), or {"n"} or {"tolerance", ...}
 * with "fields" (samples.c). */
static int decode_samples(const json_t *v, const char *ptr, void *dest,
                          const api_call *c) {
  orbit_x *x = (orbit_x *)((char *)dest - offsetof(orbit_x, samples));
  if (json_is_object(v)) {
    x->samples_object = 1;
    return api__decode(&API_ORBIT_SAMPLES, v, ptr, &x->samples, c);
  }
  json_int_t n = json_is_integer(v) ? json_integer_value(v) : -1;
  if (n < 0)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be a whole number of samples per period, or an "
                     "object ({\"n\"} or {\"tolerance\"}, with \"fields\")",
                     ptr);
  if ((unsigned long long)n > c->lim->max_samples)
    return api__limit(c->e, "max_samples", (double)c->lim->max_samples, ptr,
                      "%lld samples, the limit is %zu", (long long)n,
                      c->lim->max_samples);
  x->samples.n = n;
  x->samples.has_n = n > 0;
  return 0;
}

static json_t *echo_samples(const void *dest) {
  const orbit_x *x =
      (const orbit_x *)((const char *)dest - offsetof(orbit_x, samples));
  if (x->samples_object)
    return api__echo(&API_ORBIT_SAMPLES, &x->samples);
  return json_integer(x->samples.n);
}

static const api_custom SAMPLES = {decode_samples, echo_samples};

static const api_field FIELDS[] = {
    API_PARAMS_FIELDS(orbit_x, ap),
    {"kind", API_T_ENUM, API_DEFAULT, 0, 0, NULL, offsetof(orbit_x, kind), 0, 0,
     0, KINDS},
    {"guess", API_T_OBJECT, 0, 0, 0, NULL, offsetof(orbit_x, guess),
     API_HAS(orbit_x, has_guess), 0, 0, &API_GUESS_SPEC},
    {"samples", API_T_CUSTOM, API_DEFAULT, 0, 0, NULL,
     offsetof(orbit_x, samples), 0, 0, 0, &SAMPLES},
    {"effort", API_T_COUNT, API_DEFAULT, 1, 3, NULL, offsetof(orbit_x, effort)},
    {"max_period", API_T_COUNT, API_DEFAULT, 1, 8, NULL,
     offsetof(orbit_x, max_period)},
    {"finite_difference", API_T_BOOL, API_DEFAULT, 0, 0, NULL,
     offsetof(orbit_x, finite_difference)},
    {"certify", API_T_BOOL, API_DEFAULT, 0, 0, NULL,
     offsetof(orbit_x, certify)},
    {"certify_seconds", API_T_NUMBER, API_DEFAULT, 0.01, 3600, NULL,
     offsetof(orbit_x, certify_seconds)},
};
static const api_spec SPEC = API_SPEC(FIELDS);

/* Every conversion of the request's units into the core's options. */
static void to_core(orbit_x *x, const api_limits *lim) {
  ss_orbit_opts *o = &x->opts;
  o->kinds = KIND_MASK[x->kind];
  if (x->has_guess) {
    o->n_guess = x->guess.durations.n;
    for (int k = 0; k < o->n_guess; k++)
      o->guess[k] = api__time_in(&x->ap, x->guess.durations.v[k]);
    memcpy(o->guess_modes, x->guess.modes.m,
           (size_t)o->n_guess * sizeof(ss_mode));
  }
  o->effort = (int)x->effort;
  o->max_period = (int)x->max_period;
  o->difference_check = x->finite_difference;
  o->max_seconds = lim->max_seconds;
  o->certify = x->certify;
  o->certify_seconds = x->certify_seconds;
}

/* The client's hang-up, as the server reports it, stops the search. */
static void cancel_hook(ss_orbit_opts *o, const api_call *c) {
  if (c->srv && c->srv->cancelled) {
    o->cancelled = c->srv->cancelled;
    o->cancel_cls = c->srv->cancel_cls;
  }
}

/* Whether the work is small and bounded (api_server_info.small_only): a
 * Newton solve from a guess (its iterations capped) with no samples, whose
 * phases' events are found over at most SMALL_TIME (about a hundred periods
 * of the paper's orbit), at ten microseconds or so. */
#define SMALL_TIME 1000.0
static int is_small(const orbit_x *x) {
  double total = 0;
  for (int k = 0; k < x->opts.n_guess; k++)
    total += x->opts.guess[k];
  return x->has_guess && !x->samples.has_n && !x->samples.has_tolerance &&
         total <= SMALL_TIME;
}

int ep_orbit_decode(const json_t *root, const api_call *c, void **xp) {
  orbit_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->kind = 3; /* all */
  x->effort = 2;
  x->max_period = 4;
  x->finite_difference = 1;
  x->certify_seconds = 10;
  if (api__decode_request(&SPEC, root, x, &x->ap, c) ||
      (x->has_guess && api__guess_modes(&x->guess, "/guess", c)))
    return -1;
  if (x->has_guess && x->certify)
    return api__fail(c->e, API_P_INVALID_VALUE, "/certify",
                     "/certify proves what the search without a guess "
                     "finds; leave out /guess or /certify");
  to_core(x, c->lim);
  cancel_hook(&x->opts, c);
  if (c->small)
    *c->small = is_small(x);
  return api__model(&x->m, &x->ap, c);
}

/* One period of each orbit, sampled evenly or placed for a curve, for
 * plotting. */
static int sample_paths(orbit_x *x, const api_call *c) {
  const api_samples_req *s = &x->samples;
  if (!(s->has_n || s->has_tolerance) || x->n == 0)
    return 0;
  if (!(x->paths = calloc((size_t)x->n, sizeof *x->paths)))
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  size_t used = 0; /* curves' samples so far: all of them within the limit */
  for (int i = 0; i < x->n; i++) {
    const ss_orbit *o = &x->orbits[i];
    ss_sim_opts so;
    memset(&so, 0, sizeof so);
    so.t_end = o->period;
    so.n_samples = s->has_n ? (size_t)s->n : 0;
    so.sample_to = o->period;
    if (api__samples_core(s, &x->ap, "/samples", &so, c))
      return -1;
    if (s->has_tolerance) {
      /* a curve ends where the period does, at its last event (found to
       * rounding either side of the period): its stick -> slip point */
      so.stop_after = (size_t)o->n_phases;
      so.start_in_mode = 1;
      so.start_mode = o->modes[0];
      so.t_end = so.sample_to = o->period * (1 + 1e-9) + 1e-12;
      size_t left = c->lim->max_samples - used;
      if (so.max_samples > left) /* the curves together */
        so.max_samples = left;
    }
    so.max_events = 64 * (size_t)o->n_phases;
    so.max_seconds = c->lim->max_seconds;
    so.cancelled = x->opts.cancelled;
    so.cancel_cls = x->opts.cancel_cls;
    int rc = ss_simulate(&x->m, o->x0, &so, &x->paths[i], NULL);
    if (rc == SS_ELIMIT_SAMPLES)
      return api__status_limit(
          c->e, rc, "max_samples", (double)so.max_samples, "/samples/tolerance",
          "the tolerance %g needs more than %zu samples over the period of "
          "orbit %d (the %zu samples of all the orbits' curves are within "
          "--max-samples); give a larger tolerance or scale, or a larger max",
          so.sample_tolerance, so.max_samples, i, c->lim->max_samples);
    used += x->paths[i].n_samples;
    if (rc != SS_OK)
      ss_sim_result_free(&x->paths[i]);
  }
  return 0;
}

int ep_orbit_run(void *xp, const api_call *c) {
  orbit_x *x = xp;
  const api_limits *lim = c->lim;
  /* a guess gives one orbit at most: room for one, not for max_orbits */
  int max_out = x->opts.n_guess > 0   ? 1
                : lim->max_orbits > 0 ? lim->max_orbits
                                      : 1;
  ss_diag d;
  if (!(x->orbits = calloc((size_t)max_out, sizeof *x->orbits)))
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  ss_diag_clear(&d);
  int rc =
      ss_orbit_find(&x->m, &x->opts, x->orbits, max_out, &x->n, &x->rep, &d);
  if (rc == SS_ELIMIT_TIME)
    return api__status_limit(c->e, rc, "max_seconds", lim->max_seconds, "",
                             "the orbit search needed more than %g s; lower "
                             "effort or max_period, or give a guess",
                             lim->max_seconds);
  if (rc)
    return api__from_diag(c->e, rc, &d, "");
  if ((size_t)x->samples.n * (size_t)(x->n ? x->n : 1) > lim->max_samples)
    return api__limit(c->e, "max_samples", (double)lim->max_samples, "/samples",
                      "%lld samples for each of %d orbits is over the limit "
                      "of %zu",
                      x->samples.n, x->n, lim->max_samples);
  return sample_paths(x, c);
}

/* A margin: its value stays dimensionless (velocities in units of V's,
 * forces as chi (x2 - x1), in units of k1 + k2), its place t in the time unit
 * of the request; the condition it measures when @a condition. */
static void w_margin(api_wbuf *w, const ss_margin *mg, const api_params *ap,
                     const char *condition) {
  API_W_LIT(w, "{\"value\":");
  api__w_real(w, mg->value);
  if (mg->phase >= 0) {
    API_W_LIT(w, ",\"phase\":");
    api__w_int(w, mg->phase);
    API_W_LIT(w, ",\"t\":");
    api__w_real(w, api__time_out(ap, mg->t));
  }
  if (condition) {
    API_W_LIT(w, ",\"condition\":");
    api__w_str(w, condition, strlen(condition));
  }
  API_W_LIT(w, "}");
}

static void w_margins(api_wbuf *w, const ss_orbit *o, const api_params *ap) {
  const ss_margin *each[] = {&o->slip_below,  &o->over_above, &o->stick_upper,
                             &o->stick_lower, &o->switching,  &o->transversal};
  static const char UNITS[] =
      "values dimensionless; t in the time unit of the request";
  API_W_LIT(w, "{");
  for (int k = 0; k < 6; k++) { /* SS_MARGIN_SLIP_BELOW_V .. _TRANSVERSALITY */
    const char *name =
        ss_margin_name((ss_margin_id)(SS_MARGIN_SLIP_BELOW_V + k));
    api__w_str(w, name, strlen(name));
    API_W_LIT(w, ":");
    w_margin(w, each[k], ap, NULL);
    API_W_LIT(w, ",");
  }
  API_W_LIT(w, "\"min\":");
  w_margin(w, &o->min_margin, ap, NULL);
  API_W_LIT(w, ",\"units\":");
  if (ap->has_physical)
    api__w_str(w, UNITS, sizeof UNITS - 1);
  else
    API_W_LIT(w, "\"dimensionless\"");
  API_W_LIT(w, "}");
}

/* The margins of orbit l->a (k 0), or its violation (k 1), in the units of
 * l->b. */
static void margins_item(api_wbuf *w, const api_lazy *l, size_t i) {
  const ss_orbit *o = l->a;
  (void)i;
  if (l->k)
    w_margin(w, &o->violation, l->b, ss_margin_name(o->violation_id));
  else
    w_margins(w, o, l->b);
}

/* The members of orbit l->a, in the units of l->b, but for its samples. */
static void orbit_item(api_wbuf *w, const api_lazy *l, size_t i) {
  const ss_orbit *o = l->a;
  const api_params *ap = l->b;
  const char *kind = ss_orbit_kind_name(o->kind);
  const char *source = ss_orbit_source_name(o->source);
  (void)i;
  API_W_LIT(w, "\"kind\":");
  api__w_str(w, kind, strlen(kind));
  API_W_LIT(w, ",\"phases\":");
  api__w_phases(w, o, ap);
  API_W_LIT(w, ",\"period\":");
  api__w_real(w, api__time_out(ap, o->period));
  API_W_LIT(w, ",\"n_turns\":");
  api__w_int(w, o->n_turns);
  API_W_LIT(w, ",\"z0\":");
  api__w_state(w, ap, o->z0);
  API_W_LIT(w, ",\"x0\":");
  api__w_state(w, ap, o->x0);
  API_W_LIT(w, ",\"margins\":");
  w_margins(w, o, ap);
  API_W_LIT(w, ",\"residual\":");
  api__w_real(w, o->residual);
  API_W_LIT(w, ",\"closure\":");
  api__w_real(w, o->closure);
  API_W_LIT(w, ",\"stability\":");
  api__w_stability(w, &o->stab, ap);
  API_W_LIT(w, ",\"iterations\":");
  api__w_int(w, o->iterations);
  API_W_LIT(w, ",\"source\":");
  api__w_str(w, source, strlen(source));
}

/* An orbit: its members written from @a o when the answer is, and its
 * samples, a lazy array each column. */
static json_t *orbit_json(const ss_orbit *o, const ss_sim_result *path,
                          const api_params *ap, unsigned columns,
                          const api_call *c) {
  json_t *j = json_object();
  if (api__set_fields(j, c, orbit_item, o, ap, 0) ||
      (path && path->n_samples &&
       api__set(j, "samples", api__samples(path, ap, columns, c)))) {
    json_decref(j);
    return NULL;
  }
  return j;
}

/* The rejected root closest to feasible: its sequence, the condition it
 * fails by how much, where, and its margins up to that phase. */
static json_t *rejected_json(const ss_orbit_report *rep, const api_params *ap,
                             const api_call *c) {
  const ss_orbit *o = &rep->rejected;
  json_t *j = json_object();
  api__set(j, "kind", json_string(ss_orbit_kind_name(o->kind)));
  api__set(j, "phases", api__phases(c, o, ap));
  api__set(j, "violation", api__raw(c, margins_item, o, ap, 1));
  api__set(j, "margins", api__raw(c, margins_item, o, ap, 0));
  api__set(j, "reason", json_string(rep->reason));
  return j;
}

/* What the certificate of a period-1 family proved, and in which box. */
static json_t *cert_json(const ss_family_cert *fc, const api_params *ap) {
  json_t *j = json_object(), *box = json_object(), *d = json_array();
  api__set(j, "complete", json_boolean(fc->complete));
  for (int k = 0; k < fc->n_phases; k++)
    json_array_append_new(
        d, api__vec((double[2]){api__time_out(ap, fc->duration_lo[k]),
                                api__time_out(ap, fc->duration_hi[k])},
                    2));
  api__set(box, "durations", d);
  double lo[4] = {fc->x1_lo, 0, fc->v1_lo, 0},
         hi[4] = {fc->x1_hi, 0, fc->v1_hi, 0};
  json_t *l = api__state(ap, lo), *h = api__state(ap, hi);
  api__set(box, "x1",
           json_pack("[OO]", json_array_get(l, 0), json_array_get(h, 0)));
  api__set(box, "v1",
           json_pack("[OO]", json_array_get(l, 2), json_array_get(h, 2)));
  json_decref(l);
  json_decref(h);
  api__set(j, "box", box);
  api__set(j, "roots", json_integer(fc->roots));
  api__set(j, "orbits", json_integer(fc->orbits));
  api__set(j, "rejected", json_integer(fc->rejected));
  api__set(j, "added", json_integer(fc->added));
  api__set(j, "boxes", json_integer(fc->boxes));
  api__set(j, "seconds", api__real(fc->seconds));
  if (!fc->complete)
    api__set(j, "reason", json_string(fc->why));
  return j;
}

/* The "search" object: how the orbits were found, what the scan covered,
 * and, asked for, the families' certificates ("complete": false with the
 * reason where one was not made). */
static void search_item(api_wbuf *w, const api_lazy *l, size_t i) {
  const orbit_x *x = l->a;
  const ss_orbit_report *rep = &x->rep;
  (void)i;
  if (x->has_guess)
    API_W_LIT(w, "{\"method\":\"guess\"");
  else
    API_W_LIT(w, "{\"method\":\"search\"");
  API_W_LIT(w, ",\"simulations\":");
  api__w_int(w, rep->simulations);
  API_W_LIT(w, ",\"newton_starts\":");
  api__w_int(w, rep->newton_starts);
  API_W_LIT(w, ",\"roots\":");
  api__w_int(w, rep->roots);
  API_W_LIT(w, ",\"infeasible\":");
  api__w_int(w, rep->infeasible);
  API_W_LIT(w, ",\"duplicates\":");
  api__w_int(w, rep->duplicates);
  API_W_LIT(w, ",\"truncated\":");
  api__w_int(w, rep->truncated);
  /* what "every orbit of the two period-1 families" covered */
  if (rep->scan_box > 0) {
    API_W_LIT(w, ",\"scan\":{\"max_duration\":");
    api__w_real(w, api__time_out(&x->ap, rep->scan_box));
    API_W_LIT(w, ",\"max_duration_cap\":");
    api__w_real(w, api__time_out(&x->ap, rep->scan_box_cap));
    API_W_LIT(w, ",\"step\":");
    api__w_real(w, api__time_out(&x->ap, rep->scan_step));
    API_W_LIT(w, "}");
  }
  if (x->certify) {
    const char *name[2] = {"stick-slip", "overshoot"};
    int first = 1;
    API_W_LIT(w, ",\"certificate\":{");
    for (int f = 0; f < 2; f++) {
      if (!rep->cert[f].ran)
        continue;
      json_t *ce = cert_json(&rep->cert[f], &x->ap);
      if (!first)
        API_W_LIT(w, ",");
      first = 0;
      api__w_str(w, name[f], strlen(name[f]));
      API_W_LIT(w, ":");
      if (ce)
        api__w_json(w, ce);
      else
        w->oom = 1;
      json_decref(ce);
    }
    API_W_LIT(w, "}");
  }
  API_W_LIT(w, "}");
}

int ep_orbit_encode(const void *xp, const api_call *c, api_response *out) {
  const orbit_x *x = xp;
  json_t *o = json_object(), *arr = json_array();
  for (int i = 0; i < x->n; i++)
    json_array_append_new(
        arr, orbit_json(&x->orbits[i], x->paths ? &x->paths[i] : NULL, &x->ap,
                        api__samples_columns(&x->samples), c));
  api__set(o, "orbits", arr);
  /* reason explains an absence; a rejection is told with its numbers */
  if (x->n == 0 && x->rep.reason[0])
    api__set(o, "reason", json_string(x->rep.reason));
  if (x->rep.has_rejected)
    api__set(o, "rejected", rejected_json(&x->rep, &x->ap, c));
  api__set(o, "search", api__raw(c, search_item, x, NULL, 0));
  return api__answer(o, &SPEC, x, &x->ap, c, out);
}

void ep_orbit_release(void *xp) {
  orbit_x *x = xp;
  if (!x)
    return;
  for (int i = 0; x->paths && i < x->n; i++)
    ss_sim_result_free(&x->paths[i]);
  free(x->paths);
  free(x->orbits);
  api__samples_release(&x->samples);
  free(x);
}
