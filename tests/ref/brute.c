/*
 * brute.c: brute-force search for ALL feasible period-1 orbits of the
 * sequences (A) slip -> stick and (B) slip -> overshoot -> stick, each phase
 * duration in (0, dmax].  Independent of libstickslip: written from the
 * equations (1.1)-(1.2) alone (closed-form modal solution of each mode, own
 * event location); refsim.h is used only by brute_refcheck().
 *
 * EQUATIONS.  State y = (x1, x2, x1', x2').  Slip (u = +us) and overshoot
 * (u = -us): x'' = -K (x - d), d = +d0 / -d0, d0 = (us/(1-chi),
 * us/(chi(1-chi))), K = [[1,-chi],[-chi eta, chi eta]], solved by our own
 * eigen-decomposition of K (eigenvalues 0 < l_slow < 1 < l_fast, eigenvectors
 * (chi, 1-l)).  Stick: x2 = x2(0) + V t and x1 - chi x2 = A cos t + B sin t,
 * so the friction force f = chi (x2 - x1) = chi ((1-chi) x2 - A cos t -
 * B sin t).  All flows are affine in the state.
 *
 * REDUCTION TO TWO UNKNOWNS.  An orbit starts at the stick -> slip point
 * y0(s) = (x1, x1 + ur/chi, x1', V), s = (x1, x1').  In the stick phase x2
 * grows like V t, so the stick duration is EXPLICIT: t_stick = (x2(y0) -
 * x2(stick start)) / V, and closure of x2 is then automatic.  Hence
 *  (A) unknowns (t1, t2): s solves the 2x2 linear system {x2' = V at the end
 *      of slip, x2(end of slip) + V t2 = x2(y0)}; residual R = closure of
 *      (x1, x1') after the stick phase (2 equations);
 *  (B) unknowns (t1, t2): s solves {x2' = V after the slip, x2' = V after
 *      the overshoot}; t3 = (x2(y0) - x2c) / V; residual R = closure of
 *      (x1, x1') after the stick of duration t3.
 * Both are two equations in (t1, t2) in (0, dmax]^2 (plus t3 in (0, dmax]).
 *
 * GRID.  h = dmax / N with N = ceil(dmax / min(0.1 / w_fast, 0.1)), i.e. at
 * most 0.1 rad of the fastest phase (slip modes or the unit stick frequency)
 * per cell, at least 63 points per fastest period (N ~ 1000-1500 for the
 * test ranges; about 1-2 M residual evaluations per sequence).  The
 * residual is scanned scaled by the determinant of the 2x2 system (det * R is
 * smooth and pole-free for (A); for (B) only the stick rotation through t3
 * is not).  A cell is a candidate when, for both components, the corner
 * values reach to within 0.5 * (their spread) of zero (looser than a sign
 * change, to catch curved zero lines and near-tangent intersections).  (B)
 * cells in which t3 varies by more than 0.5 rad, or the determinant changes
 * sign, are split recursively (up to 16x finer); a cell still split at the
 * finest level, or with a corner's t3 outside (-0.5, dmax + 0.5), is not a
 * candidate.  From each candidate cell Newton (central-difference Jacobian,
 * damped to 3 cells a step) starts at the centre and at the four
 * quarter-cell centres; a start whose first step is longer than 3 cells is
 * given up (the root it points to is another cell's), and so is one still
 * taking steps over 1e-6 after 16.  Roots are deduplicated (|dt| < 1e-7).
 *
 * CHECK.  Each root is re-simulated from its s with our own event-driven
 * closed-form simulator: the first root of each switching function is
 * located by a certified branch-and-bound (linear interpolation plus the
 * bound |g''| <= M2 taken from the modal amplitudes, so a crossing or a
 * touching to within M2*ulp^2 cannot be stepped over), then bisected to
 * adjacent doubles.  A root is kept only if the simulated return follows
 * exactly the expected sequence, with the same durations (to 1e-7), closure
 * < 1e-8, and every margin > 0.  margin = min of:
 *   end of slip: (A) ur - |f|; (B) -ur - f; end of overshoot: ur - |f|;
 *   slip/overshoot: -(x2' - V) resp. -(V - x2') at every interior local
 *     maximum (sampled at 0.02 rad of w_fast, refined by bisection on the
 *     derivative), and the end crossing slope divided by eta
 *     (us - f resp. f + us);
 *   stick: ur - f at interior maxima, f + ur at minima and at both ends,
 *     ur - f at the start, f' at the end.
 * The spectral radius is that of the central-difference Jacobian (step
 * 1e-5 * max(1, |s|)) of the simulated Poincare map on the section.
 *
 * WHAT CAN STILL BE MISSED.  Two roots closer than about a quarter cell
 * (~0.02-0.03 in durations, i.e. a pair born in a fold a very short
 * parameter distance away) may merge into one; a root where the two zero
 * lines are tangent (a fold exactly) may be missed; roots with t1 < h or
 * (for B) t2 < h are not scanned (the grid lines t1 = 0, t2 = 0 are
 * degenerate: det = 0 there), although such short slip / overshoot phases
 * are physically implausible (the force must fall from ur to below us in
 * a slip, rise from -ur to above -us in an overshoot); degenerate roots with
 * a singular 2x2 system are not found, nor (B) roots within 1/16 of a cell
 * of where it is singular, where t3 turns faster than 8 rad per cell.
 * Nothing here is a certificate of completeness.
 */
#include "brute.h"
#include "refsim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#define BR_PI 3.14159265358979323846
/* (B) cells in which t3 varies by more than BRUTE_T3_SPREAD rad, or the
 * determinant changes sign, are split, at most BRUTE_DEPTH times. */
