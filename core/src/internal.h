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

/* The switching function that ends a phase of @a mode followed by @a next:
 * a stick's side is the next mode's (+ur into slip, -ur into overshoot). */
void ss__end_switching(const ss_model *m, ss_mode mode, ss_mode next,
                       const double x[4], ss_trig *g);

/* The motion in @a mode from the anchor state x, coordinate by coordinate
 * (x1, x2, x1', x2'), as functions of local time: free oscillations are two
 * modal terms about their equilibrium, the stick is a line plus one term
 * (x1, x1') or a line (x2, x2').  They are the closed forms of ss_flow(),
 * written so that their derivatives and bounds on them come for free. */
void ss__coords(const ss_model *m, ss_mode mode, const double x[4],
                ss_trig g[4]);

/* Error-free sum of two doubles (Knuth's TwoSum). */
static inline void ss__two_sum(double a, double b, double *s, double *e) {
  double x = a + b;
  double bv = x - a;
  double av = x - bv;
  *s = x;
  *e = (a - av) + (b - bv);
}

double ss__now(void); /* monotonic seconds */

/* The roots of the period-1 duration equations of slip-stick (n = 2) or
 * slip-overshoot-stick (n = 3) with every duration in (0, dmax], scanned on
 * a grid of step about h (scan.c): the durations of each root that may be
 * an orbit into roots (at most max_roots), their number into *n_roots; of
 * the others, the one closest to the rules of its phases among those that
 * fail at a phase's end, and among those that fail inside a phase, into
 * rejected (*n_rejected of them, 0 to 2).  The Newton starts are added to
 * *newton_starts, the cells examined (at every refinement) to *cells.  The
 * step is widened to keep at most 1000 cells a side;
 * the step used into *step.
 * stop (if not NULL) is polled once per row of the grid: a non-zero answer
 * ends the scan with SS_ECANCELED and what it found so far.
 * SS_OK, SS_EINVAL, SS_ENOMEM or SS_ECANCELED. */
int ss__scan_period1(const ss_model *m, int n, double dmax, double h,
                     double (*roots)[3], int max_roots, int *n_roots,
                     double (*rejected)[3], int *n_rejected, int *newton_starts,
                     long *cells, double *step, int (*stop)(void *),
                     void *stop_cls);

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
 * x1'), solved by interval branch and bound with the Krawczyk test
 * (certify.c).  Each root is proved the only one in a box of its own
 * (out->roots); out->complete when nothing is left undecided.  At most
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

/* Whether the sequence (n phases, durations tau) is a shorter one repeated
 * two or more times, durations equal within @a tol: the same orbit
 * travelled again, not an orbit of longer period.  The length of the
 * shortest such block, or 0. */
int ss__is_repetition(int n, const ss_mode *modes, const double *tau,
                      double tol);

/* Whether orbit b passes through a's start with a's sequence rotated (the
 * same orbit started at another of its stick -> slip points), states within
 * @a tol (search.c). */
int ss__same_orbit(const ss_model *m, const ss_orbit *a, const ss_orbit *b,
                   double tol);

/* The member of @a p (@a ph) that parameter @a id names; NULL for an id out
 * of range (params.c). */
double *ss__param_ref(ss_params *p, ss_param_id id);
double *ss__phys_ref(ss_physical *ph, ss_phys_id id);

/* Whether g(t0) is zero within the event finder's tolerance (returns 1) and
 * the direction g leaves t0 in (*dir = -1 down, +1 up); when g(t0) is not
 * zero, returns 0 and *dir is its sign. */
int ss__trig_at_zero(const ss_trig *g, double t0, int *dir);

/* The certificate of a first-root search, kept to answer the next search of
 * a nearby function at a fraction of the cost (events.c).  A simulation
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

/* Records kept per switching function of a simulation: an orbit of up to
 * this many turns repeats each of its phases within them. */
#define SS__CERT_SLOTS 4

/* A simulation in progress (ss_sim of the header).  The core's own loops
 * keep one on the stack, started with ss__sim_init(_mode), so that no
 * allocation enters them. */
