/*
 * encode.c: core results to JSON.  No NaN or Infinity is ever emitted: a
 * non-finite number becomes null (an unbounded margin, for example).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codec.h"

json_t *api__real(double v) { return isfinite(v) ? json_real(v) : json_null(); }

json_t *api__vec4(const double x[4]) {
  json_t *a = json_array();
  for (int i = 0; i < 4; i++)
    json_array_append_new(a, api__real(x[i]));
  return a;
}

int api__set(json_t *obj, const char *key, json_t *v) {
  if (!v)
    return -1;
  return json_object_set_new(obj, key, v);
}

json_t *api__params_echo(const api_params *ap) {
  json_t *o = json_object();
  json_t *p = json_object();
  const double pv[] = {ap->p.chi, ap->p.eta, ap->p.us, ap->p.ur, ap->p.V};
  for (int i = 0; API_PARAM_KEYS[i]; i++)
    api__set(p, API_PARAM_KEYS[i], api__real(pv[i]));
  api__set(o, "params", p);
  if (ap->physical) {
    json_t *ph = json_object();
    const double hv[] = {ap->ph.m1, ap->ph.m2, ap->ph.k1, ap->ph.k2,
                         ap->ph.Fs, ap->ph.Fr, ap->ph.v0};
    for (int i = 0; API_PHYS_KEYS[i]; i++)
      api__set(ph, API_PHYS_KEYS[i], api__real(hv[i]));
    api__set(o, "physical", ph);
    api__set(o, "omega", api__real(ap->omega));
  }
  return o;
}

/* ---- the response writer ----------------------------------------------- */

typedef struct wbuf {
  char *p;
  size_t len, cap;
  int oom;
} wbuf;

static void w_grow(wbuf *b, size_t n) {
  if (b->oom || b->len + n + 1 <= b->cap)
    return;
  size_t cap = b->cap ? b->cap : 4096;
  while (cap < b->len + n + 1)
    cap *= 2;
  char *q = realloc(b->p, cap);
  if (!q) {
    b->oom = 1;
    return;
  }
  b->p = q;
  b->cap = cap;
}

static void w_put(wbuf *b, const char *s, size_t n) {
  w_grow(b, n);
  if (b->oom)
    return;
  memcpy(b->p + b->len, s, n);
  b->len += n;
  b->p[b->len] = 0;
}

static void w_str(wbuf *b, const char *s, size_t n) {
  static const char hex[] = "0123456789abcdef";
  w_put(b, "\"", 1);
  size_t run = 0;
  for (size_t i = 0; i < n; i++) {
    unsigned char c = (unsigned char)s[i];
    if (c >= 0x20 && c != '"' && c != '\\')
      continue;
    w_put(b, s + run, i - run);
    run = i + 1;
    char esc[6] = {'\\', 'u', '0', '0', hex[c >> 4], hex[c & 15]};
    if (c == '"' || c == '\\') {
      esc[1] = (char)c;
      w_put(b, esc, 2);
    } else if (c == '\n') {
      w_put(b, "\\n", 2);
    } else {
      w_put(b, esc, 6);
    }
  }
  w_put(b, s + run, n - run);
  w_put(b, "\"", 1);
}

/* The shortest of 15, 16 or 17 significant digits that reads back as the
 * same double.  17 always do; the shorter forms are tried only when the
 * 17-digit form ends in a run of zeros or nines, the mark of a decimal input
 * such as 0.0724 printed as 0.072400000000000006. */
static void w_real(wbuf *b, double v) {
  char s[40];
  if (!isfinite(v)) {
    w_put(b, "null", 4);
    return;
  }
  int n = snprintf(s, sizeof s, "%.17g", v);
  if (strstr(s, "0000") || strstr(s, "9999"))
    for (int prec = 15; prec <= 16; prec++) {
      char t[40];
      int m = snprintf(t, sizeof t, "%.*g", prec, v);
      if (strtod(t, NULL) == v) {
        memcpy(s, t, (size_t)m + 1);
        n = m;
        break;
      }
    }
  /* keep it a real: 1 -> 1.0 */
  if (!strpbrk(s, ".eE")) {
    s[n++] = '.';
    s[n++] = '0';
    s[n] = 0;
  }
  w_put(b, s, (size_t)n);
}

static void w_value(wbuf *b, const json_t *j) {
  char num[32];
  switch (json_typeof(j)) {
  case JSON_OBJECT: {
    const char *k;
    json_t *v;
    int first = 1;
    w_put(b, "{", 1);
    json_object_foreach((json_t *)j, k, v) {
      if (!first)
        w_put(b, ",", 1);
      first = 0;
      w_str(b, k, strlen(k));
      w_put(b, ":", 1);
      w_value(b, v);
    }
    w_put(b, "}", 1);
    break;
  }
  case JSON_ARRAY:
    w_put(b, "[", 1);
    for (size_t i = 0; i < json_array_size(j); i++) {
      if (i)
        w_put(b, ",", 1);
      w_value(b, json_array_get(j, i));
    }
    w_put(b, "]", 1);
    break;
  case JSON_STRING:
    w_str(b, json_string_value(j), json_string_length(j));
    break;
  case JSON_INTEGER:
    w_put(b, num,
          (size_t)snprintf(num, sizeof num, "%" JSON_INTEGER_FORMAT,
                           json_integer_value(j)));
    break;
  case JSON_REAL:
    w_real(b, json_real_value(j));
    break;
  case JSON_TRUE:
    w_put(b, "true", 4);
    break;
  case JSON_FALSE:
    w_put(b, "false", 5);
    break;
  case JSON_NULL:
    w_put(b, "null", 4);
    break;
  }
}

char *api__dump(const json_t *j, size_t *len) {
  wbuf b = {NULL, 0, 0, 0};
  w_grow(&b, 1024);
  w_value(&b, j);
  if (b.oom) {
    free(b.p);
    return NULL;
  }
  *len = b.len;
  return b.p;
}
