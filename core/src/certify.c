/*
 * certify.c: a proof of every root of the period-1 orbit equations of the
 * slip-stick and slip-overshoot-stick sequences in a box, by interval branch
 * and bound with the Krawczyk test.
 *
 * Unknowns (t1, t2, s1, s2): the slip's duration, the next phase's (the
 * stick of slip-stick, the overshoot of slip-overshoot-stick) and the start
 * s = (x1, x1') on Sigma0, y0(s) = (s1, s1 + ur/chi, s2, V).  The free
 * phases are affine in s, so each condition below is a row over (s1, s2, 1)
 * whose entries are linear forms in the modal sinusoids cos/sin(w_k t):
 *   a . (s, 1) = 0: x2' = V at the slip's end;
 *   b . (s, 1) = 0: x2' = V at the overshoot's end, or for slip-stick the
 *                   closure of x2, x2 + V t2 = s1 + ur/chi;
 *   R0 = R1 = 0:    the closure of (x1, x1') after the stick, a rotation of
 *                   (x1 - chi x2, x1' - chi V) by its duration (t2, or for
 *                   slip-overshoot-stick t3 = (s1 + ur/chi - x2) / V).
 * The start is an unknown of bounded range rather than eliminated: scan.c's
 * elimination multiplies by the determinant of (a, b), and where a and b are
 * parallel every residual vanishes at isolated points, roots "at infinity"
 * that no interval method can decide.
 *
 * Interval arithmetic: every operation rounds outward, sin and cos are
 * widened by two ulps (glibc's are within one), and the modal data
 * (frequencies, mode shapes, of ss_model) are taken as exact: the proof is
 * of the closed forms that the solver itself evaluates.  Each quantity is
 * carried with its gradient (forward differentiation in intervals), so one
 * pass over a box X gives an enclosure F(X) and the Jacobian's J(X).
 *
 * A box is
 *  - narrowed to the starts whose phases keep the rules an orbit's must
 *    (keep_rules: x2' <= V in the slip, x2' >= V in the overshoot and
 *    |f| <= ur in the stick, at fixed times before the box's least
 *    duration, and the friction each free phase ends with, each a linear
 *    inequality in s): most roots of the equations break one, and need not
 *    be isolated;
 *  - excluded when s has no value in it that solves a and b (interval
 *    Gauss-Seidel, which also narrows it; for slip-overshoot-stick with
 *    the stick's duration in its range; for a short slip or overshoot also
 *    with the phase's mean x2'', a / t1 or (b - a) / t2, which stay apart
 *    where a and b nearly coincide), or keeps no rule; when a residual's
 *    enclosure misses zero (the natural one or the mean-value form F(c) +
 *    J(X)(X - c)), or that of the stick's rotation condition |u| = |w|, or
 *    of R less its dependence on s through a and b, or of the closures with
 *    s eliminated, C . (a x b); or when the Krawczyk image K(X) = c - Y F(c)
 *    + (I - Y J(X))(X - c), Y = mid(J)^-1, misses X;
 *  - proved to hold exactly one root when K(X) lies inside X's interior;
 *  - otherwise cut to X n K(X) and halved across its widest side (the
 *    states' sides weigh less: they follow from the durations); a small
 *    box is first tried in a box around Newton's point that holds it (a
 *    root near a face), and below a width it is left undecided (a double
 *    root, or a continuum: at t1 = t2 = 0 every start closes).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "certify.h"

#define NV 4           /* unknowns: t1, t2, s1, s2 */
#define STACK_MAX 512  /* boxes waiting (depth-first) */
#define MIN_WIDTH 1e-9 /* relative to the box: below this, undecided */
#define INFLATE_BELOW                                                          \
  1e-3 /* relative width where a box is tried around                           \
          Newton's point */
#define NEWTON_ITERS 12
#define STATE_WEIGHT 0.03 /* of the states' widths in the choice of a side */

typedef struct iv {
  double lo, hi;
} iv;

/* a value and its gradient in the unknowns */
typedef struct ad {
  iv v;
  int n; /* d[i] is zero for i >= n */
  iv d[NV];
} ad;

/* Outward rounding without a change of rounding mode: a result rounded to
 * nearest is within |x| 2^-53 (plus 2^-1075 below the normal range) of the
 * exact value, and x -+ (|x| 2^-52 + 2^-1074) rounded to nearest lies at
 * least that far outside x. */
static inline double dn(double x) {
  return x - (fabs(x) * 0x1p-52 + 0x1p-1074);
}
static inline double up(double x) {
  return x + (fabs(x) * 0x1p-52 + 0x1p-1074);
}

static inline iv iv_exact(double x) { return (iv){x, x}; }
/* a double that stands for a real within an ulp of it */
static inline iv iv_near(double x) { return (iv){dn(x), up(x)}; }

static inline iv iv_add(iv a, iv b) {
  return (iv){dn(a.lo + b.lo), up(a.hi + b.hi)};
}

static inline iv iv_sub(iv a, iv b) {
  return (iv){dn(a.lo - b.hi), up(a.hi - b.lo)};
}

static inline iv iv_mul(iv a, iv b) {
  if (a.lo == 0 && a.hi == 0)
    return a;
  if (b.lo == 0 && b.hi == 0)
    return b;
  double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  /* inf * 0 (an unbounded box): unbounded, never an exclusion */
  if (isnan(p[0]) || isnan(p[1]) || isnan(p[2]) || isnan(p[3]))
    return (iv){-INFINITY, INFINITY};
  /* comparisons, not fmin and fmax: the NaNs are out, and the libm calls
   * were a sixth of the proof's time */
  double lo = p[0], hi = p[0];
  for (int i = 1; i < 4; i++) {
    lo = p[i] < lo ? p[i] : lo;
    hi = p[i] > hi ? p[i] : hi;
  }
  return (iv){dn(lo), up(hi)};
}

static inline int iv_has_zero(iv a) { return !(a.lo > 0 || a.hi < 0); }
static inline double iv_mid(iv a) { return 0.5 * a.lo + 0.5 * a.hi; }

static ad ad_const(iv c) {
  ad r;
  r.v = c;
  r.n = 0;
  return r;
}

static ad ad_add(const ad *a, const ad *b) {
  ad r;
  r.v = iv_add(a->v, b->v);
  r.n = a->n > b->n ? a->n : b->n;
  for (int i = 0; i < r.n; i++)
    r.d[i] = i >= a->n   ? b->d[i]
             : i >= b->n ? a->d[i]
                         : iv_add(a->d[i], b->d[i]);
  return r;
}

static ad ad_sub(const ad *a, const ad *b) {
  ad r;
  r.v = iv_sub(a->v, b->v);
  r.n = a->n > b->n ? a->n : b->n;
  for (int i = 0; i < r.n; i++)
    r.d[i] = i >= a->n   ? (iv){-b->d[i].hi, -b->d[i].lo}
             : i >= b->n ? a->d[i]
                         : iv_sub(a->d[i], b->d[i]);
  return r;
}

static ad ad_mul(const ad *a, const ad *b) {
  ad r;
  r.v = iv_mul(a->v, b->v);
  r.n = a->n > b->n ? a->n : b->n;
  for (int i = 0; i < r.n; i++)
    r.d[i] = i >= a->n   ? iv_mul(a->v, b->d[i])
             : i >= b->n ? iv_mul(a->d[i], b->v)
                         : iv_add(iv_mul(a->v, b->d[i]), iv_mul(a->d[i], b->v));
  return r;
}

/* c a, c an interval constant */
static ad ad_scale(iv c, const ad *a) {
  ad r;
  r.v = iv_mul(c, a->v);
  r.n = a->n;
  for (int i = 0; i < r.n; i++)
    r.d[i] = iv_mul(c, a->d[i]);
  return r;
}

