/*
 * scan.c: the roots of the period-1 duration equations of the slip-stick
 * and slip-overshoot-stick sequences, every duration in a box (0, dmax].
 *
 * Two equations in two durations.  The orbit starts at the stick -> slip
 * point y0(s) = (s1, s1 + k, s2, V), k = ur/chi, s = (x1, x1').  The slip
 * and overshoot flows are affine, so the state at the end of the slip (and
 * of the overshoot) is affine in s, and each of them must end with x2' = V:
 * one linear condition on s per phase.  Under stick x2 grows like V t, so
 * the closure of x2 is linear too: for slip-stick it is the second
 * condition on s, x2(end of slip) + V t2 = s1 + k; for slip-overshoot-stick
 * it gives the stick's duration, t3 = (s1 + k - x2(end of overshoot)) / V.
 * Under stick c = x1 - chi x2 turns at unit frequency, c(t) = Ac cos t +
 * Bc sin t, so the closure of (x1, x1') after a stick of duration t is
 *   R0 = chi (s1 + k) + Ac cos t + Bc sin t - s1,
 *   R1 = chi V - Ac sin t + Bc cos t - s2,
 * Ac = x1 - chi x2 and Bc = x1' - chi V at the start of the stick.  The
 * unknowns are (t1, t2) for both sequences.
 *
 * Scan: the residual times the determinant of the linear system for s (for
 * slip-stick a smooth function, with no pole) on a grid of step h; a cell is
 * a candidate when each component's corner values reach zero within half
 * their spread, which also catches zero lines that curve inside the cell
 * (where not both change sign, the plane through the corners must also put
 * the zero within two cells).  For slip-overshoot-stick t3 is not smooth
 * where the system is singular: a cell across which the determinant changes
 * sign or t3 turns by more than 1 rad is split, up to 8 times finer (and
 * then tried as it is, unless a pole crosses it); a
 * cell whose corners do not all give t3 in (-0.5, dmax + 0.5) cannot hold a
 * root with t3 in the box (nor can one a pole crosses where t3's numerator
 * keeps its sign), and away from a pole neither can one where the
 * rotation condition E (below) stays away from zero, nor one whose every
 * start has the slip reach x2' = V before the cell's slip duration (most
 * roots of the reduced equations are of that kind).  Newton on the reduced
 * equations times det (forward differences) starts at the centre of each
 * candidate cell; where Newton's first step leaves the cell's reach, the
 * cell is split and each quarter tried again, down to 1/8 (or less deep, as
 * the caller asks).  A root is kept if
 * its phases, sampled on the grid and at their ends, keep the rules of their
 * modes (implausible()), once.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scan.h"
#include "sincos.h"

#define SCAN_MAX_DEPTH 3
#define SCAN_T3_TURN 1.0
#define SCAN_NEWTON_ITERS 16
#define SCAN_MAX_CELLS 1000 /* per axis */
#define SCAN_MAX_REFINE 3   /* halvings of a cell Newton fails in, at most */

/* The slip from y0(s) for time t: x = Y s + y. */
typedef struct slip_map {
  double Y[4][2], y[4];
} slip_map;

/* The overshoot for time t: x = G x0 + g. */
typedef struct over_map {
  double G[4][4], g[4];
} over_map;

/* x -> A (x - D) + c + D, D = (d0, 0): the affine flow in x coordinates. */
static void affine(const ss_model *m, ss_mode mode, double t, double G[4][4],
                   double g[4]) {
  double A[16], c[4], D[4] = {m->d0[0], m->d0[1], 0, 0};
  ss_transition(m, mode, t, A, c, NULL, NULL);
  for (int i = 0; i < 4; i++) {
    g[i] = c[i] + D[i];
    for (int j = 0; j < 4; j++) {
      G[i][j] = A[4 * i + j];
      g[i] -= G[i][j] * D[j];
    }
  }
}

static void slip_at(const ss_model *m, double t, slip_map *S) {
  double G[4][4], g[4], k = m->p.ur / m->p.chi, V = m->p.V;
  affine(m, SS_MODE_SLIP, t, G, g);
  for (int i = 0; i < 4; i++) {
    S->Y[i][0] = G[i][0] + G[i][1];
    S->Y[i][1] = G[i][2];
    S->y[i] = G[i][1] * k + G[i][3] * V + g[i];
  }
}

static void over_at(const ss_model *m, double t, over_map *O) {
  affine(m, SS_MODE_OVERSHOOT, t, O->G, O->g);
}

