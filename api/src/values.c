/*
 * values.c: JSON values from numbers.  No NaN or Infinity is ever emitted:
 * a non-finite number becomes null (an unbounded margin, for example).
 */
#include <math.h>

#include "values.h"

json_t *api__real(double v) { return isfinite(v) ? json_real(v) : json_null(); }

json_t *api__vec4(const double x[4]) {
  json_t *a = json_array();
  for (int i = 0; i < 4; i++)
    json_array_append_new(a, api__real(x[i]));
  return a;
}

int api__set(json_t *obj, const char *key, json_t *v) {
  if (!v)
    return -1;
  return json_object_set_new(obj, key, v);
}

json_t *api__vec(const double *x, int n) {
  json_t *a = json_array();
  for (int i = 0; i < n; i++)
    json_array_append_new(a, api__real(x[i]));
  return a;
}
