/*
 * bench_orbit.c: time to find the paper's orbit with and without a guess,
 * and to compute its stability; also the cost per event and per period of
 * the exact simulation.  Medians of many runs.
 * Writes bench/results/orbit.md.  Usage: bench_orbit [results-dir]
 */
#include "bench_common.h"

#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "stickslip.h"

#define RUNS 301

static ss_model M;

typedef double (*job_fn)(void);

static double timed(job_fn fn, int runs, double *out_med) {
  double *tv = malloc((size_t)runs * sizeof *tv), check = 0;
  for (int k = 0; k < runs; k++) {
    double t0 = cpu_now();
    check += fn();
    tv[k] = cpu_now() - t0;
  }
  *out_med = median(tv, runs);
  free(tv);
  return check;
}

static double find_from_guess(int fd) {
  ss_orbit_opts o;
  ss_orbit out[4];
  int n = 0;
  memset(&o, 0, sizeof o);
  o.n_guess = 3;
  o.guess[0] = 4.5;
  o.guess[1] = 2.717;
  o.guess[2] = 3.0536;
  o.difference_check = fd;
  ss_orbit_find(&M, &o, out, 4, &n, NULL, NULL);
  return n ? out[0].period : 0;
}

static double find_guess(void) { return find_from_guess(0); }
static double find_guess_fd(void) { return find_from_guess(1); }

static double find_overshoot(void) {
  ss_orbit_opts o;
  ss_orbit out[32];
  int n = 0;
  memset(&o, 0, sizeof o);
  o.kinds = SS_ORBIT_OVERSHOOT;
  ss_orbit_find(&M, &o, out, 32, &n, NULL, NULL);
  return n;
}

static double find_all(void) {
  ss_orbit_opts o;
  ss_orbit out[32];
  int n = 0;
  memset(&o, 0, sizeof o);
  o.difference_check = 1;
  ss_orbit_find(&M, &o, out, 32, &n, NULL, NULL);
  return n;
}

static ss_orbit ORB;

static double stab_analytic(void) {
  ss_stab st;
  ss_stab_opts so = {1, 0};
  ss_stability(&M, 3, ORB.modes, ORB.durations, ORB.z0, &so, &st);
  return st.spectral_radius;
}

static double stab_fd(void) {
  ss_stab st;
  ss_stab_opts so = {1, 1};
  ss_stability(&M, 3, ORB.modes, ORB.durations, ORB.z0, &so, &st);
  return st.spectral_radius;
}

static double sim_1000(void) {
  ss_sim_opts o;
  ss_sim_result r;
  memset(&o, 0, sizeof o);
  o.t_end = 1000 * ORB.period;
  ss_simulate(&M, ORB.x0, &o, &r, NULL);
  return r.x[0];
}

/* The same with every event searched from scratch: what the certificates
 * save, in the same run. */
static double sim_1000_full(void) {
  ss_sim_opts o;
  ss_sim_result r;
  memset(&o, 0, sizeof o);
  o.t_end = 1000 * ORB.period;
  o.full_search = 1;
  ss_simulate(&M, ORB.x0, &o, &r, NULL);
  return r.x[0];
}

/* The paper's other stable orbit, of 3 turns and 7 phases: a slip differs
 * from the slip of the turn before, and repeats 3 turns later. */
static ss_orbit ORB3;
static double sim_3turn(void) {
  ss_sim_opts o;
  ss_sim_result r;
  memset(&o, 0, sizeof o);
  o.t_end = 1000 * ORB3.period / 3;
  ss_simulate(&M, ORB3.x0, &o, &r, NULL);
  return r.x[0];
}

/* From rest in stick, x = (0, 0, 0, V): a transient onto the overshoot
 * orbit, about 1000 of its periods' time. */
static double sim_transient(void) {
  ss_sim_opts o;
  ss_sim_result r;
  double x0[4] = {0, 0, 0, 1};
  memset(&o, 0, sizeof o);
  o.t_end = 1000 * ORB.period;
  ss_simulate(&M, x0, &o, &r, NULL);
  return r.x[0];
}

