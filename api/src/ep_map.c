/*
 * ep_map.c: POST /map, the periodic orbits over a grid of one or two
 * parameters (ss_map_run), answered as NDJSON: one line per cell, then a
 * line {"done": true, ...}.
 *
 * The cells are computed together (a family found in one cell is continued
 * into its neighbours, and back), so the lines are written once the map is
 * done, in row-major order; the lines are made here with the writer, not as
 * JSON trees: a 100x100 map is 10000 of them.
 *
 * As a job (job.h), a map is cut where the core cuts it (ss_map_lattice,
 * ss_map_search, ss_map_opts.searched): stage 0, the full searches of the
 * map's lattice in groups of MAP_JOB_SEARCHES, each group a chunk that is
 * not part of the answer; stage 1, one chunk that reads them, makes the
 * map with them (the searches where families end, and the spreading, are
 * its own) and writes the lines the synchronous map writes.  A group's
 * result is a JSON document of what its searches found, every double in
 * the shortest digits that read back as the same double (the writer's, a
 * non-finite one as the string "inf", "-inf" or "nan"), so that the map
 * made from them is the synchronous map bit for bit, hence byte for byte
 * its lines.  The done line's "seconds" of a job is its compute time: the
 * seconds of every group (each result records its own) and of the last
 * chunk's map, summed.  Its items are the map's cells: a group counts the
 * cells it searched, the last chunk the others.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "endpoints.h"
#include "decode.h"
#include "job.h"
#include "problem.h"
#include "writer.h"

/* The full searches of one chunk of a map's job: at 10-30 ms each (up to
 * 120 ms where the search is hard; effort 2, measured on overshoot,
 * stick-slip and all-kinds maps), a chunk takes about 0.2-0.5 s. */
#define MAP_JOB_SEARCHES 16

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

/* The map's cells. */
static long long cells_of(const map_x *x) {
  long long cells = 1;
  for (int i = 0; i < x->axes.n; i++)
    cells *= x->axes.a[i].n;
  return cells;
}

/* The options of @a x's map that the call sets (@a o: x->opts, or a copy
 * of it in a copy of x): its threads, time budget, cancel hook, and where
 * the physical parameters are. */
static void call_opts(const map_x *x, const api_call *c, ss_map_opts *o) {
  o->physical = x->ap.has_physical ? &x->ap.ph : NULL;
  o->threads = api__threads(c, cells_of(x));
  o->max_seconds = c->lim->max_seconds;
  o->cancelled = NULL;
  o->cancel_cls = NULL;
  if (c->srv && c->srv->cancelled) {
    o->cancelled = c->srv->cancelled;
    o->cancel_cls = c->srv->cancel_cls;
  }
}

