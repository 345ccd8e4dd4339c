/*
 * test_continue.c: families of orbits followed in one parameter, each point
 * and each special point verified by an independent method: closure by
 * simulation, multipliers by central differences of the simulated Poincare
 * map, a grazing by the rk8pd reference simulation and by solving on both
 * sides of it.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "refsim.h"
#include "stickslip.h"
#include "test.h"

static const ss_params PAPER = {0.2, 4, 0.0724, 0.6178, 1};

/* The overshoot orbit at @a p, found with no guess. */
static int overshoot_at(const ss_params *p, ss_orbit *o) {
  ss_model m;
  ss_orbit_opts oo;
  int n = 0;
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_OVERSHOOT;
  if (ss_model_init(&m, p, NULL) != SS_OK ||
      ss_orbit_find(&m, &oo, o, 1, &n, NULL, NULL) != SS_OK)
    return 0;
  return n;
}

static double *param(ss_params *p, ss_param_id id) {
  double *v[] = {&p->chi, &p->eta, &p->us, &p->ur, &p->V};
  return v[id];
}

/* The multipliers of a 2x2 matrix, larger modulus first (re, im). */
static void eig2(const double J[2][2], double re[2], double im[2]) {
  double tr = J[0][0] + J[1][1], det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
  double disc = tr * tr / 4 - det;
  if (disc >= 0) {
    double a = tr / 2 + sqrt(disc), b = tr / 2 - sqrt(disc);
    re[0] = fabs(a) >= fabs(b) ? a : b;
    re[1] = fabs(a) >= fabs(b) ? b : a;
    im[0] = im[1] = 0;
  } else {
    re[0] = re[1] = tr / 2;
    im[0] = sqrt(-disc);
    im[1] = -im[0];
  }
}

/* A point of a family, checked: it closes by simulation, it is feasible,
 * and its multipliers are those of the finite-difference Jacobian of the
 * simulated map.  Returns the largest multiplier difference. */
static double check_point(const ss_params *p0, ss_param_id id,
                          const ss_branch *b, const ss_cont_point *pt) {
  ss_params p = *p0;
  *param(&p, id) = pt->value;
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  ss_orbit o;
  memset(&o, 0, sizeof o);
  o.n_phases = b->n_phases;
  memcpy(o.modes, b->modes, sizeof o.modes);
  memcpy(o.durations, pt->durations, sizeof o.durations);
  memcpy(o.z0, pt->z0, sizeof o.z0);
  ASSERT_EQ_INT(ss_orbit_check(&m, &o, NULL), SS_OK);
  ASSERT_TRUE(o.closure < 1e-12);
  ASSERT_TRUE(pt->residual < 1e-11);
  /* within a difference step of a grazing the simulated map is not
   * smooth: no finite differences there */
  if (o.min_margin.value < 1e-5)
    return 0;
  ss_stab_opts so = {o.n_turns, 1};
  ss_stab st;
  ASSERT_EQ_INT(
      ss_stability(&m, o.n_phases, o.modes, o.durations, o.z0, &so, &st),
      SS_OK);
  double re[2], im[2], diff = 0;
  eig2(st.jac_fd, re, im);
  for (int k = 0; k < 2; k++)
    diff = fmax(
        diff, hypot(re[k] - pt->eig_re[k], fabs(im[k]) - fabs(pt->eig_im[k])));
  return diff;
}

/* The rk8pd reference simulation of one period from the orbit's x0: the
 * switching margin -ur - chi (x2 - x1) at the end of its first phase. */
static double ref_switching_margin(const ss_params *p, const ss_cont_point *pt,
                                   const double d0[2]) {
  ref_params rp = {p->chi, p->eta, p->us, p->ur, p->V};
  ref_opts ro = {gsl_odeiv2_step_rk8pd, 1e-14, 1e-14, 0, 1e-14};
  ref_event ev[16];
  double x0[4] = {pt->z0[0] + d0[0], pt->z0[1] + d0[1], pt->z0[2], pt->z0[3]},
         xe[4];
  int me;
  long n = ref_simulate(&rp, 0, x0, REF_SLIP, pt->durations[0] * 1.01, &ro, ev,
                        16, xe, &me);
  ASSERT_TRUE(n >= 1);
  if (n < 1)
    return INFINITY;
  return -p->ur - p->chi * (ev[0].x[1] - ev[0].x[0]);
}

/* EVIDENCE: docs/checked/families.md: the paper's overshoot orbit continued in
 * ur; every point closes and its multipliers match the finite-difference
 * Jacobian; the family ends below at the grazing of (3.2) at the end of
 * slip, located to 1e-10, where the rk8pd reference shows the margin at
 * zero, with the overshoot orbit just above the located value and not just
 * below */
static void test_ur_family(void) {
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&PAPER, &start), 1);
  ss_cont_opts co;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_UR;
  co.lo = 0.3;
  co.hi = 1.5;
  co.max_points = 400;
  ss_branch b;
  ss_diag d;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, &d), SS_OK);
  ASSERT_TRUE(b.n_points > 10);
  double worst = 0;
  for (int i = 0; i < b.n_points; i++) {
    worst = fmax(worst, check_point(&PAPER, SS_PARAM_UR, &b, &b.points[i]));
    if (i > 0) /* in order along the family */
      ASSERT_TRUE(b.points[i].value > b.points[i - 1].value);
  }
  printf("ur family: %d points from ur = %.12g to %.12g, multipliers within "
         "%.2g of the finite-difference ones\n",
         b.n_points, b.points[0].value, b.points[b.n_points - 1].value, worst);
  ASSERT_TRUE(worst < 1e-6);
  ASSERT_TRUE(b.points[b.n_points - 1].value == 1.5);
  ASSERT_TRUE(strstr(b.end[1], "end of the range") != NULL);
  /* one special point: the grazing at the bottom */
  ASSERT_EQ_INT(b.n_special, 1);
  const ss_special *g = &b.special[0];
  ASSERT_EQ_INT((int)g->kind, (int)SS_SPECIAL_GRAZING);
  ASSERT_TRUE(g->margin == SS_MARGIN_SWITCHING);
  ASSERT_EQ_INT(g->at.min_margin.phase, 0);
  ASSERT_TRUE(g->precision <= 1e-10);
  ASSERT_TRUE(g->value == b.points[0].value);
  ASSERT_TRUE(strstr(b.end[0], "grazing at ur = ") != NULL);
  ASSERT_TRUE(strstr(g->detail, "at ur = ") != NULL);
  /* the rk8pd reference at the located value */
  ss_params at = PAPER;
  at.ur = g->value;
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &at, NULL), SS_OK);
  double mref = ref_switching_margin(&at, &g->at, m.d0);
  printf("ur family: grazing at ur = %.15g (precision %.2g), margin %.2g, "
         "rk8pd margin %.2g\n",
         g->value, g->precision, g->at.min_margin.value, mref);
  ASSERT_TRUE(fabs(mref) < 1e-9);
  ASSERT_TRUE(g->at.min_margin.value >= 0 && g->at.min_margin.value < 1e-9);
  /* the overshoot orbit solved just above the located value is feasible,
   * just below it is not */
  ss_orbit o;
  for (int side = -1; side <= 1; side += 2) {
    at.ur = g->value * (1 + side * 1e-7);
    ASSERT_EQ_INT(ss_model_init(&m, &at, NULL), SS_OK);
    int rc = ss_orbit_solve(&m, b.n_phases, b.modes, g->at.durations, NULL, &o,
                            NULL);
    ASSERT_EQ_INT(rc, side > 0 ? SS_OK : SS_INFEASIBLE);
  }
  ss_branch_free(&b);
}

/* EVIDENCE: docs/checked/families.md: the overshoot family in chi at ur = 12 us
 * loses and regains stability through two period doublings, each located
 * to 1e-10 where the finite-difference Jacobian of the simulated map has a
 * multiplier within 1e-6 of -1; the family ends at a grazing at both ends */
static void test_period_doubling(void) {
  ss_params p = PAPER;
  p.ur = 12 * p.us;
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&p, &start), 1);
  ASSERT_TRUE(!start.stab.marginal && start.stab.unit_margin > 1e-3);
  ss_cont_opts co;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_CHI;
  co.lo = 0.01;
  co.hi = 0.99;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&p, &start, &co, &b, NULL), SS_OK);
  double worst = 0;
  for (int i = 0; i < b.n_points; i++)
    worst = fmax(worst, check_point(&p, SS_PARAM_CHI, &b, &b.points[i]));
  ASSERT_TRUE(worst < 1e-6);
  int pd = 0, grazing = 0;
  for (int i = 0; i < b.n_special; i++) {
    const ss_special *s = &b.special[i];
    if (s->kind == SS_SPECIAL_GRAZING) {
      grazing++;
      continue;
    }
    ASSERT_EQ_INT((int)s->kind, (int)SS_SPECIAL_PERIOD_DOUBLING);
    ASSERT_TRUE(s->precision <= 1e-10);
    ASSERT_TRUE(s->stable_before != s->stable_after);
    /* independent: the finite-difference Jacobian of the simulated map */
    ss_params at = p;
    at.chi = s->value;
    ss_model m;
    ss_orbit o;
    ss_stab_opts so = {0, 1};
    ASSERT_EQ_INT(ss_model_init(&m, &at, NULL), SS_OK);
    ASSERT_EQ_INT(
        ss_orbit_solve(&m, b.n_phases, b.modes, s->at.durations, &so, &o, NULL),
        SS_OK);
    double re[2], im[2];
    eig2(o.stab.jac_fd, re, im);
    double off = fmin(fabs(re[0] + 1), fabs(re[1] + 1));
    printf("period doubling at chi = %.15g (precision %.2g): finite-difference "
           "multipliers %.12g, %.12g\n",
           s->value, s->precision, re[0], re[1]);
    ASSERT_TRUE(im[0] == 0 && off < 1e-6);
    /* there the verdict is marginal, and says how close */
    ASSERT_TRUE(o.stab.marginal);
    ASSERT_TRUE(o.stab.unit_margin == 1 - o.stab.spectral_radius);
    ASSERT_TRUE(fabs(o.stab.unit_margin) < 1e-8);
    pd++;
  }
  ASSERT_EQ_INT(pd, 2);
  ASSERT_EQ_INT(grazing, 2);
  /* the period-2 family born at the first period doubling (stable to
   * unstable as chi grows: on the unstable side, supercritical) */
  const ss_special *first = NULL;
  for (int i = 0; i < b.n_special && !first; i++)
    if (b.special[i].kind == SS_SPECIAL_PERIOD_DOUBLING)
      first = &b.special[i];
  ss_branch b2;
  ss_diag d;
  ss_diag_clear(&d);
  ASSERT_TRUE(first != NULL);
  if (first) {
    ASSERT_TRUE(first->stable_before && !first->stable_after);
    ASSERT_EQ_INT(ss_continue_period2(&p, &b, first, &co, &b2, &d), SS_OK);
    ASSERT_EQ_INT(b2.n_phases, 2 * b.n_phases);
    ASSERT_TRUE(b2.n_points >= 3);
    double worst2 = 0, lowest = INFINITY, t_low = 0;
    for (int i = 0; i < b2.n_points; i++) {
      const ss_cont_point *q = &b2.points[i];
      int h = b.n_phases;
      ASSERT_EQ_INT(q->n_turns, 2);
      ASSERT_TRUE(fabs(q->durations[0] - q->durations[h]) > 1e-6);
      ASSERT_TRUE(q->value > first->value);
      worst2 = fmax(worst2, check_point(&p, SS_PARAM_CHI, &b2, q));
      if (q->value < lowest) {
        lowest = q->value;
        t_low = q->period;
      }
    }
    printf("period-2 family from chi = %.12g: %d points up to chi = %.12g; "
           "nearest the doubling its period is %.9g (twice the period-1 "
           "orbit's there: %.9g); multipliers within %.2g of the "
           "finite-difference ones; ends: %s / %s\n",
           first->value, b2.n_points, b2.points[b2.n_points - 1].value, t_low,
           2 * first->at.period, worst2, b2.end[0], b2.end[1]);
    ASSERT_TRUE(worst2 < 1e-6);
    ASSERT_TRUE(fabs(t_low - 2 * first->at.period) < 1e-3);
    ASSERT_TRUE(strstr(b2.end[0], "half its period") != NULL);
    ss_branch_free(&b2);
    /* a grazing is no period doubling */
    ASSERT_EQ_INT(ss_continue_period2(&p, &b, &b.special[0], &co, &b2, NULL),
                  SS_EINVAL);
  }
  ss_branch_free(&b);
}