/* cos over [lo, hi]: the ends, and 1 or -1 where a multiple of 2 pi or an
 * odd multiple of pi lies inside (decided on a slightly widened interval:
 * an extremum missed by a rounding is within 1e-15 of an end, where cos is
 * flat to 1e-30) */
static iv iv_cos(iv x) {
  if (!(x.hi - x.lo < 6.0) || !isfinite(x.lo) || !isfinite(x.hi))
    return (iv){-1, 1};
  double a = cos(x.lo), b = cos(x.hi);
  double lo = fmin(a, b), hi = fmax(a, b);
  const double pi = 3.141592653589793;
  double e = 4e-16 * fmax(fabs(x.lo), fabs(x.hi)) + 1e-300;
  /* multiples of pi inside: k pi, k from ceil((lo - e)/pi) */
  double k0 = ceil((x.lo - e) / pi), k1 = floor((x.hi + e) / pi);
  for (double k = k0; k <= k1; k++) {
    if (fmod(fabs(k), 2.0) == 0)
      hi = 1;
    else
      lo = -1;
  }
  lo = dn(dn(lo)) - 1e-300;
  hi = up(up(hi)) + 1e-300;
  return (iv){fmax(lo, -1), fmin(hi, 1)};
}

static iv iv_sin(iv x) {
  /* sin x = cos(x - pi/2); pi/2 as a double is within 6e-17 of it, which
   * the widening of iv_cos covers */
  const double h = 1.5707963267948966;
  iv y = {dn(x.lo - h), up(x.hi - h)};
  iv r = iv_cos(y);
  r.lo = fmax(dn(r.lo - 1e-16), -1);
  r.hi = fmin(up(r.hi + 1e-16), 1);
  return r;
}

/* cos and sin of w t, w exact, t an unknown (or a function of one) */
static void ad_cos_sin(double w, const ad *t, ad *c, ad *s) {
  ad u = ad_scale(iv_exact(w), t);
  iv cu = iv_cos(u.v), su = iv_sin(u.v);
  iv ncs = {-su.hi, -su.lo};
  c->v = cu;
  s->v = su;
  c->n = s->n = u.n;
  for (int i = 0; i < u.n; i++) {
    c->d[i] = iv_mul(ncs, u.d[i]);
    s->d[i] = iv_mul(cu, u.d[i]);
  }
}

/* a linear form over the basis {1, cos w0 t, sin w0 t, cos w1 t, sin w1 t}
 * of a free oscillation */
typedef struct lin {
  iv c[5];
} lin;

static ad lin_at(const lin *L, const ad B[5]) {
  ad r;
  r.v = L->c[0];
  r.n = 0;
  for (int k = 1; k < 5; k++)
    if (L->c[k].lo != 0 || L->c[k].hi != 0) {
      r.v = iv_add(r.v, iv_mul(L->c[k], B[k].v));
      r.n = B[k].n > r.n ? B[k].n : r.n;
    }
  for (int j = 0; j < r.n; j++) {
    r.d[j] = iv_exact(0);
    for (int k = 1; k < 5; k++)
      if ((L->c[k].lo != 0 || L->c[k].hi != 0) && j < B[k].n)
        r.d[j] = iv_add(r.d[j], iv_mul(L->c[k], B[k].d[j]));
  }
  return r;
}

/* The free flow's transition in x: x(t) = A(t) (x0 - e) + e, e = sgn D.
 * A = sum_k C_k cos w_k t + S_k sin w_k t, as linear forms. */
static void flow_forms(const ss_model *m, lin A[4][4]) {
  memset(A, 0, 16 * sizeof(lin));
  for (int k = 0; k < 2; k++) {
    iv w = iv_exact(m->w[k]);
    iv winv = iv_near(1.0 / m->w[k]);
    for (int i = 0; i < 2; i++)
      for (int j = 0; j < 2; j++) {
        iv p = iv_mul(iv_exact(m->phi[i][k]), iv_exact(m->phiinv[k][j]));
        int ci = 1 + 2 * k, si = 2 + 2 * k;
        A[i][j].c[ci] = p;                   /* pos <- pos */
        A[i][j + 2].c[si] = iv_mul(p, winv); /* pos <- vel */
        iv mpw = iv_mul(p, w);               /* vel <- pos */
        A[i + 2][j].c[si] = (iv){-mpw.hi, -mpw.lo};
        A[i + 2][j + 2].c[ci] = p; /* vel <- vel */
      }
  }
}

/* The problem of one box search. */
typedef struct problem {
  const ss_model *m;
  int n;  /* 2: slip-stick, 3: slip-overshoot-stick (3 unknowns) */
  int nv; /* unknowns */
  /* slip from y0(s) = (s1, s1 + k, s2, V): x = Y s + y; the derivatives in
   * t of row 3 (x2') */
  lin Y[4][2], y[4], Y3d[2], y3d;
  /* the forms at t = 0, less what they are in exact arithmetic (rounding
   * of the modal data): x2' - V of the slip, a row over (s1, s2, 1); row 3
   * of the overshoot's G - I, then g3 */
  iv a0[3], q0[5];
  /* overshoot: x = G x0 + g; the derivatives in t of row 3 (x2') */
  lin G[4][4], g[4], G3d[4], g3d;
  iv chi, k, V, chiV, chik, omc, Vinv;
  double tau_lo, tau_hi; /* the range of the stick's duration */
  /* the phases' rules at the times j h, j = 1 .. n_rule (rules_init):
   * x2' - V after a slip of j h from y0(s), a row over (s1, s2, 1); row 3
   * of the overshoot's map over j h, G3 (4 entries) then g3 */
  double h_rule, tol_rule;
  double t_short; /* below it an overshoot is short (contract_s) */
  int n_rule;
  iv (*slip_v)[3], (*over_v)[5];
  iv (*stick_cs)[2]; /* cos and sin of j h, for the stick's rotation */
} problem;

/* The basis at t: 1, cos w0 t, sin w0 t, cos w1 t, sin w1 t */
static void basis(const ss_model *m, const ad *t, ad B[5]) {
  B[0] = ad_const(iv_exact(1));
  ad_cos_sin(m->w[0], t, &B[1], &B[2]);
  ad_cos_sin(m->w[1], t, &B[3], &B[4]);
}

/* The derivative in t of a linear form over the basis */
static void lin_deriv(const ss_model *m, const lin *L, lin *Ld) {
  memset(Ld, 0, sizeof *Ld);
  for (int k = 0; k < 2; k++) {
    iv w = iv_exact(m->w[k]), sc = L->c[2 + 2 * k], cc = L->c[1 + 2 * k];
    Ld->c[1 + 2 * k] = iv_mul(sc, w); /* (c cos + s sin)' = s w cos - */
    iv cw = iv_mul(cc, w);            /*                     c w sin */
    Ld->c[2 + 2 * k] = (iv){-cw.hi, -cw.lo};
  }
}

