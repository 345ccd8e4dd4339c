/*
 * test_map_kinds.c: maps of every kind, cell by cell, against the separate
 * search at each cell.
 *
 * EVIDENCE: docs/api/map.md — by default a map holds, in every cell, every
 * orbit /orbit with the map's kind, max_period and effort finds there; with
 * search_every 8 it holds it wherever the family of that orbit reaches a
 * cell the map holds it in.
 *
 * The battery: eight maps, two of each kind (stick-slip, overshoot, other,
 * all), each over one of four parameter planes (chi-eta, us-ur, eta-ur,
 * chi-ur) around a parameter set of its own, drawn by a seeded generator
 * (xorshift64, seed 20261127: the draw is the same on every run, and was
 * not chosen by looking at the maps).  Each map is n x n cells (default 12;
 * SS_MAP_N overrides, smaller under the sanitizers), made by ss_map_run
 * with its defaults and again with search_every 8, and every cell is
 * searched on its own by ss_orbit_find with the map's kinds, max_period
 * and effort (what n^2 separate /orbit requests do).  With the defaults
 * every cell is complete and holds every orbit the separate search finds,
 * and has no hole (below).  With search_every 8, at every cell:
 *  - no hole: every orbit of a neighbour's cell, solved at the cell from its
 *    durations (what /orbit does with it as a guess), gives no feasible
 *    orbit or one the cell holds;
 *  - every orbit the separate search finds is in the cell, unless it is an
 *    island: solved from its durations at each of the eight neighbours, it
 *    gives no orbit that the neighbour's cell holds (no family the map has
 *    reaches it; only a search at the cell itself finds it), and no family
 *    the map holds bifurcates between the cell and a neighbour (a
 *    multiplier through +1, -1 or the unit circle: the map searches there).
 *    Islands are listed, and are at most 1 % of the orbits of the battery.
 * And the reproducer of a hole: the 30 x 30 stick-slip map in chi and eta
 * at us 0.1, ur 0.6, with search_every 8; its cell chi 0.1724137931034483, eta
 * 0.5 holds the stable orbit of durations [18.05922, 6.75598], which the
 * neighbour's orbit, solved there, gives (the orbit the cell had continued into
 * that neighbour, where it jumped to another family: solved back, it is not the
 * one the cell had); and its cells (14, 2), (17, 3), (18, 4) hold the
 * islands that families passing a multiplier through -1 or the unit
 * circle beside them give birth to.
 * Usage: test_map_kinds [n]
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/map_holds.h"
#include "stickslip.h"
#include "test.h"

#define MAXO 32

static uint64_t rng = 20261127u;

/* xorshift64 (Marsaglia 2003): a uniform double in [a, b). */
static double draw(double a, double b) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return a + (b - a) * (double)(rng >> 11) * 0x1p-53;
}

typedef struct tally {
  int orbits, missing, islands, holes;
} tally;

/* The cell of @a map at (i, j), or -1 outside. */
static int cell_at(const ss_map *map, int i, int j) {
  int n0 = map->n_axes == 2 ? map->axes[0].n : 1, n1 = map->axes[1].n;
  return i < 0 || j < 0 || i >= n0 || j >= n1 ? -1 : i * n1 + j;
}

static void model_at(const ss_params *base, const ss_map *map, int c,
                     ss_model *m) {
  ss_params p;
  ASSERT_EQ_INT(ss_map_params(base, NULL, map, c, &p, NULL, NULL), SS_OK);
  ASSERT_EQ_INT(ss_model_init(m, &p, NULL), SS_OK);
}

/* The orbit of @a m that /orbit gives from the guess (n, modes, dur): 1 and
 * *o, or 0. */
