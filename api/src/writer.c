/*
 * writer.c: the text of an answer.  A JSON tree is written compactly with
 * the shortest exact digits; the large arrays of an answer (samples, event
 * lists) are not in the tree at all but "lazy": a marker in the tree and a
 * function that writes element i straight from the core's arrays.  A small
 * answer is written whole.  A large one, when the server asks for it
 * (api_server_info.stream_above), becomes a stream: the tree's text is cut
 * at each lazy array, and the elements are written only as the server
 * reads, a chunk at a time, from the endpoint's result, which the stream
 * keeps until it is freed.  Either way the bytes are the same.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "writer.h"
#include "problem.h"
#include "shortest.h"

/* ---- the buffer ---------------------------------------------------------- */

static void w_grow(api_wbuf *b, size_t n) {
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

void api__w_room(api_wbuf *b, size_t n) { w_grow(b, n); }

void api__w_str(api_wbuf *b, const char *s, size_t n) {
  static const char hex[] = "0123456789abcdef";
  api__w_put(b, "\"", 1);
  size_t run = 0;
  for (size_t i = 0; i < n; i++) {
    unsigned char c = (unsigned char)s[i];
    if (c >= 0x20 && c != '"' && c != '\\')
      continue;
    api__w_put(b, s + run, i - run);
    run = i + 1;
    char esc[6] = {'\\', 'u', '0', '0', hex[c >> 4], hex[c & 15]};
    if (c == '"' || c == '\\') {
      esc[1] = (char)c;
      api__w_put(b, esc, 2);
    } else if (c == '\n') {
      api__w_put(b, "\\n", 2);
    } else {
      api__w_put(b, esc, 6);
    }
  }
  api__w_put(b, s + run, n - run);
  api__w_put(b, "\"", 1);
}

/* The fewest digits that read back as the same double (shortest.c). */
void api__w_real(api_wbuf *b, double v) {
  if (!isfinite(v)) {
    api__w_put(b, "null", 4);
    return;
  }
  /* straight into the buffer, which has the 32 bytes it writes */
  if (b->oom || b->len + 32 + 1 > b->cap) {
    api__w_room(b, 32);
    if (b->oom)
      return;
  }
  b->len += (size_t)api__shortest(v, b->p + b->len);
}

/* ---- lazy arrays ----------------------------------------------------------
 */

/* A lazy array's marker is a string "\1lazy" followed by its index; the
 * writer checks the pointer too, so no request text can pose as one. */
#define LAZY_TAG "\001lazy"

/* The decimal digits of @a u, written to end at @a end; their count.  The
 * bytes printf's %llu writes, without its format parsing. */
static size_t decimal(char *end, unsigned long long u) {
  char *p = end;
  do
    *--p = (char)('0' + u % 10);
  while ((u /= 10) != 0);
  return (size_t)(end - p);
}

static json_t *lazy_new(const api_call *c, size_t n, api_item_fn *item,
                        const void *a, const void *b, int k, size_t held,
                        api_lazy_form form, const void *aux) {
  api_lazies *lz = c->lazy;
  if (!lz) /* api_handle always gives one */
    return NULL;
  if (lz->n == lz->cap) {
    size_t cap = lz->cap ? 2 * lz->cap : 16;
    api_lazy *v = realloc(lz->v, cap * sizeof *v);
    if (!v)
      return NULL;
    lz->v = v;
    lz->cap = cap;
  }
  /* the tag and the index in decimal */
  char tag[32] = LAZY_TAG, digits[24];
  size_t d = decimal(digits + sizeof digits, lz->n);
  memcpy(tag + sizeof LAZY_TAG - 1, digits + sizeof digits - d, d);
  tag[sizeof LAZY_TAG - 1 + d] = 0;
  json_t *marker = json_string(tag);
  if (!marker)
    return NULL;
  lz->v[lz->n++] = (api_lazy){marker, item, a, b, k, n, form, aux};
  lz->held += held;
  return marker;
}

json_t *api__lazy(const api_call *c, size_t n, api_item_fn *item, const void *a,
                  const void *b, int k, size_t held) {
  return lazy_new(c, n, item, a, b, k, held, API_LAZY_ARRAY, NULL);
}

json_t *api__raw(const api_call *c, api_item_fn *item, const void *a,
                 const void *b, int k) {
  return lazy_new(c, 1, item, a, b, k, 0, API_LAZY_VALUE, NULL);
}

json_t *api__raw_aux(const api_call *c, api_item_fn *item, const void *a,
                     const void *b, const void *aux) {
  return lazy_new(c, 1, item, a, b, 0, 0, API_LAZY_VALUE, aux);
}

/* The members go in under a key of their own, the marker's text: unique in
 * the object, and in the order it was set. */
int api__set_fields(json_t *o, const api_call *c, api_item_fn *item,
                    const void *a, const void *b, int k) {
  json_t *m = lazy_new(c, 1, item, a, b, k, 0, API_LAZY_FIELDS, NULL);
  return m ? json_object_set_new(o, json_string_value(m), m) : -1;
}

void api__lazies_free(api_lazies *lz) {
  free(lz->v);
  memset(lz, 0, sizeof *lz);
}

/* The lazy array @a j stands for, or NULL. */
static const api_lazy *lazy_of(const api_lazies *lz, const json_t *j) {
  const char *s = json_string_value(j);
  if (!lz || strncmp(s, LAZY_TAG, sizeof LAZY_TAG - 1) != 0)
    return NULL;
  size_t i = strtoul(s + sizeof LAZY_TAG - 1, NULL, 10);
  return i < lz->n && lz->v[i].marker == j ? &lz->v[i] : NULL;
}

static void lazy_items(api_wbuf *b, const api_lazy *l, size_t from, size_t to) {
  for (size_t i = from; i < to; i++) {
    if (i)
      api__w_put(b, ",", 1);
    l->item(b, l, i);
  }
}

/* ---- the tree -------------------------------------------------------------
 */

/* Where the text is cut at the lazy arrays (a stream), or NULL (whole). */
typedef struct cutter {
  api_stream *s;
} cutter;

static void cut(cutter *ct, api_wbuf *b, const api_lazy *l);

/* An integer in decimal, the bytes printf's %lld writes. */
void api__w_int(api_wbuf *b, long long v) {
  char num[24];
  size_t k = sizeof num -
             decimal(num + sizeof num, v < 0 ? 0ULL - (unsigned long long)v
                                             : (unsigned long long)v);
  if (v < 0)
    num[--k] = '-';
  api__w_put(b, num + k, sizeof num - k);
}

static void w_value(api_wbuf *b, const json_t *j, const api_lazies *lz,
                    cutter *ct) {
  const api_lazy *l;
  switch (json_typeof(j)) {
  case JSON_OBJECT: {
    const char *k;
    json_t *v;
    int first = 1;
    api__w_put(b, "{", 1);
    json_object_foreach((json_t *)j, k, v) {
      if (!first)
        api__w_put(b, ",", 1);
      first = 0;
      if (json_is_string(v) && (l = lazy_of(lz, v)) != NULL &&
          l->form == API_LAZY_FIELDS) {
        l->item(b, l, 0);
        continue;
      }
      api__w_str(b, k, strlen(k));
      api__w_put(b, ":", 1);
      w_value(b, v, lz, ct);
    }
    api__w_put(b, "}", 1);
    break;
  }
  case JSON_ARRAY:
    api__w_put(b, "[", 1);
    for (size_t i = 0; i < json_array_size(j); i++) {
      if (i)
        api__w_put(b, ",", 1);
      w_value(b, json_array_get(j, i), lz, ct);
    }
    api__w_put(b, "]", 1);
    break;
  case JSON_STRING:
    if ((l = lazy_of(lz, j)) != NULL && l->form != API_LAZY_ARRAY) {
      l->item(b, l, 0); /* small: written in place, also in a stream */
      break;
    }
    if (l) {
      api__w_put(b, "[", 1);
      if (ct)
        cut(ct, b, l);
      else
        lazy_items(b, l, 0, l->n);
      api__w_put(b, "]", 1);
      break;
    }
    api__w_str(b, json_string_value(j), json_string_length(j));
    break;
  case JSON_INTEGER:
    api__w_int(b, json_integer_value(j));
    break;
  case JSON_REAL:
    api__w_real(b, json_real_value(j));
    break;
  case JSON_TRUE:
    api__w_put(b, "true", 4);
    break;
  case JSON_FALSE:
    api__w_put(b, "false", 5);
    break;
  case JSON_NULL:
    api__w_put(b, "null", 4);
    break;
  }
}

void api__w_json(api_wbuf *b, const json_t *j) { w_value(b, j, NULL, NULL); }

char *api__dump(const json_t *j, size_t *len) {
  /* small texts are common (a batch item's id and body): the buffer starts
   * small and doubles */
  api_wbuf b = {malloc(256), 0, 256, 0};
  b.oom = !b.p;
  w_value(&b, j, NULL, NULL);
  if (b.oom) {
    free(b.p);
    return NULL;
  }
  /* a text kept for long (a batch item's body) keeps its length, not the
   * buffer's 4 KiB or more */
  char *fit = b.cap > b.len + 1 ? realloc(b.p, b.len + 1) : NULL;
  *len = b.len;
  return fit ? fit : b.p;
}

/* ---- streams --------------------------------------------------------------
 */

/* A piece of a streamed answer: text, a lazy array's elements, or another
 * stream (an item's answer inside a line of a batch). */
typedef struct part {
  char *text; /* NULL for a lazy array or a stream */
  size_t len; /* of the text */
  api_lazy lazy;
  api_stream *sub;
} part;

struct api_stream {
  part *parts;
  size_t n, cap;
  int oom;
  size_t cur, pos;  /* the part being read, and the byte or element in it */
  api_wbuf stage;   /* the element being read */
  size_t stage_off; /* of it, what has been read */
  void *x;          /* the endpoint's result the elements are read from */
  void (*release)(void *);
};

/* The stream owns @a p from here on, also when out of memory. */
static void add_part(api_stream *s, part p) {
  if (s->n == s->cap && !s->oom) {
    size_t cap = s->cap ? 2 * s->cap : 8;
    part *v = realloc(s->parts, cap * sizeof *v);
    if (!v)
      s->oom = 1;
    else {
      s->parts = v;
      s->cap = cap;
    }
  }
  if (s->oom) {
    free(p.text);
    api_stream_free(p.sub);
    return;
  }
  s->parts[s->n++] = p;
}

/* The text so far becomes a part, then the lazy array @a l. */
static void cut(cutter *ct, api_wbuf *b, const api_lazy *l) {
  part t = {NULL, b->len, {0}, NULL};
  if (b->oom || !(t.text = malloc(b->len ? b->len : 1))) {
    ct->s->oom = 1;
    return;
  }
  memcpy(t.text, b->p, b->len);
  b->len = 0;
  add_part(ct->s, t);
  add_part(ct->s, (part){NULL, 0, *l, NULL});
}

void api_stream_free(api_stream *s) {
  if (!s)
    return;
  for (size_t i = 0; i < s->n; i++) {
    free(s->parts[i].text);
    api_stream_free(s->parts[i].sub);
  }
  free(s->parts);
  free(s->stage.p);
  if (s->release)
    s->release(s->x);
  free(s);
}

/* A response holds the text written here, or a stream of it. */
void api_response_free(api_response *r) {
  if (!r)
    return;
  free(r->body);
  api_stream_free(r->stream);
  r->body = NULL;
  r->stream = NULL;
  r->len = 0;
  r->held = 0;
}

/* @a j (consumed by the caller) cut into a stream; NULL when out of
 * memory. */
static api_stream *stream_of(const json_t *j, const api_lazies *lz,
                             size_t *text_bytes) {
  api_stream *s = calloc(1, sizeof *s);
  api_wbuf b = {NULL, 0, 0, 0};
  if (!s)
    return NULL;
  cutter ct = {s};
  w_value(&b, j, lz, &ct);
  if (b.oom)
    s->oom = 1;
  else
    add_part(s, (part){b.p, b.len, {0}, NULL});
  if (s->oom) {
    if (b.oom)
      free(b.p);
    api_stream_free(s);
    return NULL;
  }
  *text_bytes = 0;
  for (size_t i = 0; i < s->n; i++)
    *text_bytes += s->parts[i].len;
  return s;
}

void api__stream_own(api_stream *s, void *x, void (*release)(void *)) {
  s->x = x;
  s->release = release;
}

long api_stream_read(api_stream *s, char *buf, size_t max) {
  size_t got = 0;
  while (got < max) {
    if (s->stage_off < s->stage.len) { /* the rest of an element */
      size_t k = s->stage.len - s->stage_off;
      k = k < max - got ? k : max - got;
      memcpy(buf + got, s->stage.p + s->stage_off, k);
      s->stage_off += k;
      got += k;
      continue;
    }
    if (s->cur >= s->n)
      break;
    part *p = &s->parts[s->cur];
    if (p->sub) {
      long k = api_stream_read(p->sub, buf + got, max - got);
      if (k < 0)
        return -1;
      got += (size_t)k;
      if (k == 0) { /* that stream has ended */
        s->cur++;
        s->pos = 0;
      }
      continue;
    }
    if (p->text) {
      size_t k = p->len - s->pos;
      k = k < max - got ? k : max - got;
      memcpy(buf + got, p->text + s->pos, k);
      s->pos += k;
      got += k;
    } else if (s->pos < p->lazy.n) {
      s->stage.len = 0;
      s->stage_off = 0;
      lazy_items(&s->stage, &p->lazy, s->pos, s->pos + 1);
      if (s->stage.oom)
        return -1;
      s->pos++;
      continue;
    }
    if (p->text ? s->pos == p->len : s->pos == p->lazy.n) {
      s->cur++;
      s->pos = 0;
    }
  }
  return (long)got;
}

/* Text, then an answer (whole or a stream), then text: the stream of a
 * line that wraps an answer. */
api_stream *api__stream_wrap(char *head, size_t head_len, api_response *r,
                             const char *tail) {
  api_stream *s = calloc(1, sizeof *s);
  char *t = strdup(tail);
  if (!s || !t) {
    free(s);
    free(t);
    free(head);
    api_response_free(r);
    return NULL;
  }
  add_part(s, (part){head, head_len, {0}, NULL});
  if (r->stream)
    add_part(s, (part){NULL, 0, {0}, r->stream});
  else
    add_part(s, (part){r->body, r->len, {0}, NULL});
  add_part(s, (part){t, strlen(t), {0}, NULL});
  r->stream = NULL;
  r->body = NULL;
  api_response_free(r);
  if (s->oom) {
    api_stream_free(s);
    return NULL;
  }
  return s;
}

/* ---- the answer -----------------------------------------------------------
 */

int api__json_response(json_t *j, const api_call *c, api_response *out) {
  const api_lazies *lz = c->lazy;
  size_t text = 0;
  out->status = 200;
  out->content_type = "application/json";
  if (j && lz && lz->n && c->srv && c->srv->stream_above &&
      lz->held > c->srv->stream_above) {
    out->stream = stream_of(j, lz, &text);
    out->held = text + lz->held;
    json_decref(j);
    if (!out->stream)
      return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                       "the response could not be encoded: out of memory");
    return 0;
  }
  api_wbuf b = {NULL, 0, 0, 0};
  if (j) {
    w_grow(&b, 1024);
    w_value(&b, j, lz, NULL);
  }
  json_decref(j);
  if (!j || b.oom) {
    free(b.p);
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                     "the response could not be encoded: out of memory");
  }
  out->body = b.p;
  out->len = b.len;
  out->held = b.len;
  return 0;
}
