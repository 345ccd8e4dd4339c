/*
 * test_search.c: the default orbit search finds every slip-stick and
 * slip-overshoot-stick orbit that an independent brute-force search finds.
 *
 * On random parameter sets (chi 0.05-0.9, eta 0.2-20 and ur/us 1.5-20
 * log-uniform, us 0.02-0.3, V = 1) tests/ref/brute.c solves the two
 * families' duration equations from a dense grid over every duration in
 * (0, dmax], dmax = 1.5 slow modal periods, and keeps each root that its own
 * event-driven simulation confirms.  Each of them must be among the orbits
 * the default search returns (same sequence, durations within 1e-6, and
 * spectral radii within 1e-4); each orbit of those families the search
 * returns with every duration within the box must be one of them.  Counts,
 * misses and times are printed.
 * Each family's proof (ss_orbit_opts.certify) must complete on every set,
 * and then hold every brute-force orbit of the family in its box and no
 * orbit the brute force lacks.
 * Usage: test_search [first [sets]]: the sets first to first + sets - 1 of
 * the battery's 40 (default: all of them; tests/CMakeLists.txt runs pieces
 * of 4, CTest core_search_<first>).  The piece from set 0 also runs
 * the checks below of the search's budget, report and work, and two fixed
 * sets before the random ones.  Environment:
 *   SS_SEARCH_SETS=n  only the first n sets of each half of the battery
 *                     (sets 0 to n-1 and 20 to 19+n); the sanitizer and
 *                     shared-library runs take a few;
 *   SS_SLOW_PROOFS=0  no slip-overshoot-stick proof (seconds a set here,
 *                     under the sanitizers an hour in all); the slip-stick
 *                     proof still runs on every set.
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_errno.h>

#include "battery.h"
#include "brute.h"
#include "stickslip.h"
#include "test.h"

#define MAXO 128
#define MAXB 64

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Is search orbit o the brute-force orbit b? */
static int same(const ss_orbit *o, const brute_orbit *b) {
  if (o->n_turns != 1 || o->n_phases != b->n_phases)
    return 0;
  static const ss_mode seq[2][3] = {
      {SS_MODE_SLIP, SS_MODE_STICK, SS_MODE_STICK},
      {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK}};
  for (int k = 0; k < b->n_phases; k++)
    if (o->modes[k] != seq[b->n_phases - 2][k] ||
        fabs(o->durations[k] - b->dur[k]) > 1e-6 * (1 + b->period))
      return 0;
  return 1;
}

/* brute_orbits(), or its answer for set s from the file named by the
 * environment variable SS_BRUTE_CACHE (written there when absent): for
 * trying changes to the search without waiting for the brute force. */
static int cached_brute(const brute_params *bp, double dmax, brute_orbit *bo,
                        int max, int s) {
  const char *dir = getenv("SS_BRUTE_CACHE");
  char path[512];
  if (dir) {
    snprintf(path, sizeof path, "%s/set%d.bin", dir, s);
    FILE *f = fopen(path, "rb");
    if (f) {
      int n = 0;
      if (fread(&n, sizeof n, 1, f) != 1 || n < 0 || n > max ||
          fread(bo, sizeof *bo, (size_t)n, f) != (size_t)n)
        n = -1;
      fclose(f);
      return n;
    }
  }
  int n = brute_orbits(bp, dmax, bo, max);
  if (dir && n >= 0) {
    FILE *f = fopen(path, "wb");
    if (f) {
      fwrite(&n, sizeof n, 1, f);
      fwrite(bo, sizeof *bo, (size_t)n, f);
      fclose(f);
    }
  }
  return n;
}

/* A search whose scan would take over a second (chi = eta = 0.01: the slow
 * period is 630, the box 940 wide, at 1000 cells a side) stops within its
 * budget: the scan polls it once per row. */
static void test_budget(void) {
  ss_params p = {0.01, 0.01, 0.1, 1, 1};
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  ss_orbit_opts oo;
  memset(&oo, 0, sizeof oo);
  oo.max_seconds = 0.05;
  oo.kinds = SS_ORBIT_OVERSHOOT;
  static ss_orbit out[MAXO];
  int n = 0;
  double t0 = now();
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, NULL, NULL),
                SS_ELIMIT_TIME);
  double t = now() - t0;
  printf("budget 0.05 s: the search stopped after %.3f s\n", t);
  ASSERT_TRUE(t < 0.5);
}

/* The report says which box the scan covered, and at which step: 1.5 slow
 * modal periods at 0.3 rad of the fastest motion, the step widened to keep
 * 1000 cells a side; nothing when there was no scan. */