#ifndef BRUTE_DEPTH
#define BRUTE_DEPTH 4
#endif
#ifndef BRUTE_T3_SPREAD
#define BRUTE_T3_SPREAD 0.5
#endif

enum { SLIP = 0, OVER = 1, STICK = 2 };

typedef struct model {
  double chi, eta, us, ur, V;
  double w[2];              /* modal frequencies, w[0] slow, w[1] fast */
  double P[2][2], Pi[2][2]; /* modal matrix (columns eigenvectors), inverse */
  double d0[2];
  double dmax;
} model;

static int model_init(model *m, const brute_params *p) {
  if (!p)
    return -1;
  double chi = p->chi, eta = p->eta;
  if (!(chi > 0 && chi < 1 && eta > 0 && isfinite(eta) && p->us > 0 &&
        p->ur > p->us && isfinite(p->ur) && p->V > 0 && isfinite(p->V)))
    return -1;
  m->chi = chi;
  m->eta = eta;
  m->us = p->us;
  m->ur = p->ur;
  m->V = p->V;
  double ce = chi * eta, a = 1 - ce;
  double disc = sqrt(a * a + 4 * ce * chi);
  double lb = 0.5 * (1 + ce + disc), ls = ce * (1 - chi) / lb;
  /* 1 - l without cancellation */
  double oms = a >= 0 ? 0.5 * (a + disc) : 2 * ce * chi / (disc - a);
  double omb = a <= 0 ? 0.5 * (a - disc) : -2 * ce * chi / (disc + a);
  m->w[0] = sqrt(ls);
  m->w[1] = sqrt(lb);
  double n0 = hypot(chi, oms), n1 = hypot(chi, omb);
  m->P[0][0] = chi / n0;
  m->P[1][0] = oms / n0;
  m->P[0][1] = chi / n1;
  m->P[1][1] = omb / n1;
  double det = m->P[0][0] * m->P[1][1] - m->P[0][1] * m->P[1][0];
  m->Pi[0][0] = m->P[1][1] / det;
  m->Pi[0][1] = -m->P[0][1] / det;
  m->Pi[1][0] = -m->P[1][0] / det;
  m->Pi[1][1] = m->P[0][0] / det;
  m->d0[0] = p->us / (1 - chi);
  m->d0[1] = p->us / (chi * (1 - chi));
  m->dmax = 1.5 * 2 * BR_PI / m->w[0];
  return 0;
}

double brute_dmax(const brute_params *p) {
  model m;
  if (model_init(&m, p))
    return NAN;
  return m.dmax;
}

/* ---- closed-form flows ------------------------------------------------ */

/* Linear part of the slip/overshoot flow for time t (4x4, on (z, z')). */
static void lin_flow(const model *m, double t, double M[4][4]) {
  double c[2], sn[2];
  for (int k = 0; k < 2; k++) {
    c[k] = cos(m->w[k] * t);
    sn[k] = sin(m->w[k] * t);
  }
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) {
      double zz = 0, zv = 0, vz = 0;
      for (int k = 0; k < 2; k++) {
        double pp = m->P[i][k] * m->Pi[k][j];
        zz += pp * c[k];
        zv += pp * sn[k] / m->w[k];
        vz -= pp * sn[k] * m->w[k];
      }
      M[i][j] = zz;
      M[i][2 + j] = zv;
      M[2 + i][j] = vz;
      M[2 + i][2 + j] = zz;
    }
}

/* out = M (y - D) + D, D = (+-d0, 0, 0). */
static void aff_apply(const model *m, int mode, double M[4][4],
                      const double y[4], double out[4]) {
  double sg = mode == SLIP ? 1 : -1;
  double D[4] = {sg * m->d0[0], sg * m->d0[1], 0, 0}, z[4];
  for (int i = 0; i < 4; i++)
    z[i] = y[i] - D[i];
  for (int i = 0; i < 4; i++) {
    double acc = D[i];
    for (int j = 0; j < 4; j++)
      acc += M[i][j] * z[j];
    out[i] = acc;
  }
}

/* Slip from the section point y0(s): y_b = Y s + y. */
typedef struct preS {
  double Y[4][2], y[4];
} preS;
/* Overshoot flow: y_c = G y_b + g. */
typedef struct preO {
  double G[4][4], g[4];
} preO;

static void pre_slip(const model *m, double t, preS *S) {
  double M[4][4], a0[4] = {0, m->ur / m->chi, 0, m->V};
  lin_flow(m, t, M);
  for (int i = 0; i < 4; i++) {
    S->Y[i][0] = M[i][0] + M[i][1];
    S->Y[i][1] = M[i][2];
  }
  aff_apply(m, SLIP, M, a0, S->y);
}

static void pre_over(const model *m, double t, preO *O) {
  double zero[4] = {0, 0, 0, 0};
  lin_flow(m, t, O->G);
  aff_apply(m, OVER, O->G, zero, O->g);
}

/* ---- the two reduced residuals ------------------------------------------ */

