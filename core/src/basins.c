/*
 * basins.c: basins of attraction over a slice of initial states.
 *
 * Each cell's motion is simulated exactly, event by event, and watched at
 * its returns to Sigma0 (stick -> slip).  A return within an attractor's
 * certified radius of one of the attractor's own returns labels the cell.
 *
 * The radius: the Poincare map P^k of a stable orbit (k its turns) is a
 * contraction near its fixed points, but only near them: the map is
 * piecewise smooth, and a phase that appears or vanishes (a grazing) bounds
 * the neighbourhood where the orbit's sequence, and so its contraction,
 * holds.  The radius starts at 1e-2 of the problem's scale, or at the
 * orbit's smallest feasibility margin when that is smaller, and is quartered
 * (up to 8 times) until, for some j, P^(k j) maps 64 points of the
 * circle of that radius around each of the orbit's returns, 32 of the circle
 * of half of it and the return itself to within 0.9 of the radius: a check on
 * samples, not a proof, but one made on the map itself rather than on its
 * linearisation.  One period is often not enough: the Jacobian of a stable
 * orbit is far from normal (the paper's overshoot orbit: spectral radius 0.20,
 * norm 1.40; its period-3 orbit 0.31 and 6.4), so a circle is first stretched
 * before it shrinks.
 *
 * j runs to twice what the linearisation needs (check_iterations()), so a
 * slowly contracting orbit is judged by as many periods as it needs.
 *
 * The cells run on opts->threads threads, a row at a time.  Cells that
 * land nowhere are then resolved from their last return: Newton on P^k,
 * the search's (a motion that has not settled after max_returns returns is
 * often near an attractor that contracts slowly, and Newton converges there
 * in a few steps), then simulation on to what it settles on; each periodic
 * orbit found that way is solved and, when it is a feasible stable one,
 * added, and the unresolved cells are run again.
 *
 * The time budget and the cancel hook are polled inside the cells, every
 * SS__POLL_EVERY events of their motions (and of the attractor finder's and
 * the contraction check's), not only between rows: a cell far from every
 * attractor may simulate max_returns returns, seconds of work, before it is
 * unresolved, and a row of them minutes.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "attractor.h"
#include "internal.h"
#include "search.h"
#include "simulate.h"
#include "stability.h"

#define BASIN_MAX_RETURNS 500
#define BASIN_EVENTS_PER_RETURN 64
#define BASIN_CIRCLE 64 /* points of the circle checked */
#define BASIN_SHRINK 0.9
#define BASIN_HALVINGS 8
/* the periods the contraction check may take: at least, and at most */
#define BASIN_MAX_ITERATIONS 8
#define BASIN_ITERATIONS_CAP 256
#define BASIN_MAX_THREADS 64
#define BASIN_SETTLE_TURNS 5000

typedef struct runner {
  const ss_model *m;
  ss_basin_opts o; /* the options, defaults applied */
  ss_basins *b;
  int max_returns;
  double t_start;
  /* the rows to do, and the next one */
  pthread_mutex_t lock;
  int next_row, end_row;
  int only_unresolved; /* the cells after a new attractor */
  int stopped;
} runner;

void ss_basins_free(ss_basins *b) {
  if (!b)
    return;
  free(b->attractors);
  free(b->labels);
  memset(b, 0, sizeof *b);
}

static double axis_value(const ss_basin_opts *o, int a, int i) {
  if (o->n[a] <= 1)
    return o->from[a];
  double k = (double)(o->n[a] - 1);
  return (o->from[a] * (k - (double)i) + o->to[a] * (double)i) / k;
}

/* The return of an attractor within its radius of @a s, or -1. */
static int landed(const ss_basins *b, const double s[2]) {
  for (int a = 0; a < b->n_attractors; a++) {
    const ss_basin_attractor *at = &b->attractors[a];
    for (int k = 0; k < at->n_points; k++)
      if (hypot(s[0] - at->points[k][0], s[1] - at->points[k][1]) < at->radius)
        return a;
  }
  return -1;
}

/* Simulate from @a x0 until a return lands: the label; *returns the
 * returns it took, s the last return.  Unresolved when @a poll says stop. */
