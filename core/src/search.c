/*
 * search.c: finding periodic orbits with no guess.
 *
 * Three sources of candidates, each refined by the duration equations of
 * orbit.c and accepted only if ss_orbit_check() proves them feasible:
 *  1. simulation: iterate the Poincare map from points of Sigma0 until it
 *     repeats with some period k; this finds the stable orbits, of any phase
 *     sequence;
 *  2. a grid of durations for the overshoot (3 unknowns) and stick-slip (2)
 *     equations; Newton does not care about stability, so this finds the
 *     unstable orbits that simulation never reaches;
 *  3. Newton on the fixed points of P^k from points of Sigma0, for unstable
 *     orbits of other sequences and periods.
 */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "certify.h"
#include "internal.h"
#include "orbit.h"
#include "scan.h"
#include "search.h"
#include "stability.h"

#define SS_TWO_PI 6.283185307179586476925287
#define MAP_EVENTS 64    /* events allowed for one return to Sigma0 */
#define SETTLE_TURNS 400 /* returns simulated at most from each start */
#define SETTLE_CHECK 10  /* returns between two checks for a period */
#define CLOSE_RETURN_K 4 /* longest period tried from a close return */
#define KNOWN_MAX 64     /* returns of stable orbits a simulation looks for */
#define MAP_NEWTON_ITERS 30
#define SS_SCAN_PERIODS 1.5 /* the box of the scan, in slow modal periods */
/* the most it grows to, in slow modal periods (see grow_box) */
#define SS_SCAN_MAX_PERIODS 3.0
/* a grown box's room beyond an orbit's longest phase */
#define BOX_MARGIN 1.1
/* the step of the bound on the starts of long slips, in radians of the fast
 * mode, and the room of its polygon's vertices */
#define LONG_SLIP_STEP 0.1
#define LONG_SLIP_VERTICES 512
/* At most this many clipping times: where the fast mode is many times the
 * slow one (or the parameters are extreme, a box of 1e135 time units), the
 * times are spread wider; fewer cuts leave a larger polygon, which still
 * holds every start of a long slip. */
#define LONG_SLIP_MAX_STEPS 4096
#define SCAN_MAX_ROOTS 256
#define MAX_SEEDS 42 /* the finest grid of seeds, 7 x 6 */

typedef struct collect {
  const ss_model *m;
  ss_orbit *out;
  int max, n;
  double scale;
  ss_orbit_report *rep;
  double t_start, budget;
  int (*cancelled)(void *);
  void *cancel_cls;
  int stopped; /* SS_ELIMIT_TIME or SS_ECANCELED once the search must stop */
  double box;  /* the box of the scan and of the proof (family_box, grown) */
  /* the returns to Sigma0 (x1, x1') of the stable orbits found, for
   * simulations to stop when they reach one; made for the first n_seen of
   * out */
  double known[KNOWN_MAX][2];
  int n_known, n_seen;
} collect;

/* Whether the search must stop: its time budget is spent, or its caller
 * cancelled it.  The first reason sticks. */
static int over_budget(collect *c) {
  if (!c->stopped && c->budget > 0 && ss__now() - c->t_start > c->budget)
    c->stopped = SS_ELIMIT_TIME;
  if (!c->stopped && c->cancelled && c->cancelled(c->cancel_cls))
    c->stopped = SS_ECANCELED;
  return c->stopped != 0;
}

static int scan_stop(void *cls) { return over_budget(cls); }

/* Does orbit b pass through a's start with a's sequence rotated?  Compares
 * a.z0 with b's state at each of its stick -> slip points. */
int ss__same_orbit(const ss_model *m, const ss_orbit *a, const ss_orbit *b,
                   double tol) {
  if (a->n_phases != b->n_phases ||
      fabs(a->period - b->period) > 1e-6 * (1 + a->period))
    return 0;
  int n = b->n_phases;
  double x[4];
  memcpy(x, b->x0, sizeof x);
  for (int r = 0; r < n; r++) {
    if (b->modes[r] == SS_MODE_SLIP &&
        (r == 0 || b->modes[r - 1] == SS_MODE_STICK)) {
      int seq_ok = 1;
      for (int k = 0; k < n && seq_ok; k++)
        seq_ok = a->modes[k] == b->modes[(k + r) % n] &&
                 fabs(a->durations[k] - b->durations[(k + r) % n]) <
                     1e-6 * (1 + a->period);
      double z[4];
      ss_x_to_z(m, x, z);
      if (seq_ok && fabs(z[0] - a->z0[0]) < tol && fabs(z[2] - a->z0[2]) < tol)
        return 1;
    }
    ss_flow(m, b->modes[r], b->durations[r], x, x);
    x[3] = m->p.V;
  }
  return 0;
}

/* A shorter orbit travelled k times is that orbit: solved again from its
 * first n/k durations, it replaces *o (1), if it repeats to *o within
 * 1e-8 of the period; else *o is an orbit of its own period (0), or the
 * shorter one does not solve (-1). */
static int to_minimal(const ss_model *m, ss_orbit *o, const ss_stab_opts *so) {
  int b = ss__is_repetition(o->n_phases, o->modes, o->durations,
                            1e-6 * (1 + o->period));
  if (!b)
    return 0;
  ss_orbit r;
  ss_diag d;
  ss_diag_clear(&d);
  if (ss_orbit_solve(m, b, o->modes, o->durations, so, &r, &d) != SS_OK)
    return -1;
  for (int k = 0; k < o->n_phases; k++)
    if (!(fabs(r.durations[k % b] - o->durations[k]) <= 1e-8 * (1 + o->period)))
      return 0;
  r.source = o->source;
  *o = r;
  return 1;
}

