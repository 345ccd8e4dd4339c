/*
 * endpoints.c: the endpoint table at work: routing, and one request served
 * as parse -> decode -> run -> encode.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <strings.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "endpoints.h"
#include "arena.h"
#include "problem.h"
#include "scan.h"
#include "writer.h"

typedef struct ep_row {
  api_endpoint pub;
  ep_decode_fn *decode;
  ep_run_fn *run;
  ep_encode_fn *encode;
  ep_release_fn *release;
} ep_row;

static const ep_row ENDPOINTS[] = {
#define API_EP_ROW(name, method, path, label, cls, dec, run, enc, rel)         \
  {{method, path, label, cls}, dec, run, enc, rel},
    API_ENDPOINTS(API_EP_ROW)
#undef API_EP_ROW
};

#define N_ENDPOINTS (sizeof ENDPOINTS / sizeof ENDPOINTS[0])

size_t api_endpoint_count(void) { return N_ENDPOINTS; }

const api_endpoint *api_endpoint_at(size_t i) {
  return i < N_ENDPOINTS ? &ENDPOINTS[i].pub : NULL;
}

/* The index of each endpoint, in the order of the one list. */
enum {
#define EP_INDEX(name, method, path, label, cls, dec, run, enc, rel) EP_##name,
  API_ENDPOINTS(EP_INDEX)
#undef EP_INDEX
      EP_COUNT
};

/* The quality (RFC 9110 12.4.2) an Accept header @a accept gives the media
 * type @a type when it names it; -1 when it does not.  Ranges (* / *) are
 * not counted: they accept the default form. */
static double quality(const char *accept, const char *type) {
  size_t n = strlen(type);
  double q = -1;
  for (const char *s = accept; s && *s;
       s = strchr(s, ',') ? strchr(s, ',') + 1 : NULL) {
    while (*s == ' ' || *s == '\t')
      s++;
    const char *end = s + strcspn(s, ",;");
    while (end > s && (end[-1] == ' ' || end[-1] == '\t'))
      end--;
    if ((size_t)(end - s) != n || strncasecmp(s, type, n) != 0)
      continue;
    double v = 1;
    const char *param = s + strcspn(s, ",;");
    while (*param == ';') {
      param++;
      while (*param == ' ')
        param++;
      if ((param[0] == 'q' || param[0] == 'Q') && param[1] == '=')
        v = strtod(param + 2, NULL);
      param += strcspn(param, ",;");
    }
    if (v > q)
      q = v;
  }
  return q;
}

api_form api_negotiate(size_t index, const char *accept) {
  static const size_t FORMS[] = {
#define EP_NDJSON_FORM(name) EP_##name,
      API_NDJSON_FORMS(EP_NDJSON_FORM)
#undef EP_NDJSON_FORM
  };
  int has = 0;
  for (size_t i = 0; i < sizeof FORMS / sizeof FORMS[0]; i++)
    has |= FORMS[i] == index;
  if (!has || !accept)
    return API_FORM_DEFAULT;
  double nd = quality(accept, "application/x-ndjson");
  return nd > 0 && nd > quality(accept, "application/json") ? API_FORM_NDJSON
                                                            : API_FORM_DEFAULT;
}

int api_route(const char *method, const char *path, size_t *index) {
  for (size_t i = 0; i < N_ENDPOINTS; i++) {
    const api_endpoint *ep = &ENDPOINTS[i].pub;
    if (strcmp(path, ep->path) != 0)
      continue;
    *index = i;
    if (strcmp(method, ep->method) == 0 ||
        (strcmp(method, "HEAD") == 0 && strcmp(ep->method, "GET") == 0))
      return 200;
    return 405;
  }
  return 404;
}

void api_limits_default(api_limits *l) {
  l->max_body = 1 << 20;
  l->max_samples = 100000;
  l->max_events = 2000000;
  l->max_event_list = 100000;
  l->max_horizon = 1e7;
  l->max_seconds = 10;
  l->max_orbits = 32;
  l->max_depth = 32;
  l->max_batch_items = 10000;
  l->max_points = 2000;
  l->max_map_cells = 10000;
  l->max_basin_cells = 1 << 20;
  l->map_threads = 1;
}

const char *api_version(void) { return SS_VERSION; }

/* Nesting depth of a JSON text, outside strings; stops counting past max.
 * jansson's own limit (2048) is far above what a request needs. */
