/*
 * bench_map.c: a parameter map (ss_map_run, what POST /map runs) against
 * the same map made as separate searches, one per cell (what one /orbit
 * request per cell runs, without the HTTP), both on 2 threads.
 *
 * The map: overshoot orbits over ur/us 1.5-15 and chi 0.04-0.96 (eta 4,
 * us 0.0724, V 1), n x n cells (default 50).  Reported: wall time of the
 * map with its defaults (the full search at every cell; median of 3) and
 * with sparser lattices of searches (once each), the
 * separate searches' wall time (once), the ratio, and whether the map has
 * every orbit the separate searches find.
 * Usage: bench_map [results_dir] [n]
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "stickslip.h"

#define MAXO 32

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int N = 50;
static const ss_params BASE = {0.2, 4, 0.0724, 0.6178, 1};

static void axes(ss_map_axis ax[2]) {
  ax[0] = (ss_map_axis){SS_PARAM_CHI, 0.04, 0.96, N};
  ax[1] = (ss_map_axis){SS_PARAM_UR, 0.0724 * 1.5, 0.0724 * 15, N};
}

/* The separate searches: each cell's orbits, and the next cell to do. */
typedef struct cellres {
  int n;
  double dur[MAXO][3];
  double period[MAXO];
} cellres;

static cellres *sep;
static int next_cell;
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static const ss_map *shape;

static void *worker(void *arg) {
  (void)arg;
  ss_orbit out[MAXO];
  for (;;) {
    pthread_mutex_lock(&lock);
    int c = next_cell < N * N ? next_cell++ : -1;
    pthread_mutex_unlock(&lock);
    if (c < 0)
      return NULL;
    ss_params p;
    ss_model m;
    ss_map_params(&BASE, NULL, shape, c, &p, NULL, NULL);
    ss_model_init(&m, &p, NULL);
    ss_orbit_opts oo;
    memset(&oo, 0, sizeof oo);
    oo.kinds = SS_ORBIT_OVERSHOOT;
    int n = 0;
    ss_orbit_find(&m, &oo, out, MAXO, &n, NULL, NULL);
    sep[c].n = n;
    for (int k = 0; k < n; k++) {
      memcpy(sep[c].dur[k], out[k].durations, sizeof sep[c].dur[k]);
      sep[c].period[k] = out[k].period;
    }
  }
}

static double run_map(const ss_map_opts *mo, ss_map *map) {
  ss_map_axis ax[2];
  axes(ax);
  double t0 = now();
  if (ss_map_run(&BASE, 2, ax, mo, map, NULL) != SS_OK)
    fprintf(stderr, "bench_map: the map failed\n");
  return now() - t0;
}

/* Orbits of the separate searches that the map lacks; cells with orbits. */
static int missing(const ss_map *map, int *with) {
  int miss = 0;
  *with = 0;
  for (int c = 0; c < N * N; c++) {
    *with += map->cells[c].n_orbits > 0;
    for (int k = 0; k < sep[c].n; k++) {
      int found = 0;
      for (int i = 0; i < map->cells[c].n_orbits && !found; i++) {
        const ss_map_orbit *q = &map->cells[c].orbits[i];
        found = q->n_phases == 3 &&
                fabs(q->period - sep[c].period[k]) < 1e-6 * q->period &&
                fabs(q->durations[0] - sep[c].dur[k][0]) < 1e-6 * q->period;
      }
      miss += !found;
    }
  }
  return miss;
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y;
}

int main(int argc, char **argv) {
  const char *dir = argc > 1 ? argv[1] : NULL;
  if (argc > 2)
    N = atoi(argv[2]);
  if (N < 3)
    N = 3;
  ss_map_opts mo;
  memset(&mo, 0, sizeof mo);
  mo.kinds = SS_ORBIT_OVERSHOOT;
  mo.threads = 2;
  ss_map map;
  double t[3];
  for (int r = 0; r < 3; r++) {
    t[r] = run_map(&mo, &map);
    if (r < 2)
      ss_map_free(&map);
  }
  qsort(t, 3, sizeof t[0], cmp);
  shape = &map;
  /* the separate searches */
  sep = calloc((size_t)N * (size_t)N, sizeof *sep);
  double t0 = now();
  pthread_t th;
  pthread_create(&th, NULL, worker, NULL);
  worker(NULL);
  pthread_join(th, NULL);
  double t_sep = now() - t0;
  int with_sep = 0, orbits_sep = 0;
  for (int c = 0; c < N * N; c++) {
    with_sep += sep[c].n > 0;
    orbits_sep += sep[c].n;
  }
  int with = 0, miss = missing(&map, &with);
  char line[5][400];
  snprintf(line[0], sizeof line[0],
           "| map, defaults (search_every 1: every cell) | %.2f s | %d | "
           "%d | %d | %.1fx |",
           t[1], map.searches, with, miss, t_sep / t[1]);
  ss_map_free(&map);
  /* lighter settings */
  const struct {
    int every, no_edge;
    const char *name;
  } light[] = {{8, 0, "search_every 8 (with edge_search)"},
               {16, 0, "search_every 16"},
               {8, 1, "search_every 8, no edge_search"}};
  for (int v = 0; v < 3; v++) {
    mo.search_every = light[v].every;
    mo.no_edge_search = light[v].no_edge;
    double tv = run_map(&mo, &map);
    int w = 0, ms = missing(&map, &w);
    snprintf(line[1 + v], sizeof line[1 + v],
             "| map, %s | %.2f s | %d | %d | %d | %.1fx |", light[v].name, tv,
             map.searches, w, ms, t_sep / tv);
    ss_map_free(&map);
  }
  snprintf(line[4], sizeof line[4],
           "| %d separate searches (one /orbit each) | %.2f s | %d | %d | "
           "- | 1x |",
           N * N, t_sep, N * N, with_sep);
  FILE *f = stdout;
  char path[512];
  if (dir) {
    snprintf(path, sizeof path, "%s/map.md", dir);
    if (!(f = fopen(path, "w")))
      f = stdout;
  }
  fprintf(f,
          "# Parameter map: ss_map_run (POST /map) against separate "
          "searches\n\n"
          "Overshoot orbits on a %dx%d grid, ur/us 1.5-15 and chi "
          "0.04-0.96 (eta 4, us 0.0724, V 1); both on 2 threads of a 2-core "
          "machine, wall time (the map's default: median of 3 runs).  "
          "\"missing\": orbits the separate searches find that the map "
          "lacks.  %d orbits in %d cells by the separate searches.\n\n"
          "| how | wall time | full searches | cells with an orbit | missing "
          "| speed-up |\n|---|---|---|---|---|---|\n%s\n%s\n%s\n%s\n%s\n",
          N, N, orbits_sep, with_sep, line[0], line[1], line[2], line[3],
          line[4]);
  if (f != stdout) {
    fclose(f);
    printf("bench_map: results in %s\n", path);
    for (int k = 0; k < 5; k++)
      printf("%s\n", line[k]);
  }
  free(sep);
  return 0;
}
