/*
 * simulate.c: event-driven simulation of the non-smooth motion.
 *
 * Within a mode the state is the closed form from the last event (the
 * anchor); at each event the state is re-anchored, the mode is switched by the
 * rule of ss_mode_of_state(), and the search for the next event starts again
 * from local time zero.  No error accumulates within a phase, and absolute
 * time is carried as an unevaluated double-double sum so that event times
 * stay accurate over long runs.
 */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "internal.h"

double ss__now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int finite4(const double x[4]) {
  return isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]) && isfinite(x[3]);
}

int ss__sim_init_mode(ss_sim *s, const ss_model *m, double t0,
                      const double x0[4], ss_mode mode, ss_diag *d) {
  if (!s || !m || !x0)
    return ss__fail(d, SS_EINVAL, "initial", 0, "missing argument");
  if (!isfinite(t0))
    return ss__fail(d, SS_EINVAL, "t0", t0, "the start time must be finite");
  if (!finite4(x0))
    return ss__fail(d, SS_EINVAL, "initial", 0,
                    "the initial state must be four finite numbers");
  if (mode != SS_MODE_SLIP && mode != SS_MODE_OVERSHOOT &&
      mode != SS_MODE_STICK)
    return ss__fail(d, SS_EINVAL, "mode", mode, "unknown mode");
  double V = m->p.V, vtol = 4 * DBL_EPSILON * V;
  if ((mode == SS_MODE_SLIP && x0[3] > V + vtol) ||
      (mode == SS_MODE_OVERSHOOT && x0[3] < V - vtol))
    return ss__fail(d, SS_EINVAL, "mode", x0[3],
                    "x2' = %.17g is inconsistent with mode %s", x0[3],
                    ss_mode_name(mode));
  memset(s, 0, sizeof *s);
  s->m = m;
  s->mode = mode;
  s->t_hi = t0;
  s->t_lo = 0;
  memcpy(s->x, x0, sizeof s->x);
  if (fabs(s->x[3] - V) <= vtol || mode == SS_MODE_STICK)
    s->x[3] = V;
  return SS_OK;
}

int ss__sim_init(ss_sim *s, const ss_model *m, double t0, const double x0[4],
                 ss_diag *d) {
  if (!m || !x0 || !finite4(x0))
    return ss__fail(d, SS_EINVAL, "initial", 0,
                    "the initial state must be four finite numbers");
  return ss__sim_init_mode(s, m, t0, x0, ss_mode_of_state(m, x0), d);
}

ss_sim *ss_sim_new_mode(const ss_model *m, double t0, const double x0[4],
                        ss_mode mode, ss_diag *d) {
  ss_sim *s = malloc(sizeof *s);
  if (!s) {
    ss__fail(d, SS_ENOMEM, "", 0, "out of memory");
    return NULL;
  }
  if (ss__sim_init_mode(s, m, t0, x0, mode, d)) {
    free(s);
    return NULL;
  }
  return s;
}

ss_sim *ss_sim_new(const ss_model *m, double t0, const double x0[4],
                   ss_diag *d) {
  if (!m || !x0 || !finite4(x0)) {
    ss__fail(d, SS_EINVAL, "initial", 0,
             "the initial state must be four finite numbers");
    return NULL;
  }
  return ss_sim_new_mode(m, t0, x0, ss_mode_of_state(m, x0), d);
}

void ss_sim_free(ss_sim *s) { free(s); }

ss_mode ss_sim_mode(const ss_sim *s) { return s->mode; }

double ss_sim_time(const ss_sim *s) { return s->t_hi + s->t_lo; }

static double local_time(const ss_sim *s, double t) {
  return (t - s->t_hi) - s->t_lo;
}

