/*
 * test_map_pieces.c: a map made in pieces is the map made whole.
 *
 * ss_map_lattice lists the cells of a map's first full searches; each is
 * made on its own by ss_map_search, in a shuffled order, into a table; the
 * map made by ss_map_run with the table (ss_map_opts.searched) is then
 * compared to the map ss_map_run makes alone, cell for cell, orbit for
 * orbit, every double by its bits (memcmp).  The maps: an overshoot map
 * and a stick-slip map in two dimensions, a map of every kind in two and
 * in one, and a sweep in physical units; some of them make full searches
 * off its lattice too (where families end), which are counted.  And the
 * table is used: the hook is asked for the lattice's cells, and a search
 * taken from the table, not made again, shows in the map when it is
 * altered.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "stickslip.h"
#include "test.h"

/* The table of searches made apart, by cell. */
typedef struct table {
  ss_map_found *found; /* n_cells */
  unsigned char *has;  /* n_cells */
  int asked, given;    /* the hook's calls, and its answers 1 */
} table;

static int searched(void *cls, int cell, ss_map_found *found) {
  table *t = cls;
  t->asked++;
  if (!t->has[cell])
    return 0;
  *found = t->found[cell];
  t->given++;
  return 1;
}

/* Are the two orbits the same, every double by its bits? */
static int same_bits(const ss_map_orbit *a, const ss_map_orbit *b) {
  int n = a->n_phases;
  return a->kind == b->kind && n == b->n_phases &&
         !memcmp(a->modes, b->modes, (size_t)n * sizeof a->modes[0]) &&
         !memcmp(a->durations, b->durations, sizeof a->durations) &&
         !memcmp(&a->period, &b->period, sizeof a->period) &&
         a->n_turns == b->n_turns && !memcmp(a->z0, b->z0, sizeof a->z0) &&
         !memcmp(a->eig_re, b->eig_re, sizeof a->eig_re) &&
         !memcmp(a->eig_im, b->eig_im, sizeof a->eig_im) &&
         !memcmp(&a->spectral_radius, &b->spectral_radius,
                 sizeof a->spectral_radius) &&
         a->stable == b->stable && a->marginal == b->marginal &&
         !memcmp(&a->min_margin.value, &b->min_margin.value, sizeof(double)) &&
         a->min_margin.phase == b->min_margin.phase &&
         !memcmp(&a->min_margin.t, &b->min_margin.t, sizeof(double)) &&
         a->from_cell == b->from_cell;
}

/* The cells where the two maps differ. */
static int differ(const ss_map *a, const ss_map *b) {
  int bad = a->n_cells != b->n_cells || a->searches != b->searches ||
            a->solves != b->solves;
  for (int c = 0; c < a->n_cells && c < b->n_cells; c++) {
    const ss_map_cell *x = &a->cells[c], *y = &b->cells[c];
    int same = x->complete == y->complete && x->n_orbits == y->n_orbits &&
               x->truncated == y->truncated;
    for (int k = 0; same && k < x->n_orbits; k++)
      same = same_bits(&x->orbits[k], &y->orbits[k]);
    bad += !same;
  }
  return bad;
}

typedef struct map_case {
  const char *name;
  int n_axes;
  ss_map_axis axes[2];
  unsigned kinds;
  int search_every;
  int physical;
} map_case;

static const ss_params BASE = {0.2, 4, 0.0724, 0.6178, 1};
/* m1 = 1, k1 + k2 = 1: omega = 1, the dimensionless parameters of BASE */
static const ss_physical PHYS = {1, 0.25, 0.8, 0.2, 0.0724, 0.6178, 1};

/* The searches off the lattice (where families end) of every case. */
static int edges_all;

