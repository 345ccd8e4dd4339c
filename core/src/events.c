/*
 * events.c: certified location of the first zero of a switching function.
 *
 * Every switching function of the model is a short trigonometric sum plus a
 * line, g(t) = c0 + c1 t + sum_k a_k cos(w_k t) + b_k sin(w_k t), whose
 * derivatives are bounded by the modal amplitudes R_k = hypot(a_k, b_k):
 * |g''| <= M2 = sum R_k w_k^2 and |g'''| <= M3 = sum R_k w_k^3.  From a point
 * a where g(a) < 0 the Taylor bounds
 *
 *   g(a+h) <= g(a) + g'(a) h + M2 h^2 / 2                              (Q)
 *   g(a+h) <= g(a) + g'(a) h + g''(a) h^2 / 2 + M3 h^3 / 6             (C)
 *
 * give steps over which g provably stays negative; stepping by the larger
 * certified step never passes a zero, however close two zeros are, and
 * converges quadratically onto a simple zero.  This is the safe-step idea of
 * interval root isolation (R. E. Moore, "Methods and Applications of
 * Interval Analysis", SIAM 1979, ch. 7) specialised to a known derivative
 * bound.  The bounds hold in exact arithmetic; the tolerance tol below
 * absorbs the rounding of the evaluation of g.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "events.h"
#include "sincos.h"

/* A zero within tol = TOL_ULPS * DBL_EPSILON * scale is indistinguishable
 * from rounding noise in the evaluation of g (a sum of at most 2 + 2n terms
 * of size <= scale, each with a relative error of a few ulps). */
#define TOL_ULPS 16.0
/* Never more steps than this in one search: a safeguard, not a limit that a
 * well-posed search reaches (each step covers at least a certified piece). */
#define MAX_STEPS 2000000

void ss_trig_eval(const ss_trig *g, double t, int order, double *out) {
  /* All derivatives are accumulated without branches (a few multiplies
   * cost less than the tests); only the ones asked for are stored. */
  double v0 = g->c0 + g->c1 * t, v1 = g->c1, v2 = 0, v3 = 0;
  for (int k = 0; k < g->n; k++) {
    double w = g->w[k], c = 1, s = 0;
    if (t != 0) /* searches start at the anchor, where no sine is needed */
      ss__sincos(w * t, &s, &c);
    double A = g->a[k] * c + g->b[k] * s, B = g->b[k] * c - g->a[k] * s;
    double w2 = w * w;
    v0 += A;
    v1 += w * B;
    v2 -= w2 * A;
    v3 -= w2 * w * B;
  }
  out[0] = v0;
  if (order >= 1)
    out[1] = v1;
  if (order >= 2)
    out[2] = v2;
  if (order >= 3)
    out[3] = v3;
}

typedef struct bounds {
  double M1, M2, M3, amp; /* derivative bounds and sum of amplitudes */
} bounds;

static void get_bounds(const ss_trig *g, bounds *b) {
  b->M1 = b->M2 = b->M3 = b->amp = 0;
  for (int k = 0; k < g->n; k++) {
    double R = sqrt(g->a[k] * g->a[k] + g->b[k] * g->b[k]), w = g->w[k];
    b->amp += R;
    b->M1 += R * w;
    b->M2 += R * w * w;
    b->M3 += R * w * w * w;
  }
}

static double tol_at(const ss_trig *g, const bounds *b, double t) {
  return TOL_ULPS * DBL_EPSILON * (fabs(g->c0) + fabs(g->c1 * t) + b->amp);
}

/* The first positive zero of p(h) = g0 + g1 h + (M/2) h^2, g0 < 0, M >= 0:
 * the largest step certified by (Q).  Written without cancellation. */
static double quad_step(double g0, double g1, double M) {
  if (M <= 0)
    return g1 > 0 ? -g0 / g1 : INFINITY;
  double disc = sqrt(g1 * g1 - 2 * M * g0);
  return g1 >= 0 ? -2 * g0 / (g1 + disc) : (disc - g1) / M;
}