static int from_guess(const ss_model *m, int n, const ss_mode *modes,
                      const double *dur, ss_orbit *o) {
  ss_orbit_opts oo;
  int k = 0;
  memset(&oo, 0, sizeof oo);
  oo.n_guess = n;
  memcpy(oo.guess_modes, modes, (size_t)n * sizeof *modes);
  memcpy(oo.guess, dur, (size_t)n * sizeof *dur);
  return ss_orbit_find(m, &oo, o, 1, &k, NULL, NULL) == SS_OK && k == 1;
}

/* Does the orbit (n, modes, dur), solved at each neighbour of cell c, give
 * an orbit that neighbour's cell holds? */
static int reaches_map(const ss_params *base, const ss_map *map, int c, int n,
                       const ss_mode *modes, const double *dur) {
  int n1 = map->axes[1].n, i = c / n1, j = c % n1;
  for (int di = -1; di <= 1; di++)
    for (int dj = -1; dj <= 1; dj++) {
      int b = cell_at(map, i + di, j + dj);
      if ((!di && !dj) || b < 0)
        continue;
      ss_model m;
      ss_orbit o;
      model_at(base, map, b, &m);
      if (from_guess(&m, n, modes, dur, &o) &&
          holds(&map->cells[b], o.n_phases, o.modes, o.durations, o.period))
        return 1;
    }
  return 0;
}

/* Does a family of cell c of @a map bifurcate between c and a neighbour? */
static int bifurcates_near(const ss_map *map, int c) {
  int n1 = map->axes[1].n, i = c / n1, j = c % n1;
  for (int di = -1; di <= 1; di++)
    for (int dj = -1; dj <= 1; dj++) {
      int b = cell_at(map, i + di, j + dj);
      if ((di || dj) && b >= 0 &&
          (bifurcates(&map->cells[c], &map->cells[b]) ||
           bifurcates(&map->cells[b], &map->cells[c])))
        return 1;
    }
  return 0;
}

/* Holes at cell c of @a map (model @a m): every orbit of a neighbour's
 * cell, solved at c from its durations, gives no feasible orbit of the
 * map's kinds or one the cell holds. */
static void check_holes(const ss_map *map, int c, const ss_model *m,
                        const ss_orbit_opts *oo, tally *t) {
  int n1 = map->axes[1].n, i = c / n1, j = c % n1;
  for (int di = -1; di <= 1; di++)
    for (int dj = -1; dj <= 1; dj++) {
      int b = cell_at(map, i + di, j + dj);
      if ((!di && !dj) || b < 0)
        continue;
      for (int k = 0; k < map->cells[b].n_orbits; k++) {
        const ss_map_orbit *q = &map->cells[b].orbits[k];
        ss_orbit o;
        if (from_guess(m, q->n_phases, q->modes, q->durations, &o) &&
            (oo->kinds & o.kind) && o.n_turns <= 4 &&
            !holds(&map->cells[c], o.n_phases, o.modes, o.durations,
                   o.period)) {
          t->holes++;
          printf("  HOLE: cell (%d, %d): the orbit of period %.6f of its "
                 "neighbour (%+d, %+d) gives one it lacks, period %.6f\n",
                 i, j, q->period, di, dj, o.period);
        }
      }
    }
}

/* The cell c of @a map against the separate search with @a oo, into @a t;
 * and, when @a full is not NULL, of @a full against the same search, into
 * @a tf, every orbit it lacks counted as missing. */