/* Find the next event within local horizon H (cached). */
static int sim_find(ss_sim *s, double H) {
  ss_trig g;
  double t;
  int rc;
  if (s->have_next && (s->next_status != SS_HORIZON || H <= s->next_horizon))
    return SS_OK;
  s->have_next = 1;
  s->next_horizon = H;
  s->next_sign = 0;
  if (s->perpetual || !(H > 0)) {
    s->next_status = SS_HORIZON;
    s->t_next = INFINITY;
    return SS_OK;
  }
  if (s->mode != SS_MODE_STICK) {
    ss__switching(s->m, s->mode, 0, s->x, &g);
    rc = ss_trig_first_root(&g, 0, H, &t);
    /* x2' beyond V at the anchor contradicts the mode: the state is bad */
    if (rc == SS_ABOVE)
      rc = SS_EINVAL;
    if (rc == SS_NEVER) {
      s->perpetual = 1;
      s->next_status = SS_HORIZON;
      s->t_next = INFINITY;
      return SS_OK;
    }
    if (rc < 0) {
      s->have_next = 0;
      return rc;
    }
    s->next_status = rc;
    s->t_next = t;
    return SS_OK;
  }
  /* stick: the first of chi(x2-x1) = +ur and = -ur */
  double t_up, t_lo;
  int rc_lo;
  ss__switching(s->m, SS_MODE_STICK, 1, s->x, &g);
  rc = ss_trig_first_root(&g, 0, H, &t_up);
  /* a stick force already beyond +ur: the state is not a stick */
  if (rc == SS_ABOVE)
    rc = SS_EINVAL;
  if (rc < 0) {
    s->have_next = 0;
    return rc;
  }
  ss__switching(s->m, SS_MODE_STICK, -1, s->x, &g);
  rc_lo = ss_trig_first_root(&g, 0, rc == SS_HORIZON ? H : fmax(t_up, 1e-300),
                             &t_lo);
  /* SS_ABOVE: the force starts below -ur beyond the tolerance while the
   * search for +ur decided the state is a stick; -ur is then not the next
   * event, as if it were never reached. */
  if (rc_lo == SS_ABOVE)
    rc_lo = SS_HORIZON;
  if (rc_lo < 0) {
    s->have_next = 0;
    return rc_lo;
  }
  if ((rc_lo == SS_OK || rc_lo == SS_GRAZING) &&
      (rc == SS_HORIZON || t_lo < t_up)) {
    s->next_status = rc_lo;
    s->t_next = t_lo;
    s->next_sign = -1;
  } else {
    s->next_status = rc;
    s->t_next = t_up;
    s->next_sign = 1;
  }
  return SS_OK;
}

/* Peek: local time of the next event if it is no later than absolute t_stop.
 * Returns SS_OK with *tau, SS_HORIZON, or a failure. */
static int sim_peek(ss_sim *s, double t_stop, double *tau) {
  double H = local_time(s, t_stop);
  if (!(H >= 0))
    return SS_HORIZON;
  int rc = sim_find(s, H);
  if (rc)
    return rc;
  if (s->next_status == SS_HORIZON || s->t_next > H)
    return SS_HORIZON;
  *tau = s->t_next;
  return SS_OK;
}

/* The mode after a slip or overshoot phase ends with x2' = V. */
static ss_mode mode_after_slip(const ss_model *m, ss_mode from,
                               const double x[4]) {
  ss_mode to = ss_mode_of_state(m, x);
  /* From slip, x2' reaches V only where x2'' >= 0, that is chi(x2-x1) <= us
   * < ur, so slip cannot follow slip; likewise for overshoot.  A rounding
   * artefact at a tangency could say otherwise: the mass then sticks. */
  return to == from ? SS_MODE_STICK : to;
}

static void sim_commit(ss_sim *s, ss_event *ev) {
  double xe[4], tau = s->t_next;
  ss_mode from = s->mode, to;
  ss_event_kind kind =
      s->next_status == SS_GRAZING ? SS_EVENT_GRAZING : SS_EVENT_TRANSITION;
  ss_flow(s->m, from, tau, s->x, xe);
  xe[3] = s->m->p.V;
  if (from == SS_MODE_STICK)
    to = kind == SS_EVENT_GRAZING
             ? SS_MODE_STICK
             : (s->next_sign > 0 ? SS_MODE_SLIP : SS_MODE_OVERSHOOT);
  else
    to = mode_after_slip(s->m, from, xe);
  /* absolute time: (t_hi + t_lo) + tau, renormalised */
  double hi, err, lo;
  ss__two_sum(s->t_hi, tau, &hi, &err);
  lo = s->t_lo + err;
  ss__two_sum(hi, lo, &s->t_hi, &s->t_lo);
  memcpy(s->x, xe, sizeof xe);
  s->mode = to;
  s->have_next = 0;
  s->perpetual = 0;
  if (ev) {
    ev->t = s->t_hi + s->t_lo;
    ev->from = from;
    ev->to = to;
    ev->kind = kind;
    memcpy(ev->x, xe, sizeof xe);
  }
}

