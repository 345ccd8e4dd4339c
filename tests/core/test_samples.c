/*
 * test_samples.c: samples placed for a curve (ss_sim_opts.sample_tolerance)
 * against the true curve.
 *
 * The truth is the closed form of each phase (ss_flow from the phase's
 * start, as the recorded events give it), evaluated at 10^5 evenly spaced
 * times over the window and at 8 points inside every polyline segment; the
 * distance of each such point to the polyline is bounded above by its
 * distance to the segment that spans its time.  Every event must be a
 * vertex, twice (the mode before, then the mode after).  The count is set
 * against the fewest evenly spaced samples that meet the same tolerance,
 * as the API's even samples are (events not among them): three times our
 * count must still miss the tolerance; and per phase with the events
 * included (the strongest even sampling), found by doubling and bisection
 * on the count, reported; and against the fewest vertices on the curve any
 * sampler keeping the events could place (estimated greedily): ours must
 * be within a fifth of it.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "stickslip.h"
#include "test.h"

static const ss_params PAPER = {0.2, 4.0, 0.0724, 0.6178, 1.0};

/* The true curve: the phases of one run from its events. */
typedef struct truth {
  const ss_model *m;
  int n;
  double t[512];    /* start of each phase */
  double x[512][4]; /* state there */
  ss_mode mode[512];
} truth;

static void truth_init(truth *tr, const ss_model *m, const double x0[4],
                       const ss_sim_result *r, double t_end) {
  tr->m = m;
  tr->n = 1;
  tr->t[0] = 0;
  memcpy(tr->x[0], x0, sizeof tr->x[0]);
  tr->mode[0] = ss_mode_of_state(m, x0);
  for (size_t k = 0; k < r->n_events && tr->n < 512; k++) {
    if (r->events[k].t > t_end)
      break;
    tr->t[tr->n] = r->events[k].t;
    memcpy(tr->x[tr->n], r->events[k].x, sizeof tr->x[0]);
    tr->mode[tr->n] = r->events[k].to;
    tr->n++;
  }
}

static void truth_at(const truth *tr, double t, double x[4]) {
  int k = tr->n - 1;
  while (k > 0 && tr->t[k] > t)
    k--;
  ss_flow(tr->m, tr->mode[k], t - tr->t[k], tr->x[k], x);
}

typedef struct metric {
  unsigned axes;
  double scale[4];
} metric;

/* The scaled distance from p to the segment [a, b]. */
static double seg_dist(const metric *mt, const double p[4], const double a[4],
                       const double b[4]) {
  double ab[4], ap[4], ab2 = 0, t = 0, d2 = 0;
  for (int i = 0; i < 4; i++) {
    int on = !mt->axes || (mt->axes & (1u << i));
    double s = on ? 1 / (mt->scale[i] > 0 ? mt->scale[i] : 1) : 0;
    ab[i] = (b[i] - a[i]) * s;
    ap[i] = (p[i] - a[i]) * s;
    ab2 += ab[i] * ab[i];
  }
  if (ab2 > 0) {
    for (int i = 0; i < 4; i++)
      t += ap[i] * ab[i];
    t /= ab2;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
  }
  for (int i = 0; i < 4; i++) {
    double e = ap[i] - t * ab[i];
    d2 += e * e;
  }
  return sqrt(d2);
}

/* The largest distance of the true curve to the polyline (st, sx): at n
 * evenly spaced times over [t0, t1] and at 8 points inside each segment,
 * each to the segment that spans its time. */
static double polyline_error(const truth *tr, const metric *mt, size_t ns,
                             const double *st, const double *sx, double t0,
                             double t1, size_t n) {
  double worst = 0, p[4];
  size_t j = 0;
  for (size_t i = 0; i < n; i++) {
    double t = t0 + (t1 - t0) * ((double)i / (double)(n - 1));
    while (j + 2 < ns && st[j + 1] < t)
      j++;
    truth_at(tr, t, p);
    double e = seg_dist(mt, p, sx + 4 * j, sx + 4 * (j + 1));
    worst = e > worst ? e : worst;
  }
  for (size_t k = 0; k + 1 < ns; k++)
    for (int q = 1; q <= 8; q++) {
      double t = st[k] + (st[k + 1] - st[k]) * q / 9.0;
      truth_at(tr, t, p);
      double e = seg_dist(mt, p, sx + 4 * k, sx + 4 * (k + 1));
      worst = e > worst ? e : worst;
    }
  return worst;
}

