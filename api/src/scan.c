/*
 * scan.c: JSON text checked without a tree (scan.h).
 *
 * It vouches for a subset of what jansson reads, so that text it passes
 * parses later without error into the same values, and answers nothing
 * itself: whatever it does not pass (other escapes, UTF-8, long numbers,
 * large objects) goes to jansson, whose problem, line and column stand.
 * A batch of 2500 items is scanned in about a millisecond, where jansson's
 * tree of it took some ten.
 */
#define _GNU_SOURCE /* strtod_l */
#include "scan.h"

#include <locale.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* Keys of an object compared for duplicates; an object with more is left
 * to jansson. */
enum { MAX_KEYS = 64 };

static const char *ws(const char *p, const char *end) {
  while (p < end && (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r'))
    p++;
  return p;
}

/* The end of the string at @a p (after its closing quote): printable ASCII
 * and, when @a esc, the escapes other than \u. */
static const char *string_end(const char *p, const char *end, int esc) {
  for (p++; p < end; p++) {
    unsigned char c = (unsigned char)*p;
    if (c == '"')
      return p + 1;
    if (c < 0x20 || c > 0x7e)
      return NULL;
    if (c == '\\') {
      if (!esc || ++p == end || !strchr("\"\\/bfnrt", *p) || !*p)
        return NULL;
    }
  }
  return NULL;
}

static const char *digits(const char *p, const char *end, int *n) {
  *n = 0;
  while (p < end && *p >= '0' && *p <= '9') {
    p++;
    (*n)++;
  }
  return p;
}

/* The end of the number at @a p: an integer of at most 18 digits, or a
 * real of at most 30 digits before its point and an exponent of at most 3
 * digits under 250 (far from a double's overflow). */
static const char *number_end(const char *p, const char *end) {
  int n_int, n_frac = 0, n_exp = 0, e = 0, real = 0;
  if (*p == '-')
    p++;
  const char *q = digits(p, end, &n_int);
  if (n_int == 0 || (n_int > 1 && *p == '0'))
    return NULL;
  p = q;
  if (p < end && *p == '.') {
    p = digits(p + 1, end, &n_frac);
    if (n_frac == 0)
      return NULL;
    real = 1;
  }
  if (p < end && (*p == 'e' || *p == 'E')) {
    p++;
    if (p < end && (*p == '+' || *p == '-'))
      p++;
    /* the value of the first 4 digits only: more are refused below */
    for (; p < end && *p >= '0' && *p <= '9'; p++, n_exp++)
      if (n_exp < 4)
        e = 10 * e + (*p - '0');
    if (n_exp == 0 || n_exp > 3 || e >= 250)
      return NULL;
    real = 1;
  }
  if (real ? n_int > 30 : n_int > 18)
    return NULL;
  return p;
}

static const char *value_end(const char *p, const char *end, int depth,
                             api_scan_top *top);

static const char *object_end(const char *p, const char *end, int depth,
                              api_scan_top *top) {
  const char *key[MAX_KEYS];
  size_t key_len[MAX_KEYS], n = 0;
  p = ws(p + 1, end);
  if (p < end && *p == '}')
    return p + 1;
  for (;;) {
    if (p == end || *p != '"' || n == MAX_KEYS)
      return NULL;
    const char *k = p + 1, *q = string_end(p, end, 0);
    if (!q)
      return NULL;
    size_t kl = (size_t)(q - 1 - k);
    for (size_t i = 0; i < n; i++)
      if (key_len[i] == kl && memcmp(key[i], k, kl) == 0)
        return NULL;
    key[n] = k;
    key_len[n++] = kl;
    p = ws(q, end);
    if (p == end || *p != ':')
      return NULL;
    p = ws(p + 1, end);
    const char *v = p;
    if (!(p = value_end(p, end, depth - 1, NULL)))
      return NULL;
    if (top && top->n < API_SCAN_MEMBERS)
      top->m[top->n] = (api_scan_member){k, v, kl, (size_t)(p - v)};
    if (top)
      top->n++;
    p = ws(p, end);
    if (p < end && *p == '}')
      return p + 1;
    if (p == end || *p != ',')
      return NULL;
    p = ws(p + 1, end);
  }
}

static const char *array_end(const char *p, const char *end, int depth) {
  p = ws(p + 1, end);
  if (p < end && *p == ']')
    return p + 1;
  for (;;) {
    if (!(p = value_end(p, end, depth - 1, NULL)))
      return NULL;
    p = ws(p, end);
    if (p < end && *p == ']')
      return p + 1;
    if (p == end || *p != ',')
      return NULL;
    p = ws(p + 1, end);
  }
}

static const char *literal_end(const char *p, const char *end,
                               const char *word) {
  size_t n = strlen(word);
  return (size_t)(end - p) >= n && memcmp(p, word, n) == 0 ? p + n : NULL;
}

static const char *value_end(const char *p, const char *end, int depth,
                             api_scan_top *top) {
  if (p == end)
    return NULL;
  switch (*p) {
  case '{':
    return depth > 0 ? object_end(p, end, depth, top) : NULL;
  case '[':
    return depth > 0 ? array_end(p, end, depth) : NULL;
  case '"':
    return string_end(p, end, 1);
  case 't':
    return literal_end(p, end, "true");
  case 'f':
    return literal_end(p, end, "false");
  case 'n':
    return literal_end(p, end, "null");
  default:
    return *p == '-' || (*p >= '0' && *p <= '9') ? number_end(p, end) : NULL;
  }
}

const char *api__json_scan(const char *p, const char *end, int depth,
                           api_scan_top *top) {
  if (top)
    top->n = 0;
  return value_end(p, end, depth, top);
}

/* ---- the tree of text the scan vouched for ------------------------------ */

/* Numbers are read in the C locale whatever the process's, as jansson
 * reads them (it swaps the point for the locale's). */
static locale_t c_numeric;
static pthread_once_t c_numeric_once = PTHREAD_ONCE_INIT;
static void c_numeric_init(void) {
  c_numeric = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
}

/* Each builder is given text the scan passed, at the value's first byte,
 * and leaves *pp after it. */
static json_t *build_value(const char **pp);

static const char *skip_ws(const char *p) {
  while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r')
    p++;
  return p;
}

static json_t *build_string(const char **pp) {
  const char *s = *pp + 1, *p = s;
  int esc = 0;
  while (*p != '"') {
    if (*p == '\\') {
      esc = 1;
      p++;
    }
    p++;
  }
  *pp = p + 1;
  if (!esc)
    return json_stringn_nocheck(s, (size_t)(p - s));
  char *t = malloc((size_t)(p - s));
  if (!t)
    return NULL;
  size_t n = 0;
  for (const char *q = s; q < p; q++) {
    if (*q != '\\') {
      t[n++] = *q;
      continue;
    }
    switch (*++q) {
    case 'b':
      t[n++] = '\b';
      break;
    case 'f':
      t[n++] = '\f';
      break;
    case 'n':
      t[n++] = '\n';
      break;
    case 'r':
      t[n++] = '\r';
      break;
    case 't':
      t[n++] = '\t';
      break;
    default: /* the quote, the backslash, the slash */
      t[n++] = *q;
    }
  }
  json_t *j = json_stringn_nocheck(t, n);
  free(t);
  return j;
}

/* An integer when it has neither point nor exponent, as jansson reads it
 * (the scan passed at most 18 digits, and an exponent under 250). */
static json_t *build_number(const char **pp) {
  const char *p = *pp;
  int real = 0;
  for (; (*p >= '0' && *p <= '9') || *p == '-' || *p == '+' || *p == '.' ||
         *p == 'e' || *p == 'E';
       p++)
    real |= *p == '.' || *p == 'e' || *p == 'E';
  char text[80]; /* 30 digits, a point, 30 more at most... */
  size_t n = (size_t)(p - *pp);
  if (n >= sizeof text)
    return NULL;
  memcpy(text, *pp, n);
  text[n] = 0;
  *pp = p;
  if (!real)
    return json_integer((json_int_t)strtoll(text, NULL, 10));
  pthread_once(&c_numeric_once, c_numeric_init);
  if (c_numeric == (locale_t)0)
    return NULL;
  return json_real(strtod_l(text, NULL, c_numeric));
}

static json_t *build_object(const char **pp) {
  json_t *o = json_object();
  const char *p = skip_ws(*pp + 1);
  if (*p == '}') {
    *pp = p + 1;
    return o;
  }
  while (o) {
    const char *k = p + 1, *q = strchr(k, '"'); /* keys have no escapes */
    p = skip_ws(skip_ws(q + 1) + 1);
    json_t *v = build_value(&p);
    if (!v || json_object_setn_new_nocheck(o, k, (size_t)(q - k), v) != 0) {
      json_decref(o);
      return NULL;
    }
    p = skip_ws(p);
    if (*p == '}')
      break;
    p = skip_ws(p + 1);
  }
  *pp = p + 1;
  return o;
}

static json_t *build_array(const char **pp) {
  json_t *a = json_array();
  const char *p = skip_ws(*pp + 1);
  if (*p == ']') {
    *pp = p + 1;
    return a;
  }
  while (a) {
    json_t *v = build_value(&p);
    if (!v || json_array_append_new(a, v) != 0) {
      json_decref(a);
      return NULL;
    }
    p = skip_ws(p);
    if (*p == ']')
      break;
    p = skip_ws(p + 1);
  }
  *pp = p + 1;
  return a;
}

static json_t *build_value(const char **pp) {
  switch (**pp) {
  case '{':
    return build_object(pp);
  case '[':
    return build_array(pp);
  case '"':
    return build_string(pp);
  case 't':
    *pp += 4;
    return json_true();
  case 'f':
    *pp += 5;
    return json_false();
  case 'n':
    *pp += 4;
    return json_null();
  default:
    return build_number(pp);
  }
}

json_t *api__json_build(const char *p, const char *end, int depth) {
  p = ws(p, end);
  if (p == end || (*p != '{' && *p != '['))
    return NULL; /* jansson takes nothing else at the top */
  const char *q = api__json_scan(p, end, depth, NULL);
  if (!q || ws(q, end) != end)
    return NULL;
  return build_value(&p);
}
