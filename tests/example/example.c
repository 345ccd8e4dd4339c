/* Find the paper's overshoot orbit and print its phases and stability. */
#include <stdio.h>
#include <stickslip.h>
int main(void) {
  ss_params p = {.chi = 0.2, .eta = 4, .us = 0.0724, .ur = 0.6178, .V = 1};
  ss_orbit_opts opts = {.kinds = SS_ORBIT_OVERSHOOT};
  ss_model m;
  ss_orbit o[8];
  int n = 0;
  ss_gsl_quiet();
  if (ss_model_init(&m, &p, 0) || ss_orbit_find(&m, &opts, o, 8, &n, 0, 0))
    return 1;
  for (int i = 0; i < n; i++) {
    for (int k = 0; k < o[i].n_phases; k++)
      printf("%s %.6f  ", ss_mode_name(o[i].modes[k]), o[i].durations[k]);
    printf("\nspectral radius %.6f (%s)\n", o[i].stab.spectral_radius,
           o[i].stab.stable ? "stable" : "unstable");
  }
  return n > 0 ? 0 : 1;
}
