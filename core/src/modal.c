/*
 * modal.c: the modal decomposition of K and the closed-form motion in each
 * mode (section 2 of the paper).
 *
 * Slip and overshoot are free oscillations of z'' = -K z about the
 * equilibria +d0 (slip) and -d0 (overshoot); K = [[1, -chi], [-chi eta,
 * chi eta]] has the real eigenvalues lam0 < lam1, and with its mode shapes
 * phi (columns) each modal coordinate q = phiinv (x -+ d0) is a harmonic
 * oscillator of frequency w_k = sqrt(lam_k).  The stick motion (2.5) is
 * x2 = x2(0) + V t and x1 = chi x2 + a cos t + b sin t.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "events.h"
#include "internal.h"
#include "modal.h"
#include "sincos.h"

const char *ss_mode_name(ss_mode m) {
  switch (m) {
  case SS_MODE_SLIP:
    return "slip";
  case SS_MODE_OVERSHOOT:
    return "overshoot";
  case SS_MODE_STICK:
    return "stick";
  }
  return NULL;
}

int ss_model_init(ss_model *m, const ss_params *p, ss_diag *d) {
  double chi, ce, s, disc, r, det;
  ss_gsl_quiet(); /* every computation starts here: GSL must not abort */
  int rc = ss_params_check(p, d);
  if (rc)
    return rc;
  memset(m, 0, sizeof *m);
  m->p = *p;
  chi = p->chi;
  ce = chi * p->eta;
  s = 1 + ce;
  /* lam^2 - (1 + chi eta) lam + chi eta (1 - chi) = 0; the discriminant
   * (1 - chi eta)^2 + 4 chi^2 eta is written without cancellation. */
  disc = (1 - ce) * (1 - ce) + 4 * chi * ce;
  r = sqrt(disc);
  m->lam[1] = 0.5 * (s + r);
  m->lam[0] = ce * (1 - chi) / m->lam[1]; /* product of the roots */
  m->w[0] = sqrt(m->lam[0]);
  m->w[1] = sqrt(m->lam[1]);
  /* Mode shapes from whichever row of (K - lam I) phi = 0 avoids
   * cancellation: row 1 gives (chi, 1 - lam), row 2 (chi eta - lam, chi eta).
   * With r = sqrt(disc) >= |1 - chi eta|:
   *   1 - lam0 = (1 - chi eta + r)/2,   chi eta - lam0 = (chi eta - 1 + r)/2,
   *   1 - lam1 = (1 - chi eta - r)/2,   chi eta - lam1 = (chi eta - 1 - r)/2,
   * so row 1 is exact for lam0 and row 2 for lam1 when chi eta <= 1, and the
   * other way round when chi eta > 1. */
  if (ce <= 1) {
    m->phi[0][0] = chi;
    m->phi[1][0] = 0.5 * (1 - ce + r);
    m->phi[0][1] = 0.5 * (ce - 1 - r);
    m->phi[1][1] = ce;
  } else {
    m->phi[0][0] = 0.5 * (ce - 1 + r);
    m->phi[1][0] = ce;
    m->phi[0][1] = chi;
    m->phi[1][1] = 0.5 * (1 - ce - r);
  }
  /* Normalise each column to unit max-norm, for conditioning. */
  for (int k = 0; k < 2; k++) {
    double n = fmax(fabs(m->phi[0][k]), fabs(m->phi[1][k]));
    m->phi[0][k] /= n;
    m->phi[1][k] /= n;
  }
  det = m->phi[0][0] * m->phi[1][1] - m->phi[0][1] * m->phi[1][0];
  m->phiinv[0][0] = m->phi[1][1] / det;
  m->phiinv[0][1] = -m->phi[0][1] / det;
  m->phiinv[1][0] = -m->phi[1][0] / det;
  m->phiinv[1][1] = m->phi[0][0] / det;
  m->d0[0] = p->us / (1 - chi);
  m->d0[1] = p->us / (chi * (1 - chi));
  /* Parameters that are each in range can still be too extreme together
   * for double precision (chi eta overflowing, d0 beyond DBL_MAX). */
  double all[] = {m->lam[0],       m->lam[1],       m->phiinv[0][0],
                  m->phiinv[0][1], m->phiinv[1][0], m->phiinv[1][1],
                  m->d0[0],        m->d0[1]};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
    if (!isfinite(all[i]))
      return ss__fail(d, SS_EDOMAIN, "eta", p->eta,
                      "chi = %.3g, eta = %.3g, us = %.3g are too extreme "
                      "together: the modal decomposition overflows double "
                      "precision",
                      chi, p->eta, p->us);
  if (!(m->lam[0] > 0))
    return ss__fail(d, SS_EDOMAIN, "eta", p->eta,
                    "chi eta (1 - chi) = %.3g underflows: the slow modal "
                    "frequency is zero in double precision",
                    ce * (1 - chi));
  return SS_OK;
}

