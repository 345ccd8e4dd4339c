/*
 * shortest.c: a double in the fewest decimal digits that read back as the
 * same double (the closest to it when several of that length do), with
 * 64-bit integers: Schubfach (R. Giulietti, "The Schubfach way to render
 * doubles", 2020).  Which decimals at the double's scale, and at ten times
 * it, lie in the interval that reads back as the double is decided from
 * three products of 128 by 64 bits, rounded to odd, which the paper proves
 * exact enough for every case: no double needs a slower path.
 * tests/api/test_numbers.c checks it against glibc's correctly rounded
 * printf; bench/bench_numbers.c measures it against printf("%.17g").
 *
 * The powers of ten it needs (g = floor(10^k 2^(127 - floor(log2 10^k)))
 * + 1 for k = -292 .. 326, 128 bits each) are computed once, exactly, from
 * big integers, rather than typed in.
 */
#include <pthread.h>
#include <stdint.h>
#include <string.h>

#include "shortest.h"

enum { K_MIN = -292, K_MAX = 326, K_N = K_MAX - K_MIN + 1 };

typedef struct {
  uint64_t hi, lo;
} g128; /* hi 2^64 + lo */

static g128 g_table[K_N]; /* g for 10^(K_MIN + i) */
static pthread_once_t g_once = PTHREAD_ONCE_INIT;

/* ---- the table, from big integers --------------------------------------- */

enum { LIMBS = 40 }; /* 1280 bits: 10^326 has 1083, 2^1184 has 1185 */

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

/* The 128 leading bits of @a a, rounded down (@a a has some). */
static unsigned __int128 big_top128(const big *a) {
  int n = big_bits(a), lo = n - 128;
  unsigned __int128 r = 0;
  for (int i = n - 1; i >= lo && i >= 0; i--)
    r = (r << 1) | (unsigned __int128)big_bit(a, i);
  if (lo < 0) /* fewer than 128 bits: exact */
    r <<= -lo;
  return r;
}

static void g_put(int k, unsigned __int128 top) {
  g_table[k - K_MIN].hi = (uint64_t)(top >> 64);
  g_table[k - K_MIN].lo = (uint64_t)top;
  /* + 1: above 10^k 2^(127 - e) even where that is whole */
  if (++g_table[k - K_MIN].lo == 0)
    g_table[k - K_MIN].hi++;
}

static void g_build(void) {
  big a;
  memset(&a, 0, sizeof a);
  a.w[0] = 1;
  for (int k = 0; k <= K_MAX; k++) {
    if (k)
      big_mul10(&a);
    g_put(k, big_top128(&a));
  }
  /* floor(2^B / 10^j), each division rounding down, is floor of the
   * quotient itself; 2^B / 10^292 still has over 128 bits */
  enum { B = 1184 };
  memset(&a, 0, sizeof a);
  a.w[B / 32] = 1u << (B % 32);
  for (int k = -1; k >= K_MIN; k--) {
    big_div10(&a);
    g_put(k, big_top128(&a));
  }
}

/* floor(log2 10^k), over the table's range (test_numbers checks each
 * against strtold); floor(log10 2^q) is inline in to_decimal. */
static int floor_log2_pow10(int k) { return (k * 1741647) >> 19; }

int api__pow10_g(int k, uint64_t *hi, uint64_t *lo, int *e) {
  if (k < K_MIN || k > K_MAX)
    return 0;
  pthread_once(&g_once, g_build);
  *hi = g_table[k - K_MIN].hi;
  *lo = g_table[k - K_MIN].lo;
  *e = floor_log2_pow10(k);
  return 1;
}

/* ---- Schubfach ------------------------------------------------------------
 */

/* floor(g cp / 2^128), made odd when the product has bits below that
 * (those under the last 64 never decide: the paper's rounding to odd). */
static uint64_t round_odd(g128 g, uint64_t cp) {
  unsigned __int128 x = (unsigned __int128)g.lo * cp;
  unsigned __int128 y = (unsigned __int128)g.hi * cp + (uint64_t)(x >> 64);
  return (uint64_t)(y >> 64) | ((uint64_t)y > 1);
}

/* The shortest decimal of the finite, nonzero |v|, the closest to it of
 * that length: v = d 10^k, d with no trailing zero. */