static int follow(const runner *r, const double x0[4], ss__poll *poll,
                  int *returns, double s[2]) {
  const ss_model *m = r->m;
  ss_sim sim;
  ss_event ev;
  *returns = 0;
  if (ss__sim_init(&sim, m, 0, x0, NULL) != SS_OK)
    return SS_BASIN_UNRESOLVED;
  size_t max_events = (size_t)(r->max_returns + 1) * BASIN_EVENTS_PER_RETURN;
  for (size_t k = 0; k < max_events; k++) {
    if (ss__poll_tick(poll))
      return SS_BASIN_UNRESOLVED;
    int rc = ss_sim_next_event(&sim, INFINITY, &ev);
    if (rc == SS_HORIZON)
      return SS_BASIN_PERPETUAL;
    if (rc != SS_OK)
      return SS_BASIN_UNRESOLVED;
    if (ev.kind != SS_EVENT_TRANSITION || ev.from != SS_MODE_STICK ||
        ev.to != SS_MODE_SLIP)
      continue;
    s[0] = ev.x[0] - m->d0[0];
    s[1] = ev.x[2];
    int a = landed(r->b, s);
    ++*returns;
    if (a >= 0)
      return a;
    if (*returns >= r->max_returns)
      return SS_BASIN_UNRESOLVED;
  }
  return SS_BASIN_UNRESOLVED;
}

static int over_budget(runner *r) {
  if (!r->stopped && r->o.max_seconds > 0 &&
      ss__now() - r->t_start > r->o.max_seconds)
    r->stopped = SS_ELIMIT_TIME;
  if (!r->stopped && r->o.cancelled && r->o.cancelled(r->o.cancel_cls))
    r->stopped = SS_ECANCELED;
  return r->stopped != 0;
}

/* over_budget() from any thread: the stop of the runner's polls. */
static int must_stop(void *cls) {
  runner *r = cls;
  pthread_mutex_lock(&r->lock);
  int stop = over_budget(r);
  pthread_mutex_unlock(&r->lock);
  return stop;
}

static void *worker(void *arg) {
  runner *r = arg;
  const ss_basin_opts *o = &r->o;
  int n1 = o->n[1];
  long returns = 0;
  int max_seen = 0;
  ss__poll poll = {must_stop, r, 0, 0};
  for (;;) {
    pthread_mutex_lock(&r->lock);
    int i = -1;
    if (!over_budget(r) && r->next_row < r->end_row)
      i = r->next_row++;
    pthread_mutex_unlock(&r->lock);
    if (i < 0)
      break;
    for (int j = 0; j < n1 && !poll.stopped; j++) {
      unsigned char *lab = &r->b->labels[(size_t)i * (size_t)n1 + (size_t)j];
      if (r->only_unresolved && *lab != SS_BASIN_UNRESOLVED)
        continue;
      double x[4], s[2];
      memcpy(x, o->state, sizeof x);
      x[o->vary[0]] = axis_value(o, 0, i);
      x[o->vary[1]] = axis_value(o, 1, j);
      int n = 0, l = follow(r, x, &poll, &n, s);
      *lab = (unsigned char)l;
      returns += n;
      if (n > max_seen && l < SS_BASIN_MAX_ATTRACTORS)
        max_seen = n;
    }
  }
  pthread_mutex_lock(&r->lock);
  r->b->returns += returns;
  if (max_seen > r->b->max_returns)
    r->b->max_returns = max_seen;
  pthread_mutex_unlock(&r->lock);
  return NULL;
}

/* Rows @a from to @a to (excluded), on the options' threads. */
static void run_rows(runner *r, int from, int to) {
  pthread_t th[BASIN_MAX_THREADS];
  int nt = r->o.threads < 1                   ? 1
           : r->o.threads > BASIN_MAX_THREADS ? BASIN_MAX_THREADS
                                              : r->o.threads;
  int started = 0;
  r->next_row = from;
  r->end_row = to;
  for (int t = 1; t < nt; t++)
    if (pthread_create(&th[started], NULL, worker, r) == 0)
      started++;
  worker(r);
  for (int t = 0; t < started; t++)
    pthread_join(th[t], NULL);
}

/* The periods the contraction check may take for the orbit @a o: twice
 * those its linearisation takes, the least j with |J^j| (Frobenius, above
 * the 2-norm) <= BASIN_SHRINK / 2, and at least BASIN_MAX_ITERATIONS; 0
 * when that is more than BASIN_ITERATIONS_CAP (a spectral radius above
 * about 0.994: an attractor too slow to certify at a bounded cost).  A
 * multiplier near the unit circle contracts slowly (issue 32's period
 * 25.59 orbit: spectral radius 0.917, a circle shrunk to 0.916 of itself
 * after 8 periods, to 0.892 after 9), and a fixed count of 8 refused such
 * an attractor however small its radius. */
