/*
 * test_existence.c: an existence map of the overshoot orbits has no hole
 * that a neighbour fills.
 *
 * A 50x50 map (ur/us 1.5-15 and chi 0.04-0.96, both linear, eta = 4,
 * us = 0.0724, V = 1) of the overshoot orbits the default search returns
 * with kind = overshoot.  Every cell where the search returns none is tried
 * again from the durations of each neighbour's orbits (up to 8 neighbours)
 * as guesses: a feasible orbit found that way, with every duration within
 * the search's box (1.5 slow modal periods), is one the search missed.
 * Usage: test_existence [n]   (default 50; SS_EXISTENCE_N overrides)
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "stickslip.h"
#include "test.h"

#define MAXO 16

typedef struct cell {
  int n;
  double dur[MAXO][3];
} cell;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
  const char *env = getenv("SS_EXISTENCE_N");
  int N = env ? atoi(env) : argc > 1 ? atoi(argv[1]) : 50;
  if (N < 2)
    N = 2;
  cell *map = calloc((size_t)N * (size_t)N, sizeof *map);
  ss_params base = {0.2, 4, 0.0724, 0.6178, 1};
  ss_orbit out[MAXO];
  double t0 = now();
  int with = 0;
  for (int i = 0; i < N; i++)
    for (int j = 0; j < N; j++) {
      ss_params p = base;
      p.chi = 0.04 + (0.96 - 0.04) * i / (N - 1);
      p.ur = p.us * (1.5 + (15 - 1.5) * j / (N - 1));
      ss_model m;
      ASSERT_EQ_INT(ss_model_init(&m, &p, NULL), SS_OK);
      ss_orbit_opts oo;
      memset(&oo, 0, sizeof oo);
      oo.kinds = SS_ORBIT_OVERSHOOT;
      int n = 0;
      ASSERT_EQ_INT(ss_orbit_find(&m, &oo, out, MAXO, &n, NULL, NULL), SS_OK);
      cell *c = &map[i * N + j];
      for (int k = 0; k < n; k++)
        if (out[k].n_phases == 3 && out[k].n_turns == 1 && c->n < MAXO) {
          memcpy(c->dur[c->n], out[k].durations, sizeof c->dur[0]);
          c->n++;
        }
      with += c->n > 0;
    }
  double t_map = now() - t0;
  int holes = 0, filled = 0, tried = 0;
  ss_mode modes[3] = {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK};
  for (int i = 0; i < N; i++)
    for (int j = 0; j < N; j++) {
      if (map[i * N + j].n)
        continue;
      ss_params p = base;
      p.chi = 0.04 + (0.96 - 0.04) * i / (N - 1);
      p.ur = p.us * (1.5 + (15 - 1.5) * j / (N - 1));
      ss_model m;
      ss_model_init(&m, &p, NULL);
      double box = 1.5 * 6.283185307179586 / m.w[0] * (1 + 1e-12);
      int next = 0, found = 0;
      for (int di = -1; di <= 1 && !found; di++)
        for (int dj = -1; dj <= 1 && !found; dj++) {
          int a = i + di, b = j + dj;
          if ((!di && !dj) || a < 0 || b < 0 || a >= N || b >= N)
            continue;
          const cell *nb = &map[a * N + b];
          next |= nb->n > 0;
          for (int k = 0; k < nb->n && !found; k++) {
            ss_orbit o;
            tried++;
            if (ss_orbit_solve(&m, 3, modes, nb->dur[k], NULL, &o, NULL) ==
                    SS_OK &&
                o.durations[0] <= box && o.durations[1] <= box &&
                o.durations[2] <= box) {
              found = 1;
              printf("hole filled: chi %.6f ur %.6f: durations [%.9g, %.9g, "
                     "%.9g] from the neighbour (%+d, %+d)\n",
                     p.chi, p.ur, o.durations[0], o.durations[1],
                     o.durations[2], di, dj);
            }
          }
        }
      holes += next;
      filled += found;
    }
  printf("existence: %dx%d map, %d cells with an overshoot orbit (%.1f s); "
         "%d empty cells next to one, %d guesses from the neighbours, %d of "
         "them filled\n",
         N, N, with, t_map, holes, tried, filled);
  ASSERT_EQ_INT(filled, 0);
  free(map);
  TEST_DONE();
}
