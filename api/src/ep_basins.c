/*
 * ep_basins.c: POST /basins, the attractors of one parameter set and the
 * basin of each over a two-dimensional slice of initial states
 * (ss_basins_run); the labels as a base64 byte array, row-major.
 *
 * Its other form, NDJSON (API_FORM_NDJSON, asked with Accept:
 * application/x-ndjson), is the map in the order the core's stages make
 * it, one line each:
 *   the head     {"labels": {rows, cols, encoding, unresolved,
 *                perpetual_slip}, "attractors": [...]}: the slice and the
 *                attractors of the orbit search (stage 0), without counts;
 *   a group of rows, from the first  {"row", "rows", "labels": base64 of
 *                their labels, "returns", "max_to_land"}: the labels of
 *                stage 1, final for every cell labelled with an attractor;
 *                a cell labelled unresolved (255) may still land on an
 *                attractor found by simulation;
 *   the last     {"done": true, "attractors": all of them, with their
 *                counts, "relabelled": [[cell, count, label], ...], the
 *                shares and returns of the JSON form, its input, units and
 *                version}: each run of consecutive cells (row-major index
 *                of the first, how many) whose label stage 2 changed, and
 *                the label they now have.
 * The rows' lines and the runs give the JSON form's labels exactly.  As a
 * job (below) each line is the result of a chunk, so its results stream
 * the rows as they are stored.
 */
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "endpoints.h"
#include "decode.h"
#include "encode.h"
#include "job.h"
#include "problem.h"
#include "values.h"
#include "writer.h"

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
  int ndjson;                 /* its form: lines (API_FORM_NDJSON) */
  api_wbuf lines;             /* of that form, the head and the rows' lines */
  unsigned char *provisional; /* the labels of stage 1, before stage 2 */
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

/* What the call gives a computation over @a rows rows: its threads, its
 * time budget and its cancel hook. */
static void call_opts(const api_call *c, long long rows, ss_basin_opts *o) {
  o->threads = api__threads(c, rows);
  o->max_seconds = c->lim->max_seconds;
  o->cancelled = NULL;
  o->cancel_cls = NULL;
  if (c->srv && c->srv->cancelled) {
    o->cancelled = c->srv->cancelled;
    o->cancel_cls = c->srv->cancel_cls;
  }
}

int ep_basins_decode(const json_t *root, const api_call *c, void **xp) {
  basins_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->max_period = 4;
  x->max_returns = 500;
  x->ndjson = c->form == API_FORM_NDJSON;
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
  call_opts(c, x->axes.a[0].n, o);
  return 0;
}

/* The problem of a core status @a rc that is not SS_OK; 0 for SS_OK. */
static int basins_problem(int rc, const ss_diag *d, const api_call *c) {
  if (rc == SS_ELIMIT_TIME)
    return api__status_limit(c->e, rc, "max_seconds", c->lim->max_seconds, "",
                             "the basins needed more than %g s; make the "
                             "slice smaller or coarser, or lower max_returns",
                             c->lim->max_seconds);
  if (rc)
    return api__from_diag(c->e, rc, d, "");
  return 0;
}

static int run_lines(basins_x *x, const api_call *c);

