/*
 * orbit.c: periodic orbits (sections 3 and 5): the duration equations with
 * the start state eliminated through (5.1), their feasibility with the
 * certified event finder, and a search that needs no guess.
 */
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_multiroots.h>
#include <gsl/gsl_vector.h>

#include "events.h"
#include "internal.h"
#include "linalg.h"
#include "modal.h"
#include "orbit.h"
#include "simulate.h"

#define MAXP SS_MAX_PHASES

/* Convergence of the duration equations: max |F| below this many ulps of the
 * scale of the equations (velocities ~ V, forces ~ ur). */
#define RESID_ULPS 64.0
#define MAX_SOLVER_ITERS 100

const char *ss_orbit_kind_name(ss_orbit_kind k) {
  switch (k) {
  case SS_ORBIT_OVERSHOOT:
    return "overshoot";
  case SS_ORBIT_STICKSLIP:
    return "stick-slip";
  case SS_ORBIT_OTHER:
    return "other";
  default:
    return NULL;
  }
}

const char *ss_orbit_source_name(ss_orbit_source s) {
  static const char *const names[] = {"guess", "simulation", "duration-grid",
                                      "poincare-newton", "certificate"};
  return (unsigned)s < sizeof names / sizeof names[0] ? names[s] : NULL;
}

ss_orbit_kind ss_orbit_kind_of(int n, const ss_mode *modes) {
  if (n == 3 && modes[0] == SS_MODE_SLIP && modes[1] == SS_MODE_OVERSHOOT &&
      modes[2] == SS_MODE_STICK)
    return SS_ORBIT_OVERSHOOT;
  if (n == 2 && modes[0] == SS_MODE_SLIP && modes[1] == SS_MODE_STICK)
    return SS_ORBIT_STICKSLIP;
  return SS_ORBIT_OTHER;
}

/* ---- the duration equations ------------------------------------------- */

static double maxabs(const double *v, int n) {
  double r = 0;
  for (int i = 0; i < n; i++)
    r = fmax(r, fabs(v[i]));
  return r;
}

typedef struct oeq {
  const ss_model *m;
  int n;
  ss_mode modes[MAXP];
  int sign[MAXP]; /* stick phase k < n-1: +1 ends at +ur (slip), -1 at -ur */
} oeq;

static int oeq_init(oeq *q, const ss_model *m, int n, const ss_mode *modes) {
  if (n < 2 || n > MAXP || modes[0] != SS_MODE_SLIP ||
      modes[n - 1] != SS_MODE_STICK)
    return SS_EINVAL;
  q->m = m;
  q->n = n;
  for (int k = 0; k < n; k++) {
    if (modes[k] != SS_MODE_SLIP && modes[k] != SS_MODE_OVERSHOOT &&
        modes[k] != SS_MODE_STICK)
      return SS_EINVAL;
    if (k > 0 && modes[k] == modes[k - 1])
      return SS_EINVAL;
    q->modes[k] = modes[k];
    q->sign[k] = 0;
    if (modes[k] == SS_MODE_STICK)
      q->sign[k] = (k + 1 < n && modes[k + 1] == SS_MODE_OVERSHOOT) ? -1 : 1;
  }
  return SS_OK;
}

/* Gradient of the end condition of phase k (in z). */
static void end_grad(const oeq *q, int k, double gvec[4]) {
  memset(gvec, 0, 4 * sizeof *gvec);
  if (q->modes[k] == SS_MODE_STICK) {
    gvec[0] = -q->m->p.chi;
    gvec[1] = q->m->p.chi;
  } else {
    gvec[3] = 1;
  }
}

static double end_value(const oeq *q, int k, const double Z[4]) {
  const ss_params *p = &q->m->p;
  if (q->modes[k] == SS_MODE_STICK)
    return p->chi * (Z[1] - Z[0]) + p->us - q->sign[k] * p->ur;
  return Z[3] - p->V;
}

/* The phase maps at tau and their prefixes: after k phases the state is
 * P[k] z0 + qv[k]; A, c are phase k's map and dA, dc their derivatives in
 * its duration. */
typedef struct oeq_maps {
  double A[MAXP][16], c[MAXP][4], dA[MAXP][16], dc[MAXP][4];
  double P[MAXP + 1][16], qv[MAXP + 1][4];
} oeq_maps;