static void problem_init(problem *P, const ss_model *m, int n) {
  memset(P, 0, sizeof *P);
  P->m = m;
  P->n = n;
  P->nv = 4; /* t1, t2 (the stick's or the overshoot's), s1, s2 */
  P->chi = iv_exact(m->p.chi);
  P->V = iv_exact(m->p.V);
  P->k = iv_near(m->p.ur / m->p.chi);
  P->chiV = iv_mul(P->chi, P->V);
  P->chik = iv_mul(P->chi, P->k);
  P->omc = iv_sub(iv_exact(1), P->chi);
  P->Vinv = iv_near(1 / m->p.V);
  lin A[4][4];
  flow_forms(m, A);
  iv D[4] = {iv_exact(m->d0[0]), iv_exact(m->d0[1]), iv_exact(0), iv_exact(0)};
  for (int i = 0; i < 4; i++)
    for (int b = 0; b < 5; b++) {
      P->Y[i][0].c[b] = iv_add(A[i][0].c[b], A[i][1].c[b]);
      P->Y[i][1].c[b] = A[i][2].c[b];
      /* y = A (k e2 + V e4 - D) + D */
      iv s = iv_add(iv_mul(A[i][1].c[b], iv_sub(P->k, D[1])),
                    iv_mul(A[i][3].c[b], P->V));
      s = iv_sub(s, iv_mul(A[i][0].c[b], D[0]));
      P->y[i].c[b] = s;
      /* overshoot: x = A (x0 + D) - D */
      for (int j = 0; j < 4; j++)
        P->G[i][j].c[b] = A[i][j].c[b];
      P->g[i].c[b] =
          iv_add(iv_mul(A[i][0].c[b], D[0]), iv_mul(A[i][1].c[b], D[1]));
    }
  for (int i = 0; i < 4; i++) {
    P->y[i].c[0] = iv_add(P->y[i].c[0], D[i]);
    P->g[i].c[0] = iv_sub(P->g[i].c[0], D[i]);
  }
  ad t0 = ad_const(iv_exact(0)), B0[5];
  basis(m, &t0, B0);
  P->a0[0] = lin_at(&P->Y[3][0], B0).v;
  P->a0[1] = lin_at(&P->Y[3][1], B0).v;
  P->a0[2] = iv_sub(lin_at(&P->y[3], B0).v, P->V);
  for (int l = 0; l < 4; l++)
    P->q0[l] = iv_sub(lin_at(&P->G[3][l], B0).v, iv_exact(l == 3));
  P->q0[4] = lin_at(&P->g[3], B0).v;
  for (int l = 0; l < 8; l++) {
    const lin *L = l < 4    ? &P->G[3][l]
                   : l == 4 ? &P->g[3]
                   : l < 7  ? &P->Y[3][l - 5]
                            : &P->y[3];
    lin *Ld = l < 4    ? &P->G3d[l]
              : l == 4 ? &P->g3d
              : l < 7  ? &P->Y3d[l - 5]
                       : &P->y3d;
    lin_deriv(m, L, Ld);
  }
}

/* The rules' rows at the times j h up to tmax (h about 0.3 rad of the
 * fastest motion, as the scan's grid); 0, or SS_ENOMEM. */
static int rules_init(problem *P, double tmax) {
  const ss_model *m = P->m;
  const ss_params *p = &m->p;
  P->h_rule = 0.3 / fmax(m->w[1], 1.0);
  P->t_short = 1.0 / m->w[1];
  P->n_rule = (int)fmax(0, fmin(ceil(tmax / P->h_rule), 100000));
  /* velocities, displacements and forces alike */
  P->tol_rule = 1e-9 * fmax(fmax(p->V, (p->ur - p->us) / p->chi), p->ur);
  P->slip_v = malloc((size_t)(P->n_rule + 1) * sizeof *P->slip_v);
  P->over_v = malloc((size_t)(P->n_rule + 1) * sizeof *P->over_v);
  P->stick_cs = malloc((size_t)(P->n_rule + 1) * sizeof *P->stick_cs);
  if (!P->slip_v || !P->over_v || !P->stick_cs)
    return SS_ENOMEM;
  for (int j = 1; j <= P->n_rule; j++) {
    ad t = ad_const(iv_exact((double)j * P->h_rule)), B[5];
    basis(m, &t, B);
    for (int c = 0; c < 2; c++)
      P->slip_v[j][c] = lin_at(&P->Y[3][c], B).v;
    P->slip_v[j][2] = iv_sub(lin_at(&P->y[3], B).v, P->V);
    for (int l = 0; l < 4; l++)
      P->over_v[j][l] = lin_at(&P->G[3][l], B).v;
    P->over_v[j][4] = lin_at(&P->g[3], B).v;
    P->stick_cs[j][0] = iv_cos(iv_exact((double)j * P->h_rule));
    P->stick_cs[j][1] = iv_sin(iv_exact((double)j * P->h_rule));
  }
  return 0;
}

static void problem_free(problem *P) {
  free(P->slip_v);
  free(P->over_v);
  free(P->stick_cs);
  P->slip_v = NULL;
  P->over_v = NULL;
  P->stick_cs = NULL;
}

static ad ad_var(iv x, int i) {
  ad r = ad_const(x);
  r.n = i + 1;
  for (int j = 0; j < i; j++)
    r.d[j] = iv_exact(0);
  r.d[i] = iv_exact(1);
  return r;
}

/* The end of the free phases from y0(s), as rows over (s1, s2, 1): x[i] .
 * (s1, s2, 1) is coordinate i at the end of the slip (slip-stick) or of
 * the overshoot (slip-overshoot-stick); a, and b for the overshoot, the
 * conditions x2' = V at the slip's and the overshoot's end. */
typedef struct ends {
  ad x[4][3];
  ad xs[4][3]; /* the slip's end (for slip-stick, x) */
  ad a[3], b[3];
  /* slip-overshoot-stick: V times the stick's duration, c . (s1, s2, 1) */
  ad c[3];
} ends;

static void free_ends(const problem *P, const iv *X, ends *e) {
  const ss_model *m = P->m;
  ad t1 = ad_var(X[0], 0), B1[5], B2[5];
  basis(m, &t1, B1);
  for (int i = 0; i < 4; i++) {
    e->x[i][0] = lin_at(&P->Y[i][0], B1);
    e->x[i][1] = lin_at(&P->Y[i][1], B1);
    e->x[i][2] = lin_at(&P->y[i], B1);
  }
  ad Vc = ad_const(P->V);
  e->a[0] = e->x[3][0];
  e->a[1] = e->x[3][1];
  e->a[2] = ad_sub(&e->x[3][2], &Vc);
  memcpy(e->xs, e->x, sizeof e->xs);
  ad t2 = ad_var(X[1], 1);
  if (P->n == 2) {
    /* the stick's end: x2 + V t2 = s1 + k */
    ad one = ad_const(iv_exact(1)), kc = ad_const(P->k);
    ad Vt = ad_scale(P->V, &t2);
    e->b[0] = ad_sub(&e->x[1][0], &one);
    e->b[1] = e->x[1][1];
    e->b[2] = ad_add(&e->x[1][2], &Vt);
    e->b[2] = ad_sub(&e->b[2], &kc);
    return;
  }
  /* the overshoot's end, G x + g, x the slip's end */
  ad y[4][3];
  basis(m, &t2, B2);
  for (int i = 0; i < 4; i++) {
    ad gi = lin_at(&P->g[i], B2);
    for (int c = 0; c < 3; c++)
      y[i][c] = c == 2 ? gi : ad_const(iv_exact(0));
    for (int l = 0; l < 4; l++) {
      ad Gil = lin_at(&P->G[i][l], B2);
      for (int c = 0; c < 3; c++) {
        ad q = ad_mul(&Gil, &e->x[l][c]);
        y[i][c] = ad_add(&y[i][c], &q);
      }
    }
  }
  memcpy(e->x, y, sizeof y);
  /* V t3 = s1 + k - x2 */
  ad one = ad_const(iv_exact(1)), kc = ad_const(P->k),
     zero = ad_const(iv_exact(0));
  e->c[0] = ad_sub(&one, &e->x[1][0]);
  e->c[1] = ad_sub(&zero, &e->x[1][1]);
  e->c[2] = ad_sub(&kc, &e->x[1][2]);
  e->b[0] = e->x[3][0];
  e->b[1] = e->x[3][1];
  e->b[2] = ad_sub(&e->x[3][2], &Vc);
}

