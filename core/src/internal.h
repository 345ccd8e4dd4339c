/*
 * internal.h: helpers shared by the core's source files; not installed.
 */
#ifndef SS_INTERNAL_H
#define SS_INTERNAL_H

#include "stickslip.h"

/* Record the first error into @a d (NULL allowed) and return @a status. */
int ss__fail(ss_diag *d, int status, const char *where, double value,
             const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* Modal amplitudes of the free oscillation about an equilibrium: with
 * zb = the shifted state, q = phiinv zb[0..1], qd = phiinv zb[2..3]. */
void ss__modal(const ss_model *m, const double zb[4], double q[2],
               double qd[2]);

/* The switching function of @a mode from the anchor state x (local time):
 * slip:      g = x2' - V          (must stay < 0)
 * overshoot: g = V - x2'          (must stay < 0)
 * stick:     g = chi(x2-x1) - ur  (sign = +1) or -ur - chi(x2-x1) (sign = -1)
 */
void ss__switching(const ss_model *m, ss_mode mode, int sign, const double x[4],
                   ss_trig *g);

/* Error-free sum of two doubles (Knuth's TwoSum). */
static inline void ss__two_sum(double a, double b, double *s, double *e) {
  double x = a + b;
  double bv = x - a;
  double av = x - bv;
  *s = x;
  *e = (a - av) + (b - bv);
}

double ss__now(void); /* monotonic seconds */

/* Whether g(t0) is zero within the event finder's tolerance (returns 1) and
 * the direction g leaves t0 in (*dir = -1 down, +1 up); when g(t0) is not
 * zero, returns 0 and *dir is its sign. */
int ss__trig_at_zero(const ss_trig *g, double t0, int *dir);

/* The duration equations of orbit.c at tau: the start z0, the residuals F
 * (n) and, if J != NULL, their analytic Jacobian (n x n, row-major).  For
 * the tests.  Returns SS_OK, SS_EINVAL or SS_ESINGULAR. */
int ss__orbit_equations(const ss_model *m, int n, const ss_mode *modes,
                        const double *tau, double z0[4], double *F, double *J);

#endif