static void maps_eval(const oeq *q, const double *tau, oeq_maps *x) {
  static const double I4[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  for (int k = 0; k < q->n; k++)
    ss_transition(q->m, q->modes[k], tau[k], x->A[k], x->c[k], x->dA[k],
                  x->dc[k]);
  memcpy(x->P[0], I4, sizeof I4);
  memset(x->qv[0], 0, sizeof x->qv[0]);
  for (int k = 0; k < q->n; k++) {
    mat4_mul(x->A[k], x->P[k], x->P[k + 1]);
    memcpy(x->qv[k + 1], x->c[k], sizeof x->c[k]);
    mat4_vec(x->A[k], x->qv[k], x->qv[k + 1], 1);
  }
}

/* The derivatives of the prefixes in tau_j: dP[k], dq[k] for k > j (the
 * earlier ones do not depend on it). */
static void maps_deriv(const oeq *q, const oeq_maps *x, int j,
                       double dP[MAXP + 1][16], double dq[MAXP + 1][4]) {
  /* dP_{j+1} = dA_j P_j, dq_{j+1} = dA_j q_j + dc_j */
  mat4_mul(x->dA[j], x->P[j], dP[j + 1]);
  memcpy(dq[j + 1], x->dc[j], sizeof dq[j + 1]);
  mat4_vec(x->dA[j], x->qv[j], dq[j + 1], 1);
  for (int k = j + 1; k < q->n; k++) {
    mat4_mul(x->A[k], dP[k], dP[k + 1]);
    mat4_vec(x->A[k], dq[k], dq[k + 1], 0);
  }
}

/* The matrix of (5.1) in z0: rows 1-3 of N - I, row 4 picking z2'(0). */
static void periodicity_matrix(const oeq_maps *x, int n, double B[16]) {
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 4; j++)
      B[4 * i + j] = x->P[n][4 * i + j] - (i == j);
  B[12] = B[13] = B[14] = 0;
  B[15] = 1;
}

/* The duration equations at the start z0: (3.1) and the end condition of
 * every phase but the last. */
static void duration_rows(const oeq *q, const oeq_maps *x, const double z0[4],
                          double *F) {
  const ss_params *p = &q->m->p;
  F[0] = p->chi * (z0[1] - z0[0]) - (p->ur - p->us);
  for (int k = 0; k + 1 < q->n; k++) {
    double Z[4];
    memcpy(Z, x->qv[k + 1], sizeof Z);
    mat4_vec(x->P[k + 1], z0, Z, 1);
    F[k + 1] = end_value(q, k, Z);
  }
}

/* F(tau) and, if J != NULL, its Jacobian (n x n row-major); z0 the start. */
static int oeq_eval(const oeq *q, const double *tau, double z0[4], double *F,
                    double *J) {
  const int n = q->n;
  const ss_params *p = &q->m->p;
  oeq_maps x;
  maps_eval(q, tau, &x);
  /* (5.1): rows 1-3 of (N - I) z0 = -c, row 4 replaced by z2'(0) = V. */
  double LU[16];
  int piv[4];
  periodicity_matrix(&x, n, LU);
  if (lu_factor(LU, 4, piv, 1e-13))
    return SS_ESINGULAR;
  z0[0] = -x.qv[n][0];
  z0[1] = -x.qv[n][1];
  z0[2] = -x.qv[n][2];
  z0[3] = p->V;
  lu_solve(LU, 4, piv, z0);
  duration_rows(q, &x, z0, F);
  if (!J)
    return SS_OK;
  for (int j = 0; j < n; j++) {
    double dPk[MAXP + 1][16], dqk[MAXP + 1][4], dz0[4];
    maps_deriv(q, &x, j, dPk, dqk);
    /* dz0 = B^-1 (-(dM z0 + dc)[0..2], 0) */
    double r[4] = {0, 0, 0, 0};
    mat4_vec(dPk[n], z0, r, 0);
    for (int i = 0; i < 3; i++)
      dz0[i] = -(r[i] + dqk[n][i]);
    dz0[3] = 0;
    lu_solve(LU, 4, piv, dz0);
    J[j] = p->chi * (dz0[1] - dz0[0]);
    for (int k = 0; k + 1 < n; k++) {
      double dZ[4], gv[4];
      mat4_vec(x.P[k + 1], dz0, dZ, 0);
      if (j <= k) {
        mat4_vec(dPk[k + 1], z0, dZ, 1);
        for (int i = 0; i < 4; i++)
          dZ[i] += dqk[k + 1][i];
      }
      end_grad(q, k, gv);
      J[n * (k + 1) + j] =
          gv[0] * dZ[0] + gv[1] * dZ[1] + gv[2] * dZ[2] + gv[3] * dZ[3];
    }
  }
  return SS_OK;
}

/* The same equations before z0 is eliminated: the n + 4 unknowns
 * u = (z0, tau), the rows of (5.1) (as B z0 + (q_n, -V)) and the n
 * duration rows, with their Jacobian ((n + 4) x (n + 4)) when JG is not
 * NULL.  Where a multiplier of the return map is +1, B is singular (z0 is
 * then not fixed by tau alone) and F(tau) has a pole on the family, but
 * this system stays regular. */