int ss_sim_next_event(ss_sim *s, double t_stop, ss_event *ev) {
  double tau;
  int rc = sim_peek(s, t_stop, &tau);
  if (rc)
    return rc;
  sim_commit(s, ev);
  return SS_OK;
}

void ss_sim_state_at(const ss_sim *s, double t, double x[4]) {
  ss_flow(s->m, s->mode, local_time(s, t), s->x, x);
  if (s->mode == SS_MODE_STICK)
    x[3] = s->m->p.V;
}

void ss_sim_advance(ss_sim *s, double t) {
  double tau = local_time(s, t);
  if (!(tau > 0))
    return;
  ss_flow(s->m, s->mode, tau, s->x, s->x);
  if (s->have_next && s->next_status != SS_HORIZON)
    s->t_next -= tau;
  else
    s->have_next = 0;
  if (s->have_next)
    s->next_horizon -= tau;
  s->t_hi = t;
  s->t_lo = 0;
}

/* ---- ss_simulate ---- */

typedef struct sampler {
  const ss_sim_opts *o;
  size_t n, i; /* total and next index */
  ss_sim_result *r;
} sampler;

static double sample_time(const sampler *sp, size_t i) {
  const ss_sim_opts *o = sp->o;
  if (o->sample_times)
    return o->sample_times[i];
  if (sp->n == 1)
    return o->sample_from;
  return o->sample_from +
         (o->sample_to - o->sample_from) * ((double)i / (double)(sp->n - 1));
}

/* Emit every sample with time <= t_until (< t_until if strict) from the
 * current phase of s. */
static void emit_samples(sampler *sp, const ss_sim *s, double t_until,
                         int strict) {
  while (sp->i < sp->n) {
    double ts = sample_time(sp, sp->i);
    if (strict ? ts >= t_until : ts > t_until)
      break;
    ss_sim_state_at(s, ts, sp->r->sx + 4 * sp->i);
    sp->r->st[sp->i] = ts;
    sp->r->smode[sp->i] = (unsigned char)s->mode;
    sp->i++;
  }
}

static int check_opts(const ss_sim_opts *o, size_t *n_samples, ss_diag *d) {
  if (!isfinite(o->t0))
    return ss__fail(d, SS_EINVAL, "t0", o->t0, "t0 must be finite");
  if (!isfinite(o->t_end) || !(o->t_end >= o->t0))
    return ss__fail(d, SS_EINVAL, "t_end", o->t_end,
                    "t_end must be finite and not before the start time");
  if (o->sample_times && o->n_samples)
    return ss__fail(d, SS_EINVAL, "samples", 0,
                    "give either sample times or an even sample count");
  if (o->sample_times) {
    for (size_t i = 0; i < o->n_sample_times; i++) {
      double t = o->sample_times[i];
      if (!isfinite(t) || t < o->t0 || t > o->t_end)
        return ss__fail(d, SS_EINVAL, "samples", t,
                        "sample time %zu (%.17g) lies outside [t0, t_end]", i,
                        t);
      if (i > 0 && !(t >= o->sample_times[i - 1]))
        return ss__fail(d, SS_EINVAL, "samples", t,
                        "sample times must be ascending (index %zu)", i);
    }
    *n_samples = o->n_sample_times;
  } else if (o->n_samples) {
    if (!isfinite(o->sample_from) || !isfinite(o->sample_to) ||
        o->sample_from < o->t0 || o->sample_to > o->t_end ||
        o->sample_from > o->sample_to)
      return ss__fail(d, SS_EINVAL, "samples", o->sample_from,
                      "the sample window must satisfy t0 <= from <= to <= "
                      "t_end");
    *n_samples = o->n_samples;
  } else {
    *n_samples = 0;
  }
  if (o->max_samples && *n_samples > o->max_samples)
    return ss__fail(d, SS_ELIMIT_SAMPLES, "samples", (double)*n_samples,
                    "%zu samples asked for, the limit is %zu", *n_samples,
                    o->max_samples);
  return SS_OK;
}

static int push_event(ss_sim_result *r, size_t *cap, const ss_event *ev) {
  if (r->n_events == *cap) {
    size_t nc = *cap ? 2 * *cap : 64;
    ss_event *e = realloc(r->events, nc * sizeof *e);
    if (!e)
      return SS_ENOMEM;
    r->events = e;
    *cap = nc;
  }
  r->events[r->n_events] = *ev;
  return SS_OK;
}