/* EVIDENCE: docs/checked/families.md: bad options are refused, never guessed */
static void test_bad_options(void) {
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&PAPER, &start), 1);
  ss_cont_opts co;
  ss_branch b;
  ss_diag d;
  ss_diag_clear(&d);
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_UR;
  co.lo = 0.7; /* the start's ur = 0.6178 is outside */
  co.hi = 1.0;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, &d), SS_EINVAL);
  ASSERT_TRUE(!strcmp(d.where, "range"));
  co.lo = 1.0;
  co.hi = 0.5;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, &d), SS_EINVAL);
  co.lo = 0.5;
  co.param = (ss_param_id)7;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, &d), SS_EINVAL);
  co.param = SS_PARAM_UR;
  co.direction = 2;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, &d), SS_EINVAL);
  co.direction = 0;
  /* a start that is not an orbit of these parameters */
  ss_params far = PAPER;
  far.ur = 0.5;
  co.lo = 0.3;
  ASSERT_TRUE(ss_continue(&far, &start, &co, &b, &d) != SS_OK);
  ASSERT_TRUE(b.n_points == 0 && b.points == NULL);
  ss_param_id id;
  ASSERT_EQ_INT(ss_param_by_name("V", &id), SS_OK);
  ASSERT_EQ_INT((int)id, (int)SS_PARAM_V);
  ASSERT_EQ_INT(ss_param_by_name("v", &id), SS_EINVAL);
}

/* EVIDENCE: docs/checked/families.md: the time budget stops a continuation with
 * what it found */
static int always(void *cls) {
  (void)cls;
  return 1;
}

static void test_budget(void) {
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&PAPER, &start), 1);
  ss_cont_opts co;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_UR;
  co.lo = 0.3;
  co.hi = 1.5;
  co.cancelled = always;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, NULL), SS_ECANCELED);
  ASSERT_EQ_INT(b.n_points, 1); /* the start */
  ss_branch_free(&b);
  co.cancelled = NULL;
  co.max_points = 5;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, NULL), SS_OK);
  ASSERT_TRUE(b.n_points <= 5);
  ASSERT_TRUE(strstr(b.end[1], "max_points") != NULL);
  ss_branch_free(&b);
}

/* EVIDENCE: docs/checked/families.md: the grazing that bounds the paper's
 * family followed in chi draws the boundary ur*(chi) of the overshoot orbit's
 * existence; at every point the orbit solved 1e-7 either side in ur exists
 * on one side only, and the rk8pd reference gives the switching margin at
 * zero */
static void test_grazing_curve(void) {
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&PAPER, &start), 1);
  ss_cont_opts co, o2;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_UR;
  co.lo = 0.3;
  co.hi = 1.5;
  co.direction = -1;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, NULL), SS_OK);
  ASSERT_EQ_INT(b.n_special, 1);
  memset(&o2, 0, sizeof o2);
  o2.param = SS_PARAM_CHI;
  o2.lo = 0.05;
  o2.hi = 0.6;
  o2.max_points = 400;
  ss_curve cv;
  ss_diag d;
  ss_diag_clear(&d);
  ASSERT_EQ_INT(ss_continue_grazing(&PAPER, &b, &b.special[0], &o2, &cv, &d),
                SS_OK);
  ASSERT_TRUE(cv.n_points > 20);
  ASSERT_TRUE(cv.points[cv.start].v2 == PAPER.chi);
  double worst = 0, lowest = INFINITY, at = 0;
  int sides = 0;
  for (int i = 0; i < cv.n_points; i++) {
    const ss_curve_point *q = &cv.points[i];
    ss_params p = PAPER;
    p.chi = q->v2;
    int ok[2];
    for (int s = 0; s < 2; s++) {
      ss_params ps = p;
      ss_model m;
      ss_orbit o;
      ps.ur = q->v1 * (1 + (s ? 1e-7 : -1e-7));
      ASSERT_EQ_INT(ss_model_init(&m, &ps, NULL), SS_OK);
      ok[s] = ss_orbit_solve(&m, b.n_phases, b.modes, q->durations, NULL, &o,
                             NULL) == SS_OK;
    }
    sides += ok[0] != ok[1] && ok[1] == (q->feasible_side > 0);
    if (i % 8 == 0 || i == cv.n_points - 1) {
      ss_model m;
      ss_cont_point pt;
      p.ur = q->v1;
      ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
      memcpy(pt.durations, q->durations, sizeof pt.durations);
      memcpy(pt.z0, q->z0, sizeof pt.z0);
      worst = fmax(worst, fabs(ref_switching_margin(&p, &pt, m.d0)));
    }
    if (q->v1 / PAPER.us < lowest) {
      lowest = q->v1 / PAPER.us;
      at = q->v2;
    }
  }
  printf("grazing curve in (chi, ur): %d points, chi from %.6g to %.6g; the "
         "orbit on one side only at %d; rk8pd margin at most %.2g; smallest "
         "ur/us %.6g at chi = %.6g\n",
         cv.n_points, cv.points[0].v2, cv.points[cv.n_points - 1].v2, sides,
         worst, lowest, at);
  ASSERT_EQ_INT(sides, cv.n_points);
  ASSERT_TRUE(worst < 1e-9);
  /* two methods, one boundary: where the curve crosses ur = 12 us, the
   * family in chi at ur = 12 us has its grazings */
  ss_params p12 = PAPER;
  p12.ur = 12 * PAPER.us;
  ss_orbit s12;
  ss_branch b12;
  ss_cont_opts c12;
  memset(&c12, 0, sizeof c12);
  c12.param = SS_PARAM_CHI;
  c12.lo = 0.01;
  c12.hi = 0.99;
  ASSERT_EQ_INT(overshoot_at(&p12, &s12), 1);
  ASSERT_EQ_INT(ss_continue(&p12, &s12, &c12, &b12, NULL), SS_OK);
  int crossings = 0;
  for (int i = 0; i + 1 < cv.n_points; i++) {
    const ss_curve_point *q0 = &cv.points[i], *q1 = &cv.points[i + 1];
    if ((q0->v1 < p12.ur) == (q1->v1 < p12.ur))
      continue;
    double chi = q0->v2 +
                 (p12.ur - q0->v1) / (q1->v1 - q0->v1) * (q1->v2 - q0->v2),
           best = INFINITY;
    for (int k = 0; k < b12.n_special; k++)
      if (b12.special[k].kind == SS_SPECIAL_GRAZING)
        best = fmin(best, fabs(b12.special[k].value - chi));
    printf("grazing curve crosses ur = 12 us at chi = %.6g (interpolated "
           "between points %.4g apart); the chi family's grazing is %.2g "
           "away\n",
           chi, fabs(q1->v2 - q0->v2), best);
    ASSERT_TRUE(best < 0.2 * fabs(q1->v2 - q0->v2) + 1e-6);
    crossings++;
  }
  ASSERT_EQ_INT(crossings, 2);
  ss_branch_free(&b12);
  ss_curve_free(&cv);
  /* only a switching grazing can be followed */
  ss_special other = b.special[0];
  other.kind = SS_SPECIAL_PERIOD_DOUBLING;
  ASSERT_EQ_INT(ss_continue_grazing(&PAPER, &b, &other, &o2, &cv, NULL),
                SS_EINVAL);
  o2.param = SS_PARAM_UR; /* the same parameter twice */
  ASSERT_EQ_INT(ss_continue_grazing(&PAPER, &b, &b.special[0], &o2, &cv, NULL),
                SS_EINVAL);
  ss_branch_free(&b);
}

/* EVIDENCE: docs/checked/families.md: beyond the grazing that ends a family the
 * motion settles, by simulation, on a periodic attractor, which the rk8pd
 * reference closes over its period through the same number of phases */
