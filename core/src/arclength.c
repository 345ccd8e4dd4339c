/*
 * arclength.c: pseudo-arclength continuation, the steps that families of
 * orbits (continue.c) and curves of special points (curve.c) share.
 *
 * A curve F(y) = 0 with one more unknown than equations is followed from a
 * point by a step of ds along the unit tangent t, then Newton on
 * [F(y); t.(y - y_pred)] = 0.  The step halves when the corrector fails or
 * the tangent turns by more than about 18 degrees (t.tn < 0.95), grows by
 * half when Newton needs 3 iterations or fewer and shrinks when it needs 6
 * or more.  A range's bound is met by correcting with the bounded unknown
 * held on it instead.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "arclength.h"
#include "internal.h"
#include "linalg.h"

int arc_tangent(const arc_curve *cv, const double *y, const double *prev,
                double *t) {
  int n = cv->ne, np = n + 1, piv[ARC_NMAX];
  double A[ARC_NMAX * ARC_NMAX], F[ARC_NMAX];
  int rc = cv->f(cv->ctx, y, F, A);
  if (rc != SS_OK)
    return rc;
  for (int k = 0; k < np; k++) {
    A[np * n + k] = prev[k];
    t[k] = 0;
  }
  t[n] = 1;
  if (lu_factor(A, np, piv, 1e-14))
    return SS_ESINGULAR;
  lu_solve(A, np, piv, t);
  double s = 0;
  for (int k = 0; k < np; k++)
    s += t[k] * t[k];
  s = sqrt(s);
  if (!(s > 0) || !isfinite(s))
    return SS_ESINGULAR;
  for (int k = 0; k < np; k++)
    t[k] /= s;
  return SS_OK;
}

int arc_correct(const arc_curve *cv, double *y, const double *a,
                const double *base, int *iters, double *res) {
  int n = cv->ne, np = n + 1, piv[ARC_NMAX];
  double A[ARC_NMAX * ARC_NMAX], F[ARC_NMAX], dy_prev = INFINITY;
  for (int it = 1; it <= 12; it++) {
    int rc = cv->f(cv->ctx, y, F, A);
    if (rc != SS_OK)
      return rc;
    double g = 0;
    for (int k = 0; k < np; k++) {
      A[np * n + k] = a[k];
      g += a[k] * (y[k] - base[k]);
    }
    F[n] = g;
    for (int k = 0; k < np; k++)
      F[k] = -F[k];
    if (lu_factor(A, np, piv, 1e-15))
      return SS_ESINGULAR;
    lu_solve(A, np, piv, F);
    double dy = 0, ymax = 1;
    for (int k = 0; k < np; k++) {
      y[k] += F[k];
      dy = fmax(dy, fabs(F[k]));
      ymax = fmax(ymax, fabs(y[k]));
    }
    if (!isfinite(dy) || dy > 1)
      return SS_ENOCONV;
    /* converged, or (an ill-conditioned system) the steps stopped
     * shrinking at the level of rounding */
    int stalled = it >= 4 && dy <= 1e-9 * ymax && dy > 0.5 * dy_prev;
    dy_prev = dy;
    if (dy <= 1e-13 * ymax || stalled) {
      /* the residual at the final iterate */
      if ((rc = cv->f(cv->ctx, y, F, NULL)) != SS_OK)
        return rc;
      double r = 0;
      for (int k = 0; k < n; k++)
        r = fmax(r, fabs(F[k]));
      *iters = it;
      *res = r;
      return r < 1e-9 ? SS_OK : SS_ENOCONV;
    }
  }
  return SS_ENOCONV;
}

/* A very wide range would otherwise make the first step or the difference
 * step leave the parameter's domain. */
double arc_scale(double lo, double hi, double v) {
  double w = hi - lo;
  return v != 0 && w > 10 * fabs(v) ? 10 * fabs(v) : w;
}

void arc_clock_start(arc_clock *k, const ss_cont_opts *o) {
  memset(k, 0, sizeof *k);
  k->t0 = ss__now();
  k->budget = o->max_seconds;
  k->cancelled = o->cancelled;
  k->cancel_cls = o->cancel_cls;
}

int arc_should_stop(arc_clock *k) {
  if (k->stop)
    return 1;
  if (k->cancelled && k->cancelled(k->cancel_cls))
    k->stop = SS_ECANCELED;
  else if (k->budget > 0 && ss__now() - k->t0 > k->budget)
    k->stop = SS_ELIMIT_TIME;
  return k->stop != 0;
}

int arc_walk_start(arc_walk *w, const arc_curve *cv, const double *y0, int i,
                   int dir, double step, double ds_max) {
  double e[ARC_NMAX] = {0};
  memset(w, 0, sizeof *w);
  w->cv = cv;
  w->ds = step;
  w->ds_max = ds_max;
  memcpy(w->y, y0, sizeof w->y[0] * (size_t)(cv->ne + 1));
  e[i] = dir;
  return arc_tangent(cv, w->y, e, w->t);
}

