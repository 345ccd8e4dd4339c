/*
 * map.c: the periodic orbits over a grid of one or two parameters.
 *
 * By default (search_every 1) the full search (ss_orbit_find with the map's
 * kinds, max_period and effort) runs at every cell, so a map holds in each
 * cell every orbit that search finds there: no rule that decides from a
 * cell's neighbours where to search found every orbit (below; the measured
 * rules are in docs/api/map.md), for an island may be born in a cell whose
 * neighbours hold no orbit of the map's kinds, and nothing there tells of
 * it.  Continuation then adds the orbits of families it carries into cells
 * whose own search missed them.
 *
 * A full search costs milliseconds; a solve from a guess tens of
 * microseconds.  So a map may instead run the full search on a lattice of
 * cells (search_every > 1: spread evenly along each axis, at most
 * search_every apart), and every orbit
 * found anywhere is then continued into each neighbouring cell as a guess
 * (ss_orbit_find from a guess: solved, checked feasible, a repetition of a
 * shorter orbit reduced to it).  A cell that gains an orbit puts its
 * neighbours back on the work list, so a family spreads over every cell of
 * its region that it reaches from a cell where it was found, around corners
 * and across the whole grid.  A neighbour's orbit that does not continue
 * into a cell that, when the spreading is done, holds no orbit near it
 * marks the edge of a family (a grazing, a fold): the full search runs there
 * too, for what begins where another family ends, and the spreading goes on
 * from what it finds.
 *
 * An orbit that does not continue into a neighbour, or continues to one
 * far from it (another family: that orbit is kept too), marks an end where
 * the cell holds no orbit near it, not where it holds none of its
 * sequence: one family of a sequence may begin where another of the same
 * sequence ends (on the 30x30 stick-slip map in chi and eta at us 0.1,
 * ur 0.6, the rule by sequence, with the skip below, missed 27 of the 2417
 * orbits separate searches find; this one misses 3, each of a family that
 * lives in 1 or 2 cells only).
 *
 * Where a family a cell holds bifurcates between it and a neighbour, the
 * full search runs at both, when neither the lattice nor an end has
 * searched them: a family of one or two cells (an island) is born at a
 * fold, a period doubling or a torus of another, so a multiplier of the
 * family it is born from passes +1, -1 or the unit circle there (the map's
 * own orbits tell where: test functions of their multipliers, as
 * continuation locates special points, change sign between two cells).  On
 * the 30x30 map above this finds the 3 islands (795 full searches; every
 * cell's search: 900); an island where no family the map holds bifurcates
 * (a region without orbits of the map's kinds) is found only by a search
 * at its cell (search_every 1).
 *
 * Each neighbour's orbits are tried once per cell (a cell remembers how
 * many of each neighbour's orbits it has tried; orbits are only ever
 * appended), the one continued from the cell itself too (it was skipped):
 * where that continuation jumped to another family, it solved back need
 * not give the orbit it came from (the 30x30 map's cell at chi 0.1724,
 * eta 0.5 lacked its stable orbit [18.05922, 6.75598] so).
 *
 * A map can be made in pieces: the full searches of its lattice
 * (ss_map_lattice) each made on its own (ss_map_search, anywhere, in any
 * order), then handed to ss_map_run (ss_map_opts.searched), which takes a
 * search it is given where it would have made it.  A search is what the
 * search of a cell found (ss_map_found), before the cell takes it: the cell
 * takes it by the one function that takes every orbit (add), whichever way
 * the search was made, so the map is the same bit for bit.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"
#include "params.h"
#include "search.h"

#define MAP_SEARCH_EVERY 1
#define MAP_MAX_ORBITS 16
#define MAP_MAX_CELLS (1 << 24)
#define MAP_MAX_THREADS 64
/* A continued orbit is near the one it came from when no phase's duration
 * moved by more than this part of the period (a cell's step moves a family
 * by a few per cent, a jump to another family by tens). */
#define MAP_NEAR 0.1

/* A cell while the map is made. */
typedef struct work {
  int tried[8]; /* of each neighbour's orbits, how many were tried */
  unsigned char queued, searched, ended, bifurcates;
} work;

/* A neighbour's orbit that did not continue into a cell: orbit t of cell
 * nb, tried in cell. */
typedef struct failure {
  int cell, nb, t;
} failure;

