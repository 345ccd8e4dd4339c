/*
 * test_map.c: ss_map_run against the full search at every cell.
 *
 * The n x n existence map of the overshoot orbits of test_existence (ur/us
 * 1.5-15 and chi 0.04-0.96, eta = 4, us = 0.0724, V = 1) is made by
 * ss_map_run on a lattice sparser than the grid (search_every 4, or 3 for a
 * small grid: the default searches every cell), and every cell is searched
 * on its own by
 * ss_orbit_find (what n^2 separate /orbit requests do):
 *  - every orbit the separate searches find is in the map's cell;
 *  - no hole: every orbit of a cell's neighbour, given as a guess at the
 *    cell, either solves to no feasible orbit or to one the cell has;
 *  - every orbit of the map closes: the Poincare map by simulation from its
 *    start returns to it within 1e-8 after its turns;
 *  - a complete cell holds what the search alone finds there, no fewer;
 * and on a 1-D sweep: search_every = 1, the default, makes every cell
 * complete; the lattice of search_every 8 is spread evenly; the time
 * budget and the cancel hook stop a map; axes and parameters out of range
 * are refused; a physical map equals the dimensionless one.
 * Usage: test_map [n]   (default 12; SS_MAP_N overrides)
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/map_holds.h"
#include "stickslip.h"
#include "test.h"

#define MAXO 32

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void test_grid(int N) {
  ss_params base = {0.2, 4, 0.0724, 0.6178, 1};
  ss_map_axis ax[2] = {{SS_PARAM_CHI, 0.04, 0.96, N},
                       {SS_PARAM_UR, 0.0724 * 1.5, 0.0724 * 15, N}};
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = SS_ORBIT_OVERSHOOT;
  mo.search_every = N > 8 ? 4 : 3; /* a lattice sparse for the grid */
  ss_map map;
  ss_diag d;
  double t0 = now();
  ASSERT_EQ_INT(ss_map_run(&base, 2, ax, &mo, &map, &d), SS_OK);
  double t_map = now() - t0;
  ASSERT_EQ_INT(map.n_cells, N * N);
  int with = 0, complete = 0, missing = 0, holes = 0, unclosed = 0, lesser = 0;
  double t_sep = 0;
  ss_orbit out[MAXO];
  for (int c = 0; c < map.n_cells; c++) {
    ss_model m;
    const ss_map_cell *ce = &map.cells[c];
    with += ce->n_orbits > 0;
    complete += ce->complete;
    /* the separate search */
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    oo.kinds = SS_ORBIT_OVERSHOOT;
    int lacking = 0;
    double t1 = now();
    int n = search_cell(&base, &mo, &map, c, &oo, &m, out, MAXO, &lacking);
    t_sep += now() - t1;
    const ss_params p = m.p;
    for (int k = 0; k < lacking; k++) {
      missing++;
      printf("missing: cell %d (chi %.4f ur %.4f) durations [%.6g %.6g "
             "%.6g]\n",
             c, p.chi, p.ur, out[k].durations[0], out[k].durations[1],
             out[k].durations[2]);
    }
    if (ce->complete && ce->n_orbits < n)
      lesser++;
    /* closure by simulation */
    for (int k = 0; k < ce->n_orbits; k++) {
      const ss_map_orbit *q = &ce->orbits[k];
      double s[2] = {q->z0[0], q->z0[2]}, e[2];
      if (ss_poincare(&m, s, q->n_turns, 64 * (size_t)q->n_phases, e, NULL,
                      NULL, NULL) != SS_OK ||
          !(fabs(e[0] - s[0]) + fabs(e[1] - s[1]) < 1e-8 * (1 + fabs(s[0]))))
        unclosed++;
    }
    /* no hole: the neighbours' orbits as guesses here */
    int i = c / N, j = c % N;
    for (int di = -1; di <= 1; di++)
      for (int dj = -1; dj <= 1; dj++) {
        int a = i + di, b = j + dj;
        if ((!di && !dj) || a < 0 || b < 0 || a >= N || b >= N)
          continue;
        const ss_map_cell *nb = &map.cells[a * N + b];
        for (int k = 0; k < nb->n_orbits; k++) {
          const ss_map_orbit *q = &nb->orbits[k];
          ss_orbit o;
          if (ss_orbit_solve(&m, q->n_phases, q->modes, q->durations, NULL, &o,
                             NULL) == SS_OK &&
              !holds(ce, o.n_phases, o.modes, o.durations, o.period)) {
            holes++;
            printf("hole: cell %d (chi %.4f ur %.4f): the orbit of its "
                   "neighbour (%+d, %+d) continues into it\n",
                   c, p.chi, p.ur, di, dj);
          }
        }
      }
  }
  printf("map %dx%d: %d cells with an overshoot orbit, %d complete, %d full "
         "searches, %d solves, %.3f s; separate searches %.3f s (%.1fx); "
         "%d missing, %d holes, %d not closing, %d complete cells short\n",
         N, N, with, complete, map.searches, map.solves, t_map, t_sep,
         t_sep / t_map, missing, holes, unclosed, lesser);
  ASSERT_TRUE(with > 0);
  ASSERT_EQ_INT(missing, 0);
  ASSERT_EQ_INT(holes, 0);
  ASSERT_EQ_INT(unclosed, 0);
  ASSERT_EQ_INT(lesser, 0);
  /* the lattice: cells (0, 0) and (N-1, N-1) were searched */
  ASSERT_TRUE(map.cells[0].complete && map.cells[N * N - 1].complete);
  ss_map_free(&map);
}