/* One point of the scan: the determinant, det * R, and (overshoot) t3. */
typedef struct point {
  double det, t3;
  double n3;    /* V det t3, smooth where t3 has a pole (overshoot) */
  double sn[2]; /* det * s: the start */
  /* a slip from the start keeps x2' <= V at the grid times j h, j = 1 ..
   * clear, and breaks it first at j = first_bad (-1: not found yet); made
   * as far as slip_breaks() needs */
  long clear, first_bad;
  /* det (c, c') at the stick's start, c = x1 - chi x2 */
  double Ac, Bc;
  /* det^2 (|u|^2 - |w|^2): the stick turns w = (Ac, Bc) into u = (s1 -
   * chi (s1 + k), s2 - chi V), a rotation, so a root needs E = 0; E does not
   * depend on the stick's duration */
  double E;
  /* det * R, made by residual() when a cell needs it (a sincos of t3: most
   * points are only ever judged by det, t3, E and the start); NAN where t3
   * is not in (-0.5, tmax + 0.5) */
  double Rn[2], tmax;
  int rn_made;
} point;

/* The stick's start times det, from its start state times det (xd), and
 * E. */
static void stick_start(const ss_model *m, const double xd[3], point *q) {
  double chi = m->p.chi, V = m->p.V, k = m->p.ur / chi, det = q->det;
  q->Ac = xd[0] - chi * xd[1];
  q->Bc = xd[2] - chi * V * det;
  double u0 = q->sn[0] - chi * (q->sn[0] + k * det);
  double u1 = q->sn[1] - chi * V * det;
  q->E = u0 * u0 + u1 * u1 - q->Ac * q->Ac - q->Bc * q->Bc;
}

/* The stick's closure residual times det for a stick of duration t (co =
 * cos t, si = sin t). */
static void closure(const ss_model *m, double co, double si, point *q) {
  double chi = m->p.chi, V = m->p.V, k = m->p.ur / chi, det = q->det;
  const double *sn = q->sn;
  q->Rn[0] = chi * (sn[0] + k * det) + q->Ac * co + q->Bc * si - sn[0];
  q->Rn[1] = chi * V * det - q->Ac * si + q->Bc * co - sn[1];
  q->rn_made = 1;
}

/* det * R at q, made on first use. */
static const double *residual(const ss_model *m, point *q) {
  if (!q->rn_made) {
    if (q->t3 > -0.5 && q->t3 < q->tmax + 0.5) {
      double co, si;
      ss__sincos(q->t3, &si, &co);
      closure(m, co, si, q);
    } else {
      q->Rn[0] = q->Rn[1] = NAN;
      q->rn_made = 1;
    }
  }
  return q->Rn;
}

/* Slip-stick at (t1 of S, t2), c2 = cos t2, s2 = sin t2. */
static void eval_ss(const ss_model *m, const slip_map *S, double t2, double c2,
                    double s2, point *q) {
  double V = m->p.V, k = m->p.ur / m->p.chi;
  /* x2' = V at the end of the slip; x2 + V t2 = s1 + k at the end of the
   * stick */
  double a0 = S->Y[3][0], a1 = S->Y[3][1], ra = V - S->y[3];
  double b0 = S->Y[1][0] - 1, b1 = S->Y[1][1], rb = k - S->y[1] - V * t2;
  double det = a0 * b1 - a1 * b0, *sn = q->sn;
  q->clear = 0;
  q->first_bad = -1;
  sn[0] = ra * b1 - a1 * rb;
  sn[1] = a0 * rb - b0 * ra;
  double xd[3];
  for (int i = 0; i < 3; i++)
    xd[i] = S->Y[i][0] * sn[0] + S->Y[i][1] * sn[1] + S->y[i] * det;
  q->det = det;
  q->t3 = q->n3 = 0;
  stick_start(m, xd, q);
  closure(m, c2, s2, q);
}

/* Slip-overshoot-stick at (t1 of S, t2 of O); the residual (residual())
 * only where t3 is in (-0.5, tmax + 0.5), else NAN: such a point is never
 * a corner of a candidate cell. */