static int check_iterations(const ss_orbit *o) {
  const double(*J)[2] = o->stab.jac;
  double P[2][2] = {{J[0][0], J[0][1]}, {J[1][0], J[1][1]}};
  for (int j = 1; 2 * j <= BASIN_ITERATIONS_CAP; j++) {
    if (hypot(hypot(P[0][0], P[0][1]), hypot(P[1][0], P[1][1])) <=
        0.5 * BASIN_SHRINK)
      return 2 * j > BASIN_MAX_ITERATIONS ? 2 * j : BASIN_MAX_ITERATIONS;
    double Q[2][2];
    for (int r = 0; r < 2; r++)
      for (int c = 0; c < 2; c++)
        Q[r][c] = P[r][0] * J[0][c] + P[r][1] * J[1][c];
    memcpy(P, Q, sizeof P);
  }
  return 0;
}

/* The returns of the orbit @a o (its start and P of it, k - 1 times), and
 * the certified radius; 0, or -1 when the orbit cannot be an attractor
 * here (more turns than room, or the check fails at every radius) or when
 * @a poll says stop.  The samples of each radius are carried one period
 * (P^k) at a time, and the check passes at the first period j at which all
 * are inside. */
static int certify(const ss_model *m, const ss_orbit *o, ss__poll *poll,
                   ss_basin_attractor *a) {
  enum { PER_RETURN = BASIN_CIRCLE + BASIN_CIRCLE / 2 + 1 };
  int k = o->n_turns, max_it = check_iterations(o);
  if (k < 1 || k > SS_BASIN_MAX_TURNS || max_it == 0)
    return -1;
  a->orbit = *o;
  a->n_points = k;
  a->points[0][0] = o->z0[0];
  a->points[0][1] = o->z0[2];
  size_t ev = BASIN_EVENTS_PER_RETURN * (size_t)k;
  for (int i = 1; i < k; i++)
    if (ss__poincare(m, a->points[i - 1], 1, ev, a->points[i], NULL, NULL, NULL,
                     poll) != SS_OK)
      return -1;
  const ss_params *p = &m->p;
  double scale = fmax(p->V, (p->ur - p->us) / p->chi);
  /* no larger than the orbit's smallest feasibility margin: farther out a
   * phase may appear or vanish, and the map change its form */
  double rad = 1e-2 * scale;
  if (o->min_margin.value > 0 && o->min_margin.value < rad)
    rad = o->min_margin.value;
  double e[SS_BASIN_MAX_TURNS][PER_RETURN][2];
  for (int h = 0; h < BASIN_HALVINGS && !poll->stopped; h++, rad *= 0.25) {
    /* the circle, a circle of half the radius, and the centre */
    for (int i = 0; i < k; i++)
      for (int q = 0; q < PER_RETURN; q++) {
        int outer = q < BASIN_CIRCLE;
        double ang = outer ? 6.283185307179586 * q / BASIN_CIRCLE
                           : 12.566370614359172 * (q - BASIN_CIRCLE + 0.5) /
                                 BASIN_CIRCLE;
        double u = q == PER_RETURN - 1 ? 0 : outer ? rad : 0.5 * rad;
        e[i][q][0] = a->points[i][0] + u * cos(ang);
        e[i][q][1] = a->points[i][1] + u * sin(ang);
      }
    int failed = 0;
    for (int it = 1; it <= max_it && !failed && !poll->stopped; it++) {
      int inside = 1;
      for (int i = 0; i < k && !failed; i++)
        for (int q = 0; q < PER_RETURN && !failed; q++) {
          failed = ss__poincare(m, e[i][q], k, ev, e[i][q], NULL, NULL, NULL,
                                poll) != SS_OK;
          inside = inside &&
                   hypot(e[i][q][0] - a->points[i][0],
                         e[i][q][1] - a->points[i][1]) < BASIN_SHRINK * rad;
        }
      if (!failed && inside) {
        a->radius = rad;
        a->iterations = it;
        return 0;
      }
    }
  }
  return -1;
}

/* Is @a o (a stable orbit) one of the attractors already?  Its start
 * within the certified radius of an attractor's return is that attractor,
 * or that attractor travelled several times (a motion settling slowly on
 * it can repeat after k turns to the finder's tolerance before it does
 * after one): no other periodic orbit is inside a radius every motion from
 * which is drawn to the attractor. */
