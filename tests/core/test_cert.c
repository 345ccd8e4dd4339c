/*
 * test_cert.c: the event search answered from the last search's certificate
 * (ss__trig_first_root_cert) against the full search and a long-double
 * oracle, on functions near the recorded one and on functions made to
 * defeat it: a bump raised to touch zero before the recorded zero, a zero
 * moved out of the bracket, a change of frequency or of the number of
 * terms.  Every answer must be the full search's: the same status, the
 * same zero to rounding.  Built with core/src/events.c, whose internal
 * entry point the shared library does not export.
 */
#define _GNU_SOURCE
#include <float.h>
#include <string.h>

#include "../core/src/events.h"
#include "test.h"

static unsigned long seed = 2024;
static double rnd(void) {
  seed = seed * 6364136223846793005UL + 1442695040888963407UL;
  return (double)(seed >> 11) / 9007199254740992.0;
}

static long double geval(const ss_trig *g, long double t) {
  long double v = g->c0 + g->c1 * t;
  for (int k = 0; k < g->n; k++)
    v += g->a[k] * cosl(g->w[k] * t) + g->b[k] * sinl(g->w[k] * t);
  return v;
}

/* The first sign change of g on (0, tmax] by sampling and bisection in long
 * double, or tmax + 1; *peak the largest value of g sampled before it. */
static double oracle(const ss_trig *g, double tmax, double h, double *peak) {
  long double a = h, ga = geval(g, a), pk = -INFINITY;
  for (long double b = 2 * h;; b += h) {
    if (b > tmax)
      b = tmax;
    long double gb = geval(g, b);
    if (ga < 0 && gb >= 0) {
      for (int i = 0; i < 200; i++) {
        long double m = 0.5L * (a + b);
        if (geval(g, m) >= 0)
          b = m;
        else
          a = m;
      }
      *peak = (double)pk;
      return (double)b;
    }
    if (b >= tmax)
      break;
    if (gb > pk)
      pk = gb;
    a = b;
    ga = gb;
  }
  *peak = (double)pk;
  return tmax + 1;
}

static int n_fast, n_full, n_compared;

/* g searched with a copy of the certificate c and in full: the same
 * answer.  Returns whether the certificate answered. */
static int compare(const ss_trig *g, double tmax, const ss__root_cert *c) {
  ss__root_cert cc = *c;
  double tp = 0, tc = 0;
  int rp = ss_trig_first_root(g, 0, tmax, &tp);
  int rcert = ss__trig_first_root_cert(g, tmax, &cc, 1, &tc);
  int fast = cc.hits > c->hits; /* answered from the record */
  ASSERT_EQ_INT(rcert, rp);
  if (rp == SS_OK || rp == SS_GRAZING) {
    /* the same zero to its conditioning: g is known to about 16 ulp of its
     * size, which moves a zero by that over the slope */
    double size = fabs(g->c0) + fabs(g->c1 * tp), d[2];
    for (int k = 0; k < g->n; k++)
      size += hypot(g->a[k], g->b[k]);
    ss_trig_eval(g, tp, 1, d);
    double cond = 32 * DBL_EPSILON * size / fmax(fabs(d[1]), 1e-300);
    ASSERT_NEAR(tc, tp, fmin(cond, 1e-9) + 4 * DBL_EPSILON * fabs(tp));
  }
  n_compared++;
  if (fast) {
    n_fast++;
    ASSERT_EQ_INT(rcert, SS_OK);
  } else
    n_full++;
  return fast;
}

/* A reference function with a simple first zero before tmax whose search
 * leaves a certificate; 0 if this draw gives none. */
