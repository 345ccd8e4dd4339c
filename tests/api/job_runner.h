/*
 * job_runner.h: a request served as a job the way a server with a store
 * serves it (job_runner.c), for the tests that hold a job's answer against
 * the synchronous one: opened, its chunks run stage by stage in a chosen
 * order, their results kept in memory and read by later stages through
 * api_job_inputs, the answer made of the visible results in chunk order.
 */
#ifndef SS_TEST_JOB_RUNNER_H
#define SS_TEST_JOB_RUNNER_H

#include <stddef.h>

#include "stickslip_api.h"

/* The order in which the chunks of one stage run. */
typedef enum job_order { JOB_FORWARD, JOB_REVERSE, JOB_SHUFFLE } job_order;

/* What the run saw, beyond its answer. */
typedef struct job_trace {
  int opened;     /* api_job_open accepted the request */
  size_t chunks;  /* api_job_chunks */
  int stages;     /* the last stage + 1 */
  long items;     /* api_job_items, which must be the sum over the chunks */
  long items_sum; /* the sum of api_job_chunk_items */
  int bad_reads;  /* reads of a chunk not of an earlier stage, or not yet
                     stored: a cut that reads what it may not */
  const char *content_type; /* api_job_content_type */
} job_trace;

/* The job's answer to @a body for endpoint @a ep in @a out, as a server
 * would give it: the problem of api_job_open, or the problem of the first
 * chunk that failed, or 200 and the visible results concatenated (its media
 * type the job's).  @a seed shuffles (JOB_SHUFFLE).  Returns out->status. */
int job_answer(size_t ep, const char *body, size_t len, const api_limits *lim,
               job_order order, unsigned seed, api_response *out, job_trace *t);

/* job_answer for an answer in @a form (api_job_open_form). */
int job_answer_form(size_t ep, api_form form, const char *body, size_t len,
                    const api_limits *lim, job_order order, unsigned seed,
                    api_response *out, job_trace *t);

/* A copy of @a s (malloc'd) where the value of every "key": (a number or a
 * string) is 0: the answers compared but for a time they report. */
char *job_blank(const char *s, size_t len, const char *key);

#endif
