/*
 * brute_main.c: CLI for the brute-force orbit finder.
 *   brute chi eta us ur V
 * prints dmax, one line per feasible orbit of (A) slip-stick and
 * (B) slip-overshoot-stick, a refsim (GSL rk8pd) cross-check of each, and
 * the time taken by the search.
 */
#define _POSIX_C_SOURCE 199309L
#include "brute.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
  if (argc != 6) {
    fprintf(stderr, "usage: %s chi eta us ur V\n", argv[0]);
    return 2;
  }
  brute_params p;
  char *end;
  double *f[5] = {&p.chi, &p.eta, &p.us, &p.ur, &p.V};
  for (int i = 0; i < 5; i++) {
    *f[i] = strtod(argv[i + 1], &end);
    if (end == argv[i + 1] || *end) {
      fprintf(stderr, "bad number: %s\n", argv[i + 1]);
      return 2;
    }
  }
  double dmax = brute_dmax(&p);
  if (!(dmax > 0)) {
    fprintf(stderr, "inadmissible parameters\n");
    return 2;
  }
  enum { MAXO = 256 };
  static brute_orbit o[MAXO];
  double t0 = now();
  int n = brute_orbits(&p, dmax, o, MAXO);
  double t1 = now();
  if (n < 0) {
    fprintf(stderr, "brute_orbits failed\n");
    return 1;
  }
  printf("params chi=%g eta=%g us=%g ur=%g V=%g  dmax=%.10f  orbits=%d\n",
         p.chi, p.eta, p.us, p.ur, p.V, dmax, n);
  for (int i = 0; i < n && i < MAXO; i++) {
    const brute_orbit *q = &o[i];
    printf("%s dur=[", q->n_phases == 2 ? "A slip-stick          "
                                        : "B slip-overshoot-stick");
    for (int k = 0; k < q->n_phases; k++)
      printf("%s%.10f", k ? ", " : "", q->dur[k]);
    double derr;
    double rc = brute_refcheck(&p, q, &derr);
    printf("] period=%.10f s=[%.10f, %.10f] closure=%.2e margin=%.3e "
           "radius=%.6f refsim_closure=%.2e refsim_dur_err=%.2e\n",
           q->period, q->s[0], q->s[1], q->closure, q->margin, q->radius, rc,
           derr);
  }
  printf("time %.3f s (search)\n", t1 - t0);
  return 0;
}
