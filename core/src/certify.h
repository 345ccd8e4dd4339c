/*
 * certify.h: the proof that a box holds every root of the period-1
 * equations (certify.c); not installed.
 */
#ifndef SS_CERTIFY_H
#define SS_CERTIFY_H

#include "stickslip.h"

/* A box of the certificate's unknowns (t1, t2, s1, s2): the slip's
 * duration, the stick's (slip-stick) or the overshoot's
 * (slip-overshoot-stick), and the start (s1, s2) = (x1, x1') on Sigma0;
 * [lo[i], hi[i]] for each. */
typedef struct ss__cert_box {
  double lo[4], hi[4];
} ss__cert_box;

/* A root proved: the only one in box, and within at. */
typedef struct ss__cert_root {
  ss__cert_box box, at;
} ss__cert_root;

/* What ss__certify_period1() proved. */
typedef struct ss__certificate {
  /* every part of the box excluded or proved to hold one root (listed),
   * within the budget */
  int complete;
  long boxes; /* boxes tested */
  int n_roots, cap_roots;
  ss__cert_root *roots;   /* malloc'd; ss__certificate_free() */
  int n_undecided;        /* boxes left undecided */
  ss__cert_box undecided; /* the first of them */
  int budget_spent;       /* max_boxes reached */
} ss__certificate;

/* Every root of the period-1 equations of slip-stick (n = 2) or
 * slip-overshoot-stick (n = 3) in the box [lo, hi] of (t1, t2, s1, s2),
 * for slip-overshoot-stick with the stick's duration (which the closure of
 * x2 gives) in [stick_lo, stick_hi]: four equations, x2' = V at the end of
 * each free phase (slip-stick: the closure of x2) and the closure of (x1,
 * x1'), solved by interval branch and bound with the Krawczyk test.  Each
 * root is proved the only one in a box of its own (out->roots);
 * out->complete when nothing is left undecided.  At most
 * max_boxes boxes are tested; stop (if not NULL) is polled every 1024.
 * SS_OK, SS_EINVAL (n, or a box that is empty or not finite), SS_ENOMEM or
 * SS_ECANCELED (out then holds what was proved). */
int ss__certify_period1(const ss_model *m, int n, const double lo[4],
                        const double hi[4], double stick_lo, double stick_hi,
                        long max_boxes, int (*stop)(void *), void *stop_cls,
                        ss__certificate *out);
/* At u = (t1, t2, s1, s2): the four residuals (F may be NULL) and the
 * stick's duration. */
void ss__cert_point(const ss_model *m, int n, const double *u, double *F,
                    double *stick);
void ss__certificate_free(ss__certificate *c);
/* The root r as a point u = (t1, t2, s1, s2), polished by Newton in double
 * precision within the root's box. */
void ss__cert_polish(const ss_model *m, int n, const ss__cert_root *r,
                     double u[4]);
/* The enclosures over the box [lo, hi] of the residuals (Flo, Fhi) and of
 * their Jacobian (row-major), as the proof computes them (for the tests). */
void ss__cert_enclose(const ss_model *m, int n, const double lo[4],
                      const double hi[4], double Flo[4], double Fhi[4],
                      double Jlo[16], double Jhi[16]);

#endif