int ep_map_decode(const json_t *root, const api_call *c, void **xp) {
  map_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->kind = 3; /* all */
  x->max_period = 4;
  x->effort = 2;
  x->search_every = 1;
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
  call_opts(x, c, o);
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

/* The core's axes of @a x, into @a axes. */
static void core_axes(const map_x *x, ss_map_axis axes[2]) {
  for (int i = 0; i < x->axes.n; i++)
    axes[i] = core_axis(&x->axes.a[i]);
}

static const ss_params *params_of(const map_x *x) {
  return x->ap.has_physical ? NULL : &x->ap.p;
}

/* The problem of a map's status @a rc (not SS_OK): -1. */
static int map_problem(int rc, const ss_diag *d, const api_call *c) {
  if (rc == SS_ELIMIT_TIME)
    return api__status_limit(c->e, rc, "max_seconds", c->lim->max_seconds, "",
                             "the map needed more than %g s; run it as a "
                             "job (Prefer: respond-async), make it smaller "
                             "or coarser, or search less (search_every, "
                             "edge_search, effort)",
                             c->lim->max_seconds);
  if (rc == SS_EDOMAIN)
    /* a cell out of the parameters' ranges */
    return api__fail(c->e, API_P_INVALID_VALUE, "/axes",
                     "a cell of the map has parameters out of range: %s",
                     d->text);
  return api__from_diag(c->e, rc, d, "");
}

/* The map of @a x with its options into x->map, its time in x->seconds. */
static int run_map(map_x *x, const api_call *c) {
  ss_map_axis axes[2];
  ss_diag d;
  core_axes(x, axes);
  ss_diag_clear(&d);
  double t0 = now();
  int rc = ss_map_run(params_of(x), x->axes.n, axes, &x->opts, &x->map, &d);
  x->seconds = now() - t0;
  return rc ? map_problem(rc, &d, c) : 0;
}

int ep_map_run(void *xp, const api_call *c) { return run_map(xp, c); }

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
      api__w_int(w, o->n_turns);
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
        api__w_int(w, o->min_margin.phase);
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
      api__w_int(&w, cell / n1);
      API_W_LIT(&w, ",");
      api__w_int(&w, cell % n1);
    } else {
      api__w_int(&w, cell);
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
      api__w_int(&w, ce->truncated);
    }
    API_W_LIT(&w, "}\n");
    with += ce->n_orbits > 0;
    orbits += ce->n_orbits;
    complete += ce->complete;
  }
  /* the last line: counts, and the request as it was understood */
  API_W_LIT(&w, "{\"done\":true,\"cells\":");
  api__w_int(&w, mp->n_cells);
  API_W_LIT(&w, ",\"with_orbits\":");
  api__w_int(&w, with);
  API_W_LIT(&w, ",\"orbits\":");
  api__w_int(&w, orbits);
  API_W_LIT(&w, ",\"complete\":");
  api__w_int(&w, complete);
  API_W_LIT(&w, ",\"searches\":");
  api__w_int(&w, mp->searches);
  API_W_LIT(&w, ",\"solves\":");
  api__w_int(&w, mp->solves);
  API_W_LIT(&w, ",\"seconds\":");
  api__w_real(&w, x->seconds);
  API_W_LIT(&w, ",\"units\":");
  if (x->ap.has_physical)
    API_W_LIT(&w, "\"physical\"");
  else
    API_W_LIT(&w, "\"dimensionless\"");
  API_W_LIT(&w, ",\"version\":\"" SS_VERSION "\",\"input\":");
  if (api__echo_as_tree) {
    json_t *in = api__echo(&SPEC, x);
    api__params_echo(in, &x->ap);
    api__w_json(&w, in);
    json_decref(in);
  } else
    api__w_echo(&w, &SPEC, x, &x->ap);
  API_W_LIT(&w, "}\n");
  if (w.oom) {
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

/* ---- as a job ------------------------------------------------------------
 */

/* A double that reads back as itself: the shortest exact digits, or the
 * string "inf", "-inf" or "nan" (JSON has no such numbers). */
static void w_exact(api_wbuf *w, double v) {
  if (isfinite(v))
    api__w_real(w, v);
  else if (isnan(v))
    API_W_LIT(w, "\"nan\"");
  else if (v > 0)
    API_W_LIT(w, "\"inf\"");
  else
    API_W_LIT(w, "\"-inf\"");
}

static void w_exacts(api_wbuf *w, const double *v, int n) {
  API_W_LIT(w, "[");
  for (int i = 0; i < n; i++) {
    if (i)
      API_W_LIT(w, ",");
    w_exact(w, v[i]);
  }
  API_W_LIT(w, "]");
}

/* The search of @a cell as a group's result holds it. */
static void w_found(api_wbuf *w, int cell, const ss_map_found *f) {
  API_W_LIT(w, "{\"cell\":");
  api__w_int(w, cell);
  API_W_LIT(w, ",\"status\":");
  api__w_int(w, f->status);
  API_W_LIT(w, ",\"diag\":{\"status\":");
  api__w_int(w, f->diag.status);
  API_W_LIT(w, ",\"where\":");
  api__w_str(w, f->diag.where, strnlen(f->diag.where, sizeof f->diag.where));
  API_W_LIT(w, ",\"value\":");
  w_exact(w, f->diag.value);
  API_W_LIT(w, ",\"text\":");
  api__w_str(w, f->diag.text, strnlen(f->diag.text, sizeof f->diag.text));
  API_W_LIT(w, "},\"orbits\":[");
  for (int i = 0; i < f->n_orbits; i++) {
    const ss_map_orbit *o = &f->orbits[i];
    if (i)
      API_W_LIT(w, ",");
    API_W_LIT(w, "{\"kind\":");
    api__w_int(w, o->kind);
    API_W_LIT(w, ",\"modes\":[");
    for (int k = 0; k < o->n_phases; k++) {
      if (k)
        API_W_LIT(w, ",");
      api__w_int(w, o->modes[k]);
    }
    API_W_LIT(w, "],\"durations\":");
    w_exacts(w, o->durations, o->n_phases);
    API_W_LIT(w, ",\"period\":");
    w_exact(w, o->period);
    API_W_LIT(w, ",\"n_turns\":");
    api__w_int(w, o->n_turns);
    API_W_LIT(w, ",\"z0\":");
    w_exacts(w, o->z0, 4);
    API_W_LIT(w, ",\"eig_re\":");
    w_exacts(w, o->eig_re, 2);
    API_W_LIT(w, ",\"eig_im\":");
    w_exacts(w, o->eig_im, 2);
    API_W_LIT(w, ",\"spectral_radius\":");
    w_exact(w, o->spectral_radius);
    API_W_LIT(w, ",\"stable\":");
    api__w_int(w, o->stable);
    API_W_LIT(w, ",\"marginal\":");
    api__w_int(w, o->marginal);
    API_W_LIT(w, ",\"min_margin\":[");
    w_exact(w, o->min_margin.value);
    API_W_LIT(w, ",");
    api__w_int(w, o->min_margin.phase);
    API_W_LIT(w, ",");
    w_exact(w, o->min_margin.t);
    API_W_LIT(w, "],\"from_cell\":");
    api__w_int(w, o->from_cell);
    API_W_LIT(w, "}");
  }
  API_W_LIT(w, "]}");
}

/* A double written by w_exact; 0 when @a v is none. */
static int r_exact(const json_t *v, double *out) {
  if (json_is_number(v))
    *out = json_number_value(v);
  else if (json_is_string(v) && (!strcmp(json_string_value(v), "nan") ||
                                 !strcmp(json_string_value(v), "inf") ||
                                 !strcmp(json_string_value(v), "-inf")))
    *out = strtod(json_string_value(v), NULL);
  else
    return 0;
  return 1;
}

static int r_exacts(const json_t *a, double *out, size_t n) {
  int ok = json_is_array(a) && json_array_size(a) == n;
  for (size_t i = 0; ok && i < n; i++)
    ok = r_exact(json_array_get(a, i), &out[i]);
  return ok;
}

static int r_int(const json_t *v, int *out) {
  if (!json_is_integer(v))
    return 0;
  *out = (int)json_integer_value(v);
  return 1;
}

/* An orbit written by w_found into @a o (zeroed first, as the core makes
 * it); 0 when @a j is none. */
static int r_orbit(const json_t *j, ss_map_orbit *o) {
  const json_t *modes = json_object_get(j, "modes");
  const json_t *mm = json_object_get(j, "min_margin");
  int kind = 0;
  size_t n = json_array_size(modes);
  memset(o, 0, sizeof *o);
  int ok = json_is_array(modes) && n >= 1 && n <= SS_MAX_PHASES &&
           r_int(json_object_get(j, "kind"), &kind);
  o->kind = (ss_orbit_kind)kind;
  o->n_phases = (int)n;
  for (size_t k = 0; ok && k < n; k++) {
    int m = 0;
    ok = r_int(json_array_get(modes, k), &m);
    o->modes[k] = (ss_mode)m;
  }
  return ok && r_exacts(json_object_get(j, "durations"), o->durations, n) &&
         r_exact(json_object_get(j, "period"), &o->period) &&
         r_int(json_object_get(j, "n_turns"), &o->n_turns) &&
         r_exacts(json_object_get(j, "z0"), o->z0, 4) &&
         r_exacts(json_object_get(j, "eig_re"), o->eig_re, 2) &&
         r_exacts(json_object_get(j, "eig_im"), o->eig_im, 2) &&
         r_exact(json_object_get(j, "spectral_radius"), &o->spectral_radius) &&
         r_int(json_object_get(j, "stable"), &o->stable) &&
         r_int(json_object_get(j, "marginal"), &o->marginal) &&
         json_array_size(mm) == 3 &&
         r_exact(json_array_get(mm, 0), &o->min_margin.value) &&
         r_int(json_array_get(mm, 1), &o->min_margin.phase) &&
         r_exact(json_array_get(mm, 2), &o->min_margin.t) &&
         r_int(json_object_get(j, "from_cell"), &o->from_cell);
}

/* A search written by w_found into @a f; 0 when @a j is none. */
static int r_found(const json_t *j, ss_map_found *f) {
  const json_t *d = json_object_get(j, "diag");
  const json_t *orbits = json_object_get(j, "orbits");
  const char *where = json_string_value(json_object_get(d, "where"));
  const char *text = json_string_value(json_object_get(d, "text"));
  size_t n = json_array_size(orbits);
  memset(f, 0, sizeof *f);
  int ok = r_int(json_object_get(j, "status"), &f->status) &&
           r_int(json_object_get(d, "status"), &f->diag.status) &&
           r_exact(json_object_get(d, "value"), &f->diag.value) && where &&
           strlen(where) < sizeof f->diag.where && text &&
           strlen(text) < sizeof f->diag.text && json_is_array(orbits) &&
           n <= SS_MAP_FOUND_MAX;
  if (ok) {
    strcpy(f->diag.where, where);
    strcpy(f->diag.text, text);
    f->n_orbits = (int)n;
  }
  for (size_t i = 0; ok && i < n; i++)
    ok = r_orbit(json_array_get(orbits, i), &f->orbits[i]);
  return ok;
}

/* The cells of @a x's lattice (malloc'd) and their count; NULL and the
 * problem the synchronous map answers for its arguments. */
static int *lattice_of(const map_x *x, const api_call *c, int *n) {
  ss_map_axis axes[2];
  ss_diag d;
  core_axes(x, axes);
  ss_diag_clear(&d);
  int *cells = malloc((size_t)cells_of(x) * sizeof *cells);
  if (!cells) {
    api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
              "the map could not be cut: out of memory");
    return NULL;
  }
  int rc =
      ss_map_lattice(params_of(x), x->axes.n, axes, &x->opts, cells, n, &d);
  if (rc) {
    free(cells);
    map_problem(rc, &d, c);
    return NULL;
  }
  return cells;
}

