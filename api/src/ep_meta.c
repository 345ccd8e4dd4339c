/*
 * ep_meta.c: the endpoints that describe the service rather than compute:
 * GET /health, /version, /openapi.json, /metrics, and the explorer (GET /
 * and its assets).  They have no body, so
 * decode and run do nothing; what the server knows of itself (uptime,
 * requests in flight, metrics) comes in c->srv.
 */
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_version.h>

#include "endpoints.h"
#include "problem.h"
#include "values.h"
#include "writer.h"

int ep_meta_decode(const json_t *root, const api_call *c, void **x) {
  (void)root;
  (void)c;
  *x = NULL;
  return 0;
}

int ep_meta_run(void *x, const api_call *c) {
  (void)x;
  (void)c;
  return 0;
}

void ep_meta_release(void *x) { (void)x; }

int ep_health_encode(const void *x, const api_call *c, api_response *out) {
  json_t *o = json_object();
  (void)x;
  api__set(o, "status", json_string("ok"));
  api__set(o, "version", json_string(api_version()));
  if (c->srv) {
    api__set(o, "uptime_seconds", api__real(c->srv->uptime_seconds));
    api__set(o, "in_flight", json_integer(c->srv->in_flight));
  }
  return api__json_response(o, c, out);
}

int ep_version_encode(const void *x, const api_call *c, api_response *out) {
  json_t *o = json_object();
  (void)x;
  api__set(o, "service", json_string("stickslipd"));
  api__set(o, "version", json_string(api_version()));
  api__set(o, "gsl", json_string(GSL_VERSION));
  api__set(o, "jansson", json_string(JANSSON_VERSION));
  if (c->srv && c->srv->transport)
    api__set(o, "microhttpd", json_string(c->srv->transport));
  return api__json_response(o, c, out);
}

static int text(const char *s, size_t n, const char *ctype, api_response *out,
                api_err *e) {
  out->body = malloc(n + 1);
  if (!out->body)
    return api__fail(e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  memcpy(out->body, s, n + 1);
  out->len = n;
  out->status = 200;
  out->content_type = ctype;
  return 0;
}

int ep_openapi_encode(const void *x, const api_call *c, api_response *out) {
  const char *s = api_openapi_json();
  (void)x;
  return text(s, strlen(s), "application/json", out, c->e);
}

/* The explorer (api/explorer, embedded): its page and its two assets. */
static const struct {
  const char *label, *file, *ctype;
} ASSETS[] = {
    {"explorer", "index.html", "text/html; charset=utf-8"},
    {"explorer_js", "app.js", "text/javascript; charset=utf-8"},
    {"explorer_css", "style.css", "text/css; charset=utf-8"},
};

static int asset(int k, const api_call *c, api_response *out) {
  size_t n;
  const char *s = api_explorer_asset(ASSETS[k].file, &n);
  return text(s, n, ASSETS[k].ctype, out, c->e);
}

int ep_explorer_encode(const void *x, const api_call *c, api_response *out) {
  (void)x;
  return asset(0, c, out);
}

int ep_explorer_js_encode(const void *x, const api_call *c, api_response *out) {
  (void)x;
  return asset(1, c, out);
}

int ep_explorer_css_encode(const void *x, const api_call *c,
                           api_response *out) {
  (void)x;
  return asset(2, c, out);
}

const char *api_static_body(size_t i, size_t *len) {
  const api_endpoint *ep = api_endpoint_at(i);
  *len = 0;
  if (!ep)
    return NULL;
  if (!strcmp(ep->label, "openapi")) {
    const char *s = api_openapi_json();
    *len = strlen(s);
    return s;
  }
  for (size_t k = 0; k < sizeof ASSETS / sizeof ASSETS[0]; k++)
    if (!strcmp(ep->label, ASSETS[k].label))
      return api_explorer_asset(ASSETS[k].file, len);
  return NULL;
}

int ep_metrics_encode(const void *x, const api_call *c, api_response *out) {
  (void)x;
  if (!c->srv || !c->srv->metrics_text)
    return api__fail(c->e, API_P_NOT_FOUND, NULL,
                     "this server keeps no metrics");
  char *s = c->srv->metrics_text(c->srv->metrics_cls);
  if (!s)
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  out->body = s;
  out->len = strlen(s);
  out->status = 200;
  out->content_type = "text/plain; version=0.0.4; charset=utf-8";
  return 0;
}
