/*
 * test_box.c: the box of the search grows where the motion shows longer
 * phases, and every answer says which box it covered.
 *
 * First the set where a stable slip-stick orbit slips longer than the
 * default box of 1.5 slow modal periods (chi 0.1283, eta 7.2748, us 0.0951,
 * ur 0.3825: durations [13.75842, 4.72384], spectral radius 0.974, the box
 * 11.98): the search with no guess, for the kind stick-slip, returns it at
 * every effort, reports a box grown to cover it (the same at every effort,
 * within its cap), and the proof of the slip-stick family covers the same
 * box, holds the orbit and is complete.  Then a seeded random draw of its
 * own (the search battery's ranges: chi 0.05-0.9, eta 0.2-20 and ur/us
 * 1.5-20 log-uniform, us 0.02-0.3, V = 1) against the brute force of
 * tests/ref/brute.c over a box twice the default (the cap): every
 * brute-force orbit with each duration within the box the search reports is
 * returned; those beyond it are counted and printed.
 * Usage: test_box [sets]: 6 sets by default; 2 with SS_SLOW_PROOFS=0 (the
 * sanitizer runs).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "battery.h"
#include "brute.h"
#include "stickslip.h"
#include "test.h"

#define MAXO 128
#define MAXB 128
#define TWO_PI 6.283185307179586

/* Is search orbit o the brute-force orbit b? */
static int same(const ss_orbit *o, const brute_orbit *b) {
  static const ss_mode seq[2][3] = {
      {SS_MODE_SLIP, SS_MODE_STICK, SS_MODE_STICK},
      {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK}};
  if (o->n_turns != 1 || o->n_phases != b->n_phases)
    return 0;
  for (int k = 0; k < b->n_phases; k++)
    if (o->modes[k] != seq[b->n_phases - 2][k] ||
        fabs(o->durations[k] - b->dur[k]) > 1e-6 * (1 + b->period))
      return 0;
  return 1;
}

/* The orbit [13.75842, 4.72384] among out, or NULL. */
static const ss_orbit *long_slip_orbit(const ss_orbit *out, int n) {
  for (int i = 0; i < n; i++)
    if (out[i].n_phases == 2 && fabs(out[i].durations[0] - 13.75842) < 1e-5 &&
        fabs(out[i].durations[1] - 4.72384) < 1e-5)
      return &out[i];
  return NULL;
}

/* EVIDENCE: docs/checked/index.md "Every slip-stick and slip-overshoot-stick
 * orbit in a box": the box grows to a periodic motion's longer phases, and
 * search.scan and search.certificate report the box covered. */
static void test_long_slip(void) {
  ss_params p = {0.1283, 7.2748, 0.0951, 0.3825, 1};
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  double box = 1.5 * TWO_PI / m.w[0], cap = 3 * TWO_PI / m.w[0];
  double grown = 0;
  static ss_orbit out[MAXO];
  for (int e = 1; e <= 3; e++) {
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    oo.kinds = SS_ORBIT_STICKSLIP;
    oo.effort = e;
    ss_orbit_report rep;
    int n = 0;
    ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, &rep, NULL), SS_OK);
    const ss_orbit *o = long_slip_orbit(out, n);
    printf("long slip, effort %d: %d orbits, box %.6g (default %.6g, cap "
           "%.6g), [13.75842, 4.72384] %s\n",
           e, n, rep.scan_box, box, rep.scan_box_cap, o ? "found" : "MISSING");
    ASSERT_TRUE(o != NULL);
    if (!o)
      continue;
    ASSERT_TRUE(o->stab.stable);
    ASSERT_NEAR(o->stab.spectral_radius, 0.974, 1e-3);
    /* the box holds the orbit's slip, within the cap, at every effort */
    ASSERT_NEAR(rep.scan_box_cap, cap, 1e-12 * cap);
    ASSERT_TRUE(rep.scan_box > 13.75842 && rep.scan_box <= cap);
    if (e == 1)
      grown = rep.scan_box;
    ASSERT_TRUE(rep.scan_box == grown);
  }
  /* the proof covers the box the scan covered, and the orbit in it */
  ss_orbit_opts oc;
  memset(&oc, 0, sizeof oc);
  oc.kinds = SS_ORBIT_STICKSLIP;
  oc.certify = 1;
  oc.certify_seconds = 600;
  ss_orbit_report rc;
  int n = 0;
  ASSERT_EQ_INT(ss_orbit_find(&m, &oc, out, MAXO, &n, &rc, NULL), SS_OK);
  const ss_family_cert *fc = &rc.cert[0];
  printf("long slip, proof: %s, box %.6g x %.6g, %d roots, %d orbits, %d "
         "added, %.2f s\n",
         fc->complete ? "complete" : fc->why, fc->duration_hi[0],
         fc->duration_hi[1], fc->roots, fc->orbits, fc->added, fc->seconds);
  ASSERT_TRUE(fc->ran && fc->complete);
  ASSERT_TRUE(fc->duration_hi[0] == rc.scan_box &&
              fc->duration_hi[1] == rc.scan_box);
  ASSERT_TRUE(long_slip_orbit(out, n) != NULL);
  /* the brute force's three orbits over twice the box, all in it */
  ASSERT_EQ_INT(fc->orbits, 3);
}