/* (A) det * R and det * s for (t1 from S, t2); returns det. */
static double evalA(const model *m, const preS *S, double t2, double c2,
                    double s2, double Rn[2], double sn[2]) {
  double k = m->ur / m->chi, chi = m->chi, V = m->V;
  double a0 = S->Y[3][0], a1 = S->Y[3][1], ra = V - S->y[3];
  double b0 = S->Y[1][0] - 1, b1 = S->Y[1][1], rb = k - S->y[1] - V * t2;
  double det = a0 * b1 - a1 * b0;
  sn[0] = ra * b1 - a1 * rb;
  sn[1] = a0 * rb - b0 * ra;
  double yb[3];
  for (int i = 0; i < 3; i++)
    yb[i] = S->Y[i][0] * sn[0] + S->Y[i][1] * sn[1] + S->y[i] * det;
  double Ac = yb[0] - chi * yb[1], Bc = yb[2] - chi * V * det;
  double A = Ac * c2 + Bc * s2, B = -Ac * s2 + Bc * c2;
  double x20 = sn[0] + k * det;
  Rn[0] = chi * x20 + A - sn[0];
  Rn[1] = chi * V * det + B - sn[1];
  return det;
}

typedef struct ptB {
  double Rn[2], t3, det, Nn;
} ptB;

/* (B) det * R, t3, det, det * t3; s (unscaled) into s if not NULL. */
static void evalB(const model *m, const preS *S, const preO *O, ptB *q,
                  double *R, double *s) {
  double k = m->ur / m->chi, chi = m->chi, V = m->V;
  double a0 = S->Y[3][0], a1 = S->Y[3][1], ra = V - S->y[3];
  double b0 = 0, b1 = 0, cg = O->g[3];
  for (int l = 0; l < 4; l++) {
    b0 += O->G[3][l] * S->Y[l][0];
    b1 += O->G[3][l] * S->Y[l][1];
    cg += O->G[3][l] * S->y[l];
  }
  double rb = V - cg;
  double det = a0 * b1 - a1 * b0;
  q->det = det;
  double sv[2] = {(ra * b1 - a1 * rb) / det, (a0 * rb - b0 * ra) / det};
  if (!(det != 0) || !isfinite(sv[0]) || !isfinite(sv[1])) {
    q->Rn[0] = q->Rn[1] = NAN;
    q->t3 = INFINITY;
    q->Nn = NAN;
    if (R)
      R[0] = R[1] = NAN;
    return;
  }
  double yb[4], yc[4];
  for (int i = 0; i < 4; i++)
    yb[i] = S->Y[i][0] * sv[0] + S->Y[i][1] * sv[1] + S->y[i];
  for (int i = 0; i < 3; i++) {
    double acc = O->g[i];
    for (int l = 0; l < 4; l++)
      acc += O->G[i][l] * yb[l];
    yc[i] = acc;
  }
  double x20 = sv[0] + k;
  double t3 = (x20 - yc[1]) / V;
  double Ac = yc[0] - chi * yc[1], Bc = yc[2] - chi * V;
  double c3 = cos(t3), s3 = sin(t3);
  double A = Ac * c3 + Bc * s3, B = -Ac * s3 + Bc * c3;
  double r0 = chi * x20 + A - sv[0], r1 = chi * V + B - sv[1];
  q->t3 = t3;
  q->Nn = det * t3;
  q->Rn[0] = det * r0;
  q->Rn[1] = det * r1;
  if (R) {
    R[0] = r0;
    R[1] = r1;
  }
  if (s) {
    s[0] = sv[0];
    s[1] = sv[1];
  }
}

/* Unscaled residual of sequence kind (0 = A, 1 = B) at t; s, t3 out. */
static int resid(const model *m, int kind, const double t[2], double R[2],
                 double s[2], double *t3) {
  preS S;
  pre_slip(m, t[0], &S);
  if (kind == 0) {
    double Rn[2], sn[2];
    double det = evalA(m, &S, t[1], cos(t[1]), sin(t[1]), Rn, sn);
    if (!(det != 0))
      return -1;
    R[0] = Rn[0] / det;
    R[1] = Rn[1] / det;
    if (s) {
      s[0] = sn[0] / det;
      s[1] = sn[1] / det;
    }
    if (t3)
      *t3 = 0;
  } else {
    preO O;
    ptB q;
    double sv[2];
    pre_over(m, t[1], &O);
    evalB(m, &S, &O, &q, R, sv);
    if (s) {
      s[0] = sv[0];
      s[1] = sv[1];
    }
    if (t3)
      *t3 = q.t3;
  }
  return isfinite(R[0]) && isfinite(R[1]) ? 0 : -1;
}

/* ---- phases, switching functions, certified event location ------------- */

typedef struct phase {
  int mode;
  double al[2], be[2], d[2]; /* slip/overshoot: q_k = al cos + be sin */
  double A, B, x2c;          /* stick */
  double M2, om;             /* bound on |g''|, fastest frequency */
} phase;

static void phase_init(const model *m, phase *ph, int mode, const double y[4]) {
  ph->mode = mode;
  if (mode == STICK) {
    ph->x2c = y[1];
    ph->A = y[0] - m->chi * y[1];
    ph->B = y[2] - m->chi * m->V;
    ph->M2 = m->chi * hypot(ph->A, ph->B);
    ph->om = 1;
    return;
  }
  double sg = mode == SLIP ? 1 : -1;
  ph->d[0] = sg * m->d0[0];
  ph->d[1] = sg * m->d0[1];
  double z[2] = {y[0] - ph->d[0], y[1] - ph->d[1]};
  ph->M2 = 0;
  for (int k = 0; k < 2; k++) {
    double q = m->Pi[k][0] * z[0] + m->Pi[k][1] * z[1];
    double qd = m->Pi[k][0] * y[2] + m->Pi[k][1] * y[3];
    ph->al[k] = q;
    ph->be[k] = qd / m->w[k];
    ph->M2 += fabs(m->P[1][k]) * m->w[k] * m->w[k] * m->w[k] *
              hypot(ph->al[k], ph->be[k]);
  }
  ph->om = m->w[1] > 1 ? m->w[1] : 1;
}