void ss_x_to_z(const ss_model *m, const double x[4], double z[4]) {
  z[0] = x[0] - m->d0[0];
  z[1] = x[1] - m->d0[1];
  z[2] = x[2];
  z[3] = x[3];
}

void ss_z_to_x(const ss_model *m, const double z[4], double x[4]) {
  x[0] = z[0] + m->d0[0];
  x[1] = z[1] + m->d0[1];
  x[2] = z[2];
  x[3] = z[3];
}

double ss_stick_force(const ss_model *m, const double x[4]) {
  return m->p.chi * (x[1] - x[0]);
}

/* Modal amplitudes of the free oscillation about an equilibrium: with
 * zb = the shifted state, q = phiinv zb[0..1], qd = phiinv zb[2..3]. */
static void modal_amplitudes(const ss_model *m, const double zb[4], double q[2],
                             double qd[2]) {
  q[0] = m->phiinv[0][0] * zb[0] + m->phiinv[0][1] * zb[1];
  q[1] = m->phiinv[1][0] * zb[0] + m->phiinv[1][1] * zb[1];
  qd[0] = m->phiinv[0][0] * zb[2] + m->phiinv[0][1] * zb[3];
  qd[1] = m->phiinv[1][0] * zb[2] + m->phiinv[1][1] * zb[3];
}

/* Free oscillation about the equilibrium (sgn d0, 0): sgn = +1 slip, -1
 * overshoot. */
static void free_flow(const ss_model *m, double sgn, double t,
                      const double x0[4], double x[4]) {
  double zb[4], q[2], qd[2], qt[2], qdt[2];
  zb[0] = x0[0] - sgn * m->d0[0];
  zb[1] = x0[1] - sgn * m->d0[1];
  zb[2] = x0[2];
  zb[3] = x0[3];
  modal_amplitudes(m, zb, q, qd);
  for (int k = 0; k < 2; k++) {
    double w = m->w[k], c, s;
    ss__sincos(w * t, &s, &c);
    qt[k] = q[k] * c + qd[k] / w * s;
    qdt[k] = qd[k] * c - q[k] * w * s;
  }
  x[0] = m->phi[0][0] * qt[0] + m->phi[0][1] * qt[1] + sgn * m->d0[0];
  x[1] = m->phi[1][0] * qt[0] + m->phi[1][1] * qt[1] + sgn * m->d0[1];
  x[2] = m->phi[0][0] * qdt[0] + m->phi[0][1] * qdt[1];
  x[3] = m->phi[1][0] * qdt[0] + m->phi[1][1] * qdt[1];
}

static void stick_flow(const ss_model *m, double t, const double x0[4],
                       double x[4]) {
  double chi = m->p.chi, V = m->p.V;
  double a = x0[0] - chi * x0[1], b = x0[2] - chi * V;
  double c, s;
  ss__sincos(t, &s, &c);
  double x2 = x0[1] + V * t;
  x[0] = chi * x2 + a * c + b * s;
  x[1] = x2;
  x[2] = chi * V - a * s + b * c;
  x[3] = V;
}

void ss_flow(const ss_model *m, ss_mode mode, double t, const double x0[4],
             double x[4]) {
  switch (mode) {
  case SS_MODE_SLIP:
    free_flow(m, 1.0, t, x0, x);
    break;
  case SS_MODE_OVERSHOOT:
    free_flow(m, -1.0, t, x0, x);
    break;
  case SS_MODE_STICK:
    stick_flow(m, t, x0, x);
    break;
  }
}

