/*
 * values.h: JSON values from numbers (values.c), never NaN or Infinity: a
 * non-finite value becomes null.  Both the echo of a request (decode.c)
 * and the answers (encode.c, the endpoints) build their numbers with these.
 */
#ifndef SS_API_VALUES_H
#define SS_API_VALUES_H

#include <jansson.h>

json_t *api__real(double v);
json_t *api__vec4(const double x[4]);
json_t *api__vec(const double *x, int n);
/* json_object_set_new, and -1 when @a v is NULL (a value that could not be
 * made). */
int api__set(json_t *obj, const char *key, json_t *v);

#endif
