/*
 * job.h: how an endpoint cuts its jobs (api_job_*, stickslip_api.h).
 *
 * api_job_open decodes the request once with the endpoint's own decode
 * (endpoints.h) into x, and asks the endpoint to cut it; an endpoint that
 * does not cut (a single answer) is one visible chunk, computed by its run
 * and encode.  An endpoint that cuts gives a row of the table in job.c:
 *   cut  the chunks of request x: their stages, items and visibility;
 *   run  chunk k of x, reading the results of earlier stages through in,
 *        into out (200 and the bytes to store, or a problem).
 * x is shared by the chunks of one job, which may run at the same time on
 * different threads: run does not change it (its work is its own).
 */
#ifndef SS_API_JOB_H
#define SS_API_JOB_H

#include <stddef.h>

#include "call.h"
#include "stickslip_api.h"

/* The cuts of one job; job.c frees the arrays. */
typedef struct api_job_cut {
  size_t n;               /* chunks, >= 1 */
  int *stage;             /* malloc'd, n: non-decreasing from 0 */
  long *items;            /* malloc'd, n */
  unsigned char *visible; /* malloc'd, n */
} api_job_cut;

/* Allocate the arrays of @a cut for @a n chunks (zeroed): 0, or -1 with
 * out of memory recorded in c->e. */
int api__job_cut_alloc(api_job_cut *cut, size_t n, const api_call *c);

typedef int ep_job_cut_fn(const void *x, const api_call *c, api_job_cut *cut);
/* Optional: decode a job's body into x without jansson's tree of the whole
 * body (a large body of the usual shape): 1 and *x; 0 when it leaves the
 * body to the whole parse and decode (nothing recorded); -1 with the
 * problem in c->e. */
typedef int ep_job_open_fn(const char *body, size_t len, const api_call *c,
                           void **x);
typedef int ep_job_run_fn(const void *x, size_t k, const api_job_inputs *in,
                          const api_call *c, api_response *out);

#endif
