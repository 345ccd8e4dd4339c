/*
 * test_basins.c: basins of attraction of the paper's parameter set.
 *
 * The paper's set (chi 0.2, eta 4, us 0.0724, ur 0.6178, V 1) has two
 * stable attractors, its overshoot orbit and a period-3 orbit.  Over the
 * slice x1 in [-2, 4], x2 in [0, 8] with x1' = 0, x2' = V (n x n cells,
 * default 24; SS_BASINS_N overrides):
 *  - both attractors are found, every cell is labelled (none unresolved),
 *    and the counts add up;
 *  - a sample of cells of each label, simulated by the independent rk8pd
 *    reference (tests/ref) for 1500 time units, settles on the attractor
 *    of its label (its last return within 1e-5 of one of the attractor's),
 *    wherever the reference's answer does not depend on its tolerance;
 *  - the labels do not change when us, ur, V and the slice are all scaled
 *    by 2 (the equations are homogeneous in them);
 *  - a cell started on an attractor's own stick -> slip point is labelled
 *    with it;
 *  - max_returns 1 leaves cells unresolved; the time budget and the cancel
 *    hook stop; bad options are refused;
 *  - the time budget and the cancel hook are polled inside a cell: one cell
 *    far from every attractor, whose motion never returns to Sigma0, runs
 *    its max_returns * 64 events (seconds) unless they stop it.
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "refsim.h"
#include "stickslip.h"
#include "test.h"

#define MAXEV 20000

static const ss_params PAPER = {0.2, 4, 0.0724, 0.6178, 1};

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* The CPU time of the calling thread: what the computation spends between
 * two polls, whatever else the machine runs. */
static double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void slice(ss_basin_opts *o, int n, double c) {
  memset(o, 0, sizeof *o);
  o->vary[0] = 0;
  o->vary[1] = 1;
  o->from[0] = -2 * c;
  o->to[0] = 4 * c;
  o->from[1] = 0;
  o->to[1] = 8 * c;
  o->n[0] = o->n[1] = n;
  o->state[2] = 0;
  o->state[3] = c;
}

static double cell_value(const ss_basin_opts *o, int a, int i) {
  double k = (double)(o->n[a] - 1);
  return (o->from[a] * (k - (double)i) + o->to[a] * (double)i) / k;
}

/* The attractor the rk8pd reference settles on from @a x0, by its last
 * return to Sigma0 (x, not z, coordinates); -1 if none matches. */
static int reference_at(const ss_params *p, const ss_basins *b,
                        const double x0[4], ref_event *ev, double tol) {
  ref_params rp = {p->chi, p->eta, p->us, p->ur, p->V};
  ref_opts ro = {gsl_odeiv2_step_rk8pd, tol, tol, 0, 1e-14};
  /* the friction law: on the belt's speed, stick while the force is inside
   * [-ur, ur], else slip (above) or overshoot (below) */
  double f = p->chi * (x0[1] - x0[0]);
  int mode = x0[3] != p->V ? (x0[3] < p->V ? REF_SLIP : REF_OVERSHOOT)
             : f > p->ur   ? REF_SLIP
             : f < -p->ur  ? REF_OVERSHOOT
                           : REF_STICK;
  double xe[4];
  int me;
  long ne = ref_simulate(&rp, 0, x0, mode, 1500, &ro, ev, MAXEV, xe, &me);
  double d0 = p->us / (1 - p->chi), scale = (p->ur - p->us) / p->chi;
  for (long e = ne - 1; e >= 0; e--)
    if (ev[e].from == REF_STICK && ev[e].to == REF_SLIP) {
      for (int a = 0; a < b->n_attractors; a++)
        for (int k = 0; k < b->attractors[a].n_points; k++)
          if (fabs(ev[e].x[0] - d0 - b->attractors[a].points[k][0]) +
                  fabs(ev[e].x[2] - b->attractors[a].points[k][1]) <
              1e-5 * scale)
            return a;
      return -1;
    }
  return -1;
}