static void test_scan_report(void) {
  const double two_pi = 6.283185307179586;
  ss_params ps[2] = {{0.2, 4, 0.0724, 0.6178, 1}, {0.01, 0.01, 0.1, 1, 1}};
  static ss_orbit out[MAXO];
  for (int i = 0; i < 2; i++) {
    ss_model m;
    ASSERT_EQ_INT(ss_model_init(&m, &ps[i], NULL), SS_OK);
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    oo.kinds = SS_ORBIT_STICKSLIP;
    ss_orbit_report rep;
    int n = 0;
    ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, &rep, NULL), SS_OK);
    double box = 1.5 * two_pi / m.w[0];
    ASSERT_NEAR(rep.scan_box, box, 1e-12 * box);
    double step = 0.3 / fmax(m.w[1], 1);
    if (i == 0) /* the box a whole number of steps */
      ASSERT_NEAR(rep.scan_step, box / ceil(box / step), 1e-15 * box);
    else /* 940 wide: 1000 cells */
      ASSERT_NEAR(rep.scan_step, box / 1000, 1e-15 * box);
    printf("scan: box %.6g, step %.6g (%.0f cells a side)\n", rep.scan_box,
           rep.scan_step, rep.scan_box / rep.scan_step);
    if (i)
      continue;
    /* from a guess, or for other sequences only: no scan */
    oo.kinds = SS_ORBIT_OTHER;
    ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, &rep, NULL), SS_OK);
    ASSERT_TRUE(rep.scan_box == 0 && rep.scan_step == 0);
    oo.kinds = 0;
    oo.n_guess = 3;
    oo.guess[0] = 4.5;
    oo.guess[1] = 2.7;
    oo.guess[2] = 3.0;
    ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, &rep, NULL), SS_OK);
    ASSERT_TRUE(rep.scan_box == 0 && rep.scan_step == 0);
  }
}

/* The scan's work where it is largest on the overshoot map (chi 0.96, ur/us
 * 15: the slow period 35, the box 52.7 wide, 386 cells a side): most roots
 * of the reduced slip-overshoot-stick equations there have a slip that
 * reaches x2' = V before its end (4201 of the 4391 in the box, none an
 * orbit), and a cell whose every start breaks the slip's rule at one grid time
 * before it is passed over; so is a cell that a pole of the stick's
 * duration crosses where its numerator keeps its sign.  Measured: 6766
 * Newton starts and 469k cells; without the first rule 128708 starts and
 * 2.10M cells, without the second 737k cells.  The bounds leave a margin of
 * a fifth; test_existence and the brute force below check that nothing is
 * lost. */
static void test_scan_work(void) {
  ss_params p = {0.96, 4, 0.0724, 0.0724 * 15, 1};
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  ss_orbit_opts oo;
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_OVERSHOOT;
  static ss_orbit out[MAXO];
  ss_orbit_report rep;
  int n = 0;
  ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, &rep, NULL), SS_OK);
  printf("scan at chi 0.96, ur/us 15: %d Newton starts, %ld cells, %d "
         "orbits\n",
         rep.newton_starts, rep.scan_cells, n);
  ASSERT_TRUE(rep.newton_starts < 8200);
  ASSERT_TRUE(rep.scan_cells < 563000);
}

/* A simulation stops once it comes within 1e-7 of the scale of a stable
 * orbit already found (its returns compared on Sigma0, in z): the paper's
 * set has two stable orbits and 12 simulations, so most of them do. */
static void test_simulations_known(void) {
  ss_params p = {0.2, 4, 0.0724, 0.6178, 1};
  ss_model m;
  ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
  static ss_orbit out[MAXO];
  ss_orbit_report rep;
  int n = 0;
  ASSERT_EQ_INT(ss_orbit_find(&m, NULL, out, MAXO, &n, &rep, NULL), SS_OK);
  printf("paper's set: %d simulations, %d stopped on an orbit found\n",
         rep.simulations, rep.simulations_known);
  ASSERT_TRUE(rep.simulations_known >= rep.simulations / 2);
}

/* The battery's halves, of which SS_SEARCH_SETS takes the first sets. */
#define HALF 20

