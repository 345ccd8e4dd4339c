/*
 * stickslip.h: the public interface of libstickslip.
 *
 * libstickslip computes the motion of the two-mass oscillator driven by a belt
 * through Coulomb friction of M. Pascal, "New events in stick slip oscillators
 * behaviour", J. Appl. Math. Mech. 75(3), 2011.  Equation numbers such as
 * (2.7) or (5.1) refer to that paper.
 *
 * Whatever this header does not declare is not part of the library's API.
 *
 * The model, in dimensionless time t (equations (1.1), (1.2)):
 *
 *     x1'' + x1 - chi x2 = 0
 *     x2'' + chi eta (x2 - x1) = eta u
 *
 * with belt speed V and friction u: +us while x2' < V ("slip"), -us while
 * x2' > V ("overshoot"), and u = chi (x2 - x1) while x2' = V ("stick"), which
 * holds as long as chi |x2 - x1| <= ur.  0 < chi < 1, eta > 0, 0 < us < ur,
 * V > 0.
 *
 * A state is always the array x[4] = {x1, x2, x1', x2'} in the coordinates of
 * (1.1).  The paper's shifted coordinates z = x - d0 with
 * d0 = (us/(1-chi), us/(chi(1-chi))) are used by the transition matrices and
 * by the orbit functions, and are named z where they appear.
 *
 * Errors.  Every function that can fail returns an int status from the table
 * SS_STATUS_MAP: zero is success, a positive value is information the caller
 * must read (for example SS_GRAZING), a negative value is a failure.  Details
 * go to an optional caller-owned ss_diag; pass NULL when they are not wanted.
 * The library never prints, exits or aborts.  It calls GSL, whose default
 * error handler prints and aborts, and GSL has one handler per process: the
 * first ss_model_init() in the process (every computation starts from a
 * model) therefore turns that handler off, unless the program installed a
 * handler of its own before, which is then left in place and is called for
 * GSL's errors, the library's included.  Once off, GSL's handler stays off
 * for the whole process, for the program's own GSL calls too.  See
 * ss_gsl_quiet().
 *
 * Thread safety.  Every function is reentrant: it touches only its arguments
 * (the one exception is GSL's process-wide handler, set once under
 * pthread_once by the first ss_model_init() or ss_gsl_quiet()).  Objects
 * may be shared read-only between threads; an ss_sim that is advanced
 * belongs to one thread at a time.
 */
#ifndef STICKSLIP_H
#define STICKSLIP_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* SS_API marks what the shared library exports; everything else in it is
 * hidden. */
#if defined(STICKSLIP_BUILDING) && defined(__GNUC__)
#define SS_API __attribute__((visibility("default")))
#else
#define SS_API
#endif

/* The version: the one place it is written.  The build (CMakeLists.txt),
 * the daemon and its OpenAPI document read it from here. */
#define SS_VERSION_MAJOR 0
#define SS_VERSION_MINOR 4
#define SS_VERSION_PATCH 0
#define SS_VERSION_HEX                                                         \
  ((SS_VERSION_MAJOR << 16) | (SS_VERSION_MINOR << 8) | SS_VERSION_PATCH)
#define SS_STR_(x) #x
#define SS_STR(x) SS_STR_(x)
/** "MAJOR.MINOR.PATCH" of this header. */
#define SS_VERSION                                                             \
  SS_STR(SS_VERSION_MAJOR)                                                     \
  "." SS_STR(SS_VERSION_MINOR) "." SS_STR(SS_VERSION_PATCH)

/** The version of the library linked, SS_VERSION of its build: a program
 *  can compare it with the header it was compiled with. */
SS_API const char *ss_version(void);

/* ------------------------------------------------------------------------ */
/* Status codes                                                              */
/* ------------------------------------------------------------------------ */

/*
 * The one table of status codes: name, value, message.  Positive values are
 * information, negative values are failures.
 */
#define SS_STATUS_MAP(X)                                                       \
  X(OK, 0, "success")                                                          \
  X(GRAZING, 1, "trajectory touches a switching surface tangentially")         \
  X(HORIZON, 2, "no event before the horizon")                                 \
  X(NEVER, 3, "the switching function can never reach zero")                   \
  X(INFEASIBLE, 4, "a root of the orbit equations that violates a constraint") \
  X(ABOVE, 5, "the switching function is already positive at the start")       \
  X(EDOMAIN, -1, "parameter outside its domain")                               \
  X(EINVAL, -2, "invalid argument")                                            \
  X(ENOCONV, -3, "iteration did not converge")                                 \
  X(ELIMIT_EVENTS, -4, "event limit reached before the end of the run")        \
  X(ELIMIT_SAMPLES, -5, "sample limit exceeded")                               \
  X(ELIMIT_TIME, -6, "compute time budget exhausted")                          \
  X(ENOMEM, -7, "out of memory")                                               \
  X(ESINGULAR, -8, "singular linear system")                                   \
  X(EBUG, -9, "internal invariant violated")                                   \
  X(ECANCELED, -10, "cancelled by the caller")

enum {
#define SS_STATUS_ENUM(name, value, msg) SS_##name = (value),
  SS_STATUS_MAP(SS_STATUS_ENUM)
#undef SS_STATUS_ENUM
};

/** The message of a status code ("unknown status" for anything else).
 *  @return a static string, never NULL. */
SS_API const char *ss_strerror(int status);
/** The name of a status code without its prefix, e.g. "GRAZING"
 *  ("UNKNOWN" for anything else).  @return a static string, never NULL. */
SS_API const char *ss_status_name(int status);

/**
 * Details of a failure.  The first error recorded wins; later ones are
 * ignored, so the most specific cause survives.
 */
typedef struct ss_diag {
  int status;     /**< the status the failing call returned */
  char where[32]; /**< parameter or phase concerned, e.g. "chi", "stick" */
  double value;   /**< the offending value, when there is one */
  char text[192]; /**< a sentence a person can act on */
} ss_diag;

/** Reset @a d to "no error".  NULL is allowed. */
SS_API void ss_diag_clear(ss_diag *d);

/**
 * Turn GSL's default abort-on-error handler off, once per process: the
 * first call (from here or from ss_model_init(), which every computation
 * starts with) calls gsl_set_error_handler_off(), and if the handler it
 * replaced was one the program had installed (not GSL's default), puts that
 * one back with gsl_set_error_handler().  Later calls do nothing, so a
 * handler the program installs afterwards is never touched.  A program may
 * call it early, for example before starting threads; it need not.
 * Thread-safe (pthread_once).
 */
SS_API void ss_gsl_quiet(void);

/* ------------------------------------------------------------------------ */
/* Parameters                                                                */
/* ------------------------------------------------------------------------ */

/** The dimensionless parameters of (1.1)-(1.2). */
typedef struct ss_params {
  double chi; /**< k2/(k1+k2), 0 < chi < 1 */
  double eta; /**< m1/m2, eta > 0 */
  double us;  /**< dynamic friction level Fs/(k1+k2), 0 < us < ur */
  double ur;  /**< static friction level Fr/(k1+k2) */
  double V;   /**< belt speed v0/omega, V > 0 */
} ss_params;

/** Parameters in physical units (any consistent unit system). */
typedef struct ss_physical {
  double m1, m2; /**< masses, > 0 */
  double k1, k2; /**< spring stiffnesses, > 0 */
  double Fs, Fr; /**< dynamic and static friction forces, 0 < Fs < Fr */
  double v0;     /**< belt speed, > 0 */
} ss_physical;

/**
 * Check @a p: every value finite, 0 < chi < 1, eta > 0, 0 < us < ur, V > 0.
 * @param d  details of a failure, may be NULL
 * @return SS_OK; SS_EDOMAIN, with the parameter named in @a d->where and
 *         the reason in @a d->text; SS_EINVAL (@a p NULL).
 */
SS_API int ss_params_check(const ss_params *p, ss_diag *d);

/**
 * Convert physical parameters to dimensionless ones:
 * omega = sqrt((k1+k2)/m1), chi = k2/(k1+k2), eta = m1/m2,
 * us = Fs/(k1+k2), ur = Fr/(k1+k2), V = v0/omega.
 * Dimensionless time is t = omega * (physical time); displacements keep their
 * unit; a velocity v in the model is v*omega in physical units.
 * @param ph         the physical parameters
 * @param[out] p      the dimensionless parameters, checked
 * @param[out] omega  the time scale (1/s when the inputs are SI), may be NULL
 * @param d           details of a failure, may be NULL
 * @return SS_OK; SS_EDOMAIN (naming the physical field in @a d->where);
 *         SS_EINVAL (@a ph NULL).
 */
SS_API int ss_params_from_physical(const ss_physical *ph, ss_params *p,
                                   double *omega, ss_diag *d);

/**
 * Convert a dimensionless state x (positions, velocities) and time t back to
 * physical units with the time scale @a omega: t/omega, x, x'*omega.
 * Either of @a t_out and @a x_out may be NULL.
 */
SS_API void ss_to_physical(double omega, double t, const double x[4],
                           double *t_out, double x_out[4]);

/** The inverse of ss_to_physical(). */
SS_API void ss_from_physical(double omega, double t_phys,
                             const double x_phys[4], double *t_out,
                             double x_out[4]);

/* ------------------------------------------------------------------------ */
/* Model: modal decomposition and closed-form flows                          */
/* ------------------------------------------------------------------------ */

/** The three modes of motion of the mass on the belt. */
typedef enum ss_mode {
  SS_MODE_SLIP = 0,      /**< x2' < V, u = +us */
  SS_MODE_OVERSHOOT = 1, /**< x2' > V, u = -us */
  SS_MODE_STICK = 2      /**< x2' = V, u = chi (x2 - x1), |u| <= ur */
} ss_mode;

/** "slip", "overshoot", "stick"; NULL for anything else. */
SS_API const char *ss_mode_name(ss_mode m);

/**
 * The parameters with everything derived from them once: the eigenvalues
 * lam of K = [[1, -chi], [-chi eta, chi eta]] (the squared modal
 * frequencies, lam[0] < lam[1]), the mode shapes phi (columns) and their
 * inverse, and d0.  Caller-allocated; fill it with ss_model_init().
 */