int ep_basins_run(void *xp, const api_call *c) {
  basins_x *x = xp;
  if (x->ndjson)
    return run_lines(x, c);
  ss_diag d;
  ss_diag_clear(&d);
  return basins_problem(ss_basins_run(&x->m, &x->opts, &x->b, &d), &d, c);
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

/* Attractor @a i of @a b as the answer writes it; its cells and fraction
 * only when @a counted (after stage 2). */
static json_t *attractor_json(const basins_x *x, const ss_basins *b, int i,
                              double total, int counted) {
  const ss_basin_attractor *a = &b->attractors[i];
  const ss_orbit *o = &a->orbit;
  const api_params *ap = &x->ap;
  json_t *j = json_object(), *sec = json_array();
  api__set(j, "label", json_integer(i));
  api__set(j, "kind", json_string(ss_orbit_kind_name(o->kind)));
  api_wbuf w = {NULL, 0, 0, 0};
  api__w_phases(&w, o, ap);
  api__set(j, "phases", api__json_of(&w));
  api__set(j, "period", api__real(api__time_out(ap, o->period)));
  api__set(j, "n_turns", json_integer(o->n_turns));
  api__set(j, "x0", api__state(ap, o->x0));
  api__w_stability(&w, &o->stab, ap);
  api__set(j, "stability", api__json_of(&w));
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
  if (counted) {
    api__set(j, "cells", json_integer(a->cells));
    api__set(j, "fraction", api__real((double)a->cells / total));
  }
  return j;
}

/* The attractors of @a b as an array (see attractor_json). */
static json_t *attractors_json(const basins_x *x, const ss_basins *b,
                               int counted) {
  double total = (double)b->n[0] * (double)b->n[1];
  json_t *arr = json_array();
  for (int i = 0; i < b->n_attractors; i++)
    json_array_append_new(arr, attractor_json(x, b, i, total, counted));
  return arr;
}

/* The labels' description: the slice's shape, the labels themselves when
 * @a data is not NULL (their base64), and the labels that are not an
 * attractor's. */
static json_t *labels_json(const ss_basins *b, const char *data) {
  json_t *lab = json_object();
  api__set(lab, "rows", json_integer(b->n[0]));
  api__set(lab, "cols", json_integer(b->n[1]));
  api__set(lab, "encoding", json_string("base64"));
  if (data)
    api__set(lab, "data", json_string(data));
  api__set(lab, "unresolved", json_integer(SS_BASIN_UNRESOLVED));
  api__set(lab, "perpetual_slip", json_integer(SS_BASIN_PERPETUAL));
  return lab;
}

/* What both forms end with, set on @a o: the attractors with their counts
 * (in the place of a key "attractors" @a o has already, if it has one),
 * the unresolved and perpetual shares, the returns. */
static void summary(const basins_x *x, json_t *o) {
  const ss_basins *b = &x->b;
  double total = (double)b->n[0] * (double)b->n[1];
  api__set(o, "attractors", attractors_json(x, b, 1));
  api__set(o, "unresolved", share(b->unresolved, total));
  api__set(o, "perpetual_slip", share(b->perpetual, total));
  json_t *ret = json_object();
  api__set(ret, "total", json_integer(b->returns));
  api__set(ret, "max_to_land", json_integer(b->max_returns));
  api__set(o, "returns", ret);
}

/* The relabelled runs of the last line: each run of consecutive cells
 * whose label is @a after and not @a before, as [first, count, label]. */
static json_t *relabelled(const unsigned char *before,
                          const unsigned char *after, size_t n) {
  json_t *runs = json_array();
  for (size_t i = 0; runs && i < n;) {
    size_t j = i + 1;
    if (before[i] == after[i]) {
      i++;
      continue;
    }
    while (j < n && before[j] != after[j] && after[j] == after[i])
      j++;
    json_t *run = json_array();
    json_array_append_new(run, json_integer((json_int_t)i));
    json_array_append_new(run, json_integer((json_int_t)(j - i)));
    json_array_append_new(run, json_integer(after[i]));
    if (json_array_append_new(runs, run)) {
      json_decref(runs);
      runs = NULL;
    }
    i = j;
  }
  return runs;
}

/* The last line of the NDJSON form: the map @a x holds, finished, against
 * the labels of stage 1 @a before; a body that ends with a newline. */
static int last_line(const basins_x *x, const unsigned char *before,
                     const api_call *c, api_response *out) {
  const ss_basins *b = &x->b;
  json_t *o = json_object();
  api__set(o, "done", json_true());
  api__set(o, "attractors", json_null());
  api__set(o, "relabelled",
           relabelled(before, b->labels, (size_t)b->n[0] * (size_t)b->n[1]));
  summary(x, o);
  if (api__answer(o, &SPEC, x, &x->ap, c, out))
    return -1;
  char *body = out->body ? realloc(out->body, out->len + 2) : NULL;
  if (!body)
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  body[out->len++] = '\n';
  body[out->len] = 0;
  out->body = body;
  out->held = out->len;
  out->content_type = "application/x-ndjson";
  return 0;
}

int ep_basins_encode(const void *xp, const api_call *c, api_response *out) {
  const basins_x *x = xp;
  const ss_basins *b = &x->b;
  if (x->ndjson) {
    api_response last;
    memset(&last, 0, sizeof last);
    if (x->lines.oom || last_line(x, x->provisional, c, &last))
      goto oom;
    char *body = malloc(x->lines.len + last.len + 1);
    if (!body) {
      api_response_free(&last);
      goto oom;
    }
    memcpy(body, x->lines.p, x->lines.len);
    memcpy(body + x->lines.len, last.body, last.len + 1);
    *out = last;
    out->body = body;
    out->len = out->held = x->lines.len + last.len;
    free(last.body);
    return 0;
  oom:
    return c->e->set
               ? -1
               : api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  }
  json_t *o = json_object();
  char *data = base64(b->labels, (size_t)b->n[0] * (size_t)b->n[1]);
  if (!data) {
    json_decref(o);
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  }
  api__set(o, "attractors", json_null());
  api__set(o, "labels", labels_json(b, data));
  free(data);
  summary(x, o);
  return api__answer(o, &SPEC, x, &x->ap, c, out);
}

void ep_basins_release(void *xp) {
  basins_x *x = xp;
  if (!x)
    return;
  ss_basins_free(&x->b);
  free(x->lines.p);
  free(x->provisional);
  free(x);
}

/* ---- the endpoint as a job -----------------------------------------------
 *
 * A /basins job is cut where the core stages its map (stickslip.h, the
 * stages of ss_basins_run):
 *   stage 0  one chunk, not visible: the attractors (ss_basins_attractors);
 *   stage 1  the rows in groups of about BASINS_JOB_CELLS cells (at least
 *            a row), not visible: each the labels of its rows against stage
 *            0's attractors (ss_basins_rows), its returns and the most
 *            returns one of its cells took to land;
 *   stage 2  one visible chunk: the map gathered from them, finished
 *            (ss_basins_finish) and written as the synchronous answer.
 * Items are cells, counted by the chunks of stage 1.  The NDJSON form is
 * cut so that each of its lines is the result of a chunk, in order: stage
 * 1 begins with a chunk that writes the head line from stage 0's
 * attractors, its groups are visible (their results are the rows' lines),
 * and stage 2 writes the last line.
 *
 * The attractors go from stage 0 to the others as the core holds them:
 * their bytes, in base64, under the library's version and the size of
 * one, so that every double reads back bit for bit and the map is the
 * synchronous one by the core's promise; a replica of another build
 * refuses them rather than misread them.
 *
 * Why 8192 cells: 16 rows of the paper's 512x512 slice took 0.19-0.36 s on
 * one thread of a loaded machine (cells far from every attractor cost more,
 * up to max_returns returns each), a fraction of a second, so that the
 * store's cost per chunk (a claim, a lease, a result written) is small
 * beside it and a chunk lost with its replica costs little to do again.
 */
enum { BASINS_JOB_CELLS = 8192 };

ep_job_cut_fn ep_basins_job_cut;
ep_job_run_fn ep_basins_job_run;

static long long rows_per_chunk(const basins_x *x) {
  long long per = BASINS_JOB_CELLS / x->axes.a[1].n;
  return per > 1 ? per : 1;
}

static size_t groups_of(const basins_x *x) {
  long long per = rows_per_chunk(x);
  return (size_t)((x->axes.a[0].n + per - 1) / per);
}

int ep_basins_job_cut(const void *xp, const api_call *c, api_job_cut *cut) {
  const basins_x *x = xp;
  size_t groups = groups_of(x), head = x->ndjson ? 1 : 0;
  long long per = rows_per_chunk(x), n0 = x->axes.a[0].n;
  if (api__job_cut_alloc(cut, groups + head + 2, c) != 0)
    return -1;
  for (size_t k = 1; k <= groups + head; k++) {
    cut->stage[k] = 1;
    cut->visible[k] = (unsigned char)head; /* the lines of the NDJSON form */
  }
  for (size_t g = 0; g < groups; g++) {
    long long row = (long long)g * per;
    cut->items[g + head + 1] =
        (long)((row + per <= n0 ? per : n0 - row) * x->axes.a[1].n);
  }
  cut->stage[groups + head + 1] = 2;
  cut->visible[groups + head + 1] = 1;
  return 0;
}

/* A copy of @a n bytes at @a p (malloc'd); NULL when out of memory. */
static unsigned char *memdup(const unsigned char *p, size_t n) {
  unsigned char *q = malloc(n ? n : 1);
  if (q)
    memcpy(q, p, n);
  return q;
}

/* RFC 4648 base64 @a s (@a n characters) into exactly @a want bytes at
 * @a out: 0, or -1 when it is not that. */
static int unbase64(const char *s, size_t n, unsigned char *out, size_t want) {
  size_t w = 0;
  if (n != 4 * ((want + 2) / 3))
    return -1;
  for (size_t i = 0; i < n; i += 4) {
    unsigned v = 0;
    int pad = 0;
    for (int q = 0; q < 4; q++) {
      char ch = s[i + (size_t)q];
      int d = ch >= 'A' && ch <= 'Z'   ? ch - 'A'
              : ch >= 'a' && ch <= 'z' ? ch - 'a' + 26
              : ch >= '0' && ch <= '9' ? ch - '0' + 52
              : ch == '+'              ? 62
              : ch == '/'              ? 63
                                       : -1;
      if (ch == '=' && i + 4 == n && q >= 2) {
        pad++;
        d = 0;
      } else if (d < 0 || pad) {
        return -1;
      }
      v = v << 6 | (unsigned)d;
    }
    for (int q = 0; q < 3 - pad; q++) {
      if (w == want)
        return -1;
      out[w++] = (unsigned char)(v >> (16 - 8 * q));
    }
  }
  return w == want ? 0 : -1;
}

/* The integer @a key of @a o within [@a lo, @a hi] into *v: 1, or 0. */
static int int_of(const json_t *o, const char *key, long long lo, long long hi,
                  long long *v) {
  const json_t *j = json_object_get(o, key);
  if (!json_is_integer(j))
    return 0;
  *v = json_integer_value(j);
  return *v >= lo && *v <= hi;
}

/* The bytes @a key of @a o (base64), exactly @a want of them, into @a out:
 * 1, or 0. */
static int bytes_of(const json_t *o, const char *key, unsigned char *out,
                    size_t want) {
  const json_t *j = json_object_get(o, key);
  return json_is_string(j) &&
         unbase64(json_string_value(j), json_string_length(j), out, want) == 0;
}

/* Chunk @a k's stored document, parsed, into *doc: 0, or -1 and the
 * problem. */
static int read_doc(const api_job_inputs *in, size_t k, const api_call *c,
                    json_t **doc) {
  char *buf = NULL;
  size_t len = 0;
  *doc = NULL;
  if (!in || !in->read || in->read(in->cls, k, &buf, &len) != 0)
    return api__fail(c->e, API_P_STORE_UNAVAILABLE, NULL,
                     "the result of chunk %zu could not be read from the job "
                     "store",
                     k);
  *doc = json_loadb(buf, len, 0, NULL);
  free(buf);
  return *doc ? 0
              : api__fail(c->e, API_P_INTERNAL, NULL,
                          "the stored result of chunk %zu is not JSON", k);
}

/* The compact text of @a doc (consumed), followed by a newline when it is
 * a @a line of the NDJSON form: malloc'd, its length in *len; NULL when
 * out of memory. */
static char *text_of(json_t *doc, int line, size_t *len) {
  char *text = doc ? api__dump(doc, len) : NULL;
  json_decref(doc);
  char *more = text && line ? realloc(text, *len + 2) : text;
  if (!more) {
    free(text);
    return NULL;
  }
  if (line) {
    more[(*len)++] = '\n';
    more[*len] = 0;
  }
  return more;
}

/* A 200 result, the compact text of @a doc (consumed), a @a line of the
 * NDJSON form or not. */
static int result_of(json_t *doc, int line, const api_call *c,
                     api_response *out) {
  size_t len = 0;
  char *text = text_of(doc, line, &len);
  if (!text)
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                     "the chunk's result could not be written: out of memory");
  out->status = 200;
  out->content_type = line ? "application/x-ndjson" : "application/json";
  out->body = text;
  out->len = len;
  out->held = len;
  return 0;
}

