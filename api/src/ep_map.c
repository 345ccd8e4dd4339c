/*
 * ep_map.c: POST /map, the periodic orbits over a grid of one or two
 * parameters (ss_map_run), answered as NDJSON: one line per cell, then a
 * line {"done": true, ...}.
 *
 * The cells are computed together (a family found in one cell is continued
 * into its neighbours, and back), so the lines are written once the map is
 * done, in row-major order; the lines are made here with the writer, not as
 * JSON trees: a 100x100 map is 10000 of them.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "endpoints.h"
#include "decode.h"
#include "problem.h"
#include "writer.h"

static const char *const KINDS[] = {"overshoot", "stick-slip", "other", "all",
                                    NULL};
static const unsigned KIND_MASK[] = {SS_ORBIT_OVERSHOOT, SS_ORBIT_STICKSLIP,
                                     SS_ORBIT_OTHER, SS_ORBIT_ALL};

/* The fields of an orbit in a cell's line; the first N_DEFAULT_FIELDS of
 * them are sent when the request names none. */
static const char *const ORBIT_FIELDS[] = {
    "kind",        "n_turns",         "period",     "durations",
    "stable",      "spectral_radius", "min_margin", "modes",
    "multipliers", "marginal",        "found_by",   NULL};
enum {
  F_KIND,
  F_N_TURNS,
  F_PERIOD,
  F_DURATIONS,
  F_STABLE,
  F_RADIUS,
  F_MIN_MARGIN,
  F_MODES,
  F_MULTIPLIERS,
  F_MARGINAL,
  F_FOUND_BY,
  N_ORBIT_FIELDS,
  N_DEFAULT_FIELDS = F_MODES
};

typedef struct map_axis {
  int parameter; /* index in API_PARAMETER_NAMES */
  double from, to;
  long long n;
} map_axis;

typedef struct map_axes {
  map_axis a[2];
  int n;
} map_axes;

typedef struct map_fields {
  unsigned mask; /* bit k: ORBIT_FIELDS[k] */
} map_fields;

typedef struct map_x {
  /* the request */
  api_params ap;
  map_axes axes;
  int kind;
  long long max_period, effort, search_every;
  int edge_search;
  map_fields fields;
  int has_fields;
  /* the answer */
  ss_map map;
  ss_map_opts opts;
  double seconds;
} map_x;

static const api_field AXIS_FIELDS[] = {
    {"parameter", API_T_ENUM, API_REQUIRED, 0, 0, NULL,
     offsetof(map_axis, parameter), 0, 0, 0, API_PARAMETER_NAMES},
    {"from", API_T_NUMBER, API_REQUIRED, -INFINITY, INFINITY, NULL,
     offsetof(map_axis, from)},
    {"to", API_T_NUMBER, API_REQUIRED, -INFINITY, INFINITY, NULL,
     offsetof(map_axis, to)},
    {"n", API_T_COUNT, API_REQUIRED, 1, 1e9, NULL, offsetof(map_axis, n)},
};
static const api_spec AXIS_SPEC = API_SPEC(AXIS_FIELDS);

static int decode_axes(const json_t *v, const char *ptr, void *dest,
                       const api_call *c) {
  map_axes *ax = dest;
  if (!json_is_array(v) || json_array_size(v) < 1 || json_array_size(v) > 2)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an array of one or two axes {parameter, "
                     "from, to, n}",
                     ptr);
  ax->n = (int)json_array_size(v);
  for (int i = 0; i < ax->n; i++) {
    char p[64];
    snprintf(p, sizeof p, "%s/%d", ptr, i);
    const json_t *a = json_array_get(v, (size_t)i);
    if (!json_is_object(a))
      return api__fail(c->e, API_P_INVALID_TYPE, p,
                       "%s must be an object {parameter, from, to, n}", p);
    if (api__decode(&AXIS_SPEC, a, p, &ax->a[i], c))
      return -1;
    if (ax->a[i].n > 1 && !(ax->a[i].from != ax->a[i].to))
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s: from and to must differ when n > 1", p);
  }
  if (ax->n == 2 && ax->a[0].parameter == ax->a[1].parameter)
    return api__fail(c->e, API_P_INVALID_VALUE, "/axes/1/parameter",
                     "the two axes must vary different parameters, not both "
                     "%s",
                     API_PARAMETER_NAMES[ax->a[0].parameter]);
  return 0;
}