/* EVIDENCE: docs/checked/index.md "Every slip-stick and slip-overshoot-stick
 * orbit in a box": every orbit of the two families in the box the search
 * reports is returned, on a draw of its own against a longer brute force. */
static void test_draw(int sets) {
  battery bt = {0x626f78};
  int in_box = 0, beyond_default = 0, beyond = 0, missing = 0, grown = 0;
  static ss_orbit out[MAXO];
  static brute_orbit bo[MAXB];
  for (int s = 0; s < sets; s++) {
    double q[5];
    battery_next(&bt, q);
    ss_params p = {q[0], q[1], q[2], q[3], q[4]};
    ss_model m;
    ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
    ss_orbit_report rep;
    int n = 0;
    ASSERT_EQ_INT(ss_orbit_find(&m, NULL, out, MAXO, &n, &rep, NULL), SS_OK);
    brute_params bp = {p.chi, p.eta, p.us, p.ur, p.V};
    double box = brute_dmax(&bp);
    int nb = brute_orbits(&bp, 2 * box, bo, MAXB);
    ASSERT_TRUE(nb >= 0 && nb <= MAXB);
    grown += rep.scan_box > box * (1 + 1e-12);
    printf("set %d: chi %.4f eta %.4f us %.4f ur %.4f: box %.6g (default "
           "%.6g), %d orbits, %d by the brute force over %.6g\n",
           s, p.chi, p.eta, p.us, p.ur, rep.scan_box, box, n, nb, 2 * box);
    for (int i = 0; i < nb; i++) {
      double longest = 0;
      for (int k = 0; k < bo[i].n_phases; k++)
        longest = fmax(longest, bo[i].dur[k]);
      int found = 0;
      for (int j = 0; j < n && !found; j++)
        found = same(&out[j], &bo[i]);
      beyond_default += longest > box;
      if (longest > rep.scan_box) {
        beyond++;
        printf("  beyond the box: [%.6f, %.6f%s], radius %.4f, %s\n",
               bo[i].dur[0], bo[i].dur[1], bo[i].n_phases == 3 ? ", ..." : "",
               bo[i].radius, found ? "found" : "not found");
        continue;
      }
      in_box++;
      if (!found) {
        missing++;
        printf("  MISSING in the box: [%.6f, %.6f%s], radius %.4f\n",
               bo[i].dur[0], bo[i].dur[1], bo[i].n_phases == 3 ? ", ..." : "",
               bo[i].radius);
      }
    }
  }
  printf("random draw: %d sets, %d boxes grown, %d brute-force orbits in the "
         "box (%d beyond the default box), %d beyond it, %d missing\n",
         sets, grown, in_box, beyond_default, beyond, missing);
  ASSERT_EQ_INT(missing, 0);
  ASSERT_TRUE(in_box > sets);
}

int main(int argc, char **argv) {
  const char *slow = getenv("SS_SLOW_PROOFS");
  int sets = slow && strcmp(slow, "0") == 0 ? 2 : 6;
  if (argc > 1)
    sets = atoi(argv[1]);
  gsl_set_error_handler_off();
  test_long_slip();
  test_draw(sets);
  TEST_DONE();
}