static ad row_at(const ad *w, const ad *s1, const ad *s2) {
  ad p = ad_mul(&w[0], s1), q = ad_mul(&w[1], s2);
  p = ad_add(&p, &q);
  return ad_add(&p, &w[2]);
}

/* The residuals over the box X = (t1, [t2,] s1, s2), with gradients, from
 * the free phases' ends e: x2' = V at the end of each free phase, and the
 * closure of (x1, x1') after the stick, whose duration the closure of x2
 * gives, tau = (s1 + k - x2) / V (x2 at the stick's start):
 *   R0 = chi (s1 + k) - s1 + Ac cos tau + Bc sin tau,
 *   R1 = chi V - s2 - Ac sin tau + Bc cos tau,
 * Ac = x1 - chi x2 and Bc = x1' - chi V at the stick's start.  *tau: its
 * enclosure. */
static void residuals_at(const problem *P, const ends *e, const iv *X, ad *F,
                         iv *tau, ad *Erot) {
  int nf = 0;
  ad s1 = ad_var(X[2], 2), s2 = ad_var(X[3], 3);
  F[nf++] = row_at(e->a, &s1, &s2);
  F[nf++] = row_at(e->b, &s1, &s2);
  ad x0 = row_at(e->x[0], &s1, &s2), x1 = row_at(e->x[1], &s1, &s2),
     x2 = row_at(e->x[2], &s1, &s2);
  ad t;
  if (P->n == 2) {
    t = ad_var(X[1], 1);
  } else {
    ad kc = ad_const(P->k);
    t = ad_add(&s1, &kc);
    t = ad_sub(&t, &x1);
    t = ad_scale(P->Vinv, &t);
  }
  *tau = t.v;
  ad co, si;
  ad_cos_sin(1.0, &t, &co, &si);
  ad Ac = ad_scale(P->chi, &x1);
  Ac = ad_sub(&x0, &Ac);
  ad cv = ad_const(P->chiV);
  ad Bc = ad_sub(&x2, &cv);
  if (Erot) {
    /* the stick turns (Ac, Bc) into u = ((1 - chi) s1 - chi k, s2 - chi V),
     * a rotation: |u|^2 - |(Ac, Bc)|^2 = 0, whatever its duration */
    ad ck = ad_const(P->chik);
    ad u0 = ad_scale(P->omc, &s1);
    u0 = ad_sub(&u0, &ck);
    ad u1 = ad_sub(&s2, &cv);
    ad p0 = ad_mul(&u0, &u0), p1 = ad_mul(&u1, &u1), q0 = ad_mul(&Ac, &Ac),
       q1 = ad_mul(&Bc, &Bc);
    p0 = ad_add(&p0, &p1);
    q0 = ad_add(&q0, &q1);
    *Erot = ad_sub(&p0, &q0);
  }
  /* chi (s1 + k) - s1 = chi k - (1 - chi) s1 */
  ad r0 = ad_scale(P->omc, &s1);
  ad ck = ad_const(P->chik);
  r0 = ad_sub(&ck, &r0);
  ad p = ad_mul(&Ac, &co), q = ad_mul(&Bc, &si);
  r0 = ad_add(&r0, &p);
  F[nf++] = ad_add(&r0, &q);
  ad r1 = ad_sub(&cv, &s2);
  p = ad_mul(&Ac, &si);
  q = ad_mul(&Bc, &co);
  r1 = ad_sub(&r1, &p);
  F[nf++] = ad_add(&r1, &q);
}

static void residuals(const problem *P, const iv *X, ad *F, iv *tau) {
  ends e;
  free_ends(P, X, &e);
  residuals_at(P, &e, X, F, tau, NULL);
}

/* The inverse of the nv x nv matrix M (row-major, doubles) by Gauss-Jordan
 * with partial pivoting; 0 if singular or not finite.  Any matrix serves
 * as Krawczyk's preconditioner: this one need not be accurate. */
static int invert(int nv, const double *M, double *I) {
  double A[NV][2 * NV];
  for (int i = 0; i < nv; i++)
    for (int j = 0; j < nv; j++) {
      A[i][j] = M[nv * i + j];
      A[i][nv + j] = i == j;
    }
  for (int c = 0; c < nv; c++) {
    int p = c;
    for (int r = c + 1; r < nv; r++)
      if (fabs(A[r][c]) > fabs(A[p][c]))
        p = r;
    if (!(A[p][c] != 0) || !isfinite(A[p][c]))
      return 0;
    for (int j = 0; j < 2 * nv; j++) {
      double t = A[c][j];
      A[c][j] = A[p][j];
      A[p][j] = t;
    }
    double d = A[c][c];
    for (int j = 0; j < 2 * nv; j++)
      A[c][j] /= d;
    for (int r = 0; r < nv; r++)
      if (r != c && A[r][c] != 0) {
        double f = A[r][c];
        for (int j = 0; j < 2 * nv; j++)
          A[r][j] -= f * A[c][j];
      }
  }
  for (int i = 0; i < nv; i++)
    for (int j = 0; j < nv; j++) {
      I[nv * i + j] = A[i][nv + j];
      if (!isfinite(I[nv * i + j]))
        return 0;
    }
  return 1;
}

static iv iv_div(iv a, iv b) {
  /* b does not hold zero */
  iv r = {1 / b.hi, 1 / b.lo};
  r = (iv){dn(r.lo), up(r.hi)};
  return iv_mul(a, r);
}

/* One Gauss-Seidel step: the row a0 s[v] + a1 s[1 - v] in r narrows s[v].
 * 0 when s[v] is left empty. */
static int narrow(iv r, iv a0, iv a1, iv *s, int v) {
  if (iv_has_zero(a0))
    return 1;
  iv x = iv_div(iv_sub(r, iv_mul(a1, s[1 - v])), a0);
  if (isnan(x.lo) || isnan(x.hi))
    return 1;
  double lo = fmax(s[v].lo, x.lo), hi = fmin(s[v].hi, x.hi);
  if (lo > hi)
    return 0;
  s[v] = (iv){lo, hi};
  return 1;
}

/* One pass of interval Gauss-Seidel on s = (s1, s2) with the rows w0 and
 * w1 (over (s1, s2, 1)), preconditioned by the inverse of their midpoint
 * matrix, and (slip-overshoot-stick) the stick's duration in its range.
 * 0 when s is left empty. */
static int gauss_seidel(const problem *P, const ends *e, const iv *w0,
                        const iv *w1, iv *s) {
  iv A[2][2] = {{w0[0], w0[1]}, {w1[0], w1[1]}};
  iv r[2] = {{-w0[2].hi, -w0[2].lo}, {-w1[2].hi, -w1[2].lo}};
  double M[4] = {iv_mid(A[0][0]), iv_mid(A[0][1]), iv_mid(A[1][0]),
                 iv_mid(A[1][1])},
         Y[4];
  if (invert(2, M, Y)) {
    iv PA[2][2], q[2];
    for (int i = 0; i < 2; i++) {
      iv y0 = iv_exact(Y[2 * i]), y1 = iv_exact(Y[2 * i + 1]);
      q[i] = iv_add(iv_mul(y0, r[0]), iv_mul(y1, r[1]));
      for (int j = 0; j < 2; j++)
        PA[i][j] = iv_add(iv_mul(y0, A[0][j]), iv_mul(y1, A[1][j]));
    }
    memcpy(A, PA, sizeof A);
    memcpy(r, q, sizeof r);
  }
  /* slip-overshoot-stick: the stick's duration in its range, V t3 = c .
   * (s, 1), bounds s along the direction the two conditions leave loose
   * (where they are nearly parallel s is large, and so is t3) */
  iv rt = {0, 0};
  if (P->n == 3)
    rt = iv_sub(iv_mul(P->V, (iv){P->tau_lo, P->tau_hi}), e->c[2].v);
  for (int sweep = 0; sweep < 2; sweep++)
    for (int v = 0; v < 2; v++) {
      for (int i = 0; i < 2; i++)
        if (!narrow(r[i], A[i][v], A[i][1 - v], s, v))
          return 0;
      if (P->n == 3 && !narrow(rt, e->c[v].v, e->c[1 - v].v, s, v))
        return 0;
    }
  return 1;
}