typedef struct ss_model {
  ss_params p;         /**< the parameters, as checked */
  double lam[2];       /**< eigenvalues of K, ascending */
  double w[2];         /**< modal frequencies sqrt(lam) */
  double phi[2][2];    /**< z = phi q: column k is the k-th mode shape */
  double phiinv[2][2]; /**< q = phiinv z */
  double d0[2];        /**< static deflection under +us: K d0 = (0, eta us) */
} ss_model;

/**
 * Check @a p and derive the modal data.  The first call in the process
 * also runs ss_gsl_quiet().
 * @param[out] m  the model, filled on success
 * @param p       the parameters (ss_params_check())
 * @param d       details of a failure, may be NULL
 * @return SS_OK; SS_EDOMAIN (also for parameters too extreme together for
 *         doubles); SS_EINVAL (@a p NULL).  Thread-safe; allocates nothing.
 */
SS_API int ss_model_init(ss_model *m, const ss_params *p, ss_diag *d);

/**
 * The friction force needed to hold the stick, chi (x2 - x1), of a state.
 */
SS_API double ss_stick_force(const ss_model *m, const double x[4]);

/**
 * The mode a state starts in.  The rule, which also decides every transition
 * at the end of a slip or overshoot phase:
 *
 * - x2' < V: slip; x2' > V: overshoot (an x2' within 4 DBL_EPSILON V of V
 *   is taken as V);
 * - x2' = V and chi |x2 - x1| < ur: stick;
 * - x2' = V and chi (x2 - x1) > ur: slip; < -ur: overshoot;
 * - x2' = V and chi |x2 - x1| = ur (the threshold, within the event
 *   finder's tolerance, 16 DBL_EPSILON of the force's scale): the static
 *   friction can still hold (the stick set is closed), so the state sticks if
 *   the stick force moves back inside (its first non-zero derivative under
 *   the stick motion points inward, or all vanish) and slips to the side
 *   of the threshold otherwise.  A stick is therefore never of zero length.
 */
SS_API ss_mode ss_mode_of_state(const ss_model *m, const double x[4]);

/**
 * The state after time @a t >= 0 of the motion in mode @a mode from @a x0,
 * by the closed form (no integration).  In stick, x0[3] is taken to be V.
 * @a x0 and @a x may alias.
 */
SS_API void ss_flow(const ss_model *m, ss_mode mode, double t,
                    const double x0[4], double x[4]);

/**
 * The affine transition of mode @a mode over time @a t in the coordinates
 * z = x - (d0, 0):  Z(t) = A(t) Z0 + c(t), row-major 4x4 A.
 *
 *   slip:      A = H(t),      c = 0          (2.1)
 *   overshoot: A = H(t),      c = 2 L(t) d0  (2.4)
 *   stick:     A = Gamma(t),  c = 0          (2.6), valid when z2'(0) = V
 *
 * @param[out] A, c    the map; either may be NULL
 * @param[out] dA, dc  their time derivatives; either may be NULL
 */
SS_API void ss_transition(const ss_model *m, ss_mode mode, double t,
                          double A[16], double c[4], double dA[16],
                          double dc[4]);

/** The paper's coordinates z = x - (d0, 0).  @a x and @a z may alias. */
SS_API void ss_x_to_z(const ss_model *m, const double x[4], double z[4]);
/** x = z + (d0, 0).  @a x and @a z may alias. */
SS_API void ss_z_to_x(const ss_model *m, const double z[4], double x[4]);

/* ------------------------------------------------------------------------ */
/* Certified event location                                                  */
/* ------------------------------------------------------------------------ */

/** The most sinusoidal terms an ss_trig holds. */
#define SS_TRIG_MAX 3

/**
 * A switching function of the form
 *
 *     g(t) = c0 + c1 t + sum_{k<n} (a[k] cos(w[k] t) + b[k] sin(w[k] t))
 *
 * with n <= SS_TRIG_MAX and w[k] > 0.  Every switching function of the model
 * has this form: x2' - V in slip and overshoot (two modal terms), and
 * chi (x2 - x1) -+ ur in stick (a line plus one term).
 */
typedef struct ss_trig {
  double c0, c1;         /**< the line c0 + c1 t */
  int n;                 /**< number of sinusoidal terms, 0..SS_TRIG_MAX */
  double a[SS_TRIG_MAX]; /**< cosine amplitudes */
  double b[SS_TRIG_MAX]; /**< sine amplitudes */
  double w[SS_TRIG_MAX]; /**< angular frequencies, > 0 */
} ss_trig;

/** g(t) and its first @a order derivatives into out[0..order], 0 <= order
 *  <= 3.  Thread-safe; allocates nothing. */
SS_API void ss_trig_eval(const ss_trig *g, double t, int order, double *out);

/**
 * The first zero of @a g after @a t0, for a g that is negative just after t0.
 *
 * Method.  From a point a with g(a) < 0, the bound
 *   g(a+h) <= g(a) + g'(a) h + g''(a) h^2/2 + M3 h^3/6,
 *   M3 = sum_k sqrt(a_k^2 + b_k^2) w_k^3,
 * (and its second-order counterpart with M2) gives the largest step over
 * which g provably stays negative, so no root is stepped over, however close
 * two roots are.  The steps converge quadratically to a simple root, which is
 * then polished by a safeguarded Newton iteration.
 *
 * Tolerance.  |g| <= tol with tol = 16 DBL_EPSILON * scale, scale =
 * |c0| + |c1 t| + sum_k sqrt(a_k^2 + b_k^2), counts as zero: below it the
 * sign of a computed g is not reliable.  A zero at which g does not rise
 * above tol (a local maximum within tol of zero) is a tangency: the function
 * returns SS_GRAZING with @a *t at the maximum.  A maximum of g below -tol is
 * a near miss and is passed over.
 *
 * Start.  If g(t0) is within tol of zero, the direction in which g leaves
 * t0 decides: if it leaves downward (first non-negligible derivative
 * negative) the search starts just after t0; if it rises, t0 itself is the
 * root (SS_OK, *t = t0).
 *
 * @param tmax     search horizon, > t0
 * @param[out] t   the root or tangency; tmax on SS_HORIZON; INFINITY on
 *                 SS_NEVER; the last point reached on SS_ENOCONV
 * @return SS_OK (crossing), SS_GRAZING (tangency), SS_HORIZON (g < 0 on
 *         (t0, tmax]), SS_NEVER (c1 <= 0 and c0 + c1 t0 + sum |terms| <
 *         -tol: g can never reach zero), SS_ENOCONV (no root located in
 *         2e6 steps of the bracket search), SS_ABOVE (g is positive at t0
 *         beyond tol: there is no first crossing from below), SS_EINVAL
 *         (bad arguments: NULL, n outside 0..SS_TRIG_MAX, t0 not finite,
 *         tmax not above t0, a coefficient or frequency not finite).
 *         Thread-safe; allocates nothing.
 */
SS_API int ss_trig_first_root(const ss_trig *g, double t0, double tmax,
                              double *t);

/* ------------------------------------------------------------------------ */
/* Event-driven simulation                                                   */
/* ------------------------------------------------------------------------ */

/** What kind of event. */
typedef enum ss_event_kind {
  SS_EVENT_TRANSITION = 0, /**< the mode changes */
  SS_EVENT_GRAZING = 1     /**< a tangency with a switching surface */
} ss_event_kind;

/** One event: the switching time, the modes before and after, the state. */
typedef struct ss_event {
  double t;           /**< absolute time of the event */
  ss_mode from, to;   /**< from == to for a grazing that changes nothing */
  ss_event_kind kind; /**< a mode change or a tangency */
  double x[4];        /**< state at the event */
} ss_event;

/**
 * An event-driven simulation in progress (opaque).  The state is re-anchored
 * at every event, so within a phase it is the closed form from the last
 * event: a long run keeps machine precision.  Absolute time is kept as an
 * unevaluated sum of two doubles, so that event times stay accurate after
 * 10^6 events.  The model must outlive it.  Its functions change it (all
 * but ss_sim_mode(), ss_sim_time() and ss_sim_state_at()), so a simulation
 * belongs to one thread at a time.
 */
typedef struct ss_sim ss_sim;

/**
 * Start a simulation at absolute time @a t0 from @a x0; the mode follows
 * ss_mode_of_state().
 * @param m   the model; it must outlive the simulation
 * @param t0  the start time, finite
 * @param x0  the start state, four finite numbers
 * @param d   details of a failure, may be NULL
 * @return the simulation (release with ss_sim_free()), or NULL with the
 *         reason in @a d: SS_EINVAL (a NULL or non-finite input) or
 *         SS_ENOMEM.
 */
SS_API ss_sim *ss_sim_new(const ss_model *m, double t0, const double x0[4],
                          ss_diag *d);

/**
 * Start in a given @a mode (for example stick at the threshold).  The state
 * must be consistent with it: x2' = V for stick (forced exactly), x2' <= V
 * for slip, x2' >= V for overshoot (within 4 DBL_EPSILON V).
 * @return the simulation, or NULL as ss_sim_new(); a state inconsistent with
 *         @a mode, or an unknown mode, is SS_EINVAL.
 */
SS_API ss_sim *ss_sim_new_mode(const ss_model *m, double t0, const double x0[4],
                               ss_mode mode, ss_diag *d);

/** Release a simulation.  NULL-safe. */
SS_API void ss_sim_free(ss_sim *s);

/** The current mode: the mode the motion is in after the anchor. */
SS_API ss_mode ss_sim_mode(const ss_sim *s);

/** Current absolute time of the anchor (the last event or the start). */
SS_API double ss_sim_time(const ss_sim *s);

/**
 * Advance to the next event if it comes no later than absolute time
 * @a t_stop; fill @a ev and re-anchor there.
 * @param ev  the event, may be NULL
 * @return SS_OK (an event, in @a ev; ev->kind says whether it is a grazing),
 *         SS_HORIZON (no event up to t_stop, or none ever: a perpetual slip;
 *         nothing changes), or a failure of the event search (SS_EINVAL
 *         for a state that contradicts its mode).
 */
SS_API int ss_sim_next_event(ss_sim *s, double t_stop, ss_event *ev);