/* The map's row of API_JOB_CUTS (job.c). */
ep_job_cut_fn ep_map_job_cut;
ep_job_run_fn ep_map_job_run;

int ep_map_job_cut(const void *xp, const api_call *c, api_job_cut *cut) {
  const map_x *x = xp;
  int n = 0;
  int *cells = lattice_of(x, c, &n);
  if (!cells)
    return -1;
  free(cells);
  size_t groups = ((size_t)n + MAP_JOB_SEARCHES - 1) / MAP_JOB_SEARCHES;
  if (api__job_cut_alloc(cut, groups + 1, c))
    return -1;
  for (size_t k = 0; k < groups; k++) {
    size_t left = (size_t)n - k * MAP_JOB_SEARCHES;
    cut->items[k] = (long)(left < MAP_JOB_SEARCHES ? left : MAP_JOB_SEARCHES);
  }
  cut->stage[groups] = 1;
  cut->items[groups] = (long)(cells_of(x) - n);
  cut->visible[groups] = 1;
  return 0;
}

/* Group @a k of the lattice's searches: {"searches": [...], "seconds"},
 * within the call's time budget as a whole. */
static int run_group(const map_x *x, size_t k, const int *cells, int n,
                     const api_call *c, api_response *out) {
  int rc = SS_OK;
  ss_map_axis axes[2];
  ss_map_opts o = x->opts;
  ss_map_found *f = malloc(sizeof *f);
  ss_diag d;
  api_wbuf w = {NULL, 0, 0, 0};
  size_t from = k * MAP_JOB_SEARCHES, to = from + MAP_JOB_SEARCHES;
  core_axes(x, axes);
  call_opts(x, c, &o);
  ss_diag_clear(&d);
  API_W_LIT(&w, "{\"searches\":[");
  double t0 = now();
  for (size_t i = from; i < to && i < (size_t)n && f && rc == SS_OK; i++) {
    double left = c->lim->max_seconds - (now() - t0);
    if (c->lim->max_seconds > 0 && !(left > 0)) {
      rc = SS_ELIMIT_TIME;
      break;
    }
    o.max_seconds = c->lim->max_seconds > 0 ? left : 0;
    rc = ss_map_search(params_of(x), x->axes.n, axes, &o, cells[i], f, &d);
    if (rc == SS_OK &&
        (f->status == SS_ELIMIT_TIME || f->status == SS_ECANCELED)) {
      rc = f->status; /* stopped, not searched: no result */
      d = f->diag;
    }
    if (rc == SS_OK) {
      if (i > from)
        API_W_LIT(&w, ",");
      w_found(&w, cells[i], f);
    }
  }
  API_W_LIT(&w, "],\"seconds\":");
  api__w_real(&w, now() - t0);
  API_W_LIT(&w, "}");
  if (!f || w.oom || rc) {
    free(f);
    free(w.p);
    return rc ? map_problem(rc, &d, c)
              : api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                          "the searches could not be written: out of memory");
  }
  free(f);
  out->status = 200;
  out->content_type = "application/json";
  out->body = w.p;
  out->len = w.len;
  out->held = w.len;
  return 0;
}

