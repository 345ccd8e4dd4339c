/*
 * endpoints.h: the only list of endpoints.
 *
 * One row per endpoint: its name, method, path, metrics label, run class,
 * and the four functions that serve it.  Routing (api_route), the server's
 * metrics, the codec case runner and the check of api/openapi.json all read
 * this table through api_endpoint_at(); nothing else lists endpoints.
 *
 * An endpoint is served as decode -> run -> encode:
 *   decode  the request body (parsed JSON object) into the endpoint's own
 *           struct, allocated by decode in *x: fields checked, units of the
 *           request converted to dimensionless core structs;
 *   run     the core computation on *x;
 *   encode  *x into the answer;
 *   release frees *x (NULL-safe), whatever step failed.
 * Each returns 0, or -1 with the problem recorded in c->e.  For an inline
 * (GET) endpoint there is no body: decode and run may do nothing.
 *
 * Adding an endpoint: write api/src/ep_<name>.c with its four functions,
 * add its row here and its path to api/openapi.json (a test checks that the
 * two agree).
 */
#ifndef SS_API_ENDPOINTS_H
#define SS_API_ENDPOINTS_H

#include <jansson.h>
#include <stddef.h>

#include "call.h"
#include "problem.h"
#include "stickslip_api.h"

/*     name       method  path             label        class
 *     decode                 run                  encode
 *     release */
#define API_ENDPOINTS(X)                                                       \
  X(ORBIT, "POST", "/orbit", "orbit", API_RUN_COMPUTE, ep_orbit_decode,        \
    ep_orbit_run, ep_orbit_encode, ep_orbit_release)                           \
  X(SIMULATE, "POST", "/simulate", "simulate", API_RUN_COMPUTE,                \
    ep_simulate_decode, ep_simulate_run, ep_simulate_encode,                   \
    ep_simulate_release)                                                       \
  X(STABILITY, "POST", "/stability", "stability", API_RUN_COMPUTE,             \
    ep_stability_decode, ep_stability_run, ep_stability_encode,                \
    ep_stability_release)                                                      \
  X(CONTINUE, "POST", "/continue", "continue", API_RUN_COMPUTE,                \
    ep_continue_decode, ep_continue_run, ep_continue_encode,                   \
    ep_continue_release)                                                       \
  X(MAP, "POST", "/map", "map", API_RUN_COMPUTE, ep_map_decode, ep_map_run,    \
    ep_map_encode, ep_map_release)                                             \
  X(BASINS, "POST", "/basins", "basins", API_RUN_COMPUTE, ep_basins_decode,    \
    ep_basins_run, ep_basins_encode, ep_basins_release)                        \
  X(BATCH, "POST", "/batch", "batch", API_RUN_BATCH, ep_batch_decode,          \
    ep_batch_run, ep_batch_encode, ep_batch_release)                           \
  X(HEALTH, "GET", "/health", "health", API_RUN_INLINE, ep_meta_decode,        \
    ep_meta_run, ep_health_encode, ep_meta_release)                            \
  X(VERSION, "GET", "/version", "version", API_RUN_INLINE, ep_meta_decode,     \
    ep_meta_run, ep_version_encode, ep_meta_release)                           \
  X(OPENAPI, "GET", "/openapi.json", "openapi", API_RUN_INLINE,                \
    ep_meta_decode, ep_meta_run, ep_openapi_encode, ep_meta_release)           \
  X(METRICS, "GET", "/metrics", "metrics", API_RUN_INLINE, ep_meta_decode,     \
    ep_meta_run, ep_metrics_encode, ep_meta_release)                           \
  X(EXPLORER, "GET", "/", "explorer", API_RUN_INLINE, ep_meta_decode,          \
    ep_meta_run, ep_explorer_encode, ep_meta_release)                          \
  X(EXPLORER_JS, "GET", "/explorer/app.js", "explorer_js", API_RUN_INLINE,     \
    ep_meta_decode, ep_meta_run, ep_explorer_js_encode, ep_meta_release)       \
  X(EXPLORER_CSS, "GET", "/explorer/style.css", "explorer_css",                \
    API_RUN_INLINE, ep_meta_decode, ep_meta_run, ep_explorer_css_encode,       \
    ep_meta_release)

/* The endpoints that also answer in NDJSON (API_FORM_NDJSON), when the
 * client's Accept asks for it: their decode reads the form from
 * api_call.form. */
#define API_NDJSON_FORMS(X) X(BASINS)

typedef int ep_decode_fn(const json_t *root, const api_call *c, void **x);
typedef int ep_run_fn(void *x, const api_call *c);
typedef int ep_encode_fn(const void *x, const api_call *c, api_response *out);
typedef void ep_release_fn(void *x);

#define API_EP_DECLARE(name, method, path, label, cls, dec, run, enc, rel)     \
  ep_decode_fn dec;                                                            \
  ep_run_fn run;                                                               \
  ep_encode_fn enc;                                                            \
  ep_release_fn rel;
API_ENDPOINTS(API_EP_DECLARE)
#undef API_EP_DECLARE

/* A request body as a JSON object (nesting depth at most lim->max_depth,
 * no duplicate keys), or NULL with the problem in @a e. */
json_t *api__parse(const char *body, size_t len, const api_limits *lim,
                   api_err *e);

/* Serve endpoint @a index as api_handle does; a problem's pointer, when it
 * names a field, is prefixed by @a prefix (NULL: none), for an answer read
 * as part of a larger document (an item of a batch). */
int api__handle(size_t index, const char *body, size_t len,
                const api_limits *lim, const api_server_info *srv,
                api_response *out, const char *prefix);

#endif
