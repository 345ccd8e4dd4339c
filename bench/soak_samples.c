/*
 * soak_samples.c: a long random check of samples placed for a curve
 * (ss_sim_opts.sample_tolerance): the true curve (ss_flow per phase from the
 * recorded events, at dense times in every segment) against the polyline of
 * the samples, over random parameter sets, states, windows, tolerances
 * (1e-7 to 1e-1), axes and scales; with adversarial 1, every run a long
 * stick with a small ripple measured at scales down to 1e-4.  Also checks
 * that every phase starts and ends with a sample in its own mode.  Prints
 * each violation (distance above eps beyond 1e-12 relative) and a summary;
 * exits 1 on any violation.  test_samples runs a short version of it.
 * Usage: soak_samples [runs [seed [dense [adversarial [t0]]]]]
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stickslip.h"

static unsigned long long rs = 88172645463325252ULL;
static double urand(void) {
  rs ^= rs << 13;
  rs ^= rs >> 7;
  rs ^= rs << 17;
  return (double)(rs >> 11) * (1.0 / 9007199254740992.0);
}
static double uni(double a, double b) { return a + (b - a) * urand(); }
static double logu(double a, double b) { return exp(uni(log(a), log(b))); }

static double inv[4];

static void scaled(const double x[4], double c[4]) {
  for (int i = 0; i < 4; i++)
    c[i] = inv[i] * x[i];
}

static double seg_dist(const double p[4], const double a[4],
                       const double b[4]) {
  double ab[4], ap[4], l2 = 0, dot = 0;
  for (int i = 0; i < 4; i++) {
    ab[i] = b[i] - a[i];
    ap[i] = p[i] - a[i];
    l2 += ab[i] * ab[i];
    dot += ab[i] * ap[i];
  }
  double s = l2 > 0 ? dot / l2 : 0;
  if (s < 0)
    s = 0;
  if (s > 1)
    s = 1;
  double d2 = 0;
  for (int i = 0; i < 4; i++) {
    double r = ap[i] - s * ab[i];
    d2 += r * r;
  }
  return sqrt(d2);
}

typedef struct {
  double worst_ratio;
  long viol;
  long runs, samples;
} stats;

static stats ST;
static int verbose = 0;
static double T0 = 0;

/* returns worst ratio dist/eps for this run; prints violations */
static double run_one(const ss_params *p, const double x0[4], double t_end,
                      double from, double to, double eps, unsigned axes,
                      const double scale[4], long id, int dense) {
  ss_model m;
  if (ss_model_init(&m, p, NULL))
    return 0;
  ss_sim_opts o;
  memset(&o, 0, sizeof o);
  o.t0 = T0;
  o.t_end = t_end;
  o.record_events = 1;
  o.sample_tolerance = eps;
  o.sample_from = from;
  o.sample_to = to;
  o.sample_axes = axes;
  memcpy(o.sample_scale, scale, sizeof o.sample_scale);
  o.max_samples = 3000000;
  o.max_events = 100000;
  ss_sim_result r;
  ss_diag d;
  int rc = ss_simulate(&m, x0, &o, &r, &d);
  if (rc) {
    if (verbose)
      printf("run %ld: rc %d %s\n", id, rc, d.text);
    ss_sim_result_free(&r);
    return 0;
  }
  for (int i = 0; i < 4; i++)
    inv[i] =
        (!axes || (axes & (1u << i))) ? (scale[i] > 0 ? 1 / scale[i] : 1) : 0;
  ST.runs++;
  ST.samples += (long)r.n_samples;
  size_t np = r.n_events + 1, idx = 0;
  double worst = 0;
  ss_mode mode0 = ss_mode_of_state(&m, x0);
  for (size_t k = 0; k < np; k++) {
    double Ta = k ? r.events[k - 1].t : T0,
           Tb = k < r.n_events ? r.events[k].t : t_end;
    const double *xa = k ? r.events[k - 1].x : x0;
    ss_mode md = k ? r.events[k - 1].to : mode0;
    double a = fmax(Ta, from), b = fmin(Tb, to);
    if (!(b >= a))
      continue;
    if (idx >= r.n_samples || r.st[idx] != a) {
      printf("run %ld: phase %zu: sample %zu time %.17g, expected %.17g\n", id,
             k, idx, idx < r.n_samples ? r.st[idx] : NAN, a);
      exit(2);
    }
    size_t i0 = idx;
    idx++;
    if (b > a) {
      while (idx < r.n_samples && r.st[idx] < b)
        idx++;
      if (idx >= r.n_samples || r.st[idx] != b) {
        printf("run %ld: phase %zu: no end sample\n", id, k);
        exit(2);
      }
      idx++;
    }
    size_t i1 = idx; /* [i0, i1) */
    for (size_t i = i0; i < i1; i++)
      if (r.smode[i] != md) {
        printf("run %ld: sample %zu mode %d, phase mode %d\n", id, i,
               r.smode[i], md);
        exit(2);
      }
    for (size_t i = i0; i + 1 < i1; i++) {
      double ca[4], cb[4], t0 = r.st[i], t1 = r.st[i + 1];
      scaled(r.sx + 4 * i, ca);
      scaled(r.sx + 4 * (i + 1), cb);
      for (int q = 0; q <= dense; q++) {
        double t = t0 + (t1 - t0) * q / dense, x[4], c[4];
        ss_flow(&m, md, t - Ta, xa, x);
        if (md == SS_MODE_STICK)
          x[3] = p->V;
        scaled(x, c);
        double dd = seg_dist(c, ca, cb);
        if (dd > eps) {
          /* against the phase's whole polyline */
          double best = dd;
          for (size_t j = i0; j + 1 < i1 && best > eps; j++) {
            double pa[4], pb[4];
            scaled(r.sx + 4 * j, pa);
            scaled(r.sx + 4 * (j + 1), pb);
            double e = seg_dist(c, pa, pb);
            if (e < best)
              best = e;
          }
          dd = best;
        }
        double ratio = dd / eps;
        if (ratio > worst)
          worst = ratio;
        if (ratio > 1 + 1e-12) {
          double cm = 0, vm = 0, xd[4];
          for (int z = 0; z < 4; z++)
            cm = fmax(cm, fabs(c[z]));
          /* |c'| by difference */
          ss_flow(&m, md, t - Ta + 1e-7, xa, xd);
          if (md == SS_MODE_STICK)
            xd[3] = p->V;
          double cd[4];
          scaled(xd, cd);
          for (int z = 0; z < 4; z++)
            vm += (cd[z] - c[z]) * (cd[z] - c[z]);
          vm = sqrt(vm) / 1e-7;
          double allow = 4e-16 * cm + vm * 2.3e-16 * fmax(1, fabs(t));
          ST.viol++;
          if (ST.viol < 40)
            printf(
                "VIOLATION run %ld phase %zu mode %d seg [%.17g, %.17g] t "
                "%.17g "
                "dist %.6g eps %.3g ratio %.9g excess %.3g (rounding allowance "
                "~%.3g) |c| %.3g |c'| %.3g nseg %zu\n",
                id, k, md, t0, t1, t, dd, eps, ratio, dd - eps, allow, cm, vm,
                i1 - i0 - 1);
        }
      }
    }
  }
  ss_sim_result_free(&r);
  if (worst > ST.worst_ratio)
    ST.worst_ratio = worst;
  return worst;
}

