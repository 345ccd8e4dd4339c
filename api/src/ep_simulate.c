/*
 * ep_simulate.c: POST /simulate, the exact event-driven motion from any
 * state.  The client chooses what is computed: events listed or not,
 * samples evenly spaced, at given times or placed for a curve to a
 * tolerance, their columns, or only the final state.
 */
#include <stdlib.h>
#include <string.h>

#include "endpoints.h"
#include "decode.h"
#include "encode.h"
#include "problem.h"
#include "samples.h"
#include "values.h"
#include "writer.h"

typedef struct sim_x {
  /* the request, in its own units */
  api_params ap;
  double initial[4];
  double orbit_x0[4];
  int has_initial, has_orbit;
  double t0, t_end;
  int events;
  long long stop_after;
  int has_stop_after;
  api_samples_req samples;
  int has_samples;
  /* for the core, dimensionless */
  ss_model m;
  double x0[4];
  double *times; /* malloc'd */
  ss_sim_opts o;
  ss_sim_result r;
} sim_x;

/* An orbit as /orbit returns it: only its start x0 is used. */
#define X0                                                                     \
  { "x0", API_T_VEC4, API_REQUIRED, 0, 0, NULL, 0 }
static const api_field ORBIT_FIELDS[] = {
    API_ORBIT_FIELDS(X0, API_ANY("z0"), API_ANY("phases"))};
static const api_spec ORBIT_SPEC = API_SPEC(ORBIT_FIELDS);

static const api_field FIELDS[] = {
    API_PARAMS_FIELDS(sim_x, ap),
    {"initial", API_T_VEC4, API_REQUIRED | API_DEFAULT, 0, 0, NULL,
     offsetof(sim_x, initial), API_HAS(sim_x, has_initial), 2, 0},
    {"orbit", API_T_OBJECT, API_REQUIRED | API_ECHO_NEVER, 0, 0, NULL,
     offsetof(sim_x, orbit_x0), API_HAS(sim_x, has_orbit), 2, 1, &ORBIT_SPEC},
    {"t0", API_T_NUMBER, API_DEFAULT, 0, 0, NULL, offsetof(sim_x, t0)},
    {"t_end", API_T_NUMBER, API_REQUIRED, 0, 0, NULL, offsetof(sim_x, t_end)},
    {"events", API_T_BOOL, API_DEFAULT, 0, 0, NULL, offsetof(sim_x, events)},
    {"stop_after", API_T_COUNT, 0, 1, 1e18, "max_events",
     offsetof(sim_x, stop_after), API_HAS(sim_x, has_stop_after)},
    {"samples", API_T_OBJECT, API_ECHO_NEVER, 0, 0, NULL,
     offsetof(sim_x, samples), API_HAS(sim_x, has_samples), 0, 0,
     &API_SIM_SAMPLES},
};
static const api_spec SPEC = API_SPEC(FIELDS);

/* The sample times or window, dimensionless, checked against the run. */
static int samples_to_core(sim_x *x, const api_call *c) {
  const api_samples_req *s = &x->samples;
  const api_params *ap = &x->ap;
  if (api__samples_core(s, ap, "/samples", &x->o, c))
    return -1;
  if (s->has_t) {
    if (!(x->times = malloc(s->t.n * sizeof *x->times)))
      return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
    for (size_t i = 0; i < s->t.n; i++) {
      double t = api__time_in(ap, s->t.v[i]);
      if (t < x->o.t0 || t > x->o.t_end || (i > 0 && !(t >= x->times[i - 1])))
        return api__fail(c->e, API_P_INVALID_VALUE, "/samples/t",
                         "/samples/t/%zu: sample times must be ascending and "
                         "within [t0, t_end]",
                         i);
      x->times[i] = t;
    }
    x->o.sample_times = x->times;
    x->o.n_sample_times = s->t.n;
    return 0;
  }
  double from = s->has_from ? api__time_in(ap, s->from) : x->o.t0;
  double to = s->has_to ? api__time_in(ap, s->to) : x->o.t_end;
  if (!(from >= x->o.t0 && to <= x->o.t_end && from <= to))
    return api__fail(c->e, API_P_INVALID_VALUE, "/samples",
                     "the sample window must satisfy t0 <= from <= to <= "
                     "t_end");
  x->o.n_samples = s->has_n ? (size_t)s->n : 0;
  x->o.sample_from = from;
  x->o.sample_to = to;
  return 0;
}

/* Every conversion of the request's units, and the checks that need them. */
static int to_core(sim_x *x, const api_call *c) {
  const api_limits *lim = c->lim;
  ss_from_physical(x->ap.omega, x->t0, x->initial, &x->o.t0, x->x0);
  x->o.t_end = api__time_in(&x->ap, x->t_end);
  if (!(x->o.t_end >= x->o.t0))
    return api__fail(c->e, API_P_INVALID_VALUE, "/t_end",
                     "t_end must not be before t0");
  if (x->o.t_end - x->o.t0 > lim->max_horizon)
    return api__limit(c->e, "max_horizon", lim->max_horizon, "/t_end",
                      "the horizon t_end - t0 = %.6g (dimensionless) is over "
                      "the limit of %.6g",
                      x->o.t_end - x->o.t0, lim->max_horizon);
  if (x->has_samples && samples_to_core(x, c))
    return -1;
  x->o.stop_after = (size_t)x->stop_after;
  x->o.record_events = x->events;
  x->o.max_events = x->events && lim->max_event_list < lim->max_events
                        ? lim->max_event_list
                        : lim->max_events;
  if (!(x->has_samples && x->samples.has_tolerance))
    x->o.max_samples = lim->max_samples; /* else the curve's own */
  x->o.max_seconds = lim->max_seconds;
  if (c->srv && c->srv->cancelled) {
    x->o.cancelled = c->srv->cancelled;
    x->o.cancel_cls = c->srv->cancel_cls;
  }
  return 0;
}

