/*
 * bench_basins.c: the basins of the paper's parameter set (ss_basins_run,
 * what POST /basins runs) over the slice x1 in [-2, 4], x2 in [0, 8],
 * x1' = 0, x2' = V: wall time on 1 and 2 threads (median of 5), time per
 * cell and per return.
 * Usage: bench_basins [results_dir] [n]   (n x n cells, default 256)
 */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "stickslip.h"

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

int main(int argc, char **argv) {
  const char *dir = argc > 1 ? argv[1] : NULL;
  int N = argc > 2 ? atoi(argv[2]) : 256;
  if (N < 2)
    N = 2;
  ss_params p = {0.2, 4, 0.0724, 0.6178, 1};
  ss_model m;
  ss_model_init(&m, &p, NULL);
  ss_basin_opts o;
  memset(&o, 0, sizeof o);
  o.vary[0] = 0;
  o.vary[1] = 1;
  o.from[0] = -2;
  o.to[0] = 4;
  o.from[1] = 0;
  o.to[1] = 8;
  o.n[0] = o.n[1] = N;
  o.state[3] = 1;
  double med[2];
  ss_basins b;
  for (int th = 1; th <= 2; th++) {
    double t[5];
    o.threads = th;
    for (int r = 0; r < 5; r++) {
      double t0 = now();
      ss_basins_run(&m, &o, &b, NULL);
      t[r] = now() - t0;
      if (!(th == 2 && r == 4))
        ss_basins_free(&b);
    }
    qsort(t, 5, sizeof t[0], cmp);
    med[th - 1] = t[2];
  }
  double cells = (double)N * N;
  char text[2048];
  int k = snprintf(
      text, sizeof text,
      "# Basins of attraction of the paper's parameter set\n\n"
      "%dx%d cells, x1 in [-2, 4], x2 in [0, 8], x1' = 0, x2' = V; wall "
      "time, median of 5.\n\n"
      "| threads | wall time | per cell | per return |\n|---|---|---|---|\n"
      "| 1 | %.3f s | %.2f us | %.0f ns |\n| 2 | %.3f s | %.2f us | %.0f ns "
      "|\n\n"
      "%ld returns to Sigma0 in all (%.1f per cell, at most %d to land); ",
      N, N, med[0], 1e6 * med[0] / cells, 1e9 * med[0] / (double)b.returns,
      med[1], 1e6 * med[1] / cells, 1e9 * med[1] / (double)b.returns, b.returns,
      (double)b.returns / cells, b.max_returns);
  for (int a = 0; a < b.n_attractors && k < (int)sizeof text - 200; a++) {
    const ss_basin_attractor *at = &b.attractors[a];
    k +=
        snprintf(text + k, sizeof text - (size_t)k,
                 "%s%s orbit of %d turns, period %.6g: %.1f%% of the cells "
                 "(radius %.3g, %d periods)",
                 a ? "; " : "", ss_orbit_kind_name(at->orbit.kind),
                 at->n_points, at->orbit.period,
                 100.0 * (double)at->cells / cells, at->radius, at->iterations);
  }
  snprintf(text + k, sizeof text - (size_t)k,
           "; %ld unresolved, %ld slipping for ever.\n", b.unresolved,
           b.perpetual);
  FILE *f = stdout;
  char path[512];
  if (dir) {
    snprintf(path, sizeof path, "%s/basins.md", dir);
    if (!(f = fopen(path, "w")))
      f = stdout;
  }
  fputs(text, f);
  if (f != stdout) {
    fclose(f);
    fputs(text, stdout);
  }
  ss_basins_free(&b);
  return 0;
}
