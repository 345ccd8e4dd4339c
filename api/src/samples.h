/*
 * samples.h: what a request asks of its samples (samples.c): even, at given
 * times, or placed for a curve to a tolerance, and which columns; shared
 * by /simulate and /orbit.
 */
#ifndef SS_API_SAMPLES_H
#define SS_API_SAMPLES_H

#include <stddef.h>

#include "call.h"
#include "decode.h"
#include "stickslip.h"

/* Sample times as given (malloc'd). */
typedef struct api_times {
  double *v;
  size_t n;
} api_times;

/* "samples": {"n", "from", "to"}, {"t": [...]}, or {"tolerance", "plane",
 * "scale", "max", "from", "to"}; with any, "fields" (the columns). */
typedef struct api_samples_req {
  long long n, max;
  double from, to, tolerance;
  double scale[4]; /* of x1, x2, v1, v2; 0: 1 */
  unsigned plane;  /* bits of x1, x2, v1, v2 */
  unsigned fields; /* bits of API_SAMPLE_COLUMNS */
  api_times t;
  int has_n, has_from, has_to, has_t, has_tolerance, has_plane, has_scale,
      has_max, has_fields;
} api_samples_req;

/* t, x1, x2, v1, v2, mode, force, F1, F2 (NULL-terminated). */
extern const char *const API_SAMPLE_COLUMNS[];
/* The object's spec in /simulate (all of it) and in /orbit (n, or a
 * tolerance; over one period). */
extern const api_spec API_SIM_SAMPLES, API_ORBIT_SAMPLES;

/* The tolerance, axes, scales and count limit of a curve's samples into
 * @a o (nothing for even samples or times), after the checks that span
 * fields; @a ptr is the object's pointer.  0 or -1 (problem in c->e). */
int api__samples_core(const api_samples_req *s, const api_params *ap,
                      const char *ptr, ss_sim_opts *o, const api_call *c);
/* The columns asked for, as bits of API_SAMPLE_COLUMNS. */
unsigned api__samples_columns(const api_samples_req *s);
void api__samples_release(api_samples_req *s);

#endif