/* The error of n evenly spaced samples over [t0, t1]; per phase (each
 * phase's own n_k = ceil(n * length / (t1 - t0)) segments, its ends
 * included) when per_phase. */
static double even_error(const truth *tr, const metric *mt, double t0,
                         double t1, size_t n, int per_phase) {
  double worst = 0, a[4], b[4], p[4];
  if (!per_phase) {
    for (size_t k = 0; k + 1 < n; k++) {
      double ta = t0 + (t1 - t0) * ((double)k / (double)(n - 1));
      double tb = t0 + (t1 - t0) * ((double)(k + 1) / (double)(n - 1));
      truth_at(tr, ta, a);
      truth_at(tr, tb, b);
      for (int q = 1; q <= 8; q++) {
        truth_at(tr, ta + (tb - ta) * q / 9.0, p);
        double e = seg_dist(mt, p, a, b);
        worst = e > worst ? e : worst;
      }
    }
    return worst;
  }
  for (int ph = 0; ph < tr->n; ph++) {
    double pa = fmax(t0, tr->t[ph]);
    double pb = fmin(t1, ph + 1 < tr->n ? tr->t[ph + 1] : t1);
    if (!(pb > pa))
      continue;
    size_t m = (size_t)ceil((double)n * (pb - pa) / (t1 - t0));
    m = m < 1 ? 1 : m;
    for (size_t k = 0; k < m; k++) {
      double ta = pa + (pb - pa) * ((double)k / (double)m);
      double tb = pa + (pb - pa) * ((double)(k + 1) / (double)m);
      ss_flow(tr->m, tr->mode[ph], ta - tr->t[ph], tr->x[ph], a);
      ss_flow(tr->m, tr->mode[ph], tb - tr->t[ph], tr->x[ph], b);
      for (int q = 1; q <= 8; q++) {
        ss_flow(tr->m, tr->mode[ph], ta + (tb - ta) * q / 9.0 - tr->t[ph],
                tr->x[ph], p);
        double e = seg_dist(mt, p, a, b);
        worst = e > worst ? e : worst;
      }
    }
  }
  return worst;
}

/* The fewest even samples (to 3 %) whose error is at most eps; 0 when
 * more than cap are needed. */
static size_t even_needed(const truth *tr, const metric *mt, double t0,
                          double t1, double eps, int per_phase, size_t cap) {
  size_t lo = 2, hi = 2;
  while (even_error(tr, mt, t0, t1, hi, per_phase) > eps) {
    lo = hi;
    hi *= 2;
    if (hi > cap)
      return 0;
  }
  while (hi - lo > 1 && (double)(hi - lo) > 0.03 * (double)hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (even_error(tr, mt, t0, t1, mid, per_phase) > eps)
      lo = mid;
    else
      hi = mid;
  }
  return hi;
}

/* The largest distance of the phase ph's curve over [ta, tb] to its
 * chord, at 32 times inside. */
static double chord_error(const truth *tr, const metric *mt, int ph, double ta,
                          double tb) {
  double a[4], b[4], p[4], worst = 0;
  ss_flow(tr->m, tr->mode[ph], ta - tr->t[ph], tr->x[ph], a);
  ss_flow(tr->m, tr->mode[ph], tb - tr->t[ph], tr->x[ph], b);
  for (int q = 1; q <= 32; q++) {
    ss_flow(tr->m, tr->mode[ph], ta + (tb - ta) * q / 33.0 - tr->t[ph],
            tr->x[ph], p);
    double e = seg_dist(mt, p, a, b);
    worst = e > worst ? e : worst;
  }
  return worst;
}