static void check_beyond(const ss_params *p, ss_param_id id, double lo,
                         double hi) {
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(p, &start), 1);
  ss_cont_opts co;
  memset(&co, 0, sizeof co);
  co.param = id;
  co.lo = lo;
  co.hi = hi;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(p, &start, &co, &b, NULL), SS_OK);
  for (int i = 0; i < b.n_special; i++) {
    const ss_special *g = &b.special[i];
    if (g->kind != SS_SPECIAL_GRAZING)
      continue;
    double v;
    ss_attractor a;
    ASSERT_EQ_INT(ss_beyond_grazing(p, &b, g, &v, &a), SS_OK);
    ASSERT_TRUE(a.found);
    /* on the side where the family does not exist */
    ASSERT_TRUE((v - g->value) * (b.points[b.start].value - g->value) < 0);
    ss_params q = *p;
    *param(&q, id) = v;
    ss_model m;
    ASSERT_EQ_INT(ss_model_init(&m, &q, NULL), SS_OK);
    double x[4] = {a.s[0] + m.d0[0], a.s[0] + (q.ur - q.us) / q.chi + m.d0[1],
                   a.s[1], q.V};
    ref_params rp = {q.chi, q.eta, q.us, q.ur, q.V};
    ref_opts ro = {gsl_odeiv2_step_rk8pd, 1e-13, 1e-13, 0, 1e-13};
    ref_event ev[256];
    double xe[4], err = 0;
    int me;
    long ne = ref_simulate(&rp, 0, x, REF_SLIP, a.period * (1 - 1e-9), &ro, ev,
                           256, xe, &me);
    for (int k = 0; k < 4; k++)
      err = fmax(err, fabs(xe[k] - x[k]));
    printf("beyond the grazing at %s = %.12g (at %.12g): an attractor of %d "
           "returns, period %.9g, %d phases (%d overshoots) after %d "
           "returns; rk8pd closes it to %.2g through %ld events\n",
           ss_param_name(id), g->value, v, a.n_turns, a.period, a.n_phases,
           a.n_overshoot, a.turns_run, err, ne);
    ASSERT_TRUE(err < 1e-6);
    /* the last event is the return itself, at the period's end */
    ASSERT_TRUE(ne == a.n_phases || ne == a.n_phases - 1);
    /* the family ends here: the adjacent sequence (a stick inserted where
     * the switching margin vanished) has no orbit past the boundary, and
     * the search finds no orbit of the family's kind there either */
    ss_branch adj;
    ss_diag d;
    ss_diag_clear(&d);
    ASSERT_EQ_INT(ss_continue_adjacent(p, &b, g, &co, &adj, &d), SS_INFEASIBLE);
    /* d records the status returned */
    ASSERT_EQ_INT(d.status, SS_INFEASIBLE);
    ASSERT_EQ_INT(adj.n_phases, b.n_phases + 1);
    ASSERT_EQ_INT((int)adj.modes[g->at.min_margin.phase + 1],
                  (int)SS_MODE_STICK);
    ss_branch_free(&adj);
    ASSERT_EQ_INT(overshoot_at(&q, &start), 0);
  }
  ss_branch_free(&b);
}

static void test_beyond(void) {
  check_beyond(&PAPER, SS_PARAM_UR, 0.3, 1.5);
  ss_params p = PAPER;
  p.ur = 12 * p.us;
  check_beyond(&p, SS_PARAM_CHI, 0.01, 0.99);
}

/* EVIDENCE: docs/checked/families.md: the paper's family continued in us loses
 * its stability at a Neimark-Sacker point, where the finite-difference
 * Jacobian of the simulated map has a complex pair on the unit circle */
static void test_neimark_sacker(void) {
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&PAPER, &start), 1);
  ss_cont_opts co;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_US;
  co.lo = 0.001;
  co.hi = 0.6;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&PAPER, &start, &co, &b, NULL), SS_OK);
  int ns = 0;
  for (int i = 0; i < b.n_special; i++) {
    const ss_special *s = &b.special[i];
    if (s->kind != SS_SPECIAL_NEIMARK_SACKER)
      continue;
    ss_params at = PAPER;
    at.us = s->value;
    ss_model m;
    ss_orbit o;
    ss_stab_opts so = {0, 1};
    ASSERT_EQ_INT(ss_model_init(&m, &at, NULL), SS_OK);
    ASSERT_EQ_INT(
        ss_orbit_solve(&m, b.n_phases, b.modes, s->at.durations, &so, &o, NULL),
        SS_OK);
    double re[2], im[2];
    eig2(o.stab.jac_fd, re, im);
    double mod = hypot(re[0], im[0]);
    printf("Neimark-Sacker at us = %.15g (precision %.2g): finite-difference "
           "multipliers %.9g +- %.9gi, modulus %.12g\n",
           s->value, s->precision, re[0], im[0], mod);
    ASSERT_TRUE(im[0] != 0 && fabs(mod - 1) < 1e-6);
    ASSERT_TRUE(s->precision <= 1e-10);
    /* unstable below the point, stable above (in increasing us), whichever
     * way the family was followed to it */
    ASSERT_TRUE(!s->stable_before && s->stable_after);
    ASSERT_TRUE(strstr(s->detail, "unstable below, stable above") != NULL);
    ns++;
  }
  ASSERT_EQ_INT(ns, 1);
  ss_branch_free(&b);
}

/* EVIDENCE: docs/checked/families.md: a family followed around a fold comes
 * back: the stick-slip family at ur = 12 us turns back in chi at a saddle-node,
 * where the finite-difference Jacobian of the simulated map has a
 * multiplier of +1, and the orbit changes continuously through the turn */
static void test_fold(void) {
  ss_params p = PAPER;
  p.ur = 12 * p.us;
  p.chi = 0.5;
  ss_model m;
  ss_orbit_opts oo;
  ss_orbit found[16], *start = NULL;
  int n = 0;
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_STICKSLIP;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, found, 16, &n, NULL, NULL), SS_OK);
  for (int i = 0; i < n; i++)
    if (fabs(found[i].period - 12.569) < 0.01)
      start = &found[i];
  ASSERT_TRUE(start != NULL);
  if (!start)
    return;
  ss_cont_opts co;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_CHI;
  co.lo = 0.01;
  co.hi = 0.99;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&p, start, &co, &b, NULL), SS_OK);
  const ss_special *fold = NULL, *sn = NULL;
  for (int i = 0; i < b.n_special; i++) {
    if (b.special[i].kind == SS_SPECIAL_FOLD)
      fold = &b.special[i];
    if (b.special[i].kind == SS_SPECIAL_SADDLE_NODE)
      sn = &b.special[i];
  }
  /* one special point: the fold, which says it is a saddle-node */
  ASSERT_TRUE(fold != NULL && sn == NULL);
  if (!fold)
    return;
  ASSERT_TRUE(strstr(fold->detail, "saddle-node") != NULL);
  sn = fold;
  /* the parameter turns: it falls to the fold along the family and rises
   * after it, and the durations move by small steps throughout */
  int turns = 0;
  double jump = 0, least = INFINITY;
  for (int i = 1; i < b.n_points; i++) {
    const ss_cont_point *a = &b.points[i - 1], *c = &b.points[i];
    for (int k = 0; k < b.n_phases; k++)
      jump = fmax(jump, fabs(c->durations[k] - a->durations[k]) / a->period);
    if (i + 1 < b.n_points &&
        (c->value - a->value) * (b.points[i + 1].value - c->value) < 0)
      turns++;
    least = fmin(least, c->value);
  }
  ss_params at = p;
  ss_orbit o;
  ss_stab_opts so = {0, 1};
  at.chi = sn->value;
  ASSERT_EQ_INT(ss_model_init(&m, &at, NULL), SS_OK);
  ASSERT_EQ_INT(
      ss_orbit_solve(&m, b.n_phases, b.modes, sn->at.durations, &so, &o, NULL),
      SS_OK);
  double re[2], im[2];
  eig2(o.stab.jac_fd, re, im);
  double off = fmin(fabs(re[0] - 1), fabs(re[1] - 1));
  printf("fold of the stick-slip family at chi = %.12g (saddle-node at "
         "%.12g): %d turn of the parameter, lowest chi on the family %.12g, "
         "largest step in a duration %.3g of the period; finite-difference "
         "multipliers %.9g, %.9g\n",
         fold->value, sn->value, turns, least, jump, re[0], re[1]);
  ASSERT_EQ_INT(turns, 1);
  ASSERT_TRUE(fabs(fold->value - sn->value) < 1e-8);
  ASSERT_TRUE(least >= fold->value - 1e-12);
  ASSERT_TRUE(jump < 0.05);
  ASSERT_TRUE(im[0] == 0 && off < 1e-6);
  ss_branch_free(&b);
}

/* EVIDENCE: docs/checked/families.md: a real multiplier crosses +1 where the
 * family does not turn (the stick-slip family of period 30.6 continued as
 * /continue does, through ss_continue_study): the saddle-node is located to
 * 1e-10 where the finite-difference Jacobian of the simulated map has a real
 * multiplier 1, not left at an orbit of complex multipliers (before: eta =
 * 0.32313454920, multipliers 0.98785 +- 0.09338i, "not located"), in
 * eta at the value an independent solver gives, 0.3235446; likewise in chi
 * (before: 5.4e-5 off, "not located") */
static void test_saddle_node_without_fold(void) {
  const ss_params p = {0.5668, 0.3432, 0.2466, 3.1875, 1};
  const struct {
    ss_param_id id;
    double lo, hi, near, tol;
  } cases[] = {{SS_PARAM_ETA, 0.05, 3, 0.3235446, 1e-6},
               {SS_PARAM_CHI, 0.01, 0.99, NAN, 0}};
  ss_orbit start;
  memset(&start, 0, sizeof start);
  start.n_phases = 2;
  start.modes[0] = SS_MODE_SLIP;
  start.modes[1] = SS_MODE_STICK;
  start.durations[0] = 14.77787;
  start.durations[1] = 15.85481;
  for (int c = 0; c < 2; c++) {
    ss_study_opts so;
    ss_study st;
    memset(&so, 0, sizeof so);
    so.family.param = cases[c].id;
    so.family.lo = cases[c].lo;
    so.family.hi = cases[c].hi;
    ASSERT_EQ_INT(ss_continue_study(&p, &start, &so, &st, NULL), SS_OK);
    const ss_special *sn = NULL;
    int n_sn = 0;
    for (int i = 0; i < st.family.n_special; i++)
      if (st.family.special[i].kind == SS_SPECIAL_SADDLE_NODE) {
        sn = &st.family.special[i];
        n_sn++;
      }
    ASSERT_EQ_INT(n_sn, 1);
    if (!sn) {
      ss_study_free(&st);
      continue;
    }
    ss_params at = p;
    *param(&at, cases[c].id) = sn->value;
    ss_model m;
    ss_stab_opts fo = {sn->at.n_turns, 1};
    ss_stab fd;
    ASSERT_EQ_INT(ss_model_init(&m, &at, NULL), SS_OK);
    ASSERT_EQ_INT(ss_stability(&m, st.family.n_phases, st.family.modes,
                               sn->at.durations, sn->at.z0, &fo, &fd),
                  SS_OK);
    /* det(I - J) of the finite-difference Jacobian: with two multipliers
     * near 1 each is sensitive to the differences' error, their product
     * with the other's distance from 1 much less */
    const double(*J)[2] = fd.jac_fd;
    double re[2], im[2],
        psi = (1 - J[0][0]) * (1 - J[1][1]) - J[0][1] * J[1][0];
    eig2(fd.jac_fd, re, im);
    double off_an =
        fmin(fabs(sn->at.eig_re[0] - 1), fabs(sn->at.eig_re[1] - 1));
    printf("saddle-node without a fold in %s at %.12g (precision %.2g): "
           "multipliers %.12g, %.12g (finite differences %.9g, %.9g, "
           "det(I - J) %.2g)\n",
           ss_param_name(cases[c].id), sn->value, sn->precision,
           sn->at.eig_re[0], sn->at.eig_re[1], re[0], re[1], psi);
    ASSERT_TRUE(sn->precision <= 1e-10);
    ASSERT_TRUE(strstr(sn->detail, "not located") == NULL);
    if (!isnan(cases[c].near))
      ASSERT_NEAR(sn->value, cases[c].near, cases[c].tol);
    ASSERT_TRUE(sn->at.eig_im[0] == 0 && off_an < 1e-7);
    ASSERT_TRUE(im[0] == 0 && fabs(psi) < 5e-8);
    ss_study_free(&st);
  }
}

