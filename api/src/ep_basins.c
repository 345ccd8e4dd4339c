/*
 * ep_basins.c: POST /basins, the attractors of one parameter set and the
 * basin of each over a two-dimensional slice of initial states
 * (ss_basins_run); the labels as a base64 byte array, row-major.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "endpoints.h"
#include "decode.h"
#include "encode.h"
#include "problem.h"
#include "values.h"

static const char *const VARIABLES[] = {"x1", "x2", "v1", "v2", NULL};

typedef struct basin_axis {
  int variable;
  double from, to;
  long long n;
} basin_axis;

typedef struct basin_axes {
  basin_axis a[2];
} basin_axes;

/* The values of the two state variables the axes do not vary. */
typedef struct basin_state {
  double v[4];
  int given[4];
} basin_state;

typedef struct basins_x {
  /* the request, in its units */
  api_params ap;
  basin_axes axes;
  basin_state state;
  long long max_period, max_returns;
  /* for the core */
  ss_model m;
  ss_basin_opts opts;
  /* the answer */
  ss_basins b;
} basins_x;

static const api_field AXIS_FIELDS[] = {
    {"variable", API_T_ENUM, API_REQUIRED, 0, 0, NULL,
     offsetof(basin_axis, variable), 0, 0, 0, VARIABLES},
    {"from", API_T_NUMBER, API_REQUIRED, -INFINITY, INFINITY, NULL,
     offsetof(basin_axis, from)},
    {"to", API_T_NUMBER, API_REQUIRED, -INFINITY, INFINITY, NULL,
     offsetof(basin_axis, to)},
    {"n", API_T_COUNT, API_REQUIRED, 1, 1e9, NULL, offsetof(basin_axis, n)},
};
static const api_spec AXIS_SPEC = API_SPEC(AXIS_FIELDS);

static int decode_axes(const json_t *v, const char *ptr, void *dest,
                       const api_call *c) {
  basin_axes *ax = dest;
  if (!json_is_array(v) || json_array_size(v) != 2)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an array of two axes {variable, from, to, "
                     "n}",
                     ptr);
  for (int i = 0; i < 2; i++) {
    char p[64];
    snprintf(p, sizeof p, "%s/%d", ptr, i);
    const json_t *a = json_array_get(v, (size_t)i);
    if (!json_is_object(a))
      return api__fail(c->e, API_P_INVALID_TYPE, p,
                       "%s must be an object {variable, from, to, n}", p);
    if (api__decode(&AXIS_SPEC, a, p, &ax->a[i], c))
      return -1;
    if (ax->a[i].n > 1 && !(ax->a[i].from != ax->a[i].to))
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s: from and to must differ when n > 1", p);
  }
  if (ax->a[0].variable == ax->a[1].variable)
    return api__fail(c->e, API_P_INVALID_VALUE, "/axes/1/variable",
                     "the two axes must vary different state variables, not "
                     "both %s",
                     VARIABLES[ax->a[0].variable]);
  return 0;
}

static json_t *echo_axes(const void *dest) {
  const basin_axes *ax = dest;
  json_t *arr = json_array();
  for (int i = 0; i < 2; i++)
    json_array_append_new(arr, api__echo(&AXIS_SPEC, &ax->a[i]));
  return arr;
}

static const api_custom AXES = {decode_axes, echo_axes};

static int decode_state(const json_t *v, const char *ptr, void *dest,
                        const api_call *c) {
  basin_state *st = dest;
  const char *k;
  json_t *f;
  if (!json_is_object(v))
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an object giving the two state variables "
                     "the axes do not vary, e.g. {\"v1\": 0, \"v2\": 1}",
                     ptr);
  json_object_foreach((json_t *)v, k, f) {
    char p[64];
    int i = 0;
    snprintf(p, sizeof p, "%s/%.20s", ptr, k);
    while (i < 4 && strcmp(k, VARIABLES[i]))
      i++;
    if (i == 4)
      return api__fail(c->e, API_P_UNKNOWN_FIELD, p,
                       "unknown state variable \"%.20s\" (x1, x2, v1, v2)", k);
    if (!json_is_number(f))
      return api__fail(c->e, API_P_INVALID_TYPE, p, "%s must be a number", p);
    st->v[i] = json_number_value(f);
    if (!isfinite(st->v[i]))
      return api__fail(c->e, API_P_INVALID_VALUE, p, "%s must be finite", p);
    st->given[i] = 1;
  }
  return 0;
}