/* @a n bytes as a new JSON string of their base64; NULL when out of
 * memory. */
static json_t *base64_json(const void *p, size_t n) {
  char *text = base64(p, n);
  json_t *j = text ? json_string(text) : NULL;
  free(text);
  return j;
}

/* Stage 0: {"version", "size", "n", "attractors": base64 of their bytes}. */
static int run_attractors(const basins_x *x, const api_call *c,
                          api_response *out) {
  ss_basin_opts o = x->opts;
  ss_basins b;
  ss_diag d;
  ss_diag_clear(&d);
  call_opts(c, 1, &o);
  int rc = ss_basins_alloc(&o, &b, &d);
  if (rc == SS_OK)
    rc = ss_basins_attractors(&x->m, &o, &b, &d);
  if (rc) {
    ss_basins_free(&b);
    return basins_problem(rc, &d, c);
  }
  json_t *doc = json_object();
  if (doc && (api__set(doc, "version", json_string(SS_VERSION)) ||
              api__set(doc, "size", json_integer(sizeof *b.attractors)) ||
              api__set(doc, "n", json_integer(b.n_attractors)) ||
              api__set(doc, "attractors",
                       base64_json(b.attractors, (size_t)b.n_attractors *
                                                     sizeof *b.attractors)))) {
    json_decref(doc);
    doc = NULL;
  }
  ss_basins_free(&b);
  return result_of(doc, 0, c, out);
}