static int draw(ss_trig *g, double tmax, ss__root_cert *c, int start_at_zero) {
  memset(g, 0, sizeof *g);
  g->n = 1 + (int)(rnd() * 3);
  double amp = 0;
  for (int k = 0; k < g->n; k++) {
    g->w[k] = 0.2 + 3 * rnd();
    g->a[k] = rnd() - 0.5;
    g->b[k] = rnd() - 0.5;
    amp += hypot(g->a[k], g->b[k]);
  }
  g->c1 = rnd() < 0.3 ? 0.05 * (rnd() - 0.3) : 0;
  if (start_at_zero) {
    /* g(0) = 0 leaving downward, as x2' - V at the start of a slip */
    double s = 0, d = 0;
    for (int k = 0; k < g->n; k++) {
      s += g->a[k];
      d += g->w[k] * g->b[k];
    }
    g->c0 = -s;
    if (g->c1 + d >= 0)
      return 0;
  } else {
    g->c0 = -amp * (0.2 + 0.8 * rnd());
  }
  double t;
  memset(c, 0, sizeof *c);
  int rc = ss__trig_first_root_cert(g, tmax, c, 1, &t);
  return rc == SS_OK && c->valid;
}

/* A function delta away from ref; one that starts at a zero keeps it, as
 * every slip starts at x2' = V. */
static void perturb(ss_trig *g, const ss_trig *ref, double delta,
                    int start_at_zero) {
  *g = *ref;
  g->c0 += delta * (rnd() - 0.5);
  g->c1 += g->c1 != 0 ? 0.05 * delta * (rnd() - 0.5) : 0;
  double s = 0;
  for (int k = 0; k < g->n; k++) {
    g->a[k] += delta * (rnd() - 0.5);
    g->b[k] += delta * (rnd() - 0.5);
    s += g->a[k];
  }
  if (start_at_zero)
    g->c0 = -s;
}

/* Functions near the recorded one, at distances from 1e-15 to 1e-1: the
 * near ones answered from the record, every one as the full search. */
static void test_near(int start_at_zero) {
  int refs = 0, fast_small = 0, small = 0;
  double worst = 0;
  for (int trial = 0; trial < 300; trial++) {
    ss_trig ref, g;
    ss__root_cert c;
    double tmax = 60;
    if (!draw(&ref, tmax, &c, start_at_zero))
      continue;
    refs++;
    for (int j = 0; j < 40; j++) {
      double delta = pow(10.0, -15 + 14 * rnd());
      perturb(&g, &ref, delta, start_at_zero);
      int fast = compare(&g, tmax, &c);
      if (delta < 1e-6) {
        small++;
        fast_small += fast;
      }
      if (fast) {
        double peak, expect = oracle(&g, tmax, 1e-3, &peak);
        double d[2];
        ss_trig_eval(&g, expect, 1, d);
        if (expect <= tmax && fabs(d[1]) > 1e-3) {
          double tc;
          ss__root_cert cc = c;
          ss__trig_first_root_cert(&g, tmax, &cc, 1, &tc);
          ASSERT_NEAR(tc, expect, 1e-12 * (1 + expect));
          worst = fmax(worst, fabs(tc - expect));
        }
      }
    }
  }
  printf("near (start %s): %d references, %d of %d within 1e-6 answered "
         "from the record; largest |t - oracle| %.2g\n",
         start_at_zero ? "at a zero" : "below", refs, fast_small, small, worst);
  ASSERT_TRUE(refs > 100);
  /* the record must do its work: most near functions answered from it */
  ASSERT_TRUE(fast_small > small / 2);
}

/* A bump before the recorded zero raised towards zero and beyond: raising
 * c0 by the bump's depth times 0.5 .. 1.5 makes an earlier touch or zero,
 * which the record must never hide. */