static void add_orbit(collect *c, const ss_orbit *found) {
  /* a shorter orbit travelled twice is that orbit */
  ss_orbit q = *found;
  const ss_orbit *o = &q;
  if (to_minimal(c->m, &q, NULL) < 0) {
    c->rep->duplicates++;
    return;
  }
  for (int i = 0; i < c->n; i++)
    if (ss__same_orbit(c->m, o, &c->out[i], 1e-6 * c->scale)) {
      c->rep->duplicates++;
      return;
    }
  if (c->n < c->max)
    c->out[c->n++] = *o;
  else
    c->rep->truncated++;
}

/* A phase of (next to) no length. */
static int degenerate(const ss_orbit *o) {
  for (int k = 0; k < o->n_phases; k++)
    if (!(o->durations[k] > 1e-9 * o->period))
      return 1;
  return 0;
}

/* Keep a rejected root if it is the closest to feasible so far; a root
 * with a phase of (next to) no length, a trivial solution of the duration
 * equations, only when there is no other. */
static void keep_rejected(ss_orbit_report *rep, const ss_orbit *o,
                          const ss_diag *d) {
  if (rep->has_rejected) {
    int dn = degenerate(o), dk = degenerate(&rep->rejected);
    if (dn > dk ||
        (dn == dk && !(o->violation.value > rep->rejected.violation.value)))
      return;
  }
  rep->has_rejected = 1;
  rep->rejected = *o;
  snprintf(rep->reason, sizeof rep->reason, "%s orbit rejected: %s",
           ss_orbit_kind_name(o->kind), d->text);
}

/* The two period-1 families the scan and the proof cover: slip-stick
 * (f = 0) and slip-overshoot-stick (f = 1), 2 + f phases. */
static const ss_mode FAMILY_SEQ[2][3] = {
    {SS_MODE_SLIP, SS_MODE_STICK, SS_MODE_STICK},
    {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK}};
static const unsigned FAMILY_KIND[2] = {SS_ORBIT_STICKSLIP, SS_ORBIT_OVERSHOOT};

/* Their box: each duration up to 1.5 slow modal periods. */
static double family_box(const ss_model *m) {
  return SS_SCAN_PERIODS * SS_TWO_PI / m->w[0];
}

/* Whether family f's period-1 orbit of durations tau is among those found
 * (durations within 1e-7 of the period). */
static int known_period1(const collect *c, int f, const double *tau) {
  int n = 2 + f;
  for (int i = 0; i < c->n; i++) {
    const ss_orbit *q = &c->out[i];
    int same = q->n_phases == n && q->n_turns == 1;
    for (int k = 0; k < n && same; k++)
      same = q->modes[k] == FAMILY_SEQ[f][k] &&
             fabs(q->durations[k] - tau[k]) < 1e-7 * (1 + q->period);
    if (same)
      return 1;
  }
  return 0;
}

/* Refine a candidate sequence and durations; keep it if feasible. */
static void try_solve(collect *c, int n, const ss_mode *modes,
                      const double *tau, ss_orbit_source source) {
  ss_orbit o;
  ss_diag d;
  ss_diag_clear(&d);
  c->rep->newton_starts++;
  /* the finite-difference check is made once, on the orbits returned */
  int rc = ss_orbit_solve(c->m, n, modes, tau, NULL, &o, &d);
  if (rc == SS_OK) {
    c->rep->roots++;
    o.source = source;
    add_orbit(c, &o);
  } else if (rc == SS_INFEASIBLE) {
    c->rep->roots++;
    c->rep->infeasible++;
    keep_rejected(c->rep, &o, &d);
  }
}

/* The certificate of a period-1 family (f = 0 slip-stick, 1
 * slip-overshoot-stick): every root of its duration equations in the box
 * proved (certify.c), each judged an orbit or not by ss_orbit_check(), an
 * orbit missing from the search's solved and added, and every orbit of the
 * family the search returned inside the box found among the roots. */
#define CERT_STATE_BOX 100.0 /* the start box, in units of max(V, ur/chi) */
/* the least duration of a slip and of an overshoot, in fast periods: at
 * zero slip (and stick) every start closes, and an overshoot of zero
 * length is the grazing where the overshoot appears, where the two
 * conditions x2' = V coincide */
#define CERT_SLIP_MIN 1e-2

typedef struct cert_cls {
  collect *c;
  double t_end;
} cert_cls;

static int cert_stop(void *cls) {
  cert_cls *cc = cls;
  return over_budget(cc->c) || ss__now() > cc->t_end;
}

static int in_root(const ss__cert_root *r, const double *u) {
  for (int i = 0; i < 4; i++) {
    double e = 1e-9 * (1 + fabs(u[i]));
    if (!(u[i] >= r->box.lo[i] - e && u[i] <= r->box.hi[i] + e))
      return 0;
  }
  return 1;
}

/* The box of family f's proof, recorded in fc: the durations from tlo (the
 * stick from below) to dmax, the start within CERT_STATE_BOX units of d0;
 * lo and hi in the proof's unknowns (t1, t2, x1, x1'). */