/* The map of @a o with stage 0's attractors read back: 0, or -1 and the
 * problem (@a b then to be freed all the same). */
static int read_attractors(const ss_basin_opts *o, const api_job_inputs *in,
                           const api_call *c, ss_basins *b) {
  ss_diag d;
  ss_diag_clear(&d);
  json_t *doc = NULL;
  int rc = ss_basins_alloc(o, b, &d);
  if (rc)
    return basins_problem(rc, &d, c);
  if (read_doc(in, 0, c, &doc))
    return -1;
  const json_t *v = json_object_get(doc, "version");
  long long size = 0, n = 0;
  int ok = json_is_string(v) && !strcmp(json_string_value(v), SS_VERSION) &&
           int_of(doc, "size", 0, LLONG_MAX, &size) &&
           size == (long long)sizeof *b->attractors &&
           int_of(doc, "n", 0, SS_BASIN_MAX_ATTRACTORS, &n) &&
           bytes_of(doc, "attractors", (unsigned char *)b->attractors,
                    (size_t)n * sizeof *b->attractors);
  json_decref(doc);
  if (!ok)
    return api__fail(c->e, API_P_INTERNAL, NULL,
                     "the stored attractors are not those of this build (%s, "
                     "%zu bytes each)",
                     SS_VERSION, sizeof *b->attractors);
  b->n_attractors = (int)n;
  return 0;
}