int main(int argc, char **argv) {
  const char *env = getenv("SS_SEARCH_SETS");
  const char *slow = getenv("SS_SLOW_PROOFS");
  int first = argc > 1 ? atoi(argv[1]) : 0;
  int range = argc > 2 ? atoi(argv[2]) : 2 * HALF;
  int per_half = env && atoi(env) > 0 && atoi(env) < HALF ? atoi(env) : HALF;
  int families = slow && strcmp(slow, "0") == 0 ? 1 : 2;
  gsl_set_error_handler_off();
  if (first == 0) {
    test_budget();
    test_scan_report();
    test_scan_work();
    test_simulations_known();
  }
  int total = 0, stable = 0, missed = 0, missed_stable = 0, extra = 0;
  int radius_off = 0, certified[2] = {0, 0}, cert_missed = 0, cert_extra = 0;
  double cert_time[2] = {0, 0};
  double *times = calloc((size_t)(range > 0 ? range : 1), sizeof *times);
  int sets = 0; /* of the random ones, taken */
  double brute_time = 0;
  /* before the random sets of the first half: the example (a
   * stick-slip orbit of durations about [5.64122, 0.55821] that the former
   * search missed at every effort), and the paper's parameters */
  static const ss_params fixed[] = {{0.2759, 0.3357, 0.1833, 1.0572, 1},
                                    {0.2, 4, 0.0724, 0.6178, 1}};
  int n_fixed = first == 0 ? 2 : 0;
  battery bt;
  battery_init(&bt);
  for (int s = -n_fixed; s < first + range; s++) {
    ss_params p;
    if (s < 0) {
      p = fixed[s + n_fixed];
    } else {
      double q[5];
      battery_next(&bt, q);
      p = (ss_params){q[0], q[1], q[2], q[3], q[4]};
    }
    if (s >= 0 && (s < first || s % HALF >= per_half))
      continue;
    int slot = s >= 0 ? sets++ : -1; /* its place in times */
    brute_params bp = {p.chi, p.eta, p.us, p.ur, p.V};
    double dmax = brute_dmax(&bp);
    brute_orbit bo[MAXB];
    double t0 = now();
    int nb = cached_brute(&bp, dmax, bo, MAXB, s);
    double tb = now() - t0;
    brute_time += tb;
    printf("set %d: chi %.4f eta %.4f us %.4f ur %.4f: brute force %.2f s\n", s,
           p.chi, p.eta, p.us, p.ur, tb);
    fflush(stdout);
    ASSERT_TRUE(nb >= 0 && nb <= MAXB);
    if (nb < 0)
      continue;

    ss_model m;
    ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    static ss_orbit out[MAXO];
    int n = 0;
    t0 = now();
    ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, NULL, NULL), SS_OK);
    double ts = now() - t0;
    if (slot >= 0)
      times[slot] = ts;
    printf("set %d: %d orbits by brute force, %d by the search (%.2f ms)\n", s,
           nb, n, 1e3 * ts);
    fflush(stdout);

    for (int i = 0; i < nb; i++) {
      total++;
      int st = bo[i].radius < 1 - 1e-4;
      stable += st;
      int found = -1;
      for (int o = 0; o < n && found < 0; o++)
        if (same(&out[o], &bo[i]))
          found = o;
      if (found < 0) {
        missed++;
        missed_stable += st;
        printf("missed: set %d {\"chi\": %.17g, \"eta\": %.17g, \"us\": "
               "%.17g, \"ur\": %.17g}: %s durations [%.9g, %.9g, %.9g] "
               "radius %.6f margin %.3g\n",
               s, p.chi, p.eta, p.us, p.ur,
               bo[i].n_phases == 2 ? "slip-stick" : "slip-overshoot-stick",
               bo[i].dur[0], bo[i].dur[1],
               bo[i].n_phases == 3 ? bo[i].dur[2] : 0.0, bo[i].radius,
               bo[i].margin);
      } else if (fabs(out[found].stab.spectral_radius - bo[i].radius) >
                 1e-4 * fmax(1, bo[i].radius)) {
        radius_off++;
        printf("radius: set %d: search %.9g, brute force %.9g\n", s,
               out[found].stab.spectral_radius, bo[i].radius);
      }
    }
    /* the proof of each family (a search for that kind alone): when it
     * says complete, every brute-force orbit of the family in its box is
     * returned, and every orbit of that kind returned in the box is one of
     * the brute force's */
    for (int f = 0; f < families; f++) {
      static const char *name[2] = {"slip-stick", "slip-overshoot-stick"};
      int np = 2 + f;
      ss_orbit_opts oc;
      memset(&oc, 0, sizeof oc);
      oc.kinds = f ? SS_ORBIT_OVERSHOOT : SS_ORBIT_STICKSLIP;
      oc.certify = 1;
      oc.certify_seconds = 600;
      static ss_orbit outc[MAXO];
      ss_orbit_report rc;
      int nc = 0;
      ASSERT_EQ_INT(ss_orbit_find(&m, &oc, outc, MAXO, &nc, &rc, NULL), SS_OK);
      const ss_family_cert *fc = &rc.cert[f];
      printf("set %d: %s proof %s, %d roots, %d orbits, %d added, %ld boxes, "
             "%.2f s\n",
             s, name[f], fc->complete ? "complete" : "not complete", fc->roots,
             fc->orbits, fc->added, fc->boxes, fc->seconds);
      certified[f] += fc->complete;
      cert_time[f] += fc->seconds;
      for (int i = 0; i < nb && fc->complete; i++) {
        int in_box = bo[i].n_phases == np && bo[i].s[0] >= fc->x1_lo &&
                     bo[i].s[0] <= fc->x1_hi && bo[i].s[1] >= fc->v1_lo &&
                     bo[i].s[1] <= fc->v1_hi;
        for (int k = 0; k < np && in_box; k++)
          in_box = bo[i].dur[k] >= fc->duration_lo[k];
        if (!in_box)
          continue;
        int found = 0;
        for (int o = 0; o < nc && !found; o++)
          found = same(&outc[o], &bo[i]);
        if (!found) {
          cert_missed++;
          printf("proved complete, yet missed: set %d %s durations [%.9g, "
                 "%.9g, %.9g]\n",
                 s, name[f], bo[i].dur[0], bo[i].dur[1],
                 np == 3 ? bo[i].dur[2] : 0.0);
        }
      }
      for (int o = 0; o < nc; o++) {
        int found = 0, inside = 1;
        for (int i = 0; i < nb && !found; i++)
          found = same(&outc[o], &bo[i]);
        for (int k = 0; k < outc[o].n_phases; k++)
          inside = inside && outc[o].durations[k] <= dmax;
        if (!found && inside) {
          cert_extra++;
          printf("proved, not in the brute force: set %d %s durations "
                 "[%.9g, %.9g, %.9g]\n",
                 s, name[f], outc[o].durations[0], outc[o].durations[1],
                 outc[o].n_phases == 3 ? outc[o].durations[2] : 0.0);
        }
      }
    }
    /* the other way round: within the box, nothing the brute force lacks */
    for (int o = 0; o < n; o++) {
      const ss_orbit *q = &out[o];
      if (q->n_turns != 1 ||
          (q->kind != SS_ORBIT_STICKSLIP && q->kind != SS_ORBIT_OVERSHOOT))
        continue;
      int inside = 1;
      for (int k = 0; k < q->n_phases; k++)
        inside = inside && q->durations[k] <= dmax;
      if (!inside)
        continue;
      int found = 0;
      for (int i = 0; i < nb && !found; i++)
        found = same(q, &bo[i]);
      if (!found) {
        extra++;
        printf("not in the brute force: set %d: %d phases, durations [%.9g, "
               "%.9g, %.9g], min margin %.3g\n",
               s, q->n_phases, q->durations[0], q->durations[1],
               q->n_phases == 3 ? q->durations[2] : 0.0, q->min_margin.value);
      }
    }
  }
  if (sets > 0) {
    qsort(times, (size_t)sets, sizeof *times, cmp_double);
    printf("search: %d sets, %d orbits by brute force (%d stable), %d missed "
           "by the default search (%d stable), %d returned that the brute "
           "force lacks, %d radii off; search median %.2f ms, worst %.2f ms; "
           "brute force %.1f s\n",
           sets, total, stable, missed, missed_stable, extra, radius_off,
           1e3 * times[sets / 2], 1e3 * times[sets - 1], brute_time);
  }
  printf("proofs: slip-stick %d of %d sets complete (%.1f s in all), "
         "slip-overshoot-stick %d (%.1f s); %d brute-force orbits missed "
         "where complete, %d proved orbits the brute force lacks\n",
         certified[0], sets + n_fixed, cert_time[0], certified[1], cert_time[1],
         cert_missed, cert_extra);
  ASSERT_EQ_INT(certified[0], sets + n_fixed);
  ASSERT_EQ_INT(certified[1], families == 2 ? sets + n_fixed : 0);
  ASSERT_EQ_INT(cert_missed, 0);
  ASSERT_EQ_INT(cert_extra, 0);
  ASSERT_EQ_INT(missed, 0);
  ASSERT_EQ_INT(extra, 0);
  ASSERT_EQ_INT(radius_off, 0);
  free(times);
  TEST_DONE();
}
