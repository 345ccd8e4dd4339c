/*
 * encode.c: core results to JSON, in the units of the request, with the
 * numbers of values.c (a non-finite one becomes null, never NaN or
 * Infinity).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "encode.h"
#include "decode.h"
#include "samples.h"
#include "values.h"
#include "writer.h"

json_t *api__state(const api_params *ap, const double x[4]) {
  double y[4];
  ss_to_physical(ap->omega, 0, x, NULL, y);
  return api__vec4(y);
}

int api__answer(json_t *out, const api_spec *spec, const void *x,
                const api_params *ap, const api_call *c, api_response *resp) {
  json_t *in = api__echo(spec, x);
  api__params_echo(in, ap);
  api__set(out, "input", in);
  api__set(out, "units",
           json_string(ap->has_physical ? "physical" : "dimensionless"));
  api__set(out, "version", json_string(SS_VERSION));
  return api__json_response(out, c, resp);
}

/* Sample i of column k of API_SAMPLE_COLUMNS of the result a: time and
 * state in the request's units; the mode; the stick force chi (x2 - x1)
 * and the constraints of the paper's section 5, F1 = force + ur (> 0 in a
 * stick) and F2 = force - ur (<= 0), dimensionless as the margins are. */
static void sample_item(api_wbuf *w, const api_lazy *l, size_t i) {
  const ss_sim_result *r = l->a;
  const api_params *ap = l->b;
  const double *xi = r->sx + 4 * i;
  double t, x[4];
  if (l->k == 5) {
    const char *m = ss_mode_name((ss_mode)r->smode[i]);
    api__w_str(w, m, strlen(m));
    return;
  }
  if (l->k >= 6) {
    double force = ap->p.chi * (xi[1] - xi[0]);
    api__w_real(w, l->k == 6   ? force
                   : l->k == 7 ? force + ap->p.ur
                               : force - ap->p.ur);
    return;
  }
  ss_to_physical(ap->omega, r->st[i], xi, &t, x);
  api__w_real(w, l->k == 0 ? t : x[l->k - 1]);
}

json_t *api__samples(const ss_sim_result *r, const api_params *ap,
                     unsigned columns, const api_call *c) {
  json_t *s = json_object();
  size_t per = sizeof *r->st + 4 * sizeof *r->sx + sizeof *r->smode;
  int first = 1;
  for (int k = 0; API_SAMPLE_COLUMNS[k]; k++) {
    if (!(columns & (1u << k)))
      continue;
    if (api__set(s, API_SAMPLE_COLUMNS[k],
                 api__lazy(c, r->n_samples, sample_item, r, ap, k,
                           first ? r->n_samples * per : 0))) {
      json_decref(s);
      return NULL;
    }
    first = 0;
  }
  return s;
}

json_t *api__phases(int n, const ss_mode *modes, const double *tau,
                    const api_params *ap) {
  json_t *a = json_array();
  for (int k = 0; k < n; k++) {
    json_t *p = json_object();
    api__set(p, "mode", json_string(ss_mode_name(modes[k])));
    api__set(p, "duration", api__real(api__time_out(ap, tau[k])));
    json_array_append_new(a, p);
  }
  return a;
}

/* In physical units the map acts on (z1, z1'): J' = D J D^-1 with
 * D = diag(1, omega). */
json_t *api__jacobian(const double J[2][2], const api_params *ap) {
  json_t *a = json_array();
  for (int i = 0; i < 2; i++) {
    json_t *row = json_array();
    for (int j = 0; j < 2; j++) {
      double s = (i == 1 ? ap->omega : 1) / (j == 1 ? ap->omega : 1);
      json_array_append_new(row, api__real(J[i][j] * s));
    }
    json_array_append_new(a, row);
  }
  return a;
}

static const char *const STAB_NOTE =
    "Stability of the fixed point of the Poincare map on the section (4.2) "
    "in (z1, z1'): all eigenvalues inside the unit circle means small "
    "perturbations, except during stick, stay near the orbit. This is "
    "neither Lyapunov nor orbital stability (the paper, section 4).";

json_t *api__stability(const ss_stab *st, const api_params *ap) {
  json_t *s = json_object(), *ev = json_array();
  for (int i = 0; i < 2; i++) {
    json_t *p = json_array();
    json_array_append_new(p, api__real(st->eig_re[i]));
    json_array_append_new(p, api__real(st->eig_im[i]));
    json_array_append_new(ev, p);
  }
  api__set(s, "eigenvalues", ev);
  api__set(s, "spectral_radius", api__real(st->spectral_radius));
  api__set(s, "stable", json_boolean(st->stable));
  api__set(s, "unit_margin", api__real(st->unit_margin));
  api__set(s, "marginal", json_boolean(st->marginal));
  api__set(s, "jacobian", api__jacobian(st->jac, ap));
  if (!isnan(st->jac_diff)) {
    api__set(s, "jacobian_fd", api__jacobian(st->jac_fd, ap));
    api__set(s, "jacobian_difference", api__real(st->jac_diff));
  }
  api__set(s, "note", json_string(STAB_NOTE));
  return s;
}