static void eval_sos(const ss_model *m, const slip_map *S, const over_map *O,
                     double tmax, point *q) {
  double V = m->p.V, k = m->p.ur / m->p.chi;
  /* the overshoot's end is G (Y s + y) + g; its x2' (row 3 of G) is the
   * second condition on s, so only that row is needed before s */
  double b0 = 0, b1 = 0, rb = V - O->g[3];
  for (int l = 0; l < 4; l++) {
    b0 += O->G[3][l] * S->Y[l][0];
    b1 += O->G[3][l] * S->Y[l][1];
    rb -= O->G[3][l] * S->y[l];
  }
  double a0 = S->Y[3][0], a1 = S->Y[3][1], ra = V - S->y[3];
  double det = a0 * b1 - a1 * b0, *sn = q->sn;
  q->clear = 0;
  q->first_bad = -1;
  sn[0] = ra * b1 - a1 * rb;
  sn[1] = a0 * rb - b0 * ra;
  /* then the slip's end times det, u = Y sn + y det, and the overshoot's
   * end times det, G u + g det */
  double u[4], xd[3];
  for (int l = 0; l < 4; l++)
    u[l] = S->Y[l][0] * sn[0] + S->Y[l][1] * sn[1] + S->y[l] * det;
  for (int i = 0; i < 3; i++)
    xd[i] = O->G[i][0] * u[0] + O->G[i][1] * u[1] + O->G[i][2] * u[2] +
            O->G[i][3] * u[3] + O->g[i] * det;
  q->det = det;
  q->n3 = sn[0] + k * det - xd[1];
  q->t3 = q->n3 / (V * det);
  q->tmax = tmax;
  q->rn_made = 0;
  if (!isfinite(q->t3)) {
    q->E = NAN;
    return;
  }
  stick_start(m, xd, q);
}

/* The last two slip and overshoot maps off the grid: Newton's differences
 * and a cell's refinement come back to the same times. */
typedef struct maps {
  const ss_model *m;
  double ts[2], to[2]; /* their times (NAN: empty) */
  slip_map S[2];
  over_map O[2];
  int next_s, next_o; /* the entry to replace next */
} maps;

static const slip_map *slip_cached(maps *mc, double t) {
  for (int i = 0; i < 2; i++)
    if (mc->ts[i] == t)
      return &mc->S[i];
  int i = mc->next_s;
  mc->next_s = 1 - i;
  mc->ts[i] = t;
  slip_at(mc->m, t, &mc->S[i]);
  return &mc->S[i];
}

static const over_map *over_cached(maps *mc, double t) {
  for (int i = 0; i < 2; i++)
    if (mc->to[i] == t)
      return &mc->O[i];
  int i = mc->next_o;
  mc->next_o = 1 - i;
  mc->to[i] = t;
  over_at(mc->m, t, &mc->O[i]);
  return &mc->O[i];
}

static void eval_at(maps *mc, int n, double t1, double t2, point *q) {
  const slip_map *S = slip_cached(mc, t1);
  if (n == 2) {
    double co, si;
    ss__sincos(t2, &si, &co);
    eval_ss(mc->m, S, t2, co, si, q);
  } else {
    eval_sos(mc->m, S, over_cached(mc, t2), INFINITY, q);
  }
}

/* The reduced residual at t, times det (smooth where R has a pole) into
 * Rn, and det; -1 where it is not finite. */
static int reduced(maps *mc, int n, const double t[2], double Rn[2],
                   double *det, double *t3) {
  point q;
  eval_at(mc, n, t[0], t[1], &q);
  const double *r = residual(mc->m, &q);
  Rn[0] = r[0];
  Rn[1] = r[1];
  *det = q.det;
  *t3 = q.t3;
  return isfinite(Rn[0]) && isfinite(Rn[1]) ? 0 : -1;
}

typedef struct scan {
  const ss_model *m;
  maps mc;
  int n;       /* 2: slip-stick, 3: slip-overshoot-stick */
  double dmax; /* the box */
  double scale;
  double h;    /* the grid's step */
  int refine;  /* halvings of a cell Newton fails in */
  long np;     /* grid points per axis */
  long stride; /* fine steps per grid step: 2^SCAN_MAX_DEPTH */
  slip_map *S; /* the slip for times j h / stride */
  over_map *O; /* the overshoot for the same times (n = 3) */
  /* whether S[j] and O[j] are made: those of the grid's own times always,
   * the finer ones when a split needs them (few do) */
  unsigned char *made;
  /* x2' - V at the end of a slip of duration j h from y0(s), = xv[j][0] s1 +
   * xv[j][1] s2 + xv[j][2]: row 3 of S[j stride], side by side */
  double (*xv)[3];
  double (*roots)[3];
  int max, count;
  int newton; /* Newton starts */
  long cells; /* cells examined */
  /* the roots closest to passing implausible(), failing at a phase's end
   * [0] or inside a phase [1], and how far they fail (INFINITY: none) */
  double rejected[2][3], rejected_by[2];
} scan;