/* The fewest vertices on the curve that any sampler keeping the events
 * could place, estimated greedily: from each vertex the furthest time (to
 * 1e-4) whose chord is within eps at 32 times inside, per phase, each
 * phase's ends included.  Greedy is optimal when a chord within eps stays
 * so over any sub-arc; the 32 times make the estimate, if anything, low. */
static size_t fewest_needed(const truth *tr, const metric *mt, double t0,
                            double t1, double eps) {
  size_t n = 0;
  for (int ph = 0; ph < tr->n; ph++) {
    double pa = fmax(t0, tr->t[ph]);
    double pb = fmin(t1, ph + 1 < tr->n ? tr->t[ph + 1] : t1);
    if (!(pb > pa))
      continue;
    n++;
    for (double u = pa; u < pb;) {
      double lo = 0, hi = pb - u;
      if (chord_error(tr, mt, ph, u, pb) > eps) {
        hi = (pb - u) / 2;
        while (chord_error(tr, mt, ph, u, u + hi) > eps)
          hi /= 2;
        lo = hi;
        hi *= 2;
        while (hi - lo > 1e-4 * hi) {
          double mid = 0.5 * (lo + hi);
          if (chord_error(tr, mt, ph, u, u + mid) > eps)
            hi = mid;
          else
            lo = mid;
        }
        hi = lo;
      }
      u += hi;
      n++;
      if (pb - u < 1e-12 * fmax(1, pb))
        break;
    }
  }
  return n;
}

/* One run sampled to eps: the tolerance holds, every event is a vertex
 * twice; the count within a fifth of the fewest possible, and at most a
 * third of even sampling's (compare 2) or so wherever the fewest possible
 * is (compare 1).  Returns the count. */
static size_t check_curve(const ss_model *m, const double x0[4], double t_end,
                          const metric *mt, double eps, int compare,
                          const char *what) {
  ss_sim_opts o;
  memset(&o, 0, sizeof o);
  o.t_end = t_end;
  o.sample_to = t_end;
  o.record_events = 1;
  o.sample_tolerance = eps;
  o.sample_axes = mt->axes;
  memcpy(o.sample_scale, mt->scale, sizeof o.sample_scale);
  o.max_samples = 10000000;
  ss_sim_result r;
  ASSERT_EQ_INT(ss_simulate(m, x0, &o, &r, NULL), SS_OK);
  truth tr;
  truth_init(&tr, m, x0, &r, t_end);
  double err =
      polyline_error(&tr, mt, r.n_samples, r.st, r.sx, 0, t_end, 100001);
  ASSERT_TRUE(err <= eps * (1 + 1e-9) + 1e-13);
  /* the ends, and each event inside twice: before, then after */
  ASSERT_TRUE(r.n_samples >= 2);
  ASSERT_TRUE(r.st[0] == 0 && r.st[r.n_samples - 1] == t_end);
  int missing = 0;
  for (size_t k = 0; k < r.n_events; k++) {
    const ss_event *e = &r.events[k];
    if (e->t >= t_end)
      continue;
    int found = 0;
    for (size_t i = 0; i + 1 < r.n_samples && !found; i++)
      found = fabs(r.st[i] - e->t) <= 1e-12 * fmax(1, e->t) &&
              fabs(r.st[i + 1] - e->t) <= 1e-12 * fmax(1, e->t) &&
              r.smode[i] == (unsigned char)e->from &&
              r.smode[i + 1] == (unsigned char)e->to;
    missing += !found;
  }
  ASSERT_EQ_INT(missing, 0);
  for (size_t i = 1; i < r.n_samples; i++)
    ASSERT_TRUE(r.st[i] >= r.st[i - 1]);
  size_t n = r.n_samples;
  if (compare) {
    /* the API's even samples: how many meet eps (up to 16 times ours),
     * and whether three times ours still miss it; the strongest even
     * sampling: per phase, the events included */
    double err3 = even_error(&tr, mt, 0, t_end, 3 * n, 0);
    size_t plain = even_needed(&tr, mt, 0, t_end, eps, 0, 16 * n);
    size_t phased = even_needed(&tr, mt, 0, t_end, eps, 1, 16 * n);
    char pl[32];
    if (plain)
      snprintf(pl, sizeof pl, "%zu (%.1fx)", plain, (double)plain / (double)n);
    else
      snprintf(pl, sizeof pl, "> %zu (16x)", 16 * n);
    size_t fewest = fewest_needed(&tr, mt, 0, t_end, eps);
    printf("%-26s eps %.0e: %5zu points, error %.3g; even: %-15s x3 error "
           "%.2g; per phase with events: %zu (%.2fx); fewest: %zu (%.2fx)\n",
           what, eps, n, err, pl, err3, phased, (double)phased / (double)n,
           fewest, (double)fewest / (double)n);
    fflush(stdout);
    /* within a fifth of the fewest any sampler could place */
    ASSERT_TRUE(5 * n <= 6 * fewest);
    /* a third of the even samples' count, or, where the curve's curvature
     * and not its corners sets both counts, at least where the fewest
     * possible is itself more than a third (reported) */
    if (compare > 1)
      ASSERT_TRUE(plain == 0 || plain >= 3 * n);
    else
      ASSERT_TRUE(plain == 0 || plain >= 3 * n || 3 * fewest > plain);
  }
  ss_sim_result_free(&r);
  return n;
}