/* EVIDENCE: docs/checked/families.md: a period doubling followed in a second
 * parameter: at every point of the curve the orbit is feasible and the
 * finite-difference Jacobian of the simulated map has a multiplier -1 */
static void test_period_doubling_curve(void) {
  ss_params p = PAPER;
  p.ur = 12 * p.us;
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&p, &start), 1);
  ss_cont_opts co, o2;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_CHI;
  co.lo = 0.01;
  co.hi = 0.99;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&p, &start, &co, &b, NULL), SS_OK);
  memset(&o2, 0, sizeof o2);
  o2.param = SS_PARAM_UR;
  o2.lo = 0.3;
  o2.hi = 2.0;
  o2.max_points = 400;
  int curves = 0;
  for (int i = 0; i < b.n_special; i++) {
    const ss_special *pd = &b.special[i];
    if (pd->kind != SS_SPECIAL_PERIOD_DOUBLING)
      continue;
    ss_curve cv;
    ASSERT_EQ_INT(ss_continue_period_doubling(&p, &b, pd, &o2, &cv, NULL),
                  SS_OK);
    ASSERT_TRUE(cv.n_points > 10);
    double worst = 0;
    int near = 0;
    for (int k = 0; k < cv.n_points; k++) {
      ss_params q = p;
      ss_model m;
      ss_orbit o;
      ss_stab_opts so = {0, 1};
      q.chi = cv.points[k].v1;
      q.ur = cv.points[k].v2;
      ASSERT_EQ_INT(ss_model_init(&m, &q, NULL), SS_OK);
      ASSERT_EQ_INT(ss_orbit_solve(&m, b.n_phases, b.modes,
                                   cv.points[k].durations, &so, &o, NULL),
                    SS_OK);
      if (o.min_margin.value < 1e-5) { /* no differences across a boundary */
        near++;
        continue;
      }
      double re[2], im[2];
      eig2(o.stab.jac_fd, re, im);
      worst = fmax(worst, im[0] != 0 ? INFINITY
                                     : fmin(fabs(re[0] + 1), fabs(re[1] + 1)));
    }
    printf("period doubling at chi = %.9g followed in ur: %d points from "
           "ur = %.6g to %.6g, finite-difference multiplier -1 within %.2g "
           "(%d points next to a grazing not compared); ends: %s | %s\n",
           pd->value, cv.n_points, cv.points[0].v2,
           cv.points[cv.n_points - 1].v2, worst, near, cv.end[0], cv.end[1]);
    ASSERT_TRUE(worst < 1e-6);
    ASSERT_TRUE(cv.n_points - near >= 20);
    ss_curve_free(&cv);
    curves++;
  }
  ASSERT_EQ_INT(curves, 2);
  ss_branch_free(&b);
}

/* EVIDENCE: docs/checked/families.md: continuation in a physical parameter; Fr
 * is ur (k1 + k2), so the paper's boundary in Fr is ten times the one in ur; a
 * family in m1 (which moves eta, V and the time scale together) closes by
 * simulation at every point */
static void test_physical(void) {
  ss_physical ph = {2.5, 0.625, 8, 2, 0.724, 6.178, 2};
  ss_params p;
  double omega;
  ASSERT_EQ_INT(ss_params_from_physical(&ph, &p, &omega, NULL), SS_OK);
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&p, &start), 1);
  ss_cont_opts co;
  memset(&co, 0, sizeof co);
  co.physical = &ph;
  co.phys = SS_PHYS_FR;
  co.lo = 3;
  co.hi = 15;
  co.direction = -1;
  ss_branch b, bu;
  /* bad physical parameters: SS_EINVAL, and d records that status with
   * the value at fault */
  ss_physical bad = ph;
  bad.m2 = -1;
  co.physical = &bad;
  ss_diag d;
  ss_diag_clear(&d);
  ASSERT_EQ_INT(ss_continue(&p, &start, &co, &b, &d), SS_EINVAL);
  ASSERT_EQ_INT(d.status, SS_EINVAL);
  ASSERT_TRUE(d.text[0] != 0);
  ss_branch_free(&b);
  co.physical = &ph;
  ASSERT_EQ_INT(ss_continue(&p, &start, &co, &b, NULL), SS_OK);
  ASSERT_EQ_INT(b.n_special, 1);
  co.physical = NULL;
  co.param = SS_PARAM_UR;
  co.lo = 0.3;
  co.hi = 1.5;
  ASSERT_EQ_INT(ss_continue(&p, &start, &co, &bu, NULL), SS_OK);
  double rel =
      fabs(b.special[0].value / 10 - bu.special[0].value) / bu.special[0].value;
  printf("in Fr the boundary is at %.12g, ten times the one in ur (%.12g) "
         "to %.2g\n",
         b.special[0].value, bu.special[0].value, rel);
  ASSERT_TRUE(rel < 1e-9);
  ASSERT_TRUE(strstr(b.end[0], "grazing at Fr = ") != NULL);
  ss_branch_free(&b);
  ss_branch_free(&bu);
  /* m1 over [1, 6] */
  co.physical = &ph;
  co.phys = SS_PHYS_M1;
  co.lo = 1;
  co.hi = 6;
  co.direction = 0;
  ASSERT_EQ_INT(ss_continue(&p, &start, &co, &b, NULL), SS_OK);
  ASSERT_TRUE(b.n_points > 5);
  for (int i = 0; i < b.n_points; i++) {
    ss_physical q = ph;
    ss_params pq;
    ss_model m;
    ss_orbit o;
    q.m1 = b.points[i].value;
    ASSERT_EQ_INT(ss_params_from_physical(&q, &pq, NULL, NULL), SS_OK);
    ASSERT_EQ_INT(ss_model_init(&m, &pq, NULL), SS_OK);
    memset(&o, 0, sizeof o);
    o.n_phases = b.n_phases;
    memcpy(o.modes, b.modes, sizeof o.modes);
    memcpy(o.durations, b.points[i].durations, sizeof o.durations);
    memcpy(o.z0, b.points[i].z0, sizeof o.z0);
    ASSERT_EQ_INT(ss_orbit_check(&m, &o, NULL), SS_OK);
    ASSERT_TRUE(o.closure < 1e-12);
  }
  printf("in m1: %d points from m1 = %.9g to %.9g; %s / %s\n", b.n_points,
         b.points[0].value, b.points[b.n_points - 1].value, b.end[0], b.end[1]);
  ss_branch_free(&b);
}

/* The largest chi (x2 - x1) - ur inside phase k of the orbit (modes, tau,
 * x0) by the rk8pd reference: each phase integrated from its start, the
 * maximum by golden-section search on the time in phase k. */
static double ref_interior_max(const ss_params *p, const ss_mode *modes,
                               const double *tau, const double x0[4], int k) {
  ref_params rp = {p->chi, p->eta, p->us, p->ur, p->V};
  ref_opts ro = {gsl_odeiv2_step_rk8pd, 1e-13, 1e-13, 0, 1e-13};
  double x[4];
  memcpy(x, x0, sizeof x);
  for (int j = 0; j < k; j++) {
    ref_flow(&rp, (int)modes[j], tau[j], x, &ro);
    if (modes[j] == SS_MODE_STICK ||
        (j + 1 < k + 1 && modes[j + 1] == SS_MODE_STICK))
      x[3] = p->V; /* a stick starts at the belt's speed */
  }
  double a = 0, b = tau[k], g = (sqrt(5) - 1) / 2, best = -INFINITY;
  for (int it = 0; it < 80; it++) {
    double t1 = b - g * (b - a), t2 = a + g * (b - a), f[2];
    double ts[2] = {t1, t2};
    for (int s = 0; s < 2; s++) {
      double xs[4];
      memcpy(xs, x, sizeof xs);
      ref_flow(&rp, (int)modes[k], ts[s], xs, &ro);
      f[s] = p->chi * (xs[1] - xs[0]) - p->ur;
    }
    if (f[0] > f[1])
      b = t2;
    else
      a = t1;
    best = fmax(best, fmax(f[0], f[1]));
  }
  return best;
}

/* EVIDENCE: docs/checked/families.md: a grazing inside a phase (the stick force
 * touching ur in the middle of a stick) followed in a second parameter:
 * at every point the orbit exists on one side only in the first, and the
 * rk8pd reference puts the stick force's maximum on ur */