static json_t *echo_state(const void *dest) {
  const basin_state *st = dest;
  json_t *o = json_object();
  for (int i = 0; i < 4; i++)
    if (st->given[i])
      api__set(o, VARIABLES[i], api__real(st->v[i]));
  return o;
}

static const api_custom STATE = {decode_state, echo_state};

static const api_field FIELDS[] = {
    API_PARAMS_FIELDS(basins_x, ap),
    {"axes", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL, offsetof(basins_x, axes),
     0, 0, 0, &AXES},
    {"state", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL, offsetof(basins_x, state),
     0, 0, 0, &STATE},
    {"max_period", API_T_COUNT, API_DEFAULT, 1, SS_BASIN_MAX_TURNS, NULL,
     offsetof(basins_x, max_period)},
    {"max_returns", API_T_COUNT, API_DEFAULT, 1, 100000, NULL,
     offsetof(basins_x, max_returns)},
};
static const api_spec SPEC = API_SPEC(FIELDS);

int ep_basins_decode(const json_t *root, const api_call *c, void **xp) {
  basins_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->max_period = 4;
  x->max_returns = 500;
  if (api__decode_request(&SPEC, root, x, &x->ap, c))
    return -1;
  /* the state: exactly the two variables the axes leave */
  for (int i = 0; i < 4; i++) {
    int varied = x->axes.a[0].variable == i || x->axes.a[1].variable == i;
    char p[32];
    snprintf(p, sizeof p, "/state/%s", VARIABLES[i]);
    if (varied && x->state.given[i])
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s is varied by an axis; give only the other two",
                       VARIABLES[i]);
    if (!varied && !x->state.given[i])
      return api__fail(c->e, API_P_MISSING_FIELD, p,
                       "state needs %s, which no axis varies", VARIABLES[i]);
  }
  double cells = (double)x->axes.a[0].n * (double)x->axes.a[1].n;
  if (cells > (double)c->lim->max_basin_cells)
    return api__limit(c->e, "max_basin_cells", (double)c->lim->max_basin_cells,
                      "/axes",
                      "the slice has %.0f cells, over the limit of %zu", cells,
                      c->lim->max_basin_cells);
  if (api__model(&x->m, &x->ap, c))
    return -1;
  /* into the core's units: velocities over omega */
  ss_basin_opts *o = &x->opts;
  double unit[4] = {1, 1, 1 / x->ap.omega, 1 / x->ap.omega};
  for (int a = 0; a < 2; a++) {
    const basin_axis *ax = &x->axes.a[a];
    o->vary[a] = ax->variable;
    o->from[a] = ax->from * unit[ax->variable];
    o->to[a] = ax->to * unit[ax->variable];
    o->n[a] = (int)ax->n;
  }
  for (int i = 0; i < 4; i++)
    o->state[i] = x->state.v[i] * unit[i];
  o->max_period = (int)x->max_period;
  o->max_returns = (int)x->max_returns;
  o->threads = api__threads(c, x->axes.a[0].n);
  o->max_seconds = c->lim->max_seconds;
  if (c->srv && c->srv->cancelled) {
    o->cancelled = c->srv->cancelled;
    o->cancel_cls = c->srv->cancel_cls;
  }
  return 0;
}

int ep_basins_run(void *xp, const api_call *c) {
  basins_x *x = xp;
  ss_diag d;
  ss_diag_clear(&d);
  int rc = ss_basins_run(&x->m, &x->opts, &x->b, &d);
  if (rc == SS_ELIMIT_TIME)
    return api__status_limit(c->e, rc, "max_seconds", c->lim->max_seconds, "",
                             "the basins needed more than %g s; make the "
                             "slice smaller or coarser, or lower max_returns",
                             c->lim->max_seconds);
  if (rc)
    return api__from_diag(c->e, rc, &d, "");
  return 0;
}