static void test_bump(void) {
  int cases = 0, earlier = 0;
  for (int trial = 0; trial < 2000 && cases < 150; trial++) {
    ss_trig ref, g;
    ss__root_cert c;
    double tmax = 60;
    if (!draw(&ref, tmax, &c, 0))
      continue;
    /* the deepest point reached before the zero is known; a bump is a
     * local maximum of g before it, found by sampling */
    double peak, root = oracle(&ref, tmax, 1e-3, &peak);
    if (!(root <= tmax) || !(peak < 0) || !(peak > -0.3))
      continue;
    cases++;
    for (int j = 0; j < 21; j++) {
      g = ref;
      double f = 0.5 + 0.05 * j; /* 0.5 .. 1.5 of the depth */
      g.c0 -= f * peak;
      compare(&g, tmax, &c);
      double t, pk2, r2 = oracle(&g, tmax, 1e-3, &pk2);
      ss__root_cert cc = c;
      int rc = ss__trig_first_root_cert(&g, tmax, &cc, 1, &t);
      if (f > 1.02 && r2 < root - 1e-2) {
        earlier++;
        /* the earlier zero, not the recorded one */
        ASSERT_TRUE(rc == SS_OK || rc == SS_GRAZING);
        ASSERT_TRUE(t < root - 1e-3);
      }
    }
  }
  printf("bump: %d references raised towards an earlier touch, %d raised "
         "past it\n",
         cases, earlier);
  ASSERT_TRUE(cases >= 50 && earlier > 0);
}

/* Whether g's first zero is still the recorded one: a simple zero inside
 * the record's bracket [lo, hi], g rising all the way from lo to it. */
static int same_zero(const ss_trig *g, double tmax, double lo, double hi) {
  double t, d[2];
  if (ss_trig_first_root(g, 0, tmax, &t) != SS_OK || !(t > lo && t < hi))
    return 0;
  for (int i = 0; i <= 200; i++) {
    ss_trig_eval(g, lo + (t - lo) * i / 200.0, 1, d);
    if (!(d[1] > 0))
      return 0;
  }
  return 1;
}

/* At the edge: along a direction of the coefficients, the distance at
 * which the first zero stops being the recorded one (it leaves the
 * bracket, or the bracket stops rising to it, or the status changes),
 * found by bisection with the full search; then functions just short of
 * and just past it.  Whichever part of the record gives way first, the
 * answer must be the full search's.  Directions: every coefficient at
 * random (kind 0), or only the fastest term's (kind 1), which bends the
 * bracket more than it moves g. */
static void test_edge(int start_at_zero, int kind) {
  int edges = 0;
  for (int trial = 0; trial < 2000 && edges < 150; trial++) {
    ss_trig ref, dir, g;
    ss__root_cert c;
    double tmax = 60;
    if (!draw(&ref, tmax, &c, start_at_zero))
      continue;
    unsigned long keep = seed;
    perturb(&dir, &ref, 1, start_at_zero); /* dir - ref: a direction */
    if (kind == 1) {
      int f = 0;
      for (int k = 1; k < ref.n; k++)
        f = ref.w[k] > ref.w[f] ? k : f;
      ss_trig only = ref;
      only.a[f] = dir.a[f];
      only.b[f] = dir.b[f];
      if (start_at_zero)
        only.c0 = ref.c0 - (dir.a[f] - ref.a[f]);
      dir = only;
    }
    double lo = 0, hi = 1;
    double lo_b = c.a[c.n - 1], hi_b = c.hi;
#define ALONG(x)                                                               \
  do {                                                                         \
    g = ref;                                                                   \
    g.c0 += (x) * (dir.c0 - ref.c0);                                           \
    g.c1 += (x) * (dir.c1 - ref.c1);                                           \
    for (int k = 0; k < g.n; k++) {                                            \
      g.a[k] += (x) * (dir.a[k] - ref.a[k]);                                   \
      g.b[k] += (x) * (dir.b[k] - ref.b[k]);                                   \
    }                                                                          \
  } while (0)
    ALONG(hi);
    if (same_zero(&g, tmax, lo_b, hi_b))
      continue; /* no edge along this direction */
    for (int i = 0; i < 60; i++) {
      double mid = 0.5 * (lo + hi);
      ALONG(mid);
      if (same_zero(&g, tmax, lo_b, hi_b))
        lo = mid;
      else
        hi = mid;
    }
    edges++;
    for (int j = 1; j <= 8; j++) {
      ALONG(lo * (1 - ldexp(1, -3 * j)));
      compare(&g, tmax, &c);
      ALONG(hi * (1 + ldexp(1, -3 * j)));
      compare(&g, tmax, &c);
    }
    seed = keep;
#undef ALONG
  }
  printf("edge (start %s, %s): %d edges approached from both sides\n",
         start_at_zero ? "at a zero" : "below",
         kind ? "fastest term" : "all terms", edges);
  ASSERT_TRUE(edges >= 50);
}