static int too_deep(const char *s, size_t n, int max) {
  int depth = 0, in_str = 0;
  for (size_t i = 0; i < n; i++) {
    char c = s[i];
    if (in_str) {
      if (c == '\\')
        i++;
      else if (c == '"')
        in_str = 0;
    } else if (c == '"') {
      in_str = 1;
    } else if (c == '[' || c == '{') {
      if (++depth > max)
        return 1;
    } else if (c == ']' || c == '}') {
      depth--;
    }
  }
  return 0;
}

json_t *api__parse(const char *body, size_t len, const api_limits *lim,
                   api_err *e) {
  json_error_t jerr;
  json_t *root;
  if (len == 0) {
    api__fail(e, API_P_INVALID_JSON, NULL,
              "the request body is empty; send a JSON object");
    return NULL;
  }
  if (too_deep(body, len, lim->max_depth)) {
    api__fail(e, API_P_INVALID_JSON, NULL,
              "the JSON nesting is deeper than %d levels", lim->max_depth);
    return NULL;
  }
  root = api__json_build(body, body + len, lim->max_depth + 1);
  if (!root)
    root = json_loadb(body, len, JSON_REJECT_DUPLICATES, &jerr);
  if (!root) {
    api__fail(e, API_P_INVALID_JSON, NULL,
              "the body is not valid JSON: %s (line %d, column %d)", jerr.text,
              jerr.line, jerr.column);
    return NULL;
  }
  if (!json_is_object(root)) {
    json_decref(root);
    api__fail(e, API_P_INVALID_TYPE, "",
              "the request body must be a JSON object");
    return NULL;
  }
  return root;
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int api_handle(size_t index, const char *body, size_t len,
               const api_limits *lim, const api_server_info *srv,
               api_response *out) {
  return api__handle(index, body, len, lim, srv, out, NULL);
}

int api__handle(size_t index, const char *body, size_t len,
                const api_limits *lim, const api_server_info *srv,
                api_response *out, const char *prefix) {
  api_err e;
  api_lazies lz = {NULL, 0, 0, 0};
  int small = 0;
  api_call c = {lim, srv,    &e,
                &lz, &small, srv ? (api_form)srv->form : API_FORM_DEFAULT};
  json_t *root = NULL;
  void *x = NULL;
  memset(&e, 0, sizeof e);
  memset(out, 0, sizeof *out);
  if (index >= N_ENDPOINTS) {
    api__fail(&e, API_P_NOT_FOUND, NULL, "no such endpoint");
    api__problem_response(&e, out);
    return out->status;
  }
  const ep_row *ep = &ENDPOINTS[index];
  api_arena_mark mark; /* the request's tree and the answer's */
  api__arena_begin(&mark);
  if (ep->pub.run_class != API_RUN_INLINE &&
      !(root = api__parse(body ? body : "", len, lim, &e))) {
    api__arena_end(&mark);
    api__problem_response(&e, out);
    return out->status;
  }
  double t0 = now();
  int decoded = ep->decode(root, &c, &x) == 0;
  if (decoded && srv && srv->small_only &&
      ep->pub.run_class == API_RUN_COMPUTE && !small) {
    ep->release(x); /* left to the server: out->status 0 */
    json_decref(root);
    api__arena_end(&mark);
    return 0;
  }
  if (decoded && ep->run(x, &c) == 0 && ep->encode(x, &c, out) == 0 &&
      ep->pub.run_class == API_RUN_COMPUTE && lim->max_seconds > 0 &&
      now() - t0 > lim->max_seconds)
    /* the compute-time limit covers the encoding of the answer too */
    api__limit(&e, "max_seconds", lim->max_seconds, "",
               "computing and encoding the answer took %.3g s, over the "
               "limit of %g s",
               now() - t0, lim->max_seconds);
  if (out->stream && !e.set)
    api__stream_own(out->stream, x, ep->release); /* read from x later */
  else
    ep->release(x);
  api__lazies_free(&lz);
  json_decref(root);
  api__arena_end(&mark);
  if (e.set) {
    api_response_free(out);
    if (prefix && e.pointer[0]) {
      char p[sizeof e.pointer];
      snprintf(p, sizeof p, "%s%s", prefix, e.pointer);
      memcpy(e.pointer, p, sizeof p);
    }
    api__problem_response(&e, out);
  }
  return out->status;
}