/* The head line of the NDJSON form: the slice, and the attractors @a b
 * holds after stage 0. */
static json_t *head_doc(const basins_x *x, const ss_basins *b) {
  json_t *doc = json_object();
  api__set(doc, "labels", labels_json(b, NULL));
  api__set(doc, "attractors", attractors_json(x, b, 0));
  return doc;
}

/* The result of a group of rows, a line of the NDJSON form:
 * {"row", "rows", "returns", "max_to_land", "labels": base64 of the
 * labels of those rows of @a b}; NULL when out of memory. */
static json_t *rows_doc(const ss_basins *b, long long row, long long rows,
                        long returns, int most) {
  size_t width = (size_t)b->n[1];
  json_t *doc = json_object();
  if (doc && (api__set(doc, "row", json_integer(row)) ||
              api__set(doc, "rows", json_integer(rows)) ||
              api__set(doc, "returns", json_integer(returns)) ||
              api__set(doc, "max_to_land", json_integer(most)) ||
              api__set(doc, "labels",
                       base64_json(b->labels + (size_t)row * width,
                                   (size_t)rows * width)))) {
    json_decref(doc);
    doc = NULL;
  }
  return doc;
}

/* Stage 1 of the NDJSON form, its first chunk: the head line. */
static int run_head(const basins_x *x, const api_job_inputs *in,
                    const api_call *c, api_response *out) {
  ss_basins b;
  int rc = read_attractors(&x->opts, in, c, &b);
  json_t *doc = rc ? NULL : head_doc(x, &b);
  ss_basins_free(&b);
  return rc ? -1 : result_of(doc, 1, c, out);
}