/* The maps at fine time j h / stride, made on first use. */
static void make_maps(scan *sc, long j) {
  if (sc->made[j])
    return;
  double t = (double)j * sc->h / (double)sc->stride;
  slip_at(sc->m, t, &sc->S[j]);
  if (sc->O)
    over_at(sc->m, t, &sc->O[j]);
  sc->made[j] = 1;
}

/* How far a root is from being an orbit (0: it may be one): each phase, sampled
 * at the grid's times and at its end, keeps the rule of its mode.  x2' < V
 * inside a slip, x2' > V inside an overshoot, |f| < ur inside a stick (f = chi
 * (x2 - x1), the friction force); |f| <= ur where a slip or an overshoot ends
 * into stick, f <= -ur where a slip ends into overshoot (3.2); the first rule
 * that fails gives how far it fails.  A root that fails here by more than
 * rounding fails ss_orbit_check() too, which decides the rest. */
static double implausible(const scan *sc, const double t[2], double t3,
                          int *inside) {
  *inside = 1;
  const ss_model *m = sc->m;
  double chi = m->p.chi, ur = m->p.ur, V = m->p.V;
  double tol = 1e-9 * (ur + sc->scale);
  slip_map S;
  over_map O;
  point q;
  double s[2], x[4], y[4];
  slip_at(m, t[0], &S);
  if (sc->n == 2) {
    double co, si;
    ss__sincos(t[1], &si, &co);
    eval_ss(m, &S, t[1], co, si, &q);
  } else {
    over_at(m, t[1], &O);
    eval_sos(m, &S, &O, INFINITY, &q);
  }
  s[0] = q.sn[0] / q.det;
  s[1] = q.sn[1] / q.det;
  for (long j = 1; j < sc->np && (double)j * sc->h < t[0]; j++) {
    double g = sc->xv[j][0] * s[0] + sc->xv[j][1] * s[1] + sc->xv[j][2];
    if (g > tol)
      return g;
  }
  for (int i = 0; i < 4; i++)
    x[i] = S.Y[i][0] * s[0] + S.Y[i][1] * s[1] + S.y[i];
  double f = chi * (x[1] - x[0]), stick = t[1];
  if (sc->n == 3) {
    if (!(f <= -ur + tol)) {
      *inside = 0;
      return f + ur;
    }
    for (long j = 1; j < sc->np && (double)j * sc->h < t[1]; j++) {
      const over_map *Oj = &sc->O[j * sc->stride];
      double v = Oj->g[3];
      for (int l = 0; l < 4; l++)
        v += Oj->G[3][l] * x[l];
      if (V - v > tol)
        return V - v;
    }
    for (int i = 0; i < 4; i++) {
      y[i] = O.g[i];
      for (int l = 0; l < 4; l++)
        y[i] += O.G[i][l] * x[l];
    }
    memcpy(x, y, sizeof x);
    f = chi * (x[1] - x[0]);
    stick = t3;
  }
  if (!(fabs(f) <= ur + tol)) {
    *inside = 0;
    return fabs(f) - ur;
  }
  /* the stick: x2 = x2(0) + V t, x1 - chi x2 = Ac cos t + Bc sin t */
  double Ac = x[0] - chi * x[1], Bc = x[2] - chi * V;
  for (double u = sc->h; u < stick; u += sc->h) {
    double fu = chi * ((1 - chi) * (x[1] + V * u) - Ac * cos(u) - Bc * sin(u));
    if (fabs(fu) > ur + tol)
      return fabs(fu) - ur;
  }
  return 0;
}

/* Newton from the centre of a candidate cell of size h, on det * R: near
 * a pole of R (the system for s singular close by) R itself turns Newton
 * away.  1 if it converged (the root kept, or rejected, or known); -1 if
 * it stepped out of reach of the cell (the cell too coarse a model). */
