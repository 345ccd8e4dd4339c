/*
 * stickslip_api.h: the JSON interface of stickslip.
 *
 * The api layer turns a request body into validated core structs, calls
 * libstickslip, and turns the result into a response body.  It knows JSON
 * (jansson) but not HTTP transport: the server hands it a body and gets back
 * a status code and a body.  The contract is api/openapi.yaml.
 *
 * Errors are RFC 9457 problem details (application/problem+json):
 *   {"type", "title", "status", "detail", "pointer"?, "limit"?, "limit_value"?}
 * 400 for malformed JSON, 422 for a well-formed request with a wrong field
 * (the JSON pointer names it), 422 with "limit" for a request over a limit.
 */
#ifndef STICKSLIP_API_H
#define STICKSLIP_API_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Per-request limits; api_limits_default() gives the documented defaults. */
typedef struct api_limits {
  size_t max_body;       /**< request body bytes (server enforces) */
  size_t max_samples;    /**< samples in one response */
  size_t max_events;     /**< events computed by one /simulate */
  size_t max_event_list; /**< events listed in one response */
  double max_horizon;    /**< t_end - t0, dimensionless time */
  double max_seconds;    /**< compute time of one request */
  int max_orbits;        /**< orbits in one /orbit response */
  int max_depth;         /**< JSON nesting depth */
} api_limits;

/** Fill @a l with the defaults documented in the README. */
void api_limits_default(api_limits *l);

/** A response: status, body (malloc'd, NUL-terminated), media type. */
typedef struct api_response {
  int status;
  char *body;
  size_t len;
  const char *content_type; /**< static string */
} api_response;

/** Free the body; NULL-safe. */
void api_response_free(api_response *r);

/** The endpoints that compute. */
typedef enum api_endpoint {
  API_ORBIT = 0,
  API_SIMULATE = 1,
  API_STABILITY = 2
} api_endpoint;

/**
 * Handle one request body for @a ep: parse, validate, compute, encode.
 * Always fills @a out (a result or a problem); returns out->status.
 * Thread-safe.
 */
int api_handle(api_endpoint ep, const char *body, size_t len,
               const api_limits *lim, api_response *out);

/**
 * A problem response built by the caller (transport errors: 404, 405, 413,
 * 415, 503).  @a pointer and @a limit may be NULL.
 */
void api_problem(api_response *out, int status, const char *type,
                 const char *title, const char *detail, const char *pointer,
                 const char *limit, double limit_value);

/** The OpenAPI document (api/openapi.yaml, which is written in JSON syntax). */
const char *api_openapi_json(void);

/** The version string of the service. */
const char *api_version(void);

#ifdef __cplusplus
}
#endif

#endif