/* Stage 1, group @a g: rows_doc, a line of the NDJSON form. */
static int run_rows(const basins_x *x, size_t g, const api_job_inputs *in,
                    const api_call *c, api_response *out) {
  long long per = rows_per_chunk(x), n0 = x->axes.a[0].n;
  long long row = (long long)g * per, rows = row + per <= n0 ? per : n0 - row;
  ss_basin_opts o = x->opts;
  ss_basins b;
  ss_diag d;
  ss_diag_clear(&d);
  call_opts(c, rows, &o);
  int rc = read_attractors(&o, in, c, &b);
  if (rc == 0) {
    rc = ss_basins_rows(&x->m, &o, &b, (int)row, (int)rows, &d);
    rc = basins_problem(rc, &d, c);
  }
  if (rc) {
    ss_basins_free(&b);
    return -1;
  }
  json_t *doc = rows_doc(&b, row, rows, b.returns, b.max_returns);
  ss_basins_free(&b);
  return result_of(doc, x->ndjson, c, out);
}

/* Stage 2: the map gathered from the groups of stage 1, finished, and
 * written as the synchronous answer. */
static int run_last(const basins_x *x, const api_job_inputs *in,
                    const api_call *c, api_response *out) {
  long long per = rows_per_chunk(x), n0 = x->axes.a[0].n;
  size_t groups = groups_of(x), width = (size_t)x->axes.a[1].n;
  size_t first = x->ndjson ? 2 : 1; /* the chunk of the first group */
  unsigned char *before = NULL;
  basins_x *y = malloc(sizeof *y);
  ss_diag d;
  ss_diag_clear(&d);
  if (!y)
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  *y = *x; /* its own map and options: x is shared by the chunks */
  call_opts(c, n0, &y->opts);
  int rc = read_attractors(&y->opts, in, c, &y->b);
  for (size_t g = 0; rc == 0 && g < groups; g++) {
    long long row = (long long)g * per, rows = row + per <= n0 ? per : n0 - row;
    long long r0 = -1, r1 = -1, returns = 0, most = 0;
    json_t *doc = NULL;
    if ((rc = read_doc(in, g + first, c, &doc)))
      break;
    int ok = int_of(doc, "row", 0, n0, &r0) && r0 == row &&
             int_of(doc, "rows", 0, n0, &r1) && r1 == rows &&
             int_of(doc, "returns", 0, LLONG_MAX, &returns) &&
             int_of(doc, "max_to_land", 0, INT_MAX, &most) &&
             bytes_of(doc, "labels", y->b.labels + (size_t)row * width,
                      (size_t)rows * width);
    json_decref(doc);
    if (!ok) {
      rc = api__fail(c->e, API_P_INTERNAL, NULL,
                     "the stored result of chunk %zu is not the labels of "
                     "rows %lld to %lld",
                     g + first, row, row + rows - 1);
      break;
    }
    y->b.returns += (long)returns;
    if (most > y->b.max_returns)
      y->b.max_returns = (int)most;
  }
  if (rc == 0 && x->ndjson &&
      !(before = memdup(y->b.labels, (size_t)n0 * width)))
    rc = api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  if (rc == 0)
    rc = basins_problem(ss_basins_finish(&y->m, &y->opts, &y->b, &d), &d, c);
  if (rc == 0)
    rc = x->ndjson ? last_line(y, before, c, out) : ep_basins_encode(y, c, out);
  free(before);
  ss_basins_free(&y->b);
  free(y);
  return rc;
}