static void test_interior_grazing_curve(void) {
  ss_params p = PAPER;
  p.ur = 12 * p.us;
  p.chi = 0.5;
  ss_model m;
  ss_orbit_opts oo;
  ss_orbit found[16], *start = NULL;
  int n = 0;
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_STICKSLIP;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, found, 16, &n, NULL, NULL), SS_OK);
  for (int i = 0; i < n; i++)
    if (fabs(found[i].period - 12.569) < 0.01)
      start = &found[i];
  ASSERT_TRUE(start != NULL);
  if (!start)
    return;
  ss_cont_opts co, o2;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_CHI;
  co.lo = 0.01;
  co.hi = 0.99;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&p, start, &co, &b, NULL), SS_OK);
  memset(&o2, 0, sizeof o2);
  o2.param = SS_PARAM_UR;
  o2.lo = 0.3;
  o2.hi = 2;
  o2.max_points = 300;
  int curves = 0;
  for (int i = 0; i < b.n_special; i++) {
    const ss_special *g = &b.special[i];
    if (g->kind != SS_SPECIAL_GRAZING || g->margin != SS_MARGIN_STICK_BELOW_UR)
      continue;
    ss_curve cv;
    ASSERT_EQ_INT(ss_continue_grazing(&p, &b, g, &o2, &cv, NULL), SS_OK);
    ASSERT_TRUE(cv.n_points > 20);
    if (cv.n_points == 0)
      continue;
    int sides = 0;
    double worst = 0;
    for (int k = 0; k < cv.n_points; k++) {
      const ss_curve_point *q = &cv.points[k];
      ss_params at = p;
      at.chi = q->v1;
      at.ur = q->v2;
      int ok[2];
      for (int s = 0; s < 2; s++) {
        ss_params ps = at;
        ss_orbit o;
        ps.chi = q->v1 * (1 + (s ? 1e-7 : -1e-7));
        ASSERT_EQ_INT(ss_model_init(&m, &ps, NULL), SS_OK);
        ok[s] = ss_orbit_solve(&m, b.n_phases, b.modes, q->durations, NULL, &o,
                               NULL) == SS_OK;
      }
      sides += ok[0] != ok[1] && ok[1] == (q->feasible_side > 0);
      if (k % 10 == 0) {
        double x0[4];
        ASSERT_EQ_INT(ss_model_init(&m, &at, NULL), SS_OK);
        ss_z_to_x(&m, q->z0, x0);
        worst = fmax(worst, fabs(ref_interior_max(&at, b.modes, q->durations,
                                                  x0, g->at.min_margin.phase)));
      }
    }
    printf("the stick grazing at chi = %.9g followed in ur: %d points from "
           "(chi, ur) = (%.6g, %.6g) to (%.6g, %.6g); one side only at %d; "
           "rk8pd maximum of the stick force within %.2g of ur\n",
           g->value, cv.n_points, cv.points[0].v1, cv.points[0].v2,
           cv.points[cv.n_points - 1].v1, cv.points[cv.n_points - 1].v2, sides,
           worst);
    ASSERT_EQ_INT(sides, cv.n_points);
    ASSERT_TRUE(worst < 1e-8);
    ss_curve_free(&cv);
    curves++;
  }
  ASSERT_EQ_INT(curves, 2);
  ss_branch_free(&b);
}

/* The slope of |chi (x2 - x1)| at the end of the stick phase k of the
 * orbit (modes, tau, x0) by the rk8pd reference: the phases integrated
 * from their starts, the slope by central differences at the end (h 1e-4:
 * an error of about h^2 / 6 times the third derivative, 1e-9 here). */
static double ref_stick_end_slope(const ss_params *p, const ss_mode *modes,
                                  const double *tau, const double x0[4],
                                  int k) {
  ref_params rp = {p->chi, p->eta, p->us, p->ur, p->V};
  ref_opts ro = {gsl_odeiv2_step_rk8pd, 1e-13, 1e-13, 0, 1e-13};
  double x[4], h = 1e-4, f[2];
  memcpy(x, x0, sizeof x);
  for (int j = 0; j < k; j++) {
    ref_flow(&rp, (int)modes[j], tau[j], x, &ro);
    if (j + 1 == k && modes[k] == SS_MODE_STICK)
      x[3] = p->V; /* a stick starts at the belt's speed */
  }
  for (int s = 0; s < 2; s++) {
    double xs[4];
    memcpy(xs, x, sizeof xs);
    ref_flow(&rp, (int)modes[k], tau[k] + (s ? h : -h), xs, &ro);
    f[s] = p->chi * (xs[1] - xs[0]);
  }
  double slope = (f[1] - f[0]) / (2 * h);
  return f[1] + f[0] < 0 ? -slope : slope;
}

/* The side of ur on which the orbit with durations tau exists near
 * (ur, chi): the smallest relative offset of 1e-5, 1e-4, 1e-3 at which it
 * solves on one side only, +1 (above) or -1; 0 if none. */
static int tangency_side(const ss_params *p, int n, const ss_mode *modes,
                         const double *tau) {
  for (double off = 1e-5; off < 2e-3; off *= 10) {
    int ok[2];
    for (int s = 0; s < 2; s++) {
      ss_params ps = *p;
      ss_model m;
      ss_orbit o;
      ps.ur = p->ur * (1 + (s ? off : -off));
      ok[s] = ss_model_init(&m, &ps, NULL) == SS_OK &&
              ss_orbit_solve(&m, n, modes, tau, NULL, &o, NULL) == SS_OK;
    }
    if (ok[0] != ok[1])
      return ok[1] ? 1 : -1;
    if (ok[0])
      return 0;
  }
  return 0;
}

/* The slip-stick family of period in [pmin, pmax] at p, continued in ur
 * over [0.3, 3] ur, ends where its stick ends tangentially: located at the
 * zero of the end slope, with the attractor past it; followed in chi over
 * [chi_lo, chi_hi], every point on the boundary (one side only) with a
 * zero end slope by the rk8pd reference.  The curve's points. */
static int tangency_case(const ss_params *p, double pmin, double pmax,
                         double chi_lo, double chi_hi, int attractor,
                         ss_curve *cv) {
  ss_model m;
  ss_orbit_opts oo;
  ss_orbit found[16], *start = NULL;
  int n = 0;
  memset(cv, 0, sizeof *cv);
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_STICKSLIP;
  ASSERT_EQ_INT(ss_model_init(&m, p, NULL), SS_OK);
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, found, 16, &n, NULL, NULL), SS_OK);
  for (int i = 0; i < n; i++)
    if (found[i].n_phases == 2 && found[i].period > pmin &&
        found[i].period < pmax)
      start = &found[i];
  ASSERT_TRUE(start != NULL);
  if (!start)
    return 0;
  ss_cont_opts co, o2;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_UR;
  co.lo = 0.3 * p->ur;
  co.hi = 3 * p->ur;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(p, start, &co, &b, NULL), SS_OK);
  const ss_special *g = NULL;
  for (int i = 0; i < b.n_special; i++)
    if (b.special[i].kind == SS_SPECIAL_GRAZING &&
        b.special[i].margin == SS_MARGIN_TRANSVERSALITY)
      g = &b.special[i];
  ASSERT_TRUE(g != NULL);
  if (!g) {
    ss_branch_free(&b);
    return 0;
  }
  int k = g->at.min_margin.phase;
  ASSERT_EQ_INT(b.modes[k], SS_MODE_STICK);
  ASSERT_TRUE(g->precision <= 1e-12);
  /* the located value: one side only */
  ss_params pg = *p;
  pg.ur = g->value;
  int side1 = tangency_side(&pg, b.n_phases, b.modes, g->at.durations);
  ASSERT_TRUE(side1 != 0);
  /* just beyond it, where the early crossing is within the check's slack
   * in time, the end slope's sign rejects the orbit: none is accepted
   * from 3e-8 to 3e-6 past it */
  int accepted = 0, by_slope = 0;
  for (double e = -7.5; e <= -5.5; e += 0.1) {
    ss_params ps = *p;
    ss_orbit o;
    ps.ur = g->value * (1 - side1 * pow(10, e));
    ASSERT_EQ_INT(ss_model_init(&m, &ps, NULL), SS_OK);
    accepted += ss_orbit_solve(&m, b.n_phases, b.modes, g->at.durations, NULL,
                               &o, NULL) == SS_OK;
    by_slope += o.violation_id == SS_MARGIN_TRANSVERSALITY;
  }
  ASSERT_EQ_INT(accepted, 0);
  /* past it, what the motion does (where asked: an attractor of its own) */
  double past;
  ss_attractor att;
  ASSERT_EQ_INT(ss_beyond_grazing(p, &b, g, &past, &att), SS_OK);
  ASSERT_TRUE(!attractor || att.found || att.perpetual_slip);
  memset(&o2, 0, sizeof o2);
  o2.param = SS_PARAM_CHI;
  o2.lo = chi_lo;
  o2.hi = chi_hi;
  o2.max_points = 400;
  ASSERT_EQ_INT(ss_continue_grazing(p, &b, g, &o2, cv, NULL), SS_OK);
  ASSERT_TRUE(cv->n_points > 20);
  ASSERT_TRUE(cv->margin == SS_MARGIN_TRANSVERSALITY);
  int sides = 0;
  double worst = 0, located = NAN;
  for (int j = 0; j < cv->n_points; j++) {
    const ss_curve_point *q = &cv->points[j];
    ss_params at = *p;
    at.ur = q->v1;
    at.chi = q->v2;
    int side = tangency_side(&at, b.n_phases, b.modes, q->durations);
    sides += side != 0 && side == q->feasible_side;
    if (j % 10 == 0 || j == cv->start) {
      double x0[4];
      ASSERT_EQ_INT(ss_model_init(&m, &at, NULL), SS_OK);
      ss_z_to_x(&m, q->z0, x0);
      double sl = ref_stick_end_slope(&at, b.modes, q->durations, x0, k);
      worst = fmax(worst, fabs(sl));
      if (j == cv->start)
        located = fabs(q->v1 - g->value) / g->value;
    }
  }
  printf("the stick's tangential end at ur = %.12g (precision %.1e, %.1e "
         "past the last feasible point; %d of 21 orbits just past it "
         "rejected by their end slope; past it an attractor of %d turns, "
         "period %.6g) followed in chi: %d points from (ur, chi) = (%.6g, "
         "%.6g) to (%.6g, %.6g); one side only at %d; rk8pd end slope "
         "within %.2g of zero; the curve's start %.1e from the located "
         "value\n",
         g->value, g->precision, fabs(g->value - g->at.value) / g->value,
         by_slope, att.n_turns, att.period, cv->n_points, cv->points[0].v1,
         cv->points[0].v2, cv->points[cv->n_points - 1].v1,
         cv->points[cv->n_points - 1].v2, sides, worst, located);
  ASSERT_EQ_INT(sides, cv->n_points);
  ASSERT_TRUE(worst < 1e-8);
  ASSERT_TRUE(located < 1e-10);
  ss_branch_free(&b);
  return by_slope;
}

/* EVIDENCE: docs/checked/families.md: a phase that ends tangentially (the stick
 * force reaching ur at its maximum, at the stick's end) is located at the
 * zero of the end slope and followed in a second parameter; the rk8pd
 * reference gives a zero slope there, and at every point of the curve the
 * orbit exists on one side only (at 1e-5, or 1e-4 or 1e-3 where the band
 * in which a crossing cannot be told from a touch is wider) */