int ep_simulate_decode(const json_t *root, const api_call *c, void **xp) {
  sim_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->events = 1;
  if (api__decode_request(&SPEC, root, x, &x->ap, c))
    return -1;
  if (x->has_orbit)
    memcpy(x->initial, x->orbit_x0, sizeof x->initial);
  if (to_core(x, c))
    return -1;
  return api__model(&x->m, &x->ap, c);
}

int ep_simulate_run(void *xp, const api_call *c) {
  sim_x *x = xp;
  const api_limits *lim = c->lim;
  ss_diag d;
  ss_diag_clear(&d);
  int rc = ss_simulate(&x->m, x->x0, &x->o, &x->r, &d);
  if (rc == SS_OK)
    return 0;
  if (rc == SS_ELIMIT_EVENTS && x->events &&
      x->o.max_events == lim->max_event_list)
    return api__status_limit(
        c->e, rc, "max_event_list", (double)lim->max_event_list, "/events",
        "the run has more than %zu events to list; ask for \"events\": "
        "false, a shorter t_end, or stop_after",
        lim->max_event_list);
  if (rc == SS_ELIMIT_EVENTS)
    return api__status_limit(c->e, rc, "max_events", (double)lim->max_events,
                             "/t_end",
                             "the run has more than %zu events before t_end; "
                             "shorten t_end or use stop_after",
                             lim->max_events);
  if (rc == SS_ELIMIT_SAMPLES)
    return api__status_limit(
        c->e, rc, "max_samples", (double)x->o.max_samples, "/samples/tolerance",
        "the tolerance %g needs more than %zu samples; give a larger "
        "tolerance or scale, a shorter window, or a larger max (up to the "
        "limit of %zu)",
        x->o.sample_tolerance, x->o.max_samples, lim->max_samples);
  if (rc == SS_ELIMIT_TIME)
    return api__status_limit(
        c->e, rc, "max_seconds", lim->max_seconds, "/t_end",
        "the computation needed more than %g s; shorten t_end",
        lim->max_seconds);
  return api__from_diag(c->e, rc, &d, "");
}

/* Event i of the result a: {t, from, to, kind, x}. */
static void event_item(api_wbuf *w, const api_lazy *l, size_t i) {
  const ss_event *ev = &((const ss_sim_result *)l->a)->events[i];
  const api_params *ap = l->b;
  const char *from = ss_mode_name(ev->from), *to = ss_mode_name(ev->to);
  const char *kind = ev->kind == SS_EVENT_GRAZING ? "grazing" : "transition";
  double y[4];
  API_W_LIT(w, "{\"t\":");
  api__w_real(w, api__time_out(ap, ev->t));
  API_W_LIT(w, ",\"from\":");
  api__w_str(w, from, strlen(from));
  API_W_LIT(w, ",\"to\":");
  api__w_str(w, to, strlen(to));
  API_W_LIT(w, ",\"kind\":");
  api__w_str(w, kind, strlen(kind));
  API_W_LIT(w, ",\"x\":[");
  ss_to_physical(ap->omega, 0, ev->x, NULL, y);
  for (int k = 0; k < 4; k++) {
    if (k)
      API_W_LIT(w, ",");
    api__w_real(w, y[k]);
  }
  API_W_LIT(w, "]}");
}

int ep_simulate_encode(const void *xp, const api_call *c, api_response *out) {
  const sim_x *x = xp;
  const ss_sim_result *r = &x->r;
  json_t *o = json_object(), *fin = json_object();
  api__set(fin, "t", api__real(api__time_out(&x->ap, r->t)));
  api__set(fin, "mode", json_string(ss_mode_name(r->mode)));
  api__set(fin, "x", api__state(&x->ap, r->x));
  api__set(o, "final", fin);
  api__set(o, "n_events", json_integer((json_int_t)r->n_events));
  api__set(o, "n_grazing", json_integer((json_int_t)r->n_grazing));
  api__set(o, "perpetual_slip", json_boolean(r->perpetual));
  if (x->events)
    api__set(o, "events",
             api__lazy(c, r->n_events, event_item, r, &x->ap, 0,
                       r->n_events * sizeof *r->events));
  if (x->has_samples)
    api__set(o, "samples",
             api__samples(r, &x->ap, api__samples_columns(&x->samples), c));
  return api__answer(o, &SPEC, x, &x->ap, c, out);
}

void ep_simulate_release(void *xp) {
  sim_x *x = xp;
  if (!x)
    return;
  api__samples_release(&x->samples);
  free(x->times);
  ss_sim_result_free(&x->r);
  free(x);
}