/* The largest value of g on [a, b], sampled densely. */
static double sampled_max(const ss_trig *g, double a, double b, int n) {
  double m = -INFINITY, v[1];
  for (int i = 0; i <= n; i++) {
    ss_trig_eval(g, a + (b - a) * i / n, 0, v);
    m = fmax(m, v[0]);
  }
  return m;
}

/* A zero raised inside the record's first piece, [0, a_1], where only g's
 * own bound from 0 and the record's bound back from a_1 speak: references
 * whose highest point before the bracket lies inside that piece, with
 * more room elsewhere, raised just past it. */
static void test_first_piece(void) {
  int cases = 0;
  for (int trial = 0; trial < 200000 && cases < 12; trial++) {
    ss_trig ref, g;
    ss__root_cert c;
    double tmax = 60;
    if (!draw(&ref, tmax, &c, 0) || c.n < 3)
      continue;
    double a1 = c.a[1], lo = c.a[c.n - 1], v[2];
    ss_trig_eval(&ref, 0, 0, v);
    double m0 = sampled_max(&ref, 0, a1, 200);
    if (!(m0 > v[0] + 0.1 * fabs(m0)))
      continue;
    double rest = sampled_max(&ref, a1, lo, 2000);
    ss_trig_eval(&ref, lo, 0, v + 1);
    /* inside the piece, not at its start; higher than the rest and much
     * nearer zero than the bracket's start */
    if (!(m0 > v[0] + 0.1 * fabs(m0)) || !(m0 > rest + 0.5 * fabs(m0)) ||
        !(fabs(m0) < 0.25 * fabs(v[1])))
      continue;
    cases++;
    g = ref;
    g.c0 -= 1.01 * m0;
    double t;
    ASSERT_EQ_INT(ss_trig_first_root(&g, 0, tmax, &t), SS_OK);
    ASSERT_TRUE(t < a1);
    compare(&g, tmax, &c);
  }
  printf("first piece: %d zeros raised inside it\n", cases);
  ASSERT_TRUE(cases == 12);
}

/* What the record cannot cover: another frequency, another number of
 * terms, a horizon before its bracket, a start above zero. */
static void test_mismatch(void) {
  int refs = 0;
  for (int trial = 0; trial < 200 && refs < 50; trial++) {
    ss_trig ref, g;
    ss__root_cert c;
    if (!draw(&ref, 60, &c, 0))
      continue;
    refs++;
    g = ref;
    g.w[0] *= 1 + 1e-12;
    ASSERT_EQ_INT(compare(&g, 60, &c), 0);
    if (ref.n < SS_TRIG_MAX) {
      g = ref;
      g.n++;
      g.w[g.n - 1] = 1;
      g.a[g.n - 1] = 1e-13;
      ASSERT_EQ_INT(compare(&g, 60, &c), 0);
    }
    /* a horizon inside the bracket: the full search's answer (horizon) */
    g = ref;
    ASSERT_EQ_INT(compare(&g, c.a[c.n - 1] + 0.5 * (c.hi - c.a[c.n - 1]), &c),
                  0);
    g.c0 += 10; /* above zero at the start */
    ASSERT_EQ_INT(compare(&g, 60, &c), 0);
  }
  ASSERT_TRUE(refs == 50);
}

/* Records for functions that take turns, as the phases of one mode on an
 * orbit of three turns: each answered from its own record once all are
 * kept; with fewer records than turns, fewer answers from them; every
 * answer the full search's. */
