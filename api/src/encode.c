/*
 * encode.c: core results to JSON.  No NaN or Infinity is ever emitted: a
 * non-finite number becomes null (an unbounded margin, for example).
 */
#include <math.h>
#include <string.h>

#include "codec.h"

json_t *api__real(double v) {
  return isfinite(v) ? json_real(v) : json_null();
}

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

json_t *api__params_echo(const api_params *ap) {
  json_t *o = json_object();
  json_t *p = json_object();
  api__set(p, "chi", api__real(ap->p.chi));
  api__set(p, "eta", api__real(ap->p.eta));
  api__set(p, "us", api__real(ap->p.us));
  api__set(p, "ur", api__real(ap->p.ur));
  api__set(p, "V", api__real(ap->p.V));
  api__set(o, "params", p);
  if (ap->physical) {
    json_t *ph = json_object();
    api__set(ph, "m1", api__real(ap->ph.m1));
    api__set(ph, "m2", api__real(ap->ph.m2));
    api__set(ph, "k1", api__real(ap->ph.k1));
    api__set(ph, "k2", api__real(ap->ph.k2));
    api__set(ph, "Fs", api__real(ap->ph.Fs));
    api__set(ph, "Fr", api__real(ap->ph.Fr));
    api__set(ph, "v0", api__real(ap->ph.v0));
    api__set(o, "physical", ph);
    api__set(o, "omega", api__real(ap->omega));
  }
  return o;
}
