/*
 * decode.c: requests decoded from their declarative specs.
 *
 * Each endpoint describes its fields once (api_field: name, type, range,
 * required, destination, alternative); from that one description this file
 * refuses unknown keys, reports missing fields, checks every value for type,
 * finiteness, range and limit, writes it to its destination, and echoes the
 * request back.  Every failure names the field by its JSON pointer.  A
 * missing required field is an error, never a zero; an unknown field is an
 * error, never ignored, except in an object the daemon answered with and a
 * client sends back (an orbit: API_OTHER_KEYS), whose other keys are the
 * daemon's own or the client's notes.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "decode.h"
#include "writer.h"
#include "problem.h"
#include "values.h"

/* A key as it may be shown back to the client: printable ASCII, at most 40
 * characters, the rest elided. */
static void safe_key(const char *k, char *out, size_t n) {
  size_t j = 0;
  for (size_t i = 0; k[i] && j + 4 < n && i < 40; i++)
    out[j++] = isprint((unsigned char)k[i]) ? k[i] : '?';
  if (strlen(k) > 40 && j + 4 < n) {
    out[j++] = '.';
    out[j++] = '.';
    out[j++] = '.';
  }
  out[j] = 0;
}

/* Append @a s to out[*j], within n - 1 bytes. */
static void put_cut(char *out, size_t n, size_t *j, const char *s) {
  size_t m = strlen(s);
  if (m > n - 1 - *j)
    m = n - 1 - *j;
  memcpy(out + *j, s, m);
  *j += m;
}

/* "ptr/key", cut to n - 1 bytes as snprintf would, without its format
 * parsing: every field of every request passes here. */
static void join(char *out, size_t n, const char *ptr, const char *key) {
  char k[48];
  size_t j = 0;
  safe_key(key, k, sizeof k);
  put_cut(out, n, &j, ptr);
  put_cut(out, n, &j, "/");
  put_cut(out, n, &j, k);
  out[j] = 0;
}

/* The most fields an object's spec has: its values are found in one pass
 * over the object's keys. */
#define API_MAX_FIELDS 64

/* The value of each field of @a s in @a obj, NULL where its key is absent
 * or its value null, into vals: one pass over the object's keys (a body
 * gives a few of a spec's fields), each key refused when the spec has no
 * such field (the message lists the known ones). */
static int field_values(const api_spec *s, const json_t *obj, const char *ptr,
                        const json_t **vals, api_err *e) {
  const char *key;
  json_t *v;
  for (int i = 0; i < s->n; i++)
    vals[i] = NULL;
  json_object_foreach((json_t *)obj, key, v) {
    int i = 0, other = -1;
    for (; i < s->n && strcmp(key, s->fields[i].name) != 0; i++)
      if (!strcmp(s->fields[i].name, "*"))
        other = i;
    if (i == s->n && other >= 0)
      continue; /* API_OTHER_KEYS */
    if (i == s->n) {
      char p[160], list[256] = "";
      join(p, sizeof p, ptr, key);
      for (int k = 0; k < s->n; k++) {
        strncat(list, k ? ", " : "", sizeof list - strlen(list) - 1);
        strncat(list, s->fields[k].name, sizeof list - strlen(list) - 1);
      }
      return api__fail(e, API_P_UNKNOWN_FIELD, p,
                       "unknown field '%s'; the fields here are: %s", p, list);
    }
    vals[i] = json_is_null(v) ? NULL : v;
  }
  return 0;
}

/* The fields of alternative @a alt of group @a g, as "/a and /b". */
static void alt_names(const api_spec *s, int g, int alt, const char *ptr,
                      char *out, size_t n) {
  out[0] = 0;
  for (int i = 0; i < s->n; i++) {
    const api_field *f = &s->fields[i];
    if (f->group != g || f->alt != alt || !(f->flags & API_REQUIRED))
      continue;
    size_t l = strlen(out);
    snprintf(out + l, n - l, "%s%s/%s", l ? " and " : "", ptr, f->name);
  }
}