/* Narrow s = (X[nt], X[nt + 1]) to the solutions of the two linear
 * conditions on it (a, b) over the durations of X.  0 when no s of X
 * solves them.
 * A short phase: a = x2'(t1) - x2'(0) over the slip (x2'(0) = V on
 * Sigma0), and for slip-overshoot-stick b - a = x2'(t2) - x2'(0) over the
 * overshoot, are nearly zero for every s, so they leave s loose.  a / t1
 * and (b - a) / t2, the phases' mean x2'' (rows over (s1, s2, 1)), have
 * the same solutions for t1, t2 > 0.  By the mean value theorem each of
 * their entries lies in the hull of the entry's derivative over [0, t],
 * which the rows Y3' s + y3' and G3' x + g3' (x the slip's end) give, plus
 * the forms' value at t = 0 (zero but for the rounding of the modal data)
 * over t.  Each pair of a or a / t1 with b or (b - a) / t2 that applies
 * narrows s in turn. */
static int contract_s(const problem *P, const ends *e, const iv *X, iv *s) {
  iv rows[4][3];
  int na = 1, nb = 1;
  for (int c = 0; c < 3; c++) {
    rows[0][c] = e->a[c].v;
    rows[2][c] = e->b[c].v;
  }
  if (X[0].lo > 0 && X[0].hi < P->t_short) {
    ad tt = ad_const((iv){0, X[0].hi}), B[5];
    basis(P->m, &tt, B);
    rows[1][0] = lin_at(&P->Y3d[0], B).v;
    rows[1][1] = lin_at(&P->Y3d[1], B).v;
    rows[1][2] = lin_at(&P->y3d, B).v;
    for (int c = 0; c < 3; c++)
      rows[1][c] = iv_add(rows[1][c], iv_div(P->a0[c], X[0]));
    na = 2;
  }
  if (P->n == 3 && X[1].lo > 0 && X[1].hi < P->t_short) {
    ad tt = ad_const((iv){0, X[1].hi}), B[5];
    basis(P->m, &tt, B);
    iv *q = rows[3], q0[3] = {{0, 0}, {0, 0}, P->q0[4]};
    q[0] = q[1] = iv_exact(0);
    q[2] = lin_at(&P->g3d, B).v;
    for (int l = 0; l < 4; l++) {
      iv gl = lin_at(&P->G3d[l], B).v;
      for (int c = 0; c < 3; c++) {
        q[c] = iv_add(q[c], iv_mul(gl, e->xs[l][c].v));
        q0[c] = iv_add(q0[c], iv_mul(P->q0[l], e->xs[l][c].v));
      }
    }
    for (int c = 0; c < 3; c++)
      q[c] = iv_add(q[c], iv_div(q0[c], X[1]));
    nb = 2;
  }
  for (int i = 0; i < na; i++)
    for (int j = 0; j < nb; j++)
      if (!gauss_seidel(P, e, rows[i], rows[2 + j], s))
        return 0;
  return 1;
}

/* The closure residuals with s eliminated, det [a; b; C] = C . (a x b),
 * functions of the durations alone: for slip-stick the stick's duration is
 * t2; for slip-overshoot-stick it is any value of T (the range the box
 * allows it), and the closure of x2 is a third, c . (a x b) = V t3 det.
 * Where one keeps a sign over the box no root lies there, of any s: at a
 * root with det != 0 it is det times the residual, and where a and b are
 * parallel and have a common solution a x b = 0.  Into R; their number. */
static int reduced_at(const problem *P, const ends *e, const iv *X, iv T,
                      ad *R) {
  ad sg[3];
  for (int i = 0; i < 3; i++) {
    int j = (i + 1) % 3, k = (i + 2) % 3;
    ad p = ad_mul(&e->a[j], &e->b[k]), q = ad_mul(&e->a[k], &e->b[j]);
    sg[i] = ad_sub(&p, &q);
  }
  /* the stick's duration: t2, or (slip-overshoot-stick) any value of T */
  ad st = P->n == 2 ? ad_var(X[1], 1) : ad_const(T), co, si;
  ad_cos_sin(1.0, &st, &co, &si);
  R[0] = R[1] = ad_const(iv_exact(0));
  for (int c = 0; c < 3; c++) {
    ad Ac = ad_scale(P->chi, &e->x[1][c]);
    Ac = ad_sub(&e->x[0][c], &Ac);
    ad Bc = e->x[2][c];
    if (c == 2) {
      ad cv = ad_const(P->chiV);
      Bc = ad_sub(&Bc, &cv);
    }
    ad p = ad_mul(&Ac, &co), q = ad_mul(&Bc, &si);
    ad r0 = ad_add(&p, &q);
    p = ad_mul(&Ac, &si);
    q = ad_mul(&Bc, &co);
    ad r1 = ad_sub(&q, &p);
    iv k0 = c == 0   ? (iv){-P->omc.hi, -P->omc.lo}
            : c == 2 ? P->chik
                     : iv_exact(0);
    iv k1 = c == 1 ? iv_exact(-1) : c == 2 ? P->chiV : iv_exact(0);
    ad c0 = ad_const(k0), c1 = ad_const(k1);
    r0 = ad_add(&r0, &c0);
    r1 = ad_add(&r1, &c1);
    p = ad_mul(&r0, &sg[c]);
    q = ad_mul(&r1, &sg[c]);
    R[0] = ad_add(&R[0], &p);
    R[1] = ad_add(&R[1], &q);
  }
  if (P->n == 2)
    return 2;
  /* the closure of x2: c . sigma = V t3 det */
  ad vt = ad_const(iv_mul(P->V, T));
  R[2] = ad_mul(&e->c[0], &sg[0]);
  for (int c = 1; c < 3; c++) {
    ad p = ad_mul(&e->c[c], &sg[c]);
    R[2] = ad_add(&R[2], &p);
  }
  ad q = ad_mul(&vt, &sg[2]);
  R[2] = ad_sub(&R[2], &q);
  return 3;
}

/* The mean-value form of f over X about its middle Xc: f(Xc) + f'(X) (X -
 * Xc), the gradient's first n entries (the rest are zero). */
static iv centred(iv f_mid, const ad *f, int n, const iv *X, const iv *Xc) {
  for (int j = 0; j < n && j < f->n; j++)
    f_mid = iv_add(f_mid, iv_mul(f->d[j], iv_sub(X[j], Xc[j])));
  return f_mid;
}

/* 1 when one of them keeps a sign (natural enclosure, or the mean-value
 * form about the middle of the durations, where the free phases end as ec
 * says). */
static int reduced_excludes(const problem *P, const ends *e, const ends *ec,
                            const iv *X, const iv *Xc, iv T) {
  ad R[3], Rc[3];
  int nr = reduced_at(P, e, X, T, R);
  for (int r = 0; r < nr; r++)
    if (!iv_has_zero(R[r].v))
      return 1;
  reduced_at(P, ec, Xc, T, Rc);
  for (int r = 0; r < nr; r++)
    if (!iv_has_zero(centred(Rc[r].v, &R[r], 2, X, Xc)))
      return 1;
  return 0;
}