static void cert_box(const ss_model *m, int f, double dmax, double tlo,
                     double below, ss_family_cert *fc, double lo[4],
                     double hi[4]) {
  const ss_params *p = &m->p;
  int n = 2 + f;
  double L = CERT_STATE_BOX * fmax(p->V, p->ur / p->chi);
  memset(fc, 0, sizeof *fc);
  fc->ran = 1;
  fc->n_phases = n;
  fc->duration_lo[0] = tlo;
  if (n == 3)
    fc->duration_lo[1] = tlo;
  for (int k = 0; k < n; k++)
    fc->duration_hi[k] = dmax;
  fc->x1_lo = m->d0[0] - L;
  fc->x1_hi = m->d0[0] + L;
  fc->v1_lo = -L;
  fc->v1_hi = L;
  lo[0] = tlo;
  lo[1] = n == 3 ? tlo : below;
  lo[2] = fc->x1_lo;
  lo[3] = fc->v1_lo;
  hi[0] = dmax;
  hi[1] = dmax;
  hi[2] = fc->x1_hi;
  hi[3] = fc->v1_hi;
}

/* Root q of family f's proof: an orbit (counted; solved and added if the
 * search missed it) or not one.  Clears *complete, and says why, when it
 * could not be judged or added. */
static void cert_judge_root(collect *c, int f, const ss__cert_root *q,
                            ss_family_cert *fc, int *complete) {
  const ss_model *m = c->m;
  const ss_params *p = &m->p;
  const ss_mode *seq = FAMILY_SEQ[f];
  int n = 2 + f;
  double u[4], tau[3], st;
  ss__cert_polish(m, n, q, u);
  ss__cert_point(m, n, u, NULL, &st);
  tau[0] = u[0];
  tau[1] = u[1];
  tau[2] = st;
  int positive = 1;
  for (int k = 0; k < n; k++)
    positive = positive && tau[k] > 0;
  if (!positive) {
    fc->rejected++;
    return;
  }
  ss_orbit o;
  memset(&o, 0, sizeof o);
  o.kind = f ? SS_ORBIT_OVERSHOOT : SS_ORBIT_STICKSLIP;
  o.n_phases = n;
  memcpy(o.modes, seq, sizeof o.modes[0] * (size_t)n);
  memcpy(o.durations, tau, sizeof tau[0] * (size_t)n);
  double x0[4] = {u[2], u[2] + p->ur / p->chi, u[3], p->V};
  ss_x_to_z(m, x0, o.z0);
  ss_diag dd;
  ss_diag_clear(&dd);
  int ck = ss_orbit_check(m, &o, &dd);
  if (ck == SS_INFEASIBLE) {
    fc->rejected++;
    return;
  }
  if (ck != SS_OK) {
    *complete = 0;
    snprintf(fc->why, sizeof fc->why,
             "the root at durations %.9g, %.9g could not be checked: %.96s",
             tau[0], tau[1], dd.text);
    return;
  }
  fc->orbits++;
  if (known_period1(c, f, tau))
    return;
  int before = c->n, trunc = c->rep->truncated;
  try_solve(c, n, seq, tau, SS_SOURCE_CERTIFICATE);
  if (c->n > before) {
    fc->added++;
  } else if (c->rep->truncated > trunc) {
    *complete = 0;
    snprintf(fc->why, sizeof fc->why, "more orbits than room in the answer");
  } else {
    *complete = 0;
    snprintf(fc->why, sizeof fc->why,
             "the orbit proved at durations %.9g, %.9g did not solve "
             "again",
             tau[0], tau[1]);
  }
}

/* Every orbit of family f the search returned inside the box of fc (least
 * slip and overshoot tlo, longest phase dmax) is among the proof's roots;
 * clears *complete, and says why, if one is not. */
static void cert_returned_in_roots(const collect *c, int f,
                                   const ss__certificate *ce, double tlo,
                                   double dmax, ss_family_cert *fc,
                                   int *complete) {
  int n = 2 + f;
  for (int i = 0; i < c->n; i++) {
    const ss_orbit *b = &c->out[i];
    if (b->n_phases != n || b->n_turns != 1 || b->modes[1] != FAMILY_SEQ[f][1])
      continue;
    double u[4] = {b->durations[0], b->durations[1], b->x0[0], b->x0[2]};
    int inside = u[0] >= tlo && u[0] <= dmax && u[1] <= dmax &&
                 (n == 2 || u[1] >= tlo) && b->durations[n - 1] <= dmax &&
                 u[2] >= fc->x1_lo && u[2] <= fc->x1_hi && u[3] >= fc->v1_lo &&
                 u[3] <= fc->v1_hi;
    int found = 0;
    for (int r = 0; r < ce->n_roots && !found; r++)
      found = in_root(&ce->roots[r], u);
    if (inside && !found) {
      *complete = 0;
      snprintf(fc->why, sizeof fc->why,
               "the orbit at durations %.9g, %.9g is not among the proved "
               "roots",
               u[0], u[1]);
    }
  }
}

static void certify_family(collect *c, int f, double dmax, double seconds,
                           ss_family_cert *fc) {
  const ss_model *m = c->m;
  int n = 2 + f;
  double tlo = CERT_SLIP_MIN * SS_TWO_PI / m->w[1];
  /* the stick reaches a little below zero, so that a root with a stick of
   * length zero lies inside and is proved (and rejected), not left on the
   * face; so does the slip-stick's */
  double below = -1e-3 * dmax;
  double lo[4], hi[4];
  cert_box(m, f, dmax, tlo, below, fc, lo, hi);
  double t0 = ss__now();
  cert_cls cc = {c, t0 + seconds};
  ss__certificate ce;
  int rc = ss__certify_period1(m, n, lo, hi, below, dmax, LONG_MAX, cert_stop,
                               &cc, &ce);
  fc->boxes = ce.boxes;
  fc->roots = ce.n_roots;
  if (rc == SS_ENOMEM || rc == SS_EINVAL) {
    snprintf(fc->why, sizeof fc->why, "the proof could not run (%s)",
             ss_strerror(rc));
    ss__certificate_free(&ce);
    fc->seconds = ss__now() - t0;
    return;
  }
  int complete = ce.complete;
  if (rc == SS_ECANCELED)
    snprintf(fc->why, sizeof fc->why,
             "the proof ran out of its %g s budget after %ld boxes", seconds,
             ce.boxes);
  else if (ce.n_undecided)
    snprintf(fc->why, sizeof fc->why,
             "%d boxes not decided, the first at durations [%.9g, %.9g] x "
             "[%.9g, %.9g] (a double root, or one on the box's face)",
             ce.n_undecided, ce.undecided.lo[0], ce.undecided.hi[0],
             ce.undecided.lo[1], ce.undecided.hi[1]);
  for (int r = 0; r < ce.n_roots; r++)
    cert_judge_root(c, f, &ce.roots[r], fc, &complete);
  if (ce.complete)
    cert_returned_in_roots(c, f, &ce, tlo, dmax, fc, &complete);
  fc->complete = complete;
  ss__certificate_free(&ce);
  fc->seconds = ss__now() - t0;
}