/* Exactly one alternative of each group: chosen[g] is its number. */
static int groups(const api_spec *s, const json_t *const *vals, const char *ptr,
                  int chosen[8], api_err *e) {
  for (int g = 1; g < 8; g++) {
    int first_field = -1;
    char a[128], b[128], p[160];
    chosen[g] = -1;
    for (int i = 0; i < s->n; i++) {
      const api_field *f = &s->fields[i];
      if (f->group != g)
        continue;
      if (first_field < 0)
        first_field = i;
      if (!vals[i])
        continue;
      if (chosen[g] < 0) {
        chosen[g] = f->alt;
      } else if (f->alt != chosen[g]) {
        alt_names(s, g, chosen[g], ptr, a, sizeof a);
        alt_names(s, g, f->alt, ptr, b, sizeof b);
        join(p, sizeof p, ptr, f->name);
        return api__fail(e, API_P_INVALID_VALUE, p,
                         "give either %s or %s, not both", a, b);
      }
    }
    if (first_field >= 0 && chosen[g] < 0) {
      /* every alternative, "x, y or z" */
      char all[400] = "";
      int last = -1;
      for (int alt = 0; alt < 8; alt++) {
        alt_names(s, g, alt, ptr, a, sizeof a);
        if (a[0])
          last = alt;
      }
      for (int alt = 0, k = 0; alt < 8; alt++) {
        alt_names(s, g, alt, ptr, a, sizeof a);
        if (!a[0])
          continue;
        size_t l = strlen(all);
        snprintf(all + l, sizeof all - l, "%s%s",
                 k == 0        ? ""
                 : alt == last ? " or "
                               : ", ",
                 a);
        k++;
      }
      join(p, sizeof p, ptr, s->fields[first_field].name);
      return api__fail(e, API_P_MISSING_FIELD, p,
                       "the required field %s is missing: give %s", p, all);
    }
  }
  return 0;
}

/* The value of the api_limits field named @a name. */
static double limit_of(const api_limits *l, const char *name) {
  if (strcmp(name, "max_samples") == 0)
    return (double)l->max_samples;
  if (strcmp(name, "max_events") == 0)
    return (double)l->max_events;
  if (strcmp(name, "max_points") == 0)
    return (double)l->max_points;
  return INFINITY;
}

static int number(const api_field *f, const json_t *v, const char *p,
                  double *out, api_err *e) {
  if (!json_is_number(v))
    return api__fail(e, API_P_INVALID_TYPE, p, "%s must be a number", p);
  *out = json_number_value(v);
  if (!isfinite(*out))
    return api__fail(e, API_P_INVALID_VALUE, p, "%s must be finite", p);
  if (f->lo < f->hi && !(*out >= f->lo && *out <= f->hi))
    return api__fail(e, API_P_INVALID_VALUE, p,
                     "%s must be between %g and %g (got %.17g)", p, f->lo,
                     f->hi, *out);
  return 0;
}

static int count(const api_field *f, const json_t *v, const char *p,
                 long long *out, const api_call *c) {
  if (!json_is_integer(v))
    return api__fail(c->e, API_P_INVALID_TYPE, p, "%s must be an integer", p);
  *out = (long long)json_integer_value(v);
  /* a value over a limit names the limit, however far over it is */
  if (f->limit && *out >= (long long)f->lo) {
    double lim = limit_of(c->lim, f->limit);
    if ((double)*out > lim)
      return api__limit(c->e, f->limit, lim, p,
                        "%s = %lld is over the limit %s = %.0f", p, *out,
                        f->limit, lim);
  }
  if (*out < (long long)f->lo || *out > (long long)f->hi)
    return api__fail(c->e, API_P_INVALID_VALUE, p,
                     "%s must be between %lld and %lld (got %lld)", p,
                     (long long)f->lo, (long long)f->hi, *out);
  return 0;
}

static int vec4(const json_t *v, const char *p, double *out, api_err *e) {
  if (!json_is_array(v) || json_array_size(v) != 4)
    return api__fail(e, API_P_INVALID_TYPE, p,
                     "%s must be an array of 4 numbers", p);
  return api__numbers(v, p, out, e);
}

static int enumeration(const api_field *f, const json_t *v, const char *p,
                       int *out, api_err *e) {
  const char *const *names = f->aux;
  char list[160] = "";
  for (int i = 0; json_is_string(v) && names[i]; i++)
    if (strcmp(json_string_value(v), names[i]) == 0) {
      *out = i;
      return 0;
    }
  for (int i = 0; names[i]; i++) {
    size_t l = strlen(list);
    snprintf(list + l, sizeof list - l, "%s\"%s\"", i ? ", " : "", names[i]);
  }
  return api__fail(e,
                   json_is_string(v) ? API_P_INVALID_VALUE : API_P_INVALID_TYPE,
                   p, "%s must be one of %s", p, list);
}