/* A longer step certified by (C): the largest of 2, 4, ..., 64 times the (Q)
 * step over which the cubic bound p stays negative.  The maximum of p over
 * [0, h] is at h or at p's local maximum (the smaller root of p'), so both
 * are checked.  Returns 0 when (C) certifies no more than (Q). */
static double cubic_step(double g0, double g1, double g2, double M3,
                         double hq) {
  if (M3 <= 0)
    return 0;
  /* the usual answer, when even twice the (Q) step is not certified */
  double h2 = 2 * hq;
  if (!(g0 + h2 * (g1 + h2 * (g2 / 2 + h2 * M3 / 6)) < 0))
    return 0;
  /* p'(s) = g1 + g2 s + M3 s^2/2 = 0: the local maximum of p is the smaller
   * root, where p'' = g2 + M3 s < 0; smax <= 0 when there is none ahead. */
  double smax = 0, pm = -1, D = g2 * g2 - 2 * M3 * g1;
  if (D > 0) {
    smax = (-g2 - sqrt(D)) / M3;
    if (smax > 0)
      pm = g0 + smax * (g1 + smax * (g2 / 2 + smax * M3 / 6));
  }
  double best = 0;
  for (double f = 2; f <= 64; f *= 2) {
    double h = f * hq;
    double ph = g0 + h * (g1 + h * (g2 / 2 + h * M3 / 6));
    if (!(ph < 0))
      break;
    if (smax > 0 && smax < h && !(pm < 0))
      break;
    best = h;
  }
  return best;
}

/* Direction in which g leaves t0 when g(t0) is within tol of zero: -1 down
 * (into g < 0), +1 up, judged by the first derivative that is clearly not
 * rounding noise. */
static int departure(const bounds *b, double tol, const double v[4]) {
  double slope_tol = 4 * sqrt(2 * tol * b->M2);
  if (v[1] > slope_tol)
    return 1;
  if (v[1] < -slope_tol)
    return -1;
  if (v[2] > 0)
    return 1;
  if (v[2] < 0)
    return -1;
  return v[3] > 0 ? 1 : -1;
}

/* From t0 with g(t0) ~ 0 and g leaving downward, a later point where g is
 * certified below -tol with g < tol on the whole way there. */
static double escape(const ss_trig *g, const bounds *b, double t0, double tol,
                     const double v[4]) {
  double h;
  if (v[1] < 0 && b->M2 > 0) {
    h = -v[1] / b->M2; /* minimum of the (Q) bound */
    if (v[0] + v[1] * h + b->M2 * h * h / 2 < -tol)
      return t0 + h;
  }
  h = (v[2] < 0 && b->M3 > 0) ? -v[2] / b->M3 : 1e-3;
  for (int i = 0; i < 200; i++, h *= 0.5) {
    double p = v[0] + h * (fmax(v[1], 0) + h * (v[2] / 2 + h * b->M3 / 6));
    if (p < -tol)
      return t0 + h;
    double u[4];
    ss_trig_eval(g, t0 + h, 1, u);
    if (u[0] < -tol && p < tol)
      return t0 + h;
  }
  return t0 + h;
}

/* Refine a zero known to lie in [lo, hi] with g(lo) <= 0 <= g(hi): Halley
 * steps (cubic convergence, from g, g', g'' of one evaluation) kept inside
 * the bracket, bisection when a step leaves it.  Once a step is so small
 * that the next error, at most (M2 / 2 g') step^2 for Newton's part, is below
 * the resolution of t, the step is applied and the iteration stops without
 * another evaluation. */
static double polish(const ss_trig *g, const bounds *b, double lo, double hi,
                     double t) {
  for (int i = 0; i < 100; i++) {
    double v[3];
    ss_trig_eval(g, t, 2, v);
    if (v[0] == 0)
      return t;
    if (v[0] < 0)
      lo = t;
    else
      hi = t;
    double step = 0.5 * (lo + hi) - t;
    if (v[1] > 0) {
      double den = 2 * v[1] * v[1] - v[0] * v[2];
      step = den > 0 ? -2 * v[0] * v[1] / den : -v[0] / v[1];
    }
    double tn = t + step;
    /* converged: the correction is below the resolution of t */
    if (fabs(step) <= 2 * DBL_EPSILON * fabs(t) || hi - lo <= 0)
      return t;
    if (!(tn > lo && tn < hi)) {
      t = 0.5 * (lo + hi);
      continue;
    }
    if (v[1] > 0 &&
        b->M2 / (2 * v[1]) * step * step <= 0.5 * DBL_EPSILON * fabs(tn))
      return tn;
    t = tn;
  }
  return t;
}