static json_t *echo_axes(const void *dest) {
  const map_axes *ax = dest;
  json_t *arr = json_array();
  for (int i = 0; i < ax->n; i++)
    json_array_append_new(arr, api__echo(&AXIS_SPEC, &ax->a[i]));
  return arr;
}

static const api_custom AXES = {decode_axes, echo_axes};

static int decode_fields(const json_t *v, const char *ptr, void *dest,
                         const api_call *c) {
  map_fields *f = dest;
  if (!json_is_array(v))
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an array of field names", ptr);
  f->mask = 0;
  for (size_t i = 0; i < json_array_size(v); i++) {
    const json_t *e = json_array_get(v, i);
    char p[64];
    int k = 0;
    snprintf(p, sizeof p, "%s/%zu", ptr, i);
    if (!json_is_string(e))
      return api__fail(c->e, API_P_INVALID_TYPE, p, "%s must be a string", p);
    while (k < N_ORBIT_FIELDS && strcmp(json_string_value(e), ORBIT_FIELDS[k]))
      k++;
    if (k == N_ORBIT_FIELDS)
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s: no orbit field \"%.40s\" (kind, n_turns, period, "
                       "durations, stable, spectral_radius, min_margin, "
                       "modes, multipliers, marginal, found_by)",
                       p, json_string_value(e));
    f->mask |= 1u << k;
  }
  return 0;
}

static json_t *echo_fields(const void *dest) {
  const map_fields *f = dest;
  json_t *a = json_array();
  for (int k = 0; k < N_ORBIT_FIELDS; k++)
    if (f->mask & (1u << k))
      json_array_append_new(a, json_string(ORBIT_FIELDS[k]));
  return a;
}

static const api_custom FIELDS_OF = {decode_fields, echo_fields};

static const api_field FIELDS[] = {
    API_PARAMS_FIELDS(map_x, ap),
    {"axes", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL, offsetof(map_x, axes), 0,
     0, 0, &AXES},
    {"kind", API_T_ENUM, API_DEFAULT, 0, 0, NULL, offsetof(map_x, kind), 0, 0,
     0, KINDS},
    {"max_period", API_T_COUNT, API_DEFAULT, 1, 8, NULL,
     offsetof(map_x, max_period)},
    {"effort", API_T_COUNT, API_DEFAULT, 1, 3, NULL, offsetof(map_x, effort)},
    {"search_every", API_T_COUNT, API_DEFAULT, 1, 1e9, NULL,
     offsetof(map_x, search_every)},
    {"edge_search", API_T_BOOL, API_DEFAULT, 0, 0, NULL,
     offsetof(map_x, edge_search)},
    {"fields", API_T_CUSTOM, 0, 0, 0, NULL, offsetof(map_x, fields),
     API_HAS(map_x, has_fields), 0, 0, &FIELDS_OF},
};
static const api_spec SPEC = API_SPEC(FIELDS);

int ep_map_decode(const json_t *root, const api_call *c, void **xp) {
  map_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->kind = 3; /* all */
  x->max_period = 4;
  x->effort = 2;
  x->search_every = 8;
  x->edge_search = 1;
  if (api__decode_request(&SPEC, root, x, &x->ap, c))
    return -1;
  if (!x->has_fields)
    x->fields.mask = (1u << N_DEFAULT_FIELDS) - 1;
  long long cells = 1;
  for (int i = 0; i < x->axes.n; i++) {
    const map_axis *a = &x->axes.a[i];
    char p[64];
    snprintf(p, sizeof p, "/axes/%d/parameter", i);
    int physical = a->parameter >= API_N_DIMENSIONLESS;
    if (x->ap.has_physical != physical)
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       x->ap.has_physical
                           ? "%s must be a physical parameter (m1, m2, k1, "
                             "k2, Fs, Fr, v0) for a request in physical units"
                           : "%s must be a dimensionless parameter (chi, eta, "
                             "us, ur, V); send \"physical\" to map physical "
                             "ones",
                       p);
    cells *= a->n;
    if (cells > (long long)c->lim->max_map_cells) {
      snprintf(p, sizeof p, "/axes/%d/n", i);
      return api__limit(c->e, "max_map_cells", (double)c->lim->max_map_cells, p,
                        "the map has %lld cells or more, over the limit "
                        "of %zu",
                        cells, c->lim->max_map_cells);
    }
  }
  ss_map_opts *o = &x->opts;
  o->kinds = KIND_MASK[x->kind];
  o->max_period = (int)x->max_period;
  o->effort = (int)x->effort;
  o->search_every = x->search_every > 1000000 ? 1000000 : (int)x->search_every;
  o->no_edge_search = !x->edge_search;
  o->physical = x->ap.has_physical ? &x->ap.ph : NULL;
  o->threads = api__threads(c, cells);
  o->max_seconds = c->lim->max_seconds;
  if (c->srv && c->srv->cancelled) {
    o->cancelled = c->srv->cancelled;
    o->cancel_cls = c->srv->cancel_cls;
  }
  return 0;
}

