/*
 * test_basins_staged.c: a basin map made in its stages, as a job makes it,
 * is the map of ss_basins_run().
 *
 * Stage 0 (the attractors) on one map; the rows in groups, each group on a
 * map of its own that holds a copy of stage 0's attractors, the groups in
 * a shuffled order; their labels, returns and max_returns gathered into a
 * last map, on which stage 2 runs.  Its attractors (every field, bit for
 * bit), labels, counts and returns must be those of ss_basins_run(), on
 * one thread and on two, with groups of 1, 3 and 7 rows, on:
 *  - the paper's set over a 12x12 slice (two attractors of the search);
 *  - chi 0.6673, eta 2.5843, us 0.1883, ur 2.4124 over 32x32 cells of the
 *    slice of issue 32 (max_period 8): three attractors of the search, every
 *    cell resolved in stage 1;
 *  - chi 0.4977, eta 0.3593, us 0.1201, ur 0.8447 over 16x16 cells: two
 *    attractors of the search (the slow one, spectral radius 0.978, the
 *    period-4 attractor stage 2 found before the contraction check could
 *    take more than 8 periods: itself travelled four times), and cells
 *    that stage 2 leaves unresolved (they near a period-2 orbit of spectral
 *    radius 0.99987, too slow to certify);
 *  - chi 0.54, eta 4.8436, us 0.0574, ur 0.3402 over 8x8 cells: a 2-turn
 *    attractor the search does not name, found in stage 2 by Newton on the
 *    return map from the last return of a cell that did not settle.
 * The stages also refuse a map of another slice and rows outside it.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stickslip.h"
#include "test.h"

typedef struct slice_case {
  const char *name;
  ss_params p;
  double from[2], to[2];
  int n, max_period;
  int want_simulation; /* an attractor from simulation is expected */
  int want_unresolved; /* cells left unresolved are expected */
  int want_newton;     /* one from Newton on the return map is expected */
} slice_case;

static const slice_case CASES[] = {
    {"paper", {0.2, 4, 0.0724, 0.6178, 1}, {-2, 0}, {4, 8}, 12, 4, 0, 0, 0},
    {"issue 32, 32x32",
     {0.6673, 2.5843, 0.1883, 2.4124, 1},
     {-3.4340246468289752, -5.151842719659786},
     {4.565975353171025, 6.848157280340214},
     32,
     8,
     0,
     0,
     0},
    {"slow attractor",
     {0.4977, 0.3593, 0.1201, 0.8447, 1},
     {-1.456, -1.456},
     {1.456, 2.912},
     16,
     4,
     0,
     1,
     0},
    {"Newton in stage 2",
     {0.54, 4.8436, 0.0574, 0.3402, 1},
     {-1.875, -1.77},
     {2.125, 2.23},
     8,
     4,
     1,
     1,
     1},
};

static void opts_of(const slice_case *c, int threads, ss_basin_opts *o) {
  memset(o, 0, sizeof *o);
  o->vary[0] = 0;
  o->vary[1] = 1;
  for (int a = 0; a < 2; a++) {
    o->from[a] = c->from[a];
    o->to[a] = c->to[a];
    o->n[a] = c->n;
  }
  o->state[2] = 0;
  o->state[3] = 1;
  o->max_period = c->max_period;
  o->threads = threads;
}

#define SAME(f) (memcmp(&x->f, &y->f, sizeof x->f) == 0)
#define SAME_MARGIN(f) (SAME(f.value) && SAME(f.phase) && SAME(f.t))

/* Every field of two attractors, bit for bit (not their padding). */
static int same_attractor(const ss_basin_attractor *x,
                          const ss_basin_attractor *y) {
  return SAME(orbit.kind) && SAME(orbit.n_phases) && SAME(orbit.modes) &&
         SAME(orbit.durations) && SAME(orbit.period) && SAME(orbit.n_turns) &&
         SAME(orbit.z0) && SAME(orbit.x0) && SAME_MARGIN(orbit.slip_below) &&
         SAME_MARGIN(orbit.over_above) && SAME_MARGIN(orbit.stick_upper) &&
         SAME_MARGIN(orbit.stick_lower) && SAME_MARGIN(orbit.switching) &&
         SAME_MARGIN(orbit.transversal) && SAME_MARGIN(orbit.min_margin) &&
         SAME(orbit.residual) && SAME(orbit.closure) && SAME(orbit.stab.jac) &&
         SAME(orbit.stab.jac_fd) && SAME(orbit.stab.jac_diff) &&
         SAME(orbit.stab.eig_re) && SAME(orbit.stab.eig_im) &&
         SAME(orbit.stab.spectral_radius) && SAME(orbit.stab.stable) &&
         SAME(orbit.stab.unit_margin) && SAME(orbit.stab.marginal) &&
         SAME(orbit.iterations) && SAME(orbit.source) &&
         SAME_MARGIN(orbit.violation) && SAME(orbit.violation_id) &&
         SAME(from_simulation) && SAME(n_points) && SAME(points) &&
         SAME(radius) && SAME(iterations) && SAME(cells);
}

/* The number of differences between two maps (0: the same map). */
static int differences(const ss_basins *x, const ss_basins *y) {
  int n = 0;
  if (x->n_attractors != y->n_attractors || x->n[0] != y->n[0] ||
      x->n[1] != y->n[1])
    return 1;
  for (int a = 0; a < x->n_attractors; a++)
    n += !same_attractor(&x->attractors[a], &y->attractors[a]);
  n += memcmp(x->labels, y->labels, (size_t)x->n[0] * (size_t)x->n[1]) != 0;
  n += !SAME(unresolved) + !SAME(perpetual) + !SAME(returns) +
       !SAME(max_returns);
  return n;
}