static int newton(scan *sc, double t1, double t2, double h) {
  double t[2] = {t1, t2}, R[2], det = 0, t3 = 0;
  sc->newton++;
  int ok = 0;
  for (int it = 0; it < SCAN_NEWTON_ITERS && !ok; it++) {
    if (reduced(&sc->mc, sc->n, t, R, &det, &t3))
      return 0;
    /* forward differences: the root is polished by ss_orbit_solve() */
    double J[2][2];
    for (int j = 0; j < 2; j++) {
      double e = 1e-7 * fmax(1, t[j]), tp[2] = {t[0], t[1]}, Rp[2], u, v;
      tp[j] += e;
      if (reduced(&sc->mc, sc->n, tp, Rp, &u, &v))
        return 0;
      J[0][j] = (Rp[0] - R[0]) / e;
      J[1][j] = (Rp[1] - R[1]) / e;
    }
    double dj = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    if (!(dj != 0) || !isfinite(dj))
      return 0;
    double d0 = -(J[1][1] * R[0] - J[0][1] * R[1]) / dj;
    double d1 = -(J[0][0] * R[1] - J[1][0] * R[0]) / dj;
    double len = hypot(d0, d1);
    /* a root in the cell is within a step or so of its centre */
    if (len > 3 * h)
      return -1;
    t[0] += d0;
    t[1] += d1;
    if (!(t[0] > 0 && t[1] > 0))
      return 0;
    ok = len < 1e-10 * (1 + t[0] + t[1]);
    /* from inside its cell Newton reaches a root in a few steps */
    if (!ok && it >= SCAN_NEWTON_ITERS / 2 && len > 1e-6 * h)
      return 0;
  }
  if (reduced(&sc->mc, sc->n, t, R, &det, &t3) ||
      !(fabs(R[0]) + fabs(R[1]) < 1e-8 * sc->scale * fabs(det)))
    return 0;
  double lim = sc->dmax * (1 + 1e-12);
  if (!(t[0] <= lim && t[1] <= lim) || (sc->n == 3 && !(t3 > 0 && t3 <= lim)))
    return 1;
  int inside;
  double bad = implausible(sc, t, t3, &inside);
  if (bad > 0) {
    /* the closest of them, of those failing inside a phase and of those
     * failing at a phase's end, for a report of why there is no orbit */
    if (!(bad >= sc->rejected_by[inside])) {
      sc->rejected_by[inside] = bad;
      sc->rejected[inside][0] = t[0];
      sc->rejected[inside][1] = t[1];
      sc->rejected[inside][2] = t3;
    }
    return 1;
  }
  for (int i = 0; i < sc->count; i++)
    if (fabs(sc->roots[i][0] - t[0]) + fabs(sc->roots[i][1] - t[1]) <
        1e-7 * (1 + t[0] + t[1]))
      return 1;
  if (sc->count < sc->max) {
    sc->roots[sc->count][0] = t[0];
    sc->roots[sc->count][1] = t[1];
    sc->roots[sc->count][2] = t3;
  }
  sc->count++;
  return 1;
}

/* Do the four values keep one sign by more than half their spread?  As
 * fmin and fmax would, a NAN is passed over; with none finite, not said. */
static int keeps_sign(const double v[4]) {
  double lo = INFINITY, hi = -INFINITY;
  for (int k = 0; k < 4; k++) {
    lo = v[k] < lo ? v[k] : lo;
    hi = v[k] > hi ? v[k] : hi;
  }
  return isfinite(lo) && isfinite(hi) &&
         (lo > 0.5 * (hi - lo) || hi < -0.5 * (hi - lo));
}

/* Do the corners' E reach zero within half their spread?  A root needs
 * E = 0 (the stick is a rotation), wherever the stick's duration turns, so
 * a cell whose E keeps one sign has none.  E not finite at a corner: not
 * said.  Used for the slip-overshoot-stick cells, at every refinement (it
 * halves the Newton starts where the stick's duration turns fast); for the
 * slip-stick cells it lost one of the search battery's orbits at effort 1,
 * so those go by the residual alone. */
static int e_reaches_zero(point *const c[4]) {
  double v[4] = {c[0]->E, c[1]->E, c[2]->E, c[3]->E};
  return !keeps_sign(v);
}

/* Do the corners' n3 keep one sign by more than half their spread? */
static int n3_keeps_sign(point *const c[4]) {
  double v[4] = {c[0]->n3, c[1]->n3, c[2]->n3, c[3]->n3};
  return keeps_sign(v);
}

/* Does the slip break its rule (x2' < V) at one grid time j h before a1,
 * the cell's least slip duration, for the start of each corner, by more
 * than half the corners' spread?  Then no root in the cell is an orbit
 * (implausible() rejects a root at that grid time).  In a cell the
 * determinant keeps its sign in, the start s is smooth and x2'(j h) - V is
 * linear in s; were it linear across the cell, its least value would be at
 * a corner, and the margin of half the spread is for its curvature, as for
 * E and the residual.  Most roots of the reduced equations are of this kind
 * (from a start, x2' = V at every crossing, and t1 must be the first): at
 * chi 0.96, ur/us 15, 4201 of the 4391 roots in the box, none an orbit,
 * which took 128708 Newton starts to find. */
