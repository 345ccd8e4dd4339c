/*
 * problem.c: RFC 9457 problem details.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codec.h"

static const char *title_of(int status) {
  switch (status) {
  case 400:
    return "Bad Request";
  case 404:
    return "Not Found";
  case 405:
    return "Method Not Allowed";
  case 413:
    return "Content Too Large";
  case 415:
    return "Unsupported Media Type";
  case 422:
    return "Unprocessable Content";
  case 503:
    return "Service Unavailable";
  default:
    return status >= 500 ? "Internal Server Error" : "Client Error";
  }
}

int api__fail(api_err *e, int status, const char *type, const char *pointer,
              const char *fmt, ...) {
  if (e->status)
    return -1;
  va_list ap;
  e->status = status;
  snprintf(e->type, sizeof e->type, "%s", type);
  snprintf(e->title, sizeof e->title, "%s", title_of(status));
  snprintf(e->pointer, sizeof e->pointer, "%s", pointer ? pointer : "");
  va_start(ap, fmt);
  vsnprintf(e->detail, sizeof e->detail, fmt, ap);
  va_end(ap);
  return -1;
}

int api__limit(api_err *e, const char *limit, double value, const char *pointer,
               const char *fmt, ...) {
  if (e->status)
    return -1;
  va_list ap;
  e->status = 422;
  snprintf(e->type, sizeof e->type, "limit-exceeded");
  snprintf(e->title, sizeof e->title, "Request over a limit");
  snprintf(e->pointer, sizeof e->pointer, "%s", pointer ? pointer : "");
  snprintf(e->limit, sizeof e->limit, "%s", limit);
  e->limit_value = value;
  va_start(ap, fmt);
  vsnprintf(e->detail, sizeof e->detail, fmt, ap);
  va_end(ap);
  return -1;
}

void api__problem_response(const api_err *e, api_response *out) {
  json_t *o = json_object();
  char type[96];
  snprintf(type, sizeof type, "/problems/%s", e->type[0] ? e->type : "error");
  json_object_set_new(o, "type", json_string(type));
  json_object_set_new(o, "title", json_string(e->title));
  json_object_set_new(o, "status", json_integer(e->status));
  json_object_set_new(o, "detail", json_string(e->detail));
  if (e->pointer[0])
    json_object_set_new(o, "pointer", json_string(e->pointer));
  if (e->limit[0]) {
    json_object_set_new(o, "limit", json_string(e->limit));
    json_object_set_new(o, "limit_value", json_real(e->limit_value));
  }
  out->status = e->status;
  out->body = json_dumps(o, JSON_COMPACT | JSON_ENSURE_ASCII);
  out->len = out->body ? strlen(out->body) : 0;
  out->content_type = "application/problem+json";
  json_decref(o);
  if (!out->body) {
    static const char fallback[] =
        "{\"type\":\"/problems/internal\",\"title\":\"Internal Server "
        "Error\",\"status\":500,\"detail\":\"out of memory\"}";
    out->status = 500;
    out->body = strdup(fallback);
    out->len = out->body ? strlen(out->body) : 0;
  }
}

void api_problem(api_response *out, int status, const char *type,
                 const char *title, const char *detail, const char *pointer,
                 const char *limit, double limit_value) {
  api_err e;
  memset(&e, 0, sizeof e);
  e.status = status;
  snprintf(e.type, sizeof e.type, "%s", type ? type : "error");
  snprintf(e.title, sizeof e.title, "%s", title ? title : title_of(status));
  snprintf(e.detail, sizeof e.detail, "%s", detail ? detail : "");
  snprintf(e.pointer, sizeof e.pointer, "%s", pointer ? pointer : "");
  if (limit) {
    snprintf(e.limit, sizeof e.limit, "%s", limit);
    e.limit_value = limit_value;
  }
  api__problem_response(&e, out);
}

void api_response_free(api_response *r) {
  if (!r)
    return;
  free(r->body);
  r->body = NULL;
  r->len = 0;
}