static void test_transversality_curve(void) {
  const ss_params p = {0.45718539037873918, 0.957262457729113,
                       0.25138758401573669, 3.9803720170071393, 1};
  ss_curve cv;
  /* the band is narrow here (1.3e-7): the check's slack decides just
   * past the tangency, where the end slope's sign must reject */
  int by_slope = tangency_case(&p, 5, 6, 0.01, 0.99, 1, &cv);
  ASSERT_TRUE(by_slope >= 3);
  /* the boundary runs across the whole range of chi */
  ASSERT_TRUE(cv.n_points > 0 && cv.points[0].v2 == 0.01 &&
              cv.points[cv.n_points - 1].v2 == 0.99);
  ss_curve_free(&cv);
  /* at small chi the band is wide (6.3e-5), the sides are told at 1e-4 */
  ss_params q = p;
  q.chi = 0.01;
  q.eta = 0.3;
  q.us = 1;
  tangency_case(&q, 6, 7, 0.005, 0.05, 0, &cv);
  ASSERT_TRUE(cv.n_points > 0 && cv.points[cv.n_points - 1].v2 > 0.04);
  ss_curve_free(&cv);
  /* a family that ends with a slope as its smallest margin but no tangency
   * (its orbits solve on both sides; the chord spans a jump of the
   * corrector): said not located, and not followed */
  q.chi = 0.1;
  q.us = 0.05;
  ss_model m;
  ss_orbit_opts oo;
  ss_orbit found[16];
  int n = 0, seen = 0;
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_STICKSLIP;
  ASSERT_EQ_INT(ss_model_init(&m, &q, NULL), SS_OK);
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, found, 16, &n, NULL, NULL), SS_OK);
  for (int i = 0; i < n; i++) {
    if (found[i].n_phases != 2 || !(found[i].period > 60))
      continue;
    ss_cont_opts co, o2;
    memset(&co, 0, sizeof co);
    co.param = SS_PARAM_UR;
    co.lo = 0.3 * q.ur;
    co.hi = 3 * q.ur;
    ss_branch b;
    ASSERT_EQ_INT(ss_continue(&q, &found[i], &co, &b, NULL), SS_OK);
    for (int k = 0; k < b.n_special; k++) {
      const ss_special *g = &b.special[k];
      if (g->kind != SS_SPECIAL_GRAZING ||
          g->margin != SS_MARGIN_TRANSVERSALITY)
        continue;
      seen++;
      ASSERT_TRUE(g->at.min_margin.value > 0.05);
      ASSERT_TRUE(strstr(g->detail, "not located") != NULL);
      memset(&o2, 0, sizeof o2);
      o2.param = SS_PARAM_CHI;
      o2.lo = 0.05;
      o2.hi = 0.2;
      ASSERT_TRUE(ss_continue_grazing(&q, &b, g, &o2, &cv, NULL) != SS_OK);
      ss_curve_free(&cv);
    }
    ss_branch_free(&b);
  }
  ASSERT_EQ_INT(seen, 1);
}

/* EVIDENCE: docs/checked/families.md: a phase that ends tangentially: orbits
 * whose stick ends with a slope too small for the event finder to tell
 * the crossing from a touch by the values (the band, 3e-7 to 1e-8 below
 * the end here) are accepted by the slope, judged against its own rounding
 * bound: the family (the README's, at its rounded parameters) is feasible
 * to within 1e-9 of its end at ur = 4.407438357428859 (the value an
 * independent solver gives), and at 1e-7 below it the search returns the
 * orbit and its certificate counts it (before: rejected as grazing,
 * certificate complete without it); the rk8pd reference gives a rising end */
static void test_tangency_band(void) {
  const ss_params p = {0.4572, 0.9573, 0.2514, 3.9804, 1};
  const double end = 4.407438357428859;
  ss_model m;
  ss_orbit_opts oo;
  ss_orbit found[16], *start = NULL;
  int n = 0;
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_STICKSLIP;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, found, 16, &n, NULL, NULL), SS_OK);
  for (int i = 0; i < n; i++)
    if (found[i].n_phases == 2 && found[i].period > 5 && found[i].period < 6)
      start = &found[i];
  ASSERT_TRUE(start != NULL);
  if (!start)
    return;
  ss_cont_opts co;
  memset(&co, 0, sizeof co);
  co.param = SS_PARAM_UR;
  co.lo = 0.3 * p.ur;
  co.hi = 3 * p.ur;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&p, start, &co, &b, NULL), SS_OK);
  const ss_special *g = NULL;
  for (int i = 0; i < b.n_special; i++)
    if (b.special[i].margin == SS_MARGIN_TRANSVERSALITY)
      g = &b.special[i];
  ASSERT_TRUE(g != NULL);
  double last = g ? fabs(g->value - g->at.value) / end : NAN,
         located = g ? g->value : NAN;
  if (g) {
    ASSERT_NEAR_REL(g->value, end, 1e-12);
    ASSERT_TRUE(last < 1e-9);
  }
  ss_branch_free(&b);
  /* 1e-7 below the end: found, certified, and rising at its end */
  ss_params q = p;
  q.ur = end * (1 - 1e-7);
  ss_orbit_report rep;
  const ss_orbit *o = NULL;
  memset(&rep, 0, sizeof rep);
  oo.certify = 1;
  oo.max_period = 1;
  ASSERT_EQ_INT(ss_model_init(&m, &q, NULL), SS_OK);
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, found, 16, &n, &rep, NULL), SS_OK);
  for (int i = 0; i < n; i++)
    if (found[i].n_phases == 2 && fabs(found[i].period - 6.0036) < 1e-3)
      o = &found[i];
  ASSERT_TRUE(o != NULL);
  ASSERT_TRUE(rep.cert[0].ran && rep.cert[0].complete);
  ASSERT_EQ_INT(rep.cert[0].rejected, 0);
  ASSERT_EQ_INT(rep.cert[0].orbits, rep.cert[0].roots);
  if (!o)
    return;
  double sl = ref_stick_end_slope(&q, o->modes, o->durations, o->x0, 1);
  printf("the tangency band: the family's last feasible point %.1e below "
         "its end at ur = %.15g; 1e-7 below it the orbit of period %.9g is "
         "returned (end slope %.3g, rk8pd %.3g, residual %.1e), certified "
         "with %d roots, %d orbits, %d rejected\n",
         last, located, o->period, o->transversal.value, sl, o->residual,
         rep.cert[0].roots, rep.cert[0].orbits, rep.cert[0].rejected);
  ASSERT_TRUE(o->transversal.value > 1e-7 && o->residual < 1e-13);
  ASSERT_TRUE(sl > 1e-7);
}

/* The bits of two doubles are the same (a NaN equals itself). */
static int same_bits(double a, double b) {
  return memcmp(&a, &b, sizeof a) == 0;
}

#define ASSERT_SAME(a, b) ASSERT_TRUE(same_bits((a), (b)))
#define ASSERT_SAME_N(a, b, n)                                                 \
  do {                                                                         \
    for (int k_ = 0; k_ < (n); k_++)                                           \
      ASSERT_SAME((a)[k_], (b)[k_]);                                           \
  } while (0)
#define ASSERT_SAME_STR(a, b) ASSERT_TRUE(strcmp((a), (b)) == 0)

static void same_margin(const ss_margin *a, const ss_margin *b) {
  ASSERT_SAME(a->value, b->value);
  ASSERT_EQ_INT(a->phase, b->phase);
  ASSERT_SAME(a->t, b->t);
}

static void same_point(int n, const ss_cont_point *a, const ss_cont_point *b) {
  ASSERT_SAME(a->value, b->value);
  ASSERT_SAME_N(a->durations, b->durations, n);
  ASSERT_SAME(a->period, b->period);
  ASSERT_SAME_N(a->z0, b->z0, 4);
  ASSERT_EQ_INT(a->n_turns, b->n_turns);
  ASSERT_SAME_N(a->eig_re, b->eig_re, 2);
  ASSERT_SAME_N(a->eig_im, b->eig_im, 2);
  ASSERT_SAME(a->spectral_radius, b->spectral_radius);
  ASSERT_EQ_INT(a->stable, b->stable);
  same_margin(&a->min_margin, &b->min_margin);
  ASSERT_SAME(a->residual, b->residual);
}

/* Two families, field by field. */
static void same_branch(const ss_branch *a, const ss_branch *b) {
  ASSERT_EQ_INT(a->n_phases, b->n_phases);
  ASSERT_TRUE(!memcmp(a->modes, b->modes, sizeof a->modes));
  ASSERT_EQ_INT((int)a->param, (int)b->param);
  ASSERT_EQ_INT(a->physical, b->physical);
  ASSERT_EQ_INT((int)a->phys, (int)b->phys);
  ASSERT_SAME(a->lo, b->lo);
  ASSERT_SAME(a->hi, b->hi);
  ASSERT_EQ_INT(a->n_points, b->n_points);
  ASSERT_EQ_INT(a->start, b->start);
  ASSERT_EQ_INT(a->n_special, b->n_special);
  ASSERT_SAME_STR(a->end[0], b->end[0]);
  ASSERT_SAME_STR(a->end[1], b->end[1]);
  if (a->n_points != b->n_points || a->n_special != b->n_special)
    return;
  for (int i = 0; i < a->n_points; i++)
    same_point(a->n_phases, &a->points[i], &b->points[i]);
  for (int i = 0; i < a->n_special; i++) {
    const ss_special *s = &a->special[i], *t = &b->special[i];
    ASSERT_EQ_INT((int)s->kind, (int)t->kind);
    ASSERT_SAME(s->value, t->value);
    ASSERT_SAME(s->precision, t->precision);
    same_point(a->n_phases, &s->at, &t->at);
    ASSERT_EQ_INT((int)s->margin, (int)t->margin);
    ASSERT_EQ_INT(s->stable_before, t->stable_before);
    ASSERT_EQ_INT(s->stable_after, t->stable_after);
    ASSERT_SAME_STR(s->detail, t->detail);
  }
}

/* Two curves, field by field. */
static void same_curve(int n_phases, const ss_curve *a, const ss_curve *b) {
  ASSERT_EQ_INT((int)a->kind, (int)b->kind);
  ASSERT_EQ_INT((int)a->margin, (int)b->margin);
  ASSERT_EQ_INT(a->phase, b->phase);
  ASSERT_EQ_INT((int)a->p1, (int)b->p1);
  ASSERT_EQ_INT((int)a->p2, (int)b->p2);
  ASSERT_EQ_INT(a->n_points, b->n_points);
  ASSERT_EQ_INT(a->start, b->start);
  ASSERT_SAME_STR(a->end[0], b->end[0]);
  ASSERT_SAME_STR(a->end[1], b->end[1]);
  if (a->n_points != b->n_points)
    return;
  for (int i = 0; i < a->n_points; i++) {
    const ss_curve_point *q = &a->points[i], *r = &b->points[i];
    ASSERT_SAME(q->v1, r->v1);
    ASSERT_SAME(q->v2, r->v2);
    ASSERT_SAME_N(q->durations, r->durations, n_phases);
    ASSERT_SAME_N(q->z0, r->z0, 4);
    ASSERT_EQ_INT(q->feasible_side, r->feasible_side);
  }
}