/* The row of chi (x2 - x1) at the state x (rows over (s1, s2, 1)): the
 * friction the stick would need, times sg */
static void force_row(const problem *P, const ad x[4][3], double sg, iv w[3]) {
  iv c = iv_mul(iv_exact(sg), P->chi);
  for (int k = 0; k < 3; k++)
    w[k] = iv_mul(c, iv_sub(x[1][k].v, x[0][k].v));
}

/* Narrow s to the points where w . (s1, s2, 1) <= r may hold: w_v s_v <=
 * r - w2 - w_(1-v) s_(1-v) bounds s_v above where w_v > 0, below where w_v
 * < 0.  0 when s is left empty. */
static int narrow_le(const iv w[3], double r, iv *s) {
  for (int v = 0; v < 2; v++) {
    iv q = iv_sub(iv_sub(iv_exact(r), w[2]), iv_mul(w[1 - v], s[1 - v]));
    if (w[v].lo > 0) {
      iv x = iv_div(q, w[v]);
      if (x.hi < s[v].hi)
        s[v].hi = x.hi;
    } else if (w[v].hi < 0) {
      iv x = iv_div(q, w[v]);
      if (x.lo > s[v].lo)
        s[v].lo = x.lo;
    }
    if (!(s[v].lo <= s[v].hi)) /* also a NAN */
      return 0;
  }
  return 1;
}

/* The stick keeps |f| <= ur at the times j h before its least duration
 * (t2 for slip-stick; for slip-overshoot-stick V t3 = c . (s, 1)): x2 =
 * x2s + V t and c = x1 - chi x2 = Ac cos t + Bc sin t from the stick's
 * start, so f(t) = chi ((1 - chi) x2 - c) is a row over (s1, s2, 1) at each
 * such t.  0 when no s is left. */
static int keep_stick(const problem *P, const ends *e, const iv *X, iv *S) {
  double tol = P->tol_rule, ur = P->m->p.ur, h = P->h_rule;
  iv t3 = X[1];
  if (P->n == 3) {
    iv vt = iv_add(iv_add(iv_mul(e->c[0].v, S[0]), iv_mul(e->c[1].v, S[1])),
                   e->c[2].v);
    t3 = iv_mul(P->Vinv, vt);
  }
  int last = (int)fmax(0, fmin(t3.lo / h, P->n_rule));
  for (int j = last; j >= 1; j--) {
    double t = (double)j * h;
    if (!(t < t3.lo))
      continue;
    iv co = P->stick_cs[j][0], si = P->stick_cs[j][1], w[3];
    for (int c = 0; c < 3; c++) {
      iv x2 = e->x[1][c].v;
      iv ac = iv_sub(e->x[0][c].v, iv_mul(P->chi, x2));
      iv bc = c == 2 ? iv_sub(e->x[2][c].v, P->chiV) : e->x[2][c].v;
      if (c == 2)
        x2 = iv_add(x2, iv_mul(P->V, iv_exact(t)));
      iv r = iv_sub(iv_mul(P->omc, x2), iv_add(iv_mul(ac, co), iv_mul(bc, si)));
      w[c] = iv_mul(P->chi, r);
    }
    if (!narrow_le(w, ur + tol, S))
      return 0;
    for (int c = 0; c < 3; c++)
      w[c] = (iv){-w[c].hi, -w[c].lo};
    if (!narrow_le(w, ur + tol, S))
      return 0;
  }
  return 1;
}

/* Keep s in X to where its phases may keep the rules they must keep to be
 * an orbit (to tol_rule): the slip keeps x2' <= V (at the times j h before
 * the least t1), and ends with |f| <= ur into stick (slip-stick) or with
 * f <= -ur into overshoot (3.2; f = chi (x2 - x1)); the overshoot keeps
 * x2' >= V (at the times j h before the least t2) and ends with |f| <= ur.
 * Each is linear in s for given durations, so it narrows s as a linear
 * inequality.  A root of the equations where one of them fails is not an
 * orbit, so no orbit is lost; most roots are of that kind (scan.c: at chi
 * 0.96 all but 190 of 4391 have a slip that reaches V before its end), and
 * the proof need not isolate them.  0 when no s is left. */
static int keep_rules(const problem *P, const ends *e, iv *X) {
  iv *S = &X[P->nv - 2], w[3];
  double tol = P->tol_rule, ur = P->m->p.ur, V = P->m->p.V, h = P->h_rule;
  int last = (int)fmin(X[0].lo / h, P->n_rule);
  for (int j = last; j >= 1; j--)
    if ((double)j * h < X[0].lo && !narrow_le(P->slip_v[j], tol, S))
      return 0;
  force_row(P, e->xs, 1, w);
  if (!narrow_le(w, P->n == 2 ? ur + tol : -ur + tol, S))
    return 0;
  if (P->n == 2) {
    force_row(P, e->xs, -1, w);
    return narrow_le(w, ur + tol, S) && keep_stick(P, e, X, S);
  }
  force_row(P, e->x, 1, w);
  if (!narrow_le(w, ur + tol, S))
    return 0;
  force_row(P, e->x, -1, w);
  if (!narrow_le(w, ur + tol, S))
    return 0;
  last = (int)fmax(0, fmin(X[1].lo / h, P->n_rule));
  for (int j = last; j >= 1; j--) {
    if (!((double)j * h < X[1].lo))
      continue;
    /* V - x2' <= tol */
    const iv *g = P->over_v[j];
    for (int c = 0; c < 3; c++) {
      iv v = c == 2 ? g[4] : iv_exact(0);
      for (int l = 0; l < 4; l++)
        v = iv_add(v, iv_mul(g[l], e->xs[l][c].v));
      w[c] = (iv){-v.hi, -v.lo};
    }
    if (!narrow_le(w, tol - V, S))
      return 0;
  }
  return keep_stick(P, e, X, S);
}

/* What one box is: 0 no root, 1 exactly one root (its enclosure into E),
 * 2 not decided (X then cut to what may hold roots, K n X). */