static void full_eval(const oeq *q, const double *u, double *G, double *JG) {
  const int n = q->n, nu = n + 4;
  const double *z0 = u, *tau = u + 4;
  oeq_maps x;
  double B[16];
  maps_eval(q, tau, &x);
  periodicity_matrix(&x, n, B);
  for (int i = 0; i < 4; i++) {
    G[i] = i < 3 ? x.qv[n][i] : -q->m->p.V;
    for (int j = 0; j < 4; j++)
      G[i] += B[4 * i + j] * z0[j];
  }
  duration_rows(q, &x, z0, G + 4);
  if (!JG)
    return;
  memset(JG, 0, sizeof(double) * (size_t)(nu * nu));
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++)
      JG[nu * i + j] = B[4 * i + j];
  JG[nu * 4 + 0] = -q->m->p.chi;
  JG[nu * 4 + 1] = q->m->p.chi;
  for (int k = 0; k + 1 < n; k++) {
    double gv[4];
    end_grad(q, k, gv);
    for (int j = 0; j < 4; j++)
      for (int i = 0; i < 4; i++)
        JG[nu * (5 + k) + j] += gv[i] * x.P[k + 1][4 * i + j];
  }
  for (int j = 0; j < n; j++) {
    double dPk[MAXP + 1][16], dqk[MAXP + 1][4], dZ[4];
    maps_deriv(q, &x, j, dPk, dqk);
    memcpy(dZ, dqk[n], sizeof dZ);
    mat4_vec(dPk[n], z0, dZ, 1);
    for (int i = 0; i < 3; i++)
      JG[nu * i + 4 + j] = dZ[i];
    for (int k = j; k + 1 < n; k++) {
      double gv[4];
      memcpy(dZ, dqk[k + 1], sizeof dZ);
      mat4_vec(dPk[k + 1], z0, dZ, 1);
      end_grad(q, k, gv);
      JG[nu * (5 + k) + 4 + j] =
          gv[0] * dZ[0] + gv[1] * dZ[1] + gv[2] * dZ[2] + gv[3] * dZ[3];
    }
  }
}

int ss__orbit_solve_full(const ss_model *m, int n, const ss_mode *modes,
                         double *tau, double z0[4], double *resid) {
  oeq q;
  if (oeq_init(&q, m, n, modes))
    return SS_EINVAL;
  const int nu = n + 4;
  const double tolF = RESID_ULPS * DBL_EPSILON * fmax(m->p.V, m->p.ur);
  double u[MAXP + 4], best[MAXP + 4], G[MAXP + 4];
  double JG[(MAXP + 4) * (MAXP + 4)], rbest = INFINITY, sprev = INFINITY;
  int piv[MAXP + 4];
  memcpy(u, z0, 4 * sizeof *u);
  memcpy(u + 4, tau, (size_t)n * sizeof *u);
  /* Newton until the step is a few ulps of the unknowns or, the system
   * being ill-conditioned near a singular point, stops shrinking at the
   * level of rounding; the iterate of least residual is kept, and taken
   * when its residual is within the tolerance of ss_orbit_solve(). */
  for (int it = 0; it < 30; it++) {
    double smax = 0, umax = 0, r;
    full_eval(&q, u, G, JG);
    if ((r = maxabs(G, nu)) < rbest) {
      rbest = r;
      memcpy(best, u, (size_t)nu * sizeof *u);
    }
    if (lu_factor(JG, nu, piv, 1e-15))
      break;
    for (int i = 0; i < nu; i++)
      G[i] = -G[i];
    lu_solve(JG, nu, piv, G);
    for (int i = 0; i < nu; i++) {
      u[i] += G[i];
      smax = fmax(smax, fabs(G[i]));
      umax = fmax(umax, fabs(u[i]));
    }
    if (!isfinite(smax) ||
        (it >= 3 && smax <= 1e-8 * umax && smax > 0.5 * sprev))
      break;
    sprev = smax;
    if (smax <= 8 * DBL_EPSILON * umax) {
      full_eval(&q, u, G, NULL);
      if ((r = maxabs(G, nu)) < rbest) {
        rbest = r;
        memcpy(best, u, (size_t)nu * sizeof *u);
      }
      break;
    }
  }
  for (int i = 0; i < n; i++)
    if (!(best[4 + i] > 0))
      return SS_ENOCONV;
  if (!(rbest <= 1e3 * tolF))
    return SS_ENOCONV;
  memcpy(z0, best, 4 * sizeof *u);
  memcpy(tau, best + 4, (size_t)n * sizeof *u);
  *resid = rbest;
  return SS_OK;
}

int ss_orbit_equations(const ss_model *m, int n, const ss_mode *modes,
                       const double *tau, double z0[4], double *F, double *J) {
  oeq q;
  if (!m || !modes || !tau || !z0 || !F || oeq_init(&q, m, n, modes))
    return SS_EINVAL;
  return oeq_eval(&q, tau, z0, F, J);
}

/* GSL callbacks */
typedef struct gsl_ctx {
  const oeq *q;
  int bad;
} gsl_ctx;