static void check_cell(const ss_params *base, const ss_map *map, int c,
                       const ss_orbit_opts *oo, tally *t, const ss_map *full,
                       tally *tf) {
  ss_model m;
  ss_orbit out[MAXO];
  int lacking = 0, n1 = map->axes[1].n, i = c / n1, j = c % n1;
  int n = search_cell(base, NULL, map, c, oo, &m, out, MAXO, &lacking);
  t->orbits += n;
  for (int k = 0; k < lacking; k++) {
    const ss_orbit *o = &out[k];
    /* an island where a family of the map bifurcates is missing: the map
     * searches there */
    int island =
        !reaches_map(base, map, c, o->n_phases, o->modes, o->durations) &&
        !bifurcates_near(map, c);
    t->islands += island;
    t->missing += !island;
    printf("  %s: cell (%d, %d) lacks the %s orbit of period %.6f, "
           "durations [%.6f %.6f ...]\n",
           island ? "island" : "MISSING", i, j,
           o->stab.stable ? "stable" : "unstable", o->period, o->durations[0],
           o->durations[1]);
  }
  check_holes(map, c, &m, oo, t);
  if (!full)
    return;
  tf->orbits += n;
  for (int k = 0; k < n; k++)
    if (!holds(&full->cells[c], out[k].n_phases, out[k].modes, out[k].durations,
               out[k].period)) {
      tf->missing++;
      printf("  MISSING: cell (%d, %d) of the default map lacks the orbit of "
             "period %.6f\n",
             i, j, out[k].period);
    }
  check_holes(full, c, &m, oo, tf);
}

typedef struct plane {
  const char *name;
  int param[2];
} plane;

static void check_map(const char *kind, unsigned kinds, const plane *pl, int N,
                      tally *all) {
  /* a parameter set of its own, and the plane around it */
  ss_params base;
  base.chi = draw(0.15, 0.7);
  base.eta = draw(0.5, 6);
  base.us = draw(0.03, 0.25);
  base.ur = base.us * draw(1.5, 8);
  base.V = 1;
  ss_map_axis ax[2];
  for (int a = 0; a < 2; a++) {
    int q = pl->param[a];
    double lo = 0, hi = 0;
    if (q == SS_PARAM_CHI)
      lo = 0.1, hi = 0.85;
    else if (q == SS_PARAM_ETA)
      lo = 0.3, hi = 8;
    else if (q == SS_PARAM_US) /* below the least ur of the plane */
      lo = 0.02, hi = 0.2;
    else if (pl->param[0] == SS_PARAM_US) /* ur above the most us */
      lo = 0.25, hi = 1.5;
    else
      lo = base.us * 1.3, hi = base.us * 12;
    ax[a] = (ss_map_axis){q, lo, hi, N};
  }
  /* the default (every cell searched), and the sketch of search_every 8 */
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = kinds;
  ss_map map, sketch;
  ss_diag d;
  ASSERT_EQ_INT(ss_map_run(&base, 2, ax, &mo, &map, &d), SS_OK);
  mo.search_every = 8;
  ASSERT_EQ_INT(ss_map_run(&base, 2, ax, &mo, &sketch, &d), SS_OK);
  ss_orbit_opts oo;
  memset(&oo, 0, sizeof oo);
  oo.kinds = kinds; /* the map's max_period (4) and effort (2) by default */
  tally t = {0, 0, 0, 0}, ts = {0, 0, 0, 0};
  int complete = 0;
  printf("%-10s %-6s chi %.4f eta %.4f us %.4f ur %.4f: %d searches, %d "
         "solves; search_every 8: %d searches, %d solves\n",
         kind, pl->name, base.chi, base.eta, base.us, base.ur, map.searches,
         map.solves, sketch.searches, sketch.solves);
  for (int c = 0; c < map.n_cells; c++) {
    complete += map.cells[c].complete;
    check_cell(&base, &sketch, c, &oo, &ts, &map, &t);
  }
  printf("  %d orbits by separate searches: the default map lacks %d "
         "(%d islands), %d holes; search_every 8 lacks %d (%d islands), %d "
         "holes\n",
         t.orbits, t.missing + t.islands, t.islands, t.holes,
         ts.missing + ts.islands, ts.islands, ts.holes);
  /* the default holds every orbit of every cell */
  ASSERT_EQ_INT(complete, map.n_cells);
  ASSERT_EQ_INT(t.missing + t.islands + t.holes, 0);
  /* the sketch: nothing missing but islands, no hole */
  ASSERT_EQ_INT(ts.missing, 0);
  ASSERT_EQ_INT(ts.holes, 0);
  all->orbits += ts.orbits;
  all->islands += ts.islands;
  ss_map_free(&map);
  ss_map_free(&sketch);
}