static uint64_t to_decimal(double v, int *k) {
  uint64_t bits;
  memcpy(&bits, &v, sizeof bits);
  uint64_t frac = bits & (((uint64_t)1 << 52) - 1), c;
  int bexp = (int)((bits >> 52) & 0x7ff), q;
  if (bexp) {
    c = frac | (uint64_t)1 << 52;
    q = bexp - 1075;
  } else {
    c = frac;
    q = -1074;
  }
  uint64_t d;
  if (q <= 0 && q > -53 && (c & (((uint64_t)1 << -q) - 1)) == 0) {
    d = c >> -q; /* a whole number below 2^53 */
    *k = 0;
  } else {
    /* the interval that reads back as v, in quarters of 2^q: [cbl, cbr],
     * closed when c is even; its lower half is narrower at a power of 2 */
    int even = !(c & 1), closer = frac == 0 && bexp > 1;
    uint64_t cbl = 4 * c - 2 + (uint64_t)closer, cb = 4 * c, cbr = 4 * c + 2;
    /* 10^e10 <= 2^q (3/4 2^q when closer) < 10^(e10 + 1) */
    int e10 = (q * 1262611 - (closer ? 524031 : 0)) >> 22;
    int h = q + floor_log2_pow10(-e10) + 1; /* 1 .. 4 */
    pthread_once(&g_once, g_build);
    g128 g = g_table[-e10 - K_MIN];
    /* the bounds and v times 10^-e10, times 4, rounded to odd */
    uint64_t vbl = round_odd(g, cbl << h), vb = round_odd(g, cb << h),
             vbr = round_odd(g, cbr << h);
    uint64_t lower = vbl + !even, upper = vbr - !even, s = vb / 4;
    *k = e10;
    int done = 0;
    if (s >= 10) { /* one digit fewer: s' or s' + 1, tens of s */
      uint64_t sp = s / 10;
      int up_in = lower <= 40 * sp, wp_in = 40 * sp + 40 <= upper;
      if (up_in != wp_in) {
        d = sp + (uint64_t)wp_in;
        *k = e10 + 1;
        done = 1;
      }
    }
    if (!done) {
      int u_in = lower <= 4 * s, w_in = 4 * s + 4 <= upper;
      if (u_in != w_in)
        d = s + (uint64_t)w_in;
      else /* both: the closer, the even one on a tie */
        d = s + (uint64_t)(vb > 4 * s + 2 || (vb == 4 * s + 2 && (s & 1)));
    }
  }
  /* the trailing zeros off (a short decimal has a dozen): 8 at a time,
   * then 4, 2, 1 */
  while (d % 100000000 == 0) {
    d /= 100000000;
    *k += 8;
  }
  if (d % 10000 == 0) {
    d /= 10000;
    *k += 4;
  }
  if (d % 100 == 0) {
    d /= 100;
    *k += 2;
  }
  if (d % 10 == 0) {
    d /= 10;
    *k += 1;
  }
  return d;
}

static const char PAIRS[] =
    "00010203040506070809101112131415161718192021222324"
    "25262728293031323334353637383940414243444546474849"
    "50515253545556575859606162636465666768697071727374"
    "75767778798081828384858687888990919293949596979899";

/* @a x below 10^8 as its 8 digits, leading zeros included: two halves,
 * and the pairs of each, found independently. */
static inline void put8(char *p, uint32_t x) {
  uint32_t a = x / 10000, b = x % 10000;
  memcpy(p, PAIRS + 2 * (a / 100), 2);
  memcpy(p + 2, PAIRS + 2 * (a % 100), 2);
  memcpy(p + 4, PAIRS + 2 * (b / 100), 2);
  memcpy(p + 6, PAIRS + 2 * (b % 100), 2);
}

/* The decimal digits of @a d (> 0, below 10^17) at the start of @a buf,
 * which has room for 17 (and may get bytes after the digits); their
 * count.  Every copy is of a fixed size: a copy of a variable size is a
 * call, and a number has several. */
static int digits_of(uint64_t d, char *buf) {
  static const uint64_t P10[] = {1,
                                 10,
                                 100,
                                 1000,
                                 10000,
                                 100000,
                                 1000000,
                                 10000000,
                                 100000000,
                                 1000000000,
                                 10000000000,
                                 100000000000,
                                 1000000000000,
                                 10000000000000,
                                 100000000000000,
                                 1000000000000000,
                                 10000000000000000};
  /* 17 digits with leading zeros, then the n that d has */
  char t[40];
  uint64_t hi = d / 100000000;
  t[0] = (char)('0' + hi / 100000000);
  put8(t + 1, (uint32_t)(hi % 100000000));
  put8(t + 9, (uint32_t)(d % 100000000));
  /* bits times log10(2): the count of digits or one less */
  int n = (64 - __builtin_clzll(d)) * 1233 >> 12;
  n += n < 17 && d >= P10[n];
  memcpy(buf, t + 17 - n, 17);
  return n;
}

int api__shortest(double v, char *out) {
  /* written in a buffer with room past the end for whole copies of the
   * digits (17 bytes at most, 24 with sign, point and exponent) */
  char buf[64], *o = buf;
  uint64_t bits;
  memcpy(&bits, &v, sizeof bits);
  if (bits >> 63)
    *o++ = '-';
  if (v == 0) {
    memcpy(o, "0.0", 4);
    memcpy(out, buf, 8);
    return (int)(o - buf) + 3;
  }
  char d[40];
  int k;
  int len = digits_of(to_decimal(v, &k), d);
  int n = len + k; /* v = 0.d1d2... * 10^n */
  if (n - 1 < -4 || n - 1 >= 17) {
    /* d1.d2...e+XX, as printf's %g writes it */
    *o++ = d[0];
    if (len > 1) {
      *o++ = '.';
      memcpy(o, d + 1, 16);
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
  } else if (n <= 0) { /* 0.000ddd: n is -3 at least */
    memcpy(o, "0.000", 5);
    o += 2 - n;
    memcpy(o, d, 17);
    o += len;
  } else if (n >= len) { /* ddd000.0: n is 17 at most */
    memcpy(o, d, 17);
    o += len;
    memcpy(o, "0000000000000000", 16);
    o += n - len;
    memcpy(o, ".0", 2);
    o += 2;
  } else { /* dd.ddd */
    memcpy(o, d, 17);
    o += n;
    *o++ = '.';
    memcpy(o, d + n, 17);
    o += len - n;
  }
  *o = 0;
  memcpy(out, buf, 32);
  return (int)(o - buf);
}