typedef struct mapper {
  const ss_params *p;
  const ss_map_opts *o;
  ss_map *map;
  work *w;
  int *queue; /* a ring of the cells to visit */
  int head, count;
  unsigned kinds;
  int max_period, effort, max_orbits, threads;
  failure *failed; /* since the last edge searches */
  int n_failed, max_failed;
  double t_start;
  int stopped;
} mapper;

/* Whether index i of an axis of n cells is on the lattice of full
 * searches: m + 1 indices spread evenly from the first to the last, m =
 * ceil((n - 1) / every), so that none is more than every apart (as many
 * as every-th and the last would be, without the last two side by side). */
static int on_lattice(int i, int n, int every) {
  if (n <= 1)
    return 1;
  long span = n - 1, m = (span + every - 1) / every;
  long k = (i * m + span / 2) / span; /* the nearest lattice index */
  return (k * span + m / 2) / m == i;
}

double ss_map_value(const ss_map_axis *a, int i) {
  if (a->n <= 1)
    return a->from;
  /* exact at both ends, and at the middle of an odd count */
  double k = (double)(a->n - 1);
  return (a->from * (k - (double)i) + a->to * (double)i) / k;
}

static int axis_name_ok(const ss_map_opts *o, int param) {
  return o && o->physical ? ss_phys_name((ss_phys_id)param) != NULL
                          : ss_param_name((ss_param_id)param) != NULL;
}

static const char *axis_name(const ss_map_opts *o, int param) {
  return o && o->physical ? ss_phys_name((ss_phys_id)param)
                          : ss_param_name((ss_param_id)param);
}

int ss_map_params(const ss_params *p, const ss_map_opts *opts,
                  const ss_map *map, int cell, ss_params *out, double *omega,
                  ss_diag *d) {
  if (!map || !out || cell < 0 || cell >= map->n_cells ||
      (!p && !(opts && opts->physical)))
    return ss__fail(d, SS_EINVAL, "cell", cell, "no such cell");
  int idx[2] = {cell, 0};
  if (map->n_axes == 2) {
    idx[0] = cell / map->axes[1].n;
    idx[1] = cell % map->axes[1].n;
  }
  if (omega)
    *omega = 1;
  if (opts && opts->physical) {
    ss_physical ph = *opts->physical;
    for (int a = 0; a < map->n_axes; a++)
      *ss__phys_ref(&ph, (ss_phys_id)map->axes[a].param) =
          ss_map_value(&map->axes[a], idx[a]);
    return ss_params_from_physical(&ph, out, omega, d);
  }
  *out = *p;
  for (int a = 0; a < map->n_axes; a++)
    *ss__param_ref(out, (ss_param_id)map->axes[a].param) =
        ss_map_value(&map->axes[a], idx[a]);
  return ss_params_check(out, d);
}

void ss_map_free(ss_map *map) {
  if (!map)
    return;
  for (int i = 0; map->cells && i < map->n_cells; i++)
    free(map->cells[i].orbits);
  free(map->cells);
  memset(map, 0, sizeof *map);
}

static int over_budget(mapper *mp) {
  const ss_map_opts *o = mp->o;
  if (!mp->stopped && o->max_seconds > 0 &&
      ss__now() - mp->t_start > o->max_seconds)
    mp->stopped = SS_ELIMIT_TIME;
  if (!mp->stopped && o->cancelled && o->cancelled(o->cancel_cls))
    mp->stopped = SS_ECANCELED;
  return mp->stopped != 0;
}