static int field(const api_field *f, const json_t *v, const char *p, char *dst,
                 const api_call *c) {
  switch (f->type) {
  case API_T_ANY:
    return 0;
  case API_T_NUMBER:
    return number(f, v, p, (double *)(dst + f->off), c->e);
  case API_T_COUNT:
    return count(f, v, p, (long long *)(dst + f->off), c);
  case API_T_BOOL:
    if (!json_is_boolean(v))
      return api__fail(c->e, API_P_INVALID_TYPE, p, "%s must be true or false",
                       p);
    *(int *)(dst + f->off) = json_is_true(v);
    return 0;
  case API_T_ENUM:
    return enumeration(f, v, p, (int *)(dst + f->off), c->e);
  case API_T_VEC4:
    return vec4(v, p, (double *)(dst + f->off), c->e);
  case API_T_OBJECT:
    if (!json_is_object(v))
      return api__fail(c->e, API_P_INVALID_TYPE, p, "%s must be an object", p);
    return api__decode(f->aux, v, p, dst + f->off, c);
  case API_T_CUSTOM:
    return ((const api_custom *)f->aux)->decode(v, p, dst + f->off, c);
  }
  return api__fail(c->e, API_P_INTERNAL, p, "field %s has no decoder", p);
}

int api__decode(const api_spec *s, const json_t *obj, const char *ptr,
                void *dest, const api_call *c) {
  int chosen[8];
  char *dst = dest;
  const json_t *vals[API_MAX_FIELDS];
  if (s->n > API_MAX_FIELDS)
    return api__fail(c->e, API_P_INTERNAL, ptr, "%s has more than %d fields",
                     ptr, API_MAX_FIELDS);
  if (field_values(s, obj, ptr, vals, c->e) ||
      groups(s, vals, ptr, chosen, c->e))
    return -1;
  for (int i = 0; i < s->n; i++) {
    const api_field *f = &s->fields[i];
    const json_t *v = vals[i];
    char p[160];
    if (!v) {
      if ((f->flags & API_REQUIRED) &&
          (f->group == 0 || chosen[f->group] == f->alt)) {
        join(p, sizeof p, ptr, f->name);
        return api__fail(c->e, API_P_MISSING_FIELD, p,
                         "the required field %s is missing", p);
      }
      continue;
    }
    /* the field's pointer, for its problems and its members' */
    join(p, sizeof p, ptr, f->name);
    if (field(f, v, p, dst, c))
      return -1;
    if (f->has)
      *(int *)(dst + f->has - 1) = 1;
  }
  return 0;
}

int api__given(const api_spec *s, const void *dest, const char *name) {
  for (int i = 0; i < s->n; i++)
    if (strcmp(s->fields[i].name, name) == 0 && s->fields[i].has)
      return *(const int *)((const char *)dest + s->fields[i].has - 1);
  return 0;
}

/* Whether field @a f of the request at @a src is echoed: given, or
 * defaulted, or required outside any alternative (so given, or the request
 * would have been refused). */
static int echoed(const api_field *f, const char *src) {
  int was_given = f->has && *(const int *)(src + f->has - 1);
  int always =
      (f->flags & API_DEFAULT) || ((f->flags & API_REQUIRED) && f->group == 0);
  return !(f->flags & API_ECHO_NEVER) && f->type != API_T_ANY &&
         (was_given || always);
}

json_t *api__echo(const api_spec *s, const void *dest) {
  json_t *o = json_object();
  const char *src = dest;
  for (int i = 0; i < s->n; i++) {
    const api_field *f = &s->fields[i];
    const void *at = src + f->off;
    json_t *v = NULL;
    if (!echoed(f, src))
      continue;
    switch (f->type) {
    case API_T_NUMBER:
      v = api__real(*(const double *)at);
      break;
    case API_T_COUNT:
      v = json_integer(*(const long long *)at);
      break;
    case API_T_BOOL:
      v = json_boolean(*(const int *)at);
      break;
    case API_T_ENUM:
      v = json_string(((const char *const *)f->aux)[*(const int *)at]);
      break;
    case API_T_VEC4:
      v = api__vec4(at);
      break;
    case API_T_OBJECT:
      v = api__echo(f->aux, at);
      break;
    case API_T_CUSTOM:
      v = ((const api_custom *)f->aux)->echo(at);
      break;
    case API_T_ANY:
      break;
    }
    api__set(o, f->name, v);
  }
  return o;
}