/* The bound on the rounding error of g' as ss_trig_eval computes it: the
 * terms w_k B_k, each of size at most R_k w_k with a relative error of a
 * few ulps, and the line's slope. */
static double slope_tol_of(const ss_trig *g, const bounds *b) {
  return TOL_ULPS * DBL_EPSILON * (fabs(g->c1) + b->M1);
}

/* At a point a where g(a) >= -tol after certified steps from below, decide
 * between a crossing (return SS_OK, *t the zero) and a tangency (SS_GRAZING,
 * *t the touching maximum).  A crossing has a slope well above the rounding
 * level; otherwise the nearby maximum of g (Newton on g') decides: a maximum
 * no higher than tol is a tangency, a higher one means g crosses zero
 * between a and the maximum. */
static int classify(const ss_trig *g, const bounds *b, double a, double tol,
                    double *t) {
  double v[3];
  ss_trig_eval(g, a, 2, v);
  double slope_tol = 4 * sqrt(2 * tol * b->M2);
  if (v[1] > slope_tol) {
    double d = 4 * (tol + fabs(v[0])) / v[1];
    *t = polish(g, b, a - d, a + d, a);
    return SS_OK;
  }
  /* Newton on g' converges onto the maximum until g' is rounding noise,
   * about TOL_ULPS eps (|c1| + sum R_k w_k); divided by a small |g''| that
   * noise can keep the step above a few ulps of s for ever, so the noise
   * level ends the iteration too. */
  double slope_noise = slope_tol_of(g, b);
  double s = a;
  int found = 0;
  for (int i = 0; i < 60; i++) {
    double u[3];
    ss_trig_eval(g, s, 2, u);
    if (!(u[2] < 0))
      break;
    double ds = -u[1] / u[2];
    s += ds;
    if (fabs(ds) <= 4 * DBL_EPSILON * fmax(1.0, fabs(s)) ||
        fabs(u[1]) <= slope_noise) {
      found = 1;
      break;
    }
  }
  if (!found) {
    /* No maximum nearby (g'' >= 0): g rises from a flat start. */
    *t = a;
    return SS_OK;
  }
  double gs[1];
  ss_trig_eval(g, s, 0, gs);
  if (gs[0] <= tol) {
    *t = s;
    return SS_GRAZING;
  }
  *t = polish(g, b, a, s, a);
  return SS_OK;
}

/* The largest value over [a, b] of min(F, B) for the convex bounds
 *   F(t) = fa + f1 (t - a) + M (t - a)^2 / 2   (forward from a),
 *   B(t) = gb - g1 (b - t) + M (b - t)^2 / 2   (backward from b),
 * both bounds on one function, so min(F, B) is one too.  F - B is linear,
 * so it is the larger of the ends and the value where F = B. */
static double piece_max(double fa, double f1, double gb, double g1, double M,
                        double a, double b) {
  double L = b - a;
  double Fb = fa + L * (f1 + 0.5 * M * L), Ba = gb - L * (g1 - 0.5 * M * L);
  double m = fmax(fmin(fa, Ba), fmin(Fb, gb));
  /* F - B = c + e s, s = t - a */
  double c = fa - gb + g1 * L - 0.5 * M * L * L, e = f1 - g1 + M * L;
  if (e != 0) {
    double sx = -c / e;
    if (sx > 0 && sx < L)
      m = fmax(m, fa + sx * (f1 + 0.5 * M * sx));
  }
  return m;
}

/* Finish a record: g, its bounds, the bracket and the zero, and the room
 * each piece between recorded points leaves (the first piece is judged
 * against the next function's own start). */
