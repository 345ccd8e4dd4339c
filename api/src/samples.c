/*
 * samples.c: what a request asks of its samples (even, at given times, or
 * placed for a curve to a tolerance; which columns), shared by /simulate
 * and /orbit, and the columns of the answer.
 */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "samples.h"
#include "decode.h"
#include "problem.h"
#include "values.h"

const char *const API_SAMPLE_COLUMNS[] = {"t",    "x1",    "x2", "v1", "v2",
                                          "mode", "force", "F1", "F2", NULL};
static const char *const STATE[] = {"x1", "x2", "v1", "v2", NULL};

/* The default columns: time, state and mode. */
#define DEFAULT_COLUMNS 0x3fu

static int index_of(const char *const *names, const char *s) {
  for (int i = 0; names[i]; i++)
    if (!strcmp(names[i], s))
      return i;
  return -1;
}

/* A non-empty array of distinct names of @a names into a bit mask. */
static int name_set(const json_t *v, const char *ptr, unsigned *mask,
                    const char *const *names, const char *what,
                    const api_call *c) {
  size_t i;
  const json_t *s;
  char list[160] = "";
  for (int k = 0; names[k]; k++)
    snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s",
             k ? ", " : "", names[k]);
  if (!json_is_array(v) || json_array_size(v) == 0)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be a non-empty array of %s (of %s)", ptr, what,
                     list);
  *mask = 0;
  json_array_foreach(v, i, s) {
    char p[128];
    snprintf(p, sizeof p, "%s/%zu", ptr, i);
    int k = json_is_string(s) ? index_of(names, json_string_value(s)) : -1;
    if (k < 0)
      return api__fail(c->e, API_P_INVALID_VALUE, p, "%s must be one of %s", p,
                       list);
    if (*mask & (1u << k))
      return api__fail(c->e, API_P_INVALID_VALUE, p, "%s: %s is named twice", p,
                       json_string_value(s));
    *mask |= 1u << k;
  }
  return 0;
}

static json_t *mask_echo(unsigned mask, const char *const *names) {
  json_t *a = json_array();
  for (int k = 0; names[k]; k++)
    if (mask & (1u << k))
      json_array_append_new(a, json_string(names[k]));
  return a;
}

static int decode_fields(const json_t *v, const char *ptr, void *dest,
                         const api_call *c) {
  return name_set(v, ptr, dest, API_SAMPLE_COLUMNS, "columns", c);
}

static json_t *echo_fields(const void *dest) {
  return mask_echo(*(const unsigned *)dest, API_SAMPLE_COLUMNS);
}

static int decode_plane(const json_t *v, const char *ptr, void *dest,
                        const api_call *c) {
  return name_set(v, ptr, dest, STATE, "state variables", c);
}

static json_t *echo_plane(const void *dest) {
  return mask_echo(*(const unsigned *)dest, STATE);
}

/* {"x1": s, ...}: a positive scale for some of the state variables. */
static int decode_scale(const json_t *v, const char *ptr, void *dest,
                        const api_call *c) {
  double *scale = dest;
  const char *k;
  const json_t *s;
  if (!json_is_object(v))
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an object of scales, e.g. {\"x2\": 0.01, "
                     "\"v2\": 0.02}",
                     ptr);
  json_object_foreach((json_t *)v, k, s) {
    int i = index_of(STATE, k);
    double x = json_is_number(s) ? json_number_value(s) : -1;
    char p[160];
    snprintf(p, sizeof p, "%s/%.60s", ptr, k);
    if (i < 0)
      return api__fail(c->e, API_P_UNKNOWN_FIELD, p,
                       "%s: the scales are of x1, x2, v1, v2", p);
    if (!(x > 0) || x > DBL_MAX)
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s must be a positive number", p);
    scale[i] = x;
  }
  return 0;
}

static json_t *echo_scale(const void *dest) {
  const double *scale = dest;
  json_t *o = json_object();
  for (int i = 0; i < 4; i++)
    api__set(o, STATE[i], api__real(scale[i] > 0 ? scale[i] : 1));
  return o;
}

static int decode_times(const json_t *v, const char *ptr, void *dest,
                        const api_call *c) {
  api_times *s = dest;
  size_t n = json_is_array(v) ? json_array_size(v) : 0;
  if (n == 0)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be a non-empty array of times", ptr);
  if (n > c->lim->max_samples)
    return api__limit(c->e, "max_samples", (double)c->lim->max_samples, ptr,
                      "%zu sample times, the limit is %zu", n,
                      c->lim->max_samples);
  if (!(s->v = malloc(n * sizeof *s->v)))
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  s->n = n;
  return api__numbers(v, ptr, s->v, c->e);
}

static json_t *echo_nothing(const void *dest) {
  (void)dest;
  return NULL;
}

