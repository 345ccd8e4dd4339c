/*
 * problem.c: RFC 9457 problem details, and the one table that turns a
 * status of the core into an HTTP answer.
 */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "arena.h"
#include "problem.h"
#include "shortest.h"

typedef struct problem_row {
  int status;
  const char *type, *title;
} problem_row;

static const problem_row PROBLEMS[API_P_COUNT] = {
#define API_PROBLEM_ROW(name, status, type, title) {status, type, title},
    API_PROBLEM_MAP(API_PROBLEM_ROW)
#undef API_PROBLEM_ROW
};

/*
 * The only place a failure status of the core becomes an HTTP answer.  The
 * endpoint that met the status says which field is at fault (the pointer)
 * and why (the detail); this table decides the status, type and title, the
 * same for every endpoint.  A status that is not here is an internal error.
 */
#define API_STATUS_PROBLEM(X)                                                  \
  X(SS_EDOMAIN, INVALID_VALUE)                                                 \
  X(SS_EINVAL, INVALID_VALUE)                                                  \
  X(SS_ESINGULAR, INVALID_VALUE)                                               \
  X(SS_ENOCONV, NO_CONVERGENCE)                                                \
  X(SS_ELIMIT_EVENTS, LIMIT)                                                   \
  X(SS_ELIMIT_SAMPLES, LIMIT)                                                  \
  X(SS_ELIMIT_TIME, LIMIT)                                                     \
  X(SS_ENOMEM, OUT_OF_MEMORY)                                                  \
  X(SS_EBUG, INTERNAL)                                                         \
  X(SS_ECANCELED, CLIENT_CLOSED)

static int kind_of_status(int status, api_problem_kind *kind) {
  switch (status) {
#define API_STATUS_CASE(st, kind_name)                                         \
  case st:                                                                     \
    *kind = API_P_##kind_name;                                                 \
    return 0;
    API_STATUS_PROBLEM(API_STATUS_CASE)
#undef API_STATUS_CASE
  default:
    return -1;
  }
}

int api_problem_status(api_problem_kind kind) {
  return (unsigned)kind < API_P_COUNT ? PROBLEMS[kind].status : 500;
}

/* The length of the number that starts at s[i] when it is written with 16
 * or 17 significant digits (as %.17g writes a double that has no shorter
 * form, and %.17g is how the core and the codec write a number so that it
 * reads back exactly); 0 for anything else: an integer, a number already
 * short, a number inside a word. */
static size_t long_number(const char *s, size_t i) {
  size_t n = i, digits = 0, lead = 1;
  int point = 0;
  if (i > 0 &&
      (isalnum((unsigned char)s[i - 1]) || s[i - 1] == '.' || s[i - 1] == '_'))
    return 0;
  for (; isdigit((unsigned char)s[n]) || (s[n] == '.' && !point); n++) {
    if (s[n] == '.')
      point = 1;
    else if (s[n] != '0' || !lead)
      digits++, lead = 0;
  }
  if (digits < 16)
    return 0;
  if ((s[n] == 'e' || s[n] == 'E') && (s[n + 1] == '+' || s[n + 1] == '-') &&
      isdigit((unsigned char)s[n + 2]))
    for (n += 2; isdigit((unsigned char)s[n]);)
      n++;
  else if (!point)
    return 0;
  return isalnum((unsigned char)s[n]) || s[n] == '_' ? 0 : n - i;
}

/* Every number of @a s that is written with 16 or 17 significant digits
 * rewritten in the fewest digits that read back as the same double
 * (shortest.c), as the answers write their numbers: 0.69999999999999996
 * becomes 0.7.  A whole number loses the ".0" that JSON needs and prose
 * does not. */
static void shorten_numbers(char *s, size_t cap) {
  char out[sizeof((api_err *)0)->detail], num[32];
  size_t o = 0;
  for (size_t i = 0; s[i] && o + 1 < sizeof out;) {
    size_t n = long_number(s, i);
    if (!n) {
      out[o++] = s[i++];
      continue;
    }
    int len = api__shortest(strtod(s + i, NULL), num);
    if (len > 2 && !strcmp(num + len - 2, ".0"))
      num[len -= 2] = 0;
    for (int k = 0; k < len && o + 1 < sizeof out; k++)
      out[o++] = num[k];
    i += n;
  }
  out[o] = 0;
  snprintf(s, cap, "%s", out);
}

static int vfail(api_err *e, api_problem_kind kind, const char *pointer,
                 const char *fmt, va_list ap) {
  if (e->set)
    return -1;
  e->set = 1;
  e->kind = (unsigned)kind < API_P_COUNT ? kind : API_P_INTERNAL;
  snprintf(e->pointer, sizeof e->pointer, "%s", pointer ? pointer : "");
  vsnprintf(e->detail, sizeof e->detail, fmt, ap);
  shorten_numbers(e->detail, sizeof e->detail);
  return -1;
}