static void test_slots(void) {
  int cycles = 0;
  unsigned long all_hits = 0, max_hits = 0;
  for (int trial = 0; trial < 400 && cycles < 40; trial++) {
    ss_trig f[3];
    ss__root_cert tmp;
    if (!draw(&f[0], 60, &tmp, 0))
      continue;
    /* the others: far from it (no record of one covers another), with the
     * same frequencies, as the phases of one mode are */
    int ok = 1;
    for (int k = 1; k < 3 && ok; k++) {
      double t;
      perturb(&f[k], &f[0], 0.3, 0);
      memset(&tmp, 0, sizeof tmp);
      ok = ss__trig_first_root_cert(&f[k], 60, &tmp, 1, &t) == SS_OK &&
           tmp.valid;
    }
    if (!ok)
      continue;
    cycles++;
    for (int slots = 2; slots <= 4; slots++) {
      ss__root_cert c[4];
      memset(c, 0, sizeof c);
      unsigned long hits = 0;
      for (int turn = 0; turn < 6; turn++)
        for (int k = 0; k < 3; k++) {
          ss_trig g;
          perturb(&g, &f[k], 1e-12, 0);
          double tp, tc;
          int rp = ss_trig_first_root(&g, 0, 60, &tp);
          int rc = ss__trig_first_root_cert(&g, 60, c, slots, &tc);
          ASSERT_EQ_INT(rc, rp);
          if (rp == SS_OK)
            ASSERT_NEAR(tc, tp, 1e-12 * (1 + tp));
        }
      for (int i = 0; i < slots; i++)
        hits += c[i].hits;
      if (slots >= 3) {
        all_hits += hits; /* turns 2 to 6 can come from the records */
        max_hits += 15;
      }
    }
  }
  printf("slots: %d cycles of three functions; with 3 or 4 records, %lu of "
         "%lu searches after the first turn answered from them\n",
         cycles, all_hits, max_hits);
  ASSERT_TRUE(cycles >= 20);
  ASSERT_TRUE(all_hits > 0.7 * (double)max_hits);
}

/* A start just above zero: the record's tolerance is wider than the new
 * function's own (the bounds derived from the record's are larger), and a
 * g(0) between the two once was taken for a start below zero, a root
 * answered where the full search says SS_ABOVE.  g(0) is walked across
 * both tolerances, one ulp of c0 at a time. */
static void test_start_tolerance(void) {
  ss_trig ref = {0}, g;
  ref.n = 1;
  ref.w[0] = 1;
  ref.b[0] = -1; /* -sin t: its first zero after 0 at pi */
  ss__root_cert c = {0};
  double t;
  ASSERT_EQ_INT(ss__trig_first_root_cert(&ref, 60, &c, 1, &t), SS_OK);
  ASSERT_TRUE(c.valid);
  g = ref;
  g.a[0] = 0x1.47ae147ae147bp-7;
  g.c0 = -0x1.47ae147ae0c66p-7; /* g(0) 3.6e-15, above its tolerance */
  int seen_above = 0;
  for (int k = 0; k < 400; k++, g.c0 = nextafter(g.c0, -1)) {
    compare(&g, 60, &c);
    seen_above += ss_trig_first_root(&g, 0, 60, &t) == SS_ABOVE;
  }
  /* the walk crosses the tolerance: both kinds of start were compared */
  ASSERT_TRUE(seen_above > 0 && seen_above < 400);
}

int main(void) {
  test_near(0);
  test_near(1);
  test_bump();
  test_edge(0, 0);
  test_edge(1, 0);
  test_edge(0, 1);
  test_edge(1, 1);
  test_first_piece();
  test_slots();
  test_mismatch();
  test_start_tolerance();
  printf("%d comparisons, %d answered from the record, %d in full\n",
         n_compared, n_fast, n_full);
  TEST_DONE();
}