/* Families: the paper's in ur up from the start (no special point), the
 * same down to its grazing and up, and the chi family at ur = 12 us (two
 * period doublings, two grazings). */
static int family(const ss_params *p, const ss_orbit *start, ss_param_id id,
                  double lo, double hi, int direction, int *n_special) {
  ss_cont_opts co;
  ss_branch b;
  memset(&co, 0, sizeof co);
  co.param = id;
  co.lo = lo;
  co.hi = hi;
  co.direction = direction;
  co.max_points = 1000;
  ss_continue(p, start, &co, &b, NULL);
  int n = b.n_points;
  if (n_special)
    *n_special = b.n_special;
  ss_branch_free(&b);
  return n;
}

static const ss_params PAPER = {0.2, 4.0, 0.0724, 0.6178, 1.0};
static ss_params P12 = {0.2, 4.0, 0.0724, 12 * 0.0724, 1.0};
static ss_orbit START12;

static double family_up(void) {
  return family(&PAPER, &ORB, SS_PARAM_UR, 0.3, 1.5, 1, NULL);
}
static double locate_grazing(void) {
  return family(&PAPER, &ORB, SS_PARAM_UR, 0.3, 1.5, -1, NULL);
}
static double family_ur(void) {
  return family(&PAPER, &ORB, SS_PARAM_UR, 0.3, 1.5, 0, NULL);
}
static double family_chi(void) {
  return family(&P12, &START12, SS_PARAM_CHI, 0.01, 0.99, 0, NULL);
}

/* The paper family's grazing followed in chi over [0.05, 0.6]. */
static ss_branch DOWN;
static int curve_points(void) {
  ss_cont_opts o2;
  ss_curve cv;
  memset(&o2, 0, sizeof o2);
  o2.param = SS_PARAM_CHI;
  o2.lo = 0.05;
  o2.hi = 0.6;
  o2.max_points = 200; /* a 200-point curve: the middle of the boundary */
  o2.step = 0.005;
  ss_continue_grazing(&PAPER, &DOWN, &DOWN.special[0], &o2, &cv, NULL);
  int n = cv.n_points;
  ss_curve_free(&cv);
  return n;
}
static double boundary_curve(void) { return curve_points(); }