static int box_test(const problem *P, iv *X, iv *E) {
  int nv = P->nv, nt = nv - 2;
  ends e, ec;
  free_ends(P, X, &e);
  if (!contract_s(P, &e, X, &X[nt]))
    return 0;
  if (P->slip_v && (!keep_rules(P, &e, X) || !contract_s(P, &e, X, &X[nt])))
    return 0;
  /* the middle, where the mean-value forms are centred (the free phases'
   * ends depend on the durations alone) */
  iv Xc[NV] = {{0, 0}}, tau, tauc;
  for (int i = 0; i < nv; i++)
    Xc[i] = iv_exact(iv_mid(X[i]));
  free_ends(P, Xc, &ec);
  if (P->n == 2 && reduced_excludes(P, &e, &ec, X, Xc, iv_exact(0)))
    return 0;
  ad FX[NV + 1], Fc[NV + 1];
  residuals_at(P, &e, X, FX, &tau, &FX[nv]);
  /* the stick's duration in its range */
  if (P->n == 3 && (tau.lo > P->tau_hi || tau.hi < P->tau_lo))
    return 0;
  /* slip-overshoot-stick: the closures with s eliminated, for any stick's
   * duration the box allows */
  if (P->n == 3 &&
      reduced_excludes(P, &e, &ec, X, Xc,
                       (iv){fmax(tau.lo, P->tau_lo), fmin(tau.hi, P->tau_hi)}))
    return 0;
  residuals_at(P, &ec, Xc, Fc, &tauc, &Fc[nv]);
  /* exclusion by an enclosure of a residual or of the rotation condition:
   * the natural one, or the mean-value form */
  for (int r = 0; r <= nv; r++)
    if (!iv_has_zero(FX[r].v) ||
        !iv_has_zero(centred(Fc[r].v, &FX[r], nv, X, Xc)))
      return 0;
  /* the closure residuals (and the rotation condition) less their
   * dependence on s through the two linear conditions: G = R - la a - lb b,
   * (la, lb) cancelling dG/ds at the middle.  s follows from the durations,
   * so G's enclosure is nearly R's along the solutions, not over s's
   * interval as if it were free of t */
  double A[4] = {iv_mid(FX[0].d[nt]), iv_mid(FX[1].d[nt]),
                 iv_mid(FX[0].d[nt + 1]), iv_mid(FX[1].d[nt + 1])},
         Ai[4];
  if (invert(2, A, Ai))
    for (int r = 2; r <= nv; r++) {
      double g0 = iv_mid(FX[r].d[nt]), g1 = iv_mid(FX[r].d[nt + 1]);
      iv la = iv_exact(Ai[0] * g0 + Ai[1] * g1),
         lb = iv_exact(Ai[2] * g0 + Ai[3] * g1);
      iv v = iv_sub(iv_sub(Fc[r].v, iv_mul(la, Fc[0].v)), iv_mul(lb, Fc[1].v));
      for (int j = 0; j < nv; j++) {
        iv d = iv_sub(iv_sub(FX[r].d[j], iv_mul(la, FX[0].d[j])),
                      iv_mul(lb, FX[1].d[j]));
        v = iv_add(v, iv_mul(d, iv_sub(X[j], Xc[j])));
      }
      if (!iv_has_zero(v))
        return 0;
    }
  /* Krawczyk */
  double M[NV * NV] = {0}, Yp[NV * NV];
  for (int r = 0; r < nv; r++)
    for (int j = 0; j < nv; j++)
      M[nv * r + j] = iv_mid(FX[r].d[j]);
  if (!invert(nv, M, Yp))
    return 2;
  iv K[NV];
  int inside = 1, misses = 0;
  for (int i = 0; i < nv; i++) {
    /* c - Y F(c) */
    iv v = Xc[i];
    for (int r = 0; r < nv; r++)
      v = iv_sub(v, iv_mul(iv_exact(Yp[nv * i + r]), Fc[r].v));
    /* + (I - Y J) (X - c) */
    for (int j = 0; j < nv; j++) {
      iv a = iv_exact(i == j ? 1.0 : 0.0);
      for (int r = 0; r < nv; r++)
        a = iv_sub(a, iv_mul(iv_exact(Yp[nv * i + r]), FX[r].d[j]));
      v = iv_add(v, iv_mul(a, iv_sub(X[j], Xc[j])));
    }
    if (isnan(v.lo) || isnan(v.hi))
      return 2;
    misses |= v.lo > X[i].hi || v.hi < X[i].lo;
    inside = inside && v.lo > X[i].lo && v.hi < X[i].hi;
    K[i] = v;
  }
  if (misses)
    return 0;
  if (inside) {
    for (int i = 0; i < nv; i++)
      E[i] = K[i];
    return 1;
  }
  for (int i = 0; i < nv; i++) {
    X[i].lo = fmax(X[i].lo, K[i].lo);
    X[i].hi = fmin(X[i].hi, K[i].hi);
  }
  return 2;
}

/* Newton from the middle of X in floating point, for an approximate root
 * to build a box around; 1 if it converged within reach of X. */
static int newton_point(const problem *P, const iv *X, double *r) {
  int nv = P->nv;
  iv Xr[NV] = {{0, 0}};
  double reach = 0;
  for (int i = 0; i < nv; i++)
    r[i] = iv_mid(X[i]);
  for (int it = 0; it < NEWTON_ITERS; it++) {
    for (int i = 0; i < nv; i++)
      Xr[i] = iv_exact(r[i]);
    ad F[NV];
    iv tau;
    residuals(P, Xr, F, &tau);
    double M[NV * NV], Y[NV * NV], step = 0;
    for (int i = 0; i < nv; i++)
      for (int j = 0; j < nv; j++)
        M[nv * i + j] = iv_mid(F[i].d[j]);
    if (!invert(nv, M, Y))
      return 0;
    for (int i = 0; i < nv; i++) {
      double d = 0;
      for (int j = 0; j < nv; j++)
        d -= Y[nv * i + j] * iv_mid(F[j].v);
      r[i] += d;
      step = fmax(step, fabs(d) / (X[i].hi - X[i].lo));
    }
    if (!(step < 4))
      return 0;
    if (step < 1e-6)
      break;
  }
  for (int i = 0; i < nv; i++) {
    double w = X[i].hi - X[i].lo;
    reach = fmax(reach, fabs(r[i] - iv_mid(X[i])) / w);
  }
  return reach < 2;
}

/* A root proved unique in H, enclosed in E (within H): the same as a root
 * already listed when one's enclosure lies in the other's box; -1 when
 * they overlap but neither holds the other's (not decided), 0 new, 1 known. */
static int known_root(const ss__certificate *c, int nv, const iv *H,
                      const iv *E) {
  for (int k = 0; k < c->n_roots; k++) {
    const ss__cert_root *q = &c->roots[k];
    int e_in_q = 1, qe_in_h = 1, meet = 1;
    for (int i = 0; i < nv; i++) {
      e_in_q = e_in_q && E[i].lo >= q->box.lo[i] && E[i].hi <= q->box.hi[i];
      qe_in_h = qe_in_h && q->at.lo[i] >= H[i].lo && q->at.hi[i] <= H[i].hi;
      meet = meet && E[i].lo <= q->box.hi[i] && E[i].hi >= q->box.lo[i];
    }
    if (e_in_q || qe_in_h)
      return 1;
    if (meet) {
      /* E reaches into q's box, without lying in it: still two roots if
       * q's enclosure and E are apart */
      int apart = 0;
      for (int i = 0; i < nv; i++)
        apart |= E[i].lo > q->at.hi[i] || E[i].hi < q->at.lo[i];
      if (!apart)
        return -1;
    }
  }
  return 0;
}

static int add_root(ss__certificate *c, int nv, const iv *H, const iv *E) {
  int k = known_root(c, nv, H, E);
  if (k != 0)
    return k;
  if (c->n_roots == c->cap_roots) {
    int cap = c->cap_roots ? 2 * c->cap_roots : 16;
    ss__cert_root *q = realloc(c->roots, (size_t)cap * sizeof *q);
    if (!q)
      return -2;
    c->roots = q;
    c->cap_roots = cap;
  }
  ss__cert_root *q = &c->roots[c->n_roots++];
  memset(q, 0, sizeof *q);
  for (int i = 0; i < nv; i++) {
    q->box.lo[i] = H[i].lo;
    q->box.hi[i] = H[i].hi;
    q->at.lo[i] = fmax(E[i].lo, H[i].lo);
    q->at.hi[i] = fmin(E[i].hi, H[i].hi);
  }
  return 0;
}

static void note_undecided(ss__certificate *c, int nv, const iv *X) {
  if (c->n_undecided++ == 0)
    for (int i = 0; i < nv; i++) {
      c->undecided.lo[i] = X[i].lo;
      c->undecided.hi[i] = X[i].hi;
    }
}

/* The root proved unique in H (E its interval of the unknowns) recorded;
 * if it cannot be told apart from one recorded before, box X (which holds
 * it) noted undecided.  SS_ENOMEM when there is no room for it. */
static int record_root(ss__certificate *c, int nv, const iv *H, const iv *E,
                       const iv *X) {
  int k = add_root(c, nv, H, E);
  if (k == -2)
    return SS_ENOMEM;
  if (k == -1)
    note_undecided(c, nv, X);
  return SS_OK;
}