/* The groups' searches read back, by cell (ss_map_opts.searched). */
typedef struct given {
  json_t **docs; /* one per group */
  size_t n_docs;
  const json_t **by_cell; /* a search of the docs, or NULL */
  int bad;                /* a search that could not be read */
} given;

static int given_search(void *cls, int cell, ss_map_found *found) {
  given *g = cls;
  if (!g->by_cell[cell])
    return 0;
  if (r_found(g->by_cell[cell], found))
    return 1;
  g->bad = 1; /* the map then searches it itself; the chunk fails after */
  return 0;
}

/* Read the results of the @a groups chunks of stage 0 into @a g, their
 * seconds into *seconds: 0, or -1 and the problem. */
static int read_groups(size_t groups, long long cells, const api_job_inputs *in,
                       const api_call *c, given *g, double *seconds) {
  g->docs = calloc(groups ? groups : 1, sizeof *g->docs);
  g->by_cell = calloc((size_t)cells, sizeof *g->by_cell);
  if (!g->docs || !g->by_cell)
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                     "the searches could not be read: out of memory");
  *seconds = 0;
  for (size_t k = 0; k < groups; k++, g->n_docs++) {
    char *buf = NULL;
    size_t len = 0;
    double s = 0;
    if (!in || !in->read || in->read(in->cls, k, &buf, &len) != 0)
      return api__fail(c->e, API_P_INTERNAL, NULL,
                       "the searches of chunk %zu could not be read", k);
    g->docs[k] = json_loadb(buf, len, 0, NULL);
    free(buf);
    const json_t *a = json_object_get(g->docs[k], "searches");
    int ok =
        json_is_array(a) && r_exact(json_object_get(g->docs[k], "seconds"), &s);
    for (size_t i = 0; ok && i < json_array_size(a); i++) {
      const json_t *e = json_array_get(a, i);
      int cell = -1;
      ok =
          r_int(json_object_get(e, "cell"), &cell) && cell >= 0 && cell < cells;
      if (ok)
        g->by_cell[cell] = e;
    }
    if (!ok)
      return api__fail(c->e, API_P_INTERNAL, NULL,
                       "the searches of chunk %zu are not what a chunk "
                       "writes",
                       k);
    *seconds += s;
  }
  return 0;
}