void ss__coords(const ss_model *m, ss_mode mode, const double x[4],
                ss_trig g[4]) {
  memset(g, 0, 4 * sizeof *g);
  if (mode == SS_MODE_STICK) {
    double chi = m->p.chi, V = m->p.V;
    double a = x[0] - chi * x[1], b = x[2] - chi * V;
    /* x1 = chi (x2(0) + V t) + a cos t + b sin t, x1' = chi V - a sin t +
     * b cos t, x2 = x2(0) + V t, x2' = V */
    g[0].c0 = chi * x[1];
    g[0].c1 = chi * V;
    g[0].n = 1;
    g[0].w[0] = 1;
    g[0].a[0] = a;
    g[0].b[0] = b;
    g[1].c0 = x[1];
    g[1].c1 = V;
    g[2].c0 = chi * V;
    g[2].n = 1;
    g[2].w[0] = 1;
    g[2].a[0] = b;
    g[2].b[0] = -a;
    g[3].c0 = V;
    return;
  }
  double sgn = mode == SS_MODE_SLIP ? 1.0 : -1.0;
  double zb[4] = {x[0] - sgn * m->d0[0], x[1] - sgn * m->d0[1], x[2], x[3]};
  double q[2], qd[2];
  modal_amplitudes(m, zb, q, qd);
  for (int i = 0; i < 2; i++) {
    g[i].c0 = sgn * m->d0[i];
    g[i].n = g[i + 2].n = 2;
    for (int k = 0; k < 2; k++) {
      double w = m->w[k];
      g[i].w[k] = g[i + 2].w[k] = w;
      g[i].a[k] = m->phi[i][k] * q[k];
      g[i].b[k] = m->phi[i][k] * qd[k] / w;
      g[i + 2].a[k] = m->phi[i][k] * qd[k];
      g[i + 2].b[k] = -m->phi[i][k] * q[k] * w;
    }
  }
}

/* B = phi diag(v) phiinv, 2x2. */
static void modal_matrix(const ss_model *m, const double v[2], double B[2][2]) {
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++)
      B[i][j] = m->phi[i][0] * v[0] * m->phiinv[0][j] +
                m->phi[i][1] * v[1] * m->phiinv[1][j];
}

static void put_blocks(double A[16], double B11[2][2], double B12[2][2],
                       double B21[2][2], double B22[2][2]) {
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) {
      A[4 * i + j] = B11[i][j];
      A[4 * i + j + 2] = B12[i][j];
      A[4 * (i + 2) + j] = B21[i][j];
      A[4 * (i + 2) + j + 2] = B22[i][j];
    }
}

void ss_transition(const ss_model *m, ss_mode mode, double t, double A[16],
                   double c[4], double dA[16], double dc[4]) {
  if (mode == SS_MODE_STICK) {
    /* Gamma(t) of (2.6), with z2' = V carried as the fourth coordinate. */
    double chi = m->p.chi, co, si;
    ss__sincos(t, &si, &co);
    /* clang-format off */
    if (A) {
      double G[16] = {co,  chi * (1 - co), si, chi * (t - si),
                      0,   1,              0,  t,
                      -si, chi * si,       co, chi * (1 - co),
                      0,   0,              0,  1};
      memcpy(A, G, sizeof G);
    }
    if (dA) {
      double G[16] = {-si, chi * si, co,  chi * (1 - co),
                      0,   0,        0,   1,
                      -co, chi * co, -si, chi * si,
                      0,   0,        0,   0};
      memcpy(dA, G, sizeof G);
    }
    /* clang-format on */
    if (c)
      memset(c, 0, 4 * sizeof *c);
    if (dc)
      memset(dc, 0, 4 * sizeof *dc);
    return;
  }
  /* H(t) of (2.1): H1 = phi cos(Wt) phiinv, H2 = phi W^-1 sin(Wt) phiinv,
   * H3 = -phi W sin(Wt) phiinv; H' = [[H3, H1], [-K H1, H3]]. */
  double vc[2], vs[2], vws[2], vw2c[2];
  double H1[2][2], H2[2][2], H3[2][2], KH1[2][2];
  double Hloc[16], dHloc[16];
  for (int k = 0; k < 2; k++) {
    double w = m->w[k], co, si;
    ss__sincos(w * t, &si, &co);
    vc[k] = co;
    vs[k] = si / w;
    vws[k] = -w * si;
    vw2c[k] = -w * w * co;
  }
  modal_matrix(m, vc, H1);
  modal_matrix(m, vs, H2);
  modal_matrix(m, vws, H3);
  modal_matrix(m, vw2c, KH1);
  put_blocks(Hloc, H1, H2, H3, H1);
  put_blocks(dHloc, H3, H1, KH1, H3);
  if (A)
    memcpy(A, Hloc, sizeof Hloc);
  if (dA)
    memcpy(dA, dHloc, sizeof dHloc);
  if (mode == SS_MODE_OVERSHOOT) {
    /* c = 2 L(t) d0 with L = [H1 - I; H3] (2.4). */
    const double *d0 = m->d0;
    if (c)
      for (int i = 0; i < 4; i++)
        c[i] = 2 * (Hloc[4 * i] * d0[0] + Hloc[4 * i + 1] * d0[1] -
                    (i < 2 ? d0[i] : 0));
    if (dc)
      for (int i = 0; i < 4; i++)
        dc[i] = 2 * (dHloc[4 * i] * d0[0] + dHloc[4 * i + 1] * d0[1]);
  } else {
    if (c)
      memset(c, 0, 4 * sizeof *c);
    if (dc)
      memset(dc, 0, 4 * sizeof *dc);
  }
}