struct ss_sim {
  const ss_model *m;
  ss_mode mode;      /* current mode */
  double t_hi, t_lo; /* absolute time of the anchor, as a sum */
  double x[4];       /* state at the anchor */
  int perpetual;     /* the current slip can never end */
  double t_next;     /* local time of the next event (if have_next) */
  int next_status;   /* SS_OK, SS_GRAZING or SS_HORIZON for t_next */
  int next_sign;     /* stick: +1 next event at +ur, -1 at -ur */
  int have_next;
  double next_horizon; /* local horizon the search for t_next used */
  int full_search;     /* no certificates (ss_sim_opts.full_search) */
  /* stick anchored at a touch of +ur (+1) or -ur (-1): that side's
   * function is at its maximum there, on the surface */
  int touch;
  /* the last searches' certificates: slip, overshoot, stick at +ur, -ur */
  ss__root_cert cert[4][SS__CERT_SLOTS];
};

/* Start @a s at absolute time t0 from x0 in the mode of ss_mode_of_state(),
 * or in @a mode; SS_OK or SS_EINVAL (with the reason in d). */
int ss__sim_init(ss_sim *s, const ss_model *m, double t0, const double x0[4],
                 ss_diag *d);
int ss__sim_init_mode(ss_sim *s, const ss_model *m, double t0,
                      const double x0[4], ss_mode mode, ss_diag *d);

/* A caller's wish to stop a long computation (its time budget spent, its
 * client gone), asked at one tick in SS__POLL_EVERY of the loops it is
 * handed to (a tick is an event): an event costs about a microsecond, so a
 * stop is seen within a millisecond, and the question (a clock read, a
 * flag) costs nothing measurable.  The count of ticks is the poll's own,
 * carried across every simulation it is handed to, so that many short ones
 * ask as often as one long one; once the answer is stop, every tick says
 * so. */
#define SS__POLL_EVERY 256
typedef struct ss__poll {
  int (*stop)(void *cls); /* non-zero: stop now; NULL: never */
  void *cls;
  unsigned ticks;
  int stopped; /* stop has said so */
} ss__poll;

/* One tick of @a p (NULL: never stops): whether to stop now. */
static inline int ss__poll_tick(ss__poll *p) {
  if (p && p->stop && !p->stopped && ++p->ticks % SS__POLL_EVERY == 0)
    p->stopped = p->stop(p->cls) != 0;
  return p && p->stopped;
}

/* The returns to Sigma0 of one motion, one at a time, by one simulation (its
 * event certificates carried from return to return): ss_poincare() for one
 * turn after another without restarting. */
typedef struct ss__returns {
  ss_sim sim;
  double t_last;  /* the last phase's end */
  int np;         /* phases so far */
  ss__poll *poll; /* ticked at each event; NULL after ss__returns_start */
} ss__returns;

/* Start at s = (z1, z1') on Sigma0; SS_OK or SS_EINVAL. */
int ss__returns_start(ss__returns *r, const ss_model *m, const double s[2]);

/* On to the next return, into out = (z1, z1'), spending at most
 * *events_left events (decremented); the phases travelled are appended to
 * modes and durations (room for SS_MAX_PHASES in all) when both are given.
 * SS_OK, SS_ELIMIT_EVENTS, SS_HORIZON, SS_ECANCELED (r->poll said stop), or
 * the simulation's failure. */
int ss__returns_next(ss__returns *r, size_t *events_left, double out[2],
                     ss_mode *modes, double *durations);

/* ss_poincare() polling @a poll (NULL: never) at each event: SS_ECANCELED
 * when it says stop. */
int ss__poincare(const ss_model *m, const double s[2], int turns,
                 size_t max_events, double out[2], ss_mode *modes,
                 double *durations, int *n_phases, ss__poll *poll);

/* ss_attractor_from() polling @a poll (NULL: never) at each event:
 * SS_ECANCELED when it says stop (attractor.c). */
int ss__attractor_from(const ss_model *m, const double s0[2], int max_turns,
                       int max_period, ss__poll *poll, ss_attractor *a);

#endif