static int gf(const gsl_vector *x, void *vp, gsl_vector *f) {
  gsl_ctx *g = vp;
  double z0[4];
  if (oeq_eval(g->q, x->data, z0, f->data, NULL)) {
    g->bad = 1;
    return GSL_EBADFUNC;
  }
  return GSL_SUCCESS;
}

static int gdf(const gsl_vector *x, void *vp, gsl_matrix *J) {
  gsl_ctx *g = vp;
  double z0[4], F[MAXP];
  if (oeq_eval(g->q, x->data, z0, F, J->data)) {
    g->bad = 1;
    return GSL_EBADFUNC;
  }
  return GSL_SUCCESS;
}

static int gfdf(const gsl_vector *x, void *vp, gsl_vector *f, gsl_matrix *J) {
  gsl_ctx *g = vp;
  double z0[4];
  if (oeq_eval(g->q, x->data, z0, f->data, J->data)) {
    g->bad = 1;
    return GSL_EBADFUNC;
  }
  return GSL_SUCCESS;
}

/* The hybridsj solvers of a thread, by number of unknowns, kept from one
 * solve to the next: allocating one is some 55 blocks from malloc, a tenth
 * of a solve from a guess, and gsl_multiroot_fdfsolver_set initialises
 * all of its state.  Freed when the thread ends. */
static _Thread_local gsl_multiroot_fdfsolver *solver_kept[MAXP + 1];
static pthread_key_t solver_key;
static pthread_once_t solver_once = PTHREAD_ONCE_INIT;
static int solver_key_ok;

static void solvers_free(void *kept) {
  gsl_multiroot_fdfsolver **k = kept;
  for (int n = 0; n <= MAXP; n++)
    if (k[n]) {
      gsl_multiroot_fdfsolver_free(k[n]);
      k[n] = NULL;
    }
}

static void solver_key_make(void) {
  solver_key_ok = pthread_key_create(&solver_key, solvers_free) == 0;
}

static gsl_multiroot_fdfsolver *solver_take(int n) {
  gsl_multiroot_fdfsolver *s = solver_kept[n];
  if (s) {
    solver_kept[n] = NULL;
    return s;
  }
  return gsl_multiroot_fdfsolver_alloc(gsl_multiroot_fdfsolver_hybridsj,
                                       (size_t)n);
}

/* @a s back to the thread's solvers, where the thread's end frees it (or
 * freed now, when that cannot be arranged). */
static void solver_give(int n, gsl_multiroot_fdfsolver *s) {
  pthread_once(&solver_once, solver_key_make);
  if (solver_kept[n] || !solver_key_ok ||
      (!pthread_getspecific(solver_key) &&
       pthread_setspecific(solver_key, solver_kept) != 0)) {
    gsl_multiroot_fdfsolver_free(s);
    return;
  }
  solver_kept[n] = s;
}

/* Solve the duration equations from tau (in place).  Returns SS_OK with
 * z0, the residual and the iteration count, or a failure. */
static int solve_durations(const oeq *q, double *tau, double z0[4],
                           double *resid, int *iters) {
  const int n = q->n;
  const ss_params *p = &q->m->p;
  double scale = fmax(p->V, p->ur);
  double tolF = RESID_ULPS * DBL_EPSILON * scale;
  gsl_ctx ctx = {q, 0};
  gsl_multiroot_function_fdf fdf = {gf, gdf, gfdf, (size_t)n, &ctx};
  gsl_vector_view xv = gsl_vector_view_array(tau, (size_t)n);
  gsl_multiroot_fdfsolver *s = solver_take(n);
  int rc = SS_ENOCONV, it = 0, status;
  double F[MAXP], J[MAXP * MAXP], x[MAXP];
  if (!s)
    return SS_ENOMEM;
  if (gsl_multiroot_fdfsolver_set(s, &fdf, &xv.vector) != GSL_SUCCESS ||
      ctx.bad) {
    solver_give(n, s);
    return SS_ESINGULAR;
  }
  do {
    it++;
    status = gsl_multiroot_fdfsolver_iterate(s);
    if (status != GSL_SUCCESS || ctx.bad)
      break;
    status = gsl_multiroot_test_residual(s->f, 1e3 * tolF);
  } while (status == GSL_CONTINUE && it < MAX_SOLVER_ITERS);
  memcpy(x, s->x->data, (size_t)n * sizeof *x);
  solver_give(n, s);
  /* Polish: plain Newton steps while the residual falls. */
  if (oeq_eval(q, x, z0, F, J))
    return SS_ESINGULAR;
  double r = maxabs(F, n);
  for (int k = 0; k < 4 && r > tolF; k++) {
    int piv[MAXP];
    double step[MAXP], xn[MAXP], Fn[MAXP], Jn[MAXP * MAXP], zn[4];
    if (lu_factor(J, n, piv, 1e-15))
      break;
    for (int i = 0; i < n; i++)
      step[i] = -F[i];
    lu_solve(J, n, piv, step);
    for (int i = 0; i < n; i++)
      xn[i] = x[i] + step[i];
    if (oeq_eval(q, xn, zn, Fn, Jn))
      break;
    double rn = maxabs(Fn, n);
    if (!(rn < r))
      break;
    memcpy(x, xn, (size_t)n * sizeof *x);
    memcpy(F, Fn, (size_t)n * sizeof *F);
    memcpy(J, Jn, (size_t)(n * n) * sizeof *J);
    memcpy(z0, zn, 4 * sizeof *z0);
    r = rn;
    it++;
  }
  if (oeq_eval(q, x, z0, F, NULL))
    return SS_ESINGULAR;
  r = maxabs(F, n);
  memcpy(tau, x, (size_t)n * sizeof *tau);
  *resid = r;
  *iters = it;
  if (r <= 1e3 * tolF && isfinite(r))
    rc = SS_OK;
  return rc;
}