int api__fail(api_err *e, api_problem_kind kind, const char *pointer,
              const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vfail(e, kind, pointer, fmt, ap);
  va_end(ap);
  return -1;
}

int api__limit(api_err *e, const char *limit, double value, const char *pointer,
               const char *fmt, ...) {
  va_list ap;
  if (e->set)
    return -1;
  va_start(ap, fmt);
  vfail(e, API_P_LIMIT, pointer, fmt, ap);
  va_end(ap);
  snprintf(e->limit, sizeof e->limit, "%s", limit);
  e->limit_value = value;
  return -1;
}

int api__status(api_err *e, int status, const char *pointer, const char *fmt,
                ...) {
  api_problem_kind kind;
  va_list ap;
  if (e->set)
    return -1;
  if (kind_of_status(status, &kind))
    return api__fail(e, API_P_INTERNAL, NULL,
                     "the core answered status %d (%s), which has no HTTP "
                     "mapping",
                     status, ss_status_name(status));
  va_start(ap, fmt);
  vfail(e, kind, kind == API_P_INTERNAL ? NULL : pointer, fmt, ap);
  va_end(ap);
  return -1;
}

int api__status_limit(api_err *e, int status, const char *limit, double value,
                      const char *pointer, const char *fmt, ...) {
  char detail[sizeof e->detail];
  va_list ap;
  if (e->set)
    return -1;
  va_start(ap, fmt);
  vsnprintf(detail, sizeof detail, fmt, ap);
  va_end(ap);
  api__status(e, status, pointer, "%s", detail);
  if (e->kind == API_P_LIMIT) {
    snprintf(e->limit, sizeof e->limit, "%s", limit);
    e->limit_value = value;
  }
  return -1;
}

int api__from_diag(api_err *e, int rc, const ss_diag *d, const char *base) {
  char p[160];
  if (d->where[0] && base)
    snprintf(p, sizeof p, "%s/%s", base, d->where);
  else
    snprintf(p, sizeof p, "%s", base ? base : "");
  return api__status(e, rc, p, "%s", d->text[0] ? d->text : ss_strerror(rc));
}

static void respond(api_response *out, api_problem_kind kind,
                    const char *detail, const char *pointer, const char *limit,
                    double limit_value) {
  const problem_row *row = &PROBLEMS[kind];
  json_t *o = json_object();
  memset(out, 0, sizeof *out);
  char type[96];
  snprintf(type, sizeof type, "/problems/%s", row->type);
  json_object_set_new(o, "type", json_string(type));
  json_object_set_new(o, "title", json_string(row->title));
  json_object_set_new(o, "status", json_integer(row->status));
  json_object_set_new(o, "detail", json_string(detail ? detail : ""));
  if (pointer && pointer[0])
    json_object_set_new(o, "pointer", json_string(pointer));
  if (limit && limit[0])
    json_object_set_new(o, "limit", json_string(limit));
  out->status = row->status;
  out->body = api__json_dumps(o, JSON_COMPACT | JSON_ENSURE_ASCII);
  out->len = out->body ? strlen(out->body) : 0;
  if (out->body && limit && limit[0] && isfinite(limit_value)) {
    /* the limit's value last, in its shortest digits as every number of
     * the API (jansson would write 0.3 as 0.29999999999999999) */
    char num[32];
    int k = api__shortest(limit_value, num);
    char *b = realloc(out->body, out->len + k + 17);
    if (b) {
      snprintf(b + out->len - 1, (size_t)k + 18, ",\"limit_value\":%s}", num);
      out->body = b;
      out->len = strlen(b);
    } else {
      free(out->body);
      out->body = NULL;
      out->len = 0;
    }
  }
  out->content_type = "application/problem+json";
  out->held = out->len;
  json_decref(o);
  if (!out->body) {
    static const char fallback[] =
        "{\"type\":\"/problems/out-of-memory\",\"title\":\"Service "
        "Unavailable\",\"status\":503,\"detail\":\"out of memory\"}";
    out->status = 503;
    out->body = strdup(fallback);
    out->len = out->body ? strlen(out->body) : 0;
    out->held = out->len;
  }
}

void api__problem_response(const api_err *e, api_response *out) {
  respond(out, e->set ? e->kind : API_P_INTERNAL,
          e->set ? e->detail : "no answer was produced", e->pointer, e->limit,
          e->limit_value);
}

void api_problem(api_response *out, api_problem_kind kind, const char *detail,
                 const char *pointer, const char *limit, double limit_value) {
  respond(out, (unsigned)kind < API_P_COUNT ? kind : API_P_INTERNAL, detail,
          pointer, limit, limit_value);
}
