/*
 * decode.c: field-by-field validation of request bodies.  Every value is
 * checked for type, finiteness, range and length, and every failure names
 * the field by its JSON pointer.  A missing required field is an error,
 * never a zero; an unknown field is an error, never ignored.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "codec.h"

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

static void join(char *out, size_t n, const char *ptr, const char *key) {
  char k[48];
  safe_key(key, k, sizeof k);
  snprintf(out, n, "%s/%s", ptr, k);
}

int api__keys(const json_t *obj, const char *ptr, const char *const *allowed,
              api_err *e) {
  const char *key;
  json_t *v;
  json_object_foreach((json_t *)obj, key, v) {
    int ok = 0;
    for (int i = 0; allowed[i]; i++)
      if (strcmp(key, allowed[i]) == 0)
        ok = 1;
    if (!ok) {
      char p[160], list[256] = "";
      join(p, sizeof p, ptr, key);
      for (int i = 0; allowed[i]; i++) {
        strncat(list, i ? ", " : "", sizeof list - strlen(list) - 1);
        strncat(list, allowed[i], sizeof list - strlen(list) - 1);
      }
      return api__fail(e, 422, "unknown-field", p,
                       "unknown field '%s'; the fields here are: %s", p, list);
    }
  }
  return 0;
}

static int lookup(const json_t *obj, const char *ptr, const char *key,
                  int required, json_t **v, char *p, size_t pn, api_err *e) {
  join(p, pn, ptr, key);
  *v = json_object_get(obj, key);
  if (!*v || json_is_null(*v)) {
    if (required)
      return api__fail(e, 422, "missing-field", p,
                       "the required field %s is missing", p);
    return 1;
  }
  return 0;
}

int api__object(const json_t *obj, const char *ptr, const char *key,
                int required, json_t **out, api_err *e) {
  char p[160];
  int rc = lookup(obj, ptr, key, required, out, p, sizeof p, e);
  if (rc)
    return rc;
  if (!json_is_object(*out))
    return api__fail(e, 422, "invalid-type", p, "%s must be an object", p);
  return 0;
}

int api__number(const json_t *obj, const char *ptr, const char *key,
                int required, double *out, api_err *e) {
  char p[160];
  json_t *v;
  int rc = lookup(obj, ptr, key, required, &v, p, sizeof p, e);
  if (rc)
    return rc;
  if (!json_is_number(v))
    return api__fail(e, 422, "invalid-type", p, "%s must be a number", p);
  *out = json_number_value(v);
  if (!isfinite(*out))
    return api__fail(e, 422, "invalid-value", p, "%s must be finite", p);
  return 0;
}

int api__count(const json_t *obj, const char *ptr, const char *key,
               int required, long long lo, long long hi, long long *out,
               api_err *e) {
  char p[160];
  json_t *v;
  int rc = lookup(obj, ptr, key, required, &v, p, sizeof p, e);
  if (rc)
    return rc;
  if (!json_is_integer(v))
    return api__fail(e, 422, "invalid-type", p, "%s must be an integer", p);
  *out = (long long)json_integer_value(v);
  if (*out < lo || *out > hi)
    return api__fail(e, 422, "invalid-value", p,
                     "%s must be between %lld and %lld (got %lld)", p, lo, hi,
                     *out);
  return 0;
}

int api__bool(const json_t *obj, const char *ptr, const char *key, int required,
              int *out, api_err *e) {
  char p[160];
  json_t *v;
  int rc = lookup(obj, ptr, key, required, &v, p, sizeof p, e);
  if (rc)
    return rc;
  if (!json_is_boolean(v))
    return api__fail(e, 422, "invalid-type", p, "%s must be true or false", p);
  *out = json_is_true(v);
  return 0;
}

int api__string(const json_t *obj, const char *ptr, const char *key,
                int required, const char **out, api_err *e) {
  char p[160];
  json_t *v;
  int rc = lookup(obj, ptr, key, required, &v, p, sizeof p, e);
  if (rc)
    return rc;
  if (!json_is_string(v))
    return api__fail(e, 422, "invalid-type", p, "%s must be a string", p);
  *out = json_string_value(v);
  return 0;
}

int api__vec(const json_t *obj, const char *ptr, const char *key, int required,
             size_t n, double *out, api_err *e) {
  char p[160];
  json_t *v;
  int rc = lookup(obj, ptr, key, required, &v, p, sizeof p, e);
  if (rc)
    return rc;
  if (!json_is_array(v) || json_array_size(v) != n)
    return api__fail(e, 422, "invalid-type", p,
                     "%s must be an array of %zu numbers", p, n);
  for (size_t i = 0; i < n; i++) {
    json_t *x = json_array_get(v, i);
    if (!json_is_number(x) || !isfinite(json_number_value(x)))
      return api__fail(e, 422, "invalid-type", p,
                       "%s/%zu must be a finite number", p, i);
    out[i] = json_number_value(x);
  }
  return 0;
}

void api__from_diag(api_err *e, int rc, const ss_diag *d,
                    const char *ptr_base) {
  char p[160];
  if (d->where[0] && ptr_base)
    snprintf(p, sizeof p, "%s/%s", ptr_base, d->where);
  else
    snprintf(p, sizeof p, "%s", ptr_base ? ptr_base : "");
  if (rc == SS_ENOMEM || rc == SS_EBUG)
    api__fail(e, 500, "internal", NULL, "%s",
              d->text[0] ? d->text : ss_strerror(rc));
  else
    api__fail(e, 422, "invalid-value", p, "%s",
              d->text[0] ? d->text : ss_strerror(rc));
}

const char *const API_PARAM_KEYS[] = {"chi", "eta", "us", "ur", "V", NULL};
const char *const API_PHYS_KEYS[] = {"m1", "m2", "k1", "k2",
                                     "Fs", "Fr", "v0", NULL};

int api__params(const json_t *root, api_params *ap, api_err *e) {
  json_t *pp = NULL, *ph = NULL;
  int a = api__object(root, "", "params", 0, &pp, e);
  int b = api__object(root, "", "physical", 0, &ph, e);
  ss_diag d;
  if (a < 0 || b < 0)
    return -1;
  memset(ap, 0, sizeof *ap);
  ap->omega = 1;
  if (a == 0 && b == 0)
    return api__fail(e, 422, "invalid-value", "/physical",
                     "give either params or physical, not both");
  if (a == 1 && b == 1)
    return api__fail(e, 422, "missing-field", "/params",
                     "the parameters are missing: give params {chi, eta, us, "
                     "ur, V} or physical {m1, m2, k1, k2, Fs, Fr, v0}");
  ss_diag_clear(&d);
  if (a == 0) {
    double *dst[] = {&ap->p.chi, &ap->p.eta, &ap->p.us, &ap->p.ur, &ap->p.V};
    if (api__keys(pp, "/params", API_PARAM_KEYS, e))
      return -1;
    for (int i = 0; i < 5; i++)
      if (api__number(pp, "/params", API_PARAM_KEYS[i], 1, dst[i], e))
        return -1;
    int rc = ss_params_check(&ap->p, &d);
    if (rc) {
      api__from_diag(e, rc, &d, "/params");
      return -1;
    }
    return 0;
  }
  double *dst[] = {&ap->ph.m1, &ap->ph.m2, &ap->ph.k1, &ap->ph.k2,
                   &ap->ph.Fs, &ap->ph.Fr, &ap->ph.v0};
  if (api__keys(ph, "/physical", API_PHYS_KEYS, e))
    return -1;
  for (int i = 0; i < 7; i++)
    if (api__number(ph, "/physical", API_PHYS_KEYS[i], 1, dst[i], e))
      return -1;
  int rc = ss_params_from_physical(&ap->ph, &ap->p, &ap->omega, &d);
  if (rc) {
    api__from_diag(e, rc, &d, "/physical");
    return -1;
  }
  ap->physical = 1;
  return 0;
}
