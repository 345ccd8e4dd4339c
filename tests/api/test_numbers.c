/*
 * test_numbers.c: the digits of the numbers in every answer (shortest.c).
 *
 * Checked against glibc, which converts with multi-precision arithmetic:
 * each power of ten of the table against strtold (its leading 64 bits,
 * where long double has a 64-bit significand), and exactly against
 * 128-bit integers where 10^k fits; each number written must read back (strtod)
 * as the same double, bit for bit, must be a JSON number, and must have the
 * fewest digits that read back, the closest to it of that many (found by
 * trying printf's correctly rounded %.*e from 1 to 17 digits, and its
 * neighbours).
 * The doubles: every power of two and of ten, their neighbours, the
 * extremes, short decimals such as 0.0724, and random bit patterns.
 * Usage: test_numbers [random-count]   (default 200000; CTest runs a million,
 * the sanitizer build 200000 by SS_NUMBERS_COUNT)
 */
#define _GNU_SOURCE
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shortest.h"
#include "test.h"

static struct { long n, exact, bad; } st;

/* A JSON number: -?(0|[1-9][0-9]*)(\.[0-9]+)?([eE][+-]?[0-9]+)? */
static int json_number(const char *s) {
  if (*s == '-')
    s++;
  if (*s == '0')
    s++;
  else if (*s >= '1' && *s <= '9')
    while (*s >= '0' && *s <= '9')
      s++;
  else
    return 0;
  if (*s == '.') {
    s++;
    if (!(*s >= '0' && *s <= '9'))
      return 0;
    while (*s >= '0' && *s <= '9')
      s++;
  }
  if (*s == 'e' || *s == 'E') {
    s++;
    if (*s == '+' || *s == '-')
      s++;
    if (!(*s >= '0' && *s <= '9'))
      return 0;
    while (*s >= '0' && *s <= '9')
      s++;
  }
  return *s == 0;
}

/* The significant digits of a decimal text (no sign, point, leading or
 * trailing zeros) and its exponent: value = 0.digits * 10^n. */
static void digits_of(const char *s, char *dig, int *n) {
  char all[40];
  int nall = 0, point = -1;
  if (*s == '-')
    s++;
  for (; *s && *s != 'e' && *s != 'E' && nall < 39; s++)
    if (*s == '.')
      point = nall;
    else
      all[nall++] = *s;
  if (point < 0)
    point = nall;
  int x = *s ? atoi(s + 1) : 0, first = 0;
  while (first < nall && all[first] == '0')
    first++;
  int len = 0;
  for (int i = first; i < nall; i++)
    dig[len++] = all[i];
  while (len > 0 && dig[len - 1] == '0')
    len--;
  dig[len] = 0;
  *n = point - first + x;
}

static void check(double v) {
  char out[40], ref[48], dig[40], rdig[40];
  if (!isfinite(v))
    return;
  int n = api__shortest(v, out), rn, on;
  st.n++;
  if (n != (int)strlen(out) || !json_number(out) || strtod(out, NULL) != v ||
      signbit(strtod(out, NULL)) != signbit(v)) {
    if (st.bad++ < 10)
      TEST_FAIL_("%.17g (%a) written as '%s'", v, v, out);
    return;
  }
  if (v == 0)
    return;
  /* the shortest: for 1, 2, ... digits, the correctly rounded decimal, or
   * else its neighbour on the side of the interval that reads back as v
   * (the lower half of the interval of a power of two is the narrower) */
  for (int p = 1; p <= 17; p++) {
    snprintf(ref, sizeof ref, "%.*e", p - 1, fabs(v));
    if (strtod(ref, NULL) == fabs(v))
      break;
    unsigned long long m = 0;
    for (const char *q = ref; *q != 'e'; q++)
      if (*q != '.')
        m = 10 * m + (unsigned long long)(*q - '0');
    int x = atoi(strchr(ref, 'e') + 1) - (p - 1);
    snprintf(ref, sizeof ref, "%llue%d", m + 1, x);
    if (strtod(ref, NULL) == fabs(v))
      break;
    snprintf(ref, sizeof ref, "%llue%d", m - 1, x);
    if (strtod(ref, NULL) == fabs(v))
      break;
  }
  digits_of(out, dig, &on);
  digits_of(ref, rdig, &rn);
  if (strcmp(dig, rdig) == 0 && on == rn)
    st.exact++;
  else if (st.bad++ < 10)
    TEST_FAIL_("%.17g written as '%s'; the shortest '%s'", v, out, ref);
}

static void check_near(double v) {
  check(v);
  check(-v);
  check(nextafter(v, INFINITY));
  check(nextafter(v, 0));
}

static uint64_t rng = 0x9e3779b97f4a7c15u;
static uint64_t next64(void) { /* xorshift64* */
  rng ^= rng >> 12;
  rng ^= rng << 25;
  rng ^= rng >> 27;
  return rng * 2685821657736338717u;
}

static void same(double v, const char *want) {
  char out[40];
  api__shortest(v, out);
  test_checks_++;
  if (strcmp(out, want) != 0)
    TEST_FAIL_("%.17g written as '%s', want '%s'", v, out, want);
}