/* The map in stages, rows in groups of @a group in an order shuffled by
 * @a seed, into @a out. */
static void staged(const ss_model *m, const ss_basin_opts *o, int group,
                   unsigned seed, ss_basins *out) {
  ss_basins b0;
  ss_diag d;
  ASSERT_EQ_INT(ss_basins_alloc(o, &b0, &d), SS_OK);
  ASSERT_EQ_INT(ss_basins_attractors(m, o, &b0, &d), SS_OK);
  int rows = o->n[0], groups = (rows + group - 1) / group;
  int *order = malloc((size_t)groups * sizeof *order);
  for (int g = 0; g < groups; g++)
    order[g] = g;
  for (int g = groups; g > 1; g--) { /* Fisher-Yates, a fixed generator */
    seed = seed * 1103515245u + 12345u;
    int r = (int)((seed >> 8) % (unsigned)g), t = order[g - 1];
    order[g - 1] = order[r];
    order[r] = t;
  }
  ASSERT_EQ_INT(ss_basins_alloc(o, out, &d), SS_OK);
  out->n_attractors = b0.n_attractors;
  memcpy(out->attractors, b0.attractors,
         SS_BASIN_MAX_ATTRACTORS * sizeof *b0.attractors);
  for (int g = 0; g < groups; g++) {
    int row = order[g] * group;
    int n = row + group <= rows ? group : rows - row;
    size_t width = (size_t)o->n[1];
    ss_basins bg;
    ASSERT_EQ_INT(ss_basins_alloc(o, &bg, &d), SS_OK);
    bg.n_attractors = b0.n_attractors;
    memcpy(bg.attractors, b0.attractors,
           SS_BASIN_MAX_ATTRACTORS * sizeof *b0.attractors);
    ASSERT_EQ_INT(ss_basins_rows(m, o, &bg, row, n, &d), SS_OK);
    memcpy(out->labels + (size_t)row * width, bg.labels + (size_t)row * width,
           (size_t)n * width);
    out->returns += bg.returns;
    if (bg.max_returns > out->max_returns)
      out->max_returns = bg.max_returns;
    ss_basins_free(&bg);
  }
  ASSERT_EQ_INT(ss_basins_finish(m, o, out, &d), SS_OK);
  free(order);
  ss_basins_free(&b0);
}

/* A map of another slice, and rows outside the slice, are refused. */
static void refusals(const ss_model *m, const ss_basin_opts *o) {
  ss_basins b;
  ss_diag d;
  ss_basin_opts other = *o;
  other.n[1] = o->n[1] + 1;
  ASSERT_EQ_INT(ss_basins_alloc(&other, &b, &d), SS_OK);
  ASSERT_EQ_INT(ss_basins_rows(m, o, &b, 0, 1, &d), SS_EINVAL);
  ASSERT_EQ_INT(ss_basins_finish(m, o, &b, &d), SS_EINVAL);
  ss_basins_free(&b);
  ASSERT_EQ_INT(ss_basins_alloc(o, &b, &d), SS_OK);
  ASSERT_EQ_INT(ss_basins_rows(m, o, &b, o->n[0] - 1, 2, &d), SS_EINVAL);
  ASSERT_EQ_INT(ss_basins_rows(m, o, &b, -1, 1, &d), SS_EINVAL);
  ASSERT_EQ_INT(ss_basins_rows(m, o, &b, 0, 0, &d), SS_OK);
  ss_basins_free(&b);
}

int main(void) {
  static const int GROUPS[] = {1, 3, 7};
  for (size_t k = 0; k < sizeof CASES / sizeof CASES[0]; k++) {
    const slice_case *c = &CASES[k];
    ss_model m;
    ASSERT_EQ_INT(ss_model_init(&m, &c->p, NULL), SS_OK);
    for (int threads = 1; threads <= 2; threads++) {
      ss_basin_opts o;
      opts_of(c, threads, &o);
      ss_basins whole;
      ss_diag d;
      ASSERT_EQ_INT(ss_basins_run(&m, &o, &whole, &d), SS_OK);
      int simulation = 0, newton = 0;
      for (int a = 0; a < whole.n_attractors; a++) {
        simulation += whole.attractors[a].from_simulation;
        newton += whole.attractors[a].from_simulation &&
                  whole.attractors[a].orbit.source == SS_SOURCE_MAP_NEWTON;
      }
      printf("%s, %d thread(s): %d attractors (%d from simulation), %ld "
             "unresolved, %ld returns\n",
             c->name, threads, whole.n_attractors, simulation, whole.unresolved,
             whole.returns);
      ASSERT_TRUE(whole.n_attractors >= 1);
      ASSERT_EQ_INT(simulation > 0, c->want_simulation);
      ASSERT_EQ_INT(whole.unresolved > 0, c->want_unresolved);
      ASSERT_EQ_INT(newton > 0, c->want_newton);
      for (size_t g = 0; g < sizeof GROUPS / sizeof GROUPS[0]; g++) {
        ss_basins parts;
        staged(&m, &o, GROUPS[g], 7u * (unsigned)g + (unsigned)k, &parts);
        int diff = differences(&whole, &parts);
        printf("  rows in groups of %d, shuffled: %d differences\n", GROUPS[g],
               diff);
        ASSERT_EQ_INT(diff, 0);
        ss_basins_free(&parts);
      }
      if (threads == 1)
        refusals(&m, &o);
      ss_basins_free(&whole);
    }
  }
  TEST_DONE();
}