/* The reference's label at tolerances 1e-12 and 1e-13 (events located to
 * 1e-14), or -2 when they differ: a transient that passes so close to a
 * switching that the reference's own error decides it (one cell of the
 * 24x24 slice: at 1e-11 it settles on the overshoot orbit, at 1e-12 and
 * below on the period-3 orbit the exact simulation finds). */
static int reference_label(const ss_params *p, const ss_basins *b,
                           const double x0[4], ref_event *ev) {
  int a = reference_at(p, b, x0, ev, 1e-12);
  return a == reference_at(p, b, x0, ev, 1e-13) ? a : -2;
}

static int cancel_now(void *cls) {
  (void)cls;
  return 1;
}

/* A cancel hook that says stop from stop_after seconds after t0 on, and
 * records the longest CPU time between two of its calls. */
typedef struct watch {
  double t0, stop_after, last, gap;
  long calls;
} watch;

static int watch_hook(void *cls) {
  watch *w = cls;
  double c = cpu_now();
  if (w->calls++ && c - w->last > w->gap)
    w->gap = c - w->last;
  w->last = c;
  return now() - w->t0 > w->stop_after;
}

/* EVIDENCE: DESIGN section 5, a request's compute time is bounded and a
 * client that hangs up stops its computation, whatever the request's shape:
 * here one cell of 6.4 million events (100001 returns' worth), 3 s in the
 * optimised build, stopped within a fraction of a second. */
static void stops_inside_a_cell(const ss_model *m) {
  ss_basin_opts o;
  memset(&o, 0, sizeof o);
  o.vary[0] = 0;
  o.vary[1] = 1;
  o.from[0] = o.to[0] = o.from[1] = o.to[1] = -1e6;
  o.n[0] = o.n[1] = 1;
  o.state[3] = 1;
  o.max_returns = 100000;
  ss_basins b;
  ss_diag d;
  watch w = {now(), 0.5, 0, 0, 0};
  o.cancelled = watch_hook;
  o.cancel_cls = &w;
  ASSERT_EQ_INT(ss_basins_run(m, &o, &b, &d), SS_ECANCELED);
  double t = now() - w.t0;
  printf("cancelled after %.3f s: %ld polls, at most %.4f s apart\n", t,
         w.calls, w.gap);
  /* unpolled, the cell runs 3 s of CPU or more: a second's room for a
   * loaded machine still tells them apart */
  ASSERT_TRUE(t < w.stop_after + 1.0);
  ASSERT_TRUE(w.gap < 0.1);
  ASSERT_EQ_INT(b.unresolved, 1);
  ss_basins_free(&b);
  o.cancelled = NULL;
  o.max_seconds = 0.5;
  double t0 = now();
  ASSERT_EQ_INT(ss_basins_run(m, &o, &b, &d), SS_ELIMIT_TIME);
  t = now() - t0;
  printf("over the budget of %g s after %.3f s\n", o.max_seconds, t);
  ASSERT_TRUE(t < o.max_seconds + 1.0);
  ss_basins_free(&b);
}

