/*
 * shortest.c: a double in the fewest decimal digits that read back as the
 * same double (the closest to it when several of that length do), with
 * 64-bit integers: Grisu3 (F. Loitsch, "Printing floating-point numbers
 * quickly and accurately with integers", PLDI 2010).  For the few doubles
 * where Grisu3 cannot be sure (about 1 in 200; tests/api/test_numbers.c
 * counts), glibc's correctly rounded printf gives the digits instead.
 * bench/bench_numbers.c measures it against printf("%.17g").
 *
 * The powers of ten it needs (10^k, k = -348, -340, ..., 340, each as a
 * 64-bit significand rounded to nearest and a binary exponent) are
 * computed once, exactly, from big integers, rather than typed in.
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shortest.h"

typedef struct {
  uint64_t f;
  int e;
} diy; /* f * 2^e */

enum { POW_MIN = -348, POW_STEP = 8, POW_N = 87 };

static diy pow10_cache[POW_N]; /* 10^(POW_MIN + POW_STEP * i) */
static pthread_once_t pow10_once = PTHREAD_ONCE_INIT;

/* ---- the table, from big integers --------------------------------------- */

enum { LIMBS = 48 }; /* 1536 bits: 10^340 has 1130, 2^1235 / 10^348 needs */

typedef struct {
  uint32_t w[LIMBS]; /* little endian */
} big;

static int big_bits(const big *a) {
  for (int i = LIMBS - 1; i >= 0; i--)
    if (a->w[i])
      return 32 * i + 32 - __builtin_clz(a->w[i]);
  return 0;
}

static void big_mul10(big *a) {
  uint64_t carry = 0;
  for (int i = 0; i < LIMBS; i++) {
    uint64_t t = (uint64_t)a->w[i] * 10 + carry;
    a->w[i] = (uint32_t)t;
    carry = t >> 32;
  }
}

/* a /= 10, rounding down; the remainder. */
static unsigned big_div10(big *a) {
  uint64_t rem = 0;
  for (int i = LIMBS - 1; i >= 0; i--) {
    uint64_t t = (rem << 32) | a->w[i];
    a->w[i] = (uint32_t)(t / 10);
    rem = t % 10;
  }
  return (unsigned)rem;
}

static int big_bit(const big *a, int i) {
  return i >= 0 && ((a->w[i / 32] >> (i % 32)) & 1);
}

/* The 64 leading bits of @a a, rounded to nearest (a tie, which the
 * powers of ten in the table never are, rounds up); the binary exponent
 * of the result in a's units. */
static diy big_top64(const big *a) {
  int n = big_bits(a), lo = n - 64;
  diy r = {0, lo};
  for (int i = n - 1; i >= lo && i >= 0; i--)
    r.f = (r.f << 1) | (uint64_t)big_bit(a, i);
  if (lo < 0) { /* fewer than 64 bits: exact */
    r.f <<= -lo;
    return r;
  }
  if (big_bit(a, lo - 1) && ++r.f == 0) {
    r.f = (uint64_t)1 << 63;
    r.e++;
  }
  return r;
}

static void pow10_build(void) {
  for (int i = 0; i < POW_N; i++) {
    int k = POW_MIN + POW_STEP * i;
    big a;
    memset(&a, 0, sizeof a);
    if (k >= 0) {
      a.w[0] = 1;
      for (int j = 0; j < k; j++)
        big_mul10(&a);
      pow10_cache[i] = big_top64(&a);
    } else {
      /* floor(2^b / 10^-k), 67 bits or more, then 10^k = that / 2^b; the
       * bits dropped below the 65th decide the rounding only in a tie,
       * which cannot happen (10^k is not a dyadic rational) */
      int b = (int)(-k * 3.3219280948873623) + 67;
      a.w[b / 32] = 1u << (b % 32);
      for (int j = 0; j < -k; j++)
        big_div10(&a);
      pow10_cache[i] = big_top64(&a);
      pow10_cache[i].e -= b;
    }
  }
}