/* ---- feasibility and margins ------------------------------------------ */

static void margin_set(ss_margin *mg, double v, int phase, double t) {
  if (v < mg->value) {
    mg->value = v;
    mg->phase = phase;
    mg->t = t;
  }
}

/* The derivative of g as an ss_trig. */
static void trig_deriv(const ss_trig *g, ss_trig *h) {
  memset(h, 0, sizeof *h);
  h->n = g->n;
  h->c0 = g->c1;
  for (int k = 0; k < g->n; k++) {
    h->w[k] = g->w[k];
    h->a[k] = g->w[k] * g->b[k];
    h->b[k] = -g->w[k] * g->a[k];
  }
}

/* The interior local maxima of g on (0, T), reported through cb: the zeros
 * of g' at which g' falls.  Walks from one zero of g' to the next with the
 * certified finder: while g' > 0 (g rising) the next zero of g' is a maximum
 * of g, found as the first zero of -g'; while g' < 0 it is a minimum, found
 * as the first zero of g'. */
static void interior_maxima(const ss_trig *g, double T,
                            void (*cb)(void *, double, double), void *ctx) {
  ss_trig h, hn;
  double t = 0;
  trig_deriv(g, &h);
  hn = h;
  hn.c0 = -h.c0;
  hn.c1 = -h.c1;
  for (int k = 0; k < h.n; k++) {
    hn.a[k] = -h.a[k];
    hn.b[k] = -h.b[k];
  }
  for (int guard = 0; guard < 10000 && t < T; guard++) {
    double r;
    int dir;
    (void)ss__trig_at_zero(&h, t, &dir); /* sign of g' at t, or where it goes */
    int rising = dir > 0;
    int rc = ss_trig_first_root(rising ? &hn : &h, t, T, &r);
    if (rc != SS_OK && rc != SS_GRAZING)
      break;
    if (rising && rc == SS_OK && r > 0 && r < T * (1 - 1e-12)) {
      double gv[1];
      ss_trig_eval(g, r, 0, gv);
      cb(ctx, r, gv[0]);
    }
    if (r <= t) /* at a zero of g' already: step past it */
      r = t + 1e-9 * fmax(1.0, T);
    t = r;
  }
}

typedef struct max_ctx {
  ss_margin *mg;
  int phase;
} max_ctx;

static void record_max(void *vp, double t, double g) {
  max_ctx *c = vp;
  margin_set(c->mg, -g, c->phase, t);
}

static void violate(ss_orbit *o, ss_margin_id id, double value, int phase,
                    double t) {
  o->violation_id = id;
  o->violation.value = value;
  o->violation.phase = phase;
  o->violation.t = t;
  o->min_margin = o->violation; /* what decides, for a rejected root */
}

static void check_fail(ss_diag *d, const char *fmt, int k, ss_mode m, double a,
                       double b) {
  char where[32];
  snprintf(where, sizeof where, "phase %d (%s)", k, ss_mode_name(m));
  ss__fail(d, SS_INFEASIBLE, where, a, fmt, k, ss_mode_name(m), a, b);
}

/* The value margins ss_orbit_check() fills, in the order the smallest is
 * chosen (after the switching margin, the first of a tie kept). */
#define N_VALUE_MARGINS 5
static void value_margins(ss_orbit *o, ss_margin *all[N_VALUE_MARGINS]) {
  all[0] = &o->slip_below;
  all[1] = &o->over_above;
  all[2] = &o->stick_upper;
  all[3] = &o->stick_lower;
  all[4] = &o->switching;
}

/* Every margin unbound, no violation, no period yet. */
static void check_reset(ss_orbit *o) {
  ss_margin *all[N_VALUE_MARGINS];
  value_margins(o, all);
  for (int i = 0; i < N_VALUE_MARGINS; i++) {
    all[i]->value = INFINITY;
    all[i]->phase = -1;
    all[i]->t = 0;
  }
  o->transversal.value = INFINITY;
  o->transversal.phase = -1;
  o->violation_id = SS_MARGIN_NONE;
  o->min_margin.value = INFINITY;
  o->min_margin.phase = -1;
  o->violation.value = INFINITY;
  o->violation.phase = -1;
  o->violation.t = 0;
  o->period = 0;
  o->n_turns = 0;
}

