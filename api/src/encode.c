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

json_t *api__vec(const double *x, int n) {
  json_t *a = json_array();
  for (int i = 0; i < n; i++)
    json_array_append_new(a, api__real(x[i]));
  return a;
}

json_t *api__state(const api_params *ap, const double x[4]) {
  double y[4];
  ss_to_physical(ap->omega, 0, x, NULL, y);
  return api__vec4(y);
}

int api__answer(json_t *out, const api_spec *spec, const void *x,
                const api_params *ap, const api_call *c, api_response *resp) {
  json_t *in = api__echo(spec, x);
  api__params_echo(in, ap);
  api__set(out, "input", in);
  api__set(out, "units",
           json_string(ap->has_physical ? "physical" : "dimensionless"));
  api__set(out, "version", json_string(SS_VERSION));
  return api__json_response(out, resp, c->e);
}

json_t *api__samples(const ss_sim_result *r, const api_params *ap) {
  json_t *s = json_object(), *col[6];
  static const char *const names[6] = {"t", "x1", "x2", "v1", "v2", "mode"};
  for (int c = 0; c < 6; c++)
    col[c] = json_array();
  for (size_t i = 0; i < r->n_samples; i++) {
    double t, x[4];
    ss_to_physical(ap->omega, r->st[i], r->sx + 4 * i, &t, x);
    json_array_append_new(col[0], api__real(t));
    for (int c = 0; c < 4; c++)
      json_array_append_new(col[1 + c], api__real(x[c]));
    json_array_append_new(col[5],
                          json_string(ss_mode_name((ss_mode)r->smode[i])));
  }
  for (int c = 0; c < 6; c++)
    api__set(s, names[c], col[c]);
  return s;
}

json_t *api__phases(int n, const ss_mode *modes, const double *tau,
                    const api_params *ap) {
  json_t *a = json_array();
  for (int k = 0; k < n; k++) {
    json_t *p = json_object();
    api__set(p, "mode", json_string(ss_mode_name(modes[k])));
    api__set(p, "duration", api__real(api__time_out(ap, tau[k])));
    json_array_append_new(a, p);
  }
  return a;
}

/* In physical units the map acts on (z1, z1'): J' = D J D^-1 with
 * D = diag(1, omega). */
json_t *api__jacobian(const double J[2][2], const api_params *ap) {
  json_t *a = json_array();
  for (int i = 0; i < 2; i++) {
    json_t *row = json_array();
    for (int j = 0; j < 2; j++) {
      double s = (i == 1 ? ap->omega : 1) / (j == 1 ? ap->omega : 1);
      json_array_append_new(row, api__real(J[i][j] * s));
    }
    json_array_append_new(a, row);
  }
  return a;
}

static const char *const STAB_NOTE =
    "Stability of the fixed point of the Poincare map on the section (4.2) "
    "in (z1, z1'): all eigenvalues inside the unit circle means small "
    "perturbations, except during stick, stay near the orbit. This is "
    "neither Lyapunov nor orbital stability (the paper, section 4).";

json_t *api__stability(const ss_stab *st, const api_params *ap) {
  json_t *s = json_object(), *ev = json_array();
  for (int i = 0; i < 2; i++) {
    json_t *p = json_array();
    json_array_append_new(p, api__real(st->eig_re[i]));
    json_array_append_new(p, api__real(st->eig_im[i]));
    json_array_append_new(ev, p);
  }
  api__set(s, "eigenvalues", ev);
  api__set(s, "spectral_radius", api__real(st->spectral_radius));
  api__set(s, "stable", json_boolean(st->stable));
  api__set(s, "jacobian", api__jacobian(st->jac, ap));
  if (!isnan(st->jac_diff)) {
    api__set(s, "jacobian_fd", api__jacobian(st->jac_fd, ap));
    api__set(s, "jacobian_difference", api__real(st->jac_diff));
  }
  api__set(s, "note", json_string(STAB_NOTE));
  return s;
}

int api__json_response(json_t *j, api_response *out, api_err *e) {
  out->body = j ? api__dump(j, &out->len) : NULL;
  json_decref(j);
  if (!out->body)
    return api__fail(e, API_P_OUT_OF_MEMORY, NULL,
                     "the response could not be encoded: out of memory");
  out->status = 200;
  out->content_type = "application/json";
  return 0;
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