/* The time budget spent, or the caller cancelled: the status, else 0. */
static int must_stop(const ss_sim_opts *o, double t_start, ss_diag *d,
                     const ss_sim *s) {
  if (o->max_seconds > 0 && ss__now() - t_start > o->max_seconds)
    return ss__fail(d, SS_ELIMIT_TIME, "max_seconds", o->max_seconds,
                    "compute time budget of %g s exhausted at t = %.17g",
                    o->max_seconds, ss_sim_time(s));
  if (o->cancelled && o->cancelled(o->cancel_cls))
    return ss__fail(d, SS_ECANCELED, "", 0, "cancelled at t = %.17g",
                    ss_sim_time(s));
  return 0;
}

int ss_simulate(const ss_model *m, const double x0[4], const ss_sim_opts *o,
                ss_sim_result *r, ss_diag *d) {
  ss_sim s;
  sampler sp;
  size_t ns = 0, cap = 0;
  double t_start = 0, tau;
  int rc;
  if (!r)
    return ss__fail(d, SS_EINVAL, "result", 0, "no result struct");
  memset(r, 0, sizeof *r);
  if (!m || !x0 || !o)
    return ss__fail(d, SS_EINVAL, "", 0, "missing argument");
  if ((rc = check_opts(o, &ns, d)))
    return rc;
  if ((rc = ss__sim_init(&s, m, o->t0, x0, d)))
    return rc;
  if (ns) {
    r->st = malloc(ns * sizeof *r->st);
    r->sx = malloc(4 * ns * sizeof *r->sx);
    r->smode = malloc(ns);
    if (!r->st || !r->sx || !r->smode) {
      rc = ss__fail(d, SS_ENOMEM, "samples", (double)ns, "out of memory");
      goto fail;
    }
  }
  r->n_samples = ns;
  sp.o = o;
  sp.n = ns;
  sp.i = 0;
  sp.r = r;
  if (o->max_seconds > 0)
    t_start = ss__now();
  for (;;) {
    rc = sim_peek(&s, o->t_end, &tau);
    if (rc == SS_HORIZON)
      break;
    if (rc) {
      ss__fail(d, rc, ss_mode_name(s.mode), ss_sim_time(&s),
               "event search failed in %s at t = %.17g", ss_mode_name(s.mode),
               ss_sim_time(&s));
      goto partial;
    }
    if (o->max_events && r->n_events >= o->max_events) {
      rc = ss__fail(d, SS_ELIMIT_EVENTS, "max_events", (double)o->max_events,
                    "more than %zu events before t_end = %.17g; the run "
                    "stopped at t = %.17g",
                    o->max_events, o->t_end, ss_sim_time(&s));
      goto partial;
    }
    if ((r->n_events & 255) == 255 && (rc = must_stop(o, t_start, d, &s)))
      goto partial;
    /* samples of this phase, strictly before the event */
    if (sp.i < sp.n)
      emit_samples(&sp, &s, s.t_hi + (s.t_lo + tau), 1);
    ss_event ev;
    sim_commit(&s, &ev);
    if (ev.kind == SS_EVENT_GRAZING)
      r->n_grazing++;
    if (o->record_events && (rc = push_event(r, &cap, &ev))) {
      ss__fail(d, rc, "events", 0, "out of memory");
      goto fail;
    }
    r->n_events++;
    if (o->stop_after && r->n_events >= o->stop_after) {
      r->t = ev.t;
      r->mode = s.mode;
      memcpy(r->x, ev.x, sizeof ev.x);
      if (sp.i < sp.n)
        emit_samples(&sp, &s, ev.t, 0);
      r->n_samples = sp.i;
      return SS_OK;
    }
  }
  emit_samples(&sp, &s, o->t_end, 0);
  r->t = o->t_end;
  r->mode = s.mode;
  r->perpetual = s.perpetual;
  ss_sim_state_at(&s, o->t_end, r->x);
  return SS_OK;
partial:
  r->t = ss_sim_time(&s);
  r->mode = s.mode;
  memcpy(r->x, s.x, sizeof s.x);
  r->n_samples = sp.i;
  return rc;
fail:
  ss_sim_result_free(r);
  return rc;
}

void ss_sim_result_free(ss_sim_result *r) {
  if (!r)
    return;
  free(r->events);
  free(r->st);
  free(r->sx);
  free(r->smode);
  memset(r, 0, sizeof *r);
}