/* Each duration positive; the period and the passes through Sigma0. */
static int check_durations(ss_orbit *o, ss_diag *d) {
  const int n = o->n_phases;
  for (int k = 0; k < n; k++) {
    if (!(o->durations[k] > 0)) {
      violate(o, SS_MARGIN_DURATION, o->durations[k], k, 0);
      return ss__fail(d, SS_INFEASIBLE, "durations", o->durations[k],
                      "phase %d (%s) has a non-positive duration %.6g", k,
                      ss_mode_name(o->modes[k]), o->durations[k]);
    }
    o->period += o->durations[k];
    if (o->modes[k] == SS_MODE_STICK &&
        (k + 1 == n || o->modes[k + 1] == SS_MODE_SLIP))
      o->n_turns++;
  }
  return SS_OK;
}

/* The value margins of phase k (mode, then want, of duration tau from xs)
 * from its closed form. */
static void phase_margins(const ss_model *m, ss_orbit *o, int k, ss_mode mode,
                          ss_mode want, const double xs[4], double tau) {
  ss_trig g;
  max_ctx mc = {NULL, k};
  if (mode == SS_MODE_STICK) {
    /* (2.7) on both sides: ur - chi(x2-x1) and ur + chi(x2-x1).  The side
     * the stick ends on is zero at the end by construction, so only its
     * interior maxima count; the other side counts at both ends too. */
    int end_sign = want == SS_MODE_OVERSHOOT ? -1 : 1;
    for (int side = 1; side >= -1; side -= 2) {
      mc.mg = side > 0 ? &o->stick_upper : &o->stick_lower;
      ss__switching(m, mode, side, xs, &g);
      interior_maxima(&g, tau, record_max, &mc);
      if (side != end_sign) {
        double v0[1], v1[1];
        ss_trig_eval(&g, 0, 0, v0);
        ss_trig_eval(&g, tau, 0, v1);
        margin_set(mc.mg, -v0[0], k, 0);
        margin_set(mc.mg, -v1[0], k, tau);
      }
    }
  } else {
    mc.mg = mode == SS_MODE_SLIP ? &o->slip_below : &o->over_above;
    ss__switching(m, mode, 0, xs, &g);
    interior_maxima(&g, tau, record_max, &mc);
  }
}

/* The end switching function's value and slope at the end of phase k: a
 * slope > 0 is a transversal crossing. */
static void phase_end_slope(const ss_model *m, ss_orbit *o, int k, ss_mode mode,
                            ss_mode want, const double xs[4], double tau,
                            ss_trig *ge, double *g_end, double *g_slope) {
  double v[2];
  ss__end_switching(m, mode, want, xs, ge);
  ss_trig_eval(ge, tau, 1, v);
  margin_set(&o->transversal, v[1], k, tau);
  *g_end = v[0];
  *g_slope = v[1];
}

/* The certified finder: the first event of phase k (started at t0k of the
 * run) must be its end, at the sum of the durations up to it (t_expect),
 * not earlier, and not a tangency.  A tangency at the end when the end
 * rises (@a rises) is SS_GRAZING, for end_by_slope to judge. */
static int phase_event(ss_orbit *o, ss_sim *sim, int k, double t0k,
                       double g_end, int rises, double t_expect, ss_event *ev,
                       ss_diag *d) {
  double tau = o->durations[k], slack = 1e-7 * (1 + tau);
  ss_mode mode = o->modes[k];
  int rc = ss_sim_next_event(sim, ss_sim_time(sim) + tau + slack, ev);
  if (rc == SS_HORIZON) {
    violate(o, SS_MARGIN_PHASE_END, g_end, k, tau);
    return ss__fail(d, SS_INFEASIBLE, "phases", tau,
                    "phase %d (%s) does not end at its duration %.9g: its "
                    "switching function does not reach zero",
                    k, ss_mode_name(mode), tau);
  }
  if (rc)
    return ss__fail(d, rc, "phases", tau, "event search failed");
  if (ev->kind == SS_EVENT_GRAZING) {
    if (rises && fabs(ev->t - t_expect) <= slack * (k + 1))
      return SS_GRAZING;
    violate(o, SS_MARGIN_GRAZING, 0, k, ev->t - t0k);
    check_fail(d,
               "phase %d (%s) touches its switching surface tangentially at "
               "t = %.9g (duration %.9g): a grazing orbit",
               k, mode, ev->t, tau);
    return SS_INFEASIBLE;
  }
  if (ev->from != mode)
    return ss__fail(d, SS_EBUG, "phases", k, "mode mismatch");
  /* compare the end time, measured from the start of the run */
  if (ev->t < t_expect - slack * (k + 1)) {
    violate(o, SS_MARGIN_ENDS_EARLY, ev->t - t_expect, k, ev->t - t0k);
    check_fail(d,
               "phase %d (%s) ends early, at its first crossing t = %.9g "
               "instead of %.9g",
               k, mode, ev->t, t_expect);
    return SS_INFEASIBLE;
  }
  return SS_OK;
}