static void given_free(given *g) {
  for (size_t k = 0; g->docs && k < g->n_docs; k++)
    json_decref(g->docs[k]);
  free(g->docs);
  free(g->by_cell);
}

/* The last chunk: the map made with the groups' searches, written as the
 * synchronous map writes it; its seconds those of every chunk. */
static int run_last(const map_x *x, size_t groups, const api_job_inputs *in,
                    const api_call *c, api_response *out) {
  map_x *y = malloc(sizeof *y);
  given g = {NULL, 0, NULL, 0};
  double before = 0;
  int rc = -1;
  if (!y) {
    api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
    goto done;
  }
  *y = *x; /* its own map and options; x is shared by the chunks */
  call_opts(y, c, &y->opts);
  y->opts.searched = given_search;
  y->opts.searched_cls = &g;
  if (read_groups(groups, cells_of(x), in, c, &g, &before))
    goto done;
  rc = run_map(y, c);
  y->seconds += before;
  if (rc == 0 && g.bad)
    rc = api__fail(c->e, API_P_INTERNAL, NULL,
                   "a search of the map's lattice could not be read");
  if (rc == 0)
    rc = ep_map_encode(y, c, out);
  ss_map_free(&y->map);
done:
  given_free(&g);
  free(y);
  return rc;
}

int ep_map_job_run(const void *xp, size_t k, const api_job_inputs *in,
                   const api_call *c, api_response *out) {
  const map_x *x = xp;
  int n = 0;
  int *cells = lattice_of(x, c, &n);
  if (!cells)
    return -1;
  size_t groups = ((size_t)n + MAP_JOB_SEARCHES - 1) / MAP_JOB_SEARCHES;
  int rc = k < groups ? run_group(x, k, cells, n, c, out)
                      : run_last(x, groups, in, c, out);
  free(cells);
  return rc;
}