static void same_attractor(const ss_attractor *a, const ss_attractor *b) {
  ASSERT_EQ_INT(a->found, b->found);
  ASSERT_EQ_INT(a->perpetual_slip, b->perpetual_slip);
  ASSERT_EQ_INT(a->n_turns, b->n_turns);
  ASSERT_SAME(a->period, b->period);
  ASSERT_EQ_INT(a->n_phases, b->n_phases);
  ASSERT_EQ_INT(a->n_overshoot, b->n_overshoot);
  int n = a->n_phases < SS_MAX_PHASES ? a->n_phases : SS_MAX_PHASES;
  ASSERT_TRUE(!memcmp(a->modes, b->modes, n * sizeof a->modes[0]));
  ASSERT_SAME_N(a->durations, b->durations, n);
  ASSERT_SAME_N(a->s, b->s, 2);
  ASSERT_EQ_INT(a->turns_run, b->turns_run);
}

/* A periodic orbit at @a p of the kinds @a kinds, @a n_phases phases (0:
 * any) and period in (pmin, pmax), found with no guess; 0 if none. */
static int orbit_at(const ss_params *p, unsigned kinds, int n_phases,
                    double pmin, double pmax, ss_orbit *out) {
  ss_model m;
  ss_orbit_opts oo;
  ss_orbit found[16];
  int n = 0;
  memset(&oo, 0, sizeof oo);
  oo.kinds = kinds;
  if (ss_model_init(&m, p, NULL) != SS_OK ||
      ss_orbit_find(&m, &oo, found, 16, &n, NULL, NULL) != SS_OK)
    return 0;
  for (int i = 0; i < n; i++)
    if ((!n_phases || found[i].n_phases == n_phases) &&
        found[i].period > pmin && found[i].period < pmax) {
      *out = found[i];
      return 1;
    }
  return 0;
}

/* What a study's check saw: special points followed and not, families
 * started (period-2, adjacent), attractors found past a grazing. */
typedef struct study_count {
  int followed, unfollowed, branches, beyond, adjacent;
} study_count;

/* The study's curves against ss_continue_grazing() or
 * ss_continue_period_doubling() at each special point of the kind followed
 * of the family @a b; one that cannot be followed says why, with no
 * points. */
static void same_curves(const ss_params *p, const ss_study_opts *o,
                        const ss_branch *b, const ss_study *s, study_count *c) {
  ss_cont_opts o2 = o->family;
  o2.param = o->follow_param;
  o2.lo = o->follow_lo;
  o2.hi = o->follow_hi;
  o2.direction = 0;
  int nc = 0;
  for (int i = 0; o->follow && i < b->n_special; i++) {
    const ss_special *g = &b->special[i];
    if (g->kind != o->follow_kind)
      continue;
    ss_curve cv;
    ss_diag d;
    ss_diag_clear(&d);
    int rc = g->kind == SS_SPECIAL_GRAZING
                 ? ss_continue_grazing(p, b, g, &o2, &cv, &d)
                 : ss_continue_period_doubling(p, b, g, &o2, &cv, &d);
    ASSERT_TRUE(nc < s->n_curves);
    const ss_curve *sc = nc < s->n_curves ? &s->curves[nc++] : NULL;
    if (sc && rc == SS_OK) {
      same_curve(b->n_phases, sc, &cv);
      c->followed++;
    } else if (sc) {
      ASSERT_EQ_INT((int)sc->kind, (int)g->kind);
      ASSERT_EQ_INT((int)sc->p1, (int)b->param);
      ASSERT_EQ_INT((int)sc->p2, (int)o->follow_param);
      ASSERT_EQ_INT(sc->n_points, 0);
      ASSERT_TRUE(sc->points == NULL);
      ASSERT_EQ_INT(sc->start, -1);
      ASSERT_SAME_STR(sc->end[0], d.text[0] ? d.text : ss_strerror(rc));
      c->unfollowed++;
    }
    ss_curve_free(&cv);
  }
  ASSERT_EQ_INT(s->n_curves, nc);
}

/* The study's period-2 families against ss_continue_period2() at each
 * period doubling of @a b, and why there is none where there is none;
 * the next of the study's families in *nb. */
static void same_period2(const ss_params *p, const ss_study_opts *o,
                         const ss_branch *b, const ss_study *s, int *nb,
                         study_count *c) {
  for (int i = 0; o->branch_switching && i < b->n_special; i++) {
    const ss_special *pd = &b->special[i];
    if (pd->kind != SS_SPECIAL_PERIOD_DOUBLING)
      continue;
    ss_branch b2;
    ss_diag d;
    ss_diag_clear(&d);
    int rc = ss_continue_period2(p, b, pd, &o->family, &b2, &d);
    if (rc == SS_OK && *nb < s->n_branches) {
      ASSERT_EQ_INT(s->of_special[*nb], i);
      same_branch(&s->branches[(*nb)++], &b2);
      c->branches++;
    } else {
      ASSERT_EQ_INT(rc, SS_ENOCONV);
      ASSERT_SAME_STR(s->why_none[i], d.text);
      ASSERT_TRUE(s->why_none[i][0] != '\0');
    }
    ss_branch_free(&b2);
  }
}

/* Past each grazing of @a b: the study's attractor against
 * ss_beyond_grazing(), its adjacent sequence against
 * ss_continue_adjacent() (the family kept with branch switching). */
static void same_beyond(const ss_params *p, const ss_study_opts *o,
                        const ss_branch *b, const ss_study *s, int *nb,
                        study_count *c) {
  for (int i = 0; i < b->n_special; i++) {
    const ss_special *g = &b->special[i];
    const ss_beyond *by = &s->beyond[i];
    if (g->kind != SS_SPECIAL_GRAZING)
      continue;
    double v;
    ss_attractor a;
    int done = ss_beyond_grazing(p, b, g, &v, &a) == SS_OK;
    ASSERT_EQ_INT(by->done, done);
    if (done) {
      ASSERT_SAME(by->value, v);
      same_attractor(&by->attractor, &a);
      c->beyond++;
    }
    ss_branch adj;
    ss_diag d;
    ss_diag_clear(&d);
    int rc = ss_continue_adjacent(p, b, g, &o->family, &adj, &d);
    ASSERT_EQ_INT(by->adjacent_rc, rc);
    ASSERT_EQ_INT(by->adjacent_n_phases, adj.n_phases);
    ASSERT_TRUE(!memcmp(by->adjacent_modes, adj.modes, sizeof adj.modes));
    ASSERT_SAME_STR(by->adjacent_why, d.text);
    if (rc == SS_OK && o->branch_switching && *nb < s->n_branches) {
      ASSERT_EQ_INT(s->of_special[*nb], i);
      same_branch(&s->branches[(*nb)++], &adj);
      c->adjacent++;
    }
    ss_branch_free(&adj);
  }
}

/* The study @a s against the public calls it stands for, each made here
 * separately with the same options: the family (ss_continue()), its
 * curves, then the families started at its period doublings and past its
 * grazings, in that order, and the attractors past its grazings; nothing
 * said of a special point the study had nothing to say about. */
static study_count check_study(const ss_params *p, const ss_orbit *start,
                               const ss_study_opts *o, const ss_study *s) {
  study_count c = {0, 0, 0, 0, 0};
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(p, start, &o->family, &b, NULL), SS_OK);
  same_branch(&s->family, &b);
  same_curves(p, o, &b, s, &c);
  int nb = 0;
  same_period2(p, o, &b, s, &nb, &c);
  same_beyond(p, o, &b, s, &nb, &c);
  ASSERT_EQ_INT(s->n_branches, nb);
  for (int i = 0; i < SS_MAX_SPECIAL; i++) {
    int pd = i < b.n_special && o->branch_switching &&
             b.special[i].kind == SS_SPECIAL_PERIOD_DOUBLING;
    int g = i < b.n_special && b.special[i].kind == SS_SPECIAL_GRAZING;
    if (!pd)
      ASSERT_TRUE(s->why_none[i][0] == '\0');
    if (!g)
      ASSERT_TRUE(s->beyond[i].done == 0 && s->beyond[i].adjacent_rc == 0);
  }
  ss_branch_free(&b);
  return c;
}

/* A cancel hook that says stop after @a after polls (-1: never), and
 * counts them. */
typedef struct polls {
  int n, after;
} polls;

static int poll_count(void *cls) {
  polls *k = cls;
  k->n++;
  return k->after >= 0 && k->n > k->after;
}

/* One study of test_study: the parameters, the start and what it asks. */
typedef struct study_case {
  const char *what;
  ss_params p;
  unsigned kinds;
  int n_phases;
  double pmin, pmax;
  ss_param_id param;
  double lo, hi;
  ss_special_kind kind;
  ss_param_id follow;
  double follow_lo, follow_hi;
  study_count want; /* at least */
} study_case;

/* EVIDENCE: docs/checked/families.md: one call, ss_continue_study, gives the
 * family and what its special points lead to, the same to the bit as the
 * separate calls it stands for, on families that end at grazings (of the
 * switching condition, inside a phase, of a phase's end, one not located
 * and so not followed), with period doublings (one that starts a period-2
 * family, one that does not) and a fold */