/**
 * The state at absolute time @a t, which must lie between the anchor and
 * the next event: anchor time + local time, from the closed form.
 * @param[out] x  the state
 */
SS_API void ss_sim_state_at(const ss_sim *s, double t, double x[4]);

/** Move the anchor forward to absolute time @a t, which must come before
 *  the next event (ss_sim_next_event() with t_stop = t said SS_HORIZON);
 *  a @a t not after the anchor changes nothing. */
SS_API void ss_sim_advance(ss_sim *s, double t);

/** What a simulation request asks for; zero-initialise, then set. */
typedef struct ss_sim_opts {
  double t0;         /**< start time (usually 0) */
  double t_end;      /**< stop at this absolute time, > t0 */
  size_t stop_after; /**< if > 0: stop at the stop_after-th event */
  int record_events; /**< store the events in the result */
  size_t n_samples;  /**< evenly spaced samples over [sample_from, sample_to] */
  double sample_from; /**< first sample time, t0 <= sample_from */
  double sample_to;   /**< last sample time, sample_to <= t_end */
  /** Or explicit sample times in [t0, t_end], ascending (not both). */
  const double *sample_times;
  size_t n_sample_times; /**< how many sample_times */
  /**
   * Or, when > 0, samples placed for a curve: over [sample_from, sample_to],
   * as few as the bound below allows, so that the polyline through them
   * lies within sample_tolerance of the true curve in the coordinates of
   * sample_axes, each divided by its sample_scale.  Every event inside the
   * window is sampled twice, at the same time: with the mode before and
   * with the mode after (a corner of the curve is a vertex of the polyline,
   * and the polyline splits by mode there).  A stick's straight x2 and x2'
   * cost its two ends.
   *
   * The bound, in the scaled coordinates: on a step h from local time u,
   * at t_j = u + j h/4 (j = 0..4), the curve minus its chord at the same
   * time, f, is at most max_j |f(t_j)| + (h/4)^2/8 max|c''|, and
   * max|c''| <= max_j |c''(t_j)| + (h/8)|b3|, b3 = sum_k R_k w_k^3 from
   * the closed form's terms (amplitude R_k, frequency w_k); where the curve
   * moves forward along the chord all the way (the same kind of bound on
   * c'), the same holds for the part of c - c(u) across the chord with the
   * part of c'' across it.  The distance to the polyline is at most either,
   * so the smaller must be <= sample_tolerance (up to rounding: about 1e-15
   * of the coordinates, and the curve's speed times the rounding of the
   * samples' absolute times).  Each step is about the longest that allows.
   * A tolerance near the coordinates' rounding needs steps near the times'
   * rounding: set max_samples (the API always does).
   * The count is limited by max_samples (SS_ELIMIT_SAMPLES beyond it).
   */
  double sample_tolerance;
  /** The coordinates of sample_tolerance's distance: bit 1 x1, 2 x2, 4 x1',
   *  8 x2' (0: all four). */
  unsigned sample_axes;
  /** Divides each coordinate's difference (x1, x2, x1', x2'; 0: 1). */
  double sample_scale[4];
  /** Start in start_mode (as ss_sim_new_mode(), the state consistent with
   *  it) instead of the mode of ss_mode_of_state(): for an orbit from its
   *  stick -> slip point, which at the threshold may read as a stick. */
  int start_in_mode;
  ss_mode start_mode; /**< with start_in_mode */
  /** Search every event from scratch.  By default a search whose switching
   *  function is near one of the last searches' of its mode is answered
   *  from that search's certificate (the same answer at a fraction of the
   *  cost, see the README's "What a period costs"); this turns that off,
   *  for checking and for comparison. */
  int full_search;
  /** Limit: more events than this is SS_ELIMIT_EVENTS (0: none). */
  size_t max_events;
  size_t max_samples; /**< limit on samples (0: none) */
  double max_seconds; /**< CPU/wall budget in seconds (0: none) */
  /** Polled where the time budget is (every 256 events): a non-zero answer
   *  stops the run with SS_ECANCELED.  NULL: never.  It may be called from
   *  the computing thread only; make it cheap and thread-safe. */
  int (*cancelled)(void *cls);
  void *cancel_cls; /**< its argument */
} ss_sim_opts;

/** The result of ss_simulate(); release with ss_sim_result_free(). */
typedef struct ss_sim_result {
  double t;             /**< final time */
  ss_mode mode;         /**< final mode */
  double x[4];          /**< final state */
  size_t n_events;      /**< events that happened */
  size_t n_grazing;     /**< of which tangencies */
  ss_event *events;     /**< the events if record_events, else NULL */
  size_t n_samples;     /**< samples taken (fewer than asked if stopped) */
  double *st;           /**< sample times */
  double *sx;           /**< samples, 4 per time: x1, x2, x1', x2' */
  unsigned char *smode; /**< mode at each sample */
  int perpetual;        /**< ended in a slip that can never end */
} ss_sim_result;

/**
 * Simulate from @a x0 (mode by ss_mode_of_state()) under @a o.
 * Samples cost only when asked for; with no samples and record_events = 0,
 * nothing is allocated.
 * @param[out] r  the result; release it with ss_sim_result_free() whatever
 *                the status
 * @param d       details of a failure, may be NULL
 * @return SS_OK; or SS_ELIMIT_EVENTS, SS_ELIMIT_TIME, SS_ECANCELED when a
 *         limit or the caller stops the run (the result then holds the
 *         state reached, but the run is not complete); SS_ELIMIT_SAMPLES
 *         (too many samples asked for); SS_EINVAL; SS_ENOMEM.  Thread-safe
 *         (the cancel hook aside).
 */
SS_API int ss_simulate(const ss_model *m, const double x0[4],
                       const ss_sim_opts *o, ss_sim_result *r, ss_diag *d);

/** Release what ss_simulate() allocated.  NULL-safe; zeroes @a r. */
SS_API void ss_sim_result_free(ss_sim_result *r);

/* ------------------------------------------------------------------------ */
/* Periodic orbits and their stability                                       */
/* ------------------------------------------------------------------------ */

/*
 * An orbit is described from its stick -> slip point, on the section Sigma0
 * of (4.2): x2' = V and chi (x2 - x1) = ur.  A point of Sigma0 is given by
 * the two coordinates s = (z1, z1'); z2 = z1 + (ur - us)/chi, z2' = V.
 * Its phases are a sequence of modes starting with slip and ending with a
 * stick that ends at +ur (back on Sigma0).
 */

/** The most phases an orbit, a guess or a travelled sequence holds. */
#define SS_MAX_PHASES 32

/** Orbit kinds; the values are bits of a mask (ss_orbit_opts.kinds). */
typedef enum ss_orbit_kind {
  SS_ORBIT_OVERSHOOT = 1, /**< slip, overshoot, stick (section 3) */
  SS_ORBIT_STICKSLIP = 2, /**< slip, stick */
  SS_ORBIT_OTHER = 4,     /**< any other sequence, or period k > 1 */
  SS_ORBIT_ALL = 7        /**< the mask of all three */
} ss_orbit_kind;

/** "overshoot", "stick-slip", "other"; NULL for anything else. */
SS_API const char *ss_orbit_kind_name(ss_orbit_kind k);

/** The kind of a phase sequence (OVERSHOOT, STICKSLIP or OTHER). */
SS_API ss_orbit_kind ss_orbit_kind_of(int n, const ss_mode *modes);

/** How the search found an orbit. */
typedef enum ss_orbit_source {
  SS_SOURCE_GUESS = 0, /**< from the caller's guess */
  /** from a simulation: the orbit it settled on (an attractor), or Newton
   *  from a close return of one that did not settle (of any stability) */
  SS_SOURCE_SIMULATION = 1,
  SS_SOURCE_DURATION_GRID = 2, /**< Newton on the durations from a grid */
  SS_SOURCE_MAP_NEWTON = 3,    /**< Newton on the Poincare map P^k */
  SS_SOURCE_CERTIFICATE = 4    /**< a root the certificate proved (one the
                                    other sources missed) */
} ss_orbit_source;

/** "guess", "simulation", "duration-grid", "poincare-newton",
 *  "certificate"; NULL for anything else. */
SS_API const char *ss_orbit_source_name(ss_orbit_source s);

/** Options of ss_stability() and ss_orbit_solve(); zero-initialise for the
 *  defaults (or pass NULL). */
typedef struct ss_stab_opts {
  /** Returns to Sigma0 per period; 0: counted from the modes (a stick
   *  followed by slip, or the last phase).  ss_orbit_solve() always counts,
   *  by its orbit check. */
  int turns;
  /** Also the central-difference Jacobian of ss_poincare(), as a
   *  cross-check of the analytic one (ss_stab.jac_fd, .jac_diff). */
  int difference_check;
} ss_stab_opts;

/** The feasibility conditions of an orbit (section 5), by which its margins
 *  and the condition it violates are named.  The first six are the margins
 *  of ss_orbit; the others are conditions a rejected root can fail. */
typedef enum ss_margin_id {
  SS_MARGIN_NONE = 0,                 /**< "": none (a feasible orbit) */
  SS_MARGIN_SLIP_BELOW_V = 1,         /**< "slip_below_V" */
  SS_MARGIN_OVERSHOOT_ABOVE_V = 2,    /**< "overshoot_above_V" */
  SS_MARGIN_STICK_BELOW_UR = 3,       /**< "stick_below_ur" */
  SS_MARGIN_STICK_ABOVE_MINUS_UR = 4, /**< "stick_above_minus_ur" */
  SS_MARGIN_SWITCHING = 5, /**< "switching": the mode rule at a phase end */
  SS_MARGIN_TRANSVERSALITY = 6, /**< "transversality": a phase end's slope */
  SS_MARGIN_DURATION = 7,       /**< "duration": a duration not > 0 */
  SS_MARGIN_PHASE_END = 8,      /**< "phase_end": the phase does not end */
  SS_MARGIN_GRAZING = 9,        /**< "grazing": a touch of a surface */
  SS_MARGIN_ENDS_EARLY = 10     /**< "ends_early": a crossing before the end */
} ss_margin_id;

/** The name of a margin or condition, as listed in ss_margin_id ("" for
 *  SS_MARGIN_NONE); NULL for anything else. */
SS_API const char *ss_margin_name(ss_margin_id id);