static void phase_state(const model *m, const phase *ph, double t,
                        double y[4]) {
  if (ph->mode == STICK) {
    double c = cos(t), s = sin(t);
    y[1] = ph->x2c + m->V * t;
    y[0] = m->chi * y[1] + ph->A * c + ph->B * s;
    y[2] = m->chi * m->V - ph->A * s + ph->B * c;
    y[3] = m->V;
    return;
  }
  double q[2], qd[2];
  for (int k = 0; k < 2; k++) {
    double c = cos(m->w[k] * t), s = sin(m->w[k] * t);
    q[k] = ph->al[k] * c + ph->be[k] * s;
    qd[k] = m->w[k] * (-ph->al[k] * s + ph->be[k] * c);
  }
  for (int i = 0; i < 2; i++) {
    y[i] = ph->d[i] + m->P[i][0] * q[0] + m->P[i][1] * q[1];
    y[2 + i] = m->P[i][0] * qd[0] + m->P[i][1] * qd[1];
  }
}

/* Switching function `which` (negative inside the mode) and derivative.
 * slip: x2' - V; overshoot: V - x2'; stick: 0: f - ur, 1: -ur - f. */
static double phase_g(const model *m, const phase *ph, int which, double t,
                      double *dg) {
  if (ph->mode == STICK) {
    double c = cos(t), s = sin(t), chi = m->chi;
    double x2 = ph->x2c + m->V * t;
    double f = chi * ((1 - chi) * x2 - (ph->A * c + ph->B * s));
    double fd = chi * ((1 - chi) * m->V + ph->A * s - ph->B * c);
    if (which == 0) {
      if (dg)
        *dg = fd;
      return f - m->ur;
    }
    if (dg)
      *dg = -fd;
    return -m->ur - f;
  }
  double v2 = 0, a2 = 0;
  for (int k = 0; k < 2; k++) {
    double w = m->w[k], c = cos(w * t), s = sin(w * t);
    v2 += m->P[1][k] * w * (-ph->al[k] * s + ph->be[k] * c);
    a2 -= m->P[1][k] * w * w * (ph->al[k] * c + ph->be[k] * s);
  }
  if (ph->mode == SLIP) {
    if (dg)
      *dg = a2;
    return v2 - m->V;
  }
  if (dg)
    *dg = -a2;
  return m->V - v2;
}

/* stick force chi (x2 - x1) and its derivative */
static double stick_f(const model *m, const phase *ph, double t, double *df) {
  double g = phase_g(m, ph, 0, t, df);
  return g + m->ur;
}

typedef struct sctx {
  const model *m;
  const phase *ph;
  int which;
  long evals, budget;
  int unres;
} sctx;

static double gv(sctx *c, double t) {
  c->evals++;
  return phase_g(c->m, c->ph, c->which, t, NULL);
}

/* First point of [a, b] with g >= 0, given g(a) = ga, g(b) = gb.  Uses
 * g <= linear interpolant + M2 (t-a)(b-t)/2 to discard subintervals; the
 * left half is always searched first, so the first crossing is found. */
static int srch(sctx *c, double a, double b, double ga, double gb,
                double *hit) {
  double L = b - a;
  if (fmax(ga, gb) + c->ph->M2 * L * L * 0.125 < 0)
    return 0;
  if (ga >= 0) {
    *hit = a;
    return 1;
  }
  double mid = a + 0.5 * L;
  if (!(mid > a && mid < b) || c->evals >= c->budget) {
    if (gb >= 0) {
      *hit = b;
      return 1;
    }
    c->unres = 1; /* touches to within M2 * ulp^2, or out of budget */
    return 0;
  }
  double gm = gv(c, mid);
  if (srch(c, a, mid, ga, gm, hit))
    return 1;
  return srch(c, mid, b, gm, gb, hit);
}

/* First t in (0, tmax] with g_which >= 0.  1 and *te if found. */
static int first_event(const model *m, const phase *ph, int which, double tmax,
                       double *te, int *unres) {
  sctx c = {m, ph, which, 0, 400000, 0};
  double dg0, g0 = phase_g(m, ph, which, 0, &dg0);
  double scale = ph->mode == STICK ? m->ur : m->V;
  double t = 0;
  if (g0 >= -1e-12 * scale) {
    /* starts on the switching surface: it must leave it inwards */
    if (!(dg0 < 0)) {
      *te = 0;
      return 1;
    }
    /* g <= g0 + dg0 t + M2 t^2 / 2 < 0 on (0, -dg0 / M2] */
    t = ph->M2 > 0 ? fmin(-dg0 / ph->M2, tmax) : tmax;
    g0 = phase_g(m, ph, which, t, NULL);
  }
  double hs = 0.5 / ph->om;
  while (t < tmax) {
    double b = fmin(t + hs, tmax), gb = phase_g(m, ph, which, b, NULL), hit;
    if (srch(&c, t, b, g0, gb, &hit)) {
      *te = hit;
      if (unres)
        *unres |= c.unres;
      return 1;
    }
    t = b;
    g0 = gb;
  }
  if (unres)
    *unres |= c.unres;
  return 0;
}

/* ---- own event-driven simulation of the Poincare map --------------------- */

#define SIM_MAXPH 8
typedef struct simres {
  int n;
  int modes[SIM_MAXPH];
  double dur[SIM_MAXPH];
  double ystart[SIM_MAXPH][4];
  double sout[2];
  double T;
  int unres;
} simres;