static int slip_breaks(const scan *sc, double a1, point *const c[4]) {
  double s[4][2];
  int pos = 0, neg = 0;
  for (int k = 0; k < 4; k++) {
    pos |= c[k]->det > 0;
    neg |= !(c[k]->det > 0);
  }
  if (pos && neg)
    return 0;
  const ss_params *p = &sc->m->p;
  double tol = 1e-9 * (p->ur + sc->scale);
  long last = a1 / sc->h < (double)sc->np ? (long)(a1 / sc->h) : sc->np - 1;
  while (last >= 1 && (double)last * sc->h >= a1)
    last--;
  /* before the corners' latest first break, one of them keeps the rule */
  long first = 1;
  for (int k = 0; k < 4; k++) {
    point *q = c[k];
    s[k][0] = q->sn[0] / q->det;
    s[k][1] = q->sn[1] / q->det;
    if (q->first_bad < 0 && q->clear < last) {
      long j = q->clear + 1;
      double s0 = s[k][0], s1 = s[k][1];
      while (j <= last &&
             !(sc->xv[j][0] * s0 + sc->xv[j][1] * s1 + sc->xv[j][2] > tol))
        j++;
      if (j <= last)
        q->first_bad = j;
      q->clear = j - 1;
    }
    if (q->first_bad < 0 || q->first_bad > last)
      return 0;
    first = q->first_bad > first ? q->first_bad : first;
  }
  /* from the end back: the crossing before t1 is the likely one */
  for (long j = last; j >= first; j--) {
    const double *v = sc->xv[j];
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 4; k++) {
      double g = v[0] * s[k][0] + v[1] * s[k][1] + v[2];
      lo = g < lo ? g : lo;
      hi = g > hi ? g : hi;
    }
    if (lo > tol + 0.5 * (hi - lo))
      return 1;
  }
  return 0;
}

/* Does each component's corner values reach zero within half their
 * spread?  Where not both change sign, the plane through the corners must
 * also put the zero within two cells of the centre (Newton's first step,
 * nearly). */
static int candidate(const ss_model *m, point *const c[4]) {
  for (int k = 0; k < 4; k++)
    residual(m, c[k]);
  int strict = 1;
  for (int r = 0; r < 2; r++) {
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 4; k++) {
      double v = c[k]->Rn[r];
      if (!isfinite(v))
        return 0;
      lo = v < lo ? v : lo; /* v is finite here */
      hi = v > hi ? v : hi;
    }
    double spread = hi - lo;
    if (lo > 0.5 * spread || hi < -0.5 * spread)
      return 0;
    strict = strict && lo <= 0 && hi >= 0;
  }
  if (strict)
    return 1;
  double f[2], g1[2], g2[2];
  for (int r = 0; r < 2; r++) {
    f[r] = 0.25 * (c[0]->Rn[r] + c[1]->Rn[r] + c[2]->Rn[r] + c[3]->Rn[r]);
    g1[r] = 0.5 * (c[2]->Rn[r] + c[3]->Rn[r] - c[0]->Rn[r] - c[1]->Rn[r]);
    g2[r] = 0.5 * (c[1]->Rn[r] + c[3]->Rn[r] - c[0]->Rn[r] - c[2]->Rn[r]);
  }
  double det = g1[0] * g2[1] - g2[0] * g1[1];
  if (!(det != 0))
    return 1;
  double u = -(f[0] * g2[1] - g2[0] * f[1]) / det;
  double v = -(g1[0] * f[1] - f[0] * g1[1]) / det;
  return fabs(u) <= 2 && fabs(v) <= 2;
}

/* A candidate cell [a1, b1] x [a2, b2], corners c as for cell_sos: Newton
 * from its centre; where Newton's step leaves the cell's reach (two zero
 * lines crossing at a small angle, or curving fast near a pole: the cell is
 * too coarse a model), the same in its quarters, up to refine more
 * halvings. */