/** How far a constraint is from being violated, and where. */
typedef struct ss_margin {
  double value; /**< >= 0 when satisfied; INFINITY when it never binds */
  int phase;    /**< index of the phase it is measured in (-1: none) */
  double t;     /**< local time in that phase */
} ss_margin;

/** The stability of an orbit: the Poincare map on Sigma0 in (z1, z1'). */
typedef struct ss_stab {
  double jac[2][2];    /**< analytic Jacobian (section 4, derived anew) */
  double jac_fd[2][2]; /**< central differences of the map by simulation */
  double jac_diff;     /**< max |jac - jac_fd|; NAN if jac_fd not computed */
  double eig_re[2]; /**< eigenvalues of jac, real parts, larger modulus first */
  double eig_im[2]; /**< and imaginary parts */
  double spectral_radius; /**< the largest |eigenvalue| */
  int stable; /**< spectral radius < 1 (stable in the paper's sense, sec. 4) */
  /** 1 - spectral_radius: the distance of the largest multiplier to the
   *  unit circle, positive inside */
  double unit_margin;
  /** |unit_margin| <= SS_MARGINAL_TOL: the verdict `stable` is within the
   *  accuracy of the Jacobian and may go either way */
  int marginal;
} ss_stab;

/** A multiplier within this distance of the unit circle makes the stability
 *  verdict marginal.  The analytic Jacobian agrees with central differences
 *  of the simulated map to 2e-10 .. 1.3e-8 in the tests (the differences'
 *  own truncation error); a simple eigenvalue moves by about the Jacobian's
 *  error, so 1e-6 keeps a factor of 75 or more; a double one moves by its
 *  square root, and a verdict within 1e-6 of the circle there is marginal
 *  however the Jacobian was obtained. */
#define SS_MARGINAL_TOL 1e-6

/** A periodic orbit. */
typedef struct ss_orbit {
  ss_orbit_kind kind;              /**< the kind of its phase sequence */
  int n_phases;                    /**< phases per period, 2..SS_MAX_PHASES */
  ss_mode modes[SS_MAX_PHASES];    /**< the sequence: slip first, stick last */
  double durations[SS_MAX_PHASES]; /**< the duration of each phase */
  double period;                   /**< the sum of the durations */
  int n_turns;  /**< passes through Sigma0 per period (period-k: k) */
  double z0[4]; /**< start (stick -> slip point) in z = x - (d0, 0) */
  double x0[4]; /**< the same in x */
  /* Margins of the constraints of section 5, from the certified finder: */
  ss_margin slip_below; /**< slip: min of V - x2' at interior maxima */
  ss_margin over_above; /**< overshoot: min of x2' - V at interior minima */
  /** stick: min of ur - chi(x2-x1) at interior maxima */
  ss_margin stick_upper;
  ss_margin stick_lower;  /**< stick: min of ur + chi(x2-x1) over the phase */
  ss_margin switching;    /**< at phase ends: how far the mode rule holds,
                               e.g. -ur - chi(x2-x1) for (3.2) */
  ss_margin transversal;  /**< min slope of the switching function at the
                               phase ends (0 would be grazing) */
  ss_margin min_margin;   /**< the smallest of the value margins above */
  double residual;        /**< max |F| of the orbit equations at the root */
  double closure;         /**< max |P^k(s) - s| by simulation */
  ss_stab stab;           /**< its stability */
  int iterations;         /**< Newton iterations of the final solve */
  ss_orbit_source source; /**< how the search found it */
  /** When ss_orbit_check() rejects it: the condition that fails
   *  (violation_id: SS_MARGIN_DURATION, _PHASE_END, _GRAZING, _ENDS_EARLY,
   *  _TRANSVERSALITY, _SWITCHING), its margin (< 0: how far it fails; 0 for a
   * grazing), the phase and the time in it.  The margins above then cover the
   * phases up to that one.  violation_id is SS_MARGIN_NONE for a feasible
   * orbit. */
  ss_margin violation;
  ss_margin_id violation_id;
} ss_orbit;

/** Options of ss_orbit_find(); zero-initialise for the defaults. */
typedef struct ss_orbit_opts {
  unsigned kinds; /**< mask of ss_orbit_kind; 0 means all (a guess's orbit
                       is returned whatever its kind) */
  int n_guess;    /**< > 0: start from this guess only (<= SS_MAX_PHASES) */
  /** The guess's sequence.  One that does not start with slip and end with
   *  stick stands for slip, overshoot, stick (3 phases) or slip, stick (2). */
  ss_mode guess_modes[SS_MAX_PHASES];
  double guess[SS_MAX_PHASES]; /**< its durations, finite and > 0 */
  int max_period; /**< largest k for period-k orbits, 1..8 (0: 4) */
  int effort;     /**< 1 coarse, 2 default (also 0), 3 fine search */
  /** Cross-check every returned orbit's Jacobian by central differences of
   *  the Poincare map (ss_stab_opts.difference_check). */
  int difference_check;
  double max_seconds; /**< time budget (0: none) */
  /** Polled where the time budget is (between candidate solves): a non-zero
   *  answer stops the search with SS_ECANCELED.  NULL: never. */
  int (*cancelled)(void *cls);
  void *cancel_cls; /**< its argument */
  /** 1: prove that the slip-stick and slip-overshoot-stick period-1 orbits
   *  returned are all there are in a box of durations and start states
   *  (ss_orbit_report.cert); an orbit the proof finds and the search missed
   *  is added.  Costly: seconds per family (see the README). */
  int certify;
  /** The proof's budget per family, in seconds (0: 10); past it the family
   *  is said not complete. */
  double certify_seconds;
} ss_orbit_opts;

/** What the certificate of one period-1 family proved
 *  (ss_orbit_opts.certify).  The box: the slip's duration in
 *  [duration_lo[0], duration_hi[0]], each other phase's in [0,
 *  duration_hi[k]], and the start on Sigma0 with x1 in [x1_lo, x1_hi] and
 *  x1' in [v1_lo, v1_hi].  Interval branch and bound with the Krawczyk
 *  test proves each root of the family's duration equations there unique in
 *  a box of its own and excludes the rest; each root is then an orbit
 *  (returned) or not (ss_orbit_check() fails, or a duration is not
 *  positive). */
typedef struct ss_family_cert {
  int ran;      /**< 1: the proof was attempted for this family */
  int complete; /**< 1: every orbit of the family in the box is returned */
  int n_phases; /**< 2 slip-stick, 3 slip-overshoot-stick */
  double duration_lo[3], duration_hi[3];
  double x1_lo, x1_hi, v1_lo, v1_hi;
  /** roots of the duration equations proved in the box, of those whose
   *  start keeps the rules the phases of an orbit keep (the others are
   *  excluded without being isolated) */
  int roots;
  int orbits;   /**< of them feasible orbits, all returned */
  int rejected; /**< of them not orbits */
  int added;    /**< orbits the other sources had missed, added */
  long boxes;   /**< boxes tested */
  double seconds;
  char why[192]; /**< when not complete: what was left */
} ss_family_cert;

/** What the search did. */
typedef struct ss_orbit_report {
  int simulations; /**< simulations to an attractor */
  /** of them, stopped on reaching a stable orbit already found (within
   *  1e-7 of the scale of one of its returns) */
  int simulations_known;
  int newton_starts; /**< Newton solves started (durations and map) */
  int roots;         /**< converged roots */
  int infeasible;    /**< roots rejected as physically inadmissible */
  int duplicates;    /**< roots already found */
  int truncated;     /**< more orbits than room in the output */
  /** The scan of the slip-stick and slip-overshoot-stick duration equations:
   *  every root with each duration in (0, scan_box] on a grid of step
   *  scan_step (both 0 when there was no scan: from a guess, or neither
   *  family asked for).  The box is 1.5 slow modal periods, grown where the
   *  motion from the starts of slips that may outlast it travels longer
   *  phases (to 1.1 times the longest), at most scan_box_cap (3 slow modal
   *  periods); the proof (cert) covers the same durations.  Orbits of those
   *  families outside the box, and of other sequences, come only from
   *  simulation and Newton starts. */
  double scan_box, scan_step;
  double scan_box_cap; /**< the most scan_box grows to (0: no search) */
  /** The scan's work: cells examined, at every refinement of the grid. */
  long scan_cells;
  char reason[256]; /**< why nothing was found, or the closest rejection */
  /** The rejected root closest to feasible (largest violation.value), with
   *  its margins, when a root was rejected. */
  int has_rejected;
  ss_orbit rejected;
  /** With ss_orbit_opts.certify: [0] slip-stick, [1] slip-overshoot-stick */
  ss_family_cert cert[2];
} ss_orbit_report;

/**
 * Solve the orbit equations for the phase sequence @a modes (n phases,
 * modes[0] = slip, modes[n-1] = stick) from the guess @a tau.
 *
 * The unknowns are the n durations.  The start state is eliminated through
 * the periodicity system (5.1): rows 1-3 of (N - I) z0 + c = 0 (N, c the
 * affine map of the whole cycle), with the fourth row replaced by z2'(0) = V
 * (3.1), which with the phase-end conditions implies it.  The n equations are
 * chi (z2 - z1)(0) = ur - us (3.1) and the end condition of every phase but
 * the last (x2' = V (3.7) for slip and overshoot, chi(x2-x1) = +-ur for a
 * stick); ss_orbit_equations() evaluates them.  GSL's hybridsj solver uses
 * the analytic Jacobian, built from the derivatives of the phase transition
 * matrices; plain Newton steps polish while the residual falls.
 *
 * The root is then checked (ss_orbit_check()) and its stability computed
 * (ss_stability(), with the turns the check counted).
 * @param n, modes  the phase sequence, 2..SS_MAX_PHASES phases, no mode
 *                  twice in a row
 * @param tau       the guessed durations, finite and > 0
 * @param opts      may be NULL (no difference check); opts->turns is not
 *                  used
 * @param[out] o    the orbit
 * @param d         details of a failure, may be NULL
 * @return SS_OK (a feasible orbit in @a o); SS_INFEASIBLE (a root that is not
 *         an orbit: @a o holds it and @a d->text says why); SS_ENOCONV;
 *         SS_ESINGULAR; SS_EINVAL.  Thread-safe.
 */