int main(int argc, char **argv) {
  const char *dir = argc > 1 ? argv[1] : "bench/results";
  ss_params p = {0.2, 4.0, 0.0724, 0.6178, 1.0};
  ss_mode modes[3] = {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK};
  double guess[3] = {4.5, 2.717, 3.0536};
  gsl_set_error_handler_off();
  ss_model_init(&M, &p, NULL);
  ss_orbit_solve(&M, 3, modes, guess, NULL, &ORB, NULL);
  {
    ss_orbit_opts oo;
    ss_orbit all[32];
    int n = 0;
    memset(&oo, 0, sizeof oo);
    oo.kinds = SS_ORBIT_ALL;
    oo.max_period = 4;
    ss_orbit_find(&M, &oo, all, 32, &n, NULL, NULL);
    for (int i = 0; i < n; i++)
      if (all[i].n_turns == 3 && all[i].stab.stable)
        ORB3 = all[i];
  }
  {
    ss_model m12;
    ss_orbit_opts oo;
    int n = 0;
    memset(&oo, 0, sizeof oo);
    oo.kinds = SS_ORBIT_OVERSHOOT;
    ss_model_init(&m12, &P12, NULL);
    ss_orbit_find(&m12, &oo, &START12, 1, &n, NULL, NULL);
  }
  int sp_ur = 0, sp_chi = 0;
  int n_up = family(&PAPER, &ORB, SS_PARAM_UR, 0.3, 1.5, 1, NULL);
  int n_ur = family(&PAPER, &ORB, SS_PARAM_UR, 0.3, 1.5, 0, &sp_ur);
  int n_chi = family(&P12, &START12, SS_PARAM_CHI, 0.01, 0.99, 0, &sp_chi);
  {
    ss_cont_opts co;
    memset(&co, 0, sizeof co);
    co.param = SS_PARAM_UR;
    co.lo = 0.3;
    co.hi = 1.5;
    co.direction = -1;
    ss_continue(&PAPER, &ORB, &co, &DOWN, NULL);
  }
  int n_curve = curve_points();
  char w_up[160], w_ur[160], w_chi[160], w_curve[160];
  snprintf(w_curve, sizeof w_curve,
           "the boundary ur*(chi): the grazing followed in chi (%d points, "
           "step 0.005)",
           n_curve);
  snprintf(w_up, sizeof w_up,
           "continue the paper's family in ur up to 1.5 (%d points, no "
           "special point)",
           n_up);
  snprintf(w_ur, sizeof w_ur,
           "continue it both ways over ur in [0.3, 1.5] (%d points, %d "
           "special: the grazing located)",
           n_ur, sp_ur);
  snprintf(w_chi, sizeof w_chi,
           "continue the family in chi at ur = 12 us (%d points, %d special: "
           "2 period doublings, 2 grazings)",
           n_chi, sp_chi);
  struct {
    const char *what;
    job_fn fn;
    int runs;
    const char *target;
    int per; /* > 0: also the time per point */
  } jobs[] = {
      {"find the paper's orbit from a guess (no finite differences)",
       find_guess, RUNS, "< 20 us"},
      {"find the paper's orbit from a guess, with the finite-difference "
       "Jacobian",
       find_guess_fd, RUNS, ""},
      {"find overshoot orbits with no guess (kind = overshoot)", find_overshoot,
       51, "< 2 ms"},
      {"find all orbits with no guess, with finite-difference Jacobians",
       find_all, 51, ""},
      {"stability, analytic Jacobian and eigenvalues", stab_analytic, 2001, ""},
      {"stability with the finite-difference check (8 simulated maps)", stab_fd,
       RUNS, ""},
      {"simulate 1000 periods (3000 events), final state only", sim_1000, 21,
       "< 0.5 ms (0.5 us per period)"},
      {"the same, every event searched from scratch (full_search)",
       sim_1000_full, 21, ""},
      {"simulate 1000 turns of the 3-turn orbit (2333 events), final state "
       "only",
       sim_3turn, 21, ""},
      {"simulate from rest in stick for 1000 periods' time (a transient onto "
       "the orbit)",
       sim_transient, 21, ""},
      {w_up, family_up, 51, "< 30 us per point", n_up},
      {"locate the grazing that ends it below (one step, then bisection to "
       "1e-10)",
       locate_grazing, 51, "", 0},
      {w_ur, family_ur, 51, "", n_ur},
      {w_chi, family_chi, 51, "", n_chi},
      {w_curve, boundary_curve, 21, "", n_curve},
  };
  char path[512];
  snprintf(path, sizeof path, "%s/orbit.md", dir);
  FILE *f = fopen(path, "w");
  if (!f) {
    perror(path);
    return 1;
  }
  fprintf(f, "# Orbit, stability and simulation timings\n\nGenerated by "
             "`bench_orbit`: median CPU time of repeated runs in one process, "
             "paper's data set.\n\n| task | runs | median | target |\n"
             "| --- | ---: | ---: | --- |\n");
  for (size_t i = 0; i < sizeof jobs / sizeof jobs[0]; i++) {
    double med;
    timed(jobs[i].fn, jobs[i].runs, &med);
    const char *unit = med < 1e-3 ? "us" : "ms";
    double v = med < 1e-3 ? med * 1e6 : med * 1e3;
    char per[64] = "";
    if (jobs[i].per > 0)
      snprintf(per, sizeof per, " (%.1f us per point)",
               med / jobs[i].per * 1e6);
    printf("%-75s %9.2f %s%s\n", jobs[i].what, v, unit, per);
    fprintf(f, "| %s | %d | %.2f %s%s | %s |\n", jobs[i].what, jobs[i].runs, v,
            unit, per, jobs[i].target);
  }
  fclose(f);
  printf("wrote %s\n", path);
  return 0;
}