static void try_cell(scan *sc, double a1, double b1, double a2, double b2,
                     point *const c[4], int refine) {
  sc->cells++;
  if ((sc->n == 3 && (!e_reaches_zero(c) || slip_breaks(sc, a1, c))) ||
      !candidate(sc->m, c) ||
      newton(sc, 0.5 * (a1 + b1), 0.5 * (a2 + b2), b1 - a1) != -1 ||
      refine == 0)
    return;
  double m1 = 0.5 * (a1 + b1), m2 = 0.5 * (a2 + b2);
  point e[5]; /* (a1, m2) (m1, a2) (m1, m2) (m1, b2) (b1, m2) */
  eval_at(&sc->mc, sc->n, a1, m2, &e[0]);
  eval_at(&sc->mc, sc->n, m1, a2, &e[1]);
  eval_at(&sc->mc, sc->n, m1, m2, &e[2]);
  eval_at(&sc->mc, sc->n, m1, b2, &e[3]);
  eval_at(&sc->mc, sc->n, b1, m2, &e[4]);
  point *const q[4][4] = {{c[0], &e[0], &e[1], &e[2]},
                          {&e[0], c[1], &e[2], &e[3]},
                          {&e[1], &e[2], c[2], &e[4]},
                          {&e[2], &e[3], &e[4], c[3]}};
  try_cell(sc, a1, m1, a2, m2, q[0], refine - 1);
  try_cell(sc, a1, m1, m2, b2, q[1], refine - 1);
  try_cell(sc, m1, b1, a2, m2, q[2], refine - 1);
  try_cell(sc, m1, b1, m2, b2, q[3], refine - 1);
}

/* A slip-overshoot-stick cell [i1, k1] x [i2, k2] in fine steps, corners
 * c: (i1, i2), (i1, k2), (k1, i2), (k1, k2). */
static void cell_sos(scan *sc, long i1, long k1, long i2, long k2, point *c0,
                     point *c1, point *c2, point *c3) {
  point *const c[4] = {c0, c1, c2, c3};
  sc->cells++;
  double lo = INFINITY, hi = -INFINITY, dm = sc->dmax;
  int pos = 0, neg = 0, near = 0;
  for (int k = 0; k < 4; k++) {
    double t3 = c[k]->t3;
    pos |= c[k]->det > 0;
    neg |= !(c[k]->det > 0);
    if (isfinite(t3)) {
      lo = t3 < lo ? t3 : lo; /* t3 is finite here */
      hi = t3 > hi ? t3 : hi;
      near |= t3 > -0.5 && t3 < dm + 0.5;
    }
  }
  int across = pos && neg;
  /* nowhere near the box, and no pole through the cell; or a pole through
   * it, but t3's numerator n3 keeping its sign: then t3 runs from the
   * corners' values out to an infinity, never into the box (for n3 and det
   * linear in the cell, n3 / det has no extremum inside it; the margin of
   * half the spread, as for E, is for their curvature) */
  if (!near && (!across || n3_keeps_sign(c)))
    return;
  /* away from a pole, E must reach zero in the cell, and the slip keep its
   * rule */
  if (!across && (!e_reaches_zero(c) ||
                  slip_breaks(sc, (double)i1 * sc->h / (double)sc->stride, c)))
    return;
  double hf = sc->h / (double)sc->stride;
  /* split; at the finest level a cell with no pole is tried as it is */
  if ((across || !(hi - lo <= SCAN_T3_TURN)) && (k1 - i1 >= 2 || across)) {
    if (k1 - i1 < 2)
      return;
    long m1 = (i1 + k1) / 2, m2 = (i2 + k2) / 2;
    make_maps(sc, m1);
    make_maps(sc, m2);
    const slip_map *S = sc->S;
    const over_map *O = sc->O;
    point e[5]; /* (i1, m2) (m1, i2) (m1, m2) (m1, k2) (k1, m2) */
    eval_sos(sc->m, &S[i1], &O[m2], dm, &e[0]);
    eval_sos(sc->m, &S[m1], &O[i2], dm, &e[1]);
    eval_sos(sc->m, &S[m1], &O[m2], dm, &e[2]);
    eval_sos(sc->m, &S[m1], &O[k2], dm, &e[3]);
    eval_sos(sc->m, &S[k1], &O[m2], dm, &e[4]);
    cell_sos(sc, i1, m1, i2, m2, c0, &e[0], &e[1], &e[2]);
    cell_sos(sc, i1, m1, m2, k2, &e[0], c1, &e[2], &e[3]);
    cell_sos(sc, m1, k1, i2, m2, &e[1], &e[2], c2, &e[4]);
    cell_sos(sc, m1, k1, m2, k2, &e[2], &e[3], &e[4], c3);
    return;
  }
  if (!(lo > -0.5 && hi < dm + 0.5))
    return;
  try_cell(sc, (double)i1 * hf, (double)k1 * hf, (double)i2 * hf,
           (double)k2 * hf, c, sc->refine);
}

