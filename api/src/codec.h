/*
 * codec.h: internal helpers of the api layer: problem details and field
 * decoding with JSON pointers.
 */
#ifndef SS_API_CODEC_H
#define SS_API_CODEC_H

#include <jansson.h>

#include "stickslip.h"
#include "stickslip_api.h"

/* A problem being built; the first failure wins. */
typedef struct api_err {
  int status; /* 0: none */
  char type[48];
  char title[64];
  char detail[400];
  char pointer[160];
  char limit[32];
  double limit_value;
} api_err;

int api__fail(api_err *e, int status, const char *type, const char *pointer,
              const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 5, 6)))
#endif
    ;
int api__limit(api_err *e, const char *limit, double value, const char *pointer,
               const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* The response for a problem. */
void api__problem_response(const api_err *e, api_response *out);

/* Field access.  Each returns 0 (set), 1 (absent and optional) or -1
 * (error recorded in e).  ptr is the JSON pointer of the containing object. */
int api__keys(const json_t *obj, const char *ptr, const char *const *allowed,
              api_err *e);
int api__object(const json_t *obj, const char *ptr, const char *key,
                int required, json_t **out, api_err *e);
int api__number(const json_t *obj, const char *ptr, const char *key,
                int required, double *out, api_err *e);
int api__count(const json_t *obj, const char *ptr, const char *key,
               int required, long long lo, long long hi, long long *out,
               api_err *e);
int api__bool(const json_t *obj, const char *ptr, const char *key, int required,
              int *out, api_err *e);
int api__vec(const json_t *obj, const char *ptr, const char *key, int required,
             size_t n, double *out, api_err *e);
int api__string(const json_t *obj, const char *ptr, const char *key,
                int required, const char **out, api_err *e);

/* The physical or dimensionless parameters of a request. */
typedef struct api_params {
  ss_params p;
  int physical;
  ss_physical ph;
  double omega; /* 1 when dimensionless */
} api_params;

/* The field names of "params" and "physical", in the order of the fields of
 * ss_params and ss_physical (NULL-terminated); decode and echo share them. */
extern const char *const API_PARAM_KEYS[];
extern const char *const API_PHYS_KEYS[];

int api__params(const json_t *root, api_params *ap, api_err *e);
json_t *api__params_echo(const api_params *ap);

/* Encoding helpers that never emit NaN or Infinity: a non-finite value
 * becomes null. */
json_t *api__real(double v);
json_t *api__vec4(const double x[4]);
int api__set(json_t *obj, const char *key, json_t *v);

/* The compact text of @a j (malloc'd, NUL-terminated, length in *len), with
 * reals in the shortest of 15-17 significant digits that reads back exactly;
 * NULL when out of memory.  Strings must be valid UTF-8 (jansson's own). */
char *api__dump(const json_t *j, size_t *len);

/* The core's diagnostic as a problem, with the JSON pointer of where. */
void api__from_diag(api_err *e, int rc, const ss_diag *d, const char *ptr_base);

#endif