/* The reproducer: the stable orbit [18.05922, 6.75598] at cell (3, 0). */
static void check_reproducer(void) {
  ss_params base = {0.3, 2, 0.1, 0.6, 1};
  ss_map_axis ax[2] = {{SS_PARAM_CHI, 0.1, 0.8, 30},
                       {SS_PARAM_ETA, 0.5, 8, 30}};
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = SS_ORBIT_STICKSLIP;
  mo.search_every = 8; /* the sketch: the default searches every cell */
  ss_map map;
  ss_diag d;
  ASSERT_EQ_INT(ss_map_run(&base, 2, ax, &mo, &map, &d), SS_OK);
  int c = cell_at(&map, 3, 0);
  ASSERT_TRUE(ss_map_value(&map.axes[0], 3) == 0.1724137931034483 &&
              ss_map_value(&map.axes[1], 0) == 0.5);
  const ss_map_cell *ce = &map.cells[c];
  int found = 0;
  for (int k = 0; k < ce->n_orbits; k++)
    found += ce->orbits[k].n_phases == 2 && ce->orbits[k].stable &&
             fabs(ce->orbits[k].durations[0] - 18.05922) < 1e-5 &&
             fabs(ce->orbits[k].durations[1] - 6.75598) < 1e-5;
  printf("reproducer: %d searches, %d solves; cell (3, 0) holds %d orbits, "
         "the stable [18.05922, 6.75598] %s\n",
         map.searches, map.solves, ce->n_orbits, found ? "among them" : "NOT");
  ASSERT_EQ_INT(found, 1);
  /* and all the separate search finds there, and at the three cells of
   * islands (families of 1-2 cells, born where a family of the map passes
   * a multiplier through +1, -1 or the unit circle) */
  static const int CELLS[4][2] = {{3, 0}, {14, 2}, {17, 3}, {18, 4}};
  ss_orbit_opts oo;
  memset(&oo, 0, sizeof oo);
  oo.kinds = SS_ORBIT_STICKSLIP;
  tally t = {0, 0, 0, 0};
  for (int k = 0; k < 4; k++)
    check_cell(&base, &map, cell_at(&map, CELLS[k][0], CELLS[k][1]), &oo, &t,
               NULL, NULL);
  ASSERT_EQ_INT(t.missing + t.islands, 0);
  ASSERT_EQ_INT(t.holes, 0);
  ss_map_free(&map);
}

int main(int argc, char **argv) {
  int N = argc > 1 ? atoi(argv[1]) : 12;
  const char *env = getenv("SS_MAP_N");
  if (env && atoi(env) > 0)
    N = atoi(env);
  static const plane PLANES[] = {
      {"chi-eta", {SS_PARAM_CHI, SS_PARAM_ETA}},
      {"us-ur", {SS_PARAM_US, SS_PARAM_UR}},
      {"eta-ur", {SS_PARAM_ETA, SS_PARAM_UR}},
      {"chi-ur", {SS_PARAM_CHI, SS_PARAM_UR}},
  };
  static const struct {
    const char *name;
    unsigned kinds;
  } KINDS[] = {{"stick-slip", SS_ORBIT_STICKSLIP},
               {"overshoot", SS_ORBIT_OVERSHOOT},
               {"other", SS_ORBIT_OTHER},
               {"all", SS_ORBIT_ALL}};
  tally all = {0, 0, 0, 0};
  check_reproducer();
  for (int k = 0; k < 4; k++)
    for (int r = 0; r < 2; r++)
      check_map(KINDS[k].name, KINDS[k].kinds, &PLANES[(k + 2 * r) % 4], N,
                &all);
  printf("battery: %d orbits; search_every 8 lacks %d islands\n", all.orbits,
         all.islands);
  ASSERT_TRUE(all.orbits > 0);
  ASSERT_TRUE(100 * all.islands <= all.orbits);
  TEST_DONE();
}