/* Newton on P^k(s) = s with the analytic Jacobian of the travelled
 * sequence.  On success, fills the sequence and returns 0. */
int ss__map_newton(const ss_model *m, double s[2], int k, ss_mode *modes,
                   double *dur, int *np) {
  const ss_params *p = &m->p;
  double scale = fmax(p->V, (p->ur - p->us) / p->chi);
  for (int it = 0; it < MAP_NEWTON_ITERS; it++) {
    double out[2], z0[4];
    ss_stab st;
    if (ss_poincare(m, s, k, (size_t)(MAP_EVENTS * k), out, modes, dur, np))
      return -1;
    double g0 = out[0] - s[0], g1 = out[1] - s[1];
    if (fabs(g0) + fabs(g1) < 1e-12 * scale)
      return 0;
    z0[0] = s[0];
    z0[1] = s[0] + (p->ur - p->us) / p->chi;
    z0[2] = s[1];
    z0[3] = p->V;
    ss_stab_opts so = {k, 0};
    if (ss_stability(m, *np, modes, dur, z0, &so, &st))
      return -1;
    double a = st.jac[0][0] - 1, b = st.jac[0][1], cc = st.jac[1][0],
           d = st.jac[1][1] - 1, det = a * d - b * cc;
    if (!(fabs(det) > 1e-14))
      return -1;
    double d0 = (-g0 * d + g1 * b) / det, d1 = (-a * g1 + cc * g0) / det;
    /* damp steps that leave the neighbourhood */
    double lim = 0.5 * scale, len = fabs(d0) + fabs(d1);
    if (len > lim) {
      d0 *= lim / len;
      d1 *= lim / len;
    }
    s[0] += d0;
    s[1] += d1;
  }
  return -1;
}

/* Has x (on Sigma0) reached a stable orbit already found?  Brings the list
 * of their returns up to date first. */
static int reached_known(collect *c, const double x[2]) {
  for (; c->n_seen < c->n; c->n_seen++) {
    const ss_orbit *o = &c->out[c->n_seen];
    if (!(o->stab.spectral_radius < 1))
      continue;
    double y[4];
    memcpy(y, o->x0, sizeof y);
    for (int r = 0; r < o->n_phases; r++) {
      if (o->modes[r] == SS_MODE_SLIP &&
          (r == 0 || o->modes[r - 1] == SS_MODE_STICK) &&
          c->n_known < KNOWN_MAX) {
        /* Sigma0's coordinates are z = x - (d0, 0) */
        c->known[c->n_known][0] = y[0] - c->m->d0[0];
        c->known[c->n_known][1] = y[2];
        c->n_known++;
      }
      ss_flow(c->m, o->modes[r], o->durations[r], y, y);
      y[3] = c->m->p.V;
    }
  }
  for (int i = 0; i < c->n_known; i++)
    if (fabs(x[0] - c->known[i][0]) + fabs(x[1] - c->known[i][1]) <
        1e-7 * c->scale)
      return 1;
  return 0;
}

/* Source 1: iterate P from a seed; if it settles with period k, refine.
 * Every SETTLE_CHECK returns the last ones are compared: repeating to
 * 1e-9 of the scale, it has settled; after SETTLE_TURNS a repetition to
 * 1e-3 (a slowly attracting orbit) is refined all the same. */