SS_API int ss_orbit_solve(const ss_model *m, int n, const ss_mode *modes,
                          const double *tau, const ss_stab_opts *opts,
                          ss_orbit *o, ss_diag *d);

/**
 * The duration equations of ss_orbit_solve() at the durations @a tau, for
 * callers that build their own solvers or continuation on them.  The start
 * z0 is the solution of the periodicity system (5.1) at @a tau (rows 1-3 of
 * (N - I) z0 + c = 0, the fourth row z2'(0) = V), and the n residuals are
 *
 *   F[0]   = chi (z2 - z1)(0) - (ur - us)     (3.1: z0 lies on Sigma0)
 *   F[k+1] = the end condition of phase k, k = 0..n-2, at the state reached
 *            after its duration: x2' - V for slip and overshoot (3.7),
 *            chi (x2 - x1) - ur for a stick that ends in slip,
 *            chi (x2 - x1) + ur for one that ends in overshoot;
 *
 * all vanish at an orbit (the last phase, a stick, ends on Sigma0 by (5.1)).
 * @param n, modes   the phase sequence, as for ss_orbit_solve()
 * @param tau        the n durations
 * @param[out] z0    the start state in z = x - (d0, 0)
 * @param[out] F     the n residuals
 * @param[out] J     NULL, or room for n x n: the analytic Jacobian, row-major,
 *                   J[n i + j] = dF[i] / dtau[j]
 * @return SS_OK; SS_EINVAL (a NULL argument, or a sequence ss_orbit_solve()
 *         refuses); SS_ESINGULAR (the periodicity system is singular at
 *         @a tau; F and J are then not set).  Thread-safe; allocates nothing.
 */
SS_API int ss_orbit_equations(const ss_model *m, int n, const ss_mode *modes,
                              const double *tau, double z0[4], double *F,
                              double *J);

/**
 * Check the orbit in @a o (modes, durations, z0 set) by simulation with the
 * certified event finder: every phase must end at its FIRST crossing, at its
 * duration, into the next mode of the sequence, without grazing, and all
 * durations must be positive.  Fills x0, n_turns, the margins, period and
 * closure.
 * @return SS_OK; SS_INFEASIBLE with the reason in @a d; SS_EINVAL (a phase
 *         count outside 2..SS_MAX_PHASES, or a start that is not finite);
 *         or a failure of the event search.
 */
SS_API int ss_orbit_check(const ss_model *m, ss_orbit *o, ss_diag *d);

/**
 * Find periodic orbits for the parameters of @a m with no guess (or from the
 * guess in @a opts): simulation to attractors (stable orbits of any
 * sequence and period up to max_period), Newton on the duration equations
 * from a grid of durations for the overshoot and stick-slip kinds (which
 * finds unstable orbits), and Newton on the Poincare map P^k from points of
 * Sigma0.  Duplicates are removed; every orbit returned is feasible.
 * @param opts          may be NULL (the defaults)
 * @param out, max_out  room for the orbits, sorted by kind then period
 * @param[out] n_out    number returned
 * @param[out] rep      what the search did, may be NULL
 * @param d             details of a failure, may be NULL
 * @return SS_OK (possibly with *n_out = 0: then rep->reason says why) or a
 *         failure: SS_ELIMIT_TIME when the budget ran out or SS_ECANCELED
 *         when the caller cancelled (*n_out orbits were found before);
 *         SS_EINVAL (bad options or output).  Thread-safe (the cancel hook
 *         aside).
 */
SS_API int ss_orbit_find(const ss_model *m, const ss_orbit_opts *opts,
                         ss_orbit *out, int max_out, int *n_out,
                         ss_orbit_report *rep, ss_diag *d);

/**
 * The Poincare map on Sigma0 by simulation: from s = (z1, z1') follow the
 * motion through @a turns stick -> slip returns.
 * @param s            the start on Sigma0, (z1, z1')
 * @param turns        returns to Sigma0 to follow, >= 1
 * @param max_events   give up after this many events (SS_ELIMIT_EVENTS)
 * @param[out] out     the point reached, (z1, z1')
 * @param[out] modes, durations, n_phases  the sequence travelled (may be NULL;
 *                     modes and durations are written only when both are
 *                     given; room for SS_MAX_PHASES phases, more is
 *                     SS_ELIMIT_EVENTS)
 * @return SS_OK, SS_ELIMIT_EVENTS, SS_HORIZON (perpetual slip), or a failure
 *         (SS_EINVAL for a start that is not finite).  Thread-safe.
 */
SS_API int ss_poincare(const ss_model *m, const double s[2], int turns,
                       size_t max_events, double out[2], ss_mode *modes,
                       double *durations, int *n_phases);

/**
 * The stability of the orbit given by (@a n, @a modes, @a tau, @a z0):
 * the analytic Jacobian of the Poincare map, composed from the phase
 * transition matrices with the switching-time corrections of section 4,
 *   dZ_{k+1} = (I - f_k n_k^T / (n_k . f_k)) A_k(tau_k) dZ_k,
 * (f_k the vector field at the end of phase k, n_k the gradient of its
 * switching function), started from dZ_0 = (x, x, v, 0) on Sigma0 (4.3);
 * with opts->difference_check, also the central-difference Jacobian of
 * ss_poincare() over opts->turns returns (counted from the modes when 0).
 * @param n, modes, tau  the phase sequence and its durations
 *                       (1..SS_MAX_PHASES phases)
 * @param z0    the start, on Sigma0, in z = x - (d0, 0)
 * @param opts  may be NULL (turns counted, no difference check)
 * @param[out] st  the stability; st->jac_diff is NAN without the check
 * @return SS_OK, SS_EINVAL or SS_ESINGULAR (a phase ends tangentially).
 *         Thread-safe.
 */
SS_API int ss_stability(const ss_model *m, int n, const ss_mode *modes,
                        const double *tau, const double z0[4],
                        const ss_stab_opts *opts, ss_stab *st);

/* ------------------------------------------------------------------------ */
/* Continuation of an orbit family in one parameter                         */
/* ------------------------------------------------------------------------ */

/** The names of the dimensionless parameters in the order of ss_param_id,
 *  each as X(name): the one list ss_param_name() and tables of names (a
 *  decoder's, say) expand. */
#define SS_PARAM_NAMES(X) X(chi) X(eta) X(us) X(ur) X(V)

/** The dimensionless parameters, for continuation. */
typedef enum ss_param_id {
  SS_PARAM_CHI = 0,
  SS_PARAM_ETA = 1,
  SS_PARAM_US = 2,
  SS_PARAM_UR = 3,
  SS_PARAM_V = 4
} ss_param_id;

/** "chi", "eta", "us", "ur", "V"; NULL for anything else. */
SS_API const char *ss_param_name(ss_param_id id);

/** The parameter called @a name; SS_OK or SS_EINVAL. */
SS_API int ss_param_by_name(const char *name, ss_param_id *id);

/** The names of the physical parameters in the order of ss_phys_id, each
 *  as X(name), as SS_PARAM_NAMES. */
#define SS_PHYS_NAMES(X) X(m1) X(m2) X(k1) X(k2) X(Fs) X(Fr) X(v0)

/** The physical parameters, for continuation in physical units. */
typedef enum ss_phys_id {
  SS_PHYS_M1 = 0,
  SS_PHYS_M2 = 1,
  SS_PHYS_K1 = 2,
  SS_PHYS_K2 = 3,
  SS_PHYS_FS = 4,
  SS_PHYS_FR = 5,
  SS_PHYS_V0 = 6
} ss_phys_id;

/** "m1", "m2", "k1", "k2", "Fs", "Fr", "v0"; NULL for anything else. */
SS_API const char *ss_phys_name(ss_phys_id id);

/** The physical parameter called @a name; SS_OK or SS_EINVAL. */
SS_API int ss_phys_by_name(const char *name, ss_phys_id *id);

/** One orbit of a family. */
typedef struct ss_cont_point {
  double value;                    /**< the continued parameter */
  double durations[SS_MAX_PHASES]; /**< of the phases of the family */
  double period;                   /**< their sum */
  double z0[4];                    /**< start, on Sigma0, in z */
  int n_turns;                     /**< returns to Sigma0 per period */
  double eig_re[2], eig_im[2];     /**< multipliers, larger modulus first */
  double spectral_radius;          /**< the largest |multiplier| */
  int stable;                      /**< spectral radius < 1 */
  ss_margin min_margin;            /**< the smallest feasibility margin */
  double residual;                 /**< max |F| of the orbit equations */
} ss_cont_point;

/** What happens at a special point of a family. */
typedef enum ss_special_kind {
  SS_SPECIAL_GRAZING = 0,         /**< a feasibility margin reaches zero */
  SS_SPECIAL_FOLD = 1,            /**< the family turns back in the parameter */
  SS_SPECIAL_SADDLE_NODE = 2,     /**< a real multiplier through +1 */
  SS_SPECIAL_PERIOD_DOUBLING = 3, /**< a real multiplier through -1 */
  SS_SPECIAL_NEIMARK_SACKER = 4   /**< a complex pair through |m| = 1 */
} ss_special_kind;

/** "grazing", "fold", "saddle_node", "period_doubling", "neimark_sacker";
 *  NULL for anything else. */
SS_API const char *ss_special_name(ss_special_kind k);

/** A located special point. */
typedef struct ss_special {
  ss_special_kind kind;
  double value; /**< the parameter where it is located */
  /** The width of the final bracket in the parameter, relative to |value|
   *  (the location's precision) */
  double precision;
  ss_cont_point at; /**< the orbit there (the feasible side of a grazing) */
  /** grazing: the margin that reaches zero (SS_MARGIN_SWITCHING, one of
   *  the four of a phase's inside, SS_MARGIN_SLIP_BELOW_V ..
   *  _STICK_ABOVE_MINUS_UR, or SS_MARGIN_TRANSVERSALITY), its phase and time
   *  in at.min_margin; SS_MARGIN_NONE for the other kinds */
  ss_margin_id margin;
  /** The stability verdict below and above the value (in increasing
   *  parameter) */
  int stable_before, stable_after;
  char detail[400]; /**< a sentence */
} ss_special;