/* The side to halve X across: the widest relative to the starting box's
 * widths W (its relative width in *rel); the states (s1, s2) weigh less:
 * they follow from the durations. */
static int widest_side(int nv, const iv *X, const double *W, double *rel) {
  int w = 0;
  *rel = 0;
  for (int i = 0; i < nv; i++) {
    double v = (X[i].hi - X[i].lo) / W[i] * (i >= nv - 2 ? STATE_WEIGHT : 1);
    if (v > *rel) {
      *rel = v;
      w = i;
    }
  }
  return w;
}

/* A small box X that is not decided may hold a root near its face: prove
 * it in a box H around Newton's point that holds X.  1 when that decides X
 * (H holds no root, or its root is recorded: *rc SS_OK, or SS_ENOMEM when
 * there was no room for it), 0 when X is still to be halved. */
static int decide_near_newton(const problem *P, const iv *X,
                              ss__certificate *out, int *rc) {
  int nv = P->nv;
  double rp[NV];
  if (!newton_point(P, X, rp))
    return 0;
  iv H[NV], EH[NV];
  for (int i = 0; i < nv; i++) {
    double wi = X[i].hi - X[i].lo;
    H[i].lo = fmin(X[i].lo, rp[i] - 0.25 * wi);
    H[i].hi = fmax(X[i].hi, rp[i] + 0.25 * wi);
  }
  iv Hc[NV];
  memcpy(Hc, H, sizeof H);
  int rh = box_test(P, Hc, EH);
  if (rh == 0)
    return 1; /* H, and X in it, holds no root */
  if (rh == 1) {
    /* unique in Hc, which box_test narrowed: by the phases' rules too, so
     * a root that breaks one may lie in H outside Hc */
    *rc = record_root(out, nv, Hc, EH, X);
    return 1;
  }
  return 0;
}

int ss__certify_period1(const ss_model *m, int n, const double lo[4],
                        const double hi[4], double stick_lo, double stick_hi,
                        long max_boxes, int (*stop)(void *), void *stop_cls,
                        ss__certificate *out) {
  memset(out, 0, sizeof *out);
  if ((n != 2 && n != 3) || !(stick_hi > stick_lo) || !isfinite(stick_lo) ||
      !isfinite(stick_hi))
    return SS_EINVAL;
  problem P;
  problem_init(&P, m, n);
  P.tau_lo = stick_lo;
  P.tau_hi = stick_hi;
  int nv = P.nv;
  double W[NV];
  for (int i = 0; i < nv; i++) {
    if (!(hi[i] > lo[i] && isfinite(hi[i]) && isfinite(lo[i])))
      return SS_EINVAL;
    W[i] = hi[i] - lo[i];
  }
  iv(*stack)[NV] = malloc(STACK_MAX * sizeof *stack);
  if (!stack || rules_init(&P, fmax(hi[0], hi[1]))) {
    free(stack);
    problem_free(&P);
    return SS_ENOMEM;
  }
  for (int i = 0; i < nv; i++)
    stack[0][i] = (iv){lo[i], hi[i]};
  int top = 1, rc = SS_OK;
  while (top > 0) {
    if (out->boxes >= max_boxes) {
      out->budget_spent = 1;
      break;
    }
    if (stop && (out->boxes & 1023) == 0 && stop(stop_cls)) {
      rc = SS_ECANCELED;
      break;
    }
    iv X[NV], E[NV];
    memcpy(X, stack[--top], sizeof X);
    out->boxes++;
    int r = box_test(&P, X, E);
    if (r == 0)
      continue;
    if (r == 1) {
      if ((rc = record_root(out, nv, X, E, X)))
        break;
      continue;
    }
    double rel;
    int w = widest_side(nv, X, W, &rel);
    if (rel < INFLATE_BELOW && decide_near_newton(&P, X, out, &rc)) {
      if (rc)
        break;
      continue;
    }
    if (!((X[w].hi - X[w].lo) / W[w] > MIN_WIDTH) || top + 2 > STACK_MAX) {
      note_undecided(out, nv, X);
      continue;
    }
    double mid = iv_mid(X[w]);
    memcpy(stack[top], X, sizeof X);
    stack[top][w].hi = mid;
    top++;
    memcpy(stack[top], X, sizeof X);
    stack[top][w].lo = mid;
    top++;
  }
  if (top > 0 && rc == SS_OK)
    out->budget_spent = 1;
  out->complete = rc == SS_OK && !out->budget_spent && out->n_undecided == 0;
  free(stack);
  problem_free(&P);
  return rc;
}

void ss__cert_polish(const ss_model *m, int n, const ss__cert_root *r,
                     double u[4]) {
  problem P;
  problem_init(&P, m, n);
  iv X[NV] = {{0, 0}};
  for (int i = 0; i < P.nv; i++)
    X[i] = (iv){r->at.lo[i], r->at.hi[i]};
  int nv = P.nv;
  double v[NV];
  for (int i = 0; i < nv; i++)
    u[i] = v[i] = iv_mid(X[i]);
  for (int it = 0; it < NEWTON_ITERS; it++) {
    iv Xr[NV] = {{0, 0}};
    ad F[NV];
    iv tau;
    double M[NV * NV] = {0}, Y[NV * NV];
    for (int i = 0; i < nv; i++)
      Xr[i] = iv_exact(v[i]);
    residuals(&P, Xr, F, &tau);
    for (int i = 0; i < nv; i++)
      for (int j = 0; j < nv; j++)
        M[nv * i + j] = iv_mid(F[i].d[j]);
    if (!invert(nv, M, Y))
      return;
    double step = 0;
    for (int i = 0; i < nv; i++) {
      double d = 0;
      for (int j = 0; j < nv; j++)
        d -= Y[nv * i + j] * iv_mid(F[j].v);
      v[i] += d;
      step = fmax(step, fabs(d) / (1 + fabs(v[i])));
    }
    /* the root is the only one in its box: Newton must stay there */
    for (int i = 0; i < nv; i++)
      if (!(v[i] >= r->box.lo[i] && v[i] <= r->box.hi[i]))
        return;
    memcpy(u, v, sizeof v[0] * (size_t)nv);
    if (step < 1e-15)
      return;
  }
}

void ss__certificate_free(ss__certificate *c) {
  free(c->roots);
  c->roots = NULL;
  c->n_roots = c->cap_roots = 0;
}

void ss__cert_point(const ss_model *m, int n, const double *u, double *F,
                    double *stick) {
  problem P;
  problem_init(&P, m, n);
  iv X[NV] = {{0, 0}};
  for (int i = 0; i < P.nv; i++)
    X[i] = iv_exact(u[i]);
  ad R[NV];
  iv tau;
  residuals(&P, X, R, &tau);
  for (int i = 0; F && i < P.nv; i++)
    F[i] = iv_mid(R[i].v);
  *stick = iv_mid(tau);
}

void ss__cert_enclose(const ss_model *m, int n, const double lo[4],
                      const double hi[4], double Flo[4], double Fhi[4],
                      double Jlo[16], double Jhi[16]) {
  problem P;
  problem_init(&P, m, n);
  iv X[NV] = {{0, 0}}, tau;
  for (int i = 0; i < P.nv; i++)
    X[i] = (iv){lo[i], hi[i]};
  ad F[NV];
  residuals(&P, X, F, &tau);
  for (int r = 0; r < P.nv; r++) {
    Flo[r] = F[r].v.lo;
    Fhi[r] = F[r].v.hi;
    for (int j = 0; j < P.nv; j++) {
      iv d = j < F[r].n ? F[r].d[j] : iv_exact(0);
      Jlo[P.nv * r + j] = d.lo;
      Jhi[P.nv * r + j] = d.hi;
    }
  }
}