int main(int argc, char **argv) {
  const char *env = getenv("SS_NUMBERS_COUNT");
  long count = env ? atol(env) : argc > 1 ? atol(argv[1]) : 200000;

  /* the powers of ten, against glibc's correctly rounded strtold and,
   * where 10^k = 5^k 2^k has 5^k below 2^128, exactly */
  uint64_t hi, lo;
  int e;
  ASSERT_TRUE(!api__pow10_g(-293, &hi, &lo, &e));
  ASSERT_TRUE(!api__pow10_g(327, &hi, &lo, &e));
  ASSERT_TRUE(api__pow10_g(-292, &hi, &lo, &e));
  ASSERT_TRUE(hi == 0xff77b1fcbebcdc4fu && lo == 0x25e8e89c13bb0f7bu);
  ASSERT_EQ_INT(e, -971);
  ASSERT_TRUE(api__pow10_g(0, &hi, &lo, &e));
  ASSERT_TRUE(hi == (uint64_t)1 << 63 && lo == 1 && e == 0);
  unsigned __int128 five = 1;
  for (int k = -292; k <= 326; k++) {
    ASSERT_TRUE(api__pow10_g(k, &hi, &lo, &e));
    test_checks_++;
    if (!(hi >> 63))
      TEST_FAIL_("10^%d: %016llx%016llx not 128 bits", k,
                 (unsigned long long)hi, (unsigned long long)lo);
    /* floor: the table's value less one */
    unsigned __int128 g = ((unsigned __int128)hi << 64 | lo) - 1;
    if (k >= 0 && k <= 55) {
      /* 5^k 2^k 2^(127 - e) = 5^k shifted left by 127 - e + k */
      int sh = 127 - e + k, b = 0;
      while (b < 128 && (five >> b) > 1)
        b++;
      test_checks_++;
      if (sh < 0 || b + sh != 127 || g != five << sh)
        TEST_FAIL_("10^%d: the table is not 5^%d shifted", k, k);
      if (k < 55)
        five *= 5;
    }
#if LDBL_MANT_DIG == 64
    char s[16];
    snprintf(s, sizeof s, "1e%d", k);
    long double want = strtold(s, NULL),
                got = ldexpl((long double)(uint64_t)(g >> 64) +
                                 (long double)(uint64_t)((g >> 63) & 1),
                             e - 63);
    test_checks_++;
    if (want != got)
      TEST_FAIL_("10^%d: %016llx%016llx * 2^%d, strtold %La", k,
                 (unsigned long long)hi, (unsigned long long)lo, e - 127, want);
#endif
  }

  /* the layout: printf's %g with 17 digits, and a whole number as x.0 */
  same(0.1, "0.1");
  same(0.0724, "0.0724");
  same(-0.8074871367243053, "-0.8074871367243053");
  same(1.0, "1.0");
  same(0.0, "0.0");
  same(-0.0, "-0.0");
  same(4.5, "4.5");
  same(123456.0, "123456.0");
  same(1e16, "10000000000000000.0");
  same(1e17, "1e+17");
  same(1.5e300, "1.5e+300");
  same(1e-4, "0.0001");
  same(1.25e-5, "1.25e-05");
  same(0.1 + 0.2, "0.30000000000000004");
  same(1.5543122344752192e-15, "1.5543122344752192e-15");
  same(DBL_MAX, "1.7976931348623157e+308");
  same(DBL_MIN, "2.2250738585072014e-308");
  same(4.9406564584124654e-324, "5e-324");
  same(10.271429855353585, "10.271429855353585");

  /* every power of two and ten, and their neighbours */
  for (int i = -1074; i <= 1023; i++)
    check_near(ldexp(1.0, i));
  for (int i = -323; i <= 308; i++) {
    char s[16];
    snprintf(s, sizeof s, "1e%d", i);
    check_near(strtod(s, NULL));
  }
  check_near(DBL_MAX);
  check_near(DBL_MIN);
  check_near(DBL_TRUE_MIN);
  check(nextafter(DBL_MIN, 0)); /* the largest subnormal */
  /* short decimals, as the parameters of a request are written */
  for (long i = 0; i < count / 4; i++) {
    static const uint64_t p10[] = {1e1,  1e2,  1e3,  1e4,  1e5,  1e6,
                                   1e7,  1e8,  1e9,  1e10, 1e11, 1e12,
                                   1e13, 1e14, 1e15, 1e16, 1e17};
    char s[64];
    uint64_t top = p10[next64() % 17], m = next64() % top; /* 1-17 digits */
    snprintf(s, sizeof s, "%llue%d", (unsigned long long)m,
             (int)(next64() % 80) - 40);
    check(strtod(s, NULL));
  }
  /* random bit patterns: every exponent, normal and subnormal */
  for (long i = 0; i < count; i++) {
    uint64_t b = next64();
    double v;
    memcpy(&v, &b, sizeof v);
    if (isfinite(v))
      check(v);
  }
  printf("%ld doubles: %ld in the fewest digits, the closest of them, %ld "
         "not\n",
         st.n, st.exact, st.bad);
  ASSERT_EQ_INT(st.bad, 0);
  TEST_DONE();
}