/* The core's axis of request axis @a a. */
static ss_map_axis core_axis(const map_axis *a) {
  ss_map_axis s = {a->parameter >= API_N_DIMENSIONLESS
                       ? a->parameter - API_N_DIMENSIONLESS
                       : a->parameter,
                   a->from, a->to, (int)a->n};
  return s;
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int ep_map_run(void *xp, const api_call *c) {
  map_x *x = xp;
  ss_map_axis axes[2];
  ss_diag d;
  for (int i = 0; i < x->axes.n; i++)
    axes[i] = core_axis(&x->axes.a[i]);
  ss_diag_clear(&d);
  double t0 = now();
  int rc = ss_map_run(x->ap.has_physical ? NULL : &x->ap.p, x->axes.n, axes,
                      &x->opts, &x->map, &d);
  x->seconds = now() - t0;
  if (rc == SS_ELIMIT_TIME)
    return api__status_limit(c->e, rc, "max_seconds", c->lim->max_seconds, "",
                             "the map needed more than %g s; make it "
                             "smaller or coarser, or search less "
                             "(search_every, edge_search, effort)",
                             c->lim->max_seconds);
  if (rc == SS_EDOMAIN)
    /* a cell out of the parameters' ranges */
    return api__fail(c->e, API_P_INVALID_VALUE, "/axes",
                     "a cell of the map has parameters out of range: %s",
                     d.text);
  if (rc)
    return api__from_diag(c->e, rc, &d, "");
  return 0;
}

static void w_int(api_wbuf *w, long v) {
  char num[32];
  api__w_put(w, num, (size_t)snprintf(num, sizeof num, "%ld", v));
}

static void w_key(api_wbuf *w, int *first, const char *key) {
  if (!*first)
    API_W_LIT(w, ",");
  *first = 0;
  api__w_put(w, "\"", 1);
  api__w_put(w, key, strlen(key));
  api__w_put(w, "\":", 2);
}

static void w_orbit(api_wbuf *w, const ss_map_orbit *o, unsigned mask,
                    double omega) {
  int first = 1;
  API_W_LIT(w, "{");
  for (int k = 0; k < N_ORBIT_FIELDS; k++) {
    if (!(mask & (1u << k)))
      continue;
    w_key(w, &first, ORBIT_FIELDS[k]);
    switch (k) {
    case F_KIND: {
      const char *s = ss_orbit_kind_name(o->kind);
      api__w_str(w, s, strlen(s));
      break;
    }
    case F_N_TURNS:
      w_int(w, o->n_turns);
      break;
    case F_PERIOD:
      api__w_real(w, o->period / omega);
      break;
    case F_DURATIONS:
    case F_MODES:
      API_W_LIT(w, "[");
      for (int i = 0; i < o->n_phases; i++) {
        if (i)
          API_W_LIT(w, ",");
        if (k == F_DURATIONS)
          api__w_real(w, o->durations[i] / omega);
        else {
          const char *s = ss_mode_name(o->modes[i]);
          api__w_str(w, s, strlen(s));
        }
      }
      API_W_LIT(w, "]");
      break;
    case F_STABLE:
      if (o->stable)
        API_W_LIT(w, "true");
      else
        API_W_LIT(w, "false");
      break;
    case F_RADIUS:
      api__w_real(w, o->spectral_radius);
      break;
    case F_MIN_MARGIN:
      API_W_LIT(w, "{\"value\":");
      api__w_real(w, o->min_margin.value);
      if (o->min_margin.phase >= 0) {
        API_W_LIT(w, ",\"phase\":");
        w_int(w, o->min_margin.phase);
        API_W_LIT(w, ",\"t\":");
        api__w_real(w, o->min_margin.t / omega);
      }
      API_W_LIT(w, "}");
      break;
    case F_MULTIPLIERS:
      API_W_LIT(w, "[[");
      api__w_real(w, o->eig_re[0]);
      API_W_LIT(w, ",");
      api__w_real(w, o->eig_im[0]);
      API_W_LIT(w, "],[");
      api__w_real(w, o->eig_re[1]);
      API_W_LIT(w, ",");
      api__w_real(w, o->eig_im[1]);
      API_W_LIT(w, "]]");
      break;
    case F_MARGINAL:
      if (o->marginal)
        API_W_LIT(w, "true");
      else
        API_W_LIT(w, "false");
      break;
    case F_FOUND_BY:
      if (o->from_cell < 0)
        API_W_LIT(w, "\"search\"");
      else
        API_W_LIT(w, "\"continuation\"");
      break;
    }
  }
  API_W_LIT(w, "}");
}

int ep_map_encode(const void *xp, const api_call *c, api_response *out) {
  const map_x *x = xp;
  const ss_map *mp = &x->map;
  api_wbuf w = {NULL, 0, 0, 0};
  int n1 = mp->axes[1].n, with = 0, orbits = 0, complete = 0;
  for (int cell = 0; cell < mp->n_cells && !w.oom; cell++) {
    const ss_map_cell *ce = &mp->cells[cell];
    double omega = 1;
    ss_params q;
    ss_map_params(&x->ap.p, &x->opts, mp, cell, &q, &omega, NULL);
    API_W_LIT(&w, "{\"index\":[");
    if (mp->n_axes == 2) {
      w_int(&w, cell / n1);
      API_W_LIT(&w, ",");
      w_int(&w, cell % n1);
    } else {
      w_int(&w, cell);
    }
    API_W_LIT(&w, "],\"at\":{");
    for (int a = 0; a < mp->n_axes; a++) {
      const char *name = API_PARAMETER_NAMES[x->axes.a[a].parameter];
      if (a)
        API_W_LIT(&w, ",");
      api__w_str(&w, name, strlen(name));
      API_W_LIT(&w, ":");
      api__w_real(&w, ss_map_value(&mp->axes[a], mp->n_axes == 2 && a == 0
                                                     ? cell / n1
                                                     : cell % n1));
    }
    API_W_LIT(&w, "},\"orbits\":[");
    for (int i = 0; i < ce->n_orbits; i++) {
      if (i)
        API_W_LIT(&w, ",");
      w_orbit(&w, &ce->orbits[i], x->fields.mask, omega);
    }
    API_W_LIT(&w, "],\"complete\":");
    if (ce->complete)
      API_W_LIT(&w, "true");
    else
      API_W_LIT(&w, "false");
    if (ce->truncated) {
      API_W_LIT(&w, ",\"truncated\":");
      w_int(&w, ce->truncated);
    }
    API_W_LIT(&w, "}\n");
    with += ce->n_orbits > 0;
    orbits += ce->n_orbits;
    complete += ce->complete;
  }
  /* the last line: counts, and the request as it was understood */
  json_t *in = api__echo(&SPEC, x);
  api__params_echo(in, &x->ap);
  size_t n_in = 0;
  char *in_text = api__dump(in, &n_in);
  json_decref(in);
  API_W_LIT(&w, "{\"done\":true,\"cells\":");
  w_int(&w, mp->n_cells);
  API_W_LIT(&w, ",\"with_orbits\":");
  w_int(&w, with);
  API_W_LIT(&w, ",\"orbits\":");
  w_int(&w, orbits);
  API_W_LIT(&w, ",\"complete\":");
  w_int(&w, complete);
  API_W_LIT(&w, ",\"searches\":");
  w_int(&w, mp->searches);
  API_W_LIT(&w, ",\"solves\":");
  w_int(&w, mp->solves);
  API_W_LIT(&w, ",\"seconds\":");
  api__w_real(&w, x->seconds);
  API_W_LIT(&w, ",\"units\":");
  if (x->ap.has_physical)
    API_W_LIT(&w, "\"physical\"");
  else
    API_W_LIT(&w, "\"dimensionless\"");
  API_W_LIT(&w, ",\"version\":\"" SS_VERSION "\",\"input\":");
  if (in_text)
    api__w_put(&w, in_text, n_in);
  else
    API_W_LIT(&w, "null");
  API_W_LIT(&w, "}\n");
  free(in_text);
  (void)c;
  if (w.oom || !in_text) {
    free(w.p);
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                     "the answer could not be written: out of memory");
  }
  out->status = 200;
  out->content_type = "application/x-ndjson";
  out->body = w.p;
  out->len = w.len;
  out->held = w.len;
  return 0;
}

void ep_map_release(void *xp) {
  map_x *x = xp;
  if (!x)
    return;
  ss_map_free(&x->map);
  free(x);
}