/* RFC 4648 base64 of @a n bytes; malloc'd, NUL-terminated. */
static char *base64(const unsigned char *p, size_t n) {
  static const char T[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  char *out = malloc(4 * ((n + 2) / 3) + 1), *w = out;
  if (!out)
    return NULL;
  size_t i = 0;
  for (; i + 2 < n; i += 3) {
    unsigned v = (unsigned)p[i] << 16 | (unsigned)p[i + 1] << 8 | p[i + 2];
    *w++ = T[v >> 18];
    *w++ = T[(v >> 12) & 63];
    *w++ = T[(v >> 6) & 63];
    *w++ = T[v & 63];
  }
  if (i < n) {
    unsigned v =
        (unsigned)p[i] << 16 | (i + 1 < n ? (unsigned)p[i + 1] << 8 : 0);
    *w++ = T[v >> 18];
    *w++ = T[(v >> 12) & 63];
    *w++ = i + 1 < n ? T[(v >> 6) & 63] : '=';
    *w++ = '=';
  }
  *w = 0;
  return out;
}

static json_t *share(long cells, double total) {
  json_t *o = json_object();
  api__set(o, "cells", json_integer(cells));
  api__set(o, "fraction", api__real((double)cells / total));
  return o;
}

static json_t *attractor_json(const basins_x *x, int i, double total) {
  const ss_basin_attractor *a = &x->b.attractors[i];
  const ss_orbit *o = &a->orbit;
  const api_params *ap = &x->ap;
  json_t *j = json_object(), *sec = json_array();
  api__set(j, "label", json_integer(i));
  api__set(j, "kind", json_string(ss_orbit_kind_name(o->kind)));
  api__set(j, "phases", api__phases(o->n_phases, o->modes, o->durations, ap));
  api__set(j, "period", api__real(api__time_out(ap, o->period)));
  api__set(j, "n_turns", json_integer(o->n_turns));
  api__set(j, "x0", api__state(ap, o->x0));
  api__set(j, "stability", api__stability(&o->stab, ap));
  api__set(j, "found_by",
           json_string(a->from_simulation ? "simulation" : "search"));
  /* its returns to Sigma0, (x1, v1) in the request's units */
  for (int k = 0; k < a->n_points; k++) {
    json_t *pt = json_array();
    json_array_append_new(pt, api__real(a->points[k][0] + x->m.d0[0]));
    json_array_append_new(pt, api__real(a->points[k][1] * ap->omega));
    json_array_append_new(sec, pt);
  }
  api__set(j, "section", sec);
  api__set(j, "radius", api__real(a->radius));
  api__set(j, "iterations", json_integer(a->iterations));
  api__set(j, "cells", json_integer(a->cells));
  api__set(j, "fraction", api__real((double)a->cells / total));
  return j;
}

int ep_basins_encode(const void *xp, const api_call *c, api_response *out) {
  const basins_x *x = xp;
  const ss_basins *b = &x->b;
  double total = (double)b->n[0] * (double)b->n[1];
  json_t *o = json_object(), *arr = json_array(), *lab = json_object();
  for (int i = 0; i < b->n_attractors; i++)
    json_array_append_new(arr, attractor_json(x, i, total));
  api__set(o, "attractors", arr);
  char *data = base64(b->labels, (size_t)total);
  if (!data) {
    json_decref(o);
    json_decref(lab);
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  }
  api__set(lab, "rows", json_integer(b->n[0]));
  api__set(lab, "cols", json_integer(b->n[1]));
  api__set(lab, "encoding", json_string("base64"));
  api__set(lab, "data", json_string(data));
  api__set(lab, "unresolved", json_integer(SS_BASIN_UNRESOLVED));
  api__set(lab, "perpetual_slip", json_integer(SS_BASIN_PERPETUAL));
  free(data);
  api__set(o, "labels", lab);
  api__set(o, "unresolved", share(b->unresolved, total));
  api__set(o, "perpetual_slip", share(b->perpetual, total));
  json_t *ret = json_object();
  api__set(ret, "total", json_integer(b->returns));
  api__set(ret, "max_to_land", json_integer(b->max_returns));
  api__set(o, "returns", ret);
  return api__answer(o, &SPEC, x, &x->ap, c, out);
}

void ep_basins_release(void *xp) {
  basins_x *x = xp;
  if (!x)
    return;
  ss_basins_free(&x->b);
  free(x);
}
