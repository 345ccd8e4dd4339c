/*
 * test_effort.c: more effort only adds: every orbit the search returns at
 * effort k it returns at effort k + 1 too.
 *
 * First a set where effort 3 lost the stable slip-stick orbit of durations
 * about [6.12159, 0.09484] that efforts 1 and 2 found (its stick is short,
 * so near it the duration equations depend on the period t1 + t2 almost
 * alone and their zero lines run side by side through one cell of the finer
 * grid).  Then a seeded random draw of its own (the search battery's ranges:
 * chi 0.05-0.9, eta 0.2-20 and ur/us 1.5-20 log-uniform, us 0.02-0.3,
 * V = 1, from another seed), each set searched for each kind (all, overshoot,
 * stick-slip, other) at efforts 1, 2 and 3: each orbit of effort k must be
 * among those of effort k + 1 (same kind and phase sequence, up to the
 * stick -> slip point it starts at, durations within 1e-6 of the period).
 * Usage: test_effort [sets]: 20 sets by default (about 10 s of CPU in the
 * optimised build); 4 with SS_SLOW_PROOFS=0 (the sanitizer runs).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "battery.h"
#include "stickslip.h"
#include "test.h"

#define MAXO 128

/* Is b the orbit a, started at the same or another of its phases? */
static int same_orbit(const ss_orbit *a, const ss_orbit *b) {
  int n = a->n_phases;
  if (a->kind != b->kind || n != b->n_phases ||
      !(fabs(a->period - b->period) <= 1e-6 * (1 + a->period)))
    return 0;
  for (int r = 0; r < n; r++) {
    int ok = 1;
    for (int k = 0; k < n && ok; k++)
      ok = a->modes[k] == b->modes[(k + r) % n] &&
           fabs(a->durations[k] - b->durations[(k + r) % n]) <=
               1e-6 * (1 + a->period);
    if (ok)
      return 1;
  }
  return 0;
}

static void print_orbit(const char *what, const ss_orbit *o) {
  printf("  %s: %s,", what, ss_orbit_kind_name(o->kind));
  for (int k = 0; k < o->n_phases; k++)
    printf(" %s %.6f", ss_mode_name(o->modes[k]), o->durations[k]);
  printf(", radius %.4f\n", o->stab.spectral_radius);
}

/* The search at efforts 1, 2, 3 for the kinds asked; 0 if each effort's
 * orbits are among the next one's, else the number missing (each printed). */
static int check_set(const ss_params *p, unsigned kinds, int *found) {
  static ss_orbit out[3][MAXO];
  int n[3], missing = 0;
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, p, NULL), SS_OK);
  for (int e = 0; e < 3; e++) {
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    oo.kinds = kinds;
    oo.effort = e + 1;
    n[e] = 0;
    ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out[e], MAXO, &n[e], NULL, NULL),
                  SS_OK);
  }
  for (int e = 0; e < 2; e++)
    for (int i = 0; i < n[e]; i++) {
      int in = 0;
      for (int j = 0; j < n[e + 1] && !in; j++)
        in = same_orbit(&out[e][i], &out[e + 1][j]);
      if (!in) {
        missing++;
        printf("chi %.17g eta %.17g us %.17g ur %.17g, kinds %u: effort %d "
               "lacks\n",
               p->chi, p->eta, p->us, p->ur, kinds, e + 2);
        print_orbit("found at the effort below", &out[e][i]);
      }
    }
  *found += n[2];
  return missing;
}

/* EVIDENCE: docs/checked/index.md: a higher
 * effort returns every orbit a lower one does, here where it did not. */
static void test_short_stick(void) {
  ss_params p = {0.3035, 0.2236, 0.0399, 0.2567, 1};
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  for (int e = 1; e <= 3; e++) {
    static ss_orbit out[MAXO];
    int n = 0, hit = 0;
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    oo.kinds = SS_ORBIT_STICKSLIP;
    oo.effort = e;
    ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, NULL, NULL), SS_OK);
    for (int i = 0; i < n; i++)
      if (out[i].n_phases == 2 && fabs(out[i].durations[0] - 6.12159) < 1e-5 &&
          fabs(out[i].durations[1] - 0.09484) < 1e-5) {
        hit = 1;
        ASSERT_TRUE(out[i].stab.stable);
        ASSERT_NEAR(out[i].stab.spectral_radius, 0.953, 1e-3);
      }
    printf("short stick, effort %d: %d orbits, [6.12159, 0.09484] %s\n", e, n,
           hit ? "found" : "MISSING");
    ASSERT_TRUE(hit);
  }
  int found = 0;
  ASSERT_EQ_INT(check_set(&p, SS_ORBIT_STICKSLIP, &found), 0);
}

/* EVIDENCE: docs/checked/index.md: a higher
 * effort returns every orbit a lower one does, on a draw of its own. */
static void test_draw(int sets) {
  static const unsigned kinds[4] = {SS_ORBIT_ALL, SS_ORBIT_OVERSHOOT,
                                    SS_ORBIT_STICKSLIP, SS_ORBIT_OTHER};
  battery bt = {999};
  int missing = 0, found = 0;
  for (int s = 0; s < sets; s++) {
    double q[5];
    battery_next(&bt, q);
    ss_params p = {q[0], q[1], q[2], q[3], q[4]};
    for (int k = 0; k < 4; k++)
      missing += check_set(&p, kinds[k], &found);
  }
  printf("random draw: %d sets, 4 kinds each, %d orbits at effort 3, %d "
         "missing from a higher effort\n",
         sets, found, missing);
  ASSERT_EQ_INT(missing, 0);
  ASSERT_TRUE(found > sets);
}

int main(int argc, char **argv) {
  const char *slow = getenv("SS_SLOW_PROOFS");
  int sets = slow && strcmp(slow, "0") == 0 ? 4 : 20;
  if (argc > 1)
    sets = atoi(argv[1]);
  gsl_set_error_handler_off();
  test_short_stick();
  test_draw(sets);
  TEST_DONE();
}