/** The most special points one family reports. */
#define SS_MAX_SPECIAL 32

/** Options of ss_continue(); zero-initialise, then set param, lo and hi. */
typedef struct ss_cont_opts {
  ss_param_id param; /**< the continued parameter */
  double lo, hi;     /**< its range, lo < hi, containing the start */
  int max_points;    /**< accepted points in all (0: 200) */
  /** The first step, in the scaled arclength (parameter over (hi - lo),
   *  durations over the start's period); 0: 0.02 */
  double step;
  int direction; /**< 0 both ways from the start, +1 up, -1 down */
  /** Non-NULL: continue the physical parameter @a phys of *physical
   *  instead of @a param (lo, hi and the points' values in its unit; the
   *  dimensionless parameters of every point are derived from it, the
   *  points' times stay dimensionless).  Only ss_continue() reads it. */
  const ss_physical *physical;
  ss_phys_id phys;
  double max_seconds; /**< time budget (0: none) */
  /** Polled between steps: a non-zero answer stops with SS_ECANCELED. */
  int (*cancelled)(void *cls);
  void *cancel_cls;
} ss_cont_opts;

/** A family: its points in order along it, and its special points. */
typedef struct ss_branch {
  int n_phases;
  ss_mode modes[SS_MAX_PHASES];
  /** The continued parameter and its range, as ss_continue() was asked:
   *  param, or with physical set the physical parameter phys */
  ss_param_id param;
  int physical;
  ss_phys_id phys;
  double lo, hi;
  int n_points;
  ss_cont_point *points; /**< malloc'd; ss_branch_free() */
  int start;             /**< the index of the starting orbit in points */
  int n_special;
  ss_special special[SS_MAX_SPECIAL];
  /** Why the family ended going down ([0]) and up ([1]) from the start;
   *  "" for a direction not followed. */
  char end[2][320];
} ss_branch;

/**
 * Continue the periodic orbit @a start (its modes and durations; it is
 * solved again at @a p) in the parameter opts->param over [lo, hi], by
 * pseudo-arclength on the duration equations of ss_orbit_equations() with
 * the parameter as one more unknown (its derivative by central differences),
 * with an adaptive step.  Every accepted point is feasible by
 * ss_orbit_check() and has its stability.  Between accepted points, sign
 * changes locate special points to a relative 1e-10 in the parameter: a
 * point that is not feasible ends the family at a grazing, located by
 * bisection along the family; the tangent's parameter component at a fold;
 * det(I - J), det(I + J) and det J - 1 (a complex pair) of the Poincare map's
 * Jacobian J at the multiplier crossings.
 * @param p      the parameters; p's value of opts->param is the start's
 * @param start  a feasible orbit at @a p (as ss_orbit_find() gives)
 * @param[out] b the family; release with ss_branch_free() whatever happens
 * @return SS_OK (b->end says why each direction ended); SS_EINVAL (bad
 *         options or a start outside the range); SS_INFEASIBLE or
 *         SS_ENOCONV (the start is not a feasible orbit at @a p);
 *         SS_ELIMIT_TIME or SS_ECANCELED (b holds what was found);
 *         SS_ENOMEM.  Thread-safe (the cancel hook aside).
 */
SS_API int ss_continue(const ss_params *p, const ss_orbit *start,
                       const ss_cont_opts *opts, ss_branch *b, ss_diag *d);

/** Release what ss_continue() allocated.  NULL-safe; zeroes @a b. */
SS_API void ss_branch_free(ss_branch *b);

/**
 * Start the period-2 family at the period doubling @a pd of the family @a b
 * (continued with @a o from parameters @a p) and continue it with @a o:
 * the period-2 orbit (the family's sequence twice, halves that differ) is
 * looked for by ss_orbit_find() a little way either side of the located
 * value, nearest first.  The new family ends where it meets the period-1
 * family again (its halves become equal) or as any family does.
 * @return SS_OK (@a out is the period-2 family); SS_EINVAL (@a pd is not a
 *         period doubling, or the family or @a o is in a physical
 *         parameter); SS_ENOCONV (no period-2 orbit found near it);
 *         SS_ELIMIT_TIME or SS_ECANCELED (the search for it stopped, or as
 *         ss_continue()); or as ss_continue().  Release @a out with
 *         ss_branch_free().
 */
SS_API int ss_continue_period2(const ss_params *p, const ss_branch *b,
                               const ss_special *pd, const ss_cont_opts *o,
                               ss_branch *out, ss_diag *d);

/** Where the motion settles: a periodic attractor found by simulation. */
typedef struct ss_attractor {
  int found;          /**< 1: a periodic attractor; 0: none within the budget */
  int perpetual_slip; /**< the motion slips for ever (no return) */
  int n_turns;        /**< returns to Sigma0 per period */
  double period;      /**< its period */
  int n_phases;       /**< phases per period (may exceed SS_MAX_PHASES) */
  int n_overshoot;    /**< overshoot phases per period */
  ss_mode modes[SS_MAX_PHASES];    /**< the first min(n_phases,
                                        SS_MAX_PHASES) modes */
  double durations[SS_MAX_PHASES]; /**< and their durations */
  double s[2];                     /**< a point of it on Sigma0, (z1, z1') */
  int turns_run;                   /**< returns simulated to find it */
} ss_attractor;

/**
 * Simulate from (z1, z1') = @a s0 on Sigma0, return by return, and find
 * the periodic attractor the motion settles on: the smallest k <= max_period
 * with each component of P^k(s) - s within 1e-9 (1 + |s0| + |s1|) at two
 * successive returns, looked for from the 21st return on, within max_turns
 * returns.
 * @return SS_OK (a->found says whether one was found); SS_EINVAL (a NULL,
 *         max_turns < 1, max_period outside 1..256); SS_ENOMEM; a failure
 *         of the simulation.  Thread-safe.
 */
SS_API int ss_attractor_from(const ss_model *m, const double s0[2],
                             int max_turns, int max_period, ss_attractor *a);

/**
 * What the motion does just beyond the grazing @a g that ends the family
 * @a b (continued in b->param): from the grazing orbit's start, at the
 * parameter 1e-4 (relative) past the located value on the side where the
 * family does not exist (*value), the attractor simulation reaches
 * (ss_attractor_from, 5000 returns, periods up to 64 returns).
 * @return SS_OK; SS_EINVAL (@a g is not a grazing that ends @a b, or @a b
 *         is a family in a physical parameter); or as ss_attractor_from().
 */
SS_API int ss_beyond_grazing(const ss_params *p, const ss_branch *b,
                             const ss_special *g, double *value,
                             ss_attractor *a);

/**
 * The family on the other side of the grazing @a g that ends the family
 * @a b (continued with @a o from parameters @a p): the adjacent sequence,
 * a short stick inserted after the phase whose switching margin reaches
 * zero, or, for a margin's maximum inside a phase, that phase split there
 * by a short phase of the mode the margin's zero would start (the new
 * phase 1e-3 of the period at the start), solved 1e-4 (relative) past the
 * located value and, when that orbit is feasible, continued with @a o (its
 * modes in out->modes).
 * @return SS_OK (@a out is the adjacent family); SS_INFEASIBLE (no
 *         feasible orbit of the adjacent sequence there: @a d says why, the
 *         family ends at the grazing; out->modes holds the sequence tried);
 *         SS_EINVAL (not such a grazing that ends @a b); or as
 *         ss_continue().  Release @a out with ss_branch_free().
 */
SS_API int ss_continue_adjacent(const ss_params *p, const ss_branch *b,
                                const ss_special *g, const ss_cont_opts *o,
                                ss_branch *out, ss_diag *d);

/** A point of a curve of special points in two parameters. */
typedef struct ss_curve_point {
  double v1, v2;                   /**< the first and second parameter */
  double durations[SS_MAX_PHASES]; /**< the orbit there */
  double z0[4];
  /** A grazing's: the side of v1 on which the orbit exists, +1 above, -1
   *  below (0 for a period doubling) */
  int feasible_side;
} ss_curve_point;

/** A curve of special points: where a family's grazing moves as a second
 *  parameter changes. */
typedef struct ss_curve {
  ss_special_kind kind; /**< SS_SPECIAL_GRAZING or _PERIOD_DOUBLING */
  ss_margin_id margin;  /**< the margin that is zero along it (a grazing) */
  int phase;            /**< at the end of this phase */
  ss_param_id p1, p2;
  int n_points;
  ss_curve_point *points; /**< malloc'd, in order along the curve */
  int start;              /**< the index of the grazing it started from */
  char end[2][320];       /**< why it ended, p2 going down and up */
} ss_curve;

/**
 * Follow the grazing @a g of the family @a b (continued from parameters
 * @a p in p1 = b->param over [b->lo, b->hi]) as a second parameter,
 * o2->param, moves over [o2->lo, o2->hi] (o2's direction and physical are
 * not read): pseudo-arclength on the duration equations and the grazing's
 * equation, in (durations, p1, p2).  At every point the orbit solved 1e-7
 * (relative) either side in p1 (1e-5 for a grazing of a phase's end, ten
 * or a hundred times that where neither side is feasible) is feasible on
 * one side only, or the curve ends.  A grazing of the switching condition at
 * the end of a slip or overshoot (SS_MARGIN_SWITCHING), of a phase's end
 * (SS_MARGIN_TRANSVERSALITY) or of a margin's maximum inside a phase can
 * be followed.
 * @return SS_OK; SS_EINVAL (bad options, another kind of special point or
 *         margin, p2 == p1, a family in a physical parameter, a range
 *         without p2's value); SS_ENOCONV (no curve through the point);
 *         SS_ELIMIT_TIME, SS_ECANCELED (with what was found); SS_ENOMEM.
 *         Release @a cv with ss_curve_free().
 */
SS_API int ss_continue_grazing(const ss_params *p, const ss_branch *b,
                               const ss_special *g, const ss_cont_opts *o2,
                               ss_curve *cv, ss_diag *d);

/**
 * Follow the period doubling @a pd of the family @a b as a second parameter
 * moves, as ss_continue_grazing() does a grazing: the duration equations
 * and det(I + J) = 0 (J the Poincare map's Jacobian), every point a
 * feasible orbit (the curve ends where it is not).  Points have
 * feasible_side 0.
 */