static int known(const ss_basins *b, const ss_orbit *o) {
  double s[2] = {o->z0[0], o->z0[2]};
  return landed(b, s) >= 0;
}

static int add_attractor(const ss_model *m, ss_basins *b, const ss_orbit *o,
                         int from_simulation, ss__poll *poll) {
  if (!o->stab.stable || o->stab.marginal || known(b, o) ||
      b->n_attractors == SS_BASIN_MAX_ATTRACTORS)
    return 0;
  ss_basin_attractor a;
  memset(&a, 0, sizeof a);
  if (certify(m, o, poll, &a) != 0)
    return 0;
  a.from_simulation = from_simulation;
  b->attractors[b->n_attractors++] = a;
  return 1;
}

/* The stable orbit of k turns, k up to max_period, that Newton on the
 * return map P^k (the orbit search's, ss__map_newton()) reaches from the
 * return @a s of a motion that did not settle, added as an attractor: 1 if
 * one was. */
static int from_newton(runner *r, const double s[2], ss__poll *poll) {
  for (int k = 1; k <= r->o.max_period && !poll->stopped; k++) {
    double f[2] = {s[0], s[1]}, dur[SS_MAX_PHASES];
    ss_mode modes[SS_MAX_PHASES];
    int n;
    ss_orbit orb;
    if (ss__map_newton(r->m, f, k, modes, dur, &n) != 0 ||
        !ss__minimal_period(r->m, f, k) ||
        ss_orbit_solve(r->m, n, modes, dur, NULL, &orb, NULL) != SS_OK)
      continue;
    orb.source = SS_SOURCE_MAP_NEWTON;
    if (add_attractor(r->m, r->b, &orb, 1, poll))
      return 1;
  }
  return 0;
}

/* The periodic attractor a motion that landed nowhere, its last return
 * @a s, settles on, simulated on: 1 if it was added. */
static int from_settling(runner *r, const double s[2], ss__poll *poll) {
  ss_attractor at;
  if (ss__attractor_from(r->m, s, BASIN_SETTLE_TURNS, r->o.max_period, poll,
                         &at) != SS_OK ||
      !at.found || at.n_phases > SS_MAX_PHASES)
    return 0;
  ss_orbit orb;
  if (ss_orbit_solve(r->m, at.n_phases, at.modes, at.durations, NULL, &orb,
                     NULL) != SS_OK)
    return 0;
  orb.source = SS_SOURCE_SIMULATION;
  return add_attractor(r->m, r->b, &orb, 1, poll);
}

/* The cells still unresolved: from each one's last return, Newton on the
 * return map, then its motion simulated on; the first stable orbit either
 * gives is added.  1 if one was (this cell and those like it are then run
 * again). */
static int from_simulation(runner *r) {
  const ss_basin_opts *o = &r->o;
  ss_basins *b = r->b;
  int tried = 0;
  ss__poll poll = {must_stop, r, 0, 0};
  for (int i = 0; i < o->n[0] && !over_budget(r); i++)
    for (int j = 0; j < o->n[1] && tried < 64 && !poll.stopped; j++) {
      size_t c = (size_t)i * (size_t)o->n[1] + (size_t)j;
      if (b->labels[c] != SS_BASIN_UNRESOLVED)
        continue;
      double x[4], s[2];
      memcpy(x, o->state, sizeof x);
      x[o->vary[0]] = axis_value(o, 0, i);
      x[o->vary[1]] = axis_value(o, 1, j);
      int n = 0;
      if (follow(r, x, &poll, &n, s) != SS_BASIN_UNRESOLVED || n == 0)
        continue;
      tried++;
      if (from_newton(r, s, &poll) || from_settling(r, s, &poll))
        return 1;
    }
  return 0;
}

/* ---- the stages ----------------------------------------------------------
 *
 * A basin map is made in three stages, each a function below, and
 * ss_basins_run() is their composition:
 *   0  the attractors of the orbit search, certified (ss_basins_attractors);
 *   1  the cells of any rows, labelled against those attractors alone, the
 *      rows independent of one another (ss_basins_rows);
 *   2  the attractors from simulation over the cells no row resolved, those
 *      cells labelled again after each, and the counts (ss_basins_finish).
 * A label of stage 1 depends on its cell and the attractors of stage 0
 * only, so rows done in any order, in any process, give the same labels;
 * stage 2 reads every label and goes through the cells in row-major order.
 */