/* EVIDENCE: docs/api/simulate.md: on the paper's orbit, one
 * period, for eps from 1e-2 to 1e-6, in the four state variables and in the
 * (x2, x2') plane with per-axis scales (pixels): within eps, every event a
 * vertex twice, at most a third of the even samples; the stick in (x2, x2')
 * costs its two ends. */
static void test_paper(void) {
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &PAPER, NULL), SS_OK);
  ss_orbit_opts oo;
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_OVERSHOOT;
  ss_orbit orb[4];
  int n = 0;
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, orb, 4, &n, NULL, NULL), SS_OK);
  ASSERT_EQ_INT(n, 1);
  const double *x0 = orb[0].x0;
  double T = orb[0].period;
  metric all = {0, {1, 1, 1, 1}};
  /* a 600 x 400 pixel plot of x2 in [-3, 5], x2' in [-3, 3] */
  metric plane = {2 | 8, {8.0 / 600, 0, 0, 6.0 / 400}};
  for (double eps = 1e-2; eps > 0.5e-6; eps /= 10) {
    check_curve(&m, x0, T, &all, eps, 2, "paper, x1 x2 x1' x2'");
    check_curve(&m, x0, T, &plane, eps / 1e-2 * 0.5, 2,
                "paper, (x2, x2') pixels");
  }
  /* the stick is straight in (x2, x2'): its two ends only */
  ss_sim_opts o;
  memset(&o, 0, sizeof o);
  o.t_end = o.sample_to = T;
  o.sample_tolerance = 1e-6;
  o.sample_axes = 2 | 8;
  o.max_samples = 100000;
  ss_sim_result r;
  ASSERT_EQ_INT(ss_simulate(&m, x0, &o, &r, NULL), SS_OK);
  int stick = 0;
  for (size_t i = 0; i < r.n_samples; i++)
    stick += r.smode[i] == SS_MODE_STICK;
  ASSERT_EQ_INT(stick, 2);
  ss_sim_result_free(&r);
  /* a window inside the period: its ends are samples */
  o.sample_from = 3;
  o.sample_to = 8;
  o.sample_axes = 0;
  ASSERT_EQ_INT(ss_simulate(&m, x0, &o, &r, NULL), SS_OK);
  ASSERT_TRUE(r.n_samples > 2 && r.st[0] == 3 && r.st[r.n_samples - 1] == 8);
  ss_sim_result_free(&r);
}

static double uniform(unsigned long long *s, double lo, double hi) {
  *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
  return lo + (hi - lo) * (double)(*s >> 11) / 9007199254740992.0;
}