int api__numbers(const json_t *v, const char *ptr, double *out, api_err *e) {
  for (size_t i = 0; i < json_array_size(v); i++) {
    json_t *x = json_array_get(v, i);
    if (!json_is_number(x) || !isfinite(json_number_value(x)))
      return api__fail(e, API_P_INVALID_TYPE, ptr,
                       "%s/%zu must be a finite number", ptr, i);
    out[i] = json_number_value(x);
  }
  return 0;
}

/* ---- parameters ---------------------------------------------------------- */

/* Every parameter is a required number, echoed back. */
#define PARAM(type, m)                                                         \
  {                                                                            \
#m, API_T_NUMBER, API_REQUIRED | API_DEFAULT, 0, 0, NULL,                  \
        offsetof(type, m)                                                      \
  }
static const api_field PARAM_FIELDS[] = {
    PARAM(ss_params, chi), PARAM(ss_params, eta), PARAM(ss_params, us),
    PARAM(ss_params, ur), PARAM(ss_params, V)};
static const api_field PHYSICAL_FIELDS[] = {
    PARAM(ss_physical, m1), PARAM(ss_physical, m2), PARAM(ss_physical, k1),
    PARAM(ss_physical, k2), PARAM(ss_physical, Fs), PARAM(ss_physical, Fr),
    PARAM(ss_physical, v0)};
const api_spec API_PARAMS_SPEC = API_SPEC(PARAM_FIELDS);

#define NAME_STRING(name) #name,
const char *const API_PARAMETER_NAMES[] = {SS_PARAM_NAMES(NAME_STRING)
                                               SS_PHYS_NAMES(NAME_STRING) NULL};
#undef NAME_STRING
const api_spec API_PHYSICAL_SPEC = API_SPEC(PHYSICAL_FIELDS);

void *api__alloc(size_t size, void **xp, const api_call *c) {
  if (!(*xp = calloc(1, size)))
    api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  return *xp;
}

int api__decode_request(const api_spec *spec, const json_t *root, void *x,
                        api_params *ap, const api_call *c) {
  if (api__decode(spec, root, "", x, c))
    return -1;
  return api__params_resolve(ap, c);
}

int api__model(ss_model *m, const api_params *ap, const api_call *c) {
  ss_diag d;
  int rc;
  ss_diag_clear(&d);
  if ((rc = ss_model_init(m, &ap->p, &d)))
    return api__from_diag(c->e, rc, &d, "/params");
  return 0;
}

int api__params_resolve(api_params *ap, const api_call *c) {
  ss_diag d;
  int rc;
  ss_diag_clear(&d);
  ap->omega = 1;
  if (ap->has_params)
    rc = ss_params_check(&ap->p, &d);
  else
    rc = ss_params_from_physical(&ap->ph, &ap->p, &ap->omega, &d);
  if (rc)
    return api__from_diag(c->e, rc, &d,
                          ap->has_params ? "/params" : "/physical");
  return 0;
}

void api__w_echo(api_wbuf *w, const api_spec *s, const void *dest,
                 const api_params *ap) {
  const char *src = dest;
  int first = 1;
  api__w_put(w, "{", 1);
  for (int i = 0; i < s->n; i++) {
    const api_field *f = &s->fields[i];
    const void *at = src + f->off;
    if (!echoed(f, src))
      continue;
    if (!first)
      api__w_put(w, ",", 1);
    first = 0;
    api__w_str(w, f->name, strlen(f->name));
    api__w_put(w, ":", 1);
    switch (f->type) {
    case API_T_NUMBER:
      api__w_real(w, *(const double *)at);
      break;
    case API_T_COUNT:
      api__w_int(w, *(const long long *)at);
      break;
    case API_T_BOOL:
      if (*(const int *)at)
        API_W_LIT(w, "true");
      else
        API_W_LIT(w, "false");
      break;
    case API_T_ENUM: {
      const char *e = ((const char *const *)f->aux)[*(const int *)at];
      api__w_str(w, e, strlen(e));
      break;
    }
    case API_T_VEC4:
      for (int k = 0; k < 4; k++) {
        api__w_put(w, k ? "," : "[", 1);
        api__w_real(w, ((const double *)at)[k]);
      }
      api__w_put(w, "]", 1);
      break;
    case API_T_OBJECT:
      api__w_echo(w, f->aux, at, NULL);
      break;
    case API_T_CUSTOM: {
      json_t *v = ((const api_custom *)f->aux)->echo(at);
      if (v)
        api__w_json(w, v);
      else
        w->oom = 1;
      json_decref(v);
      break;
    }
    case API_T_ANY:
      break;
    }
  }
  if (ap) { /* api__params_echo's members */
    if (!first)
      api__w_put(w, ",", 1);
    API_W_LIT(w, "\"params\":");
    api__w_echo(w, &API_PARAMS_SPEC, &ap->p, NULL);
    if (ap->has_physical) {
      API_W_LIT(w, ",\"physical\":");
      api__w_echo(w, &API_PHYSICAL_SPEC, &ap->ph, NULL);
      API_W_LIT(w, ",\"omega\":");
      api__w_real(w, ap->omega);
    }
  }
  api__w_put(w, "}", 1);
}