int api__pow10_cached(int i, uint64_t *f, int *e) {
  if (i < 0 || i >= POW_N)
    return 0;
  pthread_once(&pow10_once, pow10_build);
  *f = pow10_cache[i].f;
  *e = pow10_cache[i].e;
  return POW_MIN + POW_STEP * i;
}

/* ---- Grisu3 ---------------------------------------------------------------
 */

/* a * b, the upper 64 bits of the product rounded. */
static diy diy_mul(diy a, diy b) {
  unsigned __int128 p = (unsigned __int128)a.f * b.f;
  uint64_t h = (uint64_t)(p >> 64), l = (uint64_t)p;
  return (diy){h + (l >> 63), a.e + b.e + 64};
}

static diy diy_norm(diy a) {
  int s = __builtin_clzll(a.f);
  return (diy){a.f << s, a.e - s};
}

/* Grisu3's weeding: step the last digit down towards the double while
 * that brings it closer, then say whether the result is certainly the
 * closest within the interval that reads back as v (1), or whether the
 * imprecision of the products (@a unit) leaves that open (0).  Distances
 * are to the upper bound widened by one unit. */
static int round_weed(char *buf, int len, uint64_t too_high_w, uint64_t unsafe,
                      uint64_t rest, uint64_t ten_kappa, uint64_t unit) {
  uint64_t small = too_high_w - unit, large = too_high_w + unit;
  while (
      rest < small && unsafe - rest >= ten_kappa &&
      (rest + ten_kappa < small || small - rest >= rest + ten_kappa - small)) {
    buf[len - 1]--;
    rest += ten_kappa;
  }
  if (rest < large && unsafe - rest >= ten_kappa &&
      (rest + ten_kappa < large || large - rest > rest + ten_kappa - large))
    return 0;
  return 2 * unit <= rest && rest <= unsafe - 4 * unit;
}

static const uint32_t P10[] = {
    1, 10, 100, 1000, 10000, 100000, 1000000, 10000000, 100000000, 1000000000};

/* The digits of the scaled upper bound, as few as leave the scaled
 * interval (low, high) widened by one unit each side: their count, or 0
 * when they are not certainly the shortest and closest. */
static int digit_gen(diy w, diy low, diy high, char *buf, int *k) {
  int shift = -w.e; /* 32..59 */
  uint64_t unit = 1, one = (uint64_t)1 << shift;
  if (high.f == UINT64_MAX)
    return 0;
  uint64_t too_high = high.f + unit, unsafe = too_high - (low.f - unit);
  uint32_t p1 = (uint32_t)(too_high >> shift);
  uint64_t p2 = too_high & (one - 1);
  int kappa = 1, len = 0;
  while (kappa < 10 && p1 >= P10[kappa])
    kappa++;
  while (kappa > 0) {
    buf[len++] = (char)('0' + p1 / P10[kappa - 1]);
    p1 %= P10[kappa - 1];
    kappa--;
    uint64_t rest = ((uint64_t)p1 << shift) + p2;
    if (rest < unsafe) {
      *k += kappa;
      return round_weed(buf, len, too_high - w.f, unsafe, rest,
                        (uint64_t)P10[kappa] << shift, unit)
                 ? len
                 : 0;
    }
  }
  for (;;) {
    p2 *= 10;
    unit *= 10;
    unsafe *= 10;
    buf[len++] = (char)('0' + (p2 >> shift));
    p2 &= one - 1;
    kappa--;
    if (p2 < unsafe) {
      *k += kappa;
      return round_weed(buf, len, (too_high - w.f) * unit, unsafe, p2, one,
                        unit)
                 ? len
                 : 0;
    }
  }
}

/* The shortest digits of the finite, nonzero |v| (v = digits * 10^k), the
 * closest to v of that many; their count, or 0 when Grisu3 cannot be sure
 * (about 0.5% of doubles). */