int main(void) {
  const char *env = getenv("SS_BASINS_N");
  int N = env ? atoi(env) : 24;
  if (N < 4)
    N = 4;
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &PAPER, NULL), SS_OK);
  ss_basin_opts o;
  slice(&o, N, 1);
  o.threads = 2;
  ss_basins b;
  ss_diag d;
  double t0 = now();
  ASSERT_EQ_INT(ss_basins_run(&m, &o, &b, &d), SS_OK);
  double t = now() - t0;
  ASSERT_EQ_INT(b.n_attractors, 2);
  int k_over = -1, k_three = -1;
  for (int a = 0; a < b.n_attractors; a++) {
    const ss_basin_attractor *at = &b.attractors[a];
    if (at->orbit.kind == SS_ORBIT_OVERSHOOT && at->n_points == 1)
      k_over = a;
    if (at->n_points == 3)
      k_three = a;
    ASSERT_TRUE(at->orbit.stab.stable && at->radius > 0 && at->cells > 0);
    ASSERT_TRUE(!at->from_simulation);
  }
  ASSERT_TRUE(k_over >= 0 && k_three >= 0);
  /* the certificate, on 64 other points of each circle and half-way in:
   * P^(k j) takes them inside the radius */
  for (int a = 0; a < b.n_attractors; a++) {
    const ss_basin_attractor *at = &b.attractors[a];
    int k = at->n_points * at->iterations, outside = 0;
    double worst = 0;
    for (int i = 0; i < at->n_points; i++)
      for (int q = 0; q < 128; q++) {
        double ang = 6.283185307179586 * (q + 0.5) / 64;
        double u = at->radius * (q < 64 ? 1 : 0.5);
        double s[2] = {at->points[i][0] + u * cos(ang),
                       at->points[i][1] + u * sin(ang)},
               e[2];
        int rc = ss_poincare(&m, s, k, 64 * (size_t)k, e, NULL, NULL, NULL);
        double r = hypot(e[0] - at->points[i][0], e[1] - at->points[i][1]);
        outside += rc != SS_OK || !(r < at->radius);
        worst = fmax(worst, rc == SS_OK ? r / at->radius : INFINITY);
      }
    printf("attractor %d: 256 points of its circles, after %d periods, at "
           "most %.3g of the radius from it\n",
           a, at->iterations, worst);
    ASSERT_EQ_INT(outside, 0);
  }
  ASSERT_EQ_INT((int)b.unresolved, 0);
  ASSERT_EQ_INT(
      (int)(b.attractors[0].cells + b.attractors[1].cells + b.perpetual),
      N * N);
  printf("basins %dx%d: %.3f s, overshoot orbit %ld cells (radius %.3g, %d "
         "periods), period-3 orbit %ld cells (radius %.3g, %d periods), %ld "
         "returns, at most %d to land\n",
         N, N, t, b.attractors[k_over].cells, b.attractors[k_over].radius,
         b.attractors[k_over].iterations, b.attractors[k_three].cells,
         b.attractors[k_three].radius, b.attractors[k_three].iterations,
         b.returns, b.max_returns);

  /* labels against the reference, on up to 6 cells of each label */
  ref_event *ev = malloc(MAXEV * sizeof *ev);
  int checked[2] = {0, 0}, agree = 0, tried = 0;
  for (int c = 0; c < N * N && (checked[0] < 6 || checked[1] < 6); c += 7) {
    int l = b.labels[c];
    int slot = l == k_three ? 1 : 0;
    if (l >= 2 || checked[slot] >= 6)
      continue;
    double x0[4] = {cell_value(&o, 0, c / N), cell_value(&o, 1, c % N), 0, 1};
    int r = reference_label(&PAPER, &b, x0, ev);
    if (r == -2) {
      printf("cell %d: the reference depends on its tolerance\n", c);
      continue;
    }
    tried++;
    checked[slot]++;
    if (r == l)
      agree++;
    else
      printf("cell %d (x1 %.6g, x2 %.6g): label %d, the reference settles "
             "on %d\n",
             c, x0[0], x0[1], l, r);
  }
  /* the period-3 basin is small: look for its cells everywhere */
  for (int c = 0; c < N * N && checked[1] < 6; c++)
    if (b.labels[c] == k_three && c % 7) {
      double x0[4] = {cell_value(&o, 0, c / N), cell_value(&o, 1, c % N), 0, 1};
      int r = reference_label(&PAPER, &b, x0, ev);
      if (r == -2)
        continue;
      tried++;
      checked[1]++;
      agree += r == k_three;
      if (r != k_three)
        printf("cell %d: label %d (period 3), the reference settles on %d\n", c,
               k_three, r);
    }
  printf("reference: %d of %d sampled labels agree\n", agree, tried);
  ASSERT_TRUE(checked[0] == 6 && checked[1] >= 1);
  ASSERT_EQ_INT(agree, tried);
  free(ev);

  /* V-scaling: us, ur, V and the slice times 2 */
  {
    ss_params q = PAPER;
    q.us *= 2;
    q.ur *= 2;
    q.V *= 2;
    ss_model m2;
    ASSERT_EQ_INT(ss_model_init(&m2, &q, NULL), SS_OK);
    ss_basin_opts o2;
    slice(&o2, N, 2);
    o2.threads = 2;
    ss_basins b2;
    ASSERT_EQ_INT(ss_basins_run(&m2, &o2, &b2, &d), SS_OK);
    ASSERT_EQ_INT(b2.n_attractors, b.n_attractors);
    int differ = 0;
    for (int c = 0; c < N * N; c++) {
      /* the attractors may be listed in another order */
      int l = b.labels[c], l2 = b2.labels[c];
      int same = l < 2 && l2 < 2
                     ? b.attractors[l].n_points == b2.attractors[l2].n_points
                     : l == l2;
      differ += !same;
    }
    printf("V-scaling: %d of %d labels differ\n", differ, N * N);
    ASSERT_EQ_INT(differ, 0);
    ss_basins_free(&b2);
  }

  /* started on an attractor's own stick -> slip point */
  for (int a = 0; a < b.n_attractors; a++) {
    const ss_orbit *orb = &b.attractors[a].orbit;
    ss_basin_opts o1;
    memset(&o1, 0, sizeof o1);
    o1.vary[0] = 0;
    o1.vary[1] = 1;
    o1.from[0] = o1.to[0] = orb->x0[0];
    o1.from[1] = o1.to[1] = orb->x0[1];
    o1.n[0] = o1.n[1] = 1;
    o1.state[2] = orb->x0[2];
    o1.state[3] = orb->x0[3];
    ss_basins b1;
    ASSERT_EQ_INT(ss_basins_run(&m, &o1, &b1, &d), SS_OK);
    ASSERT_EQ_INT(b1.n_attractors, 2);
    ASSERT_TRUE(b1.labels[0] < 2 &&
                b1.attractors[b1.labels[0]].n_points == orb->n_turns);
    ASSERT_TRUE(b1.max_returns <= 1);
    ss_basins_free(&b1);
  }

  /* unresolved at max_returns; the budget; the cancel hook; bad options */
  {
    ss_basin_opts o3;
    slice(&o3, 8, 1);
    o3.max_returns = 1;
    ss_basins b3;
    ASSERT_EQ_INT(ss_basins_run(&m, &o3, &b3, &d), SS_OK);
    ASSERT_TRUE(b3.unresolved > 0);
    ss_basins_free(&b3);
    slice(&o3, 400, 1);
    o3.max_seconds = 0.05;
    ASSERT_EQ_INT(ss_basins_run(&m, &o3, &b3, &d), SS_ELIMIT_TIME);
    ASSERT_TRUE(b3.unresolved > 0);
    ss_basins_free(&b3);
    o3.max_seconds = 0;
    o3.cancelled = cancel_now;
    ASSERT_EQ_INT(ss_basins_run(&m, &o3, &b3, &d), SS_ECANCELED);
    ss_basins_free(&b3);
    slice(&o3, 8, 1);
    o3.vary[1] = 0;
    ASSERT_EQ_INT(ss_basins_run(&m, &o3, &b3, &d), SS_EINVAL);
    slice(&o3, 8, 1);
    o3.n[0] = 0;
    ASSERT_EQ_INT(ss_basins_run(&m, &o3, &b3, &d), SS_EINVAL);
    slice(&o3, 8, 1);
    o3.max_period = 9;
    ASSERT_EQ_INT(ss_basins_run(&m, &o3, &b3, &d), SS_EINVAL);
    ss_basins_free(&b3);
  }
  stops_inside_a_cell(&m);
  ss_basins_free(&b);
  TEST_DONE();
}