static void from_simulation(collect *c, const double seed[2], int max_k) {
  double pts[SETTLE_TURNS + 1][2];
  int np = 0, k_found = 0;
  pts[0][0] = seed[0];
  pts[0][1] = seed[1];
  c->rep->simulations++;
  /* one simulation through all the returns: each event is found from the
   * last one's certificate, none from scratch after a restart */
  ss__returns r;
  if (ss__returns_start(&r, c->m, seed))
    return;
  for (int i = 0; i < SETTLE_TURNS && !k_found; i++) {
    size_t events = MAP_EVENTS;
    if (ss__returns_next(&r, &events, pts[i + 1], NULL, NULL))
      break;
    np = i + 1;
    /* within 1e-7 of a stable orbit found: it settles there, nothing new */
    if (reached_known(c, pts[np])) {
      c->rep->simulations_known++;
      return;
    }
    if (np % SETTLE_CHECK || np < 2 * max_k + 1)
      continue;
    for (int k = 1; k <= max_k && !k_found; k++)
      if (fabs(pts[np][0] - pts[np - k][0]) +
              fabs(pts[np][1] - pts[np - k][1]) <
          1e-9 * c->scale)
        k_found = k;
    if (over_budget(c))
      break;
  }
  if (np < 2 * max_k + 1)
    return;
  for (int k = 1; k <= max_k && !k_found; k++)
    if (fabs(pts[np][0] - pts[np - k][0]) + fabs(pts[np][1] - pts[np - k][1]) <
        1e-3 * c->scale)
      k_found = k;
  double s[2], dur[SS_MAX_PHASES];
  ss_mode modes[SS_MAX_PHASES];
  int n;
  if (k_found) {
    s[0] = pts[np][0];
    s[1] = pts[np][1];
    c->rep->newton_starts++;
    if (ss__map_newton(c->m, s, k_found, modes, dur, &n) == 0)
      try_solve(c, n, modes, dur, SS_SOURCE_SIMULATION);
    return;
  }
  /* Not settled: a long transient, or motion with no attracting orbit.
   * Where it came closest to repeating after k returns, a periodic orbit
   * of k turns is near (the close-return idea for unstable periodic orbits
   * in chaotic motion, and for attractors that a transient reaches late):
   * Newton on P^k from there, for each k up to CLOSE_RETURN_K. */
  for (int k = 1; k <= max_k && k <= CLOSE_RETURN_K && !over_budget(c); k++) {
    int best_j = 0;
    double best = 0.05 * c->scale;
    for (int j = np / 4 + k; j <= np; j++) {
      double e =
          fabs(pts[j][0] - pts[j - k][0]) + fabs(pts[j][1] - pts[j - k][1]);
      if (e < best) {
        best = e;
        best_j = j;
      }
    }
    if (!best_j)
      continue;
    s[0] = pts[best_j][0];
    s[1] = pts[best_j][1];
    c->rep->newton_starts++;
    if (ss__map_newton(c->m, s, k, modes, dur, &n) == 0)
      try_solve(c, n, modes, dur, SS_SOURCE_SIMULATION);
  }
}

/* The box that the dynamics ask for: a periodic motion's phases can last
 * longer than family_box (a slip of a two-mode motion whose velocity only
 * just reaches V lasts arbitrarily long), and where they do, the box grows
 * to cover them.
 *
 * Where to look: a slip from s = (z1, z1') on Sigma0 is affine in s, so its
 * velocity less V is g(t; s) = a1(t) z1 + a2(t) z1' + b(t), and the starts
 * whose slip outlasts T are those with g(t; s) <= 0 for every t in (0, T]:
 * an intersection of half-planes, a convex set.  Clipping the proof's
 * start box (CERT_STATE_BOX) by the half-planes at t = h, 2h, ..., T (h a
 * tenth of a radian of the fast mode) leaves a convex polygon that holds
 * that set (the constraints between the samples are dropped, so it can only
 * be larger); when it is empty, no slip from a start in the box outlasts T.
 * When it is not, the motion from its centre (the mean of its vertices) is
 * simulated like any seed, before the others (so that no orbit found before
 * stops it): an orbit refined from it is returned, and if one has a phase
 * longer than the box, the box grows to BOX_MARGIN times the longest, at
 * most SS_SCAN_MAX_PERIODS slow modal periods.  The phases of a motion that
 * does not settle are not enough: from such starts it wanders among slips
 * near perpetual (up to 20 boxes long over the search battery), and a box
 * grown to them costs four times the scan for no orbit.  The rule depends
 * on the parameters and max_period alone, not on the effort, so every
 * effort scans and proves the same box. */

/* The slip's g(t; s) = a[0] z1 + a[1] z1' + a[2] on Sigma0 (z2 - z1 =
 * (ur - us) / chi, z2' = V): z = phi q, each q_j a sinusoid of w_j. */
static void slip_velocity_row(const ss_model *m, double t, double a[3]) {
  const ss_params *p = &m->p;
  double D = (p->ur - p->us) / p->chi;
  a[0] = a[1] = 0;
  a[2] = -p->V;
  for (int j = 0; j < 2; j++) {
    double sn = sin(m->w[j] * t), cs = cos(m->w[j] * t), f = m->phi[1][j];
    double pi0 = m->phiinv[j][0], pi1 = m->phiinv[j][1];
    /* q_j(0) = pi0 z1 + pi1 (z1 + D), q_j'(0) = pi0 z1' + pi1 V */
    a[0] += -f * m->w[j] * sn * (pi0 + pi1);
    a[1] += f * cs * pi0;
    a[2] += -f * m->w[j] * sn * pi1 * D + f * cs * pi1 * p->V;
  }
}

/* Clip the convex polygon v (n vertices, room for LONG_SLIP_VERTICES) to
 * a[0] x + a[1] y + a[2] <= 0; the vertices left.  A convex polygon gains
 * at most one vertex; should rounding make it gain more than the room, v is
 * left as it was, which still holds the clipped set. */
static int clip_polygon(double v[][2], int n, const double a[3]) {
  double w[LONG_SLIP_VERTICES][2];
  int k = 0;
  for (int i = 0; i < n; i++) {
    if (k + 2 > LONG_SLIP_VERTICES)
      return n;
    const double *p = v[i], *q = v[(i + 1) % n];
    double fp = a[0] * p[0] + a[1] * p[1] + a[2];
    double fq = a[0] * q[0] + a[1] * q[1] + a[2];
    if (fp <= 0) {
      w[k][0] = p[0];
      w[k++][1] = p[1];
    }
    if ((fp < 0 && fq > 0) || (fp > 0 && fq < 0)) {
      double r = fp / (fp - fq);
      w[k][0] = p[0] + r * (q[0] - p[0]);
      w[k++][1] = p[1] + r * (q[1] - p[1]);
    }
  }
  memcpy(v, w, sizeof w[0] * (size_t)k);
  return k;
}