void ss__end_switching(const ss_model *m, ss_mode mode, ss_mode next,
                       const double x[4], ss_trig *g) {
  ss__switching(
      m, mode, mode == SS_MODE_STICK ? (next == SS_MODE_OVERSHOOT ? -1 : 1) : 0,
      x, g);
}

void ss__switching(const ss_model *m, ss_mode mode, int sign, const double x[4],
                   ss_trig *g) {
  memset(g, 0, sizeof *g);
  if (mode == SS_MODE_STICK) {
    /* chi (x2 - x1) = chi ((1 - chi)(x2 + V t) - a cos t - b sin t). */
    double chi = m->p.chi, V = m->p.V;
    double a = x[0] - chi * x[1], b = x[2] - chi * V;
    double s = sign > 0 ? 1.0 : -1.0;
    g->n = 1;
    g->w[0] = 1;
    g->c0 = s * chi * (1 - chi) * x[1] - m->p.ur;
    g->c1 = s * chi * (1 - chi) * V;
    g->a[0] = -s * chi * a;
    g->b[0] = -s * chi * b;
    return;
  }
  double sgn = mode == SS_MODE_SLIP ? 1.0 : -1.0;
  double zb[4] = {x[0] - sgn * m->d0[0], x[1] - sgn * m->d0[1], x[2], x[3]};
  double q[2], qd[2];
  modal_amplitudes(m, zb, q, qd);
  /* x2'(t) = sum_k phi[1][k] (qd_k cos(w_k t) - q_k w_k sin(w_k t)). */
  g->n = 2;
  g->c0 = -sgn * m->p.V;
  for (int k = 0; k < 2; k++) {
    g->w[k] = m->w[k];
    g->a[k] = sgn * m->phi[1][k] * qd[k];
    g->b[k] = -sgn * m->phi[1][k] * q[k] * m->w[k];
  }
}

ss_mode ss_mode_of_state(const ss_model *m, const double x[4]) {
  double V = m->p.V;
  double vtol = 4 * DBL_EPSILON * V;
  if (x[3] < V - vtol)
    return SS_MODE_SLIP;
  if (x[3] > V + vtol)
    return SS_MODE_OVERSHOOT;
  /* x2' = V: test both stick thresholds with the event finder's own
   * tolerance and departure rule, so that a stick is entered exactly when the
   * finder would not end it at once. */
  double xs[4] = {x[0], x[1], x[2], V};
  ss_trig g;
  int dir;
  ss__switching(m, SS_MODE_STICK, 1, xs, &g);
  (void)ss__trig_at_zero(&g, 0, &dir);
  if (dir > 0)
    return SS_MODE_SLIP;
  ss__switching(m, SS_MODE_STICK, -1, xs, &g);
  (void)ss__trig_at_zero(&g, 0, &dir);
  if (dir > 0)
    return SS_MODE_OVERSHOOT;
  return SS_MODE_STICK;
}