int api__echo_as_tree;

static void echo_item(api_wbuf *w, const api_lazy *l, size_t i) {
  (void)i;
  api__w_echo(w, l->aux, l->a, l->b);
}

json_t *api__echo_raw(const api_call *c, const api_spec *s, const void *dest,
                      const api_params *ap) {
  return api__raw_aux(c, echo_item, dest, ap, s);
}

void api__params_echo(json_t *in, const api_params *ap) {
  api__set(in, "params", api__echo(&API_PARAMS_SPEC, &ap->p));
  if (ap->has_physical) {
    api__set(in, "physical", api__echo(&API_PHYSICAL_SPEC, &ap->ph));
    api__set(in, "omega", api__real(ap->omega));
  }
}

int api__mode_of(const char *s, ss_mode *m) {
  static const ss_mode all[] = {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK};
  for (int i = 0; s && i < 3; i++)
    if (strcmp(s, ss_mode_name(all[i])) == 0) {
      *m = all[i];
      return 0;
    }
  return -1;
}

/* ---- phase sequences ----------------------------------------------------- */

static int seq_length(const json_t *v, const char *ptr, const char *what,
                      const api_call *c) {
  if (!json_is_array(v) || json_array_size(v) < 2 ||
      json_array_size(v) > SS_MAX_PHASES)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an array of 2 to %d %s", ptr, SS_MAX_PHASES,
                     what);
  return (int)json_array_size(v);
}

static int decode_durations(const json_t *v, const char *ptr, void *dest,
                            const api_call *c) {
  api_durations *d = dest;
  int n = seq_length(v, ptr, "durations", c);
  if (n < 0 || api__numbers(v, ptr, d->v, c->e))
    return -1;
  for (int i = 0; i < n; i++)
    if (!(d->v[i] > 0))
      return api__fail(c->e, API_P_INVALID_VALUE, ptr,
                       "%s/%d must be a number > 0", ptr, i);
  d->n = n;
  return 0;
}

static json_t *echo_durations(const void *dest) {
  const api_durations *d = dest;
  return api__vec(d->v, d->n);
}

static int decode_modes(const json_t *v, const char *ptr, void *dest,
                        const api_call *c) {
  api_modes *s = dest;
  int n = seq_length(v, ptr, "mode names", c);
  if (n < 0)
    return -1;
  for (int i = 0; i < n; i++) {
    json_t *x = json_array_get(v, (size_t)i);
    char p[160];
    snprintf(p, sizeof p, "%s/%d", ptr, i);
    if (!json_is_string(x))
      return api__fail(c->e, API_P_INVALID_TYPE, p, "%s must be a mode name",
                       p);
    if (api__mode_of(json_string_value(x), &s->m[i]))
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s must be \"slip\", \"overshoot\" or \"stick\"", p);
  }
  s->n = n;
  return 0;
}

static json_t *echo_modes(const void *dest) {
  const api_modes *s = dest;
  json_t *a = json_array();
  for (int i = 0; i < s->n; i++)
    json_array_append_new(a, json_string(ss_mode_name(s->m[i])));
  return a;
}

const api_custom API_DURATIONS = {decode_durations, echo_durations};
const api_custom API_MODES = {decode_modes, echo_modes};

int api__sequence(const api_modes *s, const char *ptr, const api_call *c) {
  if (s->m[0] != SS_MODE_SLIP || s->m[s->n - 1] != SS_MODE_STICK)
    return api__fail(c->e, API_P_INVALID_VALUE, ptr,
                     "%s must start with slip (at the stick -> slip point) "
                     "and end with stick",
                     ptr);
  for (int i = 1; i < s->n; i++)
    if (s->m[i] == s->m[i - 1])
      return api__fail(c->e, API_P_INVALID_VALUE, ptr,
                       "%s repeats a mode in two consecutive phases", ptr);
  return 0;
}