static void test_study(void) {
  const double ur12 = 12 * PAPER.us;
  const study_case cases[] = {
      {"the paper's family in ur, its grazing followed in chi",
       PAPER,
       SS_ORBIT_OVERSHOOT,
       0,
       0,
       INFINITY,
       SS_PARAM_UR,
       0.3,
       1.5,
       SS_SPECIAL_GRAZING,
       SS_PARAM_CHI,
       0.05,
       0.6,
       {1, 0, 0, 1, 0}},
      {"the overshoot family in chi at ur = 12 us, its period doublings "
       "followed in ur",
       {0.2, 4, 0.0724, ur12, 1},
       SS_ORBIT_OVERSHOOT,
       0,
       0,
       INFINITY,
       SS_PARAM_CHI,
       0.01,
       0.99,
       SS_SPECIAL_PERIOD_DOUBLING,
       SS_PARAM_UR,
       0.3,
       2.0,
       {2, 0, 1, 2, 0}},
      {"the stick-slip family in chi at ur = 12 us (a fold, grazings inside "
       "the stick) followed in ur",
       {0.5, 4, 0.0724, ur12, 1},
       SS_ORBIT_STICKSLIP,
       0,
       12.559,
       12.579,
       SS_PARAM_CHI,
       0.01,
       0.99,
       SS_SPECIAL_GRAZING,
       SS_PARAM_UR,
       0.3,
       2.0,
       {2, 0, 1, 2, 0}},
      {"a slip-stick family in ur ending tangentially, followed in chi",
       {0.45718539037873918, 0.957262457729113, 0.25138758401573669,
        3.9803720170071393, 1},
       SS_ORBIT_STICKSLIP,
       2,
       5,
       6,
       SS_PARAM_UR,
       0.3 * 3.9803720170071393,
       3 * 3.9803720170071393,
       SS_SPECIAL_GRAZING,
       SS_PARAM_CHI,
       0.01,
       0.99,
       {1, 0, 1, 1, 0}},
      {"a slip-stick family in ur whose end is not located",
       {0.1, 0.3, 0.05, 3.9803720170071393, 1},
       SS_ORBIT_STICKSLIP,
       2,
       60,
       INFINITY,
       SS_PARAM_UR,
       0.3 * 3.9803720170071393,
       3 * 3.9803720170071393,
       SS_SPECIAL_GRAZING,
       SS_PARAM_CHI,
       0.05,
       0.2,
       {1, 1, 0, 2, 0}},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    const study_case *k = &cases[c];
    ss_orbit start;
    ASSERT_TRUE(
        orbit_at(&k->p, k->kinds, k->n_phases, k->pmin, k->pmax, &start));
    ss_study_opts o;
    memset(&o, 0, sizeof o);
    o.family.param = k->param;
    o.family.lo = k->lo;
    o.family.hi = k->hi;
    o.family.max_points = 400;
    o.follow = 1;
    o.follow_kind = k->kind;
    o.follow_param = k->follow;
    o.follow_lo = k->follow_lo;
    o.follow_hi = k->follow_hi;
    o.branch_switching = 1;
    ss_study s;
    ss_diag d;
    ss_diag_clear(&d);
    ASSERT_EQ_INT(ss_continue_study(&k->p, &start, &o, &s, &d), SS_OK);
    study_count n = check_study(&k->p, &start, &o, &s);
    printf("study of %s: %d special points; %d followed, %d not; %d "
           "period-2 families, %d adjacent; %d attractors past a grazing\n",
           k->what, s.family.n_special, n.followed, n.unfollowed, n.branches,
           n.adjacent, n.beyond);
    ASSERT_TRUE(n.followed >= k->want.followed);
    ASSERT_TRUE(n.unfollowed >= k->want.unfollowed);
    ASSERT_TRUE(n.branches >= k->want.branches);
    ASSERT_TRUE(n.beyond >= k->want.beyond);
    ss_study_free(&s);
  }
}

/* EVIDENCE: docs/checked/families.md: what ss_continue_study does besides the
 * family is what its options ask; a family in a physical parameter is
 * followed nowhere and has no beyond; a cancel stops it with what it
 * found; ss_study_free is NULL-safe and zeroes */
static void test_study_options(void) {
  static const ss_study ZERO;
  ss_study_free(NULL);
  ss_params p = PAPER;
  p.ur = 12 * p.us;
  ss_orbit start;
  ASSERT_EQ_INT(overshoot_at(&p, &start), 1);
  ss_study_opts o;
  memset(&o, 0, sizeof o);
  o.family.param = SS_PARAM_CHI;
  o.family.lo = 0.01;
  o.family.hi = 0.99;
  ss_study s;
  ss_diag d;
  ss_diag_clear(&d);
  /* neither follow nor branch switching: the family, and past its
   * grazings the attractors */
  ASSERT_EQ_INT(ss_continue_study(&p, &start, &o, &s, &d), SS_OK);
  study_count n = check_study(&p, &start, &o, &s);
  ASSERT_EQ_INT(s.n_curves, 0);
  ASSERT_EQ_INT(s.n_branches, 0);
  ASSERT_TRUE(s.branches == NULL);
  ASSERT_EQ_INT(n.beyond, 2);
  ss_study_free(&s);
  ASSERT_TRUE(!memcmp(&s, &ZERO, sizeof s));
  ss_study_free(&s); /* twice is harmless */
  /* a follow of another kind of special point is refused */
  o.follow = 1;
  o.follow_kind = SS_SPECIAL_FOLD;
  ASSERT_EQ_INT(ss_continue_study(&p, &start, &o, &s, &d), SS_EINVAL);
  ASSERT_TRUE(!strcmp(d.where, "follow"));
  ss_study_free(&s);
  /* the polls of the family alone; a cancel after them stops the first
   * curve, after none stops the family at its start; each study holds
   * what it found */
  polls k = {0, -1};
  o.follow_kind = SS_SPECIAL_PERIOD_DOUBLING;
  o.follow_param = SS_PARAM_UR;
  o.follow_lo = 0.3;
  o.follow_hi = 2;
  o.branch_switching = 1;
  o.family.cancelled = poll_count;
  o.family.cancel_cls = &k;
  ss_branch b;
  ASSERT_EQ_INT(ss_continue(&p, &start, &o.family, &b, NULL), SS_OK);
  ASSERT_TRUE(k.n > 0);
  k.after = k.n;
  k.n = 0;
  ASSERT_EQ_INT(ss_continue_study(&p, &start, &o, &s, NULL), SS_ECANCELED);
  same_branch(&s.family, &b);
  ASSERT_EQ_INT(s.n_curves, 1);
  ASSERT_EQ_INT(s.n_branches, 0);
  ASSERT_TRUE(s.curves[0].n_points >= 1);
  ASSERT_TRUE(strstr(s.curves[0].end[0], "cancelled") != NULL ||
              strstr(s.curves[0].end[1], "cancelled") != NULL);
  ss_study_free(&s);
  /* following nothing, a cancel at the last poll of the first period-2
   * family (after its orbit search, in its continuation): stopped, and
   * none kept */
  const ss_special *pd = NULL;
  for (int i = 0; i < b.n_special && !pd; i++)
    if (b.special[i].kind == SS_SPECIAL_PERIOD_DOUBLING)
      pd = &b.special[i];
  ASSERT_TRUE(pd != NULL);
  ss_branch b2;
  k.after = -1;
  k.n = 0;
  ASSERT_EQ_INT(ss_continue(&p, &start, &o.family, &b2, NULL), SS_OK);
  ss_branch_free(&b2);
  if (pd)
    ASSERT_EQ_INT(ss_continue_period2(&p, &b, pd, &o.family, &b2, NULL), SS_OK);
  ss_branch_free(&b2);
  /* a cancel in the period-2 orbit's search stops it: it is not a side
   * without a period-2 orbit (SS_ENOCONV); a physical parameter is refused */
  int polls_period2 = k.n;
  k.after = 0;
  k.n = 0;
  if (pd)
    ASSERT_EQ_INT(ss_continue_period2(&p, &b, pd, &o.family, &b2, NULL),
                  SS_ECANCELED);
  ss_branch_free(&b2);
  ss_physical ph_pd = {2.5, 0.625, 8, 2, 0.724, 6.178, 2};
  ss_cont_opts in_fr = o.family;
  in_fr.physical = &ph_pd;
  in_fr.phys = SS_PHYS_FR;
  if (pd)
    ASSERT_EQ_INT(ss_continue_period2(&p, &b, pd, &in_fr, &b2, NULL),
                  SS_EINVAL);
  ss_branch_free(&b2);
  k.n = polls_period2;
  k.after = k.n - 1;
  k.n = 0;
  o.follow = 0;
  ASSERT_EQ_INT(ss_continue_study(&p, &start, &o, &s, NULL), SS_ECANCELED);
  same_branch(&s.family, &b);
  ASSERT_EQ_INT(s.n_curves, 0);
  /* the period-2 family the cancel stopped is kept with what was found */
  ASSERT_EQ_INT(s.n_branches, pd ? 1 : 0);
  if (pd)
    ASSERT_TRUE(s.branches[0].n_points > 0 && s.of_special[0] >= 0);
  ss_study_free(&s);
  ss_branch_free(&b);
  o.follow = 1;
  o.family.cancelled = always;
  o.family.cancel_cls = NULL;
  ASSERT_EQ_INT(ss_continue_study(&p, &start, &o, &s, &d), SS_ECANCELED);
  ASSERT_EQ_INT(s.family.n_points, 1); /* the start */
  ASSERT_EQ_INT(s.n_curves, 0);
  ASSERT_EQ_INT(s.n_branches, 0);
  ss_study_free(&s);
  ASSERT_TRUE(!memcmp(&s, &ZERO, sizeof s));
  /* a family in Fr: its grazing is listed unfollowed with the reason, and
   * nothing is simulated past it */
  ss_physical ph = {2.5, 0.625, 8, 2, 0.724, 6.178, 2};
  ASSERT_EQ_INT(ss_params_from_physical(&ph, &p, NULL, NULL), SS_OK);
  ASSERT_EQ_INT(overshoot_at(&p, &start), 1);
  memset(&o, 0, sizeof o);
  o.family.physical = &ph;
  o.family.phys = SS_PHYS_FR;
  o.family.lo = 3;
  o.family.hi = 15;
  o.follow = 1;
  o.follow_kind = SS_SPECIAL_GRAZING;
  o.follow_param = SS_PARAM_US;
  o.follow_lo = 0.05;
  o.follow_hi = 0.1;
  o.branch_switching = 1;
  ASSERT_EQ_INT(ss_continue_study(&p, &start, &o, &s, &d), SS_OK);
  ASSERT_EQ_INT(ss_continue(&p, &start, &o.family, &b, NULL), SS_OK);
  same_branch(&s.family, &b);
  ASSERT_EQ_INT(s.family.n_special, 1);
  ASSERT_EQ_INT(s.n_curves, 1);
  ASSERT_EQ_INT(s.curves[0].n_points, 0);
  ASSERT_EQ_INT(s.curves[0].start, -1);
  ASSERT_TRUE(strstr(s.curves[0].end[0], "physical parameter") != NULL);
  ASSERT_EQ_INT(s.n_branches, 0);
  ASSERT_TRUE(!memcmp(&s.beyond, &ZERO.beyond, sizeof s.beyond));
  printf("study in Fr: %d points, its grazing not followed (%s), nothing "
         "past it\n",
         s.family.n_points, s.curves[0].end[0]);
  ss_branch_free(&b);
  ss_study_free(&s);
}

int main(void) {
  gsl_set_error_handler_off();
  test_ur_family();
  test_period_doubling();
  test_bad_options();
  test_budget();
  test_grazing_curve();
  test_beyond();
  test_neimark_sacker();
  test_fold();
  test_saddle_node_without_fold();
  test_period_doubling_curve();
  test_physical();
  test_interior_grazing_curve();
  test_transversality_curve();
  test_tangency_band();
  test_study();
  test_study_options();
  TEST_DONE();
}