/* EVIDENCE: docs/api/simulate.md: the same on the orbits
 * of random parameter sets (all kinds, up to 2 turns), over one period and
 * over three. */
static void test_random(void) {
  unsigned long long seed = 20261124;
  int orbits = 0;
  for (int set = 0; set < 40 && orbits < 12; set++) {
    ss_params p = {uniform(&seed, 0.05, 0.9), uniform(&seed, 0.2, 20),
                   uniform(&seed, 0.02, 0.2), 0, 1};
    p.ur = p.us * uniform(&seed, 1.5, 15);
    ss_model m;
    if (ss_model_init(&m, &p, NULL) != SS_OK)
      continue;
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    oo.max_period = 2;
    ss_orbit orb[8];
    int n = 0;
    if (ss_orbit_find(&m, &oo, orb, 8, &n, NULL, NULL) != SS_OK)
      continue;
    for (int k = 0; k < n && k < 2; k++, orbits++) {
      metric all = {0, {1, 1, 1, 1}};
      char what[64];
      snprintf(what, sizeof what, "set %d orbit %d (%d phases)", set, k,
               orb[k].n_phases);
      check_curve(&m, orb[k].x0, orb[k].period, &all, 1e-3, 1, what);
      check_curve(&m, orb[k].x0, orb[k].period, &all, 1e-5, 2, what);
      check_curve(&m, orb[k].x0, 3 * orb[k].period, &all, 1e-4, 0, what);
    }
  }
  ASSERT_TRUE(orbits >= 8);
}

/* EVIDENCE: docs/api/simulate.md: a curve nearly straight
 * in its scaled coordinates (a stick with a small ripple, x1 and x2 scaled
 * up 300 and 8000 times): the part across a long chord is small against
 * the chord and must not be lost to rounding (it was, as |f|^2 - (f.e)^2,
 * and the polyline missed the curve by 13.8 times eps). */
static void test_straight(void) {
  ss_params p = {0.3297988943736313, 0.79922832841287161, 0.17527159304885123,
                 0.82124920468136198, 1};
  double x0[4] = {-0.75817458155770356, -2.2988997066001438,
                  0.32979911479541635, 1};
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  metric mt = {1 | 2, {0.0029893984450986891, 0.0001268481247761, 0, 0}};
  check_curve(&m, x0, 2.3699399726452652, &mt, 2.0232206634829993e-07, 0,
              "stick with a ripple");
}

/* EVIDENCE: docs/api/simulate.md: random runs from random
 * states (half of them starting in a stick with a small ripple), random
 * tolerances 1e-1 to 1e-7, random axes and scales 1e-4 to 1e4: every one within
 * eps, every event a vertex. */