static int cancel_now(void *cls) {
  (void)cls;
  return 1;
}

static void test_sweep(void) {
  ss_params base = {0.2, 4, 0.0724, 0.6178, 1};
  ss_map_axis ax = {SS_PARAM_UR, 0.55, 0.75, 9};
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = SS_ORBIT_OVERSHOOT;
  mo.search_every = 1;
  ss_map map;
  ss_diag d;
  ASSERT_EQ_INT(ss_map_run(&base, 1, &ax, &mo, &map, &d), SS_OK);
  ASSERT_EQ_INT(map.n_cells, 9);
  ASSERT_EQ_INT(map.searches, 9);
  int with = 0;
  for (int c = 0; c < 9; c++) {
    ASSERT_TRUE(map.cells[c].complete);
    with += map.cells[c].n_orbits > 0;
  }
  /* the paper's overshoot orbit exists above its grazing (ur ~ 0.62) */
  ASSERT_TRUE(map.cells[0].n_orbits == 0 && map.cells[8].n_orbits == 1);
  ASSERT_TRUE(with >= 4 && with <= 7);
  /* the axis's values are exact at both ends and the middle */
  ASSERT_TRUE(ss_map_value(&map.axes[0], 0) == 0.55 &&
              ss_map_value(&map.axes[0], 8) == 0.75 &&
              ss_map_value(&map.axes[0], 4) == 0.65);

  /* the same sweep in physical units: m1 = 1, k1 + k2 = 1, so omega = 1
   * and the dimensionless parameters are the physical ones (Fr = ur) */
  ss_physical ph = {1, 0.25, 0.8, 0.2, 0.0724, 0.6178, 1};
  ss_map_axis pax = {SS_PHYS_FR, 0.55, 0.75, 9};
  ss_map pm;
  mo.physical = &ph;
  ASSERT_EQ_INT(ss_map_run(NULL, 1, &pax, &mo, &pm, &d), SS_OK);
  for (int c = 0; c < 9; c++) {
    ASSERT_EQ_INT(pm.cells[c].n_orbits, map.cells[c].n_orbits);
    for (int k = 0; k < pm.cells[c].n_orbits; k++)
      ASSERT_NEAR(pm.cells[c].orbits[k].period, map.cells[c].orbits[k].period,
                  1e-9);
  }
  ss_map_free(&pm);
  mo.physical = NULL;
  ss_map_free(&map);

  /* stops: the budget, the cancel hook */
  ss_map_axis big[2] = {{SS_PARAM_CHI, 0.1, 0.9, 40},
                        {SS_PARAM_UR, 0.2, 1.0, 40}};
  mo.search_every = 1;
  mo.max_seconds = 0.05;
  double t0 = now();
  ASSERT_EQ_INT(ss_map_run(&base, 2, big, &mo, &map, &d), SS_ELIMIT_TIME);
  ASSERT_TRUE(now() - t0 < 2);
  ASSERT_TRUE(map.searches < 1600);
  ss_map_free(&map);
  mo.max_seconds = 0;
  mo.cancelled = cancel_now;
  ASSERT_EQ_INT(ss_map_run(&base, 2, big, &mo, &map, &d), SS_ECANCELED);
  ss_map_free(&map);
  mo.cancelled = NULL;

  /* refused: a cell with ur <= us, one parameter twice, no cells */
  ss_map_axis low = {SS_PARAM_UR, 0.05, 0.5, 10};
  ss_diag_clear(&d);
  ASSERT_EQ_INT(ss_map_run(&base, 1, &low, &mo, &map, &d), SS_EDOMAIN);
  ASSERT_TRUE(strstr(d.text, "ur") != NULL);
  ss_map_free(&map);
  ss_map_axis twice[2] = {{SS_PARAM_UR, 0.5, 0.7, 3},
                          {SS_PARAM_UR, 0.5, 0.7, 3}};
  ASSERT_EQ_INT(ss_map_run(&base, 2, twice, &mo, &map, &d), SS_EINVAL);
  ss_map_axis none = {SS_PARAM_UR, 0.5, 0.7, 0};
  ASSERT_EQ_INT(ss_map_run(&base, 1, &none, &mo, &map, &d), SS_EINVAL);
  ss_map_axis flat = {SS_PARAM_UR, 0.5, 0.5, 3};
  ASSERT_EQ_INT(ss_map_run(&base, 1, &flat, &mo, &map, &d), SS_EINVAL);
  ss_map_free(&map);
}

