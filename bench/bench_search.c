/*
 * bench_search.c: the default orbit search with no guess over the parameter
 * battery of tests/core/test_search.c (the same 40 random sets, the same
 * generator): the CPU time of each set (median of 5 runs), and the median
 * and worst over the battery, for the default effort and for effort 1 and
 * 3; then the cost of the proof that each family is complete
 * (ss_orbit_opts.certify, one run per set: it takes seconds), and what it
 * proved.  Writes results/search.md.
 * Usage: bench_search [results-dir]
 */
#include "bench_common.h"
#include "battery.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "stickslip.h"

#define SETS 40
#define REPS 5
#define MAXO 128

int main(int argc, char **argv) {
  ss_params ps[SETS];
  battery bt;
  battery_init(&bt);
  for (int s = 0; s < SETS; s++) {
    double q[5];
    battery_next(&bt, q);
    ps[s] = (ss_params){q[0], q[1], q[2], q[3], q[4]};
  }
  char path[512];
  snprintf(path, sizeof path, "%s/search.md", argc > 1 ? argv[1] : ".");
  FILE *f = fopen(path, "w");
  if (!f) {
    perror(path);
    return 1;
  }
  fprintf(f,
          "# The orbit search with no guess over the test battery\n\n"
          "CPU time of `ss_orbit_find` (all kinds, max_period 4) on the "
          "40 random parameter sets of tests/core/test_search.c, each the "
          "median of %d runs; one run of bench_search.\n\n"
          "| effort | median | worst | orbits returned in all |\n"
          "|---|---|---|---|\n",
          REPS);
  static ss_orbit out[MAXO];
  for (int effort = 1; effort <= 3; effort++) {
    double per[SETS];
    int total = 0;
    for (int s = 0; s < SETS; s++) {
      ss_model m;
      if (ss_model_init(&m, &ps[s], NULL) != SS_OK)
        return 1;
      ss_orbit_opts oo;
      memset(&oo, 0, sizeof oo);
      oo.effort = effort;
      double t[REPS];
      int n = 0;
      for (int r = 0; r < REPS; r++) {
        double t0 = cpu_now();
        if (ss_orbit_find(&m, &oo, out, MAXO, &n, NULL, NULL) != SS_OK)
          return 1;
        t[r] = cpu_now() - t0;
      }
      per[s] = median(t, REPS);
      total += n;
    }
    double worst = 0;
    for (int s = 0; s < SETS; s++)
      worst = fmax(worst, per[s]);
    double med = median(per, SETS);
    printf("effort %d: median %.2f ms, worst %.2f ms, %d orbits\n", effort,
           1e3 * med, 1e3 * worst, total);
    fprintf(f, "| %d%s | %.2f ms | %.2f ms | %d |\n", effort,
            effort == 2 ? " (default)" : "", 1e3 * med, 1e3 * worst, total);
  }
  /* the proof of each family, over and above the search */
  fprintf(f, "\n## The proof that each family is complete\n\n"
             "`ss_orbit_opts.certify` with `kinds` the family alone (the "
             "search itself then skips the other kinds' sources), wall time "
             "of the proof alone (`ss_family_cert.seconds`), one run per "
             "set, on the same machine right after the searches above.\n\n"
             "| family | median | worst | boxes, median | boxes, worst | "
             "complete | roots proved | orbits | added by the proof |\n"
             "|---|---|---|---|---|---|---|---|---|\n");
  static const char *name[2] = {"slip-stick", "slip-overshoot-stick"};
  for (int fam = 0; fam < 2; fam++) {
    double cs[SETS], boxes[SETS];
    int complete = 0, roots = 0, orbits = 0, added = 0;
    for (int s = 0; s < SETS; s++) {
      ss_model m;
      if (ss_model_init(&m, &ps[s], NULL) != SS_OK)
        return 1;
      ss_orbit_opts oo;
      memset(&oo, 0, sizeof oo);
      oo.kinds = fam ? SS_ORBIT_OVERSHOOT : SS_ORBIT_STICKSLIP;
      oo.certify = 1;
      oo.certify_seconds = 600;
      ss_orbit_report rep;
      int n = 0;
      if (ss_orbit_find(&m, &oo, out, MAXO, &n, &rep, NULL) != SS_OK)
        return 1;
      const ss_family_cert *fc = &rep.cert[fam];
      cs[s] = fc->seconds;
      boxes[s] = (double)fc->boxes;
      complete += fc->complete;
      roots += fc->roots;
      orbits += fc->orbits;
      added += fc->added;
    }
    double cworst = 0, bworst = 0;
    for (int s = 0; s < SETS; s++) {
      cworst = fmax(cworst, cs[s]);
      bworst = fmax(bworst, boxes[s]);
    }
    double cmed = median(cs, SETS), bmed = median(boxes, SETS);
    printf("%s proof: median %.2f s, worst %.2f s; %d of %d complete, %d "
           "roots, %d orbits, %d added\n",
           name[fam], cmed, cworst, complete, SETS, roots, orbits, added);
    fprintf(f,
            "| %s | %.2f s | %.2f s | %.0f | %.0f | %d of %d | %d | %d | %d "
            "|\n",
            name[fam], cmed, cworst, bmed, bworst, complete, SETS, roots,
            orbits, added);
  }
  fclose(f);
  return 0;
}