/* Whether a slip from a start in the proof's box may outlast T; if so, the
 * centre of the polygon that holds those starts, in s. */
static int long_slip_start(const ss_model *m, double T, double s[2]) {
  const ss_params *p = &m->p;
  double L = CERT_STATE_BOX * fmax(p->V, p->ur / p->chi);
  double v[LONG_SLIP_VERTICES][2] = {{-L, -L}, {L, -L}, {L, L}, {-L, L}};
  double h = fmax(LONG_SLIP_STEP / m->w[1], T / LONG_SLIP_MAX_STEPS);
  int n = 4;
  for (int i = 1; i * h <= T && n > 0; i++) {
    double a[3];
    slip_velocity_row(m, i * h, a);
    n = clip_polygon(v, n, a);
  }
  if (n == 0)
    return 0;
  s[0] = s[1] = 0;
  for (int i = 0; i < n; i++) {
    s[0] += v[i][0] / n;
    s[1] += v[i][1] / n;
  }
  return 1;
}

/* The box of the scan and the proof, into c->box: family_box, grown where
 * the motion from the starts of long slips travels longer phases. */
static void grow_box(collect *c, int max_k) {
  const ss_model *m = c->m;
  double s[2], longest = 0;
  c->box = family_box(m);
  c->rep->scan_box_cap = SS_SCAN_MAX_PERIODS * SS_TWO_PI / m->w[0];
  if (!long_slip_start(m, c->box, s))
    return;
  int before = c->n;
  from_simulation(c, s, max_k);
  for (int i = before; i < c->n; i++)
    for (int k = 0; k < c->out[i].n_phases; k++)
      longest = fmax(longest, c->out[i].durations[k]);
  if (longest > c->box)
    c->box = fmin(c->rep->scan_box_cap, BOX_MARGIN * longest);
}

/* The sequence of a guess of n phases: its own modes, or, when they do not
 * start with slip and end with stick, the default sequence of that length
 * (slip-stick, slip-overshoot-stick). */
static int guess_sequence(const ss_orbit_opts *opts, ss_mode *modes,
                          ss_diag *d) {
  int n = opts->n_guess;
  if (n > SS_MAX_PHASES)
    return ss__fail(d, SS_EINVAL, "guess", n, "too many phases");
  memcpy(modes, opts->guess_modes, sizeof opts->guess_modes);
  if (modes[0] != SS_MODE_SLIP || modes[n - 1] != SS_MODE_STICK) {
    if (n != 2 && n != 3)
      return ss__fail(d, SS_EINVAL, "guess", n,
                      "give the modes of a guess with more than 3 phases");
    memcpy(modes, FAMILY_SEQ[n - 2], sizeof modes[0] * (size_t)n);
  }
  return SS_OK;
}

/* The search from the caller's guess alone: its root, if it solves and is
 * feasible (a guess that goes round a shorter orbit k times finds that
 * orbit), or the reason it is not one.  A guess that does not converge, or
 * is infeasible or singular, is an answer with no orbit, not a failure. */
static int from_guess(collect *c, const ss_orbit_opts *opts, ss_diag *d) {
  ss_orbit_report *rep = c->rep;
  ss_mode modes[SS_MAX_PHASES];
  int rc = guess_sequence(opts, modes, d);
  if (rc)
    return rc;
  ss_diag dd;
  ss_orbit o;
  ss_diag_clear(&dd);
  rep->newton_starts = 1;
  ss_stab_opts so = {0, opts->difference_check};
  rc = ss_orbit_solve(c->m, opts->n_guess, modes, opts->guess, &so, &o, &dd);
  if (rc == SS_OK) {
    rep->roots = 1;
    o.source = SS_SOURCE_GUESS;
    if (to_minimal(c->m, &o, &so) < 0)
      rep->duplicates = 1;
    else if (c->n < c->max)
      c->out[c->n++] = o;
    else
      rep->truncated = 1;
    return SS_OK;
  }
  snprintf(rep->reason, sizeof rep->reason, "%s", dd.text);
  if (rc == SS_INFEASIBLE) {
    rep->roots = 1;
    rep->infeasible = 1;
    rep->has_rejected = 1;
    rep->rejected = o;
  }
  if (rc != SS_INFEASIBLE && rc != SS_ENOCONV && rc != SS_ESINGULAR)
    return ss__fail(d, rc, dd.where, dd.value, "%s", dd.text);
  return SS_OK;
}

/* The seeds on Sigma0, a grid in (z1, z1') on the scales of the stick's
 * reach and of V, finer with the effort.  The first of them, the number
 * returned (a smaller grid), start simulations; Newton on P^k starts from
 * all *ns.  The period-1 orbits of the two families come from the scan,
 * stable or not; simulations are for the attractors of other sequences and
 * periods. */
static int make_seeds(const collect *c, int effort, double seeds[MAX_SEEDS][2],
                      int *ns) {
  const ss_params *p = &c->m->p;
  double L = (p->ur - p->us) / p->chi, V = p->V;
  const double z1f[] = {0, 0.5, -0.5, 1.0, -1.0, 1.5, -1.5};
  const double vf[] = {-0.8, 0.8, 0.0, -1.6, 1.6, -2.4};
  int nz = effort == 1 ? 3 : 7, nv = effort == 1 ? 2 : 6;
  int nz_sim = effort == 1 || effort == 2 ? 3 : 7;
  int nv_sim = effort == 1 ? 2 : effort == 2 ? 4 : 6;
  *ns = 0;
  for (int pass = 0; pass < 2; pass++)
    for (int i = 0; i < nz; i++)
      for (int j = 0; j < nv; j++) {
        int in_sim = i < nz_sim && j < nv_sim;
        if (in_sim != (pass == 0))
          continue;
        seeds[*ns][0] = z1f[i] * L;
        seeds[*ns][1] = vf[j] * V;
        (*ns)++;
      }
  return nz_sim * nv_sim;
}