/* A tangency that the finder reports at the end of phase k, whose
 * switching function rises there beyond the rounding of its slope
 * (ss__trig_rises_at): the finder judges a zero by the values of g, and
 * cannot tell a crossing whose rise above zero, slope^2 / (2 |g''|), is
 * below their rounding (its tolerance) from a touch.  The orbit's equations
 * put the zero at the end, to their residual; g rises through it, and the
 * certified steps before the touch exclude an earlier zero.  So the phase
 * ends there by a crossing: the run goes on from the end's closed-form
 * state in the next mode, and @a ev is that event.  (A simulation from the
 * orbit's start, with only the values, reports the touch and stays in the
 * mode.) */
static int end_by_slope(const ss_model *m, ss_sim *sim, ss_mode mode,
                        ss_mode want, const double xs[4], double tau,
                        double t_expect, ss_event *ev, ss_diag *d) {
  ev->t = t_expect;
  ev->from = mode;
  ev->to = want;
  ev->kind = SS_EVENT_TRANSITION;
  ss_flow(m, mode, tau, xs, ev->x);
  return ss__sim_init_mode(sim, m, t_expect, ev->x, want, d) == SS_OK ? SS_OK
                                                                      : SS_EBUG;
}

/* Falling (or flat) at its end, the switching function was above zero just
 * before: it crossed zero earlier, and the phase ends early, however little
 * (within the slack of phase_event: beside a tangency at the end, by about
 * 2 |slope| / |curvature|). */
static int phase_transversal(ss_orbit *o, int k, double g_end, double g_slope,
                             ss_diag *d) {
  double tau = o->durations[k];
  ss_mode mode = o->modes[k];
  if (!(g_slope > 0)) {
    violate(o, SS_MARGIN_TRANSVERSALITY, g_slope, k, tau);
    check_fail(d,
               "phase %d (%s) meets its end with the switching function's "
               "slope %.3g <= 0: it crossed zero before, so it ends early "
               "(its value there %.3g)",
               k, mode, g_slope, g_end);
    return SS_INFEASIBLE;
  }
  return SS_OK;
}

/* The switching conditions at the end of phase k (event ev): the margin of
 * the mode rule, and the next mode must be the sequence's. */
static int phase_switching(const ss_model *m, ss_orbit *o, int k, ss_mode want,
                           const ss_event *ev, ss_diag *d) {
  const ss_params *p = &m->p;
  double tau = o->durations[k];
  ss_mode mode = o->modes[k];
  double f = ss_stick_force(m, ev->x), sw = INFINITY;
  if (mode == SS_MODE_SLIP)
    sw = want == SS_MODE_OVERSHOOT ? -p->ur - f /* (3.2) */ : f + p->ur;
  else if (mode == SS_MODE_OVERSHOOT)
    sw = want == SS_MODE_STICK ? p->ur - f /* (3.4) */ : f - p->ur;
  if (mode != SS_MODE_STICK)
    margin_set(&o->switching, sw, k, tau);
  if (ev->to != want) {
    violate(o, SS_MARGIN_SWITCHING, mode == SS_MODE_STICK ? 0 : fmin(sw, 0), k,
            tau);
    if (mode == SS_MODE_SLIP && want == SS_MODE_OVERSHOOT)
      check_fail(d,
                 "the solution violates (3.2) at the end of slip (phase %d, "
                 "%s): chi(x2-x1) + ur = %.6g must be < 0 (margin %.3g)",
                 k, mode, f + p->ur, -p->ur - f);
    else
      check_fail(d,
                 "phase %d (%s) is followed by the wrong mode: chi(x2-x1) = "
                 "%.9g at its end (margin %.3g)",
                 k, mode, f, o->switching.value);
    return SS_INFEASIBLE;
  }
  return SS_OK;
}

/* Phase k from the simulation's state: its margins, its end by the
 * certified finder, and the mode that follows. */