/* From y0(s) in slip to the next stick -> slip (f = +ur) event. */
static int sim_map(const model *m, const double s[2], simres *r) {
  double y[4] = {s[0], s[0] + m->ur / m->chi, s[1], m->V};
  int mode = SLIP;
  double tmax = 2 * m->dmax + 20;
  r->n = 0;
  r->T = 0;
  r->unres = 0;
  while (r->n < SIM_MAXPH) {
    phase ph;
    phase_init(m, &ph, mode, y);
    memcpy(r->ystart[r->n], y, sizeof y);
    double te = 0, te1;
    int which = 0, u = 0;
    int found = first_event(m, &ph, 0, tmax, &te, &u);
    if (mode == STICK && first_event(m, &ph, 1, found ? te : tmax, &te1, &u) &&
        (!found || te1 < te)) {
      te = te1;
      which = 1;
      found = 1;
    }
    r->unres |= u;
    if (!found)
      return -1;
    r->modes[r->n] = mode;
    r->dur[r->n] = te;
    r->n++;
    r->T += te;
    phase_state(m, &ph, te, y);
    double f = m->chi * (y[1] - y[0]);
    if (mode == STICK) {
      if (which == 0) {
        r->sout[0] = y[0];
        r->sout[1] = y[2];
        return 0;
      }
      mode = OVER;
    } else {
      y[3] = m->V;
      if (fabs(f) < m->ur)
        mode = STICK;
      else if (f <= -m->ur)
        mode = OVER;
      else
        mode = SLIP;
    }
  }
  return -1;
}

/* ---- margins ------------------------------------------------------------ */

/* Interior local maxima of g (or minima when sgn = -1) of a function given
 * by its derivative; calls back with each extremum time. */
static double extrema_margin(const model *m, const phase *ph, double T) {
  double mg = INFINITY;
  double hs = 0.02 / ph->om;
  int n = (int)ceil(T / hs);
  if (n < 8)
    n = 8;
  double h = T / n, dprev;
  if (ph->mode != STICK) {
    phase_g(m, ph, 0, 0, &dprev);
    for (int i = 1; i <= n; i++) {
      double t = i * h, d;
      phase_g(m, ph, 0, t, &d);
      if (dprev > 0 && d <= 0) { /* local maximum in [t - h, t] */
        double lo = t - h, hi = t;
        for (int it = 0; it < 80 && hi - lo > 1e-15 * (1 + hi); it++) {
          double mid = 0.5 * (lo + hi), dm;
          phase_g(m, ph, 0, mid, &dm);
          if (dm > 0)
            lo = mid;
          else
            hi = mid;
        }
        double gmax = phase_g(m, ph, 0, 0.5 * (lo + hi), NULL);
        if (0.5 * (lo + hi) < T)
          mg = fmin(mg, -gmax);
      }
      dprev = d;
    }
    double dT;
    phase_g(m, ph, 0, T, &dT);
    mg = fmin(mg, dT / m->eta); /* us - f (slip) or f + us (overshoot) */
    return mg;
  }
  /* stick: -ur < f < ur on [0, T), f reaching +ur at T */
  double dT, f0 = stick_f(m, ph, 0, &dprev), fT = stick_f(m, ph, T, &dT);
  mg = fmin(mg, m->ur - f0);
  mg = fmin(mg, f0 + m->ur);
  mg = fmin(mg, fT + m->ur);
  mg = fmin(mg, dT);
  for (int i = 1; i <= n; i++) {
    double t = i * h, d;
    stick_f(m, ph, t, &d);
    if ((dprev > 0 && d <= 0) || (dprev < 0 && d >= 0)) {
      int ismax = dprev > 0;
      double lo = t - h, hi = t;
      for (int it = 0; it < 80 && hi - lo > 1e-15 * (1 + hi); it++) {
        double mid = 0.5 * (lo + hi), dm;
        stick_f(m, ph, mid, &dm);
        if ((dm > 0) == ismax)
          lo = mid;
        else
          hi = mid;
      }
      double te = 0.5 * (lo + hi), fe = stick_f(m, ph, te, NULL);
      if (te < T) {
        if (ismax)
          mg = fmin(mg, m->ur - fe);
        else
          mg = fmin(mg, fe + m->ur);
      }
    }
    dprev = d;
  }
  return mg;
}

/* Margins of a simulated return (expected sequence already checked). */
static double orbit_margin(const model *m, const simres *r) {
  double mg = INFINITY;
  for (int k = 0; k < r->n; k++) {
    phase ph;
    phase_init(m, &ph, r->modes[k], r->ystart[k]);
    mg = fmin(mg, extrema_margin(m, &ph, r->dur[k]));
    if (r->modes[k] != STICK) {
      double y[4];
      phase_state(m, &ph, r->dur[k], y);
      double f = m->chi * (y[1] - y[0]);
      int next = r->modes[k + 1];
      if (next == STICK)
        mg = fmin(mg, m->ur - fabs(f));
      else if (r->modes[k] == SLIP && next == OVER)
        mg = fmin(mg, -m->ur - f);
      else
        mg = fmin(mg, -INFINITY);
    }
  }
  return mg;
}

static int same_seq(const simres *r, int n, const int *modes) {
  if (r->n != n)
    return 0;
  for (int k = 0; k < n; k++)
    if (r->modes[k] != modes[k])
      return 0;
  return 1;
}

/* ---- Newton on the reduced residual -------------------------------------- */

