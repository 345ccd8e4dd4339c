/*
 * arclength.h: pseudo-arclength continuation of a curve F(y) = 0, F from
 * R^(ne + 1) to R^ne, shared by the families of one parameter (continue.c)
 * and the curves of special points in two (curve.c).
 */
#ifndef SS_ARCLENGTH_H
#define SS_ARCLENGTH_H

#include <stddef.h>

#include "stickslip.h"

/* The most unknowns of a curve: the durations, an interior time, two
 * parameters. */
#define ARC_NMAX (SS_MAX_PHASES + 3)

/* A curve F(y) = 0: f fills F and, when J is not NULL, dF/dy (ne x (ne + 1),
 * row-major). */
typedef int arc_fn(const void *ctx, const double *y, double *F, double *J);
typedef struct arc_curve {
  arc_fn *f;
  const void *ctx;
  int ne;
} arc_curve;

/* The unit tangent at y, oriented along @a prev: [J; prev^T] t = e_ne. */
int arc_tangent(const arc_curve *cv, const double *y, const double *prev,
                double *t);

/* Newton from @a y (updated in place) on F = 0 and a.(y - base) = 0.
 * Returns SS_OK with the iterations in *iters and the final residual in
 * *res, or a failure. */
int arc_correct(const arc_curve *cv, double *y, const double *a,
                const double *base, int *iters, double *res);

/* The scale of a parameter's unknown: its range's width, but no more than
 * ten times its value. */
double arc_scale(double lo, double hi, double v);

/* When to stop: a time budget and a cancel hook, as in ss_cont_opts. */
typedef struct arc_clock {
  double t0, budget;
  int (*cancelled)(void *);
  void *cancel_cls;
  int stop; /* SS_ELIMIT_TIME or SS_ECANCELED once asked to stop */
} arc_clock;

/* Start the clock of options @a o now. */
void arc_clock_start(arc_clock *k, const ss_cont_opts *o);

/* Whether to stop now (then k->stop says why). */
int arc_should_stop(arc_clock *k);

/* A walk along a curve: the last accepted point y and its tangent t, the
 * candidate yn and its tangent tn, the step ds. */
typedef struct arc_walk {
  const arc_curve *cv;
  double y[ARC_NMAX], t[ARC_NMAX];
  double yn[ARC_NMAX], tn[ARC_NMAX];
  double ds, ds_max;
  int iters;  /* the corrector's iterations for the candidate */
  double res; /* and its residual */
} arc_walk;

/* Start at y0 with the tangent along unknown @a i going @a dir (+1, -1),
 * the first step @a step, the longest @a ds_max.  SS_OK or a failure of
 * the tangent. */
int arc_walk_start(arc_walk *w, const arc_curve *cv, const double *y0, int i,
                   int dir, double step, double ds_max);

/* The candidate: a step of ds along t, corrected on the hyperplane normal
 * to t, with its tangent.  SS_OK, a failure, or SS_ENOCONV when the tangent
 * turns by more than about 18 degrees. */
int arc_walk_predict(arc_walk *w);

/* The candidate again, from y with unknown @a i held at @a q (a range's
 * bound), with its tangent when @a with_tangent (tn is kept otherwise). */
int arc_walk_onto(arc_walk *w, int i, double q, int with_tangent);

/* Halve the step after a failed candidate: 1 when it falls below the
 * smallest step (the walk ends), 0 to try again. */
int arc_walk_shrink(arc_walk *w);

/* Take the candidate, and adapt the step to the corrector's work. */
void arc_walk_accept(arc_walk *w);

/* A growing array of points of @a size bytes each. */
typedef struct arc_list {
  void *v;
  int n, cap;
  size_t size;
} arc_list;

/* Append *p; SS_OK or SS_ENOMEM. */
int arc_push(arc_list *l, const void *p);

/* One way along a curve from its first point: @a dir -1 or +1, at most
 * @a budget points appended to @a pts, why it ended in @a end. */
typedef int arc_leg_fn(void *ctx, int dir, int budget, arc_list *pts, char *end,
                       size_t end_n);

/* The points both ways from the first one: max_points in all, the first
 * included; @a direction 0 both ways (down first, up with what down left),
 * +1 up only, -1 down only; with @a note_unwalked a way that had no points
 * left to walk says "max_points (N) reached".  The points in order along
 * the curve go to *points (malloc'd, @a size bytes each), their number to
 * *n_points and the first's index to *start; end[0] and end[1] say why
 * each way ended.  *leg_rc: the first failure of a way (down first).
 * Returns SS_OK, or SS_ENOMEM when the points could not be put together. */
int arc_both_ways(arc_leg_fn *leg, void *ctx, const void *first, size_t size,
                  int max_points, int direction, int note_unwalked,
                  void **points, int *n_points, int *start, char end[2][320],
                  int *leg_rc);

/* What arc_both_ways' *leg_rc says, into @a d: SS_OK; SS_ENOMEM; or the
 * stop (SS_ELIMIT_TIME, SS_ECANCELED, said with @a cancelled) of a walk
 * whose time budget was @a budget.  Returns @a leg_rc. */
int arc_leg_status(ss_diag *d, int leg_rc, double budget,
                   const char *cancelled);

#endif