int ep_basins_job_run(const void *xp, size_t k, const api_job_inputs *in,
                      const api_call *c, api_response *out) {
  const basins_x *x = xp;
  size_t groups = groups_of(x), head = x->ndjson ? 1 : 0;
  if (k == 0)
    return run_attractors(x, c, out);
  if (head && k == 1)
    return run_head(x, in, c, out);
  if (k <= groups + head)
    return run_rows(x, k - 1 - head, in, c, out);
  return run_last(x, in, c, out);
}

/* ---- the NDJSON form, synchronous -----------------------------------------
 *
 * The same stages and the same lines as the job's chunks: the attractors
 * and the head line, each group of rows (returns and the most returns to
 * land counted per group) and its line, then stage 2.  The whole runs
 * under the request's one budget: each stage has what is left of it.
 */

static double seconds_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The budget left at a stage's start into @a o: 0 (none, or time left),
 * or SS_ELIMIT_TIME when it is spent. */
static int budget_left(double t0, const api_call *c, ss_basin_opts *o) {
  double limit = c->lim->max_seconds, left = limit - (seconds_now() - t0);
  o->max_seconds = limit > 0 ? left : 0;
  return limit > 0 && !(left > 0) ? SS_ELIMIT_TIME : SS_OK;
}

/* Append @a doc (consumed) to the lines of @a x as a line. */
static void append_line(basins_x *x, json_t *doc) {
  size_t len = 0;
  char *text = text_of(doc, 1, &len);
  if (!text)
    x->lines.oom = 1;
  else
    api__w_put(&x->lines, text, len);
  free(text);
}

static int run_lines(basins_x *x, const api_call *c) {
  long long per = rows_per_chunk(x), n0 = x->axes.a[0].n;
  size_t groups = groups_of(x), cells = (size_t)n0 * (size_t)x->axes.a[1].n;
  ss_basin_opts o = x->opts;
  ss_basins *b = &x->b;
  ss_diag d;
  ss_diag_clear(&d);
  double t0 = seconds_now();
  int rc = ss_basins_alloc(&o, b, &d);
  if (rc == SS_OK && (rc = budget_left(t0, c, &o)) == SS_OK &&
      (rc = ss_basins_attractors(&x->m, &o, b, &d)) == SS_OK)
    append_line(x, head_doc(x, b));
  long returns = 0;
  int most = 0;
  for (size_t g = 0; rc == SS_OK && g < groups; g++) {
    long long row = (long long)g * per, rows = row + per <= n0 ? per : n0 - row;
    b->returns = 0;
    b->max_returns = 0;
    if ((rc = budget_left(t0, c, &o)) == SS_OK &&
        (rc = ss_basins_rows(&x->m, &o, b, (int)row, (int)rows, &d)) == SS_OK)
      append_line(x, rows_doc(b, row, rows, b->returns, b->max_returns));
    returns += b->returns;
    most = b->max_returns > most ? b->max_returns : most;
  }
  b->returns = returns;
  b->max_returns = most;
  if (rc == SS_OK && !(x->provisional = memdup(b->labels, cells)))
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  if (rc == SS_OK && (rc = budget_left(t0, c, &o)) == SS_OK)
    rc = ss_basins_finish(&x->m, &o, b, &d);
  return basins_problem(rc, &d, c);
}