static int newton(const model *m, int kind, double t[2], double hcell) {
  double R[2], s[2];
  int conv = 0;
  for (int it = 0; it < 60; it++) {
    if (resid(m, kind, t, R, s, NULL))
      return -1;
    double J[2][2];
    for (int j = 0; j < 2; j++) {
      double hj = 1e-7 * fmax(1, fabs(t[j]));
      double tp[2] = {t[0], t[1]}, tm[2] = {t[0], t[1]}, Rp[2], Rm[2];
      tp[j] += hj;
      tm[j] -= hj;
      if (resid(m, kind, tp, Rp, NULL, NULL) ||
          resid(m, kind, tm, Rm, NULL, NULL))
        return -1;
      J[0][j] = (Rp[0] - Rm[0]) / (2 * hj);
      J[1][j] = (Rp[1] - Rm[1]) / (2 * hj);
    }
    double det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    if (!(det != 0) || !isfinite(det))
      return -1;
    double d0 = -(J[1][1] * R[0] - J[0][1] * R[1]) / det;
    double d1 = -(-J[1][0] * R[0] + J[0][0] * R[1]) / det;
    double nd = hypot(d0, d1), lim = 3 * hcell;
    /* a root in the candidate cell is within a step or so of any of its
     * points: a first step beyond three cells points away from the cell,
     * and the root there (if any) is its own cell's */
    if (it == 0 && nd > lim)
      return -1;
    if (nd > lim) {
      d0 *= lim / nd;
      d1 *= lim / nd;
    }
    t[0] += d0;
    t[1] += d1;
    if (!(t[0] > 0 && t[1] > 0 && t[0] < 2 * m->dmax && t[1] < 2 * m->dmax))
      return -1;
    if (nd < 1e-14 * (1 + hypot(t[0], t[1]))) {
      conv = 1;
      break;
    }
    if (nd < 1e-11 && it > 30) {
      conv = 1;
      break;
    }
    /* from inside a candidate cell Newton converges in a few steps; one
     * still taking large steps after 16 wanders and is given up */
    if (it >= 16 && nd > 1e-6 * (1 + hypot(t[0], t[1])))
      return -1;
  }
  if (resid(m, kind, t, R, s, NULL))
    return -1;
  double sc = 1 + fabs(s[0]) + fabs(s[1]);
  if (!(hypot(R[0], R[1]) < 1e-9 * sc))
    return -1;
  (void)conv;
  return 0;
}

/* ---- candidate collection ------------------------------------------------ */

typedef struct root {
  int kind;
  double t[2];
} root;

typedef struct rlist {
  root *r;
  int n, cap;
  long newton_runs;
} rlist;

static int cand_test(double r[4][2]) {
  const double kappa = 0.5;
  for (int c = 0; c < 2; c++) {
    double lo = r[0][c], hi = r[0][c];
    for (int k = 1; k < 4; k++) {
      if (!isfinite(r[k][c]))
        return 0;
      lo = fmin(lo, r[k][c]);
      hi = fmax(hi, r[k][c]);
    }
    if (!isfinite(lo) || !isfinite(hi))
      return 0;
    double sp = hi - lo;
    if (lo > kappa * sp || hi < -kappa * sp)
      return 0;
  }
  return 1;
}

static int add_root(rlist *L, int kind, const double t[2]) {
  for (int i = 0; i < L->n; i++)
    if (L->r[i].kind == kind && fabs(L->r[i].t[0] - t[0]) < 1e-7 &&
        fabs(L->r[i].t[1] - t[1]) < 1e-7)
      return 0;
  if (L->n == L->cap) {
    int nc = L->cap ? 2 * L->cap : 16;
    root *nr = realloc(L->r, nc * sizeof *nr);
    if (!nr)
      return -1;
    L->r = nr;
    L->cap = nc;
  }
  L->r[L->n].kind = kind;
  L->r[L->n].t[0] = t[0];
  L->r[L->n].t[1] = t[1];
  L->n++;
  return 1;
}

/* Newton from the centre and the quarter centres of a candidate cell. */
static int try_cell(const model *m, rlist *L, int kind, double a1, double b1,
                    double a2, double b2, double hcell) {
  static const double fx[5][2] = {
      {0.5, 0.5}, {0.25, 0.25}, {0.75, 0.25}, {0.25, 0.75}, {0.75, 0.75}};
  for (int k = 0; k < 5; k++) {
    double t[2] = {a1 + fx[k][0] * (b1 - a1), a2 + fx[k][1] * (b2 - a2)};
    L->newton_runs++;
    if (newton(m, kind, t, hcell))
      continue;
    double t3 = 0, R[2];
    if (resid(m, kind, t, R, NULL, &t3))
      continue;
    double lim = m->dmax * (1 + 1e-12);
    if (!(t[0] > 0 && t[0] <= lim && t[1] > 0 && t[1] <= lim))
      continue;
    if (kind == 1 && !(t3 > 0 && t3 <= lim))
      continue;
    if (add_root(L, kind, t) < 0)
      return -1;
  }
  return 0;
}

static void ptB_at(const model *m, double t1, double t2, ptB *q) {
  preS S;
  preO O;
  pre_slip(m, t1, &S);
  pre_over(m, t2, &O);
  evalB(m, &S, &O, q, NULL, NULL);
}

