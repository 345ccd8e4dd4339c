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
  json_t *in;
  if (api__echo_as_tree) {
    in = api__echo(spec, x);
    api__params_echo(in, ap);
  } else
    in = api__echo_raw(c, spec, x, ap);
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

/* [x0, ..., xn-1] */
void api__w_vec(api_wbuf *w, const double *x, int n) {
  API_W_LIT(w, "[");
  for (int i = 0; i < n; i++) {
    if (i)
      API_W_LIT(w, ",");
    api__w_real(w, x[i]);
  }
  API_W_LIT(w, "]");
}

void api__w_state(api_wbuf *w, const api_params *ap, const double x[4]) {
  double y[4];
  ss_to_physical(ap->omega, 0, x, NULL, y);
  api__w_vec(w, y, 4);
}

/* Phase i of the orbit a: {mode, duration}. */
static void phase_item(api_wbuf *w, const api_lazy *l, size_t i) {
  const ss_orbit *o = l->a;
  const char *m = ss_mode_name(o->modes[i]);
  API_W_LIT(w, "{\"mode\":");
  api__w_str(w, m, strlen(m));
  API_W_LIT(w, ",\"duration\":");
  api__w_real(w, api__time_out(l->b, o->durations[i]));
  API_W_LIT(w, "}");
}

json_t *api__phases(const api_call *c, const ss_orbit *o,
                    const api_params *ap) {
  return api__lazy(c, (size_t)o->n_phases, phase_item, o, ap, 0, 0);
}

void api__w_phases(api_wbuf *w, const ss_orbit *o, const api_params *ap) {
  api_lazy l = {NULL,          phase_item, o, ap, 0, (size_t)o->n_phases,
                API_LAZY_ARRAY};
  API_W_LIT(w, "[");
  for (size_t i = 0; i < l.n; i++) {
    if (i)
      API_W_LIT(w, ",");
    phase_item(w, &l, i);
  }
  API_W_LIT(w, "]");
}

/* In physical units the map acts on (z1, z1'): J' = D J D^-1 with
 * D = diag(1, omega). */
static void w_jacobian(api_wbuf *w, const double J[2][2],
                       const api_params *ap) {
  API_W_LIT(w, "[");
  for (int i = 0; i < 2; i++) {
    double row[2];
    for (int j = 0; j < 2; j++) {
      double s = (i == 1 ? ap->omega : 1) / (j == 1 ? ap->omega : 1);
      row[j] = J[i][j] * s;
    }
    if (i)
      API_W_LIT(w, ",");
    api__w_vec(w, row, 2);
  }
  API_W_LIT(w, "]");
}

/* The note, as the JSON string it is written as (it has nothing to escape:
 * no quote, backslash or control character). */
static const char STAB_NOTE[] =
    "\"Stability of the fixed point of the Poincare map on the section (4.2) "
    "in (z1, z1'): all eigenvalues inside the unit circle means small "
    "perturbations, except during stick, stay near the orbit. This is "
    "neither Lyapunov nor orbital stability (the paper, section 4).\"";

static void w_bool(api_wbuf *w, int v) {
  if (v)
    API_W_LIT(w, "true");
  else
    API_W_LIT(w, "false");
}

/* The members of the stability object of l->a in the units of l->b; with
 * its braces when l->k. */
static void stability_item(api_wbuf *w, const api_lazy *l, size_t i) {
  const ss_stab *st = l->a;
  const api_params *ap = l->b;
  (void)i;
  if (l->k)
    API_W_LIT(w, "{");
  API_W_LIT(w, "\"eigenvalues\":[");
  for (int e = 0; e < 2; e++) {
    if (e)
      API_W_LIT(w, ",");
    api__w_vec(w, (double[2]){st->eig_re[e], st->eig_im[e]}, 2);
  }
  API_W_LIT(w, "],\"spectral_radius\":");
  api__w_real(w, st->spectral_radius);
  API_W_LIT(w, ",\"stable\":");
  w_bool(w, st->stable);
  API_W_LIT(w, ",\"unit_margin\":");
  api__w_real(w, st->unit_margin);
  API_W_LIT(w, ",\"marginal\":");
  w_bool(w, st->marginal);
  API_W_LIT(w, ",\"jacobian\":");
  w_jacobian(w, st->jac, ap);
  if (!isnan(st->jac_diff)) {
    API_W_LIT(w, ",\"jacobian_fd\":");
    w_jacobian(w, st->jac_fd, ap);
    API_W_LIT(w, ",\"jacobian_difference\":");
    api__w_real(w, st->jac_diff);
  }
  API_W_LIT(w, ",\"note\":");
  api__w_put(w, STAB_NOTE, sizeof STAB_NOTE - 1);
  if (l->k)
    API_W_LIT(w, "}");
}

json_t *api__stability(const api_call *c, const ss_stab *st,
                       const api_params *ap) {
  json_t *o = json_object();
  if (o && api__set_fields(o, c, stability_item, st, ap, 0) != 0) {
    json_decref(o);
    return NULL;
  }
  return o;
}

void api__w_stability(api_wbuf *w, const ss_stab *st, const api_params *ap) {
  api_lazy l = {NULL, stability_item, st, ap, 1, 1, API_LAZY_VALUE};
  stability_item(w, &l, 0);
}

json_t *api__json_of(api_wbuf *w) {
  json_t *j = w->oom || !w->p ? NULL : json_loadb(w->p, w->len, 0, NULL);
  free(w->p);
  memset(w, 0, sizeof *w);
  return j;
}