static int check_phase(const ss_model *m, ss_orbit *o, ss_sim *sim, int k,
                       double t0k, double t_expect, ss_diag *d) {
  const int n = o->n_phases;
  double tau = o->durations[k], xs[4], g_end, g_slope;
  ss_mode mode = o->modes[k], want = k + 1 < n ? o->modes[k + 1] : SS_MODE_SLIP;
  ss_event ev;
  ss_trig ge;
  int rc;
  memcpy(xs, sim->x, sizeof xs);
  phase_margins(m, o, k, mode, want, xs, tau);
  phase_end_slope(m, o, k, mode, want, xs, tau, &ge, &g_end, &g_slope);
  int rises = ss__trig_rises_at(&ge, tau);
  rc = phase_event(o, sim, k, t0k, g_end, rises, t_expect, &ev, d);
  if (rc == SS_GRAZING)
    rc = end_by_slope(m, sim, mode, want, xs, tau, t_expect, &ev, d);
  if (rc || (rc = phase_transversal(o, k, g_end, g_slope, d)))
    return rc;
  return phase_switching(m, o, k, want, &ev, d);
}

/* Back at the start: the closure, and the smallest value margin. */
static void check_close(const ss_model *m, ss_orbit *o, const double x[4]) {
  ss_margin *all[N_VALUE_MARGINS];
  double ze[4];
  value_margins(o, all);
  ss_x_to_z(m, x, ze);
  o->closure = 0;
  for (int i = 0; i < 4; i++)
    o->closure = fmax(o->closure, fabs(ze[i] - o->z0[i]));
  o->min_margin = o->switching;
  for (int i = 0; i < N_VALUE_MARGINS; i++)
    if (all[i]->value < o->min_margin.value)
      o->min_margin = *all[i];
}

int ss_orbit_check(const ss_model *m, ss_orbit *o, ss_diag *d) {
  const int n = o->n_phases;
  ss_sim sim;
  int rc;
  if (n < 2 || n > MAXP)
    return ss__fail(d, SS_EINVAL, "phases", n, "bad phase count");
  check_reset(o);
  if ((rc = check_durations(o, d)))
    return rc;
  ss_z_to_x(m, o->z0, o->x0);
  if (ss__sim_init_mode(&sim, m, 0, o->x0, SS_MODE_SLIP, d))
    return SS_EINVAL;
  double t0k = 0; /* the start of phase k */
  for (int k = 0; k < n; k++) {
    double t_expect = 0; /* its end */
    for (int i = 0; i <= k; i++)
      t_expect += o->durations[i];
    if ((rc = check_phase(m, o, &sim, k, t0k, t_expect, d)))
      return rc;
    t0k = t_expect;
  }
  check_close(m, o, sim.x);
  return SS_OK;
}

int ss_orbit_solve(const ss_model *m, int n, const ss_mode *modes,
                   const double *tau, const ss_stab_opts *opts, ss_orbit *o,
                   ss_diag *d) {
  oeq q;
  double x[MAXP], z0[4] = {0, 0, 0, 0}, resid = INFINITY;
  int iters = 0, rc;
  if (!m || !modes || !tau || !o)
    return ss__fail(d, SS_EINVAL, "orbit", 0, "missing argument");
  if (oeq_init(&q, m, n, modes))
    return ss__fail(d, SS_EINVAL, "modes", n,
                    "a phase sequence starts with slip, ends with stick, has "
                    "at most %d phases and no mode twice in a row",
                    MAXP);
  for (int k = 0; k < n; k++) {
    if (!isfinite(tau[k]) || !(tau[k] > 0))
      return ss__fail(d, SS_EINVAL, "guess", tau[k],
                      "guess duration %d must be finite and > 0", k);
    x[k] = tau[k];
  }
  memset(o, 0, sizeof *o);
  rc = solve_durations(&q, x, z0, &resid, &iters);
  o->n_phases = n;
  memcpy(o->modes, modes, (size_t)n * sizeof *modes);
  memcpy(o->durations, x, (size_t)n * sizeof *x);
  memcpy(o->z0, z0, sizeof z0);
  o->residual = resid;
  o->iterations = iters;
  o->kind = ss_orbit_kind_of(n, modes);
  if (rc)
    return ss__fail(d, rc, "orbit", resid,
                    "the orbit equations did not converge from this guess "
                    "(residual %.3g after %d iterations)",
                    resid, iters);
  ss_z_to_x(m, z0, o->x0);
  if ((rc = ss_orbit_check(m, o, d)))
    return rc;
  ss_stab_opts so = {o->n_turns, opts && opts->difference_check};
  rc = ss_stability(m, n, o->modes, o->durations, o->z0, &so, &o->stab);
  if (rc == SS_ESINGULAR) {
    violate(o, SS_MARGIN_GRAZING, 0, -1, 0);
    return ss__fail(d, SS_INFEASIBLE, "orbit", 0,
                    "a phase of the orbit ends tangentially (grazing)");
  }
  return rc;
}

int ss__is_repetition(int n, const ss_mode *modes, const double *tau,
                      double tol) {
  for (int m = 1; m <= n / 2; m++) {
    if (n % m)
      continue;
    int same = 1;
    for (int k = m; k < n && same; k++)
      same = modes[k] == modes[k % m] && fabs(tau[k] - tau[k % m]) < tol;
    if (same)
      return m;
  }
  return 0;
}