/* Two threads give the map one thread gives. */
static void test_threads(void) {
  ss_params base = {0.2, 4, 0.0724, 0.6178, 1};
  ss_map_axis ax[2] = {{SS_PARAM_CHI, 0.15, 0.35, 6},
                       {SS_PARAM_UR, 0.5, 0.9, 6}};
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = SS_ORBIT_OVERSHOOT;
  mo.search_every = 2;
  ss_map a, b;
  ASSERT_EQ_INT(ss_map_run(&base, 2, ax, &mo, &a, NULL), SS_OK);
  mo.threads = 2;
  ASSERT_EQ_INT(ss_map_run(&base, 2, ax, &mo, &b, NULL), SS_OK);
  ASSERT_EQ_INT(a.searches, b.searches);
  for (int c = 0; c < a.n_cells; c++) {
    ASSERT_EQ_INT(a.cells[c].n_orbits, b.cells[c].n_orbits);
    ASSERT_EQ_INT(a.cells[c].complete, b.cells[c].complete);
    for (int k = 0; k < a.cells[c].n_orbits; k++)
      ASSERT_TRUE(a.cells[c].orbits[k].period == b.cells[c].orbits[k].period);
  }
  ss_map_free(&a);
  ss_map_free(&b);
}

/* EVIDENCE: docs/api/map.md: by default (search_every 0 here, 1 in the
 * API) the full search runs at every cell, so every cell is complete, on a
 * sweep where no orbit exists as on one where a family lives (ur across the
 * overshoot family's grazing). */
static void test_default_every_cell(void) {
  ss_params base = {0.2, 4, 0.0724, 0.6178, 1};
  ss_map_axis ax = {SS_PARAM_UR, 0.3, 0.8, 21};
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = SS_ORBIT_OVERSHOOT;
  ss_map map;
  ASSERT_EQ_INT(ss_map_run(&base, 1, &ax, &mo, &map, NULL), SS_OK);
  int complete = 0, with = 0;
  for (int c = 0; c < map.n_cells; c++) {
    complete += map.cells[c].complete;
    with += map.cells[c].n_orbits > 0;
  }
  ASSERT_EQ_INT(map.searches, 21);
  ASSERT_EQ_INT(complete, 21);
  ASSERT_TRUE(with > 0 && with < 21); /* both kinds of cell were searched */
  ss_map_free(&map);
}

/* EVIDENCE: docs/api/map.md: the lattice of full searches is spread
 * evenly from the first cell to the last, at most search_every apart: on a
 * sweep where no orbit exists (ur below the overshoot family's grazing, so
 * no search where a family ends), the complete cells are the lattice. */