static void record(ss__root_cert *c, const ss_trig *g, const bounds *b,
                   double tol, double hi, double root) {
  c->g = *g;
  c->amp = b->amp;
  c->M1 = b->M1;
  c->M2 = b->M2;
  c->M3 = b->M3;
  c->tol = tol;
  c->hi = hi;
  c->root = root;
  for (int i = 1; i + 1 < c->n; i++)
    c->mu[i] = piece_max(c->gu[i], c->g1[i], c->gu[i + 1], c->g1[i + 1], b->M2,
                         c->a[i], c->a[i + 1]);
  c->valid = 1;
}

/* The search of ss_trig_first_root; with rec, the certificate of a search
 * that ends in a simple zero by the bracket below is recorded into it
 * (every other end leaves it invalid). */
static int first_root(const ss_trig *g, double t0, double tmax, double *t,
                      ss__root_cert *rec) {
  bounds b;
  double v[4], a = t0;
  if (rec)
    rec->valid = rec->n = 0;
  if (!g || !t || g->n < 0 || g->n > SS_TRIG_MAX || !isfinite(t0) ||
      !(tmax > t0) || !isfinite(g->c0) || !isfinite(g->c1))
    return SS_EINVAL;
  for (int k = 0; k < g->n; k++)
    if (!isfinite(g->a[k]) || !isfinite(g->b[k]) || !isfinite(g->w[k]))
      return SS_EINVAL;
  get_bounds(g, &b);
  double tol = tol_at(g, &b, t0);
  /* For c1 <= 0 the supremum of g over [t0, inf) is at most
   * c0 + c1 t0 + sum R_k: below -tol, g never reaches zero. */
  if (g->c1 <= 0 && g->c0 + g->c1 * t0 + b.amp < -tol) {
    *t = INFINITY;
    return SS_NEVER;
  }
  ss_trig_eval(g, t0, 3, v);
  if (v[0] > tol)
    return SS_ABOVE;
  if (v[0] >= -tol) {
    if (departure(&b, tol, v) > 0) {
      *t = t0;
      return SS_OK;
    }
    a = escape(g, &b, t0, tol, v);
  }
  /* v holds g at t0 already when the search starts there */
  int fresh = a == t0;
  for (long it = 0; it < MAX_STEPS; it++) {
    if (a >= tmax) {
      *t = tmax;
      return SS_HORIZON;
    }
    if (!fresh) {
      ss_trig_eval(g, a, 2, v);
      tol = tol_at(g, &b, a);
    }
    fresh = 0;
    if (v[0] >= -tol)
      return classify(g, &b, a, tol, t);
    if (rec) {
      if (rec->n == SS__CERT_MAX)
        rec = NULL; /* too many steps to keep: no record */
      else {
        rec->a[rec->n] = a;
        rec->gu[rec->n] = v[0] + tol;
        rec->g1[rec->n] = v[1];
        rec->n++;
      }
    }
    /* Near a simple root: if the Newton step d = -g/g' is short enough that
     * g' stays positive over [a, a + 2d] (g' >= g'(a) - M2 s) and the bound
     * certifies g(a + 2d) >= |g(a)|/2 > tol, the first root is the only one
     * in that bracket, and safeguarded Newton finds it at once. */
    if (v[1] > 0 && v[0] < -2 * tol) {
      double d = -v[0] / v[1];
      if (4 * d * b.M2 < v[1] && a + 2 * d <= tmax) {
        /* start from the Halley point, which the same g, g', g'' give */
        double den = 2 * v[1] * v[1] - v[0] * v[2];
        double th = den > 0 ? a - 2 * v[0] * v[1] / den : a + d;
        if (!(th > a && th < a + 2 * d))
          th = a + d;
        *t = polish(g, &b, a, a + 2 * d, th);
        if (rec)
          record(rec, g, &b, tol, a + 2 * d, *t);
        return SS_OK;
      }
    }
    /* The bounds are applied to g(a) + tol, the largest value the exact
     * g(a) can have, so that the rounding of g cannot fake a certificate. */
    double hq = quad_step(v[0] + tol, v[1], b.M2);
    double hc = cubic_step(v[0] + tol, v[1], v[2], b.M3, hq);
    double h = fmax(hq, hc);
    if (!(h > 0) || a + h == a) {
      /* Cannot move: g is within rounding of zero here. */
      return classify(g, &b, a, tol, t);
    }
    a += h;
  }
  *t = a;
  return SS_ENOCONV;
}

