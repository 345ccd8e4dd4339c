/*
 * problem.h: problems (problem.c): a failure recorded as the request is
 * served, the first one winning, and its RFC 9457 answer; the one table
 * from a status of the core to an HTTP answer.
 */
#ifndef SS_API_PROBLEM_H
#define SS_API_PROBLEM_H

#include "stickslip.h"
#include "stickslip_api.h"

#define API_FORMAT(a, b)
#ifdef __GNUC__
#undef API_FORMAT
#define API_FORMAT(a, b) __attribute__((format(printf, a, b)))
#endif

/* A problem being built; the first failure wins. */
typedef struct api_err {
  int set;
  api_problem_kind kind;
  char detail[400];
  char pointer[160];
  char limit[32];
  double limit_value;
} api_err;

/* Record a problem of @a kind at @a pointer (may be NULL); returns -1. */
int api__fail(api_err *e, api_problem_kind kind, const char *pointer,
              const char *fmt, ...) API_FORMAT(4, 5);

/* A request over the limit named @a limit (its value @a value); returns -1. */
int api__limit(api_err *e, const char *limit, double value, const char *pointer,
               const char *fmt, ...) API_FORMAT(5, 6);

/* A failure status of the core that is a limit: as api__status, and the
 * problem names the limit @a limit and its value. */
int api__status_limit(api_err *e, int status, const char *limit, double value,
                      const char *pointer, const char *fmt, ...)
    API_FORMAT(6, 7);

/* A failure status of the core, answered by the table API_STATUS_PROBLEM;
 * a status the table does not know is an internal error.  @a pointer names
 * the field at fault (may be NULL).  Returns -1. */
int api__status(api_err *e, int status, const char *pointer, const char *fmt,
                ...) API_FORMAT(4, 5);

/* The core's diagnostic as a problem: the pointer is @a base followed by the
 * diagnostic's "where" (a parameter name), the detail is its text. */
int api__from_diag(api_err *e, int rc, const ss_diag *d, const char *base);

/* The response for a recorded problem. */
void api__problem_response(const api_err *e, api_response *out);

#endif