static void test_lattice(void) {
  ss_params base = {0.2, 4, 0.0724, 0.6178, 1};
  ss_map_axis ax = {SS_PARAM_UR, 0.3, 0.5, 50};
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = SS_ORBIT_OVERSHOOT;
  mo.search_every = 8;
  ss_map map;
  ASSERT_EQ_INT(ss_map_run(&base, 1, &ax, &mo, &map, NULL), SS_OK);
  static const int want[] = {0, 7, 14, 21, 28, 35, 42, 49};
  int k = 0, ok = map.n_cells == 50;
  for (int c = 0; c < map.n_cells && ok; c++) {
    ok = map.cells[c].n_orbits == 0;
    if (map.cells[c].complete)
      ok = ok && k < 8 && want[k++] == c;
  }
  ASSERT_TRUE(ok && k == 8);
  ASSERT_EQ_INT(map.searches, 8);
  ss_map_free(&map);
}

/* Is index i of an axis of n cells on the lattice of full searches (every
 * apart at most, spread evenly from the first to the last)? */
static int on_lattice(int i, int n, int every) {
  long span = n - 1, m = (span + every - 1) / every;
  long k = (i * m + span / 2) / span;
  return (k * span + m / 2) / m == i;
}

/* Is a continued orbit of @a c near @a q: its sequence, no phase's
 * duration more than a tenth of q's period away? */
static int has_near(const ss_map_cell *c, const ss_map_orbit *q) {
  for (int k = 0; k < c->n_orbits; k++) {
    const ss_map_orbit *o = &c->orbits[k];
    int near =
        o->from_cell >= 0 && o->n_phases == q->n_phases &&
        !memcmp(o->modes, q->modes, (size_t)q->n_phases * sizeof q->modes[0]);
    for (int i = 0; near && i < q->n_phases; i++)
      near = fabs(o->durations[i] - q->durations[i]) < 0.1 * q->period;
    if (near)
      return 1;
  }
  return 0;
}

/* EVIDENCE: docs/api/map.md: a full search runs where a neighbour's
 * orbit does not continue into a cell that holds no orbit near it when
 * the spreading is done; not where such an orbit arrives from another
 * neighbour later in the spreading.  On the 20x20 overshoot map, every cell
 * searched off the lattice lacks, among the orbits continued into it, one
 * near one of its neighbours' orbits (judged at each visit instead, 15 of
 * its 47 edge searches were needless), or holds a family whose multipliers
 * pass +1, -1 or the unit circle on the way to a neighbour. */
static void test_edges(void) {
  enum { N = 20 };
  ss_params base = {0.2, 4, 0.0724, 0.6178, 1};
  ss_map_axis ax[2] = {{SS_PARAM_CHI, 0.04, 0.96, N},
                       {SS_PARAM_UR, 0.0724 * 1.5, 0.0724 * 15, N}};
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = SS_ORBIT_OVERSHOOT;
  mo.search_every = 8;
  mo.threads = 2;
  ss_map map;
  ASSERT_EQ_INT(ss_map_run(&base, 2, ax, &mo, &map, NULL), SS_OK);
  int edges = 0, needless = 0;
  for (int i = 0; i < N; i++)
    for (int j = 0; j < N; j++) {
      const ss_map_cell *c = &map.cells[i * N + j];
      if (!c->complete || (on_lattice(i, N, 8) && on_lattice(j, N, 8)))
        continue;
      edges++;
      int all = 1; /* an orbit near each neighbour's continued in, and no
                      bifurcation */
      for (int di = -1; di <= 1; di++)
        for (int dj = -1; dj <= 1; dj++) {
          int a = i + di, b = j + dj;
          if ((!di && !dj) || a < 0 || b < 0 || a >= N || b >= N)
            continue;
          const ss_map_cell *nb = &map.cells[a * N + b];
          for (int t = 0; t < nb->n_orbits; t++)
            all = all && has_near(c, &nb->orbits[t]);
          all = all && !bifurcates(c, nb);
        }
      needless += all;
    }
  printf("edges: %d full searches, %d off the lattice, %d needless\n",
         map.searches, edges, needless);
  ASSERT_TRUE(edges > 0);
  ASSERT_EQ_INT(needless, 0);
  ss_map_free(&map);
}

int main(int argc, char **argv) {
  const char *env = getenv("SS_MAP_N");
  int N = env ? atoi(env) : argc > 1 ? atoi(argv[1]) : 12;
  test_sweep();
  test_default_every_cell();
  test_lattice();
  test_edges();
  test_threads();
  test_grid(N < 3 ? 3 : N);
  TEST_DONE();
}