/* ---- phases: [{"mode", "duration"}, ...] ----------------------------- */

typedef struct phase_one {
  int mode; /* ss_mode: the names below are in its order */
  double duration;
} phase_one;

static const char *const MODE_NAMES[] = {"slip", "overshoot", "stick", NULL};

static const api_field PHASE_FIELDS[] = {
    {"mode", API_T_ENUM, API_REQUIRED, 0, 0, NULL, offsetof(phase_one, mode), 0,
     0, 0, MODE_NAMES},
    {"duration", API_T_NUMBER, API_REQUIRED, 0, 0, NULL,
     offsetof(phase_one, duration)},
};
static const api_spec PHASE_SPEC = API_SPEC(PHASE_FIELDS);

static int decode_phases(const json_t *v, const char *ptr, void *dest,
                         const api_call *c) {
  api_phases *s = dest;
  if (!json_is_array(v) || json_array_size(v) < 2 ||
      json_array_size(v) > SS_MAX_PHASES)
    return api__fail(c->e, API_P_INVALID_TYPE, ptr,
                     "%s must be an array of 2 to %d phases", ptr,
                     SS_MAX_PHASES);
  int n = (int)json_array_size(v);
  for (int i = 0; i < n; i++) {
    const json_t *el = json_array_get(v, (size_t)i);
    phase_one ph;
    char p[160];
    snprintf(p, sizeof p, "%s/%d", ptr, i);
    if (!json_is_object(el))
      return api__fail(c->e, API_P_INVALID_TYPE, p,
                       "%s must be a phase {mode, duration}", p);
    /* an unknown mode name is reported at the phase (as clients know it) */
    const json_t *mode = json_object_get(el, "mode");
    ss_mode m;
    if (json_is_string(mode) && api__mode_of(json_string_value(mode), &m))
      return api__fail(c->e, API_P_INVALID_VALUE, p,
                       "%s must be \"slip\", \"overshoot\" or \"stick\"", p);
    if (api__decode(&PHASE_SPEC, el, p, &ph, c))
      return -1;
    if (!(ph.duration > 0))
      return api__fail(c->e, API_P_INVALID_VALUE, p, "%s/duration must be > 0",
                       p);
    s->modes.m[i] = (ss_mode)ph.mode;
    s->dur.v[i] = ph.duration;
  }
  s->modes.n = s->dur.n = n;
  return api__sequence(&s->modes, ptr, c);
}

static json_t *echo_phases(const void *dest) {
  const api_phases *s = dest;
  json_t *a = json_array();
  for (int k = 0; k < s->modes.n; k++) {
    json_t *p = json_object();
    api__set(p, "mode", json_string(ss_mode_name(s->modes.m[k])));
    api__set(p, "duration", api__real(s->dur.v[k]));
    json_array_append_new(a, p);
  }
  return a;
}

const api_custom API_PHASES = {decode_phases, echo_phases};

/* ---- a guess of an orbit's durations ---------------------------------- */

static const api_field GUESS_FIELDS[] = {
    {"durations", API_T_CUSTOM, API_REQUIRED, 0, 0, NULL,
     offsetof(api_guess, durations), 0, 0, 0, &API_DURATIONS},
    {"modes", API_T_CUSTOM, API_DEFAULT, 0, 0, NULL, offsetof(api_guess, modes),
     API_HAS(api_guess, has_modes), 0, 0, &API_MODES},
};
const api_spec API_GUESS_SPEC = API_SPEC(GUESS_FIELDS);

int api__guess_modes(api_guess *g, const char *ptr, const api_call *c) {
  static const ss_mode ov[3] = {SS_MODE_SLIP, SS_MODE_OVERSHOOT, SS_MODE_STICK};
  static const ss_mode ss[2] = {SS_MODE_SLIP, SS_MODE_STICK};
  int n = g->durations.n;
  char p[96];
  snprintf(p, sizeof p, "%.80s/modes", ptr);
  if (g->has_modes) {
    if (g->modes.n != n)
      return api__fail(c->e, API_P_INVALID_TYPE, p,
                       "%s must have one entry per duration", p);
    return api__sequence(&g->modes, p, c);
  }
  if (n > 3)
    return api__fail(c->e, API_P_MISSING_FIELD, p,
                     "a guess with more than 3 durations needs its modes");
  memcpy(g->modes.m, n == 3 ? ov : ss, (size_t)n * sizeof(ss_mode));
  g->modes.n = n;
  return 0;
}
