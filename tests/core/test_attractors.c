/*
 * test_attractors.c: every attractor that long simulation reaches is one
 * the orbit search returns.
 *
 * On 40 random parameter sets (chi 0.05-0.9, eta 0.2-20 and ur/us 1.5-20
 * log-uniform, us 0.02-0.3, V = 1) the independent rk8pd reference
 * (tests/ref) is run from 6 points of the section Sigma0 (the stick -> slip
 * states) for 1500 time units; where its returns to Sigma0 repeat with a
 * period of k <= 8 returns to 1e-7, it has settled on an attractor.  The
 * default search with max_period 8 must return an orbit of k turns through
 * that return point (within 1e-5).  Counts, misses and times are printed.
 * Usage: test_attractors [sets]   (default 40)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "refsim.h"
#include "stickslip.h"
#include "test.h"

#define MAXO 64
#define MAXEV 40000

static uint64_t rng = 0x9e3779b97f4a7c15u;
static double unif(double a, double b) {
  rng ^= rng >> 12;
  rng ^= rng << 25;
  rng ^= rng >> 27;
  return a + (b - a) * (double)((rng * 2685821657736338717u) >> 11) * 0x1p-53;
}

/* Does orbit o of k turns pass through the return point (x1, x1') = s? */
static int passes(const ss_model *m, const ss_orbit *o, const double s[2],
                  double tol) {
  double x[4];
  memcpy(x, o->x0, sizeof x);
  for (int r = 0; r < o->n_phases; r++) {
    if (o->modes[r] == SS_MODE_SLIP &&
        (r == 0 || o->modes[r - 1] == SS_MODE_STICK) &&
        fabs(x[0] - s[0]) < tol && fabs(x[2] - s[1]) < tol)
      return 1;
    ss_flow(m, o->modes[r], o->durations[r], x, x);
    if (o->modes[r] == SS_MODE_STICK)
      x[3] = m->p.V;
  }
  return 0;
}

int main(int argc, char **argv) {
  int sets = argc > 1 ? atoi(argv[1]) : 40;
  gsl_set_error_handler_off();
  ref_event *ev = malloc(MAXEV * sizeof *ev);
  int attractors = 0, missed = 0, unsettled = 0, by_k[9] = {0};
  for (int s = 0; s < sets; s++) {
    ss_params p;
    p.chi = unif(0.05, 0.9);
    p.eta = exp(unif(log(0.2), log(20)));
    p.us = unif(0.02, 0.3);
    p.ur = p.us * exp(unif(log(1.5), log(20)));
    p.V = 1;
    ss_model m;
    ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    oo.max_period = 8;
    ss_orbit out[MAXO];
    int n = 0;
    ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, NULL, NULL), SS_OK);
    double L = (p.ur - p.us) / p.chi, d0 = p.us / (1 - p.chi);
    double scale = fmax(p.V, L);
    ref_params rp = {p.chi, p.eta, p.us, p.ur, p.V};
    ref_opts ro = {gsl_odeiv2_step_rk8pd, 1e-12, 1e-12, 0, 1e-12};
    double seen[6][2];
    int n_seen = 0;
    for (int i = 0; i < 6; i++) {
      /* a stick -> slip state: chi (x2 - x1) = ur, x2' = V */
      double x1 = d0 + (i % 3 - 1) * 0.5 * L, v1 = (i < 3 ? -0.8 : 0.8) * p.V;
      double x0[4] = {x1, x1 + p.ur / p.chi, v1, p.V}, xe[4];
      int me;
      long ne =
          ref_simulate(&rp, 0, x0, REF_SLIP, 1500, &ro, ev, MAXEV, xe, &me);
      double r[64][2];
      int nr = 0;
      for (long e = ne - 1; e >= 0 && nr < 64; e--)
        if (ev[e].from == REF_STICK && ev[e].to == REF_SLIP) {
          r[nr][0] = ev[e].x[0];
          r[nr][1] = ev[e].x[2];
          nr++;
        }
      int k = 0;
      for (int j = 1; j <= 8 && !k && 2 * j < nr; j++)
        if (fabs(r[0][0] - r[j][0]) + fabs(r[0][1] - r[j][1]) < 1e-7 * scale &&
            fabs(r[j][0] - r[2 * j][0]) + fabs(r[j][1] - r[2 * j][1]) <
                1e-7 * scale)
          k = j;
      if (!k) {
        unsettled++;
        continue;
      }
      /* the same attractor from another start is counted once */
      int again = 0;
      for (int a = 0; a < n_seen && !again; a++)
        for (int j = 0; j < k && !again; j++)
          again = fabs(seen[a][0] - r[j][0]) + fabs(seen[a][1] - r[j][1]) <
                  1e-5 * scale;
      if (again)
        continue;
      seen[n_seen][0] = r[0][0];
      seen[n_seen][1] = r[0][1];
      n_seen++;
      attractors++;
      by_k[k]++;
      int found = 0;
      for (int o = 0; o < n && !found; o++)
        found = out[o].n_turns == k && passes(&m, &out[o], r[0], 1e-5 * scale);
      if (!found) {
        missed++;
        printf("missed: set %d {chi %.17g, eta %.17g, us %.17g, ur %.17g}: an "
               "attractor of %d returns through (x1, x1') = (%.9g, %.9g)\n",
               s, p.chi, p.eta, p.us, p.ur, k, r[0][0], r[0][1]);
      }
    }
  }
  printf("attractors: %d sets, %d attractors reached by rk8pd (period 1: %d, "
         "2: %d, 3-8: %d), %d runs not settled in 1500 time units, %d "
         "missed by the search\n",
         sets, attractors, by_k[1], by_k[2],
         by_k[3] + by_k[4] + by_k[5] + by_k[6] + by_k[7] + by_k[8], unsettled,
         missed);
  ASSERT_EQ_INT(missed, 0);
  free(ev);
  TEST_DONE();
}