int api__grisu3(double v, char *buf, int *k) {
  uint64_t bits;
  memcpy(&bits, &v, sizeof bits);
  uint64_t frac = bits & (((uint64_t)1 << 52) - 1);
  int bexp = (int)((bits >> 52) & 0x7ff);
  diy x =
      bexp ? (diy){frac | (uint64_t)1 << 52, bexp - 1075} : (diy){frac, -1074};
  /* the bounds of the interval that reads back as v */
  diy plus = diy_norm((diy){(x.f << 1) + 1, x.e - 1});
  diy minus = frac == 0 && bexp > 1 ? (diy){(x.f << 2) - 1, x.e - 2}
                                    : (diy){(x.f << 1) - 1, x.e - 1};
  minus.f <<= minus.e - plus.e;
  minus.e = plus.e;
  diy w = diy_norm(x);
  /* a cached 10^-k that brings the exponent into [-59, -32] */
  pthread_once(&pow10_once, pow10_build);
  int i = (int)((-59 - 64 - plus.e - pow10_cache[0].e) / 26.575424759098897);
  if (i < 0)
    i = 0;
  if (i >= POW_N)
    i = POW_N - 1;
  while (i < POW_N - 1 && plus.e + pow10_cache[i].e + 64 < -59)
    i++;
  while (i > 0 && plus.e + pow10_cache[i].e + 64 > -32)
    i--;
  diy c = pow10_cache[i];
  *k = -(POW_MIN + POW_STEP * i);
  return digit_gen(diy_mul(w, c), diy_mul(minus, c), diy_mul(plus, c), buf, k);
}

/* The same from glibc, when Grisu3 cannot be sure: 15 correctly rounded
 * digits are the shortest whenever 15 or fewer read back (two decimals of
 * 15 digits are farther apart than a double's interval); otherwise 16,
 * otherwise 17. */
static int digits_printf(double v, char *buf, int *k) {
  char s[40];
  for (int p = 15;; p++) {
    snprintf(s, sizeof s, "%.*e", p - 1, fabs(v));
    if (p == 17 || strtod(s, NULL) == fabs(v))
      break;
  }
  int len = 0;
  const char *q = s;
  for (; *q != 'e'; q++)
    if (*q != '.')
      buf[len++] = *q;
  while (len > 1 && buf[len - 1] == '0')
    len--;
  *k = atoi(q + 1) + 1 - len;
  return len;
}

int api__shortest(double v, char *out) {
  char *o = out;
  uint64_t bits;
  memcpy(&bits, &v, sizeof bits);
  if (bits >> 63)
    *o++ = '-';
  if (v == 0) {
    memcpy(o, "0.0", 4);
    return (int)(o - out) + 3;
  }
  char d[24];
  int k = 0, len = api__grisu3(v, d, &k);
  if (!len)
    len = digits_printf(v, d, &k);
  int n = len + k; /* v = 0.d1d2... * 10^n */
  if (n - 1 < -4 || n - 1 >= 17) {
    /* d1.d2...e+XX, as printf's %g writes it */
    *o++ = d[0];
    if (len > 1) {
      *o++ = '.';
      memcpy(o, d + 1, (size_t)len - 1);
      o += len - 1;
    }
    int x = n - 1;
    *o++ = 'e';
    *o++ = x < 0 ? '-' : '+';
    if (x < 0)
      x = -x;
    if (x >= 100)
      *o++ = (char)('0' + x / 100);
    *o++ = (char)('0' + x / 10 % 10);
    *o++ = (char)('0' + x % 10);
  } else if (n <= 0) { /* 0.000ddd */
    memcpy(o, "0.", 2);
    o += 2;
    memset(o, '0', (size_t)-n);
    o += -n;
    memcpy(o, d, (size_t)len);
    o += len;
  } else if (n >= len) { /* ddd000.0 */
    memcpy(o, d, (size_t)len);
    o += len;
    memset(o, '0', (size_t)(n - len));
    o += n - len;
    memcpy(o, ".0", 2);
    o += 2;
  } else { /* dd.ddd */
    memcpy(o, d, (size_t)n);
    o += n;
    *o++ = '.';
    memcpy(o, d + n, (size_t)(len - n));
    o += len - n;
  }
  *o = 0;
  return (int)(o - out);
}