/* Source 1 from each of the first ns_sim seeds. */
static void from_simulations(collect *c, double seeds[][2], int ns_sim,
                             int max_k) {
  for (int i = 0; i < ns_sim && !over_budget(c); i++)
    from_simulation(c, seeds[i], max_k);
}

/* Source 2 for family f: every root of its period-1 duration equations in
 * the box dmax, from the scan (scan.c) at step h splitting refine times,
 * solved unless found already; when none of the family is feasible, its
 * closest rejected roots solved too, to say why in numbers (the report
 * keeps the closest to feasible). */
static int scan_family(collect *c, int f, double dmax, double h, int refine,
                       ss_diag *d) {
  ss_orbit_report *rep = c->rep;
  double roots[SCAN_MAX_ROOTS][3], rejected[2][3];
  int nr = 0, n_rejected = 0, before = c->n;
  int rc = ss__scan_period1(c->m, 2 + f, dmax, h, refine, roots, SCAN_MAX_ROOTS,
                            &nr, rejected, &n_rejected, &rep->newton_starts,
                            &rep->scan_cells, &rep->scan_step, scan_stop, c);
  rep->scan_box = dmax;
  if (rc == SS_ENOMEM)
    return ss__fail(d, rc, "", 0, "out of memory in the orbit search");
  for (int r = 0; r < nr && !over_budget(c); r++) {
    /* one the simulations found already needs no solve */
    if (known_period1(c, f, roots[r]))
      rep->duplicates++;
    else
      try_solve(c, 2 + f, FAMILY_SEQ[f], roots[r], SS_SOURCE_DURATION_GRID);
  }
  for (int r = 0; r < n_rejected && c->n == before && !over_budget(c); r++)
    try_solve(c, 2 + f, FAMILY_SEQ[f], rejected[r], SS_SOURCE_DURATION_GRID);
  return SS_OK;
}

/* The scans of each effort: the grid's step in radians of the fastest
 * motion (the fast mode, or x1 under stick), and how many times a cell
 * Newton steps out of is split (scan.c).  A finer grid alone does not find
 * every root a coarser one finds: the cell test judges a cell by its
 * corners, and where two zero lines run side by side a cell can hold a root
 * it does not see, which a coarser grid reached by Newton from a
 * neighbouring cell (at chi 0.3035, eta 0.2236, us 0.0399, ur 0.2567, a
 * stick of 0.095 that a step of 0.49 and 0.29 found and one of 0.148
 * lost).  So each effort makes every Newton start of the one below and more:
 * effort 1 is effort 2's grid without the splits, effort 3 effort 2's scan
 * and then one on a grid twice as fine.  A step of 0 ends the list. */
#define EFFORT_SCANS 2
static const struct {
  double step;
  int refine;
} EFFORT_SCAN[3][EFFORT_SCANS] = {
    {{0.3, 0}, {0, 0}}, {{0.3, 3}, {0, 0}}, {{0.3, 3}, {0.15, 3}}};

/* Source 2: every root of the period-1 duration equations of the two
 * families asked for, with each duration within 1.5 slow modal periods,
 * from the scans of the effort (the report gives the finest step). */
static int from_scan(collect *c, unsigned kinds, int effort, ss_diag *d) {
  const ss_model *m = c->m;
  double dmax = c->box;
  for (int f = 0; f < 2; f++)
    for (int l = 0; l < EFFORT_SCANS && EFFORT_SCAN[effort - 1][l].step > 0;
         l++) {
      if (!(kinds & FAMILY_KIND[f]) || over_budget(c))
        continue;
      double h = EFFORT_SCAN[effort - 1][l].step / fmax(m->w[1], 1.0);
      int rc = scan_family(c, f, dmax, h, EFFORT_SCAN[effort - 1][l].refine, d);
      if (rc)
        return rc;
    }
  return SS_OK;
}

/* Whether the fixed point s of P^k is one of no P^j, j | k, j < k. */
int ss__minimal_period(const ss_model *m, const double s[2], int k) {
  const ss_params *p = &m->p;
  double scale = fmax(p->V, (p->ur - p->us) / p->chi), o1[2];
  for (int j = 1; j < k; j++)
    if (k % j == 0 &&
        ss_poincare(m, s, j, MAP_EVENTS * (size_t)j, o1, NULL, NULL, NULL) ==
            0 &&
        fabs(o1[0] - s[0]) + fabs(o1[1] - s[1]) < 1e-8 * scale)
      return 0;
  return 1;
}

/* Source 3: Newton on P^k from each seed, k up to kmax; a fixed point of
 * P^k that is one of P^j, j | k, is not new. */
static void from_map_newton(collect *c, double seeds[][2], int ns, int kmax) {
  for (int k = 1; k <= kmax; k++)
    for (int i = 0; i < ns && !over_budget(c); i++) {
      double s[2] = {seeds[i][0], seeds[i][1]}, dur[SS_MAX_PHASES];
      ss_mode modes[SS_MAX_PHASES];
      int n;
      c->rep->newton_starts++;
      if (ss__map_newton(c->m, s, k, modes, dur, &n) == 0 &&
          ss__minimal_period(c->m, s, k))
        try_solve(c, n, modes, dur, SS_SOURCE_MAP_NEWTON);
    }
}