/* @a in checked, with its defaults, into @a o: SS_OK or SS_EINVAL. */
static int opts_check(const ss_basin_opts *in, ss_basin_opts *o, ss_diag *d) {
  *o = *in;
  if (o->max_period == 0)
    o->max_period = 4;
  if (o->max_period < 1 || o->max_period > SS_BASIN_MAX_TURNS)
    return ss__fail(d, SS_EINVAL, "max_period", o->max_period,
                    "max_period is 1..%d", SS_BASIN_MAX_TURNS);
  if (o->max_returns < 0)
    return ss__fail(d, SS_EINVAL, "max_returns", o->max_returns,
                    "max_returns is >= 0");
  for (int a = 0; a < 2; a++) {
    if (o->vary[a] < 0 || o->vary[a] > 3 || o->n[a] < 1 ||
        !isfinite(o->from[a]) || !isfinite(o->to[a]) ||
        (o->n[a] > 1 && !(o->from[a] != o->to[a])))
      return ss__fail(d, SS_EINVAL, "axes", a,
                      "axis %d: a state variable 0..3, n >= 1, finite ends "
                      "that differ when n > 1",
                      a);
  }
  if (o->vary[0] == o->vary[1])
    return ss__fail(d, SS_EINVAL, "axes", 1,
                    "the two axes vary the same state variable");
  for (int k = 0; k < 4; k++)
    if (!isfinite(o->state[k]))
      return ss__fail(d, SS_EINVAL, "state", k, "the state must be finite");
  if ((double)o->n[0] * (double)o->n[1] > 1e9)
    return ss__fail(d, SS_EINVAL, "axes", 0, "too many cells");
  return SS_OK;
}

int ss_basins_alloc(const ss_basin_opts *opts, ss_basins *b, ss_diag *d) {
  if (!b)
    return ss__fail(d, SS_EINVAL, "basins", 0, "missing output");
  memset(b, 0, sizeof *b);
  if (!opts)
    return ss__fail(d, SS_EINVAL, "basins", 0, "missing options");
  ss_basin_opts o;
  int rc = opts_check(opts, &o, d);
  if (rc)
    return rc;
  size_t cells = (size_t)o.n[0] * (size_t)o.n[1];
  b->n[0] = o.n[0];
  b->n[1] = o.n[1];
  b->attractors = calloc(SS_BASIN_MAX_ATTRACTORS, sizeof *b->attractors);
  b->labels = malloc(cells);
  if (!b->attractors || !b->labels) {
    ss_basins_free(b);
    return ss__fail(d, SS_ENOMEM, "", 0, "out of memory for the basins");
  }
  memset(b->labels, SS_BASIN_UNRESOLVED, cells);
  return SS_OK;
}

/* A runner of @a opts over @a b (from ss_basins_alloc() with the same
 * slice), its budget from now: SS_OK or SS_EINVAL. */
static int runner_init(runner *r, const ss_model *m, const ss_basin_opts *opts,
                       ss_basins *b, ss_diag *d) {
  memset(r, 0, sizeof *r);
  if (!m || !opts || !b)
    return ss__fail(d, SS_EINVAL, "basins", 0,
                    "missing model, options or basins");
  int rc = opts_check(opts, &r->o, d);
  if (rc)
    return rc;
  if (!b->labels || !b->attractors || b->n[0] != r->o.n[0] ||
      b->n[1] != r->o.n[1] || b->n_attractors < 0 ||
      b->n_attractors > SS_BASIN_MAX_ATTRACTORS)
    return ss__fail(d, SS_EINVAL, "basins", 0,
                    "the basins were not allocated for this slice");
  r->m = m;
  r->b = b;
  r->max_returns = r->o.max_returns ? r->o.max_returns : BASIN_MAX_RETURNS;
  r->t_start = ss__now();
  pthread_mutex_init(&r->lock, NULL);
  return SS_OK;
}

/* The end of a runner: its stop as the status, SS_OK when none. */
static int runner_end(runner *r, ss_diag *d) {
  pthread_mutex_destroy(&r->lock);
  if (r->stopped == SS_ELIMIT_TIME)
    return ss__fail(d, SS_ELIMIT_TIME, "max_seconds", r->o.max_seconds,
                    "the basins ran out of their %g s budget",
                    r->o.max_seconds);
  if (r->stopped == SS_ECANCELED)
    return ss__fail(d, SS_ECANCELED, "", 0, "the basins were cancelled");
  return SS_OK;
}