SS_API int ss_continue_period_doubling(const ss_params *p, const ss_branch *b,
                                       const ss_special *pd,
                                       const ss_cont_opts *o2, ss_curve *cv,
                                       ss_diag *d);

/** Release what ss_continue_grazing() allocated.  NULL-safe. */
SS_API void ss_curve_free(ss_curve *c);

/** What ss_continue_study() does besides continuing the family;
 *  zero-initialise, then set family.param, .lo and .hi. */
typedef struct ss_study_opts {
  /** The family, as for ss_continue(); also how the curves and the
   *  families branch switching starts are continued (their step,
   *  max_points, time budget each, cancel hook) */
  ss_cont_opts family;
  /** 1: follow each special point of kind follow_kind (SS_SPECIAL_GRAZING
   *  or SS_SPECIAL_PERIOD_DOUBLING) in follow_param over [follow_lo,
   *  follow_hi] (ss_continue_grazing(), ss_continue_period_doubling()) */
  int follow;
  ss_special_kind follow_kind;
  ss_param_id follow_param;
  double follow_lo, follow_hi;
  /** 1: continue the family each special point starts: the period-2
   *  family at a period doubling (ss_continue_period2()), the adjacent
   *  family past a grazing (ss_continue_adjacent()) */
  int branch_switching;
} ss_study_opts;

/** Past a grazing that ends the family (a dimensionless one). */
typedef struct ss_beyond {
  /** ss_beyond_grazing() succeeded: value and attractor are set */
  int done;
  double value;
  ss_attractor attractor;
  /** ss_continue_adjacent()'s status: SS_OK when the adjacent sequence
   *  has a family there; its modes, and why it has none */
  int adjacent_rc;
  int adjacent_n_phases;
  ss_mode adjacent_modes[SS_MAX_PHASES];
  char adjacent_why[192];
} ss_beyond;

/** A family with what its special points lead to. */
typedef struct ss_study {
  ss_branch family;
  /** One curve per followed special point, in the family's order; one
   *  that could not be followed has no points, start -1 and the reason in
   *  end[0] */
  int n_curves;
  ss_curve curves[SS_MAX_SPECIAL];
  /** With branch_switching: the families started, each from the special
   *  point family.special[of_special[i]] (malloc'd) */
  int n_branches;
  ss_branch *branches;
  int of_special[SS_MAX_SPECIAL];
  /** Per special point of the family: why a period doubling starts no
   *  family (with branch_switching), and past a grazing what happens */
  char why_none[SS_MAX_SPECIAL][192];
  ss_beyond beyond[SS_MAX_SPECIAL];
} ss_study;

/**
 * A family and what its special points lead to, in one call: the family
 * (ss_continue()); with opts->follow, each special point of that kind
 * followed in a second parameter; with opts->branch_switching, the
 * period-2 family at each period doubling; past each grazing (of a family
 * in a dimensionless parameter) the attractor (ss_beyond_grazing()) and the
 * adjacent sequence (ss_continue_adjacent(), its family kept with
 * branch_switching).  A special point that leads nowhere says why in @a s;
 * only running out of time, a cancel or memory stops the study.
 * @param[out] s the study; release with ss_study_free() whatever happens
 * @param d      details of the family's own failure, may be NULL
 * @return SS_OK; as ss_continue() for the family; SS_ELIMIT_TIME,
 *         SS_ECANCELED or SS_ENOMEM from a later step (@a s holds what was
 *         found, @a d is not written).  Thread-safe (the cancel hook aside).
 */
SS_API int ss_continue_study(const ss_params *p, const ss_orbit *start,
                             const ss_study_opts *opts, ss_study *s,
                             ss_diag *d);

/** Release what ss_continue_study() allocated.  NULL-safe; zeroes @a s. */
SS_API void ss_study_free(ss_study *s);

/* ------------------------------------------------------------------------ */
/* Parameter maps                                                            */
/* ------------------------------------------------------------------------ */

/** One axis of a map: @a n values from @a from to @a to, evenly spaced
 *  (n = 1: @a from alone). */
typedef struct ss_map_axis {
  int param;       /**< an ss_param_id, or with ss_map_opts.physical an
                        ss_phys_id */
  double from, to; /**< the first and the last value */
  int n;           /**< values, >= 1 */
} ss_map_axis;

/** An orbit of a map cell: what a map tells of it. */
typedef struct ss_map_orbit {
  ss_orbit_kind kind;
  int n_phases;
  ss_mode modes[SS_MAX_PHASES];
  double durations[SS_MAX_PHASES];
  double period;
  int n_turns;
  double z0[4];
  double eig_re[2], eig_im[2]; /**< multipliers, larger modulus first */
  double spectral_radius;
  int stable, marginal; /**< as in ss_stab */
  ss_margin min_margin;
  /** -1: found by the full search at this cell; else the cell whose orbit,
   *  as a guess, continued into this one */
  int from_cell;
} ss_map_orbit;

/** One cell of a map. */
typedef struct ss_map_cell {
  /** 1: the full search (ss_orbit_find() with the map's kinds, max_period
   *  and effort) ran here and finished: the cell holds every orbit it finds,
   *  and those continued in from the neighbours; 0: the orbits continued
   *  in from the neighbours only. */
  int complete;
  int n_orbits;
  ss_map_orbit *orbits; /**< sorted by kind, then period */
  int truncated;        /**< orbits left out for want of room */
} ss_map_cell;

/** The most orbits one full search of a map's cell gives. */
#define SS_MAP_FOUND_MAX 32

/** The full search of one cell of a map (ss_map_search()): what it found,
 *  before the cell takes it (the cell drops what its kinds, max_period and
 *  max_orbits leave out, and what it holds already). */
typedef struct ss_map_found {
  int status;   /**< of the search: SS_OK (the cell is complete), or what
                     stops the map (ss_map_run() returns it) */
  ss_diag diag; /**< why, when status is not SS_OK */
  int n_orbits;
  /** in the order found; from_cell -1 */
  ss_map_orbit orbits[SS_MAP_FOUND_MAX];
} ss_map_found;

/** Options of ss_map_run(); zero-initialise for the defaults. */
typedef struct ss_map_opts {
  unsigned kinds; /**< mask of ss_orbit_kind; 0 means all */
  int max_period; /**< as in ss_orbit_opts (0: 4) */
  int effort;     /**< of the full searches, as in ss_orbit_opts (0: 2) */
  /** The full search runs on a lattice of cells spread evenly along each
   *  axis from the first to the last, at most search_every apart, at every
   *  cell into which a neighbour's orbit does not continue (or continues
   *  far from itself) and which holds no orbit near it, at the two cells
   *  between which a family the map holds passes a multiplier through +1,
   *  -1 or the unit circle, and, when search_every is 1, everywhere (the
   *  map then holds in every cell every orbit its search finds; see
   *  no_edge_search).  0: 1, every cell: a sparser lattice is faster and may
   *  lack an orbit the search finds at a cell it did not search. */
  int search_every;
  int max_orbits; /**< per cell (0: 16) */
  int threads;    /**< the full searches run on this many threads (0: 1) */
  /** 1: no full search where a family ends or bifurcates (the lattice and
   *  the spreading only): faster, and blind to a family that begins only
   *  there */
  int no_edge_search;
  /** Non-NULL: the axes are physical parameters (ss_phys_id) of *physical,
   *  whose dimensionless parameters each cell takes (times stay
   *  dimensionless). */
  const ss_physical *physical;
  double max_seconds; /**< time budget (0: none) */
  /** Polled between cells and within each cell's search, on the worker
   *  threads and possibly at once (it must be thread-safe: an atomic flag
   *  read); a non-zero answer stops with SS_ECANCELED. */
  int (*cancelled)(void *cls);
  void *cancel_cls;
  /** Non-NULL: full searches made already, apart (a map made in pieces:
   *  ss_map_lattice(), ss_map_search()).  Asked, on the calling thread,
   *  for each cell before the map searches it: 1 and *found as
   *  ss_map_search() gave it for this cell with the same parameters, axes
   *  and options (found->status neither SS_ELIMIT_TIME nor SS_ECANCELED);
   *  or 0, and the map makes that search itself.  The map is the same, bit
   *  for bit, either way; a search given counts in ss_map.searches. */
  int (*searched)(void *cls, int cell, ss_map_found *found);
  void *searched_cls;
} ss_map_opts;

/** A map: cells in row-major order, cell (i, j) at i * axes[1].n + j. */
typedef struct ss_map {
  int n_axes;
  ss_map_axis axes[2];
  int n_cells;
  ss_map_cell *cells; /**< malloc'd; ss_map_free() */
  int searches;       /**< full searches run */
  int solves;         /**< solves from a neighbour's orbit */
} ss_map;

/** The value of axis @a a at index @a i. */
SS_API double ss_map_value(const ss_map_axis *a, int i);

/** The dimensionless parameters of cell @a cell of @a map made from the
 *  base @a p (or opts->physical; then *omega is its time scale, else 1).
 *  SS_OK, SS_EDOMAIN (parameters out of range; @a d says which) or
 *  SS_EINVAL (no such cell). */
SS_API int ss_map_params(const ss_params *p, const ss_map_opts *opts,
                         const ss_map *map, int cell, ss_params *out,
                         double *omega, ss_diag *d);

/**
 * A map of the periodic orbits over a grid of one or two parameters,
 * the others those of @a p (or of opts->physical).  Full searches at a
 * lattice of cells; every orbit found is continued into the neighbouring
 * cells (8 of them in two dimensions) as a guess, again from every cell
 * it reaches, so that no cell lacks an orbit of a family that a neighbour
 * has and that continues into it; where a neighbour's orbit does not
 * continue, or continues far from itself, and the cell holds no orbit near
 * it (a family ends, or turns), the full search runs there too.  Every
 * orbit is feasible by ss_orbit_check(), with its stability.
 * @param n_axes  1 or 2; two axes name different parameters
 * @param[out] map  release with ss_map_free() whatever happens
 * @return SS_OK; SS_EINVAL (bad axes or options); SS_EDOMAIN (a cell's
 *         parameters are out of range: @a d says which); SS_ELIMIT_TIME or
 *         SS_ECANCELED (the cells done hold what was found); SS_ENOMEM.
 *         Thread-safe when the cancel hook is.
 */