static const api_custom FIELDS_C = {decode_fields, echo_fields};
static const api_custom PLANE_C = {decode_plane, echo_plane};
static const api_custom SCALE_C = {decode_scale, echo_scale};
static const api_custom TIMES_C = {decode_times, echo_nothing};

#define N_FIELD                                                                \
  {                                                                            \
    "n", API_T_COUNT, API_REQUIRED, 1, 1e9, "max_samples",                     \
        offsetof(api_samples_req, n), API_HAS(api_samples_req, has_n), 1, 0    \
  }
#define CURVE_FIELDS                                                           \
  {"tolerance",                                                                \
   API_T_NUMBER,                                                               \
   API_REQUIRED,                                                               \
   1e-12,                                                                      \
   1e15,                                                                       \
   NULL,                                                                       \
   offsetof(api_samples_req, tolerance),                                       \
   API_HAS(api_samples_req, has_tolerance),                                    \
   1,                                                                          \
   2},                                                                         \
      {"plane",                                                                \
       API_T_CUSTOM,                                                           \
       0,                                                                      \
       0,                                                                      \
       0,                                                                      \
       NULL,                                                                   \
       offsetof(api_samples_req, plane),                                       \
       API_HAS(api_samples_req, has_plane),                                    \
       0,                                                                      \
       0,                                                                      \
       &PLANE_C},                                                              \
      {"scale",                                                                \
       API_T_CUSTOM,                                                           \
       0,                                                                      \
       0,                                                                      \
       0,                                                                      \
       NULL,                                                                   \
       offsetof(api_samples_req, scale),                                       \
       API_HAS(api_samples_req, has_scale),                                    \
       0,                                                                      \
       0,                                                                      \
       &SCALE_C},                                                              \
      {"max",                                                                  \
       API_T_COUNT,                                                            \
       0,                                                                      \
       2,                                                                      \
       1e9,                                                                    \
       "max_samples",                                                          \
       offsetof(api_samples_req, max),                                         \
       API_HAS(api_samples_req, has_max)},                                     \
  {                                                                            \
    "fields", API_T_CUSTOM, 0, 0, 0, NULL, offsetof(api_samples_req, fields),  \
        API_HAS(api_samples_req, has_fields), 0, 0, &FIELDS_C                  \
  }

static const api_field SIM_FIELDS[] = {
    N_FIELD,
    {"t", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL, offsetof(api_samples_req, t),
     API_HAS(api_samples_req, has_t), 1, 1, &TIMES_C},
    CURVE_FIELDS,
    {"from", API_T_NUMBER, 0, 0, 0, NULL, offsetof(api_samples_req, from),
     API_HAS(api_samples_req, has_from)},
    {"to", API_T_NUMBER, 0, 0, 0, NULL, offsetof(api_samples_req, to),
     API_HAS(api_samples_req, has_to)},
};
const api_spec API_SIM_SAMPLES = API_SPEC(SIM_FIELDS);

static const api_field ORBIT_FIELDS[] = {N_FIELD, CURVE_FIELDS};
const api_spec API_ORBIT_SAMPLES = API_SPEC(ORBIT_FIELDS);

void api__samples_release(api_samples_req *s) {
  free(s->t.v);
  s->t.v = NULL;
}

int api__samples_core(const api_samples_req *s, const api_params *ap,
                      const char *ptr, ss_sim_opts *o, const api_call *c) {
  char p[96];
  if (!s->has_tolerance && (s->has_plane || s->has_scale || s->has_max)) {
    snprintf(p, sizeof p, "%s/%s", ptr,
             s->has_plane   ? "plane"
             : s->has_scale ? "scale"
                            : "max");
    return api__fail(c->e, API_P_INVALID_VALUE, p,
                     "%s goes with %s/tolerance (samples placed for a curve)",
                     p, ptr);
  }
  if (s->has_t && (s->has_from || s->has_to)) {
    snprintf(p, sizeof p, "%s/%s", ptr, s->has_from ? "from" : "to");
    return api__fail(c->e, API_P_INVALID_VALUE, p,
                     "%s goes with %s/n or %s/tolerance, not with %s/t", p, ptr,
                     ptr, ptr);
  }
  if (!s->has_tolerance)
    return 0;
  o->sample_tolerance = s->tolerance;
  o->sample_axes = s->has_plane ? s->plane : 0;
  /* in the answer's units: velocities are omega times the dimensionless */
  for (int i = 0; i < 4; i++)
    o->sample_scale[i] =
        (s->scale[i] > 0 ? s->scale[i] : 1) / (i >= 2 ? ap->omega : 1);
  size_t max = c->lim->max_samples;
  if (s->has_max && (size_t)s->max < max)
    max = (size_t)s->max;
  o->max_samples = max;
  return 0;
}

unsigned api__samples_columns(const api_samples_req *s) {
  return s->has_fields ? s->fields : DEFAULT_COLUMNS;
}
