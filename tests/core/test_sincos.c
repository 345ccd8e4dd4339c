/*
 * test_sincos.c: the closed forms' inline sin and cos (core/src/sincos.h)
 * against the C library's long-double sinl and cosl: within one ulp over
 * the arguments the model meets (modal phases up to 2^20 pi/2) and next to
 * the multiples of pi/2 where the reduction cancels, and the C library's
 * own answer beyond that range and for non-finite arguments.
 */
#define _GNU_SOURCE
#include <float.h>
#include <stdio.h>

#include "../core/src/sincos.h"
#include "test.h"

static double ulps(double got, long double want) {
  double w = (double)want;
  double ulp = nextafter(fabs(w), INFINITY) - fabs(w);
  return (double)fabsl(got - want) / ulp;
}

static double worst;
static double worst_x;

static void check(double x) {
  double s, c;
  ss__sincos(x, &s, &c);
  double e = fmax(ulps(s, sinl(x)), ulps(c, cosl(x)));
  if (e > worst) {
    worst = e;
    worst_x = x;
  }
}

int main(void) {
  unsigned long seed = 7;
  const double range[] = {1e-9, 0.5, 1, 4, 30, 1e3, 1e5, 1.6e6};
  for (int r = 0; r < 8; r++)
    for (int i = 0; i < 250000; i++) {
      seed = seed * 6364136223846793005UL + 1442695040888963407UL;
      double u = (double)(seed >> 11) / 9007199254740992.0;
      check((2 * u - 1) * range[r]);
    }
  /* next to k pi/2, where x - k pi/2 cancels: a few ulps either side */
  for (long k = -20000; k <= 20000; k++) {
    double x = (double)k * 1.57079632679489661923;
    for (int d = 0; d < 4; d++) {
      check(x);
      x = nextafter(x, INFINITY);
    }
  }
  /* up to the end of the range */
  for (double x = 1e5; x < 1647099.0; x *= 1.01)
    check(x);
  printf("ss__sincos: largest error %.3f ulp (at %.17g)\n", worst, worst_x);
  ASSERT_TRUE(worst < 1.0);
  /* beyond the range and non-finite: the C library's answers */
  double big[] = {1.7e6, 1e22, -3e300, INFINITY, -INFINITY, NAN};
  for (int i = 0; i < 6; i++) {
    double s, c;
    ss__sincos(big[i], &s, &c);
    if (isnan(sin(big[i]))) {
      ASSERT_TRUE(isnan(s) && isnan(c));
    } else {
      ASSERT_TRUE(s == sin(big[i]) && c == cos(big[i]));
    }
  }
  /* the quadrants' signs: exact values where they are exact */
  double s, c;
  ss__sincos(0, &s, &c);
  ASSERT_TRUE(s == 0 && c == 1);
  ss__sincos(-0.0, &s, &c);
  ASSERT_TRUE(s == 0 && c == 1);
  TEST_DONE();
}