static void print_case(const ss_params *p, const double x0[4], double t_end,
                       double from, double to, double eps, unsigned axes,
                       const double sc[4]) {
  printf(
      "  params {%.17g, %.17g, %.17g, %.17g, %.17g} x0 {%.17g, %.17g, %.17g, "
      "%.17g} t_end %.17g window [%.17g, %.17g] eps %.17g axes %u scale "
      "{%.17g, "
      "%.17g, %.17g, %.17g}\n",
      p->chi, p->eta, p->us, p->ur, p->V, x0[0], x0[1], x0[2], x0[3], t_end,
      from, to, eps, axes, sc[0], sc[1], sc[2], sc[3]);
}

int main(int argc, char **argv) {
  long n = argc > 1 ? atol(argv[1]) : 200;
  if (argc > 2)
    rs = strtoull(argv[2], NULL, 10) * 2654435761ULL + 1;
  int dense = argc > 3 ? atoi(argv[3]) : 48;
  int adv = argc > 4 ? atoi(argv[4]) : 0;
  T0 = argc > 5 ? atof(argv[5]) : 0;
  long shown = 0;
  for (long id = 0; id < n; id++) {
    ss_params p;
    p.chi = uni(0.05, 0.95);
    p.eta = logu(0.2, 20);
    p.us = uni(0.02, 0.2);
    p.ur = p.us * uni(1.5, 15);
    p.V = 1;
    double x0[4];
    for (int i = 0; i < 4; i++)
      x0[i] = uni(-3, 3);
    if (urand() < 0.3)
      x0[3] = p.V; /* a start on the belt */
    if (adv) {     /* a long stick with a small ripple */
      x0[3] = p.V;
      x0[1] = -0.95 * p.ur / (p.chi * (1 - p.chi)) * uni(0.5, 1);
      x0[0] = p.chi * x0[1] + (urand() < .5 ? -1 : 1) * logu(1e-12, 1e-2);
      x0[2] = p.chi * p.V + (urand() < .5 ? -1 : 1) * logu(1e-12, 1e-2);
    }
    double t_end = logu(1, 60);
    double from = urand() < 0.5 ? 0 : uni(0, t_end);
    double to = urand() < 0.5 ? t_end : uni(from, t_end);
    t_end += T0;
    from += T0;
    to += T0;
    if (to > t_end)
      to = t_end;
    double eps = logu(1e-7, 1e-1);
    unsigned axes = (unsigned)(urand() * 16);
    double sc[4];
    for (int i = 0; i < 4; i++)
      sc[i] = urand() < 0.3 ? 0 : adv ? logu(1e-4, 1e4) : logu(1e-3, 1e3);
    long before = ST.viol;
    double w = run_one(&p, x0, t_end, from, to, eps, axes, sc, id, dense);
    if (ST.viol > before && shown++ < 10)
      print_case(&p, x0, t_end, from, to, eps, axes, sc);
    if (w > 5) {
      printf("RUN %ld worst %.6g\n", id, w);
      print_case(&p, x0, t_end, from, to, eps, axes, sc);
    }
  }
  printf("runs %ld samples %ld violations %ld worst ratio %.12g\n", ST.runs,
         ST.samples, ST.viol, ST.worst_ratio);
  return ST.viol != 0;
}
