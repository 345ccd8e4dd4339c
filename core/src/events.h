/*
 * events.h: the event finder's zero test and its certificates (events.c);
 * not installed.
 */
#ifndef SS_EVENTS_H
#define SS_EVENTS_H

#include "stickslip.h"

/* Whether g(t0) is zero within the event finder's tolerance (returns 1) and
 * the direction g leaves t0 in (*dir = -1 down, +1 up); when g(t0) is not
 * zero, returns 0 and *dir is its sign. */
int ss__trig_at_zero(const ss_trig *g, double t0, int *dir);

/* Whether g rises at t beyond the rounding of its slope: g' as computed
 * exceeds the bound on its evaluation's error, so g' > 0 at t in exact
 * arithmetic. */
int ss__trig_rises_at(const ss_trig *g, double t);

/* The certificate of a first-root search, kept to answer the next search of
 * a nearby function at a fraction of the cost.  A simulation
 * that settles onto a periodic motion searches, period after period, for
 * the first zero of functions that differ from the last by little: with
 * Delta = g_new - g the coefficients' difference,
 *   |Delta(t)| <= D0 + D1 t,   |Delta'(t)| <= D1 + sum_k w_k (|da_k| + |db_k|),
 * and the bounds that certified g < 0 piece by piece (forward from each
 * point a_i and backward from a_{i+1}, with g's own M2) certify g_new < 0
 * where they leave more room than D, and the last bracket, where g rises
 * monotonically through its zero, brackets g_new's first zero alone when
 * its margins exceed D.  Only evaluations of g_new at the zero remain.
 * Where the room is too small the search runs in full and records anew. */
#define SS__CERT_MAX 12
typedef struct ss__root_cert {
  int valid;
  ss_trig g;              /* the function the record certifies */
  double amp, M1, M2, M3; /* sum R_k, and its bounds on |g' - c1|, |g''|,
                           * |g'''| (R_k = hypot(a_k, b_k)) */
  double tol;             /* its evaluation tolerance at the bracket */
  int n; /* points a[0] < ... < a[n-1]; a[n-1] starts the bracket */
  double a[SS__CERT_MAX];
  double gu[SS__CERT_MAX]; /* upper bounds on g(a_i): value + tolerance */
  double g1[SS__CERT_MAX]; /* g'(a_i) */
  double mu[SS__CERT_MAX]; /* max of the bound over [a_i, a_i+1], i >= 1 */
  double hi;               /* the bracket [a[n-1], hi] */
  double root;             /* g's first zero, where g_new's is sought */
  unsigned long hits;      /* searches answered from this record */
} ss__root_cert;

/* ss_trig_first_root from t0 = 0 with certificates: answered from the one
 * of the @a n records @a c nearest g when it covers g, else searched in
 * full and recorded into an empty record or the least near one (a record
 * is left invalid by a search that did not end in a simple zero).  Several
 * records serve a motion whose phases of one mode differ from turn to turn
 * and repeat, as on an orbit of several turns. */
int ss__trig_first_root_cert(const ss_trig *g, double tmax, ss__root_cert *c,
                             int n, double *t);

#endif