/* The search answered from the record c, if c covers g (see ss__root_cert):
 * SS_OK with the zero in *t, or -1 when it does not. */
/* The distance of g from the record's function: D0, D1 of
 * ss__root_cert's bound |Delta(t)| <= D0 + D1 t, and Dp, that of Delta';
 * D0 is INFINITY for a record that cannot cover g (another form).  With
 * e_k = |da_k| + |db_k| >= |R_k(g) - R_k(record)|, the record's bounds
 * plus the sums of e_k w_k^j bound g's, without a square root. */
typedef struct distance {
  double D0, D1, Dp;
  bounds b;
} distance;

static distance distance_to(const ss_trig *g, const ss__root_cert *c) {
  const ss_trig *r = &c->g;
  distance d = {INFINITY, INFINITY, INFINITY, {0, 0, 0, 0}};
  if (!c->valid || g->n != r->n)
    return d;
  double D0 = fabs(g->c0 - r->c0), D1 = fabs(g->c1 - r->c1);
  double E0 = 0, E1 = 0, E2 = 0, E3 = 0, size = fabs(g->c0);
  for (int k = 0; k < g->n; k++) {
    double w = g->w[k];
    /* the bounds below are sums of |e| w^j: for w > 0 only */
    if (w != r->w[k] || !(w > 0))
      return d;
    double e = fabs(g->a[k] - r->a[k]) + fabs(g->b[k] - r->b[k]);
    E0 += e;
    E1 += w * e;
    E2 += w * w * e;
    E3 += w * w * w * e;
    size += fabs(g->a[k]) + fabs(g->b[k]);
  }
  /* the differences' own rounding */
  d.D0 = D0 + E0 + 4 * DBL_EPSILON * size;
  d.D1 = D1 + 4 * DBL_EPSILON * fabs(g->c1);
  d.Dp = D1 + E1;
  /* the sums' own rounding, relative */
  double up = 1 + 8 * DBL_EPSILON;
  d.b.amp = (c->amp + E0) * up;
  d.b.M1 = (c->M1 + E1) * up;
  d.b.M2 = (c->M2 + E2) * up;
  d.b.M3 = (c->M3 + E3) * up;
  return d;
}