/* (B) cell with corners c[0]=(a1,a2) c[1]=(a1,b2) c[2]=(b1,a2) c[3]=(b1,b2). */
static int cellB(const model *m, rlist *L, double a1, double b1, double a2,
                 double b2, const ptB *c0, const ptB *c1, const ptB *c2,
                 const ptB *c3, int depth, double hcell) {
  const ptB *c[4] = {c0, c1, c2, c3};
  double dm = m->dmax, lo3 = INFINITY, hi3 = -INFINITY;
  int rel = 0, dpos = 0, dneg = 0, npos = 0, nneg = 0;
  for (int k = 0; k < 4; k++) {
    double t3 = c[k]->t3;
    if (isfinite(t3)) {
      lo3 = fmin(lo3, t3);
      hi3 = fmax(hi3, t3);
      if (t3 > -1 && t3 < dm + 1)
        rel = 1;
    }
    if (c[k]->det > 0)
      dpos = 1;
    else
      dneg = 1;
    if (c[k]->Nn > 0)
      npos = 1;
    else if (c[k]->Nn < 0)
      nneg = 1;
  }
  int dchange = dpos && dneg;
  if (!rel && !(dchange && npos && nneg))
    return 0;
  int wild = dchange || !(hi3 - lo3 <= BRUTE_T3_SPREAD);
  if (wild && depth < BRUTE_DEPTH) {
    double m1 = 0.5 * (a1 + b1), m2 = 0.5 * (a2 + b2);
    ptB e[5]; /* (a1,m2) (m1,a2) (m1,m2) (m1,b2) (b1,m2) */
    ptB_at(m, a1, m2, &e[0]);
    ptB_at(m, m1, a2, &e[1]);
    ptB_at(m, m1, m2, &e[2]);
    ptB_at(m, m1, b2, &e[3]);
    ptB_at(m, b1, m2, &e[4]);
    double hc = 0.5 * hcell;
    if (cellB(m, L, a1, m1, a2, m2, c0, &e[0], &e[1], &e[2], depth + 1, hc) ||
        cellB(m, L, a1, m1, m2, b2, &e[0], c1, &e[2], &e[3], depth + 1, hc) ||
        cellB(m, L, m1, b1, a2, m2, &e[1], &e[2], c2, &e[4], depth + 1, hc) ||
        cellB(m, L, m1, b1, m2, b2, &e[2], &e[3], &e[4], c3, depth + 1, hc))
      return -1;
    return 0;
  }
  /* a cell still astride the singular curve of the 2x2 system at the
   * finest level: a root there would have an unbounded start state */
  if (wild)
    return 0;
  for (int k = 0; k < 4; k++)
    if (!(c[k]->t3 > -0.5 && c[k]->t3 < dm + 0.5))
      return 0;
  double r[4][2];
  for (int k = 0; k < 4; k++) {
    r[k][0] = c[k]->Rn[0];
    r[k][1] = c[k]->Rn[1];
  }
  if (cand_test(r))
    return try_cell(m, L, 1, a1, b1, a2, b2, hcell);
  return 0;
}

static int scan(const model *m, double dmax, rlist *L, long *ncells) {
  double hmin = fmin(0.1 / m->w[1], 0.1);
  int N = (int)ceil(dmax / hmin);
  if (N < 50)
    N = 50;
  double h = dmax / N;
  int np = N + 1, rc = 0;
  preS *S = malloc(np * sizeof *S);
  preO *O = malloc(np * sizeof *O);
  double *c2 = malloc(np * sizeof *c2), *s2 = malloc(np * sizeof *s2);
  double *RA = malloc(2 * np * 2 * sizeof *RA);
  ptB *PB = malloc(2 * np * sizeof *PB);
  if (!S || !O || !c2 || !s2 || !RA || !PB) {
    rc = -1;
    goto out;
  }
  for (int i = 0; i < np; i++) {
    double t = i * h;
    pre_slip(m, t, &S[i]);
    pre_over(m, t, &O[i]);
    c2[i] = cos(t);
    s2[i] = sin(t);
  }
  *ncells = 0;
  /* (A) */
  for (int i = 0; i < np; i++) {
    double *cur = RA + (i & 1) * np * 2, *prv = RA + ((i + 1) & 1) * np * 2;
    for (int j = 0; j < np; j++) {
      double sn[2];
      evalA(m, &S[i], j * h, c2[j], s2[j], cur + 2 * j, sn);
    }
    if (i < 2)
      continue; /* cells with t1 < h are not scanned */
    for (int j = 0; j < N; j++) {
      double r[4][2] = {{prv[2 * j], prv[2 * j + 1]},
                        {prv[2 * j + 2], prv[2 * j + 3]},
                        {cur[2 * j], cur[2 * j + 1]},
                        {cur[2 * j + 2], cur[2 * j + 3]}};
      (*ncells)++;
      if (cand_test(r) &&
          try_cell(m, L, 0, (i - 1) * h, i * h, j * h, (j + 1) * h, h)) {
        rc = -1;
        goto out;
      }
    }
  }
  /* (B) */
  for (int i = 0; i < np; i++) {
    ptB *cur = PB + (i & 1) * np, *prv = PB + ((i + 1) & 1) * np;
    for (int j = 0; j < np; j++)
      evalB(m, &S[i], &O[j], &cur[j], NULL, NULL);
    if (i < 2)
      continue;
    for (int j = 1; j < N; j++) { /* cells with t2 < h are not scanned */
      (*ncells)++;
      if (cellB(m, L, (i - 1) * h, i * h, j * h, (j + 1) * h, &prv[j],
                &prv[j + 1], &cur[j], &cur[j + 1], 0, h)) {
        rc = -1;
        goto out;
      }
    }
  }
out:
  free(S);
  free(O);
  free(c2);
  free(s2);
  free(RA);
  free(PB);
  return rc;
}

/* ---- verification and output --------------------------------------------- */