/* The proof that nothing of the two period-1 families asked for is missing,
 * each within the search's own budget: a share of what is left of it, a
 * tenth kept for the rest. */
static void certify_families(collect *c, unsigned kinds,
                             const ss_orbit_opts *opts) {
  ss_orbit_report *rep = c->rep;
  double dmax = c->box;
  double secs = opts->certify_seconds > 0 ? opts->certify_seconds : 10;
  int left = !!(kinds & FAMILY_KIND[0]) + !!(kinds & FAMILY_KIND[1]);
  for (int f = 0; f < 2; f++) {
    if (!(kinds & FAMILY_KIND[f]) || over_budget(c))
      continue;
    double s = secs;
    if (c->budget > 0) {
      double rest = 0.9 * c->budget - (ss__now() - c->t_start);
      s = fmin(s, rest / left);
    }
    if (s > 0) {
      certify_family(c, f, dmax, s, &rep->cert[f]);
    } else {
      memset(&rep->cert[f], 0, sizeof rep->cert[f]);
      rep->cert[f].ran = 1;
      snprintf(rep->cert[f].why, sizeof rep->cert[f].why,
               "no time left for the proof in the search's budget");
    }
    left--;
  }
}

/* Only the kinds asked for, sorted by kind, then period (stable: the order
 * found among equals). */
static void keep_and_sort(collect *c, unsigned kinds) {
  int w = 0;
  for (int i = 0; i < c->n; i++)
    if (kinds & c->out[i].kind)
      c->out[w++] = c->out[i];
  c->n = w;
  for (int i = 1; i < c->n; i++)
    for (int j = i; j > 0; j--) {
      ss_orbit *a = &c->out[j - 1], *b = &c->out[j];
      if (a->kind > b->kind || (a->kind == b->kind && a->period > b->period)) {
        ss_orbit t = *a;
        *a = *b;
        *b = t;
      }
    }
}

/* The finite-difference check of the Jacobian, for the orbits returned. */
static void difference_checks(collect *c) {
  for (int i = 0; i < c->n; i++) {
    ss_orbit *q = &c->out[i];
    ss_stab_opts so = {q->n_turns, 1};
    ss_stability(c->m, q->n_phases, q->modes, q->durations, q->z0, &so,
                 &q->stab);
  }
}

/* The search's status: why nothing was found, if so and not said yet; a
 * cancellation or a spent budget. */
static int search_status(collect *c, ss_diag *d) {
  ss_orbit_report *rep = c->rep;
  if (c->n == 0 && !rep->reason[0])
    snprintf(rep->reason, sizeof rep->reason,
             "no periodic orbit found: %d Newton starts gave %d roots, none "
             "feasible; %d simulations did not settle on a periodic motion",
             rep->newton_starts, rep->roots, rep->simulations);
  if (over_budget(c) && c->stopped == SS_ECANCELED)
    return ss__fail(d, SS_ECANCELED, "", 0,
                    "the orbit search was cancelled after finding %d orbits",
                    c->n);
  if (c->stopped)
    return ss__fail(d, SS_ELIMIT_TIME, "max_seconds", c->budget,
                    "the orbit search ran out of its %g s budget after "
                    "finding %d orbits",
                    c->budget, c->n);
  return SS_OK;
}

int ss_orbit_find(const ss_model *m, const ss_orbit_opts *opts, ss_orbit *out,
                  int max_out, int *n_out, ss_orbit_report *rep, ss_diag *d) {
  ss_orbit_opts def = {0};
  ss_orbit_report rep_local;
  const ss_params *p = &m->p;
  collect c;
  int rc;
  if (!opts)
    opts = &def;
  if (!rep)
    rep = &rep_local;
  memset(rep, 0, sizeof *rep);
  if (!out || max_out < 0 || !n_out)
    return ss__fail(d, SS_EINVAL, "orbits", 0, "missing output");
  unsigned kinds = opts->kinds ? opts->kinds : SS_ORBIT_ALL;
  int effort = opts->effort ? opts->effort : 2;
  int max_k = opts->max_period ? opts->max_period : 4;
  if (effort < 1 || effort > 3)
    return ss__fail(d, SS_EINVAL, "effort", effort, "effort is 1, 2 or 3");
  if (max_k < 1 || max_k > 8)
    return ss__fail(d, SS_EINVAL, "max_period", max_k,
                    "max_period is between 1 and 8");
  memset(&c, 0, sizeof c);
  c.m = m;
  c.out = out;
  c.max = max_out;
  c.scale = fmax(p->V, (p->ur - p->us) / p->chi);
  c.rep = rep;
  c.t_start = ss__now();
  c.budget = opts->max_seconds;
  c.cancelled = opts->cancelled;
  c.cancel_cls = opts->cancel_cls;
  *n_out = 0;
  if (opts->n_guess > 0) {
    if ((rc = from_guess(&c, opts, d)) == SS_OK)
      *n_out = c.n;
    return rc;
  }
  double seeds[MAX_SEEDS][2];
  int ns, ns_sim = make_seeds(&c, effort, seeds, &ns);
  grow_box(&c, max_k);
  from_simulations(&c, seeds, ns_sim, max_k);
  if ((rc = from_scan(&c, kinds, effort, d)))
    return rc;
  if ((kinds & SS_ORBIT_OTHER) && effort >= 2)
    from_map_newton(&c, seeds, ns,
                    effort == 2 ? (max_k < 2 ? max_k : 2) : max_k);
  if (opts->certify)
    certify_families(&c, kinds, opts);
  keep_and_sort(&c, kinds);
  if (opts->difference_check)
    difference_checks(&c);
  *n_out = c.n;
  return search_status(&c, d);
}