static void check_case(const map_case *mc, unsigned seed) {
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = mc->kinds;
  mo.search_every = mc->search_every;
  mo.physical = mc->physical ? &PHYS : NULL;
  const ss_params *p = mc->physical ? NULL : &BASE;
  ss_map whole, pieces;
  ss_diag d;
  ASSERT_EQ_INT(ss_map_run(p, mc->n_axes, mc->axes, &mo, &whole, &d), SS_OK);

  /* the lattice's searches, apart, in a shuffled order */
  int n_cells = whole.n_cells, n = 0;
  int *cells = malloc((size_t)n_cells * sizeof *cells);
  table t = {calloc((size_t)n_cells, sizeof *t.found),
             calloc((size_t)n_cells, 1), 0, 0};
  ASSERT_TRUE(cells && t.found && t.has);
  ASSERT_EQ_INT(ss_map_lattice(p, mc->n_axes, mc->axes, &mo, cells, &n, &d),
                SS_OK);
  srand(seed);
  for (int i = n - 1; i > 0; i--) {
    int j = rand() % (i + 1), c = cells[i];
    cells[i] = cells[j];
    cells[j] = c;
  }
  for (int i = 0; i < n; i++) {
    ASSERT_EQ_INT(ss_map_search(p, mc->n_axes, mc->axes, &mo, cells[i],
                                &t.found[cells[i]], &d),
                  SS_OK);
    t.has[cells[i]] = 1;
  }

  /* the map from them, on two threads (the hook on the calling one) */
  mo.searched = searched;
  mo.searched_cls = &t;
  mo.threads = 2;
  ASSERT_EQ_INT(ss_map_run(p, mc->n_axes, mc->axes, &mo, &pieces, &d), SS_OK);
  int edges = whole.searches - n;
  printf("%-10s %4d cells, lattice %3d, %3d edge searches, %5d solves, %d "
         "asked: %d cells differ\n",
         mc->name, n_cells, n, edges, whole.solves, t.asked,
         differ(&whole, &pieces));
  ASSERT_EQ_INT(differ(&whole, &pieces), 0);
  /* every lattice search came from the table; the hook was asked for the
   * edge searches too, and had none of them */
  ASSERT_EQ_INT(t.given, n);
  ASSERT_EQ_INT(t.asked, whole.searches);
  edges_all += edges;
  ss_map_free(&pieces);

  /* a search from the table is taken, not made again: one with an orbit
   * altered (its period off by a bit) shows in the map */
  int with = 0;
  while (with < n && t.found[cells[with]].n_orbits == 0)
    with++;
  ASSERT_TRUE(with < n);
  ss_map_found *f = &t.found[cells[with]];
  f->orbits[0].period = f->orbits[0].period * (1 + 0x1p-52);
  ASSERT_EQ_INT(ss_map_run(p, mc->n_axes, mc->axes, &mo, &pieces, &d), SS_OK);
  ASSERT_TRUE(differ(&whole, &pieces) > 0);
  ss_map_free(&pieces);

  ss_map_free(&whole);
  free(cells);
  free(t.found);
  free(t.has);
}

/* A search given for a cell with more orbits than a search gives is
 * refused, not read past its end. */
static int too_many(void *cls, int cell, ss_map_found *found) {
  (void)cls;
  (void)cell;
  memset(found, 0, sizeof *found);
  found->n_orbits = SS_MAP_FOUND_MAX + 1;
  return 1;
}

static void check_refusals(void) {
  ss_map_axis ax = {SS_PARAM_UR, 0.55, 0.75, 9};
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.searched = too_many;
  ss_map map;
  ss_map_found f;
  ss_diag d;
  int cells[9], n = 0;
  ASSERT_EQ_INT(ss_map_run(&BASE, 1, &ax, &mo, &map, &d), SS_EINVAL);
  ss_map_free(&map);
  ASSERT_EQ_INT(ss_map_search(&BASE, 1, &ax, NULL, 9, &f, &d), SS_EINVAL);
  ASSERT_EQ_INT(ss_map_search(&BASE, 1, &ax, NULL, -1, &f, &d), SS_EINVAL);
  /* a cell out of range: the lattice refuses the map as ss_map_run does */
  ss_map_axis low = {SS_PARAM_UR, 0.01, 0.2, 9};
  ASSERT_EQ_INT(ss_map_lattice(&BASE, 1, &low, NULL, cells, &n, &d),
                SS_EDOMAIN);
  ASSERT_EQ_INT(ss_map_run(&BASE, 1, &low, NULL, &map, &d), SS_EDOMAIN);
  ASSERT_EQ_INT(n, 0);
  ss_map_free(&map);
}

int main(void) {
  gsl_set_error_handler_off();
  static const map_case CASES[] = {
      {"overshoot",
       2,
       {{SS_PARAM_CHI, 0.04, 0.96, 16},
        {SS_PARAM_UR, 0.0724 * 1.5, 0.0724 * 15, 16}},
       SS_ORBIT_OVERSHOOT,
       0,
       0},
      {"stick-slip",
       2,
       {{SS_PARAM_CHI, 0.1, 0.9, 12}, {SS_PARAM_ETA, 0.5, 10, 12}},
       SS_ORBIT_STICKSLIP,
       4,
       0},
      {"all-2d",
       2,
       {{SS_PARAM_CHI, 0.1, 0.5, 8}, {SS_PARAM_UR, 0.3, 1.0, 8}},
       SS_ORBIT_ALL,
       4,
       0},
      {"all-1d", 1, {{SS_PARAM_UR, 0.1, 1.0, 60}}, SS_ORBIT_ALL, 0, 0},
      {"physical", 1, {{SS_PHYS_FR, 0.3, 1.0, 30}}, SS_ORBIT_ALL, 6, 1},
  };
  for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++)
    check_case(&CASES[i], 12345u + (unsigned)i);
  /* the hook was asked for cells off the lattice, and made them itself */
  ASSERT_TRUE(edges_all > 0);
  check_refusals();
  TEST_DONE();
}