static int from_record(const ss_trig *g, double tmax, ss__root_cert *c,
                       const distance *dist, double *t) {
  const ss_trig *r = &c->g;
  const bounds *b = &dist->b; /* bounds of g, from the record's */
  double D0 = dist->D0, D1 = dist->D1, Dp = dist->Dp;
  if (!isfinite(D0))
    return -1;
  int n = c->n;
  double lo = c->a[n - 1], hi = c->hi;
  if (!(hi <= tmax))
    return -1;
  /* g's own start: at 0 (free of sines), negative or leaving zero downward
   * at once (the first case of escape()); F0 bounds g from 0 on.  Within
   * the bounds' tolerance of zero the start is judged as the full search
   * judges it, with g's own bounds and tolerance: the record's, larger, once
   * took a g(0) between the two for a start below zero where the full
   * search says SS_ABOVE. */
  double v[4], tol = tol_at(g, b, 0), s = 0;
  ss_trig_eval(g, 0, 3, v);
  if (v[0] >= -tol) {
    bounds own;
    get_bounds(g, &own);
    double tol0 = tol_at(g, &own, 0);
    if (v[0] > tol0)
      return -1;
    if (v[0] >= -tol0) {
      if (departure(&own, tol0, v) > 0 || !(v[1] < 0 && own.M2 > 0))
        return -1;
      s = -v[1] / own.M2;
      if (!(v[0] + v[1] * s + own.M2 * s * s / 2 < -tol0))
        return -1;
    }
  }
  /* [s, a_1] (or [s, lo] with no point between): F0, g's own bound from
   * 0 (with M >= its M2), and there B_1 + D as well, the record's bound
   * backward from a_1 */
  double M = fmax(b->M2, c->M2);
  double fs = (v[0] + tol) + s * (v[1] + 0.5 * M * s), f1 = v[1] + M * s;
  double e1 = n > 1 ? c->a[1] : lo, m0;
  if (!(s <= e1))
    return -1;
  if (n > 1)
    m0 = piece_max(fs, f1, c->gu[1] + D0 + D1 * e1, c->g1[1], M, s, e1);
  else /* F0 is convex: its largest value is at an end */
    m0 = fmax(fs, fs + (e1 - s) * (f1 + 0.5 * M * (e1 - s)));
  /* g below -2 tol, not just below 0, so that no evaluation of it there
   * could come within tol of zero, where the full search would stop to
   * judge a touch: the answer is the full search's, not only a true one */
  double tz = 2 * tol_at(g, b, hi);
  if (!(m0 < -tz))
    return -1;
  for (int i = 1; i + 1 < n; i++)
    if (!(c->mu[i] + D0 + D1 * c->a[i + 1] < -tz))
      return -1;
  /* the bracket (g < 0 at lo, the end of the pieces above): g > 0 at hi,
   * and rising all the way there, so that its zero is the only one.  (The
   * bracket's width, under g'(lo) / (2 M2), makes the rise follow from the
   * value at hi in every case the tests could build; it is kept because
   * the proof needs it.) */
  double L = hi - lo, gu = c->gu[n - 1], g1 = c->g1[n - 1];
  double slope_noise = TOL_ULPS * DBL_EPSILON * (fabs(r->c1) + c->M1);
  double g1lo = g1 - slope_noise; /* g'(lo) is at least this */
  if (!((gu - 2 * c->tol) + L * (g1lo - 0.5 * c->M2 * L) - (D0 + D1 * hi) >
        0) ||
      !(g1lo - c->M2 * L - Dp > 0))
    return -1;
  double th = c->root > lo && c->root < hi ? c->root : 0.5 * (lo + hi);
  *t = polish(g, b, lo, hi, th);
  c->root = *t;
  c->hits++;
  return SS_OK;
}

int ss_trig_first_root(const ss_trig *g, double t0, double tmax, double *t) {
  return first_root(g, t0, tmax, t, NULL);
}

int ss__trig_first_root_cert(const ss_trig *g, double tmax, ss__root_cert *c,
                             int n, double *t) {
  if (!c || n < 1 || !g || !t || g->n < 0 || g->n > SS_TRIG_MAX || !(tmax > 0))
    return first_root(g, 0, tmax, t, NULL);
  /* the nearest record answers, if any can; a search in full replaces an
   * empty record, else the farthest */
  int near = -1, far = 0;
  distance dn = {INFINITY, 0, 0, {0, 0, 0, 0}};
  double dfar = -1;
  for (int i = 0; i < n; i++) {
    distance d = distance_to(g, &c[i]);
    if (d.D0 < dn.D0) {
      dn = d;
      near = i;
    }
    double key = c[i].valid ? d.D0 : INFINITY;
    if (key > dfar) {
      dfar = key;
      far = i;
    }
  }
  if (near >= 0 && from_record(g, tmax, &c[near], &dn, t) == SS_OK)
    return SS_OK;
  return first_root(g, 0, tmax, t, &c[far]);
}

/* Internal use: the tolerance and departure rule, so that the mode rule at a
 * threshold agrees with the event finder. */
int ss__trig_at_zero(const ss_trig *g, double t0, int *dir) {
  bounds b;
  double v[4];
  get_bounds(g, &b);
  double tol = tol_at(g, &b, t0);
  ss_trig_eval(g, t0, 3, v);
  if (v[0] > tol) {
    *dir = 1;
    return 0;
  }
  if (v[0] < -tol) {
    *dir = -1;
    return 0;
  }
  *dir = departure(&b, tol, v);
  return 1;
}

int ss__trig_rises_at(const ss_trig *g, double t) {
  bounds b;
  double v[2];
  get_bounds(g, &b);
  ss_trig_eval(g, t, 1, v);
  return v[1] > slope_tol_of(g, &b);
}
