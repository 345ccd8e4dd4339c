/*
 * sincos.h: sin and cos of one argument together, inline, for the closed
 * forms' hot loops (every event search evaluates a few modal sinusoids at
 * each step, and the library's own sincos is an out-of-line call that must
 * handle every double).
 *
 * The arguments met here are modal phases w t of moderate size, so the
 * reduction by pi/2 is Cody and Waite's with pi/2 split in three parts of 33
 * bits (exact products for |n| < 2^20), refined only when the first
 * subtraction cancels, and the kernels are minimax polynomials on
 * [-pi/4, pi/4] that take the reduced argument as an unevaluated sum y0 + y1.
 * Both are those of FreeBSD's and musl's libm (__rem_pio2's medium case,
 * __sin, __cos), which descend from fdlibm:
 *
 *   Copyright (C) 1993 by Sun Microsystems, Inc. All rights reserved.
 *   Developed at SunPro, a Sun Microsystems, Inc. business.
 *   Permission to use, copy, modify, and distribute this software is freely
 *   granted, provided that this notice is preserved.
 *
 * Their error is below one ulp (test core_sincos compares with the C
 * library's over the whole range used); arguments beyond 2^20 pi/2, and
 * non-finite ones, go to the C library.
 */
#ifndef SS_SINCOS_H
#define SS_SINCOS_H

#include <math.h>
#include <stdint.h>
#include <string.h>

/* sin(y0 + y1) for |y0 + y1| <= pi/4 (fdlibm __kernel_sin with a tail) */
static inline double ss__ksin(double x, double y) {
  const double S1 = -1.66666666666666324348e-01,
               S2 = 8.33333333332248946124e-03,
               S3 = -1.98412698298579493134e-04,
               S4 = 2.75573137070700676789e-06,
               S5 = -2.50507602534068634195e-08,
               S6 = 1.58969099521155010221e-10;
  double z = x * x, w = z * z, v = z * x;
  double r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
  return x - ((z * (0.5 * y - v * r) - y) - v * S1);
}

/* cos(y0 + y1) for |y0 + y1| <= pi/4 (fdlibm __kernel_cos with a tail) */
static inline double ss__kcos(double x, double y) {
  const double C1 = 4.16666666666666019037e-02,
               C2 = -1.38888888888741095749e-03,
               C3 = 2.48015872894767294178e-05,
               C4 = -2.75573143513906633035e-07,
               C5 = 2.08757232129817482790e-09,
               C6 = -1.13596475577881948265e-11;
  double z = x * x, w = z * z;
  double r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
  double hz = 0.5 * z;
  w = 1.0 - hz;
  return w + (((1.0 - w) - hz) + (z * r - x * y));
}

static inline int ss__exponent(double x) {
  uint64_t u;
  memcpy(&u, &x, sizeof u);
  return (int)(u >> 52 & 0x7ff);
}

/* sin and cos of y + n pi/2 from those of y, without branches (the
 * quadrant of a modal phase is not predictable). */
static inline void ss__quadrant(int64_t n, double sn, double cs, double *s,
                                double *c) {
  uint64_t bs, bc, odd = -(uint64_t)(n & 1);
  memcpy(&bs, &sn, sizeof bs);
  memcpy(&bc, &cs, sizeof bc);
  uint64_t rs = ((bs & ~odd) | (bc & odd)) ^ ((uint64_t)(n & 2) << 62);
  uint64_t rc = ((bc & ~odd) | (bs & odd)) ^ ((uint64_t)((n + 1) & 2) << 62);
  memcpy(s, &rs, sizeof rs);
  memcpy(c, &rc, sizeof rc);
}

static inline void ss__sincos(double x, double *s, double *c) {
  const double toint = 6755399441055744.0, /* 1.5 * 2^52 */
      invpio2 = 6.36619772367581382433e-01, pio4 = 7.85398163397448278999e-01,
               pio2_1 = 1.57079632673412561417e+00,
               pio2_1t = 6.07710050650619224932e-11,
               pio2_2 = 6.07710050630396597660e-11,
               pio2_2t = 2.02226624879595063154e-21,
               pio2_3 = 2.02226624871116645580e-21,
               pio2_3t = 8.47842766036889956997e-32;
  if (!(fabs(x) <= 1647099.0)) { /* 2^20 pi/2 */
    *s = sin(x);
    *c = cos(x);
    return;
  }
  double fn = x * invpio2 + toint - toint;
  double r = x - fn * pio2_1, w = fn * pio2_1t;
  if (r - w < -pio4) {
    fn -= 1;
    r = x - fn * pio2_1;
    w = fn * pio2_1t;
  } else if (r - w > pio4) {
    fn += 1;
    r = x - fn * pio2_1;
    w = fn * pio2_1t;
  }
  double y0 = r - w;
  int ex = ss__exponent(x);
  if (ex - ss__exponent(y0) > 16) { /* cancellation: 118 bits of pi/2 */
    double t = r;
    w = fn * pio2_2;
    r = t - w;
    w = fn * pio2_2t - ((t - r) - w);
    y0 = r - w;
    if (ex - ss__exponent(y0) > 49) { /* 151 bits, every case */
      t = r;
      w = fn * pio2_3;
      r = t - w;
      w = fn * pio2_3t - ((t - r) - w);
      y0 = r - w;
    }
  }
  double y1 = (r - y0) - w;
  ss__quadrant((int64_t)fn, ss__ksin(y0, y1), ss__kcos(y0, y1), s, c);
}

#endif
