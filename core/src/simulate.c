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
#include <stddef.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "events.h"
#include "internal.h"
#include "modal.h"
#include "simulate.h"
#include "sincos.h"

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
  /* all but the certificates, of which only the flags need clearing */
  memset(s, 0, offsetof(ss_sim, cert));
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < SS__CERT_SLOTS; j++)
      s->cert[i][j].valid = 0;
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

/* A stick that goes on after its force touched +-ur starts at that touch:
 * the side's function is at its maximum, zero but for the rounding of the
 * state at the event, which the previous anchor's tolerance (it holds the
 * |c1 t| of the time since) covered and the new one, without it, may not:
 * a value of 2.4e-15 against a tolerance of 2.3e-15 made the next search
 * refuse the stick (+ur) or never look at -ur again.  Above zero, the
 * value is taken off c0 (the later roots move by that over the slope,
 * rounding); the search then leaves the touch downward. */
static void on_surface(ss_trig *g) {
  double v[1];
  ss_trig_eval(g, 0, 0, v);
  if (v[0] > 0)
    g->c0 -= v[0];
}

/* Find the next event within local horizon H (cached). */
static int sim_find(ss_sim *s, double H) {
  ss_trig g;
  double t;
  int rc;
  if (s->have_next && (s->next_status != SS_HORIZON || H <= s->next_horizon))
    return SS_OK;
  int slots = s->full_search ? 0 : SS__CERT_SLOTS;
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
    rc = ss__trig_first_root_cert(&g, H, s->cert[s->mode], slots, &t);
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
  if (s->touch == 1)
    on_surface(&g);
  rc = ss__trig_first_root_cert(&g, H, s->cert[2], slots, &t_up);
  /* a stick force already beyond +ur: the state is not a stick */
  if (rc == SS_ABOVE)
    rc = SS_EINVAL;
  if (rc < 0) {
    s->have_next = 0;
    return rc;
  }
  ss__switching(s->m, SS_MODE_STICK, -1, s->x, &g);
  if (s->touch == -1)
    on_surface(&g);
  rc_lo = ss__trig_first_root_cert(
      &g, rc == SS_HORIZON ? H : fmax(t_up, 1e-300), s->cert[3], slots, &t_lo);
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

/* Error-free sum of two doubles (Knuth's TwoSum). */
static void two_sum(double a, double b, double *s, double *e) {
  double x = a + b;
  double bv = x - a;
  double av = x - bv;
  *s = x;
  *e = (a - av) + (b - bv);
}

/* The absolute time of local time tau, (t_hi + t_lo) + tau, renormalised
 * into *hi + *lo as the anchor is at an event. */
static void abs_time2(const ss_sim *s, double tau, double *hi, double *lo) {
  double h, err;
  two_sum(s->t_hi, tau, &h, &err);
  two_sum(h, s->t_lo + err, hi, lo);
}

/* That time as one double: the event time sim_commit() will record, so
 * that samples up to an event end exactly where the next phase's begin. */
static double abs_time(const ss_sim *s, double tau) {
  double hi, lo;
  abs_time2(s, tau, &hi, &lo);
  return hi + lo;
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
  abs_time2(s, tau, &s->t_hi, &s->t_lo);
  memcpy(s->x, xe, sizeof xe);
  s->mode = to;
  s->touch =
      from == SS_MODE_STICK && kind == SS_EVENT_GRAZING ? s->next_sign : 0;
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
  /* adaptive samples (o->sample_tolerance > 0): grown as they come */
  int adaptive;
  size_t cap;
  double inv_scale[4]; /* 1/scale of each coordinate, 0 when not measured */
  int status;          /* SS_OK, or why the sampling stopped */
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

/* ---- samples placed for a curve (sample_tolerance) ---- */

/* One more sample at absolute time t in the current phase of s. */
static int push_sample(sampler *sp, const ss_sim *s, double t) {
  ss_sim_result *r = sp->r;
  size_t max = sp->o->max_samples;
  if (sp->status)
    return sp->status;
  if (max && sp->i >= max)
    return sp->status = SS_ELIMIT_SAMPLES;
  if (sp->i == sp->cap) {
    size_t nc = sp->cap ? 2 * sp->cap : 256;
    if (max && nc > max)
      nc = max;
    double *st = realloc(r->st, nc * sizeof *st);
    if (st)
      r->st = st;
    double *sx = st ? realloc(r->sx, 4 * nc * sizeof *sx) : NULL;
    if (sx)
      r->sx = sx;
    unsigned char *sm = sx ? realloc(r->smode, nc) : NULL;
    if (!sm)
      return sp->status = SS_ENOMEM;
    r->smode = sm;
    sp->cap = nc;
  }
  ss_sim_state_at(s, t, r->sx + 4 * sp->i);
  r->st[sp->i] = t;
  r->smode[sp->i] = (unsigned char)s->mode;
  sp->i++;
  return SS_OK;
}

/* The points at which chord_bound evaluates a step, its ends included. */
#define CHORD_POINTS 5

/* The bound of ss_sim_opts.sample_tolerance on the chord over local times
 * [u, u + h] of the coordinates g (b3: their third-derivative bounds), in
 * scaled coordinates c, from c, c', c'' at the points t_j = u + j d,
 * d = h / (CHORD_POINTS - 1).  Every time of the step is within d/2 of
 * one, so max|c''| <= max_j |c''_j| + (d/2)|b3|, and likewise for c' with
 * max|c''|.  For a function f vanishing at both ends of the step, on
 * [t_j, t_j+1] f differs from the segment between f_j and f_j+1 by at most
 * d^2/8 max|f''|, and that segment's norm is at most max(|f_j|, |f_j+1|):
 * - at equal times, f = c - chord: |f| <= max_j |f_j| + d^2/8 max|c''|;
 * - across: when the projection of c(t) on the chord's direction e moves
 *   forward all along (min_j c'_j.e - (d/2) max|c''| > 0), c(t) stays over
 *   the segment and its distance to it is that of f = P(c - c(u)), P the
 *   projection across e: |f| <= max_j |f_j| + d^2/8 (max_j |P c''_j| +
 *   (d/2)|b3|).
 * The smaller of the two holds.  The first terms are the curve's own
 * distances at the points, so the bound is close to the true distance. */
static double chord_bound(const sampler *sp, const ss_trig g[4],
                          const double b3[4], double u, double h) {
  enum { K = CHORD_POINTS };
  double c[K][4], v[K][4], a[K][4], B = 0, L = 0, dt = h / (K - 1);
  for (int j = 0; j < K; j++) {
    /* the coordinates share their modes' frequencies: one sincos each */
    double t = j == K - 1 ? u + h : u + j * dt, wq[4 * SS_TRIG_MAX],
           sq[4 * SS_TRIG_MAX], cq[4 * SS_TRIG_MAX];
    int nq = 0;
    for (int i = 0; i < 4; i++) {
      double s = sp->inv_scale[i], d0 = 0, d1 = 0, d2 = 0;
      if (s != 0) {
        d0 = g[i].c0 + g[i].c1 * t;
        d1 = g[i].c1;
        for (int k = 0; k < g[i].n; k++) {
          double w = g[i].w[k];
          int q = 0;
          while (q < nq && wq[q] != w)
            q++;
          if (q == nq) {
            ss__sincos(w * t, &sq[q], &cq[q]);
            wq[nq++] = w;
          }
          double A = g[i].a[k] * cq[q] + g[i].b[k] * sq[q];
          double Bk = g[i].b[k] * cq[q] - g[i].a[k] * sq[q];
          d0 += A;
          d1 += w * Bk;
          d2 -= w * w * A;
        }
      }
      c[j][i] = s * d0;
      v[j][i] = s * d1;
      a[j][i] = s * d2;
    }
  }
  for (int i = 0; i < 4; i++) {
    double s = sp->inv_scale[i];
    B += (s * b3[i]) * (s * b3[i]);
    L += (c[K - 1][i] - c[0][i]) * (c[K - 1][i] - c[0][i]);
  }
  B = 0.5 * dt * sqrt(B);
  double amax = 0, fmax_t = 0;
  for (int j = 0; j < K; j++) {
    double n2 = 0, f2 = 0, w = (double)j / (K - 1);
    for (int i = 0; i < 4; i++) {
      double f = c[j][i] - c[0][i] - w * (c[K - 1][i] - c[0][i]);
      n2 += a[j][i] * a[j][i];
      f2 += f * f;
    }
    amax = fmax(amax, sqrt(n2));
    fmax_t = fmax(fmax_t, sqrt(f2));
  }
  amax += B;
  double best = fmax_t + 0.125 * dt * dt * amax;
  if (L > 0) {
    L = sqrt(L);
    double e[4], vmin = INFINITY, across = 0, fmax_p = 0;
    for (int i = 0; i < 4; i++)
      e[i] = (c[K - 1][i] - c[0][i]) / L;
    for (int j = 0; j < K; j++) {
      double ve = 0, ae = 0, n2 = 0, fe = 0, f2 = 0;
      for (int i = 0; i < 4; i++) {
        ve += v[j][i] * e[i];
        ae += a[j][i] * e[i];
        fe += (c[j][i] - c[0][i]) * e[i];
      }
      /* the parts across e as vectors, not as differences of squares
       * (|f|^2 - (f.e)^2 loses a small part across a long chord) */
      for (int i = 0; i < 4; i++) {
        double f = c[j][i] - c[0][i] - fe * e[i], q = a[j][i] - ae * e[i];
        f2 += f * f;
        n2 += q * q;
      }
      vmin = fmin(vmin, ve);
      across = fmax(across, sqrt(n2));
      fmax_p = fmax(fmax_p, sqrt(f2));
    }
    if (vmin - 0.5 * dt * amax > 0)
      best = fmin(best, fmax_p + 0.125 * dt * dt * (across + B));
  }
  return best;
}

/* The samples of the current phase of s over absolute times [a, b] (within
 * the phase): a, the points the tolerance needs, and b.  Each step is the
 * longest the bound allows, to about 10 %: as the distance grows as
 * h^2, one evaluation mostly predicts it; otherwise it is bracketed
 * between the longest step that held and the shortest that did not. */
static void sample_phase(sampler *sp, const ss_sim *s, double a, double b) {
  if (b < a || push_sample(sp, s, a))
    return;
  if (b == a)
    return;
  ss_trig g[4];
  double b3[4];
  ss__coords(s->m, s->mode, s->x, g);
  for (int i = 0; i < 4; i++) {
    b3[i] = 0;
    for (int k = 0; k < g[i].n; k++)
      b3[i] += hypot(g[i].a[k], g[i].b[k]) * g[i].w[k] * g[i].w[k] * g[i].w[k];
  }
  double eps = sp->o->sample_tolerance;
  double ua = local_time(s, a), ub = local_time(s, b), u = ua, h = ub - ua;
  /* below this a step is at the rounding level of the times themselves */
  double h_min = 8 * DBL_EPSILON * fmax(1.0, fmax(fabs(ub), fabs(s->t_hi)));
  while (ub - u > h_min) {
    /* lo: the longest step known to hold; hi: the shortest known not to */
    double rem = ub - u, lo = 0, hi = INFINITY;
    h = fmin(h, rem);
    for (int k = 0;; k++) {
      double E = chord_bound(sp, g, b3, u, h);
      if (isnan(E)) {
        lo = h; /* no bound (a state out of range): the step as it is */
        break;
      }
      if (E <= eps)
        lo = h;
      else
        hi = h;
      if (lo == rem || (lo > 0 && (lo >= 0.9 * hi || k >= 8)))
        break;
      if (lo == 0 && h <= h_min) {
        lo = h; /* at the rounding level of the times: taken as it is */
        break;
      }
      /* the chord's distance grows as h^2: the step that meets eps */
      double f = E > 0 ? 0.98 * sqrt(eps / E) : 4;
      double t = h * (f < 0.1 ? 0.1 : f > 4 ? 4 : f);
      if (lo > 0 && t < 1.02 * lo && hi == INFINITY)
        break; /* the longest step, as far as the bound tells */
      if (t <= lo || t >= hi)
        t = hi == INFINITY ? 2 * lo : 0.5 * (lo + hi);
      h = fmin(t, rem);
    }
    h = lo;
    u += h;
    if (ub - u <= h_min)
      break;
    if (push_sample(sp, s, s->t_hi + (s->t_lo + u)))
      return;
  }
  push_sample(sp, s, b);
}

/* The part of the current phase of s up to absolute time t_until that lies
 * in the sample window. */
static void sample_window(sampler *sp, const ss_sim *s, double t_until) {
  double a = fmax(ss_sim_time(s), sp->o->sample_from);
  double b = fmin(t_until, sp->o->sample_to);
  if (!sp->status && b >= a)
    sample_phase(sp, s, a, b);
}

/* The sampler's status as the run's: a limit or a failure, with its
 * reason in d. */
static int sampled(const sampler *sp, ss_diag *d) {
  if (sp->status == SS_ELIMIT_SAMPLES)
    return ss__fail(d, SS_ELIMIT_SAMPLES, "max_samples",
                    (double)sp->o->max_samples,
                    "the tolerance %g needs more than %zu samples",
                    sp->o->sample_tolerance, sp->o->max_samples);
  if (sp->status)
    return ss__fail(d, sp->status, "samples", 0, "out of memory");
  return SS_OK;
}

/* The samples of the run up to t_until (strict: before it), at the given
 * times, then adaptive ones; SS_OK, or why the sampling stopped. */
static int sample_until(sampler *sp, const ss_sim *s, double t_until,
                        int strict, ss_diag *d) {
  emit_samples(sp, s, t_until, strict);
  if (!sp->adaptive)
    return SS_OK;
  sample_window(sp, s, t_until);
  return sampled(sp, d);
}

/* The sampler of a run of ns samples at given times (their room in r), or
 * of adaptive ones, measured in the coordinates asked for. */
static int sampler_start(sampler *sp, const ss_sim_opts *o, size_t ns,
                         ss_sim_result *r, ss_diag *d) {
  if (ns) {
    r->st = malloc(ns * sizeof *r->st);
    r->sx = malloc(4 * ns * sizeof *r->sx);
    r->smode = malloc(ns);
    if (!r->st || !r->sx || !r->smode)
      return ss__fail(d, SS_ENOMEM, "samples", (double)ns, "out of memory");
  }
  r->n_samples = ns;
  memset(sp, 0, sizeof *sp);
  sp->o = o;
  sp->n = ns;
  sp->r = r;
  sp->adaptive = o->sample_tolerance > 0;
  for (int i = 0; i < 4; i++)
    if (!o->sample_axes || (o->sample_axes & (1u << i)))
      sp->inv_scale[i] = o->sample_scale[i] > 0 ? 1 / o->sample_scale[i] : 1;
  return SS_OK;
}

static int check_opts(const ss_sim_opts *o, size_t *n_samples, ss_diag *d) {
  if (!isfinite(o->t0))
    return ss__fail(d, SS_EINVAL, "t0", o->t0, "t0 must be finite");
  if (!isfinite(o->t_end) || !(o->t_end >= o->t0))
    return ss__fail(d, SS_EINVAL, "t_end", o->t_end,
                    "t_end must be finite and not before the start time");
  if ((o->sample_times != NULL) + (o->n_samples > 0) +
          (o->sample_tolerance != 0) >
      1)
    return ss__fail(d, SS_EINVAL, "samples", 0,
                    "give one of sample times, an even sample count or a "
                    "tolerance");
  if (o->sample_tolerance != 0) {
    if (!(o->sample_tolerance > 0) || !isfinite(o->sample_tolerance))
      return ss__fail(d, SS_EINVAL, "tolerance", o->sample_tolerance,
                      "the sample tolerance must be a positive number");
    for (int i = 0; i < 4; i++)
      if (!(o->sample_scale[i] >= 0) || !isfinite(o->sample_scale[i]))
        return ss__fail(d, SS_EINVAL, "scale", o->sample_scale[i],
                        "a sample scale must be a positive number (0: 1)");
    if (o->sample_axes > 15)
      return ss__fail(d, SS_EINVAL, "axes", o->sample_axes,
                      "sample axes are bits 1, 2, 4, 8 (x1, x2, x1', x2')");
  }
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
  } else if (o->n_samples || o->sample_tolerance != 0) {
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
  if ((rc = o->start_in_mode
                ? ss__sim_init_mode(&s, m, o->t0, x0, o->start_mode, d)
                : ss__sim_init(&s, m, o->t0, x0, d)))
    return rc;
  s.full_search = o->full_search != 0;
  if ((rc = sampler_start(&sp, o, ns, r, d)))
    goto fail;
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
    /* samples of this phase, strictly before the event (or, placed for a
     * curve, up to it) */
    if ((rc = sample_until(&sp, &s, abs_time(&s, tau), 1, d)))
      goto stopped;
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
      if ((rc = sample_until(&sp, &s, ev.t, 0, d)))
        goto stopped;
      r->n_samples = sp.i;
      return SS_OK;
    }
  }
  if ((rc = sample_until(&sp, &s, o->t_end, 0, d)))
    goto stopped;
  if (sp.adaptive)
    r->n_samples = sp.i;
  r->t = o->t_end;
  r->mode = s.mode;
  r->perpetual = s.perpetual;
  ss_sim_state_at(&s, o->t_end, r->x);
  return SS_OK;
stopped:
  if (rc == SS_ENOMEM)
    goto fail;
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