int arc_walk_predict(arc_walk *w) {
  int np = w->cv->ne + 1;
  for (int k = 0; k < np; k++)
    w->yn[k] = w->y[k] + w->ds * w->t[k];
  int rc = arc_correct(w->cv, w->yn, w->t, w->yn, &w->iters, &w->res);
  if (rc == SS_OK)
    rc = arc_tangent(w->cv, w->yn, w->t, w->tn);
  double dot = 0;
  for (int k = 0; rc == SS_OK && k < np; k++)
    dot += w->t[k] * w->tn[k];
  return rc != SS_OK ? rc : dot < 0.95 ? SS_ENOCONV : SS_OK;
}

int arc_walk_onto(arc_walk *w, int i, double q, int with_tangent) {
  double a[ARC_NMAX] = {0}, base[ARC_NMAX];
  memcpy(base, w->yn, sizeof base);
  a[i] = 1;
  base[i] = q;
  memcpy(w->yn, w->y, sizeof w->yn);
  w->yn[i] = base[i];
  int rc = arc_correct(w->cv, w->yn, a, base, &w->iters, &w->res);
  if (rc == SS_OK && with_tangent)
    rc = arc_tangent(w->cv, w->yn, w->t, w->tn);
  if (rc == SS_OK)
    w->yn[i] = base[i]; /* exactly on the bound */
  return rc;
}

int arc_walk_shrink(arc_walk *w) { return (w->ds *= 0.5) < 1e-9; }

void arc_walk_accept(arc_walk *w) {
  memcpy(w->y, w->yn, sizeof w->y);
  memcpy(w->t, w->tn, sizeof w->t);
  if (w->iters <= 3)
    w->ds = fmin(w->ds * 1.5, w->ds_max);
  else if (w->iters >= 6)
    w->ds *= 0.6;
}

int arc_push(arc_list *l, const void *p) {
  if (l->n == l->cap) {
    int nc = l->cap ? 2 * l->cap : 64;
    void *w = realloc(l->v, (size_t)nc * l->size);
    if (!w)
      return SS_ENOMEM;
    l->v = w;
    l->cap = nc;
  }
  memcpy((char *)l->v + (size_t)l->n++ * l->size, p, l->size);
  return SS_OK;
}

int arc_leg_status(ss_diag *d, int leg_rc, double budget,
                   const char *cancelled) {
  if (leg_rc == SS_OK)
    return SS_OK;
  if (leg_rc == SS_ENOMEM)
    return ss__fail(d, SS_ENOMEM, "points", 0, "out of memory");
  return ss__fail(d, leg_rc, "max_seconds", budget, "%s",
                  leg_rc == SS_ECANCELED ? cancelled
                                         : "the time budget ran out");
}

int arc_both_ways(arc_leg_fn *leg, void *ctx, const void *first, size_t size,
                  int max_points, int direction, int note_unwalked,
                  void **points, int *n_points, int *start, char end[2][320],
                  int *leg_rc) {
  arc_list down = {NULL, 0, 0, size}, up = {NULL, 0, 0, size};
  int budget_down = direction == 0 ? (max_points - 1) / 2 : 0;
  int budget_up = max_points - 1 - budget_down;
  if (direction == -1) {
    budget_down = max_points - 1;
    budget_up = 0;
  }
  int rc_down = SS_OK, rc_up = SS_OK;
  if (budget_down > 0)
    rc_down = leg(ctx, -1, budget_down, &down, end[0], sizeof end[0]);
  else if (direction == 0 && note_unwalked)
    snprintf(end[0], sizeof end[0], "max_points (%d) reached", max_points);
  /* going up gets what going down left of the budget */
  if (direction == 0)
    budget_up = max_points - 1 - down.n;
  if (budget_up > 0 && rc_down != SS_ENOMEM)
    rc_up = leg(ctx, +1, budget_up, &up, end[1], sizeof end[1]);
  else if (direction != -1 && note_unwalked)
    snprintf(end[1], sizeof end[1], "max_points (%d) reached", max_points);
  *leg_rc = rc_down != SS_OK ? rc_down : rc_up;
  int n = down.n + up.n + 1;
  char *v = malloc((size_t)n * size);
  if (v) {
    for (int k = 0; k < down.n; k++)
      memcpy(v + (size_t)k * size,
             (char *)down.v + (size_t)(down.n - 1 - k) * size, size);
    memcpy(v + (size_t)down.n * size, first, size);
    if (up.n)
      memcpy(v + (size_t)(down.n + 1) * size, up.v, (size_t)up.n * size);
    *points = v;
    *n_points = n;
    *start = down.n;
  }
  free(down.v);
  free(up.v);
  return v ? SS_OK : SS_ENOMEM;
}