static void test_random_runs(void) {
  unsigned long long seed = 20261125;
  int runs = 0;
  for (int k = 0; k < 60; k++) {
    ss_params p = {uniform(&seed, 0.05, 0.95), uniform(&seed, 0.2, 20),
                   uniform(&seed, 0.02, 0.2), 0, 1};
    p.ur = p.us * uniform(&seed, 1.5, 15);
    ss_model m;
    if (ss_model_init(&m, &p, NULL) != SS_OK)
      continue;
    double x0[4], L = p.ur / p.chi;
    x0[0] = uniform(&seed, -3, 3) * L;
    if (k % 2 == 0) {
      /* a stick (the force chi (x2 - x1) inside (-ur, ur)) near the
       * stick's own rest (x1 = chi x2, x1' = chi V): a long stick with a
       * small ripple, nearly straight */
      double ripple = exp(uniform(&seed, log(1e-12), log(1e-2)));
      x0[1] = -0.95 * L / (1 - p.chi) * uniform(&seed, 0.5, 1);
      x0[0] = p.chi * x0[1] + ripple * (k % 4 ? 1 : -1);
      x0[2] = p.chi * p.V + ripple * uniform(&seed, -1, 1);
      x0[3] = p.V;
    } else {
      x0[1] = uniform(&seed, -3, 3) * L;
      x0[2] = uniform(&seed, -2, 2);
      x0[3] = uniform(&seed, -2, 2);
    }
    metric mt = {0, {1, 1, 1, 1}};
    mt.axes = (unsigned)(uniform(&seed, 0, 16)) & 15u;
    for (int i = 0; i < 4; i++)
      mt.scale[i] = exp(uniform(&seed, log(1e-4), log(1e4)));
    double eps = exp(uniform(&seed, log(1e-7), log(1e-1)));
    if (k % 2 == 0) {
      /* the stick nearly straight where it counts: x1 or x2 measured at a
       * fine scale (its travel long against the ripple), eps small */
      int i = k % 4 ? 1 : 0;
      mt.axes |= 1u << i;
      mt.scale[i] = exp(uniform(&seed, log(1e-4), log(1e-3)));
      eps = exp(uniform(&seed, log(1e-7), log(1e-5)));
    }
    double t_end = exp(uniform(&seed, 0, log(60)));
    /* at most a few hundred thousand samples */
    ss_sim_opts o;
    memset(&o, 0, sizeof o);
    o.t_end = o.sample_to = t_end;
    o.sample_tolerance = eps;
    o.sample_axes = mt.axes;
    memcpy(o.sample_scale, mt.scale, sizeof o.sample_scale);
    o.max_samples = 200000;
    ss_sim_result r;
    int rc = ss_simulate(&m, x0, &o, &r, NULL);
    ss_sim_result_free(&r);
    if (rc == SS_ELIMIT_SAMPLES)
      continue;
    ASSERT_EQ_INT(rc, SS_OK);
    char what[64];
    snprintf(what, sizeof what, "random run %d", k);
    check_curve(&m, x0, t_end, &mt, eps, 0, what);
    runs++;
  }
  printf("random runs checked: %d\n", runs);
  ASSERT_TRUE(runs >= 40);
}

/* EVIDENCE: docs/api/simulate.md: the count is bounded by
 * max_samples (SS_ELIMIT_SAMPLES, the samples so far kept), and a bad
 * tolerance, scale or axis set, or a tolerance with even samples, is
 * SS_EINVAL. */
static void test_limits(void) {
  ss_model m;
  ss_model_init(&m, &PAPER, NULL);
  double x0[4] = {1.2739277342427062, 4.362927734242709, -0.8074871367243069,
                  1.0};
  ss_sim_opts o;
  memset(&o, 0, sizeof o);
  o.t_end = o.sample_to = 100;
  o.sample_tolerance = 1e-8;
  o.max_samples = 50;
  ss_sim_result r;
  ss_diag d;
  ss_diag_clear(&d);
  ASSERT_EQ_INT(ss_simulate(&m, x0, &o, &r, &d), SS_ELIMIT_SAMPLES);
  ASSERT_EQ_INT((int)r.n_samples, 50);
  printf("limit: %s\n", d.text);
  ss_sim_result_free(&r);
  o.max_samples = 0;
  double bad[] = {-1, NAN, INFINITY};
  for (int i = 0; i < 3; i++) {
    o.sample_tolerance = bad[i];
    ASSERT_EQ_INT(ss_simulate(&m, x0, &o, &r, NULL), SS_EINVAL);
    ss_sim_result_free(&r);
  }
  o.sample_tolerance = 1e-3;
  o.sample_scale[1] = -2;
  ASSERT_EQ_INT(ss_simulate(&m, x0, &o, &r, NULL), SS_EINVAL);
  ss_sim_result_free(&r);
  o.sample_scale[1] = 0;
  o.sample_axes = 16;
  ASSERT_EQ_INT(ss_simulate(&m, x0, &o, &r, NULL), SS_EINVAL);
  ss_sim_result_free(&r);
  o.sample_axes = 0;
  o.n_samples = 10;
  ASSERT_EQ_INT(ss_simulate(&m, x0, &o, &r, NULL), SS_EINVAL);
  ss_sim_result_free(&r);
}

int main(void) {
  test_paper();
  test_random();
  test_straight();
  test_random_runs();
  test_limits();
  TEST_DONE();
}
