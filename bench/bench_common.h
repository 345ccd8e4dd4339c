/*
 * bench_common.h: timing helpers for the benchmarks (they report; they do
 * not gate).  CPU time per run is the median over repeated runs.
 */
#ifndef SS_BENCH_COMMON_H
#define SS_BENCH_COMMON_H

#define _GNU_SOURCE
#include <stdlib.h>
#include <time.h>

static inline double cpu_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline int cmp_dbl(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

static inline double median(double *v, int n) {
  qsort(v, (size_t)n, sizeof *v, cmp_dbl);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

#endif