/* The neighbour of @a cell in direction @a k (0..7), or -1. */
static int neighbour(const ss_map *map, int cell, int k) {
  static const int DI[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
  static const int DJ[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
  if (map->n_axes == 1) {
    if (k != 3 && k != 4)
      return -1;
    int j = cell + DJ[k];
    return j >= 0 && j < map->n_cells ? j : -1;
  }
  int n1 = map->axes[1].n, i = cell / n1 + DI[k], j = cell % n1 + DJ[k];
  if (i < 0 || i >= map->axes[0].n || j < 0 || j >= n1)
    return -1;
  return i * n1 + j;
}

static void enqueue(mapper *mp, int cell) {
  if (cell < 0 || mp->w[cell].queued)
    return;
  mp->w[cell].queued = 1;
  mp->queue[(mp->head + mp->count) % mp->map->n_cells] = cell;
  mp->count++;
}

static void enqueue_neighbours(mapper *mp, int cell) {
  for (int k = 0; k < 8; k++)
    enqueue(mp, neighbour(mp->map, cell, k));
}

/* The parts of a map orbit ss__same_orbit reads. */
static void as_orbit(const ss_model *m, const ss_map_orbit *a, ss_orbit *o) {
  o->n_phases = a->n_phases;
  memcpy(o->modes, a->modes, sizeof o->modes);
  memcpy(o->durations, a->durations, sizeof o->durations);
  o->period = a->period;
  memcpy(o->z0, a->z0, sizeof o->z0);
  memcpy(o->x0, a->z0, sizeof o->x0);
  o->x0[0] += m->d0[0];
  o->x0[1] += m->d0[1];
}

/* The map orbit of @a o, continued from @a from_cell (-1: searched). */
static void to_map_orbit(const ss_orbit *o, int from_cell, ss_map_orbit *a) {
  memset(a, 0, sizeof *a);
  a->kind = o->kind;
  a->n_phases = o->n_phases;
  /* the phases alone: what follows them stays zero */
  memcpy(a->modes, o->modes, (size_t)o->n_phases * sizeof a->modes[0]);
  memcpy(a->durations, o->durations,
         (size_t)o->n_phases * sizeof a->durations[0]);
  a->period = o->period;
  a->n_turns = o->n_turns;
  memcpy(a->z0, o->z0, sizeof a->z0);
  for (int k = 0; k < 2; k++) {
    a->eig_re[k] = o->stab.eig_re[k];
    a->eig_im[k] = o->stab.eig_im[k];
  }
  a->spectral_radius = o->stab.spectral_radius;
  a->stable = o->stab.stable;
  a->marginal = o->stab.marginal;
  a->min_margin = o->min_margin;
  a->from_cell = from_cell;
}

/* Add @a a to @a cell unless it holds it already; 1 if added. */
static int add(mapper *mp, const ss_model *m, int cell, const ss_map_orbit *a) {
  ss_map_cell *c = &mp->map->cells[cell];
  if (!(mp->kinds & a->kind) || a->n_turns > mp->max_period)
    return 0;
  double tol = 1e-6 * fmax(m->p.V, (m->p.ur - m->p.us) / m->p.chi);
  ss_orbit o;
  as_orbit(m, a, &o);
  for (int i = 0; i < c->n_orbits; i++) {
    ss_orbit q;
    as_orbit(m, &c->orbits[i], &q);
    if (ss__same_orbit(m, &o, &q, tol))
      return 0;
  }
  if (c->n_orbits == mp->max_orbits) {
    c->truncated++;
    return 0;
  }
  if (c->n_orbits % 4 == 0) {
    ss_map_orbit *g =
        realloc(c->orbits, (size_t)(c->n_orbits + 4) * sizeof *c->orbits);
    if (!g) {
      mp->stopped = SS_ENOMEM;
      return 0;
    }
    c->orbits = g;
  }
  /* appended: the neighbours count what they tried in this order; sorted
   * when the map is done */
  c->orbits[c->n_orbits++] = *a;
  return 1;
}

static int by_kind_period(const void *a, const void *b) {
  const ss_map_orbit *x = a, *y = b;
  if (x->kind != y->kind)
    return x->kind < y->kind ? -1 : 1;
  return x->period < y->period ? -1 : x->period > y->period ? 1 : 0;
}

static int model_of(mapper *mp, int cell, ss_model *m, ss_diag *d) {
  ss_params q;
  int rc = ss_map_params(mp->p, mp->o, mp->map, cell, &q, NULL, d);
  return rc ? rc : ss_model_init(m, &q, d);
}

/* The full search at @a cell into @a f (ss_map_search), and the cell's
 * model into @a m; @a out: room for the search's orbits. */
static void search_one(mapper *mp, int cell, ss_model *m, ss_orbit *out,
                       ss_map_found *f) {
  ss_diag_clear(&f->diag);
  f->n_orbits = 0;
  if ((f->status = model_of(mp, cell, m, &f->diag)) != SS_OK)
    return;
  ss_orbit_opts oo;
  memset(&oo, 0, sizeof oo);
  oo.kinds = mp->kinds;
  oo.max_period = mp->max_period;
  oo.effort = mp->effort;
  oo.cancelled = mp->o->cancelled;
  oo.cancel_cls = mp->o->cancel_cls;
  if (mp->o->max_seconds > 0) {
    oo.max_seconds = mp->o->max_seconds - (ss__now() - mp->t_start);
    if (!(oo.max_seconds > 0)) {
      f->status = SS_ELIMIT_TIME;
      return;
    }
  }
  f->status = ss_orbit_find(m, &oo, out, SS_MAP_FOUND_MAX, &f->n_orbits, NULL,
                            &f->diag);
  for (int i = 0; i < f->n_orbits; i++)
    to_map_orbit(&out[i], -1, &f->orbits[i]);
}

/* A full search, made on any thread (or given: opts->searched), its
 * orbits added on the map's. */
typedef struct job {
  int cell, given;
  ss_model m;
  ss_map_found f;
  ss_orbit out[SS_MAP_FOUND_MAX];
} job;

typedef struct pool {
  mapper *mp;
  job *jobs;
  int n, next;
  pthread_mutex_t lock;
} pool;

static void run_job(mapper *mp, job *jb) {
  if (!jb->given)
    search_one(mp, jb->cell, &jb->m, jb->out, &jb->f);
  else if (model_of(mp, jb->cell, &jb->m, NULL) != SS_OK)
    jb->f.n_orbits = 0; /* as the search itself, which stopped there */
}

static void *worker(void *arg) {
  pool *pl = arg;
  for (;;) {
    pthread_mutex_lock(&pl->lock);
    int i = pl->next < pl->n ? pl->next++ : -1;
    pthread_mutex_unlock(&pl->lock);
    if (i < 0)
      return NULL;
    run_job(pl->mp, &pl->jobs[i]);
  }
}

/* Whether opts->searched gives the search of @a jb's cell, on the map's
 * thread (the hook need not be thread-safe); SS_EINVAL in mp->stopped when
 * what it gives is no search. */
static int given(mapper *mp, job *jb, ss_diag *d) {
  const ss_map_opts *o = mp->o;
  if (!o->searched || !o->searched(o->searched_cls, jb->cell, &jb->f))
    return 0;
  if (jb->f.n_orbits < 0 || jb->f.n_orbits > SS_MAP_FOUND_MAX) {
    mp->stopped = ss__fail(d, SS_EINVAL, "searched", jb->f.n_orbits,
                           "the search given for cell %d has %d orbits",
                           jb->cell, jb->f.n_orbits);
    return 0;
  }
  return 1;
}

/* Take the search of @a jb into its cell; the map's first failure, other
 * than the time budget and a cancel (which stop it), into *rc and @a d. */
static void take(mapper *mp, const job *jb, int *rc, ss_diag *d) {
  mp->w[jb->cell].searched = 1;
  mp->map->searches++;
  int gained = 0;
  for (int o = 0; o < jb->f.n_orbits; o++)
    gained += add(mp, &jb->m, jb->cell, &jb->f.orbits[o]);
  if (gained)
    enqueue_neighbours(mp, jb->cell);
  if (jb->f.status == SS_OK)
    mp->map->cells[jb->cell].complete = 1;
  else if (jb->f.status == SS_ELIMIT_TIME || jb->f.status == SS_ECANCELED)
    mp->stopped = jb->f.status;
  else if (*rc == SS_OK) {
    *rc = jb->f.status;
    if (d)
      *d = jb->f.diag;
  }
}

/* The full search at each of the @a n cells, on up to opts->threads
 * threads, or given; their orbits are added in the order of the cells. */
static int search_cells(mapper *mp, const int *cells, int n, ss_diag *d) {
  enum { CHUNK = 64 };
  job *jobs = malloc(CHUNK * sizeof *jobs);
  if (!jobs)
    return mp->stopped = SS_ENOMEM;
  int rc = SS_OK;
  for (int at = 0; at < n && rc == SS_OK && !over_budget(mp); at += CHUNK) {
    int k = n - at < CHUNK ? n - at : CHUNK;
    for (int i = 0; i < k && !mp->stopped; i++) {
      jobs[i].cell = cells[at + i];
      jobs[i].given = given(mp, &jobs[i], d);
    }
    if (mp->stopped)
      break;
    pool pl = {mp, jobs, k, 0, PTHREAD_MUTEX_INITIALIZER};
    int nt = mp->threads < k ? mp->threads : k, started = 0;
    pthread_t th[MAP_MAX_THREADS];
    for (int t = 1; t < nt; t++)
      if (pthread_create(&th[started], NULL, worker, &pl) == 0)
        started++;
    worker(&pl);
    for (int t = 0; t < started; t++)
      pthread_join(th[t], NULL);
    for (int i = 0; i < k; i++)
      take(mp, &jobs[i], &rc, d);
  }
  free(jobs);
  return rc ? rc : mp->stopped;
}

/* Note that orbit t of cell nb did not continue into cell. */
static int note_failure(mapper *mp, int cell, int nb, int t) {
  if (mp->n_failed == mp->max_failed) {
    int n = mp->max_failed ? 2 * mp->max_failed : 256;
    failure *g = realloc(mp->failed, (size_t)n * sizeof *g);
    if (!g)
      return mp->stopped = SS_ENOMEM;
    mp->failed = g;
    mp->max_failed = n;
  }
  mp->failed[mp->n_failed++] = (failure){cell, nb, t};
  return SS_OK;
}

/* How far an orbit of @a n phases @a modes, @a dur is from the orbit @a q
 * it was solved from: the largest change of a phase's duration over q's
 * period, or 1 when the sequences differ. */
static double distance(int n, const ss_mode *modes, const double *dur,
                       const ss_map_orbit *q) {
  if (n != q->n_phases || memcmp(modes, q->modes, (size_t)n * sizeof *modes))
    return 1;
  double dmax = 0;
  for (int k = 0; k < n; k++)
    dmax = fmax(dmax, fabs(dur[k] - q->durations[k]));
  return dmax / q->period;
}

static int near(const ss_orbit *o, const ss_map_orbit *q) {
  return distance(o->n_phases, o->modes, o->durations, q) < MAP_NEAR;
}

/* Orbit @a q of a neighbour solved from its durations at model @a m (as
 * /orbit does with it as a guess): 1 and *o, or 0. */
static int continue_orbit(mapper *mp, const ss_model *m, const ss_map_orbit *q,
                          ss_orbit *o) {
  ss_orbit_opts oo;
  memset(&oo, 0, sizeof oo);
  oo.n_guess = q->n_phases;
  memcpy(oo.guess_modes, q->modes, sizeof oo.guess_modes);
  memcpy(oo.guess, q->durations, sizeof oo.guess);
  int n = 0;
  mp->map->solves++;
  if (ss_orbit_find(m, &oo, o, 1, &n, NULL, NULL) == SS_ENOMEM)
    mp->stopped = SS_ENOMEM;
  return n == 1;
}

/* Continue the neighbours' orbits into @a cell. */
static int visit(mapper *mp, int cell, ss_diag *d) {
  ss_model m;
  int rc = model_of(mp, cell, &m, d);
  if (rc)
    return rc;
  work *w = &mp->w[cell];
  int gained = 0;
  for (int k = 0; k < 8 && !mp->stopped; k++) {
    int nb = neighbour(mp->map, cell, k);
    if (nb < 0)
      continue;
    const ss_map_cell *b = &mp->map->cells[nb];
    for (int t = w->tried[k]; t < b->n_orbits; t++) {
      const ss_map_orbit *q = &b->orbits[t];
      ss_orbit o;
      int close = 0;
      if (continue_orbit(mp, &m, q, &o)) {
        ss_map_orbit a;
        to_map_orbit(&o, nb, &a);
        gained += add(mp, &m, cell, &a);
        close = near(&o, q);
      }
      if (mp->stopped)
        return mp->stopped;
      if (!close && note_failure(mp, cell, nb, t))
        return mp->stopped;
    }
    w->tried[k] = b->n_orbits;
  }
  if (gained)
    enqueue_neighbours(mp, cell);
  return SS_OK;
}

/* Mark where families end, once the spreading is done: a cell that a
 * neighbour's orbit did not continue into and that holds no orbit near it
 * (from another neighbour, at any time of the spreading: judged at its
 * end, so the order of the visits does not matter).  Near, not of the same
 * sequence: where one family of a sequence ends another of that sequence
 * may begin, and the cell's other orbit of the sequence says nothing of
 * it. */
static void mark_ends(mapper *mp) {
  for (int f = 0; f < mp->n_failed; f++) {
    const failure *e = &mp->failed[f];
    work *w = &mp->w[e->cell];
    if (w->ended || w->searched)
      continue;
    const ss_map_orbit *q = &mp->map->cells[e->nb].orbits[e->t];
    const ss_map_cell *c = &mp->map->cells[e->cell];
    int has = 0;
    for (int i = 0; i < c->n_orbits && !has; i++)
      has = distance(c->orbits[i].n_phases, c->orbits[i].modes,
                     c->orbits[i].durations, q) < MAP_NEAR;
    w->ended = !has;
  }
  mp->n_failed = 0;
}

/* The test functions of an orbit's multipliers l1, l2 whose zeros are a
 * fold (l = +1: det(J - I)), a period doubling (l = -1: det(J + I)) and a
 * torus (|l| = 1 for a complex pair: det J - 1); each is a product over
 * the two multipliers, so it is real and continuous whether they are real
 * or a complex pair. */
static void bifurcation_tests(const ss_map_orbit *a, double f[3]) {
  double r0 = a->eig_re[0], r1 = a->eig_re[1], im = a->eig_im[0];
  if (im != 0) {
    f[0] = (1 - r0) * (1 - r0) + im * im;
    f[1] = (1 + r0) * (1 + r0) + im * im;
    f[2] = r0 * r0 + im * im - 1;
  } else {
    f[0] = (1 - r0) * (1 - r1);
    f[1] = (1 + r0) * (1 + r1);
    f[2] = r0 * r1 - 1;
  }
}

/* Whether a family of cell @a c bifurcates between it and cell @a nb: an
 * orbit of c and one near it of nb (the same family, a cell's step away)
 * whose test functions differ in sign. */
static int bifurcates(const ss_map *map, int c, int nb) {
  const ss_map_cell *a = &map->cells[c], *b = &map->cells[nb];
  for (int i = 0; i < a->n_orbits; i++) {
    double fa[3];
    bifurcation_tests(&a->orbits[i], fa);
    for (int j = 0; j < b->n_orbits; j++) {
      const ss_map_orbit *q = &b->orbits[j];
      if (distance(q->n_phases, q->modes, q->durations, &a->orbits[i]) >=
          MAP_NEAR)
        continue;
      double fb[3];
      bifurcation_tests(q, fb);
      for (int t = 0; t < 3; t++)
        if ((fa[t] < 0) != (fb[t] < 0))
          return 1;
    }
  }
  return 0;
}

/* Mark the cells between which a family bifurcates (both sides: each is
 * judged with each of its neighbours). */
static void mark_bifurcations(mapper *mp) {
  for (int c = 0; c < mp->map->n_cells; c++)
    for (int k = 0; k < 8 && !mp->w[c].searched && !mp->w[c].bifurcates; k++) {
      int nb = neighbour(mp->map, c, k);
      mp->w[c].bifurcates = nb >= 0 && bifurcates(mp->map, c, nb);
    }
}

/* The cells marked for the full search and not searched yet, into @a
 * todo; how many. */
static int marked(const mapper *mp, int *todo) {
  int n = 0;
  for (int c = 0; c < mp->map->n_cells; c++)
    if ((mp->w[c].ended || mp->w[c].bifurcates) && !mp->w[c].searched)
      todo[n++] = c;
  return n;
}

/* Visit the cells on the work list until it is empty. */
static int spread(mapper *mp, ss_diag *d) {
  while (mp->count > 0 && !over_budget(mp)) {
    int cell = mp->queue[mp->head];
    mp->head = (mp->head + 1) % mp->map->n_cells;
    mp->count--;
    mp->w[cell].queued = 0;
    int rc = visit(mp, cell, d);
    if (rc)
      return rc;
  }
  return mp->stopped;
}

/* The axes: each a parameter the map knows, finite ends, at least one
 * point, the two different; their product (*cells) within the limit. */
static int check_axes(int n_axes, const ss_map_axis *axes,
                      const ss_map_opts *opts, long *cells_out, ss_diag *d) {
  long cells = 1;
  for (int a = 0; a < n_axes; a++) {
    const ss_map_axis *x = &axes[a];
    if (!axis_name_ok(opts, x->param))
      return ss__fail(d, SS_EINVAL, "axes", a, "axis %d: no such parameter", a);
    if (!isfinite(x->from) || !isfinite(x->to) || x->n < 1 ||
        (x->n > 1 && !(x->from != x->to)))
      return ss__fail(d, SS_EINVAL, "axes", a,
                      "axis %d: finite from and to, different when n > 1, "
                      "and n >= 1",
                      a);
    cells *= x->n;
    if (cells > MAP_MAX_CELLS)
      return ss__fail(d, SS_EINVAL, "axes", (double)cells, "more than %d cells",
                      MAP_MAX_CELLS);
  }
  if (n_axes == 2 && axes[0].param == axes[1].param)
    return ss__fail(d, SS_EINVAL, "axes", 1,
                    "the two axes name the same parameter, %s",
                    axis_name(opts, axes[0].param));
  *cells_out = cells;
  return SS_OK;
}

/* The run's status, with its reason in d. */
static int map_status(int rc, const ss_map_opts *opts, ss_diag *d) {
  if (rc == SS_ELIMIT_TIME)
    return ss__fail(d, rc, "max_seconds", opts->max_seconds,
                    "the map ran out of its %g s budget", opts->max_seconds);
  if (rc == SS_ECANCELED)
    return ss__fail(d, rc, "", 0, "the map was cancelled");
  if (rc == SS_ENOMEM)
    return ss__fail(d, rc, "", 0, "out of memory for the map");
  return rc;
}

/* What every entry point does first: the arguments checked, the options
 * with their defaults into @a mp, the shape of @a map (its cells not
 * allocated, their parameters not checked: check_cells). */
static int map_setup(mapper *mp, const ss_params *p, int n_axes,
                     const ss_map_axis *axes, const ss_map_opts *opts,
                     ss_map *map, ss_diag *d) {
  static const ss_map_opts defaults;
  if (!opts)
    opts = &defaults;
  if ((!p && !opts->physical) || !axes)
    return ss__fail(d, SS_EINVAL, "params", 0, "missing parameters or axes");
  if (n_axes < 1 || n_axes > 2)
    return ss__fail(d, SS_EINVAL, "axes", n_axes, "a map has 1 or 2 axes");
  long cells = 0;
  int rc = check_axes(n_axes, axes, opts, &cells, d);
  if (rc)
    return rc;
  if (opts->search_every < 0 || opts->max_orbits < 0)
    return ss__fail(d, SS_EINVAL, "search_every", opts->search_every,
                    "search_every and max_orbits are >= 0");
  memset(mp, 0, sizeof *mp);
  mp->p = p;
  mp->o = opts;
  mp->map = map;
  mp->kinds = opts->kinds ? opts->kinds : SS_ORBIT_ALL;
  mp->max_period = opts->max_period ? opts->max_period : 4;
  mp->effort = opts->effort ? opts->effort : 2;
  mp->max_orbits = opts->max_orbits ? opts->max_orbits : MAP_MAX_ORBITS;
  mp->threads = opts->threads < 1                 ? 1
                : opts->threads > MAP_MAX_THREADS ? MAP_MAX_THREADS
                                                  : opts->threads;
  if (mp->max_period < 1 || mp->max_period > 8 || mp->effort < 1 ||
      mp->effort > 3)
    return ss__fail(d, SS_EINVAL, "max_period", mp->max_period,
                    "max_period is 1..8 and effort 1..3");
  mp->t_start = ss__now();
  map->n_axes = n_axes;
  memcpy(map->axes, axes, (size_t)n_axes * sizeof *axes);
  if (n_axes == 1) /* one column: cell j is (0, j) */
    map->axes[1] =
        (ss_map_axis){axes[0].param, axes[0].from, axes[0].to, axes[0].n};
  map->n_cells = (int)cells;
  return SS_OK;
}

/* Every cell's parameters in range, before any work. */
static int check_cells(const mapper *mp, ss_diag *d) {
  for (int i = 0; i < mp->map->n_cells; i++) {
    ss_params q;
    int rc = ss_map_params(mp->p, mp->o, mp->map, i, &q, NULL, d);
    if (rc != SS_OK)
      return rc;
  }
  return SS_OK;
}

/* The cells of the lattice, row-major, into @a todo; how many. */
static int lattice(const mapper *mp, int *todo) {
  const ss_map *map = mp->map;
  int every = mp->o->search_every ? mp->o->search_every : MAP_SEARCH_EVERY;
  int n0 = map->n_axes == 2 ? map->axes[0].n : 1, n1 = map->axes[1].n, n = 0;
  for (int i = 0; i < n0; i++)
    for (int j = 0; j < n1; j++)
      if ((map->n_axes == 1 || on_lattice(i, n0, every)) &&
          on_lattice(j, n1, every))
        todo[n++] = i * n1 + j;
  return n;
}

int ss_map_lattice(const ss_params *p, int n_axes, const ss_map_axis *axes,
                   const ss_map_opts *opts, int *cells, int *n, ss_diag *d) {
  ss_map map;
  mapper mp;
  memset(&map, 0, sizeof map);
  if (!cells || !n)
    return ss__fail(d, SS_EINVAL, "cells", 0, "missing output");
  int rc = map_setup(&mp, p, n_axes, axes, opts, &map, d);
  if (rc == SS_OK)
    rc = check_cells(&mp, d);
  if (rc == SS_OK)
    *n = lattice(&mp, cells);
  return rc;
}

int ss_map_search(const ss_params *p, int n_axes, const ss_map_axis *axes,
                  const ss_map_opts *opts, int cell, ss_map_found *found,
                  ss_diag *d) {
  ss_map map;
  mapper mp;
  memset(&map, 0, sizeof map);
  if (!found)
    return ss__fail(d, SS_EINVAL, "found", 0, "missing output");
  int rc = map_setup(&mp, p, n_axes, axes, opts, &map, d);
  if (rc)
    return rc;
  if (cell < 0 || cell >= map.n_cells)
    return ss__fail(d, SS_EINVAL, "cell", cell, "no such cell");
  ss_model m;
  ss_orbit *out = malloc(SS_MAP_FOUND_MAX * sizeof *out);
  if (!out)
    return ss__fail(d, SS_ENOMEM, "", 0, "out of memory for the search");
  search_one(&mp, cell, &m, out, found);
  free(out);
  return SS_OK;
}

int ss_map_run(const ss_params *p, int n_axes, const ss_map_axis *axes,
               const ss_map_opts *opts, ss_map *map, ss_diag *d) {
  if (!map)
    return ss__fail(d, SS_EINVAL, "map", 0, "missing output");
  memset(map, 0, sizeof *map);
  mapper mp;
  int rc = map_setup(&mp, p, n_axes, axes, opts, map, d);
  if (rc == SS_OK)
    rc = check_cells(&mp, d);
  if (rc) {
    map->n_cells = 0;
    return rc;
  }
  opts = mp.o;
  size_t cells = (size_t)map->n_cells;
  map->cells = calloc(cells, sizeof *map->cells);
  mp.w = calloc(cells, sizeof *mp.w);
  mp.queue = malloc(cells * sizeof *mp.queue);
  int *todo = malloc(cells * sizeof *todo), n_todo = 0;
  if (!map->cells || !mp.w || !mp.queue || !todo) {
    free(mp.w);
    free(mp.queue);
    free(todo);
    ss_map_free(map);
    return ss__fail(d, SS_ENOMEM, "", 0, "out of memory for the map");
  }
  n_todo = lattice(&mp, todo);
  rc = search_cells(&mp, todo, n_todo, d);
  /* spread; search where families end, or else where they bifurcate;
   * spread what that finds */
  while (rc == SS_OK && (rc = spread(&mp, d)) == SS_OK &&
         !opts->no_edge_search) {
    mark_ends(&mp);
    if ((n_todo = marked(&mp, todo)) == 0) {
      mark_bifurcations(&mp);
      n_todo = marked(&mp, todo);
    }
    if (n_todo == 0)
      break;
    rc = search_cells(&mp, todo, n_todo, d);
  }
  free(todo);
  if (rc == SS_OK)
    rc = mp.stopped;
  for (int c = 0; c < map->n_cells; c++)
    if (map->cells[c].n_orbits > 1)
      qsort(map->cells[c].orbits, (size_t)map->cells[c].n_orbits,
            sizeof(ss_map_orbit), by_kind_period);
  free(mp.w);
  free(mp.queue);
  free(mp.failed);
  return map_status(rc, opts, d);
}