int ss__scan_period1(const ss_model *m, int n, double dmax, double h,
                     int refine, double (*roots)[3], int max_roots,
                     int *n_roots, double (*rejected)[3], int *n_rejected,
                     int *newton_starts, long *cells, double *step,
                     int (*stop)(void *), void *stop_cls) {
  *n_roots = 0;
  *n_rejected = 0;
  if ((n != 2 && n != 3) || !(dmax > 0) || !(h > 0) || refine < 0 ||
      refine > SCAN_MAX_REFINE)
    return SS_EINVAL;
  double side = ceil(dmax / h);
  long N = side < 8 ? 8 : side > SCAN_MAX_CELLS ? SCAN_MAX_CELLS : (long)side;
  h = dmax / (double)N;
  *step = h;
  long np = N + 1, stride = n == 3 ? 1L << SCAN_MAX_DEPTH : 1;
  long nf = N * stride + 1;
  slip_map *S = malloc((size_t)nf * sizeof *S);
  over_map *O = n == 3 ? malloc((size_t)nf * sizeof *O) : NULL;
  point *row = malloc(2 * (size_t)np * sizeof *row);
  double(*cs)[2] = malloc((size_t)np * sizeof *cs);
  unsigned char *made = calloc((size_t)nf, 1);
  double(*xv)[3] = malloc((size_t)np * sizeof *xv);
  if (!S || (n == 3 && !O) || !row || !cs || !made || !xv) {
    free(S);
    free(O);
    free(row);
    free(cs);
    free(made);
    free(xv);
    return SS_ENOMEM;
  }
  for (long j = 0; j < np; j++) {
    cs[j][0] = cos((double)j * h);
    cs[j][1] = sin((double)j * h);
  }
  const ss_params *p = &m->p;
  scan sc = {.m = m,
             .mc = {.m = m, .ts = {NAN, NAN}, .to = {NAN, NAN}},
             .n = n,
             .dmax = dmax,
             .scale = fmax(p->V, (p->ur - p->us) / p->chi),
             .h = h,
             .refine = refine,
             .np = np,
             .stride = stride,
             .S = S,
             .O = O,
             .made = made,
             .xv = xv,
             .roots = roots,
             .max = max_roots,
             .rejected_by = {INFINITY, INFINITY}};
  for (long i = 0; i < nf; i += stride)
    make_maps(&sc, i);
  for (long j = 0; j < np; j++) {
    const slip_map *Sj = &S[j * stride];
    xv[j][0] = Sj->Y[3][0];
    xv[j][1] = Sj->Y[3][1];
    xv[j][2] = Sj->y[3] - p->V;
  }
  /* rows t1 = i h; the first row of cells (t1 < h) is degenerate: at
   * t1 = 0 the slip's end condition holds for every s */
  int rc = SS_OK;
  for (long i = 1; i < np && rc == SS_OK; i++) {
    if (stop && stop(stop_cls))
      rc = SS_ECANCELED;
    point *cur = row + (i & 1) * np, *prv = row + ((i + 1) & 1) * np;
    for (long j = 0; j < np; j++) {
      if (n == 2)
        eval_ss(m, &S[i], (double)j * h, cs[j][0], cs[j][1], &cur[j]);
      else
        eval_sos(m, &S[i * stride], &O[j * stride], dmax, &cur[j]);
    }
    if (i < 2)
      continue;
    for (long j = n == 2 ? 0 : 1; j < N; j++) {
      if (n == 3) {
        cell_sos(&sc, (i - 1) * stride, i * stride, j * stride,
                 (j + 1) * stride, &prv[j], &prv[j + 1], &cur[j], &cur[j + 1]);
      } else {
        point *const c[4] = {&prv[j], &prv[j + 1], &cur[j], &cur[j + 1]};
        try_cell(&sc, (double)(i - 1) * h, (double)i * h, (double)j * h,
                 (double)(j + 1) * h, c, refine);
      }
    }
  }
  free(S);
  free(O);
  free(row);
  free(cs);
  free(made);
  free(xv);
  *n_roots = sc.count < max_roots ? sc.count : max_roots;
  for (int k = 0; k < 2; k++)
    if (isfinite(sc.rejected_by[k]))
      memcpy(rejected[(*n_rejected)++], sc.rejected[k], sizeof sc.rejected[k]);
  if (newton_starts)
    *newton_starts += sc.newton;
  if (cells)
    *cells += sc.cells;
  return rc;
}