SS_API int ss_map_run(const ss_params *p, int n_axes, const ss_map_axis *axes,
                      const ss_map_opts *opts, ss_map *map, ss_diag *d);

/** Release what ss_map_run() allocated.  NULL-safe; zeroes @a map. */
SS_API void ss_map_free(ss_map *map);

/**
 * The cells where ss_map_run() with these arguments makes its first full
 * searches, the lattice (row-major order).  Those searches are independent
 * of each other and nearly all of a map's time: made apart with
 * ss_map_search() and given back through ss_map_opts.searched, they make
 * the map ss_map_run() makes alone.  (The searches where families end
 * depend on the spreading: ss_map_run() makes them.)
 * @param[out] cells  room for every cell of the map
 * @param[out] n      how many cells the lattice has
 * @return SS_OK; otherwise what ss_map_run() returns before any search
 *         (SS_EINVAL, SS_EDOMAIN with @a d), and *n is untouched.
 *         Thread-safe; allocates nothing.
 */
SS_API int ss_map_lattice(const ss_params *p, int n_axes,
                          const ss_map_axis *axes, const ss_map_opts *opts,
                          int *cells, int *n, ss_diag *d);

/**
 * The full search of cell @a cell, as ss_map_run() with these arguments
 * makes it (the same code; opts->threads and opts->searched are not read):
 * ss_orbit_find() with the map's kinds, max_period and effort, within
 * opts->max_seconds from the call and opts->cancelled.
 * @param[out] found  the search; its own outcome in found->status
 * @return SS_OK (the search ran: *found); SS_EINVAL (bad arguments, no
 *         such cell); SS_ENOMEM.  Thread-safe (the cancel hook aside).
 */
SS_API int ss_map_search(const ss_params *p, int n_axes,
                         const ss_map_axis *axes, const ss_map_opts *opts,
                         int cell, ss_map_found *found, ss_diag *d);

/* ------------------------------------------------------------------------ */
/* Basins of attraction                                                      */
/* ------------------------------------------------------------------------ */

/** Labels of ss_basins.labels that are not an attractor's index. */
#define SS_BASIN_UNRESOLVED 255 /**< not landed within max_returns */
#define SS_BASIN_PERPETUAL 254  /**< slips for ever, never returns */
/** The most attractors a basin map tells apart. */
#define SS_BASIN_MAX_ATTRACTORS 64
/** The most returns to Sigma0 per period of an attractor. */
#define SS_BASIN_MAX_TURNS 8

/** A periodic attractor of a basin map. */
typedef struct ss_basin_attractor {
  ss_orbit orbit;      /**< feasible and stable, with its stability */
  int from_simulation; /**< 0: the orbit search found it; 1: a motion that
                            landed on no known one settled on it */
  int n_points;        /**< its returns to Sigma0 per period (n_turns) */
  double points[SS_BASIN_MAX_TURNS][2]; /**< those returns, (z1, z1') */
  /** A motion whose return comes within this distance of one of the
   *  points is labelled with the attractor: the contraction check passed
   *  at that radius (see ss_basins_run()). */
  double radius;
  int iterations; /**< the periods the check needed to shrink the circle */
  long cells;     /**< cells labelled with it */
} ss_basin_attractor;

/** Options of ss_basins_run(); zero-initialise, then set the slice. */
typedef struct ss_basin_opts {
  /** The slice: state variables vary[0] and vary[1] (0 x1, 1 x2, 2 x1',
   *  3 x2') over n[a] values from from[a] to to[a] (n >= 1; different
   *  ends when n > 1); the other two are those of state. */
  int vary[2];
  double from[2], to[2];
  int n[2];
  double state[4];
  int max_period;  /**< of the orbit search and of attractors found by
                        simulation, 1..SS_BASIN_MAX_TURNS (0: 4) */
  int max_returns; /**< returns to Sigma0 per cell before it is unresolved
                        (0: 500) */
  int threads;     /**< the cells are simulated on this many threads (0: 1) */
  double max_seconds; /**< time budget (0: none) */
  /** Polled between rows, within each cell's motion (every 256 events)
   *  and within the search for attractors, on the worker threads (it must
   *  be thread-safe: an atomic flag read); a non-zero answer stops with
   *  SS_ECANCELED. */
  int (*cancelled)(void *cls);
  void *cancel_cls;
} ss_basin_opts;

/** A basin map: the attractors, and a label per cell, row-major
 *  (cell (i, j) at i * n[1] + j, i along vary[0]). */
typedef struct ss_basins {
  int n_attractors;
  ss_basin_attractor *attractors; /**< malloc'd */
  int n[2];
  unsigned char *labels; /**< malloc'd; an attractor's index, or
                              SS_BASIN_UNRESOLVED / SS_BASIN_PERPETUAL */
  long unresolved, perpetual;
  long returns;    /**< returns simulated in all */
  int max_returns; /**< the most returns one cell took to land */
} ss_basins;

/**
 * The basins of attraction over a two-dimensional slice of initial states.
 * The attractors are the stable orbits ss_orbit_find() gives (all kinds,
 * periods up to max_period); a cell's motion, simulated exactly event by
 * event, is labelled with the attractor one of whose returns to Sigma0 it
 * comes within the attractor's radius of.  The radius is certified by a
 * contraction check: starting at 1e-2 of the scale (ur - us)/chi (and V),
 * or at the orbit's smallest feasibility margin when smaller, it is
 * quartered until, for some j, P^(k j) (k the attractor's turns) maps
 * 64 points of the circle of that radius around each of its returns, 32 of
 * the circle of half of it and the return itself to within 0.9 of it; a motion
 * inside is then drawn in, and the label is final.  j may reach twice the
 * periods its linearisation takes to shrink a circle to 0.45 of itself (at
 * least 8); an orbit that needs more than 256 (spectral radius above about
 * 0.994) is not certified, and is no attractor.  So every stable orbit of
 * the search's that the check passes, in particular every one of spectral
 * radius below 0.99 whose map is smooth within the radius, is an attractor.
 * Cells that land on no known attractor within max_returns are resolved from
 * their last return: Newton on the return map P^k, k up to max_period (the
 * search's own, source SS_SOURCE_MAP_NEWTON), then simulated on
 * (ss_attractor_from()); a stable orbit either reaches is added
 * (from_simulation) when it solves as a feasible stable orbit, and those
 * cells are tried again; the rest stay unresolved.  The composition of
 * ss_basins_alloc(), ss_basins_attractors(), ss_basins_rows() over every row
 * and ss_basins_finish(), under one budget.
 * @return SS_OK; SS_EINVAL (bad options); SS_ELIMIT_TIME, SS_ECANCELED
 *         (labels not reached are SS_BASIN_UNRESOLVED); SS_ENOMEM.
 *         Release @a b with ss_basins_free() whatever happens.
 */
SS_API int ss_basins_run(const ss_model *m, const ss_basin_opts *opts,
                         ss_basins *b, ss_diag *d);

/** Release what ss_basins_run() or ss_basins_alloc() allocated.  NULL-safe;
 *  zeroes @a b. */
SS_API void ss_basins_free(ss_basins *b);

/*
 * The stages of ss_basins_run(), which is their composition, for a basin
 * map computed in pieces (rows in any order, in other processes):
 *   ss_basins_alloc()       the map of the slice: every label unresolved;
 *   ss_basins_attractors()  stage 0: the attractors of the orbit search;
 *   ss_basins_rows()        stage 1: any rows, labelled against the
 *                           attractors b holds (cells that land on none
 *                           stay SS_BASIN_UNRESOLVED);
 *   ss_basins_finish()      stage 2: attractors from simulation over the
 *                           cells still unresolved, those cells run again
 *                           after each, and the counts.
 * A row's labels depend on its cells and the attractors alone, so a map
 * whose attractors are copied from stage 0's (every byte of them, n and
 * order) and whose rows are done by separate calls on separate maps, their
 * labels, returns (summed) and max_returns (the largest) gathered into one,
 * is after stage 2 the map ss_basins_run() gives, bit for bit.  Each call
 * has its own time budget (opts->max_seconds from its start); @a opts is
 * the same slice throughout.
 */

/** A map of the slice of @a opts (checked as ss_basins_run() checks it):
 *  no attractors, every label SS_BASIN_UNRESOLVED, no returns.  SS_OK;
 *  SS_EINVAL; SS_ENOMEM.  Release it with ss_basins_free(). */
SS_API int ss_basins_alloc(const ss_basin_opts *opts, ss_basins *b, ss_diag *d);

/** Stage 0: the stable orbits of ss_orbit_find() that pass the contraction
 *  check, in its order, as @a b's attractors (those it held are replaced).
 *  SS_OK; SS_EINVAL (options, or @a b not of this slice); SS_ELIMIT_TIME,
 *  SS_ECANCELED (the attractors found so far); the search's failure. */
SS_API int ss_basins_attractors(const ss_model *m, const ss_basin_opts *opts,
                                ss_basins *b, ss_diag *d);

/** Stage 1: the cells of rows @a row to @a row + @a rows - 1 of @a b (along
 *  vary[0]) labelled against @a b's attractors, on opts->threads threads;
 *  their returns added to b->returns, b->max_returns raised to theirs.
 *  SS_OK; SS_EINVAL; SS_ELIMIT_TIME, SS_ECANCELED (cells not reached stay
 *  as they were). */
SS_API int ss_basins_rows(const ss_model *m, const ss_basin_opts *opts,
                          ss_basins *b, int row, int rows, ss_diag *d);

/** Stage 2: the unresolved cells of @a b simulated on, in row-major order,
 *  for attractors to add (from_simulation); after each, the unresolved
 *  cells labelled again; then b->unresolved, b->perpetual and each
 *  attractor's cells counted.  SS_OK; SS_EINVAL; SS_ELIMIT_TIME,
 *  SS_ECANCELED (the counts are still made). */
SS_API int ss_basins_finish(const ss_model *m, const ss_basin_opts *opts,
                            ss_basins *b, ss_diag *d);

#ifdef __cplusplus
}
#endif

#endif /* STICKSLIP_H */