/* Stage 0: the attractors the search names, in its order.  SS_OK (also
 * when stopped: r->stopped says so), or the search's failure. */
static int stage_attractors(runner *r, ss_diag *d) {
  ss_basins *b = r->b;
  ss_orbit found[32];
  int nf = 0;
  ss_orbit_opts oo;
  memset(&oo, 0, sizeof oo);
  oo.max_period = r->o.max_period;
  oo.max_seconds = r->o.max_seconds;
  oo.cancelled = r->o.cancelled;
  oo.cancel_cls = r->o.cancel_cls;
  b->n_attractors = 0;
  memset(b->attractors, 0, SS_BASIN_MAX_ATTRACTORS * sizeof *b->attractors);
  int rc = ss_orbit_find(r->m, &oo, found, 32, &nf, NULL, d);
  if (rc == SS_ELIMIT_TIME || rc == SS_ECANCELED)
    r->stopped = rc;
  else if (rc)
    return rc;
  ss__poll poll = {must_stop, r, 0, 0};
  for (int i = 0; i < nf; i++)
    add_attractor(r->m, b, &found[i], 0, &poll);
  return SS_OK;
}

/* Stage 2: attractors from simulation, the cells that land nowhere run
 * again after each; then the counts. */
static void stage_finish(runner *r) {
  ss_basins *b = r->b;
  size_t cells = (size_t)b->n[0] * (size_t)b->n[1];
  r->only_unresolved = 1;
  while (!over_budget(r) && from_simulation(r))
    run_rows(r, 0, b->n[0]);
  b->unresolved = b->perpetual = 0;
  for (int a = 0; a < b->n_attractors; a++)
    b->attractors[a].cells = 0;
  for (size_t c = 0; c < cells; c++) {
    unsigned char l = b->labels[c];
    if (l == SS_BASIN_UNRESOLVED)
      b->unresolved++;
    else if (l == SS_BASIN_PERPETUAL)
      b->perpetual++;
    else if (l < b->n_attractors)
      b->attractors[l].cells++;
  }
}

int ss_basins_attractors(const ss_model *m, const ss_basin_opts *opts,
                         ss_basins *b, ss_diag *d) {
  runner r;
  int rc = runner_init(&r, m, opts, b, d);
  if (rc)
    return rc;
  rc = stage_attractors(&r, d);
  int end = runner_end(&r, d);
  return rc ? rc : end;
}

int ss_basins_rows(const ss_model *m, const ss_basin_opts *opts, ss_basins *b,
                   int row, int rows, ss_diag *d) {
  runner r;
  int rc = runner_init(&r, m, opts, b, d);
  if (rc)
    return rc;
  if (row < 0 || rows < 0 || row > b->n[0] - rows) {
    pthread_mutex_destroy(&r.lock);
    return ss__fail(d, SS_EINVAL, "rows", row,
                    "rows %d to %d are not rows of the slice (0 to %d)", row,
                    row + rows, b->n[0]);
  }
  run_rows(&r, row, row + rows);
  return runner_end(&r, d);
}

int ss_basins_finish(const ss_model *m, const ss_basin_opts *opts, ss_basins *b,
                     ss_diag *d) {
  runner r;
  int rc = runner_init(&r, m, opts, b, d);
  if (rc)
    return rc;
  stage_finish(&r);
  return runner_end(&r, d);
}

int ss_basins_run(const ss_model *m, const ss_basin_opts *opts, ss_basins *b,
                  ss_diag *d) {
  if (!b)
    return ss__fail(d, SS_EINVAL, "basins", 0, "missing output");
  memset(b, 0, sizeof *b);
  if (!m || !opts)
    return ss__fail(d, SS_EINVAL, "basins", 0, "missing model or options");
  int rc = ss_basins_alloc(opts, b, d);
  if (rc)
    return rc;
  /* the three stages under one budget: a stop in one ends the others */
  runner r;
  if ((rc = runner_init(&r, m, opts, b, d)))
    return rc;
  if ((rc = stage_attractors(&r, d))) {
    pthread_mutex_destroy(&r.lock);
    return rc;
  }
  if (!r.stopped)
    run_rows(&r, 0, b->n[0]);
  stage_finish(&r);
  return runner_end(&r, d);
}