static int verify(const model *m, const root *rt, brute_orbit *o) {
  static const int seqA[2] = {SLIP, STICK}, seqB[3] = {SLIP, OVER, STICK};
  double R[2], s[2], t3;
  if (resid(m, rt->kind, rt->t, R, s, &t3))
    return 0;
  memset(o, 0, sizeof *o);
  o->n_phases = rt->kind == 0 ? 2 : 3;
  const int *seq = rt->kind == 0 ? seqA : seqB;
  for (int k = 0; k < o->n_phases; k++)
    o->modes[k] = seq[k];
  o->dur[0] = rt->t[0];
  o->dur[1] = rt->t[1];
  if (rt->kind == 1)
    o->dur[2] = t3;
  o->period = o->dur[0] + o->dur[1] + o->dur[2];
  o->s[0] = s[0];
  o->s[1] = s[1];
  simres r;
  if (sim_map(m, s, &r) || !same_seq(&r, o->n_phases, seq))
    return 0;
  for (int k = 0; k < o->n_phases; k++)
    if (!(fabs(r.dur[k] - o->dur[k]) < 1e-7 * (1 + o->dur[k])))
      return 0;
  o->closure = hypot(r.sout[0] - s[0], r.sout[1] - s[1]);
  if (!(o->closure < 1e-8 * (1 + fabs(s[0]) + fabs(s[1]))))
    return 0;
  o->margin = orbit_margin(m, &r);
  if (r.unres)
    o->margin = fmin(o->margin, 0);
  if (!(o->margin > 0))
    return 0;
  /* Jacobian of the simulated Poincare map, central differences */
  double J[2][2], hj = 1e-5 * fmax(1, fmax(fabs(s[0]), fabs(s[1])));
  int ok = 1;
  for (int j = 0; j < 2; j++) {
    double sp[2] = {s[0], s[1]}, sm[2] = {s[0], s[1]};
    simres rp, rm;
    sp[j] += hj;
    sm[j] -= hj;
    if (sim_map(m, sp, &rp) || sim_map(m, sm, &rm) ||
        !same_seq(&rp, o->n_phases, seq) || !same_seq(&rm, o->n_phases, seq)) {
      ok = 0;
      break;
    }
    J[0][j] = (rp.sout[0] - rm.sout[0]) / (2 * hj);
    J[1][j] = (rp.sout[1] - rm.sout[1]) / (2 * hj);
  }
  if (!ok) {
    o->radius = NAN;
  } else {
    double tr = J[0][0] + J[1][1], det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    double disc = 0.25 * tr * tr - det;
    if (disc >= 0) {
      double sq = sqrt(disc);
      o->radius = fmax(fabs(0.5 * tr + sq), fabs(0.5 * tr - sq));
    } else {
      o->radius = sqrt(fabs(det));
    }
  }
  return 1;
}

static int cmp_orbit(const void *a, const void *b) {
  const brute_orbit *x = a, *y = b;
  if (x->n_phases != y->n_phases)
    return x->n_phases - y->n_phases;
  return (x->period > y->period) - (x->period < y->period);
}

int brute_orbits(const brute_params *p, double dmax, brute_orbit *out,
                 int max_out) {
  model m;
  if (model_init(&m, p) || !(dmax > 0) || !isfinite(dmax) || max_out < 0)
    return -1;
  m.dmax = dmax;
  rlist L = {0};
  long ncells = 0;
  if (scan(&m, dmax, &L, &ncells)) {
    free(L.r);
    return -1;
  }
  brute_orbit *all = malloc((L.n + 1) * sizeof *all);
  if (!all) {
    free(L.r);
    return -1;
  }
  int n = 0;
  for (int i = 0; i < L.n; i++)
    if (verify(&m, &L.r[i], &all[n]))
      n++;
  qsort(all, n, sizeof *all, cmp_orbit);
  for (int i = 0; i < n && i < max_out; i++)
    out[i] = all[i];
  if (getenv("BRUTE_DEBUG"))
    fprintf(stderr,
            "brute: cells %ld, newton runs %ld, roots %d, feasible %d\n",
            ncells, L.newton_runs, L.n, n);
  free(all);
  free(L.r);
  return n;
}

/* ---- cross-check with refsim -----------------------------------------------
 */

double brute_refcheck(const brute_params *p, const brute_orbit *o,
                      double *dur_err) {
  ref_params rp = {p->chi, p->eta, p->us, p->ur, p->V};
  ref_opts opt = {gsl_odeiv2_step_rk8pd, 1e-12, 1e-12, 0, 1e-13};
  double x0[4] = {o->s[0], o->s[0] + p->ur / p->chi, o->s[1], p->V}, xe[4];
  ref_event ev[16];
  int mode_end;
  gsl_error_handler_t *old = gsl_set_error_handler_off();
  long n = ref_simulate(&rp, 0, x0, REF_SLIP, o->period + 1e-3, &opt, ev, 16,
                        xe, &mode_end);
  gsl_set_error_handler(old);
  if (dur_err)
    *dur_err = NAN;
  if (n < o->n_phases)
    return -1;
  double tprev = 0, derr = 0;
  for (int k = 0; k < o->n_phases; k++) {
    int to = k + 1 < o->n_phases ? o->modes[k + 1] : REF_SLIP;
    if (ev[k].from != o->modes[k] || ev[k].to != to)
      return -1;
    derr = fmax(derr, fabs(ev[k].t - tprev - o->dur[k]));
    tprev = ev[k].t;
  }
  if (dur_err)
    *dur_err = derr;
  const double *xf = ev[o->n_phases - 1].x;
  return hypot(xf[0] - o->s[0], xf[2] - o->s[1]);
}
